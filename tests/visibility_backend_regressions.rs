//! Failures of the clipping backend found by comparing it with the Pluecker backend and exact
//! rays, whose cause lay outside the `visibility` layer (all fixed now; none is ignored).

use arealight::glam::DVec3;
use arealight::internals::{TriangleRole, triangle_polygon};
use arealight::shade::{Light, Scene, ShadingFrame, TriangleMesh};
use arealight::sphere::SphericalPolygon;
use arealight::visibility::Visibility;
use arealight::visibility::plucker::PluckerVisibility;

mod support;

use support::visibility::mismatches;

/// A terrain point under a low quad light, and one triangle of the terrain next to it whose
/// vertex `t[0]` lies 8e-17 above the point's tangent plane (a vertex the point's own triangle
/// shares with it, up to rounding), the other two 0.06 below. Minimized from the benches'
/// terrain of 9.8K triangles, where 18 of 12720 queries give up with `Undecidable`.
fn scene() -> (Scene, ShadingFrame, TriangleMesh) {
    let t = vec![
        DVec3::new(
            -0.8000000000000003,
            1.1428571428571423,
            -0.09863617043921438,
        ),
        DVec3::new(
            -0.6857142857142859,
            1.2571428571428571,
            -0.05209060811094356,
        ),
        DVec3::new(-0.8000000000000003, 1.2571428571428571, -0.0647685235598502),
    ];
    let x = DVec3::new(-0.8058513346244496, 1.1416881874042106, -0.1006342637852814);
    let n = DVec3::new(
        -0.09780005645882967,
        -0.7072476944934483,
        0.7001684422982458,
    );
    let quad = TriangleMesh::quad(DVec3::new(2.2, 0.3, 1.9), DVec3::Y * 0.4, DVec3::X * 0.4);
    let tri = TriangleMesh::new(t, vec![[0, 1, 2]]).unwrap();
    let light = Light::new(quad.unwrap(), DVec3::ONE).unwrap();
    let scene = Scene::new(vec![light], vec![tri.clone().into()]).unwrap();
    (scene, ShadingFrame::new(x, n, n).unwrap(), tri)
}

/// Layer: `sphere` (`SphericalPolygon::clip_to_hemisphere`, issue 24).
///
/// The triangle hides nothing of the light (its only point above the horizon is the vertex
/// 8e-17 above it): the Pluecker backend returns the whole light (0.0253 sr) and every ray
/// agrees. The clipping backend gives up with `Undecidable` ("the horizon clip of a region
/// added a horizon arc outside the region"): projected from the point, the triangle is a valid
/// spherical triangle of 0.0678 sr with one vertex at `z = 1.3e-14` and two well below, and its
/// `clip_to_hemisphere(+z)` is a six-vertex ring of solid angle `2 pi` (the exit and entry
/// points a rounding apart, joined the long way round the horizon): the whole upper
/// hemisphere instead of (nearly) nothing. `visibility::clip`'s `upper_part` check catches it
/// and gives up; before that check (branch point of wip-plucker) the backend returned 0 sr, a
/// silently wrong value. Fixed in the sphere layer (the exact order of the crossings).
#[test]
fn a_blocker_touching_the_horizon_at_one_vertex_is_decided() {
    let (scene, f, tri) = scene();
    let pl = PluckerVisibility::from_clip(scene.visibility().clone());
    let sa = |p: &[SphericalPolygon]| p.iter().map(SphericalPolygon::solid_angle).sum::<f64>();
    let full = sa(&pl.unoccluded_region(0, &f).unwrap());
    let lazy = pl.visible_region(0, &f).unwrap();
    assert!((sa(&lazy) - full).abs() <= 1e-12 * full && full > 0.025);
    assert_eq!(mismatches(&scene, &f, 0, [&lazy, &lazy], 4096, 1), [0, 0]);
    // The sphere layer's step alone: the upper part of a polygon is part of it.
    let p = triangle_polygon(&tri, 0, &f, TriangleRole::Blocker)
        .unwrap()
        .unwrap();
    let up = p.clip_to_hemisphere(DVec3::Z);
    assert!(
        up.solid_angle() <= p.solid_angle() * (1.0 + 1e-12),
        "upper part {} sr of a {} sr polygon",
        up.solid_angle(),
        p.solid_angle()
    );
    let clip = scene.visibility().visible_region(0, &f).unwrap();
    assert!((sa(&clip) - full).abs() <= 1e-9 * full);
}
