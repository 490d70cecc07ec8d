//! Fits the GGX LTC tables and rewrites `src/ltc/table_data.rs`.
//!
//! ```text
//! cargo run --release --features fit --example fit_ltc [-- --no-reference] [--out PATH] [--size N]
//! ```
//!
//! Also fits a reproduction of the public reference fit (unless `--no-reference`) and prints, for
//! both tables, the shading error at random (view, roughness) points, the error of LTC shading of
//! random quad lights against brute force, and per-cell diagnostics. `--size N` fits an N x N grid
//! (for experiments; write it elsewhere with `--out`). With `FIT_LTC_MAP=1` it also prints the
//! per-cell error map (rows: roughness nodes, smooth at the bottom; columns: view nodes).

use std::time::Instant;

use arealight::ltc::fit::{
    FitConfig, FitMode, FittedTable, fit_ggx, quad_shading_errors, shading_error,
};

const COMMAND: &str = "cargo run --release --features fit --example fit_ltc";

fn percentile(sorted: &[f64], p: f64) -> f64 {
    let i = ((sorted.len() - 1) as f64 * p).round() as usize;
    sorted[i]
}

/// Shading error (relative L1) at `count` random points: theta uniform in [0, 85] degrees,
/// alpha = r^2 with r uniform in [0.05, 1] (fixed seed, the same points for every table).
fn evaluate(name: &str, fitted: &FittedTable, count: usize) {
    let mut state = 0x1234_5678_9abc_def0u64;
    let mut next = || {
        state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (state >> 11) as f64 / (1u64 << 53) as f64
    };
    let mut errs = Vec::with_capacity(count);
    for i in 0..count {
        let theta = next() * 85f64.to_radians();
        let r = 0.05 + 0.95 * next();
        let e = shading_error(fitted.table(), theta.cos(), r * r, 64, i as u64).unwrap_or(f64::NAN);
        errs.push(e);
    }
    errs.sort_by(f64::total_cmp);
    println!(
        "{name}: shading L1/albedo over {count} random points: median {:.4} p90 {:.4} max {:.4}",
        percentile(&errs, 0.5),
        percentile(&errs, 0.9),
        errs[count - 1]
    );
    let (nv, nr) = (
        fitted.table().view_nodes(),
        fitted.table().roughness_nodes(),
    );
    if std::env::var_os("FIT_LTC_MAP").is_some() {
        for k in (0..nr).rev() {
            let row: Vec<String> = (0..nv)
                .map(|j| format!("{:.3}", fitted.cell_errors()[k * nv + j].min(9.999)))
                .collect();
            println!("  k={k:2} {}", row.join(" "));
        }
    }
    match quad_shading_errors(fitted.table(), 300, 256, 7) {
        Ok(mut q) => {
            q.sort_by(f64::total_cmp);
            println!(
                "{name}: random quads |LTC - brute force| / albedo over {}: median {:.4}% p90 {:.4}% max {:.3}%",
                q.len(),
                100.0 * percentile(&q, 0.5),
                100.0 * percentile(&q, 0.9),
                100.0 * q[q.len() - 1]
            );
        }
        Err(e) => println!("{name}: quad evaluation failed: {e}"),
    }
    println!(
        "{name}: cells improved by each neighbour-restart pass: {:?}",
        fitted.refinements()
    );
    // Spikes: cells whose error exceeds 1.5 x the worst of their 4 neighbours (plus 1e-3).
    let e = fitted.cell_errors();
    let spikes = (0..nv * nr)
        .filter(|&i| {
            let (k, j) = (i / nv, i % nv);
            let mut worst: f64 = 0.0;
            for (dk, dj) in [(-1i64, 0i64), (1, 0), (0, -1), (0, 1)] {
                let (kk, jj) = (k as i64 + dk, j as i64 + dj);
                if (0..nr as i64).contains(&kk) && (0..nv as i64).contains(&jj) {
                    worst = worst.max(e[kk as usize * nv + jj as usize]);
                }
            }
            e[i] > 1.5 * worst + 1e-3
        })
        .count();
    println!("{name}: cells with error > 1.5 x their worst neighbour's: {spikes}");
    let mut cells: Vec<f64> = fitted.cell_errors().to_vec();
    cells.sort_by(f64::total_cmp);
    println!(
        "{name}: per-cell objective: median {:.3e} p90 {:.3e} max {:.3e}",
        percentile(&cells, 0.5),
        percentile(&cells, 0.9),
        cells[cells.len() - 1]
    );
}

/// Shading error (relative L1) at `count` random grazing points: `cos_theta_v` log-uniform in
/// `[1e-4, 0.05]`, `alpha = r^2` with `r` uniform in `[0.01, sqrt(0.05)]` (near-mirror to
/// moderately glossy), fixed seed.
fn evaluate_grazing(name: &str, fitted: &FittedTable, count: usize) {
    let mut state = 0x0fed_cba9_8765_4321u64;
    let mut next = || {
        state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (state >> 11) as f64 / (1u64 << 53) as f64
    };
    let mut errs = Vec::with_capacity(count);
    for i in 0..count {
        let c = 1e-4 * 500f64.powf(next());
        let r = 0.01 + (0.05f64.sqrt() - 0.01) * next();
        let e = shading_error(fitted.table(), c, r * r, 64, i as u64).unwrap_or(f64::NAN);
        errs.push(e);
    }
    errs.sort_by(f64::total_cmp);
    println!(
        "{name}: grazing shading L1/albedo over {count} random points: median {:.4} p90 {:.4} max {:.4}",
        percentile(&errs, 0.5),
        percentile(&errs, 0.9),
        errs[count - 1]
    );
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let reference = !args.iter().any(|a| a == "--no-reference");
    let out = args
        .iter()
        .position(|a| a == "--out")
        .and_then(|i| args.get(i + 1).cloned())
        .unwrap_or_else(|| concat!(env!("CARGO_MANIFEST_DIR"), "/src/ltc/table_data.rs").into());

    let size = args
        .iter()
        .position(|a| a == "--size")
        .and_then(|i| args.get(i + 1)?.parse().ok())
        .unwrap_or(64);
    let cfg = FitConfig {
        size,
        ..FitConfig::new(FitMode::Arealight)
    };
    // Roughness nodes times view nodes (the uniform part and the grazing tail).
    let total = cfg.size * (cfg.size - 1 + if cfg.size >= 32 { 18 } else { 9 });
    let t0 = Instant::now();
    let ours = fit_ggx(&cfg, |d| {
        if d % 512 == 0 {
            eprintln!("  arealight fit: {d}/{total} cells");
        }
    });
    println!("arealight fit: {:.1} s", t0.elapsed().as_secs_f64());
    if let Err(e) = std::fs::write(&out, ours.to_source(COMMAND)) {
        eprintln!("cannot write {out}: {e}");
        std::process::exit(1);
    }
    println!("wrote {out}");
    evaluate("arealight", &ours, 400);
    evaluate_grazing("arealight", &ours, 200);

    if reference {
        let t1 = Instant::now();
        let refc = FitConfig {
            size,
            ..FitConfig::new(FitMode::Reference)
        };
        let theirs = fit_ggx(&refc, |d| {
            if d % 512 == 0 {
                eprintln!("  reference fit: {d}/{total} cells");
            }
        });
        println!(
            "reference-reproduction fit: {:.1} s",
            t1.elapsed().as_secs_f64()
        );
        evaluate("reference", &theirs, 400);
        evaluate_grazing("reference", &theirs, 200);
    }
}
