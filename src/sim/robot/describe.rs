//! A robot model as a human-readable table.

use super::RobotModel;

/// A robot model as people read it (what `robot info` prints): joints in canonical
/// order with their limits, armature and default position, bodies, keypoints and hands.
pub fn describe(model: &RobotModel) -> String {
    use std::fmt::Write;
    let mut s = String::new();
    let _ = writeln!(
        s,
        "robot {}: {} joints, {} bodies, total mass {:.3} kg",
        model.name,
        model.n_joints(),
        model.bodies.len(),
        model.total_mass_kg()
    );
    let _ = writeln!(s, "\njoints (canonical order):");
    let _ = writeln!(
        s,
        "  {:>2}  {:<28} {:>9} {:>9} {:>8} {:>8} {:>10} {:>8}",
        "#", "name", "lower", "upper", "effort", "vel", "armature", "default"
    );
    let _ = writeln!(
        s,
        "  {:>2}  {:<28} {:>9} {:>9} {:>8} {:>8} {:>10} {:>8}",
        "", "", "rad", "rad", "N·m", "rad/s", "kg·m²", "rad"
    );
    for (i, j) in model.joints.iter().enumerate() {
        let _ = writeln!(
            s,
            "  {:>2}  {:<28} {:>9.4} {:>9.4} {:>8.1} {:>8.1} {:>10.6} {:>8.3}",
            i,
            j.name,
            j.lower_rad,
            j.upper_rad,
            j.effort_nm,
            j.velocity_rad_s,
            j.armature_kgm2,
            j.default_rad
        );
    }
    let _ = writeln!(s, "\nbodies (fixed links merged into their parent):");
    for (i, b) in model.bodies.iter().enumerate() {
        let merged: Vec<&str> = model
            .frames
            .iter()
            .filter(|f| f.body == i && f.name != b.name)
            .map(|f| f.name.as_str())
            .collect();
        let parent = b
            .parent
            .map_or("-".to_string(), |p| model.bodies[p].name.clone());
        let _ = write!(
            s,
            "  {:>2}  {:<28} {:>7.4} kg  parent {:<26} shapes {}",
            i,
            b.name,
            b.mass_kg,
            parent,
            b.shapes.len()
        );
        if !merged.is_empty() {
            let _ = write!(s, "  + {}", merged.join(", "));
        }
        let _ = writeln!(s);
    }
    let _ = writeln!(s, "\nkeypoint sets:");
    for k in &model.keypoint_sets {
        let names = |r: &[usize]| {
            r.iter()
                .map(|&f| model.frames[f].name.as_str())
                .collect::<Vec<_>>()
                .join(", ")
        };
        let _ = writeln!(s, "  {} ({} points)", k.name, k.frames.len());
        let _ = writeln!(s, "    upper: {}", names(&k.frames[..k.n_upper]));
        let _ = writeln!(s, "    lower: {}", names(&k.frames[k.n_upper..]));
    }
    let _ = writeln!(s, "\nhands:");
    for (side, h) in ["left", "right"].iter().zip(&model.hands) {
        let f = &model.frames[h.frame];
        let (r, p, y) = h.hand_from_sensor.euler_angles();
        let _ = writeln!(
            s,
            "  {side:<5} frame {} (body {}), point [{:.4}, {:.4}, {:.4}] m, hand_from_sensor rpy [{r:.3}, {p:.3}, {y:.3}] rad",
            f.name, model.bodies[f.body].name, h.point_hand.x, h.point_hand.y, h.point_hand.z
        );
    }
    s
}
