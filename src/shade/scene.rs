//! Scenes of lights and occluders, and the analytic shading of a point (seed 000 Alg. 1).

use alloc::vec::Vec;

use glam::DVec3;

use crate::GeomError;
use crate::solid::{Body, ShadingFrame};
use crate::sphere::SphericalPolygon;
use crate::visibility::{Blocker, ClipVisibility, Method};

/// An area light: a body emitting the uniform RGB radiance `radiance` from its outer surface.
///
/// # Which side emits
///
/// Only the front side of each triangle emits: the side its normal points to, from which its
/// corners run counter-clockwise ([`TriangleMesh`](crate::solid::TriangleMesh)). For
/// [`TriangleMesh::quad(c, u, v)`](crate::solid::TriangleMesh::quad) that is the side `u x v`
/// points to; for a closed mesh or a convex polyhedron, the outside. A light facing away from
/// everything gives a black image and no error: [`Scene::validate`] reports it. A planar light
/// made with [`Light::two_sided`] emits from both sides.
#[derive(Debug, Clone, PartialEq)]
pub struct Light {
    body: Body,
    radiance: DVec3,
    two_sided: bool,
}

impl Light {
    /// A light of the given geometry and RGB radiance, emitting from the front side of its
    /// triangles only (see "Which side emits" above; [`Light::two_sided`] for both sides).
    ///
    /// # Errors
    ///
    /// - [`GeomError::OutOfRange`] for a negative or non-finite radiance component;
    /// - [`GeomError::OverlappingLightTriangles`] for a planar mesh whose triangles overlap
    ///   (each would emit over the overlap: a planar light's triangles are integrated as
    ///   disjoint pieces).
    pub fn new(body: impl Into<Body>, radiance: DVec3) -> Result<Self, GeomError> {
        for c in radiance.to_array() {
            if !(c >= 0.0 && c.is_finite()) {
                return Err(GeomError::OutOfRange {
                    what: "light radiance (non-negative, finite)",
                    value: c,
                    limit: f64::MAX,
                });
            }
        }
        let body = body.into();
        if let Some((triangle, other)) = body.mesh().planar_overlap() {
            return Err(GeomError::OverlappingLightTriangles { triangle, other });
        }
        Ok(Light {
            body,
            radiance,
            two_sided: false,
        })
    }

    /// A planar light that emits `radiance` from both of its sides: from behind its plane it
    /// gives what the same light turned around ([`TriangleMesh::flipped`], or
    /// [`BezierShape::flipped`] for a light bounded by curves) would give, in front what it
    /// gives as built. Its geometry blocks other lights as any light's does.
    ///
    /// Costs nothing per shading point over a one-sided light (one facing test picks the side);
    /// a scene with two-sided lights keeps a second copy of its visibility data for the back
    /// sides, built by [`Scene::new`].
    ///
    /// # Errors
    ///
    /// As [`Light::new`]; [`GeomError::Degenerate`] for a body that is neither a planar
    /// [`TriangleMesh`] nor a [`BezierShape`] (a closed light has no second side to show, and a
    /// curved open mesh would need a facing decision per triangle).
    ///
    /// [`TriangleMesh`]: crate::solid::TriangleMesh
    /// [`TriangleMesh::flipped`]: crate::solid::TriangleMesh::flipped
    /// [`BezierShape`]: crate::solid::BezierShape
    /// [`BezierShape::flipped`]: crate::solid::BezierShape::flipped
    pub fn two_sided(body: impl Into<Body>, radiance: DVec3) -> Result<Self, GeomError> {
        let mut light = Light::new(body, radiance)?;
        match &light.body {
            Body::Mesh(m) if m.is_planar() => {}
            Body::Bezier(_) => {}
            _ => {
                return Err(GeomError::Degenerate(
                    "a two-sided light must be a planar TriangleMesh or a BezierShape",
                ));
            }
        }
        light.two_sided = true;
        Ok(light)
    }

    /// Whether the light emits from both sides ([`Light::two_sided`]).
    #[must_use]
    pub fn is_two_sided(&self) -> bool {
        self.two_sided
    }

    /// The same light with another geometry (the turned-around copy of a two-sided light).
    pub(super) fn with_body(&self, body: Body) -> Light {
        Light {
            body,
            radiance: self.radiance,
            two_sided: self.two_sided,
        }
    }

    /// The light's geometry.
    #[must_use]
    pub fn shape(&self) -> &Body {
        &self.body
    }

    /// The emitted RGB radiance.
    #[must_use]
    pub fn radiance(&self) -> DVec3 {
        self.radiance
    }
}

impl AsRef<Body> for Light {
    fn as_ref(&self) -> &Body {
        &self.body
    }
}

/// Lights, occluders and the shading method: everything [`Scene::shade`] needs besides the
/// shading point and its material.
///
/// A `Scene` is immutable after construction and holds no interior mutability, so it is
/// `Send + Sync`: a renderer shares one `&Scene` among all its threads.
///
/// # What blocks what
///
/// Every object is opaque. Occluders block every light; a light's geometry blocks every other
/// light (both its sides: only the front side emits, but all of it is solid), and a mesh light's
/// triangles block the rest of the same light. The [Monte Carlo reference](super::MonteCarlo)
/// models exactly the same thing. An object hides a direction only where it lies strictly
/// between the shading point and the light surface along that direction; see
/// [`ClipVisibility::visible_region`] for the exact rule and how it is evaluated.
///
/// # Examples
///
/// ```
/// use arealight::glam::DVec3;
/// use arealight::shade::{Light, Material, Scene, TriangleMesh};
/// // A 1 x 1 quad light facing down, 2 above a diffuse white floor.
/// let quad = TriangleMesh::quad(DVec3::new(0.0, 0.0, 2.0), DVec3::Y * 0.5, DVec3::X * 0.5)?;
/// let scene = Scene::new(vec![Light::new(quad, DVec3::ONE)?], vec![])?;
/// let white = Material::diffuse(DVec3::ONE)?;
/// let rgb = scene.shade(DVec3::ZERO, DVec3::Z, DVec3::Z, &white)?;
/// // Irradiance of a square of side 2a at distance d on the axis, over pi:
/// // (2 / pi) * 2 (a / sqrt(a^2 + d^2)) atan(a / sqrt(a^2 + d^2)).
/// let (a, d) = (0.5f64, 2.0f64);
/// let s = a / (a * a + d * d).sqrt();
/// let expect = 4.0 / std::f64::consts::PI * s * s.atan();
/// assert!((rgb.x - expect).abs() < 1e-12);
/// # Ok::<(), arealight::GeomError>(())
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct Scene {
    vis: ClipVisibility<Light>,
    /// With two-sided lights: the same scene with each of them turned around
    /// ([`Scene::light_visibility`]).
    back: Option<ClipVisibility<Light>>,
}

impl Scene {
    /// A scene with the default [`Method::Silhouette`].
    ///
    /// Computes, once for the scene, a separating plane between every light and every other
    /// object (see [`ClipVisibility::new`]).
    ///
    /// # Errors
    ///
    /// None today (lights and shapes are validated when built); the `Result` leaves room for
    /// scene-level checks.
    pub fn new(lights: Vec<Light>, occluders: Vec<Body>) -> Result<Self, GeomError> {
        let back = super::two_sided::back_visibility(&lights, &occluders);
        Ok(Scene {
            vis: ClipVisibility::new(lights, occluders),
            back,
        })
    }

    /// The same scene evaluated with another [`Method`].
    #[must_use]
    pub fn with_method(mut self, method: Method) -> Self {
        self.vis = self.vis.with_method(method);
        self.back = self.back.map(|b| b.with_method(method));
        self
    }

    /// The method in use.
    #[must_use]
    pub fn method(&self) -> Method {
        self.vis.method()
    }

    /// The lights.
    #[must_use]
    pub fn lights(&self) -> &[Light] {
        self.vis.lights()
    }

    /// The occluders.
    #[must_use]
    pub fn occluders(&self) -> &[Body] {
        self.vis.occluders()
    }

    /// The visibility backend. It holds every light as built: queries of a two-sided light
    /// ([`Light::two_sided`]) from behind its plane go to a copy of the scene in which that
    /// light is turned around.
    #[must_use]
    pub fn visibility(&self) -> &ClipVisibility<Light> {
        &self.vis
    }

    /// The visibility backend that holds light `light` facing the frame's point where it can:
    /// [`Scene::visibility`], or for a two-sided light whose plane has the point behind it, the
    /// copy of the scene with that light turned around. Every query of one light goes through
    /// here, so the rest of the crate sees one-sided lights only.
    pub(crate) fn light_visibility(
        &self,
        light: usize,
        frame: &ShadingFrame,
    ) -> &ClipVisibility<Light> {
        match &self.back {
            Some(back) if super::two_sided::seen_from_behind(self.lights(), light, frame) => back,
            _ => &self.vis,
        }
    }

    /// Light `i`, or [`GeomError::OutOfRange`] past the end.
    pub(super) fn light(&self, i: usize) -> Result<&Light, GeomError> {
        self.lights().get(i).ok_or(GeomError::OutOfRange {
            what: "light index",
            value: i as f64,
            limit: self.lights().len() as f64,
        })
    }

    /// Indices of the occluders that may hide part of light `light` from the frame's point (the
    /// occluders among [`Scene::blockers_between`]).
    pub fn occluders_between(
        &self,
        light: usize,
        frame: &ShadingFrame,
    ) -> impl Iterator<Item = usize> + '_ {
        self.light_visibility(light, frame)
            .blockers_between(light, frame)
            .filter_map(|b| match b {
                Blocker::Occluder(k) => Some(k),
                Blocker::Light(_) => None,
            })
    }

    /// The objects that may hide part of light `light` from the frame's point
    /// ([`ClipVisibility::blockers_between`]).
    pub fn blockers_between(
        &self,
        light: usize,
        frame: &ShadingFrame,
    ) -> impl Iterator<Item = Blocker> + '_ {
        self.light_visibility(light, frame)
            .blockers_between(light, frame)
    }

    /// The part of light `light` visible from the frame's point, in the shading frame, clipped to
    /// the upper hemisphere, as pieces with disjoint interiors whose integrals add up
    /// ([`ClipVisibility::visible_region`], where the exact rule is stated).
    ///
    /// # Errors
    ///
    /// As [`ClipVisibility::visible_region`].
    pub fn visible_region(
        &self,
        light: usize,
        frame: &ShadingFrame,
    ) -> Result<Vec<SphericalPolygon>, GeomError> {
        self.light_visibility(light, frame)
            .visible_region(light, frame)
    }

    /// The region light `light` covers seen from the frame's point, before any blocker
    /// ([`ClipVisibility::light_region`]).
    ///
    /// # Errors
    ///
    /// As [`ClipVisibility::light_region`].
    pub fn light_region(
        &self,
        light: usize,
        frame: &ShadingFrame,
    ) -> Result<Vec<SphericalPolygon>, GeomError> {
        self.light_visibility(light, frame)
            .light_region(light, frame)
    }
}
