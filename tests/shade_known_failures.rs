//! Known failures of the spherical boolean met by the shading layer's per-triangle path, kept as
//! ignored regression tests for the `sphere` layer (run with `cargo test -- --ignored`).
//!
//! Found by running the per-triangle method over 3000 ground points of the demo scene: 16 of
//! 2.4 million triangle differences failed. This one is light-minus-occluder-triangle where the
//! triangle (an occluder face seen from a ground point) shares, up to 1e-15, an edge with the
//! current visible region (which that face's neighbour cut earlier).

use arealight::glam::DVec3;
use arealight::planar::BoolOp;
use arealight::sphere::SphericalPolygon;

#[test]
#[ignore = "sphere layer: boolean difference with a nearly shared edge reports Degenerate"]
fn difference_with_nearly_shared_edge() {
    let a = SphericalPolygon::new(vec![vec![
        DVec3::new(-0.6690880280221996, -0.1568454495401529, 0.7264438833908037),
        DVec3::new(
            -0.5626500404802729,
            -0.21021721592028306,
            0.7995208903326244,
        ),
        DVec3::new(-0.5537970634980699, -0.14639720242518545, 0.819680835193183),
        DVec3::new(
            -0.5596900797691979,
            -0.14691706044559386,
            0.8155748843349545,
        ),
        DVec3::new(-0.603541450890866, -0.1359192926164673, 0.785661290220657),
        DVec3::new(
            -0.6444013730021253,
            -0.11284483557928683,
            0.7563153532462894,
        ),
    ]])
    .unwrap();
    let b = SphericalPolygon::new(vec![vec![
        DVec3::new(-0.6035414508908648, -0.13591929261646715, 0.785661290220658),
        DVec3::new(
            -0.6444013730021242,
            -0.11284483557928654,
            0.7563153532462903,
        ),
        DVec3::new(
            -0.6913513594738174,
            -0.20005646227339818,
            0.6942699112422752,
        ),
    ]])
    .unwrap();
    let d = a.boolean(&b, BoolOp::Difference).unwrap();
    let i = a.boolean(&b, BoolOp::Intersection).unwrap();
    assert!((d.solid_angle() + i.solid_angle() - a.solid_angle()).abs() < 1e-12);
}
