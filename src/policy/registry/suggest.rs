//! "Did you mean …?" for names a user types (policies, profiles): the closest known name
//! by edit distance, when it is close enough to be a typo rather than another word.

/// The candidate closest to `given`, if within two edits (or a third of its length).
pub fn closest<'a>(given: &str, candidates: impl IntoIterator<Item = &'a str>) -> Option<&'a str> {
    let limit = 2.max(given.chars().count() / 3);
    candidates
        .into_iter()
        .map(|c| (strsim::levenshtein(given, c), c))
        .filter(|(d, _)| *d <= limit)
        .min_by_key(|(d, _)| *d)
        .map(|(_, c)| c)
}

/// ` (did you mean `x`?)`, or nothing.
pub fn did_you_mean<'a>(given: &str, candidates: impl IntoIterator<Item = &'a str>) -> String {
    closest(given, candidates).map_or_else(String::new, |c| format!(" (did you mean `{c}`?)"))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn typos_get_the_nearest_name_and_other_words_nothing() {
        let names = ["hold", "replay", "balance"];
        assert_eq!(closest("balanc", names), Some("balance"));
        assert_eq!(closest("hodl", names), Some("hold"));
        assert_eq!(
            closest("twist", ["default", "twist2", "gmt"]),
            Some("twist2")
        );
        assert_eq!(closest("mjlab", names), None);
    }
}
