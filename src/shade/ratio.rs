//! The ratio estimator of Heitz, Hill and McGuire (\[HHM18\]), the stochastic-shadow baseline
//! seed 000 compares against (section 4.2, figure 6): the analytic unshadowed shading times a
//! Monte Carlo estimate of the shadowed-to-unshadowed ratio.
//!
//! Per light `i` and RGB channel, with `U_i` the analytic unshadowed radiance (the LTC integrals
//! over the light's unoccluded region, exactly [`LightShading::unshadowed`] of
//! [`Scene::shade_per_light`]) and `n` directions `l_k` drawn uniformly by solid angle over the
//! same region ([`LightSampling`]):
//!
//! `L_i = U_i * R_i`, `R_i = sum_k f(l_k) V(l_k) / sum_k f(l_k)`,
//!
//! `f` the BRDF times the cosine ([`ReferenceBrdf`]) and `V` the exact visibility of the light's
//! surface along `l_k` past every other object (the Monte Carlo reference's ray tests). Seed
//! 000's `U * SN / UN` is this with the shadowed (`SN`) and unshadowed (`UN`) estimates from the
//! same samples. The same samples make the numerator and denominator correlated, which is the
//! point: where a light is unoccluded `R_i = 1` exactly and the result is the analytic value,
//! noise-free; noise appears only in penumbrae.
//!
//! # What it estimates
//!
//! `R_i` is a ratio of two sample means, so it is consistent but not unbiased: it converges to
//! `S_i / U'_i` (`S_i = integral of f V`, `U'_i = integral of f` over the region, for the
//! sampled BRDF), but its expectation for finite `n` is that of a ratio, not the ratio of the
//! expectations; the bias is `O(1 / n)`, below the noise (`O(1 / sqrt(n))`) for any `n` worth
//! using. For one sample, `R_i` is `V(l_1)`, whose expectation is the fraction of the region's
//! *solid angle* that is visible, whatever the BRDF (`tests/shade_ratio.rs` checks this
//! identity). The limit is:
//!
//! - with [`ReferenceBrdf::Ltc`] (the BRDF the analytic path integrates), `U'_i = U_i`, so
//!   `L_i -> S_i`: the analytic shadowed radiance of [`Scene::shade`];
//! - with [`ReferenceBrdf::True`] (what a renderer would use, and what seed 000 compares), the
//!   LTC unshadowed radiance scaled by the true BRDF's shadow ratio: exact where the light is
//!   unoccluded (up to the LTC fit), the \[HHM18\] approximation in penumbrae.
//!
//! The standard error is the delta method's: `Var(R) ~ sum_k (y_k - R x_k)^2 / (n (n - 1) xbar^2)`
//! with `x_k = f(l_k) / pdf`, `y_k = x_k V(l_k)`; since `V` is 0 or 1 the sum is
//! `(1 - R)^2 sum_{V=1} x_k^2 + R^2 sum_{V=0} x_k^2`, formed without cancellation.
//!
//! # References
//!
//! - \[HHM18\] E. Heitz, S. Hill, M. McGuire. *Combining analytic direct illumination and
//!   stochastic shadows.* I3D 2018.

use alloc::vec::Vec;

use glam::DVec3;

use super::material::Material;
use super::query::{ShadeContext, region_integrals, specular_setup};
use super::reference::{
    Estimate, LightDomain, LightSampling, Outcome, Pcg32, PointSampler, ReferenceBrdf,
};
use super::scene::Scene;
use crate::GeomError;
use crate::math::sqrt;
use crate::visibility::Visibility;

#[cfg(doc)]
use super::query::LightShading;

/// Ratio estimator settings (see the [module documentation](crate::shade::ratio)).
///
/// # Examples
///
/// ```
/// use arealight::glam::DVec3;
/// use arealight::shade::{
///     ConvexPolyhedron, Light, Material, RatioEstimator, ReferenceBrdf, Scene, TriangleMesh,
/// };
/// let quad = TriangleMesh::quad(DVec3::new(0.0, 0.0, 3.0), DVec3::Y * 0.5, DVec3::X * 0.5)?;
/// let cube = ConvexPolyhedron::cuboid(DVec3::new(0.3, 0.0, 1.5), DVec3::splat(0.25))?;
/// let scene = Scene::new(vec![Light::new(quad, DVec3::ONE)?], vec![cube.into()])?;
/// let floor = Material::new(DVec3::splat(0.8), DVec3::splat(0.04), 0.5)?;
/// let (n, v) = (DVec3::Z, DVec3::new(0.3, 0.0, 1.0));
/// let ratio = RatioEstimator::new(256, ReferenceBrdf::Ltc);
/// // Far from the cube's shadow the light is unoccluded: the ratio is 1, the value analytic.
/// let lit = DVec3::new(-2.0, 0.0, 0.0);
/// let e = ratio.estimate(&scene, lit, n, v, &floor, 7)?;
/// assert_eq!(e.std_error, DVec3::ZERO);
/// assert!((e.mean - scene.shade(lit, n, v, &floor)?).abs().max_element() < 1e-12);
/// // In the penumbra it is a noisy estimate of the analytic shadowed value.
/// let e = ratio.estimate(&scene, DVec3::ZERO, n, v, &floor, 7)?;
/// let exact = scene.shade(DVec3::ZERO, n, v, &floor)?;
/// assert!(((e.mean - exact).abs() - 5.0 * e.std_error).max_element() <= 0.0);
/// # Ok::<(), arealight::GeomError>(())
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct RatioEstimator {
    /// Samples per light.
    pub samples_per_light: u32,
    /// The BRDF of the sampled ratio.
    pub brdf: ReferenceBrdf,
    /// Where directions towards each light are drawn.
    pub sampling: LightSampling,
}

/// One light's share of a ratio estimate ([`RatioEstimator::estimate_lights`]), per RGB channel.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct LightRatio {
    /// The analytic unshadowed radiance `U` (equal to [`LightShading::unshadowed`]).
    pub unshadowed: DVec3,
    /// The estimated shadow ratio `R` in `[0, 1]` (1 where no sample met the light with a
    /// non-zero BRDF: no evidence of a shadow).
    pub ratio: DVec3,
    /// The delta-method standard error of `ratio` (0 for a single sample).
    pub ratio_std_error: DVec3,
    /// Whether [`LightSampling::Silhouette`] gave up for this light at this point (its
    /// triangulation returned [`GeomError::Undecidable`]) and the ratio was sampled over the
    /// light's faces instead: still unbiased, only noisier.
    pub fell_back: bool,
}

impl LightRatio {
    /// The light's estimated radiance, `U * R`.
    #[must_use]
    pub fn radiance(&self) -> DVec3 {
        self.unshadowed * self.ratio
    }
}

impl RatioEstimator {
    /// Settings with `samples_per_light` samples per light, the given BRDF and the default
    /// [`LightSampling::Silhouette`] (the region `U` is integrated over, so the two factors
    /// see the same directions).
    #[must_use]
    pub fn new(samples_per_light: u32, brdf: ReferenceBrdf) -> Self {
        RatioEstimator {
            samples_per_light,
            brdf,
            sampling: LightSampling::Silhouette,
        }
    }

    /// The same settings drawing directions by `sampling`.
    #[must_use]
    pub fn with_sampling(mut self, sampling: LightSampling) -> Self {
        self.sampling = sampling;
        self
    }

    /// The estimated radiance at `point` (the arguments of [`Scene::shade`]) with the random
    /// sequence given by `seed`: the sum over lights of `U * R`, with the standard error from
    /// the delta method (see the [module documentation](crate::shade::ratio)).
    ///
    /// # Errors
    ///
    /// As [`Scene::shade_per_light`]: input faults of the arguments, and
    /// [`GeomError::Undecidable`] where a light's unoccluded region cannot be decided (then
    /// there is no analytic factor; fall back to [`super::MonteCarlo`]).
    pub fn estimate(
        &self,
        scene: &Scene,
        point: DVec3,
        normal: DVec3,
        view: DVec3,
        material: &Material,
        seed: u64,
    ) -> Result<Estimate, GeomError> {
        let mut mean = DVec3::ZERO;
        let mut var = DVec3::ZERO;
        let mut fallbacks = 0;
        for r in self.estimate_lights(scene, point, normal, view, material, seed)? {
            mean += r.radiance();
            let s = r.unshadowed * r.ratio_std_error;
            var += s * s;
            fallbacks += u32::from(r.fell_back);
        }
        Ok(Estimate {
            mean,
            std_error: DVec3::new(sqrt(var.x), sqrt(var.y), sqrt(var.z)),
            samples: self.samples_per_light.max(1),
            // A ratio of two means, not a mean of bounded steps: no Bernstein interval.
            sample_bound: DVec3::INFINITY,
            fallbacks,
        })
    }

    /// Every light's analytic factor and estimated ratio, in the order of [`Scene::lights`].
    ///
    /// # Errors
    ///
    /// As [`RatioEstimator::estimate`].
    pub fn estimate_lights(
        &self,
        scene: &Scene,
        point: DVec3,
        normal: DVec3,
        view: DVec3,
        material: &Material,
        seed: u64,
    ) -> Result<Vec<LightRatio>, GeomError> {
        let ps = PointSampler::new(scene, point, normal, view, material, self.brdf)?;
        let frame = ps.frame();
        let spec = specular_setup(frame, material)?;
        let mut rng = Pcg32::new(seed, 0x7a71);
        let n = self.samples_per_light.max(1);
        let mut domain = LightDomain::default();
        let mut out = Vec::with_capacity(scene.lights().len());
        let mut ctx = ShadeContext::new();
        for (li, light) in scene.lights().iter().enumerate() {
            // Two-sided lights seen from behind live in the turned-around backend.
            let vis = scene.light_visibility(li, frame);
            let pieces = vis.unoccluded_region(li, frame)?;
            // The analytic factor, as `Scene::shade_per_light` forms it (from the same path,
            // so that the two agree bit for bit).
            let (d, s) = region_integrals(vis, li, frame, &spec, false, &mut ctx)?;
            let rgb = light.radiance();
            let mut unshadowed = material.albedo() * d * rgb;
            if let Some((_, scale)) = spec {
                unshadowed += scale * s * rgb;
            }
            let mut r = LightRatio {
                unshadowed,
                ratio: DVec3::ONE,
                ratio_std_error: DVec3::ZERO,
                fell_back: false,
            };
            if self.sampling == LightSampling::Faces {
                ps.faces_domain(li, &mut domain);
            } else {
                r.fell_back = ps.silhouette_domain(li, Ok(&pieces), &mut domain);
            }
            if domain.is_empty() || pieces.is_empty() {
                out.push(r);
                continue;
            }
            let total = domain.total();
            // x = f / pdf over all samples; y = x where visible. The squares of x split by V.
            let (mut sx, mut sy) = (DVec3::ZERO, DVec3::ZERO);
            let (mut sq_seen, mut sq_hidden) = (DVec3::ZERO, DVec3::ZERO);
            for _ in 0..n {
                let (l, outcome) = ps.trace(li, &domain, rng.next_2d());
                let x = match outcome {
                    Outcome::Miss => continue,
                    _ => ps.brdf(l) * total,
                };
                sx += x;
                if outcome == Outcome::Visible {
                    sy += x;
                    sq_seen += x * x;
                } else {
                    sq_hidden += x * x;
                }
            }
            let nf = f64::from(n);
            for c in 0..3 {
                if !(sx[c] > 0.0) {
                    continue;
                }
                let ratio = (sy[c] / sx[c]).clamp(0.0, 1.0);
                r.ratio[c] = ratio;
                if n > 1 {
                    let q =
                        (1.0 - ratio) * (1.0 - ratio) * sq_seen[c] + ratio * ratio * sq_hidden[c];
                    r.ratio_std_error[c] = sqrt(q * nf / (nf - 1.0)) / sx[c];
                }
            }
            out.push(r);
        }
        Ok(out)
    }
}
