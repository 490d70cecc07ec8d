//! Image error measures for comparing an approximate rendering with the exact one: mean
//! absolute error, root mean square error and the structural similarity index (SSIM).
//!
//! SSIM follows Wang, Bovik, Sheikh and Simoncelli, *Image quality assessment: from error
//! visibility to structural similarity*, IEEE TIP 13(4), 2004, with their standard settings: a
//! circular-symmetric Gaussian window of standard deviation 1.5 pixels, truncated to 11 x 11 and
//! normalized to sum 1; `K1 = 0.01`, `K2 = 0.03` and dynamic range `L` given by the caller (1
//! for images scaled to `[0, 1]`); per window
//!
//! `SSIM = (2 mu_x mu_y + C1)(2 sigma_xy + C2) / ((mu_x^2 + mu_y^2 + C1)(sigma_x^2 + sigma_y^2 + C2))`
//!
//! with `C1 = (K1 L)^2`, `C2 = (K2 L)^2` and weighted means, variances and covariance; the index
//! is the mean over every window that lies entirely inside the image (no padding).
#![allow(dead_code)]

/// Side of the SSIM window.
pub const WINDOW: usize = 11;
/// Standard deviation of the SSIM window's Gaussian, in pixels.
pub const SIGMA: f64 = 1.5;

/// A single-channel image, row-major.
#[derive(Debug, Clone, PartialEq)]
pub struct Gray {
    pub width: usize,
    pub height: usize,
    pub data: Vec<f64>,
}

impl Gray {
    pub fn new(width: usize, height: usize) -> Self {
        Gray {
            width,
            height,
            data: vec![0.0; width * height],
        }
    }
    pub fn at(&self, x: usize, y: usize) -> f64 {
        self.data[y * self.width + x]
    }
}

/// Mean absolute difference over the pixels where `mask` is true (all if `None`).
pub fn mae(a: &Gray, b: &Gray, mask: Option<&[bool]>) -> f64 {
    let (sum, n) =
        masked(a, b, mask).fold((0.0, 0usize), |(s, n), (x, y)| (s + (x - y).abs(), n + 1));
    if n == 0 { 0.0 } else { sum / n as f64 }
}

/// Root mean square difference over the pixels where `mask` is true (all if `None`).
pub fn rmse(a: &Gray, b: &Gray, mask: Option<&[bool]>) -> f64 {
    let (sum, n) = masked(a, b, mask).fold((0.0, 0usize), |(s, n), (x, y)| {
        (s + (x - y) * (x - y), n + 1)
    });
    if n == 0 { 0.0 } else { (sum / n as f64).sqrt() }
}

fn masked<'a>(
    a: &'a Gray,
    b: &'a Gray,
    mask: Option<&'a [bool]>,
) -> impl Iterator<Item = (f64, f64)> + 'a {
    assert_eq!((a.width, a.height), (b.width, b.height));
    a.data
        .iter()
        .zip(&b.data)
        .enumerate()
        .filter(move |(i, _)| mask.is_none_or(|m| m[*i]))
        .map(|(_, (&x, &y))| (x, y))
}

/// The normalized Gaussian window, row-major `WINDOW x WINDOW`.
pub fn gaussian_window() -> Vec<f64> {
    let c = (WINDOW / 2) as f64;
    let mut w: Vec<f64> = (0..WINDOW * WINDOW)
        .map(|i| {
            let (x, y) = ((i % WINDOW) as f64 - c, (i / WINDOW) as f64 - c);
            (-(x * x + y * y) / (2.0 * SIGMA * SIGMA)).exp()
        })
        .collect();
    let sum: f64 = w.iter().sum();
    w.iter_mut().for_each(|v| *v /= sum);
    w
}

/// Mean SSIM of `a` against `b` with dynamic range `range` (see the module docs). Images smaller
/// than the window have no window: `None`.
pub fn ssim(a: &Gray, b: &Gray, range: f64) -> Option<f64> {
    assert_eq!((a.width, a.height), (b.width, b.height));
    if a.width < WINDOW || a.height < WINDOW {
        return None;
    }
    let w = gaussian_window();
    let c1 = (0.01 * range).powi(2);
    let c2 = (0.03 * range).powi(2);
    let (mut sum, mut count) = (0.0, 0usize);
    for y0 in 0..=a.height - WINDOW {
        for x0 in 0..=a.width - WINDOW {
            let (mut mx, mut my) = (0.0, 0.0);
            for j in 0..WINDOW {
                for i in 0..WINDOW {
                    let k = w[j * WINDOW + i];
                    mx += k * a.at(x0 + i, y0 + j);
                    my += k * b.at(x0 + i, y0 + j);
                }
            }
            let (mut vx, mut vy, mut cxy) = (0.0, 0.0, 0.0);
            for j in 0..WINDOW {
                for i in 0..WINDOW {
                    let k = w[j * WINDOW + i];
                    let (dx, dy) = (a.at(x0 + i, y0 + j) - mx, b.at(x0 + i, y0 + j) - my);
                    vx += k * dx * dx;
                    vy += k * dy * dy;
                    cxy += k * dx * dy;
                }
            }
            sum += (2.0 * mx * my + c1) * (2.0 * cxy + c2)
                / ((mx * mx + my * my + c1) * (vx + vy + c2));
            count += 1;
        }
    }
    Some(sum / count as f64)
}
