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
//! It declines (the caller takes the general path) where the light is wider than one chart, a
//! mesh light's contour reaches the horizon, the point lies in the box of a component of the
//! mesh light or of a blocker component in the shaft, the region before the overlay is not a set of simple rings, or the overlay declines
//! within rounding.

use alloc::boxed::Box;
use alloc::vec::Vec;

use glam::{DVec2, DVec3};

use super::contour::{Cull, chain_rings};
use super::cull::Shaft;
use super::overlay::{BLOCKER, LIGHT, Overlay, RingPoint};
use super::{Blocker, ClipVisibility, Pieces};
use crate::solid::{Body, ShadingFrame};

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
    next: Vec<u32>,
    ring: Vec<u32>,
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
            next: Vec::with_capacity(SCRATCH_VERTICES),
            ring: Vec::with_capacity(SCRATCH_VERTICES),
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
        let chart = Chart { c, u, v };
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
                &mut s.edges,
                |i| frame.to_local(verts[i as usize]),
                &mut s.next,
                &mut s.ring,
                |ring| {
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
                s.edges.clear();
                if !mc.contour(mesh, x, Cull::Shaft(&shaft), &mut s.edges) {
                    return false;
                }
                let verts = mesh.vertices();
                let base = (self.slot(b) as u64 + 1) << 32;
                let (ov, buf, cut) = (&mut s.overlay, &mut s.buf, &mut s.cut);
                let ok = chain_rings(
                    &mut s.edges,
                    |i| frame.to_local(verts[i as usize]),
                    &mut s.next,
                    &mut s.ring,
                    |ring| {
                        buf.clear();
                        for &i in ring.iter().rev() {
                            buf.push(RingPoint {
                                p: DVec2::ZERO,
                                d: frame.to_local(verts[i as usize]),
                                id: base | u64::from(i),
                                bridge: false,
                            });
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
                if !ok {
                    return false;
                }
            }
        }
        if !mesh_light && s.overlay.family.iter().all(|&f| f == LIGHT) {
            // No blocker reaches the box: the region is the light's.
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
        let mut prev = ring[ring.len() - 1];
        let mut sp = n.dot(prev.d);
        for &cur in ring.iter() {
            let sc = n.dot(cur.d);
            if sc >= 0.0 {
                if sp < 0.0 {
                    // Entering: the rest of the edge `prev -> cur` follows.
                    tmp.push(RingPoint {
                        p: DVec2::ZERO,
                        d: cut(prev.d, sp, cur.d, sc),
                        id: *fresh,
                        bridge: prev.bridge,
                    });
                    *fresh += 1;
                }
                tmp.push(cur);
            } else if sp >= 0.0 {
                // Leaving: along the plane to the next entry.
                tmp.push(RingPoint {
                    p: DVec2::ZERO,
                    d: cut(prev.d, sp, cur.d, sc),
                    id: *fresh,
                    bridge: true,
                });
                *fresh += 1;
            }
            (prev, sp) = (cur, sc);
        }
        // A cut at a vertex on the plane repeats it: the later copy is kept, whose flag is the
        // edge's that leaves the point.
        ring.clear();
        for (k, q) in tmp.iter().enumerate() {
            let next = tmp[(k + 1) % tmp.len()];
            if next.d != q.d {
                ring.push(*q);
            }
        }
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
