//! The kernels a network runs on, pinned to one instruction-set family so that a policy's
//! actions — and the chaotic episodes they drive — are the same bits on every x86-64
//! machine.
//!
//! Why: tract (`tract-linalg` 0.23, `src/x86_64/mmm.rs`, `src/isa.rs`) chooses its matrix
//! and activation kernels when a plan is made, from the instruction sets the CPU reports.
//! An AVX-512 host runs 16-wide kernels whose sums round differently from the AVX2+FMA
//! kernels of a host without AVX-512; the last bits of an action differ, and a pushed
//! robot's fall — chaotic — happens at another step. TWIST2's three released walks under a
//! 30 N push survived 0.31 / 0.30 on one host and 0.48 / 0.28 on another before this pin.
//!
//! What: before the first plan is made, tract's `TRACT_CPU_ISA` knob is set (as a
//! programmatic override, which outranks the environment) to remove every feature above
//! [`PINNED_FAMILY`]: AVX-512 (all of it), AVX-VNNI, AMX and F16C. Every x86-64 CPU with
//! AVX2 and FMA (Intel since Haswell, 2013; AMD since Zen, 2017 — the psABI's x86-64-v3)
//! then runs the same kernels. Within that family the vendor only chooses tile shapes, and
//! every tile shape sums a row in the same order (`tests/network_kernels.rs` holds it).
//!
//! A machine below the family (no AVX2 or no FMA) cannot run its kernels; it keeps what it
//! has, and every run names the kernels it used in `run.json` (`network_kernels`), so
//! `merge`, `--resume` and sweeps refuse to mix its episodes with a pinned machine's.
//!
//! `TRACT_CPU_ISA` in the environment keeps tract's meaning — edits to what this machine
//! reports, to stand in for another machine — and the pin applies on top of it. The
//! environment variable [`KERNELS_ENV`]`=host` leaves tract's own choice, for measuring what
//! the pin costs; such a run records the kernels it used, like any other.

use super::network_file::NetworkFile;
use std::sync::OnceLock;
use tract_onnx::prelude::*;
use tract_onnx::tract_core::tract_linalg::isa::{self, Isa};

/// The family every x86-64 run uses when the machine has it, as tract names the features.
pub const PINNED_FAMILY: &str = "x86_64,avx,avx2,fma";

/// Set to `host` to leave tract's own choice of kernels (measurement only).
pub const KERNELS_ENV: &str = "THORARENA_NETWORK_KERNELS";

/// The features removed to reach [`PINNED_FAMILY`] from any richer x86-64 machine.
const ABOVE_THE_FAMILY: [Isa; 7] = [
    Isa::X86_64F16c,
    Isa::X86_64Avx512f,
    Isa::X86_64Avx512Vnni,
    Isa::X86_64Avx512Fp16,
    Isa::X86_64AvxVnni,
    Isa::X86_64AmxInt8,
    Isa::X86_64AmxBf16,
];

/// What this process's networks run on.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct NetworkKernels {
    /// The instruction sets tract dispatches on, comma-separated as tract names them
    /// (`x86_64,avx,avx2,fma` when pinned).
    pub isa: String,
    /// Whether that is [`PINNED_FAMILY`]: records then equal any pinned machine's.
    pub pinned: bool,
}

/// Pins tract's kernels (once per process, before any plan) and says what they are.
/// Every network ThorArena loads goes through [`load_onnx`], which calls this first.
pub fn network_kernels() -> &'static NetworkKernels {
    static KERNELS: OnceLock<NetworkKernels> = OnceLock::new();
    KERNELS.get_or_init(|| {
        let keep_host = std::env::var(KERNELS_ENV).is_ok_and(|v| v == "host");
        if cfg!(target_arch = "x86_64") && !keep_host {
            let mut spec: Vec<String> = std::env::var("TRACT_CPU_ISA")
                .ok()
                .into_iter()
                .filter(|s| !s.trim().is_empty())
                .collect();
            spec.extend(ABOVE_THE_FAMILY.iter().map(|i| format!("-{}", i.name())));
            tract_onnx::tract_core::knobs::set_str("TRACT_CPU_ISA", &spec.join(","));
        }
        let isa = isa::native()
            .iter()
            .map(|i| i.name())
            .collect::<Vec<_>>()
            .join(",");
        let pinned = isa == PINNED_FAMILY;
        if cfg!(target_arch = "x86_64") && !pinned && !keep_host {
            log::warn!(
                "this CPU lacks AVX2 or FMA: networks run on {isa}, not {PINNED_FAMILY}, so \
                 their records may differ in the last bits from other machines' (run.json \
                 names the kernels)"
            );
        }
        NetworkKernels { isa, pinned }
    })
}

/// Loads an ONNX network after pinning the kernels its plans will use, and says which
/// network it is by content: the file is read once (bounded, a regular file only:
/// [`NetworkFile::read`]) and parsed from those bytes, external data resolved beside it.
pub fn load_onnx(path: &std::path::Path) -> TractResult<(InferenceModel, NetworkFile)> {
    network_kernels();
    let (bytes, identity) = NetworkFile::read(path)?;
    let onnx = tract_onnx::onnx();
    let proto = onnx.proto_model_for_read(&mut bytes.as_slice())?;
    let dir = path.parent().and_then(std::path::Path::to_str);
    let parsed = onnx.parse(&proto, dir)?;
    if !parsed.unresolved_inputs.is_empty() {
        anyhow::bail!(
            "the network has inputs that nothing feeds: {}",
            parsed.unresolved_inputs.join(", ")
        );
    }
    Ok((parsed.model, identity))
}
