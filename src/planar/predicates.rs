//! Exact predicates and small numeric helpers shared by the planar layer.
//!
//! Every topological decision (which side of a line, does a vertex lie on an edge, which way does a
//! corner turn) goes through [`orient`], Shewchuk's adaptive-precision `orient2d` from the `robust`
//! crate. Its sign is exact for all finite inputs whose products do not overflow, which is what the
//! coordinate limit [`MAX_COORD`] guarantees. Only intersection *points* are computed in plain
//! `f64`; their topology is re-checked with the exact predicate afterwards (see
//! `boolean::intersect`).

use alloc::vec::Vec;

use glam::DVec2;

/// Largest coordinate magnitude accepted by [`Shape::new`](super::Shape::new).
///
/// `orient2d` multiplies differences of coordinates; with `|x| <= 1e150` the products stay below
/// `4e300`, far from overflow, so the predicate's sign stays exact (Shewchuk's error analysis
/// assumes no overflow or underflow). Gnomonic coordinates near the horizon reach `1e6..1e12`,
/// well inside this range.
pub const MAX_COORD: f64 = 1e150;

/// Exact orientation of the triangle `(a, b, c)`: positive when counter-clockwise, negative when
/// clockwise, exactly zero when collinear.
///
/// Algebraic properties (used as property tests): `orient(a, b, c) == orient(b, c, a)` and
/// `orient(a, b, c) == -orient(b, a, c)` in sign.
#[inline]
#[must_use]
pub(crate) fn orient(a: DVec2, b: DVec2, c: DVec2) -> f64 {
    robust::orient2d(
        robust::Coord { x: a.x, y: a.y },
        robust::Coord { x: b.x, y: b.y },
        robust::Coord { x: c.x, y: c.y },
    )
}

/// Sign of [`orient`] as `-1`, `0` or `1`.
#[inline]
#[must_use]
pub(crate) fn orient_sign(a: DVec2, b: DVec2, c: DVec2) -> i8 {
    let o = orient(a, b, c);
    if o > 0.0 {
        1
    } else if o < 0.0 {
        -1
    } else {
        0
    }
}

/// Whether `p`, known to be collinear with `a` and `b`, lies strictly between them.
///
/// Collinear points are ordered along the line by either coordinate of the dominant axis, so this
/// comparison is exact.
#[inline]
#[must_use]
pub(crate) fn strictly_between(a: DVec2, b: DVec2, p: DVec2) -> bool {
    if (b.x - a.x).abs() >= (b.y - a.y).abs() {
        (a.x < p.x && p.x < b.x) || (b.x < p.x && p.x < a.x)
    } else {
        (a.y < p.y && p.y < b.y) || (b.y < p.y && p.y < a.y)
    }
}

/// The convex hull of `pts` as indices into it, counter-clockwise, points on its edges left out
/// (Andrew's monotone chain, A. M. Andrew, *Another efficient algorithm for convex hulls in two
/// dimensions*, 1979). Plain floating-point turns: for callers that check what the hull stands
/// for themselves.
#[must_use]
pub(crate) fn monotone_hull(pts: &[DVec2]) -> Vec<usize> {
    let mut order: Vec<usize> = (0..pts.len()).collect();
    order.sort_by(|&a, &b| {
        let (p, q) = (pts[a], pts[b]);
        p.x.total_cmp(&q.x).then(p.y.total_cmp(&q.y))
    });
    let turn = |o: usize, a: usize, c: usize| {
        let (o, a, c) = (pts[o], pts[a], pts[c]);
        (a.x - o.x) * (c.y - o.y) - (a.y - o.y) * (c.x - o.x)
    };
    let mut hull: Vec<usize> = Vec::with_capacity(2 * pts.len());
    for pass in 0..2 {
        let start = hull.len();
        for k in 0..order.len() {
            let p = if pass == 0 {
                order[k]
            } else {
                order[order.len() - 1 - k]
            };
            while hull.len() >= start + 2
                && turn(hull[hull.len() - 2], hull[hull.len() - 1], p) <= 0.0
            {
                hull.pop();
            }
            hull.push(p);
        }
        hull.pop();
    }
    hull
}

/// Twice the signed area of a closed ring (positive for counter-clockwise).
///
/// Coordinates are taken relative to the first vertex, which removes the cancellation that the
/// plain shoelace formula suffers far from the origin (gnomonic coordinates near the horizon).
#[must_use]
pub(crate) fn signed_area2(pts: &[DVec2]) -> f64 {
    let Some(&o) = pts.first() else {
        return 0.0;
    };
    let mut s = 0.0;
    let mut prev = DVec2::ZERO;
    for &p in pts.iter().skip(1) {
        let q = p - o;
        s += prev.x * q.y - prev.y * q.x;
        prev = q;
    }
    s
}

/// Exact winding number of `p` with respect to an oriented ring, valid when `p` is not on the ring.
#[must_use]
pub(crate) fn winding(pts: &[DVec2], p: DVec2) -> i32 {
    let n = pts.len();
    let mut w = 0;
    for i in 0..n {
        let a = pts[i];
        let b = pts[if i + 1 == n { 0 } else { i + 1 }];
        if a.y <= p.y {
            if b.y > p.y && orient(a, b, p) > 0.0 {
                w += 1;
            }
        } else if b.y <= p.y && orient(a, b, p) < 0.0 {
            w -= 1;
        }
    }
    w
}

/// Whether `p` lies on the closed segment `ab` (exact).
#[inline]
#[must_use]
pub(crate) fn on_segment(a: DVec2, b: DVec2, p: DVec2) -> bool {
    p == a || p == b || (orient(a, b, p) == 0.0 && strictly_between(a, b, p))
}

/// Whether the closed segments `ab` and `cd` share at least one point (exact).
#[must_use]
pub(crate) fn segments_touch(a: DVec2, b: DVec2, c: DVec2, d: DVec2) -> bool {
    if a.x.max(b.x) < c.x.min(d.x)
        || c.x.max(d.x) < a.x.min(b.x)
        || a.y.max(b.y) < c.y.min(d.y)
        || c.y.max(d.y) < a.y.min(b.y)
    {
        return false;
    }
    let o1 = orient_sign(a, b, c);
    let o2 = orient_sign(a, b, d);
    let o3 = orient_sign(c, d, a);
    let o4 = orient_sign(c, d, b);
    if o1 * o2 < 0 && o3 * o4 < 0 {
        return true;
    }
    on_segment(a, b, c) || on_segment(a, b, d) || on_segment(c, d, a) || on_segment(c, d, b)
}

/// The candidates lying exactly inside the segment `a-b` (collinear by [`orient`], strictly
/// between the ends by [`strictly_between`]), without repeats, in order from `a`: the vertices a
/// segment must be split at so that two contours touching along it share them.
pub(crate) fn vertices_inside_segment(
    candidates: impl IntoIterator<Item = DVec2>,
    a: DVec2,
    b: DVec2,
) -> smallvec::SmallVec<[DVec2; 2]> {
    let d = b - a;
    let mut hits: smallvec::SmallVec<[(f64, DVec2); 2]> = smallvec::SmallVec::new();
    for p in candidates {
        if orient(a, b, p) == 0.0 && strictly_between(a, b, p) && !hits.iter().any(|h| h.1 == p) {
            hits.push(((p - a).dot(d), p));
        }
    }
    hits.sort_by(|x, y| x.0.total_cmp(&y.0));
    hits.into_iter().map(|h| h.1).collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn pt() -> impl Strategy<Value = DVec2> {
        (-1e3f64..1e3, -1e3f64..1e3).prop_map(|(x, y)| DVec2::new(x, y))
    }

    proptest! {
        #![proptest_config(ProptestConfig { cases: 256, ..ProptestConfig::default() })]

        /// S2-style algebraic properties of the orientation predicate.
        #[test]
        fn orient_is_cyclic_and_antisymmetric(a in pt(), b in pt(), c in pt()) {
            let s = orient_sign(a, b, c);
            prop_assert_eq!(s, orient_sign(b, c, a));
            prop_assert_eq!(s, orient_sign(c, a, b));
            prop_assert_eq!(s, -orient_sign(b, a, c));
        }

        /// Points on a segment built by exact binary fractions are exactly collinear.
        #[test]
        fn exact_midpoints_are_on_segment(a in pt(), b in pt()) {
            let m = (a + b) * 0.5;
            if orient(a, b, m) == 0.0 {
                prop_assert!(on_segment(a, b, m));
            }
        }
    }

    #[test]
    fn winding_counts_orientation() {
        let sq = [
            DVec2::new(0.0, 0.0),
            DVec2::new(1.0, 0.0),
            DVec2::new(1.0, 1.0),
            DVec2::new(0.0, 1.0),
        ];
        assert_eq!(winding(&sq, DVec2::splat(0.5)), 1);
        let mut cw = sq;
        cw.reverse();
        assert_eq!(winding(&cw, DVec2::splat(0.5)), -1);
        assert_eq!(winding(&sq, DVec2::splat(2.0)), 0);
        assert!((signed_area2(&sq) - 2.0).abs() < 1e-15);
    }
}
