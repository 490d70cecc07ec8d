//! Solid-angle sampling of spherical triangles (Arvo 1995): samples land in the triangle and are
//! uniform in solid angle. Fixed seeds; the confidence bounds are 4 sigma of the estimators.

use arealight::GeomError;
use arealight::glam::{DVec2, DVec3};
use arealight::ltc::clamped_cosine_integral;
use arealight::sphere::{SphericalPolygon, SphericalTriangle};
use std::f64::consts::PI;
use support::Rng;
use support::sphere::polar;

mod support;

/// A random counter-clockwise triangle of angular radius about `rho` around a direction in the
/// upper hemisphere, entirely above the horizon.
fn triangle(rng: &mut Rng, rho: f64) -> [DVec3; 3] {
    let z_min = (rho + 0.05).sin().max(0.1);
    let z = z_min + (1.0 - z_min) * rng.f64();
    let phi = 2.0 * PI * rng.f64();
    let r = (1.0 - z * z).sqrt();
    let c = DVec3::new(r * phi.cos(), r * phi.sin(), z);
    let t0 = 2.0 * PI * rng.f64();
    let gaps = [0.5 + rng.f64(), 0.5 + rng.f64(), 0.5 + rng.f64()];
    let s: f64 = gaps.iter().sum();
    let t1 = t0 + 2.0 * PI * gaps[0] / s;
    let t2 = t1 + 2.0 * PI * gaps[1] / s;
    [
        polar(c, rho, t0),
        polar(c, rho * (0.5 + 0.5 * rng.f64()), t1),
        polar(c, rho, t2),
    ]
}

#[test]
fn samples_are_inside_and_cosine_mean_matches_baum() {
    let mut rng = Rng::new(701);
    for (k, rho) in [0.9, 0.5, 0.1, 1e-3]
        .into_iter()
        .cycle()
        .take(24)
        .enumerate()
    {
        let [a, b, c] = triangle(&mut rng, rho);
        let tri = SphericalTriangle::new(a, b, c).unwrap();
        let poly = SphericalPolygon::new(vec![vec![a, b, c]]).unwrap();
        assert!((tri.solid_angle() - poly.solid_angle()).abs() <= 1e-12 * poly.solid_angle());
        let n = 20_000;
        let (mut s, mut s2) = (0.0, 0.0);
        for _ in 0..n {
            let w = tri.sample(rng.point2());
            assert!((w.length() - 1.0).abs() < 1e-12);
            // Inside, up to rounding on the boundary: every edge plane has w on its left.
            for (p, q) in [(a, b), (b, c), (c, a)] {
                assert!(
                    p.cross(q).normalize().dot(w) > -1e-12 * rho.max(1e-3),
                    "case {k}"
                );
            }
            s += w.z;
            s2 += w.z * w.z;
        }
        let nf = n as f64;
        let mean = s / nf;
        let sigma = ((s2 / nf - mean * mean).max(0.0) / nf).sqrt();
        // Uniform over the triangle: E[z] = (integral of z) / Omega = pi E / Omega.
        let expect = PI * clamped_cosine_integral(&poly) / poly.solid_angle();
        assert!(
            (mean - expect).abs() <= 4.0 * sigma + 1e-12,
            "case {k}: mean {mean} expect {expect} sigma {sigma}"
        );
    }
}

#[test]
fn sub_triangle_counts_follow_their_areas() {
    // Split into four by the edge midpoints; the counts must be binomial with p = area share.
    let mut rng = Rng::new(1102);
    for _ in 0..8 {
        let [a, b, c] = triangle(&mut rng, 0.7);
        let tri = SphericalTriangle::new(a, b, c).unwrap();
        let (ab, bc, ca) = (
            (a + b).normalize(),
            (b + c).normalize(),
            (c + a).normalize(),
        );
        let parts = [[a, ab, ca], [ab, b, bc], [ca, bc, c], [ab, bc, ca]];
        let polys: Vec<SphericalPolygon> = parts
            .iter()
            .map(|p| SphericalPolygon::new(vec![p.to_vec()]).unwrap())
            .collect();
        let n = 40_000;
        let mut counts = [0usize; 4];
        for _ in 0..n {
            let w = tri.sample(rng.point2());
            if let Some(i) = polys.iter().position(|p| p.contains(w)) {
                counts[i] += 1;
            }
        }
        for (p, &cnt) in polys.iter().zip(&counts) {
            let prob = p.solid_angle() / tri.solid_angle();
            let sigma = (n as f64 * prob * (1.0 - prob)).sqrt();
            assert!(
                (cnt as f64 - n as f64 * prob).abs() <= 4.0 * sigma,
                "count {cnt} expected {}",
                n as f64 * prob
            );
        }
    }
}

#[test]
fn degenerate_triangles_are_errors() {
    assert!(matches!(
        SphericalTriangle::new(DVec3::X, DVec3::X, DVec3::Y),
        Err(GeomError::Degenerate(_))
    ));
    assert_eq!(
        SphericalTriangle::new(DVec3::X, DVec3::NAN, DVec3::Y),
        Err(GeomError::NonFinite { ring: 0, vertex: 1 })
    );
    assert_eq!(
        SphericalTriangle::new(DVec3::X, DVec3::ZERO, DVec3::Y),
        Err(GeomError::ZeroVector { ring: 0, vertex: 1 })
    );
    let t = SphericalTriangle::new(DVec3::X, DVec3::Y, DVec3::Z).unwrap();
    // Out-of-range uniforms are clamped, never NaN.
    assert!(t.sample(DVec2::new(2.0, -1.0)).is_finite());
}
