//! `thorarena robot info`: a human-readable dump of a robot model.

/// Arguments of `robot info`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Bundled robot name (under data/robots/) or a robot directory.
    #[arg(long, default_value = "g1_29dof")]
    pub robot: String,
}

/// Arguments of `robot mjcf`.
#[derive(Debug, clap::Args)]
pub struct MjcfArgs {
    /// Bundled robot name (under data/robots/) or a robot directory.
    #[arg(long, default_value = "g1_29dof")]
    pub robot: String,
    /// Physics step written into the MJCF's `<option timestep>`, s (eval sets its own).
    #[arg(long, default_value_t = thorarena::physics::PhysicsSettings::default().dt_s)]
    pub physics_dt: f64,
}

/// `robot mjcf`: the generated MJCF on stdout.
pub(super) fn mjcf(args: &MjcfArgs) -> anyhow::Result<()> {
    let model = thorarena::registry::robot(&args.robot)?;
    let settings = thorarena::physics::PhysicsSettings {
        dt_s: args.physics_dt,
        ..Default::default()
    };
    print!("{}", thorarena::physics::mjcf_of(&model, &settings));
    Ok(())
}

pub(super) fn run(args: &Args) -> anyhow::Result<()> {
    let model = thorarena::registry::robot(&args.robot)?;
    print!("{}", thorarena::robot::describe(&model));
    Ok(())
}
