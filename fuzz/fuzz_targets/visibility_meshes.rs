//! Fuzz the fast path for closed meshes (`visible_pieces`: closed mesh blockers and closed mesh
//! lights by their contours, resolved in one overlay, `visibility/mesh_pieces.rs`) and the
//! default path (`Scene::visible_region`, `Scene::shade`) against the per-triangle path
//! (`Method::PerTriangle`: every triangle subtracted by its own spherical boolean).
//!
//! Scenes: up to three closed meshes of 32 triangles or more (bumpy spheres, tori, extruded
//! stars) scaled, turned, tilted, possibly inside out, with vertices moved by `2^-4` to `2^-60`
//! or snapped to within `2^-k` of another vertex's height (near-coplanar pieces) and the top
//! cut flat (many coplanar triangles); a mesh may be stacked on the previous one (boxes
//! touching, star caps face to face) or merged into it (one closed mesh, interpenetrating).
//! Under a quad light, a closed mesh light, or both. Shading points on the ground, free, inside
//! a mesh's bounding box, at its centre, at vertices, and on or `2^-10` to `2^-60` off its
//! triangles; normals up, free, the surface's (either way) or grazing (perpendicular to the
//! direction to a light, tilted `2^-k` towards it).
//!
//! Asserted, per light and point:
//! - `visible_pieces` never errs (the light index is valid); the default and per-triangle
//!   paths give regions or `GeomError::Undecidable`, never another error or a panic; a
//!   give-up on one side while the other answers is accepted (it is reported as such);
//! - every solid angle is finite and non-negative (to 1e-10 sr) and at most the light's
//!   unoccluded solid angle plus the tolerance below;
//! - where they answer, the fast path's and the default path's visible solid angles equal the
//!   per-triangle path's to 1e-10 sr (the tolerance of `tests/visibility_scale.rs`,
//!   `fast_path_agrees_with_per_triangle`), plus, within about 1e-4 of a light, the rounding
//!   any evaluation inherits from forming directions there (see [`conditioning`]);
//! - the shaded value of a glossy to near-mirror material (GGX roughness 0.5, 0.2 or 0.08, views
//!   from overhead to 3 degrees above the ground) is finite, non-negative and within the
//!   tolerance below times `1 + 4 / alpha^2` (the lobe's peak) of the per-triangle path's;
//! - the shaded value of a white diffuse material (`(1 / pi)` times the clamped-cosine integral
//!   over the region times the radiance, so within `1e-10 / pi` of the reference's where the
//!   regions agree to 1e-10 sr) is finite, non-negative and within the same tolerance of the
//!   per-triangle path's.
//!
//! Run: `RUSTC_BOOTSTRAP=1 cargo fuzz run visibility_meshes -- -max_total_time=600
//! -len_control=0 -max_len=1024` (from the crate root). Without the last two flags libFuzzer
//! keeps to inputs too short to build a mesh for most of a run.
#![no_main]

use arealight::glam::DVec3;
use arealight::internals::{bumpy_sphere, extruded_star, torus};
use arealight::shade::{Body, Light, Material, Method, Scene, ShadingFrame, TriangleMesh};
use arealight::sphere::SphericalPolygon;
use arealight::visibility::{Pieces, Visibility};
use libfuzzer_sys::arbitrary::{self, Arbitrary};
use libfuzzer_sys::fuzz_target;

/// The tolerance in visible solid angle, as `fast_path_agrees_with_per_triangle`.
const TOL: f64 = 1e-10;

/// A point of a coarse grid: integers over 16.
#[derive(Debug, Clone, Copy, Arbitrary)]
struct Grid(i8, i8, i8);

impl Grid {
    fn at(self) -> DVec3 {
        DVec3::new(self.0 as f64, self.1 as f64, self.2 as f64) / 16.0
    }
}

/// A fraction in `[0, 1]` from a byte.
fn frac(b: u8) -> f64 {
    f64::from(b) / 255.0
}

/// A closed mesh of 32 triangles or more, about the origin, of radius about 1.
#[derive(Debug, Clone, Copy, Arbitrary)]
enum Kind {
    /// Subdivisions 1 or 2 (80 or 320 triangles), amplitude up to 0.6.
    Bumpy(bool, u8, u64),
    /// Tube radius over ring radius, segments around (4 to 19) and along the tube (4 to 11).
    Torus(u8, u8, u8),
    /// Tips (4 to 15), notch radius over tip radius, half height.
    Star(u8, u8, u8),
}

impl Kind {
    fn build(self) -> Option<TriangleMesh> {
        match self {
            Kind::Bumpy(two, amp, seed) => {
                bumpy_sphere(1 + u32::from(two), 0.6 * frac(amp), seed).ok()
            }
            Kind::Torus(r, around, tube) => torus(
                1.0,
                0.05 + 0.9 * frac(r),
                4 + usize::from(around % 16),
                4 + usize::from(tube % 8),
            )
            .ok(),
            Kind::Star(tips, inner, h) => extruded_star(
                4 + usize::from(tips % 12),
                0.05 + 0.9 * frac(inner),
                1.0,
                0.05 + 0.95 * frac(h),
            )
            .ok(),
        }
    }
}

/// A change of the mesh's vertices before it is placed.
#[derive(Debug, Clone, Copy, Arbitrary)]
enum Perturb {
    /// Vertex `i` moved by `2^-(4 + k % 57)` along the grid direction.
    Move(u16, Grid, u8),
    /// Vertex `i` moved to the height of vertex `j` plus `±2^-k` (`k < 10`: exactly).
    Snap(u16, u16, u8, bool),
    /// Every vertex above the height `-1 + 2 * frac` moved down to it (a flat cut).
    Cut(u8),
}

/// One closed mesh and where it goes.
#[derive(Debug, Clone, Arbitrary)]
struct Solid {
    kind: Kind,
    perturb: Vec<Perturb>,
    /// Scale `0.05 + 0.6 * frac`.
    scale: u8,
    /// Turn about `z` and tilt about `x`, in 1/256 of a turn.
    turn: u8,
    tilt: u8,
    center: Grid,
    flip: bool,
}

impl Solid {
    fn build(&self, lift: f64) -> Option<TriangleMesh> {
        let m = self.kind.build()?;
        let mut v = m.vertices().to_vec();
        let n = v.len();
        for p in self.perturb.iter().take(8) {
            match *p {
                Perturb::Move(i, d, k) => {
                    v[usize::from(i) % n] += d.at() * (-f64::from(4 + k % 57)).exp2();
                }
                Perturb::Snap(i, j, k, up) => {
                    let off = if k % 61 < 10 {
                        0.0
                    } else {
                        (-f64::from(k % 61)).exp2()
                    };
                    v[usize::from(i) % n].z = v[usize::from(j) % n].z + if up { off } else { -off };
                }
                Perturb::Cut(h) => {
                    let h = -1.0 + 2.0 * frac(h);
                    for p in &mut v {
                        p.z = p.z.min(h);
                    }
                }
            }
        }
        let s = 0.05 + 0.6 * frac(self.scale);
        let (st, ct) = (f64::from(self.turn) / 256.0 * std::f64::consts::TAU).sin_cos();
        let (sa, ca) = (f64::from(self.tilt) / 256.0 * std::f64::consts::TAU).sin_cos();
        let c = self.center.at() / 8.0 + DVec3::new(0.0, 0.0, lift);
        for p in &mut v {
            let q = DVec3::new(p.x, ca * p.y - sa * p.z, sa * p.y + ca * p.z);
            *p = DVec3::new(ct * q.x - st * q.y, st * q.x + ct * q.y, q.z) * s + c;
        }
        let t = m
            .triangles()
            .iter()
            .map(|t| if self.flip { [t[0], t[2], t[1]] } else { *t })
            .collect();
        TriangleMesh::new(v, t).ok()
    }
}

/// How an occluder relates to the one before it.
#[derive(Debug, Clone, Copy, Arbitrary)]
enum Relation {
    Free,
    /// Moved so that its lowest vertex is at the previous mesh's highest (touching), its box
    /// centred over the previous box's centre plus `offset / 64`.
    Stacked(i8, i8),
    /// Merged into the previous mesh as one closed mesh.
    Merged,
}

#[derive(Debug, Clone, Copy, Arbitrary)]
enum PointSpec {
    Ground(i8, i8),
    Free(Grid),
    /// In the bounding box of object `o` (lights first), at fractions of its extent.
    InBox(u8, u8, u8, u8),
    Center(u8),
    Vertex(u8, u16),
    /// On triangle `t` of object `o` (barycentrics in 1/16), moved along the normal by
    /// `±2^-k` (`k` in 10..=60) or not at all (`k < 10`).
    OnSurface(u8, u16, u8, u8, u8, bool),
}

#[derive(Debug, Clone, Copy, Arbitrary)]
enum NormalSpec {
    Up,
    Free(Grid),
    /// The normal of the triangle the point was put on (or +z), possibly reversed.
    Surface(bool),
    /// Perpendicular to the direction to the light's centre, tilted towards it by `2^-k`.
    Grazing(u8, u8),
}

#[derive(Debug, Arbitrary)]
struct Case {
    /// A quad light (corner offset, sizes, tilt) over the scene.
    quad: Option<(Grid, u8, u8, i8)>,
    /// A closed mesh light, 2.5 above the ground.
    mesh_light: Option<Solid>,
    occluders: Vec<(Solid, Relation)>,
    points: Vec<(PointSpec, NormalSpec, u8, u8)>,
}

fn bounds(m: &TriangleMesh) -> (DVec3, DVec3) {
    let v = m.vertices();
    v.iter()
        .fold((v[0], v[0]), |(lo, hi), &p| (lo.min(p), hi.max(p)))
}

fn moved(m: &TriangleMesh, d: DVec3) -> Option<TriangleMesh> {
    TriangleMesh::new(
        m.vertices().iter().map(|&p| p + d).collect(),
        m.triangles().to_vec(),
    )
    .ok()
}

/// The solid angle of a chain of rings of directions in the closed upper hemisphere (the fast
/// path's `Pieces`, whose winding number is the region's indicator): the signed solid angles of
/// the triangles each edge makes with the zenith (Van Oosterom and Strackee, 1983), summed.
fn chain_solid_angle<'a>(rings: impl Iterator<Item = &'a [DVec3]>) -> f64 {
    let z = DVec3::Z;
    let mut sum = 0.0;
    for ring in rings {
        for k in 0..ring.len() {
            let (a, b) = (ring[k].normalize(), ring[(k + 1) % ring.len()].normalize());
            let num = z.dot(a.cross(b));
            let den = 1.0 + z.dot(a) + a.dot(b) + b.dot(z);
            sum += 2.0 * num.atan2(den);
        }
    }
    sum
}

fn solid_angle(pieces: &[SphericalPolygon]) -> f64 {
    pieces.iter().map(SphericalPolygon::solid_angle).sum()
}

/// The extra tolerance near a light. Within `h` of the light, the elevations of its edges above
/// the point carry a relative rounding of about `eps |d| / h` from forming `d = v - x` alone
/// (whatever the algorithm), so solid angles of the light's region are only determined to about
/// `2 pi eps R / h` there (seen: 1.6e-8 sr at 3.7e-9 above a quad's edge, against a 60-digit
/// evaluation; `fast_path_near_a_quad_lights_plane` in `tests/visibility_scale.rs`). `h` is a
/// lower bound on the distance to every light triangle (its plane, or its bounding ball), `R`
/// the farthest vertex; a factor 8 over that estimate.
fn conditioning(light: &TriangleMesh, x: DVec3) -> f64 {
    let (mut h, mut r) = (f64::INFINITY, 0.0f64);
    for t in 0..light.triangle_count() {
        let [a, b, c] = light.triangle(t);
        let m = (a + b + c) / 3.0;
        let rad = (a - m).length().max((b - m).length()).max((c - m).length());
        let plane = light.triangle_normal(t).dot(x - a).abs();
        h = h.min(plane.max((x - m).length() - rad));
        r = r
            .max((a - x).length())
            .max((b - x).length())
            .max((c - x).length());
    }
    8.0 * f64::EPSILON * std::f64::consts::TAU * r / h.max(1e-300)
}

fuzz_target!(|case: Case| {
    let mut lights: Vec<TriangleMesh> = Vec::new();
    if let Some((c, a, b, t)) = case.quad {
        let t = f64::from(t) / 256.0;
        let q = TriangleMesh::quad(
            c.at() / 4.0 + DVec3::new(0.0, 0.0, 3.0),
            DVec3::Y * (0.1 + frac(a)),
            DVec3::new(t.cos(), 0.0, t.sin()) * (0.1 + frac(b)),
        );
        lights.push(q.unwrap());
    }
    if let Some(s) = &case.mesh_light {
        let Some(m) = s.build(2.5) else {
            return;
        };
        lights.push(m);
    }
    let mut occ: Vec<TriangleMesh> = Vec::new();
    for (s, rel) in case.occluders.iter().take(3) {
        let Some(m) = s.build(1.2) else {
            return;
        };
        match (*rel, occ.last_mut()) {
            (Relation::Stacked(dx, dy), Some(prev)) => {
                let ((plo, phi), (lo, hi)) = (bounds(prev), bounds(&m));
                let d = DVec3::new(
                    (plo.x + phi.x - lo.x - hi.x) / 2.0 + f64::from(dx) / 64.0,
                    (plo.y + phi.y - lo.y - hi.y) / 2.0 + f64::from(dy) / 64.0,
                    phi.z - lo.z,
                );
                let Some(m) = moved(&m, d) else {
                    return;
                };
                occ.push(m);
            }
            (Relation::Merged, Some(prev)) => {
                let Ok(m) = prev.merged(&m) else {
                    return;
                };
                *prev = m;
            }
            _ => occ.push(m),
        }
    }
    if lights.is_empty()
        || occ
            .iter()
            .any(|m| !m.is_closed() || m.triangle_count() < 32)
    {
        return;
    }
    let objects: Vec<TriangleMesh> = lights.iter().chain(occ.iter()).cloned().collect();
    let Ok(lights) = lights
        .into_iter()
        .map(|m| Light::new(m, DVec3::ONE))
        .collect::<Result<Vec<_>, _>>()
    else {
        return;
    };
    let Ok(scene) = Scene::new(lights, occ.into_iter().map(Body::from).collect()) else {
        return;
    };
    let reference = scene.clone().with_method(Method::PerTriangle);
    let white = Material::diffuse(DVec3::ONE).unwrap();
    let mut pieces = Pieces::new();
    for &(ps, ns, va, vb) in case.points.iter().take(4) {
        let mut surface = DVec3::Z;
        let pick = |o: u8| &objects[usize::from(o) % objects.len()];
        let x = match ps {
            PointSpec::Ground(a, b) => DVec3::new(f64::from(a), f64::from(b), 0.0) / 64.0,
            PointSpec::Free(g) => g.at() / 4.0,
            PointSpec::InBox(o, a, b, c) => {
                let (lo, hi) = bounds(pick(o));
                lo + (hi - lo) * DVec3::new(frac(a), frac(b), frac(c))
            }
            PointSpec::Center(o) => pick(o).bounding_sphere().center,
            PointSpec::Vertex(o, i) => {
                let m = pick(o);
                m.vertices()[usize::from(i) % m.vertices().len()]
            }
            PointSpec::OnSurface(o, t, u, v, k, sign) => {
                let m = pick(o);
                let t = usize::from(t) % m.triangle_count();
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
        };
        for (l, lmesh) in objects.iter().enumerate().take(scene.lights().len()) {
            let n = match ns {
                NormalSpec::Up => DVec3::Z,
                NormalSpec::Free(g) => g.at(),
                NormalSpec::Surface(flip) => {
                    if flip {
                        -surface
                    } else {
                        surface
                    }
                }
                NormalSpec::Grazing(k, a) => {
                    let Some(to) = (lmesh.bounding_sphere().center - x).try_normalize() else {
                        continue;
                    };
                    let (e1, e2) = to.any_orthonormal_pair();
                    let phi = frac(a) * std::f64::consts::TAU;
                    e1 * phi.cos() + e2 * phi.sin() + to * (-f64::from(k % 61)).exp2()
                }
            };
            let Some(n) = n.try_normalize() else {
                continue;
            };
            // A view above the tangent plane, its cosine with the normal in [0.2, 1).
            let (t, b) = n.any_orthonormal_pair();
            let cv = 0.2 + 0.79 * frac(va);
            let phi = frac(vb) * std::f64::consts::TAU;
            let v = n * cv + (t * phi.cos() + b * phi.sin()) * (1.0 - cv * cv).sqrt();
            let Ok(frame) = ShadingFrame::new(x, n, v) else {
                continue;
            };
            let describe = || {
                format!(
                    "light {l}, point DVec3::new({:?}, {:?}, {:?}) normal DVec3::new({:?}, \
                     {:?}, {:?}) view DVec3::new({:?}, {:?}, {:?})",
                    x.x, x.y, x.z, n.x, n.y, n.z, v.x, v.y, v.z
                )
            };
            let tol = TOL + conditioning(lmesh, x);
            let lit = match scene.visibility().unoccluded_region(l, &frame) {
                Ok(r) => solid_angle(&r),
                Err(e) => {
                    assert!(e.is_undecidable(), "unoccluded: {e:?}\n{}", describe());
                    continue;
                }
            };
            assert!(
                lit.is_finite() && lit >= -TOL,
                "unoccluded {lit}\n{}",
                describe()
            );
            let reference_sa = match reference.visible_region(l, &frame) {
                Ok(r) => Some(solid_angle(&r)),
                Err(e) => {
                    assert!(e.is_undecidable(), "per triangle: {e:?}\n{}", describe());
                    None
                }
            };
            let fast = match scene
                .visibility()
                .visible_pieces(l, &frame, true, &mut pieces)
            {
                Ok(true) => Some(chain_solid_angle(pieces.rings())),
                Ok(false) => None,
                Err(e) => panic!("visible_pieces: {e:?}\n{}", describe()),
            };
            let default = match scene.visible_region(l, &frame) {
                Ok(r) => Some(solid_angle(&r)),
                Err(e) => {
                    assert!(e.is_undecidable(), "default: {e:?}\n{}", describe());
                    None
                }
            };
            for (name, sa) in [
                ("fast", fast),
                ("default", default),
                ("per triangle", reference_sa),
            ] {
                if let Some(sa) = sa {
                    assert!(
                        sa.is_finite() && sa >= -TOL && sa <= lit + tol,
                        "{name}: visible {sa}, unoccluded {lit}\n{}",
                        describe()
                    );
                }
            }
            if let Some(rs) = reference_sa {
                for (name, sa) in [("fast", fast), ("default", default)] {
                    if let Some(sa) = sa {
                        assert!(
                            (sa - rs).abs() <= tol,
                            "{name} {sa}, per triangle {rs} (difference {:e}, tolerance {tol:e}), \
                             unoccluded {lit}\n{}",
                            sa - rs,
                            describe()
                        );
                    }
                }
            }
        }
        // The shaded value over all lights, where both answer (white diffuse: at most the
        // solid angle's error over pi per light).
        let shade_tol = objects[..scene.lights().len()]
            .iter()
            .fold(TOL, |t, m| t + conditioning(m, x));
        let (n, v) = (DVec3::Z, DVec3::new(0.3, 0.0, 1.0));
        let (a, b) = (
            scene.shade(x, n, v, &white),
            reference.shade(x, n, v, &white),
        );
        for r in [&a, &b] {
            match r {
                Ok(c) => assert!(
                    c.is_finite() && c.min_element() >= -TOL,
                    "shade {c} at {x:?}"
                ),
                Err(e) => assert!(e.is_undecidable(), "shade: {e:?} at {x:?}"),
            }
        }
        if let (Ok(a), Ok(b)) = (a, b) {
            assert!(
                (a - b).abs().max_element() <= shade_tol,
                "shade {a} per triangle {b} at DVec3::new({:?}, {:?}, {:?})",
                x.x,
                x.y,
                x.z
            );
        }
        // Glossy to near-mirror (GGX alpha 0.25 down to 0.0064) under a view from overhead to
        // grazing: the integrand is at most about `1 / (pi alpha^2)` (the LTC lobe's peak), so
        // where the regions agree to the solid-angle tolerance the values agree to that times
        // `1 + 4 / alpha^2` (a factor 4 of margin for the lobe's stretch at grazing views).
        let roughness = [0.5, 0.2, 0.08][usize::from(va) % 3];
        let glossy = Material::new(DVec3::splat(0.5), DVec3::splat(0.9), roughness).unwrap();
        let alpha = roughness * roughness;
        let cv = 0.05 + 0.94 * frac(vb);
        let phi = frac(va) * std::f64::consts::TAU;
        let v = DVec3::new(phi.cos(), phi.sin(), 0.0) * (1.0 - cv * cv).sqrt() + DVec3::Z * cv;
        let (a, b) = (
            scene.shade(x, n, v, &glossy),
            reference.shade(x, n, v, &glossy),
        );
        for r in [&a, &b] {
            match r {
                Ok(c) => assert!(
                    c.is_finite() && c.min_element() >= -TOL,
                    "glossy shade {c} at {x:?}"
                ),
                Err(e) => assert!(e.is_undecidable(), "glossy shade: {e:?} at {x:?}"),
            }
        }
        if let (Ok(a), Ok(b)) = (a, b) {
            let tol = shade_tol * (1.0 + 4.0 / (alpha * alpha));
            assert!(
                (a - b).abs().max_element() <= tol,
                "glossy (roughness {roughness}, view {v}) shade {a} per triangle {b} (tolerance \
                 {tol:e}) at DVec3::new({:?}, {:?}, {:?})",
                x.x,
                x.y,
                x.z
            );
        }
    }
});
