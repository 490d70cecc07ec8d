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
//! The region a blocker covers is convex whenever the blocker is: a convex polyhedron seen from
//! outside covers the cone bounded by the planes through the point and its contour edges (seed
//! 000 Alg. 2, thesis 003 section 4.2), `K = n_j H_j`, one half-space `H_j` per contour edge,
//! in any order; a mesh triangle covers the cone of its three edges. The region is kept as a
//! signed sum of loops, `R = sum_i s_i [L_i]` (`s_i = +-1`, `[L]` the indicator of the region a
//! loop bounds), and a blocker is subtracted by
//!
//! `R - K = R - R n K = sum_i s_i [L_i] - sum_i s_i [L_i n K]`,
//!
//! one loop `L_i n K` more, with the opposite sign, for each loop that `K` meets: the
//! inclusion–exclusion of the blockers' covers, over the light's region only. `L n K` is
//! Sutherland–Hodgman against the planes of `K` in turn (each a plane through the origin). On a
//! loop that is not convex a cut may leave bridges (edges along the cutting circle run once each
//! way), but as a chain its winding number is still that of the loop times the indicator of the
//! half-space: the parts of the loop outside are closed by the same bridges into loops outside
//! it. So every loop's boundary integral is the integral over its region, and the signed sum of
//! the integrals is the integral over `R`. A loop that `K` covers whole is removed instead, and
//! one that a plane of `K` leaves entirely outside costs one pass over its vertices. The sum
//! cancels where blockers overlap, to an absolute error of a few ulps of the light's integral,
//! far below the spherical path's own snapping of vertices (`crate::planar::SNAP_REL` of the
//! projected coordinates). Each cut is continuous in its input: a vertex on or within rounding
//! of a cutting plane moves a loop's boundary by rounding, not its topology, so no
//! near-degenerate configuration needs a decision (and none is an [`GeomError::Undecidable`]).
//! The light is clipped to the upper hemisphere first (one more half-space, `z >= 0`, whose
//! crossing points have `z` exactly zero), so every loop lies in the closed upper hemisphere,
//! where Baum's edge sum is the clamped-cosine integral.
//!
//! # Where it applies
//!
//! [`ClipVisibility::visible_pieces`] answers for [`Method::Silhouette`] with:
//!
//! - a convex light (its silhouette ring), or a planar mesh light whose boundary
//!   ([`TriangleMesh::boundary_loops`], once per scene) has only outer loops (no holes): seen
//!   from the front its region is those loops, not a union of its triangles;
//! - blockers that are separated from the light by the precomputed plane (step 2 of
//!   [`ClipVisibility::visible_region`]: subtracted whole), convex (their contour half-spaces)
//!   or meshes (each triangle's three half-spaces, seen from either side).
//!
//! It declines (`Ok(false)`), leaving the region to the spherical path, for everything else: a
//! blocker that interpenetrates the light, non-planar mesh lights, a planar light seen
//! edge-on by some of its triangles and not others, and every silhouette that
//! [`convex_silhouette`](crate::solid::silhouette::convex_silhouette) would not take as one
//! loop chained by vertex index with well separated vertices (the point inside or on a convex
//! object, a point within rounding of an edge's line): there the spherical path decides, or
//! gives up, exactly as without this path.

use glam::DVec3;
use smallvec::SmallVec;

use super::cull::{above_horizon, may_occlude};
use super::{ClipVisibility, Method};
use crate::GeomError;
use crate::solid::facing::{FACE_TOLERANCE, Side, face_side, in_front};
use crate::solid::silhouette::chain_by_index;
use crate::solid::{Body, ConvexPolyhedron, ShadingFrame, TriangleMesh};
use crate::sphere::{ANTIPODAL_TOLERANCE, MATCH_TOLERANCE};

/// Directions of one ring of vertices, inline for the rings of small lights and their cuts.
type Ring = SmallVec<[DVec3; 32]>;

/// Most loops [`Pieces`] holds before the fast path declines: inclusion–exclusion doubles them
/// with each blocker that meets all of them, so this bounds the work (and the cancellation)
/// for many mutually overlapping blockers, which the spherical path then takes.
const MAX_LOOPS: usize = 64;

/// The visible region of a light from a shading point, as the fast path of
/// [`ClipVisibility::visible_pieces`] leaves it: a signed sum of loops in the closed upper
/// hemisphere of the shading frame, each a ring of directions of any positive length (not unit
/// vectors) with its region on the left of each edge, as for a
/// [`SphericalPolygon`](crate::sphere::SphericalPolygon): the region's integral is the sum over
/// the loops of the sign times the loop's integral. A loop may be a closed chain with bridges
/// (edges run once each way, see the source of `visibility::pieces`): its edge integrals are
/// still those of its region.
///
/// It is also the scratch storage of the fast path: a caller that keeps one across calls
/// reuses its buffers. Inline room for 128 vertices in all, so small lights and blockers (up to
/// 16 vertices each, a few blockers) allocate nothing; larger ones spill to the heap once per
/// `Pieces` value.
#[derive(Debug, Default, Clone)]
pub struct Pieces {
    /// The loops' vertices: loop `k` is `pts[loops[k].0 as usize..loops[k].1 as usize]`.
    pts: SmallVec<[DVec3; 128]>,
    /// Start, end and sign (`true` for `+1`) of each loop.
    loops: SmallVec<[(u32, u32, bool); 16]>,
    /// A loop being cut by a blocker's planes, and the cut's output, used in turn.
    rings: [Ring; 2],
    /// The normals of the current blocker's half-spaces (`n . v >= 0` inside).
    planes: SmallVec<[DVec3; 24]>,
    /// Front-face flags and contour edges of a convex silhouette.
    front: SmallVec<[bool; 64]>,
    contour: SmallVec<[(u32, u32); 24]>,
    /// Unit directions of a silhouette's vertices.
    dirs: Ring,
}

impl Pieces {
    /// Empty storage (no heap allocation).
    #[must_use]
    pub fn new() -> Self {
        Self::default()
    }

    /// The loops, each with its sign (`1.0` or `-1.0`) and its ring of directions in the
    /// shading frame (not normalized).
    pub fn loops(&self) -> impl Iterator<Item = (f64, &[DVec3])> + '_ {
        self.loops.iter().map(|&(a, b, plus)| {
            (
                if plus { 1.0 } else { -1.0 },
                &self.pts[a as usize..b as usize],
            )
        })
    }

    /// Number of loops.
    #[must_use]
    pub fn len(&self) -> usize {
        self.loops.len()
    }

    /// Whether there is no loop (nothing of the light is visible).
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.loops.is_empty()
    }

    fn clear(&mut self) {
        self.pts.clear();
        self.loops.clear();
    }

    /// Appends `self.dirs` clipped to the closed upper hemisphere (`z >= 0`) as a positive loop.
    fn push_dirs_upper(&mut self) {
        let Pieces {
            pts, loops, dirs, ..
        } = self;
        push_upper(pts, loops, dirs);
    }
}

/// Appends `ring` clipped to the closed upper hemisphere (`z >= 0`) to `pts` as a positive loop.
fn push_upper(
    pts: &mut SmallVec<[DVec3; 128]>,
    loops: &mut SmallVec<[(u32, u32, bool); 16]>,
    ring: &[DVec3],
) {
    {
        let start = pts.len();
        if ring.iter().all(|v| v.z > 0.0) {
            pts.extend_from_slice(ring);
        } else {
            let Some(&last) = ring.last() else {
                return;
            };
            let mut prev = last;
            for &cur in ring {
                if prev.z >= 0.0 {
                    pts.push(prev);
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
                    pts.push(DVec3::new(x.x, x.y, 0.0));
                }
                prev = cur;
            }
        }
        if pts.len() - start >= 3 {
            loops.push((start as u32, pts.len() as u32, true));
        } else {
            pts.truncate(start);
        }
    }
}

impl Pieces {
    /// Subtracts `K`, the intersection of the half-spaces in `self.planes`, from the region:
    /// for each loop `L` that `K` meets, `L n K` with the opposite sign, or `L` removed where
    /// `K` covers it (see the source of `visibility::pieces`). `false` when the loops would
    /// exceed [`MAX_LOOPS`].
    fn subtract_planes(&mut self) -> bool {
        let count = self.loops.len();
        let mut k = 0;
        let mut kept = 0;
        while k < count {
            let (a, b, plus) = self.loops[k];
            k += 1;
            match self.cut_by_planes(a as usize..b as usize) {
                Cut::Outside => {
                    self.loops[kept] = (a, b, plus);
                    kept += 1;
                }
                // Covered whole: the loop and its cut cancel.
                Cut::Inside => {}
                Cut::Part(r) => {
                    self.loops[kept] = (a, b, plus);
                    kept += 1;
                    let start = self.pts.len();
                    self.pts.extend_from_slice(&self.rings[r]);
                    self.loops
                        .push((start as u32, self.pts.len() as u32, !plus));
                }
            }
        }
        // The removed loops' slots are reused by the new ones; their vertices stay in `pts`
        // until the next clear.
        self.loops.drain(kept..count);
        self.loops.len() <= MAX_LOOPS
    }

    /// The loop `pts[range]` cut by every plane of `self.planes` (Sutherland–Hodgman), the
    /// result, if any, in `self.rings[r]`.
    fn cut_by_planes(&mut self, range: core::ops::Range<usize>) -> Cut {
        // Index of the ring holding the current cut; `None` while it is still the loop itself.
        let mut at: Option<usize> = None;
        for j in 0..self.planes.len() {
            let n = self.planes[j];
            let src: &[DVec3] = match at {
                None => &self.pts[range.clone()],
                Some(r) => &self.rings[r],
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
            let dst = at.map_or(0, |r| 1 - r);
            let (lo, hi) = self.rings.split_at_mut(1);
            let (src, out): (&[DVec3], &mut Ring) = match at {
                None => (&self.pts[range.clone()], &mut lo[0]),
                Some(0) => (&lo[0], &mut hi[0]),
                Some(_) => (&hi[0], &mut lo[0]),
            };
            cut_ring(src, n, out);
            if out.len() < 3 {
                return Cut::Outside;
            }
            at = Some(dst);
        }
        match at {
            None => Cut::Inside,
            Some(r) => Cut::Part(r),
        }
    }
}

/// What a blocker's planes leave of a loop ([`Pieces::cut_by_planes`]).
enum Cut {
    /// Nothing inside: the blocker misses the loop (or meets it in no area).
    Outside,
    /// All of it inside: the blocker covers the loop.
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
            // The point of the chord a-b on the plane: a convex combination, so its length
            // stays between theirs.
            let (wa, wb) = (sb.abs(), sa.abs());
            out.push((a * wa + b * wb) / (wa + wb));
        }
        (a, sa) = (b, sb);
    }
}

impl<L: AsRef<Body>> ClipVisibility<L> {
    /// The fast path of [`ClipVisibility::visible_region`] (with `blocked`) or of
    /// [`Visibility::unoccluded_region`](super::Visibility::unoccluded_region) (without): the
    /// region as [`Pieces`], whose integrals are those of the spherical path's region up to
    /// rounding. `Ok(true)` when `out` holds the region; `Ok(false)` when this path does not
    /// apply (see [`Pieces`] and the source of `visibility::pieces`) and the caller takes
    /// [`ClipVisibility::visible_region`]. Allocates nothing for lights and blockers of up to
    /// 16 vertices (beyond what `out` already holds).
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
        if !self.light_loops(light, body, frame, out) {
            out.clear();
            return Ok(false);
        }
        if !blocked {
            return Ok(true);
        }
        for b in self.blockers_between(light, frame) {
            if out.is_empty() {
                break;
            }
            // Interpenetrating blockers act face by face: the spherical path's business.
            let fits = self.separation(light, b).is_some()
                && match self.blocker(b).0 {
                    Body::Convex(p) => convex_planes(p, frame, out) && out.subtract_planes(),
                    Body::Mesh(m) => self.subtract_triangles(light, m, frame, out),
                };
            if !fits {
                out.clear();
                return Ok(false);
            }
        }
        Ok(true)
    }

    /// The light's own region as the first loops of `out`, clipped to the upper hemisphere;
    /// `false` where the fast path does not apply.
    fn light_loops(
        &self,
        light: usize,
        body: &Body,
        frame: &ShadingFrame,
        out: &mut Pieces,
    ) -> bool {
        match body {
            Body::Convex(p) => {
                if !convex_silhouette_dirs(p, frame, out) {
                    return false;
                }
                out.push_dirs_upper();
                true
            }
            Body::Mesh(m) => {
                let Some(loops) = &self.outlines[light] else {
                    return false;
                };
                // Every triangle of a planar mesh lies in one plane, but the facing predicate
                // sees each with its own normal: the region is the loops only if it sees all of
                // them from the front, and nothing if from none. (The facing predicate of
                // `face_side`, with the tolerance computed once.)
                let x = frame.origin();
                let bound = m.bounding_sphere();
                let rel = x - bound.center;
                let tol = FACE_TOLERANCE * (bound.radius + rel.length());
                let front = m
                    .normals()
                    .iter()
                    .zip(m.offsets())
                    .filter(|&(nf, &d)| in_front(nf.dot(rel) - d, tol))
                    .count();
                if front == 0 {
                    return true;
                }
                if front != m.triangle_count() {
                    return false;
                }
                // Lengths of the scene's scale would make the edge terms' products overflow or
                // underflow far from 1: scaled by the inverse distance there.
                let d2 = rel.length_squared();
                let scale = if (1e-60..=1e60).contains(&d2) {
                    1.0
                } else {
                    1.0 / crate::math::sqrt(d2)
                };
                for lp in loops {
                    // Counter-clockwise seen from the point is clockwise on the sphere seen from
                    // outside: reversed, so that the region is on the left.
                    out.dirs.clear();
                    for &i in lp.iter().rev() {
                        out.dirs
                            .push(frame.to_local(m.vertices()[i as usize]) * scale);
                    }
                    out.push_dirs_upper();
                }
                true
            }
        }
    }

    /// Subtracts from `out` every triangle of the mesh blocker `m` (seen from either side, each
    /// with its three half-spaces), after the per-triangle cull of the spherical path; `false`
    /// when the loops would exceed [`MAX_LOOPS`].
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
                .extend((0..3).map(|k| edge_plane(ring[k], ring[(k + 1) % 3])));
            if !out.subtract_planes() {
                return false;
            }
        }
        true
    }
}

/// The silhouette of the convex polyhedron `p` seen from the frame's point as unit directions
/// in the frame, in `out.dirs` (counter-clockwise on the sphere: the silhouette on the left),
/// exactly where [`convex_silhouette`](crate::solid::silhouette::convex_silhouette) returns the
/// loop of the same vertices without its general ordering: front faces by the facing predicate
/// (the same distances and tolerance), contour edges oriented by their front face, chained by
/// vertex index into one loop whose consecutive directions are further apart than
/// [`MATCH_TOLERANCE`] and not antipodal within [`ANTIPODAL_TOLERANCE`]. `false` elsewhere: no
/// face in front (the point inside or on the surface, where that function returns a hemisphere,
/// a lune or the full sphere) or a loop that needs the general ordering.
fn convex_silhouette_dirs(p: &ConvexPolyhedron, frame: &ShadingFrame, out: &mut Pieces) -> bool {
    let mesh = p.mesh();
    let b = mesh.bounding_sphere();
    let rel = frame.origin() - b.center;
    let tol = FACE_TOLERANCE * (b.radius + rel.length());
    let normals = mesh.normals();
    let offsets = mesh.offsets();
    out.contour.clear();
    if normals.len() <= 64 {
        // Front faces as bits: the common small polyhedron, without a buffer.
        let mut front = 0u64;
        for (f, (nf, &d)) in normals.iter().zip(offsets).enumerate() {
            front |= u64::from(in_front(nf.dot(rel) - d, tol)) << f;
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
            let f = in_front(nf.dot(rel) - d, tol);
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
    let Some(ring) = chain_by_index(&out.contour, p.vertices().len()) else {
        return false;
    };
    out.dirs.clear();
    let verts = p.vertices();
    for &i in &ring {
        let Some(u) = frame.to_local(verts[i as usize]).try_normalize() else {
            return false;
        };
        out.dirs.push(u);
    }
    let n = out.dirs.len();
    // Squared chord lengths against the squared tolerances, with the root taken only near the
    // threshold, where the comparison of the lengths themselves decides.
    let apart = |c: DVec3, tol: f64| {
        let c2 = c.length_squared();
        c2 > 2.0 * tol * tol || (c2 > 0.5 * tol * tol && crate::math::sqrt(c2) > tol)
    };
    if n < 3 {
        return false;
    }
    let mut prev = out.dirs[n - 1];
    for &cur in &out.dirs {
        if !(apart(prev - cur, MATCH_TOLERANCE) && apart(prev + cur, ANTIPODAL_TOLERANCE)) {
            return false;
        }
        prev = cur;
    }
    true
}

/// The half-spaces of the convex blocker `p`'s silhouette into `out.planes`, one per contour
/// edge (the silhouette is their intersection); `false` where [`convex_silhouette_dirs`]
/// declines.
fn convex_planes(p: &ConvexPolyhedron, frame: &ShadingFrame, out: &mut Pieces) -> bool {
    if !convex_silhouette_dirs(p, frame, out) {
        return false;
    }
    let n = out.dirs.len();
    out.planes.clear();
    for k in 0..n {
        let next = out.dirs[if k + 1 == n { 0 } else { k + 1 }];
        out.planes.push(edge_plane(out.dirs[k], next));
    }
    // The intersection of the half-spaces is the silhouette only where it is convex: at a reflex
    // vertex (a face seen within the facing tolerance of edge-on is left out of the silhouette,
    // which then turns back by the angle that face's sliver would have filled) the planes would
    // cut a wedge out of the silhouette along the extended edge. Every turn must be strictly to
    // the left; a turn within rounding of straight could only hide a wedge of a few ulps.
    let mut prev = out.dirs[n - 1];
    for k in 0..n {
        let (cur, next) = (out.dirs[k], out.dirs[if k + 1 == n { 0 } else { k + 1 }]);
        if !(left_turn(prev, cur, next) > 0.0) {
            return false;
        }
        prev = cur;
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
