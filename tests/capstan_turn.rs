//! The capstan law at a full turn (`splinerod::problems::capstan`): a rope wound once
//! around a horizontal capsule (wrap 2π, the outgoing strand beside the incoming one, so
//! the rope touches itself), 1 N at one end, the other end's load slowly raised; it
//! slips when the ratio passes e^{2πμ}. At 8 control points (a user's coarse fit of the
//! wrap, overlapping the capsule only because it is coarse) the start is refined and
//! pushed out, not refused (#46), and the rope holds below e^{2πμ} and slides above it.
//! The report measures the threshold per resolution (`splinerod::report::capstan`).
//! Figures: `cargo test --release --test integration capstan_turn:: -- --nocapture`.

use splinerod::problems::capstan::{self, capstan_ratio, Turn};
use splinerod::Scene;

/// The load ratio ramps from 1 at `T0` to 1.5 e^{2πμ} at `T1`.
const T0: f64 = 1.0;
const T1: f64 = 9.0;

/// The load ratio at which the heavy end starts to slide, 64 control points and a
/// penalty contact. Also the smallest clearance ratio and the most rope–rope contact
/// pairs seen.
fn slip_ratio(mu: f64) -> (f64, f64, usize) {
    let turn = Turn {
        mu,
        control_points: 64,
        contact_stiffness: Some(1e5),
        adaptivity: None,
        ratio: vec![[0.0, 1.0], [T0, 1.0], [T1, 1.5 * capstan_ratio(mu)]],
        duration: T1,
    };
    let run = capstan::run(&turn, T0 + 0.2).expect("run");
    let t = run.slip_time.unwrap_or_else(|| panic!("mu {mu}: no slip"));
    (turn.ratio_at(t), run.clearance, run.pairs)
}

/// At μ = 0.3 (for CI's time; every μ: `…_at_every_friction`, ignored).
#[test]
fn a_rope_wound_a_full_turn_slips_at_the_capstan_ratio() {
    slips_at_the_capstan_ratio(&[0.3]);
}

#[test]
#[ignore = "about 15 s; run with --ignored"]
fn a_rope_wound_a_full_turn_slips_at_the_capstan_ratio_at_every_friction() {
    slips_at_the_capstan_ratio(&[0.1, 0.3, 0.5]);
}

fn slips_at_the_capstan_ratio(frictions: &[f64]) {
    for &mu in frictions {
        let threshold = capstan_ratio(mu);
        let (ratio, clearance, pairs) = slip_ratio(mu);
        let error = ratio / threshold - 1.0;
        eprintln!(
            "mu {mu}: slips at ratio {ratio:.4}, capstan e^(2πμ) = {threshold:.4} ({error:+.4}); \
             min clearance {clearance:.3}, up to {pairs} rope–rope contact pairs"
        );
        assert!(clearance >= 0.95, "{clearance}");
        assert!(error.abs() < 0.03, "mu {mu}: {ratio} against {threshold}");
    }
}

/// The full turn as a user would write it at 8 control points: the wrap fitted by
/// least squares, its rest state the start, no contact stiffness (the barrier), the
/// loads `1 N` and `ratio` N held from the start for `duration` s.
fn coarse(mu: f64, ratio: f64, duration: f64) -> Turn {
    Turn {
        mu,
        control_points: 8,
        contact_stiffness: None,
        adaptivity: None,
        ratio: vec![[0.0, ratio]],
        duration,
    }
}

/// Runs the coarse full turn with the load ratio `ratio` for `duration` s: whether the
/// heavy end slid in the last half second, the control points the start was refined
/// to, and the smallest clearance seen.
fn coarse_slides(mu: f64, ratio: f64, duration: f64) -> (bool, usize, f64) {
    let run = capstan::run(&coarse(mu, ratio, duration), duration - 0.5)
        .expect("the coarse start is refined, not refused");
    (run.slip_time.is_some(), run.start_points, run.clearance)
}

/// Over 1 s, slip judged in its second half (for CI's time; over 2.5 s:
/// `…_over_two_and_a_half_seconds`, ignored; both refine to 45 points and agree).
#[test]
fn a_full_turn_fitted_with_eight_control_points_runs_and_holds_below_the_capstan_ratio() {
    eight_points_hold_below_and_slide_above(1.0);
}

#[test]
#[ignore = "about 30 s; run with --ignored"]
fn a_full_turn_fitted_with_eight_control_points_holds_over_two_and_a_half_seconds() {
    eight_points_hold_below_and_slide_above(2.5);
}

fn eight_points_hold_below_and_slide_above(duration: f64) {
    let mu = 0.3;
    let threshold = capstan_ratio(mu);
    let (held_slides, points, held_clearance) = coarse_slides(mu, 0.75 * threshold, duration);
    let (slid, _, slid_clearance) = coarse_slides(mu, 1.33 * threshold, duration);
    eprintln!(
        "8 control points refined to {points}: at 0.75 e^(2πμ) slides {held_slides} (clearance {held_clearance:.3}), at 1.33 e^(2πμ) slides {slid} (clearance {slid_clearance:.3})"
    );
    assert!(points > 8, "the coarse start was not refined");
    assert!(!held_slides, "slides below the capstan ratio");
    assert!(slid, "holds above the capstan ratio");
    assert!(held_clearance.min(slid_clearance) >= 0.95);
}

#[test]
fn a_start_through_the_capsule_is_still_refused_naming_the_field() {
    // The rope laid straight through the capsule: its control polygon overlaps too.
    let text = coarse(0.3, 1.0, 0.1).scene_text().expect("scene text");
    let start = text.find("initial_control_points").expect("points");
    let end = start + text[start..].find('\n').expect("line");
    let straight = format!(
        "{}start = [-0.3, 0.0, 0.0]\nend = [0.6, 0.0, 0.0]{}",
        &text[..start],
        &text[end..]
    )
    .replace("rest_shape = \"initial\"\n", "");
    let error = Scene::from_toml(&straight).and_then(|s| s.build().map(|_| ()));
    let message = format!("{:?}", error.expect_err("refused"));
    assert!(message.contains("rod.radius"), "{message}");
}
