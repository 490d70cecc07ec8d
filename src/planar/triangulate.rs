//! Constrained Delaunay triangulation of points and segments in the plane (spade's CDT): the
//! planar half of spherical triangulation, and the one place in the crate that names spade.

use alloc::vec;
use alloc::vec::Vec;

use glam::DVec2;
use spade::{ConstrainedDelaunayTriangulation, Point2, Triangulation};

use crate::GeomError;

/// A constrained Delaunay triangulation ([`constrained_delaunay`]): counter-clockwise triangles
/// as index triples into the input points, and for each triangle edge `s` (from vertex `s` to
/// vertex `s + 1 mod 3`) the triangle across it and whether it is a constraint.
#[derive(Debug, Clone, Default)]
pub(crate) struct Cdt {
    /// The triangles, covering the convex hull of the points.
    pub tris: Vec<[usize; 3]>,
    /// `across[k][s]`: the index of the triangle on the other side of edge `s` of triangle `k`,
    /// or [`Cdt::HULL`] on the convex hull.
    pub across: Vec<[u32; 3]>,
    /// `constraint[k]`, bit `s`: edge `s` of triangle `k` is (a piece of) a segment.
    pub constraint: Vec<u8>,
}

impl Cdt {
    /// The value of [`Cdt::across`] for an edge on the convex hull.
    pub const HULL: u32 = u32::MAX;
}

/// The constrained Delaunay triangulation of `points` with every segment of `segments` (pairs of
/// indices into `points`) as an edge, with triangle adjacency ([`Cdt`]).
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
/// - spade: `ConstrainedDelaunayTriangulation::try_bulk_load_cdt`.
pub(crate) fn constrained_delaunay(
    points: &[DVec2],
    segments: &[[usize; 2]],
) -> Result<Cdt, GeomError> {
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
    let scaled: Vec<Point2<f64>> = points
        .iter()
        .map(|p| {
            let q = *p * s1 * s2;
            Point2::new(flush(q.x), flush(q.y))
        })
        .collect();
    // Points at the same position are one vertex, named by the first index that has it: sorted
    // by bits, each run of equal positions maps to its smallest index.
    let key = |p: &Point2<f64>| (p.x.to_bits(), p.y.to_bits());
    let mut order: Vec<usize> = (0..points.len()).collect();
    order.sort_unstable_by_key(|&i| (key(&scaled[i]), i));
    let mut vertex_of = vec![0usize; points.len()];
    let mut first: Vec<usize> = Vec::with_capacity(points.len());
    let mut unique: Vec<Point2<f64>> = Vec::with_capacity(points.len());
    for (k, &i) in order.iter().enumerate() {
        if k == 0 || key(&scaled[i]) != key(&scaled[order[k - 1]]) {
            first.push(i);
            unique.push(scaled[i]);
        }
        vertex_of[i] = unique.len() - 1;
    }
    let mut edges: Vec<[usize; 2]> = Vec::with_capacity(segments.len());
    for &[i, j] in segments {
        let (a, b) = (vertex_of[i], vertex_of[j]);
        if a != b {
            edges.push([a, b]);
        }
    }
    // Spade's bulk loading (vertices from the center outwards, constraints added as their
    // nearer end is inserted) costs about n log n where inserting one point at a time walks
    // from the last one; both keep the vertex order, so spade's vertex k is `unique[k]`.
    let mut crossing = false;
    let cdt: ConstrainedDelaunayTriangulation<Point2<f64>> =
        ConstrainedDelaunayTriangulation::try_bulk_load_cdt(unique, edges, |_| crossing = true)
            .map_err(|_| {
                // Every coordinate was checked finite and scaled into spade's range above, so
                // this is spade declining input the crate derived, not a fault of the caller's.
                GeomError::Undecidable("the planar triangulation rejected scaled coordinates")
            })?;
    if crossing {
        return Err(GeomError::Undecidable(
            "segments of the planar triangulation cross in rounded coordinates",
        ));
    }
    // Spade numbers the outer face 0 and the inner faces from 1, in the order it iterates them.
    let n = cdt.num_inner_faces();
    let mut out = Cdt {
        tris: Vec::with_capacity(n),
        across: Vec::with_capacity(n),
        constraint: Vec::with_capacity(n),
    };
    for face in cdt.inner_faces() {
        let edges = face.adjacent_edges();
        let mut tri = [0usize; 3];
        let mut across = [Cdt::HULL; 3];
        let mut constraint = 0u8;
        for (s, e) in edges.iter().enumerate() {
            tri[s] = first[e.from().fix().index()];
            if let Some(f) = e.rev().face().as_inner() {
                across[s] = (f.fix().index() - 1) as u32;
            }
            if e.as_undirected().data().is_constraint_edge() {
                constraint |= 1 << s;
            }
        }
        debug_assert_eq!(face.fix().index() - 1, out.tris.len());
        out.tris.push(tri);
        out.across.push(across);
        out.constraint.push(constraint);
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
        let cdt = constrained_delaunay(&pts, &[[1, 3], [0, 4]]).unwrap();
        let tris = &cdt.tris;
        assert_eq!(tris.len(), 2);
        // The two triangles are across the constraint 1-3 from each other, and the hull
        // elsewhere; the constraints are 1-3 and 0-1 (segment 0-4, 4 a repeat of 1).
        for (k, t) in tris.iter().enumerate() {
            for s in 0..3 {
                let e = [t[s], t[(s + 1) % 3]];
                let diagonal = e.contains(&1) && e.contains(&3);
                let bottom = e.contains(&0) && e.contains(&1);
                assert_eq!(cdt.across[k][s] == 1 - k as u32, diagonal);
                assert_eq!(cdt.across[k][s] == Cdt::HULL, !diagonal);
                assert_eq!(cdt.constraint[k] & (1 << s) != 0, diagonal || bottom);
            }
        }
        for t in tris {
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
            assert_eq!(constrained_delaunay(&pts, &[[0, 2]]).unwrap().tris.len(), 2);
        }
    }
}
