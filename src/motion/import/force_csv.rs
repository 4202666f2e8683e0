//! (being written: placeholder with the agreed API)
#![allow(missing_docs, dead_code)]
use std::path::Path;
#[derive(Debug, Clone, PartialEq)]
pub struct ForceLog {
    pub time_s: Vec<f64>,
    pub force_n: Vec<[f64; 3]>,
}
pub fn read_force_csv(_path: &Path) -> Result<ForceLog, super::ImportError> {
    unimplemented!()
}
impl ForceLog {
    pub fn resample(&self, _times_s: &[f64], _offset_s: f64) -> (Vec<[f64; 3]>, usize) {
        unimplemented!()
    }
}
