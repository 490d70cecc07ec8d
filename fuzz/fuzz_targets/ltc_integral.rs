//! Fuzz the clamped-cosine integrals: the clip-free paths (unit vectors and under a linear map,
//! exact and rational edge terms) against the exact clip, for any polygon and any scale of the
//! map; results finite and in [0, 1] (or `GeomError::Undecidable` where the exact path's clip is
//! inconsistent), a singular map an error and never a panic.
//!
//! Run: `RUSTC_BOOTSTRAP=1 cargo fuzz run ltc_integral -- -max_total_time=60` (from the crate root).
#![no_main]

#[path = "sphere_common/mod.rs"]
mod common;

use arealight::glam::{DMat3, DVec3};
use arealight::ltc::{
    EDGE_FACTOR_RATIONAL_MAX_ERROR, clamped_cosine_integral, clamped_cosine_integral_clip_free,
    clamped_cosine_integral_rational, ltc_integral, ltc_integral_rational,
};
use arealight::sphere::SphericalPolygon;
use libfuzzer_sys::fuzz_target;
use std::f64::consts::PI;

/// The edges of `p`'s rings as pairs of endpoints.
fn edges(p: &SphericalPolygon) -> impl Iterator<Item = (DVec3, DVec3)> + '_ {
    p.rings()
        .flat_map(|r| (0..r.len()).map(move |i| (r[i], r[(i + 1) % r.len()])))
}

/// Length of the boundary of `p` (great-circle arcs), for the rational error bound.
fn perimeter(p: &SphericalPolygon) -> f64 {
    edges(p)
        .map(|(a, b)| a.cross(b).length().atan2(a.dot(b)))
        .sum()
}

/// Sensitivity of the integral to rounding in the vertices from edges close to half a circle: the
/// plane through nearly antipodal endpoints turns by `eps / sin(theta)` when they move by `eps`
/// (seen: 3.5e-12 between two exact computations with `sin(theta)` near 1e-4).
fn antipodal_condition(p: &SphericalPolygon) -> f64 {
    edges(p)
        .filter(|(a, b)| a.dot(*b) < 0.0)
        .map(|(a, b)| 1.0 / a.cross(b).length())
        .fold(1.0, f64::max)
}

fn check(what: &str, got: f64, want: f64, tol: f64, p: &SphericalPolygon, m: DMat3) {
    assert!(
        got.is_finite() && (0.0..=1.0).contains(&got),
        "{what}: {got} outside [0, 1]\nP = {p:?}\nM = {m:?}"
    );
    assert!(
        (got - want).abs() <= tol,
        "{what}: {got} vs exact {want}\nP = {p:?}\nM = {m:?}"
    );
}

fuzz_target!(|case: (common::Poly, [i8; 9], bool, i8)| {
    let (p, e, general, exponent) = case;
    let Some(p) = p.build() else { return };
    let exact = clamped_cosine_integral(&p);
    let bound = |q: &SphericalPolygon| {
        EDGE_FACTOR_RATIONAL_MAX_ERROR * perimeter(&q.clip_to_hemisphere(DVec3::Z)) / (2.0 * PI)
            + 1e-12
    };
    let id = DMat3::IDENTITY;
    // The unit-vector paths compute the same edge planes as the exact clip: no slack needed.
    check("clip-free", clamped_cosine_integral_clip_free(&p), exact, 1e-12, &p, id);
    check("rational", clamped_cosine_integral_rational(&p), exact, bound(&p), &p, id);

    // The tables' form (y passes unchanged) or any matrix, scaled by 2^exponent.
    let f = |i: usize| e[i] as f64 / 16.0;
    let m = if general {
        DMat3::from_cols_array(&core::array::from_fn(f))
    } else {
        DMat3::from_cols(
            DVec3::new(f(0), 0.0, f(1)),
            DVec3::Y,
            DVec3::new(f(2), 0.0, f(3)),
        )
    };
    // Scales up to 2^±889: the entries (at most 8 in magnitude) stay normal numbers.
    let scaled = m * 2f64.powi(exponent as i32 * 7);
    match p.transformed(m) {
        Ok(t) => {
            // Rounding in the images of the vertices grows with the map's condition; the exact
            // integral itself moves by that much with the scale (seen: 1.3e-12 at a ratio of 255).
            // Hadamard's ratio (product of column lengths over |det|, at least 1) measures it.
            let kappa = m.x_axis.length() * m.y_axis.length() * m.z_axis.length()
                / m.determinant().abs();
            let planes = antipodal_condition(&p).max(antipodal_condition(&t));
            let tol = 1e-12 * kappa.max(1.0) * planes;
            let want = clamped_cosine_integral(&t);
            // `Undecidable` (the exact path found its clip inconsistent) is an answer; any other
            // error on a regular map is a bug.
            let decided = |r: Result<f64, arealight::GeomError>| match r {
                Ok(v) => Some(v),
                Err(e) if e.is_undecidable() => None,
                Err(e) => panic!("{e}: {p:?} {scaled:?}"),
            };
            if let Some(got) = decided(ltc_integral(&p, scaled)) {
                check("ltc", got, want, tol, &p, scaled);
            }
            if let Some(got) = decided(ltc_integral_rational(&p, scaled)) {
                check("ltc rational", got, want, bound(&t) + tol, &p, scaled);
            }
        }
        Err(_) => {
            assert!(ltc_integral(&p, scaled).is_err(), "singular map accepted: {m:?}");
            assert!(ltc_integral_rational(&p, scaled).is_err(), "singular map accepted: {m:?}");
        }
    }
});
