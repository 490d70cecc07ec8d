//! Sphere tracing (seed 001 Alg. 1, after \[Har96\]) and Lipschitz-safe cone tracing
//! (\[BV18\], as summarized in seed 001 section 2).
//!
//! Both march along a ray `origin + t dir` by steps that cannot cross the surface, and both
//! always terminate: a trace stops at a hit, past `t_max`, or after `max_steps` evaluations of
//! the field ([`Trace::StepLimit`]), whichever comes first. A step limit is not an error: it
//! says the ray crept along a surface without reaching it (grazing rays converge only
//! geometrically), and reports how far it got.
//!
//! # References
//!
//! - \[Har96\] J. C. Hart. *Sphere tracing.* The Visual Computer 12(10), 1996.
//! - \[BV18\] G. Bálint, M. Valasek. *Accelerating sphere tracing.* Eurographics short papers,
//!   2018: cone tracing by steps of `F(t) / (1 + |tan a|)`.

use super::field::{Sdf, check_direction, check_finite, check_point};
use crate::GeomError;
use glam::DVec3;

/// Where a trace starts and stops, and how many steps it may take.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TraceLimits {
    /// Distance along the ray where the march starts (`>= 0`); a ray leaving a surface starts a
    /// little above it so as not to hit its own origin.
    pub t_min: f64,
    /// Distance past which the ray has missed (`>= t_min`).
    pub t_max: f64,
    /// Largest number of field evaluations (`>= 1`).
    pub max_steps: u32,
    /// A hit is declared where the (cone's) distance to the surface drops to this value or
    /// below (`> 0`: with zero a ray would only converge, never arrive).
    pub hit_distance: f64,
}

impl TraceLimits {
    /// Limits `[0, t_max]`, 256 steps, hits within `1e-6 * t_max`.
    #[must_use]
    pub fn new(t_max: f64) -> Self {
        TraceLimits {
            t_min: 0.0,
            t_max,
            max_steps: 256,
            hit_distance: 1e-6 * t_max,
        }
    }

    /// Checks the limits.
    ///
    /// # Errors
    ///
    /// Non-finite values ([`GeomError::OutOfRange`]), `t_min < 0`, `t_max < t_min`,
    /// `hit_distance <= 0` or `max_steps == 0` ([`GeomError::Degenerate`]).
    pub fn validate(&self) -> Result<(), GeomError> {
        check_finite("trace t_min", self.t_min)?;
        check_finite("trace t_max", self.t_max)?;
        check_finite("trace hit distance", self.hit_distance)?;
        if !(self.t_min >= 0.0 && self.t_max >= self.t_min) {
            return Err(GeomError::Degenerate(
                "sdf: trace limits need 0 <= t_min <= t_max",
            ));
        }
        if !(self.hit_distance > 0.0) {
            return Err(GeomError::Degenerate(
                "sdf: a trace's hit distance must be > 0",
            ));
        }
        if self.max_steps == 0 {
            return Err(GeomError::Degenerate(
                "sdf: a trace needs at least one step",
            ));
        }
        Ok(())
    }
}

/// How a trace ended.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Trace {
    /// The surface (or, for a cone, the cone's boundary) is within `hit_distance` at `t`.
    Hit {
        /// Distance along the ray.
        t: f64,
        /// Field evaluations used.
        steps: u32,
    },
    /// The ray passed `t_max` without a hit.
    Miss {
        /// Field evaluations used.
        steps: u32,
    },
    /// `max_steps` evaluations were used up at `t`, before a hit or `t_max`.
    StepLimit {
        /// How far the ray got.
        t: f64,
        /// Field evaluations used (`max_steps`).
        steps: u32,
    },
}

impl Trace {
    /// The hit distance, if the trace hit.
    #[must_use]
    pub fn hit(&self) -> Option<f64> {
        match *self {
            Trace::Hit { t, .. } => Some(t),
            _ => None,
        }
    }

    /// Field evaluations used.
    #[must_use]
    pub fn steps(&self) -> u32 {
        match *self {
            Trace::Hit { steps, .. } | Trace::Miss { steps } | Trace::StepLimit { steps, .. } => {
                steps
            }
        }
    }
}

/// The field's value at `p`, or an error if it is NaN or `-inf` (a broken field, or a point
/// outside its range). `+inf` is the empty field, no surface anywhere: a value, not an error.
pub(crate) fn eval<S: Sdf + ?Sized>(sdf: &S, p: DVec3) -> Result<f64, GeomError> {
    let d = sdf.distance(p);
    if d.is_nan() || d == f64::NEG_INFINITY {
        return Err(GeomError::OutOfRange {
            what: "signed distance value",
            value: d,
            limit: f64::MAX,
        });
    }
    Ok(d)
}

/// Sphere tracing (seed 001 Alg. 1): from `origin + t_min dir`, step by the field's value until
/// it drops to `hit_distance`. `dir` need not be normalized.
///
/// A start inside a solid (negative value) is a hit at `t_min`.
///
/// # Errors
///
/// Invalid limits ([`TraceLimits::validate`]), a non-finite or zero `origin`/`dir`, a field
/// value that is NaN or `-inf` on the way.
pub fn sphere_trace<S: Sdf + ?Sized>(
    sdf: &S,
    origin: DVec3,
    dir: DVec3,
    limits: &TraceLimits,
) -> Result<Trace, GeomError> {
    cone_trace(sdf, origin, dir, 0.0, 0.0, limits)
}

/// Lipschitz-safe cone tracing (\[BV18\]): the first `t` where the cone of radius
/// `radius + t tan_half_angle` around the ray touches the surface, found by steps of
/// `F(t) / (1 + |tan_half_angle|)` with `F(t) = f(origin + t dir) - radius - t tan_half_angle`.
///
/// `F` is `(1 + |tan a|)`-Lipschitz along the ray (the field is 1-Lipschitz, the radius grows
/// at rate `tan a`), so each step is at most the distance to the nearest root of `F`: the march
/// never steps over a contact of the cone with the surface. Negative `radius` and
/// `tan_half_angle` give the inverted cone of seed 001 (it stops inside the surface).
/// `dir` need not be normalized.
///
/// # Errors
///
/// As [`sphere_trace`]; non-finite `radius` or `tan_half_angle` ([`GeomError::OutOfRange`]).
pub fn cone_trace<S: Sdf + ?Sized>(
    sdf: &S,
    origin: DVec3,
    dir: DVec3,
    radius: f64,
    tan_half_angle: f64,
    limits: &TraceLimits,
) -> Result<Trace, GeomError> {
    limits.validate()?;
    check_point("ray origin", origin)?;
    let dir = check_direction("ray direction", dir)?;
    check_finite("cone radius", radius)?;
    check_finite("cone tan(half angle)", tan_half_angle)?;
    let lipschitz = 1.0 + tan_half_angle.abs();
    let mut t = limits.t_min;
    for step in 1..=limits.max_steps {
        let f = eval(sdf, origin + t * dir)?;
        let gap = f - radius - t * tan_half_angle;
        if gap <= limits.hit_distance {
            return Ok(Trace::Hit { t, steps: step });
        }
        t += gap / lipschitz;
        if !(t <= limits.t_max) {
            return Ok(Trace::Miss { steps: step });
        }
    }
    Ok(Trace::StepLimit {
        t,
        steps: limits.max_steps,
    })
}
