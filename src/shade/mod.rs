//! Shading with area lights and analytic soft shadows: scenes of lights and occluders, and the
//! radiance they give a shading point (seed paper 000, Alg. 1-3; thesis 003, section 4.2).
//!
//! - [`mesh`]: [`TriangleMesh`] (any mesh, the per-triangle method) and [`ConvexPolyhedron`]
//!   (validated, or built as a convex hull), with the primitives of the seed paper's test scene.
//! - [`silhouette`]: the spherical polygon of a convex polyhedron seen from a point (its
//!   silhouette, oriented by front faces) and of single triangles, in the [`ShadingFrame`].
//! - [`cull`]: discarding occluders that cannot lie between the point and a light (`GetBetween`).
//! - [`brdf`]: [`Material`] (Lambert + GGX with Schlick's Fresnel).
//! - [`demo`]: the test scene of seed 000 (Fig. 4), shared by the render example, tests and benches.
//! - [`scene`]: [`Scene::shade`], the analytic radiance at a shading point.
//! - [`reference`](mod@reference): a Monte Carlo estimator of the same radiance (solid-angle sampling of the
//!   lights' triangles, exact ray-triangle visibility), with its standard error, for tests and
//!   comparisons.
//!
//! # References
//!
//! - Seed 000: *Fast analytic soft shadows from area lights* (Alg. 1 overview, Alg. 2 silhouettes,
//!   section 3.5 culling, section 4.4 per-triangle method).
//! - Thesis 003: section 4.2 (silhouettes of convex polyhedra oriented by front faces),
//!   section 6 (solid-angle sampling of silhouettes, \[Arv95\], \[Pet20\]).
//! - \[HDHN16\] E. Heitz, J. Dupuy, S. Hill, D. Neubelt. *Real-time polygonal-light shading with
//!   linearly transformed cosines.* ACM TOG 35(4), 2016.

pub mod brdf;
pub mod cull;
pub mod demo;
pub mod mesh;
pub mod reference;
pub mod scene;
pub mod silhouette;

pub use brdf::Material;
pub use cull::{BoundingSphere, may_occlude};
pub use demo::{Demo, DemoConfig, demo_scene};
pub use mesh::{ConvexPolyhedron, TriangleMesh};
pub use reference::{Estimate, MonteCarlo, Pcg32, ReferenceBrdf};
pub use scene::{Light, Method, Scene, Shape};
pub use silhouette::{ShadingFrame, TriangleRole, convex_silhouette, triangle_polygon};
