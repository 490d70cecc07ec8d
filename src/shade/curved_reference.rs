//! The Monte Carlo reference for lights bounded by Bezier curves: uniform area samples of the
//! exact curved region ([`BezierShape::sample`]), not of its flattening, so that the analytic
//! path's flattening is checked too. The frame, the BRDF and the brute-force visibility are the
//! other lights' ([`PointSampler`]).

use glam::DVec3;

use super::reference::{Pcg32, PointSampler};
use crate::solid::BezierShape;

/// The mean and the variance of the mean of `n` samples of light `light`'s contribution (its
/// body `shape`; `two_sided` as [`super::Light::is_two_sided`]) at the sampler's point, per unit
/// radiance: `brdf(l) A |cos(theta_light)| / d^2` for an area sample at distance `d` seen in
/// local direction `l`, zero where blocked by another object (a planar light cannot hide
/// itself).
pub(super) fn estimate(
    ps: &PointSampler<'_>,
    light: usize,
    shape: &BezierShape,
    two_sided: bool,
    n: u32,
    rng: &mut Pcg32,
) -> (DVec3, DVec3) {
    let frame = ps.frame();
    let x = frame.origin();
    // The emitting side the point sees: the front, or the back of a two-sided light. Points
    // within the shape's tolerance of its plane see it edge-on, as the analytic path.
    let side = if shape.faces(x) {
        1.0
    } else if two_sided && shape.faces_back(x) {
        -1.0
    } else {
        return (DVec3::ZERO, DVec3::ZERO);
    };
    let area = shape.area();
    let normal = shape.normal() * side;
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
        if !(cos_light > 0.0) || !(l.z > 0.0) || ps.blocked(light, w, d) {
            continue;
        }
        let f = ps.brdf(l) * (area * cos_light / d2);
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
