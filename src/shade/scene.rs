//! Scenes of lights and occluders, and the analytic shading of a point (seed 000 Alg. 1).

use alloc::vec::Vec;

use glam::DVec3;

use crate::GeomError;
use crate::solid::{Body, ShadingFrame};
use crate::sphere::SphericalPolygon;
use crate::visibility::{Blocker, ClipVisibility, Method};

/// An area light: a body emitting the uniform RGB radiance `radiance` from its outer surface.
#[derive(Debug, Clone, PartialEq)]
pub struct Light {
    body: Body,
    radiance: DVec3,
}

impl Light {
    /// A light of the given geometry and RGB radiance.
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
        Ok(Light { body, radiance })
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
        Ok(Scene {
            vis: ClipVisibility::new(lights, occluders),
        })
    }

    /// The same scene evaluated with another [`Method`].
    #[must_use]
    pub fn with_method(mut self, method: Method) -> Self {
        self.vis = self.vis.with_method(method);
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

    /// The visibility backend.
    #[must_use]
    pub fn visibility(&self) -> &ClipVisibility<Light> {
        &self.vis
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
        self.vis
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
        self.vis.blockers_between(light, frame)
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
        self.vis.visible_region(light, frame)
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
        self.vis.light_region(light, frame)
    }
}
