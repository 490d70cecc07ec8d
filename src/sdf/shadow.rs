//! Approximate soft shadows of area lights in signed-distance scenes: seed 001's minimal tangent
//! cone search and the two shading methods built on it, and the Quilez soft shadow with its
//! improved variant as baselines.
//!
//! # The shadow cone
//!
//! From a shading point `p` toward a light bounded by the sphere `(c, R)` at distance `D > R`,
//! the cone with apex `p` tangent to the sphere has axis `v = (c - p) / D` and half angle
//! `alpha` with `sin alpha = R / D`, so `tan alpha = R / sqrt(D^2 - R^2)`. It touches the sphere
//! along a circle at axial distance `(D^2 - R^2) / D`, where every search below stops: past it
//! the light itself fills the cone.
//!
//! # Minimal tangent cone (seed 001 section 3, Alg. 2)
//!
//! With cone radius `rho(t) = r0 + t tan alpha` the search minimizes the relative distance
//! `m(t) = f(p + t v) / rho(t)`, clamped to `[-1, 1]`: `1` means the surface touches the cone,
//! `0` that it touches the axis, `-1` that it touches the inverted cone (the cone is covered).
//! It marches with the Lipschitz-safe cone step of [`cone_trace`](super::cone_trace) against a
//! cone shrunk to `(m - epsilon) rho(t)`, `m` the smallest ratio found so far: every skipped
//! point has `f > (m - epsilon) rho`, and every evaluated one was compared with `m`. Hence on
//! completion the true minimum over `[t_min, t_max]` lies in `[m - epsilon, m]`
//! ([`ConeMinimum`]). The paper's loop condition reads `m > epsilon` in the extracted text; the
//! search here stops when `m <= -1 + epsilon` instead (nothing below `-1` counts, so the bound
//! above still holds), because stopping at `m <= epsilon` would cut off the inner half of every
//! penumbra, which the occlusion formula needs.
//!
//! # Shading (seed 001 section 4)
//!
//! The occluder nearest the axis (relative to the cone) is taken to be planar or edge-like there,
//! so it cuts the cone's cross-section (a disk of radius `rho`) along a chord at signed distance
//! `m rho` from the center. The visible fraction of the disk is (section 4.1)
//!
//! `V(m) = (2 / pi) * integral_{-1}^{m} sqrt(1 - x^2) dx = (m sqrt(1 - m^2) + asin m) / pi + 1/2`
//!
//! ([`chord_visibility`]), or its cheaper smoothstep stand-in `s^2 (3 - 2 s)` with
//! `s = (m + 1) / 2` ([`smoothstep_visibility`]). The fast method multiplies the unshadowed light
//! integral by `V` (seed 001 eq. 2). Section 4.2 instead keeps the occluder as a proxy: a plane
//! through `p` that splits the directions ([`ProxyOccluder`]), and integrates the light over the
//! directions it leaves visible, numerically for any light that can be ray-tested
//! ([`proxy_integral`]) or exactly for a quad light ([`proxy_quad_integral`]).
//!
//! # Baselines
//!
//! [`quilez_shadow`]: sphere tracing from `p` toward the light center with
//! `res = min(res, k h / t)` and `k = 1 / tan alpha` (so `k h / t` is the unsigned `m(t)` of a
//! cone with apex `p`), returning 0 at a hit; [`quilez_improved_shadow`]: Aaltonen's variant,
//! which estimates the distance to the closest point between two consecutive spheres.
//!
//! # Light inside geometry
//!
//! A shading point inside or on a light's bounding sphere has no shadow cone:
//! [`GeomError::Degenerate`]. A spherical light entirely inside a solid (`f(c) <= -R`) has
//! visibility 0 for every method; a light partly inside a solid is treated like any other
//! light (the solid around it occludes part of the cone).
//!
//! # References
//!
//! - Seed 001: G. Ban, C. Bálint, G. Valasek. *Area lights in signed distance function scenes.*
//!   Eurographics 2019 short papers (Alg. 2, eq. 2, sections 4.1 and 4.2).
//! - \[Qui10\] I. Quilez. *Penumbra shadows in raymarched SDFs* (web article, 2010).
//! - \[Aal18\] S. Aaltonen. *GPU-based clay simulation and ray tracing tech in Claybook.*
//!   GDC 2018 (the improved soft shadow).

use super::field::{Sdf, check_direction, check_finite, check_point, check_positive, normal};
use super::trace::eval;
use crate::GeomError;
use crate::ltc::clamped_cosine_integral;
use crate::math::{asin, sqrt};
use crate::sphere::SphericalPolygon;
use glam::{DMat3, DVec3};

/// A spherical light (or the bounding sphere of any light).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SphereLight {
    center: DVec3,
    radius: f64,
}

impl SphereLight {
    /// The light of `radius` about `center`.
    ///
    /// # Errors
    ///
    /// Non-finite or too large input ([`GeomError::OutOfRange`]); `radius <= 0`
    /// ([`GeomError::Degenerate`]).
    pub fn new(center: DVec3, radius: f64) -> Result<Self, GeomError> {
        check_point("light center", center)?;
        check_positive("light radius", radius, "sdf: a light radius must be > 0")?;
        Ok(SphereLight { center, radius })
    }

    /// The center.
    #[must_use]
    pub fn center(&self) -> DVec3 {
        self.center
    }

    /// The radius.
    #[must_use]
    pub fn radius(&self) -> f64 {
        self.radius
    }
}

/// A light that [`proxy_integral`] can integrate: bounded by a sphere, and ray-testable.
pub trait AreaLight {
    /// A sphere containing the light.
    fn bounding_sphere(&self) -> SphereLight;
    /// Whether the ray from `origin` along unit `dir` meets the light's emitting surface.
    fn emits_toward(&self, origin: DVec3, dir: DVec3) -> bool;
}

impl AreaLight for SphereLight {
    fn bounding_sphere(&self) -> SphereLight {
        *self
    }
    fn emits_toward(&self, origin: DVec3, dir: DVec3) -> bool {
        let oc = self.center - origin;
        let along = oc.dot(dir);
        along > 0.0 && (oc - along * dir).length_squared() <= self.radius * self.radius
    }
}

/// A one-sided parallelogram light `center ± u ± v`, emitting toward `u x v` (the orientation of
/// `arealight::shade::TriangleMesh::quad`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct QuadLight {
    center: DVec3,
    u: DVec3,
    v: DVec3,
    normal: DVec3,
}

impl QuadLight {
    /// The parallelogram `center ± u ± v`, emitting toward `u x v`.
    ///
    /// # Errors
    ///
    /// Non-finite or too large input ([`GeomError::OutOfRange`]); `u` and `v` parallel or zero
    /// ([`GeomError::Degenerate`]).
    pub fn new(center: DVec3, u: DVec3, v: DVec3) -> Result<Self, GeomError> {
        check_point("quad center", center)?;
        check_point("quad u", u)?;
        check_point("quad v", v)?;
        let normal = check_direction("quad normal", u.cross(v))
            .map_err(|_| GeomError::Degenerate("sdf: quad edges u and v are parallel"))?;
        Ok(QuadLight {
            center,
            u,
            v,
            normal,
        })
    }

    /// The four corners, counter-clockwise seen from the emitting side.
    #[must_use]
    pub fn corners(&self) -> [DVec3; 4] {
        let (c, u, v) = (self.center, self.u, self.v);
        [c - u - v, c + u - v, c + u + v, c - u + v]
    }
}

impl AreaLight for QuadLight {
    fn bounding_sphere(&self) -> SphereLight {
        let r = (self.u + self.v).length().max((self.u - self.v).length());
        SphereLight {
            center: self.center,
            radius: r,
        }
    }
    fn emits_toward(&self, origin: DVec3, dir: DVec3) -> bool {
        let from = origin - self.center;
        let height = from.dot(self.normal);
        let rate = dir.dot(self.normal);
        // In front of the emitting side, moving toward the plane.
        if !(height > 0.0 && rate < 0.0) {
            return false;
        }
        let x = from + dir * (-height / rate);
        // Coordinates in the (u, v) basis from the dual basis of the parallelogram's plane.
        let (uu, uv, vv) = (self.u.dot(self.u), self.u.dot(self.v), self.v.dot(self.v));
        let det = uu * vv - uv * uv;
        let (xu, xv) = (x.dot(self.u), x.dot(self.v));
        let a = (xu * vv - xv * uv) / det;
        let b = (xv * uu - xu * uv) / det;
        a.abs() <= 1.0 && b.abs() <= 1.0
    }
}

/// The settings of the minimal tangent cone search ([`minimal_tangent_cone`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ConeSearch {
    /// The accuracy `epsilon` of seed 001 Alg. 2, in `(0, 1]`: the minimum found is within
    /// `epsilon` of the true one. The paper recommends `0.05` to `0.1` (smaller for larger
    /// lights); the number of steps grows like `1 / epsilon` along surfaces near the cone.
    pub epsilon: f64,
    /// Where the search starts along the axis (`> 0`): far enough from the shading point that
    /// the rounding of its own surface distance does not count as an occluder, small against
    /// the scene (the receiving surface itself is seen as an occluder from `t_min` on, which
    /// models the horizon).
    pub t_min: f64,
    /// The largest number of field evaluations (`>= 1`). A search that runs out reports
    /// [`ConeMinimum::complete`] `false`.
    pub max_steps: u32,
}

impl ConeSearch {
    /// `epsilon`, `t_min`, and at most 512 steps.
    #[must_use]
    pub fn new(epsilon: f64, t_min: f64) -> Self {
        ConeSearch {
            epsilon,
            t_min,
            max_steps: 512,
        }
    }

    /// Checks the settings.
    ///
    /// # Errors
    ///
    /// Non-finite values ([`GeomError::OutOfRange`]); `epsilon` outside `(0, 1]`, `t_min <= 0`
    /// or `max_steps == 0` ([`GeomError::Degenerate`]).
    pub fn validate(&self) -> Result<(), GeomError> {
        check_finite("cone search epsilon", self.epsilon)?;
        if !(self.epsilon > 0.0 && self.epsilon <= 1.0) {
            return Err(GeomError::Degenerate(
                "sdf: the cone search epsilon must be in (0, 1]",
            ));
        }
        check_positive(
            "cone search t_min",
            self.t_min,
            "sdf: the cone search t_min must be > 0",
        )?;
        if self.max_steps == 0 {
            return Err(GeomError::Degenerate(
                "sdf: the cone search needs at least one step",
            ));
        }
        Ok(())
    }
}

/// The result of [`minimal_tangent_cone`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ConeMinimum {
    /// The smallest relative distance `f / rho` found, clamped to `[-1, 1]`. When
    /// [`ConeMinimum::complete`], the true minimum over the searched range lies in
    /// `[m - epsilon, m]`.
    pub m: f64,
    /// Where along the axis `m` was found (`t_min` if no point came within `(1 + epsilon) rho`).
    pub t: f64,
    /// The field's value there.
    pub distance: f64,
    /// Field evaluations used.
    pub steps: u32,
    /// Whether the search covered the whole range (or reached `m <= -1 + epsilon`, below which
    /// nothing changes the result); `false` when it ran out of steps first, in which case `m`
    /// bounds the minimum of the part searched only.
    pub complete: bool,
}

/// Seed 001 Alg. 2, the minimal tangent cone search: the minimum over `t` in `[t_min, t_max]`
/// of `m(t) = f(origin + t dir) / (radius + t tan_half_angle)`, clamped to `[-1, 1]`, within
/// `epsilon` (see the module docs for the guarantee and its proof).
///
/// # Errors
///
/// Invalid settings ([`ConeSearch::validate`]); non-finite input; `radius < 0`,
/// `tan_half_angle < 0`, or a cone of zero radius at `t_min` ([`GeomError::Degenerate`]); a
/// field value that is NaN or `-inf`.
pub fn minimal_tangent_cone<S: Sdf + ?Sized>(
    sdf: &S,
    origin: DVec3,
    dir: DVec3,
    radius: f64,
    tan_half_angle: f64,
    t_max: f64,
    search: &ConeSearch,
) -> Result<ConeMinimum, GeomError> {
    search.validate()?;
    check_point("cone apex", origin)?;
    let dir = check_direction("cone axis", dir)?;
    check_finite("cone radius", radius)?;
    check_finite("cone tan(half angle)", tan_half_angle)?;
    check_finite("cone search t_max", t_max)?;
    if !(radius >= 0.0 && tan_half_angle >= 0.0 && radius + search.t_min * tan_half_angle > 0.0) {
        return Err(GeomError::Degenerate(
            "sdf: a shadow cone needs radius >= 0, tan(half angle) >= 0, and a positive radius \
             at t_min",
        ));
    }
    let eps = search.epsilon;
    let mut t = search.t_min;
    let mut best = ConeMinimum {
        m: 1.0,
        t,
        distance: f64::INFINITY,
        steps: 0,
        complete: false,
    };
    // The cone marched against has radius `factor * rho(t)`: the full cone until the first
    // near contact, then `(m - epsilon) rho(t)`.
    let mut factor = 1.0;
    while best.steps < search.max_steps {
        if t > t_max {
            best.complete = true;
            return Ok(best);
        }
        let f = eval(sdf, origin + t * dir)?;
        best.steps += 1;
        let rho = radius + t * tan_half_angle;
        if f < (factor + eps) * rho {
            let ratio = (f / rho).max(-1.0);
            if ratio < best.m {
                best.m = ratio;
                best.t = t;
                best.distance = f;
            }
            if best.m <= -1.0 + eps {
                best.complete = true;
                return Ok(best);
            }
            factor = best.m - eps;
        }
        // At least epsilon * rho after the update above, so the march always advances.
        let gap = f - factor * rho;
        t += gap / (1.0 + factor.abs() * tan_half_angle);
    }
    best.complete = t > t_max;
    Ok(best)
}

/// The visible fraction of a disk cut by a chord at signed distance `m` (in radii) from its
/// center, `m` clamped to `[-1, 1]`: `(m sqrt(1 - m^2) + asin m) / pi + 1/2` (seed 001 section
/// 4.1). NaN gives NaN.
#[must_use]
pub fn chord_visibility(m: f64) -> f64 {
    let m = m.clamp(-1.0, 1.0);
    let v = (m * sqrt((1.0 - m * m).max(0.0)) + asin(m)) / core::f64::consts::PI + 0.5;
    v.clamp(0.0, 1.0)
}

/// The smoothstep stand-in for [`chord_visibility`] (seed 001 section 4.1): `s^2 (3 - 2 s)`
/// with `s = (m + 1) / 2`, `m` clamped to `[-1, 1]`. It matches the chord formula at `-1`, `0`
/// and `1` and in slope at `±1`; in between it differs by at most 0.04 (0.0394, near `m = ±0.5`).
#[must_use]
pub fn smoothstep_visibility(m: f64) -> f64 {
    let s = 0.5 * m.clamp(-1.0, 1.0) + 0.5;
    s * s * (3.0 - 2.0 * s)
}

/// Which occlusion formula [`fast_soft_shadow`] uses.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Profile {
    /// [`chord_visibility`].
    #[default]
    Chord,
    /// [`smoothstep_visibility`].
    Smoothstep,
}

/// The shadow cone from `p` to the sphere `light`: axis, `tan alpha` and the axial distance of
/// the tangent circle (see the module docs).
struct ShadowCone {
    axis: DVec3,
    tan_half_angle: f64,
    t_end: f64,
    sin_half_angle: f64,
}

fn shadow_cone(p: DVec3, light: &SphereLight) -> Result<ShadowCone, GeomError> {
    check_point("shading point", p)?;
    let to = light.center - p;
    let d = to.length();
    let r = light.radius;
    // D^2 - R^2 as (D - R)(D + R), which keeps its relative precision near the sphere.
    let slack = (d - r) * (d + r);
    if !(d > r && slack > 0.0) {
        return Err(GeomError::Degenerate(
            "sdf: the shading point is inside the light's bounding sphere, so there is no shadow \
             cone",
        ));
    }
    let leg = sqrt(slack);
    Ok(ShadowCone {
        axis: to / d,
        tan_half_angle: r / leg,
        t_end: slack / d,
        sin_half_angle: r / d,
    })
}

/// Whether the light is entirely inside a solid (documented visibility 0).
fn light_buried<S: Sdf + ?Sized>(sdf: &S, light: &SphereLight) -> Result<bool, GeomError> {
    Ok(eval(sdf, light.center)? <= -light.radius)
}

/// Seed 001 section 4.1, the fast soft shadow of a spherical light: the visible fraction `V` of
/// the light seen from `p`, from the minimal tangent cone (apex `p`) and the occlusion formula
/// `profile`. Multiply the unshadowed light integral by it (seed 001 eq. 2).
///
/// # Errors
///
/// As [`minimal_tangent_cone`]; `p` inside the light's sphere ([`GeomError::Degenerate`]).
pub fn fast_soft_shadow<S: Sdf + ?Sized>(
    sdf: &S,
    p: DVec3,
    light: &SphereLight,
    search: &ConeSearch,
    profile: Profile,
) -> Result<f64, GeomError> {
    let cone = shadow_cone(p, light)?;
    if light_buried(sdf, light)? {
        return Ok(0.0);
    }
    let min = minimal_tangent_cone(
        sdf,
        p,
        cone.axis,
        0.0,
        cone.tan_half_angle,
        cone.t_end,
        search,
    )?;
    Ok(match profile {
        Profile::Chord => chord_visibility(min.m),
        Profile::Smoothstep => smoothstep_visibility(min.m),
    })
}

/// The settings of the Quilez soft shadows.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct QuilezSettings {
    /// Where the march starts along the ray (`> 0`), as [`ConeSearch::t_min`].
    pub t_min: f64,
    /// A field value below this is a hit, visibility 0 (`> 0`).
    pub hit_distance: f64,
    /// The largest number of field evaluations (`>= 1`); a march that runs out returns the
    /// visibility found so far.
    pub max_steps: u32,
}

impl QuilezSettings {
    /// `t_min`, hits below `1e-3 * t_min`, at most 512 steps.
    #[must_use]
    pub fn new(t_min: f64) -> Self {
        QuilezSettings {
            t_min,
            hit_distance: 1e-3 * t_min,
            max_steps: 512,
        }
    }

    fn validate(&self) -> Result<(), GeomError> {
        check_positive(
            "quilez t_min",
            self.t_min,
            "sdf: the soft shadow t_min must be > 0",
        )?;
        check_positive(
            "quilez hit distance",
            self.hit_distance,
            "sdf: the soft shadow hit distance must be > 0",
        )?;
        if self.max_steps == 0 {
            return Err(GeomError::Degenerate(
                "sdf: the soft shadow needs at least one step",
            ));
        }
        Ok(())
    }
}

/// The Quilez soft shadow \[Qui10\] of a spherical light: sphere tracing from `p` toward the
/// center, `res = min(res, k h / t)` over the march with `k = 1 / tan alpha` (the light's
/// angular size sets the penumbra), 0 at a hit. The result, in `[0, 1]`, is the visibility.
///
/// # Errors
///
/// Invalid settings or input, `p` inside the light's sphere, as [`fast_soft_shadow`].
pub fn quilez_shadow<S: Sdf + ?Sized>(
    sdf: &S,
    p: DVec3,
    light: &SphereLight,
    settings: &QuilezSettings,
) -> Result<f64, GeomError> {
    quilez_march(sdf, p, light, settings, false)
}

/// Aaltonen's improved Quilez soft shadow \[Aal18\]: as [`quilez_shadow`], but each step
/// estimates the closest approach between the current and the previous unbounding spheres
/// (their intersection circle, at `y = h^2 / (2 h_prev)` back along the ray and distance
/// `sqrt(h^2 - y^2)` from it) instead of using the sphere's center, which removes the banding
/// of the classic version.
///
/// # Errors
///
/// As [`quilez_shadow`].
pub fn quilez_improved_shadow<S: Sdf + ?Sized>(
    sdf: &S,
    p: DVec3,
    light: &SphereLight,
    settings: &QuilezSettings,
) -> Result<f64, GeomError> {
    quilez_march(sdf, p, light, settings, true)
}

fn quilez_march<S: Sdf + ?Sized>(
    sdf: &S,
    p: DVec3,
    light: &SphereLight,
    settings: &QuilezSettings,
    improved: bool,
) -> Result<f64, GeomError> {
    settings.validate()?;
    let cone = shadow_cone(p, light)?;
    if light_buried(sdf, light)? {
        return Ok(0.0);
    }
    let k = 1.0 / cone.tan_half_angle;
    let mut res: f64 = 1.0;
    let mut t = settings.t_min;
    let mut previous = f64::INFINITY;
    for _ in 0..settings.max_steps {
        if t > cone.t_end {
            break;
        }
        let h = eval(sdf, p + t * cone.axis)?;
        if h < settings.hit_distance {
            return Ok(0.0);
        }
        if improved {
            // The two spheres meet in a circle at y back along the ray, of radius d. A step
            // straight away from a surface doubles h (h <= 2 h_prev by the Lipschitz bound), the
            // previous sphere then touches the current one from inside (y = h, d = 0) and there is
            // no circle to estimate from: the classic estimate is used there.
            let y = h * h / (2.0 * previous);
            let along = t - y;
            if y < h && along > 0.0 {
                let d = sqrt(h * h - y * y);
                res = res.min(k * d / along);
            } else {
                res = res.min(k * h / t);
            }
            previous = h;
        } else {
            res = res.min(k * h / t);
        }
        t += h;
    }
    Ok(res.clamp(0.0, 1.0))
}

/// The proxy occluder of seed 001 section 4.2: which directions from the shading point it
/// leaves visible.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ProxyOccluder {
    /// Nothing comes near the cone: every direction is visible.
    Clear,
    /// The cone is covered: no direction is visible.
    Covered,
    /// The directions `l` with `normal . l >= 0` are visible: the occluder is replaced by the
    /// plane through the shading point that contains the nearest surface point `s` and the
    /// direction `n x v` (`n` the surface normal at the minimum, `v` the cone axis), the
    /// surface's edge line across the cone as seed 001 section 4 assumes it. `normal` is a unit
    /// vector oriented away from the occluder.
    HalfSpace {
        /// Unit normal of the plane, pointing to the visible side.
        normal: DVec3,
    },
}

impl ProxyOccluder {
    /// Whether direction `l` is visible past the proxy.
    #[must_use]
    pub fn visible(&self, l: DVec3) -> bool {
        match *self {
            ProxyOccluder::Clear => true,
            ProxyOccluder::Covered => false,
            ProxyOccluder::HalfSpace { normal } => normal.dot(l) >= 0.0,
        }
    }
}

/// The proxy occluder (seed 001 section 4.2) between `p` and a light bounded by `bound`, with
/// the relative distance `m` it was built from.
///
/// The nearest surface point at the minimum `q = p + t v` of Alg. 2 is `s = q - f(q) n`, with
/// `n` the field's normal there ([`normal`], step `1e-3 rho(t)`). Should `n` be (nearly) along
/// the axis, or the plane through `p`, `s` and `n x v` (nearly) contain `n`, the chord of the
/// cross-section is used instead: the plane through `p` whose trace on the cross-section at `t`
/// is the line at signed distance `m rho` from the axis, perpendicular to `n`'s projection.
/// Where the axis is inside the occluder at the minimum (`f(q) < 0`), `n` belongs to the face
/// the axis pierced rather than to the edge across the cone; the chord's direction is then
/// estimated from the field at 8 points around the cross-section's circle (its first Fourier
/// component), with the same offset `m rho`.
///
/// # Errors
///
/// As [`fast_soft_shadow`].
pub fn proxy_occluder<S: Sdf + ?Sized>(
    sdf: &S,
    p: DVec3,
    bound: &SphereLight,
    search: &ConeSearch,
) -> Result<(ProxyOccluder, ConeMinimum), GeomError> {
    let cone = shadow_cone(p, bound)?;
    let min = minimal_tangent_cone(
        sdf,
        p,
        cone.axis,
        0.0,
        cone.tan_half_angle,
        cone.t_end,
        search,
    )?;
    if light_buried(sdf, bound)? || min.m <= -1.0 {
        return Ok((ProxyOccluder::Covered, min));
    }
    if min.m >= 1.0 {
        return Ok((ProxyOccluder::Clear, min));
    }
    let v = cone.axis;
    let rho = min.t * cone.tan_half_angle;
    let q = p + min.t * v;
    let all_or_nothing = if min.m >= 0.0 {
        ProxyOccluder::Clear
    } else {
        ProxyOccluder::Covered
    };
    if min.distance < 0.0 {
        // The axis is inside the occluder at the minimum. The nearest surface point then lies
        // on whichever face the axis pierced, not on the edge that bounds the occluder across
        // the cone, so the normal there says nothing about the chord. The chord's direction is
        // taken from the field on the cross-section's circle instead: for a half-plane section
        // the first Fourier component of f around the circle points away from the occluder.
        let (a, b) = v.any_orthonormal_pair();
        let mut toward = glam::DVec3::ZERO;
        for k in 0..CHORD_SAMPLES {
            let angle = 2.0 * core::f64::consts::PI * f64::from(k) / f64::from(CHORD_SAMPLES);
            let (sn, cs) = crate::math::sin_cos(angle);
            let u = cs * a + sn * b;
            toward += eval(sdf, q + rho * u)? * u;
        }
        return Ok((
            chord_proxy(toward, v, min.t, min.m, rho, all_or_nothing),
            min,
        ));
    }
    let Some(n) = normal(sdf, q, 1e-3 * rho) else {
        return Ok((all_or_nothing, min));
    };
    let s = q - min.distance * n;
    let edge = n.cross(v);
    if let Some(g) = (s - p).cross(edge).try_normalize() {
        let along_n = g.dot(n);
        // The plane must separate s from the inside of the occluder (-n from s): require it to
        // be clearly transversal to n before trusting it.
        if along_n.abs() > 1e-3 {
            let normal = if along_n > 0.0 { g } else { -g };
            return Ok((ProxyOccluder::HalfSpace { normal }, min));
        }
    }
    Ok((chord_proxy(n, v, min.t, min.m, rho, all_or_nothing), min))
}

/// Field samples around the cross-section's circle that estimate the chord's direction when
/// the axis is inside the occluder.
const CHORD_SAMPLES: u32 = 8;

/// The chord model: in the cross-section at `t` the occluder's edge is the line at offset
/// `-m rho` from the axis along `n_perp`, the part of `toward` (pointing away from the occluder)
/// perpendicular to the axis `v`. A direction `l` meets that cross-section at
/// `p + (t / (v . l)) l`, whose offset along `n_perp` is `t (n_perp . l) / (v . l)`; it is
/// visible iff that offset exceeds `-m rho`, that is iff `(t n_perp + m rho v) . l >= 0`.
fn chord_proxy(
    toward: DVec3,
    v: DVec3,
    t: f64,
    m: f64,
    rho: f64,
    fallback: ProxyOccluder,
) -> ProxyOccluder {
    let Some(n_perp) = (toward - toward.dot(v) * v).try_normalize() else {
        return fallback;
    };
    match (t * n_perp + m * rho * v).try_normalize() {
        Some(normal) => ProxyOccluder::HalfSpace { normal },
        None => fallback,
    }
}

/// Seed 001 section 4.2 by numerical integration: the integral over the directions `l` toward
/// the light of `weight(l)` times "the ray meets the light" times the proxy's visibility, over
/// `samples` directions spread evenly (a spherical Fibonacci lattice) in the cone tangent to the
/// light's bounding sphere. With `weight(l) = albedo * max(0, n . l) / pi` and unit radiance,
/// this is the diffuse outgoing radiance.
///
/// The lattice is deterministic: the same arguments give the same value, and the error falls
/// like that of a low-discrepancy set (about `1 / samples` for smooth integrands, slower across
/// the light's and the proxy's edges).
///
/// # Errors
///
/// As [`proxy_occluder`]; `samples == 0` ([`GeomError::Degenerate`]).
pub fn proxy_integral<S, L, W>(
    sdf: &S,
    p: DVec3,
    light: &L,
    weight: W,
    samples: u32,
    search: &ConeSearch,
) -> Result<f64, GeomError>
where
    S: Sdf + ?Sized,
    L: AreaLight + ?Sized,
    W: Fn(DVec3) -> f64,
{
    if samples == 0 {
        return Err(GeomError::Degenerate(
            "sdf: proxy integration needs at least one sample",
        ));
    }
    let bound = light.bounding_sphere();
    let cone = shadow_cone(p, &bound)?;
    let (proxy, _) = proxy_occluder(sdf, p, &bound, search)?;
    if proxy == ProxyOccluder::Covered {
        return Ok(0.0);
    }
    let frame = basis(cone.axis);
    // cos alpha = sqrt(1 - sin^2 alpha); the cap's solid angle is 2 pi (1 - cos alpha), with
    // 1 - cos alpha written as sin^2 / (1 + cos) to keep small caps accurate.
    let sin_a = cone.sin_half_angle;
    let cos_a = sqrt((1.0 - sin_a * sin_a).max(0.0));
    let one_minus_cos = sin_a * sin_a / (1.0 + cos_a);
    let solid_angle = 2.0 * core::f64::consts::PI * one_minus_cos;
    // Golden-angle increment of the spherical Fibonacci lattice.
    let golden = core::f64::consts::PI * (3.0 - sqrt(5.0));
    let mut sum = 0.0;
    for i in 0..samples {
        let u = (f64::from(i) + 0.5) / f64::from(samples);
        let one_minus_z = u * one_minus_cos;
        let z = 1.0 - one_minus_z;
        let r = sqrt((one_minus_z * (2.0 - one_minus_z)).max(0.0));
        let (s, c) = crate::math::sin_cos(golden * f64::from(i));
        let l = frame * DVec3::new(r * c, r * s, z);
        if proxy.visible(l) && light.emits_toward(p, l) {
            sum += weight(l);
        }
    }
    Ok(sum * solid_angle / f64::from(samples))
}

/// Seed 001 section 4.2 for a quad light, integrated exactly: `(1 / pi)` times the integral of
/// `max(0, n . l)` over the directions of the quad left visible by the proxy occluder (the
/// quad's spherical polygon clipped to the proxy's hemisphere, integrated with
/// [`clamped_cosine_integral`]). Times albedo and radiance, this is the diffuse outgoing
/// radiance. Zero when `p` is behind the quad's emitting side.
///
/// # Errors
///
/// As [`proxy_occluder`]; a zero or non-finite `n`; a shading point (nearly) in the quad's
/// plane, where its spherical polygon degenerates.
pub fn proxy_quad_integral<S: Sdf + ?Sized>(
    sdf: &S,
    p: DVec3,
    n: DVec3,
    quad: &QuadLight,
    search: &ConeSearch,
) -> Result<f64, GeomError> {
    let n = check_direction("surface normal", n)?;
    check_point("shading point", p)?;
    if (p - quad.center).dot(quad.normal) <= 0.0 {
        return Ok(0.0);
    }
    let (proxy, _) = proxy_occluder(sdf, p, &quad.bounding_sphere(), search)?;
    // Local frame with the normal on +z, where clamped_cosine_integral measures.
    let to_local = basis(n).transpose();
    // The corners run counter-clockwise seen from the emitting side, that is from p, inside
    // the sphere of directions; the convention wants them counter-clockwise seen from outside
    // it, so the ring is reversed.
    let ring: alloc::vec::Vec<DVec3> = quad
        .corners()
        .iter()
        .rev()
        .map(|&c| to_local * (c - p))
        .collect();
    let poly = SphericalPolygon::new(alloc::vec![ring])?;
    let visible = match proxy {
        ProxyOccluder::Clear => poly,
        ProxyOccluder::Covered => return Ok(0.0),
        ProxyOccluder::HalfSpace { normal } => poly.try_clip_to_hemisphere(to_local * normal)?,
    };
    Ok(clamped_cosine_integral(&visible))
}

/// An orthonormal basis (as matrix columns) whose third axis is the unit `z`.
fn basis(z: DVec3) -> DMat3 {
    let (x, y) = z.any_orthonormal_pair();
    DMat3::from_cols(x, y, z)
}
