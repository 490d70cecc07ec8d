//! Scene checks a renderer runs once after building a scene ([`Scene::validate`]): mistakes that
//! are valid input, so no constructor rejects them, but that give a black or a wrong image
//! without any error.

use alloc::vec::Vec;
use core::fmt;

use glam::{DVec2, DVec3};

use super::scene::{Light, Scene};
use crate::IntoDVec3;
use crate::solid::facing::{Side, face_side};
use crate::solid::{Body, TriangleMesh};

/// One finding of [`Scene::validate`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum SceneIssue {
    /// Light `light` shows no front face to any point the check knows (every vertex of the
    /// occluders and of the other lights, and the receiver points passed to
    /// [`Scene::validate`]): it lights none of them. Usually a quad built with its half-edges
    /// in the wrong order (`TriangleMesh::quad(c, u, v)` emits towards `u x v`): swap them,
    /// turn the mesh around ([`TriangleMesh::flipped`]) or make the light two-sided
    /// ([`Light::two_sided`]).
    LightFacesAway {
        /// Index of the light.
        light: usize,
    },
    /// Planar lights `a` and `b` lie in one plane, face the same way and overlap: neither hides
    /// the other (nothing in a light's plane blocks it), so the overlap emits twice. Merge them
    /// or move one.
    OverlappingLights {
        /// Index of the first light.
        a: usize,
        /// Index of the second light.
        b: usize,
    },
}

impl fmt::Display for SceneIssue {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            SceneIssue::LightFacesAway { light } => write!(
                f,
                "light {light} faces away from every occluder, other light and receiver point: \
                 it lights nothing (a quad(c, u, v) emits towards u x v; swap u and v, use \
                 TriangleMesh::flipped or Light::two_sided)"
            ),
            SceneIssue::OverlappingLights { a, b } => write!(
                f,
                "lights {a} and {b} are coplanar, face the same way and overlap, so the overlap \
                 emits twice; merge them or move one"
            ),
        }
    }
}

/// What [`Scene::validate`] found: empty for a scene without the mistakes it looks for.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct SceneReport {
    /// The findings, lights in order.
    pub issues: Vec<SceneIssue>,
}

impl SceneReport {
    /// Whether nothing was found.
    #[must_use]
    pub fn is_clean(&self) -> bool {
        self.issues.is_empty()
    }
}

impl fmt::Display for SceneReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.issues.is_empty() {
            return f.write_str("no scene issues found");
        }
        for (k, issue) in self.issues.iter().enumerate() {
            if k > 0 {
                f.write_str("\n")?;
            }
            write!(f, "{issue}")?;
        }
        Ok(())
    }
}

impl Scene {
    /// Looks for scene mistakes that no constructor can reject because each object is valid
    /// alone, but that make a black or a wrong image without any error ([`SceneIssue`]):
    ///
    /// - a light that shows no front face ([`Light`], "Which side emits") to any point of the
    ///   scene: the vertices of the occluders and of the other lights, and `receivers`, points
    ///   the renderer shades that are not on an occluder (a ground plane it draws itself; pass
    ///   `&[] as &[DVec3]` when there are none). A light with no such point at all is not
    ///   reported (nothing to reason about);
    /// - coplanar planar lights facing the same way that overlap: both emit where they overlap
    ///   (nothing in a light's plane hides it), so the overlap emits twice. (Overlapping
    ///   triangles within one planar light are rejected by [`Light::new`].)
    ///
    /// Decided with the facing predicate of the shading itself ([`face_side`]) and exact
    /// orientation tests in the light's plane. Costs up to (points x light triangles) facing
    /// tests per light (it stops at the first point that sees a front face, usually the first)
    /// and (triangles squared) overlap tests per pair of coplanar lights: run it once per scene,
    /// not per frame.
    ///
    /// # Examples
    ///
    /// ```
    /// use arealight::glam::DVec3;
    /// use arealight::shade::{Light, Scene, SceneIssue, TriangleMesh};
    /// // u x v = X x Y = +Z: this quad at height 3 emits upwards, away from the floor.
    /// let up = TriangleMesh::quad(DVec3::new(0.0, 0.0, 3.0), DVec3::X, DVec3::Y)?;
    /// let scene = Scene::new(vec![Light::new(up.clone(), DVec3::ONE)?], vec![])?;
    /// let floor = [DVec3::new(-5.0, -5.0, 0.0), DVec3::new(5.0, 5.0, 0.0)];
    /// let report = scene.validate(&floor);
    /// assert_eq!(report.issues, [SceneIssue::LightFacesAway { light: 0 }]);
    /// // Turned around, it lights the floor.
    /// let scene = Scene::new(vec![Light::new(up.flipped(), DVec3::ONE)?], vec![])?;
    /// assert!(scene.validate(&floor).is_clean());
    /// # Ok::<(), arealight::GeomError>(())
    /// ```
    #[must_use]
    pub fn validate<P: IntoDVec3 + Copy>(&self, receivers: &[P]) -> SceneReport {
        let mut issues = Vec::new();
        let receivers: Vec<DVec3> = receivers.iter().map(|p| p.into_dvec3()).collect();
        let lights = self.lights();
        for (i, light) in lights.iter().enumerate() {
            let others = self
                .occluders()
                .iter()
                .chain(
                    lights
                        .iter()
                        .enumerate()
                        .filter(|&(k, _)| k != i)
                        .map(|(_, l)| l.shape()),
                )
                .flat_map(|b| b.mesh().vertices().iter().copied());
            let mut points = others.chain(receivers.iter().copied()).peekable();
            if points.peek().is_some() && !lights_any(light, points) {
                issues.push(SceneIssue::LightFacesAway { light: i });
            }
        }
        for (i, a) in lights.iter().enumerate() {
            for (k, b) in lights.iter().enumerate().skip(i + 1) {
                if let (Some(ma), Some(mb)) = (planar_mesh(a), planar_mesh(b))
                    && coplanar_same_way(ma, mb)
                    && overlapping_pair(ma, mb).is_some()
                {
                    issues.push(SceneIssue::OverlappingLights { a: i, b: k });
                }
            }
        }
        SceneReport { issues }
    }
}

/// Whether some point sees a face of the light it emits from (a front face, or for a two-sided
/// light either side).
fn lights_any(light: &Light, points: impl Iterator<Item = DVec3>) -> bool {
    let mesh = light.shape().mesh();
    let emits = |s: Side| s == Side::Front || (light.is_two_sided() && s == Side::Behind);
    points
        .into_iter()
        .any(|x| (0..mesh.triangle_count()).any(|t| emits(face_side(mesh, t, x))))
}

/// The light's mesh when it is a planar mesh light.
fn planar_mesh(light: &Light) -> Option<&TriangleMesh> {
    match light.shape() {
        Body::Mesh(m) if m.is_planar() => Some(m),
        _ => None,
    }
}

/// Whether every vertex of `b` lies in the plane of `a` (by the facing predicate) and the two
/// face the same way.
fn coplanar_same_way(a: &TriangleMesh, b: &TriangleMesh) -> bool {
    a.triangle_normal(0).dot(b.triangle_normal(0)) > 0.0
        && b.vertices().iter().all(|&v| face_side(a, 0, v) == Side::On)
}

/// A pair of triangles, one of `a` and one of `b`, whose interiors overlap, both meshes lying in
/// `a`'s plane. `None` if there is none.
fn overlapping_pair(a: &TriangleMesh, b: &TriangleMesh) -> Option<(usize, usize)> {
    let flat = Flattening::new(a.triangle_normal(0));
    let ta: Vec<[DVec2; 3]> = (0..a.triangle_count())
        .map(|t| flat.triangle(a.triangle(t)))
        .collect();
    let tb: Vec<[DVec2; 3]> = (0..b.triangle_count())
        .map(|t| flat.triangle(b.triangle(t)))
        .collect();
    for (i, p) in ta.iter().enumerate() {
        for (k, q) in tb.iter().enumerate() {
            if interiors_overlap(p, q) {
                return Some((i, k));
            }
        }
    }
    None
}

/// Drops the coordinate along which the plane's normal is largest, so that the plane maps to a
/// coordinate plane one to one, and orders corners counter-clockwise there.
struct Flattening {
    axis: usize,
}

impl Flattening {
    fn new(normal: DVec3) -> Self {
        let a = normal.abs();
        let axis = if a.x >= a.y && a.x >= a.z {
            0
        } else if a.y >= a.z {
            1
        } else {
            2
        };
        Flattening { axis }
    }

    fn triangle(&self, t: [DVec3; 3]) -> [DVec2; 3] {
        let [p, q, r] = t.map(|v| match self.axis {
            0 => DVec2::new(v.y, v.z),
            1 => DVec2::new(v.z, v.x),
            _ => DVec2::new(v.x, v.y),
        });
        if orient(p, q, r) < 0.0 {
            [p, r, q]
        } else {
            [p, q, r]
        }
    }
}

/// Shewchuk's exact `orient2d`: positive when `r` lies left of `p -> q`.
fn orient(p: DVec2, q: DVec2, r: DVec2) -> f64 {
    robust::orient2d(
        robust::Coord { x: p.x, y: p.y },
        robust::Coord { x: q.x, y: q.y },
        robust::Coord { x: r.x, y: r.y },
    )
}

/// Whether two counter-clockwise triangles share interior points. Two convex polygons have
/// disjoint interiors exactly when a line through an edge of one of them has the whole other
/// polygon on its outer side or on it (separating axis theorem); decided with exact
/// orientations. A triangle of no area (exactly collinear corners) has no interior.
fn interiors_overlap(p: &[DVec2; 3], q: &[DVec2; 3]) -> bool {
    if orient(p[0], p[1], p[2]) == 0.0 || orient(q[0], q[1], q[2]) == 0.0 {
        return false;
    }
    let separates = |t: &[DVec2; 3], other: &[DVec2; 3]| {
        (0..3).any(|e| {
            let (a, b) = (t[e], t[(e + 1) % 3]);
            other.iter().all(|&v| orient(a, b, v) <= 0.0)
        })
    };
    !separates(p, q) && !separates(q, p)
}
