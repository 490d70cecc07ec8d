//! Exact, noise-free direct lighting from area lights, with analytic soft shadows, built on robust
//! spherical-polygon geometry.
//!
//! The crate is layered; each layer uses only the ones below it (see `ARCHITECTURE.md`):
//!
//! - [`planar`]: 2D polygons and their boolean operations.
//! - [`sphere`]: spherical polygons: solid angle, gnomonic projection, ordering of silhouette edges,
//!   hemisphere clipping.
//! - [`ltc`]: linearly transformed cosines and polygon integrals.
//! - [`solid`]: 3D geometry without light: triangle meshes, convex polyhedra, silhouettes seen
//!   from a point.
//! - [`visibility`]: which part of a light a shading point sees, behind one trait with backends.
//! - [`sdf`]: signed-distance scenes and approximate area-light soft shadows in them (beside
//!   the exact shading, for comparison).
//! - [`shade`]: scenes of lights and occluders, materials, and the radiance at a shading point.
//!
//! Scalars are `f64` and vectors are glam's `DVec2`/`DVec3`; glam is re-exported so that callers
//! name the same version. Invalid input (NaN, infinity, degenerate geometry) is reported as a
//! [`GeomError`], never as a panic.
//!
//! # Features
//!
//! - `std` (default): `std::error::Error` for [`GeomError`], std's float functions.
//! - `libm`: float functions from libm, for `no_std` targets (wins over `std` when both are on,
//!   which makes results bit-identical across platforms).
#![no_std]
#![forbid(unsafe_code)]
#![warn(missing_docs)]
// Comparisons are written `!(x > t)` on purpose where NaN must fail the test.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

extern crate alloc;
#[cfg(feature = "std")]
extern crate std;

pub use glam;

mod convert;
mod error;
#[cfg(any(feature = "obj", feature = "gltf"))]
pub mod io;
pub mod ltc;
pub(crate) mod math;
pub mod planar;
pub mod sdf;
pub mod shade;
pub mod solid;
pub mod sphere;
pub mod visibility;

/// Items public only for the crate's own tests, benchmarks, fuzz targets and examples: the
/// planar fast path and robust pipeline called separately, the planar vertex classes, the demo
/// scene, the silhouette and culling helpers. Not part of the API: they may change or vanish in
/// any release.
#[doc(hidden)]
pub mod internals {
    pub use crate::planar::boolean::intersect::MAX_PASSES;
    pub use crate::planar::boolean::label::VertexClass;
    pub use crate::planar::boolean::{
        ContactClasses, boolean_fast, boolean_robust, contact_classes,
    };
    pub use crate::shade::demo::{Demo, DemoConfig, demo_scene};
    pub use crate::solid::fixtures::{bumpy_sphere, extruded_star, thesis_polyhedra, torus};
    pub use crate::solid::silhouette::{TriangleRole, convex_silhouette, triangle_polygon};
    pub use crate::visibility::cull::{above_horizon, may_occlude};
}

pub use convert::IntoDVec3;
pub use error::GeomError;

// The README's example is compiled and run as a doctest.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
struct ReadmeDoctests;
