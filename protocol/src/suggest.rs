//! "Did you mean": the nearest of a list of valid words to a misspelt one (scene keys and
//! command-line values).

/// The candidate nearest to `word` by optimal string alignment distance (a transposition costs
/// one, so `cvs` is one from `csv`), if it is within a third of the longer word's length (at
/// least one edit); ties go to the first candidate.
pub fn nearest<'a>(word: &str, candidates: &[&'a str]) -> Option<&'a str> {
    let mut best: Option<(usize, &'a str)> = None;
    for &c in candidates {
        let d = strsim::osa_distance(word, c);
        let limit = (word.chars().count().max(c.chars().count()) / 3).max(1);
        if d <= limit && best.is_none_or(|(b, _)| d < b) {
            best = Some((d, c));
        }
    }
    best.map(|(_, c)| c)
}

/// `" (did you mean `X`?)"` for the candidate [`nearest`] to `word`, or nothing.
pub fn did_you_mean(word: &str, candidates: &[&str]) -> String {
    nearest(word, candidates).map_or_else(String::new, |c| format!(" (did you mean `{c}`?)"))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn finds_transpositions_typos_and_nothing_far() {
        assert_eq!(nearest("cvs", &["json", "csv"]), Some("csv"));
        assert_eq!(nearest("gama", &["node", "gamma", "cfl"]), Some("gamma"));
        assert_eq!(nearest("pressur", &["real", "pressure"]), Some("pressure"));
        assert_eq!(
            nearest("velocty", &["rho", "p", "velocity"]),
            Some("velocity")
        );
        // Too far from every candidate: no suggestion rather than a wrong one.
        assert_eq!(nearest("xyz", &["json", "csv"]), None);
        assert_eq!(nearest("cells", &["gamma", "cfl"]), None);
        assert_eq!(
            did_you_mean("jsno", &["json", "csv"]),
            " (did you mean `json`?)"
        );
        assert_eq!(did_you_mean("zzzz", &["json", "csv"]), "");
    }
}
