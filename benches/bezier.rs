//! Adaptive against uniform subdivision of a curved light (seed 004 section 3.3, figure 8).
//!
//! The light of the seed's figure 8: two cubics and one line segment (a "D", 1.6 x 2), 1.5
//! above a glossy floor, facing down; 48 floor points in `[-2, 2]^2` seen from a camera at
//! `(0, -4, 2.5)`; the specular lobe only (GGX, `f0 = 1`), as the seed's timings. For each
//! roughness, uniform subdivision with `N = 6, 18, 30` chords per cubic sets a maximum error over
//! the points (against `eps = 1e-12`); the adaptive threshold is then lowered by factors of 2
//! from `1e-2` until its maximum error is no larger, and both are timed on the same points
//! (adaptive also with its proven error bound, `Subdivision::AdaptiveWithBound`). Where no
//! threshold matches (adaptive's coarsest is already more accurate than N = 6), the smallest
//! uniform N that reaches adaptive's coarsest error is found and timed against it.
//! The matching table (errors and edges) is printed once; results in BENCHMARKS.md (section
//! `Bezier lights`). Run with `cargo bench -p arealight-benches --bench bezier`.

use arealight::glam::{DVec2, DVec3};
use arealight::ltc::{CurveSegment, Subdivision, ggx_curved_integral, specular_eps};
use arealight::solid::ShadingFrame;
use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use std::hint::black_box;
use std::time::Duration;

/// The D in world space: plane z = 1.5, facing down (counter-clockwise about -z).
fn light() -> Vec<[DVec3; 4]> {
    let p = |x: f64, y: f64| DVec3::new(x, y, 1.5);
    // Counter-clockwise seen from below is clockwise seen from above: y mirrored.
    let q = |v: DVec2| p(v.x * 0.8, -v.y);
    let d = DVec2::new;
    let a = q(d(-1.0, 1.0));
    let b = q(d(-1.0, -1.0));
    let c = q(d(1.0, 0.0));
    vec![
        [a, a, b, b], // the line (kept as a line below)
        [b, q(d(0.2, -1.0)), q(d(1.0, -0.8)), c],
        [c, q(d(1.0, 0.8)), q(d(0.2, 1.0)), a],
    ]
}

/// The light's segments in a point's frame, oriented for the `ltc` layer (reversed: the light
/// faces the point).
fn local(frame: &ShadingFrame) -> Vec<CurveSegment> {
    let l = light();
    let mut out: Vec<CurveSegment> = l
        .iter()
        .enumerate()
        .map(|(i, c)| {
            let m = c.map(|v| frame.to_local(v));
            if i == 0 {
                CurveSegment::Line([m[0], m[3]])
            } else {
                CurveSegment::Cubic(m)
            }
        })
        .collect();
    out.reverse();
    out.iter().map(CurveSegment::reversed).collect()
}

/// 48 floor points, their segments and view cosines.
fn points() -> Vec<(Vec<CurveSegment>, f64)> {
    let mut s = 0x0b_e71e_u64;
    let mut next = || {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        (s >> 11) as f64 / (1u64 << 53) as f64
    };
    let eye = DVec3::new(0.0, -4.0, 2.5);
    (0..48)
        .map(|_| {
            let x = DVec3::new(4.0 * next() - 2.0, 4.0 * next() - 2.0, 0.0);
            let frame = ShadingFrame::new(x, DVec3::Z, eye - x).unwrap();
            (local(&frame), frame.view().z)
        })
        .collect()
}

fn shade(pts: &[(Vec<CurveSegment>, f64)], alpha: f64, sub: Subdivision) -> (Vec<f64>, usize) {
    let mut edges = 0;
    let v = pts
        .iter()
        .map(|(segs, cos_v)| {
            let r = ggx_curved_integral(segs, *cos_v, alpha, 1.0, sub).unwrap();
            edges += r.edges;
            r.value
        })
        .collect();
    (v, edges)
}

fn max_error(a: &[f64], b: &[f64]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64::max)
}

/// The smallest time of one pass over the points for each subdivision, over `rounds` rounds
/// that run every subdivision once, interleaved (on a loaded machine the minimum is the
/// least disturbed measure, and interleaving shares the disturbances).
fn min_times(
    pts: &[(Vec<CurveSegment>, f64)],
    alpha: f64,
    subs: &[Subdivision],
    rounds: usize,
) -> Vec<f64> {
    let mut best = vec![f64::INFINITY; subs.len()];
    for _ in 0..rounds {
        for (k, &sub) in subs.iter().enumerate() {
            let t = std::time::Instant::now();
            black_box(shade(pts, alpha, sub));
            best[k] = best[k].min(t.elapsed().as_secs_f64());
        }
    }
    best
}

fn bench(c: &mut Criterion) {
    let pts = points();
    let mut g = c.benchmark_group("bezier");
    g.measurement_time(Duration::from_secs(3));
    g.warm_up_time(Duration::from_secs(1));
    for alpha in [0.1, 0.25] {
        let (reference, _) = shade(&pts, alpha, Subdivision::Adaptive { eps: 1e-12 });
        let (paper, paper_edges) = shade(
            &pts,
            alpha,
            Subdivision::Adaptive {
                eps: specular_eps(alpha),
            },
        );
        println!(
            "alpha {alpha}: adaptive at eps_s = 0.1 alpha^2 = {:.1e}: max error {:.2e}, {:.1} edges per point",
            specular_eps(alpha),
            max_error(&paper, &reference),
            paper_edges as f64 / pts.len() as f64
        );
        for n in [6, 18, 30] {
            let uniform = Subdivision::Uniform { n };
            let (u, u_edges) = shade(&pts, alpha, uniform);
            let target = max_error(&u, &reference);
            let mut eps = 1e-2;
            let (mut a, mut a_edges) = shade(&pts, alpha, Subdivision::Adaptive { eps });
            while max_error(&a, &reference) > target && eps > 1e-12 {
                eps *= 0.5;
                (a, a_edges) = shade(&pts, alpha, Subdivision::Adaptive { eps });
            }
            println!(
                "alpha {alpha}: uniform N = {n}: max error {target:.2e}, {:.1} edges per point; \
                 adaptive eps {eps:.2e}: max error {:.2e}, {:.1} edges per point",
                u_edges as f64 / pts.len() as f64,
                max_error(&a, &reference),
                a_edges as f64 / pts.len() as f64
            );
            let adaptive = Subdivision::Adaptive { eps };
            let bounded = Subdivision::AdaptiveWithBound { eps };
            let t = min_times(&pts, alpha, &[uniform, adaptive, bounded], 300);
            println!(
                "alpha {alpha}: N = {n}: minimum of 300 interleaved passes over the 48 points: \
                 uniform {:.1} us, adaptive {:.1} us (ratio {:.2}), adaptive with its error \
                 bound {:.1} us",
                t[0] * 1e6,
                t[1] * 1e6,
                t[0] / t[1],
                t[2] * 1e6
            );
            let id = format!("alpha{alpha}/N{n}");
            g.bench_with_input(BenchmarkId::new("uniform", &id), &uniform, |b, &s| {
                b.iter(|| black_box(shade(&pts, alpha, s)))
            });
            g.bench_with_input(BenchmarkId::new("adaptive", &id), &adaptive, |b, &s| {
                b.iter(|| black_box(shade(&pts, alpha, s)))
            });
        }
        // Equal error from the other side, for the row where no threshold matches (N = 6):
        // adaptive cannot be made coarser than `N_div = 4` intervals per cubic, each accepted
        // with its midpoint (8 chords), so its coarsest threshold is already more accurate than
        // N = 6; the uniform N that reaches that error is timed against it.
        let coarsest = Subdivision::Adaptive { eps: 1e-2 };
        let (a, a_edges) = shade(&pts, alpha, coarsest);
        let target = max_error(&a, &reference);
        let mut n = 1;
        let (mut u, mut u_edges) = shade(&pts, alpha, Subdivision::Uniform { n });
        while max_error(&u, &reference) > target && n < 1000 {
            n += 1;
            (u, u_edges) = shade(&pts, alpha, Subdivision::Uniform { n });
        }
        let uniform = Subdivision::Uniform { n };
        let t = min_times(&pts, alpha, &[uniform, coarsest], 300);
        println!(
            "alpha {alpha}: adaptive at its coarsest (eps 1e-2): max error {target:.2e}, {:.1} \
             edges per point, {:.1} us; the smallest uniform N reaching it: N = {n}, max error \
             {:.2e}, {:.1} edges per point, {:.1} us (uniform / adaptive time {:.2})",
            a_edges as f64 / pts.len() as f64,
            t[1] * 1e6,
            max_error(&u, &reference),
            u_edges as f64 / pts.len() as f64,
            t[0] * 1e6,
            t[0] / t[1]
        );
    }
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
