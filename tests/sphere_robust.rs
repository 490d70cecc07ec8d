//! Named regressions of issue 24 ("never a silently wrong value"), sphere layer: each reproducer
//! of the issue and each minimized failure of the robustness generators
//! (`tests/sphere_robust_props.rs`, `fuzz/fuzz_targets/sphere_*`), checked against a value
//! computed independently (closed form, exact identity, or a reference clip written here).

use arealight::glam::DVec3;
use arealight::sphere::SphericalPolygon;

fn v(x: f64, y: f64, z: f64) -> DVec3 {
    DVec3::new(x, y, z)
}

/// Issue 24, reproducer 1: a triangle with one vertex `h = 1e-13` above the horizon and two
/// below. The part above is the tiny triangle cut off near the apex; in the gnomonic plane about
/// `+x` (great circles are lines, the horizon is the line `t = 0`) it has the apex `(0, h)` and
/// its base on `t = 0` at `y = +-0.3 h / (0.3 + h)`, so its planar area is
/// `A = 0.3 h^2 / (0.3 + h)`. Its solid angle is the integral of `(1 + r^2)^-3/2` over it, within
/// `1.5 r^2 < 1e-25` (relative) of `A`; its clamped-cosine integral is `(1/pi)` times the
/// integral of `t / (1 + r^2)^2`, within as little of `A * (h / 3) / pi` (the centroid's height).
/// Before the fix the clip returned the whole upper hemisphere (2 pi) and the integral was 1.
#[test]
fn issue24_repro1_vertex_just_above_the_horizon() {
    for h in [1e-13, 3e-14, 1.5e-14, 2e-13, 1e-12] {
        let p = SphericalPolygon::new(vec![vec![
            v(1.0, 0.0, h),
            v(1.0, -0.3, -0.3),
            v(1.0, 0.3, -0.3),
        ]])
        .unwrap();
        let clipped = p.clip_to_hemisphere(DVec3::Z);
        let area = 0.3 * h * h / (0.3 + h);
        let w = clipped.solid_angle();
        assert!(
            (w - area).abs() <= 1e-6 * area,
            "h = {h:e}: {w:e} sr vs {area:e}"
        );
        // The integral is far below what its sum of edge terms can resolve (about 1e-16 per
        // term): the check is that it is that small, not 1.
        let expect = area * (h / 3.0) / std::f64::consts::PI;
        for cc in [
            arealight::ltc::clamped_cosine_integral(&p),
            arealight::ltc::clamped_cosine_integral(&clipped),
        ] {
            assert!(
                (cc - expect).abs() <= 1e-15,
                "h = {h:e}: {cc:e} vs {expect:e}"
            );
        }
    }
}
