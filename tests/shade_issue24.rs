//! Issue 24's shade-level reproducers (6 to 9) and minimized census findings
//! (tests/shade_census.rs): scenes whose shading was a silently wrong value, an error on valid
//! input, or a give-up. Each is checked against the Monte Carlo
//! reference (`ReferenceBrdf::Ltc`, the BRDF the analytic path models, so that only visibility
//! differs) at 4.5 standard errors plus a relative 1e-6 for its rounding, or against an exact
//! identity (a light shaded twice, a light in a scene of its own). The reference samples each
//! light twice: by its front faces (`LightSampling::Faces`, which uses nothing of the visibility
//! and sphere code under test, so a light region both got wrong cannot hide an error) and by
//! its unoccluded region (the default, whose samples are not wasted); both must agree.

use arealight::GeomError;
use arealight::glam::DVec3;
use arealight::internals::torus;
use arealight::shade::{
    ConvexPolyhedron, Light, LightSampling, Material, Method, MonteCarlo, ReferenceBrdf, Scene,
    TriangleMesh,
};

fn v(x: f64, y: f64, z: f64) -> DVec3 {
    DVec3::new(x, y, z)
}

fn diffuse() -> Material {
    Material::diffuse(DVec3::splat(0.8)).unwrap()
}

/// `scene.shade` at the point equals the Monte Carlo estimate within 4.5 standard errors (plus
/// relative 1e-6 and absolute 1e-12 for rounding), channel by channel, for the lights sampled
/// by their front faces and by their unoccluded regions.
fn assert_matches_mc(what: &str, scene: &Scene, x: DVec3, n: DVec3, view: DVec3, m: &Material) {
    let got = scene
        .shade(x, n, view, m)
        .unwrap_or_else(|e| panic!("{what}: {e:?}"));
    for sampling in [LightSampling::Faces, LightSampling::Silhouette] {
        let mc = MonteCarlo::new(100_000, ReferenceBrdf::Ltc)
            .with_sampling(sampling)
            .estimate(scene, x, n, view, m, 24)
            .unwrap();
        for c in 0..3 {
            let bound = 4.5 * mc.std_error[c] + 1e-6 * mc.mean[c].abs() + 1e-12;
            assert!(
                (got[c] - mc.mean[c]).abs() <= bound,
                "{what}: shade {} vs Monte Carlo ({sampling:?}) {} +- {}",
                got[c],
                mc.mean[c],
                mc.std_error[c]
            );
        }
    }
}

/// A 0.5 x 0.5 quad light at height 2 facing down (`quad(c, u, v)` emits towards `u x v`).
fn quad_light_down() -> TriangleMesh {
    TriangleMesh::quad(v(0.0, 0.0, 2.0), v(0.0, 0.5, 0.0), v(0.5, 0.0, 0.0)).unwrap()
}

/// Reproducer 6: a sliver triangle occluder in front of a box light blacked the light out (0
/// against 0.0044).
#[test]
fn reproducer_6_sliver_occluder_does_not_black_out_a_light() {
    let light = ConvexPolyhedron::cuboid(
        v(0.34662662372029085, 0.3801404514925406, 2.6289028376302745),
        v(0.5691938344005386, 0.6489062175053231, 0.08607525176378929),
    )
    .unwrap();
    let occ = TriangleMesh::new(
        vec![
            v(0.29188742424502323, 0.3201087557747302, 2.2137470850638947),
            v(0.5655398223611996, 0.1271265099632863, 2.230593127534444),
            v(0.42871362330969065, 0.22361763287890185, 2.2221701063056316),
        ],
        vec![[0, 1, 2]],
    )
    .unwrap();
    let scene = Scene::new(
        vec![Light::new(light, DVec3::ONE).unwrap()],
        vec![occ.into()],
    )
    .unwrap();
    assert_matches_mc(
        "reproducer 6",
        &scene,
        v(1.461551556855122, 0.9425202071881889, 0.762240455191973),
        v(-0.541648495327134, 0.8375866133026321, -0.07117283699613974),
        v(0.7137525187322471, -0.2436296406503727, -0.6566596837022535),
        &diffuse(),
    );
}

/// Reproducer 7: `Method::PerTriangle` gave 0 where `Method::Silhouette` gave the right value,
/// at a point near a small icosphere occluder next to a box light.
#[test]
fn reproducer_7_per_triangle_agrees_with_silhouette() {
    let light = ConvexPolyhedron::cuboid(
        v(0.15342134478867786, -0.4333232720532363, 2.627123700298531),
        v(
            0.22647124283262277,
            0.19302968335407344,
            0.07831073417701455,
        ),
    )
    .unwrap();
    let occ = ConvexPolyhedron::icosphere(
        v(
            -0.0986495086265729,
            -0.26334861748226895,
            3.0187500060104977,
        ),
        0.06392490881624406,
        1,
    )
    .unwrap();
    let x = v(
        -0.10434798299896249,
        -0.22951160606365514,
        2.966949074523864,
    );
    let n = v(-0.31509390132915, 0.5831287832016006, -0.7487834503693286);
    for method in [Method::Silhouette, Method::PerTriangle] {
        let scene = Scene::new(
            vec![Light::new(light.clone(), DVec3::ONE).unwrap()],
            vec![occ.clone().into()],
        )
        .unwrap()
        .with_method(method);
        assert_matches_mc(
            &format!("reproducer 7, {method:?}"),
            &scene,
            x,
            n,
            n,
            &diffuse(),
        );
    }
}

/// Reproducer 8a: a flat occluder lying in a quad light's plane hides nothing (it is met no
/// earlier than the light), for either facing of the occluder.
#[test]
fn reproducer_8_occluder_in_the_light_plane_hides_nothing() {
    let light = Light::new(quad_light_down(), DVec3::ONE).unwrap();
    let alone = Scene::new(vec![light.clone()], vec![]).unwrap();
    let x = v(0.2, 0.1, 0.0);
    let m = diffuse();
    let free = alone.shade(x, DVec3::Z, DVec3::Z, &m).unwrap();
    assert!(free.x > 0.05, "{free}");
    for flat in [
        TriangleMesh::quad(v(0.1, 0.1, 2.0), v(0.2, 0.0, 0.0), v(0.0, 0.2, 0.0)).unwrap(),
        TriangleMesh::quad(v(0.1, 0.1, 2.0), v(0.0, 0.2, 0.0), v(0.2, 0.0, 0.0)).unwrap(),
        // Larger than the light, and with a wall rising from it towards the point: only the
        // wall hides anything.
        TriangleMesh::new(
            vec![
                v(-1.0, -1.0, 2.0),
                v(2.0, -1.0, 2.0),
                v(2.0, 2.0, 2.0),
                v(-1.0, 2.0, 2.0),
                v(0.25, -1.0, 1.5),
                v(0.25, 2.0, 1.5),
            ],
            vec![[0, 1, 2], [0, 2, 3], [4, 5, 1]],
        )
        .unwrap(),
    ] {
        let scene = Scene::new(vec![light.clone()], vec![flat.into()]).unwrap();
        assert_matches_mc("reproducer 8a", &scene, x, DVec3::Z, DVec3::Z, &m);
    }
    // The first two exactly: nothing is hidden.
    for flat in [
        TriangleMesh::quad(v(0.1, 0.1, 2.0), v(0.2, 0.0, 0.0), v(0.0, 0.2, 0.0)).unwrap(),
        TriangleMesh::quad(v(0.1, 0.1, 2.0), v(0.0, 0.2, 0.0), v(0.2, 0.0, 0.0)).unwrap(),
    ] {
        let scene = Scene::new(vec![light.clone()], vec![flat.into()]).unwrap();
        assert_eq!(scene.shade(x, DVec3::Z, DVec3::Z, &m).unwrap(), free);
    }
}

/// Reproducer 8b: two coincident quad lights each hide nothing of the other: twice one light.
#[test]
fn reproducer_8_coincident_lights_add_up() {
    let light = Light::new(quad_light_down(), DVec3::ONE).unwrap();
    let m = diffuse();
    let x = v(0.2, 0.1, 0.0);
    let one = Scene::new(vec![light.clone()], vec![])
        .unwrap()
        .shade(x, DVec3::Z, DVec3::Z, &m)
        .unwrap();
    let two = Scene::new(vec![light.clone(), light.clone()], vec![]).unwrap();
    let got = two.shade(x, DVec3::Z, DVec3::Z, &m).unwrap();
    assert!(
        (got - 2.0 * one).abs().max_element() <= 1e-15 * one.x,
        "{got} vs 2 x {one}"
    );
    assert_matches_mc("reproducer 8b", &two, x, DVec3::Z, DVec3::Z, &m);
}

/// Reproducer 8c: a point inside a closed light receives nothing from it (its outer surface
/// emits outwards), for a convex light on either method and for a closed non-convex one (inside
/// a torus's tube, where the far side of the tube faces the point).
#[test]
fn reproducer_8_point_inside_a_closed_light_receives_nothing() {
    let m = diffuse();
    let cube = ConvexPolyhedron::cuboid(v(0.0, 0.0, 1.0), v(0.5, 0.5, 0.5)).unwrap();
    for method in [Method::Silhouette, Method::PerTriangle] {
        let scene = Scene::new(vec![Light::new(cube.clone(), DVec3::ONE).unwrap()], vec![])
            .unwrap()
            .with_method(method);
        for x in [v(0.0, 0.0, 0.9), v(0.3, -0.2, 1.4)] {
            assert_eq!(
                scene.shade(x, DVec3::Z, DVec3::Z, &m).unwrap(),
                DVec3::ZERO,
                "{method:?} {x}"
            );
            assert_matches_mc("reproducer 8c, cube", &scene, x, DVec3::Z, DVec3::Z, &m);
        }
        // Just outside the cube's top face, looking up at nothing, and beside it, looking at
        // its side: the reference sees what the analytic path sees.
        for (x, n) in [
            (v(0.1, 0.2, 1.5 + 1e-9), DVec3::Z),
            (v(0.9, 0.1, 1.0), v(-1.0, 0.0, 0.0)),
        ] {
            assert_matches_mc("reproducer 8c, cube outside", &scene, x, n, n, &m);
        }
    }
    let tube = torus(1.0, 0.4, 12, 8).unwrap();
    for method in [Method::Silhouette, Method::PerTriangle] {
        let scene = Scene::new(vec![Light::new(tube.clone(), DVec3::ONE).unwrap()], vec![])
            .unwrap()
            .with_method(method);
        for (x, n) in [
            (v(1.0, 0.0, 0.0), DVec3::Z),
            (v(0.0, -1.1, 0.1), v(0.0, 1.0, 0.0)),
        ] {
            assert_eq!(
                scene.shade(x, n, n, &m).unwrap(),
                DVec3::ZERO,
                "torus {method:?} {x}"
            );
            assert_matches_mc("reproducer 8c, torus", &scene, x, n, n, &m);
        }
        // Just outside the tube, in the hole: the far side of the ring is seen.
        let x = v(0.55, 0.0, 0.0);
        let n = v(-1.0, 0.0, 0.0);
        assert!(scene.shade(x, n, n, &m).unwrap().x > 0.0);
        assert_matches_mc("reproducer 8c, torus hole", &scene, x, n, n, &m);
    }
}

/// Reproducer 8d: a planar light whose triangles overlap is rejected, naming them (its overlap
/// would be counted twice); neighbours sharing an edge or a vertex are fine.
#[test]
fn reproducer_8_planar_light_with_overlapping_triangles_is_rejected() {
    let verts = vec![
        v(0.0, 0.0, 2.0),
        v(0.0, 1.0, 2.0),
        v(1.0, 0.0, 2.0),
        v(1.0, 1.0, 2.0),
    ];
    let overlapping = TriangleMesh::new(verts.clone(), vec![[0, 1, 2], [0, 1, 3]]).unwrap();
    assert_eq!(
        Light::new(overlapping, DVec3::ONE).unwrap_err(),
        GeomError::OverlappingLightTriangles {
            triangle: 0,
            other: 1
        }
    );
    // A copy of a triangle.
    let twice = TriangleMesh::new(verts.clone(), vec![[0, 1, 2], [3, 2, 1], [0, 1, 2]]).unwrap();
    assert_eq!(
        Light::new(twice, DVec3::ONE).unwrap_err(),
        GeomError::OverlappingLightTriangles {
            triangle: 0,
            other: 2
        }
    );
    // A fan of four triangles round a centre, and two triangles touching at a vertex only.
    let fan = TriangleMesh::new(
        vec![
            v(0.5, 0.5, 2.0),
            v(0.0, 0.0, 2.0),
            v(1.0, 0.0, 2.0),
            v(1.0, 1.0, 2.0),
            v(0.0, 1.0, 2.0),
        ],
        vec![[0, 1, 2], [0, 2, 3], [0, 3, 4], [0, 4, 1]],
    )
    .unwrap();
    assert!(Light::new(fan, DVec3::ONE).is_ok());
    let bow = TriangleMesh::new(
        vec![
            v(0.0, 0.0, 2.0),
            v(1.0, 0.0, 2.0),
            v(0.5, 0.5, 2.0),
            v(0.0, 1.0, 2.0),
            v(1.0, 1.0, 2.0),
        ],
        vec![[0, 1, 2], [2, 4, 3]],
    )
    .unwrap();
    assert!(Light::new(bow, DVec3::ONE).is_ok());
}

/// Reproducer 9: `icosphere` with a non-positive radius is an error naming the radius.
#[test]
fn reproducer_9_icosphere_radius_must_be_positive() {
    for r in [0.0, -1.0] {
        assert!(matches!(
            ConvexPolyhedron::icosphere(DVec3::ZERO, r, 1),
            Err(GeomError::OutOfRange { value, .. }) if value == r
        ));
    }
    assert!(matches!(
        ConvexPolyhedron::icosphere(DVec3::ZERO, f64::NAN, 1),
        Err(GeomError::NonFiniteArgument { .. })
    ));
}

/// Reproducer 8e: a point very far from a quad light with an occluder in front of it gets a tiny
/// value, not an error. From far below, the 0.2 x 0.2 box hides the light's corner
/// `[0, 0.1]^2` of its `[0, 0.5]^2` in the parallel-projection limit: the ratio to the
/// unoccluded value tends to `1 - 0.01 / 0.25 = 0.96`, within about `size / distance`.
#[test]
fn reproducer_8_far_point_with_an_occluder_gets_a_tiny_value() {
    let light = Light::new(quad_light_down(), DVec3::ONE).unwrap();
    let cube = ConvexPolyhedron::cuboid(v(0.0, 0.0, 1.0), DVec3::splat(0.1)).unwrap();
    let scene = Scene::new(vec![light.clone()], vec![cube.into()]).unwrap();
    let alone = Scene::new(vec![light], vec![]).unwrap();
    let m = diffuse();
    for d in [1e7, 1e9, 1e12] {
        let x = v(0.25, 0.25, 1.0 - d);
        let got = scene.shade(x, DVec3::Z, DVec3::Z, &m).unwrap();
        let free = alone.shade(x, DVec3::Z, DVec3::Z, &m).unwrap();
        assert!(free.x > 0.0, "{d}");
        assert!(
            (got.x / free.x - 0.96).abs() < 1e-6,
            "{d}: {} / {}",
            got.x,
            free.x
        );
    }
}

/// Two sheets of a census light (tests/shade_census.rs, light kind 3): triangles `[0, 1, 2]`,
/// `[0, 2, 3]` of the lower sheet facing down and the same of the upper one.
fn two_sheets(v8: [DVec3; 8]) -> TriangleMesh {
    TriangleMesh::new(
        v8.to_vec(),
        vec![[0, 1, 2], [0, 2, 3], [4, 5, 6], [4, 6, 7]],
    )
    .unwrap()
}

/// `scene` shaded with both methods: equal within 1e-9 of the value, and the Monte Carlo
/// reference agrees (see [`assert_matches_mc`]).
fn assert_methods_and_mc(what: &str, scene: Scene, x: DVec3, n: DVec3, view: DVec3) {
    let m = diffuse();
    let a = scene.shade(x, n, view, &m).unwrap();
    let per = scene.clone().with_method(Method::PerTriangle);
    let b = per
        .shade(x, n, view, &m)
        .unwrap_or_else(|e| panic!("{what}: {e:?}"));
    assert!(
        (a - b).abs().max_element() <= 1e-9 * a.max_element(),
        "{what}: {a} vs {b}"
    );
    assert_matches_mc(what, &scene, x, n, view, &m);
}

/// A sliver occluder (its third vertex 1e-12 of its length off the line of the other two) that
/// the lower sheet's plane cuts through both long edges, 1.7e-12 apart: the cut quadrilateral,
/// projected, folds back within rounding, and the query gave up (census case 255 at
/// `CENSUS_CASES=5`). Its solid angle, bounded on its fan, is below what the sphere layer
/// resolves: it covers nothing.
#[test]
fn sliver_cut_by_a_light_plane_through_both_long_edges() {
    let sheets = two_sheets([
        v(
            -0.27629705746767286,
            -0.7620828334948009,
            2.3385006980673775,
        ),
        v(
            -0.27629705746767286,
            0.32030539462759067,
            2.3385006980673775,
        ),
        v(0.8060911706547187, 0.32030539462759067, 2.3385006980673775),
        v(0.8060911706547187, -0.7620828334948009, 2.3385006980673775),
        v(-0.5486539210709264, -0.7620828334948009, 2.6524794094459905),
        v(-0.5486539210709264, 0.32030539462759067, 2.6524794094459905),
        v(0.5337343070514652, 0.32030539462759067, 2.6524794094459905),
        v(0.5337343070514652, -0.7620828334948009, 2.6524794094459905),
    ]);
    let sliver = TriangleMesh::new(
        vec![
            v(0.4025046460461048, -0.4010611479721148, 2.452577496704594),
            v(0.6627000786457589, -0.19278217630566977, 2.154057911598133),
            v(0.5556375748898016, -0.27848263600792933, 2.2768896380492567),
        ],
        vec![[0, 1, 2]],
    )
    .unwrap();
    let scene = Scene::new(
        vec![Light::new(sheets, DVec3::new(1.0, 0.8, 0.6)).unwrap()],
        vec![sliver.into()],
    )
    .unwrap();
    assert_methods_and_mc(
        "census 255:2",
        scene,
        v(0.7576565195956513, 0.10300093211591088, 0.0),
        v(0.0, 0.0, 1.0),
        v(0.99975602411972, 0.0, 0.02208828278363511),
    );
}

/// A sliver occluder 2.2 rad long and 8e-13 rad wide seen from a point on a box face: its
/// projection folds back at a corner (a wedge below 1e-12 rad) though its solid angle is
/// 9.9e-13 sr, above the 1e-12 sr that was certified to cover nothing, and the query gave up
/// (census case 215 at `CENSUS_CASES=5`). A triangle with such a corner lies in a lune of
/// 2e-12 sr.
#[test]
fn long_sliver_seen_with_a_corner_below_the_fold_test() {
    let sheets = two_sheets([
        v(
            -0.37284029592149937,
            -0.7173967268137957,
            1.8038782273453542,
        ),
        v(
            -0.37284029592149937,
            0.24398464508734996,
            1.8038782273453542,
        ),
        v(0.5885410759796463, 0.24398464508734996, 1.8038782273453542),
        v(0.5885410759796463, -0.7173967268137957, 1.8038782273453542),
        v(
            -0.18948193952119247,
            -0.7173967268137957,
            2.2781337759792897,
        ),
        v(
            -0.18948193952119247,
            0.24398464508734996,
            2.2781337759792897,
        ),
        v(0.7718994323799533, 0.24398464508734996, 2.2781337759792897),
        v(0.7718994323799533, -0.7173967268137957, 2.2781337759792897),
    ]);
    let sliver = TriangleMesh::new(
        vec![
            v(
                -0.014902834998565997,
                -0.04677988127660854,
                0.7969957209175123,
            ),
            v(
                -0.12908020193304331,
                -0.04540665089422305,
                1.386296251114674,
            ),
            v(
                -0.06741935399516182,
                -0.04614825627505141,
                1.0680477982308811,
            ),
        ],
        vec![[0, 1, 2]],
    )
    .unwrap();
    let scene = Scene::new(
        vec![Light::new(sheets, DVec3::new(1.0, 0.8, 0.6)).unwrap()],
        vec![sliver.into()],
    )
    .unwrap();
    assert_methods_and_mc(
        "census 215:13",
        scene,
        v(
            0.06913413265098811,
            0.019832009320439076,
            1.0930474670953358,
        ),
        v(0.0, -1.0, 0.0),
        v(0.999515634572607, -0.031120672308271778, 0.0),
    );
}
