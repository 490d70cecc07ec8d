//! GGX BRDF and visible-normal sampler: energy, reciprocity, sampler density.

mod support;

use arealight::glam::{DVec2, DVec3};
use arealight::ltc::{ggx_brdf_cos, ggx_ndf, ggx_sample_vndf, ggx_vndf_pdf, ggx_vndf_weight};
use support::Rng;
use support::ltc::{histogram_sigma, sphere_quad, view};

fn mirror(v: DVec3) -> DVec3 {
    DVec3::new(-v.x, -v.y, v.z)
}

/// Directional albedo by deterministic quadrature about the mirror direction.
fn albedo_quad(v: DVec3, alpha: f64) -> f64 {
    sphere_quad(mirror(v), 3.0, 1200, 256, |l| ggx_brdf_cos(v, l, alpha))
}

#[test]
fn albedo_by_quadrature_is_at_most_one_and_matches_sampler_weights() {
    let mut rng = Rng::from_state(1);
    for &alpha in &[0.02, 0.1, 0.3, 0.6, 1.0] {
        for &c in &[1.0, 0.8, 0.5, 0.2, 0.05] {
            let v = view(c);
            let a = albedo_quad(v, alpha);
            assert!(
                a > 0.0 && a <= 1.0 + 1e-6,
                "alpha {alpha} cos {c}: albedo {a}"
            );
            // Sampler weights f cos / pdf = G2 / G1 average to the same albedo (stratified MC,
            // weights in [0, 1], so 64^2 samples give an error well below 1e-2).
            let n = 64;
            let mut mc = 0.0;
            for i in 0..n {
                for j in 0..n {
                    let u = DVec2::new(
                        (i as f64 + rng.f64()) / n as f64,
                        (j as f64 + rng.f64()) / n as f64,
                    );
                    if let Some((_, w)) = ggx_vndf_weight(v, alpha, u) {
                        assert!((0.0..=1.0 + 1e-12).contains(&w), "weight {w}");
                        mc += w;
                    }
                }
            }
            mc /= (n * n) as f64;
            assert!(
                (mc - a).abs() < 5e-3,
                "alpha {alpha} cos {c}: quadrature {a} vs MC {mc}"
            );
        }
    }
}

#[test]
fn albedo_tends_to_one_for_smooth_surfaces_at_normal_incidence() {
    // At alpha -> 0 and v = n, the only loss is shadowing towards l, which vanishes with alpha.
    let mut prev = 0.0;
    for &alpha in &[0.3, 0.1, 0.03, 0.01] {
        let a = albedo_quad(DVec3::Z, alpha);
        assert!(
            a > prev,
            "albedo must grow as alpha shrinks: {a} after {prev}"
        );
        prev = a;
    }
    assert!(
        prev > 0.995 && prev <= 1.0 + 1e-6,
        "albedo at alpha 0.01: {prev}"
    );
    // Rougher surfaces lose more energy at normal incidence (single scattering only).
    assert!(albedo_quad(DVec3::Z, 1.0) < albedo_quad(DVec3::Z, 0.5));
}

#[test]
fn brdf_is_reciprocal() {
    let mut rng = Rng::from_state(2);
    for _ in 0..2000 {
        let dir = |rng: &mut Rng| {
            let z = rng.range(0.01, 1.0);
            let phi = rng.range(0.0, 2.0 * std::f64::consts::PI);
            let s = (1.0 - z * z).sqrt();
            DVec3::new(s * phi.cos(), s * phi.sin(), z)
        };
        let v = dir(&mut rng);
        let l = dir(&mut rng);
        let alpha = rng.range(1e-3, 1.0);
        let f_vl = ggx_brdf_cos(v, l, alpha) / l.z;
        let f_lv = ggx_brdf_cos(l, v, alpha) / v.z;
        assert!(
            (f_vl - f_lv).abs() <= 1e-12 * f_vl.abs().max(1e-300),
            "{f_vl} vs {f_lv}"
        );
    }
}

#[test]
fn ndf_is_normalised_over_projected_area() {
    // integral of D(h) cos(theta_h) over the hemisphere of normals is 1 (Walter et al. 2007).
    for &alpha in &[0.01, 0.1, 0.5, 1.0] {
        let i = sphere_quad(DVec3::Z, 3.0, 1200, 8, |h| {
            if h.z > 0.0 {
                ggx_ndf(h, alpha) * h.z
            } else {
                0.0
            }
        });
        assert!((i - 1.0).abs() < 1e-4, "alpha {alpha}: {i}");
    }
}

#[test]
fn vndf_pdf_integrates_to_one() {
    for &alpha in &[0.01, 0.1, 0.4, 1.0] {
        for &c in &[1.0, 0.7, 0.3, 0.02] {
            let v = view(c);
            // At grazing view the lobe of reflected directions is strongly anisotropic: resolve
            // the azimuth finely.
            let i = sphere_quad(mirror(v), 3.0, 1200, 2048, |l| ggx_vndf_pdf(v, l, alpha));
            assert!((i - 1.0).abs() < 2e-3, "alpha {alpha} cos {c}: {i}");
        }
    }
}

#[test]
fn vndf_samples_follow_the_pdf() {
    // 200k samples in 10 x 12 polar bins about the mirror direction; every bin's frequency must be
    // within 5 binomial standard deviations of its quadrature probability.
    let mut rng = Rng::from_state(3);
    for &(alpha, c) in &[(0.05, 0.9), (0.3, 0.5), (0.8, 0.15)] {
        let v = view(c);
        let sigma = histogram_sigma(
            mirror(v),
            2.0,
            10,
            12,
            200_000,
            || ggx_sample_vndf(v, alpha, DVec2::new(rng.f64(), rng.f64())),
            |l| ggx_vndf_pdf(v, l, alpha),
        );
        assert!(
            sigma < 5.0,
            "alpha {alpha} cos {c}: worst bin {sigma} sigma"
        );
    }
}

#[test]
fn bad_input_does_not_panic() {
    assert!(ggx_brdf_cos(DVec3::new(f64::NAN, 0.0, 0.5), DVec3::Z, 0.2).is_nan());
    assert!(ggx_brdf_cos(DVec3::Z, DVec3::Z, 0.0).is_finite());
    assert_eq!(ggx_brdf_cos(-DVec3::Z, DVec3::Z, 0.2), 0.0);
    assert_eq!(ggx_vndf_pdf(DVec3::Z, -DVec3::Z, 0.2), 0.0);
    let l = ggx_sample_vndf(DVec3::Z, 0.0, DVec2::new(0.5, 0.5));
    assert!(l.is_finite());
}
