//! Planar polygons and their boolean operations.
//!
//! A [`Shape`] is a set of closed [`Contour`]s — outer contours counter-clockwise, holes
//! clockwise — that never cross but may touch at points. [`boolean`] computes the regularized
//! intersection, union, difference or symmetric difference of two shapes with Greiner–Hormann
//! clipping extended to degenerate contacts after Foster, Hormann and Popa (2019): shared
//! vertices, vertices on edges, overlapping edges and identical contours are the normal case here
//! (adjacent triangles of one mesh, projected), and are decided with exact `orient2d` predicates
//! rather than perturbation.
//!
//! Polygons as users hold them — rings that cross themselves or each other, overlap, repeat
//! points or bound no area — become shapes through [`Shape::with_fill_rule`] (a [`FillRule`] on
//! winding numbers) or the GeoJSON-role constructors [`Shape::from_polygon_rings`] and
//! [`Shape::from_multipolygon`], which resolve them with the same machinery.
//!
//! Tolerances are relative to the coordinate scale (the largest coordinate magnitude of the
//! operands) and are documented where they are defined: [`SNAP_REL`] and [`SLIVER_REL`].
//! Coordinates must be finite with magnitude at most [`MAX_COORD`].
//!
//! # Cost
//!
//! Inputs are small (3 to 64 vertices per shape after projection), so the pipeline favours
//! simple arrays. Operands in generic position (every contact a proper crossing, far from
//! vertices and other crossings, in units of the snapping distance) take a fast path: classic
//! Greiner–Hormann on buffers of a [`Workspace`], with all edge pairs tested directly for small
//! operands and a sweep over x for larger ones. Anything else — shared or nearly shared
//! vertices, vertices on or near edges, overlapping edges — bails out to the robust pipeline
//! (welding, splitting to a fixpoint, exact local labelling, leftmost-turn tracing), and the fast
//! path returns only results identical to the robust pipeline's (`tests/planar_fast.rs`).
//! Scratch storage is `SmallVec` with inline room for about 32 points per operand, so operands
//! of up to about 32 vertices *including* inserted intersection points are processed without
//! heap allocation; the only allocations are the output: one vector per contour, allocated
//! once at its final size on the fast path, and the list of contours (two allocations for a
//! one-contour result). Larger operands spill to the
//! heap (once per [`Workspace`] on the fast path, with [`boolean_with`]). `Shape::new` validates
//! in `O(n^2)` (all edge pairs), once per shape, and caches what the choice of path needs to
//! know about the shape alone (bounding box, minimum vertex separation, vertices on its own
//! other contours); `boolean` does not re-validate, and computes those facts per operation only
//! for operands that are results of earlier operations. Measured costs
//! against i_overlay, clipper2 and geo are in `BENCHMARKS.md`.
//!
//! # Testing
//!
//! - `tests/planar_cases.rs`: degenerate configurations with areas known in closed form (shared
//!   edges, vertex on edge, vertex on vertex, identical contours, holes touching outers, a
//!   50-triangle grid union, 50-step difference chains against union-first), input errors, and
//!   the FHP vertex classes (`contact_classes`).
//! - `compare/tests/planar_proptest.rs` (the workspace member `compare/`, which alone builds the
//!   reference clippers: `cargo test -p arealight-compare`): 256 cases per property (`PLANAR_CASES=N` for more) against
//!   i_overlay and clipper2 (symmetric-difference area at most `1e-7` of the operands' area) and
//!   the identities among our own results (`1e-9`), on random, integer-grid, copied,
//!   sub-polygon, shared-edge, vertex-on-edge, far-from-origin and chained inputs.
//! - `tests/planar_fast.rs`: the fast path against the robust pipeline (identical results
//!   wherever the fast path answers; bail-out on exact and near degeneracies; taken on generic
//!   inputs and on the benchmark inputs).
//! - `compare/tests/planar_fill.rs`: `with_fill_rule` and the GeoJSON constructors on random
//!   self-intersecting rings, grid soups, overlapping stars, bow-ties, self-touching and nested
//!   rings at scales `2^-20..2^20` with offsets, against i_overlay's and clipper2's resolution
//!   under the same rule and against the exact winding number at sample points; hand-checked
//!   areas, bad input, slivers.
//! - `tests/planar_regressions.rs`: every minimized failure as a named test (their checks
//!   against i_overlay in `compare/tests/planar_regressions.rs`); proptest's seeds are in
//!   `compare/proptest-regressions/planar_proptest.txt`; golden fixtures checked against both
//!   references in `compare/tests/planar_fixtures.rs`.
//! - `fuzz/fuzz_targets/planar_{intersection,union,difference,xor}.rs`: validity and identities;
//!   run with `RUSTC_BOOTSTRAP=1 cargo fuzz run planar_difference -- -max_total_time=60`
//!   (after `cargo install cargo-fuzz`).
//!
//! # Examples
//!
//! ```
//! use arealight::glam::DVec2;
//! use arealight::planar::{BoolOp, Shape, boolean};
//!
//! let light = Shape::new(vec![vec![
//!     DVec2::new(0.0, 0.0),
//!     DVec2::new(4.0, 0.0),
//!     DVec2::new(4.0, 4.0),
//!     DVec2::new(0.0, 4.0),
//! ]])?;
//! let occluder = Shape::new(vec![vec![
//!     DVec2::new(0.0, 0.0),
//!     DVec2::new(4.0, 0.0),
//!     DVec2::new(0.0, 4.0),
//! ]])?;
//! let visible = boolean(&light, &occluder, BoolOp::Difference)?;
//! assert_eq!(visible.area(), 8.0);
//! visible.validate()?;
//! # Ok::<(), arealight::GeomError>(())
//! ```

pub(crate) mod boolean;
mod contour;
mod fill;
pub(crate) mod predicates;
mod shape;
mod triangulate;

pub(crate) use boolean::boolean_at_scale;
pub use boolean::intersect::SNAP_REL;
pub use boolean::trace::SLIVER_REL;
pub use boolean::{BoolOp, Workspace, boolean, boolean_with};
pub use contour::Contour;
pub use fill::FillRule;
pub use predicates::MAX_COORD;
pub use shape::Shape;
pub(crate) use triangulate::{Cdt, constrained_delaunay};
