//! Spherical generators and references: polygons star-shaped about a direction, an independent
//! stratified Monte Carlo estimator of solid angles and integrals with a stated confidence bound,
//! Gauss-Legendre quadrature over spherical triangles.

use super::Rng;
use arealight::glam::DVec3;
use arealight::sphere::SphericalPolygon;
use std::f64::consts::PI;

/// The point at geodesic distance `rho` from unit `c` in azimuth `theta` (about `c`).
pub fn polar(c: DVec3, rho: f64, theta: f64) -> DVec3 {
    let (u, v) = c.any_orthonormal_pair();
    (c * rho.cos() + (u * theta.cos() + v * theta.sin()) * rho.sin()).normalize()
}

/// A ring star-shaped about `c` (counter-clockwise seen from outside): `n` sorted azimuths with
/// gaps below pi (at most 1.4 times the even spacing) and radii in `[rho * shrink, rho]`.
pub fn star_ring(rng: &mut Rng, c: DVec3, n: usize, rho: f64, shrink: f64) -> Vec<DVec3> {
    let n = n.max(3);
    // Evenly spaced azimuths jittered by at most a fifth of the spacing: every gap is below
    // 1.4 * 2 pi / 3 < pi, so c sees every edge from inside and fans from c cover the ring once.
    let step = 2.0 * PI / n as f64;
    let start = rng.range(0.0, 2.0 * PI);
    (0..n)
        .map(|i| {
            let th = start + step * (i as f64 + rng.range(-0.2, 0.2));
            polar(c, rho * rng.range(shrink, 1.0), th)
        })
        .collect()
}

/// Stratified Monte Carlo estimate of the solid angle of `{d : inside(d)}`, with two jittered
/// samples per cell of an `nz x nphi` equal-area grid in (z, phi), and its estimated standard
/// deviation (from the within-cell sample variance, which is unbiased for the estimator's
/// variance). Returns (estimate, sigma, cell area).
pub fn mc_solid_angle(
    rng: &mut Rng,
    nz: usize,
    nphi: usize,
    mut inside: impl FnMut(DVec3) -> bool,
) -> (f64, f64, f64) {
    mc_integral(rng, nz, nphi, |d| if inside(d) { 1.0 } else { 0.0 })
}

/// As [`mc_solid_angle`], for the integral of a bounded function over the sphere. The floor of
/// [`assert_mc_agrees`] assumes `|f| <= 1`.
pub fn mc_integral(
    rng: &mut Rng,
    nz: usize,
    nphi: usize,
    mut f_of: impl FnMut(DVec3) -> f64,
) -> (f64, f64, f64) {
    let dz = 2.0 / nz as f64;
    let dphi = 2.0 * PI / nphi as f64;
    let area = dz * dphi;
    let (mut est, mut var) = (0.0, 0.0);
    for i in 0..nz {
        for j in 0..nphi {
            let mut f = [0.0; 2];
            for fk in &mut f {
                let z = -1.0 + dz * (i as f64 + rng.f64());
                let phi = dphi * (j as f64 + rng.f64());
                let r = (1.0 - z * z).max(0.0).sqrt();
                let d = DVec3::new(r * phi.cos(), r * phi.sin(), z);
                *fk = f_of(d);
            }
            est += area * (f[0] + f[1]) / 2.0;
            var += area * area * (f[0] - f[1]) * (f[0] - f[1]) / 4.0;
        }
    }
    (est, var.sqrt(), area)
}

/// Asserts that `exact` agrees with a stratified Monte Carlo estimate of an integrand with values
/// in `[0, 1]`, given an upper bound `boundary_cells` on the number of grid cells the integrand's
/// discontinuities (the region's boundary) cross.
///
/// The bound has two parts. Cells crossed by the boundary contribute independent, mean-zero
/// errors each within a range of one cell area `a`; by Hoeffding's inequality their sum exceeds
/// `a * sqrt(10.7 * N)` with probability below 1e-9. Cells not crossed have a smooth integrand;
/// their error is covered by 5 estimated standard deviations (from the within-cell spread).
/// A bound from the sample variance alone is not safe: in a boundary cell both samples agree
/// half the time or more, which makes small regions look noise-free.
pub fn assert_mc_agrees(exact: f64, mc: (f64, f64, f64), boundary_cells: f64, what: &str) {
    let (est, sigma, cell) = mc;
    let bound = 5.0 * sigma + cell * (10.7 * boundary_cells).sqrt() + 1e-12;
    assert!(
        (exact - est).abs() <= bound,
        "{what}: exact {exact} vs Monte Carlo {est} (bound {bound}, sigma {sigma})"
    );
}

/// Upper bound on the number of cells of the `nz x nphi` (z, phi) grid crossed by the minor arcs
/// `edges`: an arc crosses each latitude circle at most twice and, having monotone longitude,
/// each meridian at most once; every crossing enters one more cell.
pub fn crossed_cells(edges: impl Iterator<Item = (DVec3, DVec3)>, nz: usize, nphi: usize) -> f64 {
    let (dz, dphi) = (2.0 / nz as f64, 2.0 * PI / nphi as f64);
    let mut total = 0.0;
    for (a, b) in edges {
        let (mut zmin, mut zmax) = (a.z.min(b.z), a.z.max(b.z));
        // The z-extremes of the great circle, where they fall inside the arc.
        let n = a.cross(b);
        if n.length() > 0.0 {
            let top = DVec3::Z - n * (n.z / n.length_squared());
            if let Some(top) = top.try_normalize() {
                for p in [top, -top] {
                    if a.cross(p).dot(n) >= 0.0 && p.cross(b).dot(n) >= 0.0 {
                        zmin = zmin.min(p.z);
                        zmax = zmax.max(p.z);
                    }
                }
            }
        }
        let dphi_arc = {
            let d = b.y.atan2(b.x) - a.y.atan2(a.x);
            (d + PI).rem_euclid(2.0 * PI) - PI
        };
        total += 2.0 * (((zmax - zmin) / dz).ceil() + 1.0) + (dphi_arc.abs() / dphi).ceil() + 1.0;
    }
    total
}

/// The directed edges of a polygon's rings.
pub fn boundary_edges(p: &SphericalPolygon) -> impl Iterator<Item = (DVec3, DVec3)> + '_ {
    p.rings()
        .flat_map(|r| (0..r.len()).map(move |i| (r[i], r[(i + 1) % r.len()])))
}

/// The great circle orthogonal to `n`, as four quarter arcs.
pub fn great_circle(n: DVec3) -> impl Iterator<Item = (DVec3, DVec3)> {
    let (u, v) = n.normalize().any_orthonormal_pair();
    let q = [u, v, -u, -v];
    (0..4).map(move |i| (q[i], q[(i + 1) % 4]))
}

/// Gauss–Legendre nodes and weights on [0, 1], by Newton iteration on P_n.
pub fn gauss_legendre01(n: usize) -> Vec<(f64, f64)> {
    (0..n)
        .map(|i| {
            let mut x = (PI * (i as f64 + 0.75) / (n as f64 + 0.5)).cos();
            let mut dp = 0.0;
            for _ in 0..100 {
                let (mut p0, mut p1) = (1.0, x);
                for k in 2..=n {
                    let p2 = ((2 * k - 1) as f64 * x * p1 - (k - 1) as f64 * p0) / k as f64;
                    p0 = p1;
                    p1 = p2;
                }
                dp = n as f64 * (x * p1 - p0) / (x * x - 1.0);
                let dx = p1 / dp;
                x -= dx;
                if dx.abs() < 1e-16 {
                    break;
                }
            }
            let w = 2.0 / ((1.0 - x * x) * dp * dp);
            ((x + 1.0) / 2.0, w / 2.0)
        })
        .collect()
}

/// Integral of `f` over the spherical triangle (a, b, c) (all within an open hemisphere about
/// their sum), by tensor Gauss–Legendre on the planar triangle through them, mapped centrally to
/// the sphere: d omega = |q . N| / |q|^3 dA.
pub fn triangle_quadrature(
    a: DVec3,
    b: DVec3,
    c: DVec3,
    n: usize,
    f: impl Fn(DVec3) -> f64,
) -> f64 {
    let gl = gauss_legendre01(n);
    let (e1, e2) = (b - a, c - b);
    let cross = e1.cross(e2);
    let area2 = cross.length();
    let normal = cross / area2;
    let mut sum = 0.0;
    for &(s, ws) in &gl {
        for &(t, wt) in &gl {
            let q = a + e1 * s + e2 * (s * t);
            let r = q.length();
            let jac = area2 * s * q.dot(normal).abs() / (r * r * r);
            sum += ws * wt * jac * f(q / r);
        }
    }
    sum
}

/// The icosahedron subdivided once (42 vertices, 80 faces, counter-clockwise from outside), from
/// the crate's own mesh primitives.
pub fn icosphere(center: DVec3, radius: f64) -> (Vec<DVec3>, Vec<[usize; 3]>) {
    let ico = arealight::shade::ConvexPolyhedron::icosphere(center, radius, 1).expect("icosphere");
    let mesh = ico.mesh();
    let faces = mesh
        .triangles()
        .iter()
        .map(|t| t.map(|i| i as usize))
        .collect();
    (mesh.vertices().to_vec(), faces)
}
