//! Spherical polygons: construction and validation, solid angle, containment, gnomonic
//! projection, ordering of silhouette edges, hemisphere clipping, triangulation and uniform
//! sampling by solid angle.
//!
//! Directions are unit `DVec3`s; edges are minor great-circle arcs; the interior of a ring lies
//! on its left (see [`SphericalPolygon`]). This layer knows nothing of light: it is the geometry
//! that the `ltc` and shading layers integrate over.

mod boolean;
mod clip;
mod exact;
mod gnomonic;
mod order;
mod polygon;
pub(crate) mod predicates;
mod sample;
mod triangulate;
mod wolfe;

pub use boolean::MIN_CAP_COS;
pub use clip::HORIZON_TOLERANCE;
pub use gnomonic::{Gnomonic, enclosing_cap};
pub use order::{MATCH_TOLERANCE, order_directed_edges, order_edges};
pub(crate) use polygon::ring_slices;
pub use polygon::{ANTIPODAL_TOLERANCE, COINCIDENT_TOLERANCE, SphericalPolygon};
pub use sample::{PolygonSampler, SAMPLE_TOLERANCE, SphericalTriangle};
pub(crate) use wolfe::min_norm_point;
