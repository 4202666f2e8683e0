//! What a benchmark says as it runs, one line at a time and in the order it happens: a
//! table's row is handed over as soon as it is measured, so a caller watching a run of
//! several minutes sees each figure when it exists, not all of them at the end.

/// A line of a benchmark's output.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum BenchLine {
    /// Part of the figures: a heading, a Markdown table's row, a measurement with its
    /// ratio (`thorarena bench …` prints it on standard output).
    Figure(String),
    /// Beside the figures: progress, a client skipped or refused, advice on the request
    /// (standard error). A user's option is named by its field in backticks,
    /// `` `option.ipc_lib` ``.
    Note(String),
}
