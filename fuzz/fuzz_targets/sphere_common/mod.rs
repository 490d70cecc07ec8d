//! Shared driver of the spherical fuzz targets: decode polygons from small integer directions
//! (so that shared vertices, vertices on great circles through others and exact degeneracies are
//! frequent), or from structured inputs that live in the regimes of issue 24 (vertices 1e-16..1e-9
//! off a horizon, tiny polygons and near-antipodal tiny pairs, slivers), skip invalid inputs
//! (`SphericalPolygon::new` rejects them), and assert invariants: every result passes
//! `SphericalPolygon::validate` (and `new` on its rings), identities of the set operations,
//! partition and continuity of the clip, and the values the structure of the input implies.

#![allow(dead_code)] // each target uses the part of the driver for its regime

use arealight::glam::DVec3;
use arealight::planar::BoolOp;
use arealight::sphere::SphericalPolygon;
use libfuzzer_sys::arbitrary::{self, Arbitrary};
use std::f64::consts::PI;

/// One polygon: up to 3 rings of up to 12 integer directions, optionally complemented.
#[derive(Debug, Arbitrary)]
pub struct Poly {
    rings: Vec<Vec<(i8, i8, i8)>>,
    complement: bool,
}

impl Poly {
    pub fn build(&self) -> Option<SphericalPolygon> {
        let rings: Vec<Vec<DVec3>> = self
            .rings
            .iter()
            .take(3)
            .map(|r| {
                r.iter()
                    .take(12)
                    .map(|&(x, y, z)| DVec3::new(x as f64, y as f64, z as f64))
                    .collect()
            })
            .collect();
        let p = SphericalPolygon::new(rings).ok()?;
        Some(if self.complement { p.complement() } else { p })
    }
}

/// Panics unless `p` passes full validation again (the output of every operation must be a
/// valid input to every operation).
pub fn assert_valid(p: &SphericalPolygon, what: &str) {
    if let Err(e) = p.validate() {
        panic!("{what}: result fails validate ({e}): {p:?}");
    }
    if p.is_full() {
        return;
    }
    let rings = p.rings().map(<[DVec3]>::to_vec).collect();
    if let Err(e) = SphericalPolygon::new(rings) {
        panic!("{what}: invalid result ({e}): {p:?}");
    }
    let w = p.solid_angle();
    assert!((0.0..=4.0 * PI).contains(&w), "{what}: solid angle {w} out of range");
}

/// Clipping: valid output, partition of the solid angle, idempotence. An edge between nearly
/// antipodal vertices has its great circle, and so the region's area, only to about
/// `1e-16 / |a + b|` (`ANTIPODAL_TOLERANCE` lets `|a + b|` go down to 1e-10): the tolerance
/// grows with that factor.
pub fn clip(p: &SphericalPolygon, n: DVec3) {
    let (up, down) = (p.clip_to_hemisphere(n), p.clip_to_hemisphere(-n));
    assert_valid(&up, &format!("clip(n) of\nP = {p:?}\nn = {n:?}\n"));
    assert_valid(&down, &format!("clip(-n) of\nP = {p:?}\nn = {n:?}\n"));
    let bulge = p
        .rings()
        .flat_map(|r| (0..r.len()).map(move |k| 2.0 / (r[k] + r[(k + 1) % r.len()]).length()))
        .fold(1.0, f64::max);
    let (wu, wd, w) = (up.solid_angle(), down.solid_angle(), p.solid_angle());
    let tol = 1e-10 * 4.0 * PI + 1e-14 * bulge * p.vertex_count() as f64;
    assert!((wu + wd - w).abs() <= tol, "clip partition: {wu} + {wd} vs {w}\nP = {p:?}\nn = {n}");
    let twice = up.clip_to_hemisphere(n).solid_angle();
    assert!((twice - wu).abs() <= 1e-12 + 1e-15 * bulge, "clip not idempotent: {twice} vs {wu}\nP = {p:?}\nn = {n}");
}

/// Set operations: valid outputs and the solid-angle identities.
pub fn boolean(a: &SphericalPolygon, b: &SphericalPolygon) {
    let run = |op| {
        let r = match a.boolean(b, op) {
            Ok(r) => r,
            // A numerical give-up on valid input is allowed (rarely), never a wrong value.
            Err(e) if e.is_undecidable() => return None,
            Err(e) => panic!("{op:?} failed on valid input: {e}\nA = {a:?}\nB = {b:?}"),
        };
        assert_valid(&r, "boolean");
        Some(r.solid_angle())
    };
    let (Some(i), Some(u), Some(d), Some(x)) = (
        run(BoolOp::Intersection),
        run(BoolOp::Union),
        run(BoolOp::Difference),
        run(BoolOp::Xor),
    ) else {
        return;
    };
    let (wa, wb) = (a.solid_angle(), b.solid_angle());
    let tol = 1e-10 * 4.0 * PI;
    assert!((d + i - wa).abs() <= tol, "A-B + AnB = A: {d} + {i} vs {wa}\nA = {a:?}\nB = {b:?}");
    assert!((u - (wa + wb - i)).abs() <= tol, "AuB: {u} vs {wa} + {wb} - {i}\nA = {a:?}\nB = {b:?}");
    assert!((x - (u - i)).abs() <= tol, "xor: {x} vs {u} - {i}\nA = {a:?}\nB = {b:?}");
}

/// `p` moved along the great circle through `n` to height `h` above the circle of `n`.
fn at_height(p: DVec3, n: DVec3, h: f64) -> DVec3 {
    match (p - n * p.dot(n)).try_normalize() {
        Some(flat) => flat * (1.0 - h * h).sqrt() + n * h,
        None => p,
    }
}

fn dir(v: (i8, i8, i8)) -> Option<DVec3> {
    DVec3::new(v.0 as f64, v.1 as f64, v.2 as f64).try_normalize()
}

fn perimeter(ring: &[DVec3]) -> f64 {
    let m = ring.len();
    (0..m)
        .map(|i| {
            let (a, b) = (ring[i], ring[(i + 1) % m]);
            a.cross(b).length().atan2(a.dot(b))
        })
        .sum()
}

/// Near-horizon family: a polygon of integer directions with one vertex (and optionally a
/// neighbour) moved to 1e-16..1e-9 above or below the circle of `normal`, absolutely or in
/// proportion to the polygon's size.
#[derive(Debug, Arbitrary)]
pub struct Horizon {
    ring: Vec<(i8, i8, i8)>,
    normal: (i8, i8, i8),
    vertex: u8,
    exponent: u8,
    mantissa: u8,
    relative: bool,
    neighbour: Option<(u8, bool)>,
    complement: bool,
}

impl Horizon {
    pub fn run(&self) {
        let Some(n) = dir(self.normal) else { return };
        let mut ring: Vec<DVec3> = self.ring.iter().take(8).filter_map(|&v| dir(v)).collect();
        if ring.len() < 3 {
            return;
        }
        let size = perimeter(&ring) / ring.len() as f64;
        let scale = if self.relative { size } else { 1.0 };
        let eps = 10f64.powi(-9 - (self.exponent % 8) as i32) * (1.0 + self.mantissa as f64 / 256.0) * scale;
        let i = self.vertex as usize % ring.len();
        if let Some((e, up)) = self.neighbour {
            let j = (i + 1) % ring.len();
            let h = 10f64.powi(-9 - (e % 8) as i32) * scale * if up { 1.0 } else { -1.0 };
            ring[j] = at_height(ring[j], n, h);
        }
        let moved = |h: f64| {
            let mut r = ring.clone();
            r[i] = at_height(r[i], n, h);
            SphericalPolygon::new(vec![r]).ok().map(|p| if self.complement { p.complement() } else { p })
        };
        let (Some(pp), Some(pm), Some(p0)) = (moved(eps), moved(-eps), moved(0.0)) else {
            return;
        };
        // Measured on the moved ring: moving a vertex moves its edges by up to 2 / |a + b| times
        // as much, which is large for an edge that the move makes nearly antipodal.
        let r0: Vec<DVec3> = {
            let mut r = ring.clone();
            r[i] = at_height(r[i], n, 0.0);
            r
        };
        let per = perimeter(&r0);
        let bulge = (0..r0.len())
            .map(|k| 2.0 / (r0[k] + r0[(k + 1) % r0.len()]).length())
            .fold(1.0, f64::max);
        let area = p0.solid_angle();
        // Rounding, and what the clip may move (documented at HORIZON_TOLERANCE, FLAT_SLOPE).
        let slack = 1e-15 * ring.len() as f64 * per * bulge + 1e-12 * area.min(4.0 * PI - area) + 4e-14;
        let snapping = 8.0 * (1e-14 + 4e-12) * per + 4e-12 * per * per;
        let mut up = [0.0; 3];
        for (k, p) in [&pp, &pm, &p0].into_iter().enumerate() {
            clip(p, n);
            let (u, d) = (p.clip_to_hemisphere(n), p.clip_to_hemisphere(-n));
            up[k] = u.solid_angle();
            let (wu, wd, w) = (up[k], d.solid_angle(), p.solid_angle());
            assert!(
                (wu + wd - w).abs() <= snapping + 2.0 * slack,
                "partition: {wu} + {wd} vs {w}\nP = {p:?}\nn = {n}"
            );
        }
        // Continuity where the move is well-conditioned (not an edge near its antipode moved by
        // a good part of |a + b|) and the input itself is continuous (a polygon all of whose
        // vertices lie near one great circle turns into its complement as a vertex crosses it).
        let whole = [pp.solid_angle(), pm.solid_angle(), p0.solid_angle()];
        for (a, b, d) in [(0, 1, 2.0 * eps), (0, 2, eps), (1, 2, eps)] {
            let bound = d * per * bulge + snapping + slack;
            if d * per * bulge < 1e-6 && (whole[a] - whole[b]).abs() <= bound {
                assert!(
                    (up[a] - up[b]).abs() <= bound,
                    "clip not continuous: {} vs {} (bound {bound:e})\n{self:?}",
                    up[a],
                    up[b]
                );
            }
        }
    }
}

/// Tiny family: two polygons 1e-10..1e-6 rad across, given as integer offsets about a center in
/// units of the size, near each other or near each other's antipode, possibly complemented.
#[derive(Debug, Arbitrary)]
pub struct Tiny {
    center: (i8, i8, i8),
    size_exponent: u8,
    a: Vec<(i8, i8)>,
    b: Vec<(i8, i8)>,
    b_offset: (i8, i8),
    antipodal: bool,
    complement_a: bool,
    complement_b: bool,
}

impl Tiny {
    pub fn run(&self) {
        let Some(c) = dir(self.center) else { return };
        let size = 10f64.powi(-6 - (self.size_exponent % 5) as i32) / 128.0;
        let (u, v) = c.any_orthonormal_pair();
        let ring = |center: DVec3, pts: &[(i8, i8)], off: (i8, i8)| -> Vec<DVec3> {
            let (u, v) = if center.dot(c) < 0.0 { (u, -v) } else { (u, v) };
            pts.iter()
                .take(8)
                .map(|&(x, y)| {
                    let (x, y) = (x as f64 + off.0 as f64, y as f64 + off.1 as f64);
                    (center + (u * x + v * y) * size).normalize()
                })
                .collect()
        };
        let ra = ring(c, &self.a, (0, 0));
        let rb = ring(if self.antipodal { -c } else { c }, &self.b, self.b_offset);
        let (Ok(a0), Ok(b0)) = (SphericalPolygon::new(vec![ra]), SphericalPolygon::new(vec![rb])) else {
            return;
        };
        // The complement of a valid region is valid.
        for p in [&a0, &b0] {
            let rev: Vec<DVec3> = p.rings().next().unwrap().iter().rev().copied().collect();
            let q = SphericalPolygon::new(vec![rev]).expect("the complement of a valid region");
            assert_eq!(q, p.complement());
        }
        let a = if self.complement_a { a0.complement() } else { a0.clone() };
        let b = if self.complement_b { b0.complement() } else { b0.clone() };
        boolean(&a, &b);
        if self.antipodal {
            // Disjoint: the small side of each result follows from the operands' areas. A ring
            // given clockwise is the large region (the tiny one's complement): the tiny regions
            // are then the complements, and the flags say which side each operand is.
            let small_side = |p: &SphericalPolygon, complemented: bool| {
                if p.solid_angle() > 2.0 * PI {
                    (p.complement(), !complemented)
                } else {
                    (p.clone(), complemented)
                }
            };
            let ((a0, ca), (b0, cb)) = (
                small_side(&a0, self.complement_a),
                small_side(&b0, self.complement_b),
            );
            let (wa, wb) = (a0.solid_angle(), b0.solid_angle());
            for op in [BoolOp::Intersection, BoolOp::Union, BoolOp::Difference, BoolOp::Xor] {
                let (small, comp) = match (op, ca, cb) {
                    (BoolOp::Intersection, false, false) => (0.0, false),
                    (BoolOp::Intersection, true, false) => (wb, false),
                    (BoolOp::Intersection, false, true) => (wa, false),
                    (BoolOp::Intersection, true, true) => (wa + wb, true),
                    (BoolOp::Union, false, false) => (wa + wb, false),
                    (BoolOp::Union, true, false) => (wa, true),
                    (BoolOp::Union, false, true) => (wb, true),
                    (BoolOp::Union, true, true) => (0.0, true),
                    (BoolOp::Difference, false, false) => (wa, false),
                    (BoolOp::Difference, true, false) => (wa + wb, true),
                    (BoolOp::Difference, false, true) => (0.0, false),
                    (BoolOp::Difference, true, true) => (wb, false),
                    (BoolOp::Xor, false, false) | (BoolOp::Xor, true, true) => (wa + wb, false),
                    (BoolOp::Xor, ..) => (wa + wb, true),
                };
                let Ok(r) = a.boolean(&b, op) else { continue };
                let got = if comp { r.complement() } else { r }.solid_angle();
                assert!(
                    (got - small).abs() <= 1e-6 * (wa + wb),
                    "{op:?}: {got:e} vs {small:e}\n{self:?}"
                );
            }
        }
    }
}

/// Sliver family: a polygon of integer directions and its copy with one vertex moved by
/// 1e-15..1e-9 of the polygon's size, possibly complemented.
#[derive(Debug, Arbitrary)]
pub struct Sliver {
    poly: Poly,
    vertex: u8,
    exponent: u8,
    angle: u8,
    complement_b: bool,
}

impl Sliver {
    pub fn run(&self) {
        let Some(a) = self.poly.build() else { return };
        let Some(ring) = a.rings().next() else { return };
        let ring = ring.to_vec();
        let i = self.vertex as usize % ring.len();
        let size = perimeter(&ring) / ring.len() as f64;
        let moved = size * 10f64.powi(-9 - (self.exponent % 7) as i32);
        let (u, v) = ring[i].any_orthonormal_pair();
        let t = self.angle as f64 * (2.0 * PI / 256.0);
        let mut rb: Vec<Vec<DVec3>> = a.rings().map(<[DVec3]>::to_vec).collect();
        rb[0][i] = (ring[i] + (u * t.cos() + v * t.sin()) * moved).normalize();
        let Ok(b) = SphericalPolygon::new(rb) else { return };
        let b = if self.complement_b { b.complement() } else { b };
        boolean(&a, &b);
        // A xor B is the thin region the move sweeps (or its complement when exactly one of
        // them is complemented): the two thin triangles between the moved vertex's old and new
        // positions and its neighbours, each of area about `moved tan(L / 2)` for an edge of
        // length `L` (the angle at the far end is `moved / sin L`, the triangle's area that
        // angle times `1 - cos L`; `tan(L / 2) = |a - b| / |a + b|`, which grows without bound
        // for nearly antipodal ends), up to the operation's resolution of 1e-11 per unit of
        // edge (longer near antipodal ends, by the same factor).
        let Ok(x) = a.boolean(&b, BoolOp::Xor) else { return };
        let per = perimeter(&ring);
        let n = ring.len();
        let tan_half = |p: DVec3, q: DVec3| (p - q).length() / (p + q).length();
        let (prev, next) = (ring[(i + n - 1) % n], ring[(i + 1) % n]);
        let sweep = tan_half(prev, ring[i]) + tan_half(ring[i], next);
        let bulge = (0..n)
            .map(|k| 2.0 / (ring[k] + ring[(k + 1) % n]).length())
            .fold(1.0, f64::max);
        let x = x.solid_angle();
        let small = if self.complement_b { 4.0 * PI - x } else { x };
        assert!(
            small <= moved * sweep * 1.01 + 2e-11 * per * bulge + 1e-13,
            "A xor B = {x} (small side {small:e}, sweep factor {sweep})\n{self:?}"
        );
    }
}

/// The polygons of the tiny and horizon families, for targets that take polygons one at a time
/// (`sphere_triangulate`): what `run` builds, without its checks.
impl Tiny {
    /// Both tiny rings (complemented as asked), the two as one polygon when they are disjoint
    /// (near each other or near each other's antipode), that pair's complement, and the results
    /// of the set operations between the two.
    pub fn polygons(&self) -> Vec<SphericalPolygon> {
        let Some(c) = dir(self.center) else { return Vec::new() };
        let size = 10f64.powi(-6 - (self.size_exponent % 5) as i32) / 128.0;
        let (u, v) = c.any_orthonormal_pair();
        let ring = |center: DVec3, pts: &[(i8, i8)], off: (i8, i8)| -> Vec<DVec3> {
            let (u, v) = if center.dot(c) < 0.0 { (u, -v) } else { (u, v) };
            pts.iter()
                .take(8)
                .map(|&(x, y)| {
                    let (x, y) = (x as f64 + off.0 as f64, y as f64 + off.1 as f64);
                    (center + (u * x + v * y) * size).normalize()
                })
                .collect()
        };
        let ra = ring(c, &self.a, (0, 0));
        let rb = ring(if self.antipodal { -c } else { c }, &self.b, self.b_offset);
        let mut out = Vec::new();
        if let Ok(both) = SphericalPolygon::new(vec![ra.clone(), rb.clone()]) {
            out.push(both.complement());
            out.push(both);
        }
        let (Ok(a0), Ok(b0)) = (SphericalPolygon::new(vec![ra]), SphericalPolygon::new(vec![rb])) else {
            return out;
        };
        let a = if self.complement_a { a0.complement() } else { a0 };
        let b = if self.complement_b { b0.complement() } else { b0 };
        for op in [BoolOp::Intersection, BoolOp::Union, BoolOp::Difference, BoolOp::Xor] {
            if let Ok(r) = a.boolean(&b, op) {
                out.push(r);
            }
        }
        out.push(a);
        out.push(b);
        out
    }
}

impl Horizon {
    /// The polygon with its vertex moved to `+eps`, `-eps` and onto the circle of `normal`
    /// (complemented as asked), and the clips of each to both sides of that circle.
    pub fn polygons(&self) -> Vec<SphericalPolygon> {
        let Some(n) = dir(self.normal) else { return Vec::new() };
        let mut ring: Vec<DVec3> = self.ring.iter().take(8).filter_map(|&v| dir(v)).collect();
        if ring.len() < 3 {
            return Vec::new();
        }
        let size = perimeter(&ring) / ring.len() as f64;
        let scale = if self.relative { size } else { 1.0 };
        let eps = 10f64.powi(-9 - (self.exponent % 8) as i32) * (1.0 + self.mantissa as f64 / 256.0) * scale;
        let i = self.vertex as usize % ring.len();
        if let Some((e, up)) = self.neighbour {
            let j = (i + 1) % ring.len();
            let h = 10f64.powi(-9 - (e % 8) as i32) * scale * if up { 1.0 } else { -1.0 };
            ring[j] = at_height(ring[j], n, h);
        }
        let mut out = Vec::new();
        for h in [eps, -eps, 0.0] {
            let mut r = ring.clone();
            r[i] = at_height(r[i], n, h);
            if let Ok(p) = SphericalPolygon::new(vec![r]) {
                let p = if self.complement { p.complement() } else { p };
                out.push(p.clip_to_hemisphere(n));
                out.push(p.clip_to_hemisphere(-n));
                out.push(p);
            }
        }
        out
    }
}
