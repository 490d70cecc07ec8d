//! Fuzz `SphericalPolygon::triangulate` and `PolygonSampler`: on every valid polygon (several
//! rings, holes, pinches, complements, from small integer directions so that exact degeneracies
//! are frequent) the triangles pass the shared invariant checker (exact orientation, solid
//! angles within 1e-12 relative, exact coverage of a lattice of directions and of probes around
//! every vertex and edge), and samples land in the polygon. `GeomError::Undecidable` is allowed
//! (it is the documented answer where rounding decides); any other error on valid input fails.
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
use arealight::sphere::PolygonSampler;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|case: common::Poly| {
    let Some(p) = case.build() else { return };
    match p.triangulate() {
        Ok(tris) => {
            let mut dirs = check::fibonacci(600);
            dirs.extend(check::near_features(&p));
            if let Err(e) = check::check(&p, &tris, &dirs) {
                panic!("{e}\nP = {p:?}");
            }
            if !tris.is_empty() {
                let s = PolygonSampler::new(&p).unwrap_or_else(|e| panic!("sampler: {e}\nP = {p:?}"));
                let edges: Vec<_> = p
                    .rings()
                    .flat_map(|r| (0..r.len()).map(move |i| (r[i], r[(i + 1) % r.len()])))
                    .collect();
                for k in 0..16 {
                    let u = DVec2::new((k % 4) as f64 / 4.0 + 0.1, (k / 4) as f64 / 4.0 + 0.1);
                    let d = s.sample(u);
                    let near = edges.iter().any(|&(a, b)| {
                        let n = a.cross(b - a).normalize();
                        (d - a).dot(n).abs() < 1e-9
                    });
                    if !near && check::exact_contains(&p, d, &edges) == Some(false) {
                        panic!("sample {d} (u = {u}) outside\nP = {p:?}");
                    }
                }
            }
        }
        Err(e) if e.is_undecidable() => {}
        Err(e) => panic!("triangulate failed on valid input: {e}\nP = {p:?}"),
    }
});
