//! Integrals of the clamped cosine over spherical polygons (Lambert's irradiance formula).

use core::f64::consts::PI;

use glam::DVec3;

use crate::sphere::{HORIZON_TOLERANCE, SphericalPolygon};

/// A direction of any positive length with its squared length, computed once per vertex because
/// the horizon test and the rational edge term both need it.
#[derive(Clone, Copy)]
pub(super) struct Ray {
    v: DVec3,
    len2: f64,
}

impl Ray {
    #[inline(always)]
    pub(super) fn new(v: DVec3) -> Self {
        Self {
            v,
            len2: v.length_squared(),
        }
    }

    /// The dot product of the two directions' vectors.
    #[inline(always)]
    pub(super) fn dot(self, other: Ray) -> f64 {
        self.v.dot(other.v)
    }

    /// The squared length.
    #[inline(always)]
    pub(super) fn len2(self) -> f64 {
        self.len2
    }
}

/// Baum's edge term for the edge `a -> b`: `theta * (a x b)_z / |a x b|`, with the angle taken as
/// `atan2(|a x b|, a . b)`, which stays accurate for tiny edges (no `acos` of a rounded dot
/// product near 1) and for edges near pi long. For a tiny edge `theta / |a x b| -> 1`.
///
/// Always inlined, like [`rational_edge_term`] and [`ClipFree::finish`]: out of line (the
/// compiler's choice in callers that do not inline the whole integral) the rays and the running
/// state go through memory, and the reloads of separately stored fields stall store-to-load
/// forwarding (see BENCHMARKS.md, "ltc shading").
#[inline(always)]
pub(super) fn edge_term(a: Ray, b: Ray) -> f64 {
    // Invariant under positive scaling of `a` and `b`, so the endpoints need not be unit vectors.
    let (a, b) = (a.v, b.v);
    let c = a.cross(b);
    let s = c.length();
    if s == 0.0 {
        return 0.0; // coincident endpoints: an edge of zero length contributes nothing
    }
    crate::math::atan2(s, a.dot(b)) / s * c.z
}

/// A rational approximation of the edge factor `theta / sin(theta)` as a function of
/// `x = cos(theta) = a . b`, for renderers that prefer it to an `atan2`.
///
/// On `[0, 1]` it is a (2, 2) rational function fitted by this crate (minimax on the relative
/// error, see `tests/ltc_integrals.rs`); for `x < 0` it uses the reflection
/// `theta / sin(theta) = pi / sin(theta) - (pi - theta) / sin(pi - theta)`, which needs one
/// square root. Maximum relative error over `[-1, 1]`: [`EDGE_FACTOR_RATIONAL_MAX_ERROR`]
/// (the factor diverges as `x -> -1`; `1 - x^2` is clamped at `1e-14`).
#[inline]
#[must_use]
pub fn edge_factor_rational(x: f64) -> f64 {
    let [p0, p1, p2, q0, q1] = EDGE_FACTOR_COEFFS;
    let y = x.abs();
    let v = (p0 + (p1 + p2 * y) * y) / (q0 + (q1 + y) * y);
    if x >= 0.0 {
        v
    } else {
        PI / crate::math::sqrt((1.0 - x * x).max(1e-14)) - v
    }
}

/// `(p0 + p1 y + p2 y^2) / (q0 + q1 y + y^2)`: this crate's minimax fit of `theta / sin(theta)`
/// for `y = cos(theta)` in `[0, 1]`.
const EDGE_FACTOR_COEFFS: [f64; 5] = [
    5.429131712,
    3.130161863,
    0.089934273,
    3.456294690,
    4.192928007,
];

/// Largest relative error of [`edge_factor_rational`] against `acos(x) / sqrt(1 - x^2)` over
/// `[-1, 1]`, as measured on a dense grid by the tests.
pub const EDGE_FACTOR_RATIONAL_MAX_ERROR: f64 = 6.1e-7;

/// [`clamped_cosine_integral`] with the edge factor from [`edge_factor_rational`] instead of an
/// `atan2` per edge: exact clipping, approximate edge terms. Each edge term is off by at most
/// [`EDGE_FACTOR_RATIONAL_MAX_ERROR`] times `theta_e`, so the result is off by at most that
/// constant times the clipped polygon's perimeter over `2 pi` (below the constant itself for a
/// convex polygon, whose perimeter inside a hemisphere is below `2 pi`).
#[must_use]
pub fn clamped_cosine_integral_rational(poly: &SphericalPolygon) -> f64 {
    clipped_sum(poly, Rational)
}

/// Integral of a linearly transformed cosine over a polygon in the shading frame: the polygon is
/// mapped by `m_inv` (HDHN16 eq. 14: integrating `D` over `P` equals integrating the clamped
/// cosine over `M^-1 P`) and its clamped-cosine integral is taken. Multiply by the lookup's
/// normalization (`LtcLookup::norm`, `specular_scale`) for the specular response.
///
/// # Errors
///
/// As [`SphericalPolygon::transformed`] for a singular or non-finite `m_inv`;
/// [`crate::GeomError::Undecidable`] when the exact path's clip of the transformed polygon at the
/// horizon is not consistent (its parts above and below do not partition the region's solid
/// angle, or the integral exceeds the part above's solid angle over pi): a vertex's image a few
/// ulps from the horizon, where the clip is delicate, rather than a possibly wrong value.
pub fn ltc_integral(poly: &SphericalPolygon, m_inv: glam::DMat3) -> Result<f64, crate::GeomError> {
    transformed_integral(poly, m_inv, Exact)
}

/// [`ltc_integral`] with the rational edge factor ([`edge_factor_rational`]) and no `atan2` at
/// all: the rational factor also gives the total angle of the horizon arcs. Error bound as for
/// [`clamped_cosine_integral_rational`], applied to the transformed polygon (the horizon arcs
/// count in its perimeter).
///
/// # Errors
///
/// As [`ltc_integral`].
#[inline]
pub fn ltc_integral_rational(
    poly: &SphericalPolygon,
    m_inv: glam::DMat3,
) -> Result<f64, crate::GeomError> {
    transformed_integral(poly, m_inv, Rational)
}

/// The clamped-cosine integral of `m` applied to `poly`, with the given edge term: the stack-only
/// clip-free path (thesis 003 eq. 4.6/4.7) when the map keeps orientation, the exact clip of the
/// transformed polygon otherwise. Both agree to rounding (tested).
#[inline(always)]
fn transformed_integral(
    poly: &SphericalPolygon,
    m: glam::DMat3,
    edge: impl EdgeTerm,
) -> Result<f64, crate::GeomError> {
    if !poly.is_full()
        && !poly.is_empty()
        && let Some(v) = transformed_clip_free(poly, &m, edge)
    {
        return Ok(v);
    }
    exact_transformed(poly, m, edge)
}

/// The exact path of [`transformed_integral`], kept out of line so that the clip-free path's
/// code stays small and needs no large stack frame. The clip of the transformed polygon is
/// checked ([`checked_upper_part`]): the clip-free path hands over exactly the configurations
/// where clipping is delicate (a vertex's image within `HORIZON_TOLERANCE` of the horizon).
#[cold]
#[inline(never)]
fn exact_transformed(
    poly: &SphericalPolygon,
    m: glam::DMat3,
    edge: impl EdgeTerm,
) -> Result<f64, crate::GeomError> {
    let t = poly.transformed(m)?;
    let up = checked_upper_part(&t, "the LTC integral's clip at the cosine's horizon")?;
    let v = upper_sum(&up.0, edge);
    // The clamped cosine is at most `1 / pi`: no more than the part's solid angle over pi (the
    // rational factor's error and rounding aside).
    if v > up.1 / PI + 1e-12 {
        return Err(crate::GeomError::Undecidable(
            "the LTC integral exceeds its clipped part's solid angle over pi",
        ));
    }
    Ok(v)
}

/// The part of `poly` in the closed upper hemisphere with its solid angle, or
/// [`crate::GeomError::Undecidable`] when the clip is not consistent with the region: the part
/// cannot be larger than the region, nor leave out more than the lower hemisphere (both to
/// `1e-9` of the sphere's solid angle, the sphere layer's own fuzzing tolerance). The sphere
/// layer's clip can fail that near the horizon (issue 24, reproducer 1: a sliver clipped to the
/// whole hemisphere, or the complement of one to nothing), and the integral of a wrong clip is a
/// wrong value. Not a proof of the clip: a wrong part within those bounds passes (the clip of
/// the other hemisphere, which would complete the partition check, fails the same way today and
/// would flag correct parts). The check costs two solid angles, on the exact paths only.
fn checked_upper_part(
    poly: &SphericalPolygon,
    what: &'static str,
) -> Result<(SphericalPolygon, f64), crate::GeomError> {
    const TOL: f64 = 4e-9 * PI;
    let up = poly.clip_to_axis_hemisphere(DVec3::Z);
    let (wu, w) = (up.solid_angle(), poly.solid_angle());
    if !(wu <= w + TOL && w - wu <= 2.0 * PI + TOL) {
        return Err(crate::GeomError::Undecidable(what));
    }
    Ok((up, wu))
}

/// The GGX specular response to a uniform unit-radiance polygon light: approximately
/// `integral over P of f(v, l) F(v, l) cos(theta_l) dl` with the height-correlated GGX BRDF and
/// Schlick's Fresnel with reflectance `f0` (HDHN16 section 4 and eq. 14; the albedo/Fresnel split
/// follows the Fresnel tables of this crate's fit).
///
/// `poly` is given in the shading frame (normal `+z`, view in the xz-plane with `x >= 0`) with
/// the view at `cos_theta_v` from the normal; `alpha` is GGX's roughness parameter (`alpha =
/// roughness^2` in the usual artist mapping). Evaluated here: the table lookup, the clip to the
/// shading horizon (the tables are fitted for LTCs clipped there), the transform by `M^-1`, the
/// horizon handling in cosine space and Baum's edge sum. The clip is skipped for regions shown
/// to lie in the upper hemisphere (every vertex above the horizon is not enough: the complement
/// of a light above the point holds the whole lower hemisphere), and checked against the
/// region's solid angle otherwise; where it fails the check, the part above the horizon is taken
/// as the upper hemisphere less the complement's part (whose LTC integral is `albedo / norm` in
/// closed form minus that of the complement's clip, if that one passes).
///
/// With `f0 = 1` the result lies in `[0, albedo]` for every region: `norm` is the albedo over
/// the LTC's mass above the horizon.
///
/// # Errors
///
/// [`crate::GeomError::OutOfRange`] for NaN parameters (see [`super::lookup`]);
/// [`crate::GeomError::Undecidable`] where a clip at a horizon is not consistent within rounding:
/// the shading one, of the region and of its complement, or the cosine space's on the exact path
/// of [`ltc_integral`].
pub fn ggx_polygon_integral(
    poly: &SphericalPolygon,
    cos_theta_v: f64,
    alpha: f64,
    f0: f64,
) -> Result<f64, crate::GeomError> {
    if !f0.is_finite() {
        return Err(crate::GeomError::OutOfRange {
            what: "Fresnel reflectance f0",
            value: f0,
            limit: 1.0,
        });
    }
    let l = super::lookup(cos_theta_v, alpha)?;
    // The tables' LTCs are fitted as clipped to the shading horizon and renormalized (`norm`),
    // so the light is clipped there first; the clip is skipped only for regions shown to lie in
    // the upper hemisphere. Vertices above the horizon are not enough: a region may still
    // contain the whole lower hemisphere (the complement of a light above the point).
    let integral = if inside_upper_hemisphere(poly) {
        ltc_integral(poly, l.m_inv)?
    } else {
        match checked_upper_part(poly, "the clip at the shading horizon") {
            Ok((up, _)) => ltc_integral(&up, l.m_inv)?,
            // The complement's clip, where the region's is inconsistent: `P n H` is `H` less
            // `P' n H`, and the LTC integral of `H` is in closed form (`albedo / norm`).
            Err(e) => {
                let (rest, _) = checked_upper_part(&poly.complement(), "").map_err(|_| e)?;
                (l.albedo / l.norm - ltc_integral(&rest, l.m_inv)?).max(0.0)
            }
        }
    };
    // No part of the upper hemisphere holds more of the LTC than all of it, `albedo / norm`
    // (exactly, where rounding in the images under a map of condition up to about 1e7 at
    // grazing views could put a region just short of the hemisphere a few 1e-9 above it).
    let integral = integral.min(l.albedo / l.norm);
    Ok(l.specular_scale(f0.clamp(0.0, 1.0)) * integral)
}

/// Whether the region certainly lies in the open upper hemisphere: `false` when it does not or
/// when that is not certain (and for the empty region, which needs no decision).
///
/// Every vertex must lie above the horizon by more than [`HORIZON_TOLERANCE`]: then no edge (a
/// minor arc, a positive combination of its endpoints) meets the closed lower hemisphere, which
/// is therefore wholly inside or wholly outside the region. The gnomonic map about `+z`,
/// `p -> (x / z, y / z)`, takes the rings to plane polygons with the region on their left; the
/// sum of their signed areas is the area of the region's image when that image is bounded (the
/// region avoids the lower hemisphere), and minus the area of the bounded part it leaves out
/// otherwise. So the sign decides, when it exceeds the rounding bound accumulated alongside.
/// Each ring's area is taken about its own first vertex, so that a small ring far from the
/// zenith keeps its relative precision: its terms are of the ring's size squared, not of its
/// distance from the zenith times its size.
///
/// Linear in the vertices with one division per coordinate; an undecided sign (a region about
/// `1e-15` of its distance from the zenith across, or less) answers `false`, and the caller
/// clips, which is right either way.
fn inside_upper_hemisphere(poly: &SphericalPolygon) -> bool {
    if poly.is_full() {
        return false;
    }
    let project = |v: DVec3| (v.z > HORIZON_TOLERANCE).then(|| (v.x / v.z, v.y / v.z));
    // The signed area (twice), a bound on the error of its terms, and the sum of their sizes.
    let (mut area, mut bound, mut size) = (0.0, 0.0, 0.0);
    for ring in poly.rings() {
        let Some((&first, rest)) = ring.split_first() else {
            continue;
        };
        let Some(o) = project(first) else {
            return false;
        };
        let size_o = o.0.abs() + o.1.abs();
        // Offsets from the first vertex (the first offset is zero, and so is its term), each
        // with a bound on its error per coordinate: a rounded quotient and a rounded difference,
        // below `eps (|p| + |o|)`; doubled.
        let (mut d, mut err_d, mut size_d) = ((0.0, 0.0), 0.0, 0.0);
        for &v in rest {
            let Some(p) = project(v) else {
                return false;
            };
            let e = (p.0 - o.0, p.1 - o.1);
            let err_e = 2.0 * f64::EPSILON * (p.0.abs() + p.1.abs() + size_o);
            let size_e = e.0.abs() + e.1.abs();
            area += d.0 * e.1 - d.1 * e.0;
            // The inputs' errors times the other factor, and the products' and the difference's
            // own rounding (doubled).
            bound += size_d * err_e + size_e * err_d + 4.0 * f64::EPSILON * size_d * size_e;
            size += size_d * size_e;
            (d, err_d, size_d) = (e, err_e, size_e);
        }
    }
    // The summation's rounding: below `n eps` times the sum of the terms' magnitudes.
    let n = poly.vertex_count() as f64;
    area > 2.0 * (bound + n * f64::EPSILON * size)
}

/// [`edge_factor_rational`] of `y / l` divided by `l`, as a fraction `num / den` of
/// homogeneous polynomials in `l = sqrt(l2)` and `y` (the endpoints' length product and `|a . b|`
/// for an edge of any scale): one root and, by the caller, one division.
#[inline(always)]
fn rational_ratio(l2: f64, y: f64) -> (f64, f64) {
    let [p0, p1, p2, q0, q1] = EDGE_FACTOR_COEFFS;
    let l = crate::math::sqrt(l2);
    let num = p0 * l2 + (p1 * l + p2 * y) * y;
    let den = (q0 * l2 + (q1 * l + y) * y) * l;
    (num, den)
}

/// The edge term with [`edge_factor_rational`] in place of `theta / sin(theta)`, for endpoints of
/// any positive length (the clip-free path does not normalize).
///
/// With `l = |a| |b|` and `d = a . b`, the (2, 2) rational function of `|d| / l` is evaluated in
/// homogeneous form, so the whole term costs one square root and one division; edges longer than
/// a quarter circle add the reflection term `pi / sin(theta)` with `l sin(theta) = |a x b|`.
#[inline(always)]
fn rational_edge_term(a: Ray, b: Ray) -> f64 {
    let l2 = a.len2 * b.len2;
    let (a, b) = (a.v, b.v);
    let d = a.dot(b);
    let cz = a.x * b.y - a.y * b.x;
    let (num, den) = rational_ratio(l2, d.abs());
    let v = num * cz / den;
    if d >= 0.0 {
        v
    } else {
        // `cz / |a x b|` is at most 1 in magnitude, so unlike `pi / sin(theta)` alone this needs
        // no clamp near theta = pi (a horizon arc of half a circle comes out as pi); only the
        // zero-length cross product of antipodal endpoints (where `cz` is zero too) is guarded.
        let s = crate::math::sqrt(a.cross(b).length_squared()).max(f64::MIN_POSITIVE);
        PI * cz / s - v
    }
}

/// [`rational_edge_term`] of the two edges `a[k] -> b[k]`, written lane by lane with one branch
/// for both, so that the compiler evaluates them with two-lane operations (one packed square root
/// and one packed division for two edges): two edge terms side by side instead of two chains of
/// scalar ones in a row (see BENCHMARKS.md, "ltc shading"). Edges longer than a quarter circle take
/// the scalar terms.
#[inline(always)]
fn rational_edge_term_pair(a: [Ray; 2], b: [Ray; 2]) -> [f64; 2] {
    let d = lanes(|k| a[k].v.dot(b[k].v));
    if !(d[0] >= 0.0 && d[1] >= 0.0) {
        return [
            rational_edge_term(a[0], b[0]),
            rational_edge_term(a[1], b[1]),
        ];
    }
    let l2 = lanes(|k| a[k].len2 * b[k].len2);
    let cz = lanes(|k| a[k].v.x * b[k].v.y - a[k].v.y * b[k].v.x);
    let [(n0, d0), (n1, d1)] = [rational_ratio(l2[0], d[0]), rational_ratio(l2[1], d[1])];
    [n0 * cz[0] / d0, n1 * cz[1] / d1]
}

/// `[f(0), f(1)]`: one value per lane of [`rational_edge_term_pair`].
#[inline(always)]
fn lanes(f: impl Fn(usize) -> f64) -> [f64; 2] {
    [f(0), f(1)]
}

/// The two ways of evaluating Baum's edge terms: exactly ([`Exact`]) or with the rational edge
/// factor ([`Rational`]).
trait EdgeTerm: Copy {
    /// The edge term of the edge `a -> b`, for endpoints of any positive length.
    fn term(self, a: Ray, b: Ray) -> f64;

    /// The edge term of the horizon arc from the x-axis to `(re, im, 0)` (not both zero): the
    /// argument of `re + i im` in `[-pi, pi]`, with the same error as [`EdgeTerm::term`].
    fn arg(self, re: f64, im: f64) -> f64;

    /// The terms of the two edges `a[k] -> b[k]`: for the rational factor, evaluated side by side
    /// so that the compiler can pair them into two-lane operations.
    #[inline(always)]
    fn term_pair(self, a: [Ray; 2], b: [Ray; 2]) -> [f64; 2] {
        [self.term(a[0], b[0]), self.term(a[1], b[1])]
    }
}

/// Edge terms with `atan2` ([`edge_term`]).
#[derive(Clone, Copy)]
struct Exact;

impl EdgeTerm for Exact {
    #[inline(always)]
    fn term(self, a: Ray, b: Ray) -> f64 {
        edge_term(a, b)
    }

    #[inline(always)]
    fn arg(self, re: f64, im: f64) -> f64 {
        crate::math::atan2(im, re)
    }
}

/// Edge terms with the rational edge factor ([`rational_edge_term`]).
#[derive(Clone, Copy)]
struct Rational;

impl EdgeTerm for Rational {
    #[inline(always)]
    fn term(self, a: Ray, b: Ray) -> f64 {
        rational_edge_term(a, b)
    }

    /// [`rational_edge_term`] from `(1, 0, 0)` to `(re, im, 0)`, where `|a x b| = |im|` needs no
    /// root: the reflection for an argument beyond a quarter turn adds no second root and no
    /// second division.
    #[inline(always)]
    fn arg(self, re: f64, im: f64) -> f64 {
        let (num, den) = rational_ratio(re * re + im * im, re.abs());
        let v = num * im / den;
        if re >= 0.0 { v } else { PI.copysign(im) - v }
    }

    #[inline(always)]
    fn term_pair(self, a: [Ray; 2], b: [Ray; 2]) -> [f64; 2] {
        rational_edge_term_pair(a, b)
    }
}

/// Signed integral of `z / pi` over the region bounded by the rings, by Stokes' theorem
/// (Baum, Rushmeier and Winget 1989; HDHN16 eq. 11): `(1 / 2 pi) sum theta_e n_e . z`.
fn boundary_sum(poly: &SphericalPolygon, edge: impl EdgeTerm) -> f64 {
    let mut sum = 0.0;
    for ring in poly.rings() {
        let n = ring.len();
        for i in 0..n {
            sum += edge.term(Ray::new(ring[i]), Ray::new(ring[(i + 1) % n]));
        }
    }
    sum / (2.0 * PI)
}

/// The exact path: clip to the upper hemisphere, then the boundary sum.
fn clipped_sum(poly: &SphericalPolygon, edge: impl EdgeTerm) -> f64 {
    upper_sum(&poly.clip_to_axis_hemisphere(DVec3::Z), edge)
}

/// The boundary sum of a region inside the closed upper hemisphere, where it is the integral.
fn upper_sum(poly: &SphericalPolygon, edge: impl EdgeTerm) -> f64 {
    boundary_sum(poly, edge).clamp(0.0, 1.0)
}

/// [`clamped_cosine_integral`] of a region already inside the closed upper hemisphere (a result
/// of [`SphericalPolygon::clip_to_hemisphere`] about `+z`, or a part of one): Baum's edge sum
/// without clipping it a second time. For other regions it is not the integral.
pub(crate) fn clamped_cosine_integral_upper(poly: &SphericalPolygon) -> f64 {
    upper_sum(poly, Exact)
}

/// [`clamped_cosine_integral_upper`] of a region given as a chain of rings of directions of any
/// positive length (not normalized: Baum's edge terms are invariant under positive scaling of
/// each endpoint) in the closed upper hemisphere: the sum of the rings' edge terms, whatever the
/// rings' orientation or overlap, is the integral weighted by the chain's winding number, which
/// for the shading fast path's regions (`crate::visibility::Pieces`) is the region's indicator.
/// The diffuse integral of that path, the same sum as the polygon's up to rounding.
pub(crate) fn upper_rings_integral<'a>(rings: impl Iterator<Item = &'a [DVec3]>) -> f64 {
    let mut sum = 0.0;
    for ring in rings {
        let Some(&last) = ring.last() else {
            continue;
        };
        let mut prev = Ray::new(last);
        for &v in ring {
            let cur = Ray::new(v);
            sum += edge_term(prev, cur);
            prev = cur;
        }
    }
    integral_of_sum(sum)
}

/// [`ltc_integral`] of a region given as a chain of rings (as for [`upper_rings_integral`]) in
/// the closed upper hemisphere (clipped at the shading horizon, as the LTC tables assume): the
/// specular integral of the shading fast path.
///
/// The clip-free kernel ([`transformed_clip_free`], the same code as for a polygon: the quad and
/// single-ring kernels for one ring, the general loop for several) decides most regions; where it
/// hands over (an image within rounding of the cosine's horizon, as the images of a piece's
/// vertices on the shading horizon under a map that keeps the horizon), each ring's images are
/// clipped at the horizon by Sutherland–Hodgman in homogeneous coordinates and Baum's sum is
/// taken over the result: one plane, so the clipped chain's winding number is the ring's times
/// the half-space's indicator for any ring (the parts outside are closed into loops outside by
/// the same bridges along the horizon). `None` only for a map that is singular, not finite or
/// reverses orientation, which the LTC tables never give.
pub(crate) fn ltc_rings_integral<'a, I>(rings: I, m_inv: glam::DMat3) -> Option<f64>
where
    I: Iterator<Item = &'a [DVec3]> + Clone,
{
    let mut one = rings.clone();
    let v = match (one.next(), one.next()) {
        (Some(ring), None) => transformed_clip_free(ring, &m_inv, Exact),
        _ => transformed_clip_free(&RingChain(rings.clone()), &m_inv, Exact),
    };
    v.or_else(|| clipped_rings_integral(rings, m_inv))
}

/// Several rings integrated as one region by the clip-free path ([`ring_sum`]).
struct RingChain<I>(I);

impl<'a, I: Iterator<Item = &'a [DVec3]> + Clone> ClipFreeInput for RingChain<I> {
    #[inline(always)]
    fn clip_free(&self, map: impl Fn(DVec3) -> DVec3, edge: impl EdgeTerm) -> Option<f64> {
        ring_sum(self.0.clone(), map, edge)
    }
}

/// The exact path of [`ltc_rings_integral`], out of line.
#[cold]
#[inline(never)]
fn clipped_rings_integral<'a>(
    rings: impl Iterator<Item = &'a [DVec3]>,
    m_inv: glam::DMat3,
) -> Option<f64> {
    let m = crate::math::unit_scaled(m_inv)?;
    if !(m.determinant() > 0.0) {
        return None;
    }
    let mut sum = 0.0;
    let mut up: smallvec::SmallVec<[DVec3; 32]> = smallvec::SmallVec::new();
    for ring in rings {
        let Some(&last) = ring.last() else {
            continue;
        };
        up.clear();
        let mut prev = m * last;
        for &v in ring {
            let cur = m * v;
            if prev.z >= 0.0 {
                up.push(prev);
            }
            if (prev.z > 0.0 && cur.z < 0.0) || (prev.z < 0.0 && cur.z > 0.0) {
                // A positive combination of the two with `z` exactly zero (the products
                // commute).
                let (a, b) = if prev.z > 0.0 {
                    (prev, cur)
                } else {
                    (cur, prev)
                };
                let x = a * -b.z + b * a.z;
                up.push(DVec3::new(x.x, x.y, 0.0));
            }
            prev = cur;
        }
        if let Some(&last) = up.last() {
            let mut prev = Ray::new(last);
            for &v in &up {
                let cur = Ray::new(v);
                sum += edge_term(prev, cur);
                prev = cur;
            }
        }
    }
    Some(integral_of_sum(sum))
}

/// `(1 / pi)` times the integral of `max(0, z)` over the polygon: the irradiance from a uniform
/// unit-radiance light filling the polygon onto a surface with normal `+z`, relative to a light
/// filling the whole hemisphere. In `[0, 1]`.
///
/// The polygon is clipped exactly to the upper hemisphere ([`SphericalPolygon::clip_to_hemisphere`])
/// and Baum's edge sum is evaluated on the result (HDHN16 section 3.1 and eq. 11; seed paper 000,
/// Alg. 1 line 15). Works for every valid polygon: holes, several rings, regions larger than a
/// hemisphere, the full sphere (which gives 1).
///
/// # Examples
///
/// ```
/// use arealight::glam::DVec3;
/// use arealight::ltc::clamped_cosine_integral;
/// use arealight::sphere::SphericalPolygon;
///
/// // The whole upper hemisphere receives pi * L, i.e. 1 in these units.
/// let up = SphericalPolygon::new(vec![vec![DVec3::X, DVec3::Y, -DVec3::X, -DVec3::Y]])?;
/// assert!((clamped_cosine_integral(&up) - 1.0).abs() < 1e-15);
/// assert!(clamped_cosine_integral(&up.complement()).abs() < 1e-15);
/// # Ok::<(), arealight::GeomError>(())
/// ```
#[must_use]
pub fn clamped_cosine_integral(poly: &SphericalPolygon) -> f64 {
    clipped_sum(poly, Exact)
}

/// The same integral as [`clamped_cosine_integral`] without building the clipped polygon: the
/// parts of the original edges above the horizon are integrated as they are, and the new edges
/// along the horizon enter only through their endpoints (thesis 003, eq. 4.6).
///
/// A horizon edge from an exit point `X` counter-clockwise to an entry point `E` contributes its
/// angle `theta_E - theta_X`. Summed over all of them, the angles of the entries count `+1` and
/// those of the exits `-1`, so no pairing of crossings is needed; and by the atan2 sum identity
/// (eq. 4.7) the whole sum is the argument of one complex product, so one `atan2` is evaluated in
/// total (none in the rational variant of [`ltc_integral_rational`], which takes that argument
/// with its rational factor). The product gives the sum modulo `2 pi`; since the horizon arcs are disjoint their total
/// lies in `[0, 2 pi]`, which removes the ambiguity except between "none" and "all" of the circle.
///
/// Configurations where that or the pairing is ambiguous (a vertex within [`HORIZON_TOLERANCE`] of
/// the horizon, no crossing while some vertex is below it, or every edge above the horizon with
/// an edge sum within rounding of zero, where its sign would decide whether the region surrounds
/// the horizon) are delegated to the exact path, so the two agree to rounding on every valid
/// polygon.
#[must_use]
pub fn clamped_cosine_integral_clip_free(poly: &SphericalPolygon) -> f64 {
    if poly.is_full() {
        return 1.0;
    }
    clip_free_sum(poly, |v| v, Exact).unwrap_or_else(|| clamped_cosine_integral(poly))
}

/// [`clamped_cosine_integral_clip_free`] of the region bounded by `rings`, given as directions of
/// any positive length that are trusted to bound a valid region (as [`SphericalPolygon::new`]
/// would accept them once normalized: simple, disjoint, interior on the left): a front-facing
/// mesh face seen from a point, a silhouette valid by construction. No polygon is built and no
/// vertex is normalized (every quantity of the clip-free sum is invariant under positive scaling
/// of a vertex), so a renderer integrating many small rings pays only for the edge terms.
///
/// Where the clip-free path hands over to the exact one (a vertex within rounding of the
/// horizon; see [`clamped_cosine_integral_clip_free`]), the rings are normalized and validated
/// as a [`SphericalPolygon`] and integrated exactly; the two paths agree to rounding.
///
/// # Errors
///
/// Those of [`SphericalPolygon::new`] for rings that are not a valid polygon, raised only on the
/// rare exact path: the validity of the rings is the caller's to guarantee, and on the fast
/// path rings that are not valid give the integral of their boundary chain (each part of the
/// sphere weighted by its winding number where that is defined), not an error.
pub fn clamped_cosine_integral_rings<'a, I>(rings: I) -> Result<f64, crate::GeomError>
where
    I: IntoIterator<Item = &'a [DVec3]>,
    I::IntoIter: Clone,
{
    let rings = rings.into_iter();
    let mut one = rings.clone();
    let fast = match (one.next(), one.next()) {
        (None, _) => return Ok(0.0),
        (Some(ring), None) => ring_clip_free_sum(ring, |v| v, Exact),
        _ => ring_sum(rings.clone(), |v| v, Exact),
    };
    match fast {
        Some(v) => Ok(v),
        None => Ok(clamped_cosine_integral(&polygon_of_rings(rings)?)),
    }
}

/// [`ltc_integral`] of the region bounded by `rings` (directions of any positive length trusted
/// to bound a valid region, as for [`clamped_cosine_integral_rings`]): the clip-free path on the
/// vertices' images under `m_inv`, the exact path on the validated polygon where it hands over.
///
/// # Errors
///
/// As [`ltc_integral`]; and those of [`SphericalPolygon::new`] for rings that are not a valid
/// polygon, on the exact path only (see [`clamped_cosine_integral_rings`]).
pub fn ltc_integral_rings<'a, I>(rings: I, m_inv: glam::DMat3) -> Result<f64, crate::GeomError>
where
    I: IntoIterator<Item = &'a [DVec3]>,
    I::IntoIter: Clone,
{
    let rings = rings.into_iter();
    let mut one = rings.clone();
    let fast = match (one.next(), one.next()) {
        (None, _) => return Ok(0.0),
        (Some(ring), None) => transformed_clip_free(ring, &m_inv, Exact),
        _ => transformed_clip_free(&RingChain(rings.clone()), &m_inv, Exact),
    };
    match fast {
        Some(v) => Ok(v),
        None => ltc_integral(&polygon_of_rings(rings)?, m_inv),
    }
}

/// The validated polygon of rings of directions of any positive length: the exact paths of
/// [`clamped_cosine_integral_rings`] and [`ltc_integral_rings`], out of line.
#[cold]
#[inline(never)]
fn polygon_of_rings<'a>(
    rings: impl Iterator<Item = &'a [DVec3]>,
) -> Result<SphericalPolygon, crate::GeomError> {
    let mut out = alloc::vec::Vec::new();
    for ring in rings {
        let mut r = alloc::vec::Vec::with_capacity(ring.len());
        for &v in ring {
            r.push(v.try_normalize().ok_or(crate::GeomError::Degenerate(
                "a ring vertex is zero or not finite",
            ))?);
        }
        out.push(r);
    }
    SphericalPolygon::new(out)
}

/// The clip-free sum of [`clamped_cosine_integral_clip_free`] over the images of the polygon's
/// vertices under `map`, with the edge term given: a single ring through [`single_ring_sum`],
/// several through [`ring_sum`]. `None` where the exact path must decide (a vertex on the
/// horizon, or no crossing while some vertex is below).
#[inline(always)]
fn clip_free_sum(
    poly: &SphericalPolygon,
    map: impl Fn(DVec3) -> DVec3,
    edge: impl EdgeTerm,
) -> Option<f64> {
    match poly.single_ring() {
        Some(ring) => ring_clip_free_sum(ring, map, edge),
        None => ring_sum(poly.rings(), map, edge),
    }
}

/// [`clip_free_sum`] of one ring: quads through [`quad_sum`], other rings through
/// [`single_ring_sum`].
#[inline(always)]
fn ring_clip_free_sum(
    ring: &[DVec3],
    map: impl Fn(DVec3) -> DVec3,
    edge: impl EdgeTerm,
) -> Option<f64> {
    if ring.len() == 4 {
        quad_sum(ring, map, edge)
    } else {
        single_ring_sum(ring, map, edge)
    }
}

/// What the clip-free path integrates: the rings of a [`SphericalPolygon`], or one bare ring of
/// directions of any positive length (the pieces of the shading fast path, which are never
/// built as polygons). Generic, so that each caller's code is the kernel inlined for its input.
trait ClipFreeInput {
    /// The clip-free sum of the images of the vertices under `map` ([`clip_free_sum`]).
    fn clip_free(&self, map: impl Fn(DVec3) -> DVec3, edge: impl EdgeTerm) -> Option<f64>;
}

impl ClipFreeInput for SphericalPolygon {
    #[inline(always)]
    fn clip_free(&self, map: impl Fn(DVec3) -> DVec3, edge: impl EdgeTerm) -> Option<f64> {
        clip_free_sum(self, map, edge)
    }
}

impl ClipFreeInput for [DVec3] {
    #[inline(always)]
    fn clip_free(&self, map: impl Fn(DVec3) -> DVec3, edge: impl EdgeTerm) -> Option<f64> {
        ring_clip_free_sum(self, map, edge)
    }
}

/// The clip-free sum over the images of the rings' vertices under `map`, which need not be unit
/// vectors: every quantity the sum uses is invariant under positive scaling of each vertex (the
/// edge terms by construction, the horizon crossings as positive combinations, the arguments of
/// the crossing product, the sign tests), so no vertex is normalized. Each image is computed once
/// and nothing is buffered.
#[inline(always)]
fn ring_sum<'a>(
    rings: impl Iterator<Item = &'a [DVec3]>,
    map: impl Fn(DVec3) -> DVec3,
    edge: impl EdgeTerm,
) -> Option<f64> {
    let mut acc = ClipFree::new();
    for ring in rings {
        let Some((&first, rest)) = ring.split_first() else {
            continue;
        };
        let first = Ray::new(map(first));
        let mut prev = first;
        for &v in rest {
            let cur = Ray::new(map(v));
            acc.add_edge(prev, cur, edge)?;
            prev = cur;
        }
        acc.add_edge(prev, first, edge)?;
    }
    acc.finish(edge)
}

/// Running state of the clip-free sum (thesis 003 eq. 4.6 and 4.7) over the edges of closed
/// rings.
struct ClipFree {
    /// Sum of the edge terms of the parts of edges above the horizon.
    sum: f64,
    /// Running complex product of the entry points and conjugated exit points on the horizon.
    re: f64,
    im: f64,
    crossings: usize,
    edges: usize,
    any_below: bool,
    /// Sum of the magnitudes of the edge terms: the scale of the rounding in `sum`.
    magnitude: f64,
}

impl ClipFree {
    /// Squared [`HORIZON_TOLERANCE`]: a vertex `v` is on the horizon when
    /// `v.z^2 <= HORIZON_TOLERANCE^2 |v|^2`, the tolerance of the exact clip for unit vectors.
    const ON_HORIZON2: f64 = HORIZON_TOLERANCE * HORIZON_TOLERANCE;

    /// Relative margin for the sign of the edge sum when no edge crosses the horizon: above the
    /// error of the rational edge factor ([`EDGE_FACTOR_RATIONAL_MAX_ERROR`]) and of rounding.
    const SIGN_MARGIN: f64 = 4.0 * EDGE_FACTOR_RATIONAL_MAX_ERROR;

    /// Bound on the absolute rounding error of one edge term: `(a x b)_z` is a difference of
    /// products of the (scaled) coordinates, off by a few ulps of 1 whatever the edge's length,
    /// and the factor `theta / |a x b|` is accurate (for a tiny edge both parts of the ratio come
    /// from the same `|a x b|`). So the sum of a ring of width `h` (about `h^2`) is decided by
    /// its sign only above roughly `h = 1e-7`; smaller regions take the exact path.
    const TERM_ROUNDING: f64 = 64.0 * f64::EPSILON;

    fn new() -> Self {
        Self {
            sum: 0.0,
            re: 1.0,
            im: 0.0,
            crossings: 0,
            edges: 0,
            any_below: false,
            magnitude: 0.0,
        }
    }

    /// The horizon's part of the sum when every edge lies strictly above it: the horizon is then
    /// wholly inside or wholly outside the region. Outside, the region lies in the upper
    /// hemisphere and the edge sum is 2 pi times its (positive) integral; inside, the complement
    /// does and the sum is minus 2 pi times the complement's integral. So the sign decides, unless
    /// it is within the rounding (or the rational edge factor's error) of zero: a region of almost
    /// no integral on one side or the other, left to the exact path (`None`).
    #[inline(always)]
    fn horizon_if_all_above(sum: f64, magnitude: f64, edges: usize) -> Option<f64> {
        let margin = Self::SIGN_MARGIN * magnitude + Self::TERM_ROUNDING * edges as f64;
        if sum < -margin {
            Some(2.0 * PI)
        } else if sum > margin {
            Some(0.0)
        } else {
            None
        }
    }

    /// Whether `a` is off the horizon by more than [`HORIZON_TOLERANCE`] (false for NaN and
    /// infinite components too).
    #[inline(always)]
    fn off_horizon(a: Ray) -> bool {
        a.v.z * a.v.z > Self::ON_HORIZON2 * a.len2
    }

    /// Whether `a` is strictly above the horizon by more than [`HORIZON_TOLERANCE`] (false for
    /// NaN and infinite components too).
    #[inline(always)]
    fn clearly_above(a: Ray) -> bool {
        a.v.z > 0.0 && Self::off_horizon(a)
    }

    /// Adds the edge `a -> b` (vectors of any positive length); `None` when `a` lies on the
    /// horizon (or is zero or not finite), where the exact path must decide.
    #[inline(always)]
    fn add_edge(&mut self, ra: Ray, rb: Ray, edge: impl EdgeTerm) -> Option<()> {
        let (a, b) = (ra.v, rb.v);
        if !Self::off_horizon(ra) {
            return None;
        }
        self.edges += 1;
        match (a.z > 0.0, b.z > 0.0) {
            (true, true) => self.add_above(ra, rb, edge),
            (false, false) => self.any_below = true,
            (up_a, _) => {
                self.any_below = true;
                self.cross(ra, rb, up_a, edge);
            }
        }
        Some(())
    }

    /// Adds the term of the edge `a -> b` that lies wholly above the horizon (the caller counts
    /// the edge).
    #[inline(always)]
    fn add_above(&mut self, ra: Ray, rb: Ray, edge: impl EdgeTerm) {
        let t = edge.term(ra, rb);
        self.sum += t;
        self.magnitude += t.abs();
    }

    /// Adds the terms of the edges `a[k] -> b[k]`, both wholly above the horizon (the caller
    /// counts the edges).
    #[inline(always)]
    fn add_above_pair(&mut self, a: [Ray; 2], b: [Ray; 2], edge: impl EdgeTerm) {
        let [t0, t1] = edge.term_pair(a, b);
        self.sum += t0 + t1;
        self.magnitude += t0.abs() + t1.abs();
    }

    /// Adds the edge `a -> b` that crosses the horizon (`a` above it when `up_a`, else `b`): the
    /// part above and the crossing's factor of the product (thesis 003 eq. 4.6 and 4.7).
    #[inline(always)]
    fn cross(&mut self, ra: Ray, rb: Ray, up_a: bool, edge: impl EdgeTerm) {
        let x = if up_a {
            crossing_point(ra, rb)
        } else {
            crossing_point(rb, ra)
        };
        let (pr, pi) = (x.v.x, if up_a { -x.v.y } else { x.v.y });
        // The first factor starts the product (a multiplication by 1 would only lengthen the
        // chain of dependent operations up to the horizon's term). Only the argument matters,
        // so the product so far is brought within 1e±90 ([`in_range`]) before each further one.
        // The factors lie within about 2^-240 to 2^64 (images within 2^±92, see
        // `CLIP_FREE_RANGE`, vertices off the horizon by `HORIZON_TOLERANCE`, edges shorter than
        // half a circle), so no product leaves the range of f64.
        (self.re, self.im) = if self.crossings == 0 {
            (pr, pi)
        } else {
            let (re, im) = in_range(self.re, self.im);
            (re * pr - im * pi, re * pi + im * pr)
        };
        self.crossings += 1;
        // One call site, so that the edge term is inlined.
        let (p, q) = if up_a { (ra, x) } else { (x, rb) };
        self.sum += edge.term(p, q);
    }

    /// The total angle of the horizon arcs, the argument of the crossings' product, given at
    /// least one crossing; `None` where rounding decides between almost none and almost all of
    /// the circle ([`arcs_undecided`]).
    #[inline(always)]
    fn horizon_arcs(&self, edge: impl EdgeTerm) -> Option<f64> {
        // The rational argument is a ratio of polynomials of degree 3 in the product's size:
        // brought within 1e±90 first, as before each factor, so that they neither underflow nor
        // overflow.
        let (re, im) = in_range(self.re, self.im);
        if arcs_undecided(re, im, self.crossings) {
            return None;
        }
        Some(counter_clockwise_arc(re, im, || edge.arg(re, im)))
    }

    /// The integral, or `None` when no edge crosses the horizon but some vertex is below it
    /// (the pairing of the horizon arcs is then unknown here).
    #[inline(always)]
    fn finish(self, edge: impl EdgeTerm) -> Option<f64> {
        let horizon = if self.crossings > 0 {
            // The argument of the product in [0, 2 pi), through the edge term of the horizon arc
            // from the x-axis to the product: `theta * sign(im)` (an `atan2` for the exact term,
            // the rational factor for the rational one, with the same relative error bound as
            // its edges). Exactly on the negative axis the arc is a half circle, which an edge
            // term cannot tell from a zero-length one.
            self.horizon_arcs(edge)?
        } else if self.edges == 0 {
            0.0
        } else if !self.any_below {
            Self::horizon_if_all_above(self.sum, self.magnitude, self.edges)?
        } else {
            return None;
        };
        Some(integral_of_sum(self.sum + horizon))
    }
}

/// `(re, im)` scaled by powers of ten until the sum of their magnitudes lies within `1e±90`,
/// where the products and the rational argument of [`ClipFree`]'s crossings stay far from
/// underflow and overflow. Only their argument matters. The common case, already in range, is a
/// predicted branch with no select on the way to the horizon's term.
#[inline(always)]
fn in_range(re: f64, im: f64) -> (f64, f64) {
    let size = re.abs() + im.abs();
    if (1e-90..=1e90).contains(&size) {
        (re, im)
    } else {
        rescale_product(re, im, size)
    }
}

/// Whether the crossings' product `re + i im` (of `crossings` factors) lies within its rounding
/// of the positive real axis, where the horizon arcs total either almost nothing or almost a
/// full turn and the sign of `im` is noise: crossing points closer than rounding can resolve,
/// as the two crossings next to a vertex a little below the horizon between two edges of a
/// sliver (a vertex `1e-14` below the horizon in a wedge of 0.005 rad puts them `5e-17` apart).
/// Each crossing point's direction is good to a few ulps; the margin allows 64 per factor.
/// The exact path decides these.
#[inline(always)]
fn arcs_undecided(re: f64, im: f64, crossings: usize) -> bool {
    const ARC_MARGIN: f64 = 64.0 * f64::EPSILON;
    re > 0.0 && im.abs() <= ARC_MARGIN * crossings as f64 * re
}

/// The arc from the x-axis counter-clockwise to `re + i im` (not both zero), in `[0, 2 pi)`:
/// `short()`, its signed angle in `[-pi, pi]`, wrapped by a turn when negative (no `rem_euclid`,
/// which would be a call to `fmod`); on the real axis, where an edge term cannot tell a half
/// turn from none, decided by the sign of `re` without calling `short`.
#[inline(always)]
fn counter_clockwise_arc(re: f64, im: f64, short: impl FnOnce() -> f64) -> f64 {
    if im == 0.0 {
        if re < 0.0 { PI } else { 0.0 }
    } else if im < 0.0 {
        short() + 2.0 * PI
    } else {
        short()
    }
}

/// [`in_range`] out of range: out of line, so that the common case stays small.
#[cold]
#[inline(never)]
fn rescale_product(mut re: f64, mut im: f64, mut size: f64) -> (f64, f64) {
    // Bounded by the finite range of f64 (an infinite or NaN size is left alone).
    while size > 1e90 && size < f64::INFINITY {
        (re, im, size) = (re * 1e-60, im * 1e-60, size * 1e-60);
    }
    while size < 1e-90 && size > 0.0 {
        (re, im, size) = (re * 1e60, im * 1e60, size * 1e60);
    }
    (re, im)
}

/// The crossing point of the edge between `above` (above the horizon) and `below` (below it), in
/// either direction: a positive combination of the two on the horizon (thesis 003 eq. 4.6), of
/// any positive length.
#[inline(always)]
fn crossing_point(above: Ray, below: Ray) -> Ray {
    let (a, b) = (above.v, below.v);
    let x = b * a.z - a * b.z;
    Ray::new(DVec3::new(x.x, x.y, 0.0))
}

/// [`single_ring_sum`] for a quad, the most common light, without loops and without the running
/// product of crossings: the vertices are classified at once, and when one run of them lies
/// above the horizon (two crossings, the common case for a light cut by the horizon), the
/// clipped quad's edges and its horizon arc, from the exit point to the entry point, are
/// evaluated as two pairs of terms ([`EdgeTerm::term_pair`]). Four crossings take the general
/// loop; a vertex on the horizon, or every vertex below it, the exact path, as there.
#[inline(always)]
fn quad_sum(quad: &[DVec3], map: impl Fn(DVec3) -> DVec3, edge: impl EdgeTerm) -> Option<f64> {
    let (p0, p1, p2, p3) = (quad[0], quad[1], quad[2], quad[3]);
    let v = [
        Ray::new(map(p0)),
        Ray::new(map(p1)),
        Ray::new(map(p2)),
        Ray::new(map(p3)),
    ];
    let off = ClipFree::off_horizon;
    if !(off(v[0]) & off(v[1]) & off(v[2]) & off(v[3])) {
        return None;
    }
    // Bit k: vertex k above the horizon.
    let bit = |k: usize| usize::from(v[k].v.z > 0.0) << k;
    let up = bit(0) | bit(1) | bit(2) | bit(3);
    if up == 0b1111 {
        // Every edge above the horizon: the paired loop's two steps.
        let mut acc = ClipFree::new();
        acc.edges = 4;
        acc.add_above_pair([v[0], v[1]], [v[1], v[2]], edge);
        acc.add_above_pair([v[2], v[3]], [v[3], v[0]], edge);
        return acc.finish(edge);
    }
    if up == 0 {
        // Wholly below: the exact path decides whether the region surrounds the upper hemisphere.
        return None;
    }
    // By mask, the first vertex of the run above the horizon (its predecessor is below) and the
    // run's length; length 0 where there is no single run. (A table rather than `count_ones`,
    // which baseline x86-64 has no instruction for.)
    const RUNS: [(usize, u8); 16] = [
        (0, 0),
        (0, 1),
        (1, 1),
        (0, 2),
        (2, 1),
        (0, 0),
        (1, 2),
        (0, 3),
        (3, 1),
        (3, 2),
        (0, 0),
        (3, 3),
        (2, 2),
        (2, 3),
        (1, 3),
        (0, 0),
    ];
    let (first, run) = RUNS[up];
    if run == 0 {
        return single_ring_sum(quad, map, edge);
    }
    // The images in the run's order, by a match rather than by a computed index: indexing the
    // array puts it through memory, and reloading parts of its stores stalls store-to-load
    // forwarding, enough to make the kernel slower than the general loop.
    let [a0, a1, a2, a3] = match first {
        0 => [v[0], v[1], v[2], v[3]],
        1 => [v[1], v[2], v[3], v[0]],
        2 => [v[2], v[3], v[0], v[1]],
        _ => [v[3], v[0], v[1], v[2]],
    };
    let x_in = crossing_point(a0, a3);
    let x_out = match run {
        1 => crossing_point(a0, a1),
        2 => crossing_point(a1, a2),
        _ => crossing_point(a2, a3),
    };
    // The horizon arc's term on the crossing points' own scale: a product of two of them, which
    // must stay far from underflow in the edge term (extreme maps and near-horizon vertices).
    if !(x_in.len2 * x_out.len2 >= 1e-180) {
        return single_ring_sum(quad, map, edge);
    }
    // The clipped quad: x_in -> a0 -> ... -> a[run - 1] -> x_out, then the horizon arc.
    let (t, arc) = match run {
        1 => {
            let [t0, t1] = edge.term_pair([x_in, a0], [a0, x_out]);
            (t0 + t1, edge.term(x_out, x_in))
        }
        2 => {
            let [t0, t1] = edge.term_pair([x_in, a0], [a0, a1]);
            let [t2, arc] = edge.term_pair([a1, x_out], [x_out, x_in]);
            (t0 + t1 + t2, arc)
        }
        _ => {
            let [t0, t1] = edge.term_pair([x_in, a0], [a0, a1]);
            let [t2, t3] = edge.term_pair([a1, a2], [a2, x_out]);
            (t0 + t1 + t2 + t3, edge.term(x_out, x_in))
        }
    };
    // The arc runs counter-clockwise from the exit to the entry point; `conj(x_out) x_in` is
    // the crossings' product of the general loop.
    let (xo, xi) = (x_out.v, x_in.v);
    let (re, im) = (xo.x * xi.x + xo.y * xi.y, xo.x * xi.y - xo.y * xi.x);
    if arcs_undecided(re, im, 2) {
        return None;
    }
    Some(integral_of_sum(t + counter_clockwise_arc(re, im, || arc)))
}

/// [`ring_sum`] for a single ring, with the edges between vertices clearly above the horizon (all
/// of them for most lights) taken two at a time ([`EdgeTerm::term_pair`]) and without the horizon
/// tests of [`ClipFree::add_edge`]; from the first pair with a vertex that is not, that takes
/// over. Each image is computed once and nothing is buffered.
#[inline(always)]
fn single_ring_sum(
    ring: &[DVec3],
    map: impl Fn(DVec3) -> DVec3,
    edge: impl EdgeTerm,
) -> Option<f64> {
    let (&first, rest) = ring.split_first()?;
    let first = Ray::new(map(first));
    let mut acc = ClipFree::new();
    let mut prev = first;
    let mut rest = rest.iter();
    if ClipFree::clearly_above(first) {
        // Two edges per step, `prev -> c1 -> c2`, with `c2` the first vertex again at the end of
        // the ring, so that their terms can be evaluated side by side.
        loop {
            let Some(&v1) = rest.next() else {
                acc.edges += 1;
                acc.add_above(prev, first, edge);
                return acc.finish(edge);
            };
            let c1 = Ray::new(map(v1));
            let (c2, closing) = match rest.next() {
                Some(&v2) => (Ray::new(map(v2)), false),
                None => (first, true),
            };
            let above = ClipFree::clearly_above(c1) && ClipFree::clearly_above(c2);
            if above {
                acc.edges += 2;
                acc.add_above_pair([prev, c1], [c1, c2], edge);
            } else {
                acc.add_edge(prev, c1, edge)?;
                acc.add_edge(c1, c2, edge)?;
            }
            if closing {
                return acc.finish(edge);
            }
            prev = c2;
            if !above {
                break;
            }
        }
    }
    for &v in rest {
        let cur = Ray::new(map(v));
        acc.add_edge(prev, cur, edge)?;
        prev = cur;
    }
    acc.add_edge(prev, first, edge)?;
    acc.finish(edge)
}

/// The integral from Baum's edge sum including the horizon's part: `sum / 2 pi`, clamped to the
/// integral's range against rounding.
#[inline(always)]
fn integral_of_sum(sum: f64) -> f64 {
    const INV_2PI: f64 = 0.5 * core::f64::consts::FRAC_1_PI;
    (sum * INV_2PI).clamp(0.0, 1.0)
}

/// Runs the clip-free sum on the images of the polygon's vertices under `m`; `None` when the
/// exact path is needed.
///
/// The matrix is read entry by entry: a caller's freshly stored matrix read back with wide loads
/// at other offsets stalls store-to-load forwarding, which cost more than the rest of a quad.
#[inline(always)]
fn transformed_clip_free<P: ClipFreeInput + ?Sized>(
    poly: &P,
    m: &glam::DMat3,
    edge: impl EdgeTerm,
) -> Option<f64> {
    let (x, y, z) = (&m.x_axis, &m.y_axis, &m.z_axis);
    if y.x == 0.0 && y.z == 0.0 && x.y == 0.0 && z.y == 0.0 {
        // The form of the fitted tables' matrices (HDHN16 §4.1): `y` only scaled, so five
        // products per vertex instead of nine; the images are the same.
        let (m00, m02, m20, m22, m11) = (x.x, z.x, x.z, z.z, y.y);
        let small = |e: f64| e.abs() <= CLIP_FREE_RANGE;
        let in_range = small(m00) & small(m02) & small(m20) & small(m22) & small(m11);
        let regular =
            m00 * m22 - m02 * m20 >= 1.0 / CLIP_FREE_RANGE && m11 >= 1.0 / CLIP_FREE_RANGE;
        if !(regular && in_range) {
            // Far from the tables' matrices (or NaN): let the general path rescale it.
            return general_clip_free(poly, m, edge);
        }
        let map = |v: DVec3| DVec3::new(m00 * v.x + m02 * v.z, m11 * v.y, m20 * v.x + m22 * v.z);
        poly.clip_free(map, edge)
    } else {
        general_clip_free(poly, m, edge)
    }
}

/// Bound on the entries (at most this) and the determinant (at least its inverse) of the maps the
/// clip-free path takes (for the tables' form, on the xz block's determinant and on the `y`
/// scale separately, which keeps its images' lengths within `2^±61`): the images of unit vectors
/// then have lengths within about `2^±92`, so
/// the crossing points (products of two images) and the edge terms' products of squared lengths
/// stay far from overflow and underflow. The fitted tables' matrices lie well inside (entries up
/// to about `1 / alpha_min = 1e4`).
const CLIP_FREE_RANGE: f64 = 1_073_741_824.0; // 2^30

/// [`transformed_clip_free`] for a matrix of any form, out of line so that the common form's
/// path reads no more of the matrix than it uses.
#[inline(never)]
fn general_clip_free<P: ClipFreeInput + ?Sized>(
    poly: &P,
    m: &glam::DMat3,
    edge: impl EdgeTerm,
) -> Option<f64> {
    // Every quantity of the sum is invariant under positive scaling of the map, so it is scaled
    // to entries of at most 1; then a determinant of at least `1 / CLIP_FREE_RANGE` bounds the
    // images' lengths away from zero too. Worse conditioned maps go to the exact path, which
    // normalizes every image.
    let m = crate::math::unit_scaled(*m)?;
    if !(m.determinant() >= 1.0 / CLIP_FREE_RANGE) {
        return None;
    }
    poly.clip_free(|v| m * v, edge)
}

#[cfg(test)]
mod tests {
    use super::*;
    use alloc::vec;

    #[test]
    fn edge_term_is_stable_for_tiny_and_long_edges() {
        let a = DVec3::new(1.0, 0.0, 0.0);
        let b = DVec3::new(1.0, 1e-9, 0.0).normalize();
        // theta * (a x b)_z / |a x b| -> theta for an edge on the horizon going counter-clockwise.
        assert!((edge_term(Ray::new(a), Ray::new(b)) - 1e-9).abs() < 1e-24);
        let c = DVec3::new(-1.0, 1e-9, 0.0).normalize();
        assert!((edge_term(Ray::new(a), Ray::new(c)) - (PI - 1e-9)).abs() < 1e-15);
    }

    /// Short images: at `2^-61`, the shortest image of a unit vector under the maps of the tables'
    /// form that the clip-free path takes (entries at most `CLIP_FREE_RANGE`, determinant at
    /// least its inverse), the quad kernel's own arc term holds; at `2^-92` (the bound quoted at
    /// `CLIP_FREE_RANGE` for maps of any form) and `2^-100` that term (on the scale of a product
    /// of two crossing points) would underflow, and the kernel hands over to the general loop,
    /// which rescales its running product (at `2^-92` it returned NaN before its final rescale).
    #[test]
    fn quad_kernel_hands_over_where_its_arc_term_would_underflow() {
        let quad = [
            DVec3::new(1.0, -0.4, -0.3),
            DVec3::new(1.0, 0.4, -0.3),
            DVec3::new(0.6, 0.4, 0.7),
            DVec3::new(0.6, -0.4, 0.7),
        ]
        .map(DVec3::normalize);
        let scales = [2f64.powi(-61), 2f64.powi(-92), 2f64.powi(-100)];
        for (k, scale) in (0..4).flat_map(|k| scales.map(|s| (k, s))) {
            let mut q = quad;
            q.rotate_left(k);
            let unit = quad_sum(&q, |v| v, Rational).unwrap();
            let short = quad_sum(&q, |v| v * scale, Rational).unwrap();
            assert!((unit - short).abs() <= 1e-15, "{scale}: {unit} vs {short}");
            let unit = quad_sum(&q, |v| v, Exact).unwrap();
            let short = quad_sum(&q, |v| v * scale, Exact).unwrap();
            assert!((unit - short).abs() <= 1e-15, "{scale}: {unit} vs {short}");
        }
    }

    #[test]
    fn full_sphere_and_empty() {
        assert_eq!(clamped_cosine_integral(&SphericalPolygon::full()), 1.0);
        assert_eq!(
            clamped_cosine_integral_clip_free(&SphericalPolygon::full()),
            1.0
        );
        assert_eq!(clamped_cosine_integral(&SphericalPolygon::empty()), 0.0);
        assert_eq!(
            clamped_cosine_integral_clip_free(&SphericalPolygon::empty()),
            0.0
        );
        let down =
            SphericalPolygon::new(vec![vec![DVec3::X, -DVec3::Y, -DVec3::X, DVec3::Y]]).unwrap();
        assert_eq!(clamped_cosine_integral(&down), 0.0);
    }
}
