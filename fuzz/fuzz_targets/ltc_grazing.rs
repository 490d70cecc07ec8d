//! Fuzz the LTC layer where renderers meet its edges (issue 24): a vertex of any polygon moved to
//! `1e-16` to `1e-9` above, onto and below the horizon (absolute, or relative to its edges'
//! lengths), grazing views (`cos_v` from 1e-4 to 0.05, or any) and roughness from 0 to 0.05 (or
//! any). Invariants: every integral finite and in range, or `GeomError::Undecidable` (an exact
//! path's clip found inconsistent) and no other error; `0 <= ggx_polygon_integral <= albedo`;
//! the clip-free integrals continuous across the horizon, in the shading frame and under the
//! table's map (the change bounded by the moved vertex's displacement, as the image of the
//! vertex moves, times its edges' lengths).
//!
//! Run: `RUSTC_BOOTSTRAP=1 cargo fuzz run ltc_grazing -- -max_total_time=300` (from the crate root).
#![no_main]

#[path = "sphere_common/mod.rs"]
mod common;

use arealight::GeomError;
use arealight::glam::{DMat3, DVec3};
use arealight::ltc::{
    EDGE_FACTOR_RATIONAL_MAX_ERROR, clamped_cosine_integral_clip_free, ggx_polygon_integral,
    lookup, ltc_integral, ltc_integral_rational,
};
use arealight::sphere::SphericalPolygon;
use libfuzzer_sys::arbitrary::{self, Arbitrary};
use libfuzzer_sys::fuzz_target;
use std::f64::consts::PI;

#[derive(Debug, Arbitrary)]
struct Case {
    poly: common::Poly,
    /// Which vertex moves (modulo the vertex count).
    vertex: u8,
    /// The height: `10^-(9 + exponent % 8)`.
    exponent: u8,
    /// The height relative to the moved vertex's edges' lengths.
    relative: bool,
    /// `cos_v`: log-uniform in `[1e-4, 0.05]` when `grazing`, uniform in `(0, 1]` otherwise.
    view: u16,
    /// `alpha`: `(r sqrt(0.05))^2` with `r = rough / 65535` when `grazing`, `r^2` otherwise;
    /// exactly 0 when `rough == 0`.
    rough: u16,
    grazing: bool,
}

/// The polygon with ring vertex `k` (counting over all rings) moved to height `h`, its azimuth
/// kept, and the moved vertex with its two neighbours.
fn moved(p: &SphericalPolygon, k: usize, h: f64) -> Option<(SphericalPolygon, [DVec3; 3])> {
    let mut rings: Vec<Vec<DVec3>> = p.rings().map(<[DVec3]>::to_vec).collect();
    let mut k = k;
    for ring in &mut rings {
        if k < ring.len() {
            let v = ring[k];
            let horiz = (v.x * v.x + v.y * v.y).sqrt();
            if horiz == 0.0 {
                return None;
            }
            let s = (1.0 - h * h).sqrt() / horiz;
            ring[k] = DVec3::new(v.x * s, v.y * s, h);
            let n = ring.len();
            let around = [ring[(k + n - 1) % n], ring[k], ring[(k + 1) % n]];
            let q = SphericalPolygon::new(rings.clone()).ok()?;
            return Some((q, around));
        }
        k -= ring.len();
    }
    None
}

fn arc(a: DVec3, b: DVec3) -> f64 {
    a.cross(b).length().atan2(a.dot(b))
}

/// Bound on the change of a clamped-cosine integral when the middle vertex of `around` moves
/// from `a[1]` to `b[1]` (the neighbours fixed): a point at angle `theta` along an edge of length
/// `L` from the fixed end moves by at most `d sin(theta) / sin(L)`, so the edge sweeps at most
/// `d tan(L / 2)` (`d L / 2` for short edges, unbounded for nearly antipodal ones), and the
/// integrand is at most `1 / pi`.
fn sweep_bound(a: [DVec3; 3], b: [DVec3; 3]) -> f64 {
    let d = arc(a[1], b[1]);
    let half_tan = |p: DVec3, q: DVec3| (0.5 * arc(p, q)).tan();
    let e0 = half_tan(a[0], a[1]).max(half_tan(b[0], b[1]));
    let e1 = half_tan(a[1], a[2]).max(half_tan(b[1], b[2]));
    d * (e0 + e1) / PI
}

fuzz_target!(|case: Case| {
    let Some(p) = case.poly.build() else { return };
    if p.is_full() || p.is_empty() {
        return;
    }
    let count = p.vertex_count();
    let k = case.vertex as usize % count;
    let mut h = 10f64.powi(-(9 + (case.exponent % 8) as i32));
    if case.relative {
        let Some((_, around)) = moved(&p, k, 0.0) else { return };
        h *= arc(around[0], around[1]).min(arc(around[1], around[2]));
    }
    let u = case.view as f64 / 65535.0;
    let cos_v = if case.grazing { 1e-4 * 500f64.powf(u) } else { u.max(1e-300) };
    let r = case.rough as f64 / 65535.0;
    let alpha = if case.grazing { (r * 0.05f64.sqrt()).powi(2) } else { r * r };
    let look = lookup(cos_v, alpha).unwrap();
    let m_inv = look.m_inv;

    // An undecidable case ends the check (an honest answer); any other error is a bug.
    let decided = |r: Result<f64, GeomError>, q: &SphericalPolygon| match r {
        Ok(v) => Some(v),
        Err(e) if e.is_undecidable() => None,
        Err(e) => panic!("{e} on valid input\nP = {q:?}\nM = {m_inv:?}"),
    };
    let mut sides = Vec::new();
    for height in [h, 0.0, -h] {
        let Some((q, around)) = moved(&p, k, height) else { return };
        let lambert = clamped_cosine_integral_clip_free(&q);
        let Some(ltc) = decided(ltc_integral(&q, DMat3::IDENTITY), &q) else { return };
        let Some(rational) = decided(ltc_integral_rational(&q, DMat3::IDENTITY), &q) else { return };
        let Some(mapped) = decided(ltc_integral(&q, m_inv), &q) else { return };
        let Some(mapped_rational) = decided(ltc_integral_rational(&q, m_inv), &q) else { return };
        for (what, v) in [
            ("clip-free", lambert),
            ("ltc identity", ltc),
            ("ltc rational identity", rational),
            ("ltc", mapped),
            ("ltc rational", mapped_rational),
        ] {
            assert!(
                v.is_finite() && (0.0..=1.0).contains(&v),
                "{what}: {v} at height {height:e}\nP = {q:?}\nM = {m_inv:?}"
            );
        }
        let Some(ggx) = decided(ggx_polygon_integral(&q, cos_v, alpha, 1.0), &q) else { return };
        assert!(
            ggx.is_finite() && ggx >= 0.0 && ggx <= look.albedo * (1.0 + 1e-9),
            "ggx {ggx} outside [0, albedo {}] at ({cos_v}, {alpha})\nP = {q:?}",
            look.albedo
        );
        // The rational factor's error bound: its constant times the clipped polygon's perimeter
        // over 2 pi (the clip adds at most a circle per ring), here and under the map.
        let perimeter = |f: &dyn Fn(DVec3) -> DVec3| -> f64 {
            q.rings()
                .map(|r| (0..r.len()).map(|i| arc(f(r[i]), f(r[(i + 1) % r.len()]))).sum::<f64>() + 2.0 * PI)
                .sum()
        };
        let bounds = [
            EDGE_FACTOR_RATIONAL_MAX_ERROR * perimeter(&|v| v) / (2.0 * PI),
            EDGE_FACTOR_RATIONAL_MAX_ERROR * perimeter(&|v| (m_inv * v).normalize()) / (2.0 * PI),
        ];
        sides.push((height, around, [ltc, rational, mapped, mapped_rational, lambert], bounds));
    }
    // Continuity: between consecutive heights the integrals move by at most the swept area's
    // bound (under the map, of the images), plus rounding (the map's conditioning) and the
    // rational factor's error on both sides.
    let images = |a: [DVec3; 3]| a.map(|v| (m_inv * v).normalize());
    let cond = {
        let m = m_inv.inverse();
        let norm1 = |x: DMat3| x.to_cols_array().iter().map(|e| e.abs()).sum::<f64>();
        norm1(m) * norm1(m_inv)
    };
    for w in sides.windows(2) {
        let ((h0, a0, v0, r0), (h1, a1, v1, r1)) = (&w[0], &w[1]);
        let shading = sweep_bound(*a0, *a1) + 1e-12;
        let mapped = sweep_bound(images(*a0), images(*a1)) + 1e-12 * cond;
        for (i, (what, bound)) in [
            ("ltc identity", shading),
            ("ltc rational identity", shading + r0[0] + r1[0]),
            ("ltc", mapped),
            ("ltc rational", mapped + r0[1] + r1[1]),
            // No error channel: its undecidable cases go to the sphere layer's clip, which must
            // be continuous too.
            ("clip-free", shading),
        ]
        .into_iter()
        .enumerate()
        {
            assert!(
                (v0[i] - v1[i]).abs() <= bound,
                "{what}: {} at height {h0:e}, {} at {h1:e} (bound {bound:e})\nP = {p:?}\nvertex {k}\nM = {m_inv:?}",
                v0[i],
                v1[i]
            );
        }
    }
});
