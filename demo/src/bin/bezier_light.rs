//! A letter-shaped light: a "B" built in code from its outline of cubic Bezier curves and line
//! segments (two holes), tilted over a glossy floor, with a box and a ball casting soft shadows
//! from it (seed 004's free-form lights in a scene with seed 000's exact visibility).
//!
//! ```sh
//! cargo run --release -p arealight-demo --bin bezier_light   # 240 x 180, 2 threads
//! cargo run --release -p arealight-demo --bin bezier_light -- --width 480 --height 360 --samples 1024
//! ```
//!
//! Writes `target/arealight-out/bezier_light.png`: the analytic image (the scene's per-point
//! flattening of the curves through the exact visible-region pipeline), the Monte Carlo
//! reference (area samples of the exact curved region, exact ray visibility, the LTC BRDF so that
//! the two differ only in geometry and noise), and their difference times 10. Prints the mean
//! absolute error against the reference of the analytic image, of the same scene with a coarse
//! flattening (0.05 rad), and of the unshadowed curved integrals (`Light::shade_curved`, no
//! occluders: the shadows' share), next to the reference's own noise (its mean standard error;
//! an exact image would show about 0.8 of it), and the noise-free difference of the two
//! flattenings.

use arealight::glam::{DVec2, DVec3};
use arealight::shade::{
    BezierSegment, BezierShape, Body, ConvexPolyhedron, DEFAULT_DIFFUSE_SUBDIVISION, Light,
    Material, MonteCarlo, ReferenceBrdf, Scene,
};
use std::time::Instant;

use arealight_demo::trace::Hit;
use arealight_demo::{image, trace};

/// A 2D outline segment: a line to a point, or a cubic with two handles to a point.
enum Seg {
    Line(f64, f64),
    Cubic([f64; 2], [f64; 2], [f64; 2]),
}

/// The glyph "B" in font units (0 .. 1 wide, 0 .. 1.4 tall): the outer contour
/// counter-clockwise, the two counters clockwise, each from its start point.
fn glyph() -> Vec<((f64, f64), Vec<Seg>)> {
    use Seg::{Cubic, Line};
    vec![
        (
            (0.0, 0.0),
            vec![
                Line(0.55, 0.0),
                Cubic([0.92, 0.0], [0.95, 0.70], [0.62, 0.74]),
                Cubic([0.88, 0.80], [0.88, 1.40], [0.50, 1.40]),
                Line(0.0, 1.40),
                Line(0.0, 0.0),
            ],
        ),
        (
            (0.2, 0.2),
            vec![
                Line(0.2, 0.6),
                Line(0.5, 0.6),
                Cubic([0.72, 0.6], [0.72, 0.2], [0.5, 0.2]),
                Line(0.2, 0.2),
            ],
        ),
        (
            (0.2, 0.88),
            vec![
                Line(0.2, 1.22),
                Line(0.45, 1.22),
                Cubic([0.66, 1.22], [0.66, 0.88], [0.45, 0.88]),
                Line(0.2, 0.88),
            ],
        ),
    ]
}

/// The glyph placed in 3D: `size` units tall, centred at `center`, its baseline along `+x` and
/// its up direction tilted `tilt` radians from `+z` towards `-y`, so that it faces the floor and
/// the camera (its front, about which the outer contour runs counter-clockwise).
fn letter(center: DVec3, size: f64, tilt: f64) -> BezierShape {
    let e1 = DVec3::X;
    let e2 = DVec3::new(0.0, -tilt.sin(), tilt.cos());
    let at = |x: f64, y: f64| {
        let q = (DVec2::new(x, y) - DVec2::new(0.5, 0.7)) * (size / 1.4);
        center + e1 * q.x + e2 * q.y
    };
    let loops = glyph()
        .into_iter()
        .map(|((x0, y0), segs)| {
            let mut prev = at(x0, y0);
            segs.into_iter()
                .map(|s| {
                    let seg = match s {
                        Seg::Line(x, y) => BezierSegment::Line([prev, at(x, y)]),
                        Seg::Cubic(a, b, [x, y]) => {
                            BezierSegment::Cubic([prev, at(a[0], a[1]), at(b[0], b[1]), at(x, y)])
                        }
                    };
                    prev = seg.end();
                    seg
                })
                .collect()
        })
        .collect();
    BezierShape::new(loops).expect("the B is a valid outline")
}

struct World {
    scene: Scene,
    floor: Material,
    occluder_materials: Vec<Material>,
}

fn world(flatten_angle: f64) -> World {
    let b = letter(DVec3::new(0.0, 0.6, 2.3), 1.8, 0.7)
        .with_flatten_angle(flatten_angle)
        .expect("angle");
    let occluders: Vec<Body> = vec![
        ConvexPolyhedron::cuboid(DVec3::new(0.55, -0.2, 0.35), DVec3::new(0.25, 0.25, 0.35))
            .expect("box")
            .into(),
        ConvexPolyhedron::icosphere(DVec3::new(-0.6, -0.5, 0.35), 0.35, 2)
            .expect("ball")
            .into(),
    ];
    World {
        scene: Scene::new(
            vec![Light::new(b, DVec3::new(2.0, 1.6, 1.1)).expect("light")],
            occluders,
        )
        .expect("scene"),
        floor: Material::new(DVec3::splat(0.45), DVec3::splat(0.7), 0.2).expect("floor"),
        occluder_materials: vec![
            Material::new(DVec3::new(0.7, 0.3, 0.2), DVec3::splat(0.04), 0.5).expect("box"),
            Material::new(DVec3::new(0.2, 0.5, 0.7), DVec3::splat(0.04), 0.3).expect("ball"),
        ],
    }
}

fn trace(w: &World, o: DVec3, d: DVec3) -> Hit {
    let (mut best, mut hit) = (f64::INFINITY, Hit::Nothing);
    if d.z < 0.0 {
        let t = -o.z / d.z;
        let p = o + t * d;
        if p.x.abs() <= 5.0 && p.y.abs() <= 5.0 {
            best = t;
            hit = Hit::Surface(DVec3::new(p.x, p.y, 0.0), DVec3::Z, -d, w.floor);
        }
    }
    for light in w.scene.lights() {
        if let Body::Bezier(b) = light.shape() {
            // The exact curved region: the ray's point in the plane, tested against the curves.
            let n = b.normal();
            let den = n.dot(d);
            if den != 0.0 {
                let t = n.dot(b.plane_point() - o) / den;
                if t > 1e-9 && t < best && b.contains(o + t * d) {
                    best = t;
                    hit = Hit::Emitter(if den < 0.0 {
                        light.radiance()
                    } else {
                        DVec3::splat(0.03)
                    });
                }
            }
        }
    }
    for (k, occ) in w.scene.occluders().iter().enumerate() {
        let mesh = occ.mesh();
        for i in 0..mesh.triangle_count() {
            if let Some(t) = trace::ray_triangle(o, d, mesh.triangle(i)).map(|h| h.0)
                && t < best
            {
                best = t;
                let n = mesh.triangle_normal(i);
                let p = o + t * d;
                let p = p - n * n.dot(p - mesh.triangle(i)[0]);
                hit = Hit::Surface(p, n, -d, w.occluder_materials[k]);
            }
        }
    }
    hit
}

/// Per pixel: analytic, coarse flattening, unshadowed curved integrals, reference and its
/// standard error; `None` for pixels that show no shaded surface.
type Pixel = Option<[DVec3; 5]>;

/// One thread's rows: the row index, its displayed colours and its pixels' values.
type Rows<'a> = Vec<(usize, &'a mut [DVec3], &'a mut [Pixel])>;

fn main() {
    let mut args = std::env::args().skip(1);
    let (mut width, mut height, mut threads, mut samples) = (240usize, 180usize, 2usize, 512u32);
    while let Some(flag) = args.next() {
        let value: usize = args
            .next()
            .and_then(|v| v.parse().ok())
            .unwrap_or_else(|| panic!("{flag} needs a number"));
        match flag.as_str() {
            "--width" => width = value.max(1),
            "--height" => height = value.max(1),
            "--threads" => threads = value.max(1),
            "--samples" => samples = value.max(2) as u32,
            _ => panic!("unknown flag {flag} (--width, --height, --threads, --samples)"),
        }
    }
    let w = world(arealight::solid::DEFAULT_FLATTEN_ANGLE);
    let coarse = world(0.05);
    let eye = DVec3::new(0.4, -5.2, 1.5);
    let fwd = (DVec3::new(0.0, 0.3, 0.9) - eye).normalize();
    let right = fwd.cross(DVec3::Z).normalize();
    let up = right.cross(fwd);
    let tan_half = (48f64.to_radians() / 2.0).tan();
    let aspect = width as f64 / height as f64;
    let mc = MonteCarlo::new(samples, ReferenceBrdf::Ltc);
    let light = &w.scene.lights()[0];
    let mut shown = vec![DVec3::ZERO; width * height];
    let mut pixels: Vec<Pixel> = vec![None; width * height];
    let mut times = [0.0f64; 2]; // analytic, reference (summed over threads)
    let gave_up = std::sync::atomic::AtomicUsize::new(0);
    let mut rows: Vec<Rows> = (0..threads).map(|_| Vec::new()).collect();
    for (y, (row, px)) in shown
        .chunks_mut(width)
        .zip(pixels.chunks_mut(width))
        .enumerate()
    {
        rows[y % threads].push((y, row, px));
    }
    let start = Instant::now();
    let spent: Vec<[f64; 2]> = std::thread::scope(|s| {
        let handles: Vec<_> = rows
            .into_iter()
            .map(|mine| {
                let (w, coarse, mc, gave_up) = (&w, &coarse, &mc, &gave_up);
                s.spawn(move || {
                    let mut t = [0.0f64; 2];
                    for (y, row, px) in mine {
                        for x in 0..width {
                            let sx =
                                (2.0 * (x as f64 + 0.5) / width as f64 - 1.0) * tan_half * aspect;
                            let sy = (1.0 - 2.0 * (y as f64 + 0.5) / height as f64) * tan_half;
                            let d = (fwd + sx * right + sy * up).normalize();
                            row[x] = match trace(w, eye, d) {
                                Hit::Nothing => DVec3::splat(0.02),
                                Hit::Emitter(l) => l,
                                Hit::Surface(p, n, v, m) => {
                                    let t0 = Instant::now();
                                    let a = w.scene.shade(p, n, v, &m);
                                    t[0] += t0.elapsed().as_secs_f64();
                                    let t1 = Instant::now();
                                    let e = mc
                                        .estimate(&w.scene, p, n, v, &m, (y * width + x) as u64)
                                        .expect("reference");
                                    t[1] += t1.elapsed().as_secs_f64();
                                    let a = a.unwrap_or_else(|_| {
                                        gave_up.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                                        e.mean
                                    });
                                    let c = coarse.scene.shade(p, n, v, &m).unwrap_or(e.mean);
                                    let u = light
                                        .shade_curved(
                                            p,
                                            n,
                                            v,
                                            &m,
                                            DEFAULT_DIFFUSE_SUBDIVISION,
                                            None,
                                        )
                                        .map(|r| r.total())
                                        .unwrap_or(e.mean);
                                    px[x] = Some([a, c, u, e.mean, e.std_error]);
                                    a
                                }
                            };
                        }
                    }
                    t
                })
            })
            .collect();
        handles
            .into_iter()
            .map(|h| h.join().expect("thread"))
            .collect()
    });
    for t in spent {
        times[0] += t[0];
        times[1] += t[1];
    }
    let wall = start.elapsed().as_secs_f64();
    // Mean absolute errors over the shaded pixels and channels.
    let (mut n, mut mae) = (0usize, [0.0f64; 5]);
    for p in pixels.iter().flatten() {
        let [a, c, u, r, se] = *p;
        n += 3;
        mae[0] += (a - r).abs().element_sum();
        mae[1] += (c - r).abs().element_sum();
        mae[2] += (u - r).abs().element_sum();
        mae[3] += se.element_sum();
        mae[4] += (a - c).abs().element_sum();
    }
    let mae = mae.map(|v| v / n.max(1) as f64);
    // The image: analytic | reference | 10 x |analytic - reference|.
    let mut out_img = vec![DVec3::ZERO; 3 * width * height];
    for y in 0..height {
        for x in 0..width {
            let i = y * width + x;
            let (a, r) = match pixels[i] {
                Some([a, _, _, r, _]) => (a, r),
                None => (shown[i], shown[i]),
            };
            out_img[y * 3 * width + x] = a;
            out_img[y * 3 * width + width + x] = r;
            out_img[y * 3 * width + 2 * width + x] = (a - r).abs() * 10.0;
        }
    }
    let path = image::out_dir()
        .expect("output directory")
        .join("bezier_light.png");
    image::write_png(&path, 3 * width, height, &image::to_bytes(&out_img, 2.0)).expect("PNG");
    let shaded = n / 3;
    println!(
        "{width} x {height}, {shaded} shaded pixels, {threads} threads, {wall:.1} s wall; \
         analytic {:.1} us per pixel, reference ({samples} samples) {:.1} us per pixel; {} pixels gave up",
        times[0] / shaded.max(1) as f64 * 1e6,
        times[1] / shaded.max(1) as f64 * 1e6,
        gave_up.load(std::sync::atomic::Ordering::Relaxed)
    );
    println!("mean absolute error against the reference (per channel):");
    println!(
        "  analytic, flattening within 1e-3 rad:       {:.3e}",
        mae[0]
    );
    println!(
        "  analytic, flattening within 0.05 rad:       {:.3e}",
        mae[1]
    );
    println!(
        "  curved integrals without the occluders:     {:.3e}",
        mae[2]
    );
    println!(
        "  the reference's own noise (mean std error): {:.3e} (an exact image: about 0.8 of it)",
        mae[3]
    );
    println!(
        "mean absolute difference of the two flattenings (no noise): {:.3e}",
        mae[4]
    );
    println!(
        "image (analytic | reference | 10 x difference): {}",
        path.display()
    );
}
