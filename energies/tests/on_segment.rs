//! `OnSegment`: energies of the rods of a joined rod equal the same energies on the rods
//! alone — energy, gradient and Hessian placed at the rod's control points — before and
//! after knot changes inside one rod.
mod common;

use common::part;
use nalgebra::Vector3;
use splinerod_core::{BlockBanded, HessianKind, Real, Rod};
use splinerod_energies::{Bending, Energy, Frame, OnSegment, Stretching, Twisting};

/// One energy per part (different kinds and stiffnesses), built for a rod of its own.
fn part_energies(k: usize, rod: &Rod) -> Vec<Box<dyn Energy>> {
    match k {
        0 => vec![
            Box::new(Stretching::new(50.0).expect("stretch")),
            Box::new(Bending::new(0.01).expect("bend")),
        ],
        1 => vec![Box::new(Stretching::new(400.0).expect("stretch"))],
        _ => vec![
            Box::new(Bending::new(0.3).expect("bend")),
            Box::new(twisting(rod)),
        ],
    }
}

/// Twisting between frames at the ends that differ from the transported one.
fn twisting(rod: &Rod) -> Twisting {
    let l = rod.material().rest_length;
    let axis = |s| rod.tangent(s).expect("tangent");
    let start = Frame::new(axis(0.0), Vector3::z()).expect("frame");
    let end = Frame::new(axis(l), Vector3::new(0.0, 1.0, 1.0)).expect("frame");
    Twisting::new(0.02, rod, start, end).expect("twist")
}

fn wrapped(joined: &Rod) -> Vec<Box<dyn Energy>> {
    let mut out: Vec<Box<dyn Energy>> = Vec::new();
    for k in 0..joined.segments().len() {
        let p = joined.segment_rod(k).expect("segment");
        for e in part_energies(k, &p) {
            out.push(Box::new(OnSegment::new(joined, k, e).expect("wrap")));
        }
    }
    out
}

/// Each part as a rod of its own with its energies: what the wrappers must reproduce.
struct Direct {
    rods: Vec<Rod>,
    energies: Vec<Vec<Box<dyn Energy>>>,
}

impl Direct {
    fn new(joined: &Rod) -> Self {
        let rods: Vec<Rod> = (0..joined.segments().len())
            .map(|k| joined.segment_rod(k).expect("segment"))
            .collect();
        let energies = rods
            .iter()
            .enumerate()
            .map(|(k, p)| part_energies(k, p))
            .collect();
        Self { rods, energies }
    }

    /// Replays on part `k` the insertion (or removal) of `value` (local coordinate).
    fn replay(&mut self, k: usize, value: Real, insert: bool) {
        let rod = &mut self.rods[k];
        let map = if insert {
            rod.insert_knot(value).expect("insert")
        } else {
            let index = rod.basis().knots().partition_point(|&t| t < value);
            rod.remove_knot(index, 1.0).expect("remove")
        };
        self.energies[k]
            .iter_mut()
            .filter_map(|e| e.lifecycle_mut())
            .for_each(|l| l.on_knot_change(rod, &map));
    }
}

fn compare(joined: &Rod, whole: &[Box<dyn Energy>], direct: &Direct) {
    let n = joined.len();
    let (mut g, mut h) = (vec![Vector3::zeros(); n], BlockBanded::zeros(n, 3));
    let mut e = 0.0;
    for w in whole {
        e += w.energy(joined);
        w.add_gradient(joined, &mut g);
        w.add_hessian(joined, HessianKind::Exact, &mut h);
    }
    let mut e_parts = 0.0;
    for (k, (p, energies)) in direct.rods.iter().zip(&direct.energies).enumerate() {
        let first = joined.segment_points(k).start;
        let (mut gp, mut hp) = (
            vec![Vector3::zeros(); p.len()],
            BlockBanded::zeros(p.len(), 3),
        );
        for energy in energies {
            e_parts += energy.energy(p);
            energy.add_gradient(p, &mut gp);
            energy.add_hessian(p, HessianKind::Exact, &mut hp);
        }
        for i in 0..p.len() {
            assert!(
                (g[first + i] - gp[i]).norm() <= 1e-14 * (1.0 + gp[i].norm()),
                "{k} {i}"
            );
        }
        let (dense, dense_p) = (h.to_dense(), hp.to_dense());
        let with_low_rank = |d: &mut nalgebra::DMatrix<Real>, m: &BlockBanded, off: usize| {
            for t in m.low_rank() {
                for (i, ui) in t.vector.iter().enumerate() {
                    for (j, uj) in t.vector.iter().enumerate() {
                        let b = ui * uj.transpose() * t.coefficient;
                        let mut v = d.fixed_view_mut::<3, 3>(3 * (i + off), 3 * (j + off));
                        v += b;
                    }
                }
            }
        };
        let (mut dense, mut dense_p) = (dense, dense_p);
        with_low_rank(&mut dense, &h, 0);
        with_low_rank(&mut dense_p, &hp, 0);
        let block = dense.view((3 * first, 3 * first), (3 * p.len(), 3 * p.len()));
        let scale = dense_p.amax();
        assert!(
            (block - &dense_p).amax() < 1e-10 * scale,
            "Hessian of part {k}"
        );
    }
    assert!((e - e_parts).abs() < 1e-12 * e_parts.abs(), "{e} {e_parts}");
}

#[test]
fn energies_of_joined_rods_are_the_rods_energies() {
    let parts = vec![part(7, 1.0, 0.0), part(9, 0.6, 1.0), part(6, 1.3, -1.0)];
    let mut joined = Rod::join(&parts).expect("join");
    let mut whole = wrapped(&joined);
    let mut direct = Direct::new(&joined);
    // Turn the last rod's twist away from rest, and bend the others further.
    for q in joined.positions.iter_mut().skip(3) {
        q.z += 0.05 * q.x * q.x;
    }
    direct = Direct {
        rods: (0..3)
            .map(|k| {
                let mut r = direct.rods[k].clone();
                r.positions
                    .copy_from_slice(&joined.positions[joined.segment_points(k)]);
                r
            })
            .collect(),
        energies: direct.energies,
    };
    compare(&joined, &whole, &direct);

    // Knot changes inside the middle and last rods, heard by the wrappers and replayed
    // on the parts.
    for (k, local, insert) in [
        (1, 0.37, true),
        (2, 0.5, true),
        (1, 0.05, true),
        (1, 0.37, false),
    ] {
        let start = joined.segments()[k].start;
        let map = if insert {
            joined.insert_knot(start + local).expect("insert")
        } else {
            let index = joined
                .basis()
                .knots()
                .partition_point(|&t| t < start + local);
            joined.remove_knot(index, 1.0).expect("remove")
        };
        whole
            .iter_mut()
            .filter_map(|w| w.lifecycle_mut())
            .for_each(|l| l.on_knot_change(&joined, &map));
        let shifted = (start + local) - start;
        direct.replay(k, shifted, insert);
        for (k, r) in direct.rods.iter_mut().enumerate() {
            r.positions
                .copy_from_slice(&joined.positions[joined.segment_points(k)]);
        }
        compare(&joined, &whole, &direct);
    }
}
