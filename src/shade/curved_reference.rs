//! The Monte Carlo reference for lights bounded by Bezier curves: uniform area samples of the
//! exact curved region ([`BezierShape::sample`]), not of its flattening, so that the analytic
//! path's flattening is checked too.

use glam::DVec3;

use super::reference::{Pcg32, RAY_EPS, ray_meets_sphere, ray_triangle};
use crate::solid::{BezierShape, BoundingSphere, ShadingFrame, TriangleMesh};

/// The mean and the variance of the mean of `n` samples of the light's contribution at the
/// frame's point, per unit radiance: `brdf(l) A cos(theta_light) / d^2` for an area sample at
/// distance `d` seen in local direction `l`, zero where blocked. `blockers` are every object's
/// triangles with a bounding sphere, and the index of the light's own entry, skipped (a planar
/// light cannot hide itself).
pub(super) fn estimate(
    shape: &BezierShape,
    frame: &ShadingFrame,
    n: u32,
    rng: &mut Pcg32,
    brdf: &dyn Fn(DVec3) -> DVec3,
    (blockers, own): (&[(&TriangleMesh, BoundingSphere)], usize),
) -> (DVec3, DVec3) {
    let x = frame.origin();
    if !shape.faces(x) {
        return (DVec3::ZERO, DVec3::ZERO);
    }
    let area = shape.area();
    let normal = shape.normal();
    let (mut sum, mut sum2) = (DVec3::ZERO, DVec3::ZERO);
    for _ in 0..n {
        // A region that rejects 10 000 points in a row is vanishingly rare; such a sample
        // counts as zero.
        let Some(p) = shape.sample(|| rng.next_f64()) else {
            continue;
        };
        let to = p - x;
        let d2 = to.length_squared();
        let d = crate::math::sqrt(d2);
        let w = to / d;
        let cos_light = -normal.dot(w);
        let l = frame.dir_to_local(w);
        if !(cos_light > 0.0) || !(l.z > 0.0) {
            continue;
        }
        let (t_min, t_max) = (d * RAY_EPS, d * (1.0 - RAY_EPS));
        let blocked = blockers.iter().enumerate().any(|(j, &(m, b))| {
            j != own
                && ray_meets_sphere(x, w, b.center, b.radius, t_max)
                && (0..m.triangle_count()).any(|k| {
                    ray_triangle(x, w, m.triangle(k)).is_some_and(|t| t > t_min && t < t_max)
                })
        });
        if blocked {
            continue;
        }
        let f = brdf(l) * (area * cos_light / d2);
        sum += f;
        sum2 += f * f;
    }
    let nf = f64::from(n);
    let m = sum / nf;
    let s2 = if n > 1 {
        ((sum2 - sum * m) / (nf - 1.0)).max(DVec3::ZERO)
    } else {
        DVec3::ZERO
    };
    (m, s2 / nf)
}
