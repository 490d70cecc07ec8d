//! Many shading points at once: [`Scene::shade_batch`], and with the `rayon` feature
//! [`Scene::par_shade_batch`] on all cores.
//!
//! A renderer's G-buffer is a set of parallel arrays (positions, normals, view vectors,
//! materials), often in `f32`; these take them as slices and return one result per point, so
//! that a point that fails (see [`Scene::shade`]'s errors) can fall back alone. Points are
//! independent and each is shaded by exactly the code of [`Scene::shade`] (through
//! [`Scene::shade_in`], with one [`super::ShadeContext`] per thread: scratch storage, no
//! results), so the results do not depend on the order, the batch or the number of threads:
//! `par_shade_batch` returns bit for bit what `shade_batch` returns, and both what `shade`
//! returns point by point.

use alloc::vec::Vec;

use glam::DVec3;

use super::material::Material;
use super::query::ShadeContext;
use super::scene::Scene;
use crate::{GeomError, IntoDVec3};

/// The radiance of each point of a batch, or the error [`Scene::shade`] gave for it.
pub type BatchResult = Vec<Result<DVec3, GeomError>>;

/// Checks that the slices of a batch have matching lengths: `normals` and `views` as many as
/// `points`, and `materials` as many or exactly one.
fn check_lengths(
    points: usize,
    normals: usize,
    views: usize,
    materials: usize,
) -> Result<(), GeomError> {
    for (what, n) in [
        ("batch normals (one per point)", normals),
        ("batch views (one per point)", views),
    ] {
        if n != points {
            return Err(GeomError::OutOfRange {
                what,
                value: n as f64,
                limit: points as f64,
            });
        }
    }
    if materials != points && materials != 1 {
        return Err(GeomError::OutOfRange {
            what: "batch materials (one per point, or one for all)",
            value: materials as f64,
            limit: points as f64,
        });
    }
    Ok(())
}

/// The material of point `i`: its own, or the one shared by all.
#[inline]
fn material_of(materials: &[Material], i: usize) -> &Material {
    if materials.len() == 1 {
        &materials[0]
    } else {
        &materials[i]
    }
}

impl Scene {
    /// [`Scene::shade`] for every point of a batch: `points[i]` with `normals[i]`, `views[i]`
    /// and `materials[i]` (or `materials[0]` for all, when it holds one material), in order.
    ///
    /// Vectors may be `f32` ([`IntoDVec3`]: glam's `Vec3`, `Vec3A`, `[f32; 3]`) or `f64`. Each
    /// entry of the result is what `shade` returns for that point, error included: skip or fix
    /// an input fault, fall back on [`GeomError::Undecidable`] (see [`Scene::shade`]).
    ///
    /// Runs on the calling thread; with the `rayon` feature, [`Scene::par_shade_batch`] returns
    /// the same results on all cores.
    ///
    /// # Examples
    ///
    /// ```
    /// use arealight::glam::{DVec3, Vec3};
    /// use arealight::shade::{Light, Material, Scene, TriangleMesh};
    /// let quad = TriangleMesh::quad(DVec3::new(0.0, 0.0, 2.0), DVec3::Y * 0.5, DVec3::X * 0.5)?;
    /// let scene = Scene::new(vec![Light::new(quad, DVec3::ONE)?], vec![])?;
    /// // An f32 G-buffer: three floor points under the light.
    /// let points = [Vec3::ZERO, Vec3::new(0.5, 0.0, 0.0), Vec3::new(f32::NAN, 0.0, 0.0)];
    /// let up = [Vec3::Z; 3];
    /// let white = [Material::diffuse(DVec3::ONE)?];
    /// let rgb = scene.shade_batch(&points, &up, &up, &white)?;
    /// assert_eq!(rgb[0], scene.shade(DVec3::ZERO, DVec3::Z, DVec3::Z, &white[0]));
    /// assert!(rgb[1].as_ref().unwrap().x < rgb[0].as_ref().unwrap().x);
    /// assert!(rgb[2].is_err()); // the NaN point alone
    /// # Ok::<(), arealight::GeomError>(())
    /// ```
    ///
    /// # Errors
    ///
    /// The outer `Result`: [`GeomError::OutOfRange`] when `normals` or `views` do not have one
    /// entry per point, or `materials` neither one per point nor exactly one (nothing is shaded
    /// then). Per point: as [`Scene::shade`].
    pub fn shade_batch<P, N, V>(
        &self,
        points: &[P],
        normals: &[N],
        views: &[V],
        materials: &[Material],
    ) -> Result<BatchResult, GeomError>
    where
        P: IntoDVec3 + Copy,
        N: IntoDVec3 + Copy,
        V: IntoDVec3 + Copy,
    {
        check_lengths(points.len(), normals.len(), views.len(), materials.len())?;
        // One context for the batch: `shade`'s value without its scratch set-up per point.
        let mut ctx = ShadeContext::new();
        Ok((0..points.len())
            .map(|i| {
                let m = material_of(materials, i);
                self.shade_in(&mut ctx, points[i], normals[i], views[i], m)
            })
            .collect())
    }

    /// [`Scene::shade_batch`] on all cores (rayon's global pool, or the pool this is called
    /// from inside `ThreadPool::install`): the same results, bit for bit, in the same order.
    ///
    /// Points are handed out in runs of at least [`PAR_MIN_RUN`], so that rayon's work
    /// splitting costs little next to the points themselves (a few microseconds each).
    ///
    /// # Errors
    ///
    /// As [`Scene::shade_batch`].
    #[cfg(feature = "rayon")]
    pub fn par_shade_batch<P, N, V>(
        &self,
        points: &[P],
        normals: &[N],
        views: &[V],
        materials: &[Material],
    ) -> Result<BatchResult, GeomError>
    where
        P: IntoDVec3 + Copy + Sync,
        N: IntoDVec3 + Copy + Sync,
        V: IntoDVec3 + Copy + Sync,
    {
        use rayon::prelude::*;
        check_lengths(points.len(), normals.len(), views.len(), materials.len())?;
        Ok((0..points.len())
            .into_par_iter()
            .with_min_len(PAR_MIN_RUN)
            .map_init(ShadeContext::new, |ctx, i| {
                let m = material_of(materials, i);
                self.shade_in(ctx, points[i], normals[i], views[i], m)
            })
            .collect())
    }
}

/// The smallest run of points [`Scene::par_shade_batch`] gives one task.
#[cfg(feature = "rayon")]
pub const PAR_MIN_RUN: usize = 16;
