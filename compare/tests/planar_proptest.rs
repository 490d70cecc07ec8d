//! Property tests: our boolean operations against the reference clippers i_overlay and clipper2,
//! and the area identities among our own results, on random and deliberately degenerate inputs.
//!
//! Every property runs a fixed 256 cases. Failures are persisted by proptest under
//! `proptest-regressions/` and each one is also turned into a named test in
//! the crate's `tests/planar_regressions.rs` (their reference checks in this package's
//! `tests/planar_regressions.rs`).

// The crate's shared test helpers (generators, text format), from the package next door.
#[path = "../../tests/support/mod.rs"]
mod support;

use arealight::glam::DVec2;
use arealight::planar::{BoolOp, Shape, boolean};
use arealight_compare::*;
use proptest::prelude::*;
use proptest::test_runner::FileFailurePersistence;
use support::planar::*;

/// Relative tolerance against the references (they snap to an integer grid).
const REF_TOL: f64 = 1e-7;
/// Relative tolerance for identities among our own results.
const ID_TOL: f64 = 1e-9;

/// 256 cases per property; `PLANAR_CASES=N` raises it for a longer hunt.
fn config() -> ProptestConfig {
    ProptestConfig {
        cases: std::env::var("PLANAR_CASES")
            .ok()
            .and_then(|v| v.parse().ok())
            .unwrap_or(256),
        failure_persistence: Some(Box::new(FileFailurePersistence::Direct(
            "proptest-regressions/planar_proptest.txt",
        ))),
        ..ProptestConfig::default()
    }
}

/// Checks identities, validity, and agreement with both references for all four operations.
fn check(a: &Shape, b: &Shape) -> Result<(), TestCaseError> {
    let results = check_all(a, b, ID_TOL).map_err(TestCaseError::fail)?;
    let norm = a.area() + b.area();
    for (op, r) in OPS.iter().zip(results.iter()) {
        let sd = sym_diff_vs_ioverlay(a, b, *op, r);
        prop_assert!(
            sd <= REF_TOL * norm,
            "{}: symmetric difference with i_overlay {sd} (norm {norm})\nA = {:?}\nB = {:?}\nours = {:?}",
            op_name(*op),
            a,
            b,
            r
        );
        // clipper2 is the second reference. Where it disagrees with i_overlay too, i_overlay
        // decides: clipper2's union fills a hole that touches the boundary at a single point
        // (found by this property; see `vertex_at_edge_midpoint_union` in
        // the crate's tests/planar_regressions.rs, whose areas are checked by hand there).
        let ca = clipper_area(a, b, *op);
        let ia = ioverlay_area(&ioverlay(&to_paths(a), &to_paths(b), *op));
        let refs_agree = (ca - ia).abs() <= REF_TOL * norm;
        prop_assert!(
            (ca - r.area()).abs() <= REF_TOL * norm || !refs_agree,
            "{}: area {} vs clipper2 {ca} (i_overlay {ia})\nA = {:?}\nB = {:?}",
            op_name(*op),
            r.area(),
            a,
            b
        );
    }
    Ok(())
}

/// A star with a hole (a smaller star around the same centre, inside the kernel disk), or two
/// stars that may overlap (rejected by `Shape::new` when they cross, so then only one).
fn multi_shape() -> impl Strategy<Value = Shape> {
    (
        star_ring(10, 1.0),
        star_ring(6, 2.0),
        prop::collection::vec(0.05f64..0.09, 3..=6),
        any::<bool>(),
    )
        .prop_filter_map("invalid shape", |(outer, other, hole_radii, with_hole)| {
            let c = outer.iter().copied().sum::<DVec2>() / outer.len() as f64;
            let mut rings = vec![outer.clone()];
            if with_hole {
                // Radii below 0.2 * cos(pi/3) stay inside the kernel disk of the star only when
                // centred at its centre; `Shape::new` rejects the rest.
                rings.push(star(c, &hole_radii, 0.3));
            } else {
                rings.push(other);
            }
            Shape::new(rings.clone())
                .ok()
                .or_else(|| Shape::new(vec![outer]).ok())
        })
}

/// A star on an integer grid: rounding creates collinear runs, vertices on edges, and (between
/// two such polygons) shared vertices and overlapping edges.
fn grid_ring(max: usize) -> impl Strategy<Value = Vec<DVec2>> {
    (
        -2i32..=2,
        -2i32..=2,
        prop::collection::vec(1.0f64..5.0, 3..=max),
        0.0f64..6.3,
    )
        .prop_map(|(cx, cy, radii, phase)| {
            star(DVec2::new(cx as f64, cy as f64), &radii, phase)
                .into_iter()
                .map(|p| DVec2::new(p.x.round(), p.y.round()))
                .collect()
        })
}

fn grid_shape(max: usize) -> impl Strategy<Value = Shape> {
    grid_ring(max).prop_filter_map("invalid grid ring", |r| Shape::new(vec![r]).ok())
}

fn gcd(a: i64, b: i64) -> i64 {
    if b == 0 { a.abs() } else { gcd(b, a % b) }
}

proptest! {
    #![proptest_config(config())]

    #[test]
    fn random_simple_polygons(a in star_shape(16), b in star_shape(16)) {
        check(&a, &b)?;
    }

    #[test]
    fn random_shapes_with_holes_and_several_outers(a in multi_shape(), b in multi_shape()) {
        check(&a, &b)?;
    }

    #[test]
    fn integer_grid_polygons(a in grid_shape(12), b in grid_shape(12)) {
        check(&a, &b)?;
    }

    #[test]
    fn copy_and_sub_polygon(a in grid_shape(12), keep in prop::collection::vec(any::<bool>(), 12)) {
        check(&a, &a.clone())?;
        // Any subset of the vertices of one ring, kept in order: often a sub-polygon sharing
        // vertices and edges with the original (rejected when it self-intersects).
        let ring: Vec<DVec2> = a.contours().next().unwrap().to_vec();
        let sub: Vec<DVec2> = ring
            .iter()
            .zip(keep.iter().cycle())
            .filter(|(_, k)| **k)
            .map(|(p, _)| *p)
            .collect();
        if let Ok(b) = Shape::new(vec![sub]) {
            check(&a, &b)?;
            check(&b, &a)?;
        }
    }

    #[test]
    fn shared_and_partially_overlapping_edges(a in grid_shape(10), k in 0usize..10, mirror in any::<bool>()) {
        let ring: Vec<DVec2> = a.contours().next().unwrap().to_vec();
        let n = ring.len();
        let (p, q) = (ring[k % n], ring[(k + 1) % n]);
        let b_ring: Vec<DVec2> = if mirror {
            // Reflect across the line through edge k: shares that edge, opposite direction.
            let d = q - p;
            ring.iter()
                .map(|&v| {
                    if v == p || v == q {
                        v
                    } else {
                        let t = (v - p).dot(d) / d.length_squared();
                        let foot = p + d * t;
                        foot * 2.0 - v
                    }
                })
                .collect()
        } else {
            // Slide along edge k by an exact lattice step: edge k of both stays collinear and
            // the two overlap partially.
            let (dx, dy) = ((q.x - p.x) as i64, (q.y - p.y) as i64);
            let g = gcd(dx, dy).max(1);
            let step = DVec2::new((dx / g) as f64, (dy / g) as f64);
            ring.iter().map(|&v| v + step).collect()
        };
        if let Ok(b) = Shape::new(vec![b_ring]) {
            check(&a, &b)?;
        }
    }

    #[test]
    fn vertex_on_edge_and_vertex_on_vertex(a in grid_shape(10), b in grid_ring(8), k in 0usize..10, j in 0usize..8, on_vertex in any::<bool>()) {
        let ra: Vec<DVec2> = a.contours().next().unwrap().to_vec();
        let n = ra.len();
        let (p, q) = (ra[k % n], ra[(k + 1) % n]);
        // Exactly on the edge: the midpoint of lattice points is exact in binary.
        let target = if on_vertex { p } else { (p + q) * 0.5 };
        let mut rb = b;
        let m = rb.len();
        rb[j % m] = target;
        if let Ok(b) = Shape::new(vec![rb]) {
            check(&a, &b)?;
        }
    }

    #[test]
    fn far_from_origin(a in star_shape(8), b in star_shape(8), off in 1.0e5f64..1.0e6) {
        let shift = |s: &Shape| {
            Shape::new(s.contours().map(|c| c.iter().map(|&p| p + DVec2::splat(off)).collect()).collect())
        };
        if let (Ok(a), Ok(b)) = (shift(&a), shift(&b)) {
            // Identities only: the references' integer grids are too coarse at this offset.
            check_all(&a, &b, ID_TOL).map_err(TestCaseError::fail)?;
        }
    }

    #[test]
    fn chains_compose(tris in prop::collection::vec(grid_ring(3), 1..12), light in grid_shape(8)) {
        // Light minus several occluders one by one equals light minus their union.
        let mut visible = light.clone();
        let mut occ = Shape::empty();
        for t in tris {
            let Ok(t) = Shape::new(vec![t]) else { continue };
            visible = boolean(&visible, &t, BoolOp::Difference).map_err(|e| TestCaseError::fail(e.to_string()))?;
            occ = boolean(&occ, &t, BoolOp::Union).map_err(|e| TestCaseError::fail(e.to_string()))?;
            visible.validate().map_err(|e| TestCaseError::fail(e.to_string()))?;
            occ.validate().map_err(|e| TestCaseError::fail(e.to_string()))?;
        }
        let direct = boolean(&light, &occ, BoolOp::Difference).map_err(|e| TestCaseError::fail(e.to_string()))?;
        prop_assert!((direct.area() - visible.area()).abs() <= ID_TOL * light.area());
    }

    #[test]
    fn chains_over_float_mesh_fan(
        c in (-0.5f64..0.5, -0.5f64..0.5),
        radii in prop::collection::vec(0.5f64..3.0, 6..40),
        skip in prop::collection::vec(any::<bool>(), 40),
        light in star_shape(12),
    ) {
        // A projected triangle fan: float coordinates, every triangle sharing the apex and two
        // edges with its neighbours, subtracted one by one and compared with union-first.
        let apex = DVec2::new(c.0, c.1);
        let ring = star(apex, &radii, 0.1);
        let n = ring.len();
        let mut visible = light.clone();
        let mut occ = Shape::empty();
        for k in 0..n {
            if skip[k] {
                continue;
            }
            let Ok(t) = Shape::new(vec![vec![apex, ring[k], ring[(k + 1) % n]]]) else { continue };
            visible = boolean(&visible, &t, BoolOp::Difference).map_err(|e| TestCaseError::fail(e.to_string()))?;
            occ = boolean(&occ, &t, BoolOp::Union).map_err(|e| TestCaseError::fail(e.to_string()))?;
            visible.validate().map_err(|e| TestCaseError::fail(format!("visible: {e}")))?;
            occ.validate().map_err(|e| TestCaseError::fail(format!("occ: {e}")))?;
        }
        let direct = boolean(&light, &occ, BoolOp::Difference).map_err(|e| TestCaseError::fail(e.to_string()))?;
        prop_assert!((direct.area() - visible.area()).abs() <= ID_TOL * light.area(),
            "chain {} vs union-first {}", visible.area(), direct.area());
    }
}
