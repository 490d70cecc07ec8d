//! Driver for instruction counts of the planar benchmark (BENCHMARKS.md `## planar`): runs one
//! implementation on one benchmark input `iters` times, so that
//! `(callgrind count at 1001 iterations - count at 1) / 1000` is the cost of one call.
//!
//! Usage: `cargo run --release -p arealight-compare --example planar_count -- IMPL OP SHAPE N ITERS` with IMPL one of
//! `arealight`, `clipper2`, `i_overlay`; OP `difference` or `intersection`; SHAPE `convex` or
//! `star`. Inputs are those of `benches/planar.rs`.

// The inputs are shared with the tests (the crate's tests/planar_fast.rs checks that they take the fast path).
#[path = "../../tests/support/mod.rs"]
mod support;

use std::hint::black_box;

use arealight::glam::DVec2;
use arealight::planar::{BoolOp, Shape, boolean};
use i_overlay::core::fill_rule::FillRule;
use i_overlay::core::overlay_rule::OverlayRule;
use i_overlay::float::single::SingleFloatOverlay;

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if args.len() != 5 {
        eprintln!("usage: planar_count IMPL OP SHAPE N ITERS");
        std::process::exit(2);
    }
    let op = match args[1].as_str() {
        "difference" => BoolOp::Difference,
        "intersection" => BoolOp::Intersection,
        o => panic!("unknown op {o}"),
    };
    let star = args[2] == "star";
    let n: usize = args[3].parse().expect("N");
    let iters: usize = args[4].parse().expect("ITERS");
    let pa = support::planar::bench_polygon(n, DVec2::ZERO, 0.0, star);
    let pb = support::planar::bench_polygon(n, DVec2::new(0.37, 0.21), 0.13, star);
    match args[0].as_str() {
        "arealight" => {
            let sa = Shape::new(vec![pa]).unwrap();
            let sb = Shape::new(vec![pb]).unwrap();
            for _ in 0..iters {
                black_box(boolean(black_box(&sa), black_box(&sb), op).unwrap());
            }
        }
        "clipper2" => {
            let ca: Vec<(f64, f64)> = pa.iter().map(|p| (p.x, p.y)).collect();
            let cb: Vec<(f64, f64)> = pb.iter().map(|p| (p.x, p.y)).collect();
            for _ in 0..iters {
                let a: clipper2::Paths = vec![black_box(&ca).clone()].into();
                let b: clipper2::Paths = vec![black_box(&cb).clone()].into();
                black_box(
                    match op {
                        BoolOp::Difference => {
                            clipper2::difference(a, b, clipper2::FillRule::NonZero)
                        }
                        _ => clipper2::intersect(a, b, clipper2::FillRule::NonZero),
                    }
                    .unwrap(),
                );
            }
        }
        "i_overlay" => {
            let ia: Vec<[f64; 2]> = pa.iter().map(|p| [p.x, p.y]).collect();
            let ib: Vec<[f64; 2]> = pb.iter().map(|p| [p.x, p.y]).collect();
            let rule = match op {
                BoolOp::Difference => OverlayRule::Difference,
                _ => OverlayRule::Intersect,
            };
            for _ in 0..iters {
                black_box(black_box(&ia).overlay(black_box(&ib), rule, FillRule::NonZero));
            }
        }
        i => panic!("unknown implementation {i}"),
    }
}
