//! Fuzz the two visibility backends against each other: tiny random scenes (one light, up to
//! three occluders from quads, boxes, icospheres, two-sheet meshes and loose triangles on a
//! coarse grid, so that touching, coplanar and interpenetrating objects are frequent), shaded
//! at points free, on or near (2^-10 to 2^-60 off) surfaces and at vertices, with free or
//! surface normals.
//!
//! Asserted, for `PluckerVisibility` per call and through a `PluckerContext` (a fresh one of
//! the case's cell size, and one kept across all inputs, so trees of earlier scenes must never
//! leak into later ones):
//! - a valid query gives regions or `GeomError::Undecidable`, never another error or a panic;
//! - every piece lies in the upper hemisphere; the visible solid angle and clamped-cosine
//!   integral are finite and at most the unoccluded ones;
//! - the paths agree with each other, and with `ClipVisibility` (face by face, where it
//!   answers), within `1e-6` of the unoccluded solid angle plus `1e-9` sr and `1e-7` of the
//!   unoccluded clamped-cosine integral (the points here sit 1e-8 to 1e-10 off surfaces, where
//!   rounding is amplified; see the comment at the tolerances);
//! - where the integrals of the two backends differ beyond that, the Monte Carlo reference
//!   (exact ray casts, same opacity model) decides: this backend must be within 5 sigma +
//!   1e-4 of it, or at least as close as the clipping backend (whose own failures are not
//!   this target's to find; the reference itself is unreliable within a nanometre of a
//!   light's plane, where its spherical-triangle sampler meets near-hemispheres, so agreement
//!   of the two backends is accepted first).
//!
//! Run: `RUSTC_BOOTSTRAP=1 cargo fuzz run visibility_backends -- -max_total_time=300` (from the
//! crate root).
#![no_main]

use std::cell::RefCell;

use arealight::glam::DVec3;
use arealight::ltc::clamped_cosine_integral;
use arealight::shade::{
    Body, Light, Material, Method, MonteCarlo, ReferenceBrdf, Scene, ShadingFrame, TriangleMesh,
};
use arealight::sphere::SphericalPolygon;
use arealight::visibility::Visibility;
use arealight::visibility::plucker::{PluckerContext, PluckerVisibility};
use libfuzzer_sys::arbitrary::{self, Arbitrary};
use libfuzzer_sys::fuzz_target;

#[path = "scene_common/mod.rs"]
mod scene_common;
use scene_common::{Grid, cuboid, icosphere, quad, sheets};

#[derive(Debug, Clone, Copy, Arbitrary)]
enum Prim {
    Quad(Grid, Grid, Grid),
    Cuboid(Grid, u8, u8, u8),
    Icosphere(Grid, u8),
    /// Two quads as one open, non-planar mesh.
    Sheets(Grid, Grid, u8),
    /// One loose triangle.
    Triangle(Grid, Grid, Grid),
}

impl Prim {
    fn build(self) -> Option<Body> {
        Some(match self {
            Prim::Quad(c, u, v) => quad(c, u, v)?,
            Prim::Cuboid(c, x, y, z) => cuboid(c, x, y, z)?,
            Prim::Icosphere(c, r) => icosphere(c, r)?,
            Prim::Sheets(c, d, s) => sheets(c, d, s)?,
            Prim::Triangle(a, b, c) => {
                TriangleMesh::new(vec![a.at(), b.at(), c.at()], vec![[0, 1, 2]])
                    .ok()?
                    .into()
            }
        })
    }
}

#[derive(Debug, Clone, Copy, Arbitrary)]
enum PointSpec {
    Free(Grid),
    /// On a triangle of an object (barycentric `u, v` in 1/16), moved along its normal by
    /// `sign * 2^-k` (`k` in 10..=60) or not at all (`k < 10`).
    OnSurface(u8, u16, u8, u8, u8, bool),
    Vertex(u8, u16),
}

#[derive(Debug, Clone, Copy, Arbitrary)]
enum DirSpec {
    Free(Grid),
    /// The normal of the triangle the point was put on (or +z), possibly reversed.
    Surface(bool),
}

#[derive(Debug, Arbitrary)]
struct Case {
    light: Prim,
    occluders: Vec<Prim>,
    point: PointSpec,
    normal: DirSpec,
    view: DirSpec,
    cell: u8,
}

/// Solid angle and clamped-cosine integral of a region; `None` when a piece leaves the upper
/// hemisphere.
fn measures(pieces: &[SphericalPolygon]) -> Option<[f64; 2]> {
    let mut out = [0.0; 2];
    for p in pieces {
        if p.rings().flatten().any(|v| v.z < -1e-12) {
            return None;
        }
        out[0] += p.solid_angle();
        out[1] += clamped_cosine_integral(p);
    }
    Some(out)
}

thread_local! {
    static CTX: RefCell<Option<PluckerContext>> = const { RefCell::new(None) };
}

fuzz_target!(|case: Case| {
    let Some(light) = case.light.build() else {
        return;
    };
    let occluders: Vec<Body> = case.occluders.iter().take(3).filter_map(|p| p.build()).collect();
    let objects: Vec<&TriangleMesh> = std::iter::once(light.mesh())
        .chain(occluders.iter().map(Body::mesh))
        .collect();
    let mut surface = DVec3::Z;
    let x = match case.point {
        PointSpec::Free(g) => g.at(),
        PointSpec::OnSurface(o, t, u, v, k, sign) => {
            let m = objects[o as usize % objects.len()];
            let t = t as usize % m.triangle_count();
            let [a, b, c] = m.triangle(t);
            let (mut u, mut v) = (f64::from(u % 17) / 16.0, f64::from(v % 17) / 16.0);
            if u + v > 1.0 {
                (u, v) = (1.0 - u, 1.0 - v);
            }
            surface = m.triangle_normal(t);
            let k = k % 61;
            let off = if k < 10 { 0.0 } else { (-f64::from(k)).exp2() };
            a + (b - a) * u + (c - a) * v + surface * if sign { off } else { -off }
        }
        PointSpec::Vertex(o, i) => {
            let m = objects[o as usize % objects.len()];
            m.vertices()[i as usize % m.vertices().len()]
        }
    };
    let dir = |spec: DirSpec| match spec {
        DirSpec::Free(g) => g.at(),
        DirSpec::Surface(flip) => {
            if flip {
                -surface
            } else {
                surface
            }
        }
    };
    let Ok(frame) = ShadingFrame::new(x, dir(case.normal), dir(case.view)) else {
        return;
    };
    let scene = Scene::new(
        vec![Light::new(light, DVec3::ONE).unwrap()],
        occluders.clone(),
    )
    .unwrap()
    .with_method(Method::PerTriangle);
    let clip = scene.visibility();
    let pl = PluckerVisibility::from_clip(clip.clone());
    let describe = || {
        format!(
            "light {:?}\noccluders {:?}\npoint DVec3::new({:?}, {:?}, {:?}) normal {} view {}",
            case.light,
            case.occluders,
            x.x,
            x.y,
            x.z,
            frame.normal(),
            frame.dir_to_world(frame.view())
        )
    };
    // A context of this case's cell size, and one kept across all inputs.
    let mut fresh = PluckerContext::new(f64::from(1 + case.cell % 64) / 32.0).unwrap();
    let regions = CTX.with(|c| {
        let mut c = c.borrow_mut();
        let kept = c.get_or_insert_with(|| PluckerContext::new(0.25).unwrap());
        [
            pl.visible_region(0, &frame),
            pl.visible_region_in(&mut fresh, 0, &frame),
            pl.visible_region_in(kept, 0, &frame),
            pl.unoccluded_region(0, &frame),
        ]
    });
    let mut m = Vec::new();
    for r in regions {
        match r {
            Ok(pieces) => match measures(&pieces) {
                Some(v) => m.push(v),
                None => panic!("a piece below the horizon\n{}", describe()),
            },
            Err(e) => {
                assert!(e.is_undecidable(), "error {e:?}\n{}", describe());
                return;
            }
        }
    }
    let (ms, mu) = (m[0], m[3]);
    // Tolerances, per measure (solid angle, clamped-cosine integral). The inputs put points 1e-8
    // to 1e-10 off surfaces: regions close to a hemisphere, whose solid angles are
    // ill-conditioned sums of triangle areas (1e-9 of the region seen between decompositions),
    // and blockers passing within 1e-8 of the point, which leave horizon slivers of the
    // rounding over that distance (1e-10 sr seen) where cuts are made differently. The
    // cosine-weighted integral is insensitive to both. `tests/visibility_plucker.rs` checks
    // 1e-9 (against the clipping backend) and 1e-12 (between the paths) on ordinary points.
    let tol = [1e-6 * mu[0] + 1e-9, 1e-7 * mu[1] + 1e-12];
    for k in 0..2 {
        assert!(
            ms[k].is_finite() && ms[k] <= mu[k] + tol[k],
            "{ms:?} > {mu:?}\n{}",
            describe()
        );
        for other in [m[1], m[2]] {
            assert!(
                (ms[k] - other[k]).abs() <= tol[k],
                "single {ms:?} through a context {other:?}\n{}",
                describe()
            );
        }
    }
    let Ok(c) = clip.visible_region(0, &frame) else {
        return;
    };
    let Some(mc) = measures(&c) else {
        return;
    };
    // The clamped-cosine integrals first: beyond tolerance the Monte Carlo reference decides
    // (below); solid angles are not arbitrated.
    if (ms[1] - mc[1]).abs() <= tol[1] {
        assert!(
            (ms[0] - mc[0]).abs() <= tol[0],
            "solid angles: plucker {ms:?} clip {mc:?} unoccluded {mu:?}\n{}",
            describe()
        );
        return;
    }
    // Disagreement: the Monte Carlo reference (diffuse, albedo 1: (1 / pi) cos over the visible
    // region, which is the clamped-cosine integral) decides.
    let white = Material::diffuse(DVec3::ONE).unwrap();
    let view = frame.dir_to_world(frame.view());
    let e = MonteCarlo::new(1 << 14, ReferenceBrdf::Ltc)
        .estimate(&scene, x, frame.normal(), view, &white, 7)
        .unwrap();
    let (mean, sigma) = (e.mean.x, e.std_error.x);
    let (ep, ec) = ((ms[1] - mean).abs(), (mc[1] - mean).abs());
    if ec > 5.0 * sigma + 1e-4 && ep <= 5.0 * sigma + 1e-4 {
        // Not this target's failure, but worth seeing when the corpus is replayed.
        eprintln!(
            "clipping backend off the reference: plucker {} clip {} reference {mean} +- {sigma}",
            ms[1], mc[1]
        );
    }
    assert!(
        ep <= 5.0 * sigma + 1e-4 || ep <= ec,
        "plucker {ms:?} clip {mc:?} unoccluded {mu:?} Monte Carlo {mean} +- {sigma}\n{}",
        describe()
    );
});
