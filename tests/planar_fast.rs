//! The generic-position fast path against the robust pipeline: wherever the fast path returns a
//! result, it must be identical (same contours, points, starting points and order) to the robust
//! pipeline's; on degenerate inputs it must bail out. Inputs: random stars, shapes with holes,
//! integer-grid polygons (exact degeneracies), and near-degenerate pairs (vertices a few ulps off
//! the other operand's edges, near-copies, slightly rotated copies, far from the origin).

mod support;

use arealight::glam::DVec2;
use arealight::internals::{boolean_fast, boolean_robust};
use arealight::planar::{BoolOp, Shape, boolean};
use proptest::prelude::*;
use support::Rng;
use support::planar::*;

/// Runs all four operations both ways; returns how many the fast path took.
fn agree(a: &Shape, b: &Shape) -> Result<usize, TestCaseError> {
    let mut taken = 0;
    for op in OPS {
        let robust = boolean_robust(a, b, op);
        let fast = boolean_fast(a, b, op);
        match (fast, robust) {
            (Ok(Some(f)), Ok(r)) => {
                prop_assert_eq!(&f, &r, "{}\nA = {:?}\nB = {:?}", op_name(op), a, b);
                taken += 1;
            }
            (Ok(None), _) => {}
            (Ok(Some(f)), Err(e)) => {
                return Err(TestCaseError::fail(format!(
                    "{}: fast path gave {f:?}, robust failed with {e}\nA = {a:?}\nB = {b:?}",
                    op_name(op)
                )));
            }
            (Err(e), _) => {
                return Err(TestCaseError::fail(format!(
                    "{}: fast path failed with {e}\nA = {a:?}\nB = {b:?}",
                    op_name(op)
                )));
            }
        }
        // The public entry point returns whichever ran, so it equals the robust result too.
        let auto = boolean(a, b, op).map_err(|e| TestCaseError::fail(e.to_string()))?;
        let robust = boolean_robust(a, b, op).map_err(|e| TestCaseError::fail(e.to_string()))?;
        prop_assert_eq!(auto, robust, "{}", op_name(op));
    }
    Ok(taken)
}

/// A star with a star-shaped hole around its centre, or with a second outer contour.
fn multi_shape() -> impl Strategy<Value = Shape> {
    (
        star_ring(10, 1.0),
        star_ring(6, 2.5),
        prop::collection::vec(0.05f64..0.09, 3..=6),
        any::<bool>(),
    )
        .prop_filter_map("invalid shape", |(outer, other, hole_radii, with_hole)| {
            let c = outer.iter().copied().sum::<DVec2>() / outer.len() as f64;
            let second = if with_hole {
                star(c, &hole_radii, 0.3)
            } else {
                other
            };
            Shape::new(vec![outer, second]).ok()
        })
}

fn grid_shape(max: usize) -> impl Strategy<Value = Shape> {
    (
        -2i32..=2,
        -2i32..=2,
        prop::collection::vec(1.0f64..5.0, 3..=max),
        0.0f64..6.3,
    )
        .prop_filter_map("invalid grid ring", |(cx, cy, radii, phase)| {
            let r: Vec<DVec2> = star(DVec2::new(cx as f64, cy as f64), &radii, phase)
                .into_iter()
                .map(|p| p.round())
                .collect();
            Shape::new(vec![r]).ok()
        })
}

/// Moves `p` by `k` units in the last place in x and `l` in y.
fn nudge(p: DVec2, k: i64, l: i64) -> DVec2 {
    let step = |v: f64, k: i64| {
        let mut v = v;
        for _ in 0..k.abs() {
            v = if k > 0 { v.next_up() } else { v.next_down() };
        }
        v
    };
    DVec2::new(step(p.x, k), step(p.y, l))
}

fn shape_of(rings: Vec<Vec<DVec2>>) -> Option<Shape> {
    Shape::new(rings).ok()
}

proptest! {
    #![proptest_config(ProptestConfig {
        cases: std::env::var("PLANAR_CASES").ok().and_then(|v| v.parse().ok()).unwrap_or(256),
        ..ProptestConfig::default()
    })]

    #[test]
    fn random_stars_agree(a in star_shape(24), b in star_shape(24)) {
        agree(&a, &b)?;
    }

    #[test]
    fn shapes_with_holes_agree(a in multi_shape(), b in multi_shape()) {
        agree(&a, &b)?;
    }

    #[test]
    fn grid_polygons_agree(a in grid_shape(12), b in grid_shape(12)) {
        agree(&a, &b)?;
    }

    /// A vertex of B placed on an edge of A (at parameter `t`, rounded) and then nudged by a
    /// few ulps: the fast path must see it as near and leave it to the robust path.
    #[test]
    fn vertex_within_ulps_of_an_edge_is_left_to_the_robust_path(
        a in star_shape(12),
        b in star_ring(12, 1.0),
        k in 0usize..12,
        j in 0usize..12,
        t in 0.05f64..0.95,
        dx in -40i64..40,
        dy in -40i64..40,
    ) {
        let ra: Vec<DVec2> = a.contours().next().unwrap().to_vec();
        let n = ra.len();
        let (p, q) = (ra[k % n], ra[(k + 1) % n]);
        let mut rb = b;
        let m = rb.len();
        rb[j % m] = nudge(p + (q - p) * t, dx, dy);
        if let Some(b) = shape_of(vec![rb]) {
            agree(&a, &b)?;
            for op in OPS {
                prop_assert!(boolean_fast(&a, &b, op).unwrap().is_none(), "{}: fast path took a vertex within ulps of an edge", op_name(op));
            }
        }
    }

    /// B is A moved by a tiny offset or turned by a tiny angle: long stretches of edges within
    /// rounding of each other.
    #[test]
    fn near_copies_agree(
        a in star_shape(16),
        shift in (-1e-12f64..1e-12, -1e-12f64..1e-12),
        angle in -1e-9f64..1e-9,
        big in any::<bool>(),
    ) {
        let s = if big { 1e4 } else { 1.0 };
        let (sin, cos) = (angle * s).sin_cos();
        let b = shape_of(vec![a.contours().next().unwrap().iter().map(|p| {
            DVec2::new(cos * p.x - sin * p.y, sin * p.x + cos * p.y) + DVec2::new(shift.0, shift.1) * s
        }).collect()]);
        if let Some(b) = b {
            agree(&a, &b)?;
        }
    }

    #[test]
    fn far_from_origin_agree(a in star_shape(12), b in star_shape(12), off in 1.0e3f64..1.0e7) {
        let shift = |s: &Shape| {
            shape_of(s.contours().map(|c| c.iter().map(|&p| p + DVec2::splat(off)).collect()).collect())
        };
        if let (Some(a), Some(b)) = (shift(&a), shift(&b)) {
            agree(&a, &b)?;
        }
    }
}

/// A star-shaped ring around `c` with `3 + floor(extra * u)` vertices.
fn random_star(rng: &mut Rng, c: DVec2, extra: f64) -> Vec<DVec2> {
    let n = 3 + (rng.f64() * extra) as usize;
    let radii: Vec<f64> = (0..n).map(|_| 0.2 + 1.8 * rng.f64()).collect();
    star(c, &radii, 6.3 * rng.f64())
}

/// The fast path is not a dead branch: on random stars in general position it takes most
/// operations (all but the symmetric difference, which it leaves to the robust path).
#[test]
fn fast_path_takes_generic_inputs() {
    let mut rng = Rng::new(1);
    let (mut taken, mut total) = (0, 0);
    for _ in 0..200 {
        let mut ring = |c: DVec2| random_star(&mut rng, c, 20.0);
        let a = Shape::new(vec![ring(DVec2::ZERO)]).unwrap();
        let c = DVec2::new(0.37, -0.21);
        let b = Shape::new(vec![ring(c)]).unwrap();
        taken += agree(&a, &b).unwrap();
        total += 3;
    }
    assert!(taken * 10 >= total * 9, "fast path took {taken} of {total}");
}

/// Exactly degenerate contacts (shared vertices, shared edges, identical contours, vertex on
/// edge) always go to the robust path.
#[test]
fn fast_path_bails_out_on_exact_degeneracies() {
    let cases = [
        ("0:0, 2:0, 2:2, 0:2", "2:0, 4:0, 4:2, 2:2"), // shared edge
        ("0:0, 2:0, 2:2, 0:2", "0:0, 2:0, 2:2, 0:2"), // identical
        ("0:0, 2:0, 2:2, 0:2", "1:0, 3:-1, 3:1"),     // vertex on edge
        ("0:0, 2:0, 2:2, 0:2", "2:2, 3:1, 3:3"),      // shared vertex
        ("0:0, 4:0, 4:4, 0:4; 1:1, 1:3, 3:3, 3:1", "3:3, 5:3, 5:5"), // vertex of a hole
        ("0:0, 2:0, 2:2, 0:2", "1:-1, 1:3, -1:1"),    // edge through a vertex
    ];
    for (a, b) in cases {
        let (a, b) = (shape(a), shape(b));
        for op in OPS {
            assert!(
                boolean_fast(&a, &b, op).unwrap().is_none(),
                "{}: {a:?} {b:?}",
                op_name(op)
            );
            assert!(
                boolean_fast(&b, &a, op).unwrap().is_none(),
                "{}: {b:?} {a:?}",
                op_name(op)
            );
        }
        agree(&a, &b).unwrap();
    }
}

/// The fast path leaves `a` op `b` and `b` op `a` to the robust path for every operation it
/// handles, and the results agree.
fn bails_out_both_ways(a: &Shape, b: &Shape) {
    for op in [BoolOp::Intersection, BoolOp::Union, BoolOp::Difference] {
        assert!(boolean_fast(a, b, op).unwrap().is_none(), "{}", op_name(op));
        assert!(boolean_fast(b, a, op).unwrap().is_none(), "{}", op_name(op));
    }
    agree(a, b).unwrap();
    agree(b, a).unwrap();
}

/// `a` as the result of an earlier operation (whose facts are computed on demand, not cached):
/// its union with a far-away unit square, which keeps `a`'s contours verbatim.
fn with_far_square(a: &Shape) -> Shape {
    boolean(a, &shape("10:10, 11:10, 11:11, 10:11"), BoolOp::Union).unwrap()
}

/// The benchmark inputs (benches/planar.rs) are in generic position and take the fast path, so
/// the benchmark measures it.
#[test]
fn benchmark_inputs_take_the_fast_path() {
    let polygon = bench_polygon;
    for star in [false, true] {
        for n in [4, 8, 16, 64] {
            let a = Shape::new(vec![polygon(n, DVec2::ZERO, 0.0, star)]).unwrap();
            let b = Shape::new(vec![polygon(n, DVec2::new(0.37, 0.21), 0.13, star)]).unwrap();
            for op in [BoolOp::Difference, BoolOp::Intersection, BoolOp::Union] {
                let f = boolean_fast(&a, &b, op).unwrap();
                assert!(f.is_some(), "{} star={star} n={n}: bailed out", op_name(op));
                assert_eq!(f.unwrap(), boolean_robust(&a, &b, op).unwrap());
            }
        }
    }
}

/// Two contours of one operand with vertices a few ulps apart: `Shape::new` caches the
/// operand's minimum vertex separation, and the fast path must leave the operand to the robust
/// path, which welds the two copies into one point (the fast path would keep both, and its
/// result would differ).
#[test]
fn near_duplicate_vertices_within_an_operand_bail_out() {
    let apex = DVec2::new(1.0, 1.0);
    let near = DVec2::new(1.0f64.next_up().next_up(), 1.0);
    let a = Shape::new(vec![
        vec![DVec2::new(0.0, 0.0), DVec2::new(2.0, 0.0), apex],
        vec![near, DVec2::new(2.0, 2.0), DVec2::new(0.0, 2.0)],
    ])
    .unwrap();
    // A band across both triangles, far from the near-duplicate pair and from every vertex.
    let b = Shape::new(vec![vec![
        DVec2::new(-1.0, 0.3),
        DVec2::new(3.0, 0.35),
        DVec2::new(3.0, 1.7),
        DVec2::new(-1.0, 1.65),
    ]])
    .unwrap();
    bails_out_both_ways(&a, &b);
    // The robust path welded the copies: the apex appears once, `near` never.
    let r = boolean(&a, &b, BoolOp::Intersection).unwrap();
    let pts: Vec<DVec2> = r.contours().flatten().copied().collect();
    assert!(pts.contains(&apex) && !pts.contains(&near), "{r:?}");

    // The same operand as the result of an earlier operation (whose facts are computed on
    // demand, not cached): a union with a far-away square keeps both triangles verbatim.
    let chained = with_far_square(&a);
    assert_eq!(chained.contours().count(), 3);
    for op in [BoolOp::Intersection, BoolOp::Union, BoolOp::Difference] {
        assert!(
            boolean_fast(&chained, &b, op).unwrap().is_none(),
            "{}",
            op_name(op)
        );
    }
    agree(&chained, &b).unwrap();
}

/// A hole whose vertex lies on an edge of its outer contour: `Shape::new` caches the self
/// contact, and the fast path must leave the operand to the robust path, which inserts the
/// vertex into the outer edge (and traces through it).
#[test]
fn vertex_on_an_edge_of_its_own_shape_bails_out() {
    let a = shape("0:0, 4:0, 4:4, 0:4; 2:0, 1:2, 3:2");
    // Crosses the outer contour's left and right edges only.
    let b = Shape::new(vec![vec![
        DVec2::new(-1.0, 3.0),
        DVec2::new(5.0, 2.7),
        DVec2::new(5.0, 5.0),
        DVec2::new(-1.0, 5.0),
    ]])
    .unwrap();
    bails_out_both_ways(&a, &b);
    let chained = with_far_square(&a);
    assert!(
        boolean_fast(&chained, &b, BoolOp::Difference)
            .unwrap()
            .is_none()
    );
    agree(&chained, &b).unwrap();
}

/// Results of earlier operations as operands (their facts are computed per operation, not
/// cached), on random stars: the fast path still agrees with the robust path, and takes most
/// of these operations.
#[test]
fn chained_results_agree() {
    let mut rng = Rng::new(2);
    let (mut taken, mut total) = (0, 0);
    for _ in 0..100 {
        let mut ring = |c: DVec2| random_star(&mut rng, c, 14.0);
        let a = Shape::new(vec![ring(DVec2::ZERO)]).unwrap();
        let b = Shape::new(vec![ring(DVec2::new(0.37, -0.21))]).unwrap();
        let c = Shape::new(vec![ring(DVec2::new(-0.3, 0.4))]).unwrap();
        for op in [BoolOp::Difference, BoolOp::Union, BoolOp::Intersection] {
            let r = boolean(&a, &b, op).unwrap();
            taken += agree(&r, &c).unwrap() + agree(&c, &r).unwrap();
            total += 6;
        }
    }
    assert!(taken * 10 >= total * 7, "fast path took {taken} of {total}");
}

/// Equality of shapes is equality of contours: a result equals the same contours built by
/// `Shape::new` (which caches facts that results compute on demand).
#[test]
fn shape_equality_ignores_cached_facts() {
    let a = shape("0:0, 4:0, 4:4, 0:4");
    let b = shape("2:1, 6:1, 6:3, 2:3");
    let r = boolean(&a, &b, BoolOp::Difference).unwrap();
    let rebuilt = Shape::new(r.contours().map(<[DVec2]>::to_vec).collect()).unwrap();
    assert_eq!(r, rebuilt);
    assert_eq!(format!("{r:?}"), format!("{rebuilt:?}"));
}
