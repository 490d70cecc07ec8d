//! A pinhole camera and brute-force ray casting against triangles: primary visibility for the
//! scene-file examples (a few hundred triangles; no acceleration structure needed).

use arealight::glam::DVec3;
use arealight::shade::Material;

/// What a camera ray sees first.
pub enum Hit {
    /// Nothing (the background).
    Nothing,
    /// A light's emitting side: its radiance.
    Emitter(DVec3),
    /// A shaded surface: point, normal, view, material.
    Surface(DVec3, DVec3, DVec3, Material),
}

/// A pinhole camera looking from `eye` at `target`, `up` roughly up, vertical field of view
/// `fov_deg`.
pub struct Camera {
    pub eye: DVec3,
    fwd: DVec3,
    right: DVec3,
    up: DVec3,
    tan_half: f64,
}

impl Camera {
    pub fn new(eye: DVec3, target: DVec3, up: DVec3, fov_deg: f64) -> Self {
        let fwd = (target - eye).normalize();
        let right = fwd.cross(up).normalize();
        let up = right.cross(fwd);
        Camera {
            eye,
            fwd,
            right,
            up,
            tan_half: (fov_deg.to_radians() / 2.0).tan(),
        }
    }

    /// The unit direction through pixel position `(px, py)` (pixels, from the top left) of a
    /// `w x h` image.
    pub fn ray(&self, px: f64, py: f64, w: usize, h: usize) -> DVec3 {
        let aspect = w as f64 / h as f64;
        let sx = (2.0 * px / w as f64 - 1.0) * self.tan_half * aspect;
        let sy = (1.0 - 2.0 * py / h as f64) * self.tan_half;
        (self.fwd + sx * self.right + sy * self.up).normalize()
    }
}

/// Where a ray meets a triangle: distance and barycentric weights of corners 1 and 2
/// (Moeller-Trumbore), for distances above `1e-9`.
pub fn ray_triangle(o: DVec3, d: DVec3, [a, b, c]: [DVec3; 3]) -> Option<(f64, f64, f64)> {
    let e1 = b - a;
    let e2 = c - a;
    let p = d.cross(e2);
    let det = e1.dot(p);
    if det.abs() < 1e-300 {
        return None;
    }
    let s = o - a;
    let u = s.dot(p) / det;
    if !(0.0..=1.0).contains(&u) {
        return None;
    }
    let q = s.cross(e1);
    let v = d.dot(q) / det;
    if v < 0.0 || u + v > 1.0 {
        return None;
    }
    let t = e2.dot(q) / det;
    (t > 1e-9).then_some((t, u, v))
}

/// The nearest hit of a ray among triangle lists: `(list, triangle, distance, u, v)`.
pub fn nearest<'a>(
    o: DVec3,
    d: DVec3,
    lists: impl Iterator<Item = (usize, &'a [DVec3], &'a [[u32; 3]])>,
) -> Option<(usize, usize, f64, f64, f64)> {
    let mut best: Option<(usize, usize, f64, f64, f64)> = None;
    for (k, pos, tris) in lists {
        for (t, tri) in tris.iter().enumerate() {
            let corners = tri.map(|i| pos[i as usize]);
            if let Some((dist, u, v)) = ray_triangle(o, d, corners)
                && best.is_none_or(|b| dist < b.2)
            {
                best = Some((k, t, dist, u, v));
            }
        }
    }
    best
}
