//! glTF 2.0 through the `gltf` crate's document model, with the buffers and accessors read here.
//!
//! The crate parses and validates the JSON (and the GLB container); the bytes are read by this
//! module, every range checked first, so that no malformed accessor can index out of bounds:
//! the `gltf` crate's own readers assume well-formed accessors.

use std::format;
use std::path::Path;
use std::string::{String, ToString};
use std::vec::Vec;

use glam::{DMat3, DMat4, DQuat, DVec3};

use super::object::{RawObject, SceneObject};
use super::{SceneFileError, SceneFileErrorKind, material};
use gltf::accessor::{DataType, Dimensions};
use gltf::buffer::Source;
use gltf::mesh::Mode;
use gltf::scene::Transform;

/// Node hierarchies deeper than this are rejected (they can only be a cycle or an abuse).
const MAX_DEPTH: usize = 256;

/// Reads the objects of a glTF file (see the module documentation of [`super`]).
pub(super) fn read(path: &Path) -> Result<Vec<SceneObject>, SceneFileError> {
    let file_err = |kind| SceneFileError::new(path, None, kind);
    let bytes = std::fs::read(path).map_err(|e| file_err(SceneFileErrorKind::Io(e)))?;
    let gltf = parse(&bytes).map_err(|m| file_err(SceneFileErrorKind::Parse(m)))?;
    let dir = path.parent().unwrap_or(Path::new(""));
    let buffers = load_buffers(&gltf, dir, path)?;
    let doc = &gltf.document;
    let roots: Vec<gltf::Node> = match doc.default_scene().or_else(|| doc.scenes().next()) {
        Some(scene) => scene.nodes().collect(),
        None => {
            let mut is_child = std::vec![false; doc.nodes().count()];
            for n in doc.nodes() {
                for c in n.children() {
                    is_child[c.index()] = true;
                }
            }
            doc.nodes().filter(|n| !is_child[n.index()]).collect()
        }
    };
    let mut objects = Vec::new();
    let mut path_nodes = Vec::new();
    for root in roots {
        visit(
            &root,
            DMat4::IDENTITY,
            &mut path_nodes,
            &buffers,
            path,
            &mut objects,
        )?;
    }
    if objects.is_empty() {
        return Err(file_err(SceneFileErrorKind::Invalid(
            "the scene holds no triangles".into(),
        )));
    }
    Ok(objects)
}

/// The document, parsed and validated by the `gltf` crate. Its validation indexes the accessor a
/// primitive names as `POSITION` without a bounds check, so that reference is checked first.
fn parse(bytes: &[u8]) -> Result<gltf::Gltf, String> {
    let raw = gltf::Gltf::from_slice_without_validation(bytes).map_err(|e| e.to_string())?;
    let root = raw.document.into_json();
    for (m, mesh) in root.meshes.iter().enumerate() {
        for (p, prim) in mesh.primitives.iter().enumerate() {
            let pos = gltf::json::validation::Checked::Valid(gltf::Semantic::Positions);
            if let Some(a) = prim.attributes.get(&pos)
                && a.value() >= root.accessors.len()
            {
                return Err(format!(
                    "mesh {m} primitive {p}: POSITION accessor {} does not exist",
                    a.value()
                ));
            }
        }
    }
    let document = gltf::Document::from_json(root).map_err(|e| e.to_string())?;
    Ok(gltf::Gltf {
        document,
        blob: raw.blob,
    })
}

/// The bytes of every buffer: the GLB binary chunk, a `data:` URI (base64), or a file relative
/// to the glTF file's folder; each at least as long as the buffer's declared `byteLength`.
fn load_buffers(
    gltf: &gltf::Gltf,
    dir: &Path,
    path: &Path,
) -> Result<Vec<Vec<u8>>, SceneFileError> {
    let mut out = Vec::new();
    for b in gltf.document.buffers() {
        let invalid = |m: String| SceneFileError::new(path, None, SceneFileErrorKind::Invalid(m));
        let data = match b.source() {
            Source::Bin => gltf.blob.clone().ok_or_else(|| {
                invalid(format!(
                    "buffer {} refers to a GLB binary chunk the file does not have",
                    b.index()
                ))
            })?,
            Source::Uri(uri) => {
                if let Some(rest) = uri.strip_prefix("data:") {
                    let (_, payload) = rest.split_once(";base64,").ok_or_else(|| {
                        SceneFileError::new(
                            path,
                            None,
                            SceneFileErrorKind::Unsupported(format!(
                                "buffer {}: a data URI that is not base64",
                                b.index()
                            )),
                        )
                    })?;
                    decode_base64(payload).ok_or_else(|| {
                        SceneFileError::new(
                            path,
                            None,
                            SceneFileErrorKind::Parse(format!(
                                "buffer {}: invalid base64 data",
                                b.index()
                            )),
                        )
                    })?
                } else {
                    let file = dir.join(percent_decode(uri));
                    std::fs::read(&file)
                        .map_err(|e| SceneFileError::new(&file, None, SceneFileErrorKind::Io(e)))?
                }
            }
        };
        if data.len() < b.length() {
            return Err(invalid(format!(
                "buffer {} holds {} bytes, fewer than its byteLength {}",
                b.index(),
                data.len(),
                b.length()
            )));
        }
        out.push(data);
    }
    Ok(out)
}

/// Walks node `node` with the world transform of its parent, appending one object per triangle
/// primitive of its mesh, then its children.
fn visit(
    node: &gltf::Node,
    parent: DMat4,
    stack: &mut Vec<usize>,
    buffers: &[Vec<u8>],
    path: &Path,
    objects: &mut Vec<SceneObject>,
) -> Result<(), SceneFileError> {
    let node_name = node
        .name()
        .map(String::from)
        .unwrap_or_else(|| format!("node {}", node.index()));
    let err = |kind| SceneFileError::new(path, Some(&node_name), kind);
    if stack.contains(&node.index()) || stack.len() >= MAX_DEPTH {
        return Err(err(SceneFileErrorKind::Invalid(
            "the node hierarchy has a cycle (or is deeper than 256 levels)".into(),
        )));
    }
    let world = parent * local_transform(node).map_err(|m| err(SceneFileErrorKind::Invalid(m)))?;
    if let Some(mesh) = node.mesh() {
        let base = node
            .name()
            .or(mesh.name())
            .map(String::from)
            .unwrap_or_else(|| format!("mesh {}", mesh.index()));
        let count = mesh.primitives().count();
        for (p, prim) in mesh.primitives().enumerate() {
            let name = if count > 1 {
                format!("{base} primitive {p}")
            } else {
                base.clone()
            };
            if let Some(raw) = primitive(&prim, world, buffers)
                .map_err(|kind| SceneFileError::new(path, Some(&name), kind))?
            {
                objects.push(RawObject { name, ..raw }.check(path)?);
            }
        }
    }
    stack.push(node.index());
    for child in node.children() {
        visit(&child, world, stack, buffers, path, objects)?;
    }
    stack.pop();
    Ok(())
}

/// A node's local transform in `f64` (translation * rotation * scale, or its matrix).
fn local_transform(node: &gltf::Node) -> Result<DMat4, String> {
    let m = match node.transform() {
        Transform::Matrix { matrix } => {
            DMat4::from_cols_array_2d(&matrix.map(|c| c.map(f64::from)))
        }
        Transform::Decomposed {
            translation,
            rotation,
            scale,
        } => {
            let q = DQuat::from_array(rotation.map(f64::from));
            let q = if q.length() > 0.0 { q.normalize() } else { q };
            DMat4::from_scale_rotation_translation(
                DVec3::from_array(scale.map(f64::from)),
                q,
                DVec3::from_array(translation.map(f64::from)),
            )
        }
    };
    if !m.is_finite() {
        return Err("the node's transform has a NaN or infinite entry".into());
    }
    Ok(m)
}

/// One primitive in world space, or `None` for points and lines (they bound no area).
fn primitive(
    prim: &gltf::Primitive,
    world: DMat4,
    buffers: &[Vec<u8>],
) -> Result<Option<RawObject>, SceneFileErrorKind> {
    let corners = match prim.mode() {
        Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan => prim.mode(),
        _ => return Ok(None),
    };
    let position = prim
        .get(&gltf::Semantic::Positions)
        .ok_or_else(|| SceneFileErrorKind::Invalid("a primitive without POSITION".into()))?;
    let local = read_vec3(&position, buffers, "POSITION")?;
    let normals_local = match prim.get(&gltf::Semantic::Normals) {
        Some(a) => read_vec3(&a, buffers, "NORMAL")?,
        None => Vec::new(),
    };
    let order: Vec<u32> = match prim.indices() {
        Some(a) => read_indices(&a, buffers)?,
        None => (0..local.len() as u32).collect(),
    };
    let triangles = assemble(corners, &order);
    let linear = DMat3::from_mat4(world);
    let det = linear.determinant();
    if !(det.is_finite() && det != 0.0) {
        return Err(SceneFileErrorKind::Invalid(
            "the node's transform is singular, so the mesh has no area".into(),
        ));
    }
    // A mirroring transform turns counter-clockwise into clockwise: swap two corners so that
    // each triangle keeps facing the side it faced (glTF 2.0, section 3.7.4).
    let triangles = if det < 0.0 {
        triangles.into_iter().map(|[a, b, c]| [a, c, b]).collect()
    } else {
        triangles
    };
    let normal_map = linear.inverse().transpose();
    let m = prim.material();
    let pbr = m.pbr_metallic_roughness();
    let base = DVec3::from_array(
        pbr.base_color_factor()[..3]
            .try_into()
            .unwrap_or([1.0; 3])
            .map(f64::from),
    );
    let metallic = f64::from(pbr.metallic_factor());
    let roughness = f64::from(pbr.roughness_factor());
    if !(0.0..=1.0).contains(&metallic) {
        return Err(SceneFileErrorKind::Invalid(format!(
            "material {:?}: metallicFactor {metallic} outside [0, 1]",
            m.name().unwrap_or("")
        )));
    }
    // The metallic-roughness model's split (glTF 2.0, Appendix B): dielectric f0 = 0.04,
    // metals reflect their base colour and have no diffuse lobe.
    let albedo = base * (1.0 - metallic);
    let f0 = DVec3::splat(0.04).lerp(base, metallic);
    let mat = material(albedo, f0, roughness).map_err(|k| match k {
        SceneFileErrorKind::Invalid(why) => {
            SceneFileErrorKind::Invalid(format!("material {:?}: {why}", m.name().unwrap_or("")))
        }
        k => k,
    })?;
    let strength = m.emissive_strength().map_or(1.0, f64::from);
    let emission = DVec3::from_array(m.emissive_factor().map(f64::from)) * strength;
    Ok(Some(RawObject {
        name: String::new(),
        positions: local.iter().map(|&p| world.transform_point3(p)).collect(),
        normals: normals_local.iter().map(|&n| normal_map * n).collect(),
        triangles,
        material: mat,
        emission,
        two_sided: m.double_sided() && emission.max_element() > 0.0,
    }))
}

/// Triangles from the vertex order of a triangle list, strip or fan (glTF 2.0, section 3.7.2.1:
/// strip triangle `i` is `(i, i + 1 + i % 2, i + 2 - i % 2)`, fan triangle `i` is
/// `(i + 1, i + 2, 0)`); a trailing incomplete triangle is ignored.
fn assemble(mode: Mode, v: &[u32]) -> Vec<[u32; 3]> {
    match mode {
        Mode::TriangleStrip => (0..v.len().saturating_sub(2))
            .map(|i| [v[i], v[i + 1 + i % 2], v[i + 2 - i % 2]])
            .collect(),
        Mode::TriangleFan => (0..v.len().saturating_sub(2))
            .map(|i| [v[i + 1], v[i + 2], v[0]])
            .collect(),
        _ => v.chunks_exact(3).map(|t| [t[0], t[1], t[2]]).collect(),
    }
}

/// The byte ranges of an accessor's elements, checked: `(data, offset of element 0, stride)`,
/// with every element of `size` bytes inside its buffer view and the view inside its buffer.
fn element_range<'b>(
    a: &gltf::Accessor,
    buffers: &'b [Vec<u8>],
    size: usize,
    what: &str,
) -> Result<(&'b [u8], usize, usize), SceneFileErrorKind> {
    let invalid =
        |m: String| SceneFileErrorKind::Invalid(format!("{what} accessor {}: {m}", a.index()));
    if a.sparse().is_some() {
        return Err(SceneFileErrorKind::Unsupported(format!(
            "{what} accessor {}: sparse accessors are not read",
            a.index()
        )));
    }
    let view = a.view().ok_or_else(|| {
        SceneFileErrorKind::Unsupported(format!("{what} accessor {}: no buffer view", a.index()))
    })?;
    let data = buffers
        .get(view.buffer().index())
        .ok_or_else(|| invalid("its buffer does not exist".into()))?;
    let stride = view.stride().unwrap_or(size);
    if stride < size {
        return Err(invalid(format!(
            "byteStride {stride} below the element size {size}"
        )));
    }
    let view_end = view.offset().checked_add(view.length());
    if view_end.is_none_or(|e| e > data.len()) {
        return Err(invalid("its buffer view runs past the buffer".into()));
    }
    let count = a.count();
    if count == 0 {
        return Err(invalid("no elements".into()));
    }
    let end = (count - 1)
        .checked_mul(stride)
        .and_then(|x| x.checked_add(a.offset()))
        .and_then(|x| x.checked_add(size));
    if end.is_none_or(|e| e > view.length()) {
        return Err(invalid("its elements run past its buffer view".into()));
    }
    Ok((data, view.offset() + a.offset(), stride))
}

/// Three `f32` per element (`VEC3` of `FLOAT`), widened.
fn read_vec3(
    a: &gltf::Accessor,
    buffers: &[Vec<u8>],
    what: &str,
) -> Result<Vec<DVec3>, SceneFileErrorKind> {
    if a.data_type() != DataType::F32 || a.dimensions() != Dimensions::Vec3 {
        return Err(SceneFileErrorKind::Unsupported(format!(
            "{what} accessor {}: {:?} {:?}, not VEC3 of FLOAT",
            a.index(),
            a.dimensions(),
            a.data_type()
        )));
    }
    let (data, start, stride) = element_range(a, buffers, 12, what)?;
    let f = |o: usize| {
        f64::from(f32::from_le_bytes([
            data[o],
            data[o + 1],
            data[o + 2],
            data[o + 3],
        ]))
    };
    Ok((0..a.count())
        .map(|i| {
            let o = start + i * stride;
            DVec3::new(f(o), f(o + 4), f(o + 8))
        })
        .collect())
}

/// Unsigned byte, short or int indices (`SCALAR`).
fn read_indices(a: &gltf::Accessor, buffers: &[Vec<u8>]) -> Result<Vec<u32>, SceneFileErrorKind> {
    let size = match (a.data_type(), a.dimensions()) {
        (DataType::U8, Dimensions::Scalar) => 1,
        (DataType::U16, Dimensions::Scalar) => 2,
        (DataType::U32, Dimensions::Scalar) => 4,
        (t, d) => {
            return Err(SceneFileErrorKind::Invalid(format!(
                "index accessor {}: {d:?} {t:?}, not an unsigned integer SCALAR",
                a.index()
            )));
        }
    };
    let (data, start, stride) = element_range(a, buffers, size, "index")?;
    Ok((0..a.count())
        .map(|i| {
            let o = start + i * stride;
            match size {
                1 => u32::from(data[o]),
                2 => u32::from(u16::from_le_bytes([data[o], data[o + 1]])),
                _ => u32::from_le_bytes([data[o], data[o + 1], data[o + 2], data[o + 3]]),
            }
        })
        .collect())
}

/// Standard base64 (RFC 4648, with or without `=` padding); `None` on any other character.
fn decode_base64(text: &str) -> Option<Vec<u8>> {
    let value = |c: u8| -> Option<u32> {
        Some(match c {
            b'A'..=b'Z' => c - b'A',
            b'a'..=b'z' => c - b'a' + 26,
            b'0'..=b'9' => c - b'0' + 52,
            b'+' => 62,
            b'/' => 63,
            _ => return None,
        } as u32)
    };
    let body = text.trim_end_matches('=').as_bytes();
    if text.len() - body.len() > 2 || body.len() % 4 == 1 {
        return None;
    }
    let mut out = Vec::with_capacity(body.len() * 3 / 4);
    for chunk in body.chunks(4) {
        let mut acc = 0u32;
        for &c in chunk {
            acc = (acc << 6) | value(c)?;
        }
        // A chunk of k characters carries 6k bits, of which the first 8 (k - 1) are bytes.
        let bytes = chunk.len() - 1;
        acc <<= 6 * (4 - chunk.len()) as u32;
        for k in 0..bytes {
            out.push((acc >> (16 - 8 * k)) as u8);
        }
    }
    Some(out)
}

/// A relative URI's `%XX` escapes decoded (file names with spaces and the like); anything that
/// is not a valid escape is kept as it is.
fn percent_decode(uri: &str) -> String {
    let b = uri.as_bytes();
    let mut out = Vec::with_capacity(b.len());
    let mut i = 0;
    while i < b.len() {
        let hex = |c: u8| (c as char).to_digit(16);
        if b[i] == b'%'
            && i + 2 < b.len()
            && let (Some(hi), Some(lo)) = (hex(b[i + 1]), hex(b[i + 2]))
        {
            out.push((hi * 16 + lo) as u8);
            i += 3;
        } else {
            out.push(b[i]);
            i += 1;
        }
    }
    String::from_utf8_lossy(&out).into_owned()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn base64_round_trips_every_length() {
        const ALPHABET: &[u8] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
        // Encoded independently, bit by bit.
        let encode = |data: &[u8]| -> String {
            let bits: Vec<u8> = data
                .iter()
                .flat_map(|b| (0..8).rev().map(move |k| (b >> k) & 1))
                .collect();
            let mut s: String = bits
                .chunks(6)
                .map(|c| {
                    let mut v = 0usize;
                    for k in 0..6 {
                        v = (v << 1) | usize::from(*c.get(k).unwrap_or(&0));
                    }
                    ALPHABET[v] as char
                })
                .collect();
            while !s.len().is_multiple_of(4) {
                s.push('=');
            }
            s
        };
        for n in 0..40usize {
            let data: Vec<u8> = (0..n).map(|i| (i * 37 + 11) as u8).collect();
            assert_eq!(
                decode_base64(&encode(&data)),
                Some(data.clone()),
                "length {n}"
            );
        }
        assert_eq!(decode_base64("TWFu"), Some(b"Man".to_vec()));
        assert_eq!(decode_base64("TWE="), Some(b"Ma".to_vec()));
        assert_eq!(decode_base64("TQ=="), Some(b"M".to_vec()));
        assert_eq!(decode_base64("TWF*"), None);
        assert_eq!(decode_base64("T"), None);
    }

    #[test]
    fn percent_escapes_decode() {
        assert_eq!(percent_decode("my%20scene.bin"), "my scene.bin");
        assert_eq!(percent_decode("100%"), "100%");
        assert_eq!(percent_decode("a%zzb"), "a%zzb");
        assert_eq!(percent_decode("a%+1b"), "a%+1b");
    }

    #[test]
    fn strips_and_fans_unroll_as_the_specification_says() {
        assert_eq!(
            assemble(Mode::TriangleStrip, &[0, 1, 2, 3, 4]),
            [[0, 1, 2], [1, 3, 2], [2, 3, 4]]
        );
        assert_eq!(
            assemble(Mode::TriangleFan, &[0, 1, 2, 3]),
            [[1, 2, 0], [2, 3, 0]]
        );
        assert_eq!(assemble(Mode::Triangles, &[0, 1, 2, 3]), [[0, 1, 2]]);
    }
}
