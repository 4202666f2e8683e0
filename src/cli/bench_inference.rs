//! `thorarena bench inference`: one network's cost per environment against the batch size
//! of a tract call (`policy::BatchPlans`), each batch size timed in the same run, with
//! the ratio to batch one.

use std::path::PathBuf;
use std::time::Instant;
use thorarena::policy::BatchPlans;

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

pub(super) fn run(args: &Args) -> anyhow::Result<()> {
    let model = thorarena::policy::load_onnx(&args.onnx)?;
    let width = thorarena::onnx_export::fixed_width(model.input_fact(0)?).ok_or_else(|| {
        anyhow::anyhow!(
            "{}: the first input has no fixed width",
            args.onnx.display()
        )
    })?;
    let plans = BatchPlans::new(model, width)?;
    println!("{}: input width {width}; µs per tract call and per environment, {} environments per batch size", args.onnx.display(), args.envs);
    println!("| batch | µs per call | µs per environment | per environment ÷ batch one |");
    println!("|---:|---:|---:|---:|");
    let mut batch_one_us = None;
    for &batch in &args.batches {
        anyhow::ensure!(batch > 0, "--batches: a batch size must be at least 1");
        let inputs: Vec<f32> = (0..batch * width)
            .map(|i| ((i % 97) as f32 - 48.0) / 48.0)
            .collect();
        plans.run(&inputs, batch)?; // plan made and warmed before the clock
        let calls = args.envs.div_ceil(batch);
        let t0 = Instant::now();
        for _ in 0..calls {
            std::hint::black_box(plans.run(&inputs, batch)?);
        }
        let per_call = t0.elapsed().as_secs_f64() * 1e6 / calls as f64;
        let per_env = per_call / batch as f64;
        let one = *batch_one_us.get_or_insert(per_env);
        println!(
            "| {batch} | {per_call:.1} | {per_env:.1} | {:.2} |",
            per_env / one
        );
    }
    Ok(())
}
