//! The spherical polygon type: construction, validation, solid angle and point containment.

use core::f64::consts::PI;

use glam::DVec3;
use smallvec::SmallVec;

use super::predicates::{
    AXES, arc_lever, arcs_intersect, normalize_any, orient, triangle_solid_angle,
};
use crate::GeomError;
use alloc::vec::Vec;

/// Consecutive vertices closer than this chord length are rejected as coincident.
///
/// Unit vectors carry about `1.1e-16` of rounding per component, so two directions within a few
/// times that distance are the same direction for every purpose of this crate.
pub const COINCIDENT_TOLERANCE: f64 = 1e-15;

/// Consecutive vertices whose chord to each other's antipode is below this are rejected as
/// antipodal.
///
/// The plane of an edge `a-b` is `a x b`, whose direction is known only to about
/// `1e-16 / |a x b|` radians; at `|a + b| = 1e-10` the edge's great circle is uncertain by about a
/// micro-radian, too much to call it the same edge in every later operation.
pub const ANTIPODAL_TOLERANCE: f64 = 1e-10;

/// Inline capacity for vertices: silhouettes of the lights and occluders a renderer meets (quads,
/// boxes, clipped versions of them) fit without touching the heap.
pub(crate) type Verts = SmallVec<[DVec3; 12]>;

/// A region of the unit sphere bounded by rings of great-circle arcs.
///
/// Each ring is a closed sequence of unit vectors; an edge is the minor great-circle arc between
/// consecutive vertices. The region lies to the LEFT of every edge `a -> b`, on the side where
/// `(a x b) . p > 0`: seen from outside the sphere, an outer ring runs counter-clockwise and a hole
/// clockwise. A single ring therefore describes either of the two regions it bounds, depending
/// on its direction, and regions larger than a hemisphere are ordinary values. No rings is the
/// empty region; the full sphere, which has no boundary, is [`SphericalPolygon::full`].
///
/// Values built with [`SphericalPolygon::new`] are valid: vertices are unit vectors, rings are
/// simple and disjoint except at pinches, and consistently oriented. A pinch is a vertex shared
/// (the same direction) by two rings, or visited twice by one ring: rings may touch there, as
/// long as they do not cross there (the visits' edges do not interleave around the vertex);
/// results of clipping and set operations have them where a hole touches an outer boundary or
/// two parts meet at a corner. Every operation of the crate returns valid values
/// ([`SphericalPolygon::validate`]).
///
/// # Examples
///
/// ```
/// use arealight::glam::DVec3;
/// use arealight::sphere::SphericalPolygon;
///
/// // The positive octant, counter-clockwise seen from outside: an eighth of the sphere.
/// let octant = SphericalPolygon::new(vec![vec![DVec3::X, DVec3::Y, DVec3::Z]])?;
/// assert!((octant.solid_angle() - std::f64::consts::PI / 2.0).abs() < 1e-15);
/// assert!(octant.contains(DVec3::ONE));
/// // The same ring the other way round bounds the other seven eighths.
/// let rest = SphericalPolygon::new(vec![vec![DVec3::X, DVec3::Z, DVec3::Y]])?;
/// assert!((rest.solid_angle() - 3.5 * std::f64::consts::PI).abs() < 1e-14);
/// # Ok::<(), arealight::GeomError>(())
/// ```
#[derive(Clone, Debug, PartialEq, Default)]
pub struct SphericalPolygon {
    verts: Verts,
    /// One past the last vertex of each ring, in `verts`.
    ends: SmallVec<[u32; 2]>,
    /// The full sphere (then there are no rings).
    full: bool,
}

impl SphericalPolygon {
    /// Builds a polygon from rings of directions, validating them.
    ///
    /// Each vertex may have any non-zero finite length and is normalized (one that is a unit
    /// vector to within `4 eps` in squared length is kept as given). Orientation is taken as
    /// given (interior on the left). No rings is the empty region.
    ///
    /// # Errors
    ///
    /// - [`GeomError::NonFinite`] or [`GeomError::ZeroVector`] for a vertex that names no direction;
    /// - [`GeomError::CoincidentVertices`] for consecutive vertices closer than
    ///   [`COINCIDENT_TOLERANCE`], [`GeomError::AntipodalVertices`] for consecutive vertices within
    ///   [`ANTIPODAL_TOLERANCE`] of antipodal;
    /// - [`GeomError::TooFewVertices`] for a ring of fewer than three vertices;
    /// - [`GeomError::SelfIntersecting`] when a ring crosses itself or another ring, touches one
    ///   anywhere but at a pinch (a vertex shared by both, or visited twice by one ring, where
    ///   touching is allowed), crosses one at a pinch, or leaves a vertex along the direction of
    ///   another edge there (within `1e-12` rad, or with the shorter edge's far end within
    ///   `5e-16` of the other's great circle: a spike, or an overlap); checked exactly, with
    ///   Shewchuk's `orient3d`, on the pairs of edges whose bounding boxes meet;
    /// - [`GeomError::ZeroArea`] for a ring whose vertices lie on one great circle to within
    ///   rounding (its smaller side is below `1e-12` times its squared perimeter);
    /// - [`GeomError::InconsistentOrientation`] when two rings bounding the same face disagree on
    ///   which side is inside (for example two nested rings both counter-clockwise);
    /// - [`GeomError::Undecidable`] when the rings are valid as given, but normalizing their
    ///   vertices makes them cross (a vertex within rounding of another ring's edge).
    pub fn new(rings: Vec<Vec<DVec3>>) -> Result<Self, GeomError> {
        let mut poly = SphericalPolygon::empty();
        // The caller's vertices scaled by powers of two only (exact), for the exact predicates:
        // an exact degeneracy in the input (a vertex exactly on another edge, a spike) is no
        // longer exact once normalized, but the sign of det(a, b, c) survives positive scaling.
        let mut raw: Vec<DVec3> = Vec::new();
        let mut renormalized = false;
        for (r, ring) in rings.iter().enumerate() {
            let start = poly.verts.len();
            for (i, &p) in ring.iter().enumerate() {
                if !p.is_finite() {
                    return Err(GeomError::NonFinite { ring: r, vertex: i });
                }
                let u = unit_as_given(p).ok_or(GeomError::ZeroVector { ring: r, vertex: i })?;
                renormalized |= u != p;
                poly.verts.push(u);
                raw.push(scale_pow2(p));
            }
            let n = ring.len();
            if n < 3 {
                return Err(GeomError::TooFewVertices { ring: r, count: n });
            }
            let vs = &poly.verts[start..];
            for i in 0..n {
                let (a, b) = (vs[i], vs[(i + 1) % n]);
                if (a - b).length() <= COINCIDENT_TOLERANCE {
                    return Err(GeomError::CoincidentVertices { ring: r, vertex: i });
                }
                if (a + b).length() <= ANTIPODAL_TOLERANCE {
                    return Err(GeomError::AntipodalVertices { ring: r, vertex: i });
                }
            }
            poly.ends.push(poly.verts.len() as u32);
        }
        poly.check_simple(&raw)?;
        if renormalized {
            // The given rings are simple; the normalized ones, which are stored, must be too.
            // They differ only for a vertex within rounding of another edge.
            poly.check_simple(&poly.verts).map_err(|_| {
                GeomError::Undecidable(
                    "a vertex lies within rounding of another edge: the rings are simple as \
                     given but cross once their vertices are normalized",
                )
            })?;
        }
        poly.check_area()?;
        poly.check_consistent()?;
        Ok(poly)
    }

    /// Checks every invariant that [`SphericalPolygon::new`] establishes and that every result of
    /// the crate's operations keeps: unit vertices (to within `1e-14`), rings of at least three vertices with no two
    /// consecutive ones coincident or antipodal, rings simple, disjoint except at shared
    /// vertices and not folding back on themselves (exact predicates, and the `1e-12` rad fold
    /// test), no ring thinner than [`GeomError::ZeroArea`] allows, and consistent orientation.
    /// Equivalently: `SphericalPolygon::new(p.rings().map(<[_]>::to_vec).collect())` succeeds
    /// and gives `p` back.
    ///
    /// This is the one invariant checker shared by the tests and the fuzz targets. It costs
    /// about `n log n` in the number of edges (a sweep over their bounding boxes) plus the
    /// exact tests of the pairs it finds.
    ///
    /// # Examples
    ///
    /// ```
    /// use arealight::glam::DVec3;
    /// use arealight::planar::BoolOp;
    /// use arealight::sphere::SphericalPolygon;
    ///
    /// let a = SphericalPolygon::new(vec![vec![DVec3::X, DVec3::Y, DVec3::Z]])?;
    /// // B is A with one vertex moved by 2e-12: A - B is a sliver no operation can resolve.
    /// let moved = (DVec3::Y + DVec3::new(1e-12, 0.0, 1e-12)).normalize();
    /// let b = SphericalPolygon::new(vec![vec![DVec3::X, moved, DVec3::Z]])?;
    /// let d = a.boolean(&b, BoolOp::Difference)?;
    /// d.validate()?; // every result is a valid input
    /// assert!(d.solid_angle() < 1e-11);
    /// # Ok::<(), arealight::GeomError>(())
    /// ```
    ///
    /// # Errors
    ///
    /// The first violated invariant, as the error [`SphericalPolygon::new`] would report for it,
    /// or [`GeomError::Degenerate`] for storage that no input could have produced (a vertex
    /// that is not a unit vector, the full sphere with rings).
    pub fn validate(&self) -> Result<(), GeomError> {
        if self.full {
            return if self.ends.is_empty() && self.verts.is_empty() {
                Ok(())
            } else {
                Err(GeomError::Degenerate("the full sphere has rings"))
            };
        }
        let mut start = 0usize;
        for (r, &end) in self.ends.iter().enumerate() {
            let end = end as usize;
            if end < start || end > self.verts.len() {
                return Err(GeomError::Degenerate("ring bounds out of order"));
            }
            let ring = &self.verts[start..end];
            let n = ring.len();
            for (i, p) in ring.iter().enumerate() {
                if !p.is_finite() {
                    return Err(GeomError::NonFinite { ring: r, vertex: i });
                }
                // Unit to within a few dozen ulps (points made on a circle from a rounded frame
                // carry a few): every use is scale-invariant or far coarser than that.
                if !((p.length_squared() - 1.0).abs() <= 1e-14) {
                    return Err(GeomError::Degenerate("a vertex is not a unit vector"));
                }
            }
            if n < 3 {
                return Err(GeomError::TooFewVertices { ring: r, count: n });
            }
            for i in 0..n {
                let (a, b) = (ring[i], ring[(i + 1) % n]);
                if (a - b).length() <= COINCIDENT_TOLERANCE {
                    return Err(GeomError::CoincidentVertices { ring: r, vertex: i });
                }
                if (a + b).length() <= ANTIPODAL_TOLERANCE {
                    return Err(GeomError::AntipodalVertices { ring: r, vertex: i });
                }
            }
            start = end;
        }
        if start != self.verts.len() {
            return Err(GeomError::Degenerate("vertices after the last ring"));
        }
        self.check_simple(&self.verts)?;
        self.check_area()?;
        self.check_consistent()
    }

    /// The empty region (no rings).
    #[must_use]
    pub fn empty() -> Self {
        SphericalPolygon::default()
    }

    /// The whole sphere: no boundary, solid angle `4 pi`.
    #[must_use]
    pub fn full() -> Self {
        SphericalPolygon {
            full: true,
            ..SphericalPolygon::default()
        }
    }

    /// Builds a polygon from rings the caller guarantees valid (unit vectors, simple, disjoint,
    /// consistently oriented). Used by the crate's own operations, whose outputs are valid by
    /// construction, to skip the quadratic checks of [`SphericalPolygon::new`].
    pub(crate) fn from_parts(verts: Verts, ends: SmallVec<[u32; 2]>) -> Self {
        debug_assert!(
            ends.last()
                .map_or(verts.is_empty(), |&e| e as usize == verts.len())
        );
        SphericalPolygon {
            verts,
            ends,
            full: false,
        }
    }

    /// Whether this is the empty region.
    #[must_use]
    #[inline]
    pub fn is_empty(&self) -> bool {
        !self.full && self.ends.is_empty()
    }

    /// Whether this is the full sphere.
    #[must_use]
    #[inline]
    pub fn is_full(&self) -> bool {
        self.full
    }

    /// The rings, each a slice of unit vectors (the closing edge from last to first is implied).
    pub fn rings(&self) -> impl Iterator<Item = &[DVec3]> + Clone + '_ {
        ring_slices(&self.verts, &self.ends)
    }

    /// Number of rings.
    #[must_use]
    pub fn ring_count(&self) -> usize {
        self.ends.len()
    }

    /// The vertices of the only ring, when there is exactly one (the common shape of a light).
    #[inline]
    pub(crate) fn single_ring(&self) -> Option<&[DVec3]> {
        (self.ends.len() == 1).then(|| &self.verts[..])
    }

    /// Total number of vertices over all rings.
    #[must_use]
    pub fn vertex_count(&self) -> usize {
        self.verts.len()
    }

    /// The complement: every ring reversed (and empty and full swapped).
    #[must_use]
    pub fn complement(&self) -> Self {
        if self.full {
            return SphericalPolygon::empty();
        }
        if self.ends.is_empty() {
            return SphericalPolygon::full();
        }
        let mut out = self.clone();
        let mut start = 0usize;
        for &e in &self.ends {
            out.verts[start..e as usize].reverse();
            start = e as usize;
        }
        out
    }

    /// The image of the region under the linear map `m` applied to directions: each vertex `v`
    /// becomes `m v / |m v|`. Great circles map to great circles, so the rings stay valid; a map
    /// with negative determinant mirrors the sphere, and the rings are reversed to keep the
    /// interior on the left. This is how a polygon enters the space of a linearly transformed
    /// cosine (HDHN16 section 3). Any positive multiple of `m` gives the same polygon, however
    /// large or small its entries.
    ///
    /// # Errors
    ///
    /// [`GeomError::Degenerate`] when `m` is singular (or nearly so: `|det m|` below `1e-12`
    /// times the product of its column lengths) or not finite.
    pub fn transformed(&self, m: glam::DMat3) -> Result<SphericalPolygon, GeomError> {
        // Only directions matter, so the map is first scaled to entries of at most 1: a map far
        // from singular is then not rejected for its determinant's overflow or underflow.
        let m = crate::math::unit_scaled(m).unwrap_or(m);
        let det = m.determinant();
        let scale = m.x_axis.length() * m.y_axis.length() * m.z_axis.length();
        if !det.is_finite() || !(det.abs() > 1e-12 * scale) {
            return Err(GeomError::Degenerate(
                "the linear map is singular or not finite",
            ));
        }
        if self.full || self.ends.is_empty() {
            return Ok(self.clone());
        }
        let mut out = self.clone();
        for v in out.verts.iter_mut() {
            *v = unit_as_given(m * *v)
                .ok_or(GeomError::Degenerate("a vertex maps to the zero vector"))?;
        }
        Ok(if det < 0.0 {
            let mut start = 0usize;
            for &e in &self.ends {
                out.verts[start..e as usize].reverse();
                start = e as usize;
            }
            out
        } else {
            out
        })
    }

    /// Solid angle of the region in steradians, in `[0, 4 pi]`.
    ///
    /// Each ring's left region is measured as a fan of Van Oosterom–Strackee triangles from one of
    /// its own vertices (chosen so that no vertex is near its antipode, where the triangle formula
    /// is ill-conditioned); a triangle's area is only defined modulo `4 pi` when its far edge
    /// passes near the apex's antipode, but the sum modulo `4 pi` is exact. The rings' areas add
    /// up to the region's area modulo `4 pi`; they are summed as the signed areas of their
    /// smaller sides, so that a small region with holes (an annulus 1e-16 sr wide) keeps its
    /// precision, and a total within its rounding bound of zero is resolved by one point far
    /// from the boundary (empty or full). Accuracy: about `1e-15 * n` absolute for `n`
    /// vertices, and full relative precision for small polygons and their complements' small
    /// sides (the determinant is evaluated on edge differences), so a polygon of 1e-6 rad across
    /// keeps about 1e-10 relative accuracy, which is what its unit-vector vertices determine. An
    /// edge between nearly antipodal vertices `a`, `b` has its great circle only to about
    /// `1e-16 / |a + b|` rad, and the area loses that much times the edge's length (down to about
    /// `1e-6` for `|a + b|` at [`ANTIPODAL_TOLERANCE`]).
    #[must_use]
    pub fn solid_angle(&self) -> f64 {
        const FOUR_PI: f64 = 4.0 * PI;
        if self.full {
            return FOUR_PI;
        }
        match self.ends.len() {
            0 => 0.0,
            1 => ring_left_area(&self.verts),
            _ => {
                // The rings' areas add up to the region's modulo 4 pi. Summing their smaller sides
                // (each with its own relative precision) keeps a small total precise, where the
                // left areas of holes (4 pi - epsilon each) would swamp it.
                let (mut total, mut err) = (0.0, 0.0);
                for ring in self.rings() {
                    let (a, e) = ring_small_area_err(ring);
                    total += a;
                    err += e + f64::EPSILON * total.abs();
                }
                let r = if (-2.0 * PI..=2.0 * PI).contains(&total) {
                    total
                } else {
                    let left = total.rem_euclid(FOUR_PI);
                    err += 4.0 * f64::EPSILON * FOUR_PI;
                    if left > 2.0 * PI {
                        left - FOUR_PI
                    } else {
                        left
                    }
                };
                if r.abs() > err {
                    return if r > 0.0 { r } else { FOUR_PI + r };
                }
                // Within rounding of both the empty and the full region, which look alike modulo
                // 4 pi: one point far from the boundary tells them apart.
                if self.contains(self.far_point()) {
                    FOUR_PI + r.min(0.0)
                } else {
                    r.max(0.0)
                }
            }
        }
    }

    /// Whether the direction `dir` lies in the region. `dir` need not be normalized; the zero
    /// vector and non-finite vectors are in no region (not even the full sphere).
    ///
    /// Decided by the boundary feature (edge or vertex) nearest to `dir`: the geodesic from `dir`
    /// to it crosses no other edge, so the side of that one feature is the answer. Directions on
    /// the boundary, within rounding, may be reported either way.
    #[must_use]
    pub fn contains(&self, dir: DVec3) -> bool {
        let Some(p) = normalize_any(dir) else {
            return false;
        };
        if self.full {
            return true;
        }
        rings_contain(self.rings(), p)
    }

    /// A direction well away from the boundary: the best of the six axis directions.
    fn far_point(&self) -> DVec3 {
        let mut best = (f64::NEG_INFINITY, DVec3::Z);
        for c in AXES {
            if let Some((d, _)) = nearest_feature(self.rings(), c)
                && d > best.0
            {
                best = (d, c);
            }
        }
        best.1
    }

    /// Rejects rings that cross or overlap themselves or each other.
    ///
    /// Rings may touch at a shared vertex (the same `DVec3` in both places), as the results of
    /// clipping and set operations do where a hole touches an outer boundary; they may not cross
    /// there, nor touch anywhere else.
    fn check_simple(&self, raw: &[DVec3]) -> Result<(), GeomError> {
        // Every edge as (ring, index in ring, start, end), with start and end as indices into
        // `verts` (unit vectors) and `raw` (exactly scaled input).
        let mut edges: SmallVec<[(usize, usize, usize, usize); 32]> =
            SmallVec::with_capacity(self.verts.len());
        let mut start = 0usize;
        for (r, &end) in self.ends.iter().enumerate() {
            let end = end as usize;
            let n = end - start;
            for i in 0..n {
                edges.push((r, i, start + i, start + (i + 1) % n));
            }
            start = end;
        }
        let err = |r: usize, s: usize| GeomError::SelfIntersecting {
            ring: r,
            other_ring: s,
        };
        let v = &self.verts;
        // Only arcs whose bounding boxes overlap can meet: boxes of the endpoints grown by the
        // arc's sagitta 1 - |a + b| / 2 (the farthest a minor arc strays from its chord), with a
        // margin for rounding.
        let boxes: SmallVec<[(DVec3, DVec3); 32]> = edges
            .iter()
            .map(|&(_, _, a, b)| {
                let (p, q) = (v[a], v[b]);
                let grow = DVec3::splat((1.0 - 0.5 * (p + q).length()).max(0.0) + 1e-15);
                (p.min(q) - grow, p.max(q) + grow)
            })
            .collect();
        let overlap = |k: usize, l: usize| {
            let (bk, bl) = (boxes[k], boxes[l]);
            !(bl.0.cmpgt(bk.1).any() || bk.0.cmpgt(bl.1).any())
        };
        let check = |k: usize, l: usize| -> Result<(), GeomError> {
            let ((r, i, a, b), (s, j, c, d)) = (edges[k], edges[l]);
            {
                let n = self.ring_len(r);
                let consecutive = r == s && (j == (i + 1) % n || i == (j + 1) % n);
                // A shared endpoint (the same direction) is allowed; the two edges may not leave
                // it along the same direction (an overlap, or a fold for consecutive edges).
                let shared = if v[b] == v[c] {
                    Some((b, a, d))
                } else if v[a] == v[d] {
                    Some((a, b, c))
                } else if v[a] == v[c] {
                    Some((a, b, d))
                } else if v[b] == v[d] {
                    Some((b, a, c))
                } else {
                    None
                };
                match shared {
                    Some((xi, pi, qi)) => {
                        let (x, p, q) = (v[xi], v[pi], v[qi]);
                        // Within rounding of the same direction counts as overlapping: a spike
                        // narrower than 1e-12 rad has no side any later operation can resolve
                        // (an exactly collinear spike in the caller's coordinates is no longer
                        // exactly collinear once normalized, hence the test on those too).
                        let (tp, tq) = (p - x * p.dot(x), q - x * q.dot(x));
                        let exact_fold = tp.dot(tq) > 0.0 && orient(raw[xi], raw[pi], raw[qi]) == 0;
                        if exact_fold || folds_back(p, x, q) {
                            return Err(err(r, s));
                        }
                        // The far ends may still meet the other edge (two edges sharing both
                        // ends are caught above, as they leave in the same direction).
                    }
                    None if consecutive => {}
                    None => {
                        if arcs_intersect(raw[a], raw[b], raw[c], raw[d]) {
                            return Err(err(r, s));
                        }
                    }
                }
            }
            Ok(())
        };
        let ne = edges.len();
        if ne <= 48 {
            // Few edges (the common case): every pair, in input order.
            for k in 0..ne {
                for l in k + 1..ne {
                    if overlap(k, l) {
                        check(k, l)?;
                    }
                }
            }
        } else {
            // A sweep along x, then the pairs found in input order, so that the first violation
            // reported is the first in the input.
            let mut order: Vec<usize> = (0..ne).collect();
            order.sort_by(|&x, &y| boxes[x].0.x.total_cmp(&boxes[y].0.x));
            let mut pairs: Vec<(usize, usize)> = Vec::new();
            for (w, &k) in order.iter().enumerate() {
                for &l in &order[w + 1..] {
                    if boxes[l].0.x > boxes[k].1.x {
                        break;
                    }
                    if overlap(k, l) {
                        pairs.push((k.min(l), k.max(l)));
                    }
                }
            }
            pairs.sort_unstable();
            for (k, l) in pairs {
                check(k, l)?;
            }
        }
        self.check_pinches()
    }

    /// At a vertex visited more than once (a pinch), each visit's two edges must be adjacent in
    /// the angular order around the vertex; interleaved visits cross each other there.
    fn check_pinches(&self) -> Result<(), GeomError> {
        // (vertex, ring, prev, next) for every vertex occurrence, sorted so equal vertices meet.
        let mut occ: Vec<(DVec3, usize, DVec3, DVec3)> = Vec::with_capacity(self.verts.len());
        for (r, ring) in self.rings().enumerate() {
            let n = ring.len();
            for i in 0..n {
                occ.push((ring[i], r, ring[(i + n - 1) % n], ring[(i + 1) % n]));
            }
        }
        let key = |p: &DVec3| (p.x.to_bits(), p.y.to_bits(), p.z.to_bits());
        occ.sort_by_key(|o| key(&o.0));
        let mut start = 0;
        while start < occ.len() {
            let mut end = start + 1;
            while end < occ.len() && occ[end].0 == occ[start].0 {
                end += 1;
            }
            let group = &occ[start..end];
            if group.len() > 1 {
                let x = group[0].0;
                let (u, v) = super::predicates::tangent_frame(x);
                // Directions of the neighbours in the tangent plane at x, from the differences
                // q - x (exact for close points): x . u is zero only to rounding, which would
                // swamp the direction of an edge shorter than about 1e-13.
                let ang = |p: DVec3| {
                    let d = p - x;
                    crate::math::atan2(d.dot(v), d.dot(u))
                };
                let two_pi = 2.0 * PI;
                for (gi, &(_, ri, pi, ni)) in group.iter().enumerate() {
                    let (lo, span) = (ang(ni), (ang(pi) - ang(ni)).rem_euclid(two_pi));
                    let within = |t: f64| (t - lo).rem_euclid(two_pi) < span;
                    for &(_, rj, pj, nj) in &group[gi + 1..] {
                        if within(ang(pj)) != within(ang(nj)) {
                            return Err(GeomError::SelfIntersecting {
                                ring: ri,
                                other_ring: rj,
                            });
                        }
                    }
                }
            }
            start = end;
        }
        Ok(())
    }

    fn ring_len(&self, r: usize) -> usize {
        let s = if r == 0 { 0 } else { self.ends[r - 1] as usize };
        self.ends[r] as usize - s
    }

    /// Rejects rings whose smaller side is negligible against their extent: a ring of width below
    /// about `1e-12` of its length is a sliver whose two sides cannot be told apart reliably
    /// (every side test near it is decided by rounding). The threshold is relative, so tiny but
    /// well-shaped rings (a square `1e-7` rad across) are accepted.
    fn check_area(&self) -> Result<(), GeomError> {
        for (r, ring) in self.rings().enumerate() {
            if is_sliver(ring) {
                return Err(GeomError::ZeroArea { ring: r });
            }
        }
        Ok(())
    }

    /// Rejects rings that disagree about which side of a shared face is inside.
    ///
    /// Disjoint simple rings cut the sphere into faces whose adjacency graph is a tree. Two rings
    /// border a common face iff no third ring separates them; the face is then on the left of
    /// both or of neither, which is the condition "`j` lies left of `i` iff `i` lies left of `j`".
    fn check_consistent(&self) -> Result<(), GeomError> {
        let k = self.ends.len();
        if k < 2 {
            return Ok(());
        }
        let rings: SmallVec<[&[DVec3]; 4]> = self.rings().collect();
        // side[i * k + j]: ring j (any of its vertices; rings are disjoint) lies left of ring i.
        let mut side: SmallVec<[bool; 16]> = SmallVec::from_elem(false, k * k);
        for i in 0..k {
            for j in 0..k {
                if i != j {
                    // A vertex of ring j that is not a pinch shared with ring i, so that it lies
                    // strictly on one side of ring i (all shared would mean overlapping edges).
                    // If every vertex is such a pinch, an edge midpoint is off ring i (edges
                    // never overlap).
                    let probe = rings[j]
                        .iter()
                        .find(|p| !rings[i].contains(p))
                        .copied()
                        .unwrap_or_else(|| (rings[j][0] + rings[j][1]).normalize());
                    side[i * k + j] = rings_contain(core::iter::once(rings[i]), probe);
                }
            }
        }
        for i in 0..k {
            for j in i + 1..k {
                let separated =
                    (0..k).any(|l| l != i && l != j && side[l * k + i] != side[l * k + j]);
                if !separated && side[i * k + j] != side[j * k + i] {
                    return Err(GeomError::InconsistentOrientation {
                        ring: i,
                        other_ring: j,
                    });
                }
            }
        }
        Ok(())
    }
}

/// `false` when a ring is certainly not a sliver ([`is_sliver`]), by a bound without
/// trigonometry that is conclusive for ordinary rings.
///
/// The vector area of the ring's arcs, `1/2 sum theta_i m_i` (angle `theta_i`, unit normal `m_i`
/// of edge `i`), is `int_W x dA` over either side `W` (the two integrals cancel over the sphere),
/// so its length is at most the smaller side's area. The chords' vector area
/// `1/2 sum sin(theta_i) m_i` differs from it by at most `sum (theta_i - sin theta_i) / 2 <=
/// sum theta_i^3 / 12`, with `theta <= (pi / 2) chord`; the perimeter is at most `pi / 2` times
/// the sum of the chords.
pub(crate) fn may_be_sliver(ring: &[DVec3]) -> bool {
    let m = ring.len();
    let (mut area2, mut chords, mut cubes) = (DVec3::ZERO, 0.0, 0.0);
    for i in 0..m {
        let (a, b) = (ring[i], ring[(i + 1) % m]);
        area2 += a.cross(b);
        let c = (b - a).length();
        chords += c;
        cubes += c * c * c;
    }
    let half_pi = 0.5 * PI;
    let lower =
        0.5 * area2.length() - half_pi * half_pi * half_pi / 12.0 * cubes - 1e-15 * m as f64;
    let perimeter = half_pi * chords;
    !(lower > 1e-12 * perimeter * perimeter)
}

/// Whether a ring's smaller side is below `1e-12` times its squared perimeter: the
/// [`GeomError::ZeroArea`] criterion of [`SphericalPolygon::new`], which operations also apply
/// to their results (a ring that thin is dropped as an artifact of rounding).
pub(crate) fn is_sliver(ring: &[DVec3]) -> bool {
    if !may_be_sliver(ring) {
        return false;
    }
    let area = ring_small_area(ring).abs();
    let n = ring.len();
    let perimeter: f64 = (0..n)
        .map(|i| {
            let (a, b) = (ring[i], ring[(i + 1) % n]);
            crate::math::atan2(a.cross(b).length(), a.dot(b))
        })
        .sum();
    !(area > 1e-12 * perimeter * perimeter)
}

/// Whether the ring folds back at `x` between its neighbours `p` and `q`: the two edges leave
/// `x` in the same direction, exactly, within `1e-12` rad, or so nearly that the far end of the
/// shorter one lies within `5e-16` (a few ulps of a unit vector: the rounding of the vertices)
/// of the other's great circle (a spike, or a notch of the same width). This is the test [`SphericalPolygon::new`] applies to
/// edges sharing an endpoint: a wedge that narrow has no side any later operation can resolve
/// (the direction of an edge of length `l` is only known to about `1e-16 / l`).
pub(crate) fn folds_back(p: DVec3, x: DVec3, q: DVec3) -> bool {
    let (tp, tq) = (p - x * p.dot(x), q - x * q.dot(x));
    if !(tp.dot(tq) > 0.0) {
        return false;
    }
    let (lp, lq) = (tp.length(), tq.length());
    let cross = tp.cross(tq).length();
    orient(x, p, q) == 0 || cross <= 1e-12 * lp * lq || cross <= 5e-16 * lp.max(lq)
}

/// The result of an operation, built from rings that may hold what validation rejects (the
/// operations are exact up to rounding, and rounding can leave features below the resolution
/// validation demands): consecutive vertices closer than `merge` (the operation's weld
/// distance, so that the next operation does not weld them itself) become one where that moves
/// the following edge by at most `merge` ([`arc_lever`]; always within
/// [`COINCIDENT_TOLERANCE`]), vertices where a
/// ring folds back ([`folds_back`]) are removed (this cuts a spike or fills a notch narrower
/// than `1e-12` rad), and rings left with fewer than three vertices or thinner than
/// [`is_sliver`] are dropped. The region moves by at most those edges, wedges and slivers. When
/// every ring is dropped, the result is empty or full as the rings' region was (small or
/// large).
///
/// Also returns whether anything was changed.
pub(crate) fn regularized(
    verts: Verts,
    ends: SmallVec<[u32; 2]>,
    merge: f64,
) -> (SphericalPolygon, bool) {
    let mut out = Verts::new();
    let mut out_ends: SmallVec<[u32; 2]> = SmallVec::new();
    let mut dropped_large = false;
    let mut changed = false;
    let mut start = 0usize;
    for &end in &ends {
        let ring = &verts[start..end as usize];
        start = end as usize;
        let mut r: Verts = ring.iter().copied().collect();
        // Remove short edges' second ends and fold vertices until none is left; each pass
        // removes a vertex or stops.
        loop {
            let m = r.len();
            if m < 3 {
                break;
            }
            let fold = (0..m).find(|&i| {
                let (p, x, q) = (r[(i + m - 1) % m], r[i], r[(i + 1) % m]);
                // Removing `x` moves its edge to `q` by up to `|x - p|` times its lever: only
                // where that stays within `merge` (coincident vertices always go).
                let d = (x - p).length();
                let short = d <= COINCIDENT_TOLERANCE || d * arc_lever(x, q) <= merge;
                p == q || short || folds_back(p, x, q)
            });
            match fold {
                Some(i) => {
                    r.remove(i);
                    changed = true;
                }
                None => break,
            }
        }
        let begin = out.len();
        out.extend_from_slice(&r);
        let before = out_ends.len();
        close_ring(&mut out, &mut out_ends, begin);
        if out_ends.len() > before && is_sliver(&out[begin..]) {
            dropped_large |= ring_small_area(ring) < 0.0;
            out.truncate(begin);
            out_ends.pop();
            changed = true;
        } else if out_ends.len() == before {
            dropped_large |= ring.len() >= 3 && ring_small_area(ring) < 0.0;
            changed = true;
        } else if out.len() - begin != r.len() {
            changed = true;
        }
    }
    if out_ends.is_empty() && !ends.is_empty() {
        let r = if dropped_large {
            SphericalPolygon::full()
        } else {
            SphericalPolygon::empty()
        };
        return (r, true);
    }
    (SphericalPolygon::from_parts(out, out_ends), changed)
}

/// The rings of a flat vertex buffer `verts` whose ring `k` ends (exclusive) at `ends[k]`, the
/// layout of [`SphericalPolygon`] and of the crate's other ring chains.
#[inline]
pub(crate) fn ring_slices<'a>(
    verts: &'a [DVec3],
    ends: &'a [u32],
) -> impl Iterator<Item = &'a [DVec3]> + Clone + 'a {
    let mut start = 0usize;
    ends.iter().map(move |&e| {
        let s = start;
        start = e as usize;
        &verts[s..e as usize]
    })
}

/// Ends the ring begun at `start`: drops vertices that coincide with their predecessor, and the
/// whole ring if fewer than three vertices remain (a zero-area remnant of a touching contact).
pub(crate) fn close_ring(verts: &mut Verts, ends: &mut SmallVec<[u32; 2]>, start: usize) {
    let mut w = start;
    for r in start..verts.len() {
        let p = verts[r];
        if w > start && (p - verts[w - 1]).length() <= COINCIDENT_TOLERANCE {
            continue;
        }
        verts[w] = p;
        w += 1;
    }
    while w - start >= 2 && (verts[w - 1] - verts[start]).length() <= COINCIDENT_TOLERANCE {
        w -= 1;
    }
    verts.truncate(w);
    if w - start < 3 {
        verts.truncate(start);
    } else {
        ends.push(w as u32);
    }
}

/// `p` as a unit vector: `p` itself, bit for bit, when its squared length is within `4 eps` of
/// 1 (as [`normalize_any`] leaves a vector), else normalized; `None` for zero or non-finite `p`.
///
/// Normalizing a unit vector again moves it by an ulp, which can put it on the other side of an
/// edge passing within an ulp (a vertex exactly on another edge's great circle in the caller's
/// coordinates, beyond its end): the stored polygon would cross itself where the given one does
/// not, and a polygon passed through the identity map would not be itself.
pub(crate) fn unit_as_given(p: DVec3) -> Option<DVec3> {
    if (p.length_squared() - 1.0).abs() <= 4.0 * f64::EPSILON {
        Some(p)
    } else {
        normalize_any(p)
    }
}

/// `p` times a power of two that brings its largest component into `[0.5, 1)`: exact, so every
/// sign of a determinant of such vectors is that of the caller's vectors, and no product in the
/// exact predicates can overflow or underflow.
fn scale_pow2(p: DVec3) -> DVec3 {
    let m = p.abs().max_element();
    if m == 0.0 || !m.is_finite() {
        return p;
    }
    // Subnormal magnitudes are first lifted by an exact 2^600, huge ones lowered by 2^-600, so
    // that the final power of two below is a normal number.
    let (p, m) = if m < f64::MIN_POSITIVE {
        let k = f64::from_bits((1023u64 + 600) << 52);
        (p * k, m * k)
    } else if m >= f64::from_bits((1023u64 + 1000) << 52) {
        let k = f64::from_bits((1023u64 - 600) << 52);
        (p * k, m * k)
    } else {
        (p, m)
    };
    let e = ((m.to_bits() >> 52) & 0x7ff) as i64 - 1023; // m in [2^e, 2^(e+1))
    let scale = f64::from_bits(((1023 - e - 1) as u64) << 52); // 2^-(e+1)
    p * scale
}

/// Solid angle of the region to the left of one ring, in `[0, 4 pi]`.
pub(crate) fn ring_left_area(ring: &[DVec3]) -> f64 {
    let small = ring_small_area(ring);
    // A tiny clockwise ring gives -epsilon and maps to 4 pi - epsilon, as it should.
    if small >= 0.0 {
        small
    } else {
        4.0 * PI + small
    }
}

/// The solid angle of a ring's smaller side, positive when that side is on the left (the ring
/// runs counter-clockwise around it), negative when on the right: in `[-2 pi, 2 pi]`, with full
/// relative precision for small rings of either orientation.
///
/// The fan of Van Oosterom-Strackee triangles gives the left area modulo `4 pi`; for a small
/// ring that is `+-epsilon` directly, with the relative precision of its edge differences, which
/// the left area of a clockwise ring (`4 pi - epsilon`, absolute error about `1e-15`) loses.
pub(crate) fn ring_small_area(ring: &[DVec3]) -> f64 {
    ring_small_area_with::<false>(ring).0
}

/// [`ring_small_area`] with a bound on its rounding error: each triangle's determinant on edge
/// differences rounds by a few ulps of the product of the two edge lengths (bounded by half the
/// sum of their squares), its angle by that over the denominator, plus the rounding of the
/// angle and of the sum.
pub(crate) fn ring_small_area_err(ring: &[DVec3]) -> (f64, f64) {
    ring_small_area_with::<true>(ring)
}

fn ring_small_area_with<const ERR: bool>(ring: &[DVec3]) -> (f64, f64) {
    let n = ring.len();
    let apex = fan_apex(ring);
    let (mut sum, mut err) = (0.0, 0.0);
    for i in 0..n {
        let (b, c) = (ring[i], ring[(i + 1) % n]);
        // Triangles through the apex vertex itself are degenerate and contribute exactly zero.
        if b != apex && c != apex {
            let t = triangle_solid_angle(apex, b, c);
            sum += t;
            if ERR {
                // t = 2 atan2(det, den) moves by 2 (|den| e_det + |det| e_den) / (det^2 + den^2)
                // for errors e_det, e_den of its arguments: a few ulps of the edges' product
                // (at most half the sum of their squares) and of the four unit terms of den.
                // Over det^2 + den^2, not den^2: where den alone vanishes (b and c almost
                // antipodal, the apex a quarter turn from both) the angle is near +-pi and
                // conditioned by |det|.
                let det = apex.dot((b - apex).cross(c - apex));
                let den = 1.0 + apex.dot(b) + b.dot(c) + c.dot(apex);
                let sides = 0.5 * ((b - apex).length_squared() + (c - apex).length_squared());
                let spread = (sides * den.abs() + 4.0 * det.abs()) / (det * det + den * den);
                err += 32.0 * f64::EPSILON * (spread + t.abs() + sum.abs());
            }
        }
    }
    if (-2.0 * PI..=2.0 * PI).contains(&sum) {
        return (sum, err);
    }
    let left = sum.rem_euclid(4.0 * PI);
    let small = if left > 2.0 * PI {
        left - 4.0 * PI
    } else {
        left
    };
    (small, err + 8.0 * f64::EPSILON * 4.0 * PI)
}

/// Whether the unit vector `p` lies in the region bounded by `rings` (none: no region): the test
/// of [`SphericalPolygon::contains`], also for a subset of a polygon's rings (one ring alone
/// bounds the region on its left).
///
/// The side of the nearest boundary feature decides, where it is well-conditioned: within a
/// quarter turn (squared chord at most 2). Farther away (for a tiny polygon all features are
/// then almost equally far, and the direction from each towards `p` is almost normal to the
/// sphere) every vertex lies in the open hemisphere about `-p`, whose gnomonic plane holds the
/// whole boundary with `p` at infinity: `p` is inside iff the outermost rings run clockwise
/// there ([`far_side_inside`]).
///
/// Where another feature with the other verdict is as near within rounding (`p` faces the two
/// sides of a sliver thinner than the rounding of its distance to them: the geodesic to the
/// nearer one crosses the other, and rounding picks either), the parity of the exact crossings
/// of an arc from `p` to a reference direction decides instead ([`parity_contains`]).
pub(crate) fn rings_contain<'a>(
    rings: impl Iterator<Item = &'a [DVec3]> + Clone,
    p: DVec3,
) -> bool {
    let Some((d, inside, ambiguous)) = nearest_feature_checked(rings.clone(), p) else {
        return false;
    };
    if d <= 2.0 {
        if ambiguous {
            return parity_contains(rings, p).unwrap_or(inside);
        }
        return inside;
    }
    far_side_inside(rings, -p).unwrap_or(inside)
}

/// Whether `p` lies in the region, by the parity of the exact crossings (`orient3d`) of the
/// minor arc from `p` to a reference direction `r` with the edges, `r`'s own membership decided
/// by its nearest feature where that is unambiguous and clear of the boundary. References: the
/// coordinate axes and the cube's diagonals, each skipped when it is near `-p` or when the arc
/// passes exactly through a vertex or ends on an edge's circle. `None` when none will do.
fn parity_contains<'a>(rings: impl Iterator<Item = &'a [DVec3]> + Clone, p: DVec3) -> Option<bool> {
    let s = 1.0 / crate::math::sqrt(3.0);
    let diagonals = [-1.0, 1.0].into_iter().flat_map(move |x| {
        [-1.0, 1.0]
            .into_iter()
            .flat_map(move |y| [-1.0, 1.0].map(|z| DVec3::new(x, y, z) * s))
    });
    'reference: for r in AXES.into_iter().chain(diagonals) {
        if (p + r).length_squared() < 0.25 || p == r {
            continue;
        }
        let (dr, inside_r, ambiguous) = nearest_feature_checked(rings.clone(), r)?;
        if ambiguous || !(dr > 1e-12) || dr > 2.0 {
            continue;
        }
        let mut odd = false;
        for ring in rings.clone() {
            let n = ring.len();
            for i in 0..n {
                let (a, b) = (ring[i], ring[(i + 1) % n]);
                let (abp, abr) = (orient(a, b, p), orient(a, b, r));
                let (pra, prb) = (orient(p, r, a), orient(p, r, b));
                if abr == 0 || pra == 0 || prb == 0 {
                    continue 'reference;
                }
                if abp == 0 {
                    // p on this edge's circle: on the boundary if within the arc, else the
                    // crossing is decided by the other edges; either way rounding may decide.
                    return None;
                }
                // The arcs cross (at the point on both minor arcs, not its antipode).
                if abp != abr && pra != prb && pra == abr {
                    odd = !odd;
                }
            }
        }
        return Some(inside_r ^ odd);
    }
    None
}

/// When every vertex of `rings` lies in the open hemisphere about `c` (by more than
/// [`super::HORIZON_TOLERANCE`]): whether the region contains the far side of that hemisphere
/// (its bounding circle and `-c`), else `None`.
///
/// In the gnomonic plane about `c` the rings are closed polygons and the far side is at
/// infinity; the unbounded face is inside the region iff the outermost rings run clockwise,
/// i.e. iff the total signed area is negative (nested rings alternate and are smaller than their
/// parents). Each ring's shoelace sum is taken about its own first vertex: summing
/// `P_i x P_{i+1}` about the plane's origin instead adds terms of the size of the ring's distance
/// from `c` times its width, whose rounding swamps the area of a ring of 1e-8 rad or less. A
/// total within rounding of zero (nested rings of almost equal areas) decides nothing (`None`).
pub(crate) fn far_side_inside<'a>(
    rings: impl Iterator<Item = &'a [DVec3]>,
    c: DVec3,
) -> Option<bool> {
    let (mut area2, mut size2, mut terms) = (0.0, 0.0f64, 0usize);
    for ring in rings {
        let project = |p: DVec3| {
            let w = p.dot(c);
            (w > super::HORIZON_TOLERANCE).then(|| p / w)
        };
        let origin = project(*ring.first()?)?;
        let mut prev = DVec3::ZERO;
        for &p in &ring[1..] {
            let d = project(p)? - origin;
            area2 += prev.cross(d).dot(c);
            let d2 = d.length_squared();
            if d2 > size2 {
                size2 = d2;
            }
            prev = d;
        }
        terms += ring.len();
    }
    // Each term rounds by a few ulps of |prev| |d| <= size2.
    (area2.abs() > 1e-12 * terms as f64 * size2).then_some(area2 < 0.0)
}

/// The fan apex for [`ring_left_area`]: the first vertex when no vertex lies near its antipode
/// (the common case), else the vertex or axis direction whose antipode is farthest from every
/// vertex. The Van Oosterom–Strackee denominator `1 + a.b + b.c + c.a` and numerator both vanish
/// only when a vertex is antipodal to the apex.
fn fan_apex(ring: &[DVec3]) -> DVec3 {
    let clearance = |c: DVec3| {
        ring.iter()
            .map(|&v| (c + v).length_squared())
            .fold(f64::INFINITY, f64::min)
    };
    if clearance(ring[0]) >= 0.5 {
        return ring[0];
    }
    let mut best = (clearance(ring[0]), ring[0]);
    for &c in ring.iter().chain(AXES.iter()) {
        let d = clearance(c);
        if d > best.0 {
            best = (d, c);
        }
    }
    best.1
}

/// The boundary feature nearest to the unit vector `p`, as (squared chord distance, whether `p`
/// is on the inside of it), or `None` when there are no rings.
pub(crate) fn nearest_feature<'a>(
    rings: impl Iterator<Item = &'a [DVec3]> + Clone,
    p: DVec3,
) -> Option<(f64, bool)> {
    nearest_feature_checked(rings, p).map(|(d, inside, _)| (d, inside))
}

/// [`nearest_feature`], and whether another feature within `1e-12` (relative, in squared chord)
/// of the same distance gives the other verdict, which rounding may have put first.
pub(crate) fn nearest_feature_checked<'a>(
    rings: impl Iterator<Item = &'a [DVec3]> + Clone,
    p: DVec3,
) -> Option<(f64, bool, bool)> {
    // The nearest feature so far: its squared chord distance, and either the side of an edge or
    // the vertex itself (whose side is decided after the scan, from all its visits).
    let mut best: Option<(f64, Result<bool, DVec3>)> = None;
    // For the ambiguity: the nearest edge of each verdict, the two nearest distinct vertices.
    let mut edge_min = [f64::INFINITY; 2];
    let mut vertex_min = [(f64::INFINITY, DVec3::ZERO); 2];
    let mut consider = |d: f64, what: Result<bool, DVec3>| {
        match what {
            Ok(inside) => edge_min[inside as usize] = edge_min[inside as usize].min(d),
            Err(v) => {
                if v != vertex_min[0].1 && v != vertex_min[1].1 {
                    if d < vertex_min[0].0 {
                        vertex_min = [(d, v), vertex_min[0]];
                    } else if d < vertex_min[1].0 {
                        vertex_min[1] = (d, v);
                    }
                }
            }
        }
        if best.is_none_or(|(bd, _)| d < bd) {
            best = Some((d, what));
        }
    };
    for ring in rings.clone() {
        let n = ring.len();
        for i in 0..n {
            let a = ring[i];
            let b = ring[(i + 1) % n];
            // a x (b - a) = a x b, without the cancellation that would leave a short edge's
            // normal with a relative error of 1e-16 over its length.
            let nrm = a.cross(b - a);
            let len = nrm.length();
            // p's nearest point on the great circle lies inside the arc iff turning from a to p
            // and from p to b both go the arc's way round. The turns are taken from differences
            // (a x p = a x (p - a)), so their rounding is relative to |p - a| and |b - p|; a foot
            // within that rounding of an end is left to the end's vertex, which is then as near
            // and decides the side from all the edges there (an edge whose foot only rounds
            // into the arc would decide it alone, and wrongly, when p lies straight above a
            // vertex outside the edge's wedge).
            let pa = p - a;
            let bp = b - p;
            if a.cross(pa).dot(nrm) > 1e-15 * pa.length() * len
                && p.cross(bp).dot(nrm) > 1e-15 * bp.length() * len
            {
                // Sine of the distance to the circle (p - a is exact for close points).
                let s = pa.dot(nrm) / len;
                let s2 = (s * s).min(1.0);
                // Squared chord to the nearest point, 2 - 2 cos(d), without cancellation.
                let d = 2.0 * s2 / (1.0 + crate::math::sqrt(1.0 - s2));
                consider(d, Ok(s > 0.0));
            }
            consider(pa.length_squared(), Err(a));
        }
    }
    let (d, what) = best?;
    let inside = what.unwrap_or_else(|v| vertex_side(rings.clone(), v, p));
    let near = |x: f64| x <= d + 1e-12 * d;
    let ambiguous = near(edge_min[!inside as usize])
        || vertex_min.iter().any(|&(dv, v)| {
            near(dv) && Err(v) != what && vertex_side(rings.clone(), v, p) != inside
        });
    Some((d, inside, ambiguous))
}

/// Whether the point `p` lies inside the region near the vertex `v`, from every visit of the
/// rings to `v` (a pinch vertex is visited more than once). Around `v`, the sector just
/// counter-clockwise of an edge direction is inside iff that edge leaves `v` (the interior is on
/// the left of every edge); so the answer is the kind of the edge met first turning clockwise
/// from `p`.
pub(crate) fn vertex_side<'a>(
    rings: impl Iterator<Item = &'a [DVec3]>,
    v: DVec3,
    p: DVec3,
) -> bool {
    let (u, w) = super::predicates::tangent_frame(v);
    // Directions in the tangent plane at v from the differences q - v, as in `check_pinches`.
    let ang = |q: DVec3| {
        let d = q - v;
        crate::math::atan2(d.dot(w), d.dot(u))
    };
    let target = ang(p);
    // (clockwise turn from p's direction to the edge's, edge leaves v)
    let mut best = (f64::INFINITY, false);
    for ring in rings {
        let n = ring.len();
        for i in 0..n {
            if ring[i] != v {
                continue;
            }
            for (q, leaves) in [(ring[(i + n - 1) % n], false), (ring[(i + 1) % n], true)] {
                let turn = (target - ang(q)).rem_euclid(2.0 * PI);
                if turn < best.0 {
                    best = (turn, leaves);
                }
            }
        }
    }
    best.1
}

#[cfg(test)]
mod tests {
    use super::*;
    use alloc::vec;

    #[test]
    fn hemisphere_ring_measures_two_pi() {
        let up =
            SphericalPolygon::new(vec![vec![DVec3::X, DVec3::Y, -DVec3::X, -DVec3::Y]]).unwrap();
        assert!((up.solid_angle() - 2.0 * PI).abs() < 1e-14);
        assert!(up.contains(DVec3::Z));
        assert!(!up.contains(-DVec3::Z));
    }

    #[test]
    fn power_of_two_scaling_is_exact_and_bounded() {
        for p in [
            DVec3::new(3.0, -7.0, 0.5),
            DVec3::new(1e-310, 0.0, -3e-312),
            DVec3::new(1e308, -1.7e308, 2.0),
            DVec3::new(0.0, 0.0, 1.0),
        ] {
            let q = scale_pow2(p);
            let m = q.abs().max_element();
            assert!((0.5..1.0).contains(&m), "{p} -> {q}");
            // Exact: normal components keep their significand bits (only the exponent moves).
            let mask = (1u64 << 52) - 1;
            for (a, b) in p.to_array().into_iter().zip(q.to_array()) {
                if a.is_normal() && b.is_normal() {
                    assert_eq!(a.to_bits() & mask, b.to_bits() & mask, "{a} -> {b}");
                }
            }
        }
    }

    #[test]
    fn rejects_bad_rings() {
        let e = SphericalPolygon::new(vec![vec![DVec3::X, DVec3::Y]]);
        assert_eq!(e, Err(GeomError::TooFewVertices { ring: 0, count: 2 }));
        let e = SphericalPolygon::new(vec![vec![
            DVec3::X,
            DVec3::Y,
            DVec3::new(f64::NAN, 0.0, 1.0),
        ]]);
        assert_eq!(e, Err(GeomError::NonFinite { ring: 0, vertex: 2 }));
        let e = SphericalPolygon::new(vec![vec![DVec3::X, DVec3::ZERO, DVec3::Z]]);
        assert_eq!(e, Err(GeomError::ZeroVector { ring: 0, vertex: 1 }));
        let e = SphericalPolygon::new(vec![vec![DVec3::X, DVec3::Y, -DVec3::Y]]);
        assert_eq!(e, Err(GeomError::AntipodalVertices { ring: 0, vertex: 1 }));
        let e = SphericalPolygon::new(vec![vec![DVec3::X, DVec3::X * 2.0, DVec3::Z]]);
        assert_eq!(e, Err(GeomError::CoincidentVertices { ring: 0, vertex: 0 }));
        // A bow tie.
        let bow = vec![
            DVec3::new(1.0, -0.1, -0.1),
            DVec3::new(1.0, 0.1, 0.1),
            DVec3::new(1.0, 0.1, -0.1),
            DVec3::new(1.0, -0.1, 0.1),
        ];
        assert!(matches!(
            SphericalPolygon::new(vec![bow]),
            Err(GeomError::SelfIntersecting { .. })
        ));
    }

    #[test]
    fn nested_rings_must_alternate() {
        let square = |h: f64| {
            vec![
                DVec3::new(h, -h, 1.0),
                DVec3::new(h, h, 1.0),
                DVec3::new(-h, h, 1.0),
                DVec3::new(-h, -h, 1.0),
            ]
        };
        let mut hole = square(0.1);
        hole.reverse();
        let ok = SphericalPolygon::new(vec![square(0.5), hole.clone()]).unwrap();
        assert!(!ok.contains(DVec3::Z));
        assert!(ok.contains(DVec3::new(0.3, 0.0, 1.0)));
        let (a, b) = (
            SphericalPolygon::new(vec![square(0.5)])
                .unwrap()
                .solid_angle(),
            SphericalPolygon::new(vec![square(0.1)])
                .unwrap()
                .solid_angle(),
        );
        assert!((ok.solid_angle() - (a - b)).abs() < 1e-14);
        assert!(matches!(
            SphericalPolygon::new(vec![square(0.5), square(0.1)]),
            Err(GeomError::InconsistentOrientation { .. })
        ));
    }

    #[test]
    fn complement_adds_to_four_pi() {
        let tri = SphericalPolygon::new(vec![vec![
            DVec3::new(1.0, 0.0, 0.2),
            DVec3::new(0.0, 1.0, 0.3),
            DVec3::new(0.1, 0.2, 1.0),
        ]])
        .unwrap();
        assert!((tri.solid_angle() + tri.complement().solid_angle() - 4.0 * PI).abs() < 1e-13);
        assert_eq!(
            SphericalPolygon::full().complement(),
            SphericalPolygon::empty()
        );
    }

    /// `regularized` removes a spike narrower than the fold test and a repeated vertex, drops a
    /// sliver ring, and says empty or full when every ring goes.
    #[test]
    fn regularized_removes_what_validation_rejects() {
        let (a, b, c, d) = (
            DVec3::new(1.0, 0.0, 0.2).normalize(),
            DVec3::new(0.0, 1.0, 0.3).normalize(),
            DVec3::new(0.1, 0.2, 1.0).normalize(),
            DVec3::new(0.2, 0.1, 1.0).normalize(),
        );
        // A spike from c out towards d and back, 1e-14 rad wide, and a repeated vertex.
        let tip = (d + (d - c).cross(c) * 1e-14).normalize();
        let spiky: Verts = [a, b, b, c, tip, c, d].into_iter().collect();
        let ends: SmallVec<[u32; 2]> = SmallVec::from_slice(&[spiky.len() as u32]);
        assert!(
            SphericalPolygon::from_parts(spiky.clone(), ends.clone())
                .validate()
                .is_err()
        );
        let (r, changed) = regularized(spiky, ends, 1e-13);
        assert!(changed);
        r.validate().unwrap();
        let clean = SphericalPolygon::new(vec![vec![a, b, c, d]]).unwrap();
        assert!((r.solid_angle() - clean.solid_angle()).abs() < 1e-13);
        // A sliver ring alone (counter-clockwise: the path out bulges to the right of the arc
        // back): dropped, leaving the empty region; reversed, the full sphere.
        let mid = (a + b).normalize();
        let sliver: Verts = [a, (mid - a.cross(b) * 1e-14).normalize(), b, mid]
            .into_iter()
            .collect();
        let ends: SmallVec<[u32; 2]> = SmallVec::from_slice(&[4]);
        let (r, _) = regularized(sliver.clone(), ends.clone(), 1e-13);
        assert!(r.is_empty());
        let reversed: Verts = sliver.into_iter().rev().collect();
        let (r, _) = regularized(reversed, ends, 1e-13);
        assert!(r.is_full());
    }

    #[test]
    fn tiny_polygon_keeps_relative_precision() {
        // A square 2e-7 rad on a side around +z: planar area 4e-14 to within O(h^4).
        let h = 1e-7;
        let ring = vec![
            DVec3::new(h, -h, 1.0),
            DVec3::new(h, h, 1.0),
            DVec3::new(-h, h, 1.0),
            DVec3::new(-h, -h, 1.0),
        ];
        let w = SphericalPolygon::new(vec![ring.clone()])
            .unwrap()
            .solid_angle();
        assert!((w / (4.0 * h * h) - 1.0).abs() < 1e-8, "{w}");
        let mut rev = ring;
        rev.reverse();
        let big = SphericalPolygon::new(vec![rev]).unwrap().solid_angle();
        assert!((big - (4.0 * PI - w)).abs() < 1e-14);
    }
}
