//! Gnomonic (central) projection between a hemisphere and its tangent plane.

use glam::{DVec2, DVec3};
use smallvec::SmallVec;

use super::predicates::{normalize_any, tangent_frame};
use crate::GeomError;

/// Gnomonic projection about a center direction: a direction `p` with `p . c > 0` maps to the
/// point where the ray through it meets the plane tangent to the sphere at `c`.
///
/// Great-circle arcs map to straight segments, which is why set operations on spherical polygons
/// inside an open hemisphere reduce to planar ones (Snyder 1987, "Map projections: a working
/// manual", section 22; seed paper 000, section 3.2, which uses a look-at camera for the same
/// map). The plane's axes `(u, v)` satisfy `u x v = c`, so a ring counter-clockwise seen from
/// outside the sphere stays counter-clockwise in the plane.
///
/// # Examples
///
/// ```
/// use arealight::glam::DVec3;
/// use arealight::sphere::Gnomonic;
///
/// let g = Gnomonic::new(DVec3::Z)?;
/// let q = g.project(DVec3::new(1.0, 0.0, 1.0)).unwrap();
/// assert!((q.length() - 1.0).abs() < 1e-15); // 45 degrees from the center: distance tan(45)
/// assert!(g.project(DVec3::new(1.0, 0.0, -1.0)).is_none()); // the far hemisphere has no image
/// let p = g.unproject(q);
/// assert!((p - DVec3::new(1.0, 0.0, 1.0).normalize()).length() < 1e-15);
/// # Ok::<(), arealight::GeomError>(())
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Gnomonic {
    center: DVec3,
    u: DVec3,
    v: DVec3,
}

impl Gnomonic {
    /// The projection about `center` (any non-zero finite vector; it is normalized).
    ///
    /// # Errors
    ///
    /// [`GeomError::NonFiniteArgument`] or [`GeomError::ZeroLengthArgument`] (`what` is
    /// `"projection center"`) when `center` names no direction.
    pub fn new(center: DVec3) -> Result<Self, GeomError> {
        const WHAT: &str = "projection center";
        if !center.is_finite() {
            return Err(GeomError::NonFiniteArgument { what: WHAT });
        }
        let c = normalize_any(center).ok_or(GeomError::ZeroLengthArgument { what: WHAT })?;
        let (u, v) = tangent_frame(c);
        Ok(Gnomonic { center: c, u, v })
    }

    /// The projection about the center of the smallest spherical cap holding all `dirs`
    /// (see [`enclosing_cap`]), which keeps projected coordinates as small as they can be.
    ///
    /// # Errors
    ///
    /// As [`enclosing_cap`].
    pub fn fit(dirs: &[DVec3]) -> Result<Self, GeomError> {
        let (c, _) = enclosing_cap(dirs)?;
        Gnomonic::new(c)
    }

    /// The unit center direction.
    #[must_use]
    pub fn center(&self) -> DVec3 {
        self.center
    }

    /// The plane's axes `(u, v)`, unit vectors orthogonal to the center with `u x v = center`.
    #[must_use]
    pub fn axes(&self) -> (DVec3, DVec3) {
        (self.u, self.v)
    }

    /// Projects a direction (of any positive length) to the plane; `None` when it does not lie in
    /// the open hemisphere around the center or is not finite.
    #[must_use]
    pub fn project(&self, p: DVec3) -> Option<DVec2> {
        let w = p.dot(self.center);
        if !(w > 0.0) {
            return None;
        }
        let q = DVec2::new(p.dot(self.u) / w, p.dot(self.v) / w);
        q.is_finite().then_some(q)
    }

    /// Maps a point of the plane back to its unit direction. Every finite point has one;
    /// non-finite input gives a NaN vector (use [`Gnomonic::try_unproject`] to check).
    #[must_use]
    pub fn unproject(&self, q: DVec2) -> DVec3 {
        self.try_unproject(q).unwrap_or(DVec3::NAN)
    }

    /// As [`Gnomonic::unproject`], with `None` for non-finite input.
    #[must_use]
    pub fn try_unproject(&self, q: DVec2) -> Option<DVec3> {
        if !q.is_finite() {
            return None;
        }
        // Scaled so that even coordinates near f64::MAX do not overflow before normalization.
        normalize_any(self.center + self.u * q.x + self.v * q.y).or_else(|| {
            let m = q.abs().max_element();
            normalize_any(self.center / m + self.u * (q.x / m) + self.v * (q.y / m))
        })
    }
}

/// The smallest spherical cap holding every direction in `dirs`: its center `c` (a unit vector)
/// and `min_i c . d_i`, the cosine of its angular radius, which is positive.
///
/// Maximizing `min_i c . d_i` over unit `c` is dual to finding the point of the convex hull of the
/// unit directions nearest to the origin (separating hyperplane theorem): `c` is that point,
/// normalized. The nearest point is found exactly (up to rounding) with Wolfe's minimum-norm-point
/// algorithm (Wolfe 1976, "Finding the nearest point in a polytope"), whose corrals in 3D have at
/// most four points.
///
/// # Errors
///
/// - [`GeomError::Degenerate`] for an empty slice;
/// - [`GeomError::NonFinite`] / [`GeomError::ZeroVector`] (with `vertex` the index) for an invalid
///   direction;
/// - [`GeomError::NotInOpenHemisphere`] when the origin lies in the hull, i.e. no open hemisphere
///   holds all directions (the best cap would reach or pass a great circle).
pub fn enclosing_cap(dirs: &[DVec3]) -> Result<(DVec3, f64), GeomError> {
    if dirs.is_empty() {
        return Err(GeomError::Degenerate("no directions to enclose"));
    }
    let mut pts: SmallVec<[DVec3; 16]> = SmallVec::with_capacity(dirs.len());
    for (i, &d) in dirs.iter().enumerate() {
        if !d.is_finite() {
            return Err(GeomError::NonFinite { ring: 0, vertex: i });
        }
        pts.push(normalize_any(d).ok_or(GeomError::ZeroVector { ring: 0, vertex: i })?);
    }
    let x = min_norm_point(&pts);
    let c = normalize_any(x).ok_or(GeomError::NotInOpenHemisphere)?;
    if x.length() < 1e-12 {
        return Err(GeomError::NotInOpenHemisphere);
    }
    let min_dot = pts.iter().map(|p| p.dot(c)).fold(f64::INFINITY, f64::min);
    if min_dot > 0.0 {
        Ok((c, min_dot))
    } else {
        Err(GeomError::NotInOpenHemisphere)
    }
}

/// Wolfe's algorithm: the point of the convex hull of `pts` (unit vectors) nearest the origin.
fn min_norm_point(pts: &[DVec3]) -> DVec3 {
    // The lowest point along x, the first one on ties.
    let support = |x: DVec3| {
        pts.iter()
            .copied()
            .fold((DVec3::ZERO, f64::INFINITY), |best, p| {
                let m = x.dot(p);
                if m < best.1 { (p, m) } else { best }
            })
            .0
    };
    super::wolfe::min_norm_point(support, pts[0], 1.0, 1e-15, 4 * pts.len() + 16)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cap_of_symmetric_points_is_centered() {
        let dirs = [
            DVec3::new(1.0, 0.0, 1.0),
            DVec3::new(-1.0, 0.0, 1.0),
            DVec3::new(0.0, 1.0, 1.0),
            DVec3::new(0.0, -1.0, 1.0),
            DVec3::new(0.1, 0.1, 1.0),
        ];
        let (c, cosr) = enclosing_cap(&dirs).unwrap();
        assert!((c - DVec3::Z).length() < 1e-14, "{c}");
        assert!((cosr - core::f64::consts::FRAC_1_SQRT_2).abs() < 1e-14);
    }

    #[test]
    fn cap_of_two_points_is_their_midpoint() {
        let a = DVec3::new(1.0, 0.0, 0.0);
        let b = DVec3::new(0.0, 1.0, 0.0);
        let (c, cosr) = enclosing_cap(&[a, b, (a + b) * 3.0]).unwrap();
        assert!((c - (a + b).normalize()).length() < 1e-14);
        assert!((cosr - core::f64::consts::FRAC_1_SQRT_2).abs() < 1e-14);
    }

    #[test]
    fn no_open_hemisphere() {
        // The octahedron's vertices.
        assert_eq!(
            enclosing_cap(&crate::sphere::predicates::AXES),
            Err(GeomError::NotInOpenHemisphere)
        );
        // A great circle: a closed but not an open hemisphere.
        let equator = [DVec3::X, DVec3::Y, DVec3::NEG_X, DVec3::NEG_Y];
        assert_eq!(enclosing_cap(&equator), Err(GeomError::NotInOpenHemisphere));
        assert_eq!(
            enclosing_cap(&[DVec3::X, DVec3::NEG_X]),
            Err(GeomError::NotInOpenHemisphere)
        );
    }

    #[test]
    fn invalid_centers_are_errors() {
        assert!(matches!(
            Gnomonic::new(DVec3::ZERO),
            Err(GeomError::ZeroLengthArgument {
                what: "projection center"
            })
        ));
        assert!(matches!(
            Gnomonic::new(DVec3::new(f64::INFINITY, 0.0, 0.0)),
            Err(GeomError::NonFiniteArgument {
                what: "projection center"
            })
        ));
        assert!(matches!(enclosing_cap(&[]), Err(GeomError::Degenerate(_))));
        let g = Gnomonic::new(DVec3::new(0.0, 0.0, 1e300)).unwrap();
        assert_eq!(g.center(), DVec3::Z);
        assert!(g.unproject(DVec2::new(f64::NAN, 0.0)).is_nan());
        let far = g.unproject(DVec2::new(1e308, -1e308));
        assert!((far - DVec3::new(1.0, -1.0, 0.0).normalize()).length() < 1e-15);
    }
}
