//! The clipping backend on blockers that touch a light's plane: a box hanging from a quad light,
//! its top face in the light's plane. That face hides nothing (a ray meets it where it meets the
//! light), so from a point inside the box, or on its surface with a hemisphere that looks into
//! it, the light is seen through the top face. Checked against the exact ray arbiter
//! (`support::visibility::mismatches`: rays over the light against every triangle, compared with
//! membership in the regions) and against the Pluecker backend, for the box as a convex
//! polyhedron and as a plain mesh, under both methods.

use arealight::glam::DVec3;
use arealight::shade::{Body, ConvexPolyhedron, Light, Method, Scene, ShadingFrame, TriangleMesh};
use arealight::sphere::SphericalPolygon;
use arealight::visibility::Visibility;
use arealight::visibility::plucker::PluckerVisibility;

mod support;

use support::Rng;
use support::visibility::mismatches;

fn solid_angle(p: &[SphericalPolygon]) -> f64 {
    p.iter().map(SphericalPolygon::solid_angle).sum()
}

#[test]
fn a_box_hanging_from_a_quad_light_hides_nothing_through_its_top_face() {
    // Before the fix the box was subtracted whole (its hull touches the light's, so a
    // separating plane exists, and every vertex is on the point's side or on the plane): from
    // its centre the clipping backend returned 0 sr where the rays see 1.89 sr of the light
    // (1741 of 4096 rays disagreeing), and from its side faces with tilted normals 0.75 sr for
    // 1.89.
    let quad = TriangleMesh::quad(DVec3::new(-0.3, 0.0, 2.5), DVec3::Y * 0.6, DVec3::X * 0.6);
    let cuboid = ConvexPolyhedron::cuboid(DVec3::new(-0.1, 0.2, 2.3), DVec3::new(0.25, 0.2, 0.2));
    let (quad, cuboid) = (quad.unwrap(), cuboid.unwrap());
    let mut rng = Rng::new(61);
    let mut checked = 0;
    let mut seen_through = 0;
    for method in [Method::Silhouette, Method::PerTriangle] {
        for (name, body) in [
            ("convex", Body::from(cuboid.clone())),
            ("mesh", Body::Mesh(cuboid.mesh().clone())),
        ] {
            let light = Light::new(quad.clone(), DVec3::ONE).unwrap();
            let scene = Scene::new(vec![light], vec![body])
                .unwrap()
                .with_method(method);
            let clip = scene.visibility();
            let pl = PluckerVisibility::from_clip(clip.clone());
            let m = cuboid.mesh();
            for k in 0..40 {
                // Inside, on a face (a point of a random triangle), or at the top face.
                let x = match k % 3 {
                    0 => {
                        DVec3::new(-0.1, 0.2, 2.3)
                            + DVec3::new(
                                rng.range(-0.24, 0.24),
                                rng.range(-0.19, 0.19),
                                rng.range(-0.19, 0.19),
                            )
                    }
                    1 => support::shade::point_on_mesh(&mut rng, m).0,
                    _ => DVec3::new(rng.range(-0.3, 0.1), rng.range(0.05, 0.35), 2.5),
                };
                let f = ShadingFrame::new(x, rng.dir(), rng.dir()).unwrap();
                let c = clip.visible_region(0, &f).unwrap();
                let p = pl.visible_region(0, &f).unwrap();
                let full = solid_angle(&clip.unoccluded_region(0, &f).unwrap());
                let rays = mismatches(&scene, &f, 0, [&c, &p], 2048, k);
                let what = format!("{method:?} {name} x {x} n {}", f.normal());
                assert!(rays[0] <= 3, "clip: {rays:?} ray mismatches, {what}");
                assert!(
                    (solid_angle(&c) - solid_angle(&p)).abs() <= 1e-9 * full.max(1e-6),
                    "clip {} plucker {}, {what}",
                    solid_angle(&c),
                    solid_angle(&p)
                );
                checked += 1;
                seen_through += usize::from(k % 3 == 0 && solid_angle(&c) > 0.0);
            }
        }
    }
    assert_eq!(checked, 160);
    // The interior points that see some of the light through the top face: the case is there.
    assert!(seen_through >= 20, "{seen_through}");
}
