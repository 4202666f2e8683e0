//! Reference clips and datasets: the canonical format (safetensors + manifest), importers,
//! resampling and forward kinematics of references.
//!
//! Beside them: a batch of files imported all or nothing (`import_batch`), teleoperation
//! glitches found, and trimmed only when asked (`glitch.rs`, shared with `data info`), the
//! synthetic dataset (`synth`, `thorarena data synth`), one sequence's hand forces grafted
//! onto another motion (`force_graft`), which of a dataset's sequences a run evaluates
//! (`SequenceSelection`: `--tasks`, `--sequences`), and the export for Python
//! (`export.rs`). `import::G1_CANONICAL_JOINTS` is the one list of the G1's joint order in
//! code; `robot.toml` holds the same order as data.

mod bundled;
pub mod check;
mod dataset;
mod describe;
mod error;
mod export;
pub mod force_graft;
mod format;
mod glitch;
pub mod import;
mod reference;
mod selection;
mod sequence;
pub mod synth;

/// Frame rates a motion may have, Hz: any capture or simulation rate, and nothing that
/// makes a clip last longer than its frames could fill (a `fps` of 1e-300 once imported
/// as a motion of 6e301 s, which no evaluation finishes).
pub const FPS_RANGE: std::ops::RangeInclusive<f64> = 1.0..=1000.0;

/// Why `fps` is no frame rate of [`FPS_RANGE`], or `None` when it is one.
pub fn fps_problem(fps: f64) -> Option<String> {
    (!FPS_RANGE.contains(&fps)).then(|| {
        format!(
            "must be a frame rate of {} to {} Hz, got {fps}",
            FPS_RANGE.start(),
            FPS_RANGE.end()
        )
    })
}

pub use bundled::{
    bundled_dataset, bundled_datasets, dataset_arg, BundledDataset, BUNDLED_DATASETS,
};
pub use dataset::{Dataset, DatasetWriter, Manifest, ManifestEntry, MANIFEST};
pub use describe::{describe, joint_limit_margin, plural, total_hand_force};
pub use error::DataError;
pub use export::export_npz;
pub use format::{decode_sequence, encode_sequence, sha256_hex, write_sequence, SCHEMA_VERSION};
pub use glitch::{
    scan_root_glitches, GlitchScan, RootJump, TrimmedGlitches, EDGE_GLITCH_WINDOW_S,
    MAX_HUMAN_ROOT_SPEED_M_PER_S,
};
pub use reference::{
    correct_ground, ground_check, heading_rad, reference_keypoints, shift_root_height, GroundCheck,
    Reference, ReferenceFrame, GROUND_SHIFT_KEY,
};
pub use selection::{SelectionError, SequenceSelection, Subset};
pub use sequence::{ForceFrame, Sequence, LEFT, QUAT_NORM_TOLERANCE, RIGHT};
