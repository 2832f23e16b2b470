//! Lengths: no `.rs` file of the workspace over [`MAX_FILE_LINES`] lines and no function over
//! [`MAX_FN_LINES`], but those on [`ALLOWED`], a list that can only shrink: an entry that no
//! longer exceeds its limit (or names a file or function that is gone) fails the test until it
//! is removed.
//!
//! How lengths are measured:
//! - a file: its number of lines;
//! - a function: the lines from the one of its `fn` keyword to the one of its closing brace,
//!   both counted. The closing brace is the first line after the signature that has the `fn`
//!   line's indentation and starts with `}` (where rustfmt puts it). The signature ends on the
//!   first line that ends with `{` (a body follows), `;` (no body: a trait item, not measured)
//!   or `}` (a body on one line). Doc comments and attributes above the `fn` line are not
//!   counted; a nested function is measured on its own and counts in its parent's lines too.

use std::path::Path;

/// The longest a `.rs` file may be, in lines.
const MAX_FILE_LINES: usize = 800;
/// The longest a function may be, in lines (see the module docs for how they are counted).
const MAX_FN_LINES: usize = 150;

/// What an allow-list entry lets exceed its limit.
#[derive(Clone, Copy, Debug, PartialEq)]
#[allow(
    dead_code,
    reason = "the allow-list is empty since issue 34 split the last long items"
)]
enum Item {
    /// The whole file (over [`MAX_FILE_LINES`]).
    File,
    /// Every function of this name in the file (over [`MAX_FN_LINES`]).
    Fn(&'static str),
}

/// An exception to the limits, with the reason it stands.
struct Allowed {
    /// Path from the workspace root, with `/`.
    path: &'static str,
    item: Item,
    reason: &'static str,
}

/// The exceptions. Remove an entry once its item is within the limit (the test says which).
const ALLOWED: &[Allowed] = &[];

/// A function found in a file: its name, the line of its `fn` (from 1) and its length.
#[derive(Debug, PartialEq)]
struct FnLength {
    name: String,
    line: usize,
    lines: usize,
}

/// The name of the function a line declares, if it does (`pub(crate) const fn name<...>(`).
fn declared_fn(line: &str) -> Option<&str> {
    let mut rest = line.trim_start();
    loop {
        let before = rest;
        for qualifier in [
            "pub ",
            "const ",
            "async ",
            "unsafe ",
            "extern \"C\" ",
            "default ",
        ] {
            rest = rest.strip_prefix(qualifier).unwrap_or(rest);
        }
        if let Some(scoped) = rest.strip_prefix("pub(") {
            rest = scoped.split_once(") ").map_or(rest, |(_, after)| after);
        }
        if rest == before {
            break;
        }
    }
    let name = rest.strip_prefix("fn ")?;
    let end = name
        .find(|c: char| !(c.is_alphanumeric() || c == '_'))
        .unwrap_or(name.len());
    let name = &name[..end];
    name.starts_with(|c: char| c.is_alphabetic() || c == '_')
        .then_some(name)
}

fn indentation(line: &str) -> usize {
    line.len() - line.trim_start().len()
}

/// The line without a trailing `// comment` (a `//` after a space; good enough for rustfmt'd
/// code, where a signature line never holds one inside a string).
fn without_comment(line: &str) -> &str {
    line.find(" //").map_or(line, |at| &line[..at]).trim_end()
}

/// Every function with a body in `text`, with its length (see the module docs).
fn function_lengths(text: &str) -> Vec<FnLength> {
    let lines: Vec<&str> = text.lines().collect();
    let mut found = Vec::new();
    for (start, line) in lines.iter().enumerate() {
        let Some(name) = declared_fn(line) else {
            continue;
        };
        let Some(signature_end) = (start..lines.len()).find(|&i| {
            let code = without_comment(lines[i]);
            code.ends_with('{') || code.ends_with(';') || code.ends_with('}')
        }) else {
            continue;
        };
        let code = without_comment(lines[signature_end]);
        let end = if code.ends_with(';') {
            continue;
        } else if code.ends_with('}') {
            Some(signature_end)
        } else {
            let indent = indentation(line);
            (signature_end + 1..lines.len()).find(|&i| {
                indentation(lines[i]) == indent && lines[i].trim_start().starts_with('}')
            })
        };
        if let Some(end) = end {
            found.push(FnLength {
                name: name.to_string(),
                line: start + 1,
                lines: end - start + 1,
            });
        }
    }
    found
}

/// The workspace's `.rs` files: path from the workspace root (with `/`) and text.
fn sources() -> Vec<(String, String)> {
    let root = super::workspace_root();
    super::crate_files()
        .into_iter()
        .map(|path| {
            let text = std::fs::read_to_string(&path).expect("readable");
            (relative(&root, &path), text)
        })
        .collect()
}

fn relative(root: &Path, path: &Path) -> String {
    let rel = path.strip_prefix(root).unwrap_or(path);
    rel.components()
        .map(|c| c.as_os_str().to_string_lossy().into_owned())
        .collect::<Vec<_>>()
        .join("/")
}

fn allowed(path: &str, item: Item) -> bool {
    ALLOWED.iter().any(|a| a.path == path && a.item == item)
}

#[test]
fn no_file_or_function_over_its_limit_but_the_allowed() {
    let sources = sources();
    assert!(sources.len() > 50, "{} files", sources.len());
    let mut over = Vec::new();
    // Allow-list entries still needed: (path, item) of every item over its limit.
    let mut needed = Vec::new();
    for (path, text) in &sources {
        let n_lines = text.lines().count();
        if n_lines > MAX_FILE_LINES {
            needed.push((path.as_str(), Item::File));
            if !allowed(path, Item::File) {
                over.push(format!("{path}: {n_lines} lines (limit {MAX_FILE_LINES})"));
            }
        }
        for f in function_lengths(text) {
            if f.lines <= MAX_FN_LINES {
                continue;
            }
            if let Some(entry) = ALLOWED
                .iter()
                .find(|a| a.path == path && matches!(a.item, Item::Fn(name) if name == f.name))
            {
                needed.push((entry.path, entry.item));
            } else {
                over.push(format!(
                    "{path}:{}: fn {} is {} lines (limit {MAX_FN_LINES})",
                    f.line, f.name, f.lines
                ));
            }
        }
    }
    let stale: Vec<String> = ALLOWED
        .iter()
        .filter(|a| !needed.contains(&(a.path, a.item)))
        .map(|a| format!("{} {:?} ({})", a.path, a.item, a.reason))
        .collect();
    assert!(
        over.is_empty() && stale.is_empty(),
        "over the limit (split them; see the module docs of tests/it/tidy/lengths.rs):\n  {}\n\
         allow-list entries within their limit now (remove them from `ALLOWED`):\n  {}",
        over.join("\n  "),
        stale.join("\n  ")
    );
}

#[test]
fn function_lengths_run_from_the_fn_line_to_its_closing_brace() {
    let text = "//! doc\n\
                pub(crate) fn two_lines() {\n}\n\
                \n\
                impl A {\n    \
                    /// doc\n    \
                    pub const fn long_signature(\n        \
                        a: u8,\n    \
                    ) -> u8\n    \
                    where\n        \
                        u8: Copy,\n    \
                    {\n        \
                        if a > 0 {\n            \
                            a\n        \
                        } else {\n            \
                            0\n        \
                        }\n    \
                    }\n\
                }\n\
                trait T {\n    \
                    fn declared(&self) -> u8;\n    \
                    fn one_line(&self) -> u8 { 1 } // note\n\
                }\n";
    let found = function_lengths(text);
    let summary: Vec<(&str, usize, usize)> = found
        .iter()
        .map(|f| (f.name.as_str(), f.line, f.lines))
        .collect();
    assert_eq!(
        summary,
        [
            ("two_lines", 2, 2),
            ("long_signature", 7, 12),
            ("one_line", 22, 1)
        ]
    );
    assert_eq!(
        declared_fn("    pub(in crate::a) unsafe fn x_1<T>()"),
        Some("x_1")
    );
    assert_eq!(declared_fn("    // fn not_code()"), None);
    assert_eq!(declared_fn("    let fn_ptr = 1;"), None);
}

#[test]
fn each_crate_has_one_integration_test_binary() {
    let root = super::workspace_root();
    for krate in ["protocol", "fluid-node", "solid-node", "coupler-node"] {
        let dir = root.join(krate).join("tests");
        let loose: Vec<String> = std::fs::read_dir(&dir)
            .expect("tests folder")
            .map(|e| e.expect("entry").file_name().to_string_lossy().into_owned())
            .filter(|name| name != "it")
            .collect();
        assert!(
            loose.is_empty(),
            "{krate}/tests holds {loose:?}: integration tests are modules of \
             {krate}/tests/it/main.rs (one test binary per crate)"
        );
        assert!(dir.join("it/main.rs").is_file(), "{krate}/tests/it/main.rs");
    }
}
