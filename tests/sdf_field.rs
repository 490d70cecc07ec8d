//! Signed distance fields against brute force, each primitive with random parameters from six
//! seeds. Its surface is given by an independent parametrization (faces, edge cylinders, corner
//! octants, hemispherical caps, ... each a map of the unit square), and the distance from a query
//! point to it is found by a grid search over every patch refined by a pattern search on the
//! parameters; membership has its own test. For each query point `p`:
//!
//! - `|f(p)| <= d(p)` (up to rounding): the field never overestimates, since every point the
//!   search measures lies on the surface;
//! - `d(p) <= |f(p)| + 1e-12` (times one plus the object's size): it does not underestimate
//!   beyond the refinement's convergence (measured gaps below 1e-15);
//! - the sign agrees with membership (points within 1e-9 of the surface are exempt).
//!
//! A coarser comparison with a dense sample of the surface (underestimates within its covering
//! radius) checks similarity transforms (the samples are mapped) and the exactness table of the
//! CSG operations (the union's surface is each operand's surface outside the other).
//! A proptest checks that every field, CSG and transform included, is 1-Lipschitz.

mod support;

use arealight::GeomError;
use arealight::glam::{DQuat, DVec3};
use arealight::sdf::{
    Capsule, Cuboid, Cylinder, Difference, Exactness, Intersection, Plane, RoundedBox, Sdf,
    SmoothUnion, Sphere, Torus, Transformed, Union, UnionAll, normal,
};
use proptest::prelude::*;
use std::f64::consts::PI;
use support::Rng;

/// A dense sample of a surface with its covering radius.
struct Samples {
    points: Vec<DVec3>,
    cover: f64,
}

impl Samples {
    fn new() -> Self {
        Samples {
            points: Vec::new(),
            cover: 0.0,
        }
    }
    /// Adds the grid `corner + i/n1 * a + j/n2 * b` over `[0, 1]^2` (a parallelogram face).
    fn face(&mut self, corner: DVec3, a: DVec3, b: DVec3, n: usize) {
        for i in 0..=n {
            for j in 0..=n {
                let (s, t) = (i as f64 / n as f64, j as f64 / n as f64);
                self.points.push(corner + s * a + t * b);
            }
        }
        self.cover = self.cover.max(0.5 * (a.length() + b.length()) / n as f64);
    }
    /// Adds the grid of `f(u, v)` for `u, v` in `[0, 1]`, where moving `1/n` in `u` or `v`
    /// moves the point by at most `lu / n` or `lv / n`.
    fn param(&mut self, f: impl Fn(f64, f64) -> DVec3, lu: f64, lv: f64, n: usize) {
        for i in 0..=n {
            for j in 0..=n {
                self.points
                    .push(f(i as f64 / n as f64, j as f64 / n as f64));
            }
        }
        self.cover = self.cover.max(0.5 * (lu + lv) / n as f64);
    }
    fn nearest(&self, p: DVec3) -> f64 {
        self.points
            .iter()
            .fold(f64::INFINITY, |d, s| d.min((p - *s).length_squared()))
            .sqrt()
    }
}

/// A point on a sphere of radius `r` about `c` from `u, v` in `[0, 1]` restricted to
/// the given ranges of polar angle and azimuth.
fn sphere_point(c: DVec3, r: f64, theta: (f64, f64), phi: (f64, f64), u: f64, v: f64) -> DVec3 {
    let th = theta.0 + u * (theta.1 - theta.0);
    let ph = phi.0 + v * (phi.1 - phi.0);
    c + r * DVec3::new(th.sin() * ph.cos(), th.sin() * ph.sin(), th.cos())
}

/// Two unit vectors completing the unit `w` to an orthonormal basis.
fn perp(w: DVec3) -> (DVec3, DVec3) {
    let a = if w.x.abs() < 0.6 { DVec3::X } else { DVec3::Y };
    let u = w.cross(a).normalize();
    (u, w.cross(u))
}

fn sphere_samples(c: DVec3, r: f64, n: usize) -> Samples {
    let mut s = Samples::new();
    s.param(
        |u, v| sphere_point(c, r, (0.0, PI), (0.0, 2.0 * PI), u, v),
        r * PI,
        r * 2.0 * PI,
        n,
    );
    s
}

/// The six faces of the box `c ± h`.
fn box_faces(s: &mut Samples, c: DVec3, h: DVec3, n: usize) {
    let axes = [DVec3::X, DVec3::Y, DVec3::Z];
    for k in 0..3 {
        let (a, b) = (axes[(k + 1) % 3], axes[(k + 2) % 3]);
        let (ha, hb, hk) = (h.dot(a), h.dot(b), h.dot(axes[k]));
        for sign in [-1.0, 1.0] {
            let corner = c + sign * hk * axes[k] - ha * a - hb * b;
            s.face(corner, 2.0 * ha * a, 2.0 * hb * b, n);
        }
    }
}

fn torus_samples(c: DVec3, axis: DVec3, big: f64, small: f64, n: usize) -> Samples {
    let w = axis.normalize();
    let (u1, u2) = perp(w);
    let mut s = Samples::new();
    s.param(
        |u, v| {
            let (a, b) = (u * 2.0 * PI, v * 2.0 * PI);
            let radial = a.cos() * u1 + a.sin() * u2;
            c + (big + small * b.cos()) * radial + small * b.sin() * w
        },
        2.0 * PI * (big + small),
        2.0 * PI * small,
        n,
    );
    s
}

/// Query points: near the surface (shells around the object's scale), far away, and inside.
fn queries(rng: &mut Rng, center: DVec3, scale: f64, count: usize) -> Vec<DVec3> {
    (0..count)
        .map(|i| {
            let reach = match i % 4 {
                0 => 0.3,
                1 => 1.0,
                2 => 1.5,
                _ => 4.0,
            };
            center + rng.dir() * scale * reach * rng.f64().sqrt()
        })
        .collect()
}

/// Checks the exactness of `f` at `p` against `samples`, on the side(s) `exact` says.
fn check_point(
    what: &str,
    f: &dyn Sdf,
    samples: &Samples,
    inside: &dyn Fn(DVec3) -> bool,
    p: DVec3,
    exact: Exactness,
) {
    let d = f.distance(p);
    let brute = samples.nearest(p);
    let h = samples.cover;
    let tol = 1e-12 * (1.0 + p.length());
    assert!(
        d.abs() <= brute + tol,
        "{what}: |f| = {} exceeds the distance to a surface sample {brute} at {p}",
        d.abs()
    );
    if brute > h {
        assert_eq!(
            d < 0.0,
            inside(p),
            "{what}: sign of f = {d} disagrees with membership at {p}"
        );
    }
    let exact_here = if d >= 0.0 {
        exact.exact_outside()
    } else {
        exact.exact_inside()
    };
    if exact_here {
        assert!(
            brute <= d.abs() + h + tol,
            "{what}: f = {d} underestimates the distance {brute} (cover {h}) at {p}"
        );
    }
}

fn check_exact(
    what: &str,
    f: &dyn Sdf,
    samples: &Samples,
    inside: &dyn Fn(DVec3) -> bool,
    center: DVec3,
    scale: f64,
    seed: u64,
) {
    assert_eq!(f.exactness(), Exactness::Exact, "{what}");
    let mut rng = Rng::new(seed);
    for p in queries(&mut rng, center, scale, 80) {
        check_point(what, f, samples, inside, p, Exactness::Exact);
    }
}

fn seg_dist(p: DVec3, a: DVec3, b: DVec3) -> f64 {
    let w = b - a;
    let t = ((p - a).dot(w) / w.length_squared()).clamp(0.0, 1.0);
    (p - (a + t * w)).length()
}

/// A surface as patches, each a map of `[0, 1]^2` onto a piece of it; the distance to the
/// surface from a query point is found by a grid search over every patch, then refined from the
/// patches' best grid points by a pattern search on the parameters ([`refine`]). Every point it
/// measures lies on the surface, so the result never underestimates the distance (up to
/// rounding); the refinement takes it to the local minimum, which the dense grid puts in the
/// right basin.
struct Surface {
    patches: Vec<Box<dyn Fn(f64, f64) -> DVec3>>,
}

impl Surface {
    fn new() -> Self {
        Surface {
            patches: Vec::new(),
        }
    }

    fn add(&mut self, f: impl Fn(f64, f64) -> DVec3 + 'static) {
        self.patches.push(Box::new(f));
    }

    /// The parallelogram `corner + u a + v b`.
    fn face(&mut self, corner: DVec3, a: DVec3, b: DVec3) {
        self.add(move |u, v| corner + u * a + v * b);
    }

    /// The distance from `p` to the surface: grids of `(n + 1)^2` points per patch, then the
    /// best point of each patch and the eight best overall refined.
    fn distance(&self, p: DVec3, n: usize) -> f64 {
        let mut starts: Vec<(f64, usize, f64, f64)> = Vec::new();
        for (k, f) in self.patches.iter().enumerate() {
            let mut best = (f64::INFINITY, k, 0.0, 0.0);
            for i in 0..=n {
                for j in 0..=n {
                    let (u, v) = (i as f64 / n as f64, j as f64 / n as f64);
                    let d = (f(u, v) - p).length_squared();
                    starts.push((d, k, u, v));
                    if d < best.0 {
                        best = (d, k, u, v);
                    }
                }
            }
            starts.push(best);
        }
        let per_patch: Vec<_> = starts.split_off(starts.len() - self.patches.len());
        starts.sort_unstable_by(|a, b| a.0.total_cmp(&b.0));
        per_patch
            .iter()
            .chain(starts.iter().take(8))
            .map(|&(_, k, u, v)| refine(&*self.patches[k], p, u, v, 1.0 / n as f64))
            .fold(f64::INFINITY, f64::min)
    }
}

/// The distance from `p` to the patch `f` near `(u, v)`: a pattern search on `|f(u, v) - p|^2`
/// over the unit square, moving to the best of the eight neighbours at step `s` and halving
/// `s` when none is better, from the grid's spacing down to `1e-13` (where differences of the
/// squared distance reach its rounding). Slower than Newton's method but it cannot diverge, and
/// on a smooth patch it ends within rounding of the local minimum.
fn refine(f: &dyn Fn(f64, f64) -> DVec3, p: DVec3, u0: f64, v0: f64, step: f64) -> f64 {
    let g = |u: f64, v: f64| (f(u, v) - p).length_squared();
    let (mut u, mut v, mut best) = (u0, v0, g(u0, v0));
    let mut s = step;
    while s > 1e-13 {
        let mut moved = false;
        for (du, dv) in [
            (1.0, 0.0),
            (-1.0, 0.0),
            (0.0, 1.0),
            (0.0, -1.0),
            (1.0, 1.0),
            (1.0, -1.0),
            (-1.0, 1.0),
            (-1.0, -1.0),
        ] {
            let (un, vn) = ((u + s * du).clamp(0.0, 1.0), (v + s * dv).clamp(0.0, 1.0));
            let gn = g(un, vn);
            if gn < best {
                (u, v, best) = (un, vn, gn);
                moved = true;
            }
        }
        if !moved {
            s *= 0.5;
        }
    }
    best.sqrt()
}

fn sphere_surface(c: DVec3, r: f64) -> Surface {
    let mut s = Surface::new();
    s.add(move |u, v| sphere_point(c, r, (0.0, PI), (0.0, 2.0 * PI), u, v));
    s
}

fn box_surface(c: DVec3, h: DVec3) -> Surface {
    let mut s = Surface::new();
    let axes = [DVec3::X, DVec3::Y, DVec3::Z];
    for k in 0..3 {
        let (a, b) = (axes[(k + 1) % 3], axes[(k + 2) % 3]);
        let (ha, hb, hk) = (h.dot(a), h.dot(b), h.dot(axes[k]));
        for sign in [-1.0, 1.0] {
            s.face(
                c + sign * hk * axes[k] - ha * a - hb * b,
                2.0 * ha * a,
                2.0 * hb * b,
            );
        }
    }
    s
}

/// The rounded box of outer half extents `outer` and radius `r`: the inner box's faces pushed
/// out by `r`, a quarter cylinder along each of its 12 edges, a sphere octant at each corner.
fn rounded_box_surface(c: DVec3, outer: DVec3, r: f64) -> Surface {
    let inner = outer - DVec3::splat(r);
    let mut s = Surface::new();
    let axes = [DVec3::X, DVec3::Y, DVec3::Z];
    for k in 0..3 {
        let (a, b, w) = (axes[(k + 1) % 3], axes[(k + 2) % 3], axes[k]);
        let (ha, hb, hk) = (inner.dot(a), inner.dot(b), inner.dot(w));
        for sign in [-1.0, 1.0] {
            s.face(
                c + sign * (hk + r) * w - ha * a - hb * b,
                2.0 * ha * a,
                2.0 * hb * b,
            );
        }
        for sa in [-1.0, 1.0] {
            for sb in [-1.0, 1.0] {
                let base = c + sa * ha * a + sb * hb * b;
                s.add(move |u, v| {
                    let ang = v * PI / 2.0;
                    base + (2.0 * u - 1.0) * hk * w + r * (ang.cos() * sa * a + ang.sin() * sb * b)
                });
            }
        }
    }
    for sx in [-1.0, 1.0] {
        for sy in [-1.0, 1.0] {
            for sz in [-1.0, 1.0] {
                let corner = c + DVec3::new(sx, sy, sz) * inner;
                s.add(move |u, v| {
                    let d = sphere_point(DVec3::ZERO, 1.0, (0.0, PI / 2.0), (0.0, PI / 2.0), u, v);
                    corner + r * DVec3::new(sx * d.x, sy * d.y, sz * d.z)
                });
            }
        }
    }
    s
}

/// The capsule: the cylinder side of the segment and the hemisphere at each end facing away.
fn capsule_surface(a: DVec3, b: DVec3, r: f64) -> Surface {
    let w = (b - a).normalize();
    let (u1, u2) = perp(w);
    let mut s = Surface::new();
    s.add(move |u, v| {
        let ang = v * 2.0 * PI;
        a + u * (b - a) + r * (ang.cos() * u1 + ang.sin() * u2)
    });
    for (end, out) in [(a, -w), (b, w)] {
        s.add(move |u, v| {
            let (th, ph) = (u * PI / 2.0, v * 2.0 * PI);
            end + r * (th.sin() * (ph.cos() * u1 + ph.sin() * u2) + th.cos() * out)
        });
    }
    s
}

/// The cylinder: its side and its two end disks.
fn cylinder_surface(a: DVec3, b: DVec3, r: f64) -> Surface {
    let w = (b - a).normalize();
    let (u1, u2) = perp(w);
    let mut s = Surface::new();
    s.add(move |u, v| {
        let ang = v * 2.0 * PI;
        a + u * (b - a) + r * (ang.cos() * u1 + ang.sin() * u2)
    });
    for end in [a, b] {
        s.add(move |u, v| {
            let ang = v * 2.0 * PI;
            end + u * r * (ang.cos() * u1 + ang.sin() * u2)
        });
    }
    s
}

fn torus_surface(c: DVec3, axis: DVec3, big: f64, small: f64) -> Surface {
    let w = axis.normalize();
    let (u1, u2) = perp(w);
    let mut s = Surface::new();
    s.add(move |u, v| {
        let (a, b) = (u * 2.0 * PI, v * 2.0 * PI);
        let radial = a.cos() * u1 + a.sin() * u2;
        c + (big + small * b.cos()) * radial + small * b.sin() * w
    });
    s
}

/// How far below the refined brute-force distance an exact field may be, relative to the
/// object's scale plus one: the refinement's convergence and rounding (measured at most 9e-16
/// over all primitives and seeds; the sampled brute force this replaces allowed its covering
/// radius, 0.3-0.8% of the object).
const UNDER_TOL: f64 = 1e-12;

/// Checks that `f` is the exact signed distance to `surface` (membership by `inside`) at 40
/// query points around `center` at the object's `scale`: never above the distance to the
/// surface's points (1e-12), at most `UNDER_TOL` below the refined distance, the sign from
/// membership away from the surface. Returns the largest gap `refined - |f|` seen.
fn check_exact_refined(
    what: &str,
    f: &dyn Sdf,
    surface: &Surface,
    inside: &dyn Fn(DVec3) -> bool,
    center: DVec3,
    scale: f64,
    rng: &mut Rng,
) -> f64 {
    assert_eq!(f.exactness(), Exactness::Exact, "{what}");
    let mut worst = 0.0f64;
    for p in queries(rng, center, scale, 40) {
        let d = f.distance(p);
        let brute = surface.distance(p, 48);
        let tol = 1e-12 * (1.0 + p.length() + scale);
        assert!(
            d.abs() <= brute + tol,
            "{what}: |f| = {} exceeds the distance to the surface {brute} at {p}",
            d.abs()
        );
        assert!(
            brute <= d.abs() + UNDER_TOL * (1.0 + scale),
            "{what}: f = {d} underestimates the distance {brute} at {p}"
        );
        worst = worst.max(brute - d.abs());
        if brute > 1e-9 * (1.0 + scale) {
            assert_eq!(
                d < 0.0,
                inside(p),
                "{what}: sign of f = {d} disagrees with membership at {p}"
            );
        }
    }
    worst
}

fn random_point(rng: &mut Rng) -> DVec3 {
    DVec3::new(
        rng.range(-1.0, 1.0),
        rng.range(-1.0, 1.0),
        rng.range(-1.0, 1.0),
    )
}

/// Seeds of the randomized primitives (each test draws its parameters from each).
const SEEDS: [u64; 6] = [1, 2, 3, 4, 5, 6];

#[test]
fn sphere_is_exact() {
    let mut worst = 0.0f64;
    for seed in SEEDS {
        let mut rng = Rng::new(100 + seed);
        let (c, r) = (random_point(&mut rng), rng.range(0.05, 1.5));
        let f = Sphere::new(c, r).unwrap();
        let inside = move |p: DVec3| (p - c).length() <= r;
        let w = check_exact_refined("sphere", &f, &sphere_surface(c, r), &inside, c, r, &mut rng);
        worst = worst.max(w);
    }
    println!("sphere: worst gap {worst:e}");
}

#[test]
fn box_is_exact() {
    let mut worst = 0.0f64;
    for seed in SEEDS {
        let mut rng = Rng::new(200 + seed);
        let c = random_point(&mut rng);
        let h = DVec3::new(
            rng.range(0.05, 1.5),
            rng.range(0.05, 1.5),
            rng.range(0.05, 1.5),
        );
        let f = Cuboid::new(c, h).unwrap();
        let inside = move |p: DVec3| {
            let q = (p - c).abs();
            q.x <= h.x && q.y <= h.y && q.z <= h.z
        };
        let scale = h.max_element();
        let w = check_exact_refined("box", &f, &box_surface(c, h), &inside, c, scale, &mut rng);
        worst = worst.max(w);
    }
    println!("box: worst gap {worst:e}");
}

#[test]
fn rounded_box_is_exact() {
    let mut worst = 0.0f64;
    for seed in SEEDS {
        let mut rng = Rng::new(300 + seed);
        let c = random_point(&mut rng);
        let h = DVec3::new(
            rng.range(0.1, 1.5),
            rng.range(0.1, 1.5),
            rng.range(0.1, 1.5),
        );
        let r = rng.range(0.01, 0.95) * h.min_element();
        let f = RoundedBox::new(c, h, r).unwrap();
        let inner = h - DVec3::splat(r);
        let inside = move |p: DVec3| {
            let q = p - c;
            (q - q.clamp(-inner, inner)).length() <= r
        };
        let s = rounded_box_surface(c, h, r);
        let w = check_exact_refined("rounded box", &f, &s, &inside, c, h.max_element(), &mut rng);
        worst = worst.max(w);
    }
    println!("rounded box: worst gap {worst:e}");
}

#[test]
fn capsule_is_exact() {
    let mut worst = 0.0f64;
    for seed in SEEDS {
        let mut rng = Rng::new(400 + seed);
        let (a, b, r) = (
            random_point(&mut rng),
            random_point(&mut rng),
            rng.range(0.05, 0.8),
        );
        let f = Capsule::new(a, b, r).unwrap();
        let inside = move |p: DVec3| seg_dist(p, a, b) <= r;
        let scale = 0.5 * (b - a).length() + r;
        let s = capsule_surface(a, b, r);
        let w = check_exact_refined("capsule", &f, &s, &inside, 0.5 * (a + b), scale, &mut rng);
        worst = worst.max(w);
    }
    println!("capsule: worst gap {worst:e}");
}

#[test]
fn cylinder_is_exact() {
    let mut worst = 0.0f64;
    for seed in SEEDS {
        let mut rng = Rng::new(500 + seed);
        let (a, b, r) = (
            random_point(&mut rng),
            random_point(&mut rng),
            rng.range(0.05, 0.8),
        );
        let f = Cylinder::new(a, b, r).unwrap();
        let w = (b - a).normalize();
        let len = (b - a).length();
        let inside = move |p: DVec3| {
            let t = (p - a).dot(w);
            (0.0..=len).contains(&t) && (p - a - t * w).length() <= r
        };
        let scale = 0.5 * len + r;
        let s = cylinder_surface(a, b, r);
        let g = check_exact_refined("cylinder", &f, &s, &inside, 0.5 * (a + b), scale, &mut rng);
        worst = worst.max(g);
    }
    println!("cylinder: worst gap {worst:e}");
}

#[test]
fn torus_is_exact() {
    let mut worst = 0.0f64;
    for seed in SEEDS {
        let mut rng = Rng::new(600 + seed);
        let (c, axis) = (random_point(&mut rng), rng.dir());
        let big = rng.range(0.2, 1.2);
        // The last seed is a horn torus (major == minor), still exact: the tube reaches the
        // axis only at a point.
        let small = if seed == 6 {
            big
        } else {
            rng.range(0.05, 1.0) * big
        };
        let f = Torus::new(c, axis, big, small).unwrap();
        let inside = move |p: DVec3| {
            let q = p - c;
            let z = q.dot(axis);
            let rho = (q - z * axis).length();
            (rho - big).hypot(z) <= small
        };
        let s = torus_surface(c, axis, big, small);
        let w = check_exact_refined("torus", &f, &s, &inside, c, big + small, &mut rng);
        worst = worst.max(w);
    }
    println!("torus: worst gap {worst:e}");
}

#[test]
fn plane_matches_point_plane_distance() {
    let mut rng = Rng::new(8);
    for _ in 0..200 {
        let point = DVec3::new(
            rng.range(-5.0, 5.0),
            rng.range(-5.0, 5.0),
            rng.range(-5.0, 5.0),
        );
        let n = rng.dir() * rng.range(1e-3, 1e3);
        let f = Plane::new(point, n).unwrap();
        let p = DVec3::new(
            rng.range(-9.0, 9.0),
            rng.range(-9.0, 9.0),
            rng.range(-9.0, 9.0),
        );
        // Distance to the plane through the foot of the perpendicular, by projection.
        let d = (p - point).dot(n) / n.length();
        assert!((f.distance(p) - d).abs() <= 1e-12 * (1.0 + p.length() + point.length()));
    }
}

#[test]
fn transforms_keep_distances_exact() {
    let (c, h) = (DVec3::new(0.2, 0.0, -0.1), DVec3::new(0.5, 0.3, 0.2));
    let rot = DQuat::from_axis_angle(DVec3::new(1.0, 2.0, -0.5).normalize(), 0.9);
    let (shift, scale) = (DVec3::new(1.0, -2.0, 0.5), 2.5);
    // The quaternion is given unnormalized on purpose: the constructor normalizes it.
    let f = Transformed::new(Cuboid::new(c, h).unwrap(), rot * 3.0, shift, scale).unwrap();
    let mut s = Samples::new();
    box_faces(&mut s, c, h, 250);
    let map = |p: DVec3| scale * (rot * p) + shift;
    s.points.iter_mut().for_each(|p| *p = map(*p));
    s.cover *= scale;
    let inside = |p: DVec3| {
        let q = (rot.inverse() * (p - shift) / scale - c).abs();
        q.x <= h.x && q.y <= h.y && q.z <= h.z
    };
    check_exact("transformed box", &f, &s, &inside, map(c), scale, 9);

    let t = Transformed::new(
        Torus::new(DVec3::ZERO, DVec3::Z, 0.5, 0.2).unwrap(),
        DQuat::from_rotation_x(1.1),
        DVec3::new(-1.0, 0.0, 2.0),
        0.4,
    )
    .unwrap();
    let mut s = torus_samples(DVec3::ZERO, DVec3::Z, 0.5, 0.2, 500);
    let map = |p: DVec3| 0.4 * (DQuat::from_rotation_x(1.1) * p) + DVec3::new(-1.0, 0.0, 2.0);
    s.points.iter_mut().for_each(|p| *p = map(*p));
    s.cover *= 0.4;
    let inside = |p: DVec3| {
        let q = DQuat::from_rotation_x(-1.1) * (p - DVec3::new(-1.0, 0.0, 2.0)) / 0.4;
        (q.truncate().length() - 0.5).hypot(q.z) <= 0.2
    };
    check_exact(
        "transformed torus",
        &t,
        &s,
        &inside,
        DVec3::new(-1.0, 0.0, 2.0),
        0.4,
        10,
    );
}

/// The CSG table: union exact outside, intersection and difference exact inside, each checked
/// against the brute-force distance to the result's true surface, on its exact side; the
/// other side must still never overestimate (checked by `check_point` too).
#[test]
fn csg_exactness_table_holds() {
    let (ca, ra) = (DVec3::new(-0.3, 0.0, 0.0), 0.6);
    let (cb, hb) = (DVec3::new(0.3, 0.1, 0.0), DVec3::new(0.45, 0.4, 0.5));
    let a = Sphere::new(ca, ra).unwrap();
    let b = Cuboid::new(cb, hb).unwrap();
    let in_a = |p: DVec3| (p - ca).length() <= ra;
    let in_b = |p: DVec3| {
        let q = (p - cb).abs();
        q.x <= hb.x && q.y <= hb.y && q.z <= hb.z
    };
    let sa = sphere_samples(ca, ra, 500);
    let mut sb = Samples::new();
    box_faces(&mut sb, cb, hb, 300);
    // The surface of a boolean result: each operand's surface points kept by the operation.
    let pick = |keep_a: &dyn Fn(DVec3) -> bool, keep_b: &dyn Fn(DVec3) -> bool| {
        let mut s = Samples::new();
        s.points
            .extend(sa.points.iter().copied().filter(|&p| keep_a(p)));
        s.points
            .extend(sb.points.iter().copied().filter(|&p| keep_b(p)));
        s.cover = sa.cover.max(sb.cover);
        s
    };
    let strictly = |f: &dyn Fn(DVec3) -> bool, p: DVec3| f(p);
    let union_s = pick(&|p| !strictly(&in_b, p), &|p| !strictly(&in_a, p));
    let inter_s = pick(&|p| in_b(p), &|p| in_a(p));
    let diff_s = pick(&|p| !in_b(p), &|p| in_a(p));

    let mut rng = Rng::new(11);
    let pts = queries(&mut rng, DVec3::ZERO, 1.2, 160);
    let u = Union(a, b);
    let i = Intersection(a, b);
    let d = Difference(a, b);
    assert_eq!(u.exactness(), Exactness::ExactOutside);
    assert_eq!(i.exactness(), Exactness::ExactInside);
    assert_eq!(d.exactness(), Exactness::ExactInside);
    let all = UnionAll::new(vec![Box::new(a), Box::new(b)]);
    assert_eq!(all.exactness(), Exactness::ExactOutside);
    for &p in &pts {
        check_point(
            "union",
            &u,
            &union_s,
            &|p| in_a(p) || in_b(p),
            p,
            u.exactness(),
        );
        check_point(
            "union all",
            &all,
            &union_s,
            &|p| in_a(p) || in_b(p),
            p,
            u.exactness(),
        );
        check_point(
            "intersection",
            &i,
            &inter_s,
            &|p| in_a(p) && in_b(p),
            p,
            i.exactness(),
        );
        check_point(
            "difference",
            &d,
            &diff_s,
            &|p| in_a(p) && !in_b(p),
            p,
            d.exactness(),
        );
    }
    // The other sides really are only bounds: somewhere the value is clearly below the distance
    // (else the table would undersell the operations).
    let gap = |f: &dyn Sdf, s: &Samples, outside: bool| {
        pts.iter()
            .filter(|&&p| (f.distance(p) >= 0.0) == outside)
            .map(|&p| s.nearest(p) - f.distance(p).abs())
            .fold(0.0, f64::max)
    };
    assert!(gap(&u, &union_s, false) > 0.05);
    assert!(gap(&i, &inter_s, true) > 0.05);
    assert!(gap(&d, &diff_s, true) > 0.05);
    // Nested exactness: a difference of an exact-outside union is only a bound inside.
    assert_eq!(
        Difference(a, Intersection(a, b)).exactness(),
        Exactness::Bound
    );
    assert_eq!(Union(a, Intersection(a, b)).exactness(), Exactness::Bound);
    assert_eq!(
        SmoothUnion::new(a, b, 0.1).unwrap().exactness(),
        Exactness::Bound
    );
    let one = UnionAll::new(vec![Box::new(a)]);
    assert_eq!(one.exactness(), Exactness::Exact);
}

#[test]
fn smooth_union_blends_only_within_its_width() {
    let a = Sphere::new(DVec3::new(-0.5, 0.0, 0.0), 0.4).unwrap();
    let b = Sphere::new(DVec3::new(0.5, 0.0, 0.0), 0.4).unwrap();
    let k = 0.2;
    let s = SmoothUnion::new(a, b, k).unwrap();
    let mut rng = Rng::new(12);
    for _ in 0..2000 {
        let p = DVec3::new(
            rng.range(-2.0, 2.0),
            rng.range(-2.0, 2.0),
            rng.range(-2.0, 2.0),
        );
        let (da, db) = (a.distance(p), b.distance(p));
        let v = s.distance(p);
        // Never above the union, at most k/4 below it, equal to it where the operands differ
        // by k or more.
        assert!(v <= da.min(db) + 1e-15);
        assert!(v >= da.min(db) - k / 4.0 - 1e-15);
        if (da - db).abs() >= k {
            assert_eq!(v, da.min(db));
        }
    }
    // At the midpoint between the balls the operands are equal: the full k/4 is added.
    let mid = s.distance(DVec3::ZERO);
    assert!((mid - (0.1 - k / 4.0)).abs() < 1e-15);
}

#[test]
fn normals_match_the_geometry() {
    let c = DVec3::new(0.2, 0.3, -0.4);
    let f = Sphere::new(c, 0.5).unwrap();
    let mut rng = Rng::new(13);
    for _ in 0..100 {
        let d = rng.dir();
        let n = normal(&f, c + 0.5 * d, 1e-6).unwrap();
        assert!((n - d).length() < 1e-8, "{n} vs {d}");
    }
    // On a box face, the face normal.
    let b = Cuboid::new(DVec3::ZERO, DVec3::ONE).unwrap();
    let n = normal(&b, DVec3::new(0.3, 1.0, -0.2), 1e-6).unwrap();
    assert!((n - DVec3::Y).length() < 1e-8);
    // At the center of a sphere the gradient vanishes: no normal, no panic.
    assert!(normal(&f, c, 1e-6).is_none());
}

#[test]
fn bad_parameters_are_errors() {
    let nan = f64::NAN;
    let inf = f64::INFINITY;
    let o = DVec3::ZERO;
    let is_range = |e: GeomError| matches!(e, GeomError::OutOfRange { .. });
    let is_degen = |e: GeomError| matches!(e, GeomError::Degenerate(_));
    assert!(is_range(Sphere::new(o, nan).unwrap_err()));
    assert!(is_range(
        Sphere::new(DVec3::new(inf, 0.0, 0.0), 1.0).unwrap_err()
    ));
    assert!(is_degen(Sphere::new(o, -1.0).unwrap_err()));
    assert!(is_degen(Sphere::new(o, 0.0).unwrap_err()));
    assert!(is_range(Sphere::new(o, 1e200).unwrap_err()));
    assert!(is_degen(
        Cuboid::new(o, DVec3::new(1.0, -1.0, 1.0)).unwrap_err()
    ));
    assert!(is_range(
        Cuboid::new(o, DVec3::new(1.0, nan, 1.0)).unwrap_err()
    ));
    assert!(is_degen(RoundedBox::new(o, DVec3::ONE, -0.1).unwrap_err()));
    assert!(is_degen(RoundedBox::new(o, DVec3::ONE, 1.0).unwrap_err()));
    assert!(is_range(RoundedBox::new(o, DVec3::ONE, inf).unwrap_err()));
    assert!(is_degen(Capsule::new(o, DVec3::X, -0.5).unwrap_err()));
    assert!(is_range(
        Capsule::new(o, DVec3::splat(nan), 0.5).unwrap_err()
    ));
    assert!(Capsule::new(o, o, 0.5).is_ok());
    assert!(is_degen(Cylinder::new(o, o, 0.5).unwrap_err()));
    assert!(is_degen(Cylinder::new(o, DVec3::Z, 0.0).unwrap_err()));
    assert!(is_degen(Torus::new(o, DVec3::Z, 0.2, 0.3).unwrap_err()));
    assert!(is_degen(Torus::new(o, DVec3::ZERO, 0.5, 0.3).unwrap_err()));
    assert!(is_degen(Torus::new(o, DVec3::Z, 0.5, -0.3).unwrap_err()));
    assert!(is_range(Torus::new(o, DVec3::Z, nan, 0.3).unwrap_err()));
    assert!(is_degen(Plane::new(o, DVec3::ZERO).unwrap_err()));
    assert!(is_range(
        Plane::new(o, DVec3::new(0.0, inf, 0.0)).unwrap_err()
    ));
    assert!(Plane::new(o, DVec3::new(0.0, 1e-300, 0.0)).is_ok());
    let s = Sphere::new(o, 1.0).unwrap();
    assert!(is_degen(
        Transformed::new(s, DQuat::from_xyzw(0.0, 0.0, 0.0, 0.0), o, 1.0).unwrap_err()
    ));
    assert!(is_degen(
        Transformed::new(s, DQuat::IDENTITY, o, -2.0).unwrap_err()
    ));
    assert!(is_range(
        Transformed::new(s, DQuat::from_xyzw(nan, 0.0, 0.0, 1.0), o, 1.0).unwrap_err()
    ));
    assert!(is_degen(SmoothUnion::new(s, s, 0.0).unwrap_err()));
    assert!(is_range(SmoothUnion::new(s, s, nan).unwrap_err()));
    // The empty union is the empty set: +inf everywhere.
    assert_eq!(UnionAll::new(vec![]).distance(DVec3::ONE), f64::INFINITY);
}

/// One field of every kind, nested, from proptest parameters.
fn zoo(params: &[f64]) -> Vec<Box<dyn Sdf>> {
    let v = |i: usize| DVec3::new(params[i], params[i + 1], params[i + 2]);
    let pos = |i: usize| 0.05 + params[i].abs();
    let sphere = Sphere::new(v(0), pos(3)).unwrap();
    let cuboid = Cuboid::new(v(4), v(7).abs() + DVec3::splat(0.05)).unwrap();
    let rounded = RoundedBox::new(v(4), v(7).abs() + DVec3::splat(0.3), 0.25).unwrap();
    let capsule = Capsule::new(v(0), v(4), pos(10)).unwrap();
    let cylinder = Cylinder::new(v(0), v(4) + DVec3::X * 0.1, pos(10)).unwrap();
    let torus = Torus::new(v(4), v(7) + DVec3::Z, pos(3) + pos(10), pos(10)).unwrap();
    let plane = Plane::new(v(0), v(7) + DVec3::Y).unwrap();
    let rot = DQuat::from_axis_angle((v(7) + DVec3::X).normalize(), params[11]);
    let moved = Transformed::new(torus, rot, v(0), pos(3) + 0.1).unwrap();
    vec![
        Box::new(sphere),
        Box::new(cuboid),
        Box::new(rounded),
        Box::new(capsule),
        Box::new(cylinder),
        Box::new(torus),
        Box::new(plane),
        Box::new(moved),
        Box::new(Union(sphere, cuboid)),
        Box::new(Intersection(capsule, rounded)),
        Box::new(Difference(cylinder, sphere)),
        Box::new(SmoothUnion::new(cuboid, torus, pos(11)).unwrap()),
        Box::new(
            Transformed::new(
                SmoothUnion::new(sphere, capsule, 0.3).unwrap(),
                rot,
                v(4),
                0.7,
            )
            .unwrap(),
        ),
    ]
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(support::cases(300)))]

    /// Every field is 1-Lipschitz: `|f(p) - f(q)| <= |p - q|`, at far pairs and at pairs a
    /// hair apart (where a wrong gradient shows).
    #[test]
    fn fields_are_one_lipschitz(
        params in proptest::collection::vec(-1.0f64..1.0, 12),
        p in proptest::array::uniform3(-3.0f64..3.0),
        q in proptest::array::uniform3(-3.0f64..3.0),
        near in proptest::array::uniform3(-1e-4f64..1e-4),
    ) {
        let (p, q) = (DVec3::from_array(p), DVec3::from_array(q));
        let close = p + DVec3::from_array(near);
        for (k, f) in zoo(&params).iter().enumerate() {
            for (a, b) in [(p, q), (p, close)] {
                let lhs = (f.distance(a) - f.distance(b)).abs();
                let rhs = (a - b).length();
                prop_assert!(lhs <= rhs * (1.0 + 1e-9) + 1e-12, "field {k}: {lhs} > {rhs}");
            }
        }
    }

    /// Constructors never panic on arbitrary (also non-finite) input, and a field they accept
    /// gives finite values at finite points.
    #[test]
    fn constructors_reject_or_accept_cleanly(
        raw in proptest::collection::vec(
            prop_oneof![
                4 => -10.0f64..10.0,
                1 => Just(f64::NAN),
                1 => Just(f64::INFINITY),
                1 => Just(-0.0f64),
                1 => Just(1e150f64),
            ],
            7,
        ),
    ) {
        let v = DVec3::new(raw[0], raw[1], raw[2]);
        let w = DVec3::new(raw[3], raw[4], raw[5]);
        let r = raw[6];
        let p = DVec3::new(0.3, -0.7, 1.1);
        let fields: Vec<Result<Box<dyn Sdf>, GeomError>> = vec![
            Sphere::new(v, r).map(|f| Box::new(f) as Box<dyn Sdf>),
            Cuboid::new(v, w).map(|f| Box::new(f) as Box<dyn Sdf>),
            RoundedBox::new(v, w, r).map(|f| Box::new(f) as Box<dyn Sdf>),
            Capsule::new(v, w, r).map(|f| Box::new(f) as Box<dyn Sdf>),
            Cylinder::new(v, w, r).map(|f| Box::new(f) as Box<dyn Sdf>),
            Torus::new(v, w, raw[0], r).map(|f| Box::new(f) as Box<dyn Sdf>),
            Plane::new(v, w).map(|f| Box::new(f) as Box<dyn Sdf>),
        ];
        for f in fields.into_iter().flatten() {
            prop_assert!(f.distance(p).is_finite());
        }
    }
}
