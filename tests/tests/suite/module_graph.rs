//! No import cycles between the top-level modules of any crate (issue 14: `grid` ↔
//! `solver` ↔ `cpu` in core, `cli` ↔ `gui` ↔ `bench` in the app). A cycle means two
//! modules cannot be understood, tested or moved one without the other; the layering this
//! test keeps is the one docs/architecture.md's "The crates" describes.
//!
//! How: a module's dependencies are the `crate::<module>` paths in its files (a file
//! `src/m.rs`, or every file under `src/m/`), outside comments and `#[cfg(test)]` blocks.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

const CRATES: [&str; 7] = ["core", "cpu", "engine", "shaders", "backend-wgpu", "backend-vulkan", "app"];

fn files(path: &Path, out: &mut Vec<PathBuf>) {
    if path.is_dir() {
        let mut entries: Vec<_> = std::fs::read_dir(path).unwrap().map(|e| e.unwrap().path()).collect();
        entries.sort();
        for e in entries {
            files(&e, out);
        }
    } else if path.extension().is_some_and(|e| e == "rs") {
        out.push(path.to_owned());
    }
}

/// The code of a file without line comments and without what follows its first
/// `#[cfg(test)]` (the tests modules sit at the ends of the files).
fn code(text: &str) -> String {
    let text = text.split("#[cfg(test)]").next().unwrap_or("");
    text.lines().filter(|l| !l.trim_start().starts_with("//")).map(|l| l.split(" // ").next().unwrap_or(l)).fold(
        String::new(),
        |mut s, l| {
            s.push_str(l);
            s.push('\n');
            s
        },
    )
}

/// The modules of `modules` that `code` names through `prefix` (`crate::` for a crate's
/// top-level modules; `super::` or `crate::bench::` for the modules of `bench/`).
fn uses(code: &str, prefix: &str, modules: &BTreeSet<String>) -> BTreeSet<String> {
    let ident = |s: &str| s.chars().take_while(|c| c.is_alphanumeric() || *c == '_').collect::<String>();
    let mut found = BTreeSet::new();
    for (i, _) in code.match_indices(prefix) {
        // `crate::` inside `foo_crate::` or `super::` inside `super::super::` is not it.
        if code[..i].ends_with(|c: char| c.is_alphanumeric() || c == '_' || c == ':') {
            continue;
        }
        let rest = &code[i + prefix.len()..];
        if let Some(group) = rest.strip_prefix('{') {
            // `crate::{a::X, b, c::{..}}`: every item's first segment, at brace depth 0.
            let mut depth = 0;
            let mut start = true;
            for (k, ch) in group.char_indices() {
                match ch {
                    '{' => depth += 1,
                    '}' if depth == 0 => break,
                    '}' => depth -= 1,
                    ',' if depth == 0 => start = true,
                    c if start && (c.is_alphanumeric() || c == '_') => {
                        found.insert(ident(&group[k..]));
                        start = false;
                    }
                    _ => {}
                }
            }
        } else {
            found.insert(ident(rest));
        }
    }
    found.retain(|m| modules.contains(m));
    found
}

/// The module graph of the modules in `dir` (a crate's `src/`, or a directory module's
/// folder): module → the modules beside it that it names. `prefixes`: how a module names a
/// sibling (`crate::` at the top; `super::` from a file directly in a directory module,
/// `crate::<dir>::` from anywhere); `super::` counts only in the files directly in `dir`.
fn graph(dir: &Path, prefixes: &[String]) -> BTreeMap<String, BTreeSet<String>> {
    let mut modules = BTreeMap::new();
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        let name = path.file_stem().unwrap().to_string_lossy().into_owned();
        if !["lib", "main", "mod"].contains(&name.as_str())
            && (path.is_dir() || path.extension().is_some_and(|e| e == "rs"))
        {
            modules.insert(name, path);
        }
    }
    let names: BTreeSet<String> = modules.keys().cloned().collect();
    modules
        .into_iter()
        .map(|(name, path)| {
            let mut list = Vec::new();
            files(&path, &mut list);
            let mut deps = BTreeSet::new();
            for f in list {
                let text = code(&std::fs::read_to_string(&f).unwrap());
                for prefix in prefixes {
                    if prefix == "super::" && f.parent() != Some(dir) {
                        continue;
                    }
                    deps.extend(uses(&text, prefix, &names));
                }
            }
            deps.remove(&name);
            (name, deps)
        })
        .collect()
}

/// A cycle of `g`, as the modules along it, if there is one.
fn cycle(g: &BTreeMap<String, BTreeSet<String>>) -> Option<Vec<String>> {
    fn visit(
        m: &str,
        g: &BTreeMap<String, BTreeSet<String>>,
        path: &mut Vec<String>,
        done: &mut BTreeSet<String>,
    ) -> Option<Vec<String>> {
        if let Some(at) = path.iter().position(|p| p == m) {
            let mut c = path[at..].to_vec();
            c.push(m.to_owned());
            return Some(c);
        }
        if done.contains(m) {
            return None;
        }
        path.push(m.to_owned());
        for d in g.get(m).into_iter().flatten() {
            if let Some(c) = visit(d, g, path, done) {
                return Some(c);
            }
        }
        path.pop();
        done.insert(m.to_owned());
        None
    }
    let mut done = BTreeSet::new();
    g.keys().find_map(|m| visit(m, g, &mut Vec::new(), &mut done))
}

#[test]
fn the_parser_sees_a_cycle_and_grouped_imports() {
    let names: BTreeSet<String> = ["a", "b", "c"].iter().map(|s| s.to_string()).collect();
    let deps = uses(&code("use crate::{a::X, b};\n// crate::c\nfn f() { crate::c::g() }\n"), "crate::", &names);
    assert_eq!(deps, names, "grouped items, plain paths; the comment alone would not count");
    let in_tests = uses(&code("use crate::a;\n#[cfg(test)]\nmod tests { use crate::b; }\n"), "crate::", &names);
    let siblings = uses(&code("use super::{a::X, b};\nuse other_crate::c;\n"), "super::", &names);
    assert_eq!(siblings.len(), 2, "{siblings:?}: `super::` paths, not another crate's");
    assert_eq!(in_tests.len(), 1, "{in_tests:?}: test modules may reach back");
    let g: BTreeMap<String, BTreeSet<String>> = [("a", "b"), ("b", "c"), ("c", "a")]
        .iter()
        .map(|(m, d)| (m.to_string(), BTreeSet::from([d.to_string()])))
        .collect();
    assert_eq!(cycle(&g).map(|c| c.len()), Some(4), "a → b → c → a");
}

#[test]
fn no_crate_and_no_directory_module_has_an_import_cycle() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let mut directories = 0;
    for krate in CRATES {
        let src = root.join(krate).join("src");
        let g = graph(&src, &["crate::".to_owned()]);
        assert!(g.len() >= 2 || krate == "shaders", "{krate}: {} modules found — is the path right?", g.len());
        if let Some(c) = cycle(&g) {
            panic!("{krate}: import cycle {}\n(graph: {g:?})", c.join(" → "));
        }
        // Inside each directory module (app/src/bench, core/src/cpu, …): its files among
        // themselves (issue 32: bench's ladder, output and plot imported each other).
        for entry in std::fs::read_dir(&src).unwrap() {
            let dir = entry.unwrap().path();
            if !dir.is_dir() {
                continue;
            }
            let m = dir.file_name().unwrap().to_string_lossy().into_owned();
            let g = graph(&dir, &["super::".to_owned(), format!("crate::{m}::")]);
            directories += 1;
            if let Some(c) = cycle(&g) {
                panic!("{krate}/src/{m}: import cycle {}\n(graph: {g:?})", c.join(" → "));
            }
        }
    }
    assert!(directories >= 4, "{directories} directory modules found — is the path right?");
}

#[test]
fn the_app_reaches_everything_but_its_drawing_surface_through_the_library() {
    // The app builds its simulations, solvers, pictures and bench cells through the
    // `clothlab` crate (the model's types are the library's re-exports): its manifest names
    // no crate underneath but the three APIs' drawing code, and only the drawing surface
    // (`gui/gfx.rs`: the renderers, the presenter, the overlays on a window) uses them.
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let manifest = std::fs::read_to_string(root.join("app/Cargo.toml")).unwrap();
    for under in ["clothlab-core", "clothlab-cpu", "clothlab-engine", "clothlab-shaders"] {
        assert!(!manifest.contains(&format!("{under}.workspace")), "app/Cargo.toml depends on {under}");
    }
    let mut all = Vec::new();
    files(&root.join("app/src"), &mut all);
    assert!(all.len() >= 20, "{} files under app/src", all.len());
    let mut reaching = Vec::new();
    for f in &all {
        let text = code(&std::fs::read_to_string(f).unwrap());
        let rel = f.strip_prefix(&root).unwrap().to_string_lossy().replace('\\', "/");
        let apis = ["clothlab_wgpu", "clothlab_vulkan", "clothlab_gl"];
        let below = ["clothlab_core", "clothlab_cpu", "clothlab_engine"];
        if below.iter().any(|c| text.contains(c))
            || (rel != "app/src/gui/gfx.rs" && apis.iter().any(|c| text.contains(c)))
        {
            reaching.push(rel);
        }
    }
    assert!(reaching.is_empty(), "app files reaching past the library: {reaching:?}");
}
