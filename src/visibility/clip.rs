//! The clipping backend: the exact visibility rule evaluated with spherical set operations
//! (seed 000 Alg. 1, extended to blockers that interpenetrate or hide lights).

use alloc::vec::Vec;

use glam::DVec3;
use smallvec::SmallVec;

use super::contour::MeshContours;
use super::cull::{LightCone, Shaft, above_horizon, may_occlude, shaft_triangles};
use super::pieces::{CellTables, ConvexFaces};
use super::union::{BlockerAccel, BlockerGeometry, LightRegion, one_pass};
use super::{Blocker, Visibility};
use crate::GeomError;
use crate::planar::BoolOp;
use crate::solid::facing::{Side, face_side, snapped_distance};
use crate::solid::separation::{Separation, separating_plane};
use crate::solid::silhouette::{
    TriangleRole, clipped_triangle_polygon, convex_silhouette, nonconvex_silhouette,
    triangle_polygon,
};
use crate::solid::{Body, BoundingSphere, Bvh, ClosedMesh, ShadingFrame, TriangleMesh};
use crate::sphere::SphericalPolygon;

/// What a failed union of a mesh light's front faces reports: the faces are valid polygons, so
/// any error of [`SphericalPolygon::boolean`] is a rounding give-up.
const UNION_FAILED: &str = "the union of a mesh light's front triangles failed within rounding";

/// What a face's piece that grew under subtractions reports (the face-by-face path of
/// [`ClipVisibility::visible_region`]).
const DIFFERENCE_GREW: &str =
    "subtracting blockers from a light face returned more than the face within rounding";

/// What a failed subtraction of a blocker's region reports (as [`UNION_FAILED`]).
const DIFFERENCE_FAILED: &str =
    "subtracting a blocker's region from a light's region failed within rounding";

/// How objects are turned into spherical polygons and combined.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[non_exhaustive]
pub enum Method {
    /// One silhouette polygon per convex polyhedron (seed 000 Alg. 2), meshes by their
    /// triangles inside the shaft to the light, all blockers that lie wholly on the point's side
    /// of the light removed in one planar pass (see `visibility/union.rs`); a closed mesh
    /// light's region is the union of its front faces computed in the same chart.
    #[default]
    Silhouette,
    /// As [`Method::Silhouette`] for convex shapes and mesh lights, but every blocker region
    /// (a convex silhouette, or each triangle of a mesh) subtracted in turn by its own spherical
    /// boolean, as seed 000 Alg. 1 is written: the path before the one-pass union, kept for
    /// comparisons.
    Sequential,
    /// Every shape per triangle (seed 000 section 4.4), convex ones included, subtracted in
    /// turn. Slower; it exists as a cross-check of the silhouette paths and for comparisons.
    PerTriangle,
}

/// The clipping backend of [`Visibility`]: lights (anything that has a [`Body`]) and occluders,
/// with what is precomputed once per scene (bounding spheres, and a plane separating each light
/// from each other object where one exists).
///
/// Every object is opaque: occluders block every light; a light's geometry blocks every other
/// light (both its sides), and a mesh light's triangles block the rest of the same light. An
/// object hides a direction only where it lies strictly between the shading point and the light
/// surface along that direction; see [`ClipVisibility::visible_region`] for the exact rule and
/// how it is evaluated.
#[derive(Debug, Clone, PartialEq)]
pub struct ClipVisibility<L> {
    lights: Vec<L>,
    occluders: Vec<Body>,
    pub(super) light_bounds: Vec<BoundingSphere>,
    occluder_bounds: Vec<BoundingSphere>,
    pub(super) method: Method,
    /// Per light: its mesh validated as a solid ([`ClosedMesh`]) when it is a closed,
    /// non-planar mesh light that bounds one (then its region is its non-convex silhouette).
    solids: Vec<Option<ClosedMesh>>,
    /// Per light `i` and blocker slot `j` (occluders first, then lights, see
    /// [`ClipVisibility::slot`]), at `i * blockers + j`: a plane separating the convex hulls of
    /// the two, or `None` when they overlap (the blocker interpenetrates the light, or is the
    /// light itself).
    separations: Vec<Option<Separation>>,
    /// Per planar mesh light: its [`Outline`], for the fast path
    /// ([`ClipVisibility::visible_pieces`]).
    pub(super) outlines: Vec<Option<Outline>>,
    /// Per blocker slot: a bounding-volume hierarchy over the triangles of a body with at least
    /// [`BVH_MIN_TRIANGLES`] of them, for culling by shafts, and whether front faces alone
    /// cover what a closed mesh hides.
    accels: Vec<BlockerAccel>,
    /// Per light and blocker slot, as `separations`: some vertex of the blocker lies in the
    /// plane of one of the light's triangles (by [`face_side`]). Such a blocker is never
    /// subtracted whole (see [`ClipVisibility::visible_region`], step 2).
    touching: Vec<bool>,
    /// Per blocker slot: a small convex body's facing planes and contour candidates, for the
    /// fast path's silhouettes ([`ConvexFaces`]).
    faces: Vec<Option<ConvexFaces>>,
}

/// Bodies with at least this many triangles get a [`Bvh`]; for fewer, testing every triangle
/// against a shaft costs less than descending a tree.
pub const BVH_MIN_TRIANGLES: usize = 32;

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

impl<L: AsRef<Body>> ClipVisibility<L> {
    /// The backend for these lights and occluders, with the default [`Method::Silhouette`].
    ///
    /// Computes, once, a separating plane between every light and every other object (the fast
    /// path of [`ClipVisibility::visible_region`]): `lights x (occluders + lights)`
    /// minimum-norm-point runs, each a few passes over the two vertex lists (and, only for hulls
    /// that touch, one scan of their face normals); and validates each closed non-planar mesh
    /// light as a solid ([`ClosedMesh::new`], about `n log n` in its triangle count), which
    /// lets its region be its silhouette.
    #[must_use]
    pub fn new(lights: Vec<L>, occluders: Vec<Body>) -> Self {
        let light_bounds = lights
            .iter()
            .map(|l| l.as_ref().bounding_sphere())
            .collect();
        let occluder_bounds = occluders.iter().map(Body::bounding_sphere).collect();
        let mut separations = Vec::with_capacity(lights.len() * (occluders.len() + lights.len()));
        let mut touching = Vec::with_capacity(separations.capacity());
        for (i, light) in lights.iter().enumerate() {
            let lm = light.as_ref().mesh();
            let touches = |m: &TriangleMesh| {
                let b = m.bounding_sphere();
                (0..lm.triangle_count()).any(|f| {
                    // Only a blocker whose bounding sphere reaches the plane has vertices on it
                    // (with a margin far above the facing tolerance).
                    let n = lm.triangle_normal(f);
                    let d = n.dot(b.center - lm.triangle(f)[0]).abs();
                    d <= b.radius * (1.0 + 1e-6) + 1e-6 * lm.bounding_sphere().radius
                        && m.vertices()
                            .iter()
                            .any(|&v| face_side(lm, f, v) == Side::On)
                })
            };
            for o in &occluders {
                separations.push(separating_plane(lm, o.mesh()));
                touching.push(touches(o.mesh()));
            }
            for (k, other) in lights.iter().enumerate() {
                separations.push(if k == i {
                    None
                } else {
                    separating_plane(lm, other.as_ref().mesh())
                });
                touching.push(k != i && touches(other.as_ref().mesh()));
            }
        }
        let accels = occluders
            .iter()
            .chain(lights.iter().map(AsRef::as_ref))
            .map(|b| BlockerAccel::new(b, BVH_MIN_TRIANGLES))
            .collect();
        let mut tables = CellTables::new();
        let faces = occluders
            .iter()
            .chain(lights.iter().map(AsRef::as_ref))
            .map(|b| match b {
                Body::Convex(p) => ConvexFaces::of_sharing(p, &mut tables),
                _ => None,
            })
            .collect();
        let solids = lights
            .iter()
            .map(|l| match l.as_ref() {
                Body::Mesh(m) if m.is_closed() && !m.is_planar() => ClosedMesh::new(m.clone()).ok(),
                _ => None,
            })
            .collect();
        let outlines = lights
            .iter()
            .map(|l| match l.as_ref() {
                Body::Mesh(m) if m.is_planar() => Outline::of(m),
                _ => None,
            })
            .collect();
        ClipVisibility {
            lights,
            occluders,
            light_bounds,
            occluder_bounds,
            method: Method::Silhouette,
            solids,
            separations,
            outlines,
            accels,
            touching,
            faces,
        }
    }

    /// The same backend with another [`Method`].
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
    pub fn lights(&self) -> &[L] {
        &self.lights
    }

    /// The occluders.
    #[must_use]
    pub fn occluders(&self) -> &[Body] {
        &self.occluders
    }

    /// The body of light `i`, or [`GeomError::OutOfRange`] past the end.
    pub(super) fn light_body(&self, i: usize) -> Result<&Body, GeomError> {
        self.lights
            .get(i)
            .map(AsRef::as_ref)
            .ok_or(GeomError::OutOfRange {
                what: "light index",
                value: i as f64,
                limit: self.lights.len() as f64,
            })
    }

    /// Number of blocker slots per light: every occluder, then every light (the light itself
    /// among them, never returned by [`ClipVisibility::blockers_between`]).
    pub(super) fn blocker_count(&self) -> usize {
        self.occluders.len() + self.lights.len()
    }

    /// The blocker's slot in a light's row of [`ClipVisibility::separations`].
    pub(super) fn slot(&self, b: Blocker) -> usize {
        match b {
            Blocker::Occluder(k) => k,
            Blocker::Light(k) => self.occluders.len() + k,
        }
    }

    /// The precomputed separating plane between light `light` and blocker `b`, if any.
    pub(super) fn separation(&self, light: usize, b: Blocker) -> Option<Separation> {
        self.separations[light * self.blocker_count() + self.slot(b)]
    }

    /// Whether convex shapes are taken by their silhouettes.
    fn silhouettes(&self) -> bool {
        self.method != Method::PerTriangle
    }

    /// The bounding-volume hierarchy of a blocker's triangles, if it has one.
    pub(super) fn bvh(&self, b: Blocker) -> Option<&Bvh> {
        self.accels[self.slot(b)].bvh.as_ref()
    }

    /// The precomputed contour structure of blocker `b`, if it is a closed mesh
    /// (`visibility/contour.rs`).
    pub(super) fn contours(&self, b: Blocker) -> Option<&MeshContours> {
        self.accels[self.slot(b)].contours.as_ref()
    }

    /// Bytes held by the contour structures of closed meshes (edges with their faces by
    /// component, facing hierarchies, component boxes and their hierarchy), and the number of
    /// triangles they cover.
    #[must_use]
    pub fn contour_bytes(&self) -> (usize, usize) {
        self.occluders
            .iter()
            .chain(self.lights.iter().map(AsRef::as_ref))
            .zip(&self.accels)
            .filter_map(|(b, a)| Some((a.contours.as_ref()?, b.mesh().triangle_count())))
            .fold((0, 0), |(b, t), (c, n)| (b + c.byte_size(), t + n))
    }

    /// Bytes held by the bounding-volume hierarchies of all objects, and the number of
    /// triangles they cover.
    #[must_use]
    pub fn bvh_bytes(&self) -> (usize, usize) {
        self.accels
            .iter()
            .filter_map(|a| a.bvh.as_ref())
            .fold((0, 0), |(b, t), h| {
                (b + h.byte_size(), t + h.triangle_count())
            })
    }

    /// The precomputed facing planes and edges of blocker `b`, if it is a small convex body.
    pub(super) fn convex_faces(&self, b: Blocker) -> Option<&ConvexFaces> {
        self.faces[self.slot(b)].as_ref()
    }

    /// [`ClipVisibility::separation`] (by reference) and [`ClipVisibility::touches`] together.
    pub(super) fn pair(&self, light: usize, b: Blocker) -> (Option<&Separation>, bool) {
        let k = light * self.blocker_count() + self.slot(b);
        (self.separations[k].as_ref(), self.touching[k])
    }

    /// Whether blocker `b` has a vertex in the plane of a triangle of light `light`.
    pub(super) fn touches(&self, light: usize, b: Blocker) -> bool {
        self.touching[light * self.blocker_count() + self.slot(b)]
    }

    /// The geometry and bounding sphere of a blocker.
    pub(super) fn blocker(&self, b: Blocker) -> (&Body, BoundingSphere) {
        match b {
            Blocker::Occluder(k) => (&self.occluders[k], self.occluder_bounds[k]),
            Blocker::Light(k) => (self.lights[k].as_ref(), self.light_bounds[k]),
        }
    }

    /// The objects that may hide part of light `light` from the frame's point: the occluders
    /// and the other lights that pass the culling of `may_occlude` (seed 000 `GetBetween`,
    /// section 3.5) and that do not lie entirely behind the light as seen from the point (the
    /// precomputed separating plane has the point on the light's side). An invalid light index
    /// has none.
    pub fn blockers_between(
        &self,
        light: usize,
        frame: &ShadingFrame,
    ) -> impl Iterator<Item = Blocker> + '_ {
        let (x, n) = (frame.origin(), frame.normal());
        let lb = self.light_bounds.get(light).copied();
        let (no, nl) = if lb.is_some() {
            (self.occluders.len(), self.lights.len())
        } else {
            (0, 0)
        };
        let lb = lb.unwrap_or(BoundingSphere {
            center: DVec3::ZERO,
            radius: 0.0,
        });
        let cone = LightCone::new(x, n, lb);
        (0..no)
            .map(Blocker::Occluder)
            .chain((0..nl).filter(move |&k| k != light).map(Blocker::Light))
            .filter(move |&b| {
                if let Some(sep) = self.separation(light, b)
                    && !sep.blocker_side(x)
                {
                    return false;
                }
                cone.may_occlude(self.blocker(b).1)
            })
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
    /// 1. A light entirely below the horizon is empty. Blockers that cannot be in front are
    ///    culled ([`ClipVisibility::blockers_between`]).
    /// 2. A blocker whose convex hull is disjoint from the light's has a separating plane
    ///    (precomputed): with `x` on the blocker's side it lies in every `H_f`, since every ray
    ///    crosses the plane once, blocker first. It is then subtracted whole from the light's
    ///    region (seed 000 Alg. 1 lines 7-12), which costs one dot product per point beyond the
    ///    paper's plain subtraction. With `x` on the light's side it hides nothing (culled in
    ///    step 1). A blocker that touches the plane of a light triangle (a vertex on it by
    ///    [`face_side`], e.g. a box hanging from a quad light) is not in the open `H_f` there:
    ///    it goes to step 3.
    /// 3. A blocker that interpenetrates or touches the light is tested against each front
    ///    face's plane (its vertices, by the facing predicate [`face_side`]): entirely in
    ///    every `H_f`, with no vertex on a face plane, it is subtracted whole as in 2; in none,
    ///    it is dropped. Its points in a face's plane hide nothing of that face: subtracted
    ///    whole, a face of the blocker lying in the light's plane would hide the directions
    ///    through it from a point inside the blocker or on its surface, so such a blocker
    ///    straddles (step 4).
    /// 4. Otherwise, and for open non-planar mesh lights, the light is handled face by face: each
    ///    front triangle's projection (seed 000 section 4.4) minus the blockers that are whole on
    ///    its side, minus each triangle of a straddling blocker cut by the face plane to its part
    ///    on `x`'s side (for a convex blocker seen from outside only its front triangles: a ray
    ///    enters it through one of those first), minus, for a non-planar mesh light, its own
    ///    other triangles cut the same way. A light bounded by Bezier curves is one face here:
    ///    its per-point flattening ([`crate::solid::BezierShape::region`]), not its mesh.
    ///
    /// A closed or planar mesh light without straddling blockers keeps the union of its front
    /// faces ([`ClipVisibility::light_region`]): seen from outside a closed surface a ray meets a
    /// front face first, so no triangle of the light can hide a front face that the union keeps.
    ///
    /// # Errors
    ///
    /// [`GeomError::OutOfRange`] for a light index past the end; otherwise only
    /// [`GeomError::Undecidable`]: the geometry is valid (checked when built), so a silhouette or
    /// a spherical set operation that fails within rounding is a give-up.
    pub fn visible_region(
        &self,
        light: usize,
        frame: &ShadingFrame,
    ) -> Result<Vec<SphericalPolygon>, GeomError> {
        self.region(light, frame, true)
    }

    /// [`ClipVisibility::visible_region`] with all blockers (`blocked`) or none but the light's
    /// own triangles. The pieces of the paths that run many set operations on single or cut
    /// triangles (the per-triangle method, mesh lights, face by face) are checked by
    /// [`upper_pieces`]; the silhouette of a convex light minus whole silhouettes, the path a
    /// renderer runs most, costs no check.
    fn region(
        &self,
        light: usize,
        frame: &ShadingFrame,
        blocked: bool,
    ) -> Result<Vec<SphericalPolygon>, GeomError> {
        let (pieces, checked) = self.region_unchecked(light, frame, blocked)?;
        if checked {
            upper_pieces(pieces)
        } else {
            Ok(pieces)
        }
    }

    /// The region and whether its pieces need [`upper_pieces`] (see [`ClipVisibility::region`]).
    fn region_unchecked(
        &self,
        light: usize,
        frame: &ShadingFrame,
        blocked: bool,
    ) -> Result<(Vec<SphericalPolygon>, bool), GeomError> {
        let body = self.light_body(light)?;
        if !above_horizon(frame.origin(), frame.normal(), self.light_bounds[light])
            || self.seen_from_inside(light, body, frame.origin())
        {
            return Ok((Vec::new(), false));
        }
        let mesh = body.mesh();
        // Step 2: separated blockers (culled ones, behind the light, are not even listed).
        let mut whole: SmallVec<[Blocker; 8]> = SmallVec::new();
        let mut overlapping: SmallVec<[Blocker; 4]> = SmallVec::new();
        if blocked {
            for b in self.blockers_between(light, frame) {
                if self.separation(light, b).is_some() && !self.touches(light, b) {
                    whole.push(b);
                } else {
                    overlapping.push(b);
                }
            }
        }
        // A non-planar mesh light can hide itself: face by face, its own triangles are blockers
        // (planar and convex lights cannot hide themselves). Closed ones need the face-by-face
        // path only when a blocker straddles; open ones always (a back face can be met first).
        let own_blockers = matches!(body, Body::Mesh(_)) && !mesh.is_planar();
        let self_blocking = own_blockers && !mesh.is_closed();
        // Step 3: interpenetrating blockers that still act the same on every front face.
        let x = frame.origin();
        // A light bounded by curves goes face by face as one face, its per-point flattening
        // (`BezierShape::region`), in the plane of its mesh's first triangle: its mesh is a
        // fixed flattening, coarser than that one seen from near points.
        let curved = matches!(body, Body::Bezier(_));
        let faces: SmallVec<[usize; 16]> = if overlapping.is_empty() && !self_blocking {
            SmallVec::new()
        } else if curved {
            (face_side(mesh, 0, x) == Side::Front)
                .then_some(0)
                .into_iter()
                .collect()
        } else {
            (0..mesh.triangle_count())
                .filter(|&t| face_side(mesh, t, x) == Side::Front)
                .collect()
        };
        // Straddling blockers keep how they act on each front face (in the order of `faces`),
        // for step 4.
        let mut straddling: SmallVec<[(Blocker, SmallVec<[Reach; 16]>); 4]> = SmallVec::new();
        for &b in &overlapping {
            let reach: SmallVec<[Reach; 16]> =
                faces.iter().map(|&f| self.reach(light, b, f)).collect();
            let first = reach.first().copied().unwrap_or(Reach::Nothing);
            match (first, reach.iter().all(|&r| r == first)) {
                (Reach::Whole, true) => whole.push(b),
                (Reach::Nothing, true) => {}
                _ => straddling.push((b, reach)),
            }
        }
        if straddling.is_empty() && !self_blocking {
            if self.method == Method::Silhouette
                && let Some(out) = self.one_pass_region(light, frame, &whole)?
            {
                return Ok((out, true));
            }
            let mut out = self.light_region_unchecked(light, frame)?;
            if !whole.is_empty() {
                let mut regions = Vec::new();
                for &b in &whole {
                    self.blocker_regions(light, b, frame, &mut regions)?;
                }
                for piece in &mut out {
                    *piece = subtract_all(core::mem::take(piece), &regions)?;
                }
                out.retain(|p| !p.is_empty());
            }
            // Checked where pieces came out of set operations on single triangles: differences
            // (whole blockers) or the union of a non-convex mesh light's front faces.
            let silhouette = matches!(body, Body::Convex(_)) && self.silhouettes();
            let combined =
                !whole.is_empty() || (matches!(body, Body::Mesh(_)) && !mesh.is_planar());
            return Ok((out, !silhouette && combined));
        }
        // Step 4: face by face.
        let mut whole_regions = Vec::new();
        for &b in &whole {
            self.blocker_regions(light, b, frame, &mut whole_regions)?;
        }
        // Whole regions of the straddling blockers, built on first use.
        let mut cached: SmallVec<[Option<Vec<SphericalPolygon>>; 4]> =
            straddling.iter().map(|_| None).collect();
        let mut out = Vec::new();
        for (fi, &f) in faces.iter().enumerate() {
            let (piece, face_bound) = match body {
                Body::Bezier(b) => (b.region(frame)?, self.light_bounds[light]),
                _ => match triangle_polygon(mesh, f, frame, TriangleRole::Emitter)? {
                    Some(p) => (p, triangle_bound(mesh.triangle(f))),
                    None => continue,
                },
            };
            let face_part = upper_part(&piece)?;
            let mut piece = subtract_all(face_part.clone(), &whole_regions)?;
            for (k, (b, reach)) in straddling.iter().enumerate() {
                let b = *b;
                if piece.is_empty() {
                    break;
                }
                match reach[fi] {
                    Reach::Nothing => {}
                    Reach::Whole => {
                        if cached[k].is_none() {
                            let mut r = Vec::new();
                            self.blocker_regions(light, b, frame, &mut r)?;
                            cached[k] = Some(r);
                        }
                        piece = subtract_all(piece, cached[k].as_deref().unwrap_or(&[]))?;
                    }
                    Reach::Straddles => {
                        let (body, _) = self.blocker(b);
                        let cut = (mesh, f, face_bound);
                        piece = subtract_cut(piece, body, self.bvh(b), true, cut, frame)?;
                    }
                }
            }
            if own_blockers && !piece.is_empty() {
                let own = self.bvh(Blocker::Light(light));
                piece = subtract_cut(piece, body, own, false, (mesh, f, face_bound), frame)?;
            }
            if !piece.is_empty() {
                // Differences only remove: a piece larger than the face's part it started from
                // is a set operation gone wrong within rounding. The face-by-face path runs many
                // differences of cut slivers, where the sphere layer is most exposed; two solid
                // angles per face are small next to them.
                if piece.solid_angle() > face_part.solid_angle() * (1.0 + 1e-9) + 1e-12 {
                    return Err(GeomError::Undecidable(DIFFERENCE_GREW));
                }
                out.push(piece);
            }
        }
        Ok((out, true))
    }

    /// How blocker `b` acts on front triangle `f` of light `light` (step 3 of
    /// [`ClipVisibility::visible_region`]): the sides of `f`'s plane its vertices lie on, by the
    /// facing predicate ([`face_side`]; vertices within its tolerance are on the plane).
    fn reach(&self, light: usize, b: Blocker, f: usize) -> Reach {
        let mesh = self.lights[light].as_ref().mesh();
        let (mut front, mut behind, mut on) = (false, false, false);
        for &v in self.blocker(b).0.mesh().vertices() {
            match face_side(mesh, f, v) {
                Side::Front => front = true,
                Side::Behind => behind = true,
                Side::On => on = true,
            }
        }
        match (front, behind, on) {
            (true, false, false) => Reach::Whole,
            (false, _, _) => Reach::Nothing,
            // Part of the blocker lies in the face's plane and hides nothing: subtracted whole,
            // it would hide the directions through that part from a point inside the blocker
            // or on its surface (seen from outside a closed blocker a ray enters it elsewhere
            // first, but that is not known here).
            (true, _, _) => Reach::Straddles,
        }
    }

    /// The visible region of light `light` minus the `whole` blockers in one planar pass
    /// ([`Method::Silhouette`]; see `visibility/union.rs`), or `None` when the light is too wide
    /// for one chart. A non-planar mesh light (closed here: open ones go face by face) is the
    /// union of its front faces in the same chart, other lights their
    /// [`ClipVisibility::light_region`] pieces.
    fn one_pass_region(
        &self,
        light: usize,
        frame: &ShadingFrame,
        whole: &[Blocker],
    ) -> Result<Option<Vec<SphericalPolygon>>, GeomError> {
        let body = self.light_body(light)?;
        let blockers: SmallVec<[BlockerGeometry<'_>; 8]> = whole
            .iter()
            .map(|&b| (self.blocker(b).0, &self.accels[self.slot(b)]))
            .collect();
        let bound = self.light_bounds[light];
        match body {
            Body::Mesh(m) if !m.is_planar() || !blockers.is_empty() => {
                one_pass(LightRegion::FrontFaces(m), bound, &blockers, frame)
            }
            _ if blockers.is_empty() => Ok(None),
            _ => {
                let pieces = self.light_region_unchecked(light, frame)?;
                one_pass(LightRegion::Pieces(&pieces), bound, &blockers, frame)
            }
        }
    }

    /// The region covered by light `light` seen from the frame's point, clipped to the upper
    /// hemisphere (seed 000 Alg. 1 lines 4-5), as pieces with disjoint interiors:
    ///
    /// - a convex light with [`Method::Silhouette`]: its silhouette, one piece;
    /// - a Bezier-bounded light ([`crate::solid::BezierShape`]): its flattening within the
    ///   shape's angular flatness as seen from the point ([`crate::solid::BezierShape::region`]),
    ///   one piece;
    /// - a convex light with [`Method::PerTriangle`], or a planar mesh light: each front-facing
    ///   triangle, one piece each (seed 000 section 4.4). Their projections cannot overlap, so
    ///   their integrals add up exactly;
    /// - a closed mesh light that bounds a solid ([`ClosedMesh`]) with [`Method::Silhouette`]:
    ///   its silhouette ([`nonconvex_silhouette`], thesis 003 section 4.3), one piece: the union
    ///   of its front faces' projections without computing a union. Where the silhouette gives
    ///   up (the point in the plane of a face that bounds it, or on the surface), the union
    ///   below is computed instead;
    /// - any other mesh light: the union of its front-facing triangles, one piece. The union, not
    ///   the sum, makes a non-convex light's self-occlusion right: where front faces overlap in
    ///   projection, the nearer one is seen, with the same radiance.
    ///
    /// # Errors
    ///
    /// As [`ClipVisibility::visible_region`]: [`GeomError::OutOfRange`] for a light index past
    /// the end, [`GeomError::Undecidable`] for a silhouette or a union of front triangles that
    /// cannot be decided within rounding.
    pub fn light_region(
        &self,
        light: usize,
        frame: &ShadingFrame,
    ) -> Result<Vec<SphericalPolygon>, GeomError> {
        if self.seen_from_inside(light, self.light_body(light)?, frame.origin()) {
            return Ok(Vec::new());
        }
        upper_pieces(self.light_region_unchecked(light, frame)?)
    }

    /// Whether `x` is inside closed light `light` (`body`). Seen from inside, every ray leaves
    /// the light through a back face before it can meet a front one, and its outer surface
    /// emits nothing inwards: the light has no region there, though a convex light's silhouette
    /// is then the whole sphere and a non-convex one's front faces need not be empty. A point
    /// on the surface of a convex light has no front face either and receives nothing from it.
    pub(super) fn seen_from_inside(&self, light: usize, body: &Body, x: DVec3) -> bool {
        match body {
            Body::Convex(p) => !p.has_front_face(x),
            _ => self.solids[light].as_ref().is_some_and(|s| s.encloses(x)),
        }
    }

    fn light_region_unchecked(
        &self,
        light: usize,
        frame: &ShadingFrame,
    ) -> Result<Vec<SphericalPolygon>, GeomError> {
        let body = self.light_body(light)?;
        let one = |s: SphericalPolygon| {
            if s.is_empty() {
                Vec::new()
            } else {
                alloc::vec![s]
            }
        };
        if let (Body::Convex(p), true) = (body, self.silhouettes()) {
            return Ok(one(upper_part(&convex_silhouette(p, frame)?)?));
        }
        if let Body::Bezier(b) = body {
            // A flattening within the shape's angular flatness seen from the point (seed 004
            // lights), with either method.
            return Ok(one(upper_part(&b.region(frame)?)?));
        }
        if let (Some(solid), true) = (&self.solids[light], self.silhouettes()) {
            match nonconvex_silhouette(solid, frame) {
                Ok(s) => return Ok(one(upper_part(&s)?)),
                Err(e) if e.is_undecidable() => {}
                Err(e) => return Err(e),
            }
        }
        let mesh = body.mesh();
        let mut pieces = Vec::new();
        for t in 0..mesh.triangle_count() {
            if let Some(p) = triangle_polygon(mesh, t, frame, TriangleRole::Emitter)? {
                let p = upper_part(&p)?;
                if !p.is_empty() {
                    pieces.push(p);
                }
            }
        }
        let disjoint = matches!(body, Body::Convex(_)) || mesh.is_planar();
        if disjoint || pieces.len() <= 1 {
            return Ok(pieces);
        }
        let mut union = pieces.pop().unwrap_or_default();
        for p in &pieces {
            union = union
                .boolean(p, BoolOp::Union)
                .map_err(|e| e.give_up(UNION_FAILED))?;
        }
        Ok(alloc::vec![union])
    }

    /// Appends to `out` the regions blocker `b` covers, clipped to the upper hemisphere (seed
    /// 000 Alg. 1 line 10): a convex blocker's silhouette with [`Method::Silhouette`]; otherwise
    /// each of its triangles seen from either side (seed 000 section 4.4), after a per-triangle
    /// bounding-sphere cull against light `light`.
    fn blocker_regions(
        &self,
        light: usize,
        b: Blocker,
        frame: &ShadingFrame,
        out: &mut Vec<SphericalPolygon>,
    ) -> Result<(), GeomError> {
        let (x, n) = (frame.origin(), frame.normal());
        let lb = self.light_bounds[light];
        match (self.blocker(b).0, self.silhouettes()) {
            (Body::Convex(p), true) => {
                let occ = upper_part(&convex_silhouette(p, frame)?)?;
                if !occ.is_empty() {
                    out.push(occ);
                }
            }
            (body, _) => {
                let mesh = body.mesh();
                let mut ts = Vec::new();
                shaft_triangles(mesh, self.bvh(b), &Shaft::to_sphere(x, n, lb), &mut ts);
                for t in ts {
                    let t = t as usize;
                    if !may_occlude(x, n, lb, triangle_bound(mesh.triangle(t))) {
                        continue;
                    }
                    if let Some(p) = triangle_polygon(mesh, t, frame, TriangleRole::Blocker)? {
                        let p = upper_part(&p)?;
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

impl<L: AsRef<Body>> Visibility for ClipVisibility<L> {
    fn light_count(&self) -> usize {
        self.lights.len()
    }

    fn visible_region(
        &self,
        light: usize,
        frame: &ShadingFrame,
    ) -> Result<Vec<SphericalPolygon>, GeomError> {
        self.region(light, frame, true)
    }

    fn unoccluded_region(
        &self,
        light: usize,
        frame: &ShadingFrame,
    ) -> Result<Vec<SphericalPolygon>, GeomError> {
        self.region(light, frame, false)
    }

    fn visible_pieces(
        &self,
        light: usize,
        frame: &ShadingFrame,
        blocked: bool,
        out: &mut super::Pieces,
    ) -> Result<bool, GeomError> {
        ClipVisibility::visible_pieces(self, light, frame, blocked, out)
    }
}

/// Subtracts from `piece` (part of light face `f` of `light_mesh`, within `face_bound`) the
/// triangles of `blocker` cut to their parts strictly on the shading point's side of `f`'s
/// plane (step 4 of [`ClipVisibility::visible_region`]). `external` is false when the blocker
/// is the light's own mesh (then `f` itself is skipped).
fn subtract_cut(
    mut piece: SphericalPolygon,
    blocker: &Body,
    bvh: Option<&Bvh>,
    external: bool,
    (light_mesh, f, face_bound): (&TriangleMesh, usize, BoundingSphere),
    frame: &ShadingFrame,
) -> Result<SphericalPolygon, GeomError> {
    let (x, up_world) = (frame.origin(), frame.normal());
    let bm = blocker.mesh();
    // Seen from outside a convex blocker, a ray enters through a front triangle before it can
    // meet a back one, so the back ones add nothing.
    let front_only = matches!(blocker, Body::Convex(_))
        && (0..bm.triangle_count()).any(|t| face_side(bm, t, x) == Side::Front);
    let mut ts = Vec::new();
    shaft_triangles(bm, bvh, &Shaft::to_sphere(x, up_world, face_bound), &mut ts);
    for t in ts {
        let t = t as usize;
        if (!external && t == f) || (front_only && face_side(bm, t, x) == Side::Behind) {
            continue;
        }
        // Only a triangle whose cone from x meets the face's can hide part of it.
        if !may_occlude(x, up_world, face_bound, triangle_bound(bm.triangle(t))) {
            continue;
        }
        // Cut by the same predicate that decided the blocker straddles the face.
        let dist = bm.triangle(t).map(|v| snapped_distance(light_mesh, f, v));
        if let Some(p) = clipped_triangle_polygon(bm, t, dist, frame)? {
            let p = upper_part(&p)?;
            if !p.is_empty() {
                piece = piece
                    .boolean(&p, BoolOp::Difference)
                    .map_err(|e| e.give_up(DIFFERENCE_FAILED))?;
                if piece.is_empty() {
                    break;
                }
            }
        }
    }
    Ok(piece)
}

/// The region a planar mesh light covers seen from its front, as the fast path takes it
/// ([`ClipVisibility::visible_pieces`]): its boundary loops ([`TriangleMesh::boundary_loops`]),
/// whose chain bounds exactly the union of its triangles, and whether they are one convex loop
/// (every turn to the left about the mesh's normal, or straight), which stays one simple loop
/// when the horizon cuts it.
#[derive(Debug, Clone, PartialEq)]
pub(super) struct Outline {
    /// The loops' vertex positions, each loop reversed: counter-clockwise about the normal, so
    /// clockwise seen from the front, which is counter-clockwise on the sphere of directions
    /// seen from outside (the region on the left of each edge).
    pub(super) rings: Vec<Vec<DVec3>>,
    pub(super) convex: bool,
}

impl Outline {
    /// The outline of planar mesh `m`; `None` for a mesh without boundary (which covers
    /// nothing seen from either side, and which the fast path leaves alone).
    fn of(m: &TriangleMesh) -> Option<Outline> {
        let loops = m.boundary_loops();
        if loops.is_empty() {
            return None;
        }
        let n = m.triangle_normal(0);
        let v = m.vertices();
        let convex = loops.len() == 1 && {
            let lp = &loops[0];
            let k = lp.len();
            let mut distinct = lp.clone();
            distinct.sort_unstable();
            distinct.dedup();
            distinct.len() == k
                && (0..k).all(|i| {
                    let (a, b, c) = (
                        v[lp[i] as usize],
                        v[lp[(i + 1) % k] as usize],
                        v[lp[(i + 2) % k] as usize],
                    );
                    (b - a).cross(c - b).dot(n) >= 0.0
                })
        };
        let rings = loops
            .iter()
            .map(|lp| lp.iter().rev().map(|&i| v[i as usize]).collect())
            .collect();
        Some(Outline { rings, convex })
    }
}

/// What a clip that added part of the horizon outside its polygon reports (see [`upper_part`]).
const CLIP_LEFT_POLYGON: &str =
    "the horizon clip of a region added a horizon arc outside the region within rounding";

/// Both ends of an edge within this of the horizon (in `z`) make it a horizon edge for
/// [`upper_part`].
const ON_HORIZON: f64 = 1e-12;

/// Horizon edges at least this long (radians) are checked by [`upper_part`]: what a clip that
/// joins an exit to an entry the long way round the circle adds is this long (its arcs are up to
/// `2 pi / 3`); the short ones of a region cut by the horizon near the point cost no check.
const LONG_ARC: f64 = 0.5;

/// How far above a horizon edge's midpoint (radians) [`upper_part`] looks for the region.
const ABOVE_ARC: f64 = 1e-7;

/// The part of `p` in the upper hemisphere (`clip_to_hemisphere(+z)`), checked where the clip
/// added a long arc of the horizon.
///
/// The clipped region lies above each of its horizon edges and inside `p`, so the direction
/// [`ABOVE_ARC`] above such an edge's midpoint is in `p` (unless `p` is thinner than that there).
/// A clip that joins the points where a sliver of `p` leaves and re-enters the hemisphere the
/// long way round the circle breaks this (a whole hemisphere for a sliver, or a ring that runs
/// over itself along the circle), and would be integrated as a large part of the sky: it is a
/// give-up, [`GeomError::Undecidable`]. One containment test per long horizon edge.
fn upper_part(p: &SphericalPolygon) -> Result<SphericalPolygon, GeomError> {
    let c = p.clip_to_axis_hemisphere(DVec3::Z);
    // Most parts do not touch the horizon at all (a light above it): one pass over the
    // vertices, without the edge pairs.
    let mut touches = false;
    for r in c.rings() {
        for v in r {
            touches |= v.z.abs() <= ON_HORIZON;
        }
    }
    if !touches || p.is_full() {
        return Ok(c);
    }
    for r in c.rings() {
        for k in 0..r.len() {
            let (a, b) = (r[k], r[(k + 1) % r.len()]);
            if a.z.abs() <= ON_HORIZON
                && b.z.abs() <= ON_HORIZON
                && a.angle_between(b) >= LONG_ARC
                && !p.contains((a + b).normalize() + DVec3::Z * ABOVE_ARC)
            {
                return Err(GeomError::Undecidable(CLIP_LEFT_POLYGON));
            }
        }
    }
    Ok(c)
}

/// What a region that left the upper hemisphere reports (see [`upper_pieces`]).
const REGION_LEFT_HEMISPHERE: &str =
    "a spherical set operation returned a region outside the upper hemisphere within rounding";

/// The pieces of a region, checked: every piece is clipped to the upper hemisphere before any
/// set operation, and differences and unions of such pieces stay in it, so a piece that is the
/// full sphere or contains the nadir `-z` is a set operation gone wrong within rounding (a
/// region complemented). That is a give-up, [`GeomError::Undecidable`], not a radiance
/// integrated over the wrong region.
fn upper_pieces(pieces: Vec<SphericalPolygon>) -> Result<Vec<SphericalPolygon>, GeomError> {
    if pieces
        .iter()
        .any(|p| p.is_full() || p.contains(DVec3::NEG_Z))
    {
        return Err(GeomError::Undecidable(REGION_LEFT_HEMISPHERE));
    }
    Ok(pieces)
}

/// A sphere holding a triangle (about its centroid, padded by a relative ulp margin), for the
/// per-triangle culling.
pub(super) fn triangle_bound(tri: [DVec3; 3]) -> BoundingSphere {
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
        piece = piece
            .boolean(r, BoolOp::Difference)
            .map_err(|e| e.give_up(DIFFERENCE_FAILED))?;
    }
    Ok(piece)
}
