//! Refinement by many knots at once (the Oslo algorithm, in blossom form), for scratch
//! copies of a rod that error estimators evaluate on a finer basis.
//!
//! Inserting knots one at a time (Boehm, [`crate::KnotMap`]) shifts every coefficient
//! after the knot, so refining every span of an `n`-point rod that way costs O(n²). Here
//! each new coefficient is computed directly: with old knots `t`, new knots `τ ⊇ t` and
//! the blossom (polar form) `F_μ` of the curve's polynomial piece on a non-empty old
//! span `μ`,
//!
//! \\[ \hat q_j = F_\mu(\tau_{j+1}, \dots, \tau_{j+d}) \\]
//!
//! for any `μ` containing a non-empty new span of function `j`'s support (Ramshaw;
//! de Boor's algorithm with a different argument at each level). The weights
//! `q̂_j = Σ_i α_{ji} q_i` (at most `d + 1` consecutive old coefficients) form a
//! [`RefinementOperator`] that maps any coefficient field, in O(n d³) for the whole rod.

use crate::basis::MAX_ORDER;
use crate::knot_map::Coefficient;
use crate::{CoreError, Real};

/// The old→new coefficient map of a refinement: new coefficient `j` is
/// `Σ_a weights[j][a] · old[first[j] + a]`, `a < d + 1`.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct RefinementOperator {
    order: usize,
    first: Vec<usize>,
    weights: Vec<[Real; MAX_ORDER]>,
}

impl RefinementOperator {
    /// Number of new coefficients.
    pub fn len(&self) -> usize {
        self.first.len()
    }

    /// Whether the operator maps to no coefficient.
    pub fn is_empty(&self) -> bool {
        self.first.is_empty()
    }

    /// New coefficient `j` as (first old index, weights of the `d + 1` old coefficients
    /// from there).
    pub fn row(&self, j: usize) -> (usize, &[Real]) {
        (self.first[j], &self.weights[j][..self.order])
    }

    /// Makes new coefficient `distinct + j` repeat coefficient `j` for every `j` past the
    /// end (a periodic space's copies across the seam), so they agree bit for bit.
    pub(crate) fn tie_periodic(&mut self, distinct: usize) {
        for j in distinct..self.len() {
            self.first[j] = self.first[j - distinct];
            self.weights[j] = self.weights[j - distinct];
        }
    }

    /// Maps `old` (one coefficient per old basis function) into `new` (resized; no
    /// allocation when its capacity allows).
    pub fn apply<T: Coefficient>(&self, old: &[T], new: &mut Vec<T>) {
        new.clear();
        new.extend((0..self.len()).map(|j| {
            let (first, w) = self.row(j);
            w.iter()
                .enumerate()
                .filter(|&(a, _)| first + a < old.len())
                .fold(T::zero(), |acc, (a, &wa)| acc + old[first + a] * wa)
        }));
    }
}

/// Fills `op` with the refinement from B-splines of degree `d` on `old` knots to those on
/// `new` knots (which must contain every old knot with at least its multiplicity and
/// the same domain).
pub fn bspline_refinement(
    d: usize,
    old: &[Real],
    new: &[Real],
    op: &mut RefinementOperator,
) -> Result<(), CoreError> {
    let (n_old, n_new) = (old.len() - d - 1, new.len() - d - 1);
    op.order = d + 1;
    op.first.clear();
    op.weights.clear();
    for j in 0..n_new {
        // A non-empty new span of function j inside the domain, and the old span holding it.
        let k = (j.max(d)..=(j + d).min(n_new - 1))
            .find(|&k| new[k + 1] > new[k])
            .ok_or(CoreError::InvalidParameter {
                name: "refined knot vector",
                value: j as Real,
                reason: "a basis function has no non-empty span inside the domain",
            })?;
        let mu = (d + old[d + 1..n_old].partition_point(|&t| t <= new[k])).min(n_old - 1);
        op.first.push(mu - d);
        op.weights
            .push(blossom_weights(d, old, mu, &new[j + 1..=j + d]));
    }
    Ok(())
}

/// Weights of old coefficients `μ − d ..= μ` in the blossom of piece `μ` at `args`
/// (de Boor's algorithm, argument `args[r − 1]` at level `r`).
fn blossom_weights(d: usize, t: &[Real], mu: usize, args: &[Real]) -> [Real; MAX_ORDER] {
    // w[i][a]: weight of old coefficient μ − d + a in the level-r point i (i = 0..=d).
    let mut w = [[0.0; MAX_ORDER]; MAX_ORDER];
    for (a, row) in w.iter_mut().enumerate().take(d + 1) {
        row[a] = 1.0;
    }
    for (r, &u) in args.iter().enumerate().map(|(r, u)| (r + 1, u)) {
        for i in (r..=d).rev() {
            let g = mu - d + i;
            let alpha = (u - t[g]) / (t[g + d - r + 1] - t[g]);
            for a in 0..=d {
                w[i][a] = (1.0 - alpha) * w[i - 1][a] + alpha * w[i][a];
            }
        }
    }
    w[d]
}
