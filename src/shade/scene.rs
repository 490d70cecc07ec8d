//! Scenes of lights and occluders, and the analytic shading of a point (seed 000 Alg. 1).

use alloc::vec::Vec;

use glam::{DMat3, DVec3};

use super::brdf::Material;
use super::cull::{BoundingSphere, above_horizon, may_occlude};
use super::mesh::{ConvexPolyhedron, TriangleMesh};
use super::silhouette::{ShadingFrame, TriangleRole, convex_silhouette, triangle_polygon};
use crate::GeomError;
use crate::ltc::{clamped_cosine_integral, lookup, ltc_integral};
use crate::planar::BoolOp;
use crate::sphere::SphericalPolygon;

/// The geometry of a light or an occluder.
#[derive(Debug, Clone, PartialEq)]
pub enum Shape {
    /// A convex polyhedron: one silhouette polygon per shading point (seed 000 section 3.3).
    Convex(ConvexPolyhedron),
    /// Any triangle mesh: one spherical triangle per triangle (seed 000 section 4.4). As a light,
    /// only front faces emit; as an occluder, every triangle blocks.
    Mesh(TriangleMesh),
}

impl Shape {
    /// The triangle mesh of the shape (the hull triangles of a convex polyhedron).
    #[must_use]
    pub fn mesh(&self) -> &TriangleMesh {
        match self {
            Shape::Convex(p) => p.mesh(),
            Shape::Mesh(m) => m,
        }
    }

    /// A sphere holding the shape.
    #[must_use]
    pub fn bounding_sphere(&self) -> BoundingSphere {
        let (center, radius) = self.mesh().bounding_sphere();
        BoundingSphere { center, radius }
    }
}

impl From<ConvexPolyhedron> for Shape {
    fn from(p: ConvexPolyhedron) -> Self {
        Shape::Convex(p)
    }
}

impl From<TriangleMesh> for Shape {
    fn from(m: TriangleMesh) -> Self {
        Shape::Mesh(m)
    }
}

/// An area light: a shape emitting the uniform RGB radiance `radiance` from its outer surface.
#[derive(Debug, Clone, PartialEq)]
pub struct Light {
    shape: Shape,
    radiance: DVec3,
}

impl Light {
    /// A light of the given shape and RGB radiance.
    ///
    /// # Errors
    ///
    /// [`GeomError::OutOfRange`] for a negative or non-finite radiance component.
    pub fn new(shape: impl Into<Shape>, radiance: DVec3) -> Result<Self, GeomError> {
        for c in radiance.to_array() {
            if !(c >= 0.0 && c.is_finite()) {
                return Err(GeomError::OutOfRange {
                    what: "light radiance (non-negative, finite)",
                    value: c,
                    limit: f64::MAX,
                });
            }
        }
        Ok(Light {
            shape: shape.into(),
            radiance,
        })
    }

    /// The light's geometry.
    #[must_use]
    pub fn shape(&self) -> &Shape {
        &self.shape
    }

    /// The emitted RGB radiance.
    #[must_use]
    pub fn radiance(&self) -> DVec3 {
        self.radiance
    }
}

/// How convex polyhedra are turned into spherical polygons.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Method {
    /// One silhouette polygon per convex polyhedron (seed 000 Alg. 2); meshes per triangle.
    #[default]
    Silhouette,
    /// Every shape per triangle (seed 000 section 4.4), convex ones included. Slower; it exists
    /// as a cross-check of the silhouette path and for comparisons.
    PerTriangle,
}

/// Lights, occluders and the shading method: everything [`Scene::shade`] needs besides the
/// shading point and its material.
///
/// A `Scene` is immutable after construction and holds no interior mutability, so it is
/// `Send + Sync`: a renderer shares one `&Scene` among all its threads.
///
/// Lights do not block each other; occluders block every light.
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
    lights: Vec<Light>,
    occluders: Vec<Shape>,
    light_bounds: Vec<BoundingSphere>,
    occluder_bounds: Vec<BoundingSphere>,
    method: Method,
}

impl Scene {
    /// A scene with the default [`Method::Silhouette`].
    ///
    /// # Errors
    ///
    /// None today (lights and shapes are validated when built); the `Result` leaves room for
    /// scene-level checks.
    pub fn new(lights: Vec<Light>, occluders: Vec<Shape>) -> Result<Self, GeomError> {
        let light_bounds = lights.iter().map(|l| l.shape.bounding_sphere()).collect();
        let occluder_bounds = occluders.iter().map(Shape::bounding_sphere).collect();
        Ok(Scene {
            lights,
            occluders,
            light_bounds,
            occluder_bounds,
            method: Method::Silhouette,
        })
    }

    /// The same scene evaluated with another [`Method`].
    #[must_use]
    pub fn with_method(mut self, method: Method) -> Self {
        self.method = method;
        self
    }

    /// The method in use.
    #[must_use]
    pub fn method(&self) -> Method {
        self.method
    }

    /// The lights.
    #[must_use]
    pub fn lights(&self) -> &[Light] {
        &self.lights
    }

    /// Light `i`, or [`GeomError::OutOfRange`] past the end.
    fn light(&self, i: usize) -> Result<&Light, GeomError> {
        self.lights.get(i).ok_or(GeomError::OutOfRange {
            what: "light index",
            value: i as f64,
            limit: self.lights.len() as f64,
        })
    }

    /// The occluders.
    #[must_use]
    pub fn occluders(&self) -> &[Shape] {
        &self.occluders
    }

    /// Indices of the occluders that may hide part of light `light` from the frame's point (the
    /// culling of [`may_occlude`]).
    pub fn occluders_between(
        &self,
        light: usize,
        frame: &ShadingFrame,
    ) -> impl Iterator<Item = usize> + '_ {
        let (x, n) = (frame.origin(), frame.normal());
        // An invalid light index has no occluders in between (and no region either).
        let lb = self.light_bounds.get(light).copied();
        let count = if lb.is_some() {
            self.occluders.len()
        } else {
            0
        };
        let lb = lb.unwrap_or(BoundingSphere {
            center: DVec3::ZERO,
            radius: 0.0,
        });
        (0..count).filter(move |&o| may_occlude(x, n, lb, self.occluder_bounds[o]))
    }

    /// The outgoing radiance (RGB) at `point` towards `view`, for a surface with normal
    /// `normal` and material `material`: seed 000 Alg. 1 summed over the lights.
    ///
    /// `view` points from the surface towards the viewer; `normal` and `view` need not be
    /// normalized. For each light the visible region is computed in the shading frame
    /// ([`Scene::visible_region`]), and integrated with Baum's formula for the diffuse lobe and,
    /// after the LTC transform `M^-1` looked up for the view angle and roughness, for the GGX lobe
    /// (HDHN16 eq. 2 / seed 000 eq. 2, Alg. 1 lines 13-16).
    ///
    /// # Errors
    ///
    /// Invalid point, normal or view ([`ShadingFrame::new`]); a degenerate silhouette (the point
    /// within rounding distance of a light's or occluder's edge line); an error of the spherical
    /// set operations ([`SphericalPolygon::boolean`]) on a near-degenerate configuration.
    pub fn shade(
        &self,
        point: DVec3,
        normal: DVec3,
        view: DVec3,
        material: &Material,
    ) -> Result<DVec3, GeomError> {
        let frame = ShadingFrame::new(point, normal, view)?;
        let mut total = DVec3::ZERO;
        let spec = specular_setup(&frame, material)?;
        for i in 0..self.lights.len() {
            total += self.shade_light_in(i, &frame, material, spec)?;
        }
        Ok(total)
    }

    /// The contribution of light `light` alone to [`Scene::shade`] (occluders included).
    ///
    /// # Errors
    ///
    /// As [`Scene::shade`]; [`GeomError::OutOfRange`] for a light index past the end.
    pub fn shade_light(
        &self,
        light: usize,
        point: DVec3,
        normal: DVec3,
        view: DVec3,
        material: &Material,
    ) -> Result<DVec3, GeomError> {
        self.light(light)?;
        let frame = ShadingFrame::new(point, normal, view)?;
        let spec = specular_setup(&frame, material)?;
        self.shade_light_in(light, &frame, material, spec)
    }

    fn shade_light_in(
        &self,
        i: usize,
        frame: &ShadingFrame,
        material: &Material,
        spec: Option<(DMat3, DVec3)>,
    ) -> Result<DVec3, GeomError> {
        let light = &self.lights[i];
        if !above_horizon(frame.origin(), frame.normal(), self.light_bounds[i]) {
            return Ok(DVec3::ZERO);
        }
        let (mut diffuse, mut specular) = (0.0, 0.0);
        for vis in self.visible_region(i, frame)? {
            diffuse += clamped_cosine_integral(&vis);
            if let Some((m_inv, _)) = spec {
                specular += ltc_integral(&vis, m_inv)?;
            }
        }
        let mut out = material.albedo() * diffuse;
        if let Some((_, scale)) = spec {
            out += scale * specular;
        }
        Ok(out * light.radiance)
    }

    /// The part of light `light` visible from the frame's point, in the shading frame, clipped to
    /// the upper hemisphere, as pieces with disjoint interiors whose integrals add up: each piece
    /// of the light's region ([`Scene::light_region`]) minus the regions of the occluders that may
    /// lie in between ([`Scene::subtract_occluders`]).
    ///
    /// # Errors
    ///
    /// As [`Scene::light_region`] and [`Scene::subtract_occluders`].
    pub fn visible_region(
        &self,
        light: usize,
        frame: &ShadingFrame,
    ) -> Result<Vec<SphericalPolygon>, GeomError> {
        let mut out = self.light_region(light, frame)?;
        for piece in &mut out {
            let p = core::mem::take(piece);
            *piece = self.subtract_occluders(light, frame, p)?;
        }
        out.retain(|p| !p.is_empty());
        Ok(out)
    }

    /// The region covered by light `light` seen from the frame's point, clipped to the upper
    /// hemisphere (seed 000 Alg. 1 lines 4-5), as pieces with disjoint interiors:
    ///
    /// - a convex light with [`Method::Silhouette`]: its silhouette, one piece;
    /// - a convex light with [`Method::PerTriangle`], or a planar mesh light: each front-facing
    ///   triangle, one piece each (seed 000 section 4.4). Their projections cannot overlap, so
    ///   their integrals add up exactly;
    /// - any other mesh light: the union of its front-facing triangles, one piece. The union, not
    ///   the sum, makes a non-convex light's self-occlusion right: where front faces overlap in
    ///   projection, the nearer one is seen, with the same radiance.
    ///
    /// # Errors
    ///
    /// As [`Scene::shade`], and those of [`SphericalPolygon::boolean`];
    /// [`GeomError::OutOfRange`] for a light index past the end.
    pub fn light_region(
        &self,
        light: usize,
        frame: &ShadingFrame,
    ) -> Result<Vec<SphericalPolygon>, GeomError> {
        let up = DVec3::Z;
        let shape = &self.light(light)?.shape;
        if let (Shape::Convex(p), Method::Silhouette) = (shape, self.method) {
            let s = convex_silhouette(p, frame)?.clip_to_hemisphere(up);
            return Ok(if s.is_empty() {
                Vec::new()
            } else {
                alloc::vec![s]
            });
        }
        let mesh = shape.mesh();
        let mut pieces = Vec::new();
        for t in 0..mesh.triangle_count() {
            if let Some(p) = triangle_polygon(mesh, t, frame, TriangleRole::Emitter)? {
                let p = p.clip_to_hemisphere(up);
                if !p.is_empty() {
                    pieces.push(p);
                }
            }
        }
        let disjoint = matches!(shape, Shape::Convex(_)) || mesh.is_planar();
        if disjoint || pieces.len() <= 1 {
            return Ok(pieces);
        }
        let mut union = pieces.pop().unwrap_or_default();
        for p in &pieces {
            union = union.boolean(p, BoolOp::Union)?;
        }
        Ok(alloc::vec![union])
    }

    /// The occlusion step of seed 000 Alg. 1 (lines 7-12): subtracts from the light's region the
    /// regions of the occluders that may lie between the point and the light ([`may_occlude`],
    /// the paper's `GetBetween`), each clipped to the upper hemisphere first (Alg. 1 line 10).
    ///
    /// A convex occluder subtracts its silhouette (with [`Method::Silhouette`]); a mesh occluder,
    /// or any occluder with [`Method::PerTriangle`], subtracts each of its triangles seen from
    /// either side (seed 000 section 4.4), after a per-triangle bounding-sphere cull.
    ///
    /// Occluders are assumed not to interpenetrate the light: an occluder partly behind the
    /// light (farther along some direction the light covers) is subtracted as if in front. The
    /// culling removes occluders entirely behind the light.
    ///
    /// # Errors
    ///
    /// As [`Scene::shade`], and those of [`SphericalPolygon::boolean`];
    /// [`GeomError::OutOfRange`] for a light index past the end.
    pub fn subtract_occluders(
        &self,
        light: usize,
        frame: &ShadingFrame,
        region: SphericalPolygon,
    ) -> Result<SphericalPolygon, GeomError> {
        let up = DVec3::Z;
        self.light(light)?;
        let mut vis = region;
        if vis.is_empty() {
            return Ok(vis);
        }
        let (x, n) = (frame.origin(), frame.normal());
        let lb = self.light_bounds[light];
        for o in self.occluders_between(light, frame) {
            match (&self.occluders[o], self.method) {
                (Shape::Convex(p), Method::Silhouette) => {
                    let occ = convex_silhouette(p, frame)?.clip_to_hemisphere(up);
                    if !occ.is_empty() {
                        vis = vis.boolean(&occ, BoolOp::Difference)?;
                    }
                }
                (shape, _) => {
                    let mesh = shape.mesh();
                    for t in 0..mesh.triangle_count() {
                        let tri = mesh.triangle(t);
                        let c = (tri[0] + tri[1] + tri[2]) / 3.0;
                        let r = tri.iter().map(|&v| (v - c).length()).fold(0.0, f64::max)
                            * (1.0 + 1e-12);
                        if !may_occlude(
                            x,
                            n,
                            lb,
                            BoundingSphere {
                                center: c,
                                radius: r,
                            },
                        ) {
                            continue;
                        }
                        if let Some(p) = triangle_polygon(mesh, t, frame, TriangleRole::Blocker)? {
                            let p = p.clip_to_hemisphere(up);
                            if !p.is_empty() {
                                vis = vis.boolean(&p, BoolOp::Difference)?;
                                if vis.is_empty() {
                                    return Ok(vis);
                                }
                            }
                        }
                    }
                }
            }
            if vis.is_empty() {
                break;
            }
        }
        Ok(vis)
    }
}

/// The LTC inverse matrix and the per-channel specular scale (`norm` with Schlick's Fresnel,
/// [`crate::ltc::LtcLookup::specular_scale`]) for the frame's view angle and the material's
/// roughness; `None` for a material without a specular lobe. One table lookup per shading point.
fn specular_setup(
    frame: &ShadingFrame,
    material: &Material,
) -> Result<Option<(DMat3, DVec3)>, GeomError> {
    if !material.has_specular() {
        return Ok(None);
    }
    let look = lookup(frame.view().z, material.alpha())?;
    let f0 = material.f0();
    let scale = DVec3::new(
        look.specular_scale(f0.x),
        look.specular_scale(f0.y),
        look.specular_scale(f0.z),
    );
    Ok(Some((look.m_inv, scale)))
}
