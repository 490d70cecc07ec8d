//! Linearly transformed cosines and exact polygon integrals.
//!
//! The integrals here are of the clamped cosine `max(0, z) / pi` over spherical polygons in the
//! shading frame (normal `+z`): Lambert shading directly, and GGX shading after the polygon is
//! transformed by an LTC matrix (Heitz, Dupuy, Hill and Neubelt 2016, "Real-time polygonal-light
//! shading with linearly transformed cosines", here HDHN16).

mod integrate;

pub use integrate::{clamped_cosine_integral, clamped_cosine_integral_clip_free};
