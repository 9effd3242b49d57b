//! The start-state fingerprint a preloaded batched step is recognised by.

use nalgebra::Vector3;
use splinerod_core::Real;

/// A 64-bit fingerprint of a state (every bit of every coordinate, FNV-1a style):
/// what a preloaded step ([`crate::Integrator::preload`]) recognises its start by,
/// without a copy of it to write. Each coordinate feeds its own chain (x, y, z of the
/// positions, then of the velocities), so that the chains' multiplications overlap;
/// they are folded together with the lengths at the end.
pub fn fingerprint(positions: &[Vector3<Real>], velocities: &[Vector3<Real>]) -> u64 {
    const PRIME: u64 = 0x0000_0100_0000_01b3;
    let mut chains = [0xcbf2_9ce4_8422_2325_u64; 6];
    for (field, chains) in [positions, velocities]
        .iter()
        .zip(chains.chunks_exact_mut(3))
    {
        for p in field.iter() {
            for (h, x) in chains.iter_mut().zip(p.iter()) {
                *h = (*h ^ x.to_bits()).wrapping_mul(PRIME);
            }
        }
    }
    let lengths = (positions.len() as u64) << 32 | velocities.len() as u64;
    chains
        .iter()
        .fold(lengths, |h, &c| (h ^ c).wrapping_mul(PRIME))
}
