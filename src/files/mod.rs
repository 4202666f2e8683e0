//! What touches the disk, below everything else: whole files written atomically
//! ([`atomic_file`]), content hashes ([`content_hash`]), outside names checked before they become paths ([`names`]), and the
//! bundled data compiled into the binary ([`embedded_data`]).

pub mod atomic_file;
pub mod content_hash;
pub mod embedded_data;
pub mod names;
