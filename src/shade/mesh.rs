//! Meshes of lights and occluders: validated triangle meshes, convex polyhedra (with a convex
//! hull constructor) and the primitives of the seed paper's test scene (000, Fig. 4).

use alloc::vec;
use alloc::vec::Vec;
use core::f64::consts::PI;

use crate::sphere::predicates::c3;
use glam::DVec3;
use robust::orient3d;

use crate::GeomError;
use crate::math::{sin_cos, sqrt};

/// Largest coordinate magnitude accepted by the mesh constructors.
///
/// Squared distances and cross products of coordinates must stay finite and keep relative
/// precision; `1e100` leaves a wide margin below `sqrt(f64::MAX) ~ 1.3e154`.
pub const MAX_COORDINATE: f64 = 1e100;

/// A triangle is degenerate when twice its area is at most this fraction of the square of its
/// longest edge (its smallest angle is then below about `1e-12` rad).
///
/// Below that, the face normal is dominated by rounding (a cross product of `f64` edge vectors
/// carries a relative error of a few `1e-16` of the squared edge length), so front/back facing
/// would be a coin toss.
pub const DEGENERATE_TRIANGLE: f64 = 1e-12;

/// Relative tolerance of the "is the point in front of the face plane" test: a face counts as
/// front-facing only when the point lies more than `FACE_TOLERANCE * scale` in front of its plane,
/// with `scale` the polyhedron's bounding radius plus the point's distance to its center.
///
/// The signed distance is evaluated relative to the bounding center, so its rounding error is a
/// few `1e-16 * scale`; `1e-11` is far above that. A point closer to the plane than this sees the
/// face edge-on (zero solid angle) and treats it as back-facing, which handles shading points
/// lying in a face's plane (a cube standing on the ground plane, seen from the ground).
pub const FACE_TOLERANCE: f64 = 1e-11;

/// Checks a vertex list: finite and within [`MAX_COORDINATE`]. `ring` in the error is 0.
fn check_vertices(vertices: &[DVec3]) -> Result<(), GeomError> {
    for (i, v) in vertices.iter().enumerate() {
        if !v.is_finite() {
            return Err(GeomError::NonFinite { ring: 0, vertex: i });
        }
        let m = v.abs().max_element();
        if m > MAX_COORDINATE {
            return Err(GeomError::OutOfRange {
                what: "mesh vertex coordinate",
                value: m,
                limit: MAX_COORDINATE,
            });
        }
    }
    Ok(())
}

/// Center of the axis-aligned bounding box and the largest distance from it to a vertex: a
/// bounding sphere (not the smallest one, but within a factor `sqrt 3` of it), used for culling.
fn bounding_sphere(vertices: &[DVec3]) -> (DVec3, f64) {
    let Some(&first) = vertices.first() else {
        return (DVec3::ZERO, 0.0);
    };
    let (lo, hi) = vertices
        .iter()
        .fold((first, first), |(lo, hi), &v| (lo.min(v), hi.max(v)));
    let c = 0.5 * (lo + hi);
    let r2 = vertices
        .iter()
        .map(|&v| (v - c).length_squared())
        .fold(0.0, f64::max);
    // Pad by a relative ulp margin so that the sphere truly contains every vertex after rounding.
    (c, sqrt(r2) * (1.0 + 1e-12))
}

/// A triangle mesh: vertices and index triples. Triangles are counter-clockwise seen from the
/// side their normal points to (outside, for a closed mesh); that side is the emitting side of a
/// light.
///
/// The mesh need not be closed, convex or manifold: lights and occluders built from it use the
/// per-triangle method (seed paper 000, section 4.4). Values are valid: coordinates are finite
/// and at most [`MAX_COORDINATE`] in magnitude, indices are in range and no triangle is
/// degenerate ([`DEGENERATE_TRIANGLE`]).
///
/// # Examples
///
/// ```
/// use arealight::glam::DVec3;
/// use arealight::shade::TriangleMesh;
/// // A unit square in the plane z = 2, facing down (-z).
/// let quad = TriangleMesh::quad(DVec3::new(0.0, 0.0, 2.0), DVec3::Y * 0.5, DVec3::X * 0.5)?;
/// assert_eq!(quad.triangle_count(), 2);
/// assert!(quad.triangle_normal(0).z < 0.0);
/// # Ok::<(), arealight::GeomError>(())
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct TriangleMesh {
    vertices: Vec<DVec3>,
    triangles: Vec<[u32; 3]>,
    /// Unit normal of each triangle.
    normals: Vec<DVec3>,
    center: DVec3,
    radius: f64,
    /// All triangles in one plane, facing the same way.
    planar: bool,
    /// Every directed edge has exactly one reversed twin (a closed, consistently oriented
    /// surface).
    closed: bool,
}

impl TriangleMesh {
    /// Builds and validates a mesh.
    ///
    /// # Errors
    ///
    /// - [`GeomError::NonFinite`] / [`GeomError::OutOfRange`] for a bad coordinate (`vertex` is the
    ///   vertex index);
    /// - [`GeomError::InvalidIndex`] for an index past the vertex list;
    /// - [`GeomError::DegenerateTriangle`] for a triangle with (nearly) zero area or a repeated
    ///   index;
    /// - [`GeomError::TooFewVertices`] for a mesh without triangles.
    pub fn new(vertices: Vec<DVec3>, triangles: Vec<[u32; 3]>) -> Result<Self, GeomError> {
        check_vertices(&vertices)?;
        if triangles.is_empty() {
            return Err(GeomError::TooFewVertices { ring: 0, count: 0 });
        }
        let mut normals = Vec::with_capacity(triangles.len());
        for (t, tri) in triangles.iter().enumerate() {
            for &i in tri {
                if i as usize >= vertices.len() {
                    return Err(GeomError::InvalidIndex {
                        triangle: t,
                        index: i as usize,
                    });
                }
            }
            let [a, b, c] = tri.map(|i| vertices[i as usize]);
            normals.push(
                triangle_normal(a, b, c).ok_or(GeomError::DegenerateTriangle { triangle: t })?,
            );
        }
        let (center, radius) = bounding_sphere(&vertices);
        let n0 = normals[0];
        let p0 = vertices[triangles[0][0] as usize];
        let planar = normals.iter().all(|n| (*n - n0).length() <= 1e-12)
            && vertices
                .iter()
                .all(|v| n0.dot(*v - p0).abs() <= FACE_TOLERANCE * radius);
        let closed = is_closed(&triangles);
        Ok(TriangleMesh {
            vertices,
            triangles,
            normals,
            center,
            radius,
            planar,
            closed,
        })
    }

    /// A planar quad light or occluder: the parallelogram `center +- u +- v`, two triangles,
    /// facing `u x v` (counter-clockwise seen from that side).
    ///
    /// # Errors
    ///
    /// As [`TriangleMesh::new`]: non-finite input, or `u` and `v` (nearly) parallel.
    pub fn quad(center: DVec3, u: DVec3, v: DVec3) -> Result<Self, GeomError> {
        TriangleMesh::new(
            vec![
                center - u - v,
                center + u - v,
                center + u + v,
                center - u + v,
            ],
            vec![[0, 1, 2], [0, 2, 3]],
        )
    }

    /// The vertices.
    #[must_use]
    pub fn vertices(&self) -> &[DVec3] {
        &self.vertices
    }

    /// The triangles, as indices into [`TriangleMesh::vertices`].
    #[must_use]
    pub fn triangles(&self) -> &[[u32; 3]] {
        &self.triangles
    }

    /// Number of triangles.
    #[must_use]
    pub fn triangle_count(&self) -> usize {
        self.triangles.len()
    }

    /// The three corners of triangle `i` (panics if `i` is out of range, like slice indexing).
    #[must_use]
    pub fn triangle(&self, i: usize) -> [DVec3; 3] {
        self.triangles[i].map(|k| self.vertices[k as usize])
    }

    /// The unit normal of triangle `i` (the side it faces).
    #[must_use]
    pub fn triangle_normal(&self, i: usize) -> DVec3 {
        self.normals[i]
    }

    /// A sphere holding every vertex: `(center, radius)`.
    #[must_use]
    pub fn bounding_sphere(&self) -> (DVec3, f64) {
        (self.center, self.radius)
    }

    /// Whether every vertex lies in one plane and every triangle faces the same way (a flat
    /// light such as a quad). The triangles of a planar mesh are assumed not to overlap, so their
    /// projections from any point are disjoint.
    #[must_use]
    pub fn is_planar(&self) -> bool {
        self.planar
    }

    /// Whether the mesh is a closed, consistently oriented surface: every directed edge `a -> b`
    /// of a triangle has exactly one reversed twin `b -> a` in another triangle (by vertex index).
    ///
    /// Seen from outside a closed mesh, every ray that meets the mesh meets a front face first
    /// (it has to enter), which is why the union of the front faces is the region a closed light
    /// covers; an open mesh (sheets) can show a back face first, which then hides what lies
    /// behind it.
    #[must_use]
    pub fn is_closed(&self) -> bool {
        self.closed
    }

    /// The mesh of all triangles of `self` and `other` (no vertices are merged).
    ///
    /// # Errors
    ///
    /// Never for valid inputs; the `Result` guards the index range (more than `u32::MAX`
    /// vertices is [`GeomError::OutOfRange`]).
    pub fn merged(&self, other: &TriangleMesh) -> Result<Self, GeomError> {
        let n = self.vertices.len();
        if n + other.vertices.len() > u32::MAX as usize {
            return Err(GeomError::OutOfRange {
                what: "vertex count",
                value: (n + other.vertices.len()) as f64,
                limit: u32::MAX as f64,
            });
        }
        let mut vertices = self.vertices.clone();
        vertices.extend_from_slice(&other.vertices);
        let mut triangles = self.triangles.clone();
        triangles.extend(other.triangles.iter().map(|t| t.map(|i| i + n as u32)));
        TriangleMesh::new(vertices, triangles)
    }
}

/// Whether every directed edge of `triangles` has exactly one reversed twin and no directed edge
/// repeats (see [`TriangleMesh::is_closed`]).
fn is_closed(triangles: &[[u32; 3]]) -> bool {
    let mut directed: Vec<(u32, u32)> = triangles
        .iter()
        .flat_map(|t| (0..3).map(move |k| (t[k], t[(k + 1) % 3])))
        .collect();
    directed.sort_unstable();
    if directed.windows(2).any(|w| w[0] == w[1]) {
        return false;
    }
    directed
        .iter()
        .all(|&(a, b)| directed.binary_search(&(b, a)).is_ok())
}

/// Unit normal of the triangle `(a, b, c)` (counter-clockwise seen from the side it points to),
/// or `None` when the triangle is degenerate in the sense of [`DEGENERATE_TRIANGLE`].
fn triangle_normal(a: DVec3, b: DVec3, c: DVec3) -> Option<DVec3> {
    let (e0, e1, e2) = (b - a, c - b, a - c);
    let longest2 = e0
        .length_squared()
        .max(e1.length_squared())
        .max(e2.length_squared());
    // The cross product of the two edges adjacent to the largest angle is the best conditioned.
    let n = e0.cross(-e2);
    let len = n.length();
    if len.is_nan() || len <= DEGENERATE_TRIANGLE * longest2 || !len.is_finite() {
        return None;
    }
    Some(n / len)
}

/// An edge of a convex polyhedron with its two faces. It runs `a -> b` counter-clockwise around
/// face `f0` (seen from outside), hence `b -> a` around `f1`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct HullEdge {
    /// First vertex (index into [`ConvexPolyhedron::vertices`]).
    pub a: u32,
    /// Second vertex.
    pub b: u32,
    /// The face (triangle index) around which `a -> b` is counter-clockwise.
    pub f0: u32,
    /// The other face.
    pub f1: u32,
}

/// A convex polyhedron: a closed triangle mesh with outward normals, every vertex on or behind
/// every face plane, and its edge list with adjacent faces (thesis 003, section 4.2: "store the
/// edges of the polyhedron along with the normals of the adjacent faces").
///
/// Coplanar faces are allowed (a cube has two triangles per side); an edge between coplanar
/// faces is never on the silhouette, because both faces are front-facing or neither is.
///
/// # Examples
///
/// ```
/// use arealight::glam::DVec3;
/// use arealight::shade::ConvexPolyhedron;
/// let cube = ConvexPolyhedron::cuboid(DVec3::ZERO, DVec3::ONE)?;
/// assert_eq!(cube.vertices().len(), 8);
/// assert_eq!(cube.mesh().triangle_count(), 12);
/// assert_eq!(cube.edges().len(), 18);
/// // Points that are not in convex position are rejected by `from_mesh`, and coplanar point
/// // sets by `hull`.
/// assert!(ConvexPolyhedron::hull(&[DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::X + DVec3::Y]).is_err());
/// # Ok::<(), arealight::GeomError>(())
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct ConvexPolyhedron {
    mesh: TriangleMesh,
    /// Per face: `n . (y - center) = offset` on the plane.
    offsets: Vec<f64>,
    edges: Vec<HullEdge>,
}

impl ConvexPolyhedron {
    /// The convex hull of a point set (incremental construction with Shewchuk's exact `orient3d`,
    /// so every visibility decision is exact for the given coordinates). Points inside the hull
    /// or on its faces are dropped; duplicates are allowed.
    ///
    /// # Errors
    ///
    /// - [`GeomError::NonFinite`] / [`GeomError::OutOfRange`] for a bad coordinate;
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

    /// Validates a triangle mesh as a convex polyhedron: closed (every directed edge has exactly
    /// one opposite), every vertex at most `FACE_TOLERANCE * radius` in front of every face plane.
    ///
    /// # Errors
    ///
    /// [`GeomError::OpenMesh`] for an edge without exactly one opposite edge, [`GeomError::NotConvex`]
    /// for a vertex in front of a face plane (a non-convex or inside-out mesh).
    pub fn from_mesh(mesh: &TriangleMesh) -> Result<Self, GeomError> {
        let (center, radius) = mesh.bounding_sphere();
        let offsets: Vec<f64> = (0..mesh.triangle_count())
            .map(|f| mesh.normals[f].dot(mesh.triangle(f)[0] - center))
            .collect();
        let tol = FACE_TOLERANCE * radius;
        for (f, (&n, &d)) in mesh.normals.iter().zip(&offsets).enumerate() {
            for (v, &p) in mesh.vertices.iter().enumerate() {
                if n.dot(p - center) - d > tol {
                    return Err(GeomError::NotConvex { face: f, vertex: v });
                }
            }
        }
        // Pair directed edges: sort (min, max, face, dir) and match neighbours.
        let mut half: Vec<(u32, u32, u32, u32)> = Vec::with_capacity(3 * mesh.triangle_count());
        for (f, t) in mesh.triangles.iter().enumerate() {
            for k in 0..3 {
                let (a, b) = (t[k], t[(k + 1) % 3]);
                half.push((a.min(b), a.max(b), f as u32, u32::from(a > b)));
            }
        }
        half.sort_unstable();
        let mut edges = Vec::with_capacity(half.len() / 2);
        let mut i = 0;
        while i < half.len() {
            let (lo, hi, f, dir) = half[i];
            let ok = i + 1 < half.len()
                && half[i + 1].0 == lo
                && half[i + 1].1 == hi
                && half[i + 1].3 != dir
                && (i + 2 >= half.len() || half[i + 2].0 != lo || half[i + 2].1 != hi);
            if !ok {
                return Err(GeomError::OpenMesh {
                    triangle: f as usize,
                });
            }
            let g = half[i + 1].2;
            // dir == 0 means this face runs lo -> hi.
            let (a, b, f0, f1) = if dir == 0 {
                (lo, hi, f, g)
            } else {
                (lo, hi, g, f)
            };
            edges.push(HullEdge { a, b, f0, f1 });
            i += 2;
        }
        Ok(ConvexPolyhedron {
            mesh: mesh.clone(),
            offsets,
            edges,
        })
    }

    /// An axis-aligned box `center +- half_extents` (8 vertices, 12 triangles).
    ///
    /// # Errors
    ///
    /// Non-finite input, or a (nearly) zero extent ([`GeomError::Degenerate`]).
    pub fn cuboid(center: DVec3, half_extents: DVec3) -> Result<Self, GeomError> {
        let h = half_extents;
        let pts: Vec<DVec3> = (0..8)
            .map(|i| {
                center
                    + DVec3::new(
                        if i & 1 == 0 { -h.x } else { h.x },
                        if i & 2 == 0 { -h.y } else { h.y },
                        if i & 4 == 0 { -h.z } else { h.z },
                    )
            })
            .collect();
        ConvexPolyhedron::hull(&pts)
    }

    /// A sphere approximated by an icosahedron subdivided `subdivisions` times (12, 42, 162, ...
    /// vertices), with every vertex on the sphere.
    ///
    /// # Errors
    ///
    /// Non-finite input or a non-positive radius; `subdivisions > 5` is
    /// [`GeomError::OutOfRange`] (over 10 000 vertices: use a mesh instead).
    pub fn icosphere(center: DVec3, radius: f64, subdivisions: u32) -> Result<Self, GeomError> {
        ConvexPolyhedron::ellipsoid_icosphere(center, DVec3::splat(radius), subdivisions)
    }

    /// As [`ConvexPolyhedron::icosphere`], scaled by `radii` along the axes.
    ///
    /// # Errors
    ///
    /// As [`ConvexPolyhedron::icosphere`].
    pub fn ellipsoid_icosphere(
        center: DVec3,
        radii: DVec3,
        subdivisions: u32,
    ) -> Result<Self, GeomError> {
        if subdivisions > 5 {
            return Err(GeomError::OutOfRange {
                what: "icosphere subdivisions",
                value: f64::from(subdivisions),
                limit: 5.0,
            });
        }
        let pts = icosphere_points(subdivisions);
        ConvexPolyhedron::hull(&pts.iter().map(|&p| center + p * radii).collect::<Vec<_>>())
    }

    /// An ellipsoid with semi-axes `radii` as a latitude-longitude polyhedron: two poles and
    /// `rings x segments` vertices (the seed paper's ellipsoid has 154 vertices, e.g. 8 x 19 + 2).
    ///
    /// # Errors
    ///
    /// Non-finite input, a zero radius, `rings < 1` or `segments < 3`
    /// ([`GeomError::OutOfRange`]).
    pub fn ellipsoid(
        center: DVec3,
        radii: DVec3,
        rings: u32,
        segments: u32,
    ) -> Result<Self, GeomError> {
        if rings < 1 || segments < 3 || rings > 1000 || segments > 1000 {
            return Err(GeomError::OutOfRange {
                what: "ellipsoid rings (>= 1) or segments (>= 3), each at most",
                value: f64::from(rings.min(segments)),
                limit: 1000.0,
            });
        }
        let mut pts = vec![
            center + DVec3::new(0.0, 0.0, radii.z),
            center - DVec3::new(0.0, 0.0, radii.z),
        ];
        for r in 1..=rings {
            let (st, ct) = sin_cos(PI * f64::from(r) / f64::from(rings + 1));
            for s in 0..segments {
                let (sp, cp) = sin_cos(2.0 * PI * f64::from(s) / f64::from(segments));
                pts.push(center + radii * DVec3::new(st * cp, st * sp, ct));
            }
        }
        ConvexPolyhedron::hull(&pts)
    }

    /// A truncated cone (frustum) along `axis` from `base` (radius `r0`) to `base + axis` (radius
    /// `r1`), with `segments` vertices on each rim. With `r0 == r1` it is a cylinder; the seed
    /// paper's cylinder and truncated-cone lights have 20 vertices (`segments = 10`).
    ///
    /// # Errors
    ///
    /// Non-finite input, a zero axis, `segments < 3` or a negative radius
    /// ([`GeomError::OutOfRange`]); both radii zero is [`GeomError::Degenerate`].
    pub fn frustum(
        base: DVec3,
        axis: DVec3,
        r0: f64,
        r1: f64,
        segments: u32,
    ) -> Result<Self, GeomError> {
        if !(3..=10_000).contains(&segments) {
            return Err(GeomError::OutOfRange {
                what: "frustum segments (at least 3)",
                value: f64::from(segments),
                limit: 10_000.0,
            });
        }
        if r0.is_nan() || r1.is_nan() || r0 < 0.0 || r1 < 0.0 {
            return Err(GeomError::OutOfRange {
                what: "frustum radius (non-negative)",
                value: if r0 >= 0.0 { r1 } else { r0 },
                limit: MAX_COORDINATE,
            });
        }
        let len = axis.length();
        if len.is_nan() || len <= 0.0 || !len.is_finite() {
            return Err(GeomError::ZeroVector { ring: 0, vertex: 0 });
        }
        let w = axis / len;
        let (u, v) = w.any_orthonormal_pair();
        let mut pts = Vec::with_capacity(2 * segments as usize);
        for (c, r) in [(base, r0), (base + axis, r1)] {
            if r == 0.0 {
                pts.push(c);
                continue;
            }
            for s in 0..segments {
                let (sp, cp) = sin_cos(2.0 * PI * f64::from(s) / f64::from(segments));
                pts.push(c + r * (cp * u + sp * v));
            }
        }
        ConvexPolyhedron::hull(&pts)
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
        &self.mesh.vertices
    }

    /// The edges with their adjacent faces (each undirected edge once).
    #[must_use]
    pub fn edges(&self) -> &[HullEdge] {
        &self.edges
    }

    /// A sphere holding every vertex: `(center, radius)`.
    #[must_use]
    pub fn bounding_sphere(&self) -> (DVec3, f64) {
        self.mesh.bounding_sphere()
    }

    /// Signed distances of `x` in front of each face plane, and the tolerance below which a face
    /// counts as edge-on ([`FACE_TOLERANCE`]).
    pub(crate) fn facing(&self, x: DVec3, out: &mut Vec<f64>) -> f64 {
        let (c, r) = self.bounding_sphere();
        let rel = x - c;
        out.clear();
        out.extend(
            self.mesh
                .normals
                .iter()
                .zip(&self.offsets)
                .map(|(n, d)| n.dot(rel) - d),
        );
        FACE_TOLERANCE * (r + rel.length())
    }
}

/// The 12 vertices of the icosahedron on the unit sphere, subdivided `n` times (each triangle
/// into four, midpoints pushed to the sphere).
fn icosphere_points(n: u32) -> Vec<DVec3> {
    let t = (1.0 + sqrt(5.0)) / 2.0;
    let mut pts: Vec<DVec3> = [
        (-1.0, t, 0.0),
        (1.0, t, 0.0),
        (-1.0, -t, 0.0),
        (1.0, -t, 0.0),
        (0.0, -1.0, t),
        (0.0, 1.0, t),
        (0.0, -1.0, -t),
        (0.0, 1.0, -t),
        (t, 0.0, -1.0),
        (t, 0.0, 1.0),
        (-t, 0.0, -1.0),
        (-t, 0.0, 1.0),
    ]
    .iter()
    .map(|&(x, y, z)| DVec3::new(x, y, z).normalize())
    .collect();
    let mut tris: Vec<[usize; 3]> = vec![
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    for _ in 0..n {
        let mut mid = alloc::collections::BTreeMap::new();
        let mut next = Vec::with_capacity(4 * tris.len());
        for &[a, b, c] in &tris {
            let mut m = |i: usize, j: usize| {
                *mid.entry((i.min(j), i.max(j))).or_insert_with(|| {
                    pts.push((pts[i] + pts[j]).normalize());
                    pts.len() - 1
                })
            };
            let (ab, bc, ca) = (m(a, b), m(b, c), m(c, a));
            next.extend([[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]);
        }
        tris = next;
    }
    pts
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
    fn primitives_have_expected_vertex_counts() {
        let ico = ConvexPolyhedron::icosphere(DVec3::ZERO, 1.0, 1).unwrap();
        assert_eq!(ico.vertices().len(), 42);
        let cyl = ConvexPolyhedron::frustum(DVec3::ZERO, DVec3::Z, 1.0, 1.0, 10).unwrap();
        assert_eq!(cyl.vertices().len(), 20);
        let cone = ConvexPolyhedron::frustum(DVec3::ZERO, DVec3::Z, 1.0, 0.5, 10).unwrap();
        assert_eq!(cone.vertices().len(), 20);
        let ell =
            ConvexPolyhedron::ellipsoid(DVec3::ZERO, DVec3::new(1.0, 0.5, 0.7), 8, 19).unwrap();
        assert_eq!(ell.vertices().len(), 154);
        for p in [&ico, &cyl, &cone, &ell] {
            let v = p.vertices().len() as i64;
            assert_eq!(
                v - p.edges().len() as i64 + p.mesh().triangle_count() as i64,
                2
            );
        }
    }

    #[test]
    fn closedness() {
        let cube = ConvexPolyhedron::cuboid(DVec3::ZERO, DVec3::ONE).unwrap();
        assert!(cube.mesh().is_closed());
        let quad = TriangleMesh::quad(DVec3::ZERO, DVec3::X, DVec3::Y).unwrap();
        assert!(!quad.is_closed());
        // Two closed parts are closed; a closed part plus a sheet is not.
        assert!(cube.mesh().merged(cube.mesh()).unwrap().is_closed());
        assert!(!cube.mesh().merged(&quad).unwrap().is_closed());
        // A triangle and its reverse form a closed (two-sided) surface; a repeated triangle does
        // not.
        let v = vec![DVec3::ZERO, DVec3::X, DVec3::Y];
        assert!(
            TriangleMesh::new(v.clone(), vec![[0, 1, 2], [0, 2, 1]])
                .unwrap()
                .is_closed()
        );
        assert!(
            !TriangleMesh::new(v, vec![[0, 1, 2], [0, 1, 2], [0, 2, 1]])
                .unwrap()
                .is_closed()
        );
    }

    #[test]
    fn invalid_meshes_are_errors() {
        let v = vec![DVec3::ZERO, DVec3::X, DVec3::Y];
        assert!(matches!(
            TriangleMesh::new(v.clone(), vec![[0, 1, 3]]),
            Err(GeomError::InvalidIndex { .. })
        ));
        assert!(matches!(
            TriangleMesh::new(v.clone(), vec![[0, 1, 1]]),
            Err(GeomError::DegenerateTriangle { .. })
        ));
        assert!(matches!(
            TriangleMesh::new(vec![DVec3::ZERO, DVec3::X, DVec3::NAN], vec![[0, 1, 2]]),
            Err(GeomError::NonFinite { .. })
        ));
        // An open mesh is not a convex polyhedron.
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
        assert!(ConvexPolyhedron::from_mesh(&TriangleMesh::new(v, bad).unwrap()).is_err());
    }
}
