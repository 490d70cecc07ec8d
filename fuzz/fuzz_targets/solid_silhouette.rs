//! Fuzz the non-convex silhouette (`solid::nonconvex_silhouette`): random closed meshes from generators (tori,
//! extruded stars, bumpy spheres, the thesis's polyhedra, unions of boxes on a coarse grid so
//! that faces share planes and lines), rotated by a quaternion of small integers, seen from grid
//! points, mesh vertices, points on edges' lines and points 2^-1 to 2^-50 off a face.
//!
//! Asserted, for every mesh that `ClosedMesh::new` accepts (it must reject the others with a
//! mesh error, never panic):
//! - the silhouette is a valid polygon (its rings rebuild with `SphericalPolygon::new`) or
//!   `GeomError::Undecidable`, never another error;
//! - it equals the union of the front triangles' projections: where the sphere layer's set
//!   operations decide, their symmetric difference is below `1e-10 * 4 pi`, or else exact cone
//!   tests at directions inside the difference (uniform ones and points of its edges moved
//!   inward by 1e-11 to 1e-4 rad, those farther than 1e-12 rad from the silhouette's boundary)
//!   all side with the silhouette; and directions that a floating-point ray cast finds clearly
//!   inside or outside every front triangle (and that are not within 1e-9 rad of the
//!   silhouette's boundary) are contained exactly when hit;
//!
//! The BSP-precomputed silhouettes are not built here: even small rotated solids give trees of
//! tens of megabytes under the sanitizer, which exhausted libFuzzer's memory limit within a
//! thousand runs; `tests/solid_silhouette_bsp.rs` checks them against this silhouette.
//!
//! Run: `RUSTC_BOOTSTRAP=1 cargo fuzz run solid_silhouette -- -max_total_time=300` (from the
//! crate root).
#![no_main]

use arealight::GeomError;
use arealight::glam::{DMat3, DQuat, DVec2, DVec3};
use arealight::internals::{
    TriangleRole, bumpy_sphere, extruded_star, thesis_polyhedra, torus, triangle_polygon,
};
use arealight::planar::BoolOp;
use arealight::shade::ConvexPolyhedron;
use arealight::solid::{
    ClosedMesh, ShadingFrame, Side, TriangleMesh, face_side, nonconvex_silhouette,
};
use arealight::sphere::{PolygonSampler, SphericalPolygon};
use libfuzzer_sys::arbitrary::{self, Arbitrary};
use libfuzzer_sys::fuzz_target;

/// A point of the coarse grid: integers over 4.
#[derive(Debug, Clone, Copy, Arbitrary)]
struct Grid(i8, i8, i8);

impl Grid {
    fn at(self) -> DVec3 {
        DVec3::new(f64::from(self.0 % 16), f64::from(self.1 % 16), f64::from(self.2 % 16)) / 4.0
    }
}

#[derive(Debug, Arbitrary)]
enum Shape {
    Torus { around: u8, tube: u8, r: u8 },
    Star { points: u8, inner: u8, h: u8 },
    Bumpy { seed: u64, amp: u8, subdiv: bool },
    Thesis(u8),
    /// Boxes on the grid, merged into one mesh (rejected where they touch or overlap).
    Boxes(Vec<(Grid, u8, u8, u8)>),
}

#[derive(Debug, Arbitrary)]
enum View {
    Grid(Grid),
    Vertex(u16),
    /// On the line of an edge, at `t / 8` along it.
    EdgeLine(u16, i8),
    /// Off a face at `2^-exp` of the mesh's size, on either side.
    NearFace(u16, u8, u8, u8, bool),
}

#[derive(Debug, Arbitrary)]
struct Case {
    shape: Shape,
    rot: [i8; 4],
    view: View,
    view_dir: Grid,
}

fn mesh_of(s: &Shape) -> Option<TriangleMesh> {
    match *s {
        Shape::Torus { around, tube, r } => {
            torus(1.0, 0.1 + f64::from(r % 8) / 10.0, 3 + (around % 14) as usize, 3 + (tube % 6) as usize)
                .ok()
        }
        Shape::Star { points, inner, h } => extruded_star(
            2 + (points % 7) as usize,
            0.1 + f64::from(inner % 8) / 10.0,
            1.0,
            0.05 + f64::from(h % 16) / 8.0,
        )
        .ok(),
        Shape::Bumpy { seed, amp, subdiv } => {
            bumpy_sphere(u32::from(subdiv), f64::from(amp % 9) / 10.0, seed).ok()
        }
        Shape::Thesis(k) => thesis_polyhedra().ok()?.into_iter().nth((k % 9) as usize).map(|p| p.1),
        Shape::Boxes(ref boxes) => {
            let mut out: Option<TriangleMesh> = None;
            for &(c, x, y, z) in boxes.iter().take(4) {
                let h = DVec3::new(f64::from(1 + x % 8), f64::from(1 + y % 8), f64::from(1 + z % 8)) / 8.0;
                let b = ConvexPolyhedron::cuboid(c.at(), h).ok()?.mesh().clone();
                out = Some(match out {
                    None => b,
                    Some(m) => m.merged(&b).ok()?,
                });
            }
            out
        }
    }
}

/// Front triangles hit by the ray from `x` along `w`, by Moeller-Trumbore: `None` when a
/// triangle is too close to call (barycentric margin `1e-9`).
fn ray_hits_front(mesh: &TriangleMesh, x: DVec3, w: DVec3) -> Option<bool> {
    let mut hit = false;
    for t in 0..mesh.triangle_count() {
        if face_side(mesh, t, x) != Side::Front {
            continue;
        }
        let [a, b, c] = mesh.triangle(t);
        let (e1, e2) = (b - a, c - a);
        let p = w.cross(e2);
        let det = e1.dot(p);
        if det.abs() < 1e-300 {
            continue;
        }
        let s = x - a;
        let u = s.dot(p) / det;
        let q = s.cross(e1);
        let v = w.dot(q) / det;
        let m = 1e-9;
        let inside = u > m && v > m && 1.0 - u - v > m;
        let outside = u < -m || v < -m || 1.0 - u - v < -m;
        if !inside && !outside {
            return None;
        }
        if inside && e2.dot(q) / det > 0.0 {
            hit = true;
        }
    }
    Some(hit)
}

/// Whether the ray from `x` along `w` lies in the closed cone of a front triangle (exact).
fn exactly_covered(mesh: &TriangleMesh, x: DVec3, w: DVec3) -> bool {
    let c = |p: DVec3| robust::Coord3D { x: p.x, y: p.y, z: p.z };
    let q = x + w;
    (0..mesh.triangle_count())
        .filter(|&f| face_side(mesh, f, x) == Side::Front)
        .any(|f| {
            let t = mesh.triangle(f);
            (0..3).all(|e| robust::orient3d(c(t[e]), c(t[(e + 1) % 3]), c(q), c(x)) <= 0.0)
        })
}

fn boundary_distance(p: &SphericalPolygon, d: DVec3) -> f64 {
    let mut best = f64::INFINITY;
    for r in p.rings() {
        for i in 0..r.len() {
            let (a, b) = (r[i], r[(i + 1) % r.len()]);
            let Some(n) = a.cross(b).try_normalize() else {
                continue;
            };
            let q = d - n * d.dot(n);
            let dist = if a.cross(q).dot(n) >= 0.0 && q.cross(b).dot(n) >= 0.0 {
                d.dot(n).abs().asin()
            } else {
                d.angle_between(a).min(d.angle_between(b))
            };
            best = best.min(dist);
        }
    }
    best
}

fn front_union(mesh: &TriangleMesh, frame: &ShadingFrame) -> Result<SphericalPolygon, GeomError> {
    let mut parts = Vec::new();
    for t in 0..mesh.triangle_count() {
        if let Some(p) = triangle_polygon(mesh, t, frame, TriangleRole::Emitter)? {
            parts.push(p);
        }
    }
    while parts.len() > 1 {
        let mut next = Vec::with_capacity(parts.len() / 2 + 1);
        for pair in parts.chunks(2) {
            next.push(match pair {
                [a, b] => a.boolean(b, BoolOp::Union)?,
                [a] => a.clone(),
                _ => unreachable!(),
            });
        }
        parts = next;
    }
    Ok(parts.pop().unwrap_or_default())
}

fuzz_target!(|case: Case| {
    let Some(mesh) = mesh_of(&case.shape) else {
        return;
    };
    let q = DQuat::from_xyzw(
        f64::from(case.rot[0]),
        f64::from(case.rot[1]),
        f64::from(case.rot[2]),
        f64::from(case.rot[3]),
    );
    let r = if q.length_squared() > 0.0 {
        DMat3::from_quat(q.normalize())
    } else {
        DMat3::IDENTITY
    };
    let Ok(mesh) = TriangleMesh::new(
        mesh.vertices().iter().map(|&v| r * v).collect(),
        mesh.triangles().to_vec(),
    ) else {
        return;
    };
    if mesh.triangle_count() > 400 {
        return;
    }
    let solid = match ClosedMesh::new(mesh.clone()) {
        Ok(s) => s,
        Err(
            GeomError::OpenMesh { .. }
            | GeomError::NonManifoldVertex { .. }
            | GeomError::SelfIntersectingMesh { .. },
        ) => return,
        Err(e) => panic!("unexpected mesh error {e}"),
    };
    let size = mesh.bounding_sphere().radius;
    let x = match case.view {
        View::Grid(g) => g.at() - DVec3::splat(2.0),
        View::Vertex(k) => mesh.vertices()[k as usize % mesh.vertices().len()],
        View::EdgeLine(k, t) => {
            let e = mesh.edges()[k as usize % mesh.edges().len()];
            let (a, b) = (mesh.vertices()[e.a as usize], mesh.vertices()[e.b as usize]);
            a + (b - a) * (f64::from(t) / 8.0)
        }
        View::NearFace(k, u, v, exp, side) => {
            let t = k as usize % mesh.triangle_count();
            let [a, b, c] = mesh.triangle(t);
            let (u, v) = (f64::from(u) / 255.0, f64::from(v) / 255.0);
            let (u, v) = if u + v > 1.0 { (1.0 - u, 1.0 - v) } else { (u, v) };
            let off = size * 2f64.powi(-i32::from(1 + exp % 50));
            a + (b - a) * u + (c - a) * v + mesh.triangle_normal(t) * if side { off } else { -off }
        }
    };
    let Ok(frame) = ShadingFrame::new(x, DVec3::Z, case.view_dir.at() + DVec3::Z * 0.1) else {
        return;
    };
    let sil = match nonconvex_silhouette(&solid, &frame) {
        Ok(s) => s,
        Err(e) => {
            assert!(e.is_undecidable(), "{e}");
            return;
        }
    };
    if !sil.is_empty() && !sil.is_full() {
        let rings: Vec<Vec<DVec3>> = sil.rings().map(<[DVec3]>::to_vec).collect();
        SphericalPolygon::new(rings).unwrap_or_else(|e| panic!("invalid silhouette: {e}"));
    }
    // Directions against the ray cast.
    let verts: Vec<DVec3> = sil.rings().flatten().copied().collect();
    for k in 0..64u32 {
        // Fibonacci-sphere directions, and directions near silhouette vertices.
        let d = if k % 2 == 0 || verts.is_empty() {
            let z = 1.0 - (f64::from(k) + 0.5) / 32.0;
            let phi = f64::from(k) * 2.399_963_229_728_653;
            let rr = (1.0 - z * z).max(0.0).sqrt();
            DVec3::new(rr * phi.cos(), rr * phi.sin(), z)
        } else {
            let v = verts[k as usize % verts.len()];
            (v + DVec3::new(1e-4, -2e-4, 3e-4) * f64::from(k % 7 + 1)).normalize()
        };
        if boundary_distance(&sil, d) < 1e-9 {
            continue;
        }
        if let Some(hit) = ray_hits_front(&mesh, x, frame.dir_to_world(d)) {
            assert_eq!(sil.contains(d), hit, "direction {d}");
        }
    }
    // The union of front triangles: where the set operations decide, the symmetric difference
    // must be below 1e-10 * 4 pi, or else the silhouette must agree with exact cone tests at
    // directions inside the difference (the union is then the wrong one).
    if let Ok(u) = front_union(&mesh, &frame)
        && let Ok(xor) = sil.boolean(&u, BoolOp::Xor)
    {
        let a = xor.solid_angle();
        if a > 1e-10 * 4.0 * std::f64::consts::PI {
            let mut tested = 0;
            for (k, d) in inside_samples(&xor).into_iter().enumerate() {
                if boundary_distance(&sil, d) <= 1e-12 {
                    continue;
                }
                tested += 1;
                assert_eq!(
                    sil.contains(d),
                    exactly_covered(&mesh, x, frame.dir_to_world(d)),
                    "symmetric difference {a}; direction {d} (sample {k})"
                );
            }
            assert!(tested >= 64, "symmetric difference {a}: {tested} directions tested");
        }
    }
});

/// Directions in a region: 64 uniform ones where `PolygonSampler` triangulates it (a thin
/// sliver often cannot be), and 256 points of its edges each moved to the interior side by
/// `1e-11` to `1e-4` rad, so that slivers of any width from about `1e-11` rad get directions
/// inside them (a direction outside is harmless: the silhouette must agree with exact cone
/// tests everywhere off its boundary).
fn inside_samples(region: &SphericalPolygon) -> Vec<DVec3> {
    let mut out = Vec::new();
    let halton = |k: u32, base: u32| {
        let (mut f, mut r, mut i) = (1.0, 0.0, k);
        while i > 0 {
            f /= f64::from(base);
            r += f * f64::from(i % base);
            i /= base;
        }
        r
    };
    if let Ok(s) = PolygonSampler::new(region) {
        out.extend((1..=64).map(|k| s.sample(DVec2::new(halton(k, 2), halton(k, 3)))));
    }
    let edges: Vec<(DVec3, DVec3)> = region
        .rings()
        .flat_map(|r| (0..r.len()).map(move |i| (r[i], r[(i + 1) % r.len()])))
        .collect();
    for k in 0..256u32 {
        if edges.is_empty() {
            break;
        }
        let (a, b) = edges[k as usize % edges.len()];
        let Some(inward) = a.cross(b).try_normalize() else {
            continue;
        };
        let t = halton(k + 1, 5);
        let on = (a * (1.0 - t) + b * t).normalize();
        out.push((on + inward * 10f64.powi(-11 + (k / 7 % 8) as i32)).normalize());
    }
    out
}
