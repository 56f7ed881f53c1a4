//! The README and `docs/` as a user meets them (issue 12): the two commands the README opens
//! with exist in the Makefile and CI runs the test command; every relative link (file and
//! `#anchor`) in README.md, ARCHITECTURE.md and docs/*.md resolves; the README's Python
//! example reads keys and columns that `pound run --out` and a study's `cases.csv` /
//! `peaks.csv` really have, and, where Python with pandas is installed, runs against them.

mod common;

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

use common::{pound, TempDir};

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn read(p: &Path) -> String {
    std::fs::read_to_string(p).unwrap_or_else(|e| panic!("{}: {e}", p.display()))
}

/// The documents a user reads.
fn documents() -> Vec<PathBuf> {
    let r = root();
    let mut v = vec![r.join("README.md"), r.join("ARCHITECTURE.md")];
    let mut docs: Vec<PathBuf> = std::fs::read_dir(r.join("docs"))
        .expect("docs/ exists")
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "md"))
        .collect();
    docs.sort();
    assert!(!docs.is_empty(), "docs/ has no Markdown file");
    v.extend(docs);
    v
}

/// GitHub's anchor of a heading: lower case, spaces to '-', punctuation other than '-' and
/// '_' dropped.
fn slug(heading: &str) -> String {
    heading
        .trim()
        .to_lowercase()
        .chars()
        .filter_map(|c| {
            if c == ' ' {
                Some('-')
            } else if c.is_alphanumeric() || c == '-' || c == '_' {
                Some(c)
            } else {
                None
            }
        })
        .collect()
}

fn anchors(md: &str) -> BTreeSet<String> {
    let mut in_code = false;
    let mut out = BTreeSet::new();
    for line in md.lines() {
        if line.starts_with("```") {
            in_code = !in_code;
            continue;
        }
        if !in_code && line.starts_with('#') {
            out.insert(slug(line.trim_start_matches('#')));
        }
    }
    out
}

/// Targets of Markdown links `[text](target)` and images outside code blocks.
fn links(md: &str) -> Vec<String> {
    let mut in_code = false;
    let mut out = Vec::new();
    for line in md.lines() {
        if line.starts_with("```") {
            in_code = !in_code;
            continue;
        }
        if in_code {
            continue;
        }
        let mut rest = line;
        while let Some(i) = rest.find("](") {
            let after = &rest[i + 2..];
            let Some(j) = after.find(')') else { break };
            out.push(after[..j].to_string());
            rest = &after[j..];
        }
    }
    out
}

#[test]
fn every_relative_link_and_anchor_resolves() {
    let mut broken = Vec::new();
    let mut checked = 0;
    for doc in documents() {
        let text = read(&doc);
        let dir = doc.parent().unwrap();
        for target in links(&text) {
            if target.starts_with("http://") || target.starts_with("https://") {
                continue;
            }
            checked += 1;
            let (file, anchor) = match target.split_once('#') {
                Some((f, a)) => (f, Some(a)),
                None => (target.as_str(), None),
            };
            let path = if file.is_empty() {
                doc.clone()
            } else {
                dir.join(file)
            };
            if !path.exists() {
                broken.push(format!("{}: {target} (no such file)", doc.display()));
                continue;
            }
            if let Some(a) = anchor {
                if !anchors(&read(&path)).contains(a) {
                    broken.push(format!("{}: {target} (no such heading)", doc.display()));
                }
            }
        }
    }
    assert!(
        checked > 20,
        "only {checked} links found: is the parser right?"
    );
    assert!(broken.is_empty(), "broken links:\n{}", broken.join("\n"));
}

#[test]
fn readme_opens_with_the_two_commands_and_ci_runs_the_test_command() {
    let readme = read(&root().join("README.md"));
    let first_block = readme
        .split("```")
        .nth(1)
        .expect("the README opens with a code block");
    assert!(first_block.contains("make studies"), "{first_block}");
    assert!(first_block.contains("make test"), "{first_block}");
    let makefile = read(&root().join("Makefile"));
    for target in ["studies:", "test:"] {
        assert!(
            makefile.lines().any(|l| l.starts_with(target)),
            "Makefile has no `{target}` target"
        );
    }
    let ci = read(&root().join(".ci/run"));
    assert!(
        ci.lines().any(|l| l.trim() == "make test"),
        ".ci/run does not run `make test`:\n{ci}"
    );
    // The minimum Rust version the README states is the one Cargo enforces.
    let cargo = read(&root().join("Cargo.toml"));
    let msrv = cargo
        .lines()
        .find_map(|l| l.strip_prefix("rust-version = \""))
        .map(|v| v.trim_end_matches('"').to_string())
        .expect("rust-version in the workspace Cargo.toml");
    assert!(
        readme.contains(&format!("Rust toolchain, {msrv} or newer")),
        "README does not state rust-version {msrv}"
    );
}

/// The README's Python block.
fn python_example() -> String {
    let readme = read(&root().join("README.md"));
    let start = readme
        .find("```python\n")
        .expect("README has a Python example");
    let body = &readme[start + "```python\n".len()..];
    body[..body.find("```").unwrap()].to_string()
}

/// Every `name["key"]` and `.attr` the example reads must exist in what pound writes.
#[test]
fn python_example_matches_the_outputs_and_runs_where_pandas_is_installed() {
    let code = python_example();
    let d = TempDir::new("docs-python");
    let scene = root().join("studies/paper/scene.toml");
    let run = d.path("run.json");
    let o = pound(&[
        "run",
        scene.to_str().unwrap(),
        "--method",
        "momentum",
        "--set",
        "analysis.duration=12",
        "--out",
        run.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let json: serde_json::Value = serde_json::from_str(&read(&run)).unwrap();
    // Keys the example reads from the run JSON.
    for path in [
        &["method"][..],
        &["record", "file"],
        &["stats", "impacts"],
        &["amplification"],
    ] {
        let mut v = &json;
        for k in path {
            v = v
                .get(k)
                .unwrap_or_else(|| panic!("run JSON has no {path:?}"));
        }
        assert!(code.contains(&format!("[\"{}\"]", path[path.len() - 1])));
    }
    let amp = &json["amplification"][0];
    assert!(amp.get("name").is_some() && amp.get("story_shear").is_some());

    let studies = root().join("studies");
    let out = d.path("results");
    let o = common::quick_run(
        "stiffness",
        studies.to_str().unwrap(),
        out.to_str().unwrap(),
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let header = |f: &str| -> Vec<String> {
        read(&out.join("stiffness").join(f))
            .lines()
            .next()
            .unwrap()
            .split(',')
            .map(|s| s.trim_matches('"').to_string())
            .collect()
    };
    let cases = header("cases.csv");
    let peaks = header("peaks.csv");
    for c in ["case_id", "method"] {
        assert!(
            cases.contains(&c.to_string()),
            "cases.csv lacks {c}: {cases:?}"
        );
    }
    for c in ["case_id", "building", "story", "amplification"] {
        assert!(
            peaks.contains(&c.to_string()),
            "peaks.csv lacks {c}: {peaks:?}"
        );
    }

    // Run it where Python and pandas are there (CI machines need not have them).
    let has_pandas = std::process::Command::new("python3")
        .args(["-c", "import pandas"])
        .output()
        .map(|o| o.status.success())
        .unwrap_or(false);
    if !has_pandas {
        eprintln!("python3 with pandas not found: the example was checked, not run");
        return;
    }
    // The example's own paths, pointed at this test's outputs (both must be there).
    for p in ["\"/tmp/run.json\"", "\"results/stiffness/"] {
        assert!(code.contains(p), "the README example no longer reads {p}");
    }
    let script = code
        .replace("\"/tmp/run.json\"", &format!("{:?}", run.to_str().unwrap()))
        .replace(
            "\"results/stiffness/",
            &format!("\"{}/stiffness/", out.to_str().unwrap()),
        );
    let py = d.write("example.py", &script);
    let o = std::process::Command::new("python3")
        .arg(&py)
        .output()
        .unwrap();
    assert!(
        o.status.success(),
        "the README's Python example failed:\n{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(stdout.contains("momentum"), "{stdout}");
    assert!(stdout.contains("amplification"), "{stdout}");
}
