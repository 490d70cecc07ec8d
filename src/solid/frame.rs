//! The local shading frame of a point, in which silhouettes are projected and the LTC integrals
//! are evaluated.

use glam::{DMat3, DVec3};

use super::mesh::MAX_MESH_COORD;
use crate::GeomError;

/// The unit vector along an argument `v` named `what`: an error for a non-finite vector or one of
/// zero or subnormal length. Scaled by its largest component first, so that no length in between
/// overflows or underflows.
fn direction(v: DVec3, what: &'static str) -> Result<DVec3, GeomError> {
    if !v.is_finite() {
        return Err(GeomError::NonFiniteArgument { what });
    }
    let m = v.abs().max_element();
    if !(m >= f64::MIN_POSITIVE) {
        return Err(GeomError::ZeroLengthArgument { what });
    }
    Ok((v / m).normalize())
}

/// The local shading frame of a point (DESIGN.md): the normal on `+z`, the view direction in the
/// xz-plane with `x >= 0`, right-handed; directions are taken from the shading point.
///
/// # Examples
///
/// ```
/// use arealight::glam::DVec3;
/// use arealight::solid::ShadingFrame;
/// let f = ShadingFrame::new(DVec3::ZERO, DVec3::Y, DVec3::new(0.0, 1.0, 1.0))?;
/// assert!((f.to_local(DVec3::new(0.0, 2.0, 0.0)) - DVec3::new(0.0, 0.0, 2.0)).length() < 1e-15);
/// let v = f.view();
/// assert!(v.y.abs() < 1e-15 && v.x > 0.0 && (v.z - v.x).abs() < 1e-15);
/// # Ok::<(), arealight::GeomError>(())
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ShadingFrame {
    origin: DVec3,
    /// Rows are the tangent, bitangent and normal: `to_local(p) = rot * (p - origin)`.
    rot: DMat3,
    view: DVec3,
}

impl ShadingFrame {
    /// The frame at `point` with surface normal `normal` and direction to the viewer `view`
    /// (neither needs to be normalized; any magnitude from `f64::MIN_POSITIVE` up is fine). A
    /// view along the normal picks an arbitrary tangent; a view below the surface is allowed (the
    /// LTC lookup treats it as grazing).
    ///
    /// # Errors
    ///
    /// Input faults, naming the argument: [`GeomError::NonFiniteArgument`] for a NaN or infinite
    /// point, normal or view; [`GeomError::ZeroLengthArgument`] for a normal or view of zero or
    /// subnormal length; [`GeomError::OutOfRange`] for a point coordinate beyond
    /// [`MAX_MESH_COORD`] (the range of scene geometry).
    pub fn new(point: DVec3, normal: DVec3, view: DVec3) -> Result<Self, GeomError> {
        if !point.is_finite() {
            return Err(GeomError::NonFiniteArgument {
                what: "shading point",
            });
        }
        let m = point.abs().max_element();
        if m > MAX_MESH_COORD {
            return Err(GeomError::OutOfRange {
                what: "shading point coordinate",
                value: m,
                limit: MAX_MESH_COORD,
            });
        }
        let n = direction(normal, "surface normal")?;
        let v = direction(view, "view direction")?;
        // Tangent: the view's component in the surface plane; any tangent for a view along n.
        // (`p * (1 / |p|)` is `try_normalize`'s result, which above 1e-12 always exists.)
        let p = v - n * v.dot(n);
        let len = p.length();
        let t = if len > 1e-12 {
            p * len.recip()
        } else {
            n.any_orthonormal_vector()
        };
        let b = n.cross(t);
        let rot = DMat3::from_cols(t, b, n).transpose();
        let local_v = rot * v;
        // Exactly in the xz-plane, x >= 0, as the LTC tables assume.
        let view = DVec3::new(local_v.x.max(0.0), 0.0, local_v.z).normalize();
        Ok(ShadingFrame {
            origin: point,
            rot,
            view,
        })
    }

    /// The shading point.
    #[must_use]
    pub fn origin(&self) -> DVec3 {
        self.origin
    }

    /// The vector from the shading point to the world point `p`, in the local frame.
    #[must_use]
    pub fn to_local(&self, p: DVec3) -> DVec3 {
        self.rot * (p - self.origin)
    }

    /// A world direction in the local frame.
    #[must_use]
    pub fn dir_to_local(&self, d: DVec3) -> DVec3 {
        self.rot * d
    }

    /// A local direction in world coordinates.
    #[must_use]
    pub fn dir_to_world(&self, d: DVec3) -> DVec3 {
        self.rot.transpose() * d
    }

    /// The unit view direction in the local frame (`y = 0`, `x >= 0`).
    #[must_use]
    pub fn view(&self) -> DVec3 {
        self.view
    }

    /// The world-space surface normal.
    #[must_use]
    pub fn normal(&self) -> DVec3 {
        self.rot.row(2)
    }
}
