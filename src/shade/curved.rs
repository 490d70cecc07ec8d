//! Lights bounded by Bezier curves shaded with seed 004's per-point curved integrals, where
//! nothing is in the way: the `ltc` layer's adaptive subdivision and algebraic horizon clipping
//! on the light's control points, without a flattening chosen in advance.

use glam::DVec3;

use super::material::Material;
use super::scene::Light;
use crate::GeomError;
use crate::ltc::{
    CurveSegment, DIFFUSE_EPS, Subdivision, curved_clamped_cosine_integral, ggx_curved_integral,
    lookup, specular_eps,
};
use crate::solid::{BezierSegment, Body, ShadingFrame};

impl From<BezierSegment> for CurveSegment {
    fn from(s: BezierSegment) -> Self {
        match s {
            BezierSegment::Line(p) => CurveSegment::Line(p),
            BezierSegment::Cubic(p) => CurveSegment::Cubic(p),
        }
    }
}

/// The unshadowed radiance of one curved light at a point by the curved integrals
/// ([`Light::shade_curved`]).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct CurvedShading {
    /// The Lambertian lobe (RGB, radiance included).
    pub diffuse: DVec3,
    /// The GGX lobe (RGB, radiance included; zero without one).
    pub specular: DVec3,
    /// Chords summed, both lobes together (seed 004 figure 5's measure of cost).
    pub edges: usize,
}

impl CurvedShading {
    /// `diffuse + specular`.
    #[must_use]
    pub fn total(&self) -> DVec3 {
        self.diffuse + self.specular
    }
}

impl Light {
    /// For a light bounded by Bezier curves ([`Body::Bezier`]): its radiance at `point` (same
    /// arguments as [`super::Scene::shade`]) with nothing in the way, by the curved integrals of
    /// seed 004 on the light's control points in the shading frame: `diffuse` subdivision for
    /// the Lambertian lobe, `specular` for the GGX lobe (`None`: the seed's
    /// `eps_s = 0.1 alpha^2`, [`specular_eps`]). Use `Subdivision::Adaptive { eps:
    /// DIFFUSE_EPS }` for the default diffuse threshold.
    ///
    /// This is the whole light, unclipped by other objects: what [`super::Scene::shade`] gives
    /// for the light when nothing lies between, up to the scene's flattening
    /// ([`crate::solid::BezierShape::region`]). A two-sided light ([`Light::two_sided`]) seen
    /// from behind gives its turned-around shape's value
    /// ([`crate::solid::BezierShape::local_segments_behind`]).
    ///
    /// # Errors
    ///
    /// [`GeomError::Degenerate`] for a light that is not bounded by curves; those of
    /// [`ShadingFrame::new`] for the arguments; [`GeomError::OutOfRange`] for a bad
    /// subdivision; [`GeomError::Undecidable`] should the integrals give up.
    pub fn shade_curved(
        &self,
        point: DVec3,
        normal: DVec3,
        view: DVec3,
        material: &Material,
        diffuse: Subdivision,
        specular: Option<Subdivision>,
    ) -> Result<CurvedShading, GeomError> {
        let Body::Bezier(shape) = self.shape() else {
            return Err(GeomError::Degenerate(
                "shade_curved needs a light bounded by Bezier curves",
            ));
        };
        let frame = ShadingFrame::new(point, normal, view)?;
        let seen = match shape.local_segments(&frame) {
            Some(s) => Some(s),
            None if self.is_two_sided() => shape.local_segments_behind(&frame),
            None => None,
        };
        let Some(local) = seen else {
            return Ok(CurvedShading::default());
        };
        let segs: alloc::vec::Vec<CurveSegment> = local.into_iter().map(Into::into).collect();
        let d = curved_clamped_cosine_integral(&segs, diffuse)?;
        let mut out = CurvedShading {
            diffuse: material.albedo() * d.value * self.radiance(),
            specular: DVec3::ZERO,
            edges: d.edges,
        };
        if material.has_specular() {
            let alpha = material.alpha();
            let sub = specular.unwrap_or(Subdivision::Adaptive {
                eps: specular_eps(alpha),
            });
            let cos_v = frame.view().z;
            // One integral with f0 = 1, scaled per channel: the Fresnel weight is linear in f0.
            let s = ggx_curved_integral(&segs, cos_v, alpha, 1.0, sub)?;
            let l = lookup(cos_v, alpha)?;
            let unit = l.specular_scale(1.0);
            let f0 = material.f0();
            let ratio = DVec3::new(
                l.specular_scale(f0.x.clamp(0.0, 1.0)),
                l.specular_scale(f0.y.clamp(0.0, 1.0)),
                l.specular_scale(f0.z.clamp(0.0, 1.0)),
            ) / unit;
            out.specular = ratio * s.value * self.radiance();
            out.edges += s.edges;
        }
        Ok(out)
    }
}

/// The default diffuse subdivision of [`Light::shade_curved`] callers: seed 004's adaptive
/// scheme at [`DIFFUSE_EPS`].
pub const DEFAULT_DIFFUSE_SUBDIVISION: Subdivision = Subdivision::Adaptive { eps: DIFFUSE_EPS };
