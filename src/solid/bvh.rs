//! A bounding-volume hierarchy over the triangles of a mesh: axis-aligned boxes, built once,
//! queried with any conservative box test (the visibility layer's shafts and cones).
//!
//! The tree is built top-down: each node's triangles are split at the median of their
//! centroids along the longest axis of the centroids' box (Wald, Boulos and Shirley, *Ray
//! tracing deformable scenes using dynamic bounding volume hierarchies*, ACM TOG 26(1), 2007,
//! section 3 describes the same family of builders; the median split is the simplest of them
//! and never degenerates into an empty child). Leaves hold at most [`Bvh::LEAF_SIZE`]
//! triangles.
//!
//! Nodes are stored compactly, 32 bytes each: the box as six `f32` relative to the root box
//! (coordinates `(p - origin) / scale`, rounded outwards, so the stored box always contains the
//! exact one), and two `u32`. With leaves of two to four triangles and one `u32` per triangle
//! for the leaf order, a tree costs 20 to 30 bytes per triangle ([`Bvh::byte_size`]).

use alloc::vec::Vec;

use glam::DVec3;
use smallvec::SmallVec;

use super::mesh::TriangleMesh;

/// One node: a box relative to the root box and either two children or a run of triangles.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Node {
    /// Lower corner, `(p - origin) / scale`, rounded down.
    lo: [f32; 3],
    /// Upper corner, rounded up.
    hi: [f32; 3],
    /// A leaf's first index into [`Bvh::order`]; an inner node's second child (its first child
    /// is the next node).
    start: u32,
    /// A leaf's triangle count (at least 1); 0 for an inner node.
    count: u32,
}

/// A bounding-volume hierarchy over the triangles of one [`TriangleMesh`] (or over any boxes,
/// [`Bvh::over_boxes`]).
///
/// Queries never miss a triangle whose box passes the caller's test: every stored box contains
/// the exact box of its triangles after the conversion back to `f64` (the conversion's rounding
/// is covered by a padding computed at build time).
///
/// # Examples
///
/// ```
/// use arealight::glam::DVec3;
/// use arealight::solid::{Bvh, ConvexPolyhedron};
/// let ball = ConvexPolyhedron::icosphere(DVec3::ZERO, 1.0, 2)?;
/// let m = ball.mesh();
/// let bvh = Bvh::build(m);
/// // The triangles in leaves whose boxes reach above z = 0.9: every triangle that does, and
/// // few others.
/// let mut top = Vec::new();
/// bvh.for_each(|_, hi| hi.z >= 0.9, |t| top.push(t as usize));
/// let reaching = (0..m.triangle_count()).filter(|&t| m.triangle(t).iter().any(|v| v.z >= 0.9));
/// assert!(reaching.clone().all(|t| top.contains(&t)));
/// assert!(top.len() < 3 * reaching.count());
/// # Ok::<(), arealight::GeomError>(())
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct Bvh {
    nodes: Vec<Node>,
    /// Triangle indices in leaf order.
    order: Vec<u32>,
    /// Centre of the root box.
    origin: DVec3,
    /// Largest half-extent of the root box (positive).
    scale: f64,
    /// Added on every side of a decoded box: covers the rounding of `origin + scale * f`.
    pad: f64,
}

impl Bvh {
    /// Most triangles in one leaf.
    pub const LEAF_SIZE: usize = 4;

    /// Builds the hierarchy over every triangle of `mesh` (about `n log n`).
    #[must_use]
    pub fn build(mesh: &TriangleMesh) -> Self {
        let boxes: Vec<(DVec3, DVec3)> = (0..mesh.triangle_count())
            .map(|t| {
                let [a, b, c] = mesh.triangle(t);
                (a.min(b).min(c), a.max(b).max(c))
            })
            .collect();
        Self::over_boxes(&boxes)
    }

    /// Builds the hierarchy over any axis-aligned boxes `(lo, hi)` (finite, `lo <= hi`): its
    /// queries then name the boxes by their index, as [`Bvh::build`]'s name triangles.
    #[must_use]
    pub fn over_boxes(boxes: &[(DVec3, DVec3)]) -> Self {
        let n = boxes.len();
        let (lo, hi) = boxes.iter().fold(
            (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)),
            |(lo, hi), b| (lo.min(b.0), hi.max(b.1)),
        );
        let origin = if n == 0 { DVec3::ZERO } else { 0.5 * (lo + hi) };
        let scale = if n == 0 {
            1.0
        } else {
            (0.5 * (hi - lo)).max_element().max(f64::MIN_POSITIVE)
        };
        // `origin + scale * f` with |f| <= 1 (plus one f32 ulp) rounds by at most an ulp of
        // |origin| + scale per operation; four of them leave a wide margin.
        let pad = 4.0 * f64::EPSILON * (origin.abs().max_element() + 2.0 * scale);
        let mut bvh = Bvh {
            nodes: Vec::with_capacity(n.div_ceil(Self::LEAF_SIZE) * 2),
            order: (0..n as u32).collect(),
            origin,
            scale,
            pad,
        };
        if n == 0 {
            return bvh;
        }
        let centroids: Vec<DVec3> = boxes.iter().map(|b| 0.5 * (b.0 + b.1)).collect();
        // Depth first: a node's first child is the next node; its second child gets its index
        // when its range is popped, after the first child's whole subtree (LIFO), and is
        // recorded in the parent then. Entries: (parent to record as second child, first, end).
        let mut stack: SmallVec<[(Option<usize>, usize, usize); 64]> = SmallVec::new();
        stack.push((None, 0, n));
        while let Some((parent, first, end)) = stack.pop() {
            let node = bvh.nodes.len();
            if let Some(p) = parent {
                bvh.nodes[p].start = node as u32;
            }
            let range = &mut bvh.order[first..end];
            let (blo, bhi) = range.iter().fold(
                (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)),
                |(lo, hi), &t| (lo.min(boxes[t as usize].0), hi.max(boxes[t as usize].1)),
            );
            let leaf = range.len() <= Self::LEAF_SIZE;
            bvh.nodes.push(Node {
                lo: bvh.encode(blo, false),
                hi: bvh.encode(bhi, true),
                start: if leaf { first as u32 } else { 0 },
                count: if leaf { (end - first) as u32 } else { 0 },
            });
            if leaf {
                continue;
            }
            let range = &mut bvh.order[first..end];
            let (clo, chi) = range.iter().fold(
                (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)),
                |(lo, hi), &t| (lo.min(centroids[t as usize]), hi.max(centroids[t as usize])),
            );
            let ext = chi - clo;
            let axis = if ext.x >= ext.y && ext.x >= ext.z {
                0
            } else if ext.y >= ext.z {
                1
            } else {
                2
            };
            let mid = range.len() / 2;
            range.select_nth_unstable_by(mid, |&a, &b| {
                centroids[a as usize][axis].total_cmp(&centroids[b as usize][axis])
            });
            stack.push((Some(node), first + mid, end));
            stack.push((None, first, first + mid));
        }
        bvh
    }

    /// `(p - origin) / scale` as `f32`, rounded down (`up` false) or up.
    fn encode(&self, p: DVec3, up: bool) -> [f32; 3] {
        let r = (p - self.origin) / self.scale;
        [r.x, r.y, r.z].map(|x| {
            let f = x as f32;
            // The division rounds too: step one more f32 ulp outwards, far above it.
            if up {
                f.next_up().next_up()
            } else {
                f.next_down().next_down()
            }
        })
    }

    /// The box of node `i` in world coordinates, padded to contain the exact one.
    fn decode(&self, i: usize) -> (DVec3, DVec3) {
        let n = &self.nodes[i];
        let lo =
            self.origin + self.scale * DVec3::new(n.lo[0].into(), n.lo[1].into(), n.lo[2].into());
        let hi =
            self.origin + self.scale * DVec3::new(n.hi[0].into(), n.hi[1].into(), n.hi[2].into());
        (lo - DVec3::splat(self.pad), hi + DVec3::splat(self.pad))
    }

    /// Calls `visit` with every triangle (index into the mesh) of every leaf whose box passes
    /// `keep(lo, hi)`, descending only into nodes whose boxes pass. `keep` must be conservative
    /// (true for any box that may hold what the caller looks for): a triangle is skipped only
    /// when some box holding it failed.
    pub fn for_each(&self, mut keep: impl FnMut(DVec3, DVec3) -> bool, mut visit: impl FnMut(u32)) {
        self.for_each_with(
            (),
            |lo, hi, ()| keep(lo, hi).then_some(()),
            |t, ()| visit(t),
        );
    }

    /// [`Bvh::for_each`] with a state passed down the tree: `test(lo, hi, state)` returns `None`
    /// to skip a node, or the state its children start from (a node found inside a region
    /// tells its triangles so, and their tests can be skipped); `visit(t, state)` gets each
    /// triangle of a leaf that passed with that leaf's state.
    pub fn for_each_with<S: Copy>(
        &self,
        root: S,
        mut test: impl FnMut(DVec3, DVec3, S) -> Option<S>,
        mut visit: impl FnMut(u32, S),
    ) {
        if self.nodes.is_empty() {
            return;
        }
        let mut stack: SmallVec<[(u32, S); 64]> = SmallVec::new();
        stack.push((0, root));
        while let Some((i, state)) = stack.pop() {
            let (lo, hi) = self.decode(i as usize);
            let Some(state) = test(lo, hi, state) else {
                continue;
            };
            let n = &self.nodes[i as usize];
            if n.count > 0 {
                let s = n.start as usize;
                for &t in &self.order[s..s + n.count as usize] {
                    visit(t, state);
                }
            } else {
                stack.push((n.start, state));
                stack.push((i + 1, state));
            }
        }
    }

    /// Number of nodes.
    #[must_use]
    pub fn node_count(&self) -> usize {
        self.nodes.len()
    }

    /// Number of triangles.
    #[must_use]
    pub fn triangle_count(&self) -> usize {
        self.order.len()
    }

    /// Heap bytes held by the tree (nodes and leaf order) plus the struct itself.
    #[must_use]
    pub fn byte_size(&self) -> usize {
        self.nodes.len() * core::mem::size_of::<Node>()
            + self.order.len() * core::mem::size_of::<u32>()
            + core::mem::size_of::<Self>()
    }
}
