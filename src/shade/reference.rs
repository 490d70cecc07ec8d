//! A Monte Carlo estimator of the radiance [`Scene::shade`] computes, for tests and comparisons,
//! and the per-point sampling machinery it shares with the ratio estimator
//! ([`super::RatioEstimator`]).
//!
//! Each light is sampled uniformly by solid angle ([`LightSampling`]; both sides of a two-sided
//! light, [`super::Light::two_sided`]): by default over the part
//! of the sphere of directions it covers with every other object removed (its silhouette,
//! clipped to the upper hemisphere, without its self-occluded parts:
//! [`Visibility::unoccluded_region`]), triangulated ([`SphericalPolygon::triangulate`]) and
//! sampled triangle by triangle in proportion to solid angle (thesis 003 chapter 6, \[Arv95\]);
//! or over its front-facing triangles, which does not depend on the visibility layer at all.
//! Every sample has density `1 / Omega`, `Omega` the summed solid angle of the triangles.
//!
//! Visibility is exact and brute force, the same opacity model as [`Scene`]'s: the sample's ray
//! must meet the light first on a triangle that emits towards the point (its own nearer
//! triangles hide farther ones), and it is intersected with every triangle of every occluder
//! and of every other light whose bounding sphere it meets (no culling and no separating
//! planes, so the analytic path's shortcuts are checked too); any
//! hit strictly before the point the ray meets on the light blocks the sample, except on a
//! triangle whose plane holds the shading point (seen edge-on by the facing predicate, as in
//! the analytic path: a point on a surface is not hidden by it). The estimator
//! returns its mean and standard error, so tests can state a confidence bound.
//!
//! Lights bounded by Bezier curves are sampled uniformly by area over the exact curved region
//! (rejection from its bounding box; `curved_reference.rs`), whatever the [`LightSampling`], so
//! that the analytic path's per-point flattening is checked too; visibility as above.
//!
//! Near-mirror lobes (GGX roughness `0.05` and below, `alpha <= 0.0025`) are narrower than
//! anything light sampling resolves with a few thousand samples: the estimate and its standard
//! error both miss the peak. [`Techniques::LightAndBrdf`] adds a second technique per sample, a
//! direction drawn from the BRDF itself (the cosine lobe, and the LTC distribution
//! ([`crate::ltc::Ltc::sample`]) for [`ReferenceBrdf::Ltc`] or the GGX visible normals
//! ([`crate::ltc::ggx_sample_vndf`], \[Hei18\]) for [`ReferenceBrdf::True`]), and combines the
//! two by multiple importance sampling with the balance heuristic (\[Vea97\] section 9.2.2,
//! one sample per technique): each sample of either technique contributes
//! `f(l) V(l) / (p_light(l) + p_brdf(l))`, which is unbiased wherever either density is
//! positive and has bounded variance for any lobe width. The BRDF's samples are traced to the
//! light's nearest triangle (which must emit towards the point), so they also cover any part of
//! a light that a region of [`LightSampling::Silhouette`] would miss: there `p_light = 0` and
//! the BRDF sample counts whole.
//!
//! Which reference checks [`Scene::shade`]: the analytic path integrates the LTC lobe of the
//! table ([`crate::ltc::lookup`], scaled by [`crate::ltc::LtcLookup::specular_scale`]) and the
//! Lambertian lobe over the visible region exactly, so [`ReferenceBrdf::Ltc`] estimates the
//! same integral and any difference beyond the confidence bound is an error of the geometry
//! (visibility, clipping, integration). [`ReferenceBrdf::True`] estimates the true GGX
//! reflection instead; it differs from the analytic value by the table's fitting error as well,
//! which is checked separately (tests/ltc_robust.rs against brute-force VNDF albedos) and must
//! not be mistaken for a geometric error.
//!
//! Only the outer (front) side of a light emits: a shading point inside a closed light sees none
//! of its triangles from the front and gets nothing, here as on both analytic paths.
//!
//! # References
//!
//! - \[Vea97\] E. Veach. *Robust Monte Carlo methods for light transport simulation.* PhD
//!   thesis, Stanford, 1997 (chapter 9, multiple importance sampling).
//! - \[Hei18\] E. Heitz. *Sampling the GGX distribution of visible normals.* JCGT 7(4), 2018.

use alloc::vec::Vec;

use glam::{DVec2, DVec3};

use super::material::Material;
use super::scene::Scene;
use crate::ltc::{Ltc, cosine_sample, ggx_sample_vndf, ggx_vndf_pdf, lookup};
use crate::math::sqrt;
use crate::solid::{Body, BoundingSphere, ShadingFrame, Side, TriangleMesh, face_side};
use crate::sphere::{SphericalPolygon, SphericalTriangle};
use crate::visibility::Visibility;
use crate::{GeomError, IntoDVec3};

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

/// Where the estimators draw their directions towards a light.
///
/// Both are uniform in solid angle over a set of spherical triangles covering the directions in
/// which the light can contribute, so both are unbiased; they differ in how much of the set is
/// wasted and in what they take on trust.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[non_exhaustive]
pub enum LightSampling {
    /// The light's region with every other object removed, [`Visibility::unoccluded_region`]
    /// (its silhouette clipped to the upper hemisphere, self-occlusion of a non-convex mesh
    /// light removed), triangulated (thesis 003 chapter 6). No sample is wasted below the
    /// horizon or on a face the light hides itself, and a convex light costs a triangle fan of
    /// its silhouette instead of one triangle per front face (thesis 003 table 7.3). Where the
    /// region or its triangulation gives up ([`GeomError::Undecidable`]), that light falls back
    /// to [`LightSampling::Faces`] at that point.
    ///
    /// The region comes from the visibility layer the estimate is meant to check: a region that
    /// is too large only wastes samples (each ray must still meet the light's emitting side
    /// first), but a part of the light that the region misses would be missed by light samples
    /// and the analytic path alike; only the BRDF's samples of [`Techniques::LightAndBrdf`]
    /// reach it. Tests that check the analytic value use [`LightSampling::Faces`], which shares
    /// no code with the visibility and sphere layers; occlusion is checked independently either
    /// way.
    #[default]
    Silhouette,
    /// Every front-facing triangle of the light, projected, chosen in proportion to its solid
    /// angle: independent of the visibility layer. Samples that fall below the horizon or on
    /// faces hidden behind the light's own nearer faces are wasted (they count as zero).
    Faces,
}

/// Which sampling techniques the estimator draws each light's samples with.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[non_exhaustive]
pub enum Techniques {
    /// Directions towards the light only ([`LightSampling`]): enough for diffuse and moderately
    /// glossy lobes, blind to near-mirror ones.
    #[default]
    Light,
    /// Per sample, one direction towards the light and one drawn from the BRDF (the Lambertian
    /// lobe or the specular one, chosen at random in proportion to their weights), combined by
    /// multiple importance sampling with the balance heuristic (\[Vea97\] section 9.2; see the
    /// module documentation). Twice the rays of [`Techniques::Light`] per sample; resolves
    /// lobes of any width, down to [`crate::ltc::GGX_MIN_ALPHA`]. Lights bounded by Bezier
    /// curves are still sampled by area alone.
    LightAndBrdf,
}

/// A Monte Carlo estimate: the mean and its standard error, per RGB channel.
///
/// The standard error is itself estimated from the samples, so it misleads where the integrand
/// is concentrated on a set that few samples hit (a sliver of a light seen in a near-mirror
/// lobe: no sample may hit it, and the estimate and its error both read near zero). Where one
/// step's contribution has a known bound, [`Estimate::bernstein_halfwidth`] gives a confidence
/// interval that holds regardless.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Estimate {
    /// The estimated radiance.
    pub mean: DVec3,
    /// The estimated standard deviation of `mean` (sample standard deviation over `sqrt(n)`).
    pub std_error: DVec3,
    /// The number of steps `n` averaged (samples per light; a step of
    /// [`Techniques::LightAndBrdf`] is one sample of each technique).
    pub samples: u32,
    /// An upper bound on one step's contribution, summed over the lights (every step's value
    /// lies in `[0, sample_bound]`), or infinite where none is known (light sampling alone with
    /// a specular lobe, whose peak density is not bounded in advance; lights bounded by Bezier
    /// curves).
    pub sample_bound: DVec3,
    /// How many lights were sampled by their faces because [`LightSampling::Silhouette`] gave
    /// up at this point (the light's unoccluded region or its triangulation returned
    /// [`GeomError::Undecidable`]): the estimate is still unbiased, only noisier. Always 0
    /// with [`LightSampling::Faces`].
    pub fallbacks: u32,
}

impl Estimate {
    /// The half-width of a two-sided confidence interval for the true value around `mean`, of
    /// level at least `1 - delta`, that holds however skewed the steps' distribution is: the
    /// empirical Bernstein bound (Maurer and Pontil 2009, theorem 4, with `delta / 2` per side)
    /// for steps in `[0, B]`,
    ///
    /// ```text
    /// sqrt(2 V ln(4 / delta) / n) + 7 B ln(4 / delta) / (3 (n - 1)),
    /// ```
    ///
    /// with `V = n std_error^2` the steps' sample variance and `B` = [`Estimate::sample_bound`].
    /// Infinite where `B` is, or for fewer than two steps. (With several lights the steps'
    /// variance is taken as the sum of the lights', which it equals in expectation.)
    ///
    /// # References
    ///
    /// A. Maurer, M. Pontil. *Empirical Bernstein bounds and sample variance penalization.*
    /// COLT 2009.
    #[must_use]
    pub fn bernstein_halfwidth(&self, delta: f64) -> DVec3 {
        if self.samples < 2 {
            return DVec3::INFINITY;
        }
        let n = f64::from(self.samples);
        let log = crate::math::ln(4.0 / delta);
        let v = self.std_error * self.std_error * n;
        let spread = (v * (2.0 * log / n)).map(sqrt);
        spread + self.sample_bound * (7.0 * log / (3.0 * (n - 1.0)))
    }
}

/// Monte Carlo estimator settings.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct MonteCarlo {
    /// Samples per light.
    pub samples_per_light: u32,
    /// The BRDF integrated.
    pub brdf: ReferenceBrdf,
    /// Where directions towards each light are drawn.
    pub sampling: LightSampling,
    /// Whether the BRDF is sampled too ([`Techniques::LightAndBrdf`]).
    pub techniques: Techniques,
}

/// Relative distance along a ray, short of the point where it meets the light, within which a
/// hit counts as the light itself: rays end on the light and must not be blocked by it or by
/// blockers touching it.
///
/// The start needs no such margin and has none: a ray starting on a surface is not blocked by
/// that surface because the shading point lies in its plane, which [`face_side`] decides with
/// the tolerance the analytic path uses (a triangle seen edge-on covers nothing there, see
/// [`hits_before`]). A margin relative to the ray's length would instead let a ray through a
/// blocker triangle that the point lies a little behind: from a point `1.5e-11` inside a face
/// of an icosphere occluder, rays that meet a light face a few units away passed through that
/// face, and the estimate read 0.49 where the visible light gives 0.027.
const RAY_EPS: f64 = 1e-9;

/// How far outside a light triangle (in barycentric coordinates) a ray may pass and still count
/// as meeting it, when the nearest point of a non-convex mesh light along a sampled direction is
/// searched: directions sampled inside its region can graze a shared edge, where both
/// neighbours would reject the ray by rounding.
const LIGHT_HIT_SLACK: f64 = 1e-10;

/// Möller–Trumbore ray-triangle intersection: the distance `t > 0` along `dir` (unit) from
/// `orig` to the triangle, if the ray hits it within barycentric slack `slack`.
fn ray_triangle(orig: DVec3, dir: DVec3, [a, b, c]: [DVec3; 3], slack: f64) -> Option<f64> {
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
    if !(-slack..=1.0 + slack).contains(&u) {
        return None;
    }
    let q = s.cross(e1);
    let v = dir.dot(q) * inv;
    if v < -slack || u + v > 1.0 + slack {
        return None;
    }
    let t = e2.dot(q) * inv;
    (t > 0.0).then_some(t)
}

/// Whether the ray from `orig` along unit `dir` can meet the sphere `(c, r)` before `t_max`.
fn ray_meets_sphere(orig: DVec3, dir: DVec3, c: DVec3, r: f64, t_max: f64) -> bool {
    let oc = c - orig;
    let along = oc.dot(dir);
    let d2 = oc.length_squared() - along * along;
    if d2 > r * r * (1.0 + 1e-9) + 1e-300 {
        return false;
    }
    // Nearest point of the sphere along the ray is before t_max.
    along - sqrt((r * r - d2).max(0.0)) < t_max
}

/// What one sampled direction towards a light finds.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Outcome {
    /// The direction carries no light from this light even with every other object removed:
    /// below the horizon, past the light, on its back side or on one of its own faces that a
    /// nearer face of it hides.
    Miss,
    /// The light's emitting side, hidden by another object (an occluder or another light).
    Blocked,
    /// The light's emitting side, seen.
    Visible,
}

/// The BRDF times the cosine at a shading point, as a [`ReferenceBrdf`] defines it.
struct BrdfEval {
    kind: ReferenceBrdf,
    material: Material,
    /// The view in the shading frame.
    view: DVec3,
    /// The LTC distribution and its per-channel scale ([`ReferenceBrdf::Ltc`] with a specular
    /// lobe).
    ltc: Option<(Ltc, DVec3)>,
    /// The probability with which a BRDF sample is drawn from the Lambertian lobe (the rest
    /// from the specular one).
    p_diffuse: f64,
}

/// The smallest probability with which [`BrdfEval::sample`] picks a lobe that the material has:
/// the lobes' weights are only estimates of their shares, so neither is starved.
const MIN_LOBE_PICK: f64 = 0.25;

impl BrdfEval {
    fn eval(&self, l: DVec3) -> DVec3 {
        match self.kind {
            ReferenceBrdf::True => self.material.eval_cos(self.view, l),
            ReferenceBrdf::Ltc => {
                if l.z <= 0.0 {
                    return DVec3::ZERO;
                }
                let mut f = self.material.albedo() * (l.z / core::f64::consts::PI);
                if let Some((d, scale)) = &self.ltc {
                    f += *scale * d.density(l);
                }
                f
            }
        }
    }

    /// A bound on `f(l) / pdf(l)` per channel over all directions (per unit radiance): with
    /// `f = albedo cos / pi + s(l)` and `pdf = p_d cos / pi + (1 - p_d) p_s(l)`, the ratio is at
    /// most the larger of `albedo / p_d` and the specular lobe's `s / ((1 - p_d) p_s)`, which is
    /// the LTC scale over `1 - p_d` for [`ReferenceBrdf::Ltc`] (`s` is the scale times the
    /// density sampled) and at most `1 / (1 - p_d)` for [`ReferenceBrdf::True`] (Fresnel at most
    /// one, and `f_ggx cos / pdf_vndf = G2 / G1 <= 1`, \[Hei18\]).
    fn ratio_bound(&self) -> DVec3 {
        let diffuse = if self.p_diffuse > 0.0 {
            self.material.albedo() / self.p_diffuse
        } else {
            DVec3::ZERO
        };
        let specular = if self.p_diffuse < 1.0 {
            match (self.kind, &self.ltc) {
                (ReferenceBrdf::Ltc, Some((_, scale))) => *scale / (1.0 - self.p_diffuse),
                (ReferenceBrdf::Ltc, None) => DVec3::ZERO,
                (ReferenceBrdf::True, _) => DVec3::splat(1.0 / (1.0 - self.p_diffuse)),
            }
        } else {
            DVec3::ZERO
        };
        diffuse.max(specular)
    }

    /// A direction in the shading frame drawn from the BRDF's sampling density ([`Self::pdf`])
    /// with the uniform numbers `u` (the direction) and `pick` (the lobe), both in `[0, 1)`.
    /// It may lie below the horizon, where the BRDF is zero.
    fn sample(&self, u: DVec2, pick: f64) -> DVec3 {
        if pick < self.p_diffuse {
            return cosine_sample(u);
        }
        match (self.kind, &self.ltc) {
            (ReferenceBrdf::Ltc, Some((d, _))) => d.sample(u),
            _ => ggx_sample_vndf(self.view, self.material.alpha(), u),
        }
    }

    /// The density per unit solid angle (over the whole sphere) with which [`Self::sample`]
    /// draws `l`: the mixture of the cosine density and the specular lobe's sampling density.
    fn pdf(&self, l: DVec3) -> f64 {
        let diffuse = if l.z > 0.0 {
            l.z / core::f64::consts::PI
        } else {
            0.0
        };
        let specular = if self.p_diffuse < 1.0 {
            match (self.kind, &self.ltc) {
                (ReferenceBrdf::Ltc, Some((d, _))) => d.density(l),
                _ => ggx_vndf_pdf(self.view, l, self.material.alpha()),
            }
        } else {
            0.0
        };
        self.p_diffuse * diffuse + (1.0 - self.p_diffuse) * specular
    }
}

/// The probability of drawing a BRDF sample from the Lambertian lobe: the lobes' weights (the
/// largest diffuse albedo, the largest specular albedo the table gives at this view) in
/// proportion, each kept at least [`MIN_LOBE_PICK`] when the material has it; `1` without a
/// specular lobe, `0` without a diffuse one.
fn diffuse_pick(material: &Material, cos_v: f64) -> f64 {
    let wd = material.albedo().max_element();
    if !material.has_specular() {
        return 1.0;
    }
    if wd <= 0.0 {
        return 0.0;
    }
    let ws = lookup(cos_v, material.alpha()).map_or(material.f0().max_element(), |look| {
        let f0 = material.f0();
        look.albedo * look.specular_scale(f0.max_element()) / look.norm
    });
    if !(ws > 0.0) {
        return 1.0;
    }
    (wd / (wd + ws)).clamp(MIN_LOBE_PICK, 1.0 - MIN_LOBE_PICK)
}

/// The directions of one light at one shading point that samples are drawn from: spherical
/// triangles and their cumulative solid angles.
#[derive(Debug, Clone, Default)]
pub(crate) struct LightDomain {
    tris: Vec<SphericalTriangle>,
    /// Per triangle, the light triangle it is the projection of ([`LightSampling::Faces`]);
    /// empty for a region's triangulation.
    faces: Vec<usize>,
    /// `cdf[k]`: the solid angle of triangles `0..=k`.
    cdf: Vec<f64>,
    /// Whether the triangles are in the shading frame (a region of the visibility layer) or in
    /// world directions (projected faces).
    local: bool,
}

impl LightDomain {
    fn clear(&mut self, local: bool) {
        self.tris.clear();
        self.faces.clear();
        self.cdf.clear();
        self.local = local;
    }

    fn push(&mut self, t: SphericalTriangle) {
        let total = self.total() + t.solid_angle();
        self.tris.push(t);
        self.cdf.push(total);
    }

    /// The summed solid angle of the triangles: `1 / pdf`.
    pub(crate) fn total(&self) -> f64 {
        self.cdf.last().copied().unwrap_or(0.0)
    }

    /// Whether there is nothing to sample.
    pub(crate) fn is_empty(&self) -> bool {
        self.tris.is_empty()
    }

    /// The triangle `u.x` picks by cumulative solid angle, and `u` rescaled to it.
    fn pick(&self, u: DVec2) -> (usize, DVec2) {
        let total = self.total();
        let x = u.x.clamp(0.0, 1.0) * total;
        let k = self
            .cdf
            .partition_point(|&c| c <= x)
            .min(self.cdf.len() - 1);
        let lo = if k == 0 { 0.0 } else { self.cdf[k - 1] };
        let w = self.tris[k].solid_angle();
        (k, DVec2::new(((x - lo) / w).clamp(0.0, 1.0), u.y))
    }
}

/// Everything the estimators need at one shading point: the frame, the BRDF and the blockers.
pub(crate) struct PointSampler<'a> {
    scene: &'a Scene,
    frame: ShadingFrame,
    brdf: BrdfEval,
    /// Every object that can block a sample, occluders first, then lights (a light is skipped as
    /// a blocker of itself; its own mesh is checked separately when it is not convex).
    blockers: Vec<(&'a TriangleMesh, BoundingSphere)>,
}

impl<'a> PointSampler<'a> {
    /// The sampler at `point` (the arguments of [`Scene::shade`]) for the BRDF `brdf`.
    pub(crate) fn new(
        scene: &'a Scene,
        point: DVec3,
        normal: DVec3,
        view: DVec3,
        material: &Material,
        brdf: ReferenceBrdf,
    ) -> Result<Self, GeomError> {
        let frame = ShadingFrame::new(point, normal, view)?;
        let v = frame.view();
        let ltc = if brdf == ReferenceBrdf::Ltc && material.has_specular() {
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
        let blockers = scene
            .occluders()
            .iter()
            .chain(scene.lights().iter().map(|l| l.shape()))
            .map(|o| (o.mesh(), o.mesh().bounding_sphere()))
            .collect();
        Ok(PointSampler {
            scene,
            frame,
            brdf: BrdfEval {
                kind: brdf,
                material: *material,
                view: v,
                ltc,
                p_diffuse: diffuse_pick(material, v.z),
            },
            blockers,
        })
    }

    /// The shading frame.
    pub(crate) fn frame(&self) -> &ShadingFrame {
        &self.frame
    }

    /// The BRDF times the cosine for the direction `l` in the shading frame.
    pub(crate) fn brdf(&self, l: DVec3) -> DVec3 {
        self.brdf.eval(l)
    }

    /// A direction in the shading frame drawn from the BRDF ([`Techniques::LightAndBrdf`]), and
    /// the density it was drawn with.
    fn brdf_sample(&self, u: DVec2, pick: f64) -> (DVec3, f64) {
        let l = self.brdf.sample(u, pick);
        (l, self.brdf.pdf(l))
    }

    /// Fills `out` with the directions of light `light` to sample by `sampling` (see
    /// [`LightSampling`]); empty when the light can give nothing. `true` when
    /// [`LightSampling::Silhouette`] gave up and the faces were taken instead.
    pub(crate) fn domain(
        &self,
        light: usize,
        sampling: LightSampling,
        out: &mut LightDomain,
    ) -> bool {
        if sampling == LightSampling::Faces {
            self.faces_domain(light, out);
            return false;
        }
        let region = self
            .scene
            .light_visibility(light, &self.frame)
            .unoccluded_region(light, &self.frame);
        self.silhouette_domain(light, region.as_deref(), out)
    }

    /// Fills `out` with the triangulation of `region` (light `light`'s unoccluded region, see
    /// [`PointSampler::region_domain`]), or, where the region or its triangulation is an error,
    /// with the light's faces ([`PointSampler::faces_domain`]); `true` in the second case.
    pub(crate) fn silhouette_domain(
        &self,
        light: usize,
        region: Result<&[SphericalPolygon], &GeomError>,
        out: &mut LightDomain,
    ) -> bool {
        if let Ok(pieces) = region
            && self.region_domain(light, pieces, out).is_ok()
        {
            return false;
        }
        self.faces_domain(light, out);
        true
    }

    /// Fills `out` with the triangulation of `pieces`, a region of light `light` in the shading
    /// frame where it gives light with every other object removed (the light's unoccluded
    /// region); the light's sampled rays are still traced to its surface.
    ///
    /// # Errors
    ///
    /// Those of [`SphericalPolygon::triangulate`] (`out` is then left empty).
    pub(crate) fn region_domain(
        &self,
        light: usize,
        pieces: &[SphericalPolygon],
        out: &mut LightDomain,
    ) -> Result<(), GeomError> {
        out.clear(true);
        // From inside a convex light no face is seen from the front (its silhouette would be
        // the whole sphere): nothing, as for the face sampling.
        if let Body::Convex(p) = self.scene.lights()[light].shape()
            && !(0..p.mesh().triangle_count()).any(|i| self.emits_towards(light, p.mesh(), i))
        {
            return Ok(());
        }
        for piece in pieces {
            match piece.triangulate() {
                Ok(tris) => {
                    for t in tris {
                        out.push(t);
                    }
                }
                Err(e) => {
                    out.clear(true);
                    return Err(e);
                }
            }
        }
        Ok(())
    }

    /// Whether triangle `i` of light `light`'s mesh `mesh` emits towards the shading point, by
    /// the facing predicate the analytic path decides it with ([`face_side`]): the point is in
    /// front of it, or behind it and the light is two-sided ([`super::Light::two_sided`]). A
    /// point within the predicate's tolerance of the triangle's plane sees it edge-on and gets
    /// nothing from it, as on the analytic path (a point on a box's top face `2e-16` below a
    /// sheet light facing down is in the sheet's plane; by the sign alone the reference counted
    /// the whole sheet there, 0.22 where the analytic value is 0).
    ///
    /// The facing predicate is the analytic path's on purpose. Which side of a face a point
    /// within rounding of its plane is on is a convention of the model (like the opacity model,
    /// which [`hits_before`] shares for the same reason), not something the reference could
    /// check: the face covers a solid angle of the order of the tolerance there. What the
    /// reference checks independently is the rest: which directions reach the light (its own
    /// ray casts) and what they carry (sampling, the BRDF).
    fn emits_towards(&self, light: usize, mesh: &TriangleMesh, i: usize) -> bool {
        match face_side(mesh, i, self.frame.origin()) {
            Side::Front => true,
            Side::Behind => self.scene.lights()[light].is_two_sided(),
            Side::On => false,
        }
    }

    /// Fills `out` with the projections of light `light`'s front faces ([`LightSampling::Faces`]).
    pub(crate) fn faces_domain(&self, light: usize, out: &mut LightDomain) {
        out.clear(false);
        let x = self.frame.origin();
        let mesh = self.scene.lights()[light].shape().mesh();
        for i in 0..mesh.triangle_count() {
            if !self.emits_towards(light, mesh, i) {
                continue; // back face: emits nothing towards x
            }
            let [a, b, c] = mesh.triangle(i);
            if let Ok(t) = SphericalTriangle::new(a - x, b - x, c - x) {
                out.push(t);
                out.faces.push(i);
            }
        }
    }

    /// Draws a direction of `domain` (light `light`) from `u` and traces it: the direction in
    /// the shading frame and what it finds.
    pub(crate) fn trace(&self, light: usize, domain: &LightDomain, u: DVec2) -> (DVec3, Outcome) {
        let (k, u) = domain.pick(u);
        let d = domain.tris[k].sample(u);
        let (w, l) = if domain.local {
            (self.frame.dir_to_world(d), d)
        } else {
            (d, self.frame.dir_to_local(d))
        };
        if l.z <= 0.0 {
            return (l, Outcome::Miss);
        }
        let outcome = match domain.faces.get(k) {
            Some(&face) => self.trace_face(light, face, w),
            None => self.trace_region(light, w),
        };
        (l, outcome)
    }

    /// A direction `w` (world) sampled on the projection of face `face` of light `light`.
    fn trace_face(&self, light: usize, face: usize, w: DVec3) -> Outcome {
        let x = self.frame.origin();
        let body = self.scene.lights()[light].shape();
        let mesh = body.mesh();
        let Some(t_light) = ray_triangle(x, w, mesh.triangle(face), 0.0).or_else(|| {
            // A sample on the triangle's boundary may miss it by rounding: take the distance
            // to its plane.
            let [a, ..] = mesh.triangle(face);
            let nn = mesh.triangle_normal(face);
            let den = nn.dot(w);
            (den != 0.0)
                .then(|| nn.dot(a - x) / den)
                .filter(|t| *t > 0.0)
        }) else {
            return Outcome::Miss;
        };
        if matches!(body, Body::Mesh(_))
            && hits_before(x, w, mesh, Some(face), t_light * (1.0 - RAY_EPS))
        {
            return Outcome::Miss; // the light's own nearer triangle
        }
        if self.blocked(light, w, t_light) {
            Outcome::Blocked
        } else {
            Outcome::Visible
        }
    }

    /// A direction `w` (world) sampled in light `light`'s unoccluded region: traced as any
    /// direction is ([`Self::trace_light`]), so a region larger than the light only wastes
    /// samples.
    fn trace_region(&self, light: usize, w: DVec3) -> Outcome {
        self.trace_light(light, w).1
    }

    /// What the ray from the shading point along `w` (world) finds of light `light`: the light
    /// triangle it meets first (within [`LIGHT_HIT_SLACK`], triangles seen edge-on skipped) if
    /// that one emits towards the point, and whether another object hides it. The light's own
    /// nearer triangles hide farther ones; a ray that meets none of its triangles, or meets one
    /// that does not emit towards the point first (a back face, the inside of a closed light),
    /// is a [`Outcome::Miss`].
    fn trace_light(&self, light: usize, w: DVec3) -> (Option<usize>, Outcome) {
        let x = self.frame.origin();
        let mesh = self.scene.lights()[light].shape().mesh();
        let Some((t, j)) = nearest_hit(x, w, mesh) else {
            return (None, Outcome::Miss);
        };
        if !self.emits_towards(light, mesh, j) {
            return (Some(j), Outcome::Miss);
        }
        if self.blocked(light, w, t) {
            (Some(j), Outcome::Blocked)
        } else {
            (Some(j), Outcome::Visible)
        }
    }

    /// Traces a direction `l` (shading frame) drawn from the BRDF towards light `light`
    /// ([`Self::trace_light`]): what it finds, and the density with which the light technique
    /// over `domain` draws that direction (for the balance heuristic): `1 / domain.total()`
    /// inside a region's triangulation ([`LightSampling::Silhouette`]), or where the triangle
    /// the ray meets is one of the domain's faces ([`LightSampling::Faces`]: the light technique
    /// reaches a direction only through the projection of the triangle it meets first), and
    /// zero elsewhere (outside a region, or on a face whose projection could not be built).
    fn trace_brdf(&self, light: usize, domain: &LightDomain, l: DVec3) -> (f64, Outcome) {
        if l.z <= 0.0 {
            return (0.0, Outcome::Miss);
        }
        let (face, outcome) = self.trace_light(light, self.frame.dir_to_world(l));
        if outcome != Outcome::Visible || domain.is_empty() {
            return (0.0, outcome);
        }
        let drawn = if domain.local {
            domain.tris.iter().any(|t| spherical_triangle_holds(t, l))
        } else {
            face.is_some_and(|j| domain.faces.contains(&j))
        };
        (if drawn { 1.0 / domain.total() } else { 0.0 }, outcome)
    }

    /// Whether another object than light `light` has a triangle on the ray from the shading
    /// point along `w` strictly between its start and `t_light` (short of `t_light` by the
    /// relative margin [`RAY_EPS`]; see [`hits_before`] for the start).
    pub(super) fn blocked(&self, light: usize, w: DVec3, t_light: f64) -> bool {
        let x = self.frame.origin();
        let t_max = t_light * (1.0 - RAY_EPS);
        let own = self.scene.occluders().len() + light;
        self.blockers.iter().enumerate().any(|(j, &(m, b))| {
            j != own
                && ray_meets_sphere(x, w, b.center, b.radius, t_max)
                && hits_before(x, w, m, None, t_max)
        })
    }
}

/// Whether the ray from `x` along `w` meets a triangle of `m` (other than `skip`) at a distance
/// strictly between `0` and `t_max`. A triangle whose plane holds `x` by the facing predicate
/// ([`face_side`] says [`Side::On`]) is seen edge-on and meets no ray from `x`: a ray from a
/// point on a surface is not blocked by that surface, as in the analytic path, where such a
/// triangle covers nothing.
fn hits_before(x: DVec3, w: DVec3, m: &TriangleMesh, skip: Option<usize>, t_max: f64) -> bool {
    (0..m.triangle_count()).any(|j| {
        Some(j) != skip
            && ray_triangle(x, w, m.triangle(j), 0.0).is_some_and(|t| t < t_max)
            && face_side(m, j, x) != Side::On
    })
}

/// The distance along `w` from `x` to the nearest triangle of `mesh` the ray meets (within
/// [`LIGHT_HIT_SLACK`]), and that triangle's index. Triangles seen edge-on from `x` are skipped,
/// as in [`hits_before`].
fn nearest_hit(x: DVec3, w: DVec3, mesh: &TriangleMesh) -> Option<(f64, usize)> {
    let mut best: Option<(f64, usize)> = None;
    for j in 0..mesh.triangle_count() {
        if let Some(t) = ray_triangle(x, w, mesh.triangle(j), LIGHT_HIT_SLACK)
            && best.is_none_or(|(b, _)| t < b)
            && face_side(mesh, j, x) != Side::On
        {
            best = Some((t, j));
        }
    }
    best
}

/// Whether the spherical triangle `t` (minor-arc edges, positive orientation: the intersection
/// of the three half-spaces on the left of its edges) holds the direction `l`, boundary
/// included.
fn spherical_triangle_holds(t: &SphericalTriangle, l: DVec3) -> bool {
    let [a, b, c] = t.vertices();
    a.cross(b).dot(l) >= 0.0 && b.cross(c).dot(l) >= 0.0 && c.cross(a).dot(l) >= 0.0
}

impl MonteCarlo {
    /// Settings with `samples_per_light` samples per light, the given BRDF, and the default
    /// [`LightSampling::Silhouette`].
    #[must_use]
    pub fn new(samples_per_light: u32, brdf: ReferenceBrdf) -> Self {
        MonteCarlo {
            samples_per_light,
            brdf,
            sampling: LightSampling::Silhouette,
            techniques: Techniques::Light,
        }
    }

    /// The same settings sampling the BRDF too, combined with the light samples by multiple
    /// importance sampling ([`Techniques::LightAndBrdf`]): for glossy lobes of any width.
    #[must_use]
    pub fn with_brdf_sampling(mut self) -> Self {
        self.techniques = Techniques::LightAndBrdf;
        self
    }

    /// The same settings drawing directions by `sampling`.
    #[must_use]
    pub fn with_sampling(mut self, sampling: LightSampling) -> Self {
        self.sampling = sampling;
        self
    }

    /// Estimates the radiance [`Scene::shade`] computes at `point` (same arguments, `f32`
    /// vectors included through [`IntoDVec3`]), with the random sequence given by `seed`.
    ///
    /// # Errors
    ///
    /// Those of [`ShadingFrame::new`] and of the LTC lookup.
    pub fn estimate(
        &self,
        scene: &Scene,
        point: impl IntoDVec3,
        normal: impl IntoDVec3,
        view: impl IntoDVec3,
        material: &Material,
        seed: u64,
    ) -> Result<Estimate, GeomError> {
        let (point, normal, view) = (point.into_dvec3(), normal.into_dvec3(), view.into_dvec3());
        let ps = PointSampler::new(scene, point, normal, view, material, self.brdf)?;
        let mut rng = Pcg32::new(seed, 0x5ade);
        let n = self.samples_per_light.max(1);
        let mut mean = DVec3::ZERO;
        let mut var = DVec3::ZERO;
        let mut domain = LightDomain::default();
        let mut bound = DVec3::ZERO;
        let mut fallbacks = 0;
        for (li, light) in scene.lights().iter().enumerate() {
            if let Body::Bezier(shape) = light.shape() {
                let two = light.is_two_sided();
                let (m, s2) = super::curved_reference::estimate(&ps, li, shape, two, n, &mut rng);
                mean += m * light.radiance();
                var += s2 * light.radiance() * light.radiance();
                bound = DVec3::INFINITY;
                continue;
            }
            if ps.domain(li, self.sampling, &mut domain) {
                fallbacks += 1;
            }
            let mis = self.techniques == Techniques::LightAndBrdf;
            if domain.is_empty() && !mis {
                continue;
            }
            let total = domain.total();
            let (mut sum, mut sum2) = (DVec3::ZERO, DVec3::ZERO);
            for _ in 0..n {
                // One sample of each technique per step; with the balance heuristic
                // (Vea97 eq. 9.6, one sample per technique) either contributes
                // f / (p_light + p_brdf), and their sum is one independent, unbiased sample of
                // the light's integral, so the steps' spread gives the standard error.
                let mut f = DVec3::ZERO;
                if !domain.is_empty() {
                    let (l, outcome) = ps.trace(li, &domain, rng.next_2d());
                    if outcome == Outcome::Visible {
                        f += if mis {
                            ps.brdf(l) * light.radiance() / (1.0 / total + ps.brdf.pdf(l))
                        } else {
                            ps.brdf(l) * light.radiance() * total
                        };
                    }
                }
                if mis {
                    let (l, p_brdf) = ps.brdf_sample(rng.next_2d(), rng.next_f64());
                    let (p_light, outcome) = ps.trace_brdf(li, &domain, l);
                    if outcome == Outcome::Visible && p_brdf + p_light > 0.0 {
                        f += ps.brdf(l) * light.radiance() / (p_brdf + p_light);
                    }
                }
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
            // One step: each technique's term is at most f / p_brdf; light sampling alone gives
            // f * total, bounded for the Lambertian lobe (f <= albedo / pi).
            bound += if mis {
                2.0 * ps.brdf.ratio_bound() * light.radiance()
            } else if ps.brdf.ltc.is_none()
                && !(ps.brdf.kind == ReferenceBrdf::True && material.has_specular())
            {
                material.albedo() * light.radiance() * (total / core::f64::consts::PI)
            } else {
                DVec3::INFINITY
            };
        }
        Ok(Estimate {
            mean,
            std_error: DVec3::new(sqrt(var.x), sqrt(var.y), sqrt(var.z)),
            samples: n,
            sample_bound: bound,
            fallbacks,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shade::{Light, TriangleMesh};

    /// The silhouette sampling falls back to the faces exactly where the region is an error,
    /// and says so.
    #[test]
    fn silhouette_falls_back_to_faces_and_says_so() {
        let quad =
            TriangleMesh::quad(DVec3::new(0.0, 0.0, 2.0), DVec3::Y * 0.5, DVec3::X * 0.5).unwrap();
        let scene = Scene::new(
            alloc::vec![Light::new(quad, DVec3::ONE).unwrap()],
            alloc::vec![],
        )
        .unwrap();
        let m = Material::new(DVec3::splat(0.5), DVec3::ZERO, 0.5).unwrap();
        let ps = PointSampler::new(
            &scene,
            DVec3::ZERO,
            DVec3::Z,
            DVec3::Z,
            &m,
            ReferenceBrdf::Ltc,
        )
        .unwrap();
        let mut faces = LightDomain::default();
        ps.faces_domain(0, &mut faces);
        assert!(!faces.is_empty() && !faces.local);
        let mut out = LightDomain::default();
        // The light's own region: triangulated, no fallback.
        assert!(!ps.domain(0, LightSampling::Silhouette, &mut out));
        assert!(out.local && !out.is_empty());
        let cap = SphericalPolygon::new(alloc::vec![alloc::vec![
            DVec3::new(0.1, 0.0, 1.0),
            DVec3::new(0.0, 0.1, 1.0),
            DVec3::new(-0.1, -0.1, 1.0),
        ]])
        .unwrap();
        assert!(!ps.silhouette_domain(0, Ok(&[cap]), &mut out));
        assert!(out.local && out.tris.len() == 1);
        // The region given up on (as `unoccluded_region` or `triangulate` report it).
        let region = Err(&GeomError::Undecidable("test"));
        assert!(ps.silhouette_domain(0, region, &mut out));
        assert!(!out.local && out.tris == faces.tris);
        assert!(!ps.domain(0, LightSampling::Faces, &mut out));
        assert!(!out.local);
    }
}
