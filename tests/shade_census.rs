//! Issue 24's families at the shade level, as a census: random scenes that live where silently
//! wrong values hide (sliver occluders, occluders in a light's plane or cutting through it,
//! shading points whose horizon passes within `1e-16..1e-9` of a light vertex, grazing views with
//! near-mirror roughness, points on occluder surfaces and on slivers), each point shaded with
//! both methods.
//!
//! Asserted per point: a valid query gives a finite, non-negative value or
//! `GeomError::Undecidable`, never another error; per light, `0 <= shadowed <= unshadowed <=`
//! radiance times the material's directional albedo from the GGX table (relative 1e-9); the two
//! methods agree, per lobe, within `1e-9` of the light's unshadowed value, the specular lobe
//! also within what a boundary moved by the sphere layer's resolution changes under a lobe of
//! its width, and both widened for a point within the facing predicate's tolerance of a face
//! plane by how much the per-triangle value changes when the point moves across that band (see
//! [`methods_disagree`] and [`facing_band_spread`]). A subsample is checked
//! against the Monte Carlo reference (`ReferenceBrdf::Ltc`, the BRDF the analytic path
//! integrates; light sampling by front faces, independent of the visibility and sphere code,
//! combined with BRDF sampling so that near-mirror lobes are resolved) at 4.5 standard errors
//! plus `1e-6` relative and `1e-9` of the light's hemisphere bound, with a second stage of 16
//! times the samples and the empirical Bernstein interval (level `1 - 1e-6`) for a point that
//! fails the first (see tests/shade_glossy_mc.rs for why a rare-event estimate needs it).
//!
//! Give-ups (`Undecidable`) are counted per family (light kind / point kind). Asserted: fewer
//! than 0.1% over each census, and per family what the sample resolves: in every run, no family
//! has more give-ups than a rate of 0.1% makes plausible (a binomial tail probability below
//! `1e-3`), and a family with at least 5 000 queries (the opt-in large run) has a rate below
//! 0.1%.
//!
//! A second census (`census_of_points_near_cut_light_faces`) lives where a light face's plane
//! cuts a small occluder: points inside or just outside it, points `1e-6..1e-2` from a light
//! face, big faces seen from close.
//!
//! `CENSUS_CASES=N` multiplies the number of scenes (default 1: 60 scenes x 40 points, about 300
//! queries per family, and 40 scenes x 24 points, about 160 per family; `CENSUS_CASES=64` gives
//! every family 8 800 to 29 600, about 18 minutes on the shared VM). `CENSUS_VERBOSE=1` prints
//! every give-up with its arguments,
//! `CENSUS_DUMP=case` a scene's geometry, `CENSUS_ONLY=case:point` runs that point alone, e.g.
//! `CENSUS_CASES=64 cargo test --release --test shade_census -- --nocapture`.

use arealight::GeomError;
use arealight::glam::DVec3;
use arealight::shade::{
    Body, ConvexPolyhedron, Estimate, Light, LightSampling, LightShading, Material, Method,
    MonteCarlo, ReferenceBrdf, Scene, ShadingFrame, TriangleMesh,
};
use arealight::solid::{FACE_TOLERANCE, Side, face_side};
use std::collections::BTreeMap;
use support::Rng;
use support::shade::{point_on_mesh, view_above};

mod support;

/// A light of one of four kinds about `c`, facing down where it is flat.
fn random_light(rng: &mut Rng, c: DVec3, kind: u64) -> Body {
    let s = rng.range(0.3, 0.7);
    match kind % 4 {
        0 => TriangleMesh::quad(c, DVec3::new(0.0, s, 0.0), DVec3::new(s, 0.0, 0.0))
            .unwrap()
            .into(),
        1 => ConvexPolyhedron::cuboid(c, DVec3::new(s, rng.range(0.2, 0.6), rng.range(0.05, 0.3)))
            .unwrap()
            .into(),
        2 => ConvexPolyhedron::icosphere(c, s * 0.6, 1).unwrap().into(),
        _ => TriangleMesh::quad(c, DVec3::new(0.0, s, 0.0), DVec3::new(s, 0.0, 0.0))
            .unwrap()
            .merged(
                &TriangleMesh::quad(
                    c + DVec3::new(rng.range(-0.3, 0.3), 0.0, rng.range(0.3, 0.6)),
                    DVec3::new(0.0, s, 0.0),
                    DVec3::new(s, 0.0, 0.0),
                )
                .unwrap(),
            )
            .unwrap()
            .into(),
    }
}

/// A sliver triangle near `c`: one vertex moved off the segment of the other two by
/// `1e-15..1e-9` of the size (`None` where that is too thin for a reliable normal, which
/// `TriangleMesh::new` rejects).
fn sliver(rng: &mut Rng, c: DVec3) -> Option<Body> {
    let a = c + rng.dir() * 0.4;
    let b = c - rng.dir() * 0.4;
    let off = 10f64.powf(rng.range(-15.0, -9.0));
    let m = a.lerp(b, rng.range(0.2, 0.8)) + rng.dir() * off * (b - a).length();
    TriangleMesh::new(vec![a, b, m], vec![[0, 1, 2]])
        .ok()
        .map(Into::into)
}

/// Occluders of the families: a sliver, a flat quad in the light's plane (either facing), a
/// box cutting through the light, a box touching its plane from below.
fn occluders(rng: &mut Rng, c: DVec3, light: &Body) -> Vec<Body> {
    let mut out = Vec::new();
    let at = c - DVec3::new(0.0, 0.0, rng.range(0.2, 1.0));
    if let Some(s) = sliver(rng, at) {
        out.push(s);
    }
    // The plane of the light's lowest vertex (a face plane for quads and boxes).
    let z = light
        .mesh()
        .vertices()
        .iter()
        .map(|v| v.z)
        .fold(f64::INFINITY, f64::min);
    let q = DVec3::new(c.x + rng.range(-0.4, 0.4), c.y + rng.range(-0.4, 0.4), z);
    let (u, v) = (
        DVec3::X * rng.range(0.1, 0.3),
        DVec3::Y * rng.range(0.1, 0.3),
    );
    let flat = if rng.f64() < 0.5 {
        TriangleMesh::quad(q, u, v)
    } else {
        TriangleMesh::quad(q, v, u)
    };
    out.push(flat.unwrap().into());
    let h = DVec3::new(
        rng.range(0.05, 0.2),
        rng.range(0.05, 0.2),
        rng.range(0.05, 0.4),
    );
    let through = c + DVec3::new(rng.range(-0.5, 0.5), rng.range(-0.5, 0.5), 0.0);
    out.push(ConvexPolyhedron::cuboid(through, h).unwrap().into());
    let below = DVec3::new(
        c.x + rng.range(-0.6, 0.6),
        c.y + rng.range(-0.6, 0.6),
        z - h.z,
    );
    out.push(ConvexPolyhedron::cuboid(below, h).unwrap().into());
    out
}

/// Names of the point kinds of [`point`].
const POINT_KINDS: [&str; 4] = [
    "horizon at a vertex",
    "on an occluder",
    "on a sliver",
    "ground",
];

/// A shading point, normal and view, and its kind (an index of [`POINT_KINDS`]): on the ground
/// with the horizon tilted to pass within `1e-16..1e-9` (absolute or relative) of a light
/// vertex, on a box or the flat quad, on the sliver (where the scene has one; a point on a
/// triangle thinner than rounding may be on either side of it), or on the ground; views grazing
/// (`cos 1e-4..0.05`) half of the time.
fn point(rng: &mut Rng, scene: &Scene, i: usize, has_sliver: bool) -> (DVec3, DVec3, DVec3, usize) {
    let occ = scene.occluders();
    let kind = match i % 4 {
        2 if !has_sliver => 1,
        k => k,
    };
    let (x, n) = match kind {
        0 => {
            let x = DVec3::new(rng.range(-2.0, 2.0), rng.range(-2.0, 2.0), 0.0);
            let lm = scene.lights()[0].shape().mesh();
            let p = lm.vertices()[rng.below(lm.vertices().len())];
            let d = (p - x).normalize();
            // A normal perpendicular to the direction of the vertex, tilted by a tiny angle.
            let side = d.cross(DVec3::Z).normalize();
            let mut n = side.cross(d).normalize();
            if n.z < 0.0 {
                n = -n;
            }
            let eps = 10f64.powf(rng.range(-16.0, -9.0)) * if rng.f64() < 0.5 { -1.0 } else { 1.0 };
            (x, (n + d * eps).normalize())
        }
        1 => {
            let k = rng.below(3);
            point_on_mesh(rng, occ[occ.len() - 3 + k].mesh())
        }
        2 => {
            let (x, n) = point_on_mesh(rng, occ[0].mesh());
            (x, if rng.f64() < 0.5 { n } else { -n })
        }
        _ => (
            DVec3::new(rng.range(-2.0, 2.0), rng.range(-2.0, 2.0), 0.0),
            DVec3::Z,
        ),
    };
    let (t, b) = n.any_orthonormal_pair();
    let v = if rng.f64() < 0.5 {
        let c = rng.range(1e-4, 0.05);
        n * c + t * (1.0 - c * c).sqrt()
    } else {
        n * (0.3 + rng.f64()) + t * (rng.f64() - 0.5) + b * (rng.f64() - 0.5)
    };
    (x, n, v, kind)
}

/// Whether `x` lies strictly inside a convex occluder (behind every face plane by 1e-9).
fn inside_a_convex_occluder(scene: &Scene, x: DVec3) -> bool {
    scene.occluders().iter().any(|o| match o {
        Body::Convex(p) => {
            let m = p.mesh();
            (0..m.triangle_count()).all(|t| m.triangle_normal(t).dot(x - m.triangle(t)[0]) < -1e-9)
        }
        _ => false,
    })
}

#[derive(Default)]
struct Tally {
    queries: usize,
    gave_up: usize,
    gave_up_per_triangle: usize,
    mc_checks: usize,
    mc_retested: usize,
    /// Per family (a label of the light and point kinds): queries and give-ups.
    families: BTreeMap<String, (usize, usize)>,
    failures: Vec<String>,
}

/// The probability that a binomial variable of `q` trials with success rate `p` is at least `g`
/// (summed in logarithms, so that `q (1 - p)^q` underflowing does not matter).
fn binomial_tail(q: usize, g: usize, p: f64) -> f64 {
    if g == 0 {
        return 1.0;
    }
    let mean = q as f64 * p;
    let last = q.min(g.max(mean as usize) + 60 + (40.0 * mean.sqrt()) as usize);
    let mut ln_t = q as f64 * (-p).ln_1p();
    let mut tail = 0.0;
    for k in 0..=last {
        if k >= g {
            tail += ln_t.exp();
        }
        ln_t += ((q - k) as f64 / (k + 1) as f64).ln() + (p / (1.0 - p)).ln();
    }
    tail.min(1.0)
}

/// The give-up rate asserted per family.
const MAX_RATE: f64 = 1e-3;

/// Queries from which a family's own rate must be below [`MAX_RATE`] (0.1% is then 5 give-ups
/// or more, resolved); below that only counts implausible at 0.1% fail.
const RESOLVED_QUERIES: usize = 5_000;

impl Tally {
    /// Prints the totals and the give-up rate per family, then asserts no failures, fewer
    /// give-ups than 0.1% of the queries, and per family: a count that a rate of 0.1% would
    /// reach with probability below `1e-3` fails, and with [`RESOLVED_QUERIES`] or more queries
    /// a rate of 0.1% or more fails.
    fn report(&self, what: &str) {
        eprintln!(
            "{what}: {} queries, {} give-ups ({:.3}%; {} of them PerTriangle), {} Monte Carlo checks ({} re-estimated), {} failures",
            self.queries,
            self.gave_up,
            100.0 * self.gave_up as f64 / self.queries as f64,
            self.gave_up_per_triangle,
            self.mc_checks,
            self.mc_retested,
            self.failures.len()
        );
        let mut over = Vec::new();
        for (family, &(q, g)) in &self.families {
            eprintln!(
                "  {family:<48} {q:>7} queries {g:>4} give-ups ({:.3}%)",
                100.0 * g as f64 / q as f64
            );
            let tail = binomial_tail(q, g, MAX_RATE);
            if tail < 1e-3 || (q >= RESOLVED_QUERIES && g as f64 >= MAX_RATE * q as f64) {
                over.push(format!(
                    "{family}: {g} give-ups in {q} queries (P(>= {g} | 0.1%) = {tail:.1e})"
                ));
            }
        }
        assert!(
            self.failures.is_empty(),
            "{} failures:\n{}",
            self.failures.len(),
            self.failures.join("\n")
        );
        assert!(
            self.gave_up * 1000 < self.queries,
            "{} give-ups in {} queries",
            self.gave_up,
            self.queries
        );
        assert!(
            over.is_empty(),
            "families over the give-up rate of 0.1%:\n{}",
            over.join("\n")
        );
    }
}

fn cases() -> u64 {
    std::env::var("CENSUS_CASES")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(1)
}

/// Whether `CENSUS_ONLY=case:point` names another point than this one (to rerun one point, with
/// `CENSUS_VERBOSE` for its arguments and `CENSUS_DUMP=case` for its scene).
fn skipped(case: u64, i: usize) -> bool {
    std::env::var("CENSUS_ONLY").is_ok_and(|only| only != format!("{case}:{i}"))
}

/// Prints the scene's geometry when `CENSUS_DUMP` names this case.
fn dump(case: u64, scene: &Scene) {
    if std::env::var("CENSUS_DUMP").is_ok_and(|d| d == case.to_string()) {
        for l in scene.lights() {
            let m = l.shape().mesh();
            eprintln!("DUMP light {:?} {:?}", m.vertices(), m.triangles());
        }
        for o in scene.occluders() {
            let m = o.mesh();
            eprintln!("DUMP occ {:?} {:?}", m.vertices(), m.triangles());
        }
    }
}

/// How a point is compared with the Monte Carlo reference, if at all.
#[derive(Clone, Copy)]
struct McCheck {
    samples: u32,
    seed: u64,
}

/// What light 0 of `base` can send at most: its radiance times the directional albedo of the
/// material, the diffuse albedo plus the GGX table's albedo with Schlick's Fresnel at the
/// point's view angle (the whole upper hemisphere covered by the light).
fn albedo_bound(base: &Scene, (x, n, v): (DVec3, DVec3, DVec3), m: &Material) -> DVec3 {
    let cos_v = ShadingFrame::new(x, n, v).unwrap().view().z;
    let spec = if m.has_specular() {
        let look = arealight::ltc::lookup(cos_v, m.alpha()).unwrap();
        m.f0()
            .map(|f0| look.albedo * (f0 + (1.0 - f0) * look.fresnel))
    } else {
        DVec3::ZERO
    };
    base.lights()[0].radiance() * (m.albedo() + spec)
}

/// How much the per-triangle value of light 0 changes, per lobe (diffuse, specular), when `x`
/// moves across the facing predicate's band of a face plane it lies in (`face_side` says
/// `Side::On`: within `FACE_TOLERANCE` times the mesh's bounding radius plus its distance from
/// the centre), per channel: the largest change from `x` to the two points of the band's edges
/// (at 0.999 of the tolerance) on the normal through `x`, over every such face of every object.
/// Zero for a point in no band.
///
/// Inside the band the model is not unique: the face covers nothing from there, and the
/// silhouette of a convex occluder takes the point as on its surface (the region behind it is
/// exactly the half-space behind that face plane, `solid::silhouette::convex_silhouette`),
/// while the per-triangle method projects the occluder's other triangles from the point as it
/// is. The two meet at the plane, so they differ by at most this spread. It is rounding-sized
/// for the Lambertian lobe (`1e-12` of the value) but not for a near-mirror lobe whose peak
/// lies on the face plane: from a point `4.9e-14` off a box face (band `4e-13`) with the mirror
/// direction along that face, the two methods differed by `3.5e-7` of the value at roughness
/// 0, and the per-triangle value changes by `3.6e-8` per `1e-14` of offset.
fn facing_band_spread(
    base: &Scene,
    (x, n, v): (DVec3, DVec3, DVec3),
    m: &Material,
    at_x: &LightShading,
) -> (DVec3, DVec3) {
    let per = base.clone().with_method(Method::PerTriangle);
    let meshes = base
        .lights()
        .iter()
        .map(|l| l.shape().mesh())
        .chain(base.occluders().iter().map(Body::mesh));
    let (mut diffuse, mut specular) = (DVec3::ZERO, DVec3::ZERO);
    for mesh in meshes {
        let b = mesh.bounding_sphere();
        let tol = FACE_TOLERANCE * (b.radius + (x - b.center).length());
        for f in (0..mesh.triangle_count()).filter(|&f| face_side(mesh, f, x) == Side::On) {
            let nf = mesh.triangle_normal(f);
            let s = nf.dot(x - mesh.triangle(f)[0]);
            for edge in [-0.999 * tol, 0.999 * tol] {
                let y = x + nf * (edge - s);
                if let Ok(parts) = per.shade_per_light(y, n, v, m) {
                    diffuse = diffuse.max((parts[0].diffuse - at_x.diffuse).abs());
                    specular = specular.max((parts[0].specular - at_x.specular).abs());
                }
            }
        }
    }
    (diffuse, specular)
}

/// The boundary displacement, in radians, within which two decompositions of one region may
/// place an edge: the sphere layer's vertex-merge distance (`sphere::MATCH_TOLERANCE`), also
/// the order of its booleans' snapping in wide gnomonic charts (`planar::SNAP_REL`, `1.4e-14`
/// of coordinates up to `1e5`).
const BOUNDARY_RESOLUTION: f64 = 1e-9;

/// Whether the two methods' values of one light agree: each lobe within `1e-9` of its
/// unshadowed value plus the facing band's spread ([`facing_band_spread`], computed only when
/// needed), and the specular lobe also within what moving a boundary by
/// [`BOUNDARY_RESOLUTION`] can change: a lobe of width `alpha` (at least the table's smallest,
/// `1e-4`) integrates to at most about `1 / alpha` per radian across a boundary through its
/// peak, so `BOUNDARY_RESOLUTION / alpha` of its value; and both within `1e-12` of what the
/// light can send at most, the integrals' rounding (a box far in a mirror lobe's tail, seen at
/// a grazing view, gave `7.7e-21` on one method and `7.4e-21` on the other, found by the
/// `shade_regimes` fuzz target). (A point `1.3e-12` inside a box face,
/// outside the band, with a mirror lobe at roughness 0.01 along that face: the per-triangle
/// union of the box's faces left a gap of `1.3e-10` sr where the silhouette covers everything,
/// `1.1e-11` of the diffuse value and `7.5e-6` of the specular one.) Returns the failure's
/// description.
fn methods_disagree(
    base: &Scene,
    (x, n, v): (DVec3, DVec3, DVec3),
    m: &Material,
    a: &LightShading,
    b: &LightShading,
) -> Option<String> {
    let floor = albedo_bound(base, (x, n, v), m) * 1e-12 + 1e-300;
    let slack_d = a.unshadowed_diffuse.max(b.unshadowed_diffuse) * 1e-9 + floor;
    let u_s = a.unshadowed_specular.max(b.unshadowed_specular);
    let slack_s = u_s * (1e-9 + BOUNDARY_RESOLUTION / m.alpha().max(1e-4)) + floor;
    let (dd, ds) = (
        (a.diffuse - b.diffuse).abs(),
        (a.specular - b.specular).abs(),
    );
    let within = |sd: DVec3, ss: DVec3| {
        (0..3).all(|c| dd[c] <= slack_d[c] + sd[c] && ds[c] <= slack_s[c] + ss[c])
    };
    if within(DVec3::ZERO, DVec3::ZERO) {
        return None;
    }
    let (sd, ss) = facing_band_spread(base, (x, n, v), m, b);
    (!within(sd, ss)).then(|| {
        format!(
            "Silhouette {} + {} vs PerTriangle {} + {} (diffuse + specular; unshadowed {} + {}, facing band spread {sd} + {ss})",
            a.diffuse, a.specular, b.diffuse, b.specular, a.unshadowed_diffuse, a.unshadowed_specular
        )
    })
}

/// Shades one point of `base` (one light) with both methods and records what the census
/// asserts: a finite value with `0 <= shadowed <= unshadowed <=` the hemisphere bound, or a
/// give-up; the two methods in agreement ([`methods_disagree`]); and, with `mc`, the value
/// against the Monte Carlo reference
/// (light and BRDF sampling; see the module documentation for the bound).
#[allow(clippy::too_many_arguments)]
fn check_point(
    t: &mut Tally,
    family: &str,
    base: &Scene,
    (case, i): (u64, usize),
    (x, n, v): (DVec3, DVec3, DVec3),
    m: &Material,
    mc: Option<McCheck>,
) {
    let most = albedo_bound(base, (x, n, v), m);
    let mut values = Vec::new();
    for method in [Method::Silhouette, Method::PerTriangle] {
        let scene = base.clone().with_method(method);
        t.queries += 1;
        let fam = t.families.entry(family.to_string()).or_default();
        fam.0 += 1;
        match scene.shade_per_light(x, n, v, m) {
            Ok(parts) => {
                let p = parts[0];
                let (s, u) = (p.shadowed(), p.unshadowed());
                let ok = s.is_finite()
                    && u.is_finite()
                    && s.min_element() >= 0.0
                    && (s - u * (1.0 + 1e-9)).max_element() <= 1e-15
                    && (u - most * (1.0 + 1e-9)).max_element() <= 1e-15;
                if !ok {
                    t.failures.push(format!(
                        "case {case} point {i} ({family}) {method:?}: shadowed {s} unshadowed {u} at x {x:?} n {n:?} v {v:?}"
                    ));
                }
                values.push(p);
            }
            Err(e) if e.is_undecidable() => {
                t.gave_up += 1;
                fam.1 += 1;
                t.gave_up_per_triangle += usize::from(method == Method::PerTriangle);
                if std::env::var("CENSUS_VERBOSE").is_ok() {
                    eprintln!(
                        "gave up: case {case} point {i} ({family}) {method:?}: {e}\n  x {x:?} n {n:?} v {v:?}"
                    );
                }
            }
            Err(e) => t.failures.push(format!(
                "case {case} point {i} ({family}) {method:?}: error {e:?} at x {x:?} n {n:?} v {v:?}"
            )),
        }
    }
    if let [a, b] = &values[..]
        && let Some(what) = methods_disagree(base, (x, n, v), m, a, b)
    {
        t.failures.push(format!(
            "case {case} point {i} ({family}): {what} at x {x:?} n {n:?} v {v:?}"
        ));
    }
    let Some(mc) = mc else { return };
    let Some(a) = values.first().map(LightShading::shadowed) else {
        return;
    };
    let est = |samples: u32, seed: u64| {
        MonteCarlo::new(samples, ReferenceBrdf::Ltc)
            .with_sampling(LightSampling::Faces)
            .with_brdf_sampling()
            .estimate(base, x, n, v, m, seed)
            .unwrap()
    };
    let slack = |c: usize| 1e-6 * a[c] + 1e-9 * most[c];
    let agrees =
        |e: &Estimate, c: usize| (a[c] - e.mean[c]).abs() <= 4.5 * e.std_error[c] + slack(c);
    t.mc_checks += 1;
    let e = est(mc.samples, mc.seed);
    if !(0..3).all(|c| agrees(&e, c)) {
        t.mc_retested += 1;
        let e2 = est(16 * mc.samples, !mc.seed);
        let hw = e2.bernstein_halfwidth(1e-6);
        for c in (0..3).filter(|&c| (a[c] - e2.mean[c]).abs() > hw[c] + slack(c)) {
            t.failures.push(format!(
                "case {case} point {i} ({family}) ch {c}: analytic {} mc {} +- {}, then {} +- {} (Bernstein {}) at x {x:?} n {n:?} v {v:?}",
                a[c], e.mean[c], e.std_error[c], e2.mean[c], e2.std_error[c], hw[c]
            ));
        }
    }
}

/// Names of the light kinds of [`random_light`].
const LIGHT_KINDS: [&str; 4] = ["quad", "box", "icosphere", "two sheets"];

#[test]
fn census_of_the_shade_families() {
    let mut rng = Rng::new(2424);
    let mut t = Tally::default();
    for case in 0..60 * cases() {
        let c = DVec3::new(
            rng.range(-0.5, 0.5),
            rng.range(-0.5, 0.5),
            rng.range(1.5, 2.5),
        );
        let body = random_light(&mut rng, c, case);
        let occ = occluders(&mut rng, c, &body);
        let has_sliver = occ.len() == 4;
        let base = Scene::new(
            vec![Light::new(body, DVec3::new(1.0, 0.8, 0.6)).unwrap()],
            occ,
        )
        .unwrap();
        dump(case, &base);
        let roughness = [0.0, 0.01, 0.05, 0.4][(case % 4) as usize];
        let m = Material::new(DVec3::splat(0.5), DVec3::splat(0.04), roughness).unwrap();
        for i in 0..40 {
            let (x, n, v, kind) = point(&mut rng, &base, i, has_sliver);
            if skipped(case, i) {
                continue;
            }
            // A point on one box inside another (the generator overlaps them): every ray leaves
            // through the outer box, unless it meets the light in the plane of a face of it
            // first. Each such point is checked against the reference.
            let inside = inside_a_convex_occluder(&base, x);
            let family = format!(
                "{} / {}",
                LIGHT_KINDS[(case % 4) as usize],
                POINT_KINDS[kind]
            );
            let mc = (i % 8 == 0 || inside).then_some(McCheck {
                samples: 4096,
                seed: case * 1000 + i as u64,
            });
            check_point(&mut t, &family, &base, (case, i), (x, n, v), &m, mc);
        }
    }
    t.report("census");
}

/// A light of the near-face family about `c`: a big quad (2 to 8 across) facing down, two
/// sheets 0.05..0.3 apart facing each other (an open mesh light, always taken face by face), a
/// box or an icosphere.
fn near_face_light(rng: &mut Rng, c: DVec3, kind: u64) -> Body {
    match kind % 4 {
        0 => {
            let s = rng.range(1.0, 4.0);
            TriangleMesh::quad(c, DVec3::Y * s, DVec3::X * s)
                .unwrap()
                .into()
        }
        1 => {
            let h = rng.range(0.5, 2.0);
            let gap = rng.range(0.05, 0.3);
            let below = c + DVec3::new(rng.range(-0.2, 0.2), rng.range(-0.2, 0.2), -gap);
            TriangleMesh::quad(c, DVec3::Y * h, DVec3::X * h)
                .unwrap()
                .merged(&TriangleMesh::quad(below, DVec3::X * h, DVec3::Y * h).unwrap())
                .unwrap()
                .into()
        }
        2 => ConvexPolyhedron::cuboid(
            c,
            DVec3::new(
                rng.range(0.3, 0.8),
                rng.range(0.3, 0.8),
                rng.range(0.2, 0.5),
            ),
        )
        .unwrap()
        .into(),
        _ => ConvexPolyhedron::icosphere(c, rng.range(0.3, 0.8), 1)
            .unwrap()
            .into(),
    }
}

/// A uniform point of triangle `f` of `mesh`.
fn point_on_triangle(rng: &mut Rng, mesh: &TriangleMesh, f: usize) -> DVec3 {
    let [a, b, c] = mesh.triangle(f);
    let (mut u, mut v) = (rng.f64(), rng.f64());
    if u + v > 1.0 {
        (u, v) = (1.0 - u, 1.0 - v);
    }
    a + u * (b - a) + v * (c - a)
}

/// A small convex occluder (radius `1e-1.7..1e-0.7`, an icosphere or a box) whose centre lies
/// within 0.8 of its radius of the plane of light triangle `f`, over the triangle: the face's
/// plane cuts it.
fn cut_occluder(rng: &mut Rng, light: &TriangleMesh, f: usize) -> Body {
    let r = 10f64.powf(rng.range(-1.7, -0.7));
    let centre =
        point_on_triangle(rng, light, f) + light.triangle_normal(f) * r * rng.range(-0.8, 0.8);
    if rng.f64() < 0.5 {
        ConvexPolyhedron::icosphere(centre, r, 1).unwrap().into()
    } else {
        let h = DVec3::new(
            r * rng.range(0.5, 1.0),
            r * rng.range(0.5, 1.0),
            r * rng.range(0.5, 1.0),
        );
        ConvexPolyhedron::cuboid(centre, h).unwrap().into()
    }
}

/// Names of the point kinds of [`near_face_point`].
const NEAR_FACE_POINTS: [&str; 3] = [
    "near an occluder face",
    "near the face over the occluder",
    "near the face anywhere",
];

/// A shading point of the near-face family, in front of light triangle `f`:
/// - kind 0: on a face of the occluder that is not wholly behind `f`'s plane, moved off that
///   face by `1e-13..1e-3` of the occluder's radius, inwards or outwards (inside or just outside
///   the occluder, close to the part of it that the face's plane cuts);
/// - kind 1: `1e-6..1e-2` in front of `f`'s plane, over the occluder's footprint (inside it
///   where its cut disc is);
/// - kind 2: `1e-6..1e-2` in front of a point of `f` (a big face seen from close covers nearly
///   a hemisphere).
///
/// Normals: uniform half of the time, else parallel to `f`'s plane or facing it. `None` when the
/// draw lies behind `f`'s plane.
fn near_face_point(
    rng: &mut Rng,
    light: &TriangleMesh,
    f: usize,
    occ: &TriangleMesh,
    kind: usize,
) -> Option<(DVec3, DVec3, DVec3)> {
    let (a, nf) = (light.triangle(f)[0], light.triangle_normal(f));
    let r = occ.bounding_sphere().radius;
    let near = 10f64.powf(rng.range(-6.0, -2.0));
    let x = match kind {
        0 => {
            let t = rng.below(occ.triangle_count());
            let sign = if rng.f64() < 0.5 { -1.0 } else { 1.0 };
            point_on_triangle(rng, occ, t)
                + occ.triangle_normal(t) * sign * r * 10f64.powf(rng.range(-13.0, -3.0))
        }
        1 => {
            let c = occ.bounding_sphere().center;
            let (u, w) = nf.any_orthonormal_pair();
            let on_plane = c - nf * nf.dot(c - a);
            on_plane + (u * rng.range(-1.0, 1.0) + w * rng.range(-1.0, 1.0)) * r + nf * near
        }
        _ => point_on_triangle(rng, light, f) + nf * near,
    };
    if nf.dot(x - a) <= 0.0 {
        return None;
    }
    let n = match rng.below(4) {
        0 | 1 => rng.dir(),
        2 => {
            let (u, w) = nf.any_orthonormal_pair();
            let phi = rng.range(0.0, std::f64::consts::TAU);
            u * phi.cos() + w * phi.sin()
        }
        _ => -nf,
    };
    let v = if rng.f64() < 0.5 {
        view_above(rng, n, 0.0)
    } else {
        let c = rng.range(1e-4, 0.05);
        let (t, _) = n.any_orthonormal_pair();
        n * c + t * (1.0 - c * c).sqrt()
    };
    Some((x, n, v))
}

/// The family of the `sheet_light_seen_from_inside_a_small_icosphere_it_cuts` regression
/// (tests/shade_regressions.rs): small convex occluders that a light face's plane cuts, shading
/// points inside or just outside them, points `1e-6..1e-2` from a light face, big faces seen
/// from close. Asserted as in [`census_of_the_shade_families`], with the Monte Carlo reference
/// on every fourth point sampling the light's front faces (independent of the light regions
/// under test).
#[test]
fn census_of_points_near_cut_light_faces() {
    let mut rng = Rng::new(2525);
    let mut t = Tally::default();
    for case in 0..40 * cases() {
        let c = DVec3::new(
            rng.range(-0.5, 0.5),
            rng.range(-0.5, 0.5),
            rng.range(1.5, 2.5),
        );
        let body = near_face_light(&mut rng, c, case);
        let lm = body.mesh().clone();
        let f = rng.below(lm.triangle_count());
        let occ = cut_occluder(&mut rng, &lm, f);
        let om = occ.mesh().clone();
        let base = Scene::new(
            vec![Light::new(body, DVec3::new(1.0, 0.8, 0.6)).unwrap()],
            vec![occ],
        )
        .unwrap();
        dump(case, &base);
        let roughness = [0.0, 0.01, 0.05, 0.4][(case % 4) as usize];
        let m = Material::new(DVec3::splat(0.5), DVec3::splat(0.04), roughness).unwrap();
        for i in 0..24 {
            // Points behind the face's plane are drawn again (a few times), so that every kind
            // gets about as many queries.
            let Some((x, n, v)) =
                (0..8).find_map(|_| near_face_point(&mut rng, &lm, f, &om, i % 3))
            else {
                continue;
            };
            if skipped(case, i) {
                continue;
            }
            let family = format!(
                "{} / {}",
                ["big quad", "two sheets", "box", "icosphere"][(case % 4) as usize],
                NEAR_FACE_POINTS[i % 3]
            );
            let mc = (i % 4 == 0).then_some(McCheck {
                samples: 4096,
                seed: case * 1000 + i as u64,
            });
            check_point(&mut t, &family, &base, (case, i), (x, n, v), &m, mc);
        }
    }
    t.report("near-face census");
}

/// Invalid arguments stay input faults in these scenes too.
#[test]
fn invalid_arguments_are_input_faults() {
    let mut rng = Rng::new(7);
    let c = DVec3::new(0.0, 0.0, 2.0);
    let body = random_light(&mut rng, c, 0);
    let occ = occluders(&mut rng, c, &body);
    let scene = Scene::new(vec![Light::new(body, DVec3::ONE).unwrap()], occ).unwrap();
    let m = Material::diffuse(DVec3::splat(0.5)).unwrap();
    let nan = DVec3::new(f64::NAN, 0.0, 1.0);
    for (x, n, v) in [
        (nan, DVec3::Z, DVec3::Z),
        (DVec3::ZERO, nan, DVec3::Z),
        (DVec3::ZERO, DVec3::Z, nan),
    ] {
        assert!(matches!(
            scene.shade(x, n, v, &m),
            Err(GeomError::NonFiniteArgument { .. })
        ));
    }
    assert!(matches!(
        scene.shade(DVec3::ZERO, DVec3::ZERO, DVec3::Z, &m),
        Err(GeomError::ZeroLengthArgument { .. })
    ));
}
