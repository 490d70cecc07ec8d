//! The GGX microfacet BRDF with height-correlated Smith masking, and its visible-normal sampler.
//!
//! This is the BRDF that the LTC tables approximate (\[HDHN16\] §4 fits GGX; we use the
//! height-correlated form of the Smith masking-shadowing term from \[Hei14\]). Everything here is
//! expressed in the shading frame: the surface normal is `+z`, and directions are unit vectors
//! pointing away from the surface. The Fresnel factor is left out (it is handled by the tables'
//! Schlick weights, see [`LtcLookup::specular_scale`](super::LtcLookup::specular_scale)).
//!
//! The functions are meant for hot loops (Monte Carlo references, the table fitter), so they do not
//! return `Result`: directions below the horizon give `0.0`, `alpha` is clamped to at least
//! [`GGX_MIN_ALPHA`], and NaN input propagates to a NaN output (it never panics).
//!
//! # References
//!
//! - \[HDHN16\] E. Heitz, J. Dupuy, S. Hill, D. Neubelt. *Real-time polygonal-light shading with
//!   linearly transformed cosines.* ACM TOG 35(4), 2016.
//! - \[Hei14\] E. Heitz. *Understanding the masking-shadowing function in microfacet-based BRDFs.*
//!   JCGT 3(2), 2014.
//! - \[Hei18\] E. Heitz. *Sampling the GGX distribution of visible normals.* JCGT 7(4), 2018.
//! - \[WMLT07\] B. Walter, S. Marschner, H. Li, K. Torrance. *Microfacet models for refraction through
//!   rough surfaces.* EGSR 2007.

use glam::{DVec2, DVec3};

use crate::math::{sin_cos, sqrt};

/// The smallest GGX roughness `alpha` the functions in this module use; smaller values are clamped
/// to it so that the distribution stays a function (at `alpha = 0` it is a Dirac delta).
pub const GGX_MIN_ALPHA: f64 = 1e-7;

#[inline]
fn clamp_alpha(alpha: f64) -> f64 {
    // `max` would turn NaN into the bound; keep NaN visible instead.
    if alpha < GGX_MIN_ALPHA {
        GGX_MIN_ALPHA
    } else {
        alpha
    }
}

/// The GGX normal distribution `D(h)` (\[WMLT07\] eq. 33) for a unit half vector `h`.
///
/// Written as `alpha^2 / (pi (h_x^2 + h_y^2 + alpha^2 h_z^2)^2)`, which equals the textbook
/// `alpha^2 / (pi ((alpha^2 - 1) cos^2 + 1)^2)` for unit `h` but does not cancel catastrophically
/// near the peak when `alpha` is tiny.
///
/// # Examples
///
/// ```
/// use arealight::glam::DVec3;
/// use arealight::ltc::ggx_ndf;
/// // At normal incidence D = 1 / (pi alpha^2).
/// let d = ggx_ndf(DVec3::Z, 0.5);
/// assert!((d - 1.0 / (core::f64::consts::PI * 0.25)).abs() < 1e-12);
/// ```
#[must_use]
pub fn ggx_ndf(h: DVec3, alpha: f64) -> f64 {
    let a2 = clamp_alpha(alpha) * clamp_alpha(alpha);
    let t = h.x * h.x + h.y * h.y + a2 * h.z * h.z;
    a2 / (core::f64::consts::PI * t * t)
}

/// `sqrt(c^2 (1 - alpha^2) + alpha^2)` = `c (1 + 2 Lambda(c))`, the building block of the Smith
/// terms (the GGX `Lambda` of \[Hei14\]), finite and well-behaved at grazing `c -> 0`.
#[inline]
fn smith_s(c: f64, a2: f64) -> f64 {
    sqrt(c * c * (1.0 - a2) + a2)
}

/// The cosine-weighted GGX BRDF `f(v, l) cos(theta_l)` without Fresnel, with height-correlated
/// Smith masking-shadowing `G2 = 1 / (1 + Lambda(v) + Lambda(l))` (\[Hei14\]).
///
/// `v` (towards the viewer) and `l` (towards the light) are unit vectors in the shading frame
/// (normal `+z`). Returns `0.0` when either lies on or below the horizon. The value is computed as
/// `D(h) * V * cos(theta_l)` with the visibility term
/// `V = G2 / (4 cos_v cos_l) = 0.5 / (cos_l S(cos_v) + cos_v S(cos_l))`, which stays finite at
/// grazing angles.
///
/// The BRDF itself is reciprocal: `ggx_brdf_cos(v, l, a) / l.z == ggx_brdf_cos(l, v, a) / v.z`.
///
/// # Examples
///
/// ```
/// use arealight::glam::DVec3;
/// use arealight::ltc::ggx_brdf_cos;
/// let v = DVec3::new(0.6, 0.0, 0.8);
/// let mirror = DVec3::new(-0.6, 0.0, 0.8);
/// // The lobe peaks around the mirror direction ...
/// assert!(ggx_brdf_cos(v, mirror, 0.2) > ggx_brdf_cos(v, DVec3::Z, 0.2));
/// // ... and vanishes below the horizon.
/// assert_eq!(ggx_brdf_cos(v, -DVec3::Z, 0.2), 0.0);
/// ```
#[must_use]
pub fn ggx_brdf_cos(v: DVec3, l: DVec3, alpha: f64) -> f64 {
    // Below the horizon. (NaN compares false and falls through to a NaN result.)
    if v.z <= 0.0 || l.z <= 0.0 {
        return 0.0;
    }
    let alpha = clamp_alpha(alpha);
    let a2 = alpha * alpha;
    let hv = v + l;
    let h = hv / sqrt(hv.length_squared());
    let d = ggx_ndf(h, alpha);
    let vis = 0.5 / (l.z * smith_s(v.z, a2) + v.z * smith_s(l.z, a2));
    d * vis * l.z
}

/// Samples a light direction `l` for view `v` by reflecting `v` about a GGX visible normal
/// (\[Hei18\], with the sampled normal distribution `D_v(h) = G1(v) max(0, v.h) D(h) / cos_v`).
///
/// `v` must be a unit vector above the horizon (`v.z > 0`); `u` holds two uniform numbers in
/// `[0, 1)`. The result is a unit vector; it can lie below the horizon (where the BRDF is zero),
/// and its density over the whole sphere is [`ggx_vndf_pdf`], which integrates to one.
///
/// # Examples
///
/// ```
/// use arealight::glam::{DVec2, DVec3};
/// use arealight::ltc::{ggx_brdf_cos, ggx_sample_vndf, ggx_vndf_pdf};
/// let v = DVec3::new(0.6, 0.0, 0.8);
/// let l = ggx_sample_vndf(v, 0.3, DVec2::new(0.25, 0.75));
/// assert!((l.length() - 1.0).abs() < 1e-12);
/// // Monte Carlo weight of the sample: f cos / pdf = G2 / G1 <= 1.
/// let w = ggx_brdf_cos(v, l, 0.3) / ggx_vndf_pdf(v, l, 0.3);
/// assert!((0.0..=1.0).contains(&w));
/// ```
#[must_use]
pub fn ggx_sample_vndf(v: DVec3, alpha: f64, u: DVec2) -> DVec3 {
    let alpha = clamp_alpha(alpha);
    // Stretch the view direction into the configuration where the microsurface is a hemisphere.
    let vh = DVec3::new(alpha * v.x, alpha * v.y, v.z);
    let vh = vh / sqrt(vh.length_squared());
    // Orthonormal basis around vh ([Hei18] listing 1).
    let lensq = vh.x * vh.x + vh.y * vh.y;
    let t1 = if lensq > 0.0 {
        DVec3::new(-vh.y, vh.x, 0.0) / sqrt(lensq)
    } else {
        DVec3::X
    };
    let t2 = vh.cross(t1);
    // Uniform point on the projected disk, warped to the visible half of it.
    let r = sqrt(u.x);
    let (s_phi, c_phi) = sin_cos(2.0 * core::f64::consts::PI * u.y);
    let p1 = r * c_phi;
    let mut p2 = r * s_phi;
    let s = 0.5 * (1.0 + vh.z);
    p2 = (1.0 - s) * sqrt((1.0 - p1 * p1).max(0.0)) + s * p2;
    let nh = p1 * t1 + p2 * t2 + sqrt((1.0 - p1 * p1 - p2 * p2).max(0.0)) * vh;
    // Unstretch back to the ellipsoid's normal.
    let ne = DVec3::new(alpha * nh.x, alpha * nh.y, nh.z.max(0.0));
    let len2 = ne.length_squared();
    let h = if len2 > 0.0 {
        ne / sqrt(len2)
    } else {
        DVec3::Z
    };
    let l = 2.0 * v.dot(h) * h - v;
    l / sqrt(l.length_squared())
}

/// The density (per unit solid angle, over the whole sphere) with which [`ggx_sample_vndf`]
/// produces `l` for view `v`: `G1(v) D(h) / (4 cos_v)` (the visible-normal density of \[Hei18\]
/// times the reflection Jacobian `1 / (4 v.h)`), evaluated as `D(h) / (2 (cos_v + S(cos_v)))`.
///
/// Returns `0.0` when `v` is not above the horizon or `l` is not in the sampled set (`v.h <= 0`).
///
/// # Examples
///
/// ```
/// use arealight::glam::DVec3;
/// use arealight::ltc::ggx_vndf_pdf;
/// // At normal incidence the sampler draws the normal distribution itself:
/// // pdf(l) = D(h) (h.z) / (4 v.h), with h = z for l = z.
/// let d = arealight::ltc::ggx_ndf(DVec3::Z, 0.4);
/// assert!((ggx_vndf_pdf(DVec3::Z, DVec3::Z, 0.4) - d / 4.0).abs() < 1e-12);
/// ```
#[must_use]
pub fn ggx_vndf_pdf(v: DVec3, l: DVec3, alpha: f64) -> f64 {
    if v.z <= 0.0 {
        return 0.0;
    }
    let alpha = clamp_alpha(alpha);
    let hv = v + l;
    let len2 = hv.length_squared();
    if len2 <= 0.0 {
        return 0.0;
    }
    let h = hv / sqrt(len2);
    if v.dot(h) <= 0.0 || h.z <= 0.0 {
        return 0.0;
    }
    ggx_ndf(h, alpha) / (2.0 * (v.z + smith_s(v.z, alpha * alpha)))
}

/// One sample of the GGX reflectance estimator for view `v`: the direction `l` that
/// [`ggx_sample_vndf`] draws from `u`, with its weight `f(v, l) cos(theta_l) / pdf(l)` (which is
/// `G2 / G1`, in `[0, 1]`, \[Hei18\]). `None` when `l` is below the horizon or has no density:
/// its weight is zero there.
///
/// With `u` uniform on the unit square, the mean of `w g(l)` (counting `None` as zero) is the
/// integral of `f cos g` over the hemisphere: for `g = 1` the directional albedo, for the
/// indicator of a light the brute-force reflectance the LTC tables are checked against.
///
/// # Examples
///
/// ```
/// use arealight::glam::{DVec2, DVec3};
/// use arealight::ltc::ggx_vndf_weight;
/// let v = DVec3::new(0.6, 0.0, 0.8);
/// let (l, w) = ggx_vndf_weight(v, 0.3, DVec2::new(0.25, 0.75)).unwrap();
/// assert!(l.z > 0.0 && (0.0..=1.0).contains(&w));
/// ```
#[must_use]
pub fn ggx_vndf_weight(v: DVec3, alpha: f64, u: DVec2) -> Option<(DVec3, f64)> {
    let l = ggx_sample_vndf(v, alpha, u);
    let pdf = ggx_vndf_pdf(v, l, alpha);
    // Written so that a NaN density is skipped too.
    if !(pdf > 0.0 && l.z > 0.0) {
        return None;
    }
    Some((l, ggx_brdf_cos(v, l, alpha) / pdf))
}
