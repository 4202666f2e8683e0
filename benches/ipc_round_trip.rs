//! One policy round trip over shared memory (simulator and echo policy on two threads of
//! this process) at 1 and 64 environments, next to a Unix-socket pair moving the same
//! bytes. The cross-process, cross-language benchmark is `thorarena bench ipc`.

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use std::io::{Read, Write};
use std::os::unix::net::UnixStream;
use std::time::Duration;
use thorarena_ipc::{
    ActionBatchMut, EnvHeader, Layout, ObsBatch, PolicyClient, PolicyConfig, SimConfig, SimSession,
    FLAG_ACTIVE,
};

const JOINTS: usize = 29;

fn names() -> Vec<String> {
    (0..JOINTS).map(|j| format!("joint_{j}")).collect()
}

fn echo(obs: &ObsBatch, out: &mut ActionBatchMut) {
    for i in 0..obs.n_envs() {
        out.env(i).copy_from_slice(obs.env(i).array("q"));
    }
}

fn shared_memory(c: &mut Criterion, envs: usize) {
    let session = format!("criterion-{envs}-{}", std::process::id());
    let mut sim = SimSession::create(SimConfig {
        session: session.clone(),
        n_envs: envs,
        joint_names: names(),
        control_dt_s: 0.02,
        action_offset_rad: vec![0.0; JOINTS],
        action_scale: vec![1.0; JOINTS],
        budget: None,
        wait: Default::default(),
        inputs: vec![],
    })
    .expect("session");
    let policy = std::thread::spawn(move || {
        let config = PolicyConfig::new(&session, "echo", names(), vec![0.0]);
        let mut client = PolicyClient::connect(&config, Duration::from_secs(10)).expect("connect");
        client.run(echo).expect("run")
    });
    sim.accept(Some(Duration::from_secs(10)), |_| {})
        .expect("accept");
    let mut step = 0u64;
    c.bench_with_input(
        BenchmarkId::new("shared_memory_round_trip", envs),
        &envs,
        |b, &envs| {
            b.iter(|| {
                step += 1;
                sim.step(
                    |batch| {
                        for i in 0..envs {
                            let mut env = batch.env(i);
                            env.set_header(&EnvHeader {
                                episode_id: i as u64,
                                step,
                                flags: FLAG_ACTIVE,
                                reserved: 0,
                                time_s: 0.0,
                            });
                            env.array("q").fill(step as f64);
                        }
                    },
                    None,
                    |actions| assert_eq!(actions.env(envs - 1)[0], step as f64),
                )
                .expect("step")
            })
        },
    );
    sim.end();
    policy.join().expect("policy thread");
}

fn unix_socket(c: &mut Criterion, envs: usize) {
    let layout = Layout {
        n_envs: envs,
        n_joints: JOINTS,
        n_refs: 1,
        n_inputs: 0,
    };
    let (mut ours, mut theirs) = UnixStream::pair().expect("socket pair");
    let peer = std::thread::spawn(move || {
        let mut obs = vec![0u64; layout.obs_words()];
        let mut actions = vec![0u64; layout.action_words()];
        while theirs
            .read_exact(bytemuck::cast_slice_mut(&mut obs))
            .is_ok()
        {
            let batch = ObsBatch::new(layout, bytemuck::cast_slice(&obs)).expect("batch");
            let mut out = ActionBatchMut::new(layout, bytemuck::cast_slice_mut(&mut actions), 0);
            echo(&batch, &mut out);
            theirs
                .write_all(bytemuck::cast_slice(&actions))
                .expect("write");
        }
    });
    let mut obs = vec![0u64; layout.obs_words()];
    thorarena_ipc::ObsBatchMut::new(layout, bytemuck::cast_slice_mut(&mut obs), 0, 0);
    let mut actions = vec![0u64; layout.action_words()];
    c.bench_with_input(
        BenchmarkId::new("unix_socket_round_trip", envs),
        &envs,
        |b, _| {
            b.iter(|| {
                ours.write_all(bytemuck::cast_slice(&obs)).expect("write");
                ours.read_exact(bytemuck::cast_slice_mut(&mut actions))
                    .expect("read");
            })
        },
    );
    drop(ours);
    peer.join().expect("peer thread");
}

fn round_trips(c: &mut Criterion) {
    for envs in [1, 64] {
        shared_memory(c, envs);
        unix_socket(c, envs);
    }
}

criterion_group!(benches, round_trips);
criterion_main!(benches);
