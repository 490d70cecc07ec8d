//! Shading-point benchmarks: one shading point in a penumbra with 1 light and 0, 1, 3 occluders,
//! the silhouette path against the per-triangle path for a subdivided-icosahedron light, and the
//! face-by-face path of occluders that interpenetrate a light, and issue 15's quad-light scene
//! (a shaded point against the bare integrals it needs). Fixed inputs; results in BENCHMARKS.md
//! (sections `shade` and `shade: cost of a point`).
//!
//! Besides criterion (`cargo bench -p arealight-benches --bench shade`), the binary has a plain
//! mode for instruction counts: `SHADE_POINT_CASE=<case> [SHADE_POINT_REPS=n]` shades issue 15's
//! eight points `n` times (default 1) with no criterion (cases: see `count_case`), so that
//! `valgrind --tool=callgrind` counts exactly that; run it with `n = 0` too and divide the
//! difference by `8 n` for the instructions per shading point (scene construction cancels).
//! `SHADE_POINT_ONLY=k` (0 to 7) shades only the `k`-th point (divide by `n`), to see what each
//! point costs.

use arealight::glam::DVec3;
use arealight::internals::{DemoConfig, demo_scene};
use arealight::ltc::{clamped_cosine_integral_clip_free, lookup, ltc_integral};
use arealight::shade::{
    Body, ConvexPolyhedron, Light, Material, Method, Scene, ShadeContext, TriangleMesh,
};
use arealight::solid::ShadingFrame;
use arealight::sphere::SphericalPolygon;
use criterion::{BenchmarkId, Criterion, criterion_group};
use std::hint::black_box;

fn occluders(c: &mut Criterion) {
    let demo = demo_scene(DemoConfig::default()).unwrap();
    // The truncated-cone light alone, with the first k occluders (cube, icosphere, ellipsoid).
    let cone = demo.scene.lights()[2].clone();
    // A ground point in the penumbra of the icosphere under the cone light.
    let (x, n, v) = (
        DVec3::new(1.4, -0.25, 0.0),
        DVec3::Z,
        DVec3::new(0.2, -0.7, 0.7),
    );
    let m = demo.ground;
    // Check once that the point is in a penumbra: the icosphere hides part of the light.
    let lit = Scene::new(vec![cone.clone()], vec![])
        .unwrap()
        .shade(x, n, v, &m)
        .unwrap();
    let ico = vec![demo.scene.occluders()[1].clone()];
    let half = Scene::new(vec![cone.clone()], ico)
        .unwrap()
        .shade(x, n, v, &m)
        .unwrap();
    assert!(
        half.y > 0.05 * lit.y && half.y < 0.95 * lit.y,
        "not a penumbra: {half} of {lit}"
    );
    let mut group = c.benchmark_group("shade/one point, 1 light");
    for k in [0usize, 1, 3] {
        let occ = match k {
            1 => vec![demo.scene.occluders()[1].clone()],
            _ => demo.scene.occluders()[..k].to_vec(),
        };
        let scene = Scene::new(vec![cone.clone()], occ).unwrap();
        group.bench_with_input(BenchmarkId::new("occluders", k), &scene, |b, s| {
            b.iter(|| s.shade(black_box(x), n, v, &m).unwrap())
        });
    }
    group.finish();
}

fn silhouette_vs_per_triangle(c: &mut Criterion) {
    // An icosahedron subdivided twice (162 vertices, 320 triangles) as a light, 3 above a
    // diffuse + GGX floor, no occluders.
    let ico = ConvexPolyhedron::icosphere(DVec3::new(0.2, 0.1, 3.0), 1.0, 2).unwrap();
    let scene = Scene::new(vec![Light::new(ico, DVec3::ONE).unwrap()], vec![]).unwrap();
    let per_tri = scene.clone().with_method(Method::PerTriangle);
    let m = Material::new(DVec3::splat(0.5), DVec3::splat(0.04), 0.4).unwrap();
    let (x, n, v) = (
        DVec3::new(0.5, -0.3, 0.0),
        DVec3::Z,
        DVec3::new(0.3, 0.0, 1.0),
    );
    let mut group = c.benchmark_group("shade/icosphere light (162 vertices)");
    group.bench_function("silhouette", |b| {
        b.iter(|| scene.shade(black_box(x), n, v, &m).unwrap())
    });
    group.bench_function("per-triangle", |b| {
        b.iter(|| per_tri.shade(black_box(x), n, v, &m).unwrap())
    });
    group.finish();
}

fn interpenetrating(c: &mut Criterion) {
    // Occluders through lights, so the light goes face by face: a box through a quad light's
    // plane, and a rod through a once-subdivided icosphere light (80 triangles), each from a
    // ground point whose view of the light the occluder partly hides.
    let m = Material::new(DVec3::splat(0.5), DVec3::splat(0.04), 0.4).unwrap();
    let (n, v) = (DVec3::Z, DVec3::new(0.3, 0.0, 1.0));
    let quad =
        TriangleMesh::quad(DVec3::new(0.0, 0.0, 2.5), DVec3::Y * 0.6, DVec3::X * 0.6).unwrap();
    let straddling =
        ConvexPolyhedron::cuboid(DVec3::new(0.45, 0.1, 2.5), DVec3::new(0.3, 0.25, 0.4)).unwrap();
    let ico = ConvexPolyhedron::icosphere(DVec3::new(0.0, 0.0, 2.5), 0.6, 1).unwrap();
    let rod =
        ConvexPolyhedron::cuboid(DVec3::new(0.2, 0.05, 2.5), DVec3::new(0.12, 0.12, 1.0)).unwrap();
    let cases: [(&str, Body, Body, DVec3); 2] = [
        (
            "quad light, straddling box",
            quad.into(),
            straddling.into(),
            DVec3::new(-0.6, 0.2, 0.0),
        ),
        (
            "icosphere light, piercing rod",
            ico.into(),
            rod.into(),
            DVec3::new(0.7, -0.3, 0.0),
        ),
    ];
    let mut group = c.benchmark_group("shade/interpenetrating occluder (face by face)");
    for (name, light, occ, x) in cases {
        let lit = Scene::new(vec![Light::new(light.clone(), DVec3::ONE).unwrap()], vec![]).unwrap();
        let scene = Scene::new(vec![Light::new(light, DVec3::ONE).unwrap()], vec![occ]).unwrap();
        let (full, part) = (
            lit.shade(x, n, v, &m).unwrap(),
            scene.shade(x, n, v, &m).unwrap(),
        );
        assert!(
            part.y > 0.05 * full.y && part.y < 0.95 * full.y,
            "{name}: not a penumbra"
        );
        group.bench_function(name, |b| {
            b.iter(|| scene.shade(black_box(x), n, v, &m).unwrap())
        });
    }
    group.finish();
}

/// Issue 15's scene: a 1 x 1 quad light at height 2 facing down, a 0.5 cube at height 1, and
/// for the three-occluder case a flat box and an icosahedron (12 vertices) beside it; ground
/// points in the penumbra of all of them.
pub fn issue15_scene(occluders: usize) -> Scene {
    let quad =
        TriangleMesh::quad(DVec3::new(0.0, 0.0, 2.0), DVec3::Y * 0.5, DVec3::X * 0.5).unwrap();
    let all: [Body; 3] = [
        ConvexPolyhedron::cuboid(DVec3::new(0.0, 0.0, 1.0), DVec3::splat(0.25))
            .unwrap()
            .into(),
        ConvexPolyhedron::cuboid(DVec3::new(0.35, -0.3, 1.35), DVec3::new(0.15, 0.1, 0.05))
            .unwrap()
            .into(),
        ConvexPolyhedron::icosphere(DVec3::new(0.1, 0.35, 1.5), 0.12, 0)
            .unwrap()
            .into(),
    ];
    Scene::new(
        vec![Light::new(quad, DVec3::ONE).unwrap()],
        all[..occluders].to_vec(),
    )
    .unwrap()
}

/// The ground points of issue 15's benchmarks, with a view each: eight points of a row through
/// the penumbra of the three occluders.
pub fn issue15_points() -> Vec<(DVec3, DVec3)> {
    (0..8)
        .map(|k| {
            let t = k as f64 / 7.0;
            (
                DVec3::new(0.25 + 0.35 * t, 0.05 + 0.1 * t, 0.0),
                DVec3::new(0.3 - 0.5 * t, -0.2, 1.0),
            )
        })
        .collect()
}

fn quad_light_points(c: &mut Criterion) {
    let points = issue15_points();
    let diffuse = Material::diffuse(DVec3::splat(0.8)).unwrap();
    let glossy = Material::new(DVec3::splat(0.5), DVec3::splat(0.04), 0.4).unwrap();
    let scenes: Vec<Scene> = (0..4).filter(|&k| k != 2).map(issue15_scene).collect();
    // Every point is in the penumbra of the cube and of the three occluders together.
    for &(x, v) in &points {
        let lit = scenes[0].shade(x, DVec3::Z, v, &diffuse).unwrap();
        for s in &scenes[1..] {
            let part = s.shade(x, DVec3::Z, v, &diffuse).unwrap();
            assert!(
                part.x > 0.05 * lit.x && part.x < 0.95 * lit.x,
                "{x}: not a penumbra ({part} of {lit})"
            );
        }
    }
    // The integrals alone: the light's quad seen from each point, prebuilt in its frame.
    let quads: Vec<(SphericalPolygon, f64)> = points
        .iter()
        .map(|&(x, v)| {
            let f = ShadingFrame::new(x, DVec3::Z, v).unwrap();
            let m = scenes[0].lights()[0].shape().mesh();
            let c = [0, 1, 2, 3].map(|k| f.to_local(m.vertices()[k]));
            // The quad's outline as a region: the light faces the point, so its corners run
            // clockwise seen from outside the sphere of directions; reversed.
            let ring = SphericalPolygon::new(vec![c.iter().rev().copied().collect()]).unwrap();
            assert!(ring.solid_angle() < 1.0);
            (ring, f.view().z)
        })
        .collect();
    let mut group = c.benchmark_group("shade/quad light, 8 penumbra points");
    group.bench_function("integrals only, diffuse", |b| {
        b.iter(|| {
            let mut s = 0.0;
            for (q, _) in &quads {
                s += clamped_cosine_integral_clip_free(black_box(q));
            }
            s
        })
    });
    group.bench_function("integrals only, glossy", |b| {
        b.iter(|| {
            let mut s = 0.0;
            for (q, cos_v) in &quads {
                let l = lookup(black_box(*cos_v), glossy.alpha()).unwrap();
                s += clamped_cosine_integral_clip_free(black_box(q))
                    + l.norm * ltc_integral(q, l.m_inv).unwrap();
            }
            s
        })
    });
    for (scene, k) in scenes.iter().zip([0, 1, 3]) {
        for (name, m) in [("diffuse", &diffuse), ("glossy", &glossy)] {
            group.bench_function(format!("shade, {k} occluders, {name}"), |b| {
                b.iter(|| {
                    let mut s = DVec3::ZERO;
                    for &(x, v) in &points {
                        s += scene.shade(black_box(x), DVec3::Z, v, m).unwrap();
                    }
                    s
                })
            });
            // The same through a context kept across calls, as a renderer's thread keeps one.
            let mut ctx = ShadeContext::new();
            group.bench_function(format!("shade_in, {k} occluders, {name}"), |b| {
                b.iter(|| {
                    let mut s = DVec3::ZERO;
                    for &(x, v) in &points {
                        s += scene
                            .shade_in(&mut ctx, black_box(x), DVec3::Z, v, m)
                            .unwrap();
                    }
                    s
                })
            });
        }
    }
    group.finish();
}

/// The plain mode for instruction counts (see the module documentation): `case` is
/// `integrals-diffuse`, `integrals-glossy`, or `shade-K-M` / `shade_in-K-M` with `K` in 0, 1, 3
/// occluders and `M` in `diffuse`, `glossy`; the eight points of issue 15 are shaded `reps`
/// times. Returns the sum of the values, which the caller prints so that nothing is optimized
/// out.
fn count_case(case: &str, reps: usize) -> f64 {
    let mut points = issue15_points();
    if let Ok(k) = std::env::var("SHADE_POINT_ONLY") {
        let k: usize = k.parse().unwrap();
        points = vec![points[k]];
    }
    let diffuse = Material::diffuse(DVec3::splat(0.8)).unwrap();
    let glossy = Material::new(DVec3::splat(0.5), DVec3::splat(0.04), 0.4).unwrap();
    let parts: Vec<&str> = case.split('-').collect();
    let mut sum = 0.0;
    match parts.as_slice() {
        ["integrals", lobe] => {
            let scene = issue15_scene(0);
            let m = scene.lights()[0].shape().mesh();
            let quads: Vec<(SphericalPolygon, f64)> = points
                .iter()
                .map(|&(x, v)| {
                    let f = ShadingFrame::new(x, DVec3::Z, v).unwrap();
                    let c = [0, 1, 2, 3].map(|k| f.to_local(m.vertices()[k]));
                    let ring =
                        SphericalPolygon::new(vec![c.iter().rev().copied().collect()]).unwrap();
                    (ring, f.view().z)
                })
                .collect();
            let glossy_lobe = *lobe == "glossy";
            for _ in 0..reps {
                for (q, cos_v) in &quads {
                    sum += clamped_cosine_integral_clip_free(black_box(q));
                    if glossy_lobe {
                        let l = lookup(black_box(*cos_v), glossy.alpha()).unwrap();
                        sum += l.norm * ltc_integral(q, l.m_inv).unwrap();
                    }
                }
            }
        }
        [entry, k, lobe] => {
            let scene = issue15_scene(k.parse().expect("occluder count"));
            let m = if *lobe == "glossy" { &glossy } else { &diffuse };
            let mut ctx = ShadeContext::new();
            for _ in 0..reps {
                for &(x, v) in &points {
                    let rgb = if *entry == "shade_in" {
                        scene.shade_in(&mut ctx, black_box(x), DVec3::Z, v, m)
                    } else {
                        scene.shade(black_box(x), DVec3::Z, v, m)
                    };
                    sum += rgb.unwrap().x;
                }
            }
        }
        _ => panic!("unknown SHADE_POINT_CASE {case}"),
    }
    sum
}

criterion_group!(
    benches,
    quad_light_points,
    occluders,
    silhouette_vs_per_triangle,
    interpenetrating
);

fn main() {
    if let Ok(case) = std::env::var("SHADE_POINT_CASE") {
        let reps: usize = std::env::var("SHADE_POINT_REPS")
            .ok()
            .and_then(|r| r.parse().ok())
            .unwrap_or(1);
        println!("{case} x {reps}: {}", count_case(&case, reps));
        return;
    }
    benches();
    Criterion::default().configure_from_args().final_summary();
}
