//! Triangulation of spherical polygons into minor-arc triangles (thesis 003, chapter 6), each
//! result certified exactly before it is returned.

use alloc::collections::BTreeMap;
use alloc::vec::Vec;
use core::f64::consts::PI;

use glam::{DVec2, DVec3};

use super::gnomonic::enclosing_cap;
use super::polygon::{COINCIDENT_TOLERANCE, SphericalPolygon};
use super::predicates::{AXES, normalize_any, orient, tangent_frame};
use super::sample::{SphericalTriangle, signed_solid_angle_with_error};
use crate::GeomError;
use crate::planar::{Cdt, constrained_delaunay};

/// Smallest cosine of the radius of a cap that is triangulated in one gnomonic chart: projected
/// coordinates stay below `1 / CHART_COS` (here 1e3) of the cap's center, where the planar
/// triangulation's decisions on rounded coordinates still match the sphere's except within
/// rounding of a degeneracy (and those are caught by the certificate). Wider polygons are cut
/// in two by a coordinate plane, recursively.
const CHART_COS: f64 = 1e-3;

/// Smallest gap between a triangle's solid angle and a hemisphere's that a triangulation
/// accepts: [`SphericalTriangle::sample`] is uniform and inside to that gap (its tests go to
/// 4e-8); a triangle closer to a hemisphere than rounding cannot even be measured.
const HEMISPHERE_MARGIN: f64 = 1e-6;

impl SphericalPolygon {
    /// Splits the region into spherical triangles with minor-arc edges, positive orientation,
    /// non-zero area and disjoint interiors, whose union is the region.
    ///
    /// Any valid polygon: several rings, holes, pinches, regions larger than a hemisphere,
    /// bands around a great circle, tiny polygons, the full sphere (four triangles of a
    /// tetrahedron), the empty region (no triangles). The methods, tried in this order:
    ///
    /// 1. a single ring: the fan from its first vertex (thesis 003, section 6.1), which
    ///    succeeds for convex rings and rings star-shaped about that vertex; no extra vertex;
    /// 2. vertices in a cap narrower than a hemisphere: the gnomonic projection about (nearly)
    ///    the cap's center maps arcs to segments, so the constrained Delaunay triangulation of
    ///    the projected vertices with the edges as constraints, restricted to the region
    ///    (labels spread from the edges' sides), is a spherical triangulation; no extra vertex,
    ///    or, when the region contains the far side of the chart (a complement), one: the
    ///    antipode of the hull vertices' mean direction, fanned over the projected convex hull
    ///    (no triangle with vertices in an open hemisphere reaches its far side, so one is
    ///    needed). The center is turned 1e-3 rad off the cap's: symmetric rings (regular stars,
    ///    silhouettes of round lights) would otherwise be cocircular in the chart, where every
    ///    in-circle test takes the exact slow path;
    /// 3. otherwise the stereographic projection from a pole outside the region, far from every
    ///    vertex (stretched by 5% along one direction, so that points on one circle of the
    ///    sphere are not cocircular in the plane): bands around a great circle, polar caps and
    ///    lunes get triangles between their own vertices; no extra vertex;
    /// 4. a single ring star-shaped about a point (its area vector, or an axis): the fan from
    ///    that point (one extra vertex: a hemisphere bounded by vertices on its great circle has
    ///    no triangle of its own vertices);
    /// 5. otherwise the region is cut in two by the coordinate plane `x = 0` (exact hemisphere
    ///    clipping, [`SphericalPolygon::clip_to_hemisphere`]), each half solved the same way, then
    ///    `y = 0`, then `z = 0`; an octant always fits a chart. The cuts add vertices where edges
    ///    cross the planes and along the planes' circles, and the two halves share every vertex
    ///    on a cut bit for bit. Regions reach this step when no cap narrower than a hemisphere
    ///    holds their vertices, no stereographic pole of step 3 is both outside them and clear of
    ///    their vertices (the sphere minus six or more small holes, a complement of many small
    ///    occluders) or its chart cannot be repaired, and they are not one ring star-shaped about
    ///    a candidate point (a ring wrapped most of the way round the sphere with long edges).
    ///
    /// Thesis 003 section 6.2 adds extra vertices where a triangulation would need arcs longer
    /// than `pi`; here steps 1-3 use none, and an extra vertex is added (steps 2 and 4) only
    /// where no triangle of the region's own vertices can reach part of it.
    ///
    /// In steps 2 and 3, planar triangles that come out inverted on the sphere (a vertex within
    /// rounding of another's edge, which the rounded chart coordinates put on the wrong side;
    /// a stereographic chart's straight edges, which are not the images of arcs) are repaired
    /// by flipping their longest edge, and two more centers (poles) are tried before the next
    /// step.
    ///
    /// Every candidate is certified with exact predicates before it is used: each triangle is
    /// positively oriented (`orient3d`) and at least 1e-6 sr short of a hemisphere, every
    /// directed edge of the triangles is either an edge of the polygon or cancelled by its
    /// reverse, and the areas add up to the region's within `2 pi`. The first two make the
    /// number of triangles over any direction off the edges equal to the region's indicator
    /// plus a constant `k`, and the third makes `k = 0`: the triangles tile the region exactly
    /// (for step 5, each half exactly, and the halves meet exactly along the cut; they tile the
    /// region up to what the clipping moves: the crossing points rounded off their edges, and
    /// vertices within the clip's tolerances of a cut plane snapped onto it). Deterministic; no
    /// sampling.
    ///
    /// Triangles certified positive whose area rounds to zero (slivers below rounding between
    /// nearly collinear vertices) are left out: they cover nothing beyond rounding of an edge.
    /// Distinct vertices closer than [`COINCIDENT_TOLERANCE`] (which validation accepts where
    /// they are not consecutive, and step 5's cuts make where they cross a sliver's tip) are
    /// triangulated as one: the triangles tile the polygon with those vertices merged, which
    /// moves its boundary by less than `1e-15`.
    ///
    /// # Examples
    ///
    /// ```
    /// use arealight::glam::DVec3;
    /// use arealight::sphere::SphericalPolygon;
    /// // An L-shaped ring (not star-shaped about its first vertex).
    /// let l = SphericalPolygon::new(vec![vec![
    ///     DVec3::new(0.0, 0.0, 1.0), DVec3::new(0.2, 0.0, 1.0), DVec3::new(0.2, 0.1, 1.0),
    ///     DVec3::new(0.1, 0.1, 1.0), DVec3::new(0.1, 0.2, 1.0), DVec3::new(0.0, 0.2, 1.0),
    /// ]])?;
    /// let tris = l.triangulate()?;
    /// assert_eq!(tris.len(), 4);
    /// let sum: f64 = tris.iter().map(|t| t.solid_angle()).sum();
    /// assert!((sum - l.solid_angle()).abs() < 1e-15);
    /// assert_eq!(SphericalPolygon::full().triangulate()?.len(), 4);
    /// # Ok::<(), arealight::GeomError>(())
    /// ```
    ///
    /// # Errors
    ///
    /// [`GeomError::Undecidable`] when no candidate passes the certificate (rounding in every
    /// chart made the planar triangulation disagree with the sphere at a near-degeneracy), or
    /// when the triangles' areas miss the region's by more than `1e-12` relative plus the
    /// rounding bounds of both sums (and the move of merged vertices): a fault, or step 5's
    /// clips moving the boundary by more than that at every plane tried. Never a wrong
    /// triangulation.
    pub fn triangulate(&self) -> Result<Vec<SphericalTriangle>, GeomError> {
        if let Some(ring) = self.single_ring()
            && let Some(fan) = fan_from_first(ring)
        {
            return Ok(fan);
        }
        let mut tris: Vec<[DVec3; 3]> = Vec::new();
        let mut moved = 0.0;
        solve(self, 0, &mut tris, &mut moved)?;
        let mut out = Vec::with_capacity(tris.len());
        let (mut sum, mut rounding) = (0.0, 0.0);
        for [a, b, c] in tris {
            match SphericalTriangle::from_unit(a, b, c) {
                Ok(t) => {
                    sum += t.solid_angle();
                    // The triangles are certified positive, so `(a, b, c)` is the
                    // counter-clockwise order whose area `from_unit` took.
                    rounding += signed_solid_angle_with_error(a, b, c).1;
                    out.push(t);
                }
                // Certified positive, area below rounding.
                Err(GeomError::Degenerate(_)) => {}
                Err(e) => return Err(e),
            }
        }
        let (area, area_err) = region_area_with_error(self);
        // The certificate makes the triangles tile the polygon (for step 5, the halves the cuts
        // leave: see `cut`), so the sums may differ only by their rounding.
        let tol =
            AREA_GUARD * area + rounding + out.len() as f64 * f64::EPSILON * sum + area_err + moved;
        if !((sum - area).abs() <= tol) {
            return Err(GeomError::Undecidable(
                "triangle areas do not add up to the polygon's",
            ));
        }
        Ok(out)
    }
}

/// Step 1 of [`SphericalPolygon::triangulate`] for a polygon of one ring, certified without the
/// general certificate's sorting and without the region's area: the fan `(r0, ri, ri+1)` is a
/// 2-chain whose boundary is the ring (the diagonals `r0 -> ri` cancel by position, repeated
/// vertex values or not), so with every triangle positive (exact `orient3d`) the number of
/// triangles over a direction off the edges is the region's indicator plus a constant `k >= 0`,
/// and the areas add up to the region's plus `4 pi k`: a sum below `4 pi` makes `k = 0`. `None`
/// when a triangle is not positive, within [`HEMISPHERE_MARGIN`] of a hemisphere, or the sum
/// reaches `4 pi`.
fn fan_from_first(ring: &[DVec3]) -> Option<Vec<SphericalTriangle>> {
    let apex = ring[0];
    let mut out = Vec::with_capacity(ring.len().saturating_sub(2));
    let mut sum = 0.0;
    for w in ring[1..].windows(2) {
        let (b, c) = (w[0], w[1]);
        // The area decides before the triangle is built: a positive triangle with its vertices
        // nearly on a great circle is either a sliver or nearly a hemisphere, and the latter
        // must not pass for the former below.
        let (area, err) = signed_solid_angle_with_error(apex, b, c);
        if orient(apex, b, c) != 1
            || !(err <= MAX_AREA_ERROR)
            || !(area <= 2.0 * PI - HEMISPHERE_MARGIN)
        {
            return None;
        }
        match SphericalTriangle::from_unit(apex, b, c) {
            Ok(t) => {
                sum += t.solid_angle();
                out.push(t);
            }
            // Certified positive, area within its own rounding.
            Err(GeomError::Degenerate(_)) if area <= err => {}
            Err(_) => return None,
        }
    }
    (sum < 4.0 * PI && !out.is_empty()).then_some(out)
}

/// The region's solid angle, reduced modulo `4 pi` only after the rings' signed fan sums (from
/// a vertex or axis far from every antipode of the ring; a triangle's area is defined modulo `4 pi` even where its far edge
/// passes the apex's antipode, see [`signed_solid_angle_with_error`]) are added, so that a tiny outer ring and its tiny hole cancel as small numbers (reducing each
/// ring first, as a ring's own left area must be, leaves the hole at `4 pi - epsilon`, which
/// cannot hold `epsilon` to relative precision).
fn region_area(poly: &SphericalPolygon) -> f64 {
    region_area_with_error(poly).0
}

/// [`region_area`] and a bound on its rounding error: the fan terms' own bounds
/// ([`signed_solid_angle_with_error`]) plus the rounding of their sum.
fn region_area_with_error(poly: &SphericalPolygon) -> (f64, f64) {
    if poly.is_full() {
        return (4.0 * PI, 0.0);
    }
    let (mut sum, mut err, mut magnitude) = (0.0, 0.0, 0.0);
    for ring in poly.rings() {
        // The apex: the first vertex, unless a vertex is near its antipode (where the arcs from
        // the apex are undefined); then the vertex or axis farthest from every antipode.
        let clearance = |x: DVec3| {
            ring.iter()
                .map(|&v| (x + v).length_squared())
                .fold(f64::INFINITY, f64::min)
        };
        let mut apex = ring[0];
        if clearance(apex) < 0.5 {
            for &x in ring.iter().chain(AXES.iter()) {
                if clearance(x) > clearance(apex) {
                    apex = x;
                }
            }
        }
        let n = ring.len();
        for i in 0..n {
            let (b, c) = (ring[i], ring[(i + 1) % n]);
            if b != apex && c != apex {
                let (w, e) = signed_solid_angle_with_error(apex, b, c);
                sum += w;
                err += e;
                magnitude += w.abs();
            }
        }
    }
    // Recursive summation rounds by at most (terms - 1) eps times the sum of magnitudes; the
    // reduction rounds only when it shifts the sum.
    let terms = poly.vertex_count() as f64;
    let reduced = sum.rem_euclid(4.0 * PI);
    let shift = if reduced == sum { 0.0 } else { 4.0 * PI };
    (
        reduced,
        err + terms * f64::EPSILON * magnitude + f64::EPSILON * shift,
    )
}

/// A polygon as indexed geometry: its distinct vertices (equal bits are one vertex, so pinches
/// are shared) and its directed edges.
struct Indexed {
    verts: Vec<DVec3>,
    edges: Vec<[u32; 2]>,
}

impl Indexed {
    fn new(poly: &SphericalPolygon) -> Self {
        let all: Vec<DVec3> = poly.rings().flatten().copied().collect();
        let key = |p: DVec3| [p.x.to_bits(), p.y.to_bits(), p.z.to_bits()];
        let mut order: Vec<u32> = (0..all.len() as u32).collect();
        order.sort_unstable_by_key(|&i| key(all[i as usize]));
        let mut id = alloc::vec![0u32; all.len()];
        let mut verts: Vec<DVec3> = Vec::with_capacity(all.len());
        for (k, &i) in order.iter().enumerate() {
            if k == 0 || key(all[i as usize]) != key(all[order[k - 1] as usize]) {
                verts.push(all[i as usize]);
            }
            id[i as usize] = verts.len() as u32 - 1;
        }
        let mut edges = Vec::with_capacity(all.len());
        let mut start = 0usize;
        for ring in poly.rings() {
            let n = ring.len();
            for i in 0..n {
                edges.push([id[start + i], id[start + (i + 1) % n]]);
            }
            start += n;
        }
        Indexed { verts, edges }
    }

    /// Merges distinct vertices closer than [`COINCIDENT_TOLERANCE`] (the same direction for
    /// every purpose of the crate; validation rejects only consecutive ones) into the first of
    /// them, and returns a bound on the solid angle that moves (each merged vertex's distance
    /// times the length of its edges). No chart can tell such vertices apart, and step 5's clips
    /// make them where a cut crosses a sliver's tip (two edges 1e-9 apart cross the plane
    /// 1e-18 apart). Nothing is merged (and 0 returned) when a merge would shrink an edge to a
    /// point.
    fn merge_unresolved(&mut self) -> f64 {
        let n = self.verts.len();
        let mut order: Vec<u32> = (0..n as u32).collect();
        order.sort_unstable_by(|&i, &j| {
            self.verts[i as usize]
                .x
                .total_cmp(&self.verts[j as usize].x)
        });
        // Union-find with the smallest id as the root.
        let mut rep: Vec<u32> = (0..n as u32).collect();
        fn root(rep: &mut [u32], mut i: u32) -> u32 {
            while rep[i as usize] != i {
                rep[i as usize] = rep[rep[i as usize] as usize];
                i = rep[i as usize];
            }
            i
        }
        let mut any = false;
        for (k, &i) in order.iter().enumerate() {
            let p = self.verts[i as usize];
            for &j in &order[k + 1..] {
                let q = self.verts[j as usize];
                if q.x - p.x > COINCIDENT_TOLERANCE {
                    break;
                }
                if (p - q).length() <= COINCIDENT_TOLERANCE {
                    let (a, b) = (root(&mut rep, i), root(&mut rep, j));
                    if a != b {
                        rep[a.max(b) as usize] = a.min(b);
                        any = true;
                    }
                }
            }
        }
        if !any {
            return 0.0;
        }
        let rep: Vec<u32> = (0..n as u32).map(|i| root(&mut rep, i)).collect();
        if self
            .edges
            .iter()
            .any(|&[i, j]| rep[i as usize] == rep[j as usize])
        {
            return 0.0;
        }
        let mut moved = 0.0;
        for &[i, j] in &self.edges {
            let (a, b) = (self.verts[i as usize], self.verts[j as usize]);
            let shift = (a - self.verts[rep[i as usize] as usize]).length()
                + (b - self.verts[rep[j as usize] as usize]).length();
            moved += shift * (a - b).length();
        }
        // The merged vertices leave the vertex list (a chart would triangulate them as points).
        let mut new_id = alloc::vec![u32::MAX; n];
        let mut verts = Vec::with_capacity(n);
        for i in 0..n {
            if rep[i] == i as u32 {
                new_id[i] = verts.len() as u32;
                verts.push(self.verts[i]);
            }
        }
        self.verts = verts;
        for e in &mut self.edges {
            *e = e.map(|i| new_id[rep[i as usize] as usize]);
        }
        moved
    }

    /// The rings' vertex ids in order (for the single-ring fans).
    fn single_ring(&self) -> Vec<u32> {
        self.edges.iter().map(|e| e[0]).collect()
    }
}

/// Triangulates `poly` into `out`; `used` has bit `k` set for each coordinate plane `AXES[k]`
/// already cut by, and `moved` collects a bound on the solid angle that merging unresolved
/// vertices moves ([`Indexed::merge_unresolved`]).
fn solve(
    poly: &SphericalPolygon,
    used: u8,
    out: &mut Vec<[DVec3; 3]>,
    moved: &mut f64,
) -> Result<(), GeomError> {
    if poly.is_empty() {
        return Ok(());
    }
    if poly.is_full() {
        out.extend(tetrahedron());
        return Ok(());
    }
    let mut ix = Indexed::new(poly);
    *moved += ix.merge_unresolved();
    let area = region_area(poly);
    let single = poly.ring_count() == 1;
    let emit = |ix: &Indexed, tris: &[[u32; 3]], out: &mut Vec<[DVec3; 3]>| {
        out.extend(tris.iter().map(|t| t.map(|i| ix.verts[i as usize])));
    };
    // 1. The fan from the first vertex.
    if single {
        let ring = ix.single_ring();
        let apex = ring[0];
        let tris: Vec<[u32; 3]> = (1..ring.len() - 1)
            .map(|i| [apex, ring[i], ring[i + 1]])
            .collect();
        if certify(&ix.verts, &tris, &ix.edges, area) {
            emit(&ix, &tris, out);
            return Ok(());
        }
    }
    // 2. One gnomonic chart. A failed certificate here is a near-degeneracy that the rounded
    // projected coordinates decided the other way (a vertex within rounding of another's edge):
    // charts about slightly turned centers round differently.
    if let Ok((c, cos_r)) = enclosing_cap(&ix.verts)
        && cos_r >= CHART_COS
    {
        let n = ix.verts.len();
        let r = ix
            .verts
            .iter()
            .map(|&v| (v - c).length())
            .fold(0.0, f64::max);
        for c in chart_centers(c, r) {
            if c.dot(c) != 0.0 && ix.verts.iter().all(|v| v.dot(c) >= CHART_COS) {
                let complement = poly.contains(-c);
                if let Ok(tris) = chart(&mut ix, c, complement)
                    && certify(&ix.verts, &tris, &ix.edges, area)
                {
                    emit(&ix, &tris, out);
                    return Ok(());
                }
                ix.verts.truncate(n);
            }
        }
    }
    // 3. One stereographic chart (no extra vertex), for vertex sets no cap narrower than a
    // hemisphere holds: bands, polar caps, regions around a great circle; the next poles as
    // retries, as for step 2.
    for pole in stereographic_poles(poly, &ix.verts) {
        if let Ok(tris) = stereographic_chart(&ix, pole)
            && certify(&ix.verts, &tris, &ix.edges, area)
        {
            emit(&ix, &tris, out);
            return Ok(());
        }
    }
    // 4. A fan from a point the ring is star-shaped about.
    if single {
        let ring = ix.single_ring();
        let mut normal = DVec3::ZERO;
        for i in 0..ring.len() {
            let (a, b) = (
                ix.verts[ring[i] as usize],
                ix.verts[ring[(i + 1) % ring.len()] as usize],
            );
            normal += a.cross(b - a);
        }
        let apex_id = ix.verts.len() as u32;
        let candidates = normalize_any(normal).into_iter().chain(AXES);
        for apex in candidates {
            if ix.verts.contains(&apex) {
                continue;
            }
            ix.verts.push(apex);
            let tris: Vec<[u32; 3]> = (0..ring.len())
                .map(|i| [apex_id, ring[i], ring[(i + 1) % ring.len()]])
                .collect();
            if certify(&ix.verts, &tris, &ix.edges, area) {
                emit(&ix, &tris, out);
                return Ok(());
            }
            ix.verts.pop();
        }
    }
    // 5. Cut by a coordinate plane not used yet (see `cut`).
    if used != 0b111 {
        let (k, up, down) = cut(poly, used);
        solve(&up, used | 1 << k, out, moved)?;
        return solve(&down, used | 1 << k, out, moved);
    }
    Err(GeomError::Undecidable(
        "no chart of an octant triangulates the polygon within rounding",
    ))
}

/// Relative part of the final guard of [`SphericalPolygon::triangulate`]: the triangles' areas
/// must add up to the region's within this fraction of it, on top of the rounding bounds of both
/// sums and the move of merged vertices. What step 5's clips move ([`cut`]) must fit in it.
const AREA_GUARD: f64 = 1e-12;

/// Step 5 of [`SphericalPolygon::triangulate`]: the halves `poly.clip_to_axis_hemisphere(n)` and
/// `poly.clip_to_axis_hemisphere(-n)` for the coordinate axis `n = AXES[k]` not in `used` whose
/// halves' solid angles come closest to adding up to the polygon's (the first that adds up
/// exactly; the final guard of [`SphericalPolygon::triangulate`] decides whether the closest is
/// close enough); with `k`.
///
/// Where the halves meet they agree bit for bit: every vertex the clip makes on the plane (an
/// edge's crossing `w - n (w . n)` with `w = below (above . n) - above (below . n)`, a vertex
/// near the plane projected as `p - n (p . n)`, a point of the circle `u cos t + v sin t` with
/// `u`, `v` orthogonal to the axis) has its axis coordinate exactly zero, and an edge's crossing
/// is the same expression for `n` and `-n` (heights negated exactly, `above` and `below`
/// swapped), so both halves end their chains at the same vectors and their edges along the cut
/// lie on the same great circle. What the halves can still miss is what the clip moves: a
/// crossing rounded off its edge (about `1e-14` of the edge's length), vertices or edges within
/// the clip's tolerances of the plane snapped onto it, and crossings of two edges that meet
/// within `1e-11` of the plane, which the clip may take in the wrong order (a pinched polygon
/// with nearly antipodal vertices lost 1.2e-11 sr to the cut `x = 0`, and none to `y = 0`; a
/// hemisphere bounded by vertices on its circle, with a ring along it, 7.5e-12 to `y = 0` after
/// `x = 0`, and none to `z = 0`). Measuring each candidate avoids that where another plane is
/// clean; the rounding of the measures (a few ulps of `4 pi`) is far below what it looks for.
fn cut(poly: &SphericalPolygon, used: u8) -> (usize, SphericalPolygon, SphericalPolygon) {
    let area = region_area(poly);
    let mut best: Option<(usize, SphericalPolygon, SphericalPolygon, f64)> = None;
    for k in (0..3).filter(|k| used & 1 << k == 0) {
        let (up, down) = (
            poly.clip_to_axis_hemisphere(AXES[k]),
            poly.clip_to_axis_hemisphere(-AXES[k]),
        );
        let miss = (region_area(&up) + region_area(&down) - area).abs();
        if miss == 0.0 {
            return (k, up, down);
        }
        if best.as_ref().is_none_or(|b| miss < b.3) {
            best = Some((k, up, down, miss));
        }
    }
    // `used` has a free axis whenever this is called.
    best.map_or_else(
        || (0, SphericalPolygon::empty(), SphericalPolygon::empty()),
        |(k, up, down, _)| (k, up, down),
    )
}

/// The full sphere as the four faces of a regular tetrahedron, positively oriented.
fn tetrahedron() -> [[DVec3; 3]; 4] {
    let s = 1.0 / crate::math::sqrt(3.0);
    let v = [
        DVec3::new(s, s, s),
        DVec3::new(s, -s, -s),
        DVec3::new(-s, s, -s),
        DVec3::new(-s, -s, s),
    ];
    let face = |i: usize, j: usize, k: usize| {
        if orient(v[i], v[j], v[k]) > 0 {
            [v[i], v[j], v[k]]
        } else {
            [v[i], v[k], v[j]]
        }
    };
    [face(0, 1, 2), face(0, 1, 3), face(0, 2, 3), face(1, 2, 3)]
}

/// The triangles of the region inside one gnomonic chart about `c` (every vertex has
/// `v . c >= CHART_COS`): the constrained Delaunay triangulation of the projected vertices and
/// edges, keeping the triangles on the region's side of the edges; with `complement` (the region
/// contains `-c`), also the fan from `-c` (appended to `ix.verts`) over the reversed convex hull.
fn chart(ix: &mut Indexed, c: DVec3, complement: bool) -> Result<Vec<[u32; 3]>, GeomError> {
    let (u, v) = tangent_frame(c);
    // p . u written as (p - c) . u + c . u: the difference keeps the relative precision of small
    // offsets from c (tiny polygons), and c . u, a constant of rounding size, keeps the map
    // projective (lines to lines) exactly as p . u would.
    let (cu, cv) = (c.dot(u), c.dot(v));
    let pts: Vec<DVec2> = ix
        .verts
        .iter()
        .map(|&p| {
            let d = p - c;
            let w = p.dot(c);
            DVec2::new((d.dot(u) + cu) / w, (d.dot(v) + cv) / w)
        })
        .collect();
    let (mut tris, mut inside) = planar_triangles(ix, &pts)?;
    if complement {
        let mut directed: Vec<[u32; 2]> = tris
            .iter()
            .flat_map(|t| [[t[0], t[1]], [t[1], t[2]], [t[2], t[0]]])
            .collect();
        directed.sort_unstable();
        let hull: Vec<[u32; 2]> = directed
            .iter()
            .filter(|&&[i, j]| directed.binary_search(&[j, i]).is_err())
            .copied()
            .collect();
        // The apex: the antipode of the hull vertices' mean direction, whose image lies strictly
        // inside the projected hull (a positive combination of its vertices), so every fan
        // triangle is proper. The cap's center itself can lie on the hull's boundary (a cap
        // fixed by two vertices), which makes hemisphere-sized slivers.
        let mean: DVec3 = hull.iter().map(|e| ix.verts[e[0] as usize]).sum();
        let apex_dir = normalize_any(-mean).ok_or(GeomError::Undecidable(
            "degenerate convex hull in the chart",
        ))?;
        let apex = ix.verts.len() as u32;
        ix.verts.push(apex_dir);
        for &[i, j] in &hull {
            tris.push([apex, j, i]);
            inside.push(true);
        }
    }
    // After the fan: a sliver on the hull between vertices that set operations left on one
    // great circle can be inverted on the sphere, and is repaired by a flip with its fan
    // triangle.
    flip_inverted(&ix.verts, &mut tris, &inside, &ix.edges)?;
    Ok(kept(&tris, &inside))
}

/// The triangles with `inside` set.
fn kept(tris: &[[u32; 3]], inside: &[bool]) -> Vec<[u32; 3]> {
    tris.iter()
        .zip(inside)
        .filter(|(_, k)| **k)
        .map(|(t, _)| *t)
        .collect()
}

/// Smallest chord from a stereographic pole to every vertex: the projection's coordinates stay
/// below `2 / STEREO_CLEARANCE` (the image of a point at chord `d` from the pole lies at
/// `sqrt(4 - d^2) / d`).
const STEREO_CLEARANCE: f64 = 0.05;

/// Poles for [`stereographic_chart`], best first (at most [`CHART_TRIES`]): directions outside
/// the region, at least [`STEREO_CLEARANCE`] from every vertex, among a few candidates (the axes,
/// the region's area vector and the vertex means of its first rings, and their antipodes),
/// farthest from the vertices first.
fn stereographic_poles(poly: &SphericalPolygon, verts: &[DVec3]) -> Vec<DVec3> {
    let mut cands: Vec<(f64, DVec3)> = Vec::with_capacity(16);
    let mut add = |d: Option<DVec3>| {
        if let Some(d) = d {
            for d in [d, -d] {
                let chord2 = verts
                    .iter()
                    .map(|&v| (v - d).length_squared())
                    .fold(f64::INFINITY, f64::min);
                if chord2 >= STEREO_CLEARANCE * STEREO_CLEARANCE {
                    cands.push((chord2, d));
                }
            }
        }
    };
    let mut area_vector = DVec3::ZERO;
    for (k, ring) in poly.rings().enumerate() {
        let n = ring.len();
        for i in 0..n {
            let (a, b) = (ring[i], ring[(i + 1) % n]);
            area_vector += a.cross(b - a);
        }
        if k < 4 {
            add(normalize_any(ring.iter().copied().sum::<DVec3>()));
        }
    }
    add(normalize_any(area_vector));
    for axis in &AXES[..3] {
        add(Some(*axis));
    }
    cands.sort_unstable_by(|a, b| b.0.total_cmp(&a.0));
    cands
        .into_iter()
        .map(|(_, d)| d)
        .filter(|&d| !poly.contains(d))
        .take(CHART_TRIES)
        .collect()
}

/// How many charts (centers for step 2, poles for step 3 of [`SphericalPolygon::triangulate`])
/// are tried before the next method.
const CHART_TRIES: usize = 3;

/// Centers for the gnomonic chart about the cap center `c` holding every vertex within chord
/// `r`. A wide cap's chart is first turned 1e-3 rad off `c`, so that points on a circle about
/// `c` (symmetric rings, round silhouettes) are not cocircular in the plane, where every
/// in-circle test takes the exact slow path; then `c` itself and a turn by 0.01 rad. A narrow
/// cap (below 0.01) is charted about `c` first (a turn larger than the polygon would only make
/// its coordinates small differences of large ones), then turned by a tenth of its size two
/// ways. Zero vectors where normalizing fails; callers skip them and any center that leaves a
/// vertex below [`CHART_COS`].
fn chart_centers(c: DVec3, r: f64) -> [DVec3; CHART_TRIES] {
    let (u, v) = tangent_frame(c);
    let turn = |t: DVec3| normalize_any(c + t).unwrap_or(DVec3::ZERO);
    let (a, b) = (u + v * 0.37, v - u * 0.5);
    if r > 0.01 {
        [turn(a * 1e-3), c, turn(b * 0.01)]
    } else {
        [c, turn(a * (0.1 * r)), turn(b * (0.1 * r))]
    }
}

/// The triangles of the region in the stereographic projection from `pole` (outside the
/// region), onto the plane through the origin orthogonal to it (`p -> (p . u, p . v) / (1 - p .
/// pole)`, with `u, v, -pole` right-handed so that orientation is kept): the constrained
/// Delaunay triangulation of the projected vertices and edges, keeping the triangles on the
/// region's side. The projection maps great circles to circles, not lines, so the planar
/// triangles are only candidates for spherical ones; the certificate decides. Without the
/// stretch below, the triangulation without constraints would be the sphere's Delaunay
/// triangulation whatever the pole (the projection keeps circles), which is what makes this a
/// good guess: well-shaped spherical triangles whose straight images rarely disagree with their
/// arcs.
fn stereographic_chart(ix: &Indexed, pole: DVec3) -> Result<Vec<[u32; 3]>, GeomError> {
    let (u, v) = tangent_frame(-pole);
    // The projection keeps circles, so points on one circle of the sphere (the rings of a band,
    // a round light's silhouette) are cocircular in the plane, where every in-circle test takes
    // the exact slow path. A stretch by 5% along a direction no regular polygon is symmetric
    // about (1 rad from u) breaks that; it maps segments to segments, so the triangulation is
    // as valid a candidate as before, only no longer Delaunay.
    let (du, dv) = (crate::math::cos(1.0), crate::math::sin(1.0));
    let pts: Vec<DVec2> = ix
        .verts
        .iter()
        .map(|&p| {
            // 1 - p . pole as half the squared chord, without cancellation near the pole.
            let w = 0.5 * (p - pole).length_squared();
            let (x, y) = (p.dot(u) / w, p.dot(v) / w);
            let along = 0.05 * (x * du + y * dv);
            DVec2::new(x + along * du, y + along * dv)
        })
        .collect();
    let (mut tris, inside) = planar_triangles(ix, &pts)?;
    flip_inverted(&ix.verts, &mut tris, &inside, &ix.edges)?;
    Ok(kept(&tris, &inside))
}

/// Repairs planar triangles that are not positively oriented on the sphere (exact `orient3d`)
/// by flipping their longest edge, the one the middle vertex of a sliver lies along: a chart's
/// rounded coordinates can put a vertex within rounding of another edge on the wrong side of
/// it (vertices that set operations placed on edges), and a stereographic chart's straight
/// edges are not the images of arcs. A flip replaces the triangles `(a, b, c)` and `(b, a, d)`
/// of edge `ab` by `(c, a, d)` and `(d, b, c)`, taken only when both are positive on the sphere;
/// the triangles keep covering the same planar region, so labelling is unaffected. Only triangles
/// with `inside` set are repaired (`ab` is not a polygon edge, so its other triangle is inside
/// too): the others are not part of the result.
///
/// # Errors
///
/// [`GeomError::Undecidable`] when an inverted triangle's longest edge is a polygon edge or on
/// the convex hull, when a flip would invert another triangle, or after `4 n` flips: the chart
/// cannot be repaired this way.
fn flip_inverted(
    verts: &[DVec3],
    tris: &mut [[u32; 3]],
    inside: &[bool],
    edges: &[[u32; 2]],
) -> Result<(), GeomError> {
    let positive = |t: [u32; 3]| {
        orient(
            verts[t[0] as usize],
            verts[t[1] as usize],
            verts[t[2] as usize],
        ) == 1
    };
    let mut queue: Vec<usize> = (0..tris.len())
        .filter(|&k| inside[k] && !positive(tris[k]))
        .collect();
    if queue.is_empty() {
        return Ok(());
    }
    let fail = GeomError::Undecidable("a chart's triangle is inverted on the sphere");
    let mut constraint: Vec<[u32; 2]> = edges
        .iter()
        .map(|&[i, j]| if i < j { [i, j] } else { [j, i] })
        .collect();
    constraint.sort_unstable();
    // Directed edge -> triangle, built only when a repair is needed.
    let mut owner: BTreeMap<[u32; 2], usize> = BTreeMap::new();
    for (k, t) in tris.iter().enumerate() {
        for s in 0..3 {
            owner.insert([t[s], t[(s + 1) % 3]], k);
        }
    }
    let mut flips = 0;
    while let Some(k) = queue.pop() {
        let t = tris[k];
        if positive(t) {
            continue;
        }
        flips += 1;
        if flips > 4 * tris.len() {
            return Err(fail);
        }
        let chord =
            |s: usize| (verts[t[s] as usize] - verts[t[(s + 1) % 3] as usize]).length_squared();
        let s = (0..3)
            .max_by(|&x, &y| chord(x).total_cmp(&chord(y)))
            .unwrap_or(0);
        let (a, b, c) = (t[s], t[(s + 1) % 3], t[(s + 2) % 3]);
        let key = if a < b { [a, b] } else { [b, a] };
        if constraint.binary_search(&key).is_ok() {
            return Err(fail);
        }
        let Some(&m) = owner.get(&[b, a]).filter(|&&m| inside[m]) else {
            return Err(fail); // the convex hull
        };
        let u = tris[m];
        let Some(&d) = u.iter().find(|&&x| x != a && x != b) else {
            return Err(fail);
        };
        let (t1, t2) = ([c, a, d], [d, b, c]);
        if !positive(t1) || !positive(t2) {
            return Err(fail);
        }
        for old in [t, u] {
            for s in 0..3 {
                owner.remove(&[old[s], old[(s + 1) % 3]]);
            }
        }
        tris[k] = t1;
        tris[m] = t2;
        for (idx, new) in [(k, t1), (m, t2)] {
            for s in 0..3 {
                owner.insert([new[s], new[(s + 1) % 3]], idx);
            }
        }
    }
    Ok(())
}

/// A directed edge `i -> j` as one integer, for sorting and searching.
#[inline]
fn edge_key(i: u32, j: u32) -> u64 {
    (u64::from(i) << 32) | u64::from(j)
}

/// The planar constrained Delaunay triangulation of the chart points `pts` (indexed as
/// `ix.verts`) with the polygon's edges as constraints, and which of its triangles lie in the
/// region ([`label`]). The labels come from the plane, where the sides of the constraint edges
/// are consistent by construction; the caller repairs the kept triangles that rounding made
/// inverted on the sphere ([`flip_inverted`]).
fn planar_triangles(ix: &Indexed, pts: &[DVec2]) -> Result<(Vec<[u32; 3]>, Vec<bool>), GeomError> {
    let segs: Vec<[usize; 2]> = ix
        .edges
        .iter()
        .map(|e| [e[0] as usize, e[1] as usize])
        .collect();
    let Cdt {
        tris,
        across,
        constraint,
    } = constrained_delaunay(pts, &segs)?;
    let tris: Vec<[u32; 3]> = tris.into_iter().map(|t| t.map(|i| i as u32)).collect();
    let inside = label(&tris, &across, &constraint, &ix.edges)?;
    Ok((tris, inside))
}

/// Which triangles (counter-clockwise index triples) lie in the region bounded by the directed
/// `edges` (region on their left): a triangle with edge `i -> j` is inside, one with `j -> i`
/// outside, and the label spreads across edges that are not polygon edges. `across` and
/// `constraint` are the adjacency and constraint bits of [`Cdt`]: only constraint edges can be
/// polygon edges.
fn label(
    tris: &[[u32; 3]],
    across: &[[u32; 3]],
    constraint: &[u8],
    edges: &[[u32; 2]],
) -> Result<Vec<bool>, GeomError> {
    let mut boundary: Vec<u64> = edges.iter().map(|&[i, j]| edge_key(i, j)).collect();
    boundary.sort_unstable();
    let is_edge = |i: u32, j: u32| boundary.binary_search(&edge_key(i, j)).is_ok();
    // Per triangle edge: 1 a polygon edge (region on this side), 0 a reversed one, -1 neither.
    let side: Vec<[i8; 3]> = tris
        .iter()
        .zip(constraint)
        .map(|(t, &c)| {
            core::array::from_fn(|s| {
                let (i, j) = (t[s], t[(s + 1) % 3]);
                if c & (1 << s) == 0 {
                    -1
                } else if is_edge(i, j) {
                    1
                } else if is_edge(j, i) {
                    0
                } else {
                    -1
                }
            })
        })
        .collect();
    let undecided = GeomError::Undecidable("triangles on both sides of a polygon edge");
    let mut state: Vec<i8> = alloc::vec![-1; tris.len()];
    let mut stack: Vec<u32> = Vec::new();
    for (k, sides) in side.iter().enumerate() {
        for &sd in sides {
            if sd < 0 {
                continue;
            }
            if state[k] == -1 {
                state[k] = sd;
                stack.push(k as u32);
            } else if state[k] != sd {
                return Err(undecided);
            }
        }
    }
    while let Some(k) = stack.pop() {
        let k = k as usize;
        for s in 0..3 {
            let nb = across[k][s];
            if side[k][s] >= 0 || nb == Cdt::HULL {
                continue;
            }
            let nb = nb as usize;
            if state[nb] == -1 {
                state[nb] = state[k];
                stack.push(nb as u32);
            } else if state[nb] != state[k] {
                return Err(undecided);
            }
        }
    }
    if state.contains(&-1) {
        return Err(GeomError::Undecidable(
            "a part of the planar triangulation touches no polygon edge",
        ));
    }
    Ok(state.into_iter().map(|s| s == 1).collect())
}

/// Largest rounding error of a result triangle's area (sr) that the certificate accepts: a
/// triangle with nearly antipodal vertices nearly on one great circle (a diagonal across a region
/// about a hemisphere wide) has an area that rounding decides at will; another candidate avoids
/// that diagonal.
const MAX_AREA_ERROR: f64 = 1e-11;

/// Whether `tris` tiles exactly the region of solid angle `area` bounded by the directed
/// `edges` (see [`SphericalPolygon::triangulate`]): every triangle positively oriented (exact)
/// and at least [`HEMISPHERE_MARGIN`] short of a hemisphere,
/// every directed triangle edge a polygon edge or cancelled by its reverse, every polygon edge
/// used, and the areas adding up to `area` within `2 pi`.
fn certify(verts: &[DVec3], tris: &[[u32; 3]], edges: &[[u32; 2]], area: f64) -> bool {
    let mut sum = 0.0;
    for t in tris {
        let [a, b, c] = t.map(|i| verts[i as usize]);
        if orient(a, b, c) != 1 {
            return false;
        }
        // Van Oosterom-Strackee. The sum needs only to tell multiples of 4 pi apart, so the
        // plain form does where its denominator is not small; where it is (a fan triangle from
        // the far side of a tiny polygon, nearly antipodal vertices) it cancels to rounding noise
        // and an area of any sign, and the form on differences is used.
        let den = 1.0 + a.dot(b) + b.dot(c) + c.dot(a);
        let w = if den >= 0.5 {
            2.0 * crate::math::atan2(a.dot((b - a).cross(c - a)), den)
        } else {
            let (w, err) = signed_solid_angle_with_error(a, b, c);
            if !(err <= MAX_AREA_ERROR) {
                return false;
            }
            w
        };
        // Triangles within HEMISPHERE_MARGIN of a hemisphere (three vertices nearly on a great
        // circle) are valid but beyond what sampling resolves; another method splits them.
        if !(w <= 2.0 * PI - HEMISPHERE_MARGIN) {
            return false;
        }
        sum += w;
    }
    if !((sum - area).abs() < 2.0 * PI) {
        return false;
    }
    // (undirected key, direction, weight): triangles count +1, polygon edges -1; the net count
    // of each direction must match the other's and be >= 0.
    let mut all: Vec<(u64, u8, i32)> = Vec::with_capacity(3 * tris.len() + edges.len());
    let mut add = |i: u32, j: u32, w: i32| {
        if i < j {
            all.push((edge_key(i, j), 0, w));
        } else {
            all.push((edge_key(j, i), 1, w));
        }
    };
    for t in tris {
        add(t[0], t[1], 1);
        add(t[1], t[2], 1);
        add(t[2], t[0], 1);
    }
    for e in edges {
        add(e[0], e[1], -1);
    }
    all.sort_unstable_by_key(|x| x.0);
    let mut k = 0;
    while k < all.len() {
        let mut net = [0i32; 2];
        let key = all[k].0;
        while k < all.len() && all[k].0 == key {
            net[all[k].1 as usize] += all[k].2;
            k += 1;
        }
        if net[0] != net[1] || net[0] < 0 {
            return false;
        }
    }
    true
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A fan whose triangles are all positive can still cover the sphere more than once: from
    /// the north pole, a ring that runs twice round a southern circle (the way that makes the
    /// fan positive) gives triangles summing to twice the sphere minus the southern cap.
    /// Only the sum (>= 4 pi) tells; no valid polygon of the integration tests has such a ring,
    /// so the check is tested here on the raw ring.
    #[test]
    fn fan_winding_twice_is_rejected() {
        let south = |k: usize| {
            let t = 2.0 * PI * k as f64 / 7.0;
            DVec3::new(0.5 * t.cos(), 0.5 * t.sin(), -0.8).normalize()
        };
        let mut ring = alloc::vec![DVec3::Z];
        ring.extend((0..=14).map(|k| south(k % 7)));
        let tris: Vec<[DVec3; 3]> = ring[1..]
            .windows(2)
            .map(|w| [ring[0], w[0], w[1]])
            .collect();
        assert!(tris.iter().all(|&[a, b, c]| orient(a, b, c) == 1));
        assert_eq!(fan_from_first(&ring), None);
        // Once round: the sphere minus the cap, accepted.
        assert_eq!(fan_from_first(&ring[..9]).map(|f| f.len()), Some(7));
    }
}
