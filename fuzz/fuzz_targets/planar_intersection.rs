//! Fuzz `boolean(a, b, BoolOp::Intersection)`: the result must be valid and the area identities must hold.
//!
//! Run: `RUSTC_BOOTSTRAP=1 cargo fuzz run planar_intersection -- -max_total_time=60` (from the crate root).
#![no_main]

#[path = "common/mod.rs"]
mod common;

use arealight::planar::BoolOp;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|case: common::Case| common::run(&case, BoolOp::Intersection));
