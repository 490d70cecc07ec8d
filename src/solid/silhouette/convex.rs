//! The silhouette of a convex polyhedron seen from a point (seed 000 Alg. 2, section 3.3; thesis
//! 003 section 4.2).

use alloc::vec::Vec;

use glam::DVec3;
use smallvec::SmallVec;

use super::rings::{SilhouetteRings, spaced};
use crate::GeomError;
use crate::solid::facing::{FacingAt, Side};
use crate::solid::{ConvexPolyhedron, ShadingFrame};
use crate::sphere::{
    ANTIPODAL_TOLERANCE, COINCIDENT_TOLERANCE, MATCH_TOLERANCE, SphericalPolygon,
    order_directed_edges,
};

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
/// Front faces are decided by the facing predicate ([`face_side`](crate::solid::face_side)): a
/// face whose plane passes within its tolerance of the point is seen edge-on and counts as
/// back-facing. A point inside the polyhedron (behind every face) sees the full sphere; a point on
/// its surface (no face strictly in front, some within the tolerance) is covered by the
/// intersection of the half-spaces behind the faces it lies on: a hemisphere for a point on a
/// face, a lune on an edge.
///
/// # Errors
///
/// [`GeomError::Undecidable`] when the projected silhouette is degenerate within rounding (the
/// point within rounding distance of an edge's line, so that [`order_directed_edges`] cannot
/// close its loops).
pub fn convex_silhouette(
    poly: &ConvexPolyhedron,
    frame: &ShadingFrame,
) -> Result<SphericalPolygon, GeomError> {
    let (ring, contour) = match convex_contour(poly, frame.origin()) {
        ConvexContour::NoFront => return inside_region(poly, frame),
        ConvexContour::Loop(ring, contour) => (ring, contour),
        ConvexContour::Edges(contour) => {
            return order_edges_of(&contour, poly.vertices(), frame);
        }
    };
    let verts = poly.vertices();
    // The silhouette of a convex polyhedron seen from outside is one simple loop through
    // distinct vertices, which are at least about FACE_TOLERANCE apart in direction (they span
    // front faces, whose planes miss the point by more than the tolerance). So when the
    // combinatorial walk closes one loop, only consecutive-vertex spacing needs checking, not
    // the quadratic simplicity test of `SphericalPolygon::new`.
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
    // Vertices closer than the general path's merge tolerance: a polyhedron seen from far away
    // (1e-9 rad across at 1e9 of its sizes) or an edge seen nearly end-on. Merging would
    // collapse the ring, but the walk's order is exact, so the ring stands whenever it is a
    // valid polygon (the sphere layer's validation resolves such tiny polygons exactly), once
    // the ends of edges seen end-on, the same direction within rounding, are one vertex (which
    // moves the boundary by less than COINCIDENT_TOLERANCE).
    let mut ring: Vec<DVec3> = Vec::with_capacity(n);
    for &u in &out {
        if ring
            .last()
            .is_none_or(|&l| (u - l).length() > COINCIDENT_TOLERANCE)
        {
            ring.push(u);
        }
    }
    while ring.len() > 1 && (ring[0] - ring[ring.len() - 1]).length() <= COINCIDENT_TOLERANCE {
        ring.pop();
    }
    if ring.len() >= 3
        && let Ok(p) = SphericalPolygon::new(alloc::vec![ring])
    {
        return Ok(p);
    }
    order_edges_of(&contour, verts, frame)
}

/// [`convex_silhouette`] written to `out` as rings of directions that are not normalized
/// ([`SilhouetteRings`]), for the clip-free integrals, which need no unit vectors: where
/// [`convex_silhouette`] returns the chained loop as it is, the same vertices before
/// normalization (the spacing test decided the same way, on the unit vectors where it is
/// close); elsewhere (no face in front, a loop that needs merging or the general ordering) a
/// copy of its polygon's rings.
///
/// # Errors
///
/// As [`convex_silhouette`].
pub fn convex_silhouette_rings(
    poly: &ConvexPolyhedron,
    frame: &ShadingFrame,
    out: &mut SilhouetteRings,
) -> Result<(), GeomError> {
    out.clear();
    if let ConvexContour::Loop(ring, _) = convex_contour(poly, frame.origin()) {
        let verts = poly.vertices();
        let n = ring.len();
        let first = frame.to_local(verts[ring[0] as usize]);
        let mut prev = first;
        out.push(first);
        let mut ok = n >= 3;
        for &i in &ring[1..] {
            let cur = frame.to_local(verts[i as usize]);
            ok &= spaced(prev, cur, MATCH_TOLERANCE, ANTIPODAL_TOLERANCE);
            out.push(cur);
            prev = cur;
        }
        if ok && spaced(prev, first, MATCH_TOLERANCE, ANTIPODAL_TOLERANCE) {
            out.close_ring();
            return Ok(());
        }
    }
    out.set_polygon(&convex_silhouette(poly, frame)?);
    Ok(())
}

/// The contour of a convex polyhedron seen from a point.
enum ConvexContour {
    /// No face in front by the facing predicate: the point is inside or on the surface.
    NoFront,
    /// The contour edges chained into one loop by vertex index ([`chain_by_index`]), with the
    /// directed edges themselves.
    Loop(SmallVec<[u32; 24]>, SmallVec<[(u32, u32); 24]>),
    /// Directed contour edges that do not chain into one loop by index.
    Edges(SmallVec<[(u32, u32); 24]>),
}

/// The contour edges of `poly` seen from `x` (thesis 003 eq. 4.1/4.2), each directed so that its
/// front face lies on its left on the sphere (see [`convex_silhouette`]), chained where they make
/// one loop by index. Front faces by the facing predicate, the same distances and tolerance as
/// [`face_distances`](crate::solid::facing::face_distances), kept as flags on the stack.
fn convex_contour(poly: &ConvexPolyhedron, x: DVec3) -> ConvexContour {
    let mesh = poly.mesh();
    let at = FacingAt::new(mesh, x);
    // Front faces as flags on the stack for up to 256 faces.
    let faces = mesh.normals().len();
    let mut inline = [false; 256];
    let mut heap = Vec::new();
    let front: &mut [bool] = if faces <= inline.len() {
        &mut inline[..faces]
    } else {
        heap.resize(faces, false);
        &mut heap
    };
    let mut any = false;
    for ((is, n), &d) in front.iter_mut().zip(mesh.normals()).zip(mesh.offsets()) {
        *is = at.front(*n, d);
        any |= *is;
    }
    if !any {
        return ConvexContour::NoFront;
    }
    let mut contour: SmallVec<[(u32, u32); 24]> = SmallVec::new();
    for e in poly.edges() {
        // Every edge of a convex polyhedron has both faces (checked by `from_mesh`).
        match (front[e.f0 as usize], front[e.f1 as usize]) {
            (true, false) => contour.push((e.b, e.a)),
            (false, true) => contour.push((e.a, e.b)),
            _ => {}
        }
    }
    match chain_by_index(&contour, poly.vertices().len()) {
        Some(ring) => ConvexContour::Loop(ring, contour),
        None => ConvexContour::Edges(contour),
    }
}

/// What a convex polyhedron covers seen from a point with no face in front (inside or on the
/// surface): the intersection of the closed half-spaces behind the faces the point lies on:
/// the full sphere inside, a hemisphere on a face (a cube standing on the ground covers the
/// ground point's whole upper hemisphere), a lune on an edge.
#[cold]
fn inside_region(
    poly: &ConvexPolyhedron,
    frame: &ShadingFrame,
) -> Result<SphericalPolygon, GeomError> {
    let mut s = Vec::new();
    let tol = poly.facing(frame.origin(), &mut s);
    let mut region = SphericalPolygon::full();
    for (f, &d) in s.iter().enumerate() {
        if Side::of(d, tol) == Side::On {
            let n = frame.dir_to_local(poly.mesh().triangle_normal(f));
            region = region.try_clip_to_hemisphere(-n).map_err(|e| {
                e.give_up("a face normal of a convex polyhedron is not a direction")
            })?;
        }
    }
    Ok(region)
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
    // The polyhedron and the point are valid, so edges that do not close into loops are a
    // rounding give-up, not an input fault.
    order_directed_edges(&edges).map_err(|e| {
        e.give_up("silhouette edges do not close into loops within rounding (the point is within rounding distance of an edge's line)")
    })
}

/// Walks directed edges (vertex index pairs) as one loop: `Some(vertex indices)` when every
/// vertex used has exactly one outgoing edge and the walk from the first edge uses all of them,
/// `None` otherwise (several loops or pinches: left to the general path).
pub(crate) fn chain_by_index(edges: &[(u32, u32)], nverts: usize) -> Option<SmallVec<[u32; 24]>> {
    const NONE: u32 = u32::MAX;
    if edges.len() < 3 {
        return None;
    }
    // Inline for polyhedra of up to 64 vertices, so that silhouettes of small ones allocate
    // nothing here.
    let mut next: SmallVec<[u32; 64]> = smallvec::smallvec![NONE; nverts];
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
