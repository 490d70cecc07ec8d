//! The LTC table fitter (feature `fit`): fits the GGX tables that `table_data.rs` ships.
//!
//! Run it with `cargo run --release --features fit --example fit_ltc`; it rewrites
//! `src/ltc/table_data.rs`. The procedure follows \[HDHN16\] §4 with the refinements of the public
//! implementation, and one change of objective:
//!
//! 1. For each cell (view cosine, roughness) of the grid, estimate the directional albedo `A`, the
//!    Fresnel weight and the average direction `Z` of the cosine-weighted BRDF `f cos` with
//!    stratified visible-normal samples (\[Hei18\]). `Z` lies in the xz-plane; `X = Y x Z`, `Y = y`.
//! 2. Parameterise the LTC in the frame of `Z`: `M = [X Y Z] S` with
//!    `S = [[m11, 0, m13], [0, m22, 0], [m31, 0, 1]]`, optimised as `ln m11`, `ln m22`, `m13`
//!    (and `m31`), so that the simplex adapts to lobes of any width down to `alpha = 1e-4`. The
//!    reference fit keeps `m31 = 0` (three parameters); ours frees it, which is the fourth degree
//!    of freedom of \[HDHN16\] §4 (`M = [[a, 0, b], [0, c, 0], [d, 0, 1]]`) expressed in the
//!    frame of the average direction.
//! 3. Minimise a sampled error between the LTC and `f cos / A` with Nelder–Mead, warm-started from
//!    the neighbouring cell. The error is estimated by multiple importance sampling (balance
//!    heuristic) with a fixed stratified set of uniform numbers pushed through both the BRDF
//!    sampler and the LTC sampler, so that it is a deterministic function of the parameters.
//!
//! Two objectives are available ([`FitMode`]):
//!
//! - [`FitMode::Arealight`] (the shipped table): the L1 distance `integral |q - p| dw` between the
//!   normalised BRDF `p = f cos / A` and the LTC *clipped to the upper hemisphere and renormalised*,
//!   `q = D [z > 0] / h` with `h` its upper-hemisphere mass. Shading only ever sees the clipped
//!   LTC scaled by `norm = A / h`, and the L1 distance bounds the shading error of every light
//!   polygon at once: `|integral over P of (q - p)| <= L1 / 2` for any region `P`. The grid is
//!   uniform in `sqrt(alpha)` from `alpha = 1e-4` and in `sqrt(1 - cos theta)` down to
//!   `cos theta = 1e-3`.
//! - [`FitMode::Reference`]: a straightforward reproduction of the public implementation's fit,
//!   for comparison: the cubed error `integral |f cos - A D|^3 / (pdf_brdf + pdf_ltc)` of the
//!   unclipped LTC scaled by `norm = A`, on the grid `alpha = max(r^2, 1e-4)` with `r` uniform
//!   from 0 and `theta = min(acos(1 - x^2), 1.57)`.
//!
//! After the warm-started sweep, refinement passes re-start the optimiser in each cell from each
//! neighbour's solution when that is better there, until a pass changes nothing, so that no cell
//! (in particular at `alpha -> 0` or at grazing angles) is left in a worse local minimum than its
//! neighbours ([`FittedTable::refinements`] reports the passes).
//!
//! # References
//!
//! - \[HDHN16\] E. Heitz, J. Dupuy, S. Hill, D. Neubelt. *Real-time polygonal-light shading with
//!   linearly transformed cosines.* ACM TOG 35(4), 2016.
//! - \[Hei18\] E. Heitz. *Sampling the GGX distribution of visible normals.* JCGT 7(4), 2018.
//! - \[NM65\] J. A. Nelder, R. Mead. *A simplex method for function minimization.* The Computer
//!   Journal 7(4), 1965.

use std::fmt::Write as _;
use std::string::String;
use std::vec;
use std::vec::Vec;

use glam::{DMat3, DVec2, DVec3};

use super::distribution::Ltc;
use super::ggx::{ggx_brdf_cos, ggx_sample_vndf, ggx_vndf_pdf, ggx_vndf_weight};
use super::table::{CHANNELS, Channel, Grid, LtcTable};
use crate::GeomError;

/// Which objective and grid to fit; see the [module documentation](self).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FitMode {
    /// This crate's fit: L1 error of the horizon-clipped, renormalised LTC; the shipped table.
    Arealight,
    /// Reproduction of the public reference fit (cubed error, unclipped LTC, reference grid).
    Reference,
}

impl FitMode {
    /// Number of free LTC parameters.
    fn dims(self) -> usize {
        match self {
            FitMode::Arealight => 4,
            FitMode::Reference => 3,
        }
    }

    /// The grid for `n` roughness nodes: for [`FitMode::Arealight`], `n - 1` uniform view nodes
    /// down to `cos = 1/32`, then a tail uniform in `ln(cos)` down to `2^-14` (two nodes per
    /// halving for `n >= 32`, one below); for [`FitMode::Reference`], `n` uniform view nodes.
    fn grid(self, n: usize) -> Grid {
        match self {
            FitMode::Arealight => {
                let steps = if n >= 32 { 2 } else { 1 };
                let knee = n - 2;
                let tail = 9 * steps;
                let (cos_knee, cos_min) = (1.0 / 32.0, 1.0 / 16384.0);
                Grid::new(
                    knee + 1 + tail,
                    knee,
                    cos_knee,
                    steps,
                    cos_min,
                    n,
                    1e-4,
                    false,
                )
            }
            FitMode::Reference => {
                let c = 1.57f64.cos();
                Grid::new(n, n - 1, c, 1, c, n, 1e-4, true)
            }
        }
    }
}

/// Fitter settings.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct FitConfig {
    /// Objective and grid.
    pub mode: FitMode,
    /// Nodes per axis (the shipped table uses 64).
    pub size: usize,
    /// Stratified samples per axis for each sampler in the objective (`n^2` BRDF samples plus
    /// `n^2` LTC samples per evaluation).
    pub samples: usize,
    /// Worker threads.
    pub threads: usize,
}

impl FitConfig {
    /// The settings that produced the shipped table (for [`FitMode::Arealight`]) or the
    /// comparison table (for [`FitMode::Reference`]): 64 x 64 cells, 32 x 32 samples per sampler,
    /// two threads.
    #[must_use]
    pub fn new(mode: FitMode) -> Self {
        Self {
            mode,
            size: 64,
            samples: 32,
            threads: 2,
        }
    }
}

/// The result of a fit: the table and per-cell diagnostics.
#[derive(Debug, Clone)]
pub struct FittedTable {
    mode: FitMode,
    table: LtcTable,
    /// `(ln m11, ln m22, m13, m31)` per cell, `k * n_view + j` order.
    params: Vec<Params>,
    /// Final objective value per cell.
    errors: Vec<f64>,
    /// Cells improved by each refinement pass.
    refinements: Vec<usize>,
}

impl FittedTable {
    /// The fitted table, ready for lookups.
    #[must_use]
    pub fn table(&self) -> &LtcTable {
        &self.table
    }

    /// The final objective value of each cell, indexed `k * n_view + j` (roughness node `k`, view
    /// node `j`, `n_view` = [`LtcTable::view_nodes`]). For [`FitMode::Arealight`] this is the L1
    /// distance described in the module docs.
    #[must_use]
    pub fn cell_errors(&self) -> &[f64] {
        &self.errors
    }

    /// The fitted `(ln m11, ln m22, m13, m31)` of each cell, indexed like [`Self::cell_errors`].
    #[must_use]
    pub fn cell_params(&self) -> &[[f64; 4]] {
        &self.params
    }

    /// The number of cells that each refinement pass improved by restarting from a neighbour's
    /// solution. A final `0` means that no cell is fitted worse than a neighbour's parameters
    /// would fit it (the passes stop there, or after a fixed maximum of passes).
    #[must_use]
    pub fn refinements(&self) -> &[usize] {
        &self.refinements
    }

    /// Rust source for `table_data.rs`: the grid's constants and plain `pub(crate) const` arrays,
    /// one per channel.
    #[must_use]
    pub fn to_source(&self, command: &str) -> String {
        let g = self.table.grid();
        let mut s = String::new();
        let _ = writeln!(s, "// @generated by `{command}`; do not edit.");
        let _ = writeln!(
            s,
            "// GGX (height-correlated Smith) LTC table, fit mode {:?}: {} x {} nodes, index",
            self.mode, g.n_view, g.n_rough
        );
        let _ = writeln!(
            s,
            "// k * VIEW_NODES + j (roughness node k, uniform in sqrt(alpha) over [ALPHA_MIN, 1]; view"
        );
        let _ = writeln!(
            s,
            "// node j, uniform in sqrt(1 - cos theta) from 1 to COS_KNEE at node KNEE, then uniform in"
        );
        let _ = writeln!(
            s,
            "// ln(cos theta), TAIL_STEPS per halving, down to COS_MIN). M^-1 is scaled so that its"
        );
        let _ = writeln!(s, "// first row (M_INV_00, 0, M_INV_02) is a unit vector.");
        let _ = writeln!(s, "pub(crate) const VIEW_NODES: usize = {};", g.n_view);
        let _ = writeln!(s, "pub(crate) const ROUGH_NODES: usize = {};", g.n_rough);
        let _ = writeln!(s, "pub(crate) const KNEE: usize = {};", g.knee);
        let _ = writeln!(s, "pub(crate) const COS_KNEE: f64 = {:e};", g.cos_knee);
        let _ = writeln!(s, "pub(crate) const TAIL_STEPS: usize = {};", g.tail_steps);
        let _ = writeln!(s, "pub(crate) const COS_MIN: f64 = {:e};", g.cos_min);
        let _ = writeln!(s, "pub(crate) const ALPHA_MIN: f64 = {:e};", g.alpha_min);
        for (ch, name) in Channel::ALL {
            let vals: Vec<f64> = self.table.channel(ch as usize).collect();
            let _ = writeln!(s, "pub(crate) const {name}: [f64; {}] = [", vals.len());
            for row in vals.chunks(8) {
                s.push_str("    ");
                for v in row {
                    let _ = write!(s, "{v:.10e}, ");
                }
                s.pop();
                s.push('\n');
            }
            s.push_str("];\n");
        }
        s
    }
}

/// Per-cell BRDF statistics and the fixed BRDF samples of the objective.
struct Cell {
    v: DVec3,
    alpha: f64,
    albedo: f64,
    fresnel: f64,
    /// Frame of the average direction: columns X, Y, Z.
    frame: DMat3,
    /// BRDF samples: direction, `f cos`, VNDF pdf.
    brdf: Vec<(DVec3, f64, f64)>,
}

fn stratified(n: usize) -> Vec<DVec2> {
    let mut u = Vec::with_capacity(n * n);
    for i in 0..n {
        for j in 0..n {
            u.push(DVec2::new(
                (i as f64 + 0.5) / n as f64,
                (j as f64 + 0.5) / n as f64,
            ));
        }
    }
    u
}

impl Cell {
    fn new(cos_theta: f64, alpha: f64, us: &[DVec2], stats: &[DVec2]) -> Self {
        let c = cos_theta.clamp(0.0, 1.0);
        let v = DVec3::new((1.0 - c * c).max(0.0).sqrt(), 0.0, c);
        // Albedo, Fresnel weight and average direction by VNDF sampling: weight f cos / pdf.
        let (mut a, mut fr, mut dir) = (0.0, 0.0, DVec3::ZERO);
        for (l, w) in stats.iter().filter_map(|&u| ggx_vndf_weight(v, alpha, u)) {
            let h = (v + l).normalize();
            a += w;
            fr += w * (1.0 - v.dot(h).clamp(0.0, 1.0)).powi(5);
            dir += w * l;
        }
        let m = stats.len() as f64;
        let albedo = a / m;
        let fresnel = if a > 0.0 { fr / a } else { 0.0 };
        let z = DVec3::new(dir.x, 0.0, dir.z).normalize_or(DVec3::Z);
        let x = DVec3::new(z.z, 0.0, -z.x);
        let frame = DMat3::from_cols(x, DVec3::Y, z);
        let brdf = us
            .iter()
            .map(|&u| {
                let l = ggx_sample_vndf(v, alpha, u);
                (l, ggx_brdf_cos(v, l, alpha), ggx_vndf_pdf(v, l, alpha))
            })
            .collect();
        Self {
            v,
            alpha,
            albedo,
            fresnel,
            frame,
            brdf,
        }
    }

    fn matrix(&self, p: &Params) -> DMat3 {
        let s = DMat3::from_cols(
            DVec3::new(p[0].exp(), 0.0, p[3]),
            DVec3::new(0.0, p[1].exp(), 0.0),
            DVec3::new(p[2], 0.0, 1.0),
        );
        self.frame * s
    }

    fn objective(&self, p: &Params, mode: FitMode, us: &[DVec2]) -> f64 {
        const BAD: f64 = 1e10;
        if !p.iter().all(|x| x.is_finite()) || p[0].abs() > 30.0 || p[1].abs() > 30.0 {
            return BAD;
        }
        let Ok(ltc) = Ltc::new(self.matrix(p)) else {
            return BAD;
        };
        let a = self.albedo;
        let n = us.len() as f64;
        let mut err = 0.0;
        match mode {
            FitMode::Arealight => {
                // The lobe's axis above the horizon (`M^-1[0][0] > 0`, `M^-1[2][2] > 0`, a
                // positive determinant), so that interpolating between nodes never turns it
                // under the horizon (`table.rs`; `tests/ltc_robust.rs` checks every cell).
                let mi = ltc.inverse();
                if !(mi.x_axis.x > 0.0 && mi.z_axis.z > 0.0 && mi.determinant() > 0.0) {
                    return BAD;
                }
                let h = ltc.upper_hemisphere_mass();
                if h.is_nan() || h <= 1e-6 {
                    return BAD;
                }
                let term = |fc: f64, d: f64, pdf: f64, up: bool| {
                    let q = if up { d / h } else { 0.0 };
                    let denom = pdf + d;
                    if denom > 0.0 {
                        (q - fc / a).abs() / denom
                    } else {
                        0.0
                    }
                };
                for &(l, fc, pdf) in &self.brdf {
                    err += term(fc, ltc.density(l), pdf, l.z > 0.0);
                }
                for &u in us {
                    let l = ltc.sample(u);
                    if l.z <= 0.0 {
                        continue;
                    }
                    let fc = ggx_brdf_cos(self.v, l, self.alpha);
                    err += term(
                        fc,
                        ltc.density(l),
                        ggx_vndf_pdf(self.v, l, self.alpha),
                        true,
                    );
                }
            }
            FitMode::Reference => {
                let term = |fc: f64, d: f64, pdf: f64| {
                    let e = (fc - a * d).abs();
                    let denom = pdf + d;
                    if denom > 0.0 { e * e * e / denom } else { 0.0 }
                };
                for &(l, fc, pdf) in &self.brdf {
                    err += term(fc, ltc.density(l), pdf);
                }
                for &u in us {
                    let l = ltc.sample(u);
                    let fc = ggx_brdf_cos(self.v, l, self.alpha);
                    err += term(fc, ltc.density(l), ggx_vndf_pdf(self.v, l, self.alpha));
                }
            }
        }
        err / n
    }
}

/// Nelder–Mead \[NM65\] in `D` dimensions with the standard coefficients (reflection 1, expansion
/// 2, contraction 1/2, shrink 1/2); returns the best point and value.
fn nelder_mead<const D: usize>(
    f: &dyn Fn(&[f64; D]) -> f64,
    x0: [f64; D],
    step: [f64; D],
    max_evals: usize,
) -> ([f64; D], f64) {
    let mut pts: Vec<[f64; D]> = vec![x0; D + 1];
    for i in 0..D {
        pts[i + 1][i] += step[i];
    }
    let mut vals: Vec<f64> = pts.iter().map(f).collect();
    let mut evals = D + 1;
    let lerp = |a: &[f64; D], b: &[f64; D], t: f64| -> [f64; D] {
        core::array::from_fn(|i| a[i] + t * (b[i] - a[i]))
    };
    while evals < max_evals {
        let mut idx: Vec<usize> = (0..=D).collect();
        idx.sort_by(|&a, &b| vals[a].total_cmp(&vals[b]));
        pts = idx.iter().map(|&i| pts[i]).collect();
        vals = idx.iter().map(|&i| vals[i]).collect();
        if vals[D] - vals[0] <= 1e-9 * vals[0].abs() + 1e-14 {
            break;
        }
        // Centroid of all but the worst point.
        let c: [f64; D] =
            core::array::from_fn(|i| pts[..D].iter().map(|p| p[i]).sum::<f64>() / D as f64);
        let xr = lerp(&c, &pts[D], -1.0);
        let fr = f(&xr);
        evals += 1;
        if fr < vals[0] {
            let xe = lerp(&c, &pts[D], -2.0);
            let fe = f(&xe);
            evals += 1;
            (pts[D], vals[D]) = if fe < fr { (xe, fe) } else { (xr, fr) };
        } else if fr < vals[D - 1] {
            (pts[D], vals[D]) = (xr, fr);
        } else {
            // Outside contraction if the reflection beat the worst point, inside otherwise.
            let xc = if fr < vals[D] {
                lerp(&c, &xr, 0.5)
            } else {
                lerp(&c, &pts[D], 0.5)
            };
            let fc = f(&xc);
            evals += 1;
            if fc < vals[D].min(fr) {
                (pts[D], vals[D]) = (xc, fc);
            } else {
                for i in 1..=D {
                    pts[i] = lerp(&pts[0], &pts[i], 0.5);
                    vals[i] = f(&pts[i]);
                }
                evals += D;
            }
        }
    }
    let best = (0..=D)
        .min_by(|&a, &b| vals[a].total_cmp(&vals[b]))
        .unwrap_or(0);
    (pts[best], vals[best])
}

/// The LTC parameters of a cell: `(ln m11, ln m22, m13, m31)`.
type Params = [f64; 4];

/// Optimises from `x0`, restarting the simplex at the best point until it stops improving. With
/// `dims == 3`, `m31` stays fixed (the reference parameterisation).
fn minimise(f: &dyn Fn(&Params) -> f64, x0: Params, dims: usize) -> (Params, f64) {
    let mut best = (x0, f(&x0));
    let mut scale = 0.2;
    for _ in 0..6 {
        let p = best.0;
        let s13 = scale * (0.5 * (p[0] + p[1])).exp();
        let r = if dims == 4 {
            nelder_mead::<4>(f, p, [scale, scale, s13, scale], 600)
        } else {
            let f3 = |q: &[f64; 3]| f(&[q[0], q[1], q[2], p[3]]);
            let (q, v) = nelder_mead::<3>(&f3, [p[0], p[1], p[2]], [scale, scale, s13], 400);
            ([q[0], q[1], q[2], p[3]], v)
        };
        let improved = r.1 < best.1 * (1.0 - 1e-6);
        if r.1 < best.1 {
            best = r;
        }
        if !improved {
            break;
        }
        scale *= 0.5;
    }
    best
}

/// Warm start from a neighbour at roughness `a_from`, for a cell at roughness `a_to`: the lobe
/// width scales roughly like alpha, so also try the neighbour's matrix scaled by the ratio.
fn warm_starts(p: Params, a_from: f64, a_to: f64) -> [Params; 2] {
    let r = a_to / a_from;
    let lr = r.ln();
    [p, [p[0] + lr, p[1] + lr, p[2] * r, p[3]]]
}

/// Upper bound on the refinement passes of [`fit_ggx`].
const MAX_REFINE_PASSES: usize = 6;

/// Fits a GGX LTC table; `progress` is called with the number of finished cell fits.
///
/// # Examples
///
/// ```no_run
/// use arealight::ltc::fit::{FitConfig, FitMode, fit_ggx};
/// let fitted = fit_ggx(&FitConfig::new(FitMode::Arealight), |_| {});
/// let source = fitted.to_source("cargo run --release --features fit --example fit_ltc");
/// assert!(source.contains("pub(crate) const NORM"));
/// ```
pub fn fit_ggx(cfg: &FitConfig, progress: impl Fn(usize) + Sync) -> FittedTable {
    let mode = cfg.mode;
    let dims = mode.dims();
    let grid = mode.grid(cfg.size.max(4));
    let (nv, nr, knee) = (grid.n_view, grid.n_rough, grid.knee);
    let us = stratified(cfg.samples.max(2));
    let stats = stratified(128);
    let threads = cfg.threads.max(1);
    let done = std::sync::atomic::AtomicUsize::new(0);
    let tick = || progress(done.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1);

    // Cells, built in parallel (column j = view node).
    let make_col = |j: usize| -> Vec<Cell> {
        (0..nr)
            .map(|k| Cell::new(grid.node_cos(j), grid.node_alpha(k), &us, &stats))
            .collect()
    };
    let cols: Vec<Vec<Cell>> = par_map(nv, threads, make_col);
    let cell = |k: usize, j: usize| &cols[j][k];
    let fit_from = |k: usize, j: usize, starts: &[Params]| -> (Params, f64) {
        let c = cell(k, j);
        let f = |p: &Params| c.objective(p, mode, &us);
        let x0 = starts
            .iter()
            .copied()
            .min_by(|a, b| f(a).total_cmp(&f(b)))
            .unwrap_or([0.0; 4]);
        tick();
        minimise(&f, x0, dims)
    };

    // Roughest row first, sequentially over the view angle.
    let mut top = Vec::with_capacity(nv);
    let mut prev = [0.0; 4];
    for j in 0..nv {
        let r = fit_from(nr - 1, j, &[prev]);
        prev = r.0;
        top.push(r);
    }

    // Then each view column of the uniform part downwards in roughness, warm-started from the
    // cell above.
    let col_fit = |j: usize| -> Vec<(Params, f64)> {
        let mut out = vec![([0.0; 4], 0.0); nr];
        out[nr - 1] = top[j];
        for k in (0..nr - 1).rev() {
            out[k] = fit_from(
                k,
                j,
                &warm_starts(out[k + 1].0, cell(k + 1, j).alpha, cell(k, j).alpha),
            );
        }
        out
    };
    let fitted: Vec<Vec<(Params, f64)>> = par_map(knee + 1, threads, col_fit);
    let mut res: Vec<(Params, f64)> = vec![([0.0; 4], 0.0); nv * nr];
    for (j, col) in fitted.iter().enumerate() {
        for (k, &r) in col.iter().enumerate() {
            res[k * nv + j] = r;
        }
    }
    // The grazing tail row by row, outwards from the knee: near-mirror lobes change with the
    // view's elevation, and each fit starts from the lobe of the next higher view.
    let row_fit = |k: usize| -> Vec<(Params, f64)> {
        let mut out = vec![res[k * nv + knee]];
        for j in knee + 1..nv {
            let r = if k == nr - 1 {
                top[j]
            } else {
                fit_from(k, j, &[out[j - knee - 1].0])
            };
            out.push(r);
        }
        out
    };
    let rows: Vec<Vec<(Params, f64)>> = par_map(nr, threads, row_fit);
    for (k, row) in rows.iter().enumerate() {
        for (t, &r) in row.iter().enumerate() {
            res[k * nv + knee + t] = r;
        }
    }

    // Refinement: restart each cell from any neighbour's solution that is better there, until a
    // pass changes nothing (then no neighbour's parameters fit any cell better than its own).
    let mut refinements = Vec::new();
    for _pass in 0..MAX_REFINE_PASSES {
        let snap = res.clone();
        let refine_col = |j: usize| -> Vec<(Params, f64)> {
            (0..nr)
                .map(|k| {
                    let c = cell(k, j);
                    let f = |p: &Params| c.objective(p, mode, &us);
                    let mut best = snap[k * nv + j];
                    let mut cand: Vec<Params> = Vec::new();
                    if j > 0 {
                        cand.push(snap[k * nv + j - 1].0);
                    }
                    if j + 1 < nv {
                        cand.push(snap[k * nv + j + 1].0);
                    }
                    for kk in [k.wrapping_sub(1), k + 1] {
                        if kk < nr {
                            let ws = warm_starts(snap[kk * nv + j].0, cell(kk, j).alpha, c.alpha);
                            cand.extend_from_slice(&ws);
                        }
                    }
                    for p in cand {
                        if f(&p) < best.1 {
                            let r = minimise(&f, p, dims);
                            if r.1 < best.1 {
                                best = r;
                            }
                        }
                    }
                    best
                })
                .collect()
        };
        let refined: Vec<Vec<(Params, f64)>> = par_map(nv, threads, refine_col);
        res = (0..nv * nr).map(|i| refined[i % nv][i / nv]).collect();
        let changed = (0..nv * nr).filter(|&i| res[i].1 < snap[i].1).count();
        refinements.push(changed);
        if changed == 0 {
            break;
        }
    }

    // Tabulate.
    let mut data: [Vec<f64>; CHANNELS] = core::array::from_fn(|_| vec![0.0; nv * nr]);
    for k in 0..nr {
        for j in 0..nv {
            let c = cell(k, j);
            let i = k * nv + j;
            let mi = c.matrix(&res[i].0).inverse();
            // The first row a unit vector (see `LtcLookup::m_inv`).
            let s = 1.0 / mi.x_axis.x.hypot(mi.z_axis.x);
            data[Channel::M00 as usize][i] = mi.x_axis.x * s;
            data[Channel::M02 as usize][i] = mi.z_axis.x * s;
            data[Channel::M20 as usize][i] = mi.x_axis.z * s;
            data[Channel::M22 as usize][i] = mi.z_axis.z * s;
            data[Channel::M11 as usize][i] = mi.y_axis.y * s;
            data[Channel::Albedo as usize][i] = c.albedo;
            data[Channel::Fresnel as usize][i] = c.fresnel;
        }
    }
    FittedTable {
        mode,
        table: LtcTable::from_parts(grid, data, mode == FitMode::Arealight),
        params: res.iter().map(|r| r.0).collect(),
        errors: res.iter().map(|r| r.1).collect(),
        refinements,
    }
}

/// Maps `f` over `0..n` on `threads` scoped threads (interleaved), preserving order.
fn par_map<T: Send>(n: usize, threads: usize, f: impl Fn(usize) -> T + Sync) -> Vec<T> {
    let f = &f;
    let mut parts: Vec<Vec<(usize, T)>> = std::thread::scope(|s| {
        let hs: Vec<_> = (0..threads)
            .map(|t| s.spawn(move || (t..n).step_by(threads).map(|i| (i, f(i))).collect()))
            .collect();
        hs.into_iter()
            .map(|h| h.join().unwrap_or_default())
            .collect()
    });
    let mut all: Vec<(usize, T)> = parts.iter_mut().flat_map(core::mem::take).collect();
    all.sort_by_key(|x| x.0);
    all.into_iter().map(|x| x.1).collect()
}

/// SplitMix64, for the jittered samples of [`shading_error`].
struct SplitMix(u64);

impl SplitMix {
    fn next_f64(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^= z >> 31;
        (z >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
    }
}

/// The shading error of a table at one (view cosine, alpha), relative to the albedo:
/// `integral over the sphere of |norm D_ltc(l) [l.z > 0] - f(v, l) cos| dl / A`.
///
/// This bounds the relative error of LTC shading for every light polygon (the error for a polygon
/// is at most this integral, and at most half of it when the total albedo is matched). It is
/// estimated with `samples^2` jittered BRDF samples and as many LTC samples (balance-heuristic
/// MIS), using the true GGX BRDF, independently of the fitter's fixed sample set. The BRDF is
/// taken at the view given, even below the table's smallest `cos_theta_v` (whose lookups are
/// clamped), so that the figure includes the clamping; `alpha` below the table's range is taken
/// as the table's smallest.
///
/// # Errors
///
/// As for [`LtcTable::lookup`].
pub fn shading_error(
    table: &LtcTable,
    cos_theta_v: f64,
    alpha: f64,
    samples: usize,
    seed: u64,
) -> Result<f64, GeomError> {
    let look = table.lookup(cos_theta_v, alpha)?;
    let ltc = look.ltc()?;
    let c = cos_theta_v.clamp(f64::MIN_POSITIVE, 1.0);
    let alpha = alpha.clamp(table.alpha_min(), 1.0);
    let v = DVec3::new((1.0 - c * c).sqrt(), 0.0, c);
    let mut rng = SplitMix(seed);
    let n = samples.max(1);
    let (mut err, mut albedo) = (0.0, 0.0);
    for i in 0..n {
        for j in 0..n {
            let u1 = DVec2::new(
                (i as f64 + rng.next_f64()) / n as f64,
                (j as f64 + rng.next_f64()) / n as f64,
            );
            let u2 = DVec2::new(
                (i as f64 + rng.next_f64()) / n as f64,
                (j as f64 + rng.next_f64()) / n as f64,
            );
            for (l, from_brdf) in [
                (ggx_sample_vndf(v, alpha, u1), true),
                (ltc.sample(u2), false),
            ] {
                let fc = ggx_brdf_cos(v, l, alpha);
                let d = ltc.density(l);
                let pdf = ggx_vndf_pdf(v, l, alpha);
                let q = if l.z > 0.0 { look.norm * d } else { 0.0 };
                if pdf + d > 0.0 {
                    err += (q - fc).abs() / (pdf + d);
                }
                if from_brdf && pdf > 0.0 {
                    albedo += fc / pdf;
                }
            }
        }
    }
    let m = (n * n) as f64;
    Ok((err / m) / (albedo / m))
}

/// Form factor of a polygon of directions (vertices need not be normalised; edges are the
/// straight segments between them, i.e. great arcs on the sphere) after clipping to `z >= 0`:
/// `(1 / pi) integral over the polygon of max(0, z) dw`, by Baum's formula (as used in \[HDHN16\]).
/// The absolute value is returned, so the orientation does not matter.
fn clipped_form_factor(poly: &[DVec3]) -> f64 {
    let mut clipped: Vec<DVec3> = Vec::with_capacity(poly.len() + 2);
    for (i, &a) in poly.iter().enumerate() {
        let b = poly[(i + 1) % poly.len()];
        if a.z >= 0.0 {
            clipped.push(a);
        }
        if (a.z >= 0.0) != (b.z >= 0.0) {
            let t = a.z / (a.z - b.z);
            let p = a + (b - a) * t;
            clipped.push(DVec3::new(p.x, p.y, 0.0));
        }
    }
    if clipped.len() < 3 {
        return 0.0;
    }
    let mut sum = 0.0;
    for i in 0..clipped.len() {
        let a = clipped[i].normalize_or_zero();
        let b = clipped[(i + 1) % clipped.len()].normalize_or_zero();
        let cr = a.cross(b);
        let s = cr.length();
        if s > 0.0 {
            // Angle via atan2 (accurate for short edges), times the z of the edge's plane normal.
            sum += s.atan2(a.dot(b)) * cr.z / s;
        }
    }
    (sum / (2.0 * core::f64::consts::PI)).abs()
}

/// A random planar quad light facing the origin, as four vertices in the shading frame.
fn random_quad(rng: &mut SplitMix, v: DVec3, alpha: f64) -> [DVec3; 4] {
    // Half of the lights are centred on a direction drawn from the BRDF lobe, half uniformly over
    // the upper hemisphere (most of those barely reflect anything).
    let center = loop {
        let d = if rng.next_f64() < 0.5 {
            ggx_sample_vndf(v, alpha, DVec2::new(rng.next_f64(), rng.next_f64()))
        } else {
            let z = rng.next_f64();
            let phi = 2.0 * core::f64::consts::PI * rng.next_f64();
            let s = (1.0 - z * z).sqrt();
            DVec3::new(s * phi.cos(), s * phi.sin(), z)
        };
        if d.z > 0.02 {
            break d;
        }
    };
    let dist = 1.0 + 2.0 * rng.next_f64();
    let c = center * dist;
    // Light normal towards the origin, tilted by up to ~45 degrees; random spin in its plane.
    let tilt = DVec3::new(
        rng.next_f64() - 0.5,
        rng.next_f64() - 0.5,
        rng.next_f64() - 0.5,
    );
    let n = (-center + tilt).normalize();
    let a = if n.x.abs() < 0.9 { DVec3::X } else { DVec3::Y };
    let t1 = a.cross(n).normalize();
    let t2 = n.cross(t1);
    let spin = 2.0 * core::f64::consts::PI * rng.next_f64();
    let (e1, e2) = (
        t1 * spin.cos() + t2 * spin.sin(),
        -t1 * spin.sin() + t2 * spin.cos(),
    );
    let h1 = dist * (0.05 + 0.95 * rng.next_f64());
    let h2 = dist * (0.05 + 0.95 * rng.next_f64());
    [
        c - e1 * h1 - e2 * h2,
        c + e1 * h1 - e2 * h2,
        c + e1 * h1 + e2 * h2,
        c - e1 * h1 + e2 * h2,
    ]
}

/// Whether the ray from the origin along `d` hits the convex planar quad `q`.
fn hits_quad(q: &[DVec3; 4], d: DVec3) -> bool {
    let n = (q[1] - q[0]).cross(q[3] - q[0]);
    let denom = n.dot(d);
    if denom.abs() < 1e-300 {
        return false;
    }
    let t = n.dot(q[0]) / denom;
    if t <= 0.0 {
        return false;
    }
    let p = d * t;
    (0..4).all(|i| (q[(i + 1) % 4] - q[i]).cross(p - q[i]).dot(n) >= 0.0)
}

/// The end-to-end check of the tables: LTC shading of random quad lights against brute-force
/// integration of the real GGX BRDF (`f cos` over the quad), at `count` random configurations
/// (view 0..85 degrees, `alpha = r^2` with `r` uniform in `[0.05, 1]`).
///
/// Returns `|LTC - reference| / albedo` per configuration, where the LTC value is
/// `norm * form_factor(clip(M^-1 clip(P)))` and the reference is a stratified estimate with
/// `samples^2` jittered visible-normal samples (weights `G2 / G1`, so its error is small compared
/// with the quantities measured for `samples >= 256`).
///
/// # Errors
///
/// As for [`LtcTable::lookup`] (never, for the generated configurations).
pub fn quad_shading_errors(
    table: &LtcTable,
    count: usize,
    samples: usize,
    seed: u64,
) -> Result<Vec<f64>, GeomError> {
    let mut rng = SplitMix(seed);
    let mut out = Vec::with_capacity(count);
    let n = samples.max(1);
    for _ in 0..count {
        let c = (rng.next_f64() * 85f64.to_radians()).cos();
        let r = 0.05 + 0.95 * rng.next_f64();
        let alpha = r * r;
        let v = DVec3::new((1.0 - c * c).sqrt(), 0.0, c);
        let quad = random_quad(&mut rng, v, alpha);
        let look = table.lookup(c, alpha)?;
        // LTC estimate: clip to the shading horizon, map to cosine space, clip again, integrate.
        let mut above: Vec<DVec3> = Vec::with_capacity(8);
        for i in 0..4 {
            let (a, b) = (quad[i], quad[(i + 1) % 4]);
            if a.z >= 0.0 {
                above.push(a);
            }
            if (a.z >= 0.0) != (b.z >= 0.0) {
                above.push(a + (b - a) * (a.z / (a.z - b.z)));
            }
        }
        let mapped: Vec<DVec3> = above.iter().map(|&p| look.m_inv * p).collect();
        let ltc = if mapped.len() >= 3 {
            look.norm * clipped_form_factor(&mapped)
        } else {
            0.0
        };
        // Brute force: stratified visible-normal sampling of f cos, counting hits on the quad.
        let (mut hit, mut albedo) = (0.0, 0.0);
        for i in 0..n {
            for j in 0..n {
                let u = DVec2::new(
                    (i as f64 + rng.next_f64()) / n as f64,
                    (j as f64 + rng.next_f64()) / n as f64,
                );
                let Some((l, w)) = ggx_vndf_weight(v, alpha, u) else {
                    continue;
                };
                albedo += w;
                if hits_quad(&quad, l) {
                    hit += w;
                }
            }
        }
        out.push((ltc - hit / (n * n) as f64).abs() / (albedo / (n * n) as f64));
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The committed table written out again gives the committed source byte for byte: the
    /// writer's channel names and the table's storage order (`Channel`) agree.
    #[test]
    fn committed_table_round_trips_through_the_writer() {
        let table = LtcTable::ggx().clone();
        let cells = table.view_nodes() * table.roughness_nodes();
        let fitted = FittedTable {
            mode: FitMode::Arealight,
            table,
            params: vec![[0.0; 4]; cells],
            errors: vec![0.0; cells],
            refinements: Vec::new(),
        };
        let source = fitted.to_source("cargo run --release --features fit --example fit_ltc");
        assert!(
            source == include_str!("table_data.rs"),
            "the writer no longer reproduces table_data.rs"
        );
    }

    #[test]
    fn nelder_mead_finds_the_minimum_of_a_skewed_quadratic() {
        let f = |p: &Params| {
            let (a, b) = (p[0] - 1.0, p[1] + 2.0);
            (a + 0.5 * b).powi(2) + 3.0 * b * b + (p[2] - 0.25).powi(2) + 2.0 * (p[3] + 0.5).powi(2)
        };
        let (x, v) = minimise(&f, [0.0; 4], 4);
        assert!(v < 1e-8, "{x:?} {v}");
        let (x3, _) = minimise(&f, [0.0; 4], 3);
        assert_eq!(x3[3], 0.0, "3-parameter mode must keep m31 fixed");
        assert!(
            (x3[0] - 1.0).abs() < 1e-3 && (x3[2] - 0.25).abs() < 1e-3,
            "{x3:?}"
        );
    }

    #[test]
    fn form_factor_matches_quadrature() {
        // A light covering the whole upper hemisphere: form factor 1 (the far plane z = 1 almost).
        let big = [
            DVec3::new(-1e6, -1e6, 1.0),
            DVec3::new(1e6, -1e6, 1.0),
            DVec3::new(1e6, 1e6, 1.0),
            DVec3::new(-1e6, 1e6, 1.0),
        ];
        assert!((clipped_form_factor(&big) - 1.0).abs() < 1e-5);
        // Random quads (some crossing the horizon) against ray-cast quadrature of z / pi.
        let mut rng = SplitMix(5);
        for _ in 0..20 {
            let v = DVec3::new(0.6, 0.0, 0.8);
            let q = random_quad(&mut rng, v, 0.5);
            // Lower the light (one shift for all vertices) so that some quads cross the horizon.
            let shift = DVec3::new(0.0, 0.0, 0.7 * rng.next_f64());
            let q = q.map(|p| p - shift);
            let n = 400;
            let mut sum = 0.0;
            for i in 0..n {
                for j in 0..n {
                    // Cosine-distributed directions: the hit fraction is the form factor.
                    let u = DVec2::new((i as f64 + 0.5) / n as f64, (j as f64 + 0.5) / n as f64);
                    if hits_quad(&q, super::super::distribution::cosine_sample(u)) {
                        sum += 1.0;
                    }
                }
            }
            let quad = sum / (n * n) as f64;
            let ff = clipped_form_factor(&q);
            assert!(
                (ff - quad).abs() < 2e-3,
                "form factor {ff} vs quadrature {quad}"
            );
        }
    }

    #[test]
    fn small_fit_is_deterministic_and_beats_its_starting_point() {
        let cfg = FitConfig {
            mode: FitMode::Arealight,
            size: 4,
            samples: 12,
            threads: 2,
        };
        let a = fit_ggx(&cfg, |_| {});
        let b = fit_ggx(&cfg, |_| {});
        assert_eq!(a.cell_params(), b.cell_params());
        // Every fitted cell beats the isotropic cosine of the same width (the generic start).
        let grid = cfg.mode.grid(4);
        let us = stratified(12);
        let stats = stratified(64);
        for k in 0..grid.n_rough {
            for j in 0..grid.n_view {
                let cell = Cell::new(grid.node_cos(j), grid.node_alpha(k), &us, &stats);
                let la = grid.node_alpha(k).ln();
                let naive = cell.objective(&[la, la, 0.0, 0.0], FitMode::Arealight, &us);
                let fitted = a.cell_errors()[k * grid.n_view + j];
                assert!(fitted <= naive, "cell ({j}, {k}): {fitted} vs {naive}");
            }
        }
        assert_eq!(a.refinements().last(), Some(&0));
    }
}
