//! The layers of the library, bottom first, and the test that holds the code to them: a module
//! imports (`crate::...`, `super::...` that leaves it) only from its own layer or those
//! below. A module's layer is the longest entry of [`LAYERS`] that prefixes its path; the
//! scene's loader (`scene::load`, the built-ins, the automatic camera, `irad scenes`'s
//! inspection) sits above the ray tracer it frames cameras with, the scene model below it.
//! Test modules (from the first `#[cfg(test)]` of a file on) may use anything.

/// Module paths from the bottom layer up; entries of one inner slice share a layer.
pub const LAYERS: &[&[&str]] = &[
    &["math", "image", "check", "layers", "interrupt"],
    &["scene"],
    &["trace"],
    &[
        "scene::load",
        "scene::builtin",
        "scene::framing",
        "scene::inspect",
    ],
    &["vpl"],
    &["gpu"],
    &["reference"],
    &["compensation"],
    &["radiosity"],
    &["config"],
    &["resolve"],
    &["frame"],
    &["metrics"],
    &["report"],
    &["commands"],
    &["view"],
    &["cli"],
    &["main"],
];

/// The layer of a module path (`scene::load::mesh`): the longest entry that prefixes it.
fn layer_of(module: &str) -> Option<(usize, &'static str)> {
    let mut best: Option<(usize, &'static str)> = None;
    for (i, layer) in LAYERS.iter().enumerate() {
        for &m in layer.iter() {
            let prefixes = module == m || module.starts_with(&format!("{m}::"));
            if prefixes && best.is_none_or(|(_, b)| m.len() > b.len()) {
                best = Some((i, m));
            }
        }
    }
    best
}

/// The module path of a file under `src/`: `scene/load/mesh.rs` -> `scene::load::mesh`.
fn module_of(file: &str) -> String {
    let f = file.trim_end_matches(".rs");
    let f = f.strip_suffix("/mod").unwrap_or(f);
    let f = if f == "lib" { "" } else { f };
    f.replace('/', "::")
}

/// The modules a file's source imports (before its first `#[cfg(test)]`, comments left out):
/// every `crate::a::b` path (and each path of a `crate::{..}` group), and `super::x` resolved
/// from the file's module. Each import is the path up to its last lower-case segment, so
/// `crate::scene::load::FOV_RANGE` is `scene::load`.
fn imports(module: &str, source: &str) -> Vec<String> {
    let code: String = source
        .split("#[cfg(test)]")
        .next()
        .unwrap_or("")
        .lines()
        .filter(|l| !l.trim_start().starts_with("//"))
        .collect::<Vec<_>>()
        .join("\n");
    // Child modules (`mod x;`): `x::y` in this file names module::x::y.
    let children: Vec<&str> = code
        .lines()
        .filter_map(|l| {
            let l = l.trim_start();
            let l = l.strip_prefix("pub ").unwrap_or(l);
            let l = l.strip_prefix("pub(crate) ").unwrap_or(l);
            l.strip_prefix("mod ")?.strip_suffix(';')
        })
        .collect();
    let own: Vec<String> = module
        .split("::")
        .filter(|s| !s.is_empty())
        .map(String::from)
        .collect();
    let mut out = Vec::new();
    let mut at = 0;
    while at < code.len() {
        let start = at;
        let word: String = code[start..]
            .chars()
            .take_while(|c| c.is_alphanumeric() || *c == '_')
            .collect();
        at += word
            .len()
            .max(code[start..].chars().next().map_or(1, char::len_utf8));
        if word.is_empty() {
            continue;
        }
        let before = code[..start].chars().next_back();
        if before.is_some_and(|c| c.is_alphanumeric() || c == '_' || c == '$' || c == ':') {
            continue;
        }
        let rest = &code[start..];
        let mut base: Vec<String> = Vec::new();
        let tail = if let Some(t) = rest.strip_prefix("crate::") {
            t
        } else if rest.starts_with("super::") {
            // `super::` in module a::b::c names a::b; each further `super::` one up.
            let mut m = own.clone();
            let mut t = rest;
            while let Some(r) = t.strip_prefix("super::") {
                m.pop();
                t = r;
            }
            base = m;
            t
        } else if children.contains(&word.as_str()) && rest[word.len()..].starts_with("::") {
            base = own.clone();
            rest
        } else {
            continue;
        };
        paths(tail, &base, &mut out);
    }
    out
}

/// The module paths `tail` names after `base` (`a::b::X`, or a `{..}` group of such).
fn paths(tail: &str, base: &[String], out: &mut Vec<String>) {
    let mut path: Vec<String> = base.to_vec();
    let mut t = tail;
    loop {
        if let Some(group) = t.strip_prefix('{') {
            // Split the group's items at depth 0, up to its closing brace.
            let (mut depth, mut item) = (0, 0);
            for (k, c) in group.char_indices() {
                match c {
                    '{' => depth += 1,
                    '}' if depth == 0 => {
                        paths(group[item..k].trim(), &path, out);
                        return;
                    }
                    '}' => depth -= 1,
                    ',' if depth == 0 => {
                        paths(group[item..k].trim(), &path, out);
                        item = k + 1;
                    }
                    _ => {}
                }
            }
            return;
        }
        let word: String = t
            .chars()
            .take_while(|c| c.is_alphanumeric() || *c == '_')
            .collect();
        let module_like =
            word.chars().next().is_some_and(|c| c.is_ascii_lowercase()) && word != "self";
        if !module_like {
            break;
        }
        let after = &t[word.len()..];
        match after.strip_prefix("::") {
            Some(r) => {
                path.push(word);
                t = r;
            }
            None => {
                // The last segment: a module (or a function, whose module's layer is the
                // same) unless a call or a macro follows.
                let next = after.trim_start().chars().next();
                if !matches!(next, Some('(') | Some('!')) {
                    path.push(word);
                }
                break;
            }
        }
    }
    if path.len() > base.len() || !base.is_empty() {
        let p = path.join("::");
        if !p.is_empty() {
            out.push(p);
        }
    }
}

/// Every import of `files` ((path under src/, source)) that reaches a higher layer, as
/// `file: module -> import (layer i -> j)`; and files whose module no layer holds.
pub fn violations(files: &[(String, String)]) -> Vec<String> {
    let mut bad = Vec::new();
    for (file, source) in files {
        let module = module_of(file);
        if module.is_empty() {
            continue;
        }
        let Some((own, _)) = layer_of(&module) else {
            bad.push(format!("{file}: module {module} is in no layer"));
            continue;
        };
        for import in imports(&module, source) {
            // Macros exported at the crate root (`crate::out!`) and the crate itself.
            let Some((theirs, _)) = layer_of(&import) else {
                continue;
            };
            if theirs > own {
                bad.push(format!(
                    "{file}: {module} (layer {own}) imports {import} (layer {theirs})"
                ));
            }
        }
    }
    bad
}

/// Cycles of imports between modules (files) that are not each other's ancestors (a folder's
/// `mod.rs` re-exporting its children is not a cycle), each as `a -> b -> ... -> a`.
pub fn cycles(files: &[(String, String)]) -> Vec<String> {
    use std::collections::{BTreeMap, BTreeSet};
    let modules: BTreeSet<String> = files.iter().map(|(f, _)| module_of(f)).collect();
    let related = |a: &str, b: &str| {
        a.is_empty()
            || b.is_empty()
            || a == b
            || a.starts_with(&format!("{b}::"))
            || b.starts_with(&format!("{a}::"))
    };
    let mut edges: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
    for (file, source) in files {
        let module = module_of(file);
        for import in imports(&module, source) {
            // The longest module that prefixes the import.
            let mut target = import.as_str();
            while !modules.contains(target) {
                match target.rsplit_once("::") {
                    Some((p, _)) => target = p,
                    None => break,
                }
            }
            if modules.contains(target) && !related(&module, target) {
                edges
                    .entry(module.clone())
                    .or_default()
                    .insert(target.to_string());
            }
        }
    }
    // Depth-first search; a back edge closes a cycle.
    fn visit(
        m: &str,
        edges: &BTreeMap<String, BTreeSet<String>>,
        path: &mut Vec<String>,
        done: &mut BTreeSet<String>,
        out: &mut Vec<String>,
    ) {
        if let Some(i) = path.iter().position(|p| p == m) {
            let mut c = path[i..].to_vec();
            c.push(m.to_string());
            out.push(c.join(" -> "));
            return;
        }
        if !done.insert(m.to_string()) {
            return;
        }
        path.push(m.to_string());
        for n in edges.get(m).into_iter().flatten() {
            visit(n, edges, path, done, out);
        }
        path.pop();
    }
    let (mut done, mut out) = (BTreeSet::new(), Vec::new());
    for m in edges.keys() {
        visit(m, &edges, &mut Vec::new(), &mut done, &mut out);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sources() -> Vec<(String, String)> {
        let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
        let mut out = Vec::new();
        let mut stack = vec![root.clone()];
        while let Some(dir) = stack.pop() {
            for e in std::fs::read_dir(&dir).unwrap() {
                let p = e.unwrap().path();
                if p.is_dir() {
                    stack.push(p);
                } else if p.extension().is_some_and(|x| x == "rs") {
                    let rel = p
                        .strip_prefix(&root)
                        .unwrap()
                        .to_string_lossy()
                        .into_owned();
                    out.push((rel, std::fs::read_to_string(&p).unwrap()));
                }
            }
        }
        out.sort();
        out
    }

    #[test]
    fn imports_point_down() {
        let files = sources();
        assert!(files.len() > 50, "read {} files", files.len());
        let bad = violations(&files);
        assert!(bad.is_empty(), "imports that run up:\n{}", bad.join("\n"));
    }

    #[test]
    fn no_import_cycles() {
        let files = sources();
        let c = cycles(&files);
        assert!(c.is_empty(), "import cycles:\n{}", c.join("\n"));
        // The cycle that was there (the comparison's plan and its reference cache) is caught.
        let mut planted = files.clone();
        let (_, s) = planted
            .iter_mut()
            .find(|(f, _)| f == "commands/compare/plan.rs")
            .unwrap();
        s.insert_str(0, "use super::reference_cache::missing;\n");
        let c = cycles(&planted);
        assert!(
            c.len() == 1 && c[0].contains("plan") && c[0].contains("reference_cache"),
            "{c:?}"
        );
    }

    #[test]
    fn a_planted_upward_import_is_caught() {
        let mut files = sources();
        let (_, trace) = files
            .iter_mut()
            .find(|(f, _)| f == "trace/mod.rs")
            .expect("trace/mod.rs");
        trace.insert_str(0, "use crate::gpu::Gpu;\n");
        let bad = violations(&files);
        assert_eq!(bad.len(), 1, "{bad:?}");
        assert!(
            bad[0].contains("trace/mod.rs") && bad[0].contains("gpu"),
            "{bad:?}"
        );
        // `super::` that climbs out of a module counts too, and so does an import of the
        // loader from the scene model.
        let planted = [
            (
                "scene/camera.rs",
                "use super::load::MAX_COORD;\n",
                "scene::load",
            ),
            (
                "vpl/paths.rs",
                "    let x = crate::frame::Pipeline::new;\n",
                "frame",
            ),
            (
                "gpu/ism.rs",
                "use crate::{radiosity::Solver};\n",
                "radiosity",
            ),
        ];
        for (file, line, what) in planted {
            let mut files = sources();
            let (_, s) = files.iter_mut().find(|(f, _)| f == file).unwrap();
            s.insert_str(0, line);
            let bad = violations(&files);
            assert!(
                bad.len() == 1 && bad[0].contains(what),
                "{file} {line}: {bad:?}"
            );
        }
        // A module in no layer is named.
        let mut files = sources();
        files.push(("newstage/mod.rs".into(), String::new()));
        assert!(violations(&files).iter().any(|b| b.contains("newstage")));
    }

    #[test]
    fn module_paths_and_layers() {
        assert_eq!(module_of("scene/load/mesh.rs"), "scene::load::mesh");
        assert_eq!(module_of("scene/mod.rs"), "scene");
        assert_eq!(layer_of("scene::load::mesh").unwrap().1, "scene::load");
        assert_eq!(layer_of("scene::camera").unwrap().1, "scene");
        assert!(layer_of("scene::load").unwrap().0 > layer_of("trace").unwrap().0);
        assert_eq!(
            imports(
                "gpu::ism",
                "use super::bindings::X;\nuse crate::scene::Frame;"
            ),
            ["gpu::bindings", "scene"]
        );
        assert_eq!(
            imports("gpu", "use super::math::X;"),
            ["math"],
            "super of a folder's mod.rs"
        );
        assert_eq!(
            imports(
                "scene",
                "pub mod load;\nfn f() { let x = load::MAX_COORD; }"
            ),
            ["scene::load"],
            "a child module's path"
        );
        assert_eq!(
            imports("a", "use crate::{b::{c::D, e}, f::G};"),
            ["b::c", "b::e", "f"]
        );
    }
}
