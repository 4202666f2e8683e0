//! `sweep status`: [`thorarena::sweep::SweepStatus`] — tasks by state (done only when the
//! run counts), failure reasons, the not-done set.

use super::super::flags::as_flags;
use super::StatusArgs;

pub(super) fn status(args: &StatusArgs) -> anyhow::Result<()> {
    let status = thorarena::sweep::SweepStatus::read(&args.dir)?;
    // The task records quote policy output as it is; only the last line names a field.
    print!("{status}");
    println!("{}", as_flags(&status.not_done_line()));
    Ok(())
}
