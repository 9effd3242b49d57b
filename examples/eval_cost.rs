//! Instructions per basis evaluation (callgrind this): `N` evaluations of a cubic
//! B-spline basis with derivatives at spread parameters.
use splinerod::core::{BSplineSpace, BasisSpace, BasisValues};

fn main() {
    let n: usize = std::env::args()
        .nth(1)
        .map_or(100_000, |a| a.parse().unwrap_or(100_000));
    let space = BSplineSpace::clamped_uniform(3, 40, 1.0).expect("space");
    let mut b = BasisValues::default();
    let mut sum = 0.0;
    for i in 0..n {
        let s = (i as f64 * 0.618_033_988_75).fract();
        space.evaluate(s, &mut b).expect("evaluate");
        sum += b.d2[1] + b.d1[0] + b.value[3];
    }
    println!("{sum}");
}
