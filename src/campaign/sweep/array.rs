//! Index sets as compact range expressions (`0-3,5,7-9`), the syntax of Slurm's
//! `--array`.

/// `indices` (any order, duplicates allowed) as `a-b,c,…`; empty for none.
pub fn compact_ranges(indices: &[usize]) -> String {
    let mut v = indices.to_vec();
    v.sort_unstable();
    v.dedup();
    let mut parts = Vec::new();
    let mut i = 0;
    while i < v.len() {
        let start = v[i];
        let mut end = start;
        while i + 1 < v.len() && v[i + 1] == end + 1 {
            i += 1;
            end = v[i];
        }
        parts.push(if start == end {
            start.to_string()
        } else {
            format!("{start}-{end}")
        });
        i += 1;
    }
    parts.join(",")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ranges_are_compacted_in_order() {
        assert_eq!(compact_ranges(&[]), "");
        assert_eq!(compact_ranges(&[4]), "4");
        assert_eq!(compact_ranges(&[3, 0, 1, 2, 5, 7, 8, 9, 9]), "0-3,5,7-9");
        assert_eq!(compact_ranges(&[10, 12]), "10,12");
    }
}
