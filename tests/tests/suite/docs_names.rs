//! The docs name what exists: every repository path and every `Type::member` or
//! `module::item` that the reference pages (README.md and docs/, all but the dated log
//! performance.md and benchmarking.md's output folders) write in backticks is found in
//! the tree (a page that names `Colliders::each_bound` after the function was
//! renamed fails here, not in a new maintainer's hands).
//!
//! How: a path (a span with a `/`, no spaces, placeholders or globs, ending in a file's
//! extension or a folder's `/`) exists from the repository's root, or some file's or folder's path ends with it (`bench/results.rs`
//! under `app/src`). A `Type::member` needs `Type` declared (`struct`, `enum`, `trait`,
//! `type`) and `member` declared — as a `fn`, `const`, `static`, field or variant — in a
//! file that declares or implements `Type`. A `module::item` (lowercase first) needs its
//! last segment declared somewhere.

use std::path::{Path, PathBuf};

/// The pages whose names are checked.
const PAGES: [&str; 14] = [
    "README.md",
    "docs/figures.md",
    "docs/README.md",
    "docs/architecture.md",
    "docs/testing.md",
    "docs/contact.md",
    "docs/worlds.md",
    "docs/variants.md",
    "docs/scenes.md",
    "docs/parameters.md",
    "docs/cli.md",
    "docs/python.md",
    "docs/app.md",
    "docs/gradients.md",
];

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// Every file under the repository's crates and folders (no `target`, no dot folders).
fn tree(dir: &Path, out: &mut Vec<PathBuf>) {
    let mut entries: Vec<_> = std::fs::read_dir(dir).unwrap().map(|e| e.unwrap().path()).collect();
    entries.sort();
    for e in entries {
        let name = e.file_name().unwrap().to_string_lossy().into_owned();
        if name == "target" || name.starts_with('.') || name == "__pycache__" {
            continue;
        }
        if e.is_dir() {
            out.push(e.clone());
            tree(&e, out);
        } else {
            out.push(e);
        }
    }
}

/// The spans a page writes in backticks.
fn spans(text: &str) -> Vec<String> {
    text.split('`').skip(1).step_by(2).map(str::to_owned).collect()
}

fn is_ident(s: &str) -> bool {
    let mut c = s.chars();
    c.next().is_some_and(|f| f.is_ascii_alphabetic() || f == '_') && c.all(|x| x.is_ascii_alphanumeric() || x == '_')
}

/// Whether `name` is declared in `code`: a fn, const, static, type, mod, struct, enum or
/// trait of that name, a field (`name:`) or an enum variant (`Name,` `Name =` `Name(`
/// `Name {`), or a macro (`macro_rules! name`).
fn declares(code: &str, name: &str) -> bool {
    let kw = ["fn", "const", "static", "type", "mod", "struct", "enum", "trait", "macro_rules!"];
    let words: Vec<&str> = code.split(|c: char| !(c.is_ascii_alphanumeric() || c == '_' || c == '!')).collect();
    if words.windows(2).any(|w| w[1] == name && kw.contains(&w[0])) {
        return true;
    }
    // A field or a variant: the name at a line's start (after `pub` and such), followed by
    // one of `:` `,` `=` `(` `{`.
    code.lines().any(|l| {
        let l = l.trim_start();
        let l = l.strip_prefix("pub(crate) ").or_else(|| l.strip_prefix("pub ")).unwrap_or(l);
        l.strip_prefix(name).is_some_and(|rest| {
            let rest = rest.trim_start();
            [":", ",", "=", "(", "{"].iter().any(|p| rest.starts_with(p)) && !rest.starts_with("::")
        })
    })
}

#[test]
fn every_path_and_item_the_reference_pages_name_exists() {
    let root = root();
    let mut files = Vec::new();
    tree(&root, &mut files);
    let rel: Vec<String> =
        files.iter().map(|f| f.strip_prefix(&root).unwrap().to_string_lossy().replace('\\', "/")).collect();
    let sources: Vec<(String, String)> = files
        .iter()
        .zip(&rel)
        .filter(|(f, _)| f.extension().is_some_and(|e| e == "rs" || e == "wgsl"))
        .map(|(f, r)| (r.clone(), std::fs::read_to_string(f).unwrap()))
        .collect();
    let mut missing = Vec::new();
    let (mut paths, mut items) = (0, 0);
    for page in PAGES {
        let text = std::fs::read_to_string(root.join(page)).unwrap();
        for span in spans(&text) {
            let s = span.trim_end_matches("()").trim_end_matches(':');
            let placeholder = |c: char| " <>…*|{}[]()$,=+".contains(c);
            // A path: a `/`, no placeholders, and a file's extension or a folder's `/` at
            // its end (`dt/m` is a quotient), not at the root (`/1.0`, `// SAFETY:` are
            // code); a path outside the repository (`../`) is the
            // workplace's, not the tree's.
            let last = s.rsplit('/').next().unwrap_or("");
            let pathlike = s.ends_with('/') || last.contains('.') || root.join(s).exists();
            if s.contains('/') && pathlike && !s.contains(placeholder) && !s.starts_with('/') {
                if s.starts_with("../") {
                    continue;
                }
                paths += 1;
                let p = s.trim_end_matches('/');
                let found = root.join(p).exists()
                    || root.join("docs").join(s).exists()
                    || rel.iter().any(|r| r.ends_with(&format!("/{p}")));
                if !found {
                    missing.push(format!("{page}: path `{s}`"));
                }
                continue;
            }
            let parts: Vec<&str> = s.split("::").collect();
            if parts.len() < 2 || !parts.iter().all(|p| is_ident(p)) {
                continue;
            }
            items += 1;
            let last = parts[parts.len() - 1];
            let owner = parts[parts.len() - 2];
            let found = if owner.starts_with(|c: char| c.is_ascii_uppercase()) {
                // A type's member: in a file that declares or implements the type.
                sources.iter().any(|(_, code)| {
                    let has_type = declares(code, owner)
                        || code.contains(&format!("for {owner}"))
                        || code.contains(&format!("impl {owner}"))
                        || code.contains(&format!("impl<E: Engine> {owner}"));
                    has_type && declares(code, last)
                })
            } else {
                sources.iter().any(|(_, code)| declares(code, last))
            };
            if !found {
                missing.push(format!("{page}: `{s}`"));
            }
        }
    }
    println!("{paths} paths and {items} items named");
    // The pages name hundreds of each; fewer than 100 and the span reader lost them.
    assert!(paths >= 100 && items >= 100, "{paths} paths, {items} items: the pages were not read");
    assert!(missing.is_empty(), "named in the docs but not in the tree:\n{}", missing.join("\n"));
}

#[test]
fn every_link_of_the_guide_and_the_log_reaches_a_file() {
    // Every relative link `](target)` of README.md, the docs' pages and the measurement
    // log (moved under docs/bench/, so its links were rewritten) names a file or folder
    // that exists; anchors are not checked.
    let root = root();
    let mut pages: Vec<PathBuf> = PAGES.iter().map(|p| root.join(p)).collect();
    pages.push(root.join("docs/bench/log.md"));
    let mut entries: Vec<_> = std::fs::read_dir(root.join("docs")).unwrap().map(|e| e.unwrap().path()).collect();
    entries.retain(|e| e.extension().is_some_and(|x| x == "md") && !pages.contains(e));
    pages.extend(entries);
    let (mut links, mut broken) = (0, Vec::new());
    for page in &pages {
        let text = std::fs::read_to_string(page).unwrap();
        for part in text.split("](").skip(1) {
            let Some(end) = part.find(')') else { continue };
            let target = part[..end].split('#').next().unwrap_or("");
            if target.is_empty() || target.contains("://") || target.contains(' ') {
                continue;
            }
            links += 1;
            if !page.parent().unwrap().join(target).exists() {
                broken.push(format!("{}: {target}", page.strip_prefix(&root).unwrap().display()));
            }
        }
    }
    println!("{links} links in {} pages", pages.len());
    // Hundreds of links (the log alone has dozens); fewer than 100 and the reader lost them.
    assert!(links >= 100, "{links} links: the pages were not read");
    assert!(broken.is_empty(), "links to nothing:\n{}", broken.join("\n"));
}
