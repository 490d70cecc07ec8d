//! Linearly transformed cosines and exact polygon integrals.
//!
//! The integrals are of the clamped cosine `max(0, z) / pi` over spherical polygons in the
//! shading frame (normal `+z`): Lambert shading directly, and GGX shading after the polygon is
//! transformed by an LTC matrix.
//!
//! - [`clamped_cosine_integral`] and [`clamped_cosine_integral_clip_free`]: the exact polygon
//!   integral (horizon clip + Baum's edge sum), and its clip-free form (thesis 003, eq. 4.6/4.7).
//! - [`ggx`]: the GGX BRDF (height-correlated Smith masking) and its visible-normal sampler, the
//!   ground truth the tables approximate.
//! - [`Ltc`]: the linearly transformed cosine distribution (\[HDHN16\] §3): density and sampling.
//! - [`LtcTable`] / [`lookup`]: the fitted GGX tables with bilinear lookup (\[HDHN16\] §4).
//! - [`curved_clamped_cosine_integral`], [`curved_ltc_integral`], [`ggx_curved_integral`]: the
//!   same integrals over planar regions bounded by cubic Bezier curves ([`CurveSegment`]), with
//!   per-point adaptive subdivision and algebraic horizon clipping (seed 004).
//! - `fit` (feature `fit`): the fitter that generates the tables.
//!
//! # Examples
//!
//! ```
//! use arealight::glam::DVec3;
//! use arealight::ltc::{ggx_brdf_cos, lookup};
//! // LTC for a view 45 degrees off the normal on a surface with GGX alpha = 0.2.
//! let cos_v = core::f64::consts::FRAC_1_SQRT_2;
//! let l = lookup(cos_v, 0.2).unwrap();
//! let ltc = l.ltc().unwrap();
//! // norm * D approximates the cosine-weighted BRDF near the mirror direction.
//! let v = DVec3::new(cos_v, 0.0, cos_v);
//! let mirror = DVec3::new(-cos_v, 0.0, cos_v);
//! let approx = l.norm * ltc.density(mirror);
//! let exact = ggx_brdf_cos(v, mirror, 0.2);
//! assert!((approx / exact - 1.0).abs() < 0.2);
//! ```
//!
//! # References
//!
//! - \[HDHN16\] E. Heitz, J. Dupuy, S. Hill, D. Neubelt. *Real-time polygonal-light shading with
//!   linearly transformed cosines.* ACM TOG 35(4), 2016.

mod curved;
mod distribution;
#[cfg(feature = "fit")]
pub mod fit;
pub mod ggx;
mod integrate;
mod table;
#[rustfmt::skip]
// The generated channel arrays are constants read only at compile time, where `table.rs`
// interleaves them into one static of nodes; no copy of them exists at run time.
#[allow(clippy::large_const_arrays)]
mod table_data;

pub use curved::{
    CURVE_PLANE_TOLERANCE, CurveSegment, CurvedIntegral, DIFFUSE_EPS, INITIAL_INTERVALS, MAX_DEPTH,
    MAX_UNIFORM, Subdivision, curved_clamped_cosine_integral, curved_ltc_integral,
    ggx_curved_integral, specular_eps,
};
pub use distribution::Ltc;
pub(crate) use distribution::cosine_sample;
pub use ggx::{
    GGX_MIN_ALPHA, ggx_brdf_cos, ggx_ndf, ggx_sample_vndf, ggx_vndf_pdf, ggx_vndf_weight,
};
pub use integrate::{
    EDGE_FACTOR_RATIONAL_MAX_ERROR, clamped_cosine_integral, clamped_cosine_integral_clip_free,
    clamped_cosine_integral_rational, clamped_cosine_integral_rings, edge_factor_rational,
    ggx_polygon_integral, ltc_integral, ltc_integral_rational, ltc_integral_rings,
};
pub(crate) use integrate::{
    clamped_cosine_integral_upper, ltc_rings_integral, upper_rings_integral,
};
pub use table::{LtcLookup, LtcTable, lookup};
