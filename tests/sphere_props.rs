//! Property tests of the spherical primitives (proptest). Each property compares against an
//! independent quantity: an exact identity, a re-derivation, or a Monte Carlo estimate with a
//! stated bound.

mod support;

use arealight::glam::{DVec2, DVec3};
use arealight::sphere::{Gnomonic, SphericalPolygon, order_edges};
use proptest::prelude::*;
use std::f64::consts::PI;
use support::Rng;
use support::sphere::{
    assert_mc_agrees, boundary_edges, crossed_cells, great_circle, mc_solid_angle, polar, star_ring,
};

fn unit() -> impl Strategy<Value = DVec3> {
    (-1.0f64..1.0, 0.0f64..2.0 * PI).prop_map(|(z, phi)| {
        let r = (1.0 - z * z).sqrt();
        DVec3::new(r * phi.cos(), r * phi.sin(), z)
    })
}

/// A valid polygon of one of several kinds, built from a seed: star-shaped rings up to nearly a
/// hemisphere, their complements (larger than a hemisphere), and rings with a hole.
fn polygon(seed: u64) -> Option<SphericalPolygon> {
    let mut rng = Rng::new(seed);
    let c = rng.dir();
    let n = 3 + (rng.next_u64() % 10) as usize;
    let rho = rng.range(0.05, 1.5);
    let ring = star_ring(&mut rng, c, n, rho, 0.6);
    let p = match rng.next_u64() % 3 {
        0 => SphericalPolygon::new(vec![ring]),
        1 => SphericalPolygon::new(vec![ring]).map(|p| p.complement()),
        _ => {
            let m = 3 + (rng.next_u64() % 5) as usize;
            let mut hole = star_ring(&mut rng, c, m, 0.25 * rho, 0.8);
            hole.reverse();
            SphericalPolygon::new(vec![ring, hole])
        }
    };
    p.ok()
}

fn revalidate(p: &SphericalPolygon) -> Result<SphericalPolygon, arealight::GeomError> {
    SphericalPolygon::new(p.rings().map(<[DVec3]>::to_vec).collect())
}

proptest! {
    #![proptest_config(ProptestConfig { cases: support::cases(256), ..ProptestConfig::default() })]

    /// project then unproject returns the direction; unproject then project returns the point.
    #[test]
    fn gnomonic_round_trip(c in unit(), p in unit(), q in (-1e3f64..1e3, -1e3f64..1e3)) {
        let g = Gnomonic::new(c).unwrap();
        if p.dot(g.center()) > 1e-3 {
            let back = g.unproject(g.project(p).unwrap());
            prop_assert!((back - p).length() <= 1e-12, "{back} vs {p}");
        }
        // Plane points round-trip through a unit vector whose component along the center is
        // 1/|q|, so their relative error grows like |q| * eps: 1e-12 holds up to |q| ~ 1e3.
        let q = DVec2::new(q.0, q.1);
        let again = g.project(g.unproject(q)).unwrap();
        prop_assert!((again - q).length() <= 1e-12 * q.length().max(1.0), "{again} vs {q}");
    }

    /// Cutting a convex polygon along a diagonal splits its solid angle exactly.
    #[test]
    fn solid_angle_additive_under_chord_split(
        seed in any::<u64>(), n in 4usize..12, k in 2usize..10, rho in 1e-4f64..1.55,
    ) {
        let mut rng = Rng::new(seed);
        let c = rng.dir();
        // Constant radius: a polygon inscribed in a cap is convex, so every diagonal is inside.
        let ring = star_ring(&mut rng, c, n, rho, 1.0);
        // Both parts need three vertices: k in [2, n - 2].
        let k = 2 + k % (n - 3);
        let whole = SphericalPolygon::new(vec![ring.clone()]).unwrap().solid_angle();
        let a = SphericalPolygon::new(vec![ring[..=k].to_vec()]);
        prop_assert!(a.is_ok(), "{:?} {:?}", a, ring);
        let a = a.unwrap().solid_angle();
        let mut rest = ring[k..].to_vec();
        rest.push(ring[0]);
        let b = SphericalPolygon::new(vec![rest]).unwrap().solid_angle();
        prop_assert!((a + b - whole).abs() <= 1e-13 + 1e-12 * whole, "{a} + {b} vs {whole}");
    }

    /// The clipped polygon's solid angle equals a Monte Carlo estimate of the original region
    /// intersected with the hemisphere, within 5 estimated standard deviations.
    #[test]
    fn clip_matches_monte_carlo(seed in any::<u64>(), n in unit()) {
        let Some(p) = polygon(seed) else { return Ok(()); };
        let clipped = p.clip_to_hemisphere(n);
        let mut rng = Rng::new(seed ^ 0xC11F);
        let mc = mc_solid_angle(&mut rng, 96, 192, |d| d.dot(n) >= 0.0 && p.contains(d));
        let cells = crossed_cells(boundary_edges(&p).chain(great_circle(n)), 96, 192);
        assert_mc_agrees(clipped.solid_angle(), mc, cells, "clip vs Monte Carlo");
    }

    /// clip(n) and clip(-n) partition the region; clipping twice changes nothing; the result is
    /// a valid polygon.
    #[test]
    fn clip_partitions_and_is_idempotent(seed in any::<u64>(), n in unit()) {
        let Some(p) = polygon(seed) else { return Ok(()); };
        let up = p.clip_to_hemisphere(n);
        let down = p.clip_to_hemisphere(-n);
        let total = p.solid_angle();
        prop_assert!((up.solid_angle() + down.solid_angle() - total).abs() <= 1e-12 * 4.0 * PI,
            "{} + {} vs {}", up.solid_angle(), down.solid_angle(), total);
        let twice = up.clip_to_hemisphere(n);
        prop_assert!((twice.solid_angle() - up.solid_angle()).abs() <= 1e-13);
        prop_assert_eq!(twice.vertex_count(), up.vertex_count());
        prop_assert!(revalidate(&up).is_ok(), "invalid clip result {:?}", up);
        prop_assert!(revalidate(&down).is_ok(), "invalid clip result {:?}", down);
    }

    /// Polygons from 1e-12 rad to a radian across, anywhere strictly above the circle, and their
    /// complements: the clip keeps a polygon whole and cuts the complement to the hemisphere
    /// minus the polygon (found by the LTC tests: a ring of 3e-12 rad far from the pole was
    /// taken for a ring around the circle, its projected shoelace sum lost to rounding).
    #[test]
    fn clip_keeps_small_polygons_above_the_circle(seed in any::<u64>(), n in unit()) {
        let mut rng = Rng::new(seed);
        let (u, v) = (n.any_orthonormal_pair().0, n.any_orthonormal_pair().1);
        let h = rng.range(0.02, 1.0);
        let phi = rng.range(0.0, 2.0 * PI);
        let c = (n * h + (u * phi.cos() + v * phi.sin()) * (1.0 - h * h).sqrt()).normalize();
        let rho = 10f64.powf(rng.range(-12.0, 0.0)).min(0.9 * h.asin());
        let k = 3 + (rng.next_u64() % 8) as usize;
        let Ok(p) = SphericalPolygon::new(vec![star_ring(&mut rng, c, k, rho, 0.5)]) else {
            return Ok(());
        };
        let area = p.solid_angle();
        let kept = p.clip_to_hemisphere(n).solid_angle();
        prop_assert!((kept - area).abs() <= 1e-12 * 4.0 * PI, "{} vs {}", kept, area);
        let rest = p.complement().clip_to_hemisphere(n).solid_angle();
        prop_assert!((rest - (2.0 * PI - area)).abs() <= 1e-12 * 4.0 * PI, "{} vs {}", rest, 2.0 * PI - area);
    }

    /// Clipping to a hemisphere through vertices of the polygon (the degenerate case) still
    /// partitions it.
    #[test]
    fn clip_through_vertices_partitions(seed in any::<u64>(), i in 0usize..64, j in 0usize..64) {
        let Some(p) = polygon(seed) else { return Ok(()); };
        let verts: Vec<DVec3> = p.rings().flatten().copied().collect();
        let (a, b) = (verts[i % verts.len()], verts[j % verts.len()]);
        let n = a.cross(b);
        if n.length() <= 1e-3 {
            return Ok(()); // the same or nearly antipodal vertices: no plane through both
        }
        let (up, down) = (p.clip_to_hemisphere(n), p.clip_to_hemisphere(-n));
        prop_assert!((up.solid_angle() + down.solid_angle() - p.solid_angle()).abs() <= 1e-12 * 4.0 * PI);
        prop_assert!(revalidate(&up).is_ok(), "invalid clip result {:?}", up);
    }

    /// order_edges does not care about edge order, direction, or 1e-12 noise on endpoints.
    #[test]
    fn order_edges_invariant(seed in any::<u64>(), flips in any::<u64>()) {
        let Some(p) = polygon(seed) else { return Ok(()); };
        let mut rng = Rng::new(seed ^ 0x0BDE);
        let mut edges = Vec::new();
        for ring in p.rings() {
            for i in 0..ring.len() {
                let jitter = |rng: &mut Rng, v: DVec3| v + rng.dir() * 1e-12;
                let (a, b) = (jitter(&mut rng, ring[i]), jitter(&mut rng, ring[(i + 1) % ring.len()]));
                edges.push(if (flips >> (i % 64)) & 1 == 1 { (b, a) } else { (a, b) });
            }
        }
        // Fisher–Yates shuffle.
        for i in (1..edges.len()).rev() {
            edges.swap(i, (rng.next_u64() % (i as u64 + 1)) as usize);
        }
        let q = order_edges(&edges).unwrap();
        prop_assert_eq!(q.ring_count(), p.ring_count());
        // order_edges orients every outer loop around its smaller side.
        let w = p.solid_angle();
        let expect = if p.ring_count() == 1 { w.min(4.0 * PI - w) } else { w };
        prop_assert!((q.solid_angle() - expect).abs() <= 1e-9, "{} vs {}", q.solid_angle(), expect);
    }
}

#[test]
fn polygon_generator_covers_all_kinds() {
    // Guard against the generator silently producing nothing valid.
    let kinds: Vec<(usize, bool)> = (0..60u64)
        .filter_map(polygon)
        .map(|p| (p.ring_count(), p.solid_angle() > 2.0 * PI))
        .collect();
    assert!(kinds.len() > 50);
    assert!(kinds.iter().any(|k| k.0 == 2));
    assert!(kinds.iter().any(|k| k.1));
    let _ = polar;
}
