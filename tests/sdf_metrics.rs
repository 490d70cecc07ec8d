//! The image measures of the `sdf_shadows` example (demo/src/bin/sdf_shadows/metrics.rs): MAE and
//! RMSE against direct sums, SSIM against its closed form for constant images, against a
//! separate single-window evaluation written out term by term, and for its basic properties.

#[path = "../demo/src/bin/sdf_shadows/metrics.rs"]
mod metrics;
mod support;

use metrics::{Gray, SIGMA, WINDOW, mae, rmse, ssim};
use support::Rng;

fn random(rng: &mut Rng, w: usize, h: usize) -> Gray {
    Gray {
        width: w,
        height: h,
        data: (0..w * h).map(|_| rng.f64()).collect(),
    }
}

#[test]
fn mae_and_rmse_are_the_plain_means() {
    let a = Gray {
        width: 2,
        height: 2,
        data: vec![0.0, 1.0, 2.0, 3.0],
    };
    let b = Gray {
        width: 2,
        height: 2,
        data: vec![1.0, 1.0, 0.0, 3.0],
    };
    assert_eq!(mae(&a, &b, None), 0.75);
    assert!((rmse(&a, &b, None) - (5.0f64 / 4.0).sqrt()).abs() < 1e-15);
    let mask = [true, false, true, false];
    assert_eq!(mae(&a, &b, Some(&mask)), 1.5);
    assert!((rmse(&a, &b, Some(&mask)) - 2.5f64.sqrt()).abs() < 1e-15);
}

#[test]
fn ssim_of_constant_images_is_the_luminance_term() {
    // Constant images have zero variances and covariance: the structure term is C2 / C2 and
    // SSIM = (2 a b + C1) / (a^2 + b^2 + C1) in every window.
    for (a, b) in [(0.2, 0.7), (0.5, 0.5), (0.0, 1.0), (0.9, 0.1)] {
        let x = Gray {
            width: 20,
            height: 15,
            data: vec![a; 300],
        };
        let y = Gray {
            width: 20,
            height: 15,
            data: vec![b; 300],
        };
        let c1 = 1e-4;
        let want = (2.0 * a * b + c1) / (a * a + b * b + c1);
        assert!((ssim(&x, &y, 1.0).unwrap() - want).abs() < 1e-12);
    }
}

#[test]
fn ssim_of_one_window_matches_a_direct_evaluation() {
    let mut rng = Rng::new(41);
    for _ in 0..20 {
        let x = random(&mut rng, WINDOW, WINDOW);
        let noise = rng.f64();
        let y = Gray {
            width: WINDOW,
            height: WINDOW,
            data: x
                .data
                .iter()
                .map(|v| v + noise * (rng.f64() - 0.5))
                .collect(),
        };
        // Weighted statistics from the raw (unnormalized) Gaussian, divided by its sum at the end.
        let c = (WINDOW / 2) as f64;
        let (mut s, mut sx, mut sy, mut sxx, mut syy, mut sxy) = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0);
        for j in 0..WINDOW {
            for i in 0..WINDOW {
                let g = (-((i as f64 - c).powi(2) + (j as f64 - c).powi(2))
                    / (2.0 * SIGMA * SIGMA))
                    .exp();
                let (a, b) = (x.at(i, j), y.at(i, j));
                s += g;
                sx += g * a;
                sy += g * b;
                sxx += g * a * a;
                syy += g * b * b;
                sxy += g * a * b;
            }
        }
        let (mx, my) = (sx / s, sy / s);
        let (vx, vy, cxy) = (sxx / s - mx * mx, syy / s - my * my, sxy / s - mx * my);
        let (c1, c2) = (1e-4, 9e-4);
        let want =
            (2.0 * mx * my + c1) * (2.0 * cxy + c2) / ((mx * mx + my * my + c1) * (vx + vy + c2));
        let got = ssim(&x, &y, 1.0).unwrap();
        assert!((got - want).abs() < 1e-12, "{got} vs {want}");
    }
}

#[test]
fn ssim_is_one_for_equal_images_symmetric_and_falls_with_noise() {
    let mut rng = Rng::new(42);
    let x = random(&mut rng, 40, 30);
    assert!((ssim(&x, &x, 1.0).unwrap() - 1.0).abs() < 1e-12);
    let mut last = 1.0;
    for amp in [0.01, 0.05, 0.2, 0.5] {
        let mut r2 = Rng::new(43);
        let y = Gray {
            width: 40,
            height: 30,
            data: x.data.iter().map(|v| v + amp * (r2.f64() - 0.5)).collect(),
        };
        let s = ssim(&x, &y, 1.0).unwrap();
        assert!((s - ssim(&y, &x, 1.0).unwrap()).abs() < 1e-12);
        assert!(s < last, "{s} after {last}");
        last = s;
    }
    assert!(ssim(&Gray::new(10, 30), &Gray::new(10, 30), 1.0).is_none());
}
