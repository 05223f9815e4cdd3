//! The layer rule of `ARCHITECTURE.md`, checked against what Cargo actually builds: every
//! workspace crate has a row in the layer table, and each of its normal and build dependencies
//! inside the workspace sits in a lower layer and is named in the row's "may depend on" column.

#![allow(clippy::unwrap_used, clippy::expect_used)] // test helpers outside #[test] functions

use std::collections::BTreeMap;
use std::path::Path;
use std::process::Command;

/// One row of the layer table.
#[derive(Debug)]
struct Row {
    layer: u32,
    group: String,
    allowed: Vec<String>,
}

/// The layer table of `ARCHITECTURE.md`: crate name → row.
fn layer_table(text: &str) -> BTreeMap<String, Row> {
    let mut rows = BTreeMap::new();
    for line in text.lines() {
        let cells: Vec<&str> = line.split('|').map(str::trim).collect();
        // | 3 framework | `pomona-pipeline` | what | may depend on |
        let [_, layer, name, _, allowed, ..] = cells.as_slice() else {
            continue;
        };
        let mut words = layer.split_whitespace();
        let (Some(Ok(layer)), Some(group)) = (words.next().map(str::parse), words.next()) else {
            continue;
        };
        let name = name.trim_matches('`').to_owned();
        let allowed = allowed
            .split(',')
            .map(|w| w.trim().trim_matches('`').to_owned())
            .collect();
        rows.insert(
            name,
            Row {
                layer,
                group: group.to_owned(),
                allowed,
            },
        );
    }
    rows
}

/// Workspace crates and their (normal or build) dependencies on other workspace crates.
fn workspace_dependencies(root: &Path) -> BTreeMap<String, Vec<String>> {
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
    let out = Command::new(cargo)
        .args([
            "metadata",
            "--format-version",
            "1",
            "--no-deps",
            "--offline",
        ])
        .current_dir(root)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let meta: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let packages = meta["packages"].as_array().unwrap();
    let members: Vec<String> = packages
        .iter()
        .map(|p| p["name"].as_str().unwrap().to_owned())
        .collect();
    packages
        .iter()
        .map(|p| {
            let deps = p["dependencies"]
                .as_array()
                .unwrap()
                .iter()
                .filter(|d| d["kind"].as_str() != Some("dev"))
                .map(|d| d["name"].as_str().unwrap().to_owned())
                .filter(|d| members.contains(d))
                .collect();
            (p["name"].as_str().unwrap().to_owned(), deps)
        })
        .collect()
}

/// Every breach of the rule, as readable lines.
fn violations(table: &BTreeMap<String, Row>, deps: &BTreeMap<String, Vec<String>>) -> Vec<String> {
    let mut found = Vec::new();
    for (krate, uses) in deps {
        let Some(row) = table.get(krate) else {
            if uses.is_empty() && krate == "pomona-test-support" {
                continue;
            }
            found.push(format!(
                "{krate} has no row in the layer table of ARCHITECTURE.md"
            ));
            continue;
        };
        for dep in uses {
            let Some(dep_row) = table.get(dep) else {
                found.push(format!("{krate} depends on {dep}, which has no layer"));
                continue;
            };
            let short = dep.strip_prefix("pomona-").unwrap_or(dep);
            let named = row
                .allowed
                .iter()
                .any(|a| a == "everything below" || a == short || a == dep || *a == dep_row.group);
            if dep_row.layer >= row.layer {
                found.push(format!(
                    "{krate} (layer {}) depends on {dep} (layer {}): only lower layers are allowed",
                    row.layer, dep_row.layer
                ));
            } else if !named {
                found.push(format!(
                    "{krate} depends on {dep}, which its \"may depend on\" column does not name"
                ));
            }
        }
    }
    found
}

#[test]
fn every_crate_depends_only_on_lower_layers_it_names() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let table = layer_table(&std::fs::read_to_string(root.join("ARCHITECTURE.md")).unwrap());
    assert!(table.len() >= 10, "layer table not found: {table:?}");
    let deps = workspace_dependencies(&root);
    let found = violations(&table, &deps);
    assert!(found.is_empty(), "layer rule broken:\n{}", found.join("\n"));
}

#[test]
fn the_check_catches_upward_sideways_and_unnamed_dependencies() {
    let table = layer_table(
        "| 0 data | `pomona-core` | x | serde |\n\
         | 1 files | `pomona-io` | x | core |\n\
         | 2 tools | `pomona-learn` | x | core, io |\n\
         | 2 tools | `pomona-eval` | x | core |\n\
         | 3 front | `pomona-cli` | x | everything below |\n",
    );
    let deps = |pairs: &[(&str, &[&str])]| -> BTreeMap<String, Vec<String>> {
        pairs
            .iter()
            .map(|(k, v)| (k.to_string(), v.iter().map(|s| s.to_string()).collect()))
            .collect()
    };
    let ok = deps(&[
        ("pomona-core", &[]),
        ("pomona-io", &["pomona-core"]),
        ("pomona-cli", &["pomona-learn", "pomona-core"]),
    ]);
    assert!(violations(&table, &ok).is_empty());
    let bad = deps(&[
        ("pomona-core", &["pomona-io"]),    // upwards
        ("pomona-learn", &["pomona-eval"]), // sideways
        ("pomona-eval", &["pomona-io"]),    // lower but not named
        ("pomona-new", &[]),                // no row
    ]);
    let found = violations(&table, &bad);
    assert_eq!(found.len(), 4, "{found:#?}");
}
