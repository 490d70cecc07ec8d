//! Lines in Pluecker coordinates, the side operator with certified signs, line-polygon stabbing
//! and the vertex-to-vertex bound of seed 002 Theorem 1.
//!
//! # Coordinates and the side operator (seed 002 section 3.1)
//!
//! The oriented line through `p` then `q` has Pluecker coordinates `(u, v)` with direction
//! `u = q - p` (the paper's `l0, l1, l2`) and moment `v = p x q` (`l3, l4, l5`). The side
//! operator of two lines is the permuted inner product `side(l, r) = u_l . v_r + v_l . u_r`. For
//! lines given by points it is a determinant,
//!
//! `side(pq, rs) = det[q - p, r - p, s - p]`,
//!
//! six times the signed volume of the tetrahedron `p, q, r, s` (set `p = 0`: `v_l = 0` and
//! `u_l . v_r = q . (r x s)`; both sides are invariant under translation). Its sign says how the
//! two lines turn about each other; zero means they meet or are parallel.
//!
//! # Certified signs
//!
//! Every sign the visibility backend acts on is the sign of such a determinant of stored points,
//! `det[p - o, a - o, b - o]`, evaluated in `f64` and accepted when it exceeds an a priori error
//! bound ([`ORIENT_ERROR`] times the permanent of the same expansion, the bound of Shewchuk's
//! `orient3d` stage A); otherwise the exact sign comes from the `robust` crate's adaptive
//! `orient3d`. Signs are therefore exact for the `f64` points the backend stores: two
//! decisions about the same lines never contradict each other, which is what keeps the BSP
//! consistent.
//!
//! # Theorem 1 (seed 002 section 3.3)
//!
//! A line `q` through a point `a = sum alpha_i a_i` of a convex polygon `A` and then a point
//! `b = sum beta_j b_j` of a convex polygon `B` (barycentric weights, non-negative, summing to
//! one) has, for any line `l`, `side(q, l) = sum_i sum_j alpha_i beta_j side(a_i b_j, l)`: the
//! side operator is bilinear in the two points once the line is written with homogeneous points
//! (`u = w_p q - w_q p`, `v = p x q`). So if every vertex-to-vertex line `a_i b_j` has
//! `side > 0` (resp. `< 0`), every line stabbing `A` then `B` does. With one zero among them the
//! conclusion is only `>= 0`; [`vvset_orientation`] therefore reports a strict sign only when
//! every term is strict, which is the form the BSP's insertion needs (a line with side zero may
//! then be sent to either child).

use glam::DVec3;
use robust::{Coord3D, orient3d};

/// A line in Pluecker coordinates: `direction = q - p` and `moment = p x q` for the line through
/// `p` then `q` (seed 002 section 3.1; oriented, defined up to a positive factor).
///
/// # Examples
///
/// ```
/// use arealight::glam::DVec3;
/// use arealight::visibility::plucker::PluckerLine;
/// // The x axis and a line parallel to y at height 1: they pass each other, and the sign of the
/// // side operator says which way round.
/// let x_axis = PluckerLine::through(DVec3::ZERO, DVec3::X);
/// let above = PluckerLine::through(DVec3::new(0.0, 0.0, 1.0), DVec3::new(0.0, 1.0, 1.0));
/// assert_eq!(x_axis.side(&above), -1.0);
/// assert_eq!(above.side(&x_axis), -1.0);
/// assert_eq!(x_axis.side(&x_axis.reversed().reversed()), 0.0);
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PluckerLine {
    direction: DVec3,
    moment: DVec3,
}

impl PluckerLine {
    /// The oriented line through `p` then `q` (`p != q` for a proper line; equal points give the
    /// zero vector, which is no line and has side zero with everything).
    #[must_use]
    pub fn through(p: DVec3, q: DVec3) -> Self {
        PluckerLine {
            direction: q - p,
            moment: p.cross(q),
        }
    }

    /// The direction `u = q - p` (coordinates `l0, l1, l2` of seed 002).
    #[must_use]
    pub fn direction(&self) -> DVec3 {
        self.direction
    }

    /// The moment `v = p x q` (coordinates `l3, l4, l5` of seed 002).
    #[must_use]
    pub fn moment(&self) -> DVec3 {
        self.moment
    }

    /// The six coordinates `(l0, ..., l5)` in the order of seed 002.
    #[must_use]
    pub fn coordinates(&self) -> [f64; 6] {
        let (u, v) = (self.direction, self.moment);
        [u.x, u.y, u.z, v.x, v.y, v.z]
    }

    /// The same line with the opposite orientation.
    #[must_use]
    pub fn reversed(&self) -> Self {
        PluckerLine {
            direction: -self.direction,
            moment: -self.moment,
        }
    }

    /// The side operator `u . v' + v . u'` (the permuted inner product, seed 002 section 3.1) in
    /// plain `f64`: symmetric, zero for lines that meet or are parallel. Its sign is not certified
    /// near zero; [`side_sign`] is.
    #[must_use]
    pub fn side(&self, other: &PluckerLine) -> f64 {
        self.direction.dot(other.moment) + self.moment.dot(other.direction)
    }
}

/// The sign of a predicate.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Sign {
    /// Strictly negative.
    Negative,
    /// Exactly zero.
    Zero,
    /// Strictly positive.
    Positive,
}

impl Sign {
    /// The sign of `x` (zero for `0.0` and `-0.0`; NaN counts as zero).
    #[must_use]
    pub fn of(x: f64) -> Sign {
        if x > 0.0 {
            Sign::Positive
        } else if x < 0.0 {
            Sign::Negative
        } else {
            Sign::Zero
        }
    }

    /// The opposite sign.
    #[must_use]
    pub fn flip(self) -> Sign {
        match self {
            Sign::Negative => Sign::Positive,
            Sign::Zero => Sign::Zero,
            Sign::Positive => Sign::Negative,
        }
    }
}

/// Relative error bound of the filtered determinant of [`Orienter`]: the computed
/// `(p - o) . ((a - o) x (b - o))` differs from the exact determinant of the stored points by
/// at most this times the permanent `sum_k |p_k - o_k| (|u_{k+1} w_{k+2}| + |u_{k+2} w_{k+1}|)`
/// (computed), with `u = a - o`, `w = b - o`.
///
/// Each difference is one rounding, each cross-product component two products and a
/// difference, the dot product three products and two sums: at most `8 eps` of the exact
/// permanent to first order (`eps = 2^-53`), and the computed permanent is within a few `eps`
/// of the exact one. `16 eps` leaves a factor of two; the tests check the filter against exact
/// integer arithmetic on near-degenerate inputs.
pub(crate) const ORIENT_ERROR: f64 = 16.0 * f64::EPSILON / 2.0;

/// Permanents below this are outside the error model of [`ORIENT_ERROR`] (products may have
/// lost bits to underflow), so their signs always go to the exact predicate.
const PERMANENT_FLOOR: f64 = 1e-280;

/// The exact sign of `det[p - o, a - o, b - o]` (Shewchuk's `orient3d(p, a, b, o)`).
#[must_use]
pub(crate) fn orient_exact(p: DVec3, a: DVec3, b: DVec3, o: DVec3) -> Sign {
    let c = |v: DVec3| Coord3D {
        x: v.x,
        y: v.y,
        z: v.z,
    };
    Sign::of(orient3d(c(p), c(a), c(b), c(o)))
}

/// The exact sign of the side operator of the line through `p` then `q` and the line through
/// `r` then `s` (seed 002 section 3.1): `sign det[q - p, r - p, s - p]`, by the `robust` crate's
/// adaptive `orient3d` (exact for any finite input whose products do not overflow).
///
/// # Examples
///
/// ```
/// use arealight::glam::DVec3;
/// use arealight::visibility::plucker::{Sign, side_sign};
/// // Two lines through the origin meet (the scalings by powers of two are exact): side zero,
/// // where the f64 side operator of the same points need not be.
/// let (a, b) = (DVec3::new(0.1, 0.2, 0.3), DVec3::new(-0.7, 0.3, 0.1));
/// assert_eq!(side_sign(-a, a * 4.0, b, -b * 0.5), Sign::Zero);
/// assert_eq!(side_sign(-a, a * 4.0, b, b * 0.5 + DVec3::Z * 1e-9), Sign::Positive);
/// ```
#[must_use]
pub fn side_sign(p: DVec3, q: DVec3, r: DVec3, s: DVec3) -> Sign {
    orient_exact(q, r, s, p)
}

/// Certified signs of `det[p - o, a - o, b - o]` for many points `p` with `a`, `b`, `o` fixed:
/// the side of the line `o -> p` relative to the line `a -> b`, i.e. the side of `p` relative to
/// the plane through `o`, `a`, `b`. The cross product is computed once; each sign costs one dot
/// product unless it falls within [`ORIENT_ERROR`] of zero, when the exact predicate decides.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Orienter {
    o: DVec3,
    a: DVec3,
    b: DVec3,
    /// `(a - o) x (b - o)`.
    m: DVec3,
    /// The permanent's factors: `|u_y w_z| + |u_z w_y|` and its cyclic shifts.
    mabs: DVec3,
}

/// The smallest ratio `|(a - o) x (b - o)| / |mabs|` for which [`Orienter::eval_near`] takes a
/// point within the error bound as lying on the plane: the distance of such a point from the
/// plane is at most `ORIENT_ERROR * |p - o| / 1e-3`, below `2e-12` of its distance from `o`.
/// Below that ratio (a node line through or near the point `o`, or a line of nearly coincident
/// points) the plane itself is ill-defined and the exact sign decides.
const WELL_CONDITIONED: f64 = 1e-3;

impl Orienter {
    /// The predicate for the plane through `o`, `a`, `b` (in that orientation).
    #[inline]
    pub(crate) fn new(a: DVec3, b: DVec3, o: DVec3) -> Self {
        let (u, w) = (a - o, b - o);
        let m = u.cross(w);
        let mabs = DVec3::new(
            (u.y * w.z).abs() + (u.z * w.y).abs(),
            (u.z * w.x).abs() + (u.x * w.z).abs(),
            (u.x * w.y).abs() + (u.y * w.x).abs(),
        );
        Orienter { o, a, b, m, mabs }
    }

    /// Whether the plane is well conditioned: `|m|` is at least [`WELL_CONDITIONED`] of
    /// `|mabs|`, so a value within the error bound means a point within a tiny distance of the
    /// plane. Computed only when a sign falls within the bound (rarely), not per orienter.
    #[inline]
    fn well(&self) -> bool {
        self.m.length_squared() >= WELL_CONDITIONED * WELL_CONDITIONED * self.mabs.length_squared()
    }

    /// The `f64` value of the determinant (for interpolation) and its certified sign.
    #[inline]
    pub(crate) fn eval(&self, p: DVec3) -> (f64, Sign) {
        let (s, strict) = self.eval_filtered(p);
        (
            s,
            strict.unwrap_or_else(|| orient_exact(p, self.a, self.b, self.o)),
        )
    }

    /// The `f64` value of the determinant and its sign when the filter certifies it as strict,
    /// `None` when the value is within the error bound of zero.
    #[inline]
    pub(crate) fn eval_filtered(&self, p: DVec3) -> (f64, Option<Sign>) {
        let d = p - self.o;
        let s = d.dot(self.m);
        let perm = d.abs().dot(self.mabs);
        let bound = ORIENT_ERROR * perm;
        let sign = if perm > PERMANENT_FLOOR && s > bound {
            Some(Sign::Positive)
        } else if perm > PERMANENT_FLOOR && s < -bound {
            Some(Sign::Negative)
        } else {
            None
        };
        (s, sign)
    }

    /// The `f64` value and a sign that is certified, except that a point within the error bound
    /// of a well-conditioned plane counts as on it (`Zero`): its distance from the plane is
    /// below `2e-12` of its distance from `o` ([`WELL_CONDITIONED`]). For ill-conditioned planes
    /// the exact sign decides.
    #[inline]
    pub(crate) fn eval_near(&self, p: DVec3) -> (f64, Sign) {
        let (s, strict) = self.eval_filtered(p);
        let sign = match strict {
            Some(sign) => sign,
            None if self.well() => Sign::Zero,
            None => orient_exact(p, self.a, self.b, self.o),
        };
        (s, sign)
    }

    /// [`Orienter::eval_near`] for a point within the reach of `bound`
    /// ([`Orienter::reach_bound`]): a value beyond `bound` is certified with one dot product,
    /// without the point's own permanent; anything else takes [`Orienter::eval_near`]. The
    /// value is computed the same way either way, and `bound` is never below the per-point
    /// filter's bound, so the answer is the same.
    #[inline]
    pub(crate) fn eval_near_within(&self, p: DVec3, bound: f64) -> (f64, Sign) {
        let s = (p - self.o).dot(self.m);
        if bound > 0.0 {
            if s > bound {
                return (s, Sign::Positive);
            }
            if s < -bound {
                return (s, Sign::Negative);
            }
        }
        self.eval_near(p)
    }

    /// The certified sign alone.
    #[inline]
    pub(crate) fn sign(&self, p: DVec3) -> Sign {
        self.eval(p).1
    }

    /// The sign when the filter certifies it as strict, `None` when the value is within the
    /// error bound of zero (then the exact sign may be zero or either strict sign). For
    /// decisions where "undecided" is a safe answer, at the cost of one dot product.
    #[inline]
    pub(crate) fn strict_sign(&self, p: DVec3) -> Option<Sign> {
        self.eval_filtered(p).1
    }

    /// A bound of [`ORIENT_ERROR`] times the permanent for every point `p` with
    /// `|p - o|` at most `reach` in each coordinate (after rounding): the permanent is
    /// `sum |d_i| mabs_i <= reach * sum mabs_i`. Slightly widened so that it is never below the
    /// per-point bound of [`Orienter::strict_sign`] computed for such a point, and zero (no
    /// fast answer) where that bound's error model does not hold.
    #[inline]
    pub(crate) fn reach_bound(&self, reach: f64) -> f64 {
        let b = ORIENT_ERROR * reach * (self.mabs.x + self.mabs.y + self.mabs.z) * (1.0 + 1e-10);
        if reach * (self.mabs.x + self.mabs.y + self.mabs.z) > 2.0 * PERMANENT_FLOOR {
            b
        } else {
            0.0
        }
    }

    /// [`Orienter::strict_sign`] for a point within the reach of `bound`
    /// ([`Orienter::reach_bound`]): a value beyond `bound` is certified with one dot product,
    /// without the point's own permanent; anything else takes the per-point filter, so the
    /// answer is the same.
    #[inline]
    pub(crate) fn strict_sign_within(&self, p: DVec3, bound: f64) -> Option<Sign> {
        let s = (p - self.o).dot(self.m);
        if bound > 0.0 {
            if s > bound {
                return Some(Sign::Positive);
            }
            if s < -bound {
                return Some(Sign::Negative);
            }
        }
        self.strict_sign(p)
    }
}

/// How a line meets a convex planar polygon ([`line_polygon`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Stab {
    /// The line crosses the polygon's plane at a point of its relative interior.
    Through,
    /// The line crosses the plane at a point of the polygon's boundary (an edge or a vertex).
    Boundary,
    /// The line lies in the polygon's plane: every side is zero; it may or may not meet it.
    Coplanar,
    /// The line misses the closed polygon (or is parallel to its plane, outside it).
    Miss,
}

/// How the line through `p` then `q` meets the convex planar polygon `poly` (vertices in order,
/// either orientation, at least three, not all on one line), from the exact signs of the side
/// operator with the lines of its edges (seed 002 section 3.2, Fig. 2): a line crosses the
/// polygon's interior iff its orientation is the same, strictly, with respect to every edge.
///
/// # Examples
///
/// ```
/// use arealight::glam::DVec3;
/// use arealight::visibility::plucker::{Stab, line_polygon};
/// let tri = [DVec3::ZERO, DVec3::X, DVec3::Y];
/// let up = |x: f64, y: f64| (DVec3::new(x, y, -1.0), DVec3::new(x, y, 1.0));
/// let (p, q) = up(0.2, 0.2);
/// assert_eq!(line_polygon(p, q, &tri), Stab::Through);
/// let (p, q) = up(0.5, 0.5); // on the hypotenuse
/// assert_eq!(line_polygon(p, q, &tri), Stab::Boundary);
/// let (p, q) = up(0.6, 0.6);
/// assert_eq!(line_polygon(p, q, &tri), Stab::Miss);
/// assert_eq!(line_polygon(DVec3::ZERO, DVec3::Y, &tri), Stab::Coplanar);
/// ```
#[must_use]
pub fn line_polygon(p: DVec3, q: DVec3, poly: &[DVec3]) -> Stab {
    let n = poly.len();
    let (mut pos, mut neg, mut zero) = (false, false, false);
    for i in 0..n {
        match side_sign(p, q, poly[i], poly[(i + 1) % n]) {
            Sign::Positive => pos = true,
            Sign::Negative => neg = true,
            Sign::Zero => zero = true,
        }
    }
    match (pos, neg, zero) {
        (true, true, _) => Stab::Miss,
        (false, false, _) => Stab::Coplanar,
        (_, _, true) => Stab::Boundary,
        _ => Stab::Through,
    }
}

/// The orientation of a set of lines relative to a line, as far as its vertex-to-vertex lines
/// bound it ([`vvset_orientation`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Orientation {
    /// Every line of the set has a strictly positive side.
    Positive,
    /// Every line of the set has a strictly negative side.
    Negative,
    /// The bound decides nothing: vertex-to-vertex lines of both signs, or one with side zero.
    Mixed,
}

/// Seed 002 Theorem 1, in the strict form the BSP uses: the orientation, relative to the line
/// `l0 -> l1`, of every line that passes through the convex hull of `from` and then through the
/// convex hull of `to`, bounded by the lines `from[i] -> to[j]` (the "vvset"), with exact signs.
///
/// [`Orientation::Positive`] when every vertex-to-vertex line has a strictly positive side:
/// then every stabbing line does (a positive combination of positive terms). Likewise
/// [`Orientation::Negative`]. Anything else is [`Orientation::Mixed`], which is conservative:
/// the stabbing lines may still all share one sign.
///
/// # Examples
///
/// ```
/// use arealight::glam::DVec3;
/// use arealight::visibility::plucker::{Orientation, vvset_orientation};
/// // A small square below a small square: every line through both passes the x axis on the
/// // same side when the squares are off to one side of it, and on both sides when they are
/// // centred on it.
/// let sq = |c: DVec3| [c, c + DVec3::X * 0.1, c + DVec3::new(0.1, 0.1, 0.0), c + DVec3::Y * 0.1];
/// let (lo, hi) = (sq(DVec3::new(0.0, 1.0, -1.0)), sq(DVec3::new(0.0, 1.0, 1.0)));
/// assert_eq!(vvset_orientation(&lo, &hi, DVec3::ZERO, DVec3::X), Orientation::Positive);
/// let (lo, hi) = (sq(DVec3::new(0.0, -0.05, -1.0)), sq(DVec3::new(0.0, -0.05, 1.0)));
/// assert_eq!(vvset_orientation(&lo, &hi, DVec3::ZERO, DVec3::X), Orientation::Mixed);
/// ```
#[must_use]
pub fn vvset_orientation(from: &[DVec3], to: &[DVec3], l0: DVec3, l1: DVec3) -> Orientation {
    let (mut pos, mut neg) = (false, false);
    for &a in from {
        for &b in to {
            match side_sign(a, b, l0, l1) {
                Sign::Positive => pos = true,
                Sign::Negative => neg = true,
                Sign::Zero => return Orientation::Mixed,
            }
            if pos && neg {
                return Orientation::Mixed;
            }
        }
    }
    match (pos, neg) {
        (true, false) => Orientation::Positive,
        (false, true) => Orientation::Negative,
        _ => Orientation::Mixed,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// SplitMix64.
    struct Rng(u64);

    impl Rng {
        fn int(&mut self, m: i64) -> i64 {
            self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
            let mut z = self.0;
            z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
            z ^= z >> 31;
            (z % (2 * m as u64 + 1)) as i64 - m
        }
    }

    fn det_exact(p: [i128; 3], a: [i128; 3], b: [i128; 3], o: [i128; 3]) -> Sign {
        let d = [p[0] - o[0], p[1] - o[1], p[2] - o[2]];
        let u = [a[0] - o[0], a[1] - o[1], a[2] - o[2]];
        let w = [b[0] - o[0], b[1] - o[1], b[2] - o[2]];
        let det = d[0] * (u[1] * w[2] - u[2] * w[1])
            + d[1] * (u[2] * w[0] - u[0] * w[2])
            + d[2] * (u[0] * w[1] - u[1] * w[0]);
        match det.signum() {
            1 => Sign::Positive,
            -1 => Sign::Negative,
            _ => Sign::Zero,
        }
    }

    #[test]
    fn the_filter_never_certifies_a_wrong_sign() {
        // Exactly coplanar, nearly coplanar and generic lattice points at several scales
        // (2^35 down to 2^-20 steps), some with a nearly degenerate plane (its two spanning
        // vectors nearly parallel, so the cross product cancels): every strict sign the filter certifies matches exact
        // integer arithmetic, the exact fallback decides the rest, and generic inputs are
        // decided by the filter alone.
        let mut rng = Rng(11);
        let (mut undecided, mut generic_undecided, mut zeros, mut by_reach) = (0, 0, 0, 0);
        for case in 0..40000 {
            let m = 1i64 << (5 + case % 31);
            let pt = |rng: &mut Rng| [rng.int(m), rng.int(m), rng.int(m)].map(i128::from);
            let (o, a, mut b) = (pt(&mut rng), pt(&mut rng), pt(&mut rng));
            if case % 8 == 7 {
                // a - o and b - o nearly parallel: the cross product cancels.
                let k = i128::from(rng.int(3));
                b = [0, 1, 2].map(|i| o[i] + k * (a[i] - o[i]) + i128::from(rng.int(1)));
            }
            let generic = case % 4 == 0;
            let p = if generic {
                pt(&mut rng)
            } else {
                let (k, l) = (i128::from(rng.int(4)), i128::from(rng.int(4)));
                let e = if case % 4 == 1 {
                    0
                } else {
                    i128::from(rng.int(1))
                };
                [0, 1, 2].map(|i| o[i] + k * (a[i] - o[i]) + l * (b[i] - o[i]) + e)
            };
            let exact = det_exact(p, a, b, o);
            zeros += usize::from(exact == Sign::Zero);
            // Scaled by a power of two (exact), so that small magnitudes are covered too.
            let s = if case % 3 == 0 {
                1.0
            } else {
                (2.0f64).powi(-55)
            };
            let f = |v: [i128; 3]| DVec3::new(v[0] as f64, v[1] as f64, v[2] as f64) * s;
            let or = Orienter::new(f(a), f(b), f(o));
            assert_eq!(or.sign(f(p)), exact, "case {case}");
            match or.strict_sign(f(p)) {
                Some(sign) => assert_eq!(sign, exact, "case {case}: filter"),
                None => {
                    undecided += 1;
                    generic_undecided += usize::from(generic);
                }
            }
            // The reach filter, with the reach of these points (their largest coordinate
            // difference), answers as the per-point filter, and from its bound alone for most
            // generic points.
            let reach = [0, 1, 2]
                .map(|i| (p[i] - o[i]).abs().max((a[i] - o[i]).abs()))
                .into_iter()
                .max()
                .unwrap() as f64
                * s;
            let bound = or.reach_bound(reach);
            assert_eq!(
                or.strict_sign_within(f(p), bound),
                or.strict_sign(f(p)),
                "case {case}: reach filter"
            );
            let v = (f(p) - f(o)).dot(or.m);
            by_reach += usize::from(generic && bound > 0.0 && v.abs() > bound);
        }
        assert!(by_reach > 5000, "{by_reach}");
        assert!(zeros > 5000, "{zeros}");
        assert!(
            undecided > 5000 && generic_undecided < 20,
            "{undecided} {generic_undecided}"
        );
    }
}
