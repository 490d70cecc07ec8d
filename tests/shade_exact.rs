//! Exact soft shadows where "light polygon minus every occluder's projection" is wrong: occluders
//! that straddle a light's plane, lie behind a light or pierce it, lights hiding other lights, and
//! non-convex (mesh) lights with an occluder between their sheets, closed non-convex lights
//! (a torus, a bowl) shaded from their silhouettes, and closed mesh lights that bound no solid
//! (self-intersecting, pinched), shaded per triangle. Each scene is checked on
//! hundreds of random ground points, for both methods, against the Monte Carlo reference (exact
//! ray-triangle visibility with the same opacity model: occluders, other lights and a mesh
//! light's own triangles block).
//!
//! A query may give up (`GeomError::Undecidable`, which a renderer answers by falling back) on
//! at most 1% of a scene's points; every other answer must be right.
//!
//! Confidence bound, in the style of tests/shade_mc.rs: with the LTC BRDF the analytic value and
//! the estimate are the same integral, so per point and channel `|analytic - mc| <= 4.5
//! sigma_hat + 1e-6`, with `sigma_hat` the estimator's standard error over 2048 samples per
//! light. The file makes about 10 500 such checks (9 scenes x 900, one x 600 and 24 random
//! scenes x 75; the two methods share the estimates), so the per-check level must be a
//! Bonferroni share of the family's: a normal deviate exceeds 4.5 sigma with probability 6.8e-6,
//! which keeps the chance of any false alarm in the file near 7%. (At 4 sigma, 6.3e-5 per check, about one false alarm
//! per run would be expected; one was seen, |z| = 4.05 on one channel, which 400 000 samples at
//! that point resolved to |z| < 1.3.) A point that fails is estimated once more with 16 times the
//! samples on an independent stream and must pass the same bound there: points very close to a
//! light can see a visible sliver of a few thousandths of its solid angle that no sample of 2048
//! hits (sigma_hat = 0, beyond the `1e-6` floor), which only more samples can tell from a wrong
//! region. Seeds are fixed, so the outcome is deterministic. A bias too small for any one point
//! shows in the mean first-stage z-score, which must stay within `4 / sqrt(points)`.
//!
//! Which directions the reference samples ([`LightSampling`]): the analytic silhouette method is
//! checked against face sampling (every front triangle of the light, projected: independent of
//! the visibility layer, so the light regions themselves are checked, not only occlusion); the
//! per-triangle method against sampling of its own unoccluded light regions, triangulated (the
//! default of the reference: the same exact ray tests against other objects, on a region of
//! directions the visibility layer provides), which runs the silhouette sampler through every
//! scene here. A light region wrong in the per-triangle method alone would not be seen by its
//! check; the silhouette method's check sees the regions the two methods share (mesh lights
//! are face by face in both).
//!
//! Every Monte Carlo test here fails with the naive rule (subtract every culled occluder's whole
//! projection, lights transparent to each other), which is seed 000's Alg. 1 as written.
//! The ten hand-built scenes also assert that they are scenes where the rule matters, by
//! recomputing the naive rule's diffuse integral from the public geometry API and counting the
//! points where it differs from the new visible region's by more than 2%.

use arealight::GeomError;
use arealight::glam::{DMat3, DVec3};
use arealight::internals::{
    TriangleRole, convex_silhouette, may_occlude, thesis_polyhedra, torus, triangle_polygon,
};
use arealight::ltc::clamped_cosine_integral;
use arealight::planar::BoolOp;
use arealight::shade::{
    Body, ConvexPolyhedron, Estimate, Light, LightSampling, Material, Method, MonteCarlo,
    ReferenceBrdf, Scene, ShadingFrame, TriangleMesh,
};
use arealight::solid::BoundingSphere;
use arealight::solid::{ClosedMesh, nonconvex_silhouette};
use arealight::sphere::SphericalPolygon;
use support::Rng;
use support::shade::{ground_point, point_on_mesh};

mod support;

/// The outcome of one scene: points checked, worst |z|, and the MC failures (empty on success).
struct Report {
    worst: f64,
    /// Points that needed the second stage.
    retested: usize,
    zmean: f64,
    failures: Vec<String>,
}

/// Analytic (`method`) against Monte Carlo on `count` ground points in `[-h, h]^2`.
fn run(scene: &Scene, method: Method, count: usize, h: f64, seed: u64) -> Report {
    let scene = scene.clone().with_method(method);
    let mut rng = Rng::new(seed * 100 + 11);
    let m = Material::new(DVec3::new(0.6, 0.5, 0.4), DVec3::splat(0.04), 0.45).unwrap();
    let sampling = match method {
        Method::Silhouette => LightSampling::Faces,
        _ => LightSampling::Silhouette,
    };
    let mc = MonteCarlo::new(2048, ReferenceBrdf::Ltc).with_sampling(sampling);
    let mc16 = MonteCarlo::new(16 * 2048, ReferenceBrdf::Ltc).with_sampling(sampling);
    let mut failures = Vec::new();
    let (mut retested, mut gave_up) = (0, 0);
    let mut worst: f64 = 0.0;
    let (mut zsum, mut zn) = (0.0, 0usize);
    for i in 0..count {
        let (x, n, v) = shading_point(&scene, &mut rng, i, h);
        let a = match scene.shade(x, n, v, &m) {
            Ok(a) => a,
            // A give-up is a documented answer (the renderer falls back), not a wrong value;
            // they are counted below and must stay rare. The one these scenes meet is the sphere
            // layer's horizon clip of an edge within 1e-14 of the horizon (issue 24,
            // tests/sphere_shade_regressions.rs).
            Err(e) if e.is_undecidable() => {
                eprintln!("point {i} x {x}: gave up: {e}");
                gave_up += 1;
                continue;
            }
            Err(e) => {
                failures.push(format!("point {i} x {x}: error {e}"));
                continue;
            }
        };
        if !(a.is_finite() && a.min_element() >= 0.0) {
            failures.push(format!("point {i} x {x}: radiance {a}"));
            continue;
        }
        let e = mc
            .estimate(&scene, x, n, v, &m, seed * 1_000_003 + i as u64)
            .unwrap();
        let agrees =
            |e: &Estimate, c: usize| (a[c] - e.mean[c]).abs() <= 4.5 * e.std_error[c] + 1e-6;
        for c in 0..3 {
            let (av, mv, s) = (a[c], e.mean[c], e.std_error[c]);
            if s > 0.0 {
                worst = worst.max((av - mv).abs() / s);
                if c == 1 {
                    zsum += (av - mv) / s;
                    zn += 1;
                }
            }
        }
        if (0..3).all(|c| agrees(&e, c)) {
            continue;
        }
        // Second stage, for this point only: 16 times the samples, an independent stream. A
        // visible sliver a few thousandths of the light's solid angle gets no sample of 2048
        // about half the time (then sigma_hat = 0), which the first stage cannot tell from a
        // wrong region; the second stage resolves it, and a real error only grows more
        // significant with more samples.
        retested += 1;
        let e2 = mc16
            .estimate(&scene, x, n, v, &m, !(seed * 1_000_003 + i as u64))
            .unwrap();
        for c in (0..3).filter(|&c| !agrees(&e2, c)) {
            failures.push(format!(
                "point {i} x {x} ch {c}: analytic {} mc {} +- {}, then {} +- {}",
                a[c], e.mean[c], e.std_error[c], e2.mean[c], e2.std_error[c]
            ));
        }
    }
    if gave_up * 100 > count {
        failures.push(format!("{gave_up} give-ups in {count} points"));
    }
    let zmean = zsum / zn.max(1) as f64;
    if zn > 0 && zmean.abs() > 4.0 / (zn as f64).sqrt() {
        failures.push(format!("mean z-score {zmean} over {zn} points: a bias"));
    }
    Report {
        worst,
        retested,
        zmean,
        failures,
    }
}

/// The diffuse integral (green radiance-weighted, summed over the lights) of the visible light
/// under the naive rule: each light's region minus the whole projection of every occluder that
/// the bounding-sphere culling keeps; lights never block.
fn naive_rule_diffuse(scene: &Scene, frame: &ShadingFrame) -> f64 {
    let up = DVec3::Z;
    let mut total = 0.0;
    for (i, l) in scene.lights().iter().enumerate() {
        let lb: BoundingSphere = l.shape().mesh().bounding_sphere();
        let mut blockers: Vec<SphericalPolygon> = Vec::new();
        for o in scene.occluders() {
            let ob: BoundingSphere = o.mesh().bounding_sphere();
            if !may_occlude(frame.origin(), frame.normal(), lb, ob) {
                continue;
            }
            match o {
                Body::Convex(p) => blockers.push(convex_silhouette(p, frame).unwrap()),
                other => {
                    let m = other.mesh();
                    for t in 0..m.triangle_count() {
                        if let Some(p) =
                            triangle_polygon(m, t, frame, TriangleRole::Blocker).unwrap()
                        {
                            blockers.push(p);
                        }
                    }
                }
            }
        }
        for piece in scene.light_region(i, frame).unwrap() {
            let mut vis = piece;
            for b in &blockers {
                vis = vis
                    .boolean(&b.clip_to_hemisphere(up), BoolOp::Difference)
                    .unwrap();
            }
            total += clamped_cosine_integral(&vis) * l.radiance().y;
        }
    }
    total
}

/// The same integral for the visible region the scene computes now.
fn exact_rule_diffuse(scene: &Scene, frame: &ShadingFrame) -> f64 {
    let mut total = 0.0;
    for (i, l) in scene.lights().iter().enumerate() {
        for piece in scene.visible_region(i, frame).unwrap() {
            total += clamped_cosine_integral(&piece) * l.radiance().y;
        }
    }
    total
}

/// Asserts that on at least a tenth of `count` random ground points the naive rule is off by more
/// than 2% (so that the Monte Carlo check below can tell the two apart).
fn assert_naive_rule_fails(name: &str, scene: &Scene, count: usize, h: f64, seed: u64) {
    let mut rng = Rng::new(seed * 100 + 12);
    let mut differ = 0;
    for _ in 0..count {
        let x = ground_point(&mut rng, h);
        let frame = ShadingFrame::new(x, DVec3::Z, DVec3::Z).unwrap();
        let (old, new) = (
            naive_rule_diffuse(scene, &frame),
            exact_rule_diffuse(scene, &frame),
        );
        if (old - new).abs() > 0.02 * new.abs() + 1e-9 {
            differ += 1;
        }
    }
    eprintln!("{name}: the naive rule is off by more than 2% at {differ} of {count} points");
    assert!(
        differ * 10 >= count,
        "{name}: the naive rule differs at only {differ} of {count} points"
    );
}

/// Shading point `i`: three in four on the ground square `[-h, h]^2` (normal `+z`), every fourth
/// on an occluder's surface (a random point of a random triangle, with its normal), each with a
/// random view at least about 17 degrees above the surface.
fn shading_point(scene: &Scene, rng: &mut Rng, i: usize, h: f64) -> (DVec3, DVec3, DVec3) {
    let occ = scene.occluders();
    let (x, n) = if i % 4 == 3 && !occ.is_empty() {
        point_on_mesh(rng, occ[(i / 4) % occ.len()].mesh())
    } else {
        (ground_point(rng, h), DVec3::Z)
    };
    let (t, b) = n.any_orthonormal_pair();
    let v = n * (0.3 + rng.f64()) + t * (rng.f64() - 0.5) + b * (rng.f64() - 0.5);
    (x, n, v)
}

/// Checks a scene with both methods on `count` points.
fn check(name: &str, scene: &Scene, count: usize, h: f64, seed: u64) {
    assert_naive_rule_fails(name, scene, count, h, seed);
    let mut all = Vec::new();
    for method in [Method::Silhouette, Method::PerTriangle] {
        let r = run(scene, method, count, h, seed);
        eprintln!(
            "{name} {method:?}: largest |z| {:.2}, mean z {:.3}, {} points re-estimated, {} failures",
            r.worst,
            r.zmean,
            r.retested,
            r.failures.len()
        );
        all.extend(r.failures.into_iter().map(|f| format!("{method:?} {f}")));
    }
    assert!(
        all.is_empty(),
        "{name}: {} failures:\n{}",
        all.len(),
        all.join("\n")
    );
}

fn quad(center: DVec3, half: f64, down: bool) -> TriangleMesh {
    // `quad` faces u x v: Y x X = -Z (down), X x Y = +Z (up).
    let (u, v) = if down {
        (DVec3::Y * half, DVec3::X * half)
    } else {
        (DVec3::X * half, DVec3::Y * half)
    };
    TriangleMesh::quad(center, u, v).unwrap()
}

fn cuboid(c: DVec3, h: DVec3) -> ConvexPolyhedron {
    ConvexPolyhedron::cuboid(c, h).unwrap()
}

fn light(shape: impl Into<Body>, rgb: DVec3) -> Light {
    Light::new(shape, rgb).unwrap()
}

#[test]
fn occluder_straddling_a_quad_lights_plane() {
    // A box through the plane of a downward quad light, over part of it: only its lower half can
    // hide the quad; its upper half, behind the quad, projects onto quad directions it does not
    // block.
    let scene = Scene::new(
        vec![light(
            quad(DVec3::new(0.0, 0.0, 2.5), 0.6, true),
            DVec3::new(1.0, 2.0, 3.0),
        )],
        vec![cuboid(DVec3::new(0.45, 0.1, 2.5), DVec3::new(0.3, 0.25, 0.4)).into()],
    )
    .unwrap();
    check("straddling quad", &scene, 300, 2.0, 21);
}

#[test]
fn occluder_wholly_behind_a_light() {
    // Boxes just above a downward quad light and above a cuboid light: near enough not to be
    // culled by distance, entirely behind the lights, so they hide nothing.
    let scene = Scene::new(
        vec![
            light(
                quad(DVec3::new(-0.6, 0.0, 2.0), 0.5, true),
                DVec3::new(2.0, 1.5, 1.0),
            ),
            light(
                cuboid(DVec3::new(1.0, 0.2, 2.2), DVec3::new(0.4, 0.3, 0.2)),
                DVec3::new(1.0, 1.5, 2.0),
            ),
        ],
        vec![
            cuboid(DVec3::new(-0.4, 0.1, 2.35), DVec3::new(0.3, 0.3, 0.25)).into(),
            ConvexPolyhedron::icosphere(DVec3::new(1.1, 0.1, 2.75), 0.3, 1)
                .unwrap()
                .into(),
        ],
    )
    .unwrap();
    check("behind lights", &scene, 300, 2.0, 22);
}

#[test]
fn occluders_piercing_convex_lights() {
    // A vertical rod through an icosphere light and a tilted cylinder through a cuboid light:
    // only the parts in front of each front face hide it.
    let scene = Scene::new(
        vec![
            light(
                ConvexPolyhedron::icosphere(DVec3::new(-0.8, 0.0, 2.5), 0.6, 1).unwrap(),
                DVec3::new(1.0, 1.2, 1.5),
            ),
            light(
                cuboid(DVec3::new(1.0, 0.3, 2.4), DVec3::new(0.5, 0.4, 0.3)),
                DVec3::new(1.5, 1.0, 0.8),
            ),
        ],
        vec![
            cuboid(DVec3::new(-0.6, 0.05, 2.5), DVec3::new(0.12, 0.12, 1.0)).into(),
            ConvexPolyhedron::frustum(
                DVec3::new(0.3, 0.5, 1.9),
                DVec3::new(1.3, -0.4, 1.0),
                0.12,
                0.12,
                8,
            )
            .unwrap()
            .into(),
        ],
    )
    .unwrap();
    check("piercing convex lights", &scene, 300, 2.0, 23);
}

#[test]
fn lights_hide_each_other() {
    // A downward quad light under an icosphere light, and a cuboid light beside them: from the
    // ground the quad hides part of the icosphere, and (from some points) the lights hide parts
    // of each other. A light's back is as opaque as an occluder.
    let scene = Scene::new(
        vec![
            light(
                quad(DVec3::new(0.0, 0.0, 2.0), 0.5, true),
                DVec3::new(1.0, 1.0, 2.0),
            ),
            light(
                ConvexPolyhedron::icosphere(DVec3::new(0.35, 0.15, 3.0), 0.5, 1).unwrap(),
                DVec3::new(2.0, 1.0, 0.5),
            ),
            light(
                cuboid(DVec3::new(-0.9, -0.2, 2.7), DVec3::new(0.3, 0.3, 0.3)),
                DVec3::new(0.5, 2.0, 1.0),
            ),
        ],
        vec![],
    )
    .unwrap();
    check("lights hide lights", &scene, 300, 2.0, 24);
}

#[test]
fn occluder_between_the_sheets_of_a_mesh_light() {
    // Two downward sheets as one (open, non-planar) mesh light, a box between them: it hides the
    // upper sheet, never the lower one.
    let sheets = quad(DVec3::new(-0.2, 0.0, 2.0), 0.5, true)
        .merged(&quad(DVec3::new(0.4, 0.1, 3.0), 0.6, true))
        .unwrap();
    assert!(!sheets.is_planar() && !sheets.is_closed());
    let scene = Scene::new(
        vec![light(sheets, DVec3::new(1.0, 2.0, 1.5))],
        vec![cuboid(DVec3::new(0.5, 0.0, 2.5), DVec3::new(0.25, 0.25, 0.2)).into()],
    )
    .unwrap();
    check("sheets with occluder", &scene, 300, 2.0, 25);
}

#[test]
fn mesh_light_showing_its_back_hides_itself() {
    // The lower sheet turned up: the ground sees its back, which emits nothing and hides the
    // upper sheet behind it; the box between them hides the upper sheet too.
    let sheets = quad(DVec3::new(-0.2, 0.0, 2.0), 0.5, false)
        .merged(&quad(DVec3::new(0.4, 0.1, 3.0), 0.6, true))
        .unwrap();
    let scene = Scene::new(
        vec![light(sheets, DVec3::new(1.0, 2.0, 1.5))],
        vec![cuboid(DVec3::new(0.5, 0.0, 2.5), DVec3::new(0.25, 0.25, 0.2)).into()],
    )
    .unwrap();
    check("back sheet with occluder", &scene, 300, 2.0, 26);
}

#[test]
fn occluder_in_the_gap_of_a_closed_non_convex_light() {
    // Two boxes as one closed, non-convex light with an occluder in the gap between them: it
    // hides the upper box, never the lower one, and the lower box hides part of the upper one.
    let boxes = cuboid(DVec3::new(-0.3, 0.0, 2.0), DVec3::new(0.5, 0.4, 0.15))
        .mesh()
        .merged(cuboid(DVec3::new(0.4, 0.1, 3.0), DVec3::new(0.5, 0.5, 0.15)).mesh())
        .unwrap();
    assert!(boxes.is_closed());
    let scene = Scene::new(
        vec![light(boxes, DVec3::new(1.5, 1.0, 2.0))],
        vec![cuboid(DVec3::new(0.45, 0.0, 2.5), DVec3::new(0.25, 0.25, 0.2)).into()],
    )
    .unwrap();
    check("closed two-box light with occluder", &scene, 300, 2.0, 27);
}

/// `mesh` scaled by `s`, rotated by `rot` and moved to `at`.
fn moved(mesh: &TriangleMesh, s: f64, rot: DMat3, at: DVec3) -> TriangleMesh {
    TriangleMesh::new(
        mesh.vertices()
            .iter()
            .map(|&v| rot * (v * s) + at)
            .collect(),
        mesh.triangles().to_vec(),
    )
    .unwrap()
}

/// A tilted torus light above a bowl light whose cavity faces the ground, and a box: closed
/// non-convex lights, which hide parts of themselves and of each other.
fn non_convex_lights_scene() -> Scene {
    let torus = moved(
        &torus(0.6, 0.2, 12, 6).unwrap(),
        1.0,
        DMat3::from_rotation_x(0.6),
        DVec3::new(-0.3, 0.1, 2.9),
    );
    let bowl = thesis_polyhedra()
        .unwrap()
        .into_iter()
        .find(|(n, _)| *n == "bowl")
        .unwrap()
        .1;
    let bowl = moved(
        &bowl,
        0.4,
        DMat3::from_rotation_y(2.6),
        DVec3::new(0.3, -0.2, 1.9),
    );
    Scene::new(
        vec![
            light(torus, DVec3::new(1.0, 2.0, 3.0)),
            light(bowl, DVec3::new(2.5, 1.5, 1.0)),
        ],
        vec![cuboid(DVec3::new(-1.0, 0.6, 1.2), DVec3::new(0.3, 0.2, 0.25)).into()],
    )
    .unwrap()
}

#[test]
fn non_convex_lights_are_shaded_from_their_silhouettes() {
    // The scene shades each closed non-convex light from its silhouette, one polygon: its
    // region is exactly the silhouette clipped to the upper hemisphere, wherever the silhouette
    // is decided (checked on the same ground points as below), and it agrees with the Monte
    // Carlo reference, which sees the lights' self-occlusion by ray casting. The naive rule
    // fails here because the lights hide parts of each other.
    let scene = non_convex_lights_scene();
    let mut rng = Rng::new(2915);
    let mut from_silhouette = 0;
    for _ in 0..200 {
        let x = DVec3::new(4.0 * rng.f64() - 2.0, 4.0 * rng.f64() - 2.0, 0.0);
        let frame = ShadingFrame::new(x, DVec3::Z, DVec3::new(0.3, 0.1, 1.0)).unwrap();
        for (i, l) in scene.lights().iter().enumerate() {
            let Body::Mesh(m) = l.shape() else {
                panic!("mesh lights")
            };
            let solid = ClosedMesh::new(m.clone()).unwrap();
            let Ok(sil) = nonconvex_silhouette(&solid, &frame) else {
                continue;
            };
            let upper = sil.clip_to_hemisphere(DVec3::Z);
            let region = scene.light_region(i, &frame).unwrap();
            let expect: Vec<SphericalPolygon> = if upper.is_empty() {
                vec![]
            } else {
                vec![upper]
            };
            assert_eq!(region, expect, "light {i} x {x}");
            from_silhouette += 1;
        }
    }
    assert!(from_silhouette >= 390, "{from_silhouette}");
    check("non-convex lights", &scene, 200, 2.0, 29);
}

/// Two cuboids as one mesh, the second's corner `weld` (a vertex position of the first) taking
/// the first's vertex index: a pinch there; `None` merges them without welding.
fn two_boxes(a: (DVec3, DVec3), b: (DVec3, DVec3), weld: Option<DVec3>) -> TriangleMesh {
    let (ma, mb) = (
        cuboid(a.0, a.1).mesh().clone(),
        cuboid(b.0, b.1).mesh().clone(),
    );
    let Some(p) = weld else {
        return ma.merged(&mb).unwrap();
    };
    let ia = ma.vertices().iter().position(|&v| v == p).unwrap() as u32;
    let ib = mb.vertices().iter().position(|&v| v == p).unwrap() as u32;
    let n = ma.vertices().len() as u32;
    let mut verts = ma.vertices().to_vec();
    verts.extend_from_slice(mb.vertices());
    let mut tris = ma.triangles().to_vec();
    tris.extend(
        mb.triangles()
            .iter()
            .map(|t| t.map(|i| if i == ib { ia } else { i + n })),
    );
    TriangleMesh::new(verts, tris).unwrap()
}

/// Closed mesh lights that do not bound a solid: two interpenetrating boxes as one mesh
/// (self-intersecting) and two boxes sharing a corner vertex (pinched), with a post through the
/// first from below to above (so that the naive rule, which subtracts the whole post, is wrong
/// where the post is inside or behind the light).
fn bad_closed_lights_scene() -> Scene {
    let crossing = two_boxes(
        (DVec3::new(-0.6, 0.0, 2.3), DVec3::new(0.4, 0.3, 0.2)),
        (DVec3::new(-0.35, 0.2, 2.5), DVec3::new(0.25, 0.35, 0.3)),
        None,
    );
    // Coordinates exact in binary, so that the corners coincide exactly.
    let corner = DVec3::new(0.75, 0.0, 2.5);
    let pinched = two_boxes(
        (DVec3::new(0.5, -0.25, 2.25), DVec3::splat(0.25)),
        (DVec3::new(1.0, 0.25, 2.75), DVec3::splat(0.25)),
        Some(corner),
    );
    Scene::new(
        vec![
            light(crossing, DVec3::new(1.0, 2.0, 3.0)),
            light(pinched, DVec3::new(2.5, 1.5, 1.0)),
        ],
        vec![cuboid(DVec3::new(-0.5, -0.1, 2.4), DVec3::new(0.08, 0.08, 0.6)).into()],
    )
    .unwrap()
}

#[test]
fn self_intersecting_and_pinched_lights_are_shaded_per_triangle() {
    // Closed meshes that are not solids are named as such by the solid layer, so the scene
    // shades them by the per-triangle method (the union of their front triangles) with either
    // method, and that agrees with the Monte Carlo reference, whose rays meet the first
    // triangle they hit (seen from outside always a front one: a ray enters one box or the
    // other first).
    let scene = bad_closed_lights_scene();
    let meshes: Vec<TriangleMesh> = scene
        .lights()
        .iter()
        .map(|l| l.shape().mesh().clone())
        .collect();
    assert!(meshes.iter().all(|m| m.is_closed() && !m.is_planar()));
    let crossing = ClosedMesh::new(meshes[0].clone());
    assert!(
        matches!(crossing, Err(GeomError::SelfIntersectingMesh { triangle, other })
            if triangle < 12 && other >= 12),
        "{crossing:?}"
    );
    let pinched = ClosedMesh::new(meshes[1].clone());
    assert!(
        matches!(pinched, Err(GeomError::NonManifoldVertex { vertex, .. })
            if meshes[1].vertices()[vertex] == DVec3::new(0.75, 0.0, 2.5)),
        "{pinched:?}"
    );
    // Same regions with both methods: the union of the front triangles' projections, clipped
    // to the upper hemisphere (here a single polygon wherever the light is seen).
    let per_triangle = scene.clone().with_method(Method::PerTriangle);
    let mut rng = Rng::new(4117);
    let mut seen = 0;
    for _ in 0..100 {
        let x = ground_point(&mut rng, 2.0);
        let frame = ShadingFrame::new(x, DVec3::Z, DVec3::new(0.3, 0.1, 1.0)).unwrap();
        for (i, m) in meshes.iter().enumerate() {
            let region = scene.light_region(i, &frame).unwrap();
            assert_eq!(
                region,
                per_triangle.light_region(i, &frame).unwrap(),
                "{i} {x}"
            );
            let mut union = SphericalPolygon::empty();
            for t in 0..m.triangle_count() {
                if let Some(p) = triangle_polygon(m, t, &frame, TriangleRole::Emitter).unwrap() {
                    union = union.boolean(&p, BoolOp::Union).unwrap();
                }
            }
            let union = union.clip_to_hemisphere(DVec3::Z);
            let area: f64 = region.iter().map(SphericalPolygon::solid_angle).sum();
            assert!(
                (area - union.solid_angle()).abs() <= 1e-12,
                "{i} {x}: {area}"
            );
            seen += usize::from(!region.is_empty());
        }
    }
    assert!(seen >= 150, "{seen}");
    check("self-intersecting and pinched lights", &scene, 300, 2.0, 31);
}

#[test]
fn occluders_touching_lights() {
    // Contacts, where the blocker and the light share points of the light's plane:
    // - a box hanging from a downward quad light, its top face in the quad's plane (it hides
    //   what it covers: rays reach the contact only through the box);
    // - a box standing on the back of the same quad (it hides nothing);
    // - a box beside a cuboid light, sharing the plane of its bottom face and overlapping it
    //   sideways (it hides part of the side faces, nothing of the bottom face).
    let scene = Scene::new(
        vec![
            light(
                quad(DVec3::new(-0.5, 0.0, 2.5), 0.6, true),
                DVec3::new(1.0, 2.0, 3.0),
            ),
            light(
                cuboid(DVec3::new(1.0, 0.0, 2.4), DVec3::new(0.4, 0.4, 0.2)),
                DVec3::new(2.0, 1.0, 1.0),
            ),
        ],
        vec![
            cuboid(DVec3::new(-0.2, 0.2, 2.3), DVec3::new(0.25, 0.2, 0.2)).into(),
            cuboid(DVec3::new(-0.7, -0.1, 2.8), DVec3::new(0.3, 0.3, 0.3)).into(),
            cuboid(DVec3::new(1.45, 0.1, 2.3), DVec3::new(0.2, 0.2, 0.1)).into(),
        ],
    )
    .unwrap();
    check("contacts", &scene, 300, 2.0, 28);
}

#[test]
fn shading_never_fails_on_degenerate_points() {
    // Shading points on light and occluder vertices, edge midpoints, in face planes and inside
    // objects, with random normals and views, in the scenes above: both methods must return a
    // finite, non-negative radiance (or, for the per-triangle method only, a give-up of the
    // sphere layer, `GeomError::Undecidable`, counted and required to be rare), never panic.
    let scenes = [
        Scene::new(
            vec![
                light(quad(DVec3::new(0.0, 0.0, 2.5), 0.6, true), DVec3::ONE),
                light(
                    ConvexPolyhedron::icosphere(DVec3::new(0.35, 0.15, 3.2), 0.5, 1).unwrap(),
                    DVec3::ONE,
                ),
            ],
            vec![
                cuboid(DVec3::new(0.45, 0.1, 2.5), DVec3::new(0.3, 0.25, 0.4)).into(),
                cuboid(DVec3::new(0.35, 0.15, 3.2), DVec3::new(0.1, 0.1, 1.0)).into(),
            ],
        )
        .unwrap(),
        Scene::new(
            vec![light(
                quad(DVec3::new(-0.2, 0.0, 2.0), 0.5, false)
                    .merged(&quad(DVec3::new(0.4, 0.1, 3.0), 0.6, true))
                    .unwrap(),
                DVec3::ONE,
            )],
            vec![cuboid(DVec3::new(0.5, 0.0, 2.5), DVec3::new(0.25, 0.25, 0.2)).into()],
        )
        .unwrap(),
        non_convex_lights_scene(),
    ];
    let m = Material::new(DVec3::splat(0.5), DVec3::splat(0.04), 0.3).unwrap();
    let mut rng = Rng::new(7713);
    let (mut failures, mut per_tri_errors, mut total) = (Vec::new(), 0, 0);
    for (k, scene) in scenes.iter().enumerate() {
        let meshes: Vec<&TriangleMesh> = scene
            .occluders()
            .iter()
            .chain(scene.lights().iter().map(|l| l.shape()))
            .map(|s| s.mesh())
            .collect();
        // The non-convex lights' degenerate points fall back to unions of front triangles,
        // which cost more: fewer points there.
        for i in 0..if k == 2 { 400 } else { 1500 } {
            let mesh = meshes[i % meshes.len()];
            let t = rng.below(mesh.triangle_count());
            let [a, b, c] = mesh.triangle(t);
            let x = match i % 5 {
                0 => a,
                1 => (a + b) / 2.0,
                // In the triangle's plane, outside it.
                2 => a + (b - a) * (1.0 + 2.0 * rng.f64()) + (c - a) * rng.f64(),
                3 => (a + b + c) / 3.0,
                _ => DVec3::new(
                    3.0 * rng.f64() - 1.5,
                    3.0 * rng.f64() - 1.5,
                    4.0 * rng.f64(),
                ),
            };
            let (n, v) = (rng.dir(), rng.dir());
            for method in [Method::Silhouette, Method::PerTriangle] {
                total += 1;
                match scene.clone().with_method(method).shade(x, n, v, &m) {
                    Ok(c) if c.is_finite() && c.min_element() >= 0.0 => {}
                    // A give-up, never an input fault: every query here is valid.
                    Err(e) if method == Method::PerTriangle && e.is_undecidable() => {
                        per_tri_errors += 1;
                        eprintln!("per-triangle x {x} n {n} v {v}: {e}");
                    }
                    other => failures.push(format!("{method:?} x {x} n {n} v {v}: {other:?}")),
                }
            }
        }
    }
    assert!(
        failures.is_empty(),
        "{} failures:\n{}",
        failures.len(),
        failures.join("\n")
    );
    assert!(
        per_tri_errors * 1000 <= total,
        "{per_tri_errors} per-triangle errors in {total} evaluations"
    );
}

#[test]
fn random_scenes_with_interpenetrating_objects() {
    // Random lights (quad, cuboid, icosphere, frustum, two-sheet mesh) with random boxes,
    // icospheres and rods placed so that they often cut through the light, touch it or sit behind
    // it, and a second light nearby: 24 scenes, 25 ground points each.
    let mut rng = Rng::new(3114);
    let mut r = |lo: f64, hi: f64| rng.range(lo, hi);
    let mut retested = 0;
    for case in 0..24u64 {
        let c = DVec3::new(r(-0.5, 0.5), r(-0.5, 0.5), r(2.0, 3.0));
        let size = r(0.3, 0.7);
        let shape: Body = match case % 5 {
            0 => quad(c, size, true).into(),
            1 => cuboid(c, DVec3::new(size, r(0.2, 0.6), r(0.1, 0.4))).into(),
            2 => ConvexPolyhedron::icosphere(c, size, 1).unwrap().into(),
            3 => ConvexPolyhedron::frustum(
                c,
                DVec3::new(r(-0.3, 0.3), r(-0.3, 0.3), r(0.3, 0.8)),
                size * 0.6,
                size * 0.3,
                7,
            )
            .unwrap()
            .into(),
            _ => quad(c, size, true)
                .merged(&quad(
                    c + DVec3::new(r(-0.4, 0.4), 0.0, r(0.4, 0.8)),
                    size,
                    true,
                ))
                .unwrap()
                .into(),
        };
        let second = light(
            cuboid(
                c + DVec3::new(r(-1.2, 1.2), r(-1.2, 1.2), r(-0.2, 0.8)),
                DVec3::splat(r(0.15, 0.35)),
            ),
            DVec3::new(0.5, 1.0, 1.5),
        );
        let mut occluders: Vec<Body> = Vec::new();
        for k in 0..2 {
            let o = c + DVec3::new(r(-0.7, 0.7), r(-0.7, 0.7), r(-0.7, 0.5));
            occluders.push(match (case + k) % 3 {
                0 => cuboid(o, DVec3::new(r(0.1, 0.4), r(0.1, 0.4), r(0.1, 0.4))).into(),
                1 => ConvexPolyhedron::icosphere(o, r(0.1, 0.35), 1)
                    .unwrap()
                    .into(),
                _ => cuboid(o, DVec3::new(0.08, 0.08, r(0.4, 1.0))).into(),
            });
        }
        let scene = Scene::new(
            vec![light(shape, DVec3::new(1.5, 1.0, 0.5)), second],
            occluders,
        )
        .unwrap();
        let name = format!("random scene {case}");
        let mut all = Vec::new();
        for method in [Method::Silhouette, Method::PerTriangle] {
            let rep = run(&scene, method, 25, 2.0, 100 + case);
            retested += rep.retested;
            all.extend(rep.failures.into_iter().map(|f| format!("{method:?} {f}")));
        }
        assert!(
            all.is_empty(),
            "{name}: {} failures:\n{}",
            all.len(),
            all.join("\n")
        );
    }
    eprintln!("random scenes: {retested} points re-estimated");
}
