//! Loading a BeyondMimic network: open it and read its metadata, map its joint order to
//! the robot's, settle the action mapping, observation terms and anchor body, and make the
//! network runnable with the input widths they imply.

use super::{
    layout_width, BeyondMimicError, BeyondMimicPolicy, FileMetadata, JointOrderFrom,
    ObservationSpec, Scratch, Term, INFERENCE_BATCH, KNOWN_LAYOUTS,
};
use crate::sim::profile::{ActionMode, BeyondMimicProfile, Profile};
use crate::sim::robot::RobotModel;
use std::path::Path;
use std::sync::Arc;
use tract_onnx::prelude::*;

impl BeyondMimicPolicy {
    /// Loads `path` for `robot` under `profile` (whose action mapping and gains the
    /// benchmark applies).
    pub fn load(
        path: &Path,
        robot: Arc<RobotModel>,
        profile: &Profile,
    ) -> Result<Self, BeyondMimicError> {
        let unusable = |reason: String| BeyondMimicError::Unusable {
            path: path.to_path_buf(),
            reason,
        };
        let network = Network::open(path)?;
        let meta = &network.meta;
        let profile_bm = profile.beyondmimic.as_ref();
        let (joint_names, to_canonical, joint_order_from) =
            joint_order(&robot, meta, profile_bm).map_err(unusable)?;
        let (default_pos, action_scale) =
            action_mapping(meta, profile, &joint_names, &to_canonical).map_err(unusable)?;
        let mut disagreements =
            disagreements(meta, profile, &robot, &to_canonical).map_err(unusable)?;
        let action_mode = action_mode(meta, profile, &mut disagreements).map_err(unusable)?;
        let n = robot.n_joints();
        let terms = observation_terms(meta, profile_bm, n, network.obs_width).map_err(unusable)?;
        let anchor_frame = anchor_frame(meta, profile_bm, &robot).map_err(unusable)?;
        let identity = network.identity.clone();
        let (obs_width, time_step_input, actions_output) = (
            network.obs_width,
            network.time_step_input,
            network.actions_output,
        );
        let (plan, call_rows) = network.into_runnable(path, n)?;
        for d in &disagreements {
            log::warn!("{}: {d}", path.display());
        }
        Ok(Self {
            name: "beyondmimic".into(),
            plan,
            network: identity,
            call_rows,
            spec: ObservationSpec {
                terms,
                to_canonical,
                default_pos,
                anchor_frame,
            },
            robot,
            obs_width,
            time_step_input,
            actions_output,
            action_scale,
            action_mode,
            control_dt_s: profile.control_dt_s,
            profile_offset: profile.action_offset_rad.clone(),
            profile_scale: profile.action_scale.clone(),
            disagreements,
            joint_order_from,
            scratch: Scratch::default(),
            input: Vec::new(),
            batch_input: Vec::new(),
            last_inputs: Vec::new(),
        })
    }
}

/// The network as loaded, before its input shapes are fixed: what it says about itself
/// and where its inputs and outputs are.
struct Network {
    model: InferenceModel,
    /// The file, by content.
    identity: crate::policy::network_file::NetworkFile,
    meta: FileMetadata,
    /// Input slot of `obs` (else the first input).
    obs_input: usize,
    /// Input slot of `time_step`, if the network has one.
    time_step_input: Option<usize>,
    /// Output slot of `actions` (else the first output).
    actions_output: usize,
    /// Width of the observation input (its last dimension).
    obs_width: usize,
}

impl Network {
    /// Loads the ONNX file and reads its metadata and input and output slots.
    fn open(path: &Path) -> Result<Self, BeyondMimicError> {
        let load_err = load_error(path);
        let (model, identity) =
            crate::policy::network_kernels::load_onnx(path).map_err(load_err)?;
        let meta = FileMetadata::from_props(&crate::policy::onnx_export::metadata_props(&model))
            .map_err(|reason| BeyondMimicError::Unusable {
                path: path.to_path_buf(),
                reason,
            })?;
        let inputs = model.input_outlets().map_err(load_err)?.to_vec();
        let outputs = model.output_outlets().map_err(load_err)?.to_vec();
        let obs_input = slot(&model, &inputs, "obs").unwrap_or(0);
        let time_step_input = slot(&model, &inputs, "time_step");
        let actions_output = slot(&model, &outputs, "actions").unwrap_or(0);
        let fact = model.input_fact(obs_input).map_err(load_err)?;
        let obs_width = crate::policy::onnx_export::fixed_width(fact).ok_or_else(|| {
            BeyondMimicError::Unusable {
                path: path.to_path_buf(),
                reason: "the observation input has no fixed width".into(),
            }
        })?;
        Ok(Self {
            model,
            identity,
            meta,
            obs_input,
            time_step_input,
            actions_output,
            obs_width,
        })
    }

    /// Fixes the input shapes, optimizes the network and makes it runnable for one call
    /// shape: [`INFERENCE_BATCH`] rows (observations `[rows, obs_width]`, time steps
    /// `[rows, 1]`) when the graph allows it, else one row — an export whose graph
    /// hard-codes a batch of one (a reshape to `[1, …]`) fails to plan for more, or
    /// answers another shape. Returns the plan and its rows. Its `actions` output must be
    /// one value per joint and row (`n_joints`), or every step would fail (a wrong width
    /// once scored as a network answering zeros).
    fn into_runnable(
        self,
        path: &Path,
        n_joints: usize,
    ) -> Result<(Arc<TypedRunnableModel>, usize), BeyondMimicError> {
        if INFERENCE_BATCH > 1 {
            match self.runnable_for(path, n_joints, INFERENCE_BATCH) {
                Ok(plan) => return Ok((plan, INFERENCE_BATCH)),
                Err(e) => log::info!(
                    "{}: one row per call, the network does not plan for {INFERENCE_BATCH}: {e}",
                    path.display()
                ),
            }
        }
        Ok((self.runnable_for(path, n_joints, 1)?, 1))
    }

    /// The network planned for calls of `rows` rows.
    fn runnable_for(
        &self,
        path: &Path,
        n_joints: usize,
        rows: usize,
    ) -> Result<Arc<TypedRunnableModel>, BeyondMimicError> {
        let load_err = load_error(path);
        let n = n_joints;
        let mut model = self
            .model
            .clone()
            .with_input_fact(self.obs_input, f32::fact([rows, self.obs_width]).into())
            .map_err(load_err)?;
        if let Some(t) = self.time_step_input {
            model = model
                .with_input_fact(t, f32::fact([rows, 1]).into())
                .map_err(load_err)?;
        }
        let typed = model.into_optimized().map_err(load_err)?;
        let action_width = typed
            .output_fact(self.actions_output)
            .ok()
            .and_then(|f| f.shape.as_concrete().map(|s| s.to_vec()));
        if action_width.as_deref().and_then(|s| s.last()) != Some(&n)
            || action_width
                .as_deref()
                .is_some_and(|s| s.iter().product::<usize>() != rows * n)
        {
            return Err(BeyondMimicError::Unusable {
                path: path.to_path_buf(),
                reason: format!(
                    "the `actions` output has shape {action_width:?} for {rows} rows, not one value per joint ({n}) and row"
                ),
            });
        }
        typed.into_runnable().map_err(load_err)
    }
}

/// tract's error loading or preparing the network at `path`.
fn load_error(path: &Path) -> impl Fn(TractError) -> BeyondMimicError + Copy + '_ {
    move |e| BeyondMimicError::Load {
        path: path.to_path_buf(),
        message: crate::files::log_text::causes_once(e.as_ref()),
    }
}

/// Index of the model input or output named `name`.
fn slot(model: &InferenceModel, outlets: &[OutletId], name: &str) -> Option<usize> {
    outlets
        .iter()
        .position(|o| model.outlet_label(*o) == Some(name) || model.node(o.node).name == name)
}

/// The policy's joint order (the file's names, else the profile's `[beyondmimic]
/// joint_names`, else the robot's), where it came from, and, for each of its joints, the
/// robot's canonical index: every joint must be the robot's, each once. A file and a
/// profile that both name an order must name the same one: a network fed its joints in
/// the wrong order still runs, and only falls.
fn joint_order(
    robot: &RobotModel,
    meta: &FileMetadata,
    profile_bm: Option<&BeyondMimicProfile>,
) -> Result<(Vec<String>, Vec<usize>, JointOrderFrom), String> {
    let n = robot.n_joints();
    let from_profile = profile_bm
        .map(|b| b.joint_names.clone())
        .filter(|names| !names.is_empty());
    let (joint_names, from) = match (&meta.joint_names, from_profile) {
        (Some(file), Some(profile)) if *file != profile => {
            let first = file
                .iter()
                .zip(&profile)
                .position(|(a, b)| a != b)
                .unwrap_or(file.len().min(profile.len()));
            return Err(format!(
                "the file's joint_names and the profile's [beyondmimic] joint_names name different orders (first difference at joint {first}: `{}` against `{}`)",
                file.get(first).map_or("(none)", String::as_str),
                profile.get(first).map_or("(none)", String::as_str)
            ));
        }
        (Some(file), _) => (file.clone(), JointOrderFrom::File),
        (None, Some(profile)) => (profile, JointOrderFrom::Profile),
        (None, None) => (
            robot.joints.iter().map(|j| j.name.clone()).collect(),
            JointOrderFrom::Robot,
        ),
    };
    if joint_names.len() != n {
        return Err(format!(
            "the policy has {} joints, the robot {} has {n}",
            joint_names.len(),
            robot.name
        ));
    }
    let to_canonical = joint_names
        .iter()
        .map(|name| {
            robot.joint_index(name).ok_or_else(|| {
                format!(
                    "joint `{name}` of the policy is not a joint of {}",
                    robot.name
                )
            })
        })
        .collect::<Result<Vec<usize>, _>>()?;
    let mut seen = vec![false; n];
    for (&c, name) in to_canonical.iter().zip(&joint_names) {
        if std::mem::replace(&mut seen[c], true) {
            return Err(format!(
                "joint `{name}` is named twice in {}'s joint order",
                from.name()
            ));
        }
    }
    Ok((joint_names, to_canonical, from))
}

/// A per-joint metadata value `what` for `n` joints: one number is spread to all joints;
/// absent, it is `fallback`. The same `n` values written several times over are read once
/// (wbc-mjlab's export writes its `action_scale` five times); any other length is an
/// error.
fn per_joint(
    what: &str,
    v: Option<Vec<f64>>,
    fallback: Vec<f64>,
    n: usize,
) -> Result<Vec<f64>, String> {
    match v {
        Some(v) if v.len() == 1 => Ok(vec![v[0]; n]),
        Some(v) if v.len() == n => Ok(v),
        Some(v) if n > 0 && v.len() % n == 0 && v.chunks(n).all(|c| c == &v[..n]) => {
            Ok(v[..n].to_vec())
        }
        Some(v) => Err(format!(
            "metadata {what} has {} values for {n} joints",
            v.len()
        )),
        None => Ok(fallback),
    }
}

/// The policy's own action mapping, policy order: default pose, rad, and action scale —
/// the file's, else the profile's. The scale must be finite and non-zero: a zero scale
/// ignores the network (and the `actions` term divides by it).
fn action_mapping(
    meta: &FileMetadata,
    profile: &Profile,
    joint_names: &[String],
    to_canonical: &[usize],
) -> Result<(Vec<f64>, Vec<f64>), String> {
    let n = to_canonical.len();
    let policy_order =
        |canonical: &[f64]| -> Vec<f64> { to_canonical.iter().map(|&c| canonical[c]).collect() };
    let default_pos = per_joint(
        "default_joint_pos",
        meta.default_joint_pos.clone(),
        policy_order(&profile.action_offset_rad),
        n,
    )?;
    let action_scale = per_joint(
        "action_scale",
        meta.action_scale.clone(),
        policy_order(&profile.action_scale),
        n,
    )?;
    if let Some(i) = action_scale
        .iter()
        .position(|a| !a.is_finite() || *a == 0.0)
    {
        return Err(format!(
            "action scale {} for joint `{}`: it must be finite and non-zero",
            action_scale[i], joint_names[i]
        ));
    }
    if let Some(i) = default_pos.iter().position(|a| !a.is_finite()) {
        return Err(format!(
            "default_joint_pos {} for joint `{}` is not finite",
            default_pos[i], joint_names[i]
        ));
    }
    Ok((default_pos, action_scale))
}

/// What the file says against what the profile applies (kp, kd, default pose, action
/// scale), canonical order: one sentence per quantity that differs. Reported, not fatal:
/// the profile's values are the ones the benchmark applies.
fn disagreements(
    meta: &FileMetadata,
    profile: &Profile,
    robot: &RobotModel,
    to_canonical: &[usize],
) -> Result<Vec<String>, String> {
    let n = robot.n_joints();
    let canonical = |policy: &[f64]| {
        let mut c = vec![0.0; n];
        for (i, &ci) in to_canonical.iter().enumerate() {
            c[ci] = policy[i];
        }
        c
    };
    let names: Vec<String> = robot.joints.iter().map(|j| j.name.clone()).collect();
    let mut disagreements = Vec::new();
    for (what, file, applied) in [
        ("kp", meta.kp.clone(), &profile.gains.kp),
        ("kd", meta.kd.clone(), &profile.gains.kd),
        (
            "default pose",
            meta.default_joint_pos.clone(),
            &profile.action_offset_rad,
        ),
        (
            "action scale",
            meta.action_scale.clone(),
            &profile.action_scale,
        ),
    ] {
        let Some(file) = file else { continue };
        let file = per_joint(what, Some(file), Vec::new(), n)?;
        if let Some(d) = compare(what, &canonical(&file), applied, &names) {
            disagreements.push(format!("{d}; the profile `{}` is applied", profile.name));
        }
    }
    Ok(disagreements)
}

/// `what` per joint, compared between file and profile (both canonical order); a sentence
/// when they differ by more than the file's rounding: mjlab exports write 3 decimals, so
/// values agree within 5e-4 absolute or 1e-3 relative, whichever is looser.
fn compare(what: &str, file: &[f64], profile: &[f64], names: &[String]) -> Option<String> {
    let worst = file
        .iter()
        .zip(profile)
        .enumerate()
        .filter(|(_, (f, p))| (*f - *p).abs() > 5e-4)
        .map(|(j, (f, p))| (j, (f - p).abs() / p.abs().max(1e-9)))
        .filter(|(_, rel)| *rel > 1e-3)
        .max_by(|a, b| a.1.total_cmp(&b.1))?;
    let j = worst.0;
    Some(format!(
        "{what}: the file and the profile differ (largest at {}: file {}, profile {})",
        names[j], file[j], profile[j]
    ))
}

/// How the network's actions become targets: the file's `action_mode`, else the
/// profile's, else `default_relative`. A file and a profile that name different modes are
/// reported (the file's applies); a mode neither spelling knows is an error.
fn action_mode(
    meta: &FileMetadata,
    profile: &Profile,
    disagreements: &mut Vec<String>,
) -> Result<ActionMode, String> {
    let from_profile = profile.beyondmimic.as_ref().and_then(|b| b.action_mode);
    let Some(written) = &meta.action_mode else {
        return Ok(from_profile.unwrap_or_default());
    };
    let from_file = ActionMode::parse(written).ok_or_else(|| {
        let known: Vec<&str> = ActionMode::ALL.iter().map(|m| m.name()).collect();
        format!(
            "metadata action_mode `{written}` is not one ThorArena knows ({})",
            known.join(", ")
        )
    })?;
    if let Some(p) = from_profile.filter(|p| *p != from_file) {
        disagreements.push(format!(
            "action mode: the file says {}, the profile `{}` {}; the file's is applied",
            from_file.name(),
            profile.name,
            p.name()
        ));
    }
    Ok(from_file)
}

/// The observation terms: the file's, the profile's, or the one known layout whose width
/// is the network's input (`obs_width` for `n` joints); whichever is used must make
/// exactly that width.
fn observation_terms(
    meta: &FileMetadata,
    profile_bm: Option<&BeyondMimicProfile>,
    n: usize,
    obs_width: usize,
) -> Result<Vec<Term>, String> {
    let (terms, from) = if let Some(names) = &meta.observation_names {
        (parse_terms(names)?, "the file's observation_names")
    } else if let Some(bm) = profile_bm.filter(|b| !b.observation_names.is_empty()) {
        (
            parse_terms(&bm.observation_names)?,
            "the profile's [beyondmimic] observation_names",
        )
    } else {
        (
            known_layout_of_width(n, obs_width)?,
            "the known layout of that width",
        )
    };
    if layout_width(&terms, n) != obs_width {
        return Err(format!(
            "{from} make {} inputs, the network takes {obs_width}",
            layout_width(&terms, n)
        ));
    }
    Ok(terms)
}

/// The frame of the anchor body: the file's, else the profile's, else `torso_link`.
fn anchor_frame(
    meta: &FileMetadata,
    profile_bm: Option<&BeyondMimicProfile>,
    robot: &RobotModel,
) -> Result<usize, String> {
    let anchor_body = meta
        .anchor_body
        .clone()
        .or_else(|| profile_bm.map(|b| b.anchor_body.clone()))
        .unwrap_or_else(|| "torso_link".into());
    robot.frame_index(&anchor_body).ok_or_else(|| {
        format!(
            "anchor body `{anchor_body}` is not a body of {}",
            robot.name
        )
    })
}

fn parse_terms(names: &[String]) -> Result<Vec<Term>, String> {
    names
        .iter()
        .map(|n| {
            Term::parse(n).ok_or_else(|| {
                format!(
                    "observation term `{n}` is not one of the BeyondMimic family's ({})",
                    Term::ALL.map(Term::name).join(", ")
                )
            })
        })
        .collect()
}

/// The one known layout `obs_width` wide for `n` joints. A width that none or several fit
/// is an error naming them: two layouts of the same width order the same numbers
/// differently, and a network fed the other one still runs — a wiring bug that would
/// score as a bad policy.
fn known_layout_of_width(n: usize, obs_width: usize) -> Result<Vec<Term>, String> {
    let fits: Vec<&(&str, &[Term])> = KNOWN_LAYOUTS
        .iter()
        .filter(|(_, l)| layout_width(l, n) == obs_width)
        .collect();
    let describe = |(name, terms): &(&str, &[Term])| {
        let names: Vec<&str> = terms.iter().map(|t| t.name()).collect();
        format!("{name}: [{}]", names.join(", "))
    };
    match fits.as_slice() {
        [(_, terms)] => Ok(terms.to_vec()),
        [] => Err(format!(
            "no observation_names in the file or the profile, and no known layout is {obs_width} inputs wide for {n} joints ({})",
            KNOWN_LAYOUTS
                .iter()
                .map(|(name, l)| format!("{name}: {}", layout_width(l, n)))
                .collect::<Vec<_>>()
                .join("; ")
        )),
        several => Err(format!(
            "no observation_names in the file or the profile, and its input width {obs_width} fits {} known layouts that order the inputs differently — {}; name the terms in order in the profile's [beyondmimic] observation_names (the bundled holosoma-wbt and holosoma-ppo profiles name holosoma's)",
            several.len(),
            several.iter().map(|f| describe(f)).collect::<Vec<_>>().join("; ")
        )),
    }
}
