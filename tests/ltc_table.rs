//! The shipped GGX LTC table: lookup semantics and fit quality against the real BRDF.

mod support;

use arealight::GeomError;
use arealight::glam::{DVec2, DVec3};
use arealight::ltc::{LtcLookup, LtcTable, ggx_brdf_cos, ggx_sample_vndf, ggx_vndf_pdf, lookup};
use support::Rng;
use support::ltc::{sphere_quad, view};

fn channels(l: &LtcLookup) -> [f64; 8] {
    [
        l.m_inv.x_axis.x,
        l.m_inv.z_axis.x,
        l.m_inv.x_axis.z,
        l.m_inv.z_axis.z,
        l.norm,
        l.albedo,
        l.fresnel,
        l.m_inv.y_axis.y,
    ]
}

#[test]
fn lookup_at_nodes_returns_stored_values() {
    let t = LtcTable::ggx();
    let (nv, nr) = (t.view_nodes(), t.roughness_nodes());
    assert_eq!((nv, nr), (81, 64));
    for k in 0..nr {
        for j in 0..nv {
            let (c, a) = t.node(j, k).unwrap();
            let got = channels(&t.lookup(c, a).unwrap());
            let want = channels(&t.node_lookup(j, k).unwrap());
            assert_eq!(got, channels(&lookup(c, a).unwrap()));
            for (g, w) in got.iter().zip(want) {
                assert!(
                    (g - w).abs() <= 1e-9 * w.abs().max(1.0),
                    "node ({j}, {k}): {got:?} vs {want:?}"
                );
            }
        }
    }
    assert!(t.node(nv, 0).is_none() && t.node_lookup(0, nr).is_none());
}

#[test]
fn shortcut_lookup_agrees_with_the_table_method() {
    // `lookup` runs the same interpolation with the committed grid's constants folded in; it must
    // give the very same bits, at nodes, between them, at the ends and outside the ranges.
    let t = LtcTable::ggx();
    let mut rng = Rng::from_state(21);
    let mut inputs = vec![
        (1.0, 1.0),
        (0.0, 0.0),
        (-0.5, -1.0),
        (2.0, 3.0),
        (f64::INFINITY, f64::NEG_INFINITY),
        (f64::NEG_INFINITY, f64::INFINITY),
        (t.cos_min(), t.alpha_min()),
        (1.0 - 1e-17, 1e-300),
    ];
    for k in 0..t.roughness_nodes() {
        inputs.push(t.node(k, k).unwrap());
        inputs.push(t.node(t.view_nodes() - 1 - k, k).unwrap());
    }
    for _ in 0..2000 {
        inputs.push((rng.range(-0.1, 1.1), rng.range(-0.1, 1.1)));
    }
    for (c, a) in inputs {
        let (got, want) = (lookup(c, a).unwrap(), t.lookup(c, a).unwrap());
        let bits = |l: &LtcLookup| channels(l).map(f64::to_bits);
        assert_eq!(bits(&got), bits(&want), "({c}, {a})");
    }
}

#[test]
fn lookup_is_bilinear_between_nodes() {
    let t = LtcTable::ggx();
    let mut rng = Rng::from_state(20);
    for _ in 0..300 {
        let j = (rng.f64() * (t.view_nodes() - 1) as f64) as usize;
        let k = (rng.f64() * (t.roughness_nodes() - 1) as f64) as usize;
        let (c0, a0) = t.node(j, k).unwrap();
        let (c1, a1) = t.node(j + 1, k + 1).unwrap();
        let c = c0 + (c1 - c0) * rng.f64();
        let a = a0 + (a1 - a0) * rng.f64();
        let v00 = channels(&t.node_lookup(j, k).unwrap());
        let v10 = channels(&t.node_lookup(j + 1, k).unwrap());
        let v01 = channels(&t.node_lookup(j, k + 1).unwrap());
        let v11 = channels(&t.node_lookup(j + 1, k + 1).unwrap());
        // Interpolation weights, recovered from 1D lookups along the cell's edges (so the test does
        // not assume the grid's parameterisation): the weight of the interpolated channel that
        // changes most.
        let weight = |lo: &[f64; 8], hi: &[f64; 8], mid: &[f64; 8]| {
            let ch = (0..8)
                .filter(|&ch| ch != 4)
                .max_by(|&x, &y| (hi[x] - lo[x]).abs().total_cmp(&(hi[y] - lo[y]).abs()))
                .unwrap();
            let w = (mid[ch] - lo[ch]) / (hi[ch] - lo[ch]);
            assert!(
                (-1e-9..=1.0 + 1e-9).contains(&w),
                "weight {w} outside the cell"
            );
            w
        };
        let tx = weight(&v00, &v10, &channels(&t.lookup(c, a0).unwrap()));
        let ty = weight(&v00, &v01, &channels(&t.lookup(c0, a).unwrap()));
        let look = t.lookup(c, a).unwrap();
        let got = channels(&look);
        // Every channel but `norm` (4), which follows from the interpolated matrix and albedo.
        for ch in (0..8).filter(|&ch| ch != 4) {
            let want = (v00[ch] * (1.0 - tx) + v10[ch] * tx) * (1.0 - ty)
                + (v01[ch] * (1.0 - tx) + v11[ch] * tx) * ty;
            assert!(
                (got[ch] - want).abs() <= 1e-9 * want.abs().max(1.0),
                "channel {ch}: {} vs {want}",
                got[ch]
            );
        }
        let h = look.ltc().unwrap().upper_hemisphere_mass();
        assert!((look.norm * h / look.albedo - 1.0).abs() <= 1e-9);
    }
}

#[test]
fn out_of_range_inputs_clamp_and_nan_is_an_error() {
    let t = LtcTable::ggx();
    assert!(matches!(
        lookup(f64::NAN, 0.3),
        Err(GeomError::OutOfRange { .. })
    ));
    assert!(matches!(
        lookup(0.3, f64::NAN),
        Err(GeomError::OutOfRange { .. })
    ));
    let same = |a: LtcLookup, b: LtcLookup| assert_eq!(channels(&a), channels(&b));
    same(
        lookup(-0.5, 0.3).unwrap(),
        lookup(t.cos_min(), 0.3).unwrap(),
    );
    same(
        lookup(f64::NEG_INFINITY, 0.3).unwrap(),
        lookup(t.cos_min(), 0.3).unwrap(),
    );
    same(lookup(1.5, 0.3).unwrap(), lookup(1.0, 0.3).unwrap());
    same(lookup(0.5, 7.0).unwrap(), lookup(0.5, 1.0).unwrap());
    same(
        lookup(0.5, f64::INFINITY).unwrap(),
        lookup(0.5, 1.0).unwrap(),
    );
    same(
        lookup(0.5, 0.0).unwrap(),
        lookup(0.5, t.alpha_min()).unwrap(),
    );
    same(
        lookup(0.5, -1.0).unwrap(),
        lookup(0.5, t.alpha_min()).unwrap(),
    );
}

#[test]
fn every_node_is_a_valid_ltc_with_sane_scalars() {
    let t = LtcTable::ggx();
    for k in 0..t.roughness_nodes() {
        for j in 0..t.view_nodes() {
            let l = t.node_lookup(j, k).unwrap();
            assert!(l.ltc().is_ok(), "node ({j}, {k}) singular");
            assert!(l.albedo > 0.0 && l.albedo <= 1.0, "albedo {}", l.albedo);
            assert!((0.0..=1.0).contains(&l.fresnel), "fresnel {}", l.fresnel);
            assert!(
                l.norm >= l.albedo * (1.0 - 1e-12),
                "norm {} < albedo {}",
                l.norm,
                l.albedo
            );
        }
    }
}

#[test]
fn albedo_and_fresnel_match_quadrature() {
    let mut rng = Rng::from_state(21);
    for _ in 0..12 {
        let c = rng.range(0.05, 1.0);
        let alpha = rng.range(0.05, 1.0).powi(2);
        let v = view(c);
        let pole = DVec3::new(-v.x, 0.0, v.z);
        let a = sphere_quad(pole, 3.0, 600, 128, |l| ggx_brdf_cos(v, l, alpha));
        let f = sphere_quad(pole, 3.0, 600, 128, |l| {
            let h = (v + l).normalize();
            ggx_brdf_cos(v, l, alpha) * (1.0 - v.dot(h).clamp(0.0, 1.0)).powi(5)
        }) / a;
        let l = lookup(c, alpha).unwrap();
        assert!(
            (l.albedo - a).abs() < 5e-3,
            "cos {c} alpha {alpha}: table {} quadrature {a}",
            l.albedo
        );
        assert!(
            (l.fresnel - f).abs() < 5e-3,
            "cos {c} alpha {alpha}: table {} quadrature {f}",
            l.fresnel
        );
    }
}

/// `integral |norm D_ltc [z > 0] - f cos| / albedo` over the sphere, by MIS with jittered samples
/// of the BRDF (visible normals) and of the LTC. This bounds the relative shading error of every
/// light polygon.
fn relative_l1(l: &LtcLookup, c: f64, alpha: f64, n: usize, rng: &mut Rng) -> f64 {
    let ltc = l.ltc().unwrap();
    let v = view(c);
    let (mut err, mut albedo) = (0.0, 0.0);
    for i in 0..n {
        for j in 0..n {
            let mut u = || {
                DVec2::new(
                    (i as f64 + rng.f64()) / n as f64,
                    (j as f64 + rng.f64()) / n as f64,
                )
            };
            let (ub, ul) = (u(), u());
            for (w, from_brdf) in [
                (ggx_sample_vndf(v, alpha, ub), true),
                (ltc.sample(ul), false),
            ] {
                let fc = ggx_brdf_cos(v, w, alpha);
                let d = ltc.density(w);
                let pdf = ggx_vndf_pdf(v, w, alpha);
                let q = if w.z > 0.0 { l.norm * d } else { 0.0 };
                if pdf + d > 0.0 {
                    err += (q - fc).abs() / (pdf + d);
                }
                if from_brdf && pdf > 0.0 {
                    albedo += fc / pdf;
                }
            }
        }
    }
    err / albedo
}

fn percentile(v: &mut [f64], p: f64) -> f64 {
    v.sort_by(f64::total_cmp);
    v[((v.len() - 1) as f64 * p).round() as usize]
}

/// Random points of the range: view 0..85 degrees, alpha = r^2 with r in [0.05, 1].
fn fit_errors(shift_alpha: f64) -> Vec<f64> {
    let mut rng = Rng::from_state(22);
    (0..300)
        .map(|_| {
            let c = rng.range(0.0, 85f64.to_radians()).cos();
            let alpha = rng.range(0.05, 1.0).powi(2);
            let l = lookup(c, alpha * shift_alpha).unwrap();
            relative_l1(&l, c, alpha, 24, &mut rng)
        })
        .collect()
}

#[test]
fn fitted_ltc_matches_the_brdf() {
    let mut e = fit_errors(1.0);
    let (median, p90) = (percentile(&mut e, 0.5), percentile(&mut e, 0.9));
    println!("relative L1 of the shipped table: median {median:.4}, p90 {p90:.4}");
    assert!(
        median < MEDIAN_MAX && p90 < P90_MAX,
        "median {median}, p90 {p90}"
    );
    // The bounds discriminate: the table looked up at the wrong roughness (x 1.5) fails them.
    let mut bad = fit_errors(1.5);
    let (bm, bp) = (percentile(&mut bad, 0.5), percentile(&mut bad, 0.9));
    println!("relative L1 at 1.5 x alpha: median {bm:.4}, p90 {bp:.4}");
    assert!(
        bm > MEDIAN_MAX || bp > P90_MAX,
        "a wrong lookup passed: {bm}, {bp}"
    );
}

// Measured for the shipped table: median 0.039, p90 0.164 (fitter's own 64^2-sample estimate at
// 400 points: 0.040 / 0.162). The reference-parameterisation reproduction (3 parameters, cubed
// error, unclipped; see BENCHMARKS.md) reaches 0.062 / 0.256 and would fail both bounds.
const MEDIAN_MAX: f64 = 0.05;
const P90_MAX: f64 = 0.2;
