//! Scenes of lights and occluders, and the analytic shading of a point (seed 000 Alg. 1).

use alloc::vec::Vec;

use glam::{DMat3, DVec3};
use smallvec::SmallVec;

use super::brdf::Material;
use super::cull::{BoundingSphere, above_horizon, may_occlude};
use super::mesh::{ConvexPolyhedron, FACE_TOLERANCE, TriangleMesh};
use super::separation::{Separation, separating_plane};
use super::silhouette::{
    ShadingFrame, TriangleRole, clipped_triangle_polygon, convex_silhouette, triangle_polygon,
    triangle_side,
};
use crate::GeomError;
use crate::ltc::{clamped_cosine_integral_upper, lookup, ltc_integral};
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
/// # What blocks what
///
/// Every object is opaque. Occluders block every light; a light's geometry blocks every other
/// light (both its sides: only the front side emits, but all of it is solid), and a mesh light's
/// triangles block the rest of the same light. The [Monte Carlo reference](super::MonteCarlo)
/// models exactly the same thing. An object hides a direction only where it lies strictly
/// between the shading point and the light surface along that direction; see
/// [`Scene::visible_region`] for the exact rule and how it is evaluated.
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
    /// Per light `i` and blocker `j` (occluders first, then lights), at `i * blockers + j`: a
    /// plane separating the convex hulls of the two, or `None` when they overlap (the blocker
    /// interpenetrates the light, or is the light itself).
    separations: Vec<Option<Separation>>,
}

/// How a blocker acts on one front face of a light (or on all of them).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Reach {
    /// Entirely on the point's side of the face plane: hides all it covers.
    Whole,
    /// Nothing strictly on the point's side: hides nothing of the face.
    Nothing,
    /// On both sides: only the part on the point's side hides the face.
    Straddles,
}

impl Scene {
    /// A scene with the default [`Method::Silhouette`].
    ///
    /// Computes, once for the scene, a separating plane between every light and every other
    /// object (the fast path of [`Scene::visible_region`]): `lights x (occluders + lights)`
    /// minimum-norm-point runs, each a few passes over the two vertex lists (and, only for hulls
    /// that touch, one scan of their face normals).
    ///
    /// # Errors
    ///
    /// None today (lights and shapes are validated when built); the `Result` leaves room for
    /// scene-level checks.
    pub fn new(lights: Vec<Light>, occluders: Vec<Shape>) -> Result<Self, GeomError> {
        let light_bounds = lights.iter().map(|l| l.shape.bounding_sphere()).collect();
        let occluder_bounds = occluders.iter().map(Shape::bounding_sphere).collect();
        let mut separations = Vec::with_capacity(lights.len() * (occluders.len() + lights.len()));
        for (i, light) in lights.iter().enumerate() {
            let lm = light.shape.mesh();
            for o in &occluders {
                separations.push(separating_plane(lm, o.mesh()));
            }
            for (k, other) in lights.iter().enumerate() {
                separations.push(if k == i {
                    None
                } else {
                    separating_plane(lm, other.shape.mesh())
                });
            }
        }
        Ok(Scene {
            lights,
            occluders,
            light_bounds,
            occluder_bounds,
            method: Method::Silhouette,
            separations,
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
    /// culling of [`may_occlude`]). Other lights block too ([`Scene::blockers_between`]).
    pub fn occluders_between(
        &self,
        light: usize,
        frame: &ShadingFrame,
    ) -> impl Iterator<Item = usize> + '_ {
        let no = self.occluders.len();
        self.blockers_between(light, frame).filter(move |&j| j < no)
    }

    /// Number of blockers of a light: every occluder, then every light (the light itself among
    /// them, never returned by [`Scene::blockers_between`]).
    fn blocker_count(&self) -> usize {
        self.occluders.len() + self.lights.len()
    }

    /// The geometry and bounding sphere of blocker `j` (occluders first, then lights).
    fn blocker(&self, j: usize) -> (&Shape, BoundingSphere) {
        let no = self.occluders.len();
        if j < no {
            (&self.occluders[j], self.occluder_bounds[j])
        } else {
            (&self.lights[j - no].shape, self.light_bounds[j - no])
        }
    }

    /// Indices of the objects that may hide part of light `light` from the frame's point: the
    /// occluders (`0..occluders().len()`) and the other lights (`occluders().len() + k` for light
    /// `k`) that pass the culling of [`may_occlude`] (seed 000 `GetBetween`, section 3.5) and
    /// that do not lie entirely behind the light as seen from the point (the precomputed
    /// separating plane has the point on the light's side). An invalid light index has none.
    pub fn blockers_between(
        &self,
        light: usize,
        frame: &ShadingFrame,
    ) -> impl Iterator<Item = usize> + '_ {
        let (x, n) = (frame.origin(), frame.normal());
        let lb = self.light_bounds.get(light).copied();
        let count = if lb.is_some() {
            self.blocker_count()
        } else {
            0
        };
        let lb = lb.unwrap_or(BoundingSphere {
            center: DVec3::ZERO,
            radius: 0.0,
        });
        let no = self.occluders.len();
        (0..count).filter(move |&j| {
            if j == no + light {
                return false;
            }
            if let Some(sep) = self.separations[light * count + j]
                && !sep.blocker_side(x)
            {
                return false;
            }
            may_occlude(x, n, lb, self.blocker(j).1)
        })
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
            // The visible pieces are already clipped to the upper hemisphere.
            diffuse += clamped_cosine_integral_upper(&vis);
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
    /// the upper hemisphere, as pieces with disjoint interiors whose integrals add up.
    ///
    /// # The exact rule
    ///
    /// Take a front face `f` of the light (a planar polygon facing the point `x`) and a direction
    /// `d` in its projection: the ray from `x` meets `f` at a point `e`, and `d` is blocked iff
    /// some opaque point lies on the ray before `e`. The ray crosses `f`'s plane only at `e`, so
    /// the points before `e` are exactly the ray's points strictly on `x`'s side of that plane:
    ///
    /// `visible(f) = proj(f) - U_B proj(B n H_f)`, with `H_f` the open half-space of `f`'s plane
    /// holding `x`, and `B` every blocker: occluders, the other lights, and, for a non-planar
    /// mesh light, its own other triangles. The light's visible region is
    /// the union of `visible(f)` over its front faces; with the light's own triangles among the
    /// blockers each direction survives in at most one `visible(f)` (the face met first), so the
    /// pieces have disjoint interiors and their integrals add up. Points of a blocker in `f`'s
    /// plane, or touching it from behind, are met no earlier than the light and hide nothing,
    /// as in the Monte Carlo reference.
    ///
    /// # How it is evaluated
    ///
    /// 1. Blockers that cannot be in front are culled ([`Scene::blockers_between`]).
    /// 2. A blocker whose convex hull is disjoint from the light's has a separating plane
    ///    (precomputed): with `x` on the blocker's side it lies in every `H_f`, since every ray
    ///    crosses the plane once, blocker first. It is then subtracted whole from the light's
    ///    region (seed 000 Alg. 1 lines 7-12): the silhouette path stays as fast as before.
    ///    With `x` on the light's side it hides nothing (culled in step 1).
    /// 3. A blocker that interpenetrates the light is tested against each front face's plane
    ///    (its vertices, with [`FACE_TOLERANCE`] relative to the pair's size): entirely in every
    ///    `H_f`, it is subtracted whole as in 2; in none, it is dropped.
    /// 4. Otherwise, and for open non-planar mesh lights, the light is handled face by face: each
    ///    front triangle's projection (seed 000 section 4.4) minus the blockers that are whole on
    ///    its side, minus each triangle of a straddling blocker cut by the face plane to its part
    ///    on `x`'s side (for a convex blocker seen from outside only its front triangles: a ray
    ///    enters it through one of those first), minus, for a non-planar mesh light, its own
    ///    other triangles cut the same way.
    ///
    /// A closed or planar mesh light without straddling blockers keeps the union of its front
    /// faces ([`Scene::light_region`]): seen from outside a closed surface a ray meets a front
    /// face first, so no triangle of the light can hide a front face that the union keeps.
    ///
    /// # Errors
    ///
    /// As [`Scene::light_region`], and those of [`SphericalPolygon::boolean`];
    /// [`GeomError::OutOfRange`] for a light index past the end.
    pub fn visible_region(
        &self,
        light: usize,
        frame: &ShadingFrame,
    ) -> Result<Vec<SphericalPolygon>, GeomError> {
        let shape = &self.light(light)?.shape;
        let mesh = shape.mesh();
        let count = self.blocker_count();
        // Step 2: separated blockers (culled ones, behind the light, are not even listed).
        let mut whole: SmallVec<[usize; 8]> = SmallVec::new();
        let mut overlapping: SmallVec<[usize; 4]> = SmallVec::new();
        for j in self.blockers_between(light, frame) {
            if self.separations[light * count + j].is_some() {
                whole.push(j);
            } else {
                overlapping.push(j);
            }
        }
        // A non-planar mesh light can hide itself: face by face, its own triangles are blockers
        // (planar and convex lights cannot hide themselves). Closed ones need the face-by-face
        // path only when a blocker straddles; open ones always (a back face can be met first).
        let own_blockers = matches!(shape, Shape::Mesh(_)) && !mesh.is_planar();
        let self_blocking = own_blockers && !mesh.is_closed();
        // Step 3: interpenetrating blockers that still act the same on every front face.
        let x = frame.origin();
        let faces: SmallVec<[usize; 16]> = if overlapping.is_empty() && !self_blocking {
            SmallVec::new()
        } else {
            (0..mesh.triangle_count())
                .filter(|&t| triangle_side(mesh, t, x) > 0)
                .collect()
        };
        // Straddling blockers keep how they act on each front face (in the order of `faces`),
        // for step 4.
        let mut straddling: SmallVec<[(usize, SmallVec<[Reach; 16]>); 4]> = SmallVec::new();
        for &j in &overlapping {
            let reach: SmallVec<[Reach; 16]> =
                faces.iter().map(|&f| self.reach(light, j, f)).collect();
            let first = reach.first().copied().unwrap_or(Reach::Nothing);
            match (first, reach.iter().all(|&r| r == first)) {
                (Reach::Whole, true) => whole.push(j),
                (Reach::Nothing, true) => {}
                _ => straddling.push((j, reach)),
            }
        }
        if straddling.is_empty() && !self_blocking {
            let mut out = self.light_region(light, frame)?;
            if !whole.is_empty() {
                let mut regions = Vec::new();
                for &j in &whole {
                    self.blocker_regions(light, j, frame, &mut regions)?;
                }
                for piece in &mut out {
                    *piece = subtract_all(core::mem::take(piece), &regions)?;
                }
                out.retain(|p| !p.is_empty());
            }
            return Ok(out);
        }
        // Step 4: face by face.
        let up = DVec3::Z;
        let mut whole_regions = Vec::new();
        for &j in &whole {
            self.blocker_regions(light, j, frame, &mut whole_regions)?;
        }
        // Whole regions of the straddling blockers, built on first use.
        let mut cached: SmallVec<[Option<Vec<SphericalPolygon>>; 4]> =
            straddling.iter().map(|_| None).collect();
        let mut out = Vec::new();
        for (fi, &f) in faces.iter().enumerate() {
            let Some(piece) = triangle_polygon(mesh, f, frame, TriangleRole::Emitter)? else {
                continue;
            };
            let mut piece = subtract_all(piece.clip_to_hemisphere(up), &whole_regions)?;
            for (k, (j, reach)) in straddling.iter().enumerate() {
                let j = *j;
                if piece.is_empty() {
                    break;
                }
                match reach[fi] {
                    Reach::Nothing => {}
                    Reach::Whole => {
                        if cached[k].is_none() {
                            let mut r = Vec::new();
                            self.blocker_regions(light, j, frame, &mut r)?;
                            cached[k] = Some(r);
                        }
                        piece = subtract_all(piece, cached[k].as_deref().unwrap_or(&[]))?;
                    }
                    Reach::Straddles => {
                        let (b, _) = self.blocker(j);
                        let tol = self.pair_tolerance(light, j);
                        piece = self.subtract_cut(piece, b, true, mesh, f, tol, frame)?;
                    }
                }
            }
            if own_blockers && !piece.is_empty() {
                let tol = self.pair_tolerance(light, self.occluders.len() + light);
                piece = self.subtract_cut(piece, shape, false, mesh, f, tol, frame)?;
            }
            if !piece.is_empty() {
                out.push(piece);
            }
        }
        Ok(out)
    }

    /// How blocker `j` acts on front triangle `f` of light `light` (step 3 of
    /// [`Scene::visible_region`]): the signs of its vertices' distances from `f`'s plane, with
    /// distances within [`Scene::pair_tolerance`] taken as zero.
    fn reach(&self, light: usize, j: usize, f: usize) -> Reach {
        let mesh = self.lights[light].shape.mesh();
        let (n, a) = (mesh.triangle_normal(f), mesh.triangle(f)[0]);
        let tol = self.pair_tolerance(light, j);
        let (mut front, mut behind) = (false, false);
        for &v in self.blocker(j).0.mesh().vertices() {
            let s = n.dot(v - a);
            front |= s > tol;
            behind |= s < -tol;
        }
        match (front, behind) {
            (true, false) => Reach::Whole,
            (false, _) => Reach::Nothing,
            (true, true) => Reach::Straddles,
        }
    }

    /// Distance from a light's face plane below which a blocker vertex counts as on the plane:
    /// [`FACE_TOLERANCE`] times the pair's size. The distance `n . (v - a)` is taken from a
    /// vertex `a` of the face, so its rounding is a few ulps of `|v - a|`, which the pair's size
    /// bounds.
    fn pair_tolerance(&self, light: usize, j: usize) -> f64 {
        let lb = self.light_bounds[light];
        let bb = self.blocker(j).1;
        FACE_TOLERANCE * (lb.radius + bb.radius + (lb.center - bb.center).length())
    }

    /// Subtracts from `piece` (part of light face `f` of `light_mesh`) the triangles of `blocker`
    /// cut to their parts strictly on the shading point's side of `f`'s plane (step 4 of
    /// [`Scene::visible_region`]). `external` is false when the blocker is the light's own mesh
    /// (then `f` itself is skipped).
    #[allow(clippy::too_many_arguments)]
    fn subtract_cut(
        &self,
        mut piece: SphericalPolygon,
        blocker: &Shape,
        external: bool,
        light_mesh: &TriangleMesh,
        f: usize,
        tol: f64,
        frame: &ShadingFrame,
    ) -> Result<SphericalPolygon, GeomError> {
        let up = DVec3::Z;
        let (x, up_world) = (frame.origin(), frame.normal());
        let (n, a) = (light_mesh.triangle_normal(f), light_mesh.triangle(f)[0]);
        let face_bound = triangle_bound(light_mesh.triangle(f));
        let bm = blocker.mesh();
        // Seen from outside a convex blocker, a ray enters through a front triangle before it can
        // meet a back one, so the back ones add nothing.
        let front_only = matches!(blocker, Shape::Convex(_))
            && (0..bm.triangle_count()).any(|t| triangle_side(bm, t, x) > 0);
        for t in 0..bm.triangle_count() {
            if (!external && t == f) || (front_only && triangle_side(bm, t, x) < 0) {
                continue;
            }
            // Only a triangle whose cone from x meets the face's can hide part of it.
            if !may_occlude(x, up_world, face_bound, triangle_bound(bm.triangle(t))) {
                continue;
            }
            let dist = bm.triangle(t).map(|v| {
                let s = n.dot(v - a);
                if s.abs() <= tol { 0.0 } else { s }
            });
            if let Some(p) = clipped_triangle_polygon(bm, t, dist, frame)? {
                let p = p.clip_to_hemisphere(up);
                if !p.is_empty() {
                    piece = piece.boolean(&p, BoolOp::Difference)?;
                    if piece.is_empty() {
                        break;
                    }
                }
            }
        }
        Ok(piece)
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

    /// Appends to `out` the regions blocker `j` covers, clipped to the upper hemisphere (seed
    /// 000 Alg. 1 line 10): a convex blocker's silhouette with [`Method::Silhouette`]; otherwise
    /// each of its triangles seen from either side (seed 000 section 4.4), after a per-triangle
    /// bounding-sphere cull against light `light`.
    fn blocker_regions(
        &self,
        light: usize,
        j: usize,
        frame: &ShadingFrame,
        out: &mut Vec<SphericalPolygon>,
    ) -> Result<(), GeomError> {
        let up = DVec3::Z;
        let (x, n) = (frame.origin(), frame.normal());
        let lb = self.light_bounds[light];
        match (self.blocker(j).0, self.method) {
            (Shape::Convex(p), Method::Silhouette) => {
                let occ = convex_silhouette(p, frame)?.clip_to_hemisphere(up);
                if !occ.is_empty() {
                    out.push(occ);
                }
            }
            (shape, _) => {
                let mesh = shape.mesh();
                for t in 0..mesh.triangle_count() {
                    if !may_occlude(x, n, lb, triangle_bound(mesh.triangle(t))) {
                        continue;
                    }
                    if let Some(p) = triangle_polygon(mesh, t, frame, TriangleRole::Blocker)? {
                        let p = p.clip_to_hemisphere(up);
                        if !p.is_empty() {
                            out.push(p);
                        }
                    }
                }
            }
        }
        Ok(())
    }
}

/// A sphere holding a triangle (about its centroid, padded by a relative ulp margin), for the
/// per-triangle culling.
fn triangle_bound(tri: [DVec3; 3]) -> BoundingSphere {
    let c = (tri[0] + tri[1] + tri[2]) / 3.0;
    let r = tri.iter().map(|&v| (v - c).length()).fold(0.0, f64::max) * (1.0 + 1e-12);
    BoundingSphere {
        center: c,
        radius: r,
    }
}

/// `piece` minus every region of `regions`, in turn (seed 000 Alg. 1 line 12), stopping once
/// nothing is left.
fn subtract_all(
    mut piece: SphericalPolygon,
    regions: &[SphericalPolygon],
) -> Result<SphericalPolygon, GeomError> {
    for r in regions {
        if piece.is_empty() {
            break;
        }
        piece = piece.boolean(r, BoolOp::Difference)?;
    }
    Ok(piece)
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
