//! No import circle between the files of a crate: file A depends on file B when A names a path
//! into B's module through `crate::` or `super::`, in a `use` (groups `{...}` expanded) or
//! inline in code (`crate::a::b::f()`). A path goes to the deepest module file it names (`use
//! crate::fv::state::State` to `fv/state.rs`, `use crate::fv::Solver` to `fv/mod.rs`);
//! `super::` inside an inline `mod tests { ... }` is the file's own module. Paths through
//! `self::` or a bare child name (a parent re-exporting its child) are not counted: a parent
//! owning its children is no circle. Comments and one-line strings are skipped.
//!
//! The circles known today are on [`ALLOWED`], a list that can only shrink: each entry must be
//! exactly a circle found (its files, a strongly connected set of the graph), so a circle that
//! grows, shrinks or goes fails the test until the entry is updated or removed.

use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

/// A known circle (the files of one strongly connected set) and the reason it stands.
struct Allowed {
    /// Paths from the workspace root, with `/`, sorted.
    files: &'static [&'static str],
    reason: &'static str,
}

/// The circles that may stand. Remove an entry once its circle is gone (the test says which).
const ALLOWED: &[Allowed] = &[];

/// The source folders whose files form one module tree: (crate root file, folder).
const CRATES: &[(&str, &str)] = &[
    ("lib.rs", "protocol/src"),
    ("lib.rs", "fluid-node/src"),
    ("lib.rs", "solid-node/src"),
    ("lib.rs", "coupler-node/src"),
    ("lib.rs", "tests/src"),
    ("main.rs", "protocol/tests/it"),
    ("main.rs", "fluid-node/tests/it"),
    ("main.rs", "solid-node/tests/it"),
    ("main.rs", "coupler-node/tests/it"),
    ("main.rs", "tests/it"),
];

/// One dependency of a file: the file it goes to, and where it is named (line, path text).
#[derive(Clone, Debug)]
struct Edge {
    to: String,
    line: usize,
    named: String,
}

/// The module path of a file of a tree rooted at `root_file` (`fv/mod.rs` and `fv.rs` are
/// `["fv"]`); `None` for another crate root in the folder (`src/main.rs` beside `lib.rs`).
fn module_of(rel: &str, root_file: &str) -> Option<Vec<String>> {
    if rel == root_file {
        return Some(Vec::new());
    }
    if !rel.contains('/') && (rel == "main.rs" || rel == "lib.rs") {
        return None;
    }
    let mut segments: Vec<String> = rel
        .strip_suffix(".rs")?
        .split('/')
        .map(String::from)
        .collect();
    if segments.last().is_some_and(|s| s == "mod") {
        segments.pop();
    }
    Some(segments)
}

/// The paths of a `use` tree (`a::{b, c::{d, e as f}, self}` gives `a::b`, `a::c::d`, `a::c::e`
/// and `a`), each as its segments.
fn expand_use_tree(tree: &str) -> Vec<Vec<String>> {
    let tree = tree.trim();
    let Some(open) = tree.find('{') else {
        let path = tree.split(" as ").next().unwrap_or(tree).trim();
        return vec![
            path.split("::")
                .map(|s| s.trim().to_string())
                .filter(|s| s != "*")
                .collect(),
        ];
    };
    let prefix: Vec<String> = tree[..open]
        .trim_end_matches("::")
        .split("::")
        .map(|s| s.trim().to_string())
        .filter(|s| !s.is_empty())
        .collect();
    let inner = &tree[open + 1..tree.rfind('}').unwrap_or(tree.len())];
    let mut parts = Vec::new();
    let (mut depth, mut start) = (0, 0);
    for (i, c) in inner.char_indices() {
        match c {
            '{' => depth += 1,
            '}' => depth -= 1,
            ',' if depth == 0 => {
                parts.push(&inner[start..i]);
                start = i + 1;
            }
            _ => {}
        }
    }
    parts.push(&inner[start..]);
    let mut paths = Vec::new();
    for part in parts.iter().filter(|p| !p.trim().is_empty()) {
        for tail in expand_use_tree(part) {
            let mut path = prefix.clone();
            path.extend(tail.into_iter().filter(|s| s != "self" && s != "*"));
            paths.push(path);
        }
    }
    paths
}

/// `line` without its comment and the contents of its one-line strings.
fn code_of(line: &str) -> String {
    let mut code = String::new();
    let mut chars = line.chars().peekable();
    let mut in_string = false;
    while let Some(c) = chars.next() {
        if in_string {
            match c {
                '\\' => {
                    chars.next();
                }
                '"' => {
                    in_string = false;
                    code.push(c);
                }
                _ => {}
            }
        } else if c == '"' {
            in_string = true;
            code.push(c);
        } else if c == '/' && chars.peek() == Some(&'/') {
            break;
        } else {
            code.push(c);
        }
    }
    code
}

/// The `crate::` and `super::` paths named inline in `code`, each as its segments.
fn inline_paths(code: &str) -> Vec<Vec<String>> {
    let is_ident = |c: char| c.is_alphanumeric() || c == '_';
    let mut paths = Vec::new();
    for head in ["crate::", "super::"] {
        for (at, _) in code.match_indices(head) {
            let before = code[..at].chars().next_back();
            if before.is_some_and(|c| is_ident(c) || c == ':') || code[..at].ends_with("in ") {
                continue;
            }
            let mut segments = vec![head.trim_end_matches("::").to_string()];
            let mut rest = &code[at + head.len()..];
            loop {
                let end = rest.find(|c: char| !is_ident(c)).unwrap_or(rest.len());
                if end == 0 {
                    break;
                }
                segments.push(rest[..end].to_string());
                match rest[end..].strip_prefix("::") {
                    Some(next) => rest = next,
                    None => break,
                }
            }
            paths.push(segments);
        }
    }
    paths
}

/// The module a path names, from the module `here` it is written in: `None` unless it starts
/// with `crate` or `super`.
fn absolute(path: &[String], here: &[String]) -> Option<Vec<String>> {
    let (first, rest) = path.split_first()?;
    match first.as_str() {
        "crate" | "$crate" => Some(rest.to_vec()),
        "super" => {
            let mut base = here.to_vec();
            base.pop();
            let mut rest = rest;
            while let Some(("super", tail)) = rest.split_first().map(|(s, t)| (s.as_str(), t)) {
                base.pop();
                rest = tail;
            }
            base.extend(rest.iter().cloned());
            Some(base)
        }
        _ => None,
    }
}

/// The paths (with their line numbers) a file names through `crate::` or `super::`, each made
/// absolute from the module it is written in (inline modules included).
fn named_paths(text: &str, module: &[String]) -> Vec<(usize, Vec<String>, String)> {
    let mut found = Vec::new();
    // Inline modules open around the current line: (indentation, name).
    let mut inline: Vec<(usize, String)> = Vec::new();
    let mut statement: Option<(usize, String)> = None;
    for (i, raw) in text.lines().enumerate() {
        let code = code_of(raw);
        let indent = raw.len() - raw.trim_start().len();
        let trimmed = code.trim();
        if inline.last().is_some_and(|(at, _)| *at == indent) && trimmed.starts_with('}') {
            inline.pop();
        }
        let mut here = module.to_vec();
        here.extend(inline.iter().map(|(_, name)| name.clone()));
        let after_visibility = if let Some(rest) = trimmed.strip_prefix("pub ") {
            rest
        } else if trimmed.starts_with("pub(") {
            trimmed.split_once(") ").map_or(trimmed, |(_, rest)| rest)
        } else {
            trimmed
        };
        if let Some(name) = after_visibility
            .strip_prefix("mod ")
            .and_then(|m| m.strip_suffix(" {"))
        {
            inline.push((indent, name.trim().to_string()));
            continue;
        }
        if statement.is_none() && after_visibility.starts_with("use ") {
            statement = Some((i + 1, String::new()));
        }
        if let Some((line, mut text)) = statement.take() {
            text.push_str(&code);
            text.push(' ');
            match text.find(';') {
                Some(end) => {
                    let tree = text[..end].trim();
                    let tree = tree[tree.find("use ").map_or(0, |at| at + 4)..].trim();
                    for path in expand_use_tree(tree) {
                        if let Some(abs) = absolute(&path, &here) {
                            found.push((line, abs, path.join("::")));
                        }
                    }
                }
                None => statement = Some((line, text)),
            }
            continue;
        }
        for path in inline_paths(&code) {
            if let Some(abs) = absolute(&path, &here) {
                found.push((i + 1, abs, path.join("::")));
            }
        }
    }
    found
}

/// The dependency graph of one crate's files: file (path from the workspace root) to edges.
fn graph(root: &Path, root_file: &str, folder: &str) -> BTreeMap<String, Vec<Edge>> {
    let mut files = Vec::new();
    super::rust_files(&root.join(folder), &mut files);
    let mut modules: BTreeMap<Vec<String>, String> = BTreeMap::new();
    let mut texts = Vec::new();
    for path in files {
        let rel = path
            .strip_prefix(root.join(folder))
            .expect("under the folder")
            .components()
            .map(|c| c.as_os_str().to_string_lossy().into_owned())
            .collect::<Vec<_>>()
            .join("/");
        let Some(module) = module_of(&rel, root_file) else {
            continue;
        };
        let name = format!("{folder}/{rel}");
        modules.insert(module.clone(), name.clone());
        texts.push((
            name,
            module,
            std::fs::read_to_string(&path).expect("readable"),
        ));
    }
    let mut graph = BTreeMap::new();
    for (name, module, text) in texts {
        let mut edges: Vec<Edge> = Vec::new();
        for (line, abs, named) in named_paths(&text, &module) {
            // The deepest module file the path names.
            let to = (0..=abs.len())
                .rev()
                .find_map(|n| modules.get(&abs[..n]))
                .expect("the crate root is a module file");
            if *to != name && !edges.iter().any(|e| e.to == *to) {
                edges.push(Edge {
                    to: to.clone(),
                    line,
                    named,
                });
            }
        }
        graph.insert(name, edges);
    }
    graph
}

/// The strongly connected sets of more than one file (Tarjan's algorithm), each sorted.
fn circles(graph: &BTreeMap<String, Vec<Edge>>) -> Vec<Vec<String>> {
    struct Walk<'a> {
        graph: &'a BTreeMap<String, Vec<Edge>>,
        index: BTreeMap<&'a str, usize>,
        low: BTreeMap<&'a str, usize>,
        stack: Vec<&'a str>,
        on_stack: BTreeSet<&'a str>,
        sets: Vec<Vec<String>>,
    }
    fn visit<'a>(w: &mut Walk<'a>, v: &'a str) {
        let n = w.index.len();
        w.index.insert(v, n);
        w.low.insert(v, n);
        w.stack.push(v);
        w.on_stack.insert(v);
        for edge in &w.graph[v] {
            let to = edge.to.as_str();
            if !w.index.contains_key(to) {
                visit(w, to);
                let low = w.low[v].min(w.low[to]);
                w.low.insert(v, low);
            } else if w.on_stack.contains(to) {
                let low = w.low[v].min(w.index[to]);
                w.low.insert(v, low);
            }
        }
        if w.low[v] == w.index[v] {
            let mut set = Vec::new();
            while let Some(top) = w.stack.pop() {
                w.on_stack.remove(top);
                set.push(top.to_string());
                if top == v {
                    break;
                }
            }
            if set.len() > 1 {
                set.sort();
                w.sets.push(set);
            }
        }
    }
    let mut walk = Walk {
        graph,
        index: BTreeMap::new(),
        low: BTreeMap::new(),
        stack: Vec::new(),
        on_stack: BTreeSet::new(),
        sets: Vec::new(),
    };
    for v in graph.keys() {
        if !walk.index.contains_key(v.as_str()) {
            visit(&mut walk, v);
        }
    }
    walk.sets
}

/// One loop through the files of `set`, as the lines that name each step
/// (`a.rs:12 crate::b::X -> b.rs`).
fn one_loop(graph: &BTreeMap<String, Vec<Edge>>, set: &[String]) -> Vec<String> {
    let start = &set[0];
    // Breadth-first from `start` inside the set, back to `start`.
    let mut came_from: BTreeMap<&str, (&str, &Edge)> = BTreeMap::new();
    let mut queue = std::collections::VecDeque::from([start.as_str()]);
    while let Some(v) = queue.pop_front() {
        for edge in &graph[v] {
            if !set.contains(&edge.to) || came_from.contains_key(edge.to.as_str()) {
                continue;
            }
            came_from.insert(&edge.to, (v, edge));
            if edge.to == *start {
                queue.clear();
                break;
            }
            queue.push_back(&edge.to);
        }
    }
    let mut steps = Vec::new();
    let mut at = start.as_str();
    while let Some((from, edge)) = came_from.get(at) {
        steps.push(format!(
            "{from}:{} {} -> {}",
            edge.line, edge.named, edge.to
        ));
        at = from;
        if at == start || steps.len() > set.len() {
            break;
        }
    }
    steps.reverse();
    steps
}

#[test]
fn no_import_circle_between_the_files_of_a_crate_but_the_allowed() {
    let root = super::workspace_root();
    let mut found = Vec::new();
    let mut unexpected = Vec::new();
    for (root_file, folder) in CRATES {
        let graph = graph(&root, root_file, folder);
        assert!(!graph.is_empty(), "no files under {folder}");
        for set in circles(&graph) {
            if !ALLOWED.iter().any(|a| a.files == set.as_slice()) {
                unexpected.push(format!(
                    "{set:?}, for example:\n    {}",
                    one_loop(&graph, &set).join("\n    ")
                ));
            }
            found.push(set);
        }
    }
    let stale: Vec<String> = ALLOWED
        .iter()
        .filter(|a| !found.iter().any(|set| a.files == set.as_slice()))
        .map(|a| format!("{:?} ({})", a.files, a.reason))
        .collect();
    assert!(
        unexpected.is_empty() && stale.is_empty(),
        "import circles (move the shared name to the lower file):\n  {}\n\
         allow-list entries that are no longer a circle found (remove or shrink them in \
         `ALLOWED` of tests/it/tidy/circles.rs):\n  {}",
        unexpected.join("\n  "),
        stale.join("\n  ")
    );
}

#[test]
fn use_trees_and_inline_paths_are_read() {
    let paths = expand_use_tree("super::{a, b::{C, d as e}, self}");
    let joined: Vec<String> = paths.iter().map(|p| p.join("::")).collect();
    assert_eq!(joined, ["super::a", "super::b::C", "super::b::d", "super"]);
    let here: Vec<String> = ["fv", "state"].map(String::from).to_vec();
    let text = "use super::init::Init;\n\
                pub(in crate::fv) fn f() -> crate::grid::Grid { x::crate::no() }\n\
                mod tests {\n    \
                    use super::*;\n\
                }\n\
                // crate::comment::Not\n\
                use crate::{\n    \
                    a::B,\n    \
                    c,\n\
                };\n";
    let found: Vec<(usize, String)> = named_paths(text, &here)
        .into_iter()
        .map(|(line, abs, _)| (line, abs.join("::")))
        .collect();
    let expected = [
        (1, "fv::init::Init"),
        (2, "grid::Grid"),
        (4, "fv::state"),
        (7, "a::B"),
        (7, "c"),
    ];
    assert_eq!(found, expected.map(|(line, path)| (line, path.to_string())));
}
