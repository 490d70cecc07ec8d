//! Two-sided planar lights ([`Light::two_sided`]).
//!
//! A planar light's triangles share one plane and one normal, so a shading point sees all of
//! them from the front, all from behind, or all edge-on. From behind, a two-sided light shows
//! what the same light turned around ([`TriangleMesh::flipped`], [`BezierShape::flipped`])
//! shows from the front, with every blocker unchanged: blockers act on either side alike, and
//! a light's geometry blocks the other lights with both of its sides. So the scene keeps a
//! second visibility backend in which the two-sided lights are turned around, and each query of
//! such a light picks the backend by one call of the facing predicate ([`face_side`]), whose
//! answer for the turned mesh is exactly the opposite one. Everything below the shading layer keeps seeing one-sided lights.

use alloc::boxed::Box;
use alloc::vec::Vec;

use super::scene::Light;
use crate::solid::facing::{Side, face_side};
use crate::solid::{Body, ShadingFrame};
use crate::visibility::ClipVisibility;

/// The visibility backend with every two-sided light turned around, or `None` when the scene
/// has no two-sided light.
pub(super) fn back_visibility(
    lights: &[Light],
    occluders: &[Body],
) -> Option<ClipVisibility<Light>> {
    if !lights.iter().any(Light::is_two_sided) {
        return None;
    }
    let turned: Vec<Light> = lights
        .iter()
        .map(|l| match (l.is_two_sided(), l.shape()) {
            (true, Body::Mesh(m)) => l.with_body(Body::Mesh(m.flipped())),
            (true, Body::Bezier(b)) => l.with_body(Body::Bezier(Box::new(b.flipped()))),
            _ => l.clone(),
        })
        .collect();
    Some(ClipVisibility::new(turned, occluders.to_vec()))
}

/// Whether light `light` is two-sided and the frame's point lies behind its plane (by the
/// facing predicate on its first triangle: a two-sided light is planar). An index past the end
/// is `false` (the query reports it).
pub(super) fn seen_from_behind(lights: &[Light], light: usize, frame: &ShadingFrame) -> bool {
    lights.get(light).is_some_and(|l| {
        l.is_two_sided() && face_side(l.shape().mesh(), 0, frame.origin()) == Side::Behind
    })
}
