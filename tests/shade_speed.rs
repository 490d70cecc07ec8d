//! The shading fast path (`ClipVisibility::visible_pieces`, loops cut by half-spaces and
//! integrated as they are) against the spherical path (`Scene::visible_region`, spherical set
//! operations), on random scenes: every (point, light) pair where both answer must agree to
//! `1e-12` of the light's unoccluded value plus `1e-15` of its radiance, per channel.
//!
//! The reference value is recomputed here from the spherical path's region through the public
//! integrals (`clamped_cosine_integral`, `ltc_integral` with the table's lookup), independently of
//! the shading code; the fast value is `Scene::shade_light` (and `Scene::shade_in`, which must
//! give the same bits). Why relative to the unoccluded value rather than to the value itself:
//! the spherical path snaps projected vertices to `planar::SNAP_REL` (about `1.4e-14`) of the
//! projected coordinates and drops slivers below `planar::SLIVER_REL`, and the fast path's
//! signed sums cancel where blockers overlap, so both are exact to a few `1e-14` of the light's
//! whole integral, not of an umbra's last sliver.
//!
//! The scenes are built where the fast path is delicate: lights cut by the horizon (tilted
//! normals, quads reaching below the ground's level), points on or within `1e-9` of occluder
//! face planes (cubes standing on the ground, points on the planes of their sides), occluders
//! partly behind the point (through the ground), blockers that overlap each other in projection,
//! mesh occluders (quads, seen from either side), lights that block other lights, glossy
//! materials up to grazing views. The test also requires that the fast path answered for most
//! pairs, so that it cannot pass by declining.
//!
//! `SHADE_SPEED_SCENES=N` runs `N` scenes instead of the default 120 (about 24 000 pairs).

use arealight::glam::{DVec2, DVec3};
use arealight::ltc::{clamped_cosine_integral, lookup, ltc_integral};
use arealight::shade::{
    Body, ConvexPolyhedron, Light, Material, Scene, ShadeContext, ShadingFrame, TriangleMesh,
};
use arealight::visibility::Pieces;
use support::Rng;
use support::shade::view_above;

mod support;

/// A random light: a quad (tilted, sometimes reaching below the ground's level) or a convex
/// polyhedron, above the ground.
fn random_light(rng: &mut Rng) -> Body {
    let c = DVec3::new(
        rng.range(-1.0, 1.0),
        rng.range(-1.0, 1.0),
        rng.range(0.3, 3.0),
    );
    match rng.below(4) {
        0 | 1 => {
            // Facing down, tilted by up to about 80 degrees; sometimes large and low, so that
            // ground points see it cut by their horizon.
            let size = rng.range(0.1, 1.5);
            let tilt = DVec3::new(rng.range(-0.9, 0.9), rng.range(-0.9, 0.9), 0.0);
            let n = (-DVec3::Z + tilt * 2.0).normalize();
            let (u, v) = n.any_orthonormal_pair();
            let (su, sv) = (size * rng.range(0.3, 1.0), size * rng.range(0.3, 1.0));
            // `quad(c, u, v)` faces `u x v`: swap to face `n`.
            let (u, v) = if u.cross(v).dot(n) > 0.0 {
                (u, v)
            } else {
                (v, u)
            };
            TriangleMesh::quad(c, u * su, v * sv).unwrap().into()
        }
        2 => ConvexPolyhedron::cuboid(
            c,
            DVec3::new(
                rng.range(0.05, 0.5),
                rng.range(0.05, 0.5),
                rng.range(0.05, 0.5),
            ),
        )
        .unwrap()
        .into(),
        _ => ConvexPolyhedron::icosphere(c, rng.range(0.05, 0.6), rng.below(2) as u32)
            .unwrap()
            .into(),
    }
}

/// A random occluder between the ground and the light (or standing on the ground, or through
/// it): a box, an icosphere or a quad sheet.
fn random_occluder(rng: &mut Rng, light: DVec3) -> Body {
    let ground = DVec3::new(rng.range(-1.5, 1.5), rng.range(-1.5, 1.5), 0.0);
    let t = rng.range(0.15, 0.85);
    let mut c = ground.lerp(light, t);
    let h = DVec3::new(
        rng.range(0.03, 0.4),
        rng.range(0.03, 0.4),
        rng.range(0.03, 0.4),
    );
    match rng.below(5) {
        // Standing on the ground: the bottom face in the ground's plane.
        0 => {
            c.z = h.z;
            ConvexPolyhedron::cuboid(c, h).unwrap().into()
        }
        // Through the ground: partly behind every ground point's horizon.
        1 => {
            c.z = rng.range(-0.2, 0.2);
            ConvexPolyhedron::cuboid(c, h).unwrap().into()
        }
        2 => ConvexPolyhedron::icosphere(c, h.x, rng.below(2) as u32)
            .unwrap()
            .into(),
        3 => {
            let (u, v) = rng.dir().any_orthonormal_pair();
            TriangleMesh::quad(c, u * h.x, v * h.y).unwrap().into()
        }
        _ => ConvexPolyhedron::cuboid(c, h).unwrap().into(),
    }
}

/// A shading point and normal: mostly ground points, some on the plane of an occluder's face
/// (or within `1e-9` of it), some with tilted normals that put the light across the horizon.
fn random_point(rng: &mut Rng, scene: &Scene) -> (DVec3, DVec3) {
    let mut x = DVec3::new(rng.range(-2.0, 2.0), rng.range(-2.0, 2.0), 0.0);
    let mut n = DVec3::Z;
    match rng.below(6) {
        0 if !scene.occluders().is_empty() => {
            // On or next to the plane of a face of an occluder.
            let o = &scene.occluders()[rng.below(scene.occluders().len())];
            let m = o.mesh();
            let f = rng.below(m.triangle_count());
            let (a, fnormal) = (m.triangle(f)[0], m.triangle_normal(f));
            let off = [0.0, 1e-9, -1e-9, 1e-12][rng.below(4)];
            let d = fnormal.dot(x - a) - off;
            x -= fnormal * d;
            if x.z < -0.5 || x.z > 3.0 {
                x.z = 0.0;
            }
        }
        1 => {
            // A tilted surface: the horizon cuts the lights.
            n = (DVec3::Z + DVec3::new(rng.range(-2.0, 2.0), rng.range(-2.0, 2.0), 0.0))
                .normalize();
            x.z = rng.range(0.0, 1.0);
        }
        _ => {}
    }
    (x, n)
}

fn random_scene(rng: &mut Rng) -> Scene {
    let nl = if rng.below(5) == 0 { 2 } else { 1 };
    let lights: Vec<Light> = (0..nl)
        .map(|_| {
            let rgb = DVec3::new(
                rng.range(0.5, 2.0),
                rng.range(0.5, 2.0),
                rng.range(0.5, 2.0),
            );
            Light::new(random_light(rng), rgb).unwrap()
        })
        .collect();
    let target = lights[0].shape().bounding_sphere().center;
    let no = rng.below(4);
    let occluders = (0..no).map(|_| random_occluder(rng, target)).collect();
    Scene::new(lights, occluders).unwrap()
}

/// Light `i`'s radiance at the point from the spherical path's region, integrated here; and the
/// same for its unoccluded region. `None` where the spherical path gives up.
fn spherical(scene: &Scene, i: usize, f: &ShadingFrame, m: &Material) -> Option<(DVec3, DVec3)> {
    let light = &scene.lights()[i];
    let value = |pieces: Vec<arealight::sphere::SphericalPolygon>| -> Option<DVec3> {
        let d: f64 = pieces.iter().map(clamped_cosine_integral).sum();
        let mut out = m.albedo() * d;
        if m.has_specular() {
            let l = lookup(f.view().z, m.alpha()).ok()?;
            let mut s = 0.0;
            for p in &pieces {
                s += ltc_integral(p, l.m_inv).ok()?;
            }
            let f0 = m.f0();
            out += DVec3::new(
                l.specular_scale(f0.x),
                l.specular_scale(f0.y),
                l.specular_scale(f0.z),
            ) * s;
        }
        Some(out * light.radiance())
    };
    let vis = scene.visibility();
    let shadowed = value(scene.visible_region(i, f).ok()?)?;
    let unoccluded = value(arealight::visibility::Visibility::unoccluded_region(vis, i, f).ok()?)?;
    Some((shadowed, unoccluded))
}

/// The absolute part of the tolerance, in units of the light's radiance (the integrals' own
/// unit): `1e-12` of it is `1e-15`, a few ulps of a whole hemisphere's integral, which both paths
/// round to in Baum's sums of long edges (a light a sliver above a tilted horizon has an integral
/// of `1e-8` made of edge terms near 1).
const ABS_FLOOR: f64 = 1e-3;

/// Shades `x` (normal `n`, view `v`) on the fast path and compares it with the spherical path
/// to `1e-12` of the unoccluded value: whether the fast path answered (its visible pieces, with
/// `pieces` as scratch), and `(fast, spherical)` where they differ by more.
fn fast_against_spherical(
    scene: &Scene,
    x: DVec3,
    n: DVec3,
    v: DVec3,
    m: &Material,
    pieces: &mut Pieces,
) -> (bool, Option<(DVec3, DVec3)>) {
    let frame = ShadingFrame::new(x, n, v).unwrap();
    let fast = scene
        .visibility()
        .visible_pieces(0, &frame, true, pieces)
        .unwrap();
    let Some((want, unoccluded)) = spherical(scene, 0, &frame, m) else {
        return (fast, None);
    };
    let got = scene.shade(x, n, v, m).unwrap();
    let err = (got - want).abs().max_element();
    (
        fast,
        (err > 1e-12 * (unoccluded.max_element() + ABS_FLOOR)).then_some((got, want)),
    )
}

#[test]
fn fast_path_agrees_with_the_spherical_path() {
    let scenes: usize = std::env::var("SHADE_SPEED_SCENES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(120);
    let mut rng = Rng::new(15);
    let materials = [
        Material::diffuse(DVec3::new(0.8, 0.6, 0.4)).unwrap(),
        Material::new(DVec3::splat(0.5), DVec3::new(0.04, 0.5, 0.9), 0.3).unwrap(),
        Material::new(DVec3::splat(0.2), DVec3::splat(0.9), 0.02).unwrap(),
    ];
    let (mut pairs, mut fast, mut gave_up) = (0usize, 0usize, 0usize);
    let mut worst: f64 = 0.0;
    let mut failures = Vec::new();
    let mut pieces = Pieces::new();
    let mut ctx = ShadeContext::new();
    for s in 0..scenes {
        let scene = random_scene(&mut rng);
        for _ in 0..100 {
            let (x, n) = random_point(&mut rng, &scene);
            let cos_min = [0.05, 0.3][rng.below(2)];
            let v = view_above(&mut rng, n, cos_min);
            let m = &materials[rng.below(materials.len())];
            let f = ShadingFrame::new(x, n, v).unwrap();
            // Each light's fast value, summed in the order `shade_in` sums them.
            let mut total = Some(DVec3::ZERO);
            for i in 0..scene.lights().len() {
                pairs += 1;
                let took = scene
                    .visibility()
                    .visible_pieces(i, &f, true, &mut pieces)
                    .unwrap();
                fast += usize::from(took);
                let got = scene.shade_light(i, x, n, v, m);
                total = match (&got, total) {
                    (Ok(g), Some(t)) => Some(t + *g),
                    _ => None,
                };
                let Some((want, unoccluded)) = spherical(&scene, i, &f, m) else {
                    gave_up += 1;
                    continue;
                };
                let got = got.unwrap_or_else(|e| {
                    panic!("scene {s}: fast path failed where the spherical one answered: {e}")
                });
                let err = (got - want).abs().max_element();
                let scale = unoccluded.max_element();
                let radiance = scene.lights()[i].radiance().max_element();
                let rel = err / (scale + ABS_FLOOR * radiance);
                worst = worst.max(rel);
                if err > 1e-12 * (scale + ABS_FLOOR * radiance) {
                    failures.push(format!(
                        "scene {s} light {i} x {x} n {n} v {v}: fast {got} spherical {want} \
                         (unoccluded {unoccluded}, took fast path: {took})"
                    ));
                }
            }
            // The whole point through a reused context: the same bits as light by light.
            if let Some(total) = total {
                let all = scene.shade_in(&mut ctx, x, n, v, m).unwrap();
                assert_eq!(
                    all, total,
                    "scene {s}: shade_in differs from its lights' sum"
                );
            }
        }
    }
    let (traced, cut) = pieces.subtractions();
    eprintln!(
        "{pairs} pairs, {fast} on the fast path ({traced} subtractions traced, {cut} by \
         inclusion-exclusion), {gave_up} spherical give-ups, worst difference {worst:.2e} of the \
         tolerance's scale (unoccluded value + 1e-3 radiance)"
    );
    assert!(
        failures.is_empty(),
        "{} of {pairs} pairs differ:\n{}",
        failures.len(),
        failures[..failures.len().min(20)].join("\n")
    );
    // The fast path must have done the work: most pairs are light and convex or quad occluders,
    // and both ways of subtracting a blocker ran often.
    assert!(
        fast * 10 >= pairs * 7,
        "only {fast} of {pairs} pairs took the fast path"
    );
    assert!(
        traced * 100 >= pairs as u64 * 10 && cut * 100 >= pairs as u64,
        "{traced} subtractions traced, {cut} by inclusion-exclusion"
    );
}

/// Points within `1e-12` to `1e-9` of the planes of a box's side faces (and on them), under a
/// quad light and a convex light: the box's silhouette from such a point leaves out the face
/// seen within the facing tolerance of edge-on, which makes the silhouette turn back by a sliver
/// (a reflex vertex). The fast path must decline there (its half-spaces would cut a wedge out
/// along the extended edge, about `1e-10` of the light) or agree with the spherical path.
#[test]
fn points_next_to_occluder_face_planes() {
    let boxed =
        ConvexPolyhedron::cuboid(DVec3::new(-0.13, -0.9, 0.52), DVec3::new(0.2, 0.11, 0.22))
            .unwrap();
    let lights: [Body; 2] = [
        TriangleMesh::quad(
            DVec3::new(-0.26, 0.57, 2.97),
            DVec3::new(0.19, 0.05, -0.29),
            DVec3::new(-0.07, -0.45, -0.13),
        )
        .unwrap()
        .into(),
        ConvexPolyhedron::icosphere(DVec3::new(0.2, 0.3, 2.5), 0.4, 1)
            .unwrap()
            .into(),
    ];
    let m = Material::new(DVec3::splat(0.5), DVec3::splat(0.04), 0.3).unwrap();
    let mut rng = Rng::new(154);
    let (mut pairs, mut fast) = (0, 0);
    let mut failures = Vec::new();
    let mut pieces = Pieces::new();
    for light in lights {
        let scene = Scene::new(
            vec![Light::new(light, DVec3::ONE).unwrap()],
            vec![boxed.clone().into()],
        )
        .unwrap();
        let mesh = boxed.mesh();
        for _ in 0..400 {
            // A ground point moved onto (or next to) the plane of a side face.
            let f = loop {
                let f = rng.below(mesh.triangle_count());
                if mesh.triangle_normal(f).z.abs() < 0.5 {
                    break f;
                }
            };
            let (a, nf) = (mesh.triangle(f)[0], mesh.triangle_normal(f));
            let mut x = DVec3::new(rng.range(-1.0, 1.0), rng.range(-2.0, 0.5), 0.0);
            let off = [0.0, 1e-12, -1e-12, 1e-10, 1e-9][rng.below(5)];
            x -= nf * (nf.dot(x - a) - off);
            let v = view_above(&mut rng, DVec3::Z, 0.2);
            pairs += 1;
            let (answered, mismatch) =
                fast_against_spherical(&scene, x, DVec3::Z, v, &m, &mut pieces);
            fast += usize::from(answered);
            if let Some((got, want)) = mismatch {
                failures.push(format!("x {x} v {v}: fast {got} spherical {want}"));
            }
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
    assert!(
        fast * 2 >= pairs,
        "only {fast} of {pairs} took the fast path"
    );
}

/// Blockers in exact contact in projection, where the boundary tracing must not decide: two
/// boxes stacked on a shared face and two side by side, the same box twice, a box whose edges
/// project onto the quad light's edges from points on symmetry lines (the light's edge at
/// `x = 0.5`, height 2, the box's at `x = 0.25`, height 1, points at `x = 0`), and a roof of two
/// quad sheets sharing an edge, at points on exact lines and on a grid of exactly representable
/// coordinates.
#[test]
fn blockers_in_exact_contact() {
    let quad =
        TriangleMesh::quad(DVec3::new(0.0, 0.0, 2.0), DVec3::Y * 0.5, DVec3::X * 0.5).unwrap();
    let cube = |c: DVec3, h: DVec3| -> Body { ConvexPolyhedron::cuboid(c, h).unwrap().into() };
    let roof = {
        let v = vec![
            DVec3::new(-0.3, -0.25, 1.0),
            DVec3::new(0.3, -0.25, 1.0),
            DVec3::new(0.3, 0.0, 1.25),
            DVec3::new(-0.3, 0.0, 1.25),
            DVec3::new(-0.3, 0.25, 1.0),
            DVec3::new(0.3, 0.25, 1.0),
        ];
        let t = vec![[0, 1, 2], [0, 2, 3], [3, 2, 5], [3, 5, 4]];
        Body::from(TriangleMesh::new(v, t).unwrap())
    };
    let scenes: Vec<Vec<Body>> = vec![
        // Stacked on a shared face.
        vec![
            cube(DVec3::new(0.0, 0.0, 0.75), DVec3::splat(0.125)),
            cube(DVec3::new(0.0, 0.0, 1.0), DVec3::splat(0.125)),
        ],
        // Side by side, sharing a face.
        vec![
            cube(DVec3::new(-0.125, 0.0, 1.0), DVec3::splat(0.125)),
            cube(DVec3::new(0.125, 0.0, 1.0), DVec3::splat(0.125)),
        ],
        // The same box twice.
        vec![
            cube(DVec3::new(0.0, 0.125, 1.0), DVec3::splat(0.125)),
            cube(DVec3::new(0.0, 0.125, 1.0), DVec3::splat(0.125)),
        ],
        // Edges at x = +-0.25, y = +-0.25, height 1: seen from the ground's axes they project
        // onto the light's edges.
        vec![cube(
            DVec3::new(0.0, 0.0, 1.0),
            DVec3::new(0.25, 0.25, 0.125),
        )],
        vec![roof],
    ];
    let m = Material::new(DVec3::splat(0.5), DVec3::splat(0.04), 0.3).unwrap();
    let mut rng = Rng::new(99);
    let (mut pairs, mut fast) = (0, 0);
    let mut failures = Vec::new();
    let mut pieces = Pieces::new();
    for (k, occ) in scenes.into_iter().enumerate() {
        let scene = Scene::new(vec![Light::new(quad.clone(), DVec3::ONE).unwrap()], occ).unwrap();
        // Points on the axes and diagonals, and on a grid of multiples of 1/16.
        let mut points: Vec<DVec3> = (0..64)
            .map(|i| {
                let t = i as f64 / 32.0 - 1.0;
                [
                    DVec3::new(t, 0.0, 0.0),
                    DVec3::new(0.0, t, 0.0),
                    DVec3::new(t, t, 0.0),
                    DVec3::new(t, -t, 0.0),
                ][i % 4]
            })
            .collect();
        points.extend((0..64).map(|i| {
            DVec3::new(
                ((i % 8) as f64 - 4.0) / 16.0,
                ((i / 8) as f64 - 4.0) / 16.0,
                0.0,
            )
        }));
        for x in points {
            let v = view_above(&mut rng, DVec3::Z, 0.2);
            pairs += 1;
            let (answered, mismatch) =
                fast_against_spherical(&scene, x, DVec3::Z, v, &m, &mut pieces);
            fast += usize::from(answered);
            if let Some((got, want)) = mismatch {
                failures.push(format!("scene {k} x {x}: fast {got} spherical {want}"));
            }
        }
    }
    let (traced, cut) = pieces.subtractions();
    eprintln!("{pairs} pairs, {fast} fast, {traced} traced, {cut} by inclusion-exclusion");
    assert!(failures.is_empty(), "{}", failures.join("\n"));
    assert!(
        fast * 2 >= pairs,
        "only {fast} of {pairs} took the fast path"
    );
}

/// Points in the plane of a light's edge that also holds a face of each box (the plane
/// `x = s/2`, dyadic coordinates times `s`, so the plane holds them exactly), and `1e-16` to
/// `1e-9` (relative) off it, at three scales: issue 15's point 5 generalized. From the plane,
/// the light's corners have sides of a few ulps on the boxes' contour planes and the contour
/// runs straight through the vertex of the face seen edge-on, so the boundary tracing must
/// decline (`visibility/pieces.rs`); off it, the sides are tiny but not zero. Boxes on the
/// light's side of the plane (as issue 15's flat box), on the other side, and on the edge line
/// below the light, one at a time and together. The fast path must agree with the spherical
/// path to `1e-12` everywhere, and must have answered for most points.
#[test]
fn faces_in_the_plane_of_a_light_edge() {
    let materials = [
        Material::diffuse(DVec3::splat(0.7)).unwrap(),
        Material::new(DVec3::splat(0.5), DVec3::splat(0.04), 0.3).unwrap(),
    ];
    let mut rng = Rng::new(515);
    let (mut pairs, mut fast) = (0, 0);
    let mut failures = Vec::new();
    let mut pieces = Pieces::new();
    for s in [1.0 / 1024.0, 1.0, 1000.0] {
        let quad = TriangleMesh::quad(
            DVec3::new(0.0, 0.0, 2.0) * s,
            DVec3::Y * 0.5 * s,
            DVec3::X * 0.5 * s,
        )
        .unwrap();
        let cube =
            |c: DVec3, h: DVec3| -> Body { ConvexPolyhedron::cuboid(c * s, h * s).unwrap().into() };
        let boxes = [
            cube(
                DVec3::new(0.375, -0.3125, 1.375),
                DVec3::new(0.125, 0.09375, 0.0625),
            ),
            cube(
                DVec3::new(0.625, 0.25, 1.25),
                DVec3::new(0.125, 0.125, 0.0625),
            ),
            cube(
                DVec3::new(0.4375, 0.0625, 0.75),
                DVec3::new(0.0625, 0.0625, 0.125),
            ),
        ];
        let mut scenes: Vec<Vec<Body>> = boxes.iter().map(|b| vec![b.clone()]).collect();
        scenes.push(boxes.to_vec());
        for occ in scenes {
            let scene =
                Scene::new(vec![Light::new(quad.clone(), DVec3::ONE).unwrap()], occ).unwrap();
            for k in 0..160 {
                let rel = [0.0, 1e-16, -1e-16, 0.0, -1e-15, 1e-13, -1e-11, 1e-9][k % 8];
                let x = DVec3::new((0.5 + rel) * s, rng.range(-0.6, 0.6) * s, 0.0);
                let n = if k % 3 == 0 {
                    DVec3::Z
                } else {
                    DVec3::new(rng.range(-0.3, 0.3), rng.range(-0.3, 0.3), 1.0).normalize()
                };
                let v = view_above(&mut rng, n, 0.2);
                let m = &materials[k % 2];
                pairs += 1;
                let (answered, mismatch) = fast_against_spherical(&scene, x, n, v, m, &mut pieces);
                fast += usize::from(answered);
                if let Some((got, want)) = mismatch {
                    failures.push(format!("s {s} x {x} n {n}: fast {got} spherical {want}"));
                }
            }
        }
    }
    let (traced, cut) = pieces.subtractions();
    eprintln!("{pairs} pairs, {fast} fast, {traced} traced, {cut} by inclusion-exclusion");
    assert!(failures.is_empty(), "{}", failures.join("\n"));
    assert!(
        fast * 4 >= pairs * 3,
        "only {fast} of {pairs} took the fast path"
    );
}

/// Points on an occluder's surface and in a planar light's plane get the spherical path's
/// finite value (a point on a box's face: the box covers the half-space behind that face; a
/// point in the light's plane sees none of it), and invalid arguments are errors naming the
/// argument, through `shade_in` as through `shade`.
#[test]
fn points_on_surfaces_and_bad_input() {
    let quad =
        TriangleMesh::quad(DVec3::new(0.0, 0.0, 2.0), DVec3::Y * 0.5, DVec3::X * 0.5).unwrap();
    let boxed = ConvexPolyhedron::cuboid(DVec3::new(0.1, 0.0, 1.0), DVec3::splat(0.25)).unwrap();
    let scene = Scene::new(
        vec![Light::new(quad, DVec3::ONE).unwrap()],
        vec![boxed.clone().into()],
    )
    .unwrap();
    let m = Material::new(DVec3::splat(0.5), DVec3::splat(0.04), 0.3).unwrap();
    let mut ctx = ShadeContext::new();
    let mut rng = Rng::new(7);
    let mesh = boxed.mesh();
    for k in 0..200 {
        let (x, n) = if k % 4 == 3 {
            // In the light's plane, facing up or down.
            let x = DVec3::new(rng.range(-1.0, 1.0), rng.range(-1.0, 1.0), 2.0);
            (x, if k % 8 == 3 { DVec3::Z } else { -DVec3::Z })
        } else {
            support::shade::point_on_mesh(&mut rng, mesh)
        };
        let v = view_above(&mut rng, n, 0.2);
        let got = scene.shade_in(&mut ctx, x, n, v, &m).unwrap();
        assert!(got.is_finite() && got.min_element() >= 0.0, "{x}: {got}");
        let frame = ShadingFrame::new(x, n, v).unwrap();
        if let Some((want, unoccluded)) = spherical(&scene, 0, &frame, &m) {
            let err = (got - want).abs().max_element();
            assert!(
                err <= 1e-12 * (unoccluded.max_element() + ABS_FLOOR),
                "{x}: {got} vs {want}"
            );
        }
    }
    let bad = [
        (DVec3::NAN, DVec3::Z, DVec3::Z, "shading point"),
        (
            DVec3::ZERO,
            DVec3::new(f64::INFINITY, 0.0, 0.0),
            DVec3::Z,
            "surface normal",
        ),
        (DVec3::ZERO, DVec3::ZERO, DVec3::Z, "surface normal"),
        (DVec3::ZERO, DVec3::Z, DVec3::NAN, "view direction"),
    ];
    for (x, n, v, what) in bad {
        for e in [
            scene.shade_in(&mut ctx, x, n, v, &m).unwrap_err(),
            scene.shade(x, n, v, &m).unwrap_err(),
        ] {
            assert!(
                !e.is_undecidable() && e.to_string().contains(what),
                "{what}: {e}"
            );
        }
    }
}

/// The same scene at scales from `1e-60` to `1e70`, and offset far from the origin: the fast
/// path's tolerances are relative to the objects' sizes and distances, so its value must not
/// depend on the scene's scale beyond rounding, and must agree with the spherical path at every
/// scale. (Meshes of this scene cannot be built much beyond these scales: their triangles'
/// areas overflow or underflow near `1e76` and `1e-77`.)
#[test]
fn scene_scale_does_not_matter() {
    let m = Material::new(DVec3::splat(0.5), DVec3::splat(0.04), 0.3).unwrap();
    let mut rng = Rng::new(40);
    let points: Vec<(DVec3, DVec3)> = (0..40)
        .map(|_| {
            let x = DVec3::new(rng.range(-0.6, 0.8), rng.range(-0.5, 0.6), 0.0);
            (x, view_above(&mut rng, DVec3::Z, 0.2))
        })
        .collect();
    let mut reference: Vec<DVec3> = Vec::new();
    for (k, (scale, offset)) in [
        (1.0, 0.0),
        (1e40, 0.0),
        (1e-40, 0.0),
        (1e70, 0.0),
        (1e-60, 0.0),
        (1.0, 1e6),
        (1e30, 3e35),
    ]
    .into_iter()
    .enumerate()
    {
        let at = |p: DVec3| p * scale + DVec3::splat(offset);
        let quad = TriangleMesh::quad(
            at(DVec3::new(0.0, 0.0, 2.0)),
            DVec3::Y * 0.5 * scale,
            DVec3::X * 0.5 * scale,
        )
        .unwrap();
        let occ: Vec<Body> = vec![
            ConvexPolyhedron::cuboid(at(DVec3::new(0.0, 0.0, 1.0)), DVec3::splat(0.25 * scale))
                .unwrap()
                .into(),
            ConvexPolyhedron::icosphere(at(DVec3::new(0.3, 0.3, 1.4)), 0.15 * scale, 0)
                .unwrap()
                .into(),
        ];
        let scene = Scene::new(vec![Light::new(quad, DVec3::ONE).unwrap()], occ).unwrap();
        let mut ctx = ShadeContext::new();
        for (i, &(x, v)) in points.iter().enumerate() {
            let got = scene.shade_in(&mut ctx, at(x), DVec3::Z, v, &m).unwrap();
            let frame = ShadingFrame::new(at(x), DVec3::Z, v).unwrap();
            if let Some((want, unoccluded)) = spherical(&scene, 0, &frame, &m) {
                let err = (got - want).abs().max_element();
                assert!(
                    err <= 1e-12 * (unoccluded.max_element() + ABS_FLOOR),
                    "scale {scale}, offset {offset}, point {i}: {got} vs {want}"
                );
            }
            if k == 0 {
                reference.push(got);
            } else if offset == 0.0 {
                // A pure scaling changes the directions by rounding only.
                let err = (got - reference[i]).abs().max_element();
                assert!(
                    err <= 1e-13,
                    "scale {scale}, point {i}: {got} vs {}",
                    reference[i]
                );
            }
        }
        assert_eq!(ctx.spherical_lights(), 0, "scale {scale}: declined");
    }
}

/// Light `i`'s radiance at the point from the spherical path's region, integrated here, and the
/// same for the light's whole region (the tolerance's scale), both from the backend that holds
/// the light facing the point (`Scene::visible_region`, `Scene::light_region`: a two-sided light
/// seen from behind is turned around). `None` where the spherical path gives up.
fn spherical_facing(
    scene: &Scene,
    i: usize,
    f: &ShadingFrame,
    m: &Material,
) -> Option<(DVec3, DVec3)> {
    let light = &scene.lights()[i];
    let value = |pieces: Vec<arealight::sphere::SphericalPolygon>| -> Option<DVec3> {
        let d: f64 = pieces.iter().map(clamped_cosine_integral).sum();
        let l = lookup(f.view().z, m.alpha()).ok()?;
        let mut s = 0.0;
        for p in &pieces {
            s += ltc_integral(p, l.m_inv).ok()?;
        }
        let f0 = m.f0();
        let scale = DVec3::new(
            l.specular_scale(f0.x),
            l.specular_scale(f0.y),
            l.specular_scale(f0.z),
        );
        Some((m.albedo() * d + scale * s) * light.radiance())
    };
    let shadowed = value(scene.visible_region(i, f).ok()?)?;
    let whole = value(scene.light_region(i, f).ok()?)?;
    Some((shadowed, whole))
}

/// The rules of the spherical path that the fast path must follow or leave to it, each on a
/// scene built to exercise it, with the value of `Scene::shade_in` checked against the spherical
/// path's region integrated here:
///
/// - a blocker with a vertex in the plane of a light triangle is never subtracted whole (a box
///   hanging from a quad light, a flat quad beside the light in its plane, a box reaching the
///   plane of a box lamp's side face): the fast path must decline wherever such a blocker is
///   among the blockers of a point that sees some of the light;
/// - a point inside a convex light or on its surface receives nothing from it;
/// - a two-sided quad light is shaded from both sides (the turned-around backend from behind),
///   with occluders on both sides, on the fast path;
/// - an open mesh occluder large enough for a hierarchy is left to the one-pass union (the fast
///   path declines wherever it is among the blockers, as for touching blockers); a closed one
///   takes the fast path (its contour, `visibility/mesh_pieces.rs`);
/// - a light bounded by Bezier curves blocks another light by its triangulated flattening, on
///   the fast path (the light itself is flattened per point on the spherical path).
#[test]
fn main_rules_hold_on_the_fast_path() {
    let m = Material::new(DVec3::splat(0.5), DVec3::splat(0.04), 0.3).unwrap();
    let quad =
        TriangleMesh::quad(DVec3::new(0.0, 0.0, 2.0), DVec3::Y * 0.5, DVec3::X * 0.5).unwrap();
    let lamp =
        ConvexPolyhedron::cuboid(DVec3::new(0.1, 0.0, 2.2), DVec3::new(0.4, 0.3, 0.1)).unwrap();
    let cube = |c: DVec3, h: DVec3| -> Body { ConvexPolyhedron::cuboid(c, h).unwrap().into() };
    // A quad in the light's plane beside it, facing up.
    let beside =
        TriangleMesh::quad(DVec3::new(0.8, 0.0, 2.0), DVec3::X * 0.2, DVec3::Y * 0.4).unwrap();
    // 80 triangles: at least `BVH_MIN_TRIANGLES`, so it has a hierarchy.
    let ball = Body::Mesh(
        ConvexPolyhedron::icosphere(DVec3::new(-0.2, 0.1, 1.2), 0.2, 1)
            .unwrap()
            .mesh()
            .clone(),
    );
    assert!(ball.mesh().triangle_count() >= arealight::visibility::BVH_MIN_TRIANGLES);
    // The same ball with one triangle left out: open.
    let open_ball = Body::Mesh(
        TriangleMesh::new(
            ball.mesh().vertices().to_vec(),
            ball.mesh().triangles()[1..].to_vec(),
        )
        .unwrap(),
    );
    assert!(!open_ball.mesh().is_closed());
    // A Bezier-bounded light facing down under the quad: a blocker of the quad by its
    // triangulated flattening, with too few triangles for a hierarchy.
    let blob = {
        use support::bezier::Seg2;
        let p = DVec2::new;
        let outline = vec![
            Seg2::Line(p(-0.2, -0.15), p(0.2, -0.15)),
            Seg2::Cubic([p(0.2, -0.15), p(0.3, -0.05), p(0.3, 0.05), p(0.2, 0.15)]),
            Seg2::Line(p(0.2, 0.15), p(-0.2, 0.15)),
            Seg2::Line(p(-0.2, 0.15), p(-0.2, -0.15)),
        ];
        support::bezier::shape(
            &support::bezier::Plane::new(DVec3::new(-0.15, 0.1, 1.4), -DVec3::Z),
            &[outline],
        )
    };
    assert!(blob.mesh().triangle_count() < arealight::visibility::BVH_MIN_TRIANGLES);
    let blob_light = Light::new(blob, DVec3::splat(2.0)).unwrap();
    struct Case {
        name: &'static str,
        lights: Vec<Light>,
        occluders: Vec<Body>,
        /// Occluders whose presence among the blockers forbids the fast path.
        forbidden: Vec<usize>,
        /// Fewest of the 300 points whose region the fast path must give (not empty).
        fast_at_least: usize,
    }
    let cases = [
        Case {
            name: "box hanging from the quad",
            lights: vec![Light::new(quad.clone(), DVec3::ONE).unwrap()],
            occluders: vec![
                cube(DVec3::new(0.1, 0.0, 1.75), DVec3::splat(0.25)),
                cube(DVec3::new(-0.3, 0.3, 1.0), DVec3::splat(0.1)),
            ],
            forbidden: vec![0],
            fast_at_least: 0,
        },
        Case {
            name: "quad beside the light in its plane",
            lights: vec![Light::new(quad.clone(), DVec3::ONE).unwrap()],
            occluders: vec![
                beside.clone().into(),
                cube(DVec3::ZERO.with_z(1.0), DVec3::splat(0.2)),
            ],
            forbidden: vec![0],
            fast_at_least: 0,
        },
        Case {
            name: "box reaching a lamp face's plane",
            lights: vec![Light::new(lamp.clone(), DVec3::ONE).unwrap()],
            occluders: vec![cube(
                DVec3::new(0.35, -0.3, 1.35),
                DVec3::new(0.15, 0.1, 0.05),
            )],
            forbidden: vec![0],
            fast_at_least: 0,
        },
        Case {
            name: "open mesh occluder with a hierarchy",
            lights: vec![Light::new(quad.clone(), DVec3::ONE).unwrap()],
            occluders: vec![
                open_ball,
                cube(DVec3::new(0.3, -0.2, 1.0), DVec3::splat(0.1)),
            ],
            forbidden: vec![0],
            fast_at_least: 0,
        },
        Case {
            name: "closed mesh occluder with a hierarchy",
            lights: vec![Light::new(quad.clone(), DVec3::ONE).unwrap()],
            occluders: vec![ball, cube(DVec3::new(0.3, -0.2, 1.0), DVec3::splat(0.1))],
            forbidden: vec![],
            fast_at_least: 100,
        },
        Case {
            name: "Bezier light under the quad",
            lights: vec![Light::new(quad.clone(), DVec3::ONE).unwrap(), blob_light],
            occluders: vec![cube(DVec3::new(0.3, -0.2, 1.0), DVec3::splat(0.1))],
            forbidden: vec![],
            fast_at_least: 100,
        },
        Case {
            name: "two-sided quad",
            lights: vec![Light::two_sided(quad.clone(), DVec3::ONE).unwrap()],
            occluders: vec![
                cube(DVec3::new(0.1, 0.0, 1.0), DVec3::splat(0.2)),
                cube(DVec3::new(-0.1, 0.1, 3.0), DVec3::splat(0.2)),
            ],
            forbidden: vec![],
            fast_at_least: 0,
        },
    ];
    let mut rng = Rng::new(1717);
    let mut pieces = Pieces::new();
    let mut failures = Vec::new();
    for case in cases {
        let scene = Scene::new(case.lights, case.occluders).unwrap();
        let two_sided = scene.lights()[0].is_two_sided();
        let mut ctx = ShadeContext::new();
        let (mut checked, mut forbidden_seen, mut behind, mut fast_seen) = (0, 0, 0, 0);
        for k in 0..300 {
            // Ground points and, for the two-sided light, points above it looking down; points
            // on the occluders' surfaces.
            let (x, n) = if k % 3 == 2 {
                let o = &scene.occluders()[rng.below(scene.occluders().len())];
                support::shade::point_on_mesh(&mut rng, o.mesh())
            } else if two_sided && k % 2 == 1 {
                behind += 1;
                (
                    DVec3::new(rng.range(-1.5, 1.5), rng.range(-1.5, 1.5), 4.0),
                    -DVec3::Z,
                )
            } else {
                (support::shade::ground_point(&mut rng, 1.5), DVec3::Z)
            };
            let v = view_above(&mut rng, n, 0.2);
            let f = ShadingFrame::new(x, n, v).unwrap();
            let took = scene
                .visibility()
                .visible_pieces(0, &f, true, &mut pieces)
                .unwrap();
            let listed = scene
                .occluders_between(0, &f)
                .any(|o| case.forbidden.contains(&o));
            if listed {
                forbidden_seen += 1;
                // An empty region (the light below the horizon, or seen edge-on) needs no
                // blocker.
                if took && !pieces.is_empty() {
                    failures.push(format!("{}: {x} took the fast path", case.name));
                }
            }
            fast_seen += usize::from(took && !pieces.is_empty());
            // Light 0's share (the only light, except beside the Bezier light).
            let got = if scene.lights().len() == 1 {
                scene.shade_in(&mut ctx, x, n, v, &m)
            } else {
                scene.shade_light(0, x, n, v, &m)
            };
            let Some((want, whole)) = spherical_facing(&scene, 0, &f, &m) else {
                continue;
            };
            let got = got.unwrap();
            checked += 1;
            if (got - want).abs().max_element() > 1e-12 * (whole.max_element() + ABS_FLOOR) {
                failures.push(format!("{}: {x} n {n}: {got} vs {want}", case.name));
            }
        }
        assert!(
            checked >= 250,
            "{}: only {checked} points checked",
            case.name
        );
        if !case.forbidden.is_empty() {
            assert!(
                forbidden_seen >= 30,
                "{}: the blocker under test was listed for {forbidden_seen} points",
                case.name
            );
        }
        // The Bezier light and the closed mesh were blockers the fast path subtracted, not
        // declined.
        {
            assert!(
                fast_seen >= case.fast_at_least,
                "{}: {fast_seen} points on the fast path",
                case.name
            );
        }
        if two_sided {
            // Both sides took the fast path (ground points see the front, points above the back).
            assert!(
                ctx.fast_lights() as usize >= 300 - 100 - behind / 4,
                "{}: {} of 300 on the fast path",
                case.name,
                ctx.fast_lights()
            );
        }
    }
    // Inside a convex light and on its surface: nothing, on either path.
    let scene = Scene::new(vec![Light::new(lamp.clone(), DVec3::ONE).unwrap()], vec![]).unwrap();
    for k in 0..100 {
        let (x, n) = if k % 2 == 0 {
            let c = DVec3::new(0.1, 0.0, 2.2);
            (
                c + DVec3::new(
                    rng.range(-0.39, 0.39),
                    rng.range(-0.29, 0.29),
                    rng.range(-0.09, 0.09),
                ),
                rng.dir(),
            )
        } else {
            support::shade::point_on_mesh(&mut rng, lamp.mesh())
        };
        let v = view_above(&mut rng, n, 0.2);
        let got = scene.shade(x, n, v, &m).unwrap();
        if got != DVec3::ZERO {
            failures.push(format!("inside or on the lamp, {x}: {got}"));
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}
