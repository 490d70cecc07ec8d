//! Spherical set operations: solid-angle identities on random and degenerate operands, Monte
//! Carlo checks for regions larger than a hemisphere, and the seed's per-triangle workflow.

mod support;

use arealight::glam::DVec3;
use arealight::planar::BoolOp;
use arealight::sphere::{SphericalPolygon, order_directed_edges};
use proptest::prelude::*;
use std::f64::consts::PI;
use support::Rng;
use support::sphere::{
    assert_mc_agrees, boundary_edges, crossed_cells, icosphere, mc_solid_angle, star_ring,
};

/// Identity tolerance: 1e-11 of the sphere, below the 1e-10 * 4 pi.
const TOL: f64 = 1e-11 * 4.0 * PI;

fn polygon_about(rng: &mut Rng, c: DVec3) -> Option<SphericalPolygon> {
    let n = 3 + (rng.next_u64() % 9) as usize;
    let rho = rng.range(0.05, 1.4);
    let ring = star_ring(rng, c, n, rho, 0.6);
    match rng.next_u64() % 4 {
        0 | 1 => SphericalPolygon::new(vec![ring]).ok(),
        2 => SphericalPolygon::new(vec![ring])
            .ok()
            .map(|p| p.complement()),
        _ => {
            let m = 3 + (rng.next_u64() % 5) as usize;
            let mut hole = star_ring(rng, c, m, 0.25 * rho, 0.8);
            hole.reverse();
            SphericalPolygon::new(vec![ring, hole]).ok()
        }
    }
}

/// A pair of operands: independent random polygons with nearby centers, or degenerate pairs
/// (identical, complementary, sharing vertices and edges).
fn pair(seed: u64) -> Option<(SphericalPolygon, SphericalPolygon)> {
    let mut rng = Rng::new(seed);
    let c = rng.dir();
    let a = polygon_about(&mut rng, c)?;
    let b = match rng.next_u64() % 6 {
        0 => a.clone(),
        1 => a.complement(),
        2 => {
            // A polygon on a subset of a's vertices (a sub-polygon, sharing vertices and maybe
            // edges), if valid.
            let ring: Vec<DVec3> = a.rings().next()?.to_vec();
            let keep: Vec<DVec3> = ring
                .iter()
                .enumerate()
                .filter(|(i, _)| i % 2 == 0 || *i == 1)
                .map(|(_, p)| *p)
                .collect();
            SphericalPolygon::new(vec![keep]).ok()?
        }
        3 => {
            let d = (c + rng.dir() * rng.range(0.0, 0.8)).normalize();
            polygon_about(&mut rng, d)?
        }
        _ => {
            // Far apart: the operands' vertices span more than a hemisphere, which sends the
            // operation through the octant split.
            let d = (-c + rng.dir() * rng.range(0.0, 0.5)).normalize();
            polygon_about(&mut rng, d)?
        }
    };
    Some((a, b))
}

fn check_identities(a: &SphericalPolygon, b: &SphericalPolygon) -> Result<(), TestCaseError> {
    let op = |o| a.boolean(b, o);
    let (i, u, d, x) = (
        op(BoolOp::Intersection),
        op(BoolOp::Union),
        op(BoolOp::Difference),
        op(BoolOp::Xor),
    );
    prop_assert!(
        i.is_ok() && u.is_ok() && d.is_ok() && x.is_ok(),
        "{:?} {:?} {:?} {:?}",
        i,
        u,
        d,
        x
    );
    let (i, u, d, x) = (i.unwrap(), u.unwrap(), d.unwrap(), x.unwrap());
    let (wa, wb) = (a.solid_angle(), b.solid_angle());
    let (wi, wu, wd, wx) = (
        i.solid_angle(),
        u.solid_angle(),
        d.solid_angle(),
        x.solid_angle(),
    );
    prop_assert!(
        (wd + wi - wa).abs() <= TOL,
        "A-B + AnB = A: {} + {} vs {}",
        wd,
        wi,
        wa
    );
    prop_assert!(
        (wu - (wa + wb - wi)).abs() <= TOL,
        "AuB: {} vs {}",
        wu,
        wa + wb - wi
    );
    prop_assert!((wx - (wu - wi)).abs() <= TOL, "xor: {} vs {}", wx, wu - wi);
    // Results are valid polygons: they pass full validation again.
    for r in [&i, &u, &d, &x] {
        if !r.is_full() {
            let again = SphericalPolygon::new(r.rings().map(<[DVec3]>::to_vec).collect());
            prop_assert!(again.is_ok(), "invalid result {:?}: {:?}", again, r);
        }
    }
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig { cases: support::cases(256), ..ProptestConfig::default() })]

    #[test]
    fn identities_hold(seed in any::<u64>()) {
        let Some((a, b)) = pair(seed) else { return Ok(()); };
        check_identities(&a, &b)?;
    }
}

#[test]
fn empty_and_full_results() {
    let mut rng = Rng::new(5);
    let a = polygon_about(&mut rng, DVec3::new(0.2, 0.3, 0.9).normalize()).unwrap();
    let c = a.complement();
    assert!(a.boolean(&a, BoolOp::Difference).unwrap().is_empty());
    assert!(a.boolean(&c, BoolOp::Intersection).unwrap().solid_angle() < 1e-12);
    let u = a.boolean(&c, BoolOp::Union).unwrap();
    assert!(
        (u.solid_angle() - 4.0 * PI).abs() < 1e-12,
        "{}",
        u.solid_angle()
    );
    let x = a.boolean(&c, BoolOp::Xor).unwrap();
    assert!((x.solid_angle() - 4.0 * PI).abs() < 1e-12);
    let full = SphericalPolygon::full();
    assert!(full.boolean(&a, BoolOp::Difference).unwrap() == c);
    assert!(a.boolean(&full, BoolOp::Intersection).unwrap() == a);
}

#[test]
fn larger_than_hemisphere_matches_monte_carlo() {
    // A light filling the whole upper hemisphere minus occluders crossing the horizon, and
    // operands whose union exceeds a hemisphere.
    let up = SphericalPolygon::new(vec![vec![DVec3::X, DVec3::Y, -DVec3::X, -DVec3::Y]]).unwrap();
    let mut rng = Rng::new(17);
    for k in 0..6 {
        let c = DVec3::new(
            rng.range(-1.0, 1.0),
            rng.range(-1.0, 1.0),
            rng.range(-0.3, 0.3),
        )
        .normalize();
        let occ = SphericalPolygon::new(vec![star_ring(&mut rng, c, 7, 0.6, 0.6)]).unwrap();
        let dir = rng.dir();
        let big = polygon_about(&mut rng, dir).unwrap().complement();
        for (a, b) in [(&up, &occ), (&big, &occ), (&up, &big)] {
            for op in [
                BoolOp::Difference,
                BoolOp::Union,
                BoolOp::Intersection,
                BoolOp::Xor,
            ] {
                let r = a.boolean(b, op).unwrap();
                let f = |d: DVec3| {
                    let (x, y) = (a.contains(d), b.contains(d));
                    match op {
                        BoolOp::Difference => x && !y,
                        BoolOp::Union => x || y,
                        BoolOp::Intersection => x && y,
                        BoolOp::Xor => x != y,
                    }
                };
                let mut mrng = Rng::new(k as u64 * 31 + op as u64);
                let mc = mc_solid_angle(&mut mrng, 64, 128, f);
                let cells = crossed_cells(boundary_edges(a).chain(boundary_edges(b)), 64, 128);
                assert_mc_agrees(r.solid_angle(), mc, cells, &format!("case {k} {op:?}"));
            }
        }
    }
}

#[test]
fn per_triangle_chain_equals_silhouette_difference() {
    let x = DVec3::ZERO; // shading point
    let light = SphericalPolygon::new(vec![vec![
        DVec3::new(-1.0, -1.0, 3.0),
        DVec3::new(1.0, -1.0, 3.0),
        DVec3::new(1.0, 1.0, 3.0),
        DVec3::new(-1.0, 1.0, 3.0),
    ]])
    .unwrap();
    for (center, radius) in [
        (DVec3::new(0.3, 0.2, 1.5), 0.4),
        (DVec3::new(0.7, -0.4, 1.6), 0.35),
    ] {
        let (v, faces) = icosphere(center, radius);
        assert_eq!(faces.len(), 80);
        // Per triangle: subtract every face as a spherical triangle (its smaller side).
        let mut chain = light.clone();
        for f in &faces {
            let tri = SphericalPolygon::new(vec![f.iter().map(|&i| v[i] - x).collect()]).unwrap();
            let tri = if tri.solid_angle() > 2.0 * PI {
                tri.complement()
            } else {
                tri
            };
            chain = chain.boolean(&tri, BoolOp::Difference).unwrap();
        }
        // Silhouette: edges between front- and back-facing faces, oriented by the front face.
        let facing = |f: &[usize; 3]| {
            (v[f[1]] - v[f[0]])
                .cross(v[f[2]] - v[f[0]])
                .dot(x - v[f[0]])
                > 0.0
        };
        let mut owner = std::collections::HashMap::new();
        for (k, f) in faces.iter().enumerate() {
            for e in 0..3 {
                owner.insert((f[e], f[(e + 1) % 3]), k);
            }
        }
        let mut sil = Vec::new();
        for f in faces.iter().filter(|f| facing(f)) {
            for e in 0..3 {
                let (a, b) = (f[e], f[(e + 1) % 3]);
                if !facing(&faces[owner[&(b, a)]]) {
                    sil.push((v[a] - x, v[b] - x));
                }
            }
        }
        let s = order_directed_edges(&sil).unwrap();
        let s = if s.solid_angle() > 2.0 * PI {
            s.complement()
        } else {
            s
        };
        let direct = light.boolean(&s, BoolOp::Difference).unwrap();
        let (wc, wd) = (chain.solid_angle(), direct.solid_angle());
        assert!(
            (wc - wd).abs() <= 1e-10,
            "per-triangle {wc} vs silhouette {wd}"
        );
        assert!(
            wd < light.solid_angle() - 1e-3,
            "the occluder must hide something: {wd} vs {} (silhouette {})",
            light.solid_angle(),
            s.solid_angle()
        );
        let (ic, id) = (
            arealight::ltc::clamped_cosine_integral(&chain),
            arealight::ltc::clamped_cosine_integral(&direct),
        );
        assert!((ic - id).abs() <= 1e-10, "{ic} vs {id}");
    }
}

/// Minimized failures, kept as named regressions.
#[test]
fn regression_hole_pinched_at_all_its_vertices() {
    // A difference produced this valid result: ring 2 is a hole touching ring 1 at all four of its
    // vertices. Validation probed a shared vertex to decide nesting and rejected it as
    // inconsistently oriented (proptest seed 9528998366313849765 of the first generator).
    let v: Vec<DVec3> = [
        [0.8805346722913457, -0.4722894962975242, -0.0400165288325119],
        [0.9924724683883259, -0.0786389200278272, 0.09388460868555967],
        [0.9361830267711194, 0.07291149209648706, 0.3438680774743845],
        [0.4255883721496805, 0.28191631485901264, 0.8598823924859138],
        [0.19846204268946735, 0.0478470059744847, 0.9789399785639575],
        [
            -0.14954229638130762,
            -0.28350314118493286,
            0.9472397112300989,
        ],
        [-0.6056135022243624, -0.5929388413426258, 0.5307125552978811],
        [
            -0.34189444626618454,
            -0.9241232940894043,
            0.17059989722648516,
        ],
        [
            0.13750115425897727,
            -0.9861716896054175,
            -0.0925139513708341,
        ],
        [0.45650157389783674, -0.8869909583839704, -0.069666008740877],
        [0.3384933543995443, -0.8108789802150641, 0.4773861418942971],
        [0.4538319640554113, -0.6210286583727801, 0.6390304796183925],
        [0.4325667033032154, -0.6173080161196025, 0.6571277352447303],
        [0.4970250646577318, -0.5135046899765584, 0.6994848236195379],
        [0.5340502584703976, -0.38786487927981667, 0.7512330908905405],
        [0.5454022656463088, -0.4182637225147756, 0.7263551659181311],
        [0.5853235416977843, -0.3228426490322618, 0.7437533028499397],
        [0.803787863709287, -0.44528545964403266, 0.39451987222859014],
        [0.7528420075593608, -0.6059536516879346, 0.257000162762689],
        [0.6022318519117558, -0.6330605777798392, 0.48636519345445917],
        [0.6070259857120942, -0.6945099893290099, 0.3862322195162894],
        [0.4970250646577318, -0.5135046899765584, 0.6994848236195379],
        [0.4538319640554113, -0.6210286583727801, 0.6390304796183925],
        [0.6022318519117558, -0.6330605777798392, 0.48636519345445917],
        [0.5454022656463088, -0.4182637225147756, 0.7263551659181311],
    ]
    .iter()
    .map(|c: &[f64; 3]| DVec3::from_array(*c))
    .collect();
    let p = SphericalPolygon::new(vec![v[..10].to_vec(), v[10..21].to_vec(), v[21..].to_vec()]);
    assert!(p.is_ok(), "{p:?}");
    let p = p.unwrap();
    let outer = SphericalPolygon::new(vec![v[..10].to_vec()])
        .unwrap()
        .solid_angle();
    let inner = SphericalPolygon::new(vec![v[10..21].to_vec()])
        .unwrap()
        .solid_angle();
    let hole = SphericalPolygon::new(vec![v[21..].to_vec()])
        .unwrap()
        .solid_angle();
    // Each single ring measures its left side; the region is their sum modulo 4 pi, and with
    // the pinched hole it must be smaller than the outer ring alone.
    let w = p.solid_angle();
    assert!((w - (outer + inner + hole).rem_euclid(4.0 * PI)).abs() < 1e-12);
    assert!(w < outer && w > 0.0);
}

#[test]
fn near_antipodal_operands() {
    // Lunes from the north pole to within 1e-6 of the south pole (edges nearly pi long), against
    // a band around the equator and against each other.
    let lune = |phi0: f64, phi1: f64| {
        let eq = |phi: f64| DVec3::new(phi.cos(), phi.sin(), 0.0);
        let south = DVec3::new(1e-6, 0.0, -1.0).normalize();
        SphericalPolygon::new(vec![vec![DVec3::Z, eq(phi0), south, eq(phi1)]]).unwrap()
    };
    let band = SphericalPolygon::new(vec![vec![
        DVec3::new(1.0, -0.5, -0.2),
        DVec3::new(1.0, 0.5, -0.2),
        DVec3::new(1.0, 0.5, 0.2),
        DVec3::new(1.0, -0.5, 0.2),
    ]])
    .unwrap();
    let cases = [
        (lune(-0.3, 0.3), band.clone()),
        (lune(-0.3, 0.3), lune(0.0, 0.6)),
        (lune(-0.3, 0.3).complement(), band.clone()),
        (lune(0.2, 2.8), lune(2.7, 4.0)),
    ];
    for (k, (a, b)) in cases.iter().enumerate() {
        check_identities(a, b).unwrap();
        for op in [BoolOp::Difference, BoolOp::Intersection] {
            let r = a.boolean(b, op).unwrap();
            let mut rng = Rng::new(k as u64);
            let mc = mc_solid_angle(&mut rng, 64, 128, |d| {
                let (x, y) = (a.contains(d), b.contains(d));
                if op == BoolOp::Difference {
                    x && !y
                } else {
                    x && y
                }
            });
            let cells = crossed_cells(boundary_edges(a).chain(boundary_edges(b)), 64, 128);
            assert_mc_agrees(
                r.solid_angle(),
                mc,
                cells,
                &format!("near-antipodal case {k} {op:?}"),
            );
        }
    }
}

#[test]
fn fuzz_regression_union_touching_at_a_vertex_inside_an_edge() {
    // B touches the boundary circle of the hemisphere A at one of B's vertices, which lies
    // inside an edge of A. The planar union returns the touching point as a T-junction, which is
    // not a valid spherical ring set, so it must be inserted into the touched edge.
    let a = SphericalPolygon::new(vec![vec![
        DVec3::new(48.0, 48.0, 37.0),
        DVec3::new(-1.0, -1.0, -1.0),
        DVec3::new(-1.0, -1.0, 46.0),
    ]])
    .unwrap()
    .complement();
    let b = SphericalPolygon::new(vec![vec![
        DVec3::new(37.0, 48.0, -1.0),
        DVec3::new(-1.0, -1.0, -17.0),
        DVec3::new(-1.0, 48.0, 48.0),
    ]])
    .unwrap();
    check_identities(&a, &b).unwrap();
    let u = a.boolean(&b, BoolOp::Union).unwrap();
    assert!((u.solid_angle() - (a.solid_angle() + b.solid_angle())).abs() < 1e-12);
}

#[test]
fn fuzz_regression_pinch_vertex_containment() {
    // An octant piece of B touches itself at the pole (two lobes either side of a triangle's
    // corner). `contains` judged points near such a pinch from one visit's corner only, and the
    // projection took the piece for the complement of itself.
    let a = SphericalPolygon::new(vec![vec![
        DVec3::new(33.0, 48.0, -1.0),
        DVec3::new(-1.0, -1.0, -1.0),
        DVec3::new(-1.0, 3.0, 46.0),
    ]])
    .unwrap()
    .complement();
    let b = SphericalPolygon::new(vec![vec![
        DVec3::new(0.0, 0.0, 37.0),
        DVec3::new(77.0, -1.0, -1.0),
        DVec3::new(1.0, -1.0, 49.0),
    ]])
    .unwrap();
    check_identities(&a, &b).unwrap();
    // A and B together exceed the sphere: their union is all of it.
    let u = a.boolean(&b, BoolOp::Union).unwrap();
    assert!(
        (u.solid_angle() - 4.0 * PI).abs() < 1e-12,
        "{}",
        u.solid_angle()
    );
}

#[test]
fn fuzz_regression_touching_a_boundary_that_lies_on_a_cut() {
    // B is the hemisphere bounded by the great circle y = 0, one of the octant cuts; A touches
    // it at one of its vertices. After the cut edges cancel, A's vertex lies inside one of B's
    // surviving circle edges, which must be split there.
    let a = SphericalPolygon::new(vec![vec![
        DVec3::new(0.0, -1.0, 1.0),
        DVec3::new(0.0, -1.0, 64.0),
        DVec3::new(-1.0, 0.0, 85.0),
    ]])
    .unwrap();
    let b = SphericalPolygon::new(vec![vec![
        DVec3::new(1.0, 0.0, -1.0),
        DVec3::new(-65.0, 0.0, -1.0),
        DVec3::new(-1.0, 0.0, 85.0),
    ]])
    .unwrap();
    check_identities(&a, &b).unwrap();
    let u = a.boolean(&b, BoolOp::Union).unwrap();
    assert!((u.solid_angle() - (a.solid_angle() + b.solid_angle())).abs() < 1e-12);
}

#[test]
fn fuzz_regression_pinch_on_the_cut_circle() {
    // B's two rings share a vertex on two of the octant cuts. Clipping the pinched piece joined
    // the coincident exits and entries there by one visit's corner only, adding a whole circle.
    let v = DVec3::new;
    let a = SphericalPolygon::new(vec![vec![
        v(9.0, 16.0, -10.0),
        v(-9.0, 37.0, -1.0),
        v(-1.0, -56.0, -1.0),
        v(117.0, -1.0, 43.0),
    ]])
    .unwrap();
    let b = SphericalPolygon::new(vec![
        vec![
            v(-1.0, 37.0, 11.0),
            v(31.0, 0.0, 0.0),
            v(71.0, 71.0, 71.0),
            v(-71.0, -1.0, 2.0),
            v(-103.0, -103.0, -42.0),
        ],
        vec![
            v(-1.0, 9.0, -103.0),
            v(-1.0, 51.0, -109.0),
            v(-109.0, -109.0, -109.0),
            v(52.0, 0.0, 0.0),
        ],
    ])
    .unwrap();
    check_identities(&a, &b).unwrap();
    let mut p = b.clone();
    for n in [DVec3::X, DVec3::Y, DVec3::Z] {
        let (up, down) = (p.clip_to_hemisphere(n), p.clip_to_hemisphere(-n));
        assert!((up.solid_angle() + down.solid_angle() - p.solid_angle()).abs() < 1e-12);
        p = up;
    }
}

#[test]
fn regression_union_with_vertex_copies_ulps_apart() {
    // Union of the front faces of a two-box light (tests/shade_geometry.rs, point 20): the
    // accumulated region holds two copies of one mesh vertex 6e-17 apart (rings 1 and 3), from
    // different earlier projections. Welding the next triangle to one copy only would keep an
    // edge overlapping the other, so operands are welded within 1e-12 first.
    let v = DVec3::new;
    let a = SphericalPolygon::new(vec![
        vec![
            v(0.2283698177811374, 0.19758094124714712, 0.9533147423503434),
            v(
                -0.02328735593967926,
                0.020252048352230094,
                0.9995236633471353,
            ),
            v(
                -0.019513797695109907,
                0.01697034113622291,
                0.9996655536834479,
            ),
        ],
        vec![
            v(
                -0.029354680297508477,
                0.14938127722141048,
                0.9883438352923193,
            ),
            v(
                -0.21798262862762907,
                0.42849310155388926,
                0.8768564509298643,
            ),
            v(-0.1793881971774195, 0.3526272046293251, 0.9184083673773575),
        ],
        vec![
            v(
                -0.029354680297508477,
                0.14938127722141048,
                0.9883438352923193,
            ),
            v(0.2844500576872629, 0.3557259865176156, 0.8902511933144387),
            v(0.3407798912685305, 0.4261706395579054, 0.8380021788073193),
        ],
        vec![
            v(-0.21798262862762907, 0.4284931015538893, 0.8768564509298642),
            v(0.3407798912685305, 0.4261706395579054, 0.8380021788073193),
            v(0.1508351825176402, 0.6198279105419324, 0.7701052584082856),
        ],
    ])
    .unwrap();
    let b = SphericalPolygon::new(vec![vec![
        v(
            -0.21798262862762904,
            0.42849310155388937,
            0.8768564509298642,
        ),
        v(
            -0.03709500671938268,
            0.18877056149538507,
            0.9813203531921704,
        ),
        v(0.34077989126853064, 0.4261706395579053, 0.8380021788073193),
    ]])
    .unwrap();
    check_identities(&a, &b).unwrap();
}

#[test]
fn regression_rings_sharing_an_edge_through_vertex_copies_1e12_apart() {
    // A light face minus the cut side triangles of a box touching its plane (tests/shade_census.rs,
    // case 208 at CENSUS_CASES=5): the running difference `a` holds two outer rings (1 and 2)
    // that share an edge whose two vertex copies lie 1e-12 apart, each an intersection point
    // computed in another projection. Valid on the sphere, but projected the two edges cross,
    // which the planar validation rejects in every projection and octant; welding them makes
    // the rings overlap along the edge. The projected rings are read under the positive fill
    // rule instead.
    let v = DVec3::new;
    let a = SphericalPolygon::new(vec![
        vec![
            v(
                -0.33715148465616496,
                -0.002970467742793994,
                0.9414457247847763,
            ),
            v(
                -0.33653860527021756,
                -0.060341687974531315,
                0.9397343496197003,
            ),
            v(
                -0.3502376764013839,
                -0.06279794429339862,
                0.9345533629608759,
            ),
            v(-0.4340368808005864, -0.0604000474259736, 0.8988680772926791),
            v(
                -0.41613686146560425,
                -0.2900589964427813,
                0.8617980570366605,
            ),
            v(-0.2776901932547135, -0.1386184140818011, 0.9506172162587874),
            v(
                -0.27877890635351554,
                -0.10728211204887807,
                0.9543442092906886,
            ),
            v(
                -0.2559629764347708,
                -0.09850188838684043,
                0.9616549967004171,
            ),
            v(
                -0.24018802621516536,
                -0.09891352929963569,
                0.9656737677830713,
            ),
            v(
                -0.006554012536182908,
                0.13833259503210815,
                0.9903641441769578,
            ),
            v(-0.4314312935178255, 0.12479884959194724, 0.8934720399173454),
            v(-0.43418492385837754, 0.0544827530004199, 0.8991746668582195),
            v(-0.3503668157425352, 0.05664729668821203, 0.934897950689996),
            v(-0.3366531713953598, 0.05443007506474083, 0.9400542586031368),
        ],
        vec![
            v(
                -0.27877890635351554,
                -0.10728211204887807,
                0.9543442092906886,
            ),
            v(
                -0.2611572429162339,
                -0.12105280572484718,
                0.9576758912589026,
            ),
            v(
                -0.24794593197272838,
                -0.10708642670405115,
                0.9628371160450416,
            ),
            v(
                -0.24788224023479263,
                -0.10653917895127205,
                0.962914221685696,
            ),
        ],
        vec![
            v(
                -0.24788224023375427,
                -0.10653917895124534,
                0.9629142216859661,
            ),
            v(-0.247945931971412, -0.10708642670266276, 0.9628371160455351),
            v(
                -0.24741570366269083,
                -0.10652717121782244,
                0.9630355296526834,
            ),
        ],
    ])
    .unwrap();
    let b = SphericalPolygon::new(vec![vec![
        v(
            -0.10484602205110993,
            -0.11109515621675774,
            0.9882637188145845,
        ),
        v(
            -0.2787789063535155,
            -0.10728211204887808,
            0.9543442092906887,
        ),
        v(
            -0.10246725140247803,
            -0.23801291674799122,
            0.9658417643957706,
        ),
    ]])
    .unwrap();
    check_identities(&a, &b).unwrap();
    assert_difference_matches_mc(&a, &b, 208);
}

/// The difference checked against stratified Monte Carlo containment in the operands.
fn assert_difference_matches_mc(a: &SphericalPolygon, b: &SphericalPolygon, seed: u64) {
    let d = a.boolean(b, BoolOp::Difference).unwrap();
    let mut rng = Rng::new(seed);
    let mc = mc_solid_angle(&mut rng, 256, 512, |p| a.contains(p) && !b.contains(p));
    let cells = crossed_cells(boundary_edges(a).chain(boundary_edges(b)), 256, 512);
    assert_mc_agrees(d.solid_angle(), mc, cells, "a - b");
}

#[test]
fn regression_octant_pieces_with_a_notch_narrower_than_the_silhouette_tolerance() {
    // A light face's part seen from a box face (tests/shade_census.rs, case 189 at
    // CENSUS_CASES=5) after a sliver occluder cut a notch into it, 1.3e-11 wide at its mouth and
    // 1e-10 at its end, minus a quad crossing the horizon. No cap narrower than a hemisphere
    // holds both, so the octant split solves the pieces; joining their rings at the silhouette
    // tolerance (1e-9) closed the notch into an edge walked twice. The pieces are joined within
    // 1e-13 when that fails.
    let v = DVec3::new;
    let a = SphericalPolygon::new(vec![vec![
        v(-0.16511769471157847, 0.9862738701259067, 0.0),
        v(0.05936841668733583, 0.2609116823376376, 0.9635354093751732),
        v(0.2184734868821402, 0.12365065690423623, 0.9679771952771977),
        v(0.21847348690723353, 0.12365065682204285, 0.9679771952820336),
        v(0.05936841669941417, 0.26091168227572753, 0.9635354093911933),
        v(0.19104542268463542, -0.7045131375627413, 0.6834931495433961),
        v(0.26172150129994853, -0.9651434379185827, 0.0),
        v(
            0.9769035015781964,
            0.21368095049456048,
            9.319347839783076e-17,
        ),
    ]])
    .unwrap();
    let b = SphericalPolygon::new(vec![vec![
        v(0.2988219341635244, -0.9543088869243387, 0.0),
        v(0.26880116855758873, -0.8584354581875471, 0.4368460780508519),
        v(
            -0.6870506422455467,
            -0.6838826383015593,
            0.24549124631986524,
        ),
        v(0.049252213552150925, -0.9987863732852053, 0.0),
    ]])
    .unwrap();
    check_identities(&a, &b).unwrap();
    assert_difference_matches_mc(&a, &b, 189);
}

#[test]
fn regression_octant_piece_with_a_crossing_1e11_from_a_pinch() {
    // A big quad light's face seen 1e-9 from an occluder face (tests/shade_census.rs, near-face
    // census case 164 at CENSUS_CASES=10): `a` is pinched at a vertex that the edge of `b`, the
    // cut occluder triangle seen from so close that it covers nearly a hemisphere, passes
    // within 1.2e-11 of. The octant piece holds a ring from the pinch to the crossing point
    // next to it, which the silhouette tolerance merged into one vertex.
    let v = DVec3::new;
    let a = SphericalPolygon::new(vec![vec![
        v(0.888974126652018, 0.0, 0.4579574239416606),
        v(0.8925914460878522, 0.0498363334732667, 0.4481036155140217),
        v(0.7936741031717446, 0.08700878979265583, 0.6020887712400425),
        v(0.8349152249708099, 0.07310679137567719, 0.5455015711862755),
        v(0.8925914460878522, 0.0498363334732667, 0.4481036155140217),
        v(
            0.4152000007164927,
            0.9097301574670505,
            8.492637520837422e-17,
        ),
        v(0.0, 1.0, 1.2819751242557095e-16),
        v(-1.0, 0.0, 0.0),
        v(-0.4637480047911058, -0.8859671484046509, 0.0),
        v(
            9.800142082344398e-18,
            -0.9665130959233881,
            0.25661729366624486,
        ),
        v(
            0.8451641394057182,
            -0.22002628780037123,
            0.48712011879964456,
        ),
    ]])
    .unwrap();
    let b = SphericalPolygon::new(vec![vec![
        v(0.9987810827737618, -0.04935938303172268, 0.0),
        v(0.7936741031717447, 0.08700878979265578, 0.6020887712400423),
        v(-0.9987810828547851, 0.04935938139222259, 0.0),
        v(-0.04935938221197274, -0.9987810828142734, 0.0),
    ]])
    .unwrap();
    check_identities(&a, &b).unwrap();
    assert_difference_matches_mc(&a, &b, 164);
}
