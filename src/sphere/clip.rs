//! Clipping spherical polygons to a hemisphere.

use core::f64::consts::PI;

use glam::DVec3;
use smallvec::SmallVec;

use super::polygon::{SphericalPolygon, Verts, close_ring, nearest_feature};
use super::predicates::{normalize_any, tangent_frame};
use crate::GeomError;

/// Vertices within this distance of the clipping great circle (`|n . v| <= HORIZON_TOLERANCE`)
/// are treated as lying on it.
///
/// `n . v` for unit vectors carries a rounding error of about `3.3e-16`; a vertex placed on the
/// circle by any computation (including this module's own output) lands within a few times that.
/// Treating such vertices as on the circle is what makes clipping idempotent and makes shared
/// horizon vertices of adjacent polygons agree.
pub const HORIZON_TOLERANCE: f64 = 1e-14;

/// Longest arc of the clipping circle emitted as one edge: edges must be minor arcs, and a
/// margin below `pi` keeps their great circles well defined.
const MAX_CIRCLE_STEP: f64 = 2.0 * PI / 3.0;

/// Side of the clipping plane, with "on" folded into "out" (see [`clip_polygon`]).
#[inline]
fn inside(s: f64) -> bool {
    s > HORIZON_TOLERANCE
}

impl SphericalPolygon {
    /// The part of the region in the closed hemisphere `{p : p . normal >= 0}`.
    ///
    /// `normal` need not be normalized. A zero or non-finite normal selects no hemisphere and
    /// gives the empty polygon; use [`SphericalPolygon::try_clip_to_hemisphere`] to get an error
    /// instead.
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
}

/// One piece of a ring inside the hemisphere, from the point where it enters (on the circle) to
/// the point where it leaves.
struct Chain {
    /// Range of this chain's vertices in the scratch buffer.
    start: usize,
    end: usize,
    /// Polar angles on the circle of the entry and exit points.
    entry_angle: f64,
    exit_angle: f64,
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
/// Degeneracies: vertices within [`HORIZON_TOLERANCE`] of the circle count as outside, and are
/// snapped onto it when a chain starts or ends there. An edge along the circle is thus dropped
/// and re-created by the joining arcs exactly when `R` lies on the `H` side of it, which is the
/// regularized result; a ring touching the circle from inside at a vertex splits into a chain
/// that exits and re-enters at the same point, joined by a zero-length arc.
fn clip_polygon(poly: &SphericalPolygon, n: DVec3) -> SphericalPolygon {
    if poly.is_full() {
        return hemisphere(n);
    }
    let (u, v) = tangent_frame(n);
    let angle = |p: DVec3| crate::math::atan2(p.dot(v), p.dot(u));
    let onto_circle = |p: DVec3| normalize_any(p - n * p.dot(n)).unwrap_or(p);

    let mut out_verts = Verts::new();
    let mut out_ends: SmallVec<[u32; 2]> = SmallVec::new();
    let mut scratch = Verts::new();
    let mut chains: SmallVec<[Chain; 4]> = SmallVec::new();
    let mut on_circle_ring: Option<bool> = None;

    for ring in poly.rings() {
        let m = ring.len();
        let s: SmallVec<[f64; 12]> = ring.iter().map(|p| p.dot(n)).collect();
        let n_in = s.iter().filter(|&&x| inside(x)).count();
        if n_in == m {
            out_verts.extend_from_slice(ring);
            out_ends.push(out_verts.len() as u32);
            continue;
        }
        if n_in == 0 {
            if s.iter().all(|x| x.abs() <= HORIZON_TOLERANCE) {
                // The ring is the circle itself: counter-clockwise about n it bounds H.
                let turn: f64 = (0..m)
                    .map(|i| ring[i].cross(ring[(i + 1) % m]).dot(n))
                    .sum();
                on_circle_ring = Some(turn > 0.0);
            }
            continue;
        }
        // Walk from an outside vertex so that every chain is complete within one pass.
        let first_out = s.iter().position(|&x| !inside(x)).unwrap_or(0);
        let mut open: Option<(usize, f64)> = None;
        for k in 0..m {
            let i = (first_out + k) % m;
            let j = (i + 1) % m;
            let (a, b, sa, sb) = (ring[i], ring[j], s[i], s[j]);
            match (inside(sa), inside(sb)) {
                (false, true) => {
                    // Entering: a lies on or below the circle.
                    let p = if sa.abs() <= HORIZON_TOLERANCE {
                        onto_circle(a)
                    } else {
                        onto_circle(b * (-sa) + a * sb)
                    };
                    open = Some((scratch.len(), angle(p)));
                    scratch.push(p);
                    scratch.push(b);
                }
                (true, true) => scratch.push(b),
                (true, false) => {
                    let on = sb.abs() <= HORIZON_TOLERANCE;
                    let p = if on {
                        onto_circle(b)
                    } else {
                        onto_circle(b * sa - a * sb)
                    };
                    scratch.push(p);
                    if let Some((start, entry_angle)) = open.take() {
                        chains.push(Chain {
                            start,
                            end: scratch.len(),
                            entry_angle,
                            exit_angle: angle(p),
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
                && winds_clockwise_about(poly, n)
                    .or_else(|| winds_clockwise_about(poly, -n))
                    .unwrap_or_else(|| circle_point_inside(poly, u, v))
        });
        if circle_inside {
            push_circle(&mut out_verts, &mut out_ends, n, u, v);
        }
        return finish(out_verts, out_ends);
    }

    // Join each exit to the entry that follows it counter-clockwise about n.
    let k = chains.len();
    let mut next: SmallVec<[usize; 4]> = SmallVec::from_elem(usize::MAX, k);
    let mut taken: SmallVec<[bool; 4]> = SmallVec::from_elem(false, k);
    for (c, chain) in chains.iter().enumerate() {
        let mut best = ((f64::INFINITY, f64::INFINITY), usize::MAX);
        for (d, other) in chains.iter().enumerate() {
            if taken[d] {
                continue;
            }
            let key = circle_gap(&scratch, n, chain, other);
            let better = if key.0 == best.0.0 && best.1 != usize::MAX && key.0 > 0.0 {
                // Two entries at one point (a pinch on the circle), reached along the circle:
                // the boundary turns into the one met first clockwise from the circle behind.
                entry_turn(&scratch, n, other) < entry_turn(&scratch, n, &chains[best.1])
            } else {
                key < best.0
            };
            if better {
                best = (key, d);
            }
        }
        if best.1 != usize::MAX {
            next[c] = best.1;
            taken[best.1] = true;
        }
    }
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
            out_verts.extend_from_slice(&scratch[ch.start..ch.end]);
            let d = next[c];
            if d == usize::MAX {
                break;
            }
            let gap = circle_gap(&scratch, n, ch, &chains[d]).0;
            // Intermediate vertices keep every circle edge a minor arc.
            let steps = crate::math::floor(gap / MAX_CIRCLE_STEP) as usize + 1;
            for t in 1..steps {
                let th = ch.exit_angle + gap * t as f64 / steps as f64;
                let (sn, cs) = (crate::math::sin(th), crate::math::cos(th));
                out_verts.push(u * cs + v * sn);
            }
            c = d;
        }
        close_ring(&mut out_verts, &mut out_ends, ring_start);
    }
    finish(out_verts, out_ends)
}

/// Counter-clockwise angle along the circle from the exit of `from` to the entry of `to`, with a
/// tie-break for when the two points coincide.
///
/// Coincident points occur at a ring touching the circle at a vertex, and at pinch vertices on
/// the circle. There the boundary of the clipped region continues along whichever is met first
/// turning clockwise (about the point) from the edge the exit arrived on: the entry's first edge
/// (join at once: angle 0, ordered by that turn) or the circle itself in its counter-clockwise
/// direction (go round: the entry is a full turn away). This is the corner rule of a region
/// whose interior lies on the left of every edge, and it sees every visit of a pinch at once.
fn circle_gap(scratch: &[DVec3], n: DVec3, from: &Chain, to: &Chain) -> (f64, f64) {
    let gap = (to.entry_angle - from.exit_angle).rem_euclid(2.0 * PI);
    if (1e-12..=2.0 * PI - 1e-12).contains(&gap) {
        return (gap, 0.0);
    }
    let x = scratch[from.end - 1];
    let (u, v) = tangent_frame(x);
    let ang = |q: DVec3| crate::math::atan2(q.dot(v), q.dot(u));
    let arrived = ang(scratch[from.end - 2]);
    let cw = |q: DVec3| {
        let t = (arrived - ang(q)).rem_euclid(2.0 * PI);
        if t <= 0.0 { 2.0 * PI } else { t }
    };
    let along_entry = cw(scratch[to.start + 1]);
    // The circle's counter-clockwise direction at x, as a point just along it.
    let along_circle = cw(x + n.cross(x));
    if along_entry < along_circle {
        (0.0, along_entry)
    } else {
        (2.0 * PI, along_entry)
    }
}

/// Clockwise turn, about the entry point of `to`, from the circle behind it (the direction the
/// boundary arrives from when it runs counter-clockwise along the circle) to the entry's first
/// edge.
fn entry_turn(scratch: &[DVec3], n: DVec3, to: &Chain) -> f64 {
    let e = scratch[to.start];
    let (u, v) = tangent_frame(e);
    let ang = |q: DVec3| crate::math::atan2(q.dot(v), q.dot(u));
    let back = ang(e - n.cross(e));
    let t = (back - ang(scratch[to.start + 1])).rem_euclid(2.0 * PI);
    if t <= 0.0 { 2.0 * PI } else { t }
}

/// When every vertex lies strictly inside the open hemisphere about `c`: whether the circle
/// bounding that hemisphere lies inside the region, else `None`.
///
/// In the gnomonic plane about `c` the rings are closed polygons and the circle is at infinity;
/// the unbounded face is inside the region iff the outermost rings run clockwise, i.e. iff the
/// total signed area is negative (nested rings alternate and are smaller than their parents).
/// Each ring's shoelace sum is taken about its own first vertex: summing `P_i x P_{i+1}` about the
/// plane's origin instead adds terms of the size of the ring's distance from `c` times its width,
/// whose rounding swamps the area of a ring of 1e-8 rad or less (a polygon of 3e-12 rad clipped
/// to its complement is such a case).
fn winds_clockwise_about(poly: &SphericalPolygon, c: DVec3) -> Option<bool> {
    let mut area2 = 0.0;
    for ring in poly.rings() {
        let project = |p: DVec3| {
            let w = p.dot(c);
            (w > HORIZON_TOLERANCE).then(|| p / w)
        };
        let origin = project(*ring.first()?)?;
        let mut prev = DVec3::ZERO;
        for &p in &ring[1..] {
            let d = project(p)? - origin;
            area2 += prev.cross(d).dot(c);
            prev = d;
        }
    }
    Some(area2 < 0.0)
}

/// Whether the clipping circle lies inside the region, when no ring crosses it: the region's side
/// at the circle point farthest from the boundary, among 16 evenly spaced ones.
fn circle_point_inside(poly: &SphericalPolygon, u: DVec3, v: DVec3) -> bool {
    let mut best = (f64::NEG_INFINITY, false);
    for k in 0..16 {
        let th = k as f64 * (PI / 8.0);
        let p = u * crate::math::cos(th) + v * crate::math::sin(th);
        if let Some((d, inside)) = nearest_feature(poly.rings(), p)
            && d > best.0
        {
            best = (d, inside);
        }
    }
    best.1
}

/// The closed hemisphere about `n` as a polygon: its boundary circle, counter-clockwise about `n`.
fn hemisphere(n: DVec3) -> SphericalPolygon {
    let (u, v) = tangent_frame(n);
    let mut verts = Verts::new();
    let mut ends = SmallVec::new();
    push_circle(&mut verts, &mut ends, n, u, v);
    SphericalPolygon::from_parts(verts, ends)
}

fn push_circle(verts: &mut Verts, ends: &mut SmallVec<[u32; 2]>, _n: DVec3, u: DVec3, v: DVec3) {
    verts.extend_from_slice(&[u, v, -u, -v]);
    ends.push(verts.len() as u32);
}

fn finish(verts: Verts, ends: SmallVec<[u32; 2]>) -> SphericalPolygon {
    SphericalPolygon::from_parts(verts, ends)
}
