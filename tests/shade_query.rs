//! `Scene::shade_per_light`: each light's share split into lobes, shadowed and unshadowed, checked
//! against independent evaluations of the same quantities: `Scene::shade` (the sum),
//! `Scene::shade_light` with diffuse-only and specular-only materials (the lobes), and a scene
//! holding the light alone (the unshadowed value). The values agree to rounding (the same
//! integrals summed in another order), so the bounds are relative `1e-12`.

use arealight::GeomError;
use arealight::glam::DVec3;
use arealight::internals::{DemoConfig, demo_scene};
use arealight::shade::{ConvexPolyhedron, Light, Material, Scene, TriangleMesh};
use support::Rng;
use support::shade::{ground_point, point_on_mesh, view_above};

mod support;

fn close(a: DVec3, b: DVec3) -> bool {
    (a - b).abs().max_element() <= 1e-12 * (a.abs().max_element() + b.abs().max_element()) + 1e-300
}

/// Checks every identity at `count` points of `scene` (ground points and points on occluder
/// surfaces, random views above the surface); returns how many (point, light) pairs were
/// shadowed by more than 1% in some channel.
fn check(scene: &Scene, count: usize, seed: u64) -> usize {
    let mut rng = Rng::new(seed * 100 + 21);
    let m = Material::new(
        DVec3::new(0.6, 0.5, 0.4),
        DVec3::new(0.04, 0.05, 0.06),
        0.35,
    )
    .unwrap();
    let diffuse_only = Material::new(m.albedo(), DVec3::ZERO, m.roughness()).unwrap();
    let specular_only = Material::new(DVec3::ZERO, m.f0(), m.roughness()).unwrap();
    let alone: Vec<Scene> = scene
        .lights()
        .iter()
        .map(|l| Scene::new(vec![l.clone()], vec![]).unwrap())
        .collect();
    let mut shadowed = 0;
    for i in 0..count {
        let occ = scene.occluders();
        let (x, n) = if i % 3 == 2 && !occ.is_empty() {
            point_on_mesh(&mut rng, occ[i % occ.len()].mesh())
        } else {
            (ground_point(&mut rng, 2.0), DVec3::Z)
        };
        let v = view_above(&mut rng, n, 0.1);
        let parts = scene.shade_per_light(x, n, v, &m).unwrap();
        assert_eq!(parts.len(), scene.lights().len());
        let total = scene.shade(x, n, v, &m).unwrap();
        let sum: DVec3 = parts.iter().map(|p| p.shadowed()).sum();
        assert!(close(sum, total), "point {i}: sum {sum} vs shade {total}");
        for (k, p) in parts.iter().enumerate() {
            let whole = scene.shade_light(k, x, n, v, &m).unwrap();
            assert!(close(p.shadowed(), whole), "point {i} light {k}");
            let d = scene.shade_light(k, x, n, v, &diffuse_only).unwrap();
            let s = scene.shade_light(k, x, n, v, &specular_only).unwrap();
            assert!(
                close(p.diffuse, d),
                "point {i} light {k}: diffuse {} vs {d}",
                p.diffuse
            );
            assert!(
                close(p.specular, s),
                "point {i} light {k}: specular {} vs {s}",
                p.specular
            );
            let ud = alone[k].shade(x, n, v, &diffuse_only).unwrap();
            let us = alone[k].shade(x, n, v, &specular_only).unwrap();
            assert!(
                close(p.unshadowed_diffuse, ud),
                "point {i} light {k}: unshadowed diffuse {} vs {ud}",
                p.unshadowed_diffuse
            );
            assert!(
                close(p.unshadowed_specular, us),
                "point {i} light {k}: unshadowed specular {} vs {us}",
                p.unshadowed_specular
            );
            let (sh, un) = (p.shadowed(), p.unshadowed());
            assert!(
                (0..3).all(|c| sh[c] <= un[c] * (1.0 + 1e-12) + 1e-300),
                "point {i} light {k}: shadowed {sh} above unshadowed {un}"
            );
            if (0..3).any(|c| sh[c] < 0.99 * un[c]) {
                shadowed += 1;
            }
        }
    }
    shadowed
}

#[test]
fn per_light_parts_match_independent_evaluations_in_the_demo_scene() {
    let demo = demo_scene(DemoConfig::default()).unwrap();
    let shadowed = check(&demo.scene, 150, 1);
    // The unshadowed values must differ from the shadowed ones somewhere, or the comparison with
    // the lone light would not tell the two regions apart.
    assert!(
        shadowed > 30,
        "only {shadowed} shadowed (point, light) pairs"
    );
}

#[test]
fn per_light_parts_with_interpenetrating_and_self_occluding_lights() {
    // An open two-sheet mesh light (it hides itself: its unshadowed value keeps that), a box
    // piercing a cuboid light (the face-by-face path), and a quad light near both.
    let sheets = TriangleMesh::quad(DVec3::new(-0.2, 0.0, 2.0), DVec3::X * 0.5, DVec3::Y * 0.5)
        .unwrap()
        .merged(
            &TriangleMesh::quad(DVec3::new(0.4, 0.1, 3.0), DVec3::Y * 0.6, DVec3::X * 0.6).unwrap(),
        )
        .unwrap();
    let cuboid =
        ConvexPolyhedron::cuboid(DVec3::new(1.2, 0.3, 2.4), DVec3::new(0.4, 0.3, 0.2)).unwrap();
    let quad =
        TriangleMesh::quad(DVec3::new(-1.0, -0.8, 2.6), DVec3::Y * 0.4, DVec3::X * 0.4).unwrap();
    let scene = Scene::new(
        vec![
            Light::new(sheets, DVec3::new(1.0, 2.0, 1.5)).unwrap(),
            Light::new(cuboid, DVec3::new(1.5, 1.0, 0.8)).unwrap(),
            Light::new(quad, DVec3::new(0.7, 0.9, 1.1)).unwrap(),
        ],
        vec![
            ConvexPolyhedron::cuboid(DVec3::new(1.3, 0.35, 2.4), DVec3::new(0.1, 0.1, 0.8))
                .unwrap()
                .into(),
            ConvexPolyhedron::cuboid(DVec3::new(0.5, 0.0, 2.5), DVec3::new(0.25, 0.25, 0.2))
                .unwrap()
                .into(),
        ],
    )
    .unwrap();
    let shadowed = check(&scene, 90, 2);
    assert!(
        shadowed > 20,
        "only {shadowed} shadowed (point, light) pairs"
    );
}

#[test]
fn per_light_query_reports_the_same_errors_as_shade() {
    let demo = demo_scene(DemoConfig::default()).unwrap();
    let s = &demo.scene;
    assert_eq!(
        s.shade_per_light(
            DVec3::ZERO,
            DVec3::new(f64::NAN, 0.0, 1.0),
            DVec3::Z,
            &demo.ground
        ),
        Err(GeomError::NonFiniteArgument {
            what: "surface normal"
        })
    );
    assert_eq!(
        s.shade_per_light(DVec3::ZERO, DVec3::Z, DVec3::ZERO, &demo.ground),
        Err(GeomError::ZeroLengthArgument {
            what: "view direction"
        })
    );
}

/// Found by the `shade` fuzz target: a point on the surface of a small icosphere light, beside a
/// long quad light. A light's shadowed and unshadowed values can come from different paths (the
/// visibility fast path and the spherical one), which agree to rounding; `shade_per_light`
/// clamped the shadowed value to the unshadowed one, so its shares no longer added up to `shade`
/// (2.1e-11 relative here). The shares are now exactly what `shade` computes per light.
#[test]
fn shares_add_up_to_shade_where_the_paths_differ_by_rounding() {
    let g = |x: f64, y: f64, z: f64| DVec3::new(x, y, z) / 8.0;
    let rgb = DVec3::new(1.0, 2.0, 0.5);
    let ico = ConvexPolyhedron::icosphere(g(-79.0, 0.0, -65.0), 1.0 / 16.0, 1).unwrap();
    let quad = TriangleMesh::quad(g(0.0, -1.0, -1.0), g(0.0, 0.0, -1.0), g(-1.0, -1.0, 64.0));
    let scene = Scene::new(
        vec![
            Light::new(ico, rgb).unwrap(),
            Light::new(quad.unwrap(), rgb).unwrap(),
        ],
        vec![],
    )
    .unwrap();
    let m = Material::new(
        DVec3::splat(142.0 / 255.0),
        DVec3::splat(14.0 / 255.0),
        142.0 / 255.0,
    )
    .unwrap();
    let x = DVec3::new(-9.821834324477997, 0.0, -8.092141805492554);
    let (n, v) = (DVec3::new(-0.0, -0.0, -1.0), DVec3::Z);
    let total = scene.shade(x, n, v, &m).unwrap();
    let sum: DVec3 = scene
        .shade_per_light(x, n, v, &m)
        .unwrap()
        .iter()
        .map(|p| p.shadowed())
        .sum();
    for c in 0..3 {
        assert!(
            (sum[c] - total[c]).abs() <= 1e-12 * total[c].abs(),
            "shares {sum} vs shade {total}"
        );
    }
}
