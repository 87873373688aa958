//! The layer rule of ARCHITECTURE.md, checked on the source: a module's code (tests aside)
//! imports only modules of its own layer or lower ones, the imports between the top-level
//! modules form no cycle (so within a layer the order is one way, e.g. `model` → `structure`,
//! `mesh` → `fe`), no two files of one module import each other through a chain of siblings
//! (a file and its own submodules aside: a parent declares and re-exports its children), and
//! `src/lib.rs` declares exactly the modules of ARCHITECTURE.md's table.
//!
//! Imports are read from the text: `use` trees (nested braces included) and inline
//! `crate::…`, `super::…`, `self::…` paths and `child::…` paths of declared submodules, in
//! code outside comments and `#[cfg(test)]` items; files that are test modules are skipped.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

const ROOT: &str = env!("CARGO_MANIFEST_DIR");

/// The layer of each top-level module from ARCHITECTURE.md's table (`| N | `name` | …`).
fn layers() -> BTreeMap<String, u32> {
    let text = std::fs::read_to_string(Path::new(ROOT).join("ARCHITECTURE.md")).unwrap();
    let mut out = BTreeMap::new();
    for line in text.lines() {
        let cells: Vec<&str> = line.split('|').map(str::trim).collect();
        if cells.len() < 4 {
            continue;
        }
        let (Ok(layer), Some(name)) = (
            cells[1].parse::<u32>(),
            cells[2].strip_prefix('`').and_then(|s| s.strip_suffix('`')),
        ) else {
            continue;
        };
        out.insert(name.to_string(), layer);
    }
    out
}

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for e in std::fs::read_dir(dir).unwrap() {
        let p = e.unwrap().path();
        if p.is_dir() {
            rust_files(&p, out);
        } else if p.extension().is_some_and(|x| x == "rs") {
            out.push(p);
        }
    }
}

/// The module path of a file under `src/` (`src/a/b.rs` and `src/a/b/mod.rs` → `[a, b]`).
fn module_path(src: &Path, file: &Path) -> Vec<String> {
    let rel = file.strip_prefix(src).unwrap().with_extension("");
    let mut v: Vec<String> = rel
        .components()
        .map(|c| c.as_os_str().to_string_lossy().into_owned())
        .collect();
    if matches!(v.last().map(String::as_str), Some("mod" | "lib" | "main")) {
        v.pop();
    }
    v
}

/// The code of a file without comment lines and without `#[cfg(test)]` items.
fn code_of(text: &str) -> String {
    let lines: Vec<&str> = text.lines().collect();
    let mut out = String::new();
    let mut i = 0;
    while i < lines.len() {
        let t = lines[i].trim_start();
        if t.starts_with("#[cfg(test)]") {
            // skip the next item: up to its `;` or its balanced braces
            let mut depth = 0i64;
            let mut opened = false;
            i += 1;
            while i < lines.len() {
                for c in lines[i].chars() {
                    match c {
                        '{' => {
                            depth += 1;
                            opened = true
                        }
                        '}' => depth -= 1,
                        _ => {}
                    }
                }
                let ends =
                    (opened && depth <= 0) || (!opened && lines[i].trim_end().ends_with(';'));
                i += 1;
                if ends {
                    break;
                }
            }
            continue;
        }
        if !t.starts_with("//") {
            out.push_str(lines[i]);
            out.push('\n');
        }
        i += 1;
    }
    out
}

/// The paths of a `use` tree (`a::{b, c::{d, e}}` → `a::b`, `a::c::d`, `a::c::e`).
fn expand_tree(prefix: &str, tree: &str, out: &mut Vec<String>) {
    let tree = tree.trim();
    match tree.find('{') {
        None => {
            let t = tree.split(" as ").next().unwrap().trim();
            let t = t.trim_end_matches("::*").trim_end_matches("::self");
            if !t.is_empty() && t != "self" && t != "*" {
                out.push(format!("{prefix}{t}"));
            } else if t == "self" || t == "*" {
                out.push(prefix.trim_end_matches("::").to_string());
            }
        }
        Some(open) => {
            let head = &tree[..open];
            let Some(close) = tree.rfind('}').filter(|&c| c > open) else {
                return;
            };
            let inner = &tree[open + 1..close];
            let mut depth = 0;
            let mut start = 0;
            let p = format!("{prefix}{head}");
            for (i, c) in inner.char_indices() {
                match c {
                    '{' => depth += 1,
                    '}' => depth -= 1,
                    ',' if depth == 0 => {
                        expand_tree(&p, &inner[start..i], out);
                        start = i + 1;
                    }
                    _ => {}
                }
            }
            expand_tree(&p, &inner[start..], out);
        }
    }
}

fn is_ident(c: char) -> bool {
    c.is_alphanumeric() || c == '_'
}

/// Every path the code names: `use` trees and inline `a::b::c` paths.
fn paths(code: &str) -> Vec<String> {
    let mut out = Vec::new();
    // use trees: statements that start a line (`use`, `pub use`, `pub(crate) use`, …)
    let mut offset = 0;
    for line in code.split_inclusive('\n') {
        let t = line.trim_start();
        let t = t
            .strip_prefix("pub(crate) ")
            .or_else(|| t.strip_prefix("pub(super) "))
            .or_else(|| t.strip_prefix("pub "))
            .unwrap_or(t);
        if let Some(tree) = t.strip_prefix("use ") {
            let start = offset + (line.len() - tree.len());
            if let Some(end) = code[start..].find(';') {
                expand_tree("", &code[start..start + end], &mut out);
            }
        }
        offset += line.len();
    }
    // inline paths: identifier chains joined by `::`
    let chars: Vec<char> = code.chars().collect();
    let mut i = 0;
    while i < chars.len() {
        if is_ident(chars[i]) && (i == 0 || (!is_ident(chars[i - 1]) && chars[i - 1] != ':')) {
            let mut j = i;
            let mut segs = vec![];
            loop {
                let s = j;
                while j < chars.len() && is_ident(chars[j]) {
                    j += 1;
                }
                segs.push(chars[s..j].iter().collect::<String>());
                if j + 2 < chars.len()
                    && chars[j] == ':'
                    && chars[j + 1] == ':'
                    && is_ident(chars[j + 2])
                {
                    j += 2;
                } else {
                    break;
                }
            }
            if segs.len() > 1 {
                out.push(segs.join("::"));
            }
            i = j.max(i + 1);
        } else {
            i += 1;
        }
    }
    out
}

struct Source {
    files: BTreeMap<Vec<String>, PathBuf>,
    code: BTreeMap<Vec<String>, String>,
}

fn source() -> Source {
    let src = Path::new(ROOT).join("src");
    let mut list = Vec::new();
    rust_files(&src, &mut list);
    let mut files = BTreeMap::new();
    let mut texts = BTreeMap::new();
    for f in list {
        let m = module_path(&src, &f);
        texts.insert(m.clone(), std::fs::read_to_string(&f).unwrap());
        files.insert(m, f);
    }
    // files declared as test modules (`#[cfg(test)] mod x;`) and everything under them
    let mut test_mods: BTreeSet<Vec<String>> = BTreeSet::new();
    for (m, t) in &texts {
        let lines: Vec<&str> = t.lines().collect();
        for w in lines.windows(2) {
            if w[0].trim() == "#[cfg(test)]" {
                let decl = w[1]
                    .trim()
                    .trim_start_matches("pub(crate) ")
                    .trim_start_matches("pub ");
                if let Some(name) = decl.strip_prefix("mod ").and_then(|s| s.strip_suffix(';')) {
                    let mut p = m.clone();
                    p.push(name.trim().to_string());
                    test_mods.insert(p);
                }
            }
        }
    }
    let code = texts
        .into_iter()
        .filter(|(m, _)| !test_mods.iter().any(|t| m.starts_with(t)))
        .map(|(m, t)| (m, code_of(&t)))
        .collect();
    Source { files, code }
}

/// The file modules a file's code refers to (the longest known prefix of each path).
fn file_edges(s: &Source) -> BTreeMap<Vec<String>, BTreeSet<Vec<String>>> {
    let mut g: BTreeMap<Vec<String>, BTreeSet<Vec<String>>> = BTreeMap::new();
    for (me, code) in &s.code {
        let mut deps = BTreeSet::new();
        for p in paths(code) {
            let segs: Vec<&str> = p.split("::").collect();
            let (base, rest): (Vec<String>, &[&str]) = match segs[0] {
                "crate" => (vec![], &segs[1..]),
                "self" => (me.clone(), &segs[1..]),
                "super" => {
                    let mut b = me.clone();
                    let mut k = 0;
                    while k < segs.len() && segs[k] == "super" {
                        b.pop();
                        k += 1;
                    }
                    (b, &segs[k..])
                }
                first => {
                    // a declared child module of this file
                    let mut c = me.clone();
                    c.push(first.to_string());
                    if s.files.contains_key(&c) {
                        (me.clone(), &segs[..])
                    } else {
                        continue;
                    }
                }
            };
            let mut full = base;
            full.extend(rest.iter().map(|x| x.to_string()));
            while !full.is_empty() {
                if s.files.contains_key(&full) {
                    if &full != me {
                        deps.insert(full.clone());
                    }
                    break;
                }
                full.pop();
            }
        }
        g.insert(me.clone(), deps);
    }
    g
}

/// Strongly connected components with more than one member (Tarjan).
fn cycles(g: &BTreeMap<Vec<String>, BTreeSet<Vec<String>>>) -> Vec<Vec<Vec<String>>> {
    struct T<'a> {
        g: &'a BTreeMap<Vec<String>, BTreeSet<Vec<String>>>,
        index: BTreeMap<&'a Vec<String>, usize>,
        low: BTreeMap<&'a Vec<String>, usize>,
        stack: Vec<&'a Vec<String>>,
        on: BTreeSet<&'a Vec<String>>,
        out: Vec<Vec<Vec<String>>>,
    }
    fn visit<'a>(t: &mut T<'a>, v: &'a Vec<String>) {
        let n = t.index.len();
        t.index.insert(v, n);
        t.low.insert(v, n);
        t.stack.push(v);
        t.on.insert(v);
        let g = t.g;
        for w in g.get(v).into_iter().flatten() {
            if !t.index.contains_key(w) {
                visit(t, w);
                let lw = t.low[w];
                let lv = t.low.get_mut(v).unwrap();
                *lv = (*lv).min(lw);
            } else if t.on.contains(w) {
                let iw = t.index[w];
                let lv = t.low.get_mut(v).unwrap();
                *lv = (*lv).min(iw);
            }
        }
        if t.low[v] == t.index[v] {
            let mut comp = vec![];
            loop {
                let w = t.stack.pop().unwrap();
                t.on.remove(w);
                comp.push(w.clone());
                if w == v {
                    break;
                }
            }
            if comp.len() > 1 {
                t.out.push(comp);
            }
        }
    }
    let mut t = T {
        g,
        index: BTreeMap::new(),
        low: BTreeMap::new(),
        stack: vec![],
        on: BTreeSet::new(),
        out: vec![],
    };
    for v in g.keys() {
        if !t.index.contains_key(v) {
            visit(&mut t, v);
        }
    }
    t.out
}

#[test]
fn lib_rs_declares_the_modules_of_the_architecture_table() {
    let table: BTreeSet<String> = layers().keys().cloned().collect();
    let lib = std::fs::read_to_string(Path::new(ROOT).join("src/lib.rs")).unwrap();
    let declared: BTreeSet<String> = lib
        .lines()
        .filter_map(|l| l.trim().strip_prefix("pub mod "))
        .map(|s| s.trim_end_matches(';').to_string())
        .collect();
    assert!(
        table.len() >= 15,
        "ARCHITECTURE.md's table parsed to {table:?}"
    );
    assert_eq!(
        declared, table,
        "src/lib.rs against ARCHITECTURE.md's table"
    );
}

#[test]
fn no_module_imports_a_higher_layer_and_the_modules_form_no_cycle() {
    let layers = layers();
    let s = source();
    let g = file_edges(&s);
    let mut violations = vec![];
    let mut modules: BTreeMap<Vec<String>, BTreeSet<Vec<String>>> = BTreeMap::new();
    for (file, deps) in &g {
        let Some(top) = file.first() else { continue };
        if top == "cli" || top == "main" {
            continue; // layer 6: the binary
        }
        let own = layers[top];
        for d in deps {
            let to = &d[0];
            if to == top {
                continue;
            }
            let l = layers[to];
            if l > own {
                violations.push(format!(
                    "{} (layer {own}) imports {to} (layer {l})",
                    file.join("::")
                ));
            }
            modules
                .entry(vec![top.clone()])
                .or_default()
                .insert(vec![to.clone()]);
        }
    }
    assert!(
        violations.is_empty(),
        "imports against the layer order:\n{}",
        violations.join("\n")
    );
    let c = cycles(&modules);
    assert!(
        c.is_empty(),
        "top-level modules importing each other: {c:?}"
    );
}

#[test]
fn no_two_sibling_files_import_each_other() {
    let s = source();
    let mut g = file_edges(&s);
    // a parent declares and re-exports its children, and they name its items: not a cycle
    for (v, deps) in g.iter_mut() {
        deps.retain(|w| !w.starts_with(v) && !v.starts_with(w));
    }
    let c = cycles(&g);
    let shown: Vec<String> = c
        .iter()
        .map(|comp| {
            comp.iter()
                .map(|m| m.join("::"))
                .collect::<Vec<_>>()
                .join(" ↔ ")
        })
        .collect();
    assert!(c.is_empty(), "file cycles:\n{}", shown.join("\n"));
}

/// The checks above see what they are meant to see: a use tree with nested braces, inline
/// paths, and a planted cycle.
#[test]
fn the_import_reader_reads_nested_use_trees_and_finds_a_planted_cycle() {
    let mut out = vec![];
    expand_tree("", "crate::a::{b, c::{d, e as f}, g::*}", &mut out);
    assert_eq!(
        out,
        [
            "crate::a::b",
            "crate::a::c::d",
            "crate::a::c::e",
            "crate::a::g"
        ]
    );
    let p = paths("fn f() { let x = crate::x::y::Z::new(); }\n// crate::no\n");
    assert!(p.contains(&"crate::x::y::Z::new".to_string()), "{p:?}");
    assert_eq!(
        code_of("a\n#[cfg(test)]\nmod t {\n  x\n}\nb\n// c\n"),
        "a\nb\n"
    );
    let mut g = BTreeMap::new();
    let (a, b, c) = (
        vec!["a".to_string()],
        vec!["b".to_string()],
        vec!["c".to_string()],
    );
    g.insert(a.clone(), BTreeSet::from([b.clone()]));
    g.insert(b.clone(), BTreeSet::from([c.clone()]));
    g.insert(c.clone(), BTreeSet::from([a.clone()]));
    assert_eq!(cycles(&g).len(), 1);
    g.get_mut(&c).unwrap().clear();
    assert!(cycles(&g).is_empty());
}

/// No glob imports: every `use` names what it brings in (test modules and integration tests
/// included), so a reader sees where a name comes from and an enum variant never silently
/// becomes a pattern binding. External crates' `prelude::*` modules are the one exception:
/// they are written to be glob-imported.
#[test]
fn no_glob_imports_but_external_preludes() {
    let root = Path::new(ROOT);
    let mut files = Vec::new();
    for dir in ["src", "tests", "examples", "python/src"] {
        if root.join(dir).is_dir() {
            rust_files(&root.join(dir), &mut files);
        }
    }
    let mut found = Vec::new();
    for f in &files {
        let text = std::fs::read_to_string(f).unwrap();
        for (i, line) in text.lines().enumerate() {
            let t = line.trim_start();
            let is_use = t.starts_with("use ")
                || t.starts_with("pub use ")
                || t.starts_with("pub(crate) use ");
            if is_use && t.contains("::*") && !t.contains("prelude::*") {
                found.push(format!("{}:{}: {}", f.display(), i + 1, t));
            }
        }
    }
    assert!(files.len() > 100, "read {} files", files.len());
    assert!(found.is_empty(), "glob imports:\n{}", found.join("\n"));
}
