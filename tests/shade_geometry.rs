//! Meshes, hulls, silhouettes, culling and non-convex shapes (per-triangle method), with fixed
//! seeds. Analytic results are checked against the Monte Carlo reference with the LTC BRDF within
//! `4 sigma_hat + 1e-6` (see tests/shade_mc.rs for why the floor), or against exact identities.

use arealight::GeomError;
use arealight::glam::DVec3;
use arealight::internals::{TriangleRole, convex_silhouette, may_occlude, triangle_polygon};
use arealight::shade::{
    Body, ConvexPolyhedron, Light, LightSampling, Material, Method, MonteCarlo, ReferenceBrdf,
    Scene, ShadingFrame, TriangleMesh,
};
use arealight::solid::{BoundingSphere, Side, face_side};
use support::Rng;
use support::shade::ground_point;

mod support;

#[test]
fn hulls_of_random_clouds_are_convex_and_silhouettes_match_per_triangle() {
    let mut rng = Rng::new(304);
    for case in 0..40 {
        let n = 4 + rng.below(60);
        let scale = DVec3::new(0.2 + rng.f64(), 0.2 + rng.f64(), 0.2 + rng.f64());
        let pts: Vec<DVec3> = (0..n)
            .map(|_| rng.dir() * rng.f64().cbrt() * scale)
            .collect();
        let hull = ConvexPolyhedron::hull(&pts).unwrap();
        let mesh = hull.mesh();
        // Every input point is on or behind every face.
        for t in 0..mesh.triangle_count() {
            let [a, ..] = mesh.triangle(t);
            let nn = mesh.triangle_normal(t);
            for p in &pts {
                assert!(
                    nn.dot(*p - a) <= 1e-12,
                    "case {case}: point in front of face {t}"
                );
            }
        }
        // Euler's formula for a closed genus-0 surface.
        let (v, e, f) = (
            hull.vertices().len() as i64,
            hull.edges().len() as i64,
            mesh.triangle_count() as i64,
        );
        assert_eq!(v - e + f, 2, "case {case}");
        // From outside, the silhouette covers what the front triangles cover.
        for _ in 0..5 {
            let x = rng.dir() * (2.0 + 3.0 * rng.f64());
            let frame = ShadingFrame::new(x, rng.dir(), rng.dir()).unwrap();
            let sil = convex_silhouette(&hull, &frame).unwrap();
            let sum: f64 = (0..mesh.triangle_count())
                .filter_map(|t| triangle_polygon(mesh, t, &frame, TriangleRole::Emitter).unwrap())
                .map(|p| p.solid_angle())
                .sum();
            assert!(
                (sil.solid_angle() - sum).abs() <= 1e-9,
                "case {case}: {} vs {sum}",
                sil.solid_angle()
            );
            let centroid = pts.iter().copied().sum::<DVec3>() / n as f64;
            assert!(sil.contains(frame.to_local(centroid)), "case {case}");
        }
    }
}

#[test]
fn culling_is_conservative() {
    // Whenever a point of the occluder's sphere, above the horizon, lies in front of a point of
    // the light's sphere along the same ray from x, the occluder must be kept.
    let mut rng = Rng::new(506);
    let mut kept_needed = 0;
    for _ in 0..20_000 {
        let x = rng.dir() * rng.f64() * 2.0;
        let n = rng.dir();
        let light = BoundingSphere {
            center: rng.dir() * 4.0 * rng.f64(),
            radius: 0.2 + rng.f64(),
        };
        let occ = BoundingSphere {
            center: rng.dir() * 4.0 * rng.f64(),
            radius: 0.1 + rng.f64(),
        };
        let keep = may_occlude(x, n, light, occ);
        for _ in 0..8 {
            let p = occ.center + rng.dir() * occ.radius * rng.f64().cbrt();
            let d = (p - x).normalize();
            if d.dot(n) <= 0.0 {
                continue;
            }
            // Far intersection of the ray with the light's sphere.
            let oc = light.center - x;
            let along = oc.dot(d);
            let h2 = light.radius * light.radius - (oc.length_squared() - along * along);
            if h2 < 0.0 {
                continue;
            }
            let t_far = along + h2.sqrt();
            if t_far > (p - x).length() {
                kept_needed += 1;
                assert!(keep, "x {x} n {n} light {light:?} occ {occ:?}");
            }
        }
    }
    assert!(kept_needed > 1000);
}

fn box_mesh(c: DVec3, h: DVec3) -> TriangleMesh {
    ConvexPolyhedron::cuboid(c, h).unwrap().mesh().clone()
}

/// Analytic (per-triangle method) against Monte Carlo with the LTC BRDF on ground points.
fn check_scene(scene: &Scene, seed: u64, points: usize) -> (usize, usize) {
    let mut rng = Rng::new(seed * 100 + 7);
    let m = Material::new(DVec3::new(0.6, 0.5, 0.4), DVec3::splat(0.04), 0.45).unwrap();
    // Face sampling: independent of the light regions under test.
    let mc = MonteCarlo::new(4096, ReferenceBrdf::Ltc).with_sampling(LightSampling::Faces);
    let (mut ok, mut errors) = (0, 0);
    for i in 0..points {
        let x = ground_point(&mut rng, 2.0);
        let v = DVec3::new(rng.f64() - 0.5, rng.f64() - 0.5, 0.5 + rng.f64());
        let a = match scene.shade(x, DVec3::Z, v, &m) {
            Ok(a) => a,
            Err(e) => {
                eprintln!("point {i}: {e}");
                errors += 1;
                continue;
            }
        };
        let e = mc
            .estimate(scene, x, DVec3::Z, v, &m, seed * 7919 + i as u64)
            .unwrap();
        for c in 0..3 {
            assert!(
                (a[c] - e.mean[c]).abs() <= 4.0 * e.std_error[c] + 1e-6,
                "point {i} ch {c}: analytic {} mc {} +- {}",
                a[c],
                e.mean[c],
                e.std_error[c]
            );
        }
        ok += 1;
    }
    (ok, errors)
}

#[test]
fn non_convex_light_is_the_union_of_its_front_faces() {
    // Two boxes as one mesh: from the ground, the upper box is partly hidden behind the lower one,
    // so summing the front faces would count the overlap twice.
    let mesh = box_mesh(DVec3::new(0.0, 0.0, 2.5), DVec3::new(0.6, 0.4, 0.3))
        .merged(&box_mesh(
            DVec3::new(0.3, 0.2, 3.4),
            DVec3::new(0.5, 0.5, 0.3),
        ))
        .unwrap();
    // Seen from below the pair, the front faces overlap: their summed solid angles exceed the
    // union's, so a sum would be wrong and the Monte Carlo check below would tell.
    let frame = ShadingFrame::new(DVec3::new(0.2, 0.1, 0.0), DVec3::Z, DVec3::Z).unwrap();
    let sum: f64 = (0..mesh.triangle_count())
        .filter_map(|t| triangle_polygon(&mesh, t, &frame, TriangleRole::Emitter).unwrap())
        .map(|p| p.solid_angle())
        .sum();
    let scene = Scene::new(
        vec![Light::new(mesh, DVec3::new(1.0, 2.0, 3.0)).unwrap()],
        vec![],
    )
    .unwrap();
    let region = scene.light_region(0, &frame).unwrap();
    assert_eq!(region.len(), 1);
    assert!(
        sum > 1.2 * region[0].solid_angle(),
        "{sum} vs {}",
        region[0].solid_angle()
    );
    let (ok, errors) = check_scene(&scene, 11, 60);
    // Unions of many edge-sharing spherical triangles are where the sphere layer's set
    // operations are most exposed to rounding; an error at any point (printed) fails the test.
    assert!(
        errors == 0 && ok == 60,
        "{ok} points checked, {errors} errors"
    );
}

#[test]
fn non_convex_occluder_subtracts_all_its_triangles() {
    // An L-shaped occluder (two boxes as one mesh) under a quad light.
    let quad = TriangleMesh::quad(
        DVec3::new(0.0, 0.0, 3.0),
        DVec3::new(0.0, 0.8, 0.0),
        DVec3::new(0.8, 0.0, 0.0),
    )
    .unwrap();
    let l_shape = box_mesh(DVec3::new(0.0, 0.0, 1.0), DVec3::new(0.6, 0.15, 0.15))
        .merged(&box_mesh(
            DVec3::new(0.45, 0.4, 1.0),
            DVec3::new(0.15, 0.25, 0.15),
        ))
        .unwrap();
    let scene = Scene::new(
        vec![Light::new(quad, DVec3::ONE).unwrap()],
        vec![Body::Mesh(l_shape)],
    )
    .unwrap();
    let (ok, errors) = check_scene(&scene, 13, 60);
    // As above: an error at any point (printed) fails the test.
    assert!(
        errors == 0 && ok == 60,
        "{ok} points checked, {errors} errors"
    );
    // The same scene with the silhouette method uses the per-triangle path for meshes anyway.
    assert_eq!(
        scene.clone().with_method(Method::PerTriangle).method(),
        Method::PerTriangle
    );
}

#[test]
fn invalid_geometry_is_an_error() {
    let v = vec![DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::Z];
    assert!(matches!(
        TriangleMesh::new(
            vec![DVec3::ZERO, DVec3::X, DVec3::INFINITY],
            vec![[0, 1, 2]]
        ),
        Err(GeomError::NonFinite { .. })
    ));
    assert!(matches!(
        TriangleMesh::new(v.clone(), vec![[0, 1, 9]]),
        Err(GeomError::InvalidIndex { .. })
    ));
    assert!(matches!(
        TriangleMesh::new(vec![DVec3::ZERO, DVec3::X, DVec3::X * 2.0], vec![[0, 1, 2]]),
        Err(GeomError::DegenerateTriangle { .. })
    ));
    assert_eq!(
        TriangleMesh::new(v.clone(), vec![]),
        Err(GeomError::TooFewVertices { ring: 0, count: 0 })
    );
    assert_eq!(
        TriangleMesh::quad(DVec3::ZERO, DVec3::X, DVec3::X),
        Err(GeomError::DegenerateTriangle { triangle: 0 })
    );
    assert_eq!(
        TriangleMesh::quad(DVec3::ZERO, DVec3::X, DVec3::new(0.0, f64::NAN, 0.0)),
        Err(GeomError::NonFiniteArgument {
            what: "quad half-edge v"
        })
    );
    // Coplanar and too few points have no hull.
    assert!(matches!(
        ConvexPolyhedron::hull(&[DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::new(1.0, 1.0, 0.0)]),
        Err(GeomError::Degenerate(_))
    ));
    assert_eq!(
        ConvexPolyhedron::hull(&v[..3]),
        Err(GeomError::TooFewVertices { ring: 0, count: 3 })
    );
    assert_eq!(
        ConvexPolyhedron::hull(&[DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::NAN]),
        Err(GeomError::NonFinite { ring: 0, vertex: 3 })
    );
    // A non-convex closed mesh is not a ConvexPolyhedron.
    let l_shape = box_mesh(DVec3::ZERO, DVec3::ONE)
        .merged(&box_mesh(DVec3::new(3.0, 0.0, 0.0), DVec3::ONE))
        .unwrap();
    assert!(matches!(
        ConvexPolyhedron::from_mesh(&l_shape),
        Err(GeomError::NotConvex { .. })
    ));
    let out_of_range = |r: Result<ConvexPolyhedron, GeomError>, name: &str| {
        assert!(
            matches!(r, Err(GeomError::OutOfRange { what, .. }) if what == name),
            "{name}: {r:?}"
        );
    };
    assert_eq!(
        ConvexPolyhedron::frustum(DVec3::ZERO, DVec3::ZERO, 1.0, 1.0, 10),
        Err(GeomError::ZeroLengthArgument {
            what: "frustum axis"
        })
    );
    out_of_range(
        ConvexPolyhedron::frustum(DVec3::ZERO, DVec3::Z, -1.0, 1.0, 10),
        "frustum radius (non-negative)",
    );
    out_of_range(
        ConvexPolyhedron::frustum(DVec3::ZERO, DVec3::Z, 1.0, 1.0, 2),
        "frustum segments (at least 3)",
    );
    out_of_range(
        ConvexPolyhedron::icosphere(DVec3::ZERO, 0.0, 1),
        "icosphere radius (positive)",
    );
    out_of_range(
        ConvexPolyhedron::icosphere(DVec3::ZERO, -1.0, 1),
        "icosphere radius (positive)",
    );
    out_of_range(
        ConvexPolyhedron::icosphere(DVec3::ZERO, 1.0, 9),
        "icosphere subdivisions",
    );
    assert_eq!(
        ConvexPolyhedron::cuboid(DVec3::new(0.0, f64::INFINITY, 0.0), DVec3::ONE),
        Err(GeomError::NonFiniteArgument {
            what: "cuboid center"
        })
    );
    for rgb in [DVec3::new(-1.0, 0.0, 0.0), DVec3::splat(f64::NAN)] {
        let r = Light::new(Body::Mesh(box_mesh(DVec3::ZERO, DVec3::ONE)), rgb);
        assert!(
            matches!(
                r,
                Err(GeomError::OutOfRange {
                    what: "light radiance (non-negative, finite)",
                    ..
                })
            ),
            "{r:?}"
        );
    }
    assert!(matches!(
        Material::new(DVec3::ONE, DVec3::ZERO, f64::NAN),
        Err(GeomError::OutOfRange {
            what: "material roughness",
            ..
        })
    ));
    assert!(matches!(
        Material::new(DVec3::splat(1.5), DVec3::ZERO, 0.5),
        Err(GeomError::OutOfRange {
            what: "material albedo",
            ..
        })
    ));
    assert_eq!(
        ShadingFrame::new(DVec3::ZERO, DVec3::Z * 1e-320, DVec3::Z),
        Err(GeomError::ZeroLengthArgument {
            what: "surface normal"
        })
    );
}

#[test]
fn invalid_shading_arguments_are_named_input_faults() {
    // A renderer must tell a bad query (skip or fix it) from a give-up (fall back): every bad
    // point, normal or view is an input fault naming the argument, never "vertex 0/1/2" and never
    // `Undecidable`; scaled normals and views, down to the smallest normal magnitudes and up to
    // the largest finite ones, shade like unit ones.
    let quad = TriangleMesh::quad(DVec3::Z * 2.0, DVec3::Y, DVec3::X).unwrap();
    let scene = Scene::new(vec![Light::new(quad, DVec3::ONE).unwrap()], vec![]).unwrap();
    let m = Material::new(DVec3::splat(0.5), DVec3::splat(0.04), 0.4).unwrap();
    let (x, n, v) = (
        DVec3::new(0.1, 0.2, 0.0),
        DVec3::Z,
        DVec3::new(0.3, 0.0, 1.0),
    );
    let bad = [f64::NAN, f64::INFINITY, f64::NEG_INFINITY];
    for b in bad {
        for k in 0..3 {
            let mut e = DVec3::ZERO;
            e[k] = b;
            let cases = [
                (x + e, n, v, "shading point"),
                (x, n + e, v, "surface normal"),
                (x, n, v + e, "view direction"),
            ];
            for (xx, nn, vv, what) in cases {
                let r = scene.shade(xx, nn, vv, &m);
                assert_eq!(r, Err(GeomError::NonFiniteArgument { what }), "{what} {b}");
                assert!(!r.unwrap_err().is_undecidable());
                assert_eq!(
                    ShadingFrame::new(xx, nn, vv).map(|_| ()),
                    Err(GeomError::NonFiniteArgument { what })
                );
            }
        }
    }
    for zero in [
        DVec3::ZERO,
        DVec3::Z * 1e-320,
        DVec3::new(0.0, -0.0, 4e-324),
    ] {
        assert_eq!(
            scene.shade(x, zero, v, &m),
            Err(GeomError::ZeroLengthArgument {
                what: "surface normal"
            })
        );
        assert_eq!(
            scene.shade(x, n, zero, &m),
            Err(GeomError::ZeroLengthArgument {
                what: "view direction"
            })
        );
    }
    assert!(matches!(
        scene.shade(DVec3::new(0.0, 2e100, 0.0), n, v, &m),
        Err(GeomError::OutOfRange {
            what: "shading point coordinate",
            ..
        })
    ));
    let unit = scene.shade(x, n, v, &m).unwrap();
    for s in [1e-300, 1e-30, 7.0, 1e30, 1e300] {
        let scaled = scene.shade(x, n * s, v * s, &m).unwrap();
        assert!(
            (scaled - unit).abs().max_element() <= 1e-15 * unit.max_element(),
            "scale {s}: {scaled} vs {unit}"
        );
    }
}

#[test]
fn scene_is_send_and_sync() {
    fn send_sync<T: Send + Sync>() {}
    send_sync::<Scene>();
    send_sync::<ConvexPolyhedron>();
}

#[test]
fn bad_light_index_is_an_error() {
    let quad = TriangleMesh::quad(DVec3::Z * 2.0, DVec3::Y, DVec3::X).unwrap();
    let scene = Scene::new(vec![Light::new(quad, DVec3::ONE).unwrap()], vec![]).unwrap();
    let f = ShadingFrame::new(DVec3::ZERO, DVec3::Z, DVec3::Z).unwrap();
    let m = Material::diffuse(DVec3::ONE).unwrap();
    let light_index = GeomError::OutOfRange {
        what: "light index",
        value: 1.0,
        limit: 1.0,
    };
    assert_eq!(scene.light_region(1, &f), Err(light_index.clone()));
    assert!(matches!(
        scene.visible_region(7, &f),
        Err(GeomError::OutOfRange {
            what: "light index",
            ..
        })
    ));
    assert_eq!(
        scene.shade_light(1, DVec3::ZERO, DVec3::Z, DVec3::Z, &m),
        Err(light_index)
    );
    assert_eq!(scene.occluders_between(3, &f).count(), 0);
    assert!(
        scene
            .shade_light(0, DVec3::ZERO, DVec3::Z, DVec3::Z, &m)
            .unwrap()
            .x
            > 0.0
    );
}

#[test]
fn points_in_face_planes_see_the_same_region_both_ways() {
    // Shading points in the plane of a face (outside the polyhedron): that face is edge-on. The
    // silhouette path treats it as back-facing; the per-triangle path skips it. Both must cover
    // the same solid angle. Also points on the lines through edges, where two faces are edge-on.
    // A case counts as checked only when the point really is outside the polyhedron, really sees
    // the face edge-on (by the facing predicate both paths use) and sees something at all; each
    // family of points must give more than 100 such cases.
    let mut rng = Rng::new(1708);
    let shapes = [
        ConvexPolyhedron::cuboid(DVec3::new(0.1, -0.2, 0.5), DVec3::new(0.5, 0.3, 0.5)).unwrap(),
        ConvexPolyhedron::icosphere(DVec3::ZERO, 0.7, 1).unwrap(),
        ConvexPolyhedron::frustum(DVec3::ZERO, DVec3::new(0.1, 0.2, 1.0), 0.5, 0.2, 10).unwrap(),
    ];
    let mut checked = [0; 2];
    for poly in &shapes {
        let mesh = poly.mesh();
        for t in 0..mesh.triangle_count() {
            let [a, b, c] = mesh.triangle(t);
            let n = mesh.triangle_normal(t);
            let centroid = (a + b + c) / 3.0;
            let (u, _) = n.any_orthonormal_pair();
            let d = u * (1.5 + 2.0 * rng.f64());
            for (family, x) in [centroid + d, a + (b - a) * (2.0 + rng.f64())]
                .into_iter()
                .enumerate()
            {
                let frame = ShadingFrame::new(x, rng.dir(), DVec3::Z).unwrap();
                let sil = convex_silhouette(poly, &frame).unwrap();
                let sum: f64 = (0..mesh.triangle_count())
                    .filter_map(|k| {
                        triangle_polygon(mesh, k, &frame, TriangleRole::Emitter).unwrap()
                    })
                    .map(|p| p.solid_angle())
                    .sum();
                assert!(
                    (sil.solid_angle() - sum).abs() <= 1e-9,
                    "face {t}: silhouette {} per-triangle {sum}",
                    sil.solid_angle()
                );
                let edge_on = face_side(mesh, t, x) == Side::On;
                let outside =
                    (0..mesh.triangle_count()).any(|k| face_side(mesh, k, x) == Side::Front);
                if edge_on && outside && sil.solid_angle() > 0.0 {
                    checked[family] += 1;
                }
            }
        }
    }
    assert!(checked[0] > 100 && checked[1] > 100, "checked {checked:?}");
}
