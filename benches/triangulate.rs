//! Spherical triangulation and sampling: `SphericalPolygon::triangulate` on 8/32/128-gons
//! (convex: the fan; star-shaped about their center but not their first vertex: the chart and
//! its constrained Delaunay triangulation), the same with a hole, and regions larger than a
//! hemisphere; triangle samples per second against a textbook implementation of Arvo's
//! algorithm written here (cosines of arcs, Girard's excess), in the same process. Fixed inputs;
//! results in BENCHMARKS.md.

use arealight::glam::{DVec2, DVec3};
use arealight::sphere::{PolygonSampler, SphericalPolygon, SphericalTriangle};
use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use std::f64::consts::PI;
use std::hint::black_box;

fn at(c: DVec3, rho: f64, t: f64) -> DVec3 {
    let (u, v) = c.any_orthonormal_pair();
    (c * rho.cos() + (u * t.cos() + v * t.sin()) * rho.sin()).normalize()
}

/// A convex `n`-gon of angular radius `rho` about `c`.
fn convex(c: DVec3, n: usize, rho: f64) -> Vec<DVec3> {
    (0..n)
        .map(|i| at(c, rho, 2.0 * PI * i as f64 / n as f64))
        .collect()
}

/// A star-shaped `n`-gon (radii alternating between `rho` and `0.4 rho`): not convex, and not
/// star-shaped about its first vertex, so it takes the chart.
fn star(c: DVec3, n: usize, rho: f64) -> Vec<DVec3> {
    (0..n)
        .map(|i| {
            let r = if i % 2 == 0 { rho } else { 0.4 * rho };
            at(c, r, 2.0 * PI * i as f64 / n as f64 + 0.01)
        })
        .collect()
}

fn triangulate(c: &mut Criterion) {
    let center = DVec3::new(0.3, 0.1, 0.9).normalize();
    let mut g = c.benchmark_group("triangulate");
    for n in [8usize, 32, 128] {
        let convex_p = SphericalPolygon::new(vec![convex(center, n, 0.6)]).unwrap();
        let star_p = SphericalPolygon::new(vec![star(center, n, 0.6)]).unwrap();
        let mut hole = convex(center, 6, 0.12);
        hole.reverse();
        let holed = SphericalPolygon::new(vec![star(center, n, 0.6), hole]).unwrap();
        g.bench_with_input(BenchmarkId::new("convex (fan)", n), &convex_p, |b, p| {
            b.iter(|| black_box(p).triangulate().unwrap())
        });
        g.bench_with_input(BenchmarkId::new("star (chart, CDT)", n), &star_p, |b, p| {
            b.iter(|| black_box(p).triangulate().unwrap())
        });
        g.bench_with_input(BenchmarkId::new("star with a hole", n), &holed, |b, p| {
            b.iter(|| black_box(p).triangulate().unwrap())
        });
        let complement = star_p.complement();
        g.bench_with_input(
            BenchmarkId::new("complement of the star (> hemisphere)", n),
            &complement,
            |b, p| b.iter(|| black_box(p).triangulate().unwrap()),
        );
    }
    // A band around the equator: no open hemisphere holds it (the stereographic chart).
    let ring = |z: f64| -> Vec<DVec3> {
        (0..16)
            .map(|i| {
                let t = 2.0 * PI * i as f64 / 16.0;
                DVec3::new(t.cos(), t.sin(), z).normalize()
            })
            .collect()
    };
    let mut top = ring(0.2);
    top.reverse();
    let band = SphericalPolygon::new(vec![ring(-0.2), top]).unwrap();
    g.bench_function("band of 2 x 16 (stereographic)", |b| {
        b.iter(|| black_box(&band).triangulate().unwrap())
    });
    g.finish();
}

/// Arvo's algorithm as published (SIGGRAPH 1995, figure 2): the angle at A from the spherical
/// law of cosines, the area by Girard, `cos(b')` for the point `C'`, and `z = 1 - u2 (1 - C'.B)`.
#[derive(Clone, Copy)]
struct TextbookArvo {
    a: DVec3,
    b: DVec3,
    c: DVec3,
    area: f64,
    alpha: f64,
    cos_c: f64,
}

impl TextbookArvo {
    fn new(a: DVec3, b: DVec3, c: DVec3) -> Self {
        let angle = |p: DVec3, q: DVec3, r: DVec3| {
            let (nq, nr) = (p.cross(q).normalize(), p.cross(r).normalize());
            nq.dot(nr).clamp(-1.0, 1.0).acos()
        };
        let (alpha, beta, gamma) = (angle(a, b, c), angle(b, c, a), angle(c, a, b));
        TextbookArvo {
            a,
            b,
            c,
            area: alpha + beta + gamma - PI,
            alpha,
            cos_c: a.dot(b),
        }
    }

    fn sample(&self, u: DVec2) -> DVec3 {
        let a_hat = u.x * self.area;
        let (s, t) = (a_hat - self.alpha).sin_cos();
        let uu = t - self.alpha.cos();
        let vv = s + self.alpha.sin() * self.cos_c;
        let q =
            ((vv * t - uu * s) * self.alpha.cos() - vv) / ((vv * s + uu * t) * self.alpha.sin());
        let ortho = |x: DVec3, y: DVec3| (x - y * x.dot(y)).normalize();
        let c_hat = self.a * q + ortho(self.c, self.a) * (1.0 - q * q).max(0.0).sqrt();
        let z = 1.0 - u.y * (1.0 - c_hat.dot(self.b));
        self.b * z + ortho(c_hat, self.b) * (1.0 - z * z).max(0.0).sqrt()
    }
}

fn sampling(c: &mut Criterion) {
    let (a, b, tc) = (
        DVec3::new(1.0, 0.1, 0.2).normalize(),
        DVec3::new(0.1, 1.0, 0.3).normalize(),
        DVec3::new(0.2, 0.3, 1.0).normalize(),
    );
    let ours = SphericalTriangle::new(a, b, tc).unwrap();
    let text = TextbookArvo::new(a, b, tc);
    // 1024 stratified points of the unit square per iteration.
    let us: Vec<DVec2> = (0..1024)
        .map(|i| {
            DVec2::new(
                ((i % 32) as f64 + 0.5) / 32.0,
                ((i / 32) as f64 + 0.37) / 32.0,
            )
        })
        .collect();
    let mut g = c.benchmark_group("sample");
    g.throughput(Throughput::Elements(us.len() as u64));
    g.bench_function("SphericalTriangle::sample", |bch| {
        bch.iter(|| {
            let mut acc = DVec3::ZERO;
            for &u in black_box(&us) {
                acc += ours.sample(u);
            }
            acc
        })
    });
    g.bench_function("textbook Arvo", |bch| {
        bch.iter(|| {
            let mut acc = DVec3::ZERO;
            for &u in black_box(&us) {
                acc += text.sample(u);
            }
            acc
        })
    });
    g.bench_function("SphericalTriangle::inverse", |bch| {
        let pts: Vec<DVec3> = us.iter().map(|&u| ours.sample(u)).collect();
        bch.iter(|| {
            let mut acc = DVec2::ZERO;
            for &p in black_box(&pts) {
                acc += ours.inverse(p).unwrap();
            }
            acc
        })
    });
    let poly =
        SphericalPolygon::new(vec![star(DVec3::new(0.3, 0.1, 0.9).normalize(), 32, 0.6)]).unwrap();
    let sampler = PolygonSampler::new(&poly).unwrap();
    g.bench_function("PolygonSampler::sample, 32-gon (30 triangles)", |bch| {
        bch.iter(|| {
            let mut acc = DVec3::ZERO;
            for &u in black_box(&us) {
                acc += sampler.sample(u);
            }
            acc
        })
    });
    g.finish();
}

criterion_group!(benches, triangulate, sampling);
criterion_main!(benches);
