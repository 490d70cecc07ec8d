//! Seed 001's methods and the Quilez baselines against independent references.
//!
//! - The occlusion formula against the area of a circular segment (a different closed form).
//! - Alg. 2's guarantee, "the true minimum lies in `[m - epsilon, m]`", against a dense scan of
//!   `m(t)` whose gaps are bounded with the Lipschitz constant of `m`.
//! - The fast soft shadow (4.1) and the proxy integration (4.2), on the configuration the
//!   paper's model assumes (an occluder whose boundary crosses the cone as a straight edge),
//!   against the visible fraction of the light by quadrature with exact ray-box tests, and
//!   against the crate's exact shading (`arealight::shade::Scene`) for a quad light.
//! - The Quilez shadow against the minimum of `k h / t` over a dense scan of the ray.
//! - Visibility in `[0, 1]`, and 1 with no occluders, for every method (proptests).

mod support;

use arealight::GeomError;
use arealight::glam::{DQuat, DVec3};
use arealight::sdf::{
    AreaLight, ConeSearch, Cuboid, Plane, Profile, ProxyOccluder, QuadLight, QuilezSettings, Sdf,
    Sphere, SphereLight, Transformed, Union, UnionAll, chord_visibility, fast_soft_shadow,
    minimal_tangent_cone, proxy_integral, proxy_occluder, proxy_quad_integral,
    quilez_improved_shadow, quilez_shadow, smoothstep_visibility,
};
use arealight::shade::{ConvexPolyhedron, Light, Material, Scene, TriangleMesh};
use proptest::prelude::*;
use std::f64::consts::PI;
use support::Rng;

#[test]
fn chord_visibility_is_the_visible_share_of_a_cut_disk() {
    // A chord at signed distance m from the center cuts off (on the far side x > m) a segment
    // with central angle theta = 2 acos(m), area (theta - sin theta) / 2 of the disk's pi.
    for i in 0..=2000 {
        let m = -1.0 + 2.0 * i as f64 / 2000.0;
        let theta = 2.0 * m.acos();
        let hidden = (theta - theta.sin()) / (2.0 * PI);
        let v = chord_visibility(m);
        assert!(
            (v - (1.0 - hidden)).abs() < 1e-12,
            "m = {m}: {v} vs {}",
            1.0 - hidden
        );
        // The smoothstep stand-in: equal at -1, 0, 1, within 0.04 in between (as documented).
        assert!((smoothstep_visibility(m) - v).abs() < 0.04);
    }
    for m in [-1.0, 0.0, 1.0] {
        assert!((smoothstep_visibility(m) - chord_visibility(m)).abs() < 1e-15);
    }
    // Clamped outside [-1, 1].
    assert_eq!(chord_visibility(3.0), 1.0);
    assert_eq!(chord_visibility(-3.0), 0.0);
    assert_eq!(smoothstep_visibility(-3.0), 0.0);
}

/// A random scene of balls and boxes (some rotated), with or without a floor.
fn scene(params: &[f64], floor: bool) -> UnionAll {
    let mut members: Vec<Box<dyn Sdf + Send + Sync>> = Vec::new();
    for c in params.chunks(5) {
        let center = DVec3::new(c[0], c[1], c[2]) * 2.0;
        let size = 0.05 + c[3].abs() * 0.5;
        if c[4] > 0.0 {
            members.push(Box::new(Sphere::new(center, size).unwrap()));
        } else {
            let b = Cuboid::new(DVec3::ZERO, DVec3::new(size, 0.5 * size, 1.5 * size)).unwrap();
            let rot = DQuat::from_axis_angle(DVec3::new(c[0], 1.0, c[2]).normalize(), c[4] * 3.0);
            members.push(Box::new(Transformed::new(b, rot, center, 1.0).unwrap()));
        }
    }
    if floor {
        members.push(Box::new(
            Plane::new(DVec3::new(0.0, 0.0, -2.0), DVec3::Z).unwrap(),
        ));
    }
    UnionAll::new(members)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(support::cases(150)))]

    /// Alg. 2: when the search completes, the true minimum of the clamped `m(t)` over
    /// `[t_min, t_max]` lies in `[m - epsilon, m]`, and `m` is the value at the reported `t`.
    ///
    /// Reference: `m(t)` on a dense grid. Between grid points `m` changes at most at rate
    /// `(1 + tan a) / rho(t)` (`f` is 1-Lipschitz, `rho` grows at `tan a`, `|m| <= 1` after
    /// clamping), so the grid gives an upper bound `ub` and a lower bound `lb` of the true
    /// minimum; the test requires `m - epsilon <= ub` (no dip deeper than `epsilon` below `m` was
    /// stepped over) and `m >= lb` (no value below the true minimum).
    #[test]
    fn cone_search_brackets_the_true_minimum(
        params in proptest::collection::vec(-1.0f64..1.0, 20),
        o in proptest::array::uniform3(-2.5f64..2.5),
        d in proptest::array::uniform3(-1.0f64..1.0),
        tan in 0.02f64..0.5,
        r0 in 0.0f64..0.1,
        t_max in 1.0f64..6.0,
        eps_pick in 0usize..3,
    ) {
        let f = scene(&params, true);
        let (o, d) = (DVec3::from_array(o), DVec3::from_array(d));
        prop_assume!(d.length() > 0.1);
        let d = d.normalize();
        let eps = [0.02, 0.05, 0.1][eps_pick];
        let mut search = ConeSearch::new(eps, 0.05);
        search.max_steps = 100_000;
        let min = minimal_tangent_cone(&f, o, d, r0, tan, t_max, &search).unwrap();
        prop_assert!(min.complete);
        prop_assert!((-1.0..=1.0).contains(&min.m));
        let m_at = |t: f64| (f.distance(o + t * d) / (r0 + t * tan)).clamp(-1.0, 1.0);
        if min.m < 1.0 {
            prop_assert!((m_at(min.t) - min.m).abs() < 1e-12);
        }
        let n = 20_000;
        let h = (t_max - 0.05) / n as f64;
        let (mut ub, mut lb) = (f64::INFINITY, f64::INFINITY);
        for i in 0..=n {
            let t = 0.05 + i as f64 * h;
            let v = m_at(t);
            ub = ub.min(v);
            let rate = (1.0 + tan) / (r0 + t * tan);
            lb = lb.min(v - rate * h);
        }
        prop_assert!(min.m - eps <= ub + 1e-9, "m = {}, eps = {eps}, scanned minimum {ub}", min.m);
        prop_assert!(min.m >= lb.max(-1.0) - 1e-9, "m = {} below the lower bound {lb}", min.m);
    }

    /// Every method's visibility is in `[0, 1]` on random scenes, points and lights.
    #[test]
    fn visibility_is_in_the_unit_interval(
        params in proptest::collection::vec(-1.0f64..1.0, 20),
        p in proptest::array::uniform3(-2.5f64..2.5),
        c in proptest::array::uniform3(-3.0f64..3.0),
        radius in 0.05f64..1.0,
    ) {
        let f = scene(&params, true);
        let (p, c) = (DVec3::from_array(p), DVec3::from_array(c));
        prop_assume!((c - p).length() > radius * 1.01);
        let light = SphereLight::new(c, radius).unwrap();
        let search = ConeSearch::new(0.05, 1e-3);
        let q = QuilezSettings::new(1e-3);
        for v in [
            fast_soft_shadow(&f, p, &light, &search, Profile::Chord).unwrap(),
            fast_soft_shadow(&f, p, &light, &search, Profile::Smoothstep).unwrap(),
            quilez_shadow(&f, p, &light, &q).unwrap(),
            quilez_improved_shadow(&f, p, &light, &q).unwrap(),
        ] {
            prop_assert!((0.0..=1.0).contains(&v), "{v}");
        }
        // The proxy integral of the uniform weight is at most the light's solid angle.
        let omega = 2.0 * PI * (1.0 - (1.0 - (radius / (c - p).length()).powi(2)).sqrt());
        let w = proxy_integral(&f, p, &light, |_| 1.0, 256, &search).unwrap();
        prop_assert!((0.0..=omega * (1.0 + 1e-9)).contains(&w), "{w} vs {omega}");
    }

    /// With no occluder in the cone every method sees the whole light: the empty scene, and
    /// scenes whose objects all lie behind the point (farther from the light than the point).
    #[test]
    fn no_occluders_means_full_visibility(
        params in proptest::collection::vec(-1.0f64..1.0, 20),
        dir in proptest::array::uniform3(-1.0f64..1.0),
        dist in 1.5f64..6.0,
        radius in 0.05f64..1.0,
    ) {
        let dir = DVec3::from_array(dir);
        prop_assume!(dir.length() > 0.1);
        let v = dir.normalize();
        // scene() keeps every object within 4.4 of the origin; the point is 6 along v, the light
        // farther on, so the whole cone lies on the far side of the plane x . v = 6.
        let p = v * 6.0;
        let light = SphereLight::new(p + v * (dist + radius), radius).unwrap();
        let search = ConeSearch::new(0.05, 1e-3);
        let q = QuilezSettings::new(1e-3);
        let behind = scene(&params, false);
        let empty = UnionAll::new(vec![]);
        let fields: [&dyn Sdf; 2] = [&behind, &empty];
        for f in fields {
            prop_assert_eq!(fast_soft_shadow(f, p, &light, &search, Profile::Chord).unwrap(), 1.0);
            prop_assert_eq!(fast_soft_shadow(f, p, &light, &search, Profile::Smoothstep).unwrap(), 1.0);
            prop_assert_eq!(quilez_shadow(f, p, &light, &q).unwrap(), 1.0);
            prop_assert_eq!(quilez_improved_shadow(f, p, &light, &q).unwrap(), 1.0);
            let (proxy, _) = proxy_occluder(f, p, &light, &search).unwrap();
            prop_assert_eq!(proxy, ProxyOccluder::Clear);
        }
    }
}

/// Slab test: the entry distance of a ray into the box `c ± h` (rotated by `rot`), if any.
fn ray_box(o: DVec3, d: DVec3, c: DVec3, h: DVec3, rot: DQuat) -> Option<f64> {
    let (o, d) = (rot.inverse() * (o - c), rot.inverse() * d);
    let (mut lo, mut hi) = (0.0f64, f64::INFINITY);
    for i in 0..3 {
        if d[i].abs() < 1e-300 {
            if o[i].abs() > h[i] {
                return None;
            }
            continue;
        }
        let (t1, t2) = ((-h[i] - o[i]) / d[i], (h[i] - o[i]) / d[i]);
        lo = lo.max(t1.min(t2));
        hi = hi.min(t1.max(t2));
    }
    (lo <= hi).then_some(lo)
}

/// An edge-like occluder: a large slab of thickness 1 whose bottom face is at height `z0` and
/// whose edge, rotated by `angle` about z, passes at `offset` from the z axis.
struct Edge {
    center: DVec3,
    half: DVec3,
    rot: DQuat,
}

impl Edge {
    fn new(angle: f64, offset: f64, z0: f64) -> Self {
        let rot = DQuat::from_rotation_z(angle);
        let half = DVec3::new(6.0, 6.0, 0.5);
        // The slab occupies local x > offset (its edge is the line x = offset, y free).
        let center = rot * DVec3::new(offset + half.x, 0.0, z0 + half.z);
        Edge { center, half, rot }
    }
    fn sdf(&self) -> Transformed<Cuboid> {
        Transformed::new(
            Cuboid::new(DVec3::ZERO, self.half).unwrap(),
            self.rot,
            self.center,
            1.0,
        )
        .unwrap()
    }
    fn polyhedron(&self) -> ConvexPolyhedron {
        let mut corners = Vec::new();
        for sx in [-1.0, 1.0] {
            for sy in [-1.0, 1.0] {
                for sz in [-1.0, 1.0] {
                    corners.push(self.center + self.rot * (DVec3::new(sx, sy, sz) * self.half));
                }
            }
        }
        ConvexPolyhedron::hull(&corners).unwrap()
    }
}

/// The share of a spherical light's solid angle seen from `p` past the edge occluder: a polar
/// grid over the light's cap (equal-area rings), each direction tested with the slab test
/// against the light sphere's distance along it. Error: the cells the two boundaries cross,
/// about `2 / rings` of the cap here.
fn visible_share(p: DVec3, light: &SphereLight, edge: &Edge, rings: usize) -> f64 {
    let to = light.center() - p;
    let dist = to.length();
    let v = to / dist;
    let (a, b) = v.any_orthonormal_pair();
    let cos_a = (1.0 - (light.radius() / dist).powi(2)).sqrt();
    let (mut seen, mut total) = (0usize, 0usize);
    for i in 0..rings {
        let z = 1.0 - (i as f64 + 0.5) / rings as f64 * (1.0 - cos_a);
        let r = (1.0 - z * z).sqrt();
        let spokes = 4 * rings;
        for j in 0..spokes {
            let phi = 2.0 * PI * (j as f64 + 0.5) / spokes as f64;
            let l = z * v + r * (phi.cos() * a + phi.sin() * b);
            // Distance to the light sphere along l.
            let along = to.dot(l);
            let t_light = along
                - (light.radius().powi(2) - (to - along * l).length_squared())
                    .max(0.0)
                    .sqrt();
            total += 1;
            if !matches!(ray_box(p, l, edge.center, edge.half, edge.rot), Some(t) if t < t_light) {
                seen += 1;
            }
        }
    }
    seen as f64 / total as f64
}

/// Seed 001 section 4.1 where its model holds: a straight edge across a small light's cone.
///
/// On the lit side (the axis outside the occluder, `m >= 0`) the chord formula gives the
/// light's visible share to within the search accuracy (`V' <= 2 / pi`, so `0.02 * 0.64`), the
/// cone-vs-cap model error (`O(alpha^2)`, about 1% at `alpha = 0.1`) and the reference's grid
/// error (under 1%): 0.03 in all. On the umbra side (the axis inside the occluder) the signed
/// distance inside is capped by the face the axis pierced, so `m` stays above the edge's true
/// relative offset and the shadow comes out too light: a known bias of the method, bounded
/// here by 0.08. On these same scenes the Quilez shadows, which see only the unsigned half of
/// the penumbra, are clearly worse (the ordering of seed 001 figure 4).
#[test]
fn fast_shadow_matches_the_visible_share_at_straight_edges() {
    let mut rng = Rng::new(31);
    let search = ConeSearch::new(0.02, 1e-4);
    let q = QuilezSettings::new(1e-4);
    let (mut err_fast, mut err_smooth, mut err_q, mut err_qi) = (0.0, 0.0, 0.0, 0.0);
    let (mut worst_lit, mut worst_umbra) = (0.0f64, 0.0f64);
    let cases = 120;
    for _ in 0..cases {
        let light = SphereLight::new(
            DVec3::new(rng.range(-0.5, 0.5), rng.range(-0.5, 0.5), 3.0),
            0.3,
        )
        .unwrap();
        let p = DVec3::new(rng.range(-0.2, 0.2), rng.range(-0.2, 0.2), 0.0);
        let z0 = rng.range(0.8, 1.5);
        // Where the cone axis crosses height z0, and the cone's radius there.
        let axis_at = p + (light.center() - p) * (z0 / light.center().z);
        let angle = rng.range(0.0, 2.0 * PI);
        let along = DQuat::from_rotation_z(angle) * DVec3::X;
        let rho = z0 * 0.3 / 3.0;
        let offset = axis_at.dot(along) + rng.range(-1.3, 1.3) * rho;
        let edge = Edge::new(angle, offset, z0);
        let f = edge.sdf();
        let want = visible_share(p, &light, &edge, 300);
        let fast = fast_soft_shadow(&f, p, &light, &search, Profile::Chord).unwrap();
        let smooth = fast_soft_shadow(&f, p, &light, &search, Profile::Smoothstep).unwrap();
        let to = light.center() - p;
        let lit_side = !matches!(
            ray_box(p, to.normalize(), edge.center, edge.half, edge.rot),
            Some(t) if t < to.length()
        );
        let err = (fast - want).abs();
        if lit_side {
            worst_lit = worst_lit.max(err);
            assert!(err < 0.03, "lit side: fast {fast} vs visible share {want}");
        } else {
            worst_umbra = worst_umbra.max(err);
            assert!(
                err < 0.08,
                "umbra side: fast {fast} vs visible share {want}"
            );
        }
        err_fast += err;
        err_smooth += (smooth - want).abs();
        err_q += (quilez_shadow(&f, p, &light, &q).unwrap() - want).abs();
        err_qi += (quilez_improved_shadow(&f, p, &light, &q).unwrap() - want).abs();
    }
    let n = cases as f64;
    let (err_fast, err_smooth, err_q, err_qi) =
        (err_fast / n, err_smooth / n, err_q / n, err_qi / n);
    eprintln!(
        "mean |error|: chord {err_fast:.4} smoothstep {err_smooth:.4} quilez {err_q:.4} \
         improved {err_qi:.4}; worst chord: lit {worst_lit:.4}, umbra {worst_umbra:.4}"
    );
    assert!(err_fast < 0.02, "mean error {err_fast}");
    assert!(err_smooth < 0.04, "mean error {err_smooth}");
    assert!(
        err_q > 2.0 * err_fast && err_qi > 2.0 * err_fast,
        "{err_q} {err_qi} vs {err_fast}"
    );
}

/// Seed 001 section 4.2 for a quad light where its model holds: the proxy occluder's exact
/// integral against the crate's exact shading of the same scene (the slab as a convex
/// polyhedron), on points whose light is partly hidden. On the lit side (the axis to the
/// light's center clear of the slab) the error comes from the search accuracy
/// (`epsilon = 0.01`) and the proxy plane's orientation, taken from the normal at the minimum:
/// within 3% of the unoccluded value (2.1% seen). On the umbra side the relative distance `m`
/// is biased as for the fast shadow (see above): within 10% (8.7% seen).
#[test]
fn proxy_quad_integral_matches_exact_shading_at_straight_edges() {
    let mut rng = Rng::new(32);
    let search = ConeSearch::new(0.01, 1e-4);
    let white = Material::diffuse(DVec3::ONE).unwrap();
    let (mut worst, mut sum, mut in_penumbra) = (0.0f64, 0.0, 0);
    for _ in 0..80 {
        let (u, v) = (DVec3::X * 0.4, -DVec3::Y * 0.25);
        let center = DVec3::new(rng.range(-0.5, 0.5), rng.range(-0.5, 0.5), 3.0);
        let quad = QuadLight::new(center, u, v).unwrap();
        let mesh = TriangleMesh::quad(center, u, v).unwrap();
        let p = DVec3::new(rng.range(-0.2, 0.2), rng.range(-0.2, 0.2), 0.0);
        let n = DVec3::new(rng.range(-0.3, 0.3), rng.range(-0.3, 0.3), 1.0).normalize();
        let z0 = rng.range(0.8, 1.5);
        let axis_at = p + (center - p) * (z0 / 3.0);
        let angle = rng.range(0.0, 2.0 * PI);
        let along = DQuat::from_rotation_z(angle) * DVec3::X;
        let offset = axis_at.dot(along) + rng.range(-0.35, 0.35) * z0 / 3.0;
        let edge = Edge::new(angle, offset, z0);
        let scene = Scene::new(
            vec![Light::new(mesh.clone(), DVec3::ONE).unwrap()],
            vec![edge.polyhedron().into()],
        )
        .unwrap();
        let open = Scene::new(vec![Light::new(mesh, DVec3::ONE).unwrap()], vec![]).unwrap();
        let exact = scene.shade(p, n, n, &white).unwrap().x;
        let unoccluded = open.shade(p, n, n, &white).unwrap().x;
        let proxy = proxy_quad_integral(&edge.sdf(), p, n, &quad, &search).unwrap();
        // The proxy's half-space itself: directions toward the light's bounding sphere that it
        // calls visible should clear the slab, and those it hides should hit it, except near
        // its boundary (the model's error): at most 15% of the cone may disagree.
        let bound = quad.bounding_sphere();
        let (occluder, _) = proxy_occluder(&edge.sdf(), p, &bound, &search).unwrap();
        let to = bound.center() - p;
        let axis = to.normalize();
        let (a, b) = axis.any_orthonormal_pair();
        let sin_a = bound.radius() / to.length();
        let (mut disagree, mut total) = (0, 0);
        for i in 0..20 {
            for j in 0..20 {
                let r = sin_a * ((i as f64 + 0.5) / 20.0).sqrt();
                let phi = 2.0 * PI * j as f64 / 20.0;
                let l =
                    (axis * (1.0 - r * r).sqrt() + r * (phi.cos() * a + phi.sin() * b)).normalize();
                let hidden = matches!(ray_box(p, l, edge.center, edge.half, edge.rot), Some(t) if t < 3.0 / l.z);
                total += 1;
                if occluder.visible(l) == hidden {
                    disagree += 1;
                }
            }
        }
        assert!(
            disagree * 100 <= 15 * total,
            "{disagree} of {total} directions disagree"
        );
        // Without occluders the two integrate the same quad exactly.
        let clear = proxy_quad_integral(&UnionAll::new(vec![]), p, n, &quad, &search).unwrap();
        assert!(
            (clear - unoccluded).abs() < 1e-12 * unoccluded.max(1e-300),
            "{clear} vs {unoccluded}"
        );
        let err = (proxy - exact).abs() / unoccluded;
        let to = center - p;
        let lit = !matches!(ray_box(p, to.normalize(), edge.center, edge.half, edge.rot), Some(t) if t < to.length());
        // The same two sides as for the fast shadow: exact up to the search accuracy and the
        // proxy plane's orientation on the lit side, biased toward light on the umbra side.
        let bound = if lit { 0.03 } else { 0.1 };
        assert!(
            err < bound,
            "lit {lit}: proxy {proxy} vs exact {exact} (unoccluded {unoccluded})"
        );
        if exact > 0.05 * unoccluded && exact < 0.95 * unoccluded {
            in_penumbra += 1;
        }
        worst = worst.max(err);
        sum += err;
    }
    eprintln!(
        "proxy vs exact: worst {worst:.4}, mean {:.4} of the unoccluded value",
        sum / 80.0
    );
    assert!(in_penumbra > 40, "only {in_penumbra} points in penumbra");
    assert!(sum / 80.0 < 0.02, "mean relative error {}", sum / 80.0);
}

/// The numerical proxy integration (a Fibonacci lattice over the bounding cone) against the
/// exact one for the same proxy, with and without an occluder. With 4096 directions the
/// lattice's error across the two boundaries stays below 1% of the unoccluded value here.
#[test]
fn proxy_integral_converges_to_the_exact_proxy_integral() {
    let mut rng = Rng::new(33);
    let search = ConeSearch::new(0.01, 1e-4);
    for _ in 0..40 {
        let (u, v) = (DVec3::X * 0.4, -DVec3::Y * 0.25);
        let center = DVec3::new(rng.range(-0.5, 0.5), rng.range(-0.5, 0.5), 3.0);
        let quad = QuadLight::new(center, u, v).unwrap();
        let p = DVec3::new(rng.range(-0.2, 0.2), rng.range(-0.2, 0.2), 0.0);
        let n = DVec3::new(rng.range(-0.3, 0.3), rng.range(-0.3, 0.3), 1.0).normalize();
        let z0 = rng.range(0.8, 1.5);
        let angle = rng.range(0.0, 2.0 * PI);
        let along = DQuat::from_rotation_z(angle) * DVec3::X;
        let axis_at = p + (center - p) * (z0 / 3.0);
        let edge = Edge::new(
            angle,
            axis_at.dot(along) + rng.range(-0.3, 0.3) * z0 / 3.0,
            z0,
        );
        let cosine = |l: DVec3| n.dot(l).max(0.0) / PI;
        for f in [&edge.sdf() as &dyn Sdf, &UnionAll::new(vec![])] {
            let exact = proxy_quad_integral(f, p, n, &quad, &search).unwrap();
            let full = proxy_quad_integral(&UnionAll::new(vec![]), p, n, &quad, &search).unwrap();
            let numeric = proxy_integral(f, p, &quad, cosine, 4096, &search).unwrap();
            assert!(
                (numeric - exact).abs() < 0.01 * full,
                "{numeric} vs {exact} ({full})"
            );
        }
    }
}

/// The Quilez shadow is the minimum of `k h / t` over the points of its march, a subset of the
/// ray: never below the minimum over a dense scan of the ray (clamped to `[0, 1]`), and 0 where
/// the axis hits an occluder.
#[test]
fn quilez_is_a_minimum_over_its_march() {
    let mut rng = Rng::new(34);
    let q = QuilezSettings::new(1e-3);
    let mut zero = 0;
    for _ in 0..300 {
        let ball = Sphere::new(
            DVec3::new(
                rng.range(-0.5, 0.5),
                rng.range(-0.5, 0.5),
                rng.range(0.8, 2.0),
            ),
            rng.range(0.1, 0.4),
        )
        .unwrap();
        let light = SphereLight::new(DVec3::new(0.0, 0.0, 3.0), rng.range(0.1, 0.5)).unwrap();
        let p = DVec3::new(rng.range(-0.5, 0.5), rng.range(-0.5, 0.5), 0.0);
        let to = light.center() - p;
        let d = to.length();
        let k = (d * d - light.radius().powi(2)).sqrt() / light.radius();
        let t_end = (d * d - light.radius().powi(2)) / d;
        let axis = to / d;
        let scan = (1..=20_000)
            .map(|i| {
                let t = 1e-3 + (t_end - 1e-3) * i as f64 / 20_000.0;
                (k * ball.distance(p + t * axis) / t).clamp(0.0, 1.0)
            })
            .fold(1.0f64, f64::min);
        let res = quilez_shadow(&ball, p, &light, &q).unwrap();
        assert!(res >= scan - 1e-9, "{res} below the scanned minimum {scan}");
        let hits = (ball.center() - p).cross(axis).length() < ball.radius();
        if hits {
            assert_eq!(res, 0.0);
            assert_eq!(quilez_improved_shadow(&ball, p, &light, &q).unwrap(), 0.0);
            zero += 1;
        }
    }
    assert!(zero > 20);
}

#[test]
fn bad_input_and_buried_lights() {
    let ball = Sphere::new(DVec3::new(0.0, 0.0, 1.5), 0.3).unwrap();
    let light = SphereLight::new(DVec3::new(0.0, 0.0, 3.0), 0.5).unwrap();
    let s = ConeSearch::new(0.05, 1e-3);
    let q = QuilezSettings::new(1e-3);
    let degen = |e: GeomError| matches!(e, GeomError::Degenerate(_));
    let range = |e: GeomError| matches!(e, GeomError::OutOfRange { .. });
    // Inside the light's sphere: no shadow cone.
    let inside = DVec3::new(0.0, 0.1, 3.2);
    assert!(degen(
        fast_soft_shadow(&ball, inside, &light, &s, Profile::Chord).unwrap_err()
    ));
    assert!(degen(quilez_shadow(&ball, inside, &light, &q).unwrap_err()));
    assert!(degen(
        quilez_improved_shadow(&ball, inside, &light, &q).unwrap_err()
    ));
    assert!(degen(
        proxy_integral(&ball, inside, &light, |_| 1.0, 16, &s).unwrap_err()
    ));
    assert!(degen(
        proxy_occluder(&ball, inside, &light, &s).unwrap_err()
    ));
    // Non-finite points and parameters.
    let nan = DVec3::new(f64::NAN, 0.0, 0.0);
    assert!(range(
        fast_soft_shadow(&ball, nan, &light, &s, Profile::Chord).unwrap_err()
    ));
    assert!(range(SphereLight::new(nan, 1.0).unwrap_err()));
    assert!(degen(SphereLight::new(DVec3::ZERO, -1.0).unwrap_err()));
    assert!(degen(
        QuadLight::new(DVec3::ZERO, DVec3::X, DVec3::X * 2.0).unwrap_err()
    ));
    assert!(range(
        QuadLight::new(DVec3::ZERO, DVec3::X, DVec3::splat(f64::INFINITY)).unwrap_err()
    ));
    for bad in [
        ConeSearch::new(0.0, 1e-3),
        ConeSearch::new(1.5, 1e-3),
        ConeSearch::new(0.05, 0.0),
        ConeSearch { max_steps: 0, ..s },
    ] {
        assert!(degen(
            fast_soft_shadow(&ball, DVec3::ZERO, &light, &bad, Profile::Chord).unwrap_err()
        ));
    }
    assert!(range(
        fast_soft_shadow(
            &ball,
            DVec3::ZERO,
            &light,
            &ConeSearch::new(f64::NAN, 1e-3),
            Profile::Chord
        )
        .unwrap_err()
    ));
    assert!(degen(
        quilez_shadow(&ball, DVec3::ZERO, &light, &QuilezSettings::new(-1.0)).unwrap_err()
    ));
    assert!(degen(
        proxy_integral(&ball, DVec3::ZERO, &light, |_| 1.0, 0, &s).unwrap_err()
    ));
    assert!(degen(
        minimal_tangent_cone(&ball, DVec3::ZERO, DVec3::Z, 0.0, -0.1, 2.0, &s).unwrap_err()
    ));
    assert!(degen(
        minimal_tangent_cone(&ball, DVec3::ZERO, DVec3::Z, -0.1, 0.1, 2.0, &s).unwrap_err()
    ));
    // Too few steps: the search says it is incomplete instead of pretending.
    let short = ConeSearch { max_steps: 2, ..s };
    // (Along a plane 1 away, with tan a = 0.01, the cone first comes near after ~100 steps.)
    let floor = Plane::new(-DVec3::Z, DVec3::Z).unwrap();
    let m = minimal_tangent_cone(&floor, DVec3::ZERO, DVec3::X, 0.0, 0.01, 1e3, &short);
    assert!(!m.unwrap().complete);
    // A light buried in a solid: visibility 0 for every method, even with the point outside.
    let block = Union(ball, Sphere::new(light.center(), 0.8).unwrap());
    let p = DVec3::new(3.0, 0.0, 0.0);
    assert_eq!(
        fast_soft_shadow(&block, p, &light, &s, Profile::Chord).unwrap(),
        0.0
    );
    assert_eq!(quilez_shadow(&block, p, &light, &q).unwrap(), 0.0);
    assert_eq!(quilez_improved_shadow(&block, p, &light, &q).unwrap(), 0.0);
    assert_eq!(
        proxy_integral(&block, p, &light, |_| 1.0, 64, &s).unwrap(),
        0.0
    );
    // A point behind a quad light's emitting side receives nothing.
    let quad = QuadLight::new(DVec3::new(0.0, 0.0, 3.0), DVec3::X, -DVec3::Y).unwrap();
    let above = DVec3::new(0.0, 0.0, 4.0);
    assert_eq!(
        proxy_quad_integral(&ball, above, -DVec3::Z, &quad, &s).unwrap(),
        0.0
    );
    assert!(!quad.emits_toward(above, -DVec3::Z));
    assert!(quad.emits_toward(DVec3::ZERO, DVec3::Z));
}

/// A step straight away from a surface doubles the distance, and the improved Quilez estimate
/// then has no circle to work from (`y = h`, `d = 0`). From a point a hair inside a floor,
/// toward a light at the zenith, the arithmetic below is exact (powers of two), so `y == h`
/// while `t - y = 2^-20 > 0`: the estimate must fall back to `k h / t` instead of reading
/// `d = 0` as a contact.
#[test]
fn improved_quilez_survives_steps_straight_away() {
    let floor = Plane::new(DVec3::ZERO, DVec3::Z).unwrap();
    let light = SphereLight::new(DVec3::new(0.0, 0.0, 10.0), 1.0).unwrap();
    let p = DVec3::new(0.0, 0.0, -(2.0f64).powi(-20));
    let q = QuilezSettings::new(0.5);
    assert_eq!(quilez_improved_shadow(&floor, p, &light, &q).unwrap(), 1.0);
    assert_eq!(quilez_shadow(&floor, p, &light, &q).unwrap(), 1.0);
}
