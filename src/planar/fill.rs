//! Ring soup to [`Shape`]: the region a set of arbitrary rings encloses under a fill rule.
//!
//! Users hold polygons as they come out of other tools: rings that cross themselves (bow-ties,
//! stars), rings of one multipolygon that overlap or share edges, holes that cross their outer
//! ring, repeated and collinear points, rings with no area. A fill rule says which points such a
//! set encloses, by their winding number: the number of times the rings wind around the point,
//! counter-clockwise turns counted positive (the convention of the PostScript/SVG fill rules).
//!
//! [`Shape::with_fill_rule`] computes that region as a valid [`Shape`] with the machinery of the
//! boolean operations (see `boolean/`), run on one edge set instead of two:
//!
//! 1. vertices closer than the snapping distance ([`SNAP_REL`](super::SNAP_REL) of the coordinate
//!    scale) are welded, and all edges are split at all their contacts, within a ring and across
//!    rings, with exact `orient2d` decisions, to the fixpoint at which any two edges meet only in
//!    shared endpoints or coincide;
//! 2. coinciding edges are merged into *segments* with a net multiplicity (how many more times
//!    the rings run along it one way than the other); the winding number jumps by exactly that
//!    multiplicity across the segment, left side minus right side;
//! 3. winding numbers of the faces are propagated exactly, around each node through its segments
//!    sorted by angle (exact comparisons) and along each segment to its other node; each
//!    connected part of the arrangement starts at its lowest-leftmost node, whose outer wedge has
//!    the winding of a ray cast from it to the left (exact, half-open crossing rule);
//! 4. a segment bounds the result when the rule keeps the face on one side and not on the other;
//!    it is directed with the kept face on its left and the directed segments are linked into
//!    contours by the boolean operations' tracing phase (leftmost turn, loops cut at repeated
//!    nodes, collinear points removed, slivers thinner than [`SLIVER_REL`](super::SLIVER_REL)
//!    dropped).
//!
//! Small input that needs none of this (simple rings that neither cross nor overlap, touching at
//! most at points, none a sliver, no two vertices within the snapping distance) takes a check
//! instead: the checks of [`Shape::new`], the nesting of the rings, and the winding number of
//! each ring's two sides from the orientations of the rings containing it.
//!
//! # References
//!
//! - The winding-number fill rules: Adobe, *PostScript Language Reference*, 3rd ed., section
//!   4.5.2 (non-zero winding number and even-odd rules); W3C, *SVG 1.1*, section 11.3
//!   (`fill-rule`).
//! - Splitting and tracing: Greiner and Hormann (1998) and Foster, Hormann and Popa (2019), as in
//!   [`boolean`](super::boolean).
//! - GeoJSON polygon roles: RFC 7946, section 3.1.6.

use alloc::vec::Vec;
use glam::DVec2;
use smallvec::SmallVec;

use super::SNAP_REL;
use super::boolean::Rings;
use super::boolean::intersect::{sort_key, split_within, weld};
use super::boolean::label::Nodes;
use super::boolean::trace::{Edge, Edges, survives, trace};
use super::contour::Contour;
use super::predicates::{MAX_COORD, orient, signed_area2};
use super::shape::{Facts, Shape, check_crossings, clean_ring, min_separation2, ring_inside};
use crate::GeomError;

/// Which points a set of rings encloses, by their winding number `w` (counter-clockwise turns
/// positive).
///
/// For one simple counter-clockwise ring all four rules give its interior; they differ on rings
/// that wind more than once around a point, cross themselves or run clockwise.
///
/// # Examples
///
/// ```
/// use arealight::glam::DVec2;
/// use arealight::planar::{FillRule, Shape};
///
/// // Two overlapping squares, both counter-clockwise: winding 2 where they overlap.
/// let square = |x: f64| {
///     vec![
///         DVec2::new(x, 0.0),
///         DVec2::new(x + 2.0, 0.0),
///         DVec2::new(x + 2.0, 2.0),
///         DVec2::new(x, 2.0),
///     ]
/// };
/// let rings = vec![square(0.0), square(1.0)];
/// let union = Shape::with_fill_rule(rings.clone(), FillRule::NonZero)?;
/// assert_eq!(union.area(), 6.0);
/// let xor = Shape::with_fill_rule(rings, FillRule::EvenOdd)?;
/// assert_eq!(xor.area(), 4.0);
/// # Ok::<(), arealight::GeomError>(())
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum FillRule {
    /// `w` odd: every ring toggles inside and outside, whatever its orientation.
    EvenOdd,
    /// `w != 0`: the union of everything any ring winds around.
    NonZero,
    /// `w > 0`: counter-clockwise rings add, clockwise rings subtract.
    Positive,
    /// `w < 0`: clockwise rings add, counter-clockwise rings subtract.
    Negative,
}

impl FillRule {
    /// Whether a point of winding number `w` is inside.
    #[inline]
    #[must_use]
    pub fn contains(self, w: i64) -> bool {
        match self {
            FillRule::EvenOdd => w % 2 != 0,
            FillRule::NonZero => w != 0,
            FillRule::Positive => w > 0,
            FillRule::Negative => w < 0,
        }
    }
}

/// Rejects NaN, infinite and out-of-range coordinates, naming the ring and vertex (indices
/// counted from `ring0` for the ring).
fn check_coordinates(rings: &[Vec<DVec2>], ring0: usize) -> Result<(), GeomError> {
    for (ri, ring) in rings.iter().enumerate() {
        for (vi, p) in ring.iter().enumerate() {
            if !p.x.is_finite() || !p.y.is_finite() {
                return Err(GeomError::NonFinite {
                    ring: ring0 + ri,
                    vertex: vi,
                });
            }
            let m = p.x.abs().max(p.y.abs());
            if m > MAX_COORD {
                return Err(GeomError::CoordinateOutOfRange {
                    ring: ring0 + ri,
                    vertex: vi,
                    value: m,
                    limit: MAX_COORD,
                });
            }
        }
    }
    Ok(())
}

impl Shape {
    /// The region that arbitrary rings enclose under a fill rule, as a valid shape.
    ///
    /// Any ring soup is accepted: rings that cross or touch themselves or each other, overlap
    /// along edges, repeat points, carry collinear points or bound no area, in any orientation,
    /// with or without a repeated closing point. A point is in the result when `rule` holds for
    /// its winding number with respect to all rings. The result is regularized like the result of
    /// a boolean operation (no zero-area parts, no spikes, no repeated or collinear consecutive
    /// points; loops thinner than [`SLIVER_REL`](super::SLIVER_REL) of the coordinate scale are
    /// dropped, vertices closer than [`SNAP_REL`](super::SNAP_REL) of it are welded), passes
    /// [`Shape::validate`] and is a valid operand of every operation. Rings of fewer than three
    /// distinct points, or of zero area, contribute nothing; no rings give the empty shape.
    ///
    /// Unlike [`Shape::new`], orientation carries meaning here: a clockwise ring winds `-1`
    /// around its interior (under [`FillRule::EvenOdd`] and [`FillRule::NonZero`] that makes no
    /// difference for rings that do not overlap).
    ///
    /// Input of up to 128 vertices that is already valid — simple rings that neither cross nor
    /// overlap, touching at most at points, none a sliver — costs one check like
    /// [`Shape::new`]'s (`O(n^2)` in the number of vertices); anything else is resolved as the
    /// module documentation describes (`O((n + k) log(n + k))` plus the pairs of edges whose
    /// x-ranges overlap, for `k` contacts).
    ///
    /// # Examples
    ///
    /// ```
    /// use arealight::glam::DVec2;
    /// use arealight::planar::{FillRule, Shape};
    ///
    /// // A bow-tie: two triangles meeting where the ring crosses itself at (1, 1).
    /// let bow_tie = vec![vec![
    ///     DVec2::new(0.0, 0.0),
    ///     DVec2::new(2.0, 2.0),
    ///     DVec2::new(2.0, 0.0),
    ///     DVec2::new(0.0, 2.0),
    /// ]];
    /// let s = Shape::with_fill_rule(bow_tie.clone(), FillRule::NonZero)?;
    /// assert_eq!(s.area(), 2.0);
    /// assert_eq!(s.contours().count(), 2);
    /// s.validate()?;
    /// // The left triangle runs counter-clockwise, the right one clockwise.
    /// let left = Shape::with_fill_rule(bow_tie, FillRule::Positive)?;
    /// assert_eq!(left.area(), 1.0);
    /// assert!(left.contours().flatten().all(|p| p.x <= 1.0));
    /// # Ok::<(), arealight::GeomError>(())
    /// ```
    ///
    /// # Errors
    ///
    /// - [`GeomError::NonFinite`] for a NaN or infinite coordinate, with its ring and vertex;
    /// - [`GeomError::CoordinateOutOfRange`] for a coordinate of magnitude above
    ///   [`MAX_COORD`](super::MAX_COORD), with its ring and vertex;
    /// - [`GeomError::Undecidable`] when `f64` cannot resolve the
    ///   arrangement consistently (splitting does not settle, or the exact winding numbers
    ///   contradict each other), as for [`boolean`](super::boolean); never for well-separated or
    ///   exactly degenerate input such as shared edges and vertices.
    pub fn with_fill_rule(contours: Vec<Vec<DVec2>>, rule: FillRule) -> Result<Shape, GeomError> {
        Shape::fill(contours, rule, true, 0.0)
    }

    /// [`Shape::with_fill_rule`] without first checking whether small input is already simple:
    /// for callers whose rings usually cross or overlap (a union of many overlapping pieces),
    /// where that quadratic check is spent for nothing. Same result.
    pub(crate) fn with_fill_rule_resolving(
        contours: Vec<Vec<DVec2>>,
        rule: FillRule,
    ) -> Result<Shape, GeomError> {
        Shape::fill(contours, rule, false, 0.0)
    }

    /// [`Shape::with_fill_rule_resolving`] at a coordinate scale of at least `min_scale` (as
    /// [`boolean_at_scale`](super::boolean::boolean_at_scale)): vertices within
    /// [`SNAP_REL`]` * min_scale` of each other are welded and of edges put on them (a ring
    /// passing that close to its own vertex touches itself there), loops thinner than
    /// [`SLIVER_REL`](super::SLIVER_REL)` * min_scale` dropped.
    pub(crate) fn with_fill_rule_resolving_at_scale(
        contours: Vec<Vec<DVec2>>,
        rule: FillRule,
        min_scale: f64,
    ) -> Result<Shape, GeomError> {
        Shape::fill(contours, rule, false, min_scale)
    }

    fn fill(
        contours: Vec<Vec<DVec2>>,
        rule: FillRule,
        try_simple: bool,
        min_scale: f64,
    ) -> Result<Shape, GeomError> {
        check_coordinates(&contours, 0)?;
        let mut rings: Vec<Vec<DVec2>> = Vec::with_capacity(contours.len());
        for ring in contours {
            // Canonical zero: -0.0 and 0.0 compare equal but hash and order differently.
            let cleaned = clean_ring(ring.into_iter().map(|p| p + DVec2::ZERO).collect());
            // Fewer than three points after dropping repeats and collinear points: the ring runs
            // forth and back along a line and winds around nothing.
            if cleaned.len() >= 3 {
                rings.push(cleaned);
            }
        }
        if rings.is_empty() {
            return Ok(Shape::empty());
        }
        let scale = rings
            .iter()
            .flatten()
            .fold(min_scale, |m, p| m.max(p.x.abs()).max(p.y.abs()));
        let n: usize = rings.iter().map(Vec::len).sum();
        if try_simple
            && n <= SIMPLE_MAX
            && let Some(s) = simple_rings(&rings, rule, scale)
        {
            return Ok(s);
        }
        resolve(rings, rule, scale)
    }

    /// A GeoJSON-style polygon: the first ring is the exterior, the others are holes, each in any
    /// orientation (RFC 7946, section 3.1.6).
    ///
    /// The region is the exterior's interior minus the union of the holes' interiors, where each
    /// ring's interior is what it winds around ([`FillRule::NonZero`] on that ring alone, so a
    /// self-intersecting or self-overlapping ring encloses everything it goes around). Roles, not
    /// orientations, decide: a hole given counter-clockwise is still a hole, a hole reaching
    /// outside the exterior removes only what lies inside it, a hole entirely outside removes
    /// nothing, and overlapping holes remove their union. No rings give the empty shape. The
    /// result is valid and regularized as for [`Shape::with_fill_rule`].
    ///
    /// # Examples
    ///
    /// ```
    /// use arealight::glam::DVec2;
    /// use arealight::planar::Shape;
    ///
    /// let sq = |x: f64, y: f64, s: f64| {
    ///     vec![
    ///         DVec2::new(x, y),
    ///         DVec2::new(x + s, y),
    ///         DVec2::new(x + s, y + s),
    ///         DVec2::new(x, y + s),
    ///     ]
    /// };
    /// // A 4x4 exterior; one hole inside, one straddling the boundary, one outside.
    /// let p = Shape::from_polygon_rings(vec![
    ///     sq(0.0, 0.0, 4.0),
    ///     sq(1.0, 1.0, 1.0),
    ///     sq(3.0, 3.0, 2.0),
    ///     sq(9.0, 9.0, 1.0),
    /// ])?;
    /// assert_eq!(p.area(), 16.0 - 1.0 - 1.0);
    /// # Ok::<(), arealight::GeomError>(())
    /// ```
    ///
    /// # Errors
    ///
    /// As [`Shape::with_fill_rule`]; ring indices count the polygon's rings in order.
    pub fn from_polygon_rings(rings: Vec<Vec<DVec2>>) -> Result<Shape, GeomError> {
        check_coordinates(&rings, 0)?;
        polygon(rings)
    }

    /// A GeoJSON-style multipolygon: the union of polygons, each given as by
    /// [`Shape::from_polygon_rings`] (first ring exterior, others holes, any orientation).
    ///
    /// Polygons may overlap, touch or share edges; the result is the union of their regions,
    /// valid and regularized as for [`Shape::with_fill_rule`].
    ///
    /// # Errors
    ///
    /// As [`Shape::with_fill_rule`]; ring indices count the rings of all polygons in order
    /// (the first ring of the second polygon has the index after the last ring of the first).
    pub fn from_multipolygon(polygons: Vec<Vec<Vec<DVec2>>>) -> Result<Shape, GeomError> {
        let mut ring0 = 0;
        for p in &polygons {
            check_coordinates(p, ring0)?;
            ring0 += p.len();
        }
        let mut parts: Vec<Shape> = Vec::with_capacity(polygons.len());
        for p in polygons {
            let s = polygon(p)?;
            if !s.is_empty() {
                parts.push(s);
            }
        }
        if parts.len() <= 1 {
            return Ok(parts.pop().unwrap_or_default());
        }
        // Each part winds exactly once around its region (outer contours counter-clockwise,
        // holes clockwise), so the sum of windings is positive exactly on the union.
        let all: Vec<Vec<DVec2>> = parts
            .into_iter()
            .flat_map(|s| s.contours.into_iter().map(|c| c.pts))
            .collect();
        Shape::with_fill_rule(all, FillRule::Positive)
    }
}

/// One GeoJSON polygon (coordinates already checked).
fn polygon(mut rings: Vec<Vec<DVec2>>) -> Result<Shape, GeomError> {
    if rings.is_empty() {
        return Ok(Shape::empty());
    }
    let holes = rings.split_off(1);
    let exterior = Shape::with_fill_rule(rings, FillRule::NonZero)?;
    if holes.is_empty() || exterior.is_empty() {
        return Ok(exterior);
    }
    // Exterior winding +1 inside; each hole, resolved on its own and reversed, -1 inside it. So
    // the sum is positive exactly inside the exterior and outside every hole.
    let mut all: Vec<Vec<DVec2>> = exterior.contours.into_iter().map(|c| c.pts).collect();
    for h in holes {
        let h = Shape::with_fill_rule(alloc::vec![h], FillRule::NonZero)?;
        all.extend(h.contours.into_iter().map(|c| {
            let mut pts = c.pts;
            pts.reverse();
            pts
        }));
    }
    Shape::with_fill_rule(all, FillRule::Positive)
}

/// The check for input that needs no resolving: rings that are simple, neither cross nor
/// overlap each other (touching at most at points), are no slivers and have no two vertices
/// within the snapping distance. Then each ring separates two faces whose winding numbers are
/// the sum of the orientations of the rings containing it, with and without its own; the ring
/// bounds the result when the rule keeps one face and not the other, directed with the kept face
/// on its left. `None` when the rings need resolving.
///
/// The kept rings form a valid shape: along any path from far away, the rule's verdict toggles
/// exactly when the path crosses a kept ring (the winding on either side of a ring is the same
/// all along it, since other rings touch it only at points), so a point is kept iff an odd
/// number of kept rings contain it, which is the nesting parity that [`Shape::validate`]
/// requires of orientations.
fn simple_rings(rings: &[Vec<DVec2>], rule: FillRule, scale: f64) -> Option<Shape> {
    // Vertices within the snapping distance would be welded, and slivers dropped, by the
    // resolving path and by every operation on the shape.
    let snap = SNAP_REL * scale;
    if !rings.iter().all(|r| survives(r, scale)) || check_crossings(rings).is_err() {
        return None;
    }
    let contours: Vec<Contour> = rings.iter().map(|r| Contour { pts: r.clone() }).collect();
    let sep2 = min_separation2(&contours);
    if sep2 <= snap * snap {
        return None;
    }
    let turns: SmallVec<[i64; 8]> = rings
        .iter()
        .map(|r| if signed_area2(r) > 0.0 { 1 } else { -1 })
        .collect();
    let mut kept: Vec<Contour> = Vec::with_capacity(rings.len());
    for (i, (r, c)) in rings.iter().zip(contours).enumerate() {
        let around: i64 = rings
            .iter()
            .enumerate()
            .filter(|&(j, s)| j != i && ring_inside(r, s))
            .map(|(j, _)| turns[j])
            .sum();
        let inside = rule.contains(around + turns[i]);
        let outside = rule.contains(around);
        if inside == outside {
            continue;
        }
        let mut c = c;
        if (turns[i] > 0) != inside {
            c.pts.reverse();
        }
        kept.push(c);
    }
    let facts = if kept.len() == rings.len() {
        Facts::with_separation(&kept, sep2)
    } else {
        Facts::all(&kept)
    };
    Some(Shape {
        contours: kept,
        facts,
    })
}

/// Up to this many vertices in all, input is first checked for needing no resolving; the check
/// is quadratic (all edge pairs, as in [`Shape::new`]), and above this size resolving, which
/// sweeps over x, is cheaper even for valid input (measured on the simple stars of
/// `benches/planar.rs`, in one window of the shared machine: 1.6 against 3.4 ms at 1024
/// vertices, 0.17 against 0.24-0.44 ms at 256, 27-57 against 18-30 us at 64).
const SIMPLE_MAX: usize = 128;

/// Marks a half-edge whose right-hand winding number is not known yet.
const UNKNOWN: i64 = i64::MIN;

/// The resolving path of [`Shape::with_fill_rule`] (steps 1-4 of the module documentation).
fn resolve(rings: Vec<Vec<DVec2>>, rule: FillRule, scale: f64) -> Result<Shape, GeomError> {
    let mut soup = Rings::default();
    for r in &rings {
        soup.pts.extend(r.iter().copied());
        soup.ends.push(soup.pts.len() as u32);
    }
    drop(rings);
    // Step 1: weld, then split to the fixpoint (welding as it goes).
    let mut none = Rings::default();
    weld(&mut soup, &mut none, scale);
    split_within(&mut soup, scale)?;

    // Step 2: segments between nodes (groups of identical points) with net multiplicities.
    let nodes = Nodes::new(&soup, &none);
    let nxt = soup.next_table();
    let mut segs: Vec<(u32, u32, i64)> = Vec::with_capacity(soup.pts.len());
    for (i, &n) in nxt.iter().enumerate() {
        let (u, v) = (nodes.of(i, false), nodes.of(n as usize, false));
        match u.cmp(&v) {
            core::cmp::Ordering::Less => segs.push((u, v, 1)),
            core::cmp::Ordering::Greater => segs.push((v, u, -1)),
            core::cmp::Ordering::Equal => {}
        }
    }
    segs.sort_unstable_by_key(|s| (s.0, s.1));
    let mut merged: Vec<(u32, u32, i64)> = Vec::with_capacity(segs.len());
    for s in segs {
        match merged.last_mut() {
            Some(l) if l.0 == s.0 && l.1 == s.1 => l.2 += s.2,
            _ => merged.push(s),
        }
    }
    // Segments the rings run along equally often both ways separate faces of equal winding.
    merged.retain(|s| s.2 != 0);
    let segs = merged;
    if segs.is_empty() {
        return Ok(Shape::empty());
    }
    let pts: &[DVec2] = &soup.pts;
    let node_count = pts.len();

    // Half-edge `2k` runs along segment `k` from its first node to its second, `2k + 1` back.
    let from = |h: usize| -> u32 {
        let s = segs[h / 2];
        if h & 1 == 0 { s.0 } else { s.1 }
    };
    let to = |h: usize| -> u32 {
        let s = segs[h / 2];
        if h & 1 == 0 { s.1 } else { s.0 }
    };
    // The winding number on the left of half-edge `h` minus that on its right.
    let jump = |h: usize| -> i64 {
        let m = segs[h / 2].2;
        if h & 1 == 0 { m } else { -m }
    };
    // Step 3a: the half-edges leaving each node, in counter-clockwise order of direction starting
    // just after the direction (-1, 0).
    let mut first: Vec<u32> = alloc::vec![0; node_count + 1];
    for s in &segs {
        first[s.0 as usize + 1] += 1;
        first[s.1 as usize + 1] += 1;
    }
    for k in 1..first.len() {
        first[k] += first[k - 1];
    }
    let mut fill = first.clone();
    let mut out: Vec<u32> = alloc::vec![0; 2 * segs.len()];
    for h in 0..2 * segs.len() {
        let slot = &mut fill[from(h) as usize];
        out[*slot as usize] = h as u32;
        *slot += 1;
    }
    let mut overlap = false;
    for v in 0..node_count {
        let (lo, hi) = (first[v] as usize, first[v + 1] as usize);
        if hi - lo < 2 {
            continue;
        }
        let p = pts[v];
        out[lo..hi].sort_unstable_by(|&g, &h| {
            let (a, b) = (pts[to(g as usize) as usize], pts[to(h as usize) as usize]);
            let c = angle_cmp(p, a, b);
            if c == core::cmp::Ordering::Equal {
                overlap = true;
            }
            c
        });
    }
    if overlap {
        return Err(GeomError::Undecidable(
            "two split edges leave a vertex in the same direction; the rings overlap within \
             rounding",
        ));
    }
    // Position of each half-edge in its node's sorted list.
    let mut pos: Vec<u32> = alloc::vec![0; out.len()];
    for v in 0..node_count {
        for k in first[v]..first[v + 1] {
            pos[out[k as usize] as usize] = k;
        }
    }

    // Step 3b: winding numbers to the right of every half-edge, one connected part at a time,
    // each started at its lowest-leftmost node.
    let mut order: Vec<u32> = (0..node_count as u32)
        .filter(|&v| first[v as usize + 1] > first[v as usize])
        .collect();
    order.sort_unstable_by_key(|&v| (sort_key(pts[v as usize].x), sort_key(pts[v as usize].y)));
    let mut right: Vec<i64> = alloc::vec![UNKNOWN; out.len()];
    let mut queue: Vec<u32> = Vec::new();
    let inconsistent = GeomError::Undecidable(
        "winding numbers of the split rings contradict each other; the rings are too close to \
         degenerate for f64",
    );
    // Each part's start costs a pass over the segments; many parts (a multipolygon of
    // thousands of separate rings) use an index of the segments by rows of y instead.
    let mut parts = 0usize;
    let mut rows: Option<Rows> = None;
    for &v0 in &order {
        let h0 = out[first[v0 as usize] as usize] as usize;
        if right[h0] != UNKNOWN {
            continue;
        }
        // All of this part lies at x >= x0 (and above the node where x = x0), so the wedge
        // containing the direction (-1, 0) at `v0` is the one right of its first half-edge, and
        // a ray from `v0` to the left meets only other parts.
        parts += 1;
        if parts == ROWS_AFTER {
            rows = Some(Rows::new(pts, &segs));
        }
        let p0 = pts[v0 as usize];
        right[h0] = match &rows {
            Some(rows) => winding_left_of(pts, rows.near(&segs, p0), p0),
            None => winding_left_of(pts, segs.iter().copied(), p0),
        };
        queue.clear();
        queue.push(h0 as u32);
        while let Some(h) = queue.pop() {
            // `h` leaves node `v` with a known winding on its right: go once around `v`.
            let v = from(h as usize) as usize;
            let (lo, hi) = (first[v] as usize, first[v + 1] as usize);
            let n = hi - lo;
            let start = pos[h as usize] as usize - lo;
            let mut w = right[h as usize];
            for step in 0..n {
                let g = out[lo + (start + step) % n] as usize;
                if step > 0 {
                    if right[g] == UNKNOWN {
                        right[g] = w;
                    } else if right[g] != w {
                        return Err(inconsistent);
                    }
                }
                // The wedge after `g` (counter-clockwise) is on its left.
                w += jump(g);
                // The twin runs the other way: its right is `g`'s left.
                let t = g ^ 1;
                if right[t] == UNKNOWN {
                    right[t] = w;
                    queue.push(t as u32);
                } else if right[t] != w {
                    return Err(inconsistent);
                }
            }
            if w != right[h as usize] {
                return Err(inconsistent);
            }
        }
    }

    // Step 4: the segments between a kept and a dropped face, kept face on the left.
    let mut edges = Edges::new();
    for (k, s) in segs.iter().enumerate() {
        let r = right[2 * k];
        let (keep_left, keep_right) = (rule.contains(r + s.2), rule.contains(r));
        let (a, b) = (s.0, s.1);
        if keep_left && !keep_right {
            edges.push(Edge::new(a, b, pts[a as usize], pts[b as usize]));
        } else if keep_right && !keep_left {
            edges.push(Edge::new(b, a, pts[b as usize], pts[a as usize]));
        }
    }
    let contours = trace(&edges, node_count, scale)?;
    let facts = if contours.iter().map(|c| c.pts.len()).sum::<usize>() <= FACTS_MAX {
        Facts::all(&contours)
    } else {
        Facts::bbox(&contours)
    };
    Ok(Shape { contours, facts })
}

/// Up to this many vertices, a resolved shape gets all the facts [`Shape::new`] caches (their
/// check for vertices on other contours is quadratic); larger ones only the bounding box, and
/// the boolean operations compute the rest when they need it, as for their own results.
const FACTS_MAX: usize = 256;

/// Exact counter-clockwise order of the directions `a - p` and `b - p`, starting just after the
/// direction (-1, 0): directions with angle in `(-pi, 0]` first, then `(0, pi]`; `Equal` only
/// for the same direction.
fn angle_cmp(p: DVec2, a: DVec2, b: DVec2) -> core::cmp::Ordering {
    // The sign of a difference of two floats is exact.
    let upper = |q: DVec2| {
        let (dx, dy) = (q.x - p.x, q.y - p.y);
        dy > 0.0 || (dy == 0.0 && dx < 0.0)
    };
    match (upper(a), upper(b)) {
        (false, true) => core::cmp::Ordering::Less,
        (true, false) => core::cmp::Ordering::Greater,
        _ => {
            let o = orient(p, a, b);
            if o > 0.0 {
                core::cmp::Ordering::Less
            } else if o < 0.0 {
                core::cmp::Ordering::Greater
            } else {
                core::cmp::Ordering::Equal
            }
        }
    }
}

/// From this many connected parts on, their starting windings are counted through [`Rows`].
const ROWS_AFTER: usize = 8;

/// Segments by horizontal bands: band `k` lists every segment whose y-range meets it, so the
/// segments that can cross the horizontal line through a point are among those of the point's
/// band. Bands come from a monotone map of y, so a segment whose y-range contains `p.y` is
/// always listed in `p`'s band; segments spanning many bands are kept in one list for all.
struct Rows {
    lo: f64,
    k: f64,
    count: usize,
    first: Vec<u32>,
    members: Vec<u32>,
    tall: Vec<u32>,
}

impl Rows {
    fn new(pts: &[DVec2], segs: &[(u32, u32, i64)]) -> Rows {
        let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
        for &(u, v, _) in segs {
            for y in [pts[u as usize].y, pts[v as usize].y] {
                lo = lo.min(y);
                hi = hi.max(y);
            }
        }
        let count = (crate::math::sqrt(segs.len() as f64) as usize).max(1);
        let k = if hi > lo {
            count as f64 / (hi - lo)
        } else {
            0.0
        };
        let band = |y: f64| (((y - lo) * k) as usize).min(count - 1);
        let span = |s: &(u32, u32, i64)| {
            let (a, b) = (pts[s.0 as usize].y, pts[s.1 as usize].y);
            (band(a.min(b)), band(a.max(b)))
        };
        // Segments spanning a quarter of the bands or more are checked for every point.
        let tall_bands = (count / 4).max(2);
        let mut first: Vec<u32> = alloc::vec![0; count + 1];
        let mut tall = Vec::new();
        for (i, s) in segs.iter().enumerate() {
            let (b0, b1) = span(s);
            if b1 - b0 >= tall_bands {
                tall.push(i as u32);
                continue;
            }
            for b in b0..=b1 {
                first[b + 1] += 1;
            }
        }
        for b in 1..first.len() {
            first[b] += first[b - 1];
        }
        let mut fill = first.clone();
        let mut members: Vec<u32> = alloc::vec![0; first[count] as usize];
        for (i, s) in segs.iter().enumerate() {
            let (b0, b1) = span(s);
            if b1 - b0 >= tall_bands {
                continue;
            }
            for b in b0..=b1 {
                members[fill[b] as usize] = i as u32;
                fill[b] += 1;
            }
        }
        Rows {
            lo,
            k,
            count,
            first,
            members,
            tall,
        }
    }

    /// The segments that may cross the horizontal line through `p` (a superset).
    fn near<'a>(
        &'a self,
        segs: &'a [(u32, u32, i64)],
        p: DVec2,
    ) -> impl Iterator<Item = (u32, u32, i64)> + 'a {
        let b = (((p.y - self.lo) * self.k) as usize).min(self.count - 1);
        let listed = &self.members[self.first[b] as usize..self.first[b + 1] as usize];
        listed
            .iter()
            .chain(self.tall.iter())
            .map(move |&i| segs[i as usize])
    }
}

/// The winding number of the points just left of `p` with respect to the segments
/// `(from, to, multiplicity)`: the signed count of segments crossing the ray from `p` to the
/// left, with the half-open rule (a segment counts when its lower end is at or below `p` and its
/// upper end above) and exact sides. Segments through `p` itself never count: their crossing with
/// the ray is `p`, where the side test is zero. `segs` may hold any superset of the segments
/// that cross the horizontal line through `p`.
fn winding_left_of(pts: &[DVec2], segs: impl Iterator<Item = (u32, u32, i64)>, p: DVec2) -> i64 {
    let mut w = 0;
    for (u, v, m) in segs {
        let (a, b) = (pts[u as usize], pts[v as usize]);
        if a.x >= p.x && b.x >= p.x {
            continue;
        }
        if a.y <= p.y && b.y > p.y {
            // Upward: p to its right means the crossing lies left of p; a clockwise turn.
            if orient(a, b, p) < 0.0 {
                w -= m;
            }
        } else if b.y <= p.y && a.y > p.y && orient(a, b, p) > 0.0 {
            w += m;
        }
    }
    w
}

#[cfg(test)]
mod tests {
    use super::*;

    fn v(x: f64, y: f64) -> DVec2 {
        DVec2::new(x, y)
    }

    #[test]
    fn angle_order_is_counter_clockwise_from_the_left() {
        let p = v(0.0, 0.0);
        let dirs = [
            v(-1.0, -1.0),
            v(0.0, -1.0),
            v(1.0, -1.0),
            v(1.0, 0.0),
            v(1.0, 1.0),
            v(0.0, 1.0),
            v(-1.0, 1.0),
            v(-1.0, 0.0),
        ];
        for (i, &a) in dirs.iter().enumerate() {
            for (j, &b) in dirs.iter().enumerate() {
                assert_eq!(angle_cmp(p, a, b), i.cmp(&j), "{a} vs {b}");
            }
        }
        assert_eq!(
            angle_cmp(p, v(2.0, 2.0), v(1.0, 1.0)),
            core::cmp::Ordering::Equal
        );
    }

    #[test]
    fn ray_to_the_left_counts_signed_crossings() {
        // A counter-clockwise square as segments from lower to higher node index.
        let pts = [v(0.0, 0.0), v(2.0, 0.0), v(2.0, 2.0), v(0.0, 2.0)];
        let segs = [(0, 1, 1), (1, 2, 1), (2, 3, 1), (0, 3, -1)];
        assert_eq!(winding_left_of(&pts, segs.iter().copied(), v(1.0, 1.0)), 1);
        assert_eq!(winding_left_of(&pts, segs.iter().copied(), v(3.0, 1.0)), 0);
        assert_eq!(winding_left_of(&pts, segs.iter().copied(), v(-1.0, 1.0)), 0);
        // At the height of a vertex: the half-open rule counts the left edge once.
        assert_eq!(winding_left_of(&pts, segs.iter().copied(), v(1.0, 0.0)), 1);
        assert_eq!(winding_left_of(&pts, segs.iter().copied(), v(1.0, 2.0)), 0);
        let rev: Vec<(u32, u32, i64)> = segs.iter().map(|&(a, b, m)| (a, b, -m)).collect();
        assert_eq!(winding_left_of(&pts, rev.iter().copied(), v(1.0, 1.0)), -1);
    }

    #[test]
    fn fill_rules_decide_by_winding_number() {
        for (w, e, n, p, q) in [
            (-2, false, true, false, true),
            (-1, true, true, false, true),
            (0, false, false, false, false),
            (1, true, true, true, false),
            (2, false, true, true, false),
            (3, true, true, true, false),
        ] {
            assert_eq!(FillRule::EvenOdd.contains(w), e, "{w}");
            assert_eq!(FillRule::NonZero.contains(w), n, "{w}");
            assert_eq!(FillRule::Positive.contains(w), p, "{w}");
            assert_eq!(FillRule::Negative.contains(w), q, "{w}");
        }
    }
}
