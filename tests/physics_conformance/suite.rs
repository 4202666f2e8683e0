// The conformance suite proper, included once per backend by `tests/physics_conformance.rs`
// (each inclusion defines its own `backend`).

fn g1() -> Arc<RobotModel> {
    Arc::new(robot::load_bundled("g1_29dof").unwrap())
}

fn pendulum() -> Arc<RobotModel> {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/pendulum");
    Arc::new(robot::load_robot_dir(&dir).unwrap())
}

fn zero_g(contacts: ContactMode) -> PhysicsSettings {
    PhysicsSettings {
        gravity: [0.0; 3],
        contacts,
        ..Default::default()
    }
}

fn state_of(p: &dyn Physics) -> PhysicsState {
    let mut s = PhysicsState::default();
    p.read_state(&mut s);
    s
}

fn com_of(p: &dyn Physics) -> Point3<f64> {
    robot::center_of_mass(p.model(), &state_of(p).world_from_body)
}

/// A G1 floating in zero gravity, joints held at the default pose by stiff PD.
fn floating_g1(settings: PhysicsSettings) -> Box<dyn Physics> {
    let m = g1();
    let mut p = backend(&m, settings, standing_gains(&m));
    let mut start = standing_default_pose(&m);
    start.root.world_from_root = Isometry3::translation(0.0, 0.0, 2.0);
    p.reset(&start);
    p.set_targets(&start.q);
    p
}

#[test]
fn momentum_change_under_a_known_force_equals_force_times_time() {
    // Zero gravity, no contacts; 20 N at the left hand, off the centre of mass, so the
    // robot also spins: the centre of mass must still gain exactly F·t of momentum.
    let mut p = floating_g1(zero_g(ContactMode::None));
    let m = p.model().clone();
    let hand = &m.hands[0];
    let frame = &m.frames[hand.frame];
    let force = Vector3::new(20.0, -5.0, 8.0);
    p.set_external_force(ExternalForce {
        body: frame.body,
        force_w: force,
        point_b: frame.body_from_frame * hand.point_hand,
    });
    let dt = p.settings().dt_s;
    let steps = 200;
    let mut prev = com_of(p.as_ref());
    for _ in 0..steps - 1 {
        p.step();
        prev = com_of(p.as_ref());
    }
    p.step();
    let v_com = (com_of(p.as_ref()) - prev) / dt;
    let momentum = v_com * m.total_mass_kg();
    let impulse = force * (steps as f64 * dt);
    let rel = (momentum - impulse).norm() / impulse.norm();
    assert!(
        rel < 0.01,
        "momentum {momentum:?} vs F·t {impulse:?} ({:.3} %)",
        100.0 * rel
    );
    let spin = state_of(p.as_ref()).root.unwrap().ang_vel_w.norm();
    assert!(
        spin > 0.1,
        "an off-centre force must spin the robot (|ω| = {spin})"
    );
}

#[test]
fn forces_hold_until_cleared_and_then_stop_acting() {
    // Rapier keeps user forces and torques across steps; ours apply exactly while set.
    let mut p = floating_g1(zero_g(ContactMode::None));
    let m = p.model().clone();
    let force = Vector3::new(0.0, 30.0, 0.0);
    p.set_external_force(ExternalForce {
        body: 0,
        force_w: force,
        point_b: Point3::from(m.bodies[0].com_b),
    });
    let dt = p.settings().dt_s;
    for _ in 0..50 {
        p.step();
    }
    p.clear_external_forces();
    let mut prev = com_of(p.as_ref());
    for _ in 0..100 {
        prev = com_of(p.as_ref());
        p.step();
    }
    let v = (com_of(p.as_ref()) - prev) / dt;
    let expected = force * (50.0 * dt) / m.total_mass_kg();
    assert!(
        (v - expected).norm() < 0.01 * expected.norm(),
        "v_com {v:?}, expected {expected:?}"
    );
}

#[test]
fn spinning_floating_robot_keeps_its_centre_of_mass_still() {
    // The floating-root centre-of-mass workaround: a free robot spun about its centre of
    // mass must not translate it. Integrating the root about its frame origin (the rapier
    // 0.36 bug: the pelvis centre of mass is 7.6 cm below its frame) would move it.
    let m = g1();
    let mut p = backend(&m, zero_g(ContactMode::None), standing_gains(&m));
    let mut start = standing_default_pose(&m);
    start.root.world_from_root = Isometry3::translation(0.0, 0.0, 2.0);
    let mut poses = Vec::new();
    robot::forward_kinematics(&m, &start.root.world_from_root, &start.q, &mut poses);
    let com0 = robot::center_of_mass(&m, &poses);
    let w = Vector3::new(0.5, 2.0, 1.0);
    start.root.ang_vel_w = w;
    start.root.lin_vel_w =
        -w.cross(&(com0 - Point3::from(start.root.world_from_root.translation.vector)));
    p.reset(&start);
    p.set_targets(&start.q);
    for _ in 0..200 {
        p.step();
    }
    let drift = (com_of(p.as_ref()) - com0).norm();
    assert!(drift < 0.002, "centre of mass drifted {drift} m in 1 s");
}

fn pd_step_response(pd_form: PdForm, dt_s: f64) -> (Vec<f64>, Vec<f64>) {
    // One joint, no gravity torque, axis inertia 0.01 + armature 0.01 = 0.02 kg·m²;
    // kp 2, kd 0.2: ω0 = 10 rad/s, ζ = 0.5. Target step of 0.5 rad.
    let m = pendulum();
    let settings = PhysicsSettings {
        dt_s,
        fixed_base: true,
        contacts: ContactMode::None,
        pd_form,
        ..Default::default()
    };
    let gains = PdGains {
        kp: vec![2.0],
        kd: vec![0.2],
        effort_limit_nm: vec![100.0],
    };
    let mut p = backend(&m, settings, gains);
    p.reset(&ResetState {
        root: RootState::at_rest(Isometry3::identity()),
        q: vec![0.0],
        qd: vec![0.0],
    });
    p.set_targets(&[0.5]);
    let (i_eff, kp, kd): (f64, f64, f64) = (0.02, 2.0, 0.2);
    let w0 = (kp / i_eff).sqrt();
    let zeta = kd / (2.0 * i_eff * w0);
    let wd = w0 * (1.0 - zeta * zeta).sqrt();
    let (mut sim, mut exact) = (Vec::new(), Vec::new());
    for _ in 0..(2.0 / dt_s) as usize {
        p.step();
        let t = p.time_s();
        sim.push(state_of(p.as_ref()).q[0]);
        let decay = (-zeta * w0 * t).exp();
        exact.push(
            0.5 * (1.0
                - decay * ((wd * t).cos() + zeta / (1.0 - zeta * zeta).sqrt() * (wd * t).sin())),
        );
    }
    (sim, exact)
}

fn rms(a: &[f64], b: &[f64]) -> f64 {
    (a.iter().zip(b).map(|(x, y)| (x - y).powi(2)).sum::<f64>() / a.len() as f64).sqrt()
}

#[test]
fn pd_step_response_matches_the_analytic_second_order_response() {
    // Also checks that armature counts: without it the oscillation would be √2 faster.
    for form in [PdForm::Hybrid, PdForm::Explicit] {
        let (sim, exact) = pd_step_response(form, 0.001);
        let e = rms(&sim, &exact);
        assert!(
            e < 0.005,
            "{form:?}: RMS {e} rad against the analytic response (1 % of the 0.5 rad step)"
        );
    }
    let (sim, exact) = pd_step_response(PdForm::Hybrid, 0.005);
    let e = rms(&sim, &exact);
    assert!(
        e < 0.0125,
        "hybrid at 5 ms: RMS {e} rad (2.5 % of the step)"
    );
}

#[test]
fn pd_torque_is_clamped_to_the_effort_limit() {
    // kp 1000 on a 1 rad error, limit 0.1 N·m: constant torque, q = ½(τ/I)t².
    let m = pendulum();
    let settings = PhysicsSettings {
        dt_s: 0.001,
        fixed_base: true,
        contacts: ContactMode::None,
        ..Default::default()
    };
    let mut p = backend(
        &m,
        settings,
        PdGains {
            kp: vec![1000.0],
            kd: vec![0.0],
            effort_limit_nm: vec![0.1],
        },
    );
    p.reset(&ResetState {
        root: RootState::at_rest(Isometry3::identity()),
        q: vec![0.0],
        qd: vec![0.0],
    });
    p.set_targets(&[1.0]);
    for _ in 0..300 {
        p.step();
    }
    let s = state_of(p.as_ref());
    let t = p.time_s();
    let expected = 0.5 * (0.1 / 0.02) * t * t;
    assert!(
        (s.q[0] - expected).abs() < 0.01 * expected,
        "q {} vs {expected}",
        s.q[0]
    );
    assert!(
        (s.applied_torque_nm[0] - 0.1).abs() < 1e-12,
        "reported torque {}",
        s.applied_torque_nm[0]
    );
}

#[test]
fn a_feedforward_torque_adds_to_the_pd_torque_before_the_clamp() {
    // kp = kd = 0: the feed-forward torque alone, constant, q = ½(τ/I)t²; beyond the
    // 0.1 N·m limit, the limit (the DDS bridge's `τ_ff + kd q̇*`).
    for (feedforward, applied) in [(0.05, 0.05), (1.0, 0.1), (-1.0, -0.1)] {
        let settings = PhysicsSettings {
            dt_s: 0.001,
            fixed_base: true,
            contacts: ContactMode::None,
            ..Default::default()
        };
        let gains = PdGains {
            kp: vec![0.0],
            kd: vec![0.0],
            effort_limit_nm: vec![0.1],
        };
        let mut p = backend(&pendulum(), settings, gains);
        p.reset(&ResetState {
            root: RootState::at_rest(Isometry3::identity()),
            q: vec![0.0],
            qd: vec![0.0],
        });
        p.set_feedforward(&[feedforward]);
        for _ in 0..300 {
            p.step();
        }
        let s = state_of(p.as_ref());
        let t = p.time_s();
        let expected = 0.5 * (applied / 0.02) * t * t;
        assert!(
            (s.q[0] - expected).abs() < 0.01 * expected.abs(),
            "feed-forward {feedforward}: q {} vs {expected}",
            s.q[0]
        );
        assert!(
            (s.applied_torque_nm[0] - applied).abs() < 1e-12,
            "feed-forward {feedforward}: reported torque {}",
            s.applied_torque_nm[0]
        );
    }
}

#[test]
fn joints_have_no_hidden_damping() {
    // rapier gives every new joint 0.1 damping; with kp = kd = 0 a spinning joint must keep
    // its speed (it would lose ~99 % in 1 s at 0.1 N·m·s/rad on 0.02 kg·m²).
    let m = pendulum();
    let settings = PhysicsSettings {
        fixed_base: true,
        contacts: ContactMode::None,
        ..Default::default()
    };
    let mut p = backend(
        &m,
        settings,
        PdGains {
            kp: vec![0.0],
            kd: vec![0.0],
            effort_limit_nm: vec![100.0],
        },
    );
    p.reset(&ResetState {
        root: RootState::at_rest(Isometry3::identity()),
        q: vec![-2.0],
        qd: vec![1.5],
    });
    for _ in 0..200 {
        p.step();
    }
    let s = state_of(p.as_ref());
    assert!(
        (s.qd[0] - 1.5).abs() < 1e-4,
        "joint speed {} after 1 s",
        s.qd[0]
    );
    assert!(
        (s.q[0] - (-2.0 + 1.5)).abs() < 1e-3,
        "joint angle {}",
        s.q[0]
    );
}

#[test]
fn root_velocity_is_read_from_the_generalized_velocity_right_after_reset() {
    let m = g1();
    let mut p = backend(&m, zero_g(ContactMode::None), standing_gains(&m));
    let mut start = standing_default_pose(&m);
    start.root.world_from_root =
        Isometry3::new(Vector3::new(0.0, 0.0, 2.0), Vector3::new(0.0, 0.0, 0.7));
    start.root.lin_vel_w = Vector3::new(0.4, -0.3, 0.2);
    p.reset(&start);
    let r = state_of(p.as_ref()).root.unwrap();
    assert!(
        (r.lin_vel_w - start.root.lin_vel_w).norm() < 1e-5,
        "{:?}",
        r.lin_vel_w
    );
    assert!(r.ang_vel_w.norm() < 1e-6);
    // Base frame: yawed by 0.7 rad.
    let expected_b = start.root.world_from_root.rotation.inverse() * start.root.lin_vel_w;
    assert!((r.lin_vel_b() - expected_b).norm() < 1e-5);
    p.set_targets(&start.q);
    for _ in 0..20 {
        p.step();
    }
    let r = state_of(p.as_ref()).root.unwrap();
    assert!(
        (r.lin_vel_w - start.root.lin_vel_w).norm() < 1e-3,
        "after 0.1 s of free flight: {:?}",
        r.lin_vel_w
    );
    let moved =
        r.world_from_root.translation.vector - start.root.world_from_root.translation.vector;
    assert!(
        (moved - start.root.lin_vel_w * 0.1).norm() < 1e-3,
        "moved {moved:?}"
    );
}

#[test]
fn after_reset_every_body_is_where_forward_kinematics_puts_it() {
    let m = g1();
    let mut p = backend(&m, zero_g(ContactMode::None), standing_gains(&m));
    let q: Vec<f64> = m
        .joints
        .iter()
        .enumerate()
        .map(|(i, j)| {
            let mid = 0.5 * (j.lower_rad + j.upper_rad);
            mid + 0.3 * (i as f64).sin() * (j.upper_rad - j.lower_rad) * 0.5
        })
        .collect();
    let root = Isometry3::new(Vector3::new(0.3, -0.2, 1.5), Vector3::new(0.2, -0.4, 1.1));
    p.reset(&ResetState {
        root: RootState::at_rest(root),
        q: q.clone(),
        qd: vec![0.0; 29],
    });
    let s = state_of(p.as_ref());
    let mut fk = Vec::new();
    robot::forward_kinematics(&m, &root, &q, &mut fk);
    for (i, (a, b)) in s.world_from_body.iter().zip(&fk).enumerate() {
        let dp = (a.translation.vector - b.translation.vector).norm();
        let da = a.rotation.angle_to(&b.rotation);
        assert!(
            dp < 1e-5 && da < 1e-5,
            "body {} off by {dp} m / {da} rad",
            m.bodies[i].name
        );
    }
    for (a, b) in s.q.iter().zip(&q) {
        assert!((a - b).abs() < 1e-6);
    }
}

#[test]
fn multibody_joints_never_separate_while_the_robot_tumbles() {
    // Reduced coordinates: after a fall with impacts every body is still exactly where the
    // joint angles put it (impulse joints drift apart under such loads).
    let m = g1();
    let mut p = backend(
        &m,
        PhysicsSettings {
            contacts: ContactMode::AllShapes,
            ..Default::default()
        },
        legged_gym_gains(&m),
    );
    let mut start = standing_default_pose(&m);
    start.root.world_from_root =
        Isometry3::new(Vector3::new(0.0, 0.0, 0.9), Vector3::new(0.4, 0.2, 0.0));
    start.root.ang_vel_w = Vector3::new(1.0, -2.0, 0.5);
    p.reset(&start);
    p.set_targets(&start.q);
    let mut fk = Vec::new();
    for _ in 0..400 {
        p.step();
    }
    let s = state_of(p.as_ref());
    robot::forward_kinematics(&m, &s.root.as_ref().unwrap().world_from_root, &s.q, &mut fk);
    for (i, (a, b)) in s.world_from_body.iter().zip(&fk).enumerate() {
        let dp = (a.translation.vector - b.translation.vector).norm();
        assert!(
            dp < 1e-4,
            "body {} is {dp} m from its kinematic place",
            m.bodies[i].name
        );
    }
}

fn run_g1_twice_identically() -> Vec<f64> {
    let m = g1();
    let mut p = backend(&m, PhysicsSettings::default(), standing_gains(&m));
    let start = standing_default_pose(&m);
    let mut out = Vec::new();
    for episode in 0..2 {
        p.reset(&start);
        let targets: Vec<f64> = start
            .q
            .iter()
            .enumerate()
            .map(|(i, q)| q + 0.05 * (i as f64).cos())
            .collect();
        p.set_targets(&targets);
        p.set_external_force(ExternalForce {
            body: 15,
            force_w: Vector3::new(10.0, 0.0, 0.0),
            point_b: Point3::origin(),
        });
        for _ in 0..300 {
            p.step();
        }
        let s = state_of(p.as_ref());
        let mut v: Vec<f64> = s.q.iter().chain(&s.qd).copied().collect();
        v.extend(s.root.unwrap().world_from_root.to_homogeneous().iter());
        if episode == 1 {
            return v;
        }
        out = v;
    }
    out
}

#[test]
fn identical_runs_give_bit_identical_state_even_after_a_reset() {
    let a = run_g1_twice_identically();
    let b = run_g1_twice_identically();
    assert_eq!(
        a.iter().map(|x| x.to_bits()).collect::<Vec<_>>(),
        b.iter().map(|x| x.to_bits()).collect::<Vec<_>>()
    );
    // The second episode of a run equals the first: a reset leaves nothing behind.
    let m = g1();
    let mut p = backend(&m, PhysicsSettings::default(), standing_gains(&m));
    let start = standing_default_pose(&m);
    let mut first = Vec::new();
    for episode in 0..2 {
        p.reset(&start);
        p.set_targets(&start.q);
        for _ in 0..100 {
            p.step();
        }
        let s = state_of(p.as_ref());
        if episode == 0 {
            first = s.q.clone();
        } else {
            assert_eq!(first, s.q);
        }
    }
}

#[test]
fn g1_stands_five_seconds_in_its_default_pose_with_stiff_gains() {
    let m = g1();
    let mut p = backend(&m, PhysicsSettings::default(), standing_gains(&m));
    let start = standing_default_pose(&m);
    p.reset(&start);
    p.set_targets(&start.q);
    let z0 = start.root.world_from_root.translation.z;
    for _ in 0..1000 {
        p.step();
    }
    let r = state_of(p.as_ref()).root.unwrap();
    let z = r.world_from_root.translation.z;
    let tilt = r.projected_gravity_b().angle(&-Vector3::z());
    assert!((z - z0).abs() < 0.05, "pelvis height {z} (started at {z0})");
    assert!(tilt < 0.1, "tilt {tilt} rad");
    assert!(
        p.contact_count() >= 4,
        "standing on its soles, {} contacts",
        p.contact_count()
    );
}

#[test]
fn robot_never_falls_asleep() {
    // Islands sleep after 0.5 s of rest by default; a sleeping robot ignores new targets
    // and pushes. Hold still for 2 s, then ask for motion.
    let m = pendulum();
    let settings = PhysicsSettings {
        fixed_base: true,
        contacts: ContactMode::None,
        ..Default::default()
    };
    let mut p = backend(
        &m,
        settings,
        PdGains {
            kp: vec![2.0],
            kd: vec![0.2],
            effort_limit_nm: vec![100.0],
        },
    );
    p.reset(&ResetState {
        root: RootState::at_rest(Isometry3::identity()),
        q: vec![0.0],
        qd: vec![0.0],
    });
    p.set_targets(&[0.0]);
    for _ in 0..400 {
        p.step();
    }
    p.set_targets(&[0.5]);
    for _ in 0..20 {
        p.step();
    }
    let q = state_of(p.as_ref()).q[0];
    assert!(
        q > 0.05,
        "the joint must follow a new target after 2 s at rest (q = {q})"
    );
}

/// Largest arm joint speed after 1 s of holding a pose (infinite if the state blew up).
fn joint_speed_after_hold(pd_form: PdForm) -> f64 {
    // Arms at legged-gym training gains (40 / 5): kd·dt/I ≈ 5 on the wrists at 5 ms.
    let m = g1();
    let settings = PhysicsSettings {
        pd_form,
        fixed_base: true,
        contacts: ContactMode::None,
        ..Default::default()
    };
    let mut p = backend(&m, settings, legged_gym_gains(&m));
    let mut start = standing_default_pose(&m);
    start.root.world_from_root = Isometry3::translation(0.0, 0.0, 1.0);
    let targets = start.q.clone();
    start.q.iter_mut().for_each(|q| *q += 0.05);
    p.reset(&start);
    p.set_targets(&targets);
    for _ in 0..200 {
        p.step();
    }
    let s = state_of(p.as_ref());
    let arms = m.joints.iter().map(|j| {
        ["shoulder", "elbow", "wrist"]
            .iter()
            .any(|k| j.name.contains(k))
    });
    s.qd.iter()
        .zip(arms)
        .filter(|(_, arm)| *arm)
        .map(|(v, _)| {
            if v.is_finite() {
                v.abs()
            } else {
                f64::INFINITY
            }
        })
        .fold(0.0, f64::max)
}

#[test]
fn hybrid_pd_is_stable_at_5_ms_where_explicit_pd_is_not() {
    let hybrid = joint_speed_after_hold(PdForm::Hybrid);
    let explicit = joint_speed_after_hold(PdForm::Explicit);
    assert!(
        hybrid < 0.05,
        "hybrid PD: arm joints still moving at {hybrid} rad/s after 1 s"
    );
    assert!(
        explicit > 5.0,
        "explicit PD should go unstable at 5 ms, max arm joint speed {explicit} rad/s"
    );
}

/// The ground's vertical force on a robot standing still in its default pose holding
/// `payloads` (set on `p`, then reset), averaged over its fourth second (the sag of the
/// first seconds settled), N.
fn standing_ground_force_n(p: &mut dyn Physics, payloads: &[PointMass]) -> f64 {
    let m = p.model().clone();
    p.set_payloads(payloads);
    let start = standing_default_pose(&m);
    p.reset(&start);
    p.set_targets(&start.q);
    let mut contacts = Vec::new();
    let (mut sum, mut n) = (0.0, 0);
    for k in 0..4000 {
        p.step();
        if k >= 3000 {
            p.ground_contacts(&mut contacts);
            sum += contacts.iter().map(|c| c.normal_n).sum::<f64>();
            n += 1;
        }
    }
    sum / n as f64
}

#[test]
fn a_payload_of_m_kg_weighs_m_g_at_each_hand_holding_it() {
    let m = g1();
    let g = PhysicsSettings::default().gravity[2].abs();
    let at_hand = |side: usize, mass_kg: f64| {
        let hand = &m.hands[side];
        let frame = &m.frames[hand.frame];
        PointMass {
            body: frame.body,
            mass_kg,
            point_b: frame.body_from_frame * hand.point_hand,
        }
    };
    let mut p = backend(&m, PhysicsSettings::default(), standing_gains(&m));
    let p = p.as_mut();
    let bare = standing_ground_force_n(p, &[]);
    assert!(
        (bare - m.total_mass_kg() * g).abs() < 0.01 * bare,
        "standing still, the ground carries the robot: {bare} N vs {} N",
        m.total_mass_kg() * g
    );
    let one = standing_ground_force_n(p, &[at_hand(0, 3.0)]) - bare;
    let both = standing_ground_force_n(p, &[at_hand(0, 2.0), at_hand(1, 2.0)]) - bare;
    assert!((one - 3.0 * g).abs() < 0.3, "3 kg in the left hand adds {one} N");
    assert!((both - 4.0 * g).abs() < 0.3, "2 kg in each hand adds {both} N");
    // Set back to none on the same engine, the next reset carries the robot alone again.
    let cleared = standing_ground_force_n(p, &[]);
    assert!((cleared - bare).abs() < 1e-6);
}
