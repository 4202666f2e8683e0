//! (being written: placeholder with the agreed API)
#![allow(missing_docs)]
pub fn read_twist_pkl(_path: &std::path::Path) -> Result<super::RawMotion, super::ImportError> {
    unimplemented!()
}
