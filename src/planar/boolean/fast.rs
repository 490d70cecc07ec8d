//! The generic-position fast path: classic Greiner–Hormann on preallocated buffers.
//!
//! Most operations meet no degeneracy at all: every contact between the two boundaries is a
//! proper crossing, far (in units of the snapping distance) from every vertex and from every
//! other crossing. For those, Greiner and Hormann's original algorithm (1998, sections 3.1–3.3)
//! is already exact enough: intersect all edge pairs, give each crossing its entry/exit flag
//! from the sign of one orientation, and walk. This module runs exactly that, on buffers that a
//! [`Workspace`](super::Workspace) keeps across calls, and *bails out* — returns `None`, so the
//! caller runs the robust pipeline — at the first sign of anything else.
//!
//! # The fast path never disagrees with the robust path
//!
//! The robust pipeline (`intersect` -> `label` -> `trace`) is the definition of the result; the
//! fast path only skips work that is provably a no-op there, and produces the same contours bit
//! for bit (same points, same starting points, same order). Precisely, it runs only when:
//!
//! - no two vertices of the operands are within the snapping distance (the caller checks this
//!   with `intersect::weld`, which then changed nothing), and no vertex of an operand lies exactly
//!   on an edge of another contour of the same operand (`split_self_contacts` would insert it);
//! - for every pair of edges whose bounding boxes, widened by `MARGIN` times the snapping
//!   distance, overlap, no endpoint of either lies within `MARGIN` snapping distances of the
//!   other's line (by the robust path's own `|orient| <= snap * (|dx| + |dy|)` measure, widened).
//!   So the robust pass 1 sees only "no contact" or "proper crossing" for every pair, never a
//!   vertex on an edge, and no computed crossing can be within the snapping distance of any vertex
//!   (such a vertex would be within `snap + rounding` of both crossing edges' lines) — the robust
//!   path snaps nothing;
//! - every two crossings are more than `MARGIN` snapping distances apart, and at every crossing
//!   the four split edges meeting there are far from collinear by the robust pass 2's own
//!   common-endpoint test (again widened by `MARGIN`). Inserting a crossing bends its two edges
//!   by a few ulps only, so the robust pass 2, which re-tests the bent edges, finds nothing new:
//!   the bent edges at a crossing fail its near-collinearity test with margin, and every other
//!   edge stays `MARGIN` snapping distances away from the thin triangle the bending sweeps;
//! - along every contour the crossings alternate between entry and exit, and every crossing
//!   has exactly one selected outgoing edge during the walk (always true in generic position;
//!   checked rather than assumed).
//!
//! Under these conditions the robust labels equal the crossing signs used here (the local wedge
//! test at a transversal crossing reduces to the side of the other edge's line), every node of
//! the selected edges has one edge in and one out, so the robust walk's leftmost-turn choice is
//! forced, and the walk here visits edges in the same order, starting each loop at the first
//! unused selected edge in the same order (A's split edges, then B's). Both hand each loop to the
//! same `trace::regularize`. `tests/planar_fast.rs` checks the agreement on random, degenerate
//! and near-degenerate inputs, and that the fast path does bail out on the degenerate ones.
//!
//! Symmetric difference is left to the robust path: all four edges at each of its crossings are
//! selected, so its walk needs the leftmost-turn rule and the loop cutting of `trace`.

use alloc::vec::Vec;
use glam::DVec2;
use smallvec::SmallVec;

use super::intersect::{SNAP_REL, crossing_point, edge_param, sort_key};
use super::trace::regularize;
use super::{Bbox, BoolOp, Rings};
use crate::planar::contour::Contour;
use crate::planar::predicates::{orient, strictly_between, winding};

/// How many snapping distances every test of the fast path keeps from the robust path's
/// thresholds. The robust decisions are made on exact orientations of points whose computed
/// crossings are off by a few ulps of the coordinate scale (much less than one snapping
/// distance, `64 * f64::EPSILON` of it); a factor of 4 leaves room for that rounding and for the
/// `|dx| + |dy|` over-estimate of an edge's length.
const MARGIN: f64 = 4.0;

const NONE: u32 = u32::MAX;

/// Operand pairs with at most this many edge pairs are intersected by testing all pairs; larger
/// ones by a sweep over the edges' x-ranges (sorting costs more than it saves below this).
const ALL_PAIRS_MAX: usize = 256;

/// Operand pairs with more than this many vertex pairs first drop the edges that are not near
/// the other operand's bounding box.
const FILTER_MIN: usize = 64;

/// One proper crossing of edge `ea` of A with edge `eb` of B (edge numbers index the flat point
/// lists of [`Rings`]).
#[derive(Clone, Copy)]
struct Crossing {
    ea: u32,
    eb: u32,
    /// Parameters along the two edges (as the robust path computes them, for the same order).
    ta: f64,
    tb: f64,
    p: DVec2,
    /// Whether A's split edge leaving the crossing runs inside B (A's far end is left of B's
    /// edge, where B's interior is).
    a_in: bool,
    /// Whether B's split edge leaving the crossing runs inside A.
    b_in: bool,
    /// Positions of the crossing in the split point lists of A and B.
    pos_a: u32,
    pos_b: u32,
}

/// An edge for the pair search: bounding box `[min x, max x, min y, max y]`, its ends, and its
/// index in the operand's point list.
#[derive(Clone, Copy)]
struct EdgeBox {
    b: [f64; 4],
    p0: DVec2,
    p1: DVec2,
    edge: u32,
}

/// One point of an operand's contours split at the crossings: an operand vertex or a crossing,
/// with its neighbours along the contour and the state of the split edge leaving it.
#[derive(Clone, Copy)]
struct Node {
    p: DVec2,
    /// Crossing index, or `NONE` for an operand vertex.
    xid: u32,
    next: u32,
    prev: u32,
    /// Whether the split edge from this point to `next` bounds the result.
    sel: bool,
    /// Whether the walk has used that edge.
    used: bool,
}

type SplitRings = SmallVec<[Node; 48]>;

/// Scratch buffers of the fast path. Inline capacities cover operands of up to 32 vertices
/// without heap allocation; larger operands spill once and, in a reused
/// [`Workspace`](super::Workspace), keep their capacity.
#[derive(Default)]
pub(crate) struct Scratch {
    boxes_a: SmallVec<[EdgeBox; 32]>,
    boxes_b: SmallVec<[EdgeBox; 32]>,
    /// Sort keys: a float's `sort_key` in the high bits, an index in the low 32.
    events: SmallVec<[u128; 64]>,
    active_a: SmallVec<[u32; 16]>,
    active_b: SmallVec<[u32; 16]>,
    cross: SmallVec<[Crossing; 16]>,
    order: SmallVec<[u128; 16]>,
    sa: SplitRings,
    sb: SplitRings,
    path: SmallVec<[DVec2; 64]>,
}

/// Runs `a op b` in generic position, or returns `None` when the operands need the robust path
/// (see the module documentation). `a` and `b` have been welded with nothing to weld; `op` is
/// not [`BoolOp::Xor`].
pub(crate) fn run(
    s: &mut Scratch,
    a: &Rings,
    b: &Rings,
    [box_a, box_b]: [Bbox; 2],
    op: BoolOp,
    scale: f64,
) -> Option<Vec<Contour>> {
    if op == BoolOp::Xor || has_self_contacts(a) || has_self_contacts(b) {
        return None;
    }
    let m = MARGIN * SNAP_REL * scale;
    // Only edges near the other operand's bounding box can meet it (for tiny operands the
    // filter costs more than the pair tests it saves).
    let filter = a.pts.len() * b.pts.len() > FILTER_MIN;
    edge_boxes(a, filter.then_some(&box_b), m, &mut s.boxes_a);
    edge_boxes(b, filter.then_some(&box_a), m, &mut s.boxes_b);
    s.cross.clear();
    find_crossings(s, m)?;
    crossings_apart(&mut s.cross, &mut s.order, m)?;
    split(&mut s.sa, a, &mut s.cross, &mut s.order, false)?;
    split(&mut s.sb, b, &mut s.cross, &mut s.order, true)?;
    transversal(s, m)?;
    label(&mut s.sa, &s.cross, b, false, op)?;
    label(&mut s.sb, &s.cross, a, true, op)?;
    walk(s, op, scale)
}

/// Whether a vertex of one contour lies exactly inside an edge of another contour of the same
/// operand (the robust path would insert it there; such contacts are left to it).
fn has_self_contacts(r: &Rings) -> bool {
    if r.ends.len() < 2 {
        return false;
    }
    let pts: &[DVec2] = &r.pts;
    let mut start = 0usize;
    for &end in &r.ends {
        let end = end as usize;
        for i in start..end {
            let (p0, p1) = (pts[i], pts[if i + 1 == end { start } else { i + 1 }]);
            let (lo, hi) = (p0.min(p1), p0.max(p1));
            for (k, &q) in pts.iter().enumerate() {
                if (start..end).contains(&k) || q.x < lo.x || q.x > hi.x || q.y < lo.y || q.y > hi.y
                {
                    continue;
                }
                if orient(p0, p1, q) == 0.0 && strictly_between(p0, p1, q) {
                    return true;
                }
            }
        }
        start = end;
    }
    false
}

/// Fills `out` with the edges of `r` (those whose boxes come within `m` of `near`, if given),
/// with their indices.
fn edge_boxes(r: &Rings, near: Option<&Bbox>, m: f64, out: &mut SmallVec<[EdgeBox; 32]>) {
    out.clear();
    let near = near.map(|n| [n.lo.x, n.hi.x, n.lo.y, n.hi.y]);
    out.reserve(r.pts.len());
    let pts: &[DVec2] = &r.pts;
    let mut start = 0usize;
    for &end in &r.ends {
        let end = end as usize;
        for i in start..end {
            let p0 = pts[i];
            let p1 = pts[if i + 1 == end { start } else { i + 1 }];
            // Plain comparisons: coordinates are finite, so `f64::min`'s NaN handling is waste.
            let (x0, x1) = if p0.x <= p1.x {
                (p0.x, p1.x)
            } else {
                (p1.x, p0.x)
            };
            let (y0, y1) = if p0.y <= p1.y {
                (p0.y, p1.y)
            } else {
                (p1.y, p0.y)
            };
            let b = [x0, x1, y0, y1];
            if near.is_none_or(|n| boxes_near(&b, &n, m)) {
                out.push(EdgeBox {
                    b,
                    p0,
                    p1,
                    edge: i as u32,
                });
            }
        }
        start = end;
    }
}

/// Tests every edge pair whose widened boxes overlap (all pairs for small operands, a sweep
/// over x otherwise), recording proper crossings; `None` at the first near contact.
fn find_crossings(s: &mut Scratch, m: f64) -> Option<()> {
    let (ba, bb): (&[EdgeBox], &[EdgeBox]) = (&s.boxes_a, &s.boxes_b);
    let cross = &mut s.cross;
    if ba.len() * bb.len() <= ALL_PAIRS_MAX {
        for ea in ba {
            for eb in bb {
                if boxes_near(&ea.b, &eb.b, m) {
                    pair(ea, eb, m, cross)?;
                }
            }
        }
        return Some(());
    }
    // Sweep: edges enter in order of their left ends; an edge leaves the active list once the
    // sweep has passed its right end by more than the margin.
    const B_BIT: u32 = 1 << 31;
    let events = &mut s.events;
    events.clear();
    for (i, e) in ba.iter().enumerate() {
        events.push(u128::from(sort_key(e.b[0])) << 32 | i as u128);
    }
    for (j, e) in bb.iter().enumerate() {
        events.push(u128::from(sort_key(e.b[0])) << 32 | (j as u32 | B_BIT) as u128);
    }
    events.sort_unstable();
    let (active_a, active_b) = (&mut s.active_a, &mut s.active_b);
    active_a.clear();
    active_b.clear();
    for &ev in events.iter() {
        let id = ev as u32;
        if id & B_BIT == 0 {
            let ea = &ba[id as usize];
            let x = ea.b[0];
            active_b.retain(|j| bb[*j as usize].b[1] + m >= x);
            for &j in active_b.iter() {
                let eb = &bb[j as usize];
                if boxes_near(&ea.b, &eb.b, m) {
                    pair(ea, eb, m, cross)?;
                }
            }
            active_a.push(id);
        } else {
            let j = id & !B_BIT;
            let eb = &bb[j as usize];
            let x = eb.b[0];
            active_a.retain(|i| ba[*i as usize].b[1] + m >= x);
            for &i in active_a.iter() {
                let ea = &ba[i as usize];
                if boxes_near(&ea.b, &eb.b, m) {
                    pair(ea, eb, m, cross)?;
                }
            }
            active_b.push(j);
        }
    }
    Some(())
}

/// Whether two boxes come within `m` of each other.
#[inline]
fn boxes_near(a: &[f64; 4], b: &[f64; 4], m: f64) -> bool {
    a[0] <= b[1] + m && b[0] <= a[1] + m && a[2] <= b[3] + m && b[2] <= a[3] + m
}

/// One edge pair: nothing, a proper crossing (recorded), or `None` for anything near a contact.
#[inline]
fn pair(
    &EdgeBox {
        p0, p1, edge: i, ..
    }: &EdgeBox,
    &EdgeBox {
        p0: q0,
        p1: q1,
        edge: j,
        ..
    }: &EdgeBox,
    m: f64,
    out: &mut SmallVec<[Crossing; 16]>,
) -> Option<()> {
    // `|orient(e0, e1, v)| / |e1 - e0|` is the distance of `v` from the line; `|dx| + |dy|`
    // bounds the length from above, so `near` errs towards bailing out.
    let near = |o: f64, e0: DVec2, e1: DVec2| {
        let d = (e1 - e0).abs();
        o.abs() <= m * (d.x + d.y)
    };
    let oq0 = orient(p0, p1, q0);
    let oq1 = orient(p0, p1, q1);
    if near(oq0, p0, p1) || near(oq1, p0, p1) {
        return None;
    }
    if (oq0 > 0.0) == (oq1 > 0.0) {
        return Some(());
    }
    let op0 = orient(q0, q1, p0);
    let op1 = orient(q0, q1, p1);
    if near(op0, q0, q1) || near(op1, q0, q1) {
        return None;
    }
    if (op0 > 0.0) == (op1 > 0.0) {
        return Some(());
    }
    let p = crossing_point([p0, p1, q0, q1], [op0, op1, oq0, oq1]);
    let (ta, tb) = (edge_param(p0, p1, p), edge_param(q0, q1, p));
    // The robust path drops a crossing that rounds onto or beyond an end; never here, since
    // the ends are far from the other edge, but checked rather than assumed.
    if !(ta > 0.0 && ta < 1.0 && tb > 0.0 && tb < 1.0) {
        return None;
    }
    out.push(Crossing {
        ea: i,
        eb: j,
        ta,
        tb,
        p,
        a_in: op1 > 0.0,
        b_in: oq1 > 0.0,
        pos_a: NONE,
        pos_b: NONE,
    });
    Some(())
}

/// `None` when two crossings are within `m` of each other.
fn crossings_apart(
    cross: &mut SmallVec<[Crossing; 16]>,
    order: &mut SmallVec<[u128; 16]>,
    m: f64,
) -> Option<()> {
    let m2 = m * m;
    let close = |x: &Crossing, y: &Crossing| (x.p - y.p).length_squared() <= m2;
    if cross.len() <= 16 {
        for (k, x) in cross.iter().enumerate() {
            if cross[k + 1..].iter().any(|y| close(x, y)) {
                return None;
            }
        }
        return Some(());
    }
    order.clear();
    for (i, c) in cross.iter().enumerate() {
        order.push(u128::from(sort_key(c.p.x)) << 32 | i as u128);
    }
    order.sort_unstable();
    for (k, &i) in order.iter().enumerate() {
        let x = &cross[i as u32 as usize];
        for &j in &order[k + 1..] {
            let y = &cross[j as u32 as usize];
            if y.p.x - x.p.x > m {
                break;
            }
            if close(x, y) {
                return None;
            }
        }
    }
    Some(())
}

/// Builds one operand's split point list: each vertex followed by the crossings on its edge in
/// order of their parameter, exactly as the robust path's insertion does.
fn split(
    out: &mut SplitRings,
    r: &Rings,
    cross: &mut SmallVec<[Crossing; 16]>,
    order: &mut SmallVec<[u128; 16]>,
    side_b: bool,
) -> Option<()> {
    let key = |c: &Crossing| if side_b { (c.eb, c.tb) } else { (c.ea, c.ta) };
    // Sorted by edge, then parameter: one packed integer key per crossing.
    order.clear();
    for (i, c) in cross.iter().enumerate() {
        let (e, t) = key(c);
        order.push(u128::from(e) << 96 | u128::from(sort_key(t)) << 32 | i as u128);
    }
    order.sort_unstable();
    // Equal parameters on one edge would leave the order to the index; never in generic
    // position (the crossings are apart), but checked.
    for w in order.windows(2) {
        if w[0] >> 32 == w[1] >> 32 {
            return None;
        }
    }
    out.clear();
    out.reserve(r.pts.len() + cross.len());
    let mut k = 0usize;
    let mut start = 0usize;
    let node = |p: DVec2, xid: u32| Node {
        p,
        xid,
        next: 0,
        prev: 0,
        sel: false,
        used: false,
    };
    for &end in &r.ends {
        let end = end as usize;
        let first = out.len();
        for e in start..end {
            out.push(node(r.pts[e], NONE));
            while let Some(&c) = order.get(k) {
                let c = c as u32;
                let x = &mut cross[c as usize];
                if key(x).0 as usize != e {
                    break;
                }
                k += 1;
                let pos = out.len() as u32;
                if side_b {
                    x.pos_b = pos;
                } else {
                    x.pos_a = pos;
                }
                out.push(node(x.p, c));
            }
        }
        let last = out.len() - 1;
        for (q, n) in out[first..].iter_mut().enumerate() {
            let q = first + q;
            n.next = if q == last { first } else { q + 1 } as u32;
            n.prev = if q == first { last } else { q - 1 } as u32;
        }
        start = end;
    }
    Some(())
}

/// At every crossing, the robust pass 2 test of the split edges meeting there (which share that
/// endpoint): each pair must be far from collinear, with margin.
fn transversal(s: &Scratch, m: f64) -> Option<()> {
    let (sa, sb): (&[Node], &[Node]) = (&s.sa, &s.sb);
    for c in &s.cross {
        let (na, nb) = (&sa[c.pos_a as usize], &sb[c.pos_b as usize]);
        let x = c.p;
        for u in [sa[na.prev as usize].p, sa[na.next as usize].p] {
            for w in [sb[nb.prev as usize].p, sb[nb.next as usize].p] {
                let d = (u - x).abs() + (w - x).abs();
                if orient(x, u, w).abs() <= m * (d.x + d.y) {
                    return None;
                }
            }
        }
    }
    Some(())
}

/// Labels the split edges of one operand (inside the other operand or not) and selects those
/// that bound the result of `op`; `None` if the crossings along a contour do not alternate.
fn label(
    sr: &mut SplitRings,
    cross: &[Crossing],
    other: &Rings,
    side_b: bool,
    op: BoolOp,
) -> Option<()> {
    let sr: &mut [Node] = sr;
    let n = sr.len();
    // Which status is selected: inside for intersection (and B's part of the difference, which
    // is walked reversed), outside for union and A's part of the difference.
    let keep_inside = match op {
        BoolOp::Intersection => true,
        BoolOp::Difference => side_b,
        BoolOp::Union | BoolOp::Xor => false,
    };
    let inside_after = |xid: u32| {
        let c = &cross[xid as usize];
        if side_b { c.b_in } else { c.a_in }
    };
    let mut first = 0usize;
    while first < n {
        // The ring starting at `first` ends where `next` wraps back to it.
        let last = sr[first].prev as usize;
        let ring = &mut sr[first..=last];
        match ring.iter().position(|x| x.xid != NONE) {
            None => {
                let p = ring[0].p;
                let mut w = 0;
                let mut start = 0usize;
                for &end in &other.ends {
                    w += winding(&other.pts[start..end as usize], p);
                    start = end as usize;
                }
                let keep = (w != 0) == keep_inside;
                ring.iter_mut().for_each(|x| x.sel = keep);
            }
            Some(f) => {
                // Statuses change only at crossings, alternating; walk once around from the
                // first crossing.
                let first_in = inside_after(ring[f].xid);
                let mut inside = first_in;
                let len = ring.len();
                for q in (f..len).chain(0..f) {
                    let x = &mut ring[q];
                    if x.xid != NONE && q != f {
                        let now = inside_after(x.xid);
                        if now == inside {
                            return None;
                        }
                        inside = now;
                    }
                    x.sel = inside == keep_inside;
                }
                // Back at the first crossing: the last one must hand over to it.
                if inside == first_in {
                    return None;
                }
            }
        }
        first = last + 1;
    }
    Some(())
}

/// Node identity for closing loops: crossings are shared by both operands, vertices belong to
/// one.
#[inline]
fn node_id(r: &[Node], side_b: bool, k: usize) -> u32 {
    const A_BIT: u32 = 1 << 30;
    const B_BIT: u32 = 1 << 31;
    let x = r[k].xid;
    if x != NONE {
        x
    } else if side_b {
        B_BIT | k as u32
    } else {
        A_BIT | k as u32
    }
}

/// Links the selected edges into contours, in the robust tracing's order: each loop starts at
/// the first unused selected edge (A's split edges in order, then B's) and follows the one
/// selected edge out of every point.
fn walk(s: &mut Scratch, op: BoolOp, scale: f64) -> Option<Vec<Contour>> {
    // B's part of a difference is walked against its direction: B's edge `e` then runs from
    // point `next[e]` to point `e`.
    let rev_b = op == BoolOp::Difference;
    let Scratch {
        sa,
        sb,
        cross,
        path,
        ..
    } = s;
    let (sa, sb, cross): (&mut [Node], &mut [Node], &[Crossing]) = (sa, sb, cross);
    let total = sa.len() + sb.len();
    let mut steps = 0usize;
    let mut contours = Vec::new();
    for side_b in [false, true] {
        let len = if side_b { sb.len() } else { sa.len() };
        for e0 in 0..len {
            let r: &[Node] = if side_b { sb } else { sa };
            if !r[e0].sel || r[e0].used {
                continue;
            }
            let k0 = if side_b && rev_b {
                r[e0].next as usize
            } else {
                e0
            };
            let start = node_id(r, side_b, k0);
            path.clear();
            path.push(r[k0].p);
            let (mut side, mut e) = (side_b, e0);
            loop {
                steps += 1;
                if steps > total {
                    return None;
                }
                let r: &mut [Node] = if side { sb } else { sa };
                r[e].used = true;
                let k = if side && rev_b { e } else { r[e].next as usize };
                if node_id(r, side, k) == start {
                    break;
                }
                path.push(r[k].p);
                // Candidate edges out of this point: the own operand's next edge, and at a
                // crossing the other operand's; exactly one must be selected and unused.
                let x = r[k].xid;
                let (ka, kb) = match (x != NONE, side) {
                    (true, _) => {
                        let c = &cross[x as usize];
                        (c.pos_a as usize, c.pos_b as usize)
                    }
                    (false, false) => (k, usize::MAX),
                    (false, true) => (usize::MAX, k),
                };
                let free = |n: &Node| n.sel && !n.used;
                let ca = ka != usize::MAX && free(&sa[ka]);
                let eb = match (kb != usize::MAX, rev_b) {
                    (false, _) => usize::MAX,
                    (true, false) => kb,
                    (true, true) => sb[kb].prev as usize,
                };
                let cb = eb != usize::MAX && free(&sb[eb]);
                (side, e) = match (ca, cb) {
                    (true, false) => (false, ka),
                    (false, true) => (true, eb),
                    _ => return None,
                };
            }
            if let Some(c) = regularize(path.iter().copied(), scale) {
                contours.push(c);
            }
        }
    }
    Some(contours)
}
