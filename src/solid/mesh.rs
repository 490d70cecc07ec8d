//! Validated triangle meshes with edge adjacency, and the bounding spheres the culling uses.

use alloc::vec::Vec;

use glam::DVec3;

use super::facing::FACE_TOLERANCE;
use crate::GeomError;
use crate::math::sqrt;

/// Largest coordinate magnitude accepted by the mesh constructors.
///
/// Squared distances and cross products of coordinates must stay finite and keep relative
/// precision; `1e100` leaves a wide margin below `sqrt(f64::MAX) ~ 1.3e154`. (The planar layer's
/// limit, [`crate::planar::MAX_COORD`], is higher: its predicates square coordinates only once.)
pub const MAX_MESH_COORD: f64 = 1e100;

/// A triangle is degenerate when twice its area is at most this fraction of the square of its
/// longest edge (its smallest angle is then below about `1e-12` rad).
///
/// Below that, the face normal is dominated by rounding (a cross product of `f64` edge vectors
/// carries a relative error of a few `1e-16` of the squared edge length), so front/back facing
/// would be a coin toss.
pub const DEGENERATE_TRIANGLE: f64 = 1e-12;

/// A sphere holding an object: what the culling tests and the scale-relative tolerances use.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BoundingSphere {
    /// Center.
    pub center: DVec3,
    /// Radius (non-negative).
    pub radius: f64,
}

/// Checks a vertex list: finite and within [`MAX_MESH_COORD`]. `ring` in the error is 0.
pub(crate) fn check_vertices(vertices: &[DVec3]) -> Result<(), GeomError> {
    for (i, v) in vertices.iter().enumerate() {
        if !v.is_finite() {
            return Err(GeomError::NonFinite { ring: 0, vertex: i });
        }
        let m = v.abs().max_element();
        if m > MAX_MESH_COORD {
            return Err(GeomError::OutOfRange {
                what: "mesh vertex coordinate",
                value: m,
                limit: MAX_MESH_COORD,
            });
        }
    }
    Ok(())
}

/// Center of the axis-aligned bounding box and the largest distance from it to a vertex: a
/// bounding sphere (not the smallest one, but within a factor `sqrt 3` of it), used for culling.
fn bounding_sphere(vertices: &[DVec3]) -> BoundingSphere {
    let Some(&first) = vertices.first() else {
        return BoundingSphere {
            center: DVec3::ZERO,
            radius: 0.0,
        };
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
    BoundingSphere {
        center: c,
        radius: sqrt(r2) * (1.0 + 1e-12),
    }
}

/// An edge of a triangle mesh with the triangles on either side. It runs `a -> b`
/// counter-clockwise around triangle `f0` (seen from the side its normal points to), hence
/// `b -> a` around `f1`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct MeshEdge {
    /// First vertex (index into [`TriangleMesh::vertices`]).
    pub a: u32,
    /// Second vertex.
    pub b: u32,
    /// The triangle around which `a -> b` is counter-clockwise.
    pub f0: u32,
    /// The triangle running `b -> a` along the same edge, or [`MeshEdge::BORDER`] on a border (the
    /// edge belongs to `f0` alone) and on a non-manifold or inconsistently oriented edge (more
    /// than two triangles, or two running the same way: each of them is then listed as an edge of
    /// its own). A plain index rather than an `Option`, so that the silhouette loop over a convex
    /// polyhedron's edges (all paired) tests nothing.
    pub f1: u32,
}

impl MeshEdge {
    /// The value of [`MeshEdge::f1`] for an edge with one triangle.
    pub const BORDER: u32 = u32::MAX;

    /// The second triangle, `None` for a border or non-manifold edge.
    #[must_use]
    pub fn twin(&self) -> Option<u32> {
        (self.f1 != MeshEdge::BORDER).then_some(self.f1)
    }
}

/// A triangle mesh: vertices and index triples. Triangles are counter-clockwise seen from the
/// side their normal points to (outside, for a closed mesh); that side is the emitting side of a
/// light.
///
/// The mesh need not be closed, convex or manifold: lights and occluders built from it use the
/// per-triangle method (seed paper 000, section 4.4). Values are valid: coordinates are finite
/// and at most [`MAX_MESH_COORD`] in magnitude, indices are in range and no triangle is
/// degenerate ([`DEGENERATE_TRIANGLE`]). Construction also records each triangle's unit normal,
/// its plane's offset for the facing predicate ([`crate::solid::face_side`]) and the edge
/// adjacency ([`TriangleMesh::edges`]).
///
/// # Examples
///
/// ```
/// use arealight::glam::DVec3;
/// use arealight::solid::TriangleMesh;
/// // A unit square in the plane z = 2, facing down (-z).
/// let quad = TriangleMesh::quad(DVec3::new(0.0, 0.0, 2.0), DVec3::Y * 0.5, DVec3::X * 0.5)?;
/// assert_eq!(quad.triangle_count(), 2);
/// assert!(quad.triangle_normal(0).z < 0.0);
/// // The diagonal is shared; the four sides are borders.
/// assert_eq!(quad.edges().iter().filter(|e| e.twin().is_some()).count(), 1);
/// assert_eq!(quad.edges().len(), 5);
/// # Ok::<(), arealight::GeomError>(())
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct TriangleMesh {
    vertices: Vec<DVec3>,
    triangles: Vec<[u32; 3]>,
    /// Unit normal of each triangle.
    normals: Vec<DVec3>,
    /// Per triangle `f`: `normals[f] . (a_f - bounds.center)`, `a_f` its first corner, so that
    /// the signed distance of `x` from its plane is `normals[f] . (x - center) - offsets[f]`.
    offsets: Vec<f64>,
    edges: Vec<MeshEdge>,
    bounds: BoundingSphere,
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
        let bounds = bounding_sphere(&vertices);
        let offsets = triangles
            .iter()
            .zip(&normals)
            .map(|(t, n)| n.dot(vertices[t[0] as usize] - bounds.center))
            .collect();
        let n0 = normals[0];
        let p0 = vertices[triangles[0][0] as usize];
        let planar = normals.iter().all(|n| (*n - n0).length() <= 1e-12)
            && vertices
                .iter()
                .all(|v| n0.dot(*v - p0).abs() <= FACE_TOLERANCE * bounds.radius);
        let (edges, closed) = edge_adjacency(&triangles);
        Ok(TriangleMesh {
            vertices,
            triangles,
            normals,
            offsets,
            edges,
            bounds,
            planar,
            closed,
        })
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

    /// The unit normals of all triangles, in triangle order.
    pub(crate) fn normals(&self) -> &[DVec3] {
        &self.normals
    }

    /// The plane offsets of all triangles relative to the bounding center (see the field).
    pub(crate) fn offsets(&self) -> &[f64] {
        &self.offsets
    }

    /// A sphere holding every vertex.
    #[must_use]
    pub fn bounding_sphere(&self) -> BoundingSphere {
        self.bounds
    }

    /// The edges with the triangles on either side, each undirected edge once (sorted by vertex
    /// indices). On a closed mesh every edge has two triangles.
    #[must_use]
    pub fn edges(&self) -> &[MeshEdge] {
        &self.edges
    }

    /// Whether every vertex lies in one plane and every triangle faces the same way (a flat
    /// light such as a quad). A planar light's triangles must not overlap, so that their
    /// projections from any point are disjoint ([`Light::new`](crate::shade::Light::new) checks).
    #[must_use]
    pub fn is_planar(&self) -> bool {
        self.planar
    }

    /// For a planar mesh, the first pair of triangles (by index) whose interiors overlap, or
    /// `None` (also for a non-planar mesh). Exact: the triangles are projected to the coordinate
    /// plane their common normal is most nearly perpendicular to, which keeps the coordinates
    /// as given, and two triangles have disjoint interiors iff an edge line of one has the other
    /// on its closed outer side (separating axes of two convex polygons), decided by Shewchuk's
    /// `orient2d`. Boxes are swept along the first coordinate, so the cost is about `n log n`
    /// plus the pairs whose boxes overlap.
    pub(crate) fn planar_overlap(&self) -> Option<(usize, usize)> {
        if !self.planar {
            return None;
        }
        let n = self.normals[0].abs();
        let (i, j) = if n.x >= n.y && n.x >= n.z {
            (1, 2)
        } else if n.y >= n.z {
            (2, 0)
        } else {
            (0, 1)
        };
        let p = |v: u32| {
            let v = self.vertices[v as usize].to_array();
            robust::Coord { x: v[i], y: v[j] }
        };
        // Counter-clockwise in the projection: the orientation every triangle shares.
        let tris: Vec<[robust::Coord<f64>; 3]> = self
            .triangles
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(p);
                if robust::orient2d(a, b, c) < 0.0 {
                    [a, c, b]
                } else {
                    [a, b, c]
                }
            })
            .collect();
        // Each triangle's extent along the first coordinate, for the sweep.
        let spans: Vec<(f64, f64)> = tris
            .iter()
            .map(|t| {
                let xs = t.map(|c| c.x);
                (xs[0].min(xs[1]).min(xs[2]), xs[0].max(xs[1]).max(xs[2]))
            })
            .collect();
        let separated = |s: &[robust::Coord<f64>; 3], t: &[robust::Coord<f64>; 3]| {
            (0..3).any(|k| {
                let (a, b) = (s[k], s[(k + 1) % 3]);
                t.iter().all(|&c| robust::orient2d(a, b, c) <= 0.0)
            })
        };
        let mut order: Vec<usize> = (0..tris.len()).collect();
        order.sort_by(|&a, &b| spans[a].0.total_cmp(&spans[b].0));
        let mut found: Option<(usize, usize)> = None;
        for (k, &a) in order.iter().enumerate() {
            let hi = spans[a].1;
            for &b in &order[k + 1..] {
                if spans[b].0 >= hi {
                    break;
                }
                if !separated(&tris[a], &tris[b]) && !separated(&tris[b], &tris[a]) {
                    let pair = (a.min(b), a.max(b));
                    if found.is_none_or(|f| pair < f) {
                        found = Some(pair);
                    }
                }
            }
        }
        found
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

    /// The boundary of the mesh as closed loops of vertex indices: the directed edges of all
    /// triangles with every pair of opposite copies `a -> b`, `b -> a` cancelled, walked into
    /// loops (each loop's closing edge runs from its last vertex to its first).
    ///
    /// As a chain of directed edges this is the boundary of the sum of the triangles, so the
    /// loops wind around each point as many times as the triangles cover it (counted with the
    /// sign of their orientation). For a planar mesh, whose triangles all face the same way and
    /// do not overlap, the loops bound exactly the union of the triangles: counter-clockwise
    /// about the normal for each outer boundary, clockwise for each hole. A quad's loop is its
    /// four corners; a closed mesh has none. Loops may pass through a vertex more than once
    /// (two parts of the mesh touching at a corner). Computed in `O(n log n)` for `n` triangles;
    /// the shading layer computes it once per planar mesh light, whose region seen from a point is
    /// then one polygon instead of a union of triangles.
    ///
    /// # Examples
    ///
    /// ```
    /// use arealight::glam::DVec3;
    /// use arealight::solid::TriangleMesh;
    /// let quad = TriangleMesh::quad(DVec3::ZERO, DVec3::X, DVec3::Y)?;
    /// assert_eq!(quad.boundary_loops(), vec![vec![0, 1, 2, 3]]);
    /// # Ok::<(), arealight::GeomError>(())
    /// ```
    #[must_use]
    pub fn boundary_loops(&self) -> Vec<Vec<u32>> {
        // Net multiplicity of each undirected edge, positive along `lo -> hi`.
        let mut half: Vec<(u32, u32, i32)> = Vec::with_capacity(3 * self.triangles.len());
        for t in &self.triangles {
            for k in 0..3 {
                let (a, b) = (t[k], t[(k + 1) % 3]);
                half.push((a.min(b), a.max(b), if a < b { 1 } else { -1 }));
            }
        }
        half.sort_unstable();
        let mut directed: Vec<(u32, u32)> = Vec::new();
        let mut i = 0;
        while i < half.len() {
            let (lo, hi) = (half[i].0, half[i].1);
            let mut net = 0;
            while i < half.len() && half[i].0 == lo && half[i].1 == hi {
                net += half[i].2;
                i += 1;
            }
            let e = if net > 0 { (lo, hi) } else { (hi, lo) };
            directed.extend(core::iter::repeat_n(e, net.unsigned_abs() as usize));
        }
        // Every vertex has as many outgoing as incoming boundary edges (the boundary of a sum of
        // closed triangles is closed), so a walk that leaves a vertex along unused edges can
        // only stop where it started.
        directed.sort_unstable();
        let mut used = alloc::vec![false; directed.len()];
        let mut loops = Vec::new();
        for start in 0..directed.len() {
            if used[start] {
                continue;
            }
            let mut ring = Vec::new();
            let mut k = start;
            loop {
                used[k] = true;
                let (a, b) = directed[k];
                ring.push(a);
                if b == directed[start].0 {
                    break;
                }
                // The first unused edge out of `b`.
                let from = directed.partition_point(|&(s, _)| s < b);
                match (from..directed.len()).find(|&j| directed[j].0 == b && !used[j]) {
                    Some(j) => k = j,
                    None => break,
                }
            }
            loops.push(ring);
        }
        loops
    }

    /// The same surface facing the other way: each triangle's corners in reverse order (the
    /// first corner kept), so every normal, and the side a light emits from, is turned around.
    ///
    /// Exact: the normals and plane offsets are the negated ones, bit for bit (what
    /// [`TriangleMesh::new`] would compute for the reversed triangles), so the facing predicate
    /// ([`crate::solid::face_side`]) gives exactly the opposite side for every point.
    ///
    /// # Examples
    ///
    /// ```
    /// use arealight::glam::DVec3;
    /// use arealight::solid::TriangleMesh;
    /// let down = TriangleMesh::quad(DVec3::new(0.0, 0.0, 2.0), DVec3::Y, DVec3::X)?;
    /// assert_eq!(down.triangle_normal(0), DVec3::NEG_Z);
    /// assert_eq!(down.flipped().triangle_normal(0), DVec3::Z);
    /// # Ok::<(), arealight::GeomError>(())
    /// ```
    #[must_use]
    pub fn flipped(&self) -> TriangleMesh {
        let triangles: Vec<[u32; 3]> = self.triangles.iter().map(|&[a, b, c]| [a, c, b]).collect();
        let (edges, closed) = edge_adjacency(&triangles);
        TriangleMesh {
            vertices: self.vertices.clone(),
            triangles,
            normals: self.normals.iter().map(|n| -*n).collect(),
            offsets: self.offsets.iter().map(|d| -d).collect(),
            edges,
            bounds: self.bounds,
            planar: self.planar,
            closed,
        }
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

/// The undirected edges of `triangles` with the triangles on either side, and whether the mesh
/// is closed (every directed edge has exactly one reversed twin and none repeats, i.e. every
/// edge pairs exactly two triangles running opposite ways).
///
/// The directed edges are sorted by `(min, max, triangle, direction)`, so the copies of one
/// undirected edge are neighbours; a pair of opposite copies becomes one edge, anything else
/// (a border, more than two triangles, two running the same way) one edge per copy.
fn edge_adjacency(triangles: &[[u32; 3]]) -> (Vec<MeshEdge>, bool) {
    let mut half: Vec<(u32, u32, u32, u32)> = Vec::with_capacity(3 * triangles.len());
    for (f, t) in triangles.iter().enumerate() {
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            half.push((a.min(b), a.max(b), f as u32, u32::from(a > b)));
        }
    }
    half.sort_unstable();
    let mut edges = Vec::with_capacity(half.len() / 2 + 1);
    let mut closed = true;
    let mut i = 0;
    while i < half.len() {
        let (lo, hi, f, dir) = half[i];
        let mut end = i + 1;
        while end < half.len() && half[end].0 == lo && half[end].1 == hi {
            end += 1;
        }
        if end == i + 2 && half[i + 1].3 != dir {
            let g = half[i + 1].2;
            // dir == 0 means triangle f runs lo -> hi.
            let (f0, f1) = if dir == 0 { (f, g) } else { (g, f) };
            edges.push(MeshEdge {
                a: lo,
                b: hi,
                f0,
                f1,
            });
        } else {
            closed = false;
            for &(lo, hi, f, dir) in &half[i..end] {
                let (a, b) = if dir == 0 { (lo, hi) } else { (hi, lo) };
                edges.push(MeshEdge {
                    a,
                    b,
                    f0: f,
                    f1: MeshEdge::BORDER,
                });
            }
        }
        i = end;
    }
    (edges, closed)
}

/// Unit normal of the triangle `(a, b, c)` (counter-clockwise seen from the side it points to),
/// or `None` when the triangle is degenerate in the sense of [`DEGENERATE_TRIANGLE`].
///
/// The normal is the direction of the exact cross product `(b - a) x (c - a)` of the given
/// vertices, rounded ([`accurate_cross`]), so its error is a few ulps whatever the triangle's
/// shape. A plain floating-point cross product errs by a few `1e-16` of the squared edge
/// length, which for a sliver (twice its area `1e-12` of its squared longest edge) turns the
/// normal by up to `1e-4` rad: a point interpolated on the sliver then lay `5e-5` of its size
/// in front of its plane by the facing predicate, far outside the predicate's tolerance, and
/// the sliver covered a hemisphere seen from a point on it.
fn triangle_normal(a: DVec3, b: DVec3, c: DVec3) -> Option<DVec3> {
    let (e0, e1, e2) = (b - a, c - b, a - c);
    let longest2 = e0
        .length_squared()
        .max(e1.length_squared())
        .max(e2.length_squared());
    let n = accurate_cross(a, b, c);
    let len = n.length();
    if len.is_nan() || len <= DEGENERATE_TRIANGLE * longest2 || !len.is_finite() {
        return None;
    }
    Some(n / len)
}

/// `a + b` as the unevaluated sum `s + e` with `s = fl(a + b)` (Knuth's TwoSum).
#[inline]
fn two_sum(a: f64, b: f64) -> (f64, f64) {
    let s = a + b;
    let bb = s - a;
    (s, (a - (s - bb)) + (b - bb))
}

/// `a` split into two halves of 26 significant bits each, `a = hi + lo` (Veltkamp).
#[inline]
fn split(a: f64) -> (f64, f64) {
    let c = 134_217_729.0 * a; // 2^27 + 1
    let hi = c - (c - a);
    (hi, a - hi)
}

/// `a * b` as the unevaluated sum `p + e` exactly (Dekker's TwoProduct; exact while nothing
/// overflows or underflows, which mesh coordinates up to [`MAX_MESH_COORD`] guarantee for
/// products of coordinate differences above about `1e-150`).
#[inline]
fn two_prod(a: f64, b: f64) -> (f64, f64) {
    let p = a * b;
    let (ah, al) = split(a);
    let (bh, bl) = split(b);
    (p, al * bl - (((p - ah * bh) - al * bh) - ah * bl))
}

/// `u * v - w * x` for coordinate differences given exactly as unevaluated sums `(hi, lo)`,
/// accurate to about one ulp of the result: the sixteen partial products are exact
/// (`two_prod`), and their sum is taken as in twice the working precision (Ogita, Rump and
/// Oishi 2005, algorithm Sum2: error at most `eps |sum| + gamma_15^2 sum |terms|`, so `1e-29`
/// of the squared edge length at most, against results of at least `1e-12` of it for the
/// triangles [`DEGENERATE_TRIANGLE`] accepts).
fn exact_2x2(u: (f64, f64), v: (f64, f64), w: (f64, f64), x: (f64, f64)) -> f64 {
    let mut s = 0.0;
    let mut err = 0.0;
    let mut add = |t: f64| {
        let (ns, e) = two_sum(s, t);
        s = ns;
        err += e;
    };
    for (p, q, sign) in [(u, v, 1.0), (w, x, -1.0)] {
        for a in [p.0, p.1] {
            for b in [q.0, q.1] {
                let (h, l) = two_prod(a, b);
                add(sign * h);
                add(sign * l);
            }
        }
    }
    s + err
}

/// The cross product `(b - a) x (c - a)` of the exact differences of the given coordinates,
/// each component rounded from its exact value to within about one ulp ([`exact_2x2`]): the
/// normal of the triangle the vertices define, accurate however thin it is.
fn accurate_cross(a: DVec3, b: DVec3, c: DVec3) -> DVec3 {
    let d = |p: f64, q: f64| two_sum(p, -q);
    let (e0x, e0y, e0z) = (d(b.x, a.x), d(b.y, a.y), d(b.z, a.z));
    let (e2x, e2y, e2z) = (d(c.x, a.x), d(c.y, a.y), d(c.z, a.z));
    DVec3::new(
        exact_2x2(e0y, e2z, e0z, e2y),
        exact_2x2(e0z, e2x, e0x, e2z),
        exact_2x2(e0x, e2y, e0y, e2x),
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::solid::ConvexPolyhedron;
    use alloc::vec;

    /// Slivers with integer coordinates times `2^-40` (so that the exact cross product is an
    /// `i128` computation), one vertex `1e-12..1e-4` of the length off the line of the others:
    /// the mesh's normal is the exact one to a few ulps, where the plain cross product is off
    /// by up to `1e-4`.
    #[test]
    fn sliver_normals_are_exact_to_a_few_ulps() {
        let mut state = 0x5EED_u64;
        let mut next = || {
            state = state
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        let unit = (-40f64).exp2();
        let mut worst_plain = 0f64;
        for k in 0..2000 {
            let mut p = || {
                [next(), next(), next()].map(|u| ((u - 0.5) * (1u64 << 41) as f64).round() as i64)
            };
            let (a, b) = (p(), p());
            // The third vertex on the segment, moved off it by a relative 1e-12..1e-4.
            let t = next();
            let off = 10f64.powf(-12.0 + 8.0 * (k as f64 / 2000.0));
            let len = ((0..3).map(|i| ((b[i] - a[i]) as f64).powi(2)).sum::<f64>()).sqrt();
            let dir = [next() - 0.5, next() - 0.5, next() - 0.5];
            let c: [i64; 3] = core::array::from_fn(|i| {
                (a[i] as f64 + t * (b[i] - a[i]) as f64 + dir[i] * off * len).round() as i64
            });
            let e0: [i128; 3] = core::array::from_fn(|i| i128::from(b[i] - a[i]));
            let e2: [i128; 3] = core::array::from_fn(|i| i128::from(c[i] - a[i]));
            let exact = [
                e0[1] * e2[2] - e0[2] * e2[1],
                e0[2] * e2[0] - e0[0] * e2[2],
                e0[0] * e2[1] - e0[1] * e2[0],
            ];
            let to = |v: [i64; 3]| DVec3::new(v[0] as f64, v[1] as f64, v[2] as f64) * unit;
            let Some(n) = triangle_normal(to(a), to(b), to(c)) else {
                continue;
            };
            let want = DVec3::new(exact[0] as f64, exact[1] as f64, exact[2] as f64).normalize();
            assert!((n - want).length() < 1e-15, "{k}: {n} vs {want}");
            let plain = (to(b) - to(a)).cross(to(c) - to(a)).normalize();
            worst_plain = worst_plain.max((plain - want).length());
        }
        // The test can fail: the plain cross product misses by far more.
        assert!(worst_plain > 1e-6, "{worst_plain}");
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
    fn edges_pair_opposite_triangles() {
        // Every edge of a closed mesh has two triangles, and runs a -> b in f0 and b -> a in f1;
        // each triangle has three edges; borders and non-manifold edges have one triangle each.
        let runs = |m: &TriangleMesh, f: u32, a: u32, b: u32| {
            let t = m.triangles()[f as usize];
            (0..3).any(|k| t[k] == a && t[(k + 1) % 3] == b)
        };
        let ico = ConvexPolyhedron::icosphere(DVec3::ZERO, 1.0, 1).unwrap();
        let m = ico.mesh();
        assert_eq!(m.edges().len(), 3 * m.triangle_count() / 2);
        let mut per_triangle = vec![0; m.triangle_count()];
        for e in m.edges() {
            let f1 = e.twin().unwrap();
            assert!(runs(m, e.f0, e.a, e.b) && runs(m, f1, e.b, e.a), "{e:?}");
            per_triangle[e.f0 as usize] += 1;
            per_triangle[f1 as usize] += 1;
        }
        assert!(per_triangle.iter().all(|&c| c == 3));
        // A fan of three triangles on one edge: three copies, none paired.
        let v = vec![DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::Z, -DVec3::Y];
        let fan = TriangleMesh::new(v, vec![[0, 1, 2], [1, 0, 3], [0, 1, 4]]).unwrap();
        let on_01: Vec<_> = fan
            .edges()
            .iter()
            .filter(|e| e.a.min(e.b) == 0 && e.a.max(e.b) == 1)
            .collect();
        assert_eq!(on_01.len(), 3);
        assert!(
            on_01
                .iter()
                .all(|e| e.twin().is_none() && runs(&fan, e.f0, e.a, e.b))
        );
        assert!(!fan.is_closed());
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
    }
}
