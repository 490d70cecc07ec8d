//! Quadrature about a pole for peaked integrands, and histogram checks of samplers against their
//! densities.

use arealight::glam::{DMat3, DVec3};
use std::f64::consts::PI;

/// An orthonormal frame whose third column is `pole`.
pub fn frame(pole: DVec3) -> DMat3 {
    let z = pole.normalize();
    let a = if z.x.abs() < 0.9 { DVec3::X } else { DVec3::Y };
    let x = a.cross(z).normalize();
    DMat3::from_cols(x, z.cross(x), z)
}

/// Midpoint quadrature of `f` over the whole sphere, in polar coordinates about `pole` with the
/// polar angle `theta = pi s^p` (points concentrated near the pole, for peaked integrands).
/// `ns` x `nphi` nodes.
pub fn sphere_quad(pole: DVec3, p: f64, ns: usize, nphi: usize, f: impl Fn(DVec3) -> f64) -> f64 {
    let fr = frame(pole);
    let mut sum = 0.0;
    for i in 0..ns {
        let s = (i as f64 + 0.5) / ns as f64;
        let theta = PI * s.powf(p);
        let dtheta = PI * p * s.powf(p - 1.0) / ns as f64;
        let (st, ct) = theta.sin_cos();
        let mut ring = 0.0;
        for k in 0..nphi {
            let phi = 2.0 * PI * (k as f64 + 0.5) / nphi as f64;
            let (sp, cp) = phi.sin_cos();
            ring += f(fr * DVec3::new(st * cp, st * sp, ct));
        }
        sum += ring * st * dtheta * 2.0 * PI / nphi as f64;
    }
    sum
}

/// Polar coordinates `(s, phi)` of `w` about `pole`, matching [`sphere_quad`] with exponent `p`:
/// `s = (theta / pi)^(1/p)` in [0, 1], `phi` in [0, 2 pi).
pub fn polar(pole: DVec3, p: f64, w: DVec3) -> (f64, f64) {
    let fr = frame(pole);
    let l = fr.transpose() * w;
    let theta = l.z.clamp(-1.0, 1.0).acos();
    let phi = l.y.atan2(l.x).rem_euclid(2.0 * PI);
    ((theta / PI).powf(1.0 / p), phi)
}

/// View direction in the shading frame for `cos_theta`.
pub fn view(cos_theta: f64) -> DVec3 {
    DVec3::new(
        (1.0 - cos_theta * cos_theta).max(0.0).sqrt(),
        0.0,
        cos_theta,
    )
}

/// Per-bin histogram check: draws `n` samples, bins them in `bins_s` x `bins_phi` polar bins about
/// `pole` (exponent `p`), and compares each bin's frequency with its probability by quadrature of
/// `pdf`. Returns the largest deviation in units of the binomial standard deviation (plus a
/// small absolute floor of 1e-4 / sigma for near-empty bins).
pub fn histogram_sigma(
    pole: DVec3,
    p: f64,
    bins_s: usize,
    bins_phi: usize,
    n: usize,
    mut sample: impl FnMut() -> DVec3,
    pdf: impl Fn(DVec3) -> f64,
) -> f64 {
    let mut counts = vec![0usize; bins_s * bins_phi];
    for _ in 0..n {
        let (s, phi) = polar(pole, p, sample());
        let i = ((s * bins_s as f64) as usize).min(bins_s - 1);
        let k = ((phi / (2.0 * PI) * bins_phi as f64) as usize).min(bins_phi - 1);
        counts[i * bins_phi + k] += 1;
    }
    // Expected bin masses by quadrature (sub-gridded within each bin).
    let sub = 24;
    let fr = frame(pole);
    let mut worst: f64 = 0.0;
    for i in 0..bins_s {
        for k in 0..bins_phi {
            let mut mass = 0.0;
            for a in 0..sub {
                let s = (i as f64 + (a as f64 + 0.5) / sub as f64) / bins_s as f64;
                let theta = PI * s.powf(p);
                let dtheta = PI * p * s.powf(p - 1.0) / (bins_s * sub) as f64;
                let (st, ct) = theta.sin_cos();
                for b in 0..sub {
                    let phi =
                        2.0 * PI * (k as f64 + (b as f64 + 0.5) / sub as f64) / bins_phi as f64;
                    let (sp, cp) = phi.sin_cos();
                    let w = fr * DVec3::new(st * cp, st * sp, ct);
                    mass += pdf(w) * st * dtheta * 2.0 * PI / (bins_phi * sub) as f64;
                }
            }
            let freq = counts[i * bins_phi + k] as f64 / n as f64;
            let sigma = (mass.max(1e-12) * (1.0 - mass).max(0.0) / n as f64).sqrt();
            let dev = ((freq - mass).abs() - 1e-4).max(0.0) / sigma;
            worst = worst.max(dev);
        }
    }
    worst
}
