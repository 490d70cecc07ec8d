//! Exact orientation predicates on the unit sphere and the small geometric kernels built on them.

use glam::DVec3;
use robust::{Coord3D, orient3d};

/// The six coordinate axis directions: candidate probe points and fan apexes that are far from
/// any given small set of directions.
pub(crate) const AXES: [DVec3; 6] = [
    DVec3::X,
    DVec3::Y,
    DVec3::Z,
    DVec3::NEG_X,
    DVec3::NEG_Y,
    DVec3::NEG_Z,
];

/// glam's vector as robust's coordinate type.
#[inline]
pub(crate) fn c3(p: DVec3) -> Coord3D<f64> {
    Coord3D {
        x: p.x,
        y: p.y,
        z: p.z,
    }
}

/// Sign of `det(a, b, c) = (a x b) . c`, evaluated exactly (Shewchuk's adaptive `orient3d` with the
/// origin as the fourth point), as -1, 0 or +1.
///
/// Properties (as in S2's `Sign`): `sign(a, b, c) == sign(b, c, a) == -sign(b, a, c)`; it is `+1`
/// when `c` lies to the left of the great circle through `a` then `b`.
#[inline]
pub(crate) fn orient(a: DVec3, b: DVec3, c: DVec3) -> i8 {
    // robust's orient3d(pa, pb, pc, pd) = det(pa - pd, pb - pd, pc - pd); with pd = 0 that is
    // det(a, b, c). Its fast path costs little more than the plain determinant.
    let d = orient3d(c3(a), c3(b), c3(c), c3(DVec3::ZERO));
    if d > 0.0 {
        1
    } else if d < 0.0 {
        -1
    } else {
        0
    }
}

/// Whether the minor arcs `a-b` and `c-d` share any point (crossing, touching or overlapping).
///
/// Used by validation, where touching rings are as invalid as crossing ones. `a != b`,
/// `c != d` and neither pair antipodal. Exact for the given floating-point inputs when the arcs
/// are in general position.
///
/// Crossing: with `n = a x b`, `m = c x d`, the great circles meet at `+-x`, `x = n x m`; `x`
/// lies inside arc `ab` iff `det(c,d,a) > 0 > det(c,d,b)` and inside arc `cd` iff
/// `det(a,b,c) < 0 < det(a,b,d)`. The arcs cross (at `x` or at `-x`) iff the four signs follow
/// this pattern or its reverse.
pub(crate) fn arcs_intersect(a: DVec3, b: DVec3, c: DVec3, d: DVec3) -> bool {
    let abc = orient(a, b, c);
    let abd = orient(a, b, d);
    let cda = orient(c, d, a);
    let cdb = orient(c, d, b);
    if abc != 0 && abd != 0 && cda != 0 && cdb != 0 {
        return abc != abd && cda != cdb && cda == abd;
    }
    // Touching or collinear: some endpoint lies on the other arc's great circle. Test each such
    // endpoint for lying on the other arc itself.
    (abc == 0 && on_arc(c, a, b))
        || (abd == 0 && on_arc(d, a, b))
        || (cda == 0 && on_arc(a, c, d))
        || (cdb == 0 && on_arc(b, c, d))
}

/// Whether `p`, known to lie on the great circle through `a` and `b`, lies on the closed minor arc
/// between them.
fn on_arc(p: DVec3, a: DVec3, b: DVec3) -> bool {
    // On the circle, turning from a to p and from p to b must both go the arc's way round (or not
    // at all, at the endpoints); -a and the far side of the circle fail one of the two.
    let n = a.cross(b);
    a.cross(p).dot(n) >= 0.0 && p.cross(b).dot(n) >= 0.0
}

/// Signed solid angle of the spherical triangle `(a, b, c)` (unit vectors), positive when
/// counter-clockwise seen from outside, in `(-2 pi, 2 pi)`.
///
/// Van Oosterom and Strackee (1983): `tan(Omega / 2) = det(a, b, c) / (1 + a.b + b.c + c.a)`.
/// The determinant is evaluated on edge differences, `a . (e x f)` for the two shorter of the
/// edges `b - a`, `c - b`, `a - c` (whose cross products, in cyclic order, are all equal): that
/// keeps full relative precision for tiny triangles, where `b x c` would cancel, and for thin
/// ones seen from a far vertex, where the cross product of the two long edges would (a triangle
/// 1e-8 wide from a vertex a radian away lost 1e-9 of its area that way).
#[inline]
pub(crate) fn triangle_solid_angle(a: DVec3, b: DVec3, c: DVec3) -> f64 {
    let (e1, e2, e3) = (b - a, c - b, a - c);
    let (l1, l2, l3) = (
        e1.length_squared(),
        e2.length_squared(),
        e3.length_squared(),
    );
    let cross = if l1 >= l2 && l1 >= l3 {
        e2.cross(e3)
    } else if l2 >= l3 {
        e3.cross(e1)
    } else {
        e1.cross(e2)
    };
    let det = a.dot(cross);
    let den = 1.0 + a.dot(b) + b.dot(c) + c.dot(a);
    2.0 * crate::math::atan2(det, den)
}

/// A right-handed orthonormal frame `(u, v)` completing the unit vector `n` (`u x v = n`).
///
/// Branch-free construction of Duff et al. 2017, "Building an orthonormal basis, revisited",
/// which is continuous except on the plane `n.z = 0` sign flip and never divides by zero.
pub(crate) fn tangent_frame(n: DVec3) -> (DVec3, DVec3) {
    let sign = if n.z >= 0.0 { 1.0 } else { -1.0 };
    let a = -1.0 / (sign + n.z);
    let b = n.x * n.y * a;
    let u = DVec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x);
    let v = DVec3::new(b, sign + n.y * n.y * a, -n.y);
    (u, v)
}

/// Normalizes a finite, non-zero vector of any magnitude, including ones whose squared length
/// would overflow or underflow; `None` for zero or non-finite input.
pub(crate) fn normalize_any(p: DVec3) -> Option<DVec3> {
    if !p.is_finite() {
        return None;
    }
    let m = p.abs().max_element();
    if m == 0.0 {
        return None;
    }
    // Scaling by the largest component first keeps the squared length in [1, 3].
    (p / m).try_normalize()
}

/// How far the minor arc between unit vectors `p` and `q` moves, at most, per unit of distance
/// one of its ends moves: `1` for arcs up to a quarter circle, `1 / sin L` for longer ones.
///
/// An end moved by `d` across the great circle turns the arc about the other end; at arc
/// length `s` from that fixed end the arc moves by `d sin s / sin L`, which peaks at the moved
/// end for `L <= pi / 2` and at `s = pi / 2` beyond. An edge between nearly antipodal vertices
/// (`sin L` about `|p + q|`) is a long lever: a vertex moved by `1e-11` moves its middle by
/// `1e-11 / |p + q|`, and the region by that over a length of about `pi`.
#[inline]
pub(crate) fn arc_lever(p: DVec3, q: DVec3) -> f64 {
    if p.dot(q) >= 0.0 {
        1.0
    } else {
        1.0 / p.cross(q).length()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frame_is_orthonormal_and_right_handed() {
        for n in [
            DVec3::Z,
            -DVec3::Z,
            DVec3::X,
            DVec3::new(0.3, -0.4, 0.5).normalize(),
            DVec3::new(1e-300, 0.0, -1.0).normalize(),
        ] {
            let (u, v) = tangent_frame(n);
            assert!((u.length() - 1.0).abs() < 1e-15);
            assert!((v.length() - 1.0).abs() < 1e-15);
            assert!(u.dot(v).abs() < 1e-15 && u.dot(n).abs() < 1e-15);
            assert!((u.cross(v) - n).length() < 1e-15);
        }
    }

    #[test]
    fn orient_properties() {
        let a = DVec3::new(1.0, 0.1, 0.2).normalize();
        let b = DVec3::new(0.1, 1.0, -0.3).normalize();
        let c = DVec3::new(0.2, 0.2, 1.0).normalize();
        assert_eq!(orient(a, b, c), 1);
        assert_eq!(orient(b, c, a), orient(a, b, c));
        assert_eq!(orient(b, a, c), -orient(a, b, c));
        assert_eq!(orient(a, b, a), 0);
    }

    #[test]
    fn octant_triangle_is_an_eighth_of_the_sphere() {
        let w = triangle_solid_angle(DVec3::X, DVec3::Y, DVec3::Z);
        assert!((w - core::f64::consts::FRAC_PI_2).abs() < 1e-15);
        assert!((triangle_solid_angle(DVec3::X, DVec3::Z, DVec3::Y) + w).abs() < 1e-15);
    }

    #[test]
    fn crossing_arcs() {
        let a = DVec3::new(1.0, -1.0, 0.0).normalize();
        let b = DVec3::new(1.0, 1.0, 0.0).normalize();
        let c = DVec3::new(1.0, 0.0, -1.0).normalize();
        let d = DVec3::new(1.0, 0.0, 1.0).normalize();
        assert!(arcs_intersect(a, b, c, d));
        assert!(arcs_intersect(c, d, b, a));
        // The antipodal arc meets the great circle of ab only at the other intersection point.
        assert!(!arcs_intersect(a, b, -c, -d));
        // Touching at an endpoint.
        assert!(arcs_intersect(a, b, DVec3::X, DVec3::Z));
        assert!(!arcs_intersect(a, b, DVec3::Z, d));
    }
}
