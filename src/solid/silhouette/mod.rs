//! Spherical polygons of objects seen from a point, in the [`ShadingFrame`](crate::solid::ShadingFrame):
//! the silhouette of a convex polyhedron (one polygon per point), and single mesh triangles,
//! whole or cut by a plane (the per-triangle method), and the silhouette of any closed mesh
//! (non-convex, thesis 003 section 4.3).

mod bsp;
mod convex;
mod nonconvex;
mod rings;
mod triangle;
mod triangulated;

pub use bsp::{DEFAULT_BUILD_BUDGET, DEFAULT_REGION_RADII, DirectReason, SilhouetteBsp};
pub(crate) use convex::chain_by_index;
pub use convex::{convex_silhouette, convex_silhouette_rings};
pub use nonconvex::nonconvex_silhouette;
#[allow(unused_imports)]
pub(crate) use nonconvex::{Arc, Outline, evaluate_rings, outline};
pub use rings::SilhouetteRings;
pub(crate) use triangle::clipped_triangle_polygon;
pub use triangle::{TriangleRole, triangle_polygon};
pub use triangulated::{SilhouetteSampler, TriangleSource};

#[cfg(test)]
mod tests {
    use super::*;
    use crate::solid::{ConvexPolyhedron, ShadingFrame, TriangleMesh};
    use crate::sphere::SphericalPolygon;
    use alloc::vec;
    use alloc::vec::Vec;
    use core::f64::consts::PI;
    use glam::DVec3;

    #[test]
    fn cube_face_on_subtends_its_solid_angle() {
        // Unit cube centered 2 above the origin: seen from below, only the bottom face, a square
        // of side 1 at distance 1.5. Solid angle of a square (side 2a) at distance d:
        // 4 asin(a^2 / (a^2 + d^2)).
        let cube = ConvexPolyhedron::cuboid(DVec3::new(0.0, 0.0, 2.0), DVec3::splat(0.5)).unwrap();
        let f = ShadingFrame::new(DVec3::ZERO, DVec3::Z, DVec3::Z).unwrap();
        let p = convex_silhouette(&cube, &f).unwrap();
        let (a, d) = (0.5f64, 1.5f64);
        let expect = 4.0 * (a * a / (a * a + d * d)).asin();
        assert!(
            (p.solid_angle() - expect).abs() < 1e-12,
            "{}",
            p.solid_angle()
        );
        assert!(p.contains(DVec3::Z));
        // Inside: full sphere.
        let fi = ShadingFrame::new(DVec3::new(0.0, 0.0, 2.0), DVec3::Z, DVec3::Z).unwrap();
        assert!(convex_silhouette(&cube, &fi).unwrap().is_full());
        // On the bottom face (a ground point under a cube standing on it): the upper hemisphere.
        let fb = ShadingFrame::new(DVec3::new(0.1, 0.2, 1.5), DVec3::Z, DVec3::Z).unwrap();
        let pb = convex_silhouette(&cube, &fb).unwrap();
        assert!((pb.solid_angle() - 2.0 * PI).abs() < 1e-12 && pb.contains(DVec3::Z));
        // On a bottom edge: a quarter of the sphere.
        let fe = ShadingFrame::new(DVec3::new(0.5, 0.2, 1.5), DVec3::Z, DVec3::Z).unwrap();
        let pe = convex_silhouette(&cube, &fe).unwrap();
        assert!(
            (pe.solid_angle() - PI).abs() < 1e-12,
            "{}",
            pe.solid_angle()
        );
        // In the plane of the bottom face (a cube standing on the ground), off to the side.
        let fg = ShadingFrame::new(DVec3::new(2.0, 0.0, 1.5), DVec3::Z, DVec3::Z).unwrap();
        let pg = convex_silhouette(&cube, &fg).unwrap();
        assert!(pg.solid_angle() > 0.0 && pg.solid_angle() < 2.0 * PI);
    }

    #[test]
    fn a_cut_triangle_splits_its_solid_angle() {
        // The parts of a triangle on either side of a plane cover, together, what the triangle
        // covers: solid angles add up, for cuts through edges and through a corner, seen from
        // both sides; a triangle in the plane, or behind it, covers nothing.
        let f = ShadingFrame::new(DVec3::new(0.1, -0.2, 0.0), DVec3::Z, DVec3::X).unwrap();
        let mut seed = 0x2545_f491_4f6c_dd1d_u64;
        let mut next = || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            (seed >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        };
        for case in 0..200 {
            let c = DVec3::new(next(), next(), 2.0 + next());
            let mut v: Vec<DVec3> = (0..3)
                .map(|_| c + DVec3::new(next(), next(), next()))
                .collect();
            let n = DVec3::new(next(), next(), next()).normalize();
            let mut a = c + DVec3::new(next(), next(), next()) * 0.3;
            if case % 4 == 0 {
                a = v[0]; // the plane through a corner
            }
            if case % 2 == 1 {
                v.swap(1, 2); // seen from the back
            }
            let mesh = TriangleMesh::new(v, vec![[0, 1, 2]]).unwrap();
            let whole = triangle_polygon(&mesh, 0, &f, TriangleRole::Blocker)
                .unwrap()
                .map_or(0.0, |p| p.solid_angle());
            let d = mesh.triangle(0).map(|p| n.dot(p - a));
            // Every corner of a part, taken back to the triangle's plane along its ray, lies on
            // the kept side of the cutting plane (`sign` 1: n . (q - a) >= 0, -1: <= 0).
            let (tn, t0) = (mesh.triangle_normal(0), mesh.triangle(0)[0]);
            let on_side = |p: &SphericalPolygon, sign: f64| {
                p.rings().flatten().all(|&l| {
                    let w = f.dir_to_world(l);
                    let q = f.origin() + w * (tn.dot(t0 - f.origin()) / tn.dot(w));
                    sign * n.dot(q - a) >= -1e-12
                })
            };
            let part = |d: [f64; 3], sign: f64| {
                let p = clipped_triangle_polygon(&mesh, 0, d, &f).unwrap();
                assert!(p.as_ref().is_none_or(|p| on_side(p, sign)), "case {case}");
                p.map_or(0.0, |p| p.solid_angle())
            };
            let (pos, neg) = (part(d, 1.0), part(d.map(|x| -x), -1.0));
            assert!(
                (pos + neg - whole).abs() <= 1e-12 * (1.0 + whole),
                "case {case}: {pos} + {neg} vs {whole}"
            );
            assert!(part([0.0; 3], 1.0) == 0.0 && part([-1.0, -2.0, 0.0], 1.0) == 0.0);
            assert!(
                (clipped_triangle_polygon(&mesh, 0, [1.0, 0.0, 2.0], &f)
                    .unwrap()
                    .map_or(0.0, |p| p.solid_angle())
                    - whole)
                    .abs()
                    <= 1e-15
            );
        }
    }

    #[test]
    fn per_triangle_sum_equals_silhouette_for_convex() {
        let ico = ConvexPolyhedron::icosphere(DVec3::new(0.3, -0.2, 3.0), 1.0, 1).unwrap();
        let f = ShadingFrame::new(DVec3::new(0.1, 0.2, 0.0), DVec3::Z, DVec3::X).unwrap();
        let sil = convex_silhouette(&ico, &f).unwrap().solid_angle();
        let sum: f64 = (0..ico.mesh().triangle_count())
            .filter_map(|i| triangle_polygon(ico.mesh(), i, &f, TriangleRole::Emitter).unwrap())
            .map(|p| p.solid_angle())
            .sum();
        assert!((sil - sum).abs() < 1e-12, "{sil} {sum}");
    }
}
