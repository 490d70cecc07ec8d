//! `BezierShape`: validation errors that name the loop and the segment, joins made identical,
//! the exact area, containment and area sampling against a fine polygonization, and the
//! per-point regions against the sphere layer's full validation.

mod support;

use arealight::GeomError;
use arealight::glam::{DVec2, DVec3};
use arealight::shade::ShadingFrame;
use arealight::solid::{BezierSegment, BezierShape};
use arealight::sphere::SphericalPolygon;
use support::Rng;
use support::bezier::{Plane, Seg2, blob, letter_d, shape};

fn flat(p: DVec2) -> DVec3 {
    DVec3::new(p.x, p.y, 1.0)
}

/// The outline's loops in the plane z = 1, as `BezierSegment`s.
fn loops3(loops: &[Vec<Seg2>]) -> Vec<Vec<BezierSegment>> {
    loops
        .iter()
        .map(|l| {
            l.iter()
                .map(|s| match *s {
                    Seg2::Line(a, b) => BezierSegment::Line([flat(a), flat(b)]),
                    Seg2::Cubic(p) => BezierSegment::Cubic(p.map(flat)),
                })
                .collect()
        })
        .collect()
}

fn expect(loops: Vec<Vec<BezierSegment>>, ring: usize, segment: usize, what: &str) {
    match BezierShape::new(loops) {
        Err(GeomError::InvalidCurve {
            ring: r,
            segment: s,
            why,
        }) => {
            assert_eq!((r, s), (ring, segment), "{what}: {why}");
            // The message is meant for people.
            let msg = GeomError::InvalidCurve {
                ring: r,
                segment: s,
                why,
            }
            .to_string();
            assert!(msg.contains(&format!("loop {r}")) && msg.contains(&format!("segment {s}")));
        }
        other => panic!("{what}: expected InvalidCurve at ({ring}, {segment}), got {other:?}"),
    }
}

fn set_point(l: &mut [Vec<BezierSegment>], r: usize, s: usize, k: usize, v: DVec3) {
    match &mut l[r][s] {
        BezierSegment::Line(p) => p[k] = v,
        BezierSegment::Cubic(p) => p[k] = v,
        _ => panic!("a segment kind these tests do not know"),
    }
}

#[test]
fn validation_errors_name_the_loop_and_the_segment() {
    let d = loops3(&letter_d());
    assert!(BezierShape::new(d.clone()).is_ok());

    let mut l = d.clone();
    set_point(&mut l, 1, 1, 1, DVec3::new(f64::NAN, 0.0, 1.0));
    expect(l, 1, 1, "NaN control point");
    let mut l = d.clone();
    set_point(&mut l, 0, 2, 2, DVec3::new(0.0, f64::INFINITY, 1.0));
    expect(l, 0, 2, "infinite control point");
    let mut l = d.clone();
    set_point(&mut l, 0, 1, 1, DVec3::new(0.0, 1e101, 1.0));
    expect(l, 0, 1, "control point out of range");
    // A gap between segments 1 and 2 of the outer loop.
    let mut l = d.clone();
    set_point(&mut l, 0, 2, 0, DVec3::new(1.0, 0.01, 1.0));
    expect(l, 0, 2, "gap");
    // The hole's last segment ends away from its start.
    let mut l = d.clone();
    let last = l[1].len() - 1;
    let k = l[1][last].control_points().len() - 1;
    set_point(&mut l, 1, last, k, DVec3::new(-0.6, 0.61, 1.0));
    expect(l, 1, last, "open loop");
    // A control point off the plane.
    let mut l = d.clone();
    set_point(&mut l, 1, 1, 2, DVec3::new(0.6, -0.5, 1.001));
    expect(l, 1, 1, "off the plane");
    // A zero-length line inside a loop.
    let mut l = d.clone();
    let p = l[0][1].start();
    l[0].insert(1, BezierSegment::Line([p, p]));
    expect(l, 0, 1, "zero-length segment");
    // The hole running the wrong way (counter-clockwise, like the outer loop).
    let mut l = d.clone();
    l[1] = l[1].iter().rev().map(BezierSegment::reversed).collect();
    expect(l, 1, 0, "hole oriented as an outer loop");
    // A clockwise loop outside the outer one: a hole with nothing around it.
    let mut l = d.clone();
    l[1] = l[1].iter().map(|s| s.map(|p| p + DVec3::X * 5.0)).collect();
    expect(l, 1, 0, "hole outside");
    // The hole pushed across the outer boundary.
    let mut l = d.clone();
    l[1] = l[1].iter().map(|s| s.map(|p| p + DVec3::X * 0.6)).collect();
    let e = BezierShape::new(l).unwrap_err();
    assert!(
        matches!(e, GeomError::InvalidCurve { why, .. } if why.contains("crosses")),
        "{e:?}"
    );
    // A figure eight with lobes of different sizes: one loop crossing itself.
    let p = DVec2::new;
    let eight = vec![vec![
        Seg2::Cubic([p(0.0, 0.0), p(1.0, 1.0), p(2.0, 1.0), p(2.0, 0.0)]),
        Seg2::Cubic([p(2.0, 0.0), p(2.0, -1.0), p(1.0, -1.0), p(0.0, 0.0)]),
        Seg2::Cubic([p(0.0, 0.0), p(-1.5, 1.5), p(-3.0, 1.5), p(-3.0, 0.0)]),
        Seg2::Cubic([p(-3.0, 0.0), p(-3.0, -1.5), p(-1.5, -1.5), p(0.0, 0.0)]),
    ]];
    let e = BezierShape::new(loops3(&eight)).unwrap_err();
    assert!(
        matches!(e, GeomError::InvalidCurve { ring: 0, why, .. } if why.contains("crosses")),
        "{e:?}"
    );
    // A loop that encloses nothing: out and back along one curve.
    let c = Seg2::Cubic([p(0.0, 0.0), p(1.0, 1.0), p(2.0, 1.0), p(3.0, 0.0)]);
    let mut l = d.clone();
    l.push(loops3(&[vec![c, c.reversed()]]).remove(0));
    expect(l, 2, 0, "zero-area loop");
    // No loop, an empty loop.
    expect(vec![], 0, 0, "no loop");
    let mut l = d.clone();
    l.push(vec![]);
    expect(l, 2, 0, "empty loop");
}

#[test]
fn joins_within_tolerance_are_made_identical() {
    let mut l = loops3(&letter_d());
    set_point(&mut l, 0, 2, 0, DVec3::new(1.0, 1e-12, 1.0));
    let s = BezierShape::new(l).unwrap();
    for lp in s.loops() {
        for i in 0..lp.len() {
            assert_eq!(lp[i].end(), lp[(i + 1) % lp.len()].start());
        }
    }
}

/// The area of a polygon (shoelace).
fn poly_area(r: &[DVec2]) -> f64 {
    (0..r.len())
        .map(|i| r[i].perp_dot(r[(i + 1) % r.len()]))
        .sum::<f64>()
        / 2.0
}

/// The loops flattened with `n` chords per cubic, in 2D.
fn fine(loops: &[Vec<Seg2>], n: usize) -> Vec<Vec<DVec2>> {
    loops
        .iter()
        .map(|l| {
            let mut r = Vec::new();
            for s in l {
                match *s {
                    Seg2::Line(a, _) => r.push(a),
                    Seg2::Cubic(p) => {
                        for k in 0..n {
                            let t = k as f64 / n as f64;
                            let u = 1.0 - t;
                            r.push(
                                p[0] * u * u * u
                                    + p[1] * 3.0 * u * u * t
                                    + p[2] * 3.0 * u * t * t
                                    + p[3] * t * t * t,
                            );
                        }
                    }
                }
            }
            r
        })
        .collect()
}

fn winding(rings: &[Vec<DVec2>], q: DVec2) -> i32 {
    let mut w = 0;
    for r in rings {
        for i in 0..r.len() {
            let (a, b) = (r[i], r[(i + 1) % r.len()]);
            let side = (b - a).perp_dot(q - a);
            if a.y <= q.y && b.y > q.y && side > 0.0 {
                w += 1;
            } else if a.y > q.y && b.y <= q.y && side < 0.0 {
                w -= 1;
            }
        }
    }
    w
}

#[test]
fn area_mesh_and_containment_match_a_fine_polygon() {
    let outlines = [
        letter_d(),
        vec![blob(
            DVec2::new(0.2, -0.1),
            &[1.0, 0.6, 1.2, 0.8, 0.9],
            10,
            0.4,
        )],
    ];
    let mut rng = Rng::new(3);
    for o in &outlines {
        let s = BezierShape::new(loops3(o)).unwrap();
        let (a1, a2) = (
            fine(o, 20_000).iter().map(|r| poly_area(r)).sum::<f64>(),
            fine(o, 40_000).iter().map(|r| poly_area(r)).sum::<f64>(),
        );
        let exact = (4.0 * a2 - a1) / 3.0;
        assert!((s.area() - exact).abs() < 1e-12, "{} vs {exact}", s.area());
        let mesh = s.mesh();
        let mesh_area: f64 = (0..mesh.triangle_count())
            .map(|t| {
                let [a, b, c] = mesh.triangle(t);
                0.5 * (b - a).cross(c - a).length()
            })
            .sum();
        // The mesh is a flattening within 1e-3 of the extent (about 2): chords cut off at most
        // 2/3 of that per unit of boundary (perimeter below 12).
        assert!(
            (mesh_area - exact).abs() < 2.0 / 3.0 * 2e-3 * 12.0,
            "{mesh_area} vs {exact}"
        );
        assert!(
            mesh_area <= exact + 1e-12,
            "chords of convex parts cut off, concave add"
        );
        let (rings, half) = (fine(o, 2_000), fine(o, 1_000));
        let mut tested = 0;
        for _ in 0..4_000 {
            let q = DVec2::new(rng.range(-2.0, 2.0), rng.range(-2.0, 2.0));
            let w = winding(&rings, q);
            if w != winding(&half, q) {
                continue; // within the polygon's error of a curve: undecided here
            }
            tested += 1;
            assert_eq!(s.contains(flat(q)), w != 0, "{q}");
        }
        assert!(tested > 3_900);
    }
}

#[test]
fn samples_are_uniform_over_the_curved_region() {
    // The mean of uniform samples is the centroid; checked per coordinate at 4.5 sigma.
    let o = letter_d();
    let s = BezierShape::new(loops3(&o)).unwrap();
    let rings = fine(&o, 50_000);
    let (mut cx, mut cy, mut a) = (0.0, 0.0, 0.0);
    for r in &rings {
        for i in 0..r.len() {
            let (p, q) = (r[i], r[(i + 1) % r.len()]);
            let c = p.perp_dot(q);
            a += c / 2.0;
            cx += (p.x + q.x) * c / 6.0;
            cy += (p.y + q.y) * c / 6.0;
        }
    }
    let centroid = DVec2::new(cx / a, cy / a);
    let mut rng = Rng::new(11);
    let n = 40_000;
    let pts: Vec<DVec3> = (0..n).map(|_| s.sample(|| rng.f64()).unwrap()).collect();
    for (k, c) in [centroid.x, centroid.y].into_iter().enumerate() {
        let xs: Vec<f64> = pts.iter().map(|p| p[k]).collect();
        let mean = xs.iter().sum::<f64>() / n as f64;
        let var = xs.iter().map(|x| (x - mean) * (x - mean)).sum::<f64>() / (n - 1) as f64;
        let se = (var / n as f64).sqrt();
        assert!(
            (mean - c).abs() < 4.5 * se,
            "axis {k}: {mean} vs {c} +- {se}"
        );
    }
    assert!(
        pts.iter()
            .all(|p| (p.z - 1.0).abs() < 1e-12 && s.contains(*p))
    );
}

#[test]
fn regions_pass_the_sphere_layers_full_validation() {
    // The per-point regions skip SphericalPolygon::new's quadratic checks; they must pass them.
    let mut rng = Rng::new(29);
    let plane = Plane::new(DVec3::new(0.0, 0.0, 2.0), DVec3::new(0.2, 0.1, -1.0));
    let s = shape(&plane, &letter_d());
    let mut seen = 0;
    for i in 0..60 {
        let x = DVec3::new(
            rng.range(-3.0, 3.0),
            rng.range(-3.0, 3.0),
            rng.range(-1.0, 1.9),
        );
        // Distances from 0.1 to 4: several flattening levels.
        let frame = ShadingFrame::new(x, DVec3::Z, DVec3::new(0.3, 0.0, 1.0)).unwrap();
        let r = s.region(&frame).unwrap();
        if r.is_empty() {
            continue;
        }
        seen += 1;
        let rings: Vec<Vec<DVec3>> = r.rings().map(<[DVec3]>::to_vec).collect();
        let checked = SphericalPolygon::new(rings).unwrap_or_else(|e| panic!("point {i}: {e}"));
        assert!((checked.solid_angle() - r.solid_angle()).abs() < 1e-13);
    }
    assert!(seen > 40);
}
