//! Shading-point generators: points on the triangles of a mesh (where occluder surfaces are
//! shaded) and views above a surface.

use super::Rng;
use arealight::glam::DVec3;
use arealight::shade::TriangleMesh;

/// A uniform point of a random triangle of `mesh` (barycentric, folded into the triangle) and
/// that triangle's normal.
pub fn point_on_mesh(rng: &mut Rng, mesh: &TriangleMesh) -> (DVec3, DVec3) {
    let t = rng.below(mesh.triangle_count());
    let [a, b, c] = mesh.triangle(t);
    let (mut u, mut v) = (rng.f64(), rng.f64());
    if u + v > 1.0 {
        (u, v) = (1.0 - u, 1.0 - v);
    }
    (a + u * (b - a) + v * (c - a), mesh.triangle_normal(t))
}

/// A point of the square `[-h, h]^2` of the ground plane `z = 0`.
pub fn ground_point(rng: &mut Rng, h: f64) -> DVec3 {
    DVec3::new(rng.range(-h, h), rng.range(-h, h), 0.0)
}

/// A unit view direction whose cosine with the unit normal `n` is uniform in `[cos_min, 1)`,
/// with a uniform azimuth.
pub fn view_above(rng: &mut Rng, n: DVec3, cos_min: f64) -> DVec3 {
    let cos_v = rng.range(cos_min, 1.0);
    let phi = rng.range(0.0, std::f64::consts::TAU);
    let (t, b) = n.any_orthonormal_pair();
    let s = (1.0 - cos_v * cos_v).sqrt();
    n * cos_v + (t * phi.cos() + b * phi.sin()) * s
}
