//! Shading a point allocates nothing for lights and occluders of up to 16 vertices: neither
//! `Scene::shade` (which lends the thread's kept scratch storage, held in thread-local storage,
//! not on the heap) nor `Scene::shade_in` (the caller's). Counted with a wrapping global allocator, only on the test's own thread.
//!
//! The scenes are the benchmark's (a quad light over a cube, a flat box and an icosahedron) and
//! a convex light (a box) over the same occluders, shaded at ground points in their penumbrae,
//! with a diffuse and a glossy material; each query must also have taken the fast path (the
//! spherical path allocates its polygons, so a query that fell back would be counted anyway).

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;

use arealight::glam::DVec3;
use arealight::shade::{
    Body, ConvexPolyhedron, Light, Material, Scene, ShadeContext, TriangleMesh,
};
use support::Rng;
use support::shade::view_above;

mod support;

struct Counting;

thread_local! {
    static COUNTING: Cell<bool> = const { Cell::new(false) };
    static COUNT: Cell<usize> = const { Cell::new(0) };
}

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        if COUNTING.with(Cell::get) {
            COUNT.with(|c| c.set(c.get() + 1));
        }
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { System.dealloc(ptr, layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        if COUNTING.with(Cell::get) {
            COUNT.with(|c| c.set(c.get() + 1));
        }
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

/// Allocations made by `f` on this thread.
fn allocations<T>(f: impl FnOnce() -> T) -> (T, usize) {
    COUNT.with(|c| c.set(0));
    COUNTING.with(|c| c.set(true));
    let r = f();
    COUNTING.with(|c| c.set(false));
    (r, COUNT.with(Cell::get))
}

fn occluders() -> Vec<Body> {
    vec![
        ConvexPolyhedron::cuboid(DVec3::new(0.0, 0.0, 1.0), DVec3::splat(0.25))
            .unwrap()
            .into(),
        ConvexPolyhedron::cuboid(DVec3::new(0.35, -0.3, 1.35), DVec3::new(0.15, 0.1, 0.05))
            .unwrap()
            .into(),
        ConvexPolyhedron::icosphere(DVec3::new(0.1, 0.35, 1.5), 0.12, 0)
            .unwrap()
            .into(),
    ]
}

#[test]
fn shading_allocates_nothing_for_small_inputs() {
    let quad =
        TriangleMesh::quad(DVec3::new(0.0, 0.0, 2.0), DVec3::Y * 0.5, DVec3::X * 0.5).unwrap();
    // No occluder vertex in the plane of a lamp face (the flat box reaches x = 0.5): a blocker
    // touching a light's face plane is never subtracted whole, and the fast path declines it.
    let lamp =
        ConvexPolyhedron::cuboid(DVec3::new(0.12, 0.0, 2.2), DVec3::new(0.4, 0.3, 0.1)).unwrap();
    let lights: [Body; 2] = [quad.into(), lamp.into()];
    let materials = [
        Material::diffuse(DVec3::splat(0.8)).unwrap(),
        Material::new(DVec3::splat(0.5), DVec3::splat(0.04), 0.4).unwrap(),
    ];
    let mut rng = Rng::new(7);
    let mut ctx = ShadeContext::new();
    let (mut checked, mut shadowed) = (0, 0);
    for light in lights {
        for k in 0..=3 {
            let scene = Scene::new(
                vec![Light::new(light.clone(), DVec3::ONE).unwrap()],
                occluders()[..k].to_vec(),
            )
            .unwrap();
            let lit =
                Scene::new(vec![Light::new(light.clone(), DVec3::ONE).unwrap()], vec![]).unwrap();
            for _ in 0..40 {
                let x = DVec3::new(rng.range(-0.2, 0.8), rng.range(-0.4, 0.6), 0.0);
                let v = view_above(&mut rng, DVec3::Z, 0.2);
                let m = &materials[rng.below(2)];
                let before = ctx.fast_lights();
                let (a, n1) = allocations(|| scene.shade_in(&mut ctx, x, DVec3::Z, v, m));
                let (b, n2) = allocations(|| scene.shade(x, DVec3::Z, v, m));
                let (a, b) = (a.unwrap(), b.unwrap());
                assert_eq!(a, b);
                assert_eq!(
                    ctx.fast_lights(),
                    before + 1,
                    "{x}, {k} occluders: not on the fast path"
                );
                assert_eq!(
                    (n1, n2),
                    (0, 0),
                    "{x}, {k} occluders: allocations (shade_in, shade)"
                );
                checked += 1;
                let full = lit.shade(x, DVec3::Z, v, m).unwrap();
                shadowed += usize::from(a.x < 0.99 * full.x);
            }
        }
    }
    // The points are in shadow often enough that the blockers' code ran, not only the light's.
    assert!(
        shadowed * 4 >= checked,
        "{shadowed} of {checked} points shadowed"
    );
    // The counter does see allocations on this thread.
    let (_, n) = allocations(|| vec![1u8; 16]);
    assert_eq!(n, 1);
}

/// `Scene::shade` keeps its scratch storage per thread: over a closed mesh blocker (whose
/// contour overlay needs heap buffers) the first call on a thread may allocate them, later calls
/// on that thread allocate nothing, and every value equals `Scene::shade_in`'s with a fresh
/// context, bit for bit, on this thread and on another. (With a context made per call, every
/// call allocates: checked.)
#[test]
fn shade_keeps_its_scratch_per_thread() {
    let quad =
        TriangleMesh::quad(DVec3::new(0.0, 0.0, 3.0), DVec3::Y * 0.5, DVec3::X * 0.5).unwrap();
    let cube = ConvexPolyhedron::cuboid(DVec3::new(0.0, 0.0, 1.5), DVec3::splat(0.35)).unwrap();
    let scene = Scene::new(
        vec![Light::new(quad, DVec3::ONE).unwrap()],
        vec![cube.mesh().clone().into()],
    )
    .unwrap();
    let m = Material::new(DVec3::splat(0.5), DVec3::splat(0.04), 0.4).unwrap();
    let mut rng = Rng::new(11);
    let pts: Vec<(DVec3, DVec3)> = (0..24)
        .map(|_| {
            let x = DVec3::new(rng.range(-0.9, 0.9), rng.range(-0.9, 0.9), 0.0);
            (x, view_above(&mut rng, DVec3::Z, 0.2))
        })
        .collect();
    let fresh: Vec<DVec3> = pts
        .iter()
        .map(|&(x, v)| {
            let mut ctx = ShadeContext::new();
            scene.shade_in(&mut ctx, x, DVec3::Z, v, &m).unwrap()
        })
        .collect();
    let (first, _) = allocations(|| scene.shade(pts[0].0, DVec3::Z, pts[0].1, &m));
    assert_eq!(first.unwrap(), fresh[0]);
    let mut later = 0;
    for (k, &(x, v)) in pts.iter().enumerate() {
        let (a, n) = allocations(|| scene.shade(x, DVec3::Z, v, &m));
        assert_eq!(a.unwrap(), fresh[k], "{x}");
        later += n;
    }
    assert_eq!(later, 0, "allocations after the thread's first call");
    // The points reach the overlay: a fresh context allocates there.
    let (_, n) = allocations(|| {
        let mut ctx = ShadeContext::new();
        scene.shade_in(&mut ctx, pts[0].0, DVec3::Z, pts[0].1, &m)
    });
    assert!(n > 0, "no scratch storage was needed");
    // Another thread: its own context, the same values.
    let other: Vec<DVec3> = std::thread::scope(|s| {
        s.spawn(|| {
            pts.iter()
                .map(|&(x, v)| scene.shade(x, DVec3::Z, v, &m).unwrap())
                .collect()
        })
        .join()
        .unwrap()
    });
    assert_eq!(other, fresh);
}
