//! Fuzz `SphericalPolygon::boolean`: valid outputs and the solid-angle identities
//! `|A-B| + |AnB| = |A|`, `|AuB| = |A| + |B| - |AnB|`, `|A^B| = |AuB| - |AnB|`.
//!
//! Run: `RUSTC_BOOTSTRAP=1 cargo fuzz run sphere_boolean -- -max_total_time=60` (from the crate
//! root).
#![no_main]

#[path = "sphere_common/mod.rs"]
mod common;

use libfuzzer_sys::fuzz_target;

fuzz_target!(|case: (common::Poly, common::Poly)| {
    if let (Some(a), Some(b)) = (case.0.build(), case.1.build()) {
        common::boolean(&a, &b);
    }
});
