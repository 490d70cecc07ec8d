//! The LTC layer where a renderer meets it at its edges (issue 24): regions that contain the lower
//! hemisphere although every vertex lies above the horizon, grazing views with near-mirror
//! roughness, and vertices at the horizon. Every value is checked against an independent
//! reference: Gauss–Legendre quadrature of the density over the region, the closed-form mass of
//! an LTC above a plane, or an exact identity.

mod support;

use arealight::glam::{DMat3, DVec3};
use arealight::ltc::{
    Ltc, clamped_cosine_integral, clamped_cosine_integral_clip_free,
    clamped_cosine_integral_rational, ggx_polygon_integral, lookup, ltc_integral,
    ltc_integral_rational,
};
use arealight::sphere::SphericalPolygon;
use std::f64::consts::PI;
use support::Rng;
use support::sphere::{star_ring, triangle_quadrature};

fn v(x: f64, y: f64, z: f64) -> DVec3 {
    DVec3::new(x, y, z)
}

/// Quadrature of `f` over a ring star-shaped about `c` (a fan of triangles from `c`), which must
/// lie within an open hemisphere about `c`: independent of the crate's clipping and edge sums.
fn fan_quadrature(c: DVec3, ring: &[DVec3], f: impl Fn(DVec3) -> f64) -> f64 {
    let n = ring.len();
    (0..n)
        .map(|i| triangle_quadrature_split(c, ring[i], ring[(i + 1) % n], &f))
        .sum()
}

/// Gauss–Legendre quadrature over a spherical triangle, split at its edges' midpoints until the
/// pieces are shorter than 0.2 rad a side: the central projection of a large flat triangle
/// varies too much for one tensor rule (a hemisphere-sized fan was off by 1e-5 with 48 points).
fn triangle_quadrature_split(a: DVec3, b: DVec3, c: DVec3, f: &dyn Fn(DVec3) -> f64) -> f64 {
    let longest = (a - b).length().max((b - c).length()).max((c - a).length());
    if longest <= 0.2 {
        return triangle_quadrature(a, b, c, 24, f);
    }
    let (ab, bc, ca) = (
        (a + b).normalize(),
        (b + c).normalize(),
        (c + a).normalize(),
    );
    triangle_quadrature_split(a, ab, ca, f)
        + triangle_quadrature_split(ab, b, bc, f)
        + triangle_quadrature_split(ca, bc, c, f)
        + triangle_quadrature_split(ab, bc, ca, f)
}

/// Issue 24, reproducer 2: the complement of a quad above the point has every vertex above the
/// horizon, yet contains the whole lower hemisphere, from which no light reaches the surface.
/// The specular response to it is the response to the whole upper hemisphere (`norm` times the
/// LTC's mass above the horizon, in closed form) minus the response to the quad (quadrature of
/// the LTC density over it). Skipping the horizon clip gave 1.817 here, about `norm` itself.
#[test]
fn reproducer_2_complement_of_a_quad_above_the_point() {
    let quad = vec![
        v(-0.2, -0.2, 1.),
        v(0.2, -0.2, 1.),
        v(0.2, 0.2, 1.),
        v(-0.2, 0.2, 1.),
    ];
    let p = SphericalPolygon::new(vec![quad.clone()]).unwrap();
    let (cos_v, alpha) = (1e-3, 1e-4);
    let got = ggx_polygon_integral(&p.complement(), cos_v, alpha, 1.0).unwrap();
    let l = lookup(cos_v, alpha).unwrap();
    let ltc = l.ltc().unwrap();
    let in_quad = fan_quadrature(DVec3::Z, &quad, |d| ltc.density(d));
    let expected = l.norm * (ltc.upper_hemisphere_mass() - in_quad);
    // The density's kink where its preimage crosses the cosine's horizon limits the quadrature.
    assert!(
        (got - expected).abs() <= 1e-5 * l.norm,
        "{got} vs upper hemisphere minus quad {expected}"
    );
}

/// A ring around `c` with every vertex above the horizon (down to `1e-12` above it), `n`
/// vertices, from tiny to nearly a hemisphere; `None` when the draw is not a valid polygon.
fn ring_above(rng: &mut Rng) -> Option<(DVec3, Vec<DVec3>)> {
    let c = DVec3::new(
        rng.range(-1.0, 1.0),
        rng.range(-1.0, 1.0),
        rng.range(0.02, 1.0),
    )
    .normalize();
    // The largest radius that keeps the ring above the horizon, less a margin of 10^-12..10^-1.
    let room = c.z.asin() - 10f64.powf(rng.range(-12.0, -1.0));
    if room <= 1e-6 {
        return None;
    }
    let rho = room * 10f64.powf(rng.range(-4.0, 0.0));
    let n = 3 + (rng.next_u64() % 6) as usize;
    let ring = star_ring(rng, c, n, rho, 0.6);
    if ring.iter().any(|p| p.z <= 0.0) {
        return None;
    }
    SphericalPolygon::new(vec![ring.clone()]).ok()?;
    Some((c, ring))
}

/// A random map of the fitted tables' form with a moderate condition number, so that quadrature
/// of its density stays accurate.
fn table_form_map(rng: &mut Rng) -> DMat3 {
    DMat3::from_cols(
        DVec3::new(rng.range(0.3, 2.0), 0.0, rng.range(-0.8, 0.8)),
        DVec3::Y,
        DVec3::new(rng.range(-0.5, 0.5), 0.0, rng.range(0.5, 1.5)),
    )
}

/// The family of reproducer 2, through every integral entry point: the complement of a region
/// above the horizon (and of two disjoint ones: a region with two rings) has every vertex above
/// the horizon and contains the lower hemisphere. Its clamped-cosine integral is one minus the
/// quadrature over the holes, and its LTC integral is one minus the quadrature of the LTC density
/// over them (the clamped cosine integrates to one over the sphere, and so does an LTC); its GGX
/// response is the upper hemisphere's (closed form) minus the holes'. (The LTC density has a kink
/// where its preimage crosses the cosine's horizon, which limits the quadrature to about `1e-7`.)
#[test]
fn regions_containing_the_lower_hemisphere_with_every_vertex_above() {
    let mut rng = Rng::new(0x24_02);
    let mut checked = 0;
    while checked < 150 {
        let Some((c1, r1)) = ring_above(&mut rng) else {
            continue;
        };
        let mut rings = vec![r1.clone()];
        let mut holes = vec![(c1, r1)];
        if rng.f64() < 0.3 {
            // A second hole, kept only if the two are disjoint (the validation decides).
            if let Some((c2, r2)) = ring_above(&mut rng) {
                rings.push(r2.clone());
                if SphericalPolygon::new(rings.clone()).is_err() {
                    continue;
                }
                holes.push((c2, r2));
            }
        }
        let region = SphericalPolygon::new(rings.clone()).unwrap().complement();
        assert!(region.rings().flatten().all(|p| p.z > 0.0));
        let over_holes = |f: &dyn Fn(DVec3) -> f64| -> f64 {
            holes.iter().map(|(c, r)| fan_quadrature(*c, r, f)).sum()
        };

        let lambert = 1.0 - over_holes(&|d| d.z.max(0.0) / PI);
        for (name, got, tol) in [
            ("exact", clamped_cosine_integral(&region), 1e-9),
            (
                "clip-free",
                clamped_cosine_integral_clip_free(&region),
                1e-9,
            ),
            ("rational", clamped_cosine_integral_rational(&region), 2e-6),
            (
                "ltc identity",
                ltc_integral(&region, DMat3::IDENTITY).unwrap(),
                1e-9,
            ),
        ] {
            assert!(
                (got - lambert).abs() <= tol,
                "{name}: {got} vs one minus quadrature {lambert} ({} rings)",
                holes.len()
            );
        }

        let m = table_form_map(&mut rng);
        let ltc = Ltc::from_inverse(m).unwrap();
        let reference = 1.0 - over_holes(&|d| ltc.density(d));
        for (name, got, tol) in [
            ("ltc", ltc_integral(&region, m).unwrap(), 1e-6),
            (
                "ltc rational",
                ltc_integral_rational(&region, m).unwrap(),
                1e-5,
            ),
        ] {
            assert!(
                (got - reference).abs() <= tol,
                "{name}: {got} vs one minus quadrature {reference}"
            );
        }

        let (cos_v, alpha) = (rng.range(1e-4, 1.0), rng.range(0.1, 1.0));
        let l = lookup(cos_v, alpha).unwrap();
        let lobe = l.ltc().unwrap();
        let ggx = ggx_polygon_integral(&region, cos_v, alpha, 1.0).unwrap();
        let expected = l.norm * (lobe.upper_hemisphere_mass() - over_holes(&|d| lobe.density(d)));
        assert!(
            (ggx - expected).abs() <= 1e-6,
            "ggx: {ggx} vs upper hemisphere minus holes {expected}"
        );
        checked += 1;
    }
}

/// The upper hemisphere as a region: a ring on the horizon, counter-clockwise seen from above.
fn upper_hemisphere() -> SphericalPolygon {
    SphericalPolygon::new(vec![vec![DVec3::X, DVec3::Y, -DVec3::X, -DVec3::Y]]).unwrap()
}

/// Stratified visible-normal estimate of the GGX directional albedo (`f cos` over the upper
/// hemisphere, no Fresnel) with its standard error: `n x n` strata, one jittered sample each.
fn brute_force_albedo(cos_v: f64, alpha: f64, n: usize, rng: &mut Rng) -> (f64, f64) {
    use arealight::glam::DVec2;
    use arealight::ltc::ggx_vndf_weight;
    let v = DVec3::new((1.0 - cos_v * cos_v).sqrt(), 0.0, cos_v);
    let (mut sum, mut sum2) = (0.0, 0.0);
    for i in 0..n {
        for j in 0..n {
            let u = DVec2::new(
                (i as f64 + rng.f64()) / n as f64,
                (j as f64 + rng.f64()) / n as f64,
            );
            let w = ggx_vndf_weight(v, alpha, u).map_or(0.0, |(_, w)| w);
            sum += w;
            sum2 += w * w;
        }
    }
    let m = (n * n) as f64;
    let mean = sum / m;
    // The stratified estimator's error is below that of plain sampling: a conservative sigma.
    (mean, ((sum2 / m - mean * mean).max(0.0) / m).sqrt())
}

/// Issue 24, reproducer 3: at grazing views and near-mirror roughness the whole upper hemisphere
/// integrated to 4.1e-6 (`cos_v = 0.025`) and to 1.064 (`cos_v = 0.03`, more than all the light)
/// against a table albedo of about 0.999: `norm` was interpolated on its own, not as the albedo
/// over the interpolated LTC's mass above the horizon. Checked against the brute-force albedo of
/// the GGX BRDF itself (VNDF sampling, 4.5 sigma plus the table's 1% albedo tolerance).
#[test]
fn reproducer_3_whole_upper_hemisphere_at_grazing_mirror_views() {
    let up = upper_hemisphere();
    let mut rng = Rng::new(3);
    for cos_v in [0.025, 0.03] {
        let alpha = 1e-4;
        let got = ggx_polygon_integral(&up, cos_v, alpha, 1.0).unwrap();
        let (albedo, sigma) = brute_force_albedo(cos_v, alpha, 256, &mut rng);
        assert!(
            (got - albedo).abs() <= 0.01 + 4.5 * sigma,
            "cos_v {cos_v}: {got} vs brute force {albedo} +- {sigma}"
        );
    }
}

/// For every view (`cos_v` from 1e-4 to 1, and beyond both ends) and roughness (0 to 1), the
/// LTC integral of the whole upper hemisphere times `norm` is the table's albedo: the identity
/// the tables' normalization stands for, between the nodes too. The rational path stays within
/// its documented bound of it (the image of the hemisphere, clipped, has a perimeter of at most
/// `2 pi`).
#[test]
fn whole_upper_hemisphere_gives_the_albedo_everywhere() {
    use arealight::ltc::EDGE_FACTOR_RATIONAL_MAX_ERROR;
    let up = upper_hemisphere();
    let mut worst: f64 = 0.0;
    for i in 0..=160 {
        let cos_v = 10f64.powf(-4.2 + 4.2 * i as f64 / 160.0);
        for k in 0..=60 {
            let r = k as f64 / 60.0;
            let alpha = r * r * 1.05;
            let l = lookup(cos_v, alpha).unwrap();
            let exact = ltc_integral(&up, l.m_inv).unwrap();
            let err = (l.norm * exact / l.albedo - 1.0).abs();
            assert!(
                err <= 1e-9,
                "({cos_v}, {alpha}): norm {} * {exact} vs albedo {}",
                l.norm,
                l.albedo
            );
            worst = worst.max(err);
            let rational = ltc_integral_rational(&up, l.m_inv).unwrap();
            assert!(
                (rational - exact).abs() <= EDGE_FACTOR_RATIONAL_MAX_ERROR + 1e-12,
                "({cos_v}, {alpha}): rational {rational} vs {exact}"
            );
        }
    }
    println!("whole upper hemisphere: largest relative deviation from the albedo {worst:.1e}");
}

/// Every cell of the committed table keeps the interpolated LTC's axis above the horizon with
/// at least half its mass there, for every pair of interpolation weights: `M^-1[0][0] > 0` at its
/// four nodes, and the determinant of the xz block, a product of interpolated entries, bounded
/// below by interval arithmetic over the cell's corner values (`min m00 * min m22` minus the
/// largest product of an `m02` and an `m20` in their ranges). Then `norm <= 2 albedo` at every
/// lookup, and a lookup never interpolates through a matrix that puts the lobe under the
/// horizon (which is what made the whole hemisphere integrate to 4.1e-6).
#[test]
fn every_cell_keeps_the_lobe_axis_above_the_horizon() {
    let t = arealight::ltc::LtcTable::ggx();
    let (nv, nr) = (t.view_nodes(), t.roughness_nodes());
    let mut tightest = f64::INFINITY;
    for k in 0..nr - 1 {
        for j in 0..nv - 1 {
            let corners = [(j, k), (j + 1, k), (j, k + 1), (j + 1, k + 1)]
                .map(|(a, b)| t.node_lookup(a, b).unwrap().m_inv);
            let range = |f: &dyn Fn(&DMat3) -> f64| {
                let v = corners.map(|m| f(&m));
                (
                    v.iter().copied().fold(f64::INFINITY, f64::min),
                    v.iter().copied().fold(f64::NEG_INFINITY, f64::max),
                )
            };
            let (lo00, _) = range(&|m| m.x_axis.x);
            let (lo22, _) = range(&|m| m.z_axis.z);
            let (lo02, hi02) = range(&|m| m.z_axis.x);
            let (lo20, hi20) = range(&|m| m.x_axis.z);
            let (lo11, _) = range(&|m| m.y_axis.y);
            assert!(lo00 > 0.0 && lo22 > 0.0 && lo11 > 0.0, "cell ({j}, {k})");
            let cross = [lo02 * lo20, lo02 * hi20, hi02 * lo20, hi02 * hi20]
                .into_iter()
                .fold(f64::NEG_INFINITY, f64::max);
            let det_lower = lo00 * lo22 - cross;
            assert!(
                det_lower > 0.0,
                "cell ({j}, {k}): determinant down to {det_lower}"
            );
            tightest = tightest.min(det_lower / (lo00 * lo22));
        }
    }
    println!("smallest determinant bound relative to m00 m22 over the cells: {tightest:.3}");
}

/// `0 <= ggx_polygon_integral <= albedo` (with `f0 = 1`) for random polygons, complements and
/// rings with holes, at random views from grazing (`cos_v` down to 1e-4 and below) to normal
/// and roughness from 0 to 1: no light gives more than the whole upper hemisphere.
#[test]
fn ggx_integral_is_never_above_the_albedo() {
    let mut rng = Rng::new(0x24_03);
    let mut checked = 0;
    while checked < 3000 {
        let c = rng.dir();
        let n = 3 + (rng.next_u64() % 8) as usize;
        let rho = 10f64.powf(rng.range(-3.0, 0.2));
        let Ok(p) = SphericalPolygon::new(vec![star_ring(&mut rng, c, n, rho, 0.5)]) else {
            continue;
        };
        let p = if rng.f64() < 0.3 { p.complement() } else { p };
        let cos_v = 10f64.powf(rng.range(-4.5, 0.0));
        let alpha = if rng.f64() < 0.2 {
            0.0
        } else {
            10f64.powf(rng.range(-5.0, 0.0))
        };
        let l = lookup(cos_v, alpha).unwrap();
        let got = ggx_polygon_integral(&p, cos_v, alpha, 1.0).unwrap();
        assert!(
            got >= 0.0 && got <= l.albedo * (1.0 + 1e-9),
            "({cos_v}, {alpha}): {got} vs albedo {}",
            l.albedo
        );
        checked += 1;
    }
}

/// Stratified visible-normal estimate of the GGX reflectance (`f cos`, no Fresnel) from the
/// directions in `region`, with its standard error (`n x n` strata, one jittered sample each).
fn brute_force_region(
    region: &SphericalPolygon,
    cos_v: f64,
    alpha: f64,
    n: usize,
    rng: &mut Rng,
) -> (f64, f64) {
    use arealight::glam::DVec2;
    use arealight::ltc::ggx_vndf_weight;
    let v = DVec3::new((1.0 - cos_v * cos_v).sqrt(), 0.0, cos_v);
    let (mut sum, mut sum2) = (0.0, 0.0);
    for i in 0..n {
        for j in 0..n {
            let u = DVec2::new(
                (i as f64 + rng.f64()) / n as f64,
                (j as f64 + rng.f64()) / n as f64,
            );
            let w = match ggx_vndf_weight(v, alpha, u) {
                Some((l, w)) if region.contains(l) => w,
                _ => 0.0,
            };
            sum += w;
            sum2 += w * w;
        }
    }
    let m = (n * n) as f64;
    let mean = sum / m;
    (mean, ((sum2 / m - mean * mean).max(0.0) / m).sqrt())
}

/// The light above the great circle through the mirror direction `m` of the view at `cos_v`
/// and the y axis: a quad with one edge through `m`, holding the half of a narrow lobe on the
/// zenith's side. Its response is a sensitive probe of where the lobe sits: moved by its own
/// width, the response goes from about half the albedo to about none or all of it.
fn half_lobe_light(cos_v: f64) -> SphericalPolygon {
    let s = (1.0 - cos_v * cos_v).sqrt();
    let m = DVec3::new(-s, 0.0, cos_v);
    let up = DVec3::new(cos_v, 0.0, s);
    let ring: Vec<DVec3> = [(-0.4, 0.0), (0.4, 0.0), (0.4, 0.3), (-0.4, 0.3)]
        .iter()
        .map(|&(y, w)| (m + DVec3::Y * y + up * w).normalize())
        .collect();
    let p = SphericalPolygon::new(vec![ring]).unwrap();
    if p.solid_angle() > 2.0 * PI {
        p.complement()
    } else {
        p
    }
}

/// Near-mirror lobes between the table's nodes sit where the GGX lobe is: the response to a
/// light whose edge runs through the mirror direction matches brute-force GGX (VNDF sampling,
/// 4.5 sigma) within 3% of the albedo, at views between nodes from near-normal to grazing
/// (`cos_v` down to 0.008) and `alpha` from 1e-4 to 3e-3. The lobes are narrower than the node
/// spacing (0.01 degrees against 1.3 to 1.8): interpolating the nodes' matrices as stored (rows
/// of different lengths, offsets linear in `sqrt(1 - cos)` or in `ln cos`) turned the lobe's
/// axis past its own width, and the response came out near 0 or near the whole albedo.
#[test]
fn near_mirror_lobes_sit_at_the_mirror_direction_between_nodes() {
    let mut rng = Rng::new(0x24_04);
    let mut worst: f64 = 0.0;
    for &cos_v in &[0.95, 0.7, 0.4, 0.15, 0.05, 0.02, 0.008] {
        // At the most grazing view the fit itself is off by more (`fit::shading_error`, about
        // 0.2 there at alpha 3e-3): only the nearest-mirror lobes.
        let alphas: &[f64] = if cos_v < 0.01 {
            &[1e-4, 3e-4, 1e-3]
        } else {
            &[1e-4, 3e-4, 1e-3, 3e-3]
        };
        for &alpha in alphas {
            // Off the nodes: a random shift of up to a few percent of the view cosine.
            let cos_v: f64 = cos_v * rng.range(0.97, 1.0);
            let light = half_lobe_light(cos_v);
            let l = lookup(cos_v, alpha).unwrap();
            let got = ggx_polygon_integral(&light, cos_v, alpha, 1.0).unwrap();
            let (bf, sigma) = brute_force_region(&light, cos_v, alpha, 160, &mut rng);
            let err = (got - bf).abs() / l.albedo;
            assert!(
                (got - bf).abs() <= 0.03 * l.albedo + 4.5 * sigma,
                "({cos_v}, {alpha}): LTC {got} vs brute force {bf} +- {sigma} (albedo {})",
                l.albedo
            );
            worst = worst.max(err);
        }
    }
    println!("half-lobe lights: largest |LTC - brute force| / albedo {worst:.4}");
}

/// A polygon for the grazing generator: a star-shaped ring about a direction near the mirror
/// direction of the view (so that the narrow lobe meets it), from `1e-4` to 1 rad across,
/// optionally complemented, with one vertex moved to `1e-16..1e-9` above or below the horizon
/// when `horizon_vertex`.
fn grazing_polygon(rng: &mut Rng, cos_v: f64, horizon_vertex: bool) -> Option<SphericalPolygon> {
    let s = (1.0 - cos_v * cos_v).sqrt();
    let mirror = DVec3::new(-s, 0.0, cos_v);
    let c = (mirror
        + DVec3::new(
            rng.range(-0.3, 0.3),
            rng.range(-0.3, 0.3),
            rng.range(-0.05, 0.2),
        ))
    .normalize();
    let rho = 10f64.powf(rng.range(-4.0, 0.0));
    let n = 3 + (rng.next_u64() % 6) as usize;
    let mut ring = star_ring(rng, c, n, rho, 0.5);
    if horizon_vertex {
        let k = (rng.next_u64() % n as u64) as usize;
        let h = 10f64.powf(rng.range(-16.0, -9.0)) * if rng.f64() < 0.5 { 1.0 } else { -1.0 };
        let v = ring[k];
        let horiz = (v.x * v.x + v.y * v.y).sqrt();
        let f = (1.0 - h * h).sqrt() / horiz;
        ring[k] = DVec3::new(v.x * f, v.y * f, h);
    }
    let p = SphericalPolygon::new(vec![ring]).ok()?;
    Some(if rng.f64() < 0.2 { p.complement() } else { p })
}

proptest::proptest! {
    #![proptest_config(proptest::prelude::ProptestConfig {
        cases: support::cases(48),
        ..proptest::prelude::ProptestConfig::default()
    })]

    /// Grazing views (`cos_v` 1e-4 to 0.05, log-uniform) and near-mirror roughness (0 to 0.05,
    /// `alpha` its square), polygons near the mirror direction with a vertex at the horizon
    /// half of the time: `ggx_polygon_integral` with `f0 = 1` is finite, in `[0, albedo]`, and
    /// over `norm` it is the LTC's probability of the polygon's part above the horizon, which
    /// sampling the LTC itself estimates (stratified, 4.5 sigma of the binomial count).
    /// `Undecidable` counts as an answer (its rate is printed by the scene test and the report).
    #[test]
    fn grazing_ggx_integrals_match_sampling_of_the_ltc(seed in proptest::prelude::any::<u64>()) {
        use arealight::glam::DVec2;
        let mut rng = Rng::new(seed);
        let cos_v = 1e-4 * 500f64.powf(rng.f64());
        let roughness = rng.range(0.0, 0.05);
        let alpha = roughness * roughness;
        let at_horizon = rng.f64() < 0.5;
        let Some(p) = grazing_polygon(&mut rng, cos_v, at_horizon) else { return Ok(()); };
        let l = lookup(cos_v, alpha).unwrap();
        let got = match ggx_polygon_integral(&p, cos_v, alpha, 1.0) {
            Ok(v) => v,
            Err(e) => {
                proptest::prop_assert!(e.is_undecidable(), "{}", e);
                return Ok(());
            }
        };
        proptest::prop_assert!(got.is_finite() && (0.0..=l.albedo * (1.0 + 1e-9)).contains(&got),
            "({}, {}): {} vs albedo {}", cos_v, alpha, got, l.albedo);
        let ltc = l.ltc().unwrap();
        let n = 256;
        let mut hits = 0usize;
        for i in 0..n {
            for j in 0..n {
                let u = DVec2::new((i as f64 + rng.f64()) / n as f64, (j as f64 + rng.f64()) / n as f64);
                let w = ltc.sample(u);
                if w.z > 0.0 && p.contains(w) {
                    hits += 1;
                }
            }
        }
        let m = (n * n) as f64;
        let q = hits as f64 / m;
        let sigma = (q.max(1.0 / m) * (1.0 - q).max(1.0 / m) / m).sqrt();
        let want = got / l.norm;
        proptest::prop_assert!((want - q).abs() <= 4.5 * sigma + 1e-9,
            "({}, {}): integral {} vs sampled {} +- {}\nP = {:?}", cos_v, alpha, want, q, sigma, p);
    }
}

/// From the grazing generator: a small pentagon below the horizon but for one vertex `4.5e-12`
/// above it (a sliver above the horizon, reproducer 1's configuration), whose clip at the
/// shading horizon the sphere layer gets wrong (larger than the region); the clip of its
/// complement is consistent, and `ggx_polygon_integral` takes the region's part as the upper
/// hemisphere less the complement's part. Against sampling of the LTC itself (4.5 sigma).
/// Without that second route the result was `Undecidable` on 0.62% of the generator's
/// polygons (1.2% of those with a vertex at the horizon); with it, none of 50 000, and the 348
/// that take it agree with sampling within 0.9 sigma.
#[test]
fn sliver_above_the_horizon_through_the_complements_clip() {
    use arealight::glam::DVec2;
    let p = SphericalPolygon::new(vec![vec![
        v(
            -0.99911445229963,
            -0.04197530436522014,
            -0.0028956915335498663,
        ),
        v(
            -0.9991178255334818,
            -0.04188922682552581,
            -0.0029771424566105297,
        ),
        v(
            -0.9991171631175485,
            -0.04190076477778337,
            -0.003036490569556565,
        ),
        v(
            -0.9991140348507329,
            -0.04197530825931199,
            -0.0030362577005032788,
        ),
        v(
            -0.9991161273946766,
            -0.042035270664815765,
            4.49929413672989e-12,
        ),
    ]])
    .unwrap();
    let (cos_v, alpha) = (0.00028661310760157496, 0.038993945272868535f64.powi(2));
    let l = lookup(cos_v, alpha).unwrap();
    let got = ggx_polygon_integral(&p, cos_v, alpha, 1.0).unwrap() / l.norm;
    let ltc = l.ltc().unwrap();
    let mut rng = Rng::new(5);
    let n = 400;
    let mut hits = 0usize;
    for i in 0..n {
        for j in 0..n {
            let u = DVec2::new(
                (i as f64 + rng.f64()) / n as f64,
                (j as f64 + rng.f64()) / n as f64,
            );
            let w = ltc.sample(u);
            if w.z > 0.0 && p.contains(w) {
                hits += 1;
            }
        }
    }
    let m = (n * n) as f64;
    let q = hits as f64 / m;
    let sigma = (q.max(1.0 / m) * (1.0 - q).max(1.0 / m) / m).sqrt();
    assert!(
        (got - q).abs() <= 4.5 * sigma + 1e-12,
        "{got} vs sampled {q} +- {sigma}"
    );
}

/// The grazing generator of `grazing_ggx_integrals_match_sampling_of_the_ltc` on fixed seeds, as
/// a census of give-ups: how often `ggx_polygon_integral` says `Undecidable`, per family (a
/// vertex within `1e-16..1e-9` of the horizon or not), which must stay below 0.1% of the valid
/// polygons (`LTC_CENSUS=N` polygons per family, default 5000; every value is also checked to
/// lie in `[0, albedo]`). Printed with `--nocapture`.
#[test]
fn census_of_the_grazing_generator() {
    let cases: u64 = std::env::var("LTC_CENSUS")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(5000);
    for at_horizon in [true, false] {
        let (mut valid, mut undecidable) = (0u64, 0u64);
        for seed in 0..cases {
            let mut rng = Rng::new(((seed << 1) | u64::from(at_horizon)) ^ 0x6A21_0000);
            let cos_v = 1e-4 * 500f64.powf(rng.f64());
            let roughness = rng.range(0.0, 0.05);
            let alpha = roughness * roughness;
            let Some(p) = grazing_polygon(&mut rng, cos_v, at_horizon) else {
                continue;
            };
            valid += 1;
            let albedo = lookup(cos_v, alpha).unwrap().albedo;
            match ggx_polygon_integral(&p, cos_v, alpha, 1.0) {
                Ok(v) => assert!(
                    v.is_finite() && (0.0..=albedo * (1.0 + 1e-9)).contains(&v),
                    "seed {seed}: {v} vs albedo {albedo}"
                ),
                Err(e) if e.is_undecidable() => undecidable += 1,
                Err(e) => panic!("seed {seed}: {e}"),
            }
        }
        println!(
            "grazing generator, vertex at the horizon {at_horizon}: {valid} valid polygons, \
             {undecidable} undecidable"
        );
        assert!(
            undecidable * 1000 < valid.max(1),
            "{undecidable} of {valid} undecidable"
        );
    }
}
