//! Phase 3: select the labelled edges that bound the result and link them into contours.
//!
//! Greiner and Hormann (1998, section 3.3) walk from an entry intersection along one polygon
//! until the next intersection, then switch polygons. With the per-edge labels of phase 2 the same
//! walk is "follow the selected edges": which edges of which operand bound the result, and in
//! which direction, is a table per operation (FHP 2019, tracing phase, gives the same rules for
//! overlapping edges: a chain shared in the same direction belongs to union and intersection, one
//! shared in opposite directions to the difference only):
//!
//! | op           | A inside B | A outside B | B inside A | B outside A | shared same | shared opposite |
//! |--------------|------------|-------------|------------|-------------|-------------|-----------------|
//! | intersection | keep       |             | keep       |             | keep once   |                 |
//! | union        |            | keep        |            | keep        | keep once   |                 |
//! | difference   |            | keep        | reversed   |             |             | keep A's        |
//! | xor          | reversed   | keep        | reversed   | keep        |             |                 |
//!
//! Every selected edge has the result's interior on its left, and at every vertex as many selected
//! edges leave as arrive, so the walk always closes. Where several selected edges leave one vertex
//! (the result touches itself there: FHP's vertex-on-vertex case), the walk takes the leftmost
//! turn, and any loop that still visits a vertex twice is cut there into simple loops. Finally the
//! result is regularized: repeated and exactly collinear points (the former intersection vertices
//! in the middle of a straight run, spikes) are removed, and loops that enclose no area, or only a
//! sliver thinner than [`SLIVER_REL`] of the coordinate scale, are dropped.

use alloc::vec::Vec;
use glam::DVec2;
use smallvec::SmallVec;

use super::label::{Nodes, Status};
use super::{BoolOp, Rings};
use crate::GeomError;
use crate::math::sqrt;
use crate::planar::contour::Contour;
use crate::planar::predicates::{orient, orient_sign, signed_area2};

/// Loops whose mean width (twice the area over the perimeter) is below this fraction of the
/// coordinate scale are dropped as slivers: `256 * f64::EPSILON` (about `5.7e-14`). Such a loop is
/// thinner than the rounding error of the intersection points that bound it, so it is an
/// artifact of `f64`, not part of the true result.
pub const SLIVER_REL: f64 = 256.0 * f64::EPSILON;

/// A selected, directed result edge: nodes (see [`Nodes`]) and points of its ends.
#[derive(Clone, Copy)]
pub(crate) struct Edge {
    from: u32,
    to: u32,
    p: DVec2,
    q: DVec2,
}

impl Edge {
    /// A directed edge from node `from` at `p` to node `to` at `q`.
    pub(crate) fn new(from: u32, to: u32, p: DVec2, q: DVec2) -> Edge {
        Edge { from, to, p, q }
    }
}

pub(crate) type Edges = SmallVec<[Edge; 64]>;

/// Collects the directed result edges of both operands for `op`.
#[allow(clippy::too_many_arguments)]
pub(crate) fn select(
    a: &Rings,
    a_nxt: &[u32],
    sa: &[Status],
    b: &Rings,
    b_nxt: &[u32],
    sb: &[Status],
    nodes: &Nodes,
    op: BoolOp,
    out: &mut Edges,
) {
    out.clear();
    for (side_b, r, nxt, st) in [(false, a, a_nxt, sa), (true, b, b_nxt, sb)] {
        for (i, &n) in nxt.iter().enumerate() {
            let keep = match (op, side_b, st[i]) {
                (BoolOp::Intersection, _, Status::Inside) => Some(false),
                (BoolOp::Intersection, false, Status::SharedSame) => Some(false),
                (BoolOp::Union, _, Status::Outside) => Some(false),
                (BoolOp::Union, false, Status::SharedSame) => Some(false),
                (BoolOp::Difference, false, Status::Outside | Status::SharedOpposite) => {
                    Some(false)
                }
                (BoolOp::Difference, true, Status::Inside) => Some(true),
                (BoolOp::Xor, _, Status::Outside) => Some(false),
                (BoolOp::Xor, _, Status::Inside) => Some(true),
                _ => None,
            };
            let n = n as usize;
            let (u, w) = (nodes.of(i, side_b), nodes.of(n, side_b));
            match keep {
                Some(false) => out.push(Edge {
                    from: u,
                    to: w,
                    p: r.pts[i],
                    q: r.pts[n],
                }),
                Some(true) => out.push(Edge {
                    from: w,
                    to: u,
                    p: r.pts[n],
                    q: r.pts[i],
                }),
                None => {}
            }
        }
    }
}

/// Rank of the turn `prev -> v -> n` for the leftmost-turn rule: smaller is further left.
/// Directions are ordered by clockwise angle from the backward direction `prev - v`.
fn turn_class(prev: DVec2, v: DVec2, n: DVec2) -> u8 {
    match orient_sign(v, prev, n) {
        -1 => 0,
        1 => 2,
        _ => {
            // Collinear: straight on (class 1) or straight back (a spike, last resort).
            let d = prev - v;
            let same = if d.x.abs() >= d.y.abs() {
                (prev.x > v.x) == (n.x > v.x)
            } else {
                (prev.y > v.y) == (n.y > v.y)
            };
            if same { 3 } else { 1 }
        }
    }
}

/// Whether candidate `n1` is a further-left turn than `n2` after arriving at `v` from `prev`.
fn further_left(prev: DVec2, v: DVec2, n1: DVec2, n2: DVec2) -> bool {
    let (c1, c2) = (turn_class(prev, v, n1), turn_class(prev, v, n2));
    if c1 != c2 {
        return c1 < c2;
    }
    // Same half-plane: n1 comes first clockwise iff n2 is clockwise of n1.
    orient(v, n1, n2) < 0.0
}

/// Links the selected edges into regularized contours.
///
/// The walk keeps the position of each node on the current path; arriving at a node already on
/// the path closes a simple loop there, which is emitted at once. So a boundary that touches
/// itself (FHP's vertex-on-vertex contacts in the result) comes out as separate simple contours
/// meeting at a point, never as one contour visiting a point twice.
pub(crate) fn trace(
    edges: &Edges,
    node_count: usize,
    scale: f64,
) -> Result<Vec<Contour>, GeomError> {
    let n = edges.len();
    // Out-edges per node, in compressed rows.
    let mut first: SmallVec<[u32; 128]> = SmallVec::from_elem(0, node_count + 1);
    for e in edges {
        if let Some(c) = first.get_mut(e.from as usize + 1) {
            *c += 1;
        }
    }
    for k in 1..first.len() {
        first[k] += first[k - 1];
    }
    let mut fill: SmallVec<[u32; 128]> = first.clone();
    let mut out_edges: SmallVec<[u32; 64]> = SmallVec::from_elem(0, n);
    for (k, e) in edges.iter().enumerate() {
        let slot = &mut fill[e.from as usize];
        out_edges[*slot as usize] = k as u32;
        *slot += 1;
    }
    let mut used: SmallVec<[bool; 64]> = SmallVec::from_elem(false, n);
    // Position + 1 of each node on the current path (0: not on it).
    let mut on_path: SmallVec<[u32; 128]> = SmallVec::from_elem(0, node_count);
    // The path as (node, point) pairs, and the edge that left each (for the turn rule).
    let mut path: SmallVec<[(u32, DVec2); 64]> = SmallVec::new();
    let mut contours = Vec::new();
    let mut steps = 0usize;
    for s in 0..n {
        if used[s] {
            continue;
        }
        let start = edges[s];
        path.clear();
        path.push((start.from, start.p));
        on_path[start.from as usize] = 1;
        let mut cur = s;
        loop {
            // Each iteration uses one edge, so `n` iterations bound the whole trace.
            steps += 1;
            if steps > n {
                return Err(GeomError::Undecidable(
                    "result boundary tracing did not terminate; the operands are too close to \
                     degenerate for f64",
                ));
            }
            used[cur] = true;
            let e = edges[cur];
            let pos = on_path[e.to as usize];
            if pos != 0 {
                // Closed a loop: emit path[pos-1..], keep the path up to the repeated node.
                let keep = pos as usize;
                for &(node, _) in &path[keep..] {
                    on_path[node as usize] = 0;
                }
                if let Some(c) = regularize(path[keep - 1..].iter().map(|x| x.1), scale) {
                    contours.push(c);
                }
                path.truncate(keep);
            } else {
                path.push((e.to, e.q));
                on_path[e.to as usize] = path.len() as u32;
            }
            // Choose the next edge out of the current node (the end of the path).
            let Some(&(v_node, v)) = path.last() else {
                break;
            };
            let lo = first[v_node as usize] as usize;
            let hi = first[v_node as usize + 1] as usize;
            let mut best: Option<usize> = None;
            for &k in &out_edges[lo..hi] {
                let k = k as usize;
                if used[k] {
                    continue;
                }
                best = match best {
                    Some(b) if !further_left(e.p, v, edges[k].q, edges[b].q) => Some(b),
                    _ => Some(k),
                };
            }
            match best {
                Some(b) => cur = b,
                None if path.len() == 1 => {
                    on_path[v_node as usize] = 0;
                    break;
                }
                None => {
                    return Err(GeomError::Undecidable(
                        "result boundary does not close; the operands are too close to \
                         degenerate for f64",
                    ));
                }
            }
        }
    }
    Ok(contours)
}

/// Removes repeated and exactly collinear points (spikes included) in one stack pass, then drops
/// the loop if it bounds no area or only a sliver.
pub(crate) fn regularize(pts: impl Iterator<Item = DVec2>, scale: f64) -> Option<Contour> {
    // Scratch on the stack; the output contour is allocated once, at its final size, and only
    // if it survives.
    let mut out: SmallVec<[DVec2; 32]> = SmallVec::new();
    for p in pts {
        while let [.., a, b] = out[..] {
            if b == p || orient(a, b, p) == 0.0 {
                out.pop();
            } else {
                break;
            }
        }
        if out.last() != Some(&p) {
            out.push(p);
        }
    }
    // Fix the seam between the end and the start (bounded: each round removes a point).
    loop {
        let n = out.len();
        if n < 3 {
            return None;
        }
        if out[n - 1] == out[0] || orient(out[n - 2], out[n - 1], out[0]) == 0.0 {
            out.pop();
        } else if orient(out[n - 1], out[0], out[1]) == 0.0 {
            out.remove(0);
        } else {
            break;
        }
    }
    survives(&out, scale).then(|| Contour { pts: out.to_vec() })
}

/// [`survives`] with a square-root-free test first: the perimeter is at most the sum of the
/// edges' `|dx| + |dy|`, so an area above [`SLIVER_REL`] times the scale times that sum passes
/// without measuring the perimeter.
pub(crate) fn clearly_survives(pts: &[DVec2], scale: f64) -> bool {
    let n = pts.len();
    let l1: f64 = pts
        .windows(2)
        .map(|w| (w[0], w[1]))
        .chain(core::iter::once((pts[n - 1], pts[0])))
        .map(|(p, q)| {
            let d = (q - p).abs();
            d.x + d.y
        })
        .sum();
    let area2 = signed_area2(pts).abs();
    area2 > SLIVER_REL * scale * l1 || survives(pts, scale)
}

/// Whether a loop without repeated or collinear consecutive points bounds more than a sliver:
/// nonzero area, and more than [`SLIVER_REL`] times the scale per unit of perimeter.
pub(crate) fn survives(out: &[DVec2], scale: f64) -> bool {
    let area2 = signed_area2(out);
    let n = out.len();
    // Edges in order, the closing one last (no `%` per edge).
    let perimeter: f64 = out
        .windows(2)
        .map(|w| (w[0], w[1]))
        .chain(core::iter::once((out[n - 1], out[0])))
        .map(|(p, q)| sqrt((q - p).length_squared()))
        .sum();
    !(area2 == 0.0 || area2.abs() <= SLIVER_REL * scale * perimeter)
}
