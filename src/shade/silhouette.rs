//! Spherical polygons of lights and occluders seen from a shading point: silhouettes of convex
//! polyhedra (seed 000 Alg. 2, section 3.3; thesis 003 section 4.2) and single triangles (the
//! per-triangle method, seed 000 section 4.4).

use alloc::vec;
use alloc::vec::Vec;

use glam::{DMat3, DVec3};

use super::mesh::{ConvexPolyhedron, FACE_TOLERANCE, TriangleMesh};
use crate::GeomError;
use crate::sphere::{ANTIPODAL_TOLERANCE, SphericalPolygon, order_directed_edges};
use smallvec::SmallVec;

/// Consecutive silhouette vertices closer than this (chord length) go to the general ordering
/// path, which merges them; the same tolerance as `order_directed_edges` uses for endpoints.
const MATCH_TOLERANCE: f64 = 1e-9;

/// Corners of a clipped blocker polygon whose directions are closer than this (chord length) are
/// merged before the polygon is built: far below any feature the sphere layer resolves, far above
/// the rounding of an interpolated cut point.
const MERGE_TOLERANCE: f64 = 1e-13;

/// The local shading frame of a point (DESIGN.md): the normal on `+z`, the view direction in the
/// xz-plane with `x >= 0`, right-handed; directions are taken from the shading point.
///
/// # Examples
///
/// ```
/// use arealight::glam::DVec3;
/// use arealight::shade::ShadingFrame;
/// let f = ShadingFrame::new(DVec3::ZERO, DVec3::Y, DVec3::new(0.0, 1.0, 1.0))?;
/// assert!((f.to_local(DVec3::new(0.0, 2.0, 0.0)) - DVec3::new(0.0, 0.0, 2.0)).length() < 1e-15);
/// let v = f.view();
/// assert!(v.y.abs() < 1e-15 && v.x > 0.0 && (v.z - v.x).abs() < 1e-15);
/// # Ok::<(), arealight::GeomError>(())
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ShadingFrame {
    origin: DVec3,
    /// Rows are the tangent, bitangent and normal: `to_local(p) = rot * (p - origin)`.
    rot: DMat3,
    view: DVec3,
}

impl ShadingFrame {
    /// The frame at `point` with surface normal `normal` and direction to the viewer `view`
    /// (neither needs to be normalized). A view along the normal picks an arbitrary tangent; a
    /// view below the surface is allowed (the LTC lookup treats it as grazing).
    ///
    /// # Errors
    ///
    /// [`GeomError::NonFinite`] (`vertex` 0, 1, 2 for point, normal, view) or
    /// [`GeomError::ZeroVector`] (`vertex` 1 or 2) for an unusable input.
    pub fn new(point: DVec3, normal: DVec3, view: DVec3) -> Result<Self, GeomError> {
        for (i, v) in [point, normal, view].into_iter().enumerate() {
            if !v.is_finite() {
                return Err(GeomError::NonFinite { ring: 0, vertex: i });
            }
        }
        let n = normal
            .try_normalize()
            .ok_or(GeomError::ZeroVector { ring: 0, vertex: 1 })?;
        let v = view
            .try_normalize()
            .ok_or(GeomError::ZeroVector { ring: 0, vertex: 2 })?;
        // Tangent: the view's component in the surface plane; any tangent for a view along n.
        let t = (v - n * v.dot(n))
            .try_normalize()
            .filter(|t| (v - n * v.dot(n)).length() > 1e-12 && t.is_finite())
            .unwrap_or_else(|| n.any_orthonormal_vector());
        let b = n.cross(t);
        let rot = DMat3::from_cols(t, b, n).transpose();
        let local_v = rot * v;
        // Exactly in the xz-plane, x >= 0, as the LTC tables assume.
        let view = DVec3::new(local_v.x.max(0.0), 0.0, local_v.z).normalize();
        Ok(ShadingFrame {
            origin: point,
            rot,
            view,
        })
    }

    /// The shading point.
    #[must_use]
    pub fn origin(&self) -> DVec3 {
        self.origin
    }

    /// The vector from the shading point to the world point `p`, in the local frame.
    #[must_use]
    pub fn to_local(&self, p: DVec3) -> DVec3 {
        self.rot * (p - self.origin)
    }

    /// A world direction in the local frame.
    #[must_use]
    pub fn dir_to_local(&self, d: DVec3) -> DVec3 {
        self.rot * d
    }

    /// A local direction in world coordinates.
    #[must_use]
    pub fn dir_to_world(&self, d: DVec3) -> DVec3 {
        self.rot.transpose() * d
    }

    /// The unit view direction in the local frame (`y = 0`, `x >= 0`).
    #[must_use]
    pub fn view(&self) -> DVec3 {
        self.view
    }

    /// The world-space surface normal.
    #[must_use]
    pub fn normal(&self) -> DVec3 {
        self.rot.row(2)
    }
}

/// The region a convex polyhedron covers, seen from the frame's origin, in the local frame.
///
/// Contour edges are the edges between a front-facing and a non-front-facing face (thesis 003
/// eq. 4.1/4.2); for a convex polyhedron every contour edge is a silhouette edge (003 section 4.2).
/// Each is oriented by its front face: a front face runs counter-clockwise seen from the point,
/// which puts its interior on the right on the unit sphere (seen from outside the sphere), so the
/// edge is taken in the reverse of its counter-clockwise direction around the front face. The
/// directed edges are then chained by vertex index (exact and combinatorial: each silhouette
/// vertex has one outgoing contour edge), which replaces the planar nearest-endpoint search of
/// seed 000 Alg. 2; configurations that are not one simple loop (near-degenerate views) go through
/// [`order_directed_edges`] instead, which merges endpoints by tolerance and validates.
///
/// A face whose plane passes within [`FACE_TOLERANCE`] of the point is seen edge-on and counts as
/// back-facing. A point inside the polyhedron (behind every face) sees the full sphere; a point on
/// its surface (no face strictly in front, some within the tolerance) is covered by the
/// intersection of the half-spaces behind the faces it lies on: a hemisphere for a point on a
/// face, a lune on an edge.
///
/// # Errors
///
/// Those of [`order_directed_edges`] when the projected silhouette is degenerate (the point
/// within rounding distance of an edge's line).
pub fn convex_silhouette(
    poly: &ConvexPolyhedron,
    frame: &ShadingFrame,
) -> Result<SphericalPolygon, GeomError> {
    let mut s = Vec::new();
    let tol = poly.facing(frame.origin(), &mut s);
    if !s.iter().any(|&d| d > tol) {
        // No front face: the point is inside or on the surface. The polyhedron then covers, seen
        // from the point, the intersection of the closed half-spaces behind the faces the point
        // lies on: the full sphere inside, a hemisphere on a face (a cube standing on the
        // ground covers the ground point's whole upper hemisphere), a lune on an edge.
        let mut region = SphericalPolygon::full();
        for (f, &d) in s.iter().enumerate() {
            if d >= -tol {
                let n = frame.dir_to_local(poly.mesh().triangle_normal(f));
                region = region.clip_to_hemisphere(-n);
            }
        }
        return Ok(region);
    }
    // Contour edges as directed pairs of vertex indices.
    let mut contour: SmallVec<[(u32, u32); 24]> = SmallVec::new();
    for e in poly.edges() {
        match (s[e.f0 as usize] > tol, s[e.f1 as usize] > tol) {
            (true, false) => contour.push((e.b, e.a)),
            (false, true) => contour.push((e.a, e.b)),
            _ => {}
        }
    }
    let verts = poly.vertices();
    if let Some(ring) = chain_by_index(&contour, verts.len()) {
        // The silhouette of a convex polyhedron seen from outside is one simple loop through
        // distinct vertices, which are at least about FACE_TOLERANCE apart in direction (they
        // span front faces, whose planes miss the point by more than the tolerance). So when the
        // combinatorial walk closes one loop, only consecutive-vertex spacing needs checking,
        // not the quadratic simplicity test of `SphericalPolygon::new`.
        let mut out: SmallVec<[DVec3; 12]> = SmallVec::with_capacity(ring.len());
        for &i in &ring {
            let Some(u) = frame.to_local(verts[i as usize]).try_normalize() else {
                return order_edges_of(&contour, verts, frame);
            };
            out.push(u);
        }
        let n = out.len();
        let spaced = n >= 3
            && (0..n).all(|k| {
                let (a, b) = (out[k], out[(k + 1) % n]);
                (a - b).length() > MATCH_TOLERANCE && (a + b).length() > ANTIPODAL_TOLERANCE
            });
        if spaced {
            let ends: SmallVec<[u32; 2]> = smallvec::smallvec![n as u32];
            return Ok(SphericalPolygon::from_parts(out, ends));
        }
    }
    order_edges_of(&contour, verts, frame)
}

/// The general path: the contour's directed edges ordered with [`order_directed_edges`], which
/// merges endpoints by tolerance, allows pinches and validates the result.
fn order_edges_of(
    contour: &[(u32, u32)],
    verts: &[DVec3],
    frame: &ShadingFrame,
) -> Result<SphericalPolygon, GeomError> {
    let edges: Vec<(DVec3, DVec3)> = contour
        .iter()
        .map(|&(a, b)| {
            (
                frame.to_local(verts[a as usize]),
                frame.to_local(verts[b as usize]),
            )
        })
        .collect();
    order_directed_edges(&edges)
}

/// Walks directed edges (vertex index pairs) as one loop: `Some(vertex indices)` when every
/// vertex used has exactly one outgoing edge and the walk from the first edge uses all of them,
/// `None` otherwise (several loops or pinches: left to the general path).
fn chain_by_index(edges: &[(u32, u32)], nverts: usize) -> Option<SmallVec<[u32; 24]>> {
    const NONE: u32 = u32::MAX;
    if edges.len() < 3 {
        return None;
    }
    let mut next = alloc::vec![NONE; nverts];
    for &(a, b) in edges {
        if next[a as usize] != NONE {
            return None;
        }
        next[a as usize] = b;
    }
    let mut ring = SmallVec::new();
    let start = edges[0].0;
    let mut at = start;
    for _ in 0..edges.len() {
        ring.push(at);
        at = next[at as usize];
        if at == NONE {
            return None;
        }
        if at == start {
            break;
        }
    }
    (at == start && ring.len() == edges.len()).then_some(ring)
}

/// How a triangle of a mesh enters the per-triangle method.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum TriangleRole {
    /// Part of a light: only its front face emits, so a back-facing triangle covers nothing.
    Emitter,
    /// Part of an occluder: it blocks light from either side.
    Blocker,
}

/// The spherical triangle that mesh triangle `i` covers, seen from the frame's origin, in the
/// local frame; `None` when it covers nothing (seen edge-on within [`FACE_TOLERANCE`] or so
/// nearly edge-on that its projection has no area within rounding, or from behind for an
/// [`TriangleRole::Emitter`]).
///
/// # Errors
///
/// Those of [`SphericalPolygon::new`] for a projection that rounding made degenerate.
pub fn triangle_polygon(
    mesh: &TriangleMesh,
    i: usize,
    frame: &ShadingFrame,
    role: TriangleRole,
) -> Result<Option<SphericalPolygon>, GeomError> {
    let side = triangle_side(mesh, i, frame.origin());
    if side == 0 || (side < 0 && role == TriangleRole::Emitter) {
        return Ok(None);
    }
    let [a, b, c] = mesh.triangle(i).map(|v| frame.to_local(v));
    covered_region(&[a, b, c], side)
}

/// Which side of mesh triangle `i`'s plane the point `x` lies on: `1` in front (the side the
/// normal points to), `-1` behind, `0` within [`FACE_TOLERANCE`] (edge-on). The one facing test
/// of the per-triangle method, shared by [`triangle_polygon`] and the per-face visibility of
/// [`crate::shade::Scene::visible_region`], so that both agree on every face.
pub(crate) fn triangle_side(mesh: &TriangleMesh, i: usize, x: DVec3) -> i8 {
    let [a, b, c] = mesh.triangle(i);
    let n = mesh.triangle_normal(i);
    // Relative to the triangle's centroid, so the rounding of s scales with the distance to it.
    let m = (a + b + c) / 3.0;
    let s = n.dot(x - m);
    let size = (a - m).length().max((b - m).length()).max((c - m).length());
    let tol = FACE_TOLERANCE * ((x - m).length() + size);
    if s > tol {
        1
    } else if s < -tol {
        -1
    } else {
        0
    }
}

/// The region covered by a planar convex polygon (vertices in the local frame, counter-clockwise
/// seen from the side `side` says the point is on: `1` front, `-1` back), or `None` when its
/// projection has no area within rounding.
fn covered_region(local: &[DVec3], side: i8) -> Result<Option<SphericalPolygon>, GeomError> {
    // Counter-clockwise seen from the point is clockwise on the sphere seen from outside, so a
    // front-facing polygon covers the reversed ring (see `convex_silhouette`).
    let ordered: SmallVec<[DVec3; 4]> = if side > 0 {
        local.iter().rev().copied().collect()
    } else {
        local.iter().copied().collect()
    };
    let mut units: SmallVec<[DVec3; 4]> = SmallVec::new();
    for v in &ordered {
        match v.try_normalize() {
            Some(u) => units.push(u),
            None => return Ok(None), // a corner at the point itself: seen edge-on
        }
    }
    // Clipped polygons can carry a cut point within rounding of a corner: merge such directions
    // (an area change far below any tolerance of the layer) rather than reject the polygon.
    let mut keep: SmallVec<[usize; 4]> = SmallVec::new();
    for k in 0..units.len() {
        if keep
            .last()
            .is_none_or(|&j| (units[j] - units[k]).length() > MERGE_TOLERANCE)
        {
            keep.push(k);
        }
    }
    while keep.len() > 1
        && (units[keep[0]] - units[keep[keep.len() - 1]]).length() <= MERGE_TOLERANCE
    {
        keep.pop();
    }
    if keep.len() < 3 {
        return Ok(None);
    }
    let ring: Vec<DVec3> = keep.iter().map(|&k| ordered[k]).collect();
    match SphericalPolygon::new(vec![ring]) {
        Ok(p) => Ok(Some(p)),
        // Seen so nearly edge-on that its projection has no area within rounding (its corners
        // on one great circle, or two of them in one direction): it covers nothing.
        Err(
            GeomError::ZeroArea { .. }
            | GeomError::CoincidentVertices { .. }
            | GeomError::TooFewVertices { .. },
        ) => Ok(None),
        Err(e) => Err(e),
    }
}

/// The region covered, seen from the frame's origin, by the part of blocker triangle `i` of
/// `mesh` that lies strictly on the positive side of a plane, given the signed distances `dist`
/// of its three corners from that plane (snapped by the caller: exactly `0` means on the plane).
///
/// This is the `proj(O n H)` of the exact visibility rule: a ray towards a light face meets the
/// face's plane once, so an occluder point hides the face only if it lies on the point's side of
/// that plane. The part strictly on that side is kept (open half-space): a triangle lying in the
/// plane, or touching it from behind, is met no earlier than the light itself and hides nothing,
/// as in the Monte Carlo reference. The cut is Sutherland–Hodgman against one plane (a triangle
/// gives a triangle or a quadrilateral); cut points are interpolated in the local frame, where
/// coordinates have the scale of the distance to the point.
///
/// `None` when nothing of the triangle is on the positive side, or when it is seen edge-on.
///
/// # Errors
///
/// Those of [`SphericalPolygon::new`] for a projection that rounding made degenerate.
pub(crate) fn clipped_triangle_polygon(
    mesh: &TriangleMesh,
    i: usize,
    dist: [f64; 3],
    frame: &ShadingFrame,
) -> Result<Option<SphericalPolygon>, GeomError> {
    if dist.iter().all(|&d| d <= 0.0) {
        return Ok(None);
    }
    let side = triangle_side(mesh, i, frame.origin());
    if side == 0 {
        return Ok(None);
    }
    let v = mesh.triangle(i).map(|p| frame.to_local(p));
    if dist.iter().all(|&d| d >= 0.0) {
        return covered_region(&v, side);
    }
    let mut out: SmallVec<[DVec3; 4]> = SmallVec::new();
    for k in 0..3 {
        let (u, w) = (v[k], v[(k + 1) % 3]);
        let (du, dw) = (dist[k], dist[(k + 1) % 3]);
        if du >= 0.0 {
            out.push(u);
        }
        if (du > 0.0 && dw < 0.0) || (du < 0.0 && dw > 0.0) {
            // Opposite strict signs: du / (du - dw) is in (0, 1) and well conditioned.
            out.push(u + (w - u) * (du / (du - dw)));
        }
    }
    covered_region(&out, side)
}

#[cfg(test)]
mod tests {
    use super::*;
    use core::f64::consts::PI;

    #[test]
    fn cube_face_on_subtends_its_solid_angle() {
        // Unit cube centered 2 above the origin: seen from below, only the bottom face, a square
        // of side 1 at distance 1.5. Solid angle of a square (side 2a) at distance d:
        // 4 asin(a^2 / (a^2 + d^2)).
        let cube = ConvexPolyhedron::cuboid(DVec3::new(0.0, 0.0, 2.0), DVec3::splat(0.5)).unwrap();
        let f = ShadingFrame::new(DVec3::ZERO, DVec3::Z, DVec3::Z).unwrap();
        let p = convex_silhouette(&cube, &f).unwrap();
        let (a, d) = (0.5f64, 1.5f64);
        let expect = 4.0 * (a * a / (a * a + d * d)).asin();
        assert!(
            (p.solid_angle() - expect).abs() < 1e-12,
            "{}",
            p.solid_angle()
        );
        assert!(p.contains(DVec3::Z));
        // Inside: full sphere.
        let fi = ShadingFrame::new(DVec3::new(0.0, 0.0, 2.0), DVec3::Z, DVec3::Z).unwrap();
        assert!(convex_silhouette(&cube, &fi).unwrap().is_full());
        // On the bottom face (a ground point under a cube standing on it): the upper hemisphere.
        let fb = ShadingFrame::new(DVec3::new(0.1, 0.2, 1.5), DVec3::Z, DVec3::Z).unwrap();
        let pb = convex_silhouette(&cube, &fb).unwrap();
        assert!((pb.solid_angle() - 2.0 * PI).abs() < 1e-12 && pb.contains(DVec3::Z));
        // On a bottom edge: a quarter of the sphere.
        let fe = ShadingFrame::new(DVec3::new(0.5, 0.2, 1.5), DVec3::Z, DVec3::Z).unwrap();
        let pe = convex_silhouette(&cube, &fe).unwrap();
        assert!(
            (pe.solid_angle() - PI).abs() < 1e-12,
            "{}",
            pe.solid_angle()
        );
        // In the plane of the bottom face (a cube standing on the ground), off to the side.
        let fg = ShadingFrame::new(DVec3::new(2.0, 0.0, 1.5), DVec3::Z, DVec3::Z).unwrap();
        let pg = convex_silhouette(&cube, &fg).unwrap();
        assert!(pg.solid_angle() > 0.0 && pg.solid_angle() < 2.0 * PI);
    }

    #[test]
    fn a_cut_triangle_splits_its_solid_angle() {
        // The parts of a triangle on either side of a plane cover, together, what the triangle
        // covers: solid angles add up, for cuts through edges and through a corner, seen from
        // both sides; a triangle in the plane, or behind it, covers nothing.
        let f = ShadingFrame::new(DVec3::new(0.1, -0.2, 0.0), DVec3::Z, DVec3::X).unwrap();
        let mut seed = 0x2545_f491_4f6c_dd1d_u64;
        let mut next = || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            (seed >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        };
        for case in 0..200 {
            let c = DVec3::new(next(), next(), 2.0 + next());
            let mut v: Vec<DVec3> = (0..3)
                .map(|_| c + DVec3::new(next(), next(), next()))
                .collect();
            let n = DVec3::new(next(), next(), next()).normalize();
            let mut a = c + DVec3::new(next(), next(), next()) * 0.3;
            if case % 4 == 0 {
                a = v[0]; // the plane through a corner
            }
            if case % 2 == 1 {
                v.swap(1, 2); // seen from the back
            }
            let mesh = TriangleMesh::new(v, vec![[0, 1, 2]]).unwrap();
            let whole = triangle_polygon(&mesh, 0, &f, TriangleRole::Blocker)
                .unwrap()
                .map_or(0.0, |p| p.solid_angle());
            let d = mesh.triangle(0).map(|p| n.dot(p - a));
            // Every corner of a part, taken back to the triangle's plane along its ray, lies on
            // the kept side of the cutting plane (`sign` 1: n . (q - a) >= 0, -1: <= 0).
            let (tn, t0) = (mesh.triangle_normal(0), mesh.triangle(0)[0]);
            let on_side = |p: &SphericalPolygon, sign: f64| {
                p.rings().flatten().all(|&l| {
                    let w = f.dir_to_world(l);
                    let q = f.origin() + w * (tn.dot(t0 - f.origin()) / tn.dot(w));
                    sign * n.dot(q - a) >= -1e-12
                })
            };
            let part = |d: [f64; 3], sign: f64| {
                let p = clipped_triangle_polygon(&mesh, 0, d, &f).unwrap();
                assert!(p.as_ref().is_none_or(|p| on_side(p, sign)), "case {case}");
                p.map_or(0.0, |p| p.solid_angle())
            };
            let (pos, neg) = (part(d, 1.0), part(d.map(|x| -x), -1.0));
            assert!(
                (pos + neg - whole).abs() <= 1e-12 * (1.0 + whole),
                "case {case}: {pos} + {neg} vs {whole}"
            );
            assert!(part([0.0; 3], 1.0) == 0.0 && part([-1.0, -2.0, 0.0], 1.0) == 0.0);
            assert!(
                (clipped_triangle_polygon(&mesh, 0, [1.0, 0.0, 2.0], &f)
                    .unwrap()
                    .map_or(0.0, |p| p.solid_angle())
                    - whole)
                    .abs()
                    <= 1e-15
            );
        }
    }

    #[test]
    fn per_triangle_sum_equals_silhouette_for_convex() {
        let ico = ConvexPolyhedron::icosphere(DVec3::new(0.3, -0.2, 3.0), 1.0, 1).unwrap();
        let f = ShadingFrame::new(DVec3::new(0.1, 0.2, 0.0), DVec3::Z, DVec3::X).unwrap();
        let sil = convex_silhouette(&ico, &f).unwrap().solid_angle();
        let sum: f64 = (0..ico.mesh().triangle_count())
            .filter_map(|i| triangle_polygon(ico.mesh(), i, &f, TriangleRole::Emitter).unwrap())
            .map(|p| p.solid_angle())
            .sum();
        assert!((sil - sum).abs() < 1e-12, "{sil} {sum}");
    }
}
