//! What touches the disk, below everything else: whole files written atomically
//! ([`atomic_file`]), output files opened without following a planted link
//! ([`no_follow`]), files read only when regular and within their kind's size
//! ([`bounded_read`]), content hashes ([`content_hash`]), outside names checked before
//! they become paths ([`names`]), the logs of processes a run starts, capped
//! ([`capped_log`]), and the text quoted back from them ([`log_text`]), and the bundled data compiled into the binary
//! ([`embedded_data`]).

pub mod atomic_file;
pub mod bounded_read;
pub mod capped_log;
pub mod content_hash;
pub mod embedded_data;
pub mod log_text;
pub mod names;
pub mod no_follow;
