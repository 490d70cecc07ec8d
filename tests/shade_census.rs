//! Issue 24's families at the shade level, as a census: random scenes that live where silently
//! wrong values hide (sliver occluders, occluders in a light's plane or cutting through it,
//! shading points whose horizon passes within `1e-16..1e-9` of a light vertex, grazing views with
//! near-mirror roughness, points on occluder surfaces), each point shaded with both methods.
//!
//! Asserted per point: a valid query gives a finite, non-negative value or
//! `GeomError::Undecidable`, never another error; per light, `0 <= shadowed <= unshadowed`
//! (relative 1e-9); the two methods agree within `1e-9` of the light's unshadowed value. Over the
//! census, give-ups stay below 0.1% of the queries. A subsample is checked against the Monte
//! Carlo reference (`ReferenceBrdf::Ltc`, the Lambertian lobe: the reference samples lights by
//! solid angle, which cannot resolve near-mirror lobes) at 4.5 standard errors, with a second stage of 16 times
//! the samples for a point that fails the first (see tests/shade_exact.rs for the bound's
//! reasoning; about 300 checks here, so a false alarm has probability near 2e-3).
//!
//! `CENSUS_CASES=N` multiplies the number of scenes (default 1: 60 scenes x 40 points).

use arealight::GeomError;
use arealight::glam::DVec3;
use arealight::shade::{
    Body, ConvexPolyhedron, Light, Material, Method, MonteCarlo, ReferenceBrdf, Scene, TriangleMesh,
};
use support::Rng;
use support::shade::point_on_mesh;

mod support;

/// A light of one of four kinds about `c`, facing down where it is flat.
fn random_light(rng: &mut Rng, c: DVec3, kind: u64) -> Body {
    let s = rng.range(0.3, 0.7);
    match kind % 4 {
        0 => TriangleMesh::quad(c, DVec3::new(0.0, s, 0.0), DVec3::new(s, 0.0, 0.0))
            .unwrap()
            .into(),
        1 => ConvexPolyhedron::cuboid(c, DVec3::new(s, rng.range(0.2, 0.6), rng.range(0.05, 0.3)))
            .unwrap()
            .into(),
        2 => ConvexPolyhedron::icosphere(c, s * 0.6, 1).unwrap().into(),
        _ => TriangleMesh::quad(c, DVec3::new(0.0, s, 0.0), DVec3::new(s, 0.0, 0.0))
            .unwrap()
            .merged(
                &TriangleMesh::quad(
                    c + DVec3::new(rng.range(-0.3, 0.3), 0.0, rng.range(0.3, 0.6)),
                    DVec3::new(0.0, s, 0.0),
                    DVec3::new(s, 0.0, 0.0),
                )
                .unwrap(),
            )
            .unwrap()
            .into(),
    }
}

/// A sliver triangle near `c`: one vertex moved off the segment of the other two by
/// `1e-15..1e-9` of the size (`None` where that is too thin for a reliable normal, which
/// `TriangleMesh::new` rejects).
fn sliver(rng: &mut Rng, c: DVec3) -> Option<Body> {
    let a = c + rng.dir() * 0.4;
    let b = c - rng.dir() * 0.4;
    let off = 10f64.powf(rng.range(-15.0, -9.0));
    let m = a.lerp(b, rng.range(0.2, 0.8)) + rng.dir() * off * (b - a).length();
    TriangleMesh::new(vec![a, b, m], vec![[0, 1, 2]])
        .ok()
        .map(Into::into)
}

/// Occluders of the families: a sliver, a flat quad in the light's plane (either facing), a
/// box cutting through the light, a box touching its plane from below.
fn occluders(rng: &mut Rng, c: DVec3, light: &Body) -> Vec<Body> {
    let mut out = Vec::new();
    let at = c - DVec3::new(0.0, 0.0, rng.range(0.2, 1.0));
    if let Some(s) = sliver(rng, at) {
        out.push(s);
    }
    // The plane of the light's lowest vertex (a face plane for quads and boxes).
    let z = light
        .mesh()
        .vertices()
        .iter()
        .map(|v| v.z)
        .fold(f64::INFINITY, f64::min);
    let q = DVec3::new(c.x + rng.range(-0.4, 0.4), c.y + rng.range(-0.4, 0.4), z);
    let (u, v) = (
        DVec3::X * rng.range(0.1, 0.3),
        DVec3::Y * rng.range(0.1, 0.3),
    );
    let flat = if rng.f64() < 0.5 {
        TriangleMesh::quad(q, u, v)
    } else {
        TriangleMesh::quad(q, v, u)
    };
    out.push(flat.unwrap().into());
    let h = DVec3::new(
        rng.range(0.05, 0.2),
        rng.range(0.05, 0.2),
        rng.range(0.05, 0.4),
    );
    let through = c + DVec3::new(rng.range(-0.5, 0.5), rng.range(-0.5, 0.5), 0.0);
    out.push(ConvexPolyhedron::cuboid(through, h).unwrap().into());
    let below = DVec3::new(
        c.x + rng.range(-0.6, 0.6),
        c.y + rng.range(-0.6, 0.6),
        z - h.z,
    );
    out.push(ConvexPolyhedron::cuboid(below, h).unwrap().into());
    out
}

/// A shading point, normal and view: on the ground with the horizon tilted to pass within
/// `1e-16..1e-9` (absolute or relative) of a light vertex, on an occluder's surface, or on the
/// ground; views grazing (`cos 1e-4..0.05`) half of the time.
fn point(rng: &mut Rng, scene: &Scene, i: usize) -> (DVec3, DVec3, DVec3) {
    let (x, n) = match i % 3 {
        0 => {
            let x = DVec3::new(rng.range(-2.0, 2.0), rng.range(-2.0, 2.0), 0.0);
            let lm = scene.lights()[0].shape().mesh();
            let p = lm.vertices()[rng.below(lm.vertices().len())];
            let d = (p - x).normalize();
            // A normal perpendicular to the direction of the vertex, tilted by a tiny angle.
            let side = d.cross(DVec3::Z).normalize();
            let mut n = side.cross(d).normalize();
            if n.z < 0.0 {
                n = -n;
            }
            let eps = 10f64.powf(rng.range(-16.0, -9.0)) * if rng.f64() < 0.5 { -1.0 } else { 1.0 };
            (x, (n + d * eps).normalize())
        }
        1 => {
            // On a box or the flat quad, not on the sliver: a point on a triangle thinner than
            // rounding may be on either side of it, which decides whether the triangle covers
            // almost nothing or a quarter of the sphere (a documented give-up).
            let occ = &scene.occluders()[scene.occluders().len() - 3..];
            let k = rng.below(occ.len());
            point_on_mesh(rng, occ[k].mesh())
        }
        _ => (
            DVec3::new(rng.range(-2.0, 2.0), rng.range(-2.0, 2.0), 0.0),
            DVec3::Z,
        ),
    };
    let (t, b) = n.any_orthonormal_pair();
    let v = if rng.f64() < 0.5 {
        let c = rng.range(1e-4, 0.05);
        n * c + t * (1.0 - c * c).sqrt()
    } else {
        n * (0.3 + rng.f64()) + t * (rng.f64() - 0.5) + b * (rng.f64() - 0.5)
    };
    (x, n, v)
}

/// Whether `x` lies strictly inside a convex occluder (behind every face plane by 1e-9).
fn inside_a_convex_occluder(scene: &Scene, x: DVec3) -> bool {
    scene.occluders().iter().any(|o| match o {
        Body::Convex(p) => {
            let m = p.mesh();
            (0..m.triangle_count()).all(|t| m.triangle_normal(t).dot(x - m.triangle(t)[0]) < -1e-9)
        }
        _ => false,
    })
}

#[derive(Default)]
struct Tally {
    queries: usize,
    gave_up: usize,
    gave_up_per_triangle: usize,
    mc_checks: usize,
    mc_retested: usize,
    failures: Vec<String>,
}

fn cases() -> u64 {
    std::env::var("CENSUS_CASES")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(1)
}

#[test]
fn census_of_the_shade_families() {
    let mut rng = Rng::new(2424);
    let mut t = Tally::default();
    let mc = MonteCarlo::new(4096, ReferenceBrdf::Ltc);
    let mc16 = MonteCarlo::new(16 * 4096, ReferenceBrdf::Ltc);
    for case in 0..60 * cases() {
        let c = DVec3::new(
            rng.range(-0.5, 0.5),
            rng.range(-0.5, 0.5),
            rng.range(1.5, 2.5),
        );
        let body = random_light(&mut rng, c, case);
        let occ = occluders(&mut rng, c, &body);
        let base = Scene::new(
            vec![Light::new(body, DVec3::new(1.0, 0.8, 0.6)).unwrap()],
            occ,
        )
        .unwrap();
        if std::env::var("CENSUS_DUMP").is_ok_and(|d| d == case.to_string()) {
            eprintln!(
                "DUMP light {:?}",
                base.lights()[0].shape().mesh().vertices()
            );
            eprintln!(
                "DUMP tris {:?}",
                base.lights()[0].shape().mesh().triangles()
            );
            for o in base.occluders() {
                eprintln!(
                    "DUMP occ {:?} {:?}",
                    o.mesh().vertices(),
                    o.mesh().triangles()
                );
            }
        }
        let roughness = [0.0, 0.01, 0.05, 0.4][(case % 4) as usize];
        let m = Material::new(DVec3::splat(0.5), DVec3::splat(0.04), roughness).unwrap();
        let lambert = Material::diffuse(m.albedo()).unwrap();
        for i in 0..40 {
            let (x, n, v) = point(&mut rng, &base, i);
            // A point on one box inside another (the generator overlaps them) receives nothing by
            // the crate's rule, since a convex occluder is an opaque solid; the reference casts
            // rays against surfaces only and sees out through a box face lying in the light's
            // plane. Not a point anyone shades.
            if inside_a_convex_occluder(&base, x) {
                continue;
            }
            let mut values = Vec::new();
            for method in [Method::Silhouette, Method::PerTriangle] {
                let scene = base.clone().with_method(method);
                t.queries += 1;
                match scene.shade_per_light(x, n, v, &m) {
                    Ok(parts) => {
                        let p = parts[0];
                        let (s, u) = (p.shadowed(), p.unshadowed());
                        let ok = s.is_finite()
                            && u.is_finite()
                            && s.min_element() >= 0.0
                            && (s - u * (1.0 + 1e-9)).max_element() <= 1e-15;
                        if !ok {
                            t.failures.push(format!(
                                "case {case} point {i} {method:?}: shadowed {s} unshadowed {u} at x {x} n {n} v {v}"
                            ));
                        }
                        values.push((s, u));
                    }
                    Err(e) if e.is_undecidable() => {
                        t.gave_up += 1;
                        t.gave_up_per_triangle += usize::from(method == Method::PerTriangle);
                        if std::env::var("CENSUS_VERBOSE").is_ok() {
                            eprintln!(
                                "gave up: case {case} point {i} kind {} {method:?}: {e}",
                                i % 3
                            );
                        }
                    }
                    Err(e) => t.failures.push(format!(
                        "case {case} point {i} {method:?}: error {e:?} at x {x} n {n} v {v}"
                    )),
                }
            }
            if let [(a, u), (b, _)] = values[..]
                && (a - b).abs().max_element() > 1e-9 * u.max_element() + 1e-15
            {
                t.failures.push(format!(
                    "case {case} point {i}: Silhouette {a} vs PerTriangle {b} (unshadowed {u}) at x {x} n {n} v {v}"
                ));
            }
            // Monte Carlo on every eighth point that has a value, on the Lambertian lobe alone:
            // it integrates over the same visible region as the GGX lobe, and the reference's
            // light sampling (by solid angle) has bounded variance for it, while it cannot find
            // a glossy lobe of roughness 0.05 or less (its estimate and standard error both
            // miss the peak; an estimate at roughness 0.05 read 0.220 +- 0.0035, then
            // 0.232 +- 0.005, against 0.255).
            if i % 8 == 0
                && !values.is_empty()
                && let Ok(a) = base.shade(x, n, v, &lambert)
            {
                let seed = case * 1000 + i as u64;
                let e = mc.estimate(&base, x, n, v, &lambert, seed).unwrap();
                let agrees = |e: &arealight::shade::Estimate, c: usize| {
                    (a[c] - e.mean[c]).abs() <= 4.5 * e.std_error[c] + 1e-6 * (1.0 + a[c])
                };
                t.mc_checks += 1;
                if !(0..3).all(|c| agrees(&e, c)) {
                    t.mc_retested += 1;
                    let e2 = mc16.estimate(&base, x, n, v, &lambert, !seed).unwrap();
                    for c in (0..3).filter(|&c| !agrees(&e2, c)) {
                        t.failures.push(format!(
                            "case {case} point {i} ch {c}: analytic {} mc {} +- {}, then {} +- {} at x {x} n {n} v {v}",
                            a[c], e.mean[c], e.std_error[c], e2.mean[c], e2.std_error[c]
                        ));
                    }
                }
            }
        }
    }
    eprintln!(
        "census: {} queries, {} give-ups ({:.3}%; {} of them PerTriangle), {} Monte Carlo checks ({} re-estimated), {} failures",
        t.queries,
        t.gave_up,
        100.0 * t.gave_up as f64 / t.queries as f64,
        t.gave_up_per_triangle,
        t.mc_checks,
        t.mc_retested,
        t.failures.len()
    );
    assert!(
        t.failures.is_empty(),
        "{} failures:\n{}",
        t.failures.len(),
        t.failures.join("\n")
    );
    assert!(
        t.gave_up * 1000 < t.queries,
        "{} give-ups in {} queries",
        t.gave_up,
        t.queries
    );
}

/// Invalid arguments stay input faults in these scenes too.
#[test]
fn invalid_arguments_are_input_faults() {
    let mut rng = Rng::new(7);
    let c = DVec3::new(0.0, 0.0, 2.0);
    let body = random_light(&mut rng, c, 0);
    let occ = occluders(&mut rng, c, &body);
    let scene = Scene::new(vec![Light::new(body, DVec3::ONE).unwrap()], occ).unwrap();
    let m = Material::diffuse(DVec3::splat(0.5)).unwrap();
    let nan = DVec3::new(f64::NAN, 0.0, 1.0);
    for (x, n, v) in [
        (nan, DVec3::Z, DVec3::Z),
        (DVec3::ZERO, nan, DVec3::Z),
        (DVec3::ZERO, DVec3::Z, nan),
    ] {
        assert!(matches!(
            scene.shade(x, n, v, &m),
            Err(GeomError::NonFiniteArgument { .. })
        ));
    }
    assert!(matches!(
        scene.shade(DVec3::ZERO, DVec3::ZERO, DVec3::Z, &m),
        Err(GeomError::ZeroLengthArgument { .. })
    ));
}
