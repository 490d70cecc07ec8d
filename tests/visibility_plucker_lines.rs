//! Pluecker geometry of the lazy visibility backend (seed 002 section 3), checked against exact
//! integer arithmetic: the side operator's coordinates and its determinant form, certified
//! signs on exactly coplanar inputs, line-polygon stabbing against the exact crossing point,
//! and Theorem 1 with its proof's bilinear identity over every line of a small lattice.

use arealight::glam::DVec3;
use arealight::visibility::plucker::{
    Orientation, PluckerLine, Sign, Stab, line_polygon, side_sign, vvset_orientation,
};

mod support;

use support::Rng;

/// Uniform integer in `[-m, m]`.
fn int(rng: &mut Rng, m: i64) -> i64 {
    rng.below(2 * m as usize + 1) as i64 - m
}

type I3 = [i128; 3];

fn sub(a: I3, b: I3) -> I3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn add(a: I3, b: I3) -> I3 {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}

fn scale(k: i128, a: I3) -> I3 {
    [k * a[0], k * a[1], k * a[2]]
}

fn cross(a: I3, b: I3) -> I3 {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

fn dot(a: I3, b: I3) -> i128 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// The exact side operator of the lines `p -> q` and `r -> s` from its definition (seed 002
/// section 3.1): `u_l . v_r + v_l . u_r` with `u = q - p`, `v = p x q`.
fn side_exact(p: I3, q: I3, r: I3, s: I3) -> i128 {
    dot(sub(q, p), cross(r, s)) + dot(cross(p, q), sub(s, r))
}

fn sign(x: i128) -> Sign {
    match x.signum() {
        1 => Sign::Positive,
        -1 => Sign::Negative,
        _ => Sign::Zero,
    }
}

fn dv(a: I3) -> DVec3 {
    DVec3::new(a[0] as f64, a[1] as f64, a[2] as f64)
}

#[test]
fn coordinates_and_side_operator_follow_the_paper() {
    // l0..l2 = q - p; l3 = qz py - qy pz, l4 = qx pz - qz px, l5 = qy px - qx py; side(l, r) =
    // l3 r0 + l4 r1 + l5 r2 + l0 r3 + l1 r4 + l2 r5, written out as in the paper; and the side
    // equals det[q - p, r - p, s - p] (six times the tetrahedron's signed volume).
    let mut rng = Rng::from_state(1);
    let pt = |rng: &mut Rng| DVec3::new(rng.f64() - 0.5, rng.f64() - 0.5, rng.f64() - 0.5) * 4.0;
    for _ in 0..2000 {
        let (p, q, r, s) = (pt(&mut rng), pt(&mut rng), pt(&mut rng), pt(&mut rng));
        let l = PluckerLine::through(p, q).coordinates();
        let expect = [
            q.x - p.x,
            q.y - p.y,
            q.z - p.z,
            q.z * p.y - q.y * p.z,
            q.x * p.z - q.z * p.x,
            q.y * p.x - q.x * p.y,
        ];
        for k in 0..6 {
            assert!(
                (l[k] - expect[k]).abs() <= 1e-15 * 16.0,
                "l{k}: {} vs {}",
                l[k],
                expect[k]
            );
        }
        let rr = PluckerLine::through(r, s).coordinates();
        let paper =
            l[3] * rr[0] + l[4] * rr[1] + l[5] * rr[2] + l[0] * rr[3] + l[1] * rr[4] + l[2] * rr[5];
        let side = PluckerLine::through(p, q).side(&PluckerLine::through(r, s));
        let det = (q - p).dot((r - p).cross(s - p));
        assert!((side - paper).abs() <= 1e-12, "{side} vs {paper}");
        assert!((side - det).abs() <= 1e-12, "{side} vs det {det}");
        // Symmetric, odd under reversal of either line.
        let back = PluckerLine::through(r, s).side(&PluckerLine::through(p, q));
        let rev = PluckerLine::through(q, p).side(&PluckerLine::through(r, s));
        assert!((side - back).abs() <= 1e-12 && (side + rev).abs() <= 1e-12);
        assert_eq!(
            PluckerLine::through(p, q).reversed().coordinates(),
            PluckerLine::through(p, q).coordinates().map(|c| -c)
        );
    }
}

#[test]
fn side_signs_are_exact_on_coplanar_and_nearly_coplanar_lattice_points() {
    // Large integer coordinates (2^35) with the fourth point an integer combination of the
    // others plus a perturbation of at most one unit: the exact determinant is zero or tiny
    // next to its terms (~2^114), where plain f64 evaluation returns noise. side_sign must
    // match i128 arithmetic on every case, zero included.
    let mut rng = Rng::from_state(2);
    let m = 1i64 << 35;
    let (mut zeros, mut nonzeros, mut naive_wrong) = (0, 0, 0);
    for case in 0..20000 {
        let p: I3 = [int(&mut rng, m), int(&mut rng, m), int(&mut rng, m)].map(i128::from);
        let q: I3 = add(
            p,
            [
                int(&mut rng, m / 8),
                int(&mut rng, m / 8),
                int(&mut rng, m / 8),
            ]
            .map(i128::from),
        );
        let r: I3 = add(
            p,
            [
                int(&mut rng, m / 8),
                int(&mut rng, m / 8),
                int(&mut rng, m / 8),
            ]
            .map(i128::from),
        );
        let (a, b) = (i128::from(int(&mut rng, 3)), i128::from(int(&mut rng, 3)));
        let delta: I3 = if case % 3 == 0 {
            [0, 0, 0]
        } else {
            [int(&mut rng, 1), int(&mut rng, 1), int(&mut rng, 1)].map(i128::from)
        };
        let s = add(add(p, add(scale(a, sub(q, p)), scale(b, sub(r, p)))), delta);
        // Lines p -> s and q -> r, and a permutation, so that every argument slot is exercised.
        for (l0, l1, r0, r1) in [(p, s, q, r), (q, r, p, s), (s, q, r, p)] {
            let exact = sign(side_exact(l0, l1, r0, r1));
            let got = side_sign(dv(l0), dv(l1), dv(r0), dv(r1));
            assert_eq!(got, exact, "case {case}: {l0:?} {l1:?} {r0:?} {r1:?}");
            let naive = Sign::of(
                PluckerLine::through(dv(l0), dv(l1)).side(&PluckerLine::through(dv(r0), dv(r1))),
            );
            naive_wrong += usize::from(naive != exact);
            if exact == Sign::Zero {
                zeros += 1;
            } else {
                nonzeros += 1;
            }
        }
    }
    // The inputs are hard: plain evaluation gets many of them wrong.
    assert!(
        zeros > 10000 && nonzeros > 10000 && naive_wrong > 1000,
        "{zeros} {nonzeros} {naive_wrong}"
    );
}

/// The exact relation of the line `p -> q` to the convex planar polygon `poly` (integer points),
/// from the crossing point in rational arithmetic and exact point-in-polygon tests: a
/// reference independent of the side operator.
fn stab_exact(p: I3, q: I3, poly: &[I3]) -> Stab {
    let nrm = cross(sub(poly[1], poly[0]), sub(poly[2], poly[0]));
    let d = sub(q, p);
    let den = dot(nrm, d);
    let num = -dot(nrm, sub(p, poly[0]));
    if den == 0 {
        return if num == 0 { Stab::Coplanar } else { Stab::Miss };
    }
    // The crossing point times den: x * den = p * den + num * d.
    let x = add(scale(den, p), scale(num, d));
    let (mut pos, mut neg, mut zero) = (false, false, false);
    for i in 0..poly.len() {
        let (a, b) = (poly[i], poly[(i + 1) % poly.len()]);
        let o = dot(cross(sub(b, a), sub(x, scale(den, a))), nrm) * den.signum();
        match o.signum() {
            1 => pos = true,
            -1 => neg = true,
            _ => zero = true,
        }
    }
    match (pos, neg, zero) {
        (true, true, _) => Stab::Miss,
        (_, _, true) => Stab::Boundary,
        _ => Stab::Through,
    }
}

#[test]
fn line_polygon_matches_the_exact_crossing_point() {
    // Lattice lines against lattice triangles and parallelograms (either orientation): small
    // coordinates make crossings through vertices, along edges and in the plane common.
    let mut rng = Rng::from_state(3);
    let mut counts = [0usize; 4];
    for case in 0..60000 {
        let pt = |rng: &mut Rng| [int(rng, 3), int(rng, 3), int(rng, 3)].map(i128::from);
        let a = pt(&mut rng);
        let (u, v) = (pt(&mut rng), pt(&mut rng));
        if cross(u, v) == [0, 0, 0] {
            continue;
        }
        let mut poly: Vec<I3> = if case % 2 == 0 {
            vec![a, add(a, u), add(a, v)]
        } else {
            vec![a, add(a, u), add(add(a, u), v), add(a, v)]
        };
        if case % 4 >= 2 {
            poly.reverse();
        }
        let (mut p, mut q) = (pt(&mut rng), pt(&mut rng));
        if case % 10 == 9 {
            // A line in the polygon's plane: through, along or beside it.
            let k = |rng: &mut Rng| i128::from(int(rng, 2));
            p = add(a, add(scale(k(&mut rng), u), scale(k(&mut rng), v)));
            q = add(p, add(scale(k(&mut rng), u), scale(k(&mut rng), v)));
        }
        if p == q {
            continue;
        }
        let exact = stab_exact(p, q, &poly);
        let polyf: Vec<DVec3> = poly.iter().map(|&c| dv(c)).collect();
        assert_eq!(
            line_polygon(dv(p), dv(q), &polyf),
            exact,
            "case {case}: {p:?} -> {q:?} vs {poly:?}"
        );
        counts[exact as usize] += 1;
    }
    assert!(counts.iter().all(|&c| c > 500), "{counts:?}");
}

/// The integer points of `{0, 1, 2}^3`.
fn lattice() -> Vec<I3> {
    let mut g = Vec::new();
    for x in 0..3 {
        for y in 0..3 {
            for z in 0..3 {
                g.push([x, y, z]);
            }
        }
    }
    g
}

/// Barycentric weights with denominator 3 over `n` vertices.
fn weights(n: usize) -> Vec<Vec<i128>> {
    let mut out = Vec::new();
    if n == 2 {
        for a in 0..=3 {
            out.push(vec![a, 3 - a]);
        }
    } else {
        for a in 0..=3 {
            for b in 0..=3 - a {
                out.push(vec![a, b, 3 - a - b]);
            }
        }
    }
    out
}

#[test]
fn theorem_1_holds_for_every_line_of_a_small_lattice() {
    // Seed 002 Theorem 1 and its proof, exhaustively on a small family: every line `l` through
    // two points of {0,1,2}^3; polygons A (triangles and segments of the z = 0 grid) and B
    // (triangles and segments in the plane z = 2 and in the slanted plane x + z = 4, so that
    // stabbing lines come in every direction); every line q from a point of A with weights in
    // thirds to a point of B with weights in thirds. Checked exactly (i128):
    // - the proof's identity: 9 side(q, l) = sum_ij alpha_i beta_j side(a_i b_j, l) (weights
    //   in thirds, so both sides are integers);
    // - the theorem in its strict form as `vvset_orientation` reports it: Positive => every q
    //   has side > 0, Negative => < 0, and the report is Positive (Negative) exactly when all
    //   vertex-to-vertex sides are strictly positive (negative).
    let g = lattice();
    let lines: Vec<(I3, I3)> = (0..g.len())
        .flat_map(|i| (i + 1..g.len()).map(move |j| (i, j)))
        .map(|(i, j)| (g[i], g[j]))
        .collect();
    let grid: Vec<I3> = (0..3)
        .flat_map(|x| (0..3).map(move |y| [x, y, 0]))
        .collect();
    let mut polys_a: Vec<Vec<I3>> = Vec::new();
    for i in 0..9 {
        for j in i + 1..9 {
            polys_a.push(vec![grid[i], grid[j]]);
            for k in j + 1..9 {
                if cross(sub(grid[j], grid[i]), sub(grid[k], grid[i])) != [0, 0, 0] {
                    polys_a.push(vec![grid[i], grid[j], grid[k]]);
                }
            }
        }
    }
    let polys_b: Vec<Vec<I3>> = vec![
        vec![[0, 0, 2], [2, 0, 2], [0, 2, 2]],
        vec![[1, 1, 2], [2, 1, 2]],
        vec![[2, 2, 2], [0, 1, 2], [1, 0, 2]],
        vec![[2, 0, 2], [1, 2, 3], [2, 2, 2]],
        vec![[1, 0, 3], [2, 1, 2]],
        vec![[0, 0, 4], [1, 0, 3], [0, 2, 4]],
    ];
    let (mut checked, mut decided) = (0u64, 0u64);
    for a in &polys_a {
        for b in &polys_b {
            let (wa, wb) = (weights(a.len()), weights(b.len()));
            // The homogeneous points of A and B (times 3) for every weight.
            let pa: Vec<(I3, &Vec<i128>)> = wa
                .iter()
                .map(|w| {
                    (
                        a.iter()
                            .zip(w)
                            .fold([0; 3], |s, (&v, &k)| add(s, scale(k, v))),
                        w,
                    )
                })
                .collect();
            let pb: Vec<(I3, &Vec<i128>)> = wb
                .iter()
                .map(|w| {
                    (
                        b.iter()
                            .zip(w)
                            .fold([0; 3], |s, (&v, &k)| add(s, scale(k, v))),
                        w,
                    )
                })
                .collect();
            let af: Vec<DVec3> = a.iter().map(|&v| dv(v)).collect();
            let bf: Vec<DVec3> = b.iter().map(|&v| dv(v)).collect();
            for &(l0, l1) in &lines {
                let (ul, vl) = (sub(l1, l0), cross(l0, l1));
                let vv: Vec<Vec<i128>> = a
                    .iter()
                    .map(|&ai| b.iter().map(|&bj| side_exact(ai, bj, l0, l1)).collect())
                    .collect();
                let all_pos = vv.iter().flatten().all(|&s| s > 0);
                let all_neg = vv.iter().flatten().all(|&s| s < 0);
                let reported = vvset_orientation(&af, &bf, dv(l0), dv(l1));
                let expect = if all_pos {
                    Orientation::Positive
                } else if all_neg {
                    Orientation::Negative
                } else {
                    Orientation::Mixed
                };
                assert_eq!(reported, expect, "A {a:?} B {b:?} l {l0:?} {l1:?}");
                if reported != Orientation::Mixed {
                    decided += 1;
                }
                for &(ha, alpha) in &pa {
                    for &(hb, beta) in &pb {
                        if ha == hb {
                            continue;
                        }
                        // 9 (b - a) and 9 (a x b) for a = ha / 3, b = hb / 3.
                        let (u, v) = (scale(3, sub(hb, ha)), cross(ha, hb));
                        let side9 = dot(u, vl) + dot(v, ul);
                        let mut sum = 0;
                        for (i, &al) in alpha.iter().enumerate() {
                            for (j, &be) in beta.iter().enumerate() {
                                sum += al * be * vv[i][j];
                            }
                        }
                        assert_eq!(side9, sum, "identity: A {a:?} B {b:?} l {l0:?} {l1:?}");
                        match reported {
                            Orientation::Positive => assert!(side9 > 0),
                            Orientation::Negative => assert!(side9 < 0),
                            Orientation::Mixed => {}
                        }
                        checked += 1;
                    }
                }
            }
        }
    }
    assert!(
        checked > 1_000_000 && decided > 10_000,
        "{checked} {decided}"
    );
}
