//! The default references pasted into the products are the in-phase
//! eigenmodes of the default models, recomputed here.

use eigenmpc::mechanics::{PlanarChain, Vector};
use eigenmpc::modes::Chart;
use eigenmpc::mpc::closed_loop::mode_and_chart;
use eigenmpc_fmu_models::controller::settings::CHART_COEFFICIENTS;
use eigenmpc_fmu_models::products::*;

/// The pasted (eigenvector, chart) against the computed ones: the vector to
/// 1e-12, coefficients to fitting noise, the curves to 1e-9 rad along the mode.
fn check<const N: usize, const NX: usize>(
    energy: f64,
    eigenvector: [f64; N],
    pasted: [[f64; CHART_COEFFICIENTS]; N],
) {
    let system = PlanarChain::<N>::default();
    let (mode, chart) =
        mode_and_chart::<_, N, NX>(&system, 0, energy, CHART_COEFFICIENTS - 1).unwrap();
    println!("eigenvector {:?}", chart.eigenvector.as_slice());
    println!("chart {:?}", chart.coefficients);
    let c = Vector::<N>::from(eigenvector);
    assert!(
        (c - chart.eigenvector).amax() < 1e-12,
        "{c} vs {}",
        chart.eigenvector
    );
    for (row, fitted) in pasted.iter().zip(&chart.coefficients) {
        for (k, (a, b)) in row.iter().zip(fitted).enumerate() {
            assert!(
                (a - b).abs() < 1e-8 * (1.0 + b.abs()),
                "power {k}: {a} vs {b}"
            );
        }
    }
    let chart_pasted =
        Chart::from_coefficients(c, Vector::<N>::zeros(), pasted.map(|r| r.to_vec())).unwrap();
    for q in &mode.path {
        let s = chart.coordinate(q);
        assert!((chart_pasted.eval(s).x - chart.eval(s).x).amax() < 1e-9);
    }
}

#[test]
fn two_link_default_is_the_14_j_in_phase_mode() {
    check::<2, 4>(14.0, DEFAULT_EIGENVECTOR, DEFAULT_CHART_14J);
}

#[test]
fn three_link_default_is_the_in_phase_mode_at_its_e_ref() {
    check::<3, 6>(DEFAULT_E_REF_3, DEFAULT_EIGENVECTOR_3, DEFAULT_CHART_3_14J);
}
