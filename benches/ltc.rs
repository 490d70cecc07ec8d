//! LTC table lookup, GGX evaluation and LTC density: the per-shading-point costs.

use std::hint::black_box;

use arealight::glam::{DVec2, DVec3};
use arealight::ltc::{Ltc, ggx_brdf_cos, ggx_sample_vndf, lookup};
use criterion::{Criterion, criterion_group, criterion_main};

/// Fixed pseudo-random inputs (LCG), so that runs compare.
fn inputs(n: usize) -> Vec<(f64, f64, DVec3)> {
    let mut s = 0x2545_f491_4f6c_dd1du64;
    let mut next = || {
        s = s
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (s >> 11) as f64 / (1u64 << 53) as f64
    };
    (0..n)
        .map(|_| {
            let c = next();
            let a = 0.01 + next();
            let z = next();
            let phi = std::f64::consts::TAU * next();
            let r = (1.0 - z * z).sqrt();
            (c, a, DVec3::new(r * phi.cos(), r * phi.sin(), z))
        })
        .collect()
}

fn bench(c: &mut Criterion) {
    let data = inputs(1024);
    c.bench_function("ltc/lookup x1024", |b| {
        b.iter(|| {
            let mut acc = 0.0;
            for &(cos, alpha, _) in &data {
                acc += lookup(black_box(cos), black_box(alpha)).map_or(0.0, |l| l.norm);
            }
            acc
        })
    });
    c.bench_function("ltc/ggx_brdf_cos x1024", |b| {
        let v = DVec3::new(0.6, 0.0, 0.8);
        b.iter(|| {
            let mut acc = 0.0;
            for &(_, alpha, l) in &data {
                acc += ggx_brdf_cos(black_box(v), black_box(l), alpha);
            }
            acc
        })
    });
    c.bench_function("ltc/ggx_sample_vndf x1024", |b| {
        let v = DVec3::new(0.6, 0.0, 0.8);
        b.iter(|| {
            let mut acc = DVec3::ZERO;
            for &(u1, alpha, l) in &data {
                acc += ggx_sample_vndf(black_box(v), alpha, DVec2::new(u1, l.z));
            }
            acc
        })
    });
    if let Ok(ltc) = lookup(0.7, 0.2).and_then(|l| l.ltc()) {
        let ltc: Ltc = ltc;
        c.bench_function("ltc/density x1024", |b| {
            b.iter(|| {
                let mut acc = 0.0;
                for &(_, _, w) in &data {
                    acc += ltc.density(black_box(w));
                }
                acc
            })
        });
    }
}

criterion_group!(benches, bench);
criterion_main!(benches);
