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
//! # References
//!
//! - G. Greiner, K. Hormann. *Efficient clipping of arbitrary polygons.* ACM Transactions on
//!   Graphics 17(2), 1998.
//! - E. L. Foster, K. Hormann, R. T. Popa. *Clipping simple polygons with degenerate
//!   intersections.* Computers & Graphics: X 2, 2019.

pub(crate) mod intersect;
pub(crate) mod label;
pub(crate) mod trace;

use alloc::vec::Vec;
use glam::DVec2;
use smallvec::SmallVec;

use super::contour::Contour;
use super::shape::Shape;
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
pub(crate) struct Rings {
    pub(crate) pts: Split,
    pub(crate) ends: SmallVec<[u32; 4]>,
}

impl Rings {
    fn from_shape(s: &Shape) -> Rings {
        let mut pts = Split::new();
        let mut ends = SmallVec::new();
        for c in &s.contours {
            // `+ 0.0` turns -0.0 into 0.0, so that bitwise-ordered lookups (which distinguish
            // the two zeros) agree with `==` (which does not).
            pts.extend(c.pts.iter().map(|&p| p + DVec2::ZERO));
            ends.push(pts.len() as u32);
        }
        Rings { pts, ends }
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
/// [`GeomError::Degenerate`] when `f64` cannot resolve the configuration consistently (edge
/// splitting does not settle, or the labels are inconsistent); never for well-separated or exactly
/// degenerate inputs such as shared edges and vertices.
///
/// # References
///
/// - G. Greiner, K. Hormann. *Efficient clipping of arbitrary polygons.* ACM TOG 17(2), 1998
///   (intersection phase section 3.1, labelling 3.2, tracing 3.3).
/// - E. L. Foster, K. Hormann, R. T. Popa. *Clipping simple polygons with degenerate
///   intersections.* Computers & Graphics: X 2, 2019 (labelling phase: local classification of
///   Table 1, overlapping chains as delayed crossings/bouncings; tracing phase).
pub fn boolean(a: &Shape, b: &Shape, op: BoolOp) -> Result<Shape, GeomError> {
    // Trivial cases first: they need no geometry and keep chains of operations cheap.
    if a.is_empty() || b.is_empty() {
        return Ok(match op {
            BoolOp::Intersection => Shape::empty(),
            BoolOp::Difference => a.clone(),
            BoolOp::Union | BoolOp::Xor => {
                if a.is_empty() {
                    b.clone()
                } else {
                    a.clone()
                }
            }
        });
    }
    let ra = Rings::from_shape(a);
    let rb = Rings::from_shape(b);
    if disjoint_boxes(&ra, &rb) {
        return Ok(match op {
            BoolOp::Intersection => Shape::empty(),
            BoolOp::Difference => a.clone(),
            BoolOp::Union | BoolOp::Xor => {
                let mut c: Vec<Contour> = a.contours.clone();
                c.extend(b.contours.iter().cloned());
                Shape::from_contours(c)
            }
        });
    }
    let l = Labelled::new(ra, rb)?;
    let mut edges = SmallVec::new();
    trace::select(
        &l.ra, &l.a_nxt, &l.sa, &l.rb, &l.b_nxt, &l.sb, &l.nodes, op, &mut edges,
    );
    let contours = trace::trace(&edges, l.ra.pts.len() + l.rb.pts.len(), l.scale)?;
    Ok(Shape::from_contours(contours))
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

fn bbox(r: &Rings) -> (DVec2, DVec2) {
    r.pts.iter().fold(
        (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY)),
        |(lo, hi), &p| (lo.min(p), hi.max(p)),
    )
}

/// Whether the bounding boxes are disjoint with a gap, so the operands cannot even touch.
fn disjoint_boxes(a: &Rings, b: &Rings) -> bool {
    let (alo, ahi) = bbox(a);
    let (blo, bhi) = bbox(b);
    ahi.x < blo.x || bhi.x < alo.x || ahi.y < blo.y || bhi.y < alo.y
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
