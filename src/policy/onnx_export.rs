//! What a BeyondMimic-style ONNX file says about itself: its `metadata_props`, in either
//! spelling in use — mjlab / whole_body_tracking (`attach_onnx_metadata`: `joint_names`,
//! `default_joint_pos`, `action_scale`, `joint_stiffness`, `joint_damping`,
//! `observation_names`, comma-separated text) or holosoma (`policies/wbt.py:174-185`:
//! `dof_names`, `kp`, `kd` as JSON lists).

//!
//! Shared by the policy that runs such a network (`policy::beyondmimic`) and the importer
//! of the motion embedded in one (`motion::import::onnx_motion`), below both.

use std::collections::HashMap;
use tract_onnx::prelude::{InferenceFact, InferenceModel};

/// The metadata the policy uses, every key optional (the profile fills the gaps).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct FileMetadata {
    /// The policy's joint order (`joint_names` or `dof_names`).
    pub joint_names: Option<Vec<String>>,
    /// Default pose, policy order, rad (`default_joint_pos`).
    pub default_joint_pos: Option<Vec<f64>>,
    /// Action scale, policy order (one number for all joints is spread).
    pub action_scale: Option<Vec<f64>>,
    /// kp the policy was trained with (`joint_stiffness` or `kp`).
    pub kp: Option<Vec<f64>>,
    /// kd (`joint_damping` or `kd`).
    pub kd: Option<Vec<f64>>,
    /// Observation terms in order.
    pub observation_names: Option<Vec<String>>,
    /// The anchor body (`anchor_body_name`).
    pub anchor_body: Option<String>,
    /// How an action becomes a joint target (`action_mode`: `default_relative` or
    /// `reference_residual`, wbc-mjlab's spelling), as written.
    pub action_mode: Option<String>,
}

/// A metadata value as a list of items: a JSON array, else comma-separated text.
fn items(text: &str) -> Vec<String> {
    if let Ok(serde_json::Value::Array(values)) = serde_json::from_str(text) {
        return values
            .into_iter()
            .map(|v| match v {
                serde_json::Value::String(s) => s,
                other => other.to_string(),
            })
            .collect();
    }
    text.split(',')
        .map(str::trim)
        .filter(|s| !s.is_empty())
        .map(str::to_string)
        .collect()
}

/// A metadata value as one string: a JSON string, else the trimmed text.
fn text(v: &str) -> String {
    serde_json::from_str::<String>(v).unwrap_or_else(|_| v.trim().to_string())
}

fn numbers(key: &str, text: &str) -> Result<Vec<f64>, String> {
    items(text)
        .iter()
        .map(|s| {
            s.parse::<f64>()
                .ok()
                .filter(|v| v.is_finite())
                .ok_or_else(|| format!("metadata `{key}`: `{s}` is not a finite number"))
        })
        .collect()
}

impl FileMetadata {
    /// Reads the keys from `props` (key → value text); an unreadable value is an error
    /// naming the key.
    pub fn from_props(props: &HashMap<String, String>) -> Result<Self, String> {
        let get = |keys: &[&'static str]| -> Option<(&'static str, &String)> {
            keys.iter().find_map(|&k| props.get(k).map(|v| (k, v)))
        };
        let list = |keys: &[&'static str]| -> Result<Option<Vec<f64>>, String> {
            get(keys).map(|(k, v)| numbers(k, v)).transpose()
        };
        Ok(Self {
            joint_names: get(&["joint_names", "dof_names"]).map(|(_, v)| items(v)),
            default_joint_pos: list(&["default_joint_pos"])?,
            action_scale: list(&["action_scale"])?,
            kp: list(&["joint_stiffness", "kp"])?,
            kd: list(&["joint_damping", "kd"])?,
            observation_names: get(&["observation_names"]).map(|(_, v)| items(v)),
            anchor_body: get(&["anchor_body_name"]).map(|(_, v)| text(v)),
            action_mode: get(&["action_mode"]).map(|(_, v)| text(v)),
        })
    }
}

/// The network's metadata properties as text (tract keeps them as `onnx.metadata_props.*`
/// string scalars).
pub fn metadata_props(model: &InferenceModel) -> HashMap<String, String> {
    model
        .properties
        .iter()
        .filter_map(|(k, v)| {
            let key = k.strip_prefix("onnx.metadata_props.")?;
            let plain = v.try_as_plain_ram().ok()?;
            let text = plain.to_scalar::<String>().ok()?.clone();
            Some((key.to_string(), text))
        })
        .collect()
}

/// The fixed last dimension of an input (an observation's width), if the file gives one.
pub fn fixed_width(fact: &InferenceFact) -> Option<usize> {
    fact.shape
        .dims()
        .last()
        .and_then(tract_onnx::tract_hir::infer::Factoid::concretize)
        .and_then(|d| d.as_i64())
        .and_then(|d| usize::try_from(d).ok())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn both_spellings_read_the_same() {
        let mjlab: HashMap<String, String> = [
            ("joint_names", "a_joint,b_joint"),
            ("joint_stiffness", "40.179,99.098"),
            ("action_scale", "0.25"),
        ]
        .into_iter()
        .map(|(k, v)| (k.to_string(), v.to_string()))
        .collect();
        let holosoma: HashMap<String, String> = [
            ("dof_names", r#"["a_joint", "b_joint"]"#),
            ("kp", "[40.179, 99.098]"),
        ]
        .into_iter()
        .map(|(k, v)| (k.to_string(), v.to_string()))
        .collect();
        let a = FileMetadata::from_props(&mjlab).unwrap();
        let b = FileMetadata::from_props(&holosoma).unwrap();
        assert_eq!(a.joint_names, b.joint_names);
        assert_eq!(a.kp, Some(vec![40.179, 99.098]));
        assert_eq!(a.kp, b.kp);
        assert_eq!(a.action_scale, Some(vec![0.25]));
        assert_eq!(b.action_scale, None);
    }

    #[test]
    fn a_bad_number_names_its_key() {
        let props: HashMap<String, String> = [("kp".to_string(), "[1, \"x\"]".to_string())]
            .into_iter()
            .collect();
        let e = FileMetadata::from_props(&props).unwrap_err();
        assert!(e.contains("`kp`") && e.contains("`x`"), "{e}");
    }
}
