//! Signed-distance scenes and approximate area-light soft shadows in them (seed 001).
//!
//! - [`field`]: the [`Sdf`] trait (signed, 1-Lipschitz fields, with [`Exactness`] saying where
//!   the value is the exact distance), primitives with exact distances ([`Sphere`], [`Cuboid`],
//!   [`RoundedBox`], [`Capsule`], [`Cylinder`], [`Torus`], [`Plane`]), similarity transforms
//!   ([`Transformed`]) and CSG ([`Union`], [`UnionAll`], [`Intersection`], [`Difference`],
//!   [`SmoothUnion`]).
//! - [`trace`]: sphere tracing (seed 001 Alg. 1) and Lipschitz-safe cone tracing, both with step
//!   and distance caps, so they always terminate.
//! - [`shadow`]: seed 001's minimal tangent cone search (Alg. 2), its fast soft shadow for
//!   spherical lights (section 4.1) and the proxy-occluder integration for any light (section
//!   4.2), and the Quilez soft shadows as baselines.
//!
//! The module sits beside the exact visibility of [`crate::shade`] and uses nothing above
//! `ltc` and `sphere`. These shadows are approximations: the example `sdf_shadows` and
//! `BENCHMARKS.md` measure them against the crate's exact soft shadows on the same scenes.
//!
//! # Examples
//!
//! ```
//! use arealight::glam::DVec3;
//! use arealight::sdf::{ConeSearch, Plane, Profile, Sphere, SphereLight, Union, fast_soft_shadow};
//! // A ball of radius 0.5 standing on the floor, a spherical light above it.
//! let scene = Union(
//!     Plane::new(DVec3::ZERO, DVec3::Z)?,
//!     Sphere::new(DVec3::new(0.0, 0.0, 0.5), 0.5)?,
//! );
//! let light = SphereLight::new(DVec3::new(0.0, 0.0, 4.0), 0.5)?;
//! let search = ConeSearch::new(0.05, 1e-4);
//! let under = fast_soft_shadow(&scene, DVec3::new(0.2, 0.0, 0.0), &light, &search, Profile::Chord)?;
//! let away = fast_soft_shadow(&scene, DVec3::new(3.0, 0.0, 0.0), &light, &search, Profile::Chord)?;
//! assert!(under < 0.01 && away > 0.99);
//! # Ok::<(), arealight::GeomError>(())
//! ```

pub mod field;
pub mod shadow;
pub mod trace;

pub use field::{
    Capsule, Cuboid, Cylinder, Difference, Exactness, Intersection, MAX_MAGNITUDE, Plane,
    RoundedBox, Sdf, SmoothUnion, Sphere, Torus, Transformed, Union, UnionAll, normal,
};
pub use shadow::{
    AreaLight, ConeMinimum, ConeSearch, Profile, ProxyOccluder, QuadLight, QuilezSettings,
    SphereLight, chord_visibility, fast_soft_shadow, minimal_tangent_cone, proxy_integral,
    proxy_occluder, proxy_quad_integral, quilez_improved_shadow, quilez_shadow,
    smoothstep_visibility,
};
pub use trace::{Trace, TraceLimits, cone_trace, sphere_trace};
