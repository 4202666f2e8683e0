//! Which cells of a run load the robot outside what its policy's family was trained with
//! (`policy::registry::TrainedForces`): judged once, when the run starts and the family is
//! known, and kept in `run.json` (`RunHeader::outside_training`), so that every table made
//! from the run — its own `tables.md`, a merge's, a sweep cell's, the leaderboard — marks
//! the same cells with the same reasons. Shown, never hidden.

use super::Setting;
use crate::policy::registry::TrainedForces;
use crate::sim::motion::check::{task_force_spans, CheckError, HandForceSpan};
use crate::sim::motion::Sequence;
use crate::sim::robot::RobotModel;
use std::collections::BTreeMap;

/// Per setting, per task: what lies outside the training (`61 N horizontal walking, above
/// 40`). A setting or task absent lies inside, or has nothing to judge.
pub type OutsideTraining = BTreeMap<String, BTreeMap<String, String>>;

/// Per task, where the dataset's recorded hand forces point (`data check`'s spans).
pub type TaskForceSpans = BTreeMap<String, HandForceSpan>;

/// Where one setting lies against a family's training.
#[derive(Debug, Clone, PartialEq)]
pub enum SettingOutside {
    /// Inside, or nothing to judge (a force-blind family, `no-force`).
    Inside,
    /// The setting's own load lies outside whatever the task (a disturbance, a push).
    EveryTask(String),
    /// Replayed forces: the tasks whose histories lie outside, with what.
    Tasks(BTreeMap<String, String>),
}

/// Where `setting` lies against `trained`, given the tasks' recorded force `spans` (a
/// replayed setting scales them by its coefficient) and, for a family with a stiffness
/// command, the stiffness the policy ran at (N/m).
pub fn setting_outside(
    trained: &TrainedForces,
    setting: &Setting,
    stiffness_n_per_m: Option<f64>,
    spans: &TaskForceSpans,
) -> SettingOutside {
    let every = |why: Option<Vec<String>>| match why {
        Some(why) if !why.is_empty() => SettingOutside::EveryTask(why.join("; ")),
        _ => SettingOutside::Inside,
    };
    if let Some(d) = &setting.disturbance {
        return every(trained.outside_disturbance(d, stiffness_n_per_m));
    }
    if setting.push_n > 0.0 {
        // A constant push acts from the first step, while every motion still stands.
        return match trained.holds_push(
            setting.push_n,
            f64::INFINITY,
            true,
            stiffness_n_per_m,
            false,
        ) {
            Some(false) => SettingOutside::EveryTask(format!(
                "a constant {} N push on both hands through the whole episode, standing included",
                setting.push_n
            )),
            _ => SettingOutside::Inside,
        };
    }
    if setting.coefficient == 0.0 {
        return SettingOutside::Inside;
    }
    let tasks: BTreeMap<String, String> = spans
        .iter()
        .filter_map(|(task, span)| {
            let why = trained.outside_hand_forces(&span.scaled(setting.coefficient))?;
            (!why.is_empty()).then(|| (task.clone(), why.join("; ")))
        })
        .collect();
    if tasks.is_empty() {
        SettingOutside::Inside
    } else {
        SettingOutside::Tasks(tasks)
    }
}

/// The cells of a run of `sequences` under `settings` outside `trained`: empty for a family
/// with nothing to judge, without measuring anything.
pub fn outside_training(
    trained: &TrainedForces,
    settings: &[Setting],
    stiffness_n_per_m: Option<f64>,
    sequences: &[Sequence],
    robot: &RobotModel,
) -> Result<OutsideTraining, CheckError> {
    if !trained.has_envelope() {
        return Ok(OutsideTraining::new());
    }
    let replays = settings
        .iter()
        .any(|s| s.coefficient != 0.0 && s.disturbance.is_none());
    let spans = if replays {
        task_force_spans(sequences, robot)?
    } else {
        TaskForceSpans::new()
    };
    let mut tasks: Vec<&str> = sequences.iter().map(|q| q.task.as_str()).collect();
    tasks.sort_unstable();
    tasks.dedup();
    let mut out = OutsideTraining::new();
    for s in settings {
        let cells: BTreeMap<String, String> =
            match setting_outside(trained, s, stiffness_n_per_m, &spans) {
                SettingOutside::Inside => continue,
                SettingOutside::EveryTask(why) => {
                    tasks.iter().map(|t| (t.to_string(), why.clone())).collect()
                }
                SettingOutside::Tasks(cells) => cells,
            };
        out.insert(s.name.clone(), cells);
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::policy::registry::{FALCON_FORCES, SOFTMIMIC_FORCES};

    fn replay(name: &str, coefficient: f64) -> Setting {
        Setting {
            name: name.into(),
            coefficient,
            push_n: 0.0,
            push_heading_deg: None,
            disturbance: None,
        }
    }

    fn spans() -> TaskForceSpans {
        [
            (
                "carry".to_string(),
                HandForceSpan {
                    horizontal_walking_max_n: 30.0,
                    horizontal_standing_max_n: 0.5,
                    vertical_n: (-20.0, 1.0),
                },
            ),
            (
                "chair".to_string(),
                HandForceSpan {
                    horizontal_walking_max_n: 61.0,
                    horizontal_standing_max_n: 0.0,
                    vertical_n: (-5.0, 0.0),
                },
            ),
        ]
        .into()
    }

    #[test]
    fn a_replay_marks_the_tasks_whose_scaled_forces_leave_the_curriculum() {
        let s = spans();
        match setting_outside(&FALCON_FORCES, &replay("force", 1.0), None, &s) {
            SettingOutside::Tasks(t) => {
                assert_eq!(t.keys().collect::<Vec<_>>(), ["chair"]);
                assert!(
                    t["chair"].contains("61 N horizontal walking"),
                    "{}",
                    t["chair"]
                );
            }
            other => panic!("{other:?}"),
        }
        // At half the level both lie inside; without force nothing is judged.
        assert_eq!(
            setting_outside(&FALCON_FORCES, &replay("coef-0.5", 0.5), None, &s),
            SettingOutside::Inside
        );
        assert_eq!(
            setting_outside(&FALCON_FORCES, &replay("no-force", 0.0), None, &s),
            SettingOutside::Inside
        );
        // A force-blind family has no envelope to mark against.
        assert_eq!(
            setting_outside(&TrainedForces::Blind, &replay("force", 1.0), None, &s),
            SettingOutside::Inside
        );
    }

    #[test]
    fn a_push_and_a_two_handed_history_are_outside_wrist_events() {
        let push = Setting {
            push_n: 20.0,
            ..replay("push-20", 0.0)
        };
        assert!(matches!(
            setting_outside(&SOFTMIMIC_FORCES, &push, Some(60.0), &spans()),
            SettingOutside::EveryTask(_)
        ));
        match setting_outside(
            &SOFTMIMIC_FORCES,
            &replay("force", 1.0),
            Some(60.0),
            &spans(),
        ) {
            SettingOutside::Tasks(t) => assert_eq!(t.len(), 2),
            other => panic!("{other:?}"),
        }
    }
}
