//! Triangulation of spherical polygons into minor-arc triangles (thesis 003, chapter 6), each
//! result certified exactly before it is returned.

use alloc::vec::Vec;
use core::f64::consts::PI;

use glam::{DVec2, DVec3};

use super::gnomonic::enclosing_cap;
use super::polygon::SphericalPolygon;
use super::predicates::{AXES, normalize_any, orient, tangent_frame, triangle_solid_angle};
use super::sample::{SphericalTriangle, signed_solid_angle};
use crate::GeomError;
use crate::planar::constrained_delaunay;

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
    /// 2. vertices in a cap narrower than a hemisphere: the gnomonic projection about the cap's
    ///    center maps arcs to segments, so the constrained Delaunay triangulation of the
    ///    projected vertices with the edges as constraints, restricted to the region (labels
    ///    spread from the edges' sides), is a spherical triangulation; no extra vertex, or, when
    ///    the region contains the far side of the chart (a complement), one: the antipode of the
    ///    hull vertices' mean direction, fanned over the projected convex hull;
    /// 3. a single ring star-shaped about a point (its area vector, or an axis): the fan from
    ///    that point (one extra vertex);
    /// 4. otherwise the region is cut in two by the coordinate plane `x = 0` (exact hemisphere
    ///    clipping, [`SphericalPolygon::clip_to_hemisphere`]), each half solved the same way, then
    ///    `y = 0`, then `z = 0`; an octant always fits a chart. The cuts add vertices where edges
    ///    cross the planes and where the cut circles need them; thesis 003 section 6.2 needs extra
    ///    vertices where arcs longer than `pi` would be required, and these are the only cases
    ///    that reach this step.
    ///
    /// Every candidate is certified with exact predicates before it is used: each triangle is
    /// positively oriented (`orient3d`) and at least 1e-6 sr short of a hemisphere, every
    /// directed edge of the triangles is either an edge of the polygon or cancelled by its
    /// reverse, and the areas add up to the region's within `2 pi`. The first two make the
    /// number of triangles over any direction off the edges equal to the region's indicator
    /// plus a constant `k`, and the third makes `k = 0`: the triangles tile the region exactly
    /// (for step 4, each half exactly; the halves tile the region up to the rounding of the
    /// crossing points the clipping computes). Deterministic; no sampling.
    ///
    /// Triangles certified positive whose area rounds to zero (slivers below rounding between
    /// nearly collinear vertices) are left out: they cover nothing beyond rounding of an edge.
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
    /// when the triangles' areas miss the region's by more than `1e-9` relative (which would
    /// mean a clipping fault). Never a wrong triangulation.
    pub fn triangulate(&self) -> Result<Vec<SphericalTriangle>, GeomError> {
        let mut tris: Vec<[DVec3; 3]> = Vec::new();
        solve(self, 0, &mut tris)?;
        let mut out = Vec::with_capacity(tris.len());
        let mut sum = 0.0;
        for [a, b, c] in tris {
            match SphericalTriangle::from_unit(a, b, c) {
                Ok(t) => {
                    sum += t.solid_angle();
                    out.push(t);
                }
                // Certified positive, area below rounding.
                Err(GeomError::Degenerate(_)) => {}
                Err(e) => return Err(e),
            }
        }
        let area = region_area(self);
        if !((sum - area).abs() <= 1e-9 * area + 1e-300) {
            return Err(GeomError::Undecidable(
                "triangle areas do not add up to the polygon's",
            ));
        }
        Ok(out)
    }
}

/// The region's solid angle, reduced modulo `4 pi` only after the rings' signed fan sums (from
/// a vertex or axis far from every antipode of the ring; a triangle's area is defined modulo `4 pi` even where its far edge
/// passes the apex's antipode, see [`signed_solid_angle`]) are added, so that a tiny outer ring and its tiny hole cancel as small numbers (reducing each
/// ring first, as a ring's own left area must be, leaves the hole at `4 pi - epsilon`, which
/// cannot hold `epsilon` to relative precision).
fn region_area(poly: &SphericalPolygon) -> f64 {
    if poly.is_full() {
        return 4.0 * PI;
    }
    let mut sum = 0.0;
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
                sum += signed_solid_angle(apex, b, c);
            }
        }
    }
    sum.rem_euclid(4.0 * PI)
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

    /// The rings' vertex ids in order (for the single-ring fans).
    fn single_ring(&self) -> Vec<u32> {
        self.edges.iter().map(|e| e[0]).collect()
    }
}

/// Triangulates `poly` into `out`; `depth` is the number of coordinate cuts already made.
fn solve(
    poly: &SphericalPolygon,
    depth: usize,
    out: &mut Vec<[DVec3; 3]>,
) -> Result<(), GeomError> {
    if poly.is_empty() {
        return Ok(());
    }
    if poly.is_full() {
        out.extend(tetrahedron());
        return Ok(());
    }
    let mut ix = Indexed::new(poly);
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
    // 2. One gnomonic chart.
    if let Ok((c, cos_r)) = enclosing_cap(&ix.verts)
        && cos_r >= CHART_COS
    {
        let n = ix.verts.len();
        let complement = poly.contains(-c);
        if let Ok(tris) = chart(&mut ix, c, complement)
            && certify(&ix.verts, &tris, &ix.edges, area)
        {
            emit(&ix, &tris, out);
            return Ok(());
        }
        ix.verts.truncate(n);
    }
    // 3. A fan from a point the ring is star-shaped about.
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
    // 4. Cut by the next coordinate plane.
    if depth < 3 {
        let n = AXES[depth];
        solve(&poly.clip_to_hemisphere(n), depth + 1, out)?;
        return solve(&poly.clip_to_hemisphere(-n), depth + 1, out);
    }
    Err(GeomError::Undecidable(
        "no chart of an octant triangulates the polygon within rounding",
    ))
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
    let segs: Vec<[usize; 2]> = ix
        .edges
        .iter()
        .map(|e| [e[0] as usize, e[1] as usize])
        .collect();
    let tris: Vec<[u32; 3]> = constrained_delaunay(&pts, &segs)?
        .into_iter()
        .map(|t| t.map(|i| i as u32))
        .collect();
    let inside = label(&tris, &ix.edges)?;
    let mut out: Vec<[u32; 3]> = tris
        .iter()
        .zip(&inside)
        .filter(|(_, k)| **k)
        .map(|(t, _)| *t)
        .collect();
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
            out.push([apex, j, i]);
        }
    }
    Ok(out)
}

/// Which triangles (counter-clockwise index triples) lie in the region bounded by the directed
/// `edges` (region on their left): a triangle with edge `i -> j` is inside, one with `j -> i`
/// outside, and the label spreads across edges that are not polygon edges.
fn label(tris: &[[u32; 3]], edges: &[[u32; 2]]) -> Result<Vec<bool>, GeomError> {
    let mut boundary: Vec<[u32; 2]> = edges.to_vec();
    boundary.sort_unstable();
    let is_edge = |e: [u32; 2]| boundary.binary_search(&e).is_ok();
    // Directed edges of the triangles, for the neighbor across each edge.
    let mut half: Vec<([u32; 2], u32)> = Vec::with_capacity(3 * tris.len());
    for (k, t) in tris.iter().enumerate() {
        for s in 0..3 {
            half.push(([t[s], t[(s + 1) % 3]], k as u32));
        }
    }
    half.sort_unstable();
    let undecided = GeomError::Undecidable("triangles on both sides of a polygon edge");
    let mut state: Vec<i8> = alloc::vec![-1; tris.len()];
    let mut stack: Vec<u32> = Vec::new();
    for (k, t) in tris.iter().enumerate() {
        for s in 0..3 {
            let (i, j) = (t[s], t[(s + 1) % 3]);
            let side = if is_edge([i, j]) {
                1
            } else if is_edge([j, i]) {
                0
            } else {
                continue;
            };
            if state[k] == -1 {
                state[k] = side;
                stack.push(k as u32);
            } else if state[k] != side {
                return Err(undecided);
            }
        }
    }
    while let Some(k) = stack.pop() {
        let t = tris[k as usize];
        for s in 0..3 {
            let (i, j) = (t[s], t[(s + 1) % 3]);
            if is_edge([i, j]) || is_edge([j, i]) {
                continue;
            }
            let Ok(at) = half.binary_search_by(|h| h.0.cmp(&[j, i])) else {
                continue; // the convex hull
            };
            let nb = half[at].1 as usize;
            if state[nb] == -1 {
                state[nb] = state[k as usize];
                stack.push(nb as u32);
            } else if state[nb] != state[k as usize] {
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
        let w = triangle_solid_angle(a, b, c);
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
    let mut all: Vec<([u32; 2], u8, i32)> = Vec::with_capacity(3 * tris.len() + edges.len());
    let mut add = |i: u32, j: u32, w: i32| {
        if i < j {
            all.push(([i, j], 0, w));
        } else {
            all.push(([j, i], 1, w));
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
