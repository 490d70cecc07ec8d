//! The lazy Pluecker-space backend (seed 002) against the clipping backend as occluder counts
//! grow: visible regions of one quad light for coherent tiles of shading points, on two
//! procedural scenes of about 10, 100, 1K, 10K and 100K triangles:
//!
//! - `terrain`: a rough height field of `2 m^2` triangles (in 8 x 8-cell chunks, one mesh each)
//!   under a quad light low on one side; tiles are terrain triangles, shaded at random points;
//! - `boxes`: a `g x g` grid of random boxes (12 triangles each, convex) on the ground under a
//!   quad light; tiles are squares of the ground between the boxes (side 1/16, 8 x 8 points).
//!
//! Per scene and size, four ways to answer the same queries (`Throughput::Elements` = queries,
//! so criterion reports queries per second):
//!
//! - `clip`: `ClipVisibility::visible_region` (silhouettes and spherical set operations);
//! - `plucker_call`: `Visibility::visible_region` of `PluckerVisibility`, a tree per query;
//! - `plucker_reuse`: `visible_region_in` with a fresh `PluckerContext` per iteration, trees
//!   reused within each tile (seed 002 Alg. 2);
//! - `plucker_reset`: the same context with reuse off, every query from its tile's root (seed
//!   002 section 5.1's "modified version").
//!
//! Each iteration answers 4 tiles of 64 queries, tiles chosen where their middle point is in
//! penumbra (between 2% and 98% of the light visible; after 2000 candidates any tile). The context's tree statistics per scene and
//! size are printed once to stderr. Results in BENCHMARKS.md (section `plucker`).
//!
//! ```sh
//! cargo bench -p arealight-benches --bench plucker                      # all
//! cargo bench -p arealight-benches --bench plucker -- 'boxes/.*/10092'  # one size
//! ```
//!
//! On a loaded machine, count instructions of one pass instead (see `one_pass`).

use arealight::glam::DVec3;
use arealight::shade::{Body, ConvexPolyhedron, Light, Scene, ShadingFrame, TriangleMesh};
use arealight::visibility::Visibility;
use arealight::visibility::plucker::{PluckerContext, PluckerVisibility};
use criterion::{BenchmarkId, Criterion, Throughput, criterion_group};
use std::hint::black_box;
use std::time::Duration;

#[path = "../tests/support/mod.rs"]
mod support;

use support::Rng;

/// Tiles per iteration and queries per tile.
const TILES: usize = 4;
const PER_TILE: usize = 64;

/// A scene, its coherent queries (tile after tile) and the context's cell size.
struct Case {
    scene: Scene,
    frames: Vec<ShadingFrame>,
    cell: f64,
    triangles: usize,
}

/// Height of the terrain: two broad waves, a finer one and per-vertex noise, so that shadows
/// appear at every scale.
fn height(x: f64, y: f64, noise: f64) -> f64 {
    0.6 * ((1.7 * x).sin() * (1.3 * y).cos() + 0.5 * (3.1 * x + 0.7).sin() * (2.3 * y).sin())
        + 0.15 * (7.3 * x + 1.1).sin() * (6.1 * y + 0.3).cos()
        + noise
}

/// Whether the frame's point sees part, not all nor none, of light 0 (so that the tiles are
/// where shadows are computed, not where every backend answers at once).
fn penumbra(pl: &PluckerVisibility<Light>, f: &ShadingFrame) -> bool {
    let area = |p: Vec<arealight::sphere::SphericalPolygon>| -> f64 {
        p.iter().map(|q| q.solid_angle()).sum()
    };
    let (v, u) = (
        area(pl.visible_region(0, f).unwrap()),
        area(pl.unoccluded_region(0, f).unwrap()),
    );
    v > 0.02 * u && v < 0.98 * u
}

fn terrain(m: usize) -> Case {
    let (s, step) = (4.0, 8.0 / m as f64);
    let mut rng = Rng::new(11);
    let mut z = vec![0.0; (m + 1) * (m + 1)];
    for (k, h) in z.iter_mut().enumerate() {
        let (i, j) = (k / (m + 1), k % (m + 1));
        let (x, y) = (-s + i as f64 * step, -s + j as f64 * step);
        *h = height(x, y, 0.3 * step * (rng.f64() - 0.5));
    }
    let p = |i: usize, j: usize| {
        DVec3::new(
            -s + i as f64 * step,
            -s + j as f64 * step,
            z[i * (m + 1) + j],
        )
    };
    let chunk = 8;
    let mut bodies = Vec::new();
    let mut tris = Vec::new();
    for ci in (0..m).step_by(chunk) {
        for cj in (0..m).step_by(chunk) {
            let (ni, nj) = (chunk.min(m - ci), chunk.min(m - cj));
            let mut verts = Vec::new();
            for i in 0..=ni {
                for j in 0..=nj {
                    verts.push(p(ci + i, cj + j));
                }
            }
            let id = |i: usize, j: usize| (i * (nj + 1) + j) as u32;
            let mut idx = Vec::new();
            for i in 0..ni {
                for j in 0..nj {
                    idx.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)]);
                    idx.push([id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
                }
            }
            let mesh = TriangleMesh::new(verts, idx).unwrap();
            for t in 0..mesh.triangle_count() {
                tris.push((mesh.triangle_normal(t), mesh.triangle(t)));
            }
            bodies.push(Body::Mesh(mesh));
        }
    }
    let light_centre = DVec3::new(2.2, 0.3, 1.9);
    let light = TriangleMesh::quad(light_centre, DVec3::Y * 0.4, DVec3::X * 0.4);
    let scene = Scene::new(
        vec![Light::new(light.unwrap(), DVec3::ONE).unwrap()],
        bodies,
    )
    .unwrap();
    let pl = PluckerVisibility::from_clip(scene.visibility().clone());
    let mut frames = Vec::new();
    let mut rng = Rng::new(7);
    let mut tries = 0;
    while frames.len() < TILES * PER_TILE {
        let (n, [a, b, c]) = tris[rng.below(tris.len())];
        let centre = (a + b + c) / 3.0;
        let near = 1.5 + step;
        if centre.x.abs() > near || centre.y.abs() > near || (light_centre - a).dot(n) <= 0.0 {
            continue;
        }
        tries += 1;
        if tries < 2000 && !penumbra(&pl, &ShadingFrame::new(centre, n, n).unwrap()) {
            continue;
        }
        for _ in 0..PER_TILE {
            let (mut u, mut w) = (rng.f64(), rng.f64());
            if u + w > 1.0 {
                (u, w) = (1.0 - u, 1.0 - w);
            }
            frames.push(ShadingFrame::new(a + (b - a) * u + (c - a) * w, n, n).unwrap());
        }
    }
    Case {
        scene,
        frames,
        cell: 2.0 * step,
        triangles: 2 * m * m,
    }
}

fn boxes(g: usize) -> Case {
    let (s, cell) = (4.0, 8.0 / g as f64);
    let mut rng = Rng::new(5);
    let mut bodies = Vec::new();
    let mut feet = Vec::new();
    for i in 0..g {
        for j in 0..g {
            let c = DVec3::new(
                -s + (i as f64 + 0.5) * cell,
                -s + (j as f64 + 0.5) * cell,
                0.0,
            );
            let h = DVec3::new(
                cell * (0.1 + 0.25 * rng.f64()),
                cell * (0.1 + 0.25 * rng.f64()),
                (cell * (0.2 + 0.6 * rng.f64())).min(0.8),
            );
            let at = c + DVec3::new(0.0, 0.0, h.z);
            feet.push((at, h));
            bodies.push(ConvexPolyhedron::cuboid(at, h).unwrap().into());
        }
    }
    let light = TriangleMesh::quad(DVec3::new(0.3, 0.2, 3.0), DVec3::Y * 0.5, DVec3::X * 0.5);
    let scene = Scene::new(
        vec![Light::new(light.unwrap(), DVec3::ONE).unwrap()],
        bodies,
    )
    .unwrap();
    let pl = PluckerVisibility::from_clip(scene.visibility().clone());
    // Ground tiles of side 1/16 (a tile of 8 x 8 pixels at 1024 pixels per 8 units), points
    // in scanline order, none under a box.
    let t = 0.0625;
    let mut frames = Vec::new();
    let mut rng = Rng::new(7);
    let side = (PER_TILE as f64).sqrt() as usize;
    let mut tries = 0;
    while frames.len() < TILES * PER_TILE {
        let c = DVec3::new(rng.f64() * 7.0 - 3.5, rng.f64() * 7.0 - 3.5, 0.0);
        let c = (c / t).floor() * t;
        let tile: Vec<ShadingFrame> = (0..PER_TILE)
            .map(|k| {
                let (i, j) = (k / side, k % side);
                let x =
                    c + DVec3::new((i as f64 + 0.5) * t, (j as f64 + 0.5) * t, 0.0) / side as f64;
                ShadingFrame::new(x, DVec3::Z, DVec3::Z).unwrap()
            })
            .collect();
        let under = |f: &ShadingFrame| {
            let x = f.origin();
            feet.iter()
                .any(|&(a, h)| (x.x - a.x).abs() <= h.x && (x.y - a.y).abs() <= h.y)
        };
        tries += 1;
        if !tile.iter().any(under) && (tries >= 2000 || penumbra(&pl, &tile[PER_TILE / 2])) {
            frames.extend(tile);
        }
    }
    Case {
        scene,
        frames,
        cell: t,
        triangles: 12 * g * g,
    }
}

fn run(c: &mut Criterion, name: &str, cases: Vec<Case>) {
    let mut group = c.benchmark_group(format!("plucker/{name}"));
    group.throughput(Throughput::Elements((TILES * PER_TILE) as u64));
    for case in &cases {
        let Case {
            scene,
            frames,
            cell,
            triangles,
        } = case;
        let clip = scene.visibility();
        let pl = PluckerVisibility::from_clip(clip.clone());
        let big = *triangles > 20_000;
        group.sample_size(10);
        group.warm_up_time(Duration::from_millis(if big { 500 } else { 1000 }));
        group.measurement_time(Duration::from_secs(if big { 4 } else { 2 }));
        // The tree statistics of one pass, and how much of the light the queries see.
        let mut ctx = PluckerContext::new(*cell).unwrap();
        let (mut lit, mut dark) = (0, 0);
        for f in frames {
            let v: f64 = pl
                .visible_region_in(&mut ctx, 0, f)
                .unwrap()
                .iter()
                .map(|p| p.solid_angle())
                .sum();
            let u: f64 = pl
                .unoccluded_region(0, f)
                .unwrap()
                .iter()
                .map(|p| p.solid_angle())
                .sum();
            lit += usize::from(v >= u * (1.0 - 1e-9));
            dark += usize::from(v <= u * 1e-9);
        }
        let s = ctx.stats();
        eprintln!(
            "{name} {triangles}: {} queries ({lit} lit, {dark} dark, the rest penumbra); \
             {} trees, at most {} occluders, peak tree {} nodes / {} KiB, {} KiB cached at \
             most; {:.1} fragments per query",
            s.queries,
            s.trees_built,
            s.max_tree_occluders,
            s.peak_tree_nodes,
            s.peak_tree_bytes / 1024,
            s.peak_cached_bytes / 1024,
            s.fragments as f64 / s.queries as f64,
        );
        // The clipping backend may give up (`Undecidable`) on a few terrain points (the sphere
        // layer's horizon clip, tests/visibility_backend_regressions.rs); a give-up is timed as an
        // answer.
        let gave_up = frames
            .iter()
            .filter(|f| clip.visible_region(0, f).is_err())
            .count();
        if gave_up > 0 {
            eprintln!("{name} {triangles}: the clipping backend gives up on {gave_up} queries");
        }
        group.bench_with_input(BenchmarkId::new("clip", triangles), frames, |b, fr| {
            b.iter(|| {
                for f in fr {
                    let _ = black_box(clip.visible_region(0, f));
                }
            })
        });
        group.bench_with_input(
            BenchmarkId::new("plucker_call", triangles),
            frames,
            |b, fr| {
                b.iter(|| {
                    for f in fr {
                        black_box(pl.visible_region(0, f).unwrap());
                    }
                })
            },
        );
        for (id, reuse) in [("plucker_reuse", true), ("plucker_reset", false)] {
            group.bench_with_input(BenchmarkId::new(id, triangles), frames, |b, fr| {
                b.iter(|| {
                    let mut ctx = PluckerContext::new(*cell).unwrap().with_reuse(reuse);
                    for f in fr {
                        black_box(pl.visible_region_in(&mut ctx, 0, f).unwrap());
                    }
                })
            });
        }
    }
    group.finish();
}

/// The scene sizes: terrain `m` (`2 m^2` triangles) and boxes `g` (`12 g^2`).
const TERRAIN: [usize; 5] = [2, 7, 22, 71, 224];
const BOXES: [usize; 5] = [1, 3, 9, 29, 91];

fn scale(c: &mut Criterion) {
    run(c, "terrain", TERRAIN.map(terrain).into());
    run(c, "boxes", BOXES.map(boxes).into());
}

/// One pass of one variant, for counting instructions on a machine too loaded for timings:
/// `PLUCKER_ONE_PASS=<terrain|boxes>/<variant>/<index 0..5> valgrind --tool=callgrind
/// target/release/deps/plucker-<hash>` (the scene is built either way; callgrind's
/// `--toggle-collect` is not needed: subtract the count of the variant `none`). With
/// `PLUCKER_BUDGET=<bytes>` the context of the `plucker_reuse` and `plucker_reset` variants has
/// that budget; with `PLUCKER_CELL_SCALE=<factor>` its cells are that factor times the scene's
/// (the tile size against the occluders per tree, BENCHMARKS.md).
fn one_pass(spec: &str) {
    let parts: Vec<&str> = spec.split('/').collect();
    let [scene, variant, index] = parts[..] else {
        panic!("PLUCKER_ONE_PASS: expected scene/variant/index, got {spec}");
    };
    let i: usize = index.parse().expect("PLUCKER_ONE_PASS: index");
    let case = match scene {
        "terrain" => terrain(TERRAIN[i]),
        "boxes" => boxes(BOXES[i]),
        _ => panic!("PLUCKER_ONE_PASS: scene {scene}"),
    };
    let clip = case.scene.visibility();
    let pl = PluckerVisibility::from_clip(clip.clone());
    // PLUCKER_CELL_SCALE=<factor>: cells that factor times the scene's.
    let scale: f64 = std::env::var("PLUCKER_CELL_SCALE")
        .ok()
        .and_then(|b| b.parse().ok())
        .unwrap_or(1.0);
    let mut ctx = PluckerContext::new(case.cell * scale)
        .unwrap()
        .with_reuse(variant != "plucker_reset");
    // PLUCKER_BUDGET=<bytes>: the context's budget (what the memory cap does).
    if let Some(b) = std::env::var("PLUCKER_BUDGET")
        .ok()
        .and_then(|b| b.parse().ok())
    {
        ctx = ctx.with_budget(b);
    }
    pass(variant, clip, &pl, &mut ctx, &case.frames);
    eprintln!("{spec}: {} queries, {:?}", case.frames.len(), ctx.stats());
}

/// The queries of one pass, apart so that callgrind can count them alone
/// (`--collect-atstart=no --toggle-collect='plucker::pass*'`).
#[inline(never)]
fn pass(
    variant: &str,
    clip: &arealight::visibility::ClipVisibility<Light>,
    pl: &PluckerVisibility<Light>,
    ctx: &mut PluckerContext,
    frames: &[ShadingFrame],
) {
    for f in frames {
        match variant {
            "none" => {}
            "clip" => drop(black_box(clip.visible_region(0, f))),
            "plucker_call" => drop(black_box(pl.visible_region(0, f).unwrap())),
            "plucker_reuse" | "plucker_reset" => {
                drop(black_box(pl.visible_region_in(ctx, 0, f).unwrap()))
            }
            _ => panic!("PLUCKER_ONE_PASS: variant {variant}"),
        }
    }
}

criterion_group!(benches, scale);

fn main() {
    match std::env::var("PLUCKER_ONE_PASS") {
        Ok(spec) => one_pass(&spec),
        Err(_) => {
            benches();
            Criterion::default().configure_from_args().final_summary();
        }
    }
}
