//! The fast path ([`ClipVisibility::visible_pieces`]) for closed meshes: closed mesh blockers
//! by their contours and closed non-planar mesh lights by theirs (issue 17), both resolved by
//! one overlay in one gnomonic chart ([`super::overlay`]) instead of the planar fill-rule pass
//! of `visibility/union.rs`.
//!
//! Seen from a point outside a closed component's box, the component's front faces cover all
//! it covers (see [`super::union::Closed`]), and the chain of their contour edges winds about a
//! direction as many times as front faces cover it ([`super::contour`]): the blockers' union is
//! where that winding is positive. A closed mesh light's region is the union of its front
//! faces, the same chain's positive part. So the light's region (its rings, or its contour) and
//! the blockers' contours, clipped to a box of the chart around the light, are all the overlay
//! needs. Components whose boxes miss the shaft from the point through that box are left out
//! whole (their contours are closed by themselves); convex and small open mesh blockers are
//! subtracted afterwards by the boundary tracing of `visibility/pieces.rs`.
//!
//! A blocker of one component with a facing hierarchy and a bounding-volume hierarchy goes
//! further: only the part of its contour that may lie in the cone through the chart's box is
//! found ([`Cull::Cone`]), and chained into closed rings and open chains whose ends lie outside
//! the cone. The pieces of these chains inside the box are each closed along the box's boundary
//! (from where the piece leaves the box, through the corners, to where it entered:
//! [`BoxClip::pieces`]). Inside the box these rings then wind as the whole contour does up to
//! one integer, the winding of the left-out edges and parts outside the box less the closing
//! paths, a closed path outside the box or on its boundary: that integer is found at one
//! direction of the box as the count of front faces a ray from the point crosses there
//! (through the mesh's hierarchy, every decision certified) less the rings' winding there, and
//! put back as that many copies of the box's boundary (bridges: counted by the overlay's rays,
//! never kept). The shaft idea of Haines and Wallace (*Shaft culling for efficient ray-cast
//! radiosity*, 1991) applied to contour edges, with the topology restored by one ray.
//!
//! It declines (the caller takes the general path) where the light is wider than one chart, a
//! mesh light's contour reaches the horizon, the point lies in the box of a component of the
//! mesh light or of a blocker component in the shaft, the region before the overlay is not a
//! set of simple rings, or the overlay declines within rounding.

use alloc::boxed::Box;
use alloc::vec::Vec;

use glam::{DVec2, DVec3};

use super::contour::{ChainScratch, Cull, chain_rings};
use super::cull::Shaft;
use super::overlay::{BLOCKER, LIGHT, Overlay, RingPoint};
use super::{Blocker, ClipVisibility, Pieces};
use crate::solid::facing::FacingAt;
use crate::solid::{Body, Bvh, ShadingFrame, TriangleMesh};

/// Smallest cosine between the chart's centre and a direction of the light (about 78 degrees),
/// as for the one-pass union's chart (`visibility/union.rs`).
const MIN_LIGHT_COS: f64 = 0.2;

/// The box around the light in the chart is widened by this fraction of its size on each side,
/// so that the blockers' cut rings run along its sides away from the light's region.
const BOX_MARGIN: f64 = 0.05;

/// Identities of vertices that are no mesh vertex (the light's, and cut points) start here;
/// mesh vertices are `(slot + 1) << 32 | index`.
const FRESH_IDS: u64 = 1 << 63;

/// Scratch storage of the mesh fast path, kept in [`Pieces`].
#[derive(Debug, Clone, Default)]
pub(crate) struct MeshScratch {
    overlay: Overlay,
    edges: Vec<(u32, u32)>,
    chain: ChainScratch,
    buf: Vec<RingPoint>,
    cut: Vec<RingPoint>,
}

/// Vertices the scratch storage is first made for (a few hundred contour vertices in the
/// light's chart are common for meshes of a thousand triangles): the buffers are reserved
/// once rather than grown in steps on a context's first point.
const SCRATCH_VERTICES: usize = 256;

impl MeshScratch {
    fn new() -> Self {
        MeshScratch {
            overlay: Overlay::with_capacity(SCRATCH_VERTICES),
            edges: Vec::with_capacity(SCRATCH_VERTICES),
            chain: ChainScratch::with_capacity(SCRATCH_VERTICES),
            buf: Vec::with_capacity(SCRATCH_VERTICES / 4),
            cut: Vec::with_capacity(SCRATCH_VERTICES / 4),
        }
    }
}

/// The chart: centre `c` and axes `u`, `v` with `u x v = c` (so that counter-clockwise in the
/// chart is counter-clockwise on the sphere seen from outside).
struct Chart {
    c: DVec3,
    u: DVec3,
    v: DVec3,
}

impl Chart {
    /// The chart position of `d` if it lies within [`MIN_LIGHT_COS`] of the centre.
    #[inline]
    fn project_near(&self, d: DVec3) -> Option<DVec2> {
        let z = d.dot(self.c);
        (z > 0.0 && z * z >= MIN_LIGHT_COS * MIN_LIGHT_COS * d.length_squared())
            .then(|| DVec2::new(d.dot(self.u), d.dot(self.v)) / z)
    }

    /// The chart position of `d`, which lies in the chart's open hemisphere.
    #[inline]
    fn project(&self, d: DVec3) -> DVec2 {
        DVec2::new(d.dot(self.u), d.dot(self.v)) / d.dot(self.c)
    }
}

impl<L: AsRef<Body>> ClipVisibility<L> {
    /// Whether light `light` is a closed non-planar mesh light with a contour structure, whose
    /// region this path computes.
    pub(super) fn contour_light(&self, light: usize, body: &Body) -> bool {
        matches!(body, Body::Mesh(m) if !m.is_planar())
            && self.contours(Blocker::Light(light)).is_some()
    }

    /// Replaces the region in `out` (the light's rings, simple; or nothing yet for a contour
    /// light, `mesh_light`) by what is left of the light once the closed mesh blockers `meshes`
    /// are removed. `false` where this path declines (see the module documentation).
    pub(super) fn overlay_region(
        &self,
        light: usize,
        frame: &ShadingFrame,
        mesh_light: bool,
        meshes: &[Blocker],
        out: &mut Pieces,
    ) -> bool {
        if !mesh_light && (out.is_empty() || meshes.is_empty()) {
            return true;
        }
        if !mesh_light && !out.is_simple() {
            return false;
        }
        let mut s = out
            .mesh
            .take()
            .unwrap_or_else(|| Box::new(MeshScratch::new()));
        let ok = self.overlay_into(light, frame, mesh_light, meshes, out, &mut s);
        out.mesh = Some(s);
        ok
    }

    fn overlay_into(
        &self,
        light: usize,
        frame: &ShadingFrame,
        mesh_light: bool,
        meshes: &[Blocker],
        out: &mut Pieces,
        s: &mut MeshScratch,
    ) -> bool {
        let x = frame.origin();
        let bound = self.light_bounds[light];
        let Some(c) = frame.to_local(bound.center).try_normalize() else {
            return false;
        };
        let (mut u, mut v) = c.any_orthonormal_pair();
        if u.cross(v).dot(c) < 0.0 {
            core::mem::swap(&mut u, &mut v);
        }
        let mut chart = Chart { c, u, v };
        let mut fresh = FRESH_IDS;
        s.overlay.clear();
        // The light's rings (winding 1 inside), or its contour (winding = front faces over it).
        if mesh_light {
            let Some(mc) = self.contours(Blocker::Light(light)) else {
                return false;
            };
            let mesh = self.light_body(light).map(Body::mesh);
            let Ok(mesh) = mesh else { return false };
            s.edges.clear();
            if !mc.contour(mesh, x, Cull::All, &mut s.edges) {
                return false;
            }
            let verts = mesh.vertices();
            let base = (self.occluders().len() as u64 + light as u64 + 1) << 32;
            let ov = &mut s.overlay;
            let mut fits = true;
            let ok = chain_rings(
                &s.edges,
                verts.len(),
                |i| frame.to_local(verts[i as usize]),
                false,
                &mut s.chain,
                |ring, _| {
                    let start = ov.pts.len();
                    // Reversed: the front faces run their contour clockwise seen from outside.
                    for &i in ring.iter().rev() {
                        let d = frame.to_local(verts[i as usize]);
                        match chart.project_near(d) {
                            Some(p) if d.z > 0.0 => ov.pts.push(RingPoint {
                                p,
                                d,
                                id: base | u64::from(i),
                                bridge: false,
                            }),
                            _ => fits = false,
                        }
                    }
                    ov.close(start, LIGHT);
                },
            );
            if !ok || !fits {
                return false;
            }
            s.overlay.repeated_ids |= s.chain.paired;
        } else {
            let ov = &mut s.overlay;
            for ring in out.rings() {
                let start = ov.pts.len();
                for &d in ring {
                    let Some(p) = chart.project_near(d) else {
                        return false;
                    };
                    ov.pts.push(RingPoint {
                        p,
                        d,
                        id: fresh,
                        bridge: false,
                    });
                    fresh += 1;
                }
                ov.close(start, LIGHT);
            }
        }
        if s.overlay.pts.is_empty() {
            out.set_region(&[], &[], true);
            return true;
        }
        // The chart's axes turned to fit the box below tightly around the light's region: what
        // the blockers leave in that box is the overlay's input.
        align_chart(&mut chart, &mut s.overlay.pts);
        let Chart { c, u, v } = chart;
        // The box around the light in the chart, and its planes through the point.
        let (mut lo, mut hi) = (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY));
        for q in &s.overlay.pts {
            lo = lo.min(q.p);
            hi = hi.max(q.p);
        }
        let m = BOX_MARGIN * (hi - lo).max_element()
            + 1e-9 * (1.0 + lo.abs().max(hi.abs()).max_element());
        let (lo, hi) = (lo - DVec2::splat(m), hi + DVec2::splat(m));
        let planes = [hi.x * c - u, u - lo.x * c, hi.y * c - v, v - lo.y * c];
        if !meshes.is_empty() {
            let mut sides = [DVec3::ZERO; 4];
            for (k, n) in planes.iter().enumerate() {
                let Some(n) = n.try_normalize() else {
                    return false;
                };
                sides[k] = frame.dir_to_world(n);
            }
            let far = (bound.center - x).length() + bound.radius;
            let shaft = Shaft::from_cone(x, frame.normal(), &sides, frame.dir_to_world(c), far);
            for &b in meshes {
                let Some(mc) = self.contours(b) else {
                    return false;
                };
                let mesh = self.blocker(b).0.mesh();
                let bvh = self.bvh(b).filter(|_| mc.single_tree());
                let cull = if bvh.is_some() {
                    Cull::Cone(&shaft, &sides)
                } else {
                    Cull::Shaft(&shaft)
                };
                s.edges.clear();
                if !mc.contour(mesh, x, cull, &mut s.edges) {
                    return false;
                }
                let verts = mesh.vertices();
                let base = (self.slot(b) as u64 + 1) << 32;
                let first_ring = s.overlay.ends.len();
                let (ov, buf, cut) = (&mut s.overlay, &mut s.buf, &mut s.cut);
                let clip = bvh.map(|_| BoxClip::new(&planes, lo, hi, c, u, v));
                let mut pieces_ok = true;
                let ok = chain_rings(
                    &s.edges,
                    verts.len(),
                    |i| frame.to_local(verts[i as usize]),
                    bvh.is_some(),
                    &mut s.chain,
                    |ring, open| {
                        buf.clear();
                        for &i in ring.iter().rev() {
                            buf.push(RingPoint {
                                p: DVec2::ZERO,
                                d: frame.to_local(verts[i as usize]),
                                id: base | u64::from(i),
                                bridge: false,
                            });
                        }
                        if let Some(clip) = &clip {
                            // Cone-culled: the winding inside the box is restored below, so
                            // the pieces may be closed along the box's boundary in any way.
                            pieces_ok &= clip.pieces(buf, open, &chart, ov, &mut fresh);
                            return;
                        }
                        if clip_to_planes(buf, cut, &planes, &mut fresh) {
                            let start = ov.pts.len();
                            for q in buf.iter() {
                                ov.pts.push(RingPoint {
                                    p: chart.project(q.d),
                                    ..*q
                                });
                            }
                            ov.close(start, BLOCKER);
                        }
                    },
                );
                if !ok || !pieces_ok {
                    return false;
                }
                s.overlay.repeated_ids |= s.chain.paired;
                if let Some(bvh) = bvh {
                    // The pieces agree with the contour inside the box up to a closed path
                    // outside it or on its boundary (the left-out edges, the parts outside the
                    // box, the closing paths along its boundary), which adds the same
                    // winding everywhere in the box: that constant is the front faces' count
                    // over one direction of the box (a ray) less the chains' winding there,
                    // and is put back as that many copies of the box's boundary.
                    let mut k = None;
                    // Directions near the corners first, with the mesh's bounding sphere only:
                    // often one of them misses it, and the count there is 0.
                    let candidates = [
                        (false, [0.02, 0.02]),
                        (false, [0.98, 0.02]),
                        (false, [0.98, 0.98]),
                        (false, [0.02, 0.98]),
                        (true, [0.5, 0.5]),
                        (true, [0.37, 0.61]),
                        (true, [0.71, 0.29]),
                    ];
                    for (full, f) in candidates {
                        let q = lo + (hi - lo) * DVec2::from(f);
                        let d = frame.dir_to_world(c + u * q.x + v * q.y);
                        let Some(wf) = front_cover(mesh, full.then_some(bvh), x, d) else {
                            continue;
                        };
                        if let Some(wc) = s.overlay.winding(first_ring, BLOCKER, q) {
                            k = Some(wf - wc);
                            break;
                        }
                    }
                    let Some(k) = k else {
                        return false;
                    };
                    for _ in 0..k.unsigned_abs() {
                        let ov = &mut s.overlay;
                        let start = ov.pts.len();
                        let corners = [lo, DVec2::new(hi.x, lo.y), hi, DVec2::new(lo.x, hi.y)];
                        for j in 0..4 {
                            let p = corners[if k > 0 { j } else { 3 - j }];
                            ov.pts.push(RingPoint {
                                p,
                                d: c + u * p.x + v * p.y,
                                id: fresh,
                                bridge: true,
                            });
                            fresh += 1;
                        }
                        ov.close(start, BLOCKER);
                    }
                }
            }
        }
        if !mesh_light && s.overlay.family.iter().all(|&f| f == LIGHT) {
            // No blocker reaches the box: the region is the light's (decided by this path,
            // counted as its overlays are).
            out.overlays += 1;
            return true;
        }
        if !s.overlay.resolve(c, u, v) {
            return false;
        }
        out.set_region(&s.overlay.out, &s.overlay.out_ends, !s.overlay.touching);
        out.overlays += 1;
        true
    }
}

/// Most light ring points whose edges are all tried as the chart's axis by [`align_chart`].
const ALIGN_EDGES: usize = 16;

/// Turns the chart's axes `u`, `v` about its centre (a rotation: `u x v = c` stays) so that
/// the box of the light's points `pts` in the chart is small, and projects them again. The
/// axes tried are the initial ones and, for a light of few points (a quad, a polygon), the
/// directions of its edges: a convex polygon's smallest enclosing rectangle has a side along
/// one of its edges (Freeman and Shapira, *Determining the minimum-area encasing rectangle
/// for an arbitrary closed curve*, 1975). Any axes give the same region (the chart is a
/// central projection whatever they are); only the box, and with it the blockers' contour
/// kept by [`Cull::Cone`] and the overlay's input, shrinks. For a quad light seen with
/// the axes at 45 degrees to its edges, the box's area halves.
fn align_chart(chart: &mut Chart, pts: &mut [RingPoint]) {
    if pts.len() > ALIGN_EDGES {
        return;
    }
    let area = |w: DVec2| {
        let (mut lo, mut hi) = (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY));
        for q in pts.iter() {
            let r = DVec2::new(q.p.dot(w), q.p.perp_dot(w));
            lo = lo.min(r);
            hi = hi.max(r);
        }
        let e = hi - lo;
        e.x * e.y
    };
    let mut best = (area(DVec2::X), DVec2::X);
    for k in 0..pts.len() {
        let e = pts[(k + 1) % pts.len()].p - pts[k].p;
        if let Some(w) = e.try_normalize() {
            let a = area(w);
            if a < best.0 {
                best = (a, w);
            }
        }
    }
    let w = best.1;
    if w == DVec2::X {
        return;
    }
    // New axes: `u' = w.x u + w.y v`, `v' = c x u'` as a rotation by the same angle.
    let (u, v) = (chart.u, chart.v);
    chart.u = u * w.x + v * w.y;
    chart.v = v * w.x - u * w.y;
    for q in pts.iter_mut() {
        q.p = chart.project(q.d);
    }
}

/// The box of the chart around the light (its planes through the point, as in
/// [`clip_to_planes`]: right, left, top, bottom) for [`BoxClip::pieces`], with its corners in
/// counter-clockwise order.
struct BoxClip<'a> {
    planes: &'a [DVec3; 4],
    /// The planes' normals by coordinate (for [`BoxClip::code`]'s four lanes).
    px: [f64; 4],
    py: [f64; 4],
    pz: [f64; 4],
    /// The corners after the bottom, right, top and left sides, counter-clockwise.
    corners: [(DVec2, DVec3); 4],
}

/// Position of each plane's side (right, left, top, bottom) in the counter-clockwise order
/// bottom, right, top, left.
const SIDE_POS: [usize; 4] = [1, 3, 2, 0];

impl<'a> BoxClip<'a> {
    fn new(planes: &'a [DVec3; 4], lo: DVec2, hi: DVec2, c: DVec3, u: DVec3, v: DVec3) -> Self {
        let corner = |p: DVec2| (p, c + u * p.x + v * p.y);
        BoxClip {
            planes,
            px: planes.map(|p| p.x),
            py: planes.map(|p| p.y),
            pz: planes.map(|p| p.z),
            corners: [
                corner(DVec2::new(hi.x, lo.y)),
                corner(hi),
                corner(DVec2::new(lo.x, hi.y)),
                corner(lo),
            ],
        }
    }

    /// The planes `d` lies strictly outside of, as bits.
    #[inline]
    fn code(&self, d: DVec3) -> u8 {
        // The four planes side by side (vector lanes); `n . d` as `DVec3::dot` sums it.
        let s: [f64; 4] =
            core::array::from_fn(|j| self.px[j] * d.x + self.py[j] * d.y + self.pz[j] * d.z);
        let mut c = 0;
        for (j, v) in s.iter().enumerate() {
            c |= u8::from(*v < 0.0) << j;
        }
        c
    }

    /// Adds to `ov` the pieces of the chain `ring` (closed, or `open`: then both its ends must
    /// lie outside the box, else `false`) inside the box, each closed by the box's boundary:
    /// from where it leaves the box (marked as a bridge), through the corners (the shorter way
    /// round) up to the side where it entered. Inside the box the rings added wind as the chain does
    /// up to a constant: the chain less these rings is a closed path outside the box or on its
    /// boundary, whose winding is the same at every direction inside. For contours found with
    /// [`Cull::Cone`] that constant is restored anyway (with that of the left-out edges), so
    /// this takes the place of [`clip_to_planes`] there at a fraction of its cost: each edge's
    /// part in the box is found at once against the four planes (Liang and Barsky's clipping,
    /// *A new concept and method for line clipping*, 1984, on direction vectors), the points
    /// outside are never copied, and no open chain needs closing first.
    fn pieces(
        &self,
        ring: &[RingPoint],
        open: bool,
        chart: &Chart,
        ov: &mut Overlay,
        fresh: &mut u64,
    ) -> bool {
        let n = ring.len();
        if n < 2 {
            return true;
        }
        let code_of = |k: usize| self.code(ring[k].d);
        // The first point outside, where the walk along the edges starts.
        let first = if open {
            if code_of(0) == 0 || code_of(n - 1) == 0 {
                return false;
            }
            0
        } else {
            match (0..n).find(|&k| code_of(k) != 0) {
                Some(k) => k,
                None => {
                    let start = ov.pts.len();
                    for q in ring {
                        ov.pts.push(RingPoint {
                            p: chart.project(q.d),
                            ..*q
                        });
                    }
                    ov.close(start, BLOCKER);
                    return true;
                }
            }
        };
        let edges = if open { n - 1 } else { n };
        // A point of the piece begun at `start`; of consecutive points in the same direction
        // (a cut at a vertex on a plane) the later is kept, whose flag is the edge's that
        // leaves it, as in `clip_to_planes`.
        let put = |ov: &mut Overlay, start: usize, d: DVec3, id: u64, bridge: bool| {
            let q = RingPoint {
                p: chart.project(d),
                d,
                id,
                bridge,
            };
            let len = ov.pts.len();
            match ov.pts.last_mut() {
                Some(last) if len > start && last.d == d => *last = q,
                _ => ov.pts.push(q),
            }
        };
        // The piece being added: its first point in `ov.pts` and the side it entered by.
        let mut piece: Option<(usize, usize)> = None;
        let mut a = first;
        let mut ca = code_of(a);
        for _ in 0..edges {
            let b = if a + 1 == n { 0 } else { a + 1 };
            let cb = code_of(b);
            let (da, db) = (ring[a].d, ring[b].d);
            if ca & cb != 0 {
                // Outside one plane at both ends: the whole arc is.
                (a, ca) = (b, cb);
                continue;
            }
            if ca == 0 && cb == 0 {
                let Some((start, _)) = piece else {
                    return false;
                };
                put(ov, start, db, ring[b].id, false);
                (a, ca) = (b, cb);
                continue;
            }
            // The part of the chord in the box: `t` in `(t0, t1)`, entering by side `s0` (the
            // plane of the last entry) and leaving by `s1` (of the first exit).
            let (mut t0, mut t1) = (0.0f64, 1.0f64);
            let (mut s0, mut s1) = (usize::MAX, usize::MAX);
            let mut vals = [(0.0f64, 0.0f64); 4];
            for (j, pl) in self.planes.iter().enumerate() {
                let (sa, sb) = (pl.dot(da), pl.dot(db));
                vals[j] = (sa, sb);
                // `sa` and `sb` are not both negative (the codes share no plane): `t` is in
                // `[0, 1]`.
                if sa < 0.0 {
                    let t = sa / (sa - sb);
                    if s0 == usize::MAX || t > t0 {
                        (t0, s0) = (t, j);
                    }
                } else if sb < 0.0 {
                    let t = sa / (sa - sb);
                    if s1 == usize::MAX || t < t1 {
                        (t1, s1) = (t, j);
                    }
                }
            }
            if ca != 0 {
                // Ending inside, the edge enters (at `b` itself where `b` lies on the plane of
                // the entry, `t0 = 1`); ending outside, it may pass the box by or touch it.
                if s0 == usize::MAX || (cb != 0 && !(t0 < t1)) {
                    (a, ca) = (b, cb);
                    continue;
                }
                if piece.is_some() {
                    return false;
                }
                let (sa, sb) = vals[s0];
                let start = ov.pts.len();
                piece = Some((start, s0));
                put(ov, start, cut(da, sa, db, sb), *fresh, false);
                *fresh += 1;
            }
            let Some((start, entered)) = piece else {
                return false;
            };
            if cb == 0 {
                put(ov, start, db, ring[b].id, false);
            } else {
                // Leaving: along the boundary back to the side it entered.
                if s1 == usize::MAX {
                    return false;
                }
                let (sa, sb) = vals[s1];
                put(ov, start, cut(da, sa, db, sb), *fresh, true);
                *fresh += 1;
                // Either way round is valid: the one through fewer corners (points the
                // overlay then handles).
                let (p, end) = (SIDE_POS[s1], SIDE_POS[entered]);
                let ccw = (end + 4 - p) % 4;
                let corners = (0..ccw.min(4 - ccw)).map(|i| {
                    if ccw <= 2 {
                        // Counter-clockwise: the corners after the sides from the exit's on.
                        (p + i) % 4
                    } else {
                        // Clockwise: the corners before the sides from the exit's back.
                        (p + 3 - i) % 4
                    }
                });
                for k in corners {
                    let (q, d) = self.corners[k];
                    put(ov, start, d, *fresh, true);
                    if let Some(last) = ov.pts.last_mut() {
                        last.p = q;
                    }
                    *fresh += 1;
                }
                if ov.pts.len() > start + 1 && ov.pts[ov.pts.len() - 1].d == ov.pts[start].d {
                    ov.pts.pop();
                }
                ov.close(start, BLOCKER);
                piece = None;
            }
            (a, ca) = (b, cb);
        }
        piece.is_none()
    }
}

/// `ring` clipped to the intersection of the half-spaces `n . d >= 0` of `planes`
/// (Sutherland–Hodgman on direction vectors: a cut point is a positive combination of its
/// edge's ends), each cut point given a fresh identity and the edge from each exit point (which
/// runs along the plane to the next entry) marked as a bridge; `false` when nothing is left.
fn clip_to_planes(
    ring: &mut Vec<RingPoint>,
    tmp: &mut Vec<RingPoint>,
    planes: &[DVec3; 4],
    fresh: &mut u64,
) -> bool {
    for n in planes {
        let (mut any_out, mut any_in) = (false, false);
        for q in ring.iter() {
            let s = n.dot(q.d);
            any_out |= s < 0.0;
            any_in |= s >= 0.0;
        }
        if !any_out {
            continue;
        }
        if !any_in {
            return false;
        }
        tmp.clear();
        // A cut at a vertex on the plane repeats it: of consecutive points in the same
        // direction, the later is kept (cyclically), whose flag is the edge's that leaves it.
        let mut push = |q: RingPoint| match tmp.last_mut() {
            Some(last) if last.d == q.d => *last = q,
            _ => tmp.push(q),
        };
        let mut prev = ring[ring.len() - 1];
        let mut sp = n.dot(prev.d);
        for &cur in ring.iter() {
            let sc = n.dot(cur.d);
            if sc >= 0.0 {
                if sp < 0.0 {
                    // Entering: the rest of the edge `prev -> cur` follows.
                    push(RingPoint {
                        p: DVec2::ZERO,
                        d: cut(prev.d, sp, cur.d, sc),
                        id: *fresh,
                        bridge: prev.bridge,
                    });
                    *fresh += 1;
                }
                push(cur);
            } else if sp >= 0.0 {
                // Leaving: along the plane to the next entry.
                push(RingPoint {
                    p: DVec2::ZERO,
                    d: cut(prev.d, sp, cur.d, sc),
                    id: *fresh,
                    bridge: true,
                });
                *fresh += 1;
            }
            (prev, sp) = (cur, sc);
        }
        if tmp.len() > 1 && tmp[tmp.len() - 1].d == tmp[0].d {
            tmp.pop();
        }
        core::mem::swap(ring, tmp);
        if ring.len() < 3 {
            return false;
        }
    }
    true
}

/// The point of the chord `a-b` where the sides `sa`, `sb` (of opposite signs, or one of them
/// zero: then that end itself) vanish.
#[inline]
fn cut(a: DVec3, sa: f64, b: DVec3, sb: f64) -> DVec3 {
    if sa == 0.0 {
        return a;
    }
    if sb == 0.0 {
        return b;
    }
    let (wa, wb) = (sb.abs(), sa.abs());
    (a * wa + b * wb) / (wa + wb)
}

/// The number of front faces of `mesh` (by [`FacingAt::front`] from `x`) that the ray from `x`
/// along `d` (world) passes through inside, found through the mesh's hierarchy `bvh`; `None`
/// where the ray passes within rounding of a front face's edge, or (without `bvh`) where it
/// meets the mesh's bounding sphere.
fn front_cover(mesh: &TriangleMesh, bvh: Option<&Bvh>, x: DVec3, d: DVec3) -> Option<i32> {
    // A ray that misses the mesh's bounding sphere (beyond rounding) meets no face.
    let bs = mesh.bounding_sphere();
    let y = bs.center - x;
    let along = y.dot(d) / d.length_squared();
    let miss = if along <= 0.0 {
        y.length_squared()
    } else {
        (y - d * along).length_squared()
    };
    if miss > bs.radius * bs.radius * (1.0 + 1e-9) + 1e-9 * y.length_squared() {
        return Some(0);
    }
    let bvh = bvh?;
    let at = FacingAt::new(mesh, x);
    let (verts, tris) = (mesh.vertices(), mesh.triangles());
    let (normals, offsets) = (mesh.normals(), mesh.offsets());
    let dn = norm1(d);
    let (mut count, mut ok) = (0i32, true);
    bvh.for_each(
        |lo, hi| ray_meets_box(x, d, lo, hi),
        |t| {
            let f = t as usize;
            if !ok || !at.front(normals[f], offsets[f]) {
                return;
            }
            let [a, b, c] = tris[f].map(|i| verts[i as usize] - x);
            // A front face runs clockwise seen from `x`'s side: the ray is inside where all
            // three `det(p, q, d)` of its edges are negative.
            let mut inside = true;
            for (p, q) in [(a, b), (b, c), (c, a)] {
                let s = p.cross(q).dot(d);
                if s.abs() <= 1e-12 * norm1(p) * norm1(q) * dn {
                    ok = false;
                    return;
                }
                inside &= s < 0.0;
            }
            count += i32::from(inside);
        },
    );
    ok.then_some(count)
}

/// Whether the ray from `x` along `d` may meet the box `[lo, hi]` (widened by `1e-9` of its
/// size and position, beyond the rounding of the slab test).
fn ray_meets_box(x: DVec3, d: DVec3, lo: DVec3, hi: DVec3) -> bool {
    let m = 1e-9
        * ((hi - lo).max_element() + lo.abs().max(hi.abs()).max_element() + x.abs().max_element());
    let (lo, hi) = (lo - DVec3::splat(m), hi + DVec3::splat(m));
    let (mut t0, mut t1) = (0.0f64, f64::INFINITY);
    for i in 0..3 {
        if d[i] == 0.0 {
            if x[i] < lo[i] || x[i] > hi[i] {
                return false;
            }
            continue;
        }
        let (a, b) = ((lo[i] - x[i]) / d[i], (hi[i] - x[i]) / d[i]);
        t0 = t0.max(a.min(b));
        t1 = t1.min(a.max(b));
    }
    t0 <= t1
}

/// `|v|_1`.
#[inline]
fn norm1(v: DVec3) -> f64 {
    v.x.abs() + v.y.abs() + v.z.abs()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn box_area(pts: &[RingPoint]) -> f64 {
        let (mut lo, mut hi) = (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY));
        for q in pts {
            lo = lo.min(q.p);
            hi = hi.max(q.p);
        }
        (hi - lo).x * (hi - lo).y
    }

    /// A square with its corners on the chart's axes: turned, the axes run along its edges,
    /// the box's area halves, the chart stays a rotation of the first (`u x v = c`) and the
    /// points are projected in the new chart.
    #[test]
    fn align_chart_fits_the_box_to_a_turned_square() {
        let mut chart = Chart {
            c: DVec3::Z,
            u: DVec3::X,
            v: DVec3::Y,
        };
        let mut pts: Vec<RingPoint> = (0..4)
            .map(|k| {
                let a = core::f64::consts::FRAC_PI_2 * k as f64;
                let d = DVec3::new(0.2 * a.cos(), 0.2 * a.sin(), 1.0) * 3.0;
                RingPoint {
                    p: chart.project(d),
                    d,
                    id: k,
                    bridge: false,
                }
            })
            .collect();
        let before = box_area(&pts);
        align_chart(&mut chart, &mut pts);
        let after = box_area(&pts);
        assert!((after - 0.5 * before).abs() < 1e-12, "{before} -> {after}");
        assert!((chart.u.cross(chart.v) - chart.c).length() < 1e-15);
        assert!(chart.u.dot(chart.c).abs() < 1e-15 && chart.v.dot(chart.c).abs() < 1e-15);
        for q in &pts {
            assert_eq!(q.p, chart.project(q.d));
        }
    }

    /// The winding number of the closed polygon `pts` about `q`, or `None` within `1e-9` of an
    /// edge (for the test: its points are well spread).
    fn planar_winding(pts: &[DVec2], q: DVec2) -> Option<i32> {
        let mut w = 0;
        for k in 0..pts.len() {
            let (a, b) = (pts[k], pts[(k + 1) % pts.len()]);
            let cross = (b - a).perp_dot(q - a);
            let len = (b - a).length();
            let t = (q - a).dot(b - a) / (len * len);
            if (-1e-9..=1.0 + 1e-9).contains(&t) && cross.abs() <= 1e-9 * len {
                return None;
            }
            if a.y <= q.y {
                if b.y > q.y && cross > 0.0 {
                    w += 1;
                }
            } else if b.y <= q.y && cross < 0.0 {
                w -= 1;
            }
        }
        Some(w)
    }

    /// Rings in and around the box, self-crossing, winding about it or not, some of their
    /// vertices on its planes, cut into pieces and closed along its boundary
    /// ([`BoxClip::pieces`]): inside the box the pieces wind as the ring does up to one
    /// constant (what the cone-culled path restores with its ray), whether the ring is given
    /// closed or as an open chain from an outside vertex back to it.
    #[test]
    fn box_pieces_wind_as_the_ring_up_to_a_constant() {
        let chart = Chart {
            c: DVec3::Z,
            u: DVec3::X,
            v: DVec3::Y,
        };
        let (lo, hi) = (DVec2::new(-0.5, -0.4), DVec2::new(0.6, 0.5));
        let (c, u, v) = (chart.c, chart.u, chart.v);
        let planes = [hi.x * c - u, u - lo.x * c, hi.y * c - v, v - lo.y * c];
        let clip = BoxClip::new(&planes, lo, hi, c, u, v);
        let mut rnd = crate::math::test_unit_stream(0x5EED);
        let (mut checked, mut cut_rings, mut constants) = (0, 0, [0; 2]);
        for case in 0..400 {
            let n = 3 + (rnd() * 12.0) as usize;
            let spread = [0.3, 1.0, 2.5][case % 3];
            let mut pts: Vec<DVec2> = (0..n)
                .map(|_| DVec2::new(rnd() - 0.5, rnd() - 0.5) * 2.0 * spread)
                .collect();
            // Vertices on the box's planes and corners.
            if case % 4 == 1 {
                pts[0].x = hi.x;
                pts[n - 1] = lo;
            }
            // A ring around the box, once or twice.
            if case % 5 == 2 {
                let turns = 1 + case % 2;
                pts = (0..8 * turns)
                    .map(|k| {
                        let a = core::f64::consts::TAU * k as f64 / 8.0;
                        DVec2::new(a.cos(), a.sin()) * (1.5 + 0.3 * rnd())
                    })
                    .collect();
            }
            let ring: Vec<RingPoint> = pts
                .iter()
                .enumerate()
                .map(|(k, &p)| RingPoint {
                    p: DVec2::ZERO,
                    d: (c + u * p.x + v * p.y) * (0.5 + rnd()),
                    id: k as u64,
                    bridge: false,
                })
                .collect();
            for open in [false, true] {
                let mut chain = ring.clone();
                if open {
                    // From an outside vertex round to it again.
                    let Some(k) = chain.iter().position(|q| clip.code(q.d) != 0) else {
                        continue;
                    };
                    chain.rotate_left(k);
                    chain.push(chain[0]);
                }
                let mut ov = Overlay::default();
                let mut fresh = FRESH_IDS;
                assert!(clip.pieces(&chain, open, &chart, &mut ov, &mut fresh));
                cut_rings += ov.ends.len();
                // Every point in the box (cut points on its sides within rounding).
                for q in &ov.pts {
                    let p = chart.project(q.d);
                    let e = 1e-12;
                    assert!(
                        p.cmpge(lo - e).all() && p.cmple(hi + e).all(),
                        "{p} outside"
                    );
                }
                let mut constant = None;
                for i in 0..7 {
                    for j in 0..7 {
                        let f = DVec2::new(0.07 + 0.14 * i as f64, 0.05 + 0.15 * j as f64);
                        let q = lo + (hi - lo) * f;
                        let (Some(wp), Some(wr)) =
                            (ov.winding(0, BLOCKER, q), planar_winding(&pts, q))
                        else {
                            continue;
                        };
                        checked += 1;
                        let k = *constant.get_or_insert(wp - wr);
                        assert_eq!(wp - wr, k, "case {case} open {open} at {q}");
                    }
                }
                constants[usize::from(constant.is_some_and(|k| k != 0))] += 1;
            }
        }
        // Enough directions checked, rings cut, and both zero and nonzero constants met.
        assert!(checked > 20_000 && cut_rings > 300, "{checked} {cut_rings}");
        assert!(constants[0] > 50 && constants[1] > 50, "{constants:?}");
    }
}
