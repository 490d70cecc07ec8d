//! Test solids: the polyhedra of thesis 003's measurements (table 7.1, figure 7.5) and
//! generators of random non-convex solids (tori, extruded stars, bumpy spheres), shared by the
//! crate's tests, benchmarks, fuzz targets and examples (through `internals`).
//!
//! The thesis counts polygon faces; here every face is split into triangles (fans of convex
//! polygons, annular faces as four trapezoids), so vertex counts match table 7.1 and triangle
//! counts are those of the triangulated faces.

use alloc::vec::Vec;
use core::f64::consts::PI;

use glam::DVec3;

use super::convex::ConvexPolyhedron;
use super::mesh::TriangleMesh;
use crate::GeomError;
use crate::math::{cos, sin};

/// Collects convex polygon faces into a triangle mesh: vertices are shared by exact position,
/// each face is oriented so that its normal points along `outward` and split into a fan.
#[derive(Default)]
struct Builder {
    vertices: Vec<DVec3>,
    triangles: Vec<[u32; 3]>,
}

impl Builder {
    fn vertex(&mut self, p: DVec3) -> u32 {
        match self.vertices.iter().position(|&q| q == p) {
            Some(i) => i as u32,
            None => {
                self.vertices.push(p);
                (self.vertices.len() - 1) as u32
            }
        }
    }

    /// A convex face (any order round the boundary), its normal turned to `outward`.
    fn face(&mut self, pts: &[DVec3], outward: DVec3) {
        // Newell's normal of the polygon as given.
        let mut n = DVec3::ZERO;
        for k in 0..pts.len() {
            let (a, b) = (pts[k], pts[(k + 1) % pts.len()]);
            n += DVec3::new(
                (a.y - b.y) * (a.z + b.z),
                (a.z - b.z) * (a.x + b.x),
                (a.x - b.x) * (a.y + b.y),
            );
        }
        let mut idx: Vec<u32> = pts.iter().map(|&p| self.vertex(p)).collect();
        if n.dot(outward) < 0.0 {
            // Reversed with the first corner kept first: a non-convex face (the corner's L)
            // is given with a first corner whose fan is valid.
            idx[1..].reverse();
        }
        for k in 1..idx.len() - 1 {
            self.triangles.push([idx[0], idx[k], idx[k + 1]]);
        }
    }

    fn mesh(self) -> Result<TriangleMesh, GeomError> {
        TriangleMesh::new(self.vertices, self.triangles)
    }
}

/// The nine polyhedra of thesis 003 table 7.1, in its order, each about the origin with a
/// half-size of 1: cube, cone (12-gon base), cylinder (12-gon), icosahedron, sphere (the
/// icosahedron subdivided once: 42 vertices), corner (an L-shaped prism), extruded cube (a cube
/// with each face extruded by its own size: a three-dimensional cross), hole (a square frame: a
/// box with a square hole through it) and bowl (a box with a box-shaped cavity open at the top).
///
/// # Errors
///
/// Never (the shapes are fixed); the `Result` is that of [`TriangleMesh::new`].
pub fn thesis_polyhedra() -> Result<Vec<(&'static str, TriangleMesh)>, GeomError> {
    Ok(alloc::vec![
        ("cube", cube()?),
        ("cone", cone(12)?),
        ("cylinder", prism(&regular_polygon(12, 1.0), -1.0, 1.0)?),
        (
            "icosahedron",
            ConvexPolyhedron::icosphere(DVec3::ZERO, 1.0, 0)?
                .mesh()
                .clone()
        ),
        (
            "sphere",
            ConvexPolyhedron::icosphere(DVec3::ZERO, 1.0, 1)?
                .mesh()
                .clone()
        ),
        ("corner", corner()?),
        ("extruded cube", extruded_cube(0.5)?),
        ("hole", frame(0.5, 0.5)?),
        ("bowl", bowl(0.6, -0.4)?),
    ])
}

/// `n` points of a regular polygon of circumradius `r` in the `xy`-plane, counter-clockwise.
fn regular_polygon(n: usize, r: f64) -> Vec<DVec3> {
    (0..n)
        .map(|k| {
            let t = 2.0 * PI * k as f64 / n as f64;
            DVec3::new(r * cos(t), r * sin(t), 0.0)
        })
        .collect()
}

fn cube() -> Result<TriangleMesh, GeomError> {
    Ok(ConvexPolyhedron::cuboid(DVec3::ZERO, DVec3::ONE)?
        .mesh()
        .clone())
}

fn cone(n: usize) -> Result<TriangleMesh, GeomError> {
    let base: Vec<DVec3> = regular_polygon(n, 1.0)
        .into_iter()
        .map(|p| p - DVec3::Z)
        .collect();
    let apex = DVec3::Z;
    let mut b = Builder::default();
    b.face(&base, -DVec3::Z);
    for k in 0..n {
        let (p, q) = (base[k], base[(k + 1) % n]);
        b.face(&[p, q, apex], (p + q) * 0.5);
    }
    b.mesh()
}

/// The prism over a polygon that is star-shaped about the `z` axis (counter-clockwise in
/// `xy`), between heights `z0 < z1`; the caps are fans about a center vertex when the polygon
/// is not convex.
fn prism(poly: &[DVec3], z0: f64, z1: f64) -> Result<TriangleMesh, GeomError> {
    let n = poly.len();
    let lo = |p: DVec3| DVec3::new(p.x, p.y, z0);
    let hi = |p: DVec3| DVec3::new(p.x, p.y, z1);
    let mut b = Builder::default();
    let convex = (0..n).all(|k| {
        let (a, c, d) = (poly[k], poly[(k + 1) % n], poly[(k + 2) % n]);
        (c - a).cross(d - c).z > 0.0
    });
    if convex {
        b.face(&poly.iter().map(|&p| lo(p)).collect::<Vec<_>>(), -DVec3::Z);
        b.face(&poly.iter().map(|&p| hi(p)).collect::<Vec<_>>(), DVec3::Z);
    } else {
        for k in 0..n {
            let (p, q) = (poly[k], poly[(k + 1) % n]);
            b.face(&[lo(DVec3::ZERO), lo(p), lo(q)], -DVec3::Z);
            b.face(&[hi(DVec3::ZERO), hi(p), hi(q)], DVec3::Z);
        }
    }
    for k in 0..n {
        let (p, q) = (poly[k], poly[(k + 1) % n]);
        let out = (q - p).cross(DVec3::Z);
        b.face(&[lo(p), lo(q), hi(q), hi(p)], out);
    }
    b.mesh()
}

fn corner() -> Result<TriangleMesh, GeomError> {
    // The L in the xy-plane; its caps are fans from (-1, -1), which sees the whole L (the
    // builder keeps the first corner first).
    let l = [
        (-1.0, -1.0),
        (1.0, -1.0),
        (1.0, 0.0),
        (0.0, 0.0),
        (0.0, 1.0),
        (-1.0, 1.0),
    ]
    .map(|(x, y)| DVec3::new(x, y, 0.0));
    let mut b = Builder::default();
    let at = |p: DVec3, z: f64| DVec3::new(p.x, p.y, z);
    b.face(&l.map(|p| at(p, -1.0)), -DVec3::Z);
    b.face(&l.map(|p| at(p, 1.0)), DVec3::Z);
    for k in 0..6 {
        let (p, q) = (l[k], l[(k + 1) % 6]);
        b.face(
            &[at(p, -1.0), at(q, -1.0), at(q, 1.0), at(p, 1.0)],
            (q - p).cross(DVec3::Z),
        );
    }
    b.mesh()
}

/// A cube of half-size `h` with each face extruded outwards to distance 1 from the center.
fn extruded_cube(h: f64) -> Result<TriangleMesh, GeomError> {
    let mut b = Builder::default();
    for axis in 0..3 {
        for s in [-1.0, 1.0] {
            let n = DVec3::AXES[axis] * s;
            let (u, v) = (DVec3::AXES[(axis + 1) % 3], DVec3::AXES[(axis + 2) % 3]);
            let corners = [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)]
                .map(|(a, c)| (u * a + v * c) * h);
            let base = corners.map(|c| c + n * h);
            let top = corners.map(|c| c + n);
            b.face(&top, n);
            for k in 0..4 {
                let (p, q) = (k, (k + 1) % 4);
                let out = (corners[p] + corners[q]) * 0.5;
                b.face(&[base[p], base[q], top[q], top[p]], out);
            }
        }
    }
    b.mesh()
}

/// The square frame `[-1, 1]^2 x [-t, t]` with the hole `[-a, a]^2` through it.
fn frame(a: f64, t: f64) -> Result<TriangleMesh, GeomError> {
    let mut b = Builder::default();
    let sq =
        |r: f64| [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)].map(|(x, y)| (x * r, y * r));
    let (outer, inner) = (sq(1.0), sq(a));
    let p = |(x, y): (f64, f64), z: f64| DVec3::new(x, y, z);
    for k in 0..4 {
        let j = (k + 1) % 4;
        let mid =
            |q: [(f64, f64); 4]| DVec3::new((q[k].0 + q[j].0) * 0.5, (q[k].1 + q[j].1) * 0.5, 0.0);
        b.face(
            &[
                p(outer[k], -t),
                p(outer[j], -t),
                p(outer[j], t),
                p(outer[k], t),
            ],
            mid(outer),
        );
        b.face(
            &[
                p(inner[k], -t),
                p(inner[j], -t),
                p(inner[j], t),
                p(inner[k], t),
            ],
            -mid(inner),
        );
        for (z, up) in [(t, DVec3::Z), (-t, -DVec3::Z)] {
            b.face(
                &[
                    p(outer[k], z),
                    p(outer[j], z),
                    p(inner[j], z),
                    p(inner[k], z),
                ],
                up,
            );
        }
    }
    b.mesh()
}

/// The box `[-1, 1]^3` with the cavity `[-a, a]^2 x [floor, 1]` open at the top.
fn bowl(a: f64, floor: f64) -> Result<TriangleMesh, GeomError> {
    let mut b = Builder::default();
    let sq =
        |r: f64| [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)].map(|(x, y)| (x * r, y * r));
    let (outer, inner) = (sq(1.0), sq(a));
    let p = |(x, y): (f64, f64), z: f64| DVec3::new(x, y, z);
    b.face(&outer.map(|q| p(q, -1.0)), -DVec3::Z);
    b.face(&inner.map(|q| p(q, floor)), DVec3::Z);
    for k in 0..4 {
        let j = (k + 1) % 4;
        let mid =
            |q: [(f64, f64); 4]| DVec3::new((q[k].0 + q[j].0) * 0.5, (q[k].1 + q[j].1) * 0.5, 0.0);
        b.face(
            &[
                p(outer[k], -1.0),
                p(outer[j], -1.0),
                p(outer[j], 1.0),
                p(outer[k], 1.0),
            ],
            mid(outer),
        );
        b.face(
            &[
                p(inner[k], floor),
                p(inner[j], floor),
                p(inner[j], 1.0),
                p(inner[k], 1.0),
            ],
            -mid(inner),
        );
        b.face(
            &[
                p(outer[k], 1.0),
                p(outer[j], 1.0),
                p(inner[j], 1.0),
                p(inner[k], 1.0),
            ],
            DVec3::Z,
        );
    }
    b.mesh()
}

/// A torus about the `z` axis: tube radius `r` about a circle of radius `big_r > r`, with
/// `around` segments along the circle and `tube` round the tube.
///
/// # Errors
///
/// [`GeomError::OutOfRange`] for `r >= big_r`, a non-positive radius or fewer than 3 segments;
/// otherwise those of [`TriangleMesh::new`].
pub fn torus(big_r: f64, r: f64, around: usize, tube: usize) -> Result<TriangleMesh, GeomError> {
    if !(r > 0.0 && big_r > r && around >= 3 && tube >= 3) {
        return Err(GeomError::OutOfRange {
            what: "torus radii (0 < r < R) or segments (>= 3)",
            value: r,
            limit: big_r,
        });
    }
    let at = |i: usize, j: usize| {
        let (t, f) = (
            2.0 * PI * (i % around) as f64 / around as f64,
            2.0 * PI * (j % tube) as f64 / tube as f64,
        );
        let w = big_r + r * cos(f);
        (
            DVec3::new(w * cos(t), w * sin(t), r * sin(f)),
            DVec3::new(cos(f) * cos(t), cos(f) * sin(t), sin(f)),
        )
    };
    let mut vertices = Vec::with_capacity(around * tube);
    for i in 0..around {
        for j in 0..tube {
            vertices.push(at(i, j).0);
        }
    }
    let id = |i: usize, j: usize| ((i % around) * tube + j % tube) as u32;
    let mut triangles = Vec::with_capacity(2 * around * tube);
    for i in 0..around {
        for j in 0..tube {
            // (i, j) -> (i + 1, j) -> (i + 1, j + 1) -> (i, j + 1) runs counter-clockwise seen
            // from outside the tube (the tube angle grows outwards-then-up).
            let q = [id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)];
            triangles.push([q[0], q[1], q[2]]);
            triangles.push([q[0], q[2], q[3]]);
        }
    }
    TriangleMesh::new(vertices, triangles)
}

/// A prism of height `2 h` over a star with `points` tips at radius `outer` and notches at
/// radius `inner` (about the `z` axis), its caps fans about their centers.
///
/// # Errors
///
/// [`GeomError::OutOfRange`] for fewer than 2 points or radii not `0 < inner < outer`;
/// otherwise those of [`TriangleMesh::new`].
pub fn extruded_star(
    points: usize,
    inner: f64,
    outer: f64,
    h: f64,
) -> Result<TriangleMesh, GeomError> {
    if !(points >= 2 && inner > 0.0 && outer > inner && h > 0.0) {
        return Err(GeomError::OutOfRange {
            what: "star points (>= 2) or radii (0 < inner < outer)",
            value: inner,
            limit: outer,
        });
    }
    let poly: Vec<DVec3> = (0..2 * points)
        .map(|k| {
            let t = PI * k as f64 / points as f64;
            let r = if k % 2 == 0 { outer } else { inner };
            DVec3::new(r * cos(t), r * sin(t), 0.0)
        })
        .collect();
    prism(&poly, -h, h)
}

/// The once-to-`subdivisions` times subdivided icosahedron with each vertex moved along its
/// direction to radius `1 + amplitude * f(direction)`, `f` a sum of three random plane waves in
/// `[-1, 1]` drawn from `seed`. Star-shaped about the origin (so never self-intersecting) for
/// `amplitude < 1`.
///
/// # Errors
///
/// [`GeomError::OutOfRange`] for `amplitude` outside `[0, 1)` or more than 4 subdivisions.
pub fn bumpy_sphere(
    subdivisions: u32,
    amplitude: f64,
    seed: u64,
) -> Result<TriangleMesh, GeomError> {
    if !(0.0..1.0).contains(&amplitude) || subdivisions > 4 {
        return Err(GeomError::OutOfRange {
            what: "bumpy sphere amplitude in [0, 1) (subdivisions at most 4)",
            value: amplitude,
            limit: 1.0,
        });
    }
    let ico = ConvexPolyhedron::icosphere(DVec3::ZERO, 1.0, subdivisions)?;
    let mut s = seed ^ 0x9E37_79B9_7F4A_7C15;
    let mut next = || {
        s = s.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = s;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
    };
    let waves: Vec<(DVec3, f64)> = (0..3)
        .map(|_| (DVec3::new(next(), next(), next()) * 4.0, next() * PI))
        .collect();
    let vertices = ico
        .vertices()
        .iter()
        .map(|&d| {
            let f: f64 = waves.iter().map(|&(k, ph)| cos(k.dot(d) + ph)).sum::<f64>() / 3.0;
            d * (1.0 + amplitude * f)
        })
        .collect();
    TriangleMesh::new(vertices, ico.mesh().triangles().to_vec())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::solid::ClosedMesh;

    /// Signed volume (divergence theorem): positive for outward normals.
    fn volume(m: &TriangleMesh) -> f64 {
        (0..m.triangle_count())
            .map(|t| {
                let [a, b, c] = m.triangle(t);
                a.dot(b.cross(c)) / 6.0
            })
            .sum()
    }

    #[test]
    fn thesis_polyhedra_match_table_7_1() {
        // Vertex counts of table 7.1, closed solids with outward normals, and their volumes
        // from the shapes' dimensions.
        let expect = [
            ("cube", 8, 8.0),
            ("cone", 13, 2.0 / 3.0 * 6.0 * (PI / 6.0).sin()),
            ("cylinder", 24, 2.0 * 6.0 * (PI / 6.0).sin()),
            ("icosahedron", 12, 0.0),
            ("sphere", 42, 0.0),
            ("corner", 12, 6.0),
            ("extruded cube", 32, 1.0 + 6.0 * 0.5),
            ("hole", 16, 4.0 - 1.0),
            ("bowl", 16, 8.0 - 1.44 * 1.4),
        ];
        for ((name, m), (ename, nv, vol)) in thesis_polyhedra().unwrap().into_iter().zip(expect) {
            assert_eq!(name, ename);
            assert_eq!(m.vertices().len(), nv, "{name}");
            let v = volume(&m);
            assert!(v > 0.0, "{name}: {v}");
            if vol > 0.0 {
                assert!((v - vol).abs() < 1e-12, "{name}: {v} vs {vol}");
            }
            ClosedMesh::new(m).unwrap_or_else(|e| panic!("{name}: {e}"));
        }
    }

    #[test]
    fn generators_give_solids() {
        let t = torus(1.0, 0.4, 12, 8).unwrap();
        let v = volume(&t);
        // The polyhedral torus is a little smaller than the smooth one (2 pi^2 R r^2).
        assert!(
            v > 0.8 * 2.0 * PI * PI * 0.16 && v < 2.0 * PI * PI * 0.16,
            "{v}"
        );
        ClosedMesh::new(t).unwrap();
        let s = extruded_star(5, 0.4, 1.0, 0.3).unwrap();
        assert!(volume(&s) > 0.0);
        ClosedMesh::new(s).unwrap();
        for seed in 0..5 {
            let b = bumpy_sphere(2, 0.3, seed).unwrap();
            assert!(volume(&b) > 0.0);
            ClosedMesh::new(b).unwrap();
        }
    }
}
