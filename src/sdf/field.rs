//! Signed distance fields: the [`Sdf`] trait, primitives with exact distances, similarity
//! transforms and CSG.
//!
//! Every field here is 1-Lipschitz with the correct sign (negative inside), which is all sphere
//! and cone tracing need: a 1-Lipschitz function `f` with zero set `S` satisfies
//! `|f(p)| <= dist(p, S)` (for `q` in `S`, `|f(p)| = |f(p) - f(q)| <= |p - q|`), so a step of
//! `|f(p)|` never crosses the surface (seed 001 section 2, \[Har96\]). Which fields are *exact*
//! distances, and where, is reported by [`Sdf::exactness`]:
//!
//! | field | exactness |
//! |---|---|
//! | every primitive, [`Transformed`] exact field | exact |
//! | [`Union`], [`UnionAll`] of fields exact outside | exact outside, a bound inside |
//! | [`Intersection`] of fields exact inside | exact inside, a bound outside |
//! | [`Difference`] `a - b`, `a` exact inside, `b` exact outside | exact inside, a bound outside |
//! | [`SmoothUnion`] | a bound |
//!
//! Why: the distance to a union of sets is the minimum of the distances (exact outside), but
//! inside, where interiors overlap, the nearest point of the union's boundary can be farther than
//! the nearest boundary point of either operand. Intersection and difference are the complement
//! statements. The smooth union moves the surface, so its value is not a distance to anything
//! named in advance; it is a convex combination of the operands' gradients, hence still
//! 1-Lipschitz (a bound of the distance to its own zero set).
//!
//! Constructors validate their parameters: non-finite values or magnitudes above
//! [`MAX_MAGNITUDE`] are [`GeomError::OutOfRange`], non-positive radii and extents
//! [`GeomError::Degenerate`]. Evaluating a field never fails: a non-finite query point gives a
//! non-finite value, which the tracers report as an error.
//!
//! # References
//!
//! - \[Har96\] J. C. Hart. *Sphere tracing: a geometric method for the antialiased ray tracing of
//!   implicit surfaces.* The Visual Computer 12(10), 1996.
//! - I. Quilez, *distance functions* (web page): the closed forms of the box, rounded box,
//!   capped cylinder and torus distances, each re-derived in the comments below.

use crate::GeomError;
use alloc::boxed::Box;
use alloc::vec::Vec;
use glam::{DQuat, DVec2, DVec3};

/// The largest magnitude accepted for any coordinate, radius, extent or scale. Distances square
/// coordinates, so `1e100` keeps every intermediate far from overflow.
pub const MAX_MAGNITUDE: f64 = 1e100;

/// Where a field's value is the exact signed distance to its zero set, and where it is only a
/// bound (`|f(p)|` at most the distance, with the right sign).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Exactness {
    /// The exact signed distance everywhere.
    Exact,
    /// Exact where `f >= 0`, a bound inside.
    ExactOutside,
    /// Exact where `f <= 0`, a bound outside.
    ExactInside,
    /// A bound everywhere (1-Lipschitz with the right sign).
    Bound,
}

impl Exactness {
    /// Whether the value is exact at points outside (and on) the surface.
    #[must_use]
    pub fn exact_outside(self) -> bool {
        matches!(self, Exactness::Exact | Exactness::ExactOutside)
    }

    /// Whether the value is exact at points inside (and on) the surface.
    #[must_use]
    pub fn exact_inside(self) -> bool {
        matches!(self, Exactness::Exact | Exactness::ExactInside)
    }

    fn from_sides(outside: bool, inside: bool) -> Self {
        match (outside, inside) {
            (true, true) => Exactness::Exact,
            (true, false) => Exactness::ExactOutside,
            (false, true) => Exactness::ExactInside,
            (false, false) => Exactness::Bound,
        }
    }
}

/// A signed distance field: negative inside, positive outside, zero on the surface, and
/// 1-Lipschitz (`|f(p) - f(q)| <= |p - q|`), so that `|f(p)|` never exceeds the distance to the
/// surface.
///
/// Implementations must keep both properties; [`Sdf::exactness`] says where the value is also
/// the exact distance.
pub trait Sdf {
    /// The signed distance (or its bound, see [`Sdf::exactness`]) at `p`.
    fn distance(&self, p: DVec3) -> f64;

    /// Where [`Sdf::distance`] is exact.
    fn exactness(&self) -> Exactness;
}

impl<S: Sdf + ?Sized> Sdf for &S {
    fn distance(&self, p: DVec3) -> f64 {
        (**self).distance(p)
    }
    fn exactness(&self) -> Exactness {
        (**self).exactness()
    }
}

impl<S: Sdf + ?Sized> Sdf for Box<S> {
    fn distance(&self, p: DVec3) -> f64 {
        (**self).distance(p)
    }
    fn exactness(&self) -> Exactness {
        (**self).exactness()
    }
}

/// The outward unit normal of `sdf` at `p`: its gradient by central differences of step `h`
/// along the axes (error `O(h^2)` where the field is smooth), or `None` where the estimate
/// vanishes or is not finite (on a ridge of the field, for example the center of a sphere). `h`
/// should be small against the features of the field and large against the rounding of its
/// values (`1e-6` times the scene size is a good start).
#[must_use]
pub fn normal<S: Sdf + ?Sized>(sdf: &S, p: DVec3, h: f64) -> Option<DVec3> {
    let diff = |e: DVec3| sdf.distance(p + h * e) - sdf.distance(p - h * e);
    DVec3::new(diff(DVec3::X), diff(DVec3::Y), diff(DVec3::Z)).try_normalize()
}

/// A finite value of magnitude at most [`MAX_MAGNITUDE`], or [`GeomError::OutOfRange`].
pub(crate) fn check_finite(what: &'static str, value: f64) -> Result<f64, GeomError> {
    if value.is_finite() && value.abs() <= MAX_MAGNITUDE {
        Ok(value)
    } else {
        Err(GeomError::OutOfRange {
            what,
            value,
            limit: MAX_MAGNITUDE,
        })
    }
}

/// As [`check_finite`], and strictly positive, or [`GeomError::Degenerate`] with `why`.
pub(crate) fn check_positive(
    what: &'static str,
    value: f64,
    why: &'static str,
) -> Result<f64, GeomError> {
    check_finite(what, value)?;
    if value > 0.0 {
        Ok(value)
    } else {
        Err(GeomError::Degenerate(why))
    }
}

/// Every coordinate finite and of magnitude at most [`MAX_MAGNITUDE`].
pub(crate) fn check_point(what: &'static str, p: DVec3) -> Result<DVec3, GeomError> {
    for c in p.to_array() {
        check_finite(what, c)?;
    }
    Ok(p)
}

/// A unit vector along `d`, or an error for a non-finite or (numerically) zero `d`.
pub(crate) fn check_direction(what: &'static str, d: DVec3) -> Result<DVec3, GeomError> {
    check_point(what, d)?;
    // Scale first so that tiny but valid directions normalize without underflow.
    let m = d.abs().max_element();
    if m == 0.0 {
        return Err(GeomError::Degenerate("sdf: a direction is the zero vector"));
    }
    (d / m)
        .try_normalize()
        .ok_or(GeomError::Degenerate("sdf: a direction is the zero vector"))
}

/// A ball.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sphere {
    center: DVec3,
    radius: f64,
}

impl Sphere {
    /// The ball of `radius` about `center`.
    ///
    /// # Errors
    ///
    /// Non-finite or too large input ([`GeomError::OutOfRange`]); `radius <= 0`
    /// ([`GeomError::Degenerate`]).
    pub fn new(center: DVec3, radius: f64) -> Result<Self, GeomError> {
        check_point("sphere center", center)?;
        check_positive("sphere radius", radius, "sdf: a sphere radius must be > 0")?;
        Ok(Sphere { center, radius })
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

impl Sdf for Sphere {
    fn distance(&self, p: DVec3) -> f64 {
        (p - self.center).length() - self.radius
    }
    fn exactness(&self) -> Exactness {
        Exactness::Exact
    }
}

/// Exact signed distance to the axis-aligned box `[-b, b]` (all `b > 0`): outside, the length of
/// the excess over the faces (the clamped point is the nearest one); inside, minus the distance
/// to the nearest face.
fn box_distance(q: DVec3, b: DVec3) -> f64 {
    let e = q.abs() - b;
    e.max(DVec3::ZERO).length() + e.max_element().min(0.0)
}

/// An axis-aligned box (rotate it with [`Transformed`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Cuboid {
    center: DVec3,
    half_extents: DVec3,
}

impl Cuboid {
    /// The box `center ± half_extents`.
    ///
    /// # Errors
    ///
    /// Non-finite or too large input ([`GeomError::OutOfRange`]); a half extent `<= 0`
    /// ([`GeomError::Degenerate`]).
    pub fn new(center: DVec3, half_extents: DVec3) -> Result<Self, GeomError> {
        check_point("box center", center)?;
        for h in half_extents.to_array() {
            check_positive("box half extent", h, "sdf: box half extents must be > 0")?;
        }
        Ok(Cuboid {
            center,
            half_extents,
        })
    }

    /// The center.
    #[must_use]
    pub fn center(&self) -> DVec3 {
        self.center
    }

    /// The half extents.
    #[must_use]
    pub fn half_extents(&self) -> DVec3 {
        self.half_extents
    }
}

impl Sdf for Cuboid {
    fn distance(&self, p: DVec3) -> f64 {
        box_distance(p - self.center, self.half_extents)
    }
    fn exactness(&self) -> Exactness {
        Exactness::Exact
    }
}

/// An axis-aligned box with edges and corners rounded by `radius`: the points within `radius`
/// of the inner box `center ± (half_extents - radius)`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RoundedBox {
    center: DVec3,
    inner: DVec3,
    radius: f64,
}

impl RoundedBox {
    /// The rounded box with outer half extents `half_extents` and rounding `radius`.
    ///
    /// # Errors
    ///
    /// Non-finite or too large input ([`GeomError::OutOfRange`]); `radius <= 0` or a half
    /// extent `<= radius` ([`GeomError::Degenerate`]: use a [`Capsule`] or [`Sphere`] for those).
    pub fn new(center: DVec3, half_extents: DVec3, radius: f64) -> Result<Self, GeomError> {
        check_point("rounded box center", center)?;
        check_point("rounded box half extents", half_extents)?;
        check_positive(
            "rounded box radius",
            radius,
            "sdf: a rounded box radius must be > 0",
        )?;
        let inner = half_extents - DVec3::splat(radius);
        if !(inner.min_element() > 0.0) {
            return Err(GeomError::Degenerate(
                "sdf: rounded box half extents must exceed its radius",
            ));
        }
        Ok(RoundedBox {
            center,
            inner,
            radius,
        })
    }
}

impl Sdf for RoundedBox {
    fn distance(&self, p: DVec3) -> f64 {
        // Offsetting a convex set K by r gives the exact field d_K - r on both sides: outside
        // because distances to a Minkowski sum with a ball drop by r, inside because eroding
        // K + B_r by B_s is K + B_(r - s) (s <= r) or K eroded by B_(s - r) (s >= r) for convex K.
        box_distance(p - self.center, self.inner) - self.radius
    }
    fn exactness(&self) -> Exactness {
        Exactness::Exact
    }
}

/// The points within `radius` of the segment `a b`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Capsule {
    a: DVec3,
    b: DVec3,
    radius: f64,
}

impl Capsule {
    /// The capsule around segment `a b` (`a == b` is a ball).
    ///
    /// # Errors
    ///
    /// Non-finite or too large input ([`GeomError::OutOfRange`]); `radius <= 0`
    /// ([`GeomError::Degenerate`]).
    pub fn new(a: DVec3, b: DVec3, radius: f64) -> Result<Self, GeomError> {
        check_point("capsule end", a)?;
        check_point("capsule end", b)?;
        check_positive(
            "capsule radius",
            radius,
            "sdf: a capsule radius must be > 0",
        )?;
        Ok(Capsule { a, b, radius })
    }
}

impl Sdf for Capsule {
    fn distance(&self, p: DVec3) -> f64 {
        // Offset of a convex set (the segment): exact, see RoundedBox.
        let ab = self.b - self.a;
        let ap = p - self.a;
        let l2 = ab.length_squared();
        let s = if l2 > 0.0 {
            (ap.dot(ab) / l2).clamp(0.0, 1.0)
        } else {
            0.0
        };
        (ap - s * ab).length() - self.radius
    }
    fn exactness(&self) -> Exactness {
        Exactness::Exact
    }
}

/// Axial and radial coordinates of `q` about the unit `axis` through the origin.
fn axial_radial(q: DVec3, axis: DVec3) -> (f64, f64) {
    let z = q.dot(axis);
    // The rejection's length, not sqrt(|q|^2 - z^2), which cancels near the axis.
    (z, (q - z * axis).length())
}

/// A solid cylinder with flat caps, from `a` to `b`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Cylinder {
    center: DVec3,
    axis: DVec3,
    half_length: f64,
    radius: f64,
}

impl Cylinder {
    /// The capped cylinder of `radius` whose axis runs from `a` to `b`.
    ///
    /// # Errors
    ///
    /// Non-finite or too large input ([`GeomError::OutOfRange`]); `radius <= 0` or `a == b`
    /// ([`GeomError::Degenerate`]).
    pub fn new(a: DVec3, b: DVec3, radius: f64) -> Result<Self, GeomError> {
        check_point("cylinder end", a)?;
        check_point("cylinder end", b)?;
        check_positive(
            "cylinder radius",
            radius,
            "sdf: a cylinder radius must be > 0",
        )?;
        let half_length = 0.5 * (b - a).length();
        if !(half_length > 0.0) {
            return Err(GeomError::Degenerate(
                "sdf: a cylinder's ends must be distinct",
            ));
        }
        Ok(Cylinder {
            center: 0.5 * (a + b),
            axis: check_direction("cylinder axis", b - a)?,
            half_length,
            radius,
        })
    }
}

impl Sdf for Cylinder {
    fn distance(&self, p: DVec3) -> f64 {
        // A solid of revolution: the nearest point lies in the meridian half-plane of p, where
        // the solid's section is the rectangle [0, r] x [-h, h]. The distance to that rectangle
        // for a point with radial coordinate >= 0 equals the distance to the symmetric rectangle
        // [-r, r] x [-h, h], the 2D box field.
        let (z, rho) = axial_radial(p - self.center, self.axis);
        let e = DVec2::new(rho, z.abs()) - DVec2::new(self.radius, self.half_length);
        e.max(DVec2::ZERO).length() + e.max_element().min(0.0)
    }
    fn exactness(&self) -> Exactness {
        Exactness::Exact
    }
}

/// A ring torus: the points within `minor` of the circle of radius `major` about `axis`
/// through `center`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Torus {
    center: DVec3,
    axis: DVec3,
    major: f64,
    minor: f64,
}

impl Torus {
    /// The torus with tube radius `minor` around the circle of radius `major` in the plane
    /// through `center` perpendicular to `axis`.
    ///
    /// # Errors
    ///
    /// Non-finite or too large input ([`GeomError::OutOfRange`]); a zero `axis`, `minor <= 0`
    /// or `major < minor` ([`GeomError::Degenerate`]: a spindle torus, whose field near the axis
    /// would not be the exact distance).
    pub fn new(center: DVec3, axis: DVec3, major: f64, minor: f64) -> Result<Self, GeomError> {
        check_point("torus center", center)?;
        let axis = check_direction("torus axis", axis)?;
        check_positive(
            "torus minor radius",
            minor,
            "sdf: a torus tube radius must be > 0",
        )?;
        check_finite("torus major radius", major)?;
        if !(major >= minor) {
            return Err(GeomError::Degenerate(
                "sdf: a torus major radius must be at least its tube radius",
            ));
        }
        Ok(Torus {
            center,
            axis,
            major,
            minor,
        })
    }
}

impl Sdf for Torus {
    fn distance(&self, p: DVec3) -> f64 {
        // Distance to the core circle, minus the tube radius. Exact outside (offset of a closed
        // set); exact inside while the inward normal line keeps its nearest circle point up to
        // depth `minor`, which holds for `major >= minor` (the line reaches the axis, where
        // nearest points stop being unique, only at depth `major`).
        let (z, rho) = axial_radial(p - self.center, self.axis);
        DVec2::new(rho - self.major, z).length() - self.minor
    }
    fn exactness(&self) -> Exactness {
        Exactness::Exact
    }
}

/// A half-space: the points `x` with `normal . x <= offset`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Plane {
    normal: DVec3,
    offset: f64,
}

impl Plane {
    /// The half-space below the plane through `point` with outward `normal` (normalized here).
    ///
    /// # Errors
    ///
    /// Non-finite or too large input ([`GeomError::OutOfRange`]); a zero `normal`
    /// ([`GeomError::Degenerate`]).
    pub fn new(point: DVec3, normal: DVec3) -> Result<Self, GeomError> {
        check_point("plane point", point)?;
        let normal = check_direction("plane normal", normal)?;
        Ok(Plane {
            normal,
            offset: normal.dot(point),
        })
    }

    /// The unit outward normal.
    #[must_use]
    pub fn normal(&self) -> DVec3 {
        self.normal
    }
}

impl Sdf for Plane {
    fn distance(&self, p: DVec3) -> f64 {
        self.normal.dot(p) - self.offset
    }
    fn exactness(&self) -> Exactness {
        Exactness::Exact
    }
}

/// A field moved by a similarity: `x -> scale * rotation * x + translation`. Rotations,
/// translations and uniform scales keep distances exact (the field is scaled back by `scale`);
/// non-uniform scales would not, so they are not offered.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Transformed<S> {
    inner: S,
    inverse_rotation: DQuat,
    translation: DVec3,
    scale: f64,
}

impl<S: Sdf> Transformed<S> {
    /// `inner` scaled by `scale`, then rotated by `rotation` (normalized here), then translated.
    ///
    /// # Errors
    ///
    /// Non-finite or too large input ([`GeomError::OutOfRange`]); a zero quaternion or
    /// `scale <= 0` ([`GeomError::Degenerate`]).
    pub fn new(
        inner: S,
        rotation: DQuat,
        translation: DVec3,
        scale: f64,
    ) -> Result<Self, GeomError> {
        for c in rotation.to_array() {
            check_finite("rotation quaternion", c)?;
        }
        check_point("translation", translation)?;
        check_positive("scale", scale, "sdf: a scale must be > 0")?;
        let m = rotation
            .to_array()
            .into_iter()
            .map(f64::abs)
            .fold(0.0, f64::max);
        if m == 0.0 {
            return Err(GeomError::Degenerate("sdf: a rotation quaternion is zero"));
        }
        let q = DQuat::from_array(rotation.to_array().map(|c| c / m)).normalize();
        Ok(Transformed {
            inner,
            inverse_rotation: q.inverse(),
            translation,
            scale,
        })
    }
}

impl<S: Sdf> Sdf for Transformed<S> {
    fn distance(&self, p: DVec3) -> f64 {
        let local = self.inverse_rotation * (p - self.translation) / self.scale;
        self.scale * self.inner.distance(local)
    }
    fn exactness(&self) -> Exactness {
        self.inner.exactness()
    }
}

/// The union of two fields: `min(a, b)`. Exact outside when both are (see the module docs).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Union<A, B>(pub A, pub B);

impl<A: Sdf, B: Sdf> Sdf for Union<A, B> {
    fn distance(&self, p: DVec3) -> f64 {
        self.0.distance(p).min(self.1.distance(p))
    }
    fn exactness(&self) -> Exactness {
        let out = self.0.exactness().exact_outside() && self.1.exactness().exact_outside();
        Exactness::from_sides(out, false)
    }
}

/// The intersection of two fields: `max(a, b)`. Exact inside when both are; a bound outside (a
/// point near a corner of the intersection is farther than either operand's surface).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Intersection<A, B>(pub A, pub B);

impl<A: Sdf, B: Sdf> Sdf for Intersection<A, B> {
    fn distance(&self, p: DVec3) -> f64 {
        self.0.distance(p).max(self.1.distance(p))
    }
    fn exactness(&self) -> Exactness {
        let inside = self.0.exactness().exact_inside() && self.1.exactness().exact_inside();
        Exactness::from_sides(false, inside)
    }
}

/// `a` minus `b`: `max(a, -b)`. Exact inside when `a` is exact inside and `b` outside; a bound
/// outside.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Difference<A, B>(pub A, pub B);

impl<A: Sdf, B: Sdf> Sdf for Difference<A, B> {
    fn distance(&self, p: DVec3) -> f64 {
        self.0.distance(p).max(-self.1.distance(p))
    }
    fn exactness(&self) -> Exactness {
        let inside = self.0.exactness().exact_inside() && self.1.exactness().exact_outside();
        Exactness::from_sides(false, inside)
    }
}

/// The union of two fields blended over a width `k` (the quadratic polynomial smooth minimum):
/// `min(a, b) - k h^2 / 4` with `h = max(k - |a - b|, 0) / k`. Equal to the union where the
/// operands differ by at least `k`; always a bound.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SmoothUnion<A, B> {
    a: A,
    b: B,
    k: f64,
}

impl<A: Sdf, B: Sdf> SmoothUnion<A, B> {
    /// The smooth union of `a` and `b` with blend width `k`.
    ///
    /// # Errors
    ///
    /// Non-finite or too large `k` ([`GeomError::OutOfRange`]); `k <= 0`
    /// ([`GeomError::Degenerate`]: use [`Union`]).
    pub fn new(a: A, b: B, k: f64) -> Result<Self, GeomError> {
        check_positive(
            "smooth union width",
            k,
            "sdf: a smooth union width must be > 0",
        )?;
        Ok(SmoothUnion { a, b, k })
    }
}

impl<A: Sdf, B: Sdf> Sdf for SmoothUnion<A, B> {
    fn distance(&self, p: DVec3) -> f64 {
        // With s = a - b and |s| < k the value is (a + b)/2 - |s|/2 - (k - |s|)^2 / (4k), whose
        // partial derivatives 1/2 - s/(2k) and 1/2 + s/(2k) are in [0, 1] and sum to 1: the
        // gradient is a convex combination of the operands' gradients, so the field stays
        // 1-Lipschitz.
        let (a, b) = (self.a.distance(p), self.b.distance(p));
        let h = (self.k - (a - b).abs()).max(0.0) / self.k;
        a.min(b) - 0.25 * self.k * h * h
    }
    fn exactness(&self) -> Exactness {
        Exactness::Bound
    }
}

/// The union of any number of fields (a scene); empty, it is the empty set (`+inf` everywhere).
/// Exact outside when all members are.
pub struct UnionAll {
    members: Vec<Box<dyn Sdf + Send + Sync>>,
}

impl UnionAll {
    /// The union of `members`.
    #[must_use]
    pub fn new(members: Vec<Box<dyn Sdf + Send + Sync>>) -> Self {
        UnionAll { members }
    }

    /// Adds a member.
    pub fn push(&mut self, member: Box<dyn Sdf + Send + Sync>) {
        self.members.push(member);
    }

    /// The members.
    #[must_use]
    pub fn members(&self) -> &[Box<dyn Sdf + Send + Sync>] {
        &self.members
    }
}

impl core::fmt::Debug for UnionAll {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        write!(f, "UnionAll({} members)", self.members.len())
    }
}

impl Sdf for UnionAll {
    fn distance(&self, p: DVec3) -> f64 {
        self.members
            .iter()
            .fold(f64::INFINITY, |d, m| d.min(m.distance(p)))
    }
    fn exactness(&self) -> Exactness {
        let out = self.members.iter().all(|m| m.exactness().exact_outside());
        // One member alone keeps its own exactness inside too.
        let inside =
            self.members.len() <= 1 && self.members.iter().all(|m| m.exactness().exact_inside());
        Exactness::from_sides(out, inside)
    }
}
