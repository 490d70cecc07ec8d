//! Triangulations of precomputed silhouettes (thesis 003 section 6.2.3): one triangulation per
//! leaf of a [`SilhouetteBsp`], certified at build time to stay valid everywhere in the leaf's
//! cell, and solid-angle sampling from it ([`SilhouetteSampler`]).
//!
//! The thesis triangulates the silhouette at one point of a cell and tests the result at 256
//! random points of the cell, which cannot guarantee it: a triangle with an apparent
//! intersection as a corner can flip between two tested points (its figure 6.6). Here the
//! triangulation is kept only when the conditions below hold, each checked exactly.
//!
//! # The certificate
//!
//! Over a leaf's convex cell `C` the silhouette's combinatorial structure is fixed: rings of
//! corners, each a mesh vertex `m` (seen from `x` in the direction `m - x`) or the point where a
//! contour edge `e` is seen crossing another contour edge `g` (the direction `P - x`, with `P` on
//! the segment `e`, and equally a point of the segment `g`). A candidate triangulation is a list
//! of index triples of corners. It is stored when
//!
//! 1. **every triangle is positively oriented everywhere in `C`.** The spherical triangle of
//!    corners `(u, v, w)` seen from `x` is positive iff `D(x) = det(U - x, V - x, W - x) > 0`
//!    (`U`, `V`, `W` the points in space). For mesh vertices `D` is `orient3d(u, v, w, x)`, affine
//!    in `x`, so it is positive on the closed cell iff it is positive at the cell's vertices.
//!    For a crossing, `P - x = l (a_e - x) + (1 - l) (b_e - x)` with `0 < l < 1` (the crossing
//!    lies inside the segment), and `D` is linear in each column, so `D(x)` is a combination
//!    with positive weights of the affine functions `orient3d(w_1, w_2, w_3, x)` over every
//!    choice of an endpoint `w_r` of each crossing corner's edge (the corner itself for a mesh
//!    vertex): `D > 0` wherever all of them are. A choice that repeats a point (the next
//!    corner is the end of the crossing's own edge) gives a function that vanishes
//!    identically and is dropped; at least one must remain. Either of the two edges that make
//!    a crossing may be used, and the certificate tries both. (A crossing reaches an end of
//!    its edge only on a plane through that end and the other edge, where the silhouette's
//!    structure changes and the direct algorithm gives up.)
//!
//!    Each affine function is checked with exact `orient3d` at every vertex of the cell: it
//!    must be non-negative there, and it may vanish only at one cell vertex that is one of its
//!    own points `w_r` (a mesh vertex at a corner of the cell: the viewpoint would be on the
//!    surface), or at cell vertices that all lie on one face plane of the mesh that splits the
//!    cells there (the query sends points within the facing predicate's tolerance of a face
//!    plane on its path to the direct algorithm). An affine function non-negative at the
//!    vertices is positive on the cell but on the hull of its zero vertices, a part of the
//!    cell's boundary holding no point the stored triangulation answers.
//! 2. **the triangles have the rings as boundary:** over the directed edges of the triangles,
//!    each directed ring edge counted `-1`, every edge is used as often in one direction as in
//!    the other. Triangles with `D > 0` have no coincident or antipodal corners, and a ring edge
//!    is the view of a piece of one mesh edge, which subtends less than `pi`, so the triangles'
//!    edges and the rings' are the same minor arcs.
//! 3. **they count the silhouette once** at the cell's representative point `x0`: their solid
//!    angles add up to less than `4 pi`.
//!
//! Then at every point `x` of `C` where the silhouette `P(x)` has the leaf's structure, the
//! triangles have disjoint interiors and their union is `P(x)`. By 2 the triangles minus `P`
//! form a 2-chain on the sphere without boundary, so the number of triangles over a direction
//! (off every arc) minus the indicator of `P` is the same integer `k(x)` for every direction:
//! crossing an arc changes both by the same amount. By 1 every triangle counts `+1`, so
//! `k(x) >= 0` (read it outside `P`), and the solid angles satisfy `sum area(T) = area(P) +
//! 4 pi k(x)`. Both areas are continuous in `x` on `C` (the corners move continuously, the
//! crossings existing throughout the cell, and no triangle degenerates), so the integer `k` is
//! constant on the cell (connected, also without the parts of its boundary excluded in 1), and
//! by 3 it is `0`.
//!
//! Where a cell is cut further by tests of the order of crossings (quadric surfaces, see
//! [`SilhouetteBsp`]), each part has its own structure and may be disconnected: its
//! triangulation is certified by 1 and 2 over the whole convex cell (which holds the part),
//! and 3 is then left to the query, which checks it at every point anyway (below).
//!
//! The candidates, first accepted wins: [`SphericalPolygon::triangulate`] of the silhouette at
//! the representative point (kept when it uses no extra vertex); every triangulation by
//! diagonals of a single ring, or of two rings joined by a bridge, through the interval
//! dynamic program with the certificate as the test of each triangle (so a triangulation is
//! found whenever one by diagonals passes); `triangulate` at a few other points of the cell.
//! Leaves where none passes store no triangulation, and their queries triangulate the
//! silhouette per point.
//!
//! What the query adds. The certificate is exact for the cell as the builder computes it
//! (vertices rounded to a few ulps of the box, except that cell vertices at mesh vertices are
//! snapped to them exactly, and vertices on a face plane that holds a function's three points
//! count as its zeros), and the query's region for the leaf is that cell only up to that
//! rounding; and the query returns directions rounded to `f64`. So the query re-checks, on the
//! rounded directions it returns, each triangle's orientation (exact) and condition 3 (with a
//! margin over rounding), which make the argument above hold for those very triangles at the
//! point, and it uses the stored triangulation only where no arc of the rings subtends more
//! than 120 degrees (near an edge's line, where the great circle through two nearly antipodal
//! rounded corners is uncertain by `eps` over the sine of their angle, and where the queried
//! polygon gets an extra vertex on the arc). Elsewhere it triangulates the queried polygon.

use alloc::vec::Vec;
use core::f64::consts::PI;

use glam::{DVec2, DVec3};
use robust::orient3d;
use smallvec::SmallVec;

use super::SilhouetteBsp;
use super::nonconvex::{Arc, arc_start};
use crate::GeomError;
use crate::solid::{ShadingFrame, TriangleMesh};
use crate::sphere::predicates::{c3, orient, triangle_solid_angle};
use crate::sphere::{SphericalPolygon, SphericalTriangle};

/// The bound of condition 3 checked on a query's rounded triangles: their solid angles must add
/// up to less than `4 pi` minus this, far above the rounding of a sum of a few hundred areas.
const FULL_MARGIN: f64 = 1e-9;

/// The bound of condition 3 at build time, on directions at the representative point.
const BUILD_FULL_MARGIN: f64 = 1e-6;

/// Triangles closer than this to a hemisphere in solid angle fail the query's check, the margin
/// `SphericalPolygon::triangulate` keeps for [`SphericalTriangle::sample`].
const HEMISPHERE_MARGIN: f64 = 1e-6;

/// Most corners (of a ring, or two bridged rings) the dynamic program is run on.
const DP_MAX: usize = 96;

/// How far (relative to the box) a cell vertex may lie from a mesh vertex it is snapped to.
pub(crate) const SNAP_REL: f64 = 1e-9;

/// Where the triangles of [`SilhouetteBsp::query_triangles`] came from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum TriangleSource {
    /// The triangulation stored for the point's cell, evaluated at the point (for a convex
    /// polyhedron: the fan of its stored silhouette loop, see
    /// [`SilhouetteBsp::build_triangulated`]).
    Stored,
    /// [`SphericalPolygon::triangulate`] of the queried silhouette: the tree stores no
    /// triangulation for the point's cell (it was built without them, the cell has none, the
    /// point lies outside the box, or the structure is answered directly there), or the stored
    /// one failed the query's check on its rounded directions (within rounding of the cell's
    /// boundary).
    Computed,
}

/// A corner of a stored silhouette ring (the start of an arc).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Corner {
    /// A mesh vertex.
    Vertex(u32),
    /// Where mesh edge `edge` is seen crossing mesh edge `other`.
    Crossing { edge: u32, other: u32 },
}

/// The corners of the rings `arcs` (ring `k` is `arcs[ends[k - 1]..ends[k]]`), in order.
fn corners(mesh: &TriangleMesh, arcs: &[Arc], ends: &[u32]) -> Vec<Corner> {
    let edges = mesh.edges();
    let mut out = Vec::with_capacity(arcs.len());
    let mut start = 0usize;
    for &end in ends {
        let ring = &arcs[start..end as usize];
        let n = ring.len();
        for (k, a) in ring.iter().enumerate() {
            out.push(if a.from_crossing {
                Corner::Crossing {
                    edge: a.edge,
                    other: ring[(k + n - 1) % n].edge,
                }
            } else {
                let e = edges[a.edge as usize];
                Corner::Vertex(if a.forward { e.a } else { e.b })
            });
        }
        start = end as usize;
    }
    out
}

/// Per corner, the index of the first corner at the same place (a mesh vertex where rings touch
/// or a ring passes twice is one corner of the triangulation).
fn canonical(corners: &[Corner]) -> Vec<u32> {
    (0..corners.len())
        .map(|i| corners.iter().position(|c| *c == corners[i]).unwrap_or(i) as u32)
        .collect()
}

/// The directed ring edges by canonical corner ids.
fn ring_edges(ends: &[u32], canon: &[u32]) -> Vec<[u32; 2]> {
    let mut out = Vec::with_capacity(canon.len());
    let mut start = 0usize;
    for &end in ends {
        let n = end as usize - start;
        for k in 0..n {
            out.push([canon[start + k], canon[start + (k + 1) % n]]);
        }
        start = end as usize;
    }
    out
}

/// Condition 2: the directed edges of `tris`, each of `ring` counted `-1`, balance.
fn boundary_matches(tris: &[[u32; 3]], ring: &[[u32; 2]]) -> bool {
    let mut all: Vec<([u32; 2], u8, i32)> = Vec::with_capacity(3 * tris.len() + ring.len());
    let mut add = |i: u32, j: u32, w: i32| {
        if i < j {
            all.push(([i, j], 0, w));
        } else {
            all.push(([j, i], 1, w));
        }
    };
    for t in tris {
        if t[0] == t[1] || t[1] == t[2] || t[2] == t[0] {
            return false;
        }
        add(t[0], t[1], 1);
        add(t[1], t[2], 1);
        add(t[2], t[0], 1);
    }
    for e in ring {
        add(e[0], e[1], -1);
    }
    all.sort_unstable_by_key(|x| x.0);
    let mut k = 0;
    while k < all.len() {
        let key = all[k].0;
        let mut net = [0i32; 2];
        while k < all.len() && all[k].0 == key {
            net[all[k].1 as usize] += all[k].2;
            k += 1;
        }
        if net[0] != net[1] {
            return false;
        }
    }
    true
}

/// The vertices of a cell for the certificate: positions (mesh vertices among them exact) and,
/// per vertex, the mesh faces whose planes split the cells there (the vertex lies on them).
#[derive(Debug, Clone, Default)]
pub(crate) struct CellCorners {
    pub p: Vec<DVec3>,
    pub faces: Vec<SmallVec<[u32; 4]>>,
}

/// Which mesh vertices lie exactly on which face's plane (exact `orient3d`), computed once per
/// build: a bit per (face, vertex).
#[derive(Debug, Clone)]
pub(crate) struct OnFace {
    words: usize,
    bits: Vec<u64>,
}

impl OnFace {
    pub(crate) fn new(mesh: &TriangleMesh) -> Self {
        let (v, t) = (mesh.vertices(), mesh.triangles());
        let words = v.len().div_ceil(64);
        let mut bits = alloc::vec![0u64; words * t.len()];
        for (f, tri) in t.iter().enumerate() {
            let [a, b, c] = tri.map(|i| c3(v[i as usize]));
            for (i, &p) in v.iter().enumerate() {
                if orient3d(a, b, c, c3(p)) == 0.0 {
                    bits[f * words + i / 64] |= 1 << (i % 64);
                }
            }
        }
        OnFace { words, bits }
    }

    fn contains(&self, face: u32, vertex: u32) -> bool {
        let i = vertex as usize;
        self.bits[face as usize * self.words + i / 64] >> (i % 64) & 1 == 1
    }
}

/// The part of condition 1 for one affine function `f(x) = orient3d(w[0], w[1], w[2], x)`:
/// `f >= 0` at every cell vertex (exact), with its zeros where `f` is allowed to vanish: at
/// one vertex that is one of the `w` itself, or at vertices on a common face plane of the mesh
/// that split the cells. An affine function that is non-negative at the vertices is positive on
/// the cell except on the hull of its zero vertices; a mesh vertex is no shading point, and the
/// query sends points within the facing predicate's tolerance of a face plane on its path to
/// the direct algorithm, so neither set holds a point the stored triangulation answers.
///
/// A cell vertex on a face plane that holds all three points is a zero without evaluation: the
/// cell's true vertex lies on that plane, where its rounded position need not.
fn affine_positive(
    mesh: &TriangleMesh,
    on_face: &OnFace,
    iw: [u32; 3],
    cell: &CellCorners,
) -> bool {
    let w = iw.map(|i| mesh.vertices()[i as usize]);
    let mut zeros: SmallVec<[usize; 8]> = SmallVec::new();
    for (k, &v) in cell.p.iter().enumerate() {
        let on_plane = || {
            cell.faces[k]
                .iter()
                .any(|&f| iw.iter().all(|&i| on_face.contains(f, i)))
        };
        let o = if w.contains(&v) || on_plane() {
            0.0
        } else {
            orient3d(c3(w[0]), c3(w[1]), c3(w[2]), c3(v))
        };
        if o > 0.0 {
            continue;
        }
        if o < 0.0 || o.is_nan() {
            return false;
        }
        zeros.push(k);
    }
    match zeros.as_slice() {
        [] => true,
        [k] if w.contains(&cell.p[*k]) => true,
        [first, rest @ ..] => cell.faces[*first]
            .iter()
            .any(|f| rest.iter().all(|&k| cell.faces[k].contains(f))),
    }
}

/// Certificate of condition 1 for triangles of one leaf, with memoized affine checks.
struct Orientation<'a> {
    mesh: &'a TriangleMesh,
    corners: &'a [Corner],
    cell: &'a CellCorners,
    on_face: &'a OnFace,
    /// Affine checks by the mesh vertex indices of their three points.
    affine: Memo,
    /// Triangles by canonical corner ids (rotated to start at the smallest).
    triangles: Memo,
}

impl Orientation<'_> {
    /// The candidate point sets of a corner: one mesh vertex, or either edge's two endpoints.
    fn options(&self, c: Corner) -> SmallVec<[[u32; 2]; 2]> {
        let ends = |e: u32| {
            let e = self.mesh.edges()[e as usize];
            [e.a, e.b]
        };
        match c {
            Corner::Vertex(m) => smallvec::smallvec![[m, m]],
            Corner::Crossing { edge, other } => smallvec::smallvec![ends(edge), ends(other)],
        }
    }

    fn affine(&mut self, w: [u32; 3]) -> bool {
        // The function is the same for every rotation of its points.
        let r = (0..3).min_by_key(|&i| w[i]).unwrap_or(0);
        let key = [w[r], w[(r + 1) % 3], w[(r + 2) % 3]];
        if let Some(r) = self.affine.get(key) {
            return r;
        }
        let r = affine_positive(self.mesh, self.on_face, key, self.cell);
        self.affine.insert(key, r);
        r
    }

    /// Whether the triangle of canonical corners `t` is positive everywhere in the cell.
    fn positive(&mut self, t: [u32; 3]) -> bool {
        let r = (0..3).min_by_key(|&i| t[i]).unwrap_or(0);
        let key = [t[r], t[(r + 1) % 3], t[(r + 2) % 3]];
        if let Some(ok) = self.triangles.get(key) {
            return ok;
        }
        let opts = key.map(|i| self.options(self.corners[i as usize]));
        let mut ok = false;
        'choice: for o0 in &opts[0] {
            for o1 in &opts[1] {
                for o2 in &opts[2] {
                    let (mut all, mut proper) = (true, false);
                    'combos: for &w0 in dedup(o0) {
                        for &w1 in dedup(o1) {
                            for &w2 in dedup(o2) {
                                // A repeated point makes the term vanish identically.
                                if w0 == w1 || w1 == w2 || w2 == w0 {
                                    continue;
                                }
                                proper = true;
                                if !self.affine([w0, w1, w2]) {
                                    all = false;
                                    break 'combos;
                                }
                            }
                        }
                    }
                    if all && proper {
                        ok = true;
                        break 'choice;
                    }
                }
            }
        }
        self.triangles.insert(key, ok);
        ok
    }
}

/// A small open-addressing map from index triples to booleans, for the per-leaf memos of the
/// certificate. Triples with an index of `2^21` or more are not memoized (they would not fit
/// the key).
#[derive(Debug, Default)]
struct Memo {
    /// `(key + 1, value)`; key 0 marks an empty slot.
    slots: Vec<(u64, bool)>,
    len: usize,
}

impl Memo {
    fn key(t: [u32; 3]) -> u64 {
        (u64::from(t[0]) | u64::from(t[1]) << 21 | u64::from(t[2]) << 42) + 1
    }

    fn slot(&self, k: u64) -> usize {
        let mask = self.slots.len() - 1;
        let mut i = (k.wrapping_mul(0x9e37_79b9_7f4a_7c15) >> 40) as usize & mask;
        while self.slots[i].0 != 0 && self.slots[i].0 != k {
            i = (i + 1) & mask;
        }
        i
    }

    fn fits(t: [u32; 3]) -> bool {
        t.iter().all(|&i| i < 1 << 21)
    }

    fn get(&self, t: [u32; 3]) -> Option<bool> {
        if self.slots.is_empty() || !Self::fits(t) {
            return None;
        }
        let s = self.slots[self.slot(Self::key(t))];
        (s.0 != 0).then_some(s.1)
    }

    fn insert(&mut self, t: [u32; 3], v: bool) {
        if !Self::fits(t) {
            return;
        }
        if 2 * (self.len + 1) > self.slots.len() {
            let size = (2 * self.slots.len()).max(64);
            let old = core::mem::replace(&mut self.slots, alloc::vec![(0, false); size]);
            for (k, v) in old {
                if k != 0 {
                    let i = self.slot(k);
                    self.slots[i] = (k, v);
                }
            }
        }
        let k = Self::key(t);
        let i = self.slot(k);
        if self.slots[i].0 == 0 {
            self.len += 1;
        }
        self.slots[i] = (k, v);
    }
}

/// The distinct entries of a pair.
fn dedup(p: &[u32; 2]) -> &[u32] {
    if p[0] == p[1] { &p[..1] } else { &p[..] }
}

/// Unit directions of the corners seen from `frame` (local frame), as the query evaluates them.
///
/// With `narrow`, `false` where an arc of a ring subtends more than 120 degrees: there the
/// query's polygon has an extra vertex on the arc ([`evaluate_rings`], same test on the same
/// values), because the minor arc between two nearly antipodal rounded corners is not the
/// edge's view within rounding (its great circle is uncertain by `eps` over the sine of the
/// angle), and a triangle with that arc as an edge would not be either.
///
/// [`evaluate_rings`]: super::nonconvex::evaluate_rings
fn corner_directions(
    mesh: &TriangleMesh,
    arcs: &[Arc],
    ends: &[u32],
    frame: &ShadingFrame,
    narrow: bool,
    out: &mut SmallVec<[DVec3; 24]>,
) -> bool {
    out.clear();
    let mut start = 0usize;
    for &end in ends {
        let ring = &arcs[start..end as usize];
        let mut prev: Option<DVec3> = None;
        for k in 0..ring.len() {
            let w = arc_start(mesh, ring, k, frame);
            let Some(u) = w.try_normalize() else {
                return false;
            };
            if narrow && prev.is_some_and(|p| p.dot(w) < -0.5 * w.length()) {
                return false;
            }
            prev = Some(u);
            out.push(u);
        }
        if narrow && let Some(p) = prev {
            // The closing arc, as `evaluate_rings` sees it: from the last corner's direction
            // to the first corner's vector.
            let w = arc_start(mesh, ring, 0, frame);
            if p.dot(w) < -0.5 * w.length() {
                return false;
            }
        }
        start = end as usize;
    }
    true
}

/// The triangles of [`SphericalPolygon::triangulate`] of the silhouette seen from `x`, as
/// canonical corner ids; `None` when the silhouette is not a valid polygon there or the
/// triangulation uses a vertex that is no corner.
fn triangulate_at(
    mesh: &TriangleMesh,
    arcs: &[Arc],
    ends: &[u32],
    canon: &[u32],
    x: DVec3,
) -> Option<Vec<[u32; 3]>> {
    let frame = ShadingFrame::new(x, DVec3::Z, DVec3::Z).ok()?;
    let mut dirs = SmallVec::new();
    if !corner_directions(mesh, arcs, ends, &frame, false, &mut dirs) {
        return None;
    }
    let mut rings = Vec::with_capacity(ends.len());
    let mut start = 0usize;
    for &end in ends {
        rings.push(dirs[start..end as usize].to_vec());
        start = end as usize;
    }
    let tris = SphericalPolygon::new(rings).ok()?.triangulate().ok()?;
    let find = |p: DVec3| -> Option<u32> {
        let (k, d) = dirs
            .iter()
            .enumerate()
            .map(|(k, &q)| (k, (q - p).length_squared()))
            .min_by(|a, b| a.1.total_cmp(&b.1))?;
        (d <= 1e-24).then(|| canon[k])
    };
    tris.iter()
        .map(|t| {
            let [a, b, c] = t.vertices();
            Some([find(a)?, find(b)?, find(c)?])
        })
        .collect()
}

/// A triangulation of a leaf's silhouette certified over its cell (see the module
/// documentation), as canonical corner ids (corner indices in ring order), or `None`.
///
/// `arcs` and `ends` are the leaf's rings, `rep` a point of the cell's interior where they are
/// the silhouette's structure, `cell` the cell's vertices (mesh vertices among them snapped
/// exactly), `on_face` the mesh's vertex-plane incidences and `extra` further candidates.
pub(crate) fn certified_triangulation(
    mesh: &TriangleMesh,
    arcs: &[Arc],
    ends: &[u32],
    rep: DVec3,
    cell: &CellCorners,
    on_face: &OnFace,
    extra: Extra<'_>,
) -> Option<Vec<[u32; 3]>> {
    let Extra { samples, hint } = extra;
    let corners = corners(mesh, arcs, ends);
    let canon = canonical(&corners);
    let frame = ShadingFrame::new(rep, DVec3::Z, DVec3::Z).ok()?;
    let mut dirs = SmallVec::new();
    if !corner_directions(mesh, arcs, ends, &frame, false, &mut dirs) {
        return None;
    }
    let mut leaf = Leaf {
        ring: ring_edges(ends, &canon),
        dirs,
        check: Orientation {
            mesh,
            corners: &corners,
            cell,
            on_face,
            affine: Memo::default(),
            triangles: Memo::default(),
        },
    };
    // The hint (the triangulation of another cell with the same structure) first, the
    // triangulation at the representative point next (one call when it passes), then every
    // triangulation by diagonals (the dynamic program), then triangulations elsewhere.
    if let Some(t) = hint
        && leaf.accept(t)
    {
        return Some(t.to_vec());
    }
    if let Some(t) = triangulate_at(mesh, arcs, ends, &canon, rep)
        && leaf.accept(&t)
    {
        return Some(t);
    }
    for seq in sequences(&canon, ends, &leaf.dirs) {
        if let Some(t) = polygon_dp(&seq, |t| leaf.plausible(t) && leaf.check.positive(t))
            && leaf.accept(&t)
        {
            return Some(t);
        }
    }
    for &x in samples {
        if let Some(t) = triangulate_at(mesh, arcs, ends, &canon, x)
            && leaf.accept(&t)
        {
            return Some(t);
        }
    }
    None
}

/// Further candidates for [`certified_triangulation`]: points of the cell at which to try
/// `triangulate`, and a triangulation to try first.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Extra<'a> {
    pub samples: &'a [DVec3],
    pub hint: Option<&'a [[u32; 3]]>,
}

/// One leaf's certificate: its ring edges, the corners' directions at the representative
/// point, and the orientation checks.
struct Leaf<'a> {
    ring: Vec<[u32; 2]>,
    dirs: SmallVec<[DVec3; 24]>,
    check: Orientation<'a>,
}

impl Leaf<'_> {
    /// A cheap necessary condition (in floating point, at the representative point) for a
    /// triangle of a valid triangulation: positively oriented, and no corner strictly inside.
    fn plausible(&self, t: [u32; 3]) -> bool {
        let [a, b, c] = t.map(|i| self.dirs[i as usize]);
        let (ab, bc, ca) = (a.cross(b), b.cross(c), c.cross(a));
        if !(ab.dot(c) > 0.0) {
            return false;
        }
        !self.dirs.iter().any(|&d| {
            let margin = 1e-12;
            d != a
                && d != b
                && d != c
                && ab.dot(d) > margin
                && bc.dot(d) > margin
                && ca.dot(d) > margin
        })
    }

    /// Conditions 1 to 3 for the triangles `tris`.
    fn accept(&mut self, tris: &[[u32; 3]]) -> bool {
        if tris.is_empty() || !boundary_matches(tris, &self.ring) {
            return false;
        }
        let mut sum = 0.0;
        for t in tris {
            if !self.check.positive(*t) {
                return false;
            }
            // Every triangle is positive at the representative point by condition 1.
            let [a, b, c] = t.map(|i| self.dirs[i as usize]);
            sum += triangle_solid_angle(a, b, c);
        }
        sum < 4.0 * PI - BUILD_FULL_MARGIN
    }
}

/// The closed corner sequences (canonical ids) whose polygon triangulations are triangulations
/// of the rings: the ring itself, or for two rings, each ring joined to the other by a bridge
/// traversed both ways (the bridges' two directions cancel in condition 2), between the
/// four pairs of corners nearest at the representative point (`dirs`; trying all pairs
/// certified no further leaf of the thesis polyhedra).
fn sequences(canon: &[u32], ends: &[u32], dirs: &[DVec3]) -> Vec<Vec<u32>> {
    match ends {
        [_] => alloc::vec![canon.to_vec()],
        [e0, _] => {
            let split = *e0 as usize;
            let (p, q) = (split, canon.len() - split);
            let mut pairs: Vec<(f64, usize, usize)> = Vec::with_capacity(p * q);
            for i in 0..p {
                for j in 0..q {
                    pairs.push(((dirs[i] - dirs[split + j]).length_squared(), i, j));
                }
            }
            pairs.sort_by(|a, b| a.0.total_cmp(&b.0));
            pairs
                .iter()
                .take(4)
                .map(|&(_, i, j)| {
                    let mut seq = Vec::with_capacity(p + q + 2);
                    seq.extend((0..=p).map(|k| canon[(i + k) % p]));
                    seq.extend((0..=q).map(|k| canon[split + (j + k) % q]));
                    seq
                })
                .collect()
        }
        _ => Vec::new(),
    }
}

/// A triangulation of the closed corner sequence `seq` (a polygon's vertices in order,
/// interior on the left) by diagonals, with every triangle `allowed`: the classic interval
/// dynamic program (sub-polygon `i..=j` closed by the diagonal `j -> i` is triangulable iff some
/// `k` between them makes an allowed triangle `(i, k, j)` with triangulable sides), which
/// considers every triangulation without extra vertices. `allowed` is asked only where both
/// sides are already triangulable.
fn polygon_dp(seq: &[u32], mut allowed: impl FnMut([u32; 3]) -> bool) -> Option<Vec<[u32; 3]>> {
    let n = seq.len();
    // The program takes up to n^3 tests of n steps each: beyond DP_MAX corners the other
    // candidates must do.
    if !(3..=DP_MAX).contains(&n) {
        return None;
    }
    // best[i * n + j]: the apex k of a triangulation of i..=j, or NONE.
    const NONE: u16 = u16::MAX;
    let mut best = alloc::vec![NONE; n * n];
    for len in 2..n {
        for i in 0..n - len {
            let j = i + len;
            for k in i + 1..j {
                let left = k == i + 1 || best[i * n + k] != NONE;
                let right = j == k + 1 || best[k * n + j] != NONE;
                let t = [seq[i], seq[k], seq[j]];
                if left && right && t[0] != t[1] && t[1] != t[2] && t[2] != t[0] && allowed(t) {
                    best[i * n + j] = k as u16;
                    break;
                }
            }
        }
    }
    if best[n - 1] == NONE {
        return None;
    }
    let mut out = Vec::with_capacity(n - 2);
    let mut stack = alloc::vec![(0usize, n - 1)];
    while let Some((i, j)) = stack.pop() {
        if j < i + 2 {
            continue;
        }
        let k = best[i * n + j] as usize;
        out.push([seq[i], seq[k], seq[j]]);
        stack.push((i, k));
        stack.push((k, j));
    }
    Some(out)
}

/// Evaluates a stored triangulation (canonical corner ids) at the frame's point, checking each
/// triangle's orientation exactly on the rounded directions and the solid angles' sum below
/// `4 pi` (see the module documentation); `false` (and `out` unspecified) where a check fails.
pub(crate) fn evaluate_stored(
    mesh: &TriangleMesh,
    arcs: &[Arc],
    ends: &[u32],
    tris: &[[u32; 3]],
    frame: &ShadingFrame,
    out: &mut Vec<SphericalTriangle>,
) -> bool {
    let mut dirs = SmallVec::new();
    if !corner_directions(mesh, arcs, ends, frame, true, &mut dirs) {
        return false;
    }
    fan_or_list(&dirs, tris.iter().copied(), out)
}

/// Triangles from unit directions and index triples, with the query's checks.
pub(crate) fn fan_or_list(
    dirs: &[DVec3],
    tris: impl Iterator<Item = [u32; 3]>,
    out: &mut Vec<SphericalTriangle>,
) -> bool {
    out.clear();
    let mut sum = 0.0;
    for t in tris {
        let [a, b, c] = t.map(|i| dirs[i as usize]);
        if orient(a, b, c) != 1 {
            return false;
        }
        match SphericalTriangle::from_unit(a, b, c) {
            // As `SphericalPolygon::triangulate` does: sampling does not resolve triangles
            // closer to a hemisphere than this.
            Ok(s) if s.solid_angle() > 2.0 * PI - HEMISPHERE_MARGIN => return false,
            Ok(s) => {
                sum += s.solid_angle();
                out.push(s);
            }
            // Positive, but its area rounds to zero: it covers nothing beyond rounding.
            Err(GeomError::Degenerate(_)) => {}
            Err(_) => return false,
        }
    }
    sum < 4.0 * PI - FULL_MARGIN
}

/// The stored triangulation as raw directions (no checks), for tests.
pub(crate) fn raw_stored(
    mesh: &TriangleMesh,
    arcs: &[Arc],
    ends: &[u32],
    tris: &[[u32; 3]],
    frame: &ShadingFrame,
) -> Option<Vec<[DVec3; 3]>> {
    let mut dirs = SmallVec::new();
    if !corner_directions(mesh, arcs, ends, frame, true, &mut dirs) {
        return None;
    }
    Some(tris.iter().map(|t| t.map(|i| dirs[i as usize])).collect())
}

/// Uniform sampling by solid angle of a precomputed silhouette seen from a point (thesis 003
/// chapter 6): the triangles of [`SilhouetteBsp::query_triangles`], one picked in proportion to
/// its solid angle, then sampled by [`SphericalTriangle::sample`]. Where the tree stores a
/// certified triangulation for the point's cell no triangulation runs per point.
///
/// # Examples
///
/// ```
/// use arealight::glam::{DVec2, DVec3};
/// use arealight::solid::{ClosedMesh, ShadingFrame, SilhouetteBsp, SilhouetteSampler};
/// use arealight::internals::thesis_polyhedra;
/// let (_, bowl) = thesis_polyhedra()?.pop().unwrap();
/// let bsp = SilhouetteBsp::build_triangulated(&ClosedMesh::new(bowl)?)?;
/// let frame = ShadingFrame::new(DVec3::new(0.3, -0.2, 3.0), DVec3::Z, DVec3::Z)?;
/// let sampler = SilhouetteSampler::new(&bsp, &frame)?;
/// let w = sampler.sample(DVec2::new(0.25, 0.5));
/// assert!(bsp.query(&frame)?.contains(w));
/// assert_eq!(sampler.pdf(w), 1.0 / sampler.solid_angle());
/// # Ok::<(), arealight::GeomError>(())
/// ```
#[derive(Debug, Clone)]
pub struct SilhouetteSampler {
    tris: Vec<SphericalTriangle>,
    /// Cumulative solid angles: `cdf[k]` is the sum over triangles `0..=k`.
    cdf: Vec<f64>,
    source: TriangleSource,
}

impl SilhouetteSampler {
    /// The triangles of the silhouette seen from the frame's point, ready for sampling.
    ///
    /// # Errors
    ///
    /// [`GeomError::Degenerate`] when the silhouette is empty (nothing to sample); the errors
    /// of [`SilhouetteBsp::query_triangles`].
    pub fn new(bsp: &SilhouetteBsp, frame: &ShadingFrame) -> Result<Self, GeomError> {
        let mut tris = Vec::new();
        let source = bsp.query_triangles(frame, &mut tris)?;
        if tris.is_empty() {
            return Err(GeomError::Degenerate(
                "the empty silhouette cannot be sampled",
            ));
        }
        let mut cdf = Vec::with_capacity(tris.len());
        let mut total = 0.0;
        for t in &tris {
            total += t.solid_angle();
            cdf.push(total);
        }
        Ok(SilhouetteSampler { tris, cdf, source })
    }

    /// The triangles sampled from, in the frame's local coordinates.
    #[must_use]
    pub fn triangles(&self) -> &[SphericalTriangle] {
        &self.tris
    }

    /// Whether the triangles were the stored ones or computed at the point.
    #[must_use]
    pub fn source(&self) -> TriangleSource {
        self.source
    }

    /// The silhouette's solid angle: the sum of its triangles'.
    #[must_use]
    pub fn solid_angle(&self) -> f64 {
        self.cdf[self.cdf.len() - 1]
    }

    /// A direction in the silhouette (local frame) from two numbers in `[0, 1]` (clamped, NaN
    /// as `0`), uniform in solid angle over uniform `u`: `u.x` picks the triangle by cumulative
    /// solid angle and, rescaled to that triangle's share, is its first coordinate.
    #[must_use]
    pub fn sample(&self, u: DVec2) -> DVec3 {
        let clamp = |v: f64| if v >= 0.0 { v.min(1.0) } else { 0.0 };
        let total = self.solid_angle();
        let x = clamp(u.x) * total;
        let k = self
            .cdf
            .partition_point(|&c| c <= x)
            .min(self.cdf.len() - 1);
        let lo = if k == 0 { 0.0 } else { self.cdf[k - 1] };
        let w = self.tris[k].solid_angle();
        self.tris[k].sample(DVec2::new(((x - lo) / w).min(1.0), clamp(u.y)))
    }

    /// `1 / solid_angle` for a direction (local frame) in the silhouette (one of the triangles
    /// covers it, to [`crate::sphere::SAMPLE_TOLERANCE`] of the triangle's size), else `0`.
    #[must_use]
    pub fn pdf(&self, dir: DVec3) -> f64 {
        match dir.try_normalize() {
            Some(p) if self.tris.iter().any(|t| t.covers(p)) => 1.0 / self.solid_angle(),
            _ => 0.0,
        }
    }
}
