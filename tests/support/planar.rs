//! Planar shapes: a compact text format, the identity checks, generators (proptest strategies
//! and the benchmark polygons). The adapters to the reference clippers (i_overlay, clipper2)
//! are in the `compare/` workspace member (`arealight_compare`), so that the crate's own tests
//! do not build them.

use arealight::glam::DVec2;
use arealight::planar::{BoolOp, Shape, boolean};
use proptest::prelude::*;

pub const OPS: [BoolOp; 4] = [
    BoolOp::Intersection,
    BoolOp::Union,
    BoolOp::Difference,
    BoolOp::Xor,
];

/// Parses S2-style text: `"0:0, 4:0, 4:4, 0:4; 1:1, 1:2, 2:2"` (rings separated by `;`).
pub fn rings(text: &str) -> Vec<Vec<DVec2>> {
    text.split(';')
        .filter(|r| !r.trim().is_empty())
        .map(|r| {
            r.split(',')
                .map(|p| {
                    let mut it = p.trim().split(':');
                    let x: f64 = it.next().unwrap().trim().parse().unwrap();
                    let y: f64 = it.next().unwrap().trim().parse().unwrap();
                    DVec2::new(x, y)
                })
                .collect()
        })
        .collect()
}

/// A shape from the text format; panics (test input) if invalid.
pub fn shape(text: &str) -> Shape {
    Shape::new(rings(text)).unwrap_or_else(|e| panic!("bad test shape {text:?}: {e}"))
}

pub fn op_name(op: BoolOp) -> &'static str {
    match op {
        BoolOp::Intersection => "intersection",
        BoolOp::Union => "union",
        BoolOp::Difference => "difference",
        BoolOp::Xor => "xor",
    }
}

/// Runs all four operations, checks each result is valid, and checks the identities
/// area(A-B) + area(A&B) = area(A), area(A|B) = area(A) + area(B) - area(A&B),
/// area(A^B) = area(A|B) - area(A&B), to `tol` of the operands' area.
pub fn check_all(a: &Shape, b: &Shape, tol: f64) -> Result<[Shape; 4], String> {
    let mut out: Vec<Shape> = Vec::new();
    for op in OPS {
        let r = boolean(a, b, op).map_err(|e| format!("{}: error {e}", op_name(op)))?;
        r.validate()
            .map_err(|e| format!("{} result invalid: {e}\n{r:?}", op_name(op)))?;
        out.push(r);
    }
    let (aa, ab) = (a.area(), b.area());
    let [i, u, d, x]: [Shape; 4] = out.try_into().unwrap();
    let (ai, au, ad, ax) = (i.area(), u.area(), d.area(), x.area());
    let eps = tol * (aa + ab).max(f64::MIN_POSITIVE);
    if (ad + ai - aa).abs() > eps {
        return Err(format!("area(A-B) {ad} + area(A&B) {ai} != area(A) {aa}"));
    }
    if (au - (aa + ab - ai)).abs() > eps {
        return Err(format!("area(A|B) {au} != {aa} + {ab} - {ai}"));
    }
    if (ax - (au - ai)).abs() > eps {
        return Err(format!("area(A^B) {ax} != area(A|B) {au} - area(A&B) {ai}"));
    }
    if ai > aa.min(ab) + eps || au + eps < aa.max(ab) {
        return Err(format!(
            "bounds violated: A&B {ai}, A|B {au}, A {aa}, B {ab}"
        ));
    }
    Ok([i, u, d, x])
}

/// Regular-ish star polygon around `c`: vertex k at angle 2 pi k / n with radius `radii[k]`.
/// Star-shaped around `c`, hence simple.
pub fn star(c: DVec2, radii: &[f64], phase: f64) -> Vec<DVec2> {
    let n = radii.len();
    radii
        .iter()
        .enumerate()
        .map(|(k, &r)| {
            let t = phase + std::f64::consts::TAU * k as f64 / n as f64;
            c + DVec2::new(t.cos(), t.sin()) * r
        })
        .collect()
}

/// Checks that every two distinct vertices of `s` are farther apart than the snapping distance
/// (`SNAP_REL` times the shape's coordinate scale). Two copies of one vertex a few ulps apart
/// pass `Shape::validate` (nothing overlaps exactly) but are one point to the next operation.
pub fn well_separated(s: &Shape) -> Result<(), String> {
    let snap = arealight::planar::SNAP_REL * s.scale();
    let pts: Vec<DVec2> = s.contours().flatten().copied().collect();
    for (i, p) in pts.iter().enumerate() {
        for q in &pts[i + 1..] {
            if p != q && (*p - *q).length() <= snap {
                return Err(format!(
                    "vertices {p:?} and {q:?} are distinct but within {snap:e}"
                ));
            }
        }
    }
    Ok(())
}

/// A star-shaped (hence simple) polygon with 3..=max vertices around a centre drawn from
/// `[-spread, spread]^2`: a proptest strategy.
pub fn star_ring(max: usize, spread: f64) -> impl Strategy<Value = Vec<DVec2>> {
    (
        -spread..spread,
        -spread..spread,
        prop::collection::vec(0.2f64..2.0, 3..=max),
        0.0f64..6.3,
    )
        .prop_map(|(cx, cy, radii, phase)| star(DVec2::new(cx, cy), &radii, phase))
}

/// A one-contour shape from [`star_ring`].
pub fn star_shape(max: usize) -> impl Strategy<Value = Shape> {
    star_ring(max, 1.0).prop_filter_map("invalid ring", |r| Shape::new(vec![r]).ok())
}

/// The benchmark inputs of `benches/planar.rs`: `n` vertices on a circle (convex) or alternating
/// between two radii (star-shaped, concave).
pub fn bench_polygon(n: usize, center: DVec2, phase: f64, star: bool) -> Vec<DVec2> {
    (0..n)
        .map(|k| {
            let t = phase + std::f64::consts::TAU * k as f64 / n as f64;
            let r = if star && k % 2 == 1 { 0.55 } else { 1.0 };
            center + DVec2::new(t.cos(), t.sin()) * r
        })
        .collect()
}

/// A star ring of `n` vertices (`n` even, not a multiple of 3) that crosses itself: the star
/// polygon {n/3} (vertex `j` at angle `3 * 2 pi j / n`, going three times around the centre)
/// with radii alternating 1 and 0.6, so that each edge crosses the edges of the neighbouring
/// turns (a few crossings per vertex) and the faces wind up to three times.
pub fn self_intersecting_star(n: usize) -> Vec<DVec2> {
    (0..n)
        .map(|j| {
            let t = std::f64::consts::TAU * (3 * j) as f64 / n as f64;
            let r = if j % 2 == 0 { 1.0 } else { 0.6 };
            DVec2::new(t.cos(), t.sin()) * r
        })
        .collect()
}
