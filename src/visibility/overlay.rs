//! The visible part of a light as an overlay of rings in one gnomonic chart, resolved by the
//! crossings of their edges and winding numbers carried along the rings (issue 17): the fast
//! path's answer for closed mesh blockers and closed non-planar mesh lights.
//!
//! # What is computed
//!
//! Two families of closed rings in the chart (great circles are its lines): the light's `L`,
//! whose winding number `w_L` about a point counts how often the light covers it (the light's
//! region, or the contour of a mesh light's front faces: `w_L >= 1` on their union), and the
//! blockers' `B`, whose winding `w_B` counts the blockers' front faces covering it (contours of
//! closed meshes, see [`super::contour`]). The visible region is `V = {w_L >= 1 and w_B = 0}`.
//! Its boundary is made of the pieces of edges (cut at every crossing with another edge) that
//! have `V` on exactly one side, run with `V` on their left: the light's edges where no blocker
//! covers them, the blockers' edges reversed where they cross the light's region uncovered
//! behind.
//!
//! # How
//!
//! 1. The crossings of every pair of edges (candidates by a sweep over their `x` ranges, then
//!    four orientation tests); consecutive edges, and edges meeting at a shared vertex (where
//!    [`super::contour::chain_rings`] pairs them so that they do not cross), are not tested.
//! 2. Winding numbers along each ring: at the first edge of each run of edges (a ring, or a
//!    part of one between bridges, see below) both windings just right of the edge are counted
//!    by a ray to infinity; along the run they change only at crossings, by one in the
//!    crossing edge's family (its left side counts one more).
//! 3. The pieces with `V` on one side only, linked into rings: at a vertex the boundary goes on
//!    along the ring, at a crossing along the one other piece that keeps it (of the four pieces
//!    meeting there exactly two bound `V` when `V` changes there: the windings of the four
//!    sectors are `w`, `w + 1`, `w + 1`, `w + 2` in each family, and no two opposite sectors can
//!    both be in `V`).
//!
//! Blocker rings enter clipped to a box of the chart around the light (Sutherland–Hodgman
//! against the box's planes through the point, on direction vectors before projecting: the
//! winding numbers inside the box are kept, outside they become 0). The parts of the rings
//! along the box's sides (bridges) lie outside the light's region by a margin: they are never
//! kept and never tested for crossings (they overlap along a side), but they count in the rays.
//!
//! # Exactness
//!
//! The projected points are taken as exact; every decision (the orientation tests, the order
//! of two crossings along an edge, each ray's crossings) is an exact sign of an expression in
//! them or is declined: it must clear its rounding bound (Shewchuk's error bound for the
//! orientation, times 3), else the overlay returns `false` and the caller takes the general
//! path. So the result is the exact overlay of the projected rings (up to the rounding of its
//! crossing points), which differ from the true ones by the projection's rounding.

use alloc::vec::Vec;

use glam::{DVec2, DVec3};

/// A vertex of an input ring: its chart position, its direction (for the output, any positive
/// length), an identity (equal for the same mesh vertex), and whether the edge leaving it runs
/// along a side of the clipping box.
#[derive(Debug, Clone, Copy)]
pub(crate) struct RingPoint {
    pub(crate) p: DVec2,
    pub(crate) d: DVec3,
    pub(crate) id: u64,
    pub(crate) bridge: bool,
}

/// Which family a ring belongs to.
pub(crate) const LIGHT: u8 = 0;
pub(crate) const BLOCKER: u8 = 1;

/// A crossing of edges `e` and `f` at parameters `te`, `tf` (with their rounding bounds).
#[derive(Debug, Clone, Copy, Default)]
struct Cross {
    x: DVec2,
    e: u32,
    f: u32,
    te: f64,
    dte: f64,
    tf: f64,
    dtf: f64,
    /// Sign of `(e's direction) x (f's direction)`.
    s: i8,
}

/// A crossing seen from one of its edges, in that edge's order.
#[derive(Debug, Clone, Copy, Default)]
struct Slot {
    t: f64,
    dt: f64,
    other: u32,
    cross: u32,
    /// Sign of `(this edge's direction) x (other's)`.
    s: i8,
    /// Index of the same crossing's slot on the other edge.
    twin: u32,
}

/// Scratch storage and result of one overlay (reused across calls).
#[derive(Debug, Clone, Default)]
pub(crate) struct Overlay {
    /// Input rings: ring `r` is `pts[ends[r - 1]..ends[r]]`, of family `family[r]`.
    pub(crate) pts: Vec<RingPoint>,
    pub(crate) ends: Vec<u32>,
    pub(crate) family: Vec<u8>,
    /// Per vertex: its ring.
    ring_of: Vec<u32>,
    /// Per vertex: the next one along its ring (the one load [`Overlay::succ`] costs).
    next: Vec<u32>,
    bbox: Vec<[f64; 4]>,
    /// Non-bridge edges by the left end of their boxes: the key's order-preserving bits above
    /// (the lowest rounded off), the edge below (integers sort faster than floating-point keys
    /// through the index).
    order: Vec<u64>,
    active: Vec<u32>,
    /// Pairs of edges whose boxes overlap (the sweep's candidates).
    pairs: Vec<(u32, u32)>,
    cross: Vec<Cross>,
    /// Per edge `e`: its crossings are `slots[xstart[e]..xstart[e + 1]]`, along it.
    xstart: Vec<u32>,
    slots: Vec<Slot>,
    /// Per piece (`xstart[e] + e + j`, the `j`-th piece of edge `e`): 0, 1 kept forwards, 2
    /// kept reversed; and visited by the walk.
    kept: Vec<u8>,
    seen: Vec<bool>,
    /// Identities of the input vertices the result passes through.
    out_ids: Vec<u64>,
    /// Per edge, the next free slot while grouping (`sort_slots`); per crossing, its first slot.
    fill: Vec<u32>,
    first: Vec<u32>,
    /// The result: rings of directions (see [`Overlay::resolve`]).
    pub(crate) out: Vec<DVec3>,
    pub(crate) out_ends: Vec<u32>,
    /// The result's rings touch (a vertex used twice): not simple.
    pub(crate) touching: bool,
    /// Whether an identity may occur more than once among the input vertices (a contour that
    /// passes a mesh vertex twice, [`super::contour::ChainScratch::paired`]); set by the caller
    /// as it adds rings. Without such an input vertex the result cannot touch (see
    /// [`Overlay::walk`]), and its identities are neither collected nor sorted.
    pub(crate) repeated_ids: bool,
}

/// Rounding bound factor of the orientation test: Shewchuk's `ccwerrboundA` is `3.33e-16`.
const ORIENT_ERR: f64 = 1e-15;

/// `orient2d(a, b, c)` (positive when `c` lies left of `a -> b`) and its rounding bound.
#[inline(always)]
fn orient(a: DVec2, b: DVec2, c: DVec2) -> (f64, f64) {
    let (l, r) = ((a.x - c.x) * (b.y - c.y), (a.y - c.y) * (b.x - c.x));
    (l - r, ORIENT_ERR * (l.abs() + r.abs()))
}

/// Bits of `v` whose unsigned order is `f64::total_cmp`'s.
#[inline(always)]
fn order_bits(v: f64) -> u64 {
    let b = v.to_bits();
    if b >> 63 == 1 { !b } else { b | 1 << 63 }
}

/// The `f64` of [`order_bits`] `o`: its inverse. Clearing low bits of `o` gives a value no
/// greater (for `v < 0` they are set in `v`'s mantissa, never reaching its exponent).
#[inline(always)]
fn from_order_bits(o: u64) -> f64 {
    f64::from_bits(if o >> 63 == 1 { o & !(1 << 63) } else { !o })
}

/// The sign of `v` as `-1` or `1` (`v` is not zero).
#[inline(always)]
fn sign(v: f64) -> i8 {
    if v > 0.0 { 1 } else { -1 }
}

/// Whether the windings `w = (w_L, w_B)` are in the visible region.
#[inline(always)]
fn visible(w: [i32; 2]) -> bool {
    w[0] >= 1 && w[1] == 0
}

impl Overlay {
    /// Storage for about `n` input vertices (reserved once: the buffers then grow rarely).
    pub(crate) fn with_capacity(n: usize) -> Self {
        let mut o = Overlay::default();
        o.pts.reserve(n);
        o.ring_of.reserve(n);
        o.next.reserve(n);
        o.bbox.reserve(n);
        o.order.reserve(n);
        o.active.reserve(n / 4);
        o.pairs.reserve(n);
        o.xstart.reserve(n + 1);
        o.fill.reserve(n);
        o.kept.reserve(2 * n);
        o.seen.reserve(2 * n);
        o.out.reserve(n);
        o.out_ids.reserve(n);
        o
    }

    /// Empties the input.
    pub(crate) fn clear(&mut self) {
        self.pts.clear();
        self.ends.clear();
        self.family.clear();
        self.repeated_ids = false;
    }

    /// Closes the ring started at `start` (of family `fam`); one of fewer than three vertices is
    /// dropped.
    pub(crate) fn close(&mut self, start: usize, fam: u8) {
        if self.pts.len() - start >= 3 {
            self.ends.push(self.pts.len() as u32);
            self.family.push(fam);
        } else {
            self.pts.truncate(start);
        }
    }

    /// The winding number about `q` of the rings of family `fam` from ring `first` on (a ray
    /// along `+x`, half-open in `y` as in [`Overlay::ray`]); `None` where the ray passes within
    /// rounding of a vertex or edge.
    pub(crate) fn winding(&self, first: usize, fam: u8, q: DVec2) -> Option<i32> {
        let mut w = 0;
        for r in first..self.ends.len() {
            if self.family[r] != fam {
                continue;
            }
            let start = if r == 0 { 0 } else { self.ends[r - 1] as usize };
            let ring = &self.pts[start..self.ends[r] as usize];
            for (k, a) in ring.iter().enumerate() {
                let (p0, p1) = (a.p, ring[(k + 1) % ring.len()].p);
                if (p0.y > q.y) == (p1.y > q.y) || (p0.x < q.x && p1.x < q.x) {
                    continue;
                }
                let (o, b) = orient(p0, p1, q);
                if o.abs() <= b {
                    return None;
                }
                if (o > 0.0) == (p1.y > p0.y) {
                    w += if o > 0.0 { 1 } else { -1 };
                }
            }
        }
        Some(w)
    }

    #[inline(always)]
    fn succ(&self, k: usize) -> usize {
        self.next[k] as usize
    }

    #[inline(always)]
    fn pred(&self, k: usize) -> usize {
        let r = self.ring_of[k] as usize;
        let start = if r == 0 { 0 } else { self.ends[r - 1] as usize };
        if k == start {
            self.ends[r] as usize - 1
        } else {
            k - 1
        }
    }

    #[inline(always)]
    fn fam(&self, k: usize) -> usize {
        self.family[self.ring_of[k] as usize] as usize
    }

    /// The visible region of the input rings into `out` / `out_ends` (directions: input
    /// vertices by their `d`, crossings unprojected as `c + x u + y v` with `z` at least 0),
    /// rings with the region on their left. `false` where a decision is within rounding (see
    /// the module documentation) or the result does not link up.
    pub(crate) fn resolve(&mut self, c: DVec3, u: DVec3, v: DVec3) -> bool {
        self.out.clear();
        self.out_ends.clear();
        self.touching = false;
        let n = self.pts.len();
        self.ring_of.clear();
        self.next.clear();
        let mut start = 0usize;
        for (r, &end) in self.ends.iter().enumerate() {
            self.ring_of
                .extend(core::iter::repeat_n(r as u32, end as usize - start));
            self.next.extend(start as u32 + 1..end);
            self.next.push(start as u32);
            start = end as usize;
        }
        if !self.crossings() {
            return false;
        }
        if !self.sort_slots() {
            return false;
        }
        self.kept.clear();
        self.kept.resize(n + self.slots.len(), 0);
        // Runs: whole rings without bridges, else the parts between bridges.
        let mut start = 0usize;
        for r in 0..self.ends.len() {
            let end = self.ends[r] as usize;
            let cyclic = !self.pts[start..end].iter().any(|p| p.bridge);
            for k in start..end {
                let first = if cyclic {
                    k == start
                } else {
                    !self.pts[k].bridge && self.pts[self.pred(k)].bridge
                };
                if first && !self.propagate(k, cyclic) {
                    return false;
                }
            }
            start = end;
        }
        self.walk(c, u, v)
    }

    /// Step 1: every crossing of two non-bridge edges.
    fn crossings(&mut self) -> bool {
        let n = self.pts.len();
        let (pts, next) = (&self.pts[..n], &self.next[..n]);
        self.bbox.clear();
        self.order.clear();
        self.order.reserve(n);
        // The keys: a box's left end with its lowest `bits` order bits cleared (rounded towards
        // `-inf`), the edge in those bits. One `u64` sorts faster than the exact `u128` key.
        let bits = usize::BITS - n.leading_zeros();
        if bits > 32 {
            return false;
        }
        let low = (1u64 << bits) - 1;
        for (k, (q, &s)) in pts.iter().zip(next).enumerate() {
            let (a, b) = (q.p, pts[s as usize].p);
            // Plain comparisons (the coordinates are finite): `f64::min`'s NaN rule costs more.
            let (x0, x1) = if a.x <= b.x { (a.x, b.x) } else { (b.x, a.x) };
            let (y0, y1) = if a.y <= b.y { (a.y, b.y) } else { (b.y, a.y) };
            self.bbox.push([x0, x1, y0, y1]);
            if !q.bridge {
                self.order.push((order_bits(x0) & !low) | k as u64);
            }
        }
        self.order.sort_unstable();
        // The sweep collects the candidate pairs, then they are tested.
        self.active.clear();
        self.pairs.clear();
        let bbox = &self.bbox[..];
        for &key in &self.order {
            let e = (key & low) as u32;
            let be = bbox[e as usize];
            // `e`'s rounded left end: no later key's box starts further left.
            let left = from_order_bits(key & !low);
            // One pass over the active edges: those whose boxes end left of `left` leave for
            // good, the others stay, in order, and are tested against `e` where their boxes
            // overlap, in `x` both ways (within one rounded key `f`'s box may start right of
            // `e`'s) and in `y`.
            let mut kept = 0;
            for j in 0..self.active.len() {
                let f = self.active[j];
                let bf = bbox[f as usize];
                if bf[1] < left {
                    continue;
                }
                self.active[kept] = f;
                kept += 1;
                if bf[2] > be[3] || be[2] > bf[3] || bf[1] < be[0] || be[1] < bf[0] {
                    continue;
                }
                self.pairs.push((e, f));
            }
            self.active.truncate(kept);
            self.active.push(e);
        }
        self.cross.clear();
        for i in 0..self.pairs.len() {
            let (e, f) = self.pairs[i];
            if !self.test_pair(e as usize, f as usize) {
                return false;
            }
        }
        true
    }

    /// Whether edges `e` and `f` cross (recorded) or not; `false` where that is within rounding
    /// (touching, or an end within rounding of the other's line).
    fn test_pair(&mut self, e: usize, f: usize) -> bool {
        let (se, sf) = (self.succ(e), self.succ(f));
        let (ie, je, i_f, jf) = (
            self.pts[e].id,
            self.pts[se].id,
            self.pts[f].id,
            self.pts[sf].id,
        );
        if ie == i_f || ie == jf || je == i_f || je == jf {
            return true;
        }
        let (a, b, c, d) = (self.pts[e].p, self.pts[se].p, self.pts[f].p, self.pts[sf].p);
        let (o1, b1) = orient(a, b, c);
        let (o2, b2) = orient(a, b, d);
        if o1.abs() <= b1 || o2.abs() <= b2 {
            // An end of `f` within rounding of `e`'s line: only a problem where the segments
            // may meet (their boxes overlap, tested by the caller; decided by `e`'s side).
            let (o3, b3) = orient(c, d, a);
            let (o4, b4) = orient(c, d, b);
            if (o3 > b3 && o4 > b4) || (o3 < -b3 && o4 < -b4) {
                return true;
            }
            return false;
        }
        if (o1 > 0.0) == (o2 > 0.0) {
            return true;
        }
        let (o3, b3) = orient(c, d, a);
        let (o4, b4) = orient(c, d, b);
        if o3.abs() <= b3 || o4.abs() <= b4 {
            return false;
        }
        if (o3 > 0.0) == (o4 > 0.0) {
            return true;
        }
        let (de, df) = ((o3 - o4).abs(), (o1 - o2).abs());
        let te = o3 / (o3 - o4);
        let tf = o1 / (o1 - o2);
        self.cross.push(Cross {
            x: a + (b - a) * te,
            e: e as u32,
            f: f as u32,
            te,
            dte: 2.0 * (b3 + b4) / de + 4.0 * f64::EPSILON,
            tf,
            dtf: 2.0 * (b1 + b2) / df + 4.0 * f64::EPSILON,
            // `(b - a) x (d - c) = o2 - o1`, of the sign of `o2`.
            s: sign(o2),
        });
        true
    }

    /// Groups the crossings by edge, in order along each edge; `false` where two on one edge
    /// are within rounding of each other.
    fn sort_slots(&mut self) -> bool {
        let n = self.pts.len();
        self.xstart.clear();
        self.xstart.resize(n + 1, 0);
        for c in &self.cross {
            self.xstart[c.e as usize + 1] += 1;
            self.xstart[c.f as usize + 1] += 1;
        }
        for k in 0..n {
            self.xstart[k + 1] += self.xstart[k];
        }
        self.slots.clear();
        self.slots.resize(2 * self.cross.len(), Slot::default());
        // Fill from the ends backwards, so that `xstart` is left as it was.
        let fill = &mut self.fill;
        fill.clear();
        fill.extend_from_slice(&self.xstart[1..]);
        for (ci, c) in self.cross.iter().enumerate().rev() {
            let (e, f) = (c.e as usize, c.f as usize);
            fill[e] -= 1;
            self.slots[fill[e] as usize] = Slot {
                t: c.te,
                dt: c.dte,
                other: c.f,
                cross: ci as u32,
                s: c.s,
                twin: 0,
            };
            fill[f] -= 1;
            self.slots[fill[f] as usize] = Slot {
                t: c.tf,
                dt: c.dtf,
                other: c.e,
                cross: ci as u32,
                s: -c.s,
                twin: 0,
            };
        }
        for k in 0..n {
            let (a, b) = (self.xstart[k] as usize, self.xstart[k + 1] as usize);
            if b < a + 2 {
                continue;
            }
            let g = &mut self.slots[a..b];
            // Insertion sort: a few crossings per edge.
            for i in 1..g.len() {
                let mut j = i;
                while j > 0 && g[j].t < g[j - 1].t {
                    g.swap(j - 1, j);
                    j -= 1;
                }
            }
            for i in 1..g.len() {
                if g[i - 1].t + g[i - 1].dt >= g[i].t - g[i].dt {
                    return false;
                }
            }
        }
        // Twins: the two slots of each crossing.
        let first = &mut self.first;
        first.clear();
        first.resize(self.cross.len(), u32::MAX);
        for i in 0..self.slots.len() {
            let ci = self.slots[i].cross as usize;
            if first[ci] == u32::MAX {
                first[ci] = i as u32;
            } else {
                let j = first[ci] as usize;
                self.slots[i].twin = j as u32;
                self.slots[j].twin = i as u32;
            }
        }
        true
    }

    /// The windings `(w_L, w_B)` of every edge but `skip` about `q`, by a ray from `q` along
    /// `+x` (`along_x`) or `+y`; `None` where a crossing of the ray is within rounding of `q`.
    fn ray(&self, q: DVec2, along_x: bool, skip: usize) -> Option<[i32; 2]> {
        let mut w = [0i32; 2];
        // Half-open: a vertex at `q`'s height (or abscissa) counts as above (right), for both
        // its edges; an edge is met where its box's range holds `q`'s coordinate that way
        // (`min <= q < max`, the same as its ends lying on different sides) and reaches `q`
        // along the ray. Only the boxes are read for the others.
        let (a, b, lo, hi, reach) = if along_x {
            (q.y, q.x, 2, 3, 1)
        } else {
            (q.x, q.y, 0, 1, 3)
        };
        for (k, bx) in self.bbox.iter().enumerate() {
            if !(bx[lo] <= a && a < bx[hi]) || bx[reach] < b || k == skip {
                continue;
            }
            let (p0, p1) = (self.pts[k].p, self.pts[self.succ(k)].p);
            let (o, bound) = orient(p0, p1, q);
            if o.abs() <= bound {
                return None;
            }
            let ahead = if along_x {
                (o > 0.0) == (p1.y > p0.y)
            } else {
                (o < 0.0) == (p1.x > p0.x)
            };
            if ahead {
                w[self.fam(k)] += if o > 0.0 { 1 } else { -1 };
            }
        }
        Some(w)
    }

    /// Step 2 for the run starting at edge `e0`: windings from a ray at the middle of its first
    /// piece, carried along the run, each piece classified.
    fn propagate(&mut self, e0: usize, cyclic: bool) -> bool {
        let (s0, s1) = (self.xstart[e0] as usize, self.xstart[e0 + 1] as usize);
        let t1 = if s1 > s0 {
            self.slots[s0].t - self.slots[s0].dt
        } else {
            1.0
        };
        if !(t1 > 0.0) {
            return false;
        }
        let (a, b) = (self.pts[e0].p, self.pts[self.succ(e0)].p);
        let d = b - a;
        let q = a + d * (0.5 * t1);
        let along_x = d.y.abs() >= d.x.abs();
        let Some(mut w) = self.ray(q, along_x, e0) else {
            return false;
        };
        // The edge itself, for a point just to its right.
        let own = if along_x { d.y < 0.0 } else { d.x > 0.0 };
        if own {
            w[self.fam(e0)] -= 1;
        }
        let w0 = w;
        // A run lies on one ring, of one family; its pieces' class changes only at crossings.
        let fam = self.fam(e0);
        let class = |w: [i32; 2]| {
            let mut left = w;
            left[fam] += 1;
            let (l, r) = (visible(left), visible(w));
            if l && !r {
                1
            } else if r && !l {
                2
            } else {
                0
            }
        };
        let mut k = class(w);
        let mut e = e0;
        loop {
            let (s0, s1) = (self.xstart[e] as usize, self.xstart[e + 1] as usize);
            self.kept[s0 + e] = k;
            for j in 1..=(s1 - s0) {
                let sl = self.slots[s0 + j - 1];
                w[self.fam(sl.other as usize)] -= i32::from(sl.s);
                k = class(w);
                self.kept[s0 + e + j] = k;
            }
            e = self.succ(e);
            if cyclic {
                if e == e0 {
                    break;
                }
            } else if self.pts[e].bridge {
                break;
            }
        }
        !cyclic || w == w0
    }

    /// Step 3: the kept pieces linked into rings.
    fn walk(&mut self, c: DVec3, u: DVec3, v: DVec3) -> bool {
        let n = self.pts.len();
        self.seen.clear();
        self.seen.resize(self.kept.len(), false);
        self.out_ids.clear();
        for e in 0..n {
            let (s0, s1) = (self.xstart[e] as usize, self.xstart[e + 1] as usize);
            for j in 0..=(s1 - s0) {
                let id = s0 + e + j;
                if self.kept[id] == 0 || self.seen[id] {
                    continue;
                }
                let ring_start = self.out.len();
                let (mut ce, mut cj, mut fwd) = (e, j, self.kept[id] == 1);
                loop {
                    let pid = self.xstart[ce] as usize + ce + cj;
                    if self.seen[pid] {
                        return false;
                    }
                    self.seen[pid] = true;
                    let cnt = (self.xstart[ce + 1] - self.xstart[ce]) as usize;
                    if fwd && cnt == 0 && !self.repeated_ids {
                        // A whole edge run forwards (the common piece): its start, and on to
                        // the next edge's first piece, which must be kept forwards too (as in
                        // `step`).
                        self.out.push(self.pts[ce].d);
                        let ne = self.succ(ce);
                        if self.kept[self.xstart[ne] as usize + ne] != 1 {
                            return false;
                        }
                        if (ne, 0) == (e, j) {
                            break;
                        }
                        (ce, cj) = (ne, 0);
                        continue;
                    }
                    if self.repeated_ids {
                        if fwd && cj == 0 {
                            self.out_ids.push(self.pts[ce].id);
                        } else if !fwd && cj == cnt {
                            self.out_ids.push(self.pts[self.succ(ce)].id);
                        }
                    }
                    let p = self.start_point(ce, cj, fwd, c, u, v);
                    self.out.push(p);
                    let Some((ne, nj, nf)) = self.step(ce, cj, fwd) else {
                        return false;
                    };
                    if (ne, nj) == (e, j) {
                        break;
                    }
                    (ce, cj, fwd) = (ne, nj, nf);
                }
                if self.out.len() - ring_start >= 3 {
                    self.out_ends.push(self.out.len() as u32);
                } else {
                    self.out.truncate(ring_start);
                }
            }
        }
        // A mesh vertex where the contour passes more than once (rings paired there by
        // `chain_rings`) can be a vertex of the result more than once: its rings then touch
        // (or one ring pinches), which the boundary tracing of `visibility/pieces.rs` does not
        // take. Crossings cannot repeat (see the module documentation), nor can the light's
        // own vertices (its rings are simple and disjoint, or a contour's mesh vertices): a
        // vertex of the result twice is an input identity twice, which only a contour paired
        // at a vertex has (`repeated_ids`); without one, `out_ids` stayed empty.
        self.out_ids.sort_unstable();
        self.touching = self.out_ids.windows(2).any(|w| w[0] == w[1]);
        true
    }

    /// The direction where the `j`-th piece of edge `e` starts, as run (`fwd`) or reversed.
    fn start_point(&self, e: usize, j: usize, fwd: bool, c: DVec3, u: DVec3, v: DVec3) -> DVec3 {
        let (s0, s1) = (self.xstart[e] as usize, self.xstart[e + 1] as usize);
        let cnt = s1 - s0;
        let slot = if fwd {
            if j == 0 {
                return self.pts[e].d;
            }
            s0 + j - 1
        } else {
            if j == cnt {
                return self.pts[self.succ(e)].d;
            }
            s0 + j
        };
        let x = self.cross[self.slots[slot].cross as usize].x;
        let d = c + u * x.x + v * x.y;
        DVec3::new(d.x, d.y, d.z.max(0.0))
    }

    /// The kept piece after the `j`-th piece of edge `e` (as run, `fwd`, or reversed) along the
    /// boundary; `None` where there is not exactly one.
    fn step(&self, e: usize, j: usize, fwd: bool) -> Option<(usize, usize, bool)> {
        let (s0, s1) = (self.xstart[e] as usize, self.xstart[e + 1] as usize);
        let cnt = s1 - s0;
        let kept = |e: usize, j: usize| self.kept[self.xstart[e] as usize + e + j];
        let slot = if fwd {
            if j == cnt {
                let e2 = self.succ(e);
                return (kept(e2, 0) == 1).then_some((e2, 0, true));
            }
            s0 + j
        } else {
            if j == 0 {
                let e2 = self.pred(e);
                let c2 = (self.xstart[e2 + 1] - self.xstart[e2]) as usize;
                return (kept(e2, c2) == 2).then_some((e2, c2, false));
            }
            s0 + j - 1
        };
        // At a crossing: the one other piece that leaves it.
        let sl = self.slots[slot];
        let f = sl.other as usize;
        let jf = sl.twin as usize - self.xstart[f] as usize;
        let mut found = None;
        let mut count = 0;
        let straight = if fwd {
            (e, j + 1, 1u8)
        } else {
            (e, j - 1, 2u8)
        };
        for (pe, pj, want) in [straight, (f, jf + 1, 1u8), (f, jf, 2u8)] {
            if kept(pe, pj) == want {
                count += 1;
                found = Some((pe, pj, want == 1));
            }
        }
        if count == 1 { found } else { None }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The sweep's candidate pairs (keys with their low bits rounded off) are exactly the pairs
    /// of edges whose boxes meet, where the boxes' ends lie a few ulps apart (many in one
    /// rounded key), about `-1`, `+1` and the two zeros.
    #[test]
    fn sweep_pairs_are_the_meeting_boxes() {
        let mut unit = crate::math::test_unit_stream(0x3c6e_f372_fe94_f82b);
        let mut checked = 0;
        for round in 0..300 {
            let mut o = Overlay::with_capacity(64);
            o.clear();
            let base = [-1.0, 1.0, 0.0][round % 3];
            let mut id = 0;
            for _ in 0..1 + round % 3 {
                let start = o.pts.len();
                for _ in 0..3 + (unit() * 20.0) as usize {
                    let j = (unit() * 40.0) as i64 - 20;
                    let x = match base {
                        0.0 if j == 0 => [0.0, -0.0][(unit() * 2.0) as usize % 2],
                        0.0 => j as f64 * f64::from_bits(1) * 3.0,
                        b => f64::from_bits((f64::to_bits(b) as i64 + j) as u64),
                    };
                    let p = DVec2::new(x, (unit() * 8.0).floor() / 8.0);
                    o.pts.push(RingPoint {
                        p,
                        d: DVec3::new(p.x, p.y, 1.0),
                        id,
                        bridge: unit() < 0.1,
                    });
                    id += 1;
                }
                o.close(start, LIGHT);
            }
            let _ = o.resolve(DVec3::Z, DVec3::X, DVec3::Y);
            let mut found: Vec<(u32, u32)> =
                o.pairs.iter().map(|&(e, f)| (e.min(f), e.max(f))).collect();
            found.sort_unstable();
            let n = o.pts.len();
            let mut meet = Vec::new();
            for e in 0..n {
                for f in e + 1..n {
                    let (be, bf) = (o.bbox[e], o.bbox[f]);
                    let x = be[0] <= bf[1] && bf[0] <= be[1];
                    let y = be[2] <= bf[3] && bf[2] <= be[3];
                    if x && y && !o.pts[e].bridge && !o.pts[f].bridge {
                        meet.push((e as u32, f as u32));
                    }
                }
            }
            assert_eq!(found, meet, "round {round}");
            checked += meet.len();
        }
        assert!(checked > 5000, "{checked}");
    }

    /// The rays of [`Overlay::resolve`] (edges met by their boxes, half-open) count the same
    /// winding numbers as [`Overlay::winding`] (edges met by their ends' sides) along `+x`, and
    /// along `+y` where both decide, at points level with the rings' vertices (where the
    /// half-open rule decides) and elsewhere: for star-shaped rings of both orientations, one
    /// of them crossing the others.
    #[test]
    fn rays_count_the_windings_at_vertex_heights() {
        let mut unit = crate::math::test_unit_stream(0x2545_f491_4f6c_dd1d);
        let mut checked = 0;
        for round in 0..40 {
            let mut o = Overlay::with_capacity(64);
            o.clear();
            let mut id = 0;
            let rings = [
                (1.0, DVec2::ZERO),
                (0.6, DVec2::new(0.7, 0.2)),
                (0.3, DVec2::ZERO),
            ];
            for (k, (r, centre)) in rings.into_iter().enumerate() {
                let (r, centre) = (
                    r * (1.0 + 0.3 * unit()),
                    centre + DVec2::splat(0.1 * k as f64),
                );
                let start = o.pts.len();
                let n = 5 + (unit() * 8.0) as usize;
                for k in 0..n {
                    // On even rounds the two later rings run clockwise (winding -1 inside).
                    let dir = if round % 2 == 0 && start > 0 {
                        -1.0
                    } else {
                        1.0
                    };
                    let a = dir * core::f64::consts::TAU * (k as f64 + 0.3 * unit()) / n as f64;
                    // Grid coordinates, so that vertices share heights with other vertices.
                    let p = centre + DVec2::new(a.cos(), a.sin()) * r * (0.6 + 0.4 * unit());
                    let p = (p * 64.0).round() / 64.0;
                    o.pts.push(RingPoint {
                        p,
                        d: DVec3::new(p.x, p.y, 1.0),
                        id,
                        bridge: false,
                    });
                    id += 1;
                }
                o.close(start, LIGHT);
            }
            if !o.resolve(DVec3::Z, DVec3::X, DVec3::Y) {
                continue;
            }
            let heights: Vec<DVec2> = o.pts.iter().map(|q| q.p).collect();
            for v in heights {
                for q in [
                    DVec2::new(v.x + 0.25 * unit() - 0.125, v.y),
                    DVec2::new(v.x, v.y + 0.25 * unit() - 0.125),
                    v + DVec2::new(unit() - 0.5, unit() - 0.5) * 0.3,
                ] {
                    let (Some(wx), Some(w)) = (o.ray(q, true, usize::MAX), o.winding(0, LIGHT, q))
                    else {
                        continue;
                    };
                    assert_eq!(wx[0], w, "{q}");
                    if let Some(wy) = o.ray(q, false, usize::MAX) {
                        assert_eq!(wy[0], w, "{q}");
                    }
                    checked += 1;
                }
            }
        }
        assert!(checked > 1000, "{checked}");
    }
}
