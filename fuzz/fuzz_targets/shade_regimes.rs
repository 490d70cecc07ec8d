//! Fuzz `Scene::shade` in the regimes of issue 24, with both methods on every input: a light
//! (quad, box, icosphere, two sheets) and up to three occluders among boxes, icospheres, quads
//! and sliver triangles (one vertex `1e-15..1e-9` of the length off the line of the others), on
//! a coarse grid so that touching, coplanar and interpenetrating objects are frequent; shading
//! points on the ground, on a surface (moved off it by `2^-k`, or not), on a sliver, or placed so
//! that the horizon passes within `1e-16..1e-9` (absolute, or relative to the light's size) of a
//! light vertex; views grazing (`cos_v` log-uniform in `1e-4..0.05`) or any; roughness `0..0.05`
//! or any.
//!
//! Asserted for each of `Method::Silhouette` and `Method::PerTriangle`:
//! - a valid query gives finite values or `GeomError::Undecidable`, never another error;
//! - per light, `0 <= shadowed <= unshadowed <=` the light's radiance times the material's
//!   directional albedo (the diffuse albedo plus the GGX table's, with Schlick's Fresnel), each
//!   `<=` up to a relative `1e-9`;
//!
//! and across them, where both decide, per lobe: the diffuse values within `1e-9` of the
//! unshadowed diffuse value, the specular ones within `1e-9 + 1e-9 / max(alpha, 1e-4)` of the
//! unshadowed specular value (a boundary moved by the sphere layer's `1e-9` rad resolution under
//! a lobe of width `alpha`), both plus `1e-12` of the light's maximum (the integrals' rounding
//! far in a lobe's tail) and, for a point within the facing predicate's tolerance of a face
//! plane, the change of the per-triangle value as the point moves across that band (inside it
//! the model is not unique; see `methods_disagree` in tests/shade_census.rs).
//!
//! Run: `RUSTC_BOOTSTRAP=1 cargo fuzz run shade_regimes -- -max_total_time=600` (from the crate
//! root).
#![no_main]

use arealight::GeomError;
use arealight::glam::DVec3;
use arealight::shade::{
    Body, Light, LightShading, Material, Method, Scene, ShadingFrame, TriangleMesh,
};
use arealight::solid::{FACE_TOLERANCE, Side, face_side};
use libfuzzer_sys::arbitrary::{self, Arbitrary};
use libfuzzer_sys::fuzz_target;

#[path = "scene_common/mod.rs"]
mod scene_common;
use scene_common::{Grid, cuboid, icosphere, quad, sheets};

/// A unit direction from three small integers (`+z` when they are all zero).
fn unit(d: (i8, i8, i8)) -> DVec3 {
    DVec3::new(f64::from(d.0), f64::from(d.1), f64::from(d.2))
        .try_normalize()
        .unwrap_or(DVec3::Z)
}

#[derive(Debug, Clone, Copy, Arbitrary)]
enum Prim {
    Quad(Grid, Grid, Grid),
    Cuboid(Grid, u8, u8, u8),
    Icosphere(Grid, u8),
    /// Two quads as one open, non-planar mesh.
    Sheets(Grid, Grid, u8),
    /// A sliver triangle: ends `a`, `b`, the third vertex at `t / 255` along the segment moved by
    /// `10^-(9 + e % 7)` of its length along `dir`.
    Sliver(Grid, Grid, u8, u8, (i8, i8, i8)),
}

impl Prim {
    fn build(self) -> Option<Body> {
        Some(match self {
            Prim::Quad(c, u, v) => quad(c, u, v)?,
            Prim::Cuboid(c, x, y, z) => cuboid(c, x, y, z)?,
            Prim::Icosphere(c, r) => icosphere(c, r)?,
            Prim::Sheets(c, d, s) => sheets(c, d, s)?,
            Prim::Sliver(a, b, t, e, dir) => {
                let (a, b) = (a.at(), b.at());
                let off = 10f64.powi(-9 - i32::from(e % 7)) * (b - a).length();
                let m = a.lerp(b, f64::from(t) / 255.0) + unit(dir) * off;
                TriangleMesh::new(vec![a, b, m], vec![[0, 1, 2]]).ok()?.into()
            }
        })
    }
}

#[derive(Debug, Clone, Copy, Arbitrary)]
enum PointSpec {
    /// On the ground plane `z = 0`, normal `+z`.
    Ground(i8, i8),
    /// On a triangle of an object (barycentric `u, v` in 1/16), moved along its normal by
    /// `sign * 2^-k` (`k` in 10..=60) or not at all (`k < 10`); the triangle's normal, either way.
    OnSurface(u8, u16, u8, u8, u8, bool, bool),
    /// On the ground at `(x, y) / 8`, the normal perpendicular to the direction of light vertex
    /// `vertex` (turned about it by `turn / 256` of a turn), then tilted towards it by
    /// `sign 10^-(9 + e % 8)`: absolute, or times the light's radius over the distance.
    HorizonAtVertex {
        x: i8,
        y: i8,
        vertex: u16,
        turn: u8,
        e: u8,
        below: bool,
        relative: bool,
    },
}

#[derive(Debug, Clone, Copy, Arbitrary)]
enum ViewSpec {
    /// `cos_v = 10^(-4 + 2.7 t / 65535)` (`1e-4..0.05`), azimuth `phi / 256` of a turn.
    Grazing(u16, u8),
    /// `cos_v = (1 + c) / 65536`, azimuth `phi / 256` of a turn.
    Any(u16, u8),
}

#[derive(Debug, Arbitrary)]
struct Case {
    light: Prim,
    occluders: Vec<Prim>,
    point: PointSpec,
    view: ViewSpec,
    /// Roughness `0.05 r / 255` when `near_mirror`, else `r / 255`.
    rough: u8,
    near_mirror: bool,
    albedo: u8,
    f0: u8,
}

/// The material's directional albedo at the view angle: no light sends more than its radiance
/// times it.
fn albedo_bound(frame: &ShadingFrame, m: &Material) -> DVec3 {
    let spec = if m.has_specular() {
        let look = arealight::ltc::lookup(frame.view().z, m.alpha()).unwrap();
        m.f0()
            .map(|f0| look.albedo * (f0 + (1.0 - f0) * look.fresnel))
    } else {
        DVec3::ZERO
    };
    m.albedo() + spec
}

/// `a <= b` up to a relative `1e-9` (and an absolute `1e-300`).
fn below(a: DVec3, b: DVec3) -> bool {
    below_within(a, b, DVec3::ZERO)
}

/// [`below`] with an absolute slack per channel: for a value far in a lobe's tail, the rounding
/// of its integral is relative to the lobe's peak, not to the value (a near-mirror lobe's tail
/// of 2e-10 computed two ways differs by 1e-18, 5e-9 of itself: tests/shade_regressions.rs).
fn below_within(a: DVec3, b: DVec3, slack: DVec3) -> bool {
    (0..3).all(|c| a[c] <= b[c] + 1e-9 * b[c].abs() + slack[c] + 1e-300)
}

/// The change of light 0's per-triangle value, per lobe (diffuse, specular), when `x` moves to
/// the two edges of the facing band (`0.999` of `FACE_TOLERANCE` times the mesh's radius plus
/// its distance) of each face plane `x` lies on, along that face's normal; zero outside every
/// band.
fn facing_band_spread(
    scene: &Scene,
    (x, n, v): (DVec3, DVec3, DVec3),
    m: &Material,
    at_x: &LightShading,
) -> (DVec3, DVec3) {
    let per = scene.clone().with_method(Method::PerTriangle);
    let meshes = scene
        .lights()
        .iter()
        .map(|l| l.shape().mesh())
        .chain(scene.occluders().iter().map(Body::mesh));
    let (mut diffuse, mut specular) = (DVec3::ZERO, DVec3::ZERO);
    for mesh in meshes {
        let b = mesh.bounding_sphere();
        let tol = FACE_TOLERANCE * (b.radius + (x - b.center).length());
        for f in (0..mesh.triangle_count()).filter(|&f| face_side(mesh, f, x) == Side::On) {
            let nf = mesh.triangle_normal(f);
            let s = nf.dot(x - mesh.triangle(f)[0]);
            for edge in [-0.999 * tol, 0.999 * tol] {
                if let Ok(parts) = per.shade_per_light(x + nf * (edge - s), n, v, m) {
                    diffuse = diffuse.max((parts[0].diffuse - at_x.diffuse).abs());
                    specular = specular.max((parts[0].specular - at_x.specular).abs());
                }
            }
        }
    }
    (diffuse, specular)
}

/// The boundary displacement, in radians, within which two decompositions of one region may
/// place an edge (the sphere layer's vertex-merge distance, `sphere::MATCH_TOLERANCE`).
const BOUNDARY_RESOLUTION: f64 = 1e-9;

fuzz_target!(|case: Case| {
    let Some(light) = case.light.build() else { return };
    if matches!(case.light, Prim::Sliver(..)) {
        return;
    }
    let occluders: Vec<Body> = case.occluders.iter().take(3).filter_map(|p| p.build()).collect();
    let light = Light::new(light, DVec3::new(1.0, 0.8, 0.6)).unwrap();
    let Ok(scene) = Scene::new(vec![light.clone()], occluders.clone()) else {
        return;
    };
    let objects: Vec<&TriangleMesh> = std::iter::once(light.shape().mesh())
        .chain(occluders.iter().map(Body::mesh))
        .collect();
    let (x, n) = match case.point {
        PointSpec::Ground(x, y) => (DVec3::new(f64::from(x), f64::from(y), 0.0) / 8.0, DVec3::Z),
        PointSpec::OnSurface(o, t, u, v, k, sign, flip) => {
            let m = objects[usize::from(o) % objects.len()];
            let t = usize::from(t) % m.triangle_count();
            let [a, b, c] = m.triangle(t);
            let (mut u, mut v) = (f64::from(u % 17) / 16.0, f64::from(v % 17) / 16.0);
            if u + v > 1.0 {
                (u, v) = (1.0 - u, 1.0 - v);
            }
            let nn = m.triangle_normal(t);
            let k = k % 61;
            let off = if k < 10 { 0.0 } else { (-f64::from(k)).exp2() };
            let x = a + (b - a) * u + (c - a) * v + nn * if sign { off } else { -off };
            (x, if flip { -nn } else { nn })
        }
        PointSpec::HorizonAtVertex { x, y, vertex, turn, e, below, relative } => {
            let x = DVec3::new(f64::from(x), f64::from(y), 0.0) / 8.0;
            let lm = light.shape().mesh();
            let p = lm.vertices()[usize::from(vertex) % lm.vertices().len()];
            let Some(d) = (p - x).try_normalize() else { return };
            let (t, b) = d.any_orthonormal_pair();
            let phi = f64::from(turn) / 256.0 * std::f64::consts::TAU;
            let n0 = t * phi.cos() + b * phi.sin();
            let mut eps = 10f64.powi(-9 - i32::from(e % 8));
            if relative {
                eps *= lm.bounding_sphere().radius / (p - x).length();
            }
            (x, (n0 + d * if below { -eps } else { eps }).normalize())
        }
    };
    let (t, b) = n.any_orthonormal_pair();
    let (cos_v, phi) = match case.view {
        ViewSpec::Grazing(c, phi) => (10f64.powf(-4.0 + 2.7 * f64::from(c) / 65535.0), phi),
        ViewSpec::Any(c, phi) => ((1.0 + f64::from(c)) / 65536.0, phi),
    };
    let phi = f64::from(phi) / 256.0 * std::f64::consts::TAU;
    let v = n * cos_v + (t * phi.cos() + b * phi.sin()) * (1.0 - cos_v * cos_v).sqrt();
    let roughness = if case.near_mirror {
        0.05 * f64::from(case.rough) / 255.0
    } else {
        f64::from(case.rough) / 255.0
    };
    let material = Material::new(
        DVec3::splat(f64::from(case.albedo) / 255.0),
        DVec3::splat(f64::from(case.f0) / 255.0),
        roughness,
    )
    .unwrap();
    let Ok(frame) = ShadingFrame::new(x, n, v) else {
        return;
    };
    let most = light.radiance() * albedo_bound(&frame, &material);
    let describe = || {
        format!(
            "light {:?}\noccluders {:?}\npoint DVec3::new({:?}, {:?}, {:?}) normal DVec3::new({:?}, {:?}, {:?}) view DVec3::new({:?}, {:?}, {:?})\nmaterial {material:?}",
            case.light, case.occluders, x.x, x.y, x.z, n.x, n.y, n.z, v.x, v.y, v.z
        )
    };
    let mut decided: Vec<(Method, LightShading)> = Vec::new();
    for method in [Method::Silhouette, Method::PerTriangle] {
        match scene.clone().with_method(method).shade_per_light(x, n, v, &material) {
            Ok(parts) => {
                let p = parts[0];
                let (s, u) = (p.shadowed(), p.unshadowed());
                assert!(
                    s.is_finite() && u.is_finite() && s.min_element() >= 0.0,
                    "{method:?}: shadowed {s}, unshadowed {u}\n{}",
                    describe()
                );
                assert!(
                    below_within(s, u, 1e-12 * most),
                    "{method:?}: shadowed {s} above unshadowed {u}\n{}",
                    describe()
                );
                assert!(
                    below(u, most),
                    "{method:?}: unshadowed {u} above radiance times albedo {most}\n{}",
                    describe()
                );
                decided.push((method, p));
            }
            Err(GeomError::Undecidable(_)) => {}
            Err(e) => panic!("{method:?}: valid query, error {e:?}\n{}", describe()),
        }
    }
    if let [(_, a), (_, b)] = decided[..] {
        // Per lobe: 1e-9 of its unshadowed value; for the specular lobe also what a boundary
        // moved by the sphere layer's resolution changes under a lobe of width alpha (at least
        // the table's 1e-4), about BOUNDARY_RESOLUTION / alpha of it; 1e-12 of the light's
        // maximum (the integrals' rounding, for values far in a lobe's tail); and the facing
        // band's spread.
        let floor = most * 1e-12 + 1e-300;
        let slack_d = a.unshadowed_diffuse.max(b.unshadowed_diffuse) * 1e-9 + floor;
        let slack_s = a.unshadowed_specular.max(b.unshadowed_specular)
            * (1e-9 + BOUNDARY_RESOLUTION / material.alpha().max(1e-4))
            + floor;
        let (dd, ds) = ((a.diffuse - b.diffuse).abs(), (a.specular - b.specular).abs());
        let within = |sd: DVec3, ss: DVec3| {
            (0..3).all(|c| dd[c] <= slack_d[c] + sd[c] && ds[c] <= slack_s[c] + ss[c])
        };
        if !within(DVec3::ZERO, DVec3::ZERO) {
            let (sd, ss) = facing_band_spread(&scene, (x, n, v), &material, &b);
            assert!(
                within(sd, ss),
                "Silhouette {} + {} vs PerTriangle {} + {} (diffuse + specular; unshadowed {} + {}; facing band spread {sd} + {ss})\n{}",
                a.diffuse,
                a.specular,
                b.diffuse,
                b.specular,
                a.unshadowed_diffuse,
                a.unshadowed_specular,
                describe()
            );
        }
    }
});
