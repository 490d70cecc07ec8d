//! Fuzz the sphere layer in the sliver regime of issue 24 (see `sphere_common::Sliver`):
//! every result a valid input, and the invariants the structure of the input implies.
//!
//! Run: `RUSTC_BOOTSTRAP=1 cargo fuzz run sphere_sliver -- -max_total_time=300` (from the crate
//! root).
#![no_main]

#[path = "sphere_common/mod.rs"]
mod common;

use libfuzzer_sys::fuzz_target;

fuzz_target!(|case: common::Sliver| case.run());
