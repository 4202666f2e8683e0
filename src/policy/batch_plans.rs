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
    made: Arc<Mutex<HashMap<usize, Arc<TypedRunnableModel>>>>,
}

impl BatchPlans {
    /// Plans for `model`, whose first input is `[batch, width]` float32; the batch-one
    /// plan is made now, so a network tract cannot run is refused at load.
    pub fn new(model: InferenceModel, width: usize) -> TractResult<Self> {
        let plans = Self {
            model: Arc::new(model),
            width,
            made: Arc::new(Mutex::new(HashMap::new())),
        };
        plans.plan(1)?;
        Ok(plans)
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
                log::warn!("{family}: inference failed: {e:#}");
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
