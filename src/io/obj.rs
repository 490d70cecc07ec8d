//! Wavefront OBJ and MTL through `tobj`.
//!
//! The text is checked line by line before tobj sees it, for what tobj does not report (it
//! panics on some malformed lines, and its errors name no line): every face corner must name a
//! vertex, texture coordinate and normal defined before it, and the colour statements of an MTL
//! file are widened from one value (grey, as the MTL format allows) to three.

use std::cell::RefCell;
use std::format;
use std::path::Path;
use std::string::{String, ToString};
use std::vec::Vec;

use glam::DVec3;

use super::object::{RawObject, SceneObject};
use super::{DEFAULT_ALBEDO, SceneFileError, SceneFileErrorKind, material};
use crate::shade::Material;

/// Reads the objects of an OBJ file (see the module documentation of [`super`]).
pub(super) fn read(path: &Path) -> Result<Vec<SceneObject>, SceneFileError> {
    let file_err = |kind| SceneFileError::new(path, None, kind);
    let text = read_text(path)?;
    check_obj(&text).map_err(|m| file_err(SceneFileErrorKind::Parse(m)))?;
    let options = tobj::LoadOptions {
        single_index: true,
        triangulate: true,
        ignore_points: true,
        ignore_lines: true,
    };
    let dir = path.parent().unwrap_or(Path::new(""));
    // The first failure of a material library, reported with its own file name.
    let mtl_error: RefCell<Option<SceneFileError>> = RefCell::new(None);
    let loaded = tobj::load_obj_buf(&mut text.as_bytes(), &options, |lib| {
        let lib_path = dir.join(lib);
        let fail = |e: SceneFileError| {
            mtl_error.borrow_mut().get_or_insert(e);
            Err(tobj::LoadError::MaterialParseError)
        };
        let mtl = match read_text(&lib_path) {
            Ok(t) => t,
            Err(e) => return fail(e),
        };
        match widen_colours(&mtl) {
            Ok(t) => tobj::load_mtl_buf(&mut t.as_bytes()).or_else(|e| {
                fail(SceneFileError::new(
                    &lib_path,
                    None,
                    SceneFileErrorKind::Parse(e.to_string()),
                ))
            }),
            Err(m) => fail(SceneFileError::new(
                &lib_path,
                None,
                SceneFileErrorKind::Parse(m),
            )),
        }
    });
    if let Some(e) = mtl_error.into_inner() {
        return Err(e);
    }
    let (models, materials) =
        loaded.map_err(|e| file_err(SceneFileErrorKind::Parse(e.to_string())))?;
    let materials = materials.unwrap_or_default();
    let mut objects = Vec::with_capacity(models.len());
    for (k, model) in models.iter().enumerate() {
        let name = if model.name.is_empty() {
            format!("object {k}")
        } else {
            model.name.clone()
        };
        let obj_err = |kind| SceneFileError::new(path, Some(&name), kind);
        let mesh = &model.mesh;
        if mesh.indices.is_empty() {
            continue; // points and lines only
        }
        let (mat, emission) = match mesh.material_id.and_then(|id| materials.get(id)) {
            None => (default_material().map_err(obj_err)?, DVec3::ZERO),
            Some(m) => convert_material(m).map_err(|kind| match kind {
                SceneFileErrorKind::Invalid(why) => obj_err(SceneFileErrorKind::Invalid(format!(
                    "material {:?}: {why}",
                    m.name
                ))),
                kind => obj_err(kind),
            })?,
        };
        let triples = |v: &[f64]| -> Vec<DVec3> {
            v.chunks_exact(3)
                .map(|c| DVec3::new(c[0], c[1], c[2]))
                .collect()
        };
        let raw = RawObject {
            name: name.clone(),
            positions: triples(&mesh.positions),
            normals: triples(&mesh.normals),
            triangles: mesh
                .indices
                .chunks_exact(3)
                .map(|t| [t[0], t[1], t[2]])
                .collect(),
            material: mat,
            emission,
            two_sided: false,
        };
        objects.push(raw.check(path)?);
    }
    if objects.is_empty() {
        return Err(file_err(SceneFileErrorKind::Invalid(
            "the file holds no faces".into(),
        )));
    }
    Ok(objects)
}

/// The file as text: an I/O error, or a parse error for text that is not UTF-8.
fn read_text(path: &Path) -> Result<String, SceneFileError> {
    let bytes = std::fs::read(path)
        .map_err(|e| SceneFileError::new(path, None, SceneFileErrorKind::Io(e)))?;
    String::from_utf8(bytes).map_err(|e| {
        SceneFileError::new(
            path,
            None,
            SceneFileErrorKind::Parse(format!(
                "not UTF-8 text (byte {})",
                e.utf8_error().valid_up_to()
            )),
        )
    })
}

/// Checks the face statements (`f`, `l`, `p`): each corner `v`, `v/vt`, `v//vn` or `v/vt/vn`
/// with non-zero integers naming an element defined on an earlier line (a negative index counts
/// back from the last one). Errors name the line.
fn check_obj(text: &str) -> Result<(), String> {
    let mut counts = [0i64; 3]; // v, vt, vn defined so far
    for (no, line) in text.lines().enumerate() {
        let mut words = line.split_whitespace();
        match words.next() {
            Some(k @ ("v" | "vn")) => {
                let numbers = words.take(3).filter(|w| w.parse::<f64>().is_ok()).count();
                if numbers < 3 {
                    return Err(format!("line {}: {k} needs three numbers", no + 1));
                }
                counts[usize::from(k == "vn") * 2] += 1;
            }
            Some("vt") => counts[1] += 1,
            Some("f" | "l" | "p") => {
                for corner in words {
                    check_corner(corner, &counts).map_err(|m| format!("line {}: {m}", no + 1))?;
                }
            }
            _ => {}
        }
    }
    Ok(())
}

/// One face corner (see [`check_obj`]).
fn check_corner(corner: &str, counts: &[i64; 3]) -> Result<(), String> {
    const WHAT: [&str; 3] = ["vertex", "texture coordinate", "normal"];
    let parts: Vec<&str> = corner.split('/').collect();
    if parts.len() > 3 || parts[0].is_empty() {
        return Err(format!(
            "face corner {corner:?} is not v, v/vt, v//vn or v/vt/vn"
        ));
    }
    for (k, p) in parts.iter().enumerate() {
        if p.is_empty() {
            continue;
        }
        let i: i64 = p
            .parse()
            .map_err(|_| format!("face corner {corner:?}: {p:?} is not an integer index"))?;
        let n = counts[k];
        if i == 0 || i > n || i < -n {
            return Err(format!(
                "face corner {corner:?} refers to {} {i}, but {n} are defined before it",
                WHAT[k]
            ));
        }
    }
    Ok(())
}

/// The MTL text with each colour statement (`Ka`, `Kd`, `Ks`, `Ke`) of one value written with
/// three (grey); a colour statement of two or of no value is an error naming the line.
fn widen_colours(text: &str) -> Result<String, String> {
    let mut out = String::with_capacity(text.len() + 64);
    for (no, line) in text.lines().enumerate() {
        let mut words = line.split_whitespace();
        let key = words.next();
        let values: Vec<&str> = words.collect();
        match key {
            Some(k @ ("Ka" | "Kd" | "Ks" | "Ke")) if values.len() == 1 => {
                let g = values[0];
                out.push_str(&format!("{k} {g} {g} {g}\n"));
                continue;
            }
            Some(k @ ("Ka" | "Kd" | "Ks" | "Ke")) if values.len() != 3 => {
                return Err(format!(
                    "line {}: {k} needs one value (grey) or three (RGB), found {}",
                    no + 1,
                    values.len()
                ));
            }
            _ => {}
        }
        out.push_str(line);
        out.push('\n');
    }
    Ok(out)
}

/// The material of an object without one: [`DEFAULT_ALBEDO`] grey, no specular lobe.
fn default_material() -> Result<Material, SceneFileErrorKind> {
    material(DVec3::splat(DEFAULT_ALBEDO), DVec3::ZERO, 1.0)
}

/// An MTL material as a [`Material`] and an emitted radiance (`Ke`).
fn convert_material(m: &tobj::Material) -> Result<(Material, DVec3), SceneFileErrorKind> {
    let rgb = |c: [f64; 3]| DVec3::from_array(c);
    let albedo = m.diffuse.map_or(DVec3::splat(DEFAULT_ALBEDO), rgb);
    let f0 = m.specular.map_or(DVec3::ZERO, rgb);
    let roughness = match m.shininess {
        None => 1.0,
        Some(ns) if ns.is_finite() && ns >= 0.0 => {
            // The Blinn-Phong exponent as a microfacet alpha (Walter et al. 2007, eq. 33), and
            // the material's perceptual roughness `sqrt(alpha)`.
            let alpha = crate::math::sqrt(2.0 / (ns + 2.0));
            crate::math::sqrt(alpha)
        }
        Some(ns) => {
            return Err(SceneFileErrorKind::Invalid(format!(
                "Ns {ns} (the specular exponent must be finite and non-negative)"
            )));
        }
    };
    let emission = m.emissive.map_or(DVec3::ZERO, rgb);
    if !(emission.is_finite() && emission.min_element() >= 0.0) {
        return Err(SceneFileErrorKind::Invalid(format!(
            "Ke {emission:?} (the emitted radiance must be finite and non-negative)"
        )));
    }
    Ok((material(albedo, f0, roughness)?, emission))
}
