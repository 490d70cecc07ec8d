//! Planar boolean operations, side by side with i_overlay, clipper2 and geo on identical inputs.
//!
//! Groups `planar/{difference,intersection}/{convex,star}`, each with the sizes 4, 8, 16 and 64
//! vertices per operand and one entry per implementation:
//!
//! - `arealight`: `boolean` on prebuilt `Shape`s (validation by `Shape::new` happens once per
//!   polygon, when it is projected, not per operation);
//! - `arealight+new`: the same including `Shape::new` for both operands, for a like-for-like view
//!   with the references, which take raw point lists;
//! - `i_overlay`: `overlay` with the default (i32 grid) float adapter, non-zero fill;
//! - `clipper2`: `difference`/`intersect` on `Paths<Centi>` built per call (the crate's API
//!   converts to its C++ core in every call);
//! - `geo`: `BooleanOps` on `Polygon<f64>` (backed by i_overlay).
//!
//! Groups `planar/resolve/{star,valid}` turn raw rings into shapes under the non-zero rule, for
//! 16 to 1024 vertices:
//!
//! - `star`: one self-intersecting star ring (`support::planar::self_intersecting_star`: every spike's edges cross
//!   the neighbouring spikes', about two crossings per vertex); `arealight` is
//!   `Shape::with_fill_rule`, `i_overlay` is `simplify_shape` (default i32 grid), `clipper2` is
//!   the union of the ring as the only subject (`Paths<Fine>`, 2^-30 grid, built per call);
//! - `valid`: the simple star of the boolean groups, which needs no resolving: `with_fill_rule`
//!   against `Shape::new` (the strict constructor) and the same references.
//!
//! Run: `cargo bench -p arealight-compare --bench planar`; results are summarized in BENCHMARKS.md.

use std::hint::black_box;
use std::time::Duration;

// The inputs are shared with the tests (the crate's tests/planar_fast.rs checks that they take the fast path).
#[path = "../../tests/support/mod.rs"]
mod support;

use arealight::glam::DVec2;
use arealight::planar::{BoolOp, FillRule as Rule, Shape, boolean};
use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use geo::BooleanOps;
use i_overlay::core::fill_rule::FillRule;
use i_overlay::core::overlay_rule::OverlayRule;
use i_overlay::float::simplify::SimplifyShape;
use i_overlay::float::single::SingleFloatOverlay;

fn bench(c: &mut Criterion) {
    for (op, op_name) in [
        (BoolOp::Difference, "difference"),
        (BoolOp::Intersection, "intersection"),
    ] {
        for star in [false, true] {
            let mut g = c.benchmark_group(format!(
                "planar/{op_name}/{}",
                if star { "star" } else { "convex" }
            ));
            g.sample_size(30)
                .warm_up_time(Duration::from_millis(300))
                .measurement_time(Duration::from_millis(1200));
            for n in [4usize, 8, 16, 64] {
                let pa = support::planar::bench_polygon(n, DVec2::ZERO, 0.0, star);
                let pb = support::planar::bench_polygon(n, DVec2::new(0.37, 0.21), 0.13, star);
                let sa = Shape::new(vec![pa.clone()]).unwrap();
                let sb = Shape::new(vec![pb.clone()]).unwrap();
                g.bench_with_input(BenchmarkId::new("arealight", n), &n, |bch, _| {
                    bch.iter(|| boolean(black_box(&sa), black_box(&sb), op).unwrap())
                });
                g.bench_with_input(BenchmarkId::new("arealight+new", n), &n, |bch, _| {
                    bch.iter(|| {
                        let a = Shape::new(vec![black_box(&pa).clone()]).unwrap();
                        let b = Shape::new(vec![black_box(&pb).clone()]).unwrap();
                        boolean(&a, &b, op).unwrap()
                    })
                });
                let ia: Vec<[f64; 2]> = pa.iter().map(|p| [p.x, p.y]).collect();
                let ib: Vec<[f64; 2]> = pb.iter().map(|p| [p.x, p.y]).collect();
                let rule = match op {
                    BoolOp::Difference => OverlayRule::Difference,
                    _ => OverlayRule::Intersect,
                };
                g.bench_with_input(BenchmarkId::new("i_overlay", n), &n, |bch, _| {
                    bch.iter(|| black_box(&ia).overlay(black_box(&ib), rule, FillRule::NonZero))
                });
                let ca: Vec<(f64, f64)> = pa.iter().map(|p| (p.x, p.y)).collect();
                let cb: Vec<(f64, f64)> = pb.iter().map(|p| (p.x, p.y)).collect();
                g.bench_with_input(BenchmarkId::new("clipper2", n), &n, |bch, _| {
                    bch.iter(|| {
                        let a: clipper2::Paths = vec![black_box(&ca).clone()].into();
                        let b: clipper2::Paths = vec![black_box(&cb).clone()].into();
                        match op {
                            BoolOp::Difference => {
                                clipper2::difference(a, b, clipper2::FillRule::NonZero)
                            }
                            _ => clipper2::intersect(a, b, clipper2::FillRule::NonZero),
                        }
                        .unwrap()
                    })
                });
                let ga = geo::Polygon::new(geo::LineString::from(ca.clone()), vec![]);
                let gb = geo::Polygon::new(geo::LineString::from(cb.clone()), vec![]);
                g.bench_with_input(BenchmarkId::new("geo", n), &n, |bch, _| {
                    bch.iter(|| match op {
                        BoolOp::Difference => black_box(&ga).difference(black_box(&gb)),
                        _ => black_box(&ga).intersection(black_box(&gb)),
                    })
                });
            }
            g.finish();
        }
    }
}

fn bench_resolve(c: &mut Criterion) {
    for star in [true, false] {
        let mut g = c.benchmark_group(format!(
            "planar/resolve/{}",
            if star { "star" } else { "valid" }
        ));
        g.sample_size(20)
            .warm_up_time(Duration::from_millis(300))
            .measurement_time(Duration::from_millis(1500));
        for n in [16usize, 64, 256, 1024] {
            let ring = if star {
                support::planar::self_intersecting_star(n)
            } else {
                support::planar::bench_polygon(n, DVec2::ZERO, 0.0, true)
            };
            g.bench_with_input(BenchmarkId::new("arealight", n), &n, |bch, _| {
                bch.iter(|| {
                    Shape::with_fill_rule(vec![black_box(&ring).clone()], Rule::NonZero).unwrap()
                })
            });
            if !star {
                g.bench_with_input(BenchmarkId::new("arealight-strict", n), &n, |bch, _| {
                    bch.iter(|| Shape::new(vec![black_box(&ring).clone()]).unwrap())
                });
            }
            let ir: Vec<[f64; 2]> = ring.iter().map(|p| [p.x, p.y]).collect();
            g.bench_with_input(BenchmarkId::new("i_overlay", n), &n, |bch, _| {
                bch.iter(|| black_box(&ir).simplify_shape(FillRule::NonZero))
            });
            let cr: Vec<(f64, f64)> = ring.iter().map(|p| (p.x, p.y)).collect();
            g.bench_with_input(BenchmarkId::new("clipper2", n), &n, |bch, _| {
                bch.iter(|| {
                    let subject: clipper2::Paths<arealight_compare::Fine> =
                        vec![black_box(&cr).clone()].into();
                    let none: clipper2::Paths<arealight_compare::Fine> =
                        Vec::<Vec<(f64, f64)>>::new().into();
                    clipper2::union(subject, none, clipper2::FillRule::NonZero).unwrap()
                })
            });
        }
        g.finish();
    }
}

criterion_group!(benches, bench, bench_resolve);
criterion_main!(benches);
