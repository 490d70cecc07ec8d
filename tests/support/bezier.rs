//! Curved lights for the Bezier tests: planar outlines in 2D placed in 3D, and two references
//! for their integrals that share no code with `ltc::curved`:
//!
//! - [`green_lambert`]: the clamped-cosine integral by Green's theorem in the light's plane,
//!   with the inner integral in closed form and Gauss-Legendre quadrature along the exact
//!   curves (split where they cross the horizon, found by sampling and bisection);
//! - [`polygon_reference`]: a fine uniform polygonization, clipped by Sutherland-Hodgman on its
//!   points (once at the shading horizon, and once more after the LTC map for the GGX lobe) and
//!   summed with Baum's formula, with Richardson extrapolation over the chord count.

use arealight::glam::{DMat3, DVec2, DVec3};
use arealight::ltc::{CurveSegment, lookup};
use arealight::solid::{BezierSegment, BezierShape};
use std::f64::consts::PI;

use super::sphere::gauss_legendre01;

/// A segment of a planar outline.
#[derive(Debug, Clone, Copy)]
pub enum Seg2 {
    Line(DVec2, DVec2),
    Cubic([DVec2; 4]),
}

impl Seg2 {
    pub fn start(&self) -> DVec2 {
        match self {
            Seg2::Line(a, _) => *a,
            Seg2::Cubic(p) => p[0],
        }
    }
    pub fn end(&self) -> DVec2 {
        match self {
            Seg2::Line(_, b) => *b,
            Seg2::Cubic(p) => p[3],
        }
    }
    pub fn reversed(&self) -> Seg2 {
        match *self {
            Seg2::Line(a, b) => Seg2::Line(b, a),
            Seg2::Cubic([a, b, c, d]) => Seg2::Cubic([d, c, b, a]),
        }
    }
}

/// A loop through `pts` of cubics with the given tangent handles (Catmull-Rom like: the handle
/// at a point is `k` times the difference of its neighbours), closed exactly.
pub fn smooth_loop(pts: &[DVec2], k: f64) -> Vec<Seg2> {
    let n = pts.len();
    (0..n)
        .map(|i| {
            let (p0, p1) = (pts[i], pts[(i + 1) % n]);
            let t0 = (pts[(i + 1) % n] - pts[(i + n - 1) % n]) * k;
            let t1 = (pts[(i + 2) % n] - pts[i]) * k;
            Seg2::Cubic([p0, p0 + t0, p1 - t1, p1])
        })
        .collect()
}

/// A star-shaped blob: `n` points at radii `r` (cycled) around `c`, joined by smooth cubics,
/// counter-clockwise.
pub fn blob(c: DVec2, r: &[f64], n: usize, phase: f64) -> Vec<Seg2> {
    let pts: Vec<DVec2> = (0..n)
        .map(|i| {
            let a = phase + 2.0 * PI * i as f64 / n as f64;
            c + r[i % r.len()] * DVec2::new(a.cos(), a.sin())
        })
        .collect();
    smooth_loop(&pts, 1.0 / 6.0)
}

/// A "D": a straight back and a round bowl (two cubics), with a D-shaped hole, about 2 x 2.
pub fn letter_d() -> Vec<Vec<Seg2>> {
    let p = DVec2::new;
    let outer = vec![
        Seg2::Line(p(-1.0, 1.0), p(-1.0, -1.0)),
        Seg2::Cubic([p(-1.0, -1.0), p(0.2, -1.0), p(1.0, -0.8), p(1.0, 0.0)]),
        Seg2::Cubic([p(1.0, 0.0), p(1.0, 0.8), p(0.2, 1.0), p(-1.0, 1.0)]),
    ];
    let hole = [
        Seg2::Line(p(-0.6, 0.6), p(-0.6, -0.6)),
        Seg2::Cubic([p(-0.6, -0.6), p(0.1, -0.6), p(0.6, -0.5), p(0.6, 0.0)]),
        Seg2::Cubic([p(0.6, 0.0), p(0.6, 0.5), p(0.1, 0.6), p(-0.6, 0.6)]),
    ];
    // Outer counter-clockwise, hole clockwise: the outer as written runs down the back and
    // round the bowl, counter-clockwise; the hole is reversed.
    let hole: Vec<Seg2> = hole.iter().rev().map(Seg2::reversed).collect();
    vec![outer, hole]
}

/// A frame for placing outlines: the plane through `o` spanned by unit `e1`, `e2`.
#[derive(Debug, Clone, Copy)]
pub struct Plane {
    pub o: DVec3,
    pub e1: DVec3,
    pub e2: DVec3,
}

impl Plane {
    /// The plane with normal `n` (either sign) through `o`, with `e1` horizontal where possible.
    pub fn new(o: DVec3, n: DVec3) -> Plane {
        let n = n.normalize();
        let e1 = n.cross(DVec3::Z).try_normalize().unwrap_or(DVec3::X);
        let e2 = n.cross(e1);
        Plane { o, e1, e2 }
    }

    pub fn at(&self, p: DVec2) -> DVec3 {
        self.o + self.e1 * p.x + self.e2 * p.y
    }

    /// The outline's segments in 3D, loops one after another; each loop's points are mapped
    /// once, so that shared end points stay bit-identical. Counter-clockwise in 2D becomes
    /// counter-clockwise about `e1 x e2`.
    pub fn place(&self, loops: &[Vec<Seg2>]) -> Vec<CurveSegment> {
        let mut out = Vec::new();
        for l in loops {
            let first = self.at(l[0].start());
            let mut prev = first;
            for (i, s) in l.iter().enumerate() {
                let end = if i + 1 == l.len() {
                    first
                } else {
                    self.at(s.end())
                };
                out.push(match s {
                    Seg2::Line(..) => CurveSegment::Line([prev, end]),
                    Seg2::Cubic(p) => {
                        CurveSegment::Cubic([prev, self.at(p[1]), self.at(p[2]), end])
                    }
                });
                prev = end;
            }
        }
        out
    }
}

/// The outline as a validated [`BezierShape`] in the plane (emitting towards `e1 x e2`).
pub fn shape(plane: &Plane, loops: &[Vec<Seg2>]) -> BezierShape {
    let segs = plane.place(loops);
    let mut out: Vec<Vec<BezierSegment>> = Vec::new();
    let mut k = 0;
    for l in loops {
        out.push(
            segs[k..k + l.len()]
                .iter()
                .map(|s| match *s {
                    CurveSegment::Line(p) => BezierSegment::Line(p),
                    CurveSegment::Cubic(p) => BezierSegment::Cubic(p),
                    _ => panic!("a segment kind these tests do not know"),
                })
                .collect(),
        );
        k += l.len();
    }
    BezierShape::new(out).unwrap()
}

/// The segments oriented for the shading point at the origin: counter-clockwise seen from
/// outside the sphere (the region's side facing away from the point), whichever side of the
/// plane the point is on.
pub fn facing_origin(plane: &Plane, loops: &[Vec<Seg2>]) -> Vec<CurveSegment> {
    let segs = plane.place(loops);
    let n = plane.e1.cross(plane.e2);
    if n.dot(plane.o) > 0.0 {
        segs
    } else {
        segs.iter().rev().map(CurveSegment::reversed).collect()
    }
}

/// The roots of `f` in `(0, 1)`: sign changes on a grid of `n` cells, refined by bisection.
fn roots(f: impl Fn(f64) -> f64, n: usize) -> Vec<f64> {
    let mut out = Vec::new();
    let mut prev = f(0.0);
    for i in 1..=n {
        let t = i as f64 / n as f64;
        let cur = f(t);
        if (prev > 0.0) != (cur > 0.0) {
            let (mut lo, mut hi) = ((i - 1) as f64 / n as f64, t);
            for _ in 0..80 {
                let m = 0.5 * (lo + hi);
                if (f(m) > 0.0) == (prev > 0.0) {
                    lo = m;
                } else {
                    hi = m;
                }
            }
            out.push(0.5 * (lo + hi));
        }
        prev = cur;
    }
    out
}

fn eval(s: &CurveSegment, t: f64) -> (DVec3, DVec3) {
    match *s {
        CurveSegment::Line([a, b]) => (a + (b - a) * t, b - a),
        CurveSegment::Cubic([a, b, c, d]) => {
            let u = 1.0 - t;
            let p = a * u * u * u + b * 3.0 * u * u * t + c * 3.0 * u * t * t + d * t * t * t;
            let dp = (b - a) * 3.0 * u * u + (c - b) * 6.0 * u * t + (d - c) * 3.0 * t * t;
            (p, dp)
        }
        _ => panic!("a segment kind this reference does not know"),
    }
}

/// `(1/pi)` times the integral of `max(0, z)` over the planar region bounded by `segs` (closed
/// loops in a plane not through the origin, oriented counter-clockwise seen from outside the
/// sphere), by Green's theorem in the plane.
///
/// With an orthonormal basis `e1, e2` of the plane (`e1` horizontal, so that `z` depends on
/// the second coordinate only) and `q = h n + u e1 + v e2`, the integrand in the plane is
/// `f(u, v) = |h| max(0, q_z(v)) / (pi |q|^4)` (`d omega = |h| / |q|^3 dA`). Its antiderivative
/// in `u` from `-inf` is `G = |h| max(0, q_z) / pi * J(u, beta)`, `beta^2 = h^2 + v^2`,
/// `J = u / (2 beta^2 (u^2 + beta^2)) + atan2(beta, -u) / (2 beta^3)`, and the integral is
/// `sign(h)` times the loop integral of `G dv`, by Gauss-Legendre quadrature (`pieces` pieces
/// of `nodes` points per segment, split at the horizon crossings where `G` has a kink).
pub fn green_lambert(segs: &[CurveSegment], pieces: usize, nodes: usize) -> f64 {
    let some = segs[0].start();
    // The plane's normal from the vector area of the loops.
    let mut area = DVec3::ZERO;
    for s in segs {
        let gl = gauss_legendre01(8);
        for &(t, w) in &gl {
            let (p, dp) = eval(s, t);
            area += (p - some).cross(dp) * (0.5 * w);
        }
    }
    let n = area.normalize();
    let h = n.dot(some);
    let e1 = n
        .cross(DVec3::Z)
        .try_normalize()
        .unwrap_or_else(|| n.any_orthonormal_vector());
    let e2 = n.cross(e1);
    let gl = gauss_legendre01(nodes);
    let g = |p: DVec3| {
        let (u, v) = (p.dot(e1), p.dot(e2));
        let qz = h * n.z + v * e2.z;
        if qz <= 0.0 {
            return 0.0;
        }
        let b2 = h * h + v * v;
        let b = b2.sqrt();
        let j = u / (2.0 * b2 * (u * u + b2)) + b.atan2(-u) / (2.0 * b2 * b);
        h.abs() * qz / PI * j
    };
    let mut sum = 0.0;
    for s in segs {
        let mut cuts = vec![0.0];
        cuts.extend(roots(|t| eval(s, t).0.z, 4096));
        cuts.push(1.0);
        for w in cuts.windows(2) {
            let (a, b) = (w[0], w[1]);
            for k in 0..pieces {
                let (lo, hi) = (
                    a + (b - a) * k as f64 / pieces as f64,
                    a + (b - a) * (k + 1) as f64 / pieces as f64,
                );
                for &(t, wt) in &gl {
                    let tt = lo + (hi - lo) * t;
                    let (p, dp) = eval(s, tt);
                    sum += wt * (hi - lo) * g(p) * dp.dot(e2);
                }
            }
        }
    }
    h.signum() * sum
}

/// Sutherland-Hodgman: the ring clipped to `f > 0`, with crossing points on `f = 0`.
fn clip_ring(ring: &[DVec3], f: impl Fn(DVec3) -> f64) -> Vec<DVec3> {
    let mut out = Vec::new();
    let n = ring.len();
    for i in 0..n {
        let (a, b) = (ring[i], ring[(i + 1) % n]);
        let (fa, fb) = (f(a), f(b));
        if fa > 0.0 {
            out.push(a);
        }
        if (fa > 0.0) != (fb > 0.0) {
            let t = fa / (fa - fb);
            out.push(a + (b - a) * t);
        }
    }
    out
}

/// Baum's sum over rings of points (any positive scale), divided by `2 pi`.
fn baum(rings: &[Vec<DVec3>]) -> f64 {
    let mut sum = 0.0;
    for r in rings {
        for i in 0..r.len() {
            let (a, b) = (r[i].normalize(), r[(i + 1) % r.len()].normalize());
            let c = a.cross(b);
            let s = c.length();
            if s > 0.0 {
                sum += s.atan2(a.dot(b)) / s * c.z;
            }
        }
    }
    sum / (2.0 * PI)
}

/// The loops of `segs` flattened uniformly, `n` chords per cubic.
pub fn flatten(segs: &[CurveSegment], n: usize) -> Vec<Vec<DVec3>> {
    let mut rings: Vec<Vec<DVec3>> = Vec::new();
    let mut cur: Vec<DVec3> = Vec::new();
    let mut start = None;
    for s in segs {
        if start.is_none() {
            start = Some(s.start());
        }
        match s {
            CurveSegment::Line([a, _]) => cur.push(*a),
            CurveSegment::Cubic(_) => {
                for k in 0..n {
                    cur.push(eval(s, k as f64 / n as f64).0);
                }
            }
            _ => panic!("a segment kind this reference does not know"),
        }
        if Some(s.end()) == start {
            rings.push(std::mem::take(&mut cur));
            start = None;
        }
    }
    rings
}

/// What [`polygon_reference`] integrates.
#[derive(Debug, Clone, Copy)]
pub enum Lobe {
    /// The clamped cosine in the shading frame.
    Lambert,
    /// `ggx_polygon_integral`'s GGX response for `(cos_theta_v, alpha, f0)`.
    Ggx(f64, f64, f64),
}

/// The integral over the polygon with `n` chords per cubic, clipped and summed exactly.
fn polygon_integral(segs: &[CurveSegment], n: usize, lobe: Lobe) -> f64 {
    let rings: Vec<Vec<DVec3>> = flatten(segs, n)
        .iter()
        .map(|r| clip_ring(r, |p| p.z))
        .collect();
    match lobe {
        Lobe::Lambert => baum(&rings).clamp(0.0, 1.0),
        Lobe::Ggx(cos_v, alpha, f0) => {
            let l = lookup(cos_v, alpha).unwrap();
            let m: DMat3 = l.m_inv;
            let mapped: Vec<Vec<DVec3>> = rings
                .iter()
                .map(|r| clip_ring(&r.iter().map(|&p| m * p).collect::<Vec<_>>(), |p| p.z))
                .collect();
            let v = baum(&mapped).clamp(0.0, 1.0).min(l.albedo / l.norm);
            l.specular_scale(f0) * v
        }
    }
}

/// [`polygon_integral`] at `n` and `2 n` chords per cubic, extrapolated (the polygon's error is
/// quadratic in the chord length): `(4 I(2n) - I(n)) / 3`. Also returns the difference of the
/// two raw values as a measure of what remains.
pub fn polygon_reference(segs: &[CurveSegment], n: usize, lobe: Lobe) -> (f64, f64) {
    let (a, b) = (
        polygon_integral(segs, n, lobe),
        polygon_integral(segs, 2 * n, lobe),
    );
    ((4.0 * b - a) / 3.0, (b - a).abs())
}
