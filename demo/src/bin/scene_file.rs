//! Renders a scene file (OBJ or glTF) with exact soft shadows: the lights are the file's
//! emissive objects, every other object occludes and is shaded. By default the shipped Cornell
//! box (`scenes/cornell_box.gltf`) from the published camera.
//!
//! ```sh
//! cargo run --release -p arealight-demo --features obj,gltf --bin scene_file
//! cargo run --release -p arealight-demo --features obj,gltf --bin scene_file -- scenes/cornell_box.obj --width 640
//! cargo run --release -p arealight-demo --features obj,gltf --bin scene_file -- --help
//! ```
//!
//! Prints the scene, `Scene::validate`'s findings, and the time of each stage: loading (parse,
//! checks, scene precomputation), primary visibility (brute-force ray casting, not part of the
//! crate), and the shading of every visible surface point with `Scene::par_shade_batch` on all
//! cores, per point. A point whose shading gives up (`GeomError::Undecidable`) is estimated by
//! the Monte Carlo reference instead, and counted: what a renderer should do with that error;
//! an input fault (none is expected from a valid camera) is black and counted.
//!
//! Writes `target/arealight-out/<file stem>.png` (linear radiance tone mapped with
//! `1 - exp(-exposure x)`, sRGB). Direct light only: the ceiling, which sees no light, is black.

use std::path::PathBuf;
use std::time::Instant;

use arealight::GeomError;
use arealight::glam::DVec3;
use arealight::io::SceneFile;
use arealight::shade::{Material, MonteCarlo, ReferenceBrdf};
use arealight_demo::image::{out_dir, to_bytes, write_png};
use arealight_demo::progress::Progress;
use arealight_demo::trace::{Camera, nearest};
use arealight_demo::{args_or_exit, cornell_camera, parse_vec, run_or_exit};

const HELP: &str = "\
scene_file: render a scene file (OBJ or glTF) with exact soft shadows

USAGE: cargo run --release -p arealight-demo --features obj,gltf --bin scene_file -- [FILE] [FLAGS]

  FILE             .obj, .gltf or .glb (default scenes/cornell_box.gltf)
  --width W        image width (default 320)
  --height H       image height (default 320)
  --eye x,y,z      camera position (default the Cornell box camera, 0.278,0.273,-0.8)
  --target x,y,z   point looked at (default 0.278,0.273,0)
  --up x,y,z       up direction (default 0,1,0)
  --fov DEG        vertical field of view (default 39.3, the Cornell camera's)
  --exposure E     tone map 1 - exp(-E x) (default 3)
  --threads T      worker threads (default 0: all cores)
  --fallback-spp N Monte Carlo samples per light for points that give up (default 4096)
  --help           this text
";

struct Args {
    file: PathBuf,
    width: usize,
    height: usize,
    camera: (DVec3, DVec3, DVec3, f64),
    exposure: f64,
    threads: usize,
    fallback_spp: u32,
}

fn parse_args() -> Result<Args, String> {
    let mut a = Args {
        file: arealight_demo::repo_path("scenes/cornell_box.gltf"),
        width: 320,
        height: 320,
        camera: cornell_camera(),
        exposure: 3.0,
        threads: 0,
        fallback_spp: 4096,
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
            "--width" => a.width = num(value("--width")?)? as usize,
            "--height" => a.height = num(value("--height")?)? as usize,
            "--eye" => a.camera.0 = parse_vec(&value("--eye")?)?,
            "--target" => a.camera.1 = parse_vec(&value("--target")?)?,
            "--up" => a.camera.2 = parse_vec(&value("--up")?)?,
            "--fov" => a.camera.3 = num(value("--fov")?)?,
            "--exposure" => a.exposure = num(value("--exposure")?)?,
            "--threads" => a.threads = num(value("--threads")?)? as usize,
            "--fallback-spp" => a.fallback_spp = num(value("--fallback-spp")?)? as u32,
            f if !f.starts_with("--") => a.file = PathBuf::from(f),
            other => return Err(format!("unknown flag {other}\n\n{HELP}")),
        }
    }
    if !(1..=8192).contains(&a.width) || !(1..=8192).contains(&a.height) {
        return Err("resolution must be between 1 and 8192".into());
    }
    if !(a.camera.3 > 0.0 && a.camera.3 < 180.0) {
        return Err("the field of view must be in (0, 180) degrees".into());
    }
    Ok(a)
}

fn main() {
    let args = args_or_exit(parse_args());
    run_or_exit("scene_file", args.threads, || run(&args));
}

/// A shading query of one pixel.
struct Query {
    pixel: usize,
    point: DVec3,
    normal: DVec3,
    view: DVec3,
    material: Material,
}

fn run(args: &Args) -> Result<(), String> {
    let (w, h) = (args.width, args.height);
    let t = Instant::now();
    let file = arealight::io::load(&args.file).map_err(|e| e.to_string())?;
    let t_load = t.elapsed().as_secs_f64();
    let tris: usize = file.objects.iter().map(|o| o.triangles.len()).sum();
    println!(
        "scene: {}: {} objects ({tris} triangles), {} lights, {} occluders; loaded in {:.1} ms",
        args.file.display(),
        file.objects.len(),
        file.scene.lights().len(),
        file.scene.occluders().len(),
        1e3 * t_load
    );
    let report = file.scene.validate::<DVec3>(&[]);
    println!("validate: {report}");

    let t = Instant::now();
    let (eye, target, up, fov) = args.camera;
    let cam = Camera::new(eye, target, up, fov);
    let mut img = vec![DVec3::ZERO; w * h];
    let queries = primary(&file, &cam, w, h, &mut img);
    let t_primary = t.elapsed().as_secs_f64();
    println!(
        "primary visibility: {} pixels, {} surface points, in {t_primary:.2} s (brute-force ray casting)",
        w * h,
        queries.len()
    );

    let t = Instant::now();
    let results = shade(&file, &queries, w);
    let t_shade = t.elapsed().as_secs_f64();
    let threads = rayon::current_num_threads();
    println!(
        "shading: {} points in {t_shade:.2} s on {threads} threads: {:.1} us per point per thread",
        queries.len(),
        1e6 * t_shade * threads as f64 / queries.len().max(1) as f64
    );

    let t = Instant::now();
    let mc = MonteCarlo::new(args.fallback_spp, ReferenceBrdf::True);
    let (mut gave_up, mut faults) = (0, 0);
    for (q, r) in queries.iter().zip(results) {
        img[q.pixel] = match r {
            Ok(rgb) => rgb,
            Err(e) if e.is_undecidable() => {
                gave_up += 1;
                mc.estimate(
                    &file.scene,
                    q.point,
                    q.normal,
                    q.view,
                    &q.material,
                    q.pixel as u64,
                )
                .map_or(DVec3::ZERO, |est| est.mean)
            }
            Err(_) => {
                faults += 1;
                DVec3::ZERO
            }
        };
    }
    println!(
        "fallbacks: {gave_up} undecidable points estimated by Monte Carlo ({:.2} s), {faults} input faults",
        t.elapsed().as_secs_f64()
    );

    let stem = args
        .file
        .file_stem()
        .map_or("scene".into(), |s| s.to_string_lossy().into_owned());
    let path = out_dir()?.join(format!("{stem}.png"));
    write_png(&path, w, h, &to_bytes(&img, args.exposure))?;
    println!("image: {}", path.display());
    Ok(())
}

/// Casts a ray per pixel: an emitter's front side (or either side of a two-sided one) is its
/// radiance, written to `img`; any other surface becomes a shading query, its normal turned
/// towards the camera (walls are shaded on the side the camera sees).
fn primary(file: &SceneFile, cam: &Camera, w: usize, h: usize, img: &mut [DVec3]) -> Vec<Query> {
    let mut queries = Vec::new();
    for (i, px) in img.iter_mut().enumerate() {
        let (x, y) = ((i % w) as f64 + 0.5, (i / w) as f64 + 0.5);
        let d = cam.ray(x, y, w, h);
        let lists = file
            .objects
            .iter()
            .enumerate()
            .map(|(k, o)| (k, o.positions.as_slice(), o.triangles.as_slice()));
        let Some((k, t, dist, _, _)) = nearest(cam.eye, d, lists) else {
            continue;
        };
        let o = &file.objects[k];
        let [a, b, c] = o.triangles[t].map(|v| o.positions[v as usize]);
        let n = (b - a).cross(c - a).normalize();
        if o.is_light() {
            if n.dot(d) < 0.0 || o.two_sided {
                *px = o.emission;
            }
            continue;
        }
        // The hit projected onto the triangle's plane, so that it lies on the face up to rounding.
        let p = cam.eye + dist * d;
        let p = p - n * n.dot(p - a);
        let normal = if n.dot(d) < 0.0 { n } else { -n };
        queries.push(Query {
            pixel: i,
            point: p,
            normal,
            view: -d,
            material: o.material,
        });
    }
    queries
}

/// Shades every query with `Scene::par_shade_batch`, in runs of a few rows so that the
/// progress line moves.
fn shade(file: &SceneFile, queries: &[Query], w: usize) -> Vec<Result<DVec3, GeomError>> {
    let progress = Progress::new("shading", queries.len());
    let mut out = Vec::with_capacity(queries.len());
    for run in queries.chunks(8 * w) {
        let p: Vec<DVec3> = run.iter().map(|q| q.point).collect();
        let n: Vec<DVec3> = run.iter().map(|q| q.normal).collect();
        let v: Vec<DVec3> = run.iter().map(|q| q.view).collect();
        let m: Vec<Material> = run.iter().map(|q| q.material).collect();
        match file.scene.par_shade_batch(&p, &n, &v, &m) {
            Ok(r) => out.extend(r),
            Err(e) => out.extend(run.iter().map(|_| Err(e.clone()))),
        }
        progress.add(run.len());
    }
    progress.finish();
    out
}
