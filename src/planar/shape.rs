//! Planar shapes: sets of non-crossing contours, validated at construction.

use alloc::vec::Vec;
use glam::DVec2;
use smallvec::SmallVec;

use super::contour::Contour;
use super::predicates::{
    MAX_COORD, on_segment, orient, orient_sign, segments_touch, strictly_between, winding,
};
use crate::GeomError;

/// A planar region bounded by closed contours: outer contours counter-clockwise, holes clockwise.
///
/// The contours of a shape never cross or overlap one another; they may touch at isolated points
/// (a hole touching its outer contour at a vertex, two faces meeting at a corner). This is exactly
/// the class of regions that [`boolean`](super::boolean) produces, so every result is a valid
/// operand again.
///
/// # Examples
///
/// ```
/// use arealight::glam::DVec2;
/// use arealight::planar::Shape;
///
/// // Given clockwise, fixed to counter-clockwise because it is not nested in anything.
/// let square = Shape::new(vec![vec![
///     DVec2::new(0.0, 0.0),
///     DVec2::new(0.0, 2.0),
///     DVec2::new(2.0, 2.0),
///     DVec2::new(2.0, 0.0),
/// ]])
/// .unwrap();
/// assert_eq!(square.area(), 4.0);
/// ```
#[derive(Clone, Default)]
pub struct Shape {
    pub(crate) contours: Vec<Contour>,
    /// Facts derived from `contours` once, so that each boolean operation need not recompute
    /// them; they never change what a shape is (equality and `Debug` ignore them).
    pub(crate) facts: Facts,
}

/// What [`boolean`](super::boolean) needs to know about an operand before it decides between
/// the generic-position fast path and the robust pipeline, computed when the shape is made.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Facts {
    /// Bounding box (`lo > hi` for the empty shape).
    pub(crate) lo: DVec2,
    pub(crate) hi: DVec2,
    /// Smallest squared distance between two vertices of the shape (any contours; `INFINITY`
    /// below two vertices). `None` for results of `boolean`, where computing it for every
    /// result would cost every operation, and only chained operations need it.
    pub(crate) sep2: Option<f64>,
    /// Whether a vertex of one contour lies exactly inside an edge of another contour (a
    /// touching point of two contours that is a vertex of only one). `None` when not computed.
    pub(crate) self_contacts: Option<bool>,
}

impl Default for Facts {
    fn default() -> Facts {
        Facts {
            lo: DVec2::INFINITY,
            hi: DVec2::NEG_INFINITY,
            sep2: Some(f64::INFINITY),
            self_contacts: Some(false),
        }
    }
}

impl Facts {
    /// The bounding box only; the other facts are left to be computed on demand.
    pub(crate) fn bbox(contours: &[Contour]) -> Facts {
        let (mut lo, mut hi) = (DVec2::INFINITY, DVec2::NEG_INFINITY);
        for c in contours {
            for &p in &c.pts {
                // Plain comparisons: coordinates are finite.
                lo.x = if p.x < lo.x { p.x } else { lo.x };
                lo.y = if p.y < lo.y { p.y } else { lo.y };
                hi.x = if p.x > hi.x { p.x } else { hi.x };
                hi.y = if p.y > hi.y { p.y } else { hi.y };
            }
        }
        Facts {
            lo,
            hi,
            sep2: None,
            self_contacts: None,
        }
    }

    /// Largest coordinate magnitude inside the bounding box (0 for the empty shape).
    pub(crate) fn bbox_scale(&self) -> f64 {
        if self.lo.x > self.hi.x {
            return 0.0;
        }
        self.lo.abs().max(self.hi.abs()).max_element()
    }

    /// All facts.
    pub(crate) fn all(contours: &[Contour]) -> Facts {
        Facts::with_separation(contours, min_separation2(contours))
    }

    /// All facts, the minimum vertex separation already known.
    pub(crate) fn with_separation(contours: &[Contour], sep2: f64) -> Facts {
        Facts {
            sep2: Some(sep2),
            self_contacts: Some(has_self_contacts(contours)),
            ..Facts::bbox(contours)
        }
    }
}

/// Smallest squared distance between two vertices over all contours (`INFINITY` below two
/// vertices): a sweep over the vertices sorted by x that stops looking once the x-distance
/// alone reaches the best squared distance so far, which is exact (the computed `dx * dx` never
/// exceeds the computed squared distance, and grows along the sorted order).
pub(crate) fn min_separation2(contours: &[Contour]) -> f64 {
    let mut by_x: SmallVec<[DVec2; 64]> = contours
        .iter()
        .flat_map(|c| c.pts.iter().copied())
        .collect();
    by_x.sort_unstable_by(|p, q| p.x.total_cmp(&q.x));
    let mut best = f64::INFINITY;
    for (i, &p) in by_x.iter().enumerate() {
        for &q in &by_x[i + 1..] {
            let dx = q.x - p.x;
            if dx * dx >= best {
                break;
            }
            best = best.min((p - q).length_squared());
        }
    }
    best
}

/// Whether a vertex of one contour lies exactly inside an edge of another contour.
pub(crate) fn has_self_contacts(contours: &[Contour]) -> bool {
    if contours.len() < 2 {
        return false;
    }
    for (ci, c) in contours.iter().enumerate() {
        let n = c.pts.len();
        for i in 0..n {
            let (p0, p1) = (c.pts[i], c.pts[if i + 1 == n { 0 } else { i + 1 }]);
            let (lo, hi) = (p0.min(p1), p0.max(p1));
            for (cj, d) in contours.iter().enumerate() {
                if cj == ci {
                    continue;
                }
                for &q in &d.pts {
                    if q.x < lo.x || q.x > hi.x || q.y < lo.y || q.y > hi.y {
                        continue;
                    }
                    if orient(p0, p1, q) == 0.0 && strictly_between(p0, p1, q) {
                        return true;
                    }
                }
            }
        }
    }
    false
}

/// Whether a vertex lies within `snap` of an edge of the shape that does not end at it (of its
/// own contour or another), beside the edge (its projection strictly inside), without lying
/// exactly on it.
///
/// [`boolean`](super::boolean) resolves such near-contacts between its two operands (the vertex
/// is put on the edge) but takes each operand's own as given: exact predicates decide them, and
/// a crossing computed next to one bends a split edge past the vertex by rounding. Callers
/// whose shapes carry that rounding (projections) check this and resolve such shapes under a
/// fill rule at the same resolution. `O(n^2)` over all vertex-edge pairs, pruned by bounding
/// boxes grown by `snap`.
pub(crate) fn has_near_self_contacts(contours: &[Contour], snap: f64) -> bool {
    for c in contours {
        let n = c.pts.len();
        for i in 0..n {
            let (p0, p1) = (c.pts[i], c.pts[if i + 1 == n { 0 } else { i + 1 }]);
            let (lo, hi) = (
                p0.min(p1) - DVec2::splat(snap),
                p0.max(p1) + DVec2::splat(snap),
            );
            let d = p1 - p0;
            let len = d.length();
            for d2 in contours {
                for &q in &d2.pts {
                    if q.x < lo.x || q.x > hi.x || q.y < lo.y || q.y > hi.y || q == p0 || q == p1 {
                        continue;
                    }
                    let o = orient(p0, p1, q);
                    if o == 0.0 || !(o.abs() <= snap * len) {
                        continue;
                    }
                    let t = (q - p0).dot(d);
                    if t > 0.0 && t < d.length_squared() {
                        return true;
                    }
                }
            }
        }
    }
    false
}

impl PartialEq for Shape {
    /// Shapes are equal when their contours are (same points, same starting points, same
    /// order); the cached facts follow from the contours.
    fn eq(&self, other: &Shape) -> bool {
        self.contours == other.contours
    }
}

impl core::fmt::Debug for Shape {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("Shape")
            .field("contours", &self.contours)
            .finish()
    }
}

impl Shape {
    /// The empty shape (no contours).
    #[must_use]
    pub fn empty() -> Shape {
        Shape::default()
    }

    /// Builds a shape from rings of points, validating them and fixing their orientation.
    ///
    /// Each ring is a closed polygon; a repeated closing point is allowed and dropped. Consecutive
    /// duplicate points and exactly collinear middle points (including spikes that double back)
    /// are removed, because they bound no area. Orientation is set by nesting depth: a ring inside
    /// an even number of other rings becomes a counter-clockwise outer contour, one inside an odd
    /// number a clockwise hole. No rings gives the empty shape.
    ///
    /// Besides validating, this computes once what [`boolean`](super::boolean) needs to know
    /// about the shape alone to choose its path (bounding box, smallest distance between two
    /// vertices, vertices lying on another contour of the shape), so that operations on the
    /// shape do not recompute it.
    ///
    /// # Errors
    ///
    /// - [`GeomError::NonFinite`] for a NaN or infinite coordinate, and
    ///   [`GeomError::CoordinateOutOfRange`] for a coordinate of magnitude above [`MAX_COORD`]
    ///   (`1e150`), beyond which the exact orientation predicate could overflow, both naming the
    ///   ring and the vertex;
    /// - [`GeomError::TooFewVertices`] for a ring with fewer than three distinct, non-collinear
    ///   points;
    /// - [`GeomError::SelfIntersecting`] when a ring touches or crosses itself, or two rings cross
    ///   or share a stretch of boundary (rings may only touch at isolated points).
    pub fn new(contours: Vec<Vec<DVec2>>) -> Result<Shape, GeomError> {
        let mut rings: Vec<Vec<DVec2>> = Vec::with_capacity(contours.len());
        for (ri, ring) in contours.into_iter().enumerate() {
            for (vi, p) in ring.iter().enumerate() {
                if !p.x.is_finite() || !p.y.is_finite() {
                    return Err(GeomError::NonFinite {
                        ring: ri,
                        vertex: vi,
                    });
                }
                let m = p.x.abs().max(p.y.abs());
                if m > MAX_COORD {
                    return Err(GeomError::CoordinateOutOfRange {
                        ring: ri,
                        vertex: vi,
                        value: m,
                        limit: MAX_COORD,
                    });
                }
            }
            // Canonical zero: -0.0 and 0.0 compare equal but order differently bitwise.
            let cleaned = clean_ring(ring.into_iter().map(|p| p + DVec2::ZERO).collect());
            if cleaned.len() < 3 {
                return Err(GeomError::TooFewVertices {
                    ring: ri,
                    count: cleaned.len(),
                });
            }
            rings.push(cleaned);
        }
        check_crossings(&rings)?;
        let depths = nesting_depths(&rings);
        let contours: Vec<Contour> = rings
            .into_iter()
            .zip(depths)
            .map(|(mut pts, depth)| {
                let ccw = super::predicates::signed_area2(&pts) > 0.0;
                if ccw != (depth % 2 == 0) {
                    pts.reverse();
                }
                Contour { pts }
            })
            .collect();
        let facts = Facts::all(&contours);
        Ok(Shape { contours, facts })
    }

    /// Whether the shape has no contours (and so no area).
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.contours.is_empty()
    }

    /// The contours as point slices: outer contours counter-clockwise, holes clockwise, no
    /// repeated closing point.
    pub fn contours(&self) -> impl Iterator<Item = &[DVec2]> {
        self.contours.iter().map(|c| c.pts.as_slice())
    }

    /// The contours as [`Contour`] values.
    #[must_use]
    pub fn contour_list(&self) -> &[Contour] {
        &self.contours
    }

    /// Total number of vertices over all contours.
    #[must_use]
    pub fn vertex_count(&self) -> usize {
        self.contours.iter().map(|c| c.pts.len()).sum()
    }

    /// The enclosed area (outer areas minus hole areas), never negative.
    #[must_use]
    pub fn area(&self) -> f64 {
        self.contours
            .iter()
            .map(Contour::signed_area)
            .sum::<f64>()
            .max(0.0)
    }

    /// Largest coordinate magnitude over all points (0 for the empty shape): the scale that the
    /// layer's relative tolerances refer to.
    #[must_use]
    pub fn scale(&self) -> f64 {
        self.contours
            .iter()
            .flat_map(|c| c.pts.iter())
            .fold(0.0, |m: f64, p| m.max(p.x.abs()).max(p.y.abs()))
    }

    /// Checks every invariant that [`Shape::new`] establishes and that every result of
    /// [`boolean`](super::boolean) must keep: finite coordinates, at least three points per
    /// contour, no repeated or collinear consecutive points, no crossing or overlapping contours,
    /// and orientation matching nesting depth (outer counter-clockwise, holes clockwise).
    ///
    /// This is the one invariant checker shared by unit tests, property tests and fuzz targets. It
    /// costs `O(n^2)` in the number of edges.
    ///
    /// # Errors
    ///
    /// The first violated invariant, as the error [`Shape::new`] would report for it, or
    /// [`GeomError::Degenerate`] for a duplicate/collinear point or a wrong orientation.
    pub fn validate(&self) -> Result<(), GeomError> {
        let mut rings: Vec<Vec<DVec2>> = Vec::with_capacity(self.contours.len());
        for (ri, c) in self.contours.iter().enumerate() {
            let pts = &c.pts;
            let n = pts.len();
            if n < 3 {
                return Err(GeomError::TooFewVertices { ring: ri, count: n });
            }
            for (vi, p) in pts.iter().enumerate() {
                if !p.x.is_finite() || !p.y.is_finite() {
                    return Err(GeomError::NonFinite {
                        ring: ri,
                        vertex: vi,
                    });
                }
            }
            for i in 0..n {
                let a = pts[(i + n - 1) % n];
                let b = pts[i];
                let c2 = pts[(i + 1) % n];
                if a == b {
                    return Err(GeomError::CoincidentVertices {
                        ring: ri,
                        vertex: (i + n - 1) % n,
                    });
                }
                if orient(a, b, c2) == 0.0 {
                    return Err(GeomError::Degenerate(
                        "a contour has three collinear consecutive points (or a spike)",
                    ));
                }
            }
            rings.push(pts.clone());
        }
        check_crossings(&rings)?;
        let depths = nesting_depths(&rings);
        for (r, d) in rings.iter().zip(depths) {
            let ccw = super::predicates::signed_area2(r) > 0.0;
            if ccw != (d % 2 == 0) {
                return Err(GeomError::Degenerate(
                    "contour orientation does not match its nesting depth \
                     (outer contours must be counter-clockwise, holes clockwise)",
                ));
            }
        }
        Ok(())
    }

    /// Whether every feature of the shape is wider than `snap`: no two vertices within it of
    /// each other and no vertex within it of an edge it is not on ([`has_near_self_contacts`]).
    pub(crate) fn is_clear_at(&self, snap: f64) -> bool {
        let sep2 = self
            .facts
            .sep2
            .unwrap_or_else(|| min_separation2(&self.contours));
        sep2 > snap * snap && !has_near_self_contacts(&self.contours, snap)
    }

    /// Wraps contours produced by the boolean pipeline, which establishes the invariants itself.
    pub(crate) fn from_contours(contours: Vec<Contour>) -> Shape {
        let facts = Facts::bbox(&contours);
        Shape { contours, facts }
    }
}

/// Drops a repeated closing point, consecutive duplicates and exactly collinear middle points
/// (spikes included), until none is left.
pub(crate) fn clean_ring(mut pts: Vec<DVec2>) -> Vec<DVec2> {
    // Each pass removes at least one point or stops, so the loop is bounded by the length.
    loop {
        let n = pts.len();
        if n < 3 {
            pts.dedup();
            return pts;
        }
        let mut out: Vec<DVec2> = Vec::with_capacity(n);
        let mut changed = false;
        for i in 0..n {
            let b = pts[i];
            let a = match out.last() {
                Some(&l) => l,
                None => pts[n - 1],
            };
            // The last point's successor is the first point kept, not the first point given
            // (a repeated closing point has just dropped that one).
            let c = match (i + 1 == n, out.first()) {
                (true, Some(&f)) => f,
                _ => pts[(i + 1) % n],
            };
            if b == a || b == c || orient(a, b, c) == 0.0 {
                changed = true;
                continue;
            }
            out.push(b);
        }
        // The first kept point was judged against the original last point, which may since have
        // been removed; the next pass re-examines it.
        if !changed {
            return out;
        }
        pts = out;
    }
}

/// Rejects rings that cross or overlap themselves or each other; isolated touching points
/// between different rings are allowed.
pub(crate) fn check_crossings(rings: &[Vec<DVec2>]) -> Result<(), GeomError> {
    for (ri, r) in rings.iter().enumerate() {
        let n = r.len();
        // Within one ring: non-adjacent edges must not meet at all.
        for i in 0..n {
            let (a, b) = (r[i], r[(i + 1) % n]);
            for j in i + 2..n {
                if i == 0 && j == n - 1 {
                    continue;
                }
                let (c, d) = (r[j], r[(j + 1) % n]);
                if segments_touch(a, b, c, d) {
                    return Err(GeomError::SelfIntersecting {
                        ring: ri,
                        other_ring: ri,
                    });
                }
            }
        }
        for (si, s) in rings.iter().enumerate().skip(ri + 1) {
            if rings_cross(r, s) {
                return Err(GeomError::SelfIntersecting {
                    ring: ri,
                    other_ring: si,
                });
            }
        }
    }
    Ok(())
}

/// Whether two simple rings cross or share a stretch of boundary.
///
/// Proper edge crossings and collinear overlaps are detected exactly. A crossing through a shared
/// point (a vertex of one ring on the other ring) leaves no proper edge crossing, so in addition
/// every vertex and edge midpoint of one ring that is off the other ring must lie on the same
/// side of it.
fn rings_cross(r: &[DVec2], s: &[DVec2]) -> bool {
    let (n, m) = (r.len(), s.len());
    for i in 0..n {
        let (a, b) = (r[i], r[(i + 1) % n]);
        for j in 0..m {
            let (c, d) = (s[j], s[(j + 1) % m]);
            if !segments_touch(a, b, c, d) {
                continue;
            }
            let o1 = orient_sign(a, b, c);
            let o2 = orient_sign(a, b, d);
            let o3 = orient_sign(c, d, a);
            let o4 = orient_sign(c, d, b);
            if o1 * o2 < 0 && o3 * o4 < 0 {
                return true;
            }
            if o1 == 0 && o2 == 0 {
                // Collinear and touching: an overlap unless they meet in a single endpoint.
                if strictly_between(a, b, c)
                    || strictly_between(a, b, d)
                    || strictly_between(c, d, a)
                    || strictly_between(c, d, b)
                    || (a == c && b == d)
                    || (a == d && b == c)
                {
                    return true;
                }
            }
        }
    }
    !one_side(r, s) || !one_side(s, r)
}

/// Whether all vertices and edge midpoints of `r` that are off ring `s` lie on one side of it.
fn one_side(r: &[DVec2], s: &[DVec2]) -> bool {
    let n = r.len();
    let mut side: Option<bool> = None;
    for i in 0..2 * n {
        let p = if i % 2 == 0 {
            r[i / 2]
        } else {
            (r[i / 2] + r[(i / 2 + 1) % n]) * 0.5
        };
        if on_ring(s, p) {
            continue;
        }
        let inside = winding(s, p) != 0;
        match side {
            None => side = Some(inside),
            Some(prev) if prev != inside => return false,
            Some(_) => {}
        }
    }
    true
}

/// Whether `p` lies exactly on the ring.
fn on_ring(s: &[DVec2], p: DVec2) -> bool {
    let m = s.len();
    (0..m).any(|j| on_segment(s[j], s[(j + 1) % m], p))
}

/// For each ring, how many other rings contain it.
fn nesting_depths(rings: &[Vec<DVec2>]) -> Vec<usize> {
    rings
        .iter()
        .enumerate()
        .map(|(i, r)| {
            rings
                .iter()
                .enumerate()
                .filter(|&(j, s)| j != i && ring_inside(r, s))
                .count()
        })
        .collect()
}

/// Whether ring `r` lies inside ring `s` (rings known not to cross).
pub(crate) fn ring_inside(r: &[DVec2], s: &[DVec2]) -> bool {
    let n = r.len();
    // A vertex off `s` decides; if all vertices touch `s`, an edge midpoint does (an edge with
    // both ends on `s` and not overlapping it runs strictly inside or outside).
    for i in 0..2 * n {
        let p = if i < n {
            r[i]
        } else {
            (r[i - n] + r[(i - n + 1) % n]) * 0.5
        };
        if !on_ring(s, p) {
            return winding(s, p) != 0;
        }
    }
    false
}
