//! Occluder culling: the `GetBetween` step of seed 000 Alg. 1 (section 3.5), per object by
//! bounding cones ([`may_occlude`]) and per triangle through a mesh's bounding-volume hierarchy
//! by shafts ([`Shaft`]).
//!
//! The paper discards objects outside the frustum from the shading point to the light, using
//! bounding spheres. Here the frustum is the cone from the shading point around the light's
//! bounding sphere, and an occluder is kept when its own bounding cone meets that cone, when it
//! is not entirely below the horizon and when it is not entirely behind the light. Every test is
//! conservative: it discards an occluder only when no direction it covers can also be a direction
//! of the light above the horizon with the occluder in front.

use glam::DVec3;
use smallvec::SmallVec;

use alloc::vec::Vec;

use crate::math::sqrt;
use crate::solid::{BoundingSphere, Bvh, TriangleMesh};

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
    LightCone::new(x, n, light).may_occlude(occ)
}

/// [`may_occlude`] for one point and light and many occluders: the light's cone, computed once.
#[derive(Debug, Clone, Copy)]
pub(crate) struct LightCone {
    x: DVec3,
    n: DVec3,
    to_light: DVec3,
    d_light: f64,
    /// The light's farthest distance from `x`.
    far: f64,
    /// `x` inside the light's sphere (its cone is every direction).
    inside: bool,
    sin_l: f64,
    cos_l: f64,
}

impl LightCone {
    /// The cone from `x` (surface normal `n`, unit) around the sphere `light`.
    #[inline]
    pub(crate) fn new(x: DVec3, n: DVec3, light: BoundingSphere) -> Self {
        let to_light = light.center - x;
        let d_light = to_light.length();
        let sin_l = (light.radius / d_light).min(1.0);
        LightCone {
            x,
            n,
            to_light,
            d_light,
            far: d_light + light.radius,
            inside: d_light <= light.radius,
            sin_l,
            cos_l: sqrt((1.0 - sin_l * sin_l).max(0.0)),
        }
    }

    /// [`may_occlude`] of the occluder bounded by `occ`.
    #[inline]
    pub(crate) fn may_occlude(&self, occ: BoundingSphere) -> bool {
        let to_occ = occ.center - self.x;
        // (1) Entirely below the horizon plane.
        if to_occ.dot(self.n) < -occ.radius {
            return false;
        }
        let d_occ = to_occ.length();
        // (2) Entirely behind the light: its nearest point is farther than the light's farthest.
        if d_occ - occ.radius > self.far {
            return false;
        }
        // (3) Disjoint cones. Inside a sphere its cone is everything.
        if d_occ <= occ.radius || self.inside {
            return true;
        }
        // The cones meet where the angle between their axes is at most the sum of their
        // half-angles `a + b` (`sin a = r / d` for each): compared through cosines, `cos(a + b)
        // = cos a cos b - sin a sin b`, with two roots and no inverse trigonometric function.
        // The margin moves to the cosine side as `cos(a + b + MARGIN) >= cos(a + b) - MARGIN`,
        // which keeps every pair the angles' test keeps (and a few more where the cones are tiny
        // and the cosine flat), far above the rounding of either side.
        let sin_o = (occ.radius / d_occ).min(1.0);
        let cos_o = sqrt((1.0 - sin_o * sin_o).max(0.0));
        let cos_between = to_occ.dot(self.to_light) / (d_occ * self.d_light);
        cos_between >= cos_o * self.cos_l - sin_o * self.sin_l - MARGIN
    }
}

/// Whether a light bounded by `light` may be above the horizon of `x` (normal `n`, unit).
#[must_use]
pub fn above_horizon(x: DVec3, n: DVec3, light: BoundingSphere) -> bool {
    (light.center - x).dot(n) >= -light.radius
}

/// Relative margin of the [`Shaft`] tests: a box or triangle is dropped only when it lies
/// outside a plane by more than `SHAFT_MARGIN` times the sum of the magnitudes the test
/// combines (its distance from the apex, its size, the plane's offset and the apex's
/// coordinates).
///
/// The test's value `n . (p - apex) - d` is a dot product of a unit normal with differences of
/// coordinates; its rounding error is a few `f64::EPSILON` (2.2e-16) of those magnitudes, and a
/// plane built from rounded sines and cosines is off by as little. `1e-12` is over a thousand
/// times that, so rounding never drops anything that reaches into the exact region; what it
/// keeps in addition is a layer a millionth of a millionth of the scene's size thick.
pub const SHAFT_MARGIN: f64 = 1e-12;

/// A convex region of space, the part of the scene that may hide a light from a point: the
/// points `p` with `n_k . (p - apex) >= d_k` for each of a few planes `(n_k, d_k)` (at most 32),
/// `n_k` unit.
///
/// Built as the shaft from a shading point to a light's bounding sphere ([`Shaft::to_sphere`]:
/// four planes circumscribing the cone, a far plane and the horizon), or from the planes of a
/// cone of directions ([`Shaft::from_cone`]). Its tests ([`Shaft::may_meet_box`],
/// [`Shaft::may_meet_triangle`]) are conservative with the margin [`SHAFT_MARGIN`]: they say
/// `false` only for boxes and triangles that certainly do not meet the region.
///
/// # Examples
///
/// ```
/// use arealight::glam::DVec3;
/// use arealight::internals::Shaft;
/// use arealight::solid::BoundingSphere;
/// let light = BoundingSphere { center: DVec3::new(0.0, 0.0, 5.0), radius: 1.0 };
/// let shaft = Shaft::to_sphere(DVec3::ZERO, DVec3::Z, light);
/// let (lo, hi) = (DVec3::splat(-0.2) + DVec3::Z * 2.0, DVec3::splat(0.2) + DVec3::Z * 2.0);
/// assert!(shaft.may_meet_box(lo, hi));
/// assert!(!shaft.may_meet_box(lo + DVec3::X * 3.0, hi + DVec3::X * 3.0));
/// // Below the horizon, or beyond the light.
/// assert!(!shaft.may_meet_box(lo - DVec3::Z * 3.0, hi - DVec3::Z * 3.0));
/// assert!(!shaft.may_meet_box(lo + DVec3::Z * 5.0, hi + DVec3::Z * 5.0));
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct Shaft {
    apex: DVec3,
    planes: SmallVec<[(DVec3, f64); 10]>,
    /// `SHAFT_MARGIN * |apex|_1`: the part of every tolerance that does not depend on the box.
    apex_tol: f64,
}

impl Shaft {
    /// The shaft from the point `x` (unit surface normal `n`) to a sphere: the points above the
    /// tangent plane at `x` (`n . (p - x) >= 0`), no farther from `x` along the axis than the
    /// sphere's far side, and inside the square pyramid from `x` that circumscribes the cone
    /// from `x` around the sphere (no side planes when `x` is inside the sphere).
    ///
    /// It holds every point between `x` and a point of the sphere above the horizon: what may
    /// hide the sphere's interior from `x` (seed 000 section 3.5, `GetBetween`), the same
    /// conditions as [`may_occlude`] with planes instead of a bounding sphere per object.
    #[must_use]
    pub fn to_sphere(x: DVec3, n: DVec3, target: BoundingSphere) -> Shaft {
        let mut planes: SmallVec<[(DVec3, f64); 10]> = SmallVec::new();
        planes.push((n, 0.0));
        let to = target.center - x;
        let d = to.length();
        if d > 0.0 && d.is_finite() {
            let a = to / d;
            planes.push((-a, -(d + target.radius)));
            if d > target.radius {
                // The plane tangent to the cone of half-angle `alpha` along `cos a + sin e`
                // has the inward normal `sin a - cos e`: every direction within `alpha` of
                // the axis has a non-negative dot product with it.
                let sin = target.radius / d;
                let cos = sqrt((1.0 - sin * sin).max(0.0));
                let (e1, e2) = a.any_orthonormal_pair();
                for e in [e1, -e1, e2, -e2] {
                    planes.push((a * sin - e * cos, 0.0));
                }
            }
        }
        Shaft {
            apex: x,
            planes,
            apex_tol: SHAFT_MARGIN * x.abs().element_sum(),
        }
    }

    /// The points above the tangent plane at `x` (unit normal `n`) in the cone from `x` on the
    /// inner side of every plane through `x` with the (unit, world) normals `sides`, no farther
    /// than `far` from `x` along the unit `axis`.
    ///
    /// Side planes past the 30th are left out (a larger region, so still conservative): the
    /// masks of [`Shaft::classify_box`] have 32 bits.
    #[must_use]
    pub fn from_cone(x: DVec3, n: DVec3, sides: &[DVec3], axis: DVec3, far: f64) -> Shaft {
        // The side planes first: they reject most of what lies outside.
        let mut planes: SmallVec<[(DVec3, f64); 10]> =
            sides.iter().take(30).map(|&s| (s, 0.0)).collect();
        planes.push((-axis, -far));
        planes.push((n, 0.0));
        Shaft {
            apex: x,
            planes,
            apex_tol: SHAFT_MARGIN * x.abs().element_sum(),
        }
    }

    /// Whether the axis-aligned box `[lo, hi]` may meet the shaft: `false` only when it lies
    /// entirely outside one of the planes (beyond the margin).
    #[must_use]
    #[inline]
    pub fn may_meet_box(&self, lo: DVec3, hi: DVec3) -> bool {
        let c = 0.5 * (lo + hi);
        let h = 0.5 * (hi - lo);
        let rel = c - self.apex;
        let base = SHAFT_MARGIN * (rel.abs().element_sum() + h.element_sum()) + self.apex_tol;
        self.planes.iter().all(|&(n, d)| {
            // The largest value of n . (p - apex) over the box.
            n.dot(rel) + n.abs().dot(h) >= d - (base + SHAFT_MARGIN * d.abs())
        })
    }

    /// The set of all planes, as a mask for [`Shaft::classify_box`].
    #[must_use]
    pub fn all_planes(&self) -> u32 {
        (1u32 << self.planes.len()) - 1
    }

    /// [`Shaft::may_meet_box`] against the planes in `mask` (bit `k` for plane `k`): `None` when
    /// the box lies outside one of them, else the planes of `mask` the box is not certainly
    /// inside of (beyond the same margin). A box inside a smaller box needs testing only against
    /// those: a hierarchy's traversal passes the mask down and tests fewer planes as it descends.
    #[must_use]
    #[inline]
    pub fn classify_box(&self, lo: DVec3, hi: DVec3, mask: u32) -> Option<u32> {
        let c = 0.5 * (lo + hi);
        let h = 0.5 * (hi - lo);
        let rel = c - self.apex;
        let base = SHAFT_MARGIN * (rel.abs().element_sum() + h.element_sum()) + self.apex_tol;
        let mut out = 0;
        let mut m = mask;
        while m != 0 {
            let k = m.trailing_zeros();
            m &= m - 1;
            let (n, d) = self.planes[k as usize];
            let (mid, spread) = (n.dot(rel), n.abs().dot(h));
            let tol = base + SHAFT_MARGIN * d.abs();
            if mid + spread < d - tol {
                return None;
            }
            if mid - spread < d + tol {
                out |= 1 << k;
            }
        }
        Some(out)
    }

    /// Whether the triangle `tri` may meet the shaft: `false` only when its three corners lie
    /// outside one of the planes (beyond the margin).
    #[must_use]
    #[inline]
    pub fn may_meet_triangle(&self, tri: &[DVec3; 3]) -> bool {
        let rel = tri.map(|v| v - self.apex);
        let size = rel
            .iter()
            .map(|r| r.abs().element_sum())
            .fold(0.0, f64::max);
        let base = SHAFT_MARGIN * size + self.apex_tol;
        self.planes.iter().all(|&(n, d)| {
            let t = d - (base + SHAFT_MARGIN * d.abs());
            rel.iter().any(|r| n.dot(*r) >= t)
        })
    }
}

/// Writes to `out`, in increasing order, the triangles of `mesh` that may meet `shaft`: through
/// the mesh's bounding-volume hierarchy when it has one, then each triangle's own test.
pub(crate) fn shaft_triangles(
    mesh: &TriangleMesh,
    bvh: Option<&Bvh>,
    shaft: &Shaft,
    out: &mut Vec<u32>,
) {
    out.clear();
    let mut test = |t: u32| {
        if shaft.may_meet_triangle(&mesh.triangle(t as usize)) {
            out.push(t);
        }
    };
    match bvh {
        Some(bvh) => {
            bvh.for_each(|lo, hi| shaft.may_meet_box(lo, hi), &mut test);
            out.sort_unstable();
        }
        None => (0..mesh.triangle_count() as u32).for_each(test),
    }
}
