//! Phase 2: label every split edge of one operand as inside, outside or on the other operand, and
//! classify the intersection vertices.
//!
//! Greiner and Hormann (1998, section 3.2) mark each intersection vertex as *entry* or *exit* by
//! alternation, which fails as soon as a vertex only touches the other polygon. Foster, Hormann and
//! Popa (2019, labelling phase, Table 1) instead label each intersection from its local
//! neighbourhood: where the predecessor and successor edges of one polygon lie relative to the
//! other polygon's boundary chain (left/right/on). Two neighbours on different sides make a
//! *crossing*, on the same side a *bouncing*; an edge "on" the other boundary starts or ends an
//! overlapping chain, and the whole chain is a *delayed crossing* when the edges before and after
//! it lie on different sides and a *delayed bouncing* otherwise (same phase, overlapping chains).
//!
//! After phase 1 the split boundaries meet only in shared vertices, so every split edge is
//! entirely inside, entirely outside, or identical to an edge of the other operand (in the same or
//! the opposite direction). We compute that edge status directly, which is the same local
//! neighbourhood test FHP use, evaluated per edge instead of per vertex:
//!
//! - an edge whose ends are both vertices of the other operand, joined there by an edge, is *on*
//!   (`SharedSame` or `SharedOpposite`, FHP's "on/on" case);
//! - an edge with an end off the other boundary takes that end's exact winding-number status;
//! - an edge with both ends on the other boundary but not along it takes the status of its
//!   direction in the other operand's corner at its first end (the wedge test of FHP Table 1:
//!   left of both corner edges at a convex corner, left of either at a reflex one).
//!
//! The FHP vertex classes then follow from the statuses of the two edges around each vertex (see
//! [`VertexClass`] and [`classify`]); the tracing phase selects edges by status (GH's entry/exit
//! walk, section 3.3, amounts to following exactly the selected edges).

use glam::DVec2;
use smallvec::SmallVec;

use alloc::vec::Vec;

use super::Rings;
use crate::planar::predicates::orient;

/// Where a split edge of one operand lies relative to the other operand.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Status {
    /// In the interior of the other operand.
    Inside,
    /// In the exterior of the other operand.
    Outside,
    /// Identical to an edge of the other operand, running the same way (interiors on one side).
    SharedSame,
    /// Identical to an edge of the other operand, running the other way (interiors on opposite
    /// sides).
    SharedOpposite,
}

impl Status {
    fn is_on(self) -> bool {
        matches!(self, Status::SharedSame | Status::SharedOpposite)
    }
}

/// Classification of a vertex after Foster, Hormann and Popa (2019, labelling phase: Table 1
/// for crossing/bouncing, overlapping chains for the delayed cases).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum VertexClass {
    /// Not on the other boundary.
    Plain,
    /// The boundary passes from inside to outside of the other operand or back here.
    Crossing,
    /// The boundary touches the other boundary here and stays on the same side.
    Bouncing,
    /// Start of an overlapping chain whose two off-chain neighbours lie on different sides.
    DelayedCrossing,
    /// Start of an overlapping chain whose two off-chain neighbours lie on the same side.
    DelayedBouncing,
    /// Inside or at the end of an overlapping chain (the chain is classified at its start).
    OnChain,
}

/// Coincident vertices of both operands, grouped with one hash pass.
///
/// The vertices of A and B are numbered together (A's first, then B's). Identical points are
/// grouped by an open-addressing hash table on their bit patterns (zeros are canonical, so equal
/// points have equal bits); a group is a *node* of the overlay, named by its first member. Phase 1
/// made every contact an identical vertex in both operands, so "is this vertex on the other
/// boundary" and "which edges of the other operand meet here" are walks along the vertex's group.
pub(crate) struct Nodes {
    /// For each vertex number, its node (the first vertex number with the same point).
    node: SmallVec<[u32; 64]>,
    /// For each vertex number, the next vertex number at the same node (`NONE` at the end).
    next_same: SmallVec<[u32; 64]>,
    /// Number of vertices of A.
    na: u32,
}

const NONE: u32 = u32::MAX;

#[inline]
fn hash_pt(p: DVec2) -> u64 {
    let h = p.x.to_bits().wrapping_mul(0x9E37_79B9_7F4A_7C15) ^ p.y.to_bits().rotate_left(29);
    h.wrapping_mul(0xD6E8_FEB8_6659_FD93) >> 32
}

impl Nodes {
    pub(crate) fn new(a: &Rings, b: &Rings) -> Nodes {
        let (pa, pb): (&[DVec2], &[DVec2]) = (&a.pts, &b.pts);
        let na = pa.len();
        let n = na + pb.len();
        let size = (2 * n).next_power_of_two().max(8);
        let mask = size - 1;
        let mut table: SmallVec<[u32; 128]> = SmallVec::from_elem(NONE, size);
        let mut node: SmallVec<[u32; 64]> = SmallVec::from_elem(0, n);
        let mut next_same: SmallVec<[u32; 64]> = SmallVec::from_elem(NONE, n);
        // Last member of each node's list, to append in vertex order.
        let mut tail: SmallVec<[u32; 64]> = SmallVec::from_elem(NONE, n);
        for (k, &p) in pa.iter().chain(pb.iter()).enumerate() {
            let mut h = hash_pt(p) as usize & mask;
            // At most `size > n` probes: the table is never full.
            for _ in 0..size {
                let slot = table[h];
                if slot == NONE {
                    table[h] = k as u32;
                    node[k] = k as u32;
                    tail[k] = k as u32;
                    break;
                }
                let q = if (slot as usize) < na {
                    pa[slot as usize]
                } else {
                    pb[slot as usize - na]
                };
                if q == p {
                    node[k] = slot;
                    let t = tail[slot as usize] as usize;
                    next_same[t] = k as u32;
                    tail[slot as usize] = k as u32;
                    break;
                }
                h = (h + 1) & mask;
            }
        }
        Nodes {
            node,
            next_same,
            na: na as u32,
        }
    }

    /// The node of vertex `i` of A (`side_b == false`) or of B.
    #[inline]
    pub(crate) fn of(&self, i: usize, side_b: bool) -> u32 {
        let k = if side_b { i + self.na as usize } else { i };
        self.node.get(k).copied().unwrap_or(0)
    }

    /// Vertices of the *other* operand at the node of vertex `i` (indices into that operand).
    #[inline]
    pub(crate) fn twins(&self, i: usize, side_b: bool) -> impl Iterator<Item = usize> + '_ {
        let na = self.na;
        let mut k = self.of(i, side_b);
        // Each step follows the list forward, so it visits each vertex once.
        core::iter::from_fn(move || {
            while k != NONE {
                let cur = k;
                k = self.next_same.get(cur as usize).copied().unwrap_or(NONE);
                if (cur >= na) != side_b {
                    return Some(if side_b {
                        cur as usize
                    } else {
                        (cur - na) as usize
                    });
                }
            }
            None
        })
    }

    /// Whether vertex `i` lies on the other operand's boundary.
    #[inline]
    pub(crate) fn on_other(&self, i: usize, side_b: bool) -> bool {
        self.twins(i, side_b).next().is_some()
    }
}

/// Exact winding number of `p` (not on the boundary) with respect to all rings of `r`.
fn winding(r: &Rings, nxt: &[u32], p: DVec2) -> i32 {
    let pts: &[DVec2] = &r.pts;
    let mut w = 0;
    for (i, &n) in nxt.iter().enumerate() {
        let a = pts[i];
        let b = pts[n as usize];
        if a.y <= p.y {
            if b.y > p.y && orient(a, b, p) > 0.0 {
                w += 1;
            }
        } else if b.y <= p.y && orient(a, b, p) < 0.0 {
            w -= 1;
        }
    }
    w
}

/// Rank of the counter-clockwise angle from direction `v -> x` to ray `v -> r`: the ray sits in
/// the open left half-plane (0), straight opposite (1), the open right half-plane (2), or along
/// `v -> x` itself (3, last).
fn ccw_class(v: DVec2, x: DVec2, r: DVec2) -> u8 {
    let o = orient(v, x, r);
    if o > 0.0 {
        0
    } else if o < 0.0 {
        2
    } else {
        let d = x - v;
        let same = if d.x.abs() >= d.y.abs() {
            (x.x > v.x) == (r.x > v.x)
        } else {
            (x.y > v.y) == (r.y > v.y)
        };
        if same { 3 } else { 1 }
    }
}

/// Whether the direction from `v` towards `x` enters the interior of the other operand, given
/// every edge of the other operand incident to `v` as a ray `(far end, is_incoming)`.
///
/// This is the local neighbourhood test of FHP 2019 (labelling phase, Table 1), generalized to
/// several contours meeting at `v` (a hole touching its outer contour, two faces meeting at a
/// corner): turning counter-clockwise from `v -> x`, the first boundary ray met is an incoming
/// edge exactly when `v -> x` lies on its left, i.e. in the interior. Decided with exact
/// `orient2d` only.
fn inside_at(v: DVec2, x: DVec2, rays: &[(DVec2, bool)]) -> bool {
    let mut best: Option<(DVec2, bool)> = None;
    for &(r, incoming) in rays {
        best = match best {
            None => Some((r, incoming)),
            Some((b, bin)) => {
                let (cr, cb) = (ccw_class(v, x, r), ccw_class(v, x, b));
                let earlier = cr < cb || (cr == cb && orient(v, r, b) > 0.0);
                if earlier {
                    Some((r, incoming))
                } else {
                    Some((b, bin))
                }
            }
        };
    }
    best.is_some_and(|(_, incoming)| incoming)
}

/// Labels every split edge of `r` (edge `i` runs from vertex `i` to `r_nxt[i]`) against `o`.
///
/// A status can only change at a vertex on the other boundary, so it is computed there, with the
/// exact local test [`inside_at`], and copied along the run of edges up to the next such vertex.
/// Only a contour that never meets the other boundary needs a winding number (one per contour).
#[allow(clippy::too_many_arguments)]
pub(crate) fn label(
    r: &Rings,
    r_nxt: &[u32],
    side_b: bool,
    nodes: &Nodes,
    o: &Rings,
    o_nxt: &[u32],
    o_prv: &[u32],
    out: &mut SmallVec<[Status; 64]>,
) {
    out.clear();
    out.resize(r.pts.len(), Status::Outside);
    let mut start = 0usize;
    for &end in &r.ends {
        let end = end as usize;
        let len = end - start;
        let first_on = (start..end).find(|&i| nodes.on_other(i, side_b));
        let Some(f) = first_on else {
            let inside = r.pts.get(start).is_some_and(|&p| winding(o, o_nxt, p) != 0);
            let s = if inside {
                Status::Inside
            } else {
                Status::Outside
            };
            out[start..end].iter_mut().for_each(|x| *x = s);
            start = end;
            continue;
        };
        let mut prev = Status::Outside;
        let mut i = f;
        for _ in 0..len {
            let status = if nodes.on_other(i, side_b) {
                edge_status(r, r_nxt, i, side_b, nodes, o, o_nxt, o_prv)
            } else {
                prev
            };
            out[i] = status;
            prev = status;
            i = r_nxt[i] as usize;
        }
        start = end;
    }
}

/// Status of edge `i` of `r`, whose first vertex lies on the other boundary.
#[allow(clippy::too_many_arguments)]
fn edge_status(
    r: &Rings,
    r_nxt: &[u32],
    i: usize,
    side_b: bool,
    nodes: &Nodes,
    o: &Rings,
    o_nxt: &[u32],
    o_prv: &[u32],
) -> Status {
    let u = r.pts[i];
    let w = r.pts[r_nxt[i] as usize];
    let opts: &[DVec2] = &o.pts;
    for k in nodes.twins(i, side_b) {
        if opts[o_nxt[k] as usize] == w {
            return Status::SharedSame;
        }
        if opts[o_prv[k] as usize] == w {
            return Status::SharedOpposite;
        }
    }
    // The other operand's edges around `u` decide (several twins when its contours touch at
    // `u`).
    let mut rays: SmallVec<[(DVec2, bool); 8]> = SmallVec::new();
    for k in nodes.twins(i, side_b) {
        rays.push((opts[o_nxt[k] as usize], false));
        rays.push((opts[o_prv[k] as usize], true));
    }
    if inside_at(u, w, &rays) {
        Status::Inside
    } else {
        Status::Outside
    }
}

/// FHP vertex classes for the vertices of `r`, given its edge statuses.
///
/// Tracing needs only the edge statuses, so this runs only for diagnostics and tests
/// ([`crate::internals::contact_classes`]), which check the classes against FHP's definitions on known
/// configurations.
pub(crate) fn classify(
    r_nxt: &[u32],
    r_prv: &[u32],
    side_b: bool,
    nodes: &Nodes,
    status: &[Status],
    out: &mut Vec<VertexClass>,
) {
    out.clear();
    let n = r_nxt.len();
    for i in 0..n {
        let s_in = status[r_prv[i] as usize];
        let s_out = status[i];
        let class = match (s_in.is_on(), s_out.is_on()) {
            _ if !nodes.on_other(i, side_b) => VertexClass::Plain,
            (false, false) if s_in == s_out => VertexClass::Bouncing,
            (false, false) => VertexClass::Crossing,
            (true, _) => VertexClass::OnChain,
            (false, true) => {
                // Walk the chain of shared edges to its end (bounded by the ring length).
                let mut k = i;
                let mut steps = 0;
                while status[k].is_on() && steps < n {
                    k = r_nxt[k] as usize;
                    steps += 1;
                }
                if status[k] == s_in {
                    VertexClass::DelayedBouncing
                } else {
                    VertexClass::DelayedCrossing
                }
            }
        };
        out.push(class);
    }
}
