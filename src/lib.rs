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
//! name the same version. The shading entry points also take `f32` vectors (glam's `Vec3`,
//! `Vec3A`, `[f32; 3]`: [`IntoDVec3`]), widened exactly at the boundary. Invalid input (NaN,
//! infinity, degenerate geometry) is reported as a [`GeomError`], never as a panic.
//!
//! # Quick start: shading
//!
//! A scene is lights and occluders; a shading point is a position, a normal, a view direction
//! (towards the viewer) and a material; [`shade::Scene::shade`] returns the RGB radiance leaving
//! the point towards the viewer, direct light with exact soft shadows.
//!
//! ```
//! use arealight::glam::{DVec3, Vec3};
//! use arealight::shade::{ConvexPolyhedron, Light, Material, Scene, TriangleMesh};
//! // A 1 x 1 quad light 2 above the floor. quad(c, u, v) emits towards u x v: here Y x X = -Z,
//! // down to the floor (the other way, the image is black: Scene::validate says so).
//! let quad = TriangleMesh::quad(DVec3::new(0.0, 0.0, 2.0), DVec3::Y * 0.5, DVec3::X * 0.5)?;
//! let light = Light::new(quad, DVec3::splat(5.0))?; // emitted RGB radiance
//! // A box standing on the floor beside the point: it hides none of the light from there.
//! let cube = ConvexPolyhedron::cuboid(DVec3::new(3.0, 0.0, 0.5), DVec3::splat(0.5))?;
//! let scene = Scene::new(vec![light], vec![cube.into()])?;
//! assert!(scene.validate(&[DVec3::ZERO]).is_clean());
//! let white = Material::diffuse(DVec3::ONE)?;
//! let rgb = scene.shade(DVec3::ZERO, DVec3::Z, DVec3::Z, &white)?;
//! // Closed form: a square of half side a at distance d on its axis gives a Lambertian surface
//! // albedo * radiance * (4 / pi) s atan(s), with s = a / sqrt(a^2 + d^2).
//! let s = 0.5 / (0.5f64 * 0.5 + 2.0 * 2.0).sqrt();
//! let expect = 5.0 * 4.0 / std::f64::consts::PI * s * s.atan();
//! assert!((rgb.x - expect).abs() < 1e-12);
//! // The same call from an f32 renderer.
//! assert_eq!(scene.shade(Vec3::ZERO, Vec3::Z, Vec3::Z, &white)?, rgb);
//! # Ok::<(), arealight::GeomError>(())
//! ```
//!
//! Many points at once, on all cores: [`shade::Scene::par_shade_batch`] (feature `rayon`, on by
//! default). Scene files (OBJ, glTF): `io::load` (features `obj`, `gltf`). Lights emit from the
//! front of their triangles only (see [`shade::Light`]); [`shade::Light::two_sided`] makes a
//! planar light emit from both sides, and [`shade::Scene::validate`] reports lights facing
//! away from everything and overlapping coplanar lights.
//!
//! # What each path costs
//!
//! Per shading point, each light costs its region seen from the point, minus the region of each
//! object that may lie between (one dot product and a bounding-cone test per object decide
//! that; a separating plane per (light, object) pair is precomputed by `Scene::new`), then two
//! LTC integrals per visible piece (about 50-100 ns each). Measured on a shared 2-core machine
//! (BENCHMARKS.md, `shade`; the examples print their own):
//!
//! - **Convex shapes** ([`shade::ConvexPolyhedron`]): one silhouette polygon per object. A convex
//!   light with nothing in the way takes 1-2 µs; with one to three convex occluders in its
//!   penumbra about 8-13 µs (each one spherical set difference).
//! - **Planar mesh lights** (quads): one spherical triangle per front triangle, no union. Closed
//!   non-convex mesh lights: their exact silhouette (a 162-vertex icosphere in about 4 µs).
//!   Open non-planar mesh lights, and meshes taken per triangle: one set operation per triangle
//!   (the same icosphere per triangle: about 110 µs).
//! - **Mesh occluders** ([`shade::TriangleMesh`]): one region, and one set difference, per
//!   triangle that passes the culling. A wall of two triangles is cheap; a dense mesh near a
//!   light is not (nothing groups triangles yet). Prefer convex pieces where the geometry is
//!   convex (the loaders make closed convex objects convex polyhedra).
//! - **Interpenetration**: a blocker that crosses a light's face planes makes that light go face
//!   by face (45-700 µs in the benchmarks). Keep lights and occluders apart where you can.
//! - **Scene size**: the culling is linear in lights times objects per point; there is no
//!   spatial index, so thousands of objects cost per point what their culling costs. The shipped
//!   Cornell box (one quad light, two convex blocks, five two-triangle walls) shades in about
//!   80 µs per point per core with glossy floors and walls, all shadow regions exact.
//!
//! # What a renderer does with each error
//!
//! Every error is a [`GeomError`]; [`GeomError::is_undecidable`] tells the two kinds apart:
//!
//! - **Input faults** (building lights, occluders, materials, or a shading query with a NaN,
//!   infinite, zero-length or out-of-range argument; the variant names the argument or the
//!   vertex): a bug or bad data on the caller's side. Fix the input or skip the object; for a
//!   shading query, skip the point (black, or the previous frame's value) and count it.
//! - **Give-ups** ([`GeomError::Undecidable`]): the query is valid, but a configuration met on
//!   the way (a point within rounding of a silhouette edge, near-coincident blocker edges) cannot
//!   be decided exactly, and the crate declines to guess. Fall back for that point: the Monte
//!   Carlo reference ([`shade::MonteCarlo`], noisy but unbiased, as the `scene_file` and `bake`
//!   examples do), or the point moved by a tiny amount. They are rare (none in the examples'
//!   renders); count them.
//!
//! Batches ([`shade::Scene::shade_batch`], [`shade::Scene::par_shade_batch`]) return one result
//! per point, so one bad point never costs the others. Scene files report
//! `io::SceneFileError` with the file, the object and the reason.
//!
//! # Features
//!
//! - `std` (default): `std::error::Error` for [`GeomError`], std's float functions.
//! - `rayon` (default, needs `std`): [`shade::Scene::par_shade_batch`] on all cores.
//! - `obj`, `gltf` (need `std`): the scene-file loaders of `io` (crates `tobj`, `gltf`).
//! - `libm`: float functions from libm, for `no_std` targets (wins over `std` when both are on,
//!   which makes results bit-identical across platforms). A `no_std` build turns the default
//!   features off and pays for none of the optional crates.
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
    pub use crate::solid::silhouette::{
        DirectReason, TriangleRole, convex_silhouette, convex_silhouette_rings, triangle_polygon,
    };
    pub use crate::visibility::cull::{SHAFT_MARGIN, Shaft, above_horizon, may_occlude};
}

pub use convert::IntoDVec3;
pub use error::GeomError;

// The README's example is compiled and run as a doctest.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
struct ReadmeDoctests;
