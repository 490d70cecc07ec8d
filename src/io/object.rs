//! One object of a scene file, checked: the part both formats share once their parsers are done.

use std::collections::HashMap;
use std::format;
use std::path::Path;
use std::string::String;
use std::vec::Vec;

use glam::DVec3;

use super::{SceneFileError, SceneFileErrorKind, body_of};
use crate::GeomError;
use crate::shade::{Material, TriangleMesh};
use crate::solid::Body;

/// One object of a scene file (see the [module documentation](super) for how each format maps
/// to it).
#[derive(Debug, Clone)]
pub struct SceneObject {
    /// The object's name in the file.
    pub name: String,
    /// Its vertices (world space), before welding: for glTF in the accessor's order, for OBJ in
    /// order of first use by a face, one per distinct pair of position and normal indices.
    pub positions: Vec<DVec3>,
    /// A unit normal per vertex: the file's, or the area-weighted mean of the normals of the
    /// triangles using the vertex.
    pub normals: Vec<DVec3>,
    /// Its triangles, as indices into [`SceneObject::positions`] (zero-area ones dropped).
    pub triangles: Vec<[u32; 3]>,
    /// The triangles of zero area that were dropped.
    pub dropped_triangles: usize,
    /// Its geometry as the scene uses it (vertices with equal coordinates welded).
    pub body: Body,
    /// Its surface material.
    pub material: Material,
    /// Its emitted RGB radiance (zero for an object that is not a light).
    pub emission: DVec3,
    /// Whether it emits from both sides (a planar glTF `doubleSided` emitter).
    pub two_sided: bool,
}

impl SceneObject {
    /// Whether the object emits (any radiance component above zero): it is then a light of
    /// the scene.
    #[must_use]
    pub fn is_light(&self) -> bool {
        self.emission.max_element() > 0.0
    }
}

/// What a format's reader hands over for one object, in `f64`, unchecked.
pub(super) struct RawObject {
    pub name: String,
    pub positions: Vec<DVec3>,
    /// One per position, or empty when the file has none.
    pub normals: Vec<DVec3>,
    pub triangles: Vec<[u32; 3]>,
    pub material: Material,
    pub emission: DVec3,
    pub two_sided: bool,
}

impl RawObject {
    /// Checks every value and builds the object: coordinates and normals finite, indices in
    /// range, emission finite and non-negative, zero-area triangles dropped, a body built.
    pub(super) fn check(self, file: &Path) -> Result<SceneObject, SceneFileError> {
        let err = |kind| SceneFileError::new(file, Some(&self.name), kind);
        let invalid = |m: String| err(SceneFileErrorKind::Invalid(m));
        if let Some(k) = self.positions.iter().position(|p| !p.is_finite()) {
            return Err(invalid(format!(
                "vertex {k} has a NaN or infinite coordinate {:?}",
                self.positions[k]
            )));
        }
        if !self.normals.is_empty() && self.normals.len() != self.positions.len() {
            return Err(invalid(format!(
                "{} normals for {} vertices",
                self.normals.len(),
                self.positions.len()
            )));
        }
        if let Some(k) = self.normals.iter().position(|n| !n.is_finite()) {
            return Err(invalid(format!(
                "the normal of vertex {k} is NaN or infinite: {:?}",
                self.normals[k]
            )));
        }
        if self.emission.is_nan() || !self.emission.is_finite() || self.emission.min_element() < 0.0
        {
            return Err(invalid(format!(
                "emission {:?} is not finite and non-negative",
                self.emission
            )));
        }
        let n = self.positions.len();
        for (t, tri) in self.triangles.iter().enumerate() {
            if let Some(&i) = tri.iter().find(|&&i| i as usize >= n) {
                return Err(invalid(format!(
                    "triangle {t} refers to vertex {i}, past the {n} vertices"
                )));
            }
        }
        // Zero-area triangles (by the mesh's own test) cover nothing: drop them.
        let mut triangles = Vec::with_capacity(self.triangles.len());
        for &tri in &self.triangles {
            let one = TriangleMesh::new(
                tri.map(|i| self.positions[i as usize]).to_vec(),
                std::vec![[0, 1, 2]],
            );
            match one {
                Ok(_) => triangles.push(tri),
                Err(GeomError::DegenerateTriangle { .. }) => {}
                Err(e) => return Err(err(SceneFileErrorKind::Geometry(e))),
            }
        }
        let dropped_triangles = self.triangles.len() - triangles.len();
        if triangles.is_empty() {
            return Err(err(SceneFileErrorKind::Geometry(GeomError::Degenerate(
                "the object has no triangle of non-zero area",
            ))));
        }
        let (welded, welded_tris) = weld(&self.positions, &triangles);
        let mesh = TriangleMesh::new(welded, welded_tris)
            .map_err(|e| err(SceneFileErrorKind::Geometry(e)))?;
        let normals = if self.normals.is_empty() {
            vertex_normals(&self.positions, &triangles)
        } else {
            self.normals
                .iter()
                .map(|v| v.try_normalize().unwrap_or(DVec3::ZERO))
                .collect()
        };
        Ok(SceneObject {
            body: body_of(mesh),
            name: self.name,
            positions: self.positions,
            normals,
            triangles,
            dropped_triangles,
            material: self.material,
            emission: self.emission,
            two_sided: self.two_sided,
        })
    }
}

/// The vertices used by the triangles, those with equal coordinates merged (bit-equal after
/// `-0.0` is read as `0.0`), and the triangles re-indexed: the topology that tells a closed mesh
/// from sheets.
fn weld(positions: &[DVec3], triangles: &[[u32; 3]]) -> (Vec<DVec3>, Vec<[u32; 3]>) {
    let key = |p: DVec3| (p + DVec3::ZERO).to_array().map(f64::to_bits);
    let mut index: HashMap<[u64; 3], u32> = HashMap::new();
    let mut out = Vec::new();
    let tris = triangles
        .iter()
        .map(|t| {
            t.map(|i| {
                let p = positions[i as usize];
                *index.entry(key(p)).or_insert_with(|| {
                    out.push(p);
                    (out.len() - 1) as u32
                })
            })
        })
        .collect();
    (out, tris)
}

/// Per vertex, the unit mean of the (area-weighted) normals of the triangles using it; zero for
/// a vertex no triangle uses.
fn vertex_normals(positions: &[DVec3], triangles: &[[u32; 3]]) -> Vec<DVec3> {
    let mut acc = std::vec![DVec3::ZERO; positions.len()];
    for t in triangles {
        let [a, b, c] = t.map(|i| positions[i as usize]);
        // Twice the area times the unit normal.
        let n = (b - a).cross(c - a);
        for &i in t {
            acc[i as usize] += n;
        }
    }
    acc.into_iter()
        .map(|n| n.try_normalize().unwrap_or(DVec3::ZERO))
        .collect()
}
