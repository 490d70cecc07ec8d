//! Uniform sampling of spherical triangles by solid angle, and its inverse (Arvo 1995; thesis 003,
//! section 3.6), in forms that keep relative precision from triangles a nanoradian across to
//! triangles within a hair of a hemisphere.

use glam::{DVec2, DVec3};

use alloc::vec::Vec;

use super::polygon::SphericalPolygon;
use super::predicates::{normalize_any, orient};
use crate::GeomError;
use crate::math::{atan2, sin_cos, sqrt};

/// How far outside its triangle a sample may land, relative to the triangle's size (its longest
/// edge chord), on top of the rounding of the sample's own coordinates.
///
/// A sample is a unit vector rounded to `f64`, so its distance to an edge's plane is uncertain by
/// about half an ulp of each coordinate weighted by the plane's normal: for a triangle around an
/// axis that is far below `1e-12` of its size even at a nanoradian, for one around `(1, 1, 1)` it
/// is about `1e-16` absolute. [`SphericalTriangle::sample`] stays within this tolerance plus that
/// rounding; [`SphericalTriangle::inverse`] accepts directions within it plus `4 eps`.
pub const SAMPLE_TOLERANCE: f64 = 1e-12;

/// A spherical triangle prepared for uniform sampling over its solid angle.
///
/// \[Arv95\]'s construction: the solid angle `A'` of a sub-triangle `(A, B, C')` is drawn uniformly
/// in `[0, area]`, which fixes `C'` on the arc `AC`; the sample is drawn on the arc from `B` to `C'`
/// with `1 - cos(theta)` uniform, which makes the result uniform. Arvo writes both steps with
/// cosines of arcs (`C'.B`, `cos(b')`), whose information sits in the last bits of a number near
/// one for a small triangle: at a micro-radian every digit is gone. Here each step is re-derived in
/// quantities that stay small with the triangle (see [`SphericalTriangle::sample`]): differences
/// of nearby unit vectors, chords instead of cosines, half-angle tangents, and the
/// Van Oosterom–Strackee form of a triangle's area, `tan(area / 2) = det(A, B, C) / (1 + A.B +
/// B.C + C.A)`. No case falls back to another method.
///
/// The vertices may be given in either orientation; the map from the unit square depends on
/// their order.
///
/// # Examples
///
/// ```
/// use arealight::glam::{DVec2, DVec3};
/// use arealight::sphere::SphericalTriangle;
/// let t = SphericalTriangle::new(DVec3::X, DVec3::Y, DVec3::Z)?;
/// assert!((t.solid_angle() - std::f64::consts::FRAC_PI_2).abs() < 1e-15);
/// let u = DVec2::new(0.3, 0.7);
/// let w = t.sample(u);
/// assert!(w.min_element() >= -1e-15 && (w.length() - 1.0).abs() < 1e-12);
/// assert!((t.inverse(w).unwrap() - u).length() < 1e-12);
/// assert_eq!(t.inverse(-w), None);
/// # Ok::<(), arealight::GeomError>(())
/// ```
///
/// # References
///
/// - \[Arv95\] J. Arvo. *Stratified sampling of spherical triangles.* SIGGRAPH 1995.
/// - A. van Oosterom, J. Strackee. *The solid angle of a plane triangle.* IEEE Trans. Biomed.
///   Eng. 30(2), 1983.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SphericalTriangle {
    /// The vertices as given.
    given: [DVec3; 3],
    /// The vertices in counter-clockwise order (seen from outside): `a, b, c`.
    a: DVec3,
    b: DVec3,
    c: DVec3,
    area: f64,
    /// `b - a` and `b + a`.
    ab: DVec3,
    apb: DVec3,
    /// Unit tangent at `a` towards `c`.
    t: DVec3,
    /// `det(a, b, t)`: positive.
    det_abt: f64,
    /// `b . t = (b - a) . t`.
    bt: f64,
    /// `1 + a.b = |a + b|^2 / 2`.
    one_ab: f64,
    /// `tan(|ac| / 2)` as the ratio `|c - a| / |c + a|`.
    tan_half_ac: (f64, f64),
    /// Longest edge chord: the triangle's size for tolerances.
    size: f64,
}

impl SphericalTriangle {
    /// Prepares the triangle `(a, b, c)`; the vertices are normalized.
    ///
    /// # Errors
    ///
    /// [`GeomError::NonFinite`] / [`GeomError::ZeroVector`] for a vertex that names no direction,
    /// [`GeomError::Degenerate`] for a triangle whose vertices lie on one great circle (exactly, by
    /// Shewchuk's `orient3d`) or whose solid angle rounds to zero.
    pub fn new(a: DVec3, b: DVec3, c: DVec3) -> Result<Self, GeomError> {
        let mut v = [DVec3::ZERO; 3];
        for (i, p) in [a, b, c].into_iter().enumerate() {
            if !p.is_finite() {
                return Err(GeomError::NonFinite { ring: 0, vertex: i });
            }
            v[i] = normalize_any(p).ok_or(GeomError::ZeroVector { ring: 0, vertex: i })?;
        }
        Self::from_unit(v[0], v[1], v[2])
    }

    /// As [`SphericalTriangle::new`] for vertices that are unit vectors already; they are kept
    /// bit for bit, so that triangles of a triangulation share their vertices exactly.
    pub(crate) fn from_unit(a: DVec3, b: DVec3, c: DVec3) -> Result<Self, GeomError> {
        let given = [a, b, c];
        let (a, b, c) = match orient(a, b, c) {
            1 => (a, b, c),
            -1 => (a, c, b),
            _ => {
                return Err(GeomError::Degenerate(
                    "spherical triangle with its vertices on one great circle",
                ));
            }
        };
        let (ab, ac) = (b - a, c - a);
        let (apb, apc) = (a + b, a + c);
        // Positive (the sign is exact above), but it may round to zero for a sliver below
        // rounding, which cannot be sampled meaningfully.
        let area = signed_solid_angle(a, b, c);
        let Some(t) = tangent(a, ac, apc) else {
            return Err(GeomError::Degenerate(
                "spherical triangle with a repeated vertex",
            ));
        };
        // det(a, b, t) and b . t, again on the shorter of b -+ a (a . t = 0).
        let bs = shorter(ab, apb);
        let det_abt = a.dot(bs.cross(t));
        let bt = bs.dot(t);
        let one_ab = 0.5 * apb.length_squared();
        if !(area > 0.0) || !(det_abt > 0.0) || !(one_ab > 0.0) || !area.is_finite() {
            return Err(GeomError::Degenerate(
                "spherical triangle of zero solid angle (within rounding) cannot be sampled",
            ));
        }
        let size = ab.length().max(ac.length()).max((c - b).length());
        Ok(SphericalTriangle {
            given,
            a,
            b,
            c,
            area,
            ab,
            apb,
            t,
            det_abt,
            bt,
            one_ab,
            tan_half_ac: (ac.length(), (a + c).length()),
            size,
        })
    }

    /// The vertices (unit vectors), in the order given.
    #[must_use]
    pub fn vertices(&self) -> [DVec3; 3] {
        self.given
    }

    /// The solid angle (positive, below `2 pi`).
    #[must_use]
    pub fn solid_angle(&self) -> f64 {
        self.area
    }

    /// A direction in the triangle from two numbers in `[0, 1]`; over uniform `u` the result is
    /// uniform in solid angle (density `1 / solid_angle`). Always a unit vector, within
    /// [`SAMPLE_TOLERANCE`] of the triangle's size (plus the rounding of its coordinates) of the
    /// triangle. Components of `u` outside `[0, 1]` are clamped to it, NaN to `0`; `u = (x, 0)`
    /// is the vertex `b` of the counter-clockwise order, `(0, 1)` is `a`, `(1, 1)` is `c`.
    ///
    /// With `A, B, C` counter-clockwise and `T` the unit tangent at `A` towards `C`, the points of
    /// arc `AC` are `C'(phi) = A cos(phi) + T sin(phi)`. Van Oosterom–Strackee for `(A, B, C')`,
    /// with half angles, gives `tan(A'/2) = tau D / ((1 + A.B) + (B.T) tau)`, `tau = tan(phi/2)`,
    /// `D = det(A, B, T)`: linear-fractional in `tau`, so the `C'` of a drawn `A'` is
    /// `tan(phi/2) = sin(A'/2) (1 + A.B) / (D cos(A'/2) - (B.T) sin(A'/2))` (this replaces
    /// \[Arv95\]'s `cos(b')`). Then `C' - A = (2N / (N^2 + M^2)) (M T - N A)` for that fraction `N/M`,
    /// and on arc `BC'` (chord `e = C' - B`), `1 - cos(theta)` uniform is
    /// `sin(theta/2) = sqrt(u2) |e| / 2`. Every quantity is a small difference computed as such.
    #[must_use]
    pub fn sample(&self, u: DVec2) -> DVec3 {
        let (u1, u2) = (clamp01(u.x), clamp01(u.y));
        let (a, b) = (self.a, self.b);
        let (sig, kap) = sin_cos(0.5 * u1 * self.area);
        let n = sig * self.one_ab;
        let m = self.det_abt * kap - self.bt * sig;
        // C' - A, with C' clamped to the arc's end C (where rounding would pass it).
        let (tn, td) = self.tan_half_ac;
        let (delta, c_prime) = if n * td >= m * tn {
            (self.c - a, self.c)
        } else {
            let h2 = n * n + m * m;
            let delta = (self.t * m - a * n) * (2.0 * n / h2);
            (delta, a + delta)
        };
        let e = delta - self.ab; // C' - B
        let f = self.apb + delta; // C' + B
        // The point at angle theta from B along arc BC' (length theta_m = 2a), with sin(theta/2) =
        // sqrt(u2) sin(a), is taken from the nearer end: from C' the arc's far half is measured
        // by psi = theta_m - theta, which stays accurate where theta itself would be lost
        // against pi (C' nearly antipodal to B, in near-hemisphere triangles).
        let (sin_a, cos_a) = (0.5 * e.length(), 0.5 * f.length());
        let (from, tan, sin_h) = if u2 <= 0.5 {
            (b, tangent(b, e, f), sqrt(u2) * sin_a)
        } else {
            // sin(psi/2) = sin(a) (1 - u2) / (cos(g) + sqrt(u2) cos(a)) with g = theta/2: the
            // difference cos(g) - sqrt(u2) cos(a) rewritten as a quotient of positive terms.
            let cos_g = sqrt(cos_a * cos_a + (1.0 - u2) * sin_a * sin_a);
            let sin_h = sin_a * (1.0 - u2) / (cos_g + sqrt(u2) * cos_a);
            (c_prime, tangent(c_prime, -e, f), sin_h)
        };
        let Some(tan) = tan else {
            return from;
        };
        let ch = sqrt((1.0 - sin_h) * (1.0 + sin_h));
        let p = from + tan * (2.0 * sin_h * ch) - from * (2.0 * sin_h * sin_h);
        normalize_any(p).unwrap_or(from)
    }

    /// The point of the unit square that [`SphericalTriangle::sample`] maps to `dir` (any
    /// positive multiple of a direction), or `None` when `dir` names no direction or lies
    /// outside the triangle by more than [`SAMPLE_TOLERANCE`] of its size plus `4 eps`.
    /// Directions within that band outside are mapped to the nearest boundary value; the result
    /// is always in `[0, 1]^2`.
    ///
    /// The arc from `B` through `dir` meets arc `AC` at `C'(phi)`: with `n = B x dir`,
    /// `tan(phi) = -(n.A) / (n.T)`; `u1` is the area of `(A, B, C')` over the triangle's (the
    /// same half-angle form as in `sample`), `u2 = |dir - B|^2 / |C' - B|^2`. `inverse(sample(u))`
    /// returns `u` to about `1e-8` (`u1` where `u2` is near `0`, where every `u1` maps near
    /// `B`, is the least determined; `tests/sphere_sample.rs` measures it).
    #[must_use]
    pub fn inverse(&self, dir: DVec3) -> Option<DVec2> {
        let p = normalize_any(dir)?;
        if !self.covers(p) {
            return None;
        }
        let (a, b) = (self.a, self.b);
        let bp = p - b;
        let nb = b.cross(shorter(bp, p + b));
        // n . A and n . T for the plane through B and p.
        let (y, x) = (-a.dot(nb), self.t.dot(nb));
        // The circle through B and p meets circle AC at phi and phi + pi; C' is the one nearer
        // the arc's range [0, |AC|] (near phi = 0 the sign of y alone is decided by rounding).
        let arc = 2.0 * atan2(self.tan_half_ac.0, self.tan_half_ac.1);
        let off = |phi: f64| {
            if (0.0..=arc).contains(&phi) {
                0.0
            } else {
                (-phi)
                    .rem_euclid(2.0 * core::f64::consts::PI)
                    .min((phi - arc).rem_euclid(2.0 * core::f64::consts::PI))
            }
        };
        let phi = atan2(y, x);
        let flip = phi - core::f64::consts::PI.copysign(phi);
        let (y, x) = if off(flip) < off(phi) {
            (-y, -x)
        } else {
            (y, x)
        };
        // tan(phi / 2) = q / w without cancellation on either side of phi = pi / 2.
        let r = sqrt(x * x + y * y);
        let (q, w) = if !(r > 0.0) {
            (0.0, 1.0)
        } else if x >= 0.0 {
            (y, r + x)
        } else {
            (r - x, y)
        };
        let half = atan2(q * self.det_abt, self.one_ab * w + self.bt * q);
        let u1 = clamp01(2.0 * half / self.area);
        let h2 = q * q + w * w;
        let delta = (self.t * w - a * q) * (2.0 * q / h2);
        let e = delta - self.ab;
        let e2 = e.length_squared();
        let u2 = if e2 > 0.0 {
            clamp01(bp.length_squared() / e2)
        } else {
            0.0
        };
        Some(DVec2::new(u1, u2))
    }

    /// Whether the unit vector `p` lies in the triangle or outside it by at most
    /// [`SAMPLE_TOLERANCE`] of its size plus `4 eps`.
    pub(crate) fn covers(&self, p: DVec3) -> bool {
        let tol = SAMPLE_TOLERANCE * self.size + 4.0 * f64::EPSILON;
        let (a, b, c) = (self.a, self.b, self.c);
        [(a, b), (b, c), (c, a)].into_iter().all(|(x, y)| {
            // Signed distance (sine) of p to the plane of x -> y: det(x, y, p) = det(x, w, p - x)
            // with w the shorter of y -+ x, all small for a small or nearly antipodal edge.
            let w = shorter(y - x, y + x);
            let d = x.dot(w.cross(p - x)) / x.cross(w).length();
            d >= -tol
        })
    }

    /// The density of [`SphericalTriangle::sample`] at `dir`: `1 / solid_angle` when
    /// [`SphericalTriangle::inverse`] accepts `dir`, else `0`.
    #[must_use]
    pub fn pdf(&self, dir: DVec3) -> f64 {
        if normalize_any(dir).is_some_and(|p| self.covers(p)) {
            1.0 / self.area
        } else {
            0.0
        }
    }
}

/// Uniform sampling of a spherical polygon by solid angle: its triangulation
/// ([`SphericalPolygon::triangulate`]) with a triangle chosen in proportion to its solid angle
/// (binary search of the cumulative areas), then sampled by [`SphericalTriangle::sample`].
///
/// # Examples
///
/// ```
/// use arealight::glam::{DVec2, DVec3};
/// use arealight::sphere::{PolygonSampler, SphericalPolygon};
/// let l = SphericalPolygon::new(vec![vec![
///     DVec3::new(0.0, 0.0, 1.0), DVec3::new(0.2, 0.0, 1.0), DVec3::new(0.2, 0.1, 1.0),
///     DVec3::new(0.1, 0.1, 1.0), DVec3::new(0.1, 0.2, 1.0), DVec3::new(0.0, 0.2, 1.0),
/// ]])?;
/// let s = PolygonSampler::new(&l)?;
/// let w = s.sample(DVec2::new(0.4, 0.9));
/// assert!(l.contains(w));
/// assert_eq!(s.pdf(w), 1.0 / s.solid_angle());
/// assert_eq!(s.pdf(-w), 0.0);
/// # Ok::<(), arealight::GeomError>(())
/// ```
#[derive(Debug, Clone)]
pub struct PolygonSampler {
    tris: Vec<SphericalTriangle>,
    /// Cumulative solid angles: `cdf[k]` is the sum over triangles `0..=k`.
    cdf: Vec<f64>,
}

impl PolygonSampler {
    /// Triangulates `poly` for sampling.
    ///
    /// # Errors
    ///
    /// [`GeomError::Degenerate`] for the empty region (nothing to sample); the errors of
    /// [`SphericalPolygon::triangulate`].
    pub fn new(poly: &SphericalPolygon) -> Result<Self, GeomError> {
        let tris = poly.triangulate()?;
        let mut cdf = Vec::with_capacity(tris.len());
        let mut total = 0.0;
        for t in &tris {
            total += t.solid_angle();
            cdf.push(total);
        }
        if tris.is_empty() {
            return Err(GeomError::Degenerate("the empty region cannot be sampled"));
        }
        Ok(PolygonSampler { tris, cdf })
    }

    /// The triangles sampled from (see [`SphericalPolygon::triangulate`]).
    #[must_use]
    pub fn triangles(&self) -> &[SphericalTriangle] {
        &self.tris
    }

    /// The polygon's solid angle: the sum of its triangles'.
    #[must_use]
    pub fn solid_angle(&self) -> f64 {
        self.cdf[self.cdf.len() - 1]
    }

    /// A direction in the polygon from two numbers in `[0, 1]` (clamped, NaN as `0`), uniform in
    /// solid angle over uniform `u`: `u.x` picks the triangle by cumulative solid angle and,
    /// rescaled to that triangle's share, is its first coordinate.
    #[must_use]
    pub fn sample(&self, u: DVec2) -> DVec3 {
        let total = self.solid_angle();
        let x = clamp01(u.x) * total;
        let k = self
            .cdf
            .partition_point(|&c| c <= x)
            .min(self.cdf.len() - 1);
        let lo = if k == 0 { 0.0 } else { self.cdf[k - 1] };
        let w = self.tris[k].solid_angle();
        self.tris[k].sample(DVec2::new((x - lo) / w, u.y))
    }

    /// `1 / solid_angle` for a direction in the polygon (one of its triangles covers it, to
    /// [`SAMPLE_TOLERANCE`] of the triangle's size), else `0` (also for non-directions).
    #[must_use]
    pub fn pdf(&self, dir: DVec3) -> f64 {
        match normalize_any(dir) {
            Some(p) if self.tris.iter().any(|t| t.covers(p)) => 1.0 / self.solid_angle(),
            _ => 0.0,
        }
    }
}

/// Signed solid angle of the triangle `(a, b, c)` of unit vectors (Van Oosterom–Strackee,
/// `tan(area / 2) = det(a, b, c) / (1 + a.b + b.c + c.a)`), with both terms kept to relative
/// precision for nearby and for nearly antipodal vertices: `det(a, b, c) = det(a, b -+ a,
/// c -+ a)` on the shorter of each pair, and each `x.y` as `1 - |x - y|^2 / 2` or
/// `|x + y|^2 / 2 - 1`, whichever chord is shorter, with the constants added first. (The plain
/// denominator cancels to rounding noise for a thin triangle from a point to a far, tiny edge,
/// as in a fan from the antipode of a tiny polygon.)
pub(crate) fn signed_solid_angle(a: DVec3, b: DVec3, c: DVec3) -> f64 {
    signed_solid_angle_with_error(a, b, c).0
}

/// [`signed_solid_angle`] and a bound on its rounding error. `det` is a dot product of short
/// vectors, off by a few `eps |u| |v|`; the denominator is an exact integer plus half-chords
/// squared, off by a few `eps` times their magnitudes (not its value: they can cancel); the
/// angle `2 atan2(det, den)` moves by `2 (|den| d_det + |det| d_den) / (det^2 + den^2)`. The
/// bound is large only where both terms vanish together: nearly antipodal vertices nearly on a
/// great circle, whose area rounding decides at will.
///
/// The half-chords are those of the directions, not of the rounded vectors: for vectors
/// `1 + d` long, `|x -+ y|^2` differs from the unit vectors' by up to about `(d_x - d_y)^2` (the
/// first order cancels), which is negligible unless the denominator itself is that small (a vertex
/// within `1e-8` of the antipode of both others, as in a fan from the far side over a tiny
/// polygon, where it moved the area by `1e-11`). There the chords are taken of
/// `x -+ y - (d_x x -+ d_y y)` with the defects `d` to their own precision
/// ([`super::exact::unit_defect`]).
pub(crate) fn signed_solid_angle_with_error(a: DVec3, b: DVec3, c: DVec3) -> (f64, f64) {
    let (u, v) = (shorter(b - a, b + a), shorter(c - a, c + a));
    let det = a.dot(u.cross(v));
    let (den, magnitude) = denominator(a, b, c, None);
    // The chords' normalization error: up to (d_x - d_y)^2 <= 1e-30 each for vectors within
    // 5e-16 of unit length when left out; with the defects, their rounding (about 4e-32) times
    // twice the chord. Below this denominator the first could show.
    let (den, magnitude, normalization) = if den.abs() < 1e-8 {
        let defects = [a, b, c].map(super::exact::unit_defect);
        let (den, magnitude) = denominator(a, b, c, Some(defects));
        (den, magnitude, 5e-31 * crate::math::sqrt(magnitude))
    } else {
        (den, magnitude, 3e-30)
    };
    let eps = f64::EPSILON;
    let d_det = 8.0 * eps * crate::math::sqrt(u.length_squared() * v.length_squared());
    let d_den = 8.0 * eps * magnitude + eps * den.abs() + normalization;
    let norm = det * det + den * den;
    let err = if norm > 0.0 {
        2.0 * (den.abs() * d_det + det.abs() * d_den) / norm
    } else {
        f64::INFINITY
    };
    (2.0 * atan2(det, den), err)
}

/// Van Oosterom–Strackee's denominator `1 + a.b + b.c + c.a` as an integer plus half-chords
/// squared (`1 + x.y = 2 - |x - y|^2 / 2 = |x + y|^2 / 2`, the shorter chord of each pair), and
/// the sum of the half-chords' magnitudes. With `defects` (`|x| - 1` per vertex), the chords
/// of the unit vectors (see [`signed_solid_angle_with_error`]).
fn denominator(a: DVec3, b: DVec3, c: DVec3, defects: Option<[f64; 3]>) -> (f64, f64) {
    let mut constant = 1.0;
    let mut small = 0.0;
    let mut magnitude = 0.0;
    for (i, j) in [(0, 1), (1, 2), (2, 0)] {
        let (x, y) = ([a, b, c][i], [a, b, c][j]);
        let (dv, sv) = (x - y, x + y);
        let (d, s) = (dv.length_squared(), sv.length_squared());
        let near = d <= s;
        let chord = match defects {
            None => {
                if near {
                    d
                } else {
                    s
                }
            }
            Some(e) => {
                let (ex, ey) = (x * e[i], y * e[j]);
                if near {
                    (dv - (ex - ey)).length_squared()
                } else {
                    (sv - (ex + ey)).length_squared()
                }
            }
        };
        if near {
            constant += 1.0;
            small -= 0.5 * chord;
        } else {
            constant -= 1.0;
            small += 0.5 * chord;
        }
        magnitude += 0.5 * chord;
    }
    (constant + small, magnitude)
}

/// The shorter of two vectors (the first on a tie).
#[inline]
fn shorter(p: DVec3, q: DVec3) -> DVec3 {
    if p.length_squared() <= q.length_squared() {
        p
    } else {
        q
    }
}

/// The unit tangent at the unit vector `from` towards the unit vector `to`, given `d = to - from`
/// and `s = to + from`: the part of the shorter of `d` and `s` orthogonal to `from`. That vector
/// is accurate to its own relative precision (nearby or nearly antipodal vertices alike), and its
/// projection is taken directly: `from . d = -|d|^2 / 2` holds only for exact unit vectors, and
/// the rounding of `|from|` would tilt the tangent by `eps / |d|`.
#[inline]
fn tangent(from: DVec3, d: DVec3, s: DVec3) -> Option<DVec3> {
    let w = shorter(d, s);
    normalize_any(w - from * from.dot(w))
}

/// `x` clamped to `[0, 1]`, NaN to `0`.
#[inline]
fn clamp01(x: f64) -> f64 {
    if x >= 1.0 {
        1.0
    } else if x > 0.0 {
        x
    } else {
        0.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn corners_of_the_unit_square_map_to_vertices() {
        let t = SphericalTriangle::new(DVec3::X, DVec3::Y, DVec3::Z).unwrap();
        assert!((t.sample(DVec2::new(0.3, 0.0)) - DVec3::Y).length() < 1e-12);
        assert!((t.sample(DVec2::new(1.0, 1.0)) - DVec3::Z).length() < 1e-12);
        assert!((t.sample(DVec2::new(0.0, 1.0)) - DVec3::X).length() < 1e-12);
        assert!(SphericalTriangle::new(DVec3::X, DVec3::Y, DVec3::X).is_err());
        assert!(SphericalTriangle::new(DVec3::X, DVec3::Y, DVec3::new(1.0, 1.0, 0.0)).is_err());
    }

    #[test]
    fn out_of_range_uniforms_are_clamped() {
        let t = SphericalTriangle::new(DVec3::X, DVec3::Y, DVec3::Z).unwrap();
        for (u, v) in [
            (DVec2::new(2.0, -1.0), DVec2::new(1.0, 0.0)),
            (DVec2::new(f64::NAN, 0.5), DVec2::new(0.0, 0.5)),
            (DVec2::new(-3.0, f64::INFINITY), DVec2::new(0.0, 1.0)),
        ] {
            assert_eq!(t.sample(u), t.sample(v));
        }
    }

    /// A fan triangle from the far side of a ring 1e-10 rad across: its apex lies within 1e-10
    /// of the antipode of both other vertices, and the vectors are unit only to 2e-16. The
    /// 60-digit area of the triangle of their directions (mpmath, normalized to 60 digits) is
    /// 1.9620406324349051326; the chords of the rounded vectors gave 1.96204063242741 (7.5e-12
    /// off, outside the bound claimed).
    #[test]
    fn area_with_an_apex_near_the_antipode_of_both_others() {
        let a = DVec3::new(
            0.21277109939609068,
            -0.47526496887180014,
            0.8537280999387719,
        );
        let b = DVec3::new(-0.21277109934982402, 0.475264968854496, -0.8537280999599359);
        let c = DVec3::new(-0.2127710993157535, 0.4752649689184834, -0.853728099932806);
        let (w, err) = signed_solid_angle_with_error(a, b, c);
        let exact = 1.962_040_632_434_905_1;
        assert!((w - exact).abs() <= err, "{w} vs {exact}, bound {err:e}");
        assert!(err < 1e-14, "{err:e}");
    }
}
