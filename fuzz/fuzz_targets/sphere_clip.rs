//! Fuzz `SphericalPolygon::clip_to_hemisphere`: valid output, `clip(n) + clip(-n) = P` in solid
//! angle, idempotence.
//!
//! Run: `RUSTC_BOOTSTRAP=1 cargo fuzz run sphere_clip -- -max_total_time=60` (from the crate root).
#![no_main]

#[path = "sphere_common/mod.rs"]
mod common;

use arealight::glam::DVec3;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|case: (common::Poly, (i8, i8, i8))| {
    let (p, (x, y, z)) = case;
    let n = DVec3::new(x as f64, y as f64, z as f64);
    if let Some(p) = p.build()
        && n != DVec3::ZERO
    {
        common::clip(&p, n);
    }
});
