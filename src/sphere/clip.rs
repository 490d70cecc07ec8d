//! Clipping spherical polygons to a hemisphere.

use core::cmp::Ordering;
use core::f64::consts::PI;

use glam::DVec3;
use smallvec::SmallVec;

use super::exact;
use super::polygon::{
    COINCIDENT_TOLERANCE, SphericalPolygon, Verts, close_ring, far_side_inside, folds_back,
    is_sliver, nearest_feature, regularized, ring_left_area, ring_small_area_err, rings_contain,
};
use super::predicates::{arcs_intersect, normalize_any, orient};
use crate::GeomError;

/// Vertices within this distance of the clipping great circle (`|n . v| <= HORIZON_TOLERANCE`)
/// are treated as lying on it.
///
/// `n . v` for unit vectors carries a rounding error of about `3.3e-16`; a vertex placed on the
/// circle by any computation (including this module's own output) lands within a few times that.
/// Treating such vertices as on the circle is what makes clipping idempotent and makes shared
/// horizon vertices of adjacent polygons agree. Moving a vertex this little onto the circle
/// changes the clipped region by at most four times `HORIZON_TOLERANCE` times the length of its
/// two edges (edges longer than about 151 degrees are first split in two).
pub const HORIZON_TOLERANCE: f64 = 1e-14;

/// Longest arc of the clipping circle emitted as one edge: edges must be minor arcs, and a
/// margin below `pi` keeps their great circles well defined.
const MAX_CIRCLE_STEP: f64 = 2.0 * PI / 3.0;

/// Edges that stay within this fraction of their length of the circle (both ends within
/// `FLAT_SLOPE` times their chord of it) lie along the circle to within the resolution of
/// validation, whose spike test rejects corners sharper than `1e-12` rad: their ends are snapped
/// onto the circle like vertices within [`HORIZON_TOLERANCE`]. Any other edge that crosses the
/// circle meets it at an angle above `FLAT_SLOPE`, so no corner of the result is sharper than
/// validation accepts. Snapping moves such an edge and the other edges of its ends by at most
/// four times `FLAT_SLOPE` times its length ([`SNAP_CHORD2`]), and the region by at most that
/// times the length of the edges involved.
const FLAT_SLOPE: f64 = 2e-12;

/// Longest squared chord of an edge whose ends may be snapped onto the circle: `|a - b|^2 <= 3.75`,
/// that is `|a + b| >= 1/2` (arcs up to about 151 degrees). A minor arc between two points
/// within `t` of the circle stays within `t / cos(L / 2) = 2 t / |a + b| <= 4 t` of it, so
/// snapping its ends moves it by at most four times their distance to the circle. A longer
/// edge at a vertex close to the circle is first split at its midpoint `a + b` (see
/// [`split_long_edges`]): near antipodal ends, such an edge could rise far above the circle
/// between two ends close to it.
const SNAP_CHORD2: f64 = 3.75;

impl SphericalPolygon {
    /// The part of the region in the closed hemisphere `{p : p . normal >= 0}`.
    ///
    /// `normal` need not be normalized, but it must be finite and non-zero. This signature
    /// (fixed by the crate's public contract) has no way to report a bad normal, so:
    ///
    /// - **Use [`SphericalPolygon::try_clip_to_hemisphere`] for any normal that comes from
    ///   input** (a shading normal, a face normal of user geometry, anything computed from
    ///   them): it returns [`GeomError::NonFiniteArgument`] or
    ///   [`GeomError::ZeroLengthArgument`] instead. Every clip inside the crate whose normal is
    ///   not a constant coordinate axis goes through it and passes the error on.
    /// - **A zero or non-finite normal here gives the empty polygon**, in every build, without
    ///   a panic (nothing in the crate panics on input). The empty region is the one answer
    ///   that cannot make a caller's result too large: integrated, it adds no light and no
    ///   solid angle. It is not a sign that the clip found nothing; only the checked form tells
    ///   the two apart.
    ///
    /// The result is exact for the polygon whose vertices within [`HORIZON_TOLERANCE`] of the
    /// circle, and ends of edges lying along it within `2e-12` of their length, are moved onto
    /// it: where the rings cross the circle, and in which order the crossings lie along it, is
    /// decided by exact predicates (a floating-point filter, and expansion arithmetic where the
    /// filter cannot decide), so that a vertex `1e-13` above the circle gives a region of
    /// `1e-26` sr, never the whole hemisphere. Result rings thinner than
    /// [`SphericalPolygon::new`] accepts ([`GeomError::ZeroArea`]) are dropped: every result
    /// is a valid input. Altogether the region moves by at most `4e-14` (vertices near the
    /// circle) or `8e-12` (edges along it) times the length of the edges involved, plus the
    /// dropped slivers (each at most `1e-12` times its squared perimeter).
    ///
    /// # Examples
    ///
    /// ```
    /// use arealight::glam::DVec3;
    /// use arealight::sphere::SphericalPolygon;
    ///
    /// // A band around the equator, from 30 degrees below it to 30 degrees above.
    /// let (c, s) = (0.5f64.sqrt() * 3f64.sqrt() / 2f64.sqrt(), 0.5);
    /// let quad = SphericalPolygon::new(vec![vec![
    ///     DVec3::new(c, -0.1, -s), DVec3::new(c, 0.1, -s),
    ///     DVec3::new(c, 0.1, s), DVec3::new(c, -0.1, s),
    /// ]])?;
    /// let upper = quad.clip_to_hemisphere(DVec3::Z);
    /// let lower = quad.clip_to_hemisphere(-DVec3::Z);
    /// assert!((upper.solid_angle() + lower.solid_angle() - quad.solid_angle()).abs() < 1e-15);
    /// # Ok::<(), arealight::GeomError>(())
    /// ```
    #[must_use]
    pub fn clip_to_hemisphere(&self, normal: DVec3) -> SphericalPolygon {
        self.try_clip_to_hemisphere(normal).unwrap_or_default()
    }

    /// As [`SphericalPolygon::clip_to_hemisphere`], with an error for a zero or non-finite
    /// normal.
    ///
    /// # Errors
    ///
    /// [`GeomError::NonFiniteArgument`] or [`GeomError::ZeroLengthArgument`] (`what` is
    /// `"hemisphere normal"`) for the normal.
    pub fn try_clip_to_hemisphere(&self, normal: DVec3) -> Result<SphericalPolygon, GeomError> {
        const WHAT: &str = "hemisphere normal";
        if !normal.is_finite() {
            return Err(GeomError::NonFiniteArgument { what: WHAT });
        }
        let n = normalize_any(normal).ok_or(GeomError::ZeroLengthArgument { what: WHAT })?;
        Ok(clip_polygon(self, n))
    }

    /// The clip at a unit normal the crate fixes itself (a coordinate axis), where no fault can
    /// arise: [`SphericalPolygon::try_clip_to_hemisphere`] without the check, bit for bit the
    /// same result (`normalize_any` returns an axis unchanged). Normals computed from input go
    /// through the checked form instead.
    pub(crate) fn clip_to_axis_hemisphere(&self, axis: DVec3) -> SphericalPolygon {
        debug_assert!(
            axis.abs().max_element() == 1.0 && axis.length_squared() == 1.0,
            "not a coordinate axis: {axis}"
        );
        clip_polygon(self, axis)
    }
}

/// Where a vertex lies against the clipping circle.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Side {
    Above,
    Below,
    /// Within [`HORIZON_TOLERANCE`] (with short edges), or exactly on it: treated as below, and
    /// snapped onto the circle where a chain starts or ends there.
    On,
}

/// What defines a point where the boundary meets the circle, exactly: the clip orders these
/// points along the circle with exact predicates on the input's own coordinates.
#[derive(Clone, Copy)]
enum Feature {
    /// A vertex on the circle (within the tolerance); the point is its projection onto the
    /// circle's plane.
    Vertex(DVec3),
    /// The crossing of the edge between a vertex above and one below the circle: the direction
    /// `(above x below) x n = below (above . n) - above (below . n)`, a positive combination of
    /// the two, so on the edge's minor arc.
    Edge { above: DVec3, below: DVec3 },
}

/// A point where the boundary meets the circle.
#[derive(Clone, Copy)]
struct Crossing {
    /// The point, rounded onto the circle.
    point: DVec3,
    /// Its polar angle about `n` in `[0, 2 pi]`, from the frame's `u` towards `v`.
    angle: f64,
    /// A bound on the error of `angle` against the exact point's angle.
    err: f64,
    feature: Feature,
}

/// One piece of a ring inside the hemisphere, from the point where it enters (on the circle) to
/// the point where it leaves.
struct Chain {
    /// Range of this chain's vertices in the scratch buffer.
    start: usize,
    end: usize,
    entry: Crossing,
    exit: Crossing,
    /// The input's vertex before the chain's first kept vertex, and after its last: the chain's
    /// first and last edges are the parts of the input's edges from and to them (exactly so
    /// for an edge's crossing, up to the snapping for a vertex on the circle).
    before: DVec3,
    after: DVec3,
}

/// The polar frame of the clipping circle. `exact_u = n x e_k` for the coordinate axis `e_k`
/// most nearly orthogonal to `n`: every component of it is a component of `n` (or zero), so it
/// is exactly orthogonal to `n`, which the exact predicates use. `(u, v)` is the normalized,
/// right-handed frame (`u x v = n`) in which the floating-point angles are measured and the
/// circle's points are made.
#[derive(Clone, Copy)]
struct Frame {
    n: DVec3,
    exact_u: DVec3,
    u: DVec3,
    v: DVec3,
}

impl Frame {
    fn new(n: DVec3) -> Frame {
        let a = n.abs();
        let axis = if a.x <= a.y && a.x <= a.z {
            DVec3::X
        } else if a.y <= a.z {
            DVec3::Y
        } else {
            DVec3::Z
        };
        let exact_u = n.cross(axis);
        let u = exact_u.normalize();
        Frame {
            n,
            exact_u,
            u,
            v: n.cross(u),
        }
    }

    fn angle(&self, p: DVec3) -> f64 {
        let t = crate::math::atan2(p.dot(self.v), p.dot(self.u));
        if t < 0.0 { t + 2.0 * PI } else { t }
    }

    fn point(&self, angle: f64) -> DVec3 {
        let (s, c) = crate::math::sin_cos(angle);
        self.u * c + self.v * s
    }

    /// The crossing of the edge between `above` (height `s_above > 0`) and `below`
    /// (`s_below < 0`; heights as computed, the signs are exact).
    fn edge_crossing(&self, above: DVec3, below: DVec3, s_above: f64, s_below: f64) -> Crossing {
        // The same expression for an edge and its reverse, so that polygons sharing an edge get
        // bit-identical crossing points.
        let w = below * s_above - above * s_below;
        let w = w - self.n * w.dot(self.n);
        let m = w.abs().max_element();
        let feature = Feature::Edge { above, below };
        if !(m > 0.0 && m.is_finite()) {
            // No usable direction in floating point (both heights round to zero): any point of
            // the edge near the circle will do for the output, and every comparison is exact.
            let point = normalize_any(above - self.n * above.dot(self.n)).unwrap_or(above);
            return Crossing {
                point,
                angle: self.angle(point),
                err: f64::INFINITY,
                feature,
            };
        }
        let len = (w / m).length();
        let point = w / m / len;
        // |w - W| <= 1.6e-15 for the exact W = below (above . n) - above (below . n) of unit
        // vectors (each height is off by at most 3.4e-16, each product and the difference round
        // by one ulp); the angle of w is then within |w - W| / |w| of W's, plus the rounding
        // of the normalization, the frame and atan2. Doubled for safety.
        let err = 4e-15 / (len * m) + 8e-15;
        Crossing {
            point,
            angle: self.angle(point),
            err,
            feature,
        }
    }

    /// The projection of a vertex `p` within the tolerance of the circle onto it.
    fn vertex_crossing(&self, p: DVec3, s: f64) -> Crossing {
        let point = normalize_any(p - self.n * s).unwrap_or(p);
        Crossing {
            point,
            angle: self.angle(point),
            err: 8e-15,
            feature: Feature::Vertex(p),
        }
    }

    /// Which half of the circle the exact point lies in: 0 for angles in `[0, pi)`, 1 for
    /// `[pi, 2 pi)`. Decided by the rounded angle where it is clear of `0` and `pi`.
    fn half(&self, c: &Crossing) -> u8 {
        let (t, e) = (c.angle, c.err);
        if t > e && t < PI - e {
            return 0;
        }
        if t > PI + e && t < 2.0 * PI - e {
            return 1;
        }
        // The point's component along v = n x exact_u (up to the positive factor |exact_u|) is
        // det(exact_u, x, n); for an edge's crossing x = (a x b) x n that is
        // (exact_u . n)((a x b) . n) - |n|^2 exact_u . (a x b) = -|n|^2 det(exact_u, a, b).
        let y = match c.feature {
            Feature::Vertex(p) => orient(self.exact_u, p, self.n),
            Feature::Edge { above, below } => -orient(self.exact_u, above, below),
        };
        if y != 0 {
            return if y > 0 { 0 } else { 1 };
        }
        // On the line of exact_u: angle 0 or pi by the component along it; for an edge's
        // crossing x . exact_u = (a . n)(b . exact_u) - (b . n)(a . exact_u).
        let x = match c.feature {
            Feature::Vertex(p) => exact::dot_sign(p, self.exact_u),
            Feature::Edge { above, below } => exact::dot_dot_difference_sign(
                (above, self.n),
                (below, self.exact_u),
                (below, self.n),
                (above, self.exact_u),
            ),
        };
        if x >= 0 { 0 } else { 1 }
    }

    /// Sign of `det(x, y, n)` for the exact points `x`, `y` of two features: positive when `y`
    /// follows `x` counter-clockwise by less than a half turn.
    fn turn_sign(&self, x: Feature, y: Feature) -> i8 {
        let n = self.n;
        match (x, y) {
            // det(p, q, n): the components along n drop out of the determinant.
            (Feature::Vertex(p), Feature::Vertex(q)) => orient(p, q, n),
            // y = b (a . n) - a (b . n): det(p, y, n) = (a . n) det(p, b, n) - (b . n) det(p, a, n).
            (Feature::Vertex(p), Feature::Edge { above, below }) => {
                exact::dot_det_difference_sign((above, n), (p, below, n), (below, n), (p, above, n))
            }
            (Feature::Edge { .. }, Feature::Vertex(_)) => -self.turn_sign(y, x),
            // x = P x n, y = Q x n: det(x, y, n) = |n|^2 det(P, Q, n), and with Q = c x d,
            // det(P, Q, n) = P . (d (c . n) - c (d . n)) = (c . n) det(a, b, d) - (d . n) det(a, b, c).
            (Feature::Edge { above: a, below: b }, Feature::Edge { above: c, below: d }) => {
                exact::dot_det_difference_sign((c, n), (a, b, d), (d, n), (a, b, c))
            }
        }
    }

    /// Sign of `det(P, x, y)` for the exact point `P` of crossing `c` and unit vectors `x`, `y`:
    /// positive when, seen from outside at `P`, the direction to `y` lies counter-clockwise of
    /// the direction to `x`. A floating-point filter (the point is within `c.err` of `P`'s
    /// direction, the determinant of unit vectors rounds by under `1e-15`), then exact: for a
    /// vertex `p`, `|n|^2 P = |n|^2 p - (p . n) n`; for an edge, `P = b (a . n) - a (b . n)`.
    fn around_sign(&self, c: &Crossing, x: DVec3, y: DVec3) -> i8 {
        let d = c.point.dot(x.cross(y));
        if d.abs() > 2.0 * c.err + 4e-15 {
            return if d > 0.0 { 1 } else { -1 };
        }
        let n = self.n;
        match c.feature {
            Feature::Vertex(p) => {
                exact::dot_det_difference_sign((n, n), (p, x, y), (p, n), (n, x, y))
            }
            Feature::Edge { above, below } => {
                exact::dot_det_difference_sign((above, n), (below, x, y), (below, n), (above, x, y))
            }
        }
    }

    /// The order of two crossings by exact polar angle in `[0, 2 pi)`.
    fn cmp(&self, a: &Crossing, b: &Crossing) -> Ordering {
        let clear = |c: &Crossing| c.angle > c.err && c.angle < 2.0 * PI - c.err;
        if (a.angle - b.angle).abs() > a.err + b.err && clear(a) && clear(b) {
            return a.angle.total_cmp(&b.angle);
        }
        let (ha, hb) = (self.half(a), self.half(b));
        if ha != hb {
            return ha.cmp(&hb);
        }
        match self.turn_sign(a.feature, b.feature) {
            1 => Ordering::Less,
            -1 => Ordering::Greater,
            _ => Ordering::Equal,
        }
    }
}

/// Seed paper 000, Alg. 3, generalized from the z-up horizon of one convex ring to any
/// hemisphere and to any valid polygon (several rings, holes, several crossings per ring, regions
/// larger than a hemisphere); the new edges on the circle are found as in thesis 003 section 4.3,
/// by sorting the crossing points by polar angle.
///
/// The result's boundary is `(boundary of R) n H` plus `(circle) n R`. Each ring is cut at its
/// crossings into chains inside `H`; going round the circle counter-clockwise about `n` (the
/// direction with `H` on the left), `R` covers exactly the arcs from a chain's exit to the next
/// entry, so each exit is joined to the entry that follows it by polar angle. Rings that never
/// enter `H` vanish, rings entirely inside stay, and when nothing crosses the circle the whole
/// circle is added if it lies inside `R`.
///
/// The order of the crossings along the circle decides everything, and two crossings can be
/// arbitrarily close (a vertex `1e-13` above the circle gives an entry and an exit `1e-13`
/// apart; a steep spike gives them far closer): it is decided exactly ([`Frame::cmp`]), and
/// the rounded angles are only used, made consistent with that order, to place the circle's
/// vertices.
///
/// Degeneracies: vertices within [`HORIZON_TOLERANCE`] of the circle count as outside, and are
/// snapped onto it when a chain starts or ends there. An edge along the circle is thus dropped
/// and re-created by the joining arcs exactly when `R` lies on the `H` side of it, which is the
/// regularized result; a ring touching the circle from inside at a vertex splits into a chain
/// that exits and re-enters at the same point, joined by a zero-length arc. Crossings at the
/// same point (exactly) are joined by the corner rule of [`first_clockwise`]. Ends of edges
/// lying along the circle within [`FLAT_SLOPE`] are snapped too, and result rings thinner than
/// validation accepts are dropped, so that every result is a valid input.
fn clip_polygon(poly: &SphericalPolygon, n: DVec3) -> SphericalPolygon {
    if poly.is_full() {
        return hemisphere(&Frame::new(n));
    }
    // Built on first use: polygons that do not cross the circle rarely need it.
    let mut frame_cell: Option<Frame> = None;
    let mut frame = || *frame_cell.get_or_insert_with(|| Frame::new(n));

    let mut out_verts = Verts::new();
    let mut out_ends: SmallVec<[u32; 2]> = SmallVec::new();
    let mut scratch = Verts::new();
    let mut chains: SmallVec<[Chain; 4]> = SmallVec::new();
    let mut on_circle_ring: Option<bool> = None;

    let mut split = Verts::new();
    for ring in poly.rings() {
        let mut s: SmallVec<[f64; 12]> = ring.iter().map(|p| p.dot(n)).collect();
        // Vertices that may be snapped must have short edges (see SNAP_CHORD2). Without any
        // vertex that close to the circle (the common case), sides are the signs of heights.
        let near = s.iter().any(|x| x.abs() <= 2.0 * FLAT_SLOPE);
        let ring = if near && has_long_edge_near(ring, &s) {
            split_long_edges(ring, &mut split);
            s = split.iter().map(|p| p.dot(n)).collect();
            &split[..]
        } else {
            ring
        };
        let m = ring.len();
        let sides: SmallVec<[Side; 12]> = if near {
            classify_ring(ring, &s)
        } else {
            SmallVec::new()
        };
        let side = |i: usize| {
            if near {
                sides[i]
            } else if s[i] > 0.0 {
                Side::Above
            } else {
                Side::Below
            }
        };
        let n_in = if near {
            (0..m).filter(|&i| side(i) == Side::Above).count()
        } else {
            s.iter().filter(|&&x| x > 0.0).count()
        };
        if n_in == m {
            out_verts.extend_from_slice(ring);
            out_ends.push(out_verts.len() as u32);
            continue;
        }
        if n_in == 0 {
            if (0..m).all(|i| side(i) == Side::On) {
                // Every vertex on the circle: if the ring winds round it, it is the circle itself
                // and, counter-clockwise about n, bounds H; otherwise it is a sliver along the
                // circle, outside H up to the tolerance.
                if let Some(ccw) = winding_about(ring, &frame()) {
                    on_circle_ring = Some(ccw);
                }
            }
            continue;
        }
        let frame = frame();
        // An edge between two vertices on the circle that is steeper than it is long along the
        // circle (a few ulps across it, more up or down it) is one point of the circle: snapping
        // its ends turns it by up to a right angle, so which side of it is inside would be set
        // by rounding, and the order of the chain's exit and entry there with it (twisting the
        // polygon). A run of such edges snaps to the run's first vertex, so that an exit into it
        // and an entry out of it meet at one point and the corner rule joins them. An edge along
        // the circle, however short, keeps its ends apart: its direction there is meaningful.
        let run_start = |i: usize| {
            let mut k = i;
            for _ in 1..m {
                let prev = (k + m - 1) % m;
                let d = ring[k] - ring[prev];
                let rise = (s[k] - s[prev]).abs();
                let along = (d - n * d.dot(n)).length();
                if side(prev) != Side::On
                    || d.length() > 2.0 * HORIZON_TOLERANCE
                    || along > rise + 4e-16
                {
                    break;
                }
                k = prev;
            }
            k
        };
        // Walk from a vertex not above so that every chain is complete within one pass.
        let first_out = (0..m).position(|i| side(i) != Side::Above).unwrap_or(0);
        let mut open: Option<(usize, Crossing, DVec3)> = None;
        for k in 0..m {
            let i = (first_out + k) % m;
            let j = (i + 1) % m;
            let (a, b) = (ring[i], ring[j]);
            let (si, sj) = (side(i), side(j));
            match (si == Side::Above, sj == Side::Above) {
                (false, true) => {
                    let c = if si == Side::On {
                        let r = run_start(i);
                        frame.vertex_crossing(ring[r], s[r])
                    } else {
                        frame.edge_crossing(b, a, s[j], s[i])
                    };
                    open = Some((scratch.len(), c, a));
                    scratch.push(c.point);
                    scratch.push(b);
                }
                (true, true) => scratch.push(b),
                (true, false) => {
                    let c = if sj == Side::On {
                        let r = run_start(j);
                        frame.vertex_crossing(ring[r], s[r])
                    } else {
                        frame.edge_crossing(a, b, s[i], s[j])
                    };
                    scratch.push(c.point);
                    if let Some((start, entry, before)) = open.take() {
                        chains.push(Chain {
                            start,
                            end: scratch.len(),
                            entry,
                            exit: c,
                            before,
                            after: b,
                        });
                    }
                }
                (false, false) => {}
            }
        }
    }

    if chains.is_empty() {
        let circle_inside = on_circle_ring.unwrap_or_else(|| {
            poly.ring_count() > 0
                && far_side_inside(poly.rings(), n)
                    .or_else(|| far_side_inside(poly.rings(), -n))
                    .unwrap_or_else(|| {
                        if out_verts.is_empty() {
                            // No ring enters the open upper side: it is all inside or all
                            // outside, and its pole is a quarter turn from every ring, even from
                            // one that runs along the circle (where every circle point is within
                            // rounding of it).
                            rings_contain(poly.rings(), n)
                        } else {
                            circle_point_inside(poly, &frame())
                        }
                    })
        });
        if circle_inside {
            push_circle(&mut out_verts, &mut out_ends, &frame());
        }
        return finish(out_verts, out_ends);
    }

    let frame = frame();
    let k = chains.len();
    // Whether two crossings lie within their rounding of each other: the order used is the
    // exact one, but their rounded points may not show it, and the result is regularized.
    let (next, delicate) = if k == 1 {
        single_chain_gap(&chains[0], &scratch, &frame)
    } else {
        join_chains(&chains, &scratch, &frame)
    };
    if delicate {
        merge_inverted_crossings(&chains, &next, &frame, &mut scratch);
    }
    let flipped = flipped_vertices(&chains, &scratch, &out_verts);
    // A chain's first or last edge ends at a rounded point: its direction is known only to the
    // point's rounding over the edge's length, and a spike of the input at the kept end (an
    // angle validation accepts, just) can become one it rejects. Such results are regularized.
    let folded = chains.iter().any(|ch| {
        let (s, e) = (ch.start, ch.end);
        folds_back(scratch[s], scratch[s + 1], scratch[s + 2])
            || folds_back(scratch[e - 3], scratch[e - 2], scratch[e - 1])
    });
    let mut visited: SmallVec<[bool; 4]> = SmallVec::from_elem(false, k);
    for first in 0..k {
        if visited[first] {
            continue;
        }
        let ring_start = out_verts.len();
        let mut c = first;
        for _ in 0..k {
            if visited[c] {
                break;
            }
            visited[c] = true;
            let ch = &chains[c];
            if flipped.is_empty() {
                out_verts.extend_from_slice(&scratch[ch.start..ch.end]);
            } else {
                // Vertices the shortened first or last edge would pass on the wrong side become
                // vertices of it, in their order along it.
                let on_edge = |exit: bool, out: &mut Verts| {
                    let from = out[out.len() - 1];
                    let mut xs: SmallVec<[DVec3; 2]> = flipped
                        .iter()
                        .filter(|f| f.0 == c && f.1 == exit)
                        .map(|f| f.2)
                        .collect();
                    xs.sort_by(|x, y| (*x - from).length().total_cmp(&(*y - from).length()));
                    out.extend_from_slice(&xs);
                };
                out_verts.push(scratch[ch.start]);
                on_edge(false, &mut out_verts);
                out_verts.extend_from_slice(&scratch[ch.start + 1..ch.end - 1]);
                on_edge(true, &mut out_verts);
                out_verts.push(scratch[ch.end - 1]);
            }
            let (d, gap, from) = next[c];
            if d == usize::MAX {
                break;
            }
            // Intermediate vertices keep every circle edge a minor arc.
            let steps = crate::math::floor(gap / MAX_CIRCLE_STEP) as usize + 1;
            for t in 1..steps {
                out_verts.push(frame.point(from + gap * t as f64 / steps as f64));
            }
            c = d;
        }
        close_ring(&mut out_verts, &mut out_ends, ring_start);
        // A ring cut from the boundary can be thinner than validation accepts (a thin spike or
        // neck of the input cut by the circle, a chain running just above the circle): such a
        // ring bounds nothing this crate can resolve and is dropped, as validation would
        // reject it. Its region, within the circle's hemisphere, is the thin side.
        if out_ends.last().is_some_and(|&e| e as usize > ring_start)
            && may_be_sliver(&out_verts[ring_start..], n)
            && is_sliver(&out_verts[ring_start..])
            && ring_left_area(&out_verts[ring_start..]) < 2.0 * PI
        {
            out_verts.truncate(ring_start);
            out_ends.pop();
        }
    }
    if delicate || folded || !flipped.is_empty() {
        // Crossings a rounding apart can leave a spike of that width (the tip of a sharp
        // corner just above the circle) or its rounded points out of the exact order: the folds
        // validation rejects are cut, and the points they leave merged.
        return regularized(out_verts, out_ends, COINCIDENT_TOLERANCE).0;
    }
    finish(out_verts, out_ends)
}

/// Kept vertices of the input that a chain's shortened first or last edge passes on the wrong
/// side of, or through: `(chain, whether the last edge, vertex)`.
///
/// The chain's first edge runs from the rounded crossing (or the vertex snapped onto the
/// circle) to the first kept vertex, instead of along the input's edge from the vertex before:
/// its great circle turns about the kept end by the crossing's rounding over the edge's length.
/// A vertex of the input closer than that to the input's edge (exactly on its great circle,
/// say, beyond the edge's end) can end up on the other side, or on the edge, and the result
/// would cross itself there. Its side of the input's edge is exact, and the same as of the exact
/// shortened edge (the crossing is a positive combination of the edge's ends), so the exact side
/// of the output's edge is compared with it; a vertex within the moved edge's reach that differs
/// (or lies on it) is put on the edge, where the boundary touches itself.
fn flipped_vertices(
    chains: &[Chain],
    scratch: &[DVec3],
    whole: &[DVec3],
) -> alloc::vec::Vec<(usize, bool, DVec3)> {
    let mut found = alloc::vec::Vec::new();
    let kept = chains
        .iter()
        .flat_map(|ch| &scratch[ch.start + 1..ch.end - 1])
        .chain(whole.iter());
    for (ci, ch) in chains.iter().enumerate() {
        for exit in [false, true] {
            let (p, q, c, original) = if exit {
                let p = scratch[ch.end - 2];
                (p, scratch[ch.end - 1], &ch.exit, (p, ch.after))
            } else {
                let q = scratch[ch.start + 1];
                (scratch[ch.start], q, &ch.entry, (ch.before, q))
            };
            let fixed = if exit { p } else { q };
            let nrm = p.cross(q);
            // The moved end is within its crossing's error bound (or the snapping distance) of
            // the exact point; the edge's great circle moves by that times the distance from
            // the fixed end over the edge's length.
            let shift = c.err.min(1.0) + 4.0 * HORIZON_TOLERANCE;
            let span = |x: DVec3| p.cross(x).dot(nrm) >= 0.0 && x.cross(q).dot(nrm) >= 0.0;
            for &x in kept.clone() {
                if x == p || x == q {
                    continue;
                }
                let tol = shift * (x - fixed).length() + 1e-15 * nrm.length();
                if x.dot(nrm).abs() > tol || !span(x) {
                    continue;
                }
                let truth = orient(original.0, original.1, x);
                if truth == 0 || orient(p, q, x) != truth {
                    found.push((ci, exit, x));
                }
            }
        }
    }
    found
}

/// Per chain, the entry its exit joins, the angle of the circle arc between them and the polar
/// angle of the exit (`usize::MAX` for none).
type Joins = SmallVec<[(usize, f64, f64); 4]>;

/// The circle arc from the exit of each chain to the entry it joins: `(chain, angle of the
/// arc, polar angle of the exit)`, or `(usize::MAX, ..)` for none; and whether two crossings
/// lie within their rounding of each other.
///
/// Each exit joins the entry that follows it counter-clockwise about `n`. At the exit's own point
/// (a ring touching the circle at a vertex, a pinch on the circle) the corner rule decides
/// whether the boundary turns into an entry there at once; otherwise it runs along the circle to
/// the nearest point holding an entry, where it turns into the entry met first clockwise from
/// the circle behind it. See [`first_clockwise`] for the corner rule.
fn join_chains(chains: &[Chain], scratch: &[DVec3], frame: &Frame) -> (Joins, bool) {
    let k = chains.len();
    let order = sorted_crossings(chains, frame);
    // Neighbours along the circle (cyclically) within their rounding of each other.
    let delicate = (0..order.len()).any(|w| {
        let (a, b) = (
            crossing(chains, order[w]),
            crossing(chains, order[(w + 1) % order.len()]),
        );
        let d = (b.angle - a.angle).rem_euclid(2.0 * PI);
        d <= a.err + b.err || d >= 2.0 * PI - a.err - b.err
    });
    // Rank of each crossing's point along the circle (crossings at exactly the same point share
    // one), and angles made consistent with that order: inside [0, pi] or [pi, 2 pi] as the
    // exact half says, non-decreasing along it, equal at equal points.
    let mut rank: SmallVec<[usize; 8]> = SmallVec::from_elem(0, 2 * k);
    let mut angle: SmallVec<[f64; 8]> = SmallVec::from_elem(0.0, 2 * k);
    let mut groups = 0usize;
    for (w, &i) in order.iter().enumerate() {
        let c = crossing(chains, i);
        let same = w > 0 && frame.cmp(crossing(chains, order[w - 1]), c) == Ordering::Equal;
        if w > 0 && !same {
            groups += 1;
        }
        rank[i] = groups;
        let t = match frame.half(c) {
            0 if c.angle > 1.5 * PI => 0.0,
            0 => c.angle.min(PI),
            _ if c.angle < 0.5 * PI => 2.0 * PI,
            _ => c.angle.max(PI),
        };
        angle[i] = if w == 0 {
            t
        } else if same {
            angle[order[w - 1]]
        } else {
            t.max(angle[order[w - 1]])
        };
    }
    let groups = groups + 1;

    // Join each exit to the entry that follows it counter-clockwise about n. At the exit's own
    // point (a ring touching the circle at a vertex, a pinch on the circle) the corner rule
    // decides whether the boundary turns into an entry there at once; otherwise it runs along
    // the circle to the nearest point holding an entry, where it turns into the entry met first
    // clockwise from the circle behind it. See `first_clockwise` for the corner rule.
    let mut next: SmallVec<[(usize, f64, f64); 4]> = SmallVec::from_elem((usize::MAX, 0.0, 0.0), k);
    let mut taken: SmallVec<[bool; 4]> = SmallVec::from_elem(false, k);
    for c in 0..k {
        let (xr, xa) = (rank[2 * c + 1], angle[2 * c + 1]);
        let exit = &chains[c].exit;
        let arrived = scratch[chains[c].end - 2];
        let first_in = |d: usize| scratch[chains[d].start + 1];
        // Entries at the exit's point that lie clockwise of the arrival (between it and the
        // circle ahead), the one met first.
        let here = (0..k).filter(|&d| !taken[d] && rank[2 * d] == xr);
        let join = first_clockwise(
            frame,
            exit,
            here.filter(|&d| frame.around_sign(exit, first_in(d), arrived) > 0),
            first_in,
        );
        let choice = match join {
            Some(d) => Some((d, 0.0)),
            None => {
                // Along the circle: the nearest rank ahead (a full turn back to the exit's own
                // point counts as the farthest).
                let ahead = |d: usize| match (rank[2 * d] + groups - xr) % groups {
                    0 => groups,
                    r => r,
                };
                let open = || (0..k).filter(|&d| !taken[d]);
                open().map(ahead).min().and_then(|r| {
                    let at = open().filter(|&d| ahead(d) == r);
                    let d =
                        first_clockwise(frame, &chains[at.clone().next()?].entry, at, first_in)?;
                    let er = rank[2 * d];
                    let gap = if r == groups {
                        2.0 * PI
                    } else {
                        angle[2 * d] - xa + if er < xr { 2.0 * PI } else { 0.0 }
                    };
                    Some((d, gap))
                })
            }
        };
        if let Some((d, gap)) = choice {
            next[c] = (d, gap.clamp(0.0, 2.0 * PI), xa);
            taken[d] = true;
        }
    }
    (next, delicate)
}

/// [`join_chains`] for a single chain, whose exit can only join its own entry: only the arc
/// between them is to be decided, by the rounded angles where it is clear of both `0` and a full
/// turn by their error bounds (no order along the circle is needed), else exactly (and then
/// the second value is `true`).
fn single_chain_gap(chain: &Chain, scratch: &[DVec3], frame: &Frame) -> (Joins, bool) {
    let (x, e) = (&chain.exit, &chain.entry);
    let gap = e.angle - x.angle;
    let gap = if gap < 0.0 { gap + 2.0 * PI } else { gap };
    let tol = x.err + e.err;
    let clear = gap > tol && gap < 2.0 * PI - tol;
    // A vertex snapped onto the circle can move its crossing by its height over its edge's
    // slope, far more than rounding: the exact order of two such points a rounding apart is
    // then an artifact of the snap. The chain closed on itself is a small loop either way, and
    // which side of it is inside (its orientation, well beyond its rounding) tells whether the
    // exit joins the entry at once or a full turn round.
    let snapped =
        matches!(x.feature, Feature::Vertex(_)) || matches!(e.feature, Feature::Vertex(_));
    let loop_sign = || {
        // The loop through the vertices as given (before the snap), whose crossing points it
        // approximates far better than their projections do: at a snapped end, the input's
        // vertex next to the chain itself, not the start of its run of steep edges (a run
        // snaps to one point, and a chain whose entry and exit snap there would otherwise close
        // on that point with no area, leaving the decision to rounding).
        let mut ring: Verts = scratch[chain.start..chain.end].iter().copied().collect();
        ring[0] = match e.feature {
            Feature::Vertex(_) => chain.before,
            Feature::Edge { .. } => e.point,
        };
        let last = ring.len() - 1;
        ring[last] = match x.feature {
            Feature::Vertex(_) => chain.after,
            Feature::Edge { .. } => x.point,
        };
        let (area, err) = ring_small_area_err(&ring);
        if area.abs() > 4.0 * err {
            area.signum() as i8
        } else {
            0
        }
    };
    let gap = if clear {
        gap
    } else if snapped && loop_sign() != 0 {
        if loop_sign() > 0 {
            gap.min(2.0 * PI - gap)
        } else {
            gap.max(2.0 * PI - gap)
        }
    } else {
        match frame.turn_sign(x.feature, e.feature) {
            // The entry just after the exit (or just before it): a short arc, or nearly all.
            1 => gap.min(2.0 * PI - gap),
            -1 => gap.max(2.0 * PI - gap),
            // The same point: the corner rule, with the circle ahead as the alternative.
            _ => {
                let first_in = |_: usize| scratch[chain.start + 1];
                let arrived = scratch[chain.end - 2];
                let join = frame.around_sign(x, first_in(0), arrived) > 0;
                if join { 0.0 } else { 2.0 * PI }
            }
        }
    };
    (smallvec::smallvec![(0, gap, x.angle)], !clear)
}

/// Neighbouring crossings along the circle whose rounded points lie out of their exact order
/// (or on one point) made one point, the first one's, in `scratch`; except an exit and the entry
/// it joins by a short arc, an edge of the result, whose fold [`regularized`] cuts. Elsewhere two
/// such points end up in different places of the result (an exit joined to an entry a full turn
/// round, its neighbour a rounding behind it), and the ring, which should touch itself there at
/// one vertex, would cross itself.
fn merge_inverted_crossings(chains: &[Chain], next: &Joins, frame: &Frame, scratch: &mut [DVec3]) {
    let at = |i: usize| {
        let c = &chains[i / 2];
        if i.is_multiple_of(2) {
            c.start
        } else {
            c.end - 1
        }
    };
    let order = sorted_crossings(chains, frame);
    let m = order.len();
    let original: SmallVec<[DVec3; 8]> = (0..m).map(|i| scratch[at(i)]).collect();
    // The edge at crossing i as rounded: from the entry point to the chain's first vertex, or
    // from its last vertex to the exit point.
    let first: SmallVec<[DVec3; 4]> = chains.iter().map(|c| scratch[c.start + 1]).collect();
    let last: SmallVec<[DVec3; 4]> = chains.iter().map(|c| scratch[c.end - 2]).collect();
    let edge = |i: usize, points: &[DVec3]| {
        if i.is_multiple_of(2) {
            (points[i], first[i / 2])
        } else {
            (last[i / 2], points[i])
        }
    };
    // Edges sharing an end (a chain of one vertex) meet there; only others can cross.
    let edges_cross = |a: usize, b: usize, points: &[DVec3]| {
        let ((p, q), (r, t)) = (edge(a, points), edge(b, points));
        p != r && p != t && q != r && q != t && arcs_intersect(p, q, r, t)
    };
    for w in 0..m {
        let (a, b) = (order[w], order[(w + 1) % m]);
        let (ca, cb) = (crossing(chains, a), crossing(chains, b));
        // Within their rounding of each other (either way round: a rounded angle may lie across
        // the polar angle 0 from its exact point), with b exactly at a or just ahead of it, not
        // just behind it a full turn round (the wrapping pair of two crossings).
        let d = (cb.angle - ca.angle).rem_euclid(2.0 * PI);
        let close = (d <= ca.err + cb.err || d >= 2.0 * PI - ca.err - cb.err)
            && frame.turn_sign(ca.feature, cb.feature) >= 0;
        let joined = a % 2 == 1 && b % 2 == 0 && next[a / 2].0 == b / 2 && next[a / 2].1 < PI;
        let (pa, pb) = (original[a], original[b]);
        // b's rounded point not counter-clockwise of a's: out of the exact order, or equal; or
        // in order along the circle but across the other's edge (the rounding of a point is not
        // only along the circle, and steep edges leave the circle a rounding apart).
        if close
            && !joined
            && (pa.cross(pb - pa).dot(frame.n) <= 0.0 || edges_cross(a, b, &original))
        {
            scratch[at(b)] = scratch[at(a)];
        }
    }
}

/// `false` when a ring of the result is certainly not a sliver ([`is_sliver`]), by a bound that
/// costs no trigonometry and is conclusive for ordinary rings; `true` leaves it to the exact
/// criterion.
///
/// The ring's region `W` lies in the hemisphere, so its area is at least its shadow on the
/// circle's plane, `int_W (x . n) dA`, which is the boundary's vector area along `n`:
/// `1/2 sum theta_i (m_i . n)` over the arcs (angle `theta_i`, unit normal `m_i`). The chord
/// polygon gives `1/2 sum sin(theta_i) (m_i . n)`; an arc on the circle (both ends on it) only
/// adds to it (`m_i = n`), any other arc changes it by at most `(theta - sin theta) / 2 <=
/// theta^3 / 12`, with `theta <= (pi / 2) chord`. The perimeter is at most `(pi / 2)` times the
/// sum of the chords.
fn may_be_sliver(ring: &[DVec3], n: DVec3) -> bool {
    let m = ring.len();
    let (mut shadow2, mut chords, mut cubes) = (0.0, 0.0, 0.0);
    for i in 0..m {
        let (a, b) = (ring[i], ring[(i + 1) % m]);
        shadow2 += a.cross(b).dot(n);
        let c = (b - a).length();
        chords += c;
        if a.dot(n).abs() > HORIZON_TOLERANCE || b.dot(n).abs() > HORIZON_TOLERANCE {
            cubes += c * c * c;
        }
    }
    let half_pi = 0.5 * PI;
    let shadow = 0.5 * shadow2 - half_pi * half_pi * half_pi / 12.0 * cubes - 1e-15 * m as f64;
    let perimeter = half_pi * chords;
    !(shadow > 1e-12 * perimeter * perimeter)
}

/// Where vertex `i` of `ring` (with heights `s`) lies against the circle: on it when within
/// [`HORIZON_TOLERANCE`] or at the end of a flat edge ([`FLAT_SLOPE`]). Vertices this close to
/// the circle have short edges ([`SNAP_CHORD2`]; the caller splits longer ones).
#[inline]
/// [`classify`] for every vertex of a ring, closed under snapping: a vertex next to a snapped
/// one is snapped too when it lies within [`FLAT_SLOPE`] of their chord from the circle (the edge
/// lies along the circle once the neighbour is on it; kept, the vertex would leave the snapped
/// point at an angle below validation's `1e-12` rad resolution, where the circle arc joined
/// there can run back over the edge: a fold), or when it is no higher than the neighbour and
/// within four times the neighbour's height of it (in the band the neighbour's snap sweeps: the
/// neighbour's other edges, moved onto the circle, would pass over it). Each such vertex is
/// within `FLAT_SLOPE` times an edge, or a snapped neighbour's height, of the circle.
fn classify_ring(ring: &[DVec3], s: &[f64]) -> SmallVec<[Side; 12]> {
    let m = ring.len();
    let mut sides: SmallVec<[Side; 12]> = (0..m).map(|i| classify(ring, s, i)).collect();
    let mut changed = true;
    while changed {
        changed = false;
        for i in 0..m {
            if sides[i] == Side::On || s[i].abs() > 2.0 * FLAT_SLOPE {
                continue;
            }
            let flat_to = |j: usize| {
                let d = (ring[j] - ring[i]).length();
                sides[j] == Side::On
                    && (s[i].abs() <= FLAT_SLOPE * d
                        || (s[i].abs() <= s[j].abs() && d <= 4.0 * s[j].abs()))
            };
            if flat_to((i + m - 1) % m) || flat_to((i + 1) % m) {
                sides[i] = Side::On;
                changed = true;
            }
        }
    }
    sides
}

fn classify(ring: &[DVec3], s: &[f64], i: usize) -> Side {
    let x = s[i];
    // Chords are at most 2, so beyond this no edge can be flat: the common case.
    if x.abs() > 2.0 * FLAT_SLOPE {
        return if x > 0.0 { Side::Above } else { Side::Below };
    }
    if x.abs() <= HORIZON_TOLERANCE {
        return Side::On;
    }
    let m = ring.len();
    let p = ring[i];
    let flat = |j: usize| x.abs().max(s[j].abs()) <= FLAT_SLOPE * (ring[j] - p).length();
    if flat((i + m - 1) % m) || flat((i + 1) % m) {
        Side::On
    } else if x > 0.0 {
        Side::Above
    } else {
        Side::Below
    }
}

/// Whether a vertex within `2 FLAT_SLOPE` of the circle (one that may be snapped) has an edge
/// longer than [`SNAP_CHORD2`].
fn has_long_edge_near(ring: &[DVec3], s: &[f64]) -> bool {
    let m = ring.len();
    (0..m).any(|i| {
        let j = (i + 1) % m;
        (s[i].abs() <= 2.0 * FLAT_SLOPE || s[j].abs() <= 2.0 * FLAT_SLOPE)
            && (ring[j] - ring[i]).length_squared() > SNAP_CHORD2
    })
}

/// `ring` with every edge longer than [`SNAP_CHORD2`] split at its midpoint, into `out`.
///
/// The midpoint direction `a + b` is a positive combination of the ends, so on the arc; it is
/// computed to full relative precision even for ends near antipodal (the sums of nearly opposite
/// coordinates are exact by Sterbenz's lemma), and validation keeps `|a + b|` above
/// [`super::ANTIPODAL_TOLERANCE`]. Both halves are shorter than a quarter turn.
fn split_long_edges(ring: &[DVec3], out: &mut Verts) {
    out.clear();
    let m = ring.len();
    for i in 0..m {
        let (a, b) = (ring[i], ring[(i + 1) % m]);
        out.push(a);
        if (b - a).length_squared() > SNAP_CHORD2
            && let Some(mid) = normalize_any(a + b)
        {
            out.push(mid);
        }
    }
}

/// Crossing `i` of the chains: entries at even, exits at odd indices.
fn crossing(chains: &[Chain], i: usize) -> &Crossing {
    let c = &chains[i / 2];
    if i.is_multiple_of(2) {
        &c.entry
    } else {
        &c.exit
    }
}

/// The indices of all crossings, sorted by exact polar angle. An insertion sort: the lists are
/// short, and it cannot be upset even by a comparison that contradicts another.
fn sorted_crossings(chains: &[Chain], frame: &Frame) -> SmallVec<[usize; 8]> {
    let mut order: SmallVec<[usize; 8]> = (0..2 * chains.len()).collect();
    for w in 1..order.len() {
        let mut j = w;
        while j > 0
            && frame.cmp(crossing(chains, order[j - 1]), crossing(chains, order[j]))
                == Ordering::Greater
        {
            order.swap(j - 1, j);
            j -= 1;
        }
    }
    order
}

/// Among entries `ds` at one point of the circle (that of `at`), the one whose first edge is met
/// first turning clockwise from above: the one most counter-clockwise, seen from outside at the
/// point, by exact orientation ([`Frame::around_sign`]). Every first edge leaves the point into
/// the open upper side (its vertex is above the circle), so these directions lie within a half
/// turn of each other and the order is well defined.
///
/// This is the corner rule of a region whose interior lies on the left of every edge: arriving
/// at a point, the boundary leaves along the first edge met turning clockwise from the edge it
/// arrived on. Arriving along the circle (from behind, counter-clockwise), that is the most
/// counter-clockwise entry; arriving by an exit, it is the most counter-clockwise among the
/// entries clockwise of the arrival, if any, and else the circle ahead.
fn first_clockwise(
    frame: &Frame,
    at: &Crossing,
    ds: impl Iterator<Item = usize>,
    first_in: impl Fn(usize) -> DVec3,
) -> Option<usize> {
    let mut best: Option<usize> = None;
    for d in ds {
        best = match best {
            Some(b) if frame.around_sign(at, first_in(b), first_in(d)) <= 0 => Some(b),
            _ => Some(d),
        };
    }
    best
}

/// For a ring whose vertices all lie on the circle (within the tolerance): whether it winds
/// round the circle counter-clockwise (`Some(true)`), clockwise (`Some(false)`), or not at all
/// (`None`: a sliver along the circle, whose polar angles go back and forth).
fn winding_about(ring: &[DVec3], frame: &Frame) -> Option<bool> {
    let m = ring.len();
    let mut total = 0.0;
    let mut prev = frame.angle(ring[m - 1]);
    for &p in ring {
        let t = frame.angle(p);
        // Each edge is a minor arc, so its polar step is the one in (-pi, pi].
        let mut d = t - prev;
        if d > PI {
            d -= 2.0 * PI;
        } else if d <= -PI {
            d += 2.0 * PI;
        }
        total += d;
        prev = t;
    }
    (total.abs() > PI).then_some(total > 0.0)
}

/// Whether the clipping circle lies inside the region, when no ring crosses it: the region's side
/// at the circle point farthest from the boundary, among 16 evenly spaced ones.
fn circle_point_inside(poly: &SphericalPolygon, frame: &Frame) -> bool {
    let mut best = (f64::NEG_INFINITY, frame.u);
    for k in 0..16 {
        let p = frame.point(k as f64 * (PI / 8.0));
        if let Some((d, _)) = nearest_feature(poly.rings(), p)
            && d > best.0
        {
            best = (d, p);
        }
    }
    rings_contain(poly.rings(), best.1)
}

/// The closed hemisphere about `n` as a polygon: its boundary circle, counter-clockwise about `n`.
fn hemisphere(frame: &Frame) -> SphericalPolygon {
    let mut verts = Verts::new();
    let mut ends = SmallVec::new();
    push_circle(&mut verts, &mut ends, frame);
    SphericalPolygon::from_parts(verts, ends)
}

fn push_circle(verts: &mut Verts, ends: &mut SmallVec<[u32; 2]>, frame: &Frame) {
    let (u, v) = (frame.u, frame.v);
    verts.extend_from_slice(&[u, v, -u, -v]);
    ends.push(verts.len() as u32);
}

fn finish(verts: Verts, ends: SmallVec<[u32; 2]>) -> SphericalPolygon {
    SphericalPolygon::from_parts(verts, ends)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Triples whose orientation is exactly zero or below the rounding of the rounded crossing
    /// point: the exact branch decides (zero is zero, and a tiny determinant keeps its sign).
    #[test]
    fn corner_orientation_is_exact() {
        let frame = Frame::new(DVec3::Z);
        let tiny = DVec3::new(0.0, 0.0, 2f64.powi(-50));
        // A vertex on the circle; its rounded point (0.6, 0.8, 0) is not exact.
        let p = DVec3::new(3.0, 4.0, 0.0);
        let at_vertex = frame.vertex_crossing(p, 0.0);
        // An edge's crossing: (above x below) x n = 2 x for these ends.
        let (above, below) = (DVec3::new(1.0, 0.0, 1.0), DVec3::new(1.0, 0.0, -1.0));
        let at_edge = frame.edge_crossing(above, below, 1.0, -1.0);
        for (c, q) in [(at_vertex, p), (at_edge, DVec3::X)] {
            let x = DVec3::new(1.0, 1.0, 1.0);
            // y = q + x lies on the plane of q and x: det(q, x, y) = 0.
            assert_eq!(frame.around_sign(&c, x, q + x), 0);
            // det(q, x, q + x + t) = det(q, x, t) = t.z (q x x).z, a 2^-50 perturbation.
            let s = q.cross(x).z.signum() as i8;
            assert_eq!(frame.around_sign(&c, x, q + x + tiny), s);
            assert_eq!(frame.around_sign(&c, q + x + tiny, x), -s);
        }
    }

    /// Crossings within rounding of the cut of the polar angle (its direction `exact_u`) are put
    /// on the right side of it by the exact half-plane test, and ordered exactly.
    #[test]
    fn order_across_the_cut_is_exact() {
        let frame = Frame::new(DVec3::Z);
        let u = frame.exact_u;
        let side = u.cross(DVec3::Z); // the clockwise side of u
        let at = |t: f64| frame.vertex_crossing(u + side * t, 0.0);
        let (before, on, after) = (at(1e-20), at(0.0), at(-1e-20));
        // `before` is a hair clockwise of the cut: angle just below 2 pi, in the upper half.
        assert_eq!(frame.half(&before), 1);
        assert_eq!(frame.half(&on), 0);
        assert_eq!(frame.half(&after), 0);
        assert_eq!(frame.cmp(&on, &after), Ordering::Less);
        assert_eq!(frame.cmp(&after, &before), Ordering::Less);
        assert_eq!(frame.cmp(&on, &before), Ordering::Less);
        assert_eq!(frame.cmp(&on, &at(0.0)), Ordering::Equal);
    }
}
