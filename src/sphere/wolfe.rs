//! Wolfe's minimum-norm-point algorithm (P. Wolfe, *Finding the nearest point in a polytope*,
//! Math. Programming 11, 1976) over a convex set given by its support function, as GJK does
//! (Gilbert, Johnson, Keerthi 1988): the smallest enclosing cap of directions
//! ([`super::enclosing_cap`]) and separating planes of convex hulls (the `shade` layer) both need
//! the point of a polytope nearest the origin.

use glam::DVec3;
use smallvec::SmallVec;

/// The point of the convex set nearest the origin, where `support(x)` returns a point of the set
/// minimising `x . p` (for a point set: its lowest point along `x`), starting from the set's point
/// `start`.
///
/// `scale2` is the squared size of the set, for the stopping tests: a major cycle ends the search
/// when no point improves on `x` by more than `optimality * scale2` (Wolfe's test) and the search
/// stops at `|x|^2 <= 1e-30 * scale2` (the origin is in the set). `max_cycles` only guards
/// against rounding cycling: in exact arithmetic each major cycle strictly decreases `|x|` and
/// corrals never repeat.
pub(crate) fn min_norm_point(
    support: impl Fn(DVec3) -> DVec3,
    start: DVec3,
    scale2: f64,
    optimality: f64,
    max_cycles: usize,
) -> DVec3 {
    // The corral: points of the set and their convex weights.
    let mut set: SmallVec<[DVec3; 4]> = SmallVec::new();
    let mut lam: SmallVec<[f64; 4]> = SmallVec::new();
    set.push(start);
    lam.push(1.0);
    let mut x = start;
    for _ in 0..max_cycles {
        let p = support(x);
        // A full corral spans the origin, which cannot happen before the test below in exact
        // arithmetic; stop there too.
        if x.dot(x) - x.dot(p) <= optimality * scale2 || set.contains(&p) || set.len() == 4 {
            break;
        }
        set.push(p);
        lam.push(0.0);
        // Minor cycles: move towards the affine minimizer of the corral until it is interior.
        for _ in 0..5 {
            let Some(alpha) = affine_minimizer(&set) else {
                // Affinely dependent corral: drop the newcomer; x is already the best.
                set.pop();
                lam.pop();
                return x;
            };
            if alpha.iter().all(|&w| w > 0.0) {
                lam = alpha;
                x = combine(&set, &lam);
                break;
            }
            let mut theta = 1.0f64;
            for (l, w) in lam.iter().zip(&alpha) {
                if *w <= 0.0 {
                    theta = theta.min(l / (l - w));
                }
            }
            for (l, w) in lam.iter_mut().zip(&alpha) {
                *l += theta * (w - *l);
            }
            // Drop the points whose weight reached zero (at least the one that set theta).
            let mut i = 0;
            while i < set.len() {
                if lam[i] <= 1e-15 {
                    set.remove(i);
                    lam.remove(i);
                } else {
                    i += 1;
                }
            }
            if set.is_empty() {
                return x;
            }
            let total: f64 = lam.iter().sum();
            lam.iter_mut().for_each(|l| *l /= total);
            x = combine(&set, &lam);
        }
        if x.length_squared() <= 1e-30 * scale2 {
            break;
        }
    }
    x
}

fn combine(set: &[DVec3], lam: &[f64]) -> DVec3 {
    set.iter().zip(lam).map(|(&p, &l)| p * l).sum()
}

/// Weights (summing to one) of the point of the corral's affine hull nearest the origin, or
/// `None` when the corral is affinely dependent (to within `1e-12` relative).
fn affine_minimizer(set: &[DVec3]) -> Option<SmallVec<[f64; 4]>> {
    let q0 = set[0];
    let d: SmallVec<[DVec3; 3]> = set[1..].iter().map(|&p| p - q0).collect();
    let m = d.len();
    // Normal equations G beta = -D^T q0 with G = D^T D (m <= 3), by Cramer's rule on the
    // zero-padded 3x3 system.
    let mut g = [[0.0f64; 3]; 3];
    let mut rhs = [0.0f64; 3];
    for i in 0..3 {
        for j in 0..3 {
            g[i][j] = if i < m && j < m {
                d[i].dot(d[j])
            } else if i == j {
                1.0
            } else {
                0.0
            };
        }
        rhs[i] = if i < m { -d[i].dot(q0) } else { 0.0 };
    }
    let det3 = |a: &[[f64; 3]; 3]| {
        a[0][0] * (a[1][1] * a[2][2] - a[1][2] * a[2][1])
            - a[0][1] * (a[1][0] * a[2][2] - a[1][2] * a[2][0])
            + a[0][2] * (a[1][0] * a[2][1] - a[1][1] * a[2][0])
    };
    let det = det3(&g);
    let scale: f64 = (0..m)
        .map(|i| g[i][i])
        .product::<f64>()
        .max(f64::MIN_POSITIVE);
    if !(det.abs() > 1e-12 * scale) {
        return None;
    }
    let mut alpha: SmallVec<[f64; 4]> = SmallVec::from_elem(0.0, m + 1);
    let mut rest = 0.0;
    for k in 0..m {
        let mut gk = g;
        for (row, r) in gk.iter_mut().zip(rhs) {
            row[k] = r;
        }
        let beta = det3(&gk) / det;
        alpha[k + 1] = beta;
        rest += beta;
    }
    alpha[0] = 1.0 - rest;
    Some(alpha)
}
