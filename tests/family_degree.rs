//! A mode family's chart degree follows the mode's curvature
//! (`ChartFamily::compute_accurate`): the paper's pendulum with a lighter
//! first link has a more curved in-phase mode at 14 J, which a degree-9
//! chart misses by more than `CHART_TOLERANCE`; the adaptation computes
//! identified models' families this way.

use eigenmpc::mechanics::{PlanarChain, PlanarChainParams};
use eigenmpc::modes::{CHART_TOLERANCE, ChartFamily, FamilyOptions, MAX_FAMILY_DEGREE};

const E_REF: f64 = 14.0;

fn pendulum(m1: f64) -> PlanarChain<2> {
    PlanarChain::new(PlanarChainParams::<2>::point_masses(
        [m1, 1.0],
        [1.0, 1.0],
        9.81,
    ))
    .unwrap()
}

#[test]
fn a_curved_mode_gets_a_higher_chart_degree() {
    // The nominal pendulum's degree-9 charts are within the tolerance at
    // 14 J (8e-4 rad on one orbit): the degree stays.
    let nominal = pendulum(1.0);
    let options = FamilyOptions::for_system(&nominal, &[E_REF]);
    let family = ChartFamily::compute_accurate::<_, 4>(&nominal, 0, &options, E_REF).unwrap();
    eprintln!(
        "nominal: degree {}, miss {:.2e}",
        family.degree(),
        family.miss_about(E_REF)
    );
    assert_eq!(family.degree(), 9);
    assert!(family.miss_about(E_REF) <= CHART_TOLERANCE);

    // Link 1 10 % lighter: degree 9 misses by 2.5e-3 rad, degree 13 is
    // within the tolerance.
    let lighter = pendulum(0.9);
    let options = FamilyOptions::for_system(&lighter, &[E_REF]);
    let nine = ChartFamily::compute::<_, 4>(&lighter, 0, &options).unwrap();
    let accurate = ChartFamily::compute_accurate::<_, 4>(&lighter, 0, &options, E_REF).unwrap();
    eprintln!(
        "m1 0.9: degree 9 misses by {:.2e}, degree {} by {:.2e}",
        nine.miss_about(E_REF),
        accurate.degree(),
        accurate.miss_about(E_REF)
    );
    assert!(nine.miss_about(E_REF) > CHART_TOLERANCE);
    assert_eq!(accurate.degree(), 13);
    assert!(accurate.miss_about(E_REF) <= CHART_TOLERANCE);
    assert!(accurate.degree() <= MAX_FAMILY_DEGREE);
}

#[test]
fn a_family_that_ends_below_the_energy_misses_it_infinitely() {
    // Link 1 25 % lighter: the degree-9 family ends below 14 J (its chart
    // at the next grid energy misses by more than the family's limit); a
    // higher degree reaches past it.
    let lightest = pendulum(0.75);
    let options = FamilyOptions::for_system(&lightest, &[E_REF]);
    let nine = ChartFamily::compute::<_, 4>(&lightest, 0, &options).unwrap();
    eprintln!("m1 0.75: degree 9 ends at {:.3} J", nine.energy_range().1);
    assert!(nine.energy_range().1 < E_REF);
    assert_eq!(nine.miss_about(E_REF), f64::INFINITY);
    let accurate = ChartFamily::compute_accurate::<_, 4>(&lightest, 0, &options, E_REF).unwrap();
    eprintln!(
        "m1 0.75: degree {} ends at {:.3} J, misses by {:.2e}",
        accurate.degree(),
        accurate.energy_range().1,
        accurate.miss_about(E_REF)
    );
    assert!(accurate.energy_range().1 > E_REF);
    assert!(accurate.degree() > 9);
    assert!(accurate.miss_about(E_REF) < 0.01);
}
