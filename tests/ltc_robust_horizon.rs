//! Continuity of every LTC-layer integral as a vertex crosses the horizon (issue 24): vertices
//! `1e-16` to `1e-9` above and below it, absolutely and relative to the polygon's size, in the
//! shading frame and, after the LTC transform, in the cosine space. Each value is checked against
//! this file's own clip-and-sum reference for convex rings (Sutherland–Hodgman against `z >= 0`
//! with crossing points as positive combinations of the edge's endpoints, then Baum's edge sum
//! with `atan2` angles), and the values on the two sides of the horizon against each other.
//!
//! Paths that go through `SphericalPolygon::clip_to_hemisphere` (the exact `clamped_cosine_integral`,
//! `clamped_cosine_integral_rational`, `ggx_polygon_integral` across the horizon) are checked in
//! `exact_clip_paths_are_continuous_across_the_horizon`, with vertices `2e-14` to `1e-12` above
//! the horizon among others (issue 24, reproducer 1).

mod support;

use arealight::glam::{DMat3, DVec3};
use arealight::ltc::{
    EDGE_FACTOR_RATIONAL_MAX_ERROR, clamped_cosine_integral, clamped_cosine_integral_clip_free,
    clamped_cosine_integral_rational, ggx_polygon_integral, lookup, ltc_integral,
    ltc_integral_rational,
};
use arealight::sphere::SphericalPolygon;
use std::f64::consts::PI;
use support::Rng;

/// The clamped-cosine integral `(1 / pi) int max(0, z)` over a convex ring (counter-clockwise
/// seen from outside, within an open hemisphere, its horizon arc shorter than half a circle):
/// clipped to `z >= 0` vertex by vertex, crossing points as positive combinations
/// `a |b.z| + b |a.z|` (exactly on the horizon up to rounding, whatever the heights), then
/// Baum's sum. Vertices with `z == 0` count as on the horizon.
fn reference(ring: &[DVec3]) -> f64 {
    let n = ring.len();
    let mut clipped: Vec<DVec3> = Vec::with_capacity(n + 2);
    for i in 0..n {
        let (a, b) = (ring[i], ring[(i + 1) % n]);
        if a.z >= 0.0 {
            clipped.push(a);
        }
        if (a.z > 0.0 && b.z < 0.0) || (a.z < 0.0 && b.z > 0.0) {
            let x = a * b.z.abs() + b * a.z.abs();
            clipped.push(DVec3::new(x.x, x.y, 0.0).normalize());
        }
    }
    let m = clipped.len();
    let mut sum = 0.0;
    for i in 0..m {
        let (a, b) = (clipped[i].normalize(), clipped[(i + 1) % m].normalize());
        let c = a.cross(b);
        let s = c.length();
        if s > 0.0 {
            sum += s.atan2(a.dot(b)) * c.z / s;
        }
    }
    (sum / (2.0 * PI)).clamp(0.0, 1.0)
}

/// The random parameters of a family of rings (see [`ring_through`]): the center's azimuth, its
/// elevation as a fraction of the radius, and whether the ring lies mostly above the horizon
/// (its lowest vertex moves) or mostly below it (its highest vertex moves; the visible part is a
/// sliver about that vertex, as in reproducer 1), drawn from `sides`.
fn family(rng: &mut Rng, sides: &[bool]) -> (f64, f64, bool) {
    let side = sides[(rng.next_u64() % sides.len() as u64) as usize];
    (rng.range(0.0, 2.0 * PI), rng.range(0.7, 1.0), side)
}

/// Both kinds of family, and those mostly above the horizon only.
const BOTH: &[bool] = &[true, false];
const ABOVE: &[bool] = &[true];

/// A convex ring of `n` vertices (a regular polygon of angular radius `rho` about a center at
/// azimuth `phi` and elevation `lift * rho`, or `-lift * rho` when not `above`, so that its
/// vertex 0, the lowest or the highest, lies just across the horizon from the center) whose
/// vertex 0 is then moved to the height `h` above the horizon (negative: below), keeping its
/// azimuth; `None` if the result is not convex and valid.
fn ring_through(
    (phi, lift, above): (f64, f64, bool),
    n: usize,
    rho: f64,
    h: f64,
) -> Option<Vec<DVec3>> {
    let elev = if above { rho * lift } else { -rho * lift };
    let c = DVec3::new(elev.cos() * phi.cos(), elev.cos() * phi.sin(), elev.sin());
    let (u, w) = {
        let e = DVec3::new(-phi.sin(), phi.cos(), 0.0);
        (e, c.cross(e))
    };
    // Vertex 0 points straight down (or up) from the center, towards the horizon.
    let start = if above { -1.0 } else { 1.0 } * std::f64::consts::FRAC_PI_2;
    let mut ring: Vec<DVec3> = (0..n)
        .map(|i| {
            let t = start + 2.0 * PI * i as f64 / n as f64;
            (c * rho.cos() + (u * t.cos() + w * t.sin()) * rho.sin()).normalize()
        })
        .collect();
    let v = ring[0];
    let horiz = (v.x * v.x + v.y * v.y).sqrt();
    ring[0] = DVec3::new(
        v.x / horiz * (1.0 - h * h).sqrt(),
        v.y / horiz * (1.0 - h * h).sqrt(),
        h,
    );
    // Convex and counter-clockwise: every vertex on the left of every other edge.
    for i in 0..n {
        let (a, b) = (ring[i], ring[(i + 1) % n]);
        for (k, &p) in ring.iter().enumerate() {
            if k != i && k != (i + 1) % n && a.cross(b).dot(p) <= 0.0 {
                return None;
            }
        }
    }
    SphericalPolygon::new(vec![ring.clone()]).ok()?;
    Some(ring)
}

/// The heights a vertex is moved to: `1e-16` to `1e-9` above and below the horizon, absolute,
/// and relative to the size `rho` of the polygon.
fn heights(rho: f64) -> Vec<f64> {
    let mut hs = vec![0.0];
    for e in -16..=-9 {
        for scale in [1.0, rho] {
            let h = 10f64.powi(e) * scale;
            hs.push(h);
            hs.push(-h);
        }
    }
    hs
}

/// Polygon sizes from tiny to large.
const SIZES: [f64; 5] = [1e-6, 1e-3, 0.05, 0.4, 1.0];

/// Asserts that `f` stays within `tol` of the reference and within `tol` plus the change of the
/// reference between the two sides of the horizon, on families drawn from `sides`.
fn check_family(
    what: &str,
    rng: &mut Rng,
    tol: f64,
    f: impl Fn(&SphericalPolygon) -> f64,
    map: impl Fn(DVec3) -> DVec3,
    sides: &[bool],
) {
    let mut checked = 0;
    for &rho in &SIZES {
        for n in [3, 4, 5, 7] {
            for _ in 0..4 {
                let fam = family(rng, sides);
                let mut values = Vec::new();
                for h in heights(rho) {
                    let Some(ring) = ring_through(fam, n, rho, h) else {
                        continue;
                    };
                    // The polygon whose image under `map` is `ring` (up to rounding).
                    let pre: Vec<DVec3> = ring.iter().map(|&p| map(p).normalize()).collect();
                    let Ok(poly) = SphericalPolygon::new(vec![pre]) else {
                        continue;
                    };
                    let got = f(&poly);
                    let want = reference(&ring);
                    assert!(
                        (got - want).abs() <= tol,
                        "{what}: rho {rho}, n {n}, height {h:e}: {got} vs reference {want}"
                    );
                    values.push((h, got, want));
                    checked += 1;
                }
                // Across the horizon: the values on both sides differ by no more than the
                // reference's values do, plus the tolerance.
                for w in values.windows(2) {
                    let ((h0, a, ra), (h1, b, rb)) = (w[0], w[1]);
                    assert!(
                        (a - b).abs() <= (ra - rb).abs() + 2.0 * tol,
                        "{what}: rho {rho}, n {n}: {a} at {h0:e}, {b} at {h1:e}"
                    );
                }
            }
        }
    }
    assert!(checked > 500, "{what}: only {checked} polygons");
}

/// The clip-free paths (thesis 003 eq. 4.6/4.7; the quad kernel for `n = 4`) in the shading
/// frame, on rings mostly above the horizon (their lowest vertex moved). Rings mostly below it
/// are in `slivers_are_continuous_across_the_horizon`.
#[test]
fn clip_free_paths_are_continuous_across_the_horizon() {
    shading_families(0x4012, ABOVE);
}

fn shading_families(seed: u64, sides: &[bool]) {
    let mut rng = Rng::new(seed);
    check_family(
        "clamped_cosine_integral_clip_free",
        &mut rng,
        1e-13,
        clamped_cosine_integral_clip_free,
        |p| p,
        sides,
    );
    check_family(
        "ltc_integral, identity",
        &mut rng,
        1e-13,
        |p| ltc_integral(p, DMat3::IDENTITY).unwrap(),
        |p| p,
        sides,
    );
    check_family(
        "ltc_integral_rational, identity",
        &mut rng,
        2.0 * EDGE_FACTOR_RATIONAL_MAX_ERROR,
        |p| ltc_integral_rational(p, DMat3::IDENTITY).unwrap(),
        |p| p,
        sides,
    );
}

/// The clip-free and LTC paths on rings mostly below the horizon (in the shading frame, and
/// below the transformed horizon), whose visible part is a sliver about the moved vertex. A
/// vertex (or image) within a few ulps of `1e-14` above the horizon, which the clip-free path
/// hands over to the exact path as on the horizon, reaches the sphere layer's clip normalized to
/// just above its tolerance, reproducer 1's regime (`clamped_cosine_integral_clip_free` at
/// `rho = 1e-3`, 3 vertices, height `1e-14`, and `ltc_integral` at `(0.9, 0.5)` at `rho = 1e-6`,
/// height `1e-14`, image at `1.00014e-14`, gave 1 instead of 0 through a wrong clip).
#[test]
fn slivers_are_continuous_across_the_horizon() {
    shading_families(0x4017, &[false]);
    ltc_families(0x4016, &[false]);
}

/// The LTC paths with images near the horizon of the cosine space: the polygon is the preimage
/// under the tables' maps (grazing and near-normal views, near-mirror and rough) of a ring with
/// a vertex at the given height there. Rings mostly below the transformed horizon are in
/// `slivers_are_continuous_across_the_horizon`.
#[test]
fn ltc_paths_are_continuous_across_the_transformed_horizon() {
    ltc_families(0x4013, ABOVE);
}

fn ltc_families(seed: u64, sides: &[bool]) {
    let mut rng = Rng::new(seed);
    for (cos_v, alpha) in [(0.9, 0.5), (0.3, 0.05), (0.02, 1e-3), (1e-4, 1e-4)] {
        let m_inv = lookup(cos_v, alpha).unwrap().m_inv;
        let m = m_inv.inverse();
        // The images carry the map's conditioning: `m_inv (m p)` is `p` up to about
        // `eps * cond(m)` in direction.
        let cond = m.to_cols_array().iter().map(|x| x.abs()).sum::<f64>()
            * m_inv.to_cols_array().iter().map(|x| x.abs()).sum::<f64>();
        let tol = 1e-13 + 64.0 * f64::EPSILON * cond;
        check_family(
            &format!("ltc_integral at ({cos_v}, {alpha})"),
            &mut rng,
            tol,
            |p| ltc_integral(p, m_inv).unwrap(),
            |p| m * p,
            sides,
        );
        check_family(
            &format!("ltc_integral_rational at ({cos_v}, {alpha})"),
            &mut rng,
            tol + 2.0 * EDGE_FACTOR_RATIONAL_MAX_ERROR,
            |p| ltc_integral_rational(p, m_inv).unwrap(),
            |p| m * p,
            sides,
        );
    }
}

/// The paths through the sphere layer's exact clip: the exact clamped-cosine integral, its
/// rational variant, and `ggx_polygon_integral` (which clips at the shading horizon first; its
/// reference is the LTC integral of the reference clip's polygon), with vertices `2e-14` to
/// `1e-12` above the horizon among the heights (issue 24, reproducer 1: a light barely touching
/// the horizon must not count as the whole hemisphere).
#[test]
fn exact_clip_paths_are_continuous_across_the_horizon() {
    let mut rng = Rng::new(0x4014);
    check_family(
        "clamped_cosine_integral",
        &mut rng,
        1e-13,
        clamped_cosine_integral,
        |p| p,
        BOTH,
    );
    check_family(
        "clamped_cosine_integral_rational",
        &mut rng,
        2.0 * EDGE_FACTOR_RATIONAL_MAX_ERROR,
        clamped_cosine_integral_rational,
        |p| p,
        BOTH,
    );
    // `ggx_polygon_integral` with `f0 = 1` is `norm` times the LTC integral of the clipped
    // polygon: against `norm` times the clip-free LTC integral of this file's clip.
    for (cos_v, alpha) in [(0.5, 0.3), (0.05, 1e-3)] {
        let l = lookup(cos_v, alpha).unwrap();
        let mut rng = Rng::new(0x4015);
        for &rho in &SIZES {
            let fam = family(&mut rng, BOTH);
            for h in heights(rho) {
                let Some(ring) = ring_through(fam, 4, rho, h) else {
                    continue;
                };
                let poly = SphericalPolygon::new(vec![ring.clone()]).unwrap();
                let got = ggx_polygon_integral(&poly, cos_v, alpha, 1.0).unwrap();
                let clipped = clip_ring(&ring);
                // A clipped part too thin to be a valid polygon integrates to rounding.
                let want = match SphericalPolygon::new(vec![clipped]) {
                    Ok(c) => l.norm * ltc_integral(&c, l.m_inv).unwrap(),
                    Err(_) => 0.0,
                };
                assert!(
                    (got - want).abs() <= 1e-12 * l.norm,
                    "ggx at ({cos_v}, {alpha}), rho {rho}, height {h:e}: {got} vs {want}"
                );
            }
        }
    }
}

/// This file's clip of a convex ring to `z >= 0` (see [`reference`]), as a ring.
fn clip_ring(ring: &[DVec3]) -> Vec<DVec3> {
    let n = ring.len();
    let mut clipped = Vec::with_capacity(n + 2);
    for i in 0..n {
        let (a, b) = (ring[i], ring[(i + 1) % n]);
        if a.z >= 0.0 {
            clipped.push(a);
        }
        if (a.z > 0.0 && b.z < 0.0) || (a.z < 0.0 && b.z > 0.0) {
            let x = a * b.z.abs() + b * a.z.abs();
            clipped.push(DVec3::new(x.x, x.y, 0.0).normalize());
        }
    }
    // Points that coincide within rounding (the two crossings next to a vertex a few ulps below
    // the horizon) are one vertex.
    let mut ring: Vec<DVec3> = Vec::with_capacity(clipped.len());
    for p in clipped {
        if ring
            .last()
            .is_none_or(|q: &DVec3| (p - *q).length() > 1e-14)
        {
            ring.push(p);
        }
    }
    while ring.len() > 1 && (ring[0] - ring[ring.len() - 1]).length() <= 1e-14 {
        ring.pop();
    }
    ring
}

/// Issue 24, reproducer 1, as the LTC layer sees it: a light one vertex of which lies `1e-13`
/// above the horizon (the others 0.3 below) lights the point by about `1e-18`, not like the
/// whole sky. The clip-free paths agree with this file's reference; the exact paths, through
/// the sphere layer's clip, are in `reproducer_1_through_the_exact_clip`.
#[test]
fn reproducer_1_light_touching_the_horizon_from_above() {
    let v = |x, y, z| DVec3::new(x, y, z);
    let ring = vec![v(1., 0., 1e-13), v(1., -0.3, -0.3), v(1., 0.3, -0.3)];
    let p = SphericalPolygon::new(vec![ring.clone()]).unwrap();
    let unit: Vec<DVec3> = ring.iter().map(|q| q.normalize()).collect();
    let want = reference(&unit);
    assert!(want < 1e-15);
    for (what, got) in [
        ("clip-free", clamped_cosine_integral_clip_free(&p)),
        ("ltc identity", ltc_integral(&p, DMat3::IDENTITY).unwrap()),
        (
            "ltc rational identity",
            ltc_integral_rational(&p, DMat3::IDENTITY).unwrap(),
        ),
    ] {
        assert!((got - want).abs() <= 1e-15, "{what}: {got} vs {want}");
    }
}

/// The exact paths on reproducer 1, through the sphere layer's clip, for heights `1.5e-14` to
/// `1e-12`: the clip keeps the sliver above the horizon, whose solid angle has the closed form
/// `0.3 h^2 / (0.3 + h)` (checked both ways to `1e-6` of it: a clip that drops the sliver fails
/// as one that returns the hemisphere), and every integral is its closed form `A h / (3 pi)`
/// (the sliver's centroid height `h / 3`) to `1e-15`, the resolution of a sum of edge terms; the
/// GGX integral with `f0 = 1` is `norm` times the LTC integral of this file's clip of the ring.
#[test]
fn reproducer_1_through_the_exact_clip() {
    let v = |x, y, z| DVec3::new(x, y, z);
    for h in [1.5e-14, 3e-14, 1e-13, 2e-13, 1e-12] {
        let ring = vec![v(1., 0., h), v(1., -0.3, -0.3), v(1., 0.3, -0.3)];
        let p = SphericalPolygon::new(vec![ring.clone()]).unwrap();
        let area = 0.3 * h * h / (0.3 + h);
        let kept = p.clip_to_hemisphere(DVec3::Z).solid_angle();
        assert!(
            (kept - area).abs() <= 1e-6 * area,
            "h {h:e}: clip keeps {kept:e} sr of {area:e}"
        );
        let want = area * (h / 3.0) / PI;
        for (what, got) in [
            ("exact", clamped_cosine_integral(&p)),
            ("rational", clamped_cosine_integral_rational(&p)),
        ] {
            assert!(
                (got - want).abs() <= 1e-15,
                "h {h:e}, {what}: {got} vs {want}"
            );
        }
        for (cos_v, alpha) in [(0.5, 0.3), (0.05, 1e-3)] {
            let l = lookup(cos_v, alpha).unwrap();
            let got = ggx_polygon_integral(&p, cos_v, alpha, 1.0).unwrap();
            let want = match SphericalPolygon::new(vec![clip_ring(&ring)]) {
                Ok(c) => l.norm * ltc_integral(&c, l.m_inv).unwrap(),
                Err(_) => 0.0,
            };
            assert!(
                (got - want).abs() <= 1e-15 * l.norm,
                "h {h:e}, ggx at ({cos_v}, {alpha}): {got} vs {want}"
            );
        }
    }
}

/// Found by fuzzing (`ltc_grazing`): a large triangle one vertex of which lies `1e-9` above the
/// horizon, another on it, seen at the most grazing view with `alpha = 0`. Its part above the
/// horizon is a sliver of `1e-9` sr, whose image in the cosine space (solid angle `1.7e-13`)
/// has one vertex `1.1e-13` above that horizon: the sphere layer's clip (reproducer 1) made it
/// the whole hemisphere, and `ggx_polygon_integral` returned `norm` (0.939) against an albedo of
/// 0.909. The value is at most `norm` times the image's solid angle over pi (`5e-14`), and the
/// clip is now consistent, so it is a value.
#[test]
fn fuzz_sliver_above_the_horizon_at_the_most_grazing_view() {
    let p = SphericalPolygon::new(vec![vec![
        DVec3::new(0.0, -1.0, 1e-9),
        DVec3::new(
            -0.026297584151910847,
            0.9993081977726123,
            -0.026297584151910847,
        ),
        DVec3::new(1.0, 0.0, 0.0),
    ]])
    .unwrap();
    let l = lookup(1e-300, 0.0).unwrap();
    let v = ggx_polygon_integral(&p, 1e-300, 0.0, 1.0).unwrap();
    assert!((0.0..=1e-12).contains(&v), "{v}, albedo {}", l.albedo);
}

/// Found by fuzzing (`ltc_grazing`), a fault of the target's first continuity bound, kept as a
/// check of continuity where it is weakest: a triangle with a nearly antipodal edge (length
/// `pi - 0.1`), its vertex 0 moved from `1e-9` above the horizon onto it and below. Moving an
/// endpoint of an edge of length `L` by `d` sweeps up to `d tan(L / 2)` (here 20 `d`), not the
/// `d L / 2` of a short edge; the integral moved by `1.8e-9` for `d = 1e-9`.
#[test]
fn fuzz_nearly_antipodal_edge_moves_continuously() {
    let ring = [
        DVec3::new(4.0, -12.0, -1.0),
        DVec3::new(-9.0, 38.0, 4.0),
        DVec3::new(-1.0, 0.0, 0.0),
    ]
    .map(DVec3::normalize);
    let arc = |a: DVec3, b: DVec3| a.cross(b).length().atan2(a.dot(b));
    let at = |h: f64| {
        let v = ring[0];
        let f = (1.0 - h * h).sqrt() / (v.x * v.x + v.y * v.y).sqrt();
        let mut r = ring;
        r[0] = DVec3::new(v.x * f, v.y * f, h);
        let p = SphericalPolygon::new(vec![r.to_vec()]).unwrap();
        let value = clamped_cosine_integral_clip_free(&p);
        // The two entry points round differently by an ulp or two (vertex normalization).
        let other = ltc_integral(&p, DMat3::IDENTITY).unwrap();
        assert!(
            (value - other).abs() <= 4.0 * f64::EPSILON * value.abs(),
            "{value} {other}"
        );
        (value, r)
    };
    let heights = [1e-9, 1e-12, 1e-15, 0.0, -1e-15, -1e-12, -1e-9];
    for w in heights.windows(2) {
        let ((a, ra), (b, rb)) = (at(w[0]), at(w[1]));
        let d = arc(ra[0], rb[0]);
        let half_tan = |p: DVec3, q: DVec3| (0.5 * arc(p, q)).tan();
        let bound = d
            * (half_tan(ra[2], ra[0]).max(half_tan(rb[2], rb[0]))
                + half_tan(ra[0], ra[1]).max(half_tan(rb[0], rb[1])))
            / PI;
        assert!(
            (a - b).abs() <= bound + 1e-13,
            "{a} at {}, {b} at {}: bound {bound}",
            w[0],
            w[1]
        );
    }
}

/// Found by fuzzing (`ltc_grazing`): the complement of a sliver (a triangle with two vertices
/// 0.005 rad apart at 35 degrees of elevation and its third near the horizon), the third vertex
/// moved to `1e-14` below the horizon. Its two crossing points lie `5e-17` apart, below what
/// rounding resolves, and the clip-free path took the horizon arc between them as empty instead
/// of almost the whole circle: 0 instead of 0.99972 (which the exact clip gives, and every other
/// height too). Now such products go to the exact path.
#[test]
fn fuzz_complement_of_a_sliver_with_a_vertex_just_below_the_horizon() {
    let a = DVec3::new(-0.9683086332611238, 0.24964206951263349, 0.0);
    let b = DVec3::new(0.5818519398793889, 0.5750862196482331, 0.5750862196482331);
    let c = DVec3::new(0.5773502691896258, 0.5773502691896258, 0.5773502691896258);
    let mut values = Vec::new();
    for h in [
        1e-9, 1e-12, 1e-14, 0.0, -1e-14, -5e-14, -1e-13, -1e-12, -1e-9,
    ] {
        let f = (1.0f64 - h * h).sqrt() / (a.x * a.x + a.y * a.y).sqrt();
        let p = SphericalPolygon::new(vec![vec![DVec3::new(a.x * f, a.y * f, h), b, c]]).unwrap();
        let want = clamped_cosine_integral(&p);
        for (what, got) in [
            ("clip-free", clamped_cosine_integral_clip_free(&p)),
            ("ltc identity", ltc_integral(&p, DMat3::IDENTITY).unwrap()),
        ] {
            assert!(
                (got - want).abs() <= 1e-12,
                "{what} at {h:e}: {got} vs exact {want}"
            );
        }
        values.push(want);
    }
    // The complement of a sliver 0.0009 of the hemisphere's integral wide.
    for &v in &values {
        assert!((v - values[0]).abs() <= 1e-9 && v > 0.999 && v < 1.0, "{v}");
    }
}

/// Found by fuzzing (`ltc_grazing`): a triangle whose part above the horizon is almost the
/// whole upper hemisphere, at the most grazing view with `alpha = 0`, where the table's map has
/// a condition of about `3e7`: its LTC integral came out `2.3e-9` (relative) above the whole
/// hemisphere's, so the response exceeded the albedo. No part of the hemisphere holds more than
/// all of it; the response is capped there exactly.
#[test]
fn fuzz_almost_the_whole_hemisphere_at_the_most_grazing_view() {
    let p = SphericalPolygon::new(vec![vec![
        DVec3::new(0.0, 1.0, 1e-9),
        DVec3::new(
            -0.9997633976070043,
            -0.015380975347800066,
            -0.015380975347800066,
        ),
        DVec3::new(
            -0.010877922219413961,
            -0.7070649442619075,
            -0.7070649442619075,
        ),
    ]])
    .unwrap();
    let l = lookup(1e-300, 0.0).unwrap();
    let got = ggx_polygon_integral(&p, 1e-300, 0.0, 1.0).unwrap();
    assert!(
        got <= l.albedo * (1.0 + 1e-12),
        "{got} vs albedo {}",
        l.albedo
    );
}

/// Found by fuzzing (`ltc_grazing`): reproducer 1's configuration (a vertex `1e-14` and an ulp
/// above the horizon, the others well below), whose part above is a sliver. The clip-free path
/// cannot order its two crossings and hands it over; `ltc_integral`, whose exact path checks the
/// clip, gives the sliver's value (the sphere clip is consistent here), and
/// `clamped_cosine_integral_clip_free`, which has no error to report, takes the sphere clip's
/// value, which must be the sliver's (it was 1).
#[test]
fn fuzz_sliver_through_the_unchecked_fallback() {
    let p = SphericalPolygon::new(vec![vec![
        DVec3::new(
            0.7784130394753295,
            0.6277524511897818,
            1.0000000000000002e-14,
        ),
        DVec3::new(
            -0.014489710525281226,
            -0.014489710525281226,
            -0.9997900262444046,
        ),
        DVec3::new(-0.16539535392599136, 0.882108554271954, -0.441054277135977),
    ]])
    .unwrap();
    let v = ltc_integral(&p, DMat3::IDENTITY).unwrap();
    assert!(v <= 1e-12, "{v}");
    let clip_free = clamped_cosine_integral_clip_free(&p);
    assert!(clip_free <= 1e-12, "{clip_free}");
}
