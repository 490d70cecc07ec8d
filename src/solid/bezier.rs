//! Planar shapes bounded by cubic Bezier curves and line segments (seed 004's free-form lights):
//! validation, flattening within a tolerance chosen per shading point, the spherical polygon
//! seen from a point, and uniform sampling of the exact curved region.
//!
//! The shape knows no light and no integral: the `ltc` layer integrates curves given as plain
//! control points, and the `shade` layer hands it [`BezierShape::local_segments`].

use alloc::vec::Vec;

use glam::{DVec2, DVec3};
use smallvec::SmallVec;

use super::frame::ShadingFrame;
use super::mesh::{BoundingSphere, MAX_MESH_COORD, TriangleMesh};
use crate::GeomError;
use crate::sphere::SphericalPolygon;

/// One segment of a boundary loop of a [`BezierShape`], by its control points: a straight
/// segment, or the cubic Bezier curve
/// `B(t) = (1-t)^3 p0 + 3 (1-t)^2 t p1 + 3 (1-t) t^2 p2 + t^3 p3`, `t` in `[0, 1]`.
///
/// More segment kinds (quadratic or rational curves) may be added, hence `#[non_exhaustive]`.
#[derive(Debug, Clone, Copy, PartialEq)]
#[non_exhaustive]
pub enum BezierSegment {
    /// The straight segment from the first point to the second.
    Line([DVec3; 2]),
    /// The cubic Bezier curve with these four control points.
    Cubic([DVec3; 4]),
}

impl BezierSegment {
    /// The first point.
    #[must_use]
    pub fn start(&self) -> DVec3 {
        self.control_points()[0]
    }

    /// The last point.
    #[must_use]
    pub fn end(&self) -> DVec3 {
        *self.control_points().last().unwrap_or(&DVec3::ZERO)
    }

    /// The control points (two for a line).
    #[must_use]
    pub fn control_points(&self) -> &[DVec3] {
        match self {
            BezierSegment::Line(p) => p,
            BezierSegment::Cubic(p) => p,
        }
    }

    /// The point at parameter `t` in `[0, 1]` (exactly the end points at 0 and 1).
    #[must_use]
    pub fn point(&self, t: f64) -> DVec3 {
        match *self {
            BezierSegment::Line([a, b]) => a.lerp(b, t),
            BezierSegment::Cubic(p) => cubic(p, t),
        }
    }

    /// The segment with every control point mapped by `f` (an affine map of the plane keeps
    /// the curve's shape: affine invariance of Bezier curves).
    #[must_use]
    pub fn map(&self, f: impl Fn(DVec3) -> DVec3) -> Self {
        match *self {
            BezierSegment::Line(p) => BezierSegment::Line(p.map(f)),
            BezierSegment::Cubic(p) => BezierSegment::Cubic(p.map(f)),
        }
    }

    /// The same segment run backwards.
    #[must_use]
    pub fn reversed(&self) -> Self {
        match *self {
            BezierSegment::Line([a, b]) => BezierSegment::Line([b, a]),
            BezierSegment::Cubic([a, b, c, d]) => BezierSegment::Cubic([d, c, b, a]),
        }
    }

    fn with_start(mut self, s: DVec3) -> Self {
        match &mut self {
            BezierSegment::Line(p) => p[0] = s,
            BezierSegment::Cubic(p) => p[0] = s,
        }
        self
    }

    /// Chords for a uniform flattening within `flatness`: on a parameter step `h` the chord
    /// stays within `h^2 / 8 max |B''|` of the curve, and `|B''| <= 6 max(|p0 - 2 p1 + p2|,
    /// |p1 - 2 p2 + p3|)` (it is linear in `t` between those two values), so
    /// `n >= sqrt(3 M / (4 flatness))` chords suffice. At least 3 for a cubic (a loop of a
    /// single cubic is a triangle at worst), one for a line.
    fn chords(&self, flatness: f64) -> usize {
        match *self {
            BezierSegment::Line(_) => 1,
            BezierSegment::Cubic(p) => {
                let m = (p[0] - 2.0 * p[1] + p[2])
                    .length()
                    .max((p[1] - 2.0 * p[2] + p[3]).length());
                let n = crate::math::sqrt(0.75 * m / flatness);
                // Bounded: callers pass flatness >= FINEST_FLATNESS of the extent, and M is at
                // most 4 extents.
                (n.min(1e6) as usize + 1).max(3)
            }
        }
    }
}

/// A cubic Bezier curve at `t` (Bernstein form; exact at the ends).
#[inline]
fn cubic(p: [DVec3; 4], t: f64) -> DVec3 {
    if t == 0.0 {
        return p[0];
    }
    if t == 1.0 {
        return p[3];
    }
    let s = 1.0 - t;
    let (s2, t2) = (s * s, t * t);
    p[0] * (s2 * s) + p[1] * (3.0 * s2 * t) + p[2] * (3.0 * s * t2) + p[3] * (t2 * t)
}

/// `B'(t)` of a cubic.
fn cubic_derivative(p: [DVec3; 4], t: f64) -> DVec3 {
    let s = 1.0 - t;
    3.0 * ((p[1] - p[0]) * (s * s) + (p[2] - p[1]) * (2.0 * s * t) + (p[3] - p[2]) * (t * t))
}

/// Relative tolerance (of the shape's extent, the largest coordinate difference from its first
/// point) for segment ends to count as joined (they are then made bit-identical) and for
/// control points to count as coplanar.
pub const BEZIER_TOLERANCE: f64 = 1e-9;

/// The finest flattening a shape keeps, relative to its extent: the chords stay this close to
/// the curves. Validation (loops simple and disjoint) is done on it.
pub const FINEST_FLATNESS: f64 = 1e-6;

/// The default angular flatness of [`BezierShape::region`]: the flattening used for a shading
/// point stays within this many radians of the curves as seen from the point (see
/// [`BezierShape::with_flatten_angle`]).
///
/// The Lambert integral moves by at most `(2/3) angle P / pi` for an angular perimeter `P`
/// (tested; about 1e-3 of the value for a letter a light's size away). The vertex count grows
/// like `angle^(-1/2)`, and subtracting an occluder from the region costs about its square (the
/// sphere layer's set operations validate planar operands quadratically): on a letter "D" 2.5
/// away with one box in the way, `1e-4` took 2.7 ms per point (280 vertices), `3e-4` 0.56 ms
/// and `1e-3` 0.17 ms (loaded machine), with the values within 9e-4 (relative) of `1e-4`'s.
pub const DEFAULT_FLATTEN_ANGLE: f64 = 1e-3;

/// The flatness, relative to the extent, of the flattening behind [`BezierShape::mesh`] (what
/// blocks other lights, and what separating planes and culling see).
const MESH_FLATNESS: f64 = 1e-3;

/// Coarsest flattening kept, relative to the extent (levels go from here to
/// [`FINEST_FLATNESS`], each four times finer, about twice the chords).
const COARSEST_FLATNESS: f64 = 1e-2;

/// One flattening of the loops: every segment replaced by uniform chords.
#[derive(Debug, Clone, PartialEq)]
struct Level {
    /// Largest distance from a chord to its curve.
    flatness: f64,
    /// The chords' end points, loop by loop (no repeated closing point).
    rings: Vec<Vec<DVec3>>,
}

/// A planar shape bounded by closed loops of cubic Bezier curves and line segments (a
/// free-form light of seed 004: letters, logos, rounded panels), validated.
///
/// The emitting side, as for the triangles of a mesh light, is the one about which the outer
/// loops run counter-clockwise (right-hand rule around [`BezierShape::normal`]); holes run
/// clockwise. Seen from the back or from within its plane, a shape shows nothing.
///
/// # Examples
///
/// ```
/// use arealight::glam::DVec3;
/// use arealight::solid::{BezierSegment, BezierShape};
/// // A rounded square at height 2 facing down (-z): counter-clockwise seen from below.
/// let p = |x: f64, y: f64| DVec3::new(x, y, 2.0);
/// let k = 0.55;
/// let corners = [p(1.0, 0.0), p(0.0, -1.0), p(-1.0, 0.0), p(0.0, 1.0)];
/// let segs: Vec<_> = (0..4)
///     .map(|i| {
///         let (a, b) = (corners[i], corners[(i + 1) % 4]);
///         let c = DVec3::new(0.0, 0.0, 2.0);
///         // Bulge outwards: handles pushed away from the centre.
///         BezierSegment::Cubic([a, a + (b - c) * k, b + (a - c) * k, b])
///     })
///     .collect();
/// let shape = BezierShape::new(vec![segs])?;
/// assert!((shape.normal() - DVec3::NEG_Z).length() < 1e-12);
/// assert!(shape.area() > 2.0 && shape.area() < std::f64::consts::PI * 1.2);
/// # Ok::<(), arealight::GeomError>(())
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct BezierShape {
    loops: Vec<Vec<BezierSegment>>,
    /// A point of the plane (the first control point) and an orthonormal basis of the plane
    /// with `e1 x e2 = normal`.
    origin: DVec3,
    e1: DVec3,
    e2: DVec3,
    normal: DVec3,
    area: f64,
    extent: f64,
    bound: BoundingSphere,
    /// Per segment (loop by loop), a sphere holding its control points.
    segment_bounds: Vec<BoundingSphere>,
    /// Bounding box of the control points in plane coordinates.
    box_min: DVec2,
    box_max: DVec2,
    /// Validated flattenings, coarsest first.
    levels: Vec<Level>,
    mesh: TriangleMesh,
    flatten_angle: f64,
}

impl BezierShape {
    /// Validates the loops and builds the shape.
    ///
    /// Each loop is a sequence of segments, each starting where the previous one ends (within
    /// [`BEZIER_TOLERANCE`] of the extent; the ends are then made identical), the last ending
    /// where the first starts.
    ///
    /// # Errors
    ///
    /// [`GeomError::InvalidCurve`], naming the loop (`ring`) and the segment, for: no loop or an
    /// empty loop; a non-finite control point, or one beyond [`MAX_MESH_COORD`]; a segment that
    /// does not start where the previous one ends (or a loop that does not close); a segment of
    /// zero length; control points off the plane of the shape (more than
    /// [`BEZIER_TOLERANCE`] of the extent); a loop that encloses no area; a loop that crosses
    /// or touches itself or another loop (decided on a flattening within [`FINEST_FLATNESS`] of
    /// the extent, with exact orientation predicates); an outer loop (inside an even number of
    /// others) that runs clockwise or a hole that runs counter-clockwise about the normal the
    /// loops' total area gives.
    pub fn new(loops: Vec<Vec<BezierSegment>>) -> Result<Self, GeomError> {
        let bad = |ring: usize, segment: usize, why: &'static str| GeomError::InvalidCurve {
            ring,
            segment,
            why,
        };
        if loops.is_empty() {
            return Err(bad(0, 0, "a shape needs at least one loop"));
        }
        let first = loops[0].first().map(BezierSegment::start);
        let first = first.ok_or(bad(0, 0, "empty loop"))?;
        let mut extent = 0.0f64;
        for (r, l) in loops.iter().enumerate() {
            if l.is_empty() {
                return Err(bad(r, 0, "empty loop"));
            }
            for (s, seg) in l.iter().enumerate() {
                for &p in seg.control_points() {
                    if !p.is_finite() {
                        return Err(bad(r, s, "non-finite control point"));
                    }
                    if p.abs().max_element() > MAX_MESH_COORD {
                        return Err(bad(r, s, "control point beyond the coordinate range"));
                    }
                    extent = extent.max((p - first).abs().max_element());
                }
            }
        }
        if !(extent > 0.0) {
            return Err(bad(0, 0, "the loop encloses no area"));
        }
        // Joins: snapped to the previous segment's end.
        let join = BEZIER_TOLERANCE * extent;
        let mut snapped: Vec<Vec<BezierSegment>> = Vec::with_capacity(loops.len());
        for (r, l) in loops.iter().enumerate() {
            let n = l.len();
            let mut out: Vec<BezierSegment> = Vec::with_capacity(n);
            for (s, seg) in l.iter().enumerate() {
                let seg = match out.last() {
                    Some(prev) => {
                        if (seg.start() - prev.end()).abs().max_element() > join {
                            return Err(bad(
                                r,
                                s,
                                "does not start where the previous segment ends",
                            ));
                        }
                        seg.with_start(prev.end())
                    }
                    None => *seg,
                };
                out.push(seg);
            }
            let (start, end) = (out[0].start(), out[n - 1].end());
            if (start - end).abs().max_element() > join {
                return Err(bad(
                    r,
                    n - 1,
                    "the loop does not close (its last segment ends away from its start)",
                ));
            }
            // The closing point is the first one, exactly.
            let last = out[n - 1];
            out[n - 1] = match last {
                BezierSegment::Line([a, _]) => BezierSegment::Line([a, start]),
                BezierSegment::Cubic([a, b, c, _]) => BezierSegment::Cubic([a, b, c, start]),
            };
            for (s, seg) in out.iter().enumerate() {
                let pts = seg.control_points();
                if pts
                    .iter()
                    .all(|&p| (p - pts[0]).abs().max_element() <= join)
                {
                    return Err(bad(r, s, "zero-length segment"));
                }
            }
            snapped.push(out);
        }
        let loops = snapped;
        // The plane: the normal of the total vector area, which also fixes the emitting side.
        let areas: Vec<DVec3> = loops
            .iter()
            .map(|l| l.iter().map(|s| vector_area(s, first)).sum())
            .collect();
        let total: DVec3 = areas.iter().copied().sum();
        let len = total.length();
        if !(len > 1e-12 * extent * extent) {
            return Err(bad(0, 0, "the loops enclose no area"));
        }
        let normal = total / len;
        // The control point farthest from the plane is named: one point off the plane tilts
        // the area's normal a little, which moves the others off it by less.
        let plane_tol = BEZIER_TOLERANCE * extent;
        let mut worst = (0.0f64, 0, 0);
        for (r, l) in loops.iter().enumerate() {
            for (s, seg) in l.iter().enumerate() {
                for &p in seg.control_points() {
                    let h = (p - first).dot(normal).abs();
                    if h > worst.0 {
                        worst = (h, r, s);
                    }
                }
            }
        }
        if !(worst.0 <= plane_tol) {
            return Err(bad(
                worst.1,
                worst.2,
                "control point off the plane of the shape",
            ));
        }
        for (r, a) in areas.iter().enumerate() {
            if !(a.dot(normal).abs() > 1e-12 * extent * extent) {
                return Err(bad(r, 0, "the loop encloses no area"));
            }
        }
        let e1 = normal.any_orthonormal_vector();
        let e2 = normal.cross(e1);
        let to2 = |p: DVec3| DVec2::new((p - first).dot(e1), (p - first).dot(e2));
        // Flattenings, finest first: the finest must be simple; coarser ones are kept only if
        // they are too (a thin feature can make a coarse flattening cross itself).
        let mut levels: Vec<Level> = Vec::new();
        let mut flatness = FINEST_FLATNESS * extent;
        loop {
            let level = flatten(&loops, flatness);
            let rings2: Vec<Vec<DVec2>> = level
                .rings
                .iter()
                .map(|r| r.iter().map(|&p| to2(p)).collect())
                .collect();
            match check_simple(&rings2) {
                Ok(()) => {
                    if levels.is_empty() {
                        check_orientation(&rings2, &areas, normal)?;
                    }
                    levels.push(level);
                }
                Err((ring, chord)) if levels.is_empty() => {
                    let segment = segment_of_chord(&loops[ring], flatness, chord);
                    return Err(bad(
                        ring,
                        segment,
                        "crosses or touches its own loop or another loop",
                    ));
                }
                Err(_) => {}
            }
            flatness *= 4.0;
            if flatness > COARSEST_FLATNESS * extent {
                break;
            }
        }
        levels.reverse();
        // The mesh: the coarsest kept level within MESH_FLATNESS, triangulated.
        let mesh_level = levels
            .iter()
            .find(|l| l.flatness <= MESH_FLATNESS * extent * (1.0 + 1e-9))
            .or(levels.last())
            .ok_or(bad(0, 0, "crosses or touches its own loop or another loop"))?;
        let mesh = triangulate(&mesh_level.rings, to2)?;
        // Bounds of the control points (the curves lie in their convex hull).
        let all: Vec<DVec3> = loops
            .iter()
            .flatten()
            .flat_map(|s| s.control_points().iter().copied())
            .collect();
        let bound = sphere_of(&all);
        let segment_bounds = loops
            .iter()
            .flatten()
            .map(|s| sphere_of(s.control_points()))
            .collect();
        let (mut box_min, mut box_max) =
            (DVec2::splat(f64::INFINITY), DVec2::splat(-f64::INFINITY));
        for &p in &all {
            box_min = box_min.min(to2(p));
            box_max = box_max.max(to2(p));
        }
        Ok(BezierShape {
            loops,
            origin: first,
            e1,
            e2,
            normal,
            area: len,
            extent,
            bound,
            segment_bounds,
            box_min,
            box_max,
            levels,
            mesh,
            flatten_angle: DEFAULT_FLATTEN_ANGLE,
        })
    }

    /// The same shape with another angular flatness for [`BezierShape::region`] (radians, in
    /// `[1e-9, 0.1]`; default [`DEFAULT_FLATTEN_ANGLE`]).
    ///
    /// # Errors
    ///
    /// [`GeomError::OutOfRange`] for an angle outside that range.
    pub fn with_flatten_angle(mut self, angle: f64) -> Result<Self, GeomError> {
        if !(1e-9..=0.1).contains(&angle) {
            return Err(GeomError::OutOfRange {
                what: "flatten angle (radians, 1e-9 ..= 0.1)",
                value: angle,
                limit: 0.1,
            });
        }
        self.flatten_angle = angle;
        Ok(self)
    }

    /// The angular flatness of [`BezierShape::region`].
    #[must_use]
    pub fn flatten_angle(&self) -> f64 {
        self.flatten_angle
    }

    /// The same region emitting from its other side: every loop run backwards, the normal
    /// negated, the flattenings and the mesh turned around ([`TriangleMesh::flipped`]), nothing
    /// recomputed, so the region seen from behind is exactly the original's turned around
    /// (what a two-sided light shows from behind its plane).
    ///
    /// # Examples
    ///
    /// ```
    /// use arealight::glam::DVec3;
    /// use arealight::solid::{BezierSegment, BezierShape};
    /// let p = |x: f64, y: f64| DVec3::new(x, y, 2.0);
    /// let tri = vec![
    ///     BezierSegment::Line([p(0.0, 0.0), p(1.0, 0.0)]),
    ///     BezierSegment::Cubic([p(1.0, 0.0), p(1.0, 0.5), p(0.5, 1.0), p(0.0, 1.0)]),
    ///     BezierSegment::Line([p(0.0, 1.0), p(0.0, 0.0)]),
    /// ];
    /// let up = BezierShape::new(vec![tri])?;
    /// let down = up.flipped();
    /// assert_eq!(down.normal(), -up.normal());
    /// assert_eq!(down.area(), up.area());
    /// assert!(down.faces(DVec3::new(0.3, 0.3, 1.0)) && !up.faces(DVec3::new(0.3, 0.3, 1.0)));
    /// # Ok::<(), arealight::GeomError>(())
    /// ```
    #[must_use]
    pub fn flipped(&self) -> BezierShape {
        let loops = self
            .loops
            .iter()
            .map(|l| l.iter().rev().map(BezierSegment::reversed).collect())
            .collect();
        let mut segment_bounds = Vec::with_capacity(self.segment_bounds.len());
        let mut at = 0;
        for l in &self.loops {
            segment_bounds.extend(self.segment_bounds[at..at + l.len()].iter().rev());
            at += l.len();
        }
        let levels = self
            .levels
            .iter()
            .map(|l| Level {
                flatness: l.flatness,
                rings: l
                    .rings
                    .iter()
                    .map(|r| r.iter().rev().copied().collect())
                    .collect(),
            })
            .collect();
        // e2 x e1 = -normal: the plane coordinates swap, and with them the box's.
        BezierShape {
            loops,
            origin: self.origin,
            e1: self.e2,
            e2: self.e1,
            normal: -self.normal,
            area: self.area,
            extent: self.extent,
            bound: self.bound,
            segment_bounds,
            box_min: DVec2::new(self.box_min.y, self.box_min.x),
            box_max: DVec2::new(self.box_max.y, self.box_max.x),
            levels,
            mesh: self.mesh.flipped(),
            flatten_angle: self.flatten_angle,
        }
    }

    /// The validated loops (segment ends made identical).
    #[must_use]
    pub fn loops(&self) -> &[Vec<BezierSegment>] {
        &self.loops
    }

    /// The unit normal of the emitting side: the outer loops run counter-clockwise about it.
    #[must_use]
    pub fn normal(&self) -> DVec3 {
        self.normal
    }

    /// The area enclosed (outer loops less holes), exact for the curves.
    #[must_use]
    pub fn area(&self) -> f64 {
        self.area
    }

    /// A point of the shape's plane (its first control point).
    #[must_use]
    pub fn plane_point(&self) -> DVec3 {
        self.origin
    }

    /// The triangulation of a flattening within `1e-3` of the extent: what the shape looks like
    /// to everything that needs triangles (blocking other lights, separating planes).
    #[must_use]
    pub fn mesh(&self) -> &TriangleMesh {
        &self.mesh
    }

    /// A sphere holding every control point, so the whole shape.
    #[must_use]
    pub fn bounding_sphere(&self) -> BoundingSphere {
        self.bound
    }

    /// The signed distance of `p` from the plane, positive on the emitting side.
    #[must_use]
    pub fn plane_distance(&self, p: DVec3) -> f64 {
        (p - self.origin).dot(self.normal)
    }

    /// Whether the shading point `x` sees the emitting side: on that side of the plane by more
    /// than [`BEZIER_TOLERANCE`] of the extent (closer, it sees the shape edge-on).
    #[must_use]
    pub fn faces(&self, x: DVec3) -> bool {
        self.plane_distance(x) > BEZIER_TOLERANCE * self.extent
    }

    /// Whether the shading point `x` is behind the emitting side, by more than
    /// [`BEZIER_TOLERANCE`] of the extent: what a two-sided light shows there is the back.
    #[must_use]
    pub fn faces_back(&self, x: DVec3) -> bool {
        self.plane_distance(x) < -BEZIER_TOLERANCE * self.extent
    }

    /// The flattening used for a point at distance at least `distance` from the shape: the
    /// coarsest kept level within `flatten_angle * distance` of the curves (the finest when
    /// none is).
    fn level_for(&self, distance: f64) -> &Level {
        let want = self.flatten_angle * distance;
        self.levels
            .iter()
            .find(|l| l.flatness <= want)
            .or(self.levels.last())
            .unwrap_or(&self.levels[0])
    }

    /// A lower bound of the distance from `x` to the shape: to its plane, and to its bounding
    /// sphere.
    fn distance_bound(&self, x: DVec3) -> f64 {
        let b = self.bound;
        self.plane_distance(x)
            .abs()
            .max((x - b.center).length() - b.radius)
    }

    /// The region the shape covers seen from the frame's point, in the shading frame, as a
    /// spherical polygon (not clipped to the horizon): a flattening of the loops within
    /// [`BezierShape::flatten_angle`] radians of the curves as seen from the point (one of the
    /// shape's validated flattenings, chosen by the point's distance; points closer than
    /// [`FINEST_FLATNESS`] of the extent over the angle get the finest, and a coarser angle).
    /// Empty when the point does not see the emitting side ([`BezierShape::faces`]).
    ///
    /// The flattening is a simple planar polygon (validated when the shape was built), so its
    /// central projection from a point off the plane is a valid spherical polygon; it is built
    /// without the quadratic checks of [`SphericalPolygon::new`].
    ///
    /// # Errors
    ///
    /// [`GeomError::Undecidable`] when two consecutive vertices are too close in direction to
    /// be told apart (a shape some `1e15` times its size away).
    pub fn region(&self, frame: &ShadingFrame) -> Result<SphericalPolygon, GeomError> {
        let x = frame.origin();
        if !self.faces(x) {
            return Ok(SphericalPolygon::empty());
        }
        let level = self.level_for(self.distance_bound(x));
        let mut verts: SmallVec<[DVec3; 12]> = SmallVec::new();
        let mut ends: SmallVec<[u32; 2]> = SmallVec::new();
        for ring in &level.rings {
            // Counter-clockwise about the normal seen from its side is clockwise seen from
            // outside the sphere: the ring is reversed.
            let start = verts.len();
            for &p in ring.iter().rev() {
                let d = frame.to_local(p);
                let u = d / d.length();
                if !u.is_finite() {
                    return Err(GeomError::Undecidable(TOO_FAR));
                }
                verts.push(u);
            }
            let n = verts.len() - start;
            for i in 0..n {
                let (a, b) = (verts[start + i], verts[start + (i + 1) % n]);
                if (a - b).length() <= crate::sphere::COINCIDENT_TOLERANCE {
                    return Err(GeomError::Undecidable(TOO_FAR));
                }
            }
            ends.push(verts.len() as u32);
        }
        Ok(SphericalPolygon::from_parts(verts, ends))
    }

    /// The loops' segments in the frame's local coordinates (relative to the shading point),
    /// loops one after another, oriented counter-clockwise seen from outside the sphere (the
    /// convention of the `ltc` layer's curved integrals); `None` when the point does not see
    /// the emitting side. Shared end points stay bit-identical.
    #[must_use]
    pub fn local_segments(&self, frame: &ShadingFrame) -> Option<Vec<BezierSegment>> {
        if !self.faces(frame.origin()) {
            return None;
        }
        let mut out = Vec::with_capacity(self.loops.iter().map(Vec::len).sum());
        for l in &self.loops {
            for s in l.iter().rev() {
                out.push(s.reversed().map(|p| frame.to_local(p)));
            }
        }
        Some(out)
    }

    /// What [`BezierShape::local_segments`] gives for the turned-around shape
    /// ([`BezierShape::flipped`], without building it): the segments in the frame's local
    /// coordinates, oriented counter-clockwise seen from outside the sphere from behind the
    /// plane; `None` unless the point is behind it ([`BezierShape::faces_back`]). For the back
    /// of a two-sided light.
    #[must_use]
    pub fn local_segments_behind(&self, frame: &ShadingFrame) -> Option<Vec<BezierSegment>> {
        if !self.faces_back(frame.origin()) {
            return None;
        }
        // The turned-around shape runs each loop backwards, and local_segments runs it
        // backwards again: the loops as stored.
        Some(
            self.loops
                .iter()
                .flatten()
                .map(|s| s.map(|p| frame.to_local(p)))
                .collect(),
        )
    }

    /// Plane coordinates of `p` (relative to the first control point).
    fn to2(&self, p: DVec3) -> DVec2 {
        let d = p - self.origin;
        DVec2::new(d.dot(self.e1), d.dot(self.e2))
    }

    /// Whether the point `p` of the plane (projected onto it) lies inside the curved region,
    /// by the winding number of the exact curves (non-zero: outer loops count `+1`, holes
    /// `-1`). Points within rounding of a curve may go either way.
    #[must_use]
    pub fn contains(&self, p: DVec3) -> bool {
        let q = self.to2(p);
        if q.x < self.box_min.x
            || q.y < self.box_min.y
            || q.x > self.box_max.x
            || q.y > self.box_max.y
        {
            return false;
        }
        let mut w = 0i32;
        for s in self.loops.iter().flatten() {
            w += crossings_right(s.control_points(), |p| self.to2(p), q);
        }
        w != 0
    }

    /// A point uniformly distributed over the curved region (by area), by rejection from the
    /// control points' bounding box with [`BezierShape::contains`]; `uniform` supplies numbers
    /// in `[0, 1)`. `None` after 10 000 rejections in a row (a region filling less than about
    /// `1e-3` of its box, sampled unluckily).
    pub fn sample(&self, mut uniform: impl FnMut() -> f64) -> Option<DVec3> {
        let size = self.box_max - self.box_min;
        for _ in 0..10_000 {
            let q = self.box_min + size * DVec2::new(uniform(), uniform());
            let p = self.origin + self.e1 * q.x + self.e2 * q.y;
            if self.contains(p) {
                return Some(p);
            }
        }
        None
    }

    /// Number of vertices of the flattening [`BezierShape::region`] uses for a point at
    /// distance `distance` (for benchmarks and reports).
    #[must_use]
    pub fn region_vertex_count(&self, distance: f64) -> usize {
        self.level_for(distance).rings.iter().map(Vec::len).sum()
    }

    /// Bounding spheres of the segments, loop by loop (for culling by callers).
    #[must_use]
    pub fn segment_bounds(&self) -> &[BoundingSphere] {
        &self.segment_bounds
    }
}

/// What [`BezierShape::region`] reports for directions it cannot separate.
const TOO_FAR: &str = "a curved light is too far away for its flattening's directions to differ";

/// `(1/2) integral of (p - o) x dp` over a segment: exact (three Gauss-Legendre points for a
/// cubic, whose integrand has degree 5).
fn vector_area(s: &BezierSegment, o: DVec3) -> DVec3 {
    match *s {
        BezierSegment::Line([a, b]) => 0.5 * (a - o).cross(b - o),
        BezierSegment::Cubic(p) => {
            const X: f64 = 0.387_298_334_620_741_7; // sqrt(3/5) / 2
            let nodes = [
                (0.5 - X, 5.0 / 18.0),
                (0.5, 8.0 / 18.0),
                (0.5 + X, 5.0 / 18.0),
            ];
            let mut sum = DVec3::ZERO;
            for (t, w) in nodes {
                sum += w * (cubic(p, t) - o).cross(cubic_derivative(p, t));
            }
            0.5 * sum
        }
    }
}

/// The loops flattened within `flatness`.
fn flatten(loops: &[Vec<BezierSegment>], flatness: f64) -> Level {
    let rings = loops
        .iter()
        .map(|l| {
            let mut ring = Vec::new();
            for s in l {
                let n = s.chords(flatness);
                for k in 0..n {
                    ring.push(s.point(k as f64 / n as f64));
                }
            }
            ring
        })
        .collect();
    Level { flatness, rings }
}

/// The segment of a loop that chord `chord` of its flattening within `flatness` belongs to.
fn segment_of_chord(l: &[BezierSegment], flatness: f64, chord: usize) -> usize {
    let mut k = 0;
    for (i, s) in l.iter().enumerate() {
        k += s.chords(flatness);
        if chord < k {
            return i;
        }
    }
    l.len() - 1
}

fn sphere_of(pts: &[DVec3]) -> BoundingSphere {
    let (mut lo, mut hi) = (DVec3::splat(f64::INFINITY), DVec3::splat(-f64::INFINITY));
    for &p in pts {
        lo = lo.min(p);
        hi = hi.max(p);
    }
    let center = 0.5 * (lo + hi);
    let r = pts
        .iter()
        .map(|&p| (p - center).length())
        .fold(0.0, f64::max);
    BoundingSphere {
        center,
        radius: r * (1.0 + 1e-12),
    }
}

/// The sign of the exact orientation of `c` against the line `a -> b`.
fn orient(a: DVec2, b: DVec2, c: DVec2) -> i8 {
    let v = robust::orient2d(
        robust::Coord { x: a.x, y: a.y },
        robust::Coord { x: b.x, y: b.y },
        robust::Coord { x: c.x, y: c.y },
    );
    if v > 0.0 {
        1
    } else if v < 0.0 {
        -1
    } else {
        0
    }
}

/// Whether `p`, collinear with `a -> b`, lies within the closed segment.
fn within(a: DVec2, b: DVec2, p: DVec2) -> bool {
    p.x >= a.x.min(b.x) && p.x <= a.x.max(b.x) && p.y >= a.y.min(b.y) && p.y <= a.y.max(b.y)
}

/// Whether the closed segments `ab` and `cd` share a point (exact).
fn touch(a: DVec2, b: DVec2, c: DVec2, d: DVec2) -> bool {
    let (o1, o2, o3, o4) = (
        orient(a, b, c),
        orient(a, b, d),
        orient(c, d, a),
        orient(c, d, b),
    );
    if o1 * o2 < 0 && o3 * o4 < 0 {
        return true;
    }
    (o1 == 0 && within(a, b, c))
        || (o2 == 0 && within(a, b, d))
        || (o3 == 0 && within(c, d, a))
        || (o4 == 0 && within(c, d, b))
}

/// Checks that the rings (closed, no repeated closing point) are simple and pairwise disjoint:
/// chords meet only where consecutive ones share their end point, and there without folding
/// back. Exact predicates, a sweep over the chords sorted by their smallest `x`. On failure the
/// ring and the index of a chord involved.
fn check_simple(rings: &[Vec<DVec2>]) -> Result<(), (usize, usize)> {
    // (min x, max x, ring, index)
    let mut chords: Vec<(f64, f64, usize, usize)> = Vec::new();
    for (r, ring) in rings.iter().enumerate() {
        let n = ring.len();
        if n < 3 {
            return Err((r, 0));
        }
        for i in 0..n {
            let (a, b) = (ring[i], ring[(i + 1) % n]);
            if a == b {
                return Err((r, i));
            }
            chords.push((a.x.min(b.x), a.x.max(b.x), r, i));
        }
    }
    chords.sort_unstable_by(|a, b| a.0.total_cmp(&b.0));
    let ends = |r: usize, i: usize| {
        let ring = &rings[r];
        (ring[i], ring[(i + 1) % ring.len()])
    };
    let mut active: Vec<(f64, usize, usize)> = Vec::new(); // (max x, ring, index)
    for &(lo, hi, r, i) in &chords {
        active.retain(|&(amax, _, _)| amax >= lo);
        let (a, b) = ends(r, i);
        for &(_, s, j) in &active {
            let (c, d) = ends(s, j);
            let n = rings[r].len();
            let next = r == s && j == (i + 1) % n; // i ends where j starts
            let prev = r == s && i == (j + 1) % n; // j ends where i starts
            if next || prev {
                // Shared end point x; the far ends p (of i) and q (of j) must not lie on the
                // same ray from x (a fold), and nothing else may meet.
                let (x, p, q) = if next { (b, a, d) } else { (a, b, c) };
                if orient(x, p, q) == 0 && (p - x).dot(q - x) > 0.0 {
                    return Err((r, i));
                }
                // A loop of three chords shares both ends pairwise; other contacts are caught
                // by the far end lying on the other chord.
                if n > 3
                    && ((orient(c, d, p) == 0 && within(c, d, p) && p != x)
                        || (orient(a, b, q) == 0 && within(a, b, q) && q != x))
                {
                    return Err((r, i));
                }
                continue;
            }
            if touch(a, b, c, d) {
                return Err((r, i));
            }
        }
        active.push((hi, r, i));
    }
    Ok(())
}

/// Checks the orientation of each loop against its nesting depth in the (simple, disjoint)
/// flattening: counter-clockwise about `normal` (positive area) at even depth, clockwise at
/// odd depth.
fn check_orientation(
    rings: &[Vec<DVec2>],
    areas: &[DVec3],
    normal: DVec3,
) -> Result<(), GeomError> {
    for (i, r) in rings.iter().enumerate() {
        let p = r[0];
        let depth = rings
            .iter()
            .enumerate()
            .filter(|&(j, s)| j != i && winding(s, p) != 0)
            .count();
        let ccw = areas[i].dot(normal) > 0.0;
        if ccw != depth.is_multiple_of(2) {
            return Err(GeomError::InvalidCurve {
                ring: i,
                segment: 0,
                why: if ccw {
                    "a hole (inside an odd number of loops) must run clockwise about the normal"
                } else {
                    "an outer loop (inside an even number of loops) must run counter-clockwise \
                     about the normal"
                },
            });
        }
    }
    Ok(())
}

/// Exact winding number of `p` (not on the ring) about a ring of points.
fn winding(ring: &[DVec2], p: DVec2) -> i32 {
    let n = ring.len();
    let mut w = 0;
    for i in 0..n {
        let (a, b) = (ring[i], ring[(i + 1) % n]);
        if a.y <= p.y {
            if b.y > p.y && orient(a, b, p) > 0 {
                w += 1;
            }
        } else if b.y <= p.y && orient(a, b, p) < 0 {
            w -= 1;
        }
    }
    w
}

/// The triangles of the region bounded by the rings (a simple, disjoint flattening): the
/// constrained Delaunay triangulation of its points with the chords as constraints, keeping
/// the triangles inside (non-zero winding of their centroid) and dropping slivers of no area.
fn triangulate(
    rings: &[Vec<DVec3>],
    to2: impl Fn(DVec3) -> DVec2,
) -> Result<TriangleMesh, GeomError> {
    let pts3: Vec<DVec3> = rings.iter().flatten().copied().collect();
    let pts: Vec<DVec2> = pts3.iter().map(|&p| to2(p)).collect();
    let mut segs = Vec::with_capacity(pts.len());
    let rings2: Vec<Vec<DVec2>> = rings
        .iter()
        .map(|r| r.iter().map(|&p| to2(p)).collect())
        .collect();
    let mut start = 0;
    for r in rings {
        let n = r.len();
        for i in 0..n {
            segs.push([start + i, start + (i + 1) % n]);
        }
        start += n;
    }
    let tris = crate::planar::constrained_delaunay(&pts, &segs)
        .map_err(|e| e.give_up("the triangulation of a curved light's flattening failed"))?;
    let scale = pts.iter().fold(0.0f64, |m, p| m.max(p.abs().max_element()));
    let mut kept: Vec<[u32; 3]> = Vec::new();
    for [a, b, c] in tris.tris {
        let (pa, pb, pc) = (pts[a], pts[b], pts[c]);
        let area2 = (pb - pa).perp_dot(pc - pa);
        if !(area2 > 1e-20 * scale * scale) {
            continue;
        }
        let centroid = (pa + pb + pc) / 3.0;
        let w: i32 = rings2.iter().map(|r| winding(r, centroid)).sum();
        if w != 0 {
            kept.push([a as u32, b as u32, c as u32]);
        }
    }
    TriangleMesh::new(pts3, kept)
        .map_err(|e| e.give_up("the triangulation of a curved light's flattening is degenerate"))
}

/// The signed number of times the segment (control points `pts`, mapped to the plane by `to2`)
/// crosses the horizontal ray from `q` to the right: `+1` going up, `-1` going down, with
/// "up" meaning `y > q.y` (so that end points shared with neighbours count once).
fn crossings_right(pts: &[DVec3], to2: impl Fn(DVec3) -> DVec2, q: DVec2) -> i32 {
    let p: SmallVec<[DVec2; 4]> = pts.iter().map(|&v| to2(v)).collect();
    let up = |v: DVec2| v.y > q.y;
    let (first, last) = (p[0], p[p.len() - 1]);
    let step = i32::from(up(last)) - i32::from(up(first));
    // Entirely above, below, or left of `q`: no crossing of the ray (by the convex hull).
    let (ymin, ymax) = p
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
            (a.min(v.y), b.max(v.y))
        });
    let xmax = p.iter().fold(f64::NEG_INFINITY, |m, v| m.max(v.x));
    if ymin > q.y || ymax <= q.y || xmax < q.x {
        return 0;
    }
    let xmin = p.iter().fold(f64::INFINITY, |m, v| m.min(v.x));
    if xmin > q.x {
        // Entirely right of `q`: only the net change of side matters.
        return step;
    }
    if p.len() == 2 {
        if step == 0 {
            return 0;
        }
        // The line's crossing is right of q iff q lies left of the upward direction.
        let (a, b) = if step > 0 {
            (first, last)
        } else {
            (last, first)
        };
        return if orient(a, b, q) > 0 { step } else { 0 };
    }
    let c = [p[0], p[1], p[2], p[3]];
    let mut w = 0;
    subdivide_crossings(c, q, 0, &mut w);
    w
}

/// [`crossings_right`] for a cubic by Bezier subdivision: a piece whose control points lie all
/// above or all at or below the ray's line, or all left of `q`, adds nothing; one whose control
/// points are all right of `q` adds its net change of side; others are halved (de Casteljau),
/// down to pieces of `2^-40` of the parameter range, where the net change of side is counted
/// by the piece's chord.
fn subdivide_crossings(c: [DVec2; 4], q: DVec2, depth: u32, w: &mut i32) {
    let up = |v: DVec2| v.y > q.y;
    if c.iter().all(|&v| up(v)) || c.iter().all(|&v| !up(v)) || c.iter().all(|&v| v.x < q.x) {
        return;
    }
    let step = i32::from(up(c[3])) - i32::from(up(c[0]));
    if c.iter().all(|&v| v.x > q.x) {
        *w += step;
        return;
    }
    if depth >= 40 {
        if step != 0 {
            let (a, b) = if step > 0 { (c[0], c[3]) } else { (c[3], c[0]) };
            if orient(a, b, q) > 0 {
                *w += step;
            }
        }
        return;
    }
    let m01 = 0.5 * (c[0] + c[1]);
    let m12 = 0.5 * (c[1] + c[2]);
    let m23 = 0.5 * (c[2] + c[3]);
    let m012 = 0.5 * (m01 + m12);
    let m123 = 0.5 * (m12 + m23);
    let mid = 0.5 * (m012 + m123);
    subdivide_crossings([c[0], m01, m012, mid], q, depth + 1, w);
    subdivide_crossings([mid, m123, m23, c[3]], q, depth + 1, w);
}

#[cfg(test)]
mod tests {
    use super::*;
    use alloc::vec;

    fn sq(c: DVec3, r: f64) -> Vec<BezierSegment> {
        let p = |x: f64, y: f64| c + DVec3::new(x, y, 0.0) * r;
        let v = [p(-1.0, -1.0), p(1.0, -1.0), p(1.0, 1.0), p(-1.0, 1.0)];
        (0..4)
            .map(|i| BezierSegment::Line([v[i], v[(i + 1) % 4]]))
            .collect()
    }

    #[test]
    fn a_square_with_a_hole_has_the_right_area_and_normal() {
        let hole: Vec<BezierSegment> = sq(DVec3::ZERO, 0.5)
            .iter()
            .rev()
            .map(BezierSegment::reversed)
            .collect();
        let s = BezierShape::new(vec![sq(DVec3::ZERO, 1.0), hole]).unwrap();
        assert!((s.area() - 3.0).abs() < 1e-14);
        assert!((s.normal() - DVec3::Z).length() < 1e-15);
        let mesh_area: f64 = (0..s.mesh().triangle_count())
            .map(|t| {
                let [a, b, c] = s.mesh().triangle(t);
                0.5 * (b - a).cross(c - a).length()
            })
            .sum();
        assert!((mesh_area - 3.0).abs() < 1e-12, "{mesh_area}");
        assert!(s.contains(DVec3::new(0.75, 0.0, 0.0)));
        assert!(!s.contains(DVec3::new(0.25, 0.0, 0.0)));
        assert!(!s.contains(DVec3::new(1.5, 0.0, 0.0)));
    }

    #[test]
    fn curved_containment_follows_the_exact_curve() {
        // A lens: two cubics bulging by 0.75 (their midpoints at y = +-0.75).
        let (a, b) = (DVec3::new(-1.0, 0.0, 0.0), DVec3::new(1.0, 0.0, 0.0));
        let up = BezierSegment::Cubic([
            a,
            DVec3::new(-1.0, -1.0, 0.0),
            DVec3::new(1.0, -1.0, 0.0),
            b,
        ]);
        let down =
            BezierSegment::Cubic([b, DVec3::new(1.0, 1.0, 0.0), DVec3::new(-1.0, 1.0, 0.0), a]);
        let s = BezierShape::new(vec![vec![up, down]]).unwrap();
        for y in [0.7499, -0.7499, 0.0] {
            assert!(s.contains(DVec3::new(0.0, y, 0.0)), "{y}");
        }
        for y in [0.7501, -0.7501] {
            assert!(!s.contains(DVec3::new(0.0, y, 0.0)), "{y}");
        }
    }
}
