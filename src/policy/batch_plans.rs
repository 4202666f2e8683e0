//! One network run on a batch of environments in one tract call: an `[N, width]` input
//! instead of N calls of `[1, width]`. tract plans for fixed shapes, so each batch size
//! asked gets its own plan, made on first use and shared by every copy of the policy
//! (one per worker thread, [`super::Policy::worker_copies`]).
//!
//! Why batch: a whole-body tracker is a small MLP whose weights do not fit in L2; one
//! call per environment streams them once per environment, one call per batch once per
//! batch. Within one call shape, each row of the output depends on its own row of the
//! input only, wherever it sits (`tests/batched_inference.rs`); another call shape may
//! round differently (tract picks kernels by shape), so a caller wanting records
//! independent of batching keeps one shape (`twist2::INFERENCE_BATCH`).

use std::collections::HashMap;
use std::sync::{Arc, Mutex};
use tract_onnx::prelude::*;

/// A network's runnable plans by batch size.
#[derive(Clone)]
pub struct BatchPlans {
    /// The model as loaded, its input shape not yet fixed.
    model: Arc<InferenceModel>,
    /// Width of the (single) input, floats.
    width: usize,
    /// Width of the first output, floats per row.
    outputs: usize,
    made: Arc<Mutex<HashMap<usize, Arc<TypedRunnableModel>>>>,
}

impl BatchPlans {
    /// Plans for `model`, which must fit its family's contract: its first input
    /// `[batch, width]` float32 (the batch axis symbolic or 1), its first output `outputs`
    /// floats per row when given (`None`: whatever it answers, e.g. a benchmark's network
    /// of any kind). The batch-one plan is made now and run once on zeros, so a network
    /// of another family — whose own input width differs, or whose graph only fails when
    /// it runs — is refused at load, naming what was expected and found, not once per
    /// control step.
    pub fn new(model: InferenceModel, width: usize, outputs: Option<usize>) -> TractResult<Self> {
        let fact = model.input_fact(0)?;
        if let Some(declared) = super::onnx_export::fixed_width(fact) {
            if declared != width {
                anyhow::bail!(
                    "the network's input is {declared} wide (declared shape {:?}); this family's networks take [batch, {width}]",
                    fact.shape
                );
            }
        }
        let plans = Self {
            model: Arc::new(model),
            width,
            outputs: 0,
            made: Arc::new(Mutex::new(HashMap::new())),
        };
        let mut plans = plans;
        let probe = plans
            .run(&vec![0.0; width], 1)
            .map_err(|e| e.context(format!("the network does not run on a [1, {width}] input")))?;
        if let Some(outputs) = outputs.filter(|&n| n != probe.len()) {
            anyhow::bail!(
                "the network answers {} values per row; this family's networks answer {outputs}",
                probe.len()
            );
        }
        plans.outputs = probe.len();
        Ok(plans)
    }

    /// Floats per row of the first output.
    pub fn outputs(&self) -> usize {
        self.outputs
    }

    /// The plan for `batch` rows.
    pub fn plan(&self, batch: usize) -> TractResult<Arc<TypedRunnableModel>> {
        let mut made = self.made.lock().unwrap_or_else(|e| e.into_inner());
        if let Some(plan) = made.get(&batch) {
            return Ok(plan.clone());
        }
        let plan = (*self.model)
            .clone()
            .with_input_fact(0, f32::fact([batch, self.width]).into())?
            .into_optimized()?
            .into_runnable()?;
        made.insert(batch, plan.clone());
        Ok(plan)
    }

    /// Runs `inputs` (`batch` rows of `width`, row-major) and returns the first output,
    /// row-major.
    pub fn run(&self, inputs: &[f32], batch: usize) -> TractResult<Vec<f32>> {
        self.run_on(&self.plan(batch)?, inputs, batch)
    }

    /// One row through `plan`, or `None` after logging why (`family`'s message): a network
    /// that fails at run time answers NaN, which the runner's miss rule keeps away from the
    /// physics and counts.
    pub fn run_row(
        &self,
        plan: &Arc<TypedRunnableModel>,
        input: &[f32],
        family: &str,
    ) -> Option<Vec<f32>> {
        match self.run_on(plan, input, 1) {
            Ok(out) => Some(out),
            Err(e) => {
                log::warn!(
                    "{family}: inference failed: {}",
                    crate::files::log_text::causes_once(e.as_ref())
                );
                None
            }
        }
    }

    /// [`Self::run`] on a plan taken from [`Self::plan`] beforehand: no lookup, for a
    /// caller that runs one shape every step.
    pub fn run_on(
        &self,
        plan: &Arc<TypedRunnableModel>,
        inputs: &[f32],
        batch: usize,
    ) -> TractResult<Vec<f32>> {
        let tensor = Tensor::from_shape(&[batch, self.width], inputs)?;
        let out = plan.run(tvec!(tensor.into()))?;
        Ok(out[0]
            .to_plain_array_view::<f32>()?
            .iter()
            .copied()
            .collect())
    }
}
