//! Reference clips and datasets: the canonical format (safetensors + manifest), importers,
//! resampling and forward kinematics of references.

pub mod import;
