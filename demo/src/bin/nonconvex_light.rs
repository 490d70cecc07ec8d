//! Renders two closed non-convex lights with soft shadows: a tilted torus and a bowl whose
//! cavity faces the camera and the ground, over a ground plane with a box and a ball standing on it. Each light
//! is shaded from its silhouette seen from the shading point (thesis 003 section 4.3), one
//! polygon per light, with exact soft shadows (seed 000's visibility rule).
//!
//! ```sh
//! cargo run --release -p arealight-demo --bin nonconvex_light   # 320 x 240, 2 threads
//! cargo run --release -p arealight-demo --bin nonconvex_light -- --width 640 --height 480 --threads 2
//! ```
//!
//! Writes `target/arealight-out/nonconvex_light.png`. Prints the render time, the number of
//! pixels where the analytic path gave up (`GeomError::Undecidable`, shaded by the Monte Carlo
//! reference instead), and, on a sparse grid of pixels, the largest difference to the same
//! scene shaded with the union of the lights' front triangles (`Method::PerTriangle`), which
//! must agree to rounding.

use arealight::glam::{DMat3, DQuat, DVec3};
use arealight::internals::{thesis_polyhedra, torus};
use arealight::shade::{
    ConvexPolyhedron, Light, Material, Method, MonteCarlo, ReferenceBrdf, Scene, TriangleMesh,
};
use std::time::Instant;

use arealight_demo::trace::Hit;
use arealight_demo::{image, trace};

/// `mesh` scaled by `s`, rotated by `rot` and moved to `at`.
fn moved(mesh: &TriangleMesh, s: f64, rot: DMat3, at: DVec3) -> TriangleMesh {
    TriangleMesh::new(
        mesh.vertices()
            .iter()
            .map(|&v| rot * (v * s) + at)
            .collect(),
        mesh.triangles().to_vec(),
    )
    .expect("a moved valid mesh is valid")
}

struct World {
    scene: Scene,
    ground: Material,
    occluder_materials: Vec<Material>,
}

fn world() -> World {
    let torus = moved(
        &torus(0.7, 0.22, 28, 12).expect("torus"),
        1.0,
        DMat3::from_rotation_x(0.9) * DMat3::from_rotation_z(0.3),
        DVec3::new(-0.9, 0.3, 1.9),
    );
    let (_, bowl) = thesis_polyhedra()
        .expect("thesis polyhedra")
        .into_iter()
        .find(|(n, _)| *n == "bowl")
        .expect("bowl");
    // The bowl's opening (its +z) turned towards the camera and down, so that both the camera
    // and the ground in front of it see into the cavity.
    let opening = DVec3::new(2.9, -4.4, -1.0).normalize();
    let bowl = moved(
        &bowl,
        0.45,
        DMat3::from_quat(DQuat::from_rotation_arc(DVec3::Z, opening)),
        DVec3::new(1.3, -0.2, 1.6),
    );
    let occluders = vec![
        ConvexPolyhedron::cuboid(DVec3::new(0.2, -0.3, 0.35), DVec3::new(0.3, 0.3, 0.35))
            .expect("box")
            .into(),
        ConvexPolyhedron::icosphere(DVec3::new(-0.7, -0.9, 0.4), 0.4, 2)
            .expect("ball")
            .into(),
    ];
    let scene = Scene::new(
        vec![
            Light::new(torus, DVec3::new(1.6, 1.1, 0.6)).expect("light"),
            Light::new(bowl, DVec3::new(0.5, 0.9, 1.8)).expect("light"),
        ],
        occluders,
    )
    .expect("scene");
    World {
        scene,
        ground: Material::new(DVec3::splat(0.6), DVec3::splat(0.04), 0.35).expect("material"),
        occluder_materials: vec![
            Material::new(DVec3::new(0.7, 0.3, 0.2), DVec3::splat(0.04), 0.5).expect("material"),
            Material::new(DVec3::new(0.2, 0.5, 0.7), DVec3::splat(0.04), 0.2).expect("material"),
        ],
    }
}

fn trace(w: &World, o: DVec3, d: DVec3) -> Hit {
    let (mut best, mut hit) = (f64::INFINITY, Hit::Nothing);
    if d.z < 0.0 {
        let t = -o.z / d.z;
        let p = o + t * d;
        if p.x.abs() <= 6.0 && p.y.abs() <= 6.0 {
            best = t;
            hit = Hit::Surface(DVec3::new(p.x, p.y, 0.0), DVec3::Z, -d, w.ground);
        }
    }
    for light in w.scene.lights() {
        let mesh = light.shape().mesh();
        for i in 0..mesh.triangle_count() {
            if let Some(t) = trace::ray_triangle(o, d, mesh.triangle(i)).map(|h| h.0)
                && t < best
            {
                best = t;
                let front = mesh.triangle_normal(i).dot(d) < 0.0;
                hit = Hit::Emitter(if front { light.radiance() } else { DVec3::ZERO });
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

fn main() {
    let mut args = std::env::args().skip(1);
    let (mut width, mut height, mut threads) = (320usize, 240usize, 2usize);
    while let Some(flag) = args.next() {
        let value: usize = args
            .next()
            .and_then(|v| v.parse().ok())
            .unwrap_or_else(|| panic!("{flag} needs a number"));
        match flag.as_str() {
            "--width" => width = value.max(1),
            "--height" => height = value.max(1),
            "--threads" => threads = value.max(1),
            _ => panic!("unknown flag {flag} (--width, --height, --threads)"),
        }
    }
    let w = world();
    let eye = DVec3::new(4.2, -4.6, 3.1);
    let fwd = (DVec3::new(0.1, 0.0, 0.9) - eye).normalize();
    let right = fwd.cross(DVec3::Z).normalize();
    let up = right.cross(fwd);
    let tan_half = (50f64.to_radians() / 2.0).tan();
    let aspect = width as f64 / height as f64;
    let mc = MonteCarlo::new(4096, ReferenceBrdf::Ltc);
    let start = Instant::now();
    let mut img = vec![DVec3::ZERO; width * height];
    let gave_up = std::sync::atomic::AtomicUsize::new(0);
    let mut rows: Vec<Vec<(usize, &mut [DVec3])>> = (0..threads).map(|_| Vec::new()).collect();
    for (y, row) in img.chunks_mut(width).enumerate() {
        rows[y % threads].push((y, row));
    }
    std::thread::scope(|s| {
        for mine in rows {
            let (w, mc, gave_up) = (&w, &mc, &gave_up);
            s.spawn(move || {
                for (y, row) in mine {
                    for (x, px) in row.iter_mut().enumerate() {
                        let sx = (2.0 * (x as f64 + 0.5) / width as f64 - 1.0) * tan_half * aspect;
                        let sy = (1.0 - 2.0 * (y as f64 + 0.5) / height as f64) * tan_half;
                        let d = (fwd + sx * right + sy * up).normalize();
                        *px = match trace(w, eye, d) {
                            Hit::Nothing => DVec3::splat(0.02),
                            Hit::Emitter(l) => l,
                            Hit::Surface(p, n, v, m) => match w.scene.shade(p, n, v, &m) {
                                Ok(c) => c,
                                Err(_) => {
                                    gave_up.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                                    mc.estimate(&w.scene, p, n, v, &m, (y * width + x) as u64)
                                        .map(|e| e.mean)
                                        .unwrap_or(DVec3::ZERO)
                                }
                            },
                        };
                    }
                }
            });
        }
    });
    let time = start.elapsed();
    // The union of front triangles on a sparse grid: the same integrals up to rounding.
    let per_tri = w.scene.clone().with_method(Method::PerTriangle);
    let mut worst: f64 = 0.0;
    for y in (height / 16..height).step_by((height / 8).max(1)) {
        for x in (width / 16..width).step_by((width / 8).max(1)) {
            let sx = (2.0 * (x as f64 + 0.5) / width as f64 - 1.0) * tan_half * aspect;
            let sy = (1.0 - 2.0 * (y as f64 + 0.5) / height as f64) * tan_half;
            let d = (fwd + sx * right + sy * up).normalize();
            if let Hit::Surface(p, n, v, m) = trace(&w, eye, d)
                && let (Ok(a), Ok(b)) = (w.scene.shade(p, n, v, &m), per_tri.shade(p, n, v, &m))
            {
                worst = worst.max((a - b).abs().max_element());
            }
        }
    }
    let path = image::out_dir()
        .expect("output directory")
        .join("nonconvex_light.png");
    image::write_png(&path, width, height, &image::to_bytes(&img, 3.0)).expect("PNG");
    println!(
        "{width} x {height} in {:.2} s ({threads} threads); {} pixels gave up (Monte Carlo); \
         largest difference to the union of front triangles on the check grid {worst:.1e}",
        time.as_secs_f64(),
        gave_up.load(std::sync::atomic::Ordering::Relaxed)
    );
    println!("image: {}", path.display());
}
