//! Lights bounded by Bezier curves in scenes: the scene's per-point flattening against the
//! curved integrals (unshadowed, within the bound the flattening angle implies), soft shadows
//! from occluders and from other lights against the Monte Carlo reference, which samples the
//! exact curved region by area (not the flattening), and points on the light's plane or edge.
//!
//! Confidence bound, as in tests/shade_exact.rs: with the LTC BRDF the analytic value and the
//! estimate are the same integral, so per point and channel `|analytic - mc| <= 4.5 sigma_hat
//! + 1e-6` over 2048 samples per light; this file makes about 1 100 such checks, and a normal
//! deviate exceeds 4.5 sigma with probability 6.8e-6, so the chance of a false alarm in the
//! file is about 0.8%. A point that fails is estimated again with 16 times the samples on an
//! independent stream and must pass there. The mean first-stage z-score must stay within
//! `4 / sqrt(points)` (a bias too small for any one point). Seeds are fixed.

mod support;

use arealight::glam::{DVec2, DVec3};
use arealight::ltc::Subdivision;
use arealight::shade::{
    BezierShape, Body, ConvexPolyhedron, Light, Material, MonteCarlo, ReferenceBrdf, Scene,
    ShadingFrame, TriangleMesh,
};
use support::Rng;
use support::bezier::{Plane, Seg2, blob, letter_d, shape};
use support::shade::{ground_point, view_above};

/// The letter D, 1.5 across, 2.2 above the ground, tilted a little, facing down.
fn d_light() -> BezierShape {
    let plane = Plane {
        o: DVec3::new(0.1, -0.2, 2.2),
        e1: DVec3::new(0.0, 1.0, 0.0),
        e2: DVec3::new(1.0, 0.0, 0.15).normalize(),
    };
    // e1 x e2 points down (-z, a little tilted): the emitting side faces the ground.
    let scaled: Vec<Vec<Seg2>> = letter_d()
        .iter()
        .map(|l| l.iter().map(|s| scale(s, 0.75)).collect())
        .collect();
    shape(&plane, &scaled)
}

fn scale(s: &Seg2, k: f64) -> Seg2 {
    match *s {
        Seg2::Line(a, b) => Seg2::Line(a * k, b * k),
        Seg2::Cubic(p) => Seg2::Cubic(p.map(|v| v * k)),
    }
}

/// A blob on a wall-like plane, leaning over the ground and facing it (towards `+x` and down).
fn blob_light() -> BezierShape {
    let plane = Plane {
        o: DVec3::new(-1.6, 0.3, 1.4),
        e1: DVec3::new(0.0, 1.0, 0.0),
        e2: DVec3::new(0.5, 0.0, 1.0).normalize(),
    };
    shape(&plane, &[blob(DVec2::ZERO, &[0.6, 0.45, 0.7, 0.5], 8, 0.2)])
}

fn material() -> Material {
    Material::new(DVec3::new(0.6, 0.5, 0.4), DVec3::splat(0.04), 0.45).unwrap()
}

/// The scenes: the D over a box, the blob over a ball beside a quad light that the D partly
/// hides, and both curved lights with a thin slab between.
fn scenes() -> Vec<(&'static str, Scene)> {
    let boxy: Body =
        ConvexPolyhedron::cuboid(DVec3::new(0.2, -0.1, 0.9), DVec3::new(0.3, 0.25, 0.2))
            .unwrap()
            .into();
    let ball: Body = ConvexPolyhedron::icosphere(DVec3::new(-0.7, 0.2, 0.6), 0.3, 2)
        .unwrap()
        .into();
    let quad =
        TriangleMesh::quad(DVec3::new(0.3, -0.3, 3.2), DVec3::Y * 0.6, DVec3::X * 0.6).unwrap();
    let slab: Body =
        ConvexPolyhedron::cuboid(DVec3::new(-0.6, 0.0, 1.3), DVec3::new(0.05, 0.8, 0.6))
            .unwrap()
            .into();
    vec![
        (
            "D over a box",
            Scene::new(
                vec![Light::new(d_light(), DVec3::new(1.0, 0.8, 0.6)).unwrap()],
                vec![boxy],
            )
            .unwrap(),
        ),
        (
            "blob and a quad hidden by the D, over a ball",
            Scene::new(
                vec![
                    Light::new(blob_light(), DVec3::new(0.4, 0.9, 1.2)).unwrap(),
                    Light::new(quad, DVec3::splat(0.7)).unwrap(),
                    Light::new(d_light(), DVec3::new(1.0, 0.8, 0.6)).unwrap(),
                ],
                vec![ball],
            )
            .unwrap(),
        ),
        (
            "two curved lights and a slab",
            Scene::new(
                vec![
                    Light::new(blob_light(), DVec3::new(0.4, 0.9, 1.2)).unwrap(),
                    Light::new(d_light(), DVec3::new(1.0, 0.8, 0.6)).unwrap(),
                ],
                vec![slab],
            )
            .unwrap(),
        ),
    ]
}

#[test]
fn shadows_agree_with_monte_carlo_over_the_exact_curves() {
    let m = material();
    let mc = MonteCarlo::new(2048, ReferenceBrdf::Ltc);
    let mc16 = MonteCarlo::new(16 * 2048, ReferenceBrdf::Ltc);
    let (mut zsum, mut zn) = (0.0, 0usize);
    let mut failures = Vec::new();
    let mut shadowed = 0;
    for (k, (name, scene)) in scenes().iter().enumerate() {
        let bare = Scene::new(scene.lights().to_vec(), vec![]).unwrap();
        let mut rng = Rng::new(19 + k as u64);
        for i in 0..120 {
            let x = ground_point(&mut rng, 2.0);
            let v = view_above(&mut rng, DVec3::Z, 0.2);
            let a = scene.shade(x, DVec3::Z, v, &m).unwrap();
            assert!(a.is_finite() && a.min_element() >= 0.0, "{name} {i}: {a}");
            let full = bare.shade(x, DVec3::Z, v, &m).unwrap();
            if a.y < 0.98 * full.y {
                shadowed += 1;
            }
            let seed = 7_000 * k as u64 + i as u64;
            let e = mc.estimate(scene, x, DVec3::Z, v, &m, seed).unwrap();
            let ok = |e: &arealight::shade::Estimate| {
                (0..3).all(|c| (a[c] - e.mean[c]).abs() <= 4.5 * e.std_error[c] + 1e-6)
            };
            if e.std_error.y > 0.0 {
                zsum += (a.y - e.mean.y) / e.std_error.y;
                zn += 1;
            }
            if ok(&e) {
                continue;
            }
            let e16 = mc16
                .estimate(scene, x, DVec3::Z, v, &m, seed ^ 0x5eed_0000)
                .unwrap();
            if !ok(&e16) {
                failures.push(format!(
                    "{name} point {i} x {x} v {v}: analytic {a}, mc {} +- {} (16x: {} +- {})",
                    e.mean, e.std_error, e16.mean, e16.std_error
                ));
            }
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
    let zmean = zsum / zn as f64;
    assert!(
        zmean.abs() <= 4.0 / (zn as f64).sqrt(),
        "mean z {zmean} over {zn}"
    );
    // The scenes cast shadows: a good share of the points lose light to a blocker.
    assert!(shadowed > 40, "only {shadowed} of 360 points shadowed");
}

/// The unshadowed scene (its flattening) against the curved integrals at a tight threshold:
/// within the bound the flattening angle implies. A flattening within angle `a` of the curves
/// moves the boundary by at most `a`, so the region changes by slivers of area at most
/// `(2/3) a` per radian of boundary (parabolic slivers) and the Lambert integral by at most
/// `(2/3) a P / pi` for an angular perimeter `P`, times the albedo and the radiance.
#[test]
fn flattening_stays_within_its_bound_of_the_curved_integral() {
    let m = material();
    let mut rng = Rng::new(5);
    for angle in [1e-3, 1e-4, 1e-6] {
        for light in [d_light(), blob_light()] {
            let light = light.with_flatten_angle(angle).unwrap();
            let rad = DVec3::new(1.0, 0.8, 0.6);
            let l = Light::new(light.clone(), rad).unwrap();
            let scene = Scene::new(vec![l.clone()], vec![]).unwrap();
            let mut worst: f64 = 0.0;
            for _ in 0..40 {
                let x = ground_point(&mut rng, 2.0);
                let v = view_above(&mut rng, DVec3::Z, 0.2);
                let flat = scene
                    .shade(x, DVec3::Z, v, &Material::diffuse(DVec3::ONE).unwrap())
                    .unwrap();
                let curved = l
                    .shade_curved(
                        x,
                        DVec3::Z,
                        v,
                        &Material::diffuse(DVec3::ONE).unwrap(),
                        Subdivision::Adaptive { eps: 1e-11 },
                        None,
                    )
                    .unwrap();
                // The angular perimeter of the flattening seen from x.
                let frame = ShadingFrame::new(x, DVec3::Z, v).unwrap();
                let region = light.region(&frame).unwrap();
                let perimeter: f64 = region
                    .rings()
                    .map(|r| {
                        (0..r.len())
                            .map(|i| r[i].angle_between(r[(i + 1) % r.len()]))
                            .sum::<f64>()
                    })
                    .sum();
                let bound = 2.0 / 3.0 * angle * perimeter / std::f64::consts::PI * rad.x;
                let diff = (flat.x - curved.diffuse.x).abs();
                assert!(
                    diff <= bound + 1e-9,
                    "angle {angle}: flattened {} vs curved {}: {diff:e} > bound {bound:e}",
                    flat.x,
                    curved.diffuse.x
                );
                worst = worst.max(diff / bound.max(1e-300));
                // The glossy lobe: the same region, a peaked density; looser, relative.
                let g = scene.shade(x, DVec3::Z, v, &m).unwrap();
                let gc = l
                    .shade_curved(
                        x,
                        DVec3::Z,
                        v,
                        &m,
                        Subdivision::Adaptive { eps: 1e-11 },
                        Some(Subdivision::Adaptive { eps: 1e-11 }),
                    )
                    .unwrap();
                assert!(
                    (g - gc.total()).abs().max_element()
                        <= 200.0 * angle * gc.total().max_element() + 1e-9,
                    "angle {angle}: {g} vs {}",
                    gc.total()
                );
            }
            eprintln!("angle {angle}: worst diffuse difference {worst:.3} of the bound");
        }
    }
}

/// The Monte Carlo sampler of the curved region against the curved integral itself (no
/// occluder): the reference samples the exact curves, so it agrees with the curved integrals
/// at eps -> 0, not only with some flattening.
#[test]
fn monte_carlo_samples_the_exact_curves() {
    let m = material();
    let mc = MonteCarlo::new(40_000, ReferenceBrdf::Ltc);
    let mut rng = Rng::new(77);
    for light in [d_light(), blob_light()] {
        let l = Light::new(light, DVec3::ONE).unwrap();
        let scene = Scene::new(vec![l.clone()], vec![]).unwrap();
        let mut coarse_off = 0;
        for i in 0..12 {
            let x = ground_point(&mut rng, 1.0);
            let v = view_above(&mut rng, DVec3::Z, 0.3);
            let fine = Subdivision::Adaptive { eps: 1e-11 };
            let curved = l
                .shade_curved(x, DVec3::Z, v, &m, fine, Some(fine))
                .unwrap();
            assert!(curved.total().y > 1e-3, "point {i} sees the light");
            let e = mc.estimate(&scene, x, DVec3::Z, v, &m, 900 + i).unwrap();
            for c in 0..3 {
                assert!(
                    (curved.total()[c] - e.mean[c]).abs() <= 4.5 * e.std_error[c] + 1e-9,
                    "point {i}: curved {} vs mc {} +- {}",
                    curved.total(),
                    e.mean,
                    e.std_error
                );
            }
            // Two chords per cubic: a polygon a few percent off the curves.
            let coarse = Subdivision::Uniform { n: 2 };
            let poly = l
                .shade_curved(x, DVec3::Z, v, &m, coarse, Some(coarse))
                .unwrap();
            if (poly.total().y - e.mean.y).abs() > 4.5 * e.std_error.y {
                coarse_off += 1;
            }
        }
        // The check has the power to tell a coarse polygon from the curves.
        assert!(
            coarse_off >= 9,
            "the 2-chord polygon passed at {} of 12 points",
            12 - coarse_off
        );
    }
}

#[test]
fn points_on_the_plane_on_an_edge_and_behind_are_finite() {
    let m = material();
    let light = d_light();
    let scene = Scene::new(vec![Light::new(light.clone(), DVec3::ONE).unwrap()], vec![]).unwrap();
    let start = light.loops()[0][0].start();
    let n = light.normal();
    let inner = light.loops()[0][1].point(0.5);
    let tangent = (inner - start).normalize();
    let side = n.cross(tangent);
    for (what, x) in [
        ("on an edge", start),
        ("on a curve", inner),
        ("in the plane outside", start - 0.5 * tangent),
        ("in the plane inside", start + 0.3 * tangent + 0.01 * side),
        ("a hair in front", inner + n * 1e-12),
        ("a hair behind", inner - n * 1e-12),
        ("behind", start - n),
    ] {
        for normal in [DVec3::Z, n, -n, side] {
            let r = scene.shade(x, normal, normal + DVec3::X * 0.3, &m);
            let v = r.unwrap_or_else(|e| panic!("{what}: {e}"));
            assert!(v.is_finite() && v.min_element() >= 0.0, "{what}: {v}");
            if what == "behind" {
                assert_eq!(v, DVec3::ZERO, "one-sided emission");
            }
        }
    }
}
