//! Builds arealight without std and exercises its public entry points.
#![no_std]

extern crate alloc;

use alloc::vec;
use arealight::glam::DVec3;
use arealight::sphere::SphericalPolygon;

/// Solid angle of the part of the octant above a tilted horizon, through the no_std build.
pub fn octant_above(normal: DVec3) -> Result<f64, arealight::GeomError> {
    let p = SphericalPolygon::new(vec![vec![DVec3::X, DVec3::Y, DVec3::Z]])?;
    Ok(p.try_clip_to_hemisphere(normal)?.solid_angle())
}
