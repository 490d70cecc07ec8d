//! Shared driver of the planar fuzz targets: decode two shapes, run one operation, and assert
//! the result is valid, equals the robust pipeline's wherever the generic-position fast path
//! answers, and the area identities hold.
//!
//! Coordinates come from small integers (so shared vertices, collinear overlaps and vertices on
//! edges are frequent), optionally scaled and offset to reach gnomonic magnitudes (`1e6`).
//! Invalid inputs (rejected by `Shape::new`) are skipped: the targets assert invariants of
//! valid inputs, not that arbitrary bytes are valid.

use arealight::glam::DVec2;
use arealight::internals::{boolean_fast, boolean_robust};
use arealight::planar::{BoolOp, Shape, boolean};
use libfuzzer_sys::arbitrary::{self, Arbitrary};

/// One fuzz case. `Debug` prints the rings so a crash pastes into a regression test.
#[derive(Debug, Arbitrary)]
pub struct Case {
    a: Vec<Vec<(i8, i8)>>,
    b: Vec<Vec<(i8, i8)>>,
    /// Scale exponent: coordinates are multiplied by `2^(scale % 24 - 8)`.
    scale: u8,
    /// Offset exponent: every coordinate is shifted by `10^(offset % 7)` when `offset > 127`.
    offset: u8,
}

/// Builds rings from lattice points, each ring ordered by angle around its points' mean so
/// that most rings are simple (star-shaped) and most cases reach the boolean operation.
fn shape(rings: &[Vec<(i8, i8)>], s: f64, off: f64) -> Option<Shape> {
    let rings: Vec<Vec<DVec2>> = rings
        .iter()
        .take(4)
        .map(|r| {
            let mut pts: Vec<DVec2> = r
                .iter()
                .take(16)
                .map(|&(x, y)| DVec2::new(f64::from(x % 16), f64::from(y % 16)))
                .collect();
            let c = pts.iter().copied().sum::<DVec2>() / pts.len().max(1) as f64;
            pts.sort_by(|p, q| {
                let (a, b) = (p - c, q - c);
                a.y.atan2(a.x).total_cmp(&b.y.atan2(b.x))
            });
            pts.into_iter().map(|p| p * s + DVec2::splat(off)).collect()
        })
        .collect();
    Shape::new(rings).ok()
}

fn all_ops(a: &Shape, b: &Shape) -> [Shape; 4] {
    [
        BoolOp::Intersection,
        BoolOp::Union,
        BoolOp::Difference,
        BoolOp::Xor,
    ]
    .map(|op| {
        let r = boolean(a, b, op)
            .unwrap_or_else(|e| panic!("{op:?} failed on valid input: {e}\nA = {a:?}\nB = {b:?}"));
        if let Err(e) = r.validate() {
            panic!("{op:?} result invalid: {e}\nA = {a:?}\nB = {b:?}\nR = {r:?}");
        }
        r
    })
}

/// Runs `op` (and, for the identities, the other three) on the decoded case.
pub fn run(case: &Case, op: BoolOp) {
    let s = 2f64.powi(i32::from(case.scale % 24) - 8);
    let off = if case.offset > 127 {
        10f64.powi(i32::from(case.offset % 7))
    } else {
        0.0
    };
    let (Some(a), Some(b)) = (shape(&case.a, s, off), shape(&case.b, s, off)) else {
        return;
    };
    let r = boolean(&a, &b, op)
        .unwrap_or_else(|e| panic!("{op:?} failed on valid input: {e}\nA = {a:?}\nB = {b:?}"));
    if let Err(e) = r.validate() {
        panic!("{op:?} result invalid: {e}\nA = {a:?}\nB = {b:?}\nR = {r:?}");
    }
    // Wherever the generic-position fast path answers, it must equal the robust pipeline.
    if let Ok(Some(f)) = boolean_fast(&a, &b, op) {
        let robust = boolean_robust(&a, &b, op).unwrap_or_else(|e| {
            panic!("{op:?}: fast path answered, robust failed: {e}\nA = {a:?}\nB = {b:?}")
        });
        assert_eq!(f, robust, "{op:?}: fast path differs\nA = {a:?}\nB = {b:?}");
    }
    let [i, u, d, x] = all_ops(&a, &b);
    let (aa, ab) = (a.area(), b.area());
    // Identities to 1e-9 of the operands' area, relaxed by the rounding of coordinates far
    // from the origin (the offset), which is what f64 can resolve there.
    let tol = 1e-9 * (aa + ab) + 1e-12 * off * off;
    let (ai, au, ad, ax) = (i.area(), u.area(), d.area(), x.area());
    assert!((ad + ai - aa).abs() <= tol, "A-B + A&B != A: {ad} + {ai} vs {aa}\nA = {a:?}\nB = {b:?}");
    assert!((au - (aa + ab - ai)).abs() <= tol, "A|B: {au} vs {aa} + {ab} - {ai}\nA = {a:?}\nB = {b:?}");
    assert!((ax - (au - ai)).abs() <= tol, "A^B: {ax} vs {au} - {ai}\nA = {a:?}\nB = {b:?}");
}
