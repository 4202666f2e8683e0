//! `thorarena policies`: every policy family a run can name, what a user supplies for it,
//! the profile it runs under when `--profile` is not given, and where it runs.

pub(super) fn run() -> anyhow::Result<()> {
    print!(
        "{}",
        super::flags::as_flags(&thorarena::registry::families_text())
    );
    Ok(())
}
