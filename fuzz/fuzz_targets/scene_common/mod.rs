//! Shared pieces of the scene fuzz targets (`shade`, `shade_regimes`, `visibility_backends`):
//! points on a coarse grid and the primitives every target builds from them. A grid of eighths
//! makes faces share planes, edges and vertices often, which is where the shading and visibility
//! paths have to decide degenerate cases.

#![allow(dead_code)] // each target uses the primitives its scenes need

use arealight::glam::DVec3;
use arealight::shade::{Body, ConvexPolyhedron, TriangleMesh};
use libfuzzer_sys::arbitrary::{self, Arbitrary};

/// A point of the coarse grid: integers over 8.
#[derive(Debug, Clone, Copy, Arbitrary)]
pub struct Grid(pub i8, pub i8, pub i8);

impl Grid {
    /// The point, in scene units.
    pub fn at(self) -> DVec3 {
        DVec3::new(f64::from(self.0), f64::from(self.1), f64::from(self.2)) / 8.0
    }
}

/// A small positive size on the grid (1/16 to 2).
pub fn size(s: u8) -> f64 {
    f64::from(1 + (s % 32)) / 16.0
}

/// The quad of centre `c` and half-edges `u`, `v` (`None` where it is degenerate).
pub fn quad(c: Grid, u: Grid, v: Grid) -> Option<Body> {
    Some(TriangleMesh::quad(c.at(), u.at(), v.at()).ok()?.into())
}

/// The axis-aligned box of centre `c` and half extents `size(x)`, `size(y)`, `size(z)`.
pub fn cuboid(c: Grid, x: u8, y: u8, z: u8) -> Option<Body> {
    let half = DVec3::new(size(x), size(y), size(z));
    Some(ConvexPolyhedron::cuboid(c.at(), half).ok()?.into())
}

/// The once-subdivided icosphere of centre `c` and radius `size(r)`.
pub fn icosphere(c: Grid, r: u8) -> Option<Body> {
    Some(ConvexPolyhedron::icosphere(c.at(), size(r), 1).ok()?.into())
}

/// Two squares of half side `size(s)` as one open, non-planar mesh, the second moved by `d`
/// (self-occluding as a light).
pub fn sheets(c: Grid, d: Grid, s: u8) -> Option<Body> {
    let h = size(s);
    let first = TriangleMesh::quad(c.at(), DVec3::Y * h, DVec3::X * h).ok()?;
    let second = TriangleMesh::quad(c.at() + d.at(), DVec3::X * h, DVec3::Y * h).ok()?;
    Some(first.merged(&second).ok()?.into())
}
