//! No module of the core imports another that imports it back: the graph of the top-level
//! modules (`frame`, `snow`, `weather`, ...), read from the `crate::<module>` paths in each
//! module's source (comments and test modules left out), has no cycle.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

type Graph = BTreeMap<String, BTreeSet<String>>;

fn sources(dir: &Path, out: &mut Vec<PathBuf>) {
    for entry in std::fs::read_dir(dir).expect("src is readable") {
        let p = entry.expect("a directory entry").path();
        if p.is_dir() {
            // A folder named `tests` holds test modules only.
            if p.file_name().is_some_and(|n| n != "tests") {
                sources(&p, out);
            }
        } else if p.extension().is_some_and(|e| e == "rs")
            && p.file_name().is_some_and(|n| n != "tests.rs")
        {
            out.push(p);
        }
    }
}

/// The `crate::<name>` paths of `code`, outside comments and before its test module.
fn imports(code: &str) -> BTreeSet<String> {
    let code = code.find("#[cfg(test)]\nmod").map_or(code, |i| &code[..i]);
    let mut found = BTreeSet::new();
    for line in code.lines() {
        let line = line.split("//").next().unwrap_or("");
        let mut rest = line;
        while let Some(i) = rest.find("crate::") {
            rest = &rest[i + "crate::".len()..];
            let name: String = rest
                .chars()
                .take_while(|c| c.is_ascii_lowercase() || c.is_ascii_digit() || *c == '_')
                .collect();
            if !name.is_empty() {
                found.insert(name);
            }
        }
    }
    found
}

fn graph(src: &Path) -> Graph {
    let mut files = Vec::new();
    sources(src, &mut files);
    let mut g = Graph::new();
    for f in files {
        let rel = f.strip_prefix(src).expect("under src");
        let top = rel
            .components()
            .next()
            .and_then(|c| c.as_os_str().to_str())
            .expect("a name")
            .trim_end_matches(".rs")
            .to_string();
        if top == "lib" {
            continue;
        }
        let code = std::fs::read_to_string(&f).expect("readable source");
        let deps = g.entry(top.clone()).or_default();
        deps.extend(imports(&code).into_iter().filter(|d| *d != top));
    }
    g
}

/// A cycle of `g`, when it has one (depth-first search with colours).
fn cycle(g: &Graph) -> Option<Vec<String>> {
    fn visit(
        g: &Graph,
        n: &str,
        state: &mut BTreeMap<String, u8>,
        path: &mut Vec<String>,
    ) -> Option<Vec<String>> {
        match state.get(n) {
            Some(2) => return None,
            Some(1) => {
                let start = path.iter().position(|p| p == n).unwrap_or(0);
                let mut c = path[start..].to_vec();
                c.push(n.to_string());
                return Some(c);
            }
            _ => {}
        }
        state.insert(n.to_string(), 1);
        path.push(n.to_string());
        for d in g.get(n).into_iter().flatten() {
            if let Some(c) = visit(g, d, state, path) {
                return Some(c);
            }
        }
        path.pop();
        state.insert(n.to_string(), 2);
        None
    }
    let mut state = BTreeMap::new();
    for n in g.keys() {
        if let Some(c) = visit(g, n, &mut state, &mut Vec::new()) {
            return Some(c);
        }
    }
    None
}

#[test]
fn the_core_modules_form_no_cycle() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let g = graph(&src);
    // The graph was read: the frame pipeline imports the effects.
    assert!(
        g["frame"].contains("haze") && g["frame"].contains("snow"),
        "{g:?}"
    );
    assert!(g["snow"].contains("particles"), "{g:?}");
    if let Some(c) = cycle(&g) {
        panic!("modules import each other: {}", c.join(" -> "));
    }
}

#[test]
fn the_checker_finds_a_cycle_and_skips_comments_and_tests() {
    let code = "use crate::a::X;\n// crate::b in a comment\nlet y = crate::c::f(); // crate::d\n\
                #[cfg(test)]\nmod tests { use crate::e; }";
    let want: BTreeSet<String> = ["a", "c"].iter().map(|s| s.to_string()).collect();
    assert_eq!(imports(code), want);
    let mut g = Graph::new();
    for (a, b) in [("x", "y"), ("y", "z"), ("z", "x"), ("w", "x")] {
        g.entry(a.into()).or_default().insert(b.into());
    }
    let c = cycle(&g).expect("x -> y -> z -> x");
    assert_eq!(c.first(), c.last());
    assert_eq!(c.len(), 4);
    g.get_mut("z").unwrap().clear();
    assert_eq!(cycle(&g), None);
}
