//! (being written: placeholder with the agreed API)
#![allow(missing_docs)]
pub fn read_lafan_csv(
    _path: &std::path::Path,
    _fps: f64,
) -> Result<super::RawMotion, super::ImportError> {
    unimplemented!()
}
