//! Scene files in: lights and occluders from Wavefront OBJ (feature `obj`, crate `tobj`) and glTF
//! 2.0 (feature `gltf`, `.gltf` and `.glb`), ready to shade.
//!
//! [`load`] reads a file, checks every value, and builds a [`Scene`]: objects with an emissive
//! material become [`Light`]s, every other object an occluder (and a receiver: the renderer
//! shades points on it). Each object keeps what a renderer needs beside the scene: its name,
//! [`Material`], emitted radiance, and its vertices with per-vertex normals ([`SceneObject`]).
//! Both features need `std`; a `no_std` build pays for neither.
//!
//! # What is read, and the defaults
//!
//! - **Objects.** OBJ: each `o` / `g` group with one material (tobj splits groups at material
//!   changes). glTF: each triangle primitive of each mesh instanced by a node of the default
//!   scene (else the first scene; else every root node), in world space (node transforms
//!   composed in `f64`; a transform that mirrors reverses the triangles, so they keep facing
//!   the side they faced). Names: OBJ `o` / `g` names; glTF node name, else mesh name, else
//!   `mesh M primitive P`.
//! - **Faces.** Polygons are fanned from their first corner (OBJ through tobj; glTF triangle
//!   strips and fans are unrolled). Points and lines are skipped: they bound no area.
//!   Counter-clockwise is the front, as in both formats and in [`TriangleMesh`]. Triangles of
//!   zero area (within [`crate::solid::DEGENERATE_TRIANGLE`]) are dropped and counted
//!   ([`SceneObject::dropped_triangles`]): they cover no solid angle.
//! - **Bodies.** An object whose mesh (vertices welded where their coordinates are equal) is
//!   closed and convex becomes a [`ConvexPolyhedron`] (one silhouette per shading point; tested
//!   for meshes of up to [`CONVEX_TEST_MAX_TRIANGLES`] triangles); every other one a
//!   [`TriangleMesh`] (per triangle; a closed mesh light is shaded from its non-convex
//!   silhouette).
//! - **Normals.** From the file where it has them (OBJ `vn`, glTF `NORMAL`); without them, each
//!   vertex gets the area-weighted mean of the normals of the triangles that use it (flat
//!   faces for a file that does not share vertices across an edge). They are for the
//!   renderer's shading; the shading geometry itself uses face planes.
//! - **Materials** ([`Material`]: Lambert + GGX). OBJ (`.mtl`): `Kd` is the albedo, `Ks` the
//!   specular reflectance at normal incidence `f0`, `Ns` (Blinn-Phong exponent) the roughness
//!   `sqrt(alpha)` with `alpha = sqrt(2 / (Ns + 2))`; `Ke` the emitted radiance. Missing: no
//!   material, or no `Kd`, is [`DEFAULT_ALBEDO`] grey; no `Ks` no specular lobe; no `Ns`
//!   roughness 1. glTF: metallic-roughness factors (`baseColorFactor` times `1 - metallic` is
//!   the albedo, `f0` is `0.04` blended to the base colour by `metallic`, `roughnessFactor` the
//!   roughness), `emissiveFactor` times `KHR_materials_emissive_strength` the radiance; a
//!   primitive without a material gets the specification's default material (white base,
//!   metallic 1, roughness 1). Textures are not read (factors only).
//! - **Lights.** An object with any emitted component above zero is a light, emitting from its
//!   front side. A glTF `doubleSided` emissive material makes a two-sided light
//!   ([`Light::two_sided`]) when the mesh is planar; otherwise it is an error (a curved
//!   two-sided emitter is not supported).
//!
//! # Errors
//!
//! Every failure is a [`SceneFileError`] naming the file, the object when one is concerned, and
//! the reason ([`SceneFileErrorKind`]): unreadable files, parse errors, unsupported content,
//! values that mean nothing (NaN or infinite coordinates or normals, colours outside `[0, 1]`,
//! negative emission), and geometry the crate rejects (coordinates beyond
//! [`crate::solid::MAX_MESH_COORD`], an object with no triangle of non-zero area). Nothing
//! panics on a malformed file.
//!
//! # Examples
//!
//! ```
//! # #[cfg(feature = "obj")] {
//! use arealight::glam::DVec3;
//! let path = concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/cornell_box.obj");
//! let file = arealight::io::load(path)?;
//! assert_eq!(file.scene.lights().len(), 1);
//! // A point on the floor in front of the tall block, which sees all of the ceiling light.
//! let floor = &file.objects[file.object_index("floor").unwrap()];
//! let p = DVec3::new(0.4, 0.0, 0.1);
//! let view = DVec3::new(0.0, 0.5, -1.0); // towards the camera
//! let parts = file.scene.shade_per_light(p, DVec3::Y, view, &floor.material)?;
//! assert!(parts[0].shadowed().x > 0.0);
//! assert!((parts[0].shadowed() - parts[0].unshadowed()).abs().max_element() < 1e-12);
//! # }
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

use std::fmt;
use std::path::{Path, PathBuf};
use std::string::String;
use std::vec::Vec;

use glam::DVec3;

use crate::GeomError;
use crate::shade::{ConvexPolyhedron, Light, Material, Scene, TriangleMesh};
use crate::solid::Body;

#[cfg(feature = "gltf")]
mod gltf;
#[cfg(feature = "obj")]
mod obj;
mod object;

pub use object::SceneObject;

/// The albedo (grey) of an OBJ object without a material or without `Kd`.
pub const DEFAULT_ALBEDO: f64 = 0.8;

/// A loaded scene file: its objects, and the [`Scene`] built from them.
#[derive(Debug, Clone)]
pub struct SceneFile {
    /// Every object of the file, in file order.
    pub objects: Vec<SceneObject>,
    /// The emissive objects as lights, the others as occluders, in file order.
    pub scene: Scene,
    /// For each light of [`SceneFile::scene`], the index of its object.
    pub light_objects: Vec<usize>,
    /// For each occluder of [`SceneFile::scene`], the index of its object.
    pub occluder_objects: Vec<usize>,
}

impl SceneFile {
    /// The index of the first object named `name`.
    #[must_use]
    pub fn object_index(&self, name: &str) -> Option<usize> {
        self.objects.iter().position(|o| o.name == name)
    }

    /// Builds the scene from checked objects (see the module documentation: emissive objects
    /// are lights).
    pub(crate) fn from_objects(
        file: &Path,
        objects: Vec<SceneObject>,
    ) -> Result<Self, SceneFileError> {
        let mut lights = Vec::new();
        let mut occluders = Vec::new();
        let (mut light_objects, mut occluder_objects) = (Vec::new(), Vec::new());
        for (k, o) in objects.iter().enumerate() {
            let err = |kind| SceneFileError::new(file, Some(&o.name), kind);
            if o.is_light() {
                let light = if o.two_sided {
                    Light::two_sided(o.body.clone(), o.emission)
                } else {
                    Light::new(o.body.clone(), o.emission)
                };
                let light = light.map_err(|e| match e {
                    GeomError::Degenerate(_) => err(SceneFileErrorKind::Unsupported(
                        "a double-sided emissive mesh must be planar (a curved two-sided light \
                         is not supported); make the material single-sided or split the mesh"
                            .into(),
                    )),
                    e => err(SceneFileErrorKind::Geometry(e)),
                })?;
                lights.push(light);
                light_objects.push(k);
            } else {
                occluders.push(o.body.clone());
                occluder_objects.push(k);
            }
        }
        let scene = Scene::new(lights, occluders)
            .map_err(|e| SceneFileError::new(file, None, SceneFileErrorKind::Geometry(e)))?;
        Ok(SceneFile {
            objects,
            scene,
            light_objects,
            occluder_objects,
        })
    }
}

/// Loads a scene file by its extension: `.obj` (feature `obj`), `.gltf` or `.glb` (feature
/// `gltf`). See the module documentation for what is read.
///
/// # Errors
///
/// A [`SceneFileError`] naming the file, the object when one is concerned, and the reason; an
/// extension without its feature is [`SceneFileErrorKind::Unsupported`].
pub fn load(path: impl AsRef<Path>) -> Result<SceneFile, SceneFileError> {
    let path = path.as_ref();
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase)
        .unwrap_or_default();
    match ext.as_str() {
        #[cfg(feature = "obj")]
        "obj" => load_obj(path),
        #[cfg(feature = "gltf")]
        "gltf" | "glb" => load_gltf(path),
        _ => Err(SceneFileError::new(
            path,
            None,
            SceneFileErrorKind::Unsupported(std::format!(
                "unknown scene file extension {ext:?}: .obj needs the feature `obj`, .gltf and \
                 .glb the feature `gltf`"
            )),
        )),
    }
}

/// Loads a Wavefront OBJ file and the `.mtl` files it names (relative to its folder).
///
/// # Errors
///
/// As [`load`].
#[cfg(feature = "obj")]
pub fn load_obj(path: impl AsRef<Path>) -> Result<SceneFile, SceneFileError> {
    let path = path.as_ref();
    SceneFile::from_objects(path, obj::read(path)?)
}

/// Loads a glTF 2.0 file, `.gltf` (JSON, with buffers as `data:` URIs or files relative to its
/// folder) or `.glb` (binary).
///
/// # Errors
///
/// As [`load`].
#[cfg(feature = "gltf")]
pub fn load_gltf(path: impl AsRef<Path>) -> Result<SceneFile, SceneFileError> {
    let path = path.as_ref();
    SceneFile::from_objects(path, gltf::read(path)?)
}

/// Why a scene file could not be loaded ([`SceneFileError::kind`]).
#[derive(Debug)]
#[non_exhaustive]
pub enum SceneFileErrorKind {
    /// The file, or a file it refers to, could not be read.
    Io(std::io::Error),
    /// The file is not valid in its format (the parser's message).
    Parse(String),
    /// The file is valid, but uses something this loader does not read.
    Unsupported(String),
    /// A value that means nothing: a NaN or infinite coordinate or normal, a colour component
    /// outside `[0, 1]`, a negative emission.
    Invalid(String),
    /// The crate rejected an object's geometry (see [`GeomError`]).
    Geometry(GeomError),
}

/// A scene file that could not be loaded: which file, which object (when one is concerned), and
/// why.
#[derive(Debug)]
pub struct SceneFileError {
    /// The file.
    pub file: PathBuf,
    /// The object concerned, if any.
    pub object: Option<String>,
    /// The reason.
    pub kind: SceneFileErrorKind,
}

impl SceneFileError {
    pub(crate) fn new(file: &Path, object: Option<&str>, kind: SceneFileErrorKind) -> Self {
        SceneFileError {
            file: file.to_path_buf(),
            object: object.map(String::from),
            kind,
        }
    }
}

impl fmt::Display for SceneFileError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.file.display())?;
        if let Some(o) = &self.object {
            write!(f, ": object {o:?}")?;
        }
        match &self.kind {
            SceneFileErrorKind::Io(e) => write!(f, ": cannot read: {e}"),
            SceneFileErrorKind::Parse(m) => write!(f, ": parse error: {m}"),
            SceneFileErrorKind::Unsupported(m) => write!(f, ": unsupported: {m}"),
            SceneFileErrorKind::Invalid(m) => write!(f, ": invalid value: {m}"),
            SceneFileErrorKind::Geometry(e) => write!(f, ": invalid geometry: {e}"),
        }
    }
}

impl std::error::Error for SceneFileError {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match &self.kind {
            SceneFileErrorKind::Io(e) => Some(e),
            SceneFileErrorKind::Geometry(e) => Some(e),
            _ => None,
        }
    }
}

/// Closed meshes of more triangles than this are not tested for convexity when loaded (the test,
/// [`ConvexPolyhedron::from_mesh`], checks every vertex against every face plane); they are used
/// as meshes.
pub const CONVEX_TEST_MAX_TRIANGLES: usize = 4096;

/// A body from a checked mesh: a convex polyhedron when the mesh is closed and convex (tested up
/// to [`CONVEX_TEST_MAX_TRIANGLES`]), else the mesh.
fn body_of(mesh: TriangleMesh) -> Body {
    if mesh.is_closed()
        && mesh.triangle_count() <= CONVEX_TEST_MAX_TRIANGLES
        && let Ok(p) = ConvexPolyhedron::from_mesh(&mesh)
    {
        return Body::Convex(p);
    }
    Body::Mesh(mesh)
}

/// A material from reflectances, checked: components in `[0, 1]`, roughness in `[0, 1]`.
fn material(albedo: DVec3, f0: DVec3, roughness: f64) -> Result<Material, SceneFileErrorKind> {
    Material::new(albedo, f0, roughness)
        .map_err(|e| SceneFileErrorKind::Invalid(std::format!("{e}")))
}
