//! Solids: triangle meshes validated as the boundary of a solid (closed, manifold, free of
//! self-intersections), the input of the non-convex silhouette (thesis 003 section 4.3) and of
//! the BSP-precomputed silhouettes (section 5).

use alloc::vec;
use alloc::vec::Vec;

use glam::DVec3;
use robust::{Coord, orient2d, orient3d};

use super::mesh::TriangleMesh;
use crate::GeomError;
use crate::sphere::predicates::{c3, triangle_solid_angle};

/// A closed triangle mesh that bounds a solid: every edge is shared by exactly two triangles
/// running opposite ways, the triangles around every vertex form a single fan, and no two
/// triangles meet anywhere but along the edge or at the vertex they share as neighbours.
///
/// These are the conditions under which the silhouette of the mesh seen from a point is the
/// boundary of the union of its front faces' projections and is made of segments of contour
/// edges (thesis 003 section 4.3): an open mesh shows back faces, and a self-intersecting one
/// has contour edges that end inside other faces. The mesh need not be convex; it may have
/// several components (disjoint, or nested as a shell around a cavity) and any genus. Both
/// checks are exact (Shewchuk's `orient3d` and `orient2d` on the given coordinates).
///
/// # Examples
///
/// ```
/// use arealight::glam::DVec3;
/// use arealight::GeomError;
/// use arealight::solid::{ClosedMesh, ConvexPolyhedron, TriangleMesh};
/// let cube = ConvexPolyhedron::cuboid(DVec3::ZERO, DVec3::ONE)?;
/// // Two cubes that overlap do not bound a solid.
/// let other = ConvexPolyhedron::cuboid(DVec3::splat(0.5), DVec3::ONE)?;
/// let both = cube.mesh().merged(other.mesh())?;
/// assert!(matches!(ClosedMesh::new(both), Err(GeomError::SelfIntersectingMesh { .. })));
/// // Two disjoint ones do.
/// let far = ConvexPolyhedron::cuboid(DVec3::splat(3.0), DVec3::ONE)?;
/// assert!(ClosedMesh::new(cube.mesh().merged(far.mesh())?).is_ok());
/// # Ok::<(), arealight::GeomError>(())
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct ClosedMesh {
    mesh: TriangleMesh,
    /// Per edge (in [`TriangleMesh::edges`] order), an id shared exactly by the edges that lie
    /// on one line (their four endpoints collinear, exactly): such edges never cross when seen
    /// from a point, which the silhouette then knows without evaluating a predicate.
    line: Vec<u32>,
    /// Per edge, the vertices known to lie exactly on its line (`on_line[on_line_start[e]..
    /// on_line_start[e + 1]]`): the endpoints of the edges that share its line id.
    on_line_start: Vec<u32>,
    on_line: Vec<u32>,
}

impl ClosedMesh {
    /// Validates `mesh` as the boundary of a solid.
    ///
    /// The self-intersection check sweeps the triangles' bounding boxes along `x` and tests the
    /// pairs whose boxes overlap exactly, so it costs about `n log n` plus the overlapping
    /// pairs.
    ///
    /// # Errors
    ///
    /// - [`GeomError::OpenMesh`] naming an edge (its two vertices) and a triangle at it that is
    ///   not shared by exactly two triangles running opposite ways (a border, a non-manifold edge
    ///   or an inconsistent orientation);
    /// - [`GeomError::NonManifoldVertex`] for a vertex whose triangles form several fans;
    /// - [`GeomError::SelfIntersectingMesh`] naming two triangles that cross, overlap or touch
    ///   away from a shared edge or vertex (two copies of one triangle included).
    pub fn new(mesh: TriangleMesh) -> Result<Self, GeomError> {
        if !mesh.is_closed() {
            let (triangle, edge) = mesh
                .edges()
                .iter()
                .find(|e| e.twin().is_none())
                .map_or((0, [0, 0]), |e| {
                    (e.f0 as usize, [e.a as usize, e.b as usize])
                });
            return Err(GeomError::OpenMesh { triangle, edge });
        }
        check_fans(&mesh)?;
        check_self_intersections(&mesh)?;
        let line = edge_lines(&mesh);
        let (on_line_start, on_line) = line_vertices(&mesh, &line);
        Ok(ClosedMesh {
            mesh,
            line,
            on_line_start,
            on_line,
        })
    }

    /// Whether vertex `v` is known to lie on the line of edge `e` (exactly; `false` may still
    /// be collinear, when no edge of that line ends at `v`).
    pub(crate) fn on_edge_line(&self, e: u32, v: u32) -> bool {
        let (a, b) = (
            self.on_line_start[e as usize] as usize,
            self.on_line_start[e as usize + 1] as usize,
        );
        self.on_line[a..b].contains(&v)
    }

    /// The line ids of the edges (see the field).
    pub(crate) fn edge_lines(&self) -> &[u32] {
        &self.line
    }

    /// The mesh.
    #[must_use]
    pub fn mesh(&self) -> &TriangleMesh {
        &self.mesh
    }

    /// Whether `x` lies inside the solid, decided by the generalized winding number: the sum of
    /// the signed solid angles of the triangles seen from `x` (Van Oosterom and Strackee 1983)
    /// is `4 pi` inside a closed, outward-oriented surface and `0` outside; a point on the
    /// surface gets about `2 pi` from the triangles it lies on and counts as outside. Rounding
    /// moves the sum by far less than the `2 pi` margin except within rounding distance of the
    /// surface, where either answer describes the same point.
    ///
    /// Why a light needs it: seen from inside, every ray leaves the solid through a back face
    /// before it can meet a front one, so a closed light sends nothing to an interior point,
    /// although the union of its front faces' projections is not empty when it is not convex.
    #[must_use]
    pub fn encloses(&self, x: DVec3) -> bool {
        let b = self.mesh.bounding_sphere();
        if (x - b.center).length_squared() > b.radius * b.radius {
            return false;
        }
        let verts = self.mesh.vertices();
        let mut total = 0.0;
        for t in self.mesh.triangles() {
            // A vertex at the point itself (on the surface) adds nothing.
            if let [Some(a), Some(b), Some(c)] = t.map(|i| (verts[i as usize] - x).try_normalize())
            {
                total += triangle_solid_angle(a, b, c);
            }
        }
        total > 2.0 * core::f64::consts::TAU * 0.75
    }

    /// The mesh, giving up the validation.
    #[must_use]
    pub fn into_mesh(self) -> TriangleMesh {
        self.mesh
    }
}

impl AsRef<TriangleMesh> for ClosedMesh {
    fn as_ref(&self) -> &TriangleMesh {
        &self.mesh
    }
}

/// Line ids of the edges: edges are bucketed by their line's direction and foot point rounded
/// to about `1e-9` of the mesh's size, and within a bucket grouped when exactly collinear
/// (`orient2d` on the three coordinate planes). Edges of one line that land in different
/// buckets keep different ids, which only costs the silhouette exact predicates.
fn edge_lines(mesh: &TriangleMesh) -> Vec<u32> {
    let v = mesh.vertices();
    let edges = mesh.edges();
    let b = mesh.bounding_sphere();
    let q = 1e-9 * b.radius.max(f64::MIN_POSITIVE);
    let key = |i: usize| -> [i64; 6] {
        let (a, c) = (
            v[edges[i].a as usize] - b.center,
            v[edges[i].b as usize] - b.center,
        );
        let mut d = (c - a).normalize();
        let k = if d.x.abs() >= d.y.abs() && d.x.abs() >= d.z.abs() {
            d.x
        } else if d.y.abs() >= d.z.abs() {
            d.y
        } else {
            d.z
        };
        if k < 0.0 {
            d = -d;
        }
        let foot = a - d * a.dot(d);
        let r = |x: f64, s: f64| (x / s).round() as i64;
        [
            r(d.x, 1e-9),
            r(d.y, 1e-9),
            r(d.z, 1e-9),
            r(foot.x, q),
            r(foot.y, q),
            r(foot.z, q),
        ]
    };
    let mut order: Vec<u32> = (0..edges.len() as u32).collect();
    let keys: Vec<[i64; 6]> = (0..edges.len()).map(key).collect();
    order.sort_unstable_by_key(|&i| keys[i as usize]);
    let mut line: Vec<u32> = (0..edges.len() as u32).collect();
    let mut start = 0;
    while start < order.len() {
        let mut end = start + 1;
        while end < order.len() && keys[order[end] as usize] == keys[order[start] as usize] {
            end += 1;
        }
        for i in start..end {
            let ei = order[i] as usize;
            if line[ei] != ei as u32 {
                continue; // already joined to an earlier edge's line
            }
            let (a, c) = (v[edges[ei].a as usize], v[edges[ei].b as usize]);
            for &ej in &order[i + 1..end] {
                let ej = ej as usize;
                let (p, r) = (v[edges[ej].a as usize], v[edges[ej].b as usize]);
                if on_line(a, c, p) && on_line(a, c, r) {
                    line[ej] = ei as u32;
                }
            }
        }
        start = end;
    }
    line
}

/// Per edge, the endpoints of all edges with its line id (see [`ClosedMesh::on_edge_line`]).
fn line_vertices(mesh: &TriangleMesh, line: &[u32]) -> (Vec<u32>, Vec<u32>) {
    let edges = mesh.edges();
    // Endpoints per line id (ids are edge indices).
    let mut members: Vec<Vec<u32>> = vec![Vec::new(); edges.len()];
    for (e, &l) in edges.iter().zip(line) {
        let m = &mut members[l as usize];
        for v in [e.a, e.b] {
            if !m.contains(&v) {
                m.push(v);
            }
        }
    }
    let mut start = Vec::with_capacity(edges.len() + 1);
    let mut out = Vec::new();
    start.push(0);
    for &l in line {
        let m = &members[l as usize];
        // An edge alone on its line knows only its own endpoints: nothing to store.
        if m.len() > 2 {
            out.extend_from_slice(m);
        }
        start.push(out.len() as u32);
    }
    (start, out)
}

/// Whether `p` lies on the line through `a` and `c` (exact).
fn on_line(a: DVec3, c: DVec3, p: DVec3) -> bool {
    (0..3).all(|k| orient2d(p2(a, k), p2(c, k), p2(p, k)) == 0.0)
}

/// Checks that the triangles around each vertex form one fan. In a closed mesh each corner
/// `v` of a triangle `(v, a, b)` contributes the link edge `a -> b`, every `a` starts exactly one
/// link edge of `v` (the directed mesh edge `v -> a` is unique), so the links form disjoint
/// cycles; one cycle per vertex is a single fan.
fn check_fans(mesh: &TriangleMesh) -> Result<(), GeomError> {
    let nv = mesh.vertices().len();
    let tris = mesh.triangles();
    // Incidences grouped by vertex (counting sort).
    let mut start = vec![0u32; nv + 1];
    for t in tris {
        for &v in t {
            start[v as usize + 1] += 1;
        }
    }
    for i in 0..nv {
        start[i + 1] += start[i];
    }
    let mut fill = start.clone();
    // (link start, link end, triangle)
    let mut links = vec![(0u32, 0u32, 0u32); 3 * tris.len()];
    for (ti, t) in tris.iter().enumerate() {
        for k in 0..3 {
            let v = t[k] as usize;
            links[fill[v] as usize] = (t[(k + 1) % 3], t[(k + 2) % 3], ti as u32);
            fill[v] += 1;
        }
    }
    let mut seen: Vec<bool> = Vec::new();
    for v in 0..nv {
        let fan = &links[start[v] as usize..start[v + 1] as usize];
        if fan.is_empty() {
            continue;
        }
        seen.clear();
        seen.resize(fan.len(), false);
        let mut at = 0usize;
        let mut walked = 0usize;
        while !seen[at] {
            seen[at] = true;
            walked += 1;
            let next = fan[at].1;
            match fan.iter().position(|l| l.0 == next) {
                Some(i) => at = i,
                None => break,
            }
        }
        if walked < fan.len() {
            let other = seen.iter().position(|&s| !s).unwrap_or(0);
            return Err(GeomError::NonManifoldVertex {
                vertex: v,
                triangle: fan[other].2 as usize,
            });
        }
    }
    Ok(())
}

/// Checks every pair of triangles whose bounding boxes overlap (sweep along `x`).
fn check_self_intersections(mesh: &TriangleMesh) -> Result<(), GeomError> {
    let n = mesh.triangle_count();
    let boxes: Vec<(DVec3, DVec3)> = (0..n)
        .map(|t| {
            let [a, b, c] = mesh.triangle(t);
            (a.min(b).min(c), a.max(b).max(c))
        })
        .collect();
    let mut order: Vec<u32> = (0..n as u32).collect();
    order.sort_unstable_by(|&i, &j| boxes[i as usize].0.x.total_cmp(&boxes[j as usize].0.x));
    for (k, &i) in order.iter().enumerate() {
        let (lo, hi) = boxes[i as usize];
        for &j in &order[k + 1..] {
            let (lo2, hi2) = boxes[j as usize];
            if lo2.x > hi.x {
                break;
            }
            if lo2.y > hi.y || lo.y > hi2.y || lo2.z > hi.z || lo.z > hi2.z {
                continue;
            }
            if triangles_meet(mesh, i as usize, j as usize) {
                let (a, b) = (i.min(j) as usize, i.max(j) as usize);
                return Err(GeomError::SelfIntersectingMesh {
                    triangle: a,
                    other: b,
                });
            }
        }
    }
    Ok(())
}

/// Whether triangles `i` and `j` meet anywhere but along their shared edge or at their shared
/// vertex (by index).
fn triangles_meet(mesh: &TriangleMesh, i: usize, j: usize) -> bool {
    let (ti, tj) = (mesh.triangles()[i], mesh.triangles()[j]);
    let v = mesh.vertices();
    let shared: usize = ti.iter().filter(|a| tj.contains(a)).count();
    match shared {
        0 => tri_tri(mesh.triangle(i), mesh.triangle(j)),
        1 => {
            // Rotate both so the shared vertex comes first.
            let s = *ti.iter().find(|a| tj.contains(a)).unwrap_or(&ti[0]);
            let rot = |t: [u32; 3]| {
                let k = t.iter().position(|&x| x == s).unwrap_or(0);
                [t[k], t[(k + 1) % 3], t[(k + 2) % 3]].map(|x| v[x as usize])
            };
            share_vertex_meet(rot(ti), rot(tj))
        }
        2 => {
            // The shared edge a-b; c1, c2 the other corners. Triangles in different planes
            // meet only along the edge; in one plane they overlap iff c1, c2 lie on the same
            // side of the edge.
            let ci = *ti.iter().find(|a| !tj.contains(a)).unwrap_or(&ti[0]);
            let cj = *tj.iter().find(|a| !ti.contains(a)).unwrap_or(&tj[0]);
            let ab: Vec<u32> = ti.iter().copied().filter(|a| tj.contains(a)).collect();
            let (a, b, c1, c2) = (
                v[ab[0] as usize],
                v[ab[1] as usize],
                v[ci as usize],
                v[cj as usize],
            );
            if orient3d(c3(a), c3(b), c3(c1), c3(c2)) != 0.0 {
                return false;
            }
            let k = drop_axis(a, b, c1);
            sign(orient2d(p2(a, k), p2(b, k), p2(c1, k)))
                == sign(orient2d(p2(a, k), p2(b, k), p2(c2, k)))
        }
        _ => true,
    }
}

/// `-1`, `0` or `1`.
fn sign(x: f64) -> i8 {
    if x > 0.0 {
        1
    } else if x < 0.0 {
        -1
    } else {
        0
    }
}

/// The coordinate axis to drop to project the plane of `(a, b, c)` to 2D: the largest component
/// of its normal, so the projection keeps the triangle non-degenerate.
fn drop_axis(a: DVec3, b: DVec3, c: DVec3) -> usize {
    let n = (b - a).cross(c - a).abs();
    if n.x >= n.y && n.x >= n.z {
        0
    } else if n.y >= n.z {
        1
    } else {
        2
    }
}

/// `p` without coordinate `k` (exact: coordinates are copied, not computed).
fn p2(p: DVec3, k: usize) -> Coord<f64> {
    match k {
        0 => Coord { x: p.y, y: p.z },
        1 => Coord { x: p.z, y: p.x },
        _ => Coord { x: p.x, y: p.y },
    }
}

fn o3(a: DVec3, b: DVec3, c: DVec3, d: DVec3) -> i8 {
    sign(orient3d(c3(a), c3(b), c3(c), c3(d)))
}

/// Whether two closed triangles with no shared vertex meet.
fn tri_tri(t1: [DVec3; 3], t2: [DVec3; 3]) -> bool {
    let s2 = t2.map(|p| o3(t1[0], t1[1], t1[2], p));
    if s2.iter().all(|&s| s > 0) || s2.iter().all(|&s| s < 0) {
        return false;
    }
    let s1 = t1.map(|p| o3(t2[0], t2[1], t2[2], p));
    if s1.iter().all(|&s| s > 0) || s1.iter().all(|&s| s < 0) {
        return false;
    }
    if s2.iter().all(|&s| s == 0) {
        let k = drop_axis(t1[0], t1[1], t1[2]);
        return tri_tri_2d(t1.map(|p| p2(p, k)), t2.map(|p| p2(p, k)));
    }
    // Two triangles in different planes meet along a segment whose ends lie where an edge of
    // one meets the other.
    (0..3).any(|e| seg_tri(t1[e], t1[(e + 1) % 3], t2))
        || (0..3).any(|e| seg_tri(t2[e], t2[(e + 1) % 3], t1))
}

/// Whether two closed triangles `(v, a, b)` and `(v, c, d)` sharing only the vertex `v` meet
/// anywhere else. Their intersection is convex and holds `v`; if it holds more, it holds a
/// segment from `v`, and the far end of the longest such segment is where it leaves one of the
/// triangles: on that triangle's edge opposite `v` (its corners included). So they meet beyond
/// `v` iff an edge opposite `v` meets the other triangle, and that edge does not hold `v`.
fn share_vertex_meet(t1: [DVec3; 3], t2: [DVec3; 3]) -> bool {
    seg_tri(t1[1], t1[2], t2) || seg_tri(t2[1], t2[2], t1)
}

/// Whether the closed segment `p-q` meets the closed triangle `t`.
fn seg_tri(p: DVec3, q: DVec3, t: [DVec3; 3]) -> bool {
    let sp = o3(t[0], t[1], t[2], p);
    let sq = o3(t[0], t[1], t[2], q);
    if sp == sq && sp != 0 {
        return false;
    }
    let k = drop_axis(t[0], t[1], t[2]);
    let t2 = t.map(|x| p2(x, k));
    if sp == 0 && sq == 0 {
        let (p, q) = (p2(p, k), p2(q, k));
        return point_in_tri_2d(p, t2)
            || point_in_tri_2d(q, t2)
            || (0..3).any(|e| seg_seg_2d(p, q, t2[e], t2[(e + 1) % 3]));
    }
    if sp == 0 {
        return point_in_tri_2d(p2(p, k), t2);
    }
    if sq == 0 {
        return point_in_tri_2d(p2(q, k), t2);
    }
    // The segment crosses the plane at one point, inside the closed triangle iff the line p-q
    // passes on the same side of (or through) every edge.
    let s = [
        o3(p, q, t[0], t[1]),
        o3(p, q, t[1], t[2]),
        o3(p, q, t[2], t[0]),
    ];
    s.iter().all(|&x| x >= 0) || s.iter().all(|&x| x <= 0)
}

fn point_in_tri_2d(p: Coord<f64>, t: [Coord<f64>; 3]) -> bool {
    let o = sign(orient2d(t[0], t[1], t[2]));
    (0..3).all(|e| sign(orient2d(t[e], t[(e + 1) % 3], p)) * o >= 0)
}

/// Whether the closed segments `a-b` and `c-d` meet.
fn seg_seg_2d(a: Coord<f64>, b: Coord<f64>, c: Coord<f64>, d: Coord<f64>) -> bool {
    let d1 = sign(orient2d(a, b, c));
    let d2 = sign(orient2d(a, b, d));
    let d3 = sign(orient2d(c, d, a));
    let d4 = sign(orient2d(c, d, b));
    if d1 * d2 < 0 && d3 * d4 < 0 {
        return true;
    }
    let within = |p: Coord<f64>, q: Coord<f64>, r: Coord<f64>| {
        r.x >= p.x.min(q.x) && r.x <= p.x.max(q.x) && r.y >= p.y.min(q.y) && r.y <= p.y.max(q.y)
    };
    (d1 == 0 && within(a, b, c))
        || (d2 == 0 && within(a, b, d))
        || (d3 == 0 && within(c, d, a))
        || (d4 == 0 && within(c, d, b))
}

fn tri_tri_2d(t1: [Coord<f64>; 3], t2: [Coord<f64>; 3]) -> bool {
    (0..3).any(|i| (0..3).any(|j| seg_seg_2d(t1[i], t1[(i + 1) % 3], t2[j], t2[(j + 1) % 3])))
        || point_in_tri_2d(t1[0], t2)
        || point_in_tri_2d(t2[0], t1)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::solid::ConvexPolyhedron;

    fn cube(c: DVec3, h: f64) -> TriangleMesh {
        ConvexPolyhedron::cuboid(c, DVec3::splat(h))
            .unwrap()
            .mesh()
            .clone()
    }

    #[test]
    fn open_pinched_and_intersecting_meshes_are_named() {
        // A cube without one triangle: open, at a triangle next to the hole.
        let c = cube(DVec3::ZERO, 1.0);
        let mut tris = c.triangles().to_vec();
        let gone = tris.pop().unwrap();
        let open = TriangleMesh::new(c.vertices().to_vec(), tris).unwrap();
        match ClosedMesh::new(open) {
            Err(GeomError::OpenMesh { triangle, edge }) => {
                // The edge is one of the missing triangle's, run as the named triangle runs it.
                let t = c.triangles()[triangle];
                let [a, b] = edge.map(|v| v as u32);
                assert!(gone.contains(&a) && gone.contains(&b) && a != b, "{edge:?}");
                assert!(
                    (0..3).any(|k| t[k] == a && t[(k + 1) % 3] == b),
                    "{t:?} {edge:?}"
                );
            }
            other => panic!("{other:?}"),
        }
        // Two cubes sharing one corner vertex (by index): a pinch.
        let a = cube(DVec3::ZERO, 1.0);
        let corner = a.vertices().iter().position(|&p| p == DVec3::ONE).unwrap();
        let b = cube(DVec3::splat(2.0), 1.0);
        let bc = b.vertices().iter().position(|&p| p == DVec3::ONE).unwrap();
        let mut verts = a.vertices().to_vec();
        let n = verts.len() as u32;
        verts.extend_from_slice(b.vertices());
        let mut tris = a.triangles().to_vec();
        tris.extend(b.triangles().iter().map(|t| {
            t.map(|i| {
                if i as usize == bc {
                    corner as u32
                } else {
                    i + n
                }
            })
        }));
        let pinched = TriangleMesh::new(verts, tris).unwrap();
        assert!(pinched.is_closed());
        assert!(matches!(
            ClosedMesh::new(pinched),
            Err(GeomError::NonManifoldVertex { vertex, .. }) if vertex == corner
        ));
        // The same cubes touching at the corner through two distinct vertices: they touch.
        let touching = a.merged(&b).unwrap();
        assert!(matches!(
            ClosedMesh::new(touching),
            Err(GeomError::SelfIntersectingMesh { .. })
        ));
        // Moved apart by one ulp-sized step: fine.
        let apart = a.merged(&cube(DVec3::splat(2.0 + 1e-15), 1.0)).unwrap();
        assert!(ClosedMesh::new(apart).is_ok());
        // A triangle and its reverse: closed, but the two coincide.
        let v = vec![DVec3::ZERO, DVec3::X, DVec3::Y];
        let sheet = TriangleMesh::new(v, vec![[0, 1, 2], [0, 2, 1]]).unwrap();
        assert!(matches!(
            ClosedMesh::new(sheet),
            Err(GeomError::SelfIntersectingMesh {
                triangle: 0,
                other: 1
            })
        ));
    }

    /// Exact separating-axis reference for two closed triangles with integer coordinates:
    /// disjoint iff some axis among the two normals, the nine edge-edge cross products and the
    /// in-plane edge normals separates their projections strictly.
    fn sat_meet(t1: [[i64; 3]; 3], t2: [[i64; 3]; 3]) -> bool {
        let sub = |a: [i64; 3], b: [i64; 3]| [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
        let cross = |a: [i64; 3], b: [i64; 3]| {
            [
                a[1] * b[2] - a[2] * b[1],
                a[2] * b[0] - a[0] * b[2],
                a[0] * b[1] - a[1] * b[0],
            ]
        };
        let dot = |a: [i64; 3], b: [i64; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
        let edges = |t: [[i64; 3]; 3]| [sub(t[1], t[0]), sub(t[2], t[1]), sub(t[0], t[2])];
        let (e1, e2) = (edges(t1), edges(t2));
        let (n1, n2) = (cross(e1[0], e1[1]), cross(e2[0], e2[1]));
        let mut axes = vec![n1, n2];
        for a in e1 {
            for b in e2 {
                axes.push(cross(a, b));
            }
            axes.push(cross(n1, a));
        }
        for b in e2 {
            axes.push(cross(n2, b));
        }
        !axes.iter().any(|&ax| {
            if ax == [0, 0, 0] {
                return false;
            }
            let p1 = t1.map(|p| dot(p, ax));
            let p2 = t2.map(|p| dot(p, ax));
            let (lo1, hi1) = (*p1.iter().min().unwrap(), *p1.iter().max().unwrap());
            let (lo2, hi2) = (*p2.iter().min().unwrap(), *p2.iter().max().unwrap());
            hi1 < lo2 || hi2 < lo1
        })
    }

    #[test]
    fn pair_tests_against_exact_references() {
        // Random triangle pairs on a coarse integer grid (so that touching, coplanar and
        // collinear cases are common and exact): pairs sharing no vertex against the exact
        // separating-axis test; pairs sharing a vertex against the same test applied to the
        // first triangle with a neighbourhood of the shared vertex cut off (any meeting beyond
        // the vertex reaches beyond a small neighbourhood once the triangles are scaled up
        // about it, see below); pairs sharing an edge meet iff coplanar and on one side.
        let mut seed = 0x1234_5678_9abc_def1_u64;
        let mut next = |m: i64| {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            (seed % (2 * m as u64 + 1)) as i64 - m
        };
        let (mut met, mut apart, mut checked) = (0, 0, 0);
        for case in 0..6000 {
            let mut t1 = [0; 3].map(|_| [next(4), next(4), next(4)]);
            let mut t2 = [0; 3].map(|_| [next(4), next(4), next(4)]);
            if case % 4 == 3 {
                t1.iter_mut().for_each(|p| p[2] = 0);
                t2.iter_mut().for_each(|p| p[2] = 0);
            }
            let shares_vertex = case % 3 == 1;
            if shares_vertex {
                t2[0] = t1[0];
            }
            let f = |p: [i64; 3]| DVec3::new(p[0] as f64, p[1] as f64, p[2] as f64);
            let verts: Vec<DVec3> = t1.iter().chain(t2.iter()).map(|&p| f(p)).collect();
            // Coincident points become one vertex index.
            let mut idx = [0u32, 1, 2, 3, 4, 5];
            for k in 3..6 {
                if let Some(j) = (0..3).find(|&j| verts[j] == verts[k]) {
                    idx[k] = j as u32;
                }
            }
            let Ok(mesh) = TriangleMesh::new(
                verts.clone(),
                vec![[idx[0], idx[1], idx[2]], [idx[3], idx[4], idx[5]]],
            ) else {
                continue;
            };
            let shared = (3..6).filter(|&k| idx[k] < 3).count();
            let exact = triangles_meet(&mesh, 0, 1);
            let expect = match shared {
                0 => sat_meet(t1, t2),
                1 => {
                    // Relative to the shared vertex s and scaled by 64: T1 ∩ T2 holds more
                    // than s iff it holds a segment from s whose far end lies on the far edge of
                    // T1 or of T2; scaled, that end lies beyond the unscaled corner. So the
                    // pair meets iff (scaled T1 minus its unscaled corner) meets scaled T2, or
                    // the same with the roles swapped. The cut quads are split in two.
                    let k = (3..6).find(|&k| idx[k] < 3).unwrap();
                    let si = t1[idx[k] as usize];
                    let rel = |t: [[i64; 3]; 3]| -> ([i64; 3], [i64; 3]) {
                        let k = t.iter().position(|&p| p == si).unwrap();
                        let d = |p: [i64; 3]| [p[0] - si[0], p[1] - si[1], p[2] - si[2]];
                        (d(t[(k + 1) % 3]), d(t[(k + 2) % 3]))
                    };
                    let m = |v: [i64; 3], f: i64| v.map(|x| x * f);
                    let ((a, b), (c, d)) = (rel(t1), rel(t2));
                    let whole = |a, b| [[0; 3], m(a, 64), m(b, 64)];
                    let cut = |a, b| [[a, m(a, 64), m(b, 64)], [a, m(b, 64), b]];
                    cut(a, b).iter().any(|&q| sat_meet(q, whole(c, d)))
                        || cut(c, d).iter().any(|&q| sat_meet(q, whole(a, b)))
                }
                _ => {
                    continue;
                }
            };
            checked += 1;
            assert_eq!(exact, expect, "case {case}: {t1:?} {t2:?}");
            if exact {
                met += 1;
            } else {
                apart += 1;
            }
        }
        assert!(
            met > 500 && apart > 500 && checked > 3000,
            "{met} {apart} {checked}"
        );
    }
}
