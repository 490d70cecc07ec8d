//! Renders the seed paper's test scene (000, Fig. 4: a ground plane lit by a quad, a cylinder and a
//! truncated-cone light, with a cube, an icosphere and an ellipsoid standing on it) with the
//! analytic method, and the same scene with the ratio estimator (\[HHM18\]: analytic unshadowed
//! times a sampled shadow ratio) and with plain Monte Carlo at equal time, and measures all three
//! against a high-sample Monte Carlo reference with the true GGX BRDF (seed 000 figure 6 makes
//! the same comparison).
//!
//! ```sh
//! cargo run --release -p arealight-demo              # defaults: 320 x 240, all cores
//! cargo run --release -p arealight-demo -- --help    # the flags
//! ```
//!
//! Prints a Markdown table with one row per method (analytic, then the ratio estimator and
//! Monte Carlo at 1x and 10x the analytic time) and the columns time (s), samples per light per
//! pixel, MAE and RMSE against the reference. Measured runs, with the command, machine and
//! settings, are in BENCHMARKS.md, section "render: analytic, ratio estimator, Monte Carlo".
//!
//! Equal time: each stochastic method's cost per pixel is modelled as a setup (frame, light
//! regions and their triangulations, for the ratio estimator the analytic unshadowed integrals)
//! plus a cost per sample, both measured on every 16th pixel at 1 and 4 samples per light; the
//! image is then rendered with the number of samples that fits the budget (rendered once more,
//! rescaled, when its time misses the budget by more than 20%), and its own time is reported (at
//! least one sample, so a method may take longer than the budget).
//! Both stochastic methods sample each light's triangulated silhouette and use the true BRDF;
//! neither is denoised.
//!
//! Flags:
//!
//! - `--width W`, `--height H`: resolution (default 320 x 240).
//! - `--ref-spp N`: samples per light per pixel of the reference (default 1024). The reference is
//!   cached in `<out>/render_reference_<version>_<W>x<H>_<L>l<O>o_<N>.bin` and reused when present.
//! - `--no-cache`: recompute the reference even when cached.
//! - `--lights L`, `--occluders O`: how many of the scene's lights (quad, cylinder, cone) and
//!   occluders (cube, icosphere, ellipsoid) to include, 0 to 3 each (default 3 and 3).
//! - `--threads T`: worker threads (default 0: all cores; rayon's pool).
//! - `--out DIR`: where the images go (default: `target/arealight-out/` in the repository, where
//!   every example writes).
//! - `--plucker`: also shade the analytic image through the lazy Pluecker-space backend (seed
//!   002; trees reused per thread), and print its time and largest per-pixel difference from
//!   the clipping backend's image.
//! - `--time-factors F1,F2,...`: the budgets of the two stochastic methods as multiples of the
//!   analytic time (default `1,10`: equal time, and ten times as long); their images are written
//!   for the first.
//!
//! Work that takes longer than a second shows a progress line on stderr. The analytic pass
//! shades all surface points with `Scene::par_shade_batch`.
//!
//! Writes `render.png` (analytic), `render_ratio.png` (ratio estimator, equal time),
//! `render_mc.png` (Monte Carlo, equal time), `render_reference.png` and
//! `render_side_by_side.png` (the four, left to right). Linear radiance is tone mapped with
//! `1 - exp(-4 x)` and encoded as sRGB; the errors are measured on linear radiance over all
//! pixels and channels.
//!
//! \[HHM18\] E. Heitz, S. Hill, M. McGuire. *Combining analytic direct illumination and
//! stochastic shadows.* I3D 2018.

use arealight::glam::DVec3;
use arealight::internals::{Demo, DemoConfig, demo_scene};
use arealight::shade::{Material, MonteCarlo, RatioEstimator, ReferenceBrdf, Scene};
use arealight::visibility::{PluckerContext, PluckerVisibility};
use arealight_demo::image::{to_bytes, write_png};
use arealight_demo::progress::Progress;
use arealight_demo::trace::{Camera, Hit, ray_triangle};
use arealight_demo::{args_or_exit, run_or_exit};
use rayon::prelude::*;
use std::cell::RefCell;
use std::path::PathBuf;
use std::time::Instant;

const HELP: &str = "\
render: the seed paper's test scene, analytic vs ratio estimator vs Monte Carlo at equal time

USAGE: cargo run --release -p arealight-demo -- [FLAGS]

  --width W        image width (default 320)
  --height H       image height (default 240)
  --ref-spp N      reference samples per light per pixel (default 1024), cached on disk
  --no-cache       recompute the reference even if a cached one exists
  --lights L       number of lights 0..=3: quad, cylinder, truncated cone (default 3)
  --occluders O    number of occluders 0..=3: cube, icosphere, ellipsoid (default 3)
  --threads T      worker threads (default 0: all cores)
  --out DIR        output directory (default target/arealight-out in the repository)
  --plucker        also shade with the Pluecker backend; print the largest difference
  --time-factors F budgets of ratio estimator and Monte Carlo as multiples of the analytic
                   time, comma-separated (default 1,10); images are written for the first
  --help           this text
";

struct Args {
    width: usize,
    height: usize,
    ref_spp: u32,
    cache: bool,
    cfg: DemoConfig,
    threads: usize,
    out: PathBuf,
    /// Budgets of the stochastic methods, in multiples of the analytic time.
    time_factors: Vec<f64>,
    plucker: bool,
}

fn parse_args() -> Result<Args, String> {
    let mut a = Args {
        width: 320,
        height: 240,
        ref_spp: 1024,
        cache: true,
        cfg: DemoConfig::default(),
        threads: 0,
        out: arealight_demo::image::default_out(),
        time_factors: vec![1.0, 10.0],
        plucker: false,
    };
    let mut it = std::env::args().skip(1);
    while let Some(flag) = it.next() {
        let mut value = |name: &str| it.next().ok_or(format!("{name} needs a value"));
        let num = |s: String, name: &str| s.parse::<usize>().map_err(|e| format!("{name}: {e}"));
        match flag.as_str() {
            "--help" | "-h" => {
                print!("{HELP}");
                std::process::exit(0);
            }
            "--width" => a.width = num(value("--width")?, "--width")?,
            "--height" => a.height = num(value("--height")?, "--height")?,
            "--ref-spp" => a.ref_spp = num(value("--ref-spp")?, "--ref-spp")? as u32,
            "--no-cache" => a.cache = false,
            "--lights" => a.cfg.lights = num(value("--lights")?, "--lights")?.min(3),
            "--occluders" => a.cfg.occluders = num(value("--occluders")?, "--occluders")?.min(3),
            "--threads" => a.threads = num(value("--threads")?, "--threads")?,
            "--out" => a.out = PathBuf::from(value("--out")?),
            "--plucker" => a.plucker = true,
            "--time-factors" => {
                a.time_factors = value("--time-factors")?
                    .split(',')
                    .map(|t| match t.trim().parse::<f64>() {
                        Ok(x) if x > 0.0 && x.is_finite() => Ok(x),
                        _ => Err(format!("--time-factors: bad factor {t:?}")),
                    })
                    .collect::<Result<_, _>>()?;
                if a.time_factors.is_empty() {
                    return Err("--time-factors needs at least one factor".into());
                }
            }
            other => return Err(format!("unknown flag {other}\n\n{HELP}")),
        }
    }
    if a.width == 0 || a.height == 0 || a.width > 8192 || a.height > 8192 {
        return Err("resolution must be between 1 and 8192".into());
    }
    Ok(a)
}

/// Nearest hit of the camera ray among lights, occluders and the ground.
fn trace(demo: &Demo, o: DVec3, d: DVec3) -> Hit {
    let mut best = f64::INFINITY;
    let mut hit = Hit::Nothing;
    let ground_half = 8.0;
    if d.z < 0.0 {
        let t = -o.z / d.z;
        let p = o + t * d;
        if p.x.abs() <= ground_half && p.y.abs() <= ground_half {
            best = t;
            hit = Hit::Surface(DVec3::new(p.x, p.y, 0.0), DVec3::Z, -d, demo.ground);
        }
    }
    let scene = &demo.scene;
    for light in scene.lights() {
        let mesh = light.shape().mesh();
        for i in 0..mesh.triangle_count() {
            if let Some(t) = ray_triangle(o, d, mesh.triangle(i)).map(|h| h.0)
                && t < best
            {
                best = t;
                let front = mesh.triangle_normal(i).dot(d) < 0.0;
                hit = Hit::Emitter(if front { light.radiance() } else { DVec3::ZERO });
            }
        }
    }
    for (k, occ) in scene.occluders().iter().enumerate() {
        let mesh = occ.mesh();
        for i in 0..mesh.triangle_count() {
            if let Some(t) = ray_triangle(o, d, mesh.triangle(i)).map(|h| h.0)
                && t < best
            {
                best = t;
                let n = mesh.triangle_normal(i);
                // The hit point projected onto the triangle's plane, so that it lies on the face
                // exactly up to rounding.
                let p = o + t * d;
                let p = p - n * n.dot(p - mesh.triangle(i)[0]);
                hit = Hit::Surface(p, n, -d, demo.occluder_materials[k]);
            }
        }
    }
    hit
}

/// Renders with `f(pixel index, hit) -> radiance` on the current rayon pool (set up from
/// `--threads` by `main`), a row per task, with a progress line for passes over a second.
fn render(
    w: usize,
    h: usize,
    _threads: usize,
    hits: &[Hit],
    f: impl Fn(usize, &Hit) -> DVec3 + Sync,
) -> Vec<DVec3> {
    render_labeled("rendering", w, h, hits, f)
}

/// [`render`] with the progress line's label.
fn render_labeled(
    label: &str,
    w: usize,
    h: usize,
    hits: &[Hit],
    f: impl Fn(usize, &Hit) -> DVec3 + Sync,
) -> Vec<DVec3> {
    let mut img = vec![DVec3::ZERO; w * h];
    let progress = Progress::new(label, h);
    img.par_chunks_mut(w).enumerate().for_each(|(y, row)| {
        for (x, px) in row.iter_mut().enumerate() {
            let i = y * w + x;
            *px = f(i, &hits[i]);
        }
        progress.add(1);
    });
    progress.finish();
    img
}

/// The analytic image: every surface point shaded by `Scene::par_shade_batch`, in runs of
/// rows so that the progress line moves; a point that fails is black and counted.
fn shade_analytic(scene: &Scene, w: usize, hits: &[Hit]) -> (Vec<DVec3>, usize) {
    let mut img: Vec<DVec3> = hits
        .iter()
        .map(|hit| match hit {
            Hit::Emitter(l) => *l,
            _ => DVec3::ZERO,
        })
        .collect();
    let surface: Vec<(usize, &DVec3, &DVec3, &DVec3, Material)> = hits
        .iter()
        .enumerate()
        .filter_map(|(i, hit)| match hit {
            Hit::Surface(p, n, v, m) => Some((i, p, n, v, *m)),
            _ => None,
        })
        .collect();
    let progress = Progress::new("analytic", surface.len());
    let mut failures = 0;
    for run in surface.chunks(8 * w.max(1)) {
        let points: Vec<&DVec3> = run.iter().map(|q| q.1).collect();
        let normals: Vec<&DVec3> = run.iter().map(|q| q.2).collect();
        let views: Vec<&DVec3> = run.iter().map(|q| q.3).collect();
        let materials: Vec<Material> = run.iter().map(|q| q.4).collect();
        let shaded = scene
            .par_shade_batch(&points, &normals, &views, &materials)
            .unwrap_or_default();
        for (q, r) in run.iter().zip(shaded) {
            match r {
                Ok(rgb) => img[q.0] = rgb,
                Err(_) => failures += 1,
            }
        }
        progress.add(run.len());
    }
    progress.finish();
    (img, failures)
}

/// Part of the reference cache's file name: bump it whenever the scene, the camera or what the
/// reference treats as opaque changes (v5: lights block each other).
const SCENE_VERSION: &str = "v5";

/// Scale of linear radiance before tone mapping.
const EXPOSURE: f64 = 4.0;

fn errors(img: &[DVec3], reference: &[DVec3]) -> (f64, f64) {
    let n = (img.len() * 3) as f64;
    let (mut abs, mut sq) = (0.0, 0.0);
    for (a, b) in img.iter().zip(reference) {
        let d = *a - *b;
        abs += d.abs().element_sum();
        sq += d.length_squared();
    }
    (abs / n, (sq / n).sqrt())
}

fn main() {
    let args = args_or_exit(parse_args());
    run_or_exit("render", args.threads, || run(&args));
}

fn run(args: &Args) -> Result<(), String> {
    let (w, h) = (args.width, args.height);
    let demo = demo_scene(args.cfg).map_err(|e| e.to_string())?;
    let cam = Camera::new(
        DVec3::new(0.3, -4.6, 4.8),
        DVec3::new(0.0, 0.3, 0.6),
        DVec3::Z,
        52.0,
    );
    std::fs::create_dir_all(&args.out).map_err(|e| e.to_string())?;

    // Primary visibility is shared by every method and not timed.
    let hits: Vec<Hit> = (0..w * h)
        .map(|i| {
            let (x, y) = ((i % w) as f64 + 0.5, (i / w) as f64 + 0.5);
            trace(&demo, cam.eye, cam.ray(x, y, w, h))
        })
        .collect();

    let (analytic, t_analytic, failures) = render_analytic(args, &demo, &hits);
    if args.plucker {
        thread_local!(static CTX: RefCell<Option<PluckerContext>> = const { RefCell::new(None) });
        let pl = PluckerVisibility::from_clip(demo.scene.visibility().clone());
        let t = Instant::now();
        let img = render(w, h, args.threads, &hits, |_, hit| match hit {
            Hit::Surface(p, n, v, m) => CTX.with_borrow_mut(|c| {
                let ctx = c.get_or_insert_with(|| PluckerContext::new(0.1).unwrap());
                let vis = pl.with_context(ctx);
                demo.scene
                    .shade_with(&vis, *p, *n, *v, m)
                    .unwrap_or(DVec3::NAN)
            }),
            Hit::Nothing => DVec3::ZERO,
            Hit::Emitter(l) => *l,
        });
        let d = img
            .iter()
            .zip(&analytic)
            .map(|(a, b)| (*a - *b).abs().max_element());
        let (max, failed) = d.fold((0.0f64, 0), |(m, f), x| {
            (m.max(x), f + usize::from(x.is_nan()))
        });
        let secs = t.elapsed().as_secs_f64();
        println!("plucker: time {secs:.2} s, max difference per pixel {max:.1e}, {failed} failed");
    }
    let (reference, ref_note) = reference_image(args, &demo, &hits)?;
    let ratio_shader = |spp: u32, i: usize, p, n, v, m: &Material| {
        let seed = 0xBEEF_0000_0000 ^ i as u64;
        RatioEstimator::new(spp, ReferenceBrdf::True)
            .estimate(&demo.scene, p, n, v, m, seed)
            .map(|e| e.mean)
            .unwrap_or_else(|_| {
                // No analytic factor where the unoccluded region gives up: plain Monte Carlo.
                MonteCarlo::new(spp, ReferenceBrdf::True)
                    .estimate(&demo.scene, p, n, v, m, seed)
                    .map(|e| e.mean)
                    .unwrap_or(DVec3::ZERO)
            })
    };
    let mc_shader = |spp: u32, i: usize, p, n, v, m: &Material| {
        MonteCarlo::new(spp, ReferenceBrdf::True)
            .estimate(&demo.scene, p, n, v, m, 0xCAFE_0000_0000 ^ i as u64)
            .map(|e| e.mean)
            .unwrap_or(DVec3::ZERO)
    };
    let mut rows = vec![Row::new(
        "analytic".into(),
        t_analytic,
        None,
        &analytic,
        &reference,
    )];
    // The images at the first time factor are kept.
    let mut kept: Vec<Timed> = Vec::new();
    for (k, &factor) in args.time_factors.iter().enumerate() {
        let budget = factor * t_analytic;
        for (name, timed) in [
            (
                "ratio estimator",
                equal_time(args, &hits, budget, ratio_shader),
            ),
            ("monte carlo", equal_time(args, &hits, budget, mc_shader)),
        ] {
            let name = format!("{name} ({factor}x time)");
            rows.push(Row::new(
                name,
                timed.time,
                Some(timed.spp),
                &timed.img,
                &reference,
            ));
            if k == 0 {
                kept.push(timed);
            }
        }
    }
    print_table(&rows);
    println!("{ref_note}");
    let nan = kept
        .iter()
        .map(|t| &t.img)
        .chain([&analytic])
        .flat_map(|img| img.iter())
        .filter(|p| !p.is_finite())
        .count();
    if failures > 0 || nan > 0 {
        println!("warning: {failures} pixels failed to shade, {nan} non-finite pixels");
    }
    let mut images = vec![("render.png", &analytic)];
    if let [ratio, mc] = &kept[..] {
        images.push(("render_ratio.png", &ratio.img));
        images.push(("render_mc.png", &mc.img));
    }
    images.push(("render_reference.png", &reference));
    write_images(args, &images)
}

/// The analytic image, its time, and the number of pixels that gave up (shaded black).
fn render_analytic(args: &Args, demo: &Demo, hits: &[Hit]) -> (Vec<DVec3>, f64, usize) {
    let t0 = Instant::now();
    let (img, failures) = shade_analytic(&demo.scene, args.width, hits);
    (img, t0.elapsed().as_secs_f64(), failures)
}

/// The reference image (Monte Carlo with the true BRDF, `--ref-spp` samples per light per
/// pixel), from the cache when present, and a line saying where it came from.
fn reference_image(args: &Args, demo: &Demo, hits: &[Hit]) -> Result<(Vec<DVec3>, String), String> {
    let (w, h) = (args.width, args.height);
    let cache = args.out.join(format!(
        "render_reference_{SCENE_VERSION}_{w}x{h}_{}l{}o_{}.bin",
        args.cfg.lights, args.cfg.occluders, args.ref_spp
    ));
    let cached: Option<Vec<DVec3>> = args
        .cache
        .then(|| std::fs::read(&cache).ok())
        .flatten()
        .filter(|b| b.len() == w * h * 24)
        .map(|b| {
            b.chunks_exact(24)
                .map(|c| {
                    let f = |k: usize| f64::from_le_bytes(c[8 * k..8 * k + 8].try_into().unwrap());
                    DVec3::new(f(0), f(1), f(2))
                })
                .collect()
        });
    if let Some(r) = cached {
        return Ok((r, format!("reference: cached {}", cache.display())));
    }
    let t = Instant::now();
    let mc = MonteCarlo::new(args.ref_spp, ReferenceBrdf::True);
    let r = render_labeled("reference", w, h, hits, |i, hit| match hit {
        Hit::Nothing => DVec3::ZERO,
        Hit::Emitter(l) => *l,
        Hit::Surface(p, n, v, m) => mc
            .estimate(&demo.scene, *p, *n, *v, m, 0xF00D_0000 + i as u64)
            .map(|e| e.mean)
            .unwrap_or(DVec3::ZERO),
    });
    let bytes: Vec<u8> = r
        .iter()
        .flat_map(|p| [p.x, p.y, p.z])
        .flat_map(f64::to_le_bytes)
        .collect();
    std::fs::write(&cache, bytes).map_err(|e| e.to_string())?;
    let note = format!(
        "reference: computed in {:.1} s ({} samples per light per pixel), cached in {}",
        t.elapsed().as_secs_f64(),
        args.ref_spp,
        cache.display()
    );
    Ok((r, note))
}

/// An image rendered by a stochastic method at about a given time.
struct Timed {
    img: Vec<DVec3>,
    time: f64,
    /// Samples per light per pixel.
    spp: u32,
}

/// A shading function `f(spp, pixel, point, normal, view, material)` of a stochastic method.
type Shader<'a> = dyn Fn(u32, usize, DVec3, DVec3, DVec3, &Material) -> DVec3 + Sync + 'a;

/// Renders with `f` at the number of samples per light per pixel whose time comes closest to
/// `budget` seconds: the cost per pixel is modelled as `a + b spp` (a per-point setup: frames,
/// light regions, their triangulations; `b` per sample), measured on every 16th pixel at 1 and
/// 4 samples, then the full image is rendered and timed (twice when the first misses the budget
/// by more than 20%: the second with the samples rescaled by the first's measured cost).
fn equal_time(
    args: &Args,
    hits: &[Hit],
    budget: f64,
    f: impl Fn(u32, usize, DVec3, DVec3, DVec3, &Material) -> DVec3 + Sync,
) -> Timed {
    let f: &Shader = &f;
    let shade = |spp: u32, i: usize, hit: &Hit| match hit {
        Hit::Nothing => DVec3::ZERO,
        Hit::Emitter(l) => *l,
        Hit::Surface(p, n, v, m) => f(spp, i, *p, *n, *v, m),
    };
    let stride = 16;
    let subset: Vec<&Hit> = hits.iter().step_by(stride).collect();
    let time_subset = |spp: u32| {
        let t0 = Instant::now();
        // The workers of the pool `main` set up (all cores by default).
        let chunk = subset.len().div_ceil(rayon::current_num_threads());
        std::thread::scope(|s| {
            for (k, part) in subset.chunks(chunk.max(1)).enumerate() {
                s.spawn(move || {
                    for (j, hit) in part.iter().enumerate() {
                        std::hint::black_box(shade(spp, (k * chunk + j) * stride, hit));
                    }
                });
            }
        });
        t0.elapsed().as_secs_f64() * stride as f64
    };
    let (t1, t4) = (time_subset(1), time_subset(4));
    // On a loaded machine `t4 - t1` can come out near zero or negative, which would ask for a
    // million samples per pixel: the time per sample is taken as at least a sixteenth of the
    // 4-sample pass (the full pass then overshoots the budget by 4x at worst, and the
    // correction below re-runs it).
    let per_sample = ((t4 - t1) / 3.0).max(t4 / 16.0).max(1e-12);
    let setup = (t1 - per_sample).max(0.0);
    let mut spp = ((budget - setup) / per_sample).round().clamp(1.0, 1e6) as u32;
    let full = |spp: u32| {
        let t0 = Instant::now();
        let img = render(args.width, args.height, args.threads, hits, |i, hit| {
            shade(spp, i, hit)
        });
        Timed {
            img,
            time: t0.elapsed().as_secs_f64(),
            spp,
        }
    };
    let mut timed = full(spp);
    // The subset's timing misses load changes on a shared machine: one correction, by the
    // measured time per sample of the full image.
    if (timed.time / budget - 1.0).abs() > 0.2 {
        let setup = setup * (timed.time / (setup + per_sample * f64::from(spp)));
        let per = ((timed.time - setup) / f64::from(spp)).max(1e-12);
        let better = ((budget - setup) / per).round().clamp(1.0, 1e6) as u32;
        if better != spp {
            spp = better;
            timed = full(spp);
        }
    }
    timed
}

/// One line of the comparison table.
struct Row {
    name: String,
    time: f64,
    spp: Option<u32>,
    mae: f64,
    rmse: f64,
}

impl Row {
    fn new(name: String, time: f64, spp: Option<u32>, img: &[DVec3], reference: &[DVec3]) -> Row {
        let (mae, rmse) = errors(img, reference);
        Row {
            name,
            time,
            spp,
            mae,
            rmse,
        }
    }
}

fn print_table(rows: &[Row]) {
    println!("| method | time (s) | samples per light per pixel | MAE | RMSE |");
    println!("|---|---|---|---|---|");
    for r in rows {
        let spp = r.spp.map_or("-".to_string(), |s| s.to_string());
        println!(
            "| {} | {:.2} | {spp} | {:.4} | {:.4} |",
            r.name, r.time, r.mae, r.rmse
        );
    }
}

/// Writes each image as a PNG, and all of them left to right in `render_side_by_side.png`.
fn write_images(args: &Args, images: &[(&str, &Vec<DVec3>)]) -> Result<(), String> {
    let (w, h) = (args.width, args.height);
    let bytes: Vec<Vec<u8>> = images
        .iter()
        .map(|(_, img)| to_bytes(img, EXPOSURE))
        .collect();
    for ((name, _), b) in images.iter().zip(&bytes) {
        write_png(&args.out.join(name), w, h, b)?;
    }
    let mut side = Vec::with_capacity(images.len() * bytes[0].len());
    for y in 0..h {
        for b in &bytes {
            side.extend_from_slice(&b[3 * w * y..3 * w * (y + 1)]);
        }
    }
    write_png(
        &args.out.join("render_side_by_side.png"),
        images.len() * w,
        h,
        &side,
    )?;
    let names: Vec<&str> = images.iter().map(|(n, _)| *n).collect();
    println!(
        "images in {}: {} (left to right in render_side_by_side.png)",
        args.out.display(),
        names.join(", ")
    );
    Ok(())
}
