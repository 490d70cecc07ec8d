//! The visibility query of seed 002 Alg. 1 (lines 15-37): which fragments of a light polygon a
//! point sees, found by walking the lazy BSP with the polygon and splitting it by the plane
//! through the point and each node's line, developing undefined leaves on the way.
//!
//! For a point `x` and a node line `h`, the lines from `x` through a light point `e` have side
//! `det[e - x, h_a - x, h_b - x]` with `h`: the side of `e` relative to the plane through `x`
//! and `h` (seed 002 Fig. 6). So the light polygon goes whole to one child when its vertices
//! are all on one side, and is cut by that plane otherwise. Fragments stay convex; each one
//! that reaches a visible leaf is a visible part of the light.
//!
//! A fragment vertex whose side the error-bounded filter cannot certify is taken to lie on the
//! plane (it joins both parts of a split) when the plane is well conditioned: it is then within
//! `2e-12` of its distance from the point of the plane (`line.rs`, `WELL_CONDITIONED`). Such a
//! vertex is a computed cut point, typically the shadow of an occluder vertex that two node
//! planes share, whose own rounding is of that order, so an exact sign of the rounded point
//! would be no truer; taking it as on the plane avoids a sliver fragment and an adaptive
//! evaluation per shadow corner. For an ill-conditioned plane (the point near the node's line)
//! the exact sign decides, so that the two parts of a split never overlap by more than that
//! rounding. A fragment with every vertex on the plane goes to the node's zero child.
//!
//! # Edges on the tile plane
//!
//! An occluder edge made by the cut to the tile plane's upper side (`tile.rs`) lies in that
//! plane, and so does the point: the plane through the point and the edge's line is the
//! point's tangent plane, and every fragment (clipped to the closed upper side of it) lies on
//! one side, the side of `up` (the tile's normal). Such a node sends the whole fragment to the
//! child of `det[up, h_a - x, h_b - x]` (which side of the edge's line the point is on, in
//! the plane; zero for a point on the line) instead of classifying its vertices against the
//! plane through the edge's computed ends: those are cut points, rounded at the blocker's
//! size, so that plane is tilted off the tangent plane by that rounding over the point's
//! distance from the line. For a point `1e-10` from a blocker's plane that tilt was `1e-6` rad,
//! and the split it made left a horizon strip of the light visible through the blocker
//! (`tests/visibility_plucker.rs`, a point a hair below a sheet). For the same reason such an
//! edge is never taken as a separating plane in [`relevant_occluder`].

use alloc::vec::Vec;

use glam::{DVec2, DVec3};
use smallvec::SmallVec;

use super::bsp::{MAX_OCCLUDER_VERTICES, Node, Occluder, Tree};
use super::line::{Orienter, Sign};
use crate::GeomError;
use crate::planar::predicates::{monotone_hull, signed_area2};
use crate::solid::ShadingFrame;
use crate::sphere::SphericalPolygon;

/// A convex planar polygon on the light, in a tree's coordinates.
pub(crate) type Fragment = SmallVec<[DVec3; 8]>;

/// The tree outgrew its memory cap during a query.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct CapExceeded;

/// Where a fragment lies relative to a node's plane.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Class {
    /// Every vertex on the positive side or on the plane, one strictly positive.
    Pos,
    /// Every vertex on the negative side or on the plane, one strictly negative.
    Neg,
    /// Every vertex on the plane: the point lies on the node's line.
    Zero,
    /// Vertices strictly on both sides.
    Split,
}

/// Buffers a query reuses: fragments live in one pool of vertices (a fragment is a range of
/// it), so that splits append instead of moving polygons around.
#[derive(Debug, Default, Clone)]
pub(crate) struct Scratch {
    /// Node, start in `pool`, vertex count, and the split the fragment is a whole part of
    /// ([`NO_SPLIT`] for none).
    stack: Vec<(u32, u32, u32, u32)>,
    pool: Vec<DVec3>,
    /// The splits of the query into two parts: see [`Merges`].
    merges: Merges,
}

/// No split: a fragment that is not one of the two parts of a split, as a whole.
const NO_SPLIT: u32 = u32::MAX;

/// The splits of one query whose parts may come out whole, to give back the fragment that was
/// split instead of its two parts when both are visible (fewer, larger fragments, so fewer
/// spherical polygons to build and integrate).
///
/// A split of the fragment `F` by a node's plane into the parts `F+` and `F-` (both with
/// area) is recorded with `F`'s range in the pool; a part that reaches a visible leaf, or an
/// undefined leaf that the relevance test finds visible, without being split again counts as
/// visible whole for its split. When both parts of a split are visible whole, every line from
/// the point through `F+` or `F-` is unblocked, and `F` is their union (the two parts share the
/// cut edge, vertices on the plane join both): `F` is then visible whole, which counts for the
/// split `F` is a part of, and so on up. A part split again with both sub-parts recorded counts
/// for its split only through them; a part that loses a sliver to a split (one side with less
/// than three distinct points) starts a fresh chain, so no merge ever adds area that was not
/// found visible. Fragments are held until the query ends; those whose split was merged are
/// dropped, the merged fragment standing for them.
#[derive(Debug, Default, Clone)]
struct Merges {
    /// Per split: the split it is a part of, the range of `F` in the pool, how many parts are
    /// visible whole, and whether both were (then `F` stands for them).
    splits: Vec<(u32, u32, u32, u8, bool)>,
    /// Visible fragments held until the query ends: their split, their range in the pool.
    held: Vec<(u32, u32, u32)>,
}

impl Merges {
    fn clear(&mut self) {
        self.splits.clear();
        self.held.clear();
    }

    /// Records a split of the fragment `pool[s..s + len]`, itself a whole part of `parent`.
    fn split(&mut self, parent: u32, s: u32, len: u32) -> u32 {
        self.splits.push((parent, s, len, 0, false));
        (self.splits.len() - 1) as u32
    }

    /// The fragment `pool[s..s + len]`, a whole part of `split`, is visible: appended to `out`
    /// when it is no part of a split, else held, and merged up while both parts of a split are
    /// visible whole.
    fn visible(
        &mut self,
        mut split: u32,
        mut s: u32,
        mut len: u32,
        pool: &[DVec3],
        out: &mut Vec<Fragment>,
    ) {
        loop {
            if split == NO_SPLIT {
                out.push(
                    pool[s as usize..(s + len) as usize]
                        .iter()
                        .copied()
                        .collect(),
                );
                return;
            }
            self.held.push((split, s, len));
            let rec = &mut self.splits[split as usize];
            rec.3 += 1;
            if rec.3 < 2 {
                return;
            }
            rec.4 = true;
            (split, s, len) = (rec.0, rec.1, rec.2);
        }
    }

    /// Appends to `out` the held fragments whose split was not merged.
    fn flush(&mut self, pool: &[DVec3], out: &mut Vec<Fragment>) {
        for &(split, s, len) in &self.held {
            if !self.splits[split as usize].4 {
                out.push(
                    pool[s as usize..(s + len) as usize]
                        .iter()
                        .copied()
                        .collect(),
                );
            }
        }
        self.clear();
    }
}

/// The class of `frag` against the plane of `or`, with each vertex's value and sign in `vals`;
/// `bound` is the plane's filter bound for points within the reach of the query
/// ([`Orienter::eval_near_within`]).
fn classify(
    or: &Orienter,
    bound: f64,
    frag: &[DVec3],
    vals: &mut SmallVec<[(f64, Sign); 8]>,
) -> Class {
    vals.clear();
    let (mut pos, mut neg) = (false, false);
    for &e in frag {
        let (v, sign) = or.eval_near_within(e, bound);
        match sign {
            Sign::Positive => pos = true,
            Sign::Negative => neg = true,
            Sign::Zero => {}
        }
        vals.push((v, sign));
    }
    match (pos, neg) {
        (true, true) => Class::Split,
        (true, false) => Class::Pos,
        (false, true) => Class::Neg,
        (false, false) => Class::Zero,
    }
}

/// Appends `p` unless it repeats the last point.
fn push_point(out: &mut Fragment, p: DVec3) {
    if out.last() != Some(&p) {
        out.push(p);
    }
}

/// The parts of `frag` on the positive and on the negative side of the plane whose values at
/// its vertices are `vals` (certified signs decide the sides; the `f64` values only place the
/// cut points, clamped to their edge). Vertices on the plane belong to both parts. A part with
/// fewer than three distinct points is `None`.
fn split(frag: &[DVec3], vals: &[(f64, Sign)]) -> (Option<Fragment>, Option<Fragment>) {
    let n = frag.len();
    let (mut pos, mut neg) = (Fragment::new(), Fragment::new());
    for i in 0..n {
        let j = (i + 1) % n;
        let (a, b) = (frag[i], frag[j]);
        let ((va, sa), (vb, sb)) = (vals[i], vals[j]);
        if sa != Sign::Negative {
            push_point(&mut pos, a);
        }
        if sa != Sign::Positive {
            push_point(&mut neg, a);
        }
        if matches!(
            (sa, sb),
            (Sign::Positive, Sign::Negative) | (Sign::Negative, Sign::Positive)
        ) {
            let p = cut_point(a, b, va, vb);
            push_point(&mut pos, p);
            push_point(&mut neg, p);
        }
    }
    let close = |mut f: Fragment| {
        while f.len() > 1 && f.first() == f.last() {
            f.pop();
        }
        (f.len() >= 3).then_some(f)
    };
    (close(pos), close(neg))
}

/// A fragment's start in the pool and its vertex count.
type Range = (u32, u32);

/// Appends to `pool` the parts of the fragment `pool[s..s + n]` on the negative and on the
/// positive side of the plane whose values at its vertices are `vals` ([`split`], which
/// computes each cut point once for both parts), and returns their ranges, each `None` for
/// fewer than three distinct points.
fn split_parts(
    pool: &mut Vec<DVec3>,
    s: usize,
    n: usize,
    vals: &[(f64, Sign)],
) -> (Option<Range>, Option<Range>) {
    let (plus, minus) = split(&pool[s..s + n], vals);
    let mut append = |f: Option<Fragment>| {
        let f = f?;
        let start = pool.len();
        pool.extend_from_slice(&f);
        Some((start as u32, f.len() as u32))
    };
    let minus = append(minus);
    (minus, append(plus))
}

/// The point where the edge `a -> b` crosses a plane, from the plane's values `va`, `vb` at its
/// ends (of opposite certified signs), clamped to the edge. Both parts of a split compute it
/// the same way, so they share it bit for bit.
///
/// It is interpolated from the end nearer the plane: its error is then the rounding of that
/// end's offset, not of the whole edge's, which matters when the plane passes a hair from a
/// vertex (a blocker cut by the tangent plane of a point `1e-6` from it: from the far end, the
/// cut edge sat `1e-16` off the plane and left a `1e-10` rad horizon sliver unblocked).
#[inline]
fn cut_point(a: DVec3, b: DVec3, va: f64, vb: f64) -> DVec3 {
    let (near, far, vn, vf) = if va.abs() <= vb.abs() {
        (a, b, va, vb)
    } else {
        (b, a, vb, va)
    };
    let den = vn - vf;
    let t = if den != 0.0 && (vn / den).is_finite() {
        (vn / den).clamp(0.0, 1.0)
    } else {
        0.5
    };
    near + (far - near) * t
}

/// Seed 002 Alg. 1 `BSP_query`: appends to `out` the fragments of `poly` (a convex polygon on
/// the tree's light, relative to the point: `p - x` in world coordinates) that the point `x`
/// (in the tree's coordinates) sees, growing the tree where it is undefined. Fragments are
/// relative to the point too, so they are the same numbers whatever the tree's origin: the
/// point's tangent-plane cut and the directions of light points very close to it (a point
/// within a few `1e-11` of a face plane) do not pick up the rounding of the tile's offset. Stops with [`CapExceeded`] as soon as the tree's size passes `cap` bytes
/// (the tree is then valid but larger; the caller resets it). `up` is the tile plane's
/// normal, and `poly` lies on the closed upper side of the plane through `x` with that normal.
pub(crate) fn query(
    tree: &mut Tree,
    x: DVec3,
    up: DVec3,
    poly: &[DVec3],
    cap: usize,
    out: &mut Vec<Fragment>,
    scratch: &mut Scratch,
) -> Result<(), CapExceeded> {
    let mut vals: SmallVec<[(f64, Sign); 8]> = SmallVec::new();
    // Every fragment corner relative to `x` is within twice the tree's reach of the origin
    // (as in `relevant_occluder`), so the node planes' signs may take the reach bound.
    let reach = 2.0 * tree.reach();
    let Scratch {
        stack,
        pool,
        merges,
    } = scratch;
    stack.clear();
    pool.clear();
    merges.clear();
    pool.extend_from_slice(poly);
    stack.push((Tree::ROOT, 0, poly.len() as u32, NO_SPLIT));
    while let Some((mut n, mut s, mut len, mut part_of)) = stack.pop() {
        loop {
            match *tree.node(n) {
                Node::Inner {
                    occ,
                    edge,
                    pos,
                    neg,
                    zero_pos,
                    pending_len,
                    ..
                } => {
                    if pending_len > 0 {
                        tree.push_down(n);
                        if tree.bytes() > cap {
                            return Err(CapExceeded);
                        }
                    }
                    let occluder = tree.occluder(occ);
                    let (ha, hb) = occluder.edge(edge);
                    // The fragment is relative to the point: the node's line is moved there
                    // instead, so that light points close to the point keep their precision.
                    let or = Orienter::new(ha - x, hb - x, DVec3::ZERO);
                    let frag = &pool[s as usize..(s + len) as usize];
                    let class = if occluder.on_tile(edge) {
                        // See "Edges on the tile plane" in the module documentation.
                        match or.sign(up) {
                            Sign::Positive => Class::Pos,
                            Sign::Negative => Class::Neg,
                            Sign::Zero => Class::Zero,
                        }
                    } else {
                        classify(&or, or.reach_bound(reach), frag, &mut vals)
                    };
                    match class {
                        Class::Pos => n = pos,
                        Class::Neg => n = neg,
                        Class::Zero => n = if zero_pos { pos } else { neg },
                        Class::Split => {
                            let (su, lu) = (s as usize, len as usize);
                            let (minus, plus) = split_parts(pool, su, lu, &vals);
                            // Only a split into two parts with area is recorded (see
                            // `Merges`): a part that lost a sliver starts afresh.
                            let split = if minus.is_some() && plus.is_some() {
                                merges.split(part_of, s, len)
                            } else {
                                NO_SPLIT
                            };
                            if let Some((ms, ml)) = minus {
                                stack.push((neg, ms, ml, split));
                            }
                            match plus {
                                Some((ps, pl)) => {
                                    (s, len, part_of) = (ps, pl, split);
                                    n = pos;
                                }
                                None => break,
                            }
                        }
                    }
                }
                Node::Visible => {
                    merges.visible(part_of, s, len, pool, out);
                    break;
                }
                Node::Invisible => break,
                Node::Undefined { start, len: listed } => {
                    let frag = &pool[s as usize..(s + len) as usize];
                    let Some(ro) = relevant_occluder(tree, x, frag, start, listed) else {
                        // No occluder of the class can hide any line from the point through
                        // the fragment: it is visible from this point, whatever the class
                        // holds for other points of the tile.
                        tree.counters.shortcuts += 1;
                        merges.visible(part_of, s, len, pool, out);
                        break;
                    };
                    tree.expand_with(n, ro);
                    if tree.bytes() > cap {
                        return Err(CapExceeded);
                    }
                }
            }
        }
    }
    merges.flush(pool, out);
    Ok(())
}

/// An occluder of the undefined leaf's list (`len` ids from `start`) that may hide some line
/// from the point `x` (tree coordinates) through the convex fragment `frag` (relative to `x`),
/// found from a pseudo-random place in the list; `None` when a plane through `x` certifiably
/// separates every occluder of the list from the fragment, so that the fragment is visible
/// from `x`.
///
/// The leaf's list holds every occluder that may block a line of its class (seed 002 Alg. 1:
/// insertion only leaves out occluders whose blocked lines are strictly on the other side of
/// an ancestor's line), and the fragment's lines from `x` are in the class. Seed 002 merges a
/// random occluder of the list; the list is conservative for the whole tile and for the whole
/// class, so most of its occluders miss the lines of one point's fragment, and merging them
/// splits the fragment by planes that change nothing. Merging only an occluder that may block
/// the fragment develops the tree where the query needs it, and a fragment that none may block
/// needs no development at all. A separating plane is one through `x` and an edge of the
/// fragment or of the occluder (two convex cones with a common apex are disjoint iff such a
/// plane separates them), accepted only when the filter certifies every sign strictly, so a
/// doubtful occluder counts as one that may block.
fn relevant_occluder(
    tree: &mut Tree,
    x: DVec3,
    frag: &[DVec3],
    start: u32,
    len: u32,
) -> Option<u32> {
    let k = frag.len();
    let c = frag.iter().copied().sum::<DVec3>() / k as f64;
    // Every point the separation tests evaluate, an occluder vertex or a fragment corner (a
    // point of the light) relative to `x`, is within the tree's reach of the origin: `x` lies
    // in the tile (a hair off its corners' hull, far less than the reach), so twice the reach
    // bounds it after rounding.
    let reach = 2.0 * tree.reach();
    let mut planes: SmallVec<[(Orienter, f64); 8]> = SmallVec::new();
    let mut inside = None;
    for i in 0..k {
        let or = Orienter::new(frag[i], frag[(i + 1) % k], DVec3::ZERO);
        let side = or.strict_sign(c);
        if side.is_none() || (inside.is_some() && inside != side) {
            // The fragment's cone is degenerate within rounding: no plane of it is trusted.
            inside = None;
            planes.clear();
            break;
        }
        inside = side;
        planes.push((or, or.reach_bound(reach)));
    }
    let outside = inside.map(Sign::flip);
    let first = tree.pick(len as usize);
    for step in 0..len as usize {
        let i = (first + step) % len as usize;
        let o = tree.list(start, len)[i];
        if !separated(tree.occluder(o), x, frag, &planes, outside, reach) {
            return Some(o);
        }
    }
    None
}

/// Whether a plane through the origin (the point) strictly separates the occluder `occ`
/// (at `x`) from the fragment `frag`: one of the fragment's edge planes `planes` (with the
/// side `outside` away from the fragment, and each plane's bound of the filter for points
/// within `reach`), or one through an edge of the occluder not on the tile plane (see the
/// module documentation). Every point tested lies within `reach` of the origin in each
/// coordinate ([`Orienter::strict_sign_within`]).
fn separated(
    occ: &Occluder,
    x: DVec3,
    frag: &[DVec3],
    planes: &[(Orienter, f64)],
    outside: Option<Sign>,
    reach: f64,
) -> bool {
    let verts = occ.vertices();
    let mut buf = [DVec3::ZERO; MAX_OCCLUDER_VERTICES];
    for (r, &b) in buf.iter_mut().zip(verts) {
        *r = b - x;
    }
    let v = &buf[..verts.len()];
    if let Some(out) = outside {
        for (pl, bound) in planes {
            if v.iter()
                .all(|&p| pl.strict_sign_within(p, *bound) == Some(out))
            {
                return true;
            }
        }
    }
    let m = v.len();
    for j in 0..m {
        if occ.on_tile(j as u8) {
            continue;
        }
        let or = Orienter::new(v[j], v[(j + 1) % m], DVec3::ZERO);
        let Some(inner) = or.strict_sign(v[(j + 2) % m]) else {
            continue;
        };
        let away = Some(inner.flip());
        let bound = or.reach_bound(reach);
        if frag
            .iter()
            .all(|&e| or.strict_sign_within(e, bound) == away)
        {
            return true;
        }
    }
    false
}

/// Corners of a fragment's spherical polygon closer than this (chord length) are merged before
/// the polygon is built, as for projected triangles in `solid::silhouette`: far below any
/// feature the sphere layer resolves, above the rounding of a cut point.
const MERGE_TOLERANCE: f64 = 1e-13;

/// Drops the vertices of a convex polygon that repeat their predecessor within `1e-12` of the
/// longest edge or [`WELD_MAGNITUDE`] of the largest coordinate (cut points a rounding away
/// from a corner): a node line through two such points would be an ill-defined plane.
pub(crate) fn weld(poly: &mut Fragment) {
    let n = poly.len();
    let longest = (0..n)
        .map(|i| (poly[(i + 1) % n] - poly[i]).length())
        .fold(0.0, f64::max);
    let magnitude = poly
        .iter()
        .map(|p| p.abs().max_element())
        .fold(0.0, f64::max);
    let tol = (1e-12 * longest).max(WELD_MAGNITUDE * magnitude);
    let mut out = Fragment::new();
    for &p in poly.iter() {
        if out.last().is_none_or(|&q: &DVec3| (p - q).length() > tol) {
            out.push(p);
        }
    }
    while out.len() > 1 && (out[0] - out[out.len() - 1]).length() <= tol {
        out.pop();
    }
    *poly = out;
}

/// Points of a polygon closer than this times its largest coordinate are one point for
/// [`weld`]: a cut point is rounded at `1.1e-16` of its coordinates, so two computed points
/// that close are the same point within a few roundings. Without it, a blocker cut by the
/// tangent plane through one of its vertices (the vertex a rounding above the plane) left a
/// triangle of three points a few ulps apart, whose edges' lines are rounding noise; its
/// node planes made the query hide the whole light behind it.
const WELD_MAGNITUDE: f64 = 1e-14;

/// Relative area below which a fragment is a sliver: twice its area at most this times its
/// squared perimeter (the threshold below which the sphere layer calls a ring zero-area).
const SLIVER: f64 = 1e-12;

/// Whether the convex fragment `frag` is a sliver ([`SLIVER`]): splits by planes passing within
/// rounding of a vertex leave such pieces, nearly collinear, which cover no area.
pub(crate) fn is_sliver(frag: &[DVec3]) -> bool {
    let mut twice_area = DVec3::ZERO;
    let mut perimeter = 0.0;
    for i in 0..frag.len() {
        let j = (i + 1) % frag.len();
        perimeter += (frag[j] - frag[i]).length();
        if i >= 1 && j != 0 {
            twice_area += (frag[i] - frag[0]).cross(frag[j] - frag[0]);
        }
    }
    !(twice_area.length() > SLIVER * perimeter * perimeter)
}

/// The spherical polygon a fragment covers seen from `x` (both in the same tree coordinates), in
/// the shading frame: the fragment lies on a front face of the light and runs counter-clockwise
/// about the face's normal, so seen from `x` its ring is reversed. Directions a rounding below
/// the horizon (the fragment was clipped to the point's tangent plane) are lifted onto it.
///
/// `None` when the fragment covers no area within rounding (a sliver the sphere layer rejects
/// as zero-area or with coincident corners).
///
/// # Errors
///
/// [`GeomError::Undecidable`] for any other rejection of [`SphericalPolygon::new`].
pub(crate) fn fragment_polygon(
    frag: &[DVec3],
    x: DVec3,
    frame: &ShadingFrame,
) -> Result<Option<SphericalPolygon>, GeomError> {
    if is_sliver(frag) {
        return Ok(None);
    }
    let mut units: SmallVec<[DVec3; 8]> = SmallVec::new();
    let mut dirs: SmallVec<[DVec3; 8]> = SmallVec::new();
    for &e in frag.iter().rev() {
        let mut d = frame.dir_to_local(e - x);
        d.z = d.z.max(0.0);
        let Some(u) = d.try_normalize() else {
            return Ok(None);
        };
        if units
            .last()
            .is_some_and(|&w: &DVec3| (w - u).length() <= MERGE_TOLERANCE)
        {
            continue;
        }
        units.push(u);
        dirs.push(d);
    }
    while units.len() > 1 && (units[0] - units[units.len() - 1]).length() <= MERGE_TOLERANCE {
        units.pop();
        dirs.pop();
    }
    if dirs.len() < 3 {
        return Ok(None);
    }
    if certainly_valid_convex(&units) {
        let n = units.len() as u32;
        return Ok(Some(SphericalPolygon::from_parts(
            units.into_iter().collect(),
            smallvec::smallvec![n],
        )));
    }
    let degenerate = |e: &GeomError| {
        matches!(
            e,
            GeomError::ZeroArea { .. }
                | GeomError::CoincidentVertices { .. }
                | GeomError::TooFewVertices { .. }
        )
    };
    match SphericalPolygon::new(alloc::vec![dirs.to_vec()]) {
        Ok(p) => Ok(Some(p)),
        Err(e) if degenerate(&e) => Ok(None),
        // The fragment is convex in exact arithmetic, so a ring that crosses itself does so by
        // rounding: a corner a hair from its neighbour (two cut points of nearly the same
        // node plane), whose short edge points anywhere. Its convex hull differs from it by
        // that rounding.
        Err(GeomError::SelfIntersecting { .. }) => match convex_hull_ring(&units) {
            Some(hull) => match SphericalPolygon::new(alloc::vec![hull]) {
                Ok(p) => Ok(Some(p)),
                Err(e) if degenerate(&e) => Ok(None),
                Err(e) => Err(e.give_up("a visible light fragment is degenerate within rounding")),
            },
            None => Err(GeomError::Undecidable(
                "a visible light fragment is degenerate within rounding",
            )),
        },
        Err(e) => Err(e.give_up("a visible light fragment is degenerate within rounding")),
    }
}

/// The convex hull of the unit vectors `u` (in an open hemisphere about their mean), as a ring
/// counter-clockwise seen from outside the sphere, without corners closer than
/// [`MERGE_TOLERANCE`]; `None` when they are not within such a hemisphere, span no area, or the
/// ring `u` is not its hull up to rounding ([`HULL_AREA_TOLERANCE`]). Monotone chain in the
/// gnomonic plane about their mean direction, which maps great circles to lines, so convexity
/// there is convexity on the sphere.
///
/// The hull stands for the ring only where the two cover the same area to rounding: a ring
/// that is convex but for a crossing at a corner a hair from its neighbour has the hull's
/// signed area (in the gnomonic plane) within that crossing's tiny triangle, while a ring
/// wrong by more than rounding (a dent, corners out of order) falls short of the hull by a
/// visible part of it, and the caller then gives up rather than answer with the hull.
fn convex_hull_ring(u: &[DVec3]) -> Option<Vec<DVec3>> {
    let m = u.iter().copied().sum::<DVec3>().try_normalize()?;
    let (e1, e2) = m.any_orthonormal_pair();
    let mut pts: Vec<DVec2> = Vec::with_capacity(u.len());
    for &w in u {
        let h = w.dot(m);
        if !(h > 1e-3) {
            return None;
        }
        pts.push(DVec2::new(w.dot(e1), w.dot(e2)) / h);
    }
    let hull = monotone_hull(&pts);
    let hull_pts: Vec<DVec2> = hull.iter().map(|&i| pts[i]).collect();
    let (ring_area, hull_area) = (signed_area2(&pts), signed_area2(&hull_pts));
    if !((hull_area - ring_area).abs() <= HULL_AREA_TOLERANCE * hull_area) {
        return None;
    }
    // Counter-clockwise in (e1, e2), with e1 x e2 = m: counter-clockwise about m.
    let mut ring: Vec<DVec3> = Vec::with_capacity(hull.len());
    for w in hull.into_iter().map(|i| u[i]) {
        if ring
            .last()
            .is_none_or(|&q: &DVec3| (q - w).length() > MERGE_TOLERANCE)
        {
            ring.push(w);
        }
    }
    while ring.len() > 1 && (ring[0] - ring[ring.len() - 1]).length() <= MERGE_TOLERANCE {
        ring.pop();
    }
    (ring.len() >= 3).then_some(ring)
}

/// How far (relative) a fragment's ring may fall short of its convex hull's area for the hull
/// to stand for it ([`convex_hull_ring`]): the backends' agreement bound, far above the
/// rounding of a fragment's corners and far below any part of a light a point may see.
const HULL_AREA_TOLERANCE: f64 = 1e-9;

/// Whether the ring of unit vectors `u` passes every check of [`SphericalPolygon::new`] with a
/// margin, so that it can be stored without them (they cost more than the rest of a fragment's
/// way to a polygon): every vertex other than an edge's ends strictly left of the edge's great
/// circle by more than the rounding of the determinant (a convex ring, hence simple, which a
/// fragment is up to rounding), consecutive vertices neither coincident nor antipodal, no
/// vertex where the ring folds back (the two edges leaving it within twice `1e-12` rad of one
/// direction, or the shorter's end within twice `5e-16` of the other's circle), and an area
/// bounded below by twice the zero-area threshold (`1e-12` times the squared perimeter), by the
/// chords' vector area less its error. A ring that misses any margin goes through the checks.
fn certainly_valid_convex(u: &[DVec3]) -> bool {
    let n = u.len();
    if n < 3 {
        return false;
    }
    let (mut area2, mut chords, mut cubes) = (DVec3::ZERO, 0.0, 0.0);
    for i in 0..n {
        let (p, a, b) = (u[(i + n - 1) % n], u[i], u[(i + 1) % n]);
        let m = a.cross(b);
        let c = (b - a).length();
        if !(c > 1e-14 && (a + b).length() > 1e-9) {
            return false;
        }
        for (k, &w) in u.iter().enumerate() {
            // A determinant of unit vectors is computed within a few 1e-16.
            if k != i && k != (i + 1) % n && !(m.dot(w) > 1e-14) {
                return false;
            }
        }
        let (tp, tq) = (p - a * p.dot(a), b - a * b.dot(a));
        if tp.dot(tq) > 0.0 {
            let (lp, lq) = (tp.length(), tq.length());
            let cross = tp.cross(tq).length();
            if !(cross > 2e-12 * lp * lq && cross > 1e-15 * lp.max(lq)) {
                return false;
            }
        }
        area2 += m;
        chords += c;
        cubes += c * c * c;
    }
    let h = 0.5 * core::f64::consts::PI;
    let lower = 0.5 * area2.length() - h * h * h / 12.0 * cubes - 1e-15 * n as f64;
    let perimeter = h * chords;
    lower > 2e-12 * perimeter * perimeter
}

/// The part of the convex polygon `poly` on the closed positive side of a plane, given the signed
/// distances `vals` of its vertices (Sutherland–Hodgman against one plane), or `None` when no
/// vertex is strictly on that side (nothing with area is left).
pub(crate) fn keep_positive(poly: &[DVec3], vals: &[(f64, Sign)]) -> Option<Fragment> {
    if vals.iter().all(|v| v.1 != Sign::Positive) {
        return None;
    }
    if vals.iter().all(|v| v.1 != Sign::Negative) {
        return (poly.len() >= 3).then(|| poly.iter().copied().collect());
    }
    split(poly, vals).0
}

/// The part of the convex polygon `poly` on the closed positive side of the plane through `p0`
/// with normal `n`, or `None` when less than a polygon is left ([`keep_positive`]).
pub(crate) fn clip_above(poly: &[DVec3], p0: DVec3, n: DVec3) -> Option<Fragment> {
    let vals: SmallVec<[(f64, Sign); 8]> = poly
        .iter()
        .map(|&p| {
            let d = n.dot(p - p0);
            (d, Sign::of(d))
        })
        .collect();
    keep_positive(poly, &vals)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::visibility::plucker::bsp::{Crossing, Occluder};

    fn area(poly: &[DVec3]) -> f64 {
        let mut s = DVec3::ZERO;
        for i in 1..poly.len().saturating_sub(1) {
            s += (poly[i] - poly[0]).cross(poly[i + 1] - poly[0]);
        }
        s.length() / 2.0
    }

    fn occluder(v: &[DVec3], crossing: Crossing) -> Occluder {
        Occluder::new(v, crossing, 0)
    }

    /// The 3D area of what `x` sees of `light` past the occluder `occ`.
    fn seen(x: DVec3, light: &[DVec3], occ: Occluder) -> f64 {
        let mut tree = Tree::new(&[x], light, alloc::vec![occ], 7);
        let mut out = Vec::new();
        let relative: Vec<DVec3> = light.iter().map(|&p| p - x).collect();
        query(
            &mut tree,
            x,
            DVec3::Z,
            &relative,
            usize::MAX,
            &mut out,
            &mut Scratch::default(),
        )
        .unwrap();
        out.iter().map(|f| area(f)).sum()
    }

    #[test]
    fn a_point_on_an_occluders_edge_line_sees_past_it() {
        // The open-occluder rule (mod.rs): from a point in the occluder's plane on the line of
        // one of its edges (on the edge, at a vertex, on the edge's extension) every line meets
        // the occluder only at that point, so nothing is hidden. The fragments reach the node
        // of that edge with side zero everywhere and must take its zero child, for a light on
        // one side of the occluder's plane (one-sided chain) and across it (two-sided chain,
        // the edge at the root and later). A point off the plane, under the occluder, sees the
        // shadow removed.
        let tri = [
            DVec3::new(-1.0, -1.0, 1.0),
            DVec3::new(1.0, -1.0, 1.0),
            DVec3::new(0.0, 1.0, 1.0),
        ];
        let above = [
            DVec3::new(-0.5, -0.5, 2.0),
            DVec3::new(0.5, -0.5, 2.0),
            DVec3::new(0.5, 0.5, 2.0),
            DVec3::new(-0.5, 0.5, 2.0),
        ];
        let across = [
            DVec3::new(-0.5, 2.0, 0.5),
            DVec3::new(0.5, 2.0, 0.5),
            DVec3::new(0.5, 2.0, 1.5),
            DVec3::new(-0.5, 2.0, 1.5),
        ];
        let on_lines = [
            DVec3::new(0.0, -1.0, 1.0),
            DVec3::new(3.0, -1.0, 1.0),
            DVec3::new(-1.0, -1.0, 1.0),
            DVec3::new(0.5, 0.0, 1.0),
            DVec3::new(-0.25, 0.5, 1.0),
        ];
        for (light, crossing) in [(&above, Crossing::Positive), (&across, Crossing::Both)] {
            // Rotations of the vertex list put each edge at the root of the chain.
            for r in 0..3 {
                let v = [tri[r], tri[(r + 1) % 3], tri[(r + 2) % 3]];
                for &x in &on_lines {
                    let a = seen(x, light, occluder(&v, crossing));
                    assert!(
                        (a - area(light)).abs() <= 1e-12,
                        "{crossing:?} r {r} x {x}: {a}"
                    );
                }
            }
        }
        // Under the occluder the light above is partly hidden.
        let hidden = seen(
            DVec3::new(0.0, -0.2, 0.2),
            &above,
            occluder(&tri, Crossing::Positive),
        );
        assert!(hidden < 0.9 * area(&above), "{hidden}");
    }

    #[test]
    fn parts_of_a_split_both_visible_come_out_as_one_fragment() {
        // A tree shared by two points: the first, under a small triangle, develops its chain;
        // from the second the triangle's shadow misses the light, but the plane through it and
        // the triangle's first edge cuts the light in two, and both parts end in visible
        // leaves. The query gives back the light as one fragment (`Merges`), with its area.
        let s = 0.2;
        let tri = [
            DVec3::new(-s, -s, 1.0),
            DVec3::new(s, -s, 1.0),
            DVec3::new(0.0, s, 1.0),
        ];
        let light = [
            DVec3::new(-0.5, -0.5, 2.0),
            DVec3::new(0.5, -0.5, 2.0),
            DVec3::new(0.5, 0.5, 2.0),
            DVec3::new(-0.5, 0.5, 2.0),
        ];
        let (x1, x2) = (DVec3::ZERO, DVec3::new(1.5, 0.0, 0.0));
        let mut tree = Tree::new(
            &[x1, x2],
            &light,
            alloc::vec![occluder(&tri, Crossing::Positive)],
            7,
        );
        let mut scratch = Scratch::default();
        let mut run = |tree: &mut Tree, x: DVec3| {
            let mut out = Vec::new();
            let relative: Vec<DVec3> = light.iter().map(|&p| p - x).collect();
            query(
                tree,
                x,
                DVec3::Z,
                &relative,
                usize::MAX,
                &mut out,
                &mut scratch,
            )
            .unwrap();
            out
        };
        let first = run(&mut tree, x1);
        let shadowed: f64 = first.iter().map(|f| area(f)).sum();
        assert!(shadowed < 0.95 * area(&light), "{shadowed}");
        let second = run(&mut tree, x2);
        assert_eq!(second.len(), 1, "{second:?}");
        assert!((area(&second[0]) - area(&light)).abs() <= 1e-12);
    }

    #[test]
    fn rings_taken_without_checks_pass_every_check() {
        // `certainly_valid_convex` skips `SphericalPolygon::new`: every ring it accepts must be
        // one that `new` accepts and stores unchanged. Rings: points on circles of radius from
        // 1e-7 to nearly a hemisphere, in either orientation, with vertices pulled in or pushed
        // out by relative amounts from 1e-16 to 1e-2 (convex, flat, reflex), repeated within
        // rounding, two of them swapped (a crossing ring for more than three), or squeezed to
        // slivers.
        let mut rnd = crate::math::test_unit_stream(0x9e37_79b9_7f4a_7c15);
        let (mut taken, mut checked) = (0, 0);
        for case in 0..20_000 {
            let n = 3 + (rnd() * 6.0) as usize;
            let radius = 10f64.powf(-7.0 + 7.0 * rnd()).min(1.5);
            let squeeze = if case % 5 == 0 {
                10f64.powf(-14.0 * rnd())
            } else {
                1.0
            };
            let axis = DVec3::new(rnd() - 0.5, rnd() - 0.5, rnd() - 0.5).normalize();
            let e1 = axis.any_orthonormal_vector();
            let e2 = axis.cross(e1);
            let mut angles: Vec<f64> = (0..n).map(|_| rnd() * core::f64::consts::TAU).collect();
            angles.sort_by(f64::total_cmp);
            if case % 2 == 1 {
                angles.reverse();
            }
            let mut ring: Vec<DVec3> = angles
                .iter()
                .map(|&t| {
                    let r = radius.tan();
                    (axis + e1 * (r * t.cos()) + e2 * (r * squeeze * t.sin())).normalize()
                })
                .collect();
            let k = (rnd() * n as f64) as usize;
            match case % 4 {
                1 => {
                    let f = 1.0 + (rnd() - 0.5) * 10f64.powf(-16.0 + 14.0 * rnd());
                    ring[k] = (axis + (ring[k] - axis) * f).normalize();
                }
                2 => ring[k] = (ring[(k + 1) % n] + DVec3::splat(1e-17 * rnd())).normalize(),
                3 => ring.swap(k, (k + 2) % n),
                _ => {}
            }
            if certainly_valid_convex(&ring) {
                taken += 1;
                let p = SphericalPolygon::new(alloc::vec![ring.clone()])
                    .unwrap_or_else(|e| panic!("case {case}: {ring:?} taken, but {e:?}"));
                assert_eq!(p.rings().next().unwrap(), &ring[..], "case {case}");
            } else if SphericalPolygon::new(alloc::vec![ring]).is_ok() {
                checked += 1;
            }
        }
        // The test has power only if both ways are common.
        assert!(
            taken > 2_000 && checked > 2_000,
            "{taken} taken, {checked} checked"
        );
    }

    #[test]
    fn a_fragment_crossing_itself_by_rounding_becomes_its_hull() {
        // From the render demo (quad, cylinder and cone lights, a context of 256 tiles): a
        // visible fragment, a thin quadrilateral two of whose corners are 9e-13 apart, whose
        // directions make a ring that crosses itself at that short edge. It covers the
        // triangle of its three distinct corners, within rounding.
        let frag = [
            DVec3::new(-2.9641372256203073, -1.5666377766619046, 2.9348195555923215),
            DVec3::new(-2.962507948578911, -1.5677777748182766, 2.935254965836143),
            DVec3::new(-3.238311400344067, -1.4446230104131506, 2.861548870967869),
            DVec3::new(-3.2383114003448834, -1.4446230104127846, 2.861548870967651),
        ];
        let frame = ShadingFrame::new(
            DVec3::new(1.2202362078367375, 1.6141299014320465, 0.0),
            DVec3::Z,
            DVec3::new(
                -0.11639960546415623,
                -0.7860180491376988,
                0.6071464059661019,
            ),
        )
        .unwrap();
        let poly = fragment_polygon(&frag, DVec3::ZERO, &frame)
            .expect("a fragment degenerate by rounding has a polygon")
            .expect("the fragment covers some area");
        let tri: Vec<DVec3> = [frag[2], frag[1], frag[0]]
            .iter()
            .map(|&e| frame.dir_to_local(e))
            .collect();
        let expected = SphericalPolygon::new(alloc::vec![tri])
            .unwrap()
            .solid_angle();
        let got = poly.solid_angle();
        // Within the rounding of the solid angle of a sliver of this aspect (1e-2).
        assert!(
            (got - expected).abs() <= 1e-10 * expected,
            "{got} {expected}"
        );
    }

    #[test]
    fn a_ring_wrong_by_more_than_rounding_is_not_its_hull() {
        // Rings of directions about +z, counter-clockwise seen from outside (as
        // `fragment_polygon` makes them). Their hull is a convex quadrilateral, but they cover
        // it only in part, so the hull must not stand for them.
        let ring = |c: &[(f64, f64)]| -> Vec<DVec3> {
            c.iter()
                .map(|&(x, y)| DVec3::new(x, y, 1.0).normalize())
                .collect()
        };
        let square = [(-0.3, -0.2), (0.3, -0.2), (0.3, 0.2), (-0.3, 0.2)];
        assert!(
            convex_hull_ring(&ring(&square)).is_some(),
            "a convex ring is its hull"
        );
        // A bowtie of unequal lobes: the corners out of order.
        let bowtie = [(-0.3, -0.2), (0.3, 0.2), (0.3, -0.2), (-0.1, 0.2)];
        assert!(convex_hull_ring(&ring(&bowtie)).is_none(), "a bowtie");
        // A dent: one more corner pushed in by a sixth of the side.
        let dent = [
            (-0.3, -0.2),
            (0.3, -0.2),
            (0.3, 0.2),
            (0.0, 0.14),
            (-0.3, 0.2),
        ];
        assert!(convex_hull_ring(&ring(&dent)).is_none(), "a dent");
    }

    #[test]
    fn split_parts_tile_the_fragment() {
        // The two parts of a split cover the fragment (areas add up), lie on their sides, and
        // vertices on the plane join both.
        let square: Fragment = [
            DVec3::new(0.0, 0.0, 0.0),
            DVec3::new(1.0, 0.0, 0.0),
            DVec3::new(1.0, 1.0, 0.0),
            DVec3::new(0.0, 1.0, 0.0),
        ]
        .into_iter()
        .collect();
        for (n, d) in [
            (DVec3::new(1.0, 0.3, 0.0), 0.4),
            (DVec3::new(1.0, 1.0, 0.0), 1.0),
            (DVec3::new(0.0, 1.0, 0.0), 0.25),
        ] {
            let vals: SmallVec<[(f64, Sign); 8]> = square
                .iter()
                .map(|&p| (n.dot(p) - d, Sign::of(n.dot(p) - d)))
                .collect();
            let (p, m) = split(&square, &vals);
            let (p, m) = (p.unwrap(), m.unwrap());
            assert!((area(&p) + area(&m) - 1.0).abs() < 1e-15, "{n}");
            assert!(p.iter().all(|&q| n.dot(q) - d >= -1e-15));
            assert!(m.iter().all(|&q| n.dot(q) - d <= 1e-15));
        }
    }
}
