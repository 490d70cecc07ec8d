//! The Monte Carlo reference for glossy lobes (issue 24): light sampling combined with BRDF
//! sampling by multiple importance sampling (`MonteCarlo::with_brdf_sampling`, balance
//! heuristic), and the analytic shading checked against it at near-mirror roughness and grazing
//! views.
//!
//! What the analytic value is checked against: `Scene::shade` integrates the table's LTC lobe
//! (scaled by `LtcLookup::specular_scale`) and the Lambertian lobe over the visible region
//! exactly, so the reference with `ReferenceBrdf::Ltc` estimates the same integral and any
//! difference beyond the confidence bound is a geometric error. The true GGX lobe differs from
//! the LTC by the table's fit, which is checked on its own (tests/ltc_robust.rs), so GGX Monte
//! Carlo is never compared with the analytic value here.
//!
//! - The estimator first: unoccluded quad lights whose value has a closed form (Baum's edge sum
//!   over the light's polygon, `clamped_cosine_integral` and `ltc_integral`), at roughness 0 to
//!   0.4 and views from normal to `cos 1e-3`, with the lobe aimed inside the light, on its edge
//!   and outside it. Over 100 independent estimates per configuration the pooled mean must agree
//!   with the closed form at 4.5 of its standard errors, and the estimates' spread (their sample
//!   variance) must be `0.5..2` times the variance they report: a standard error that is wrong
//!   by a factor of 1.5 or more fails (for normal estimates the ratio's standard deviation is
//!   0.14; the near-mirror estimates are skewed, and were seen at 0.8..1.55).
//! - The true-GGX technique (visible-normal sampling) against light sampling alone at roughness
//!   0.4, where both resolve the lobe: two unbiased estimators of one integral.
//! - Scenes of issue 24's families with the near-mirror lobe aimed at their edges: analytic
//!   (both methods) against the reference at 4.5 standard errors plus a relative 1e-6, with a
//!   second estimate of 16 times the samples for a point that fails the first (as in
//!   tests/shade_census.rs).

use arealight::glam::{DMat3, DVec3};
use arealight::ltc::{clamped_cosine_integral, lookup, ltc_integral};
use arealight::shade::{
    Body, ConvexPolyhedron, Estimate, Light, LightSampling, Material, Method, MonteCarlo,
    ReferenceBrdf, Scene, ShadingFrame, TriangleMesh,
};
use arealight::sphere::SphericalPolygon;
use support::Rng;

mod support;

/// The closed form of one quad light's radiance at a point with nothing in the way, for the
/// LTC BRDF: per channel `radiance * (albedo * E + scale * I)`, with `E` the clamped-cosine
/// integral of the light's polygon in the shading frame and `I` the LTC integral of its part
/// above the horizon.
fn closed_form(
    corners: [DVec3; 4],
    radiance: DVec3,
    (x, n, v): (DVec3, DVec3, DVec3),
    m: &Material,
) -> DVec3 {
    let frame = ShadingFrame::new(x, n, v).unwrap();
    let mut ring: Vec<DVec3> = corners
        .iter()
        .map(|&c| frame.dir_to_local(c - x).normalize())
        .collect();
    let mut poly = SphericalPolygon::new(vec![ring.clone()]).unwrap();
    if poly.solid_angle() > 2.0 * std::f64::consts::PI {
        ring.reverse();
        poly = SphericalPolygon::new(vec![ring]).unwrap();
    }
    let e = clamped_cosine_integral(&poly);
    let look = lookup(frame.view().z, m.alpha()).unwrap();
    // The BRDF is zero below the shading horizon, where the LTC need not be.
    let i = ltc_integral(&poly.clip_to_hemisphere(DVec3::Z), look.m_inv).unwrap();
    let f0 = m.f0();
    let scale = DVec3::new(
        look.specular_scale(f0.x),
        look.specular_scale(f0.y),
        look.specular_scale(f0.z),
    );
    radiance * (m.albedo() * e + scale * i)
}

/// A view at angle `acos(cos_v)` from `n` whose mirror direction about `n` points along `d`'s
/// azimuth: the lobe looks at `d` when `d`'s elevation is `asin(cos_v)`.
fn view_towards(n: DVec3, d: DVec3, cos_v: f64) -> DVec3 {
    let t = (d - n * n.dot(d)).normalize();
    -t * (1.0 - cos_v * cos_v).sqrt() + n * cos_v
}

#[test]
fn mis_estimator_agrees_with_the_closed_form_and_its_error_is_calibrated() {
    // A 1 x 1 quad light at height 1 facing down, over points on the ground; the lobe is aimed
    // at its middle, at its edge, and 0.3 beyond it.
    let c = DVec3::new(0.0, 0.0, 1.0);
    let (u, w) = (DVec3::new(0.0, 0.5, 0.0), DVec3::new(0.5, 0.0, 0.0));
    let quad = TriangleMesh::quad(c, u, w).unwrap();
    let corners = [c - u - w, c + u - w, c + u + w, c - u + w];
    let radiance = DVec3::new(1.0, 0.8, 0.6);
    let scene = Scene::new(vec![Light::new(quad, radiance).unwrap()], vec![]).unwrap();
    let mut worst = 0f64;
    for (k, &(roughness, albedo, cos_v, aim)) in [
        (0.0, 0.0, 1e-3f64, 0.0),
        (0.0, 0.5, 0.02, 0.5),
        (0.0, 0.5, 0.5, 0.8),
        (0.01, 0.0, 0.05, 0.5),
        (0.05, 0.5, 1e-3, 0.2),
        (0.05, 0.5, 0.9, 0.5),
        (0.2, 0.5, 0.3, 0.0),
        (0.4, 0.8, 0.7, 0.5),
    ]
    .iter()
    .enumerate()
    {
        let m = Material::new(DVec3::splat(albedo), DVec3::new(0.04, 0.5, 1.0), roughness).unwrap();
        // The point sees the aim point at elevation asin(cos_v) (for the near-normal views the
        // normal is tilted towards it instead).
        let target = c + DVec3::new(aim, 0.1, 0.0);
        let x = DVec3::new(target.x - 1.0, 0.1, 0.0);
        let d = (target - x).normalize();
        let elev = d.z.asin();
        // Tilt the normal about y so that d's elevation over the surface is asin(cos_v).
        let tilt = elev - cos_v.asin();
        let n = DMat3::from_rotation_y(-tilt) * DVec3::Z;
        let v = view_towards(n, d, cos_v);
        let want = closed_form(corners, radiance, (x, n, v), &m);
        let got = scene.shade(x, n, v, &m).unwrap();
        assert!(
            (got - want).abs().max_element() <= 1e-9 * want.max_element(),
            "config {k}: analytic {got} vs closed form {want}"
        );
        let runs = 100;
        let means: Vec<Estimate> = (0..runs)
            .map(|seed| {
                MonteCarlo::new(2048, ReferenceBrdf::Ltc)
                    .with_sampling(LightSampling::Faces)
                    .with_brdf_sampling()
                    .estimate(&scene, x, n, v, &m, 1000 * k as u64 + seed)
                    .unwrap()
            })
            .collect();
        let nr = runs as f64;
        for ch in 0..3 {
            if want[ch] == 0.0 {
                continue;
            }
            let pooled = means.iter().map(|e| e.mean[ch]).sum::<f64>() / nr;
            // The mean reported variance of one estimate, and the spread the estimates show.
            let reported = means.iter().map(|e| e.std_error[ch].powi(2)).sum::<f64>() / nr;
            let seen = means
                .iter()
                .map(|e| (e.mean[ch] - pooled).powi(2))
                .sum::<f64>()
                / (nr - 1.0);
            let dev = (pooled - want[ch]).abs() / (reported / nr).sqrt();
            worst = worst.max(dev);
            eprintln!(
                "config {k} ch {ch}: pooled {pooled:.9} want {:.9}, {dev:.2} standard errors; \
                 spread / reported variance {:.3}",
                want[ch],
                seen / reported
            );
            assert!(
                dev <= 4.5,
                "config {k} ch {ch}: pooled {pooled} vs closed form {}",
                want[ch]
            );
            assert!(
                (0.5..=2.0).contains(&(seen / reported)),
                "config {k} ch {ch}: the estimates' spread {seen:.3e} against their reported \
                 variance {reported:.3e}"
            );
        }
    }
    eprintln!("largest pooled deviation {worst:.2} standard errors");
}

/// The true GGX lobe by visible-normal sampling combined with light sampling, against light
/// sampling alone, at a roughness both resolve: the same integral, so the two agree within the
/// combined error.
#[test]
fn true_ggx_with_brdf_sampling_agrees_with_light_sampling() {
    let quad = TriangleMesh::quad(
        DVec3::new(0.0, 0.0, 1.0),
        DVec3::new(0.0, 0.6, 0.0),
        DVec3::new(0.6, 0.0, 0.0),
    )
    .unwrap();
    let cube = ConvexPolyhedron::cuboid(DVec3::new(0.2, 0.1, 0.5), DVec3::splat(0.15)).unwrap();
    let scene = Scene::new(
        vec![Light::new(quad, DVec3::ONE).unwrap()],
        vec![cube.into()],
    )
    .unwrap();
    let m = Material::new(DVec3::splat(0.3), DVec3::splat(0.5), 0.6).unwrap();
    for (x, v) in [
        (DVec3::new(-0.4, 0.0, 0.0), DVec3::new(-0.5, 0.1, 0.6)),
        (DVec3::new(0.3, -0.2, 0.0), DVec3::new(0.1, 0.2, 1.0)),
    ] {
        let est = |mc: MonteCarlo| {
            mc.estimate(&scene, x, DVec3::Z, v.normalize(), &m, 77)
                .unwrap()
        };
        let light = est(MonteCarlo::new(200_000, ReferenceBrdf::True));
        let both = est(MonteCarlo::new(100_000, ReferenceBrdf::True).with_brdf_sampling());
        let faces = est(MonteCarlo::new(100_000, ReferenceBrdf::True)
            .with_sampling(LightSampling::Faces)
            .with_brdf_sampling());
        for other in [both, faces] {
            for c in 0..3 {
                let se = (light.std_error[c].powi(2) + other.std_error[c].powi(2)).sqrt();
                assert!(
                    (light.mean[c] - other.mean[c]).abs() <= 4.5 * se,
                    "{x}: light sampling {} +- {} vs with BRDF sampling {} +- {}",
                    light.mean[c],
                    light.std_error[c],
                    other.mean[c],
                    other.std_error[c]
                );
            }
        }
    }
}

/// A light of one of four kinds about `c` (as tests/shade_census.rs): a quad facing down, a
/// box, an icosphere, two sheets as one open mesh.
fn light_body(rng: &mut Rng, c: DVec3, kind: usize) -> Body {
    let s = rng.range(0.3, 0.7);
    match kind % 4 {
        0 => TriangleMesh::quad(c, DVec3::Y * s, DVec3::X * s)
            .unwrap()
            .into(),
        1 => ConvexPolyhedron::cuboid(c, DVec3::new(s, rng.range(0.2, 0.6), rng.range(0.05, 0.3)))
            .unwrap()
            .into(),
        2 => ConvexPolyhedron::icosphere(c, s * 0.6, 1).unwrap().into(),
        _ => TriangleMesh::quad(c, DVec3::Y * s, DVec3::X * s)
            .unwrap()
            .merged(
                &TriangleMesh::quad(
                    c + DVec3::new(rng.range(-0.3, 0.3), 0.0, rng.range(0.3, 0.6)),
                    DVec3::Y * s,
                    DVec3::X * s,
                )
                .unwrap(),
            )
            .unwrap()
            .into(),
    }
}

/// Occluders of issue 24's families about light `light` centred at `c`: a box cutting through
/// the light, a flat quad in the plane of its lowest vertex, a sliver (one vertex
/// `1e-15..1e-9` of its size off the line of the others), a box touching that plane from below.
fn family_occluders(rng: &mut Rng, c: DVec3, light: &Body) -> Vec<Body> {
    let z = light
        .mesh()
        .vertices()
        .iter()
        .map(|v| v.z)
        .fold(f64::INFINITY, f64::min);
    let h = DVec3::new(
        rng.range(0.05, 0.2),
        rng.range(0.05, 0.2),
        rng.range(0.05, 0.4),
    );
    let mut out: Vec<Body> = vec![
        ConvexPolyhedron::cuboid(
            c + DVec3::new(rng.range(-0.5, 0.5), rng.range(-0.5, 0.5), 0.0),
            h,
        )
        .unwrap()
        .into(),
        TriangleMesh::quad(
            DVec3::new(c.x + rng.range(-0.4, 0.4), c.y + rng.range(-0.4, 0.4), z),
            DVec3::X * rng.range(0.1, 0.3),
            DVec3::Y * rng.range(0.1, 0.3),
        )
        .unwrap()
        .into(),
        ConvexPolyhedron::cuboid(
            DVec3::new(
                c.x + rng.range(-0.6, 0.6),
                c.y + rng.range(-0.6, 0.6),
                z - h.z,
            ),
            h,
        )
        .unwrap()
        .into(),
    ];
    let at = c - DVec3::new(0.0, 0.0, rng.range(0.2, 1.0));
    let (a, b) = (at + rng.dir() * 0.4, at - rng.dir() * 0.4);
    let off = 10f64.powf(rng.range(-15.0, -9.0));
    let m = a.lerp(b, rng.range(0.2, 0.8)) + rng.dir() * off * (b - a).length();
    if let Ok(s) = TriangleMesh::new(vec![a, b, m], vec![[0, 1, 2]]) {
        out.push(s.into());
    }
    out
}

/// A point of an edge of one of `meshes`, or one of their vertices, moved by `1e-12..1e-3` in a
/// random direction: where a near-mirror lobe straddles a boundary of the visible region.
fn edge_target(rng: &mut Rng, meshes: &[&TriangleMesh]) -> DVec3 {
    let m = meshes[rng.below(meshes.len())];
    let [a, b, _] = m.triangle(rng.below(m.triangle_count()));
    let p = if rng.f64() < 0.3 {
        a
    } else {
        a.lerp(b, rng.f64())
    };
    p + rng.dir() * 10f64.powf(rng.range(-12.0, -3.0))
}

/// What light 0 of `scene` can send at most at the point: its radiance times the material's
/// directional albedo (the diffuse albedo plus the GGX table's with Schlick's Fresnel).
fn hemisphere_bound(scene: &Scene, (x, n, v): (DVec3, DVec3, DVec3), m: &Material) -> DVec3 {
    let cos_v = ShadingFrame::new(x, n, v).unwrap().view().z;
    let look = lookup(cos_v, m.alpha()).unwrap();
    let spec = m
        .f0()
        .map(|f0| look.albedo * (f0 + (1.0 - f0) * look.fresnel));
    scene.lights()[0].radiance() * (m.albedo() + spec)
}

/// How many scenes the glossy-scene test shades (16 points each): `GLOSSY_CASES`, default 16.
fn glossy_cases() -> usize {
    std::env::var("GLOSSY_CASES")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(16)
}

/// Issue 24's glossy regime in scenes: roughness 0 to 0.05, views at `cos 1e-4..0.05` from the
/// normal (a quarter of them `0.05..1`), the mirror direction aimed at a light's or an
/// occluder's edge or vertex (within `1e-12..1e-3`), on random scenes of the census families
/// (interpenetrating, coplanar, touching and sliver occluders). Both methods against the
/// reference with the LTC BRDF, light and BRDF sampling combined, the light sampled by its front
/// faces (independent of the visibility layer), at 4.5 standard errors plus a relative `1e-6`
/// and `1e-9` of what the light can send at most (the analytic integral's rounding: a light far
/// in a near-mirror lobe's tail, worth `2e-14` of it, read `1.7e-12` on both methods, the
/// transformed polygon's edge terms cancelling to that). A point that fails is estimated again
/// with 16 times the samples and must then lie within the empirical Bernstein interval of level
/// `1 - 1e-6` (`Estimate::bernstein_halfwidth`): where the visible part of the light is a
/// sliver in the lobe, few samples or none hit it and the standard error reads near zero (a
/// value of `3.4e-5` estimated at `1.6e-8 +- 1.4e-8` with 65 536 samples, and at
/// `3.4e-5 +- 2.6e-6` with 4 million), which the standard error cannot show and the bound on
/// each step's contribution can.
/// A give-up (`Undecidable`) is counted and must stay below 1% of the queries here (the census
/// measures the rate per family).
#[test]
fn glossy_lobes_at_grazing_views_match_the_reference() {
    let mut rng = Rng::new(0x6_1055);
    let (mut checks, mut retests, mut gave_up, mut queries) = (0, 0, 0, 0);
    let mut failures = Vec::new();
    let mut worst = 0f64;
    for case in 0..glossy_cases() {
        let c = DVec3::new(
            rng.range(-0.5, 0.5),
            rng.range(-0.5, 0.5),
            rng.range(1.5, 2.5),
        );
        let body = light_body(&mut rng, c, case);
        let occ = family_occluders(&mut rng, c, &body);
        let base = Scene::new(
            vec![Light::new(body, DVec3::new(1.0, 0.8, 0.6)).unwrap()],
            occ,
        )
        .unwrap();
        let meshes: Vec<&TriangleMesh> = std::iter::once(base.lights()[0].shape().mesh())
            .chain(base.occluders().iter().map(Body::mesh))
            .collect();
        for i in 0..16 {
            let x = DVec3::new(rng.range(-2.0, 2.0), rng.range(-2.0, 2.0), 0.0);
            let d = (edge_target(&mut rng, &meshes) - x).normalize();
            let cos_v = if i % 4 == 3 {
                rng.range(0.05, 1.0)
            } else {
                10f64.powf(rng.range(-4.0, -1.3))
            };
            // A normal at angle acos(cos_v) from d, and the view d reflected about it: the
            // mirror direction is d.
            let (t, b) = d.any_orthonormal_pair();
            let phi = rng.range(0.0, std::f64::consts::TAU);
            let n = d * cos_v + (t * phi.cos() + b * phi.sin()) * (1.0 - cos_v * cos_v).sqrt();
            let v = 2.0 * n.dot(d) * n - d;
            let roughness = [0.0, 0.003, 0.01, 0.03, 0.05][rng.below(5)];
            let albedo = if i % 2 == 0 { 0.0 } else { 0.5 };
            let f0 = if i % 3 == 0 { 1.0 } else { 0.04 };
            let m = Material::new(DVec3::splat(albedo), DVec3::splat(f0), roughness).unwrap();
            let est = |samples: u32, seed: u64| -> Estimate {
                MonteCarlo::new(samples, ReferenceBrdf::Ltc)
                    .with_sampling(LightSampling::Faces)
                    .with_brdf_sampling()
                    .estimate(&base, x, n, v, &m, seed)
                    .unwrap()
            };
            let seed = (case * 100 + i) as u64;
            let most = hemisphere_bound(&base, (x, n, v), &m);
            let mut e = None;
            for method in [Method::Silhouette, Method::PerTriangle] {
                queries += 1;
                let a = match base.clone().with_method(method).shade(x, n, v, &m) {
                    Ok(a) => a,
                    Err(err) if err.is_undecidable() => {
                        gave_up += 1;
                        continue;
                    }
                    Err(err) => {
                        failures.push(format!("case {case} point {i} {method:?}: {err:?}"));
                        continue;
                    }
                };
                let agrees = |e: &Estimate, ch: usize| {
                    (a[ch] - e.mean[ch]).abs()
                        <= 4.5 * e.std_error[ch] + 1e-6 * a[ch] + 1e-9 * most[ch]
                };
                checks += 1;
                let first = *e.get_or_insert_with(|| est(4096, seed));
                for ch in 0..3 {
                    if first.std_error[ch] > 0.0 {
                        worst = worst.max((a[ch] - first.mean[ch]).abs() / first.std_error[ch]);
                    }
                }
                if !(0..3).all(|ch| agrees(&first, ch)) {
                    retests += 1;
                    let second = est(16 * 4096, !seed);
                    let hw = second.bernstein_halfwidth(1e-6);
                    let holds = |ch: usize| {
                        (a[ch] - second.mean[ch]).abs() <= hw[ch] + 1e-6 * a[ch] + 1e-9 * most[ch]
                    };
                    for ch in (0..3).filter(|&ch| !holds(ch)) {
                        failures.push(format!(
                            "case {case} point {i} {method:?} ch {ch} (roughness {roughness}, \
                             cos_v {cos_v:.2e}): analytic {} mc {} +- {}, then {} +- {} \
                             (Bernstein {})\n  x {x:?} n {n:?} v {v:?}",
                            a[ch],
                            first.mean[ch],
                            first.std_error[ch],
                            second.mean[ch],
                            second.std_error[ch],
                            hw[ch]
                        ));
                    }
                }
            }
        }
    }
    eprintln!(
        "{queries} queries, {gave_up} give-ups, {checks} Monte Carlo checks ({retests} \
         re-estimated; largest first deviation {worst:.2} standard errors), {} failures",
        failures.len()
    );
    assert!(failures.is_empty(), "{}", failures.join("\n"));
    assert!(gave_up * 100 < queries, "{gave_up} give-ups in {queries}");
}
