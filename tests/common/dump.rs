//! Episode dumps for the Python adapters' cross-checks: one environment's observation as
//! the wire carries it, field by field, in the JSON `thorarena.adapters.dump` reads.

/// One environment's wire block as JSON, field by field (what the Python adapter reads).
pub fn wire_json(obs: &thorarena::policy::Observation, offsets: &[f64]) -> serde_json::Value {
    use thorarena_ipc::layout::{ENV_ARRAYS, REF_ARRAYS};
    use thorarena_ipc::{Layout, ObsBatch, ObsBatchMut};
    let layout = Layout {
        n_envs: 1,
        n_joints: obs.q.len(),
        n_refs: offsets.len(),
    };
    let mut words = vec![0u64; layout.obs_words()];
    {
        let mut batch = ObsBatchMut::new(layout, bytemuck::cast_slice_mut(&mut words), 0, 0);
        thorarena::policy::wire::write_observation(obs, offsets, &mut batch.env(0), 0);
    }
    let batch = ObsBatch::new(layout, bytemuck::cast_slice(&words)).unwrap();
    let env = batch.env(0);
    let h = env.header();
    let mut map = serde_json::Map::new();
    map.insert("episode_id".into(), h.episode_id.into());
    map.insert("step".into(), h.step.into());
    map.insert("flags".into(), h.flags.into());
    map.insert("time_s".into(), h.time_s.into());
    for (name, _, _) in ENV_ARRAYS {
        map.insert(name.into(), env.array(name).to_vec().into());
    }
    let frames: Vec<serde_json::Value> = (0..layout.n_refs)
        .map(|i| {
            REF_ARRAYS
                .iter()
                .map(|(name, _, _)| {
                    let v = env.reference(i, name);
                    let v = if v.len() == 1 {
                        v[0].into()
                    } else {
                        v.to_vec().into()
                    };
                    (name.to_string(), v)
                })
                .collect::<serde_json::Map<_, _>>()
                .into()
        })
        .collect();
    map.insert("reference".into(), frames.into());
    map.into()
}
