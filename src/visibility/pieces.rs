//! The fast path of [`ClipVisibility`]: the visible region of a light as rings of directions
//! cut by half-spaces through the shading point, with no spherical polygon built, validated,
//! projected or unprojected, and no allocation for small inputs.
//!
//! # Why half-spaces suffice
//!
//! A direction is a point of the projective plane: the gnomonic plane about any center, without
//! the division (a point `(x, y)` of that plane is the direction `c + x e1 + y e2`, and any
//! positive multiple of it). Great circles are its lines, and a minor arc between two directions
//! is the chord between any positive multiples of them. So the set operations of the exact
//! visibility rule can run on direction vectors of any positive length, in the shading frame,
//! with each line given by the normal `n = a x b` of a great circle and each side test a sign
//! of `n . v`: one projection (the frame's rotation) per point and light, for the light and
//! every blocker alike, and no projection center to choose. Every integral downstream (Baum's
//! edge sum, the clip-free LTC kernel, thesis 003 eq. 4.6/4.7) is invariant under positive
//! scaling of each vertex, so nothing is ever normalized for it.
//!
//! The region is a chain of rings whose winding number is its indicator (the rings' edges with
//! the region on their left): Baum's edge sum over all of them is the integral over the region,
//! whatever their number, orientation or overlap. The light's own region starts it, clipped to
//! the upper hemisphere (one half-space, `z >= 0`, whose crossing points have `z` exactly zero),
//! so every ring lies in the closed upper hemisphere, where Baum's sum is the clamped-cosine
//! integral.
//!
//! # Subtracting a blocker
//!
//! The region a blocker covers is convex whenever the blocker is: a convex polyhedron seen from
//! outside covers the cone bounded by the planes through the point and its contour edges (seed
//! 000 Alg. 2, thesis 003 section 4.2), `K = n_j H_j`, one half-space `H_j` per contour edge; a
//! mesh triangle covers the cone of its three edges. The contour of a small polyhedron comes
//! from a [`ConvexFaces`] table built once per scene (facing tests per plane, and for a box-like
//! body the contour of every set of front planes, for others each plane's edges as bit sets),
//! the same loop the per-point chaining finds. `R - K` is computed in one of two ways:
//!
//! - **Boundary tracing** (Greiner and Hormann 1998, the difference), while the rings are simple
//!   and disjoint (an outer boundary and its holes, or the light's one ring): the crossings of
//!   the rings with `K`'s edges by parametric clipping of each ring edge against the half-spaces
//!   (Cyrus and Beck 1978), then the rings followed outside `K` and `K`'s edges followed
//!   backwards inside the region (with exactly two crossings, one bite out of one ring, the
//!   loop is written out directly). The result is the region's boundary itself, the fewest
//!   edges to integrate. Every decision it takes (a vertex's side of a plane, the order of two
//!   crossings on one edge, which plane an edge enters `K` by) must clear its rounding bound by a
//!   margin, and the traversal must close consistently; otherwise it does nothing and the
//!   subtraction below runs instead, for this blocker and every later one.
//! - **Inclusion–exclusion**, on any chain: `R - K = R - (R n K)`, each ring `L` cut by `K`'s
//!   planes in turn (Sutherland–Hodgman against planes through the origin) and the cut appended
//!   reversed. On a ring that is not convex a cut may leave bridges (edges along the cutting
//!   circle run once each way), but as a chain its winding number is still the ring's times the
//!   indicator of the half-space: the parts outside are closed by the same bridges into loops
//!   outside it. A ring that `K` covers whole is removed instead, and one that a plane of `K`
//!   leaves entirely outside costs one pass over its vertices. The chain cancels where blockers
//!   overlap, to a few ulps of the light's integral, far below the spherical path's own
//!   snapping of vertices (`crate::planar::SNAP_REL` of the projected coordinates). Each cut is
//!   continuous in its input: a vertex on or within rounding of a cutting plane moves the
//!   boundary by rounding, not its topology, so no near-degenerate configuration needs a
//!   decision (and none is an [`GeomError::Undecidable`]).
//!
//! # Where it applies
//!
//! [`ClipVisibility::visible_pieces`] answers for [`Method::Silhouette`] with:
//!
//! - a convex light (its silhouette ring), or a planar mesh light (its boundary loops,
//!   [`TriangleMesh::boundary_loops`], once per scene: seen from the front its region is the
//!   region they bound, not a union of its triangles);
//! - blockers that are separated from the light by the precomputed plane and touch none of its
//!   triangles' planes (step 2 of [`ClipVisibility::visible_region`]: subtracted whole),
//!   convex (their contour half-spaces) or meshes below
//!   [`BVH_MIN_TRIANGLES`](super::BVH_MIN_TRIANGLES) triangles (each triangle's three
//!   half-spaces, seen from either side).
//!
//! It declines (`Ok(false)`), leaving the region to the spherical path, for everything else: a
//! blocker that interpenetrates the light or has a vertex in the plane of one of its triangles,
//! a mesh blocker with a hierarchy (the one-pass union culls its triangles by shafts, see
//! `visibility/union.rs`), a point inside a closed light or on its surface (a convex light
//! without a front face), non-planar mesh lights, Bezier-bounded lights (flattened per point;
//! as blockers they are their triangulated flattening, a mesh), a planar light seen
//! edge-on by some of its triangles and not others, every silhouette that
//! [`convex_silhouette`](crate::solid::silhouette::convex_silhouette) would not take as one
//! loop chained by vertex index with well separated vertices (the point inside or on a convex
//! object, a point within rounding of an edge's line), and a blocker's silhouette that turns
//! right somewhere (a face within the facing tolerance of edge-on left out): there the
//! spherical path decides, or gives up, exactly as without this path.

use alloc::boxed::Box;
use alloc::collections::BTreeMap;
use alloc::sync::Arc;
use alloc::vec::Vec;

use glam::DVec3;
use smallvec::SmallVec;

use super::cull::{LightCone, above_horizon, may_occlude};
use super::mesh_pieces::MeshScratch;
use super::{Blocker, ClipVisibility, Method};
use crate::GeomError;
use crate::solid::facing::{FacingAt, Side, face_side, in_front};
use crate::solid::silhouette::chain_by_index;
use crate::solid::{Body, ConvexPolyhedron, ShadingFrame, TriangleMesh};
use crate::sphere::{ANTIPODAL_TOLERANCE, MATCH_TOLERANCE};

/// Directions of one ring of vertices, inline for the rings of small lights and their cuts.
type Ring = SmallVec<[DVec3; 32]>;

/// Most rings [`Pieces`] holds before the fast path declines: inclusion–exclusion can double
/// them with each blocker that meets all of them, so this bounds the work for many mutually
/// overlapping blockers, which the spherical path then takes.
const MAX_RINGS: usize = 64;

/// Margin of the boundary tracing's decisions, in units of the rounding error bounds they are
/// compared with (see [`Pieces::trace_difference`]).
const MARGIN: f64 = 64.0 * f64::EPSILON;

/// Polyhedra up to this many vertices are chained without a buffer on the heap.
const INLINE_VERTICES: usize = 64;

/// A chain of rings: ring `k` is `pts[ends[k - 1]..ends[k]]` (from 0 for the first).
#[derive(Debug, Clone)]
struct Chain {
    pts: SmallVec<[DVec3; 128]>,
    ends: SmallVec<[u32; 16]>,
}

impl Chain {
    #[inline(always)]
    fn new() -> Self {
        Chain {
            pts: SmallVec::new(),
            ends: SmallVec::new(),
        }
    }

    fn clear(&mut self) {
        self.pts.clear();
        self.ends.clear();
    }

    /// Ends the ring started at `start`; one with fewer than three vertices bounds nothing and
    /// is dropped.
    fn close(&mut self, start: usize) {
        if self.pts.len() - start >= 3 {
            self.ends.push(self.pts.len() as u32);
        } else {
            self.pts.truncate(start);
        }
    }

    /// Appends `ring` as a ring of the chain.
    fn push_ring(&mut self, ring: &[DVec3]) {
        self.pts.extend_from_slice(ring);
        self.ends.push(self.pts.len() as u32);
    }

    /// The rings' index ranges.
    fn ranges(&self) -> impl Iterator<Item = core::ops::Range<usize>> + '_ {
        let mut start = 0usize;
        self.ends.iter().map(move |&e| {
            let r = start..e as usize;
            start = e as usize;
            r
        })
    }
}

/// The visible region of a light from a shading point, as the fast path of
/// [`ClipVisibility::visible_pieces`] leaves it: rings of directions of any positive length (not
/// unit vectors) in the closed upper hemisphere of the shading frame, forming a chain whose
/// winding number is the region's indicator (the region on the left of each edge, as for a
/// [`SphericalPolygon`](crate::sphere::SphericalPolygon), but rings may overlap and cancel):
/// the region's boundary integrals are the sums of the rings' edge terms.
///
/// It is also the scratch storage of the fast path: a caller that keeps one across calls
/// reuses its buffers. Inline room for 128 vertices in all, so small lights and blockers (up to
/// 16 vertices each, a few blockers) allocate nothing; larger ones spill to the heap once per
/// `Pieces` value, as do closed mesh blockers and closed non-planar mesh lights of any size,
/// whose contour overlay keeps growable buffers here.
#[derive(Debug, Clone)]
pub struct Pieces {
    /// The region (`bufs[cur]`) and the one a subtraction builds (the other).
    bufs: [Chain; 2],
    cur: usize,
    /// Whether the rings are simple and disjoint (no two touch), so that the boundary tracing
    /// applies.
    simple: bool,
    /// A ring being cut by a blocker's planes, and the cut's output, used in turn.
    rings: [Ring; 2],
    /// The current blocker: its vertices (directions, counter-clockwise) and the normals of
    /// its half-spaces (`planes[j]` through `kv[j]` and `kv[j + 1]`, `n . v >= 0` inside).
    kv: Ring,
    planes: SmallVec<[DVec3; 24]>,
    /// Contour edges of a convex silhouette, and front-face flags of polyhedra with more than
    /// 64 faces.
    contour: SmallVec<[(u32, u32); 24]>,
    front: SmallVec<[bool; 64]>,
    /// A light ring being built.
    dirs: Ring,
    /// Boundary tracing: which vertices of the rings are inside `K` (bit `i` for vertex `i`),
    /// and the crossings with their order along `K`.
    inside_bits: u64,
    crossings: SmallVec<[Crossing; 16]>,
    order: SmallVec<[u16; 16]>,
    /// Subtractions so far by boundary tracing and by inclusion–exclusion (diagnostics).
    traced: u64,
    cut: u64,
    /// Scratch storage of the closed meshes' path (`visibility/mesh_pieces.rs`), made on its
    /// first use: its growable buffers are no cost to points that never take that path.
    pub(super) mesh: Option<Box<MeshScratch>>,
    /// Regions decided by that path: resolved by its overlay, or found clear of every
    /// blocker's contour in the light's box (diagnostics).
    pub(super) overlays: u64,
    /// Tests: take the general traversal for two crossings too, and count the subtractions
    /// that [`Pieces::traverse_two`] answered.
    #[cfg(test)]
    general_only: bool,
    #[cfg(test)]
    two_crossings: u64,
    /// Tests: run the crossings' pass on every edge whose ends are outside `K` by different
    /// planes (no [`outside_both`]), and count the edges that `outside_both` answered.
    #[cfg(test)]
    no_reject: bool,
    #[cfg(test)]
    rejects: u64,
    /// Tests: silhouette walks whose spacing and turn tests [`walk_is_certified`] answered.
    #[cfg(test)]
    certified: u64,
}

/// Where a ring of the region crosses the boundary of a blocker's region `K`.
#[derive(Debug, Default, Clone, Copy)]
struct Crossing {
    /// The crossing point.
    x: DVec3,
    /// Position along the ring: the index (into the chain's points) of the crossed edge's first
    /// vertex, and the parameter along the edge's chord.
    edge: u32,
    t: f64,
    /// The ring's first and one-past-last vertex indices.
    ring: (u32, u32),
    /// The edge of `K` crossed (from `kv[j]` to `kv[j + 1]`).
    j: u16,
    /// Whether the ring enters `K` here (else it leaves it).
    enter: bool,
    /// The next crossing along the same ring, and this crossing's position in the order along
    /// `K`'s boundary.
    next: u16,
    rank: u16,
    /// Visited by the traversal.
    done: bool,
}

impl Default for Pieces {
    #[inline(always)]
    fn default() -> Self {
        Pieces::new()
    }
}

impl Pieces {
    /// Empty storage (no heap allocation).
    #[must_use]
    #[inline(always)]
    pub fn new() -> Self {
        // Field by field and always inlined, so that a caller's `Pieces` (or `ShadeContext`) is
        // set up where it lives: only the vectors' lengths are written, not their inline storage
        // (a few kilobytes) copied.
        Pieces {
            bufs: [Chain::new(), Chain::new()],
            cur: 0,
            simple: false,
            rings: [SmallVec::new(), SmallVec::new()],
            kv: SmallVec::new(),
            planes: SmallVec::new(),
            contour: SmallVec::new(),
            front: SmallVec::new(),
            dirs: SmallVec::new(),
            inside_bits: 0,
            crossings: SmallVec::new(),
            order: SmallVec::new(),
            traced: 0,
            cut: 0,
            mesh: None,
            overlays: 0,
            #[cfg(test)]
            general_only: false,
            #[cfg(test)]
            two_crossings: 0,
            #[cfg(test)]
            no_reject: false,
            #[cfg(test)]
            rejects: 0,
            #[cfg(test)]
            certified: 0,
        }
    }

    /// The rings, each a slice of directions in the shading frame (not normalized).
    pub fn rings(&self) -> impl Iterator<Item = &[DVec3]> + Clone + '_ {
        let c = &self.bufs[self.cur];
        crate::sphere::ring_slices(&c.pts, &c.ends)
    }

    /// How many blocker subtractions this storage has run, over all calls: by boundary tracing
    /// and by inclusion–exclusion (see the source of `visibility::pieces`); for tests and
    /// benchmarks.
    #[doc(hidden)]
    #[must_use]
    pub fn subtractions(&self) -> (u64, u64) {
        (self.traced, self.cut)
    }

    /// How many regions this storage has decided by the overlay of closed meshes' contours
    /// (see the source of `visibility::mesh_pieces`): resolved by the overlay, or found with no
    /// blocker's contour in the light's box, over all calls; for tests and benchmarks.
    #[doc(hidden)]
    #[must_use]
    pub fn overlays(&self) -> u64 {
        self.overlays
    }

    /// Number of rings.
    #[must_use]
    pub fn len(&self) -> usize {
        self.bufs[self.cur].ends.len()
    }

    /// Whether there is no ring (nothing of the light is visible).
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.bufs[self.cur].ends.is_empty()
    }

    fn clear(&mut self) {
        self.bufs[self.cur].clear();
        self.simple = false;
    }

    /// Whether the rings are known to be simple and pairwise disjoint (no vertex shared, no
    /// two touching), so that further blockers may be subtracted by boundary tracing; `false`
    /// where that is not known (a result through one direction twice is never marked simple).
    #[must_use]
    pub fn is_simple(&self) -> bool {
        self.simple
    }

    /// Makes the region the rings `pts[ends[k - 1]..ends[k]]`, `simple` as the field says.
    pub(super) fn set_region(&mut self, pts: &[DVec3], ends: &[u32], simple: bool) {
        let chain = &mut self.bufs[self.cur];
        chain.clear();
        chain.pts.extend_from_slice(pts);
        chain.ends.extend_from_slice(ends);
        self.simple = simple;
    }

    /// Makes the region a subtraction built in the other buffer the current one.
    fn flip(&mut self) {
        self.cur ^= 1;
    }

    /// Appends `self.dirs` clipped to the closed upper hemisphere (`z >= 0`) as a ring; whether
    /// the horizon cut it.
    fn push_dirs_upper(&mut self) -> bool {
        let chain = &mut self.bufs[self.cur];
        let dirs = &self.dirs;
        let start = chain.pts.len();
        let mut cut = false;
        if dirs.iter().all(|v| v.z > 0.0) {
            chain.pts.extend_from_slice(dirs);
        } else if let Some(&last) = dirs.last() {
            cut = true;
            let mut prev = last;
            for &cur in dirs.iter() {
                if prev.z >= 0.0 {
                    chain.pts.push(prev);
                }
                if (prev.z > 0.0 && cur.z < 0.0) || (prev.z < 0.0 && cur.z > 0.0) {
                    // A positive combination with `z` exactly zero: the two products are the
                    // same product (multiplication commutes), so they cancel exactly.
                    let (a, b) = if prev.z > 0.0 {
                        (prev, cur)
                    } else {
                        (cur, prev)
                    };
                    let x = a * -b.z + b * a.z;
                    chain.pts.push(DVec3::new(x.x, x.y, 0.0));
                }
                prev = cur;
            }
        }
        chain.close(start);
        cut
    }

    /// Subtracts `K` (the intersection of the half-spaces in `self.planes`, whose vertices are
    /// `self.kv`): by boundary tracing while the rings are simple, else (or where the tracing
    /// declines) by inclusion–exclusion. `false` when the rings would exceed [`MAX_RINGS`].
    fn subtract(&mut self) -> bool {
        if self.simple {
            if self.trace_difference() {
                self.traced += 1;
                return true;
            }
            self.simple = false;
        }
        self.cut += 1;
        self.subtract_by_cuts()
    }

    /// `R - (R n K)`: for each ring `L` that `K` meets, `L n K` appended reversed, or `L`
    /// removed where `K` covers it (see the module documentation). Out of line (as the other
    /// rarer steps of a subtraction): the boundary tracing's common path stays small.
    #[inline(never)]
    fn subtract_by_cuts(&mut self) -> bool {
        let Pieces {
            bufs,
            cur,
            rings,
            planes,
            ..
        } = self;
        let (from, to) = flip_buffers(bufs, *cur);
        for range in from.ranges() {
            let ring = &from.pts[range];
            match cut_by_planes(ring, planes, rings) {
                Cut::Outside => to.push_ring(ring),
                // Covered whole: the ring and its cut cancel.
                Cut::Inside => {}
                Cut::Part(r) => {
                    to.push_ring(ring);
                    to.pts.extend(rings[r].iter().rev().copied());
                    to.ends.push(to.pts.len() as u32);
                }
            }
        }
        let ok = to.ends.len() <= MAX_RINGS;
        self.flip();
        ok
    }
}

/// The region's current chain `bufs[cur]` to read and the other one, cleared, to write the
/// next region into (the caller then flips `cur`).
fn flip_buffers(bufs: &mut [Chain; 2], cur: usize) -> (&Chain, &mut Chain) {
    let [a, b] = bufs;
    let (from, to) = if cur == 0 { (&*a, b) } else { (&*b, a) };
    to.clear();
    (from, to)
}

/// The ring cut by every plane of `planes` (Sutherland–Hodgman), the result, if any, in
/// `rings[r]`.
fn cut_by_planes(ring: &[DVec3], planes: &[DVec3], rings: &mut [Ring; 2]) -> Cut {
    // Index of the ring holding the current cut; `None` while it is still the ring itself.
    let mut at: Option<usize> = None;
    for &n in planes {
        let (lo, hi) = rings.split_at_mut(1);
        let (src, out): (&[DVec3], &mut Ring) = match at {
            None => (ring, &mut lo[0]),
            Some(0) => (&lo[0], &mut hi[0]),
            Some(_) => (&hi[0], &mut lo[0]),
        };
        let (mut any_in, mut any_out) = (false, false);
        for &v in src {
            let s = n.dot(v);
            any_in |= s > 0.0;
            any_out |= s < 0.0;
        }
        if !any_out {
            continue;
        }
        if !any_in {
            return Cut::Outside;
        }
        cut_ring(src, n, out);
        if out.len() < 3 {
            return Cut::Outside;
        }
        at = Some(at.map_or(0, |r| 1 - r));
    }
    match at {
        None => Cut::Inside,
        Some(r) => Cut::Part(r),
    }
}

/// What a blocker's planes leave of a ring ([`cut_by_planes`]).
enum Cut {
    /// Nothing inside: the blocker misses the ring (or meets it in no area).
    Outside,
    /// All of it inside: the blocker covers the ring.
    Inside,
    /// The part inside, in the ring of that index.
    Part(usize),
}

/// The part of `ring` on the non-negative side of the plane with normal `n` through the origin,
/// into `out` (Sutherland–Hodgman against one plane).
fn cut_ring(ring: &[DVec3], n: DVec3, out: &mut Ring) {
    out.clear();
    let Some(&last) = ring.last() else {
        return;
    };
    let (mut a, mut sa) = (last, n.dot(last));
    for &b in ring {
        let sb = n.dot(b);
        if sa >= 0.0 {
            out.push(a);
        }
        if (sa > 0.0 && sb < 0.0) || (sa < 0.0 && sb > 0.0) {
            out.push(chord_point(a, sa, b, sb));
        }
        (a, sa) = (b, sb);
    }
}

/// The point of the chord `a-b` on the plane where the sides `sa` and `sb` (of opposite signs)
/// vanish: a convex combination, so its length stays between theirs.
#[inline]
fn chord_point(a: DVec3, sa: f64, b: DVec3, sb: f64) -> DVec3 {
    let (wa, wb) = (sb.abs(), sa.abs());
    (a * wa + b * wb) / (wa + wb)
}

/// `|v|_1`, an upper bound of `|v|` without a root, for the rounding bounds.
#[inline]
fn norm1(v: DVec3) -> f64 {
    v.x.abs() + v.y.abs() + v.z.abs()
}

/// `n` scaled to a 1-norm of 1 (a plane's normal: the half-space is the same, and the rounding
/// bounds of the sides need no norm of it). `n` is not zero: the edges it comes from are checked
/// to be apart.
#[inline]
fn unit1(n: DVec3) -> DVec3 {
    n / norm1(n)
}

impl Pieces {
    /// `R - K` by boundary tracing (Greiner and Hormann 1998, the difference; the crossings by
    /// Cyrus–Beck clipping of each ring edge against `K`'s half-spaces), for simple disjoint
    /// rings. `false`, with the region unchanged, where a decision is within its rounding bound
    /// (times [`MARGIN`]) or the traversal does not close consistently.
    ///
    /// Rounding bounds: a side `n . v` (`n` from [`edge_plane`], scaled to `|n|_1 = 1` by
    /// [`unit1`]) is off by at most a few `eps |v|`; a chord parameter `t = sa / (sa - sb)` by at most
    /// `eps |n| (|a| + |b|) / |sa - sb|` times a small constant; both are compared with
    /// [`MARGIN`] (64 `eps`) times the same products, with 1-norms for the lengths.
    fn trace_difference(&mut self) -> bool {
        let region = &self.bufs[self.cur];
        let pts: &[DVec3] = &region.pts;
        let planes: &[DVec3] = &self.planes;
        if pts.len() > 64 {
            return false;
        }
        // Ring by ring: which vertices lie inside `K` (bit `i`), and the crossings of each edge
        // in order along the ring. A vertex is classified by the first plane with a negative
        // side ([`first_plane_out`]); an edge whose ends are outside `K` first by the same plane
        // (or both inside it) misses `K`'s boundary, which the crossings' pass would find at
        // that plane after the same checks on the same sides. Sides are recomputed where the
        // crossings need them, which is cheaper than storing them.
        let mut inside = 0u64;
        self.crossings.clear();
        let mut start = 0usize;
        for &end in &region.ends {
            let end = end as usize;
            let ring = (start as u32, end as u32);
            // Each vertex's 1-norm serves its classification and the crossings of both its
            // edges.
            let first1 = norm1(pts[start]);
            let Some(first) = first_plane_out(pts[start], first1, planes) else {
                return false;
            };
            inside |= u64::from(first == u32::MAX) << start;
            let (mut prev, mut prev1) = (first, first1);
            for b in start + 1..=end {
                // The edge's first end: the previous vertex (the ring's last one for the
                // closing edge, whose second end is the ring's first).
                let a = b - 1;
                let (b, out, b1) = if b == end {
                    (start, first, first1)
                } else {
                    let b1 = norm1(pts[b]);
                    let Some(out) = first_plane_out(pts[b], b1, planes) else {
                        return false;
                    };
                    inside |= u64::from(out == u32::MAX) << b;
                    (b, out, b1)
                };
                // Every side of both ends before the first plane either end is outside of is
                // positive, and was checked against its bound: the crossings' pass starts there.
                // Ends outside `K` by different first planes: where the end with the earlier
                // one is also clearly outside the other's, the edge misses `K` (one side
                // instead of the pass).
                #[cfg(test)]
                let reject = !self.no_reject;
                #[cfg(not(test))]
                let reject = true;
                let missed = prev != out
                    && reject
                    && outside_both(pts, planes, (a, b), (prev, out), (prev1, b1));
                #[cfg(test)]
                {
                    self.rejects += u64::from(missed);
                }
                if prev != out
                    && !missed
                    && !edge_crossings(
                        pts,
                        planes,
                        (a, b),
                        (prev1, b1),
                        ring,
                        prev.min(out) as usize,
                        &mut self.crossings,
                    )
                {
                    return false;
                }
                (prev, prev1) = (out, b1);
            }
            start = end;
        }
        self.inside_bits = inside;
        #[cfg(test)]
        let general_only = self.general_only;
        #[cfg(not(test))]
        let general_only = false;
        match self.crossings.len() {
            0 => self.difference_without_crossings(),
            2 if !general_only => {
                #[cfg(test)]
                {
                    self.two_crossings += 1;
                }
                self.traverse_two()
            }
            n if n > u16::MAX as usize / 2 => false,
            _ => {
                // Link each ring's crossings in a cycle (they are consecutive, in ring order).
                let cs = &mut self.crossings[..];
                let mut first = 0;
                for c in 0..cs.len() {
                    let last = c + 1 == cs.len() || cs[c + 1].ring != cs[c].ring;
                    cs[c].next = if last { first } else { c + 1 } as u16;
                    if last {
                        first = c + 1;
                    }
                }
                self.order_along_k() && self.traverse()
            }
        }
    }

    /// [`Pieces::traverse`] (after [`Pieces::order_along_k`]) for exactly two crossings: the
    /// same region, vertex for vertex in the same order, and the same decisions, without the
    /// general bookkeeping. The loop leaves `K` at the exit crossing, runs along the ring to the
    /// entry crossing, and back along `K` to the exit; where the two crossings are on one edge
    /// of `K`, their order along it (decided as `order_along_k` decides it) says whether that
    /// is no vertex of `K` or all of them.
    fn traverse_two(&mut self) -> bool {
        let (c0, c1) = (self.crossings[0], self.crossings[1]);
        // One ring leaving `K` once and entering it once, or the traversal fails.
        if c0.ring != c1.ring || c0.enter == c1.enter {
            return false;
        }
        let m = self.kv.len();
        let steps_k = if c0.j == c1.j {
            // `order_along_k`'s comparison of the two: crossing 0 is after crossing 1 along
            // `K`'s edge where `d > 0`.
            let d = c1.x.cross(c0.x).dot(self.planes[c0.j as usize]);
            if d.abs() <= MARGIN * norm1(c0.x) * norm1(c1.x) {
                return false;
            }
            // All of `K`'s vertices where the exit comes after the entry (crossing 1 is the
            // entry exactly where crossing 0 is the exit).
            if (d > 0.0) == c1.enter { m } else { 0 }
        } else {
            let (je, jp) = if c0.enter { (c0.j, c1.j) } else { (c1.j, c0.j) };
            (je as usize + m - jp as usize) % m
        };
        let (exit, entry) = if c0.enter { (c1, c0) } else { (c0, c1) };
        let Pieces {
            bufs,
            cur,
            kv,
            inside_bits,
            ..
        } = self;
        let inside = *inside_bits;
        let (from, to) = flip_buffers(bufs, *cur);
        let (r0, r1) = (exit.ring.0 as usize, exit.ring.1 as usize);
        let len = r1 - r0;
        let (ia, ib) = (exit.edge as usize - r0, entry.edge as usize - r0);
        let mut steps = (ib + len - ia) % len;
        if steps == 0 && entry.t <= exit.t {
            steps = len;
        }
        // Element by element: the pieces are a few vertices long, shorter than a copy's setup
        // (or a reservation's, for the inline storage that holds them).
        to.pts.push(exit.x);
        // The ring's vertices after the exit's edge, up to the entry's edge's last one.
        let ring = &from.pts[r0..r1];
        for k in ia + 1..=ia + steps {
            to.pts.push(ring[if k >= len { k - len } else { k }]);
        }
        to.pts.push(entry.x);
        // `K`'s vertices backwards from the entry's edge's first one.
        let je = entry.j as usize;
        for k in 0..steps_k {
            to.pts.push(kv[if k <= je { je - k } else { je + m - k }]);
        }
        to.close(0);
        // Rings without crossings: kept outside `K`, dropped inside.
        for range in from.ranges() {
            if range.start != r0 && (inside >> range.start) & 1 == 0 {
                to.push_ring(&from.pts[range]);
            }
        }
        self.flip();
        true
    }

    /// Ranks the crossings in order along `K`'s boundary (by edge, then along it); `false` where
    /// two on one edge are within rounding of each other.
    fn order_along_k(&mut self) -> bool {
        let n = self.crossings.len();
        self.order.clear();
        for c in 0..n as u16 {
            self.order.push(c);
        }
        // Insertion sort: a handful of crossings.
        for i in 1..n {
            let mut k = i;
            while k > 0 {
                let (p, q) = (self.order[k - 1] as usize, self.order[k] as usize);
                let (cp, cq) = (&self.crossings[p], &self.crossings[q]);
                let before = if cp.j != cq.j {
                    cq.j < cp.j
                } else {
                    // Along the edge's great circle, counter-clockwise about its normal.
                    let nj = self.planes[cp.j as usize];
                    let d = cq.x.cross(cp.x).dot(nj);
                    if d.abs() <= MARGIN * norm1(cp.x) * norm1(cq.x) {
                        return false;
                    }
                    d > 0.0
                };
                if !before {
                    break;
                }
                self.order.swap(k - 1, k);
                k -= 1;
            }
        }
        for (rank, &c) in self.order.iter().enumerate() {
            self.crossings[c as usize].rank = rank as u16;
        }
        true
    }

    /// The Greiner–Hormann traversal of `R - K`: from each crossing where a ring leaves `K`,
    /// along the ring to the next crossing (where it enters `K`), then backwards along `K`'s
    /// boundary to the previous crossing in `K`'s order (where a ring leaves `K` again), until
    /// the loop closes. Rings without crossings are kept outside `K` and dropped inside it.
    /// `false`, with the region unchanged, where the crossings do not alternate as they must.
    fn traverse(&mut self) -> bool {
        let n = self.crossings.len();
        let m = self.kv.len();
        let Pieces {
            bufs,
            cur,
            kv,
            inside_bits,
            crossings,
            order,
            ..
        } = self;
        let inside = *inside_bits;
        let (from, to) = flip_buffers(bufs, *cur);
        let (fp, kv, order): (&[DVec3], &[DVec3], &[u16]) = (&from.pts, kv, order);
        let crossings: &mut [Crossing] = crossings;
        let mut guard = n + 1;
        for c0 in 0..n {
            if crossings[c0].done || crossings[c0].enter {
                continue;
            }
            let start = to.pts.len();
            let mut c = c0;
            loop {
                guard = match guard.checked_sub(1) {
                    Some(g) => g,
                    None => return false,
                };
                // Leaving `K` at `c`: along the ring to the next crossing.
                let cc = crossings[c];
                if cc.enter || cc.done {
                    return false;
                }
                crossings[c].done = true;
                to.pts.push(cc.x);
                let e = crossings[cc.next as usize];
                if !e.enter || e.done {
                    return false;
                }
                let (r0, r1) = (cc.ring.0 as usize, cc.ring.1 as usize);
                let len = r1 - r0;
                let (ia, ib) = (cc.edge as usize - r0, e.edge as usize - r0);
                let mut steps = (ib + len - ia) % len;
                if steps == 0 && e.t <= cc.t {
                    steps = len;
                }
                for k in 1..=steps {
                    let i = ia + k;
                    to.pts.push(fp[r0 + if i >= len { i - len } else { i }]);
                }
                to.pts.push(e.x);
                crossings[cc.next as usize].done = true;
                // Entering `K` at `e`: backwards along `K` to the previous crossing.
                let p = order[if e.rank == 0 {
                    n - 1
                } else {
                    e.rank as usize - 1
                }] as usize;
                let pc = crossings[p];
                if pc.enter {
                    return false;
                }
                let (je, jp) = (e.j as usize, pc.j as usize);
                let mut steps = (je + m - jp) % m;
                if steps == 0 && pc.rank > e.rank {
                    steps = m;
                }
                for k in 0..steps {
                    to.pts.push(kv[(je + m - k) % m]);
                }
                c = p;
                if c == c0 {
                    break;
                }
            }
            to.close(start);
        }
        if crossings.iter().any(|c| !c.done) {
            return false;
        }
        // Rings without crossings: kept outside `K`, dropped inside.
        for range in from.ranges() {
            let crossed = crossings.iter().any(|c| c.ring.0 as usize == range.start);
            if !crossed && (inside >> range.start) & 1 == 0 {
                to.push_ring(&from.pts[range]);
            }
        }
        self.flip();
        true
    }

    /// `R - K` where no ring crosses `K`'s boundary: rings inside `K` dropped, and `K` itself a
    /// new hole where it lies inside the region (decided by the parity of the region's
    /// crossings with the meridian arc from a vertex of `K` down through the horizon). `false`
    /// where that parity is within rounding.
    #[inline(never)]
    fn difference_without_crossings(&mut self) -> bool {
        let k0 = self.kv[0];
        // The region lies in the upper hemisphere.
        let inside_region = if k0.z <= 0.0 {
            Some(false)
        } else {
            contains(&self.bufs[self.cur], k0)
        };
        let Some(inside_region) = inside_region else {
            return false;
        };
        let Pieces {
            bufs,
            cur,
            kv,
            inside_bits,
            ..
        } = self;
        let inside = *inside_bits;
        let (from, to) = flip_buffers(bufs, *cur);
        for range in from.ranges() {
            if (inside >> range.start) & 1 == 0 {
                to.push_ring(&from.pts[range]);
            }
        }
        if inside_region {
            // The boundary of `R - K` runs around `K` clockwise.
            to.pts.extend(kv.iter().rev().copied());
            to.ends.push(to.pts.len() as u32);
        }
        self.flip();
        true
    }
}

/// The first of `planes` on whose negative side `v` (of 1-norm `v1`) lies, `u32::MAX` if none
/// (`v` inside `K`); `None` where a side up to that plane is within its rounding bound (see
/// [`Pieces::trace_difference`]).
#[inline(always)]
fn first_plane_out(v: DVec3, v1: f64, planes: &[DVec3]) -> Option<u32> {
    let bound = MARGIN * v1;
    for (j, &n) in planes.iter().enumerate() {
        let s = n.dot(v);
        // Clearly positive (the common case, one comparison), else the checks in order.
        if s > bound {
            continue;
        }
        if s.abs() <= bound {
            return None;
        }
        if s < 0.0 {
            return Some(j as u32);
        }
    }
    Some(u32::MAX)
}

/// Whether the ring edge `a -> b` (indices into `pts`; 1-norms `a1`, `b1`), whose ends lie
/// outside `K` first by the different planes `ja` and `jb` ([`first_plane_out`], `u32::MAX` for
/// an end inside `K`), lies outside one plane of `K` all along: the end with the earlier first
/// plane is also clearly outside the other's (its side below minus its rounding bound, as
/// [`first_plane_out`] decides it), so both sides at that plane are negative and so is every
/// side of the chord between them, which then misses `K` (Cohen and Sutherland's trivial
/// reject, on the one plane that can give it: the later end is clearly inside the earlier
/// plane). `false` where that does not hold; the crossings' pass ([`edge_crossings`]) then
/// decides.
#[inline(always)]
fn outside_both(
    pts: &[DVec3],
    planes: &[DVec3],
    (a, b): (usize, usize),
    (ja, jb): (u32, u32),
    (a1, b1): (f64, f64),
) -> bool {
    let (v, v1, j) = if ja < jb { (a, a1, jb) } else { (b, b1, ja) };
    j != u32::MAX && planes[j as usize].dot(pts[v]) < -MARGIN * v1
}

/// Adds to `out` the crossings of the ring edge `a -> b` (indices into `pts`, the ring's range
/// `ring`; the ends' 1-norms `a1`, `b1`) with `K`'s boundary, by Cyrus–Beck: the edge's part
/// inside `K` is `[t_in, t_out]`, `t_in` the largest parameter at which it enters a half-space
/// and `t_out` the smallest at which it leaves one. `false` where a side, the plane of the entry
/// or exit, or whether the part is empty, is within rounding. The planes before `from` are
/// skipped: the caller knows both ends clearly inside them (a plane with both sides positive
/// changes nothing here).
fn edge_crossings(
    pts: &[DVec3],
    planes: &[DVec3],
    (a, b): (usize, usize),
    (a1, b1): (f64, f64),
    ring: (u32, u32),
    from: usize,
    out: &mut SmallVec<[Crossing; 16]>,
) -> bool {
    let (pa, pb) = (pts[a], pts[b]);
    // Entry and exit: parameter, error bound, plane; and the runners-up's nearest bound.
    let (mut t_in, mut e_in, mut j_in, mut second_in) = (0.0, 0.0, usize::MAX, f64::NEG_INFINITY);
    let (mut t_out, mut e_out, mut j_out, mut second_out) = (1.0, 0.0, usize::MAX, f64::INFINITY);
    let bound = MARGIN;
    let (ba, bb) = (bound * a1, bound * b1);
    for (j, &n) in planes.iter().enumerate().skip(from) {
        let (sa, sb) = (n.dot(pa), n.dot(pb));
        // Both clearly positive (the plane changes nothing), else the checks in order.
        if sa > ba && sb > bb {
            continue;
        }
        if sa.abs() <= ba || sb.abs() <= bb {
            return false;
        }
        if sa < 0.0 && sb < 0.0 {
            // Outside this half-space all along: the edge misses `K`.
            return true;
        }
        if (sa < 0.0) == (sb < 0.0) {
            continue;
        }
        let t = sa / (sa - sb);
        let e = bound * (a1 + b1) / (sa - sb).abs();
        if sa < 0.0 {
            // Entering this half-space.
            if t - e > t_in + e_in {
                second_in = second_in.max(t_in + e_in);
                (t_in, e_in, j_in) = (t, e, j);
            } else if t + e >= t_in - e_in {
                return false;
            } else {
                second_in = second_in.max(t + e);
            }
        } else if t + e < t_out - e_out {
            second_out = second_out.min(t_out - e_out);
            (t_out, e_out, j_out) = (t, e, j);
        } else if t - e <= t_out + e_out {
            return false;
        } else {
            second_out = second_out.min(t - e);
        }
    }
    if (j_in != usize::MAX && second_in >= t_in - e_in)
        || (j_out != usize::MAX && second_out <= t_out + e_out)
    {
        return false;
    }
    if t_in + e_in >= t_out - e_out {
        // Either clearly empty (the edge passes outside a corner of `K`) or within rounding of a
        // corner.
        return t_in - e_in > t_out + e_out;
    }
    let crossing = |t: f64, j: usize, enter: bool| Crossing {
        x: pa + (pb - pa) * t,
        edge: a as u32,
        t,
        ring,
        j: j as u16,
        enter,
        ..Crossing::default()
    };
    match (j_in != usize::MAX, j_out != usize::MAX) {
        (true, true) => {
            // Two pushes: `extend` is a call of its own.
            out.push(crossing(t_in, j_in, true));
            out.push(crossing(t_out, j_out, false));
        }
        (true, false) => out.push(crossing(t_in, j_in, true)),
        (false, true) => out.push(crossing(t_out, j_out, false)),
        (false, false) => {}
    }
    true
}

/// Whether the direction `p` (above the horizon, on no ring) lies in the region bounded by the
/// simple disjoint rings of `region`: the parity of their crossings with the meridian arc from
/// `p` down to the horizon and on to the nadir (the region lies in the closed upper hemisphere,
/// so the nadir is outside it). `None` where a crossing is within rounding of the arc's plane or
/// of `p`.
fn contains(region: &Chain, p: DVec3) -> Option<bool> {
    // The meridian plane's normal, `z x p`: points of the plane are further from the zenith than
    // `p` (on `p`'s side) where `(p x q) . mer > 0`.
    let mer = DVec3::new(-p.y, p.x, 0.0);
    let (pm, mm) = (norm1(p), norm1(mer));
    if mm <= MARGIN * pm {
        return None;
    }
    let mut parity = false;
    for range in region.ranges() {
        let ring = &region.pts[range];
        let mut a = ring[ring.len() - 1];
        let mut sa = mer.dot(a);
        for &b in ring {
            let sb = mer.dot(b);
            if sb.abs() <= MARGIN * mm * norm1(b) {
                return None;
            }
            if (sa < 0.0) != (sb < 0.0) {
                let x = chord_point(a, sa, b, sb);
                let d = p.cross(x).dot(mer);
                if d.abs() <= MARGIN * pm * norm1(x) * mm {
                    return None;
                }
                parity ^= d > 0.0;
            }
            (a, sa) = (b, sb);
        }
    }
    Some(parity)
}

impl<L: AsRef<Body>> ClipVisibility<L> {
    /// The fast path of [`ClipVisibility::visible_region`] (with `blocked`) or of
    /// [`Visibility::unoccluded_region`](super::Visibility::unoccluded_region) (without): the
    /// region as [`Pieces`], whose integrals are those of the spherical path's region up to
    /// rounding. `Ok(true)` when `out` holds the region; `Ok(false)` when this path does not
    /// apply (see [`Pieces`] and the source of `visibility::pieces`) and the caller takes
    /// [`ClipVisibility::visible_region`]. Allocates nothing for lights and blockers of up to
    /// 16 vertices, closed meshes aside (beyond what `out` already holds: see [`Pieces`]).
    ///
    /// # Errors
    ///
    /// [`GeomError::OutOfRange`] for a light index past the end; nothing else (where the
    /// spherical path could give up, this path declines instead).
    pub fn visible_pieces(
        &self,
        light: usize,
        frame: &ShadingFrame,
        blocked: bool,
        out: &mut Pieces,
    ) -> Result<bool, GeomError> {
        let body = self.light_body(light)?;
        out.clear();
        if self.method != Method::Silhouette {
            return Ok(false);
        }
        let (x, n) = (frame.origin(), frame.normal());
        if !above_horizon(x, n, self.light_bounds[light]) {
            return Ok(true);
        }
        if self.contour_light(light, body) {
            // A closed non-planar mesh light: the union of its front faces, from its contour.
            if self.seen_from_inside(light, body, x) {
                return Ok(true);
            }
            if !self.overlay_region(light, frame, true, &[], out) {
                out.clear();
                return Ok(false);
            }
        } else if !self.light_rings(light, body, frame, out) {
            out.clear();
            return Ok(false);
        }
        // No other object (the light alone in the scene): nothing to set up below.
        if !blocked || self.blocker_count() == 1 {
            return Ok(true);
        }
        if !self.subtract_blockers(light, frame, out) {
            out.clear();
            return Ok(false);
        }
        Ok(true)
    }

    /// Subtracts from `out` every blocker of [`ClipVisibility::blockers_between`] (the same
    /// culling, the light's cone computed once); `false` where one is the spherical path's.
    /// Out of line: the unoccluded light's path stays short.
    #[inline(never)]
    fn subtract_blockers(&self, light: usize, frame: &ShadingFrame, out: &mut Pieces) -> bool {
        let (x, n) = (frame.origin(), frame.normal());
        let cone = LightCone::new(x, n, self.light_bounds[light]);
        let (no, nl) = (self.occluders().len(), self.lights().len());
        let blockers = (0..no)
            .map(Blocker::Occluder)
            .chain((0..nl).filter(|&k| k != light).map(Blocker::Light));
        // Closed mesh blockers, removed together by their contours after the others.
        let mut meshes: SmallVec<[Blocker; 4]> = SmallVec::new();
        for b in blockers {
            let (separation, touches) = self.pair(light, b);
            if let Some(sep) = separation
                && !sep.blocker_side(x)
            {
                continue;
            }
            let (body, bound) = self.blocker(b);
            if !cone.may_occlude(bound) {
                continue;
            }
            if out.is_empty() {
                break;
            }
            // Interpenetrating blockers, and blockers with a vertex in the plane of a light
            // triangle (never subtracted whole: the touching part hides nothing), act face by
            // face: the spherical path's business. Closed meshes are removed by their
            // contours after the loop; open meshes large enough for a hierarchy go to the
            // one-pass union, which culls their triangles by shafts. A Bezier-bounded light
            // blocks others by its triangulated flattening, as on the spherical path.
            let fits = separation.is_some()
                && !touches
                && match body {
                    Body::Convex(p) => {
                        let planes = match self.convex_faces(b) {
                            Some(faces) => convex_blocker(p, faces, frame, out),
                            None => convex_planes(p, frame, out),
                        };
                        planes && out.subtract()
                    }
                    Body::Mesh(_) if self.contours(b).is_some() => {
                        meshes.push(b);
                        true
                    }
                    other => {
                        self.bvh(b).is_none()
                            && self.subtract_triangles(light, other.mesh(), frame, out)
                    }
                };
            if !fits {
                return false;
            }
        }
        meshes.is_empty() || self.overlay_region(light, frame, false, &meshes, out)
    }

    /// The light's own region as the first rings of `out`, clipped to the upper hemisphere;
    /// `false` where the fast path does not apply.
    fn light_rings(
        &self,
        light: usize,
        body: &Body,
        frame: &ShadingFrame,
        out: &mut Pieces,
    ) -> bool {
        match body {
            Body::Convex(p) => {
                if !convex_silhouette_dirs(p, frame, out, false) {
                    return false;
                }
                // A convex ring stays one simple ring when the horizon cuts it.
                out.push_dirs_upper();
                out.simple = out.len() == 1;
                true
            }
            Body::Mesh(m) => {
                let Some(outline) = &self.outlines[light] else {
                    return false;
                };
                // Every triangle of a planar mesh lies in one plane, but the facing predicate
                // sees each with its own normal: the region is the outline only if it sees all
                // of them from the front, and nothing if from none. (The facing predicate of
                // `face_side`, with the tolerance computed once.)
                let at = FacingAt::new(m, frame.origin());
                let front = m
                    .normals()
                    .iter()
                    .zip(m.offsets())
                    .filter(|&(nf, &d)| at.front(*nf, d))
                    .count();
                if front == 0 {
                    return true;
                }
                if front != m.triangle_count() {
                    return false;
                }
                // Lengths of the scene's scale would make the edge terms' products overflow or
                // underflow far from 1: scaled by the inverse distance there.
                let d2 = at.rel().length_squared();
                let scale = if (1e-60..=1e60).contains(&d2) {
                    1.0
                } else {
                    1.0 / crate::math::sqrt(d2)
                };
                let mut cut = false;
                for ring in &outline.rings {
                    // Written straight into the region; moved out to be clipped where the
                    // horizon cuts it.
                    let chain = &mut out.bufs[out.cur];
                    let start = chain.pts.len();
                    let mut above = true;
                    for &p in ring {
                        let v = frame.to_local(p);
                        above &= v.z > 0.0;
                        chain.pts.push(v);
                    }
                    if scale != 1.0 {
                        chain.pts[start..].iter_mut().for_each(|v| *v *= scale);
                    }
                    if above {
                        chain.close(start);
                    } else {
                        out.dirs.clear();
                        out.dirs.extend_from_slice(&chain.pts[start..]);
                        chain.pts.truncate(start);
                        cut |= out.push_dirs_upper();
                    }
                }
                // One ring, simple unless a concave one was cut into a chain with bridges.
                out.simple = out.len() == 1 && (outline.convex || !cut);
                true
            }
            // Flattened per point, as its own angular flatness from the point requires: the
            // spherical path's business.
            Body::Bezier(_) => false,
        }
    }

    /// Subtracts from `out` every triangle of the mesh blocker `m` (seen from either side, each
    /// with its three half-spaces), after the per-triangle cull of the spherical path; `false`
    /// where a triangle's projection is turned over by rounding or the rings would exceed
    /// [`MAX_RINGS`]. Out of line, so that its setup stays out of the loop over convex blockers.
    #[inline(never)]
    fn subtract_triangles(
        &self,
        light: usize,
        m: &TriangleMesh,
        frame: &ShadingFrame,
        out: &mut Pieces,
    ) -> bool {
        let (x, n) = (frame.origin(), frame.normal());
        let lb = self.light_bounds[light];
        for t in 0..m.triangle_count() {
            if out.is_empty() {
                break;
            }
            if !may_occlude(x, n, lb, super::clip::triangle_bound(m.triangle(t))) {
                continue;
            }
            let side = face_side(m, t, x);
            if side == Side::On {
                continue;
            }
            let [a, b, c] = m.triangle(t).map(|v| frame.to_local(v));
            // Unit directions: the normals are then at most 1 long whatever the scene's scale.
            let (Some(a), Some(b), Some(c)) =
                (a.try_normalize(), b.try_normalize(), c.try_normalize())
            else {
                continue;
            };
            // Counter-clockwise seen from the point (a front face) is clockwise on the sphere:
            // the region is on the left of the reversed ring.
            let ring = if side == Side::Front {
                [c, b, a]
            } else {
                [a, b, c]
            };
            // A triangle so nearly edge-on that rounding turns its projection over is the
            // spherical path's to decide.
            if !(left_turn(ring[0], ring[1], ring[2]) > 0.0) {
                return false;
            }
            out.planes.clear();
            out.planes
                .extend((0..3).map(|k| unit1(edge_plane(ring[k], ring[(k + 1) % 3]))));
            out.kv.clear();
            out.kv.extend_from_slice(&ring);
            if !out.subtract() {
                return false;
            }
        }
        true
    }
}

/// The silhouette of the convex polyhedron `p` seen from the frame's point as directions in the
/// frame (scaled by one positive factor), in `out.kv` if `to_kv` (a blocker's), else in
/// `out.dirs` (counter-clockwise on the sphere: the silhouette on the left), exactly where
/// [`convex_silhouette`](crate::solid::silhouette::convex_silhouette) returns the loop of the same vertices without its general ordering: front faces by the facing predicate
/// (the same distances and tolerance), contour edges oriented by their front face, chained by
/// vertex index into one loop whose consecutive directions are further apart than
/// [`MATCH_TOLERANCE`] and not antipodal within [`ANTIPODAL_TOLERANCE`]. `false` elsewhere: no
/// face in front (the point inside or on the surface, where that function returns a hemisphere,
/// a lune or the full sphere) or a loop that needs the general ordering.
fn convex_silhouette_dirs(
    p: &ConvexPolyhedron,
    frame: &ShadingFrame,
    out: &mut Pieces,
    to_kv: bool,
) -> bool {
    let mesh = p.mesh();
    let at = FacingAt::new(mesh, frame.origin());
    let normals = mesh.normals();
    let offsets = mesh.offsets();
    out.contour.clear();
    if normals.len() <= 64 && p.vertices().len() <= INLINE_VERTICES {
        let dirs = if to_kv { &mut out.kv } else { &mut out.dirs };
        return small_silhouette_dirs(p, frame, at, dirs);
    }
    if normals.len() <= 64 {
        // Front faces as bits, without a buffer.
        let mut front = 0u64;
        for (f, (nf, &d)) in normals.iter().zip(offsets).enumerate() {
            front |= u64::from(at.front(*nf, d)) << f;
        }
        if front == 0 {
            return false;
        }
        for e in p.edges() {
            let (f0, f1) = ((front >> e.f0) & 1, (front >> e.f1) & 1);
            if f0 != f1 {
                out.contour
                    .push(if f0 == 1 { (e.b, e.a) } else { (e.a, e.b) });
            }
        }
    } else {
        out.front.clear();
        let mut any = false;
        for (nf, &d) in normals.iter().zip(offsets) {
            let f = at.front(*nf, d);
            any |= f;
            out.front.push(f);
        }
        if !any {
            return false;
        }
        for e in p.edges() {
            match (out.front[e.f0 as usize], out.front[e.f1 as usize]) {
                (true, false) => out.contour.push((e.b, e.a)),
                (false, true) => out.contour.push((e.a, e.b)),
                _ => {}
            }
        }
    }
    // Directions scaled by the inverse distance to the polyhedron's center (one division for
    // all), not normalized: the planes, turns and sides below are invariant under positive
    // scaling, and the lengths stay within a few units whatever the scene's scale.
    let dist = at.rel().length();
    if !(dist > 0.0) {
        return false;
    }
    let inv = 1.0 / dist;
    let verts = p.vertices();
    out.dirs.clear();
    if !chain_contour(&out.contour, verts, frame, inv, &mut out.dirs) {
        return false;
    }
    let n = out.dirs.len();
    if n < 3 {
        return false;
    }
    // Consecutive directions further apart than `MATCH_TOLERANCE` and not antipodal within
    // `ANTIPODAL_TOLERANCE`, as unit vectors: clearly so where the sine of the angle between
    // them exceeds twice the larger tolerance and the angle is acute (no root, no division);
    // otherwise decided on the unit vectors `convex_silhouette` uses.
    const TOL2: f64 = 4.0 * MATCH_TOLERANCE * MATCH_TOLERANCE;
    let mut prev = out.dirs[n - 1];
    for k in 0..n {
        let cur = out.dirs[k];
        let clear = prev.dot(cur) > 0.0
            && prev.cross(cur).length_squared()
                > TOL2 * prev.length_squared() * cur.length_squared();
        if !clear && !spaced_units(out, verts, frame, k) {
            return false;
        }
        prev = cur;
    }
    if to_kv {
        out.kv.clear();
        out.kv.extend_from_slice(&out.dirs);
    }
    true
}

/// [`convex_silhouette_dirs`] for the common small polyhedron (at most 64 faces and
/// [`INLINE_VERTICES`] vertices), the same decisions in one pass over the edges and one walk,
/// without a list of contour edges: front faces as bits, each contour edge written straight
/// into the successor table the chaining walks, and the spacing of consecutive directions
/// tested during the walk (a vertex at the point has a zero direction, which no spacing test
/// passes).
fn small_silhouette_dirs(
    p: &ConvexPolyhedron,
    frame: &ShadingFrame,
    at: FacingAt,
    dirs: &mut Ring,
) -> bool {
    const NONE: u32 = u32::MAX;
    let mesh = p.mesh();
    let mut front = 0u64;
    for (f, (nf, &d)) in mesh.normals().iter().zip(mesh.offsets()).enumerate() {
        front |= u64::from(at.front(*nf, d)) << f;
    }
    if front == 0 {
        return false;
    }
    // Contour edges oriented by their front face (the silhouette on their left), chained by
    // vertex index: every vertex used has one outgoing edge, and the walk from the first edge's
    // tail uses all of them (as `chain_by_index` decides it).
    let mut next = [NONE; INLINE_VERTICES];
    let (mut count, mut start) = (0usize, NONE);
    for e in p.edges() {
        let (f0, f1) = ((front >> e.f0) & 1, (front >> e.f1) & 1);
        if f0 != f1 {
            let (a, b) = if f0 == 1 { (e.b, e.a) } else { (e.a, e.b) };
            if next[a as usize] != NONE {
                return false;
            }
            next[a as usize] = b;
            if count == 0 {
                start = a;
            }
            count += 1;
        }
    }
    if count < 3 {
        return false;
    }
    // Scaled by the inverse distance to the polyhedron's center, as in `convex_silhouette_dirs`.
    let dist = at.rel().length();
    if !(dist > 0.0) {
        return false;
    }
    let inv = 1.0 / dist;
    let verts = p.vertices();
    dirs.clear();
    dirs.reserve(count);
    let first = frame.to_local(verts[start as usize]) * inv;
    dirs.push(first);
    let (mut prev, mut prev_id, mut at) = (first, start, next[start as usize]);
    for k in 1..count {
        if at == NONE || at == start {
            return false;
        }
        let cur = frame.to_local(verts[at as usize]) * inv;
        if !spaced(prev, cur, verts, frame, prev_id, at) {
            return false;
        }
        dirs.push(cur);
        (prev, prev_id) = (cur, at);
        at = next[at as usize];
        if k + 1 == count && at != start {
            return false;
        }
    }
    spaced(prev, first, verts, frame, prev_id, start)
}

/// Whether consecutive directions `a` and `b` (of vertices `ia` and `ib`) are further apart than
/// `MATCH_TOLERANCE` and not antipodal within `ANTIPODAL_TOLERANCE`, as unit vectors: clearly so
/// where the sine of the angle between them exceeds twice the larger tolerance and the angle is
/// acute (no root, no division); otherwise decided on the unit vectors `convex_silhouette` uses.
#[inline(always)]
fn spaced(a: DVec3, b: DVec3, verts: &[DVec3], frame: &ShadingFrame, ia: u32, ib: u32) -> bool {
    const TOL2: f64 = 4.0 * MATCH_TOLERANCE * MATCH_TOLERANCE;
    let clear = a.dot(b) > 0.0
        && a.cross(b).length_squared() > TOL2 * a.length_squared() * b.length_squared();
    clear || spaced_ids(verts, frame, ia, ib)
}

/// The spacing test of [`convex_silhouette`](crate::solid::silhouette::convex_silhouette) on
/// the unit vectors of vertices `ia` and `ib`.
#[cold]
fn spaced_ids(verts: &[DVec3], frame: &ShadingFrame, ia: u32, ib: u32) -> bool {
    let unit = |i: u32| frame.to_local(verts[i as usize]).try_normalize();
    let (Some(a), Some(b)) = (unit(ia), unit(ib)) else {
        return false;
    };
    (a - b).length() > MATCH_TOLERANCE && (a + b).length() > ANTIPODAL_TOLERANCE
}

/// The spacing test of [`convex_silhouette`](crate::solid::silhouette::convex_silhouette) on
/// the `k`-th chained vertex and its predecessor, on the unit vectors it uses.
#[cold]
fn spaced_units(out: &Pieces, verts: &[DVec3], frame: &ShadingFrame, k: usize) -> bool {
    let n = out.contour.len();
    // The chain starts at the first contour edge's tail, in the contour's own order.
    let mut at = out.contour[0].0;
    let mut ids = [0u32; 2];
    let kp = if k == 0 { n - 1 } else { k - 1 };
    for step in 0..n {
        if step == kp {
            ids[0] = at;
        }
        if step == k {
            ids[1] = at;
        }
        match out.contour.iter().find(|e| e.0 == at) {
            Some(e) => at = e.1,
            None => return false,
        }
    }
    let unit = |i: u32| frame.to_local(verts[i as usize]).try_normalize();
    let (Some(a), Some(b)) = (unit(ids[0]), unit(ids[1])) else {
        return false;
    };
    (a - b).length() > MATCH_TOLERANCE && (a + b).length() > ANTIPODAL_TOLERANCE
}

/// The contour edges chained by vertex index into one loop (as
/// [`chain_by_index`](crate::solid::silhouette::chain_by_index) decides it: every vertex used
/// has one outgoing edge and the walk from the first edge uses all of them), with the
/// directions of its vertices in the frame, scaled by `scale`, pushed to `dirs` in order;
/// `false` where it is not one such loop or a vertex is at the point.
fn chain_contour(
    contour: &[(u32, u32)],
    verts: &[DVec3],
    frame: &ShadingFrame,
    scale: f64,
    dirs: &mut Ring,
) -> bool {
    const NONE: u32 = u32::MAX;
    if contour.len() < 3 {
        return false;
    }
    let n = contour.len();
    dirs.reserve(n);
    if verts.len() > INLINE_VERTICES {
        let Some(ring) = chain_by_index(contour, verts.len()) else {
            return false;
        };
        for &i in &ring {
            dirs.push(frame.to_local(verts[i as usize]) * scale);
        }
    } else {
        let mut next = [NONE; INLINE_VERTICES];
        for &(a, b) in contour {
            if next[a as usize] != NONE {
                return false;
            }
            next[a as usize] = b;
        }
        let start = contour[0].0;
        let mut at = start;
        for k in 0..n {
            dirs.push(frame.to_local(verts[at as usize]) * scale);
            at = next[at as usize];
            if at == NONE || (at == start) != (k + 1 == n) {
                return false;
            }
        }
    }
    // A vertex at the point has no direction.
    dirs.iter().all(|v| v.length_squared() > 0.0)
}

/// A small convex polyhedron's faces and edges as the fast path's silhouette walks them
/// ([`convex_blocker`]), built once per scene: its triangles grouped by plane, and the edges
/// between triangles of different planes.
///
/// Triangles with the same normal and offset (equal as numbers; a zero's sign cannot change a
/// facing test, whose tolerance is positive) get the same answer from the facing predicate, so
/// one test serves them all, and the edges between them (the diagonals of a box's faces) are
/// never on a contour. The edges kept are in the polyhedron's order, so the contour is chained
/// from the same first edge as by [`small_silhouette_dirs`].
#[derive(Debug, Clone, PartialEq)]
pub(super) struct ConvexFaces {
    /// Per plane: the triangles' unit normal and offset from the bounding sphere's center.
    normals: Vec<DVec3>,
    offsets: Vec<f64>,
    /// `[a, b, g0, g1]`: the edge from vertex `a` to `b`, counter-clockwise around the triangle
    /// of plane `g0`, and `b -> a` in the triangle of plane `g1`; and the bits of its two planes.
    edges: Vec<[u8; 4]>,
    masks: Vec<u64>,
    /// For at most [`CONTOUR_TABLE_PLANES`] planes, the contour for every set of front planes
    /// (bit `g` for plane `g`), as [`contour_loop`] chains it from `edges`: `loops[m]` is the
    /// range of `vertices` holding the loop's vertex indices in order, empty where it declines.
    loops: Vec<(u16, u8)>,
    vertices: Vec<u8>,
    /// Without a table of contours and with at most 64 edges: per plane `g`, the edges (bit `e`
    /// for `edges[e]`) whose plane `g0` is `g`, and those whose plane `g1` is `g`. An edge is on
    /// the contour exactly where one of its two planes is in front, so the contour's edges are
    /// the bits where the union of the front planes' first sets and that of their second sets
    /// differ ([`contour_by_bits`]): a few operations per front plane instead of a pass over
    /// every edge.
    plane_edges: Vec<[u64; 2]>,
    /// For a simple polyhedron (every vertex on exactly three edges between different planes,
    /// as a box's or a prism's), the shortest such edge and the smallest `|e x f|` of two of
    /// them at one vertex: the bounds with which [`walk_is_certified`] answers the silhouette
    /// walk's spacing and turn tests for a whole blocker at once.
    simple: Option<(f64, f64)>,
    /// With bit sets of edges and at most [`CELL_TABLE_PLANES`] planes: the contours of the sets
    /// of front planes that points see, found once ([`cell_masks`]). A set not in the table is
    /// chained per point as before. Shared by the bodies of one scene that have the same planes
    /// and edges by index ([`CellTables`]).
    cells: Option<Arc<CellTable>>,
}

/// The contours of sets of front planes of a convex body ([`ConvexFaces::cells`]): `cells`
/// sorted, and for `cells[i]` the loop [`contour_by_bits`] chains, `vertices[a..a + n]` for
/// `loops[i] = (a, n)` (`n = 0` where it declines).
///
/// The loop of a set depends only on which edges join which vertices between which planes (the
/// bit sets and `edges` of [`ConvexFaces`]), not on where they lie, so bodies that agree in
/// those (copies of one primitive, moved or scaled) can share one table; which sets the table
/// holds does depend on the geometry, but a set it lacks is only chained per point.
#[derive(Debug, PartialEq)]
pub(super) struct CellTable {
    cells: Vec<u64>,
    loops: Vec<(u32, u8)>,
    vertices: Vec<u8>,
}

/// The tables of cells built so far for one scene, by plane count and edges
/// ([`ConvexFaces::of_sharing`]; `None` where the body has more sets than [`CELL_TABLE_SETS`]):
/// a scene of copies of one body with the same numbering builds and stores its table once.
pub(super) type CellTables = BTreeMap<(usize, Vec<[u8; 4]>), Option<Arc<CellTable>>>;

/// Most tables of cells one scene builds: an icosahedron's takes about 2.3 million instructions
/// (a millisecond) and 38 KB, at most [`CELL_TABLE_SETS`] sets about 90 KB, so a scene of
/// thousands of such bodies would spend seconds and hundreds of megabytes on them. The bodies
/// beyond these chain their contours per point, as bodies without a table do.
const CELL_TABLE_BUDGET: usize = 64;

/// Polyhedra with at most this many distinct face planes (and more than
/// [`CONTOUR_TABLE_PLANES`]) get a table of the contours of the sets of front planes that
/// points can see ([`cell_masks`]): an icosahedron (20 planes) has 1 774, about 38 KB.
const CELL_TABLE_PLANES: usize = 24;

/// Most sets a table of cells holds (about 90 KB); a polyhedron with more keeps chaining its
/// contour per point.
const CELL_TABLE_SETS: usize = 4096;

/// Polyhedra with at most this many distinct face planes (a box has six; a polyhedron with eight
/// has at most twelve vertices) get a table of their contours, one per set of front planes.
const CONTOUR_TABLE_PLANES: usize = 8;

impl ConvexFaces {
    /// The table of `p`; `None` beyond 64 triangles or [`INLINE_VERTICES`] vertices (the
    /// general walk of [`convex_silhouette_dirs`] takes those).
    #[cfg(test)]
    pub(super) fn of(p: &ConvexPolyhedron) -> Option<ConvexFaces> {
        Self::of_sharing(p, &mut CellTables::new())
    }

    /// [`ConvexFaces::of`], taking its table of cells from `tables` where a body with the same
    /// planes and edges by index built one, and adding the one it builds.
    pub(super) fn of_sharing(p: &ConvexPolyhedron, tables: &mut CellTables) -> Option<ConvexFaces> {
        let mesh = p.mesh();
        if mesh.normals().len() > 64 || p.vertices().len() > INLINE_VERTICES {
            return None;
        }
        let (mut normals, mut offsets) = (Vec::new(), Vec::<f64>::new());
        let mut plane_of = Vec::with_capacity(mesh.normals().len());
        for (&n, &d) in mesh.normals().iter().zip(mesh.offsets()) {
            let g = match normals
                .iter()
                .zip(&offsets)
                .position(|(&m, &e)| m == n && e == d)
            {
                Some(g) => g,
                None => {
                    normals.push(n);
                    offsets.push(d);
                    normals.len() - 1
                }
            };
            plane_of.push(g as u8);
        }
        let edges = p
            .edges()
            .iter()
            .map(|e| {
                [
                    e.a as u8,
                    e.b as u8,
                    plane_of[e.f0 as usize],
                    plane_of[e.f1 as usize],
                ]
            })
            .filter(|e| e[2] != e[3])
            .collect::<Vec<_>>();
        let masks = edges
            .iter()
            .map(|e| (1u64 << e[2]) | (1u64 << e[3]))
            .collect::<Vec<_>>();
        let (mut loops, mut vertices) = (Vec::new(), Vec::new());
        if normals.len() <= CONTOUR_TABLE_PLANES {
            let mut order = [0u8; INLINE_VERTICES];
            for front in 0..1u64 << normals.len() {
                let n = contour_loop(front, &edges, &masks, &mut order).unwrap_or(0);
                loops.push((vertices.len() as u16, n as u8));
                vertices.extend_from_slice(&order[..n]);
            }
        }
        let mut plane_edges = Vec::new();
        if loops.is_empty() && edges.len() <= 64 {
            plane_edges.resize(normals.len(), [0u64; 2]);
            for (e, &[_, _, g0, g1]) in edges.iter().enumerate() {
                plane_edges[g0 as usize][0] |= 1u64 << e;
                plane_edges[g1 as usize][1] |= 1u64 << e;
            }
        }
        let simple = simple_bounds(p.vertices(), &edges);
        let mut faces = ConvexFaces {
            normals,
            offsets,
            edges,
            masks,
            loops,
            vertices,
            plane_edges,
            simple,
            cells: None,
        };
        if !faces.plane_edges.is_empty() && faces.normals.len() <= CELL_TABLE_PLANES {
            let key = (faces.normals.len(), faces.edges.clone());
            if let Some(table) = tables.get(&key) {
                faces.cells = table.clone();
                return Some(faces);
            }
            if tables.len() >= CELL_TABLE_BUDGET {
                return Some(faces);
            }
            let cells = cell_masks(
                &faces.normals,
                &faces.offsets,
                p.mesh().bounding_sphere().radius,
            );
            let cells = if cells.len() <= CELL_TABLE_SETS {
                cells
            } else {
                Vec::new()
            };
            let mut order = [0u8; INLINE_VERTICES];
            let (mut loops, mut verts) = (Vec::with_capacity(cells.len()), Vec::new());
            for &front in &cells {
                let n = contour_by_bits(front, &faces, &mut order).unwrap_or(0);
                loops.push((verts.len() as u32, n as u8));
                verts.extend_from_slice(&order[..n]);
            }
            faces.cells = (!cells.is_empty()).then(|| {
                Arc::new(CellTable {
                    cells,
                    loops,
                    vertices: verts,
                })
            });
            tables.insert(key, faces.cells.clone());
        }
        Some(faces)
    }

    /// The contour for the front planes `front` from the table of cells, if it holds that set:
    /// `Some(None)` where [`contour_by_bits`] declines.
    #[inline(always)]
    fn cell_contour(&self, front: u64) -> Option<Option<&[u8]>> {
        let table = self.cells.as_deref()?;
        let i = table.cells.binary_search(&front).ok()?;
        let (a, n) = table.loops[i];
        Some((n > 0).then(|| &table.vertices[a as usize..a as usize + n as usize]))
    }
}

/// The sets of front planes (bit `g` for plane `g`, given by unit `normals` and `offsets` from
/// the bounding sphere's center, radius `r`) of the cells of the planes' arrangement, sorted,
/// without the empty set: every cell of an arrangement whose normals span space has a vertex,
/// where three planes meet, so the sets are found at those points, with every combination of
/// sides for the planes through the point (within a rounding margin), each point once (from
/// its first spanning triple in index order). Sets that no point sees may be among them (they
/// cost a table entry), and sets may be missing where the rounding hides them or more than six
/// planes meet at a point (left out: 128 combinations and more); a point that sees a missing
/// set chains its contour itself, so the table only saves work.
fn cell_masks(normals: &[DVec3], offsets: &[f64], r: f64) -> Vec<u64> {
    let mut out: Vec<u64> = Vec::new();
    let n = normals.len();
    let margin = 1e-9 * r.max(f64::MIN_POSITIVE);
    let mut through: SmallVec<[usize; 16]> = SmallVec::new();
    for i in 0..n {
        for j in i + 1..n {
            for k in j + 1..n {
                let (a, b, c) = (normals[i], normals[j], normals[k]);
                let (bc, ca, ab) = (b.cross(c), c.cross(a), a.cross(b));
                let det = a.dot(bc);
                if !(det.abs() > 1e-6) {
                    continue;
                }
                let p = (bc * offsets[i] + ca * offsets[j] + ab * offsets[k]) / det;
                let mut base = 0u64;
                through.clear();
                for g in 0..n {
                    let s = normals[g].dot(p) - offsets[g];
                    if s.abs() <= margin || g == i || g == j || g == k {
                        through.push(g);
                    } else if s > 0.0 {
                        base |= 1u64 << g;
                    }
                }
                // Each point once: from the first of its triples (in index order) whose
                // normals span space; points where more than six planes meet are left out.
                if through.len() > 6 {
                    continue;
                }
                let spans = |x: usize, y: usize, z: usize| {
                    normals[x].dot(normals[y].cross(normals[z])).abs() > 1e-6
                };
                let t = &through[..];
                let mut first = true;
                'find: for (ia, &x) in t.iter().enumerate() {
                    for (ib, &y) in t.iter().enumerate().skip(ia + 1) {
                        for &z in &t[ib + 1..] {
                            if (x, y, z) < (i, j, k) && spans(x, y, z) {
                                first = false;
                                break 'find;
                            }
                        }
                    }
                }
                if !first {
                    continue;
                }
                for combo in 0..1u64 << through.len() {
                    let mut m = base;
                    for (t, &g) in through.iter().enumerate() {
                        m |= ((combo >> t) & 1) << g;
                    }
                    if m != 0 {
                        out.push(m);
                    }
                }
            }
        }
    }
    out.sort_unstable();
    out.dedup();
    out
}

/// [`ConvexFaces::simple`] of a polyhedron with vertices `verts` and the edges `edges` between
/// different planes: `None` unless every vertex that has such an edge has exactly three (and the
/// bounds are positive).
fn simple_bounds(verts: &[DVec3], edges: &[[u8; 4]]) -> Option<(f64, f64)> {
    let mut at: Vec<Vec<DVec3>> = alloc::vec![Vec::new(); verts.len()];
    let mut shortest = f64::INFINITY;
    for &[a, b, _, _] in edges {
        let e = verts[b as usize] - verts[a as usize];
        shortest = shortest.min(e.length());
        at[a as usize].push(e);
        at[b as usize].push(-e);
    }
    let mut wedge = f64::INFINITY;
    for es in at.iter().filter(|es| !es.is_empty()) {
        if es.len() != 3 {
            return None;
        }
        for (i, j) in [(0, 1), (0, 2), (1, 2)] {
            wedge = wedge.min(es[i].cross(es[j]).length());
        }
    }
    (shortest > 0.0 && wedge > 0.0 && shortest.is_finite()).then_some((shortest, wedge))
}

/// Whether every spacing and turn test of the silhouette walk ([`convex_blocker`]) is known to
/// pass for a simple polyhedron ([`ConvexFaces::simple`]: shortest edge `edge`, smallest wedge
/// `wedge`) seen from a point at distance `dist` from its bounding sphere's center (radius `r`)
/// whose distances from every face plane are at least `near` in magnitude.
///
/// With every `|distance|` that far above the facing tolerance (`FACE_TOLERANCE (r + dist)`,
/// `1e-11` of it) and the distances' rounding, the contour is the exact one, so the silhouette
/// is a convex polygon run counter-clockwise, with `s = dist + r` bounding every vertex's
/// distance from the point:
///
/// - an edge `a b` of the contour lies in a front face, so the point is at least `near` from its
///   line and the sine of the angle the edge subtends is at least `near edge / s^2`: above
///   `1e-7` it is far from 0 and from `pi` (the spacing tests need `2e-9`), so both the quick
///   accept and the test on unit vectors that decides where it does not would accept;
/// - at a simple polyhedron's vertex `b` any two edges span a face, so consecutive contour
///   vertices `a b c` lie in one face plane and `det(a - x, b - x, c - x)` is the point's
///   distance from it times `|(b - a) x (c - b)|`, at least `near wedge`, positive for a convex
///   polygon run counter-clockwise; above `1e-7 s^3` it exceeds the determinant's change under
///   the rounding of the directions (a few `eps s^3`, scaled alike), so the computed turn is
///   positive and [`turns_left`] accepts.
///
/// So the walk's decisions are all "accept" where this holds, and it need not make them.
#[inline(always)]
fn walk_is_certified((edge, wedge): (f64, f64), dist: f64, r: f64, near: f64) -> bool {
    const REL: f64 = 1e-7;
    let s = dist + r;
    near * edge > REL * s * s && near * wedge > REL * s * s * s
}

/// [`convex_planes`] for a polyhedron with a [`ConvexFaces`] table: the same silhouette
/// (vertices, in the same order and bit for bit) and the same half-spaces, and the same
/// decisions, in one walk. Front planes as bits; each contour edge written into the successor
/// table the chaining walks; each vertex's direction, the plane of the edge that reaches it,
/// the turn at the vertex before, and the spacing test, computed as the walk reaches it.
///
/// The spacing test's quick accept is taken from the edge's plane normal `p = (a + b) x (b - a)
/// = 2 a x b` (see [`spaced_by_plane`]), which the plane needs anyway; where it does not accept,
/// the test on unit vectors decides, as before.
fn convex_blocker(
    p: &ConvexPolyhedron,
    faces: &ConvexFaces,
    frame: &ShadingFrame,
    out: &mut Pieces,
) -> bool {
    let at = FacingAt::new(p.mesh(), frame.origin());
    let dist = at.dist();
    let mut front = 0u64;
    // For a simple polyhedron, also the distance to the nearest face plane, which may answer
    // every spacing and turn test below at once ([`walk_is_certified`]).
    let certified = match faces.simple {
        Some(bounds) => {
            let (mut near, tol) = (f64::INFINITY, at.tol());
            for (g, (nf, &d)) in faces.normals.iter().zip(&faces.offsets).enumerate() {
                let s = at.distance(*nf, d);
                front |= u64::from(in_front(s, tol)) << g;
                // A plain comparison rather than `f64::min` (whose NaN rule costs more): a NaN
                // distance leaves `near` as it was, and makes no plane front.
                let a = s.abs();
                near = if a < near { a } else { near };
            }
            walk_is_certified(bounds, dist, p.mesh().bounding_sphere().radius, near)
        }
        None => {
            for (g, (nf, &d)) in faces.normals.iter().zip(&faces.offsets).enumerate() {
                front |= u64::from(at.front(*nf, d)) << g;
            }
            false
        }
    };
    if front == 0 {
        return false;
    }
    let mut order = [0u8; INLINE_VERTICES];
    let order: &[u8] = if !faces.plane_edges.is_empty() {
        match faces.cell_contour(front) {
            Some(Some(loop_)) => loop_,
            Some(None) => return false,
            None => match contour_by_bits(front, faces, &mut order) {
                Some(count) => &order[..count],
                None => return false,
            },
        }
    } else if faces.loops.is_empty() {
        match contour_loop(front, &faces.edges, &faces.masks, &mut order) {
            Some(count) => &order[..count],
            None => return false,
        }
    } else {
        let (at, count) = faces.loops[front as usize];
        &faces.vertices[at as usize..at as usize + count as usize]
    };
    let count = order.len();
    if count < 3 || !(dist > 0.0) {
        return false;
    }
    // Directions scaled by the inverse distance to the polyhedron's center, as in
    // `convex_silhouette_dirs`.
    let inv = 1.0 / dist;
    let verts = p.vertices();
    #[cfg(test)]
    {
        out.certified += u64::from(certified);
    }
    let Pieces { kv, planes, .. } = out;
    // Sized once and written through slices: a push per vertex and per plane checks the
    // capacity and the inline storage each time. Sized from the previous blocker's length:
    // shortened in place, or lengthened by the difference (a few pushes, cheaper than
    // `resize`'s call); every element is overwritten below.
    while kv.len() < count {
        kv.push(DVec3::ZERO);
    }
    kv.truncate(count);
    while planes.len() < count {
        planes.push(DVec3::ZERO);
    }
    planes.truncate(count);
    let (kv, planes): (&mut [DVec3], &mut [DVec3]) = (kv, planes);
    for (d, &i) in kv.iter_mut().zip(order) {
        *d = frame.to_local(verts[i as usize]) * inv;
    }
    // Planes, turns and spacing, edge by edge: `convex_planes`' loop, with the spacing test of
    // `small_silhouette_dirs` (on the same pairs of directions, the same decisions). The turn
    // at the end of each edge is taken from the edge's plane first ([`turns_left_by_plane`]),
    // `convex_planes`' test deciding where that does not accept.
    let kv: &[DVec3] = kv;
    if certified {
        // The same planes, bit for bit, without the tests.
        let plane = |cur: DVec3, next: DVec3| {
            let n = (cur + next).cross(next - cur);
            n / norm1(n)
        };
        for (p, w) in planes.iter_mut().zip(kv.windows(2)) {
            *p = plane(w[0], w[1]);
        }
        planes[count - 1] = plane(kv[count - 1], kv[0]);
        return true;
    }
    let (mut cur, mut next) = (kv[0], kv[1]);
    let (mut cur1, mut next1) = (norm1(cur), norm1(next));
    for k in 0..count {
        let k1 = if k + 1 == count { 0 } else { k + 1 };
        let k2 = if k1 + 1 == count { 0 } else { k1 + 1 };
        let after = kv[k2];
        let after1 = norm1(after);
        let d_out = next - cur;
        // `edge_plane(cur, next)` bit for bit (see `convex_planes`).
        let n = (cur + next).cross(d_out);
        let n1 = norm1(n);
        if !spaced_by_plane(cur, next, cur1, next1, n1)
            && !spaced_ids(verts, frame, order[k].into(), order[k1].into())
        {
            return false;
        }
        if !turns_left_by_plane(n, cur1 + next1, after, after1)
            && !turns_left(d_out, after - next, next)
        {
            return false;
        }
        planes[k] = n / n1;
        (cur, cur1, next, next1) = (next, next1, after, after1);
    }
    true
}

/// The contour for the front planes `front` (bit `g` for plane `g`) as [`small_silhouette_dirs`]
/// chains it: the edges between a front and a back plane, oriented by their front face, chained
/// by vertex index from the first one's tail into one loop in which every vertex has one
/// outgoing edge; its vertex indices in order into `order`, and their number. `None` where they
/// do not form one such loop of at least three edges.
fn contour_loop(
    front: u64,
    edges: &[[u8; 4]],
    masks: &[u64],
    order: &mut [u8; INLINE_VERTICES],
) -> Option<usize> {
    const NONE: u8 = u8::MAX;
    let mut next = [NONE; INLINE_VERTICES];
    let (mut count, mut start) = (0usize, NONE);
    for (&[a, b, g0, _], &m) in edges.iter().zip(masks) {
        // One of the edge's planes in front and the other not.
        let f = front & m;
        if f != 0 && f != m {
            let (a, b) = if (front >> g0) & 1 == 1 {
                (b, a)
            } else {
                (a, b)
            };
            if next[a as usize] != NONE {
                return None;
            }
            next[a as usize] = b;
            if count == 0 {
                start = a;
            }
            count += 1;
        }
    }
    if count < 3 {
        return None;
    }
    follow_loop(&next, start, count, order)
}

/// Writes into `order` the loop of `count` vertices that the successor table `next` (`u8::MAX`
/// where a vertex has none) makes from `start`; `None` where the walk breaks off or closes
/// before `count` vertices (the contour is not one loop).
fn follow_loop(
    next: &[u8; INLINE_VERTICES],
    start: u8,
    count: usize,
    order: &mut [u8; INLINE_VERTICES],
) -> Option<usize> {
    order[0] = start;
    let mut at = next[start as usize];
    for slot in order.iter_mut().take(count).skip(1) {
        if at == u8::MAX || at == start {
            return None;
        }
        *slot = at;
        at = next[at as usize];
    }
    (at == start).then_some(count)
}

/// [`contour_loop`] from a table's per-plane edge sets ([`ConvexFaces::plane_edges`]): the same
/// contour edges, oriented alike (`b -> a` where the edge's plane `g0` is in front) and met in the
/// same order (increasing edge index), so the same loop from the same first vertex, or `None`
/// exactly where that declines.
fn contour_by_bits(
    front: u64,
    faces: &ConvexFaces,
    order: &mut [u8; INLINE_VERTICES],
) -> Option<usize> {
    const NONE: u8 = u8::MAX;
    let (mut first, mut second) = (0u64, 0u64);
    let mut f = front;
    while f != 0 {
        let [e0, e1] = faces.plane_edges[f.trailing_zeros() as usize];
        first |= e0;
        second |= e1;
        f &= f - 1;
    }
    // An edge's two planes differ, so it is on the contour where exactly one is in front.
    let mut contour = first ^ second;
    let count = contour.count_ones() as usize;
    if count < 3 {
        return None;
    }
    let mut next = [NONE; INLINE_VERTICES];
    let mut start = NONE;
    while contour != 0 {
        let e = contour.trailing_zeros();
        let [a, b, _, _] = faces.edges[e as usize];
        let (a, b) = if (first >> e) & 1 == 1 {
            (b, a)
        } else {
            (a, b)
        };
        if next[a as usize] != NONE {
            return None;
        }
        next[a as usize] = b;
        if start == NONE {
            start = a;
        }
        contour &= contour - 1;
    }
    follow_loop(&next, start, count, order)
}

/// The silhouette's turn at `cur` from the edge with difference `d_in` to the one with `d_out`
/// is to the left or straight within its rounding bound (see [`convex_planes`]): `left_turn`'s
/// operations.
#[inline(always)]
fn turns_left(d_in: DVec3, d_out: DVec3, cur: DVec3) -> bool {
    let turn = d_in.cross(d_out).dot(cur);
    turn > 0.0 || turn > -MARGIN * norm1(d_in) * norm1(d_out) * norm1(cur)
}

/// A quick accept of [`turns_left`] at the end `b` of the silhouette edge `a -> b`, from the
/// edge's computed plane normal `n = (a + b) x (b - a)` (`s = |a|_1 + |b|_1`) and the next
/// vertex `c` (`c1 = |c|_1`): where it holds, `det(a, b, c) > 0` exactly, so the turn is to the
/// left and [`turns_left`], whose bound covers its own rounding, accepts it too (the same
/// decision, one dot product instead of a cross product and a dot product).
///
/// Exactly `(a + b) x (b - a) = 2 a x b`, so `N . c = 2 det(a, b, c)` for the exact normal `N`.
/// The computed `n` is off from `N` by at most `8 eps s^2` in 1-norm ([`spaced_by_plane`]), which
/// moves `n . c` by at most `8 eps s^2 c1`; the dot product's own rounding is at most
/// `3 eps |n|_1 c1 (1 + eps)`, with `|n|_1 <= s^2 (1 + 8 eps)` (each product of a cross product's
/// 1-norm pairs components of different indices once). Both together are below `12 eps s^2 c1`,
/// well inside [`MARGIN`] (`64 eps`) times the same product.
#[inline(always)]
fn turns_left_by_plane(n: DVec3, s: f64, c: DVec3, c1: f64) -> bool {
    n.dot(c) > MARGIN * s * s * c1
}

/// A quick accept of the spacing test of [`spaced_ids`] for consecutive silhouette directions
/// `a` and `b` (1-norms `a1`, `b1`), from the 1-norm `n1` of the computed `(a + b) x (b - a)`:
/// where it holds the unit vectors are further apart than `MATCH_TOLERANCE` and not antipodal.
///
/// Exactly `|(a + b) x (b - a)| = 2 |a| |b| sin(theta)`, and `|n|_1 <= sqrt(3) |n|`, `|a| <=
/// |a|_1`, so `sin(theta) >= |n|_1 / (2 sqrt(3) a1 b1)`; the computed normal is off by at most
/// `8 eps (a1 + b1)^2` in 1-norm (the rounding of the sum, the difference, the products and the
/// subtractions). So `n1 > 8 sqrt(3) TOL a1 b1 + 16 eps (a1 + b1)^2` gives `sin(theta) > 4 TOL`
/// less rounding, more than twice `MATCH_TOLERANCE`: the unit vectors (equal to these directions'
/// up to a few ulps of angle) are more than `MATCH_TOLERANCE` apart, and with `a . b > 0` the
/// angle is acute, far from antipodal.
#[inline(always)]
fn spaced_by_plane(a: DVec3, b: DVec3, a1: f64, b1: f64, n1: f64) -> bool {
    const REL: f64 = 8.0 * 1.732_050_807_568_877_3 * MATCH_TOLERANCE;
    const ABS: f64 = 16.0 * f64::EPSILON;
    let s = a1 + b1;
    a.dot(b) > 0.0 && n1 > REL * a1 * b1 + ABS * s * s
}

/// The half-spaces of the convex blocker `p`'s silhouette into `out.planes`, one per contour
/// edge (the silhouette is their intersection), and its vertices into `out.kv`; `false` where
/// [`convex_silhouette_dirs`] declines or the silhouette turns right somewhere.
fn convex_planes(p: &ConvexPolyhedron, frame: &ShadingFrame, out: &mut Pieces) -> bool {
    if !convex_silhouette_dirs(p, frame, out, true) {
        return false;
    }
    let Pieces { kv, planes, .. } = out;
    let kv: &[DVec3] = kv;
    let n = kv.len();
    planes.clear();
    planes.reserve(n);
    // The intersection of the half-spaces is the silhouette only where it is convex: at a
    // reflex vertex (a face seen within the facing tolerance of edge-on is left out of the
    // silhouette, which then turns back by the angle that face's sliver would have filled) the
    // planes would cut a wedge out of the silhouette along the extended edge, of about the
    // reflex angle times the silhouette's size squared. Every turn must be to the left or
    // straight within its rounding bound (a face exactly edge-on lines up its corners): a
    // reflex angle of a few ulps hides a wedge of a few ulps.
    // Each edge's difference serves both turns at its ends, and its plane.
    let mut cur = kv[0];
    let mut d_in = cur - kv[n - 1];
    for k in 0..n {
        let next = kv[if k + 1 == n { 0 } else { k + 1 }];
        let d_out = next - cur;
        // `left_turn(prev, cur, next)`, the same operations.
        let turn = d_in.cross(d_out).dot(cur);
        if !(turn > 0.0 || turn > -MARGIN * norm1(d_in) * norm1(d_out) * norm1(cur)) {
            return false;
        }
        // `edge_plane(cur, next)`, bit for bit: `cur - next` is `-d_out` exactly, and negating a
        // cross product's factor negates its products exactly.
        planes.push(unit1((cur + next).cross(d_out)));
        (cur, d_in) = (next, d_out);
    }
    true
}

/// The normal of the great circle through the unit directions `a` and `b`, pointing to the left
/// of `a -> b`: `(a - b) x (a + b) = 2 a x b`, which keeps its relative precision when `a` and `b`
/// are close (the difference is exact there), so that the circle passes within rounding of both
/// however short the edge.
#[inline]
fn edge_plane(a: DVec3, b: DVec3) -> DVec3 {
    (a - b).cross(a + b)
}

/// `det(a, b, c)` for unit directions, evaluated as `((b - a) x (c - b)) . b` so that it keeps
/// its relative precision for close points: positive when `a -> b -> c` turns left (seen from
/// outside the sphere).
#[inline]
fn left_turn(a: DVec3, b: DVec3, c: DVec3) -> f64 {
    (b - a).cross(c - b).dot(b)
}

#[cfg(test)]
mod tests {
    //! The fast path's shortcuts against the code they shortcut, bit for bit: the silhouette
    //! walk over a [`ConvexFaces`] table against [`convex_planes`], and the traversal of two
    //! crossings against the general one.

    use alloc::sync::Arc;
    use alloc::vec;
    use alloc::vec::Vec;

    use glam::DVec3;

    use super::{
        CELL_TABLE_BUDGET, CELL_TABLE_PLANES, CellTable, CellTables, ConvexFaces, INLINE_VERTICES,
        Pieces, contour_by_bits, contour_loop, convex_blocker, convex_planes,
    };
    use crate::solid::{Body, ConvexPolyhedron, ShadingFrame, TriangleMesh};
    use crate::visibility::ClipVisibility;

    /// A light for [`ClipVisibility`]: a body alone.
    struct Lit(Body);

    impl AsRef<Body> for Lit {
        fn as_ref(&self) -> &Body {
            &self.0
        }
    }

    /// A small deterministic generator (SplitMix64).
    struct Rng(u64);

    impl Rng {
        fn next(&mut self) -> f64 {
            self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
            let mut z = self.0;
            z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
            ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
        }

        fn range(&mut self, a: f64, b: f64) -> f64 {
            a + (b - a) * self.next()
        }

        fn vec(&mut self, a: f64, b: f64) -> DVec3 {
            DVec3::new(self.range(a, b), self.range(a, b), self.range(a, b))
        }
    }

    /// Boxes (axis-aligned, whose coplanar triangles share a plane bit for bit, and turned),
    /// icospheres (20 and 80 faces), wedges and random hulls.
    fn polyhedra(rng: &mut Rng) -> Vec<ConvexPolyhedron> {
        let mut out = Vec::new();
        for _ in 0..6 {
            let c = rng.vec(-1.0, 1.0);
            out.push(ConvexPolyhedron::cuboid(c, rng.vec(0.05, 0.6)).unwrap());
            let (u, v) = rng.vec(-1.0, 1.0).normalize().any_orthonormal_pair();
            let w = u.cross(v);
            let h = rng.vec(0.05, 0.6);
            let corners: Vec<DVec3> = (0..8)
                .map(|k| {
                    let s = |b: usize| if k >> b & 1 == 1 { 1.0 } else { -1.0 };
                    c + u * (s(0) * h.x) + v * (s(1) * h.y) + w * (s(2) * h.z)
                })
                .collect();
            out.push(ConvexPolyhedron::hull(&corners).unwrap());
            let wedge = [
                c,
                c + DVec3::X * 0.5,
                c + DVec3::Y * 0.4,
                c + DVec3::Z * 0.3,
                c + DVec3::new(0.5, 0.0, 0.3),
                c + DVec3::new(0.0, 0.4, 0.3),
            ];
            out.push(ConvexPolyhedron::hull(&wedge).unwrap());
            out.push(ConvexPolyhedron::icosphere(c, rng.range(0.1, 0.5), 0).unwrap());
            out.push(ConvexPolyhedron::icosphere(c, rng.range(0.1, 0.5), 1).unwrap());
            let pts: Vec<DVec3> = (0..10).map(|_| c + rng.vec(-0.5, 0.5)).collect();
            if let Ok(p) = ConvexPolyhedron::hull(&pts) {
                out.push(p);
            }
        }
        out
    }

    /// The table walk ([`convex_blocker`]) and the general walk ([`convex_planes`]) at one
    /// frame: the same decision and, where both accept, the same directions and planes bit for
    /// bit. Returns whether they accepted, and whether the table walk's tests were certified
    /// ([`super::walk_is_certified`]).
    fn walks_agree(
        p: &ConvexPolyhedron,
        faces: &ConvexFaces,
        frame: &ShadingFrame,
    ) -> (bool, bool) {
        let (mut a, mut b) = (Pieces::new(), Pieces::new());
        // A reused scratch holds the previous blocker's vertices and planes, fewer or more
        // (here NaN, 0 to 39 of them): the walk must size them and overwrite every one.
        let x = frame.origin();
        let stale = (x.x.to_bits() % 40) as usize;
        a.kv.extend(core::iter::repeat_n(DVec3::NAN, stale));
        a.planes.extend(core::iter::repeat_n(DVec3::NAN, stale));
        let fast = convex_blocker(p, faces, frame, &mut a);
        let general = convex_planes(p, frame, &mut b);
        assert_eq!(fast, general, "{x}");
        if fast {
            let bits = |v: &[DVec3]| -> Vec<u64> {
                v.iter()
                    .flat_map(|d| d.to_array().map(f64::to_bits))
                    .collect()
            };
            assert_eq!(bits(&a.kv), bits(&b.kv), "{x}");
            assert_eq!(bits(&a.planes), bits(&b.planes), "{x}");
        }
        (fast, a.certified > 0)
    }

    #[test]
    fn table_walk_matches_convex_planes() {
        let mut rng = Rng(15);
        let (mut compared, mut tables, mut accepted, mut certified) = (0, 0, 0, 0);
        for p in polyhedra(&mut rng) {
            // Beyond 64 triangles (the subdivided icosphere) the general walk serves.
            let Some(faces) = ConvexFaces::of(&p) else {
                assert!(p.mesh().triangle_count() > 64);
                continue;
            };
            tables += usize::from(!faces.loops.is_empty());
            let verts = p.vertices();
            for k in 0..300 {
                // Points all around, some in the plane of a face or through an edge's line.
                let x = match k % 3 {
                    0 => p.mesh().bounding_sphere().center + rng.vec(-3.0, 3.0),
                    1 => {
                        let (a, b) = (verts[k % verts.len()], verts[(k * 7 + 1) % verts.len()]);
                        a + (a - b) * rng.range(0.5, 4.0)
                    }
                    _ => {
                        let t = p.mesh().triangle(k % p.mesh().triangle_count());
                        t[0] + (t[1] - t[0]) * rng.range(-2.0, 3.0)
                            + (t[2] - t[0]) * rng.range(-2.0, 3.0)
                    }
                };
                let frame = ShadingFrame::new(x, rng.vec(-1.0, 1.0), rng.vec(-1.0, 1.0));
                let Ok(frame) = frame else { continue };
                compared += 1;
                let (fast, sure) = walks_agree(&p, &faces, &frame);
                accepted += usize::from(fast);
                certified += usize::from(sure);
            }
        }
        // The certified walks are the boxes' and wedges' seen from points clear of their face
        // planes: a good share of them.
        assert!(
            tables >= 12
                && compared > 8_000
                && accepted > compared / 2
                && accepted < compared
                && certified > compared / 12,
            "{tables} tables, {compared} compared, {accepted} accepted, {certified} certified"
        );
    }

    /// Points within the facing tolerance of a face plane, where a face seen nearly edge-on is
    /// left out of the silhouette and the silhouette turns right by a sliver (or runs straight,
    /// in the plane): the table walk's turn decisions (a quick accept from the edge's plane,
    /// then the general test) against [`convex_planes`]', which decides every turn by the
    /// general test.
    #[test]
    fn turn_decisions_match_near_face_planes() {
        let mut rng = Rng(23);
        let (mut compared, mut accepted, mut declined) = (0, 0, 0);
        for p in polyhedra(&mut rng) {
            let Some(faces) = ConvexFaces::of(&p) else {
                continue;
            };
            let mesh = p.mesh();
            let scale = mesh.bounding_sphere().radius + mesh.bounding_sphere().center.length();
            for k in 0..400 {
                let f = k % mesh.triangle_count();
                let t = mesh.triangle(f);
                let on = t[0]
                    + (t[1] - t[0]) * rng.range(-2.0, 3.0)
                    + (t[2] - t[0]) * rng.range(-2.0, 3.0);
                let delta = [0.0, 1e-15, -1e-15, 1e-13, -1e-13, 2e-12, -2e-12, 6e-12][k % 8];
                let x = on + mesh.normals()[f] * (delta * scale);
                let frame = ShadingFrame::new(x, rng.vec(-1.0, 1.0), rng.vec(-1.0, 1.0));
                let Ok(frame) = frame else { continue };
                compared += 1;
                let (fast, sure) = walks_agree(&p, &faces, &frame);
                if fast {
                    accepted += 1;
                } else {
                    declined += 1;
                }
                // In a face plane (within a few ulps) nothing is certified.
                assert!(!sure || delta != 0.0, "{x}");
            }
        }
        assert!(
            compared > 10_000 && accepted > compared / 4 && declined > compared / 20,
            "{compared} compared, {accepted} accepted, {declined} declined"
        );
    }

    /// A scene builds at most [`CELL_TABLE_BUDGET`] tables of cells: copies of one body (the
    /// same numbering) share the first one's, and bodies of other numberings beyond the budget
    /// get none (they chain per point).
    #[test]
    fn cell_tables_are_shared_and_bounded() {
        let mut rng = Rng(41);
        let mut shared = CellTables::new();
        let ico = ConvexPolyhedron::icosphere(DVec3::ZERO, 0.5, 0).unwrap();
        let first = ConvexFaces::of_sharing(&ico, &mut shared).unwrap();
        let again = ConvexFaces::of_sharing(&ico.clone(), &mut shared).unwrap();
        let (a, b) = (first.cells.as_ref().unwrap(), again.cells.as_ref().unwrap());
        assert!(Arc::ptr_eq(a, b), "a copy builds its own table");
        let (mut with, mut without) = (0, 0);
        while shared.len() < CELL_TABLE_BUDGET + 8 && with + without < 4000 {
            let c = rng.vec(-1.0, 1.0);
            let pts: Vec<DVec3> = (0..12).map(|_| c + rng.vec(-0.5, 0.5)).collect();
            let Ok(p) = ConvexPolyhedron::hull(&pts) else {
                continue;
            };
            let Some(faces) = ConvexFaces::of_sharing(&p, &mut shared) else {
                continue;
            };
            if faces.plane_edges.is_empty() || faces.normals.len() > CELL_TABLE_PLANES {
                continue;
            }
            if faces.cells.is_some() {
                with += 1;
            } else {
                without += 1;
            }
        }
        assert!(shared.len() <= CELL_TABLE_BUDGET, "{} tables", shared.len());
        assert!(
            with >= 40 && without >= 40,
            "{with} with a table, {without} without"
        );
    }

    /// The table of cells ([`ConvexFaces::cell_contour`]) against [`contour_by_bits`] for the
    /// front planes of points all around icosahedra and random hulls, near and far, the tables
    /// shared as a scene shares them (the icosahedra of several sizes and places take the first
    /// one's): the same loop (or decline) wherever the table holds the set, and the table holds
    /// nearly all sets that points see.
    #[test]
    fn cell_table_matches_contour_by_bits() {
        let mut rng = Rng(37);
        let (mut tables, mut seen, mut hits) = (0, 0, 0);
        let mut shared = CellTables::new();
        let mut distinct: Vec<*const CellTable> = Vec::new();
        for p in polyhedra(&mut rng) {
            let Some(faces) = ConvexFaces::of_sharing(&p, &mut shared) else {
                continue;
            };
            let Some(table) = &faces.cells else {
                continue;
            };
            if !distinct.contains(&Arc::as_ptr(table)) {
                distinct.push(Arc::as_ptr(table));
            }
            tables += 1;
            let bs = p.mesh().bounding_sphere();
            for k in 0..2000 {
                let dir = rng.vec(-1.0, 1.0);
                let x = bs.center + dir * (bs.radius * [1.05, 1.5, 4.0, 30.0][k % 4]);
                let at = crate::solid::facing::FacingAt::new(p.mesh(), x);
                let mut front = 0u64;
                for (g, (nf, &d)) in faces.normals.iter().zip(&faces.offsets).enumerate() {
                    front |= u64::from(at.front(*nf, d)) << g;
                }
                if front == 0 {
                    continue;
                }
                seen += 1;
                let mut order = [0u8; INLINE_VERTICES];
                let general = contour_by_bits(front, &faces, &mut order);
                if let Some(cached) = faces.cell_contour(front) {
                    hits += 1;
                    assert_eq!(cached, general.map(|n| &order[..n]), "front {front:b}");
                }
            }
        }
        assert!(
            tables >= 6 && seen > 10_000 && hits * 100 > seen * 99,
            "{tables} tables, {seen} sets seen, {hits} in the table"
        );
        assert!(
            distinct.len() < tables,
            "{tables} bodies with tables, as many built"
        );
    }

    #[test]
    fn contour_by_bits_matches_contour_loop() {
        let mut rng = Rng(31);
        let (mut tables, mut loops) = (0, 0);
        for p in polyhedra(&mut rng) {
            let Some(faces) = ConvexFaces::of(&p) else {
                continue;
            };
            if faces.plane_edges.is_empty() {
                continue;
            }
            tables += 1;
            let planes = faces.normals.len();
            for k in 0..4000u64 {
                // Every set of front planes for the first ones, then random sets, and the sets
                // that real points see (the planes facing a random direction).
                let front = if k < 256 {
                    k & ((1u64 << planes.min(8)) - 1)
                } else if k % 2 == 0 {
                    (rng.next().to_bits() ^ (rng.next().to_bits() << 11)) & ((1u64 << planes) - 1)
                } else {
                    let d = rng.vec(-1.0, 1.0);
                    let mut f = 0u64;
                    for (g, n) in faces.normals.iter().enumerate() {
                        f |= u64::from(n.dot(d) > 0.0) << g;
                    }
                    f
                };
                let (mut a, mut b) = ([0u8; INLINE_VERTICES], [0u8; INLINE_VERTICES]);
                let fast = contour_by_bits(front, &faces, &mut a);
                let general = contour_loop(front, &faces.edges, &faces.masks, &mut b);
                assert_eq!(fast, general, "front {front:b}");
                if let Some(n) = fast {
                    loops += 1;
                    assert_eq!(a[..n], b[..n], "front {front:b}");
                }
            }
        }
        assert!(
            tables >= 12 && loops > 10_000,
            "{tables} tables, {loops} loops"
        );
    }

    /// A closed mesh light of two tetrahedra sharing one apex, seen from a point in the plane
    /// that separates them: its region is two triangles touching at the apex, whose contour
    /// leaves the apex twice (paired by `chain_rings`), so the result passes the apex twice (one
    /// pinched ring or two touching). The overlay must hand it on as not simple; it fails with
    /// the pairing's flag never set, or with `Overlay::repeated_ids` ignored.
    #[test]
    fn touching_mesh_light_region_is_not_simple() {
        let apex = DVec3::new(0.0, 0.0, 3.0);
        let mut verts = vec![apex];
        let mut tris = Vec::new();
        for side in [-1.0, 1.0] {
            let base = verts.len() as u32;
            let tet = [
                DVec3::new(side, -0.5, 2.5),
                DVec3::new(side, 0.5, 2.5),
                DVec3::new(side * 1.2, 0.0, 3.5),
            ];
            verts.extend_from_slice(&tet);
            let centre = (apex + tet[0] + tet[1] + tet[2]) / 4.0;
            let v = [0, base, base + 1, base + 2];
            for [a, b, c] in [[0, 1, 2], [0, 2, 3], [0, 3, 1], [1, 3, 2]] {
                let (pa, pb, pc) = (
                    verts[v[a] as usize],
                    verts[v[b] as usize],
                    verts[v[c] as usize],
                );
                // Outward: counter-clockwise seen from outside.
                let out = (pb - pa).cross(pc - pa).dot(pa - centre) > 0.0;
                tris.push(if out {
                    [v[a], v[b], v[c]]
                } else {
                    [v[a], v[c], v[b]]
                });
            }
        }
        let light = TriangleMesh::new(verts, tris).unwrap();
        let vis = ClipVisibility::new(vec![Lit(light.into())], vec![]);
        let mut decided = 0;
        for y in [-0.2, 0.0, 0.3] {
            let frame = ShadingFrame::new(DVec3::new(0.0, y, 0.0), DVec3::Z, DVec3::Z).unwrap();
            let mut p = Pieces::new();
            if !vis.visible_pieces(0, &frame, true, &mut p).unwrap() {
                continue;
            }
            assert_eq!(p.overlays(), 1, "the overlay decided the region");
            let mut dirs: Vec<[u64; 3]> = p
                .rings()
                .flatten()
                .map(|d| d.normalize().to_array().map(f64::to_bits))
                .collect();
            dirs.sort_unstable();
            assert!(dirs.windows(2).any(|w| w[0] == w[1]), "the apex twice");
            assert!(!p.is_simple(), "rings sharing the apex handed on as simple");
            decided += 1;
        }
        assert!(decided > 0, "the fast path declined every point");
    }

    /// A quad light at height 2 over one to four boxes and icosahedra around height 1, in
    /// random sizes and places.
    fn random_quad_scene(rng: &mut Rng) -> ClipVisibility<Lit> {
        let light = TriangleMesh::quad(
            DVec3::new(rng.range(-0.5, 0.5), rng.range(-0.5, 0.5), 2.0),
            DVec3::new(0.0, rng.range(0.2, 0.8), rng.range(-0.2, 0.2)),
            DVec3::new(rng.range(0.2, 0.8), 0.0, 0.0),
        )
        .unwrap();
        let occluders: Vec<Body> = (0..1 + (rng.next() * 4.0) as usize)
            .map(|k| {
                let c = DVec3::new(rng.range(-0.8, 0.8), rng.range(-0.8, 0.8), 1.0)
                    + DVec3::Z * rng.range(-0.5, 0.4);
                if k % 2 == 0 {
                    ConvexPolyhedron::cuboid(c, rng.vec(0.05, 0.3))
                        .unwrap()
                        .into()
                } else {
                    ConvexPolyhedron::icosphere(c, rng.range(0.05, 0.3), 0)
                        .unwrap()
                        .into()
                }
            })
            .collect();
        ClipVisibility::new(vec![Lit(light.into())], occluders)
    }

    /// A ground point (normal tilted at random) and its frame.
    fn random_ground_frame(rng: &mut Rng) -> ShadingFrame {
        let x = DVec3::new(rng.range(-1.5, 1.5), rng.range(-1.5, 1.5), 0.0);
        let n = DVec3::new(rng.range(-0.3, 0.3), rng.range(-0.3, 0.3), 1.0);
        ShadingFrame::new(x, n, DVec3::Z).unwrap()
    }

    /// The rings' coordinates as bits.
    fn ring_bits(p: &Pieces) -> Vec<Vec<u64>> {
        p.rings()
            .map(|r| {
                r.iter()
                    .flat_map(|d| d.to_array().map(f64::to_bits))
                    .collect()
            })
            .collect()
    }

    #[test]
    fn two_crossings_match_the_general_traversal() {
        let mut rng = Rng(17);
        let (mut pairs, mut two) = (0u64, 0u64);
        for _ in 0..60 {
            let vis = random_quad_scene(&mut rng);
            for _ in 0..100 {
                let frame = random_ground_frame(&mut rng);
                let (mut a, mut b) = (Pieces::new(), Pieces::new());
                b.general_only = true;
                let fast = vis.visible_pieces(0, &frame, true, &mut a).unwrap();
                let general = vis.visible_pieces(0, &frame, true, &mut b).unwrap();
                assert_eq!(fast, general);
                assert_eq!(a.subtractions(), b.subtractions());
                assert_eq!(ring_bits(&a), ring_bits(&b), "{}", frame.origin());
                pairs += 1;
                two += a.two_crossings;
            }
        }
        assert!(two > pairs / 4, "{two} of {pairs}");
    }

    /// The trivial reject of an edge outside one plane of `K` ([`super::outside_both`]) against
    /// the crossings' pass on every such edge: where both trace every subtraction, the same
    /// region bit for bit (a rejected edge adds no crossing, as the pass would find). Where the
    /// pass declines (a side within rounding on a plane before the one that rejects), the reject
    /// may let the tracing go on; those points are counted, not compared.
    #[test]
    fn trivial_reject_matches_the_crossings_pass() {
        let mut rng = Rng(29);
        let (mut compared, mut rejects) = (0u64, 0u64);
        for _ in 0..60 {
            let vis = random_quad_scene(&mut rng);
            for _ in 0..100 {
                let frame = random_ground_frame(&mut rng);
                let (mut a, mut b) = (Pieces::new(), Pieces::new());
                b.no_reject = true;
                let fast = vis.visible_pieces(0, &frame, true, &mut a).unwrap();
                let full = vis.visible_pieces(0, &frame, true, &mut b).unwrap();
                assert_eq!(fast, full);
                assert_eq!(b.rejects, 0);
                if a.subtractions() == b.subtractions() {
                    assert_eq!(ring_bits(&a), ring_bits(&b), "{}", frame.origin());
                    compared += 1;
                }
                rejects += a.rejects;
            }
        }
        assert!(
            compared > 5_000 && rejects > 1_000,
            "{compared} compared, {rejects} rejects"
        );
    }
}
