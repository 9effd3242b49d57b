//! Run state as plain numbers, for checkpoints.
//!
//! What an extension (an energy, an integrator) keeps from one step to the next and
//! cannot recompute from the rod — an integrator's history, multipliers, a transported
//! frame, a neighbour list whose rounding the results depend on — it writes into a
//! [`SavedState`] as reals and integers, and reads back, in the same order, through a
//! [`StateReader`] on a freshly built copy of itself. Reading past the end, or leaving
//! numbers unread, is an error ([`CoreError::StateMismatch`]): the checkpoint was not
//! written by the same kind of object.

use crate::{CoreError, Real};
use nalgebra::Vector3;

/// Numbers an object saved (see the module docs).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct SavedState {
    /// Reals, in the order written.
    pub reals: Vec<Real>,
    /// Integers, in the order written.
    pub ints: Vec<u64>,
}

impl SavedState {
    /// Appends a real.
    pub fn real(&mut self, x: Real) {
        self.reals.push(x);
    }

    /// Appends a length and the reals.
    pub fn reals(&mut self, xs: &[Real]) {
        self.int(xs.len() as u64);
        self.reals.extend_from_slice(xs);
    }

    /// Appends a length and the vectors' components.
    pub fn vectors(&mut self, vs: &[Vector3<Real>]) {
        self.int(vs.len() as u64);
        self.reals.extend(vs.iter().flat_map(|v| [v.x, v.y, v.z]));
    }

    /// Appends an integer.
    pub fn int(&mut self, i: u64) {
        self.ints.push(i);
    }

    /// Appends a length and the integers.
    pub fn ints(&mut self, is: impl ExactSizeIterator<Item = u64>) {
        self.int(is.len() as u64);
        self.ints.extend(is);
    }

    /// A reader from the start.
    pub fn reader(&self) -> StateReader<'_> {
        StateReader {
            state: self,
            real: 0,
            int: 0,
        }
    }
}

/// Reads a [`SavedState`] back in the order it was written.
#[derive(Debug, Clone)]
pub struct StateReader<'a> {
    state: &'a SavedState,
    real: usize,
    int: usize,
}

fn mismatch(what: &'static str) -> CoreError {
    CoreError::StateMismatch(what)
}

impl StateReader<'_> {
    /// The next real.
    pub fn real(&mut self) -> Result<Real, CoreError> {
        let x = *self
            .state
            .reals
            .get(self.real)
            .ok_or(mismatch("too few reals"))?;
        self.real += 1;
        Ok(x)
    }

    /// The next integer.
    pub fn int(&mut self) -> Result<u64, CoreError> {
        let i = *self
            .state
            .ints
            .get(self.int)
            .ok_or(mismatch("too few integers"))?;
        self.int += 1;
        Ok(i)
    }

    /// The next integer as an index or count.
    pub fn index(&mut self) -> Result<usize, CoreError> {
        usize::try_from(self.int()?).map_err(|_| mismatch("an integer out of range"))
    }

    fn length(&mut self, per_item: usize, available: usize) -> Result<usize, CoreError> {
        let n = self.index()?;
        match n.checked_mul(per_item) {
            Some(total) if total <= available => Ok(n),
            _ => Err(mismatch("a length past the end")),
        }
    }

    /// A length and as many reals, into `out` (cleared first).
    pub fn reals_into(&mut self, out: &mut Vec<Real>) -> Result<(), CoreError> {
        let left = self.state.reals.len() - self.real;
        let n = self.length(1, left)?;
        out.clear();
        out.extend_from_slice(&self.state.reals[self.real..self.real + n]);
        self.real += n;
        Ok(())
    }

    /// A length and as many vectors, into `out` (cleared first).
    pub fn vectors_into(&mut self, out: &mut Vec<Vector3<Real>>) -> Result<(), CoreError> {
        let left = self.state.reals.len() - self.real;
        let n = self.length(3, left)?;
        let xs = &self.state.reals[self.real..self.real + 3 * n];
        out.clear();
        out.extend(xs.chunks_exact(3).map(|c| Vector3::new(c[0], c[1], c[2])));
        self.real += 3 * n;
        Ok(())
    }

    /// A length and as many integers.
    pub fn ints(&mut self) -> Result<&[u64], CoreError> {
        let left = self.state.ints.len() - self.int;
        let n = self.length(1, left)?;
        let is = &self.state.ints[self.int..self.int + n];
        self.int += n;
        Ok(is)
    }

    /// An error unless every number was read.
    pub fn finish(&self) -> Result<(), CoreError> {
        if self.real == self.state.reals.len() && self.int == self.state.ints.len() {
            Ok(())
        } else {
            Err(mismatch("numbers left over"))
        }
    }
}
