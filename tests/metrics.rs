//! FATS and diagnostics on hand-computed cases — regimes, renormalised weights for an
//! empty regime, early termination, zero force, re-anchoring — and the property that the
//! order of episodes never changes any aggregate.

use nalgebra::{Isometry3, Point3, Vector3};
use thorarena::eval::metrics::{
    aggregate, keypoint_error_m, percentile, reanchor, score_episode, EpisodeSeries,
    RegimeThresholds, SIGMA_M,
};

fn series(errors: &[f64], forces: &[f64], steps_ref: usize) -> EpisodeSeries {
    EpisodeSeries {
        kp_err_m: errors.to_vec(),
        kp_err_upper_m: errors.iter().map(|e| e * 0.5).collect(),
        kp_err_lower_m: errors.iter().map(|e| e * 1.5).collect(),
        total_force_n: forces.to_vec(),
        power_w: forces.iter().map(|f| 100.0 + f).collect(),
        root_drift_m: vec![0.1; errors.len()],
        kp_err_global_m: errors.iter().map(|e| e * 2.0).collect(),
        steps_ref,
    }
}

const TH: RegimeThresholds = RegimeThresholds {
    p33_n: 10.0,
    p66_n: 20.0,
};

#[test]
fn percentiles_interpolate_between_ranks_like_numpy() {
    assert!((percentile(&[1.0, 2.0, 3.0, 4.0], 33.0) - 1.99).abs() < 1e-12);
    assert!((percentile(&[1.0, 2.0, 3.0, 4.0], 66.0) - 2.98).abs() < 1e-12);
    let th = RegimeThresholds::from_forces(&[4.0, 1.0, 3.0, 2.0]);
    assert!((th.p33_n - 1.99).abs() < 1e-12 && (th.p66_n - 2.98).abs() < 1e-12);
}

#[test]
fn score_combines_regime_errors_with_the_paper_weights() {
    let s = score_episode(
        &series(
            &[0.01, 0.01, 0.02, 0.02, 0.04, 0.04],
            &[0.0, 10.0, 15.0, 20.0, 30.0, 21.0],
            6,
        ),
        &TH,
    );
    assert_eq!(s.regime_rmse_m, [Some(0.01), Some(0.02), Some(0.04)]);
    let e: f64 = (0.2 * 1e-4 + 0.3 * 4e-4 + 0.5 * 16e-4f64).sqrt();
    assert!((s.error_m.unwrap() - e).abs() < 1e-15);
    assert_eq!(s.survival, 1.0);
    assert!((s.score - 100.0 * (-e / SIGMA_M).exp()).abs() < 1e-12);
    assert_eq!(s.regime_power_w, [Some(105.0), Some(117.5), Some(125.5)]);
}

#[test]
fn an_empty_regime_renormalises_the_weights() {
    let s = score_episode(&series(&[0.01, 0.02], &[5.0, 15.0], 2), &TH);
    assert_eq!(s.regime_rmse_m[2], None);
    let e = ((0.2 * 1e-4 + 0.3 * 4e-4) / 0.5f64).sqrt();
    assert!((s.error_m.unwrap() - e).abs() < 1e-15);
}

#[test]
fn early_termination_scales_the_score_by_survival() {
    let full = score_episode(&series(&[0.03; 10], &[0.0; 10], 10), &TH);
    let half = score_episode(&series(&[0.03; 5], &[0.0; 5], 10), &TH);
    assert_eq!(half.survival, 0.5);
    assert!((half.score - full.score / 2.0).abs() < 1e-12);
    let none = score_episode(&series(&[], &[], 10), &TH);
    assert_eq!((none.error_m, none.survival, none.score), (None, 0.0, 0.0));
}

#[test]
fn zero_force_puts_every_step_in_the_low_regime() {
    let th = RegimeThresholds::from_forces(&[0.0; 20]);
    let s = score_episode(&series(&[0.02; 20], &[0.0; 20], 20), &th);
    assert_eq!(s.regime_rmse_m, [Some(0.02), None, None]);
    assert!((s.error_m.unwrap() - 0.02).abs() < 1e-15);
}

#[test]
fn reanchoring_removes_root_drift_and_heading_from_the_error() {
    let ref_root = Isometry3::new(Vector3::new(1.0, 2.0, 0.8), Vector3::new(0.0, 0.0, 0.3));
    let robot_root = Isometry3::new(Vector3::new(-0.5, 0.7, 0.75), Vector3::new(0.05, 0.0, -1.2));
    let local = [Point3::new(0.1, 0.2, 0.3), Point3::new(-0.2, 0.1, -0.6)];
    let ref_w: Vec<Point3<f64>> = local.iter().map(|p| ref_root * p).collect();
    let robot_w: Vec<Point3<f64>> = local.iter().map(|p| robot_root * p).collect();
    let mut anchored = Vec::new();
    reanchor(&ref_w, &ref_root, &robot_root, &mut anchored);
    assert!(keypoint_error_m(&anchored, &robot_w) < 1e-12);
    // A 3 cm offset of one of two keypoints: mean error 1.5 cm.
    let mut moved = robot_w.clone();
    moved[1].x += 0.03;
    assert!((keypoint_error_m(&anchored, &moved) - 0.015).abs() < 1e-12);
}

fn episodes() -> Vec<(String, String, EpisodeSeries)> {
    let mut out = Vec::new();
    for (t, task) in ["push_chair", "clean_table", "syn_carry"]
        .iter()
        .enumerate()
    {
        for i in 0..7 {
            let n = 20 + 3 * i;
            let errors: Vec<f64> = (0..n)
                .map(|k| 0.01 + 0.001 * ((k * 7 + i * 3 + t) % 11) as f64)
                .collect();
            let forces: Vec<f64> = (0..n).map(|k| ((k * 13 + i + t * 5) % 31) as f64).collect();
            out.push((
                task.to_string(),
                format!("{task}_{i:03}"),
                series(&errors, &forces, 30),
            ));
        }
    }
    out
}

#[test]
fn permuting_episodes_leaves_every_aggregate_unchanged() {
    let th = |_: &str| RegimeThresholds {
        p33_n: 9.0,
        p66_n: 21.0,
    };
    let base = episodes();
    let (scores, tasks, overall) = aggregate(&base, &th);
    assert_eq!(tasks.len(), 3);
    assert!(overall.fats > 0.0 && overall.robustness.is_finite() && overall.power_overhead > 1.0);
    let mut state = 0x2545_f491_4f6c_dd1du64;
    for _ in 0..20 {
        let mut perm = base.clone();
        for i in (1..perm.len()).rev() {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            perm.swap(i, (state % (i as u64 + 1)) as usize);
        }
        let (s2, t2, o2) = aggregate(&perm, &th);
        assert_eq!(
            format!("{scores:?}{tasks:?}{overall:?}"),
            format!("{s2:?}{t2:?}{o2:?}")
        );
    }
}

#[test]
fn fats_std_is_the_population_std_of_episode_scores_within_a_task() {
    let th = |_: &str| TH;
    let eps = vec![
        (
            "a".to_string(),
            "1".to_string(),
            series(&[0.0; 4], &[0.0; 4], 4),
        ),
        (
            "a".to_string(),
            "2".to_string(),
            series(&[0.0; 2], &[0.0; 2], 4),
        ),
    ];
    let (_, tasks, overall) = aggregate(&eps, &th);
    // Scores 100 and 50: mean 75, population std 25.
    assert!((tasks[0].diagnostics.fats - 75.0).abs() < 1e-12);
    assert!((tasks[0].diagnostics.fats_std - 25.0).abs() < 1e-12);
    assert!(
        overall.high_kp_mm.is_nan(),
        "no high-force step anywhere: undefined, not zero"
    );
}

#[test]
fn a_task_of_one_episode_has_no_fats_spread() {
    let th = |_: &str| TH;
    let eps = vec![
        (
            "a".to_string(),
            "1".to_string(),
            series(&[0.0; 4], &[0.0; 4], 4),
        ),
        (
            "b".to_string(),
            "1".to_string(),
            series(&[0.0; 4], &[0.0; 4], 4),
        ),
        (
            "b".to_string(),
            "2".to_string(),
            series(&[0.0; 2], &[0.0; 2], 4),
        ),
    ];
    let (_, tasks, overall) = aggregate(&eps, &th);
    assert!(
        tasks[0].diagnostics.fats_std.is_nan(),
        "one score: undefined, not 0"
    );
    assert!((tasks[1].diagnostics.fats_std - 25.0).abs() < 1e-12);
    // The average over tasks is over those where it is defined.
    assert!((overall.fats_std - 25.0).abs() < 1e-12);
}

#[test]
fn the_global_keypoint_error_is_pooled_like_the_others_and_undefined_when_not_recorded() {
    let th = |_: &str| TH;
    // Global errors 2× the re-anchored ones (`series`): RMS over the pooled steps.
    let eps = vec![
        (
            "a".to_string(),
            "1".to_string(),
            series(&[0.01; 4], &[0.0; 4], 4),
        ),
        (
            "a".to_string(),
            "2".to_string(),
            series(&[0.02; 2], &[0.0; 2], 4),
        ),
    ];
    let (_, tasks, overall) = aggregate(&eps, &th);
    let rms = ((4.0 * 0.02f64.powi(2) + 2.0 * 0.04f64.powi(2)) / 6.0).sqrt() * 1e3;
    assert!((tasks[0].diagnostics.global_kp_mm - rms).abs() < 1e-9);
    assert!((tasks[0].diagnostics.global_kp_mm - 2.0 * tasks[0].diagnostics.kp_mm).abs() < 1e-9);
    assert_eq!(overall.global_kp_mm, tasks[0].diagnostics.global_kp_mm);
    // A record written before the global error was recorded has none: undefined, not 0.
    let mut old = eps.clone();
    for e in &mut old {
        e.2.kp_err_global_m.clear();
    }
    let (_, tasks, _) = aggregate(&old, &th);
    assert!(tasks[0].diagnostics.global_kp_mm.is_nan());
}
