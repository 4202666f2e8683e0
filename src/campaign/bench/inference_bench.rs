//! `thorarena bench inference` as one call: one network's cost per environment against
//! the batch size of a tract call (`policy::BatchPlans`), each batch size timed in the
//! same run on the same number of environments, with the ratio to batch one.

use super::{BenchLine, PerfError};
use crate::policy::BatchPlans;
use std::path::PathBuf;
use std::time::Instant;

/// `bench inference` as asked for.
#[derive(Debug, Clone)]
pub struct InferenceBench {
    /// The ONNX network (one float32 input `[batch, width]`, e.g. TWIST2's).
    pub onnx: PathBuf,
    /// Batch sizes, in the order timed.
    pub batches: Vec<usize>,
    /// Environments run through the network per batch size (rounded up to whole
    /// batches).
    pub envs: usize,
}

/// tract's error as one message, its causes joined.
fn network_error(e: tract_onnx::prelude::TractError) -> PerfError {
    PerfError::Network(crate::files::log_text::causes_once(e.as_ref()))
}

impl InferenceBench {
    /// Loads the network, then times each batch size, handing the table's heading and
    /// each row to `say` as it is measured.
    pub fn run(&self, say: &mut dyn FnMut(BenchLine)) -> Result<(), PerfError> {
        let (model, _) =
            crate::policy::network_kernels::load_onnx(&self.onnx).map_err(network_error)?;
        let fact = model.input_fact(0).map_err(network_error)?;
        let width = crate::policy::onnx_export::fixed_width(fact).ok_or_else(|| {
            PerfError::Network(format!(
                "{}: the first input has no fixed width",
                self.onnx.display()
            ))
        })?;
        let plans = BatchPlans::new(model, width, None).map_err(network_error)?;
        for line in [
            format!(
                "{}: input width {width}; µs per tract call and per environment, {} environments per batch size",
                self.onnx.display(),
                self.envs
            ),
            "| batch | µs per call | µs per environment | per environment ÷ batch one |".into(),
            "|---:|---:|---:|---:|".into(),
        ] {
            say(BenchLine::Figure(line));
        }
        let mut batch_one_us = None;
        for &batch in &self.batches {
            if batch == 0 {
                return Err(PerfError::Precondition(
                    "`option.batches`: a batch size must be at least 1".into(),
                ));
            }
            let per_call = time_calls(&plans, width, batch, self.envs).map_err(network_error)?;
            let per_env = per_call / batch as f64;
            let one = *batch_one_us.get_or_insert(per_env);
            say(BenchLine::Figure(format!(
                "| {batch} | {per_call:.1} | {per_env:.1} | {:.2} |",
                per_env / one
            )));
        }
        Ok(())
    }
}

/// µs per call of `batch` rows of `width` inputs, over enough calls for `envs`
/// environments; the batch's plan made and warmed before the clock starts.
fn time_calls(
    plans: &BatchPlans,
    width: usize,
    batch: usize,
    envs: usize,
) -> tract_onnx::prelude::TractResult<f64> {
    let inputs: Vec<f32> = (0..batch * width)
        .map(|i| ((i % 97) as f32 - 48.0) / 48.0)
        .collect();
    plans.run(&inputs, batch)?;
    let calls = envs.div_ceil(batch);
    let t0 = Instant::now();
    for _ in 0..calls {
        std::hint::black_box(plans.run(&inputs, batch)?);
    }
    Ok(t0.elapsed().as_secs_f64() * 1e6 / calls as f64)
}
