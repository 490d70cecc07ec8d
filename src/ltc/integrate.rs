//! Integrals of the clamped cosine over spherical polygons (Lambert's irradiance formula).

use core::f64::consts::PI;

use glam::DVec3;

use crate::sphere::{HORIZON_TOLERANCE, SphericalPolygon};

/// Baum's edge term for the edge `a -> b`: `theta * (a x b)_z / |a x b|`, with the angle taken as
/// `atan2(|a x b|, a . b)`, which stays accurate for tiny edges (no `acos` of a rounded dot
/// product near 1) and for edges near pi long. For a tiny edge `theta / |a x b| -> 1`.
#[inline]
fn edge_term(a: DVec3, b: DVec3) -> f64 {
    let c = a.cross(b);
    let s = c.length();
    if s == 0.0 {
        return 0.0; // coincident endpoints: an edge of zero length contributes nothing
    }
    crate::math::atan2(s, a.dot(b)) / s * c.z
}

/// Signed integral of `z / pi` over the region bounded by the rings, by Stokes' theorem
/// (Baum, Rushmeier and Winget 1989; HDHN16 eq. 11): `(1 / 2 pi) sum theta_e n_e . z`.
fn boundary_sum(poly: &SphericalPolygon) -> f64 {
    let mut sum = 0.0;
    for ring in poly.rings() {
        let n = ring.len();
        for i in 0..n {
            sum += edge_term(ring[i], ring[(i + 1) % n]);
        }
    }
    sum / (2.0 * PI)
}

/// `(1 / pi)` times the integral of `max(0, z)` over the polygon: the irradiance from a uniform
/// unit-radiance light filling the polygon onto a surface with normal `+z`, relative to a light
/// filling the whole hemisphere. In `[0, 1]`.
///
/// The polygon is clipped exactly to the upper hemisphere ([`SphericalPolygon::clip_to_hemisphere`])
/// and Baum's edge sum is evaluated on the result (HDHN16 section 3.1 and eq. 11; seed paper 000,
/// Alg. 1 line 15). Works for every valid polygon: holes, several rings, regions larger than a
/// hemisphere, the full sphere (which gives 1).
///
/// # Examples
///
/// ```
/// use arealight::glam::DVec3;
/// use arealight::ltc::clamped_cosine_integral;
/// use arealight::sphere::SphericalPolygon;
///
/// // The whole upper hemisphere receives pi * L, i.e. 1 in these units.
/// let up = SphericalPolygon::new(vec![vec![DVec3::X, DVec3::Y, -DVec3::X, -DVec3::Y]])?;
/// assert!((clamped_cosine_integral(&up) - 1.0).abs() < 1e-15);
/// assert!(clamped_cosine_integral(&up.complement()).abs() < 1e-15);
/// # Ok::<(), arealight::GeomError>(())
/// ```
#[must_use]
pub fn clamped_cosine_integral(poly: &SphericalPolygon) -> f64 {
    boundary_sum(&poly.clip_to_hemisphere(DVec3::Z)).clamp(0.0, 1.0)
}

/// The same integral as [`clamped_cosine_integral`] without building the clipped polygon: the
/// parts of the original edges above the horizon are integrated as they are, and the new edges
/// along the horizon enter only through their endpoints (thesis 003, eq. 4.6).
///
/// A horizon edge from an exit point `X` counter-clockwise to an entry point `E` contributes its
/// angle `theta_E - theta_X`. Summed over all of them, the angles of the entries count `+1` and
/// those of the exits `-1`, so no pairing of crossings is needed; and by the atan2 sum identity
/// (eq. 4.7) the whole sum is the argument of one complex product, so one `atan2` is evaluated in
/// total. The product gives the sum modulo `2 pi`; since the horizon arcs are disjoint their total
/// lies in `[0, 2 pi]`, which removes the ambiguity except between "none" and "all" of the circle.
///
/// Configurations where that or the pairing is ambiguous (a vertex within [`HORIZON_TOLERANCE`] of
/// the horizon, or no crossing while some vertex is below it) are delegated to the exact path, so
/// the two agree to rounding on every valid polygon.
#[must_use]
pub fn clamped_cosine_integral_clip_free(poly: &SphericalPolygon) -> f64 {
    if poly.is_full() {
        return 1.0;
    }
    let mut sum = 0.0;
    // Running complex product of entry points and conjugates of exit points on the horizon.
    let (mut re, mut im) = (1.0f64, 0.0f64);
    let mut crossings = 0usize;
    // Twice the signed area of the rings projected from +z, for the no-crossing case.
    let mut planar_area2 = 0.0;
    for ring in poly.rings() {
        let n = ring.len();
        for i in 0..n {
            let (a, b) = (ring[i], ring[(i + 1) % n]);
            if a.z.abs() <= HORIZON_TOLERANCE || b.z.abs() <= HORIZON_TOLERANCE {
                return clamped_cosine_integral(poly);
            }
            match (a.z > 0.0, b.z > 0.0) {
                (true, true) => {
                    sum += edge_term(a, b);
                    planar_area2 += (a.x * b.y - a.y * b.x) / (a.z * b.z);
                }
                (false, false) => {}
                (up_a, _) => {
                    // The crossing point, as a positive combination of a and b on the horizon.
                    let x = if up_a {
                        b * a.z - a * b.z
                    } else {
                        a * b.z - b * a.z
                    };
                    let x = DVec3::new(x.x, x.y, 0.0).normalize();
                    let (pr, pi) = (x.x, if up_a { -x.y } else { x.y });
                    (re, im) = (re * pr - im * pi, re * pi + im * pr);
                    crossings += 1;
                    if up_a {
                        sum += edge_term(a, x);
                    } else {
                        sum += edge_term(x, b);
                    }
                }
            }
        }
    }
    let horizon = if crossings > 0 {
        crate::math::atan2(im, re).rem_euclid(2.0 * PI)
    } else if poly.vertex_count() == 0 {
        0.0
    } else if poly.rings().flatten().all(|p| p.z > 0.0) {
        // Everything strictly above: the horizon is inside the region iff the rings, seen from
        // +z, wind clockwise overall (the unbounded planar face is then inside).
        if planar_area2 < 0.0 { 2.0 * PI } else { 0.0 }
    } else {
        return clamped_cosine_integral(poly);
    };
    ((sum + horizon) / (2.0 * PI)).clamp(0.0, 1.0)
}

#[cfg(test)]
mod tests {
    use super::*;
    use alloc::vec;

    #[test]
    fn edge_term_is_stable_for_tiny_and_long_edges() {
        let a = DVec3::new(1.0, 0.0, 0.0);
        let b = DVec3::new(1.0, 1e-9, 0.0).normalize();
        // theta * (a x b)_z / |a x b| -> theta for an edge on the horizon going counter-clockwise.
        assert!((edge_term(a, b) - 1e-9).abs() < 1e-24);
        let c = DVec3::new(-1.0, 1e-9, 0.0).normalize();
        assert!((edge_term(a, c) - (PI - 1e-9)).abs() < 1e-15);
    }

    #[test]
    fn full_sphere_and_empty() {
        assert_eq!(clamped_cosine_integral(&SphericalPolygon::full()), 1.0);
        assert_eq!(
            clamped_cosine_integral_clip_free(&SphericalPolygon::full()),
            1.0
        );
        assert_eq!(clamped_cosine_integral(&SphericalPolygon::empty()), 0.0);
        assert_eq!(
            clamped_cosine_integral_clip_free(&SphericalPolygon::empty()),
            0.0
        );
        let down =
            SphericalPolygon::new(vec![vec![DVec3::X, -DVec3::Y, -DVec3::X, DVec3::Y]]).unwrap();
        assert_eq!(clamped_cosine_integral(&down), 0.0);
    }
}
