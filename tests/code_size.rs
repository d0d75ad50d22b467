//! Every source file of every crate stays readable: at most [`FILE_LINES`] lines of code
//! (outside `#[cfg(test)]` items, blank lines and comments not counted) and no function longer
//! than [`FN_LINES`] lines. The sources are rustfmt'd, so a function ends at the first `}` at
//! its own indentation; WGSL follows the same layout. The shaders assembled from WGSL modules
//! live outside `src/` (each crate's `generated/`); their modules are measured.

use std::path::{Path, PathBuf};

const FILE_LINES: usize = 800;
const FN_LINES: usize = 120;

#[test]
fn no_source_file_or_function_is_too_long() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut files = Vec::new();
    collect(&root.join("src"), &mut files);
    for entry in std::fs::read_dir(root).unwrap() {
        let dir = entry.unwrap().path();
        if dir.join("Cargo.toml").is_file() {
            collect(&dir.join("src"), &mut files);
        }
    }
    assert!(files.len() > 50, "found only {} source files", files.len());
    let mut report = Vec::new();
    for file in &files {
        let text = std::fs::read_to_string(file).unwrap();
        let name = file.strip_prefix(root).unwrap().display();
        let (code, functions) = measure(&text);
        if code > FILE_LINES {
            report.push(format!("{name}: {code} lines of code (limit {FILE_LINES})"));
        }
        for (fn_name, line, length) in functions {
            if length > FN_LINES {
                report.push(format!(
                    "{name}:{line}: fn {fn_name} is {length} lines (limit {FN_LINES})"
                ));
            }
        }
    }
    assert!(report.is_empty(), "too long:\n{}", report.join("\n"));
}

#[test]
fn the_measure_counts_code_and_functions_and_skips_tests() {
    let mut text = String::from("//! docs\nuse a;\n\nfn short() {\n    let x = 1;\n}\n");
    text.push_str("pub(crate) fn long() -> u32 {\n");
    for i in 0..130 {
        text.push_str(&format!("    let v{i} = {i};\n"));
    }
    text.push_str("    if true {\n        1\n    } else {\n        2\n    }\n}\n");
    text.push_str("#[cfg(test)]\nmod tests {\n    fn huge() {\n");
    for _ in 0..1000 {
        text.push_str("        x();\n");
    }
    text.push_str("    }\n}\n");
    let (code, functions) = measure(&text);
    // use, short's 3 lines, long's 1 + 130 + 5 + 1 lines.
    assert_eq!(code, 1 + 3 + 137);
    assert_eq!(
        functions,
        vec![("short".into(), 4, 3), ("long".into(), 7, 137)]
    );
    let wgsl =
        "fn f(x: f32) -> f32 {\n    // note\n    return x;\n}\nfn g() -> u32 { return 1u; }\n";
    assert_eq!(
        measure(wgsl),
        (4, vec![("f".into(), 1, 4), ("g".into(), 5, 1)])
    );
}

fn collect(dir: &Path, out: &mut Vec<PathBuf>) {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    for entry in entries {
        let path = entry.unwrap().path();
        if path.is_dir() {
            collect(&path, out);
        } else if path.extension().is_some_and(|e| e == "rs" || e == "wgsl") {
            out.push(path);
        }
    }
}

/// Lines of code outside `#[cfg(test)]` items, and every function as (name, first line,
/// length in lines).
fn measure(text: &str) -> (usize, Vec<(String, usize, usize)>) {
    let lines: Vec<&str> = text.lines().collect();
    // (1-based line number, text) outside test items.
    let mut kept: Vec<(usize, &str)> = Vec::new();
    let mut i = 0;
    while i < lines.len() {
        if lines[i].trim_start().starts_with("#[cfg(test)]") {
            let indent = indent_of(lines[i]);
            i += 1;
            // Attributes, then the item: up to a `;` ending its first line, or through the
            // closing brace at the attribute's indentation.
            while i < lines.len() && lines[i].trim_start().starts_with("#[") {
                i += 1;
            }
            if i < lines.len() && lines[i].trim_end().ends_with(';') {
                i += 1;
                continue;
            }
            i += 1;
            while i < lines.len() && !(indent_of(lines[i]) == indent && lines[i].trim() == "}") {
                i += 1;
            }
            i += 1;
            continue;
        }
        kept.push((i + 1, lines[i]));
        i += 1;
    }
    let code = kept
        .iter()
        .filter(|(_, l)| {
            let t = l.trim();
            !t.is_empty() && !t.starts_with("//")
        })
        .count();
    let mut functions = Vec::new();
    for (k, (line, l)) in kept.iter().enumerate() {
        let Some(name) = fn_name(l) else { continue };
        if l.trim_end().ends_with(';') {
            continue; // a declaration without a body
        }
        if l.contains('{') && l.trim_end().ends_with('}') {
            functions.push((name, *line, 1));
            continue;
        }
        let indent = indent_of(l);
        let end = kept[k + 1..]
            .iter()
            .find(|(_, l2)| indent_of(l2) == indent && l2.trim_start().starts_with('}'));
        if let Some((end, _)) = end {
            functions.push((name, *line, end - line + 1));
        }
    }
    (code, functions)
}

fn indent_of(line: &str) -> usize {
    line.len() - line.trim_start().len()
}

/// The name of the function a line opens: `fn name`, after `pub`, `pub(crate)`, `const`,
/// `async`, `unsafe`, `extern "C"`.
fn fn_name(line: &str) -> Option<String> {
    let mut words = line.split_whitespace().peekable();
    while let Some(w) = words.next() {
        match w {
            "fn" => {
                let name: String = words
                    .next()?
                    .chars()
                    .take_while(|c| c.is_alphanumeric() || *c == '_')
                    .collect();
                return (!name.is_empty()).then_some(name);
            }
            "pub" | "const" | "async" | "unsafe" | "extern" | "\"C\"" | "default" => {}
            w if w.starts_with("pub(") => {}
            _ => return None,
        }
    }
    None
}
