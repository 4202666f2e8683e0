//! Many evaluations at once: [`sweep`]s over axes, run locally or as one task of a cluster
//! engine's array; the [`leaderboard`] of several policies on one dataset; what a run
//! costs ([`bench`](mod@bench), behind `thorarena bench`); a dataset's check with a tracker's
//! rollouts ([`data_check`]); and the `thorarena` command lines the
//! library runs or writes for a cluster to run ([`own_command`]).

pub mod bench;
pub mod data_check;
pub mod leaderboard;
pub mod own_command;
pub mod sweep;
