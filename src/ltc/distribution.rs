//! The linearly transformed cosine distribution itself (\[HDHN16\] §3).
//!
//! A linearly transformed cosine (LTC) is the distribution of `w = M w_o / |M w_o|` when `w_o` is
//! drawn from the clamped cosine `D_o(w_o) = max(0, z_o) / pi`. Its density is
//! (\[HDHN16\] §3, with the Jacobian of the normalised linear map)
//!
//! ```text
//! D(w) = D_o(w_o) |det M^-1| / |M^-1 w|^3,   w_o = M^-1 w / |M^-1 w|
//! ```
//!
//! and, because the transform maps spherical polygons to spherical polygons, its integral over a
//! polygon `P` equals the clamped-cosine integral over `M^-1 P` (\[HDHN16\] §3), which has a
//! closed form.
//!
//! # References
//!
//! - \[HDHN16\] E. Heitz, J. Dupuy, S. Hill, D. Neubelt. *Real-time polygonal-light shading with
//!   linearly transformed cosines.* ACM TOG 35(4), 2016.

use glam::{DMat3, DVec2, DVec3};

use crate::GeomError;
use crate::math::{sin_cos, sqrt};

/// A linearly transformed cosine distribution on the unit sphere (\[HDHN16\] §3).
///
/// Holds the matrix `M` (cosine space -> distribution space) and its inverse. Scaling `M` by a
/// positive factor does not change the distribution.
///
/// # Examples
///
/// ```
/// use arealight::glam::{DMat3, DVec2, DVec3};
/// use arealight::ltc::Ltc;
/// // Squash the cosine lobe towards +z: a narrower, glossier lobe.
/// let ltc = Ltc::new(DMat3::from_diagonal(DVec3::new(0.2, 0.2, 1.0))).unwrap();
/// assert!(ltc.density(DVec3::Z) > 1.0 / core::f64::consts::PI);
/// let w = ltc.sample(DVec2::new(0.3, 0.6));
/// assert!(w.z > 0.0 && (w.length() - 1.0).abs() < 1e-12);
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Ltc {
    m: DMat3,
    m_inv: DMat3,
    det_inv_abs: f64,
}

/// Relative threshold below which a matrix counts as singular: `|det M| <= EPS * |M|_F^3`.
const SINGULAR_EPS: f64 = 1e-14;

/// Checks `m`, an argument named `what` (or computed from one: then `what` says so).
fn check_matrix(m: DMat3, what: &'static str) -> Result<(), GeomError> {
    let cols = m.to_cols_array();
    if cols.iter().any(|c| !c.is_finite()) {
        return Err(GeomError::NonFiniteArgument { what });
    }
    let frob2: f64 = cols.iter().map(|c| c * c).sum();
    let scale = frob2 * sqrt(frob2);
    // Written so that a NaN or infinite determinant (overflowing entries) also counts as singular.
    let regular = m.determinant().abs() > SINGULAR_EPS * scale && scale.is_finite();
    if !regular {
        return Err(GeomError::Degenerate(
            "LTC matrix is singular (or nearly so); it must map the sphere onto itself",
        ));
    }
    Ok(())
}

impl Ltc {
    /// Builds the LTC with transform `m` (cosine space -> distribution space).
    ///
    /// # Errors
    ///
    /// [`GeomError::NonFiniteArgument`] if an entry of `m` is NaN or infinite,
    /// [`GeomError::Degenerate`] if `m` is singular relative to its scale.
    pub fn new(m: DMat3) -> Result<Self, GeomError> {
        check_matrix(m, "LTC matrix")?;
        let m_inv = m.inverse();
        // Regular relative to its scale bounds the inverse's entries by `1e14 / |m|`, finite for
        // every `m` whose determinant does not underflow; checked all the same.
        check_matrix(m_inv, "LTC matrix (its inverse)")?;
        Ok(Self {
            m,
            m_inv,
            det_inv_abs: m_inv.determinant().abs(),
        })
    }

    /// Builds the LTC from the inverse transform `m_inv` (distribution space -> cosine space), the
    /// matrix the tables store (\[HDHN16\] §4).
    ///
    /// # Errors
    ///
    /// As for [`Ltc::new`].
    pub fn from_inverse(m_inv: DMat3) -> Result<Self, GeomError> {
        check_matrix(m_inv, "inverse LTC matrix")?;
        let m = m_inv.inverse();
        check_matrix(m, "inverse LTC matrix (its inverse)")?;
        Ok(Self {
            m,
            m_inv,
            det_inv_abs: m_inv.determinant().abs(),
        })
    }

    /// The transform `M` from cosine space to distribution space.
    #[must_use]
    pub fn matrix(&self) -> DMat3 {
        self.m
    }

    /// The inverse transform `M^-1`, which maps a polygon into cosine space for integration.
    #[must_use]
    pub fn inverse(&self) -> DMat3 {
        self.m_inv
    }

    /// The density `D(w)` per unit solid angle at the unit direction `w` (\[HDHN16\] §3).
    /// It integrates to one over the sphere. Returns NaN for non-finite `w`, `0.0` for `w = 0`.
    #[must_use]
    pub fn density(&self, w: DVec3) -> f64 {
        let wo = self.m_inv * w;
        let len2 = wo.length_squared();
        if len2.is_nan() {
            return f64::NAN;
        }
        if len2 == 0.0 {
            return 0.0;
        }
        let len = sqrt(len2);
        let cos_o = wo.z / len;
        if cos_o <= 0.0 {
            return 0.0;
        }
        cos_o / core::f64::consts::PI * self.det_inv_abs / (len2 * len)
    }

    /// Draws a direction from the distribution: cosine-samples `w_o` with the two uniform numbers
    /// in `u` (in `[0, 1)`) and returns `M w_o / |M w_o|`. Its density is [`Ltc::density`].
    #[must_use]
    pub fn sample(&self, u: DVec2) -> DVec3 {
        let wo = cosine_sample(u);
        let w = self.m * wo;
        w / sqrt(w.length_squared())
    }

    /// The probability mass of the distribution above the horizon `z > 0`.
    ///
    /// The set `{w : (M w_o).z > 0}` is the half-space `w_o . n > 0` with `n = M^T e_z`; the clamped
    /// cosine's mass in a half-space whose normal makes angle `phi` with `+z` is
    /// `(1 + cos phi) / 2` (the form factor of a half-sphere of directions).
    ///
    /// # Examples
    ///
    /// ```
    /// use arealight::glam::DMat3;
    /// use arealight::ltc::Ltc;
    /// let tilted = Ltc::new(DMat3::from_rotation_y(core::f64::consts::FRAC_PI_2)).unwrap();
    /// assert!((tilted.upper_hemisphere_mass() - 0.5).abs() < 1e-12);
    /// ```
    #[must_use]
    pub fn upper_hemisphere_mass(&self) -> f64 {
        let n = self.m.transpose() * DVec3::Z;
        0.5 * (1.0 + n.z / sqrt(n.length_squared()))
    }
}

/// Cosine-weighted direction on the upper hemisphere from two uniform numbers (density
/// `z / pi`); concentric-free polar mapping, continuous in `u`.
#[must_use]
pub(crate) fn cosine_sample(u: DVec2) -> DVec3 {
    let r = sqrt(u.x.clamp(0.0, 1.0));
    let (s, c) = sin_cos(2.0 * core::f64::consts::PI * u.y);
    DVec3::new(r * c, r * s, sqrt((1.0 - u.x).clamp(0.0, 1.0)))
}
