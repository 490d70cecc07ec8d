//! Convex polyhedra: validation of a closed mesh as convex, and the convex hull of a point set
//! (incremental, with Shewchuk's exact `orient3d`).

use alloc::vec;
use alloc::vec::Vec;

use glam::DVec3;
use robust::orient3d;

use super::facing::{FacingAt, Side, face_distances, face_side};
use super::mesh::{BoundingSphere, DEGENERATE_TRIANGLE, MeshEdge, TriangleMesh, check_vertices};
use crate::GeomError;
use crate::sphere::predicates::c3;

/// A convex polyhedron: a closed triangle mesh with outward normals, every vertex on or behind
/// every face plane, and its edges with their two adjacent faces (thesis 003, section 4.2:
/// "store the edges of the polyhedron along with the normals of the adjacent faces").
///
/// Coplanar faces are allowed (a cube has two triangles per side); an edge between coplanar
/// faces is never on the silhouette, because both faces are front-facing or neither is.
///
/// # Examples
///
/// ```
/// use arealight::glam::DVec3;
/// use arealight::GeomError;
/// use arealight::solid::ConvexPolyhedron;
/// let cube = ConvexPolyhedron::cuboid(DVec3::ZERO, DVec3::ONE)?;
/// assert_eq!(cube.vertices().len(), 8);
/// assert_eq!(cube.mesh().triangle_count(), 12);
/// assert_eq!(cube.edges().len(), 18);
/// // Coplanar point sets have no hull.
/// let square = [DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::X + DVec3::Y];
/// assert!(matches!(ConvexPolyhedron::hull(&square), Err(GeomError::Degenerate(_))));
/// # Ok::<(), arealight::GeomError>(())
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct ConvexPolyhedron {
    mesh: TriangleMesh,
}

impl ConvexPolyhedron {
    /// The convex hull of a point set (incremental construction with Shewchuk's exact `orient3d`,
    /// so every visibility decision is exact for the given coordinates). Points inside the hull
    /// or on its faces are dropped; duplicates are allowed.
    ///
    /// # Errors
    ///
    /// - [`GeomError::NonFinite`] / [`GeomError::OutOfRange`] for a bad coordinate;
    /// - [`GeomError::TooFewVertices`] for fewer than four points;
    /// - [`GeomError::Degenerate`] when the points are (nearly) coplanar, so the hull has no
    ///   volume;
    /// - an error of [`ConvexPolyhedron::from_mesh`] if the hull has faces too thin to have a
    ///   reliable normal (sliver faces from nearly coplanar points).
    pub fn hull(points: &[DVec3]) -> Result<Self, GeomError> {
        check_vertices(points)?;
        let tris = hull_triangles(points)?;
        // Keep only the vertices the hull uses, in input order.
        let mut remap = vec![u32::MAX; points.len()];
        let mut vertices = Vec::new();
        for t in &tris {
            for &i in t {
                if remap[i as usize] == u32::MAX {
                    remap[i as usize] = vertices.len() as u32;
                    vertices.push(points[i as usize]);
                }
            }
        }
        let triangles = tris.iter().map(|t| t.map(|i| remap[i as usize])).collect();
        ConvexPolyhedron::from_mesh(&TriangleMesh::new(vertices, triangles)?)
    }

    /// Validates a triangle mesh as a convex polyhedron: no vertex in front of any face by the
    /// facing predicate ([`face_side`], within [`FACE_TOLERANCE`](crate::solid::FACE_TOLERANCE)
    /// of the plane counts as on it), and closed (every edge shared by exactly two triangles
    /// running opposite ways).
    ///
    /// # Errors
    ///
    /// [`GeomError::NotConvex`] for a vertex in front of a face plane (a non-convex or inside-out
    /// mesh), [`GeomError::OpenMesh`] for an edge without exactly one opposite edge.
    pub fn from_mesh(mesh: &TriangleMesh) -> Result<Self, GeomError> {
        for f in 0..mesh.triangle_count() {
            for (v, &p) in mesh.vertices().iter().enumerate() {
                if face_side(mesh, f, p) == Side::Front {
                    return Err(GeomError::NotConvex { face: f, vertex: v });
                }
            }
        }
        if let Some(e) = mesh.edges().iter().find(|e| e.twin().is_none()) {
            return Err(GeomError::OpenMesh {
                triangle: e.f0 as usize,
                edge: [e.a as usize, e.b as usize],
            });
        }
        Ok(ConvexPolyhedron { mesh: mesh.clone() })
    }

    /// The hull's triangle mesh (outward normals); the per-triangle method and the Monte Carlo
    /// reference use it.
    #[must_use]
    pub fn mesh(&self) -> &TriangleMesh {
        &self.mesh
    }

    /// The vertices.
    #[must_use]
    pub fn vertices(&self) -> &[DVec3] {
        self.mesh.vertices()
    }

    /// The edges with their two adjacent faces (each undirected edge once; `f1` is always set).
    #[must_use]
    pub fn edges(&self) -> &[MeshEdge] {
        self.mesh.edges()
    }

    /// A sphere holding every vertex.
    #[must_use]
    pub fn bounding_sphere(&self) -> BoundingSphere {
        self.mesh.bounding_sphere()
    }

    /// Signed distances of `x` in front of each face plane, and the tolerance below which a face
    /// counts as edge-on: the facing predicate for all faces at once (`Side::of(out[f], tol)` is
    /// `face_side(mesh, f, x)`).
    pub(crate) fn facing(&self, x: DVec3, out: &mut Vec<f64>) -> f64 {
        face_distances(&self.mesh, x, out)
    }

    /// Whether some face is strictly in front of `x` by the facing predicate. A point with none
    /// is inside the polyhedron or on its surface: as a light it sends nothing there (its outer
    /// surface faces away everywhere), while as a blocker it covers what
    /// [`convex_silhouette`](crate::solid::silhouette::convex_silhouette) says.
    pub(crate) fn has_front_face(&self, x: DVec3) -> bool {
        let at = FacingAt::new(&self.mesh, x);
        self.mesh
            .normals()
            .iter()
            .zip(self.mesh.offsets())
            .any(|(n, &d)| at.front(*n, d))
    }
}

/// Exact orientation of `p` against the outward face `(a, b, c)`: positive when `p` is strictly
/// outside (in front of the face), zero on its plane.
#[inline]
fn outside(points: &[DVec3], f: [u32; 3], p: DVec3) -> f64 {
    // robust's orient3d(a, b, c, d) is positive when d is below the plane of a, b, c seen as
    // counter-clockwise from above, i.e. behind an outward face: negate.
    -orient3d(
        c3(points[f[0] as usize]),
        c3(points[f[1] as usize]),
        c3(points[f[2] as usize]),
        c3(p),
    )
}

/// Incremental convex hull (Clarkson–Shor style without conflict lists: every face is tested
/// against every point, `O(n h)`, fine for the few hundred vertices of scene primitives).
fn hull_triangles(points: &[DVec3]) -> Result<Vec<[u32; 3]>, GeomError> {
    const COPLANAR: GeomError = GeomError::Degenerate(
        "the points are (nearly) coplanar or collinear, so their convex hull has no volume; \
         use a TriangleMesh for flat lights",
    );
    if points.len() < 4 {
        return Err(GeomError::TooFewVertices {
            ring: 0,
            count: points.len(),
        });
    }
    // Initial tetrahedron from extreme points, so that it is as well-shaped as the input allows.
    let i0 = 0usize;
    let i1 = (0..points.len())
        .max_by(|&a, &b| {
            (points[a] - points[i0])
                .length_squared()
                .total_cmp(&(points[b] - points[i0]).length_squared())
        })
        .unwrap_or(0);
    let d01 = points[i1] - points[i0];
    let i2 = (0..points.len())
        .max_by(|&a, &b| {
            d01.cross(points[a] - points[i0])
                .length_squared()
                .total_cmp(&d01.cross(points[b] - points[i0]).length_squared())
        })
        .unwrap_or(0);
    let n = d01.cross(points[i2] - points[i0]);
    let scale = d01.length_squared();
    if n.length().is_nan() || n.length() <= DEGENERATE_TRIANGLE * scale {
        return Err(COPLANAR);
    }
    let i3 = (0..points.len())
        .max_by(|&a, &b| {
            n.dot(points[a] - points[i0])
                .abs()
                .total_cmp(&n.dot(points[b] - points[i0]).abs())
        })
        .unwrap_or(0);
    let height = n.dot(points[i3] - points[i0]).abs();
    if height.is_nan() || height <= DEGENERATE_TRIANGLE * scale * d01.length() {
        return Err(COPLANAR);
    }
    let (a, b, c, d) = (i0 as u32, i1 as u32, i2 as u32, i3 as u32);
    // Orient the base so that the fourth point is behind it.
    let base = if outside(points, [a, b, c], points[i3]) > 0.0 {
        [a, c, b]
    } else {
        [a, b, c]
    };
    let [a, b, c] = base;
    let mut faces: Vec<[u32; 3]> = vec![[a, b, c], [a, d, b], [b, d, c], [c, d, a]];
    let mut visible = Vec::new();
    let mut horizon: Vec<(u32, u32)> = Vec::new();
    for (pi, &p) in points.iter().enumerate() {
        let pi = pi as u32;
        if pi == a || pi == b || pi == c || pi == d {
            continue;
        }
        visible.clear();
        visible.extend(faces.iter().map(|&f| outside(points, f, p) > 0.0));
        if !visible.iter().any(|&v| v) {
            continue; // inside or on the hull
        }
        // Horizon: directed edges of visible faces whose reverse belongs to no visible face.
        horizon.clear();
        for (f, _) in faces.iter().zip(&visible).filter(|(_, v)| **v) {
            for k in 0..3 {
                horizon.push((f[k], f[(k + 1) % 3]));
            }
        }
        horizon.sort_unstable();
        let edges: Vec<(u32, u32)> = horizon
            .iter()
            .copied()
            .filter(|&(u, v)| horizon.binary_search(&(v, u)).is_err())
            .collect();
        let mut kept: Vec<[u32; 3]> = faces
            .iter()
            .zip(&visible)
            .filter(|(_, v)| !**v)
            .map(|(f, _)| *f)
            .collect();
        kept.extend(edges.iter().map(|&(u, v)| [u, v, pi]));
        faces = kept;
    }
    Ok(faces)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hull_of_cube_with_interior_points() {
        let mut pts: Vec<DVec3> = (0..8)
            .map(|i| DVec3::new((i & 1) as f64, ((i >> 1) & 1) as f64, ((i >> 2) & 1) as f64))
            .collect();
        pts.push(DVec3::splat(0.5));
        pts.push(DVec3::new(0.5, 0.5, 1.0)); // on a face
        let h = ConvexPolyhedron::hull(&pts).unwrap();
        assert_eq!(h.vertices().len(), 8);
        assert_eq!(h.mesh().triangle_count(), 12);
        // Euler: V - E + F = 2.
        assert_eq!(8 - h.edges().len() as i64 + 12, 2);
    }

    #[test]
    fn open_or_non_convex_meshes_are_not_convex_polyhedra() {
        // An open mesh is not a convex polyhedron.
        let v = vec![DVec3::ZERO, DVec3::X, DVec3::Y];
        let m = TriangleMesh::new(v, vec![[0, 1, 2]]).unwrap();
        assert!(matches!(
            ConvexPolyhedron::from_mesh(&m),
            Err(GeomError::OpenMesh { .. })
        ));
        // A tetrahedron with one face flipped inward is not convex.
        let v = vec![DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::Z];
        let good = vec![[0, 2, 1], [0, 1, 3], [1, 2, 3], [2, 0, 3]];
        assert!(
            ConvexPolyhedron::from_mesh(&TriangleMesh::new(v.clone(), good.clone()).unwrap())
                .is_ok()
        );
        let mut bad = good;
        bad[0] = [0, 1, 2];
        assert!(matches!(
            ConvexPolyhedron::from_mesh(&TriangleMesh::new(v, bad).unwrap()),
            Err(GeomError::NotConvex { .. })
        ));
    }
}
