//! The least-squares fit of parameter identification (#48) on models with known
//! answers: exact data recovered, the covariance of a linear model equal to the
//! textbook formula, a product of two parameters reported as all the data determine,
//! bounds kept, too few residuals refused.

use crate::common;
use splinerod::fit::{fit, Model, ParameterSpace};
use splinerod::{Error, Real};

/// `y(t) = f(p, t)` at the times `t`, observed as `y` with standard deviation `sigma`;
/// the derivative by the parameters given by `df`.
struct Curve<F, D> {
    t: Vec<Real>,
    y: Vec<Real>,
    sigma: Real,
    f: F,
    df: D,
}

impl<F, D> Model for Curve<F, D>
where
    F: Fn(&[Real], Real) -> Real,
    D: Fn(&[Real], Real) -> Vec<Real>,
{
    fn residual_count(&self) -> usize {
        self.t.len()
    }

    fn evaluate(
        &mut self,
        p: &[Real],
        r: &mut [Real],
        j: Option<&mut [Real]>,
    ) -> Result<(), Error> {
        for (i, (&t, &y)) in self.t.iter().zip(&self.y).enumerate() {
            r[i] = (y - (self.f)(p, t)) / self.sigma;
        }
        if let Some(j) = j {
            for (i, &t) in self.t.iter().enumerate() {
                for (k, d) in (self.df)(p, t).into_iter().enumerate() {
                    j[i * p.len() + k] = -d / self.sigma;
                }
            }
        }
        Ok(())
    }
}

const FREE: ParameterSpace = ParameterSpace {
    log: false,
    bounds: None,
};
const POSITIVE: ParameterSpace = ParameterSpace {
    log: true,
    bounds: None,
};

#[test]
fn exact_data_are_recovered_in_log_space() {
    let decay = |p: &[Real], t: Real| p[0] * (-p[1] * t).exp();
    let t: Vec<Real> = (0..20).map(|i| 0.1 * i as Real).collect();
    let y = t.iter().map(|&t| decay(&[2.0, 3.0], t)).collect();
    let df = |p: &[Real], t: Real| vec![(-p[1] * t).exp(), -t * p[0] * (-p[1] * t).exp()];
    let mut model = Curve {
        t,
        y,
        sigma: 1e-3,
        f: decay,
        df,
    };
    let report = fit(&mut model, &[0.5, 0.5], &[POSITIVE, POSITIVE], 200).expect("fit");
    println!("{report:?}");
    assert!(report.converged);
    assert!((report.parameters[0] - 2.0).abs() < 1e-9 && (report.parameters[1] - 3.0).abs() < 1e-9);
    assert!(report.residual_rms < 1e-9 && report.unidentifiable.is_empty());
    assert!(
        report.simulations <= 60,
        "{} simulations",
        report.simulations
    );
}

#[test]
fn a_linear_model_has_the_textbook_covariance() {
    // y = a + b t with noise of σ = 0.05: the fit is the normal equations' solution and
    // the covariance s² (XᵀX)⁻¹, s² = Σ r² / (m − 2), r in units of σ.
    let (sigma, m) = (0.05, 40);
    let t: Vec<Real> = (0..m).map(|i| i as Real / m as Real).collect();
    let y: Vec<Real> = t
        .iter()
        .enumerate()
        .map(|(i, &t)| 1.0 + 2.0 * t + sigma * common::noise(i))
        .collect();
    let line = |p: &[Real], t: Real| p[0] + p[1] * t;
    let mut model = Curve {
        t: t.clone(),
        y: y.clone(),
        sigma,
        f: line,
        df: |_: &[Real], t: Real| vec![1.0, t],
    };
    let report = fit(&mut model, &[0.0, 0.0], &[FREE, FREE], 100).expect("fit");
    let (n, st, stt) = (
        m as Real,
        t.iter().sum::<Real>(),
        t.iter().map(|t| t * t).sum::<Real>(),
    );
    let (sy, sty) = (
        y.iter().sum::<Real>(),
        t.iter().zip(&y).map(|(t, y)| t * y).sum::<Real>(),
    );
    let det = n * stt - st * st;
    let (a, b) = ((stt * sy - st * sty) / det, (n * sty - st * sy) / det);
    let rss: Real = t
        .iter()
        .zip(&y)
        .map(|(t, y)| ((y - a - b * t) / sigma).powi(2))
        .sum();
    let s2 = rss / (n - 2.0);
    // (XᵀX)⁻¹ with X in units of σ.
    let (var_a, var_b) = (s2 * sigma * sigma * stt / det, s2 * sigma * sigma * n / det);
    let corr = -st / (n * stt).sqrt();
    println!(
        "{report:?}; expected a {a} ± {}, b {b} ± {}, corr {corr}",
        var_a.sqrt(),
        var_b.sqrt()
    );
    assert!((report.parameters[0] - a).abs() < 1e-10 && (report.parameters[1] - b).abs() < 1e-10);
    assert!(
        (report.std[0] / var_a.sqrt() - 1.0).abs() < 1e-8,
        "{:?}",
        report.std
    );
    assert!(
        (report.std[1] / var_b.sqrt() - 1.0).abs() < 1e-8,
        "{:?}",
        report.std
    );
    assert!(
        (report.correlation[0][1] - corr).abs() < 1e-8,
        "{:?}",
        report.correlation
    );
    assert!((report.residual_rms - (rss / n).sqrt()).abs() < 1e-10);
}

#[test]
fn parameters_the_data_cannot_separate_are_reported() {
    // y = a b t: only the product is determined — the direction (1, −1) in (ln a, ln b).
    let product = |p: &[Real], t: Real| p[0] * p[1] * t;
    let df = |p: &[Real], t: Real| vec![p[1] * t, p[0] * t];
    let t: Vec<Real> = (1..=10).map(|i| i as Real).collect();
    let y = t.iter().map(|&t| 6.0 * t).collect();
    let mut model = Curve {
        t,
        y,
        sigma: 0.01,
        f: product,
        df,
    };
    let report = fit(&mut model, &[1.0, 1.0], &[POSITIVE, POSITIVE], 100).expect("fit");
    println!("{report:?}");
    assert!((report.parameters[0] * report.parameters[1] - 6.0).abs() < 1e-8);
    assert_eq!(report.unidentifiable.len(), 1);
    let (group, direction) = &report.unidentifiable[0];
    assert_eq!(group, &vec![0, 1]);
    let half = 0.5f64.sqrt();
    assert!((direction[0].abs() - half).abs() < 1e-6 && (direction[0] + direction[1]).abs() < 1e-6);
    assert!(report.std.iter().all(|s| s.is_infinite()));
}

#[test]
fn bounds_are_kept_and_too_few_residuals_refused() {
    // The best b is 3, outside [0.5, 2]: the fit ends on the bound.
    let decay = |p: &[Real], t: Real| (-p[0] * t).exp();
    let t: Vec<Real> = (0..10).map(|i| 0.1 * i as Real).collect();
    let y = t.iter().map(|&t| (-3.0 * t).exp()).collect();
    let df = |p: &[Real], t: Real| vec![-t * (-p[0] * t).exp()];
    let mut model = Curve {
        t,
        y,
        sigma: 1e-3,
        f: decay,
        df,
    };
    let bounded = ParameterSpace {
        log: true,
        bounds: Some((0.5, 2.0)),
    };
    let report = fit(&mut model, &[1.0], &[bounded], 100).expect("fit");
    println!("{report:?}");
    assert!(
        (report.parameters[0] - 2.0).abs() < 1e-6,
        "{:?}",
        report.parameters
    );

    let line = |p: &[Real], t: Real| p[0] + p[1] * t + p[2] * t * t;
    let mut two = Curve {
        t: vec![0.0, 1.0],
        y: vec![1.0, 2.0],
        sigma: 1.0,
        f: line,
        df: |_: &[Real], t: Real| vec![1.0, t, t * t],
    };
    let e = fit(&mut two, &[0.0; 3], &[FREE; 3], 100).expect_err("2 residuals, 3 parameters");
    assert!(e.to_string().contains("observations"), "{e}");
}
