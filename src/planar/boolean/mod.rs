//! Boolean operations on shapes: Greiner–Hormann clipping extended to degenerate contacts.
//!
//! The pipeline reads in the order it runs:
//!
//! 1. [`intersect`]: split both operands' contours at every contact (crossings, vertex on edge,
//!    vertex on vertex, overlapping collinear edges), with exact orientation tests;
//! 2. [`label`]: label each split edge inside / outside / on the other operand, and classify the
//!    intersection vertices as crossing, bouncing, delayed crossing or delayed bouncing;
//! 3. [`trace`]: select edges by label for the operation, link them into contours and regularize.
//!
//! Before phase 1, vertices of both operands within the snapping distance of each other are
//! welded (`intersect::weld`). Operands in generic position skip the pipeline: [`fast`] runs
//! classic Greiner–Hormann and bails out to the pipeline at the first contact that is not a
//! clean proper crossing, so it only ever returns what the pipeline would.
//!
//! # References
//!
//! - G. Greiner, K. Hormann. *Efficient clipping of arbitrary polygons.* ACM Transactions on
//!   Graphics 17(2), 1998.
//! - E. L. Foster, K. Hormann, R. T. Popa. *Clipping simple polygons with degenerate
//!   intersections.* Computers & Graphics: X 2, 2019.

pub(crate) mod fast;
pub(crate) mod intersect;
pub(crate) mod label;
pub(crate) mod trace;

use alloc::vec::Vec;
use glam::DVec2;
use smallvec::SmallVec;

use super::contour::Contour;
use super::shape::{Shape, has_self_contacts, min_separation2};
use crate::GeomError;

/// The four regularized set operations.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum BoolOp {
    /// Points in both operands.
    Intersection,
    /// Points in either operand.
    Union,
    /// Points in the first operand but not in the second.
    Difference,
    /// Points in exactly one operand.
    Xor,
}

/// Point storage of the split contours of one operand.
pub(crate) type Split = SmallVec<[DVec2; 32]>;

/// The contours of one operand as one flat point list: ring `k` occupies
/// `ends[k - 1]..ends[k]`.
#[derive(Default)]
pub(crate) struct Rings {
    pub(crate) pts: Split,
    pub(crate) ends: SmallVec<[u32; 4]>,
}

impl Rings {
    fn from_shape(s: &Shape) -> Rings {
        let mut r = Rings::default();
        let _ = r.fill(s);
        r
    }

    /// Replaces the contents with the contours of `s`, keeping the buffers' capacity; returns
    /// the bounding box.
    fn fill(&mut self, s: &Shape) -> Bbox {
        self.pts.clear();
        self.ends.clear();
        let mut b = Bbox {
            lo: DVec2::INFINITY,
            hi: DVec2::NEG_INFINITY,
        };
        self.pts.reserve(s.vertex_count());
        for c in &s.contours {
            for &p in &c.pts {
                // `+ 0.0` turns -0.0 into 0.0, so that bitwise-ordered lookups (which
                // distinguish the two zeros) agree with `==` (which does not).
                let p = p + DVec2::ZERO;
                // Plain comparisons: coordinates are finite.
                b.lo.x = if p.x < b.lo.x { p.x } else { b.lo.x };
                b.lo.y = if p.y < b.lo.y { p.y } else { b.lo.y };
                b.hi.x = if p.x > b.hi.x { p.x } else { b.hi.x };
                b.hi.y = if p.y > b.hi.y { p.y } else { b.hi.y };
                self.pts.push(p);
            }
            self.ends.push(self.pts.len() as u32);
        }
        b
    }

    /// For each vertex, the index of the next vertex in its ring.
    pub(crate) fn next_table(&self) -> SmallVec<[u32; 64]> {
        let mut t = SmallVec::with_capacity(self.pts.len());
        let mut start = 0u32;
        for &end in &self.ends {
            for i in start..end {
                t.push(if i + 1 == end { start } else { i + 1 });
            }
            start = end;
        }
        t
    }

    /// For each vertex, the index of the previous vertex in its ring.
    pub(crate) fn prev_table(&self) -> SmallVec<[u32; 64]> {
        let mut t = SmallVec::with_capacity(self.pts.len());
        let mut start = 0u32;
        for &end in &self.ends {
            for i in start..end {
                t.push(if i == start { end - 1 } else { i - 1 });
            }
            start = end;
        }
        t
    }

    fn scale(&self) -> f64 {
        self.pts
            .iter()
            .fold(0.0, |m: f64, p| m.max(p.x.abs()).max(p.y.abs()))
    }
}

/// An axis-aligned bounding box.
#[derive(Clone, Copy)]
pub(crate) struct Bbox {
    pub(crate) lo: DVec2,
    pub(crate) hi: DVec2,
}

impl Bbox {
    /// Largest coordinate magnitude inside the box.
    fn scale(&self) -> f64 {
        self.lo.abs().max(self.hi.abs()).max_element()
    }

    /// Whether the boxes are disjoint with a gap, so the operands cannot even touch.
    fn disjoint(&self, o: &Bbox) -> bool {
        self.hi.x < o.lo.x || o.hi.x < self.lo.x || self.hi.y < o.lo.y || o.hi.y < self.lo.y
    }
}

/// Computes `a op b` as a new shape.
///
/// Both operands are valid [`Shape`]s (outer contours counter-clockwise, holes clockwise, contours
/// touching at most at points), so only numerical pathologies can fail. The result is
/// regularized — no zero-area parts, spikes, repeated or collinear consecutive points — and is a
/// valid operand again, so chains of operations compose.
///
/// Contacts are decided with exact `orient2d`; the only tolerances are relative to the larger
/// coordinate magnitude of the operands: computed crossings snap to a vertex within
/// [`SNAP_REL`](crate::planar::SNAP_REL) of the scale, and result loops thinner than
/// [`SLIVER_REL`](crate::planar::SLIVER_REL) of the scale are dropped.
///
/// # Examples
///
/// ```
/// use arealight::glam::DVec2;
/// use arealight::planar::{BoolOp, Shape, boolean};
///
/// let sq = |x: f64, y: f64| {
///     Shape::new(vec![vec![
///         DVec2::new(x, y),
///         DVec2::new(x + 2.0, y),
///         DVec2::new(x + 2.0, y + 2.0),
///         DVec2::new(x, y + 2.0),
///     ]])
///     .unwrap()
/// };
/// // Two squares sharing half an edge: a degenerate overlap handled exactly.
/// let (a, b) = (sq(0.0, 0.0), sq(2.0, 1.0));
/// assert_eq!(boolean(&a, &b, BoolOp::Union).unwrap().area(), 8.0);
/// assert_eq!(boolean(&a, &b, BoolOp::Intersection).unwrap().area(), 0.0);
/// assert_eq!(boolean(&a, &b, BoolOp::Difference).unwrap().area(), 4.0);
/// ```
///
/// # Errors
///
/// [`GeomError::Undecidable`] when `f64` cannot resolve the configuration consistently (edge
/// splitting does not settle, or the result's boundary does not close); never for well-separated
/// or exactly degenerate inputs such as shared edges and vertices.
///
/// # References
///
/// - G. Greiner, K. Hormann. *Efficient clipping of arbitrary polygons.* ACM TOG 17(2), 1998
///   (intersection phase section 3.1, labelling 3.2, tracing 3.3).
/// - E. L. Foster, K. Hormann, R. T. Popa. *Clipping simple polygons with degenerate
///   intersections.* Computers & Graphics: X 2, 2019 (labelling phase: local classification of
///   Table 1, overlapping chains as delayed crossings/bouncings; tracing phase).
pub fn boolean(a: &Shape, b: &Shape, op: BoolOp) -> Result<Shape, GeomError> {
    boolean_with(&mut Workspace::new(), a, b, op)
}

/// Scratch storage for [`boolean_with`], kept across calls.
///
/// Buffers have inline room for operands of up to about 32 vertices each, so [`boolean`] (which
/// makes a fresh workspace per call) allocates nothing but its output for small operands. For
/// larger operands, the buffers of the generic-position fast path spill to the heap once and
/// keep their capacity in a reused workspace; the robust path for degenerate contacts still
/// allocates its own tables per call when operands are that large.
///
/// A workspace holds no results: any workspace can be used for any operation.
///
/// # Examples
///
/// ```
/// use arealight::glam::DVec2;
/// use arealight::planar::{BoolOp, Shape, Workspace, boolean_with};
///
/// let ngon = |n: usize, c: f64| {
///     Shape::new(vec![(0..n)
///         .map(|k| {
///             let t = std::f64::consts::TAU * k as f64 / n as f64;
///             DVec2::new(c + t.cos(), t.sin())
///         })
///         .collect()])
/// };
/// let mut ws = Workspace::new();
/// let a = ngon(64, 0.0)?;
/// for k in 1..4 {
///     let b = ngon(64, 0.25 * k as f64)?;
///     let d = boolean_with(&mut ws, &a, &b, BoolOp::Difference)?;
///     assert!(d.area() > 0.0 && d.area() < a.area());
/// }
/// # Ok::<(), arealight::GeomError>(())
/// ```
#[derive(Default)]
pub struct Workspace {
    a: Rings,
    b: Rings,
    fast: fast::Scratch,
}

impl Workspace {
    /// An empty workspace (no heap allocation until operands outgrow the inline buffers).
    #[must_use]
    pub fn new() -> Workspace {
        Workspace::default()
    }
}

impl core::fmt::Debug for Workspace {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str("Workspace")
    }
}

/// [`boolean`] with caller-provided scratch storage, for many operations in a row.
///
/// The result is identical to `boolean(a, b, op)`; only where the scratch buffers live differs.
///
/// # Errors
///
/// As [`boolean`].
pub fn boolean_with(
    ws: &mut Workspace,
    a: &Shape,
    b: &Shape,
    op: BoolOp,
) -> Result<Shape, GeomError> {
    run(ws, a, b, op, Path::Auto, 0.0).map(|r| r.unwrap_or_default())
}

/// [`boolean`] with the coordinate scale that sets its tolerances taken as at least
/// `min_scale`: vertices closer than [`SNAP_REL`](crate::planar::SNAP_REL)` * min_scale` are
/// welded, vertices that close to the other operand's edges put on them, and loops thinner than
/// [`SLIVER_REL`](crate::planar::SLIVER_REL)` * min_scale` dropped, even when every coordinate
/// is much smaller. Coordinates keep their full precision; only the resolution is coarser.
///
/// For callers whose shapes stand for points stored with an absolute precision coarser than the
/// shapes' own coordinates allow: the sphere layer's gnomonic charts of regions `1e-10` rad
/// across have coordinates near `1e-10`, whose relative tolerances (`1e-24`) keep features that
/// the unit vectors the result is mapped back to (rounded to about `1e-16`) cannot carry.
///
/// # Errors
///
/// As [`boolean`].
pub(crate) fn boolean_at_scale(
    a: &Shape,
    b: &Shape,
    op: BoolOp,
    min_scale: f64,
) -> Result<Shape, GeomError> {
    run(&mut Workspace::new(), a, b, op, Path::Auto, min_scale).map(|r| r.unwrap_or_default())
}

/// Which pipeline [`run`] may use (tests compare them).
#[derive(Clone, Copy, PartialEq, Eq)]
enum Path {
    /// The fast path when the operands are in generic position, else the robust one.
    Auto,
    /// Only the fast path; `Ok(None)` when it bails out.
    FastOnly,
    /// Only the robust path.
    RobustOnly,
}

fn run(
    ws: &mut Workspace,
    a: &Shape,
    b: &Shape,
    op: BoolOp,
    path: Path,
    min_scale: f64,
) -> Result<Option<Shape>, GeomError> {
    // Trivial cases first: they need no geometry and keep chains of operations cheap.
    if a.is_empty() || b.is_empty() {
        let s = if a.is_empty() { b } else { a };
        let scale = s.facts.bbox_scale().max(min_scale);
        let passes = match op {
            BoolOp::Intersection => true,
            BoolOp::Difference => a.is_empty() || settled(a, scale),
            BoolOp::Union | BoolOp::Xor => settled(s, scale),
        };
        if passes {
            return Ok(Some(match op {
                BoolOp::Intersection => Shape::empty(),
                BoolOp::Difference => a.clone(),
                BoolOp::Union | BoolOp::Xor => s.clone(),
            }));
        }
        if path == Path::FastOnly {
            return Ok(None);
        }
        return robust(ws, a, b, op, scale).map(Some);
    }
    let (fa, fb) = (&a.facts, &b.facts);
    let (box_a, box_b) = (
        Bbox {
            lo: fa.lo,
            hi: fa.hi,
        },
        Bbox {
            lo: fb.lo,
            hi: fb.hi,
        },
    );
    let scale = box_a.scale().max(box_b.scale()).max(min_scale);
    if box_a.disjoint(&box_b) {
        let passes = match op {
            BoolOp::Intersection => true,
            BoolOp::Difference => settled(a, scale),
            BoolOp::Union | BoolOp::Xor => settled(a, scale) && settled(b, scale),
        };
        if passes {
            return Ok(Some(match op {
                BoolOp::Intersection => Shape::empty(),
                BoolOp::Difference => a.clone(),
                BoolOp::Union | BoolOp::Xor => {
                    let mut c: Vec<Contour> = a.contours.clone();
                    c.extend(b.contours.iter().cloned());
                    Shape::from_contours(c)
                }
            }));
        }
    }
    // The fast path needs operands in generic position, in particular no two vertices within
    // the snapping distance (which `weld` would merge) and no vertex of an operand on an edge
    // of another of its contours (which `split_self_contacts` would insert). Within an operand
    // both are facts of the shape, cached by `Shape::new` (and computed here for results of
    // earlier operations); between the operands the fast path's own pair tests see such
    // vertices (each is near the other's edges).
    if path != Path::RobustOnly && op != BoolOp::Xor {
        let snap = intersect::SNAP_REL * scale;
        let generic = |s: &Shape| {
            let sep2 = s.facts.sep2.unwrap_or_else(|| min_separation2(&s.contours));
            sep2 > snap * snap
                && !s
                    .facts
                    .self_contacts
                    .unwrap_or_else(|| has_self_contacts(&s.contours))
        };
        if generic(a)
            && generic(b)
            && let Some(c) = fast::run(&mut ws.fast, a, b, op, scale)
        {
            return Ok(Some(Shape::from_contours(c)));
        }
    }
    if path == Path::FastOnly {
        return Ok(None);
    }
    robust(ws, a, b, op, scale).map(Some)
}

/// Whether the operation's result may take the contours of `s` as they are: every contour bounds
/// more than a sliver at `scale` and, for shapes from [`Shape::new`] (whose minimum vertex
/// separation is cached), no two vertices are within the snapping distance. Results of earlier
/// operations were welded and regularized at a scale at least their own; only a larger `scale`
/// can turn their loops into slivers.
///
/// Otherwise the robust pipeline runs even against the empty shape, and welds and drops what any
/// other operation would.
fn settled(s: &Shape, scale: f64) -> bool {
    let snap = intersect::SNAP_REL * scale;
    s.facts.sep2.is_none_or(|d| d > snap * snap)
        && s.contours
            .iter()
            .all(|c| trace::clearly_survives(&c.pts, scale))
}

/// The robust pipeline (weld, split, label, trace) on any two shapes.
fn robust(
    ws: &mut Workspace,
    a: &Shape,
    b: &Shape,
    op: BoolOp,
    scale: f64,
) -> Result<Shape, GeomError> {
    ws.a.fill(a);
    ws.b.fill(b);
    intersect::weld(&mut ws.a, &mut ws.b, scale);
    let (ra, rb) = (core::mem::take(&mut ws.a), core::mem::take(&mut ws.b));
    let l = Labelled::new_welded(ra, rb, scale)?;
    let mut edges = SmallVec::new();
    trace::select(
        &l.ra, &l.a_nxt, &l.sa, &l.rb, &l.b_nxt, &l.sb, &l.nodes, op, &mut edges,
    );
    let contours = trace::trace(&edges, l.ra.pts.len() + l.rb.pts.len(), l.scale)?;
    // Give the (possibly spilled) buffers back for the next call.
    (ws.a, ws.b) = (l.ra, l.rb);
    Ok(Shape::from_contours(contours))
}

/// [`boolean`] through the robust pipeline only, skipping the generic-position fast path; for
/// tests that require both to agree.
///
/// # Errors
///
/// As [`boolean`].
#[doc(hidden)]
pub fn boolean_robust(a: &Shape, b: &Shape, op: BoolOp) -> Result<Shape, GeomError> {
    run(&mut Workspace::new(), a, b, op, Path::RobustOnly, 0.0).map(|r| r.unwrap_or_default())
}

/// [`boolean`] through the generic-position fast path only: `Ok(None)` when the operands are
/// not in generic position (the fast path bails out); for tests.
///
/// # Errors
///
/// As [`boolean`].
#[doc(hidden)]
pub fn boolean_fast(a: &Shape, b: &Shape, op: BoolOp) -> Result<Option<Shape>, GeomError> {
    run(&mut Workspace::new(), a, b, op, Path::FastOnly, 0.0)
}

/// Both operands after the intersection phase (split at every contact) and the labelling phase:
/// what tracing and the diagnostic classification both start from.
struct Labelled {
    ra: Rings,
    rb: Rings,
    scale: f64,
    a_nxt: SmallVec<[u32; 64]>,
    a_prv: SmallVec<[u32; 64]>,
    b_nxt: SmallVec<[u32; 64]>,
    b_prv: SmallVec<[u32; 64]>,
    nodes: label::Nodes,
    sa: SmallVec<[label::Status; 64]>,
    sb: SmallVec<[label::Status; 64]>,
}

impl Labelled {
    fn new(mut ra: Rings, mut rb: Rings) -> Result<Labelled, GeomError> {
        let scale = ra.scale().max(rb.scale());
        intersect::weld(&mut ra, &mut rb, scale);
        Labelled::new_welded(ra, rb, scale)
    }

    /// Phases 1 and 2 on operands already welded by [`intersect::weld`].
    fn new_welded(mut ra: Rings, mut rb: Rings, scale: f64) -> Result<Labelled, GeomError> {
        intersect::split_self_contacts(&mut ra);
        intersect::split_self_contacts(&mut rb);
        intersect::split(&mut ra, &mut rb, scale)?;
        intersect::remove_spikes(&mut ra);
        intersect::remove_spikes(&mut rb);

        let (a_nxt, a_prv) = (ra.next_table(), ra.prev_table());
        let (b_nxt, b_prv) = (rb.next_table(), rb.prev_table());
        let nodes = label::Nodes::new(&ra, &rb);
        let mut sa = SmallVec::new();
        let mut sb = SmallVec::new();
        label::label(&ra, &a_nxt, false, &nodes, &rb, &b_nxt, &b_prv, &mut sa);
        label::label(&rb, &b_nxt, true, &nodes, &ra, &a_nxt, &a_prv, &mut sb);
        Ok(Labelled {
            ra,
            rb,
            scale,
            a_nxt,
            a_prv,
            b_nxt,
            b_prv,
            nodes,
            sa,
            sb,
        })
    }
}

/// `(point, class)` for each vertex of one split operand, as returned by [`contact_classes`].
pub type ContactClasses = Vec<(DVec2, label::VertexClass)>;

/// The Foster–Hormann–Popa classification of every vertex of both operands after phase 1 (the
/// split contours), for diagnostics and tests: `(point, class)` for A's vertices, then for B's.
///
/// # Errors
///
/// As [`boolean`].
#[doc(hidden)]
pub fn contact_classes(
    a: &Shape,
    b: &Shape,
) -> Result<(ContactClasses, ContactClasses), GeomError> {
    let l = Labelled::new(Rings::from_shape(a), Rings::from_shape(b))?;
    let mut ca = Vec::new();
    let mut cb = Vec::new();
    label::classify(&l.a_nxt, &l.a_prv, false, &l.nodes, &l.sa, &mut ca);
    label::classify(&l.b_nxt, &l.b_prv, true, &l.nodes, &l.sb, &mut cb);
    Ok((
        l.ra.pts.iter().copied().zip(ca).collect(),
        l.rb.pts.iter().copied().zip(cb).collect(),
    ))
}
