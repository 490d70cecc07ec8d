//! The primitives of the seed paper's test scene (000, Fig. 4): quads, boxes, subdivided
//! icosahedra, latitude-longitude ellipsoids and truncated cones.

use alloc::vec;
use alloc::vec::Vec;
use core::f64::consts::PI;

use glam::DVec3;

use super::convex::ConvexPolyhedron;
use super::mesh::{MAX_MESH_COORD, TriangleMesh};
use crate::GeomError;
use crate::math::{sin_cos, sqrt};

/// Checks that a vector argument named `what` is finite.
fn finite(v: DVec3, what: &'static str) -> Result<(), GeomError> {
    if v.is_finite() {
        Ok(())
    } else {
        Err(GeomError::NonFiniteArgument { what })
    }
}

/// Checks that every component of the radii argument named `what` is positive and finite.
fn positive(radii: DVec3, what: &'static str) -> Result<(), GeomError> {
    finite(radii, what)?;
    let m = radii.min_element();
    if m > 0.0 {
        Ok(())
    } else {
        Err(GeomError::OutOfRange {
            what,
            value: m,
            limit: MAX_MESH_COORD,
        })
    }
}

impl TriangleMesh {
    /// A planar quad light or occluder: the parallelogram `center +- u +- v`, two triangles,
    /// facing `u x v` (counter-clockwise seen from that side).
    ///
    /// # Errors
    ///
    /// [`GeomError::NonFiniteArgument`] for a NaN or infinite argument; as
    /// [`TriangleMesh::new`] otherwise: a corner out of range, or `u` and `v` (nearly) parallel
    /// ([`GeomError::DegenerateTriangle`]).
    pub fn quad(center: DVec3, u: DVec3, v: DVec3) -> Result<Self, GeomError> {
        finite(center, "quad center")?;
        finite(u, "quad half-edge u")?;
        finite(v, "quad half-edge v")?;
        TriangleMesh::new(
            vec![
                center - u - v,
                center + u - v,
                center + u + v,
                center - u + v,
            ],
            vec![[0, 1, 2], [0, 2, 3]],
        )
    }
}

impl ConvexPolyhedron {
    /// An axis-aligned box `center +- half_extents` (8 vertices, 12 triangles).
    ///
    /// # Errors
    ///
    /// [`GeomError::NonFiniteArgument`] for a NaN or infinite argument, a corner out of range
    /// ([`GeomError::OutOfRange`]), or a (nearly) zero extent ([`GeomError::Degenerate`]).
    pub fn cuboid(center: DVec3, half_extents: DVec3) -> Result<Self, GeomError> {
        finite(center, "cuboid center")?;
        finite(half_extents, "cuboid half extents")?;
        let h = half_extents;
        let pts: Vec<DVec3> = (0..8)
            .map(|i| {
                center
                    + DVec3::new(
                        if i & 1 == 0 { -h.x } else { h.x },
                        if i & 2 == 0 { -h.y } else { h.y },
                        if i & 4 == 0 { -h.z } else { h.z },
                    )
            })
            .collect();
        ConvexPolyhedron::hull(&pts)
    }

    /// A sphere approximated by an icosahedron subdivided `subdivisions` times (12, 42, 162, ...
    /// vertices), with every vertex on the sphere.
    ///
    /// # Errors
    ///
    /// [`GeomError::NonFiniteArgument`] for a NaN or infinite center or radius;
    /// [`GeomError::OutOfRange`] for a radius that is not positive, for vertices out of range,
    /// and for `subdivisions > 5` (over 10 000 vertices: use a mesh instead).
    pub fn icosphere(center: DVec3, radius: f64, subdivisions: u32) -> Result<Self, GeomError> {
        ConvexPolyhedron::ellipsoid_icosphere(center, DVec3::splat(radius), subdivisions)
    }

    /// As [`ConvexPolyhedron::icosphere`], scaled by `radii` along the axes.
    ///
    /// # Errors
    ///
    /// As [`ConvexPolyhedron::icosphere`].
    pub fn ellipsoid_icosphere(
        center: DVec3,
        radii: DVec3,
        subdivisions: u32,
    ) -> Result<Self, GeomError> {
        finite(center, "icosphere center")?;
        positive(radii, "icosphere radius (positive)")?;
        if subdivisions > 5 {
            return Err(GeomError::OutOfRange {
                what: "icosphere subdivisions",
                value: f64::from(subdivisions),
                limit: 5.0,
            });
        }
        let pts = icosphere_points(subdivisions);
        ConvexPolyhedron::hull(&pts.iter().map(|&p| center + p * radii).collect::<Vec<_>>())
    }

    /// An ellipsoid with semi-axes `radii` as a latitude-longitude polyhedron: two poles and
    /// `rings x segments` vertices (the seed paper's ellipsoid has 154 vertices, e.g. 8 x 19 + 2).
    ///
    /// # Errors
    ///
    /// [`GeomError::NonFiniteArgument`] for a NaN or infinite center or radius;
    /// [`GeomError::OutOfRange`] for a radius that is not positive, `rings < 1` or
    /// `segments < 3`.
    pub fn ellipsoid(
        center: DVec3,
        radii: DVec3,
        rings: u32,
        segments: u32,
    ) -> Result<Self, GeomError> {
        finite(center, "ellipsoid center")?;
        positive(radii, "ellipsoid radius (positive)")?;
        if rings < 1 || segments < 3 || rings > 1000 || segments > 1000 {
            return Err(GeomError::OutOfRange {
                what: "ellipsoid rings (>= 1) or segments (>= 3), each at most",
                value: f64::from(rings.min(segments)),
                limit: 1000.0,
            });
        }
        let mut pts = vec![
            center + DVec3::new(0.0, 0.0, radii.z),
            center - DVec3::new(0.0, 0.0, radii.z),
        ];
        for r in 1..=rings {
            let (st, ct) = sin_cos(PI * f64::from(r) / f64::from(rings + 1));
            for s in 0..segments {
                let (sp, cp) = sin_cos(2.0 * PI * f64::from(s) / f64::from(segments));
                pts.push(center + radii * DVec3::new(st * cp, st * sp, ct));
            }
        }
        ConvexPolyhedron::hull(&pts)
    }

    /// A truncated cone (frustum) along `axis` from `base` (radius `r0`) to `base + axis` (radius
    /// `r1`), with `segments` vertices on each rim. With `r0 == r1` it is a cylinder; the seed
    /// paper's cylinder and truncated-cone lights have 20 vertices (`segments = 10`).
    ///
    /// # Errors
    ///
    /// [`GeomError::NonFiniteArgument`] for a NaN or infinite base, axis or radius;
    /// [`GeomError::ZeroLengthArgument`] for a zero axis; [`GeomError::OutOfRange`] for
    /// `segments < 3` or a negative radius; both radii zero is [`GeomError::Degenerate`].
    pub fn frustum(
        base: DVec3,
        axis: DVec3,
        r0: f64,
        r1: f64,
        segments: u32,
    ) -> Result<Self, GeomError> {
        if !(3..=10_000).contains(&segments) {
            return Err(GeomError::OutOfRange {
                what: "frustum segments (at least 3)",
                value: f64::from(segments),
                limit: 10_000.0,
            });
        }
        finite(base, "frustum base")?;
        finite(axis, "frustum axis")?;
        if !(r0.is_finite() && r1.is_finite()) {
            return Err(GeomError::NonFiniteArgument {
                what: "frustum radius",
            });
        }
        if r0 < 0.0 || r1 < 0.0 {
            return Err(GeomError::OutOfRange {
                what: "frustum radius (non-negative)",
                value: if r0 >= 0.0 { r1 } else { r0 },
                limit: MAX_MESH_COORD,
            });
        }
        // Scaled by the largest component first, so that no length overflows or underflows.
        let m = axis.abs().max_element();
        if !(m >= f64::MIN_POSITIVE) {
            return Err(GeomError::ZeroLengthArgument {
                what: "frustum axis",
            });
        }
        let w = (axis / m).normalize();
        let (u, v) = w.any_orthonormal_pair();
        let mut pts = Vec::with_capacity(2 * segments as usize);
        for (c, r) in [(base, r0), (base + axis, r1)] {
            if r == 0.0 {
                pts.push(c);
                continue;
            }
            for s in 0..segments {
                let (sp, cp) = sin_cos(2.0 * PI * f64::from(s) / f64::from(segments));
                pts.push(c + r * (cp * u + sp * v));
            }
        }
        ConvexPolyhedron::hull(&pts)
    }
}

/// The 12 vertices of the icosahedron on the unit sphere, subdivided `n` times (each triangle
/// into four, midpoints pushed to the sphere).
fn icosphere_points(n: u32) -> Vec<DVec3> {
    let t = (1.0 + sqrt(5.0)) / 2.0;
    let mut pts: Vec<DVec3> = [
        (-1.0, t, 0.0),
        (1.0, t, 0.0),
        (-1.0, -t, 0.0),
        (1.0, -t, 0.0),
        (0.0, -1.0, t),
        (0.0, 1.0, t),
        (0.0, -1.0, -t),
        (0.0, 1.0, -t),
        (t, 0.0, -1.0),
        (t, 0.0, 1.0),
        (-t, 0.0, -1.0),
        (-t, 0.0, 1.0),
    ]
    .iter()
    .map(|&(x, y, z)| DVec3::new(x, y, z).normalize())
    .collect();
    let mut tris: Vec<[usize; 3]> = vec![
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    for _ in 0..n {
        let mut mid = alloc::collections::BTreeMap::new();
        let mut next = Vec::with_capacity(4 * tris.len());
        for &[a, b, c] in &tris {
            let mut m = |i: usize, j: usize| {
                *mid.entry((i.min(j), i.max(j))).or_insert_with(|| {
                    pts.push((pts[i] + pts[j]).normalize());
                    pts.len() - 1
                })
            };
            let (ab, bc, ca) = (m(a, b), m(b, c), m(c, a));
            next.extend([[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]);
        }
        tris = next;
    }
    pts
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn primitives_have_expected_vertex_counts() {
        let ico = ConvexPolyhedron::icosphere(DVec3::ZERO, 1.0, 1).unwrap();
        assert_eq!(ico.vertices().len(), 42);
        let cyl = ConvexPolyhedron::frustum(DVec3::ZERO, DVec3::Z, 1.0, 1.0, 10).unwrap();
        assert_eq!(cyl.vertices().len(), 20);
        let cone = ConvexPolyhedron::frustum(DVec3::ZERO, DVec3::Z, 1.0, 0.5, 10).unwrap();
        assert_eq!(cone.vertices().len(), 20);
        let ell =
            ConvexPolyhedron::ellipsoid(DVec3::ZERO, DVec3::new(1.0, 0.5, 0.7), 8, 19).unwrap();
        assert_eq!(ell.vertices().len(), 154);
        for p in [&ico, &cyl, &cone, &ell] {
            let v = p.vertices().len() as i64;
            assert_eq!(
                v - p.edges().len() as i64 + p.mesh().triangle_count() as i64,
                2
            );
        }
    }
}
