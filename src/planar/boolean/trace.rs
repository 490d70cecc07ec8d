//! Phase 3: select the labelled edges that bound the result and link them into contours.
//!
//! Greiner and Hormann (1998, section 3.3) walk from an entry intersection along one polygon
//! until the next intersection, then switch polygons. With the per-edge labels of phase 2 the same
//! walk is "follow the selected edges": which edges of which operand bound the result, and in
//! which direction, is a table per operation (FHP 2019, section 4, gives the same rules for
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

use super::label::Status;
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

type Edges = SmallVec<[(DVec2, DVec2); 64]>;

/// Collects the directed result edges of both operands for `op`.
pub(crate) fn select(
    a: &Rings,
    a_nxt: &[u32],
    sa: &[Status],
    b: &Rings,
    b_nxt: &[u32],
    sb: &[Status],
    op: BoolOp,
    out: &mut Edges,
) {
    out.clear();
    for (i, &n) in a_nxt.iter().enumerate() {
        let e = (a.pts[i], a.pts[n as usize]);
        let keep = match (op, sa[i]) {
            (BoolOp::Intersection, Status::Inside | Status::SharedSame) => Some(false),
            (BoolOp::Union, Status::Outside | Status::SharedSame) => Some(false),
            (BoolOp::Difference, Status::Outside | Status::SharedOpposite) => Some(false),
            (BoolOp::Xor, Status::Outside) => Some(false),
            (BoolOp::Xor, Status::Inside) => Some(true),
            _ => None,
        };
        match keep {
            Some(false) => out.push(e),
            Some(true) => out.push((e.1, e.0)),
            None => {}
        }
    }
    for (i, &n) in b_nxt.iter().enumerate() {
        let e = (b.pts[i], b.pts[n as usize]);
        let keep = match (op, sb[i]) {
            (BoolOp::Intersection, Status::Inside) => Some(false),
            (BoolOp::Union, Status::Outside) => Some(false),
            (BoolOp::Difference, Status::Inside) => Some(true),
            (BoolOp::Xor, Status::Outside) => Some(false),
            (BoolOp::Xor, Status::Inside) => Some(true),
            _ => None,
        };
        match keep {
            Some(false) => out.push(e),
            Some(true) => out.push((e.1, e.0)),
            None => {}
        }
    }
}

fn cmp_pt(a: DVec2, b: DVec2) -> core::cmp::Ordering {
    a.x.total_cmp(&b.x).then(a.y.total_cmp(&b.y))
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
pub(crate) fn trace(edges: &Edges, scale: f64) -> Result<Vec<Contour>, GeomError> {
    let n = edges.len();
    let mut order: SmallVec<[u32; 64]> = (0..n as u32).collect();
    order.sort_unstable_by(|&x, &y| cmp_pt(edges[x as usize].0, edges[y as usize].0));
    let mut used: SmallVec<[bool; 64]> = SmallVec::from_elem(false, n);
    let mut out = Vec::new();
    let mut ring: SmallVec<[DVec2; 64]> = SmallVec::new();
    for s in 0..n {
        if used[s] {
            continue;
        }
        ring.clear();
        let start = edges[s].0;
        let mut cur = s;
        let mut closed = false;
        // Each step uses one edge, so `n` steps bound the walk.
        for _ in 0..n {
            used[cur] = true;
            let (from, v) = edges[cur];
            ring.push(from);
            if v == start {
                closed = true;
                break;
            }
            let lo = order
                .partition_point(|&k| cmp_pt(edges[k as usize].0, v) == core::cmp::Ordering::Less);
            let mut best: Option<usize> = None;
            for &k in order[lo..]
                .iter()
                .take_while(|&&k| edges[k as usize].0 == v)
            {
                let k = k as usize;
                if used[k] {
                    continue;
                }
                best = match best {
                    Some(b) if !further_left(from, v, edges[k].1, edges[b].1) => Some(b),
                    _ => Some(k),
                };
            }
            match best {
                Some(b) => cur = b,
                None => break,
            }
        }
        if !closed {
            return Err(GeomError::Degenerate(
                "result boundary does not close; the operands are too close to degenerate for f64",
            ));
        }
        split_and_emit(&ring, scale, &mut out);
    }
    Ok(out)
}

/// Cuts a closed walk at repeated points into simple loops, regularizes each and emits it.
fn split_and_emit(walk: &[DVec2], scale: f64, out: &mut Vec<Contour>) {
    let mut stack: SmallVec<[SmallVec<[DVec2; 32]>; 4]> = SmallVec::new();
    stack.push(walk.iter().copied().collect());
    // Every cut removes at least one point from the loop being cut, so this terminates; the
    // counter is a belt-and-braces bound.
    let mut budget = 4 * walk.len() + 4;
    while let Some(mut lp) = stack.pop() {
        if budget == 0 {
            break;
        }
        budget -= 1;
        match find_repeat(&lp) {
            Some((i, j)) => {
                let inner: SmallVec<[DVec2; 32]> = lp[i..j].iter().copied().collect();
                lp.drain(i..j);
                stack.push(inner);
                stack.push(lp);
            }
            None => {
                if let Some(c) = regularize(lp, scale) {
                    out.push(c);
                }
            }
        }
    }
}

/// Two positions `i < j` holding the same point, if any.
fn find_repeat(lp: &[DVec2]) -> Option<(usize, usize)> {
    let mut idx: SmallVec<[u32; 64]> = (0..lp.len() as u32).collect();
    idx.sort_unstable_by(|&x, &y| cmp_pt(lp[x as usize], lp[y as usize]).then(x.cmp(&y)));
    idx.windows(2).find_map(|w| {
        let (x, y) = (w[0] as usize, w[1] as usize);
        (lp[x] == lp[y]).then_some((x.min(y), x.max(y)))
    })
}

/// Removes repeated and exactly collinear points, then drops the loop if it bounds no area or
/// only a sliver.
fn regularize(mut pts: SmallVec<[DVec2; 32]>, scale: f64) -> Option<Contour> {
    // Each pass removes a point or stops.
    loop {
        let n = pts.len();
        if n < 3 {
            return None;
        }
        let mut removed = false;
        for i in 0..n {
            let a = pts[(i + n - 1) % n];
            let b = pts[i];
            let c = pts[(i + 1) % n];
            if a == b || orient(a, b, c) == 0.0 {
                pts.remove(i);
                removed = true;
                break;
            }
        }
        if !removed {
            break;
        }
    }
    let area2 = signed_area2(&pts);
    let n = pts.len();
    let perimeter: f64 = (0..n)
        .map(|i| sqrt((pts[(i + 1) % n] - pts[i]).length_squared()))
        .sum();
    if area2 == 0.0 || area2.abs() <= SLIVER_REL * scale * perimeter {
        return None;
    }
    Some(Contour {
        pts: pts.into_vec(),
    })
}
