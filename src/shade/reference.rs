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
//! is intersected with every triangle of every occluder and of every other light whose bounding
//! sphere it meets (no culling and no separating planes, so the analytic path's shortcuts are
//! checked too), and of the light's own mesh for non-convex mesh lights (self-occlusion); any
//! hit strictly before the point the ray meets on the light blocks the sample, except on a
//! triangle whose plane holds the shading point (seen edge-on by the facing predicate, as in
//! the analytic path: a point on a surface is not hidden by it). The estimator
//! returns its mean and standard error, so tests can state a confidence bound.
//!
//! Lights bounded by Bezier curves are sampled uniformly by area over the exact curved region
//! (rejection from its bounding box; `curved_reference.rs`), whatever the [`LightSampling`], so
//! that the analytic path's per-point flattening is checked too; visibility as above.
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
use crate::solid::{Body, BoundingSphere, ShadingFrame, Side, TriangleMesh, face_side};
use crate::sphere::{SphericalPolygon, SphericalTriangle};
use crate::visibility::Visibility;

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
    /// is too large only wastes samples (each ray must still meet the light's front side), but a
    /// light region that misses part of the light would be missed by both. Tests of the lights'
    /// own regions (silhouettes of non-convex lights, unions of front faces) use
    /// [`LightSampling::Faces`]; occlusion is checked independently either way.
    #[default]
    Silhouette,
    /// Every front-facing triangle of the light, projected, chosen in proportion to its solid
    /// angle: independent of the visibility layer. Samples that fall below the horizon or on
    /// faces hidden behind the light's own nearer faces are wasted (they count as zero).
    Faces,
}

/// A Monte Carlo estimate: the mean and its standard error, per RGB channel.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Estimate {
    /// The estimated radiance.
    pub mean: DVec3,
    /// The estimated standard deviation of `mean` (sample standard deviation over `sqrt(n)`).
    pub std_error: DVec3,
    /// How many lights were sampled by their faces because [`LightSampling::Silhouette`] gave
    /// up at this point (the light's unoccluded region or its triangulation returned
    /// [`GeomError::Undecidable`]): the estimate is still unbiased, only noisier. Always 0
    /// with [`LightSampling::Faces`].
    pub fallbacks: u32,
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
}

/// Relative distance along a ray, short of the point where it meets the light, within which a
/// hit counts as the light itself: rays end on the light and must not be blocked by it or by
/// blockers touching it.
///
/// The start needs no such margin and has none: a ray starting on a surface is not blocked by
/// that surface because the shading point lies in its plane, which [`face_side`] decides with
/// the tolerance the analytic path uses (a triangle seen edge-on covers nothing there, see
/// [`hits_between`]). A margin relative to the ray's length would instead let a ray through a
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
}

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

    /// Whether triangle `i` of light `light`'s mesh `mesh` emits towards the shading point: it
    /// faces the point (the point is on its centroid's front side), or the light is two-sided
    /// ([`super::Light::two_sided`]) and the point is strictly behind it.
    fn emits_towards(&self, light: usize, mesh: &TriangleMesh, i: usize) -> bool {
        let [a, b, c] = mesh.triangle(i);
        let centroid = (a + b + c) / 3.0;
        let facing = mesh.triangle_normal(i).dot(self.frame.origin() - centroid);
        facing > 0.0 || (facing < 0.0 && self.scene.lights()[light].is_two_sided())
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

    /// A direction `w` (world) sampled in light `light`'s unoccluded region.
    fn trace_region(&self, light: usize, w: DVec3) -> Outcome {
        let x = self.frame.origin();
        let body = self.scene.lights()[light].shape();
        let mesh = body.mesh();
        // A non-planar mesh light is traced to its nearest triangle first (which must face x);
        // convex and planar lights only when another object's bounding sphere is on the ray.
        let mut t_light = None;
        if matches!(body, Body::Mesh(_)) && !mesh.is_planar() {
            match nearest_front_hit(x, w, mesh) {
                Some(t) => t_light = Some(t),
                None => return Outcome::Miss,
            }
        }
        let bound = mesh.bounding_sphere();
        let t_far = t_light.unwrap_or_else(|| (bound.center - x).length() + bound.radius);
        let own = self.scene.occluders().len() + light;
        let candidate = self
            .blockers
            .iter()
            .enumerate()
            .any(|(j, (_, b))| j != own && ray_meets_sphere(x, w, b.center, b.radius, t_far));
        if !candidate {
            return Outcome::Visible;
        }
        let t_light = match t_light {
            Some(t) => t,
            None => match entry_distance(x, w, body, self.scene.lights()[light].is_two_sided()) {
                Some(t) => t,
                None => return Outcome::Miss,
            },
        };
        if self.blocked(light, w, t_light) {
            Outcome::Blocked
        } else {
            Outcome::Visible
        }
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

/// The distance along `w` from `x` to the nearest triangle of `mesh`, if the ray meets one and
/// that one faces `x` (the emitting side). Triangles seen edge-on from `x` are skipped, as in
/// [`hits_before`].
fn nearest_front_hit(x: DVec3, w: DVec3, mesh: &TriangleMesh) -> Option<f64> {
    let mut best: Option<(f64, usize)> = None;
    for j in 0..mesh.triangle_count() {
        if let Some(t) = ray_triangle(x, w, mesh.triangle(j), LIGHT_HIT_SLACK)
            && best.is_none_or(|(b, _)| t < b)
            && face_side(mesh, j, x) != Side::On
        {
            best = Some((t, j));
        }
    }
    let (t, j) = best?;
    (mesh.triangle_normal(j).dot(w) < 0.0).then_some(t)
}

/// The distance along `w` from `x` (outside the light) at which the ray enters a convex or
/// planar light, for a direction known to lie in its region: for a convex light the largest
/// distance to a face plane the ray enters through (the entry point of an intersection of
/// half-spaces; no edge test, so directions on the silhouette's rim still get their distance),
/// for a planar one the distance to its plane from the front side (from either side for a
/// two-sided light).
fn entry_distance(x: DVec3, w: DVec3, body: &Body, two_sided: bool) -> Option<f64> {
    let mesh = body.mesh();
    let plane_t = |j: usize| {
        let n = mesh.triangle_normal(j);
        let den = n.dot(w);
        (den < 0.0 || (two_sided && den > 0.0)).then(|| n.dot(mesh.triangle(j)[0] - x) / den)
    };
    let t = match body {
        Body::Convex(_) => (0..mesh.triangle_count())
            .filter_map(plane_t)
            .fold(f64::NEG_INFINITY, f64::max),
        Body::Mesh(_) | Body::Bezier(_) => plane_t(0)?,
    };
    (t > 0.0 && t.is_finite()).then_some(t)
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
        }
    }

    /// The same settings drawing directions by `sampling`.
    #[must_use]
    pub fn with_sampling(mut self, sampling: LightSampling) -> Self {
        self.sampling = sampling;
        self
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
        let ps = PointSampler::new(scene, point, normal, view, material, self.brdf)?;
        let mut rng = Pcg32::new(seed, 0x5ade);
        let n = self.samples_per_light.max(1);
        let mut mean = DVec3::ZERO;
        let mut var = DVec3::ZERO;
        let mut domain = LightDomain::default();
        let mut fallbacks = 0;
        for (li, light) in scene.lights().iter().enumerate() {
            if let Body::Bezier(shape) = light.shape() {
                let two = light.is_two_sided();
                let (m, s2) = super::curved_reference::estimate(&ps, li, shape, two, n, &mut rng);
                mean += m * light.radiance();
                var += s2 * light.radiance() * light.radiance();
                continue;
            }
            if ps.domain(li, self.sampling, &mut domain) {
                fallbacks += 1;
            }
            if domain.is_empty() {
                continue;
            }
            let total = domain.total();
            let (mut sum, mut sum2) = (DVec3::ZERO, DVec3::ZERO);
            for _ in 0..n {
                let (l, outcome) = ps.trace(li, &domain, rng.next_2d());
                if outcome != Outcome::Visible {
                    continue;
                }
                let f = ps.brdf(l) * light.radiance() * total;
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
