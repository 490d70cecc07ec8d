//! A silhouette as bare rings of directions: what the shading integrals need, without building a
//! [`SphericalPolygon`].

use glam::DVec3;
use smallvec::SmallVec;

use crate::GeomError;
use crate::sphere::SphericalPolygon;

/// A silhouette seen from a point as rings of directions from the point in its local frame, of
/// any positive length (not normalized), in the conventions of [`SphericalPolygon`] (interior on
/// the left of each ring, rings disjoint but for shared vertices), written by
/// [`SilhouetteBsp::query_rings`](crate::solid::SilhouetteBsp::query_rings) and
/// [`convex_silhouette_rings`](crate::internals::convex_silhouette_rings).
///
/// The rings are valid by construction: they are the rings the polygon-returning queries build
/// (the same vertices before normalization), with the same spacing checks, and where those would
/// take another path the rings are copied from its polygon. So they can go straight into the
/// clip-free integrals ([`clamped_cosine_integral_rings`](crate::ltc::clamped_cosine_integral_rings),
/// [`ltc_integral_rings`](crate::ltc::ltc_integral_rings)), which need no unit vectors: no
/// normalization, no polygon. The full sphere, which has no ring, is a flag of its own.
///
/// The buffer is reused across queries: nothing is allocated for silhouettes of up to 16
/// vertices in up to 2 rings.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct SilhouetteRings {
    verts: SmallVec<[DVec3; 16]>,
    ends: SmallVec<[u32; 2]>,
    full: bool,
}

impl SilhouetteRings {
    /// An empty silhouette (no rings).
    #[must_use]
    pub fn new() -> Self {
        Self::default()
    }

    /// Whether the silhouette is the full sphere (a point inside a closed cavity of the light,
    /// or inside a convex blocker).
    #[must_use]
    #[inline]
    pub fn is_full(&self) -> bool {
        self.full
    }

    /// Whether the silhouette is empty (nothing seen).
    #[must_use]
    #[inline]
    pub fn is_empty(&self) -> bool {
        !self.full && self.ends.is_empty()
    }

    /// The rings, each a slice of directions of any positive length (the closing edge from last
    /// to first implied).
    pub fn rings(&self) -> impl Iterator<Item = &[DVec3]> + Clone + '_ {
        crate::sphere::ring_slices(&self.verts, &self.ends)
    }

    /// Number of rings.
    #[must_use]
    pub fn ring_count(&self) -> usize {
        self.ends.len()
    }

    /// Total number of vertices over all rings.
    #[must_use]
    pub fn vertex_count(&self) -> usize {
        self.verts.len()
    }

    /// The silhouette as a polygon (every vertex normalized).
    ///
    /// # Errors
    ///
    /// [`GeomError::Degenerate`] for a vertex that is zero or not finite (never for rings of this
    /// crate's queries); those of [`SphericalPolygon::new`], which validates the rings.
    pub fn to_polygon(&self) -> Result<SphericalPolygon, GeomError> {
        if self.full {
            return Ok(SphericalPolygon::full());
        }
        let mut rings = alloc::vec::Vec::with_capacity(self.ends.len());
        for ring in self.rings() {
            let mut r = alloc::vec::Vec::with_capacity(ring.len());
            for &v in ring {
                r.push(
                    v.try_normalize()
                        .ok_or(GeomError::Degenerate("a ring vertex is zero or not finite"))?,
                );
            }
            rings.push(r);
        }
        SphericalPolygon::new(rings)
    }

    /// Empties the buffer (the empty silhouette).
    pub(crate) fn clear(&mut self) {
        self.verts.clear();
        self.ends.clear();
        self.full = false;
    }

    /// Makes it the full sphere.
    pub(crate) fn set_full(&mut self) {
        self.clear();
        self.full = true;
    }

    /// Appends a vertex to the ring being written.
    #[inline]
    pub(crate) fn push(&mut self, v: DVec3) {
        self.verts.push(v);
    }

    /// Closes the ring being written (the vertices pushed since the last close).
    #[inline]
    pub(crate) fn close_ring(&mut self) {
        self.ends.push(self.verts.len() as u32);
    }

    /// The polygon of these rings with no checks: their vertices must be unit vectors and the
    /// rings valid (the non-convex query's rings, checked as it checks them).
    pub(crate) fn into_polygon_unchecked(self) -> SphericalPolygon {
        if self.full {
            return SphericalPolygon::full();
        }
        SphericalPolygon::from_parts(self.verts.into_iter().collect(), self.ends)
    }

    /// Replaces the contents by a polygon's rings (the fallback paths).
    pub(crate) fn set_polygon(&mut self, p: &SphericalPolygon) {
        self.clear();
        if p.is_full() {
            self.full = true;
            return;
        }
        for ring in p.rings() {
            self.verts.extend_from_slice(ring);
            self.close_ring();
        }
    }
}

/// Whether consecutive directions `a` and `b` (of any positive lengths) are, as unit vectors,
/// farther apart than `coincident` and not antipodal within `antipodal` (chord lengths, as
/// [`crate::sphere::MATCH_TOLERANCE`] and [`crate::sphere::ANTIPODAL_TOLERANCE`]): the spacing
/// test of the polygon-returning silhouettes, decided the same way. Clearly so where the angle
/// is acute and its sine, `|a x b| / (|a| |b|)`, exceeds twice `coincident` (the chord
/// `2 sin(theta / 2)` is at least the sine): one cross product, no root, no division; otherwise
/// on the unit vectors, as those silhouettes decide it.
#[inline(always)]
pub(crate) fn spaced(a: DVec3, b: DVec3, coincident: f64, antipodal: f64) -> bool {
    let clear = a.dot(b) > 0.0
        && a.cross(b).length_squared()
            > 4.0 * coincident * coincident * a.length_squared() * b.length_squared();
    clear || spaced_units(a, b, coincident, antipodal)
}

/// [`spaced`] on the unit vectors, out of line.
#[cold]
#[inline(never)]
fn spaced_units(a: DVec3, b: DVec3, coincident: f64, antipodal: f64) -> bool {
    let (Some(u), Some(v)) = (a.try_normalize(), b.try_normalize()) else {
        return false;
    };
    (u - v).length() > coincident && (u + v).length() > antipodal
}
