//! No module of any crate imports another that imports it back, directly or through others.
//!
//! The check reads every crate's `src/` as text: it maps each file to its module (`a.rs` and
//! `a/mod.rs` are `a`, `a/b.rs` is `a::b`), finds the paths each module names (`use` trees and
//! `crate::…`, `super::…`, `self::…` paths in code, with `pub use` re-exports followed to the
//! module that defines the item), and draws an edge between the two *siblings* under the deepest
//! module both paths share (`crate::scene::x` named from `crate::bake::y` is an edge
//! `bake → scene` among the crate root's children; a parent naming its child, or a child its
//! parent, is no edge). Each sibling graph must be acyclic. Comments, strings and
//! `#[cfg(test)]` items are left out: tests may reach anywhere.

use std::collections::{BTreeMap, BTreeSet, HashMap};
use std::path::{Path, PathBuf};

type ModPath = Vec<String>;

#[test]
fn no_crate_has_modules_importing_each_other_in_a_circle() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut crates: Vec<PathBuf> = vec![root.join("src")];
    for entry in std::fs::read_dir(root).unwrap() {
        let dir = entry.unwrap().path();
        if dir.join("Cargo.toml").is_file() && dir.join("src").is_dir() {
            crates.push(dir.join("src"));
        }
    }
    crates.sort();
    assert!(
        crates.len() >= 6,
        "expected the workspace's crates, found {crates:?}"
    );
    let mut report = String::new();
    for src in &crates {
        let graph = ModuleGraph::read(src);
        assert!(graph.files.len() > 1, "{} holds no modules", src.display());
        for cycle in graph.cycles() {
            report.push_str(&format!("{}: {}\n", src.display(), cycle));
        }
    }
    assert!(
        report.is_empty(),
        "modules import each other in a circle:\n{report}"
    );
}

#[test]
fn the_check_finds_a_circle_through_use_trees_super_and_re_exports() {
    let dir = tempfile::tempdir().unwrap();
    let src = dir.path();
    let write = |name: &str, text: &str| {
        let path = src.join(name);
        std::fs::create_dir_all(path.parent().unwrap()).unwrap();
        std::fs::write(path, text).unwrap();
    };
    write(
        "lib.rs",
        "mod a; mod b; mod c; mod d;\npub use c::Thing;\npub use d::{Other as Renamed};\n",
    );
    // a → b through a grouped use tree, b → c through `super`, c → a through a path in code.
    write("a.rs", "use crate::{b::{self, X}, d};\n");
    write(
        "b.rs",
        "// crate::a in a comment is no edge\nuse super::c::Y;\n",
    );
    write(
        "c.rs",
        "pub struct Thing;\nfn f() { let s = \"crate::d\"; crate::a::g(); }\n",
    );
    // d → crate::Thing is c; c names no d (only in a string): no circle through d.
    write(
        "d.rs",
        "pub struct Other;\nuse crate::Thing;\n#[cfg(test)]\nmod tests { use crate::a; }\n",
    );
    let graph = ModuleGraph::read(src);
    let cycles = graph.cycles();
    assert_eq!(cycles.len(), 1, "{cycles:?}");
    assert!(
        cycles[0].contains("a → b") && cycles[0].contains("c → a"),
        "{cycles:?}"
    );
    let edges = &graph.edges[&Vec::<String>::new()];
    assert!(
        edges["d"].contains_key("c"),
        "re-export not followed: {edges:?}"
    );
    assert!(
        !edges.get("c").is_some_and(|e| e.contains_key("d")),
        "a string made an edge"
    );
    assert!(
        !edges.get("d").is_some_and(|e| e.contains_key("a")),
        "a test made an edge"
    );

    // Folder modules: siblings under `p` are checked too; parent and child are no edge.
    let dir = tempfile::tempdir().unwrap();
    let src = dir.path();
    let write = |name: &str, text: &str| {
        let path = src.join(name);
        std::fs::create_dir_all(path.parent().unwrap()).unwrap();
        std::fs::write(path, text).unwrap();
    };
    write("lib.rs", "mod p;\n");
    write("p/mod.rs", "mod x; mod y;\nuse self::x::A;\n");
    write("p/x.rs", "use super::y::B; use super::*;\n");
    write("p/y.rs", "use crate::p::x::A;\n");
    let cycles = ModuleGraph::read(src).cycles();
    assert_eq!(cycles.len(), 1, "{cycles:?}");
    assert!(cycles[0].contains("p: "), "{cycles:?}");
}

/// The modules of one crate and the edges among siblings.
struct ModuleGraph {
    /// Module path → its file, relative to `src`.
    files: BTreeMap<ModPath, PathBuf>,
    /// Parent module → (child → (named sibling → where: "file:line")).
    edges: BTreeMap<ModPath, BTreeMap<String, BTreeMap<String, String>>>,
}

impl ModuleGraph {
    fn read(src: &Path) -> ModuleGraph {
        let mut files = BTreeMap::new();
        collect_files(src, src, &mut files);
        let tokens: BTreeMap<ModPath, Vec<Token>> = files
            .iter()
            .map(|(m, f)| {
                (
                    m.clone(),
                    tokenize(&std::fs::read_to_string(src.join(f)).unwrap()),
                )
            })
            .collect();
        let modules: BTreeSet<ModPath> = files.keys().cloned().collect();
        // Re-exports: module → (exported name → module where the name leads).
        let mut exports: HashMap<ModPath, HashMap<String, ModPath>> = HashMap::new();
        for (module, toks) in &tokens {
            for (path, public, _) in use_paths(toks) {
                if !public {
                    continue;
                }
                let (last, alias) = match (path.segments.last(), &path.alias) {
                    (Some(l), Some(a)) => (l.clone(), a.clone()),
                    (Some(l), None) => (l.clone(), l.clone()),
                    _ => continue,
                };
                if last == "self" || last == "*" {
                    continue;
                }
                if let Some(target) = resolve(module, &path, &modules, &HashMap::new(), true) {
                    exports
                        .entry(module.clone())
                        .or_default()
                        .insert(alias, target);
                }
            }
        }
        let mut edges: BTreeMap<ModPath, BTreeMap<String, BTreeMap<String, String>>> =
            BTreeMap::new();
        for (module, toks) in &tokens {
            let in_use = use_paths(toks)
                .into_iter()
                .map(|(p, _, line)| (p, true, line));
            let in_code = code_paths(toks)
                .into_iter()
                .map(|(p, line)| (p, false, line));
            for (path, is_use, line) in in_use.chain(in_code) {
                let Some(target) = resolve(module, &path, &modules, &exports, is_use) else {
                    continue;
                };
                let common = module
                    .iter()
                    .zip(&target)
                    .take_while(|(a, b)| a == b)
                    .count();
                if common == module.len() || common == target.len() {
                    continue; // the module itself, an ancestor or a descendant
                }
                let parent = module[..common].to_vec();
                let place = format!("{}:{line}", files[module].display());
                edges
                    .entry(parent)
                    .or_default()
                    .entry(module[common].clone())
                    .or_default()
                    .entry(target[common].clone())
                    .or_insert(place);
            }
        }
        ModuleGraph { files, edges }
    }

    /// Every circle, one per strongly connected component of a sibling graph, written as
    /// `parent: a → b (file:line) → … → a`.
    fn cycles(&self) -> Vec<String> {
        let mut out = Vec::new();
        for (parent, graph) in &self.edges {
            let prefix = if parent.is_empty() {
                "crate".to_string()
            } else {
                parent.join("::")
            };
            for component in strongly_connected(graph) {
                if component.len() < 2 {
                    continue;
                }
                // Walk a circle inside the component from its first node.
                let start = component.iter().next().unwrap().clone();
                let mut steps = Vec::new();
                let mut seen = BTreeSet::new();
                let mut at = start.clone();
                while seen.insert(at.clone()) {
                    let (next, place) = graph[&at]
                        .iter()
                        .find(|(n, _)| component.contains(*n))
                        .unwrap();
                    steps.push(format!("{at} → {next} ({place})"));
                    at = next.clone();
                }
                let members: Vec<_> = component.iter().cloned().collect();
                out.push(format!(
                    "{prefix}: {{{}}}: {}",
                    members.join(", "),
                    steps.join(", ")
                ));
            }
        }
        out
    }
}

/// Tarjan's strongly connected components.
fn strongly_connected(graph: &BTreeMap<String, BTreeMap<String, String>>) -> Vec<BTreeSet<String>> {
    struct State<'a> {
        graph: &'a BTreeMap<String, BTreeMap<String, String>>,
        index: HashMap<&'a str, usize>,
        low: HashMap<&'a str, usize>,
        stack: Vec<&'a str>,
        on_stack: BTreeSet<&'a str>,
        out: Vec<BTreeSet<String>>,
    }
    fn visit<'a>(s: &mut State<'a>, v: &'a str) {
        let i = s.index.len();
        s.index.insert(v, i);
        s.low.insert(v, i);
        s.stack.push(v);
        s.on_stack.insert(v);
        if let Some(next) = s.graph.get(v) {
            for w in next.keys() {
                let w = w.as_str();
                if !s.index.contains_key(w) {
                    visit(s, w);
                    let lw = s.low[w];
                    let lv = s.low.get_mut(v).unwrap();
                    *lv = (*lv).min(lw);
                } else if s.on_stack.contains(w) {
                    let iw = s.index[w];
                    let lv = s.low.get_mut(v).unwrap();
                    *lv = (*lv).min(iw);
                }
            }
        }
        if s.low[v] == s.index[v] {
            let mut component = BTreeSet::new();
            loop {
                let w = s.stack.pop().unwrap();
                s.on_stack.remove(w);
                component.insert(w.to_string());
                if w == v {
                    break;
                }
            }
            s.out.push(component);
        }
    }
    let mut s = State {
        graph,
        index: HashMap::new(),
        low: HashMap::new(),
        stack: Vec::new(),
        on_stack: BTreeSet::new(),
        out: Vec::new(),
    };
    for v in graph.keys() {
        if !s.index.contains_key(v.as_str()) {
            visit(&mut s, v);
        }
    }
    s.out
}

/// Every `.rs` file below `dir` by its module path.
fn collect_files(src: &Path, dir: &Path, out: &mut BTreeMap<ModPath, PathBuf>) {
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        if path.is_dir() {
            collect_files(src, &path, out);
            continue;
        }
        if path.extension().is_none_or(|e| e != "rs") {
            continue;
        }
        let rel = path.strip_prefix(src).unwrap().to_path_buf();
        let mut module: ModPath = rel
            .with_extension("")
            .components()
            .map(|c| c.as_os_str().to_string_lossy().into_owned())
            .collect();
        if module.len() == 1 && (module[0] == "lib" || module[0] == "main") {
            module.clear();
        } else if module.last().is_some_and(|l| l == "mod") {
            module.pop();
        }
        out.insert(module, rel);
    }
}

#[derive(Clone, Debug, PartialEq)]
enum Token {
    Ident(String),
    /// `::`
    Path,
    Punct(char),
}

/// A path as written: its first segment (`crate`, `super`, `self`, or a name) and the rest;
/// `alias` is the name after `as`.
#[derive(Clone, Debug)]
struct WrittenPath {
    segments: Vec<String>,
    alias: Option<String>,
}

/// Identifiers, `::` and punctuation, with the line each token starts on folded in as a
/// `Punct('\n')`; comments, string and char literals and lifetimes dropped, and items under
/// `#[cfg(test)]` skipped.
fn tokenize(text: &str) -> Vec<Token> {
    let chars: Vec<char> = text.chars().collect();
    let mut out = Vec::new();
    let mut i = 0;
    while i < chars.len() {
        let c = chars[i];
        let next = chars.get(i + 1).copied();
        if c == '\n' {
            out.push(Token::Punct('\n'));
            i += 1;
        } else if c == '/' && next == Some('/') {
            while i < chars.len() && chars[i] != '\n' {
                i += 1;
            }
        } else if c == '/' && next == Some('*') {
            let mut depth = 0;
            while i < chars.len() {
                if chars[i] == '/' && chars.get(i + 1) == Some(&'*') {
                    depth += 1;
                    i += 2;
                } else if chars[i] == '*' && chars.get(i + 1) == Some(&'/') {
                    depth -= 1;
                    i += 2;
                    if depth == 0 {
                        break;
                    }
                } else {
                    if chars[i] == '\n' {
                        out.push(Token::Punct('\n'));
                    }
                    i += 1;
                }
            }
        } else if c == 'r' && (next == Some('"') || next == Some('#')) && raw_string_at(&chars, i) {
            // r"…", r#"…"#: skip to the closing quote with as many hashes.
            let mut j = i + 1;
            let mut hashes = 0;
            while chars[j] == '#' {
                hashes += 1;
                j += 1;
            }
            j += 1;
            loop {
                if j >= chars.len() {
                    break;
                }
                if chars[j] == '"' && (0..hashes).all(|k| chars.get(j + 1 + k) == Some(&'#')) {
                    j += 1 + hashes;
                    break;
                }
                if chars[j] == '\n' {
                    out.push(Token::Punct('\n'));
                }
                j += 1;
            }
            i = j;
        } else if c == '"' {
            i += 1;
            while i < chars.len() && chars[i] != '"' {
                if chars[i] == '\\' {
                    i += 1;
                }
                if chars.get(i) == Some(&'\n') {
                    out.push(Token::Punct('\n'));
                }
                i += 1;
            }
            i += 1;
        } else if c == '\'' {
            // A char literal ('x', '\n', '\u{..}') or a lifetime ('a): skip either.
            if next == Some('\\') {
                i += 2;
                while i < chars.len() && chars[i] != '\'' {
                    i += 1;
                }
                i += 1;
            } else if chars.get(i + 2) == Some(&'\'') {
                i += 3;
            } else {
                i += 1;
                while i < chars.len() && (chars[i].is_alphanumeric() || chars[i] == '_') {
                    i += 1;
                }
            }
        } else if c.is_alphabetic() || c == '_' {
            let start = i;
            while i < chars.len() && (chars[i].is_alphanumeric() || chars[i] == '_') {
                i += 1;
            }
            // `b"…"`, `br"…"`: the prefix of a literal, not a name.
            let word: String = chars[start..i].iter().collect();
            if (word == "b" || word == "c") && chars.get(i) == Some(&'"') {
                continue;
            }
            if (word == "br" || word == "cr") && raw_string_at(&chars, i - 1) {
                i -= 1;
                continue;
            }
            out.push(Token::Ident(word));
        } else if c == ':' && next == Some(':') {
            out.push(Token::Path);
            i += 2;
        } else if c.is_ascii_digit() {
            while i < chars.len() && (chars[i].is_alphanumeric() || chars[i] == '_') {
                i += 1;
            }
        } else {
            if !c.is_whitespace() {
                out.push(Token::Punct(c));
            }
            i += 1;
        }
    }
    strip_cfg_test(out)
}

/// Whether `chars[i]` (an `r`) opens a raw string: `r"` or `r#…#"`.
fn raw_string_at(chars: &[char], i: usize) -> bool {
    if i > 0 && (chars[i - 1].is_alphanumeric() || chars[i - 1] == '_') {
        // part of a longer name (`br` handled by the caller)
        if !(chars[i - 1] == 'b' || chars[i - 1] == 'c') {
            return false;
        }
    }
    let mut j = i + 1;
    while chars.get(j) == Some(&'#') {
        j += 1;
    }
    chars.get(j) == Some(&'"')
}

/// Drops the item after each `#[cfg(test)]`: up to its `;` or through its braced body.
fn strip_cfg_test(tokens: Vec<Token>) -> Vec<Token> {
    let pattern = [
        Token::Punct('#'),
        Token::Punct('['),
        Token::Ident("cfg".into()),
        Token::Punct('('),
        Token::Ident("test".into()),
        Token::Punct(')'),
        Token::Punct(']'),
    ];
    let mut out = Vec::with_capacity(tokens.len());
    let mut i = 0;
    while i < tokens.len() {
        if tokens[i..].starts_with(&pattern) {
            i += pattern.len();
            let mut depth = 0;
            while i < tokens.len() {
                match &tokens[i] {
                    Token::Punct('\n') => out.push(Token::Punct('\n')),
                    Token::Punct('{') => depth += 1,
                    Token::Punct('}') => {
                        depth -= 1;
                        if depth == 0 {
                            i += 1;
                            break;
                        }
                    }
                    Token::Punct(';') if depth == 0 => {
                        i += 1;
                        break;
                    }
                    _ => {}
                }
                i += 1;
            }
        } else {
            out.push(tokens[i].clone());
            i += 1;
        }
    }
    out
}

/// The 1-based line of token `at`.
fn line_of(tokens: &[Token], at: usize) -> usize {
    1 + tokens[..at]
        .iter()
        .filter(|t| **t == Token::Punct('\n'))
        .count()
}

/// Every leaf of every `use` tree: (path, whether the `use` is `pub`, line).
fn use_paths(tokens: &[Token]) -> Vec<(WrittenPath, bool, usize)> {
    let toks: Vec<(usize, &Token)> = tokens
        .iter()
        .enumerate()
        .filter(|(_, t)| **t != Token::Punct('\n'))
        .collect();
    let mut out = Vec::new();
    for k in 0..toks.len() {
        if *toks[k].1 != Token::Ident("use".into()) {
            continue;
        }
        // `pub use`, `pub(crate) use`: public for re-export purposes.
        let public = k >= 1
            && (*toks[k - 1].1 == Token::Ident("pub".into())
                || (*toks[k - 1].1 == Token::Punct(')')
                    && toks[..k]
                        .iter()
                        .rev()
                        .take(5)
                        .any(|(_, t)| **t == Token::Ident("pub".into()))));
        let line = line_of(tokens, toks[k].0);
        let mut j = k + 1;
        let mut leaves = Vec::new();
        parse_tree(&toks, &mut j, Vec::new(), &mut leaves);
        out.extend(leaves.into_iter().map(|p| (p, public, line)));
    }
    out
}

/// Parses one use tree at `toks[*j]` with `prefix` before it.
fn parse_tree(
    toks: &[(usize, &Token)],
    j: &mut usize,
    mut prefix: Vec<String>,
    out: &mut Vec<WrittenPath>,
) {
    if toks.get(*j).is_some_and(|t| *t.1 == Token::Path) {
        *j += 1; // `use ::std::…`
    }
    loop {
        match toks.get(*j).map(|t| t.1) {
            Some(Token::Ident(name)) => {
                prefix.push(name.clone());
                *j += 1;
                if toks.get(*j).is_some_and(|t| *t.1 == Token::Path) {
                    *j += 1;
                    continue;
                }
                let mut alias = None;
                if toks
                    .get(*j)
                    .is_some_and(|t| *t.1 == Token::Ident("as".into()))
                {
                    if let Some(Token::Ident(a)) = toks.get(*j + 1).map(|t| t.1) {
                        alias = Some(a.clone());
                    }
                    *j += 2;
                }
                out.push(WrittenPath {
                    segments: prefix,
                    alias,
                });
                return;
            }
            Some(Token::Punct('*')) => {
                *j += 1;
                prefix.push("*".into());
                out.push(WrittenPath {
                    segments: prefix,
                    alias: None,
                });
                return;
            }
            Some(Token::Punct('{')) => {
                *j += 1;
                loop {
                    match toks.get(*j).map(|t| t.1) {
                        Some(Token::Punct('}')) => {
                            *j += 1;
                            return;
                        }
                        Some(Token::Punct(',')) => *j += 1,
                        None => return,
                        _ => {
                            let before = *j;
                            parse_tree(toks, j, prefix.clone(), out);
                            if *j == before {
                                *j += 1;
                            }
                        }
                    }
                }
            }
            _ => return,
        }
    }
}

/// Paths in code (outside `use`) that start with `crate`, `super` or `self` and go on with
/// `::`: (path, line).
fn code_paths(tokens: &[Token]) -> Vec<(WrittenPath, usize)> {
    let mut out = Vec::new();
    let mut in_use = false;
    let mut i = 0;
    while i < tokens.len() {
        match &tokens[i] {
            Token::Ident(w) if w == "use" => in_use = true,
            Token::Punct(';') => in_use = false,
            Token::Ident(w)
                if !in_use
                    && (w == "crate" || w == "super" || w == "self")
                    && tokens.get(i + 1) == Some(&Token::Path)
                    && !(i > 0 && tokens[i - 1] == Token::Path)
                    && !(i > 0 && tokens[i - 1] == Token::Punct('$')) =>
            {
                let line = line_of(tokens, i);
                let mut segments = vec![w.clone()];
                let mut j = i + 1;
                while tokens.get(j) == Some(&Token::Path) {
                    match tokens.get(j + 1) {
                        Some(Token::Ident(s)) => segments.push(s.clone()),
                        _ => break,
                    }
                    j += 2;
                }
                out.push((
                    WrittenPath {
                        segments,
                        alias: None,
                    },
                    line,
                ));
                i = j;
                continue;
            }
            _ => {}
        }
        i += 1;
    }
    out
}

/// The deepest module of this crate that `path`, written in `module`, leads to: following
/// child modules and re-exported names. `None` for paths into other crates.
fn resolve(
    module: &ModPath,
    path: &WrittenPath,
    modules: &BTreeSet<ModPath>,
    exports: &HashMap<ModPath, HashMap<String, ModPath>>,
    is_use: bool,
) -> Option<ModPath> {
    let mut segs = path.segments.iter().peekable();
    let mut at: ModPath = match segs.peek()?.as_str() {
        "crate" => {
            segs.next();
            Vec::new()
        }
        "self" => {
            segs.next();
            module.clone()
        }
        "super" => {
            let mut at = module.clone();
            while segs.peek().is_some_and(|s| *s == "super") {
                segs.next();
                at.pop()?;
            }
            at
        }
        first if is_use => {
            // A 2018 use path: a child module of this one, else another crate.
            let mut child = module.clone();
            child.push(first.to_string());
            if !modules.contains(&child) {
                return None;
            }
            module.clone()
        }
        _ => return None,
    };
    let mut hops = 0;
    for seg in segs {
        let mut child = at.clone();
        child.push(seg.clone());
        if modules.contains(&child) {
            at = child;
        } else if let Some(target) = exports.get(&at).and_then(|e| e.get(seg)) {
            hops += 1;
            if hops > 16 {
                break;
            }
            at = target.clone();
        } else {
            break;
        }
    }
    Some(at)
}
