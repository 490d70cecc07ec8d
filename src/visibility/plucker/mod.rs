//! The second exact-visibility backend: lazy visibility in Pluecker space (seed 002).
//!
//! [`PluckerVisibility`] answers the same question as [`ClipVisibility`] (which part of a light a
//! shading point sees) with the lazily built BSP of seed 002: lines from the point through a
//! light face are classified by the occluder triangles they stab, in a tree over Pluecker
//! space whose inner nodes are occluder edges ([`PluckerLine`], the side operator). The light
//! face is split by the plane through the point and each node's line until every fragment lies
//! in one class; the fragments in visible classes are the visible region, as convex spherical
//! polygons in the shading frame. The tree is grown only where queries need it, and is reused
//! by later queries of the same light from nearby points ([`PluckerContext`], seed 002 Alg. 2).
//!
//! - `line.rs`: Pluecker coordinates, the side operator with certified signs, line-polygon
//!   tests, Theorem 1 ([`vvset_orientation`]).
//! - `bsp.rs`: the tree: insertion by Theorem 1, merging an occluder's classes (Alg. 1).
//! - `query.rs`: the query that splits the light (Alg. 1 `BSP_query`), fragments to polygons.
//! - `tile.rs`: trees per light and receiver tile, shaft culling, the cuts that make the tree
//!   exact (Alg. 2).
//!
//! # The rule, and how the tree decides it
//!
//! The backend evaluates the rule of [`ClipVisibility::visible_region`] exactly as stated
//! there: per front face `f` of the light, `visible(f) = proj(f) - U_B proj(B n H_f)`, every
//! object opaque (occluders, the other lights, and a non-planar mesh light's own other
//! triangles), the pieces of all front faces together. Per face (coplanar faces of one light
//! share a tree), the blocker triangles are cut to the open side `H_f` of the face's plane that
//! holds the point (with the facing predicate's snapped distances, as the clipping backend) and
//! to the open upper side of the point's tangent plane; a direction `d` above the horizon is then
//! hidden iff the line from the point along `d` stabs a cut triangle, since such a line meets
//! the region strictly between the tangent plane and `H_f`'s boundary only on the open segment
//! from the point to the face. The horizon is applied by clipping the face to the tangent plane
//! in space before the query, so the pieces are in the upper hemisphere without a spherical
//! clip.
//!
//! # Degenerate lines
//!
//! A blocker is an open polygon for this backend: a line hides a direction only if it crosses
//! the polygon's relative interior, i.e. its side operator with every edge is strictly of one
//! sign. Lines through a vertex, along an edge or in the polygon's plane hide nothing. The
//! directions where this differs from a closed polygon have measure zero, except where the
//! point itself lies on a blocker's edge line or plane: then every line from the point meets
//! that line or plane, and the rule says the blocker hides nothing, which is the clipping
//! backend's "seen edge-on covers nothing" (a blocker triangle whose plane passes within the
//! facing tolerance [`FACE_TOLERANCE`](crate::solid::FACE_TOLERANCE) of the point is dropped
//! for that point, as there). In the tree this is the node's rule for side zero: a fragment
//! whose lines all have side zero goes to the child where that edge cannot close the
//! occluder's invisible class (`bsp.rs`), and insertion sends an occluder to one child only when
//! all its vertex-to-vertex lines are strictly on that side, so any child is safe for such lines
//! with respect to the other occluders.
//!
//! Query points on the light: a face whose plane holds the point (within the facing tolerance)
//! is not a front face and contributes nothing; a point inside or on a closed light sees no
//! front face and gets nothing, as the Monte Carlo reference and [`Method::PerTriangle`] (the
//! silhouette path of the clipping backend counts the silhouette instead; see the `shade`
//! module's limitations).
//!
//! # Lights bounded by curves
//!
//! A light bounded by Bezier curves ([`BezierShape`](crate::solid::BezierShape)) is seen
//! through a flattening chosen per shading point, within an angle of its curves
//! ([`BezierShape::region`](crate::solid::BezierShape::region)); the trees here are built over
//! a light's fixed faces, and its fixed mesh is within a distance of the curves, not an angle,
//! so from near points it would be a coarser light than the clipping backend's. Queries of
//! such a light are answered by the clipping backend held here (same result, no tree, not
//! counted in [`PluckerStats`]). As a blocker of other lights it is its mesh in both backends.
//!
//! # Reuse and memory
//!
//! [`Visibility::visible_region`] builds a tree per call for the point alone (the point is the
//! tile, its shaft is the cone to the light face): exact, no reuse, no state. A
//! [`PluckerContext`], owned by one thread, keeps trees across calls
//! ([`PluckerVisibility::visible_region_in`]): the receiver plane (the frame's normal and the
//! point's offset along it) is cut into square cells of a size the caller chooses, and the
//! queries of one light from points of one cell share one tree per light face plane, with the
//! occluders culled once against the shaft from the cell to the face. The backend itself is
//! immutable, so a renderer shares one among its threads, each with its own context.
//!
//! Every tree has a memory cap (bytes, [`PluckerContext::with_budget`] /
//! [`PluckerVisibility::with_tree_cap`]). A tree that outgrows it during a query is reset to
//! its root and the query repeated; a query that alone outgrows it (from an empty tree) is
//! answered by the clipping backend. Neither aborts; [`PluckerStats`] counts both. A point that
//! cannot use its cell's shared tree (it lies within the near band of a blocker's plane, or
//! sees one edge-on) takes a tree of its own, or, when the shared tree is crowded (more than 64
//! occluders, where a tree for one point costs more than the clipping backend), the clipping
//! backend's answer ([`PluckerStats::crowded_fallbacks`]).
//!
//! # References
//!
//! - Seed 002: F. Mora, L. Aveneau, O. Apostu, D. Ghazanfarpour, *Lazy Visibility Evaluation for
//!   Exact Soft Shadows* (research report; cited by seed 000 as \[MAAG12\]): section 3.1
//!   (Pluecker coordinates, the side operator), section 3.3 (Theorem 1), section 4.2 and Alg. 1
//!   (insertion, merge, query), section 4.4 and Alg. 2 (one tree per light and receiver).
//! - J. R. Shewchuk, *Adaptive Precision Floating-Point Arithmetic and Fast Robust Geometric
//!   Predicates*, 1997 (the `orient3d` the signs fall back to).

mod bsp;
mod line;
mod query;
mod tile;

use alloc::collections::BTreeMap;
use alloc::vec::Vec;
use core::sync::atomic::{AtomicUsize, Ordering};

use glam::{DVec2, DVec3};
use smallvec::SmallVec;

use super::cull::above_horizon;
use super::{Blocker, ClipVisibility, Visibility};
use crate::GeomError;
use crate::math::floor;
use crate::planar::predicates::monotone_hull;
use crate::solid::facing::{Side, face_side};
use crate::solid::{Body, ShadingFrame, TriangleMesh};
use crate::sphere::SphericalPolygon;

pub use bsp::TreeCounters;
pub use line::{Orientation, PluckerLine, Sign, Stab, line_polygon, side_sign, vvset_orientation};

use query::{CapExceeded, Fragment, Scratch, clip_above, fragment_polygon, query};
use tile::{BlockerTri, Bvh, GroupSource, GroupTree, Owners, TileGeometry, build_group_tree};

#[cfg(doc)]
use super::Method;

/// A tile whose tree takes more occluders than this (after shaft culling) is split into four
/// sub-cells of half the side, once ([`MAX_SPLIT`]); see [`PluckerContext`].
const SPLIT_OCCLUDERS: usize = 160;

/// How many times a tile may be halved.
const MAX_SPLIT: u8 = 1;

/// A point that cannot use its tile's shared tree (it lies in the near band of a blocker's
/// plane or sees one edge-on, `tile.rs`) is answered by the clipping backend instead of a tree
/// of its own when the shared tree holds more occluders than this: a tree built and developed
/// for one point costs about as much as a query without reuse, and in shafts this crowded that
/// is more than the clipping backend's answer (`benches/plucker.rs`, the cost of a tree per
/// query over `clip`'s: 0.75x at 968 terrain triangles, 34 occluders per shared tree at most;
/// 1.3x at 10K, 85; 2.5x at 100K, 223; 0.16x on the boxes at 100K, 29). Both answers are exact; where the clipping
/// backend gives up (`GeomError`), the point's own tree answers.
const CROWDED_OCCLUDERS: usize = 64;

/// The default memory cap of one tree, in bytes.
pub const DEFAULT_TREE_CAP: usize = 64 << 20;

/// Faces of a light that share one plane and one facing side: they share a tree.
#[derive(Debug, Clone, PartialEq)]
struct FaceGroup {
    faces: SmallVec<[u32; 2]>,
    /// The face whose plane stands for the group's (the facing predicate's distances).
    rep: u32,
    /// The convex polygon the faces tile exactly, counter-clockwise about their normal, if they
    /// do (a quad's two triangles): queried as one polygon when every face is a front face.
    hull: Option<SmallVec<[DVec3; 8]>>,
}

#[derive(Debug, Clone, PartialEq)]
struct LightFaces {
    groups: Vec<FaceGroup>,
    /// The light's own triangles are blockers of its faces (a non-planar mesh light).
    own: bool,
}

/// Identifies a backend to the contexts that cache its trees.
static NEXT_ID: AtomicUsize = AtomicUsize::new(1);

/// The lazy Pluecker-space visibility backend (seed 002): the same lights, occluders and rule
/// as [`ClipVisibility`] (which it holds, for its fallback), plus a bounding-volume hierarchy
/// over every blocker triangle and the lights' faces grouped by plane.
///
/// Implements [`Visibility`] without reuse (one tree per call); for reuse across coherent
/// queries give each thread a [`PluckerContext`] and call
/// [`PluckerVisibility::visible_region_in`]. See the [module documentation](self) for the rule,
/// the degenerate cases and the memory cap.
///
/// # Examples
///
/// ```
/// use arealight::glam::DVec3;
/// use arealight::shade::{ConvexPolyhedron, Light, Scene, ShadingFrame, TriangleMesh};
/// use arealight::visibility::Visibility;
/// use arealight::visibility::plucker::{PluckerContext, PluckerVisibility};
/// let quad = TriangleMesh::quad(DVec3::new(0.0, 0.0, 3.0), DVec3::Y * 0.5, DVec3::X * 0.5)?;
/// let cube = ConvexPolyhedron::cuboid(DVec3::new(0.3, 0.0, 1.5), DVec3::splat(0.25))?;
/// let scene = Scene::new(vec![Light::new(quad, DVec3::ONE)?], vec![cube.into()])?;
/// let plucker = PluckerVisibility::from_clip(scene.visibility().clone());
/// let frame = ShadingFrame::new(DVec3::ZERO, DVec3::Z, DVec3::Z)?;
/// let area = |pieces: Vec<arealight::sphere::SphericalPolygon>| {
///     pieces.iter().map(|p| p.solid_angle()).sum::<f64>()
/// };
/// let clip = area(scene.visibility().visible_region(0, &frame)?);
/// let lazy = area(plucker.visible_region(0, &frame)?);
/// assert!((clip - lazy).abs() < 1e-12);
/// // With a context, later queries from the same cell reuse the tree.
/// let mut ctx = PluckerContext::new(0.25)?;
/// let reused = area(plucker.visible_region_in(&mut ctx, 0, &frame)?);
/// assert!((clip - reused).abs() < 1e-12);
/// # Ok::<(), arealight::GeomError>(())
/// ```
#[derive(Debug, Clone)]
pub struct PluckerVisibility<L> {
    clip: ClipVisibility<L>,
    bvh: Bvh,
    lights: Vec<LightFaces>,
    tree_cap: usize,
    id: usize,
}

impl<L: AsRef<Body>> PluckerVisibility<L> {
    /// The backend for these lights and occluders (see [`PluckerVisibility::from_clip`]).
    #[must_use]
    pub fn new(lights: Vec<L>, occluders: Vec<Body>) -> Self {
        Self::from_clip(ClipVisibility::new(lights, occluders))
    }

    /// The backend over the lights and occluders of a clipping backend (which it keeps, with its
    /// method, as the fallback of queries that outgrow the memory cap): every triangle of every
    /// object in a bounding-volume hierarchy, and each light's faces grouped by plane.
    #[must_use]
    pub fn from_clip(clip: ClipVisibility<L>) -> Self {
        let mut tris = Vec::new();
        let bodies = clip
            .occluders()
            .iter()
            .enumerate()
            .map(|(k, b)| (Blocker::Occluder(k), b))
            .chain(
                clip.lights()
                    .iter()
                    .enumerate()
                    .map(|(k, l)| (Blocker::Light(k), l.as_ref())),
            );
        for (owner, body) in bodies {
            let m = body.mesh();
            for (t, adj) in tile::mesh_adjacency(m).into_iter().enumerate() {
                tris.push(BlockerTri {
                    v: m.triangle(t),
                    owner,
                    tri: t as u32,
                    adj,
                });
            }
        }
        let lights = clip
            .lights()
            .iter()
            .map(|l| {
                let body = l.as_ref();
                LightFaces {
                    groups: face_groups(body.mesh()),
                    own: matches!(body, Body::Mesh(_)) && !body.mesh().is_planar(),
                }
            })
            .collect();
        PluckerVisibility {
            clip,
            bvh: Bvh::new(tris),
            lights,
            tree_cap: DEFAULT_TREE_CAP,
            id: NEXT_ID.fetch_add(1, Ordering::Relaxed),
        }
    }

    /// The same backend with another memory cap for the trees of [`Visibility`] calls (a call
    /// whose tree outgrows it is answered by the clipping backend).
    #[must_use]
    pub fn with_tree_cap(mut self, bytes: usize) -> Self {
        self.tree_cap = bytes;
        self
    }

    /// The clipping backend over the same scene (the fallback).
    #[must_use]
    pub fn clip(&self) -> &ClipVisibility<L> {
        &self.clip
    }

    /// The lights.
    #[must_use]
    pub fn lights(&self) -> &[L] {
        self.clip.lights()
    }

    /// The occluders.
    #[must_use]
    pub fn occluders(&self) -> &[Body] {
        self.clip.occluders()
    }

    fn mesh_of(&self, b: Blocker) -> &TriangleMesh {
        match b {
            Blocker::Occluder(k) => self.clip.occluders()[k].mesh(),
            Blocker::Light(k) => self.clip.lights()[k].as_ref().mesh(),
        }
    }

    /// [`Visibility::visible_region`] with the trees kept in `ctx` and reused by later calls of
    /// the same light from the same receiver cell (seed 002 Alg. 2): same result up to rounding.
    ///
    /// # Errors
    ///
    /// As [`Visibility::visible_region`].
    pub fn visible_region_in(
        &self,
        ctx: &mut PluckerContext,
        light: usize,
        frame: &ShadingFrame,
    ) -> Result<Vec<SphericalPolygon>, GeomError> {
        if ctx.backend != Some(self.id) {
            ctx.clear();
            ctx.backend = Some(self.id);
        }
        ctx.stats.queries += 1;
        let out = self.region(light, frame, true, Some(ctx));
        ctx.after_query();
        out
    }

    fn light_faces(&self, light: usize) -> Result<(&Body, &LightFaces), GeomError> {
        match (self.clip.lights().get(light), self.lights.get(light)) {
            (Some(l), Some(f)) => Ok((l.as_ref(), f)),
            _ => Err(GeomError::OutOfRange {
                what: "light index",
                value: light as f64,
                limit: self.lights.len() as f64,
            }),
        }
    }

    /// The visible (`blocked`) or unoccluded region of light `light`.
    fn region(
        &self,
        light: usize,
        frame: &ShadingFrame,
        blocked: bool,
        mut ctx: Option<&mut PluckerContext>,
    ) -> Result<Vec<SphericalPolygon>, GeomError> {
        let (body, faces) = self.light_faces(light)?;
        if matches!(body, Body::Bezier(_)) {
            // The faces here would be the shape's fixed mesh, not the flattening within an
            // angle of the curves that the clipping backend projects per point (see
            // "Lights bounded by curves" in the module documentation).
            return if blocked {
                self.clip.visible_region(light, frame)
            } else {
                self.clip.unoccluded_region(light, frame)
            };
        }
        let (x, n) = (frame.origin(), frame.normal());
        if !above_horizon(x, n, body.bounding_sphere()) {
            return Ok(Vec::new());
        }
        let mesh = body.mesh();
        let owners = if blocked {
            Owners::All {
                light,
                own: faces.own,
            }
        } else {
            Owners::Own { light }
        };
        let has_blockers = blocked || faces.own;
        let mut local_scratch = Workspace::default();
        let mut out = Vec::new();
        let mut tile_index = None;
        for (g, group) in faces.groups.iter().enumerate() {
            let front: SmallVec<[u32; 4]> = group
                .faces
                .iter()
                .copied()
                .filter(|&f| face_side(mesh, f as usize, x) == Side::Front)
                .collect();
            if front.is_empty() {
                continue;
            }
            let mut polys: SmallVec<[SmallVec<[DVec3; 8]>; 2]> = SmallVec::new();
            match &group.hull {
                Some(h) if front.len() == group.faces.len() => polys.push(h.clone()),
                _ => {
                    for &f in &front {
                        polys.push(mesh.triangle(f as usize).into_iter().collect());
                    }
                }
            }
            let source = GroupSource {
                mesh,
                faces: &group.faces,
                rep: group.rep as usize,
            };
            if !has_blockers {
                for poly in &polys {
                    let local: Fragment = poly.iter().map(|&p| p - x).collect();
                    if let Some(frag) = clip_above(&local, DVec3::ZERO, n) {
                        push_piece(&mut out, &frag, DVec3::ZERO, frame)?;
                    }
                }
                continue;
            }
            let status = match ctx.as_deref_mut() {
                // A tile that splits is looked up again: the point's sub-cell (at most
                // `MAX_SPLIT` times, as only tiles above that level split).
                Some(c) => loop {
                    let ti = match tile_index {
                        Some(ti) => ti,
                        None => {
                            let ti = c.tile_for(light, x, n, faces.groups.len());
                            tile_index = Some(ti);
                            ti
                        }
                    };
                    let status =
                        self.query_cached(c, ti, g, &source, owners, &polys, frame, &mut out);
                    // The query may have grown, built, reset or dropped the tile's trees.
                    c.refresh_bytes(ti);
                    match status? {
                        Status::Split => tile_index = None,
                        status => break status,
                    }
                },
                None => Status::Fallback,
            };
            if status == Status::Crowded {
                let clip = if blocked {
                    self.clip.visible_region(light, frame)
                } else {
                    self.clip.unoccluded_region(light, frame)
                };
                if let Ok(region) = clip {
                    if let Some(c) = ctx.as_deref_mut() {
                        c.stats.crowded_fallbacks += 1;
                    }
                    return Ok(region);
                }
            }
            let status = match status {
                Status::Done => Status::Done,
                Status::Fallback | Status::Crowded => {
                    let ws = match ctx.as_deref_mut() {
                        Some(c) => &mut c.ws,
                        None => &mut local_scratch,
                    };
                    self.query_single(ws, &source, owners, &polys, frame, &mut out)?
                }
                Status::TooBig | Status::Split => Status::TooBig,
            };
            if status == Status::TooBig {
                if let Some(c) = ctx.as_deref_mut() {
                    c.stats.clip_fallbacks += 1;
                }
                return if blocked {
                    self.clip.visible_region(light, frame)
                } else {
                    self.clip.unoccluded_region(light, frame)
                };
            }
        }
        Ok(out)
    }

    /// Queries `polys` through group `g`'s tree in tile `ti` of the context, building it on
    /// first use. [`Status::Fallback`] when the point sees a near blocker edge-on (the shared
    /// tree does not apply); [`Status::TooBig`] when one query alone outgrows the cap;
    /// [`Status::Split`] when the tree just built takes more than [`SPLIT_OCCLUDERS`] occluders
    /// and the tile is split instead (its trees dropped, the point to look up its sub-cell).
    #[allow(clippy::too_many_arguments)]
    fn query_cached(
        &self,
        ctx: &mut PluckerContext,
        ti: usize,
        g: usize,
        source: &GroupSource<'_>,
        owners: Owners,
        polys: &[SmallVec<[DVec3; 8]>],
        frame: &ShadingFrame,
        out: &mut Vec<SphericalPolygon>,
    ) -> Result<Status, GeomError> {
        let (x, n) = (frame.origin(), frame.normal());
        let PluckerContext {
            tiles,
            ws,
            stats,
            budget,
            reuse,
            ..
        } = ctx;
        let tile = &mut tiles[ti];
        if matches!(tile.slots[g], Slot::Unbuilt) {
            let seed = (tile.cell.0 as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15)
                ^ (tile.cell.1 as u64).wrapping_mul(0xC2B2_AE3D_27D4_EB4F)
                ^ (g as u64 + 1);
            tile.slots[g] = match build_group_tree(
                &self.bvh,
                &|b| self.mesh_of(b),
                source,
                owners,
                &tile.geom,
                seed,
                &mut ws.cull,
                bsp::TreeBuffers::default(),
            ) {
                Some(t) if t.tree.occluder_count() > SPLIT_OCCLUDERS && tile.level < MAX_SPLIT => {
                    stats.trees_built += 1;
                    stats.tiles_split += 1;
                    tile.split = true;
                    for slot in &mut tile.slots {
                        *slot = Slot::Unbuilt;
                    }
                    return Ok(Status::Split);
                }
                Some(t) => {
                    stats.trees_built += 1;
                    stats.max_tree_occluders =
                        stats.max_tree_occluders.max(t.tree.occluder_count());
                    Slot::Built(alloc::boxed::Box::new(t))
                }
                None => Slot::Empty,
            };
        }
        let Slot::Built(built) = &mut tile.slots[g] else {
            return Ok(Status::Done);
        };
        if built.excludes(x, n, polys, &|b| self.mesh_of(b)) {
            stats.edge_on_fallbacks += 1;
            return Ok(if built.tree.occluder_count() > CROWDED_OCCLUDERS {
                Status::Crowded
            } else {
                Status::Fallback
            });
        }
        let tree = &mut built.tree;
        if !*reuse {
            tree.reset();
        }
        let origin = tile.geom.origin;
        let xl = x - origin;
        let mut before = tree.counters;
        let mut attempt = 0;
        loop {
            ws.frags.clear();
            let mut result = Ok(());
            for poly in polys {
                let local: Fragment = poly.iter().map(|&p| p - x).collect();
                if let Some(frag) = clip_above(&local, DVec3::ZERO, n) {
                    result = query(tree, xl, n, &frag, *budget, &mut ws.frags, &mut ws.scratch);
                    if result.is_err() {
                        break;
                    }
                }
            }
            stats.note_tree(tree);
            stats.merges += tree.counters.merges - before.merges;
            stats.insertion_tests += tree.counters.insertion_tests - before.insertion_tests;
            stats.shortcuts += tree.counters.shortcuts - before.shortcuts;
            before = tree.counters;
            match result {
                Ok(()) => break,
                Err(CapExceeded) if attempt == 0 => {
                    stats.tree_resets += 1;
                    tree.reset();
                    attempt += 1;
                }
                Err(CapExceeded) => {
                    tree.reset();
                    return Ok(Status::TooBig);
                }
            }
        }
        stats.fragments += ws.frags.len() as u64;
        for frag in &ws.frags {
            push_piece(out, frag, DVec3::ZERO, frame)?;
        }
        Ok(Status::Done)
    }

    /// Queries `polys` through a tree built for the frame's point alone.
    fn query_single(
        &self,
        ws: &mut Workspace,
        source: &GroupSource<'_>,
        owners: Owners,
        polys: &[SmallVec<[DVec3; 8]>],
        frame: &ShadingFrame,
        out: &mut Vec<SphericalPolygon>,
    ) -> Result<Status, GeomError> {
        let (x, n) = (frame.origin(), frame.normal());
        let geom = TileGeometry {
            origin: x,
            p0: x,
            n,
            cell: core::iter::once(x).collect(),
        };
        let Some(GroupTree { mut tree, .. }) = build_group_tree(
            &self.bvh,
            &|b| self.mesh_of(b),
            source,
            owners,
            &geom,
            0x2545_f491_4f6c_dd1d,
            &mut ws.cull,
            core::mem::take(&mut ws.tree),
        ) else {
            return Ok(Status::Done);
        };
        ws.frags.clear();
        for poly in polys {
            let local: Fragment = poly.iter().map(|&p| p - x).collect();
            if let Some(frag) = clip_above(&local, DVec3::ZERO, n)
                && query(
                    &mut tree,
                    DVec3::ZERO,
                    n,
                    &frag,
                    self.tree_cap,
                    &mut ws.frags,
                    &mut ws.scratch,
                )
                .is_err()
            {
                return Ok(Status::TooBig);
            }
        }
        ws.tree = tree.into_buffers();
        for frag in &ws.frags {
            push_piece(out, frag, DVec3::ZERO, frame)?;
        }
        Ok(Status::Done)
    }
}

/// A [`PluckerVisibility`] seen through one thread's [`PluckerContext`]: a [`Visibility`] whose
/// [`Visibility::visible_region`] is [`PluckerVisibility::visible_region_in`], so that code
/// written against the trait (e.g. `Scene::shade_with`) reuses trees. Not `Sync`: one per
/// thread, as the context.
#[derive(Debug)]
pub struct WithContext<'a, L> {
    backend: &'a PluckerVisibility<L>,
    ctx: core::cell::RefCell<&'a mut PluckerContext>,
}

impl<L: AsRef<Body>> PluckerVisibility<L> {
    /// This backend answering through `ctx` (see [`WithContext`]).
    ///
    /// # Examples
    ///
    /// ```
    /// use arealight::glam::DVec3;
    /// use arealight::shade::{ConvexPolyhedron, Light, Material, Scene, TriangleMesh};
    /// use arealight::visibility::{PluckerContext, PluckerVisibility};
    /// let quad = TriangleMesh::quad(DVec3::new(0.0, 0.0, 3.0), DVec3::Y * 0.5, DVec3::X * 0.5)?;
    /// let cube = ConvexPolyhedron::cuboid(DVec3::new(0.3, 0.0, 1.5), DVec3::splat(0.25))?;
    /// let scene = Scene::new(vec![Light::new(quad, DVec3::ONE)?], vec![cube.into()])?;
    /// let floor = Material::diffuse(DVec3::splat(0.8))?;
    /// let plucker = PluckerVisibility::from_clip(scene.visibility().clone());
    /// let mut ctx = PluckerContext::new(0.25)?;
    /// for k in 0..8 {
    ///     let x = DVec3::new(0.01 * k as f64, 0.0, 0.0);
    ///     let clip = scene.shade(x, DVec3::Z, DVec3::Z, &floor)?;
    ///     let vis = plucker.with_context(&mut ctx);
    ///     let lazy = scene.shade_with(&vis, x, DVec3::Z, DVec3::Z, &floor)?;
    ///     assert!((lazy - clip).abs().max_element() <= 1e-12 * clip.max_element());
    /// }
    /// // The eight points share one cell: one tree, reused.
    /// assert_eq!((ctx.stats().queries, ctx.stats().trees_built), (8, 1));
    /// # Ok::<(), arealight::GeomError>(())
    /// ```
    #[must_use]
    pub fn with_context<'a>(&'a self, ctx: &'a mut PluckerContext) -> WithContext<'a, L> {
        WithContext {
            backend: self,
            ctx: core::cell::RefCell::new(ctx),
        }
    }
}

impl<L: AsRef<Body>> Visibility for WithContext<'_, L> {
    fn light_count(&self) -> usize {
        self.backend.light_count()
    }

    /// [`PluckerVisibility::visible_region_in`] with the context.
    fn visible_region(
        &self,
        light: usize,
        frame: &ShadingFrame,
    ) -> Result<Vec<SphericalPolygon>, GeomError> {
        // Calls do not nest (the backend never calls back into the trait), so the borrow is
        // always free.
        let mut ctx = self.ctx.borrow_mut();
        self.backend.visible_region_in(&mut ctx, light, frame)
    }

    fn unoccluded_region(
        &self,
        light: usize,
        frame: &ShadingFrame,
    ) -> Result<Vec<SphericalPolygon>, GeomError> {
        self.backend.unoccluded_region(light, frame)
    }
}

impl<L: AsRef<Body>> Visibility for PluckerVisibility<L> {
    fn light_count(&self) -> usize {
        self.lights.len()
    }

    /// The visible part of light `light`, by a tree built for this point alone (no reuse; see
    /// [`PluckerVisibility::visible_region_in`] for reuse): convex pieces with disjoint
    /// interiors in the upper hemisphere, one per visible fragment of a front face.
    fn visible_region(
        &self,
        light: usize,
        frame: &ShadingFrame,
    ) -> Result<Vec<SphericalPolygon>, GeomError> {
        self.region(light, frame, true, None)
    }

    fn unoccluded_region(
        &self,
        light: usize,
        frame: &ShadingFrame,
    ) -> Result<Vec<SphericalPolygon>, GeomError> {
        self.region(light, frame, false, None)
    }
}

/// How a group's query ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Status {
    Done,
    /// The shared tree does not apply to this point: use a tree of its own.
    Fallback,
    /// The shared tree does not apply to this point and holds more than [`CROWDED_OCCLUDERS`]
    /// occluders: ask the clipping backend, else use a tree of its own.
    Crowded,
    /// One query alone outgrew the cap: answer by the clipping backend.
    TooBig,
    /// The tile was split: look up the point's sub-cell.
    Split,
}

fn push_piece(
    out: &mut Vec<SphericalPolygon>,
    frag: &[DVec3],
    x: DVec3,
    frame: &ShadingFrame,
) -> Result<(), GeomError> {
    if let Some(p) = fragment_polygon(frag, x, frame)? {
        out.push(p);
    }
    Ok(())
}

/// The faces of a light mesh grouped by plane: faces whose normals agree within `1e-12` and
/// whose corners lie on the first face's plane by the facing predicate.
fn face_groups(mesh: &TriangleMesh) -> Vec<FaceGroup> {
    let mut groups: Vec<FaceGroup> = Vec::new();
    for f in 0..mesh.triangle_count() {
        let nf = mesh.triangle_normal(f);
        let found = groups.iter_mut().find(|g| {
            let r = g.rep as usize;
            (mesh.triangle_normal(r) - nf).length() <= 1e-12
                && mesh
                    .triangle(f)
                    .iter()
                    .all(|&v| face_side(mesh, r, v) == Side::On)
        });
        match found {
            Some(g) => g.faces.push(f as u32),
            None => groups.push(FaceGroup {
                faces: core::iter::once(f as u32).collect(),
                rep: f as u32,
                hull: None,
            }),
        }
    }
    for g in &mut groups {
        g.hull = group_hull(mesh, &g.faces);
    }
    groups
}

/// The convex polygon that coplanar faces tile exactly (their areas sum to its area within
/// `1e-12`), counter-clockwise about their normal; a single face is its own.
fn group_hull(mesh: &TriangleMesh, faces: &[u32]) -> Option<SmallVec<[DVec3; 8]>> {
    if let [f] = faces {
        return Some(mesh.triangle(*f as usize).into_iter().collect());
    }
    let n = mesh.triangle_normal(faces[0] as usize);
    let (t, b) = n.any_orthonormal_pair();
    let mut pts: Vec<DVec3> = Vec::new();
    for &f in faces {
        for v in mesh.triangle(f as usize) {
            if !pts.contains(&v) {
                pts.push(v);
            }
        }
    }
    if pts.len() > 8 {
        return None;
    }
    let flat: Vec<DVec2> = pts.iter().map(|p| DVec2::new(p.dot(t), p.dot(b))).collect();
    let mut hull: Vec<DVec3> = monotone_hull(&flat).into_iter().map(|i| pts[i]).collect();
    if hull.len() < 3 {
        return None;
    }
    if t.cross(b).dot(n) < 0.0 {
        hull.reverse();
    }
    let area = |poly: &[DVec3]| {
        let mut s = DVec3::ZERO;
        for i in 1..poly.len() - 1 {
            s += (poly[i] - poly[0]).cross(poly[i + 1] - poly[0]);
        }
        s.length() / 2.0
    };
    let faces_area: f64 = faces
        .iter()
        .map(|&f| area(&mesh.triangle(f as usize)))
        .sum();
    ((area(&hull) - faces_area).abs() <= 1e-12 * faces_area).then(|| hull.into_iter().collect())
}

/// Counters and peaks of a [`PluckerContext`] since it was made or cleared.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct PluckerStats {
    /// Calls of [`PluckerVisibility::visible_region_in`].
    pub queries: u64,
    /// Tiles created (a light and a receiver cell).
    pub tiles_built: u64,
    /// Trees created (a face plane of a light in a tile).
    pub trees_built: u64,
    /// Tiles split into four because a tree of theirs took more than 160 occluders (their
    /// points then use trees of the sub-cells; see [`PluckerContext`]).
    pub tiles_split: u64,
    /// Tiles dropped to stay within the budget or the tile count.
    pub evictions: u64,
    /// Trees reset to their root because a query made them outgrow the budget.
    pub tree_resets: u64,
    /// Queries answered by the clipping backend: one query alone outgrew the budget.
    pub clip_fallbacks: u64,
    /// Queries from a point that sees a blocker of its tile edge-on or lies within `1e-5` of
    /// the coordinates' magnitude of its plane, or that a blocker left out of the shared tree
    /// (its part above the tile plane within that band of it) may hide some of the light
    /// from, answered by a tree of their own.
    pub edge_on_fallbacks: u64,
    /// Of those, queries answered by the clipping backend because the shared tree was crowded
    /// (a tree of the point's own would cost more; see [`PluckerContext`]).
    pub crowded_fallbacks: u64,
    /// Visible fragments returned.
    pub fragments: u64,
    /// The largest tree seen, in bytes.
    pub peak_tree_bytes: usize,
    /// The largest tree seen, in nodes.
    pub peak_tree_nodes: usize,
    /// The most bytes held by all cached trees together after a query.
    pub peak_cached_bytes: usize,
    /// The most occluders one tree started with (after shaft culling).
    pub max_tree_occluders: usize,
    /// Occluders merged at undefined leaves, over all trees (seed 002 Alg. 1 line 32).
    pub merges: u64,
    /// Orientation tests of insertion, over all trees (Alg. 1 lines 6-13).
    pub insertion_tests: u64,
    /// Fragments found visible at an undefined leaf without developing it, over all trees
    /// (no occluder of the leaf can hide them from the query point).
    pub shortcuts: u64,
}

impl PluckerStats {
    fn note_tree(&mut self, tree: &bsp::Tree) {
        self.peak_tree_bytes = self.peak_tree_bytes.max(tree.peak_bytes());
        self.peak_tree_nodes = self.peak_tree_nodes.max(tree.node_count());
    }
}

/// Buffers reused across queries.
#[derive(Debug, Default, Clone)]
struct Workspace {
    scratch: Scratch,
    frags: Vec<Fragment>,
    cull: Vec<u32>,
    /// The allocations of the last per-point tree.
    tree: bsp::TreeBuffers,
}

#[derive(Debug, Clone)]
enum Slot {
    Unbuilt,
    /// Nothing of the face plane lies above the tile.
    Empty,
    Built(alloc::boxed::Box<GroupTree>),
}

#[derive(Debug, Clone)]
struct Tile {
    light: usize,
    normal: DVec3,
    offset: f64,
    cell: (i64, i64),
    /// The cell's side is the context's over `2^level`.
    level: u8,
    /// The tile holds no trees: its points look up their sub-cell at the next level.
    split: bool,
    geom: TileGeometry,
    slots: Vec<Slot>,
    last_used: u64,
    /// [`Tile::bytes`] when last counted ([`PluckerContext::refresh_bytes`]).
    counted: usize,
}

/// What identifies a tile besides its plane's offset: the light, the level, the cell and the
/// receiver normal's bits ([`PluckerContext::tile_for`]).
type TileKey = (usize, u8, (i64, i64), [u64; 3]);

impl Tile {
    fn key(&self) -> TileKey {
        (
            self.light,
            self.level,
            self.cell,
            self.normal.to_array().map(f64::to_bits),
        )
    }

    fn bytes(&self) -> usize {
        self.slots
            .iter()
            .map(|s| match s {
                Slot::Built(t) => t.tree.bytes(),
                _ => 0,
            })
            .sum()
    }
}

/// What one thread keeps between queries of a [`PluckerVisibility`] (seed 002 Alg. 2): trees
/// per light and receiver cell, their budget, buffers and counters.
///
/// A receiver cell is a square of side `cell_size` in the plane through the shading point with
/// the frame's normal, on a grid fixed by that normal; queries share a cell when their normals
/// are bitwise equal (points of one flat receiver) and their offsets along it agree to `1e-14`
/// of their coordinates' magnitude plus the cell size. Smaller cells cull more occluders per
/// tree, larger ones let more queries reuse one tree. A tile whose tree would take more than
/// 160 occluders is split once into the four cells of half the side (on the same grid), and its
/// points use their sub-cell's trees ([`PluckerStats::tiles_split`]): every occluder
/// straddling a node's plane is inserted on both sides of it, and in a crowded shaft most do,
/// so halving the tile pays for the queries the sub-cells no longer share (`benches/plucker.rs`,
/// cells of half the side: terrain at 100K triangles, 577 occluders per tree, -25% per query;
/// at 10K, 113 occluders, +8%; a quarter of the side at 100K, -19%; with pairs of mesh
/// triangles merged, `tile.rs`, a threshold of 160 instead of 256 at 100K: -3.7%, and a second
/// split of tiles still above it: +10%). Points within `1e-5` of
/// that magnitude of a blocker's plane get a tree of their own (see `tile.rs`, `NEAR_BAND`),
/// or the clipping backend's answer when the shared tree holds more than 64 occluders
/// ([`PluckerStats::crowded_fallbacks`]). A
/// context follows one backend at a time (it clears itself when used with another).
///
/// The budget bounds the bytes of all cached trees: least recently used tiles are dropped to
/// stay within it, a tree that alone outgrows it is reset, and a query that alone outgrows it
/// is answered by the clipping backend (module documentation).
#[derive(Debug, Clone)]
pub struct PluckerContext {
    backend: Option<usize>,
    cell_size: f64,
    budget: usize,
    max_tiles: usize,
    reuse: bool,
    tiles: Vec<Tile>,
    /// The tiles by key (indices into `tiles`; several only for planes of different offsets).
    index: BTreeMap<TileKey, SmallVec<[u32; 2]>>,
    /// The sum of the tiles' counted bytes.
    total_bytes: usize,
    clock: u64,
    current: Option<usize>,
    stats: PluckerStats,
    ws: Workspace,
}

impl PluckerContext {
    /// A context with receiver cells of side `cell_size` (world units), the default budget
    /// ([`DEFAULT_TREE_CAP`]) and at most 64 tiles.
    ///
    /// # Errors
    ///
    /// [`GeomError::OutOfRange`] for a cell size that is not finite and positive.
    pub fn new(cell_size: f64) -> Result<Self, GeomError> {
        if !(cell_size > 0.0 && cell_size.is_finite()) {
            return Err(GeomError::OutOfRange {
                what: "receiver cell size (finite, positive)",
                value: cell_size,
                limit: f64::MAX,
            });
        }
        Ok(PluckerContext {
            backend: None,
            cell_size,
            budget: DEFAULT_TREE_CAP,
            max_tiles: 64,
            reuse: true,
            tiles: Vec::new(),
            index: BTreeMap::new(),
            total_bytes: 0,
            clock: 0,
            current: None,
            stats: PluckerStats::default(),
            ws: Workspace::default(),
        })
    }

    /// The same context with a budget of `bytes` for all its trees together.
    #[must_use]
    pub fn with_budget(mut self, bytes: usize) -> Self {
        self.budget = bytes;
        self
    }

    /// The same context keeping at most `tiles` tiles (at least one).
    #[must_use]
    pub fn with_max_tiles(mut self, tiles: usize) -> Self {
        self.max_tiles = tiles.max(1);
        self
    }

    /// The same context with reuse on (default) or off. Off, every query starts from its
    /// tile's root (the occluders culled for the tile, nothing developed): the "modified
    /// version" of seed 002 section 5.1, which measures what reuse gains.
    #[must_use]
    pub fn with_reuse(mut self, reuse: bool) -> Self {
        self.reuse = reuse;
        self
    }

    /// The counters since the context was made or last cleared.
    #[must_use]
    pub fn stats(&self) -> PluckerStats {
        self.stats
    }

    /// The bytes held by all cached trees.
    #[must_use]
    pub fn cached_bytes(&self) -> usize {
        self.total_bytes
    }

    /// Counts the bytes of tile `i` again (after a query used it), keeping the running total.
    fn refresh_bytes(&mut self, i: usize) {
        let tile = &mut self.tiles[i];
        let now = tile.bytes();
        self.total_bytes = self.total_bytes - tile.counted + now;
        tile.counted = now;
    }

    /// Drops every tree and resets the counters.
    pub fn clear(&mut self) {
        self.tiles.clear();
        self.index.clear();
        self.total_bytes = 0;
        self.current = None;
        self.stats = PluckerStats::default();
    }

    /// The index of the tile of light `light` holding the point `x` of a receiver with unit
    /// normal `n`, created if new (evicting the least recently used one beyond the tile count).
    fn tile_for(&mut self, light: usize, x: DVec3, n: DVec3, groups: usize) -> usize {
        self.clock += 1;
        let (t, b) = n.any_orthonormal_pair();
        let (u, v) = (t.dot(x), b.dot(x));
        let offset = n.dot(x);
        let mut level = 0u8;
        loop {
            let s = self.cell_size / f64::from(1u32 << level);
            let cell = (floor(u / s) as i64, floor(v / s) as i64);
            // Far below the near band of `tile.rs` (`NEAR_BAND`), whose error bound assumes
            // it; far above the rounding of points computed on one receiver plane.
            let tol = 1e-14 * (x.abs().max_element() + s);
            let key = (light, level, cell, n.to_array().map(f64::to_bits));
            let found = self.index.get(&key).and_then(|ids| {
                ids.iter()
                    .map(|&i| i as usize)
                    .find(|&i| (self.tiles[i].offset - offset).abs() <= tol)
            });
            if let Some(i) = found {
                self.tiles[i].last_used = self.clock;
                if self.tiles[i].split {
                    level += 1;
                    continue;
                }
                self.current = Some(i);
                return i;
            }
            if self.tiles.len() >= self.max_tiles {
                self.evict_oldest(None);
            }
            // The cell, widened by a hair so that points on its border are inside.
            let m = 1e-9 * s;
            let (u0, u1) = (cell.0 as f64 * s - m, (cell.0 + 1) as f64 * s + m);
            let (v0, v1) = (cell.1 as f64 * s - m, (cell.1 + 1) as f64 * s + m);
            let at = |u: f64, v: f64| t * u + b * v + n * offset;
            let corners = [at(u0, v0), at(u1, v0), at(u1, v1), at(u0, v1)];
            let center = at(0.5 * (u0 + u1), 0.5 * (v0 + v1));
            self.tiles.push(Tile {
                light,
                normal: n,
                offset,
                cell,
                level,
                split: false,
                geom: TileGeometry {
                    origin: center,
                    p0: center,
                    n,
                    cell: corners.into_iter().collect(),
                },
                slots: (0..groups).map(|_| Slot::Unbuilt).collect(),
                last_used: self.clock,
                counted: 0,
            });
            let i = self.tiles.len() - 1;
            self.index.entry(key).or_default().push(i as u32);
            self.stats.tiles_built += 1;
            self.current = Some(i);
            return i;
        }
    }

    /// Drops the least recently used tile other than `keep`.
    fn evict_oldest(&mut self, keep: Option<usize>) -> bool {
        let victim = self
            .tiles
            .iter()
            .enumerate()
            .filter(|(i, _)| Some(*i) != keep)
            .min_by_key(|(_, t)| t.last_used)
            .map(|(i, _)| i);
        match victim {
            Some(i) => {
                self.unindex(i);
                let last = self.tiles.len() - 1;
                if i != last {
                    self.unindex(last);
                    self.index
                        .entry(self.tiles[last].key())
                        .or_default()
                        .push(i as u32);
                }
                self.total_bytes -= self.tiles[i].counted;
                self.tiles.swap_remove(i);
                if self.current == Some(self.tiles.len()) {
                    self.current = Some(i);
                }
                self.stats.evictions += 1;
                true
            }
            None => false,
        }
    }

    /// Drops tile `i` from the index.
    fn unindex(&mut self, i: usize) {
        let key = self.tiles[i].key();
        if let Some(ids) = self.index.get_mut(&key) {
            ids.retain(|k| *k as usize != i);
            if ids.is_empty() {
                self.index.remove(&key);
            }
        }
    }

    /// Keeps the cached trees within the budget after a query.
    fn after_query(&mut self) {
        debug_assert_eq!(
            self.total_bytes,
            self.tiles.iter().map(Tile::bytes).sum::<usize>()
        );
        let mut total = self.cached_bytes();
        while total > self.budget && self.tiles.len() > 1 {
            let keep = self.current;
            if !self.evict_oldest(keep) {
                break;
            }
            total = self.cached_bytes();
        }
        self.stats.peak_cached_bytes = self.stats.peak_cached_bytes.max(total);
    }
}
