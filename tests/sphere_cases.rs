//! Edge cases of the spherical primitives, each checked against a number known in closed form.

mod support;

use arealight::GeomError;
use arealight::glam::{DVec2, DVec3};
use arealight::sphere::{
    Gnomonic, SphericalPolygon, enclosing_cap, order_directed_edges, order_edges,
};
use std::f64::consts::PI;
use support::Rng;
use support::sphere::{
    assert_mc_agrees, boundary_edges, crossed_cells, great_circle, mc_solid_angle, polar,
};

fn poly(rings: Vec<Vec<DVec3>>) -> SphericalPolygon {
    SphericalPolygon::new(rings).expect("valid test polygon")
}

/// Spherical cap polygon: `n` vertices at polar angle `rho` about `c`, counter-clockwise.
fn cap_ring(c: DVec3, rho: f64, n: usize) -> Vec<DVec3> {
    (0..n)
        .map(|i| polar(c, rho, 2.0 * PI * i as f64 / n as f64))
        .collect()
}

fn close(a: f64, b: f64, tol: f64) -> bool {
    (a - b).abs() <= tol
}

/// Exact solid angle of a regular n-gon inscribed in the cap of angular radius rho: n times the
/// isoceles triangle from the center, by the spherical excess of that triangle.
fn regular_ngon_area(rho: f64, n: usize) -> f64 {
    let half = PI / n as f64;
    // Triangle with two sides rho and apex angle 2*half: excess from Van Oosterom on exact vectors
    // is what we test, so use L'Huilier-free closed form: tan(E/2) = tan(rho/2)^2 sin(2h) /
    // (1 + tan(rho/2)^2 cos(2h)).
    let t2 = (rho / 2.0).tan().powi(2);
    let e = 2.0 * (t2 * (2.0 * half).sin()).atan2(1.0 + t2 * (2.0 * half).cos());
    n as f64 * e
}

#[test]
fn solid_angle_of_regular_polygons_matches_closed_form() {
    for &(rho, n) in &[
        (1e-6, 4),
        (0.01, 7),
        (0.5, 3),
        (1.2, 12),
        (PI / 2.0, 8),
        (2.5, 9),
    ] {
        let c = DVec3::new(0.3, -0.2, 0.9).normalize();
        let p = poly(vec![cap_ring(c, rho, n)]);
        let expect = regular_ngon_area(rho, n);
        let w = p.solid_angle();
        assert!(
            close(w, expect, 1e-12 * expect.max(1e-3)),
            "rho {rho} n {n}: {w} vs {expect}"
        );
        assert!(close(
            p.complement().solid_angle(),
            4.0 * PI - expect,
            1e-12
        ));
    }
}

#[test]
fn contains_agrees_with_solid_angle_by_monte_carlo() {
    let mut rng = Rng::new(7);
    let c = DVec3::new(-0.2, 0.5, 0.4).normalize();
    let outer = cap_ring(c, 1.1, 9);
    let mut hole = cap_ring(c, 0.3, 5);
    hole.reverse();
    for p in [poly(vec![outer.clone()]), poly(vec![outer, hole])] {
        for q in [p.clone(), p.complement()] {
            let mc = mc_solid_angle(&mut rng, 128, 256, |d| q.contains(d));
            let cells = crossed_cells(boundary_edges(&q), 128, 256);
            assert_mc_agrees(q.solid_angle(), mc, cells, "contains vs solid_angle");
        }
    }
}

#[test]
fn clip_fully_inside_and_fully_outside() {
    let up = poly(vec![cap_ring(DVec3::Z, 0.4, 6)]);
    let clipped = up.clip_to_hemisphere(DVec3::Z);
    assert_eq!(clipped, up);
    assert!(up.clip_to_hemisphere(-DVec3::Z).is_empty());
    assert_eq!(up.clip_to_hemisphere(-DVec3::Z).solid_angle(), 0.0);
}

#[test]
fn clip_of_region_surrounding_the_pole() {
    // Everything except a small cap around the south pole: the whole upper hemisphere survives.
    let mut south = cap_ring(-DVec3::Z, 0.3, 6);
    south.reverse();
    let r = poly(vec![south]);
    assert!(close(
        r.clip_to_hemisphere(DVec3::Z).solid_angle(),
        2.0 * PI,
        1e-13
    ));
    let lower = r.clip_to_hemisphere(-DVec3::Z).solid_angle();
    assert!(close(lower, 2.0 * PI - regular_ngon_area(0.3, 6), 1e-13));
    // Everything except a small cap around the north pole: a hemisphere with a hole.
    let mut north = cap_ring(DVec3::Z, 0.3, 6);
    north.reverse();
    let r = poly(vec![north]);
    let c = r.clip_to_hemisphere(DVec3::Z);
    assert_eq!(c.ring_count(), 2);
    assert!(close(
        c.solid_angle(),
        2.0 * PI - regular_ngon_area(0.3, 6),
        1e-13
    ));
    assert!(SphericalPolygon::new(c.rings().map(<[DVec3]>::to_vec).collect()).is_ok());
}

#[test]
fn clip_full_and_empty() {
    assert!(close(
        SphericalPolygon::full()
            .clip_to_hemisphere(DVec3::X)
            .solid_angle(),
        2.0 * PI,
        1e-14
    ));
    assert!(
        SphericalPolygon::empty()
            .clip_to_hemisphere(DVec3::X)
            .is_empty()
    );
    // A degenerate normal is an error, and the infallible form gives the empty region.
    let up = poly(vec![cap_ring(DVec3::Z, 0.4, 6)]);
    assert_eq!(
        up.try_clip_to_hemisphere(DVec3::ZERO),
        Err(GeomError::ZeroLengthArgument {
            what: "hemisphere normal"
        })
    );
    assert_eq!(
        up.try_clip_to_hemisphere(DVec3::NAN),
        Err(GeomError::NonFiniteArgument {
            what: "hemisphere normal"
        })
    );
    assert!(up.clip_to_hemisphere(DVec3::ZERO).is_empty());
    // Every bad normal, partly or wholly non-finite or zero: an error from the checked form, and
    // the documented empty region from the infallible one, even for regions (the full sphere,
    // a cap around the normal's axis) whose clip at any valid normal is not empty.
    for bad in [
        DVec3::ZERO,
        -DVec3::ZERO,
        DVec3::NAN,
        DVec3::new(f64::NAN, 0.0, 1.0),
        DVec3::new(0.0, f64::INFINITY, 0.0),
        DVec3::new(1.0, 1.0, f64::NEG_INFINITY),
    ] {
        let want = if bad.is_finite() {
            GeomError::ZeroLengthArgument {
                what: "hemisphere normal",
            }
        } else {
            GeomError::NonFiniteArgument {
                what: "hemisphere normal",
            }
        };
        for p in [SphericalPolygon::full(), up.clone()] {
            assert_eq!(p.try_clip_to_hemisphere(bad), Err(want.clone()), "{bad}");
            assert!(p.clip_to_hemisphere(bad).is_empty(), "{bad}");
        }
    }
    // The smallest normals that name a direction are valid (the check is not a length test).
    let tiny = DVec3::new(0.0, 0.0, f64::from_bits(1));
    assert_eq!(
        up.try_clip_to_hemisphere(tiny),
        Ok(up.clip_to_hemisphere(DVec3::Z))
    );
    assert!(close(
        up.clip_to_hemisphere(tiny).solid_angle(),
        up.solid_angle(),
        0.0
    ));
}

#[test]
fn clip_hemisphere_by_orthogonal_hemisphere_is_a_quarter() {
    // Vertices X, Y, -X, -Y: two of them lie exactly on the clipping circle x = 0.
    let upper = poly(vec![vec![DVec3::X, DVec3::Y, -DVec3::X, -DVec3::Y]]);
    for n in [DVec3::X, -DVec3::X, DVec3::Y, DVec3::new(1.0, 1.0, 0.0)] {
        let q = upper.clip_to_hemisphere(n);
        assert!(
            close(q.solid_angle(), PI, 1e-14),
            "n = {n}: {}",
            q.solid_angle()
        );
    }
    // The ring lying on the clipping circle itself.
    assert!(close(
        upper.clip_to_hemisphere(DVec3::Z).solid_angle(),
        2.0 * PI,
        1e-14
    ));
    assert!(upper.clip_to_hemisphere(-DVec3::Z).is_empty());
}

#[test]
fn clip_with_vertex_on_the_boundary() {
    // Triangle touching the horizon at one vertex from above, and its mirror from below.
    let t = vec![
        DVec3::new(1.0, 0.0, 0.0),
        DVec3::new(0.0, 1.0, 1.0),
        DVec3::new(-0.2, 0.1, 1.0),
    ];
    let above = poly(vec![t.clone()]);
    let w = above.solid_angle();
    assert!(close(
        above.clip_to_hemisphere(DVec3::Z).solid_angle(),
        w,
        1e-15
    ));
    assert!(above.clip_to_hemisphere(-DVec3::Z).is_empty());
    // The complement contains the rest of the circle: clipping keeps the hemisphere minus t.
    let rest = above.complement();
    assert!(close(
        rest.clip_to_hemisphere(DVec3::Z).solid_angle(),
        2.0 * PI - w,
        1e-13
    ));
    assert!(close(
        rest.clip_to_hemisphere(-DVec3::Z).solid_angle(),
        2.0 * PI,
        1e-13
    ));
}

#[test]
fn clip_with_edge_on_the_boundary() {
    // A quad standing on the equator: its bottom edge lies on the clipping circle.
    let q = vec![
        DVec3::new(1.0, -0.5, 0.0),
        DVec3::new(1.0, 0.5, 0.0),
        DVec3::new(1.0, 0.5, 0.6),
        DVec3::new(1.0, -0.5, 0.6),
    ];
    let above = poly(vec![q.clone()]);
    let w = above.solid_angle();
    let up = above.clip_to_hemisphere(DVec3::Z);
    assert!(close(up.solid_angle(), w, 1e-15));
    assert_eq!(up.vertex_count(), 4);
    assert!(above.clip_to_hemisphere(-DVec3::Z).is_empty());
    let mirror = poly(vec![
        q.iter().rev().map(|p| DVec3::new(p.x, p.y, -p.z)).collect(),
    ]);
    assert!(close(mirror.solid_angle(), w, 1e-15));
    assert!(mirror.clip_to_hemisphere(DVec3::Z).is_empty());
    assert!(close(
        mirror.clip_to_hemisphere(-DVec3::Z).solid_angle(),
        w,
        1e-15
    ));
}

#[test]
fn clip_non_convex_with_many_crossings() {
    // A comb: teeth alternately reaching above and below the equator, 6 crossings per side.
    let mut ring = Vec::new();
    let teeth = 6;
    for i in 0..teeth {
        let y0 = -0.6 + 1.2 * i as f64 / teeth as f64;
        let y1 = y0 + 0.6 / teeth as f64;
        ring.push(DVec3::new(1.0, y0, -0.3));
        ring.push(DVec3::new(1.0, y0, 0.4));
        ring.push(DVec3::new(1.0, y1, 0.4));
        ring.push(DVec3::new(1.0, y1, -0.3));
    }
    ring.push(DVec3::new(1.0, 0.6, -0.3));
    ring.push(DVec3::new(1.0, 0.6, -0.5));
    ring.push(DVec3::new(1.0, -0.6, -0.5));
    // Reverse so that it is counter-clockwise seen from +x.
    ring.reverse();
    let comb = poly(vec![ring]);
    let up = comb.clip_to_hemisphere(DVec3::Z);
    let down = comb.clip_to_hemisphere(-DVec3::Z);
    assert_eq!(up.ring_count(), teeth);
    assert_eq!(down.ring_count(), 1);
    assert!(close(
        up.solid_angle() + down.solid_angle(),
        comb.solid_angle(),
        1e-14
    ));
    let mut rng = Rng::new(3);
    let mc = mc_solid_angle(&mut rng, 256, 512, |d| d.z >= 0.0 && comb.contains(d));
    let cells = crossed_cells(
        boundary_edges(&comb).chain(great_circle(DVec3::Z)),
        256,
        512,
    );
    assert_mc_agrees(up.solid_angle(), mc, cells, "comb above the horizon");
    for p in [&up, &down] {
        assert!(SphericalPolygon::new(p.rings().map(<[DVec3]>::to_vec).collect()).is_ok());
    }
}

#[test]
fn gnomonic_maps_great_circles_to_lines() {
    let g = Gnomonic::new(DVec3::new(0.2, 0.3, 1.0)).unwrap();
    let (a, b) = (
        DVec3::new(1.0, 0.2, 0.9).normalize(),
        DVec3::new(-0.4, 0.8, 0.7).normalize(),
    );
    let (pa, pb) = (g.project(a).unwrap(), g.project(b).unwrap());
    for t in [0.1, 0.5, 0.77] {
        let m = g.project((a * (1.0 - t) + b * t).normalize()).unwrap();
        let cross = (pb - pa).perp_dot(m - pa);
        assert!(cross.abs() < 1e-14, "{cross}");
    }
    // Orientation is preserved: a counter-clockwise ring stays counter-clockwise.
    let ring = cap_ring(g.center(), 0.5, 5);
    let pts: Vec<DVec2> = ring.iter().map(|&p| g.project(p).unwrap()).collect();
    let area2: f64 = (0..5).map(|i| pts[i].perp_dot(pts[(i + 1) % 5])).sum();
    assert!(area2 > 0.0);
}

#[test]
fn enclosing_cap_reports_the_radius() {
    let c = DVec3::new(1.0, 2.0, -0.5).normalize();
    let ring = cap_ring(c, 0.7, 6);
    let (center, cosr) = enclosing_cap(&ring).unwrap();
    assert!((center - c).length() < 1e-12);
    assert!(close(cosr, 0.7f64.cos(), 1e-12));
    // A hemisphere-spanning set (the cap would be larger than a hemisphere).
    let mut wide = cap_ring(c, 1.7, 6);
    wide.push(c);
    assert_eq!(enclosing_cap(&wide), Err(GeomError::NotInOpenHemisphere));
}

#[test]
fn order_edges_of_a_box_silhouette() {
    // The silhouette of a cube seen from a corner direction is a hexagon; its edges arrive in the
    // order of the faces and in arbitrary directions.
    let eye = DVec3::new(3.0, 2.5, 2.0);
    let corners: Vec<DVec3> = [
        (1.0, -1.0, -1.0),
        (1.0, 1.0, -1.0),
        (-1.0, 1.0, -1.0),
        (-1.0, 1.0, 1.0),
        (-1.0, -1.0, 1.0),
        (1.0, -1.0, 1.0),
    ]
    .iter()
    .map(|&(x, y, z)| (DVec3::new(x, y, z) - eye).normalize())
    .collect();
    let edges: Vec<_> = (0..6)
        .map(|i| (corners[(i * 5 + 3) % 6], corners[(i * 5 + 4) % 6]))
        .collect();
    let shuffled: Vec<_> = edges
        .iter()
        .enumerate()
        .map(|(i, &(a, b))| if i % 2 == 0 { (b, a) } else { (a, b) })
        .collect();
    let p = order_edges(&shuffled).unwrap();
    assert_eq!(p.ring_count(), 1);
    assert_eq!(p.vertex_count(), 6);
    assert!(p.solid_angle() < 2.0 * PI);
    assert!(p.contains(-eye)); // the cube's center, seen from the eye
    // Directed form keeps orientation: the two directions give complementary regions, and the
    // smaller of them is the outline found above.
    let fwd: Vec<_> = (0..6).map(|i| (corners[i], corners[(i + 1) % 6])).collect();
    let bwd: Vec<_> = fwd.iter().rev().map(|&(a, b)| (b, a)).collect();
    let (q, r) = (
        order_directed_edges(&fwd).unwrap(),
        order_directed_edges(&bwd).unwrap(),
    );
    assert!(close(q.solid_angle() + r.solid_angle(), 4.0 * PI, 1e-12));
    assert!(close(
        q.solid_angle().min(r.solid_angle()),
        p.solid_angle(),
        1e-12
    ));
}

/// Minimized fuzz failures (`fuzz/fuzz_targets/sphere_clip.rs`), kept as regressions.
#[test]
fn fuzz_regression_clip_twice_through_a_pinch() {
    // A large region (the outside of a triangle touching the clip circle at one vertex) clips to
    // a ring that passes through that vertex twice and then runs once round the circle. Clipping
    // that again must keep the circle lobe: at the second visit the ring continues exactly along
    // the circle, where a corner test deciding "closed" by rounding would drop it.
    let p = poly(vec![vec![
        DVec3::new(-1.0, -1.0, -63.0),
        DVec3::new(0.0, 4.0, -1.0),
        DVec3::new(-46.0, -3.0, 46.0),
    ]]);
    let n = DVec3::new(-1.0, 0.0, -1.0);
    let once = p.clip_to_hemisphere(n);
    let twice = once.clip_to_hemisphere(n);
    assert!(
        close(twice.solid_angle(), once.solid_angle(), 1e-12),
        "{} vs {}",
        twice.solid_angle(),
        once.solid_angle()
    );
    let down = p.clip_to_hemisphere(-n);
    assert!(close(
        once.solid_angle() + down.solid_angle(),
        p.solid_angle(),
        1e-12
    ));
    // The triangle lies in the clip hemisphere: the clipped region is the hemisphere minus it.
    let tri = p.complement().solid_angle();
    assert!(close(once.solid_angle(), 2.0 * PI - tri, 1e-12));
}

#[test]
fn fuzz_regression_sliver_is_rejected() {
    // Three directions on one great circle to within rounding (area 9e-18 sr over a perimeter
    // of 3 rad): validation must reject it, since the horizon clip would have no reliable side.
    let r = SphericalPolygon::new(vec![vec![
        DVec3::new(-1.0, -1.0, 10.0),
        DVec3::new(-1.0, 96.0, 10.0),
        DVec3::new(0.0, 1.0, 0.0),
    ]]);
    // Three directions on a great circle fold back at one of them: either diagnosis is right.
    assert!(
        matches!(
            r,
            Err(GeomError::ZeroArea { ring: 0 }) | Err(GeomError::SelfIntersecting { .. })
        ),
        "{r:?}"
    );
    // A tiny but well-shaped polygon is fine.
    assert!(SphericalPolygon::new(vec![cap_ring(DVec3::Z, 1e-7, 4)]).is_ok());
}

#[test]
fn fuzz_regression_spike_within_rounding_is_rejected() {
    // b, c, d lie on one great circle in the integer input, with d between b and c: the ring
    // folds back at c. After normalization the fold is no longer exact; validation must still
    // reject it (clipping it produced a self-crossing ring).
    let r = SphericalPolygon::new(vec![vec![
        DVec3::new(127.0, 127.0, -43.0),
        DVec3::new(4.0, 4.0, 127.0),
        DVec3::new(127.0, 0.0, 0.0),
        DVec3::new(13.0, 4.0, 127.0),
    ]]);
    assert!(
        matches!(r, Err(GeomError::SelfIntersecting { .. })),
        "{r:?}"
    );
}

#[test]
fn fuzz_regression_vertex_exactly_on_own_edge_is_rejected() {
    // (32, -5, -1) lies exactly on the great circle through (46, 0, 0) and (-1, -5, -1), between
    // them: the ring touches itself. Normalization made the contact inexact, so validation now
    // runs its exact predicates on the caller's coordinates (scaled by powers of two only).
    let r = SphericalPolygon::new(vec![vec![
        DVec3::new(-65.0, -1.0, -1.0),
        DVec3::new(32.0, -5.0, -1.0),
        DVec3::new(-1.0, 58.0, -1.0),
        DVec3::new(46.0, 0.0, 0.0),
        DVec3::new(-1.0, -5.0, -1.0),
        DVec3::new(32.0, 32.0, 32.0),
    ]]);
    assert!(
        matches!(r, Err(GeomError::SelfIntersecting { .. })),
        "{r:?}"
    );
}

#[test]
fn fuzz_regression_two_entries_at_one_pinch_on_the_circle() {
    // Rings 0 and 1 share a vertex lying on the clip circle, and both enter the hemisphere
    // there; the boundary arriving along the circle must turn into the entry met first clockwise
    // from the circle behind it (the other one makes the result exceed the input).
    let v = DVec3::new;
    let p = poly(vec![
        vec![
            v(-1.0, -1.0, -1.0),
            v(-1.0, -5.0, -1.0),
            v(-63.0, -68.0, 26.0),
        ],
        vec![
            v(-1.0, -1.0, 8.0),
            v(35.0, 43.0, -1.0),
            v(-1.0, 1.0, 0.0),
            v(-1.0, -1.0, -1.0),
        ],
        vec![
            v(-1.0, -43.0, 57.0),
            v(0.0, -1.0, -5.0),
            v(-1.0, -91.0, -1.0),
            v(10.0, -43.0, 7.0),
            v(-1.0, -1.0, 8.0),
        ],
    ])
    .complement();
    let n = v(-1.0, 0.0, 1.0);
    let (up, down) = (p.clip_to_hemisphere(n), p.clip_to_hemisphere(-n));
    assert!(close(
        up.solid_angle() + down.solid_angle(),
        p.solid_angle(),
        1e-12
    ));
    for q in [&up, &down] {
        assert!(SphericalPolygon::new(q.rings().map(<[DVec3]>::to_vec).collect()).is_ok());
    }
}
