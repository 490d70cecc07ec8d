//! Scene files in (features `obj` and `gltf`): the shipped Cornell box in both formats, small
//! files written here and read back, and malformed files, each an `Err` naming the file, the
//! object and the reason, never a panic.
//!
//! Run: `cargo test --features obj,gltf --test io_scene_files`.
//!
//! References: the published Cornell box coordinates, the closed-form irradiance of a rectangle
//! on its axis (the light seen from the floor point under its centre, every other object
//! removed), what the test itself wrote, and the OBJ and glTF versions of one scene against each
//! other.
#![cfg(all(feature = "obj", feature = "gltf"))]

mod support;

use std::path::{Path, PathBuf};

use arealight::glam::DVec3;
use arealight::io::{SceneFile, SceneFileError, SceneFileErrorKind, load};
use arealight::shade::{Body, Material};
use support::Rng;

fn shipped(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("scenes")
        .join(name)
}

/// A fresh folder for the files of one test.
fn dir(test: &str) -> PathBuf {
    let d = Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join("io_scene_files")
        .join(test);
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn write(dir: &Path, name: &str, text: impl AsRef<[u8]>) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p
}

#[test]
fn the_shipped_cornell_box_loads_in_both_formats_alike() {
    let a = load(shipped("cornell_box.obj")).unwrap();
    let b = load(shipped("cornell_box.gltf")).unwrap();
    let names: Vec<&str> = a.objects.iter().map(|o| o.name.as_str()).collect();
    assert_eq!(
        names,
        [
            "floor",
            "ceiling",
            "back_wall",
            "right_wall",
            "left_wall",
            "light",
            "short_block",
            "tall_block"
        ]
    );
    for file in [&a, &b] {
        assert_eq!(file.scene.lights().len(), 1);
        assert_eq!(file.scene.occluders().len(), 7);
        assert_eq!(file.light_objects, [5]);
        let light = &file.objects[5];
        assert!(light.is_light() && !light.two_sided);
        // The light faces down, at y = 0.5487.
        let m = light.body.mesh();
        assert!(m.is_planar() && m.triangle_normal(0).y < -0.999_999);
        // The blocks are closed and convex; the walls are sheets.
        for k in [6, 7] {
            assert!(
                matches!(file.objects[k].body, Body::Convex(_)),
                "{}",
                file.objects[k].name
            );
            assert_eq!(file.objects[k].triangles.len(), 12);
        }
        for k in 0..5 {
            assert!(matches!(file.objects[k].body, Body::Mesh(_)));
            assert_eq!(file.objects[k].dropped_triangles, 0);
        }
        // Walls face the room: the floor up, the ceiling down, the green (x = 0) wall towards +x.
        assert!(
            file.objects[0]
                .normals
                .iter()
                .all(|n| (*n - DVec3::Y).length() < 1e-12)
        );
        assert!(file.objects[1].normals.iter().all(|n| n.y < -0.999));
        assert!(file.objects[3].normals.iter().all(|n| n.x > 0.999));
        // Diffuse reflectances and the emitted radiance of the published scene's usual RGB.
        let white = file.objects[0].material;
        assert!((white.albedo() - DVec3::splat(0.73)).abs().max_element() < 1e-7);
        assert!((white.f0() - DVec3::splat(0.04)).abs().max_element() < 1e-7);
        assert_eq!(white.roughness(), 1.0);
        let red = file.objects[4].material.albedo();
        assert!((red - DVec3::new(0.63, 0.065, 0.05)).abs().max_element() < 1e-7);
        let e = light.emission;
        assert!(
            (e - DVec3::new(17.0, 12.0, 4.0)).abs().max_element() < 1e-5,
            "{e}"
        );
        // Nothing to report.
        assert!(file.scene.validate::<DVec3>(&[]).is_clean());
        // The published corners (mm / 1000).
        let has = |k: usize, p: DVec3| {
            file.objects[k]
                .positions
                .iter()
                .any(|q| (*q - p).length() < 1e-7)
        };
        assert!(has(5, DVec3::new(0.343, 0.5487, 0.227)));
        assert!(has(5, DVec3::new(0.213, 0.5487, 0.332)));
        assert!(has(7, DVec3::new(0.423, 0.33, 0.247)));
        assert!(has(7, DVec3::new(0.472, 0.0, 0.406)));
        assert!(has(6, DVec3::new(0.082, 0.165, 0.225)));
        assert!(has(4, DVec3::new(0.556, 0.5488, 0.5592)));
    }
    // OBJ (decimal text read into f64) and glTF (f32 buffers): the same objects within f32
    // rounding, the same triangles.
    for (oa, ob) in a.objects.iter().zip(&b.objects) {
        assert_eq!(oa.name, ob.name);
        assert_eq!(oa.triangles.len(), ob.triangles.len(), "{}", oa.name);
        // Vertex lists may be in another order (the OBJ loader lists them by first use): the
        // triangles' corners, in order, are the same points.
        for (ta, tb) in oa.triangles.iter().zip(&ob.triangles) {
            for (&i, &j) in ta.iter().zip(tb) {
                let (p, q) = (oa.positions[i as usize], ob.positions[j as usize]);
                assert!((p - q).abs().max_element() < 1e-7, "{}: {p} {q}", oa.name);
            }
        }
        let (ma, mb) = (oa.material, ob.material);
        assert!(
            (ma.albedo() - mb.albedo()).abs().max_element() < 1e-7,
            "{}",
            oa.name
        );
    }
    // The same shading in both.
    let mut rng = Rng::new(7);
    let floor = &a.objects[0].material;
    for _ in 0..50 {
        let p = DVec3::new(rng.range(0.02, 0.53), 0.0, rng.range(0.02, 0.54));
        let v = DVec3::new(rng.range(-0.3, 0.3), 1.0, -1.0);
        let sa = a.scene.shade(p, DVec3::Y, v, floor).unwrap();
        let sb = b.scene.shade(p, DVec3::Y, v, floor).unwrap();
        assert!(
            (sa - sb).abs().max_element() <= 1e-5 * (1e-3 + sa.max_element()),
            "{p}: {sa} {sb}"
        );
    }
}

/// `(1 / pi) x` the irradiance of a rectangle of half sides `a`, `b` at distance `h` on its
/// axis, parallel to the receiver: four times the form factor of a rectangle with a corner over
/// the point.
fn rectangle_on_axis(a: f64, b: f64, h: f64) -> f64 {
    let (x, y) = (a / h, b / h);
    let (sx, sy) = ((1.0 + x * x).sqrt(), (1.0 + y * y).sqrt());
    2.0 / std::f64::consts::PI * (x / sx * (y / sx).atan() + y / sy * (x / sy).atan())
}

#[test]
fn the_cornell_light_seen_from_the_floor_is_the_closed_form_rectangle() {
    let file = load(shipped("cornell_box.obj")).unwrap();
    let floor = file.objects[0].material;
    let below = DVec3::new(0.278, 0.0, 0.2795);
    let parts = file
        .scene
        .shade_per_light(below, DVec3::Y, DVec3::Y, &floor)
        .unwrap();
    let want =
        rectangle_on_axis(0.065, 0.0525, 0.5487) * floor.albedo() * DVec3::new(17.0, 12.0, 4.0);
    let got = parts[0].unshadowed_diffuse;
    assert!(
        (got - want).abs().max_element() < 1e-12 * want.max_element(),
        "{got} {want}"
    );
    // The closed form is not a coincidence of the square formula: a square of the same area
    // differs.
    let square = rectangle_on_axis(0.0584, 0.0584, 0.5487);
    assert!((square - rectangle_on_axis(0.065, 0.0525, 0.5487)).abs() > 1e-6);
}

/// Base64 of bytes (RFC 4648, padded), for the glTF files written here.
fn base64(data: &[u8]) -> String {
    const A: &[u8] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut s = String::new();
    for c in data.chunks(3) {
        let v = (u32::from(c[0]) << 16)
            | (u32::from(*c.get(1).unwrap_or(&0)) << 8)
            | u32::from(*c.get(2).unwrap_or(&0));
        for k in 0..4 {
            if k <= c.len() {
                s.push(A[((v >> (18 - 6 * k)) & 63) as usize] as char);
            } else {
                s.push('=');
            }
        }
    }
    s
}

/// A glTF document written by hand: buffer views over one buffer, accessors, meshes, nodes.
#[derive(Default)]
struct Gltf {
    buf: Vec<u8>,
    views: Vec<String>,
    accessors: Vec<String>,
    meshes: Vec<String>,
    nodes: Vec<String>,
    materials: Vec<String>,
}

impl Gltf {
    fn view(&mut self, bytes: &[u8]) -> usize {
        while !self.buf.len().is_multiple_of(4) {
            self.buf.push(0);
        }
        self.views.push(format!(
            r#"{{"buffer": 0, "byteOffset": {}, "byteLength": {}}}"#,
            self.buf.len(),
            bytes.len()
        ));
        self.buf.extend_from_slice(bytes);
        self.views.len() - 1
    }

    fn positions(&mut self, p: &[[f32; 3]]) -> usize {
        let bytes: Vec<u8> = p.iter().flatten().flat_map(|x| x.to_le_bytes()).collect();
        let v = self.view(&bytes);
        let (mut lo, mut hi) = ([f32::MAX; 3], [f32::MIN; 3]);
        for q in p {
            for k in 0..3 {
                lo[k] = lo[k].min(q[k]);
                hi[k] = hi[k].max(q[k]);
            }
        }
        self.accessors.push(format!(
            r#"{{"bufferView": {v}, "componentType": 5126, "count": {}, "type": "VEC3", "min": {lo:?}, "max": {hi:?}}}"#,
            p.len()
        ));
        self.accessors.len() - 1
    }

    fn normals(&mut self, n: &[[f32; 3]]) -> usize {
        let bytes: Vec<u8> = n.iter().flatten().flat_map(|x| x.to_le_bytes()).collect();
        let v = self.view(&bytes);
        self.accessors.push(format!(
            r#"{{"bufferView": {v}, "componentType": 5126, "count": {}, "type": "VEC3"}}"#,
            n.len()
        ));
        self.accessors.len() - 1
    }

    fn indices(&mut self, i: &[u16]) -> usize {
        let bytes: Vec<u8> = i.iter().flat_map(|x| x.to_le_bytes()).collect();
        let v = self.view(&bytes);
        self.accessors.push(format!(
            r#"{{"bufferView": {v}, "componentType": 5123, "count": {}, "type": "SCALAR"}}"#,
            i.len()
        ));
        self.accessors.len() - 1
    }

    /// A mesh of one primitive; `attributes` and the rest as JSON fragments.
    fn mesh(&mut self, name: &str, primitive: String) -> usize {
        self.meshes.push(format!(
            r#"{{"name": "{name}", "primitives": [{primitive}]}}"#
        ));
        self.meshes.len() - 1
    }

    fn node(&mut self, json: String) -> usize {
        self.nodes.push(json);
        self.nodes.len() - 1
    }

    fn json(&self, buffer_uri: Option<&str>) -> String {
        let uri = match buffer_uri {
            Some(u) => format!(r#", "uri": "{u}""#),
            None => String::new(),
        };
        let roots: Vec<usize> = (0..self.nodes.len()).collect();
        format!(
            r#"{{"asset": {{"version": "2.0"}}, "extensionsUsed": ["KHR_materials_emissive_strength"],
            "scene": 0, "scenes": [{{"nodes": {roots:?}}}],
            "nodes": [{}], "meshes": [{}], "materials": [{}], "accessors": [{}],
            "bufferViews": [{}], "buffers": [{{"byteLength": {}{uri}}}]}}"#,
            self.nodes.join(","),
            self.meshes.join(","),
            self.materials.join(","),
            self.accessors.join(","),
            self.views.join(","),
            self.buf.len()
        )
    }

    fn gltf_text(&self) -> String {
        self.json(Some(&format!(
            "data:application/octet-stream;base64,{}",
            base64(&self.buf)
        )))
    }

    /// The binary container: header, JSON chunk (space padded), BIN chunk (zero padded).
    fn glb(&self) -> Vec<u8> {
        let mut json = self.json(None).into_bytes();
        while !json.len().is_multiple_of(4) {
            json.push(b' ');
        }
        let mut bin = self.buf.clone();
        while !bin.len().is_multiple_of(4) {
            bin.push(0);
        }
        let total = 12 + 8 + json.len() + 8 + bin.len();
        let mut out = Vec::new();
        out.extend_from_slice(b"glTF");
        out.extend_from_slice(&2u32.to_le_bytes());
        out.extend_from_slice(&(total as u32).to_le_bytes());
        out.extend_from_slice(&(json.len() as u32).to_le_bytes());
        out.extend_from_slice(b"JSON");
        out.extend_from_slice(&json);
        out.extend_from_slice(&(bin.len() as u32).to_le_bytes());
        out.extend_from_slice(b"BIN\0");
        out.extend_from_slice(&bin);
        out
    }
}

/// A unit tetrahedron, outward faces.
const TETRA: [[f32; 3]; 4] = [
    [0.0, 0.0, 0.0],
    [1.0, 0.0, 0.0],
    [0.0, 1.0, 0.0],
    [0.0, 0.0, 1.0],
];
const TETRA_TRIS: [u16; 12] = [0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3];

/// A test scene as glTF: a translated, scaled tetrahedron occluder with a glossy material; a
/// mirrored (negative scale) copy; an emissive quad light drawn as a triangle strip with normals,
/// double-sided, with an emissive strength; a triangle without a material.
fn test_gltf() -> Gltf {
    let mut g = Gltf::default();
    g.materials.push(
        r#"{"name": "glossy", "pbrMetallicRoughness": {"baseColorFactor": [0.5, 0.25, 1.0, 1.0], "metallicFactor": 0.5, "roughnessFactor": 0.3}}"#
            .into(),
    );
    g.materials.push(
        r#"{"name": "lamp", "emissiveFactor": [1.0, 0.5, 0.25], "doubleSided": true,
            "extensions": {"KHR_materials_emissive_strength": {"emissiveStrength": 8.0}}}"#
            .into(),
    );
    let p = g.positions(&TETRA);
    let i = g.indices(&TETRA_TRIS);
    let tet = g.mesh(
        "tet",
        format!(r#"{{"attributes": {{"POSITION": {p}}}, "indices": {i}, "material": 0}}"#),
    );
    g.node(format!(
        r#"{{"name": "block", "mesh": {tet}, "translation": [1.0, 2.0, 3.0], "scale": [2.0, 2.0, 2.0]}}"#
    ));
    g.node(format!(
        r#"{{"name": "mirrored", "mesh": {tet}, "scale": [-1.0, 1.0, 1.0], "translation": [-3.0, 0.0, 0.0]}}"#
    ));
    // Strip 0 1 2 3 over the quad (0,0) (1,0) (0,1) (1,1) at height 5: triangles (0 1 2),
    // (1 3 2), both counter-clockwise seen from above.
    let q = g.positions(&[
        [0.0, 0.0, 5.0],
        [1.0, 0.0, 5.0],
        [0.0, 1.0, 5.0],
        [1.0, 1.0, 5.0],
    ]);
    let n = g.normals(&[[0.0, 0.0, 2.0]; 4]);
    let lamp = g.mesh(
        "lamp",
        format!(
            r#"{{"attributes": {{"POSITION": {q}, "NORMAL": {n}}}, "material": 1, "mode": 5}}"#
        ),
    );
    g.node(format!(r#"{{"mesh": {lamp}}}"#));
    let t = g.positions(&[[5.0, 0.0, 0.0], [6.0, 0.0, 0.0], [5.0, 1.0, 0.0]]);
    let plain = g.mesh("plain", format!(r#"{{"attributes": {{"POSITION": {t}}}}}"#));
    g.node(format!(r#"{{"mesh": {plain}}}"#));
    g
}

fn check_test_gltf(file: &SceneFile) {
    let names: Vec<&str> = file.objects.iter().map(|o| o.name.as_str()).collect();
    assert_eq!(names, ["block", "mirrored", "lamp", "plain"]);
    // Node transforms: 2 x + (1, 2, 3).
    let block = &file.objects[0];
    let want: Vec<DVec3> = TETRA
        .iter()
        .map(|p| 2.0 * DVec3::from_array(p.map(f64::from)) + DVec3::new(1.0, 2.0, 3.0))
        .collect();
    assert_eq!(block.positions, want);
    assert!(matches!(block.body, Body::Convex(_)));
    // Both tetrahedra stay outward: the mirrored one had its triangles reversed.
    for o in &file.objects[..2] {
        let m = o.body.mesh();
        let c = m.vertices().iter().copied().sum::<DVec3>() / 4.0;
        for t in 0..m.triangle_count() {
            let [a, ..] = m.triangle(t);
            assert!(
                m.triangle_normal(t).dot(a - c) > 0.0,
                "{} triangle {t}",
                o.name
            );
        }
    }
    // Metallic-roughness: albedo base (1 - metallic), f0 = 0.04 blended to the base colour.
    let mat = block.material;
    assert!(
        (mat.albedo() - DVec3::new(0.25, 0.125, 0.5))
            .abs()
            .max_element()
            < 1e-7
    );
    assert!(
        (mat.f0() - DVec3::new(0.27, 0.145, 0.52))
            .abs()
            .max_element()
            < 1e-7
    );
    assert!((mat.roughness() - 0.3).abs() < 1e-7);
    // The strip's two triangles, the file's normals (normalized), the emission with its
    // strength, two-sided because double-sided and planar.
    let lamp = &file.objects[2];
    assert_eq!(lamp.triangles, [[0, 1, 2], [1, 3, 2]]);
    assert!(lamp.normals.iter().all(|n| *n == DVec3::Z));
    assert_eq!(lamp.emission, DVec3::new(8.0, 4.0, 2.0));
    assert!(lamp.two_sided && file.scene.lights()[0].is_two_sided());
    assert_eq!(file.light_objects, [2]);
    // No material: the specification's default (white, metallic 1, roughness 1); no normals:
    // the face normal.
    let plain = &file.objects[3];
    assert_eq!(
        plain.material,
        Material::new(DVec3::ZERO, DVec3::ONE, 1.0).unwrap()
    );
    assert!(plain.normals.iter().all(|n| *n == DVec3::Z));
}

#[test]
fn gltf_files_written_here_read_back() {
    let d = dir("gltf_round_trip");
    let g = test_gltf();
    check_test_gltf(&load(write(&d, "scene.gltf", g.gltf_text())).unwrap());
    check_test_gltf(&load(write(&d, "scene.glb", g.glb())).unwrap());
    // The buffer in a file of its own, its name percent-encoded in the URI.
    write(&d, "my buffer.bin", &g.buf);
    check_test_gltf(&load(write(&d, "external.gltf", g.json(Some("my%20buffer.bin")))).unwrap());
    // The two-sided light lights both sides of its plane.
    let file = load(d.join("scene.gltf")).unwrap();
    let white = Material::diffuse(DVec3::ONE).unwrap();
    let c = DVec3::new(0.5, 0.5, 0.0);
    let below = file
        .scene
        .shade_light(0, c + DVec3::Z * 3.0, DVec3::Z, DVec3::Z, &white)
        .unwrap();
    let above = file
        .scene
        .shade_light(0, c + DVec3::Z * 7.0, -DVec3::Z, -DVec3::Z, &white)
        .unwrap();
    assert!(below.x > 0.0 && (below - above).abs().max_element() < 1e-12 * below.x);
}

#[test]
fn obj_files_written_here_read_back() {
    let d = dir("obj_round_trip");
    write(
        &d,
        "scene.mtl",
        "newmtl lamp\nKd 0.5\nKe 2 3 4\n\nnewmtl shiny\nKd 0.2 0.4 0.6\nKs 0.5 0.5 0.5\nNs 98\n",
    );
    let text = "\
mtllib scene.mtl
o plain
v 0 0 -1
v 1 0 -1
v 0 1 -1
v 2 0 -1
f -4 -3 -2
f 1 2 4
o lamp
usemtl lamp
v 0 0 2
v 0 1 2
v 1 1 2
v 1 0 2
f 5 6 7 8
o pentagon
usemtl shiny
v 0 0 0
v 2 0 0
v 3 1 0
v 1 3 0
v -1 1 0
vn 0 0 1
f 9//1 10//1 11//1 12//1 13//1
o unknown
usemtl nothing_by_that_name
f 1 3 2
";
    let file = load(write(&d, "scene.obj", text)).unwrap();
    let names: Vec<&str> = file.objects.iter().map(|o| o.name.as_str()).collect();
    assert_eq!(names, ["plain", "lamp", "pentagon", "unknown"]);
    let lamp = &file.objects[1];
    // Vertices as written, the quad fanned from its first corner, facing down (clockwise seen
    // from above as written), `Kd 0.5` read as grey, `Ke` as the radiance.
    assert_eq!(
        lamp.positions,
        [
            DVec3::new(0.0, 0.0, 2.0),
            DVec3::new(0.0, 1.0, 2.0),
            DVec3::new(1.0, 1.0, 2.0),
            DVec3::new(1.0, 0.0, 2.0)
        ]
    );
    assert_eq!(lamp.triangles, [[0, 1, 2], [0, 2, 3]]);
    assert!(lamp.body.mesh().triangle_normal(0).z < 0.0);
    assert_eq!(lamp.material.albedo(), DVec3::splat(0.5));
    assert_eq!(lamp.emission, DVec3::new(2.0, 3.0, 4.0));
    assert_eq!(file.light_objects, [1]);
    // A pentagon with the file's normals; Ks as f0; Ns 98 as roughness sqrt(sqrt(2 / 100)).
    let pent = &file.objects[2];
    assert_eq!(pent.triangles.len(), 3);
    assert!(pent.normals.iter().all(|n| *n == DVec3::Z));
    assert_eq!(pent.material.f0(), DVec3::splat(0.5));
    assert!((pent.material.roughness() - 0.02f64.sqrt().sqrt()).abs() < 1e-15);
    // No material, and a zero-area triangle (1, 2, 4 are collinear) dropped and counted;
    // relative indices.
    let plain = &file.objects[0];
    assert_eq!(plain.triangles.len(), 1);
    assert_eq!(plain.dropped_triangles, 1);
    assert_eq!(
        plain.material,
        Material::diffuse(DVec3::splat(arealight::io::DEFAULT_ALBEDO)).unwrap()
    );
    assert!(plain.normals[..3].iter().all(|n| *n == DVec3::Z));
    // An unknown material name: the default as well.
    assert_eq!(file.objects[3].material, plain.material);
    assert_eq!(file.scene.occluders().len(), 3);
    // No material library at all: defaults.
    let bare = load(write(
        &d,
        "bare.obj",
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
    ))
    .unwrap();
    assert_eq!(bare.objects.len(), 1);
    assert!(bare.scene.lights().is_empty());
}

/// The error, checked to name `file` and the object (`Some("*")`: whichever the loader or the
/// format's validation names first), and to say `reason`.
#[track_caller]
fn fails(
    r: Result<SceneFile, SceneFileError>,
    file: &str,
    object: Option<&str>,
    reason: &str,
) -> SceneFileError {
    let e = r.expect_err("an error");
    let msg = e.to_string();
    eprintln!("{msg}");
    assert!(e.file.ends_with(file), "{msg}");
    if object != Some("*") {
        assert_eq!(e.object.as_deref(), object, "{msg}");
    }
    assert!(msg.contains(file) && msg.contains(reason), "{msg}");
    e
}

#[test]
fn malformed_obj_files_are_errors_naming_file_object_and_reason() {
    let d = dir("obj_malformed");
    let tri = "v 0 0 0\nv 1 0 0\nv 0 1 0\n";
    let f = |name: &str, text: &str| load(write(&d, name, text));
    fails(
        f("nan.obj", "o bad\nv nan 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"),
        "nan.obj",
        Some("bad"),
        "NaN",
    );
    fails(
        f("inf.obj", "o big\nv 1e400 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"),
        "inf.obj",
        Some("big"),
        "infinite",
    );
    fails(
        f("far.obj", "o far\nv 1e200 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"),
        "far.obj",
        Some("far"),
        "outside the supported range",
    );
    fails(
        f("index.obj", &format!("{tri}f 1 2 9\n")),
        "index.obj",
        None,
        "line 4",
    );
    fails(
        f("zero.obj", &format!("{tri}f 0 1 2\n")),
        "zero.obj",
        None,
        "vertex 0",
    );
    fails(
        f("back.obj", &format!("{tri}f -4 1 2\n")),
        "back.obj",
        None,
        "vertex -4",
    );
    fails(
        f("huge.obj", &format!("{tri}f 1/99999999999999999999 2 3\n")),
        "huge.obj",
        None,
        "not an integer",
    );
    fails(
        f("vt.obj", &format!("{tri}f 1/1 2/1 3/1\n")),
        "vt.obj",
        None,
        "texture coordinate",
    );
    fails(
        f("parts.obj", &format!("{tri}f 1/1/1/1 2 3\n")),
        "parts.obj",
        None,
        "face corner",
    );
    fails(
        f("flat.obj", "o line\nv 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n"),
        "flat.obj",
        Some("line"),
        "no triangle of non-zero area",
    );
    fails(f("empty.obj", ""), "empty.obj", None, "no faces");
    fails(
        f("text.obj", "v 1 2 three\nf 1 1 1\n"),
        "text.obj",
        None,
        "line 1: v needs three numbers",
    );
    let e = fails(
        load(d.join("missing.obj")),
        "missing.obj",
        None,
        "cannot read",
    );
    assert!(matches!(e.kind, SceneFileErrorKind::Io(_)));
    fails(
        load(write(&d, "bytes.obj", [b'v', b' ', 0xff, 0xfe, b'\n'])),
        "bytes.obj",
        None,
        "UTF-8",
    );
    fails(
        load(write(&d, "mesh.stl", "solid")),
        "mesh.stl",
        None,
        "unknown scene file extension",
    );
    // Material libraries: missing, malformed, out of range.
    let with = |lib: &str| format!("mtllib {lib}\no thing\nusemtl m\n{tri}f 1 2 3\n");
    fails(
        f("nolib.obj", &with("absent.mtl")),
        "absent.mtl",
        None,
        "cannot read",
    );
    write(&d, "two.mtl", "newmtl m\nKd 0.5 0.5\n");
    fails(f("two.obj", &with("two.mtl")), "two.mtl", None, "line 2");
    write(&d, "bright.mtl", "newmtl m\nKd 1.5 0.5 0.5\n");
    fails(
        f("bright.obj", &with("bright.mtl")),
        "bright.obj",
        Some("thing"),
        "material \"m\"",
    );
    write(&d, "dark.mtl", "newmtl m\nKe -1 0 0\n");
    fails(
        f("dark.obj", &with("dark.mtl")),
        "dark.obj",
        Some("thing"),
        "Ke",
    );
    write(&d, "ns.mtl", "newmtl m\nNs -3\n");
    fails(f("ns.obj", &with("ns.mtl")), "ns.obj", Some("thing"), "Ns");
    write(&d, "nan.mtl", "newmtl m\nKd nan 0 0\n");
    fails(
        f("nanmtl.obj", &with("nan.mtl")),
        "nanmtl.obj",
        Some("thing"),
        "albedo",
    );
}

/// `test_gltf` with one edit of its JSON text.
fn edited(d: &Path, name: &str, from: &str, to: &str) -> Result<SceneFile, SceneFileError> {
    let text = test_gltf().gltf_text();
    assert!(text.contains(from), "{from}");
    load(write(d, name, text.replacen(from, to, 1)))
}

#[test]
fn malformed_gltf_files_are_errors_naming_file_object_and_reason() {
    let d = dir("gltf_malformed");
    fails(
        load(write(&d, "junk.gltf", "{ not json")),
        "junk.gltf",
        None,
        "parse error",
    );
    let glb = test_gltf().glb();
    fails(
        load(write(&d, "short.glb", &glb[..glb.len() / 2])),
        "short.glb",
        None,
        "parse error",
    );
    // Accessors: past the end of the view, the wrong type, sparse, without a view.
    fails(
        edited(
            &d,
            "count.gltf",
            r#""count": 4, "type": "VEC3", "min""#,
            r#""count": 40, "type": "VEC3", "min""#,
        ),
        "count.gltf",
        Some("block"),
        "run past",
    );
    fails(
        edited(
            &d,
            "vec2.gltf",
            r#""count": 4, "type": "VEC3", "min""#,
            r#""count": 4, "type": "VEC2", "min""#,
        ),
        "vec2.gltf",
        Some("*"),
        "",
    );
    fails(
        edited(
            &d,
            "sparse.gltf",
            r#""count": 4, "type": "VEC3", "min""#,
            r#""sparse": {"count": 1, "indices": {"bufferView": 1, "componentType": 5123}, "values": {"bufferView": 0}}, "count": 4, "type": "VEC3", "min""#,
        ),
        "sparse.gltf",
        Some("block"),
        "sparse",
    );
    // A primitive naming an accessor that does not exist (the gltf crate's own validation
    // indexed it unchecked: found by corrupted_files_never_panic).
    fails(
        edited(
            &d,
            "position.gltf",
            r#""POSITION": 0}"#,
            r#""POSITION": 99}"#,
        ),
        "position.gltf",
        None,
        "POSITION accessor 99 does not exist",
    );
    // NaN coordinates: the first position replaced by a NaN in the buffer.
    let mut g = test_gltf();
    g.buf[0..4].copy_from_slice(&f32::NAN.to_le_bytes());
    fails(
        load(write(&d, "nan.gltf", g.gltf_text())),
        "nan.gltf",
        Some("block"),
        "NaN",
    );
    // Transforms: singular, non-finite.
    fails(
        edited(
            &d,
            "flat.gltf",
            r#""scale": [2.0, 2.0, 2.0]"#,
            r#""scale": [2.0, 0.0, 2.0]"#,
        ),
        "flat.gltf",
        Some("block"),
        "singular",
    );
    fails(
        edited(
            &d,
            "inf.gltf",
            r#""translation": [1.0, 2.0, 3.0]"#,
            r#""translation": [1.0, 2.0, 3e39]"#,
        ),
        "inf.gltf",
        Some("*"),
        "",
    );
    // Materials: out of range, a double-sided emitter that is not planar.
    fails(
        edited(
            &d,
            "metal.gltf",
            r#""metallicFactor": 0.5"#,
            r#""metallicFactor": 2.0"#,
        ),
        "metal.gltf",
        Some("*"),
        "",
    );
    fails(
        edited(&d, "curved.gltf", r#""material": 0}"#, r#""material": 1}"#),
        "curved.gltf",
        Some("block"),
        "planar",
    );
    // Buffers: missing file, bad base64, shorter than declared.
    fails(
        load(write(
            &d,
            "nofile.gltf",
            test_gltf().json(Some("absent.bin")),
        )),
        "absent.bin",
        None,
        "cannot read",
    );
    fails(
        edited(&d, "b64.gltf", "base64,", "base64,*"),
        "b64.gltf",
        None,
        "base64",
    );
    let mut short = test_gltf();
    let full = short.buf.len();
    short.buf.truncate(full - 8);
    let text = short.gltf_text().replacen(
        &format!(r#""byteLength": {}"#, full - 8),
        &format!(r#""byteLength": {full}"#),
        1,
    );
    fails(
        load(write(&d, "short.gltf", text)),
        "short.gltf",
        Some("*"),
        "",
    );
    // A node cycle.
    fails(
        edited(
            &d,
            "cycle.gltf",
            r#"{"name": "block", "#,
            r#"{"name": "block", "children": [0], "#,
        ),
        "cycle.gltf",
        Some("*"),
        "",
    );
    // Nothing but lines.
    let mut lines = Gltf::default();
    let p = lines.positions(&TETRA);
    let m = lines.mesh(
        "l",
        format!(r#"{{"attributes": {{"POSITION": {p}}}, "mode": 1}}"#),
    );
    lines.node(format!(r#"{{"mesh": {m}}}"#));
    fails(
        load(write(&d, "lines.gltf", lines.gltf_text())),
        "lines.gltf",
        None,
        "no triangles",
    );
}

/// Byte-level corruptions of the shipped files (and of a GLB version of the test scene): each
/// load returns, `Ok` or `Err`, and never panics. `SCENE_FILE_MUTATIONS=N` for a longer run.
#[test]
fn corrupted_files_never_panic() {
    let d = dir("corrupted");
    let n: usize = std::env::var("SCENE_FILE_MUTATIONS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(150);
    let obj = std::fs::read(shipped("cornell_box.obj")).unwrap();
    let mtl = std::fs::read(shipped("cornell_box.mtl")).unwrap();
    let gltf = std::fs::read(shipped("cornell_box.gltf")).unwrap();
    let glb = test_gltf().glb();
    let mut rng = Rng::new(11);
    let alphabet = b"0123456789 -./\n#fvonaeKdsu{}[]\":,e+";
    let mut outcomes = [0usize; 2];
    for i in 0..n {
        for (k, (name, base)) in [
            ("c.obj", &obj),
            ("c.mtl", &mtl),
            ("c.gltf", &gltf),
            ("c.glb", &glb),
        ]
        .into_iter()
        .enumerate()
        {
            let mut bytes = base.clone();
            for _ in 0..1 + rng.below(4) {
                let at = rng.below(bytes.len());
                match rng.below(3) {
                    0 => bytes[at] = alphabet[rng.below(alphabet.len())],
                    1 => {
                        bytes.remove(at);
                    }
                    _ => bytes.insert(at, alphabet[rng.below(alphabet.len())]),
                }
                if k == 3 && rng.below(4) == 0 {
                    bytes[at] = (rng.next_u64() & 0xff) as u8;
                }
            }
            let path = write(&d, name, &bytes);
            // The MTL is read through an OBJ naming it.
            let path = if k == 1 {
                write(&d, "c.obj", obj.clone().replace_mtl("c.mtl"))
            } else {
                path
            };
            let r = load(&path);
            outcomes[usize::from(r.is_ok())] += 1;
            if let Err(e) = r {
                assert!(!e.to_string().is_empty(), "mutation {i} of {name}");
            }
        }
    }
    eprintln!("{} errors, {} loads", outcomes[0], outcomes[1]);
    assert!(outcomes[0] > 0 && outcomes[1] > 0);
}

trait ReplaceMtl {
    fn replace_mtl(self, lib: &str) -> Vec<u8>;
}

impl ReplaceMtl for Vec<u8> {
    fn replace_mtl(self, lib: &str) -> Vec<u8> {
        String::from_utf8(self)
            .unwrap()
            .replace("mtllib cornell_box.mtl", &format!("mtllib {lib}"))
            .into_bytes()
    }
}
