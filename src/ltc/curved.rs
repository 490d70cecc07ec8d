//! Clamped-cosine and LTC integrals over planar regions bounded by cubic Bezier curves and line
//! segments (seed 004): the boundary is discretized per shading point by radiance-aware adaptive
//! subdivision (section 2.3) and clipped at the horizon algebraically (section 2.4).
//!
//! The input is plain control points in the shading frame ([`CurveSegment`]), so this layer
//! knows no shape type: `solid::BezierShape` (or any caller) supplies them.
//!
//! # How the integral is formed
//!
//! Baum's boundary sum (HDHN16 eq. 11) holds for any closed boundary on the sphere: the integral
//! of `max(0, z) / pi` over a region in the upper hemisphere is `1 / 2 pi` times the sum over
//! its boundary of `theta (a x b)_z / |a x b|` for chords, or of `(p x p')_z / |p|^2 dt` along a
//! curve. Here the curves are replaced by chains of chords chosen per point:
//!
//! 1. **Clip** (004 section 2.4). Each segment's height `z(t)` is a cubic (or linear) polynomial
//!    in its parameter. Its sign changes in `[0, 1]` are found robustly ([`sign_changes`]): the
//!    real critical points split the parameter range into monotone pieces (the derivative is a
//!    quadratic, solved with the cancellation-free formula, its degree chosen by a scale-relative
//!    test), and each piece whose ends differ in sign holds exactly one crossing, found by Newton
//!    steps kept inside the bracket. Signs are decided only by evaluated heights, with shared
//!    endpoints evaluated once, so crossings alternate between exits and entries along every
//!    loop whatever the rounding; a near-double root becomes two crossings close together or
//!    none (a tangency), both right to rounding. No cube roots and no degree decision on the
//!    cubic itself are needed, which is what makes the seed's published solver fragile (an
//!    exact `a != 0` test, `pow(x, 0.3333)` cube roots).
//! 2. **Close along the horizon.** The parts above the horizon are kept; between an exit point
//!    and the next entry point counter-clockwise the clipped region's boundary runs along the
//!    horizon. A planar region seen from a point off its plane lies in an open hemisphere, so
//!    all crossings lie within half a circle, and exits and entries may be paired in any order
//!    (see [`Stage::arcs`]); each arc is a chord of the sum (a horizon arc is a great-circle
//!    arc), so no explicit horizon edges are built.
//! 3. **Subdivide** (004 section 2.3). Each kept part of a cubic starts as `N_div = 4` intervals
//!    of its parameter range; an interval `[t0, t1]` is split at its midpoint while the signed
//!    integral of the triangle `B(t0), B(tm), B(t1)` (its two half chords minus the chord,
//!    [`edge_term`]) exceeds `eps` in magnitude; otherwise its two half chords enter the sum.
//!    The chord's term is carried down from the parent, so each step evaluates two edge terms,
//!    and the sum is accumulated on the way (no re-evaluation). A depth cap bounds the work.
//!    One addition to the seed: an interval whose directions may spread over more than `pi / 4`
//!    (by the cone of its sub-curve's control points) is split whatever its triangle
//!    ([`wide`]), without which the test misses narrow lobes.
//!
//! For the GGX lobe ([`ggx_curved_integral`]) the region is clipped at the shading horizon
//! first (the tables' LTCs are fitted as clipped there, as in [`super::ggx_polygon_integral`]),
//! then the kept parts and the horizon arcs are mapped by `M^-1` (a Bezier curve's image under a
//! linear map has the images of its control points as control points, 004 section 2.2; a great
//! arc's image is the great arc between the images), and the result is clipped again, at the
//! cosine space's horizon.
//!
//! # Accuracy: the error bound
//!
//! With [`Subdivision::AdaptiveWithBound`], [`CurvedIntegral::error_bound`] is a proven bound
//! on what the adaptive subdivision of seed 004 section 2.3 neglects (rounding aside, which
//! ill-conditioned views amplify: see the field's documentation). The seed's test on an
//! interval's triangle decides where to split, as in the seed and as with
//! [`Subdivision::Adaptive`], whose value is the same bit for bit; the bound is computed beside
//! it, from the accepted intervals:
//!
//! 1. **What is neglected.** Where an interval `[t0, t1]` is accepted, the polygon keeps its
//!    midpoint, and each half `[t0, tm]`, `[tm, t1]` of the curve is replaced by its chord.
//!    Baum's sum is additive over closed paths, so the sum's error is the sum, over the accepted
//!    halves, of the integral over the path "sub-curve forward, chord back": by Stokes, the
//!    integral of `w max(0, z) / pi` over the directions, with `w` the winding number of the
//!    path about a direction (the radial projection maps the light's plane one to one onto an
//!    open hemisphere, so winding numbers are those of the planar path about points of the
//!    plane). In the Lambert stage the kept pieces and their chords lie above the horizon, so
//!    the integrand there is the clamped cosine; in the GGX stage the same holds in the cosine
//!    space, where the pieces are subdivided (the shading-horizon clip before the map is
//!    algebraic and neglects nothing).
//! 2. **`|w| <= 1`.** A line meets a planar cubic in at most three points (the roots of a
//!    cubic polynomial in `t`, whatever the parametrization), unless it holds the curve, which
//!    then encloses nothing. For a point off the chord's line, the lines through it parallel or
//!    nearly parallel to the chord miss the chord, so they meet the path at most three times;
//!    but each of the two rays of such a line from the point crosses the path at least `|w|`
//!    times (its signed crossings add up to `w`). So `|w| <= 1` almost everywhere, and the
//!    magnitude of a half's error is at most the integral of `max(0, z) / pi` over the
//!    directions where `w != 0`.
//! 3. **The hull.** Those lie in the convex hull of the path, and the path lies in the convex
//!    hull of the half's control points (de Casteljau's points of the sub-curve, which hold the
//!    curve, and the chord between two of them). The integrand being non-negative, each
//!    half's error is at most its integral over that hull (a triangle or quadrilateral in the
//!    plane; below the horizon it contributes nothing, so no clip is needed), which
//!    [`sliver_bound`] bounds from above in closed form: the hull's solid angle (half the sum
//!    of the four triangles' of its points) times the largest cosine in it.
//! 4. **The rest is exact.** Lines and horizon arcs are chords of the sum themselves; the
//!    clamps of the result to `[0, 1]` and to the LTC's albedo move it by no more than they
//!    move the exact value. An interval accepted at the depth cap is bounded like any other.
//!
//! The bound is not a function of `eps` alone: it is what the accepted intervals certify. For a
//! curve that is locally a parabola, a half's hull is `8/9` of the triangle of its chord and
//! end tangents, and its sliver `2/3` of it, so the bound is about `4/3` of the magnitude of the
//! error where slivers do not cancel; each half's tangent triangle is `1/8` of the interval's,
//! whose inscribed triangle is half of it, so the bound is about `(4/9) |L_triangle|` per
//! accepted interval (at most `4 eps / 9` there, times the cosine factor). Where slivers of
//! both signs cancel, or the hull reaches over the horizon, the error is further below it.
//! The parametrization does not matter (a cubic whose handles sit on an end point moves
//! arbitrarily slowly there): the hulls hold whatever the halves cover. BENCHMARKS.md
//! ("Bezier lights") reports the error and the bound against `eps` on the tests' curves.
//!
//! # References
//!
//! - Seed 004: T. Kuge, T. Yatagawa, S. Morishima. *Real-time shading with free-form planar area
//!   lights using linearly transformed cosines.* JCGT 11(1), 2022: sections 2.2-2.4, Listings 1
//!   and 2, figure 8 (uniform subdivision with N = 6, 18, 30 as the baseline).
//! - \[HDHN16\] E. Heitz, J. Dupuy, S. Hill, D. Neubelt. *Real-time polygonal-light shading with
//!   linearly transformed cosines.* ACM TOG 35(4), 2016.
//! - J. F. Blinn. *How to solve a cubic equation, part 5: back to numerics.* IEEE CG&A 27(3),
//!   2007 (the seed's choice for the horizon roots; the bracketing here is an equally robust
//!   alternative that needs no case analysis of the cubic).

use core::f64::consts::PI;

use glam::{DMat3, DVec3};
use smallvec::SmallVec;

use super::integrate::{Ray, edge_term};
use crate::GeomError;

/// One segment of a boundary loop, by its control points in the shading frame (directions are
/// taken from the shading point, at the origin): a straight segment or a cubic Bezier curve
/// `B(t) = (1-t)^3 p0 + 3 (1-t)^2 t p1 + 3 (1-t) t^2 p2 + t^3 p3`.
///
/// More segment kinds (quadratic or rational curves) may be added, hence `#[non_exhaustive]`.
#[derive(Debug, Clone, Copy, PartialEq)]
#[non_exhaustive]
pub enum CurveSegment {
    /// The straight segment from the first point to the second.
    Line([DVec3; 2]),
    /// The cubic Bezier curve with these four control points.
    Cubic([DVec3; 4]),
}

impl CurveSegment {
    /// The first point.
    #[must_use]
    pub fn start(&self) -> DVec3 {
        match self {
            CurveSegment::Line(p) => p[0],
            CurveSegment::Cubic(p) => p[0],
        }
    }

    /// The last point.
    #[must_use]
    pub fn end(&self) -> DVec3 {
        match self {
            CurveSegment::Line(p) => p[1],
            CurveSegment::Cubic(p) => p[3],
        }
    }

    /// The control points (two for a line).
    #[must_use]
    pub fn control_points(&self) -> &[DVec3] {
        match self {
            CurveSegment::Line(p) => p,
            CurveSegment::Cubic(p) => p,
        }
    }

    /// The point at parameter `t` in `[0, 1]`.
    #[must_use]
    pub fn point(&self, t: f64) -> DVec3 {
        match self {
            CurveSegment::Line([a, b]) => a.lerp(*b, t),
            CurveSegment::Cubic(p) => bezier(p, t),
        }
    }

    /// The same segment run backwards.
    #[must_use]
    pub fn reversed(&self) -> Self {
        match *self {
            CurveSegment::Line([a, b]) => CurveSegment::Line([b, a]),
            CurveSegment::Cubic([a, b, c, d]) => CurveSegment::Cubic([d, c, b, a]),
        }
    }

    /// The image of the segment under the linear map `m`: the images of its control points
    /// (affine invariance of Bezier curves, seed 004 section 2.2).
    #[must_use]
    pub fn transformed(&self, m: DMat3) -> Self {
        match *self {
            CurveSegment::Line(p) => CurveSegment::Line(p.map(|v| m * v)),
            CurveSegment::Cubic(p) => CurveSegment::Cubic(p.map(|v| m * v)),
        }
    }
}

/// How the curves are turned into chords. More strategies may be added (`#[non_exhaustive]`).
///
/// Which to choose: adaptive subdivision cannot be coarser than `2 INITIAL_INTERVALS` chords
/// per cubic (each initial interval is accepted with its midpoint), and an adaptive chord costs
/// more than a uniform one (its split test needs a curve point and the chord it replaces). So
/// at errors of about `2e-3` and above (below about 20 edges per point on a small glyph)
/// [`Subdivision::Uniform`] reaches the same accuracy as fast or faster; adaptive pays from
/// about `1e-3` down, 1.3 to 2 times faster at equal maximum error against seed 004's `N = 18`
/// and `30` (BENCHMARKS.md, "Bezier lights").
#[derive(Debug, Clone, Copy, PartialEq)]
#[non_exhaustive]
pub enum Subdivision {
    /// Radiance-aware adaptive subdivision (seed 004 section 2.3): [`INITIAL_INTERVALS`]
    /// intervals per kept part of a curve, each split at its parameter midpoint while the signed
    /// integral of its triangle exceeds `eps` (in units of the result before any BRDF scale), at
    /// most [`MAX_DEPTH`] times. `eps` must be positive (infinity: no splitting).
    Adaptive {
        /// The threshold on a triangle's signed integral.
        eps: f64,
    },
    /// [`Subdivision::Adaptive`] with a proven bound on its error
    /// ([`CurvedIntegral::error_bound`]): the same intervals, so the same `value`, bit for
    /// bit, and per accepted interval a closed-form bound on what its chords leave out (see
    /// the module documentation, "Accuracy"). The bound makes the integral take about 1.5
    /// times as long at the seed's thresholds (BENCHMARKS.md, "Bezier lights"), which is why it
    /// is asked for separately.
    AdaptiveWithBound {
        /// The threshold on a triangle's signed integral.
        eps: f64,
    },
    /// The baseline of seed 004 section 3.3: every cubic replaced by `n` chords between
    /// uniformly spaced parameters, then clipped like a polygon. `n` from 1 to
    /// [`MAX_UNIFORM`].
    Uniform {
        /// Chords per cubic segment.
        n: usize,
    },
}

/// `N_div` of seed 004 section 2.3: the initial intervals of each kept part of a curve, enough
/// for the inflections of a cubic.
pub const INITIAL_INTERVALS: usize = 4;

/// How many times an initial interval may be halved (so at most `4 * 2^MAX_DEPTH` chords per
/// part of a curve). Below it the adaptive sum converges to the exact integral like
/// `eps^(2/3)`; at it, an interval is accepted whatever its triangle (and its slivers are
/// counted in [`CurvedIntegral::error_bound`] like any other).
pub const MAX_DEPTH: u32 = 24;

/// Largest `n` of [`Subdivision::Uniform`].
pub const MAX_UNIFORM: usize = 1 << 20;

/// The threshold of seed 004 section 2.3 for the specular lobe, `eps_s = 0.1 alpha^2`: narrow
/// lobes (small `alpha`) need a fine boundary, wide ones do not.
#[must_use]
pub fn specular_eps(alpha: f64) -> f64 {
    0.1 * alpha * alpha
}

/// A threshold for the diffuse lobe. Seed 004 uses a "sufficiently large" `eps_d` (1000: no
/// splitting beyond the initial intervals), which leaves errors of a few percent on round
/// shapes seen from nearby; this crate's default keeps them near `1e-3` of the result (see
/// BENCHMARKS.md, "Bezier lights").
pub const DIFFUSE_EPS: f64 = 1e-4;

/// The result of a curved integral.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CurvedIntegral {
    /// The integral.
    pub value: f64,
    /// Number of chords summed (the edges of the polygon the curves were replaced by, horizon
    /// arcs included): the cost measure of seed 004 figure 5.
    pub edges: usize,
    /// For [`Subdivision::AdaptiveWithBound`]: a proven bound on `|value - exact|`, the exact value
    /// being the same integral over the region bounded by the exact curves (scaled like
    /// `value`). It is the sum, over the accepted intervals, of bounds on the integrals over
    /// the convex hulls of their halves' control points, which hold the slivers the chords
    /// leave out (see the module documentation, "Accuracy"). It bounds what the subdivision
    /// neglects, not rounding: the sums and the points they are taken at (curve points,
    /// horizon crossings) are rounded, which costs a few units in the last place per edge
    /// where the integral is well-conditioned and more where it is not (a near-mirror lobe at
    /// a grazing view whose peak sits on the light's horizon crossing: moving a light 800
    /// across by `1e-14` moved its response by `3e-9`). `None` for the other subdivisions.
    pub error_bound: Option<f64>,
}

/// Relative tolerance of the coplanarity check of the control points (of the region's extent):
/// the shading frame's rotation and translation move points off a plane by a few ulps of
/// their coordinates, far less than this.
pub const CURVE_PLANE_TOLERANCE: f64 = 1e-9;

/// `(1/pi)` times the integral of `max(0, z)` over the planar region bounded by `segments`:
/// the irradiance from a uniform unit-radiance light filling it, as
/// [`super::clamped_cosine_integral`] for polygons, clipped at the horizon and with the curves
/// subdivided as `subdivision` says (see the module documentation).
///
/// `segments` are closed loops given one after another: each segment starts where the previous
/// one ended, except the first of a loop, which follows a segment that ends where its own loop
/// started (the points must be bit-identical, as when both come from one computation). The
/// region lies on the left of its boundary seen from outside the sphere (the convention of
/// [`crate::sphere::SphericalPolygon`]): outer loops counter-clockwise and holes clockwise seen
/// from outside, that is clockwise and counter-clockwise as seen from the shading point. The
/// other orientation gives 0.
/// All control points must lie in one plane (to [`CURVE_PLANE_TOLERANCE`] of their extent);
/// a plane within that of the shading point shows the region edge-on and gives 0, and so do
/// control points on one line (to `1e-12` of the extent squared).
///
/// # Errors
///
/// [`GeomError::InvalidCurve`] naming the loop and the segment for a non-finite control point,
/// a segment that ends neither where the next one starts nor where its loop started (a gap,
/// or a loop that does not close), or a control point off the plane; [`GeomError::OutOfRange`] for
/// an `eps` that is not positive or an `n` outside `1..=MAX_UNIFORM`.
///
/// # Examples
///
/// ```
/// use arealight::glam::DVec3;
/// use arealight::ltc::{CurveSegment, Subdivision, curved_clamped_cosine_integral};
/// // A disk of radius 1 at height 1 above the point: four cubics, counter-clockwise seen from
/// // above (outside the sphere), clockwise as seen from the point below.
/// let k = 0.5522847498307936; // the usual circle approximation
/// let q = std::f64::consts::FRAC_PI_2;
/// let at = |i: usize| DVec3::new((i as f64 * q).cos(), (i as f64 * q).sin(), 1.0);
/// let tangent = |i: usize| DVec3::new(-(i as f64 * q).sin(), (i as f64 * q).cos(), 0.0);
/// // Segments share their end points exactly: the last one ends at `at(0)`.
/// let disk: Vec<_> = (0..4)
///     .map(|i| {
///         let (a, b) = (at(i), at((i + 1) % 4));
///         CurveSegment::Cubic([a, a + k * tangent(i), b - k * tangent(i + 1), b])
///     })
///     .collect();
/// let r = curved_clamped_cosine_integral(&disk, Subdivision::Adaptive { eps: 1e-9 })?;
/// // A disk of radius r at height h on the axis: r^2 / (r^2 + h^2) = 1/2.
/// assert!((r.value - 0.5).abs() < 1e-3);
/// # Ok::<(), arealight::GeomError>(())
/// ```
pub fn curved_clamped_cosine_integral(
    segments: &[CurveSegment],
    subdivision: Subdivision,
) -> Result<CurvedIntegral, GeomError> {
    check_subdivision(subdivision)?;
    if !check_region(segments)? {
        return Ok(nothing(subdivision));
    }
    let mut stage = Stage::default();
    stage.clip(segments.iter().map(Piece::whole), flattening(subdivision))?;
    Ok(stage.integrate(subdivision))
}

/// The integral of a linearly transformed cosine over the region bounded by `segments`: the
/// region's image under `m_inv` (its control points mapped, seed 004 section 2.2), clipped at
/// the cosine space's horizon, integrated as by [`curved_clamped_cosine_integral`]; the curve
/// counterpart of [`super::ltc_integral`]. `eps` of an adaptive subdivision applies in the
/// cosine space. Same input conventions.
///
/// # Errors
///
/// As [`curved_clamped_cosine_integral`]; [`GeomError::Degenerate`] for a singular or
/// non-finite `m_inv`.
pub fn curved_ltc_integral(
    segments: &[CurveSegment],
    m_inv: DMat3,
    subdivision: Subdivision,
) -> Result<CurvedIntegral, GeomError> {
    check_subdivision(subdivision)?;
    let m = map_for(m_inv)?;
    if !check_region(segments)? {
        return Ok(nothing(subdivision));
    }
    let mut stage = Stage::default();
    stage.clip(
        segments.iter().map(|s| Piece::whole(s).transformed(m)),
        flattening(subdivision),
    )?;
    Ok(stage.integrate(subdivision))
}

/// The GGX specular response to a uniform unit-radiance light filling the region bounded by
/// `segments`, the curve counterpart of [`super::ggx_polygon_integral`] (same arguments, same
/// steps): the LTC of the view angle and roughness, the region clipped at the shading horizon,
/// mapped by `M^-1`, clipped at the cosine space's horizon and integrated, times the lookup's
/// Fresnel-weighted norm. With `Subdivision::Adaptive { eps: specular_eps(alpha) }` this is the
/// method of seed 004. `value` and `error_bound` include the scale (the bound holds for the
/// response the LTC gives to the exact region: the table's own fitting error is not in it).
///
/// # Errors
///
/// As [`curved_clamped_cosine_integral`] and [`super::lookup`]; [`GeomError::OutOfRange`] for
/// a non-finite `f0`.
pub fn ggx_curved_integral(
    segments: &[CurveSegment],
    cos_theta_v: f64,
    alpha: f64,
    f0: f64,
    subdivision: Subdivision,
) -> Result<CurvedIntegral, GeomError> {
    if !f0.is_finite() {
        return Err(GeomError::OutOfRange {
            what: "Fresnel reflectance f0",
            value: f0,
            limit: 1.0,
        });
    }
    check_subdivision(subdivision)?;
    let l = super::lookup(cos_theta_v, alpha)?;
    let m = map_for(l.m_inv)?;
    if !check_region(segments)? {
        return Ok(nothing(subdivision));
    }
    // The uniform baseline's polygon is built before any clip, as in seed 004 section 3.3.
    let mut shading = Stage::default();
    shading.clip(segments.iter().map(Piece::whole), flattening(subdivision))?;
    let mut cosine = Stage::default();
    cosine.clip(shading.closed().map(|p| p.transformed(m)), None)?;
    let r = cosine.integrate(subdivision);
    let scale = l.specular_scale(f0.clamp(0.0, 1.0));
    // No part of the upper hemisphere holds more of the LTC than all of it (as for polygons).
    Ok(CurvedIntegral {
        value: scale * r.value.min(l.albedo / l.norm),
        edges: r.edges,
        error_bound: r.error_bound.map(|e| scale * e),
    })
}

/// The integral of a region seen edge-on (or of no area): zero, exactly.
fn nothing(subdivision: Subdivision) -> CurvedIntegral {
    CurvedIntegral {
        value: 0.0,
        edges: 0,
        error_bound: match subdivision {
            Subdivision::AdaptiveWithBound { .. } => Some(0.0),
            Subdivision::Adaptive { .. } | Subdivision::Uniform { .. } => None,
        },
    }
}

/// The chords per cubic of a uniform subdivision, applied before the first clip.
fn flattening(subdivision: Subdivision) -> Option<usize> {
    match subdivision {
        Subdivision::Uniform { n } => Some(n),
        Subdivision::Adaptive { .. } | Subdivision::AdaptiveWithBound { .. } => None,
    }
}

fn check_subdivision(s: Subdivision) -> Result<(), GeomError> {
    match s {
        Subdivision::Adaptive { eps } | Subdivision::AdaptiveWithBound { eps } if !(eps > 0.0) => {
            Err(GeomError::OutOfRange {
                what: "subdivision threshold eps (positive)",
                value: eps,
                limit: f64::INFINITY,
            })
        }
        Subdivision::Uniform { n } if n == 0 || n > MAX_UNIFORM => Err(GeomError::OutOfRange {
            what: "uniform subdivision chords per curve (1 ..= MAX_UNIFORM)",
            value: n as f64,
            limit: MAX_UNIFORM as f64,
        }),
        _ => Ok(()),
    }
}

/// `m` scaled to unit entries (the integrals see directions only), or an error for a map that
/// is singular or not finite.
fn map_for(m: DMat3) -> Result<DMat3, GeomError> {
    let m = crate::math::unit_scaled(m)
        .filter(|m| m.is_finite() && m.determinant().abs() > 1e-300)
        .ok_or(GeomError::Degenerate("singular or non-finite LTC matrix"))?;
    Ok(m)
}

/// Validates the loops (finite, closed, coplanar) and tells whether the region can be seen:
/// `false` when its plane passes within tolerance of the shading point (edge-on, integral 0) or
/// it encloses no area.
fn check_region(segments: &[CurveSegment]) -> Result<bool, GeomError> {
    // Loops, closure and finiteness; the vector area (1/2) integral of p x dp, exact for cubics
    // with three Gauss points (the integrand has degree 5); the extent.
    let mut ring = 0;
    let mut ring_start = 0;
    let mut area = DVec3::ZERO;
    let origin = segments.first().map_or(DVec3::ZERO, CurveSegment::start);
    let mut extent = 0.0f64;
    for (i, s) in segments.iter().enumerate() {
        let pts = s.control_points();
        for &p in pts {
            if !p.is_finite() {
                return Err(GeomError::InvalidCurve {
                    ring,
                    segment: i - ring_start,
                    why: "non-finite control point",
                });
            }
            extent = extent.max((p - origin).abs().max_element());
        }
        if i > ring_start && s.start() != segments[i - 1].end() {
            if segments[i - 1].end() == segments[ring_start].start() {
                ring += 1;
                ring_start = i;
            } else {
                // Loops are implicit in the list: a segment that ends neither where the next
                // one starts nor where its loop started is the one named.
                return Err(GeomError::InvalidCurve {
                    ring,
                    segment: i - 1 - ring_start,
                    why: "ends neither where the next segment starts nor where its loop started",
                });
            }
        }
        area += vector_area(s, origin);
    }
    if let Some(last) = segments.last()
        && last.end() != segments[ring_start].start()
    {
        return Err(GeomError::InvalidCurve {
            ring,
            segment: segments.len() - 1 - ring_start,
            why: "the loop does not close (its last segment ends away from its start)",
        });
    }
    // The plane's normal: the vector area's direction, or, where the area is within rounding of
    // zero (a loop crossing itself into lobes of opposite winding, whose integral need not be
    // zero), the normal through the points farthest apart; points on one line bound nothing.
    let a = area.length();
    if !a.is_finite() {
        return Ok(false);
    }
    let n = if a > 1e-12 * extent * extent {
        area / a
    } else {
        let pts = || {
            segments
                .iter()
                .flat_map(|s| s.control_points().iter().copied())
        };
        let far = |from: &dyn Fn(DVec3) -> f64| {
            pts().fold((0.0f64, origin), |m, p| {
                if from(p) > m.0 { (from(p), p) } else { m }
            })
        };
        let (_, p1) = far(&|p| (p - origin).length_squared());
        let axis = (p1 - origin).normalize_or_zero();
        let (_, p2) = far(&|p| (p - origin).reject_from_normalized(axis).length_squared());
        let c = (p1 - origin).cross(p2 - origin);
        if !(c.length() > 1e-12 * extent * extent) {
            return Ok(false);
        }
        c.normalize()
    };
    // Heights over the plane through the first point (relative, so that a far region keeps
    // its precision); the plane's distance from the shading point.
    // Rounding of points far from the shading point, on top of the relative tolerance.
    let far = segments
        .iter()
        .flat_map(|s| s.control_points())
        .fold(0.0f64, |m, p| m.max(p.abs().max_element()));
    let tol = CURVE_PLANE_TOLERANCE * extent + 16.0 * f64::EPSILON * far;
    // The control point farthest from the plane is named: one point off the plane tilts the
    // area's normal a little, which moves the others off it by less.
    let (mut ring, mut ring_start) = (0, 0);
    let mut worst = (0.0f64, 0, 0);
    for (i, s) in segments.iter().enumerate() {
        if i > ring_start && s.start() != segments[i - 1].end() {
            ring += 1;
            ring_start = i;
        }
        for &p in s.control_points() {
            let h = (p - origin).dot(n).abs();
            if h > worst.0 {
                worst = (h, ring, i - ring_start);
            }
        }
    }
    if !(worst.0 <= tol) {
        return Err(GeomError::InvalidCurve {
            ring: worst.1,
            segment: worst.2,
            why: "control point off the plane of the others",
        });
    }
    Ok(origin.dot(n).abs() > tol)
}

/// `(1/2) integral of (p - o) x dp` over the segment (exact: three Gauss-Legendre points for a
/// cubic, whose integrand has degree 5).
fn vector_area(s: &CurveSegment, o: DVec3) -> DVec3 {
    match s {
        CurveSegment::Line([a, b]) => 0.5 * (*a - o).cross(*b - o),
        CurveSegment::Cubic(p) => {
            const X: f64 = 0.387_298_334_620_741_7; // sqrt(3/5) / 2
            let nodes = [
                (0.5 - X, 5.0 / 18.0),
                (0.5, 8.0 / 18.0),
                (0.5 + X, 5.0 / 18.0),
            ];
            let mut sum = DVec3::ZERO;
            for (t, w) in nodes {
                sum += w * (bezier(p, t) - o).cross(bezier_derivative(p, t));
            }
            0.5 * sum
        }
    }
}

/// A cubic Bezier curve at `t` (Bernstein form, accurate to a few ulps of the control points'
/// size at every `t` in `[0, 1]`, and exact at the ends).
#[inline(always)]
fn bezier(p: &[DVec3; 4], t: f64) -> DVec3 {
    let s = 1.0 - t;
    let (s2, t2) = (s * s, t * t);
    p[0] * (s2 * s) + p[1] * (3.0 * s2 * t) + p[2] * (3.0 * s * t2) + p[3] * (t2 * t)
}

/// `B'(t)`.
#[inline(always)]
fn bezier_derivative(p: &[DVec3; 4], t: f64) -> DVec3 {
    let s = 1.0 - t;
    3.0 * ((p[1] - p[0]) * (s * s) + (p[2] - p[1]) * (2.0 * s * t) + (p[3] - p[2]) * (t * t))
}

/// The part of a segment between parameters `t0 < t1`, with its end points given (exactly the
/// points its neighbours share: control points, or crossing points on a horizon).
#[derive(Debug, Clone, Copy)]
struct Piece {
    /// Control points (the first two only for a line).
    cps: [DVec3; 4],
    cubic: bool,
    t0: f64,
    t1: f64,
    start: DVec3,
    end: DVec3,
}

impl Piece {
    fn whole(s: &CurveSegment) -> Self {
        match *s {
            CurveSegment::Line([a, b]) => Piece {
                cps: [a, b, b, b],
                cubic: false,
                t0: 0.0,
                t1: 1.0,
                start: a,
                end: b,
            },
            CurveSegment::Cubic(p) => Piece {
                cps: p,
                cubic: true,
                t0: 0.0,
                t1: 1.0,
                start: p[0],
                end: p[3],
            },
        }
    }

    fn line(a: DVec3, b: DVec3) -> Self {
        Piece::whole(&CurveSegment::Line([a, b]))
    }

    /// The image under `m`. Every point is mapped by the same product, so points shared with
    /// neighbours stay bit-identical.
    fn transformed(&self, m: DMat3) -> Self {
        Piece {
            cps: self.cps.map(|v| m * v),
            start: m * self.start,
            end: m * self.end,
            ..*self
        }
    }

    /// The point at `t` in `[t0, t1]`, the given end points at the ends.
    fn at(&self, t: f64) -> DVec3 {
        if t == self.t0 {
            self.start
        } else if t == self.t1 {
            self.end
        } else if self.cubic {
            bezier(&self.cps, t)
        } else {
            self.start
                .lerp(self.end, (t - self.t0) / (self.t1 - self.t0))
        }
    }

    /// The parameters in `(t0, t1)` where `z` changes sign, with the sign at `t0` (`true`:
    /// above, `z > 0`). Signs at the ends are those of the given end points.
    fn sign_changes(&self) -> (bool, SmallVec<[f64; 3]>) {
        let (za, zb) = (self.start.z, self.end.z);
        let mut out = SmallVec::new();
        if self.cubic {
            let z = self.cps.map(|p| p.z);
            sign_changes(z, self.t0, self.t1, za, zb, &mut out);
        } else if (za > 0.0) != (zb > 0.0) {
            out.push(0.5 * (self.t0 + self.t1)); // a placeholder: lines cross at `crossing`
        }
        (za > 0.0, out)
    }

    /// The point on the horizon where the piece crosses it at parameter `t` (a line: where the
    /// chord between its ends does, as a positive combination of the two on `z = 0`).
    fn crossing(&self, t: f64) -> DVec3 {
        if self.cubic {
            let p = bezier(&self.cps, t);
            DVec3::new(p.x, p.y, 0.0)
        } else {
            let (a, b) = (self.start, self.end);
            let (a, b) = if a.z > 0.0 { (a, b) } else { (b, a) };
            let x = b * a.z - a * b.z;
            DVec3::new(x.x, x.y, 0.0)
        }
    }
}

/// Inline capacity of the pieces of one stage: the lights of the seed's figures (up to a few
/// dozen segments) fit without touching the heap.
type Pieces = SmallVec<[Piece; 24]>;

/// Crossing points of one stage.
type Points = SmallVec<[DVec3; 8]>;

/// One clipping stage: the parts of the pieces above the horizon `z = 0`, and the horizon
/// arcs that close them.
#[derive(Default)]
struct Stage {
    kept: Pieces,
    exits: Points,
    entries: Points,
}

impl Stage {
    /// Clips the pieces at the horizon (seed 004 section 2.4). With `flatten`, cubics are
    /// replaced by that many chords first (the polygon of the uniform baseline is clipped edge
    /// by edge).
    fn clip(
        &mut self,
        pieces: impl Iterator<Item = Piece>,
        flatten: Option<usize>,
    ) -> Result<(), GeomError> {
        for p in pieces {
            match flatten {
                Some(n) if p.cubic => {
                    let mut prev = p.start;
                    for k in 1..=n {
                        let t = p.t0 + (p.t1 - p.t0) * (k as f64 / n as f64);
                        let cur = if k == n { p.end } else { bezier(&p.cps, t) };
                        self.clip_piece(Piece::line(prev, cur));
                        prev = cur;
                    }
                }
                _ => self.clip_piece(p),
            }
        }
        if self.exits.len() != self.entries.len() {
            // Unreachable for closed loops (signs alternate along each), kept as a give-up
            // rather than a wrong pairing.
            return Err(GeomError::Undecidable(
                "horizon crossings of a curved light do not pair up",
            ));
        }
        Ok(())
    }

    fn clip_piece(&mut self, p: Piece) {
        let (mut above, changes) = p.sign_changes();
        let mut from = (p.t0, p.start);
        for &t in &changes {
            let x = p.crossing(t);
            if above {
                self.kept.push(Piece {
                    t0: from.0,
                    t1: t,
                    start: from.1,
                    end: x,
                    ..p
                });
                self.exits.push(x);
            } else {
                self.entries.push(x);
            }
            from = (t, x);
            above = !above;
        }
        if above {
            self.kept.push(Piece {
                t0: from.0,
                start: from.1,
                ..p
            });
        }
    }

    /// The horizon arcs, exit to entry, the `i`-th exit with the `i`-th entry in the order
    /// they were met. The true arcs join each exit to the next entry counter-clockwise, but
    /// every crossing lies within half a circle of every other (the region lies in an open
    /// hemisphere), so each pair spans a minor arc of the same great circle, and as chains on
    /// that circle any pairing of the same exits with the same entries adds up to the same
    /// arcs (`[X1, E2] + [X2, E1] = [X1, E1] + [X2, E2]`). Edge terms and clipping are
    /// additive over chains, so the integral does not depend on the pairing.
    fn arcs(&self) -> impl Iterator<Item = (DVec3, DVec3)> + '_ {
        self.exits.iter().copied().zip(self.entries.iter().copied())
    }

    /// The kept pieces and the horizon arcs as line pieces: the clipped region's boundary.
    fn closed(&self) -> impl Iterator<Item = Piece> + '_ {
        self.kept
            .iter()
            .copied()
            .chain(self.arcs().map(|(x, e)| Piece::line(x, e)))
    }

    /// Baum's sum over the clipped boundary, curves subdivided.
    fn integrate(&self, subdivision: Subdivision) -> CurvedIntegral {
        // The test compares edge-term sums, which are `2 pi` times integrals.
        let (eps, bound) = match subdivision {
            Subdivision::Adaptive { eps } => (Some(2.0 * PI * eps), false),
            Subdivision::AdaptiveWithBound { eps } => (Some(2.0 * PI * eps), true),
            Subdivision::Uniform { .. } => (None, false),
        };
        let mut acc = Accumulator::default();
        for p in &self.kept {
            match eps {
                Some(eps) if p.cubic && bound => acc.adaptive::<true>(p, eps),
                Some(eps) if p.cubic => acc.adaptive::<false>(p, eps),
                _ => acc.chord(Ray::new(p.start), Ray::new(p.end)),
            }
        }
        for (x, e) in self.arcs() {
            acc.chord(Ray::new(x), Ray::new(e));
        }
        let value = (acc.sum / (2.0 * PI)).clamp(0.0, 1.0);
        CurvedIntegral {
            value,
            edges: acc.edges,
            error_bound: bound.then_some(acc.bound),
        }
    }
}

/// The running edge sum of [`Stage::integrate`].
#[derive(Default)]
struct Accumulator {
    sum: f64,
    edges: usize,
    /// Sum of the accepted intervals' sliver bounds (in units of the integral).
    bound: f64,
}

/// An interval of the adaptive subdivision on the stack: its parameters, end points and the
/// edge term of its chord.
#[derive(Clone, Copy)]
struct Interval {
    t0: f64,
    t1: f64,
    a: Ray,
    b: Ray,
    chord: f64,
    depth: u32,
}

impl Accumulator {
    fn chord(&mut self, a: Ray, b: Ray) {
        self.sum += edge_term(a, b);
        self.edges += 1;
    }

    /// Seed 004 Listing 1 on one kept part of a cubic: depth first, with an explicit stack of
    /// at most `INITIAL_INTERVALS + MAX_DEPTH` intervals (a split pops one and pushes two).
    /// With `BOUND`, every accepted interval adds the bound on its two slivers
    /// ([`sliver_bound`]) to `self.bound`; the sum is the same either way.
    fn adaptive<const BOUND: bool>(&mut self, p: &Piece, eps: f64) {
        const CAP: usize = INITIAL_INTERVALS + MAX_DEPTH as usize + 1;
        let empty = Interval {
            t0: 0.0,
            t1: 0.0,
            a: Ray::new(DVec3::ZERO),
            b: Ray::new(DVec3::ZERO),
            chord: 0.0,
            depth: 0,
        };
        let mut stack = [empty; CAP];
        let mut len = 0;
        // The initial intervals, pushed last first so that they are processed in order.
        let dt = (p.t1 - p.t0) / INITIAL_INTERVALS as f64;
        let param = |k: usize| {
            if k == INITIAL_INTERVALS {
                p.t1
            } else {
                p.t0 + dt * k as f64
            }
        };
        let mut b = Ray::new(p.end);
        for k in (0..INITIAL_INTERVALS).rev() {
            let (t0, t1) = (param(k), param(k + 1));
            let a = Ray::new(p.at(t0));
            stack[len] = Interval {
                t0,
                t1,
                a,
                b,
                chord: edge_term(a, b),
                depth: 0,
            };
            len += 1;
            b = a;
        }
        while len > 0 {
            len -= 1;
            let iv = stack[len];
            let tm = 0.5 * (iv.t0 + iv.t1);
            let m = Ray::new(p.at(tm));
            let (t01, t12) = (edge_term(iv.a, m), edge_term(m, iv.b));
            // The triangle (a, m, b): its two half chords and its chord backwards.
            let tri = t01 + t12 - iv.chord;
            let room = iv.depth < MAX_DEPTH && len + 2 <= CAP;
            // The sub-curve's control points, needed by the cone test and by the bound of an
            // accepted interval: computed once, and only when the triangle does not decide.
            let mut cps = None;
            let split = room
                && (tri.abs() > eps || {
                    let q = sub_curve(&p.cps, iv.t0, iv.t1);
                    cps = Some(q);
                    wide(&q)
                });
            if split {
                let depth = iv.depth + 1;
                stack[len] = Interval {
                    t0: tm,
                    t1: iv.t1,
                    a: m,
                    b: iv.b,
                    chord: t12,
                    depth,
                };
                stack[len + 1] = Interval {
                    t0: iv.t0,
                    t1: tm,
                    a: iv.a,
                    b: m,
                    chord: t01,
                    depth,
                };
                len += 2;
            } else {
                self.sum += t01 + t12;
                self.edges += 2;
                if BOUND {
                    let q = cps.unwrap_or_else(|| sub_curve(&p.cps, iv.t0, iv.t1));
                    let [left, right] = halves(&q);
                    self.bound += sliver_bound(&left) + sliver_bound(&right);
                }
            }
        }
    }
}

/// The control points of the cubic `p` restricted to `[t0, t1]` (and reparametrized over
/// `[0, 1]`): its blossoms `f(t0, t0, t0)`, `f(t0, t0, t1)`, `f(t0, t1, t1)`, `f(t1, t1, t1)`,
/// each by de Casteljau's steps with one parameter per level.
#[inline(always)]
fn sub_curve(p: &[DVec3; 4], t0: f64, t1: f64) -> [DVec3; 4] {
    let blossom = |u: f64, v: f64, w: f64| {
        let l1 = [p[0].lerp(p[1], u), p[1].lerp(p[2], u), p[2].lerp(p[3], u)];
        let l2 = [l1[0].lerp(l1[1], v), l1[1].lerp(l1[2], v)];
        l2[0].lerp(l2[1], w)
    };
    [
        blossom(t0, t0, t0),
        blossom(t0, t0, t1),
        blossom(t0, t1, t1),
        blossom(t1, t1, t1),
    ]
}

/// The control points of the two halves of the cubic `q` (de Casteljau at `1/2`).
#[inline(always)]
fn halves(q: &[DVec3; 4]) -> [[DVec3; 4]; 2] {
    let l1 = [
        q[0].midpoint(q[1]),
        q[1].midpoint(q[2]),
        q[2].midpoint(q[3]),
    ];
    let l2 = [l1[0].midpoint(l1[1]), l1[1].midpoint(l1[2])];
    let mid = l2[0].midpoint(l2[1]);
    [[q[0], l1[0], l2[0], mid], [mid, l2[1], l1[2], q[3]]]
}

/// Whether the directions of a cubic with control points `q` may spread over more than
/// `pi / 4`: the curve lies in the convex hull of its control points, so its directions lie in
/// their cone, and the test is whether two of them are more than `pi / 4` apart. Such an
/// interval is split whatever its triangle: the seed's test samples the curve at three points,
/// and where the directions swing between them (a light whose plane passes near the point, seen
/// through a near-mirror lobe that magnifies it) the omitted sliver can hold the lobe's peak
/// while the triangle holds nothing (the fuzz target found `7.852e-4` for `8.213e-4` at
/// `eps = 1e-13`, and `1.1e-9` for `8.1e-8`). Within a quarter turn the clamped cosine is
/// smooth enough for the test; on the seed's kind of scene the bound splits almost nothing
/// (BENCHMARKS.md). It also keeps the accepted slivers' bounds ([`sliver_bound`]) in the regime
/// where their solid-angle estimate is tight.
#[inline(always)]
fn wide(q: &[DVec3; 4]) -> bool {
    let q = q.map(Ray::new);
    let apart = |a: Ray, b: Ray| {
        let d = a.dot(b);
        d < 0.0 || d * d < MAX_CHORD_COS * MAX_CHORD_COS * a.len2() * b.len2()
    };
    apart(q[0], q[3])
        || apart(q[0], q[1])
        || apart(q[0], q[2])
        || apart(q[1], q[2])
        || apart(q[1], q[3])
        || apart(q[2], q[3])
}

/// An upper bound on `(1/pi)` times the integral of `max(0, z)` over the directions of the
/// convex hull of `q` (four points of a plane that does not hold the origin, as the control
/// points of a sub-curve are), at most 1 (the whole upper hemisphere): what the sliver between
/// the sub-curve and its chord can contribute (see the module documentation, "Accuracy").
///
/// It is the hull's solid angle times the largest `z` of a unit direction in it, both bounded
/// from above without a transcendental function, with `n_i` the unit directions of the points
/// and `d_ij` their dot products:
///
/// - Almost every point of the convex hull of four points in a plane lies in exactly two of the
///   four triangles of three of them (in convex position each diagonal splits the quadrilateral
///   in two; with one point inside the triangle of the others, that triangle and the three
///   around the inner point), so the hull's solid angle is half the sum of the four triangles'.
///   A triangle's is `2 atan(|det| / den)` with `den = 1 + d_ij + d_jk + d_ki` (Van
///   Oosterom-Strackee, for `den > 0`, that is below `pi`), at most `2 |det| / den`; the
///   smallest of the four `den` serves for all.
/// - Every direction of the hull is `p / |p|` with `p = sum mu_i n_i`, `mu_i >= 0`; for a unit
///   `u` with `n_i . u > 0` for all `i`, `p_z / |p| <= p_z / (p . u) <= max_i n_iz / (n_i . u)`
///   (a ratio of positive combinations is at most the largest ratio of its terms), at most
///   `max_i n_iz / min_i (n_i . u)`. With `u` along `sum n_i`, whose products with the `n_i`
///   are the sums of rows of the `d_ij`, and `|sum n_i|^2` the sum of those.
///
/// Both smallest-of-four steps cost a factor of `1 + O(width^2)` for a hull `width` radians
/// across, the cosine's bound one of `1 + O(width)` (its spread over the hull), and one
/// division serves the whole bound. Where the directions are spread so far that a step fails
/// (a triangle of `pi` or more, some `n_i . u <= 0`: possible only at the depth cap), its
/// factor falls back to the trivial bound (`2 pi`, 1).
#[inline(always)]
fn sliver_bound(q: &[DVec3; 4]) -> f64 {
    let l2 = q.map(|v| v.length_squared());
    let n = if l2.iter().all(|&v| v > 1e-130 && v < 1e130) {
        // One division for the four: in this range neither the squares nor the product of the
        // four lengths leave the normal floats.
        let len = l2.map(crate::math::sqrt);
        let (p01, p23) = (len[0] * len[1], len[2] * len[3]);
        let inv = 1.0 / (p01 * p23);
        let (i01, i23) = (inv * p23, inv * p01);
        [
            q[0] * (i01 * len[1]),
            q[1] * (i01 * len[0]),
            q[2] * (i23 * len[3]),
            q[3] * (i23 * len[2]),
        ]
    } else {
        q.map(|v| {
            // Brought to unit size first.
            let s = v / v.abs().max_element();
            s * (1.0 / crate::math::sqrt(s.length_squared()))
        })
    };
    let top = n[0].z.max(n[1].z).max(n[2].z).max(n[3].z);
    if !(top > 0.0) {
        // All four at or below the horizon (p_z is a positive combination of theirs), or not a
        // number: nothing, or the trivial bound.
        return if top <= 0.0 { 0.0 } else { 1.0 };
    }
    let (d01, d02, d03) = (n[0].dot(n[1]), n[0].dot(n[2]), n[0].dot(n[3]));
    let (d12, d13, d23) = (n[1].dot(n[2]), n[1].dot(n[3]), n[2].dot(n[3]));
    // The cosine: n_i . sum_j n_j, and |sum_j n_j|^2 as their sum; `z <= z_num / z_den`.
    let r = [
        1.0 + d01 + d02 + d03,
        1.0 + d01 + d12 + d13,
        1.0 + d02 + d12 + d23,
        1.0 + d03 + d13 + d23,
    ];
    let r_min = r[0].min(r[1]).min(r[2]).min(r[3]);
    let z_num = top * crate::math::sqrt(r[0] + r[1] + r[2] + r[3]);
    let (z_num, z_den) = if r_min > 0.0 && z_num < r_min {
        (z_num, r_min)
    } else {
        (1.0, 1.0)
    };
    // The solid angle: `omega <= o_num / o_den`.
    let (c12, c13, c23) = (n[1].cross(n[2]), n[1].cross(n[3]), n[2].cross(n[3]));
    let dets =
        n[0].dot(c12).abs() + n[0].dot(c13).abs() + n[0].dot(c23).abs() + n[1].dot(c23).abs();
    let den_min = (1.0 + d01 + d12 + d02)
        .min(1.0 + d01 + d13 + d03)
        .min(1.0 + d02 + d23 + d03)
        .min(1.0 + d12 + d23 + d13);
    let (o_num, o_den) = if den_min > 0.0 {
        (dets, den_min)
    } else {
        (2.0 * PI, 1.0)
    };
    let b = (o_num * z_num) / (o_den * z_den * PI);
    if b <= 1.0 { b } else { 1.0 }
}

/// `cos(pi / 4)`, the widest cone [`wide`] accepts.
const MAX_CHORD_COS: f64 = core::f64::consts::FRAC_1_SQRT_2; // cos(pi / 4)

/// The parameters in `(a, b)` where the cubic with Bernstein coefficients `z` (over `[0, 1]`)
/// changes sign, given its values `za` at `a` and `zb` at `b` (which decide the signs at the
/// ends, so that neighbours sharing an end point agree): pushed to `out` in increasing order.
/// The sign is `z > 0` against `z <= 0`, so the states alternate by construction.
///
/// The real critical points in `(a, b)` split the range into monotone pieces; a piece whose
/// ends differ in sign holds one crossing, found by [`bracketed_root`]. A near-double root
/// shows as two crossings on either side of a critical point whose value is within rounding of
/// zero, or as none: the curve only grazes the horizon there, and either answer is right to
/// rounding. The critical points are the roots of the derivative, a quadratic
/// ([`quadratic_roots`]).
pub(crate) fn sign_changes(
    z: [f64; 4],
    a: f64,
    b: f64,
    za: f64,
    zb: f64,
    out: &mut SmallVec<[f64; 3]>,
) {
    // Brought to unit size (roots and signs do not change under positive scaling), so that
    // neither the squares of the quadratic nor the degree test underflow or overflow.
    let size = z.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    if !(size > 0.0 && size.is_finite()) {
        if (za > 0.0) != (zb > 0.0) {
            out.push(0.5 * (a + b)); // a flat curve on the horizon between ends of either sign
        }
        return;
    }
    let z = z.map(|v| v / size);
    // The derivative over 3, in Bernstein form (d0, d1, d2), then in power form.
    let (d0, d1, d2) = (z[1] - z[0], z[2] - z[1], z[3] - z[2]);
    let crit = quadratic_roots(
        d0 - 2.0 * d1 + d2,
        2.0 * (d1 - d0),
        d0,
        d0.abs() + d1.abs() + d2.abs(),
    );
    let mut knots: SmallVec<[(f64, f64); 4]> = SmallVec::new();
    knots.push((a, za));
    for c in crit.into_iter().flatten() {
        if c > a && c < b {
            knots.push((c, bernstein(z, c)));
        }
    }
    knots.push((b, zb));
    for w in knots.windows(2) {
        let ((lo, flo), (hi, fhi)) = (w[0], w[1]);
        if (flo > 0.0) != (fhi > 0.0) {
            out.push(bracketed_root(z, lo, hi, flo > 0.0));
        }
    }
}

/// The roots of `a t^2 + b t + c` (power form), sorted, `None` for missing ones; `scale` is the
/// size of the coefficients the three were computed from, for the degree test.
///
/// Only roots in `[0, 1]` matter to the callers, where `|a t^2| <= |a|`: when `|a|` is within
/// rounding of `scale` the quadratic term changes the polynomial there by less than its own
/// rounding, and the linear root is taken (the other root, beyond `[0, 1]`, would be large
/// and lose all precision). Otherwise the roots come from `q = -(b + sign(b) sqrt(b^2 - 4ac))
/// / 2` as `q / a` and `c / q`: no difference of nearly equal terms (the textbook formula
/// cancels for `4 |ac| << b^2`, and a wrong sign of `sqrt` there is the published solver's bug).
pub(crate) fn quadratic_roots(a: f64, b: f64, c: f64, scale: f64) -> [Option<f64>; 2] {
    const DEGREE_TOL: f64 = 16.0 * f64::EPSILON;
    if !(a.abs() > DEGREE_TOL * scale) {
        if !(b.abs() > DEGREE_TOL * scale) {
            return [None, None]; // constant to rounding: no critical point to split at
        }
        return [Some(-c / b), None];
    }
    let disc = b * b - 4.0 * a * c;
    if !(disc >= 0.0) {
        return [None, None];
    }
    let q = -0.5 * (b + crate::math::sqrt(disc).copysign(b));
    if q == 0.0 {
        // b = 0 and c = 0: a double root at zero.
        return [Some(0.0), None];
    }
    let (r1, r2) = (q / a, c / q);
    if r1 <= r2 {
        [Some(r1), Some(r2)]
    } else {
        [Some(r2), Some(r1)]
    }
}

/// The cubic with Bernstein coefficients `z` at `t`.
#[inline(always)]
fn bernstein(z: [f64; 4], t: f64) -> f64 {
    let s = 1.0 - t;
    let (s2, t2) = (s * s, t * t);
    z[0] * (s2 * s) + z[1] * (3.0 * s2 * t) + z[2] * (3.0 * s * t2) + z[3] * (t2 * t)
}

/// The crossing in `(lo, hi)` of the cubic `z`, whose sign at `lo` is `up_lo` (`z > 0`) and at
/// `hi` the other: Newton steps from the middle, each kept inside the bracket (a step that
/// would leave it bisects instead), the bracket shrunk by the sign of every evaluation, until
/// it is a few ulps wide or a step no longer moves. At most 110 evaluations (bisection alone
/// needs 60 on `[0, 1]`); one to five for a simple root.
fn bracketed_root(z: [f64; 4], mut lo: f64, mut hi: f64, up_lo: bool) -> f64 {
    let (d0, d1, d2) = (z[1] - z[0], z[2] - z[1], z[3] - z[2]);
    let mut t = 0.5 * (lo + hi);
    for _ in 0..110 {
        let f = bernstein(z, t);
        if (f > 0.0) == up_lo {
            lo = t;
        } else {
            hi = t;
        }
        if f == 0.0 || hi - lo <= 4.0 * f64::EPSILON * hi.abs().max(f64::MIN_POSITIVE) {
            return t;
        }
        let s = 1.0 - t;
        let df = 3.0 * (d0 * s * s + 2.0 * d1 * s * t + d2 * t * t);
        let next = t - f / df;
        t = if next > lo && next < hi {
            if (next - t).abs() <= f64::EPSILON * t.abs() {
                return next;
            }
            next
        } else {
            0.5 * (lo + hi)
        };
    }
    t
}

#[cfg(test)]
mod tests {
    use super::*;
    use alloc::vec::Vec;

    /// Bernstein coefficients of `k (t - r1)(t - r2)(t - r3)`.
    fn from_roots(k: f64, r: [f64; 3]) -> [f64; 4] {
        // Power form, then to Bernstein: b0 = c0, b1 = c0 + c1/3, b2 = c0 + 2c1/3 + c2/3,
        // b3 = c0 + c1 + c2 + c3.
        let c3 = k;
        let c2 = -k * (r[0] + r[1] + r[2]);
        let c1 = k * (r[0] * r[1] + r[1] * r[2] + r[0] * r[2]);
        let c0 = -k * r[0] * r[1] * r[2];
        [
            c0,
            c0 + c1 / 3.0,
            c0 + 2.0 * c1 / 3.0 + c2 / 3.0,
            c0 + c1 + c2 + c3,
        ]
    }

    fn changes(z: [f64; 4]) -> SmallVec<[f64; 3]> {
        let mut out = SmallVec::new();
        sign_changes(z, 0.0, 1.0, z[0], z[3], &mut out);
        out
    }

    #[test]
    fn simple_roots_of_a_cubic_are_found_to_rounding() {
        for (k, r) in [
            (1.0, [0.1, 0.5, 0.9]),
            (-3.0, [0.25, 0.5, 0.75]),
            (1e-300, [0.2, 0.3, 0.95]),
            (1e300, [0.2, 0.3, 0.95]),
            (2.0, [0.3, 1.5, -7.0]),
            (1.0, [1e-9, 0.5, 2.0]),
        ] {
            let z = from_roots(k, r);
            let got = changes(z);
            let want: Vec<f64> = {
                let mut w: Vec<f64> = r.iter().copied().filter(|t| *t > 0.0 && *t < 1.0).collect();
                w.sort_by(f64::total_cmp);
                w
            };
            assert_eq!(got.len(), want.len(), "{k} {r:?}: {got:?}");
            for (g, w) in got.iter().zip(&want) {
                assert!((g - w).abs() <= 1e-12, "{k} {r:?}: {got:?}");
            }
        }
    }

    /// Near-double roots: two crossings a hair apart, or none where the curve only grazes;
    /// never one (the signs at both ends agree).
    #[test]
    fn near_double_roots_give_two_crossings_or_none() {
        for gap in [1e-3, 1e-6, 1e-9, 1e-12, 0.0] {
            let z = from_roots(1.0, [0.4, 0.4 + gap, 3.0]);
            let got = changes(z);
            assert!(got.len() == 2 || got.is_empty(), "{gap}: {got:?}");
            if gap >= 1e-6 {
                assert_eq!(got.len(), 2, "{gap}");
                assert!((got[0] - 0.4).abs() < 1e-9 && (got[1] - 0.4 - gap).abs() < 1e-9);
            }
        }
        // A triple root changes sign once.
        let got = changes(from_roots(1.0, [0.6; 3]));
        assert_eq!(got.len(), 1);
        assert!((got[0] - 0.6).abs() < 1e-5, "{got:?}");
    }

    /// Degenerate degrees: a cubic whose leading coefficient is rounding noise, quadratics and
    /// lines written as cubics, and a constant.
    #[test]
    fn lower_degrees_in_cubic_form() {
        // A line through 0.3: z = t - 0.3, as a cubic.
        let line = [-0.3, -0.3 + 1.0 / 3.0, -0.3 + 2.0 / 3.0, 0.7];
        let got = changes(line);
        assert_eq!(got.len(), 1);
        assert!((got[0] - 0.3).abs() < 1e-15);
        // A quadratic (t - 0.2)(t - 0.7) in cubic form.
        let q = |t: f64| (t - 0.2) * (t - 0.7);
        let (c0, c1, c2) = (q(0.0), -0.9, 1.0);
        let quad = [
            c0,
            c0 + c1 / 3.0,
            c0 + 2.0 * c1 / 3.0 + c2 / 3.0,
            c0 + c1 + c2,
        ];
        let got = changes(quad);
        assert_eq!(got.len(), 2, "{got:?}");
        assert!((got[0] - 0.2).abs() < 1e-14 && (got[1] - 0.7).abs() < 1e-14);
        assert!(changes([1.0; 4]).is_empty());
        assert!(changes([0.0; 4]).is_empty());
    }

    #[test]
    fn quadratic_roots_are_stable() {
        // b^2 >> 4ac: the small root 1e-10 must not cancel away.
        let [r1, r2] = quadratic_roots(1.0, -(1e10 + 1e-10), 1.0, 1e10);
        assert!((r1.unwrap() - 1e-10).abs() < 1e-24);
        assert!((r2.unwrap() - 1e10).abs() < 1e-4);
        // Both signs of b.
        let [r1, r2] = quadratic_roots(2.0, 2.0, -4.0, 8.0);
        assert_eq!((r1, r2), (Some(-2.0), Some(1.0)));
        let [r1, r2] = quadratic_roots(2.0, -2.0, -4.0, 8.0);
        assert_eq!((r1, r2), (Some(-1.0), Some(2.0)));
        // A leading coefficient at rounding level: the linear root.
        let [r1, r2] = quadratic_roots(1e-17, 1.0, -0.5, 1.5);
        assert_eq!((r1, r2), (Some(0.5), None));
    }

    /// `sliver_bound` against the exact integral over the convex hull (the hull ordered here by
    /// gift wrapping in plane coordinates, integrated by the crate's exact polygon integral):
    /// never below it, and close to it for small hulls. Hulls of every kind: quadrilaterals
    /// and triangles with a point inside, slivers, hulls around the zenith (where the largest
    /// cosine is inside, not at a point), across and below the horizon, and wide ones.
    #[test]
    fn sliver_bound_holds_the_hull_integral() {
        use crate::sphere::SphericalPolygon;
        let mut s = 0x9e37_79b9_7f4a_7c15u64;
        let mut next = || {
            s = s
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            ((s >> 11) as f64) / (1u64 << 53) as f64
        };
        let (mut checked, mut worst_small) = (0, 0.0f64);
        let (mut across, mut wide_hulls) = (0, 0);
        for k in 0..4000 {
            // The plane: normal anywhere (around the zenith for a quarter of the cases), at a
            // distance from 0.05 to 2 on either side.
            let n = if k % 4 == 0 {
                DVec3::new(0.1 * next() - 0.05, 0.1 * next() - 0.05, 1.0).normalize()
            } else {
                DVec3::new(2.0 * next() - 1.0, 2.0 * next() - 1.0, 2.0 * next() - 1.0)
                    .normalize_or(DVec3::Z)
            };
            let h = (0.05 + 1.95 * next()) * if next() < 0.5 { -1.0 } else { 1.0 };
            let e1 = n.any_orthonormal_vector();
            let e2 = n.cross(e1);
            // Four points in a window of size 1e-3 to 3, centred near the foot of the normal
            // (on the zenith for those planes) or anywhere within 3 of it.
            let size = 10f64.powf(-3.0 + 3.5 * next());
            let c = if k % 4 == 0 {
                [0.0, 0.0]
            } else {
                [6.0 * next() - 3.0, 6.0 * next() - 3.0]
            };
            let mut uv = [[0.0; 2]; 4];
            for p in &mut uv {
                *p = [
                    c[0] + size * (next() - 0.5),
                    c[1] + size * (next() - 0.5) * if k % 7 == 0 { 1e-3 } else { 1.0 },
                ];
            }
            let at = |p: [f64; 2]| n * h + e1 * p[0] + e2 * p[1];
            let q = uv.map(at);
            let bound = sliver_bound(&q);
            // The hull by gift wrapping (counter-clockwise in (e1, e2)).
            let cross = |o: [f64; 2], a: [f64; 2], b: [f64; 2]| {
                (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])
            };
            let start = (0..4)
                .min_by(|&i, &j| uv[i][0].total_cmp(&uv[j][0]))
                .unwrap();
            let mut hull = Vec::new();
            let mut cur = start;
            loop {
                hull.push(cur);
                let mut cand = (cur + 1) % 4;
                for j in 0..4 {
                    if cross(uv[cur], uv[cand], uv[j]) < 0.0 {
                        cand = j;
                    }
                }
                cur = cand;
                if cur == start || hull.len() > 4 {
                    break;
                }
            }
            let mut ring: Vec<DVec3> = hull.iter().map(|&i| q[i]).collect();
            // Counter-clockwise seen from outside the sphere: (a x b) . c > 0.
            if ring.len() < 3 {
                continue;
            }
            if ring[0].cross(ring[1]).dot(ring[2]) < 0.0 {
                ring.reverse();
            }
            let Ok(poly) = SphericalPolygon::new(alloc::vec![ring.clone()]) else {
                continue; // vertices within rounding of each other
            };
            let exact = super::super::clamped_cosine_integral(&poly);
            checked += 1;
            assert!(
                exact <= bound * (1.0 + 1e-9) + 1e-15,
                "case {k}: hull integral {exact:e} above the bound {bound:e}: {q:?}"
            );
            // Tight where the hull is small and well above the horizon.
            let width = ring
                .iter()
                .flat_map(|a| ring.iter().map(move |b| a.normalize().dot(b.normalize())))
                .fold(1.0f64, f64::min);
            let low = ring.iter().map(|p| p.normalize().z).fold(1.0f64, f64::min);
            let high = ring.iter().map(|p| p.normalize().z).fold(-1.0f64, f64::max);
            if low < 0.0 && high > 0.0 {
                across += 1;
            }
            if width < 0.7 {
                wide_hulls += 1;
            }
            if width > 0.995 && low > 0.2 && exact > 0.0 {
                worst_small = worst_small.max(bound / exact);
            }
        }
        // The generator reaches every kind of hull: across the horizon, wider than pi / 4.
        assert!(
            checked > 3000 && across > 50 && wide_hulls > 100,
            "{checked} {across} {wide_hulls}"
        );
        // Small hulls: the solid angle is exact to a fraction of a percent, and the cosine's
        // factor is its spread over the hull (up to a tenth of a radian across here).
        assert!(worst_small < 1.25, "bound / integral up to {worst_small}");
    }

    #[test]
    fn random_cubics_agree_with_dense_sign_sampling() {
        // Deterministic LCG; roots where sampling sees a sign change away from near-zero
        // values must be found, and no others.
        let mut s = 0x2545_f491_4f6c_dd1du64;
        let mut next = || {
            s = s.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1);
            ((s >> 11) as f64) / (1u64 << 53) as f64 * 2.0 - 1.0
        };
        for _ in 0..2000 {
            let z = [next(), next(), next(), next()];
            let got = changes(z);
            let n = 4096;
            let mut count = 0;
            for i in 0..n {
                let (a, b) = (i as f64 / n as f64, (i + 1) as f64 / n as f64);
                let (fa, fb) = (bernstein(z, a), bernstein(z, b));
                if (fa > 0.0) != (fb > 0.0) {
                    count += 1;
                }
            }
            assert_eq!(got.len() % 2, usize::from((z[0] > 0.0) != (z[3] > 0.0)));
            // Sampling can only miss pairs of crossings inside one sample interval.
            assert!(
                got.len() >= count && (got.len() - count).is_multiple_of(2),
                "{z:?}: {got:?}"
            );
            for &t in &got {
                assert!(bernstein(z, t).abs() < 1e-13, "{z:?}: {t}");
            }
        }
    }
}
