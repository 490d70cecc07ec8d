//! The one facing predicate: on which side of a mesh triangle's plane a point lies.
//!
//! Every decision of the form "does this face face that point" goes through here: which faces of a
//! convex polyhedron are front faces for its silhouette, whether a single triangle is seen from
//! the front, the back or edge-on in the per-triangle method, and on which side of a light face's
//! plane each vertex of a blocker lies in the exact visibility rule. With one distance formula and
//! one tolerance, the silhouette path, the per-triangle path and the face-by-face visibility agree
//! on every face, including for points on or within rounding of a face plane (a shading point on
//! the ground under a cube standing on it sees the cube's bottom face edge-on on every path).

use alloc::vec::Vec;

use glam::DVec3;

use super::mesh::TriangleMesh;

/// Relative tolerance of the facing predicate ([`face_side`]): a point lies on a face's plane
/// when its signed distance from it is at most `FACE_TOLERANCE * (r + |x - c|)` in magnitude, with
/// `c` and `r` the center and radius of the mesh's bounding sphere.
///
/// The distance is evaluated as `n . (x - c) - d`, with the face's unit normal `n` and its plane
/// offset `d = n . (a - c)` from a corner `a`, both computed once per mesh. Its rounding error is
/// a few `1e-16` of `|x - c| + r` (the dot products and the offset), plus the error of the normal
/// (a few `1e-16` for triangles that pass [`DEGENERATE_TRIANGLE`](crate::solid::DEGENERATE_TRIANGLE))
/// times the distance of `x` from the face, again at most `|x - c| + r`; `1e-11` is far above
/// that. A point this close to the plane sees the face edge-on (zero solid angle): it is neither
/// in front nor behind, which handles shading points lying in a face's plane.
pub const FACE_TOLERANCE: f64 = 1e-11;

/// Where a point lies relative to the plane of a mesh triangle, by [`face_side`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Side {
    /// Strictly behind the plane (against the triangle's normal): the triangle is seen from its
    /// back.
    Behind,
    /// On the plane within [`FACE_TOLERANCE`]: the triangle is seen edge-on.
    On,
    /// Strictly in front of the plane (the side the normal points to): a front face.
    Front,
}

/// Whether the signed distance `s` is [`Side::Front`] given the tolerance `tol`: the one test
/// of [`Side::of`] that callers deciding only front faces (convex silhouettes) need, spelled out
/// so that it compiles to one comparison.
#[inline]
#[must_use]
pub(crate) fn in_front(s: f64, tol: f64) -> bool {
    s > tol
}

impl Side {
    /// The side of a signed distance `s` given the tolerance `tol` (see [`face_side`]).
    #[inline]
    #[must_use]
    pub(crate) fn of(s: f64, tol: f64) -> Side {
        if in_front(s, tol) {
            Side::Front
        } else if s < -tol {
            Side::Behind
        } else {
            Side::On
        }
    }
}

/// On which side of the plane of triangle `f` of `mesh` the point `x` lies: the facing predicate
/// of the crate, with the tolerance of [`FACE_TOLERANCE`] (relative to the mesh's bounding
/// sphere and the point's distance from it).
///
/// # Examples
///
/// ```
/// use arealight::glam::DVec3;
/// use arealight::solid::{ConvexPolyhedron, Side, face_side};
/// let cube = ConvexPolyhedron::cuboid(DVec3::ZERO, DVec3::ONE)?;
/// let m = cube.mesh();
/// // The face whose normal is -z: seen from below it is a front face, from above a back face,
/// // and from a point in its plane edge-on.
/// let f = (0..m.triangle_count()).find(|&f| m.triangle_normal(f).z < -0.5).unwrap();
/// assert_eq!(face_side(m, f, DVec3::new(0.2, 0.3, -5.0)), Side::Front);
/// assert_eq!(face_side(m, f, DVec3::new(0.2, 0.3, 0.0)), Side::Behind);
/// assert_eq!(face_side(m, f, DVec3::new(7.0, 0.3, -1.0)), Side::On);
/// # Ok::<(), arealight::GeomError>(())
/// ```
#[must_use]
pub fn face_side(mesh: &TriangleMesh, f: usize, x: DVec3) -> Side {
    // The arithmetic of `FacingAt::new(mesh, x).side(..)`, written out: through `FacingAt` the
    // release build inlines differently elsewhere on the shading path and a shading point costs
    // up to 4 instructions more (BENCHMARKS.md, "One facing formula"). The unit test below
    // checks that both forms classify the same points the same way.
    let b = mesh.bounding_sphere();
    let rel = x - b.center;
    Side::of(
        mesh.normals()[f].dot(rel) - mesh.offsets()[f],
        FACE_TOLERANCE * (b.radius + rel.length()),
    )
}

/// The facing predicate of [`face_side`] set up for one point and one mesh, for callers that
/// decide many faces of the mesh from that point: the point relative to the mesh's bounding
/// center and the tolerance there, computed once (one square root).
/// Every facing decision in the crate goes through this type, so the distance formula and the
/// tolerance exist once; its methods take a face by its unit normal and plane offset
/// (`mesh.normals()[f]`, `mesh.offsets()[f]`) so that loops over the faces keep their own
/// iteration.
#[derive(Debug, Clone, Copy)]
pub(crate) struct FacingAt {
    rel: DVec3,
    dist: f64,
    tol: f64,
}

impl FacingAt {
    /// The predicate at `x` for the faces of `mesh`.
    #[inline]
    #[must_use]
    pub(crate) fn new(mesh: &TriangleMesh, x: DVec3) -> FacingAt {
        let b = mesh.bounding_sphere();
        let rel = x - b.center;
        let dist = rel.length();
        FacingAt {
            rel,
            dist,
            tol: FACE_TOLERANCE * (b.radius + dist),
        }
    }

    /// The signed distance of the point in front of the face plane `(normal, offset)`.
    #[inline]
    #[must_use]
    pub(crate) fn distance(self, normal: DVec3, offset: f64) -> f64 {
        normal.dot(self.rel) - offset
    }

    /// The tolerance [`Side::of`] compares the distances with at this point.
    #[inline]
    #[must_use]
    pub(crate) fn tol(self) -> f64 {
        self.tol
    }

    /// [`face_side`] of the face plane `(normal, offset)`.
    #[inline]
    #[must_use]
    pub(crate) fn side(self, normal: DVec3, offset: f64) -> Side {
        Side::of(self.distance(normal, offset), self.tol)
    }

    /// Whether [`face_side`] of the face plane `(normal, offset)` is [`Side::Front`], as one
    /// comparison.
    #[inline]
    #[must_use]
    pub(crate) fn front(self, normal: DVec3, offset: f64) -> bool {
        in_front(self.distance(normal, offset), self.tol)
    }

    /// The point relative to the mesh's bounding center.
    #[inline]
    #[must_use]
    pub(crate) fn rel(self) -> DVec3 {
        self.rel
    }

    /// The point's distance from the mesh's bounding center (`rel().length()`, computed once).
    #[inline]
    #[must_use]
    pub(crate) fn dist(self) -> f64 {
        self.dist
    }
}

/// The signed distances of `x` in front of every triangle's plane of `mesh`, written to `out` in
/// triangle order, and the tolerance [`face_side`] compares them with: `Side::of(out[f], tol)` is
/// `face_side(mesh, f, x)` for every `f`, with one square root for all faces.
pub(crate) fn face_distances(mesh: &TriangleMesh, x: DVec3, out: &mut Vec<f64>) -> f64 {
    let at = FacingAt::new(mesh, x);
    out.clear();
    out.extend(
        mesh.normals()
            .iter()
            .zip(mesh.offsets())
            .map(|(n, &d)| at.distance(*n, d)),
    );
    at.tol()
}

/// The signed distance of `x` in front of the plane of triangle `f`, or exactly `0` where
/// [`face_side`] says [`Side::On`]: the distances by which a triangle cut by that plane is split,
/// so that the cut and the facing decisions agree.
#[must_use]
pub(crate) fn snapped_distance(mesh: &TriangleMesh, f: usize, x: DVec3) -> f64 {
    let at = FacingAt::new(mesh, x);
    let s = at.distance(mesh.normals()[f], mesh.offsets()[f]);
    match Side::of(s, at.tol()) {
        Side::On => 0.0,
        _ => s,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::solid::ConvexPolyhedron;

    /// The tolerance of [`face_side`] at `x` for `mesh`.
    fn tol_at(mesh: &TriangleMesh, x: DVec3) -> f64 {
        let b = mesh.bounding_sphere();
        FACE_TOLERANCE * (b.radius + (x - b.center).length())
    }

    #[test]
    fn every_form_of_the_predicate_agrees_on_and_near_face_planes() {
        // The forms the callers use (the batch of convex silhouettes and convexity checks, the
        // per-triangle side, the prepared predicate of the loops over a mesh's faces, the
        // snapped distance of the face-by-face cut) classify every
        // point the same way, and the documented band holds: points in a face's plane are on it,
        // points 4 tolerances off are on their side, at every scale and offset.
        // Offset so that the coordinates' own rounding (ulps of 300) stays below the tolerance
        // band the test probes: the band is relative to the object, not to the origin.
        let off = DVec3::new(300.0, -100.0, 20.0);
        let convex = [
            ConvexPolyhedron::cuboid(DVec3::new(0.1, -0.2, 0.5), DVec3::new(0.5, 0.3, 0.5))
                .unwrap(),
            ConvexPolyhedron::icosphere(DVec3::ZERO, 0.7, 1).unwrap(),
            ConvexPolyhedron::frustum(DVec3::ZERO, DVec3::new(0.1, 0.2, 1.0), 0.5, 0.2, 10)
                .unwrap(),
            ConvexPolyhedron::cuboid(off, DVec3::new(0.2, 0.1, 0.3)).unwrap(),
        ];
        let sheets = TriangleMesh::quad(DVec3::new(0.0, 0.0, 2.0), DVec3::Y, DVec3::X)
            .unwrap()
            .merged(
                &TriangleMesh::quad(
                    DVec3::new(0.3, 0.1, 3.0),
                    DVec3::new(0.0, 0.8, 0.2),
                    DVec3::X,
                )
                .unwrap(),
            )
            .unwrap();
        let meshes: Vec<&TriangleMesh> = convex
            .iter()
            .map(ConvexPolyhedron::mesh)
            .chain([&sheets])
            .collect();
        let (mut on, mut off_plane) = (0, 0);
        let mut dist = Vec::new();
        for mesh in meshes {
            let size = mesh.bounding_sphere().radius;
            for f in 0..mesh.triangle_count() {
                let [a, b, c] = mesh.triangle(f);
                let n = mesh.triangle_normal(f);
                let (u, w) = n.any_orthonormal_pair();
                let centroid = (a + b + c) / 3.0;
                // Points in the plane: corners, the centroid, beyond an edge, and far away along
                // the plane (where the tolerance grows with the distance).
                let in_plane = [
                    a,
                    b,
                    c,
                    centroid,
                    a + (b - a) * 2.5,
                    centroid + u * (3.0 * size),
                    centroid + (u - w) * (40.0 * size),
                ];
                for p in in_plane {
                    let tol = tol_at(mesh, p);
                    for (x, expect) in [
                        (p, Side::On),
                        (p + n * (0.25 * tol), Side::On),
                        (p - n * (0.25 * tol), Side::On),
                        (p + n * (4.0 * tol), Side::Front),
                        (p - n * (4.0 * tol), Side::Behind),
                        (p + n * (0.3 * size), Side::Front),
                    ] {
                        let side = face_side(mesh, f, x);
                        assert_eq!(side, expect, "face {f} at {x}");
                        let t = face_distances(mesh, x, &mut dist);
                        assert_eq!(Side::of(dist[f], t), side, "batch, face {f} at {x}");
                        let at = FacingAt::new(mesh, x);
                        let (nf, df) = (mesh.normals()[f], mesh.offsets()[f]);
                        assert_eq!(at.side(nf, df), side, "prepared, face {f} at {x}");
                        assert_eq!(at.front(nf, df), side == Side::Front, "front, face {f}");
                        let s = snapped_distance(mesh, f, x);
                        let snapped = if s > 0.0 {
                            Side::Front
                        } else if s < 0.0 {
                            Side::Behind
                        } else {
                            Side::On
                        };
                        assert_eq!(snapped, side, "snapped, face {f} at {x}");
                        if side == Side::On {
                            on += 1;
                        } else {
                            off_plane += 1;
                        }
                    }
                }
            }
        }
        assert!(on > 1000 && off_plane > 1000, "{on} {off_plane}");
    }
}
