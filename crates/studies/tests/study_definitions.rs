//! The checks of the study definitions (`studies/<name>.toml`) run through the real `pound`
//! binary: a definition with no record, a count outside its range, an empty list, a value
//! the study cannot use, a paper reference list of the wrong length or a definition that
//! cannot be read is bad input. Every case must
//!
//! - exit with code 2,
//! - name the definition file and the key (and what was expected) on stderr,
//! - not panic, print nothing on stdout, and write nothing (the `--out` folder has no files).
//!
//! And every committed definition still passes these checks (built into its full case list,
//! without running a case).

use std::path::{Path, PathBuf};

mod common;
use common::{pound, TempDir, STUDIES};

use studies::studies::{all_cases, study, Ctx, StudyOptions, EXTRA, NAMES};

/// The repository root.
fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// Copies `from` into `to` recursively; in `*.toml` files the record paths relative to the
/// repository's `studies/` (`"../data/`) and `studies/paper/` (`"../../data/`) are made
/// absolute, so the copy reads the repository's records.
fn copy_studies(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).unwrap();
    let data = root().join("data").display().to_string();
    for e in std::fs::read_dir(from).unwrap() {
        let e = e.unwrap();
        let (src, dst) = (e.path(), to.join(e.file_name()));
        if src.is_dir() {
            copy_studies(&src, &dst);
        } else if src.extension().is_some_and(|x| x == "toml") {
            let text = std::fs::read_to_string(&src)
                .unwrap()
                .replace("\"../../data/", &format!("\"{data}/"))
                .replace("\"../data/", &format!("\"{data}/"));
            std::fs::write(&dst, text).unwrap();
        } else {
            std::fs::copy(&src, &dst).unwrap();
        }
    }
}

/// Replaces the value of top-level key `key` in a TOML text (a one-line value or a
/// multi-line array) with `value`, or appends `key = value` when the key is absent.
fn set_key(text: &str, key: &str, value: &str) -> String {
    let start = text
        .match_indices(&format!("{key} ="))
        .map(|(i, _)| i)
        .find(|&i| i == 0 || text.as_bytes()[i - 1] == b'\n');
    let Some(i) = start else {
        // Before the first table (`[[…]]`), so it stays a top-level key.
        let at = text.find("\n[").map_or(text.len(), |p| p + 1);
        return format!("{}{key} = {value}\n{}", &text[..at], &text[at..]);
    };
    let after = i + key.len() + 2;
    let rest = &text[after..];
    let v = rest.trim_start();
    let vstart = after + (rest.len() - v.len());
    let end = if v.starts_with('[') {
        let mut depth = 0;
        let mut end = vstart;
        for (k, c) in v.char_indices() {
            match c {
                '[' => depth += 1,
                ']' => {
                    depth -= 1;
                    if depth == 0 {
                        end = vstart + k + 1;
                        break;
                    }
                }
                _ => {}
            }
        }
        end
    } else {
        vstart + v.find('\n').unwrap_or(v.len())
    };
    format!("{}{key} = {value}{}", &text[..i], &text[end..])
}

/// Every file under `dir` (none if it does not exist).
fn files_under(dir: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    if let Ok(rd) = std::fs::read_dir(dir) {
        for e in rd.flatten() {
            let p = e.path();
            if p.is_dir() {
                out.extend(files_under(&p));
            } else {
                out.push(p);
            }
        }
    }
    out
}

/// Runs `pound studies run <study> --quick` on a scratch copy of `studies/` where `edit`
/// has changed the study's definition, and checks the bad-input contract: exit 2, the file
/// name and every fragment of `expect` on stderr, no panic, nothing on stdout, no file
/// under the output folder. Returns stderr.
#[track_caller]
fn refused_with(study: &str, edit: impl FnOnce(&Path), expect: &[&str]) -> String {
    let d = TempDir::new("study-def");
    let dir = d.path("studies");
    copy_studies(Path::new(STUDIES), &dir);
    edit(&dir);
    let out = d.path("out");
    let o = common::quick_run(study, dir.to_str().unwrap(), out.to_str().unwrap());
    let err = String::from_utf8_lossy(&o.stderr).into_owned();
    let what = format!("{study} {expect:?}: {err}");
    assert_eq!(o.status.code(), Some(2), "exit code, {what}");
    assert!(!err.contains("panicked"), "panic, {what}");
    assert!(err.contains(&format!("{study}.toml")), "the file, {what}");
    for e in expect {
        assert!(err.contains(e), "{e:?} not on stderr, {what}");
    }
    assert!(o.stdout.is_empty(), "nothing on stdout, {what}");
    let written = files_under(&out);
    assert!(written.is_empty(), "nothing written, {what}: {written:?}");
    err
}

/// [`refused_with`] for a definition with `edits` (`(key, value)`) applied.
#[track_caller]
fn refused(study: &str, edits: &[(&str, &str)], expect: &[&str]) -> String {
    refused_with(
        study,
        |dir| {
            let path = dir.join(format!("{study}.toml"));
            let mut text = std::fs::read_to_string(&path).unwrap();
            for (k, v) in edits {
                text = set_key(&text, k, v);
            }
            std::fs::write(&path, text).unwrap();
        },
        expect,
    )
}

/// A study left with no record (`records = []`, `record_dirs = []` or naming a folder with
/// no `*.AT2`) is refused naming the keys, before anything is written. It used to panic
/// (restitution, modelform: index out of bounds, exit 101, after writing the manifest and
/// tables) or run "0 cases" writing empty tables (stiffness, modes, gap, yielding).
#[test]
fn a_study_without_records_is_refused() {
    let none = [("records", "[]"), ("record_dirs", "[]")];
    for st in ["restitution", "stiffness", "modes", "gap", "yielding"] {
        refused(
            st,
            &none,
            &[
                "`records` = []",
                "`record_dirs` = []",
                "expected at least one record",
            ],
        );
    }
    // modelform takes no `record_dirs`.
    refused(
        "modelform",
        &[("records", "[]")],
        &["`records` = []", "expected at least one record"],
    );
    // A folder without any *.AT2 file.
    refused_with(
        "modes",
        |dir| {
            std::fs::create_dir(dir.join("no-records")).unwrap();
            std::fs::write(dir.join("no-records/readme.txt"), "no records here\n").unwrap();
            let path = dir.join("modes.toml");
            let text = std::fs::read_to_string(&path).unwrap();
            let text = set_key(&text, "records", "[]");
            let text = set_key(&text, "record_dirs", "[\"no-records\"]");
            std::fs::write(&path, text).unwrap();
        },
        &[
            "`record_dirs` = [\"no-records\"]",
            "expected at least one record",
        ],
    );
}

/// Every count and size key has an upper bound (and a lower one): a count of 10⁹ is refused
/// naming the key and its range, instead of allocating gigabytes (an abort, exit 134) or
/// running a case list that never ends. (With `--quick` the grids are small, so these
/// used to run and exit 0.)
#[test]
fn counts_outside_their_range_are_refused() {
    let big = "1000000000";
    for (st, key, value, range) in [
        ("gap", "gap_count", big, "2 ..= 1000"),
        ("gap", "gap_count", "1001", "2 ..= 1000"),
        ("stiffness", "stiffness_count", big, "2 ..= 1000"),
        ("stability", "adaptive_stiffness_count", big, "2 ..= 1000"),
        ("stability", "max_modes", big, "1 ..= 1000"),
        ("modes", "max_modes", big, "5 ..= 1000"),
        ("cost", "repeat", big, "1 ..= 1000"),
        ("cost", "modes", "[5, 1000000000]", "1 ..= 1000"),
        ("paper", "paper_impulse_modes", big, "1 ..= 1000"),
        ("paper", "fewer_modes", "[10, 1001]", "1 ..= 1000"),
        ("modelform", "fewer_modes", big, "1 ..= 1000"),
    ] {
        refused(st, &[(key, value)], &[&format!("`{key}`"), range]);
    }
}

/// The stability and cost definitions are checked like the others: a count of 0, an empty
/// list, an accuracy level that is not a finite number > 0 are refused naming the key and
/// the range or "at least one". They used to exit 0 running fewer cases (or, for
/// `accuracy`, a summary reading "No gap-element setting reaches -100 % …"). The same for
/// the other studies' keys that the scene does not check in every case.
#[test]
fn every_study_key_is_checked() {
    for (st, key, value, expect) in [
        ("stability", "adaptive_stiffness_count", "0", "2 ..= 1000"),
        ("stability", "max_modes", "0", "1 ..= 1000"),
        ("stability", "newmark_step", "[]", "at least one"),
        ("stability", "newmark_stiffness", "[]", "at least one"),
        ("stability", "chatter_restitution", "[]", "at least one"),
        ("stability", "gap", "-0.1", ">= 0"),
        ("cost", "modes", "[]", "at least one"),
        ("cost", "modes", "[0]", "1 ..= 1000"),
        ("cost", "adaptive_stiffness", "[]", "at least one"),
        ("cost", "adaptive_tolerance", "[]", "at least one"),
        ("cost", "newmark_step", "[]", "at least one"),
        ("cost", "newmark_stiffness", "[]", "at least one"),
        ("cost", "accuracy", "[]", "at least one"),
        ("cost", "accuracy", "[-1, nan]", "finite relative error > 0"),
        ("cost", "repeat", "0", "1 ..= 1000"),
        ("modes", "variants", "[]", "at least one"),
        (
            "modes",
            "variants",
            "[\"consistent\", \"bogus\"]",
            "\"paper\"",
        ),
        ("modes", "variants", "[\"paper\", \"paper\"]", "each once"),
        ("modes", "restitution", "1.5", "[0, 1]"),
        ("restitution", "gap_stiffness", "[]", "at least one"),
        ("restitution", "gap", "nan", ">= 0"),
        ("stiffness", "restitution", "[1.0, 1.5]", "[0, 1]"),
        (
            "stiffness",
            "fit_min_stiffness",
            "1.0e14",
            "< `stiffness_max`",
        ),
        ("stiffness", "stiffness_max", "inf", "0 < min < max"),
        ("modelform", "gaps", "[0.1, -0.05]", ">= 0"),
        ("modelform", "restitution", "[1.0, 1.2]", "[0, 1]"),
        ("modelform", "amplification_threshold", "-1.5", "> 0"),
        ("modelform", "local_band", "nan", "> 0"),
        ("paper", "gaps", "[]", "at least one"),
        ("robustness", "gaps", "[inf]", "finite"),
        ("gap", "pga", "0.0", "`pga`"),
    ] {
        refused(st, &[(key, value)], &[&format!("`{key}`"), expect]);
    }
}

/// A paper reference list of the wrong length (one value per floor of its building, top
/// floor first) is refused naming the list, instead of being read shifted (14 values: the
/// story-14 value shown as story 15); so is a reference at a gap the study does not run.
#[test]
fn paper_reference_lists_of_the_wrong_length_are_refused() {
    let fourteen = "[2.406, 1.860, 1.162, 1.141, 1.109, 1.201, 1.071, 1.066, 1.074, 1.077, 1.064, 1.038, 1.083, 1.111]";
    let sixteen = "[2.406, 1.860, 1.162, 1.141, 1.109, 1.201, 1.071, 1.066, 1.074, 1.077, 1.064, 1.038, 1.083, 1.111, 1.140, 1.0]";
    for (key, list, n) in [("building1_x", fourteen, 14), ("building2_y", sixteen, 16)] {
        refused(
            "paper",
            &[(key, list)],
            &[
                &format!("`reference[0].{key}` has {n} values"),
                "expected 15 values (one per floor",
            ],
        );
    }
    refused(
        "paper",
        &[("building1_x", "[2.406, 1.860, 1.162, 1.141, 1.109, 1.201, 1.071, 1.066, 1.074, 1.077, 1.064, 1.038, 1.083, 1.111, nan]")],
        &["`reference[0].building1_x`", "finite and > 0"],
    );
    refused(
        "paper",
        &[("gap", "0.07")],
        &["`reference[0].gap` = 0.07", "expected one of `gaps`"],
    );
}

/// A study definition that cannot be read (missing, not UTF-8, a folder) is bad input:
/// exit 2 naming the file, as an unreadable scene is. It used to exit 1.
#[test]
fn an_unreadable_study_definition_is_bad_input() {
    let expect = ["gap.toml", "cannot read the study definition"];
    refused_with(
        "gap",
        |dir| std::fs::remove_file(dir.join("gap.toml")).unwrap(),
        &expect,
    );
    refused_with(
        "gap",
        |dir| std::fs::write(dir.join("gap.toml"), b"scene = \"\xff\xfe\"\n").unwrap(),
        &[expect[0], expect[1], "UTF-8"],
    );
    refused_with(
        "gap",
        |dir| {
            std::fs::remove_file(dir.join("gap.toml")).unwrap();
            std::fs::create_dir(dir.join("gap.toml")).unwrap();
        },
        &expect,
    );
}

/// Every committed definition (`studies/*.toml`, each a study of `NAMES` or `EXTRA`) passes
/// the checks: its full case list (not `--quick`, the definition's own records) is built
/// and every case's scene validated, without running a case. So the ranges chosen admit
/// what `pound studies run --all` runs.
#[test]
fn every_committed_definition_validates() {
    let studies_dir = root().join("studies");
    let mut seen = Vec::new();
    for e in std::fs::read_dir(&studies_dir).unwrap() {
        let p = e.unwrap().path();
        if p.extension().is_none_or(|x| x != "toml") {
            continue;
        }
        let name = p.file_stem().unwrap().to_string_lossy().into_owned();
        assert!(
            NAMES.contains(&name.as_str()) || EXTRA.contains(&name.as_str()),
            "{}: not a study",
            p.display()
        );
        let text = std::fs::read_to_string(&p).unwrap();
        let ctx = Ctx {
            name: name.clone(),
            def: toml::from_str(&text).unwrap(),
            def_file: p.display().to_string(),
            opts: StudyOptions::default(),
            studies_dir: studies_dir.clone(),
            dir: std::env::temp_dir().join("pound-study-definitions-unused"),
        };
        let st = study(&name).unwrap();
        let cases = all_cases(st, &ctx).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert!(!cases.is_empty(), "{name}");
        seen.push(name);
    }
    seen.sort();
    let mut all: Vec<String> = NAMES.iter().chain(&EXTRA).map(|s| s.to_string()).collect();
    all.sort();
    assert_eq!(seen, all, "every study has its committed definition");
    assert!(
        !std::env::temp_dir()
            .join("pound-study-definitions-unused")
            .exists(),
        "validating writes nothing"
    );
}

/// Several studies in one command: every definition is checked before the first study runs,
/// so a bad definition of a later study (`gap`, after `paper`) stops the command with nothing
/// written, not after the earlier studies have written their outputs.
#[test]
fn a_bad_later_definition_stops_the_command_before_any_study_runs() {
    let d = TempDir::new("study-def-later");
    let dir = d.path("studies");
    copy_studies(Path::new(STUDIES), &dir);
    let path = dir.join("gap.toml");
    let text = std::fs::read_to_string(&path).unwrap();
    std::fs::write(&path, set_key(&text, "gap_count", "1000000000")).unwrap();
    let out = d.path("out");
    let o = pound(&[
        "studies",
        "run",
        "paper",
        "gap",
        "--quick",
        "--studies-dir",
        dir.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    let err = String::from_utf8_lossy(&o.stderr).into_owned();
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        err.contains("gap.toml") && err.contains("gap_count"),
        "{err}"
    );
    assert!(!err.contains("panicked"), "{err}");
    let written = files_under(&out);
    assert!(written.is_empty(), "nothing written: {written:?}");
}

/// The studies that say they take `record_table` (`Study::takes_record_table`) are the
/// studies whose committed definitions give it, so that the note about a missing default
/// table is said for exactly those.
#[test]
fn the_studies_with_a_record_table_are_listed() {
    for name in NAMES.iter().chain(&EXTRA) {
        let text = std::fs::read_to_string(root().join(format!("studies/{name}.toml"))).unwrap();
        let def: toml::Table = toml::from_str(&text).unwrap();
        assert_eq!(
            def.contains_key("record_table"),
            study(name).unwrap().takes_record_table(),
            "{name}"
        );
    }
}

/// A definition without `record_table` reads the default table,
/// `../data/ground-motions/records.csv` relative to the studies folder, when it exists (a
/// near-field pulse record is classified as one); when it does not (a studies folder of the
/// user's own, outside the repository) the study runs with every record unclassified and one
/// note on stderr, instead of failing on a table the file never named. A `record_table`
/// that is named and cannot be read is still refused (`cli_bad_input.rs`).
#[test]
fn a_study_without_record_table_classifies_nothing_without_the_default_table() {
    let d = TempDir::new("no-record-table");
    let dir = d.path("studies");
    copy_studies(&root().join("studies"), &dir);
    let def: String = std::fs::read_to_string(dir.join("gap.toml"))
        .unwrap()
        .lines()
        .filter(|l| !l.starts_with("record_table"))
        .map(|l| format!("{l}\n"))
        .collect();
    std::fs::write(dir.join("gap.toml"), def).unwrap();
    let pulse = root().join("data/ground-motions/near-field/RSN181_IMPVALL-H-E06_233.AT2");
    let run = |out: &Path| {
        let o = pound(&[
            "studies",
            "run",
            "gap",
            "--quick",
            "--studies-dir",
            dir.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
            "--records",
            pulse.to_str().unwrap(),
        ]);
        let err = String::from_utf8_lossy(&o.stderr).into_owned();
        assert!(o.status.success(), "{err}");
        let summary = std::fs::read_to_string(out.join("gap/summary.md")).unwrap();
        (err, summary)
    };
    let (err, summary) = run(&d.path("out1"));
    assert_eq!(err.matches("note:").count(), 1, "{err}");
    assert!(
        err.contains("gap.toml has no `record_table`")
            && err.contains("../data/ground-motions/records.csv")
            && err.contains("every record is unclassified"),
        "{err}"
    );
    assert!(summary.contains("1 record (1 unclassified)"), "{summary}");
    // The default table beside the studies folder: read, and no note.
    let table = d.path("data/ground-motions/records.csv");
    std::fs::create_dir_all(table.parent().unwrap()).unwrap();
    std::fs::copy(root().join("data/ground-motions/records.csv"), &table).unwrap();
    let (err, summary) = run(&d.path("out2"));
    assert!(!err.contains("note:"), "{err}");
    assert!(summary.contains("1 record (1 pulse)"), "{summary}");
}

/// The gap study compares 5 and 10 cm gaps (`gap_5_vs_10.md`): with a grid that lacks
/// either, the file and the summary say in one line that it was not computed and why,
/// instead of a table of n = 0 and dashes; with both in the grid the table is written.
#[test]
fn gap_5_vs_10_says_why_when_the_grid_lacks_the_gaps() {
    let d = TempDir::new("gap-5-10");
    let dir = d.path("studies");
    copy_studies(&root().join("studies"), &dir);
    let def = std::fs::read_to_string(dir.join("gap.toml")).unwrap();
    // --quick: 6 gaps from 0 to gap_max. 0.20: neither 5 nor 10 cm; 0.50: 10 cm but no
    // 5 cm (the singular); 0.25: both, the table.
    let neither =
        "not computed: the gap grid (0, 4, 8, 12, 16, 20 cm) has no 5 cm and 10 cm values";
    let no_five = "not computed: the gap grid (0, 10, 20, 30, 40, 50 cm) has no 5 cm value";
    for (gap_max, why) in [
        ("0.20", Some(neither)),
        ("0.50", Some(no_five)),
        ("0.25", None),
    ] {
        let text: String = def
            .lines()
            .map(|l| {
                if l.starts_with("gap_max") {
                    format!("gap_max = {gap_max}\n")
                } else {
                    format!("{l}\n")
                }
            })
            .collect();
        std::fs::write(dir.join("gap.toml"), text).unwrap();
        let out = d.path(&format!("out-{gap_max}"));
        let o = common::quick_run("gap", dir.to_str().unwrap(), out.to_str().unwrap());
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let md = std::fs::read_to_string(out.join("gap/gap_5_vs_10.md")).unwrap();
        let summary = std::fs::read_to_string(out.join("gap/summary.md")).unwrap();
        let csv = std::fs::read_to_string(out.join("gap/gap_5_vs_10.csv")).unwrap();
        match why {
            None => {
                assert!(
                    md.contains("| amplification, building 2 contact story |"),
                    "{md}"
                );
                assert!(!summary.contains("not computed"), "{summary}");
                assert_eq!(csv.lines().count(), 4, "{csv}");
            }
            Some(why) => {
                assert_eq!(md.lines().count(), 1, "{md}");
                assert!(md.contains(why), "{md}");
                assert!(!md.contains('–'), "{md}");
                assert!(
                    summary.contains(&format!("(`gap_5_vs_10.md`): {why}")),
                    "{summary}"
                );
                assert!(
                    !summary.contains("| amplification, building 2"),
                    "{summary}"
                );
                // The header alone.
                assert_eq!(csv.lines().count(), 1, "{csv}");
            }
        }
    }
}
