//! The clamped-cosine integral against independent references: Gauss–Legendre quadrature for
//! polygons above the horizon, stratified Monte Carlo (with a stated bound) for polygons crossing
//! it, the signed-integral identity, and the exact-clip vs clip-free agreement.

mod support;

use arealight::glam::DVec3;
use arealight::ltc::{clamped_cosine_integral, clamped_cosine_integral_clip_free};
use arealight::sphere::SphericalPolygon;
use proptest::prelude::*;
use std::f64::consts::PI;
use support::Rng;
use support::sphere::{
    assert_mc_agrees, boundary_edges, crossed_cells, great_circle, mc_integral, polar, star_ring,
    triangle_quadrature,
};

/// A random valid polygon (star-shaped rings, complements, rings with holes) around a center
/// whose height above the horizon is drawn too, so that many polygons cross it.
fn polygon(seed: u64) -> Option<SphericalPolygon> {
    let mut rng = Rng::new(seed);
    let c = rng.dir();
    let n = 3 + (rng.next_u64() % 12) as usize;
    let rho = rng.range(0.02, 1.5);
    let ring = star_ring(&mut rng, c, n, rho, 0.5);
    match rng.next_u64() % 3 {
        0 => SphericalPolygon::new(vec![ring]).ok(),
        1 => SphericalPolygon::new(vec![ring])
            .ok()
            .map(|p| p.complement()),
        _ => {
            let m = 3 + (rng.next_u64() % 5) as usize;
            let mut hole = star_ring(&mut rng, c, m, 0.2 * rho, 0.8);
            hole.reverse();
            SphericalPolygon::new(vec![ring, hole]).ok()
        }
    }
}

/// The documented error bound of the rational edge factor on `p`, plus `slack` for rounding:
/// [`EDGE_FACTOR_RATIONAL_MAX_ERROR`] times the perimeter of `p` clipped to the upper hemisphere,
/// over `2 pi`.
fn rational_bound(p: &SphericalPolygon, slack: f64) -> f64 {
    use arealight::ltc::EDGE_FACTOR_RATIONAL_MAX_ERROR;
    let perimeter: f64 = boundary_edges(&p.clip_to_hemisphere(DVec3::Z))
        .map(|(a, b)| a.cross(b).length().atan2(a.dot(b)))
        .sum();
    EDGE_FACTOR_RATIONAL_MAX_ERROR * perimeter / (2.0 * PI) + slack
}

/// A random polygon, a random map of the fitted tables' form (`y` unchanged), the exact
/// clamped-cosine integral of the mapped polygon and the documented error bound of the rational
/// edge factor on it.
fn ltc_form_case(
    seed: u64,
    salt: u64,
) -> Option<(SphericalPolygon, arealight::glam::DMat3, f64, f64)> {
    use arealight::glam::DMat3;
    let p = polygon(seed)?;
    let mut rng = Rng::new(seed ^ salt);
    let (a, d) = (rng.range(1e-3, 3.0), rng.range(1e-3, 3.0));
    let (b, c) = (rng.range(-2.0, 2.0), rng.range(-2.0, 2.0));
    let m = DMat3::from_cols(DVec3::new(a, 0.0, c), DVec3::Y, DVec3::new(b, 0.0, d));
    let t = p.transformed(m).ok()?;
    let exact = clamped_cosine_integral(&t);
    Some((p, m, exact, rational_bound(&t, 1e-12)))
}

#[test]
fn lambert_matches_quadrature_above_the_horizon() {
    let mut rng = Rng::new(11);
    let mut checked = 0;
    for _ in 0..200 {
        let c = rng.dir();
        let n = 3 + (rng.next_u64() % 9) as usize;
        let rho = rng.range(1e-3, 0.8);
        let ring = star_ring(&mut rng, c, n, rho, 0.5);
        if ring.iter().any(|p| p.z <= 0.0) {
            continue;
        }
        let poly = SphericalPolygon::new(vec![ring.clone()]).unwrap();
        // Fan from the star center: independent of the crate's own triangulation and clipping.
        let quad: f64 = (0..n)
            .map(|i| triangle_quadrature(c, ring[i], ring[(i + 1) % n], 24, |d| d.z.max(0.0) / PI))
            .sum();
        let exact = clamped_cosine_integral(&poly);
        assert!((exact - quad).abs() <= 1e-9, "{exact} vs quadrature {quad}");
        // The complement sees the rest of the hemisphere.
        let rest = clamped_cosine_integral(&poly.complement());
        assert!((exact + rest - 1.0).abs() <= 1e-12);
        checked += 1;
    }
    assert!(
        checked > 40,
        "only {checked} polygons were above the horizon"
    );
}

#[test]
fn lambert_matches_monte_carlo_across_the_horizon() {
    let mut done = 0;
    for seed in 0..40u64 {
        let Some(p) = polygon(seed) else { continue };
        if p.rings().flatten().all(|v| v.z > 0.0) {
            continue;
        }
        let mut rng = Rng::new(seed ^ 0x1A3B);
        let mc = mc_integral(&mut rng, 96, 192, |d| {
            if p.contains(d) {
                d.z.max(0.0) / PI
            } else {
                0.0
            }
        });
        let cells = crossed_cells(boundary_edges(&p).chain(great_circle(DVec3::Z)), 96, 192);
        assert_mc_agrees(
            clamped_cosine_integral(&p),
            mc,
            cells,
            "clamped cosine vs Monte Carlo",
        );
        done += 1;
    }
    assert!(done > 10);
}

#[test]
fn hemisphere_with_hole_at_the_zenith() {
    // Everything above the horizon except a cap of radius r at the zenith: 1 - sin(r)^2 exactly
    // for a disc; a 64-gon inscribed in it loses a little, measured by quadrature.
    let n = 64;
    let r = 0.4f64;
    let cap: Vec<DVec3> = (0..n)
        .map(|i| {
            let t = 2.0 * PI * i as f64 / n as f64;
            DVec3::new(r.sin() * t.cos(), r.sin() * t.sin(), r.cos())
        })
        .collect();
    let inside_cap: f64 = (0..n)
        .map(|i| triangle_quadrature(DVec3::Z, cap[i], cap[(i + 1) % n], 16, |d| d.z / PI))
        .sum();
    let mut hole = cap.clone();
    hole.reverse();
    let p = SphericalPolygon::new(vec![hole]).unwrap();
    assert!((clamped_cosine_integral(&p) - (1.0 - inside_cap)).abs() < 1e-12);
    assert!((clamped_cosine_integral_clip_free(&p) - (1.0 - inside_cap)).abs() < 1e-12);
    assert!(inside_cap < r.sin().powi(2) && inside_cap > 0.99 * r.sin().powi(2));
}

proptest! {
    #![proptest_config(ProptestConfig { cases: support::cases(512), ..ProptestConfig::default() })]

    /// The clip-free formula (thesis eq. 4.6/4.7) agrees with exact clipping to 1e-12.
    #[test]
    fn clip_free_agrees_with_exact_clip(seed in any::<u64>()) {
        let Some(p) = polygon(seed) else { return Ok(()); };
        let (a, b) = (clamped_cosine_integral(&p), clamped_cosine_integral_clip_free(&p));
        prop_assert!((a - b).abs() <= 1e-12, "exact {} vs clip-free {}", a, b);
        prop_assert!((0.0..=1.0).contains(&a));
    }

    /// (1/pi) * integral of z over P (Stokes, no clipping) = I(P) - I(P mirrored in the horizon).
    #[test]
    fn signed_integral_identity(seed in any::<u64>()) {
        let Some(p) = polygon(seed) else { return Ok(()); };
        let mirrored = SphericalPolygon::new(
            p.rings()
                .map(|r| r.iter().rev().map(|v| DVec3::new(v.x, v.y, -v.z)).collect())
                .collect(),
        )
        .unwrap();
        // Signed integral by the boundary sum on the unclipped rings.
        let mut signed = 0.0;
        for r in p.rings() {
            for i in 0..r.len() {
                let (a, b) = (r[i], r[(i + 1) % r.len()]);
                let c = a.cross(b);
                signed += c.length().atan2(a.dot(b)) / c.length() * c.z;
            }
        }
        signed /= 2.0 * PI;
        let diff = clamped_cosine_integral(&p) - clamped_cosine_integral(&mirrored);
        prop_assert!((diff - signed).abs() <= 1e-12, "{} vs {}", diff, signed);
    }
}

#[test]
fn rational_edge_factor_error_is_as_documented() {
    use arealight::ltc::{EDGE_FACTOR_RATIONAL_MAX_ERROR, edge_factor_rational};
    let mut worst: f64 = 0.0;
    let n = 400_000;
    for i in 0..=n {
        // Dense in cos(theta), including the ends; x -> -1 approached to 1e-9.
        let x = -1.0 + 1e-9 + (2.0 - 1e-9) * i as f64 / n as f64;
        let exact = if x >= 1.0 {
            1.0
        } else {
            x.acos() / (1.0 - x * x).sqrt()
        };
        worst = worst.max((edge_factor_rational(x) / exact - 1.0).abs());
    }
    assert!(
        worst <= EDGE_FACTOR_RATIONAL_MAX_ERROR,
        "max relative error {worst}"
    );
    assert!(
        worst > 0.5 * EDGE_FACTOR_RATIONAL_MAX_ERROR,
        "documented bound is loose: {worst}"
    );
}

proptest! {
    #![proptest_config(ProptestConfig { cases: support::cases(256), ..ProptestConfig::default() })]

    /// The rational variant stays within its documented error of the exact integral.
    #[test]
    fn rational_integral_within_bound(seed in any::<u64>()) {
        use arealight::ltc::clamped_cosine_integral_rational;
        let Some(p) = polygon(seed) else { return Ok(()); };
        let bound = rational_bound(&p, 1e-14);
        let (a, b) = (clamped_cosine_integral(&p), clamped_cosine_integral_rational(&p));
        prop_assert!((a - b).abs() <= bound, "{} vs {} (bound {})", a, b, bound);
    }

    /// Integrating an LTC over a polygon (transform + clamped cosine) equals quadrature of the
    /// LTC density over the polygon (HDHN16 eq. 14).
    #[test]
    fn ltc_integral_matches_density_quadrature(seed in any::<u64>()) {
        use arealight::glam::DMat3;
        use arealight::ltc::{Ltc, ltc_integral};
        let mut rng = Rng::new(seed);
        let m_inv = DMat3::from_cols(
            DVec3::new(rng.range(0.3, 2.0), 0.0, rng.range(-0.8, 0.8)),
            DVec3::new(0.0, rng.range(0.3, 2.0), 0.0),
            DVec3::new(rng.range(-0.5, 0.5), 0.0, 1.0),
        );
        prop_assume!(m_inv.determinant() > 0.05);
        let c = DVec3::new(rng.range(-0.5, 0.5), rng.range(-0.5, 0.5), 1.0).normalize();
        let n = 3 + (rng.next_u64() % 6) as usize;
        let rho = rng.range(0.05, 0.5);
        let ring = star_ring(&mut rng, c, n, rho, 0.7);
        let poly = SphericalPolygon::new(vec![ring.clone()]).unwrap();
        let ltc = Ltc::from_inverse(m_inv).unwrap();
        // 48 points per triangle: 24 left errors above 1e-8 on peaked densities (seed
        // 13682615606743527589: 1.2e-8 off, where 96 points agree with both paths to 1e-10).
        let quad: f64 = (0..n)
            .map(|i| triangle_quadrature(c, ring[i], ring[(i + 1) % n], 48, |d| ltc.density(d)))
            .sum();
        let exact = ltc_integral(&poly, m_inv).unwrap();
        prop_assert!((exact - quad).abs() <= 1e-8, "{} vs quadrature {}", exact, quad);
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: support::cases(512), ..ProptestConfig::default() })]

    /// Matrices of the fitted tables' form (`y` unchanged), which take their own transform path,
    /// agree with transform + exact clip too.
    #[test]
    fn ltc_form_matrices_agree_with_exact(seed in any::<u64>()) {
        use arealight::ltc::{ltc_integral, ltc_integral_rational};
        let Some((p, m, exact, bound)) = ltc_form_case(seed, 0x2C7) else { return Ok(()); };
        prop_assert!((exact - ltc_integral(&p, m).unwrap()).abs() <= 1e-12);
        prop_assert!((exact - ltc_integral_rational(&p, m).unwrap()).abs() <= bound);
    }

    /// The integral depends on the map only up to a positive factor: scaling it by anything from
    /// 1e-300 to 1e300 changes nothing (the clip-free path once overflowed in its crossing points
    /// and products of squared lengths beyond about 1e60, returning garbage or NaN, and the
    /// exact path rejected maps whose determinant underflowed).
    #[test]
    fn ltc_integrals_ignore_the_scale_of_the_map(seed in any::<u64>(), exponent in -300i32..=300) {
        use arealight::ltc::{ltc_integral, ltc_integral_rational};
        let Some((p, m, exact, bound)) = ltc_form_case(seed, 0x5CA1E) else { return Ok(()); };
        let scaled = m * 10f64.powi(exponent);
        let got = ltc_integral(&p, scaled);
        prop_assert!(matches!(got, Ok(v) if (v - exact).abs() <= 1e-12), "{:?} vs {}", got, exact);
        let got = ltc_integral_rational(&p, scaled);
        prop_assert!(matches!(got, Ok(v) if (v - exact).abs() <= bound), "{:?} vs {}", got, exact);
    }

    /// Regions whose boundary lies wholly above the horizon, from tiny (down to 1e-12 rad) to
    /// large, and their complements: the clip-free path decides whether the horizon is inside
    /// from the sign of the edge sum, or leaves a too-close call to the exact path.
    #[test]
    fn clip_free_decides_regions_above_the_horizon(seed in any::<u64>()) {
        use arealight::glam::DMat3;
        use arealight::ltc::{clamped_cosine_integral_rational, ltc_integral_rational};
        let mut rng = Rng::new(seed);
        let c = DVec3::new(rng.range(-1.0, 1.0), rng.range(-1.0, 1.0), rng.range(0.05, 1.0)).normalize();
        let rho = 10f64.powf(rng.range(-12.0, -0.5)).min(0.9 * c.z.asin());
        let n = 3 + (rng.next_u64() % 8) as usize;
        let Ok(p) = SphericalPolygon::new(vec![star_ring(&mut rng, c, n, rho, 0.5)]) else {
            return Ok(());
        };
        for q in [p.clone(), p.complement()] {
            let exact = clamped_cosine_integral(&q);
            let fast = clamped_cosine_integral_clip_free(&q);
            prop_assert!((exact - fast).abs() <= 1e-12, "rho {}: {} vs {}", rho, exact, fast);
            let rational = clamped_cosine_integral_rational(&q);
            prop_assert!((exact - rational).abs() <= 1e-6, "rho {}: {} vs {}", rho, exact, rational);
            let fast_rational = ltc_integral_rational(&q, DMat3::IDENTITY).unwrap();
            prop_assert!((exact - fast_rational).abs() <= 1e-6, "rho {}: {} vs {}", rho, exact, fast_rational);
        }
    }

    /// The stack-only clip-free LTC path agrees with transform + exact clip, for any matrix
    /// (mirroring ones included), and the rational path stays within its bound.
    #[test]
    fn fast_ltc_paths_agree_with_exact(seed in any::<u64>()) {
        use arealight::glam::DMat3;
        use arealight::ltc::{ltc_integral, ltc_integral_rational};
        let Some(p) = polygon(seed) else { return Ok(()); };
        let mut rng = Rng::new(seed ^ 0x17C);
        let m = DMat3::from_cols(rng.dir() * rng.range(0.2, 3.0), rng.dir(), rng.dir() * rng.range(0.2, 3.0));
        let Ok(t) = p.transformed(m) else { return Ok(()); };
        let exact = clamped_cosine_integral(&t);
        let fast = ltc_integral(&p, m).unwrap();
        prop_assert!((exact - fast).abs() <= 1e-12, "{} vs {}", exact, fast);
        let rational = ltc_integral_rational(&p, m).unwrap();
        let bound = rational_bound(&t, 1e-12);
        prop_assert!((exact - rational).abs() <= bound, "{} vs {} (bound {})", exact, rational, bound);
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: support::cases(512), ..ProptestConfig::default() })]

    /// The integrals over bare rings of directions of any length (`clamped_cosine_integral_rings`,
    /// `ltc_integral_rings`: no polygon, no normalization) agree with the exact clip of the
    /// polygon they bound, every vertex scaled by its own factor from 1e-3 to 1e3: under the
    /// identity, a map of the tables' form and a general map (mirroring ones go to the exact
    /// path).
    #[test]
    fn ring_integrals_agree_with_the_exact_clip(seed in any::<u64>()) {
        use arealight::glam::DMat3;
        use arealight::ltc::{clamped_cosine_integral_rings, ltc_integral, ltc_integral_rings};
        let Some((p, table_map, exact_table, _)) = ltc_form_case(seed, 0x21A6) else {
            return Ok(());
        };
        let mut rng = Rng::new(seed ^ 0x5CA1);
        let rings: Vec<Vec<DVec3>> = p
            .rings()
            .map(|r| r.iter().map(|&v| v * 10f64.powf(rng.range(-3.0, 3.0))).collect())
            .collect();
        let rings = || rings.iter().map(Vec::as_slice);
        let exact = clamped_cosine_integral(&p);
        let got = clamped_cosine_integral_rings(rings()).unwrap();
        prop_assert!((exact - got).abs() <= 1e-12, "{} vs {}", exact, got);
        let got = ltc_integral_rings(rings(), table_map).unwrap();
        prop_assert!((exact_table - got).abs() <= 1e-12, "{} vs {}", exact_table, got);
        let general = DMat3::from_cols(rng.dir() * rng.range(0.2, 3.0), rng.dir(), rng.dir() * rng.range(0.2, 3.0));
        if let Ok(t) = p.transformed(general) {
            let exact = clamped_cosine_integral(&t);
            let got = ltc_integral_rings(rings(), general).unwrap();
            prop_assert!((exact - got).abs() <= 1e-12, "{} vs {}", exact, got);
            prop_assert!((ltc_integral(&p, general).unwrap() - got).abs() <= 1e-12);
        }
    }
}

/// Where the clip-free path hands over (a vertex on the horizon), the ring integrals take the
/// exact path on the validated polygon; no ring is zero, a ring that is not a polygon is an error
/// there; no rings is the empty region.
#[test]
fn ring_integrals_hand_over_on_the_horizon() {
    use arealight::glam::DMat3;
    use arealight::ltc::{clamped_cosine_integral_rings, ltc_integral, ltc_integral_rings};
    // A triangle with a vertex exactly on the horizon, lengths 2, 3 and 0.5.
    let ring = [
        DVec3::new(2.0, 0.0, 0.0),
        DVec3::new(0.0, 1.5, 1.5 * 3f64.sqrt()),
        DVec3::new(-0.2, -0.3, 0.3),
    ];
    let p = SphericalPolygon::new(vec![ring.iter().map(|v| v.normalize()).collect()]).unwrap();
    let got = clamped_cosine_integral_rings([&ring[..]]).unwrap();
    assert!((got - clamped_cosine_integral(&p)).abs() <= 1e-15, "{got}");
    let m = DMat3::from_cols(
        DVec3::new(1.3, 0.0, -0.4),
        DVec3::Y,
        DVec3::new(0.2, 0.0, 0.9),
    );
    let got = ltc_integral_rings([&ring[..]], m).unwrap();
    assert!((got - ltc_integral(&p, m).unwrap()).abs() <= 1e-15, "{got}");
    // On the exact path, a zero vertex and a self-crossing ring are errors.
    let zero = [ring[0], ring[1], DVec3::ZERO];
    assert!(clamped_cosine_integral_rings([&zero[..]]).is_err());
    // A bow tie with a vertex on the horizon: its edges 0-1 and 2-3 cross at the zenith.
    let bow = [
        DVec3::new(1.0, 1.0, 0.0),
        DVec3::new(-1.0, -1.0, 1.0),
        DVec3::new(1.0, -1.0, 1.0),
        DVec3::new(-1.0, 1.0, 1.0),
    ];
    assert!(clamped_cosine_integral_rings([&bow[..]]).is_err());
    assert_eq!(
        clamped_cosine_integral_rings(std::iter::empty()).unwrap(),
        0.0
    );
    assert_eq!(ltc_integral_rings(std::iter::empty(), m).unwrap(), 0.0);
}

/// Quads take a kernel of their own in the clip-free path. Every pattern of vertices above and
/// below the horizon (a run of one, two or three vertices above in every position, two runs, none,
/// all) under the identity, two table maps and a general map, against the exact clip.
#[test]
fn quads_match_the_exact_clip_for_every_horizon_pattern() {
    use arealight::glam::DMat3;
    use arealight::ltc::{lookup, ltc_integral, ltc_integral_rational};
    let maps = [
        DMat3::IDENTITY,
        lookup(0.6, 0.2).unwrap().m_inv,
        lookup(0.1, 0.05).unwrap().m_inv,
        DMat3::from_cols(
            DVec3::new(1.0, 0.2, 0.1),
            DVec3::new(-0.1, 0.9, 0.3),
            DVec3::new(0.2, -0.3, 1.1),
        ),
    ];
    let mut rng = Rng::new(0x0ad5);
    let mut quads = Vec::new();
    // Bands around the normal, alternately above and below: four crossings.
    for k in 0..8 {
        let z = |j: usize| if (j + k).is_multiple_of(2) { 0.3 } else { -0.3 };
        let phi = |j: usize| 0.4 * k as f64 + PI / 2.0 * j as f64;
        quads.push(
            (0..4)
                .map(|j| DVec3::new(phi(j).cos(), phi(j).sin(), z(j)))
                .collect(),
        );
    }
    // Quads about centres near the horizon, small to large.
    for _ in 0..600 {
        let c = DVec3::new(
            rng.range(-1.0, 1.0),
            rng.range(-1.0, 1.0),
            rng.range(-0.5, 0.5),
        );
        let rho = rng.range(0.1, 1.4);
        quads.push(star_ring(&mut rng, c.normalize(), 4, rho, 0.5));
    }
    let mut seen = [0usize; 16];
    for ring in quads {
        let Ok(p) = SphericalPolygon::new(vec![ring.clone()]) else {
            continue;
        };
        for m in maps {
            let Ok(t) = p.transformed(m) else {
                continue;
            };
            let mask = (0..4).fold(0, |b, j| b | usize::from((m * ring[j]).z > 0.0) << j);
            seen[mask] += 1;
            let exact = clamped_cosine_integral(&t);
            let fast = ltc_integral(&p, m).unwrap();
            assert!(
                (fast - exact).abs() <= 1e-12,
                "pattern {mask:04b}: {fast} vs {exact} for {ring:?}"
            );
            let rational = ltc_integral_rational(&p, m).unwrap();
            let bound = rational_bound(&t, 1e-12);
            assert!(
                (rational - exact).abs() <= bound,
                "pattern {mask:04b}: {rational} vs {exact} (bound {bound}) for {ring:?}"
            );
        }
    }
    assert!(
        seen.iter().all(|&k| k > 0),
        "patterns not reached: {seen:?}"
    );
}

/// Polygons whose horizon arcs total exactly half a circle (edges crossing the horizon at
/// antipodal points, turned about the normal): the clip-free paths take the arcs' angle from the
/// argument of a product that lies on the negative real axis up to rounding. The rational path
/// once clamped `sin(theta)` there and lost the whole half circle.
/// Single rings whose first vertex is clearly above the horizon go through the paired loop of the
/// clip-free path (two edges per step, the second ending at the first vertex again at the end of
/// the ring), which hands over to the crossing bookkeeping at the first pair with a vertex that is
/// not clearly above. Every handover position, for rings of odd and even length, with one or two
/// consecutive vertices below the horizon or none, against the exact clip. (Quads take their own
/// kernel, tested in `quads_match_the_exact_clip_for_every_horizon_pattern`; here they check it
/// too.)
#[test]
fn paired_above_loop_hands_over_at_every_position() {
    use arealight::glam::DMat3;
    use arealight::ltc::{lookup, ltc_integral, ltc_integral_rational};
    let c = DVec3::new(0.35f64.cos(), 0.0, 0.35f64.sin());
    let table_map = lookup(0.6, 0.2).unwrap().m_inv;
    let mut handovers = 0;
    for n in 3..=9 {
        // Vertices 0 and 1 straddle the azimuth of the ring's lowest point (that of `polar`'s
        // frame), so that they dip below the horizon when pushed out.
        let (u, v) = c.any_orthonormal_pair();
        let step = 2.0 * PI / n as f64;
        let theta = |j: usize| (-v.z).atan2(-u.z) + step * (j as f64 - 0.5);
        for dipped in 0..=2 {
            let ring: Vec<DVec3> = (0..n)
                .map(|j| polar(c, if j < dipped { 1.2 } else { 0.3 }, theta(j)))
                .collect();
            let below = ring.iter().filter(|v| v.z < -0.05).count();
            assert_eq!(
                below, dipped,
                "n = {n}: the dipped vertices must be below the horizon"
            );
            for start in 0..n {
                let mut r = ring.clone();
                r.rotate_left(start);
                handovers += usize::from(r[0].z > 0.0 && dipped > 0);
                let p = SphericalPolygon::new(vec![r]).unwrap();
                for m in [DMat3::IDENTITY, table_map] {
                    let t = p.transformed(m).unwrap();
                    let exact = clamped_cosine_integral(&t);
                    let fast = ltc_integral(&p, m).unwrap();
                    let rational = ltc_integral_rational(&p, m).unwrap();
                    assert!(
                        (fast - exact).abs() < 1e-12,
                        "n {n} start {start}: {fast} vs {exact}"
                    );
                    let bound = rational_bound(&t, 1e-12);
                    assert!(
                        (rational - exact).abs() <= bound,
                        "n {n} start {start}: {rational} vs {exact} (bound {bound})"
                    );
                }
            }
        }
    }
    assert!(handovers > 40, "only {handovers} rings handed over");
}

#[test]
fn horizon_arcs_of_half_a_circle() {
    use arealight::glam::{DMat3, DQuat};
    use arealight::ltc::{ltc_integral, ltc_integral_rational};
    for (k, shift) in (0..64).flat_map(|k| [0.0, 1e-9, -1e-11, 3e-14].map(|s| (k, s))) {
        // One crossing moved off the antipode of the other by `shift`.
        let ring = [
            DVec3::new(1.0, shift - 0.5, -0.5),
            DVec3::new(1.0, shift + 0.5, 0.5),
            DVec3::new(-1.0, 0.5, 0.5),
            DVec3::new(-1.0, -0.5, -0.5),
        ];
        let turn = DQuat::from_rotation_z(k as f64 * 0.1);
        for reverse in [false, true] {
            let mut r: Vec<DVec3> = ring.iter().map(|&v| turn * v).collect();
            if reverse {
                r.reverse();
            }
            let p = SphericalPolygon::new(vec![r]).unwrap();
            let exact = clamped_cosine_integral(&p);
            assert!((clamped_cosine_integral_clip_free(&p) - exact).abs() <= 1e-12);
            assert!((ltc_integral(&p, DMat3::IDENTITY).unwrap() - exact).abs() <= 1e-12);
            let bound = rational_bound(&p, 1e-12);
            let rational = ltc_integral_rational(&p, DMat3::IDENTITY).unwrap();
            assert!(
                (rational - exact).abs() <= bound,
                "turn {k} shift {shift} reverse {reverse}: {rational} vs {exact}"
            );
        }
    }
}

/// Two inputs from the `ltc_integral` fuzz target where the clip-free path under a map and the
/// exact clip of the mapped polygon differ by more than 1e-12: not a fault of either, the
/// integral itself is that sensitive to rounding in the mapped vertices. Pinned here with the
/// slack the fuzz target allows (1e-12 times Hadamard's ratio of the map times the largest
/// `1 / sin(theta)` of an edge longer than a quarter circle), and, for the scaled map, the spread
/// of the exact value itself over scales of the map that change nothing mathematically.
#[test]
#[allow(clippy::excessive_precision)] // the fuzz target's values as printed, digit for digit
fn ill_conditioned_maps_and_edges_agree_within_their_conditioning() {
    use arealight::glam::DMat3;
    use arealight::ltc::ltc_integral;
    let hadamard = |m: DMat3| {
        m.x_axis.length() * m.y_axis.length() * m.z_axis.length() / m.determinant().abs()
    };
    // A map with nearly parallel columns (Hadamard's ratio 255), scaled by 2^-469.
    let p = SphericalPolygon::new(vec![vec![
        DVec3::new(0.7070674045037277, 0.7070674045037277, 0.01055324484333922),
        DVec3::new(
            -0.5773502691896258,
            -0.5773502691896258,
            -0.5773502691896258,
        ),
        DVec3::new(0.0328753551456474, 0.8054462010683614, 0.5917563926216534),
        DVec3::new(
            -0.9622504486493761,
            -0.19245008972987523,
            -0.19245008972987523,
        ),
        DVec3::new(-0.7071067811865475, -0.7071067811865475, 0.0),
    ]])
    .unwrap();
    let m = DMat3::from_cols(
        DVec3::new(4.6681420582728155, 5.430287700439806, 5.6208241109815534),
        DVec3::new(6.382969753148544, 6.382969753148544, 5.5255559057106796),
        DVec3::new(
            -0.09526820527087379,
            -0.09526820527087379,
            -0.09526820527087379,
        ),
    );
    let kappa = hadamard(m);
    assert!((200.0..300.0).contains(&kappa));
    let exact: Vec<f64> = [1.0, 2f64.powi(-469), 1e100]
        .iter()
        .map(|&s| clamped_cosine_integral(&p.transformed(m * s).unwrap()))
        .collect();
    let spread = exact
        .iter()
        .fold(0.0f64, |w, e| w.max((e - exact[0]).abs()));
    assert!(spread <= 1e-12 * kappa, "exact values spread by {spread}");
    for s in [1.0, 2f64.powi(-469), 1e100] {
        let got = ltc_integral(&p, m * s).unwrap();
        assert!(
            (got - exact[0]).abs() <= 1e-12 * kappa,
            "scale {s}: {got} vs {}",
            exact[0]
        );
    }

    // An edge within 1e-4 of half a circle under a well-conditioned map of the tables' form.
    let a = DVec3::new(
        -0.5728485979663679,
        -0.5795879932365605,
        -0.5795879932365605,
    );
    let b = DVec3::new(0.5727953258013961, 0.5796143177752222, 0.5796143177752222);
    let p = SphericalPolygon::new(vec![vec![
        a,
        b,
        DVec3::new(0.2873478855663454, 0.0, 0.9578262852211513),
    ]])
    .unwrap();
    let m = DMat3::from_cols(
        DVec3::new(-0.0625, 0.0, -0.0625),
        DVec3::Y,
        DVec3::new(0.0, 0.0, -8.0),
    );
    let planes = 1.0 / a.cross(b).length();
    assert!(planes > 1e3);
    let exact = clamped_cosine_integral(&p.transformed(m).unwrap());
    let got = ltc_integral(&p, m).unwrap();
    assert!(
        (got - exact).abs() <= 1e-12 * hadamard(m).max(1.0) * planes,
        "{got} vs {exact}"
    );
}

/// Maps with a NaN or infinite entry, or singular ones, are an error on every path (the
/// clip-free path's range checks must not let them through to a silent NaN).
#[test]
fn non_finite_and_singular_maps_are_errors() {
    use arealight::GeomError;
    use arealight::glam::DMat3;
    use arealight::ltc::{ltc_integral, ltc_integral_rational};
    let above = SphericalPolygon::new(vec![vec![
        DVec3::new(0.2, -0.3, 1.0),
        DVec3::new(0.2, 0.3, 1.0),
        DVec3::new(-0.3, 0.0, 1.0),
    ]])
    .unwrap();
    let crossing = SphericalPolygon::new(vec![vec![
        DVec3::new(1.0, -0.4, -0.3),
        DVec3::new(1.0, 0.4, -0.3),
        DVec3::new(0.6, 0.4, 0.7),
        DVec3::new(0.6, -0.4, 0.7),
    ]])
    .unwrap();
    let tables_form = |a: f64, b: f64, c: f64, d: f64| {
        DMat3::from_cols(DVec3::new(a, 0.0, c), DVec3::Y, DVec3::new(b, 0.0, d))
    };
    let bad = [
        tables_form(f64::NAN, 0.0, 0.0, 1.0),
        tables_form(1.0, f64::INFINITY, 0.0, 1.0),
        tables_form(1.0, 0.0, f64::NEG_INFINITY, 1.0),
        tables_form(1.0, 2.0, 0.5, 1.0), // singular: det = 1 - 1 = 0
        DMat3::from_cols(DVec3::X, DVec3::new(0.0, f64::NAN, 0.0), DVec3::Z),
        DMat3::ZERO,
        DMat3::from_cols(DVec3::X, DVec3::X, DVec3::Z),
    ];
    for m in bad {
        for p in [&above, &crossing] {
            for r in [ltc_integral(p, m), ltc_integral_rational(p, m)] {
                assert!(matches!(r, Err(GeomError::Degenerate(_))), "{m:?}: {r:?}");
            }
        }
    }
}
