//! The doors of every subcommand, tried from the clap definition: each output pointed at each
//! input (spelled five ways), at another output, at a private device node, a FIFO and a
//! directory; each input pointed at a FIFO, a device and a directory. Expected: a refusal
//! naming both paths (or the node and what it is) before any work, inputs unchanged, nodes
//! kept, nothing new left behind.
//!
//! The flags to try are read from the command tree by their types ([`InputPath`],
//! [`OutputPath`], [`OutputPrefix`], [`OutputDir`]): a path flag of any other type, a
//! subcommand without a base invocation below, or a typed flag the base invocation leaves
//! out fails the test. Commands run in this process (`cli::run`), so a door that lets one
//! through runs it for real, and the test fails on what it then does.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::time::Duration;

use clap::builder::ValueParser;
use clap::{CommandFactory as _, Parser as _};

use super::paths::{InputPath, OutputDir, OutputPath, OutputPrefix};
use super::Cli;

/// One base invocation per subcommand. `%ID=FIXTURE` is a path flag (or positional) `ID` of
/// type [`InputPath`] given the fixture file `FIXTURE`; `@ID=NAME` one of an output type given
/// `NAME` in the test's directory; other words are passed as they are.
const BASE: &[(&str, &str)] = &[
    (
        "bake",
        "bake %scene=scene.toml -q --device cpu -o @output=out.oslf --preview @preview=p.png --report-json @report_json=r.json",
    ),
    (
        "render",
        "render %store=st.oslf -o @output=r.exr --stats-json @stats_json=s.json",
    ),
    ("view", "view %store=st.oslf"),
    ("serve", "serve %stores=st.oslf --port 0"),
    ("export-web", "export-web %store=st.oslf @dir=webdir -q"),
    ("store info", "store info %store=st.oslf"),
    ("store verify", "store verify %store=st.oslf"),
    (
        "store merge",
        "store merge %shards=s0.shard %shards=s1.shard -o @output=m.oslf",
    ),
    (
        "store convert",
        "store convert %input=st.oslf @output=c.oslf --encoding bc6h",
    ),
    (
        "store export-cube",
        "store export-cube %store=st.oslf 0 -o @output=cube.exr",
    ),
    (
        "store export-sample-map",
        "store export-sample-map %store=st.oslf 0 -o @output=map.png",
    ),
    (
        "truth",
        "truth %scene=scene.toml --store %store=st.oslf -q --spp 1 --width 4 --height 4 -o @output=tr",
    ),
    (
        "compare",
        "compare %reference=a.exr %test=b.exr --second-reference %second_reference=a2.exr --json @json=c.json --csv @csv=c.csv --side-by-side @side_by_side=sbs.png",
    ),
    (
        "tables",
        "tables %scene=scene.toml --store %stores=st.oslf -q -o @out=tabdir",
    ),
    ("sweep", "sweep %scene=scene.toml -q -o @out=swdir"),
    (
        "cache-stats",
        "cache-stats %store=st.oslf --csv @csv=cs.csv --json @json=cs.json",
    ),
    ("completions", "completions bash"),
];

/// The type of a path argument, from its value parser.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Kind {
    Input,
    Output,
    Prefix,
    Dir,
}

fn kind_of(parser: &ValueParser) -> Option<Kind> {
    let parses = |other: ValueParser| parser.type_id() == other.type_id();
    [
        (parses(clap::value_parser!(InputPath).into()), Kind::Input),
        (parses(clap::value_parser!(OutputPath).into()), Kind::Output),
        (
            parses(clap::value_parser!(OutputPrefix).into()),
            Kind::Prefix,
        ),
        (parses(clap::value_parser!(OutputDir).into()), Kind::Dir),
    ]
    .into_iter()
    .find_map(|(same, k)| same.then_some(k))
}

/// Every leaf subcommand (`"store info"`) with its path arguments: id → kind. Fails on a path
/// argument whose type is none of the door's.
fn leaves() -> BTreeMap<String, BTreeMap<String, Kind>> {
    fn walk(cmd: &clap::Command, prefix: &str, out: &mut BTreeMap<String, BTreeMap<String, Kind>>) {
        for sub in cmd.get_subcommands() {
            if sub.get_name() == "help" {
                continue;
            }
            let name = format!("{prefix}{}", sub.get_name());
            if sub.has_subcommands() {
                walk(sub, &format!("{name} "), out);
                continue;
            }
            let mut args = BTreeMap::new();
            for arg in sub.get_arguments() {
                let parser = arg.get_value_parser();
                let path_buf: ValueParser = clap::value_parser!(PathBuf);
                assert!(
                    parser.type_id() != path_buf.type_id(),
                    "`oslf {name}` {}: a PathBuf argument; give it a door type (InputPath, OutputPath, OutputPrefix or OutputDir) and declare it",
                    arg.get_id()
                );
                if let Some(kind) = kind_of(parser) {
                    args.insert(arg.get_id().to_string(), kind);
                }
            }
            out.insert(name, args);
        }
    }
    let mut out = BTreeMap::new();
    walk(&Cli::command(), "", &mut out);
    out
}

/// A token of a base invocation.
#[derive(Clone, Debug)]
enum Token {
    Word(String),
    Path { id: String, path: PathBuf },
}

fn parse_base(base: &str, dir: &Path) -> Vec<Token> {
    base.split_whitespace()
        .map(|w| match w.split_once('=') {
            Some((id, name)) if id.starts_with('%') || id.starts_with('@') => Token::Path {
                id: id[1..].to_string(),
                path: dir.join(name),
            },
            _ => Token::Word(w.to_string()),
        })
        .collect()
}

fn argv(tokens: &[Token]) -> Vec<std::ffi::OsString> {
    std::iter::once("oslf".into())
        .chain(tokens.iter().map(|t| match t {
            Token::Word(w) => w.into(),
            Token::Path { path, .. } => path.clone().into_os_string(),
        }))
        .collect()
}

/// Runs `tokens` in this process on a thread; the error's message, or a panic naming the
/// command if it succeeded or took more than `limit`.
fn refused(tokens: &[Token], limit: Duration) -> String {
    let args = argv(tokens);
    let shown = format!("{args:?}");
    let (tx, rx) = std::sync::mpsc::channel();
    std::thread::spawn(move || {
        let result = Cli::try_parse_from(&args)
            .map_err(|e| e.to_string())
            .and_then(|cli| super::run(cli).map_err(|e| format!("{e:#}")));
        let _ = tx.send(result);
    });
    match rx.recv_timeout(limit) {
        Ok(Err(e)) => e,
        Ok(Ok(())) => panic!("{shown} was accepted"),
        Err(_) => panic!("{shown} did not return within {limit:?}"),
    }
}

/// The fixtures: a scene that includes an OBJ file, a store baked from it, its two shards,
/// two OpenEXR images. Made through the CLI, in this process.
fn fixtures(dir: &Path) {
    let scene = format!(
        "{}\n[[mesh]]\npath = \"floor.obj\"\nmaterial = {{ color = [0.5, 0.5, 0.5] }}\n\n[bake]\nsample_count = 12\ncube_resolution = 2\nsample_map_resolution = 4\nsamples_per_texel = 1\n",
        include_str!("../../tests/fixtures/teapot-lid.toml")
    );
    std::fs::write(dir.join("scene.toml"), scene).unwrap();
    std::fs::write(
        dir.join("floor.obj"),
        "v -9 -9 -5\nv 9 -9 -5\nv 9 9 -5\nv -9 9 -5\nf 1 2 3\nf 1 3 4\n",
    )
    .unwrap();
    let bake = |extra: &[&str], out: &str| {
        let mut a: Vec<std::ffi::OsString> = vec!["oslf".into(), "bake".into()];
        a.push(dir.join("scene.toml").into());
        for w in ["-q", "--device", "cpu", "--preview", "none"]
            .iter()
            .chain(extra)
        {
            a.push(w.into());
        }
        a.push("-o".into());
        a.push(dir.join(out).into());
        super::run(Cli::try_parse_from(a).unwrap()).unwrap();
    };
    bake(&[], "st.oslf");
    bake(&["--shard", "0/2"], "s0.shard");
    bake(&["--shard", "1/2"], "s1.shard");
    let px = vec![[0.5f32, 0.25, 0.125, 1.0]; 4];
    oslf_util::image_file::write_exr_rgba(&dir.join("a.exr"), 2, 2, &px).unwrap();
    oslf_util::image_file::write_exr_rgba(&dir.join("b.exr"), 2, 2, &px).unwrap();
    oslf_util::image_file::write_exr_rgba(&dir.join("a2.exr"), 2, 2, &px).unwrap();
}

/// The names and contents of the regular files in `dir`, and the names of everything else.
fn snapshot(dir: &Path) -> BTreeMap<String, Option<Vec<u8>>> {
    std::fs::read_dir(dir)
        .unwrap()
        .map(|e| {
            let e = e.unwrap();
            let name = e.file_name().into_string().unwrap();
            let meta = std::fs::symlink_metadata(e.path()).unwrap();
            let bytes = meta.is_file().then(|| std::fs::read(e.path()).unwrap());
            (name, bytes)
        })
        .collect()
}

/// Five spellings of the existing file `path` in `dir`, made there: as it is, with `./`, via
/// a subdirectory and `..`, a symbolic link, a hard link.
fn spellings(dir: &Path, path: &Path, n: usize) -> Vec<PathBuf> {
    let name = path.file_name().unwrap();
    let sub = dir.join("sub");
    std::fs::create_dir_all(&sub).unwrap();
    let soft = dir.join(format!("soft-{n}"));
    std::os::unix::fs::symlink(path, &soft).unwrap();
    let hard = dir.join(format!("hard-{n}"));
    std::fs::hard_link(path, &hard).unwrap();
    vec![
        path.to_path_buf(),
        dir.join(".").join(name),
        sub.join("..").join(name),
        soft,
        hard,
    ]
}

/// Removes what [`spellings`] and the node checks made.
fn tidy(dir: &Path) {
    for e in std::fs::read_dir(dir).unwrap() {
        let e = e.unwrap();
        let name = e.file_name().into_string().unwrap();
        if name.starts_with("soft-") || name.starts_with("hard-") || name.starts_with("node-") {
            let _ = std::fs::remove_file(e.path());
            let _ = std::fs::remove_dir(e.path());
        }
    }
    let _ = std::fs::remove_dir(dir.join("sub"));
}

/// A private FIFO, character device (`c 1 7`, the full device, whose writes fail with
/// ENOSPC; `c 1 5`, zero, for inputs) or directory at `path`, and what the door calls it.
fn node(path: &Path, what: &str, input: bool) -> &'static str {
    use rustix::fs::{mkfifoat, mknodat, FileType, Mode, CWD};
    match what {
        "fifo" => {
            mkfifoat(CWD, path, Mode::from_raw_mode(0o666)).unwrap();
            "(a FIFO)"
        }
        "device" => {
            let minor = if input { 5 } else { 7 };
            mknodat(
                CWD,
                path,
                FileType::CharacterDevice,
                Mode::from_raw_mode(0o666),
                rustix::fs::makedev(1, minor),
            )
            .unwrap_or_else(|e| {
                panic!(
                    "cannot make a device node {} ({e}); the door test runs as root, as CI does",
                    path.display()
                )
            });
            "(a character device)"
        }
        _ => {
            std::fs::create_dir(path).unwrap();
            "(a directory)"
        }
    }
}

fn with_path(tokens: &[Token], index: usize, path: &Path) -> Vec<Token> {
    let mut t = tokens.to_vec();
    if let Token::Path { path: p, .. } = &mut t[index] {
        *p = path.to_path_buf();
    }
    t
}

fn path_at(tokens: &[Token], index: usize) -> &Path {
    match &tokens[index] {
        Token::Path { path, .. } => path,
        Token::Word(_) => unreachable!(),
    }
}

/// One subcommand under test: its base invocation, the kinds of its path arguments, the
/// directory of the fixtures and what it held before.
struct Case<'a> {
    name: &'a str,
    tokens: Vec<Token>,
    args: &'a BTreeMap<String, Kind>,
    dir: &'a Path,
    before: &'a BTreeMap<String, Option<Vec<u8>>>,
    /// A refusal comes before any work: seconds at most, even on a loaded machine.
    limit: Duration,
    tried: usize,
}

impl Case<'_> {
    /// The indices of the tokens whose argument is of one of `kinds`.
    fn slots(&self, kinds: &[Kind]) -> Vec<usize> {
        self.tokens
            .iter()
            .enumerate()
            .filter_map(|(i, t)| match t {
                Token::Path { id, .. } if kinds.contains(&self.args[id]) => Some(i),
                _ => None,
            })
            .collect()
    }

    fn kind(&self, index: usize) -> Kind {
        match &self.tokens[index] {
            Token::Path { id, .. } => self.args[id],
            Token::Word(_) => unreachable!(),
        }
    }

    /// Runs the base invocation with token `index` set to `path`: its refusal.
    fn refused_with(&mut self, index: usize, path: &Path) -> String {
        self.tried += 1;
        refused(&with_path(&self.tokens, index, path), self.limit)
    }

    /// The fixtures' directory is as it was (after removing what the case made).
    fn unchanged(&self) {
        tidy(self.dir);
        assert_eq!(
            &snapshot(self.dir),
            self.before,
            "`oslf {}` changed the directory",
            self.name
        );
    }

    /// Every base path argument is of a door type and tried; every typed argument is in it.
    fn check_coverage(&self) {
        let mut seen = BTreeMap::new();
        for t in &self.tokens {
            if let Token::Path { id, .. } = t {
                let kind = self.args.get(id).unwrap_or_else(|| {
                    panic!(
                        "`oslf {}` has no path argument {id} (door_tests::BASE)",
                        self.name
                    )
                });
                seen.insert(id.clone(), *kind);
            }
        }
        for (id, kind) in self.args {
            assert!(
                seen.contains_key(id),
                "`oslf {}`: its {kind:?} argument {id} is not tried (add it to door_tests::BASE)",
                self.name
            );
        }
    }

    /// Each output pointed at each input (five spellings), and at each other output.
    fn outputs_over_inputs(&mut self) {
        let (inputs, outputs) = (self.slots(&[Kind::Input]), self.slots(&[Kind::Output]));
        for &o in &outputs {
            for &i in &inputs {
                let input = path_at(&self.tokens, i).to_path_buf();
                for (n, spelled) in spellings(self.dir, &input, self.tried)
                    .into_iter()
                    .enumerate()
                {
                    let e = self.refused_with(o, &spelled);
                    assert!(
                        e.contains(&spelled.display().to_string())
                            && e.contains(&input.display().to_string())
                            && e.contains("the same file"),
                        "`oslf {}`, output {o} as input {i} (spelling {n}): {e}",
                        self.name
                    );
                }
                self.unchanged();
            }
            for &p in outputs.iter().filter(|&&p| p > o) {
                let same = path_at(&self.tokens, o).to_path_buf();
                let e = self.refused_with(p, &same);
                assert!(
                    e.contains("are the same file") && e.contains(&same.display().to_string()),
                    "`oslf {}`: outputs {o} and {p}: {e}",
                    self.name
                );
            }
        }
    }

    /// Each output (file, prefix, directory) at a FIFO, a full device and a directory:
    /// refused, named, kept.
    fn outputs_at_nodes(&mut self) {
        for o in self.slots(&[Kind::Output, Kind::Prefix, Kind::Dir]) {
            let kind = self.kind(o);
            for what in ["fifo", "device", "dir"] {
                if kind == Kind::Dir && what == "dir" {
                    continue;
                }
                let (given, at) = match kind {
                    // The first file a prefix names: PREFIX-recon.exr (truth's default modes).
                    Kind::Prefix => (self.dir.join("node-p"), self.dir.join("node-p-recon.exr")),
                    _ => (self.dir.join("node-x.exr"), self.dir.join("node-x.exr")),
                };
                let called = node(&at, what, false);
                let e = self.refused_with(o, &given);
                let says = if kind == Kind::Dir {
                    "not a directory"
                } else {
                    called
                };
                assert!(
                    e.contains(&at.display().to_string()) && e.contains(says),
                    "`oslf {}`: output {o} at a {what}: {e}",
                    self.name
                );
                let meta = std::fs::symlink_metadata(&at).expect("the node was removed");
                assert!(!meta.is_file(), "the {what} was replaced by a file");
                self.unchanged();
            }
        }
    }

    /// A prefix whose first file is an input (a hard link to it); a directory at an input.
    fn prefixes_and_directories_over_inputs(&mut self) {
        let inputs = self.slots(&[Kind::Input]);
        for o in self.slots(&[Kind::Prefix]) {
            for &i in &inputs {
                let input = path_at(&self.tokens, i).to_path_buf();
                let first = self.dir.join("node-q-recon.exr");
                std::fs::hard_link(&input, &first).unwrap();
                let e = self.refused_with(o, &self.dir.join("node-q"));
                assert!(
                    e.contains(&first.display().to_string())
                        && e.contains(&input.display().to_string())
                        && e.contains("the same file"),
                    "`oslf {}`: prefix {o} over input {i}: {e}",
                    self.name
                );
                self.unchanged();
            }
        }
        for o in self.slots(&[Kind::Dir]) {
            for &i in &inputs {
                let input = path_at(&self.tokens, i).to_path_buf();
                let e = self.refused_with(o, &input);
                assert!(
                    e.contains(&input.display().to_string()) && e.contains("not a directory"),
                    "`oslf {}`: directory {o} at input {i}: {e}",
                    self.name
                );
            }
        }
    }

    /// Each input at a FIFO (refused within a second), a device and a directory.
    fn inputs_at_nodes(&mut self) {
        for i in self.slots(&[Kind::Input]) {
            for what in ["fifo", "device", "dir"] {
                let at = self.dir.join("node-in");
                let called = node(&at, what, true);
                let t = std::time::Instant::now();
                let e = self.refused_with(i, &at);
                if what == "fifo" {
                    assert!(
                        t.elapsed() < Duration::from_secs(1),
                        "`oslf {}` took {:?} to refuse a FIFO",
                        self.name,
                        t.elapsed()
                    );
                }
                assert!(
                    e.contains(&at.display().to_string()) && e.contains(called),
                    "`oslf {}`: input {i} at a {what}: {e}",
                    self.name
                );
                self.unchanged();
            }
        }
    }
}

#[test]
fn every_door_refuses_outputs_over_inputs_nodes_and_fifos() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    fixtures(dir);
    let leaves = leaves();
    let base: BTreeMap<&str, &str> = BASE.iter().copied().collect();
    for name in leaves.keys() {
        assert!(
            base.contains_key(name.as_str()),
            "`oslf {name}` has no base invocation in door_tests::BASE"
        );
    }
    let before = snapshot(dir);
    let mut tried = 0;
    for (name, args) in &leaves {
        let mut case = Case {
            name,
            tokens: parse_base(base[name.as_str()], dir),
            args,
            dir,
            before: &before,
            limit: Duration::from_secs(60),
            tried,
        };
        case.check_coverage();
        case.outputs_over_inputs();
        case.outputs_at_nodes();
        case.prefixes_and_directories_over_inputs();
        case.inputs_at_nodes();
        case.unchanged();
        tried = case.tried;
    }
    assert!(tried > 150, "only {tried} cases were tried");
}

/// The forms the issue named, which the table cannot derive: outputs beside an output (the
/// PNG of `render`, the EXR of `--preview`) and a file the scene includes.
#[test]
fn derived_outputs_and_included_files_are_doors_too() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    fixtures(dir);
    let before = snapshot(dir);
    let limit = Duration::from_secs(60);
    let run = |words: &[&str]| -> String {
        let tokens: Vec<Token> = words
            .iter()
            .map(|w| match w.strip_prefix('/') {
                Some(name) => Token::Path {
                    id: String::new(),
                    path: dir.join(name),
                },
                None => Token::Word(w.to_string()),
            })
            .collect();
        refused(&tokens, limit)
    };
    let path = |n: &str| dir.join(n).display().to_string();
    // The store given as st.png: `render st.png -o st.exr` writes its PNG over it.
    std::fs::copy(dir.join("st.oslf"), dir.join("st.png")).unwrap();
    let before_png = snapshot(dir);
    let e = run(&["render", "/st.png", "-o", "/st.exr"]);
    assert!(
        e.contains("the PNG beside --output") && e.contains(&path("st.png")),
        "{e}"
    );
    // The scene's own OBJ file as the store.
    let e = run(&["bake", "/scene.toml", "-q", "-o", "/floor.obj"]);
    assert!(
        e.contains("a file SCENE includes") && e.contains(&path("floor.obj")),
        "{e}"
    );
    // The preview's EXR over the report.
    let e = run(&[
        "bake",
        "/scene.toml",
        "-q",
        "-o",
        "/o.oslf",
        "--preview",
        "/x.png",
        "--report-json",
        "/x.exr",
    ]);
    assert!(
        e.contains("the EXR beside --preview") && e.contains("--report-json"),
        "{e}"
    );
    assert_eq!(snapshot(dir), before_png);
    std::fs::remove_file(dir.join("st.png")).unwrap();
    // One of the six face files of `export-cube --layout faces` is the store (a hard link).
    std::fs::hard_link(dir.join("st.oslf"), dir.join("cube_nz.exr")).unwrap();
    let e = run(&[
        "store",
        "export-cube",
        "/st.oslf",
        "0",
        "--layout",
        "faces",
        "-o",
        "/cube.exr",
    ]);
    assert!(
        e.contains("the nz face file of --output") && e.contains(&path("cube_nz.exr")),
        "{e}"
    );
    std::fs::remove_file(dir.join("cube_nz.exr")).unwrap();
    assert_eq!(snapshot(dir), before);
}
