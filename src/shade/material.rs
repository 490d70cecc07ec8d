//! Surface materials: Lambertian diffuse plus GGX specular with Schlick's Fresnel.

use glam::DVec3;

use crate::GeomError;
use crate::ltc::{GGX_MIN_ALPHA, ggx_brdf_cos};

/// A surface material: Lambertian diffuse with RGB `albedo`, plus GGX specular with RGB
/// reflectance at normal incidence `f0` and perceptual `roughness` (GGX `alpha = roughness^2`).
///
/// The BRDF is `albedo / pi + F(v.h) * f_ggx(v, l)`, with Schlick's
/// `F = f0 + (1 - f0) (1 - v.h)^5` and `f_ggx` the Fresnel-free GGX BRDF of
/// [`ggx_brdf_cos`] (height-correlated Smith masking). The two lobes are simply added, as in
/// seed 000 (section 4) and the LTC paper; energy conservation is the caller's choice of albedo.
///
/// # Examples
///
/// ```
/// use arealight::glam::DVec3;
/// use arealight::shade::Material;
/// let m = Material::new(DVec3::splat(0.5), DVec3::splat(0.04), 0.4)?;
/// assert!((m.alpha() - 0.16).abs() < 1e-15);
/// assert!(matches!(
///     Material::new(DVec3::splat(-0.1), DVec3::ZERO, 0.5),
///     Err(arealight::GeomError::OutOfRange { what: "material albedo", .. })
/// ));
/// # Ok::<(), arealight::GeomError>(())
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Material {
    albedo: DVec3,
    f0: DVec3,
    roughness: f64,
}

impl Material {
    /// Builds a material.
    ///
    /// # Errors
    ///
    /// [`GeomError::OutOfRange`] when a component of `albedo` or `f0` is not in `[0, 1]` or
    /// `roughness` is not in `[0, 1]` (NaN included).
    pub fn new(albedo: DVec3, f0: DVec3, roughness: f64) -> Result<Self, GeomError> {
        for (what, v) in [("material albedo", albedo), ("material f0", f0)] {
            for c in v.to_array() {
                if !(0.0..=1.0).contains(&c) {
                    return Err(GeomError::OutOfRange {
                        what,
                        value: c,
                        limit: 1.0,
                    });
                }
            }
        }
        if !(0.0..=1.0).contains(&roughness) {
            return Err(GeomError::OutOfRange {
                what: "material roughness",
                value: roughness,
                limit: 1.0,
            });
        }
        Ok(Material {
            albedo,
            f0,
            roughness,
        })
    }

    /// A purely diffuse material.
    ///
    /// # Errors
    ///
    /// As [`Material::new`].
    pub fn diffuse(albedo: DVec3) -> Result<Self, GeomError> {
        Material::new(albedo, DVec3::ZERO, 1.0)
    }

    /// The diffuse albedo (RGB).
    #[must_use]
    pub fn albedo(&self) -> DVec3 {
        self.albedo
    }

    /// The specular reflectance at normal incidence (RGB).
    #[must_use]
    pub fn f0(&self) -> DVec3 {
        self.f0
    }

    /// The perceptual roughness.
    #[must_use]
    pub fn roughness(&self) -> f64 {
        self.roughness
    }

    /// The GGX `alpha = roughness^2`, at least [`GGX_MIN_ALPHA`].
    #[must_use]
    pub fn alpha(&self) -> f64 {
        (self.roughness * self.roughness).max(GGX_MIN_ALPHA)
    }

    /// Whether the specular lobe contributes at all (`f0` not all zero).
    #[must_use]
    pub fn has_specular(&self) -> bool {
        self.f0 != DVec3::ZERO
    }

    /// The true BRDF times the cosine, `f(v, l) cos(theta_l)` per RGB channel, for unit `v`, `l`
    /// in the shading frame (normal `+z`); zero below the horizon. This is the ground truth the
    /// LTC evaluation approximates.
    #[must_use]
    pub fn eval_cos(&self, v: DVec3, l: DVec3) -> DVec3 {
        if l.z <= 0.0 || v.z <= 0.0 {
            return DVec3::ZERO;
        }
        let diffuse = self.albedo * (l.z / core::f64::consts::PI);
        if !self.has_specular() {
            return diffuse;
        }
        let h = (v + l).normalize_or_zero();
        let m = (1.0 - v.dot(h)).clamp(0.0, 1.0);
        let w = m * m * m * m * m;
        let fresnel = self.f0 + (DVec3::ONE - self.f0) * w;
        diffuse + fresnel * ggx_brdf_cos(v, l, self.alpha())
    }
}
