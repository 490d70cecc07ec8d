//! A single closed ring of a [`Shape`](super::Shape).

use alloc::vec::Vec;
use glam::DVec2;

use super::predicates::signed_area2;

/// A closed ring of points, the boundary of one face or one hole of a [`Shape`](super::Shape).
///
/// The closing edge from the last point back to the first is implicit: the first point is never
/// repeated at the end. Inside a `Shape` every contour has at least three points, no two
/// consecutive points are equal, no three consecutive points are collinear (exactly, by
/// `orient2d`), and the interior of the shape lies to the left of every edge: outer contours run
/// counter-clockwise, holes clockwise. Contours of one shape never cross or overlap each other but
/// may touch at isolated points.
#[derive(Debug, Clone, PartialEq)]
pub struct Contour {
    pub(crate) pts: Vec<DVec2>,
}

impl Contour {
    /// The points of the ring in order, without a repeated closing point.
    #[must_use]
    pub fn points(&self) -> &[DVec2] {
        &self.pts
    }

    /// Signed area: positive for an outer contour (counter-clockwise), negative for a hole.
    #[must_use]
    pub fn signed_area(&self) -> f64 {
        0.5 * signed_area2(&self.pts)
    }

    /// Whether the contour is a hole (runs clockwise).
    #[must_use]
    pub fn is_hole(&self) -> bool {
        self.signed_area() < 0.0
    }
}
