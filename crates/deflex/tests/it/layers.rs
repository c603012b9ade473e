//! Every package depends only on packages of lower layers.
//!
//! Each package of the workspace declares its layer in its manifest
//! (`[package.metadata.deflex] layer = N`, the layers of `docs/src/architecture.md`). The rule:
//! a dependency of any kind (normal, dev, build, target-specific) on another package of the
//! workspace must point to a strictly lower layer. The architecture page's package table is
//! generated from the same manifests and checked here, so the page shows the graph as it is.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// The roles of the layers, by number (the architecture page's words).
const ROLES: [&str; 9] = [
    "foundation",
    "messages",
    "science",
    "links",
    "outlets",
    "runtime",
    "simulation",
    "application",
    "front ends",
];

/// The most packages the workspace may have (issue 32: at most 18, dev-only ones included).
const MAX_PACKAGES: usize = 18;

/// A package as its manifest declares it.
#[derive(Debug, Clone, PartialEq)]
struct Package {
    name: String,
    /// `None` when the manifest declares no layer.
    layer: Option<i64>,
    /// Workspace packages it depends on, with the kind of dependency (`normal`, `dev`, `build`).
    deps: Vec<(String, &'static str)>,
}

fn workspace_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// Every package of `crates/*` from its `Cargo.toml`.
fn read_packages(root: &Path) -> Vec<Package> {
    let mut manifests: Vec<PathBuf> = std::fs::read_dir(root.join("crates"))
        .expect("crates/ is readable")
        .map(|e| e.expect("a directory entry").path().join("Cargo.toml"))
        .filter(|p| p.is_file())
        .collect();
    manifests.sort();
    let texts: Vec<(String, String)> = manifests
        .iter()
        .map(|p| {
            let text = std::fs::read_to_string(p).expect("a manifest is readable");
            (p.display().to_string(), text)
        })
        .collect();
    parse_packages(&texts)
}

/// The packages of manifests given as `(origin, text)`; dependencies on packages outside the
/// set are left out.
fn parse_packages(manifests: &[(String, String)]) -> Vec<Package> {
    let tables: Vec<(String, toml::Table)> = manifests
        .iter()
        .map(|(origin, text)| {
            let table: toml::Table = text
                .parse()
                .unwrap_or_else(|e| panic!("{origin}: not a TOML manifest: {e}"));
            (origin.clone(), table)
        })
        .collect();
    let name_of = |origin: &str, t: &toml::Table| -> String {
        t.get("package")
            .and_then(|p| p.get("name"))
            .and_then(|n| n.as_str())
            .unwrap_or_else(|| panic!("{origin}: no package name"))
            .to_string()
    };
    let names: Vec<String> = tables.iter().map(|(o, t)| name_of(o, t)).collect();
    tables
        .iter()
        .map(|(origin, t)| {
            let layer = t
                .get("package")
                .and_then(|p| p.get("metadata"))
                .and_then(|m| m.get("deflex"))
                .and_then(|d| d.get("layer"))
                .and_then(|l| l.as_integer());
            let mut deps = Vec::new();
            let mut collect = |table: &toml::Table| {
                for (section, kind) in [
                    ("dependencies", "normal"),
                    ("dev-dependencies", "dev"),
                    ("build-dependencies", "build"),
                ] {
                    if let Some(d) = table.get(section).and_then(|d| d.as_table()) {
                        for dep in d.keys() {
                            if names.contains(dep) {
                                deps.push((dep.clone(), kind));
                            }
                        }
                    }
                }
            };
            collect(t);
            if let Some(targets) = t.get("target").and_then(|x| x.as_table()) {
                for target in targets.values().filter_map(|x| x.as_table()) {
                    collect(target);
                }
            }
            deps.sort();
            deps.dedup();
            Package {
                name: name_of(origin, t),
                layer,
                deps,
            }
        })
        .collect()
}

/// Every breach of the layer rule, in words: a package without a layer, a layer outside the
/// roles, a dependency on a package of the same or a higher layer.
fn breaches(packages: &[Package]) -> Vec<String> {
    let layer: BTreeMap<&str, Option<i64>> = packages
        .iter()
        .map(|p| (p.name.as_str(), p.layer))
        .collect();
    let mut out = Vec::new();
    for p in packages {
        let Some(own) = p.layer else {
            out.push(format!(
                "{}: no `[package.metadata.deflex] layer` in its manifest",
                p.name
            ));
            continue;
        };
        if own < 0 || own as usize >= ROLES.len() {
            out.push(format!(
                "{}: layer {own} is not one of 0..={}",
                p.name,
                ROLES.len() - 1
            ));
        }
        for (dep, kind) in &p.deps {
            if let Some(Some(theirs)) = layer.get(dep.as_str())
                && *theirs >= own
            {
                out.push(format!(
                    "{} (layer {own}) has a {kind} dependency on {dep} (layer {theirs}): a package may depend only on lower layers",
                    p.name
                ));
            }
        }
    }
    out
}

/// The architecture page's package table, generated from the manifests.
fn package_table(packages: &[Package]) -> String {
    let mut sorted: Vec<&Package> = packages.iter().collect();
    sorted.sort_by_key(|p| (p.layer, p.name.clone()));
    let mut out = String::from(
        "| layer | role | package | depends on (workspace packages; dev-only in italics) |\n| --- | --- | --- | --- |\n",
    );
    for p in sorted {
        let layer = p.layer.unwrap_or(-1);
        let role = usize::try_from(layer)
            .ok()
            .and_then(|l| ROLES.get(l))
            .copied()
            .unwrap_or("?");
        let normal: Vec<&str> = p
            .deps
            .iter()
            .filter(|(_, k)| *k != "dev")
            .map(|(d, _)| d.as_str())
            .collect();
        let dev: Vec<String> = p
            .deps
            .iter()
            .filter(|(d, k)| *k == "dev" && !normal.contains(&d.as_str()))
            .map(|(d, _)| format!("*{d}*"))
            .collect();
        let mut all: Vec<String> = normal.iter().map(|d| d.to_string()).collect();
        all.extend(dev);
        let deps = if all.is_empty() {
            "–".to_string()
        } else {
            all.join(", ")
        };
        out.push_str(&format!("| {layer} | {role} | `{}` | {deps} |\n", p.name));
    }
    out
}

const TABLE_BEGIN: &str =
    "<!-- layers:begin (generated from the manifests; kept by the facade's layer test) -->\n";
const TABLE_END: &str = "<!-- layers:end -->";

#[test]
fn every_package_depends_only_on_lower_layers() {
    let packages = read_packages(&workspace_root());
    assert!(packages.len() > 1, "no packages found");
    let found = breaches(&packages);
    assert!(found.is_empty(), "layer rule broken:\n{}", found.join("\n"));
}

#[test]
fn the_workspace_has_at_most_eighteen_packages() {
    let packages = read_packages(&workspace_root());
    let names: Vec<&str> = packages.iter().map(|p| p.name.as_str()).collect();
    assert!(
        packages.len() <= MAX_PACKAGES,
        "{} packages (at most {MAX_PACKAGES}): {}",
        packages.len(),
        names.join(", ")
    );
}

#[test]
fn a_planted_upward_dependency_is_caught() {
    let manifest = |name: &str, layer: i64, deps: &str| {
        (
            format!("{name}/Cargo.toml"),
            format!(
                "[package]\nname = \"{name}\"\n[package.metadata.deflex]\nlayer = {layer}\n{deps}"
            ),
        )
    };
    let good = [
        manifest("low", 0, ""),
        manifest("high", 2, "[dependencies]\nlow = { path = \"../low\" }\n"),
    ];
    assert!(breaches(&parse_packages(&good)).is_empty());
    // Upward, sideways, through dev- and target-specific dependencies, and a missing layer.
    let planted = [
        manifest(
            "low",
            0,
            "[dev-dependencies]\nhigh = { path = \"../high\" }\n",
        ),
        manifest("high", 2, "[dependencies]\nlow = { path = \"../low\" }\n"),
        manifest(
            "side",
            2,
            "[target.'cfg(unix)'.dependencies]\nhigh = { path = \"../high\" }\n",
        ),
        (
            "bare/Cargo.toml".to_string(),
            "[package]\nname = \"bare\"\n".to_string(),
        ),
    ];
    let found = breaches(&parse_packages(&planted));
    assert_eq!(found.len(), 3, "{found:#?}");
    assert!(
        found
            .iter()
            .any(|b| b.starts_with("bare: no `[package.metadata.deflex] layer`"))
    );
    assert!(
        found
            .iter()
            .any(|b| b.starts_with("low (layer 0) has a dev dependency on high (layer 2)"))
    );
    assert!(
        found
            .iter()
            .any(|b| b.starts_with("side (layer 2) has a normal dependency on high (layer 2)"))
    );
}

#[test]
fn the_architecture_page_shows_the_graph_as_it_is() {
    let root = workspace_root();
    let page_path = root.join("docs/src/architecture.md");
    let page = std::fs::read_to_string(&page_path).expect("docs/src/architecture.md is readable");
    let expected = package_table(&read_packages(&root));
    let begin = page.find(TABLE_BEGIN).unwrap_or_else(|| {
        panic!(
            "{}: no `{}` marker",
            page_path.display(),
            TABLE_BEGIN.trim()
        )
    });
    let rest = &page[begin + TABLE_BEGIN.len()..];
    let end = rest
        .find(TABLE_END)
        .unwrap_or_else(|| panic!("{}: no `{TABLE_END}` marker", page_path.display()));
    if rest[..end] != expected && std::env::var_os("DEFLEX_BLESS_ARCHITECTURE").is_some() {
        // Opt-in rewrite of the generated block (the rest of the page is left as it is).
        let start = begin + TABLE_BEGIN.len();
        let updated = format!("{}{expected}{}", &page[..start], &page[start + end..]);
        std::fs::write(&page_path, updated).expect("docs/src/architecture.md is writable");
        return;
    }
    assert_eq!(
        &rest[..end],
        expected,
        "the package table of {} is not the manifests' graph (DEFLEX_BLESS_ARCHITECTURE=1 cargo test -p deflex --test it layers rewrites it); the table as it is:\n{expected}",
        page_path.display()
    );
}
