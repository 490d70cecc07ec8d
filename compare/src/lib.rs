//! Adapters from arealight's planar shapes to the reference clippers i_overlay and clipper2,
//! shared by the differential tests, the benchmarks and the instruction-count driver of this
//! workspace member.
//!
//! They live outside the `arealight` package so that building the crate's examples and its
//! own tests never compiles i_overlay, clipper2 or geo (`cargo test --workspace`, or
//! `cargo test -p arealight-compare`, runs the comparisons; `.ci/run` does).

use arealight::planar::{BoolOp, Shape};
use i_overlay::core::fill_rule::FillRule;
use i_overlay::core::overlay_rule::OverlayRule;
use i_overlay::float::single::SingleFloatOverlay;

/// Contours as i_overlay takes them.
pub type IPaths = Vec<Vec<[f64; 2]>>;

/// The contours of a shape as i_overlay paths.
pub fn to_paths(s: &Shape) -> IPaths {
    s.contours()
        .map(|c| c.iter().map(|p| [p.x, p.y]).collect())
        .collect()
}

/// Area of i_overlay output: each shape's first contour is its outer boundary, the rest holes.
pub fn ioverlay_area(shapes: &[Vec<Vec<[f64; 2]>>]) -> f64 {
    shapes
        .iter()
        .map(|sh| {
            sh.iter()
                .enumerate()
                .map(|(k, c)| {
                    let a = ring_area(c).abs();
                    if k == 0 { a } else { -a }
                })
                .sum::<f64>()
        })
        .sum()
}

/// Signed area of one closed ring (shoelace, fanned from the first vertex).
pub fn ring_area(c: &[[f64; 2]]) -> f64 {
    let n = c.len();
    if n < 3 {
        return 0.0;
    }
    let o = c[0];
    let mut s = 0.0;
    for k in 1..n - 1 {
        let (p, q) = (c[k], c[k + 1]);
        s += (p[0] - o[0]) * (q[1] - o[1]) - (p[1] - o[1]) * (q[0] - o[0]);
    }
    0.5 * s
}

fn rule(op: BoolOp) -> OverlayRule {
    match op {
        BoolOp::Intersection => OverlayRule::Intersect,
        BoolOp::Union => OverlayRule::Union,
        BoolOp::Difference => OverlayRule::Difference,
        BoolOp::Xor => OverlayRule::Xor,
    }
}

/// i_overlay's result for `a op b` (64-bit integer engine, non-zero fill).
pub fn ioverlay(a: &IPaths, b: &IPaths, op: BoolOp) -> Vec<Vec<Vec<[f64; 2]>>> {
    a.overlay_as::<i64>(b, rule(op), FillRule::NonZero)
}

/// Area of the symmetric difference between our result and i_overlay's reference, measured by
/// i_overlay itself (so the measurement does not depend on the code under test).
pub fn sym_diff_vs_ioverlay(a: &Shape, b: &Shape, op: BoolOp, ours: &Shape) -> f64 {
    let reference = ioverlay(&to_paths(a), &to_paths(b), op);
    let ref_paths: IPaths = reference.into_iter().flatten().collect();
    let x = to_paths(ours).overlay_as::<i64>(&ref_paths, OverlayRule::Xor, FillRule::EvenOdd);
    ioverlay_area(&x)
}

/// Fixed-point scaler for clipper2: 2^-30 resolution, plenty for the test coordinate ranges.
#[derive(Debug, Default, Clone, Copy, PartialEq, Hash)]
pub struct Fine;
impl clipper2::PointScaler for Fine {
    const MULTIPLIER: f64 = 1073741824.0;
}

/// The contours of a shape as clipper2 paths on the [`Fine`] grid.
pub fn to_clipper(s: &Shape) -> clipper2::Paths<Fine> {
    let v: Vec<Vec<(f64, f64)>> = s
        .contours()
        .map(|c| c.iter().map(|p| (p.x, p.y)).collect())
        .collect();
    v.into()
}

/// clipper2's area of `a op b` (non-zero fill).
pub fn clipper_area(a: &Shape, b: &Shape, op: BoolOp) -> f64 {
    let (pa, pb) = (to_clipper(a), to_clipper(b));
    let f = clipper2::FillRule::NonZero;
    let r = match op {
        BoolOp::Intersection => clipper2::intersect(pa, pb, f),
        BoolOp::Union => clipper2::union(pa, pb, f),
        BoolOp::Difference => clipper2::difference(pa, pb, f),
        BoolOp::Xor => clipper2::xor(pa, pb, f),
    };
    r.map(|p| p.signed_area().abs()).unwrap_or(f64::NAN)
}
