//! Fuzz `SphericalPolygon::triangulate` and `PolygonSampler`: on every valid polygon the
//! triangles pass the shared invariant checker (exact orientation, solid angles within 1e-12
//! relative, exact coverage of a lattice of directions and of probes around every vertex and
//! edge), and samples land in the polygon. Three families of input: polygons of small integer
//! directions (several rings, holes, pinches, complements; exact degeneracies are frequent),
//! the tiny family of `sphere_common::Tiny` (rings 1e-10..1e-6 rad across, pairs near each other
//! or near each other's antipode, their set operations and complements) and the horizon family
//! of `sphere_common::Horizon` (a vertex 1e-16..1e-9 off a great circle, and the clips there).
//!
//! `GeomError::Undecidable` fails the target: the triangulation census
//! (`tests/sphere_triangulate_census.rs`) finds no give-up on any of these families, so one here
//! is a finding. Any other error on valid input fails too.
//!
//! Run: `RUSTC_BOOTSTRAP=1 cargo fuzz run sphere_triangulate -- -max_total_time=300` (from the
//! crate root).
#![no_main]

#[path = "sphere_common/mod.rs"]
#[allow(dead_code)] // the clip and boolean drivers of the other targets
mod common;
#[path = "../../tests/sphere_triangulate_check/mod.rs"]
mod check;

use arealight::glam::DVec2;
use arealight::sphere::{PolygonSampler, SphericalPolygon};
use libfuzzer_sys::arbitrary::{self, Arbitrary};
use libfuzzer_sys::fuzz_target;

#[derive(Debug, Arbitrary)]
enum Case {
    Integer(common::Poly),
    Tiny(common::Tiny),
    Horizon(common::Horizon),
}

fn check(p: &SphericalPolygon) {
    let tris = match p.triangulate() {
        Ok(tris) => tris,
        Err(e) => panic!("triangulate failed on valid input: {e}\nP = {p:?}"),
    };
    let mut dirs = check::fibonacci(600);
    dirs.extend(check::near_features(p));
    if let Err(e) = check::check(p, &tris, &dirs) {
        panic!("{e}\nP = {p:?}");
    }
    if tris.is_empty() {
        return;
    }
    let s = PolygonSampler::new(p).unwrap_or_else(|e| panic!("sampler: {e}\nP = {p:?}"));
    let edges: Vec<_> = p
        .rings()
        .flat_map(|r| (0..r.len()).map(move |i| (r[i], r[(i + 1) % r.len()])))
        .collect();
    // Samples within 1e-9 of the polygon's size (plus the rounding of their coordinates) of an
    // edge are not decided.
    let size = edges.iter().map(|(a, b)| (*a - *b).length()).fold(0.0f64, f64::max).min(1.0);
    for k in 0..16 {
        let u = DVec2::new((k % 4) as f64 / 4.0 + 0.1, (k / 4) as f64 / 4.0 + 0.1);
        let d = s.sample(u);
        let near = edges.iter().any(|&(a, b)| {
            let n = a.cross(b - a).normalize();
            (d - a).dot(n).abs() < 1e-9 * size + 1e-15
        });
        if !near && check::exact_contains(p, d, &edges) == Some(false) {
            panic!("sample {d} (u = {u}) outside\nP = {p:?}");
        }
    }
}

fuzz_target!(|case: Case| {
    match case {
        Case::Integer(p) => {
            if let Some(p) = p.build() {
                check(&p);
            }
        }
        Case::Tiny(t) => t.polygons().iter().for_each(check),
        Case::Horizon(h) => h.polygons().iter().for_each(check),
    }
});
