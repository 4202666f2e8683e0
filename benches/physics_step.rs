//! One 5 ms physics step of the G1 standing on its soles under PD (default settings).
//! The scenario benchmark with a MuJoCo baseline is `thorarena bench physics`.

use criterion::{criterion_group, criterion_main, Criterion};
use std::sync::Arc;
use thorarena::sim::physics::{
    standing_default_pose, standing_gains, Physics, PhysicsSettings, RapierPhysics,
};

fn physics_step(c: &mut Criterion) {
    let model = Arc::new(thorarena::sim::robot::load_bundled("g1_29dof").expect("bundled G1"));
    let mut physics = RapierPhysics::new(
        model.clone(),
        PhysicsSettings::default(),
        standing_gains(&model),
    );
    let start = standing_default_pose(&model);
    physics.reset(&start);
    physics.set_targets(&start.q);
    for _ in 0..200 {
        physics.step(); // settle onto the soles
    }
    c.bench_function("g1_standing_physics_step_5ms", |b| {
        b.iter(|| physics.step())
    });
}

criterion_group!(benches, physics_step);
criterion_main!(benches);
