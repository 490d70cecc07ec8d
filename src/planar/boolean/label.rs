//! Phase 2: label every split edge of one operand as inside, outside or on the other operand, and
//! classify the intersection vertices.
//!
//! Greiner and Hormann (1998, section 3.2) mark each intersection vertex as *entry* or *exit* by
//! alternation, which fails as soon as a vertex only touches the other polygon. Foster, Hormann and
//! Popa (2019, section 3.1, Table 1 and Figure 5) instead label each intersection from its local
//! neighbourhood: where the predecessor and successor edges of one polygon lie relative to the
//! other polygon's boundary chain (left/right/on). Two neighbours on different sides make a
//! *crossing*, on the same side a *bouncing*; an edge "on" the other boundary starts or ends an
//! overlapping chain, and the whole chain is a *delayed crossing* when the edges before and after
//! it lie on different sides and a *delayed bouncing* otherwise (section 3.2).
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
//! walk, section 3.3, amounts to following exactly the selected edges), and the classification
//! doubles as a consistency check: a status may only change at a vertex on the other boundary.

use glam::DVec2;
use smallvec::SmallVec;

use super::Rings;
use crate::GeomError;
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

/// Classification of an intersection vertex after Foster, Hormann and Popa (2019, section 3.1,
/// Table 1, and section 3.2 for the delayed cases).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum VertexClass {
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

/// Per-vertex lookup of identical vertices in the other operand, by sorting its points.
pub(crate) struct Twins {
    order: SmallVec<[u32; 64]>,
}

fn cmp_pt(a: DVec2, b: DVec2) -> core::cmp::Ordering {
    a.x.total_cmp(&b.x).then(a.y.total_cmp(&b.y))
}

impl Twins {
    pub(crate) fn new(r: &Rings) -> Twins {
        let mut order: SmallVec<[u32; 64]> = (0..r.pts.len() as u32).collect();
        order.sort_unstable_by(|&x, &y| cmp_pt(r.pts[x as usize], r.pts[y as usize]));
        Twins { order }
    }

    /// Indices of the vertices of `r` equal to `p` (usually none or one).
    pub(crate) fn of<'a>(&'a self, r: &Rings, p: DVec2) -> &'a [u32] {
        let lo = self
            .order
            .partition_point(|&k| cmp_pt(r.pts[k as usize], p) == core::cmp::Ordering::Less);
        let hi = lo
            + self.order[lo..]
                .iter()
                .take_while(|&&k| r.pts[k as usize] == p)
                .count();
        &self.order[lo..hi]
    }
}

/// Exact winding number of `p` (not on the boundary) with respect to all rings of `r`.
fn winding(r: &Rings, nxt: &[u32], p: DVec2) -> i32 {
    let mut w = 0;
    for (i, &n) in nxt.iter().enumerate() {
        let a = r.pts[i];
        let b = r.pts[n as usize];
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
/// This is the local neighbourhood test of FHP 2019 (section 3.1, Table 1), generalized to
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
pub(crate) fn label(
    r: &Rings,
    r_nxt: &[u32],
    o: &Rings,
    o_nxt: &[u32],
    o_prv: &[u32],
    o_twins: &Twins,
    out: &mut SmallVec<[Status; 64]>,
) {
    out.clear();
    for (i, &n) in r_nxt.iter().enumerate() {
        let u = r.pts[i];
        let w = r.pts[n as usize];
        let tu = o_twins.of(o, u);
        let mut status = None;
        for &k in tu {
            let k = k as usize;
            if o.pts[o_nxt[k] as usize] == w {
                status = Some(Status::SharedSame);
                break;
            }
            if o.pts[o_prv[k] as usize] == w {
                status = Some(Status::SharedOpposite);
                break;
            }
        }
        let status = status.unwrap_or_else(|| {
            let inside = if tu.is_empty() {
                winding(o, o_nxt, u) != 0
            } else if o_twins.of(o, w).is_empty() {
                winding(o, o_nxt, w) != 0
            } else {
                // Both ends on the other boundary: the other operand's edges around `u` decide
                // (several twins when its contours touch at `u`).
                let rays: SmallVec<[(DVec2, bool); 8]> = tu
                    .iter()
                    .flat_map(|&k| {
                        let k = k as usize;
                        [
                            (o.pts[o_nxt[k] as usize], false),
                            (o.pts[o_prv[k] as usize], true),
                        ]
                    })
                    .collect();
                inside_at(u, w, &rays)
            };
            if inside {
                Status::Inside
            } else {
                Status::Outside
            }
        });
        out.push(status);
    }
}

/// FHP vertex classes for the vertices of `r`, given its edge statuses and whether each vertex
/// is also a vertex of the other operand.
///
/// # Errors
///
/// [`GeomError::Degenerate`] when the status changes at a vertex that is not on the other
/// boundary: a boundary can only pass from inside to outside through the other boundary, so this
/// means phase 1 missed a contact (which exact predicates on the split edges rule out, so it is a
/// consistency check against numerically pathological input).
pub(crate) fn classify(
    r_nxt: &[u32],
    r_prv: &[u32],
    on_other: &[bool],
    status: &[Status],
    out: &mut SmallVec<[VertexClass; 64]>,
) -> Result<(), GeomError> {
    out.clear();
    let n = r_nxt.len();
    for i in 0..n {
        let s_in = status[r_prv[i] as usize];
        let s_out = status[i];
        let class = match (s_in.is_on(), s_out.is_on()) {
            _ if !on_other[i] => {
                if s_in != s_out {
                    return Err(GeomError::Degenerate(
                        "a contour changes sides away from the other boundary; \
                         the operands are too close to degenerate for f64",
                    ));
                }
                VertexClass::Plain
            }
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
    Ok(())
}
