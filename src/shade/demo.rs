//! The test scene of seed 000 (Fig. 4), shared by the render example, the tests and the benches.
//!
//! A ground plane (the receiver, `z = 0`) under three lights, a quad (4 vertices), a cylinder and
//! a truncated cone (20 vertices each), and three occluders standing on the ground, a cube
//! (8 vertices), an icosphere (a once-subdivided icosahedron, 42 vertices) and an ellipsoid
//! (154 vertices). The cube's bottom face lies in the ground plane, so ground points see it
//! edge-on: the case the silhouette's face tolerance exists for.

use alloc::vec;
use alloc::vec::Vec;

use glam::DVec3;

use super::material::Material;
use super::scene::{Light, Scene};
use crate::GeomError;
use crate::solid::{Body, ConvexPolyhedron, TriangleMesh};

/// Which lights and occluders of the test scene to include.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct DemoConfig {
    /// Number of lights, 0 to 3: quad, then cylinder, then truncated cone.
    pub lights: usize,
    /// Number of occluders, 0 to 3: cube, then icosphere, then ellipsoid.
    pub occluders: usize,
}

impl Default for DemoConfig {
    fn default() -> Self {
        DemoConfig {
            lights: 3,
            occluders: 3,
        }
    }
}

/// The test scene and the materials of its surfaces.
#[derive(Debug, Clone)]
pub struct Demo {
    /// Lights and occluders.
    pub scene: Scene,
    /// Material of the ground plane.
    pub ground: Material,
    /// Material of each occluder (same order as the scene's occluders).
    pub occluder_materials: Vec<Material>,
    /// Half-size of the square of the ground plane that shading points are drawn from.
    pub ground_half_size: f64,
}

/// Builds the test scene.
///
/// # Errors
///
/// Never for the built-in geometry; the `Result` carries the constructors' checks.
pub fn demo_scene(cfg: DemoConfig) -> Result<Demo, GeomError> {
    // A 1.2 x 1.2 quad facing down (tilted 15 degrees towards +x), high on the left.
    let quad = TriangleMesh::quad(
        DVec3::new(-1.5, 0.4, 3.0),
        DVec3::new(0.0, 0.6, 0.0),
        DVec3::new(0.58, 0.0, 0.155),
    )?;
    let cylinder = ConvexPolyhedron::frustum(
        DVec3::new(1.9, 1.6, 2.2),
        DVec3::new(0.15, -0.1, 0.9),
        0.25,
        0.25,
        10,
    )?;
    let cone = ConvexPolyhedron::frustum(
        DVec3::new(0.6, -0.9, 2.5),
        DVec3::new(-0.2, 0.1, 0.6),
        0.35,
        0.15,
        10,
    )?;
    let all_lights = vec![
        Light::new(quad, DVec3::new(4.0, 3.5, 2.8))?,
        Light::new(cylinder, DVec3::new(1.5, 2.2, 4.5))?,
        Light::new(cone, DVec3::new(1.8, 3.6, 1.8))?,
    ];
    let cube = ConvexPolyhedron::cuboid(DVec3::new(-0.7, 0.5, 0.45), DVec3::splat(0.45))?;
    let ico = ConvexPolyhedron::icosphere(DVec3::new(0.7, -0.5, 0.75), 0.45, 1)?;
    let ell = ConvexPolyhedron::ellipsoid(
        DVec3::new(0.4, 1.1, 0.38),
        DVec3::new(0.55, 0.3, 0.35),
        8,
        19,
    )?;
    let all_occ: Vec<Body> = vec![cube.into(), ico.into(), ell.into()];
    let mats = [
        Material::new(DVec3::new(0.7, 0.25, 0.2), DVec3::splat(0.04), 0.5)?,
        Material::new(DVec3::new(0.25, 0.6, 0.3), DVec3::splat(0.04), 0.35)?,
        Material::new(DVec3::new(0.3, 0.35, 0.7), DVec3::splat(0.04), 0.6)?,
    ];
    let lights = all_lights.into_iter().take(cfg.lights.min(3)).collect();
    let occluders: Vec<Body> = all_occ.into_iter().take(cfg.occluders.min(3)).collect();
    let occluder_materials = mats[..occluders.len()].to_vec();
    Ok(Demo {
        scene: Scene::new(lights, occluders)?,
        ground: Material::new(DVec3::splat(0.6), DVec3::splat(0.04), 0.4)?,
        occluder_materials,
        ground_half_size: 3.0,
    })
}
