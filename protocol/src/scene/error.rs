//! Why a scene is refused, and the helpers every section's validation words its errors with.

/// A scene that could not be read or is inconsistent.
#[derive(Debug, thiserror::Error, PartialEq, Eq)]
pub enum SceneError {
    /// TOML syntax or type error.
    #[error("{file}: key `{path}`: {message}")]
    Parse {
        /// The scene file.
        file: String,
        /// Key path (`fluid.cfl`), empty at top level.
        path: String,
        /// The parser's message (says what was expected and found, with line and column).
        message: String,
    },
    /// A value that parses but is not acceptable.
    #[error("{file}: key `{path}`: expected {expected}, found {found}")]
    Invalid {
        /// The scene file.
        file: String,
        /// Key path.
        path: String,
        /// What is acceptable.
        expected: String,
        /// What was there.
        found: String,
    },
}

/// What every section's validation needs: the file (for the errors) and the scene's
/// dimension.
pub(super) struct Check<'a> {
    /// The scene file, named in errors.
    pub(super) file: &'a str,
    /// Spatial dimension of the scene.
    pub(super) dim: usize,
}

impl Check<'_> {
    /// An `Invalid` error at `path`.
    pub(super) fn invalid(&self, path: &str, expected: &str, found: String) -> SceneError {
        SceneError::Invalid {
            file: self.file.to_string(),
            path: path.to_string(),
            expected: expected.to_string(),
            found,
        }
    }

    /// `v` is a finite number > 0.
    pub(super) fn positive(&self, path: &str, v: f64) -> Result<(), SceneError> {
        if v.is_finite() && v > 0.0 {
            Ok(())
        } else {
            Err(self.invalid(path, "a finite number > 0", format!("{v}")))
        }
    }

    /// `v` has one finite entry per axis.
    pub(super) fn check_len(&self, path: &str, v: &[f64]) -> Result<(), SceneError> {
        let dim = self.dim;
        if v.len() == dim && v.iter().all(|x| x.is_finite()) {
            Ok(())
        } else {
            Err(self.invalid(
                path,
                &format!("{dim} finite numbers (the scene is {dim}-D)"),
                quote_list(v),
            ))
        }
    }
}

pub(super) fn check_node_impl(
    path: &str,
    value: &str,
    known: &[&str],
    file: &str,
) -> Result<(), SceneError> {
    node_impl(value, known).map_err(|expected| SceneError::Invalid {
        file: file.to_string(),
        path: path.to_string(),
        expected,
        found: format!("{value:?}"),
    })
}

/// The fluid node's implementations besides `replay:FILE.mcap` (`fluid.node`, `run --fluid`).
pub const FLUID_NODES: [&str; 2] = ["real", "pressure"];
/// The solid node's implementations besides `replay:FILE.mcap` (`solid.node`, `run --solid`).
pub const SOLID_NODES: [&str; 2] = ["real", "prescribed"];

/// Whether `value` names a node implementation: one of `known` or `replay:FILE`; else what was
/// expected, with the nearest name suggested.
pub fn node_impl(value: &str, known: &[&str]) -> Result<(), String> {
    if known.contains(&value) || value.strip_prefix("replay:").is_some_and(|f| !f.is_empty()) {
        return Ok(());
    }
    Err(format!(
        "one of {known:?} or \"replay:FILE.mcap\"{}",
        crate::suggest::did_you_mean(value, known)
    ))
}

/// Longest quoted value or message line in an error, in bytes.
const QUOTE_MAX: usize = 160;

/// A list quoted for an error: its entries, or for a long list the first ones and the count (a
/// 50 MB array must not come back whole on stderr).
pub(super) fn quote_list<T: std::fmt::Debug>(list: &[T]) -> String {
    let whole = format!("{list:?}");
    if whole.len() <= QUOTE_MAX {
        return whole;
    }
    let mut head = String::from("[");
    for (k, v) in list.iter().enumerate() {
        let next = format!("{}{v:?}", if k == 0 { "" } else { ", " });
        if head.len() + next.len() > QUOTE_MAX {
            break;
        }
        head.push_str(&next);
    }
    format!("{head}, ...] ({} entries)", list.len())
}

/// A message with every line longer than [`QUOTE_MAX`] cut (the TOML parser quotes the line of
/// the error, which can be megabytes long); serde's "unknown field" and "unknown variant" lines
/// get a "did you mean" and keep their whole list of valid names (see [`explain_unknown`]).
pub(super) fn shorten_lines(message: &str) -> String {
    message
        .lines()
        .map(|line| {
            if let Some(explained) = explain_unknown(line) {
                return explained;
            }
            if line.len() <= QUOTE_MAX {
                return line.to_string();
            }
            let cut = (0..=QUOTE_MAX)
                .rev()
                .find(|&i| line.is_char_boundary(i))
                .unwrap_or(0);
            format!("{}... ({} more bytes)", &line[..cut], line.len() - cut)
        })
        .collect::<Vec<_>>()
        .join("\n")
}

/// serde's `unknown field `x`, expected one of `a`, `b`` (or `unknown variant`) with the
/// nearest valid name suggested and the list kept whole: it is the schema's, a few hundred
/// bytes at most (cut, a misspelt key's message ended mid-list), while the misspelt name, the
/// user's, is cut to [`QUOTE_MAX`].
fn explain_unknown(line: &str) -> Option<String> {
    let (what, rest) = ["unknown field `", "unknown variant `"]
        .into_iter()
        .find_map(|p| line.strip_prefix(p).map(|rest| (&p[..p.len() - 2], rest)))?;
    let (name, expected) = rest.split_once("`, expected ")?;
    let valid: Vec<&str> = expected.split('`').skip(1).step_by(2).collect();
    if valid.is_empty() {
        return None;
    }
    let shown = if name.len() > QUOTE_MAX {
        let cut = (0..=QUOTE_MAX)
            .rev()
            .find(|&i| name.is_char_boundary(i))
            .unwrap_or(0);
        format!("{}...", &name[..cut])
    } else {
        name.to_string()
    };
    let list: Vec<String> = valid.iter().map(|v| format!("`{v}`")).collect();
    Some(format!(
        "{what} `{shown}`{}; valid here: {}",
        crate::suggest::did_you_mean(name, &valid),
        list.join(", ")
    ))
}
