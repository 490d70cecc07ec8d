//! One quad light shaded with GGX through the LTC tables: lookup + transform + horizon handling +
//! integral, for the exact-clip path, the clip-free path and the rational edge factor.

use arealight::glam::DVec3;
use arealight::ltc::{clamped_cosine_integral, lookup, ltc_integral, ltc_integral_rational};
use arealight::sphere::SphericalPolygon;
use criterion::{Criterion, criterion_group, criterion_main};
use std::hint::black_box;

fn quad(z0: f64, z1: f64) -> SphericalPolygon {
    SphericalPolygon::new(vec![vec![
        DVec3::new(1.0, -0.4, z0),
        DVec3::new(1.0, 0.4, z0),
        DVec3::new(0.6, 0.4, z1),
        DVec3::new(0.6, -0.4, z1),
    ]])
    .unwrap()
}

fn shading(c: &mut Criterion) {
    let (cos_v, alpha) = (0.8, 0.3);
    c.bench_function("ltc/lookup", |b| {
        b.iter(|| lookup(black_box(cos_v), black_box(alpha)).unwrap())
    });
    for (name, q) in [("above", quad(0.3, 0.9)), ("crossing", quad(-0.3, 0.7))] {
        c.bench_function(&format!("ltc/quad {name}/exact clip"), |b| {
            b.iter(|| {
                let l = lookup(black_box(cos_v), black_box(alpha)).unwrap();
                l.norm * clamped_cosine_integral(&black_box(&q).transformed(l.m_inv).unwrap())
            })
        });
        c.bench_function(&format!("ltc/quad {name}/clip-free"), |b| {
            b.iter(|| {
                let l = lookup(black_box(cos_v), black_box(alpha)).unwrap();
                l.norm * ltc_integral(black_box(&q), l.m_inv).unwrap()
            })
        });
        c.bench_function(&format!("ltc/quad {name}/clip-free rational"), |b| {
            b.iter(|| {
                let l = lookup(black_box(cos_v), black_box(alpha)).unwrap();
                l.norm * ltc_integral_rational(black_box(&q), l.m_inv).unwrap()
            })
        });
        // The same behind a function pointer, which nothing can inline: a renderer's shading
        // function that calls the integral out of line (the case the `inline(always)` on the
        // integral's parts is for).
        let shade: fn(&SphericalPolygon, f64, f64) -> f64 = |q, cos_v, alpha| {
            let l = lookup(cos_v, alpha).unwrap();
            l.norm * ltc_integral_rational(q, l.m_inv).unwrap()
        };
        c.bench_function(
            &format!("ltc/quad {name}/clip-free rational via fn pointer"),
            |b| b.iter(|| black_box(shade)(black_box(&q), black_box(cos_v), black_box(alpha))),
        );
        // The integral alone, for a lookup made once: what a renderer pays per extra light at the
        // same shading point.
        let l = lookup(cos_v, alpha).unwrap();
        c.bench_function(&format!("ltc/quad {name}/integral only rational"), |b| {
            b.iter(|| ltc_integral_rational(black_box(&q), black_box(l.m_inv)).unwrap())
        });
    }
}

criterion_group!(benches, shading);
criterion_main!(benches);
