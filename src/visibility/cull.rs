//! Occluder culling: the `GetBetween` step of seed 000 Alg. 1 (section 3.5).
//!
//! The paper discards objects outside the frustum from the shading point to the light, using
//! bounding spheres. Here the frustum is the cone from the shading point around the light's
//! bounding sphere, and an occluder is kept when its own bounding cone meets that cone, when it
//! is not entirely below the horizon and when it is not entirely behind the light. Every test is
//! conservative: it discards an occluder only when no direction it covers can also be a direction
//! of the light above the horizon with the occluder in front.

use glam::DVec3;

use crate::math::sqrt;
use crate::solid::BoundingSphere;

/// Angular margin (radians) added to every cone test, far above the rounding of the angles, so
/// that an occluder grazing the light's cone is kept rather than lost.
const MARGIN: f64 = 1e-9;

/// Whether an occluder bounded by `occ` may hide part of a light bounded by `light` from the
/// point `x` with surface normal `n` (unit): `false` only when it certainly cannot.
///
/// Discards the occluder when (1) it lies entirely below the tangent plane at `x` (it can only
/// hide directions that the horizon clip removes anyway); (2) it is entirely farther from `x`
/// than every point of the light; (3) the cones from `x` around the two spheres are disjoint.
/// If `x` is inside either sphere the cone test is skipped (that cone is the whole sphere).
///
/// # Examples
///
/// ```
/// use arealight::glam::DVec3;
/// use arealight::internals::may_occlude;
/// use arealight::solid::BoundingSphere;
/// let light = BoundingSphere { center: DVec3::new(0.0, 0.0, 5.0), radius: 1.0 };
/// let between = BoundingSphere { center: DVec3::new(0.0, 0.0, 2.0), radius: 0.5 };
/// let aside = BoundingSphere { center: DVec3::new(4.0, 0.0, 2.0), radius: 0.5 };
/// assert!(may_occlude(DVec3::ZERO, DVec3::Z, light, between));
/// assert!(!may_occlude(DVec3::ZERO, DVec3::Z, light, aside));
/// ```
#[must_use]
pub fn may_occlude(x: DVec3, n: DVec3, light: BoundingSphere, occ: BoundingSphere) -> bool {
    let to_occ = occ.center - x;
    // (1) Entirely below the horizon plane.
    if to_occ.dot(n) < -occ.radius {
        return false;
    }
    let d_occ = to_occ.length();
    let to_light = light.center - x;
    let d_light = to_light.length();
    // (2) Entirely behind the light: its nearest point is farther than the light's farthest.
    if d_occ - occ.radius > d_light + light.radius {
        return false;
    }
    // (3) Disjoint cones. Inside a sphere its cone is everything.
    if d_occ <= occ.radius || d_light <= light.radius {
        return true;
    }
    // The cones meet where the angle between their axes is at most the sum of their half-angles
    // `a + b` (`sin a = r / d` for each): compared through cosines, `cos(a + b) = cos a cos b -
    // sin a sin b`, with two roots and no inverse trigonometric function. The margin moves to the
    // cosine side as `cos(a + b + MARGIN) >= cos(a + b) - MARGIN`, which keeps every pair the
    // angles' test keeps (and a few more where the cones are tiny and the cosine flat), far above
    // the rounding of either side.
    let (sin_o, sin_l) = (
        (occ.radius / d_occ).min(1.0),
        (light.radius / d_light).min(1.0),
    );
    let cos_o = sqrt((1.0 - sin_o * sin_o).max(0.0));
    let cos_l = sqrt((1.0 - sin_l * sin_l).max(0.0));
    let cos_between = to_occ.dot(to_light) / (d_occ * d_light);
    cos_between >= cos_o * cos_l - sin_o * sin_l - MARGIN
}

/// Whether a light bounded by `light` may be above the horizon of `x` (normal `n`, unit).
#[must_use]
pub fn above_horizon(x: DVec3, n: DVec3, light: BoundingSphere) -> bool {
    (light.center - x).dot(n) >= -light.radius
}
