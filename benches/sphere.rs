//! Spherical primitives: solid angle of an 8-gon, hemisphere clip of an 8-gon, ordering of 12
//! silhouette edges. Fixed inputs; results in BENCHMARKS.md.

#[path = "../tests/support/mod.rs"]
mod support;

use arealight::glam::DVec3;
use arealight::internals::convex_silhouette;
use arealight::planar::BoolOp;
use arealight::solid::{ConvexPolyhedron, ShadingFrame};
use arealight::sphere::{SphericalPolygon, order_edges};
use criterion::{Criterion, criterion_group, criterion_main};
use std::f64::consts::PI;
use std::hint::black_box;

fn ngon(c: DVec3, rho: f64, n: usize) -> Vec<DVec3> {
    let (u, v) = c.any_orthonormal_pair();
    (0..n)
        .map(|i| {
            let t = 2.0 * PI * i as f64 / n as f64 + 0.1 * (i as f64).sin();
            (c * rho.cos() + (u * t.cos() + v * t.sin()) * rho.sin()).normalize()
        })
        .collect()
}

fn primitives(c: &mut Criterion) {
    let c8 = DVec3::new(0.3, 0.1, 0.4).normalize();
    let octagon = SphericalPolygon::new(vec![ngon(c8, 0.9, 8)]).unwrap();
    c.bench_function("sphere/solid_angle/8-gon", |b| {
        b.iter(|| black_box(&octagon).solid_angle())
    });
    // The horizon crosses the octagon: 2 crossings, 1 arc of the circle.
    c.bench_function("sphere/clip/8-gon crossing", |b| {
        b.iter(|| black_box(&octagon).clip_to_hemisphere(black_box(DVec3::Z)))
    });
    c.bench_function("sphere/clip/8-gon inside", |b| {
        b.iter(|| black_box(&octagon).clip_to_hemisphere(black_box(c8)))
    });
    let ring = ngon(DVec3::new(-0.2, 0.5, 0.6).normalize(), 0.4, 12);
    let mut edges: Vec<(DVec3, DVec3)> = (0..12).map(|i| (ring[i], ring[(i + 1) % 12])).collect();
    // A fixed scramble of order and direction, as silhouette extraction delivers them.
    for i in 0..12 {
        edges.swap(i, (i * 7 + 3) % 12);
        if i % 3 == 0 {
            edges[i] = (edges[i].1, edges[i].0);
        }
    }
    c.bench_function("sphere/order_edges/12 edges", |b| {
        b.iter(|| order_edges(black_box(&edges)).unwrap())
    });
    c.bench_function("sphere/new/8-gon (validation)", |b| {
        let r = ngon(c8, 0.9, 8);
        b.iter(|| SphericalPolygon::new(vec![black_box(&r).clone()]).unwrap())
    });
}

/// Visible part of a quad light: minus a cube's silhouette (one difference), and minus every
/// triangle of an 80-face icosphere (the seed's per-triangle workflow, 80 chained differences).
fn visibility(c: &mut Criterion) {
    let light = SphericalPolygon::new(vec![vec![
        DVec3::new(-1.0, -1.0, 3.0),
        DVec3::new(1.0, -1.0, 3.0),
        DVec3::new(1.0, 1.0, 3.0),
        DVec3::new(-1.0, 1.0, 3.0),
    ]])
    .unwrap();
    // A cube of half-size 0.3 at (0.2, 0.1, 1.5) seen from the origin: its silhouette hexagon.
    // The frame (normal +z, view +x) is the identity, so the silhouette is in world directions.
    let cube = ConvexPolyhedron::cuboid(DVec3::new(0.2, 0.1, 1.5), DVec3::splat(0.3)).unwrap();
    let frame = ShadingFrame::new(DVec3::ZERO, DVec3::Z, DVec3::X).unwrap();
    let sil = convex_silhouette(&cube, &frame).unwrap();
    c.bench_function("sphere/boolean/quad light - cube silhouette", |b| {
        b.iter(|| {
            black_box(&light)
                .boolean(black_box(&sil), BoolOp::Difference)
                .unwrap()
        })
    });
    let (v, faces) = support::sphere::icosphere(DVec3::new(0.3, 0.2, 1.5), 0.4);
    let tris: Vec<SphericalPolygon> = faces
        .iter()
        .map(|f| {
            let t = SphericalPolygon::new(vec![f.iter().map(|&i| v[i]).collect()]).unwrap();
            if t.solid_angle() > 2.0 * PI {
                t.complement()
            } else {
                t
            }
        })
        .collect();
    c.bench_function("sphere/boolean/quad light - 80 icosphere triangles", |b| {
        b.iter(|| {
            let mut vis = light.clone();
            for t in &tris {
                vis = vis.boolean(t, BoolOp::Difference).unwrap();
            }
            vis
        })
    });
}

criterion_group!(benches, primitives, visibility);
criterion_main!(benches);
