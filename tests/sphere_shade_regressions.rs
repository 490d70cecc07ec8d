//! Regressions of the `sphere` layer found through the shading layer: spherical booleans and
//! horizon clips that the per-triangle path met (over 3000 ground points of the demo scene, and
//! in the `shade` fuzz target) and that once failed or gave wrong results. Repeated directions
//! after unprojection must be dropped, and a planar failure in one projection must be retried
//! through the octant split. Each is checked by an identity of areas (difference plus
//! intersection, inclusion-exclusion).
//!
//! The first is light-minus-occluder-triangle where the triangle (an occluder face seen from a
//! ground point) shares, up to 1e-15, an edge with the current visible region (which that face's
//! neighbour cut before).

use arealight::GeomError;
use arealight::glam::DVec3;
use arealight::planar::BoolOp;
use arealight::sphere::{COINCIDENT_TOLERANCE, SphericalPolygon, order_directed_edges};

#[test]
fn difference_with_nearly_shared_edge() {
    let a = SphericalPolygon::new(vec![vec![
        DVec3::new(-0.6690880280221996, -0.1568454495401529, 0.7264438833908037),
        DVec3::new(
            -0.5626500404802729,
            -0.21021721592028306,
            0.7995208903326244,
        ),
        DVec3::new(-0.5537970634980699, -0.14639720242518545, 0.819680835193183),
        DVec3::new(
            -0.5596900797691979,
            -0.14691706044559386,
            0.8155748843349545,
        ),
        DVec3::new(-0.603541450890866, -0.1359192926164673, 0.785661290220657),
        DVec3::new(
            -0.6444013730021253,
            -0.11284483557928683,
            0.7563153532462894,
        ),
    ]])
    .unwrap();
    let b = SphericalPolygon::new(vec![vec![
        DVec3::new(-0.6035414508908648, -0.13591929261646715, 0.785661290220658),
        DVec3::new(
            -0.6444013730021242,
            -0.11284483557928654,
            0.7563153532462903,
        ),
        DVec3::new(
            -0.6913513594738174,
            -0.20005646227339818,
            0.6942699112422752,
        ),
    ]])
    .unwrap();
    let d = a.boolean(&b, BoolOp::Difference).unwrap();
    let i = a.boolean(&b, BoolOp::Intersection).unwrap();
    assert!((d.solid_angle() + i.solid_angle() - a.solid_angle()).abs() < 1e-12);
}

/// Union of the front faces of a non-convex light (two boxes as one mesh, seen from the ground):
/// the accumulated region `a`, itself the output of earlier unions, holds two consecutive
/// vertices one ulp apart (vertices 6 and 7 of ring 0), which `SphericalPolygon::new` rejects, so
/// the union with the next triangle `b` cannot take it; boolean results must drop such repeats
/// (`close_ring` after unprojection).
///
/// The record is kept as it was produced, repeat included: the validator must still reject it
/// (a boolean output may never look like this), the edge-ordering path that silhouettes use must
/// merge the repeat into the same region, and the union with `b` must satisfy inclusion-exclusion
/// and return a valid region without such repeats.
#[test]
fn union_output_with_vertices_one_ulp_apart() {
    let recorded = vec![
        vec![
            DVec3::new(
                -0.36175618473541277,
                0.20497637343993824,
                0.9094598117218204,
            ),
            DVec3::new(-0.5962814845221478, 0.17650413789206332, 0.7831313303163416),
            DVec3::new(
                -0.5870561956422052,
                -0.24678037806458136,
                0.7710152191496632,
            ),
            DVec3::new(
                -0.3542682213495134,
                -0.28506731117442496,
                0.8906349731745523,
            ),
            DVec3::new(-0.3286400767374422, -0.264445234920668, 0.9066776812571051),
            DVec3::new(
                -0.17533513117624425,
                -0.2756601391752283,
                0.9451291337406242,
            ),
            DVec3::new(
                -0.18231806281494323,
                0.030383957073661202,
                0.9827700336924975,
            ),
            // One ulp from the vertex before it (x differs in the last bit).
            DVec3::new(
                -0.18231806281494325,
                0.030383957073661202,
                0.9827700336924975,
            ),
            DVec3::new(
                -0.29817465763899825,
                0.029496199089381555,
                0.9540554741633978,
            ),
            DVec3::new(-0.2941325026202947, 0.16665980083247847, 0.9411219802389067),
        ],
        vec![
            DVec3::new(
                -0.15353659076596454,
                0.025587421844233148,
                0.9878116212817756,
            ),
            DVec3::new(
                -0.18231806281494323,
                0.030383957073661202,
                0.9827700336924975,
            ),
            DVec3::new(
                -0.14929605831086426,
                -0.2347217693122634,
                0.9605292176627214,
            ),
        ],
    ];
    let (r6, r7) = (recorded[0][6], recorded[0][7]);
    assert!(
        r6 != r7 && (r6 - r7).length() < 1e-16,
        "the record holds the one-ulp repeat"
    );
    // The validator rejects the record at the repeat.
    assert_eq!(
        SphericalPolygon::new(recorded.clone()),
        Err(GeomError::CoincidentVertices { ring: 0, vertex: 6 })
    );
    // The region without the repeat, as a boolean returns it ...
    let mut dropped = recorded.clone();
    dropped[0].remove(7);
    let a = SphericalPolygon::new(dropped).expect("a boolean output must be a valid input");
    // ... is what the edge-ordering path makes of the record: endpoints within its tolerance are
    // one vertex, so the one-ulp edge vanishes (the pinch with ring 1 stays).
    let edges: Vec<(DVec3, DVec3)> = recorded
        .iter()
        .flat_map(|r| (0..r.len()).map(move |i| (r[i], r[(i + 1) % r.len()])))
        .collect();
    let ordered = order_directed_edges(&edges).expect("the record's edges form valid loops");
    assert_eq!(ordered.vertex_count(), a.vertex_count());
    assert!((ordered.solid_angle() - a.solid_angle()).abs() <= 1e-15);
    let b = SphericalPolygon::new(vec![vec![
        DVec3::new(
            -0.18231806281494323,
            0.03038395707366121,
            0.9827700336924975,
        ),
        DVec3::new(
            -0.17533513117624425,
            -0.27566013917522836,
            0.9451291337406242,
        ),
        DVec3::new(
            -0.14929605831086426,
            -0.23472176931226346,
            0.9605292176627214,
        ),
    ]])
    .unwrap();
    for a in [&a, &ordered] {
        let u = a.boolean(&b, BoolOp::Union).unwrap();
        let i = a.boolean(&b, BoolOp::Intersection).unwrap();
        // Inclusion-exclusion: |A u B| + |A n B| = |A| + |B|.
        let (su, si, sa, sb) = (
            u.solid_angle(),
            i.solid_angle(),
            a.solid_angle(),
            b.solid_angle(),
        );
        assert!(
            (su + si - sa - sb).abs() <= 1e-12,
            "|A u B| {su} + |A n B| {si} vs |A| {sa} + |B| {sb}"
        );
        assert!(su >= sa.max(sb) - 1e-12);
        // The union is a valid input again: no repeated vertices, within the validator's
        // tolerance or one ulp apart.
        let rings: Vec<Vec<DVec3>> = u.rings().map(<[DVec3]>::to_vec).collect();
        for r in &rings {
            for k in 0..r.len() {
                let d = (r[k] - r[(k + 1) % r.len()]).length();
                assert!(
                    d > COINCIDENT_TOLERANCE,
                    "repeated vertex in the union: {d}"
                );
            }
        }
        let again = SphericalPolygon::new(rings).expect("the union must be a valid input");
        assert!((again.solid_angle() - su).abs() <= 1e-15);
    }
}

/// Found by the `shade` fuzz target (a quad light seen from just inside an icosphere light, the
/// per-triangle method): the light's piece `a`, a sliver 1.4e-3 rad high standing on the horizon,
/// minus the icosphere triangle `b` that shares its apex within ulps and whose base lies on the
/// horizon too. Both operands are valid; the difference comes back as a ring that runs back along
/// the horizon over itself (rejected by `SphericalPolygon::new` as self-intersecting), and the
/// next difference of that ring returns the full sphere. The shading layer reports
/// `GeomError::Undecidable` there (a region outside the upper hemisphere is a give-up); the
/// sphere layer must return a valid region.
#[test]
fn difference_of_horizon_slivers_sharing_an_apex() {
    let a = SphericalPolygon::new(vec![vec![
        DVec3::new(
            -0.9669546669374918,
            -0.25494466336659527,
            0.0013750304352578549,
        ),
        DVec3::new(
            -0.9678674481974813,
            -0.2514609367669185,
            -4.0197028831512847e-17,
        ),
        DVec3::new(
            -0.9661291992438289,
            -0.2580588505912522,
            -8.091461391699859e-17,
        ),
    ]])
    .unwrap();
    let b = SphericalPolygon::new(vec![vec![
        DVec3::new(-0.9670818850861547, -0.2544653759123426, 0.0),
        DVec3::new(
            -0.9669546669374915,
            -0.2549446633665955,
            0.0013750304352579538,
        ),
        DVec3::new(-0.967867448197481, -0.25146093676691866, 0.0),
    ]])
    .unwrap();
    let d = a.boolean(&b, BoolOp::Difference).unwrap();
    let i = a.boolean(&b, BoolOp::Intersection).unwrap();
    let rings: Vec<Vec<DVec3>> = d.rings().map(<[DVec3]>::to_vec).collect();
    assert!(
        SphericalPolygon::new(rings.clone()).is_ok(),
        "a boolean output must be a valid input: {rings:?}"
    );
    assert!((d.solid_angle() + i.solid_angle() - a.solid_angle()).abs() < 1e-15);
}

/// Found by the `shade` fuzz target (an icosphere light's front triangle in the face-by-face
/// path, seen from a point in the plane of an occluder quad): the triangle's one vertex above the
/// horizon is `3.6e-14` up, just beyond `HORIZON_TOLERANCE`, so the part above the horizon is a
/// sliver of about `1e-27` sr. The clip returns the whole upper hemisphere instead (the sliver's
/// exit and entry points are `1e-14` apart and get joined the long way round the circle), so the
/// light's radiance at that point came out 187 times its unoccluded value. The two halves of a
/// clip must add up to the polygon. The shading layer now checks clips that add long horizon arcs
/// and gives up there (`GeomError::Undecidable`).
#[test]
fn clip_of_a_vertex_just_above_the_horizon() {
    let p = SphericalPolygon::new(vec![vec![
        DVec3::new(
            -0.7010078725212144,
            0.6881619193503733,
            -0.18713934759769518,
        ),
        DVec3::new(
            -0.7545711152106989,
            0.656218280825582,
            3.6143816366547235e-14,
        ),
        DVec3::new(
            -0.7137295842095911,
            0.6984466175673911,
            -0.05255856764291619,
        ),
    ]])
    .unwrap();
    // A second instance (a light's triangle seen from 7e-12 above an open mesh it rests in): the
    // vertex above the horizon is 8e-12 up, far beyond the tolerance, and the polygon 3e-6 sr.
    let q = SphericalPolygon::new(vec![vec![
        DVec3::new(0.6014307008343528, -0.798195315891146, -0.03413721991218593),
        DVec3::new(
            0.6107633040469715,
            -0.791813226985775,
            8.033556869469265e-12,
        ),
        DVec3::new(
            0.6047048993859554,
            -0.7961461473466394,
            -0.021984010637841882,
        ),
    ]])
    .unwrap();
    for p in [p, q] {
        let (up, down) = (
            p.clip_to_hemisphere(DVec3::Z),
            p.clip_to_hemisphere(-DVec3::Z),
        );
        assert!(
            (up.solid_angle() + down.solid_angle() - p.solid_angle()).abs() <= 1e-15,
            "up {} + down {} vs {}",
            up.solid_angle(),
            down.solid_angle(),
            p.solid_angle()
        );
    }
}

/// Found by tests/shade_exact.rs on new random inputs (scene "piercing convex lights": a tilted
/// cylinder through a cuboid light, shaded on the cylinder just outside the light's corner): a
/// cut cylinder triangle whose edge runs within `1.2e-14` above the horizon over 2.2 rad. Its
/// clip comes back as a ring that runs over itself along the horizon (invalid, solid angle
/// `2.6e-14`), and subtracting that from the light's face removed 0.25 sr, 18% of the light.
/// The clip must be a valid region and the two halves must add up to the polygon, up to the
/// part above the horizon: a sliver under that edge, thinner than validation accepts, which the
/// clip drops (its area is at most the edge's greatest height above the horizon, its ends'
/// heights times the bulge `2 / |a + b|` of a minor arc, times its length).
#[test]
fn clip_of_an_edge_running_just_above_the_horizon() {
    let p = SphericalPolygon::new(vec![vec![
        DVec3::new(
            0.148073552271463,
            -0.9889763511417805,
            1.1761737919259338e-14,
        ),
        DVec3::new(
            -0.8401477477352683,
            0.5423575960336094,
            6.217089305014665e-16,
        ),
        DVec3::new(
            -0.5220330003478331,
            -0.7463991230975453,
            -0.4127588831110173,
        ),
    ]])
    .unwrap();
    let (up, down) = (
        p.clip_to_hemisphere(DVec3::Z),
        p.clip_to_hemisphere(-DVec3::Z),
    );
    let rings: Vec<Vec<DVec3>> = up.rings().map(<[DVec3]>::to_vec).collect();
    assert!(
        up.is_empty() || SphericalPolygon::new(rings.clone()).is_ok(),
        "the clip must be a valid region: {rings:?}"
    );
    up.validate().unwrap();
    down.validate().unwrap();
    let r: Vec<DVec3> = p.rings().next().unwrap().to_vec();
    let (a, b) = (r[0], r[1]);
    let sliver = a.z.max(b.z) * 2.0 / (a + b).length() * a.cross(b).length().atan2(a.dot(b));
    assert!(sliver < 1e-13);
    assert!(
        (up.solid_angle() + down.solid_angle() - p.solid_angle()).abs() <= sliver + 1e-15,
        "{} + {} vs {}",
        up.solid_angle(),
        down.solid_angle(),
        p.solid_angle()
    );
}

/// Found by the `shade` fuzz target (an icosphere light cut by a sheet light, seen from just
/// outside one of its faces, the face-by-face path): `a`, the face's part above the horizon, has
/// two vertices nearly antipodal (an edge of almost pi), and so has the cut sheet triangle `b`,
/// which holds all of `a` (`a n b = a`). `a - b` comes back as the upper hemisphere (2 pi)
/// instead of (nearly) nothing. The identity `|a - b| + |a n b| = |a|` must hold.
#[test]
fn difference_of_polygons_with_nearly_antipodal_vertices() {
    let a = SphericalPolygon::new(vec![vec![
        DVec3::new(
            0.27326640482723313,
            -0.9619379209849311,
            0.0009529763833586439,
        ),
        DVec3::new(0.8844435239984797, 0.26727805043586095, 0.38252071396508225),
        DVec3::new(
            -0.27326618423131566,
            0.9619371444548689,
            0.001588292690104681,
        ),
    ]])
    .unwrap();
    let b = SphericalPolygon::new(vec![vec![
        DVec3::new(-0.2732093735695792, 0.9619545925841397, 0.0),
        DVec3::new(
            -0.27326651667783897,
            0.9619383147155081,
            0.00029924078655490204,
        ),
        DVec3::new(
            0.2732665216190526,
            -0.9619383321093066,
            0.00023104326199104423,
        ),
        DVec3::new(0.2733106905806763, -0.9619258112839647, 0.0),
        DVec3::new(0.9619402032679626, 0.27326003245405417, -0.0),
    ]])
    .unwrap();
    let d = a.boolean(&b, BoolOp::Difference).unwrap();
    let i = a.boolean(&b, BoolOp::Intersection).unwrap();
    assert!(
        (d.solid_angle() + i.solid_angle() - a.solid_angle()).abs() <= 1e-12,
        "|a - b| {} + |a n b| {} vs |a| {}",
        d.solid_angle(),
        i.solid_angle(),
        a.solid_angle()
    );
}
