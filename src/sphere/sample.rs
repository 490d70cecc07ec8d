//! Uniform sampling of spherical triangles by solid angle (Arvo 1995; thesis 003, section 3.6).

use glam::{DVec2, DVec3};

use super::predicates::{normalize_any, triangle_solid_angle};
use crate::GeomError;
use crate::math::{atan2, sin_cos, sqrt};

/// A spherical triangle prepared for uniform sampling over its solid angle.
///
/// \[Arv95\]'s method: the solid angle `A_hat` of a sub-triangle `(A, B, C_hat)` is drawn uniformly in
/// `[0, area]`, which fixes the point `C_hat` on the arc `AC`; the sample is then drawn on the arc
/// from `B` to `C_hat` with the density that makes the result uniform. The triangle's area is taken
/// from Van Oosterom–Strackee (full relative precision for small triangles) and the angle at `A`
/// from an `atan2` of tangent vectors, not from `acos` of rounded dot products.
///
/// The vertices may be given in either orientation.
///
/// # Examples
///
/// ```
/// use arealight::glam::{DVec2, DVec3};
/// use arealight::sphere::SphericalTriangle;
/// let t = SphericalTriangle::new(DVec3::X, DVec3::Y, DVec3::Z)?;
/// assert!((t.solid_angle() - std::f64::consts::FRAC_PI_2).abs() < 1e-15);
/// let w = t.sample(DVec2::new(0.3, 0.7));
/// assert!(w.min_element() >= -1e-15 && (w.length() - 1.0).abs() < 1e-12);
/// # Ok::<(), arealight::GeomError>(())
/// ```
///
/// # References
///
/// - \[Arv95\] J. Arvo. *Stratified sampling of spherical triangles.* SIGGRAPH 1995.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SphericalTriangle {
    a: DVec3,
    b: DVec3,
    c: DVec3,
    area: f64,
    /// Angle at `a`, its sine and cosine.
    alpha: f64,
    sin_alpha: f64,
    cos_alpha: f64,
    /// Unit tangent at `a` towards `c` (the direction of arc `AC`).
    t_ac: DVec3,
}

impl SphericalTriangle {
    /// Prepares the triangle `(a, b, c)`; the vertices are normalized.
    ///
    /// # Errors
    ///
    /// [`GeomError::NonFinite`] / [`GeomError::ZeroVector`] for a vertex that names no direction,
    /// [`GeomError::Degenerate`] for a triangle of zero solid angle (collinear or repeated
    /// vertices) or one spanning a hemisphere or more.
    pub fn new(a: DVec3, b: DVec3, c: DVec3) -> Result<Self, GeomError> {
        let mut v = [DVec3::ZERO; 3];
        for (i, p) in [a, b, c].into_iter().enumerate() {
            if !p.is_finite() {
                return Err(GeomError::NonFinite { ring: 0, vertex: i });
            }
            v[i] = normalize_any(p).ok_or(GeomError::ZeroVector { ring: 0, vertex: i })?;
        }
        let [a, b, c] = v;
        let area = triangle_solid_angle(a, b, c).abs();
        // Tangents at a towards b and c.
        let tb = normalize_any(b - a * a.dot(b));
        let tc = normalize_any(c - a * a.dot(c));
        let (Some(tb), Some(tc)) = (tb, tc) else {
            return Err(GeomError::Degenerate(
                "spherical triangle with a repeated or antipodal vertex",
            ));
        };
        let alpha = atan2(tb.cross(tc).length(), tb.dot(tc));
        if area.is_nan()
            || alpha.is_nan()
            || area <= 0.0
            || alpha <= 0.0
            || area >= 2.0 * core::f64::consts::PI
        {
            return Err(GeomError::Degenerate(
                "spherical triangle of zero solid angle (or a hemisphere or more) cannot be sampled",
            ));
        }
        let (sin_alpha, cos_alpha) = sin_cos(alpha);
        Ok(SphericalTriangle {
            a,
            b,
            c,
            area,
            alpha,
            sin_alpha,
            cos_alpha,
            t_ac: tc,
        })
    }

    /// The vertices (unit vectors).
    #[must_use]
    pub fn vertices(&self) -> [DVec3; 3] {
        [self.a, self.b, self.c]
    }

    /// The solid angle (positive).
    #[must_use]
    pub fn solid_angle(&self) -> f64 {
        self.area
    }

    /// A direction in the triangle from two uniform numbers in `[0, 1)`; over uniform `u` the
    /// result is uniform in solid angle (density `1 / solid_angle`). Always a unit vector.
    #[must_use]
    pub fn sample(&self, u: DVec2) -> DVec3 {
        let (a, b) = (self.a, self.b);
        // Sub-triangle area A_hat and the point C_hat on arc AC (\[Arv95\], section 2).
        let a_hat = u.x.clamp(0.0, 1.0) * self.area;
        let (s, t) = sin_cos(a_hat - self.alpha);
        let cos_c = a.dot(b);
        let uu = t - self.cos_alpha;
        let vv = s + self.sin_alpha * cos_c;
        let den = (vv * s + uu * t) * self.sin_alpha;
        let q = if den != 0.0 {
            (((vv * t - uu * s) * self.cos_alpha - vv) / den).clamp(-1.0, 1.0)
        } else {
            // Only at a_hat = 0, where C_hat = A.
            1.0
        };
        let c_hat = q * a + sqrt((1.0 - q * q).max(0.0)) * self.t_ac;
        // The point on arc B -> C_hat, with cos(theta) drawn uniformly between 1 and B.C_hat.
        let z = 1.0 - u.y.clamp(0.0, 1.0) * (1.0 - c_hat.dot(b));
        let Some(tang) = normalize_any(c_hat - b * c_hat.dot(b)) else {
            return b;
        };
        let p = z * b + sqrt((1.0 - z * z).max(0.0)) * tang;
        normalize_any(p).unwrap_or(b)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn corners_of_the_unit_square_map_to_vertices() {
        let t = SphericalTriangle::new(DVec3::X, DVec3::Y, DVec3::Z).unwrap();
        assert!((t.sample(DVec2::new(0.3, 0.0)) - DVec3::Y).length() < 1e-12);
        assert!((t.sample(DVec2::new(1.0, 1.0)) - DVec3::Z).length() < 1e-12);
        assert!((t.sample(DVec2::new(0.0, 1.0)) - DVec3::X).length() < 1e-12);
        assert!(SphericalTriangle::new(DVec3::X, DVec3::Y, DVec3::X).is_err());
        assert!(SphericalTriangle::new(DVec3::X, DVec3::Y, DVec3::new(1.0, 1.0, 0.0)).is_err());
    }
}
