//! (being written: placeholder with the agreed API)
#![allow(missing_docs)]
pub fn read_beyondmimic_npz(
    _path: &std::path::Path,
    _joint_names: Option<&[String]>,
) -> Result<super::RawMotion, super::ImportError> {
    unimplemented!()
}
