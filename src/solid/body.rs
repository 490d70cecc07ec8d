//! The geometry of one object of a scene, whichever representation it has.

use super::bezier::BezierShape;
use super::convex::ConvexPolyhedron;
use super::mesh::{BoundingSphere, TriangleMesh};

/// The geometry of a light or an occluder: a convex polyhedron (one silhouette polygon per
/// shading point) or any triangle mesh (one spherical triangle per triangle). More kinds will
/// follow (non-convex silhouettes, curved lights), hence `#[non_exhaustive]`.
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub enum Body {
    /// A convex polyhedron: one silhouette polygon per shading point (seed 000 section 3.3).
    Convex(ConvexPolyhedron),
    /// Any triangle mesh: one spherical triangle per triangle (seed 000 section 4.4). As a light,
    /// only front faces emit; as an occluder, every triangle blocks.
    Mesh(TriangleMesh),
    /// A planar shape bounded by cubic Bezier curves (seed 004): as a light, its region is
    /// flattened per shading point ([`BezierShape::region`]); as a blocker of other lights, and
    /// for culling and separating planes, it is its triangulated flattening
    /// ([`BezierShape::mesh`]). Boxed: the shape keeps its flattenings and mesh, far larger than
    /// the other variants.
    Bezier(alloc::boxed::Box<BezierShape>),
}

impl Body {
    /// The triangle mesh of the body (the hull triangles of a convex polyhedron).
    #[must_use]
    pub fn mesh(&self) -> &TriangleMesh {
        match self {
            Body::Convex(p) => p.mesh(),
            Body::Mesh(m) => m,
            Body::Bezier(b) => b.mesh(),
        }
    }

    /// A sphere holding the body.
    #[must_use]
    pub fn bounding_sphere(&self) -> BoundingSphere {
        match self {
            // The control points' sphere: it holds the curves, not only their flattening.
            Body::Bezier(b) => b.bounding_sphere(),
            _ => self.mesh().bounding_sphere(),
        }
    }
}

impl From<ConvexPolyhedron> for Body {
    fn from(p: ConvexPolyhedron) -> Self {
        Body::Convex(p)
    }
}

impl From<BezierShape> for Body {
    fn from(b: BezierShape) -> Self {
        Body::Bezier(alloc::boxed::Box::new(b))
    }
}

impl From<TriangleMesh> for Body {
    fn from(m: TriangleMesh) -> Self {
        Body::Mesh(m)
    }
}
