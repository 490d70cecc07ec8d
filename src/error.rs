//! The crate's one error type.

use core::fmt;

/// Everything that can go wrong in a public entry point.
///
/// Every public function validates its input at the boundary and returns one of these instead of
/// panicking or producing garbage. There are two kinds, told apart by
/// [`GeomError::is_undecidable`]:
///
/// - **Input faults** (every variant but [`GeomError::Undecidable`]): the input is invalid; skip
///   it or fix it. Locations in vertex lists are `(ring, vertex)` indices into the input as the
///   caller passed it (a planar contour is a ring too); a single argument that is not a vertex
///   list (a shading point, a normal, a view direction, a primitive's center or axis) is named
///   by [`GeomError::NonFiniteArgument`] or [`GeomError::ZeroLengthArgument`].
/// - **Give-ups** ([`GeomError::Undecidable`]): the input is valid, but a configuration met on
///   the way cannot be decided within rounding; a renderer falls back for this query.
///
/// More variants may be added (`#[non_exhaustive]`); match on the kind with
/// [`GeomError::is_undecidable`] where only the kind matters.
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub enum GeomError {
    /// A coordinate is NaN or infinite.
    NonFinite {
        /// Index of the ring (or contour, or edge list) in the input.
        ring: usize,
        /// Index of the vertex within the ring.
        vertex: usize,
    },
    /// A direction vector has zero (or subnormal) length, so it names no direction.
    ZeroVector {
        /// Index of the ring in the input.
        ring: usize,
        /// Index of the vertex within the ring.
        vertex: usize,
    },
    /// A ring has fewer than three distinct vertices, so it bounds no area.
    TooFewVertices {
        /// Index of the ring in the input.
        ring: usize,
        /// Number of distinct vertices found.
        count: usize,
    },
    /// Two consecutive vertices coincide (within the documented tolerance) where the operation
    /// cannot drop one of them itself.
    CoincidentVertices {
        /// Index of the ring in the input.
        ring: usize,
        /// Index of the first of the two vertices.
        vertex: usize,
    },
    /// Two consecutive vertices of a spherical ring are antipodal (or nearly so), so the great-circle
    /// arc between them is not unique.
    AntipodalVertices {
        /// Index of the ring in the input.
        ring: usize,
        /// Index of the first of the two vertices.
        vertex: usize,
    },
    /// A contour crosses itself or another contour, so inside and outside are ambiguous.
    SelfIntersecting {
        /// Index of the first ring involved.
        ring: usize,
        /// Index of the second ring involved (equal to `ring` for a self-crossing contour).
        other_ring: usize,
    },
    /// A ring encloses no area: its vertices lie on one great circle to within rounding, so
    /// neither of its sides is a meaningful region.
    ZeroArea {
        /// Index of the ring in the input.
        ring: usize,
    },
    /// Two rings that bound the same face disagree about which side of it is inside (for example
    /// two nested rings both counter-clockwise): the region is ambiguous.
    InconsistentOrientation {
        /// Index of the first ring.
        ring: usize,
        /// Index of the second ring.
        other_ring: usize,
    },
    /// An argument that is not part of a vertex list (a shading point, a normal or view
    /// direction, a hemisphere's normal, a primitive's center, radii or axis) is NaN or
    /// infinite.
    NonFiniteArgument {
        /// Which argument.
        what: &'static str,
    },
    /// A direction argument (a normal, a view direction, an axis) has zero or subnormal length,
    /// so it names no direction.
    ZeroLengthArgument {
        /// Which argument.
        what: &'static str,
    },
    /// A value lies outside the range the algorithm supports; the message names the range.
    OutOfRange {
        /// Which input is out of range.
        what: &'static str,
        /// The offending value.
        value: f64,
        /// The largest supported magnitude.
        limit: f64,
    },
    /// A coordinate of a vertex lies outside the supported range; the message names the vertex
    /// and the range.
    CoordinateOutOfRange {
        /// Index of the ring in the input.
        ring: usize,
        /// Index of the vertex within the ring.
        vertex: usize,
        /// The offending magnitude.
        value: f64,
        /// The largest supported magnitude.
        limit: f64,
    },
    /// Silhouette edges do not close into loops: an endpoint is used by only one edge.
    OpenChain {
        /// Index (in the input slice) of an edge whose end has no successor.
        edge: usize,
    },
    /// Silhouette edges branch: an endpoint is shared by more than two edges.
    Branching {
        /// Index (in the input slice) of one edge at the branching vertex.
        edge: usize,
    },
    /// The directions are not contained in any open hemisphere, so no gnomonic projection maps them
    /// all to the plane.
    NotInOpenHemisphere,
    /// The input is geometrically degenerate in a way the operation cannot resolve (coplanar
    /// points for a hull, collinear consecutive contour points, a singular map); the string says
    /// how. This is a fault of the input: fix or drop it.
    Degenerate(&'static str),
    /// The input is valid, but the computation met a configuration it cannot decide exactly
    /// (near-degenerate within rounding) and declined to guess rather than return a possibly
    /// wrong value; the string says where. Not a fault of the input: a renderer may fall back
    /// (for example to the Monte Carlo reference, or a slightly moved shading point).
    Undecidable(&'static str),
    /// A segment of a curved boundary loop (a Bezier-bounded shape) is invalid; `why` says how.
    InvalidCurve {
        /// Index of the loop in the input.
        ring: usize,
        /// Index of the segment within the loop.
        segment: usize,
        /// What is wrong with it.
        why: &'static str,
    },
    /// (shade) A mesh triangle refers to a vertex index past the end of the vertex list.
    InvalidIndex {
        /// Index of the triangle.
        triangle: usize,
        /// The offending vertex index.
        index: usize,
    },
    /// (shade) A mesh triangle has (nearly) zero area, so it has no reliable normal.
    DegenerateTriangle {
        /// Index of the triangle.
        triangle: usize,
    },
    /// (shade) A mesh that must be closed has an edge not shared by exactly two triangles with
    /// opposite directions.
    OpenMesh {
        /// Index of a triangle at the offending edge.
        triangle: usize,
        /// The offending edge as the vertex indices of its ends, in the order that triangle
        /// runs it.
        edge: [usize; 2],
    },
    /// (shade) A mesh that must be convex has a vertex in front of a face's plane (or faces
    /// pointing inwards).
    NotConvex {
        /// Index of the face (triangle).
        face: usize,
        /// Index of the vertex in front of it.
        vertex: usize,
    },
    /// (shade) Two triangles of a planar mesh light overlap: their projections are integrated
    /// as disjoint pieces, so the overlap would be counted twice.
    OverlappingLightTriangles {
        /// Index of the first triangle.
        triangle: usize,
        /// Index of the second triangle.
        other: usize,
    },
    /// (solid) A mesh that must bound a solid has two triangles that cross, overlap or touch
    /// anywhere but along an edge or at a vertex they share as neighbours on the surface.
    SelfIntersectingMesh {
        /// Index of the first triangle.
        triangle: usize,
        /// Index of the second triangle.
        other: usize,
    },
    /// (solid) A mesh that must bound a solid has a vertex whose triangles form more than one
    /// fan (two parts of the surface touch at the vertex, as two cones tip to tip).
    NonManifoldVertex {
        /// Index of the vertex.
        vertex: usize,
        /// Index of a triangle of a second fan at that vertex.
        triangle: usize,
    },
}

impl fmt::Display for GeomError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            GeomError::NonFinite { ring, vertex } => write!(
                f,
                "coordinate of vertex {vertex} in ring {ring} is NaN or infinite; \
                 filter non-finite geometry before calling"
            ),
            GeomError::ZeroVector { ring, vertex } => write!(
                f,
                "vertex {vertex} in ring {ring} is the zero vector and names no direction; \
                 a spherical vertex must be a non-zero direction"
            ),
            GeomError::TooFewVertices { ring, count } => write!(
                f,
                "ring {ring} has only {count} distinct vertices; a ring needs at least 3"
            ),
            GeomError::CoincidentVertices { ring, vertex } => write!(
                f,
                "vertices {vertex} and {} of ring {ring} coincide; remove repeated vertices",
                vertex + 1
            ),
            GeomError::AntipodalVertices { ring, vertex } => write!(
                f,
                "vertices {vertex} and {} of ring {ring} are antipodal, so the edge between \
                 them is ambiguous; insert a vertex in between",
                vertex + 1
            ),
            GeomError::SelfIntersecting { ring, other_ring } if ring == other_ring => {
                write!(f, "ring {ring} crosses itself; split it into simple rings")
            }
            GeomError::SelfIntersecting { ring, other_ring } => write!(
                f,
                "rings {ring} and {other_ring} cross each other; rings must only nest or be disjoint"
            ),
            GeomError::ZeroArea { ring } => write!(
                f,
                "ring {ring} encloses no area (its vertices lie on one great circle within \
                 rounding); drop it"
            ),
            GeomError::InconsistentOrientation { ring, other_ring } => write!(
                f,
                "rings {ring} and {other_ring} border the same face but disagree on which side is \
                 inside; reverse one of them (outer rings counter-clockwise, holes clockwise)"
            ),
            GeomError::NonFiniteArgument { what } => {
                write!(f, "the {what} is NaN or infinite; pass finite values")
            }
            GeomError::ZeroLengthArgument { what } => write!(
                f,
                "the {what} has zero (or subnormal) length and names no direction"
            ),
            GeomError::OutOfRange { what, value, limit } => write!(
                f,
                "{what} is {value:e}, outside the supported range (magnitude at most {limit:e})"
            ),
            GeomError::CoordinateOutOfRange {
                ring,
                vertex,
                value,
                limit,
            } => write!(
                f,
                "a coordinate of vertex {vertex} in ring {ring} has magnitude {value:e}, outside \
                 the supported range (at most {limit:e}); scale the input down"
            ),
            GeomError::OpenChain { edge } => write!(
                f,
                "edge {edge} ends where no other edge starts; silhouette edges must form closed loops"
            ),
            GeomError::Branching { edge } => write!(
                f,
                "more than two edges meet at an endpoint of edge {edge}; silhouette loops must not branch"
            ),
            GeomError::NotInOpenHemisphere => f.write_str(
                "the directions do not fit in any open hemisphere, so no gnomonic projection \
                 holds them all; split the input first",
            ),
            GeomError::Degenerate(why) => write!(f, "degenerate input: {why}"),
            GeomError::Undecidable(where_) => write!(
                f,
                "valid input, but not decidable within rounding here ({where_}); \
                 fall back to an approximate method for this query"
            ),
            GeomError::InvalidCurve { ring, segment, why } => {
                write!(f, "segment {segment} of loop {ring}: {why}")
            }
            GeomError::InvalidIndex { triangle, index } => write!(
                f,
                "triangle {triangle} refers to vertex {index}, past the end of the vertex list"
            ),
            GeomError::DegenerateTriangle { triangle } => write!(
                f,
                "triangle {triangle} has (nearly) zero area; remove it or merge its vertices"
            ),
            GeomError::OpenMesh { triangle, edge } => write!(
                f,
                "the edge from vertex {} to vertex {} of triangle {triangle} is not shared by \
                 exactly one other triangle running the opposite way; a convex polyhedron or a \
                 solid must be a closed, consistently oriented mesh",
                edge[0], edge[1]
            ),
            GeomError::OverlappingLightTriangles { triangle, other } => write!(
                f,
                "triangles {triangle} and {other} of a planar light overlap, so their overlap \
                 would emit twice; remove it, or make them two lights if that is meant"
            ),
            GeomError::SelfIntersectingMesh { triangle, other } => write!(
                f,
                "triangles {triangle} and {other} cross or touch away from a shared edge or \
                 vertex: the mesh does not bound a solid; fix the mesh or use it per triangle"
            ),
            GeomError::NonManifoldVertex { vertex, triangle } => write!(
                f,
                "vertex {vertex} joins separate fans of triangles (triangle {triangle} is in a \
                 second one): the surface touches itself there; split the vertex or use the mesh \
                 per triangle"
            ),
            GeomError::NotConvex { face, vertex } => write!(
                f,
                "vertex {vertex} lies in front of the plane of face {face}: the mesh is not convex \
                 (or a face points inwards); build it with ConvexPolyhedron::hull or use a \
                 TriangleMesh (per-triangle method)"
            ),
        }
    }
}

impl GeomError {
    /// Whether the error is a numerical give-up on valid input ([`GeomError::Undecidable`])
    /// rather than a fault of the input. A renderer skips or fixes bad input, and falls back to
    /// an approximate method where this is `true`.
    #[must_use]
    pub fn is_undecidable(&self) -> bool {
        matches!(self, GeomError::Undecidable(_))
    }
}

impl GeomError {
    /// This error, met on an intermediate result the crate built itself from valid input, as a
    /// give-up: an [`GeomError::Undecidable`] stays as it is, any other error (a spherical
    /// polygon the rounding made invalid, a planar operation that did not settle) becomes
    /// `Undecidable(context)`, since nothing the caller passed was wrong.
    pub(crate) fn give_up(self, context: &'static str) -> GeomError {
        match self {
            GeomError::Undecidable(_) => self,
            _ => GeomError::Undecidable(context),
        }
    }
}

#[cfg(feature = "std")]
impl std::error::Error for GeomError {}
