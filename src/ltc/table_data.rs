// Placeholder, overwritten by `cargo run --release --features fit --example fit_ltc`.
#![cfg_attr(rustfmt, rustfmt_skip)]
pub(crate) const SIZE: usize = 64;
pub(crate) const ALPHA_MIN: f64 = 1e-4;
pub(crate) const COS_MIN: f64 = 1e-3;
pub(crate) static M_INV_00: [f64; 4096] = [1.0; 4096];
pub(crate) static M_INV_02: [f64; 4096] = [0.0; 4096];
pub(crate) static M_INV_20: [f64; 4096] = [0.0; 4096];
pub(crate) static M_INV_22: [f64; 4096] = [1.0; 4096];
pub(crate) static NORM: [f64; 4096] = [1.0; 4096];
pub(crate) static ALBEDO: [f64; 4096] = [1.0; 4096];
pub(crate) static FRESNEL: [f64; 4096] = [0.0; 4096];
