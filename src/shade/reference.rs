//! A Monte Carlo estimator of the radiance [`Scene::shade`] computes, for tests and comparisons.
//!
//! Each light is sampled by solid angle over its front-facing triangles (Arvo's spherical
//! triangle sampling, [`SphericalTriangle`]; thesis 003 section 6), a triangle chosen with
//! probability proportional to its solid angle, so every sample has density `1 / Omega` with
//! `Omega` the summed solid angle. Visibility is exact and brute force, the same opacity model as
//! [`Scene`]'s: the sample's ray is intersected with every triangle of every occluder and of
//! every other light (no culling and no separating planes, so the analytic path's shortcuts are
//! checked too), and of the light's own mesh for mesh lights (self-occlusion); any hit strictly
//! before the sampled point on the light blocks the sample. The estimator returns its mean and
//! standard error, so tests can state a confidence bound.
//!
//! Lights bounded by Bezier curves are sampled uniformly by area over the exact curved region
//! (rejection from its bounding box), with the same visibility test.
//!
//! Only the outer (front) side of a light emits: a shading point inside a closed light sees none
//! of its triangles from the front and gets nothing here, where the analytic silhouette path
//! counts the whole sphere (the one configuration where the two differ; no scene meant for
//! rendering has it).

use alloc::vec::Vec;

use glam::{DVec2, DVec3};

use super::material::Material;
use super::scene::Scene;
use crate::GeomError;
use crate::ltc::{Ltc, lookup};
use crate::math::sqrt;
use crate::solid::{Body, BoundingSphere, ShadingFrame, TriangleMesh};
use crate::sphere::SphericalTriangle;

/// PCG32 (O'Neill 2014, `XSH RR` output): a small, fast, deterministic generator, so that the
/// crate needs no RNG dependency and every estimate is reproducible from its seed.
#[derive(Debug, Clone)]
pub(crate) struct Pcg32 {
    state: u64,
    inc: u64,
}

impl Pcg32 {
    /// A generator for `seed` on stream `stream` (different streams are independent sequences).
    #[must_use]
    pub(crate) fn new(seed: u64, stream: u64) -> Self {
        let mut r = Pcg32 {
            state: 0,
            inc: (stream << 1) | 1,
        };
        r.next_u32();
        r.state = r.state.wrapping_add(seed);
        r.next_u32();
        r
    }

    /// The next 32 random bits.
    pub(crate) fn next_u32(&mut self) -> u32 {
        let old = self.state;
        self.state = old
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(self.inc);
        let xorshifted = (((old >> 18) ^ old) >> 27) as u32;
        let rot = (old >> 59) as u32;
        xorshifted.rotate_right(rot)
    }

    /// Uniform in `[0, 1)` with 53 random bits.
    pub(crate) fn next_f64(&mut self) -> f64 {
        let hi = u64::from(self.next_u32()) << 21;
        let lo = u64::from(self.next_u32()) >> 11;
        ((hi | lo) as f64) * (1.0 / (1u64 << 53) as f64)
    }

    /// Two uniform numbers in `[0, 1)`.
    pub(crate) fn next_2d(&mut self) -> DVec2 {
        DVec2::new(self.next_f64(), self.next_f64())
    }
}

/// Which BRDF the Monte Carlo estimator integrates.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum ReferenceBrdf {
    /// The BRDF as the analytic path models it: Lambert plus the LTC distribution scaled by the
    /// table's Fresnel-weighted norm. The estimate then differs from [`Scene::shade`] only by
    /// visibility (and noise), which isolates the geometry.
    Ltc,
    /// The true BRDF ([`Material::eval_cos`]): the ground truth, LTC fitting error included.
    True,
}

/// A Monte Carlo estimate: the mean and its standard error, per RGB channel.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Estimate {
    /// The estimated radiance.
    pub mean: DVec3,
    /// The estimated standard deviation of `mean` (sample standard deviation over `sqrt(n)`).
    pub std_error: DVec3,
}

/// Monte Carlo estimator settings.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct MonteCarlo {
    /// Samples per light.
    pub samples_per_light: u32,
    /// The BRDF integrated.
    pub brdf: ReferenceBrdf,
}

/// Relative distance along a ray below which a hit counts as the ray's own start or end point:
/// rays start on surfaces and end on the light, and both ends must not block themselves.
pub(super) const RAY_EPS: f64 = 1e-9;

/// Möller–Trumbore ray-triangle intersection: the distance `t > 0` along `dir` (unit) from
/// `orig` to the triangle, if the ray hits it.
pub(super) fn ray_triangle(orig: DVec3, dir: DVec3, [a, b, c]: [DVec3; 3]) -> Option<f64> {
    let e1 = b - a;
    let e2 = c - a;
    let p = dir.cross(e2);
    let det = e1.dot(p);
    if det == 0.0 || !det.is_finite() {
        return None;
    }
    let inv = 1.0 / det;
    let s = orig - a;
    let u = s.dot(p) * inv;
    if !(0.0..=1.0).contains(&u) {
        return None;
    }
    let q = s.cross(e1);
    let v = dir.dot(q) * inv;
    if v < 0.0 || u + v > 1.0 {
        return None;
    }
    let t = e2.dot(q) * inv;
    (t > 0.0).then_some(t)
}

/// Whether the ray from `orig` along unit `dir` can meet the sphere `(c, r)` before `t_max`.
pub(super) fn ray_meets_sphere(orig: DVec3, dir: DVec3, c: DVec3, r: f64, t_max: f64) -> bool {
    let oc = c - orig;
    let along = oc.dot(dir);
    let d2 = oc.length_squared() - along * along;
    if d2 > r * r * (1.0 + 1e-9) + 1e-300 {
        return false;
    }
    // Nearest point of the sphere along the ray is before t_max.
    along - sqrt((r * r - d2).max(0.0)) < t_max
}

impl MonteCarlo {
    /// Settings with `samples_per_light` samples per light and the given BRDF.
    #[must_use]
    pub fn new(samples_per_light: u32, brdf: ReferenceBrdf) -> Self {
        MonteCarlo {
            samples_per_light,
            brdf,
        }
    }

    /// Estimates the radiance [`Scene::shade`] computes at `point` (same arguments), with the
    /// random sequence given by `seed`.
    ///
    /// # Errors
    ///
    /// Those of [`ShadingFrame::new`] and of the LTC lookup.
    pub fn estimate(
        &self,
        scene: &Scene,
        point: DVec3,
        normal: DVec3,
        view: DVec3,
        material: &Material,
        seed: u64,
    ) -> Result<Estimate, GeomError> {
        let frame = ShadingFrame::new(point, normal, view)?;
        let v = frame.view();
        let ltc = if self.brdf == ReferenceBrdf::Ltc && material.has_specular() {
            let look = lookup(v.z, material.alpha())?;
            let f0 = material.f0();
            let scale = DVec3::new(
                look.specular_scale(f0.x),
                look.specular_scale(f0.y),
                look.specular_scale(f0.z),
            );
            Some((Ltc::from_inverse(look.m_inv)?, scale))
        } else {
            None
        };
        let brdf = |l: DVec3| -> DVec3 {
            match self.brdf {
                ReferenceBrdf::True => material.eval_cos(v, l),
                ReferenceBrdf::Ltc => {
                    if l.z <= 0.0 {
                        return DVec3::ZERO;
                    }
                    let mut f = material.albedo() * (l.z / core::f64::consts::PI);
                    if let Some((d, scale)) = &ltc {
                        f += *scale * d.density(l);
                    }
                    f
                }
            }
        };
        let mut rng = Pcg32::new(seed, 0x5ade);
        let n = self.samples_per_light.max(1);
        let x = frame.origin();
        // Every object that can block a sample: the occluders, then the lights (a light is
        // skipped as a blocker of itself; its own mesh is checked separately when it is not
        // convex).
        let no = scene.occluders().len();
        let blockers: Vec<(&TriangleMesh, BoundingSphere)> = scene
            .occluders()
            .iter()
            .chain(scene.lights().iter().map(|l| l.shape()))
            .map(|o| (o.mesh(), o.mesh().bounding_sphere()))
            .collect();
        let mut mean = DVec3::ZERO;
        let mut var = DVec3::ZERO;
        let mut tris: Vec<(SphericalTriangle, usize)> = Vec::new();
        let mut cdf: Vec<f64> = Vec::new();
        for (li, light) in scene.lights().iter().enumerate() {
            if let Body::Bezier(shape) = light.shape() {
                // Curved lights: sampled by area over the exact curves (not their flattening).
                let (m, s2) = super::curved_reference::estimate(
                    shape,
                    &frame,
                    n,
                    &mut rng,
                    &brdf,
                    (&blockers, no + li),
                );
                mean += m * light.radiance();
                var += s2 * light.radiance() * light.radiance();
                continue;
            }
            let mesh = light.shape().mesh();
            tris.clear();
            cdf.clear();
            let mut total = 0.0;
            for i in 0..mesh.triangle_count() {
                let [a, b, c] = mesh.triangle(i);
                let centroid = (a + b + c) / 3.0;
                if mesh.triangle_normal(i).dot(x - centroid) <= 0.0 {
                    continue; // back face: emits nothing towards x
                }
                if let Ok(t) = SphericalTriangle::new(a - x, b - x, c - x) {
                    total += t.solid_angle();
                    tris.push((t, i));
                    cdf.push(total);
                }
            }
            if tris.is_empty() {
                continue;
            }
            let self_occluding = matches!(light.shape(), Body::Mesh(_));
            let (mut sum, mut sum2) = (DVec3::ZERO, DVec3::ZERO);
            for _ in 0..n {
                let pick = rng.next_f64() * total;
                let k = cdf.partition_point(|&c| c <= pick).min(tris.len() - 1);
                let (tri, ti) = tris[k];
                let w = tri.sample(rng.next_2d());
                let l = frame.dir_to_local(w);
                if l.z <= 0.0 {
                    continue;
                }
                let Some(t_light) = ray_triangle(x, w, mesh.triangle(ti)).or_else(|| {
                    // A sample on the triangle's boundary may miss it by rounding: take the
                    // distance to its plane.
                    let [a, ..] = mesh.triangle(ti);
                    let nn = mesh.triangle_normal(ti);
                    let den = nn.dot(w);
                    (den != 0.0)
                        .then(|| nn.dot(a - x) / den)
                        .filter(|t| *t > 0.0)
                }) else {
                    continue;
                };
                let t_max = t_light * (1.0 - RAY_EPS);
                let t_min = t_light * RAY_EPS;
                let blocked_by = |m: &TriangleMesh, skip: Option<usize>| {
                    (0..m.triangle_count()).any(|j| {
                        Some(j) != skip
                            && ray_triangle(x, w, m.triangle(j))
                                .is_some_and(|t| t > t_min && t < t_max)
                    })
                };
                let mut blocked = self_occluding && blocked_by(mesh, Some(ti));
                if !blocked {
                    for (j, &(m, bound)) in blockers.iter().enumerate() {
                        if j != no + li
                            && ray_meets_sphere(x, w, bound.center, bound.radius, t_max)
                            && blocked_by(m, None)
                        {
                            blocked = true;
                            break;
                        }
                    }
                }
                if blocked {
                    continue;
                }
                let f = brdf(l) * light.radiance() * total;
                sum += f;
                sum2 += f * f;
            }
            let nf = f64::from(n);
            let m = sum / nf;
            // Unbiased sample variance of one sample, over n for the mean.
            let s2 = if n > 1 {
                ((sum2 - sum * m) / (nf - 1.0)).max(DVec3::ZERO)
            } else {
                DVec3::ZERO
            };
            mean += m;
            var += s2 / nf;
        }
        Ok(Estimate {
            mean,
            std_error: DVec3::new(sqrt(var.x), sqrt(var.y), sqrt(var.z)),
        })
    }
}
