//! Three-dimensional geometry without light: triangle meshes with edge adjacency, convex
//! polyhedra and their hulls, the primitives of the seed paper's test scene, separating planes,
//! the one facing predicate, and spherical polygons of objects seen from a point (silhouettes)
//! in a [`ShadingFrame`].
//!
//! - [`TriangleMesh`]: any mesh (the per-triangle method), validated, with its edges and the
//!   triangles on either side ([`MeshEdge`]).
//! - [`ConvexPolyhedron`]: a closed convex mesh, validated or built as a convex hull, and the
//!   primitives (`cuboid`, `icosphere`, `ellipsoid`, `frustum`; [`TriangleMesh::quad`]).
//! - [`BezierShape`]: a planar shape bounded by cubic Bezier curves and lines (seed 004's
//!   free-form lights), validated, flattened per shading point.
//! - [`Body`]: the geometry of one object of a scene.
//! - [`Bvh`]: a bounding-volume hierarchy over a mesh's triangles, for culling.
//! - [`ShadingFrame`]: the local frame of a shading point.
//! - [`face_side`]: the one facing predicate (does a mesh triangle face a point), with its
//!   tolerance [`FACE_TOLERANCE`].
//!
//! This layer knows spherical polygons (it projects objects onto the sphere of directions) but no
//! light, radiance or BRDF, and not the `ltc` layer.
//!
//! # References
//!
//! - Seed 000: section 3.3 and Alg. 2 (silhouettes of convex objects), section 4.4 (the
//!   per-triangle method), Fig. 4 (the test scene's primitives).
//! - Thesis 003: section 4.2 (silhouettes of convex polyhedra oriented by front faces).
//! - Seed 004: free-form planar lights bounded by cubic Bezier curves.

mod bezier;
mod body;
mod bvh;
mod closed;
mod convex;
pub(crate) mod facing;
pub(crate) mod fixtures;
mod frame;
mod mesh;
mod primitives;
pub(crate) mod separation;
pub(crate) mod silhouette;

pub use silhouette::{
    DEFAULT_BUILD_BUDGET, DEFAULT_REGION_RADII, SilhouetteBsp, SilhouetteRings, SilhouetteSampler,
    TriangleSource, nonconvex_silhouette,
};

pub use bezier::{
    BEZIER_TOLERANCE, BezierSegment, BezierShape, DEFAULT_FLATTEN_ANGLE, FINEST_FLATNESS,
};
pub use body::Body;
pub use bvh::Bvh;
pub use closed::ClosedMesh;
pub use convex::ConvexPolyhedron;
pub use facing::{FACE_TOLERANCE, Side, face_side};
pub use frame::ShadingFrame;
pub use mesh::{BoundingSphere, DEGENERATE_TRIANGLE, MAX_MESH_COORD, MeshEdge, TriangleMesh};
