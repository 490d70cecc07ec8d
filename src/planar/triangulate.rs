//! Constrained Delaunay triangulation of points and segments in the plane (spade's CDT): the
//! planar half of spherical triangulation, and the one place in the crate that names spade.

use alloc::vec;
use alloc::vec::Vec;

use glam::DVec2;
use spade::{ConstrainedDelaunayTriangulation, Point2, Triangulation};

use crate::GeomError;

/// The constrained Delaunay triangulation of `points` with every segment of `segments` (pairs of
/// indices into `points`) as an edge: the triangles, counter-clockwise, as index triples into
/// `points`, covering the convex hull of the points.
///
/// Points at the same position are one vertex, named by the first index that has it. A segment
/// through other points is split there (its pieces are edges). Spade's predicates are exact
/// (Shewchuk's, through the `robust` crate) on the coordinates it is given; coordinates are first
/// scaled by a power of two (exact) so that the largest lies in `[1, 2)`, inside spade's range
/// `2^-142 ..= 2^201`, and those that would fall below `2^-142` after it are set to zero (they
/// are below `2^-142` of the largest and only decide orientations of points in a line through
/// the origin to that precision).
///
/// # Errors
///
/// - [`GeomError::NonFinite`] for a non-finite coordinate (`vertex` is its index);
/// - [`GeomError::Undecidable`] when two segments cross (or overlap) in the given coordinates, so
///   that no triangulation has both as edges. Callers that derive the coordinates from exact
///   data (projections) get this only when rounding made disjoint segments meet.
///
/// # References
///
/// - L. P. Chew. *Constrained Delaunay triangulations.* Algorithmica 4, 1989.
/// - spade: `ConstrainedDelaunayTriangulation::try_add_constraint`.
pub(crate) fn constrained_delaunay(
    points: &[DVec2],
    segments: &[[usize; 2]],
) -> Result<Vec<[usize; 3]>, GeomError> {
    let mut largest = 0.0f64;
    for (i, p) in points.iter().enumerate() {
        if !p.is_finite() {
            return Err(GeomError::NonFinite { ring: 0, vertex: i });
        }
        largest = largest.max(p.abs().max_element());
    }
    let (s1, s2) = pow2_scale(largest);
    let min = spade::MIN_ALLOWED_VALUE;
    let flush = |x: f64| if x.abs() < min { 0.0 } else { x };
    let mut cdt: ConstrainedDelaunayTriangulation<Point2<f64>> =
        ConstrainedDelaunayTriangulation::new();
    // The first input index at each spade vertex, and the spade vertex of each input point.
    let mut first: Vec<usize> = Vec::with_capacity(points.len());
    let mut handle = Vec::with_capacity(points.len());
    for (i, p) in points.iter().enumerate() {
        let q = *p * s1 * s2;
        let h = cdt
            .insert(Point2::new(flush(q.x), flush(q.y)))
            .map_err(|_| GeomError::NonFinite { ring: 0, vertex: i })?;
        if h.index() == first.len() {
            first.push(i);
        }
        handle.push(h);
    }
    for &[i, j] in segments {
        let (hi, hj) = (handle[i], handle[j]);
        if hi == hj {
            continue;
        }
        if cdt.try_add_constraint(hi, hj).is_empty() {
            return Err(GeomError::Undecidable(
                "segments of the planar triangulation cross in rounded coordinates",
            ));
        }
    }
    let mut out = vec![];
    for face in cdt.inner_faces() {
        let [a, b, c] = face.vertices();
        out.push([
            first[a.fix().index()],
            first[b.fix().index()],
            first[c.fix().index()],
        ]);
    }
    Ok(out)
}

/// Two powers of two whose product brings `largest` (finite, `>= 0`) into `[1, 2)`: applied one
/// after the other, each product is exact and stays in range even where the whole factor would
/// not be a finite double (for subnormal `largest`). `(1, 1)` for zero.
fn pow2_scale(largest: f64) -> (f64, f64) {
    if !(largest > 0.0) {
        return (1.0, 1.0);
    }
    // Exponent of largest, with subnormals lifted first by an exact 2^64.
    let (m, lift) = if largest < f64::MIN_POSITIVE {
        (largest * 18446744073709551616.0, 64)
    } else {
        (largest, 0)
    };
    let e = ((m.to_bits() >> 52) & 0x7ff) as i32 - 1023 - lift;
    let half = -e / 2;
    let p = |k: i32| f64::from_bits(((1023 + k) as u64) << 52);
    (p(half), p(-e - half))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn square_with_a_diagonal_constraint() {
        let pts = [
            DVec2::new(0.0, 0.0),
            DVec2::new(1.0, 0.0),
            DVec2::new(1.0, 1.0),
            DVec2::new(0.0, 1.0),
            DVec2::new(1.0, 0.0), // a repeat of point 1
        ];
        let tris = constrained_delaunay(&pts, &[[1, 3], [0, 4]]).unwrap();
        assert_eq!(tris.len(), 2);
        for t in &tris {
            // Counter-clockwise, and the constraint 1-3 is an edge of both.
            let [a, b, c] = t.map(|i| pts[i]);
            assert!((b - a).perp_dot(c - a) > 0.0);
            assert!(t.contains(&1) && t.contains(&3) && !t.contains(&4));
        }
        let crossing = constrained_delaunay(&pts, &[[1, 3], [0, 2]]);
        assert!(matches!(crossing, Err(GeomError::Undecidable(_))));
    }

    #[test]
    fn scale_is_a_power_of_two_into_one_two() {
        for x in [1e-300, 3e-310, 1.0, 1.5, 7e200, f64::MAX] {
            let (s1, s2) = pow2_scale(x);
            assert!((1.0..2.0).contains(&(x * s1 * s2)), "{x} {s1} {s2}");
            assert_eq!(s1.log2().fract(), 0.0);
            assert_eq!(s2.log2().fract(), 0.0);
        }
    }

    #[test]
    fn tiny_and_huge_coordinates() {
        for k in [1e-200, 1e-9, 1.0, 1e200] {
            let pts = [
                DVec2::new(0.0, 0.0) * k,
                DVec2::new(1.0, 0.0) * k,
                DVec2::new(1.0, 1.0) * k,
                DVec2::new(0.0, 1.0) * k,
            ];
            assert_eq!(constrained_delaunay(&pts, &[[0, 2]]).unwrap().len(), 2);
        }
    }
}
