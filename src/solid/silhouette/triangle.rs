//! Single triangles seen from a point (the per-triangle method, seed 000 section 4.4), whole or
//! cut by a plane.

use alloc::vec;
use alloc::vec::Vec;

use glam::DVec3;
use smallvec::SmallVec;

use crate::GeomError;
use crate::solid::facing::{Side, face_side};
use crate::solid::{ShadingFrame, TriangleMesh};
use crate::sphere::SphericalPolygon;

/// Corners of a clipped blocker polygon whose directions are closer than this (chord length) are
/// merged before the polygon is built: far below any feature the sphere layer resolves, far above
/// the rounding of an interpolated cut point.
const MERGE_TOLERANCE: f64 = 1e-13;

/// How a triangle of a mesh enters the per-triangle method.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum TriangleRole {
    /// Part of a light: only its front face emits, so a back-facing triangle covers nothing.
    Emitter,
    /// Part of an occluder: it blocks light from either side.
    Blocker,
}

/// The spherical triangle that mesh triangle `i` covers, seen from the frame's origin, in the
/// local frame; `None` when it covers nothing (seen edge-on by the facing predicate,
/// [`face_side`], or so nearly edge-on that its projection has no area within rounding, or from behind for an
/// [`TriangleRole::Emitter`]).
///
/// # Errors
///
/// [`GeomError::Undecidable`] for a projection that rounding made degenerate in a way
/// [`SphericalPolygon::new`] rejects (other than having no area, which is `Ok(None)`).
pub fn triangle_polygon(
    mesh: &TriangleMesh,
    i: usize,
    frame: &ShadingFrame,
    role: TriangleRole,
) -> Result<Option<SphericalPolygon>, GeomError> {
    let side = face_side(mesh, i, frame.origin());
    if side == Side::On || (side == Side::Behind && role == TriangleRole::Emitter) {
        return Ok(None);
    }
    let [a, b, c] = mesh.triangle(i).map(|v| frame.to_local(v));
    covered_region(&[a, b, c], side)
}

/// The region covered by a planar convex polygon (vertices in the local frame, counter-clockwise
/// seen from the side `side` says the point is on, front or back), or `None` when its
/// projection has no area within rounding.
fn covered_region(local: &[DVec3], side: Side) -> Result<Option<SphericalPolygon>, GeomError> {
    // Counter-clockwise seen from the point is clockwise on the sphere seen from outside, so a
    // front-facing polygon covers the reversed ring (see `convex_silhouette`).
    let ordered: SmallVec<[DVec3; 4]> = if side == Side::Front {
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
        // Rounding can also make the ring of a convex polygon seen nearly edge-on look
        // self-intersecting (a triangle, or a sliver triangle cut by a plane through both its
        // long edges, whose two cut points lie 1e-12 apart). Its solid angle, the sum of its
        // fan triangles' by Van Oosterom and Strackee's formula on edge differences, is then
        // below what the sphere layer resolves: it covers nothing. The formula is trusted only
        // where its denominator is well away from zero (no two corners nearly opposite, which a
        // point close to the polygon's edge line makes, and where it can cover a quarter of the
        // sphere).
        Err(GeomError::SelfIntersecting { .. })
            if edge_on_fan(keep.iter().map(|&k| ordered[k])) =>
        {
            Ok(None)
        }
        Err(e) => Err(e.give_up("a projected triangle is degenerate within rounding")),
    }
}

/// Solid angle (sr) below which a projected convex polygon that [`SphericalPolygon::new`]
/// rejects is taken to cover nothing ([`edge_on_fan`]). Validation rejects a ring that folds
/// back at a vertex (a wedge below `1e-12` rad, see `sphere::polygon::folds_back`); a triangle
/// with such a corner lies in the lune of that wedge, `2e-12` sr at most, so twice that bound
/// accepts every such triangle whose measure is certified. The sphere layer drops result rings
/// at the same scale (thinner than `1e-12` times their squared perimeter).
const EDGE_ON_SOLID_ANGLE: f64 = 4e-12;

/// Whether the convex polygon of directions `ring` (any lengths; the projection of a planar
/// convex polygon) has a solid angle below [`EDGE_ON_SOLID_ANGLE`], certified on its fan from
/// the first corner: each fan triangle by Van Oosterom and Strackee's
/// `tan(Omega / 2) = det / den` with the determinant on edge differences (absolute error below
/// `64 eps` for unit vectors, whose differences are at most 2 long) and a denominator of at
/// least `0.5`, where `|Omega| <= 2 |det| / den`, and the polygon's solid angle at most the sum
/// of its fan triangles'.
fn edge_on_fan(ring: impl Iterator<Item = DVec3>) -> bool {
    let mut units: SmallVec<[DVec3; 4]> = SmallVec::new();
    for v in ring {
        match v.try_normalize() {
            Some(u) => units.push(u),
            None => return false,
        }
    }
    if units.len() < 3 {
        return false;
    }
    let a = units[0];
    let mut bound = 0.0;
    for w in units[1..].windows(2) {
        let (b, c) = (w[0], w[1]);
        let det = a.dot((b - a).cross(c - a));
        let den = 1.0 + a.dot(b) + b.dot(c) + c.dot(a);
        if !(den >= 0.5) {
            return false;
        }
        bound += 2.0 * (det.abs() + 64.0 * f64::EPSILON) / den;
    }
    bound <= EDGE_ON_SOLID_ANGLE
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
/// [`GeomError::Undecidable`] for a projection that rounding made degenerate in a way
/// [`SphericalPolygon::new`] rejects (other than having no area, which is `Ok(None)`).
pub(crate) fn clipped_triangle_polygon(
    mesh: &TriangleMesh,
    i: usize,
    dist: [f64; 3],
    frame: &ShadingFrame,
) -> Result<Option<SphericalPolygon>, GeomError> {
    if dist.iter().all(|&d| d <= 0.0) {
        return Ok(None);
    }
    let side = face_side(mesh, i, frame.origin());
    if side == Side::On {
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
