//! The float functions the crate needs, routed to std or to libm.
//!
//! `core` has no `sqrt`, `atan2` or `sin_cos` for `f64`, so a `no_std` build takes them from libm.
//! Only this module names either backend; everything else calls these wrappers, which keeps the
//! choice in one place and the results identical across the crate. When both features are on,
//! libm wins, which makes results bit-identical across platforms.

#![allow(dead_code)] // The shim offers the whole set of float functions; each layer uses a subset.

#[cfg(all(not(feature = "std"), not(feature = "libm")))]
compile_error!("arealight needs a float backend: enable the `std` feature (default) or `libm`");

macro_rules! unary {
    ($($(#[$doc:meta])* $name:ident => $libm:ident;)*) => {$(
        $(#[$doc])*
        #[inline]
        #[must_use]
        pub fn $name(x: f64) -> f64 {
            #[cfg(feature = "libm")]
            { libm::$libm(x) }
            #[cfg(all(feature = "std", not(feature = "libm")))]
            { x.$name() }
        }
    )*};
}

unary! {
    /// Square root.
    sqrt => sqrt;
    /// Sine.
    sin => sin;
    /// Cosine.
    cos => cos;
    /// Tangent.
    tan => tan;
    /// Arc cosine.
    acos => acos;
    /// Arc sine.
    asin => asin;
    /// Arc tangent.
    atan => atan;
    /// Natural exponential.
    exp => exp;
    /// Natural logarithm.
    ln => log;
    /// Cube root.
    cbrt => cbrt;
    /// Largest integer not greater than `x`.
    floor => floor;
}

/// Four-quadrant arc tangent of `y / x`.
#[inline]
#[must_use]
pub fn atan2(y: f64, x: f64) -> f64 {
    #[cfg(feature = "libm")]
    {
        libm::atan2(y, x)
    }
    #[cfg(all(feature = "std", not(feature = "libm")))]
    {
        y.atan2(x)
    }
}

/// `x` raised to the power `y`.
#[inline]
#[must_use]
pub fn powf(x: f64, y: f64) -> f64 {
    #[cfg(feature = "libm")]
    {
        libm::pow(x, y)
    }
    #[cfg(all(feature = "std", not(feature = "libm")))]
    {
        x.powf(y)
    }
}

/// Sine and cosine of `x`.
#[inline]
#[must_use]
pub fn sin_cos(x: f64) -> (f64, f64) {
    (sin(x), cos(x))
}

/// `m` scaled by a positive factor to entries of at most 1 in magnitude, or `None` when it has no
/// finite nonzero entry to scale by. Maps of directions depend on their matrix only up to such a
/// factor; scaled, their determinants and products of images stay clear of overflow and
/// underflow.
pub(crate) fn unit_scaled(m: glam::DMat3) -> Option<glam::DMat3> {
    let largest = m.abs().to_cols_array().into_iter().fold(0.0, f64::max);
    (largest > 0.0 && largest.is_finite()).then(|| m * (1.0 / largest))
}

/// A deterministic stream of uniform numbers in `[0, 1)` for the unit tests' random cases
/// (SplitMix64, 53 bits a number): one generator the tests share instead of a copy each.
#[cfg(test)]
pub(crate) fn test_unit_stream(seed: u64) -> impl FnMut() -> f64 {
    let mut state = seed;
    move || {
        state = state.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = state;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    }
}
