//! BSP-precomputed silhouettes (thesis 003 section 5): a binary space partition of a box around
//! a polyhedron whose cells each store the silhouette's combinatorial structure, so that a
//! query descends the tree and evaluates the stored structure at the point without looking at
//! the faces.
//!
//! - Convex polyhedra (section 5.1): the cells are those of the arrangement of the face planes,
//!   on whose sides the set of contour edges depends; each leaf stores the silhouette loop as
//!   vertex indices.
//! - Closed non-convex meshes (section 5.2): each cell of the face planes is split further by
//!   the planes through one edge and an endpoint of another, for pairs of its contour edges
//!   whose apparent intersection can appear or vanish inside the cell (and the planes through
//!   two contour edges sharing a vertex, where their arcs can fold over each other); each leaf
//!   stores the rings as arcs of mesh edges, with apparent-intersection endpoints named by the
//!   pair of edges that make them (section 5.4).
//!
//! # Building (section 5.3)
//!
//! The face-plane level is built twice, as in the thesis: a first pass splits explicit convex
//! cells (vertices with the planes they lie on) until no plane cuts a cell, which enumerates the
//! cells and gives each a representative point (its vertex centroid); the second pass builds the
//! tree actually stored by partitioning those points, always with the plane that splits the
//! remaining points most evenly. Since both trees partition the box by the same planes as far as
//! possible, each leaf of the second is exactly one cell. Within a cell of the face planes the
//! pair planes are applied by the first pass directly, dropping, cell by cell, the pairs whose
//! crossing cannot change inside it; the structure of each final cell is computed by the direct
//! silhouette algorithm at its representative point.
//!
//! # Beyond the thesis: orders of crossings
//!
//! The planes fix which contour edges there are and which of them cross, but not the order of
//! two crossings along one contour edge: that order flips where the three edges are seen
//! concurrent, on a quadric surface (an edge-edge-edge event of aspect graphs), which no plane
//! set captures, and the silhouette changes there (seen on tori: a cell of the planes alone
//! holds points with different silhouettes). Each final cell therefore checks every triple of
//! crossing contour edges: where the order is proven constant over the cell (a quadratic in the
//! point, bounded over the cell's vertices), nothing is added; otherwise the leaf becomes a small
//! subtree of triple tests (the sign of `det(n_a, n_b, n_c)`, computed from six vertices and the
//! point, no face), each combination of signs met at sample points of the cell storing the
//! silhouette at such a sample. Combinations no sample met, and points within the rounding bound
//! of a triple test, are answered by the direct algorithm, as are points within the facing
//! predicate's tolerance of a face plane (for non-convex solids, where exact plane tests through
//! that face's vertices and the tolerant facing predicate can disagree).
//!
//! # Storage (section 5.4)
//!
//! Nodes are one `u32` each, in preorder: an inner node packs its plane index and the index of
//! its right child (the left child follows it); a leaf holds the offset of its data. Leaf data
//! are small integers stored with the narrowest width (1, 2 or 4 bytes) that holds all of them:
//! vertex indices for convex polyhedra, `edge << 2 | direction | from-crossing` for arcs.
//! Built with triangulations ([`SilhouetteBsp::build_triangulated`]), each leaf with rings
//! ends with its triangle count and its triangles as index triples into its `n` corners (the
//! arcs' starts), one element `i + n (j + n k)` each where `n^3` fits the width (the width of
//! everything else decides), else three.

use alloc::collections::BTreeMap;
use alloc::vec;
use alloc::vec::Vec;

use glam::DVec3;
use robust::orient3d;
use smallvec::SmallVec;

use super::convex::chain_by_index;
use super::nonconvex::{
    Arc, ORDER_ERROR, Outline, collinear, evaluate_rings_into, outline, outline_with,
};
use super::rings::{SilhouetteRings, spaced};
use super::triangulated::{
    CellCorners, Extra, OnFace, SNAP_REL, TriangleSource, certified_triangulation, evaluate_stored,
    fan_or_list, raw_stored,
};
use super::{convex_silhouette, nonconvex_silhouette};
use crate::GeomError;
use crate::solid::facing::{FacingAt, Side, face_distances, in_front};
use crate::solid::{ClosedMesh, ConvexPolyhedron, ShadingFrame, TriangleMesh};
use crate::sphere::predicates::c3;
use crate::sphere::{
    ANTIPODAL_TOLERANCE, COINCIDENT_TOLERANCE, MATCH_TOLERANCE, SphericalPolygon, SphericalTriangle,
};

/// The default box of a BSP is the mesh's bounding sphere's center plus or minus this many
/// bounding radii along each axis. Shading points farther out are answered by the direct
/// silhouette algorithms.
pub const DEFAULT_REGION_RADII: f64 = 8.0;

/// The default budget of a build ([`SilhouetteBsp::build`] and the other constructors without a
/// budget of their own): 256 MiB of the storage the build counts (see
/// [`SilhouetteBsp::build_with_budget`]). The largest trees of the tests stay far below it
/// (sphere-42: 39 MiB counted, mostly the cells of the first pass, for a tree of 1.3 MiB; a
/// torus of 8 x 4 segments: 10 MiB; BENCHMARKS.md); a mesh
/// whose tree would need more gets [`GeomError::OutOfRange`] instead of exhausting memory.
pub const DEFAULT_BUILD_BUDGET: usize = 256 << 20;

/// Cells thinner than this fraction of the box's half-size are not split: a plane cuts a cell
/// only when cell vertices lie farther than that on both sides (it keeps the first pass from
/// creating slivers out of rounding).
const CELL_EPS: f64 = 1e-12;

const LEAF: u32 = 1 << 31;

/// Leaf headers of closed non-convex meshes; a header `r + RINGS` starts `r` rings.
const EMPTY: u32 = 0;
const FULL: u32 = 1;
const DIRECT: u32 = 2;
const RINGS: u32 = 3;

const GIVE_UP_QUERY: &str = "the stored silhouette evaluated at the point has coincident or antipodal vertices (the point is within rounding of a cell boundary)";

/// Why a query is answered by the direct algorithm ([`SilhouetteBsp::direct_reason`]).
#[doc(hidden)]
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum DirectReason {
    /// The point is outside the tree's box.
    OutsideBox,
    /// The point is within the facing predicate's tolerance of a face plane on its path (for
    /// non-convex solids).
    FaceBand,
    /// A triple test on its path is within its rounding bound.
    TripleBand,
    /// Its leaf stores no silhouette: a convex polyhedron's inside or a loop that is not one
    /// chain, a non-convex solid's cell where the direct algorithm gave up at every trial point
    /// or a combination of triple signs no sample met.
    DirectLeaf,
    /// A convex polyhedron's stored loop whose vertices are too close to chain at the point.
    Spacing,
}

/// A node test: the front side of a face by the facing predicate, the positive side of
/// `orient3d` of three mesh vertices and the point, or the sign of `det(n_a, n_b, n_c)` for three
/// mesh edges (`n_e = (a_e - x) x (b_e - x)`), which orders the crossings of three contour edges
/// seen from the point and changes on a quadric surface (an EEE event), not on a plane.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
enum SplitPlane {
    Face(u32),
    Through([u32; 3]),
    Triple([u32; 3]),
}

#[derive(Debug, Clone, PartialEq)]
enum Source {
    Convex(ConvexPolyhedron),
    Solid(ClosedMesh),
}

impl Source {
    fn mesh(&self) -> &TriangleMesh {
        match self {
            Source::Convex(p) => p.mesh(),
            Source::Solid(s) => s.mesh(),
        }
    }
}

/// Precomputed silhouettes of a polyhedron (thesis 003 section 5): build once, then query the
/// silhouette seen from any point of a box around it.
///
/// A query equals the direct algorithm's result ([`convex_silhouette`] for convex polyhedra,
/// [`nonconvex_silhouette`] otherwise), as a set, at every point whose cell was resolved: the
/// structure stored for a cell is computed by the direct algorithm at the cell's representative
/// point and is the same everywhere in the cell. Points outside the box, inside a convex
/// polyhedron, and in the rare cells where the direct algorithm gave up at every trial point,
/// are answered by the direct algorithm.
///
/// # Examples
///
/// ```
/// use arealight::glam::DVec3;
/// use arealight::solid::{ClosedMesh, ShadingFrame, SilhouetteBsp, nonconvex_silhouette};
/// use arealight::internals::thesis_polyhedra;
/// let (_, bowl) = thesis_polyhedra()?.pop().unwrap();
/// let solid = ClosedMesh::new(bowl)?;
/// let bsp = SilhouetteBsp::build(&solid)?;
/// let frame = ShadingFrame::new(DVec3::new(0.3, -0.2, 3.0), DVec3::Z, DVec3::Z)?;
/// let fast = bsp.query(&frame)?;
/// let direct = nonconvex_silhouette(&solid, &frame)?;
/// assert!((fast.solid_angle() - direct.solid_angle()).abs() < 1e-12);
/// # Ok::<(), arealight::GeomError>(())
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct SilhouetteBsp {
    source: Source,
    planes: Vec<SplitPlane>,
    /// The leading face planes of `planes` as unit normal and offset from the bounding sphere's
    /// center (the facing predicate's form), read by the descent without a dispatch.
    face_eqs: Vec<(DVec3, f64)>,
    nodes: Vec<u32>,
    /// Bits of an inner node word that hold the right child's index; the plane index is above.
    child_bits: u32,
    data: Vec<u8>,
    /// Bytes per data element: 1, 2 or 4.
    width: u8,
    lo: DVec3,
    hi: DVec3,
    leaves: u32,
    direct_leaves: u32,
    /// Whether leaves with rings carry a triangulation section (built with triangulations).
    triangulated: bool,
    /// The bytes the build counted against its budget.
    build_bytes: usize,
}

/// The rings of a leaf as arcs and ring ends, read from the leaf data.
type Rings = (SmallVec<[Arc; 24]>, SmallVec<[u32; 4]>);

impl SilhouetteBsp {
    /// Precomputed silhouettes of a closed mesh in its default box
    /// ([`DEFAULT_REGION_RADII`] bounding radii about its center): the convex build when the
    /// mesh is convex ([`ConvexPolyhedron::from_mesh`]), the non-convex one otherwise.
    ///
    /// # Errors
    ///
    /// As [`SilhouetteBsp::build_in`].
    pub fn build(solid: &ClosedMesh) -> Result<Self, GeomError> {
        let (lo, hi) = default_region(solid.mesh());
        SilhouetteBsp::build_in(solid, lo, hi)
    }

    /// As [`SilhouetteBsp::build`], in the box `[lo, hi]`.
    ///
    /// # Errors
    ///
    /// [`GeomError::NonFiniteArgument`] or [`GeomError::Degenerate`] for a box that is not
    /// finite or has no volume; [`GeomError::OutOfRange`] when the tree does not fit the
    /// compact node format (planes times nodes beyond `2^31`) or the build exceeds
    /// [`DEFAULT_BUILD_BUDGET`] (see [`SilhouetteBsp::build_with_budget`]).
    pub fn build_in(solid: &ClosedMesh, lo: DVec3, hi: DVec3) -> Result<Self, GeomError> {
        SilhouetteBsp::build_with_budget(solid, lo, hi, false, DEFAULT_BUILD_BUDGET)
    }

    /// [`SilhouetteBsp::build_in`] (or, with `triangulated`,
    /// [`SilhouetteBsp::build_triangulated_in`]) with a budget of `budget` bytes: the build counts
    /// the storage it holds (the cells of its first pass, with their vertices and the planes
    /// through each; the nodes, leaf data and planes of the tree as it grows, at their sizes
    /// while building, which exceed the final [`SilhouetteBsp::byte_size`]) and stops with an
    /// error as soon as the count exceeds the budget. Freed storage is not subtracted, so the
    /// count bounds the build's peak memory from above (allocator overhead aside). The default
    /// budget is [`DEFAULT_BUILD_BUDGET`].
    ///
    /// # Errors
    ///
    /// [`GeomError::OutOfRange`] (its value the bytes counted when the build stopped, its limit
    /// the budget) when the build would need more; otherwise as [`SilhouetteBsp::build_in`].
    pub fn build_with_budget(
        solid: &ClosedMesh,
        lo: DVec3,
        hi: DVec3,
        triangulated: bool,
        budget: usize,
    ) -> Result<Self, GeomError> {
        Ok(SilhouetteBsp::build_recording(solid, lo, hi, triangulated, false, budget)?.0)
    }

    /// As [`SilhouetteBsp::build`], also storing per leaf a triangulation of its silhouette
    /// that is certified valid everywhere in the leaf's cell (thesis 003 section 6.2.3; the
    /// certificate and its argument are in the documentation of [`SilhouetteSampler`]'s
    /// module, `solid/silhouette/triangulated.rs`), for [`SilhouetteBsp::query_triangles`].
    /// Convex polyhedra need none: seen from a point of a cell of the face planes (off them by
    /// more than the facing predicate's tolerance), the silhouette is strictly convex, since
    /// three of its vertices seen on one great circle would put the point on a supporting
    /// plane through three vertices, a face plane; so the fan of the stored loop from its
    /// first vertex is a triangulation, and for them this is [`SilhouetteBsp::build`].
    ///
    /// [`SilhouetteSampler`]: crate::solid::SilhouetteSampler
    ///
    /// # Errors
    ///
    /// As [`SilhouetteBsp::build_in`].
    pub fn build_triangulated(solid: &ClosedMesh) -> Result<Self, GeomError> {
        let (lo, hi) = default_region(solid.mesh());
        SilhouetteBsp::build_triangulated_in(solid, lo, hi)
    }

    /// As [`SilhouetteBsp::build_triangulated`], in the box `[lo, hi]`.
    ///
    /// # Errors
    ///
    /// As [`SilhouetteBsp::build_in`].
    pub fn build_triangulated_in(
        solid: &ClosedMesh,
        lo: DVec3,
        hi: DVec3,
    ) -> Result<Self, GeomError> {
        SilhouetteBsp::build_with_budget(solid, lo, hi, true, DEFAULT_BUILD_BUDGET)
    }

    /// As [`SilhouetteBsp::build_triangulated`], also returning the vertices of the cell of
    /// every leaf that stores a triangulation (the convex cell its certificate covers), for
    /// tests that sample points per cell.
    ///
    /// # Errors
    ///
    /// As [`SilhouetteBsp::build_in`].
    #[doc(hidden)]
    pub fn build_triangulated_with_cells(
        solid: &ClosedMesh,
    ) -> Result<(Self, Vec<Vec<DVec3>>), GeomError> {
        let (lo, hi) = default_region(solid.mesh());
        SilhouetteBsp::build_recording(solid, lo, hi, true, true, DEFAULT_BUILD_BUDGET)
    }

    /// The builds of a closed mesh: convex or not, with triangulations or not, recording the
    /// cells of the leaves that store one, within `budget` bytes.
    fn build_recording(
        solid: &ClosedMesh,
        lo: DVec3,
        hi: DVec3,
        triangulated: bool,
        record: bool,
        budget: usize,
    ) -> Result<(Self, Vec<Vec<DVec3>>), GeomError> {
        if let Ok(p) = ConvexPolyhedron::from_mesh(solid.mesh()) {
            return Ok((
                SilhouetteBsp::build_convex_budget(&p, lo, hi, budget)?,
                Vec::new(),
            ));
        }
        check_region(lo, hi)?;
        let mut b = Builder::new(solid.mesh(), Some(solid), lo, hi, budget);
        if triangulated {
            b.triangulate = Some(OnFace::new(solid.mesh()));
            b.cells = record.then(Vec::new);
        }
        b.build_nonconvex();
        let cells = b.cells.take().unwrap_or_default();
        Ok((b.finish(Source::Solid(solid.clone()), lo, hi)?, cells))
    }

    /// Precomputed silhouettes of a convex polyhedron in its default box (thesis 003 section
    /// 5.1).
    ///
    /// # Errors
    ///
    /// As [`SilhouetteBsp::build_in`].
    pub fn build_convex(poly: &ConvexPolyhedron) -> Result<Self, GeomError> {
        let (lo, hi) = default_region(poly.mesh());
        SilhouetteBsp::build_convex_in(poly, lo, hi)
    }

    /// As [`SilhouetteBsp::build_convex`], in the box `[lo, hi]`.
    ///
    /// # Errors
    ///
    /// As [`SilhouetteBsp::build_in`].
    pub fn build_convex_in(
        poly: &ConvexPolyhedron,
        lo: DVec3,
        hi: DVec3,
    ) -> Result<Self, GeomError> {
        SilhouetteBsp::build_convex_budget(poly, lo, hi, DEFAULT_BUILD_BUDGET)
    }

    /// [`SilhouetteBsp::build_convex_in`] within `budget` bytes (see
    /// [`SilhouetteBsp::build_with_budget`]).
    fn build_convex_budget(
        poly: &ConvexPolyhedron,
        lo: DVec3,
        hi: DVec3,
        budget: usize,
    ) -> Result<Self, GeomError> {
        check_region(lo, hi)?;
        let mut b = Builder::new(poly.mesh(), None, lo, hi, budget);
        b.build_convex();
        b.finish(Source::Convex(poly.clone()), lo, hi)
    }

    /// The silhouette seen from the frame's point, in the local frame: descends the tree with
    /// the facing predicate (face planes) and exact `orient3d` (planes through three vertices)
    /// and evaluates the leaf's stored structure at the point.
    ///
    /// # Errors
    ///
    /// [`GeomError::Undecidable`] where the evaluated structure has coincident or antipodal
    /// consecutive vertices (a point within rounding of a cell boundary), and the errors of the
    /// direct algorithm where it answers.
    pub fn query(&self, frame: &ShadingFrame) -> Result<SphericalPolygon, GeomError> {
        let x = frame.origin();
        if !(x.cmpge(self.lo).all() && x.cmple(self.hi).all()) {
            return self.direct(frame);
        }
        let Some(leaf) = self.leaf_of(x, matches!(self.source, Source::Solid(_))) else {
            return self.direct(frame);
        };
        let at = leaf as usize;
        match &self.source {
            Source::Convex(poly) => match self.convex_loop(poly, at, frame) {
                Some(out) => {
                    let len = out.len() as u32;
                    Ok(SphericalPolygon::from_parts(out, smallvec::smallvec![len]))
                }
                None => convex_silhouette(poly, frame),
            },
            Source::Solid(solid) => {
                let header = self.read(at);
                match header {
                    EMPTY => Ok(SphericalPolygon::empty()),
                    FULL => Ok(SphericalPolygon::full()),
                    DIRECT => nonconvex_silhouette(solid, frame),
                    _ => {
                        let mut out = SilhouetteRings::new();
                        self.solid_rings(solid, at, frame, &mut out)?;
                        // Unit vectors, and the checks `solid_rings` made.
                        Ok(out.into_polygon_unchecked())
                    }
                }
            }
        }
    }

    /// [`SilhouetteBsp::query`] written to `out` as rings of directions that need not be unit
    /// vectors ([`SilhouetteRings`]), for the clip-free integrals
    /// ([`clamped_cosine_integral_rings`](crate::ltc::clamped_cosine_integral_rings),
    /// [`ltc_integral_rings`](crate::ltc::ltc_integral_rings)), which need none: for a convex
    /// polyhedron the stored loop's vertices in the local frame as they are (no normalization;
    /// the spacing test decided as the query decides it), for a closed non-convex mesh the
    /// query's rings; where the query answers with the direct algorithm, a copy of its polygon's
    /// rings. The same region as [`SilhouetteBsp::query`].
    ///
    /// # Examples
    ///
    /// ```
    /// use arealight::glam::DVec3;
    /// use arealight::internals::thesis_polyhedra;
    /// use arealight::ltc::{clamped_cosine_integral, clamped_cosine_integral_rings};
    /// use arealight::solid::{ClosedMesh, ShadingFrame, SilhouetteBsp, SilhouetteRings};
    /// let (_, bowl) = thesis_polyhedra()?.pop().unwrap();
    /// let bsp = SilhouetteBsp::build(&ClosedMesh::new(bowl)?)?;
    /// let frame = ShadingFrame::new(DVec3::new(0.3, -0.2, 3.0), DVec3::Z, DVec3::Z)?;
    /// let mut rings = SilhouetteRings::new();
    /// bsp.query_rings(&frame, &mut rings)?;
    /// let fast = clamped_cosine_integral_rings(rings.rings())?;
    /// assert!((fast - clamped_cosine_integral(&bsp.query(&frame)?)).abs() < 1e-14);
    /// # Ok::<(), arealight::GeomError>(())
    /// ```
    ///
    /// # Errors
    ///
    /// As [`SilhouetteBsp::query`].
    pub fn query_rings(
        &self,
        frame: &ShadingFrame,
        out: &mut SilhouetteRings,
    ) -> Result<(), GeomError> {
        out.clear();
        let x = frame.origin();
        let leaf = if x.cmpge(self.lo).all() && x.cmple(self.hi).all() {
            self.leaf_of(x, matches!(self.source, Source::Solid(_)))
        } else {
            None
        };
        let Some(leaf) = leaf else {
            out.set_polygon(&self.direct(frame)?);
            return Ok(());
        };
        let at = leaf as usize;
        match &self.source {
            Source::Convex(poly) => {
                if !self.convex_loop_raw(poly, at, frame, out) {
                    out.set_polygon(&convex_silhouette(poly, frame)?);
                }
                Ok(())
            }
            Source::Solid(solid) => match self.read(at) {
                EMPTY => Ok(()),
                FULL => {
                    out.set_full();
                    Ok(())
                }
                DIRECT => {
                    out.set_polygon(&nonconvex_silhouette(solid, frame)?);
                    Ok(())
                }
                _ => self.solid_rings(solid, at, frame, out),
            },
        }
    }

    /// The rings of a non-convex solid's leaf with rings at `at` evaluated at the point
    /// ([`evaluate_rings_into`]: unit vectors) into `out`, checked as the query checks them: at
    /// least three vertices per ring, consecutive ones neither coincident nor antipodal.
    fn solid_rings(
        &self,
        solid: &ClosedMesh,
        mut at: usize,
        frame: &ShadingFrame,
        out: &mut SilhouetteRings,
    ) -> Result<(), GeomError> {
        let header = self.read(at);
        at += 1;
        let (arcs, ends) = self.read_rings(header, &mut at);
        evaluate_rings_into(solid.mesh(), &arcs, &ends, frame, out)?;
        for r in out.rings() {
            let n = r.len();
            let ok = n >= 3
                && (0..n).all(|k| {
                    let (a, b) = (r[k], r[(k + 1) % n]);
                    (a - b).length() > COINCIDENT_TOLERANCE
                        && (a + b).length() > ANTIPODAL_TOLERANCE
                });
            if !ok {
                return Err(GeomError::Undecidable(GIVE_UP_QUERY));
            }
        }
        Ok(())
    }

    /// The stored loop of a convex polyhedron's leaf at `at` written to `out` as the vertices in
    /// the local frame, not normalized, where [`SilhouetteBsp::convex_loop`] returns it (the same
    /// spacing decisions, [`spaced`]); `false` where it returns `None`.
    fn convex_loop_raw(
        &self,
        poly: &ConvexPolyhedron,
        at: usize,
        frame: &ShadingFrame,
        out: &mut SilhouetteRings,
    ) -> bool {
        let len = self.read(at) as usize;
        if len == 0 {
            return false;
        }
        let verts = poly.vertices();
        let first = frame.to_local(verts[self.read(at + 1) as usize]);
        out.push(first);
        let mut prev = first;
        let mut ok = true;
        for k in 1..len {
            let cur = frame.to_local(verts[self.read(at + 1 + k) as usize]);
            ok &= spaced(prev, cur, MATCH_TOLERANCE, ANTIPODAL_TOLERANCE);
            out.push(cur);
            prev = cur;
        }
        if ok && spaced(prev, first, MATCH_TOLERANCE, ANTIPODAL_TOLERANCE) {
            out.close_ring();
            true
        } else {
            out.clear();
            false
        }
    }

    /// A triangulation of the silhouette seen from the frame's point (local frame), written to
    /// `out`: positively oriented spherical triangles with disjoint interiors whose union is
    /// the region of [`SilhouetteBsp::query`] (up to the rounding of its vertices). Where the
    /// tree stores a certified triangulation for the point's cell
    /// ([`SilhouetteBsp::build_triangulated`]), or for a convex polyhedron (the fan of its
    /// silhouette loop), it is evaluated at the point and checked there (each triangle's
    /// orientation exactly, their solid angles below `4 pi`); otherwise, or when that check
    /// fails, the queried silhouette is triangulated at the point
    /// ([`SphericalPolygon::triangulate`]). The result says which.
    ///
    /// # Examples
    ///
    /// ```
    /// use arealight::glam::DVec3;
    /// use arealight::solid::{ClosedMesh, ShadingFrame, SilhouetteBsp, TriangleSource};
    /// use arealight::internals::thesis_polyhedra;
    /// let (_, bowl) = thesis_polyhedra()?.pop().unwrap();
    /// let bsp = SilhouetteBsp::build_triangulated(&ClosedMesh::new(bowl)?)?;
    /// let frame = ShadingFrame::new(DVec3::new(0.3, -0.2, 3.0), DVec3::Z, DVec3::Z)?;
    /// let mut tris = Vec::new();
    /// assert_eq!(bsp.query_triangles(&frame, &mut tris)?, TriangleSource::Stored);
    /// let area: f64 = tris.iter().map(|t| t.solid_angle()).sum();
    /// assert!((area - bsp.query(&frame)?.solid_angle()).abs() < 1e-12);
    /// # Ok::<(), arealight::GeomError>(())
    /// ```
    ///
    /// # Errors
    ///
    /// Those of [`SilhouetteBsp::query`] and [`SphericalPolygon::triangulate`].
    pub fn query_triangles(
        &self,
        frame: &ShadingFrame,
        out: &mut Vec<SphericalTriangle>,
    ) -> Result<TriangleSource, GeomError> {
        out.clear();
        if self.stored_into(frame, out) {
            return Ok(TriangleSource::Stored);
        }
        *out = self.query(frame)?.triangulate()?;
        Ok(TriangleSource::Computed)
    }

    /// The stored triangulation (or convex fan) evaluated and checked at the point; `false`
    /// where there is none or the check fails.
    fn stored_into(&self, frame: &ShadingFrame, out: &mut Vec<SphericalTriangle>) -> bool {
        let x = frame.origin();
        if !(x.cmpge(self.lo).all() && x.cmple(self.hi).all()) {
            return false;
        }
        let Some(leaf) = self.leaf_of(x, true) else {
            return false;
        };
        let mut at = leaf as usize;
        match &self.source {
            Source::Convex(poly) => match self.convex_loop(poly, at, frame) {
                Some(dirs) => {
                    let n = dirs.len() as u32;
                    fan_or_list(&dirs, (1..n - 1).map(|k| [0, k, k + 1]), out)
                }
                None => false,
            },
            Source::Solid(solid) => {
                let header = self.read(at);
                at += 1;
                if !self.triangulated || header < RINGS {
                    return false;
                }
                let (arcs, ends) = self.read_rings(header, &mut at);
                let tris = self.read_triangles(at, arcs.len());
                !tris.is_empty() && evaluate_stored(solid.mesh(), &arcs, &ends, &tris, frame, out)
            }
        }
    }

    /// The stored triangulation of the point's cell evaluated at the point (local frame) with
    /// no check: `None` where there is none. For tests of the build-time certificate.
    #[doc(hidden)]
    #[must_use]
    pub fn stored_triangulation(&self, frame: &ShadingFrame) -> Option<Vec<[DVec3; 3]>> {
        let x = frame.origin();
        if !(x.cmpge(self.lo).all() && x.cmple(self.hi).all()) {
            return None;
        }
        let mut at = self.leaf_of(x, true)? as usize;
        match &self.source {
            Source::Convex(poly) => {
                let d = self.convex_loop(poly, at, frame)?;
                Some((1..d.len() - 1).map(|k| [d[0], d[k], d[k + 1]]).collect())
            }
            Source::Solid(solid) => {
                let header = self.read(at);
                at += 1;
                if !self.triangulated || header < RINGS {
                    return None;
                }
                let (arcs, ends) = self.read_rings(header, &mut at);
                let tris = self.read_triangles(at, arcs.len());
                if tris.is_empty() {
                    return None;
                }
                raw_stored(solid.mesh(), &arcs, &ends, &tris, frame)
            }
        }
    }

    /// The silhouette loop of a convex polyhedron's leaf as unit directions, or `None` where
    /// [`convex_silhouette`] answers (no loop stored, or vertices too close to chain).
    fn convex_loop(
        &self,
        poly: &ConvexPolyhedron,
        at: usize,
        frame: &ShadingFrame,
    ) -> Option<SmallVec<[DVec3; 12]>> {
        let len = self.read(at) as usize;
        if len == 0 {
            return None;
        }
        let verts = poly.vertices();
        let mut out: SmallVec<[DVec3; 12]> = SmallVec::with_capacity(len);
        for k in 0..len {
            let v = verts[self.read(at + 1 + k) as usize];
            out.push(frame.to_local(v).try_normalize()?);
        }
        // The spacing test of `convex_silhouette`, which then takes its general path.
        let spaced = (0..len).all(|k| {
            let (a, b) = (out[k], out[(k + 1) % len]);
            (a - b).length() > MATCH_TOLERANCE && (a + b).length() > ANTIPODAL_TOLERANCE
        });
        spaced.then_some(out)
    }

    /// The rings of a leaf with `header` (at least [`RINGS`]), read from `*at` on; `*at` ends
    /// after them.
    fn read_rings(&self, header: u32, at: &mut usize) -> Rings {
        let mut arcs: SmallVec<[Arc; 24]> = SmallVec::new();
        let mut ends: SmallVec<[u32; 4]> = SmallVec::new();
        for _ in 0..header - RINGS {
            let len = self.read(*at) as usize;
            *at += 1;
            for _ in 0..len {
                let w = self.read(*at);
                *at += 1;
                arcs.push(Arc {
                    edge: w >> 2,
                    forward: w & 2 != 0,
                    from_crossing: w & 1 != 0,
                });
            }
            ends.push(arcs.len() as u32);
        }
        (arcs, ends)
    }

    /// The triangle section of a leaf with `corners` corners at `at` (after its rings): index
    /// triples into the corners, empty where the leaf stores none.
    fn read_triangles(&self, at: usize, corners: usize) -> SmallVec<[[u32; 3]; 16]> {
        let t = self.read(at) as usize;
        if packs(corners, self.width) {
            let n = corners as u32;
            (0..t)
                .map(|k| {
                    let w = self.read(at + 1 + k);
                    [w % n, w / n % n, w / (n * n)]
                })
                .collect()
        } else {
            (0..t)
                .map(|k| {
                    let b = at + 1 + 3 * k;
                    [self.read(b), self.read(b + 1), self.read(b + 2)]
                })
                .collect()
        }
    }

    /// The direct algorithm for the polyhedron.
    fn direct(&self, frame: &ShadingFrame) -> Result<SphericalPolygon, GeomError> {
        match &self.source {
            Source::Convex(p) => convex_silhouette(p, frame),
            Source::Solid(s) => nonconvex_silhouette(s, frame),
        }
    }

    /// Why [`SilhouetteBsp::query`] answers the point with the direct algorithm rather than from
    /// a stored leaf; `None` where it evaluates a stored leaf. For the tests and benchmarks that
    /// report how often that happens.
    #[doc(hidden)]
    #[must_use]
    pub fn direct_reason(&self, frame: &ShadingFrame) -> Option<DirectReason> {
        let x = frame.origin();
        if !(x.cmpge(self.lo).all() && x.cmple(self.hi).all()) {
            return Some(DirectReason::OutsideBox);
        }
        let at = match self.descend(x, matches!(self.source, Source::Solid(_))) {
            Ok(at) => at as usize,
            Err(r) => return Some(r),
        };
        match &self.source {
            Source::Convex(poly) => {
                if self.read(at) == 0 {
                    Some(DirectReason::DirectLeaf)
                } else {
                    self.convex_loop(poly, at, frame)
                        .is_none()
                        .then_some(DirectReason::Spacing)
                }
            }
            Source::Solid(_) => (self.read(at) == DIRECT).then_some(DirectReason::DirectLeaf),
        }
    }

    /// The data offset of the leaf holding `x`; `None` when a triple test is within rounding,
    /// or, with `band`, when `x` lies within the facing predicate's tolerance of a face plane
    /// on the path. A non-convex solid's query always sets it: there the face counts as
    /// edge-on while the exact tests of planes through vertices of that face see `x` on one
    /// side, so `x` may belong to no stored cell (the direct algorithm then decides, or gives
    /// up, itself). The stored triangulations set it for convex polyhedra too: within the band
    /// a face counted edge-on may in fact be seen from its front, and the loop is then convex
    /// only up to the tolerance.
    #[inline]
    fn leaf_of(&self, x: DVec3, band: bool) -> Option<u32> {
        self.descend(x, band).ok()
    }

    /// [`SilhouetteBsp::leaf_of`], saying why where there is no leaf.
    #[inline(always)]
    fn descend(&self, x: DVec3, band: bool) -> Result<u32, DirectReason> {
        let mesh = self.source.mesh();
        // The facing predicate (`face_side`) at x, its tolerance computed once.
        let at = FacingAt::new(mesh, x);
        let (normals, offsets, verts) = (mesh.normals(), mesh.offsets(), mesh.vertices());
        let mask = (1u32 << self.child_bits) - 1;
        let mut i = 0usize;
        loop {
            let w = self.nodes[i];
            if w & LEAF != 0 {
                return Ok(w & !LEAF);
            }
            let p = (w >> self.child_bits) as usize;
            // Face planes (interned first) from their own table: one load of the plane, no
            // dispatch; the distance is the facing predicate's, bit for bit.
            if let Some(&(n, d)) = self.face_eqs.get(p) {
                let s = at.distance(n, d);
                if band && s.abs() <= at.tol() {
                    return Err(DirectReason::FaceBand);
                }
                i = if in_front(s, at.tol()) {
                    (w & mask) as usize
                } else {
                    i + 1
                };
                continue;
            }
            let positive = match self.planes[p] {
                SplitPlane::Face(f) => {
                    let s = at.distance(normals[f as usize], offsets[f as usize]);
                    if band && s.abs() <= at.tol() {
                        return Err(DirectReason::FaceBand);
                    }
                    in_front(s, at.tol())
                }
                SplitPlane::Through([a, b, c]) => {
                    orient3d(
                        c3(verts[a as usize]),
                        c3(verts[b as usize]),
                        c3(verts[c as usize]),
                        c3(x),
                    ) > 0.0
                }
                SplitPlane::Triple(t) => triple_sign(mesh, t, x).ok_or(DirectReason::TripleBand)?,
            };
            i = if positive { (w & mask) as usize } else { i + 1 };
        }
    }

    #[inline]
    fn read(&self, at: usize) -> u32 {
        match self.width {
            1 => u32::from(self.data[at]),
            2 => u32::from(u16::from_le_bytes([
                self.data[2 * at],
                self.data[2 * at + 1],
            ])),
            _ => u32::from_le_bytes([
                self.data[4 * at],
                self.data[4 * at + 1],
                self.data[4 * at + 2],
                self.data[4 * at + 3],
            ]),
        }
    }

    /// Number of nodes (inner nodes and leaves).
    #[must_use]
    pub fn node_count(&self) -> usize {
        self.nodes.len()
    }

    /// Number of leaves (cells).
    #[must_use]
    pub fn leaf_count(&self) -> usize {
        self.leaves as usize
    }

    /// Number of leaves answered by the direct algorithm (the inside of a convex polyhedron;
    /// cells where the direct algorithm gave up at every trial point).
    #[must_use]
    pub fn direct_leaf_count(&self) -> usize {
        self.direct_leaves as usize
    }

    /// Number of distinct splitting planes.
    #[must_use]
    pub fn plane_count(&self) -> usize {
        self.planes.len()
    }

    /// Number of stored silhouette elements (vertex indices for convex polyhedra, arcs for
    /// non-convex meshes; ring lengths and headers not counted).
    #[must_use]
    pub fn silhouette_elements(&self) -> usize {
        let mut n = 0usize;
        for &w in &self.nodes {
            if w & LEAF == 0 {
                continue;
            }
            let mut at = (w & !LEAF) as usize;
            match self.source {
                Source::Convex(_) => n += self.read(at) as usize,
                Source::Solid(_) => {
                    let h = self.read(at);
                    at += 1;
                    if h >= RINGS {
                        for _ in 0..h - RINGS {
                            let len = self.read(at) as usize;
                            n += len;
                            at += 1 + len;
                        }
                    }
                }
            }
        }
        n
    }

    /// Number of leaves that store a certified triangulation
    /// ([`SilhouetteBsp::build_triangulated`]), and number of leaves with silhouette rings (the
    /// leaves that could store one; the others are empty, full, or answered directly).
    #[must_use]
    pub fn triangulated_leaf_count(&self) -> (usize, usize) {
        let (mut stored, mut rings) = (0, 0);
        self.for_each_triangulation(|t| {
            rings += 1;
            stored += usize::from(t > 0);
        });
        (stored, rings)
    }

    /// Number of stored triangles, over all leaves.
    #[must_use]
    pub fn stored_triangle_count(&self) -> usize {
        let mut n = 0;
        self.for_each_triangulation(|t| n += t);
        n
    }

    /// Calls `f` with the stored triangle count of every leaf with rings of a non-convex solid.
    fn for_each_triangulation(&self, mut f: impl FnMut(usize)) {
        if !matches!(self.source, Source::Solid(_)) {
            return;
        }
        for &w in &self.nodes {
            if w & LEAF == 0 {
                continue;
            }
            let mut at = (w & !LEAF) as usize;
            let h = self.read(at);
            at += 1;
            if h < RINGS {
                continue;
            }
            for _ in 0..h - RINGS {
                at += 1 + self.read(at) as usize;
            }
            f(if self.triangulated {
                self.read(at) as usize
            } else {
                0
            });
        }
    }

    /// Bytes of the precomputed data: nodes, leaf data and splitting planes (the mesh itself,
    /// which the query needs too, not counted).
    #[must_use]
    pub fn byte_size(&self) -> usize {
        4 * self.nodes.len()
            + self.data.len()
            + core::mem::size_of::<SplitPlane>() * self.planes.len()
            + core::mem::size_of::<(DVec3, f64)>() * self.face_eqs.len()
    }

    /// The bytes the build counted against its budget ([`SilhouetteBsp::build_with_budget`]):
    /// an upper bound on its peak storage.
    #[must_use]
    pub fn build_bytes(&self) -> usize {
        self.build_bytes
    }

    /// The box of points answered by the tree.
    #[must_use]
    pub fn region(&self) -> (DVec3, DVec3) {
        (self.lo, self.hi)
    }

    /// The splitting planes as unit normals and offsets (`n . x = d`, positive side `n . x > d`
    /// where the query goes right), for tests that probe points near them.
    #[doc(hidden)]
    #[must_use]
    pub fn plane_equations(&self) -> Vec<(DVec3, f64)> {
        let mesh = self.source.mesh();
        self.planes
            .iter()
            .filter(|p| !matches!(p, SplitPlane::Triple(_)))
            .map(|&p| plane_equation(mesh, p))
            .collect()
    }
}

fn check_region(lo: DVec3, hi: DVec3) -> Result<(), GeomError> {
    if !(lo.is_finite() && hi.is_finite()) {
        return Err(GeomError::NonFiniteArgument { what: "BSP region" });
    }
    if !(hi.cmpgt(lo).all()) {
        return Err(GeomError::Degenerate(
            "the BSP region has no volume (lo < hi on every axis)",
        ));
    }
    Ok(())
}

fn default_region(mesh: &TriangleMesh) -> (DVec3, DVec3) {
    let b = mesh.bounding_sphere();
    let h = DVec3::splat(DEFAULT_REGION_RADII * b.radius.max(f64::MIN_POSITIVE));
    (b.center - h, b.center + h)
}

/// The plane of a split plane as `(n, d)`, unit `n`, positive side `n . x > d`.
fn plane_equation(mesh: &TriangleMesh, p: SplitPlane) -> (DVec3, f64) {
    match p {
        SplitPlane::Face(f) => {
            let n = mesh.normals()[f as usize];
            (
                n,
                n.dot(mesh.bounding_sphere().center) + mesh.offsets()[f as usize],
            )
        }
        SplitPlane::Through([a, b, c]) => {
            let v = mesh.vertices();
            let (a, b, c) = (v[a as usize], v[b as usize], v[c as usize]);
            // orient3d(a, b, c, x) = (a - x) . ((b - a) x (c - a)): positive where
            // -N . x > -N . a.
            let n = -(b - a).cross(c - a);
            let len = n.length();
            (n / len, n.dot(a) / len)
        }
        // Not a plane: never used to split cells.
        SplitPlane::Triple(_) => (DVec3::ZERO, 0.0),
    }
}

/// The sign of `det(n_a, n_b, n_c)` at `x` for the mesh edges `t` (`n_e = (a_e - x) x
/// (b_e - x)`): `Some(positive)`, or `None` within the rounding bound that `outline` uses to
/// order crossings ([`ORDER_ERROR`] times the six lengths).
fn triple_sign(mesh: &TriangleMesh, t: [u32; 3], x: DVec3) -> Option<bool> {
    let (v, e) = (mesh.vertices(), mesh.edges());
    let mut bound = ORDER_ERROR;
    let n = t.map(|i| {
        let (a, b) = (
            v[e[i as usize].a as usize] - x,
            v[e[i as usize].b as usize] - x,
        );
        bound *= a.length() * b.length();
        a.cross(b)
    });
    let det = n[0].dot(n[1].cross(n[2]));
    if det > bound {
        Some(true)
    } else if det < -bound {
        Some(false)
    } else {
        None
    }
}

/// Whether the order along mesh edge `e` of its crossings with edges `g` and `h` (seen from a
/// point) is the same everywhere in a convex cell with vertices `cell`, where both crossings
/// exist (so the order is the sign of `det(n_e, n_g, n_h)` up to a factor of fixed sign).
///
/// The crossing with `g` lies at the parameter `alpha_g / beta_g` along `e`, with
/// `alpha_g(x) = det(g_a - x, g_b - x, e_a - x)` and `beta_g = alpha_g - det(g_a - x, g_b - x,
/// e_b - x)`, both affine in `x` (`beta_g` of one sign in the cell). The order is the sign of
/// the quadratic `q = alpha_g beta_h - alpha_h beta_g`, and at a convex combination
/// `x = sum l_i v_i` of the cell's vertices `q = sum l_i l_j M_ij` with `M_ij = alpha_g(v_i)
/// beta_h(v_j) - alpha_h(v_i) beta_g(v_j)`: if every symmetrized `M_ij` has one strict sign
/// (beyond its rounding bound), so has `q` everywhere in the cell.
fn order_constant(mesh: &TriangleMesh, e: u32, g: u32, h: u32, cell: &[DVec3]) -> bool {
    let (v, edges) = (mesh.vertices(), mesh.edges());
    let ends = |i: u32| {
        (
            v[edges[i as usize].a as usize],
            v[edges[i as usize].b as usize],
        )
    };
    let ((ea, eb), (ga, gb), (ha, hb)) = (ends(e), ends(g), ends(h));
    // det(p - x, q - x, r - x) in floating point and its scale |p - x| |q - x| |r - x|.
    let det = |p: DVec3, q: DVec3, r: DVec3, x: DVec3| {
        let (p, q, r) = (p - x, q - x, r - x);
        (p.dot(q.cross(r)), p.length() * q.length() * r.length())
    };
    // Per vertex: alpha and beta for g and h, and their error bounds.
    let vals: SmallVec<[[f64; 8]; 32]> = cell
        .iter()
        .map(|&x| {
            let (g1, sg1) = det(ga, gb, ea, x);
            let (g2, sg2) = det(ga, gb, eb, x);
            let (h1, sh1) = det(ha, hb, ea, x);
            let (h2, sh2) = det(ha, hb, eb, x);
            let err = 1e-14;
            [
                g1,
                g1 - g2,
                h1,
                h1 - h2,
                err * sg1,
                err * (sg1 + sg2),
                err * sh1,
                err * (sh1 + sh2),
            ]
        })
        .collect();
    let term = |i: usize, j: usize| {
        let (a, b) = (vals[i], vals[j]);
        let m = a[0] * b[3] - a[2] * b[1];
        let err = a[4] * b[3].abs() + a[0].abs() * b[7] + a[6] * b[1].abs() + a[2].abs() * b[5];
        (
            m,
            err + 1e-15 * (a[0] * b[3]).abs().max((a[2] * b[1]).abs()),
        )
    };
    let mut sign = 0i8;
    for i in 0..vals.len() {
        for j in i..vals.len() {
            let (m1, e1) = term(i, j);
            let (m2, e2) = term(j, i);
            let (m, err) = (m1 + m2, e1 + e2);
            let s = if m > err {
                1
            } else if m < -err {
                -1
            } else {
                return false;
            };
            if sign == 0 {
                sign = s;
            } else if s != sign {
                return false;
            }
        }
    }
    true
}

/// A convex cell of the first pass: its vertices, each with the planes it lies on (indices
/// into the builder's planes plus 6; 0 to 5 are the box's faces).
#[derive(Debug, Clone, Default)]
struct Cell {
    p: Vec<DVec3>,
    tag: Vec<SmallVec<[u32; 6]>>,
}

impl Cell {
    fn cuboid(lo: DVec3, hi: DVec3) -> Cell {
        let mut c = Cell::default();
        for i in 0..8u32 {
            let p = DVec3::new(
                if i & 1 == 0 { lo.x } else { hi.x },
                if i & 2 == 0 { lo.y } else { hi.y },
                if i & 4 == 0 { lo.z } else { hi.z },
            );
            c.p.push(p);
            c.tag.push(smallvec::smallvec![
                i & 1,
                2 + ((i >> 1) & 1),
                4 + ((i >> 2) & 1)
            ]);
        }
        c
    }

    fn centroid(&self) -> DVec3 {
        self.p.iter().copied().sum::<DVec3>() / self.p.len() as f64
    }

    /// Where the cell lies relative to the plane `n . x = d`: `Some(true)`/`Some(false)` when
    /// entirely on the positive/negative side (within `eps`), `None` when the plane cuts it.
    fn side(&self, n: DVec3, d: f64, eps: f64) -> Option<bool> {
        let (mut pos, mut neg) = (false, false);
        for &p in &self.p {
            let s = n.dot(p) - d;
            pos |= s > eps;
            neg |= s < -eps;
            if pos && neg {
                return None;
            }
        }
        Some(pos)
    }

    /// The two parts of the cell on either side of the plane `n . x = d` (tagged `id`), negative
    /// first. Vertices within `eps` of the plane go to both; each edge (two vertices sharing two
    /// planes) with ends strictly on opposite sides gives a new vertex.
    fn split(&self, n: DVec3, d: f64, id: u32, eps: f64) -> (Cell, Cell) {
        let s: SmallVec<[f64; 32]> = self.p.iter().map(|&p| n.dot(p) - d).collect();
        let (mut neg, mut pos) = (Cell::default(), Cell::default());
        for (k, &sk) in s.iter().enumerate() {
            if sk > eps {
                pos.p.push(self.p[k]);
                pos.tag.push(self.tag[k].clone());
            } else if sk < -eps {
                neg.p.push(self.p[k]);
                neg.tag.push(self.tag[k].clone());
            } else {
                let mut t = self.tag[k].clone();
                t.push(id);
                for c in [&mut neg, &mut pos] {
                    c.p.push(self.p[k]);
                    c.tag.push(t.clone());
                }
            }
        }
        let mut cut: Vec<(DVec3, SmallVec<[u32; 6]>)> = Vec::new();
        for i in 0..self.p.len() {
            if !(s[i] > eps) {
                continue;
            }
            for j in 0..self.p.len() {
                if !(s[j] < -eps) {
                    continue;
                }
                let shared: SmallVec<[u32; 6]> = self.tag[i]
                    .iter()
                    .copied()
                    .filter(|t| self.tag[j].contains(t))
                    .collect();
                if shared.len() < 2 {
                    continue;
                }
                let u = s[i] / (s[i] - s[j]);
                let p = self.p[i] + (self.p[j] - self.p[i]) * u;
                let mut t = shared;
                t.push(id);
                // A cut through a vertex already on the plane, or two edges meeting there.
                if let Some(k) = cut.iter().position(|(q, _)| (*q - p).length() <= eps) {
                    for x in t {
                        if !cut[k].1.contains(&x) {
                            cut[k].1.push(x);
                        }
                    }
                } else {
                    cut.push((p, t));
                }
            }
        }
        for (p, t) in cut {
            for c in [&mut neg, &mut pos] {
                c.p.push(p);
                c.tag.push(t.clone());
            }
        }
        (neg, pos)
    }
}

/// A pair of contour edges of a face cell and its planes (indices into the builder's planes),
/// with the sign that turns each plane's side into the crossing test's sign.
#[derive(Debug, Clone, Copy)]
enum Pair {
    /// Edges sharing a vertex: the plane through both.
    Fold(u32),
    /// Disjoint edges `(s1, t1)` and `(s2, t2)` (directed): the planes of `abc`, `abd`, `cda`,
    /// `cdb` in `outline`'s crossing test, each with its parity (`orient` of the directed
    /// triple = parity * the stored plane's side).
    Cross([(u32, i8); 4]),
}

/// A node while building: the final packing depends on the node and plane counts.
#[derive(Debug, Clone, Copy)]
enum BuildNode {
    Inner { plane: u32, right: u32 },
    Leaf(u32),
}

struct Builder<'a> {
    mesh: &'a TriangleMesh,
    /// The solid, for the non-convex build.
    solid: Option<&'a ClosedMesh>,
    planes: Vec<SplitPlane>,
    geo: Vec<(DVec3, f64)>,
    index: BTreeMap<SplitPlane, u32>,
    nodes: Vec<BuildNode>,
    /// Leaf data as `u32`, packed to the final width at the end.
    data: Vec<u32>,
    eps: f64,
    lo: DVec3,
    hi: DVec3,
    leaves: u32,
    direct_leaves: u32,
    /// Scratch for face distances.
    dist: Vec<f64>,
    /// Planes through vertex triples by sorted indices (`None`: collinear).
    through: BTreeMap<[u32; 3], Option<u32>>,
    /// Per plane: the stamp of the cell whose side `memo` holds, and that side.
    stamp: Vec<u32>,
    memo: Vec<Option<bool>>,
    now: u32,
    /// Whether leaves with rings get a triangulation section, with the exact coplanarity of
    /// vertices and face planes for the certificate.
    triangulate: Option<OnFace>,
    /// When recording: the cell vertices of each leaf that stores a triangulation.
    cells: Option<Vec<Vec<DVec3>>>,
    /// The last triangulation certified per leaf structure (encoded outline), tried first in
    /// the next cell with that structure (neighbouring cells often share it).
    last_triangulation: BTreeMap<Vec<u32>, Vec<[u32; 3]>>,
    /// Bytes the build may hold ([`SilhouetteBsp::build_with_budget`]) and bytes counted so
    /// far; once over, every step returns at once and [`Builder::finish`] fails.
    budget: usize,
    used: usize,
}

impl<'a> Builder<'a> {
    fn new(
        mesh: &'a TriangleMesh,
        solid: Option<&'a ClosedMesh>,
        lo: DVec3,
        hi: DVec3,
        budget: usize,
    ) -> Self {
        Builder {
            mesh,
            solid,
            planes: Vec::new(),
            geo: Vec::new(),
            index: BTreeMap::new(),
            nodes: Vec::new(),
            data: Vec::new(),
            eps: CELL_EPS * (hi - lo).max_element(),
            lo,
            hi,
            leaves: 0,
            direct_leaves: 0,
            dist: Vec::new(),
            through: BTreeMap::new(),
            stamp: Vec::new(),
            memo: Vec::new(),
            now: 0,
            triangulate: None,
            cells: None,
            last_triangulation: BTreeMap::new(),
            budget,
            used: 0,
        }
    }

    /// Counts `bytes` more held by the build; `false` once the count exceeds the budget.
    #[inline]
    fn charge(&mut self, bytes: usize) -> bool {
        self.used = self.used.saturating_add(bytes);
        self.used <= self.budget
    }

    /// Whether the build is over its budget (and stopping).
    #[inline]
    fn over(&self) -> bool {
        self.used > self.budget
    }

    /// Appends a node, counting it.
    #[inline]
    fn push_node(&mut self, node: BuildNode) {
        self.charge(core::mem::size_of::<BuildNode>());
        self.nodes.push(node);
    }

    fn plane(&mut self, p: SplitPlane) -> u32 {
        if let Some(&i) = self.index.get(&p) {
            return i;
        }
        let i = self.planes.len() as u32;
        // The plane, its equation, its index entry and its memo slots.
        self.charge(
            core::mem::size_of::<SplitPlane>() * 2
                + core::mem::size_of::<(DVec3, f64)>()
                + core::mem::size_of::<u32>() * 2
                + core::mem::size_of::<Option<bool>>(),
        );
        self.planes.push(p);
        self.geo.push(plane_equation(self.mesh, p));
        self.index.insert(p, i);
        i
    }

    /// The face planes, one per set of triangles in one plane facing the same way (within
    /// rounding; duplicates would never cut a cell again anyway).
    fn face_planes(&mut self) -> Vec<u32> {
        let m = self.mesh;
        let r = m.bounding_sphere().radius;
        let mut out: Vec<u32> = Vec::new();
        for f in 0..m.triangle_count() {
            let (n, d) = plane_equation(m, SplitPlane::Face(f as u32));
            let dup = out.iter().any(|&i| {
                let (n2, d2) = self.geo[i as usize];
                (n - n2).length() <= 1e-12 && (d - d2).abs() <= 1e-12 * r.max(d.abs())
            });
            if !dup {
                out.push(self.plane(SplitPlane::Face(f as u32)));
            }
        }
        out
    }

    /// First pass: the cells of the arrangement of `cands` in `cell` (explicit splitting, the
    /// first cutting plane each time).
    fn enumerate(&mut self, cell: Cell, cands: Vec<u32>) -> Vec<Cell> {
        let mut out = Vec::new();
        let mut stack = vec![(cell, cands)];
        while let Some((cell, cands)) = stack.pop() {
            if self.over() {
                break;
            }
            let cutting: Vec<u32> = cands
                .into_iter()
                .filter(|&i| {
                    let (n, d) = self.geo[i as usize];
                    cell.side(n, d, self.eps).is_none()
                })
                .collect();
            let Some((&first, rest)) = cutting.split_first() else {
                // The cell is kept (its vertices and their planes) and gets a representative
                // point and a word of sides per 64 face planes in the second pass.
                self.charge(
                    core::mem::size_of::<Cell>()
                        + cell.p.capacity() * core::mem::size_of::<DVec3>()
                        + cell.tag.capacity() * core::mem::size_of::<SmallVec<[u32; 6]>>()
                        + core::mem::size_of::<DVec3>()
                        + 8 * self.geo.len().div_ceil(64),
                );
                out.push(cell);
                continue;
            };
            let (n, d) = self.geo[first as usize];
            let (neg, pos) = cell.split(n, d, first + 6, self.eps);
            stack.push((pos, rest.to_vec()));
            stack.push((neg, rest.to_vec()));
        }
        out
    }

    /// Second pass: the balanced tree over representative points `pts` (indices `items`),
    /// splitting with `cands` (the plane that splits the remaining points most evenly), emitting
    /// nodes in preorder; each leaf (one point) is emitted by `leaf`.
    fn balanced(
        &mut self,
        sides: &[u64],
        words: usize,
        items: &mut [u32],
        cands: &[u32],
        leaf: &mut dyn FnMut(&mut Self, u32),
    ) {
        if self.over() {
            return;
        }
        let bit = |item: u32, c: u32| {
            sides[item as usize * words + (c >> 6) as usize] >> (c & 63) & 1 == 1
        };
        let n = items.len();
        if n == 1 {
            leaf(self, items[0]);
            return;
        }
        let mut keep: Vec<u32> = Vec::with_capacity(cands.len());
        let mut best: Option<(usize, u32)> = None;
        for &c in cands {
            let pos = items.iter().filter(|&&it| bit(it, c)).count();
            if pos == 0 || pos == n {
                continue;
            }
            keep.push(c);
            let imbalance = (2 * pos).abs_diff(n);
            if best.is_none_or(|(b, _)| imbalance < b) {
                best = Some((imbalance, c));
            }
        }
        let Some((_, c)) = best else {
            // Representative points no plane separates: cells that coincide within rounding.
            leaf(self, items[0]);
            return;
        };
        // Partition: negative side first.
        let mut k = 0;
        for i in 0..n {
            if !bit(items[i], c) {
                items.swap(i, k);
                k += 1;
            }
        }
        let node = self.nodes.len();
        self.push_node(BuildNode::Inner { plane: c, right: 0 });
        let (neg, pos) = items.split_at_mut(k);
        self.balanced(sides, words, neg, &keep, leaf);
        let right = self.nodes.len() as u32;
        self.nodes[node] = BuildNode::Inner { plane: c, right };
        self.balanced(sides, words, pos, &keep, leaf);
    }

    fn leaf_word(&mut self, payload: &[u32]) {
        self.leaves += 1;
        self.charge(core::mem::size_of_val(payload));
        self.push_node(BuildNode::Leaf(self.data.len() as u32));
        self.data.extend_from_slice(payload);
    }

    /// The face-plane level: first pass, then the balanced second pass with `leaf` per cell.
    fn face_level(
        &mut self,
        keep_cells: bool,
        leaf: &mut dyn FnMut(&mut Self, DVec3, Option<Cell>),
    ) {
        let faces = self.face_planes();
        let cells = self.enumerate(Cell::cuboid(self.lo, self.hi), faces.clone());
        let reps: Vec<DVec3> = cells.iter().map(Cell::centroid).collect();
        let words = faces.len().div_ceil(64).max(1);
        // Plane indices of the face planes are 0..faces.len() (interned first).
        let mut sides = vec![0u64; reps.len() * words];
        let m = self.mesh;
        for (k, &x) in reps.iter().enumerate() {
            // The facing predicate, with the tolerance at x computed once.
            let at = FacingAt::new(m, x);
            for &c in &faces {
                let SplitPlane::Face(f) = self.planes[c as usize] else {
                    continue;
                };
                if at.front(m.normals()[f as usize], m.offsets()[f as usize]) {
                    sides[k * words + (c >> 6) as usize] |= 1 << (c & 63);
                }
            }
        }
        let mut items: Vec<u32> = (0..reps.len() as u32).collect();
        let mut cells: Vec<Option<Cell>> = if keep_cells {
            cells.into_iter().map(Some).collect()
        } else {
            Vec::new()
        };
        self.balanced(&sides, words, &mut items, &faces, &mut |b, item| {
            let cell = cells.get_mut(item as usize).and_then(Option::take);
            leaf(b, reps[item as usize], cell);
        });
    }

    fn build_convex(&mut self) {
        self.face_level(false, &mut |b, rep, _| {
            let payload = convex_ring(b.mesh, rep, &mut b.dist);
            if payload.len() <= 1 {
                b.direct_leaves += 1;
            }
            b.leaf_word(&payload);
        });
    }

    fn build_nonconvex(&mut self) {
        self.face_level(true, &mut |b, rep, cell| {
            let cell = cell.unwrap_or_default();
            b.face_cell(cell, rep);
        });
    }

    /// The subtree of one face cell: its contour (constant in the cell) gives the pairs whose
    /// planes may split it; cells are split (first pass only) until no pair's crossing can
    /// change inside a cell.
    fn face_cell(&mut self, cell: Cell, rep: DVec3) {
        let mesh = self.mesh;
        let tol = face_distances(mesh, rep, &mut self.dist);
        let front: Vec<bool> = self
            .dist
            .iter()
            .map(|&d| Side::of(d, tol) == Side::Front)
            .collect();
        // Directed contour edges (start, end) and their lines, as `outline` takes them.
        let lines = self.solid.map(ClosedMesh::edge_lines).unwrap_or(&[]);
        let mut contour: Vec<(u32, u32, u32)> = Vec::new();
        let mut edge_of: Vec<u32> = Vec::new();
        for (ei, e) in mesh.edges().iter().enumerate() {
            let Some(f1) = e.twin() else { continue };
            let (a, b) = (front[e.f0 as usize], front[f1 as usize]);
            if a != b {
                let line = lines.get(ei).copied().unwrap_or(ei as u32);
                contour.push(if b {
                    (e.a, e.b, line)
                } else {
                    (e.b, e.a, line)
                });
                edge_of.push(ei as u32);
            }
        }
        let solid = self.solid;
        let on_line = |e: u32, v: u32| solid.is_some_and(|s| s.on_edge_line(e, v));
        let mut pairs: Vec<Pair> = Vec::new();
        for i in 0..contour.len() {
            for j in i + 1..contour.len() {
                let ((s1, t1, l1), (s2, t2, l2)) = (contour[i], contour[j]);
                let (e1, e2) = (edge_of[i], edge_of[j]);
                let shares = s1 == s2 || s1 == t2 || t1 == s2 || t1 == t2;
                if l1 == l2
                    || (!shares
                        && (on_line(e1, s2)
                            || on_line(e1, t2)
                            || on_line(e2, s1)
                            || on_line(e2, t1)))
                {
                    continue; // never cross (see `outline`)
                }
                let shared = [s1, t1].into_iter().find(|x| *x == s2 || *x == t2);
                if let Some(sv) = shared {
                    let a = if s1 == sv { t1 } else { s1 };
                    let b = if s2 == sv { t2 } else { s2 };
                    if let Some((p, _)) = self.through(sv, a, b) {
                        pairs.push(Pair::Fold(p));
                    }
                    continue;
                }
                // An endpoint on the other edge's line (exactly) makes `outline` rule the
                // crossing out for every point, so such pairs need no plane.
                let trip = [(s1, t1, s2), (s1, t1, t2), (s2, t2, s1), (s2, t2, t1)];
                let mut planes = [(u32::MAX, 0i8); 4];
                let mut degenerate = false;
                for (k, &(a, b, c)) in trip.iter().enumerate() {
                    match self.through(a, b, c) {
                        Some(p) => planes[k] = p,
                        None => degenerate = true,
                    }
                }
                if !degenerate {
                    pairs.push(Pair::Cross(planes));
                }
            }
        }
        let _ = rep;
        self.split_pairs(cell, pairs);
    }

    /// The plane through vertices `a`, `b`, `c` (interned by sorted indices) and the parity of
    /// `(a, b, c)` against the stored order; `None` for collinear vertices.
    fn through(&mut self, a: u32, b: u32, c: u32) -> Option<(u32, i8)> {
        let mut s = [a, b, c];
        // Sorting by index: each swap flips the orientation.
        let mut parity = 1i8;
        for i in 0..3 {
            for j in 0..2 - i {
                if s[j] > s[j + 1] {
                    s.swap(j, j + 1);
                    parity = -parity;
                }
            }
        }
        let id = match self.through.get(&s) {
            Some(&id) => id,
            None => {
                let v = self.mesh.vertices();
                let id = (!collinear(v[s[0] as usize], v[s[1] as usize], v[s[2] as usize]))
                    .then(|| self.plane(SplitPlane::Through(s)));
                self.through.insert(s, id);
                id
            }
        };
        id.map(|id| (id, parity))
    }

    /// Splits `cell` by the planes of `pairs` whose crossing (or fold) can change inside it.
    fn split_pairs(&mut self, cell: Cell, pairs: Vec<Pair>) {
        if self.over() {
            return;
        }
        // Side of the cell on each plane the pairs use (None: cut), computed once per plane.
        self.now += 1;
        let now = self.now;
        self.stamp.resize(self.planes.len(), 0);
        self.memo.resize(self.planes.len(), None);
        let (eps, geo, stamp, memo) = (self.eps, &self.geo, &mut self.stamp, &mut self.memo);
        let mut side = |i: u32| -> Option<bool> {
            let i = i as usize;
            if stamp[i] != now {
                stamp[i] = now;
                let (n, d) = geo[i];
                memo[i] = cell.side(n, d, eps);
            }
            memo[i]
        };
        let mut live: Vec<Pair> = Vec::new();
        let mut cutting: Vec<u32> = Vec::new();
        for p in pairs {
            match p {
                Pair::Fold(i) => {
                    if side(i).is_none() {
                        live.push(p);
                        cutting.push(i);
                    }
                }
                Pair::Cross(pl) => {
                    // Signs of abc, abd, cda, cdb where fixed over the cell.
                    let sg: [Option<i8>; 4] =
                        pl.map(|(i, par)| side(i).map(|s| if s { par } else { -par }));
                    let never = |x: Option<i8>, y: Option<i8>| matches!((x, y), (Some(a), Some(b)) if a == b);
                    // The endpoints of one edge on one side of the other's plane throughout,
                    // or the crossing on the antipodes throughout: no crossing in the cell.
                    if never(sg[0], sg[1])
                        || never(sg[2], sg[3])
                        || matches!((sg[1], sg[2]), (Some(a), Some(b)) if a != b)
                    {
                        continue;
                    }
                    if sg.iter().all(Option::is_some) {
                        continue; // decided the same way everywhere in the cell
                    }
                    live.push(p);
                    for (k, &(i, _)) in pl.iter().enumerate() {
                        if sg[k].is_none() {
                            cutting.push(i);
                        }
                    }
                }
            }
        }
        cutting.sort_unstable();
        cutting.dedup();
        if cutting.is_empty() {
            self.outline_leaf(&cell);
            return;
        }
        // The plane that splits the cell's vertices most evenly.
        let mut best = (usize::MAX, cutting[0]);
        for &i in &cutting {
            let (n, d) = self.geo[i as usize];
            let pos = cell.p.iter().filter(|&&p| n.dot(p) > d).count();
            let imb = (2 * pos).abs_diff(cell.p.len());
            if imb < best.0 {
                best = (imb, i);
            }
        }
        let c = best.1;
        let (n, d) = self.geo[c as usize];
        let (neg, pos) = cell.split(n, d, c + 6, self.eps);
        let node = self.nodes.len();
        self.push_node(BuildNode::Inner { plane: c, right: 0 });
        self.split_pairs(neg, live.clone());
        let right = self.nodes.len() as u32;
        self.nodes[node] = BuildNode::Inner { plane: c, right };
        self.split_pairs(pos, live);
    }

    /// The leaf (or small subtree) of a final cell of the plane splits: the outline at the
    /// cell's centroid (or another interior point where the direct algorithm gives up there).
    /// Its crossings' orders along the contour edges can still change inside the cell where
    /// three contour edges are seen concurrent (a quadric surface): every triple of crossing
    /// edges whose order is not proven constant over the cell ([`order_constant`]) becomes a
    /// triple test, and each combination of their signs met at sample points of the cell gets
    /// the outline at such a sample; combinations no sample met are answered directly.
    fn outline_leaf(&mut self, cell: &Cell) {
        if self.over() {
            return;
        }
        let Some(solid) = self.solid else {
            self.direct_leaves += 1;
            self.leaf_word(&[DIRECT]);
            return;
        };
        let c = cell.centroid();
        let mut crossed = Vec::new();
        let tries = core::iter::once(c).chain(cell.p.iter().map(|&p| c + (p - c) * 0.5));
        let mut found = None;
        for t in tries {
            if let Ok(o) = outline_with(solid, t, Some(&mut crossed)) {
                found = Some((o, t));
                break;
            }
        }
        let Some((first, at)) = found else {
            self.direct_leaves += 1;
            self.leaf_word(&[DIRECT]);
            return;
        };
        let mut varying: Vec<[u32; 3]> = Vec::new();
        for (e, others) in &crossed {
            for (i, &g) in others.iter().enumerate() {
                for &h in &others[i + 1..] {
                    let mut t = [*e, g, h];
                    t.sort_unstable();
                    if !varying.contains(&t) && !order_constant(self.mesh, *e, g, h, &cell.p) {
                        varying.push(t);
                    }
                }
            }
        }
        let corners = self
            .triangulate
            .is_some()
            .then(|| self.snapped_vertices(cell));
        if varying.is_empty() {
            // Further points to triangulate at: vertices pulled half-way to the centroid.
            let samples: Vec<DVec3> = cell.p.iter().take(4).map(|&p| c + (p - c) * 0.5).collect();
            let payload = self.outline_payload(&first, at, corners.as_ref(), &samples);
            self.leaf_word(&payload);
            return;
        }
        if varying.len() > 16 {
            self.direct_leaves += 1;
            self.leaf_word(&[DIRECT]);
            return;
        }
        // Sample points strictly inside the cell: the centroid, the vertices pulled a tenth
        // and a half of the way to it, and midpoints of vertex pairs pulled a twentieth.
        let mut pts: Vec<DVec3> = vec![c];
        for &p in &cell.p {
            pts.push(c + (p - c) * 0.9);
            pts.push(c + (p - c) * 0.5);
        }
        for i in 0..cell.p.len() {
            for j in i + 1..cell.p.len() {
                pts.push(c + ((cell.p[i] + cell.p[j]) * 0.5 - c) * 0.95);
            }
        }
        let _ = c;
        let mut samples: Vec<(DVec3, u32)> = Vec::new();
        'pts: for p in pts {
            let mut bits = 0u32;
            for (k, &t) in varying.iter().enumerate() {
                match triple_sign(self.mesh, t, p) {
                    Some(true) => bits |= 1 << k,
                    Some(false) => {}
                    None => continue 'pts,
                }
            }
            samples.push((p, bits));
        }
        self.triple_tree(solid, &varying, 0, samples, corners.as_ref());
    }

    /// A leaf's data for the outline `o` found at the point `at`: [`encode_outline`], and when
    /// building triangulations (`cell` given) and `o` has rings, its triangle section, with a
    /// triangulation certified over `cell` (tried at `at`, then at `samples`) or none.
    fn outline_payload(
        &mut self,
        o: &Outline,
        at: DVec3,
        cell: Option<&CellCorners>,
        samples: &[DVec3],
    ) -> Vec<u32> {
        let mut payload = encode_outline(o);
        if let (Some(on_face), Some(cell), Outline::Rings { arcs, ends }) =
            (&self.triangulate, cell, o)
        {
            let hint = self.last_triangulation.get(&payload).map(Vec::as_slice);
            let extra = Extra { samples, hint };
            let tris = certified_triangulation(self.mesh, arcs, ends, at, cell, on_face, extra);
            if let Some(t) = &tris {
                self.last_triangulation.insert(payload.clone(), t.clone());
            }
            push_triangles(&mut payload, tris.as_deref().unwrap_or(&[]));
            if let (Some(cells), Some(_)) = (&mut self.cells, &tris) {
                cells.push(cell.p.clone());
            }
        }
        payload
    }

    /// The decision subtree over the signs of `varying[k..]` for the `samples` (points with
    /// their sign bits) that reached it.
    fn triple_tree(
        &mut self,
        solid: &ClosedMesh,
        varying: &[[u32; 3]],
        k: usize,
        mut samples: Vec<(DVec3, u32)>,
        cell: Option<&CellCorners>,
    ) {
        if self.over() {
            return;
        }
        if samples.is_empty() {
            self.direct_leaves += 1;
            self.leaf_word(&[DIRECT]);
            return;
        }
        if k == varying.len() {
            for (i, &(p, _)) in samples.iter().enumerate() {
                if let Ok(o) = outline(solid, p) {
                    // The triangulation is certified over the whole cell (condition 1 of the
                    // certificate holds on any part of it); condition 3 is the query's own
                    // check, since the part with these signs may be disconnected.
                    let others: Vec<DVec3> = samples[i + 1..].iter().take(4).map(|s| s.0).collect();
                    let payload = self.outline_payload(&o, p, cell, &others);
                    self.leaf_word(&payload);
                    return;
                }
            }
            self.direct_leaves += 1;
            self.leaf_word(&[DIRECT]);
            return;
        }
        let id = self.plane(SplitPlane::Triple(varying[k]));
        let pos: Vec<(DVec3, u32)> = samples
            .iter()
            .copied()
            .filter(|s| s.1 >> k & 1 == 1)
            .collect();
        samples.retain(|s| s.1 >> k & 1 == 0);
        let node = self.nodes.len();
        self.push_node(BuildNode::Inner {
            plane: id,
            right: 0,
        });
        self.triple_tree(solid, varying, k + 1, samples, cell);
        let right = self.nodes.len() as u32;
        self.nodes[node] = BuildNode::Inner { plane: id, right };
        self.triple_tree(solid, varying, k + 1, pos, cell);
    }

    /// The cell's vertices, each snapped to a mesh vertex `m` where it is the intersection of
    /// planes that all contain `m` exactly (three of them with independent normals, so that
    /// their intersection is `m`) and lies within [`SNAP_REL`] of the box's size of it: such
    /// corners (cells touching the solid) are where the triangulation certificate evaluates
    /// affine functions that vanish at `m`, whose sign at the rounded vertex would be noise.
    fn snapped_vertices(&self, cell: &Cell) -> CellCorners {
        let verts = self.mesh.vertices();
        let tris = self.mesh.triangles();
        let points = |plane: u32| -> Option<[u32; 3]> {
            match self.planes[plane as usize] {
                SplitPlane::Face(f) => Some(tris[f as usize]),
                SplitPlane::Through(s) => Some(s),
                SplitPlane::Triple(_) => None,
            }
        };
        let reach = SNAP_REL * (self.hi - self.lo).max_element();
        let mut out = CellCorners {
            p: Vec::with_capacity(cell.p.len()),
            faces: Vec::with_capacity(cell.p.len()),
        };
        for (p, tags) in cell.p.iter().zip(&cell.tag) {
            let planes: SmallVec<[[u32; 3]; 6]> = tags
                .iter()
                .filter(|&&t| t >= 6)
                .filter_map(|&t| points(t - 6))
                .collect();
            let mut snapped = *p;
            if planes.len() >= 3 {
                let found = planes.iter().flatten().copied().find(|&m| {
                    let q = verts[m as usize];
                    (q - *p).length() <= reach
                        && planes.iter().all(|s| {
                            s.contains(&m)
                                || orient3d(
                                    c3(verts[s[0] as usize]),
                                    c3(verts[s[1] as usize]),
                                    c3(verts[s[2] as usize]),
                                    c3(q),
                                ) == 0.0
                        })
                        && independent(verts, &planes)
                });
                if let Some(m) = found {
                    snapped = verts[m as usize];
                }
            }
            out.p.push(snapped);
            out.faces.push(
                tags.iter()
                    .filter(|&&t| t >= 6)
                    .filter_map(|&t| match self.planes[(t - 6) as usize] {
                        SplitPlane::Face(f) => Some(f),
                        _ => None,
                    })
                    .collect(),
            );
        }
        out
    }

    /// Packs the leaves' triangle sections (see [`packs`]) once the width of everything else
    /// is known, moving the leaves' data offsets; returns that width.
    fn pack_triangles(&mut self) -> u8 {
        // The leaves' data in order (their offsets increase with the node order).
        let leaves: Vec<usize> = self
            .nodes
            .iter()
            .filter_map(|n| match n {
                BuildNode::Leaf(off) => Some(*off as usize),
                BuildNode::Inner { .. } => None,
            })
            .collect();
        // Per leaf with rings: where its triangle count is, its corners and its triangles.
        let parse = |at: usize| -> Option<(usize, usize, usize)> {
            let h = self.data[at];
            if h < RINGS {
                return None;
            }
            let (mut p, mut n) = (at + 1, 0usize);
            for _ in 0..h - RINGS {
                let len = self.data[p] as usize;
                n += len;
                p += 1 + len;
            }
            Some((p, n, self.data[p] as usize))
        };
        let mut max = 0u32;
        for &at in &leaves {
            let end = parse(at).map_or(at + 1, |(p, _, _)| p + 1);
            max = max.max(self.data[at..end].iter().copied().max().unwrap_or(0));
        }
        let width = width_of(max);
        let mut out: Vec<u32> = Vec::with_capacity(self.data.len());
        let mut moved: Vec<u32> = Vec::with_capacity(leaves.len());
        for &at in &leaves {
            moved.push(out.len() as u32);
            match parse(at) {
                None => out.push(self.data[at]),
                Some((p, n, t)) => {
                    out.extend_from_slice(&self.data[at..=p]);
                    for k in 0..t {
                        let tri = &self.data[p + 1 + 3 * k..p + 4 + 3 * k];
                        if packs(n, width) {
                            let n = n as u32;
                            out.push(tri[0] + n * (tri[1] + n * tri[2]));
                        } else {
                            out.extend_from_slice(tri);
                        }
                    }
                }
            }
        }
        let mut k = 0;
        for node in &mut self.nodes {
            if let BuildNode::Leaf(off) = node {
                *off = moved[k];
                k += 1;
            }
        }
        self.data = out;
        width
    }

    fn finish(mut self, source: Source, lo: DVec3, hi: DVec3) -> Result<SilhouetteBsp, GeomError> {
        if self.over() {
            return Err(GeomError::OutOfRange {
                what: "bytes held by the BSP build (its budget; see \
                       SilhouetteBsp::build_with_budget)",
                value: self.used as f64,
                limit: self.budget as f64,
            });
        }
        let n = self.nodes.len() as u64;
        let child_bits = (64 - n.max(2).leading_zeros()).max(1);
        let plane_bits = 64 - (self.planes.len() as u64).max(1).leading_zeros();
        if child_bits + plane_bits > 31 || self.data.len() as u64 >= u64::from(LEAF) {
            return Err(GeomError::OutOfRange {
                what: "BSP nodes times planes (the compact node format)",
                value: (n as f64) * self.planes.len() as f64,
                limit: f64::from(LEAF),
            });
        }
        let packed = self.triangulate.is_some().then(|| self.pack_triangles());
        let nodes: Vec<u32> = self
            .nodes
            .iter()
            .map(|&w| match w {
                BuildNode::Leaf(off) => LEAF | off,
                BuildNode::Inner { plane, right } => (plane << child_bits) | right,
            })
            .collect();
        let width =
            packed.unwrap_or_else(|| width_of(self.data.iter().copied().max().unwrap_or(0)));
        let mut data = Vec::with_capacity(self.data.len() * width as usize);
        for &x in &self.data {
            data.extend_from_slice(&x.to_le_bytes()[..width as usize]);
        }
        let face_eqs = self
            .planes
            .iter()
            .map_while(|p| match *p {
                SplitPlane::Face(f) => Some((
                    self.mesh.normals()[f as usize],
                    self.mesh.offsets()[f as usize],
                )),
                _ => None,
            })
            .collect();
        Ok(SilhouetteBsp {
            source,
            face_eqs,
            planes: self.planes,
            nodes,
            child_bits,
            data,
            width,
            lo,
            hi,
            leaves: self.leaves,
            direct_leaves: self.direct_leaves,
            triangulated: self.triangulate.is_some(),
            build_bytes: self.used,
        })
    }
}

/// The narrowest data width (bytes) that holds `max`.
fn width_of(max: u32) -> u8 {
    if max < 1 << 8 {
        1
    } else if max < 1 << 16 {
        2
    } else {
        4
    }
}

/// Whether a leaf with `n` corners stores each triangle as one word `i + n (j + n k)` at data
/// width `width`: when `n^3` fits the width.
fn packs(n: usize, width: u8) -> bool {
    (n as u64).pow(3) <= 1u64 << (8 * u32::from(width))
}

/// Whether three of the planes through the given vertex triples have clearly independent normals
/// (the determinant of their unit normals beyond `1e-6`), so that they meet in one point.
fn independent(verts: &[DVec3], planes: &[[u32; 3]]) -> bool {
    let normals: SmallVec<[DVec3; 6]> = planes
        .iter()
        .filter_map(|s| {
            let [a, b, c] = s.map(|i| verts[i as usize]);
            (b - a).cross(c - a).try_normalize()
        })
        .collect();
    let n = normals.len();
    for i in 0..n {
        for j in i + 1..n {
            for k in j + 1..n {
                if normals[i].dot(normals[j].cross(normals[k])).abs() > 1e-6 {
                    return true;
                }
            }
        }
    }
    false
}

/// Leaf data of a convex polyhedron seen from `x`: `[len, vertex indices]` of the silhouette
/// loop as [`convex_silhouette`] chains it (the same contour edges in the same order, so the
/// same ring from the same start), or `[0]` where that takes another path (no front face: the
/// inside; a contour that is not one loop).
fn convex_ring(mesh: &TriangleMesh, x: DVec3, dist: &mut Vec<f64>) -> Vec<u32> {
    let tol = face_distances(mesh, x, dist);
    let front = |d: f64| Side::of(d, tol) == Side::Front;
    if !dist.iter().any(|&d| front(d)) {
        return vec![0];
    }
    let mut contour: SmallVec<[(u32, u32); 24]> = SmallVec::new();
    for e in mesh.edges() {
        let Some(f1) = e.twin() else { continue };
        match (front(dist[e.f0 as usize]), front(dist[f1 as usize])) {
            (true, false) => contour.push((e.b, e.a)),
            (false, true) => contour.push((e.a, e.b)),
            _ => {}
        }
    }
    match chain_by_index(&contour, mesh.vertices().len()) {
        Some(ring) => {
            let mut out = Vec::with_capacity(ring.len() + 1);
            out.push(ring.len() as u32);
            out.extend(ring.iter().copied());
            out
        }
        None => vec![0],
    }
}

/// Appends a leaf's triangle section: the count, then the index triples.
fn push_triangles(payload: &mut Vec<u32>, tris: &[[u32; 3]]) {
    payload.push(tris.len() as u32);
    for t in tris {
        payload.extend_from_slice(t);
    }
}

/// Leaf data of a closed non-convex mesh: a header ([`EMPTY`], [`FULL`], or `RINGS + rings`),
/// then per ring its length and its arcs as `edge << 2 | forward << 1 | from_crossing`.
fn encode_outline(o: &Outline) -> Vec<u32> {
    match o {
        Outline::Empty => vec![EMPTY],
        Outline::Full => vec![FULL],
        Outline::Rings { arcs, ends } => {
            let mut out = Vec::with_capacity(1 + ends.len() + arcs.len());
            out.push(RINGS + ends.len() as u32);
            let mut start = 0usize;
            for &end in ends {
                out.push(end - start as u32);
                for a in &arcs[start..end as usize] {
                    out.push(a.edge << 2 | u32::from(a.forward) << 1 | u32::from(a.from_crossing));
                }
                start = end as usize;
            }
            out
        }
    }
}
