//! Hand-built degenerate configurations with areas known in closed form, input validation, and
//! the composition stress cases (chains of differences over triangles that share edges).

mod support;

use arealight::GeomError;
use arealight::glam::DVec2;
use arealight::internals::{VertexClass, contact_classes};
use arealight::planar::{BoolOp, Shape, boolean};
use support::planar::*;

/// Checks validity, identities, and the exact expected areas [A&B, A|B, A-B, A^B].
fn expect(a: &str, b: &str, areas: [f64; 4]) {
    let (sa, sb) = (shape(a), shape(b));
    let res = check_all(&sa, &sb, 1e-12).unwrap_or_else(|e| panic!("{a} / {b}: {e}"));
    for (r, want) in res.iter().zip(areas) {
        assert!(
            (r.area() - want).abs() <= 1e-12 * (1.0 + want),
            "{a} / {b}: got {} want {want}: {r:?}",
            r.area()
        );
    }
    // The swapped order must agree too (difference becomes B - A).
    check_all(&sb, &sa, 1e-12).unwrap_or_else(|e| panic!("swapped {a} / {b}: {e}"));
}

const SQ: &str = "0:0, 4:0, 4:4, 0:4";

#[test]
fn identical_contours() {
    expect(SQ, SQ, [16.0, 16.0, 0.0, 0.0]);
    let r = boolean(&shape(SQ), &shape(SQ), BoolOp::Union).unwrap();
    assert_eq!(r.contours().count(), 1);
    assert_eq!(r.vertex_count(), 4);
}

#[test]
fn identical_contours_different_start_and_orientation() {
    expect(SQ, "4:4, 4:0, 0:0, 0:4", [16.0, 16.0, 0.0, 0.0]);
}

#[test]
fn sub_polygon_sharing_two_edges() {
    // Half of the square, sharing two edges and the diagonal's end vertices.
    expect(SQ, "0:0, 4:0, 4:4", [8.0, 16.0, 8.0, 8.0]);
}

#[test]
fn adjacent_squares_share_full_edge() {
    expect(SQ, "4:0, 8:0, 8:4, 4:4", [0.0, 32.0, 16.0, 32.0]);
    let u = boolean(&shape(SQ), &shape("4:0, 8:0, 8:4, 4:4"), BoolOp::Union).unwrap();
    assert_eq!(
        u.vertex_count(),
        4,
        "collinear points must be removed: {u:?}"
    );
}

#[test]
fn partially_overlapping_edges() {
    expect(SQ, "4:2, 6:2, 6:6, 4:6", [0.0, 24.0, 16.0, 24.0]);
    expect(SQ, "4:1, 6:1, 6:3, 4:3", [0.0, 20.0, 16.0, 20.0]);
}

#[test]
fn overlapping_with_shared_partial_edge_inside() {
    // B inside A, touching A's boundary along part of the bottom edge.
    expect(SQ, "1:0, 3:0, 3:2, 1:2", [4.0, 16.0, 12.0, 12.0]);
    // B covers A's bottom strip and pokes out on both sides.
    expect(SQ, "-1:0, 5:0, 5:1, -1:1", [4.0, 18.0, 12.0, 14.0]);
}

#[test]
fn vertex_on_edge() {
    // Triangle with its apex exactly on A's right edge, from outside.
    expect(SQ, "4:2, 6:0, 6:4", [0.0, 20.0, 16.0, 20.0]);
    // Triangle with its apex exactly on A's right edge, from inside.
    expect(SQ, "4:2, 2:1, 2:3", [2.0, 16.0, 14.0, 14.0]);
}

#[test]
fn vertex_on_vertex() {
    // Corner to corner.
    expect(SQ, "4:4, 6:4, 6:6, 4:6", [0.0, 20.0, 16.0, 20.0]);
    // A diamond touching the square's corner from inside.
    expect(SQ, "4:4, 3:2, 2:2, 2:3", [2.0, 16.0, 14.0, 14.0]);
}

#[test]
fn bouncing_crossings_and_delayed() {
    // Sawtooth top edge bouncing on the square's top edge at two vertices.
    expect(SQ, "1:4, 2:5, 3:4, 3:6, 1:6", [0.0, 19.0, 16.0, 19.0]);
    // A rectangle that slides along the top edge (delayed bouncing) and one that crosses through
    // an overlapping stretch (delayed crossing).
    expect(SQ, "1:4, 3:4, 3:6, 1:6", [0.0, 20.0, 16.0, 20.0]);
    expect(SQ, "2:2, 4:2, 4:4, 6:4, 6:6, 2:6", [4.0, 24.0, 12.0, 20.0]);
}

#[test]
fn crossing_squares() {
    expect(SQ, "2:2, 6:2, 6:6, 2:6", [4.0, 28.0, 12.0, 24.0]);
}

#[test]
fn holes_and_multiple_outers() {
    // A frame (square with hole) and a square exactly filling the hole.
    let frame = "0:0, 6:0, 6:6, 0:6; 2:2, 4:2, 4:4, 2:4";
    expect(frame, "2:2, 4:2, 4:4, 2:4", [0.0, 36.0, 32.0, 36.0]);
    let u = boolean(&shape(frame), &shape("2:2, 4:2, 4:4, 2:4"), BoolOp::Union).unwrap();
    assert_eq!(u.contours().count(), 1, "{u:?}");
    // Two outers, one overlapping the frame's hole partially.
    expect(
        frame,
        "3:3, 5:3, 5:5, 3:5; 7:0, 8:0, 8:1, 7:1",
        [3.0, 34.0, 29.0, 31.0],
    );
}

#[test]
fn hole_touching_outer_at_a_point() {
    // A diamond hole whose top vertex touches the outer's top edge.
    let a = "0:0, 4:0, 4:4, 0:4; 2:4, 3:3, 2:2, 1:3";
    let sa = shape(a);
    assert!((sa.area() - 14.0).abs() < 1e-12);
    sa.validate().unwrap();
    expect(a, "2:0, 6:0, 6:4, 2:4", [7.0, 23.0, 7.0, 16.0]);
    expect(a, SQ, [14.0, 16.0, 0.0, 2.0]);
}

#[test]
fn result_pinched_at_a_point_is_split() {
    // Square minus a triangle touching its left edge and its right edge at single points leaves
    // two pieces meeting nowhere, plus the square minus a diamond touching the top and bottom
    // leaves two pieces touching at nothing but the diamond's corners.
    let d = boolean(&shape(SQ), &shape("2:0, 4:2, 2:4, 0:2"), BoolOp::Difference).unwrap();
    d.validate().unwrap();
    assert_eq!(d.contours().count(), 4);
    assert!((d.area() - 8.0).abs() < 1e-12);
}

#[test]
fn large_coordinates() {
    // Gnomonic coordinates near the horizon: 1e6 offsets, unit-size features.
    let off = 1.0e6;
    let a = Shape::new(vec![
        [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)]
            .iter()
            .map(|&(x, y)| DVec2::new(off + x, off + y))
            .collect(),
    ])
    .unwrap();
    let b = Shape::new(vec![
        [(0.5, 0.0), (1.5, 0.0), (1.5, 1.0), (0.5, 1.0)]
            .iter()
            .map(|&(x, y)| DVec2::new(off + x, off + y))
            .collect(),
    ])
    .unwrap();
    let [i, u, d, x] = check_all(&a, &b, 1e-9).unwrap();
    assert!((i.area() - 0.5).abs() < 1e-8);
    assert!((u.area() - 1.5).abs() < 1e-8);
    assert!((d.area() - 0.5).abs() < 1e-8);
    assert!((x.area() - 1.0).abs() < 1e-8);
}

#[test]
fn empty_operands() {
    let e = Shape::empty();
    let a = shape(SQ);
    assert!(boolean(&a, &e, BoolOp::Intersection).unwrap().is_empty());
    assert_eq!(boolean(&a, &e, BoolOp::Union).unwrap().area(), 16.0);
    assert_eq!(boolean(&e, &a, BoolOp::Difference).unwrap().area(), 0.0);
    assert_eq!(boolean(&e, &a, BoolOp::Xor).unwrap().area(), 16.0);
    assert!(Shape::new(vec![]).unwrap().is_empty());
}

#[test]
fn input_errors_name_the_problem() {
    let nan = Shape::new(vec![vec![
        DVec2::new(0.0, 0.0),
        DVec2::new(1.0, f64::NAN),
        DVec2::new(1.0, 1.0),
    ]]);
    assert_eq!(nan, Err(GeomError::NonFinite { ring: 0, vertex: 1 }));
    let inf = Shape::new(vec![
        rings(SQ)[0].clone(),
        vec![
            DVec2::new(0.0, 0.0),
            DVec2::new(f64::INFINITY, 0.0),
            DVec2::new(1.0, 1.0),
        ],
    ]);
    assert_eq!(inf, Err(GeomError::NonFinite { ring: 1, vertex: 1 }));
    let bowtie = Shape::new(rings("0:0, 2:2, 2:0, 0:2"));
    assert_eq!(
        bowtie,
        Err(GeomError::SelfIntersecting {
            ring: 0,
            other_ring: 0
        })
    );
    let crossing = Shape::new(rings("0:0, 2:0, 2:2, 0:2; 1:1, 3:1, 3:3, 1:3"));
    assert_eq!(
        crossing,
        Err(GeomError::SelfIntersecting {
            ring: 0,
            other_ring: 1
        })
    );
    let overlap = Shape::new(rings("0:0, 2:0, 2:2, 0:2; 2:0, 4:0, 4:2, 2:2"));
    assert!(matches!(overlap, Err(GeomError::SelfIntersecting { .. })));
    let line = Shape::new(rings("0:0, 1:1, 2:2"));
    assert!(matches!(
        line,
        Err(GeomError::TooFewVertices { ring: 0, .. })
    ));
    let huge = Shape::new(vec![
        vec![
            DVec2::new(0.0, 0.0),
            DVec2::new(1.0, 0.0),
            DVec2::new(1.0, 1.0),
        ],
        vec![
            DVec2::new(5.0, 0.0),
            DVec2::new(6.0, 0.0),
            DVec2::new(1e200, 1.0),
        ],
    ]);
    assert_eq!(
        huge,
        Err(GeomError::CoordinateOutOfRange {
            ring: 1,
            vertex: 2,
            value: 1e200,
            limit: arealight::planar::MAX_COORD,
        })
    );
    let msg = format!("{}", huge.unwrap_err());
    assert!(msg.contains("vertex 2 in ring 1"), "{msg}");
    // Messages are actionable.
    let msg = format!("{}", bowtie.unwrap_err());
    assert!(msg.contains("crosses itself"), "{msg}");
}

#[test]
fn new_fixes_orientation_by_nesting_depth() {
    // Outer given clockwise, hole given counter-clockwise, island in the hole clockwise.
    let s = shape("0:0, 0:10, 10:10, 10:0; 2:2, 8:2, 8:8, 2:8; 4:4, 4:6, 6:6, 6:4");
    let signs: Vec<bool> = s.contour_list().iter().map(|c| c.is_hole()).collect();
    assert_eq!(signs, [false, true, false]);
    assert!((s.area() - (100.0 - 36.0 + 4.0)).abs() < 1e-12);
    s.validate().unwrap();
}

/// Triangles of a `k x k` grid of unit squares with origin `o`, each square cut along a diagonal
/// that alternates, so neighbouring triangles share edges and many share vertices.
fn grid_triangles(o: DVec2, k: usize, h: f64) -> Vec<Shape> {
    let mut out = Vec::new();
    for i in 0..k {
        for j in 0..k {
            let p = |di: usize, dj: usize| o + DVec2::new((i + di) as f64, (j + dj) as f64) * h;
            let (a, b, c, d) = (p(0, 0), p(1, 0), p(1, 1), p(0, 1));
            let tris = if (i + j) % 2 == 0 {
                [[a, b, c], [a, c, d]]
            } else {
                [[a, b, d], [b, c, d]]
            };
            for t in tris {
                out.push(Shape::new(vec![t.to_vec()]).unwrap());
            }
        }
    }
    out
}

#[test]
fn union_of_triangulated_grid_is_the_square() {
    let tris = grid_triangles(DVec2::ZERO, 5, 1.0);
    assert_eq!(tris.len(), 50);
    let mut u = Shape::empty();
    for t in &tris {
        u = boolean(&u, t, BoolOp::Union).unwrap();
        u.validate().unwrap();
    }
    assert!((u.area() - 25.0).abs() < 1e-12, "{}", u.area());
    assert_eq!(u.contours().count(), 1);
    assert_eq!(u.vertex_count(), 4, "{u:?}");
}

#[test]
fn chain_of_50_differences_matches_union_first() {
    // The light covers part of the grid; each step subtracts one triangle sharing edges with
    // earlier ones. Some triangles are fully inside, some cut by the light's edges.
    let tris = grid_triangles(DVec2::new(-0.5, -0.25), 5, 1.0);
    let light = shape("0:0, 4:0.5, 4.25:3.5, 0.25:4.5");
    let mut visible = light.clone();
    let mut occ = Shape::empty();
    for (k, t) in tris.iter().enumerate() {
        if k % 7 == 3 {
            continue; // leave some holes in the occluder set, so the result has several parts
        }
        visible = boolean(&visible, t, BoolOp::Difference).unwrap();
        visible
            .validate()
            .unwrap_or_else(|e| panic!("step {k}: {e}: {visible:?}"));
        occ = boolean(&occ, t, BoolOp::Union).unwrap();
        occ.validate().unwrap();
    }
    let direct = boolean(&light, &occ, BoolOp::Difference).unwrap();
    direct.validate().unwrap();
    let la = light.area();
    assert!(visible.area() > 0.0 && visible.area() < la);
    assert!(
        (visible.area() - direct.area()).abs() <= 1e-9 * la,
        "{} vs {}",
        visible.area(),
        direct.area()
    );
    let covered = boolean(&light, &occ, BoolOp::Intersection).unwrap().area();
    assert!((visible.area() + covered - la).abs() <= 1e-9 * la);
}

#[test]
fn chain_of_differences_on_projected_fan() {
    // A fan of 50 thin triangles around a common apex (like a projected icosphere cap or a
    // cone): every triangle shares the apex and two edges with its neighbours.
    let n = 50;
    let apex = DVec2::new(0.3, 0.2);
    let ring: Vec<DVec2> = (0..n)
        .map(|k| {
            let t = std::f64::consts::TAU * k as f64 / n as f64;
            DVec2::new(t.cos(), t.sin()) * (2.0 + 0.5 * (3.0 * t).sin())
        })
        .collect();
    let light = shape("-1.5:-1.2, 1.7:-1.4, 1.2:1.6, -1.3:1.1");
    let mut visible = light.clone();
    let mut occ = Shape::empty();
    for k in 0..n {
        if k % 5 == 0 {
            continue;
        }
        let t = Shape::new(vec![vec![apex, ring[k], ring[(k + 1) % n]]]).unwrap();
        visible = boolean(&visible, &t, BoolOp::Difference).unwrap();
        visible.validate().unwrap();
        occ = boolean(&occ, &t, BoolOp::Union).unwrap();
        occ.validate().unwrap();
    }
    let direct = boolean(&light, &occ, BoolOp::Difference).unwrap();
    assert!((visible.area() - direct.area()).abs() <= 1e-9 * light.area());
}

/// The Foster–Hormann–Popa class of A's vertex at `p` (after splitting).
fn class_at(a: &str, b: &str, p: (f64, f64)) -> VertexClass {
    let (ca, _) = contact_classes(&shape(a), &shape(b)).unwrap();
    ca.iter()
        .find(|(q, _)| *q == DVec2::new(p.0, p.1))
        .map(|x| x.1)
        .unwrap_or_else(|| panic!("no vertex at {p:?} in {ca:?}"))
}

#[test]
fn fhp_vertex_classes() {
    let cases = [
        // Proper crossings of two overlapping squares.
        ("2:2, 6:2, 6:6, 2:6", (4.0, 2.0), VertexClass::Crossing),
        ("2:2, 6:2, 6:6, 2:6", (2.0, 4.0), VertexClass::Crossing),
        // Corner to corner: touching without crossing.
        ("4:4, 6:4, 6:6, 4:6", (4.0, 4.0), VertexClass::Bouncing),
        // Vertex of B on A's edge from outside.
        ("4:2, 6:0, 6:4", (4.0, 2.0), VertexClass::Bouncing),
        // A shared stretch with A outside B on both sides: delayed bouncing, classified at the
        // chain's start; the chain's end is on the chain.
        (
            "4:1, 6:1, 6:3, 4:3",
            (4.0, 1.0),
            VertexClass::DelayedBouncing,
        ),
        ("4:1, 6:1, 6:3, 4:3", (4.0, 3.0), VertexClass::OnChain),
        // A shared stretch that A enters from outside and leaves into B: delayed crossing.
        (
            "2:2, 4:2, 4:4, 6:4, 6:6, 2:6",
            (4.0, 2.0),
            VertexClass::DelayedCrossing,
        ),
        // Vertices off the other boundary are plain.
        ("2:2, 6:2, 6:6, 2:6", (0.0, 0.0), VertexClass::Plain),
    ];
    for (b, at, class) in cases {
        assert_eq!(class_at(SQ, b, at), class, "B = {b}, at {at:?}");
    }
}

#[test]
fn extreme_scales_keep_identities() {
    // The predicates are exact while products of coordinate differences neither overflow nor
    // underflow; these scales are far inside both limits, and every tolerance is relative.
    for s in [1e-100, 1e-20, 1e20, 1e100] {
        let scaled = |text: &str| {
            Shape::new(
                rings(text)
                    .into_iter()
                    .map(|r| r.into_iter().map(|p| p * s).collect())
                    .collect(),
            )
            .unwrap()
        };
        let a = scaled("0:0, 4:0, 4:4, 0:4; 1:1, 1:2, 2:2, 2:1");
        let b = scaled("2:1, 6:1, 6:3, 2:3");
        let [i, u, _, _] = check_all(&a, &b, 1e-12).unwrap_or_else(|e| panic!("scale {s}: {e}"));
        assert!((i.area() / (s * s) - 4.0).abs() < 1e-9, "scale {s}: {i:?}");
        assert!((u.area() / (s * s) - 19.0).abs() < 1e-9, "scale {s}: {u:?}");
    }
}
