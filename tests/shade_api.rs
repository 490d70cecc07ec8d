//! The renderer-facing shading API: `f32` arguments at the boundary, batches (serial and on all
//! cores), two-sided planar lights, and `Scene::validate`.
//!
//! References: exact identities (an `f32` call equals the call with its exactly widened
//! arguments; a batch equals its points shaded one by one; a two-sided light equals the sum of
//! the light and its turned-around copy as one-sided lights), the closed-form irradiance of a
//! square on its axis, and the Monte Carlo reference with the LTC BRDF at 4 sigma (Bonferroni
//! over the checks below: 2 x 120 points x 3 channels = 720 checks, each failing by chance with
//! probability 6e-5, so about one false alarm in 23 runs of arbitrary inputs; the seeds are
//! fixed, and a point that fails is re-estimated with 16 times the samples on an independent
//! stream and must pass there, as in tests/shade_mc.rs).

mod support;

use arealight::glam::{DVec3, Vec3, Vec3A};
use arealight::internals::{DemoConfig, demo_scene};
use arealight::shade::{
    ConvexPolyhedron, Light, Material, MonteCarlo, RatioEstimator, ReferenceBrdf, Scene,
    SceneIssue, TriangleMesh,
};
use arealight::{GeomError, IntoDVec3};
use support::Rng;
use support::shade::{ground_point, view_above};

/// Random `f32` shading points of the demo scene's ground and their materials.
fn f32_points(n: usize, seed: u64) -> (Scene, Vec<(Vec3, Vec3, Vec3)>, Material) {
    let demo = demo_scene(DemoConfig::default()).unwrap();
    let mut rng = Rng::new(seed);
    let pts = (0..n)
        .map(|_| {
            let x = ground_point(&mut rng, demo.ground_half_size).as_vec3();
            let nrm = (DVec3::Z + 0.2 * rng.dir()).as_vec3();
            let v = view_above(&mut rng, nrm.as_dvec3().normalize(), 0.1).as_vec3();
            (x, nrm, v)
        })
        .collect();
    (demo.scene, pts, demo.ground)
}

#[test]
fn f32_arguments_give_the_f64_result_bit_for_bit() {
    let (scene, pts, m) = f32_points(200, 1);
    for (i, &(x, n, v)) in pts.iter().enumerate() {
        let want = scene.shade(x.as_dvec3(), n.as_dvec3(), v.as_dvec3(), &m);
        assert!(want.is_ok(), "point {i}: {want:?}");
        assert_eq!(scene.shade(x, n, v, &m), want, "Vec3, point {i}");
        let (xa, na, va) = (Vec3A::from(x), Vec3A::from(n), Vec3A::from(v));
        assert_eq!(scene.shade(xa, na, va, &m), want, "Vec3A, point {i}");
        assert_eq!(
            scene.shade(x.to_array(), n.to_array(), v.to_array(), &m),
            want,
            "[f32; 3]"
        );
        let (xd, nd, vd) = (x.as_dvec3(), n.as_dvec3(), v.as_dvec3());
        let nd_ref: &DVec3 = &nd;
        assert_eq!(
            scene.shade(xd.to_array(), nd_ref, vd, &m),
            want,
            "[f64; 3], &DVec3"
        );
        if i % 20 == 0 {
            assert_eq!(
                scene.shade_light(1, x, n, v, &m),
                scene.shade_light(1, xd, nd, vd, &m)
            );
            assert_eq!(
                scene.shade_per_light(x, n, v, &m),
                scene.shade_per_light(xd, nd, vd, &m)
            );
            assert_eq!(scene.shade_with(scene.visibility(), x, n, v, &m), want);
            let mc = MonteCarlo::new(16, ReferenceBrdf::True);
            assert_eq!(
                mc.estimate(&scene, x, n, v, &m, i as u64),
                mc.estimate(&scene, xd, nd, vd, &m, i as u64)
            );
        }
    }
    // Input faults still name the argument.
    let nan = Vec3::new(f32::NAN, 0.0, 0.0);
    assert!(matches!(
        scene.shade(Vec3::ZERO, nan, Vec3::Z, &m),
        Err(GeomError::NonFiniteArgument { .. })
    ));
    assert_eq!(
        [1.5f32, -2.0, 1e-8].into_dvec3(),
        DVec3::new(1.5, -2.0, f64::from(1e-8f32))
    );
}

/// Points, normals and views of a batch with per-point materials, including invalid queries.
fn batch(n: usize, seed: u64) -> (Scene, Vec<Vec3>, Vec<Vec3>, Vec<Vec3>, Vec<Material>) {
    let (scene, pts, ground) = f32_points(n, seed);
    let other = Material::new(DVec3::new(0.2, 0.5, 0.7), DVec3::splat(0.5), 0.2).unwrap();
    let mut xs: Vec<Vec3> = pts.iter().map(|p| p.0).collect();
    let ns: Vec<Vec3> = pts.iter().map(|p| p.1).collect();
    let vs: Vec<Vec3> = pts.iter().map(|p| p.2).collect();
    let ms = (0..n)
        .map(|i| if i % 3 == 0 { other } else { ground })
        .collect();
    // Two bad queries: each fails alone.
    xs[7] = Vec3::new(f32::NAN, 0.0, 0.0);
    xs[n - 2] = Vec3::splat(f32::INFINITY);
    (scene, xs, ns, vs, ms)
}

#[test]
fn a_batch_is_its_points_shaded_one_by_one() {
    let (scene, xs, ns, vs, ms) = batch(300, 2);
    let got = scene.shade_batch(&xs, &ns, &vs, &ms).unwrap();
    assert_eq!(got.len(), xs.len());
    for i in 0..xs.len() {
        assert_eq!(
            got[i],
            scene.shade(xs[i], ns[i], vs[i], &ms[i]),
            "point {i}"
        );
    }
    let bad_point = Err(GeomError::NonFiniteArgument {
        what: "shading point",
    });
    assert_eq!(got[7], bad_point);
    assert_eq!(got[xs.len() - 2], bad_point);
    assert_eq!(got.iter().filter(|r| r.is_err()).count(), 2);
    // One material for all.
    let one = scene.shade_batch(&xs, &ns, &vs, &ms[1..2]).unwrap();
    for i in 0..xs.len() {
        assert_eq!(
            one[i],
            scene.shade(xs[i], ns[i], vs[i], &ms[1]),
            "point {i}"
        );
    }
    // Lengths that do not match shade nothing.
    for (n, v, m) in [
        (&ns[1..], &vs[..], &ms[..]),
        (&ns[..], &vs[..5], &ms[..]),
        (&ns[..], &vs[..], &ms[..2]),
        (&ns[..], &vs[..], &ms[..0]),
    ] {
        assert!(matches!(
            scene.shade_batch(&xs, n, v, m),
            Err(GeomError::OutOfRange { .. })
        ));
    }
    assert_eq!(
        scene
            .shade_batch::<Vec3, Vec3, Vec3>(&[], &[], &[], &ms[..1])
            .unwrap(),
        vec![]
    );
}

#[cfg(feature = "rayon")]
#[test]
fn the_parallel_batch_equals_the_serial_one_bit_for_bit() {
    let (scene, xs, ns, vs, ms) = batch(1500, 3);
    let serial = scene.shade_batch(&xs, &ns, &vs, &ms).unwrap();
    // On rayon's global pool and on pools of 1 and 3 threads: the same results in the same order.
    assert_eq!(scene.par_shade_batch(&xs, &ns, &vs, &ms).unwrap(), serial);
    for threads in [1, 3] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        let par = pool.install(|| scene.par_shade_batch(&xs, &ns, &vs, &ms).unwrap());
        assert_eq!(par, serial, "{threads} threads");
    }
    let one = scene.par_shade_batch(&xs, &ns, &vs, &ms[2..3]).unwrap();
    assert_eq!(one, scene.shade_batch(&xs, &ns, &vs, &ms[2..3]).unwrap());
    assert!(matches!(
        scene.par_shade_batch(&xs, &ns[1..], &vs, &ms),
        Err(GeomError::OutOfRange { .. })
    ));
}

/// A 1 x 1 quad at height 2 facing down, and the same turned around.
fn quad_down() -> TriangleMesh {
    TriangleMesh::quad(DVec3::new(0.0, 0.0, 2.0), DVec3::Y * 0.5, DVec3::X * 0.5).unwrap()
}

/// `(1 / pi) x` the irradiance of a square of half side `a` at distance `d` on its axis.
fn square_on_axis(a: f64, d: f64) -> f64 {
    let s = a / (a * a + d * d).sqrt();
    4.0 / std::f64::consts::PI * s * s.atan()
}

#[test]
fn a_two_sided_light_lights_both_sides_in_closed_form() {
    let white = Material::diffuse(DVec3::ONE).unwrap();
    let rgb = DVec3::new(1.0, 2.0, 3.0);
    let one = Scene::new(vec![Light::new(quad_down(), rgb).unwrap()], vec![]).unwrap();
    let two = Scene::new(vec![Light::two_sided(quad_down(), rgb).unwrap()], vec![]).unwrap();
    assert!(two.lights()[0].is_two_sided() && !one.lights()[0].is_two_sided());
    let below = square_on_axis(0.5, 2.0);
    let above = square_on_axis(0.5, 1.5);
    for scene in [&one, &two] {
        let x = scene
            .shade(DVec3::ZERO, DVec3::Z, DVec3::Z, &white)
            .unwrap();
        assert!((x - rgb * below).abs().max_element() < 1e-12, "{x}");
    }
    // From 1.5 above the light, looking down at it.
    let p = DVec3::new(0.0, 0.0, 3.5);
    assert_eq!(
        one.shade(p, -DVec3::Z, -DVec3::Z, &white).unwrap(),
        DVec3::ZERO
    );
    let x = two.shade(p, -DVec3::Z, -DVec3::Z, &white).unwrap();
    assert!((x - rgb * above).abs().max_element() < 1e-12, "{x}");
    // In the light's plane: edge-on from either side.
    let q = DVec3::new(3.0, 0.0, 2.0);
    assert_eq!(
        two.shade(q, DVec3::NEG_X, DVec3::NEG_X, &white).unwrap(),
        DVec3::ZERO
    );
    // Only planar meshes can be two-sided.
    let cube = ConvexPolyhedron::cuboid(DVec3::ZERO, DVec3::ONE).unwrap();
    assert!(matches!(
        Light::two_sided(cube, rgb),
        Err(GeomError::Degenerate(_))
    ));
    let bent = TriangleMesh::new(
        vec![DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::new(1.0, 1.0, 0.5)],
        vec![[0, 1, 2], [1, 3, 2]],
    )
    .unwrap();
    assert!(matches!(
        Light::two_sided(bent, rgb),
        Err(GeomError::Degenerate(_))
    ));
    assert!(matches!(
        Light::two_sided(quad_down(), DVec3::splat(f64::NAN)),
        Err(GeomError::OutOfRange { .. })
    ));
}

/// A two-sided light among occluders and other lights on both of its sides, and the points
/// shaded: on the floor under it and on a ceiling above it, facing it.
fn two_sided_scene(two_sided: bool) -> (Vec<Light>, Vec<arealight::shade::Body>) {
    // An L-shaped planar light of four triangles at height 2.
    let l_shape = TriangleMesh::new(
        vec![
            DVec3::new(-1.0, -1.0, 2.0),
            DVec3::new(1.0, -1.0, 2.0),
            DVec3::new(1.0, -0.2, 2.0),
            DVec3::new(-0.2, -0.2, 2.0),
            DVec3::new(-0.2, 1.0, 2.0),
            DVec3::new(-1.0, 1.0, 2.0),
        ],
        // Counter-clockwise seen from below: facing down.
        vec![[0, 3, 1], [1, 3, 2], [0, 5, 3], [3, 5, 4]],
    )
    .unwrap();
    assert!(l_shape.is_planar() && l_shape.triangle_normal(0).z < 0.0);
    let main = if two_sided {
        Light::two_sided(l_shape, DVec3::new(3.0, 2.0, 1.0)).unwrap()
    } else {
        Light::new(l_shape, DVec3::new(3.0, 2.0, 1.0)).unwrap()
    };
    // A small second light below the main one, which hides part of it from the floor.
    let small =
        TriangleMesh::quad(DVec3::new(0.5, 0.4, 1.3), DVec3::X * 0.2, DVec3::Y * 0.2).unwrap();
    let lights = vec![
        main,
        Light::new(small.flipped(), DVec3::splat(0.5)).unwrap(),
    ];
    let occluders = vec![
        ConvexPolyhedron::cuboid(DVec3::new(-0.3, 0.1, 1.0), DVec3::splat(0.25))
            .unwrap()
            .into(),
        ConvexPolyhedron::icosphere(DVec3::new(0.2, -0.3, 2.8), 0.3, 1)
            .unwrap()
            .into(),
    ];
    (lights, occluders)
}

/// Shading points on the floor (z = 0, facing up) and on a ceiling (z = 4, facing down).
fn both_sides(n: usize, seed: u64) -> Vec<(DVec3, DVec3, DVec3)> {
    let mut rng = Rng::new(seed);
    (0..n)
        .map(|i| {
            let (z, nrm) = if i % 2 == 0 {
                (0.0, DVec3::Z)
            } else {
                (4.0, -DVec3::Z)
            };
            let x = ground_point(&mut rng, 2.0) + DVec3::Z * z;
            (x, nrm, view_above(&mut rng, nrm, 0.2))
        })
        .collect()
}

#[test]
fn a_two_sided_light_is_the_light_plus_its_turned_around_copy() {
    let (lights, occ) = two_sided_scene(true);
    let two = Scene::new(lights.clone(), occ.clone()).unwrap();
    let (front, _) = two_sided_scene(false);
    let mut back = front.clone();
    back[0] = Light::new(front[0].shape().mesh().flipped(), front[0].radiance()).unwrap();
    let front = Scene::new(front, occ.clone()).unwrap();
    let back = Scene::new(back, occ).unwrap();
    let glossy = Material::new(DVec3::splat(0.6), DVec3::splat(0.3), 0.3).unwrap();
    let (mut lit_above, mut lit_below) = (0, 0);
    for (i, (x, n, v)) in both_sides(400, 4).into_iter().enumerate() {
        let t = two.shade_light(0, x, n, v, &glossy).unwrap();
        let f = front.shade_light(0, x, n, v, &glossy).unwrap();
        let b = back.shade_light(0, x, n, v, &glossy).unwrap();
        // One of the two is zero: the point is on one side of the light's plane.
        assert!(f == DVec3::ZERO || b == DVec3::ZERO, "point {i}: {f} {b}");
        assert_eq!(t, f + b, "point {i}");
        lit_above += usize::from(b.x > 0.0);
        lit_below += usize::from(f.x > 0.0);
        // The ratio estimator's analytic factor is the unshadowed value on both sides.
        if i % 20 < 2 {
            let r = RatioEstimator::new(16, ReferenceBrdf::Ltc)
                .estimate_lights(&two, x, n, v, &glossy, i as u64)
                .unwrap();
            let u = two.shade_per_light(x, n, v, &glossy).unwrap()[0].unshadowed();
            assert!(
                (r[0].unshadowed - u).abs().max_element() <= 1e-12 * (1.0 + u.max_element()),
                "point {i}: {} {u}",
                r[0].unshadowed
            );
        }
        // The other light and the per-light split see the same two-sided light.
        let total = two.shade(x, n, v, &glossy).unwrap();
        let parts = two.shade_per_light(x, n, v, &glossy).unwrap();
        let sum = parts[0].shadowed() + parts[1].shadowed();
        assert!((total - sum).abs().max_element() <= 1e-12 * (1.0 + total.max_element()));
        assert!((parts[0].shadowed() - t).abs().max_element() <= 1e-12 * (1.0 + t.max_element()));
    }
    // Both sides were really lit, so the identity was tested on both.
    assert!(
        lit_above > 100 && lit_below > 100,
        "{lit_above} {lit_below}"
    );
}

#[test]
fn a_two_sided_light_matches_monte_carlo_on_both_sides() {
    let (lights, occ) = two_sided_scene(true);
    let scene = Scene::new(lights, occ).unwrap();
    let m = Material::new(DVec3::splat(0.6), DVec3::splat(0.3), 0.45).unwrap();
    let mc = MonteCarlo::new(1024, ReferenceBrdf::Ltc);
    let mc16 = MonteCarlo::new(16 * 1024, ReferenceBrdf::Ltc);
    let mut failures = Vec::new();
    let (mut lit_above, mut lit_below) = (0, 0);
    for (i, (x, n, v)) in both_sides(240, 5).into_iter().enumerate() {
        let a = scene.shade(x, n, v, &m).unwrap();
        let e = mc.estimate(&scene, x, n, v, &m, 77 + i as u64).unwrap();
        if a.x > 1e-3 {
            if n.z > 0.0 {
                lit_below += 1
            } else {
                lit_above += 1
            }
        }
        for c in 0..3 {
            if (a[c] - e.mean[c]).abs() > 4.0 * e.std_error[c] + 1e-6 {
                let e2 = mc16
                    .estimate(&scene, x, n, v, &m, !(77 + i as u64))
                    .unwrap();
                if (a[c] - e2.mean[c]).abs() > 4.0 * e2.std_error[c] + 1e-6 {
                    failures.push(format!(
                        "point {i} ch {c}: {} vs {} +- {}",
                        a[c], e2.mean[c], e2.std_error[c]
                    ));
                }
            }
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
    assert!(lit_above > 60 && lit_below > 60, "{lit_above} {lit_below}");
}

#[test]
fn validate_reports_a_light_facing_away() {
    let up = quad_down().flipped();
    let floor = [DVec3::new(-3.0, -3.0, 0.0), DVec3::new(3.0, 3.0, 0.0)];
    let away = Scene::new(vec![Light::new(up.clone(), DVec3::ONE).unwrap()], vec![]).unwrap();
    let report = away.validate(&floor);
    assert_eq!(report.issues, [SceneIssue::LightFacesAway { light: 0 }]);
    assert!(!report.is_clean() && report.to_string().contains("light 0"));
    // The same light over an occluder's vertices only (no receivers): still facing away.
    let cube: arealight::shade::Body =
        ConvexPolyhedron::cuboid(DVec3::new(0.0, 0.0, 0.5), DVec3::splat(0.5))
            .unwrap()
            .into();
    let with_cube = Scene::new(
        vec![Light::new(up.clone(), DVec3::ONE).unwrap()],
        vec![cube.clone()],
    )
    .unwrap();
    assert_eq!(
        with_cube.validate::<DVec3>(&[]).issues,
        [SceneIssue::LightFacesAway { light: 0 }]
    );
    // Facing the floor, or two-sided: clean.
    let down = Scene::new(
        vec![Light::new(quad_down(), DVec3::ONE).unwrap()],
        vec![cube],
    )
    .unwrap();
    assert!(down.validate(&floor).is_clean());
    let two = Scene::new(
        vec![Light::two_sided(up.clone(), DVec3::ONE).unwrap()],
        vec![],
    )
    .unwrap();
    assert!(two.validate(&floor).is_clean());
    // Nothing to reason about: not reported.
    assert!(away.validate::<DVec3>(&[]).is_clean());
    // A point above the light sees its front: one such point is enough.
    assert!(
        away.validate(&[floor[0], DVec3::new(0.0, 0.0, 5.0)])
            .is_clean()
    );
    // f32 receivers are accepted as everywhere else.
    assert_eq!(away.validate(&[Vec3::ZERO]).issues.len(), 1);
    // The demo scene has no issue.
    let demo = demo_scene(DemoConfig::default()).unwrap();
    assert!(demo.scene.validate(&floor).is_clean());
}

#[test]
fn overlapping_light_triangles_are_rejected_and_fans_are_clean() {
    let q = quad_down();
    let tri = |m: &TriangleMesh, extra: Vec<[u32; 3]>| {
        let mut t = m.triangles().to_vec();
        t.extend(extra);
        TriangleMesh::new(m.vertices().to_vec(), t).unwrap()
    };
    let floor = [DVec3::ZERO];
    // A duplicated triangle, and one that overlaps both halves of the quad: a planar light's
    // triangles are summed, so both would emit twice; neither one- nor two-sided lights take
    // them (the check of Light::new), so Scene::validate never meets them.
    let dup = tri(&q, vec![q.triangles()[0]]);
    // The quad is [0, 1, 2] + [0, 2, 3]; [0, 1, 3] is the half across the other diagonal.
    let across = tri(&q, vec![[0, 1, 3]]);
    for m in [dup, across] {
        assert!(m.is_planar());
        assert!(matches!(
            Light::new(m.clone(), DVec3::ONE),
            Err(GeomError::OverlappingLightTriangles { .. })
        ));
        assert!(matches!(
            Light::two_sided(m, DVec3::ONE),
            Err(GeomError::OverlappingLightTriangles { .. })
        ));
    }
    // A fan of triangles that only share edges and a vertex: clean.
    let fan = TriangleMesh::new(
        (0..6)
            .map(|k| {
                let t = std::f64::consts::TAU * k as f64 / 6.0;
                DVec3::new(t.cos(), -t.sin(), 2.0)
            })
            .chain([DVec3::new(0.0, 0.0, 2.0)])
            .collect(),
        (0..6u32).map(|k| [6, k, (k + 1) % 6]).collect(),
    )
    .unwrap();
    assert!(fan.is_planar());
    let s = Scene::new(vec![Light::new(fan, DVec3::ONE).unwrap()], vec![]).unwrap();
    assert!(s.validate(&floor).is_clean(), "{}", s.validate(&floor));
}

#[test]
fn validate_reports_overlapping_coplanar_lights() {
    let at = |x: f64, z: f64| {
        TriangleMesh::quad(DVec3::new(x, 0.0, z), DVec3::Y * 0.5, DVec3::X * 0.5).unwrap()
    };
    let floor = [DVec3::ZERO];
    let scene = |a: TriangleMesh, b: TriangleMesh| {
        Scene::new(
            vec![
                Light::new(a, DVec3::ONE).unwrap(),
                Light::new(b, DVec3::ONE).unwrap(),
            ],
            vec![],
        )
        .unwrap()
    };
    // Overlapping by half, facing the same way.
    let s = scene(at(0.0, 2.0), at(0.5, 2.0));
    assert_eq!(
        s.validate(&floor).issues,
        [SceneIssue::OverlappingLights { a: 0, b: 1 }]
    );
    // Side by side (sharing an edge), in parallel planes, or facing opposite ways: no overlap
    // (the light facing up is reported as facing away: the other light's vertices are in its
    // plane and the floor is behind it).
    assert!(
        scene(at(0.0, 2.0), at(1.0, 2.0))
            .validate(&floor)
            .is_clean()
    );
    assert!(
        scene(at(0.0, 2.0), at(0.5, 2.5))
            .validate(&floor)
            .is_clean()
    );
    let opposite = scene(at(0.0, 2.0), at(0.5, 2.0).flipped()).validate(&floor);
    assert_eq!(opposite.issues, [SceneIssue::LightFacesAway { light: 1 }]);
}
