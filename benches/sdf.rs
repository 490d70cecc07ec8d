//! Time per shading point of the SDF soft shadows (Quilez, improved Quilez, seed 001's fast
//! shadow and proxy integration) and of the exact shading of the same scene, at two fixed
//! floor points: one in a single box's penumbra, one where a box and a ball both hide part of
//! the light. The scene is the one of the `sdf_shadows` example (floor, ball, box, pillar,
//! floating ball). Results in BENCHMARKS.md (section `sdf`).

use arealight::glam::{DQuat, DVec3};
use arealight::sdf::{
    ConeSearch, Cuboid, Plane, Profile, QuadLight, QuilezSettings, Sdf, Sphere, SphereLight,
    TraceLimits, Transformed, UnionAll, fast_soft_shadow, proxy_integral, proxy_quad_integral,
    quilez_improved_shadow, quilez_shadow, sphere_trace,
};
use arealight::shade::{Body, ConvexPolyhedron, Light, Material, Scene, TriangleMesh};
use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use std::hint::black_box;

struct Bench {
    field: UnionAll,
    occluders: Vec<Body>,
}

fn scene() -> Bench {
    let balls = [
        (DVec3::new(-0.9, 0.35, 0.55), 0.55, 3),
        (DVec3::new(0.0, -0.55, 0.95), 0.22, 2),
    ];
    let boxes = [
        (
            DVec3::new(0.55, 0.0, 0.35),
            DVec3::new(0.45, 0.3, 0.35),
            0.0,
        ),
        (DVec3::new(1.0, 0.3, 0.6), DVec3::new(0.12, 0.12, 0.6), 0.4),
    ];
    let mut members: Vec<Box<dyn Sdf + Send + Sync>> =
        vec![Box::new(Plane::new(DVec3::ZERO, DVec3::Z).unwrap())];
    let mut occluders: Vec<Body> = Vec::new();
    for (c, r, s) in balls {
        members.push(Box::new(Sphere::new(c, r).unwrap()));
        occluders.push(ConvexPolyhedron::icosphere(c, r, s).unwrap().into());
    }
    for (c, h, angle) in boxes {
        let rot = DQuat::from_rotation_z(angle);
        let cube = Cuboid::new(DVec3::ZERO, h).unwrap();
        members.push(Box::new(Transformed::new(cube, rot, c, 1.0).unwrap()));
        let corners: Vec<DVec3> = (0..8)
            .map(|i| {
                let s = DVec3::new(
                    if i & 1 == 0 { -1.0 } else { 1.0 },
                    if i & 2 == 0 { -1.0 } else { 1.0 },
                    if i & 4 == 0 { -1.0 } else { 1.0 },
                );
                c + rot * (s * h)
            })
            .collect();
        occluders.push(ConvexPolyhedron::hull(&corners).unwrap().into());
    }
    Bench {
        field: UnionAll::new(members),
        occluders,
    }
}

fn shadows(c: &mut Criterion) {
    let b = scene();
    let center = DVec3::new(0.7, 1.5, 3.0);
    let sphere = SphereLight::new(center, 0.45).unwrap();
    let (u, v) = (DVec3::new(0.5, 0.0, 0.0), DVec3::new(0.0, -0.35, 0.0));
    let quad = QuadLight::new(center, u, v).unwrap();
    let search = ConeSearch::new(0.05, 1e-3);
    let q = QuilezSettings::new(1e-3);
    let white = Material::diffuse(DVec3::splat(0.8)).unwrap();
    let sphere_light = || {
        Light::new(
            ConvexPolyhedron::icosphere(center, 0.45, 5).unwrap(),
            DVec3::ONE,
        )
        .unwrap()
    };
    let quad_light = || Light::new(TriangleMesh::quad(center, u, v).unwrap(), DVec3::ONE).unwrap();
    let exact_sphere = Scene::new(vec![sphere_light()], b.occluders.clone()).unwrap();
    let exact_quad = Scene::new(vec![quad_light()], b.occluders.clone()).unwrap();
    let open_sphere = Scene::new(vec![sphere_light()], vec![]).unwrap();
    let open_quad = Scene::new(vec![quad_light()], vec![]).unwrap();
    // A floor point in the box's penumbra, and one in the overlap of the box's and the floating
    // ball's penumbrae (checked below to be partly shadowed by each).
    let points = [
        ("one occluder", DVec3::new(0.45, -0.75, 0.0)),
        ("two occluders", DVec3::new(-0.05, -1.1, 0.0)),
    ];
    let n = DVec3::Z;
    for (name, p) in points {
        let full = open_sphere.shade(p, n, n, &white).unwrap().x;
        let shadowed = exact_sphere.shade(p, n, n, &white).unwrap().x;
        assert!(
            shadowed > 0.02 * full && shadowed < 0.98 * full,
            "{name}: {shadowed} of {full}"
        );
        let mut g = c.benchmark_group(format!("sdf/{name}"));
        g.bench_function("quilez", |bch| {
            bch.iter(|| quilez_shadow(&b.field, black_box(p), &sphere, &q).unwrap())
        });
        g.bench_function("quilez improved", |bch| {
            bch.iter(|| quilez_improved_shadow(&b.field, black_box(p), &sphere, &q).unwrap())
        });
        for (label, profile) in [
            ("001 fast chord", Profile::Chord),
            ("001 fast smoothstep", Profile::Smoothstep),
        ] {
            g.bench_function(label, |bch| {
                bch.iter(|| {
                    fast_soft_shadow(&b.field, black_box(p), &sphere, &search, profile).unwrap()
                })
            });
        }
        let cosine = |l: DVec3| 0.8 * n.dot(l).max(0.0) / std::f64::consts::PI;
        g.bench_function(
            BenchmarkId::new("001 proxy sphere, directions", 128),
            |bch| {
                bch.iter(|| {
                    proxy_integral(&b.field, black_box(p), &sphere, cosine, 128, &search).unwrap()
                })
            },
        );
        g.bench_function(BenchmarkId::new("001 proxy quad, directions", 128), |bch| {
            bch.iter(|| {
                proxy_integral(&b.field, black_box(p), &quad, cosine, 128, &search).unwrap()
            })
        });
        g.bench_function("001 proxy quad exact", |bch| {
            bch.iter(|| proxy_quad_integral(&b.field, black_box(p), n, &quad, &search).unwrap())
        });
        g.bench_function("exact sphere light (icosphere 5)", |bch| {
            bch.iter(|| exact_sphere.shade(black_box(p), n, n, &white).unwrap())
        });
        g.bench_function("unshadowed sphere light (icosphere 5)", |bch| {
            bch.iter(|| open_sphere.shade(black_box(p), n, n, &white).unwrap())
        });
        g.bench_function("exact quad light", |bch| {
            bch.iter(|| exact_quad.shade(black_box(p), n, n, &white).unwrap())
        });
        g.bench_function("unshadowed quad light", |bch| {
            bch.iter(|| open_quad.shade(black_box(p), n, n, &white).unwrap())
        });
        g.finish();
    }
    // A camera ray of the example (primary sphere tracing), for scale.
    let eye = DVec3::new(0.3, -4.6, 3.1);
    let dir = (DVec3::new(0.45, -0.75, 0.0) - eye).normalize();
    let limits = TraceLimits {
        t_min: 0.0,
        t_max: 80.0,
        max_steps: 1024,
        hit_distance: 1e-6,
    };
    c.bench_function("sdf/sphere trace, camera ray", |bch| {
        bch.iter(|| sphere_trace(&b.field, black_box(eye), dir, &limits).unwrap())
    });
}

criterion_group!(benches, shadows);
criterion_main!(benches);
