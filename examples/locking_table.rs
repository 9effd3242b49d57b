//! Static catenary error against the exact elastic catenary at growing EA, for both
//! stretching formulations (`cargo run --release --example locking_table`): the
//! membrane-locking study of #12.
use splinerod::locking::{peer_error, study, RESOLUTIONS};
use splinerod::StretchFormulation;

fn main() {
    for (name, formulation) in [
        ("pointwise (paper eq. 12)", StretchFormulation::Pointwise),
        ("mixed (default)", StretchFormulation::Mixed),
        (
            "mixed, consistent Gram",
            StretchFormulation::MixedConsistent,
        ),
    ] {
        println!("{name}\nEA (N)    16 points    32 points    64 points");
        for row in study(formulation) {
            let cells: Vec<String> = row
                .errors
                .iter()
                .map(|e| e.map_or("fails".into(), |e| format!("{e:.2e}")))
                .collect();
            println!("{:.0e}      {}", row.stiffness, cells.join("     "));
        }
    }
    let peers: Vec<String> = RESOLUTIONS
        .iter()
        .map(|&n| format!("{:.2e}", peer_error(n)))
        .collect();
    println!("lumped-chain peers (any EA): {}", peers.join("     "));
}
