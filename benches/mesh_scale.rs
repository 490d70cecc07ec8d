//! Exact shadows at the scale of real meshes (issue 17): the cost of one shading point against
//! the number of occluder triangles, at fixed penumbra points under a quad light.
//!
//! Scenes (all generated here, fixed seeds; `scene(name)` builds any of them):
//!
//! - a 1 x 1 quad light facing down, 3 above the ground, over an occluder centred 1.5 above the
//!   ground: `cube` (a `ConvexPolyhedron`, 12 triangles), `cube-mesh` (the same box as a
//!   `TriangleMesh`), `bumpy-80`, `bumpy-320`, `bumpy-1280` (bumpy spheres: closed,
//!   non-convex meshes of that many triangles, radius about 0.45), `torus-1280` (a torus
//!   mesh, 40 x 16 segments, tilted);
//! - the same light over a forest of random boxes standing on the ground (boxes may overlap,
//!   so the mesh does not bound a solid): `forest-5k`, `forest-20k`, `forest-100k` (one
//!   `TriangleMesh` of 5 004, 20 004 and 100 008 triangles at the same density, 2.5 boxes
//!   per unit area, so a shading point sees about the same number of boxes whatever the size);
//! - `quad-box` and `torus-light-box`: the quad light, or a torus light of 480 triangles
//!   (24 x 10 segments, radius 0.6, tube 0.15, horizontal, 3 above the ground), over a box.
//!
//! Shading points: 8 ground points in the penumbra of the cube (checked when the bench starts),
//! normal `+z`, Lambert + GGX (alpha 0.4). Criterion times one pass over the 8 points; divide
//! by 8 for the cost per point.
//!
//! Besides criterion (`cargo bench -p arealight-benches --bench mesh_scale`), the binary has two
//! plain modes, for instruction counts and images:
//!
//! - `MESH_SCALE_CASE=<scene> [MESH_SCALE_REPS=n] [MESH_SCALE_METHOD=silhouette|sequential|per-triangle]`:
//!   builds the scene and shades the 8 points `n` times (default 1) with no criterion, so that
//!   `valgrind --tool=callgrind` counts the instructions of exactly that: run it with `n = 0`
//!   too and divide the difference by `8 n` for the instructions per shading point (the scene
//!   construction and a check of the visible fractions cancel); `Scene::shade` per point (a
//!   renderer's plain call), or with `MESH_SCALE_CONTEXT=1` `Scene::shade_in` with one kept
//!   `ShadeContext`;
//! - `MESH_SCALE_IMAGE=<scene>`: renders a 200 x 150 image of the ground and the occluder (one
//!   shading point per pixel, one thread) and prints the time and images per second.

use arealight::glam::DVec3;
use arealight::internals::{bumpy_sphere, torus};
use arealight::shade::{
    Body, ConvexPolyhedron, Light, Material, Method, Scene, ShadeContext, TriangleMesh,
};
use criterion::{BenchmarkId, Criterion, criterion_group};
use std::hint::black_box;
use std::time::{Duration, Instant};

/// The quad light of every scene but `torus-light-box`.
fn quad_light() -> Light {
    let quad =
        TriangleMesh::quad(DVec3::new(0.0, 0.0, 3.0), DVec3::Y * 0.5, DVec3::X * 0.5).unwrap();
    Light::new(quad, DVec3::ONE).unwrap()
}

/// The torus light: 480 triangles, horizontal, 3 above the ground.
fn torus_light() -> Light {
    let t = torus(0.6, 0.15, 24, 10).unwrap();
    let moved = transformed(&t, 1.0, DVec3::new(0.0, 0.0, 3.0));
    Light::new(moved, DVec3::ONE).unwrap()
}

/// `mesh` scaled by `s` about the origin and moved by `d`.
fn transformed(mesh: &TriangleMesh, s: f64, d: DVec3) -> TriangleMesh {
    let v = mesh.vertices().iter().map(|&p| p * s + d).collect();
    TriangleMesh::new(v, mesh.triangles().to_vec()).unwrap()
}

/// The occluder's centre in the single-occluder scenes.
const CENTER: DVec3 = DVec3::new(0.0, 0.0, 1.5);

fn cube() -> ConvexPolyhedron {
    ConvexPolyhedron::cuboid(CENTER, DVec3::splat(0.35)).unwrap()
}

/// A bumpy sphere of `20 * 4^subdivisions` triangles, radius about 0.45 (0.4 +- 15%).
fn bumpy(subdivisions: u32) -> TriangleMesh {
    transformed(&bumpy_sphere(subdivisions, 0.15, 17).unwrap(), 0.4, CENTER)
}

/// A torus of 1 280 triangles (radius 0.35, tube 0.12), tilted 0.6 rad about `x`.
fn tilted_torus() -> TriangleMesh {
    let t = torus(0.35, 0.12, 40, 16).unwrap();
    let (s, c) = 0.6f64.sin_cos();
    let v = t
        .vertices()
        .iter()
        .map(|&p| DVec3::new(p.x, c * p.y - s * p.z, s * p.y + c * p.z) + CENTER)
        .collect();
    TriangleMesh::new(v, t.triangles().to_vec()).unwrap()
}

/// SplitMix64 in `[0, 1)`.
struct Rng(u64);

impl Rng {
    fn f64(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    }

    fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.f64()
    }
}

/// A forest of `boxes` random boxes standing on the ground at [`DENSITY`] boxes per unit area, in a
/// square centred on the origin, as one mesh (12 triangles per box; boxes may overlap each
/// other). Boxes are turned about `z`, 0.16 to 0.5 wide and 0.5 to 2.5 high; none comes within
/// 0.02 of a shading point (so no shading point is inside or on a box).
fn forest(boxes: usize) -> TriangleMesh {
    let half = (boxes as f64 / DENSITY).sqrt() / 2.0;
    let points = points();
    let mut rng = Rng(0xF0_4E57 + boxes as u64);
    let mut vertices = Vec::with_capacity(8 * boxes);
    let mut triangles = Vec::with_capacity(12 * boxes);
    let cube = ConvexPolyhedron::cuboid(DVec3::ZERO, DVec3::splat(1.0)).unwrap();
    let mut placed = 0;
    while placed < boxes {
        let c = DVec3::new(rng.range(-half, half), rng.range(-half, half), 0.0);
        let e = DVec3::new(
            rng.range(0.08, 0.25),
            rng.range(0.08, 0.25),
            rng.range(0.25, 1.25),
        );
        let (s, co) = rng.range(0.0, std::f64::consts::TAU).sin_cos();
        // The footprint's bounding circle must keep clear of every shading point.
        let reach = e.x.hypot(e.y) + 0.02;
        if points
            .iter()
            .any(|p| p.0.truncate().distance(c.truncate()) < reach)
        {
            continue;
        }
        let base = vertices.len() as u32;
        for &p in cube.vertices() {
            let q = p * e;
            vertices.push(DVec3::new(co * q.x - s * q.y, s * q.x + co * q.y, q.z + e.z) + c);
        }
        triangles.extend(cube.mesh().triangles().iter().map(|t| t.map(|i| i + base)));
        placed += 1;
    }
    TriangleMesh::new(vertices, triangles).unwrap()
}

/// Boxes per unit area of the forests.
const DENSITY: f64 = 2.5;

/// The 8 shading points (point, normal, view): on the ground, in the penumbra of the cube.
fn points() -> Vec<(DVec3, DVec3, DVec3)> {
    let mut out = Vec::new();
    for (k, r) in [0.5, 0.8, 1.1, 1.4].into_iter().enumerate() {
        for th in [0.4, 2.5] {
            let th: f64 = th + 0.3 * k as f64;
            let x = DVec3::new(r * th.cos(), r * th.sin(), 0.0);
            let v = DVec3::new(0.3 - 0.1 * k as f64, 0.2, 1.0).normalize();
            out.push((x, DVec3::Z, v));
        }
    }
    out
}

fn material() -> Material {
    Material::new(DVec3::splat(0.6), DVec3::splat(0.04), 0.4).unwrap()
}

/// Every scene of the bench, by name: (name, scene, occluder triangles).
const SCENES: [&str; 13] = [
    "lit",
    "cube",
    "cube-mesh",
    "bumpy-80",
    "bumpy-320",
    "bumpy-1280",
    "torus-1280",
    "forest-5k",
    "forest-20k",
    "forest-100k",
    "quad-box",
    "torus-light-box",
    "torus-light",
];

/// The scene called `name` (see the module documentation).
fn scene(name: &str) -> Scene {
    let one = |b: Body| Scene::new(vec![quad_light()], vec![b]).unwrap();
    let bx = || ConvexPolyhedron::cuboid(DVec3::new(0.2, 0.1, 1.5), DVec3::new(0.3, 0.2, 0.25));
    match name {
        "lit" => Scene::new(vec![quad_light()], vec![]).unwrap(),
        "cube" => one(cube().into()),
        "cube-mesh" => one(cube().mesh().clone().into()),
        "bumpy-80" => one(bumpy(1).into()),
        "bumpy-320" => one(bumpy(2).into()),
        "bumpy-1280" => one(bumpy(3).into()),
        "torus-1280" => one(tilted_torus().into()),
        "forest-5k" => one(forest(417).into()),
        "forest-20k" => one(forest(1667).into()),
        "forest-100k" => one(forest(8334).into()),
        "quad-box" => one(bx().unwrap().into()),
        "torus-light-box" => Scene::new(vec![torus_light()], vec![bx().unwrap().into()]).unwrap(),
        "torus-light" => Scene::new(vec![torus_light()], vec![]).unwrap(),
        _ => panic!("unknown scene {name}; one of {SCENES:?}"),
    }
}

/// Triangles of the scene's occluders.
fn occluder_triangles(s: &Scene) -> usize {
    s.occluders()
        .iter()
        .map(|o| o.mesh().triangle_count())
        .sum()
}

/// The scene with the method named by `MESH_SCALE_METHOD` (default: the scene's default).
fn with_env_method(s: Scene) -> Scene {
    match std::env::var("MESH_SCALE_METHOD").as_deref() {
        Ok("per-triangle") => s.with_method(Method::PerTriangle),
        Ok("silhouette") => s.with_method(Method::Silhouette),
        Ok("sequential") => s.with_method(Method::Sequential),
        Ok(other) if !other.is_empty() => panic!("unknown method {other}"),
        _ => s,
    }
}

/// One pass over the shading points: the sum of the radiances (so nothing is optimized away).
fn shade_all(s: &Scene, pts: &[(DVec3, DVec3, DVec3)], m: &Material) -> DVec3 {
    pts.iter()
        .map(|&(x, n, v)| s.shade(black_box(x), n, v, m).unwrap())
        .sum()
}

/// Checks that every shading point is in the cube's penumbra: the cube hides between 5% and
/// 95% of the light.
fn check_penumbra() {
    let (lit, cube) = (
        Scene::new(vec![quad_light()], vec![]).unwrap(),
        scene("cube"),
    );
    let m = material();
    for (x, n, v) in points() {
        let (a, b) = (
            lit.shade(x, n, v, &m).unwrap().y,
            cube.shade(x, n, v, &m).unwrap().y,
        );
        assert!(
            b > 0.05 * a && b < 0.95 * a,
            "not a penumbra at {x}: {b} of {a}"
        );
    }
}

fn per_point(c: &mut Criterion) {
    check_penumbra();
    let pts = points();
    let m = material();
    let filter = std::env::var("MESH_SCALE_ONLY").ok();
    let mut group = c.benchmark_group("mesh_scale/8 penumbra points");
    group
        .sample_size(10)
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(4));
    for name in SCENES {
        if filter.as_deref().is_some_and(|f| !name.contains(f)) {
            continue;
        }
        let s = with_env_method(scene(name));
        let id = BenchmarkId::new(name, occluder_triangles(&s));
        group.bench_with_input(id, &s, |b, s| b.iter(|| shade_all(s, &pts, &m)));
    }
    group.finish();
}

/// A 200 x 150 image: a pinhole camera at (3, -4, 3) looking at (0, 0, 0.8); each pixel's ray
/// meets the ground (shaded) or nothing (black). Occluders are not shaded (their surfaces are
/// not what is measured here) but they are hit first: a pixel whose ray meets an occluder's
/// bounding sphere before the ground is left black.
fn image(name: &str) {
    let s = with_env_method(scene(name));
    let m = material();
    let (w, h) = (200usize, 150usize);
    let eye = DVec3::new(3.0, -4.0, 3.0);
    let fwd = (DVec3::new(0.0, 0.0, 0.8) - eye).normalize();
    let right = fwd.cross(DVec3::Z).normalize();
    let up = right.cross(fwd);
    let bounds: Vec<_> = s.occluders().iter().map(Body::bounding_sphere).collect();
    let start = Instant::now();
    let (mut shaded, mut gave_up) = (0usize, 0usize);
    let mut sum = DVec3::ZERO;
    for j in 0..h {
        for i in 0..w {
            let px = (i as f64 + 0.5) / w as f64 * 2.0 - 1.0;
            let py = 1.0 - (j as f64 + 0.5) / h as f64 * 2.0;
            let d = (fwd + right * px * 0.6 + up * py * 0.45).normalize();
            if d.z >= 0.0 {
                continue;
            }
            let t = -eye.z / d.z;
            let hit_occluder = bounds.iter().any(|b| {
                let oc = eye - b.center;
                let bb = oc.dot(d);
                let cc = oc.length_squared() - b.radius * b.radius;
                let disc = bb * bb - cc;
                disc > 0.0 && -bb - disc.sqrt() < t
            });
            if hit_occluder {
                continue;
            }
            let x = eye + d * t;
            match s.shade(x, DVec3::Z, -d, &m) {
                Ok(c) => sum += c,
                Err(_) => gave_up += 1,
            }
            shaded += 1;
        }
    }
    let dt = start.elapsed().as_secs_f64();
    println!(
        "{name}: {w} x {h}, {shaded} shaded pixels ({gave_up} gave up) in {dt:.3} s: {:.3} \
         images/s, {:.1} us per shaded pixel (sum {sum})",
        1.0 / dt,
        dt / shaded as f64 * 1e6
    );
}

criterion_group!(benches, per_point);

fn main() {
    if let Ok(name) = std::env::var("MESH_SCALE_CASE") {
        let reps: usize = std::env::var("MESH_SCALE_REPS")
            .ok()
            .and_then(|r| r.parse().ok())
            .unwrap_or(1);
        let start = Instant::now();
        let s = with_env_method(scene(&name));
        let built = start.elapsed().as_secs_f64();
        let (bytes, tris) = s.visibility().bvh_bytes();
        if tris > 0 {
            println!(
                "{name}: scene built in {built:.3} s; hierarchies {bytes} bytes over {tris} \
                 triangles ({:.1} bytes per triangle)",
                bytes as f64 / tris as f64
            );
        }
        let (bytes, tris) = s.visibility().contour_bytes();
        if tris > 0 {
            println!(
                "{name}: contour structures {bytes} bytes over {tris} triangles ({:.1} bytes per \
                 triangle)",
                bytes as f64 / tris as f64
            );
        }
        let (pts, m) = (points(), material());
        let mut sum = DVec3::ZERO;
        if std::env::var("MESH_SCALE_CONTEXT").is_ok_and(|v| v == "1") {
            // A renderer's kept context (`Scene::shade_in`), its buffers made by one pass that
            // every `reps` pays alike.
            let mut ctx = ShadeContext::new();
            let pass = |ctx: &mut ShadeContext| -> DVec3 {
                pts.iter()
                    .map(|&(x, n, v)| s.shade_in(ctx, black_box(x), n, v, &m).unwrap())
                    .sum()
            };
            pass(&mut ctx);
            for _ in 0..reps {
                sum += pass(&mut ctx);
            }
        } else {
            for _ in 0..reps {
                sum += shade_all(&s, &pts, &m);
            }
        }
        // The same work for any `reps` (so that it cancels in a difference of counts): the
        // visible fraction of the light at each point.
        let lit_scene = Scene::new(s.lights().to_vec(), vec![]).unwrap();
        let lit = shade_all(&lit_scene, &pts, &m);
        let frac: Vec<String> = pts
            .iter()
            .map(|&(x, n, v)| {
                let a = s.shade(x, n, v, &m).unwrap().y;
                let b = lit_scene.shade(x, n, v, &m).unwrap().y;
                format!("{:.3}", a / b)
            })
            .collect();
        println!("visible fraction per point: {}", frac.join(" "));
        println!(
            "{name}: {} occluder triangles, {reps} passes, sum {sum}, visible {:.4} of the light",
            occluder_triangles(&s),
            sum.y / (reps.max(1) as f64 * lit.y)
        );
        return;
    }
    if let Ok(name) = std::env::var("MESH_SCALE_IMAGE") {
        image(&name);
        return;
    }
    benches();
    Criterion::default().configure_from_args().final_summary();
}
