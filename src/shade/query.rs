//! Per-point queries of a [`Scene`]: the radiance at a shading point ([`Scene::shade`]), one
//! light's share of it ([`Scene::shade_light`]), and every light's share split by lobe with its
//! unshadowed value ([`Scene::shade_per_light`]).
//!
//! Each query builds the shading frame and looks up the LTC table once per point; per light it
//! integrates the visible region (seed 000 Alg. 1 lines 13-16): Baum's formula for the diffuse
//! lobe and, after the LTC transform `M^-1` for the view angle and roughness, the same formula
//! for the GGX lobe (HDHN16 eq. 2 / seed 000 eq. 2).
//!
//! The region comes from the visibility layer's fast path ([`ClipVisibility::visible_pieces`]:
//! pieces cut by half-spaces, never built as spherical polygons, integrated as they are) where it
//! applies, and from the spherical path ([`ClipVisibility::visible_region`]) elsewhere; the two
//! agree to rounding (`tests/shade_speed.rs`). A [`ShadeContext`] holds the fast path's scratch
//! storage: [`Scene::shade_in`] reuses the caller's; [`Scene::shade`] and the other entry points
//! reuse one per thread (feature `std`; without it they make one on the stack per call).

use alloc::vec::Vec;

use glam::{DMat3, DVec3};

use super::material::Material;
use super::scene::Scene;
use crate::ltc::{
    clamped_cosine_integral_upper, lookup, ltc_integral, ltc_rings_integral, upper_rings_integral,
};
use crate::solid::ShadingFrame;
use crate::sphere::SphericalPolygon;
#[cfg(doc)]
use crate::visibility::ClipVisibility;
use crate::visibility::{Pieces, Visibility};
use crate::{GeomError, IntoDVec3};

/// What a failed LTC lookup or integral reports: the frame's view and the material were
/// validated, and the visible region is a valid polygon, so any error is a give-up.
const LTC_FAILED: &str = "the LTC integral of a visible region failed within rounding";

/// One light's share of the radiance at a shading point ([`Scene::shade_per_light`]), split by
/// lobe, shadowed and unshadowed (all RGB, the light's radiance included).
///
/// `diffuse + specular` is the light's term of [`Scene::shade`] (equal up to rounding: that sum
/// is formed in another order). The unshadowed parts are what the light would give with every
/// other object of the scene removed (its own self-occlusion, for a non-convex mesh light,
/// kept): the denominator of a shadow ratio, or the analytic factor of a ratio estimator
/// (`unshadowed * estimated visible fraction`).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct LightShading {
    /// The Lambertian lobe over the visible part of the light.
    pub diffuse: DVec3,
    /// The GGX lobe over the visible part of the light (zero for a material without one).
    pub specular: DVec3,
    /// The Lambertian lobe over the whole light, as if no other object were there.
    pub unshadowed_diffuse: DVec3,
    /// The GGX lobe over the whole light, as if no other object were there.
    pub unshadowed_specular: DVec3,
}

impl LightShading {
    /// The light's radiance at the point: `diffuse + specular`.
    #[must_use]
    pub fn shadowed(&self) -> DVec3 {
        self.diffuse + self.specular
    }

    /// The light's radiance at the point with nothing in the way:
    /// `unshadowed_diffuse + unshadowed_specular`.
    #[must_use]
    pub fn unshadowed(&self) -> DVec3 {
        self.unshadowed_diffuse + self.unshadowed_specular
    }
}

/// The LTC inverse matrix and the per-channel specular scale (`norm` with Schlick's Fresnel,
/// [`crate::ltc::LtcLookup::specular_scale`]) for the frame's view angle and the material's
/// roughness; `None` for a material without a specular lobe. One table lookup per shading point.
pub(super) type SpecularSetup = Option<(DMat3, DVec3)>;

/// The shading frame of the entry points' arguments, widened at the boundary
/// ([`IntoDVec3`]).
fn frame(
    point: impl IntoDVec3,
    normal: impl IntoDVec3,
    view: impl IntoDVec3,
) -> Result<ShadingFrame, GeomError> {
    ShadingFrame::new(point.into_dvec3(), normal.into_dvec3(), view.into_dvec3())
}

pub(super) fn specular_setup(
    frame: &ShadingFrame,
    material: &Material,
) -> Result<SpecularSetup, GeomError> {
    if !material.has_specular() {
        return Ok(None);
    }
    let look = lookup(frame.view().z, material.alpha()).map_err(|e| e.give_up(LTC_FAILED))?;
    let f0 = material.f0();
    let scale = DVec3::new(
        look.specular_scale(f0.x),
        look.specular_scale(f0.y),
        look.specular_scale(f0.z),
    );
    Ok(Some((look.m_inv, scale)))
}

/// Scratch storage and counters of shading queries ([`Scene::shade_in`]): the visibility fast
/// path's [`Pieces`], kept so that their buffers are reused from one query to the next.
///
/// Inline storage covers lights and blockers of up to 16 vertices, so a context allocates
/// nothing for them; larger inputs, and closed mesh blockers and closed non-planar mesh lights
/// of any size, spill to the heap once per context. [`Scene::shade`] reuses one context per
/// thread (feature `std`; without it, one on the stack per call). A context holds no results:
/// any context serves any scene. One per thread (it is `Send`, and the scene is shared).
///
/// # Examples
///
/// ```
/// use arealight::glam::DVec3;
/// use arealight::shade::{Light, Material, Scene, ShadeContext, TriangleMesh};
/// let quad = TriangleMesh::quad(DVec3::new(0.0, 0.0, 2.0), DVec3::Y * 0.5, DVec3::X * 0.5)?;
/// let scene = Scene::new(vec![Light::new(quad, DVec3::ONE)?], vec![])?;
/// let white = Material::diffuse(DVec3::ONE)?;
/// let mut ctx = ShadeContext::new();
/// for k in 0..4 {
///     let x = DVec3::new(0.1 * k as f64, 0.0, 0.0);
///     let rgb = scene.shade_in(&mut ctx, x, DVec3::Z, DVec3::Z, &white)?;
///     assert_eq!(rgb, scene.shade(x, DVec3::Z, DVec3::Z, &white)?);
/// }
/// // A quad light seen from the front: every query took the fast path.
/// assert_eq!((ctx.fast_lights(), ctx.spherical_lights()), (4, 0));
/// # Ok::<(), arealight::GeomError>(())
/// ```
#[derive(Debug, Clone)]
pub struct ShadeContext {
    pieces: Pieces,
    fast: u64,
    spherical: u64,
}

impl Default for ShadeContext {
    #[inline(always)]
    fn default() -> Self {
        ShadeContext::new()
    }
}

impl ShadeContext {
    /// A fresh context (no heap allocation).
    #[must_use]
    #[inline(always)]
    pub fn new() -> Self {
        ShadeContext {
            pieces: Pieces::new(),
            fast: 0,
            spherical: 0,
        }
    }

    /// How many (point, light) regions the queries through this context took from the fast path
    /// ([`ClipVisibility::visible_pieces`]).
    #[must_use]
    pub fn fast_lights(&self) -> u64 {
        self.fast
    }

    /// How many (point, light) regions took the spherical path
    /// ([`ClipVisibility::visible_region`]), where the fast path does not apply.
    #[must_use]
    pub fn spherical_lights(&self) -> u64 {
        self.spherical
    }
}

#[cfg(feature = "std")]
std::thread_local! {
    /// The context [`with_context`] lends to the entry points that take none: the scratch
    /// storage of closed meshes (the overlay's buffers, reserved for a few hundred vertices)
    /// costs about as much to set up and free as a small mesh's whole query, so a renderer
    /// calling [`Scene::shade`] per pixel should not pay it per call. Thread-local storage, not
    /// the heap: lending it allocates nothing.
    static CONTEXT: core::cell::RefCell<ShadeContext> =
        core::cell::RefCell::new(ShadeContext::new());
}

/// Runs `f` (once) with this thread's kept [`ShadeContext`] (feature `std`), or with a fresh
/// one where there is none to lend (without `std`, while another query on this thread holds it,
/// which cannot happen while the queries call no user code, or while the thread is being torn
/// down). A context holds no results, only buffers, so the value is the same bit for bit
/// whichever context `f` gets.
#[inline]
fn with_context<R>(mut f: impl FnMut(&mut ShadeContext) -> R) -> R {
    #[cfg(feature = "std")]
    if let Ok(Some(out)) =
        CONTEXT.try_with(|cell| cell.try_borrow_mut().ok().map(|mut ctx| f(&mut ctx)))
    {
        return out;
    }
    f(&mut ShadeContext::new())
}

/// The diffuse and LTC integrals of the fast path's pieces, as [`integrals`] of the same region
/// (up to rounding); `None` only for an LTC map the ring integral declines (never one of the
/// tables').
#[inline(always)]
fn piece_integrals(pieces: &Pieces, spec: &SpecularSetup) -> Option<(f64, f64)> {
    let diffuse = upper_rings_integral(pieces.rings());
    let specular = match spec {
        Some((m_inv, _)) => ltc_rings_integral(pieces.rings(), *m_inv)?,
        None => 0.0,
    };
    Some((diffuse, specular))
}

/// The diffuse (clamped cosine over pi) and LTC integrals over region pieces already clipped to
/// the upper hemisphere; the second is zero without a specular lobe.
pub(super) fn integrals(
    pieces: &[SphericalPolygon],
    spec: SpecularSetup,
) -> Result<(f64, f64), GeomError> {
    let (mut diffuse, mut specular) = (0.0, 0.0);
    for piece in pieces {
        diffuse += clamped_cosine_integral_upper(piece);
        if let Some((m_inv, _)) = spec {
            specular += ltc_integral(piece, m_inv).map_err(|e| e.give_up(LTC_FAILED))?;
        }
    }
    Ok((diffuse, specular))
}

/// The diffuse and LTC integrals of light `i`'s visible region (`blocked`) or of its region
/// with every other object removed, as `vis` gives it: from the backend's fast path
/// ([`Visibility::visible_pieces`]) where it has one that applies, else from its spherical
/// polygons ([`Visibility::visible_region`], [`Visibility::unoccluded_region`]). Counted in
/// `ctx`.
#[inline(always)]
pub(super) fn region_integrals<V: Visibility + ?Sized>(
    vis: &V,
    i: usize,
    frame: &ShadingFrame,
    spec: &SpecularSetup,
    blocked: bool,
    ctx: &mut ShadeContext,
) -> Result<(f64, f64), GeomError> {
    if vis.visible_pieces(i, frame, blocked, &mut ctx.pieces)?
        && let Some(v) = piece_integrals(&ctx.pieces, spec)
    {
        ctx.fast += 1;
        return Ok(v);
    }
    ctx.spherical += 1;
    // The spherical path's pieces are already clipped to the upper hemisphere.
    let region = if blocked {
        vis.visible_region(i, frame)?
    } else {
        vis.unoccluded_region(i, frame)?
    };
    integrals(&region, *spec)
}

impl Scene {
    /// The outgoing radiance (RGB) at `point` towards `view`, for a surface with normal
    /// `normal` and material `material`: seed 000 Alg. 1 summed over the lights.
    ///
    /// `view` points from the surface towards the viewer; `normal` and `view` need not be
    /// normalized. All three may be `f32` (glam's `Vec3`, `Vec3A`, `[f32; 3]`, see
    /// [`IntoDVec3`]): they are widened exactly, and the computation is `f64`. For each light
    /// the visible region is computed in the shading frame ([`Scene::visible_region`]), and
    /// integrated with Baum's formula for the diffuse lobe and, after the LTC transform `M^-1`
    /// looked up for the view angle and roughness, for the GGX lobe (HDHN16 eq. 2 / seed 000
    /// eq. 2, Alg. 1 lines 13-16).
    ///
    /// # Errors
    ///
    /// Two kinds, told apart by [`GeomError::is_undecidable`]:
    ///
    /// - input faults, naming the argument ([`ShadingFrame::new`]): a NaN or infinite point,
    ///   normal or view ([`GeomError::NonFiniteArgument`]), a normal or view of zero length
    ///   ([`GeomError::ZeroLengthArgument`]), a point beyond the coordinate range
    ///   ([`GeomError::OutOfRange`]); skip or fix the query;
    /// - [`GeomError::Undecidable`]: the query is valid but a silhouette or spherical set
    ///   operation cannot be decided within rounding (the point within rounding distance of an
    ///   edge's line, near-coincident blocker edges); fall back for this query (the Monte Carlo
    ///   reference, or a point moved by a tiny amount).
    ///
    /// No other error is returned: the scene and the material were validated when built.
    ///
    /// # Points on surfaces
    ///
    /// A point on an occluder's surface (or within the facing predicate's tolerance of one of its
    /// face planes, [`crate::solid::FACE_TOLERANCE`]) gets a finite value: a convex occluder
    /// covers the half-space behind the faces it lies on (a hemisphere seen from a point on a
    /// face, a lune from an edge), so such a point sees the light only through the other side
    /// of those face planes; a mesh occluder's triangles seen edge-on cover nothing. A point on
    /// a planar light's plane sees none of that light (it is seen edge-on); a point inside a
    /// closed light that bounds a solid, or on a convex light's surface, receives nothing from
    /// it.
    ///
    /// With the `std` feature (a default) each thread keeps one [`ShadeContext`] that its
    /// calls reuse; without it each call makes one on the stack. [`Scene::shade_in`] takes the
    /// caller's.
    pub fn shade(
        &self,
        point: impl IntoDVec3,
        normal: impl IntoDVec3,
        view: impl IntoDVec3,
        material: &Material,
    ) -> Result<DVec3, GeomError> {
        let frame = frame(point, normal, view)?;
        let spec = specular_setup(&frame, material)?;
        with_context(|ctx| self.shade_frame_in(ctx, &frame, material, &spec))
    }

    /// [`Scene::shade`] in the caller's [`ShadeContext`]: the same value, bit for bit, without
    /// setting up scratch storage per call, and with the context's counters of which path each
    /// light took. Keep one context per thread.
    ///
    /// # Errors
    ///
    /// As [`Scene::shade`].
    pub fn shade_in(
        &self,
        ctx: &mut ShadeContext,
        point: impl IntoDVec3,
        normal: impl IntoDVec3,
        view: impl IntoDVec3,
        material: &Material,
    ) -> Result<DVec3, GeomError> {
        let frame = frame(point, normal, view)?;
        let spec = specular_setup(&frame, material)?;
        self.shade_frame_in(ctx, &frame, material, &spec)
    }

    /// [`Scene::shade_in`] at a validated frame.
    fn shade_frame_in(
        &self,
        ctx: &mut ShadeContext,
        frame: &ShadingFrame,
        material: &Material,
        spec: &SpecularSetup,
    ) -> Result<DVec3, GeomError> {
        let mut total = DVec3::ZERO;
        for i in 0..self.lights().len() {
            total += self.shade_light_in(i, frame, material, spec, ctx)?;
        }
        Ok(total)
    }

    /// [`Scene::shade`] with the visible regions of another [`Visibility`] backend over the same
    /// lights and occluders, e.g. a
    /// [`PluckerVisibility`](crate::visibility::PluckerVisibility) built from
    /// [`Scene::visibility`] (or one of its per-thread
    /// [`PluckerVisibility::with_context`](crate::visibility::PluckerVisibility::with_context)
    /// views, which reuse trees across calls). The integration is [`Scene::shade`]'s.
    ///
    /// # Examples
    ///
    /// ```
    /// use arealight::glam::DVec3;
    /// use arealight::shade::{ConvexPolyhedron, Light, Material, Scene, TriangleMesh};
    /// use arealight::visibility::PluckerVisibility;
    /// let quad = TriangleMesh::quad(DVec3::new(0.0, 0.0, 3.0), DVec3::Y * 0.5, DVec3::X * 0.5)?;
    /// let cube = ConvexPolyhedron::cuboid(DVec3::new(0.3, 0.0, 1.5), DVec3::splat(0.25))?;
    /// let scene = Scene::new(vec![Light::new(quad, DVec3::ONE)?], vec![cube.into()])?;
    /// let floor = Material::new(DVec3::splat(0.8), DVec3::splat(0.04), 0.5)?;
    /// let (x, n, v) = (DVec3::ZERO, DVec3::Z, DVec3::new(0.3, 0.0, 1.0));
    /// let clip = scene.shade(x, n, v, &floor)?;
    /// assert_eq!(scene.shade_with(scene.visibility(), x, n, v, &floor)?, clip);
    /// let plucker = PluckerVisibility::from_clip(scene.visibility().clone());
    /// let lazy = scene.shade_with(&plucker, x, n, v, &floor)?;
    /// assert!((lazy - clip).abs().max_element() <= 1e-12 * clip.max_element());
    /// # Ok::<(), arealight::GeomError>(())
    /// ```
    ///
    /// # Errors
    ///
    /// As [`Scene::shade`]; [`GeomError::OutOfRange`] when `vis` has another number of lights.
    pub fn shade_with(
        &self,
        vis: &dyn Visibility,
        point: impl IntoDVec3,
        normal: impl IntoDVec3,
        view: impl IntoDVec3,
        material: &Material,
    ) -> Result<DVec3, GeomError> {
        if vis.light_count() != self.lights().len() {
            return Err(GeomError::OutOfRange {
                what: "light count of the visibility backend (the scene's)",
                value: vis.light_count() as f64,
                limit: self.lights().len() as f64,
            });
        }
        let frame = frame(point, normal, view)?;
        let spec = specular_setup(&frame, material)?;
        with_context(|ctx| {
            let mut total = DVec3::ZERO;
            for (i, light) in self.lights().iter().enumerate() {
                let (diffuse, specular) = region_integrals(vis, i, &frame, &spec, true, ctx)?;
                let mut out = material.albedo() * diffuse;
                if let Some((_, scale)) = spec {
                    out += scale * specular;
                }
                total += out * light.radiance();
            }
            Ok(total)
        })
    }

    /// The contribution of light `light` alone to [`Scene::shade`] (occluders included).
    ///
    /// # Errors
    ///
    /// As [`Scene::shade`]; [`GeomError::OutOfRange`] for a light index past the end.
    pub fn shade_light(
        &self,
        light: usize,
        point: impl IntoDVec3,
        normal: impl IntoDVec3,
        view: impl IntoDVec3,
        material: &Material,
    ) -> Result<DVec3, GeomError> {
        self.light(light)?;
        let frame = frame(point, normal, view)?;
        let spec = specular_setup(&frame, material)?;
        with_context(|ctx| self.shade_light_in(light, &frame, material, &spec, ctx))
    }

    /// Every light's share of [`Scene::shade`] at `point` (same arguments), split into the
    /// diffuse and specular lobes, each with its unshadowed value ([`LightShading`]), in the
    /// order of [`Scene::lights`]: what a renderer needs to denoise shadows apart from shading,
    /// to form ratio estimators, or to see which light does what.
    ///
    /// The frame and the LTC table lookup are computed once for all lights; per light, the
    /// visible and the unoccluded region ([`Visibility::unoccluded_region`]) are each integrated
    /// once. So this costs about two [`Scene::shade`] calls (one where no blocker is near).
    ///
    /// # Examples
    ///
    /// ```
    /// use arealight::glam::DVec3;
    /// use arealight::shade::{ConvexPolyhedron, Light, Material, Scene, TriangleMesh};
    /// let quad = TriangleMesh::quad(DVec3::new(0.0, 0.0, 3.0), DVec3::Y * 0.5, DVec3::X * 0.5)?;
    /// let cube = ConvexPolyhedron::cuboid(DVec3::new(0.3, 0.0, 1.5), DVec3::splat(0.25))?;
    /// let scene = Scene::new(vec![Light::new(quad, DVec3::ONE)?], vec![cube.into()])?;
    /// let floor = Material::new(DVec3::splat(0.8), DVec3::splat(0.04), 0.5)?;
    /// let (x, n, v) = (DVec3::ZERO, DVec3::Z, DVec3::new(0.3, 0.0, 1.0));
    /// let parts = scene.shade_per_light(x, n, v, &floor)?;
    /// let total = scene.shade(x, n, v, &floor)?;
    /// assert!((parts[0].shadowed() - total).abs().max_element() < 1e-12);
    /// // The shadow ratio of the penumbra, per channel.
    /// let ratio = parts[0].shadowed() / parts[0].unshadowed();
    /// assert!(ratio.x > 0.1 && ratio.x < 0.9);
    /// # Ok::<(), arealight::GeomError>(())
    /// ```
    ///
    /// # Errors
    ///
    /// As [`Scene::shade`].
    pub fn shade_per_light(
        &self,
        point: impl IntoDVec3,
        normal: impl IntoDVec3,
        view: impl IntoDVec3,
        material: &Material,
    ) -> Result<Vec<LightShading>, GeomError> {
        let frame = frame(point, normal, view)?;
        let spec = specular_setup(&frame, material)?;
        with_context(|ctx| {
            let mut out = Vec::with_capacity(self.lights().len());
            for (i, light) in self.lights().iter().enumerate() {
                let vis = self.light_visibility(i, &frame);
                let unshadowed = region_integrals(vis, i, &frame, &spec, false, ctx)?;
                // Exactly what `shade` computes for the light, so that the shares add up to it. The
                // unshadowed region may come from the other path (the fast path declines only where
                // a blocker needs the spherical one); the two agree to rounding, so the shadowed
                // value can exceed the unshadowed one by rounding.
                let shadowed = region_integrals(vis, i, &frame, &spec, true, ctx)?;
                let rgb = light.radiance();
                let lobes = |(d, s): (f64, f64)| {
                    let specular = spec.map_or(DVec3::ZERO, |(_, scale)| scale * s * rgb);
                    (material.albedo() * d * rgb, specular)
                };
                let (diffuse, specular) = lobes(shadowed);
                let (unshadowed_diffuse, unshadowed_specular) = lobes(unshadowed);
                out.push(LightShading {
                    diffuse,
                    specular,
                    unshadowed_diffuse,
                    unshadowed_specular,
                });
            }
            Ok(out)
        })
    }

    fn shade_light_in(
        &self,
        i: usize,
        frame: &ShadingFrame,
        material: &Material,
        spec: &SpecularSetup,
        ctx: &mut ShadeContext,
    ) -> Result<DVec3, GeomError> {
        let light = &self.lights()[i];
        let vis = self.light_visibility(i, frame);
        let (diffuse, specular) = region_integrals(vis, i, frame, spec, true, ctx)?;
        let mut out = material.albedo() * diffuse;
        if let Some((_, scale)) = spec {
            out += *scale * specular;
        }
        Ok(out * light.radiance())
    }
}
