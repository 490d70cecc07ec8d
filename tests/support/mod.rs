//! Helpers shared by the integration tests: the one test RNG ([`Rng`]) and the generators and
//! independent references built on it, by layer. A test file includes it with `mod support;`.
//!
//! - [`rng`]: `Rng` (SplitMix64), uniform numbers, directions.
//! - [`planar`]: the text format for shapes, identity checks, proptest strategies, reference
//!   clippers.
//! - [`sphere`]: star-shaped spherical polygons, stratified Monte Carlo solid angles and
//!   integrals with stated bounds, quadrature over spherical triangles.
//! - [`ltc`]: quadrature about a pole, histogram checks of samplers.
//! - [`bezier`]: curved outlines placed in 3D, Green's-theorem and polygonization references for
//!   their integrals.
//! - [`shade`]: shading points on meshes and the ground, views above a surface.
//! - [`visibility`]: an exact ray arbiter between visible regions.
#![allow(dead_code)]

pub mod bezier;
pub mod ltc;
pub mod planar;
pub mod rng;
pub mod shade;
pub mod sphere;
pub mod visibility;

pub use rng::Rng;

/// Number of proptest cases: `default`, or `PROPTEST_CASES` from the environment for longer
/// opt-in stress runs (`PROPTEST_CASES=20000 cargo test --release --test sphere_props`).
pub fn cases(default: u32) -> u32 {
    std::env::var("PROPTEST_CASES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(default)
}
