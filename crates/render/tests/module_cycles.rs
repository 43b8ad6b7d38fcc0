//! The module graph of `crates/render/src` has no cycles: no module uses
//! another that, directly or through others, uses it back.
//!
//! Read from the source, not from the compiler: every file under `src/` is a
//! module (`scene/mod.rs` is `scene`, `scene/build.rs` is `scene::build`), and
//! module A depends on module B when A's code, outside comments, strings and
//! `#[cfg(test)]` items, names an item of B by a path: a `use` (each leaf of a
//! `use a::{b, c::d}` tree) or an inline `crate::…`, `super::…`, `self::…` or
//! `child::…` path. A path is resolved to the module that defines the item,
//! following `pub use` re-exports; a `pub use` counts as a use by the module
//! holding it only when that module's own code names the item too (a facade
//! that only re-exports does not depend on what it re-exports).
//!
//! Checked at two granularities: every module (file) on its own, and the
//! crate's top-level modules with their submodules folded in (`scene` and
//! `scene::build` one node), which is the architecture's layering.
//!
//! `cargo test -p render --test module_cycles -- --nocapture` prints both
//! graphs' edges.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

type ModPath = Vec<String>;

/// One module: its path from the crate root, its code (comments, literals and
/// test items removed), the child modules it declares and the items it
/// re-exports (`pub use`: local name → absolute path).
struct Module {
    path: ModPath,
    code: String,
    children: Vec<String>,
    reexports: BTreeMap<String, ModPath>,
}

/// A `use` leaf: the absolute path it names (`None`: an external crate), the
/// local name it binds, and whether the `use` is public.
struct UseLeaf {
    target: Option<ModPath>,
    name: String,
    public: bool,
}

fn src_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("src")
}

/// Removes comments, string and char literals (keeping lifetimes), leaving
/// the code's tokens in place.
fn strip_comments_and_literals(s: &str) -> String {
    let c: Vec<char> = s.chars().collect();
    let mut out = String::with_capacity(s.len());
    let mut i = 0;
    while i < c.len() {
        match c[i] {
            '/' if c.get(i + 1) == Some(&'/') => {
                while i < c.len() && c[i] != '\n' {
                    i += 1;
                }
            }
            '/' if c.get(i + 1) == Some(&'*') => {
                let mut depth = 0;
                while i < c.len() {
                    if c[i] == '/' && c.get(i + 1) == Some(&'*') {
                        depth += 1;
                        i += 2;
                    } else if c[i] == '*' && c.get(i + 1) == Some(&'/') {
                        depth -= 1;
                        i += 2;
                        if depth == 0 {
                            break;
                        }
                    } else {
                        i += 1;
                    }
                }
                out.push(' ');
            }
            'r' if matches!(c.get(i + 1), Some('"' | '#')) && (i == 0 || !is_ident(c[i - 1])) => {
                // Raw string r"…", r#"…"#.
                let mut j = i + 1;
                let mut hashes = 0;
                while c.get(j) == Some(&'#') {
                    hashes += 1;
                    j += 1;
                }
                if c.get(j) != Some(&'"') {
                    out.push(c[i]);
                    i += 1;
                    continue;
                }
                j += 1;
                loop {
                    if j >= c.len() {
                        break;
                    }
                    if c[j] == '"' && (0..hashes).all(|h| c.get(j + 1 + h) == Some(&'#')) {
                        j += 1 + hashes;
                        break;
                    }
                    j += 1;
                }
                out.push_str("\"\"");
                i = j;
            }
            '"' => {
                i += 1;
                while i < c.len() && c[i] != '"' {
                    if c[i] == '\\' {
                        i += 1;
                    }
                    i += 1;
                }
                i += 1;
                out.push_str("\"\"");
            }
            '\'' => {
                // A char literal ('x', '\n', '\u{..}'), or a lifetime ('a).
                if c.get(i + 1) == Some(&'\\') {
                    let mut j = i + 2;
                    while j < c.len() && c[j] != '\'' {
                        j += 1;
                    }
                    i = j + 1;
                    out.push_str("' '");
                } else if c.get(i + 2) == Some(&'\'') {
                    i += 3;
                    out.push_str("' '");
                } else {
                    out.push('\'');
                    i += 1;
                }
            }
            ch => {
                out.push(ch);
                i += 1;
            }
        }
    }
    out
}

fn is_ident(ch: char) -> bool {
    ch.is_alphanumeric() || ch == '_'
}

/// The index one past the brace that closes the one opening at or after `from`.
fn matching_brace_end(s: &[u8], from: usize) -> usize {
    let mut depth = 0usize;
    let mut i = from;
    while i < s.len() {
        match s[i] {
            b'{' => depth += 1,
            b'}' => {
                depth -= 1;
                if depth == 0 {
                    return i + 1;
                }
            }
            _ => {}
        }
        i += 1;
    }
    s.len()
}

/// Removes every item marked `#[cfg(test)]` (a `mod tests { … }`, a test
/// helper function, a `use`).
fn strip_test_items(code: &str) -> String {
    let mut out = code.to_string();
    while let Some(at) = out.find("#[cfg(test)]") {
        let b = out.as_bytes();
        let rest = at + "#[cfg(test)]".len();
        let semi = out[rest..].find(';').map(|k| rest + k);
        let brace = out[rest..].find('{').map(|k| rest + k);
        let end = match (semi, brace) {
            (Some(s), Some(o)) if s < o => s + 1,
            (_, Some(o)) => matching_brace_end(b, o),
            (Some(s), None) => s + 1,
            (None, None) => out.len(),
        };
        out.replace_range(at..end, " ");
    }
    out
}

/// Words of `code` with their byte offsets, `::` kept as its own token.
fn tokens(code: &str) -> Vec<(usize, &str)> {
    let mut v = Vec::new();
    let b = code.as_bytes();
    let mut i = 0;
    while i < b.len() {
        let ch = b[i] as char;
        if is_ident(ch) || !ch.is_ascii() {
            let start = i;
            while i < b.len() && (is_ident(b[i] as char) || !(b[i] as char).is_ascii()) {
                i += 1;
            }
            v.push((start, &code[start..i]));
        } else if code[i..].starts_with("::") {
            v.push((i, "::"));
            i += 2;
        } else {
            if !ch.is_whitespace() {
                v.push((i, &code[i..i + 1]));
            }
            i += 1;
        }
    }
    v
}

/// Declared child modules (`mod x;`, `pub mod x;`, `pub(crate) mod x;`).
fn child_modules(code: &str) -> Vec<String> {
    let t = tokens(code);
    let mut v = Vec::new();
    for k in 0..t.len().saturating_sub(2) {
        if t[k].1 == "mod" && t[k + 2].1 == ";" {
            v.push(t[k + 1].1.to_string());
        }
    }
    v
}

/// Expands a `use` tree (`a::{b, c::{d as e, self}}`) into (path, bound name) leaves.
fn expand_use_tree(tree: &str) -> Vec<(Vec<String>, String)> {
    fn go(prefix: &[String], s: &str, out: &mut Vec<(Vec<String>, String)>) {
        let s = s.trim();
        if let Some(open) = s.find('{') {
            let head: Vec<String> = s[..open]
                .split("::")
                .map(str::trim)
                .filter(|x| !x.is_empty())
                .map(String::from)
                .collect();
            let close = s.rfind('}').unwrap_or(s.len());
            let inner = &s[open + 1..close];
            let mut p = prefix.to_vec();
            p.extend(head);
            let mut depth = 0;
            let mut start = 0;
            for (i, ch) in inner.char_indices() {
                match ch {
                    '{' => depth += 1,
                    '}' => depth -= 1,
                    ',' if depth == 0 => {
                        go(&p, &inner[start..i], out);
                        start = i + 1;
                    }
                    _ => {}
                }
            }
            go(&p, &inner[start..], out);
            return;
        }
        if s.is_empty() {
            return;
        }
        let (path, alias) = match s.split_once(" as ") {
            Some((p, a)) => (p.trim(), Some(a.trim().to_string())),
            None => (s, None),
        };
        let mut p = prefix.to_vec();
        p.extend(path.split("::").map(|x| x.trim().to_string()));
        if p.last().map(String::as_str) == Some("self") {
            p.pop();
        }
        let name = alias.unwrap_or_else(|| p.last().cloned().unwrap_or_default());
        out.push((p, name));
    }
    let mut out = Vec::new();
    go(&[], tree, &mut out);
    out
}

/// The `use` statements of `code` (with their byte ranges) and their leaves.
fn use_statements(code: &str) -> Vec<(std::ops::Range<usize>, bool, String)> {
    let t = tokens(code);
    let mut v = Vec::new();
    for k in 0..t.len() {
        if t[k].1 != "use" {
            continue;
        }
        // `pub use`, `pub(crate) use`, `pub(super) use`.
        let public = k >= 1 && (t[k - 1].1 == "pub" || (k >= 4 && t[k - 4].1 == "pub"));
        let start = t[k].0;
        let body = start + 3;
        let end = body + code[body..].find(';').unwrap_or(code.len() - body);
        let stmt_start = if public {
            if t[k - 1].1 == "pub" {
                t[k - 1].0
            } else {
                t[k - 4].0
            }
        } else {
            start
        };
        v.push((stmt_start..end + 1, public, code[body..end].to_string()));
    }
    v
}

/// Makes a path absolute from module `here`: `crate::`, `super::`, `self::`,
/// a child module's name, or one of `aliases` (names bound to modules).
/// `None` for a path into another crate.
fn absolute(
    here: &ModPath,
    children: &[String],
    aliases: &BTreeMap<String, ModPath>,
    segs: &[String],
) -> Option<ModPath> {
    let first = segs.first()?;
    let (mut base, rest) = match first.as_str() {
        "crate" => (Vec::new(), &segs[1..]),
        "self" => (here.clone(), &segs[1..]),
        "super" => {
            let mut b = here.clone();
            let mut r = segs;
            while r.first().map(String::as_str) == Some("super") {
                b.pop();
                r = &r[1..];
            }
            (b, r)
        }
        name if children.iter().any(|c| c == name) => (here.clone(), segs),
        name => (aliases.get(name)?.clone(), &segs[1..]),
    };
    base.extend(rest.iter().cloned());
    Some(base)
}

fn read_modules() -> Vec<Module> {
    let mut out = Vec::new();
    let mut todo = vec![(Vec::<String>::new(), src_dir().join("lib.rs"))];
    while let Some((path, file)) = todo.pop() {
        let text = std::fs::read_to_string(&file)
            .unwrap_or_else(|e| panic!("cannot read {}: {e}", file.display()));
        let code = strip_test_items(&strip_comments_and_literals(&text));
        let children = child_modules(&code);
        let dir = if path.is_empty() || file.ends_with("mod.rs") {
            file.parent().unwrap().to_path_buf()
        } else {
            file.with_extension("")
        };
        for ch in &children {
            let mut p = path.clone();
            p.push(ch.clone());
            let flat = dir.join(format!("{ch}.rs"));
            let nested = dir.join(ch).join("mod.rs");
            let f = if flat.exists() { flat } else { nested };
            assert!(f.exists(), "module {} has no file", p.join("::"));
            todo.push((p, f));
        }
        out.push(Module {
            path,
            code,
            children,
            reexports: BTreeMap::new(),
        });
    }
    out.sort_by(|a, b| a.path.cmp(&b.path));
    out
}

/// Every `use` leaf of module `m`, resolved to an absolute path where it is
/// one of this crate's.
fn use_leaves(m: &Module, modules: &BTreeSet<ModPath>) -> Vec<UseLeaf> {
    let mut aliases = BTreeMap::new();
    let mut leaves = Vec::new();
    for (_, public, tree) in use_statements(&m.code) {
        for (segs, name) in expand_use_tree(&tree) {
            let target = absolute(&m.path, &m.children, &aliases, &segs);
            if let Some(t) = &target
                && modules.contains(t)
            {
                aliases.insert(name.clone(), t.clone());
            }
            leaves.push(UseLeaf {
                target,
                name,
                public,
            });
        }
    }
    leaves
}

/// The module defining the item `path` names: its longest module prefix,
/// then through that module's re-exports of the next segment.
fn defining_module(
    path: &ModPath,
    modules: &BTreeSet<ModPath>,
    reexports: &BTreeMap<ModPath, BTreeMap<String, ModPath>>,
    depth: usize,
) -> Option<ModPath> {
    let k = (0..=path.len())
        .rev()
        .find(|&k| modules.contains(&path[..k].to_vec()))?;
    let m = path[..k].to_vec();
    if depth < 16
        && let Some(item) = path.get(k)
        && let Some(target) = reexports.get(&m).and_then(|r| r.get(item))
    {
        let mut t = target.clone();
        t.extend(path[k + 1..].iter().cloned());
        return defining_module(&t, modules, reexports, depth + 1);
    }
    Some(m)
}

/// Module → the modules it depends on.
fn module_graph() -> BTreeMap<ModPath, BTreeSet<ModPath>> {
    let mut mods = read_modules();
    let names: BTreeSet<ModPath> = mods.iter().map(|m| m.path.clone()).collect();
    for m in &mut mods {
        let leaves = use_leaves(m, &names);
        m.reexports = leaves
            .into_iter()
            .filter(|l| l.public)
            .filter_map(|l| Some((l.name, l.target?)))
            .collect();
    }
    let reexports: BTreeMap<ModPath, BTreeMap<String, ModPath>> = mods
        .iter()
        .map(|m| (m.path.clone(), m.reexports.clone()))
        .collect();
    let mut graph = BTreeMap::new();
    for m in &mods {
        let mut deps = BTreeSet::new();
        let mut body = m.code.clone();
        let uses = use_statements(&m.code);
        for (range, _, _) in uses.iter().rev() {
            body.replace_range(range.clone(), " ");
        }
        // Module declarations (`mod load;`) name no item.
        let body_tokens = tokens(&body);
        let body_words: BTreeSet<&str> = body_tokens
            .iter()
            .enumerate()
            .filter(|(k, _)| *k == 0 || body_tokens[k - 1].1 != "mod")
            .map(|(_, (_, w))| *w)
            .collect();
        let mut aliases = BTreeMap::new();
        for leaf in use_leaves(m, &names) {
            let Some(target) = leaf.target else { continue };
            if names.contains(&target) {
                aliases.insert(leaf.name.clone(), target.clone());
            }
            if leaf.public && !body_words.contains(leaf.name.as_str()) {
                continue;
            }
            if let Some(d) = defining_module(&target, &names, &reexports, 0) {
                deps.insert(d);
            }
        }
        // Inline paths: a run of `ident :: ident :: …` in the body.
        let t = tokens(&body);
        let mut k = 0;
        while k < t.len() {
            let starts = k == 0 || t[k - 1].1 != "::";
            if starts && t.get(k + 1).map(|x| x.1) == Some("::") {
                let mut segs = vec![t[k].1.to_string()];
                let mut j = k + 1;
                while t.get(j).map(|x| x.1) == Some("::")
                    && t.get(j + 1).is_some_and(|x| x.1.chars().all(is_ident))
                {
                    segs.push(t[j + 1].1.to_string());
                    j += 2;
                }
                if let Some(abs) = absolute(&m.path, &m.children, &aliases, &segs)
                    && let Some(d) = defining_module(&abs, &names, &reexports, 0)
                {
                    deps.insert(d);
                }
                k = j;
            } else {
                k += 1;
            }
        }
        deps.remove(&m.path);
        deps.remove(&Vec::new());
        graph.insert(m.path.clone(), deps);
    }
    graph
}

/// The graph with every module folded into its top-level module.
fn folded(graph: &BTreeMap<ModPath, BTreeSet<ModPath>>) -> BTreeMap<ModPath, BTreeSet<ModPath>> {
    let top = |p: &ModPath| p.iter().take(1).cloned().collect::<ModPath>();
    let mut g: BTreeMap<ModPath, BTreeSet<ModPath>> = BTreeMap::new();
    for (a, deps) in graph {
        if a.is_empty() {
            continue;
        }
        let e = g.entry(top(a)).or_default();
        for d in deps {
            if top(d) != top(a) {
                e.insert(top(d));
            }
        }
    }
    g
}

/// The modules that lie on a cycle, one strongly connected component per
/// entry: its members and the shortest cycle through each member, as
/// `a → b → … → a`.
fn cycles(g: &BTreeMap<ModPath, BTreeSet<ModPath>>) -> Vec<String> {
    // Breadth-first parents of every module reachable from `from`.
    let reach = |from: &ModPath| -> BTreeMap<ModPath, ModPath> {
        let mut parent = BTreeMap::new();
        let mut queue = std::collections::VecDeque::from([from.clone()]);
        while let Some(x) = queue.pop_front() {
            for y in g.get(&x).into_iter().flatten() {
                if !parent.contains_key(y) {
                    parent.insert(y.clone(), x.clone());
                    queue.push_back(y.clone());
                }
            }
        }
        parent
    };
    let name = |p: &ModPath| p.join("::");
    let shortest = |a: &ModPath| -> Option<String> {
        let parent = reach(a);
        parent.get(a)?;
        let mut path = vec![a.clone()];
        let mut x = parent[a].clone();
        while &x != a {
            path.push(x.clone());
            x = parent[&x].clone();
        }
        path.push(a.clone());
        path.reverse();
        Some(path.iter().map(name).collect::<Vec<_>>().join(" → "))
    };
    let mut seen: BTreeSet<ModPath> = BTreeSet::new();
    let mut out = Vec::new();
    for a in g.keys() {
        if seen.contains(a) || shortest(a).is_none() {
            continue;
        }
        let from_a = reach(a);
        let members: Vec<&ModPath> = g
            .keys()
            .filter(|b| from_a.contains_key(*b) && reach(b).contains_key(a))
            .collect();
        let mut lines = BTreeSet::new();
        for b in &members {
            seen.insert((*b).clone());
            lines.extend(shortest(b));
        }
        let names: Vec<String> = members.iter().map(|b| name(b)).collect();
        out.push(format!(
            "{{{}}}:\n  {}",
            names.join(", "),
            lines.into_iter().collect::<Vec<_>>().join("\n  ")
        ));
    }
    out
}

fn show(g: &BTreeMap<ModPath, BTreeSet<ModPath>>) -> String {
    g.iter()
        .map(|(a, deps)| {
            let d: Vec<String> = deps.iter().map(|p| p.join("::")).collect();
            format!("{} → {}\n", a.join("::"), d.join(", "))
        })
        .collect()
}

#[test]
fn no_module_uses_itself_through_others() {
    let g = module_graph();
    println!("modules:\n{}", show(&g));
    let c = cycles(&g);
    assert!(
        c.is_empty(),
        "{} group(s) of modules on cycles:\n{}",
        c.len(),
        c.join("\n")
    );
}

#[test]
fn no_top_level_module_uses_itself_through_others() {
    let g = folded(&module_graph());
    println!("top-level modules:\n{}", show(&g));
    let c = cycles(&g);
    assert!(
        c.is_empty(),
        "{} group(s) of top-level modules on cycles:\n{}",
        c.len(),
        c.join("\n")
    );
}

/// The reader sees the edges it must: a cycle put into a copy of the
/// parsing is found, and each kind of path resolves.
#[test]
fn the_reader_finds_uses_of_every_kind() {
    let g = module_graph();
    let dep = |a: &str, b: &str| {
        let p = |s: &str| -> ModPath { s.split("::").map(String::from).collect() };
        g.get(&p(a)).is_some_and(|d| d.contains(&p(b)))
    };
    // `use crate::…` leaves of a `{…}` tree.
    assert!(dep("integrator", "sampler"), "{}", show(&g));
    // `use super::…` from a submodule.
    assert!(dep("scene::build", "scene::desc"), "{}", show(&g));
    // An inline `crate::…::…` path.
    assert!(dep("scene::build", "film"), "{}", show(&g));
    let mut h = BTreeMap::new();
    let p = |s: &str| vec![s.to_string()];
    h.insert(p("a"), BTreeSet::from([p("b")]));
    h.insert(p("b"), BTreeSet::from([p("c")]));
    h.insert(p("c"), BTreeSet::from([p("a")]));
    h.insert(p("d"), BTreeSet::from([p("a")]));
    assert_eq!(
        cycles(&h),
        vec!["{a, b, c}:\n  a → b → c → a\n  b → c → a → b\n  c → a → b → c".to_string()]
    );
    assert_eq!(
        expand_use_tree("crate::x::{self, y::{Z as W, V}}"),
        vec![
            (vec!["crate".into(), "x".into()], "x".into()),
            (
                vec!["crate".into(), "x".into(), "y".into(), "Z".into()],
                "W".into()
            ),
            (
                vec!["crate".into(), "x".into(), "y".into(), "V".into()],
                "V".into()
            ),
        ]
    );
    let code = strip_test_items(&strip_comments_and_literals(
        "use a::b; // crate::c::d\n/* crate::e */ fn f<'a>(x: &'a str) -> char { 'q' }\n\
         const S: &str = \"crate::g\";\n#[cfg(test)]\nmod tests { use crate::h; }\n",
    ));
    assert!(!code.contains("crate"), "{code}");
    assert!(code.contains("'a"), "{code}");
}
