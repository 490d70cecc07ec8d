//! Whether a face of a mesh faces a point.

/// Relative tolerance of the "is the point in front of the face plane" test: a face counts as
/// front-facing only when the point lies more than `FACE_TOLERANCE * scale` in front of its plane,
/// with `scale` the polyhedron's bounding radius plus the point's distance to its center.
///
/// The signed distance is evaluated relative to the bounding center, so its rounding error is a
/// few `1e-16 * scale`; `1e-11` is far above that. A point closer to the plane than this sees the
/// face edge-on (zero solid angle) and treats it as back-facing, which handles shading points
/// lying in a face's plane (a cube standing on the ground plane, seen from the ground).
pub const FACE_TOLERANCE: f64 = 1e-11;
