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

/// A point on a sliver occluder (census family "on a sliver", its third vertex `1e-12..1e-9` of
/// its length off the line of the others): the sliver's normal was a floating-point cross
/// product, off by about `1e-7` here, so the facing predicate put the point `5e-8` in front of
/// the sliver's plane instead of on it. The silhouette path then gave more than the unshadowed
/// value (0.436 against 0.354), the per-triangle path gave up, and the Monte Carlo reference
/// read 0 (its rays, starting on the sliver, hit it). Seen from a point on it, the sliver
/// covers nothing.
#[test]
fn point_on_a_sliver_occluder_sees_the_light() {
    // The census's box light (case 1 of tests/shade_census.rs at its default size).
    let (x0, x1) = (0.06149612227177259, 0.7215324424789707);
    let (y0, y1) = (-0.07032703836313814, 0.5259831251025261);
    let (z0, z1) = (1.8248243615516153, 2.3813827440459243);
    let light = ConvexPolyhedron::from_mesh(
        &TriangleMesh::new(
            vec![
                v(x1, y1, z1),
                v(x1, y1, z0),
                v(x0, y1, z1),
                v(x0, y0, z0),
                v(x1, y0, z0),
                v(x0, y1, z0),
                v(x0, y0, z1),
                v(x1, y0, z1),
            ],
            vec![
                [0, 1, 2],
                [3, 1, 4],
                [1, 0, 4],
                [3, 2, 5],
                [1, 3, 5],
                [2, 1, 5],
                [3, 4, 6],
                [2, 3, 6],
                [0, 2, 6],
                [4, 0, 7],
                [6, 4, 7],
                [0, 6, 7],
            ],
        )
        .unwrap(),
    )
    .unwrap();
    let sliver = TriangleMesh::new(
        vec![
            v(0.32200879761596146, 0.5114298956195178, 1.392082148580062),
            v(0.4636840038797839, 0.008126410596820927, 1.4450760372835223),
            v(0.4312816782562113, 0.12323620199383344, 1.4329558837891267),
        ],
        vec![[0, 1, 2]],
    )
    .unwrap();
    let x = v(0.4240567254024064, 0.1489029649260155, 1.4302533760428613);
    let n = v(0.5162042379923654, 0.2321108898492351, 0.824413560958405);
    let view = v(0.32895132848226566, -0.2786378449742833, 0.3982502918466849);
    let alone = Scene::new(vec![Light::new(light.clone(), DVec3::ONE).unwrap()], vec![]).unwrap();
    let free = alone.shade(x, n, view, &diffuse()).unwrap();
    let scene = Scene::new(
        vec![Light::new(light, DVec3::ONE).unwrap()],
        vec![sliver.into()],
    )
    .unwrap();
    for method in [Method::Silhouette, Method::PerTriangle] {
        let got = scene
            .clone()
            .with_method(method)
            .shade(x, n, view, &diffuse())
            .unwrap();
        assert!(
            (got - free).abs().max_element() <= 1e-12 * free.x,
            "{method:?}: {got} vs the light alone {free}"
        );
    }
    assert_matches_mc("point on a sliver", &scene, x, n, view, &diffuse());
}

/// The family of [`point_on_a_sliver_occluder_sees_the_light`]: slivers `1e-12..1e-6` of their
/// length thin in every orientation, a point interpolated on each (so within rounding of its
/// plane) with the sliver's normal either way: the facing predicate puts the point on the
/// sliver's plane, and the sliver hides nothing (both methods equal the light shaded alone).
#[test]
fn points_on_slivers_are_on_their_planes() {
    use arealight::solid::{Side, face_side};
    let light = Light::new(quad_light_down(), DVec3::ONE).unwrap();
    let alone = Scene::new(vec![light.clone()], vec![]).unwrap();
    let mut state = 0x511_u64;
    let mut next = || {
        state = state
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        (state >> 11) as f64 / (1u64 << 53) as f64
    };
    for k in 0..300 {
        let r: [f64; 10] = std::array::from_fn(|_| next());
        let dir = |i: usize| v(r[i] - 0.5, r[i + 1] - 0.5, r[i + 2] - 0.5).normalize();
        let c = v(0.25, 0.25, 1.0);
        let (a, b) = (c + dir(0) * 0.4, c - dir(3) * 0.4);
        let off = 10f64.powf(-12.0 + 6.0 * f64::from(k) / 300.0);
        let m = a.lerp(b, 0.3 + 0.4 * r[9]) + dir(6) * off * (b - a).length();
        let Ok(sliver) = TriangleMesh::new(vec![a, b, m], vec![[0, 1, 2]]) else {
            continue;
        };
        let (u, w) = (next() * 0.5, next() * 0.5);
        let x = a + (b - a) * u + (m - a) * w;
        assert_eq!(face_side(&sliver, 0, x), Side::On, "{k}: {x}");
        let nn = sliver.triangle_normal(0);
        let scene = Scene::new(vec![light.clone()], vec![sliver.into()]).unwrap();
        for n in [nn, -nn] {
            let free = alone.shade(x, n, n, &diffuse()).unwrap();
            for method in [Method::Silhouette, Method::PerTriangle] {
                let got = scene
                    .clone()
                    .with_method(method)
                    .shade(x, n, n, &diffuse())
                    .unwrap_or_else(|e| panic!("{k} {method:?}: {e}"));
                assert!(
                    (got - free).abs().max_element() <= 1e-9 * free.x + 1e-15,
                    "{k} {method:?}: {got} vs the light alone {free}"
                );
            }
        }
    }
}

/// A point `4.9e-14` outside a box occluder's face (within the facing predicate's band, about
/// `4e-13` here), under a box light, seen at a grazing view whose mirror direction runs along
/// that face (census case 670 of the near-face census at `CENSUS_CASES=30`). Inside the band the
/// model is not unique: the silhouette path takes the point as on the box (the region behind the
/// face plane), the per-triangle path projects the box's other faces from the point as it is;
/// the two meet on the plane. For the Lambertian lobe they agree to `1e-11`; for a near-mirror
/// lobe the per-triangle value moves by `3.6e-8` per `1e-14` of offset, and the two differ by
/// `3.5e-7` of the value: within what moving the point across the band changes, which is what
/// the census allows (`facing_band_spread` in tests/shade_census.rs), and far below anything the
/// reference resolves.
#[test]
fn point_in_a_face_band_methods_differ_by_the_band_at_most() {
    let box_mesh = |lo: DVec3, hi: DVec3| {
        ConvexPolyhedron::from_mesh(
            &TriangleMesh::new(
                vec![
                    v(hi.x, hi.y, hi.z),
                    v(hi.x, hi.y, lo.z),
                    v(lo.x, hi.y, hi.z),
                    v(lo.x, lo.y, lo.z),
                    v(hi.x, lo.y, lo.z),
                    v(lo.x, hi.y, lo.z),
                    v(lo.x, lo.y, hi.z),
                    v(hi.x, lo.y, hi.z),
                ],
                vec![
                    [0, 1, 2],
                    [3, 1, 4],
                    [1, 0, 4],
                    [3, 2, 5],
                    [1, 3, 5],
                    [2, 1, 5],
                    [3, 4, 6],
                    [2, 3, 6],
                    [0, 2, 6],
                    [4, 0, 7],
                    [6, 4, 7],
                    [0, 6, 7],
                ],
            )
            .unwrap(),
        )
        .unwrap()
    };
    let light = box_mesh(
        v(-0.8464736965228763, -0.7930829597779211, 1.2217416711990796),
        v(-0.11359380736647856, 0.4526234953260767, 1.9511763413644503),
    );
    let occ = box_mesh(
        v(-0.2578015757529462, -0.6588056255626995, 1.9539176037855635),
        v(
            -0.23532813467623484,
            -0.6337742693026356,
            1.9774841690940321,
        ),
    );
    let scene = Scene::new(
        vec![Light::new(light, DVec3::ONE).unwrap()],
        vec![occ.into()],
    )
    .unwrap();
    let face_y = -0.6337742693026356;
    let x = v(-0.23879713947576608, face_y + 4.9e-14, 1.9677859565701745);
    let n = v(0.0, 0.0, -1.0);
    let view = v(0.9992564798325142, 0.0, -0.03855499335665991);
    let value = |method: Method, x: DVec3, m: &Material| {
        scene
            .clone()
            .with_method(method)
            .shade(x, n, view, m)
            .unwrap()
    };
    let lambert = diffuse();
    let (a, b) = (
        value(Method::Silhouette, x, &lambert),
        value(Method::PerTriangle, x, &lambert),
    );
    assert!((a - b).abs().max_element() <= 1e-11 * a.x, "{a} vs {b}");
    let mirror = Material::new(DVec3::ZERO, DVec3::ONE, 0.0).unwrap();
    let (a, b) = (
        value(Method::Silhouette, x, &mirror),
        value(Method::PerTriangle, x, &mirror),
    );
    // On the face plane itself the two agree.
    let on = v(x.x, face_y, x.z);
    let (a0, b0) = (
        value(Method::Silhouette, on, &mirror),
        value(Method::PerTriangle, on, &mirror),
    );
    assert!(
        (a0 - b0).abs().max_element() <= 1e-12 * a0.x,
        "{a0} vs {b0}"
    );
    // Off it, their difference is below the per-triangle value's change across the band.
    let band = 1e-11 * 0.04;
    let edge = value(Method::PerTriangle, v(x.x, face_y + band, x.z), &mirror);
    let spread = (edge - b).abs().max((b0 - b).abs());
    assert!(
        (a - b).abs().max_element() > 1e-9 * a.x,
        "the configuration is sensitive: {a} vs {b}"
    );
    assert!(
        ((a - b).abs() - spread).max_element() <= 1e-12 * a.x,
        "{a} vs {b}, band spread {spread}"
    );
}

/// A point inside a box that cuts through a two-sheet light, on the top face of a second box
/// touching the light's lower plane from below, `2.2e-16` under the lower sheet (census case 307
/// at `CENSUS_CASES=64`). Both analytic paths give 0 (the point is inside an opaque box). The
/// Monte Carlo reference gave 0.217: it decided the sheet's facing by the sign of the distance
/// alone, so the sheet, in the point's plane by the facing predicate, emitted towards the point
/// and its rays, `1e-16` long, met nothing. It now uses the facing predicate, as the analytic
/// path does: a point in a light's plane sees it edge-on.
#[test]
fn point_in_a_light_plane_gets_nothing_from_it() {
    let z = 1.889478148309195;
    let sheets = two_sheets([
        v(-0.04992437992921994, -0.9160163829738076, z),
        v(-0.04992437992921994, 0.08406243346082765, z),
        v(0.9501544365054153, 0.08406243346082765, z),
        v(0.9501544365054153, -0.9160163829738076, z),
        v(0.06813039812787336, -0.9160163829738076, 2.3747271966348524),
        v(0.06813039812787336, 0.08406243346082765, 2.3747271966348524),
        v(1.0682092145625086, 0.08406243346082765, 2.3747271966348524),
        v(1.0682092145625086, -0.9160163829738076, 2.3747271966348524),
    ]);
    let box_mesh = |lo: DVec3, hi: DVec3| -> ConvexPolyhedron {
        ConvexPolyhedron::from_mesh(
            &TriangleMesh::new(
                vec![
                    v(hi.x, hi.y, hi.z),
                    v(lo.x, hi.y, hi.z),
                    v(lo.x, lo.y, hi.z),
                    v(lo.x, lo.y, lo.z),
                    v(hi.x, lo.y, lo.z),
                    v(lo.x, hi.y, lo.z),
                    v(hi.x, hi.y, lo.z),
                    v(hi.x, lo.y, hi.z),
                ],
                vec![
                    [0, 1, 2],
                    [2, 1, 3],
                    [2, 3, 4],
                    [3, 1, 5],
                    [4, 3, 5],
                    [1, 0, 5],
                    [4, 5, 6],
                    [5, 0, 6],
                    [0, 4, 6],
                    [4, 0, 7],
                    [2, 4, 7],
                    [0, 2, 7],
                ],
            )
            .unwrap(),
        )
        .unwrap()
    };
    let top = 1.8894781483091947;
    let through = box_mesh(
        v(0.6003715346387004, -0.9427121108175012, 1.510219177469558),
        v(0.8124298291283758, -0.5592273562224122, 2.268737119148832),
    );
    let below = box_mesh(
        v(0.6238755697299854, -0.99225171685167, 1.1309602066299211),
        v(0.8359338642196608, -0.608766962256581, top),
    );
    let scene = Scene::new(
        vec![Light::new(sheets, DVec3::new(1.0, 0.8, 0.6)).unwrap()],
        vec![through.into(), below.into()],
    )
    .unwrap();
    let x = v(0.7588221087004304, -0.7736668591779706, top);
    let view = v(
        -0.09257094400627686,
        0.23224686494950086,
        0.9019025395381173,
    );
    let m = Material::new(DVec3::splat(0.5), DVec3::splat(0.04), 0.4).unwrap();
    for method in [Method::Silhouette, Method::PerTriangle] {
        let got = scene
            .clone()
            .with_method(method)
            .shade(x, DVec3::Z, view, &m)
            .unwrap();
        assert_eq!(got, DVec3::ZERO, "{method:?}");
    }
    for sampling in [LightSampling::Faces, LightSampling::Silhouette] {
        let e = MonteCarlo::new(10_000, ReferenceBrdf::Ltc)
            .with_sampling(sampling)
            .with_brdf_sampling()
            .estimate(&scene, x, DVec3::Z, view, &m, 5)
            .unwrap();
        assert_eq!(
            e.mean,
            DVec3::ZERO,
            "{sampling:?}: {} +- {}",
            e.mean,
            e.std_error
        );
    }
}

/// A point `1.3e-12` inside a box occluder's face (just outside the facing band), under two
/// sheet lights, with a near-mirror lobe (roughness 0.01) whose mirror direction runs along that
/// face (near-face census case 1573 at `CENSUS_CASES=64`). The point is inside an opaque box:
/// it gets nothing, and the silhouette path says exactly that. The per-triangle path subtracts
/// the box's twelve faces one by one and leaves a gap of `1.3e-10` sr along the face plane,
/// within the sphere layer's resolution: `2e-11` of the diffuse value, but `7.5e-6` of the
/// specular one, the gap lying on the lobe's peak. That is within the agreement the census
/// states for a lobe of width `alpha` (`1e-9 / alpha` of the specular value, the change a
/// boundary moved by `1e-9` rad makes), and it is checked to stay there.
#[test]
fn point_just_inside_a_box_face_under_a_mirror_lobe() {
    let sheets = two_sheets([
        v(-1.6065112258489538, -1.4273569966932609, 2.020410400741447),
        v(-1.6065112258489538, 1.1954288237555466, 2.020410400741447),
        v(1.0162745945998537, 1.1954288237555466, 2.020410400741447),
        v(1.0162745945998537, -1.4273569966932609, 2.020410400741447),
        v(-1.7367903158337064, -1.5183433753251367, 1.9578116749672358),
        v(0.8859955046151011, -1.5183433753251367, 1.9578116749672358),
        v(0.8859955046151011, 1.1044424451236707, 1.9578116749672358),
        v(-1.7367903158337064, 1.1044424451236707, 1.9578116749672358),
    ]);
    let (x0, x1) = (-1.1014970285661103, -1.078018529727802);
    let (y0, y1) = (-0.803605513223678, -0.7625683620567426);
    let (z0, z1) = (1.9583156022225399, 1.9902535138298945);
    let cube = ConvexPolyhedron::from_mesh(
        &TriangleMesh::new(
            vec![
                v(x1, y0, z1),
                v(x1, y1, z0),
                v(x1, y1, z1),
                v(x0, y0, z0),
                v(x1, y0, z0),
                v(x0, y1, z0),
                v(x0, y0, z1),
                v(x0, y1, z1),
            ],
            vec![
                [0, 1, 2],
                [3, 1, 4],
                [1, 0, 4],
                [0, 3, 4],
                [1, 3, 5],
                [2, 1, 5],
                [3, 0, 6],
                [5, 3, 6],
                [0, 2, 6],
                [5, 6, 7],
                [6, 2, 7],
                [2, 5, 7],
            ],
        )
        .unwrap(),
    )
    .unwrap();
    let scene = Scene::new(
        vec![Light::new(sheets, DVec3::ONE).unwrap()],
        vec![cube.into()],
    )
    .unwrap();
    let x = v(-1.0922688337434285, -0.803605513222403, 1.9586336874973191);
    let n = v(0.0, 0.0, -1.0);
    let view = v(0.9987999539873287, 0.0, -0.048976034087195676);
    let m = Material::new(DVec3::splat(0.5), DVec3::splat(0.04), 0.01).unwrap();
    let per_light = |method: Method| {
        scene
            .clone()
            .with_method(method)
            .shade_per_light(x, n, view, &m)
            .unwrap()[0]
    };
    let s = per_light(Method::Silhouette);
    assert_eq!(s.shadowed(), DVec3::ZERO);
    let p = per_light(Method::PerTriangle);
    let u = p.unshadowed_diffuse.x;
    assert!(p.diffuse.x <= 1e-9 * u, "{} of {u}", p.diffuse.x);
    let us = p.unshadowed_specular.x;
    assert!(
        p.specular.x <= (1e-9 + 1e-9 / m.alpha().max(1e-4)) * us,
        "{} of {us}",
        p.specular.x
    );
    let e = MonteCarlo::new(10_000, ReferenceBrdf::Ltc)
        .with_sampling(LightSampling::Faces)
        .with_brdf_sampling()
        .estimate(&scene, x, n, view, &m, 9)
        .unwrap();
    assert_eq!(e.mean, DVec3::ZERO, "{} +- {}", e.mean, e.std_error);
}

/// Found by the `shade_regimes` fuzz target: a box light straddling the horizon of a point on
/// the ground, far in the tail of a mirror lobe seen at `cos_v = 1e-4`. Its value is `7.7e-21`
/// on the silhouette path and `7.4e-21` per triangle: 3.5% apart, but `1e-20` of what the light
/// can send at most, the integrals' rounding. The methods agree within `1e-12` of that maximum
/// (the census's and the fuzz target's floor), and the reference agrees with both.
#[test]
fn box_light_far_in_a_mirror_lobes_tail() {
    let light =
        ConvexPolyhedron::cuboid(v(12.25, 0.0, 0.0), v(1.0 / 16.0, 14.0 / 16.0, 0.5)).unwrap();
    let scene = Scene::new(
        vec![Light::new(light, DVec3::new(1.0, 0.8, 0.6)).unwrap()],
        vec![],
    )
    .unwrap();
    let x = v(11.75, 11.75, 0.0);
    let view = v(0.8314696081451971, 0.555570230241751, 0.0001);
    let m = Material::new(DVec3::ZERO, DVec3::splat(24.0 / 255.0), 0.0).unwrap();
    let look = arealight::ltc::lookup(1e-4, m.alpha()).unwrap();
    let most = look.albedo * look.specular_scale(24.0 / 255.0) / look.norm;
    let a = scene.shade(x, DVec3::Z, view, &m).unwrap();
    let b = scene
        .clone()
        .with_method(Method::PerTriangle)
        .shade(x, DVec3::Z, view, &m)
        .unwrap();
    assert!(a.x > 0.0 && a.x < 1e-18, "{a}");
    assert!((a - b).abs().max_element() <= 1e-12 * most, "{a} vs {b}");
    let e = MonteCarlo::new(10_000, ReferenceBrdf::Ltc)
        .with_sampling(LightSampling::Faces)
        .with_brdf_sampling()
        .estimate(&scene, x, DVec3::Z, view, &m, 3)
        .unwrap();
    for got in [a, b] {
        assert!(
            (got - e.mean).abs().max_element() <= 4.5 * e.std_error.max_element() + 1e-12 * most,
            "{got} vs {} +- {}",
            e.mean,
            e.std_error
        );
    }
}
