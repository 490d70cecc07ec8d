//! The silhouette of closed non-convex meshes seen from a point (`solid::nonconvex_silhouette`,
//! thesis 003 section 4.3) against two independent references, on the polyhedra of the thesis's
//! table 7.1 and on random tori, extruded stars and bumpy spheres, randomly placed:
//!
//! - the union of the front triangles' projections computed with the sphere layer's set
//!   operations: the symmetric difference must be below `1e-10 * 4 pi` in solid angle, or else
//!   exact cone tests at directions sampled inside the difference must all side with the
//!   silhouette (the union is then the wrong one, counted and reported);
//! - per direction, a floating-point ray cast against every front triangle (barycentric
//!   coordinates with a margin; directions within the margin of a triangle edge or within
//!   `1e-9` rad of the silhouette's boundary are skipped): the silhouette must contain exactly
//!   the directions some front triangle is hit in.
//!
//! Viewpoints lie around each solid, inside its bounding box (also inside the solid and in its
//! cavities) and close to its surface (1e-9 to 1e-2 of its size off a random triangle, on both
//! sides). Every result must be a valid polygon (re-validated from its rings). Give-ups
//! (`GeomError::Undecidable`) must be rare on such points; points on face planes, on edges'
//! lines and at vertices must give a valid polygon or a give-up, never another error or a panic.
//!
//! Longer runs: `SIL_CASES=20 cargo test --release --test solid_silhouette` multiplies the
//! number of viewpoints.

mod support;

use arealight::GeomError;
use arealight::glam::{DMat3, DVec2, DVec3};
use arealight::internals::{
    TriangleRole, bumpy_sphere, extruded_star, thesis_polyhedra, torus, triangle_polygon,
};
use arealight::planar::BoolOp;
use arealight::solid::{
    ClosedMesh, ShadingFrame, Side, TriangleMesh, face_side, nonconvex_silhouette,
};
use arealight::sphere::{PolygonSampler, SphericalPolygon};
use std::f64::consts::PI;
use support::Rng;

fn multiplier() -> usize {
    std::env::var("SIL_CASES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(1)
}

/// A random rotation (uniform quaternion), scale in [0.5, 2] and translation in [-3, 3]^3.
fn placed(mesh: &TriangleMesh, rng: &mut Rng) -> TriangleMesh {
    let q = arealight::glam::DQuat::from_xyzw(
        rng.range(-1.0, 1.0),
        rng.range(-1.0, 1.0),
        rng.range(-1.0, 1.0),
        rng.range(-1.0, 1.0),
    )
    .normalize();
    let m = DMat3::from_quat(q) * rng.range(0.5, 2.0);
    let t = DVec3::new(
        rng.range(-3.0, 3.0),
        rng.range(-3.0, 3.0),
        rng.range(-3.0, 3.0),
    );
    TriangleMesh::new(
        mesh.vertices().iter().map(|&v| m * v + t).collect(),
        mesh.triangles().to_vec(),
    )
    .unwrap()
}

/// The thesis polyhedra (as generated, and once randomly placed) and `random` random solids.
fn solids(rng: &mut Rng, random: usize) -> Vec<(String, ClosedMesh)> {
    let mut out = Vec::new();
    for (name, m) in thesis_polyhedra().unwrap() {
        out.push((name.to_string(), ClosedMesh::new(m.clone()).unwrap()));
        out.push((
            format!("{name} placed"),
            ClosedMesh::new(placed(&m, rng)).unwrap(),
        ));
    }
    for k in 0..random {
        let (name, m) = match k % 3 {
            0 => {
                let big = rng.range(1.0, 2.0);
                let around = 6 + (rng.f64() * 14.0) as usize;
                let tube = 3 + (rng.f64() * 8.0) as usize;
                (
                    format!("torus {k}"),
                    torus(big, big * rng.range(0.15, 0.8), around, tube).unwrap(),
                )
            }
            1 => {
                let points = 2 + (rng.f64() * 7.0) as usize;
                let inner = rng.range(0.1, 0.9);
                (
                    format!("star {k}"),
                    extruded_star(points, inner, 1.0, rng.range(0.05, 1.5)).unwrap(),
                )
            }
            _ => (
                format!("bumpy {k}"),
                bumpy_sphere(1, rng.range(0.1, 0.6), rng.next_u64()).unwrap(),
            ),
        };
        out.push((name, ClosedMesh::new(placed(&m, rng)).unwrap()));
    }
    out
}

/// Viewpoints: around the solid, inside its bounding box, close to its surface (both sides).
fn viewpoints(mesh: &TriangleMesh, rng: &mut Rng, n: usize) -> Vec<DVec3> {
    let b = mesh.bounding_sphere();
    let (lo, hi) = mesh.vertices().iter().fold(
        (DVec3::splat(f64::MAX), DVec3::splat(f64::MIN)),
        |(l, h), &v| (l.min(v), h.max(v)),
    );
    (0..n)
        .map(|i| match i % 3 {
            0 => b.center + rng.dir() * b.radius * rng.range(1.05, 8.0),
            1 => DVec3::new(
                rng.range(lo.x, hi.x),
                rng.range(lo.y, hi.y),
                rng.range(lo.z, hi.z),
            ),
            _ => {
                let t = (rng.f64() * mesh.triangle_count() as f64) as usize;
                let [a, c, d] = mesh.triangle(t);
                let (mut u, mut w) = (rng.f64(), rng.f64());
                if u + w > 1.0 {
                    (u, w) = (1.0 - u, 1.0 - w);
                }
                let off = b.radius * 10f64.powf(rng.range(-9.0, -2.0));
                let side = if rng.f64() < 0.5 { 1.0 } else { -1.0 };
                a + (c - a) * u + (d - a) * w + mesh.triangle_normal(t) * off * side
            }
        })
        .collect()
}

/// The union of the projections of the front triangles, by the sphere layer's set operations
/// (pairwise, as a balanced tree).
fn front_union(mesh: &TriangleMesh, frame: &ShadingFrame) -> Result<SphericalPolygon, GeomError> {
    let mut parts: Vec<SphericalPolygon> = Vec::new();
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

/// Angular distance from the unit `d` to the minor arc `a-b`.
fn arc_distance(d: DVec3, a: DVec3, b: DVec3) -> f64 {
    let n = a.cross(b);
    if let Some(n) = n.try_normalize() {
        let p = d - n * d.dot(n);
        if a.cross(p).dot(n) >= 0.0 && p.cross(b).dot(n) >= 0.0 {
            return d.dot(n).abs().asin();
        }
    }
    d.angle_between(a).min(d.angle_between(b))
}

fn boundary_distance(p: &SphericalPolygon, d: DVec3) -> f64 {
    p.rings()
        .flat_map(|r| (0..r.len()).map(move |i| (r[i], r[(i + 1) % r.len()])))
        .map(|(a, b)| arc_distance(d, a, b))
        .fold(f64::INFINITY, f64::min)
}

/// Whether the ray from `x` along the world direction `w` hits a front triangle, by Moeller–
/// Trumbore in floating point: `Some(hit)` when every front triangle is clearly hit or clearly
/// missed (barycentric margin `1e-9`), `None` when one is too close to call.
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
        let dist = e2.dot(q) / det;
        let m = 1e-9;
        let inside = u > m && v > m && 1.0 - u - v > m;
        let outside = u < -m || v < -m || 1.0 - u - v < -m;
        if !inside && !outside {
            return None;
        }
        if inside && dist > 0.0 {
            hit = true;
        }
    }
    Some(hit)
}

/// Whether the ray from `x` along the world direction `w` lies in the closed cone of a front
/// triangle, by exact `orient3d` on `x` and `x + w`.
fn exactly_covered(mesh: &TriangleMesh, x: DVec3, w: DVec3) -> bool {
    let c = |p: DVec3| robust::Coord3D {
        x: p.x,
        y: p.y,
        z: p.z,
    };
    let q = x + w;
    (0..mesh.triangle_count())
        .filter(|&f| face_side(mesh, f, x) == Side::Front)
        .any(|f| {
            let t = mesh.triangle(f);
            (0..3).all(|e| robust::orient3d(c(t[e]), c(t[(e + 1) % 3]), c(q), c(x)) <= 0.0)
        })
}

/// What the set-operation reference said about one silhouette.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Reference {
    /// The symmetric difference is below `1e-10 * 4 pi`.
    Agreed,
    /// The set operations gave up (`Undecidable`): no symmetric difference to check.
    GaveUp,
    /// The symmetric difference is larger, and exact cone tests inside it side with the
    /// silhouette everywhere: the set operations' union was wrong.
    Wrong,
}

/// Directions sampled inside the symmetric difference when it exceeds the bound (uniformly, where
/// it can be triangulated, and at each of several distances off its edges).
const XOR_SAMPLES: usize = 400;

/// Directions in a region: [`XOR_SAMPLES`] uniform ones where [`PolygonSampler`] triangulates it
/// (a thin sliver often cannot be), and as many points of its edges each moved to the interior
/// side by `1e-11` to `1e-4` rad, so that slivers of any width from about `1e-11` rad get
/// directions inside them. (A direction outside the region is harmless: the caller tests the
/// silhouette against exact cone tests, which must agree everywhere off its boundary.)
fn inside_samples(region: &SphericalPolygon, rng: &mut Rng) -> Vec<DVec3> {
    let mut out = Vec::new();
    if let Ok(s) = PolygonSampler::new(region) {
        out.extend((0..XOR_SAMPLES).map(|_| s.sample(DVec2::new(rng.f64(), rng.f64()))));
    }
    let edges: Vec<(DVec3, DVec3)> = region
        .rings()
        .flat_map(|r| (0..r.len()).map(move |i| (r[i], r[(i + 1) % r.len()])))
        .collect();
    if edges.is_empty() {
        return out;
    }
    for k in 0..XOR_SAMPLES {
        let (a, b) = edges[(rng.f64() * edges.len() as f64) as usize % edges.len()];
        let Some(inward) = a.cross(b).try_normalize() else {
            continue;
        };
        let t = rng.f64();
        let on = (a * (1.0 - t) + b * t).normalize();
        let off = 10f64.powi(-11 + (k % 8) as i32);
        out.push((on + inward * off).normalize());
    }
    out
}

/// Directions inside the symmetric difference closer than this (rad) to the silhouette's
/// boundary are not tested: the silhouette's vertices are rounded crossing points, a few ulps
/// off the exact boundary.
const XOR_MARGIN: f64 = 1e-12;

/// Checks one silhouette against both references.
///
/// The set-operation reference is strict: a symmetric difference above `1e-10 * 4 pi` fails,
/// unless exact cone tests ([`exactly_covered`]) at directions inside the symmetric difference
/// itself ([`inside_samples`], those farther than [`XOR_MARGIN`] from the silhouette's
/// boundary) all agree with the silhouette, which makes the set operations' union the wrong
/// one. Sampling inside the difference finds a wrong sliver of any size, where directions over
/// the whole sphere would almost never land in it.
fn check(
    name: &str,
    mesh: &TriangleMesh,
    frame: &ShadingFrame,
    sil: &SphericalPolygon,
    rng: &mut Rng,
    min_directions: usize,
) -> Reference {
    let x = frame.origin();
    // Valid: the rings rebuild into the same polygon.
    if !sil.is_full() && !sil.is_empty() {
        let rings: Vec<Vec<DVec3>> = sil.rings().map(|r| r.to_vec()).collect();
        SphericalPolygon::new(rings).unwrap_or_else(|e| panic!("{name} x {x}: invalid: {e}"));
    }
    // Direction by direction. The frame's local axes are the world axes rotated; directions are
    // compared in the local frame.
    let mut checked = 0;
    let vertices: Vec<DVec3> = sil.rings().flatten().copied().collect();
    for k in 0..160 {
        let d = if k % 2 == 0 || vertices.is_empty() {
            rng.dir()
        } else {
            // Near a silhouette vertex, where the pieces meet.
            let v = vertices[(rng.f64() * vertices.len() as f64) as usize % vertices.len()];
            (v + rng.dir() * 10f64.powf(rng.range(-6.0, -2.0))).normalize()
        };
        if boundary_distance(sil, d) < 1e-9 {
            continue;
        }
        let Some(hit) = ray_hits_front(mesh, x, frame.dir_to_world(d)) else {
            continue;
        };
        assert_eq!(
            sil.contains(d),
            hit,
            "{name} x {x}: direction {d} (local) contained {} but ray hit {hit}",
            sil.contains(d)
        );
        checked += 1;
    }
    assert!(
        checked >= min_directions,
        "{name} x {x}: only {checked} directions checked"
    );
    // Symmetric difference with the union of the front triangles.
    let (xor, u) =
        match front_union(mesh, frame).and_then(|u| Ok((sil.boolean(&u, BoolOp::Xor)?, u))) {
            Ok(r) => r,
            Err(e) => {
                assert!(e.is_undecidable(), "{name} x {x}: reference failed: {e}");
                return Reference::GaveUp;
            }
        };
    let area = xor.solid_angle();
    if area <= 1e-10 * 4.0 * PI {
        return Reference::Agreed;
    }
    let mut tested = 0;
    for d in inside_samples(&xor, rng) {
        if boundary_distance(sil, d) <= XOR_MARGIN {
            continue;
        }
        tested += 1;
        let exact = exactly_covered(mesh, x, frame.dir_to_world(d));
        assert_eq!(
            sil.contains(d),
            exact,
            "{name} x {x}: symmetric difference {area} sr (silhouette {}, union {}); inside \
             it, direction {d} (local) is covered {exact} by exact tests",
            sil.solid_angle(),
            u.solid_angle()
        );
    }
    assert!(
        tested >= XOR_SAMPLES,
        "{name} x {x}: symmetric difference {area} sr: only {tested} directions tested"
    );
    eprintln!(
        "{name} x {x}: the union of front faces is wrong by {area} sr (silhouette {}, union {}); \
         the silhouette agrees with exact cone tests at {tested} directions inside the difference",
        sil.solid_angle(),
        u.solid_angle()
    );
    Reference::Wrong
}

#[test]
fn silhouettes_equal_the_union_of_front_faces() {
    let mut rng = Rng::new(0x5111_0e77);
    let solids = solids(&mut rng, 18 * multiplier());
    let (mut total, mut undecidable, mut holes) = (0, 0, 0);
    let (mut gave_up, mut wrong) = (0, 0);
    for (name, solid) in &solids {
        let mesh = solid.mesh();
        for x in viewpoints(mesh, &mut rng, 18 * multiplier()) {
            total += 1;
            let frame = ShadingFrame::new(x, DVec3::Z, DVec3::Z).unwrap();
            match nonconvex_silhouette(solid, &frame) {
                Ok(sil) => {
                    if sil.ring_count() > 1 {
                        holes += 1;
                    }
                    match check(name, mesh, &frame, &sil, &mut rng, 40) {
                        Reference::Agreed => {}
                        Reference::GaveUp => gave_up += 1,
                        Reference::Wrong => wrong += 1,
                    }
                }
                Err(e) => {
                    assert!(e.is_undecidable(), "{name} x {x}: {e}");
                    eprintln!("give-up: {name} x {x}: {e}");
                    undecidable += 1;
                }
            }
        }
    }
    eprintln!(
        "{total} viewpoints on {} solids: {undecidable} give-ups; set-operation reference: \
         {gave_up} gave up, {wrong} wrong (the silhouette confirmed by exact tests inside the \
         difference); {holes} with several rings",
        solids.len()
    );
    assert!(
        undecidable * 200 <= total,
        "{undecidable} give-ups of {total}"
    );
    // No budget: every silhouette is held to the set-operation reference (1e-10 * 4 pi, or
    // exact tests inside the difference, see `check`), which must neither give up nor be wrong
    // on these viewpoints (none of either in 9 720 viewpoints with SIL_CASES=5).
    assert!(
        gave_up == 0 && wrong == 0,
        "{gave_up} reference give-ups and {wrong} wrong references of {total}"
    );
    assert!(holes * 10 >= total, "only {holes} multi-ring silhouettes");
}

#[test]
fn torus_seen_along_its_axis_has_a_hole() {
    // The hole is where the axis is seen through; its solid angle is that of the inner rim
    // seen from the point (a regular polygon's cone, bounded by the exact circle's).
    let solid = ClosedMesh::new(torus(2.0, 0.5, 32, 12).unwrap()).unwrap();
    for z in [3.0, 10.0, -5.0] {
        let frame = ShadingFrame::new(DVec3::new(0.0, 0.0, z), DVec3::Z, DVec3::Z).unwrap();
        let sil = nonconvex_silhouette(&solid, &frame).unwrap();
        assert_eq!(sil.ring_count(), 2, "z {z}");
        let to_center = frame.dir_to_local(-DVec3::Z * z.signum());
        assert!(!sil.contains(to_center));
        // The tube is seen at 90 degrees from the axis.
        assert!(sil.contains(frame.dir_to_local(DVec3::new(2.0, 0.0, -z))));
    }
}

#[test]
fn degenerate_viewpoints_give_valid_polygons_or_give_ups() {
    // Vertices, edge midpoints and points on edges' lines beyond them, face centroids, points in
    // face planes outside the faces, on each thesis polyhedron and a torus: a valid polygon
    // (compared with the union of front faces when that succeeds) or a give-up.
    let mut rng = Rng::new(77);
    let mut meshes: Vec<(String, ClosedMesh)> = thesis_polyhedra()
        .unwrap()
        .into_iter()
        .map(|(n, m)| (n.to_string(), ClosedMesh::new(m).unwrap()))
        .collect();
    meshes.push((
        "torus".into(),
        ClosedMesh::new(torus(1.0, 0.4, 10, 6).unwrap()).unwrap(),
    ));
    let (mut ok, mut gave_up) = (0, 0);
    // The set-operation reference's outcomes: agreed, gave up, wrong (see `Reference`).
    let mut references = [0usize; 3];
    for (name, solid) in &meshes {
        let mesh = solid.mesh();
        let mut points: Vec<DVec3> = mesh.vertices().to_vec();
        for e in mesh.edges() {
            let (a, b) = (mesh.vertices()[e.a as usize], mesh.vertices()[e.b as usize]);
            points.push((a + b) * 0.5);
            points.push(a + (b - a) * 2.5);
            points.push(a - (b - a) * 0.75);
        }
        for t in 0..mesh.triangle_count() {
            let [a, b, c] = mesh.triangle(t);
            points.push((a + b + c) / 3.0);
            points.push(a + (b - a) * 1.7 + (c - a) * 0.9);
        }
        for x in points {
            let frame = ShadingFrame::new(x, DVec3::Z, DVec3::X).unwrap();
            match nonconvex_silhouette(solid, &frame) {
                Ok(sil) => {
                    ok += 1;
                    references[check(name, mesh, &frame, &sil, &mut rng, 40) as usize] += 1;
                }
                Err(e) => {
                    assert!(e.is_undecidable(), "{name} x {x}: {e}");
                    gave_up += 1;
                }
            }
        }
    }
    eprintln!(
        "degenerate viewpoints: {ok} valid, {gave_up} give-ups; set-operation reference: {} \
         agreed, {} gave up, {} wrong",
        references[0], references[1], references[2]
    );
    assert!(ok > 100);
}

#[test]
fn viewpoint_next_to_a_vertex() {
    // Fuzz finding (solid_silhouette): seen from 5e-8 off a torus vertex, inside, the crossing
    // and foot points near that vertex were computed from the far end of their edge, as the
    // small difference of long vectors, and the silhouette was off by a sliver of 1e-8 sr
    // (about 1e-9 rad wide) against the union of front faces; an exact cone test confirmed
    // the sliver is not covered. Both points are now computed from the nearer end.
    let m = torus(1.0, 0.8, 16, 4).unwrap();
    let r = DMat3::from_quat(arealight::glam::DQuat::from_xyzw(1.0, 1.0, 1.0, 1.0).normalize());
    let m = TriangleMesh::new(
        m.vertices().iter().map(|&v| r * v).collect(),
        m.triangles().to_vec(),
    )
    .unwrap();
    let solid = ClosedMesh::new(m.clone()).unwrap();
    let size = m.bounding_sphere().radius;
    let mut rng = Rng::new(5);
    let mut checked = 0;
    for t in 0..m.triangle_count() {
        for exp in [25, 35, 45] {
            let [a, _, _] = m.triangle(t);
            for side in [1.0, -1.0] {
                let x = a + m.triangle_normal(t) * side * size * 2f64.powi(-exp);
                for view in [DVec3::Z, DVec3::new(-2.0, -2.0, -1.9)] {
                    let frame = ShadingFrame::new(x, DVec3::Z, view).unwrap();
                    if let Ok(sil) = nonconvex_silhouette(&solid, &frame)
                        // Rays from so close to a vertex meet its faces within the ray cast's
                        // margin: the set operations are the reference here.
                        && check("torus near a vertex", &m, &frame, &sil, &mut rng, 0)
                            == Reference::Agreed
                    {
                        checked += 1;
                    }
                }
            }
        }
    }
    assert!(checked > 400, "{checked}");
}

#[test]
fn sphere_union_of_a_near_hemisphere_triangle_and_a_sliver() {
    // Two front triangles of an extruded star seen from 2.4e-7 off a face: A spans nearly a
    // hemisphere (two vertices 1.7e-6 from antipodal), B is a 3.4e-7 sr sliver sharing the edge
    // from A's first to its third vertex. Their union is about 4.05 sr; the sphere layer returns
    // 8.83 sr (a ring along the x = 0 great circle appears), wrong for 1556 of 4000 random
    // directions. The silhouette, which uses no set operation, was right there.
    let a = SphericalPolygon::new(vec![vec![
        DVec3::new(
            -4.4481329916957083e-7,
            -0.9999999999997875,
            -4.769385735380907e-7,
        ),
        DVec3::new(
            -1.1527555922126974e-6,
            0.9999999999985718,
            -1.2360098243789015e-6,
        ),
        DVec3::new(
            0.9398671813687637,
            0.18472134254898276,
            -0.28727635996168666,
        ),
    ]])
    .unwrap();
    let b = SphericalPolygon::new(vec![vec![
        DVec3::new(
            0.8597540945310062,
            -0.4379094511686852,
            -0.26278928728985607,
        ),
        DVec3::new(
            -4.4481329916957083e-7,
            -0.9999999999997875,
            -4.769385735380907e-7,
        ),
        DVec3::new(
            0.9398671813687637,
            0.18472134254898276,
            -0.28727635996168666,
        ),
    ]])
    .unwrap();
    let u = a.boolean(&b, BoolOp::Union).unwrap();
    let expect = a.solid_angle() + b.solid_angle();
    assert!(
        (u.solid_angle() - expect).abs() < 1e-9,
        "{} vs {expect}",
        u.solid_angle()
    );
}
