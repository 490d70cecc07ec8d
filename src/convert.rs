//! Conversions at the boundary: the vector types a renderer already has, accepted where the
//! shading entry points take a point or a direction.
//!
//! The crate computes in `f64` throughout (the exactness of its predicates and integrals is
//! argued in `f64`), so an `f32` renderer's `Vec3`, `Vec3A` or `[f32; 3]` is widened once when it
//! enters. Widening `f32` to `f64` is exact, so a call with `f32` arguments returns bit for bit
//! what the same call with the widened `DVec3` arguments returns.

use glam::{DVec3, Vec3, Vec3A};

/// A 3-vector the shading entry points accept for a point, a normal or a view direction:
/// [`DVec3`], glam's `f32` [`Vec3`] and [`Vec3A`], `[f32; 3]`, `[f64; 3]`, and references to
/// any of them.
///
/// Implemented by exact widening (`f32` to `f64` loses nothing); results are then returned as
/// `f64` ([`DVec3`]; `DVec3::as_vec3` narrows them for an `f32` framebuffer).
///
/// # Examples
///
/// ```
/// use arealight::IntoDVec3;
/// use arealight::glam::{DVec3, Vec3};
/// assert_eq!(Vec3::new(0.1, 2.0, -3.5).into_dvec3(), DVec3::new(0.1f32 as f64, 2.0, -3.5));
/// assert_eq!([1.0f32, 2.0, 3.0].into_dvec3(), DVec3::new(1.0, 2.0, 3.0));
/// ```
pub trait IntoDVec3 {
    /// The vector as a `DVec3` (exact).
    fn into_dvec3(self) -> DVec3;
}

impl IntoDVec3 for DVec3 {
    #[inline]
    fn into_dvec3(self) -> DVec3 {
        self
    }
}

impl IntoDVec3 for Vec3 {
    #[inline]
    fn into_dvec3(self) -> DVec3 {
        self.as_dvec3()
    }
}

impl IntoDVec3 for Vec3A {
    #[inline]
    fn into_dvec3(self) -> DVec3 {
        self.as_dvec3()
    }
}

impl IntoDVec3 for [f32; 3] {
    #[inline]
    fn into_dvec3(self) -> DVec3 {
        DVec3::new(f64::from(self[0]), f64::from(self[1]), f64::from(self[2]))
    }
}

impl IntoDVec3 for [f64; 3] {
    #[inline]
    fn into_dvec3(self) -> DVec3 {
        DVec3::from_array(self)
    }
}

impl<T: IntoDVec3 + Copy> IntoDVec3 for &T {
    #[inline]
    fn into_dvec3(self) -> DVec3 {
        (*self).into_dvec3()
    }
}
