//! Monte Carlo shading with solid-angle sampling (thesis 003 table 7.3): one shading point lit by
//! each polyhedron of thesis table 7.1 as a light (no occluders), sampled over its triangulated
//! silhouette (`LightSampling::Silhouette`: the light's unoccluded region, triangulated) and over
//! its projected front faces (`LightSampling::Faces`), with 1 and 64 samples per estimate. The
//! per-sample variance of both samplings at the point is printed once per polyhedron (from
//! 2^16 samples). Fixed inputs; results in BENCHMARKS.md (section `monte carlo`).

use arealight::glam::{DMat3, DVec3};
use arealight::internals::thesis_polyhedra;
use arealight::shade::{
    Body, ConvexPolyhedron, Light, LightSampling, Material, MonteCarlo, ReferenceBrdf, Scene,
    TriangleMesh,
};
use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use std::hint::black_box;

/// The polyhedron scaled by 0.5, turned so that no face is axis-aligned, 1.6 above the floor;
/// convex ones as convex polyhedra (one silhouette per point), the others as meshes.
fn light(mesh: &TriangleMesh) -> Body {
    let rot = DMat3::from_rotation_z(0.4) * DMat3::from_rotation_x(0.7);
    let moved = TriangleMesh::new(
        mesh.vertices()
            .iter()
            .map(|&p| rot * (p * 0.5) + DVec3::new(0.3, 0.2, 1.6))
            .collect(),
        mesh.triangles().to_vec(),
    )
    .unwrap();
    match ConvexPolyhedron::from_mesh(&moved) {
        Ok(p) => p.into(),
        Err(_) => moved.into(),
    }
}

fn monte_carlo(c: &mut Criterion) {
    let m = Material::new(DVec3::splat(0.5), DVec3::splat(0.04), 0.4).unwrap();
    let (x, n, v) = (DVec3::ZERO, DVec3::Z, DVec3::new(0.3, 0.0, 1.0));
    let mut group = c.benchmark_group("monte carlo");
    for (name, mesh) in thesis_polyhedra().unwrap() {
        let body = light(&mesh);
        let kind = if matches!(body, Body::Convex(_)) {
            "convex"
        } else {
            "mesh"
        };
        let scene = Scene::new(vec![Light::new(body, DVec3::ONE).unwrap()], vec![]).unwrap();
        let exact = scene.shade(x, n, v, &m).unwrap().y;
        let mut var = [0.0; 2];
        for (k, s) in [LightSampling::Silhouette, LightSampling::Faces]
            .into_iter()
            .enumerate()
        {
            let e = MonteCarlo::new(1 << 16, ReferenceBrdf::Ltc)
                .with_sampling(s)
                .estimate(&scene, x, n, v, &m, 1)
                .unwrap();
            // Per-sample variance, and a check that the estimate is of the analytic value.
            var[k] = e.std_error.y * e.std_error.y * f64::from(1u32 << 16);
            assert!(
                (e.mean.y - exact).abs() <= 5.0 * e.std_error.y + 1e-12,
                "{name} {s:?}: {} +- {} vs {exact}",
                e.mean.y,
                e.std_error.y
            );
        }
        eprintln!(
            "{name} ({kind}): per-sample variance silhouette {:.4e}, faces {:.4e}, ratio faces/silhouette {:.2}",
            var[0],
            var[1],
            var[1] / var[0]
        );
        for spp in [1u32, 64] {
            for (label, s) in [
                ("silhouette", LightSampling::Silhouette),
                ("faces", LightSampling::Faces),
            ] {
                let mc = MonteCarlo::new(spp, ReferenceBrdf::Ltc).with_sampling(s);
                group.bench_with_input(
                    BenchmarkId::new(format!("{label}, {spp} spp"), name),
                    &scene,
                    |b, s| {
                        let mut seed = 0u64;
                        b.iter(|| {
                            seed += 1;
                            mc.estimate(s, black_box(x), n, v, &m, seed).unwrap()
                        })
                    },
                );
            }
        }
    }
    group.finish();
}

criterion_group!(benches, monte_carlo);
criterion_main!(benches);
