//! Pins as linear equality constraints, solved by a Schur complement on the few
//! constraint rows: with `A` factorised, the KKT system
//!
//! \\[ \begin{pmatrix} A & G^T \\ G & 0 \end{pmatrix}
//! \begin{pmatrix} \Delta x \\ -\mu \end{pmatrix} =
//! \begin{pmatrix} -r \\ c - G x \end{pmatrix} \\]
//!
//! is solved as \\(y = -A^{-1} r\\), \\(Y = A^{-1} G^T\\), \\(S = G Y\\) (3k × 3k for k pins),
//! \\(\mu = S^{-1}(c - G x - G y)\\), \\(\Delta x = y + Y \mu\\): `3k + 1` back-substitutions.
//! A pin sliding along an axis holds only the directions of its projector `P`: its rows
//! are \\(P G_p\\), and `S` gains \\(I - P\\) on its block so that it stays definite (the
//! multiplier's component along the axis is then zero).

use crate::linear::LinearSolver;
use crate::point_pins::PointPins;
use crate::IntegratorError;
use nalgebra::{Matrix3, Vector3};
use splinerod_core::{BasisValues, BlockBanded, Pin, Real, Rod};

/// Constraint rows of the pins and the Schur complement workspace.
#[derive(Debug, Default)]
pub(crate) struct Constraints {
    rows: Vec<BasisValues>,
    /// Per pin, the projector onto the directions it holds.
    projectors: Vec<Matrix3<Real>>,
    /// Constraint right-hand sides `c`, one 3-vector per pin.
    pub targets: Vec<Vector3<Real>>,
    /// `Y = A⁻¹ Gᵀ`, 3k columns of length 3n, column-major.
    y: Vec<Real>,
    /// Cholesky factor of `S`, 3k × 3k row-major.
    schur: Vec<Real>,
    /// Scratch for the multipliers, 3k.
    sol: Vec<Real>,
    /// The normal equations of [`Constraints::multipliers_of`], 3k × 3k row-major.
    normal: Vec<Real>,
    /// Pins handled by the Schur complement (the others are eliminated).
    general: Vec<usize>,
    /// Pins eliminated from the system.
    pub points: PointPins,
    /// Scratch: the Schur pins' \(G^T\mu\) at each eliminated control point.
    others: Vec<Vector3<Real>>,
    n: usize,
    /// What `rows` were evaluated for: the rod's topology epoch and each pin's
    /// material coordinate (bits) and tangent flag.
    rows_for: Option<u64>,
    row_pins: Vec<(u64, bool)>,
    /// Pins held by rigid bodies: never eliminated nor augmented, with the bodies'
    /// compliance and gap offsets ([`crate::newton`]'s body coupling).
    coupling: Coupling,
}

/// The rigid bodies' part of the Schur complement: which pins they hold, the
/// compliance blocks \(J B^{-1} J^T\) between them and the gap offsets
/// \(J B^{-1} r_b\).
#[derive(Debug, Default)]
struct Coupling {
    held: Vec<usize>,
    blocks: Vec<(usize, usize, Matrix3<Real>)>,
    offsets: Vec<(usize, Vector3<Real>)>,
}

impl Constraints {
    /// Evaluates the pins' rows on the rod's current basis (kept from the last call
    /// while the basis and the pins' material coordinates are the same: a row depends on
    /// nothing else), and their projectors.
    pub fn setup(&mut self, rod: &Rod, pins: &[Pin]) -> Result<(), IntegratorError> {
        let same = self.rows_for == Some(rod.topology_epoch())
            && self.row_pins.len() == pins.len()
            && pins
                .iter()
                .zip(&self.row_pins)
                .all(|(p, &(at, tangent))| p.at.to_bits() == at && p.tangent == tangent);
        if same {
            for pin in pins {
                pin.check_position()?;
            }
        } else {
            self.rows_for = None;
            self.rows.clear();
            for pin in pins {
                self.rows.push(pin.row(rod)?);
            }
            self.row_pins.clear();
            self.row_pins
                .extend(pins.iter().map(|p| (p.at.to_bits(), p.tangent)));
            self.rows_for = Some(rod.topology_epoch());
        }
        self.projectors.clear();
        self.projectors.extend(pins.iter().map(Pin::projector));
        self.targets.resize(pins.len(), Vector3::zeros());
        self.n = rod.len();
        // A closed rod's copies across the seam are one unknown: eliminating one of them
        // alone would split it, so its pins all go through the Schur complement.
        match rod.is_closed() {
            false => self
                .points
                .setup(&self.rows, &self.projectors, &self.coupling.held)?,
            true => self.points.setup(&[], &[], &[])?,
        }
        self.general.clear();
        self.general
            .extend((0..pins.len()).filter(|&p| !self.points.contains(p)));
        Ok(())
    }

    /// Declares the pins rigid bodies hold (before [`Self::setup`]); empty: none.
    pub fn set_held(&mut self, held: impl Iterator<Item = usize>) {
        self.coupling.held.clear();
        self.coupling.held.extend(held);
        self.coupling.blocks.clear();
        self.coupling.offsets.clear();
    }

    /// The bodies' compliance blocks `(p, q, C_pq)` and gap offsets `(p, d_p)` for the
    /// next factorisation and solve.
    pub fn set_coupling(
        &mut self,
        blocks: impl Iterator<Item = (usize, usize, Matrix3<Real>)>,
        offsets: impl Iterator<Item = (usize, Vector3<Real>)>,
    ) {
        self.coupling.blocks.clear();
        self.coupling.blocks.extend(blocks);
        self.coupling.offsets.clear();
        self.coupling.offsets.extend(offsets);
    }

    /// Number of pins.
    pub fn len(&self) -> usize {
        self.rows.len()
    }

    /// The pins' rows.
    pub fn rows(&self) -> &[BasisValues] {
        &self.rows
    }

    /// `G x` for pin `p`.
    pub fn apply_row(&self, p: usize, x: &[Vector3<Real>]) -> Vector3<Real> {
        let b = &self.rows[p];
        b.combine(&b.value, x)
    }

    /// The held part of pin `p`'s violation, \\(P(c - G x)\\).
    pub fn gap(&self, p: usize, x: &[Vector3<Real>]) -> Vector3<Real> {
        self.projectors[p] * (self.targets[p] - self.apply_row(p, x))
    }

    /// `out += scale · Gᵀ μ`.
    pub fn add_transpose(&self, mu: &[Vector3<Real>], scale: Real, out: &mut [Vector3<Real>]) {
        for (b, m) in self.rows.iter().zip(mu) {
            for k in 0..b.order {
                out[b.first + k] += m * (scale * b.value[k]);
            }
        }
    }

    /// Adds the augmented Lagrangian term `ρ GᵀG` to `a` (within the band when it is at
    /// least `d` wide, since a pin's row spans `d + 1` consecutive control points; as far
    /// blocks otherwise).
    pub fn add_gram(&self, rho: Real, a: &mut BlockBanded) {
        if rho == 0.0 {
            return;
        }
        for (p, (b, proj)) in self.rows.iter().zip(&self.projectors).enumerate() {
            if self.coupling.held.contains(&p) {
                continue;
            }
            for i in 0..b.order {
                for j in i..b.order {
                    let w = rho * b.value[i] * b.value[j];
                    a.add_coupling(b.first + i, b.first + j, &(proj * w));
                }
            }
        }
    }

    /// `out += ρ Gᵀ (c − G x)`, the right-hand side matching [`add_gram`](Self::add_gram).
    pub fn add_gram_rhs(&self, rho: Real, x: &[Vector3<Real>], out: &mut [Vector3<Real>]) {
        if rho == 0.0 {
            return;
        }
        for (p, b) in self.rows.iter().enumerate() {
            if self.coupling.held.contains(&p) {
                continue;
            }
            let e = self.projectors[p] * (self.targets[p] - self.apply_row(p, x)) * rho;
            for k in 0..b.order {
                out[b.first + k] += e * b.value[k];
            }
        }
    }

    /// Computes `Y = A⁻¹ Gᵀ` and factorises `S = G Y` for the pins not eliminated.
    pub fn factor(&mut self, solver: &mut LinearSolver) -> Result<(), IntegratorError> {
        let (m, dofs) = (3 * self.general.len(), 3 * self.n);
        if m == 0 {
            return Ok(());
        }
        self.y.clear();
        self.y.resize(m * dofs, 0.0);
        for (g, &p) in self.general.iter().enumerate() {
            let (b, proj) = (&self.rows[p], &self.projectors[p]);
            for a in 0..3 {
                let col = &mut self.y[(3 * g + a) * dofs..(3 * g + a + 1) * dofs];
                for k in 0..b.order {
                    // At a point an eliminated pin holds, only its free directions remain.
                    let free = self.points.free_directions(b.first + k);
                    let column = free * proj.column(a) * b.value[k];
                    col[3 * (b.first + k)..3 * (b.first + k) + 3]
                        .copy_from_slice(column.as_slice());
                }
            }
        }
        solver.solve_in_place(&mut self.y)?;
        self.schur.clear();
        self.schur.resize(m * m, 0.0);
        for i in 0..m {
            for j in 0..m {
                self.schur[i * m + j] = self.row_dot(i, &self.y[j * dofs..(j + 1) * dofs]);
            }
        }
        for (g, &p) in self.general.iter().enumerate() {
            let free = Matrix3::identity() - self.projectors[p];
            for a in 0..3 {
                for c in 0..3 {
                    self.schur[(3 * g + a) * m + 3 * g + c] += free[(a, c)];
                }
            }
        }
        for (p, q, block) in &self.coupling.blocks {
            let at = |p| self.general.iter().position(|&g| g == p);
            let (Some(gp), Some(gq)) = (at(*p), at(*q)) else {
                return Err(IntegratorError::SolverState(
                    "a body's pin is not in the Schur complement",
                ));
            };
            for a in 0..3 {
                for c in 0..3 {
                    self.schur[(3 * gp + a) * m + 3 * gq + c] += block[(a, c)];
                }
            }
        }
        dense_cholesky(&mut self.schur, m).map_err(|_| IntegratorError::RedundantPins)
    }

    /// Row `i` of the Schur pins' `PG` (pin `general[i / 3]`, coordinate `i % 3`) dotted
    /// with a flat vector.
    fn row_dot(&self, i: usize, flat: &[Real]) -> Real {
        let p = self.general[i / 3];
        let (b, proj, a) = (&self.rows[p], &self.projectors[p], i % 3);
        (0..b.order)
            .map(|k| {
                let at = 3 * (b.first + k);
                let v = Vector3::new(flat[at], flat[at + 1], flat[at + 2]);
                b.value[k] * proj.row(a).transpose().dot(&v)
            })
            .sum()
    }

    /// Given `flat = A⁻¹ b` (with the eliminated pins' steps in place) and the current
    /// iterate `x`, turns `flat` into `Δx` and writes every pin's multiplier `μ`.
    pub fn correct(&mut self, x: &[Vector3<Real>], flat: &mut [Real], mu: &mut [Vector3<Real>]) {
        self.correct_for(x, flat, mu, true);
    }

    /// The eliminated pins' multipliers again, after [`Self::correct`], from the final
    /// step `flat` (changed since by the remainder's correction) and `rest`, per control
    /// point the row's part besides the banded product: \\(r - a + sR\,\Delta x\\)
    /// for the residual `r`, the augmentation's right-hand side `a` and the remainder's
    /// product (the banded rows leave it out). The other pins' multipliers are kept.
    pub fn remainder_multipliers(
        &self,
        flat: &[Real],
        rest: &[Vector3<Real>],
        mu: &mut [Vector3<Real>],
    ) {
        let rest = |_: usize, k: usize| rest[k];
        self.points.multipliers_from(flat, &self.others, rest, mu);
    }

    /// Whether some pins go through the Schur complement (not at a control point).
    pub fn has_schur_pins(&self) -> bool {
        !self.general.is_empty()
    }

    /// Every pin's multiplier from \\(w = G^T\mu\\) (`r + A Δx` of a solved step, `A`
    /// the whole matrix): the normal equations
    /// \\((PG\,G^TP + I - P)\,\mu = PG\,w\\), 3k unknowns, solved densely.
    pub fn multipliers_of(
        &mut self,
        w: &[Vector3<Real>],
        mu: &mut [Vector3<Real>],
    ) -> Result<(), IntegratorError> {
        let m = 3 * self.rows.len();
        self.normal.clear();
        self.normal.resize(m * m, 0.0);
        for (p, a) in self.rows.iter().enumerate() {
            for (q, b) in self.rows.iter().enumerate() {
                let dot: Real = (0..a.order)
                    .filter_map(|i| {
                        let j = (a.first + i).checked_sub(b.first)?;
                        (j < b.order).then(|| a.value[i] * b.value[j])
                    })
                    .sum();
                let mut block = self.projectors[p] * self.projectors[q] * dot;
                if p == q {
                    block += Matrix3::identity() - self.projectors[p];
                }
                for (r, c) in (0..3).flat_map(|r| (0..3).map(move |c| (r, c))) {
                    self.normal[(3 * p + r) * m + 3 * q + c] = block[(r, c)];
                }
            }
        }
        self.sol.clear();
        for (b, proj) in self.rows.iter().zip(&self.projectors) {
            let g = proj * b.combine(&b.value, w);
            self.sol.extend(g.iter().copied());
        }
        dense_cholesky(&mut self.normal, m)
            .map_err(|()| IntegratorError::SolverState("the pins' rows are dependent"))?;
        dense_cholesky_solve(&self.normal, m, &mut self.sol);
        for (p, mu) in mu.iter_mut().enumerate().take(self.rows.len()) {
            *mu = Vector3::new(self.sol[3 * p], self.sol[3 * p + 1], self.sol[3 * p + 2]);
        }
        Ok(())
    }

    /// Solves the KKT system with homogeneous constraints, `G Δx = 0`: `flat` holds the
    /// right-hand side on entry and the step on return; `mu` is scratch (the Schur pins'
    /// multipliers land there, the point pins' are not computed: no caller reads them).
    pub fn solve_homogeneous(
        &mut self,
        solver: &mut LinearSolver,
        x: &[Vector3<Real>],
        flat: &mut [Real],
        mu: &mut [Vector3<Real>],
    ) -> Result<(), IntegratorError> {
        self.points.eliminate_rhs(x, None, flat);
        solver.solve_in_place(flat)?;
        self.correct_for(x, flat, mu, false);
        Ok(())
    }

    /// [`Self::correct`], for the pins' targets or (`targets` false: the homogeneous
    /// solve) zero gaps and no point-pin multipliers.
    fn correct_for(
        &mut self,
        x: &[Vector3<Real>],
        flat: &mut [Real],
        mu: &mut [Vector3<Real>],
        targets: bool,
    ) {
        let (m, dofs) = (3 * self.general.len(), 3 * self.n);
        self.sol.clear();
        for &p in &self.general {
            let gap = if targets {
                let offset = self.coupling.offsets.iter().find(|(q, _)| *q == p);
                let offset = offset.map_or(Vector3::zeros(), |(_, d)| *d);
                self.projectors[p] * (self.targets[p] - self.apply_row(p, x)) - offset
            } else {
                Vector3::zeros()
            };
            self.sol.extend(gap.iter().copied());
        }
        for i in 0..m {
            self.sol[i] -= self.row_dot(i, flat);
        }
        dense_cholesky_solve(&self.schur, m, &mut self.sol);
        for (g, &p) in self.general.iter().enumerate() {
            mu[p] = Vector3::new(self.sol[3 * g], self.sol[3 * g + 1], self.sol[3 * g + 2]);
        }
        for (j, s) in self.sol.iter().enumerate() {
            let col = &self.y[j * dofs..(j + 1) * dofs];
            flat.iter_mut().zip(col).for_each(|(f, c)| *f += s * c);
        }
        if !targets {
            return;
        }
        self.others.clear();
        for k in self.points.control_points() {
            let mut sum = Vector3::zeros();
            for &p in &self.general {
                let b = &self.rows[p];
                if let Some(i) = k.checked_sub(b.first).filter(|&i| i < b.order) {
                    sum += mu[p] * b.value[i];
                }
            }
            self.others.push(sum);
        }
        self.points.multipliers(flat, &self.others, mu);
    }
}

/// In-place lower Cholesky of a row-major `m × m` SPD matrix; fails on a pivot that is
/// not positive relative to the diagonal's scale (linearly dependent rows).
fn dense_cholesky(a: &mut [Real], m: usize) -> Result<(), ()> {
    let scale = (0..m).map(|i| a[i * m + i].abs()).fold(0.0, Real::max);
    for j in 0..m {
        let mut d = a[j * m + j];
        for k in 0..j {
            d -= a[j * m + k] * a[j * m + k];
        }
        if d.is_nan() || d <= 1e-12 * scale {
            return Err(());
        }
        let d = d.sqrt();
        a[j * m + j] = d;
        for i in j + 1..m {
            let mut s = a[i * m + j];
            for k in 0..j {
                s -= a[i * m + k] * a[j * m + k];
            }
            a[i * m + j] = s / d;
        }
    }
    Ok(())
}

/// Solves `L Lᵀ x = b` in place with the factor from [`dense_cholesky`].
fn dense_cholesky_solve(l: &[Real], m: usize, b: &mut [Real]) {
    for i in 0..m {
        let s: Real = (0..i).map(|k| l[i * m + k] * b[k]).sum();
        b[i] = (b[i] - s) / l[i * m + i];
    }
    for i in (0..m).rev() {
        let s: Real = (i + 1..m).map(|k| l[k * m + i] * b[k]).sum();
        b[i] = (b[i] - s) / l[i * m + i];
    }
}
