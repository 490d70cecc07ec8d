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
//! It reads the operands' contours in place (no copy) and keeps only the crossings: each
//! knows its edge and parameter on both operands and, once the crossings are ordered along
//! each operand's contours (`link`), its neighbours there. The walk copies the runs of operand
//! vertices between consecutive crossings straight from the contours.
//!
//! # The fast path never disagrees with the robust path
//!
//! The robust pipeline (`intersect` -> `label` -> `trace`) is the definition of the result; the
//! fast path only skips work that is provably a no-op there, and produces the same contours bit
//! for bit (same points, same starting points, same order). Precisely, it runs only when:
//!
//! - no two vertices of the operands are within the snapping distance, so `intersect::weld`
//!   would change nothing (within an operand the caller checks the shape's minimum vertex
//!   separation, cached by `Shape::new`; across the operands such a pair is near the other's
//!   edges and fails the next condition), and no vertex of an operand lies exactly on an edge of
//!   another contour of the same operand (`split_self_contacts` would insert it; also a cached
//!   fact of the shape);
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
//! - along every contour the crossings alternate between entry and exit, no two share an edge
//!   parameter, every crossing has exactly one selected way out during the walk, and the walk
//!   meets every crossing exactly once (always true in generic position; checked rather than
//!   assumed).
//!
//! Under these conditions the robust labels equal the crossing signs used here (the local wedge
//! test at a transversal crossing reduces to the side of the other edge's line), every node of
//! the selected edges has one edge in and one out, so the robust walk's leftmost-turn choice is
//! forced, and the walk here visits edges in the same order, starting each loop at the first
//! unused selected edge in the same order (A's split edges, then B's). Each loop is then
//! regularized with the result of `trace::regularize` (`regularize_walked` skips the turn tests
//! that are already known to pass). `tests/planar_fast.rs` checks the agreement on random,
//! degenerate and near-degenerate inputs, on results of earlier operations, and that the fast
//! path does bail out on the degenerate ones.
//!
//! Symmetric difference is left to the robust path: all four edges at each of its crossings are
//! selected, so its walk needs the leftmost-turn rule and the loop cutting of `trace`.

use alloc::vec::Vec;
use glam::DVec2;
use smallvec::SmallVec;

use super::BoolOp;
use super::intersect::{SNAP_REL, crossing_point, edge_param, sort_key};
use super::trace::{regularize, survives};
use crate::planar::contour::Contour;
use crate::planar::predicates::{orient, winding};
use crate::planar::shape::Shape;

/// How many snapping distances every test of the fast path keeps from the robust path's
/// thresholds. The robust decisions are made on exact orientations of points whose computed
/// crossings are off by a few ulps of the coordinate scale (much less than one snapping
/// distance, `64 * f64::EPSILON` of it); a factor of 4 leaves room for that rounding and for the
/// `|dx| + |dy|` over-estimate of an edge's length.
const MARGIN: f64 = 4.0;

/// Operand pairs with at most this many vertex pairs are intersected by testing all edge
/// pairs; larger ones by a sweep over the edges' x-ranges (sorting costs more than it saves
/// below this).
const ALL_PAIRS_MAX: usize = 256;

/// Operand pairs with more than this many vertex pairs first drop the edges that are not near
/// the other operand's bounding box.
const FILTER_MIN: usize = 64;

/// One proper crossing of an edge of A with an edge of B.
#[derive(Clone, Copy)]
struct Crossing {
    p: DVec2,
    /// Parameters along the two edges (as the robust path computes them, for the same order).
    ta: f64,
    tb: f64,
    /// Contour of A and edge in it (the index of the edge's first vertex); the same for B.
    ca: u32,
    ia: u32,
    cb: u32,
    ib: u32,
    /// The edges' numbers over all contours of their operand (contour by contour), for the
    /// order along the operands.
    ga: u32,
    gb: u32,
    /// Whether A's boundary leaving the crossing runs inside B (A's far end is left of B's
    /// edge, where B's interior is).
    a_in: bool,
    /// Whether B's boundary leaving the crossing runs inside A.
    b_in: bool,
    /// Next and previous crossing along A's contour and along B's (cyclic), as indices into the
    /// crossing list.
    na: u32,
    pa: u32,
    nb: u32,
    pb: u32,
    /// Whether the crossing is the first along its contour of A (of B): the boundary from the
    /// previous crossing to this one passes the contour's vertex 0.
    first_a: bool,
    first_b: bool,
    /// Whether the walk has passed the crossing.
    visited: bool,
}

/// An edge for the pair search: bounding box `[min x, max x, min y, max y]`, its ends, the
/// near-line threshold for orientations against it, its contour and index there.
#[derive(Clone, Copy)]
struct EdgeBox {
    b: [f64; 4],
    p0: DVec2,
    p1: DVec2,
    /// `m * (|dx| + |dy|)`: `|orient(p0, p1, v)| / |p1 - p0|` is the distance of `v` from the
    /// line and `|dx| + |dy|` bounds the length from above, so comparing `|orient|` with this
    /// errs towards bailing out.
    near: f64,
    c: u32,
    i: u32,
    /// The edge's number over all contours of its operand.
    g: u32,
}

impl EdgeBox {
    #[inline]
    fn new(p0: DVec2, p1: DVec2, m: f64, c: usize, i: usize, g: usize) -> EdgeBox {
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
        let d = (p1 - p0).abs();
        EdgeBox {
            b: [x0, x1, y0, y1],
            p0,
            p1,
            near: m * (d.x + d.y),
            c: c as u32,
            i: i as u32,
            g: g as u32,
        }
    }
}

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
    /// The crossings in order along A's contours and along B's.
    /// Packed keys: edge number in the high 32 bits, then the parameter's bits, then the
    /// crossing's index in the low 32.
    ord_a: SmallVec<[u128; 16]>,
    ord_b: SmallVec<[u128; 16]>,
    path: SmallVec<[DVec2; 64]>,
    /// Positions of the crossings in `path`.
    xs: SmallVec<[u32; 16]>,
}

/// Runs `a op b` in generic position, or returns `None` when the operands need the robust path
/// (see the module documentation). The caller has checked that no two vertices of one operand
/// are within the snapping distance and that neither operand has a vertex on an edge of another
/// of its own contours; `scale` is the larger coordinate magnitude of the operands.
pub(crate) fn run(
    s: &mut Scratch,
    a: &Shape,
    b: &Shape,
    op: BoolOp,
    scale: f64,
) -> Option<Vec<Contour>> {
    if op == BoolOp::Xor {
        return None;
    }
    let m = MARGIN * SNAP_REL * scale;
    s.cross.clear();
    find_crossings(s, a, b, m)?;
    crossings_apart(&mut s.cross, &mut s.order, m)?;
    link(&mut s.cross, &mut s.ord_a, false, a.contours.len() == 1)?;
    link(&mut s.cross, &mut s.ord_b, true, b.contours.len() == 1)?;
    transversal(&s.cross, a, b, m)?;
    walk(s, a, b, op, scale)
}

/// The bounding box of a shape as `[min x, max x, min y, max y]`.
fn bbox(s: &Shape) -> [f64; 4] {
    [s.facts.lo.x, s.facts.hi.x, s.facts.lo.y, s.facts.hi.y]
}

/// Edge `i` of a ring: its first vertex and the next one.
#[inline]
fn edge(pts: &[DVec2], i: usize) -> (DVec2, DVec2) {
    (pts[i], pts[if i + 1 == pts.len() { 0 } else { i + 1 }])
}

/// Fills `out` with the edges of `r` (those whose boxes come within `m` of `near`, if given);
/// with `widen`, the boxes are stored widened by `m` on every side, so that each pair test
/// against them is four comparisons.
fn edge_boxes(
    r: &Shape,
    near: Option<[f64; 4]>,
    m: f64,
    widen: bool,
    out: &mut SmallVec<[EdgeBox; 32]>,
) {
    out.clear();
    out.reserve(r.vertex_count());
    let mut g = 0;
    for (c, ring) in r.contours.iter().enumerate() {
        for i in 0..ring.pts.len() {
            let (p0, p1) = edge(&ring.pts, i);
            let mut e = EdgeBox::new(p0, p1, m, c, i, g);
            g += 1;
            if near.is_none_or(|n| boxes_near(&e.b, &n, m)) {
                if widen {
                    e.b = [e.b[0] - m, e.b[1] + m, e.b[2] - m, e.b[3] + m];
                }
                out.push(e);
            }
        }
    }
}

/// Tests every edge pair whose widened boxes overlap (all pairs for small operands, a sweep
/// over x otherwise), recording proper crossings; `None` at the first near contact.
fn find_crossings(s: &mut Scratch, a: &Shape, b: &Shape, m: f64) -> Option<()> {
    let (na, nb) = (a.vertex_count(), b.vertex_count());
    // Only edges near the other operand's bounding box can meet it (for tiny operands the
    // filter costs more than the pair tests it saves).
    let filter = na * nb > FILTER_MIN;
    let (box_a, box_b) = (bbox(a), bbox(b));
    // B's boxes are widened by the margin: a pair is tested when the boxes come within `m`.
    edge_boxes(b, filter.then_some(box_a), m, true, &mut s.boxes_b);
    let cross = &mut s.cross;
    if na * nb <= ALL_PAIRS_MAX {
        // A's edges are made on the fly: each is used once.
        let bb: &[EdgeBox] = &s.boxes_b;
        let mut g = 0;
        for (c, ring) in a.contours.iter().enumerate() {
            for i in 0..ring.pts.len() {
                let (p0, p1) = edge(&ring.pts, i);
                let ea = EdgeBox::new(p0, p1, m, c, i, g);
                g += 1;
                if filter && !boxes_near(&ea.b, &box_b, m) {
                    continue;
                }
                for eb in bb {
                    if overlap(&ea.b, &eb.b) {
                        pair(&ea, eb, cross)?;
                    }
                }
            }
        }
        return Some(());
    }
    edge_boxes(a, filter.then_some(box_b), m, false, &mut s.boxes_a);
    let (ba, bb): (&[EdgeBox], &[EdgeBox]) = (&s.boxes_a, &s.boxes_b);
    // Sweep: edges enter in order of their left ends (B's widened); an edge leaves the active
    // list once the sweep has passed its right end (B's widened).
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
    // The two branches below mirror each other (an edge of A meets the active edges of B, and
    // the other way round); written out twice so that each keeps `pair`'s argument order fixed
    // without a runtime swap in this inner loop.
    let (active_a, active_b) = (&mut s.active_a, &mut s.active_b);
    active_a.clear();
    active_b.clear();
    for &ev in events.iter() {
        let id = ev as u32;
        if id & B_BIT == 0 {
            let ea = &ba[id as usize];
            let x = ea.b[0];
            active_b.retain(|j| bb[*j as usize].b[1] >= x);
            for &j in active_b.iter() {
                let eb = &bb[j as usize];
                if overlap(&ea.b, &eb.b) {
                    pair(ea, eb, cross)?;
                }
            }
            active_a.push(id);
        } else {
            let j = id & !B_BIT;
            let eb = &bb[j as usize];
            let x = eb.b[0];
            active_a.retain(|i| ba[*i as usize].b[1] >= x);
            for &i in active_a.iter() {
                let ea = &ba[i as usize];
                if overlap(&ea.b, &eb.b) {
                    pair(ea, eb, cross)?;
                }
            }
            active_b.push(j);
        }
    }
    Some(())
}

/// Whether two boxes overlap (touching counts).
#[inline]
fn overlap(a: &[f64; 4], b: &[f64; 4]) -> bool {
    a[0] <= b[1] && b[0] <= a[1] && a[2] <= b[3] && b[2] <= a[3]
}

/// Whether two boxes come within `m` of each other.
#[inline]
fn boxes_near(a: &[f64; 4], b: &[f64; 4], m: f64) -> bool {
    a[0] <= b[1] + m && b[0] <= a[1] + m && a[2] <= b[3] + m && b[2] <= a[3] + m
}

/// One edge pair: nothing, a proper crossing (recorded), or `None` for anything near a contact.
#[inline(always)]
fn pair(e: &EdgeBox, f: &EdgeBox, out: &mut SmallVec<[Crossing; 16]>) -> Option<()> {
    let (p0, p1, q0, q1) = (e.p0, e.p1, f.p0, f.p1);
    let oq0 = orient(p0, p1, q0);
    let oq1 = orient(p0, p1, q1);
    if oq0.abs() <= e.near || oq1.abs() <= e.near {
        return None;
    }
    if (oq0 > 0.0) == (oq1 > 0.0) {
        return Some(());
    }
    let op0 = orient(q0, q1, p0);
    let op1 = orient(q0, q1, p1);
    if op0.abs() <= f.near || op1.abs() <= f.near {
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
        p,
        ta,
        tb,
        ca: e.c,
        ia: e.i,
        cb: f.c,
        ib: f.i,
        ga: e.g,
        gb: f.g,
        a_in: op1 > 0.0,
        b_in: oq1 > 0.0,
        na: 0,
        pa: 0,
        nb: 0,
        pb: 0,
        first_a: false,
        first_b: false,
        visited: false,
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

/// Orders the crossings along the contours of A (or of B, `side_b`) — by contour, edge, then
/// parameter, exactly as the robust path inserts them — and links each to its neighbours
/// along its contour. `None` if two crossings share an edge parameter (never in generic
/// position, but the order would then be arbitrary) or if the crossings along a contour do
/// not alternate between entering and leaving the other operand.
fn link(
    cross: &mut [Crossing],
    ord: &mut SmallVec<[u128; 16]>,
    side_b: bool,
    one_contour: bool,
) -> Option<()> {
    // The index field's top bit holds the entry flag, so the checks below read only the keys.
    const IN: u128 = 1 << 31;
    if cross.len() >= 1 << 31 {
        return None;
    }
    ord.clear();
    // Plain pushes: `SmallVec`'s `extend` costs more than the few elements here.
    for (k, x) in cross.iter().enumerate() {
        let (g, t, inside) = if side_b {
            (x.gb, x.tb, x.b_in)
        } else {
            (x.ga, x.ta, x.a_in)
        };
        // `t` is in (0, 1), where the bits of an `f64` order as the numbers do.
        ord.push(
            u128::from(g) << 96
                | u128::from(t.to_bits()) << 32
                | u128::from(inside) << 31
                | k as u128,
        );
    }
    let ord: &mut [u128] = ord;
    if ord.len() <= 32 {
        // Insertion sort: found along A's edges, the crossings are nearly in A's order already.
        for k in 1..ord.len() {
            let x = ord[k];
            let mut j = k;
            while j > 0 && x < ord[j - 1] {
                ord[j] = ord[j - 1];
                j -= 1;
            }
            ord[j] = x;
        }
    } else {
        ord.sort_unstable();
    }
    let idx = |k: u128| (k as u32 & !(IN as u32)) as usize;
    let n = ord.len();
    let mut g = 0;
    while g < n {
        // The crossings of one contour form a run of the order.
        let h = if one_contour {
            n
        } else {
            let contour = |k: u128| {
                let x = &cross[idx(k)];
                if side_b { x.cb } else { x.ca }
            };
            let c = contour(ord[g]);
            g + 1
                + ord[g + 1..]
                    .iter()
                    .take_while(|&&k| contour(k) == c)
                    .count()
        };
        for k in g..h {
            let next = if k + 1 == h { ord[g] } else { ord[k + 1] };
            let prev = if k == g { ord[h - 1] } else { ord[k - 1] };
            // Statuses change only at crossings: leaving inside, the boundary must enter at
            // the next crossing, and vice versa (a lone crossing fails this too). Equal
            // parameters on one edge would leave the order to the index.
            if (ord[k] ^ next) & IN == 0 || (k + 1 < h && ord[k] >> 32 == next >> 32) {
                return None;
            }
            let (next, prev) = (idx(next) as u32, idx(prev) as u32);
            let y = &mut cross[idx(ord[k])];
            if side_b {
                (y.nb, y.pb, y.first_b) = (next, prev, k == g);
            } else {
                (y.na, y.pa, y.first_a) = (next, prev, k == g);
            }
        }
        g = h;
    }
    Some(())
}

/// At every crossing, the robust pass 2 test of the split edges meeting there (which share that
/// endpoint): each pair must be far from collinear, with margin.
fn transversal(cross: &[Crossing], a: &Shape, b: &Shape, m: f64) -> Option<()> {
    for x in cross {
        // The neighbours of the crossing in the split contours: the next crossing on the same
        // edge, or else the edge's end (likewise backwards).
        let ends = |pts: &[DVec2], i: u32, first: bool, prev: u32, next: u32, b_side: bool| {
            let (p0, p1) = edge(pts, i as usize);
            let (yp, yn) = (&cross[prev as usize], &cross[next as usize]);
            let (ip, first_n, i_n) = if b_side {
                (yp.ib, yn.first_b, yn.ib)
            } else {
                (yp.ia, yn.first_a, yn.ia)
            };
            [
                if !first && ip == i { yp.p } else { p0 },
                if !first_n && i_n == i { yn.p } else { p1 },
            ]
        };
        let ua = ends(
            &a.contours[x.ca as usize].pts,
            x.ia,
            x.first_a,
            x.pa,
            x.na,
            false,
        );
        let wb = ends(
            &b.contours[x.cb as usize].pts,
            x.ib,
            x.first_b,
            x.pb,
            x.nb,
            true,
        );
        let c = x.p;
        for u in ua {
            for w in wb {
                let d = (u - c).abs() + (w - c).abs();
                if orient(c, u, w).abs() <= m * (d.x + d.y) {
                    return None;
                }
            }
        }
    }
    Some(())
}

/// Whether `p` (not on `s`'s boundary) is inside `s`.
fn inside(p: DVec2, s: &Shape) -> bool {
    s.contours.iter().map(|c| winding(&c.pts, p)).sum::<i32>() != 0
}

/// Links the selected boundary pieces into contours, in the robust tracing's order: each loop
/// starts at the first unused selected split edge (A's split edges in order, then B's) and
/// follows the one selected edge out of every point.
///
/// Which pieces are selected: a contour without crossings whole, by whether it lies inside the
/// other operand; A's boundary after a crossing if it runs inside B for the intersection and
/// outside for union and difference; B's boundary after a crossing if it runs inside A for the
/// intersection and outside for the union; for the difference, B's boundary *before* a
/// crossing if it runs inside A (it is walked backwards), which is again when the boundary
/// after the crossing runs outside.
fn walk(s: &mut Scratch, a: &Shape, b: &Shape, op: BoolOp, scale: f64) -> Option<Vec<Contour>> {
    let inter = op == BoolOp::Intersection;
    let rev_b = op == BoolOp::Difference;
    let Scratch {
        cross,
        ord_a,
        ord_b,
        path,
        xs,
        ..
    } = s;
    let cross: &mut [Crossing] = cross;
    let idx = |k: u128| (k as u32 & !(1 << 31)) as usize;
    let mut out = Vec::new();
    let mut g = 0usize;
    for (c, ring) in a.contours.iter().enumerate() {
        let h = g + ord_a[g..]
            .iter()
            .take_while(|&&k| cross[idx(k)].ca == c as u32)
            .count();
        if g == h {
            if inside(ring.pts[0], b) == inter {
                out.extend(regularize_walked(&ring.pts, &[], scale));
            }
        } else {
            // The split edge from vertex 0 comes first in A's order: it belongs to the piece
            // after the contour's last crossing.
            let last = idx(ord_a[h - 1]);
            if cross[last].a_in == inter && !cross[last].visited {
                let w = Walk { a, b, inter, rev_b };
                w.trace(cross, Some(c as u32), idx(ord_a[g]), path, xs)?;
                out.extend(regularize_walked(path, xs, scale));
            }
            for &k in &ord_a[g..h] {
                let x = idx(k);
                if cross[x].a_in == inter && !cross[x].visited {
                    let w = Walk { a, b, inter, rev_b };
                    w.trace(cross, None, x, path, xs)?;
                    out.extend(regularize_walked(path, xs, scale));
                }
            }
        }
        g = h;
    }
    // Every crossing lies on one loop, and every loop through a crossing has a piece of A (the
    // walk changes operands at each crossing), so only B's contours without crossings are left.
    if cross.iter().any(|x| !x.visited) {
        return None;
    }
    let mut g = 0usize;
    for (c, ring) in b.contours.iter().enumerate() {
        let h = g + ord_b[g..]
            .iter()
            .take_while(|&&k| cross[idx(k)].cb == c as u32)
            .count();
        if g == h && inside(ring.pts[0], a) == (op != BoolOp::Union) {
            let pts = &ring.pts;
            if rev_b {
                // The robust walk of a reversed contour starts at vertex 1 (the far end of its
                // first split edge) and runs backwards.
                path.clear();
                path.extend(pts[..2].iter().rev().chain(pts[2..].iter().rev()).copied());
                out.extend(regularize_walked(path, &[], scale));
            } else {
                out.extend(regularize_walked(pts, &[], scale));
            }
        }
        g = h;
    }
    Some(out)
}

/// The operands and the operation of a walk.
struct Walk<'s> {
    a: &'s Shape,
    b: &'s Shape,
    inter: bool,
    rev_b: bool,
}

impl Walk<'_> {
    /// Walks one loop into `path`, with the positions of its crossings in `xs`: from crossing
    /// `c`, or, with `from_vertex0 = Some(r)`, from vertex 0 of A's contour `r` (then `c` is
    /// that contour's first crossing). `None` if a crossing has no or two selected ways out, or
    /// the walk meets a crossing twice.
    fn trace(
        &self,
        cross: &mut [Crossing],
        from_vertex0: Option<u32>,
        mut c: usize,
        path: &mut SmallVec<[DVec2; 64]>,
        xs: &mut SmallVec<[u32; 16]>,
    ) -> Option<()> {
        let (a, b, inter) = (self.a, self.b, self.inter);
        // Runs of vertices are mostly a few points long: plain pushes beat `memcpy` and
        // `SmallVec`'s `extend` there.
        let run = |path: &mut SmallVec<[DVec2; 64]>, pts: &[DVec2]| {
            for &p in pts {
                path.push(p);
            }
        };
        path.clear();
        xs.clear();
        let start = c;
        if let Some(r) = from_vertex0 {
            run(path, &a.contours[r as usize].pts[..=cross[c].ia as usize]);
        }
        loop {
            let x = &mut cross[c];
            if x.visited {
                return None;
            }
            x.visited = true;
            let x = &cross[c];
            xs.push(path.len() as u32);
            path.push(x.p);
            let (out_a, out_b) = (x.a_in == inter, x.b_in == inter);
            if out_a == out_b {
                return None;
            }
            if out_a {
                let y = &cross[x.na as usize];
                let pts = &a.contours[x.ca as usize].pts;
                let i = x.ia as usize + 1;
                if y.first_a {
                    run(path, &pts[i..]);
                    if from_vertex0 == Some(x.ca) {
                        return Some(());
                    }
                    run(path, &pts[..=y.ia as usize]);
                } else {
                    run(path, &pts[i..=y.ia as usize]);
                }
                c = x.na as usize;
            } else if self.rev_b {
                // Backwards along B: from the crossing down to the first vertex of its edge,
                // and on to the vertex after the previous crossing's edge.
                let y = &cross[x.pb as usize];
                let pts = &b.contours[x.cb as usize].pts;
                let (i, j) = (x.ib as usize, y.ib as usize + 1);
                let mut back = |pts: &[DVec2]| {
                    for &p in pts.iter().rev() {
                        path.push(p);
                    }
                };
                if x.first_b {
                    back(&pts[..=i]);
                    back(&pts[j..]);
                } else {
                    back(&pts[j..=i]);
                }
                c = x.pb as usize;
            } else {
                let y = &cross[x.nb as usize];
                let pts = &b.contours[x.cb as usize].pts;
                let i = x.ib as usize + 1;
                if y.first_b {
                    run(path, &pts[i..]);
                    run(path, &pts[..=y.ib as usize]);
                } else {
                    run(path, &pts[i..=y.ib as usize]);
                }
                c = x.nb as usize;
            }
            if from_vertex0.is_none() && c == start {
                return Some(());
            }
        }
    }
}

/// [`regularize`](super::trace::regularize) for a walked loop whose crossings are at the
/// positions `xs` (ascending), with the same result.
///
/// `regularize` keeps every point of a loop in which every three cyclically consecutive
/// points turn (exact `orient` nonzero, which also rules out repeated points), and then only
/// the sliver test is left. Most of those turns are known here: at a crossing, `transversal`
/// has checked the turn between the two split edges with margin; at a vertex between two
/// vertices, the three are consecutive in an operand's contour (forwards or backwards), which a
/// valid `Shape` never has collinear. Only a vertex next to a crossing needs its turn tested.
fn regularize_walked(pts: &[DVec2], xs: &[u32], scale: f64) -> Option<Contour> {
    let n = pts.len();
    let turns = |i: usize, j: usize, k: usize| orient(pts[i], pts[j], pts[k]) != 0.0;
    let clean = n >= 3
        && xs.iter().enumerate().all(|(k, &j)| {
            let j = j as usize;
            let (next_x, prev_x) = (
                xs.get(k + 1).copied().unwrap_or(xs[0]) as usize,
                xs[if k == 0 { xs.len() } else { k } - 1] as usize,
            );
            let jn = if j + 1 == n { 0 } else { j + 1 };
            let jp = if j == 0 { n - 1 } else { j - 1 };
            let (jnn, jpp) = (
                if jn + 1 == n { 0 } else { jn + 1 },
                if jp == 0 { n - 1 } else { jp - 1 },
            );
            (next_x == jn || turns(j, jn, jnn)) && (prev_x == jp || turns(jpp, jp, j))
        });
    if !clean {
        return regularize(pts.iter().copied(), scale);
    }
    survives(pts, scale).then(|| Contour { pts: pts.to_vec() })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pts(v: &[(f64, f64)]) -> Vec<DVec2> {
        v.iter().map(|&(x, y)| DVec2::new(x, y)).collect()
    }

    /// The turns that `regularize_walked` tests (at vertices next to a crossing) are the ones
    /// that can vanish: a vertex collinear with a neighbouring crossing must be removed
    /// exactly as `regularize` removes it.
    #[test]
    fn regularize_walked_removes_a_vertex_collinear_with_a_crossing() {
        // Crossings at positions 0 and 3; vertex (2, 0) lies on the line from the crossing
        // (1, 0) to the vertex (3, 0).
        let p = pts(&[(1.0, 0.0), (2.0, 0.0), (3.0, 0.0), (3.0, 2.0), (1.0, 2.0)]);
        let r = regularize(p.iter().copied(), 4.0).unwrap();
        assert_eq!(r.pts.len(), 4);
        let w = regularize_walked(&p, &[0, 3], 4.0).unwrap();
        assert_eq!(w, r);
        // At the seam: the crossing last, the collinear vertex first.
        let p = pts(&[(2.0, 0.0), (3.0, 0.0), (3.0, 2.0), (1.0, 2.0), (1.0, 0.0)]);
        let w = regularize_walked(&p, &[2, 4], 4.0).unwrap();
        assert_eq!(w, regularize(p.iter().copied(), 4.0).unwrap());
        assert_eq!(w.pts.len(), 4);
    }

    /// Loops that need no cleaning come back unchanged, and slivers are dropped as
    /// `regularize` drops them.
    #[test]
    fn regularize_walked_matches_regularize() {
        let p = pts(&[(0.0, 0.0), (2.0, 0.0), (2.0, 1.0), (1.0, 1.5), (0.0, 1.0)]);
        for xs in [&[][..], &[1, 3], &[0, 2], &[0, 1, 2, 3, 4]] {
            assert_eq!(
                regularize_walked(&p, xs, 2.0),
                regularize(p.iter().copied(), 2.0)
            );
        }
        let sliver = pts(&[(0.0, 0.0), (1.0, 0.0), (0.5, 1e-300)]);
        assert_eq!(regularize_walked(&sliver, &[0, 1], 1.0), None);
        assert_eq!(regularize(sliver.iter().copied(), 1.0), None);
    }
}
