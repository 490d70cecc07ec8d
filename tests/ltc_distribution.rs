//! The LTC distribution: normalisation, horizon mass and sampling, for arbitrary matrices.

mod support;

use arealight::GeomError;
use arealight::glam::{DMat3, DVec2, DVec3};
use arealight::ltc::Ltc;
use support::Rng;
use support::ltc::{histogram_sigma, sphere_quad};

/// A random matrix: rotation * diag(scales in [0.08, 1]) * shear, with random sign.
fn random_matrix(rng: &mut Rng) -> DMat3 {
    let rot = DMat3::from_euler(
        arealight::glam::EulerRot::ZYX,
        rng.range(-3.0, 3.0),
        rng.range(-1.5, 1.5),
        rng.range(-3.0, 3.0),
    );
    let diag = DMat3::from_diagonal(DVec3::new(rng.range(0.08, 1.0), rng.range(0.08, 1.0), 1.0));
    let shear = DMat3::from_cols(
        DVec3::X,
        DVec3::Y,
        DVec3::new(rng.range(-0.5, 0.5), rng.range(-0.5, 0.5), 1.0),
    );
    let m = rot * diag * shear * rng.range(0.1, 10.0);
    if rng.f64() < 0.3 { -m } else { m }
}

/// Direction of the LTC's peak: the image of the cosine's pole.
fn peak(ltc: &Ltc) -> DVec3 {
    (ltc.matrix() * DVec3::Z).normalize()
}

#[test]
fn density_integrates_to_one_for_arbitrary_matrices() {
    let mut rng = Rng::from_state(10);
    for case in 0..40 {
        let m = random_matrix(&mut rng);
        let ltc = Ltc::new(m).unwrap();
        let total = sphere_quad(peak(&ltc), 2.0, 800, 400, |w| ltc.density(w));
        assert!(
            (total - 1.0).abs() < 2e-3,
            "case {case}: {m:?} integrates to {total}"
        );
        // The horizon mass formula against quadrature of the density over z > 0.
        let upper = sphere_quad(peak(&ltc), 2.0, 800, 400, |w| {
            if w.z > 0.0 { ltc.density(w) } else { 0.0 }
        });
        let h = ltc.upper_hemisphere_mass();
        assert!(
            (upper - h).abs() < 3e-3,
            "case {case}: upper mass {upper} vs formula {h}"
        );
    }
}

#[test]
fn inverse_constructor_is_consistent() {
    let mut rng = Rng::from_state(11);
    for _ in 0..100 {
        let m = random_matrix(&mut rng);
        let a = Ltc::new(m).unwrap();
        let b = Ltc::from_inverse(m.inverse()).unwrap();
        let w = DVec3::new(
            rng.range(-1.0, 1.0),
            rng.range(-1.0, 1.0),
            rng.range(-1.0, 1.0),
        )
        .normalize();
        let (da, db) = (a.density(w), b.density(w));
        assert!((da - db).abs() <= 1e-9 * da.max(1.0), "{da} vs {db}");
    }
}

#[test]
fn samples_follow_the_density() {
    let mut rng = Rng::from_state(12);
    for case in 0..4 {
        let ltc = Ltc::new(random_matrix(&mut rng)).unwrap();
        let pole = peak(&ltc);
        let mut srng = Rng::from_state(100 + case);
        let sigma = histogram_sigma(
            pole,
            2.0,
            10,
            12,
            200_000,
            || ltc.sample(DVec2::new(srng.f64(), srng.f64())),
            |w| ltc.density(w),
        );
        assert!(sigma < 5.0, "case {case}: worst bin {sigma} sigma");
    }
}

#[test]
fn invalid_matrices_are_errors() {
    let nan = DMat3::from_diagonal(DVec3::new(f64::NAN, 1.0, 1.0));
    assert_eq!(
        Ltc::new(nan),
        Err(GeomError::NonFiniteArgument { what: "LTC matrix" })
    );
    assert_eq!(
        Ltc::from_inverse(nan),
        Err(GeomError::NonFiniteArgument {
            what: "inverse LTC matrix"
        })
    );

    let singular = DMat3::from_cols(DVec3::X, DVec3::X, DVec3::Z);
    assert!(matches!(Ltc::new(singular), Err(GeomError::Degenerate(_))));
    assert!(matches!(
        Ltc::new(DMat3::ZERO),
        Err(GeomError::Degenerate(_))
    ));
    // A valid LTC returns NaN, not a panic, for a NaN direction.
    let ltc = Ltc::new(DMat3::IDENTITY).unwrap();
    assert!(ltc.density(DVec3::NAN).is_nan());
    assert_eq!(ltc.density(DVec3::ZERO), 0.0);
}
