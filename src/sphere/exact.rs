//! Exact signs of the small polynomials that order points on a clipping circle.
//!
//! Floating-point expansion arithmetic after Shewchuk (1997), "Adaptive precision floating-point
//! arithmetic and fast robust geometric predicates", sections 2.2-2.8: a real number is held as a
//! sum of doubles (an *expansion*) whose components are nonoverlapping and sorted by increasing
//! magnitude, so that its sign is the sign of its largest component. Sums use Grow-Expansion
//! (Theorem 10), products Scale-Expansion (Theorem 19), and results are compressed (section 2.8)
//! so that a product of products stays a handful of components.
//!
//! Only the cold paths of the clip call this module: a float filter with an error bound decides
//! every comparison it can, and hands the rest here. Results are exact as long as no product's
//! rounding error underflows, which holds for the degree-5 products here when every nonzero
//! coordinate exceeds about `1e-55` in magnitude (coordinates that are exactly zero are fine).

use alloc::vec::Vec;
use glam::DVec3;

/// An expansion: nonoverlapping components by increasing magnitude, no zeros (zero is empty).
type Expansion = Vec<f64>;

/// `a + b` as `(sum, error)`, exactly (Knuth's Two-Sum; no precondition on the magnitudes).
#[inline]
fn two_sum(a: f64, b: f64) -> (f64, f64) {
    let s = a + b;
    let bv = s - a;
    let av = s - bv;
    (s, (a - av) + (b - bv))
}

/// Veltkamp's split of `a` into two halves of 26 significant bits each (`a = hi + lo`).
#[inline]
fn split(a: f64) -> (f64, f64) {
    // 2^27 + 1: the product's rounding leaves the high half.
    const SPLITTER: f64 = 134_217_729.0;
    let c = SPLITTER * a;
    let big = c - a;
    let hi = c - big;
    (hi, a - hi)
}

/// `a * b` as `(product, error)`, exactly barring underflow (Dekker's Two-Product).
#[inline]
fn two_product(a: f64, b: f64) -> (f64, f64) {
    let p = a * b;
    let (ah, al) = split(a);
    let (bh, bl) = split(b);
    let err = ((ah * bh - p) + ah * bl + al * bh) + al * bl;
    (p, err)
}

/// `|p| - 1` for a vector `p` within a few ulps of unit length, to about `1e-31` absolute: the
/// squares' exact products and their sum's rounding errors are kept (Two-Product, Two-Sum), so
/// the defect, itself about `1e-16`, keeps its own relative precision. (`|p|^2 - 1 = e` gives
/// `|p| - 1 = e / 2 - e^2 / 8 + ...`; the square term is below `1e-32`.)
pub(crate) fn unit_defect(p: DVec3) -> f64 {
    let (x, ex) = two_product(p.x, p.x);
    let (y, ey) = two_product(p.y, p.y);
    let (z, ez) = two_product(p.z, p.z);
    let (s, f) = two_sum(x, y);
    let (s, g) = two_sum(s, z);
    // s is within a few ulps of 1, so s - 1 is exact (Sterbenz).
    let e = (s - 1.0) + (((f + g) + (ex + ey)) + ez);
    0.5 * e - 0.125 * e * e
}

/// `e + b` (Grow-Expansion with zero elimination).
fn grow(e: &[f64], b: f64) -> Expansion {
    let mut out = Vec::with_capacity(e.len() + 1);
    let mut q = b;
    for &x in e {
        let (s, h) = two_sum(q, x);
        if h != 0.0 {
            out.push(h);
        }
        q = s;
    }
    if q != 0.0 {
        out.push(q);
    }
    out
}

/// `e + f` (Expansion-Sum: `f` grown in one component at a time).
fn sum(e: &[f64], f: &[f64]) -> Expansion {
    let mut out: Expansion = e.to_vec();
    for &x in f {
        out = grow(&out, x);
    }
    out
}

/// `-e`.
fn neg(e: &[f64]) -> Expansion {
    e.iter().map(|&x| -x).collect()
}

/// `e * b` (Scale-Expansion with zero elimination).
fn scale(e: &[f64], b: f64) -> Expansion {
    let mut out = Vec::with_capacity(2 * e.len());
    let Some((&first, rest)) = e.split_first() else {
        return out;
    };
    let (mut q, h) = two_product(first, b);
    if h != 0.0 {
        out.push(h);
    }
    for &x in rest {
        let (t_hi, t_lo) = two_product(x, b);
        let (s, h) = two_sum(q, t_lo);
        if h != 0.0 {
            out.push(h);
        }
        let (s2, h2) = two_sum(t_hi, s);
        if h2 != 0.0 {
            out.push(h2);
        }
        q = s2;
    }
    if q != 0.0 {
        out.push(q);
    }
    out
}

/// The same value in as few components as the two-pass Compress of section 2.8 leaves.
fn compress(e: &[f64]) -> Expansion {
    let m = e.len();
    if m == 0 {
        return Vec::new();
    }
    // Top-down pass: accumulate from the largest component, emitting a component whenever the
    // sum stops being exact.
    let mut g = alloc::vec![0.0; m];
    let mut bottom = m - 1;
    let mut q = e[m - 1];
    for i in (0..m - 1).rev() {
        let (s, t) = two_sum(q, e[i]);
        if t != 0.0 {
            g[bottom] = s;
            bottom -= 1;
            q = t;
        } else {
            q = s;
        }
    }
    g[bottom] = q;
    // Bottom-up pass over what the first pass left.
    let mut out = Vec::with_capacity(m - bottom);
    for &x in &g[bottom + 1..] {
        let (s, t) = two_sum(x, q);
        if t != 0.0 {
            out.push(t);
        }
        q = s;
    }
    if q != 0.0 {
        out.push(q);
    }
    out
}

/// `e * f`, compressed.
fn product(e: &[f64], f: &[f64]) -> Expansion {
    let mut acc = Vec::new();
    for &x in f {
        acc = sum(&acc, &scale(e, x));
    }
    compress(&acc)
}

/// Sign of an expansion: that of its largest component.
fn sign(e: &[f64]) -> i8 {
    match e.last() {
        Some(&x) if x > 0.0 => 1,
        Some(&x) if x < 0.0 => -1,
        _ => 0,
    }
}

/// `a . b`, exactly.
fn dot(a: DVec3, b: DVec3) -> Expansion {
    let mut acc: Expansion = Vec::new();
    for (x, y) in [(a.x, b.x), (a.y, b.y), (a.z, b.z)] {
        let (p, e) = two_product(x, y);
        acc = sum(
            &acc,
            &[e, p].into_iter().filter(|&c| c != 0.0).collect::<Vec<_>>(),
        );
    }
    compress(&acc)
}

/// `det(a, b, c) = a . (b x c)`, exactly.
fn det(a: DVec3, b: DVec3, c: DVec3) -> Expansion {
    // b x c, one exact component at a time: b_i c_j - b_j c_i.
    let minor = |bi: f64, cj: f64, bj: f64, ci: f64| {
        let (p, e) = two_product(bi, cj);
        let (q, f) = two_product(bj, ci);
        let x: Expansion = [e, p].into_iter().filter(|&c| c != 0.0).collect();
        let y: Expansion = [-f, -q].into_iter().filter(|&c| c != 0.0).collect();
        sum(&x, &y)
    };
    let cx = minor(b.y, c.z, b.z, c.y);
    let cy = minor(b.z, c.x, b.x, c.z);
    let cz = minor(b.x, c.y, b.y, c.x);
    let acc = sum(&sum(&scale(&cx, a.x), &scale(&cy, a.y)), &scale(&cz, a.z));
    compress(&acc)
}

/// Sign of `a . b`, exactly.
pub(crate) fn dot_sign(a: DVec3, b: DVec3) -> i8 {
    sign(&dot(a, b))
}

/// Sign of `(p1 . q1) det(a1, b1, c1) - (p2 . q2) det(a2, b2, c2)`, exactly: the form of every
/// product of a crossing point with another point that the clip needs (see `clip.rs`).
pub(crate) fn dot_det_difference_sign(
    (p1, q1): (DVec3, DVec3),
    (a1, b1, c1): (DVec3, DVec3, DVec3),
    (p2, q2): (DVec3, DVec3),
    (a2, b2, c2): (DVec3, DVec3, DVec3),
) -> i8 {
    let left = product(&dot(p1, q1), &det(a1, b1, c1));
    let right = product(&dot(p2, q2), &det(a2, b2, c2));
    sign(&sum(&left, &neg(&right)))
}

/// Sign of `(p1 . q1)(r1 . s1) - (p2 . q2)(r2 . s2)`, exactly.
pub(crate) fn dot_dot_difference_sign(
    (p1, q1): (DVec3, DVec3),
    (r1, s1): (DVec3, DVec3),
    (p2, q2): (DVec3, DVec3),
    (r2, s2): (DVec3, DVec3),
) -> i8 {
    let left = product(&dot(p1, q1), &dot(r1, s1));
    let right = product(&dot(p2, q2), &dot(r2, s2));
    sign(&sum(&left, &neg(&right)))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A small deterministic generator (SplitMix64) for the exactness checks.
    struct Mix(u64);
    impl Mix {
        fn next(&mut self) -> u64 {
            self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
            let mut z = self.0;
            z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
            z ^ (z >> 31)
        }
        /// An integer in [-2^20, 2^20].
        fn int(&mut self) -> i64 {
            (self.next() % (1 << 21)) as i64 - (1 << 20)
        }
        fn ivec(&mut self) -> [i64; 3] {
            [self.int(), self.int(), self.int()]
        }
    }

    fn idot(a: [i64; 3], b: [i64; 3]) -> i128 {
        (0..3).map(|i| a[i] as i128 * b[i] as i128).sum()
    }
    fn idet(a: [i64; 3], b: [i64; 3], c: [i64; 3]) -> i128 {
        let (a, b, c) = (a.map(i128::from), b.map(i128::from), c.map(i128::from));
        a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0])
            + a[2] * (b[0] * c[1] - b[1] * c[0])
    }
    /// The vector in floating point, every coordinate scaled by the same power of two `2^k`
    /// (exact), so that the tests also cover coordinates far from 1.
    fn fvec(a: [i64; 3], k: i32) -> DVec3 {
        let s = 2f64.powi(k);
        DVec3::new(a[0] as f64 * s, a[1] as f64 * s, a[2] as f64 * s)
    }

    /// The exact signs agree with integer arithmetic (i128 holds every value here: degree-5 terms
    /// of 21-bit integers stay below 2^107), on random inputs and on inputs built to cancel
    /// exactly or to within one unit.
    #[test]
    fn signs_match_integer_arithmetic() {
        let mut g = Mix(12);
        for case in 0..4000 {
            let [p1, q1, a1, b1, p2, q2, a2, b2] = core::array::from_fn(|_| g.ivec());
            let c1 = g.ivec();
            // Half the cases: the second term is built equal to the first up to a small offset,
            // so that the difference is zero or tiny against the terms.
            let (p2, q2, a2, b2, c2) = if case % 2 == 0 {
                let mut c2 = c1;
                c2[(case / 2) % 3] += (g.next() % 3) as i64 - 1;
                (p1, q1, a1, b1, c2)
            } else {
                (p2, q2, a2, b2, g.ivec())
            };
            let exact = idot(p1, q1) * idet(a1, b1, c1) - idot(p2, q2) * idet(a2, b2, c2);
            let k = (case % 7) as i32 * 40 - 120; // scales 2^-120 .. 2^120
            let f = |v: [i64; 3]| fvec(v, k);
            let got = dot_det_difference_sign(
                (f(p1), f(q1)),
                (f(a1), f(b1), f(c1)),
                (f(p2), f(q2)),
                (f(a2), f(b2), f(c2)),
            );
            assert_eq!(got, exact.signum() as i8, "case {case}");
            let exact = idot(p1, q1) * idot(a1, b1) - idot(p2, q2) * idot(a2, b2);
            let got = dot_dot_difference_sign(
                (f(p1), f(q1)),
                (f(a1), f(b1)),
                (f(p2), f(q2)),
                (f(a2), f(b2)),
            );
            assert_eq!(got, exact.signum() as i8, "case {case}");
            assert_eq!(dot_sign(f(p1), f(q1)), idot(p1, q1).signum() as i8);
        }
    }

    /// A signed integer of any size (little-endian base 2^32 limbs), enough for exact degree-5
    /// products of 53-bit integers: an independent reference for the expansions.
    #[derive(Clone, Debug)]
    struct Big {
        neg: bool,
        mag: alloc::vec::Vec<u32>,
    }

    impl Big {
        fn from_i64(x: i64) -> Big {
            let u = x.unsigned_abs();
            Big {
                neg: x < 0,
                mag: alloc::vec![u as u32, (u >> 32) as u32],
            }
            .trim()
        }
        fn trim(mut self) -> Big {
            while self.mag.last() == Some(&0) {
                self.mag.pop();
            }
            if self.mag.is_empty() {
                self.neg = false;
            }
            self
        }
        fn cmp_mag(a: &[u32], b: &[u32]) -> core::cmp::Ordering {
            a.len()
                .cmp(&b.len())
                .then_with(|| a.iter().rev().cmp(b.iter().rev()))
        }
        fn add_mag(a: &[u32], b: &[u32]) -> alloc::vec::Vec<u32> {
            let mut out = alloc::vec::Vec::new();
            let mut carry = 0u64;
            for i in 0..a.len().max(b.len()) {
                let t = carry + *a.get(i).unwrap_or(&0) as u64 + *b.get(i).unwrap_or(&0) as u64;
                out.push(t as u32);
                carry = t >> 32;
            }
            out.push(carry as u32);
            out
        }
        /// a - b for |a| >= |b|.
        fn sub_mag(a: &[u32], b: &[u32]) -> alloc::vec::Vec<u32> {
            let mut out = alloc::vec::Vec::new();
            let mut borrow = 0i64;
            for (i, &x) in a.iter().enumerate() {
                let mut t = x as i64 - *b.get(i).unwrap_or(&0) as i64 - borrow;
                borrow = 0;
                if t < 0 {
                    t += 1 << 32;
                    borrow = 1;
                }
                out.push(t as u32);
            }
            out
        }
        fn add(&self, o: &Big) -> Big {
            if self.neg == o.neg {
                return Big {
                    neg: self.neg,
                    mag: Big::add_mag(&self.mag, &o.mag),
                }
                .trim();
            }
            match Big::cmp_mag(&self.mag, &o.mag) {
                core::cmp::Ordering::Less => Big {
                    neg: o.neg,
                    mag: Big::sub_mag(&o.mag, &self.mag),
                },
                _ => Big {
                    neg: self.neg,
                    mag: Big::sub_mag(&self.mag, &o.mag),
                },
            }
            .trim()
        }
        fn neg(&self) -> Big {
            Big {
                neg: !self.neg,
                mag: self.mag.clone(),
            }
            .trim()
        }
        fn mul(&self, o: &Big) -> Big {
            let mut out = alloc::vec![0u64; self.mag.len() + o.mag.len() + 1];
            for (i, &a) in self.mag.iter().enumerate() {
                let mut carry = 0u64;
                for (j, &b) in o.mag.iter().enumerate() {
                    let t = out[i + j] + a as u64 * b as u64 + carry;
                    out[i + j] = t & 0xFFFF_FFFF;
                    carry = t >> 32;
                }
                let mut k = i + o.mag.len();
                while carry > 0 {
                    let t = out[k] + carry;
                    out[k] = t & 0xFFFF_FFFF;
                    carry = t >> 32;
                    k += 1;
                }
            }
            Big {
                neg: self.neg != o.neg,
                mag: out.into_iter().map(|x| x as u32).collect(),
            }
            .trim()
        }
        fn signum(&self) -> i8 {
            if self.mag.is_empty() {
                0
            } else if self.neg {
                -1
            } else {
                1
            }
        }
    }

    fn bdot(a: [i64; 3], b: [i64; 3]) -> Big {
        (0..3).fold(Big::from_i64(0), |acc, i| {
            acc.add(&Big::from_i64(a[i]).mul(&Big::from_i64(b[i])))
        })
    }
    fn bdet(a: [i64; 3], b: [i64; 3], c: [i64; 3]) -> Big {
        let m = |x: i64, y: i64| Big::from_i64(x).mul(&Big::from_i64(y));
        let cx = m(b[1], c[2]).add(&m(b[2], c[1]).neg());
        let cy = m(b[2], c[0]).add(&m(b[0], c[2]).neg());
        let cz = m(b[0], c[1]).add(&m(b[1], c[0]).neg());
        Big::from_i64(a[0])
            .mul(&cx)
            .add(&Big::from_i64(a[1]).mul(&cy))
            .add(&Big::from_i64(a[2]).mul(&cz))
    }

    /// With full 53-bit significands every product has a rounding error, which the expansions
    /// must carry: the signs agree with big-integer arithmetic on random inputs and on inputs
    /// built so that the two terms cancel exactly or up to a few units.
    #[test]
    fn signs_match_big_integer_arithmetic() {
        let mut g = Mix(99);
        let int53 = |g: &mut Mix| {
            let m = (g.next() >> 11) as i64; // 53 bits
            if g.next().is_multiple_of(2) { m } else { -m }
        };
        let v = |g: &mut Mix| [int53(g), int53(g), int53(g)];
        for case in 0..3000 {
            let [p1, q1, a1, b1, c1, p2, q2, a2, b2] = core::array::from_fn(|_| v(&mut g));
            // Every other case: the second term equals the first with one coordinate of one
            // factor moved by -1, 0 or +1, so that the difference is zero or tiny.
            let (p2, q2, a2, b2, c2) = if case % 2 == 0 {
                let mut c2 = c1;
                c2[case % 3] += (g.next() % 3) as i64 - 1;
                (p1, q1, a1, b1, c2)
            } else {
                (p2, q2, a2, b2, v(&mut g))
            };
            let exact = bdot(p1, q1)
                .mul(&bdet(a1, b1, c1))
                .add(&bdot(p2, q2).mul(&bdet(a2, b2, c2)).neg());
            let k = (case % 5) as i32 * 20 - 90; // all inputs scaled by 2^k, k in -90..-10
            let f = |x: [i64; 3]| fvec(x, k);
            let got = dot_det_difference_sign(
                (f(p1), f(q1)),
                (f(a1), f(b1), f(c1)),
                (f(p2), f(q2)),
                (f(a2), f(b2), f(c2)),
            );
            assert_eq!(got, exact.signum(), "case {case}");
            let exact = bdot(p1, q1)
                .mul(&bdot(a1, b1))
                .add(&bdot(p2, q2).mul(&bdot(a2, b2)).neg());
            let got = dot_dot_difference_sign(
                (f(p1), f(q1)),
                (f(a1), f(b1)),
                (f(p2), f(q2)),
                (f(a2), f(b2)),
            );
            assert_eq!(got, exact.signum(), "case {case}");
        }
    }

    /// Unit vectors whose products cancel to far below one ulp of the terms: the sign is still
    /// that of the exact value (compared with the same expression on the same doubles, shifted by
    /// a power of two, which must not change the sign), and exact zeros are found.
    #[test]
    fn cancellation_below_rounding() {
        let a = DVec3::new(0.6, 0.8, 0.0);
        let b = DVec3::new(-0.8, 0.6, 1e-50);
        // det(a, b, a) = 0 exactly, however the rounding of the parts goes.
        assert_eq!(
            dot_det_difference_sign((a, a), (a, b, a), (b, b), (b, a, b)),
            0
        );
        // a.b = -0.48 + 0.48 + 0 in real numbers, but 0.6, 0.8 and their products are rounded:
        // the sign is whatever the exact products of these doubles give, the same as for the
        // doubles scaled by powers of two; a tiny z component then decides a zero.
        let s = dot_sign(a, b);
        assert_eq!(dot_sign(a * 2f64.powi(-70), b * 2f64.powi(90)), s);
        assert_eq!(dot_sign(DVec3::X, DVec3::Y), 0);
        assert_eq!(
            dot_sign(DVec3::new(1.0, 0.0, 1e-40), DVec3::new(0.0, 1.0, 1e-40)),
            1
        );
        let c = DVec3::new(0.1, 0.2, 0.3);
        let d = c * (1.0 + f64::EPSILON);
        // (c.c) det(c,d,X) - (c.c) det(c,d,X) = 0, and a one-ulp change in one factor decides.
        let x = DVec3::X;
        assert_eq!(
            dot_det_difference_sign((c, c), (c, d, x), (c, c), (c, d, x)),
            0
        );
        let s1 = dot_det_difference_sign((c, d), (c, d, x), (c, c), (c, d, x));
        let s2 = dot_det_difference_sign((c, c), (c, d, x), (c, d), (c, d, x));
        assert_eq!(s1, -s2);
        assert_ne!(s1, 0);
    }
}
