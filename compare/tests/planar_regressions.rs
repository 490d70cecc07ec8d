//! The reference checks of the crate's minimized planar failures (`tests/planar_regressions.rs`
//! in the `arealight` package, where their validity, identities and hand-computed areas are
//! checked): each result against i_overlay's, by the area of the symmetric difference.

#[path = "../../tests/support/mod.rs"]
mod support;

use arealight::planar::{BoolOp, boolean};
use arealight_compare::sym_diff_vs_ioverlay;
use support::planar::shape;

/// `vertex_at_edge_midpoint_union`: B's vertex exactly at the midpoint of A's edge; our union
/// agrees with i_overlay (clipper2 fills the pinched hole).
#[test]
fn vertex_at_edge_midpoint_union() {
    let a = shape("2:-1, 0:-4, 3:-2");
    let b = shape("2:2, 1:2, 0:2, 0:1, 1:-2.5, 1:-2, 4:-2, 2:1");
    let u = boolean(&a, &b, BoolOp::Union).unwrap();
    let sd = sym_diff_vs_ioverlay(&a, &b, BoolOp::Union, &u);
    assert!(sd <= 1e-9 * (a.area() + b.area()), "{sd}: {u:?}");
}

/// `difference_with_nearly_shared_edge`: edges shared up to `1.5e-15`, just over the snapping
/// distance.
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
    for op in [BoolOp::Intersection, BoolOp::Difference] {
        let r = boolean(&a, &b, op).unwrap();
        let sd = sym_diff_vs_ioverlay(&a, &b, op, &r);
        assert!(sd <= 1e-9 * (a.area() + b.area()), "{sd}: {r:?}");
    }
}
