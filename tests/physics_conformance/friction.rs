// Physics-only friction checks, included once per backend by `tests/physics_conformance.rs`
// next to the suite (each inclusion defines its own `backend`).
//
// A 10 kg block on the G1's four 5 mm sole spheres (made a multibody by a hinged 1 kg disc,
// so its contacts take the robot's solver path) against Coulomb's law: held below the
// friction limit, sliding at the analytic acceleration above it, and stopping within the
// analytic distance when it lands or slides with tangential speed; and how a landing is
// absorbed. No network, no robot controller: where an engine departs from Coulomb here, it
// departs under a walking robot.
//
// Known differences, asserted at their measured values so that a change in either engine
// is noticed (docs/engines.md, "Force response: rapier against MuJoCo"):
// - MuJoCo's friction is a soft constraint: held at 0.8·μ·m·g a block creeps (8.7 mm in
//   1 s at μ 1); rapier's holds (< 1 mm).
// - MuJoCo absorbs a touchdown over its contact time constant (20 ms by default): a block
//   landing at 0.5 m/s sinks ~3.5 mm and the force builds over several steps; rapier stops
//   it within one step with a fraction of a millimetre.

fn sole_block() -> Arc<RobotModel> {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/sole_block");
    Arc::new(robot::load_robot_dir(&dir).unwrap())
}

/// The disc held still on its hinge.
fn sole_block_gains() -> PdGains {
    PdGains {
        kp: vec![20.0],
        kd: vec![1.0],
        effort_limit_nm: vec![50.0],
    }
}

const G: f64 = 9.81;

/// A sole block on the ground (resting on its soles) with `friction`, started with the
/// root's linear velocity `v0_w` and lifted by `lift_m`.
fn sole_block_on_ground(friction: f64, lift_m: f64, v0_w: Vector3<f64>) -> Box<dyn Physics> {
    let m = sole_block();
    let settings = PhysicsSettings {
        friction,
        ..Default::default()
    };
    let mut p = backend(&m, settings, sole_block_gains());
    let mut start = standing_default_pose(&m);
    start.root.world_from_root.translation.z += lift_m;
    start.root.lin_vel_w = v0_w;
    p.reset(&start);
    p.set_targets(&start.q);
    p
}

fn block_x(p: &dyn Physics) -> f64 {
    state_of(p).root.unwrap().world_from_root.translation.x
}

fn block_speed_x(p: &dyn Physics) -> f64 {
    state_of(p).root.unwrap().lin_vel_w.x
}

/// Slide of a settled block under a horizontal force of `ratio`·μ·m·g at its centre of
/// mass for `seconds`, m.
fn slide_under_force(friction: f64, ratio: f64, seconds: f64) -> f64 {
    let mut p = sole_block_on_ground(friction, 0.0, Vector3::zeros());
    let dt = p.settings().dt_s;
    for _ in 0..(0.5 / dt) as usize {
        p.step();
    }
    let mass = p.model().total_mass_kg();
    let x0 = block_x(p.as_ref());
    p.set_external_force(ExternalForce {
        body: 0,
        force_w: Vector3::new(ratio * friction * mass * G, 0.0, 0.0),
        point_b: Point3::from(p.model().bodies[0].com_b),
    });
    for _ in 0..(seconds / dt).round() as usize {
        p.step();
    }
    block_x(p.as_ref()) - x0
}

#[test]
fn ground_contacts_report_the_ground_reaction_on_a_pushed_block() {
    // Held at rest by friction under a horizontal push: the ground's normal force carries
    // the weight and its friction cancels the push, point by point summed.
    let friction = 1.0;
    let mut p = sole_block_on_ground(friction, 0.0, Vector3::zeros());
    let dt = p.settings().dt_s;
    let mass = p.model().total_mass_kg();
    let push = Vector3::new(0.5 * friction * mass * G, 0.0, 0.0);
    p.set_external_force(ExternalForce {
        body: 0,
        force_w: push,
        point_b: Point3::from(p.model().bodies[0].com_b),
    });
    for _ in 0..(1.0 / dt) as usize {
        p.step();
    }
    let mut contacts = Vec::new();
    p.ground_contacts(&mut contacts);
    let normal: f64 = contacts.iter().map(|c| c.normal_n).sum();
    let friction_w: Vector3<f64> = contacts.iter().map(|c| c.friction_w).sum();
    eprintln!(
        "{} contacts, normal {normal:.1} N (weight {:.1}), friction {friction_w:?} (push {push:?})",
        contacts.len(),
        mass * G
    );
    assert_eq!(contacts.len(), 4, "one contact per sole sphere");
    assert!(contacts.iter().all(|c| c.body == 0 && c.point_b.z < -0.03));
    assert!((normal - mass * G).abs() < 0.02 * mass * G, "normal {normal} N");
    assert!(
        (friction_w + push).norm() < 0.02 * push.norm(),
        "friction {friction_w:?} against a push of {push:?}"
    );
}

#[test]
fn sole_block_holds_below_the_friction_limit() {
    for friction in [0.3, 1.0] {
        let slide = slide_under_force(friction, 0.8, 1.0);
        eprintln!("{ENGINE} μ {friction}: 0.8·μmg for 1 s slides {:.4} m", slide);
        // Measured: rapier 0.1 / 0.2 mm; MuJoCo (soft friction) 1.2 / 8.7 mm.
        let bound = match (ENGINE, friction == 1.0) {
            ("mujoco", true) => 0.012,
            _ => 0.002,
        };
        assert!(
            slide.abs() < bound,
            "{ENGINE} μ {friction}: a tangential force of 0.8·μ·m·g slid the block {slide:.4} m in 1 s"
        );
        if ENGINE == "mujoco" && friction == 1.0 {
            assert!(
                slide > 0.005,
                "MuJoCo's soft friction no longer creeps ({slide:.4} m): update docs/engines.md and this test"
            );
        }
    }
}

/// A block dropped onto the ground from `lift_m` at `vz` m/s: its deepest sinking below
/// its resting height, m, and the number of steps whose ground force exceeds one and a half times its weight.
fn landing(lift_m: f64, vz: f64) -> (f64, usize) {
    let mut p = sole_block_on_ground(1.0, lift_m, Vector3::new(0.0, 0.0, vz));
    let z_rest = {
        let m = sole_block();
        standing_default_pose(&m).root.world_from_root.translation.z
    };
    let weight = p.model().total_mass_kg() * G;
    let mut contacts = Vec::new();
    let (mut deepest, mut loaded_steps) = (0.0_f64, 0);
    for _ in 0..40 {
        p.step();
        p.ground_contacts(&mut contacts);
        let z = state_of(p.as_ref()).root.unwrap().world_from_root.translation.z;
        deepest = deepest.max(z_rest - z);
        if contacts.iter().map(|c| c.normal_n).sum::<f64>() > 1.5 * weight {
            loaded_steps += 1;
        }
    }
    (deepest, loaded_steps)
}

#[test]
fn sole_block_touchdown_is_absorbed_as_each_engine_absorbs_it() {
    // From 4 mm at 0.5 m/s (as a foot touches down): measured, rapier sinks 0.17 mm with
    // its ground force above 1.5 × the weight for 2 steps; MuJoCo sinks 3.5 mm, above it for 4 steps.
    let (deepest, loaded_steps) = landing(0.004, -0.5);
    eprintln!(
        "{ENGINE}: touchdown at 0.5 m/s sinks {:.2} mm, {loaded_steps} steps above 1.5 × the weight",
        deepest * 1e3
    );
    match ENGINE {
        "rapier" => assert!(
            deepest < 0.0005 && loaded_steps <= 3,
            "rapier's contact is no longer rigid at touchdown: update docs/engines.md and this test"
        ),
        _ => assert!(
            (0.002..0.006).contains(&deepest) && loaded_steps >= 4,
            "MuJoCo's touchdown changed: update docs/engines.md and this test"
        ),
    }
}

#[test]
fn sole_block_slides_above_the_friction_limit_at_the_coulomb_acceleration() {
    // F = 1.25·μ·m·g: a = 0.25·μ·g, so x(1 s) = 0.125·μ·g.
    for friction in [0.3, 1.0] {
        let slide = slide_under_force(friction, 1.25, 1.0);
        let expected = 0.5 * 0.25 * friction * G;
        eprintln!("{ENGINE} μ {friction}: 1.25·μmg for 1 s slides {slide:.4} m (Coulomb {expected:.4})");
        assert!(
            (slide - expected).abs() < 0.1 * expected,
            "μ {friction}: slid {slide:.4} m, Coulomb says {expected:.4} m"
        );
    }
}

/// Distance a block travels from the first step with a sole in contact until it is at
/// rest, m, and the time that took, s.
fn slide_to_rest(friction: f64, lift_m: f64, v0_w: Vector3<f64>) -> (f64, f64) {
    let mut p = sole_block_on_ground(friction, lift_m, v0_w);
    let dt = p.settings().dt_s;
    let mut touch: Option<(f64, f64)> = None;
    for _ in 0..(2.0 / dt) as usize {
        p.step();
        if touch.is_none() && p.contact_count() > 0 {
            touch = Some((block_x(p.as_ref()), p.time_s()));
        }
        if let Some((x_touch, t_touch)) = touch {
            if block_speed_x(p.as_ref()).abs() < 1e-3 {
                return (block_x(p.as_ref()) - x_touch, p.time_s() - t_touch);
            }
        }
    }
    panic!("the block never came to rest (contact: {touch:?})");
}

#[test]
fn sole_block_sliding_at_one_metre_per_second_stops_at_the_coulomb_distance() {
    // Already on the ground: d = v²/(2μg), t = v/(μg).
    for friction in [0.3, 1.0] {
        let v = 1.0;
        let (d, t) = slide_to_rest(friction, 0.0, Vector3::new(v, 0.0, 0.0));
        let (d_c, t_c) = (v * v / (2.0 * friction * G), v / (friction * G));
        eprintln!("μ {friction}: slid {d:.4} m in {t:.3} s (Coulomb {d_c:.4} m in {t_c:.3} s)");
        assert!(
            (d - d_c).abs() < 0.15 * d_c + 0.005,
            "μ {friction}: slid {d:.4} m, Coulomb {d_c:.4} m"
        );
    }
}

#[test]
fn sole_block_landing_with_tangential_speed_stops_within_the_coulomb_distance() {
    // A foot touching down: 1 m/s forward and 0.5 m/s down from 2 cm. The impact's normal
    // impulse can only shorten the slide (its friction takes up to μ·m·Δv_n of momentum at
    // once), so the slide from touchdown is at most v²/(2μg).
    for friction in [0.3, 1.0] {
        let v = 1.0;
        let (d, t) = slide_to_rest(friction, 0.02, Vector3::new(v, 0.0, -0.5));
        let d_c = v * v / (2.0 * friction * G);
        let v_after_impact = (v - friction * 0.5).max(0.0);
        let d_min = v_after_impact * v_after_impact / (2.0 * friction * G);
        eprintln!(
            "μ {friction}: landed and slid {d:.4} m in {t:.3} s (Coulomb: {d_min:.4}..{d_c:.4} m)"
        );
        assert!(
            d < 1.1 * d_c + 0.005,
            "μ {friction}: slid {d:.4} m after touchdown, Coulomb allows at most {d_c:.4} m"
        );
    }
}
