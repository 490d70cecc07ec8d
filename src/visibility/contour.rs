//! Contours of closed meshes seen from a point, found through a hierarchy of facing bounds
//! instead of a visit of every triangle (issue 17).
//!
//! Seen from a point, the front faces of a closed mesh (by the facing predicate,
//! [`FacingAt::front`]) have as the boundary of their sum the contour edges, the edges between a
//! front face and one that is not (thesis 003 eq. 4.1): every other edge is run once each way by
//! two front faces and cancels. So the contour, oriented as its front face runs it, is a closed
//! chain whose winding number about a direction is the number of front faces covering it: the
//! union of the front faces is where it is positive. That is all the one-pass union needs of a
//! closed mesh (see `visibility/union.rs` and [`super::overlay`]), and it is found here without
//! hashing or even visiting the faces away from the contour:
//!
//! - the mesh's edges are stored with their two faces, grouped by connected component (a
//!   component's contour is closed by itself, so whole components can be culled by a shaft
//!   without opening a contour), through a bounding-volume hierarchy over the components' boxes
//!   where there are many;
//! - within a large component, a hierarchy over its edges keeps for each node a bound on the
//!   signed distances of a point from all the face planes of its edges (a cone of normals about
//!   an axis and the range of the planes' offsets from the node's centre, the normal cones of
//!   Sander et al., *Silhouette clipping*, SIGGRAPH 2000, section 4, with the offsets anchored
//!   at the node): a node whose faces are all front faces, or none, holds no contour edge and is
//!   skipped with its subtree. The hierarchy is built binary (splits take the longer of the
//!   edges' midpoints and their mean normals, scaled by the component's size, so that the cones
//!   of normals stay narrow in meshes such as tori, whose nodes would otherwise hold whole
//!   cross-sections of the tube) and walked four children at a time ([`WideNode`]: a node holds
//!   its binary node's grandchildren's bounds side by side, tested as vector lanes);
//! - with [`Cull::Cone`], nodes whose boxes lie outside a cone through the point (the light's
//!   box in the chart) are skipped as well: the contour found is then the part in that cone,
//!   as open chains and closed rings ([`chain_rings`]); `visibility/mesh_pieces.rs` restores
//!   the winding the rest contributes inside the cone.
//!
//! A query declines where the point lies inside the box of a component it takes: outside it,
//! the component lies in an open half-space away from the point (beyond a face plane of the
//! box), so its front faces project into one open hemisphere and their boundaries are closed
//! rings there, whose winding numbers add up to the count of front faces covering a direction.
//! Inside it the front faces can surround the point (the walls and floor of a cup seen from
//! its well), and the contour (the well's rim) then bounds the part they leave open.
//!
//! The bounds are conservative beyond rounding (see [`FacingNode`]): every face of a skipped
//! node gets the same answer from the facing predicate itself, so the contour is exactly the
//! one a visit of every edge finds.

use alloc::vec;
use alloc::vec::Vec;

use glam::DVec3;
use smallvec::SmallVec;

use super::cull::Shaft;
use super::union::Closed;
use crate::math::sqrt;
use crate::solid::facing::FacingAt;
use crate::solid::{Bvh, TriangleMesh};

/// Components with at least this many edges get a hierarchy of facing bounds; smaller ones are
/// tested edge by edge (a box has 18 edges).
const TREE_MIN_EDGES: usize = 48;

/// Weight of the normals' axes against the positions' (in units of the component's size) when
/// the facing hierarchy chooses the axis of a split.
const NORMAL_WEIGHT: f64 = 0.25;

/// Most edges in a leaf of the facing hierarchy.
const LEAF_EDGES: usize = 6;

/// Meshes of at most this many faces have their whole contour ([`Cull::All`]) found by one
/// pass over their faces and edges instead of the facing hierarchy's walk (a multiple of 64).
const FLAT_MAX_FACES: usize = 1024;

/// Meshes with more components than this get a hierarchy over the components' boxes.
const COMPONENT_BVH_MIN: usize = 16;

/// No facing hierarchy for a component.
const NO_TREE: u32 = u32::MAX;

/// What is precomputed for the contours of one closed mesh ([`TriangleMesh::is_closed`]): its
/// edges with their faces by component, the components' boxes, and the facing hierarchies.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct MeshContours {
    comps: Vec<Component>,
    /// Over the components' boxes, for meshes of many components.
    comp_bvh: Option<Bvh>,
    /// `[a, b, f0, f1]`: the edge `a -> b` runs counter-clockwise around face `f0`, `b -> a`
    /// around `f1` ([`crate::solid::MeshEdge`]); grouped by component, and in leaf order within
    /// a component with a hierarchy.
    edges: Vec<[u32; 4]>,
    nodes: Vec<WideNode>,
}

/// A connected component (through shared edges) of a closed mesh.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Component {
    lo: DVec3,
    hi: DVec3,
    /// Its edges: `edges[start..end]`.
    start: u32,
    end: u32,
    /// Root of its facing hierarchy (a [`WideNode`]), or [`NO_TREE`].
    root: u32,
}

/// A node of a facing hierarchy: bounds on the signed distance `s_f = n_f . (x - p_f)` of a point
/// `x` from the plane of every face `f` of its edges (`n_f` the face's unit normal as the mesh
/// stores it, `p_f` a corner).
///
/// With `y = x - center`, `s_f = n_f . y + q_f` where `q_f = n_f . (center - p_f)` is the
/// signed distance of the centre from the plane, and `n_f . y = axis . y + (n_f - axis) . y`
/// with `|n_f - axis| <= spread`: so `s_f` lies in `[axis . y - spread |y| + q_lo, axis . y +
/// spread |y| + q_hi]`. `spread`, `q_lo` and `q_hi` are widened at build time beyond their
/// rounding (relative `1e-9`), far below the facing predicate's tolerance (`1e-11` of the mesh's
/// size plus the point's distance), which is what the query compares the bounds with.
#[derive(Debug, Clone, Copy, PartialEq)]
struct FacingNode {
    center: DVec3,
    /// Half the extent of the box of its faces about `center`.
    half: DVec3,
    /// `half.max_element()`.
    half_max: f64,
    axis: DVec3,
    spread: f64,
    q_lo: f64,
    q_hi: f64,
    /// A leaf's first edge; for an inner node, the end of its subtree (its first child is the
    /// next node, and its subtree's nodes are consecutive).
    start: u32,
    /// A leaf's edge count; 0 for an inner node.
    count: u32,
}

/// Children of a [`WideNode`].
const WIDE: usize = 4;

/// A node of the facing hierarchy as the query walks it: the [`FacingNode`] bounds of up to four
/// children side by side, one array per coordinate, so that the four facing tests run as a few
/// two-lane vector operations (a wide hierarchy, as the BVH4 of ray tracers: Wald et al.,
/// *Getting rid of packets*, 2008). Each child is the binary hierarchy's grandchild (or child,
/// where that is a leaf): a query tests the same bounds as in the binary hierarchy, without its
/// inner levels in between. A slot without a child has bounds that no point can make mixed
/// (`q_lo = q_hi = -inf`).
#[derive(Debug, Clone, Copy, PartialEq)]
struct WideNode {
    cx: [f64; WIDE],
    cy: [f64; WIDE],
    cz: [f64; WIDE],
    ax: [f64; WIDE],
    ay: [f64; WIDE],
    az: [f64; WIDE],
    spread: [f64; WIDE],
    q_lo: [f64; WIDE],
    q_hi: [f64; WIDE],
    /// Half extents of the children's boxes (for the cone test).
    half: [DVec3; WIDE],
    /// The part of the cone test's rounding margin from the child's box: `1e-9` of its centre's
    /// largest coordinate and its largest half extent.
    margin: [f64; WIDE],
    /// A leaf's first edge, or an inner child's node.
    child: [u32; WIDE],
    /// A leaf's edge count; 0 for an inner child (or no child).
    count: [u32; WIDE],
}

impl WideNode {
    /// A node without children.
    fn empty() -> Self {
        WideNode {
            cx: [0.0; WIDE],
            cy: [0.0; WIDE],
            cz: [0.0; WIDE],
            ax: [0.0; WIDE],
            ay: [0.0; WIDE],
            az: [0.0; WIDE],
            spread: [0.0; WIDE],
            q_lo: [f64::NEG_INFINITY; WIDE],
            q_hi: [f64::NEG_INFINITY; WIDE],
            half: [DVec3::ZERO; WIDE],
            margin: [0.0; WIDE],
            child: [0; WIDE],
            count: [0; WIDE],
        }
    }

    /// Child slot `k` set to the bounds of `n`.
    fn set(&mut self, k: usize, n: &FacingNode, child: u32) {
        self.cx[k] = n.center.x;
        self.cy[k] = n.center.y;
        self.cz[k] = n.center.z;
        self.ax[k] = n.axis.x;
        self.ay[k] = n.axis.y;
        self.az[k] = n.axis.z;
        self.spread[k] = n.spread;
        self.q_lo[k] = n.q_lo;
        self.q_hi[k] = n.q_hi;
        self.half[k] = n.half;
        self.margin[k] = 1e-9 * (n.center.abs().max_element() + n.half_max);
        self.child[k] = child;
        self.count[k] = n.count;
    }

    /// The children whose faces may be mixed seen from `x` (facing predicate tolerance `tol`),
    /// as bits: a child's faces are all front faces where the lower bound of [`FacingNode`]
    /// clears the tolerance by half of it (`> 1.5 tol`), none where the upper bound stays
    /// below half of it (`< 0.5 tol`), else mixed.
    #[inline(always)]
    fn mixed(&self, x: DVec3, tol: f64) -> u32 {
        let (mut lo, mut hi) = ([0.0f64; WIDE], [0.0f64; WIDE]);
        for k in 0..WIDE {
            let (yx, yy, yz) = (x.x - self.cx[k], x.y - self.cy[k], x.z - self.cz[k]);
            let mid = self.ax[k] * yx + self.ay[k] * yy + self.az[k] * yz;
            let spread = self.spread[k] * sqrt(yx * yx + yy * yy + yz * yz);
            lo[k] = mid - spread + self.q_lo[k];
            hi[k] = mid + spread + self.q_hi[k];
        }
        let (front, none) = (1.5 * tol, 0.5 * tol);
        // Without short-circuits, so that the lanes stay vector operations.
        let mut bits = 0;
        for k in 0..WIDE {
            bits |= u32::from(!(lo[k] > front) & !(hi[k] < none)) << k;
        }
        bits
    }
}

/// Which components a contour query takes.
#[derive(Clone, Copy)]
pub(crate) enum Cull<'a> {
    /// All of them (a light's own contour); the query declines when the point lies inside the
    /// box of one of them.
    All,
    /// Those whose boxes may meet the shaft; the query declines when the point lies inside the
    /// box of one of them.
    Shaft(&'a Shaft),
    /// As [`Cull::Shaft`], and within a component with a facing hierarchy only the nodes whose
    /// boxes may meet the cone through the point bounded by the given planes (unit normals
    /// through the point, the cone on their positive sides): the edges left out lie outside
    /// that cone beyond rounding, and the contour is then a set of chains, closed or open
    /// (ending outside the cone), see [`chain_rings`].
    Cone(&'a Shaft, &'a [DVec3; 4]),
}

impl MeshContours {
    /// The precomputation for a closed mesh, given its components and their boxes (`closed`,
    /// those of the union path, which the query's declining rule, a point inside a component's
    /// box, must agree with).
    pub(crate) fn new(mesh: &TriangleMesh, closed: &Closed) -> Self {
        let (comp_of, boxes) = (&closed.component, &closed.boxes);
        // Edges grouped by component (counting sort).
        let nc = boxes.len();
        let mut first = vec![0u32; nc + 1];
        for e in mesh.edges() {
            first[comp_of[e.f0 as usize] as usize + 1] += 1;
        }
        for k in 0..nc {
            first[k + 1] += first[k];
        }
        let mut fill = first.clone();
        let mut edges = vec![[0u32; 4]; mesh.edges().len()];
        for e in mesh.edges() {
            let k = comp_of[e.f0 as usize] as usize;
            edges[fill[k] as usize] = [e.a, e.b, e.f0, e.f1];
            fill[k] += 1;
        }
        let mut nodes = Vec::new();
        let mut binary = Vec::new();
        let comps = (0..nc)
            .map(|k| {
                let (start, end) = (first[k] as usize, first[k + 1] as usize);
                let root = if end - start >= TREE_MIN_EDGES {
                    binary.clear();
                    build_tree(mesh, &mut edges[start..end], start as u32, &mut binary);
                    widen(&binary, 0, &mut nodes)
                } else {
                    NO_TREE
                };
                Component {
                    lo: boxes[k].0,
                    hi: boxes[k].1,
                    start: start as u32,
                    end: end as u32,
                    root,
                }
            })
            .collect();
        let comp_bvh = (nc > COMPONENT_BVH_MIN).then(|| Bvh::over_boxes(boxes));
        MeshContours {
            comps,
            comp_bvh,
            edges,
            nodes,
        }
    }

    /// Heap bytes held (edges, nodes, components and their hierarchy) plus the struct.
    pub(crate) fn byte_size(&self) -> usize {
        self.edges.len() * core::mem::size_of::<[u32; 4]>()
            + self.nodes.len() * core::mem::size_of::<WideNode>()
            + self.comps.len() * core::mem::size_of::<Component>()
            + self.comp_bvh.as_ref().map_or(0, Bvh::byte_size)
            + core::mem::size_of::<Self>()
    }

    /// Appends to `out` the contour edges of `mesh` (the mesh this was built for) seen from `x`,
    /// each as its front face runs it, `(from, to)` by vertex index: the edges whose two faces
    /// differ in [`FacingAt::front`]. Components are taken as `cull` says; `false` (with `out`
    /// in any state) where it declines.
    pub(crate) fn contour(
        &self,
        mesh: &TriangleMesh,
        x: DVec3,
        cull: Cull<'_>,
        out: &mut Vec<(u32, u32)>,
    ) -> bool {
        let at = FacingAt::new(mesh, x);
        let walk = Walk {
            at,
            normals: mesh.normals(),
            offsets: mesh.offsets(),
            edges: &self.edges,
            nodes: &self.nodes,
            x,
            cone: match cull {
                Cull::Cone(_, planes) => Some(Cone::new(planes, x)),
                _ => None,
            },
        };
        match cull {
            Cull::All if mesh.triangles().len() <= FLAT_MAX_FACES => {
                // A small mesh seen whole (a light's own contour): every face classified once,
                // in one pass over the planes, costs less than the hierarchy's walk, which
                // visits most nodes of such a mesh anyway. The same contour edges as the walk's,
                // in their stored order (chaining does not depend on the order).
                let mut front = [0u8; FLAT_MAX_FACES];
                for ((s, &n), &o) in front.iter_mut().zip(mesh.normals()).zip(mesh.offsets()) {
                    *s = u8::from(at.front(n, o));
                }
                // Face indices are below the face count, at most `FLAT_MAX_FACES` (a power of
                // two): the mask changes none and spares the bounds checks.
                let bit = |f: u32| front[f as usize & (FLAT_MAX_FACES - 1)];
                for c in &self.comps {
                    if !outside_box(c.lo, c.hi, x) {
                        return false;
                    }
                    for &[a, b, f0, f1] in &self.edges[c.start as usize..c.end as usize] {
                        let s0 = bit(f0);
                        if s0 != bit(f1) {
                            out.push(if s0 != 0 { (a, b) } else { (b, a) });
                        }
                    }
                }
                true
            }
            Cull::All => {
                for c in &self.comps {
                    if !outside_box(c.lo, c.hi, x) || !walk.component(c, out) {
                        return false;
                    }
                }
                true
            }
            Cull::Shaft(shaft) | Cull::Cone(shaft, _) => {
                let mut ok = true;
                let mut take = |c: &Component| {
                    if ok && shaft.may_meet_box(c.lo, c.hi) {
                        ok = outside_box(c.lo, c.hi, x) && walk.component(c, out);
                    }
                };
                match &self.comp_bvh {
                    Some(bvh) => bvh.for_each_with(
                        shaft.all_planes(),
                        |lo, hi, mask| shaft.classify_box(lo, hi, mask),
                        |k, _| take(&self.comps[k as usize]),
                    ),
                    None => self.comps.iter().for_each(take),
                }
                ok
            }
        }
    }
}

/// Whether `x` lies outside the box `[lo, hi]` beyond rounding (relative `1e-9` of the box's
/// size and position), as [`super::union::Closed`] decides it.
fn outside_box(lo: DVec3, hi: DVec3, x: DVec3) -> bool {
    let m = 1e-9 * ((hi - lo).max_element() + lo.abs().max(hi.abs()).max_element());
    x.cmplt(lo - DVec3::splat(m)).any() || x.cmpgt(hi + DVec3::splat(m)).any()
}

/// The cone of [`Cull::Cone`]: the planes' unit normals, their absolute values, and their
/// products with the point.
struct Cone {
    /// The planes' unit normals by coordinate, and their absolute values.
    px: [f64; 4],
    py: [f64; 4],
    pz: [f64; 4],
    ax: [f64; 4],
    ay: [f64; 4],
    az: [f64; 4],
    /// `p . x` for each plane `p`.
    at_x: [f64; 4],
    /// The rounding margin's part from the point (see [`Cone::classify`]).
    x_margin: f64,
}

/// Where a node's box lies against a [`Cone`].
enum ConeSide {
    Outside,
    Inside,
    Both,
}

impl Cone {
    fn new(planes: &[DVec3; 4], x: DVec3) -> Self {
        Cone {
            px: planes.map(|p| p.x),
            py: planes.map(|p| p.y),
            pz: planes.map(|p| p.z),
            ax: planes.map(|p| p.x.abs()),
            ay: planes.map(|p| p.y.abs()),
            az: planes.map(|p| p.z.abs()),
            at_x: planes.map(|p| p.dot(x)),
            x_margin: 2e-9 * x.abs().max_element(),
        }
    }

    /// The box of child `k` of node `n` against the cone through the point, beyond rounding
    /// (`1e-9` of the box's size and of its centre's and the point's coordinates, so at least
    /// `1e-9` of the box's offset from the point): outside where it lies on the negative side
    /// of a plane, inside where it lies on the positive side of all four. The four planes are
    /// tested side by side (vector lanes), without an early exit.
    #[inline]
    fn classify(&self, n: &WideNode, k: usize) -> ConeSide {
        let (cx, cy, cz) = (n.cx[k], n.cy[k], n.cz[k]);
        let h = n.half[k];
        let m = n.margin[k] + self.x_margin;
        let (mut mid, mut r) = ([0.0f64; 4], [0.0f64; 4]);
        for j in 0..4 {
            // `p . (c - x)`, with `p . x` computed once per query: its rounding is a few ulps
            // of `|c| + |x|`, far below the margin.
            mid[j] = self.px[j] * cx + self.py[j] * cy + self.pz[j] * cz - self.at_x[j];
            r[j] = self.ax[j] * h.x + self.ay[j] * h.y + self.az[j] * h.z;
        }
        let (mut outside, mut inside) = (false, true);
        for j in 0..4 {
            outside |= mid[j] + r[j] < -m;
            inside &= mid[j] - r[j] > m;
        }
        if outside {
            ConeSide::Outside
        } else if inside {
            ConeSide::Inside
        } else {
            ConeSide::Both
        }
    }
}

impl MeshContours {
    /// Whether the mesh is one component with a facing hierarchy: the case where
    /// [`Cull::Cone`] leaves edges out (a contour of open chains).
    pub(crate) fn single_tree(&self) -> bool {
        self.comps.len() == 1 && self.comps[0].root != NO_TREE
    }
}

/// One contour query's view of the mesh.
struct Walk<'a> {
    at: FacingAt,
    normals: &'a [DVec3],
    offsets: &'a [f64],
    edges: &'a [[u32; 4]],
    nodes: &'a [WideNode],
    x: DVec3,
    cone: Option<Cone>,
}

impl Walk<'_> {
    #[inline(always)]
    fn front(&self, f: u32) -> bool {
        self.at
            .front(self.normals[f as usize], self.offsets[f as usize])
    }

    #[inline(always)]
    fn edges(&self, range: core::ops::Range<usize>, out: &mut Vec<(u32, u32)>) {
        // A leaf's edges come in runs of one first face (`share_first_faces`): its facing is
        // decided once per run.
        let (mut last, mut s_last) = (u32::MAX, false);
        for &[a, b, f0, f1] in &self.edges[range] {
            if f0 != last {
                (last, s_last) = (f0, self.front(f0));
            }
            let (s0, s1) = (s_last, self.front(f1));
            if s0 != s1 {
                out.push(if s0 { (a, b) } else { (b, a) });
            }
        }
    }

    /// Appends the contour edges of component `c`; `false` where its hierarchy is deeper than
    /// the walk's stack (never for a hierarchy of median splits over fewer than `2^40` edges).
    fn component(&self, c: &Component, out: &mut Vec<(u32, u32)>) -> bool {
        if c.root == NO_TREE {
            self.edges(c.start as usize..c.end as usize, out);
            return true;
        }
        let tol = self.at.tol();
        // Nodes to visit, with whether their boxes lie inside the cone (no more cone tests
        // below them). A node pushes at most three more than it takes, and the median splits
        // keep the hierarchy balanced: two levels per node, so a stack of 64 holds every
        // component of fewer than `2^40` edges; deeper ones decline.
        let mut stack = [(0u32, false); 64];
        stack[0] = (c.root, self.cone.is_none());
        let mut top = 1usize;
        while top > 0 {
            top -= 1;
            let (i, inside) = stack[top];
            let n = &self.nodes[i as usize];
            let mut mixed = n.mixed(self.x, tol);
            while mixed != 0 {
                let k = mixed.trailing_zeros() as usize;
                mixed &= mixed - 1;
                if n.count[k] > 0 {
                    let start = n.child[k] as usize;
                    self.edges(start..start + n.count[k] as usize, out);
                    continue;
                }
                // The cone is tested at inner nodes only: at a leaf the test would cost about
                // what its edges' facing tests cost.
                let mut child_inside = inside;
                if !inside && let Some(cone) = &self.cone {
                    match cone.classify(n, k) {
                        ConeSide::Outside => continue,
                        ConeSide::Inside => child_inside = true,
                        ConeSide::Both => {}
                    }
                }
                if top == stack.len() {
                    return false;
                }
                stack[top] = (n.child[k], child_inside);
                top += 1;
            }
        }
        true
    }
}

/// Builds the facing hierarchy over `edges` (a component's, starting at index `offset` of the
/// mesh's edge list), reordering them into leaf order, appending its nodes (depth first: a
/// node's first child is the next node).
fn build_tree(
    mesh: &TriangleMesh,
    edges: &mut [[u32; 4]],
    offset: u32,
    nodes: &mut Vec<FacingNode>,
) {
    let verts = mesh.vertices();
    let normals = mesh.normals();
    let mid = |e: &[u32; 4]| 0.5 * (verts[e[0] as usize] + verts[e[1] as usize]);
    // The mean normal of an edge's two faces: splitting on it keeps the normal cones of the
    // children narrow, which is what classifies a node from a point far away (the spread term
    // of `FacingNode`), where a split on position alone keeps whole cross-sections of a tube
    // (every normal direction) in one node down to small nodes.
    let nrm = |e: &[u32; 4]| normals[e[2] as usize] + normals[e[3] as usize];
    // Depth first (first child first); `open` holds the inner nodes whose subtrees are not
    // complete yet, with the number of their children still to be finished.
    let mut stack: Vec<(usize, usize)> = vec![(0, edges.len())];
    // The component's size (the root's), the scale of the normals' axes.
    let mut root_size = 0.0;
    let mut open: Vec<(usize, u8)> = Vec::new();
    while let Some((first, end)) = stack.pop() {
        let node = nodes.len();
        let range = &mut edges[first..end];
        let leaf = range.len() <= LEAF_EDGES;
        if leaf {
            share_first_faces(range);
        }
        nodes.push(facing_bounds(
            mesh,
            range,
            if leaf { offset + first as u32 } else { 0 },
            leaf,
        ));
        if leaf {
            // Subtrees completed by this leaf: their ends are the next node.
            while let Some(top) = open.last_mut() {
                top.1 -= 1;
                if top.1 > 0 {
                    break;
                }
                let p = top.0;
                open.pop();
                nodes[p].start = nodes.len() as u32;
            }
            continue;
        }
        open.push((node, 2));
        // Median split along the longest of six axes: the edges' midpoints, and their mean
        // normals (components in [-1, 1]) scaled by the component's size and `NORMAL_WEIGHT`.
        let (lo, hi, nlo, nhi) = range.iter().fold(
            (
                DVec3::splat(f64::INFINITY),
                DVec3::splat(f64::NEG_INFINITY),
                DVec3::splat(f64::INFINITY),
                DVec3::splat(f64::NEG_INFINITY),
            ),
            |(lo, hi, nlo, nhi), e| {
                let (p, n) = (mid(e), 0.5 * nrm(e));
                (lo.min(p), hi.max(p), nlo.min(n), nhi.max(n))
            },
        );
        let ext = hi - lo;
        if root_size == 0.0 {
            root_size = ext.length();
        }
        let next = nhi - nlo;
        let by_normal = next.max_element() * NORMAL_WEIGHT * root_size > ext.max_element();
        let e = if by_normal { next } else { ext };
        let axis = if e.x >= e.y && e.x >= e.z {
            0
        } else if e.y >= e.z {
            1
        } else {
            2
        };
        let m = range.len() / 2;
        if by_normal {
            range.select_nth_unstable_by(m, |a, b| nrm(a)[axis].total_cmp(&nrm(b)[axis]));
        } else {
            range.select_nth_unstable_by(m, |a, b| mid(a)[axis].total_cmp(&mid(b)[axis]));
        }
        stack.push((first + m, end));
        stack.push((first, first + m));
    }
}

/// The [`WideNode`]s of the binary facing hierarchy `bin` (as [`build_tree`] lays it out) below
/// its node `i`, appended to `wide`; returns the index of the first. A node's children are its
/// binary node's grandchildren, or its children where those are leaves.
fn widen(bin: &[FacingNode], i: usize, wide: &mut Vec<WideNode>) -> u32 {
    let me = wide.len();
    wide.push(WideNode::empty());
    // A leaf root (never built: components of fewer than `TREE_MIN_EDGES` edges have no
    // hierarchy) is the node's one child.
    let kids = |i: usize| -> [usize; 2] {
        let a = i + 1;
        let b = if bin[a].count > 0 {
            a + 1
        } else {
            bin[a].start as usize
        };
        [a, b]
    };
    let mut slots: SmallVec<[usize; WIDE]> = SmallVec::new();
    if bin[i].count > 0 {
        slots.push(i);
    } else {
        for c in kids(i) {
            if bin[c].count > 0 {
                slots.push(c);
            } else {
                slots.extend(kids(c));
            }
        }
    }
    for (k, &b) in slots.iter().enumerate() {
        let n = &bin[b];
        let child = if n.count > 0 {
            n.start
        } else {
            widen(bin, b, wide)
        };
        wide[me].set(k, n, child);
    }
    me as u32
}

/// Orients and orders a leaf's edges so that edges sharing a face come in runs with it as their
/// first face: an edge `[a, b, f0, f1]` is the same edge as `[b, a, f1, f0]` (each face runs it
/// one way), so each edge takes as its first face the one of its two faces that more of the
/// leaf's edges hold, and the edges are sorted by it; the walk then decides that face once per
/// run.
fn share_first_faces(edges: &mut [[u32; 4]]) {
    let count =
        |f: u32, edges: &[[u32; 4]]| edges.iter().filter(|e| e[2] == f || e[3] == f).count();
    let counts: SmallVec<[(usize, usize); LEAF_EDGES]> = edges
        .iter()
        .map(|e| (count(e[2], edges), count(e[3], edges)))
        .collect();
    for (e, &(c0, c1)) in edges.iter_mut().zip(&counts) {
        if c1 > c0 || (c1 == c0 && e[3] < e[2]) {
            *e = [e[1], e[0], e[3], e[2]];
        }
    }
    edges.sort_unstable_by_key(|e| (e[2], e[3]));
}

/// The facing bounds of the faces of `edges` (see [`FacingNode`]).
fn facing_bounds(mesh: &TriangleMesh, edges: &[[u32; 4]], start: u32, leaf: bool) -> FacingNode {
    let verts = mesh.vertices();
    let tris = mesh.triangles();
    let normals = mesh.normals();
    let faces = || edges.iter().flat_map(|e| [e[2], e[3]]);
    let (lo, hi) = faces().fold(
        (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)),
        |(lo, hi), f| {
            let [a, b, c] = tris[f as usize].map(|i| verts[i as usize]);
            (lo.min(a).min(b).min(c), hi.max(a).max(b).max(c))
        },
    );
    let center = 0.5 * (lo + hi);
    // The axis: any vector is valid (the bound `|n_f - axis| <= spread` is what the query
    // uses, measured below from the normals themselves); the smaller the spread, the more
    // points classify the node as all front or none.
    let axis = cone_axis(faces().map(|f| normals[f as usize]));
    let mut spread: f64 = 0.0;
    let (mut q_lo, mut q_hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for f in faces() {
        let n = normals[f as usize];
        spread = spread.max((n - axis).length());
        let p = verts[tris[f as usize][0] as usize];
        let q = n.dot(center - p);
        q_lo = q_lo.min(q);
        q_hi = q_hi.max(q);
    }
    // Widened beyond the rounding of these sums and products (relative to their magnitudes).
    let scale = (hi - lo).length() + center.abs().max_element();
    let pad = 1e-9 * scale;
    FacingNode {
        center,
        half: 0.5 * (hi - lo),
        half_max: (0.5 * (hi - lo)).max_element(),
        axis,
        spread: spread * (1.0 + 1e-9) + 1e-12,
        q_lo: q_lo - pad,
        q_hi: q_hi + pad,
        start,
        count: if leaf { edges.len() as u32 } else { 0 },
    }
}

/// Iterations of [`cone_axis`]'s search for the centre of the normals' smallest ball.
const AXIS_STEPS: usize = 16;

/// Nodes of more face slots than this keep the normalized sum as their axis ([`cone_axis`]).
const AXIS_MAX_FACES: usize = 256;

/// An axis for the normal cone of `normals` (unit vectors): close to the centre of their
/// smallest enclosing ball (Badoiu and Clarkson, *Smaller core-sets for balls*, SODA 2003:
/// step towards the farthest point by `1 / (k + 1)`), started at the normalized sum of the
/// normals and kept only where it lowers the largest distance `|n - axis|`, the node's spread.
/// The ball's centre, and not its projection on the unit sphere, is what minimizes that
/// distance; the bound of [`FacingNode`] holds for any axis, unit or not.
fn cone_axis(normals: impl Iterator<Item = DVec3> + Clone) -> DVec3 {
    let spread_of = |axis: DVec3| {
        normals
            .clone()
            .fold(0.0f64, |m, n| m.max((n - axis).length_squared()))
    };
    let sum: DVec3 = normals.clone().sum();
    let mut best = sum.try_normalize().unwrap_or(DVec3::Z);
    let mut best_spread = spread_of(best);
    let mut c = best;
    // Large nodes (near the root) hold wide cones that a better axis rarely makes decisive,
    // and cost the most steps: their axis stays the normalized sum.
    let steps = if normals.clone().count() > AXIS_MAX_FACES {
        0
    } else {
        AXIS_STEPS
    };
    for k in 1..=steps {
        let (far, d) = normals.clone().fold((c, 0.0f64), |(p, m), n| {
            let d = (n - c).length_squared();
            if d > m { (n, d) } else { (p, m) }
        });
        if d < best_spread {
            best = c;
            best_spread = d;
        }
        c += (far - c) / (k as f64 + 1.0);
    }
    if !best.is_finite() {
        return DVec3::Z;
    }
    best
}

/// The contour edges in `edges` (from [`MeshContours::contour`]) chained into closed rings of
/// vertex indices, each passed to `emit`; `dir(v)` is vertex `v`'s direction from the point
/// (any positive length), used where the contour passes through a vertex more than once.
///
/// The edges balance at every vertex (as many in as out: a sum of closed triangle boundaries),
/// so walks close. Where several contour edges leave one vertex, each edge arriving there is
/// paired with a leaving one so that the rings touch there without crossing (in the angular
/// order of the edges about the vertex's direction: a non-crossing matching, as parentheses),
/// which keeps the rings' crossings those of their edges' interiors for the overlay; the chain,
/// and so its winding numbers, is the same whatever the pairing. `false` where the pairing
/// cannot be decided within rounding or the walk does not close.
///
/// With `open` (a contour of [`Cull::Cone`], some of its edges left out), a chain may also end
/// where no edge leaves its last vertex: such chains are passed to `emit` first, with their
/// last vertex and `true`; closed rings get `false`. A vertex where the kept edges do not
/// balance and more than one edge arrives or leaves declines (`false`).
pub(crate) fn chain_rings(
    edges: &[(u32, u32)],
    nverts: usize,
    dir: impl Fn(u32) -> DVec3,
    open: bool,
    s: &mut ChainScratch,
    emit: impl FnMut(&[u32], bool),
) -> bool {
    let n = edges.len();
    s.paired = false;
    if n == 0 {
        return true;
    }
    if n >= (u32::MAX / 4) as usize {
        return false;
    }
    let work = &mut s.work;
    work.clear();
    let linked = if nverts > 0 && nverts <= DENSE_CHAIN_VERTICES {
        // The mesh's vertex count is known and small: the first edge leaving each vertex in a
        // dense array (`s.first`, all `u32::MAX` between calls), no hashing.
        work.resize(2 * n, u32::MAX);
        if s.first.len() < nverts {
            s.first.resize(nverts, u32::MAX);
        }
        let first = &mut s.first[..nverts];
        let ok = successors_dense(edges, &dir, open, work, first, &mut s.paired);
        // Only the entries of the edges' first vertices were written.
        for &(a, _) in edges {
            if let Some(f) = first.get_mut(a as usize) {
                *f = u32::MAX;
            }
        }
        ok
    } else {
        successors_hashed(edges, &dir, open, work, &mut s.paired)
    };
    if !linked {
        return false;
    }
    walk_chains(edges, open, &mut s.work, &mut s.ring, emit)
}

/// Meshes of at most this many vertices chain their contours through a dense array of one
/// `u32` per vertex (256 KB at most, kept per thread), larger ones through a hash table.
const DENSE_CHAIN_VERTICES: usize = 1 << 16;

/// [`chain_rings`]' successors through a dense per-vertex array: `work` holds `next` then
/// `link` per edge (all `u32::MAX`); `first` (all `u32::MAX`) is written at the edges' first
/// vertices only. The same `next` as [`successors_hashed`]; `false` (declined) where a vertex
/// index is not below `first.len()`.
fn successors_dense(
    edges: &[(u32, u32)],
    dir: &impl Fn(u32) -> DVec3,
    open: bool,
    work: &mut [u32],
    first: &mut [u32],
    paired: &mut bool,
) -> bool {
    let n = edges.len();
    let (next, link) = work.split_at_mut(n);
    let mut several = false;
    for (k, &(a, _)) in edges.iter().enumerate() {
        let Some(head) = first.get_mut(a as usize) else {
            return false;
        };
        if *head != u32::MAX {
            link[k] = *head;
            several = true;
        }
        *head = k as u32;
    }
    let first_out = |v: u32| first.get(v as usize).copied().unwrap_or(u32::MAX);
    if !single_successors(edges, open, next, link, first_out) {
        return false;
    }
    if !several {
        return true;
    }
    // Vertices left by several edges (each once: at the edge at the head of its list).
    for k in 0..n {
        let v = edges[k].0;
        let head = first[v as usize];
        if head != k as u32 || link[k] == u32::MAX {
            continue;
        }
        *paired = true;
        if !pair_list(edges, v, head, link, dir, next) {
            return false;
        }
    }
    true
}

/// [`chain_rings`]' successors through an open-addressed hash table: `work` becomes `next`
/// and `link` per edge, then the table.
fn successors_hashed(
    edges: &[(u32, u32)],
    dir: &impl Fn(u32) -> DVec3,
    open: bool,
    work: &mut Vec<u32>,
    paired: &mut bool,
) -> bool {
    let n = edges.len();
    // The edges leaving each vertex as a linked list (`link`) from the vertex's slot in an
    // open-addressed table (`[vertex, first edge]`, at most half full): linear in the edges,
    // where a sort of them is `n log n`.
    let bits = (2 * n).next_power_of_two().trailing_zeros().max(1);
    let mask = (1usize << bits) - 1;
    let slot_of = |v: u32| (v.wrapping_mul(0x9E37_79B9) >> (32 - bits)) as usize;
    // One buffer: `next` and `link` per edge, then the table's slots as pairs.
    work.resize(2 * n + 2 * (mask + 1), u32::MAX);
    let (next, rest) = work.split_at_mut(n);
    let (link, table) = rest.split_at_mut(n);
    // Whether some vertex is left by several edges (only then is the table scanned for them).
    let mut several = false;
    for (k, &(a, _)) in edges.iter().enumerate() {
        if a == u32::MAX {
            return false;
        }
        let mut h = slot_of(a);
        loop {
            if table[2 * h] == u32::MAX {
                table[2 * h] = a;
                table[2 * h + 1] = k as u32;
                break;
            }
            if table[2 * h] == a {
                link[k] = table[2 * h + 1];
                table[2 * h + 1] = k as u32;
                several = true;
                break;
            }
            h = (h + 1) & mask;
        }
    }
    let first_out = |v: u32| {
        let mut h = slot_of(v);
        loop {
            if table[2 * h] == v {
                return table[2 * h + 1];
            }
            if table[2 * h] == u32::MAX {
                return u32::MAX;
            }
            h = (h + 1) & mask;
        }
    };
    if !single_successors(edges, open, next, link, first_out) {
        return false;
    }
    // Vertices left by several edges, paired by angle: the table is scanned only if there are
    // any.
    let scan = if several { mask + 1 } else { 0 };
    for t in 0..scan {
        let (v, head) = (table[2 * t], table[2 * t + 1]);
        if v == u32::MAX || link[head as usize] == u32::MAX {
            continue;
        }
        *paired = true;
        if !pair_list(edges, v, head, link, dir, next) {
            return false;
        }
    }
    true
}

/// The successor of every edge whose end vertex is left by one edge (`first_out(v)`: the head
/// of `v`'s list of leaving edges, `u32::MAX` for none; `link` chains the lists): `false` where
/// a closed contour's edge leads nowhere.
#[inline(always)]
fn single_successors(
    edges: &[(u32, u32)],
    open: bool,
    next: &mut [u32],
    link: &[u32],
    first_out: impl Fn(u32) -> u32,
) -> bool {
    for (k, &(_, b)) in edges.iter().enumerate() {
        let head = first_out(b);
        if head == u32::MAX {
            if open {
                continue;
            }
            return false;
        }
        if link[head as usize] == u32::MAX {
            next[k] = head;
        }
    }
    true
}

/// [`pair_at`] over the edges leaving `v`: the list from `head` through `link`.
fn pair_list(
    edges: &[(u32, u32)],
    v: u32,
    head: u32,
    link: &[u32],
    dir: &impl Fn(u32) -> DVec3,
    next: &mut [u32],
) -> bool {
    let mut outs: SmallVec<[usize; 4]> = SmallVec::new();
    let mut k = head;
    while k != u32::MAX {
        outs.push(k as usize);
        k = link[k as usize];
    }
    pair_at(edges, v, &outs, dir, next)
}

/// [`chain_rings`]' walk over the successors `work[..n]` (`work[n..2n]` reused as marks):
/// open chains from their first edges (those that no edge leads to), then the rings.
fn walk_chains(
    edges: &[(u32, u32)],
    open: bool,
    work: &mut [u32],
    ring: &mut Vec<u32>,
    mut emit: impl FnMut(&[u32], bool),
) -> bool {
    let n = edges.len();
    let (next, rest) = work.split_at_mut(n);
    let link = &mut rest[..n];
    let mut used = 0usize;
    if open {
        link.fill(0);
        for &k in next.iter() {
            if k != u32::MAX {
                link[k as usize] = 1;
            }
        }
        // `link` now marks the edges with a predecessor: chains start at the others.
        for (start, &has_pred) in link.iter().enumerate() {
            if has_pred == 1 {
                continue;
            }
            ring.clear();
            let mut k = start;
            loop {
                let nk = next[k];
                if nk == u32::MAX - 1 {
                    return false;
                }
                ring.push(edges[k].0);
                next[k] = u32::MAX - 1;
                used += 1;
                if nk == u32::MAX {
                    ring.push(edges[k].1);
                    break;
                }
                k = nk as usize;
            }
            emit(ring, true);
        }
    }
    for start in 0..n {
        if next[start] == u32::MAX - 1 {
            continue;
        }
        ring.clear();
        let mut k = start;
        loop {
            let nk = next[k];
            if nk >= u32::MAX - 1 {
                return false;
            }
            ring.push(edges[k].0);
            next[k] = u32::MAX - 1;
            used += 1;
            k = nk as usize;
            if k == start {
                break;
            }
        }
        emit(ring, false);
    }
    used == n
}

/// Scratch storage of [`chain_rings`] (reused across calls).
#[derive(Debug, Clone, Default)]
pub(crate) struct ChainScratch {
    work: Vec<u32>,
    ring: Vec<u32>,
    /// Per mesh vertex, the first contour edge leaving it (all `u32::MAX` between calls).
    first: Vec<u32>,
    /// Whether the last [`chain_rings`] paired edges at a vertex left by several: only then
    /// can its rings pass one vertex twice.
    pub(crate) paired: bool,
}

impl ChainScratch {
    /// Storage for about `n` contour edges.
    pub(crate) fn with_capacity(n: usize) -> Self {
        ChainScratch {
            work: Vec::with_capacity(6 * n),
            ring: Vec::with_capacity(n),
            first: Vec::new(),
            paired: false,
        }
    }
}

/// Pairs the edges arriving at vertex `v` with the edges `outs` leaving it (see
/// [`chain_rings`]), writing `next[arriving] = leaving`.
fn pair_at(
    edges: &[(u32, u32)],
    v: u32,
    outs: &[usize],
    dir: &impl Fn(u32) -> DVec3,
    next: &mut [u32],
) -> bool {
    // (edge index, other end's direction, +1 leaving / -1 arriving).
    let mut around: SmallVec<[(usize, DVec3, i32); 8]> = SmallVec::new();
    for &k in outs {
        around.push((k, dir(edges[k].1), 1));
    }
    for (k, e) in edges.iter().enumerate() {
        if e.1 == v {
            around.push((k, dir(e.0), -1));
        }
    }
    if around.len() != 2 * outs.len() || around.len() > 8 {
        return false;
    }
    let p = dir(v);
    let r = around[0].1;
    let bound = |a: DVec3, b: DVec3| 64.0 * f64::EPSILON * norm1(p) * norm1(a) * norm1(b);
    // Angle about `p` (counter-clockwise seen from outside the sphere) from the first edge's
    // tangent: half 0 for [0, pi), 1 for [pi, 2 pi).
    let mut half: SmallVec<[u8; 8]> = SmallVec::new();
    for &(_, w, _) in &around {
        let s = p.cross(r).dot(w);
        if w == r {
            half.push(0);
            continue;
        }
        if s.abs() <= bound(r, w) {
            // Along the first tangent's great circle: the same direction (angle 0) or opposite.
            let t_r = r - p * (p.dot(r) / p.length_squared());
            let t_w = w - p * (p.dot(w) / p.length_squared());
            if t_r.dot(t_w) > 0.0 {
                return false;
            }
            half.push(1);
            continue;
        }
        half.push(u8::from(s < 0.0));
    }
    let mut order: SmallVec<[usize; 8]> = (0..around.len()).collect();
    let mut ok = true;
    // Insertion sort by (half, angle within the half).
    for i in 1..order.len() {
        let mut k = i;
        while k > 0 {
            let (a, b) = (order[k - 1], order[k]);
            let before = if half[a] != half[b] {
                half[b] < half[a]
            } else {
                let s = p.cross(around[b].1).dot(around[a].1);
                if s.abs() <= bound(around[a].1, around[b].1) {
                    ok = false;
                }
                // b before a where a lies counter-clockwise of b.
                s > 0.0
            };
            if !before {
                break;
            }
            order.swap(k - 1, k);
            k -= 1;
        }
    }
    if !ok {
        return false;
    }
    // Parenthesis matching from the lowest prefix sum.
    let m = order.len();
    let (mut sum, mut low, mut at) = (0i32, 0i32, 0usize);
    for (i, &o) in order.iter().enumerate() {
        sum += around[o].2;
        if sum < low {
            low = sum;
            at = i + 1;
        }
    }
    let mut open: SmallVec<[usize; 8]> = SmallVec::new();
    for i in 0..m {
        let o = order[(at + i) % m];
        let (k, _, s) = around[o];
        if s > 0 {
            open.push(k);
        } else {
            let Some(leave) = open.pop() else {
                return false;
            };
            if next[k] != u32::MAX {
                return false;
            }
            next[k] = leave as u32;
        }
    }
    open.is_empty()
}

/// `|v|_1`.
#[inline]
fn norm1(v: DVec3) -> f64 {
    v.x.abs() + v.y.abs() + v.z.abs()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The largest `|n - axis|` over `normals`.
    fn spread(normals: &[DVec3], axis: DVec3) -> f64 {
        normals.iter().fold(0.0, |m, &n| m.max((n - axis).length()))
    }

    /// The contour [`MeshContours::contour`] finds for a small mesh seen whole ([`Cull::All`]:
    /// one pass over the faces and edges) is the hierarchy walk's, edge for edge (the wide walk
    /// takes them in another order): for a torus light of 480 triangles and for two tori as one mesh (two
    /// components), from points around them, close to them and in the plane of some faces.
    #[test]
    fn flat_contour_of_a_small_mesh_is_the_walks() {
        let one = crate::solid::fixtures::torus(0.6, 0.15, 24, 10).unwrap();
        let (v, t) = (one.vertices(), one.triangles());
        let shift = DVec3::new(1.7, 0.3, 0.2);
        let mut verts = v.to_vec();
        verts.extend(v.iter().map(|&p| p + shift));
        let n = v.len() as u32;
        let mut tris = t.to_vec();
        tris.extend(t.iter().map(|tri| tri.map(|i| i + n)));
        let two = TriangleMesh::new(verts, tris).unwrap();
        let mut unit = crate::math::test_unit_stream(0x9e37_79b9_7f4a_7c15);
        for mesh in [&one, &two] {
            assert!(mesh.triangles().len() <= FLAT_MAX_FACES);
            let closed = Closed::new(mesh);
            let mc = MeshContours::new(mesh, &closed);
            assert!(mc.comps.iter().all(|c| c.root != NO_TREE));
            // Points on the face planes through a vertex, off the mesh's box.
            let mut points: Vec<DVec3> = mesh
                .triangles()
                .iter()
                .take(40)
                .map(|&[a, b, _]| {
                    let (a, b) = (mesh.vertices()[a as usize], mesh.vertices()[b as usize]);
                    a + (b - a) * 40.0
                })
                .collect();
            for _ in 0..200 {
                let d = DVec3::new(unit() - 0.5, unit() - 0.5, unit() - 0.5) * 2.0;
                let r = [0.8, 1.5, 3.0, 30.0][(unit() * 4.0) as usize % 4];
                points.push(d.normalize_or(DVec3::Z) * r + DVec3::new(0.5, 0.1, 0.0));
            }
            let mut found = 0;
            for x in points {
                let mut flat = Vec::new();
                let ok = mc.contour(mesh, x, Cull::All, &mut flat);
                let inside = mc.comps.iter().any(|c| !outside_box(c.lo, c.hi, x));
                assert_eq!(ok, !inside, "{x}");
                if !ok {
                    continue;
                }
                let walk = Walk {
                    at: FacingAt::new(mesh, x),
                    normals: mesh.normals(),
                    offsets: mesh.offsets(),
                    edges: &mc.edges,
                    nodes: &mc.nodes,
                    x,
                    cone: None,
                };
                let mut walked = Vec::new();
                for c in &mc.comps {
                    walk.component(c, &mut walked);
                }
                flat.sort_unstable();
                walked.sort_unstable();
                assert_eq!(flat, walked, "{x}");
                found += usize::from(!flat.is_empty());
            }
            assert!(found > 100, "{found}");
        }
    }

    /// Runs [`chain_rings`] and returns its answer, its rings and `paired` (where it chains);
    /// checks that the
    /// dense array is left all `u32::MAX`.
    fn chained(
        edges: &[(u32, u32)],
        nverts: usize,
        dirs: &[DVec3],
        open: bool,
        s: &mut ChainScratch,
    ) -> (bool, Vec<(Vec<u32>, bool)>, bool) {
        let mut rings = Vec::new();
        let dir = |i: u32| dirs.get(i as usize).copied().unwrap_or(DVec3::Z);
        let ok = chain_rings(edges, nverts, dir, open, s, |r, o| {
            rings.push((r.to_vec(), o));
        });
        assert!(s.first.iter().all(|&f| f == u32::MAX));
        (ok, rings, ok && s.paired)
    }

    #[test]
    fn dense_chaining_is_the_hashed_one() {
        let mut unit = crate::math::test_unit_stream(0x51_7cc1_b727_220a);
        let mesh = crate::solid::fixtures::torus(0.6, 0.15, 24, 10).unwrap();
        let closed = Closed::new(&mesh);
        let mc = MeshContours::new(&mesh, &closed);
        let nv = mesh.vertices().len();
        let (mut dense, mut hashed) = (ChainScratch::default(), ChainScratch::default());
        let (mut rings, mut several, mut opened) = (0, 0, 0);
        for case in 0..600 {
            let x = DVec3::new(unit() - 0.5, unit() - 0.5, unit() - 0.5).normalize_or(DVec3::Z)
                * [0.8, 1.5, 3.0][case % 3];
            let dirs: Vec<DVec3> = mesh.vertices().iter().map(|&p| p - x).collect();
            let mut edges = Vec::new();
            if case % 4 == 3 {
                // Bowties: triangles of vertex 0 and others (several edges leave vertex 0),
                // the rest of the vertices' indices up to `nv`.
                let k = 2 + (unit() * 3.0) as u32;
                for t in 0..k {
                    let (a, b) = (1 + 2 * t, 2 + 2 * t);
                    edges.extend([(0, a), (a, b), (b, 0)]);
                }
            } else if !mc.contour(&mesh, x, Cull::All, &mut edges) {
                continue;
            }
            // Some edges left out: open chains (or declines, alike in both).
            let open = case % 2 == 1 && edges.len() > 3;
            if open {
                let drop = (unit() * edges.len() as f64) as usize % edges.len();
                edges.remove(drop);
            }
            let a = chained(&edges, nv, &dirs, open, &mut dense);
            let b = chained(&edges, 0, &dirs, open, &mut hashed);
            assert_eq!(a, b, "case {case}");
            // An index past the mesh's vertices: the dense array declines (and is left clean).
            edges.push((nv as u32 + 5, 0));
            assert!(
                !chained(&edges, nv, &dirs, open, &mut dense).0,
                "case {case}"
            );
            rings += a.1.len();
            several += usize::from(a.0 && a.2);
            opened += a.1.iter().filter(|r| r.1).count();
        }
        assert!(
            rings > 400 && several > 50 && opened > 50,
            "{rings} {several} {opened}"
        );
    }

    #[test]
    fn cone_axis_narrows_lopsided_normal_sets() {
        // Many normals along +z and a few 60 degrees off along +x: the normalized sum leans
        // towards the crowd, the smallest cone's axis lies halfway (30 degrees), where the
        // spread is about 0.52 against 0.85.
        let tilt = DVec3::new(60f64.to_radians().sin(), 0.0, 60f64.to_radians().cos());
        let mut normals = vec![DVec3::Z; 40];
        normals.extend([tilt; 3]);
        let sum: DVec3 = normals.iter().sum();
        let old = spread(&normals, sum.normalize());
        let new = spread(&normals, cone_axis(normals.iter().copied()));
        assert!(new < 0.65 && new < 0.8 * old, "{new} {old}");
        // Never worse than the normalized sum, and finite on any set of unit normals.
        for normals in [
            vec![DVec3::Z],
            vec![DVec3::Z, -DVec3::Z],
            vec![
                DVec3::X,
                DVec3::Y,
                DVec3::Z,
                -DVec3::X,
                -DVec3::Y,
                -DVec3::Z,
            ],
            vec![DVec3::X, DVec3::Y, DVec3::new(0.6, 0.8, 0.0)],
        ] {
            let sum: DVec3 = normals.iter().sum();
            let axis = cone_axis(normals.iter().copied());
            assert!(axis.is_finite());
            let base = spread(&normals, sum.try_normalize().unwrap_or(DVec3::Z));
            assert!(spread(&normals, axis) <= base, "{normals:?}");
        }
    }

    /// The wide hierarchy's walk finds exactly the contour edges a test of every edge finds,
    /// oriented as their front face runs them, from points far from and close to the meshes
    /// (a few `1e-9` off a face plane, where the bounds must not decide wrongly), with and
    /// without the cone: with [`Cull::Cone`] it may leave out only edges outside the cone.
    #[test]
    fn wide_walk_finds_every_contour_edge() {
        use crate::solid::fixtures::{bumpy_sphere, torus};
        let meshes = [
            bumpy_sphere(3, 0.15, 17).unwrap(),
            bumpy_sphere(2, 0.3, 5).unwrap(),
            torus(1.0, 0.3, 40, 16).unwrap(),
        ];
        let mut rnd = crate::math::test_unit_stream(0xC0);
        let (mut found, mut near, mut culled, mut in_cone) = (0usize, 0usize, 0usize, 0usize);
        for mesh in &meshes {
            let closed = Closed::new(mesh);
            let mc = MeshContours::new(mesh, &closed);
            assert!(mc.single_tree());
            let r = mesh.bounding_sphere().radius;
            for k in 0..60 {
                let dir = DVec3::new(rnd() - 0.5, rnd() - 0.5, rnd() - 0.5).normalize_or(DVec3::Z);
                let x = if k % 3 == 0 {
                    // Just off a face plane, outside the mesh's box.
                    let f = (rnd() * mesh.triangle_count() as f64) as usize;
                    let [a, b, c] = mesh.triangle(f);
                    let n = mesh.triangle_normal(f);
                    let t = n.any_orthonormal_pair().0;
                    near += 1;
                    (a + b + c) / 3.0 + t * (3.0 * r) + n * ((rnd() - 0.5) * 4e-9)
                } else {
                    mesh.bounding_sphere().center + dir * r * (1.2 + 4.0 * rnd())
                };
                let at = FacingAt::new(mesh, x);
                let mut expect: Vec<(u32, u32)> = mesh
                    .edges()
                    .iter()
                    .filter_map(|e| {
                        let (s0, s1) = (
                            at.front(mesh.normals()[e.f0 as usize], mesh.offsets()[e.f0 as usize]),
                            at.front(mesh.normals()[e.f1 as usize], mesh.offsets()[e.f1 as usize]),
                        );
                        (s0 != s1).then_some(if s0 { (e.a, e.b) } else { (e.b, e.a) })
                    })
                    .collect();
                expect.sort_unstable();
                let mut got = Vec::new();
                if !mc.contour(mesh, x, Cull::All, &mut got) {
                    // Declined: the point is in the mesh's box.
                    continue;
                }
                got.sort_unstable();
                assert_eq!(got, expect, "point {x}");
                found += got.len();
                // A cone about a direction to the mesh's bounding sphere, half as wide as it.
                let aim = mesh.bounding_sphere().center + dir.any_orthonormal_pair().0 * (0.8 * r);
                let axis = (aim - x).normalize();
                let (u, v) = axis.any_orthonormal_pair();
                let w = 0.5 * r / (aim - x).length();
                let planes = [
                    (axis * w - u).normalize(),
                    (axis * w + u).normalize(),
                    (axis * w - v).normalize(),
                    (axis * w + v).normalize(),
                ];
                let inside = |p: DVec3| planes.iter().all(|n| n.dot(p - x) > 1e-9);
                let shaft = Shaft::from_cone(x, axis, &planes, axis, 1e3);
                let mut coned = Vec::new();
                assert!(mc.contour(mesh, x, Cull::Cone(&shaft, &planes), &mut coned));
                coned.sort_unstable();
                for e in &expect {
                    let verts = mesh.vertices();
                    let (a, b) = (verts[e.0 as usize], verts[e.1 as usize]);
                    if inside(a) || inside(b) {
                        assert!(
                            coned.binary_search(e).is_ok(),
                            "edge {e:?} in the cone left out"
                        );
                        in_cone += 1;
                    }
                }
                assert!(coned.iter().all(|e| expect.binary_search(e).is_ok()));
                culled += expect.len() - coned.len();
            }
        }
        assert!(
            found > 2000 && near > 40 && culled > 1000 && in_cone > 500,
            "{found} {near} {culled} {in_cone}"
        );
    }
}
