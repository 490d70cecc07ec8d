//! Fuzz the SDF tracers and soft shadows: arbitrary (also non-finite, huge, tiny or negative)
//! scene, point and light parameters. Constructors either reject the input or build a field; on
//! a built scene every method either returns an error or a visibility in [0, 1] (a proxy
//! integral in [0, its solid angle]), Alg. 2 reports m in [-1, 1], and nothing panics or hangs
//! (every loop is capped).
//!
//! Run: `RUSTC_BOOTSTRAP=1 cargo fuzz run sdf_shadow -- -max_total_time=60` (from the crate root).
#![no_main]

use arealight::glam::{DQuat, DVec3};
use arealight::sdf::{
    Capsule, ConeSearch, Cuboid, Plane, Profile, QuadLight, QuilezSettings, Sdf, SmoothUnion,
    Sphere, SphereLight, TraceLimits, Transformed, Torus, UnionAll, cone_trace, fast_soft_shadow,
    minimal_tangent_cone, proxy_integral, proxy_quad_integral, quilez_improved_shadow,
    quilez_shadow, sphere_trace,
};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|raw: [f64; 24]| {
    let v = |i: usize| DVec3::new(raw[i], raw[i + 1], raw[i + 2]);
    let mut members: Vec<Box<dyn Sdf + Send + Sync>> = Vec::new();
    if let Ok(s) = Sphere::new(v(0), raw[3]) {
        members.push(Box::new(s));
    }
    if let Ok(b) = Cuboid::new(v(4), v(7))
        && let Ok(t) = Transformed::new(b, DQuat::from_xyzw(raw[0], raw[1], raw[2], raw[3]), v(0), raw[10])
    {
        members.push(Box::new(t));
    }
    if let Ok(c) = Capsule::new(v(0), v(4), raw[11]) {
        members.push(Box::new(c));
    }
    if let (Ok(a), Ok(b)) = (Torus::new(v(4), v(7), raw[10], raw[11]), Plane::new(v(0), v(7)))
        && let Ok(s) = SmoothUnion::new(a, b, raw[3])
    {
        members.push(Box::new(s));
    }
    let scene = UnionAll::new(members);
    let p = v(12);
    let eps = raw[21].abs().fract().max(1e-3);
    let search = ConeSearch { epsilon: eps, t_min: raw[22], max_steps: 256 };
    let quilez = QuilezSettings { t_min: raw[22], hit_distance: 1e-6, max_steps: 256 };
    if let Ok(light) = SphereLight::new(v(15), raw[18]) {
        for r in [
            fast_soft_shadow(&scene, p, &light, &search, Profile::Chord),
            fast_soft_shadow(&scene, p, &light, &search, Profile::Smoothstep),
            quilez_shadow(&scene, p, &light, &quilez),
            quilez_improved_shadow(&scene, p, &light, &quilez),
        ]
        .into_iter()
        .flatten()
        {
            assert!((0.0..=1.0).contains(&r), "visibility {r}");
        }
        if let Ok(w) = proxy_integral(&scene, p, &light, |_| 1.0, 16, &search) {
            assert!(w.is_finite() && (0.0..=4.0 * std::f64::consts::PI).contains(&w), "{w}");
        }
    }
    if let Ok(quad) = QuadLight::new(v(15), v(18), v(7)) {
        if let Ok(w) = proxy_quad_integral(&scene, p, v(4), &quad, &search) {
            assert!(w.is_finite() && (-1e-12..=1.0 + 1e-12).contains(&w), "{w}");
        }
    }
    if let Ok(min) = minimal_tangent_cone(&scene, p, v(4), raw[19].abs(), raw[20].abs(), raw[23], &search) {
        assert!((-1.0..=1.0).contains(&min.m) && min.steps <= 256);
    }
    let limits = TraceLimits { t_min: 0.0, t_max: raw[23].abs().min(1e6), max_steps: 256, hit_distance: 1e-9 };
    for r in [sphere_trace(&scene, p, v(4), &limits), cone_trace(&scene, p, v(4), raw[19], raw[20], &limits)]
        .into_iter()
        .flatten()
    {
        assert!(r.steps() <= 256);
    }
});
