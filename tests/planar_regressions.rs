//! Minimized failures found by the property tests and fuzzing, one named test each. Every entry
//! records the property that found it and what was wrong, and checks validity and the identities
//! (plus the chain property where that is what failed).

mod support;

use arealight::planar::{BoolOp, Shape, boolean};
use support::planar::*;

fn chain(light: &str, tris: &[&str]) {
    let light = shape(light);
    let mut visible = light.clone();
    let mut occ = Shape::empty();
    for (k, t) in tris.iter().enumerate() {
        let t = shape(t);
        check_all(&visible, &t, 1e-9)
            .unwrap_or_else(|e| panic!("step {k} visible: {e}\n{visible:?}\n{t:?}"));
        check_all(&occ, &t, 1e-9).unwrap_or_else(|e| panic!("step {k} occ: {e}\n{occ:?}\n{t:?}"));
        visible = boolean(&visible, &t, BoolOp::Difference).unwrap();
        occ = boolean(&occ, &t, BoolOp::Union).unwrap();
    }
    let direct = boolean(&light, &occ, BoolOp::Difference).unwrap();
    assert!((direct.area() - visible.area()).abs() <= 1e-9 * light.area());
}

/// proptest `integer_grid_polygons`: `-0.0` and `0.0` were different vertices to the sorted
/// twin lookup (which orders by `total_cmp`) but equal to `==`, so a shared vertex was missed.
#[test]
fn negative_zero_is_the_same_vertex() {
    let a = shape("-2:-0, -3:-1, -2:-2, -1:-1, 0:3");
    let b = shape("-1:3, -2:3, -3:2, -3:1, -2:0, -1:1");
    check_all(&a, &b, 1e-9).unwrap();
}

/// proptest `chains_compose`: result boundary did not close.
#[test]
fn chain_grid_triangles_1() {
    chain(
        "-1:2, -2:-3, 4:1",
        &["-2:1, -3:-0, 1:-3", "2:2, 0:1, 1:-1", "2:-2, 0:2, -1:1"],
    );
}

/// proptest `chains_compose`: a crossing a few ulps from a vertex elsewhere on the boundary was
/// kept as a separate point, and the split edge doubled back between the two.
#[test]
fn chain_grid_triangles_2() {
    chain(
        "-1:2, -2:-3, 4:1",
        &["-2:1, -3:-0, 1:-3", "2:2, 0:1, 1:-1", "2:-1, 0:3, -1:2"],
    );
}

/// proptest `chains_compose`: result boundary did not close.
#[test]
fn chain_grid_triangles_3() {
    chain(
        "2:0, 3:1, 3:2, 2:2, -1:3",
        &["1:-1, -3:4, -3:-1", "2:3, -3:3, 0:1", "-3:2, -1:1, -1:4"],
    );
}

/// proptest `vertex_on_edge_and_vertex_on_vertex` (seed in `proptest-regressions/`): B's vertex
/// exactly at the midpoint of A's edge. Our union disagreed with clipper2 (11.5) but agrees with
/// i_overlay; by hand, A = 5/2, B = 39/4, A & B = the triangle (2,-1), (4/3,-2), (3,-2) of area
/// 5/6, so A | B = 5/2 + 39/4 - 5/6 = 137/12, with a hole (1,-2.5), (1,-2), (4/3,-2) of area
/// 1/12 pinched at (1,-2.5): clipper2's union fills that hole.
#[test]
fn vertex_at_edge_midpoint_union() {
    let a = shape("2:-1, 0:-4, 3:-2");
    let b = shape("2:2, 1:2, 0:2, 0:1, 1:-2.5, 1:-2, 4:-2, 2:1");
    let [i, u, _, _] = check_all(&a, &b, 1e-9).unwrap();
    assert!((i.area() - 5.0 / 6.0).abs() < 1e-12, "{i:?}");
    assert!((u.area() - 137.0 / 12.0).abs() < 1e-12, "{u:?}");
    assert_eq!(u.contour_list().iter().filter(|c| c.is_hole()).count(), 1);
    // Against i_overlay: compare/tests/planar_regressions.rs.
}

/// Two copies of one vertex a few ulps apart within one operand (Issue 3, item 2). These are the
/// planar shapes that the sphere layer's union in
/// `sphere_boolean::regression_union_with_vertex_copies_ulps_apart` builds without its own
/// weld: A's rings 1 and 3 hold `(-0.29782521525192895, 0.115230665014275)` as two copies
/// `6e-17` apart, and B's first vertex is as close to both. Snapping B to one copy only would
/// leave B and ring 3 as two contours whose shared edge overlaps within rounding (valid by
/// `Shape::validate`, wrong as an operand); every operand vertex within the snapping distance of
/// another is welded instead, so B must merge with ring 3.
#[test]
fn union_with_vertex_copies_ulps_apart_within_one_operand() {
    let a = shape(
        "0.16266618305721212:-0.1419938921647603, -0.09867456425035155:-0.337326585013314, \
         -0.09472452487881344:-0.3409571852925808; \
         -0.10237701828842695:-0.19757991668221594, -0.29782521525192895:0.11523066501427495, \
         -0.2551796443306079:0.024637056767923576; \
         -0.10237701828842695:-0.19757991668221594, 0.22285340055682282:0.03143034093338467, \
         0.2896335641743427:0.11938596708017998; \
         -0.29782521525192895:0.11523066501427501, 0.2896335641743427:0.11938596708017998, \
         0.09472452487881342:0.34095718529258073",
    );
    let b = shape(
        "-0.29782521525192895:0.11523066501427505, -0.10958245993469506:-0.1560882442857163, \
         0.2896335641743429:0.11938596708017982",
    );
    let results = check_all(&a, &b, 1e-12).unwrap();
    for (r, op) in results.iter().zip(OPS) {
        well_separated(r).unwrap_or_else(|e| panic!("{}: {e}\n{r:?}", op_name(op)));
    }
    let u = &results[1];
    assert_eq!(u.contours().count(), 4, "B and ring 3 merge: {u:?}");
}

/// "Result boundary does not close" on a nearly shared edge (Issue 3, item 3): the planar shapes
/// of `sphere_shade_regressions::difference_with_nearly_shared_edge` in the sphere layer's
/// projection (before its weld). A's edge from vertex 4 to 5 and B's edge from 0 to 1 are the
/// same edge up to `1.5e-15`, just over the snapping distance `1.3e-15`, so the vertices stay
/// distinct; each is inserted into the other operand's edge, and B's closing edge, passing within
/// the distance of A's vertex 4 near its end, gets that vertex too. B's split ring then runs
/// `A4, B0, A4`: a spike through two copies of one point, whose node has an incoming result edge
/// and no outgoing one unless spikes in the split rings are cut back, as they must be.
#[test]
fn difference_with_nearly_shared_edge() {
    let a = shape(
        "-0.0563820234895846:0.013684937733375214, 0.07576353856700926:-0.03276570703995642, \
         0.09148627320009772:0.03318462560421694, 0.08427774578583314:0.03229821336503307, \
         0.030478470630320713:0.04053336589364999, -0.021166560051795704:0.06070298847285058",
    );
    let b = shape(
        "0.030478470630322215:0.04053336589365018, -0.021166560051794313:0.060702988472850966, \
         -0.09148627320009683:-0.03318462560421653",
    );
    let [i, _, d, _] = check_all(&a, &b, 1e-12).unwrap();
    assert!(d.area() > 0.0 && i.area() > 0.0);
    // Against i_overlay: compare/tests/planar_regressions.rs.
}

/// Found through the `sphere_tiny` fuzz target (the sphere layer's charts of tiny polygons run
/// at a resolution of a few snapping distances): two edges of `B` leave its tip `V`, `1.05` to
/// `1.2` snapping distances below `A`'s edge, and cross that edge less than one snapping
/// distance apart. Each crossing was inserted next to the other, and in the following passes
/// into the edges that end at the other, until the split gave up (`Undecidable`, "did not
/// settle"). Crossings of one pass that close are welded now. The tip's triangle (`0.4 d^2`, far
/// below the sliver tolerance) goes; the rest is exact: `|A n B| = 0`, `|A - B| = |A| = 2`,
/// `|A u B| = 2 + |B|`.
#[test]
fn crossings_of_one_pass_within_the_snapping_distance_are_one_point() {
    let snap = arealight::planar::SNAP_REL * 2.0; // the coordinate scale is 2
    for f in [1.05, 1.1, 1.2] {
        let d = f * snap;
        let a = shape("-1:-1, 1:-1, 1:0, -1:0");
        let b = Shape::new(vec![vec![
            arealight::glam::DVec2::new(0.0, -d),
            arealight::glam::DVec2::new(0.8, 2.0),
            arealight::glam::DVec2::new(-0.8, 2.0),
        ]])
        .unwrap();
        let wb = 0.8 * (2.0 + d);
        for (op, want) in [
            (BoolOp::Intersection, 0.0),
            (BoolOp::Union, 2.0 + wb),
            (BoolOp::Difference, 2.0),
            (BoolOp::Xor, 2.0 + wb),
        ] {
            let r = boolean(&a, &b, op).unwrap_or_else(|e| panic!("{f} {op:?}: {e}"));
            r.validate().unwrap();
            assert!(
                (r.area() - want).abs() <= 1e-13,
                "{f} {op:?}: {} vs {want}",
                r.area()
            );
        }
        check_all(&a, &b, 1e-9).unwrap();
    }
}
