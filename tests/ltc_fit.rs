//! End-to-end check of the shipped table with the fitter's evaluation tools (feature `fit`):
//! LTC shading of random quad lights against brute-force integration of the real GGX BRDF.
#![cfg(feature = "fit")]

use arealight::ltc::LtcTable;
use arealight::ltc::fit::quad_shading_errors;

#[test]
fn quad_shading_meets_the_issue_goal() {
    let mut e = quad_shading_errors(LtcTable::ggx(), 200, 256, 99).unwrap();
    e.sort_by(f64::total_cmp);
    let median = e[e.len() / 2];
    let p90 = e[(e.len() - 1) * 9 / 10];
    println!("random quads, |LTC - brute force| / albedo: median {median:.5}, p90 {p90:.5}");
    // The issue's goal: median <= 0.2 %, p90 <= 1.5 %. The public reference tables (and our
    // reproduction of their fit, 0.28 % / 2.35 % on the fitter's 300 quads) fail the p90 bound.
    assert!(
        median <= 0.002 && p90 <= 0.015,
        "median {median}, p90 {p90}"
    );
}
