//! Bakes noise-free direct lighting per vertex of a scene file: every non-emissive object is
//! subdivided into a grid of vertices about `--spacing` apart, each vertex is shaded exactly
//! (diffuse lobe, so the value does not depend on the view: what a lightmap or vertex colours
//! can hold), and the result is written as a PLY mesh with vertex colours, with a picture of it.
//!
//! ```sh
//! cargo run --release -p arealight-demo --features obj,gltf --bin bake
//! cargo run --release -p arealight-demo --features obj,gltf --bin bake -- scenes/cornell_box.obj --spacing 0.005
//! ```
//!
//! Writes to `target/arealight-out/`:
//!
//! - `<stem>_bake.ply`: ASCII PLY, per vertex position, normal, `red green blue` (the radiance
//!   tone mapped with `1 - exp(-exposure x)`, sRGB, as `uchar`) and `radiance_r radiance_g
//!   radiance_b` (linear, `float`); the emitters carry their emitted radiance. Vertices are
//!   shared within a face plane of an object, so each flat face is one smooth patch.
//! - `<stem>_bake.png`: the baked mesh seen from the camera (the Cornell box camera by default),
//!   colours interpolated across each grid triangle from its vertices, nothing shaded per pixel.
//!
//! Prints the number of vertices, the time to shade them (in total and per vertex), and the
//! vertices whose shading gave up (`GeomError::Undecidable`), which are estimated by the Monte
//! Carlo reference instead.

use std::collections::HashMap;
use std::fmt::Write as _;
use std::path::PathBuf;
use std::time::Instant;

use arealight::glam::DVec3;
use arealight::io::SceneFile;
use arealight::shade::{Material, MonteCarlo, ReferenceBrdf};
use arealight_demo::image::{out_dir, srgb, to_bytes, write_png};
use arealight_demo::progress::Progress;
use arealight_demo::trace::{Camera, nearest};
use arealight_demo::{args_or_exit, cornell_camera, parse_vec, run_or_exit};

const HELP: &str = "\
bake: per-vertex direct lighting of a scene file, to PLY with vertex colours, and a picture

USAGE: cargo run --release -p arealight-demo --features obj,gltf --bin bake -- [FILE] [FLAGS]

  FILE             .obj, .gltf or .glb (default scenes/cornell_box.gltf)
  --spacing S      vertex spacing in scene units (default 0.01: 1 cm in the Cornell box)
  --width W        picture width (default 320)
  --height H       picture height (default 320)
  --eye x,y,z      camera of the picture (default the Cornell box camera)
  --target x,y,z   point looked at (default 0.278,0.273,0)
  --exposure E     tone map 1 - exp(-E x) (default 3)
  --threads T      worker threads (default 0: all cores)
  --help           this text
";

struct Args {
    file: PathBuf,
    spacing: f64,
    width: usize,
    height: usize,
    eye: DVec3,
    target: DVec3,
    exposure: f64,
    threads: usize,
}

fn parse_args() -> Result<Args, String> {
    let (eye, target, _, _) = cornell_camera();
    let mut a = Args {
        file: arealight_demo::repo_path("scenes/cornell_box.gltf"),
        spacing: 0.01,
        width: 320,
        height: 320,
        eye,
        target,
        exposure: 3.0,
        threads: 0,
    };
    let mut it = std::env::args().skip(1);
    while let Some(flag) = it.next() {
        let mut value = |name: &str| it.next().ok_or(format!("{name} needs a value"));
        let num = |s: String| s.parse::<f64>().map_err(|e| format!("{s}: {e}"));
        match flag.as_str() {
            "--help" | "-h" => {
                print!("{HELP}");
                std::process::exit(0);
            }
            "--spacing" => a.spacing = num(value("--spacing")?)?,
            "--width" => a.width = num(value("--width")?)? as usize,
            "--height" => a.height = num(value("--height")?)? as usize,
            "--eye" => a.eye = parse_vec(&value("--eye")?)?,
            "--target" => a.target = parse_vec(&value("--target")?)?,
            "--exposure" => a.exposure = num(value("--exposure")?)?,
            "--threads" => a.threads = num(value("--threads")?)? as usize,
            f if !f.starts_with("--") => a.file = PathBuf::from(f),
            other => return Err(format!("unknown flag {other}\n\n{HELP}")),
        }
    }
    if !(a.spacing > 0.0 && a.spacing.is_finite()) {
        return Err("--spacing must be positive".into());
    }
    if !(1..=8192).contains(&a.width) || !(1..=8192).contains(&a.height) {
        return Err("resolution must be between 1 and 8192".into());
    }
    Ok(a)
}

fn main() {
    let args = args_or_exit(parse_args());
    run_or_exit("bake", args.threads, || run(&args));
}

/// The baked mesh: welded grid vertices with their normals and radiance, the grid triangles, and
/// per object triangle the index of each of its grid points, for the picture.
#[derive(Default)]
struct Baked {
    positions: Vec<DVec3>,
    normals: Vec<DVec3>,
    radiance: Vec<DVec3>,
    /// Per vertex: the object it belongs to (its material), or `None` for an emitter's.
    owner: Vec<Option<usize>>,
    triangles: Vec<[u32; 3]>,
    /// Per object, per triangle: grid size `n` and the vertex of grid point `(i, j)` at
    /// `i * (n + 1) + j` (`i + j <= n`).
    grids: Vec<Vec<(usize, Vec<u32>)>>,
}

/// The welding key of a grid point: position and normal on a `1e-9` grid (the grid points of a
/// shared edge are computed from its two ends in either order, so they agree to rounding, not
/// bit for bit).
fn key(p: DVec3, n: DVec3) -> [i64; 6] {
    let q = |v: DVec3| (v * 1e9).round().as_i64vec3().to_array();
    let (a, b) = (q(p), q(n));
    [a[0], a[1], a[2], b[0], b[1], b[2]]
}

/// Subdivides every triangle of every object into `n^2` triangles, `n` per object from its
/// longest edge and the spacing, so that triangles sharing an edge share its grid points; grid
/// points with the same position and normal within an object are one vertex.
fn subdivide(file: &SceneFile, spacing: f64) -> Baked {
    let mut b = Baked::default();
    for (k, o) in file.objects.iter().enumerate() {
        let longest = o
            .triangles
            .iter()
            .flat_map(|t| {
                let [p, q, r] = t.map(|i| o.positions[i as usize]);
                [(q - p).length(), (r - q).length(), (p - r).length()]
            })
            .fold(0.0, f64::max);
        let n = ((longest / spacing).ceil() as usize).clamp(1, 2000);
        let mut index: HashMap<[i64; 6], u32> = HashMap::new();
        let mut grids = Vec::with_capacity(o.triangles.len());
        for t in &o.triangles {
            let [p, q, r] = t.map(|i| o.positions[i as usize]);
            let normal = (q - p).cross(r - p).normalize();
            let mut grid = vec![0u32; (n + 1) * (n + 1)];
            for i in 0..=n {
                for j in 0..=n - i {
                    let x = p + (q - p) * (i as f64 / n as f64) + (r - p) * (j as f64 / n as f64);
                    grid[i * (n + 1) + j] = *index.entry(key(x, normal)).or_insert_with(|| {
                        b.positions.push(x);
                        b.normals.push(normal);
                        b.radiance.push(if o.is_light() {
                            o.emission
                        } else {
                            DVec3::ZERO
                        });
                        b.owner.push((!o.is_light()).then_some(k));
                        (b.positions.len() - 1) as u32
                    });
                }
            }
            let at = |i: usize, j: usize| grid[i * (n + 1) + j];
            for i in 0..n {
                for j in 0..n - i {
                    b.triangles.push([at(i, j), at(i + 1, j), at(i, j + 1)]);
                    if i + j + 1 < n {
                        b.triangles
                            .push([at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)]);
                    }
                }
            }
            grids.push((n, grid));
        }
        b.grids.push(grids);
    }
    b
}

fn run(args: &Args) -> Result<(), String> {
    let t = Instant::now();
    let file = arealight::io::load(&args.file).map_err(|e| e.to_string())?;
    println!(
        "scene: {}: {} objects, {} lights; loaded in {:.1} ms",
        args.file.display(),
        file.objects.len(),
        file.scene.lights().len(),
        1e3 * t.elapsed().as_secs_f64()
    );
    let mut baked = subdivide(&file, args.spacing);
    let todo: Vec<usize> = (0..baked.positions.len())
        .filter(|&v| baked.owner[v].is_some())
        .collect();
    println!(
        "grid: {} vertices ({} to shade), {} triangles, spacing {}",
        baked.positions.len(),
        todo.len(),
        baked.triangles.len(),
        args.spacing
    );

    // The diffuse lobe only: radiance towards any direction, so a view is not needed (the
    // normal serves).
    let diffuse: Vec<Material> = file
        .objects
        .iter()
        .map(|o| Material::diffuse(o.material.albedo()))
        .collect::<Result<_, _>>()
        .map_err(|e| e.to_string())?;
    let progress = Progress::new("baking", todo.len());
    let mc = MonteCarlo::new(4096, ReferenceBrdf::True);
    let (mut gave_up, mut faults) = (0, 0);
    for run in todo.chunks(4096) {
        let p: Vec<DVec3> = run.iter().map(|&v| baked.positions[v]).collect();
        let n: Vec<DVec3> = run.iter().map(|&v| baked.normals[v]).collect();
        let m: Vec<Material> = run
            .iter()
            .filter_map(|&v| baked.owner[v])
            .map(|k| diffuse[k])
            .collect();
        let shaded = file
            .scene
            .par_shade_batch(&p, &n, &n, &m)
            .map_err(|e| e.to_string())?;
        for (k, (&v, r)) in run.iter().zip(shaded).enumerate() {
            baked.radiance[v] = match r {
                Ok(rgb) => rgb,
                Err(e) if e.is_undecidable() => {
                    gave_up += 1;
                    mc.estimate(&file.scene, p[k], n[k], n[k], &m[k], v as u64)
                        .map_or(DVec3::ZERO, |est| est.mean)
                }
                Err(_) => {
                    faults += 1;
                    DVec3::ZERO
                }
            };
        }
        progress.add(run.len());
    }
    let elapsed = progress.finish().as_secs_f64();
    let threads = rayon::current_num_threads();
    println!(
        "baked {} vertices in {elapsed:.2} s on {threads} threads: {:.1} us per vertex per thread; \
         {gave_up} gave up (Monte Carlo), {faults} input faults",
        todo.len(),
        1e6 * elapsed * threads as f64 / todo.len().max(1) as f64
    );

    let dir = out_dir()?;
    let stem = args
        .file
        .file_stem()
        .map_or("scene".into(), |s| s.to_string_lossy().into_owned());
    let ply = dir.join(format!("{stem}_bake.ply"));
    std::fs::write(&ply, to_ply(&baked, args.exposure))
        .map_err(|e| format!("{}: {e}", ply.display()))?;
    println!("mesh: {}", ply.display());

    let (w, h) = (args.width, args.height);
    let (_, _, up, fov) = cornell_camera();
    let cam = Camera::new(args.eye, args.target, up, fov);
    let img = picture(&file, &baked, &cam, w, h);
    let png = dir.join(format!("{stem}_bake.png"));
    write_png(&png, w, h, &to_bytes(&img, args.exposure))?;
    println!("picture: {}", png.display());
    Ok(())
}

/// ASCII PLY: position, normal, tone-mapped colour, linear radiance per vertex; the triangles.
fn to_ply(b: &Baked, exposure: f64) -> String {
    let mut s = String::with_capacity(64 * b.positions.len() + 16 * b.triangles.len());
    let _ = write!(
        s,
        "ply\nformat ascii 1.0\ncomment arealight bake: direct lighting, diffuse lobe, per vertex\n\
         comment red green blue: radiance tone mapped 1 - exp(-{exposure} x), sRGB\n\
         element vertex {}\nproperty float x\nproperty float y\nproperty float z\n\
         property float nx\nproperty float ny\nproperty float nz\n\
         property uchar red\nproperty uchar green\nproperty uchar blue\n\
         property float radiance_r\nproperty float radiance_g\nproperty float radiance_b\n\
         element face {}\nproperty list uchar int vertex_indices\nend_header\n",
        b.positions.len(),
        b.triangles.len()
    );
    for ((p, n), l) in b.positions.iter().zip(&b.normals).zip(&b.radiance) {
        let c = [l.x, l.y, l.z].map(|x| srgb(x, exposure));
        let _ = writeln!(
            s,
            "{} {} {} {} {} {} {} {} {} {} {} {}",
            p.x as f32,
            p.y as f32,
            p.z as f32,
            n.x as f32,
            n.y as f32,
            n.z as f32,
            c[0],
            c[1],
            c[2],
            l.x as f32,
            l.y as f32,
            l.z as f32
        );
    }
    for t in &b.triangles {
        let _ = writeln!(s, "3 {} {} {}", t[0], t[1], t[2]);
    }
    s
}

/// The baked radiance seen from the camera: the grid triangle under each pixel (found from the
/// scene triangle the ray hits and its barycentric coordinates), its vertices' values
/// interpolated.
fn picture(file: &SceneFile, b: &Baked, cam: &Camera, w: usize, h: usize) -> Vec<DVec3> {
    (0..w * h)
        .map(|i| {
            let (x, y) = ((i % w) as f64 + 0.5, (i / w) as f64 + 0.5);
            let d = cam.ray(x, y, w, h);
            let lists = file
                .objects
                .iter()
                .enumerate()
                .map(|(k, o)| (k, o.positions.as_slice(), o.triangles.as_slice()));
            let Some((k, t, _, u, v)) = nearest(cam.eye, d, lists) else {
                return DVec3::ZERO;
            };
            let (n, grid) = &b.grids[k][t];
            let at = |i: usize, j: usize| b.radiance[grid[i * (n + 1) + j] as usize];
            let (gx, gy) = (u * *n as f64, v * *n as f64);
            let i = (gx.floor() as usize).min(n - 1);
            let j = (gy.floor() as usize).min(n - 1 - i);
            let (fx, fy) = (gx - i as f64, gy - j as f64);
            if fx + fy <= 1.0 || i + j + 1 >= *n {
                at(i, j) * (1.0 - fx - fy).max(0.0) + at(i + 1, j) * fx + at(i, j + 1) * fy
            } else {
                at(i + 1, j + 1) * (fx + fy - 1.0)
                    + at(i + 1, j) * (1.0 - fy)
                    + at(i, j + 1) * (1.0 - fx)
            }
        })
        .collect()
}
