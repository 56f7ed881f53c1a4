//! A sweep whose cases fail does not exit 0: `pound studies run` exits 4 and names the
//! failed cases, on stderr and in the study's summary; cases that exist to show a solver
//! error (the stability study's chattering without persistent contact) are results.

mod common;
use common::{pound, TempDir};
use std::path::{Path, PathBuf};
use std::process::Output;

fn studies_dir() -> String {
    common::STUDIES.to_string()
}

/// The same 14 s record, 0.3 g · sin(2π·1.5 t) · e^(−decay·t) at 0.01 s, as a one-column file
/// `one.txt` and a two-column file (time, acceleration) named `two`, in `d`.
fn sine_records(d: &TempDir, decay: f64, two: &str) -> (PathBuf, PathBuf) {
    let (mut a1, mut a2) = (String::new(), String::new());
    for i in 0..1400 {
        let t = i as f64 * 0.01;
        let a = 0.3 * (2.0 * std::f64::consts::PI * 1.5 * t).sin() * (-decay * t).exp();
        a1.push_str(&format!("{a:.6}\n"));
        a2.push_str(&format!("{t:.2} {a:.6}\n"));
    }
    (d.write("one.txt", &a1), d.write(two, &a2))
}

/// `pound studies run <study> --quick --studies-dir <studies> --out <out> --records …`.
fn quick_with_records(study: &str, studies: &str, out: &Path, records: &[&PathBuf]) -> Output {
    let mut extra = vec!["--records"];
    extra.extend(records.iter().map(|r| r.to_str().unwrap()));
    common::quick_run_with(study, studies, out.to_str().unwrap(), &extra)
}

/// A study whose cases fail in the solver (here the momentum method at c_r = 0 without its
/// persistent-contact phase: chattering stalls it) exits 4 and names the failed cases, on
/// stderr and in the summary; the tables are still written.
#[test]
fn failed_cases_exit_4_and_are_named() {
    let d = TempDir::new("failedcases");
    std::fs::create_dir_all(d.path("defs")).unwrap();
    let paper = std::fs::read_to_string(format!("{}/paper/scene.toml", studies_dir())).unwrap();
    let rec = format!(
        "{}/../data/ground-motions/RSN752_LOMAP_CAP000.AT2",
        studies_dir()
    );
    d.write(
        "defs/scene.toml",
        &paper
            .replace("[momentum]\n", "[momentum]\npersistent_contact = false\n")
            .replace("../../data/", &format!("{}/../data/", studies_dir())),
    );
    d.write(
        "defs/restitution.toml",
        &format!(
            "scene = \"scene.toml\"\npga = 0.40\nrecords = [\"{rec}\"]\ngap = 0.10\nrestitution = [0.0]\ngap_stiffness = [1.0e10]\nrecord_table = \"{}/../data/ground-motions/records.csv\"\n",
            studies_dir()
        ),
    );
    let out = d.path("out");
    let o = common::quick_run(
        "restitution",
        d.path("defs").to_str().unwrap(),
        out.to_str().unwrap(),
    );
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(4), "{err}");
    assert!(
        err.contains("Stalled") || err.contains("stall"),
        "the reason is named: {err}"
    );
    let summary = std::fs::read_to_string(out.join("restitution/summary.md")).unwrap();
    assert!(summary.contains("### Failed cases"), "{summary}");
    let cases: Vec<serde_json::Value> =
        serde_json::from_str(&std::fs::read_to_string(out.join("restitution/cases.json")).unwrap())
            .unwrap();
    let failed: Vec<&str> = cases
        .iter()
        .filter(|c| c["status"] != "ok")
        .map(|c| c["spec"]["id"].as_str().unwrap())
        .collect();
    assert!(!failed.is_empty());
    // Counted on stderr, the noun as the count asks.
    let counted = if failed.len() == 1 {
        "1 case failed".to_string()
    } else {
        format!("{} cases failed", failed.len())
    };
    assert!(
        err.contains(&format!("{counted} (listed in each study's summary.md)")),
        "{err}"
    );
    for id in failed {
        assert!(summary.contains(id), "{id} not named in the summary");
    }
}

/// A record that cannot be read, given with `--records`, is bad input: exit 2 before any
/// case runs, the file and line named, no results folder.
#[test]
fn unreadable_record_is_refused_before_the_sweep() {
    let d = TempDir::new("badrecord");
    let rec = d.write("garbage.AT2", "junk\n1 2 3\nfoo\n");
    let out = d.path("out");
    let o = pound(&[
        "studies",
        "run",
        "gap",
        "--quick",
        "--records",
        rec.to_str().unwrap(),
        "--studies-dir",
        &studies_dir(),
        "--out",
        out.to_str().unwrap(),
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains("garbage.AT2 line 3"), "{err}");
    assert!(!out.exists(), "nothing written");
}

#[test]
fn expected_solver_errors_are_results() {
    let d = TempDir::new("expectedfail");
    let out = d.path("out");
    let o = common::quick_run("stability", &studies_dir(), out.to_str().unwrap());
    let err = String::from_utf8_lossy(&o.stderr).into_owned();
    assert!(o.status.success(), "{err}");
    // The console line says the failure is the one the study expects.
    assert!(err.contains("(1 failed, as the study expects)"), "{err}");
    let summary = std::fs::read_to_string(out.join("stability/summary.md")).unwrap();
    assert!(
        summary.contains("end with the solver error they exist to show (1)"),
        "{summary}"
    );
    assert!(summary.contains("Stalled") && !summary.contains("### Failed cases"));
}

/// A rerun whose cases are all cached ran nothing: `timing.json` keeps the time of the run
/// that computed them (the README quotes it).
#[test]
fn a_cached_rerun_keeps_the_timing_of_the_run_that_computed() {
    let d = TempDir::new("cachedtiming");
    let out = d.path("out");
    let run = || {
        let o = common::quick_run("paper", &studies_dir(), out.to_str().unwrap());
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let t: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(out.join("timing.json")).unwrap())
                .unwrap();
        t["studies"]["paper"].clone()
    };
    let first = run();
    assert!(first["ran"].as_u64().unwrap() > 0, "{first}");
    let second = run();
    assert_eq!(first, second, "a fully cached rerun replaced the timing");
}

/// A study scene whose contact is below the roofs: the studies report the story under the
/// contact floor and say so, and the separation rules use the contact floors.
#[test]
fn studies_report_the_contact_story() {
    let d = TempDir::new("contactstory");
    let paper = std::fs::read_to_string(format!("{}/paper/scene.toml", studies_dir())).unwrap();
    let rec = format!(
        "{}/../data/ground-motions/RSN752_LOMAP_CAP000.AT2",
        studies_dir()
    );
    let scene = paper
        .replace("left_floor = 15", "left_floor = 10")
        .replace("right_floor = 15", "right_floor = 10")
        .replace("../../data/ground-motions/RSN752_LOMAP_CAP000.AT2", &rec);
    d.write("low.toml", &scene);
    let def = std::fs::read_to_string(format!("{}/gap.toml", studies_dir()))
        .unwrap()
        .replace("scene = \"paper/scene.toml\"", "scene = \"low.toml\"")
        .replace("\"../data/", &format!("\"{}/../data/", studies_dir()));
    d.write("gap.toml", &def);
    let out = d.path("out");
    let o = common::quick_run("gap", d.0.to_str().unwrap(), out.to_str().unwrap());
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let summary = std::fs::read_to_string(out.join("gap/summary.md")).unwrap();
    assert!(
        summary.contains("story 10 of 15 of building1 and story 10 of 15 of building2"),
        "{summary}"
    );
    // Δ1 of the separation table is the peak displacement of floor 10 without contact.
    let cases: Vec<serde_json::Value> =
        serde_json::from_str(&std::fs::read_to_string(out.join("gap/cases.json")).unwrap())
            .unwrap();
    let base = cases
        .iter()
        .find(|c| c["spec"]["params"]["baseline"] == true)
        .unwrap();
    let d1 = base["outputs"]["floor_displacement_max"][0][9]
        .as_f64()
        .unwrap();
    let top = base["outputs"]["floor_displacement_max"][0][14]
        .as_f64()
        .unwrap();
    assert!(
        (d1 - top).abs() > 1e-3,
        "floor 10 and roof differ: {d1} {top}"
    );
    let cell = format!("| {:.2} |", d1 * 100.0);
    assert!(
        summary.contains(&cell)
            || std::fs::read_to_string(out.join("gap/separation.md"))
                .is_ok_and(|t| t.contains(&cell)),
        "Δ1 = {cell} in the separation table"
    );
}

/// A scene whose contact 0 does not join buildings 1 and 2 is refused (exit 2).
#[test]
fn study_scene_with_contact_elsewhere_is_refused() {
    let d = TempDir::new("contactelsewhere");
    let paper = std::fs::read_to_string(format!("{}/paper/scene.toml", studies_dir())).unwrap();
    let rec = format!(
        "{}/../data/ground-motions/RSN752_LOMAP_CAP000.AT2",
        studies_dir()
    );
    let third = "[[buildings]]\nname = \"building3\"\nstories = 3\nmass = 1.0e6\nstory_stiffness = 1.0e9\n\n[[contacts]]";
    let scene = paper
        .replacen("[[contacts]]", third, 1)
        .replace("right = \"building2\"", "right = \"building3\"")
        .replace("right_floor = 15", "right_floor = 3")
        .replace("../../data/ground-motions/RSN752_LOMAP_CAP000.AT2", &rec);
    d.write("three.toml", &scene);
    let def = std::fs::read_to_string(format!("{}/gap.toml", studies_dir()))
        .unwrap()
        .replace("scene = \"paper/scene.toml\"", "scene = \"three.toml\"")
        // The definition's record paths are relative to the repository's studies/ folder.
        .replace("\"../data/", &format!("\"{}/../data/", studies_dir()));
    d.write("gap.toml", &def);
    let out = d.path("out");
    let o = common::quick_run("gap", d.0.to_str().unwrap(), out.to_str().unwrap());
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains("joins buildings 1 and 3"), "{err}");
    assert!(!out.exists(), "nothing written");
    assert!(o.stdout.is_empty());
}

/// `--record-format` / `--record-dt` read `--records` files that are not AT2 or two-column:
/// the same samples as one column (with its dt) and as two columns (time, acceleration)
/// give the same peaks; a one-column file without them is refused before the sweep, and so
/// are options that do not fit together.
#[test]
fn record_format_of_user_records() {
    let d = TempDir::new("recformat");
    let (one, two) = sine_records(&d, 0.1, "two.dat");
    let studies = studies_dir();
    let run = |out: &str, rec: &std::path::Path, extra: &[&str]| {
        let out = d.path(out);
        let mut a: Vec<String> = [
            "studies",
            "run",
            "modes",
            "--quick",
            "--studies-dir",
            &studies,
            "--out",
            out.to_str().unwrap(),
            "--records",
            rec.to_str().unwrap(),
        ]
        .iter()
        .map(|s| s.to_string())
        .collect();
        a.extend(extra.iter().map(|s| s.to_string()));
        (pound(&a), out)
    };
    let (o1, out1) = run(
        "one",
        &one,
        &["--record-format", "one-column", "--record-dt", "0.01"],
    );
    assert!(
        o1.status.success(),
        "{}",
        String::from_utf8_lossy(&o1.stderr)
    );
    let (o2, out2) = run("two", &two, &[]);
    assert!(
        o2.status.success(),
        "{}",
        String::from_utf8_lossy(&o2.stderr)
    );
    // Peaks row by row without the case id (the record options are part of it). Not bit
    // for bit: one column times the samples as i·dt, two columns parse "0.07"; the peaks
    // agree to round-off.
    let peaks = |out: &std::path::Path| -> Vec<Vec<String>> {
        std::fs::read_to_string(out.join("modes/peaks.csv"))
            .unwrap()
            .lines()
            .map(|l| l.split(',').skip(1).map(str::to_string).collect())
            .collect()
    };
    let (p1, p2) = (peaks(&out1), peaks(&out2));
    assert_eq!(p1.len(), p2.len());
    let mut numbers = 0;
    for (a, b) in p1.iter().zip(&p2) {
        assert_eq!(a.len(), b.len());
        for (x, y) in a.iter().zip(b) {
            match (x.parse::<f64>(), y.parse::<f64>()) {
                (Ok(x), Ok(y)) => {
                    numbers += 1;
                    assert!((x - y).abs() <= 1e-9 * x.abs().max(y.abs()), "{x} vs {y}");
                }
                _ => assert_eq!(x, y),
            }
        }
    }
    assert!(numbers > 100, "{numbers} numbers compared");
    // The options are kept in the manifest, so a merge rebuilds the same case list.
    let manifest = std::fs::read_to_string(out1.join("modes/manifest.json")).unwrap();
    assert!(manifest.contains("one-column"), "{manifest}");
    // `--record-dt` alone means one-column (as `pound record FILE --dt S`): the same cases,
    // ids included, as with `--record-format one-column`.
    let (o3, out3) = run("dt-alone", &one, &["--record-dt", "0.01"]);
    assert!(
        o3.status.success(),
        "{}",
        String::from_utf8_lossy(&o3.stderr)
    );
    let table = |out: &std::path::Path| std::fs::read_to_string(out.join("modes/peaks.csv"));
    assert_eq!(table(&out3).unwrap(), table(&out1).unwrap());

    for (rec, extra, expect) in [
        // A one-column file without the options: the message names the file and the
        // options to give (not a scene key).
        (
            &one,
            &[][..],
            &[
                "--records: ",
                "one.txt holds one value per line",
                "give --record-format one-column --record-dt S",
            ][..],
        ),
        (
            &one,
            &["--record-format", "two-column"][..],
            &[
                "one.txt holds one value per line",
                "--record-format one-column",
            ][..],
        ),
        (
            &one,
            &["--record-format", "one-column"][..],
            &["--record-dt"][..],
        ),
        // `--record-dt` alone would read two columns as one: refused, naming the file and
        // the options to give.
        (
            &two,
            &["--record-dt", "0.01"][..],
            &[
                "--records: ",
                "two.dat line",
                "every line of numbers holds 2 values",
                "give --record-format two-column without --record-dt",
            ][..],
        ),
        (
            &two,
            &["--record-format", "two-column", "--record-dt", "0.01"][..],
            &["--record-dt 0.01", "not --record-format two-column"][..],
        ),
        (
            &two,
            &["--record-format", "at2", "--record-dt", "0.01"][..],
            &["--record-dt 0.01", "not --record-format at2"][..],
        ),
        (
            &one,
            &["--record-format", "one-column", "--record-dt", "0"][..],
            &["--record-dt 0", "> 0"][..],
        ),
    ] {
        let (o, out) = run("bad", rec, extra);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{extra:?}: {err}");
        for e in expect {
            assert!(err.contains(e), "{extra:?}: {e:?} not in {err}");
        }
        assert!(
            !err.contains("ground_motion"),
            "{extra:?}: a --records file is not blamed on a scene key: {err}"
        );
        assert!(!out.exists(), "{extra:?}: nothing written");
    }
    // A table that fails for another reason (uneven times) is told that reason, not that it
    // holds one value per line.
    let uneven = d.write("uneven.dat", "0 0.1\n0.01 0.2\n0.03 0.1\n0.04 0.0\n");
    let (o, out) = run("uneven", &uneven, &[]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        err.contains("--records: ") && err.contains("uneven.dat"),
        "{err}"
    );
    assert!(!err.contains("one value per line"), "{err}");
    assert!(!out.exists());
    // A bad --record-dt with an AT2 file among the records: the advice to remove
    // --record-dt, whatever the files' order (it was the first file's refusal).
    let at2 = d.write(
        "cap.AT2",
        &std::fs::read_to_string(format!(
            "{studies}/../data/ground-motions/RSN752_LOMAP_CAP000.AT2"
        ))
        .unwrap(),
    );
    for (name, records) in [("at2-first", [&at2, &one]), ("at2-last", [&one, &at2])] {
        let out = d.path(name);
        let mut extra = vec!["--records"];
        extra.extend(records.iter().map(|r| r.to_str().unwrap()));
        extra.extend(["--record-dt", "-1"]);
        let o = common::quick_run_with("modes", &studies, out.to_str().unwrap(), &extra);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{name}: {err}");
        assert!(
            err.contains("--record-dt -1: ")
                && err.contains("cap.AT2 is read as a PEER AT2 record")
                && err.contains("remove --record-dt"),
            "{name}: {err}"
        );
        assert!(!out.exists(), "{name}");
    }
    // A study scene of one's own whose record is one-column (`format`, `dt`): --records
    // files are read as the options (here none: by their names) say, not in its format.
    let own = TempDir::new("recformat-own");
    own.write("own.txt", &std::fs::read_to_string(&one).unwrap());
    let scene = std::fs::read_to_string(format!("{studies}/paper/scene.toml"))
        .unwrap()
        .replace(
            "file = \"../../data/ground-motions/RSN752_LOMAP_CAP000.AT2\"",
            "file = \"own.txt\"\nformat = \"one-column\"\ndt = 0.01\nunits = \"g\"",
        );
    assert!(scene.contains("own.txt"));
    own.write("own.toml", &scene);
    let def = std::fs::read_to_string(format!("{studies}/modes.toml"))
        .unwrap()
        .replace("scene = \"paper/scene.toml\"", "scene = \"own.toml\"")
        .replace("\"../data/", &format!("\"{studies}/../data/"));
    own.write("modes.toml", &def);
    let out = own.path("out");
    let o = quick_with_records("modes", own.0.to_str().unwrap(), &out, &[&two]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    // The same peaks as the paper scene with the same file (case ids differ: the scene).
    assert_eq!(peaks(&out), peaks(&out2));
    // Without --records the record options are a usage error.
    let o = pound(&["studies", "run", "modes", "--record-format", "at2"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("--records"));
}

/// Every `--records` file is read before anything runs, also with `--quick` (whose cases use
/// the first record only): a one-column file given second without `--record-format` is
/// refused up front, naming it (exit 2, nothing written), as it is given first; an AT2 file
/// whose header is broken, likewise.
#[test]
fn every_user_record_is_read_before_the_sweep() {
    let d = TempDir::new("recs-all-read");
    let (one, two) = sine_records(&d, 0.0, "two.txt");
    let bad_at2 = d.write("broken.AT2", "PEER\nno header\n");
    let studies = studies_dir();
    for (k, recs, named) in [
        (0, [&two, &one], "one.txt"),
        (1, [&one, &two], "one.txt"),
        (2, [&two, &bad_at2], "broken.AT2"),
    ] {
        let out = d.path(&format!("out{k}"));
        let o = quick_with_records("gap", &studies, &out, &[recs[0], recs[1]]);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{recs:?}: {err}");
        assert!(
            err.contains("--records: ") && err.contains(named),
            "{recs:?}: {err}"
        );
        assert!(!out.exists(), "{recs:?}: nothing written");
        assert!(o.stdout.is_empty());
    }
    // Both readable: the sweep runs (on the first only, --quick).
    let other = d.write("other.txt", &std::fs::read_to_string(&two).unwrap());
    let out = d.path("ok");
    let o = quick_with_records("gap", &studies, &out, &[&two, &other]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
}

/// Runs `pound studies run <study> --quick` on the repository's definition with the line
/// starting `<key> =` replaced by `line` (paths made absolute) and `extra` arguments, and
/// checks the bad-input contract: exit 2, every fragment of `expect` on stderr, nothing on
/// stdout, no output folder.
#[track_caller]
fn definition_refused(study: &str, key: &str, line: &str, extra: &[&str], expect: &[&str]) {
    let studies = studies_dir();
    let d = TempDir::new("refused-def");
    let def: String = std::fs::read_to_string(format!("{studies}/{study}.toml"))
        .unwrap()
        .lines()
        .map(|l| {
            if l.starts_with(&format!("{key} =")) {
                line.to_string()
            } else {
                l.replace("\"../data/", &format!("\"{studies}/../data/"))
                    .replace("\"paper/", &format!("\"{studies}/paper/"))
            }
        })
        .collect::<Vec<_>>()
        .join("\n");
    assert!(def.contains(line), "{study}.toml has no `{key} =` line");
    d.write(&format!("{study}.toml"), &def);
    let out = d.path("out");
    let mut args = vec![
        "studies",
        "run",
        study,
        "--quick",
        "--studies-dir",
        d.0.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ];
    args.extend(extra);
    let o = pound(&args);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{study} {line}: {err}");
    assert!(!err.contains("panicked"), "{err}");
    for e in expect {
        assert!(err.contains(e), "{study} {line}: {e:?} not in {err}");
    }
    assert!(o.stdout.is_empty(), "{study} {line}: nothing on stdout");
    assert!(!out.exists(), "{study} {line}: nothing written");
}

/// Study values that cannot make a grid (empty lists, counts below what the tables need, a
/// stiffness range through zero) are bad input: exit 2 naming the key, nothing written. They
/// used to panic (index out of bounds, exit 101) after writing part of the results.
#[test]
fn empty_or_degenerate_study_grids_are_refused() {
    for (study, key, line, expect) in [
        (
            "stiffness",
            "stiffness_count",
            "stiffness_count = 0",
            "at least 2",
        ),
        (
            "stiffness",
            "stiffness_min",
            "stiffness_min = 0.0",
            "0 < min < max",
        ),
        ("gap", "gap_count", "gap_count = 0", "at least 2"),
        ("modes", "max_modes", "max_modes = 0", "at least 5"),
        (
            "restitution",
            "restitution",
            "restitution = []",
            "at least one c_r",
        ),
        ("robustness", "gaps", "gaps = []", "at least one gap"),
        (
            "robustness",
            "record_dirs",
            "record_dirs = []",
            "no *.AT2 record",
        ),
        (
            "robustness",
            "restitution",
            "restitution = [1.5]",
            "in [0, 1]",
        ),
        (
            "robustness",
            "record_dirs",
            "record_dirs = [\"no-such-folder\"]",
            "cannot be listed",
        ),
    ] {
        definition_refused(study, key, line, &[], &[&format!("`{key}`"), expect]);
    }
}

/// A damping ratio of a study definition outside 0 <= ζ < 1 (the paper study's spectrum,
/// the gap study's CQC correlation) is bad input: exit 2 naming the key and the range,
/// nothing written. They used to run (ζ >= 1 is not an underdamped oscillator).
#[test]
fn study_damping_ratios_outside_0_to_1_are_refused() {
    for (study, key, line) in [
        ("paper", "spectrum_damping", "spectrum_damping = 1.0"),
        ("paper", "spectrum_damping", "spectrum_damping = 1.5"),
        ("paper", "spectrum_damping", "spectrum_damping = -0.05"),
        ("gap", "damping", "damping = -0.05"),
        ("gap", "damping", "damping = 1.0"),
    ] {
        definition_refused(
            study,
            key,
            line,
            &[],
            &[&format!("`{key}`"), "0 <= ζ < 1", &format!("{study}.toml")],
        );
    }
}

/// A study value that the scene refuses in some of the study's cases but not in its first
/// (the robustness study's first case is the momentum method, which takes no gap-element
/// value) is refused before the sweep: exit 2 naming the case, the scene key and the
/// override, nothing written. It used to sweep through the failed cases and exit 4.
#[test]
fn a_value_refused_in_any_case_is_refused_before_the_sweep() {
    definition_refused(
        "robustness",
        "gap_stiffness",
        "gap_stiffness = 0.0",
        &[],
        &[
            "study `robustness`",
            "robustness.toml",
            "gap adaptive",
            "key `gap_element.stiffness`",
            "expected a stiffness > 0",
            "gap_element.stiffness=0e0",
        ],
    );
    definition_refused(
        "robustness",
        "newmark_time_step",
        "newmark_time_step = 0.0",
        &[],
        &[
            "gap newmark",
            "key `gap_element.time_step`",
            "expected a step > 0",
        ],
    );
    // A Newmark step that fits the first record's step (0.005 s) but not the second's
    // (0.0024 s): only the cases on the second record are refused.
    let rec = |f: &str| format!("{}/../data/ground-motions/{f}", studies_dir());
    let (first, second) = (
        rec("RSN752_LOMAP_CAP000.AT2"),
        rec("near-field/RSN292_ITALY-A-STU_223.AT2"),
    );
    definition_refused(
        "robustness",
        "newmark_time_step",
        "newmark_time_step = 0.003",
        &["--records", &first, &second],
        &[
            "gap newmark, record ITALY-A-STU_223",
            "key `gap_element.time_step`",
            "record's step (0.0024 s)",
        ],
    );
}
