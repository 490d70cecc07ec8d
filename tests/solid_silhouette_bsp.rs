//! BSP-precomputed silhouettes (`solid::SilhouetteBsp`, thesis 003 section 5) against the
//! direct algorithms (`convex_silhouette`, `nonconvex_silhouette`): on the polyhedra of the
//! thesis's table 7.1 and random non-convex solids, a query must return the same polygon as the
//! direct algorithm (bit for bit, or as sets: symmetric difference below 1e-12 sr) at random
//! points in the BSP's box, near the solid, and near its splitting planes (1e-11 to 1e-5 of the
//! solid's size off a random plane, on both sides), and outside the box (where the query answers
//! directly).
//!
//! The default run takes 2 000 points per solid; `BSP_POINTS=100000 cargo test --release --test
//! solid_silhouette_bsp` runs the 10^5.

mod support;

use arealight::GeomError;
use arealight::glam::{DMat3, DQuat, DVec3};
use arealight::internals::{
    bumpy_sphere, convex_silhouette, extruded_star, thesis_polyhedra, torus,
};
use arealight::planar::BoolOp;
use arealight::solid::{
    ClosedMesh, ConvexPolyhedron, ShadingFrame, SilhouetteBsp, TriangleMesh, nonconvex_silhouette,
};
use arealight::sphere::SphericalPolygon;
use support::Rng;

fn points_per_solid() -> usize {
    std::env::var("BSP_POINTS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(2000)
}

fn direct(solid: &ClosedMesh, frame: &ShadingFrame) -> Result<SphericalPolygon, GeomError> {
    match ConvexPolyhedron::from_mesh(solid.mesh()) {
        Ok(p) => convex_silhouette(&p, frame),
        Err(_) => nonconvex_silhouette(solid, frame),
    }
}

/// Random points for one solid: a third uniform in the box, a third near the solid, a third
/// near a random splitting plane.
fn sample(bsp: &SilhouetteBsp, mesh: &TriangleMesh, rng: &mut Rng) -> DVec3 {
    let (lo, hi) = bsp.region();
    let b = mesh.bounding_sphere();
    let in_box = |rng: &mut Rng, lo: DVec3, hi: DVec3| {
        DVec3::new(
            rng.range(lo.x, hi.x),
            rng.range(lo.y, hi.y),
            rng.range(lo.z, hi.z),
        )
    };
    match (rng.f64() * 3.0) as u32 {
        0 => in_box(rng, lo, hi),
        1 => in_box(
            rng,
            b.center - DVec3::splat(1.5 * b.radius),
            b.center + DVec3::splat(1.5 * b.radius),
        ),
        _ => {
            let planes = bsp.plane_equations();
            let (n, d) = planes[(rng.f64() * planes.len() as f64) as usize % planes.len()];
            // A point near the solid, projected onto the plane, then pushed off it.
            let p = b.center + rng.dir() * b.radius * rng.range(0.0, 3.0);
            let on = p - n * (n.dot(p) - d);
            let off = b.radius * 10f64.powf(rng.range(-11.0, -5.0));
            on + n * if rng.f64() < 0.5 { off } else { -off }
        }
    }
}

/// Angular distance from the unit `d` to the boundary of `p`.
fn boundary_distance(p: &SphericalPolygon, d: DVec3) -> f64 {
    let mut best = f64::INFINITY;
    for r in p.rings() {
        for i in 0..r.len() {
            let (a, b) = (r[i], r[(i + 1) % r.len()]);
            let n = a.cross(b).normalize();
            let q = d - n * d.dot(n);
            let along = a.cross(q).dot(n) >= 0.0 && q.cross(b).dot(n) >= 0.0;
            let dist = if along {
                d.dot(n).abs().asin()
            } else {
                d.angle_between(a).min(d.angle_between(b))
            };
            best = best.min(dist);
        }
    }
    best
}

/// Whether two polygons are the same set: equal as values, or a symmetric difference below
/// `1e-12` sr; where the sphere layer's set operation gives up, equal solid angles (within
/// `1e-12`) and equal containment of 2000 random directions farther than `1e-9` rad from both
/// boundaries.
fn same_set(a: &SphericalPolygon, b: &SphericalPolygon, rng: &mut Rng) -> bool {
    if a == b {
        return true;
    }
    match a.boolean(b, BoolOp::Xor) {
        Ok(x) => x.solid_angle() <= 1e-12,
        Err(e) => {
            assert!(e.is_undecidable(), "{e}");
            if (a.solid_angle() - b.solid_angle()).abs() > 1e-12 {
                return false;
            }
            (0..2000).all(|_| {
                let d = rng.dir();
                boundary_distance(a, d) < 1e-9
                    || boundary_distance(b, d) < 1e-9
                    || a.contains(d) == b.contains(d)
            })
        }
    }
}

fn check_solid(name: &str, solid: &ClosedMesh, rng: &mut Rng, n: usize) -> (usize, usize) {
    let mesh = solid.mesh();
    let bsp = SilhouetteBsp::build(solid).unwrap();
    assert!(bsp.leaf_count() > 1 && bsp.node_count() == 2 * bsp.leaf_count() - 1);
    let (mut checked, mut gave_up) = (0, 0);
    for _ in 0..n {
        let x = sample(&bsp, mesh, rng);
        let frame = ShadingFrame::new(x, DVec3::Z, DVec3::new(0.2, 0.1, 1.0)).unwrap();
        match (bsp.query(&frame), direct(solid, &frame)) {
            (Ok(q), Ok(d)) => {
                let same = same_set(&q, &d, rng);
                assert!(
                    same,
                    "{name} x {x}: query {} sr ({} rings), direct {} sr ({} rings)",
                    q.solid_angle(),
                    q.ring_count(),
                    d.solid_angle(),
                    d.ring_count()
                );
                checked += 1;
            }
            (q, d) => {
                // Only give-ups, and only together or at points within rounding of a plane.
                for r in [&q, &d] {
                    if let Err(e) = r {
                        assert!(e.is_undecidable(), "{name} x {x}: {e}");
                    }
                }
                gave_up += 1;
            }
        }
    }
    // Outside the box: answered directly.
    let (lo, hi) = bsp.region();
    for k in 0..20 {
        let x = hi + (hi - lo) * (0.01 + k as f64) * DVec3::new(1.0, -0.5, 0.25);
        let frame = ShadingFrame::new(x, DVec3::Z, DVec3::Z).unwrap();
        assert_eq!(bsp.query(&frame), direct(solid, &frame), "{name} outside");
    }
    eprintln!(
        "{name}: {} nodes, {} planes, {} bytes; {checked} points equal, {gave_up} give-ups",
        bsp.node_count(),
        bsp.plane_count(),
        bsp.byte_size()
    );
    (checked, gave_up)
}

#[test]
fn queries_equal_direct_silhouettes_on_the_thesis_polyhedra() {
    let mut rng = Rng::new(0xb5b);
    let n = points_per_solid();
    for (name, m) in thesis_polyhedra().unwrap() {
        let (checked, gave_up) = check_solid(name, &ClosedMesh::new(m).unwrap(), &mut rng, n);
        assert!(gave_up * 1000 <= n, "{name}: {gave_up} give-ups");
        assert!(checked + gave_up == n);
    }
}

#[test]
fn queries_equal_direct_silhouettes_on_random_solids() {
    let mut rng = Rng::new(0xb5c);
    let n = points_per_solid() / 2;
    for k in 0..6 {
        let m = match k % 3 {
            0 => torus(1.0, rng.range(0.2, 0.6), 8, 4).unwrap(),
            1 => extruded_star(3 + k / 3, rng.range(0.3, 0.7), 1.0, rng.range(0.1, 0.5)).unwrap(),
            _ => bumpy_sphere(0, rng.range(0.2, 0.5), rng.next_u64()).unwrap(),
        };
        // A random rotation, so that no plane is axis-aligned.
        let q = DQuat::from_xyzw(
            rng.range(-1.0, 1.0),
            rng.range(-1.0, 1.0),
            rng.range(-1.0, 1.0),
            rng.range(-1.0, 1.0),
        )
        .normalize();
        let r = DMat3::from_quat(q);
        let m = TriangleMesh::new(
            m.vertices()
                .iter()
                .map(|&v| r * v + DVec3::new(0.3, -0.1, 0.2))
                .collect(),
            m.triangles().to_vec(),
        )
        .unwrap();
        let (checked, gave_up) = check_solid(
            &format!("solid {k}"),
            &ClosedMesh::new(m).unwrap(),
            &mut rng,
            n,
        );
        assert!(
            gave_up * 1000 <= n && checked > 0,
            "solid {k}: {gave_up} give-ups"
        );
    }
}

#[test]
fn sphere_42_fits_the_size_goal() {
    // Thesis 003 table 7.4: 147,660 nodes and 6.7 MB for the subdivided icosahedron; the goal
    // here is at most 2 MB (deterministic: the tree does not depend on timing).
    let (_, sphere) = thesis_polyhedra().unwrap().swap_remove(4);
    assert_eq!(sphere.vertices().len(), 42);
    let bsp = SilhouetteBsp::build(&ClosedMesh::new(sphere).unwrap()).unwrap();
    eprintln!(
        "sphere-42: {} nodes, {} silhouette vertices, {} bytes",
        bsp.node_count(),
        bsp.silhouette_elements(),
        bsp.byte_size()
    );
    assert!(bsp.byte_size() <= 2_000_000, "{}", bsp.byte_size());
}
