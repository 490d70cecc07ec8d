//! Fuzz `Shape::with_fill_rule`: any ring soup of lattice points (so that repeated points,
//! collinear overlaps, vertices on edges and self-touching rings are frequent), scaled by a power
//! of two and offset, under any of the four rules. Asserts that the result
//!
//! - exists (lattice input is exactly representable, so resolving must not give up),
//! - passes `Shape::validate` and is a valid operand (its union and difference with the same
//!   soup under another rule validate, and the area identity `|A - B| + |A & B| = |A|` holds),
//! - agrees with an independent winding-number count: at sample points a quarter lattice step
//!   from every input edge, the rule applied to the exact winding number of the input (counted
//!   here with `robust::orient2d`) says inside exactly where the result contains the point.
//!
//! Run: `RUSTC_BOOTSTRAP=1 cargo fuzz run planar_fill -- -max_total_time=300` (from the crate root).
#![no_main]

use arealight::glam::DVec2;
use arealight::planar::{BoolOp, FillRule, Shape, boolean};
use libfuzzer_sys::arbitrary::{self, Arbitrary};
use libfuzzer_sys::fuzz_target;

/// One fuzz case. `Debug` prints the rings so a crash pastes into a regression test.
#[derive(Debug, Arbitrary)]
struct Case {
    rings: Vec<Vec<(i8, i8)>>,
    rule: u8,
    /// Scale exponent: coordinates are multiplied by `2^(scale % 40 - 20)`.
    scale: u8,
    /// Offset exponent: every coordinate is shifted by `10^(offset % 7)` times the scale when
    /// `offset > 127`.
    offset: u8,
}

const RULES: [FillRule; 4] = [
    FillRule::EvenOdd,
    FillRule::NonZero,
    FillRule::Positive,
    FillRule::Negative,
];

fn orient(a: DVec2, b: DVec2, c: DVec2) -> f64 {
    robust::orient2d(
        robust::Coord { x: a.x, y: a.y },
        robust::Coord { x: b.x, y: b.y },
        robust::Coord { x: c.x, y: c.y },
    )
}

/// Exact winding number of `p` (off every ring) by signed crossings of a ray to the right.
fn winding<'a>(rings: impl Iterator<Item = &'a [DVec2]>, p: DVec2) -> i64 {
    let mut w = 0;
    for r in rings {
        let n = r.len();
        for i in 0..n {
            let (a, b) = (r[i], r[(i + 1) % n]);
            if a.y <= p.y {
                if b.y > p.y && orient(a, b, p) > 0.0 {
                    w += 1;
                }
            } else if b.y <= p.y && orient(a, b, p) < 0.0 {
                w -= 1;
            }
        }
    }
    w
}

/// Squared distance from `p` to the segment `ab`, in lattice units (exact enough: inputs are
/// small integers and the sample points dyadic).
fn dist2(a: DVec2, b: DVec2, p: DVec2) -> f64 {
    let d = b - a;
    let l2 = d.length_squared();
    let t = if l2 > 0.0 {
        ((p - a).dot(d) / l2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (a + d * t - p).length_squared()
}

fn run(case: &Case) {
    let s = 2f64.powi(i32::from(case.scale % 40) - 20);
    let off = if case.offset > 127 {
        10f64.powi(i32::from(case.offset % 7)) * s
    } else {
        0.0
    };
    let lattice: Vec<Vec<DVec2>> = case
        .rings
        .iter()
        .take(5)
        .map(|r| {
            r.iter()
                .take(12)
                .map(|&(x, y)| DVec2::new(f64::from(x % 8), f64::from(y % 8)))
                .collect()
        })
        .collect();
    let place = |p: DVec2| p * s + DVec2::new(off, 0.5 * off);
    let rings: Vec<Vec<DVec2>> = lattice
        .iter()
        .map(|r| r.iter().map(|&p| place(p)).collect())
        .collect();
    let rule = RULES[usize::from(case.rule % 4)];
    let r = Shape::with_fill_rule(rings.clone(), rule)
        .unwrap_or_else(|e| panic!("{rule:?} failed: {e}\nrings = {rings:?}"));
    if let Err(e) = r.validate() {
        panic!("{rule:?} result invalid: {e}\nrings = {rings:?}\nR = {r:?}");
    }
    // Sample points on a quarter lattice, offset by an eighth, at least a quarter step from
    // every input edge (in lattice units, where the input is exact).
    let contours: Vec<Vec<DVec2>> = r.contours().map(|c| c.to_vec()).collect();
    for i in -36..36 {
        for j in -36..36 {
            let q = DVec2::new(f64::from(i) * 0.25 + 0.125, f64::from(j) * 0.25 + 0.125);
            let near = lattice.iter().any(|ring| {
                let n = ring.len();
                (0..n).any(|k| dist2(ring[k], ring[(k + 1) % n], q) < 0.0625)
            });
            if near {
                continue;
            }
            let want = rule.contains(winding(lattice.iter().map(Vec::as_slice), q));
            let got = winding(contours.iter().map(Vec::as_slice), place(q)) != 0;
            assert_eq!(
                want, got,
                "{rule:?} at lattice point {q:?}: input says {want}, result {got}\nrings = {rings:?}\nR = {r:?}"
            );
        }
    }
    // A valid operand: combined with the same soup under the next rule.
    let other = Shape::with_fill_rule(rings.clone(), RULES[usize::from(case.rule.wrapping_add(1) % 4)])
        .unwrap_or_else(|e| panic!("second rule failed: {e}\nrings = {rings:?}"));
    let mut areas = [0.0; 2];
    for (k, op) in [BoolOp::Difference, BoolOp::Intersection].into_iter().enumerate() {
        let x = boolean(&r, &other, op)
            .unwrap_or_else(|e| panic!("{op:?} failed: {e}\nA = {r:?}\nB = {other:?}"));
        if let Err(e) = x.validate() {
            panic!("{op:?} result invalid: {e}\nA = {r:?}\nB = {other:?}\nR = {x:?}");
        }
        areas[k] = x.area();
    }
    let tol = 1e-9 * (r.area() + other.area()) + 1e-12 * off * off;
    assert!(
        (areas[0] + areas[1] - r.area()).abs() <= tol,
        "A-B + A&B != A: {} + {} vs {}\nA = {r:?}\nB = {other:?}",
        areas[0],
        areas[1],
        r.area()
    );
}

fuzz_target!(|case: Case| run(&case));
