//! The lazily built BSP of occluder equivalence classes in Pluecker space (seed 002 section 4,
//! Alg. 1 lines 1-13 and 31-35): occluder insertion by Theorem 1 and the merge of an occluder's
//! own classes at an undefined leaf. The query that drives the growth is in `query.rs`.
//!
//! Every inner node holds the line of an occluder edge; its hyperplane splits Pluecker space
//! into the lines with a positive and a negative side operator. A leaf is a class of lines:
//! visible (it stabs none of the occluders merged above it), invisible (it stabs one), or
//! undefined, with the occluders that may still block some of its lines.
//!
//! Lines here are the query lines of one tree: from a shading point through the tree's light
//! polygon, oriented towards the light, stabbing an occluder only between the point and the
//! light (the tile setup clips occluders so that this holds, see `tile.rs`).

use alloc::vec::Vec;
use core::mem::size_of;

use glam::DVec3;
use smallvec::SmallVec;

use super::line::{Orienter, Sign};

/// Most vertices of an occluder: a triangle cut by two planes has 5, a merged patch of mesh
/// triangles up to this many (`tile.rs`, `merge_patches`).
pub(crate) const MAX_OCCLUDER_VERTICES: usize = 6;

/// Tries of the light's test before its rate of decisions counts ([`Tree::try_light`]).
const LIGHT_WARMUP: u32 = 256;

/// The light's test keeps being tried on every mixed occluder while at least one try in this
/// many decides ([`Tree::try_light`]).
const LIGHT_RATE: u32 = 32;

/// Otherwise it is tried on one mixed occluder in this many, so that a tree whose later nodes
/// need it more finds out ([`Tree::try_light`]).
const LIGHT_SAMPLE: u32 = 64;

/// The index of the one invisible leaf every chain ends in (invisible leaves never change, so
/// they are shared).
pub(crate) const INVISIBLE: u32 = 0;

/// Which sign of the side operator, with its own edges, a query line has when it crosses an
/// occluder: fixed by the side of the occluder's plane the light lies on.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Crossing {
    /// The light lies on the side the occluder's winding normal points to: query lines cross
    /// it along the normal and have a positive side with every edge.
    Positive,
    /// The light lies behind the occluder's plane: negative with every edge.
    Negative,
    /// The light straddles the occluder's plane: either.
    Both,
}

/// An occluder polygon in the tree's coordinates, its vertices in the blocker's winding order:
/// a blocker triangle clipped to the part that can lie between a shading point of the tile and
/// the light (convex), or whole triangles of one mesh sharing edges, merged into the polygon
/// of their outer edges where every point of the tile sees it convex (not necessarily planar;
/// `tile.rs`, `merge_patches`).
#[derive(Debug, Clone, Copy)]
pub(crate) struct Occluder {
    verts: [DVec3; MAX_OCCLUDER_VERTICES],
    len: u8,
    crossing: Crossing,
    /// Bit `i`: edge `i` lies on the tile plane (it was made by the cut to the tile plane's
    /// upper side, `tile.rs`), so the query decides its side without its computed points
    /// ([`Occluder::on_tile`]).
    on_tile: u8,
}

impl Occluder {
    /// The occluder with vertices `v` (3 to [`MAX_OCCLUDER_VERTICES`], in order) crossed by the
    /// query lines as `crossing` says, with the edges of the mask `on_tile` on the tile plane.
    pub(crate) fn new(v: &[DVec3], crossing: Crossing, on_tile: u8) -> Occluder {
        let mut verts = [DVec3::ZERO; MAX_OCCLUDER_VERTICES];
        verts[..v.len()].copy_from_slice(v);
        Occluder {
            verts,
            len: v.len() as u8,
            crossing,
            on_tile,
        }
    }

    /// Whether edge `i` lies on the tile plane: the plane through a point of the tile and the
    /// edge's line is then the point's tangent plane, whatever the rounding of the edge's
    /// computed ends (see `query.rs`, "Edges on the tile plane").
    #[inline]
    pub(crate) fn on_tile(&self, i: u8) -> bool {
        self.on_tile & (1 << i) != 0
    }

    /// How the query lines cross it.
    #[inline]
    pub(crate) fn crossing(&self) -> Crossing {
        self.crossing
    }

    /// The vertices.
    #[inline]
    pub(crate) fn vertices(&self) -> &[DVec3] {
        &self.verts[..self.len as usize]
    }

    /// Edge `i`, from vertex `i` to the next (its line, oriented by the winding).
    #[inline]
    pub(crate) fn edge(&self, i: u8) -> (DVec3, DVec3) {
        let n = self.len;
        (self.verts[i as usize], self.verts[((i + 1) % n) as usize])
    }
}

/// A node of the tree.
#[derive(Debug, Clone)]
pub(crate) enum Node {
    /// The hyperplane of edge `edge` of occluder `occ`: lines with a positive side operator go
    /// to `pos`, negative to `neg`; lines with side zero (all of a fragment, which happens only
    /// when the shading point lies on the edge's line) go to `pos` when `zero_pos`, else `neg`:
    /// always the child where that edge does not close the occluder's invisible class.
    ///
    /// `pending` occluder ids (`len` from `start` in the list pool) are still to be inserted
    /// below the node: insertion is deferred until a query passes the node
    /// ([`Tree::push_down`]).
    Inner {
        occ: u32,
        edge: u8,
        pos: u32,
        neg: u32,
        zero_pos: bool,
        pending_start: u32,
        pending_len: u32,
    },
    /// A class of lines that stab no occluder.
    Visible,
    /// A class of lines that stab an occluder.
    Invisible,
    /// A class not yet decided, with the occluders that may block some of its lines: `len`
    /// ids from `start` in the tree's list pool.
    Undefined { start: u32, len: u32 },
}

/// Counters of one tree's growth.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct TreeCounters {
    /// Occluders merged at undefined leaves (seed 002 Alg. 1 line 32).
    pub merges: u64,
    /// Orientation tests of an occluder's vertex-to-vertex lines against a node (Alg. 1 lines
    /// 6-13).
    pub insertion_tests: u64,
    /// Fragments found visible at an undefined leaf, without developing it, because no
    /// occluder of its list can hide any of their lines from the query point.
    pub shortcuts: u64,
}

/// The lazily built tree of one light polygon and one set of occluders.
#[derive(Debug, Clone)]
pub(crate) struct Tree {
    /// The light polygon's vertices: one end of the vertex-to-vertex lines of the occluders
    /// and the light.
    light: SmallVec<[DVec3; 8]>,
    /// The tile's corners (one point for a single query): one end of the vertex-to-vertex
    /// lines of the tile and the occluders.
    cell: SmallVec<[DVec3; 4]>,
    occluders: Vec<Occluder>,
    nodes: Vec<Node>,
    /// The lists of the undefined leaves, each a range written once (an expanded leaf's range
    /// becomes garbage until [`Tree::compact`]).
    lists: Vec<u32>,
    /// Ids in `lists` that no leaf refers to any more.
    garbage: usize,
    /// Scratch of the insertion: a list on its way down ([`Tree::push_down`]).
    work: Vec<u32>,
    /// The other buffer of [`Tree::compact`].
    spare: Vec<u32>,
    rng: u64,
    /// At least `|p - c|` in each coordinate, after rounding, for every occluder vertex `p`
    /// and every cell or light corner `c`: the reach of the insertion's sign filter
    /// ([`Orienter::reach_bound`]).
    reach: f64,
    peak_bytes: usize,
    /// How often the light's vertex-to-vertex test was tried after the tile's came out mixed,
    /// how often it decided, and how often it was skipped ([`Tree::try_light`]).
    light_tries: u32,
    light_hits: u32,
    light_skips: u32,
    pub(crate) counters: TreeCounters,
}

/// The allocations of a tree, kept by a caller that builds one tree after another (the
/// per-call path): [`Tree::with_buffers`] takes them, [`Tree::into_buffers`] gives them back.
#[derive(Debug, Clone, Default)]
pub(crate) struct TreeBuffers {
    pub(crate) occluders: Vec<Occluder>,
    nodes: Vec<Node>,
    lists: Vec<u32>,
    work: Vec<u32>,
    spare: Vec<u32>,
}

impl Tree {
    /// The tree of a single undefined leaf holding every occluder (Alg. 2 line 8), for query
    /// lines from the convex hull of `cell` through the convex hull of `light`.
    #[cfg(test)]
    pub(crate) fn new(
        cell: &[DVec3],
        light: &[DVec3],
        occluders: Vec<Occluder>,
        seed: u64,
    ) -> Tree {
        Tree::with_buffers(
            cell,
            light,
            TreeBuffers {
                occluders,
                ..TreeBuffers::default()
            },
            seed,
        )
    }

    /// [`Tree::new`] with the occluders in `bufs` and its other allocations reused.
    pub(crate) fn with_buffers(
        cell: &[DVec3],
        light: &[DVec3],
        bufs: TreeBuffers,
        seed: u64,
    ) -> Tree {
        let TreeBuffers {
            occluders,
            nodes,
            lists,
            mut work,
            spare,
        } = bufs;
        work.clear();
        let mut t = Tree {
            light: light.iter().copied().collect(),
            cell: cell.iter().copied().collect(),
            occluders,
            nodes,
            lists,
            garbage: 0,
            work,
            spare,
            rng: seed | 1,
            reach: 0.0,
            peak_bytes: 0,
            light_tries: 0,
            light_hits: 0,
            light_skips: 0,
            counters: TreeCounters::default(),
        };
        let (mut lo, mut hi) = (DVec3::INFINITY, DVec3::NEG_INFINITY);
        let occ = t.occluders.iter().flat_map(|o| o.vertices().iter());
        for &p in t.cell.iter().chain(t.light.iter()).chain(occ) {
            lo = lo.min(p);
            hi = hi.max(p);
        }
        // A difference of two coordinates in [lo, hi] is at most their span, rounded up by one
        // rounding; a non-finite span leaves the reach at zero (every sign takes the per-point
        // filter).
        let span = (hi - lo).max_element() * (1.0 + 4.0 * f64::EPSILON);
        if span.is_finite() {
            t.reach = span;
        }
        t.reset();
        t
    }

    /// The tree's allocations, emptied, for the next [`Tree::with_buffers`].
    pub(crate) fn into_buffers(self) -> TreeBuffers {
        let Tree {
            mut occluders,
            mut nodes,
            mut lists,
            work,
            spare,
            ..
        } = self;
        occluders.clear();
        nodes.clear();
        lists.clear();
        TreeBuffers {
            occluders,
            nodes,
            lists,
            work,
            spare,
        }
    }

    /// Back to the root leaf with every occluder (the fallback when the tree outgrows its cap,
    /// and the "modified version" of seed 002 section 5.1 that forgets between queries).
    pub(crate) fn reset(&mut self) {
        self.nodes.clear();
        self.nodes.push(Node::Invisible);
        self.lists.clear();
        self.garbage = 0;
        let n = self.occluders.len() as u32;
        self.lists.extend(0..n);
        self.nodes.push(if n == 0 {
            Node::Visible
        } else {
            Node::Undefined { start: 0, len: n }
        });
        self.note_size();
    }

    /// The root node.
    pub(crate) const ROOT: u32 = 1;

    /// The node at `i`.
    #[inline]
    pub(crate) fn node(&self, i: u32) -> &Node {
        &self.nodes[i as usize]
    }

    /// The occluder `i`.
    #[inline]
    pub(crate) fn occluder(&self, i: u32) -> &Occluder {
        &self.occluders[i as usize]
    }

    /// Number of occluders the tree was built with.
    pub(crate) fn occluder_count(&self) -> usize {
        self.occluders.len()
    }

    /// Number of nodes (leaves included).
    pub(crate) fn node_count(&self) -> usize {
        self.nodes.len()
    }

    /// The memory the tree holds, in bytes (nodes, the list pool with its garbage and the
    /// compaction's other buffer, occluders; other allocator slack not counted).
    pub(crate) fn bytes(&self) -> usize {
        self.nodes.len() * size_of::<Node>()
            + (self.lists.len() + self.spare.capacity()) * size_of::<u32>()
            + self.occluders.len() * size_of::<Occluder>()
    }

    /// The list of the undefined leaf `(start, len)`.
    #[inline]
    pub(crate) fn list(&self, start: u32, len: u32) -> &[u32] {
        &self.lists[start as usize..(start + len) as usize]
    }

    /// Rewrites the list pool with the live lists only, once garbage is most of it: the pool
    /// then stays within twice the lists the leaves hold.
    fn compact(&mut self) {
        if self.garbage < 4096 || 2 * self.garbage < self.lists.len() {
            return;
        }
        let mut fresh = core::mem::take(&mut self.spare);
        fresh.clear();
        for node in &mut self.nodes {
            if let Node::Undefined { start, len }
            | Node::Inner {
                pending_start: start,
                pending_len: len,
                ..
            } = node
            {
                let s = *start as usize;
                *start = fresh.len() as u32;
                fresh.extend_from_slice(&self.lists[s..s + *len as usize]);
            }
        }
        self.spare = core::mem::replace(&mut self.lists, fresh);
        self.garbage = 0;
    }

    /// The reach of the tree's sign filter: at least `|p - c|` in each coordinate, after
    /// rounding, for any two of its occluder vertices, cell and light corners
    /// ([`Orienter::reach_bound`]).
    #[inline]
    pub(crate) fn reach(&self) -> f64 {
        self.reach
    }

    /// The largest [`Tree::bytes`] so far.
    pub(crate) fn peak_bytes(&self) -> usize {
        self.peak_bytes
    }

    fn note_size(&mut self) {
        self.peak_bytes = self.peak_bytes.max(self.bytes());
    }

    /// Develops the undefined leaf `n` (Alg. 1 lines 31-35) with the occluder `ro` of its
    /// list: `ro` replaces the leaf by its own classes (`bsp(ro)`, [`Tree::merge`]), and the
    /// others are inserted into them ([`Tree::insert`]). `n` becomes the root of `bsp(ro)`.
    pub(crate) fn expand_with(&mut self, n: u32, ro: u32) {
        let Node::Undefined { start, len } = self.nodes[n as usize] else {
            return;
        };
        let base = self.work.len();
        let (s, e) = (start as usize, (start + len) as usize);
        self.work
            .extend(self.lists[s..e].iter().copied().filter(|&o| o != ro));
        self.garbage += len as usize;
        self.nodes[n as usize] = Node::Visible;
        self.merge(n, ro);
        self.counters.merges += 1;
        let end = self.work.len();
        if end > base {
            self.give(n, base, end);
        }
        self.work.truncate(base);
        self.note_size();
        self.compact();
    }

    /// Inserts the pending list of the inner node `n` one level down (Alg. 1 lines 6-13, one
    /// node at a time): by the orientation of each occluder's vertex-to-vertex lines (Theorem 1,
    /// [`Tree::orientation`]), strictly positive to `pos`, strictly negative to `neg`, anything
    /// else to both (conservative); each child adds its part to its own list ([`Tree::give`]).
    ///
    /// Seed 002 inserts the other occluders of a developed leaf through the whole of
    /// `bsp(ro)` at once; here a node's occluders wait until a query passes it, so the exits of
    /// `bsp(ro)` that no query reaches, and the nodes below them, are never classified. The
    /// query pushes every node it passes, so the leaf it reaches holds every occluder that may
    /// block its class.
    pub(crate) fn push_down(&mut self, n: u32) {
        let Node::Inner {
            occ,
            edge,
            pos,
            neg,
            pending_start,
            pending_len,
            ..
        } = &mut self.nodes[n as usize]
        else {
            return;
        };
        if *pending_len == 0 {
            return;
        }
        let (occ, edge, pos, neg) = (*occ, *edge, *pos, *neg);
        let (s, len) = (*pending_start as usize, *pending_len as usize);
        *pending_len = 0;
        self.garbage += len;
        let lo = self.work.len();
        self.work.extend_from_slice(&self.lists[s..s + len]);
        let hi = self.work.len();
        let (ha, hb) = self.occluders[occ as usize].edge(edge);
        let reach = self.reach;
        let bounded = |o: Orienter| (o, o.reach_bound(reach));
        // Built on the first occluder that needs it (most nodes never try the light's test).
        let mut from_light: SmallVec<[(Orienter, f64); 8]> = SmallVec::new();
        let from_cell: SmallVec<[(Orienter, f64); 4]> = self
            .cell
            .iter()
            .map(|&c| bounded(Orienter::new(ha, hb, c)))
            .collect();
        // Three-way partition: [lo, p) positive, [p, q) both, [q, hi) negative.
        let (mut p, mut i, mut q) = (lo, lo, hi);
        while i < q {
            let o = self.work[i];
            let side = match self.orientation(o, &from_cell, false) {
                Sign::Zero if self.try_light() => {
                    if from_light.is_empty() {
                        from_light.extend(
                            self.light
                                .iter()
                                .map(|&a| bounded(Orienter::new(ha, hb, a))),
                        );
                    }
                    let side = self.orientation(o, &from_light, true);
                    self.light_hits += u32::from(side != Sign::Zero);
                    side
                }
                strict => strict,
            };
            match side {
                Sign::Positive => {
                    self.work.swap(p, i);
                    p += 1;
                    i += 1;
                }
                Sign::Zero => i += 1,
                Sign::Negative => {
                    q -= 1;
                    self.work.swap(i, q);
                }
            }
        }
        self.counters.insertion_tests += len as u64;
        if q > lo {
            self.give(pos, lo, q);
        }
        if hi > p {
            self.give(neg, p, hi);
        }
        self.work.truncate(lo);
        self.note_size();
        self.compact();
    }

    /// Whether to try the light's vertex-to-vertex test on an occluder the tile's test found
    /// mixed. Either answer is exact (a mixed occluder goes to both children); the light's
    /// test only makes lists shorter when it decides, and it costs as much as the tile's. Where
    /// it almost never decides (seen from a tile much smaller than the light, occluders that
    /// straddle a node's plane from the tile mostly straddle it from the light too: 0.5% of
    /// the tries on the terrain of `benches/plucker.rs` at 100K triangles), it is tried on one
    /// mixed occluder in [`LIGHT_SAMPLE`] only: after [`LIGHT_WARMUP`] tries, while fewer than
    /// one in [`LIGHT_RATE`] decided. The counters are the tree's, kept across
    /// [`Tree::reset`], and deterministic, so a tree's growth does not depend on the timing.
    fn try_light(&mut self) -> bool {
        let useful = self.light_tries < LIGHT_WARMUP
            || self.light_hits.saturating_mul(LIGHT_RATE) >= self.light_tries;
        if useful || self.light_skips >= LIGHT_SAMPLE {
            self.light_tries = self.light_tries.saturating_add(1);
            self.light_skips = 0;
            true
        } else {
            self.light_skips += 1;
            false
        }
    }

    /// Adds the ids `work[lo..hi]` to what node `n` holds: an invisible class ignores them, a
    /// visible one becomes undefined with them, an undefined leaf or an inner node's pending
    /// list is rewritten with them at the end of the pool.
    fn give(&mut self, n: u32, lo: usize, hi: usize) {
        let at = self.lists.len() as u32;
        let (start, len) = match &mut self.nodes[n as usize] {
            Node::Invisible => return,
            Node::Visible => {
                self.nodes[n as usize] = Node::Undefined {
                    start: at,
                    len: (hi - lo) as u32,
                };
                self.lists.extend_from_slice(&self.work[lo..hi]);
                return;
            }
            Node::Undefined { start, len }
            | Node::Inner {
                pending_start: start,
                pending_len: len,
                ..
            } => {
                let old = (*start as usize, *len as usize);
                *start = at;
                *len += (hi - lo) as u32;
                old
            }
        };
        self.lists.extend_from_within(start..start + len);
        self.lists.extend_from_slice(&self.work[lo..hi]);
        self.garbage += len;
    }

    /// A pseudo-random index below `n` (xorshift64): the occluder merged at a leaf is chosen at
    /// random (seed 002 section 4.3, as the pivot of quicksort).
    pub(crate) fn pick(&mut self, n: usize) -> usize {
        let mut x = self.rng;
        x ^= x << 13;
        x ^= x >> 7;
        x ^= x << 17;
        self.rng = x;
        ((x >> 11) % n as u64) as usize
    }

    /// Writes `bsp(o)` (seed 002 Fig. 4) with its root at node `at`: a chain over the occluder's
    /// edges whose last strict step is the invisible class and whose other exits are visible
    /// leaves.
    ///
    /// For a one-sided crossing with sign `s`, node `i` sends sign `s` on to edge `i + 1` (after
    /// the last edge: invisible) and everything else, side zero included, to a visible leaf. For
    /// [`Crossing::Both`] the root (edge 0) splits into a positive chain over edges `1..k` and a
    /// negative chain over edges `1..k` and then edge 0 again; side zero at the root takes the
    /// negative chain, whose final strict test of edge 0 lets it out to a visible leaf. A line
    /// with side zero for any edge never reaches the invisible class: it passes through the
    /// occluder's boundary or plane, not its interior (the open-occluder rule of `mod.rs`).
    fn merge(&mut self, at: u32, o: u32) {
        let k = self.occluders[o as usize].len;
        match self.occluders[o as usize].crossing {
            Crossing::Positive => self.chain(at, o, (0..k).collect(), true),
            Crossing::Negative => self.chain(at, o, (0..k).collect(), false),
            Crossing::Both => {
                let p = self.push(Node::Visible);
                let m = self.push(Node::Visible);
                self.nodes[at as usize] = Node::Inner {
                    occ: o,
                    edge: 0,
                    pos: p,
                    neg: m,
                    zero_pos: false,
                    pending_start: 0,
                    pending_len: 0,
                };
                self.chain(p, o, (1..k).collect(), true);
                let mut edges: SmallVec<[u8; 8]> = (1..k).collect();
                edges.push(0);
                self.chain(m, o, edges, false);
            }
        }
    }

    /// The chain of nodes over `edges` of occluder `o` starting at node `first`, passing lines
    /// with the strict sign `positive` on and sending the others to fresh visible leaves.
    fn chain(&mut self, first: u32, o: u32, edges: SmallVec<[u8; 8]>, positive: bool) {
        let mut at = first;
        for (i, &e) in edges.iter().enumerate() {
            let next = if i + 1 == edges.len() {
                INVISIBLE
            } else {
                self.push(Node::Visible)
            };
            let leaf = self.push(Node::Visible);
            let (pos, neg) = if positive { (next, leaf) } else { (leaf, next) };
            self.nodes[at as usize] = Node::Inner {
                occ: o,
                edge: e,
                pos,
                neg,
                zero_pos: !positive,
                pending_start: 0,
                pending_len: 0,
            };
            at = next;
        }
    }

    fn push(&mut self, node: Node) -> u32 {
        self.nodes.push(node);
        (self.nodes.len() - 1) as u32
    }

    /// The orientation of the lines occluder `o` blocks, relative to a node's line, bounded by
    /// vertex-to-vertex lines (seed 002 Theorem 1): `Positive` / `Negative` when all are strictly
    /// so, `Zero` for "mixed" (some of each, or one with side zero).
    ///
    /// Signs are the filter's strict ones only: a value within rounding of zero counts as
    /// mixed, which is conservative (the occluder goes to both children) and certified (a strict
    /// answer is never wrong), so insertion needs no exact arithmetic.
    ///
    /// A blocked query line passes through the tile, then the occluder, then the light, so it
    /// stabs both the pair (occluder, light), the paper's bound, and the pair (tile, occluder):
    /// either vvset may decide, and the tile's is the tighter one for tiles smaller than the
    /// light (for a single point it is exact). The lines run towards the light: `c -> b` from a
    /// tile corner through an occluder vertex, `b -> a` from an occluder vertex to a light
    /// vertex. `orienters[k]` evaluates `det[p - o_k, h_a - o_k, h_b - o_k]`, the side of the
    /// line `o_k -> p`: as is for the tile (`reverse` false), reversed for the light.
    fn orientation(&self, o: u32, orienters: &[(Orienter, f64)], reverse: bool) -> Sign {
        let (mut pos, mut neg) = (false, false);
        for (or, bound) in orienters {
            for &b in self.occluders[o as usize].vertices() {
                let Some(s) = or.strict_sign_within(b, *bound) else {
                    return Sign::Zero;
                };
                match if reverse { s.flip() } else { s } {
                    Sign::Positive => pos = true,
                    Sign::Negative => neg = true,
                    Sign::Zero => return Sign::Zero,
                }
                if pos && neg {
                    return Sign::Zero;
                }
            }
        }
        match (pos, neg) {
            (true, false) => Sign::Positive,
            (false, true) => Sign::Negative,
            _ => Sign::Zero,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tree() -> Tree {
        let light = [
            DVec3::new(0.0, 0.0, 2.0),
            DVec3::new(1.0, 0.0, 2.0),
            DVec3::new(0.0, 1.0, 2.0),
        ];
        let occ = Occluder::new(
            &[
                DVec3::new(0.2, 0.2, 1.0),
                DVec3::new(0.4, 0.2, 1.0),
                DVec3::new(0.2, 0.4, 1.0),
            ],
            Crossing::Positive,
            0,
        );
        Tree::new(&[DVec3::ZERO], &light, alloc::vec![occ], 3)
    }

    #[test]
    fn the_light_test_is_sampled_only_where_it_rarely_decides() {
        // Never deciding: tried on every mixed occluder for the warm-up, then on one in
        // LIGHT_SAMPLE + 1 (the skips between tries), and the schedule survives a reset.
        let mut t = tree();
        for k in 0..LIGHT_WARMUP {
            assert!(t.try_light(), "warm-up try {k}");
        }
        t.reset();
        let tried: Vec<u32> = (0..3 * (LIGHT_SAMPLE + 1))
            .filter(|_| t.try_light())
            .collect();
        assert_eq!(tried.len(), 3, "{tried:?}");
        // Deciding one time in LIGHT_RATE keeps it on every occluder.
        let mut t = tree();
        for k in 0..10 * LIGHT_WARMUP {
            assert!(t.try_light(), "try {k}");
            t.light_hits += u32::from(k % LIGHT_RATE == 0);
        }
        // Rarer than that, it is sampled again.
        for _ in 0..LIGHT_WARMUP {
            t.try_light();
        }
        let tried = (0..2 * LIGHT_SAMPLE).filter(|_| t.try_light()).count();
        assert!(tried <= 2, "{tried}");
    }
}
