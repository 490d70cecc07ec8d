//! Phase 1: find every contact between the boundaries of the two operands and split both at it.
//!
//! This is the intersection phase of Greiner and Hormann (1998, section 3.1), extended to the
//! degenerate contacts of Foster, Hormann and Popa (2019, intersection phase: "vertex on edge",
//! "vertex on vertex" and overlapping collinear edges) without perturbation. For every pair of
//! edges the four exact orientations `orient2d(p0, p1, q0)`, `orient2d(p0, p1, q1)`,
//! `orient2d(q0, q1, p0)`, `orient2d(q0, q1, p1)` decide which case applies:
//!
//! - all zero: the edges are collinear; every endpoint of one lying strictly inside the other is
//!   inserted into the other, so an overlap becomes a run of identical edges in both operands;
//! - one zero with the point strictly inside the other edge: a vertex on an edge; the vertex is
//!   inserted into the other operand verbatim (bit-identical), which is exact;
//! - strictly opposite signs on both sides: a proper crossing; the point is computed in `f64` and
//!   inserted into both operands with the same bits.
//!
//! A computed crossing within [`SNAP_REL`] times the coordinate scale of an endpoint is replaced
//! by that endpoint (this is what makes "vertex almost on edge" behave like "vertex on edge").
//! Inserting a computed or snapped point bends the split edges by a few units in the last place,
//! which can create contacts that the straight edges did not have; so the phase repeats on the
//! bent edges until nothing new is found (a fixpoint, bounded by [`MAX_PASSES`]). At the fixpoint
//! the split boundaries meet only in shared vertices, as exact predicates on the stored
//! coordinates see them, which is what the labelling phase relies on.

use glam::DVec2;
use smallvec::SmallVec;

use super::{Rings, Split};
use crate::GeomError;
use crate::math::sqrt;
use crate::planar::predicates::{orient, strictly_between};

/// Snapping distance for computed crossings, relative to the largest coordinate magnitude of the
/// two operands: `64 * f64::EPSILON` (about `1.4e-14`). A crossing computed in `f64` is off by a
/// few ulps of the coordinate scale; closer than this to an endpoint, the endpoint is used
/// instead. At the scale `1e6` of gnomonic coordinates near the horizon this is `1.4e-8`.
pub const SNAP_REL: f64 = 64.0 * f64::EPSILON;

/// Bound on the number of splitting passes. In practice the second pass finds nothing new; more
/// than a handful of passes means the input is pathological (edges almost overlapping over long
/// stretches), and the operation returns [`GeomError::Undecidable`] instead of looping.
pub const MAX_PASSES: usize = 8;

/// The vertices of both operands sorted by x, built once more than a few computed crossings
/// need a nearby vertex (the first few scan linearly, which is cheaper than sorting).
#[derive(Default)]
struct SnapIndex {
    pts: SmallVec<[DVec2; 64]>,
    built: bool,
    crossings: usize,
}

/// One point to insert into an edge, with its parameter along the edge for ordering.
#[derive(Clone, Copy)]
struct Insert {
    edge: u32,
    t: f64,
    p: DVec2,
    /// Whether the point is not exactly on the straight edge, so the split edges need re-checking.
    bent: bool,
}

type Inserts = SmallVec<[Insert; 16]>;

/// Splits both operands at all their mutual contacts.
pub(crate) fn split(a: &mut Rings, b: &mut Rings, scale: f64) -> Result<(), GeomError> {
    let snap2 = {
        let s = SNAP_REL * scale;
        s * s
    };
    let mut dirty_a: SmallVec<[bool; 64]> = SmallVec::new();
    let mut dirty_b: SmallVec<[bool; 64]> = SmallVec::new();
    let mut ins_a = Inserts::new();
    let mut ins_b = Inserts::new();
    let mut by_x = SnapIndex::default();
    let mut all_pairs = true;
    for _ in 0..MAX_PASSES {
        ins_a.clear();
        ins_b.clear();
        find(
            a, b, &dirty_a, &dirty_b, all_pairs, snap2, &mut by_x, &mut ins_a, &mut ins_b,
        );
        if ins_a.is_empty() && ins_b.is_empty() {
            return Ok(());
        }
        // A crossing snaps to the vertices that exist when it is found, not to the other
        // crossings of its pass: two crossings within the snapping distance of each other (two
        // edges crossing a third where they nearly meet) would each be inserted next to the
        // other, pass after pass, into the edges that end at the other. Welding makes them one
        // point; the rebuilt rings are tested again in full.
        let close = new_points_close(&ins_a, &ins_b, snap2);
        apply(a, &mut ins_a, &mut dirty_a);
        apply(b, &mut ins_b, &mut dirty_b);
        all_pairs = close && weld(a, b, scale) == Weld::Moved;
        if all_pairs {
            by_x = SnapIndex::default();
        }
    }
    Err(GeomError::Undecidable(
        "edge intersections did not settle; the operands have long nearly-overlapping edges",
    ))
}

/// Whether two distinct points computed in one pass (bent insertions) lie within the snapping
/// distance of each other. Passes insert a few points, so all pairs are compared.
fn new_points_close(ins_a: &Inserts, ins_b: &Inserts, snap2: f64) -> bool {
    let bent = |x: &&Insert| x.bent;
    let pts: SmallVec<[DVec2; 16]> = ins_a
        .iter()
        .chain(ins_b.iter())
        .filter(bent)
        .map(|x| x.p)
        .collect();
    pts.iter().enumerate().any(|(i, &p)| {
        pts[i + 1..]
            .iter()
            .any(|&q| p != q && (p - q).length_squared() <= snap2)
    })
}

/// Splits the rings of one ring soup at every contact among all its edges, within a ring and
/// across rings, to the same fixpoint as [`split`]: afterwards any two edges meet only in shared
/// endpoints or are identical (the same two points, in either direction).
///
/// This is [`split`] with both operands the same edge set, welding after every pass. Every unordered pair of distinct
/// edges is classified once by the same pair test, so crossings, vertices on or within the
/// snapping distance of edges, and collinear overlaps (a ring doubling back over itself, two rings
/// sharing a stretch) are resolved by the same rules and snapped to the same points. Pairs of
/// edges that follow each other in a ring share an endpoint and are settled by the test's
/// common-endpoint shortcut unless they fold back onto each other.
pub(crate) fn split_within(r: &mut Rings, scale: f64) -> Result<(), GeomError> {
    let snap2 = {
        let s = SNAP_REL * scale;
        s * s
    };
    let mut dirty: SmallVec<[bool; 64]> = SmallVec::new();
    let mut ins = Inserts::new();
    let mut ins_b = Inserts::new();
    let mut by_x = SnapIndex::default();
    let mut boxes: SmallVec<[EdgeBox; 32]> = SmallVec::new();
    let mut events: SmallVec<[(f64, u32); 64]> = SmallVec::new();
    let mut active: SmallVec<[u32; 32]> = SmallVec::new();
    for pass in 0..MAX_PASSES {
        ins.clear();
        ins_b.clear();
        edge_boxes(r, &mut boxes, SNAP_REL * scale);
        let bx: &[EdgeBox] = &boxes;
        let mut test = |i: usize, j: usize| {
            let (box_i, p0, p1) = &bx[i];
            let (box_j, q0, q1) = &bx[j];
            if boxes_overlap(box_i, box_j) {
                pair(
                    [*p0, *p1, *q0, *q1],
                    (i as u32, j as u32),
                    (&mut by_x, &r.pts, &[]),
                    snap2,
                    &mut ins,
                    &mut ins_b,
                );
            }
        };
        let is_dirty = |i: usize| pass == 0 || dirty.get(i).copied().unwrap_or(true);
        // A sweep over the edges' left ends: only pairs whose x-ranges overlap are tested, and
        // after the first pass only pairs with an edge next to a point inserted by the last one.
        events.clear();
        events.extend(bx.iter().enumerate().map(|(i, e)| (e.0[0], i as u32)));
        events.sort_unstable_by(|x, y| x.0.total_cmp(&y.0));
        active.clear();
        for &(x, id) in &events {
            let i = id as usize;
            active.retain(|j| bx[*j as usize].0[1] >= x);
            for &j in &active {
                let j = j as usize;
                if is_dirty(i) || is_dirty(j) {
                    test(j, i);
                }
            }
            active.push(id);
        }
        ins.extend(ins_b.drain(..));
        if ins.is_empty() {
            return Ok(());
        }
        apply(r, &mut ins, &mut dirty);
        // Three or more edges through one point (a ring crossing two edges that overlap each
        // other, or a triple crossing) give one crossing per pair, each off by its own rounding:
        // points an ulp apart that would be inserted into each other's edges pass after pass.
        // Welding makes them one vertex; the rebuilt rings are tested again in full.
        if weld(r, &mut Rings::default(), scale) == Weld::Moved {
            dirty.clear();
        }
    }
    Err(GeomError::Undecidable(
        "edge intersections did not settle; the rings have long nearly-overlapping edges",
    ))
}

/// What [`weld`] found among the operands' vertices.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Weld {
    /// Every two vertices are farther apart than the snapping distance.
    Separated,
    /// Some vertices are within the snapping distance of each other, but all such vertices are
    /// already identical: nothing moved (shared vertices, contours touching at a point).
    Coincident,
    /// Some vertices were moved onto others; the rings were rebuilt.
    Moved,
}

/// Welds the vertices of both operands: every vertex within the snapping distance
/// ([`SNAP_REL`] times `scale`) of another vertex, in either operand, becomes the same point
/// (FHP's vertex-on-vertex case, made robust).
///
/// Two distinct points a few ulps apart would otherwise each be inserted into the other's
/// edges and produce spikes between them. Welding *within* an operand matters too: results of
/// earlier operations (in the sphere layer, of earlier projections) can carry two copies of one
/// vertex a few ulps apart on different contours, and an edge of the other operand welded to one
/// copy would then overlap the edge at the other copy within rounding but not exactly, so the
/// overlap would survive into the result.
///
/// Close vertices are grouped transitively (a chain of copies, each within the distance of the
/// next, becomes one point); the group's representative is its first vertex in input order (A's
/// before B's), so an operand that needs no welding is left bit for bit as it was. Consecutive
/// points that become equal are merged and spikes `u, v, u` are cut back; a ring left with fewer
/// than three points is dropped (it was a sliver thinner than the tolerance).
pub(crate) fn weld(a: &mut Rings, b: &mut Rings, scale: f64) -> Weld {
    let snap = SNAP_REL * scale;
    let snap2 = snap * snap;
    let na = a.pts.len();
    let n = na + b.pts.len();
    let pt = |a: &Rings, b: &Rings, k: usize| {
        if k < na { a.pts[k] } else { b.pts[k - na] }
    };
    // All vertices sorted by x (ties in input order); each looks only at the following ones
    // within the x-window. A stable merge sort on the x-keys: it finds the long monotone runs
    // of polygon chains (measured cheaper here than an unstable sort of packed integer keys).
    let mut by_x: SmallVec<[(u64, u32); 64]> = SmallVec::with_capacity(n);
    for (k, p) in a.pts.iter().chain(b.pts.iter()).enumerate() {
        by_x.push((sort_key(p.x), k as u32));
    }
    by_x.sort_by_key(|e| e.0);
    // Union-find parents, allocated only once a pair of distinct close points is met.
    let mut parent: SmallVec<[u32; 64]> = SmallVec::new();
    let mut result = Weld::Separated;
    for (s, &(_, i)) in by_x.iter().enumerate() {
        let p = pt(a, b, i as usize);
        for &(_, j) in &by_x[s + 1..] {
            let q = pt(a, b, j as usize);
            if q.x - p.x > snap {
                break;
            }
            if (p - q).length_squared() > snap2 {
                continue;
            }
            if result == Weld::Separated {
                result = Weld::Coincident;
            }
            if p == q {
                continue;
            }
            if parent.is_empty() {
                parent.extend(0..n as u32);
            }
            let (ri, rj) = (find_root(&mut parent, i), find_root(&mut parent, j));
            // The smaller index (earlier in input order) represents the group.
            let (lo, hi) = if ri < rj { (ri, rj) } else { (rj, ri) };
            parent[hi as usize] = lo;
            result = Weld::Moved;
        }
    }
    if result != Weld::Moved {
        return result;
    }
    for k in 0..n {
        let r = find_root(&mut parent, k as u32) as usize;
        if r != k {
            let p = pt(a, b, r);
            if k < na {
                a.pts[k] = p;
            } else {
                b.pts[k - na] = p;
            }
        }
    }
    remove_spikes(a);
    remove_spikes(b);
    Weld::Moved
}

/// A key whose unsigned integer order is the total order of the float (`f64::total_cmp`).
#[inline]
pub(crate) fn sort_key(f: f64) -> u64 {
    let b = f.to_bits();
    if b >> 63 == 1 { !b } else { b | 1 << 63 }
}

/// Root of `i` in the union-find forest, halving paths on the way.
fn find_root(parent: &mut [u32], mut i: u32) -> u32 {
    while parent[i as usize] != i {
        let g = parent[parent[i as usize] as usize];
        parent[i as usize] = g;
        i = g;
    }
    i
}

/// Merges consecutive equal points and cuts spikes `u, v, u` (an edge followed by its own
/// reverse, a zero-area excursion) back to `u`, repeatedly and across the seam of each ring;
/// rings left with fewer than three points are dropped. Nothing else changes, so every edge that
/// remains was an edge before.
///
/// Welding creates such rings (a ring whose vertices `u` and `w` weld in `u, v, w`), and so can
/// splitting: a vertex of one operand within the snapping distance of an edge of the other near
/// that edge's end is inserted there, and if the edge's end is itself a vertex inserted into the
/// first operand's edge a few ulps away, the second operand's ring runs `u, v, u` through the two
/// copies. Such a spike would leave a node with an incoming but no outgoing result edge.
pub(crate) fn remove_spikes(r: &mut Rings) {
    // Cheap scan first: most rings have neither repeats nor spikes.
    let mut start = 0usize;
    let mut clean = true;
    for &end in &r.ends {
        let end = end as usize;
        let len = end - start;
        for k in 0..len {
            let p = r.pts[start + k];
            let q = r.pts[start + (k + 1) % len];
            let w = r.pts[start + (k + 2) % len];
            if p == q || p == w {
                clean = false;
            }
        }
        start = end;
    }
    if clean {
        return;
    }
    let mut pts: Split = SmallVec::with_capacity(r.pts.len());
    let mut ends: SmallVec<[u32; 4]> = SmallVec::new();
    let mut start = 0usize;
    for &end in &r.ends {
        let end = end as usize;
        let s = pts.len();
        for k in start..end {
            let p = r.pts[k];
            let len = pts.len() - s;
            if len >= 1 && pts[pts.len() - 1] == p {
                continue;
            }
            if len >= 2 && pts[pts.len() - 2] == p {
                pts.pop();
                continue;
            }
            pts.push(p);
        }
        // The seam: the same rules across the wrap-around (each round removes a point).
        loop {
            let len = pts.len() - s;
            if len < 3 {
                break;
            }
            let last = pts.len() - 1;
            if pts[last] == pts[s] || pts[last - 1] == pts[s] {
                // `.., u | u ..` repeats; `.., u, v | u ..` is a spike at `v`.
                pts.pop();
            } else if pts[last] == pts[s + 1] {
                // `.., v | u, v ..` is a spike at `u`.
                pts.remove(s);
            } else {
                break;
            }
        }
        if pts.len() - s < 3 {
            pts.truncate(s);
        } else {
            ends.push(pts.len() as u32);
        }
        start = end;
    }
    r.pts = pts;
    r.ends = ends;
}

/// Inserts into each contour the vertices of the operand's *other* contours that lie exactly on
/// its edges.
///
/// Contours of one shape may touch at isolated points, e.g. a hole's vertex on the outer
/// contour's edge. Without this step, an edge of the other operand overlapping that outer edge
/// would be split at the touching point while the outer edge is not, and the shared stretch would
/// not be recognized as shared. The inserted points are existing vertices and lie exactly on the
/// edge (`orient2d == 0`), so nothing bends.
pub(crate) fn split_self_contacts(r: &mut Rings) {
    if r.ends.len() < 2 {
        return;
    }
    let nxt = r.next_table();
    let mut ins = Inserts::new();
    let mut start = 0usize;
    for &end in &r.ends {
        let end = end as usize;
        for i in start..end {
            let (p0, p1) = (r.pts[i], r.pts[nxt[i] as usize]);
            for (k, &q) in r.pts.iter().enumerate() {
                if (start..end).contains(&k) {
                    continue;
                }
                if q.x < p0.x.min(p1.x)
                    || q.x > p0.x.max(p1.x)
                    || q.y < p0.y.min(p1.y)
                    || q.y > p0.y.max(p1.y)
                {
                    continue;
                }
                if orient(p0, p1, q) == 0.0 && strictly_between(p0, p1, q) {
                    push(&mut ins, i as u32, p0, p1, q, false);
                }
            }
        }
        start = end;
    }
    if !ins.is_empty() {
        let mut dirty = SmallVec::new();
        apply(r, &mut ins, &mut dirty);
    }
}

/// One edge for the pair search: bounding box `[min x, max x, min y, max y]` and its ends.
type EdgeBox = ([f64; 4], DVec2, DVec2);

/// Fills `out` with the edges of `r` (kept in the caller's frame: these buffers are large and
/// moving them would cost more than filling them), each box grown by `pad`, the snapping
/// distance: a vertex within that distance of an edge is a contact, and beside an edge nearly
/// parallel to an axis (a box of almost no height) it can lie outside the edge's own box.
fn edge_boxes(r: &Rings, out: &mut SmallVec<[EdgeBox; 32]>, pad: f64) {
    out.clear();
    let mut start = 0usize;
    for &end in &r.ends {
        let end = end as usize;
        for i in start..end {
            let p0 = r.pts[i];
            let p1 = r.pts[if i + 1 == end { start } else { i + 1 }];
            out.push((
                [
                    p0.x.min(p1.x) - pad,
                    p0.x.max(p1.x) + pad,
                    p0.y.min(p1.y) - pad,
                    p0.y.max(p1.y) + pad,
                ],
                p0,
                p1,
            ));
        }
        start = end;
    }
}

#[inline]
fn boxes_overlap(a: &[f64; 4], b: &[f64; 4]) -> bool {
    a[0] <= b[1] && b[0] <= a[1] && a[2] <= b[3] && b[2] <= a[3]
}

/// One pass over the edge pairs in which at least one edge is new.
///
/// Every pass sweeps the edges of both operands in order of their left ends, so only pairs whose
/// x-ranges overlap are examined: `O((n + m) log(n + m) + k)` instead of all `n * m` pairs.
/// Passes after the first test only pairs with an edge next to a newly inserted point (directly,
/// without the sweep, when there are only a few such edges).
#[allow(clippy::too_many_arguments)]
fn find(
    a: &Rings,
    b: &Rings,
    dirty_a: &[bool],
    dirty_b: &[bool],
    first_pass: bool,
    snap2: f64,
    by_x: &mut SnapIndex,
    ins_a: &mut Inserts,
    ins_b: &mut Inserts,
) {
    let mut ba: SmallVec<[EdgeBox; 32]> = SmallVec::new();
    let mut bb: SmallVec<[EdgeBox; 32]> = SmallVec::new();
    let pad = sqrt(snap2);
    edge_boxes(a, &mut ba, pad);
    edge_boxes(b, &mut bb, pad);
    // Plain slices: indexing a SmallVec re-checks whether it spilled on every access.
    let (ba, bb): (&[EdgeBox], &[EdgeBox]) = (&ba, &bb);

    let mut test = |i: usize, j: usize| {
        let (boxa, p0, p1) = &ba[i];
        let (boxb, q0, q1) = &bb[j];
        if boxes_overlap(boxa, boxb) {
            pair(
                [*p0, *p1, *q0, *q1],
                (i as u32, j as u32),
                (by_x, &a.pts, &b.pts),
                snap2,
                ins_a,
                ins_b,
            );
        }
    };
    // After the first pass only pairs with a new (dirty) edge can have new contacts. When there
    // are few of them, testing each against all edges of the other operand beats a sweep.
    let n_dirty = dirty_a.iter().chain(dirty_b.iter()).filter(|d| **d).count();
    if !first_pass && n_dirty <= 16 {
        for (i, _) in dirty_a.iter().enumerate().filter(|x| *x.1) {
            for j in 0..bb.len() {
                test(i, j);
            }
        }
        for (j, _) in dirty_b.iter().enumerate().filter(|x| *x.1) {
            for i in 0..ba.len() {
                if !dirty_a.get(i).copied().unwrap_or(false) {
                    test(i, j);
                }
            }
        }
        return;
    }
    if first_pass && ba.len() * bb.len() <= 256 {
        // Tiny operands: all pairs directly; sorting for a sweep would cost more.
        for i in 0..ba.len() {
            for j in 0..bb.len() {
                test(i, j);
            }
        }
        return;
    }
    let dirty = |i: usize, j: usize| {
        first_pass
            || dirty_a.get(i).copied().unwrap_or(true)
            || dirty_b.get(j).copied().unwrap_or(true)
    };
    // Sweep: events are edges keyed by their left end; the high bit of the id marks B's edges.
    const B_BIT: u32 = 1 << 31;
    let mut events: SmallVec<[(f64, u32); 64]> = SmallVec::with_capacity(ba.len() + bb.len());
    events.extend(ba.iter().enumerate().map(|(i, e)| (e.0[0], i as u32)));
    events.extend(
        bb.iter()
            .enumerate()
            .map(|(j, e)| (e.0[0], j as u32 | B_BIT)),
    );
    events.sort_unstable_by(|x, y| x.0.total_cmp(&y.0));
    let mut active_a: SmallVec<[u32; 32]> = SmallVec::new();
    let mut active_b: SmallVec<[u32; 32]> = SmallVec::new();
    for &(x, id) in &events {
        if id & B_BIT == 0 {
            let i = id as usize;
            active_b.retain(|j| bb[*j as usize].0[1] >= x);
            for &j in &active_b {
                if dirty(i, j as usize) {
                    test(i, j as usize);
                }
            }
            active_a.push(id);
        } else {
            let j = (id & !B_BIT) as usize;
            active_a.retain(|i| ba[*i as usize].0[1] >= x);
            for &i in &active_a {
                if dirty(i as usize, j) {
                    test(i as usize, j);
                }
            }
            active_b.push(j as u32);
        }
    }
}

/// Classifies one edge pair and records the points to insert.
fn pair(
    [p0, p1, q0, q1]: [DVec2; 4],
    (i, j): (u32, u32),
    (by_x, all_a, all_b): (&mut SnapIndex, &[DVec2], &[DVec2]),
    snap2: f64,
    ins_a: &mut Inserts,
    ins_b: &mut Inserts,
) {
    // Edges with a common endpoint (the normal case after splitting, and between adjacent mesh
    // triangles) can meet anywhere else only if they are (nearly) collinear: one orientation
    // test, instead of four, settles the common case.
    let common = if p0 == q0 {
        Some((p0, p1, q1))
    } else if p0 == q1 {
        Some((p0, p1, q0))
    } else if p1 == q0 {
        Some((p1, p0, q1))
    } else if p1 == q1 {
        Some((p1, p0, q0))
    } else {
        None
    };
    if let Some((v, pa, qa)) = common {
        let o = orient(v, pa, qa);
        let d = (pa - v).abs() + (qa - v).abs();
        if o.abs() > sqrt(snap2) * (d.x + d.y) {
            return;
        }
    }
    // A vertex within the snapping distance of the other edge's line counts as on it: it is
    // inserted into that edge (bending it by at most the tolerance), exactly as FHP's
    // vertex-on-edge case. Without this, a vertex a few ulps off an edge survives as a
    // near-touch that the next operation in a chain sees as either a crossing or a gap.
    //
    // `|orient| / |edge|` is the distance from the line; `|dx| + |dy|` bounds `|edge|` from above,
    // so the square root is only taken for the rare candidates that pass the cheap test.
    let snap = sqrt(snap2);
    let near = |o: f64, e0: DVec2, e1: DVec2| {
        let d = (e1 - e0).abs();
        o == 0.0 || (o.abs() <= snap * (d.x + d.y) && o.abs() <= snap * sqrt(d.length_squared()))
    };
    let oq0 = orient(p0, p1, q0);
    let oq1 = orient(p0, p1, q1);
    let (zq0, zq1) = (near(oq0, p0, p1), near(oq1, p0, p1));
    if !zq0 && !zq1 && ((oq0 > 0.0 && oq1 > 0.0) || (oq0 < 0.0 && oq1 < 0.0)) {
        return;
    }
    let op0 = orient(q0, q1, p0);
    let op1 = orient(q0, q1, p1);
    let (zp0, zp1) = (near(op0, q0, q1), near(op1, q0, q1));
    if !zp0 && !zp1 && ((op0 > 0.0 && op1 > 0.0) || (op0 < 0.0 && op1 < 0.0)) {
        return;
    }
    // Vertex on edge (and, when all four are zero, the ends of a collinear overlap). Exactly on:
    // the vertex is copied bit for bit and nothing bends. Within the tolerance: the edge bends.
    for (z, o, v) in [(zq0, oq0, q0), (zq1, oq1, q1)] {
        if z && (o != 0.0 || strictly_between(p0, p1, v)) {
            push(ins_a, i, p0, p1, v, o != 0.0);
        }
    }
    for (z, o, v) in [(zp0, op0, p0), (zp1, op1, p1)] {
        if z && (o != 0.0 || strictly_between(q0, q1, v)) {
            push(ins_b, j, q0, q1, v, o != 0.0);
        }
    }
    if zq0 || zq1 || zp0 || zp1 {
        return;
    }
    // Proper crossing: p0 and p1 strictly on opposite sides of line q and vice versa.
    let x = crossing_point([p0, p1, q0, q1], [op0, op1, oq0, oq1]);
    for (v, own_a) in [(p0, true), (p1, true), (q0, false), (q1, false)] {
        if (x - v).length_squared() <= snap2 {
            // Snap to an existing vertex: insert it into the other operand's edge only.
            if own_a {
                push(ins_b, j, q0, q1, v, true);
            } else {
                push(ins_a, i, p0, p1, v, true);
            }
            return;
        }
    }
    // Snap to any other vertex of either operand within the tolerance: a crossing a few ulps
    // from a vertex elsewhere on the boundary (a point where the operand touches itself, or a
    // vertex of the other operand lying on this edge) must become that vertex, or the boundary
    // would carry two distinct points a few ulps apart and the split edges between them could
    // double back.
    let snap = sqrt(snap2);
    by_x.crossings += 1;
    if by_x.crossings <= 8 {
        // Few crossings: a linear scan is cheaper than sorting.
        let x = all_a
            .iter()
            .chain(all_b.iter())
            .copied()
            .find(|&v| (x - v).length_squared() <= snap2)
            .unwrap_or(x);
        push(ins_a, i, p0, p1, x, true);
        push(ins_b, j, q0, q1, x, true);
        return;
    }
    if !by_x.built {
        by_x.pts.extend(all_a.iter().chain(all_b.iter()).copied());
        by_x.pts.sort_unstable_by(|p, q| p.x.total_cmp(&q.x));
        by_x.built = true;
    }
    let by_x: &[DVec2] = &by_x.pts;
    let lo = by_x.partition_point(|v| v.x < x.x - snap);
    let x = by_x[lo..]
        .iter()
        .take_while(|v| v.x <= x.x + snap)
        .copied()
        .find(|&v| (x - v).length_squared() <= snap2)
        .unwrap_or(x);
    push(ins_a, i, p0, p1, x, true);
    push(ins_b, j, q0, q1, x, true);
}

/// The crossing point of edges `p0 p1` and `q0 q1`, which cross properly, from the exact
/// orientations `[orient(q0, q1, p0), orient(q0, q1, p1), orient(p0, p1, q0), orient(p0, p1, q1)]`.
///
/// The signed distances of `p0` and `p1` from line `q` give the parameter along `p`, and those of
/// `q0`, `q1` from line `p` the parameter along `q`; each coordinate is taken from the edge with
/// the smaller extent in that coordinate, whose rounding error is proportional to that extent. In
/// particular a crossing of an axis-parallel edge is exact in that coordinate. Both the robust
/// path and the generic fast path compute crossings here, so they agree bit for bit.
#[inline]
pub(crate) fn crossing_point(
    [p0, p1, q0, q1]: [DVec2; 4],
    [op0, op1, oq0, oq1]: [f64; 4],
) -> DVec2 {
    let t = op0 / (op0 - op1);
    let u = oq0 / (oq0 - oq1);
    let xp = p0 + (p1 - p0) * t;
    let xq = q0 + (q1 - q0) * u;
    DVec2::new(
        if (p1.x - p0.x).abs() <= (q1.x - q0.x).abs() {
            xp.x
        } else {
            xq.x
        },
        if (p1.y - p0.y).abs() <= (q1.y - q0.y).abs() {
            xp.y
        } else {
            xq.y
        },
    ) + DVec2::ZERO
}

/// Parameter of `p` along the edge `e0 e1` (its projection), which orders the points inserted
/// into one edge.
#[inline]
pub(crate) fn edge_param(e0: DVec2, e1: DVec2, p: DVec2) -> f64 {
    let d = e1 - e0;
    (p - e0).dot(d) / d.length_squared()
}

fn push(ins: &mut Inserts, edge: u32, e0: DVec2, e1: DVec2, p: DVec2, bent: bool) {
    let t = edge_param(e0, e1, p);
    // A point that projects outside the edge is a snapped vertex a few ulps beyond an endpoint;
    // inserting it would make the edge double back, so it is left out (the endpoint stands in).
    if t > 0.0 && t < 1.0 && p != e0 && p != e1 {
        ins.push(Insert { edge, t, p, bent });
    }
}

/// Rebuilds the rings with the inserted points, marking edges next to bent points as dirty.
fn apply(r: &mut Rings, ins: &mut Inserts, dirty: &mut SmallVec<[bool; 64]>) {
    if ins.is_empty() {
        dirty.iter_mut().for_each(|d| *d = false);
        return;
    }
    ins.sort_unstable_by(|x, y| x.edge.cmp(&y.edge).then(x.t.total_cmp(&y.t)));
    let mut pts: Split = SmallVec::with_capacity(r.pts.len() + ins.len());
    let mut bent: SmallVec<[bool; 64]> = SmallVec::with_capacity(r.pts.len() + ins.len());
    let mut ends: SmallVec<[u32; 4]> = SmallVec::new();
    let mut k = 0;
    let mut start = 0usize;
    for &end in &r.ends {
        let end = end as usize;
        for e in start..end {
            pts.push(r.pts[e]);
            bent.push(false);
            let e1 = r.pts[if e + 1 == end { start } else { e + 1 }];
            while let Some(x) = ins.get(k) {
                if x.edge as usize != e {
                    break;
                }
                k += 1;
                let last = pts.last().copied();
                if Some(x.p) == last || x.p == e1 {
                    continue;
                }
                pts.push(x.p);
                bent.push(x.bent);
            }
        }
        ends.push(pts.len() as u32);
        start = end;
    }
    dirty.clear();
    let mut s = 0usize;
    for &end in &ends {
        let end = end as usize;
        for e in s..end {
            let n = if e + 1 == end { s } else { e + 1 };
            dirty.push(bent[e] || bent[n]);
        }
        s = end;
    }
    r.pts = pts;
    r.ends = ends;
}
