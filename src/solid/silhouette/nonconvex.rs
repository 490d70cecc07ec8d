//! The silhouette of a closed, possibly non-convex triangle mesh seen from a point (thesis 003
//! section 4.3): contour edges, split at their apparent intersections (eq. 4.4), the segments
//! that bound the projection kept, chained into rings.
//!
//! The region computed is `U = union of proj(f)` over the front faces `f` (by the facing
//! predicate, [`face_side`](crate::solid::face_side)): for a point outside the solid, the
//! directions in which it sees the mesh. Its boundary lies on the contour edges (edges between
//! a front and a non-front face), since an edge between two front faces has one of them on
//! either side of its projection. The contour arcs are split where they cross each other; each
//! piece then lies on the boundary of `U` exactly when the side away from its own front face is
//! not covered, which is decided at one interior point of the piece (the thesis's ray test,
//! done here as an exact test against the projections of the other front faces). Kept pieces
//! meet in pairs at crossings and at mesh vertices, where they are paired by angle.
//!
//! Every decision is exact or filtered: crossings and coverage use Shewchuk's `orient3d` on the
//! mesh's coordinates and the point; the order of crossings along an edge and the angular
//! order at a vertex use floating-point values with error bounds, and a decision within the
//! bound is a give-up ([`GeomError::Undecidable`]), as is an exact degeneracy (the point on a
//! plane through an edge and a vertex of another contour edge). The combinatorial result (the
//! rings as pieces of mesh edges, [`Outline`]) is what the BSP precomputation stores per cell.

use alloc::vec;
use alloc::vec::Vec;

use glam::DVec3;
use robust::orient3d;
use smallvec::SmallVec;

use super::rings::SilhouetteRings;
use crate::GeomError;
use crate::math::atan2;
use crate::solid::facing::{Side, face_distances};
use crate::solid::{ClosedMesh, ShadingFrame, TriangleMesh};
use crate::sphere::SphericalPolygon;
use crate::sphere::predicates::c3;

/// Relative error bound of the determinant of three edge-plane normals (each a cross product of
/// two vectors from the point to mesh vertices), relative to the product of the six lengths:
/// the normals carry about `4 eps` relative error each and the determinant adds `5 eps`
/// (`eps = 2^-53`), about `2e-15`; the bound keeps a factor 5 on top.
pub(crate) const ORDER_ERROR: f64 = 1e-14;

/// Relative error bound of `((a - x) x (b - x)) . (c - x)` evaluated in floating point,
/// relative to `|a - x| |b - x| |c - x|`: the differences, the cross and the dot product carry
/// a few `eps` each (`eps = 2^-53`); beyond the bound the sign is exact without `orient3d`.
const CROSS_ERROR: f64 = 1e-14;

/// Angular gap (radians) below which two contour edges leaving a vertex are too close in
/// direction to be ordered (their tangents carry about `1e-16` of rounding relative to the
/// angle subtended, far below this).
const ANGLE_GAP: f64 = 1e-12;

/// One arc of a silhouette ring: a piece of mesh edge `edge` (an index into
/// [`TriangleMesh::edges`]), run from `a` to `b` when `forward` (else from `b` to `a`),
/// starting at the edge's start vertex, or, when `from_crossing`, where the edge crosses (seen
/// from the point) the edge of the previous arc of the ring. It ends where the next arc starts.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub(crate) struct Arc {
    pub edge: u32,
    pub forward: bool,
    pub from_crossing: bool,
}

/// The combinatorial silhouette seen from a point: which arcs of which edges bound the region.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) enum Outline {
    /// No front face: the mesh covers nothing.
    Empty,
    /// Front faces but no contour: they cover the whole sphere (a point in a closed cavity).
    Full,
    /// Rings of arcs: `arcs[ends[k - 1]..ends[k]]` is ring `k`.
    Rings { arcs: Vec<Arc>, ends: Vec<u32> },
}

const GIVE_UP_POLYGON: &str =
    "the rings of a non-convex silhouette are not a valid spherical polygon within rounding";
const GIVE_UP_DEGENERATE: &str = "the point lies on a plane through a contour edge and a vertex of another (a vertex appears on a contour edge)";
const GIVE_UP_ORDER: &str = "crossings on a contour edge are too close to order within rounding";
const GIVE_UP_ANGLE: &str =
    "contour edges at a vertex are too close in direction to order within rounding";
const GIVE_UP_CHAIN: &str =
    "the kept silhouette pieces do not pair up (a decision within rounding)";

/// The region a closed mesh covers seen from the frame's point, in the local frame: the union
/// of the projections of its front faces (thesis 003 section 4.3, made exact; see the module
/// documentation). Rings meet only at shared vertices; a projection with holes (a torus seen
/// along its axis) has them; a point inside a closed cavity sees the full sphere, and a point
/// with no front face (inside the solid, where it is convex) sees nothing.
///
/// # Examples
///
/// ```
/// use arealight::glam::DVec3;
/// use arealight::solid::{ClosedMesh, ShadingFrame, nonconvex_silhouette};
/// use arealight::internals::torus;
/// // A torus (tube radius 0.3 about a circle of radius 1) seen from far along its axis: one
/// // outer ring and one hole.
/// let solid = ClosedMesh::new(torus(1.0, 0.3, 24, 12)?)?;
/// let frame = ShadingFrame::new(DVec3::new(0.0, 0.0, -20.0), DVec3::Z, DVec3::Z)?;
/// let sil = nonconvex_silhouette(&solid, &frame)?;
/// assert_eq!(sil.ring_count(), 2);
/// assert!(!sil.contains(DVec3::Z)); // the axis is seen through the hole
/// # Ok::<(), arealight::GeomError>(())
/// ```
///
/// # Errors
///
/// [`GeomError::Undecidable`] when a decision is within rounding or exactly degenerate: the
/// point on a plane through a contour edge and a vertex of another one (in particular in the
/// plane of a face that bounds the silhouette, or on the surface), crossings or directions too
/// close to order, or rings that are not a valid polygon after rounding. A caller falls back to
/// the union of the front faces' projections for such points.
pub fn nonconvex_silhouette(
    solid: &ClosedMesh,
    frame: &ShadingFrame,
) -> Result<SphericalPolygon, GeomError> {
    let mesh = solid.mesh();
    let outline = outline(solid, frame.origin())?;
    match &outline {
        Outline::Empty => Ok(SphericalPolygon::empty()),
        Outline::Full => Ok(SphericalPolygon::full()),
        Outline::Rings { arcs, ends } => {
            let rings = evaluate_rings(mesh, arcs, ends, frame)?;
            SphericalPolygon::new(rings).map_err(|e| e.give_up(GIVE_UP_POLYGON))
        }
    }
}

/// A contour edge seen from the point: its mesh edge, its direction (front face on the left on
/// the sphere) and the vertices in that direction.
#[derive(Debug, Clone, Copy)]
struct Contour {
    edge: u32,
    forward: bool,
    front_face: u32,
    start: u32,
    end: u32,
    /// `start - x` and `end - x` (world axes).
    s: DVec3,
    t: DVec3,
    /// `s x t`: the normal of the plane through the point and the edge, in the edge's direction.
    n: DVec3,
    /// `|s| |t|`, the scale of `n`.
    nlen: f64,
}

/// A crossing on a contour edge: the other contour edge, the sign `sigma` with which
/// `n_self x n_other` points at the crossing, and its node id.
#[derive(Debug, Clone, Copy)]
struct Crossing {
    other: u32,
    sigma: i8,
    node: u32,
}

/// A piece of a contour edge between consecutive split points, by node ids (vertex nodes are
/// the vertex indices, crossing nodes follow them).
#[derive(Debug, Clone, Copy)]
struct Piece {
    contour: u32,
    from: u32,
    to: u32,
    from_crossing: bool,
}

fn sign(x: f64) -> i8 {
    if x > 0.0 {
        1
    } else if x < 0.0 {
        -1
    } else {
        0
    }
}

/// `sign det(p - x, q - x, r - x)`, exactly.
fn o3(p: DVec3, q: DVec3, r: DVec3, x: DVec3) -> i8 {
    sign(orient3d(c3(p), c3(q), c3(r), c3(x)))
}

/// The combinatorial silhouette of a solid seen from `x`.
pub(crate) fn outline(solid: &ClosedMesh, x: DVec3) -> Result<Outline, GeomError> {
    outline_with(solid, x, None)
}

/// [`outline`], also reporting, for every contour edge crossed at least twice, its mesh edge
/// and the mesh edges crossing it (whose order along it the outline depends on).
pub(crate) fn outline_with(
    solid: &ClosedMesh,
    x: DVec3,
    mut crossed: Option<&mut Vec<(u32, Vec<u32>)>>,
) -> Result<Outline, GeomError> {
    if let Some(out) = crossed.as_deref_mut() {
        out.clear();
    }
    let mesh = solid.mesh();
    let lines = solid.edge_lines();
    let verts = mesh.vertices();
    let mut dist = Vec::new();
    let tol = face_distances(mesh, x, &mut dist);
    let front: Vec<bool> = dist
        .iter()
        .map(|&d| Side::of(d, tol) == Side::Front)
        .collect();
    if !front.iter().any(|&f| f) {
        return Ok(Outline::Empty);
    }
    let mut contour: Vec<Contour> = Vec::new();
    for (ei, e) in mesh.edges().iter().enumerate() {
        let Some(f1) = e.twin() else { continue };
        let (ff0, ff1) = (front[e.f0 as usize], front[f1 as usize]);
        if ff0 == ff1 {
            continue;
        }
        // f1 runs b -> a; when it is the front face, a -> b is counter-clockwise round it seen
        // from outside the sphere reversed, i.e. the front face lies on the left of a -> b on
        // the sphere (see `convex_silhouette`).
        let forward = ff1;
        let (start, end) = if forward { (e.a, e.b) } else { (e.b, e.a) };
        let (s, t) = (verts[start as usize] - x, verts[end as usize] - x);
        contour.push(Contour {
            edge: ei as u32,
            forward,
            front_face: if ff0 { e.f0 } else { f1 },
            start,
            end,
            s,
            t,
            n: s.cross(t),
            nlen: s.length() * t.length(),
        });
    }
    if contour.is_empty() {
        return Ok(Outline::Full);
    }
    let nv = verts.len() as u32;
    let k = contour.len();

    // Apparent intersections (thesis 003 eq. 4.4): the arcs of two contour edges without a
    // shared vertex cross iff each edge's endpoints lie on opposite sides of the other's plane
    // through x, and the crossing is on the minor arcs rather than their antipodes (S2's
    // crossing rule). All four signs are exact.
    let mut crossings: Vec<Vec<Crossing>> = vec![Vec::new(); k];
    let mut next_node = nv;
    let lens: Vec<(f64, f64)> = contour
        .iter()
        .map(|c| (c.s.length(), c.t.length()))
        .collect();
    // Bounding caps of the arcs: a minor arc lies within half its angle of its midpoint
    // direction. (center, cos, sin of the radius)
    let caps: Vec<(DVec3, f64, f64)> = contour
        .iter()
        .zip(&lens)
        .map(|(c, &(ls, lt))| {
            let (us, ut) = (c.s / ls, c.t / lt);
            match (us + ut).try_normalize() {
                Some(m) if us.dot(ut) > -0.99 => {
                    let cr = m.dot(us);
                    (m, cr, crate::math::sqrt((1.0 - cr * cr).max(0.0)))
                }
                _ => (DVec3::Z, -1.0, 0.0),
            }
        })
        .collect();
    for i in 0..k {
        let ci = contour[i];
        let (a, b) = (verts[ci.start as usize], verts[ci.end as usize]);
        let (mi, ci_cos, ci_sin) = caps[i];
        for j in i + 1..k {
            let cj = contour[j];
            let (mj, cj_cos, cj_sin) = caps[j];
            // Disjoint caps (with a margin far above the rounding of the caps): no crossing.
            if ci_cos > -1.0
                && cj_cos > -1.0
                && mi.dot(mj) < ci_cos * cj_cos - ci_sin * cj_sin - 1e-9
            {
                continue;
            }
            if cj.start == ci.start
                || cj.start == ci.end
                || cj.end == ci.start
                || cj.end == ci.end
                || lines[ci.edge as usize] == lines[cj.edge as usize]
                || solid.on_edge_line(ci.edge, cj.start)
                || solid.on_edge_line(ci.edge, cj.end)
                || solid.on_edge_line(cj.edge, ci.start)
                || solid.on_edge_line(cj.edge, ci.end)
            {
                // Shared vertex (handled at the vertex), or one edge's endpoint on the other's
                // line: its arc meets the other's circle only there, off the other's arc.
                continue;
            }
            let (c, d) = (verts[cj.start as usize], verts[cj.end as usize]);
            // det(a - x, b - x, c - x) ~ n_i . (c - x), exact where the filter decides.
            let sign_of = |n: DVec3, nlen: f64, w: DVec3, wlen: f64, p, q, r| {
                let v = n.dot(w);
                let bound = CROSS_ERROR * nlen * wlen;
                if v > bound {
                    1
                } else if v < -bound {
                    -1
                } else {
                    o3(p, q, r, x)
                }
            };
            let abc = sign_of(ci.n, ci.nlen, cj.s, lens[j].0, a, b, c);
            let abd = sign_of(ci.n, ci.nlen, cj.t, lens[j].1, a, b, d);
            if abc * abd > 0 {
                continue;
            }
            let cda = sign_of(cj.n, cj.nlen, ci.s, lens[i].0, c, d, a);
            let cdb = sign_of(cj.n, cj.nlen, ci.t, lens[i].1, c, d, b);
            if cda * cdb > 0 {
                continue;
            }
            if abc == 0 || abd == 0 || cda == 0 || cdb == 0 {
                // An endpoint on the other edge's great circle. A minor arc meets a great
                // circle it does not lie on once at most, so the arcs can only touch there:
                // where that endpoint is off the other arc, they do not meet.
                let touch = (abc == 0 && on_arc(c, a, b, x)?)
                    || (abd == 0 && on_arc(d, a, b, x)?)
                    || (cda == 0 && on_arc(a, c, d, x)?)
                    || (cdb == 0 && on_arc(b, c, d, x)?);
                if touch || (abc == 0 && abd == 0) {
                    // A vertex seen on a contour edge, or both edges on one great circle.
                    if !(abc == 0 && abd == 0 && collinear(a, b, c) && collinear(a, b, d)) {
                        return Err(GeomError::Undecidable(GIVE_UP_DEGENERATE));
                    }
                }
                // Disjoint segments of one line project to disjoint arcs of one circle.
                continue;
            }
            if abd != cda {
                continue; // the great circles cross at the antipodes of the arcs
            }
            // (a x b) x (c x d) = c det(a, b, d) - d det(a, b, c), a positive combination of c
            // and d times sign det(a, b, d): the crossing is at sigma (n_i x n_j), sigma = abd;
            // symmetrically at cdb (n_j x n_i) on edge j.
            crossings[i].push(Crossing {
                other: j as u32,
                sigma: abd,
                node: next_node,
            });
            crossings[j].push(Crossing {
                other: i as u32,
                sigma: cdb,
                node: next_node,
            });
            next_node += 1;
        }
    }

    // Order the crossings along each edge: p_g comes before p_h (from start to end) iff
    // (p_g x p_h) . n > 0, i.e. sigma_g sigma_h det(n, n_g, n_h) > 0, since
    // (n x n_g) x (n x n_h) = det(n, n_g, n_h) n.
    for (i, list) in crossings.iter_mut().enumerate() {
        if list.len() < 2 {
            continue;
        }
        let ci = contour[i];
        let len_i = ci.s.length() * ci.t.length();
        // Insertion sort with a filtered comparator; any comparison within rounding gives up.
        for m in 1..list.len() {
            let mut p = m;
            while p > 0 {
                let (g, h) = (list[p - 1], list[p]);
                let (cg, ch) = (contour[g.other as usize], contour[h.other as usize]);
                let det = ci.n.dot(cg.n.cross(ch.n));
                let bound = ORDER_ERROR
                    * len_i
                    * cg.s.length()
                    * cg.t.length()
                    * ch.s.length()
                    * ch.t.length();
                if !(det.abs() > bound) {
                    return Err(GeomError::Undecidable(GIVE_UP_ORDER));
                }
                let g_first = (i32::from(g.sigma * h.sigma) * i32::from(sign(det))) > 0;
                if g_first {
                    break;
                }
                list.swap(p - 1, p);
                p -= 1;
            }
        }
    }

    if let Some(out) = crossed {
        out.clear();
        for (i, list) in crossings.iter().enumerate() {
            if list.len() >= 2 {
                out.push((
                    contour[i].edge,
                    list.iter()
                        .map(|c| contour[c.other as usize].edge)
                        .collect(),
                ));
            }
        }
    }

    // Split the contour edges into pieces and keep those on the boundary of U.
    let front_faces: Vec<u32> = (0..front.len() as u32)
        .filter(|&f| front[f as usize])
        .collect();
    let cover = Coverage::new(mesh, x, &front_faces);
    let mut pieces: Vec<Piece> = Vec::new();
    for (i, ci) in contour.iter().enumerate() {
        let list = &crossings[i];
        let point_of = |node: u32, other: Option<u32>| -> DVec3 {
            match other {
                None => verts[node as usize] - x,
                Some(g) => crossing_point(ci.s, ci.t, contour[g as usize].n),
            }
        };
        let mut from = (ci.start, None::<u32>);
        for step in 0..=list.len() {
            let to = if step < list.len() {
                (list[step].node, Some(list[step].other))
            } else {
                (ci.end, None)
            };
            let (p, q) = (point_of(from.0, from.1), point_of(to.0, to.1));
            // A point of the piece's interior, with x as origin.
            let mid = (p + q) * 0.5;
            if !cover.covers(mid, ci.front_face) {
                pieces.push(Piece {
                    contour: i as u32,
                    from: from.0,
                    to: to.0,
                    from_crossing: from.1.is_some(),
                });
            }
            from = to;
        }
    }
    if pieces.is_empty() {
        // Every contour piece is covered on both sides: U has no boundary, and it is not empty.
        return Ok(Outline::Full);
    }

    // Link each piece to the piece that continues the boundary after it.
    let nnodes = next_node as usize;
    let mut ins: Vec<Vec<u32>> = vec![Vec::new(); nnodes];
    let mut outs: Vec<Vec<u32>> = vec![Vec::new(); nnodes];
    for (pi, p) in pieces.iter().enumerate() {
        outs[p.from as usize].push(pi as u32);
        ins[p.to as usize].push(pi as u32);
    }
    let mut next = vec![u32::MAX; pieces.len()];
    for node in 0..nnodes {
        let (ni, no) = (&ins[node], &outs[node]);
        if ni.len() != no.len() {
            return Err(GeomError::Undecidable(GIVE_UP_CHAIN));
        }
        match ni.len() {
            0 => {}
            1 => next[ni[0] as usize] = no[0],
            _ if node >= nv as usize => return Err(GeomError::Undecidable(GIVE_UP_CHAIN)),
            _ => pair_at_vertex(verts[node] - x, ni, no, &pieces, &contour, &mut next)?,
        }
    }

    // Walk the rings.
    let mut arcs = Vec::with_capacity(pieces.len());
    let mut ends = Vec::new();
    let mut used = vec![false; pieces.len()];
    for first in 0..pieces.len() {
        if used[first] {
            continue;
        }
        let mut at = first;
        while !used[at] {
            used[at] = true;
            let p = pieces[at];
            let c = contour[p.contour as usize];
            arcs.push(Arc {
                edge: c.edge,
                forward: c.forward,
                from_crossing: p.from_crossing,
            });
            at = next[at] as usize;
            if at >= pieces.len() {
                return Err(GeomError::Undecidable(GIVE_UP_CHAIN));
            }
        }
        if at != first {
            return Err(GeomError::Undecidable(GIVE_UP_CHAIN));
        }
        ends.push(arcs.len() as u32);
    }
    Ok(Outline::Rings { arcs, ends })
}

/// Whether the points `a`, `b`, `c` lie on one line (exact: the three coordinate-plane
/// projections of the triangle have zero area).
pub(crate) fn collinear(a: DVec3, b: DVec3, c: DVec3) -> bool {
    use robust::{Coord, orient2d};
    let xy = |p: DVec3| Coord { x: p.x, y: p.y };
    let yz = |p: DVec3| Coord { x: p.y, y: p.z };
    let zx = |p: DVec3| Coord { x: p.z, y: p.x };
    orient2d(xy(a), xy(b), xy(c)) == 0.0
        && orient2d(yz(a), yz(b), yz(c)) == 0.0
        && orient2d(zx(a), zx(b), zx(c)) == 0.0
}

/// Whether the direction of `p` (seen from `x`), known to lie on the great circle of the arc
/// from `a` to `b` (seen from `x`), lies on the closed minor arc. A point of the segment's line
/// outside the segment is off the arc (exact); otherwise the turns `a -> p` and `p -> b` must
/// both go the arc's way, decided with a filtered test that gives up within rounding.
fn on_arc(p: DVec3, a: DVec3, b: DVec3, x: DVec3) -> Result<bool, GeomError> {
    if collinear(a, b, p) {
        // On the edge's line: a vertex of a valid solid is never inside another edge.
        return Ok(false);
    }
    let (a, b, p) = (a - x, b - x, p - x);
    let n = a.cross(b);
    // (a x p) . (a x b) and (p x b) . (a x b) are at most |p| max(|a|, |b|)^3 in magnitude.
    let bound = 1e-13 * p.length() * a.length().max(b.length()).powi(3);
    let (s1, s2) = (a.cross(p).dot(n), p.cross(b).dot(n));
    if s1.abs() <= bound || s2.abs() <= bound {
        return Err(GeomError::Undecidable(GIVE_UP_DEGENERATE));
    }
    Ok(s1 > 0.0 && s2 > 0.0)
}

/// The crossing of the segment `s -> t` (vectors from the point) with the plane through the
/// point with normal `n`: `s + u (t - s)` with `u = (n . s) / (n . s - n . t)`, evaluated from
/// the end nearer the plane (`u <= 1/2`), so that a crossing near an end close to the point
/// is not the small difference of two long vectors (its direction would lose the ratio of the
/// lengths in precision).
#[inline]
fn crossing_point(s: DVec3, t: DVec3, n: DVec3) -> DVec3 {
    let (ds, dt) = (n.dot(s), n.dot(t));
    let (base, other, db, dother) = if ds.abs() <= dt.abs() {
        (s, t, ds, dt)
    } else {
        (t, s, dt, ds)
    };
    let u = (db / (db - dother)).clamp(0.0, 1.0);
    base + (other - base) * if u.is_finite() { u } else { 0.5 }
}

/// The foot of the perpendicular from the point to the line through `s` and `t` (vectors from
/// the point), from the end nearer the point, for the reason of [`crossing_point`].
#[inline]
fn foot_point(s: DVec3, t: DVec3) -> DVec3 {
    let (p, q) = if s.length_squared() <= t.length_squared() {
        (s, t)
    } else {
        (t, s)
    };
    let d = q - p;
    p - d * (p.dot(d) / d.length_squared())
}

/// Pairs the kept pieces that end at a vertex (`ins`) with those that start there (`outs`):
/// U lies clockwise (seen from outside the sphere) of each incoming piece's backward direction
/// and counter-clockwise of each outgoing piece's direction, so an incoming piece continues
/// with the first piece met turning clockwise from it, which must be outgoing.
fn pair_at_vertex(
    v: DVec3,
    ins: &[u32],
    outs: &[u32],
    pieces: &[Piece],
    contour: &[Contour],
    next: &mut [u32],
) -> Result<(), GeomError> {
    let d = v.normalize();
    let (e1, e2) = d.any_orthonormal_pair();
    // e1 x e2 = d: angles grow counter-clockwise seen from outside.
    let angle = |w: DVec3| {
        let t = w - d * d.dot(w);
        atan2(t.dot(e2), t.dot(e1))
    };
    // (angle, piece, incoming)
    let mut around: Vec<(f64, u32, bool)> = Vec::with_capacity(ins.len() + outs.len());
    for &p in ins {
        // Backward along the edge: towards its start.
        around.push((
            angle(contour[pieces[p as usize].contour as usize].s),
            p,
            true,
        ));
    }
    for &p in outs {
        around.push((
            angle(contour[pieces[p as usize].contour as usize].t),
            p,
            false,
        ));
    }
    around.sort_by(|a, b| a.0.total_cmp(&b.0));
    let m = around.len();
    for k in 0..m {
        let gap = if k + 1 < m {
            around[k + 1].0 - around[k].0
        } else {
            around[0].0 + 2.0 * core::f64::consts::PI - around[k].0
        };
        if !(gap > ANGLE_GAP) {
            return Err(GeomError::Undecidable(GIVE_UP_ANGLE));
        }
    }
    for k in 0..m {
        let (_, p, incoming) = around[k];
        if !incoming {
            continue;
        }
        // Clockwise is the previous entry in counter-clockwise order.
        let (_, q, q_in) = around[(k + m - 1) % m];
        if q_in {
            return Err(GeomError::Undecidable(GIVE_UP_CHAIN));
        }
        next[p as usize] = q;
    }
    Ok(())
}

/// Exact coverage tests of directions by the projections of front faces, with a floating-point
/// filter: per face, the three planes through the point and its edges.
struct Coverage<'a> {
    x: DVec3,
    verts: &'a [DVec3],
    tris: &'a [[u32; 3]],
    faces: &'a [u32],
    /// Per listed face: the edge-plane normals `(p - x) x (q - x)` and the product bound
    /// `|p - x| |q - x|` of each edge.
    planes: Vec<[(DVec3, f64); 3]>,
}

/// Relative error of the filtered edge-plane test `((p - x) x (q - x)) . w`, relative to
/// `|p - x| |q - x| |w|` (a few `eps` for the differences, the cross and the dot products).
const COVER_ERROR: f64 = 1e-14;

impl<'a> Coverage<'a> {
    fn new(mesh: &'a TriangleMesh, x: DVec3, faces: &'a [u32]) -> Self {
        let verts = mesh.vertices();
        let tris = mesh.triangles();
        let planes = faces
            .iter()
            .map(|&f| {
                let t = tris[f as usize];
                let p = t.map(|i| verts[i as usize] - x);
                [0, 1, 2].map(|e| {
                    let (a, b) = (p[e], p[(e + 1) % 3]);
                    (a.cross(b), a.length() * b.length())
                })
            })
            .collect();
        Coverage {
            x,
            verts,
            tris,
            faces,
            planes,
        }
    }

    /// Whether the direction `w` (from the point) lies in the closed projection of a listed
    /// face other than `skip`. A front face's corners run clockwise seen from the point
    /// (`det(a - x, b - x, c - x) < 0`), so `w` is inside iff it is on the non-positive side of
    /// each edge plane.
    fn covers(&self, w: DVec3, skip: u32) -> bool {
        let wl = w.length();
        'faces: for (k, &f) in self.faces.iter().enumerate() {
            if f == skip {
                continue;
            }
            let mut unsure = false;
            for &(n, len) in &self.planes[k] {
                let s = n.dot(w);
                let bound = COVER_ERROR * len * wl;
                if s > bound {
                    continue 'faces;
                }
                if s >= -bound {
                    unsure = true;
                }
            }
            if !unsure {
                return true;
            }
            // Exact: w as the point x + w (both floating-point, the test is exact for it).
            let t = self.tris[f as usize].map(|i| self.verts[i as usize]);
            let q = self.x + w;
            if (0..3).all(|e| o3(t[e], t[(e + 1) % 3], q, self.x) <= 0) {
                return true;
            }
        }
        false
    }
}

/// The start and end vertices of an arc's mesh edge in the arc's direction, as vectors from the
/// frame's point in the local frame.
#[inline]
fn arc_ends(mesh: &TriangleMesh, arc: &Arc, frame: &ShadingFrame) -> (DVec3, DVec3) {
    let e = mesh.edges()[arc.edge as usize];
    let (s, t) = if arc.forward { (e.a, e.b) } else { (e.b, e.a) };
    let verts = mesh.vertices();
    (
        frame.to_local(verts[s as usize]),
        frame.to_local(verts[t as usize]),
    )
}

/// Where arc `k` of a ring starts, as a vector from the frame's point in the local frame: its
/// edge's start vertex, or the point of its edge seen in line with the previous arc's edge
/// ([`crossing_point`], always on the edge). [`evaluate_rings`] and the BSP's stored
/// triangulations both take their vertices from here, so they share them bit for bit.
pub(crate) fn arc_start(
    mesh: &TriangleMesh,
    ring: &[Arc],
    k: usize,
    frame: &ShadingFrame,
) -> DVec3 {
    let n = ring.len();
    let (s, t) = arc_ends(mesh, &ring[k], frame);
    if ring[k].from_crossing {
        let (ps, pt) = arc_ends(mesh, &ring[(k + n - 1) % n], frame);
        crossing_point(s, t, ps.cross(pt))
    } else {
        s
    }
}

/// The rings of directions (local frame) of an outline's arcs seen from the frame's point, as
/// [`evaluate_rings_into`] writes them.
pub(crate) fn evaluate_rings(
    mesh: &TriangleMesh,
    arcs: &[Arc],
    ends: &[u32],
    frame: &ShadingFrame,
) -> Result<Vec<Vec<DVec3>>, GeomError> {
    let mut out = SilhouetteRings::new();
    evaluate_rings_into(mesh, arcs, ends, frame, &mut out)?;
    Ok(out.rings().map(<[DVec3]>::to_vec).collect())
}

/// Appends to `out` the rings of unit directions (local frame) of an outline's arcs seen from
/// the frame's point. Arcs that subtend more than 120 degrees get an extra vertex at the foot of
/// the perpendicular from the point to their edge, so that no ring edge comes near half a great
/// circle.
pub(crate) fn evaluate_rings_into(
    mesh: &TriangleMesh,
    arcs: &[Arc],
    ends: &[u32],
    frame: &ShadingFrame,
    out: &mut SilhouetteRings,
) -> Result<(), GeomError> {
    let mut start = 0usize;
    let mut starts: SmallVec<[DVec3; 24]> = SmallVec::new();
    for &end in ends {
        let ring = &arcs[start..end as usize];
        let n = ring.len();
        // Start point of each arc (vectors from the point, local frame).
        starts.clear();
        starts.extend((0..n).map(|k| arc_start(mesh, ring, k, frame)));
        for k in 0..n {
            let u = starts[k]
                .try_normalize()
                .ok_or(GeomError::Undecidable(GIVE_UP_POLYGON))?;
            out.push(u);
            let w = starts[(k + 1) % n];
            if u.dot(w) < -0.5 * w.length() {
                // The foot of the perpendicular from the point to the edge's line lies between
                // the two ends of an arc wider than 90 degrees.
                let (s, t) = arc_ends(mesh, &ring[k], frame);
                if let Some(f) = foot_point(s, t).try_normalize() {
                    out.push(f);
                }
            }
        }
        out.close_ring();
        start = end as usize;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::solid::fixtures::torus;

    #[test]
    fn torus_along_its_axis_has_a_hole() {
        let solid = ClosedMesh::new(torus(1.0, 0.3, 24, 12).unwrap()).unwrap();
        let frame = ShadingFrame::new(DVec3::new(0.01, 0.02, -20.0), DVec3::Z, DVec3::Z).unwrap();
        let sil = nonconvex_silhouette(&solid, &frame).unwrap();
        assert_eq!(sil.ring_count(), 2);
        assert!(!sil.contains(DVec3::Z));
        assert!(sil.contains(DVec3::new(1.0, 0.0, 20.0)));
    }
}
