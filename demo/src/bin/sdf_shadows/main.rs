//! Area-light soft shadows in a signed-distance scene, three ways: the Quilez soft shadow (and
//! its improved variant), seed 001's methods (the fast soft shadow with its two occlusion
//! formulas, and the proxy-occluder integration), and the crate's exact analytic shading of the
//! same scene, with a Monte Carlo cross-check of the exact image.
//!
//! ```sh
//! cargo run --release -p arealight-demo --bin sdf_shadows              # defaults: 240 x 180, both lights
//! cargo run --release -p arealight-demo --bin sdf_shadows -- --help    # the flags
//! ```
//!
//! The scene: a floor, a ball, a box with a pillar pushed into its corner (a concave corner)
//! and a small floating ball whose shadow overlaps the others (several occluders). The camera
//! rays are sphere-traced through the signed-distance field; every hit point is shaded with a
//! white diffuse material (albedo 0.8) under one light, by each method:
//!
//! - `exact`: `arealight::shade::Scene::shade` with the boxes as exact convex polyhedra and the
//!   balls (and the spherical light) as icospheres refined until their silhouette error is below
//!   the comparison's resolution (half a pixel's footprint for the shadows cast, half an 8-bit
//!   level for the light); a point on an object is shaded without that object (a convex body
//!   cannot shadow its own surface beyond the horizon, which the shading clips).
//! - `quilez`, `quilez+`, `001 chord`, `001 smooth`: a visibility `V` times the exact
//!   unshadowed shading of the same light (seed 001 eq. 2), the light taken as its bounding
//!   sphere.
//! - `001 proxy`: seed 001 section 4.2, the proxy occluder integrated over 128 directions of
//!   the light's bounding cone; `001 proxy exact` (quad light): the same proxy integrated
//!   exactly (the quad clipped to the proxy's hemisphere, LTC/Baum integral).
//!
//! Output (the folder is created): `<out>/sdf_shadows_<light>.png`, one per light: the top row
//! shows the exact image and each method; the bottom row a map of pixel classes (floor without
//! shadow: dark grey; floor, one occluder: blue; floor, several occluders: magenta; object
//! surfaces: green) and each method's absolute error against the exact image (black 0, red,
//! yellow, white at 10% of the exact image's maximum). Default `<out>` is
//! `target/arealight-out`. The table printed (and copied into BENCHMARKS.md) gives per method
//! the time per shaded point, MAE, RMSE and SSIM against the exact image (all on linear
//! radiance divided by the exact image's maximum), and the MAE per pixel class.

mod metrics;

use arealight::glam::{DQuat, DVec3};
use arealight::sdf::{
    ConeSearch, Cuboid, Plane, Profile, QuadLight, QuilezSettings, Sdf, Sphere, SphereLight,
    TraceLimits, Transformed, UnionAll, fast_soft_shadow, normal, proxy_integral,
    proxy_quad_integral, quilez_improved_shadow, quilez_shadow, sphere_trace,
};
use arealight::shade::{
    Body, ConvexPolyhedron, Light, Material, MonteCarlo, ReferenceBrdf, Scene, TriangleMesh,
};
use metrics::{Gray, mae, rmse, ssim};
use std::path::PathBuf;
use std::sync::Arc;
use std::time::Instant;

const HELP: &str = "\
sdf_shadows: approximate SDF soft shadows (Quilez, seed 001) against the exact analytic shading

USAGE: cargo run --release -p arealight-demo --bin sdf_shadows -- [FLAGS]

  --width W        image width (default 240)
  --height H       image height (default 180)
  --light L        sphere, quad or both (default both)
  --epsilon E      accuracy of the minimal tangent cone search (default 0.05)
  --mc-stride S    Monte Carlo cross-check on every S-th pixel (default 23; 0 = none)
  --threads T      worker threads (default 2)
  --out DIR        output directory (default target/arealight-out in the repository)
  --help           this text
";

struct Args {
    width: usize,
    height: usize,
    lights: Vec<LightKind>,
    epsilon: f64,
    mc_stride: usize,
    threads: usize,
    out: PathBuf,
}

#[derive(Clone, Copy, PartialEq)]
enum LightKind {
    Sphere,
    Quad,
}

fn parse_args() -> Result<Args, String> {
    let mut a = Args {
        width: 240,
        height: 180,
        lights: vec![LightKind::Sphere, LightKind::Quad],
        epsilon: 0.05,
        mc_stride: 23,
        threads: 2,
        out: arealight_demo::image::default_out(),
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
            "--light" => {
                a.lights = match value("--light")?.as_str() {
                    "sphere" => vec![LightKind::Sphere],
                    "quad" => vec![LightKind::Quad],
                    "both" => vec![LightKind::Sphere, LightKind::Quad],
                    other => return Err(format!("--light: unknown light {other}")),
                }
            }
            "--epsilon" => {
                a.epsilon = value("--epsilon")?
                    .parse()
                    .map_err(|e| format!("--epsilon: {e}"))?
            }
            "--mc-stride" => a.mc_stride = num(value("--mc-stride")?, "--mc-stride")?,
            "--threads" => a.threads = num(value("--threads")?, "--threads")?.max(1),
            "--out" => a.out = PathBuf::from(value("--out")?),
            other => return Err(format!("unknown flag {other}\n\n{HELP}")),
        }
    }
    if !(11..=4096).contains(&a.width) || !(11..=4096).contains(&a.height) {
        return Err("width and height must be between 11 and 4096".into());
    }
    Ok(a)
}

/// One convex object, as a signed-distance field and as an exact polyhedron.
struct Object {
    name: &'static str,
    sdf: Arc<dyn Sdf + Send + Sync>,
    mesh: ConvexPolyhedron,
}

/// The largest distance between a sphere of radius `r` and the inscribed icosphere with
/// `subdivisions`: the radius minus the nearest face plane's distance from the center.
fn icosphere_gap(r: f64, subdivisions: u32) -> f64 {
    let ico = ConvexPolyhedron::icosphere(DVec3::ZERO, r, subdivisions).unwrap();
    let mesh = ico.mesh();
    let nearest = (0..mesh.triangle_count())
        .map(|i| {
            let [a, _, _] = mesh.triangle(i);
            mesh.triangle_normal(i).dot(a).abs()
        })
        .fold(f64::INFINITY, f64::min);
    r - nearest
}

/// The fewest subdivisions whose gap is below `tolerance` (at most 5, the constructor's limit).
fn subdivisions_for(r: f64, tolerance: f64) -> (u32, f64) {
    for s in 1..=5 {
        let gap = icosphere_gap(r, s);
        if gap <= tolerance || s == 5 {
            return (s, gap);
        }
    }
    unreachable!()
}

struct World {
    objects: Vec<Object>,
    floor: Plane,
    field: UnionAll,
}

fn world(shadow_tolerance: f64) -> World {
    let mut objects = Vec::new();
    let ball = |name, c: DVec3, r: f64| {
        let (s, gap) = subdivisions_for(r, shadow_tolerance);
        println!("  {name}: icosphere with {s} subdivisions, silhouette gap {gap:.2e}");
        Object {
            name,
            sdf: Arc::new(Sphere::new(c, r).unwrap()),
            mesh: ConvexPolyhedron::icosphere(c, r, s).unwrap(),
        }
    };
    objects.push(ball("ball", DVec3::new(-0.9, 0.35, 0.55), 0.55));
    objects.push(ball("floating ball", DVec3::new(0.0, -0.55, 0.95), 0.22));
    let cuboid = |name, c: DVec3, h: DVec3, angle: f64| {
        let rot = DQuat::from_rotation_z(angle);
        let corners: Vec<DVec3> = (0..8)
            .map(|i| {
                let s = DVec3::new(
                    if i & 1 == 0 { -1.0 } else { 1.0 },
                    if i & 2 == 0 { -1.0 } else { 1.0 },
                    if i & 4 == 0 { -1.0 } else { 1.0 },
                );
                c + rot * (s * h)
            })
            .collect();
        Object {
            name,
            sdf: Arc::new(
                Transformed::new(Cuboid::new(DVec3::ZERO, h).unwrap(), rot, c, 1.0).unwrap(),
            ),
            mesh: ConvexPolyhedron::hull(&corners).unwrap(),
        }
    };
    objects.push(cuboid(
        "box",
        DVec3::new(0.55, 0.0, 0.35),
        DVec3::new(0.45, 0.3, 0.35),
        0.0,
    ));
    objects.push(cuboid(
        "pillar",
        DVec3::new(1.0, 0.3, 0.6),
        DVec3::new(0.12, 0.12, 0.6),
        0.4,
    ));
    let floor = Plane::new(DVec3::ZERO, DVec3::Z).unwrap();
    let mut members: Vec<Box<dyn Sdf + Send + Sync>> = vec![Box::new(floor)];
    for o in &objects {
        members.push(Box::new(Shared(Arc::clone(&o.sdf))));
    }
    World {
        objects,
        floor,
        field: UnionAll::new(members),
    }
}

/// A shared field: the objects keep their own fields (to find which one a point lies on) and
/// the scene's union refers to the same ones.
struct Shared(Arc<dyn Sdf + Send + Sync>);

impl Sdf for Shared {
    fn distance(&self, p: DVec3) -> f64 {
        self.0.distance(p)
    }
    fn exactness(&self) -> arealight::sdf::Exactness {
        self.0.exactness()
    }
}

struct Camera {
    eye: DVec3,
    fwd: DVec3,
    right: DVec3,
    up: DVec3,
    tan_half: f64,
}

impl Camera {
    fn new(eye: DVec3, target: DVec3, fov_deg: f64) -> Self {
        let fwd = (target - eye).normalize();
        let right = fwd.cross(DVec3::Z).normalize();
        Camera {
            eye,
            fwd,
            right,
            up: right.cross(fwd),
            tan_half: (fov_deg.to_radians() / 2.0).tan(),
        }
    }

    /// The ray through the center of pixel `(x, y)`.
    fn ray(&self, x: usize, y: usize, w: usize, h: usize) -> DVec3 {
        let aspect = w as f64 / h as f64;
        let sx = (2.0 * (x as f64 + 0.5) / w as f64 - 1.0) * self.tan_half * aspect;
        let sy = (1.0 - 2.0 * (y as f64 + 0.5) / h as f64) * self.tan_half;
        (self.fwd + sx * self.right + sy * self.up).normalize()
    }

    /// The size of one pixel's footprint at distance `d`.
    fn footprint(&self, d: f64, h: usize) -> f64 {
        2.0 * d * self.tan_half / h as f64
    }
}

/// A shaded point: position, unit normal, direction to the viewer, and the object it lies on
/// (`None` for the floor).
#[derive(Clone, Copy)]
struct Hit {
    p: DVec3,
    n: DVec3,
    view: DVec3,
    on: Option<usize>,
}

fn primary(world: &World, cam: &Camera, w: usize, h: usize, threads: usize) -> Vec<Option<Hit>> {
    let limits = TraceLimits {
        t_min: 0.0,
        t_max: 80.0,
        max_steps: 1024,
        hit_distance: 1e-6,
    };
    par_map(w * h, threads, |i| {
        let d = cam.ray(i % w, i / w, w, h);
        let t = sphere_trace(&world.field, cam.eye, d, &limits)
            .ok()?
            .hit()?;
        let p = cam.eye + t * d;
        // The surface the point is on: the nearest of the floor and the objects.
        let mut on = None;
        let mut best = world.floor.distance(p).abs();
        for (k, o) in world.objects.iter().enumerate() {
            let f = o.sdf.distance(p).abs();
            if f < best {
                best = f;
                on = Some(k);
            }
        }
        let (p, n) = match on {
            None => (DVec3::new(p.x, p.y, 0.0), DVec3::Z),
            Some(k) => {
                let f = &*world.objects[k].sdf;
                let n = normal(f, p, 1e-7)?;
                // One projection step onto the surface (exact fields: lands within rounding).
                (p - f.distance(p) * n, n)
            }
        };
        Some(Hit { p, n, view: -d, on })
    })
    .0
}

/// `f` over `0..n` on `threads` threads (interleaved, so that costly regions are shared), and
/// the wall time it took.
fn par_map<T: Send, F: Fn(usize) -> T + Sync>(n: usize, threads: usize, f: F) -> (Vec<T>, f64) {
    let start = Instant::now();
    let mut parts: Vec<Vec<(usize, T)>> = Vec::new();
    std::thread::scope(|s| {
        let handles: Vec<_> = (0..threads)
            .map(|tid| {
                let f = &f;
                s.spawn(move || {
                    (tid..n)
                        .step_by(threads)
                        .map(|i| (i, f(i)))
                        .collect::<Vec<_>>()
                })
            })
            .collect();
        for h in handles {
            parts.push(h.join().expect("worker panicked"));
        }
    });
    let mut out: Vec<Option<T>> = (0..n).map(|_| None).collect();
    for (i, v) in parts.into_iter().flatten() {
        out[i] = Some(v);
    }
    (
        out.into_iter().map(|v| v.expect("every index")).collect(),
        start.elapsed().as_secs_f64(),
    )
}

/// The approximate methods compared with the exact image.
#[derive(Clone, Copy, PartialEq)]
enum Method {
    Quilez,
    QuilezImproved,
    Chord,
    Smoothstep,
    Proxy,
    ProxyExact,
}

impl Method {
    fn name(self) -> &'static str {
        match self {
            Method::Quilez => "quilez",
            Method::QuilezImproved => "quilez+",
            Method::Chord => "001 chord",
            Method::Smoothstep => "001 smooth",
            Method::Proxy => "001 proxy",
            Method::ProxyExact => "001 proxy exact",
        }
    }
    /// Whether the method is a visibility times the unshadowed shading (seed 001 eq. 2).
    fn times_unshadowed(self) -> bool {
        !matches!(self, Method::Proxy | Method::ProxyExact)
    }
}

/// Directions of the numerical proxy integration (seed 001 figure 4 uses 100 per pixel).
const PROXY_SAMPLES: u32 = 128;
const ALBEDO: f64 = 0.8;

/// One light, its exact scenes and its SDF stand-ins.
struct Lighting {
    bound: SphereLight,
    quad: Option<QuadLight>,
    /// The light alone (unshadowed shading).
    open: Scene,
    /// Every object as an occluder (floor points).
    full: Scene,
    /// Every object but the `k`-th (points on object `k`).
    without: Vec<Scene>,
    /// Only the `k`-th object (which occluders shadow a floor point).
    single: Vec<Scene>,
}

fn lighting(kind: LightKind, world: &World, light_tolerance: f64) -> Lighting {
    let center = DVec3::new(0.7, 1.5, 3.0);
    let (shape, bound, quad): (Body, SphereLight, Option<QuadLight>) = match kind {
        LightKind::Sphere => {
            let r = 0.45;
            let (s, gap) = subdivisions_for(r, light_tolerance);
            println!("  sphere light: icosphere with {s} subdivisions, gap {gap:.2e}");
            (
                ConvexPolyhedron::icosphere(center, r, s).unwrap().into(),
                SphereLight::new(center, r).unwrap(),
                None,
            )
        }
        LightKind::Quad => {
            let (u, v) = (DVec3::new(0.5, 0.0, 0.0), DVec3::new(0.0, -0.35, 0.0));
            let q = QuadLight::new(center, u, v).unwrap();
            let b = arealight::sdf::AreaLight::bounding_sphere(&q);
            (TriangleMesh::quad(center, u, v).unwrap().into(), b, Some(q))
        }
    };
    let light = || vec![Light::new(shape.clone(), DVec3::ONE).unwrap()];
    let occ = |keep: &dyn Fn(usize) -> bool| -> Vec<Body> {
        world
            .objects
            .iter()
            .enumerate()
            .filter(|(k, _)| keep(*k))
            .map(|(_, o)| o.mesh.clone().into())
            .collect()
    };
    let n = world.objects.len();
    Lighting {
        bound,
        quad,
        open: Scene::new(light(), vec![]).unwrap(),
        full: Scene::new(light(), occ(&|_| true)).unwrap(),
        without: (0..n)
            .map(|k| Scene::new(light(), occ(&|j| j != k)).unwrap())
            .collect(),
        single: (0..n)
            .map(|k| Scene::new(light(), occ(&|j| j == k)).unwrap())
            .collect(),
    }
}

fn white() -> Material {
    Material::diffuse(DVec3::splat(ALBEDO)).unwrap()
}

impl Lighting {
    fn exact_scene(&self, hit: &Hit) -> &Scene {
        match hit.on {
            None => &self.full,
            Some(k) => &self.without[k],
        }
    }

    fn exact(&self, hit: &Hit) -> Option<f64> {
        self.exact_scene(hit)
            .shade(hit.p, hit.n, hit.view, &white())
            .ok()
            .map(|c| c.x)
    }

    fn unshadowed(&self, hit: &Hit) -> Option<f64> {
        self.open
            .shade(hit.p, hit.n, hit.view, &white())
            .ok()
            .map(|c| c.x)
    }

    /// The method's own part: a visibility (for the eq. 2 methods) or the shading itself.
    fn method(&self, m: Method, world: &World, hit: &Hit, eps: f64) -> Option<f64> {
        let search = ConeSearch::new(eps, 1e-3);
        let q = QuilezSettings::new(1e-3);
        let f = &world.field;
        let r = match m {
            Method::Quilez => quilez_shadow(f, hit.p, &self.bound, &q),
            Method::QuilezImproved => quilez_improved_shadow(f, hit.p, &self.bound, &q),
            Method::Chord => fast_soft_shadow(f, hit.p, &self.bound, &search, Profile::Chord),
            Method::Smoothstep => {
                fast_soft_shadow(f, hit.p, &self.bound, &search, Profile::Smoothstep)
            }
            Method::Proxy => {
                let cosine = |l: DVec3| ALBEDO * hit.n.dot(l).max(0.0) / std::f64::consts::PI;
                match &self.quad {
                    Some(quad) => proxy_integral(f, hit.p, quad, cosine, PROXY_SAMPLES, &search),
                    None => proxy_integral(f, hit.p, &self.bound, cosine, PROXY_SAMPLES, &search),
                }
            }
            Method::ProxyExact => match &self.quad {
                Some(quad) => {
                    proxy_quad_integral(f, hit.p, hit.n, quad, &search).map(|v| ALBEDO * v)
                }
                None => return None,
            },
        };
        r.ok()
    }

    /// Which class a point belongs to: 0 floor in full light (no occluder hides any of the
    /// light), 1 floor shadowed by one occluder, 2 floor shadowed by several, 3 object surface.
    fn class(&self, hit: &Hit, unshadowed: f64) -> u8 {
        if hit.on.is_some() {
            return 3;
        }
        let casting = self
            .single
            .iter()
            .filter(|s| {
                s.shade(hit.p, hit.n, hit.view, &white())
                    .is_ok_and(|c| c.x < unshadowed * (1.0 - 1e-9))
            })
            .count();
        casting.min(2) as u8
    }
}

const CLASS_NAMES: [&str; 4] = [
    "floor, unshadowed",
    "floor, 1 occluder",
    "floor, >= 2 occluders",
    "object surfaces",
];

fn srgb(x: f64) -> u8 {
    let t = x.clamp(0.0, 1.0);
    let s = if t <= 0.003_130_8 {
        12.92 * t
    } else {
        1.055 * t.powf(1.0 / 2.4) - 0.055
    };
    (s * 255.0).round() as u8
}

fn heat(e: f64) -> [u8; 3] {
    let e = e.clamp(0.0, 1.0) * 3.0;
    [
        (e.min(1.0) * 255.0) as u8,
        ((e - 1.0).clamp(0.0, 1.0) * 255.0) as u8,
        ((e - 2.0).clamp(0.0, 1.0) * 255.0) as u8,
    ]
}

fn write_png(path: &PathBuf, w: usize, h: usize, pixels: &[u8]) -> Result<(), String> {
    let file = std::fs::File::create(path).map_err(|e| format!("{}: {e}", path.display()))?;
    let mut enc = png::Encoder::new(std::io::BufWriter::new(file), w as u32, h as u32);
    enc.set_color(png::ColorType::Rgb);
    enc.set_depth(png::BitDepth::Eight);
    let mut wr = enc.write_header().map_err(|e| e.to_string())?;
    wr.write_image_data(pixels).map_err(|e| e.to_string())
}

/// One row of the comparison table.
struct Row {
    name: &'static str,
    micros: f64,
    micros_total: f64,
    mae: f64,
    rmse: f64,
    ssim: f64,
    by_class: [f64; 4],
}

fn run(args: &Args, world: &World, hits: &[Option<Hit>], kind: LightKind) -> Result<(), String> {
    let (w, h, th) = (args.width, args.height, args.threads);
    let tol_light = 0.45 / 1024.0;
    let lit = lighting(kind, world, tol_light);
    let label = match kind {
        LightKind::Sphere => "sphere",
        LightKind::Quad => "quad",
    };
    let points = hits.iter().filter(|h| h.is_some()).count();
    let per_point = |secs: f64| secs * th as f64 / points as f64 * 1e6;

    let (exact, t_exact) = par_map(w * h, th, |i| hits[i].as_ref().and_then(|x| lit.exact(x)));
    let (open, t_open) = par_map(w * h, th, |i| {
        hits[i].as_ref().and_then(|x| lit.unshadowed(x))
    });
    let (class, _) = par_map(w * h, th, |i| match (&hits[i], open[i]) {
        (Some(x), Some(u)) => lit.class(x, u),
        _ => 0,
    });
    let methods: Vec<Method> = match kind {
        LightKind::Sphere => vec![
            Method::Quilez,
            Method::QuilezImproved,
            Method::Chord,
            Method::Smoothstep,
            Method::Proxy,
        ],
        LightKind::Quad => vec![
            Method::Quilez,
            Method::QuilezImproved,
            Method::Chord,
            Method::Smoothstep,
            Method::Proxy,
            Method::ProxyExact,
        ],
    };
    let mut images = Vec::new();
    let mut rows = Vec::new();
    // Pixels every method (and the exact shading) could shade.
    let mut valid: Vec<bool> = (0..w * h)
        .map(|i| exact[i].is_some() && open[i].is_some())
        .collect();
    let mut raw = Vec::new();
    for &m in &methods {
        let (v, secs) = par_map(w * h, th, |i| {
            hits[i]
                .as_ref()
                .and_then(|x| lit.method(m, world, x, args.epsilon))
        });
        for i in 0..w * h {
            valid[i] &= v[i].is_some() || hits[i].is_none();
        }
        raw.push((m, v, secs));
    }
    let invalid = hits
        .iter()
        .zip(&valid)
        .filter(|(h, v)| h.is_some() && !**v)
        .count();
    let exact_img = |i: usize| {
        if valid[i] {
            exact[i].unwrap_or(0.0)
        } else {
            0.0
        }
    };
    let scale = (0..w * h).map(exact_img).fold(0.0, f64::max).max(1e-300);
    let mut reference = Gray::new(w, h);
    for i in 0..w * h {
        reference.data[i] = exact_img(i) / scale;
    }
    for (m, v, secs) in &raw {
        let mut img = Gray::new(w, h);
        for i in 0..w * h {
            if valid[i] {
                let own = v[i].unwrap_or(0.0);
                let value = if m.times_unshadowed() {
                    own * open[i].unwrap_or(0.0)
                } else {
                    own
                };
                img.data[i] = value / scale;
            }
        }
        let mut by_class = [0.0; 4];
        for (c, slot) in by_class.iter_mut().enumerate() {
            let mask: Vec<bool> = (0..w * h)
                .map(|i| valid[i] && class[i] == c as u8)
                .collect();
            *slot = mae(&img, &reference, Some(&mask));
        }
        let mask: Vec<bool> = (0..w * h).map(|i| valid[i] && hits[i].is_some()).collect();
        rows.push(Row {
            name: m.name(),
            micros: per_point(*secs),
            micros_total: per_point(*secs)
                + if m.times_unshadowed() {
                    per_point(t_open)
                } else {
                    0.0
                },
            mae: mae(&img, &reference, Some(&mask)),
            rmse: rmse(&img, &reference, Some(&mask)),
            ssim: ssim(&img, &reference, 1.0).unwrap_or(f64::NAN),
            by_class,
        });
        images.push(img);
    }

    // Monte Carlo cross-check of the exact image on a subset of pixels.
    let mut mc_line = String::from("Monte Carlo cross-check: skipped");
    if args.mc_stride > 0 {
        let picks: Vec<usize> = (0..w * h)
            .step_by(args.mc_stride)
            .filter(|&i| valid[i] && hits[i].is_some())
            .collect();
        let mc = MonteCarlo::new(4096, ReferenceBrdf::Ltc);
        let (zs, _) = par_map(picks.len(), th, |j| {
            let i = picks[j];
            let x = hits[i].as_ref().unwrap();
            let est = mc
                .estimate(lit.exact_scene(x), x.p, x.n, x.view, &white(), i as u64)
                .ok()?;
            let se = est.std_error.x.max(1e-12);
            Some((
                (exact[i].unwrap() - est.mean.x) / se,
                (exact[i].unwrap() - est.mean.x).abs() / scale,
            ))
        });
        let zs: Vec<(f64, f64)> = zs.into_iter().flatten().collect();
        let n = zs.len().max(1) as f64;
        let mean_abs_z = zs.iter().map(|z| z.0.abs()).sum::<f64>() / n;
        let max_z = zs.iter().map(|z| z.0.abs()).fold(0.0, f64::max);
        let beyond = zs.iter().filter(|z| z.0.abs() > 4.0).count();
        let mae_mc = zs.iter().map(|z| z.1).sum::<f64>() / n;
        mc_line = format!(
            "Monte Carlo cross-check (4096 samples, {} pixels): mean |z| {mean_abs_z:.2} (0.80 expected), max |z| {max_z:.2}, {beyond} beyond 4 sigma; MAE of MC {mae_mc:.5}",
            zs.len()
        );
    }

    println!(
        "\n{label} light, {w} x {h}, {points} shaded points ({invalid} skipped: a method returned an error), epsilon {}",
        args.epsilon
    );
    println!(
        "exact: {:.1} us per point (unshadowed: {:.1} us)",
        per_point(t_exact),
        per_point(t_open)
    );
    println!("{mc_line}");
    let counts: Vec<usize> = (0..4)
        .map(|c| {
            (0..w * h)
                .filter(|&i| valid[i] && hits[i].is_some() && class[i] == c)
                .count()
        })
        .collect();
    println!(
        "\n| method | us/point (own) | us/point (with unshadowed) | MAE | RMSE | SSIM | MAE {} ({}) | MAE {} ({}) | MAE {} ({}) | MAE {} ({}) |",
        CLASS_NAMES[0],
        counts[0],
        CLASS_NAMES[1],
        counts[1],
        CLASS_NAMES[2],
        counts[2],
        CLASS_NAMES[3],
        counts[3]
    );
    println!("|---|---|---|---|---|---|---|---|---|---|");
    for r in &rows {
        println!(
            "| {} | {:.1} | {:.1} | {:.5} | {:.5} | {:.4} | {:.5} | {:.5} | {:.5} | {:.5} |",
            r.name,
            r.micros,
            r.micros_total,
            r.mae,
            r.rmse,
            r.ssim,
            r.by_class[0],
            r.by_class[1],
            r.by_class[2],
            r.by_class[3]
        );
    }

    // The picture: exact and methods on top, classes and errors below.
    let cols = 1 + images.len();
    let (pw, ph) = (cols * w, 2 * h);
    let mut px = vec![0u8; pw * ph * 3];
    let mut put = |col: usize, row: usize, i: usize, rgb: [u8; 3]| {
        let (x, y) = (col * w + i % w, row * h + i / w);
        px[(y * pw + x) * 3..(y * pw + x) * 3 + 3].copy_from_slice(&rgb);
    };
    let palette = [[60, 60, 60], [60, 110, 230], [220, 60, 220], [60, 200, 90]];
    for i in 0..w * h {
        let g = srgb(reference.data[i]);
        put(0, 0, i, [g, g, g]);
        put(
            0,
            1,
            i,
            if hits[i].is_some() {
                palette[class[i] as usize]
            } else {
                [0, 0, 0]
            },
        );
        for (k, img) in images.iter().enumerate() {
            let g = srgb(img.data[i]);
            put(k + 1, 0, i, [g, g, g]);
            put(
                k + 1,
                1,
                i,
                heat((img.data[i] - reference.data[i]).abs() / 0.1),
            );
        }
    }
    std::fs::create_dir_all(&args.out).map_err(|e| format!("{}: {e}", args.out.display()))?;
    let path = args.out.join(format!("sdf_shadows_{label}.png"));
    write_png(&path, pw, ph, &px)?;
    let order: Vec<&str> = methods.iter().map(|m| m.name()).collect();
    println!(
        "\nwrote {} (columns: exact, {})",
        path.display(),
        order.join(", ")
    );
    Ok(())
}

fn main() {
    let args = arealight_demo::args_or_exit(parse_args());
    let cam = Camera::new(DVec3::new(0.3, -4.6, 3.1), DVec3::new(0.1, 0.3, 0.35), 42.0);
    // Shadow edges move by at most the silhouette error times the largest magnification from
    // an occluder to the floor (light at height 3, objects up to 1.2: 3 / 1.8); keep that under
    // half the footprint of a pixel at the nearest shadowed floor (distance about 4).
    let shadow_tolerance = 0.5 * cam.footprint(4.0, args.height) / (3.0 / 1.8);
    println!("scene (shadow tolerance {shadow_tolerance:.2e}):");
    let world = world(shadow_tolerance);
    let names: Vec<&str> = world.objects.iter().map(|o| o.name).collect();
    println!("  objects: {}", names.join(", "));
    let start = Instant::now();
    let hits = primary(&world, &cam, args.width, args.height, args.threads);
    println!(
        "  camera rays traced in {:.2} s",
        start.elapsed().as_secs_f64()
    );
    for &kind in &args.lights {
        if let Err(e) = run(&args, &world, &hits, kind) {
            eprintln!("{e}");
            std::process::exit(1);
        }
    }
}
