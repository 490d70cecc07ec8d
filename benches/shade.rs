//! Shading-point benchmarks: one shading point in a penumbra with 1 light and 0, 1, 3 occluders,
//! the silhouette path against the per-triangle path for a subdivided-icosahedron light, and the
//! face-by-face path of occluders that interpenetrate a light. Fixed inputs; results in
//! BENCHMARKS.md (section `shade`).

use arealight::glam::DVec3;
use arealight::internals::{DemoConfig, demo_scene};
use arealight::shade::{Body, ConvexPolyhedron, Light, Material, Method, Scene, TriangleMesh};
use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use std::hint::black_box;

fn occluders(c: &mut Criterion) {
    let demo = demo_scene(DemoConfig::default()).unwrap();
    // The truncated-cone light alone, with the first k occluders (cube, icosphere, ellipsoid).
    let cone = demo.scene.lights()[2].clone();
    // A ground point in the penumbra of the icosphere under the cone light.
    let (x, n, v) = (
        DVec3::new(1.4, -0.25, 0.0),
        DVec3::Z,
        DVec3::new(0.2, -0.7, 0.7),
    );
    let m = demo.ground;
    // Check once that the point is in a penumbra: the icosphere hides part of the light.
    let lit = Scene::new(vec![cone.clone()], vec![])
        .unwrap()
        .shade(x, n, v, &m)
        .unwrap();
    let ico = vec![demo.scene.occluders()[1].clone()];
    let half = Scene::new(vec![cone.clone()], ico)
        .unwrap()
        .shade(x, n, v, &m)
        .unwrap();
    assert!(
        half.y > 0.05 * lit.y && half.y < 0.95 * lit.y,
        "not a penumbra: {half} of {lit}"
    );
    let mut group = c.benchmark_group("shade/one point, 1 light");
    for k in [0usize, 1, 3] {
        let occ = match k {
            1 => vec![demo.scene.occluders()[1].clone()],
            _ => demo.scene.occluders()[..k].to_vec(),
        };
        let scene = Scene::new(vec![cone.clone()], occ).unwrap();
        group.bench_with_input(BenchmarkId::new("occluders", k), &scene, |b, s| {
            b.iter(|| s.shade(black_box(x), n, v, &m).unwrap())
        });
    }
    group.finish();
}

fn silhouette_vs_per_triangle(c: &mut Criterion) {
    // An icosahedron subdivided twice (162 vertices, 320 triangles) as a light, 3 above a
    // diffuse + GGX floor, no occluders.
    let ico = ConvexPolyhedron::icosphere(DVec3::new(0.2, 0.1, 3.0), 1.0, 2).unwrap();
    let scene = Scene::new(vec![Light::new(ico, DVec3::ONE).unwrap()], vec![]).unwrap();
    let per_tri = scene.clone().with_method(Method::PerTriangle);
    let m = Material::new(DVec3::splat(0.5), DVec3::splat(0.04), 0.4).unwrap();
    let (x, n, v) = (
        DVec3::new(0.5, -0.3, 0.0),
        DVec3::Z,
        DVec3::new(0.3, 0.0, 1.0),
    );
    let mut group = c.benchmark_group("shade/icosphere light (162 vertices)");
    group.bench_function("silhouette", |b| {
        b.iter(|| scene.shade(black_box(x), n, v, &m).unwrap())
    });
    group.bench_function("per-triangle", |b| {
        b.iter(|| per_tri.shade(black_box(x), n, v, &m).unwrap())
    });
    group.finish();
}

fn interpenetrating(c: &mut Criterion) {
    // Occluders through lights, so the light goes face by face: a box through a quad light's
    // plane, and a rod through a once-subdivided icosphere light (80 triangles), each from a
    // ground point whose view of the light the occluder partly hides.
    let m = Material::new(DVec3::splat(0.5), DVec3::splat(0.04), 0.4).unwrap();
    let (n, v) = (DVec3::Z, DVec3::new(0.3, 0.0, 1.0));
    let quad =
        TriangleMesh::quad(DVec3::new(0.0, 0.0, 2.5), DVec3::Y * 0.6, DVec3::X * 0.6).unwrap();
    let straddling =
        ConvexPolyhedron::cuboid(DVec3::new(0.45, 0.1, 2.5), DVec3::new(0.3, 0.25, 0.4)).unwrap();
    let ico = ConvexPolyhedron::icosphere(DVec3::new(0.0, 0.0, 2.5), 0.6, 1).unwrap();
    let rod =
        ConvexPolyhedron::cuboid(DVec3::new(0.2, 0.05, 2.5), DVec3::new(0.12, 0.12, 1.0)).unwrap();
    let cases: [(&str, Body, Body, DVec3); 2] = [
        (
            "quad light, straddling box",
            quad.into(),
            straddling.into(),
            DVec3::new(-0.6, 0.2, 0.0),
        ),
        (
            "icosphere light, piercing rod",
            ico.into(),
            rod.into(),
            DVec3::new(0.7, -0.3, 0.0),
        ),
    ];
    let mut group = c.benchmark_group("shade/interpenetrating occluder (face by face)");
    for (name, light, occ, x) in cases {
        let lit = Scene::new(vec![Light::new(light.clone(), DVec3::ONE).unwrap()], vec![]).unwrap();
        let scene = Scene::new(vec![Light::new(light, DVec3::ONE).unwrap()], vec![occ]).unwrap();
        let (full, part) = (
            lit.shade(x, n, v, &m).unwrap(),
            scene.shade(x, n, v, &m).unwrap(),
        );
        assert!(
            part.y > 0.05 * full.y && part.y < 0.95 * full.y,
            "{name}: not a penumbra"
        );
        group.bench_function(name, |b| {
            b.iter(|| scene.shade(black_box(x), n, v, &m).unwrap())
        });
    }
    group.finish();
}

criterion_group!(
    benches,
    occluders,
    silhouette_vs_per_triangle,
    interpenetrating
);
criterion_main!(benches);
