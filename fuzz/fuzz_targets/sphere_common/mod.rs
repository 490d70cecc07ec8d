//! Shared driver of the spherical fuzz targets: decode polygons from small integer directions
//! (so that shared vertices, vertices on great circles through others and exact degeneracies are
//! frequent), skip invalid inputs (`SphericalPolygon::new` rejects them), and assert invariants.

use arealight::glam::DVec3;
use arealight::planar::BoolOp;
use arealight::sphere::SphericalPolygon;
use libfuzzer_sys::arbitrary::{self, Arbitrary};
use std::f64::consts::PI;

/// One polygon: up to 3 rings of up to 12 integer directions, optionally complemented.
#[derive(Debug, Arbitrary)]
pub struct Poly {
    rings: Vec<Vec<(i8, i8, i8)>>,
    complement: bool,
}

impl Poly {
    pub fn build(&self) -> Option<SphericalPolygon> {
        let rings: Vec<Vec<DVec3>> = self
            .rings
            .iter()
            .take(3)
            .map(|r| {
                r.iter()
                    .take(12)
                    .map(|&(x, y, z)| DVec3::new(x as f64, y as f64, z as f64))
                    .collect()
            })
            .collect();
        let p = SphericalPolygon::new(rings).ok()?;
        Some(if self.complement { p.complement() } else { p })
    }
}

/// Panics unless `p` passes full validation again (the output of every operation must be a
/// valid input to every operation).
pub fn assert_valid(p: &SphericalPolygon, what: &str) {
    if p.is_full() {
        return;
    }
    let rings = p.rings().map(<[DVec3]>::to_vec).collect();
    if let Err(e) = SphericalPolygon::new(rings) {
        panic!("{what}: invalid result ({e}): {p:?}");
    }
    let w = p.solid_angle();
    assert!((0.0..=4.0 * PI).contains(&w), "{what}: solid angle {w} out of range");
}

/// Clipping: valid output, partition of the solid angle, idempotence.
pub fn clip(p: &SphericalPolygon, n: DVec3) {
    let (up, down) = (p.clip_to_hemisphere(n), p.clip_to_hemisphere(-n));
    assert_valid(&up, "clip(n)");
    assert_valid(&down, "clip(-n)");
    let (wu, wd, w) = (up.solid_angle(), down.solid_angle(), p.solid_angle());
    assert!((wu + wd - w).abs() <= 1e-9 * 4.0 * PI, "clip partition: {wu} + {wd} vs {w}\nP = {p:?}\nn = {n}");
    let twice = up.clip_to_hemisphere(n).solid_angle();
    assert!((twice - wu).abs() <= 1e-12, "clip not idempotent: {twice} vs {wu}\nP = {p:?}\nn = {n}");
}

/// Set operations: valid outputs and the solid-angle identities.
pub fn boolean(a: &SphericalPolygon, b: &SphericalPolygon) {
    let run = |op| {
        let r = a
            .boolean(b, op)
            .unwrap_or_else(|e| panic!("{op:?} failed on valid input: {e}\nA = {a:?}\nB = {b:?}"));
        assert_valid(&r, "boolean");
        r.solid_angle()
    };
    let (i, u, d, x) = (
        run(BoolOp::Intersection),
        run(BoolOp::Union),
        run(BoolOp::Difference),
        run(BoolOp::Xor),
    );
    let (wa, wb) = (a.solid_angle(), b.solid_angle());
    let tol = 1e-9 * 4.0 * PI;
    assert!((d + i - wa).abs() <= tol, "A-B + AnB = A: {d} + {i} vs {wa}\nA = {a:?}\nB = {b:?}");
    assert!((u - (wa + wb - i)).abs() <= tol, "AuB: {u} vs {wa} + {wb} - {i}\nA = {a:?}\nB = {b:?}");
    assert!((x - (u - i)).abs() <= tol, "xor: {x} vs {u} - {i}\nA = {a:?}\nB = {b:?}");
}
