//! Trees per light and receiver tile (seed 002 Alg. 2): the scene's blocker triangles in a
//! bounding-volume hierarchy, shaft culling of them against a tile and a light polygon, and the
//! clipping that turns each remaining triangle into an occluder of the tree.
//!
//! A tile is a convex piece of one plane (the receiver's tangent plane, normal `n`) holding the
//! shading points that share the tree; a single shading point is the smallest tile. Three cuts
//! make the tree exact for every point `x` of the tile (see `mod.rs` for the rule):
//!
//! - the light face's plane: a blocker hides a face direction only by its part strictly on the
//!   point's side (`H_f`), cut with the facing predicate's snapped distances exactly as the
//!   clipping backend does;
//! - the tile plane: the part of a line behind `x` lies below the tangent plane, the part between
//!   `x` and the light above it, so keeping the blockers' parts above the plane makes "the line
//!   stabs a kept blocker" equivalent to "a blocker lies on the segment from `x` to the light";
//!   the edges this cut makes lie in the tile plane and are marked, so that the query decides
//!   their side by the plane itself, not by their rounded cut points (`query.rs`, "Edges on
//!   the tile plane");
//! - the shaft: the convex hull of the tile and the light polygon holds every such segment, so a
//!   triangle outside one of its supporting planes can hide nothing (seed 002 Alg. 2 line 7).
//!
//! Connected groups of whole triangles of one mesh (no cut touched them, far from the tile's
//! planes) become one convex patch occluder when every point of the tile sees them all from
//! the same side and their union convex ([`merge_patches`], with the proof): the edges inside
//! the patch bound no blocked set, so the tree needs only its boundary. Seed 002's occluders
//! are triangles; this is an extension.
//!
//! A blocker triangle whose plane passes through the point within the facing tolerance is seen
//! edge-on and hides nothing (as in the clipping backend). Triangles edge-on from every point of
//! the tile are dropped; those edge-on from some points, or whose plane passes within
//! [`NEAR_BAND`] of the tile, are listed as `near`, and a query from a point that sees one of
//! them edge-on, or lies that close to its plane, does not use the shared tree. A triangle
//! whose part above the tile plane lies within that band of it is left out of the shared tree
//! (rounding leaves such slivers of a receiver's neighbours, on which the tree's decisions are
//! not certified), and a point it may hide some of the light from (by a bound on its elevation
//! seen from the point, [`FlatPiece::may_hide`]) does not use the shared tree either.

use alloc::vec::Vec;

use glam::DVec3;
use smallvec::SmallVec;

use super::Blocker;
use super::bsp::{Crossing, MAX_OCCLUDER_VERTICES, Occluder, Tree, TreeBuffers};
use super::line::{Orienter, Sign};
use super::query::{clip_above, is_sliver, keep_positive, weld};
use crate::solid::TriangleMesh;
use crate::solid::facing::{Side, face_side, snapped_distance};

/// A triangle of a blocker (an occluder, or a light's geometry).
#[derive(Debug, Clone, Copy)]
pub(crate) struct BlockerTri {
    pub(crate) v: [DVec3; 3],
    pub(crate) owner: Blocker,
    pub(crate) tri: u32,
    /// The triangle of the same mesh across edge `v[i] -> v[i + 1]` (running it the other
    /// way), or [`MeshEdge::BORDER`](crate::solid::MeshEdge::BORDER): the candidates of
    /// [`merge_patches`].
    pub(crate) adj: [u32; 3],
}

/// Per triangle of `mesh`, the triangle across each of its edges ([`BlockerTri::adj`]).
pub(crate) fn mesh_adjacency(mesh: &TriangleMesh) -> Vec<[u32; 3]> {
    let tris = mesh.triangles();
    let mut adj = alloc::vec![[crate::solid::MeshEdge::BORDER; 3]; tris.len()];
    for e in mesh.edges() {
        let Some(f1) = e.twin() else { continue };
        for (f, other, (a, b)) in [(e.f0, f1, (e.a, e.b)), (f1, e.f0, (e.b, e.a))] {
            let t = tris[f as usize];
            if let Some(i) = (0..3).find(|&i| t[i] == a && t[(i + 1) % 3] == b) {
                adj[f as usize][i] = other;
            }
        }
    }
    adj
}

/// A plane bounding a shaft: points with `n . p > d` are outside.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Plane {
    n: DVec3,
    d: f64,
}

impl Plane {
    #[inline]
    fn outside(&self, p: DVec3) -> bool {
        self.n.dot(p) > self.d
    }

    /// Whether the box `[lo, hi]` lies entirely outside.
    #[inline]
    fn box_outside(&self, lo: DVec3, hi: DVec3) -> bool {
        let c = (lo + hi) * 0.5;
        let h = (hi - lo) * 0.5;
        self.n.dot(c) - self.n.abs().dot(h) > self.d
    }
}

#[derive(Debug, Clone, Copy)]
struct BvhNode {
    lo: DVec3,
    hi: DVec3,
    /// Leaf: first triangle; inner: index of the second child (the first follows the node).
    first: u32,
    /// Leaf: number of triangles (> 0); inner: 0.
    count: u32,
}

/// Triangles per leaf of the hierarchy.
const LEAF_SIZE: usize = 4;

/// A bounding-volume hierarchy over every blocker triangle of a scene (median splits along the
/// longest axis of the centroids), for the shaft culling.
#[derive(Debug, Clone)]
pub(crate) struct Bvh {
    nodes: Vec<BvhNode>,
    tris: Vec<BlockerTri>,
}

impl Bvh {
    pub(crate) fn new(mut tris: Vec<BlockerTri>) -> Bvh {
        let mut nodes = Vec::with_capacity(2 * tris.len() / LEAF_SIZE + 1);
        if !tris.is_empty() {
            let n = tris.len();
            build(&mut nodes, &mut tris, 0, n);
        }
        Bvh { nodes, tris }
    }

    /// The triangle at `i` (an index from [`Bvh::cull`]).
    pub(crate) fn tri(&self, i: u32) -> &BlockerTri {
        &self.tris[i as usize]
    }

    /// Appends to `out` the triangles not entirely outside some plane of `planes`.
    pub(crate) fn cull(&self, planes: &[Plane], out: &mut Vec<u32>) {
        if self.nodes.is_empty() {
            return;
        }
        let mut stack: SmallVec<[u32; 64]> = SmallVec::new();
        stack.push(0);
        while let Some(i) = stack.pop() {
            let node = self.nodes[i as usize];
            if planes.iter().any(|p| p.box_outside(node.lo, node.hi)) {
                continue;
            }
            if node.count == 0 {
                stack.push(node.first);
                stack.push(i + 1);
                continue;
            }
            for t in node.first..node.first + node.count {
                let v = self.tris[t as usize].v;
                if !planes.iter().any(|p| v.iter().all(|&q| p.outside(q))) {
                    out.push(t);
                }
            }
        }
    }
}

fn build(nodes: &mut Vec<BvhNode>, tris: &mut [BlockerTri], start: usize, end: usize) -> u32 {
    let slice = &tris[start..end];
    let (mut lo, mut hi) = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
    let (mut clo, mut chi) = (lo, hi);
    for t in slice {
        for &v in &t.v {
            lo = lo.min(v);
            hi = hi.max(v);
        }
        let c = centroid(t);
        clo = clo.min(c);
        chi = chi.max(c);
    }
    let me = nodes.len() as u32;
    nodes.push(BvhNode {
        lo,
        hi,
        first: start as u32,
        count: (end - start) as u32,
    });
    if end - start <= LEAF_SIZE {
        return me;
    }
    let ext = chi - clo;
    let axis = if ext.x >= ext.y && ext.x >= ext.z {
        0
    } else if ext.y >= ext.z {
        1
    } else {
        2
    };
    let mid = (end - start) / 2;
    tris[start..end]
        .select_nth_unstable_by(mid, |a, b| centroid(a)[axis].total_cmp(&centroid(b)[axis]));
    build(nodes, tris, start, start + mid);
    let right = build(nodes, tris, start + mid, end);
    nodes[me as usize].first = right;
    nodes[me as usize].count = 0;
    me
}

fn centroid(t: &BlockerTri) -> DVec3 {
    (t.v[0] + t.v[1] + t.v[2]) / 3.0
}

/// The planes of the convex hull of `cell` and `light` that pass through an edge of one and a
/// vertex of the other, or through three points of one, each kept only if it supports the
/// whole set, and moved outwards by a margin of `1e-9` of the set's size (so that rounding
/// never culls a triangle touching the hull). A triangle outside one of them meets no segment
/// from the cell to the light.
pub(crate) fn shaft_planes(cell: &[DVec3], light: &[DVec3], out: &mut Vec<Plane>) {
    out.clear();
    let all: SmallVec<[DVec3; 16]> = cell.iter().chain(light).copied().collect();
    if all.is_empty() {
        return;
    }
    let c = all.iter().copied().sum::<DVec3>() / all.len() as f64;
    let r = all.iter().map(|&p| (p - c).length()).fold(0.0, f64::max);
    let mut candidate = |p: DVec3, q: DVec3, s: DVec3| {
        let n = (q - p).cross(s - p);
        let len = n.length();
        if !(len > 0.0) || !len.is_finite() {
            return;
        }
        let tol = 1e-12 * len * r;
        let (mut above, mut below) = (false, false);
        for &a in &all {
            let d = n.dot(a - p);
            above |= d > tol;
            below |= d < -tol;
        }
        let margin = 1e-9 * len * r;
        if !above {
            out.push(Plane {
                n,
                d: n.dot(p) + margin,
            });
        } else if !below {
            out.push(Plane {
                n: -n,
                d: -n.dot(p) + margin,
            });
        }
    };
    for (i, &a) in light.iter().enumerate() {
        for &b in &light[i + 1..] {
            for &x in cell {
                candidate(a, b, x);
            }
        }
    }
    for (i, &a) in cell.iter().enumerate() {
        for &b in &cell[i + 1..] {
            for &l in light {
                candidate(a, b, l);
            }
        }
    }
    for pts in [light, cell] {
        if let Some((a, b, s)) = widest_triple(pts) {
            candidate(a, b, s);
        }
    }
}

/// Three of `pts` spanning the largest triangle among those with the first point (enough to
/// give the plane of a planar convex set), if any span one.
fn widest_triple(pts: &[DVec3]) -> Option<(DVec3, DVec3, DVec3)> {
    let a = *pts.first()?;
    let mut best = None;
    let mut area = 0.0;
    for (i, &b) in pts.iter().enumerate().skip(1) {
        for &s in &pts[i + 1..] {
            let w = (b - a).cross(s - a).length();
            if w > area {
                area = w;
                best = Some((a, b, s));
            }
        }
    }
    best
}

/// Which blockers a tree holds.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Owners {
    /// Everything but the light itself, whose own triangles count only when `own` (a
    /// non-planar mesh light can hide itself).
    All { light: usize, own: bool },
    /// The light's own triangles only (the unoccluded region of a self-hiding light).
    Own { light: usize },
}

impl Owners {
    fn keeps(self, b: Blocker) -> bool {
        match (self, b) {
            (Owners::All { light, own }, Blocker::Light(k)) if k == light => own,
            (Owners::All { .. }, _) => true,
            (Owners::Own { light }, Blocker::Light(k)) => k == light,
            (Owners::Own { .. }, _) => false,
        }
    }
}

/// The tile of a tree: points of the plane through `p0` with unit normal `n`, within the convex
/// polygon `cell` (one point for a single query), in world coordinates; `origin` is where the
/// tree's coordinates are centred.
#[derive(Debug, Clone)]
pub(crate) struct TileGeometry {
    pub(crate) origin: DVec3,
    pub(crate) p0: DVec3,
    pub(crate) n: DVec3,
    pub(crate) cell: SmallVec<[DVec3; 4]>,
}

/// Relative half-width of the band about a blocker's plane in which a point does not use its
/// tile's shared tree: `1e-5` of the tile's coordinate magnitude plus its size.
///
/// A shared tree is exact for points on its tile plane, in coordinates centred on the tile.
/// A point of the tile differs from that by the rounding of its world coordinates (about
/// `1e-16` of their magnitude `|x|`) and by the offset the tile accepts between its plane and
/// the point (`1e-14 (|x| + size)`, `PluckerContext`). Seen from a point at distance `d` from a
/// blocker, a blocker cut or placed that much off moves its shadow's edge by that over `d`
/// radians; outside the band (`d` above `1e-5 (|x| + size)`) that is below `1e-9`. Points in
/// the band get a tree of their own, centred on them, which has no such term.
pub(crate) const NEAR_BAND: f64 = 1e-5;

/// A blocker triangle whose plane passes through, or within [`NEAR_BAND`] of, a tile.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Near {
    pub(crate) owner: Blocker,
    pub(crate) tri: u32,
    /// The plane: unit normal and offset (`n . p = d` on it).
    n: DVec3,
    d: f64,
}

/// A tree with the blocker triangles whose planes pass through or close to its tile, and the
/// half-width of that band.
#[derive(Debug, Clone)]
pub(crate) struct GroupTree {
    pub(crate) tree: Tree,
    near: Vec<Near>,
    band: f64,
    /// Blocker triangles whose part above the tile plane lies within the band of it, left out
    /// of the tree (see [`build_group_tree`]); a point that such a triangle may hide some of
    /// the light from does not use the shared tree ([`FlatPiece::may_hide`]).
    flat: Vec<FlatPiece>,
}

/// A blocker triangle (world coordinates) whose part above a tile's plane lies at most
/// `height` above it.
#[derive(Debug, Clone, Copy)]
pub(crate) struct FlatPiece {
    tri: [DVec3; 3],
    height: f64,
}

impl FlatPiece {
    /// Whether the triangle may hide from `x` (a point of the tile, `n` the tile plane's unit
    /// normal) a direction towards a point of one of the convex polygons `light`.
    ///
    /// What `x` sees of the triangle is its part above `x`'s tangent plane, which lies at most
    /// `height` above it (`height` includes the offset a tile accepts between its plane and its
    /// points, and the rounding), and at least the triangle's distance `r` from `x`: its
    /// directions from `x` have a sine of elevation at most `height / r`. The directions of
    /// elevation at least a given one form a convex cone about `n`, so a convex light polygon
    /// whose vertices are all strictly above that elevation lies above it whole, and the
    /// triangle hides none of it.
    pub(crate) fn may_hide(&self, x: DVec3, n: DVec3, light: &[SmallVec<[DVec3; 8]>]) -> bool {
        let r = triangle_distance(x, self.tri) * (1.0 - 1e-9);
        if !(r > 0.0) {
            return true;
        }
        let sine = self.height / r * (1.0 + 1e-9);
        light.iter().flatten().any(|&e| {
            let w = e - x;
            !(n.dot(w) > sine * w.length() * (1.0 + 1e-9) + 1e-300)
        })
    }
}

/// The distance from `p` to the triangle `t` (closest point by regions, C. Ericson, *Real-Time
/// Collision Detection*, 2005, section 5.1.5).
fn triangle_distance(p: DVec3, t: [DVec3; 3]) -> f64 {
    let [a, b, c] = t;
    let (ab, ac, ap) = (b - a, c - a, p - a);
    let (d1, d2) = (ab.dot(ap), ac.dot(ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return ap.length();
    }
    let bp = p - b;
    let (d3, d4) = (ab.dot(bp), ac.dot(bp));
    if d3 >= 0.0 && d4 <= d3 {
        return bp.length();
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        let v = d1 / (d1 - d3);
        return (p - (a + ab * v)).length();
    }
    let cp = p - c;
    let (d5, d6) = (ab.dot(cp), ac.dot(cp));
    if d6 >= 0.0 && d5 <= d6 {
        return cp.length();
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        let w = d2 / (d2 - d6);
        return (p - (a + ac * w)).length();
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        let w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        return (p - (b + (c - b) * w)).length();
    }
    let denom = 1.0 / (va + vb + vc);
    let (v, w) = (vb * denom, vc * denom);
    (p - (a + ab * v + ac * w)).length()
}

impl GroupTree {
    /// Whether the point `x` must not use the shared tree: it sees a blocker of the tile edge-on
    /// (by the facing predicate, as the clipping backend), or lies within the band of one's
    /// plane, or a blocker left out of the tree as flat on the tile plane may hide some of the
    /// light polygons `light` (world coordinates) from it; `n` is the tile plane's normal.
    pub(crate) fn excludes<'m>(
        &self,
        x: DVec3,
        n: DVec3,
        light: &[SmallVec<[DVec3; 8]>],
        mesh_of: &dyn Fn(Blocker) -> &'m TriangleMesh,
    ) -> bool {
        self.flat.iter().any(|f| f.may_hide(x, n, light))
            || self.near.iter().any(|b| {
                (b.n.dot(x) - b.d).abs() <= self.band
                    || face_side(mesh_of(b.owner), b.tri as usize, x) == Side::On
            })
    }
}

/// What a tree is built from besides the tile: the light's faces that share one plane (the
/// group) and a representative face for that plane's side.
pub(crate) struct GroupSource<'a> {
    pub(crate) mesh: &'a TriangleMesh,
    pub(crate) faces: &'a [u32],
    pub(crate) rep: usize,
}

/// Builds the tree of one face group of a light for one tile (seed 002 Alg. 2 lines 7-8): the
/// group's triangles cut to the tile plane's upper side are the light polygon (its vertices are
/// the light's end of every vertex-to-vertex line); the blocker triangles that pass the shaft
/// culling, the owner filter and the edge-on test are cut to `H_f` and above the tile plane and
/// become the occluders, all in one undefined root leaf.
///
/// `None` when nothing of the group lies above the tile plane. The tree takes its allocations
/// from `bufs`.
#[allow(clippy::too_many_arguments)]
pub(crate) fn build_group_tree<'m>(
    bvh: &Bvh,
    mesh_of: &dyn Fn(Blocker) -> &'m TriangleMesh,
    group: &GroupSource<'_>,
    owners: Owners,
    tile: &TileGeometry,
    seed: u64,
    scratch: &mut Vec<u32>,
    mut bufs: TreeBuffers,
) -> Option<GroupTree> {
    let o = tile.origin;
    let p0 = tile.p0 - o;
    let mut light: SmallVec<[DVec3; 8]> = SmallVec::new();
    for &f in group.faces {
        let tri = group.mesh.triangle(f as usize).map(|v| v - o);
        if let Some(part) = clip_above(&tri, p0, tile.n) {
            for p in part {
                if !light.contains(&p) {
                    light.push(p);
                }
            }
        }
    }
    if light.len() < 3 {
        return None;
    }
    let cell_local: SmallVec<[DVec3; 4]> = tile.cell.iter().map(|&c| c - o).collect();
    let size = tile
        .cell
        .iter()
        .flat_map(|&a| tile.cell.iter().map(move |&b| (a - b).length()))
        .fold(0.0, f64::max);
    let magnitude = tile
        .cell
        .iter()
        .map(|c| c.abs().max_element())
        .fold(0.0, f64::max);
    let band = NEAR_BAND * (magnitude + size);
    let mut planes = Vec::new();
    shaft_planes(&cell_local, &light, &mut planes);
    for p in &mut planes {
        p.d += p.n.dot(o);
    }
    scratch.clear();
    bvh.cull(&planes, scratch);
    let mut occluders = core::mem::take(&mut bufs.occluders);
    occluders.clear();
    let mut near = Vec::new();
    let mut flat = Vec::new();
    let mut pairable = Vec::new();
    for &i in scratch.iter() {
        let bt = bvh.tri(i);
        if !owners.keeps(bt.owner) {
            continue;
        }
        // Cut 1: H_f, with the facing predicate's snapped distances (as the clipping backend).
        let df = bt.v.map(|v| snapped_distance(group.mesh, group.rep, v));
        if df.iter().all(|&d| d <= 0.0) {
            continue;
        }
        // Edge-on from the tile's points: everywhere (drop), somewhere (near), nowhere.
        let owner_mesh = mesh_of(bt.owner);
        let (mut front, mut behind, mut on) = (false, false, false);
        for &c in &tile.cell {
            match face_side(owner_mesh, bt.tri as usize, c) {
                Side::Front => front = true,
                Side::Behind => behind = true,
                Side::On => on = true,
            }
        }
        if !front && !behind {
            continue;
        }
        // The plane's distance is affine over the (convex) cell: its extremes are at corners.
        let tn = owner_mesh.triangle_normal(bt.tri as usize);
        let td = tn.dot(bt.v[0]);
        let (lo, hi) = tile
            .cell
            .iter()
            .map(|&c| tn.dot(c) - td)
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), v| {
                (l.min(v), h.max(v))
            });
        let near_somewhere = on || (front && behind) || (lo <= band && hi >= -band);
        let local = bt.v.map(|v| v - o);
        let vals: SmallVec<[(f64, Sign); 8]> = df.iter().map(|&d| (d, Sign::of(d))).collect();
        let Some(part) = keep_positive(&local, &vals) else {
            continue;
        };
        // Cut 2: above the tile plane.
        let Some(mut cut) = clip_above(&part, p0, tile.n) else {
            continue;
        };
        // Cut points a rounding away from a corner would make edges without a line; a sliver
        // left by the cuts covers no area.
        weld(&mut cut);
        if cut.len() > MAX_OCCLUDER_VERTICES || cut.len() < 3 || is_sliver(&cut) {
            continue;
        }
        let on_tile = tile_plane_edges(&part, &cut, p0, tile.n);
        let plane = Orienter::new(local[1], local[2], local[0]);
        let (mut pos, mut neg) = (false, false);
        for &e in &light {
            match plane.sign(e) {
                Sign::Positive => pos = true,
                Sign::Negative => neg = true,
                Sign::Zero => {}
            }
        }
        let crossing = match (pos, neg) {
            (true, false) => Crossing::Positive,
            (false, true) => Crossing::Negative,
            (true, true) => Crossing::Both,
            (false, false) => continue,
        };
        // A piece whose every point lies within the band above the tile plane is, in exact
        // arithmetic, often nothing: a neighbour of the receiver's own face, or a face through
        // one of its vertices, left above the plane by the rounding of the plane's offset
        // (taken from the tile's centre) and of the shared vertices. From a single point the
        // cut leaves a sliver or nothing and the per-call tree drops it; a shared tree that
        // keeps it makes decisions on lines grazing it that are not certified (from a point on
        // an icosphere's face, 0.13 from its edges, slivers 4e-15 above the plane hid 1.5e-6
        // sr of the light: `tests/visibility_plucker.rs`). A shared tree leaves it out, and
        // only the points it may hide some of the light from take a tree of their own
        // ([`FlatPiece::may_hide`]: from most points the light is far above such a piece).
        if tile.cell.len() > 1 {
            // The highest point of the blocker's part in `H_f` (a convex polygon, highest at a
            // vertex), before the weld of the cut moves any.
            let top = part
                .iter()
                .map(|&c| tile.n.dot(c - p0))
                .fold(f64::NEG_INFINITY, f64::max);
            if top <= band {
                // The offset a tile accepts between its plane and its points (1e-14 of the
                // magnitude plus the size, `PluckerContext`) and the rounding of the cut
                // points and of `p0`, with room to spare.
                let slack = 1e-12 * (magnitude + size);
                flat.push(FlatPiece {
                    tri: bt.v,
                    height: top.max(0.0) + slack,
                });
                if near_somewhere {
                    near.push(Near {
                        owner: bt.owner,
                        tri: bt.tri,
                        n: tn,
                        d: td,
                    });
                }
                continue;
            }
        }
        // Whole triangles (no cut touched them) far from the tile's planes may be merged
        // with neighbours of their mesh ([`merge_patches`]), whatever their crossing.
        if !near_somewhere && on_tile == 0 && cut.len() == 3 && cut[..] == local[..] {
            pairable.push(Pairable {
                key: (bt.owner, bt.tri),
                adj: bt.adj,
                occ: occluders.len() as u32,
            });
        }
        occluders.push(Occluder::new(&cut, crossing, on_tile));
        if near_somewhere {
            near.push(Near {
                owner: bt.owner,
                tri: bt.tri,
                n: tn,
                d: td,
            });
        }
    }
    merge_patches(&mut occluders, &mut pairable, &cell_local, tile.n, p0, band);
    bufs.occluders = occluders;
    Some(GroupTree {
        tree: Tree::with_buffers(&cell_local, &light, bufs, seed),
        near,
        band,
        flat,
    })
}

/// The edges of `cut` (the part of the convex polygon `part` above the plane through `p0` with
/// normal `n`, by [`clip_above`], welded) that lie on that plane, as a bit mask: those whose
/// two ends are not vertices of `part` strictly above the plane (by the same computed values
/// as `clip_above`), i.e. cut points or vertices on the plane. One plane cuts a convex
/// polygon along one edge, so these are the cut's edge (or an edge of `part` on the plane).
///
/// The cut points of that edge are rounded at the polygon's size, so the plane through a
/// point of the tile and the edge's computed line can be tilted by that rounding over the
/// point's distance from the line: `1e-6` rad for a point `1e-10` from a blocker of size 1.
/// In exact arithmetic the plane is the tile plane, and the query uses that instead.
fn tile_plane_edges(part: &[DVec3], cut: &[DVec3], p0: DVec3, n: DVec3) -> u8 {
    let on = |p: &DVec3| !part.iter().any(|q| q == p && n.dot(*q - p0) > 0.0);
    let k = cut.len();
    let mut mask = 0u8;
    for i in 0..k {
        if on(&cut[i]) && on(&cut[(i + 1) % k]) {
            mask |= 1 << i;
        }
    }
    mask
}

/// A whole blocker triangle kept as occluder `occ`, which [`merge_patches`] may merge with
/// neighbours across its edges (`adj`, triangles of the same mesh).
#[derive(Debug, Clone, Copy)]
struct Pairable {
    key: (Blocker, u32),
    adj: [u32; 3],
    occ: u32,
}

/// Relative margin of the determinants that certify a merged patch ([`merge_patches`]): far
/// above their rounding (a few `1e-16` of the product of the lengths), and above what the
/// points a tile accepts off its corners' hull (the cell widened by `1e-9` of its side, and
/// `1e-14` of the coordinates off the plane) can change, since merged triangles lie outside
/// the near band ([`NEAR_BAND`]) of every corner.
const PATCH_MARGIN: f64 = 1e-6;

/// Most vertices of a merged patch (a patch of `k` vertices holds `k - 2` triangles).
const MAX_PATCH_VERTICES: usize = MAX_OCCLUDER_VERTICES;

/// The sign of `det[p - x, q - x, r - x]` (seen from `x`, the turn `p -> q -> r`, or the
/// orientation of the triangle `p q r`) when it is strict with the margin [`PATCH_MARGIN`] of
/// the product of the three lengths, else `0.0`.
fn turn(x: DVec3, p: DVec3, q: DVec3, r: DVec3) -> f64 {
    let (rp, rq, rr) = (p - x, q - x, r - x);
    let det = rp.dot(rq.cross(rr));
    if det.abs() > PATCH_MARGIN * rp.length() * rq.length() * rr.length() {
        det.signum()
    } else {
        0.0
    }
}

/// Whether the turn `p -> q -> r` has the strict sign `sign` from every corner of `cell`.
fn turns_all(cell: &[DVec3], p: DVec3, q: DVec3, r: DVec3, sign: f64) -> bool {
    cell.iter().all(|&x| turn(x, p, q, r) == sign)
}

/// Merges connected groups of occluders that are whole triangles of one mesh into one convex
/// patch occluder each, where certified: it blocks, for every line from the tile (the convex
/// hull of `cell`), exactly what its triangles block, up to the lines through the patch's
/// interior edges (a set of measure zero). Greedy: from each triangle not yet in a patch, the
/// patch grows across its boundary edges by one neighbouring triangle at a time while the
/// certificate holds, up to [`MAX_PATCH_VERTICES`] vertices. The tree's cost grows with its
/// occluders and their edges: a patch of `k` triangles is one occluder of `k + 2` edges
/// instead of `k` of three, and its interior edges, which bound no blocked set, are no nodes
/// of the tree.
///
/// Proof. Fix a point `x` of the tile and write `o(p, q, r) = det[p - x, q - x, r - x]`.
/// Every vertex of a patch lies more than `floor` (the near band) above the tile plane (the
/// plane through `p0` with normal `up`), and `x` lies on it within far less, so the central
/// projection from `x` onto the plane `up . (p - x) = 1` maps the patch's vertices to finite
/// points, segments between them to segments, and `o(p, q, r)` has the sign of the planar
/// orientation of the images (it is that orientation times the three positive heights).
/// Invariant: the image of the patch's boundary ring is a convex polygon, oriented with sign
/// `s` (every turn `o(prev, v, next)` strictly `s`), tiled by the images of its triangles.
/// A single triangle with orientation `s` holds it. A triangle `b a c` added across the ring's
/// edge `a -> b` (it runs the edge the other way, as a mesh neighbour does) with orientation
/// `s` lies, in the image, on the other side of the line `a b` than the convex polygon (both
/// lie to the `s` side of their own direction of the edge), so the union is the two convex
/// pieces glued along `a b` with disjoint interiors, bounded by the ring with `c` inserted
/// between `a` and `b`: a simple polygon, convex since its turns at `a`, `c` (the triangle's
/// orientation) and `b` are required strictly `s` and the others are unchanged. A new vertex
/// already on the ring is refused (the patch stays a disk whose vertices all lie on its
/// boundary). Then the lines from `x` through the patch's convex image are exactly those with
/// one strict sign for all its edges, and that sign is each triangle's (same winding,
/// orientation and [`Crossing`]): the patch's invisible class (its chain over the ring's
/// edges, `bsp.rs`) is the union of its triangles' classes, plus interior edges. Each
/// determinant is affine in `x` (the terms with `x` twice vanish), so a strict sign at the
/// corners of the cell holds on the whole tile; it is required with a margin of
/// [`PATCH_MARGIN`] times the product of the lengths, for points a tile accepts a hair off
/// its corners' hull and for the rounding.
///
/// The rest of the tree uses an occluder's vertices only as bounds (Theorem 1 insertion, the
/// separating planes of the query's relevance test): the lines through the tile (or the light)
/// and the patch lie among those through the tile and the convex hull of its vertices, whose
/// sides with any line are bounded by the vertex-to-vertex lines (the side is affine in each
/// end), and seen from `x` the patch is convex, so a plane through `x` and one of its edges
/// has the other vertices on its inner side.
fn merge_patches(
    occluders: &mut Vec<Occluder>,
    pairable: &mut [Pairable],
    cell: &[DVec3],
    up: DVec3,
    p0: DVec3,
    floor: f64,
) {
    if pairable.len() < 2 || cell.is_empty() {
        return;
    }
    pairable.sort_unstable_by_key(|p| p.key);
    // Per occluder: in a patch already; dropped (merged into another).
    let mut taken = alloc::vec![false; occluders.len()];
    let mut gone = alloc::vec![false; occluders.len()];
    let mut merged = false;
    let high = |v: &DVec3| up.dot(*v - p0) > floor;
    for me in pairable.iter() {
        if taken[me.occ as usize] {
            continue;
        }
        let seed = &occluders[me.occ as usize];
        let Ok(tri) = <[DVec3; 3]>::try_from(seed.vertices()) else {
            continue;
        };
        if !tri.iter().all(high) {
            continue;
        }
        let sign = turn(cell[0], tri[0], tri[1], tri[2]);
        if sign == 0.0 || !turns_all(cell, tri[0], tri[1], tri[2], sign) {
            continue;
        }
        // Seen from the tile with orientation `sign`, a triangle above the tile plane is
        // crossed by the query lines with that sign: a light straddling its plane
        // ([`Crossing::Both`]) makes no difference (see the proof above).
        let effective = |c: Crossing| match c {
            Crossing::Both if sign > 0.0 => Crossing::Positive,
            Crossing::Both => Crossing::Negative,
            one => one,
        };
        let crossing = effective(seed.crossing());
        // The boundary ring: each vertex with the triangle across the edge to the next.
        let mut ring: SmallVec<[(DVec3, u32); MAX_PATCH_VERTICES]> =
            (0..3).map(|i| (tri[i], me.adj[i])).collect();
        let mut grown = false;
        // Try the ring's edges in turn until a whole round adds nothing.
        let (mut i, mut fails) = (0, 0);
        while ring.len() < MAX_PATCH_VERTICES && fails < ring.len() {
            let k = ring.len();
            let (a, across) = ring[i];
            let b = ring[(i + 1) % k].0;
            let next = ring[(i + 2) % k].0;
            let prev = ring[(i + k - 1) % k].0;
            let found = pairable
                .binary_search_by_key(&(me.key.0, across), |p| p.key)
                .ok()
                .map(|j| pairable[j])
                .filter(|o| !taken[o.occ as usize] && o.occ != me.occ)
                .and_then(|o| {
                    let occ = &occluders[o.occ as usize];
                    let w = <[DVec3; 3]>::try_from(occ.vertices()).ok()?;
                    let j = (0..3).find(|&j| w[j] == b && w[(j + 1) % 3] == a)?;
                    let c = w[(j + 2) % 3];
                    let ok = effective(occ.crossing()) == crossing
                        && high(&c)
                        && !ring.iter().any(|&(v, _)| v == c)
                        && turns_all(cell, a, c, b, sign)
                        && turns_all(cell, prev, a, c, sign)
                        && turns_all(cell, c, b, next, sign);
                    ok.then_some((o, c, o.adj[(j + 1) % 3], o.adj[(j + 2) % 3]))
                });
            match found {
                Some((o, c, ac, cb)) => {
                    taken[o.occ as usize] = true;
                    gone[o.occ as usize] = true;
                    ring[i].1 = ac;
                    ring.insert(i + 1, (c, cb));
                    grown = true;
                    fails = 0;
                }
                None => {
                    fails += 1;
                    i = (i + 1) % k;
                }
            }
        }
        if grown {
            taken[me.occ as usize] = true;
            let verts: SmallVec<[DVec3; MAX_PATCH_VERTICES]> =
                ring.iter().map(|&(v, _)| v).collect();
            occluders[me.occ as usize] = Occluder::new(&verts, crossing, 0);
            merged = true;
        } else if occluders[me.occ as usize].crossing() != crossing {
            occluders[me.occ as usize] = Occluder::new(&tri, crossing, 0);
        }
    }
    if merged {
        let mut k = 0;
        occluders.retain(|_| {
            k += 1;
            !gone[k - 1]
        });
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::solid::MeshEdge;

    #[test]
    fn a_merged_patch_blocks_the_lines_its_triangles_block() {
        // `merge_patches`' claim, checked on the lines themselves: for upward lines from points
        // of the tile, "some occluder after merging has all its edges of its crossing's sign"
        // equals the same for the triangles before, away from their edges. Fans of 1 to 7
        // triangles of random vertices above the tile plane, each with a random crossing (the
        // light on either side of its plane or both), tiles of four corners or one point:
        // non-convex, folded, back-facing and mixed fans are common, so the certificate must
        // refuse them.
        let mut state = 0x2545_f491_4f6c_dd1d_u64;
        let mut rnd = move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        let side = |x: DVec3, dir: DVec3, p: DVec3, q: DVec3| (p - x).cross(q - x).dot(dir);
        let blocks = |o: &Occluder, x: DVec3, dir: DVec3| {
            let v = o.vertices();
            let all =
                |s: f64| (0..v.len()).all(|i| side(x, dir, v[i], v[(i + 1) % v.len()]) * s > 0.0);
            match o.crossing() {
                Crossing::Positive => all(1.0),
                Crossing::Negative => all(-1.0),
                Crossing::Both => all(1.0) || all(-1.0),
            }
        };
        let (mut lines, mut refused) = (0, 0);
        let mut patches = [0usize; MAX_PATCH_VERTICES + 1];
        for case in 0..6000 {
            let n = 1 + case % 7;
            let mut v = || DVec3::new(rnd() - 0.5, rnd() - 0.5, rnd() * 0.5 + 1.0) * 2.0;
            let c = v();
            // A fan about `c` that mostly turns one way, so that some certify.
            let (r, z0) = (0.3 + rnd(), c.z);
            let a0 = rnd() * 6.3;
            let ring: Vec<DVec3> = (0..=n)
                .map(|i| {
                    let a = a0 + i as f64 * (0.2 + 0.9 * rnd());
                    c + DVec3::new(a.cos() * r, a.sin() * r, 0.0)
                        + DVec3::new(rnd() - 0.5, rnd() - 0.5, rnd() - 0.5) * (0.4 * rnd() * rnd())
                        - DVec3::Z * (z0 - 1.5) * rnd()
                })
                .collect();
            let tris: Vec<[DVec3; 3]> = (0..n).map(|i| [c, ring[i], ring[i + 1]]).collect();
            let crossing = |_: usize, k: f64| match (k * 3.0) as u32 {
                0 => Crossing::Positive,
                1 => Crossing::Negative,
                _ => Crossing::Both,
            };
            let mut occluders: Vec<Occluder> = tris
                .iter()
                .enumerate()
                .map(|(i, t)| Occluder::new(t, crossing(i, rnd()), 0))
                .collect();
            let before = occluders.clone();
            let b = MeshEdge::BORDER;
            let mut pairable: Vec<Pairable> = (0..n)
                .map(|i| Pairable {
                    key: (Blocker::Occluder(0), i as u32),
                    adj: [
                        if i > 0 { i as u32 - 1 } else { b },
                        b,
                        if i + 1 < n { i as u32 + 1 } else { b },
                    ],
                    occ: i as u32,
                })
                .collect();
            let centre = DVec3::new(rnd() - 0.5, rnd() - 0.5, 0.0);
            let h = if case % 2 == 0 { 0.0 } else { 0.3 * rnd() };
            let cell: SmallVec<[DVec3; 4]> = if h == 0.0 {
                core::iter::once(centre).collect()
            } else {
                [(-h, -h), (h, -h), (h, h), (-h, h)]
                    .iter()
                    .map(|&(u, w)| centre + DVec3::new(u, w, 0.0))
                    .collect()
            };
            merge_patches(
                &mut occluders,
                &mut pairable,
                &cell,
                DVec3::Z,
                DVec3::ZERO,
                1e-3,
            );
            if occluders.len() == before.len() {
                refused += 1;
            }
            for o in &occluders {
                patches[o.vertices().len()] += 1;
            }
            let (lo, hi) = tris
                .iter()
                .flatten()
                .fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(l, h), &p| {
                    (l.min(p), h.max(p))
                });
            for _ in 0..100 {
                let (u, w) = (rnd(), rnd());
                let x = match cell.len() {
                    1 => cell[0],
                    _ => {
                        let s = cell[0].lerp(cell[1], u);
                        let t = cell[3].lerp(cell[2], u);
                        s.lerp(t, w)
                    }
                };
                // Directions towards a random point of the fan's box, so that many lines hit
                // it; all of them upward.
                let target =
                    lo.lerp(hi, rnd()) + DVec3::new(rnd() - 0.5, rnd() - 0.5, rnd() - 0.5) * 0.2;
                let dir = target - x;
                let edgy = tris.iter().any(|t| {
                    (0..3).any(|i| {
                        let (p, q) = (t[i], t[(i + 1) % 3]);
                        side(x, dir, p, q).abs()
                            <= 1e-9 * (p - x).cross(q - x).length() * dir.length()
                    })
                });
                if edgy || dir.z <= 0.0 {
                    continue;
                }
                lines += 1;
                let was = before.iter().any(|o| blocks(o, x, dir));
                let now = occluders.iter().any(|o| blocks(o, x, dir));
                assert_eq!(now, was, "case {case}: x {x}, dir {dir}");
            }
        }
        // The test has power only if both answers are common, with patches of every size.
        assert!(refused > 500, "{refused} refused");
        assert!(
            patches[4] > 500 && patches[5] > 100 && patches[MAX_PATCH_VERTICES] > 20,
            "{patches:?}"
        );
        assert!(lines > 200_000, "{lines}");
    }
}
