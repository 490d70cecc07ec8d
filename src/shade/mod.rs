//! Shading with area lights and analytic soft shadows: scenes of lights and occluders, and the
//! radiance they give a shading point (seed paper 000, Alg. 1-3; thesis 003, section 4.2).
//!
//! - [`Scene`]: lights ([`Light`]) and occluders, and [`Scene::shade`], the analytic radiance at
//!   a shading point. Which part of each light the point sees comes from the visibility layer
//!   ([`crate::visibility::ClipVisibility`], the exact rule of [`Scene::visible_region`]; for
//!   convex and planar lights with separated blockers its fast path,
//!   [`crate::visibility::ClipVisibility::visible_pieces`]). [`Scene::shade_in`] reuses a
//!   [`ShadeContext`] (scratch storage, one per thread).
//! - [`Scene::shade_per_light`]: every light's share, split into diffuse and specular lobes,
//!   with its unshadowed value ([`LightShading`]), for denoising and ratio estimators.
//! - [`Material`]: Lambert + GGX with Schlick's Fresnel.
//! - Lights bounded by Bezier curves ([`BezierShape`], seed 004): in a scene, each point's
//!   flattening goes through the same visibility as any light, so occluders cast shadows from
//!   them; [`Light::shade_curved`] shades one unshadowed by the curved integrals directly.
//! - [`MonteCarlo`]: an estimator of the same radiance (solid-angle sampling of the lights'
//!   triangulated silhouettes or of their faces, [`LightSampling`], optionally combined with
//!   BRDF sampling by multiple importance sampling for near-mirror lobes, [`Techniques`]; exact
//!   ray-triangle visibility), with its standard error, for tests and comparisons.
//! - [`RatioEstimator`]: the analytic unshadowed radiance times a Monte Carlo estimate of the
//!   shadow ratio (\[HHM18\], the baseline of seed 000 section 4.2).
//!
//! The geometry types of the scene live in [`crate::solid`] and are re-exported here
//! ([`TriangleMesh`], [`ConvexPolyhedron`], [`Body`], [`ShadingFrame`]).
//!
//! # Limitations
//!
//! - Every object is opaque: occluders block every light, lights block each other (both sides),
//!   and a non-planar mesh light blocks itself. There are no transparent or emit-only objects.
//! - A blocker that interpenetrates a light and straddles some of its face planes makes that
//!   light go face by face (one spherical triangle per front face, minus cut blocker
//!   triangles): exact, but many spherical booleans, so much slower than the silhouette path.
//!   Open non-planar mesh lights always go face by face (their own back faces can hide them).
//! - A shading point inside a closed light receives nothing from it on every path (its surface
//!   emits outwards; no front face is seen).
//! - Where a value cannot be decided within rounding the query says so,
//!   [`crate::GeomError::Undecidable`], rather than return a doubtful value. The census of
//!   issue 24's regimes (tests/shade_census.rs: slivers, horizons through light vertices,
//!   grazing near-mirror views, interpenetrating and coplanar objects, points on surfaces)
//!   measures how often, per family; the rates are in BENCHMARKS.md ("never a silently wrong
//!   value (issue 24): give-up rates"). Most give-ups are on the per-triangle path
//!   ([`Method::PerTriangle`], and meshes), which chains many spherical booleans of
//!   edge-sharing triangles.
//! - A shading point within the facing predicate's tolerance of a face plane
//!   ([`crate::solid::FACE_TOLERANCE`]) lies on that plane for every facing decision, but the
//!   two methods place the rest of the object differently there (the silhouette as seen from
//!   the plane, the per-triangle path from the point as it is); their values differ by no more
//!   than moving the point across that band changes them, which only a near-mirror lobe whose
//!   peak runs along the face makes visible (`3.5e-7` of the value seen).
//!
//! # Examples
//!
//! ```
//! use arealight::glam::DVec3;
//! use arealight::shade::{ConvexPolyhedron, Light, Material, Scene, TriangleMesh};
//! // A quad light facing down, 3 above the floor, and a cube half-way, slightly off-axis.
//! let quad = TriangleMesh::quad(DVec3::new(0.0, 0.0, 3.0), DVec3::Y * 0.5, DVec3::X * 0.5)?;
//! let cube = ConvexPolyhedron::cuboid(DVec3::new(0.3, 0.0, 1.5), DVec3::splat(0.25))?;
//! let lit = Scene::new(vec![Light::new(quad.clone(), DVec3::ONE)?], vec![])?;
//! let shadowed = Scene::new(vec![Light::new(quad, DVec3::ONE)?], vec![cube.into()])?;
//! let floor = Material::new(DVec3::splat(0.8), DVec3::splat(0.04), 0.5)?;
//! let (x, n, v) = (DVec3::ZERO, DVec3::Z, DVec3::new(0.3, 0.0, 1.0));
//! let full = lit.shade(x, n, v, &floor)?;
//! let penumbra = shadowed.shade(x, n, v, &floor)?;
//! // The cube hides part of the light: a soft shadow, neither black nor fully lit.
//! assert!(penumbra.x > 0.1 * full.x && penumbra.x < 0.9 * full.x);
//! # Ok::<(), arealight::GeomError>(())
//! ```
//!
//! # References
//!
//! - Seed 000: *Fast analytic soft shadows from area lights* (Alg. 1 overview, Alg. 2 silhouettes,
//!   section 3.5 culling, section 4.4 per-triangle method).
//! - Thesis 003: section 4.2 (silhouettes of convex polyhedra oriented by front faces),
//!   section 6 (solid-angle sampling of silhouettes, \[Arv95\], \[Pet20\]).
//! - \[HDHN16\] E. Heitz, J. Dupuy, S. Hill, D. Neubelt. *Real-time polygonal-light shading with
//!   linearly transformed cosines.* ACM TOG 35(4), 2016.
//! - \[HHM18\] E. Heitz, S. Hill, M. McGuire. *Combining analytic direct illumination and
//!   stochastic shadows.* I3D 2018.

mod batch;
mod curved;
mod curved_reference;
pub(crate) mod demo;
mod material;
mod query;
pub mod ratio;
pub(crate) mod reference;
mod scene;
mod two_sided;
mod validate;

pub use crate::solid::{
    BezierSegment, BezierShape, Body, ConvexPolyhedron, ShadingFrame, TriangleMesh,
};
pub use crate::visibility::{Blocker, Method};
pub use batch::BatchResult;
#[cfg(feature = "rayon")]
pub use batch::PAR_MIN_RUN;
pub use curved::{CurvedShading, DEFAULT_DIFFUSE_SUBDIVISION};
pub use material::Material;
pub use query::{LightShading, ShadeContext};
pub use ratio::{LightRatio, RatioEstimator};
pub use reference::{Estimate, LightSampling, MonteCarlo, ReferenceBrdf, Techniques};
pub use scene::{Light, Scene};
pub use validate::{SceneIssue, SceneReport};
