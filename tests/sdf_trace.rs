//! Sphere and cone tracing against closed forms: ray-sphere and ray-box (slab) intersections,
//! and the first contact of a cone with a ball, which solves a quadratic. Random scenes check
//! that no trace steps over a surface (a dense march finds no earlier contact), and grazing rays
//! that the step cap ends every trace.

mod support;

use arealight::GeomError;
use arealight::glam::DVec3;
use arealight::sdf::{
    Cuboid, Plane, Sdf, Sphere, Trace, TraceLimits, Union, UnionAll, cone_trace, sphere_trace,
};
use proptest::prelude::*;
use support::Rng;

/// First `t >= 0` where `|o + t d - c| = r + r0 + t k` (the cone of radius `r0 + t k` around the
/// ray touches the ball `(c, r)`), from the quadratic `|w + t d|^2 = (a + t k)^2` with
/// `w = o - c`, `a = r + r0`, taking only roots where `a + t k >= 0`.
fn cone_ball_contact(o: DVec3, d: DVec3, c: DVec3, r: f64, r0: f64, k: f64) -> Option<f64> {
    let w = o - c;
    let a = r + r0;
    if w.length() <= a {
        return Some(0.0);
    }
    let qa = 1.0 - k * k;
    let qb = 2.0 * (w.dot(d) - a * k);
    let qc = w.length_squared() - a * a;
    let roots: Vec<f64> = if qa.abs() < 1e-14 {
        vec![-qc / qb]
    } else {
        let disc = qb * qb - 4.0 * qa * qc;
        if disc < 0.0 {
            return None;
        }
        let s = disc.sqrt();
        vec![(-qb - s) / (2.0 * qa), (-qb + s) / (2.0 * qa)]
    };
    roots
        .into_iter()
        .filter(|&t| t >= 0.0 && a + t * k >= 0.0)
        .fold(None, |m: Option<f64>, t| Some(m.map_or(t, |m| m.min(t))))
}

/// Slab test: entry distance of the ray into the box `c ± h`, if any (`0` from inside).
fn ray_box(o: DVec3, d: DVec3, c: DVec3, h: DVec3) -> Option<f64> {
    let (mut lo, mut hi) = (0.0f64, f64::INFINITY);
    for i in 0..3 {
        let (oi, di, ci, hi_) = (o[i], d[i], c[i], h[i]);
        if di.abs() < 1e-300 {
            if (oi - ci).abs() > hi_ {
                return None;
            }
            continue;
        }
        let (t1, t2) = ((ci - hi_ - oi) / di, (ci + hi_ - oi) / di);
        lo = lo.max(t1.min(t2));
        hi = hi.min(t1.max(t2));
    }
    (lo <= hi).then_some(lo)
}

#[test]
fn sphere_trace_meets_spheres_and_boxes_where_closed_forms_do() {
    let mut rng = Rng::new(21);
    let mut hits = 0;
    for _ in 0..400 {
        let c = DVec3::new(
            rng.range(-1.0, 1.0),
            rng.range(-1.0, 1.0),
            rng.range(-1.0, 1.0),
        );
        let h = DVec3::new(
            rng.range(0.1, 0.8),
            rng.range(0.1, 0.8),
            rng.range(0.1, 0.8),
        );
        let r = rng.range(0.1, 0.8);
        let o = rng.dir() * 4.0;
        // Aim near the object so that about half of the rays hit.
        let d = (c + rng.dir() * rng.range(0.0, 1.2) - o).normalize();
        let limits = TraceLimits {
            t_min: 0.0,
            t_max: 20.0,
            max_steps: 100_000,
            hit_distance: 1e-9,
        };
        let ball = Sphere::new(c, r).unwrap();
        let cube = Cuboid::new(c, h).unwrap();
        let checks: [(&dyn Sdf, Option<f64>); 2] = [
            (&ball, cone_ball_contact(o, d, c, r, 0.0, 0.0)),
            (&cube, ray_box(o, d, c, h)),
        ];
        for (f, want) in checks {
            let got = sphere_trace(f, o, d, &limits).unwrap();
            match (got, want) {
                (Trace::Hit { t, .. }, Some(w)) => {
                    hits += 1;
                    // Never past the surface; short of it only by the hit distance over the
                    // cosine of incidence (bounded for all but grazing rays, which end here
                    // before the surface but within 1e-9 of it).
                    assert!(t <= w + 1e-12, "overshoot: {t} > {w}");
                    assert!(f.distance(o + t * d) <= 1e-9);
                    assert!(w - t < 1e-4, "{t} vs {w}");
                }
                (Trace::Miss { .. }, None) => {}
                (Trace::Miss { .. }, Some(w)) => {
                    // Only a ray grazing the surface within the hit distance can miss it.
                    let closest = (0..=2000)
                        .map(|i| f.distance(o + d * (w * i as f64 / 2000.0)))
                        .fold(f64::INFINITY, f64::min);
                    assert!(closest < 1e-6, "missed a hit at {w}");
                }
                (got, want) => panic!("trace {got:?}, closed form {want:?}"),
            }
        }
    }
    assert!(hits > 200);
}

#[test]
fn cone_trace_meets_balls_where_the_quadratic_does() {
    let mut rng = Rng::new(22);
    let mut hits = 0;
    for _ in 0..600 {
        let c = DVec3::new(
            rng.range(-1.0, 1.0),
            rng.range(-1.0, 1.0),
            rng.range(-1.0, 1.0),
        );
        let r = rng.range(0.1, 0.8);
        let o = rng.dir() * 4.0;
        let d = (c + rng.dir() * rng.range(0.0, 2.0) - o).normalize();
        let r0 = rng.range(-0.05, 0.1);
        let k = rng.range(-0.1, 0.3);
        let limits = TraceLimits {
            t_min: 0.0,
            t_max: 8.0,
            max_steps: 100_000,
            hit_distance: 1e-10,
        };
        let ball = Sphere::new(c, r).unwrap();
        let got = cone_trace(&ball, o, d, r0, k, &limits).unwrap();
        let want = cone_ball_contact(o, d, c, r, r0, k).filter(|&t| t <= 8.0);
        match (got, want) {
            (Trace::Hit { t, .. }, Some(w)) => {
                hits += 1;
                assert!(t <= w + 1e-9, "cone overshoot: {t} > {w}");
                assert!(w - t < 1e-5, "{t} vs {w}");
            }
            (Trace::Miss { .. }, None) => {}
            (got, want) => {
                // A cone grazing the ball within rounding may go either way.
                let gap = (0..=4000)
                    .map(|i| {
                        let t = 8.0 * i as f64 / 4000.0;
                        ball.distance(o + t * d) - r0 - t * k
                    })
                    .fold(f64::INFINITY, f64::min);
                assert!(
                    gap.abs() < 1e-6,
                    "trace {got:?}, quadratic {want:?}, gap {gap}"
                );
            }
        }
    }
    assert!(hits > 150);
}

fn scene(params: &[f64]) -> UnionAll {
    let mut members: Vec<Box<dyn Sdf + Send + Sync>> = Vec::new();
    for c in params.chunks(4) {
        let center = DVec3::new(c[0], c[1], c[2]) * 2.0;
        if c[3] > 0.0 {
            members.push(Box::new(
                Sphere::new(center, 0.05 + c[3].abs() * 0.5).unwrap(),
            ));
        } else {
            members.push(Box::new(
                Cuboid::new(center, DVec3::splat(0.05 + c[3].abs() * 0.4)).unwrap(),
            ));
        }
    }
    members.push(Box::new(
        Plane::new(DVec3::new(0.0, 0.0, -2.5), DVec3::Z).unwrap(),
    ));
    UnionAll::new(members)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(support::cases(200)))]

    /// No trace passes a point where the cone's gap `f - r0 - t k` is negative: a dense march
    /// over the traced range finds none before the reported end.
    #[test]
    fn traces_never_step_over_a_contact(
        params in proptest::collection::vec(-1.0f64..1.0, 20),
        o in proptest::array::uniform3(-3.0f64..3.0),
        d in proptest::array::uniform3(-1.0f64..1.0),
        r0 in 0.0f64..0.05,
        k in 0.0f64..0.3,
    ) {
        let f = scene(&params);
        let (o, d) = (DVec3::from_array(o), DVec3::from_array(d));
        prop_assume!(d.length() > 0.1);
        let d = d.normalize();
        let limits = TraceLimits { t_min: 0.0, t_max: 10.0, max_steps: 10_000, hit_distance: 1e-7 };
        for (r0, k) in [(0.0, 0.0), (r0, k)] {
            let end = match cone_trace(&f, o, d, r0, k, &limits).unwrap() {
                Trace::Hit { t, .. } | Trace::StepLimit { t, .. } => t,
                Trace::Miss { .. } => 10.0,
            };
            if end == 0.0 {
                // Started inside a solid: a hit at t_min, nothing was stepped over.
                continue;
            }
            for i in 0..2000 {
                let t = end * i as f64 / 2000.0;
                let gap = f.distance(o + t * d) - r0 - t * k;
                prop_assert!(gap > -1e-9, "contact at {t} before the end {end}");
            }
        }
    }
}

#[test]
fn traces_always_terminate_within_their_caps() {
    // A ray grazing a plane 1e-3 above it: sphere tracing advances by 1e-3 per step, so the
    // cap ends it first.
    let floor = Plane::new(DVec3::ZERO, DVec3::Z).unwrap();
    let limits = TraceLimits {
        t_min: 0.0,
        t_max: 100.0,
        max_steps: 64,
        hit_distance: 1e-6,
    };
    let got = sphere_trace(&floor, DVec3::new(0.0, 0.0, 1e-3), DVec3::X, &limits).unwrap();
    assert!(matches!(got, Trace::StepLimit { steps: 64, .. }), "{got:?}");
    assert!((got.steps(), got.hit()) == (64, None));
    // A ray approaching the plane at a grazing angle converges geometrically: it ends as a hit
    // or at the cap, never beyond it.
    let dir = DVec3::new(1.0, 0.0, -1e-6);
    let got = sphere_trace(&floor, DVec3::new(0.0, 0.0, 1.0), dir, &limits).unwrap();
    assert!(got.steps() <= 64);
    // The empty scene: +inf everywhere, an immediate miss.
    let empty = UnionAll::new(vec![]);
    let got = sphere_trace(&empty, DVec3::ZERO, DVec3::Z, &limits).unwrap();
    assert_eq!(got, Trace::Miss { steps: 1 });
    // A start inside a solid is a hit at t_min.
    let ball = Sphere::new(DVec3::ZERO, 1.0).unwrap();
    let got = sphere_trace(&ball, DVec3::ZERO, DVec3::Z, &limits).unwrap();
    assert_eq!(got.hit(), Some(0.0));
}

/// A field that returns NaN beyond x = 1: traces report it instead of looping or panicking.
struct Broken;
impl Sdf for Broken {
    fn distance(&self, p: DVec3) -> f64 {
        if p.x > 1.0 { f64::NAN } else { 0.5 }
    }
    fn exactness(&self) -> arealight::sdf::Exactness {
        arealight::sdf::Exactness::Bound
    }
}

#[test]
fn bad_input_is_an_error() {
    let ball = Sphere::new(DVec3::ZERO, 1.0).unwrap();
    let l = TraceLimits::new(10.0);
    let o = DVec3::new(0.0, 0.0, 5.0);
    let nan = f64::NAN;
    let range = |e: GeomError| matches!(e, GeomError::OutOfRange { .. });
    let degen = |e: GeomError| matches!(e, GeomError::Degenerate(_));
    assert!(range(
        sphere_trace(&ball, DVec3::splat(nan), -DVec3::Z, &l).unwrap_err()
    ));
    assert!(degen(sphere_trace(&ball, o, DVec3::ZERO, &l).unwrap_err()));
    assert!(range(
        sphere_trace(&ball, o, DVec3::new(0.0, f64::INFINITY, 1.0), &l).unwrap_err()
    ));
    assert!(range(
        cone_trace(&ball, o, -DVec3::Z, nan, 0.1, &l).unwrap_err()
    ));
    assert!(range(
        cone_trace(&ball, o, -DVec3::Z, 0.0, f64::INFINITY, &l).unwrap_err()
    ));
    for bad in [
        TraceLimits { t_min: -1.0, ..l },
        TraceLimits { t_max: -1.0, ..l },
        TraceLimits {
            hit_distance: 0.0,
            ..l
        },
        TraceLimits { max_steps: 0, ..l },
    ] {
        assert!(degen(sphere_trace(&ball, o, -DVec3::Z, &bad).unwrap_err()));
    }
    assert!(range(
        sphere_trace(&ball, o, -DVec3::Z, &TraceLimits { t_max: nan, ..l }).unwrap_err()
    ));
    // A field that turns NaN on the way.
    assert!(range(
        sphere_trace(&Broken, DVec3::ZERO, DVec3::X, &l).unwrap_err()
    ));
    // Tiny but valid directions are normalized, not rejected.
    let tiny = sphere_trace(&ball, o, DVec3::new(0.0, 0.0, -1e-300), &l).unwrap();
    assert!((tiny.hit().unwrap() - 4.0).abs() < 1e-5);
    // Union of a ball and a plane: the trace stops at the nearer one.
    let u = Union(
        ball,
        Plane::new(DVec3::new(0.0, 0.0, 3.0), DVec3::Z).unwrap(),
    );
    assert!((sphere_trace(&u, o, -DVec3::Z, &l).unwrap().hit().unwrap() - 2.0).abs() < 1e-5);
}
