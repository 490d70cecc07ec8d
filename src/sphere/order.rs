//! Ordering of unordered silhouette edges into oriented rings.

use alloc::vec::Vec;
use core::f64::consts::PI;

use glam::DVec3;
use smallvec::SmallVec;

use super::polygon::{SphericalPolygon, ring_left_area, rings_contain};
use super::predicates::normalize_any;
use crate::GeomError;

/// Endpoints of different edges closer than this chord length are the same silhouette vertex.
///
/// Silhouette edges come from mesh vertices transformed and normalized along different paths, so
/// shared endpoints agree only to a few ulps; 1e-9 rad is far above that rounding and far below
/// the size of any feature a renderer can resolve (a 1e-9 rad feature is 1 mm at 1000 km).
/// An edge whose two endpoints merge is shorter than that and is dropped.
pub const MATCH_TOLERANCE: f64 = 1e-9;

/// Orders unordered, undirected silhouette edges into rings.
///
/// This is Alg. 2 of the seed paper 000 (section 3.3) made robust: instead of projecting to a
/// plane and chaining each edge to the nearest endpoint (which needs a hemisphere and breaks on
/// near-ties), endpoints are merged by an explicit tolerance ([`MATCH_TOLERANCE`]) directly on
/// the sphere and every merged vertex must join exactly two edges. Edges may be given in any
/// order and direction. Several loops are allowed.
///
/// Orientation: each loop is first oriented around its smaller side; a loop nested inside an
/// odd number of others (measured by those smaller sides) becomes a hole. For the silhouette of
/// a convex object seen from outside it, the result is the object's outline, counter-clockwise.
/// When the edges carry a meaningful direction (oriented by the front face, thesis 003 section
/// 4.2), use [`order_directed_edges`], which keeps it.
///
/// # Errors
///
/// - [`GeomError::NonFinite`] / [`GeomError::ZeroVector`] for an invalid endpoint, with `ring` the
///   edge index and `vertex` 0 or 1;
/// - [`GeomError::OpenChain`] when an endpoint is used by only one edge;
/// - [`GeomError::Branching`] when more than two edges meet at an endpoint;
/// - [`GeomError::TooFewVertices`] when no edges remain, or a loop has only two vertices;
/// - any error of [`SphericalPolygon::new`] for loops that cross each other.
///
/// # Examples
///
/// ```
/// use arealight::glam::DVec3;
/// use arealight::sphere::order_edges;
///
/// let (a, b, c) = (DVec3::X, DVec3::Y, DVec3::Z);
/// // Shuffled, one edge reversed, one endpoint off by rounding.
/// let poly = order_edges(&[(c, a), (b, c), (a + DVec3::splat(1e-13), b)])?;
/// assert_eq!(poly.ring_count(), 1);
/// assert!((poly.solid_angle() - std::f64::consts::FRAC_PI_2).abs() < 1e-12);
/// # Ok::<(), arealight::GeomError>(())
/// ```
pub fn order_edges(edges: &[(DVec3, DVec3)]) -> Result<SphericalPolygon, GeomError> {
    let mut rings = chain(edges, false, MATCH_TOLERANCE)?;
    // Orient each loop around its smaller side.
    for ring in rings.iter_mut() {
        if ring_left_area(ring) > 2.0 * PI {
            ring.reverse();
        }
    }
    // Holes: loops inside an odd number of other loops' smaller sides.
    let k = rings.len();
    if k > 1 {
        let depth: SmallVec<[usize; 4]> = (0..k)
            .map(|j| {
                (0..k)
                    .filter(|&i| {
                        i != j && rings_contain(core::iter::once(&rings[i][..]), rings[j][0])
                    })
                    .count()
            })
            .collect();
        for (ring, d) in rings.iter_mut().zip(depth) {
            if d % 2 == 1 {
                ring.reverse();
            }
        }
    }
    SphericalPolygon::new(rings)
}

/// Orders directed silhouette edges into rings, keeping each edge's direction: every edge must
/// start where another ends (up to [`MATCH_TOLERANCE`]). The interior is on the left of each
/// edge, as for [`SphericalPolygon`]; silhouette edges oriented by their front face (thesis 003
/// section 4.2) have exactly this property.
///
/// # Errors
///
/// As [`order_edges`]; an edge whose end starts no other edge (for example one given reversed) is
/// an [`GeomError::OpenChain`], and [`GeomError::InconsistentOrientation`] reports loops whose
/// directions contradict each other.
pub fn order_directed_edges(edges: &[(DVec3, DVec3)]) -> Result<SphericalPolygon, GeomError> {
    order_directed_edges_within(edges, MATCH_TOLERANCE)
}

/// [`order_directed_edges`] with endpoints merged within `tolerance` (chord length) instead of
/// [`MATCH_TOLERANCE`]: for edges whose shared endpoints are copies a few ulps apart, where
/// features between `tolerance` and [`MATCH_TOLERANCE`] must survive.
pub(crate) fn order_directed_edges_within(
    edges: &[(DVec3, DVec3)],
    tolerance: f64,
) -> Result<SphericalPolygon, GeomError> {
    SphericalPolygon::new(chain(edges, true, tolerance)?)
}

/// Merges endpoints closer than `tolerance` and walks the loops. With `directed`, loops follow
/// the edges' directions.
fn chain(
    edges: &[(DVec3, DVec3)],
    directed: bool,
    tolerance: f64,
) -> Result<Vec<Vec<DVec3>>, GeomError> {
    let n = edges.len();
    let mut pts: Vec<DVec3> = Vec::with_capacity(2 * n);
    for (e, &(a, b)) in edges.iter().enumerate() {
        for (k, p) in [a, b].into_iter().enumerate() {
            if !p.is_finite() {
                return Err(GeomError::NonFinite { ring: e, vertex: k });
            }
            pts.push(normalize_any(p).ok_or(GeomError::ZeroVector { ring: e, vertex: k })?);
        }
    }
    let cluster = merge_endpoints(&pts, tolerance);
    let nclusters = cluster.iter().copied().max().map_or(0, |m| m + 1);

    // Representative of each merged vertex: the normalized mean of its members, so the result does
    // not depend on the order the edges came in.
    let mut sum = alloc::vec![DVec3::ZERO; nclusters];
    for (p, &c) in pts.iter().zip(&cluster) {
        sum[c] += *p;
    }
    let rep: Vec<DVec3> = sum
        .iter()
        .zip(&pts)
        .map(|(s, p)| normalize_any(*s).unwrap_or(*p))
        .collect();

    // Incidence lists: for each vertex the edges (and which end) touching it.
    let mut out_of: Vec<SmallVec<[usize; 2]>> = alloc::vec![SmallVec::new(); nclusters];
    let mut into: Vec<SmallVec<[usize; 2]>> = alloc::vec![SmallVec::new(); nclusters];
    let mut live: Vec<bool> = alloc::vec![false; n];
    for e in 0..n {
        let (ca, cb) = (cluster[2 * e], cluster[2 * e + 1]);
        if ca == cb {
            continue; // collapsed below the matching tolerance
        }
        live[e] = true;
        out_of[ca].push(e);
        into[cb].push(e);
    }
    for e in (0..n).filter(|&e| live[e]) {
        for c in [cluster[2 * e], cluster[2 * e + 1]] {
            let (o, i) = (out_of[c].len(), into[c].len());
            // Directed loops may pinch (touch themselves or each other at a vertex): any even
            // degree with as many edges in as out. Undirected loops cannot be told apart there.
            if directed {
                if o != i {
                    return Err(GeomError::OpenChain { edge: e });
                }
            } else if o + i > 2 {
                return Err(GeomError::Branching { edge: e });
            } else if o + i < 2 {
                return Err(GeomError::OpenChain { edge: e });
            }
        }
    }

    let mut used = alloc::vec![false; n];
    let mut rings = Vec::new();
    for start in 0..n {
        if !live[start] || used[start] {
            continue;
        }
        let mut ring = Vec::new();
        let mut e = start;
        let mut at = cluster[2 * start]; // vertex the walk is leaving along e
        // Each step consumes an unused edge, so the walk ends within n steps.
        for _ in 0..n {
            used[e] = true;
            ring.push(rep[at]);
            let (ca, cb) = (cluster[2 * e], cluster[2 * e + 1]);
            let from = at;
            at = if at == ca { cb } else { ca };
            let next = if directed {
                // At a pinch, continue along the outgoing edge first met turning clockwise from
                // the edge we came in on: that keeps the loops touching without crossing.
                let pick =
                    pick_clockwise(rep[from], rep[at], &out_of[at], |f| rep[cluster[2 * f + 1]]);
                if pick == start {
                    break;
                }
                Some(pick).filter(|&f| !used[f])
            } else {
                let cand = out_of[at].iter().chain(into[at].iter()).copied();
                cand.into_iter().find(|&f| !used[f])
            };
            match next {
                Some(f) => e = f,
                None if directed => {
                    return Err(GeomError::Degenerate(
                        "directed edges revisit an edge before closing a loop",
                    ));
                }
                None => break,
            }
        }
        if ring.len() < 3 {
            return Err(GeomError::TooFewVertices {
                ring: rings.len(),
                count: ring.len(),
            });
        }
        rings.push(ring);
    }
    if rings.is_empty() {
        return Err(GeomError::TooFewVertices { ring: 0, count: 0 });
    }
    Ok(rings)
}

/// Among the edges `cands` leaving `at` (their far ends given by `far`), the one first met
/// turning clockwise about `at` from the direction back toward `from`.
fn pick_clockwise(from: DVec3, at: DVec3, cands: &[usize], far: impl Fn(usize) -> DVec3) -> usize {
    if cands.len() == 1 {
        return cands[0];
    }
    let (u, v) = super::predicates::tangent_frame(at);
    let ang = |p: DVec3| crate::math::atan2(p.dot(v), p.dot(u));
    let back = ang(from);
    let mut best = (f64::INFINITY, cands[0]);
    for &f in cands {
        let cw = (back - ang(far(f))).rem_euclid(2.0 * PI);
        // A zero turn would retrace the incoming edge: that is the last choice, not the first.
        let cw = if cw <= 0.0 { 2.0 * PI } else { cw };
        if cw < best.0 {
            best = (cw, f);
        }
    }
    best.1
}

/// Union–find of endpoints closer than `tolerance`: sort by x and compare only within the
/// tolerance window, so the cost is near linear for well-separated vertices. Returns dense
/// cluster ids in first-appearance order.
fn merge_endpoints(pts: &[DVec3], tolerance: f64) -> Vec<usize> {
    let m = pts.len();
    let mut parent: Vec<usize> = (0..m).collect();
    fn find(parent: &mut [usize], mut i: usize) -> usize {
        while parent[i] != i {
            parent[i] = parent[parent[i]];
            i = parent[i];
        }
        i
    }
    let mut order: Vec<usize> = (0..m).collect();
    order.sort_by(|&i, &j| pts[i].x.total_cmp(&pts[j].x));
    for (k, &i) in order.iter().enumerate() {
        for &j in &order[k + 1..] {
            if pts[j].x - pts[i].x > tolerance {
                break;
            }
            if (pts[i] - pts[j]).length() <= tolerance {
                let (ri, rj) = (find(&mut parent, i), find(&mut parent, j));
                parent[ri.max(rj)] = ri.min(rj);
            }
        }
    }
    let mut id = alloc::vec![usize::MAX; m];
    let mut out = Vec::with_capacity(m);
    let mut next = 0;
    for i in 0..m {
        let r = find(&mut parent, i);
        if id[r] == usize::MAX {
            id[r] = next;
            next += 1;
        }
        out.push(id[r]);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use alloc::vec;

    fn square(h: f64, z: f64) -> [DVec3; 4] {
        [
            DVec3::new(h, -h, z),
            DVec3::new(h, h, z),
            DVec3::new(-h, h, z),
            DVec3::new(-h, -h, z),
        ]
    }

    fn edges_of(r: &[DVec3]) -> Vec<(DVec3, DVec3)> {
        (0..r.len()).map(|i| (r[i], r[(i + 1) % r.len()])).collect()
    }

    #[test]
    fn errors_for_open_and_branching() {
        let s = square(0.3, 1.0);
        let mut e = edges_of(&s);
        e.pop();
        assert!(matches!(order_edges(&e), Err(GeomError::OpenChain { .. })));
        let mut e = edges_of(&s);
        e.push((s[0], s[2]));
        assert!(matches!(order_edges(&e), Err(GeomError::Branching { .. })));
        assert_eq!(
            order_edges(&[]),
            Err(GeomError::TooFewVertices { ring: 0, count: 0 })
        );
        let e = vec![(s[0], s[1]), (s[1], s[0])];
        assert!(matches!(
            order_edges(&e),
            Err(GeomError::TooFewVertices { .. })
        ));
    }

    #[test]
    fn two_loops_nested_become_outer_and_hole() {
        let mut e = edges_of(&square(0.5, 1.0));
        let mut inner = square(0.1, 1.0);
        inner.reverse(); // given clockwise; order_edges must not care
        e.extend(edges_of(&inner).into_iter().map(|(a, b)| (b, a)));
        e.reverse();
        let p = order_edges(&e).unwrap();
        assert_eq!(p.ring_count(), 2);
        let outer = SphericalPolygon::new(vec![square(0.5, 1.0).to_vec()]).unwrap();
        let hole = SphericalPolygon::new(vec![square(0.1, 1.0).to_vec()]).unwrap();
        assert!((p.solid_angle() - (outer.solid_angle() - hole.solid_angle())).abs() < 1e-14);
        assert!(!p.contains(DVec3::Z));
    }

    #[test]
    fn directed_keeps_orientation_and_rejects_reversal() {
        let mut s = square(0.5, 1.0);
        s.reverse();
        let p = order_directed_edges(&edges_of(&s)).unwrap();
        // Clockwise: the region is everything but the square.
        assert!(p.solid_angle() > 2.0 * PI);
        let mut e = edges_of(&s);
        e[1] = (e[1].1, e[1].0);
        assert!(matches!(
            order_directed_edges(&e),
            Err(GeomError::OpenChain { .. })
        ));
    }
}
