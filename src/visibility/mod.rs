//! Which part of a light a shading point sees: the visible region of each light as spherical
//! polygons in the point's [`ShadingFrame`], behind one trait ([`Visibility`]) so that backends
//! can be swapped.
//!
//! - [`ClipVisibility`]: the exact rule `visible(f) = proj(f) - U_B proj(B n H_f)` evaluated with
//!   spherical set operations (seed 000 Alg. 1, extended to blockers that interpenetrate or hide
//!   lights); see [`ClipVisibility::visible_region`].
//! - [`PluckerVisibility`]: the same rule by the lazily built BSP of occluder equivalence
//!   classes in Pluecker space (seed 002, Alg. 1), with trees reused across coherent queries
//!   through a caller-owned [`PluckerContext`]; see [`plucker`].
//!
//! Blockers are named by [`Blocker`] (an occluder or another light), never by a bare index.
//! Culling (seed 000 `GetBetween`, section 3.5) discards blockers that cannot lie between the
//! point and a light. This layer knows solids and spherical polygons, no radiance or BRDF.

mod clip;
mod contour;
pub(crate) mod cull;
mod mesh_pieces;
mod overlay;
mod pieces;
pub mod plucker;
mod union;

use alloc::vec::Vec;

pub use clip::{BVH_MIN_TRIANGLES, ClipVisibility, Method};
pub use pieces::Pieces;
pub use plucker::{PluckerContext, PluckerVisibility, WithContext};

use crate::GeomError;
use crate::solid::ShadingFrame;
use crate::sphere::SphericalPolygon;

/// An object that may hide part of a light: an occluder or another light, by its index in the
/// scene's list of occluders or of lights.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
#[non_exhaustive]
pub enum Blocker {
    /// Occluder `k` (an index into the scene's occluders).
    Occluder(usize),
    /// Light `k` (an index into the scene's lights): a light's geometry is opaque to the others.
    Light(usize),
}

/// Which part of each light a shading point sees.
///
/// Regions are in the shading frame (normal on `+z`), clipped to the upper hemisphere, as pieces
/// with disjoint interiors, so that integrals over them add up. Implementations are immutable
/// after construction and shared by all threads of a renderer.
pub trait Visibility {
    /// Number of lights.
    fn light_count(&self) -> usize;

    /// The part of light `light` visible from the frame's point: what every blocker (occluders,
    /// other lights, the light's own other triangles) leaves of it.
    ///
    /// # Errors
    ///
    /// [`GeomError::OutOfRange`] for a light index past the end; [`GeomError::Undecidable`] when
    /// the region cannot be decided within rounding.
    fn visible_region(
        &self,
        light: usize,
        frame: &ShadingFrame,
    ) -> Result<Vec<SphericalPolygon>, GeomError>;

    /// The part of light `light` the frame's point would see with every other object removed
    /// (the light's own self-occlusion kept): the reference of shadow ratios.
    ///
    /// # Errors
    ///
    /// As [`Visibility::visible_region`].
    fn unoccluded_region(
        &self,
        light: usize,
        frame: &ShadingFrame,
    ) -> Result<Vec<SphericalPolygon>, GeomError>;

    /// The backend's fast path, where it has one: the region of
    /// [`Visibility::visible_region`] (`blocked`) or of [`Visibility::unoccluded_region`]
    /// (without) as [`Pieces`] in `out`, whose integrals are those of the polygons up to
    /// rounding. `Ok(true)` when `out` holds the region, `Ok(false)` when the caller must ask
    /// for the polygons. The default has no fast path; [`ClipVisibility`] answers with
    /// [`ClipVisibility::visible_pieces`].
    ///
    /// # Errors
    ///
    /// [`GeomError::OutOfRange`] for a light index past the end (the default, which declines
    /// every query, leaves that to [`Visibility::visible_region`]).
    fn visible_pieces(
        &self,
        light: usize,
        frame: &ShadingFrame,
        blocked: bool,
        out: &mut Pieces,
    ) -> Result<bool, GeomError> {
        let _ = (light, frame, blocked, out);
        Ok(false)
    }
}
