//! An exact arbiter between visibility answers: rays cast over a light, compared with membership
//! in the answers' regions (no code shared with either backend).

use super::Rng;
use arealight::glam::DVec3;
use arealight::shade::{Scene, ShadingFrame, TriangleMesh};
use arealight::sphere::{SphericalPolygon, SphericalTriangle};

/// Möller–Trumbore: the distance `t > 0` along `dir` from `orig` to the triangle, if the ray
/// meets it (written here so that the arbiter below shares no code with either backend).
pub fn ray_triangle(orig: DVec3, dir: DVec3, [a, b, c]: [DVec3; 3]) -> Option<f64> {
    let (e1, e2) = (b - a, c - a);
    let p = dir.cross(e2);
    let det = e1.dot(p);
    if det == 0.0 || !det.is_finite() {
        return None;
    }
    let s = orig - a;
    let u = s.dot(p) / det;
    let q = s.cross(e1);
    let v = dir.dot(q) / det;
    if !(0.0..=1.0).contains(&u) || v < 0.0 || u + v > 1.0 {
        return None;
    }
    let t = e2.dot(q) / det;
    (t > 0.0).then_some(t)
}

/// An exact arbiter between two answers for light `light`: directions uniform in solid angle
/// over the light's front triangles (as the Monte Carlo reference samples them), each cast as a
/// ray against every triangle of every other object and of the light itself (every object
/// opaque; hits within `1e-9` of the ray's relative length from either end are the ray's own
/// ends, as in the reference), and compared with membership in each answer's pieces. Returns,
/// per answer, the samples where the ray's verdict and the answer's disagree. A correct answer
/// disagrees only on samples within rounding of a region or blocker boundary (measure zero); a
/// wrong part of measure `delta` of the light's solid angle `omega` shows in about
/// `samples delta / omega` samples.
pub fn mismatches(
    scene: &Scene,
    frame: &ShadingFrame,
    light: usize,
    answers: [&[SphericalPolygon]; 2],
    samples: usize,
    seed: u64,
) -> [usize; 2] {
    let x = frame.origin();
    let lm = scene.lights()[light].shape().mesh();
    let mut tris = Vec::new();
    let mut cdf = Vec::new();
    let mut total = 0.0;
    for i in 0..lm.triangle_count() {
        let [a, b, c] = lm.triangle(i);
        if lm.triangle_normal(i).dot(x - (a + b + c) / 3.0) <= 0.0 {
            continue;
        }
        if let Ok(t) = SphericalTriangle::new(a - x, b - x, c - x) {
            total += t.solid_angle();
            tris.push((t, i));
            cdf.push(total);
        }
    }
    let mut out = [0; 2];
    if tris.is_empty() {
        return out;
    }
    let objects: Vec<(usize, &TriangleMesh)> = scene
        .occluders()
        .iter()
        .map(|o| o.mesh())
        .chain(scene.lights().iter().map(|l| l.shape().mesh()))
        .enumerate()
        .collect();
    let own = scene.occluders().len() + light;
    let mut rng = Rng::new(seed);
    for _ in 0..samples {
        let pick = rng.f64() * total;
        let k = cdf.partition_point(|&c| c <= pick).min(tris.len() - 1);
        let (tri, ti) = tris[k];
        let w = tri.sample(rng.point2());
        let l = frame.dir_to_local(w);
        if l.z <= 0.0 {
            continue;
        }
        let nn = lm.triangle_normal(ti);
        let t_light = nn.dot(lm.triangle(ti)[0] - x) / nn.dot(w);
        if t_light.is_nan() || t_light <= 0.0 {
            continue;
        }
        let (t_min, t_max) = (t_light * 1e-9, t_light * (1.0 - 1e-9));
        let blocked = objects.iter().any(|&(j, m)| {
            (0..m.triangle_count()).any(|t| {
                !(j == own && t == ti)
                    && ray_triangle(x, w, m.triangle(t)).is_some_and(|t| t > t_min && t < t_max)
            })
        });
        for (a, pieces) in answers.iter().enumerate() {
            let inside = pieces.iter().any(|p| p.contains(l));
            if inside == blocked {
                out[a] += 1;
            }
        }
    }
    out
}
