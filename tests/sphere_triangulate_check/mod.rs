//! The invariant checker of `SphericalPolygon::triangulate`, shared by the tests and the fuzz
//! target: exact orientation of every triangle, solid angles adding up, and exact coverage of a
//! deterministic set of directions (every direction not within rounding of an edge lies in as
//! many triangles as the polygon contains it: 0 or 1).
#![allow(dead_code)]
// Comparisons are written `!(x > t)` on purpose where NaN must fail the check.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use arealight::glam::DVec3;
use arealight::sphere::{SphericalPolygon, SphericalTriangle};
use robust::{Coord3D, orient3d};

/// What a triangulation looked like.
#[derive(Debug, Clone, Copy, Default)]
pub struct Report {
    pub triangles: usize,
    /// Triangle vertices that are not vertices of the polygon.
    pub extra_vertices: usize,
    /// |sum of triangle solid angles - polygon solid angle| / polygon solid angle.
    pub area_error: f64,
    /// Directions whose coverage was checked (not within rounding of an edge).
    pub checked: usize,
}

/// Sign of det(a, b, c), exact.
pub fn orient(a: DVec3, b: DVec3, c: DVec3) -> f64 {
    let k = |p: DVec3| Coord3D {
        x: p.x,
        y: p.y,
        z: p.z,
    };
    orient3d(k(a), k(b), k(c), k(DVec3::ZERO))
}

/// `n` directions spread evenly over the sphere (Fibonacci lattice).
pub fn fibonacci(n: usize) -> Vec<DVec3> {
    let golden = std::f64::consts::PI * (3.0 - 5f64.sqrt());
    (0..n)
        .map(|i| {
            let z = 1.0 - (2.0 * i as f64 + 1.0) / n as f64;
            let r = (1.0 - z * z).max(0.0).sqrt();
            let t = golden * i as f64;
            DVec3::new(r * t.cos(), r * t.sin(), z)
        })
        .collect()
}

/// Directions near the polygon's features, at offsets relative to its edges' lengths: around
/// each vertex (8 directions at 1e-3 and 0.3 of the shorter adjacent edge) and across each edge
/// midpoint (both sides at 1e-3 and 0.2 of the edge), so that tiny polygons and narrow parts
/// are probed where they are.
pub fn near_features(poly: &SphericalPolygon) -> Vec<DVec3> {
    let mut out = Vec::new();
    for ring in poly.rings() {
        let n = ring.len();
        for i in 0..n {
            let (p, v, q) = (ring[(i + n - 1) % n], ring[i], ring[(i + 1) % n]);
            let len = (v - p).length().min((q - v).length());
            let (u, w) = v.any_orthonormal_pair();
            for f in [1e-3, 0.3] {
                for k in 0..8 {
                    let t = 0.3 + k as f64 * std::f64::consts::FRAC_PI_4;
                    out.push((v + (u * t.cos() + w * t.sin()) * (f * len)).normalize());
                }
            }
            let mid = (v + (q - v) * 0.5).normalize();
            let nrm = v.cross(q - v).normalize();
            let l = (q - v).length();
            for f in [1e-3, 0.2] {
                out.push((mid + nrm * (f * l)).normalize());
                out.push((mid - nrm * (f * l)).normalize());
            }
        }
    }
    out
}

/// The polygon's solid angle with relative precision for tiny regions: the rings' signed fan
/// sums (Van Oosterom–Strackee on differences, from each ring's first vertex) added before the
/// reduction modulo `4 pi`, so that a small outer ring and its small hole (whose left side is
/// nearly the whole sphere) cancel as small numbers.
pub fn reference_area(poly: &SphericalPolygon) -> f64 {
    let four_pi = 4.0 * std::f64::consts::PI;
    if poly.is_full() {
        return four_pi;
    }
    let mut sum = 0.0;
    for ring in poly.rings() {
        // From the first vertex, or the vertex or axis farthest from every antipode (a vertex
        // antipodal to the apex has no arc to it).
        let clearance = |x: DVec3| {
            ring.iter()
                .map(|&v| (x + v).length())
                .fold(f64::INFINITY, f64::min)
        };
        let candidates = ring.iter().copied().chain([
            DVec3::X,
            DVec3::Y,
            DVec3::Z,
            -DVec3::X,
            -DVec3::Y,
            -DVec3::Z,
        ]);
        let a = if clearance(ring[0]) > 0.7 {
            ring[0]
        } else {
            candidates
                .max_by(|p, q| clearance(*p).total_cmp(&clearance(*q)))
                .unwrap()
        };
        let n = ring.len();
        for i in 0..n {
            let (b, c) = (ring[i], ring[(i + 1) % n]);
            if b == a || c == a {
                continue;
            }
            let det = a.dot((b - a).cross(c - a));
            let den = 1.0 + a.dot(b) + b.dot(c) + c.dot(a);
            sum += 2.0 * det.atan2(den);
        }
    }
    sum.rem_euclid(four_pi)
}

/// Whether `p` lies in the polygon, decided exactly: the parity of the exact crossings of the
/// arc from `p` to a reference direction `q` far (1e-2) from every edge, whose own membership
/// `SphericalPolygon::contains` decides reliably there. `None` when every candidate arc passes
/// exactly through a vertex (measure zero).
pub fn exact_contains(poly: &SphericalPolygon, p: DVec3, edges: &[(DVec3, DVec3)]) -> Option<bool> {
    if poly.is_full() {
        return Some(true);
    }
    if poly.is_empty() {
        return Some(false);
    }
    let sgn = |x: f64| (x > 0.0) as i8 - (x < 0.0) as i8;
    'q: for q in fibonacci(64) {
        if (p + q).length() < 1e-3 || edges.iter().any(|&(a, b)| arc_distance(q, a, b) < 1e-2) {
            continue;
        }
        let mut odd = false;
        for &(a, b) in edges {
            let (abp, abq) = (sgn(orient(a, b, p)), sgn(orient(a, b, q)));
            let (pqa, pqb) = (sgn(orient(p, q, a)), sgn(orient(p, q, b)));
            if abq == 0 || pqa == 0 || pqb == 0 {
                continue 'q;
            }
            if abp == 0 {
                return None; // p on the edge's great circle: the caller skips near-edge p
            }
            if abp != abq && pqa != pqb && pqa == abq {
                odd = !odd;
            }
        }
        return Some(poly.contains(q) ^ odd);
    }
    None
}

/// Distance (chord) from unit `p` to the minor arc `a-b`.
fn arc_distance(p: DVec3, a: DVec3, b: DVec3) -> f64 {
    let n = a.cross(b);
    if a.cross(p).dot(n) > 0.0 && p.cross(b).dot(n) > 0.0 {
        (p.dot(n) / n.length()).abs()
    } else {
        (p - a).length().min((p - b).length())
    }
}

/// Checks every invariant of a triangulation of `poly` (solid angles to 1e-12 relative plus
/// `8 eps` times the sum of squared edge chords, the resolution of a sliver's area); `dirs` are
/// the directions whose
/// coverage is checked (those within `1e-12` of the polygon's size, plus `1e-15`, of an edge
/// are skipped: the polygon's own `contains` may go either way there).
pub fn check(
    poly: &SphericalPolygon,
    tris: &[SphericalTriangle],
    dirs: &[DVec3],
) -> Result<Report, String> {
    let mut report = Report {
        triangles: tris.len(),
        ..Report::default()
    };
    let mut sum = 0.0;
    let verts: Vec<[u64; 3]> = poly
        .rings()
        .flatten()
        .map(|p| p.to_array().map(f64::to_bits))
        .collect();
    let mut extra: Vec<[u64; 3]> = Vec::new();
    for (k, t) in tris.iter().enumerate() {
        let [a, b, c] = t.vertices();
        for p in [a, b, c] {
            if (p.length() - 1.0).abs() > 4.0 * f64::EPSILON {
                return Err(format!("triangle {k}: vertex {p} is not a unit vector"));
            }
            let key = p.to_array().map(f64::to_bits);
            if !verts.contains(&key) && !extra.contains(&key) {
                extra.push(key);
            }
        }
        if !(orient(a, b, c) > 0.0) {
            return Err(format!(
                "triangle {k} is not positively oriented: {a} {b} {c}"
            ));
        }
        if !(t.solid_angle() > 0.0) {
            return Err(format!("triangle {k} has no area"));
        }
        sum += t.solid_angle();
    }
    report.extra_vertices = extra.len();
    let area = reference_area(poly);
    report.area_error = if area > 0.0 {
        (sum - area).abs() / area
    } else {
        sum
    };
    // 1e-12 relative, plus what floating-point area formulas can resolve for a sliver: the
    // cross product of two edge vectors of length L that are nearly parallel is known to about
    // eps L^2, however small the area is.
    let sliver: f64 = poly
        .rings()
        .flat_map(|r| (0..r.len()).map(move |i| (r[i] - r[(i + 1) % r.len()]).length_squared()))
        .sum::<f64>()
        * 8.0
        * f64::EPSILON;
    // An edge between nearly antipodal vertices `a`, `b` has its great circle only to about
    // `eps / |a + b|` rad, and a plain Van Oosterom-Strackee area (the reference's) loses that
    // much times the edge's length, at most pi.
    let antipodal: f64 = poly
        .rings()
        .flat_map(|r| (0..r.len()).map(move |i| (r[i] + r[(i + 1) % r.len()]).length()))
        .map(|s| 8.0 * f64::EPSILON * std::f64::consts::PI / s.max(1e-300))
        .filter(|e| *e > 1e-15)
        .sum();
    if !((sum - area).abs() <= 1e-12 * area + sliver + antipodal) {
        return Err(format!(
            "solid angles add up to {sum}, the polygon has {area} (relative error {:e})",
            report.area_error
        ));
    }
    // The polygon's size: its longest edge chord, capped at 1 (the full sphere: 1).
    let edges: Vec<(DVec3, DVec3)> = poly
        .rings()
        .flat_map(|r| (0..r.len()).map(move |i| (r[i], r[(i + 1) % r.len()])))
        .collect();
    let size = edges
        .iter()
        .map(|(a, b)| (*a - *b).length())
        .fold(0.0f64, f64::max)
        .min(1.0);
    let size = if edges.is_empty() { 1.0 } else { size };
    let near = 1e-12 * size + 1e-15;
    let mut boxes: Vec<(DVec3, f64)> = Vec::with_capacity(tris.len());
    for t in tris {
        // A cap around each triangle for a quick rejection: center and chord radius.
        let [a, b, c] = t.vertices();
        let m = (a + b + c).normalize_or_zero();
        let r = (a - m).length().max((b - m).length()).max((c - m).length());
        boxes.push((m, r));
    }
    'dir: for &p in dirs {
        if edges.iter().any(|&(a, b)| arc_distance(p, a, b) < near) {
            continue;
        }
        let mut count = 0;
        for (t, &(m, r)) in tris.iter().zip(&boxes) {
            if m != DVec3::ZERO && (p - m).length() > r * (1.0 + 1e-9) + 1e-300 && r < 1.4 {
                continue;
            }
            let [a, b, c] = t.vertices();
            let s = [orient(a, b, p), orient(b, c, p), orient(c, a, p)];
            if s.iter().all(|&x| x > 0.0) {
                count += 1;
            } else if s.iter().all(|&x| x >= 0.0) {
                continue 'dir; // exactly on a triangle edge: measure zero, skipped
            }
        }
        let Some(expect) = exact_contains(poly, p, &edges) else {
            continue 'dir;
        };
        let expect = expect as usize;
        if count != expect {
            return Err(format!(
                "direction {p} lies in {count} triangles, the polygon contains it {expect} times"
            ));
        }
        report.checked += 1;
    }
    Ok(report)
}
