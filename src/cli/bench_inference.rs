//! `thorarena bench inference`: one network's cost per environment against the batch size
//! of a tract call, each batch size timed in the same run, with the ratio to batch one
//! (`thorarena::perf::InferenceBench`).

use std::path::PathBuf;
use thorarena::perf::InferenceBench;

/// Arguments of `bench inference`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// The ONNX network (one float32 input `[batch, width]`, e.g. TWIST2's).
    pub onnx: PathBuf,
    /// Batch sizes, comma separated.
    #[arg(long, value_delimiter = ',', default_value = "1,2,4,8,16,32,64")]
    pub batches: Vec<usize>,
    /// Environments run through the network per batch size (rounded up to whole batches).
    #[arg(long, default_value_t = 4096)]
    pub envs: usize,
}

/// `bench inference`: the library times each batch size and hands over each row as it is
/// measured.
pub(super) fn run(args: &Args) -> anyhow::Result<()> {
    let bench = InferenceBench {
        onnx: args.onnx.clone(),
        batches: args.batches.clone(),
        envs: args.envs,
    };
    bench.run(&mut super::bench_eval::print)?;
    Ok(())
}
