//! The ratio estimator (`RatioEstimator`, \[HHM18\]): the analytic unshadowed radiance times a
//! Monte Carlo shadow ratio from one set of samples.
//!
//! - Where nothing shadows a light the ratio is 1 exactly and the result is the analytic value
//!   (no noise), and the analytic factor is `Scene::shade_per_light`'s unshadowed value bit for
//!   bit.
//! - In penumbrae, with the LTC BRDF (the one the analytic path integrates) the estimator
//!   converges to the analytic shadowed value: checked on random points of the seed's test scene
//!   within `4.5 sigma_hat + 1e-6` (`sigma_hat` the delta-method standard error; about 1800
//!   checks at 6.8e-6 each, with a 16-times re-estimate before a failure is believed, as in
//!   tests/shade_mc.rs), plus a mean z-score test for a bias.
//! - It is a ratio of means, not unbiased: with one sample the ratio is the visibility of that
//!   sample, whose expectation is the visible fraction of the region's solid angle whatever the
//!   BRDF. That identity is checked against the analytic solid angles with a binomial bound, at
//!   a point where the BRDF-weighted ratio (the large-sample limit) differs from it by many
//!   standard errors.

use arealight::glam::DVec3;
use arealight::internals::{DemoConfig, demo_scene};
use arealight::shade::{
    ConvexPolyhedron, Light, Material, RatioEstimator, ReferenceBrdf, Scene, ShadingFrame,
    TriangleMesh,
};
use arealight::visibility::Visibility;
use support::Rng;
use support::shade::{ground_point, point_on_mesh, view_above};

mod support;

/// Random shading points of a demo scene: ground and occluder surfaces, views above them.
fn points(cfg: DemoConfig, count: usize, seed: u64) -> Vec<(DVec3, DVec3, DVec3, Material)> {
    let demo = demo_scene(cfg).unwrap();
    let mut rng = Rng::new(seed);
    let occ = demo.scene.occluders();
    (0..count)
        .map(|i| {
            let (x, n, m) = if i % 4 == 3 && !occ.is_empty() {
                let k = i % occ.len();
                let (x, n) = point_on_mesh(&mut rng, occ[k].mesh());
                (x, n, demo.occluder_materials[k])
            } else {
                (
                    ground_point(&mut rng, demo.ground_half_size),
                    DVec3::Z,
                    demo.ground,
                )
            };
            (x, n, view_above(&mut rng, n, 0.09), m)
        })
        .collect()
}

#[test]
fn unshadowed_lights_give_the_analytic_value_exactly() {
    // Three lights, no occluders: lights can still hide parts of each other, so each light's
    // ratio is checked only where its analytic shadowed and unshadowed values agree.
    let cfg = DemoConfig {
        lights: 3,
        occluders: 0,
    };
    let scene = demo_scene(cfg).unwrap().scene;
    let est = RatioEstimator::new(64, ReferenceBrdf::True);
    let mut exact = 0;
    for (i, (x, n, v, m)) in points(cfg, 300, 31).into_iter().enumerate() {
        let parts = scene.shade_per_light(x, n, v, &m).unwrap();
        let ratios = est.estimate_lights(&scene, x, n, v, &m, i as u64).unwrap();
        assert_eq!(parts.len(), ratios.len());
        for (k, (p, r)) in parts.iter().zip(&ratios).enumerate() {
            assert_eq!(
                r.unshadowed,
                p.unshadowed(),
                "point {i} light {k}: the analytic factor"
            );
            if p.shadowed() == p.unshadowed() {
                assert_eq!(r.ratio, DVec3::ONE, "point {i} light {k}");
                assert_eq!(r.ratio_std_error, DVec3::ZERO, "point {i} light {k}");
                exact += 1;
            }
        }
        let a = scene.shade(x, n, v, &m).unwrap();
        if parts.iter().all(|p| p.shadowed() == p.unshadowed()) {
            let e = est.estimate(&scene, x, n, v, &m, i as u64).unwrap();
            assert!(
                (e.mean - a).abs().max_element() <= 1e-12 * a.max_element(),
                "point {i}: ratio estimate {} analytic {a}",
                e.mean
            );
        }
    }
    eprintln!("{exact} unshadowed (point, light) pairs");
    assert!(exact > 600);
}

#[test]
fn converges_to_the_analytic_shadowed_value_in_penumbrae() {
    let cfg = DemoConfig::default();
    let scene = demo_scene(cfg).unwrap().scene;
    let n = 1024;
    let est = RatioEstimator::new(n, ReferenceBrdf::Ltc);
    let est16 = RatioEstimator::new(16 * n, ReferenceBrdf::Ltc);
    let (mut failures, mut penumbra) = (Vec::new(), 0);
    let (mut zsum, mut zn) = (0.0, 0usize);
    for (i, (x, nrm, v, m)) in points(cfg, 600, 32).into_iter().enumerate() {
        let a = scene.shade(x, nrm, v, &m).unwrap();
        let e = est.estimate(&scene, x, nrm, v, &m, i as u64).unwrap();
        if e.std_error.y > 0.0 {
            penumbra += 1;
            zsum += (e.mean.y - a.y) / e.std_error.y;
            zn += 1;
        }
        let agrees = |e: &arealight::shade::Estimate, c: usize| {
            (e.mean[c] - a[c]).abs() <= 4.5 * e.std_error[c] + 1e-6
        };
        if (0..3).all(|c| agrees(&e, c)) {
            continue;
        }
        let e2 = est16.estimate(&scene, x, nrm, v, &m, !(i as u64)).unwrap();
        for c in (0..3).filter(|&c| !agrees(&e2, c)) {
            failures.push(format!(
                "point {i} ch {c}: analytic {} ratio estimate {} +- {}, then {} +- {}",
                a[c], e.mean[c], e.std_error[c], e2.mean[c], e2.std_error[c]
            ));
        }
    }
    assert!(
        failures.is_empty(),
        "{} failures:\n{}",
        failures.len(),
        failures.join("\n")
    );
    let zmean = zsum / zn as f64;
    eprintln!("{penumbra} of 600 points in a penumbra, mean z {zmean:.3}");
    assert!(
        penumbra >= 60,
        "too few penumbra points to test: {penumbra}"
    );
    assert!(zmean.abs() <= 4.0 / (zn as f64).sqrt(), "mean z {zmean}");
}

#[test]
fn one_sample_estimates_the_visible_solid_angle_fraction() {
    // A quad light over a cube, a glossy floor point in the cube's penumbra, seen from where
    // the mirror direction of the narrow lobe passes through the cube: the BRDF weights the
    // hidden directions far above the seen ones.
    let quad =
        TriangleMesh::quad(DVec3::new(0.0, 0.0, 3.0), DVec3::Y * 0.8, DVec3::X * 0.8).unwrap();
    let cube = ConvexPolyhedron::cuboid(DVec3::new(0.45, 0.0, 1.5), DVec3::splat(0.3)).unwrap();
    let scene = Scene::new(
        vec![Light::new(quad, DVec3::ONE).unwrap()],
        vec![cube.into()],
    )
    .unwrap();
    let m = Material::new(DVec3::splat(0.05), DVec3::splat(0.9), 0.25).unwrap();
    let (x, nrm, v) = (DVec3::ZERO, DVec3::Z, DVec3::new(-0.2, 0.0, 1.0));
    let frame = ShadingFrame::new(x, nrm, v).unwrap();
    let solid = |pieces: Vec<arealight::sphere::SphericalPolygon>| {
        pieces.iter().map(|p| p.solid_angle()).sum::<f64>()
    };
    let seen = solid(scene.visible_region(0, &frame).unwrap());
    let all = solid(scene.visibility().unoccluded_region(0, &frame).unwrap());
    let p = seen / all;
    let part = scene.shade_per_light(x, nrm, v, &m).unwrap()[0];
    let weighted = part.shadowed().y / part.unshadowed().y;
    let runs = 20_000;
    let one = RatioEstimator::new(1, ReferenceBrdf::Ltc);
    let mean: f64 = (0..runs)
        .map(|s| {
            one.estimate_lights(&scene, x, nrm, v, &m, s).unwrap()[0]
                .ratio
                .y
        })
        .sum::<f64>()
        / f64::from(runs as u32);
    let se = (p * (1.0 - p) / f64::from(runs as u32)).sqrt();
    eprintln!(
        "visible solid angle fraction {p:.4}, BRDF-weighted ratio {weighted:.4}, \
         mean one-sample ratio {mean:.4} +- {se:.4}"
    );
    assert!(p > 0.1 && p < 0.9, "not a penumbra point: {p}");
    assert!(
        (mean - p).abs() <= 4.5 * se,
        "one-sample mean {mean}, fraction {p}"
    );
    // The point is one where the estimator's small-sample bias is visible: its large-sample
    // limit is far from the one-sample expectation.
    assert!(
        (weighted - p).abs() > 10.0 * se,
        "weighted {weighted}, fraction {p}"
    );
}
