//! Fuzz `Scene::shade`: random scenes of a few primitives (quads, boxes, icospheres, frustums,
//! two-sheet meshes) on a coarse grid, so that touching, coplanar and interpenetrating objects
//! are frequent, shaded at points on, near (2^-10 to 2^-60 off) and away from their surfaces,
//! with NaN, infinities, zero, huge and tiny values anywhere: in the point, normal and view, in
//! the primitives' parameters and raw triangles (wild geometry), in the lights' radiance and in
//! the material's albedo, f0 and roughness.
//!
//! Asserted:
//! - a non-finite, zero-length or out-of-range argument is the input fault naming it
//!   (`NonFiniteArgument`, `ZeroLengthArgument`, `OutOfRange`), never a give-up;
//! - a primitive with a non-finite parameter is `NonFiniteArgument` naming that parameter, a
//!   raw mesh with a non-finite vertex `NonFinite` naming the vertex, and finite parameters never
//!   give either; a non-finite or negative radiance and a material parameter outside `[0, 1]`
//!   (NaN included) are `OutOfRange` naming the parameter;
//! - a valid query gives a finite, non-negative radiance, or `GeomError::Undecidable` (a
//!   documented give-up), never another error;
//! - the radiance is never above the unoccluded value: each light's share (`shade_per_light`) is
//!   at most its unshadowed value, which equals the light shaded in a scene of its own, and the
//!   shares add up to `Scene::shade`;
//! - no light sends more than its radiance times the material's directional albedo (the
//!   diffuse albedo plus the GGX table's, with Schlick's Fresnel).
//!
//! Run: `RUSTC_BOOTSTRAP=1 cargo fuzz run shade -- -max_total_time=600` (from the crate root).
#![no_main]

use arealight::GeomError;
use arealight::glam::DVec3;
use arealight::shade::{
    Body, ConvexPolyhedron, Light, Material, Method, Scene, ShadingFrame, TriangleMesh,
};
use libfuzzer_sys::arbitrary::{self, Arbitrary};
use libfuzzer_sys::fuzz_target;

#[path = "scene_common/mod.rs"]
mod scene_common;
use scene_common::{Grid, cuboid, icosphere, quad, sheets, size};

#[derive(Debug, Clone, Copy, Arbitrary)]
enum Prim {
    Quad(Grid, Grid, Grid),
    Cuboid(Grid, u8, u8, u8),
    Icosphere(Grid, u8),
    Frustum(Grid, Grid, u8, u8, u8),
    /// Two quads as one open, non-planar mesh (self-occluding as a light).
    Sheets(Grid, Grid, u8),
    /// A primitive from arbitrary values (NaN, infinities, zero, huge and tiny included).
    Wild(Wild),
}

/// A vector of arbitrary values.
#[derive(Debug, Clone, Copy, Arbitrary)]
struct V(Num, Num, Num);

impl V {
    fn at(self) -> DVec3 {
        DVec3::new(self.0.value(), self.1.value(), self.2.value())
    }
}

#[derive(Debug, Clone, Copy, Arbitrary)]
enum Wild {
    Quad(V, V, V),
    Cuboid(V, V),
    Icosphere(V, Num),
    Frustum(V, V, Num, Num),
    /// One triangle through `TriangleMesh::new`.
    Triangle(V, V, V),
}

/// The error a constructor must give for these named arguments: `NonFiniteArgument` naming the
/// first non-finite one, if any.
fn first_non_finite(args: &[(&'static str, DVec3)]) -> Option<GeomError> {
    args.iter()
        .find(|(_, v)| !v.is_finite())
        .map(|&(what, _)| GeomError::NonFiniteArgument { what })
}

/// Checks a constructor's result against the fault its arguments must give (`None`: the
/// arguments are finite, so whatever the constructor decides, it is not a non-finite fault).
fn checked<T>(r: Result<T, GeomError>, fault: Option<GeomError>, what: &Wild) -> Option<T> {
    match fault {
        Some(f) => {
            assert_eq!(r.err(), Some(f), "{what:?}");
            None
        }
        None => match r {
            Ok(t) => Some(t),
            Err(e) => {
                assert!(
                    !matches!(
                        e,
                        GeomError::NonFinite { .. } | GeomError::NonFiniteArgument { .. }
                    ),
                    "finite arguments reported as non-finite: {e:?}\n{what:?}"
                );
                None
            }
        },
    }
}

impl Wild {
    fn build(self) -> Option<Body> {
        let w = &self;
        Some(match self {
            Wild::Quad(c, u, v) => {
                let (c, u, v) = (c.at(), u.at(), v.at());
                let fault = first_non_finite(&[
                    ("quad center", c),
                    ("quad half-edge u", u),
                    ("quad half-edge v", v),
                ]);
                checked(TriangleMesh::quad(c, u, v), fault, w)?.into()
            }
            Wild::Cuboid(c, h) => {
                let (c, h) = (c.at(), h.at());
                let fault =
                    first_non_finite(&[("cuboid center", c), ("cuboid half extents", h)]);
                checked(ConvexPolyhedron::cuboid(c, h), fault, w)?.into()
            }
            Wild::Icosphere(c, r) => {
                let (c, r) = (c.at(), r.value());
                let fault = first_non_finite(&[
                    ("icosphere center", c),
                    ("icosphere radius (positive)", DVec3::splat(r)),
                ]);
                checked(ConvexPolyhedron::icosphere(c, r, 1), fault, w)?.into()
            }
            Wild::Frustum(b, a, r0, r1) => {
                let (b, a, r0, r1) = (b.at(), a.at(), r0.value(), r1.value());
                let fault = first_non_finite(&[
                    ("frustum base", b),
                    ("frustum axis", a),
                    ("frustum radius", DVec3::new(r0, r1, 0.0)),
                ]);
                checked(ConvexPolyhedron::frustum(b, a, r0, r1, 5), fault, w)?.into()
            }
            Wild::Triangle(a, b, c) => {
                let pts = vec![a.at(), b.at(), c.at()];
                // The vertices are checked in order: the first bad one is reported, non-finite
                // or out of range.
                let bad = pts
                    .iter()
                    .position(|p| !p.is_finite() || p.abs().max_element() > 1e100);
                let result = TriangleMesh::new(pts.clone(), vec![[0, 1, 2]]);
                match bad {
                    Some(vertex) if !pts[vertex].is_finite() => {
                        checked(result, Some(GeomError::NonFinite { ring: 0, vertex }), w)?
                    }
                    Some(_) => {
                        assert!(
                            matches!(result, Err(GeomError::OutOfRange { .. })),
                            "{w:?}: {result:?}"
                        );
                        return None;
                    }
                    None => checked(result, None, w)?,
                }
                .into()
            }
        })
    }
}

/// A light's radiance: the usual one, or arbitrary values.
#[derive(Debug, Clone, Copy, Arbitrary)]
enum Radiance {
    Usual,
    Wild(V),
}

/// The material: from bytes (always valid), or arbitrary albedo, f0 and roughness.
#[derive(Debug, Clone, Copy, Arbitrary)]
enum MaterialSpec {
    Bytes(u8, u8, u8),
    Wild(Num, Num, Num),
}

impl MaterialSpec {
    fn build(self) -> Option<Material> {
        match self {
            MaterialSpec::Bytes(al, f0, r) => Some(
                Material::new(
                    DVec3::splat(f64::from(al) / 255.0),
                    DVec3::splat(f64::from(f0 % 128) / 255.0),
                    f64::from(r) / 255.0,
                )
                .unwrap(),
            ),
            MaterialSpec::Wild(al, f0, r) => {
                let (al, f0, r) = (al.value(), f0.value(), r.value());
                let result = Material::new(DVec3::splat(al), DVec3::splat(f0), r);
                let unit = |x: f64| (0.0..=1.0).contains(&x);
                let fault = [
                    ("material albedo", al),
                    ("material f0", f0),
                    ("material roughness", r),
                ]
                .into_iter()
                .find(|&(_, x)| !unit(x));
                match fault {
                    Some((what, _)) => {
                        assert!(
                            matches!(result, Err(GeomError::OutOfRange { what: w, .. }) if w == what),
                            "{self:?}: {result:?}, expected OutOfRange naming {what}"
                        );
                        None
                    }
                    None => Some(result.unwrap()),
                }
            }
        }
    }
}

impl Prim {
    fn build(self) -> Option<Body> {
        Some(match self {
            Prim::Quad(c, u, v) => quad(c, u, v)?,
            Prim::Cuboid(c, x, y, z) => cuboid(c, x, y, z)?,
            Prim::Icosphere(c, r) => icosphere(c, r)?,
            Prim::Frustum(b, a, r0, r1, s) => ConvexPolyhedron::frustum(
                b.at(),
                a.at(),
                size(r0),
                size(r1) * f64::from(r1 % 2),
                3 + u32::from(s % 8),
            )
            .ok()?
            .into(),
            Prim::Sheets(c, d, s) => sheets(c, d, s)?,
            Prim::Wild(w) => w.build()?,
        })
    }
}

/// A value that may be anything: a grid coordinate, or a special value.
#[derive(Debug, Clone, Copy, Arbitrary)]
enum Num {
    Grid(i8),
    Nan,
    Inf(bool),
    Zero,
    Huge(bool),
    Tiny(bool),
}

impl Num {
    fn value(self) -> f64 {
        match self {
            Num::Grid(g) => g as f64 / 8.0,
            Num::Nan => f64::NAN,
            Num::Inf(s) => {
                if s {
                    f64::INFINITY
                } else {
                    f64::NEG_INFINITY
                }
            }
            Num::Zero => 0.0,
            Num::Huge(s) => {
                if s {
                    1e300
                } else {
                    -1e300
                }
            }
            Num::Tiny(s) => {
                if s {
                    1e-310
                } else {
                    -1e-310
                }
            }
        }
    }
}

#[derive(Debug, Clone, Copy, Arbitrary)]
enum PointSpec {
    /// Anywhere (special values included).
    Free(Num, Num, Num),
    /// On a triangle of an object (barycentric `u, v` in 1/16), moved along its normal by
    /// `sign * 2^-k` (`k` in 10..=60) or not at (k = 0).
    OnSurface(u8, u16, u8, u8, u8, bool),
    /// A vertex of an object.
    Vertex(u8, u16),
}

#[derive(Debug, Clone, Copy, Arbitrary)]
enum DirSpec {
    Free(Num, Num, Num),
    /// The normal of the triangle the point was put on (or +z), possibly reversed.
    Surface(bool),
}

#[derive(Debug, Arbitrary)]
struct Case {
    lights: Vec<(Prim, Radiance)>,
    occluders: Vec<Prim>,
    point: PointSpec,
    normal: DirSpec,
    view: DirSpec,
    material: MaterialSpec,
    per_triangle: bool,
}

/// The light of `body` with `radiance`, or `None` where `Light::new` must refuse it; asserts
/// the refusal's variant.
fn light(body: Body, radiance: Radiance) -> Option<Light> {
    let rgb = match radiance {
        Radiance::Usual => DVec3::new(1.0, 2.0, 0.5),
        Radiance::Wild(v) => v.at(),
    };
    let result = Light::new(body, rgb);
    if !rgb.to_array().iter().all(|c| c.is_finite() && *c >= 0.0) {
        assert!(
            matches!(
                result,
                Err(GeomError::OutOfRange {
                    what: "light radiance (non-negative, finite)",
                    ..
                })
            ),
            "radiance {rgb}: {result:?}"
        );
        return None;
    }
    match result {
        Ok(l) => Some(l),
        // Raw triangles of a wild mesh may overlap as a planar light.
        Err(GeomError::OverlappingLightTriangles { .. }) => None,
        Err(e) => panic!("radiance {rgb}: {e:?}"),
    }
}

fn dir(spec: DirSpec, surface: DVec3) -> DVec3 {
    match spec {
        DirSpec::Free(x, y, z) => DVec3::new(x.value(), y.value(), z.value()),
        DirSpec::Surface(flip) => {
            if flip {
                -surface
            } else {
                surface
            }
        }
    }
}

/// The input fault `ShadingFrame::new` must report for these arguments, if any.
fn expected_fault(x: DVec3, n: DVec3, v: DVec3) -> Option<GeomError> {
    if !x.is_finite() {
        return Some(GeomError::NonFiniteArgument {
            what: "shading point",
        });
    }
    if x.abs().max_element() > 1e100 {
        return Some(GeomError::OutOfRange {
            what: "shading point coordinate",
            value: x.abs().max_element(),
            limit: 1e100,
        });
    }
    for (d, what) in [(n, "surface normal"), (v, "view direction")] {
        if !d.is_finite() {
            return Some(GeomError::NonFiniteArgument { what });
        }
        if !(d.abs().max_element() >= f64::MIN_POSITIVE) {
            return Some(GeomError::ZeroLengthArgument { what });
        }
    }
    None
}

/// The material's directional albedo at the point's view angle: the diffuse albedo plus the
/// GGX table's albedo with Schlick's Fresnel. No light can send more than its radiance times it.
fn albedo(x: DVec3, n: DVec3, v: DVec3, m: &Material) -> DVec3 {
    let Ok(frame) = ShadingFrame::new(x, n, v) else {
        return DVec3::INFINITY;
    };
    let spec = match arealight::ltc::lookup(frame.view().z, m.alpha()) {
        Ok(look) if m.has_specular() => m
            .f0()
            .map(|f0| look.albedo * (f0 + (1.0 - f0) * look.fresnel)),
        Ok(_) => DVec3::ZERO,
        Err(_) => DVec3::INFINITY,
    };
    m.albedo() + spec
}

/// `a <= b` up to the rounding of two evaluations of one region by different decompositions
/// (the silhouette against face by face, with endpoints merged within
/// `sphere::MATCH_TOLERANCE` = 1e-9 rad along the way): relative `1e-7`. The failures this
/// target exists for are larger by orders of magnitude (the smallest seen was 0.7%).
fn close_or_below(a: f64, b: f64) -> bool {
    a <= b + 1e-7 * b.abs() + 1e-12
}

fuzz_target!(|case: Case| {
    // Every part is built (and its faults checked) before any is found missing.
    let material = case.material.build();
    let lights: Vec<Light> = case
        .lights
        .iter()
        .take(2)
        .filter_map(|&(p, r)| light(p.build()?, r))
        .collect();
    let occluders: Vec<Body> = case.occluders.iter().take(3).filter_map(|p| p.build()).collect();
    if lights.is_empty() {
        return;
    }
    let objects: Vec<&TriangleMesh> = lights
        .iter()
        .map(|l| l.shape().mesh())
        .chain(occluders.iter().map(Body::mesh))
        .collect();
    let mut surface = DVec3::Z;
    let x = match case.point {
        PointSpec::Free(a, b, c) => DVec3::new(a.value(), b.value(), c.value()),
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
    let (n, v) = (dir(case.normal, surface), dir(case.view, surface));
    let Some(material) = material else {
        return;
    };
    let method = if case.per_triangle {
        Method::PerTriangle
    } else {
        Method::Silhouette
    };
    let scene = Scene::new(lights.clone(), occluders.clone())
        .unwrap()
        .with_method(method);
    let describe = || {
        format!(
            "lights {:?}\noccluders {:?}\npoint DVec3::new({:?}, {:?}, {:?}) normal DVec3::new({:?}, {:?}, {:?}) view DVec3::new({:?}, {:?}, {:?})\nmaterial {material:?} {method:?}",
            case.lights, case.occluders, x.x, x.y, x.z, n.x, n.y, n.z, v.x, v.y, v.z
        )
    };
    let result = scene.shade(x, n, v, &material);
    if let Some(fault) = expected_fault(x, n, v) {
        assert_eq!(result, Err(fault.clone()), "{}", describe());
        assert_eq!(
            scene.shade_per_light(x, n, v, &material),
            Err(fault),
            "{}",
            describe()
        );
        return;
    }
    let total = match result {
        Ok(c) => c,
        Err(e) => {
            assert!(e.is_undecidable(), "valid query, error {e:?}\n{}", describe());
            return;
        }
    };
    assert!(
        total.is_finite() && total.min_element() >= 0.0,
        "radiance {total}\n{}",
        describe()
    );
    let parts = match scene.shade_per_light(x, n, v, &material) {
        Ok(p) => p,
        // The unoccluded regions are more work, which may give up where the visible ones did not.
        Err(e) => {
            assert!(e.is_undecidable(), "valid query, error {e:?}\n{}", describe());
            return;
        }
    };
    let sum: DVec3 = parts.iter().map(|p| p.shadowed()).sum();
    for c in 0..3 {
        assert!(
            (sum[c] - total[c]).abs() <= 1e-12 * total[c].abs() + 1e-300,
            "parts {sum} vs shade {total}\n{}",
            describe()
        );
    }
    let mut unoccluded = DVec3::ZERO;
    for (i, (part, light)) in parts.iter().zip(&lights).enumerate() {
        let alone = Scene::new(vec![light.clone()], vec![])
            .unwrap()
            .with_method(method)
            .shade(x, n, v, &material);
        let Ok(alone) = alone else {
            // The light alone gave up where the scene did not: nothing to compare.
            return;
        };
        let un = part.unshadowed();
        let most = light.radiance() * albedo(x, n, v, &material);
        for c in 0..3 {
            assert!(
                close_or_below(un[c], most[c]),
                "light {i}: unshadowed {un} above radiance times albedo {most}\n{}",
                describe()
            );
            assert!(
                (un[c] - alone[c]).abs() <= 1e-12 * alone[c].abs() + 1e-300,
                "light {i}: unshadowed {un} vs alone {alone}\n{}",
                describe()
            );
            assert!(
                close_or_below(part.shadowed()[c], un[c]),
                "light {i}: shadowed {} above unshadowed {un}\n{}",
                part.shadowed(),
                describe()
            );
        }
        unoccluded += alone;
    }
    for c in 0..3 {
        assert!(
            close_or_below(total[c], unoccluded[c]),
            "radiance {total} above the unoccluded {unoccluded}\n{}",
            describe()
        );
    }
});
