//! Sweep engine: thread-count independence, shard + merge = single run, resume, failed cases.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use studies::studies::{merge, run_study, RunConfig, StudyOptions};
use studies::sweep::{run_cases, CaseSpec, EngineOptions, Shard};

fn studies_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../studies")
}

/// Engine options for `run_cases` on 2 threads, cases written under `study_dir`.
fn engine(study_dir: PathBuf, fresh: bool) -> EngineOptions {
    EngineOptions {
        study_dir,
        studies_dir: studies_dir(),
        threads: Some(2),
        shard: None,
        progress: false,
        fresh,
    }
}

fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("pound-sweep-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    d
}

fn cfg(out: &Path, threads: usize, shard: Option<Shard>) -> RunConfig {
    RunConfig {
        out: out.to_path_buf(),
        studies_dir: studies_dir(),
        threads: Some(threads),
        shard,
        opts: StudyOptions {
            quick: true,
            records: vec![],
            ..Default::default()
        },
        progress: false,
        fresh: false,
    }
}

/// Every deterministic output file of a study (not the case files, not wall times).
fn outputs(dir: &Path) -> BTreeMap<String, Vec<u8>> {
    let mut m = BTreeMap::new();
    for e in std::fs::read_dir(dir).unwrap() {
        let p = e.unwrap().path();
        let name = p.file_name().unwrap().to_string_lossy().into_owned();
        if p.is_dir() || name.starts_with("cases") || name.contains("cpu") || name.starts_with('.')
        {
            continue;
        }
        m.insert(name, std::fs::read(&p).unwrap());
    }
    m
}

#[test]
fn thread_count_does_not_change_outputs() {
    let (a, b) = (tmp("t1"), tmp("t2"));
    run_study("stiffness", &cfg(&a, 1, None)).unwrap();
    run_study("stiffness", &cfg(&b, 2, None)).unwrap();
    let (oa, ob) = (outputs(&a.join("stiffness")), outputs(&b.join("stiffness")));
    assert!(oa.contains_key("stiffness.png") && oa.contains_key("summary.md"));
    assert_eq!(oa.keys().collect::<Vec<_>>(), ob.keys().collect::<Vec<_>>());
    for (k, v) in &oa {
        assert!(v == &ob[k], "{k} differs between 1 and 2 threads");
    }
}

#[test]
fn shards_merged_equal_a_single_run() {
    let (single, s1, s2, merged) = (tmp("single"), tmp("s1"), tmp("s2"), tmp("merged"));
    run_study("gap", &cfg(&single, 2, None)).unwrap();
    let r1 = run_study("gap", &cfg(&s1, 1, Some(Shard { index: 1, count: 2 }))).unwrap();
    let r2 = run_study("gap", &cfg(&s2, 1, Some(Shard { index: 2, count: 2 }))).unwrap();
    assert!(!r1.reported && r1.summary.ran > 0 && r2.summary.ran > 0);
    assert_eq!(r1.summary.ran + r2.summary.ran, r1.summary.total);
    // One shard alone is incomplete: merge names the missing cases.
    let err = merge(std::slice::from_ref(&s1), &tmp("partial"), &studies_dir()).unwrap_err();
    assert!(err.to_string().contains("missing ids"), "{err}");
    merge(&[s1, s2], &merged, &studies_dir()).unwrap();
    let (a, b) = (outputs(&single.join("gap")), outputs(&merged.join("gap")));
    assert!(a.contains_key("gap.csv"));
    for (k, v) in &a {
        assert!(
            b.get(k) == Some(v),
            "{k} differs between single run and merged shards"
        );
    }
}

#[test]
fn resume_skips_finished_cases() {
    let out = tmp("resume");
    let first = run_study("modes", &cfg(&out, 2, None)).unwrap();
    assert!(first.summary.ran > 0 && first.summary.skipped == 0);
    let again = run_study("modes", &cfg(&out, 2, None)).unwrap();
    assert_eq!(again.summary.ran, 0);
    assert_eq!(again.summary.skipped, first.summary.total);
    // Remove one case file: only that case runs again.
    let cases = out.join("modes").join("cases");
    let one = std::fs::read_dir(&cases)
        .unwrap()
        .next()
        .unwrap()
        .unwrap()
        .path();
    std::fs::remove_file(one).unwrap();
    let third = run_study("modes", &cfg(&out, 2, None)).unwrap();
    assert_eq!(third.summary.ran, 1);
    // --fresh recomputes every case and removes case files the study does not name.
    let stale = cases.join("0000000000000000.json");
    std::fs::write(&stale, "{}").unwrap();
    let fresh = run_study(
        "modes",
        &RunConfig {
            fresh: true,
            ..cfg(&out, 2, None)
        },
    )
    .unwrap();
    assert_eq!(fresh.summary.ran, first.summary.total);
    assert!(!stale.exists());
}

#[test]
fn failing_cases_become_rows() {
    let out = tmp("fail");
    let base = CaseSpec::new("paper/scene.toml", solvers::Method::Momentum)
        .with("contacts.0.restitution", "0.5")
        .with("analysis.duration", "10.0");
    let storm = base.clone().with("momentum.persistent_contact", "false");
    let bad = base.clone().with("contacts.0.restitution", "1.5");
    let specs = vec![base.clone(), storm.clone(), bad.clone()];
    let opts = engine(out.clone(), false);
    let s = run_cases(&specs, &opts).unwrap();
    assert_eq!((s.ran, s.failed), (3, 2));
    let res = studies::sweep::collect("t", &specs, &out).unwrap();
    assert_eq!(res.get(&base).status, "ok");
    assert_eq!(res.get(&storm).error_kind.as_deref(), Some("Stalled"));
    assert_eq!(res.get(&bad).error_kind.as_deref(), Some("Scene"));
    assert!(res
        .get(&bad)
        .error
        .as_ref()
        .unwrap()
        .contains("restitution"));
    studies::sweep::write_cases_table(&out, &res).unwrap();
    let csv = std::fs::read_to_string(out.join("cases.csv")).unwrap();
    assert_eq!(csv.lines().count(), 4);
    assert!(csv.contains("Stalled"));
}

/// Timed cases (`repeat` > 1) run alone, after the others, in case order; the others run in
/// parallel. A mixed list runs to completion with every case written, timed ones included.
#[test]
fn timed_cases_run_alone_after_the_others() {
    let base = CaseSpec::new("paper/scene.toml", solvers::Method::Momentum)
        .with("analysis.duration", "2.0");
    let t1 = base.clone().with("contacts.0.gap", "0.05").repeat(3);
    let u1 = base.clone().with("contacts.0.gap", "0.06");
    let t2 = base.clone().with("contacts.0.gap", "0.07").repeat(2);
    let u2 = base.clone().with("contacts.0.gap", "0.08");
    let specs = vec![t1.clone(), u1.clone(), t2.clone(), u2.clone()];
    let refs: Vec<&CaseSpec> = specs.iter().collect();
    let (parallel, alone) = studies::sweep::schedule(&refs);
    let ids = |v: &[&CaseSpec]| v.iter().map(|s| s.id.clone()).collect::<Vec<_>>();
    assert_eq!(ids(&parallel), vec![u1.id.clone(), u2.id.clone()]);
    assert_eq!(ids(&alone), vec![t1.id.clone(), t2.id.clone()]);
    let out = tmp("timed");
    let opts = engine(out.clone(), true);
    let s = run_cases(&specs, &opts).unwrap();
    assert_eq!((s.ran, s.failed), (4, 0));
    let res = studies::sweep::collect("t", &specs, &out).unwrap();
    assert_eq!(res.get(&t1).wall_seconds_all.len(), 3);
    assert_eq!(res.get(&u1).wall_seconds_all.len(), 1);
    // The timed cases ran in rounds (t1, t2, t1, t2, t1), each with the outputs of one
    // analysis run alone.
    assert_eq!(studies::sweep::rounds(&[3, 2]), vec![0, 1, 0, 1, 0]);
    assert_eq!(studies::sweep::rounds(&[2, 3, 1]), vec![0, 1, 2, 0, 1, 1]);
    assert_eq!(studies::sweep::rounds(&[0, 1]), vec![0, 1]);
    assert!(studies::sweep::rounds(&[]).is_empty());
    for t in [&t1, &t2] {
        let alone = studies::sweep::run_case(&t.clone().repeat(1), &studies_dir());
        assert_eq!(res.get(t).outputs, alone.outputs);
        let w = &res.get(t).wall_seconds_all;
        assert_eq!(
            res.get(t).wall_seconds,
            w.iter().copied().fold(f64::INFINITY, f64::min)
        );
    }
}

/// A timed case that fails is written once, with its error, and not run again; the other
/// timed cases run all their repeats.
#[test]
fn failing_timed_cases_stop_at_their_failure() {
    let base = CaseSpec::new("paper/scene.toml", solvers::Method::Momentum)
        .with("contacts.0.restitution", "0.5")
        .with("analysis.duration", "10.0");
    let storm = base
        .clone()
        .with("momentum.persistent_contact", "false")
        .repeat(3);
    let bad = base.clone().with("contacts.0.restitution", "1.5").repeat(2);
    let good = base.clone().repeat(2);
    let specs = vec![storm.clone(), bad.clone(), good.clone()];
    let out = tmp("timed-fail");
    let s = run_cases(&specs, &engine(out.clone(), true)).unwrap();
    assert_eq!((s.ran, s.failed), (3, 2));
    let res = studies::sweep::collect("t", &specs, &out).unwrap();
    assert_eq!(res.get(&storm).error_kind.as_deref(), Some("Stalled"));
    assert_eq!(res.get(&storm).wall_seconds_all.len(), 1);
    assert_eq!(res.get(&bad).error_kind.as_deref(), Some("Scene"));
    assert_eq!(res.get(&good).status, "ok");
    assert_eq!(res.get(&good).wall_seconds_all.len(), 2);
}

/// A Slurm job array gives the shard; variables that are there but do not give one (not
/// numbers, an id out of range, sparse or stepped arrays) are errors, not a whole sweep.
#[test]
fn slurm_array_variables_give_a_shard_or_an_error() {
    let env = |pairs: &'static [(&'static str, &'static str)]| {
        move |k: &str| {
            pairs
                .iter()
                .find(|(a, _)| *a == k)
                .map(|(_, v)| v.to_string())
        }
    };
    assert_eq!(Shard::from_env(env(&[])), Ok(None));
    assert_eq!(
        Shard::from_env(env(&[
            ("SLURM_ARRAY_TASK_ID", "3"),
            ("SLURM_ARRAY_TASK_COUNT", "4")
        ])),
        Ok(Some(Shard { index: 3, count: 4 }))
    );
    // An array 0-3: ids mapped to 1 … 4.
    assert_eq!(
        Shard::from_env(env(&[
            ("SLURM_ARRAY_TASK_ID", "0"),
            ("SLURM_ARRAY_TASK_COUNT", "4"),
            ("SLURM_ARRAY_TASK_MIN", "0"),
            ("SLURM_ARRAY_TASK_MAX", "3"),
            ("SLURM_ARRAY_TASK_STEP", "1")
        ])),
        Ok(Some(Shard { index: 1, count: 4 }))
    );
    for (bad, says) in [
        (
            &[
                ("SLURM_ARRAY_TASK_ID", "abc"),
                ("SLURM_ARRAY_TASK_COUNT", "4"),
            ][..],
            "not a whole number",
        ),
        (
            &[
                ("SLURM_ARRAY_TASK_ID", "5"),
                ("SLURM_ARRAY_TASK_COUNT", "4"),
            ][..],
            "outside",
        ),
        (
            &[("SLURM_ARRAY_TASK_ID", "2")][..],
            "SLURM_ARRAY_TASK_COUNT is not",
        ),
        (
            &[
                ("SLURM_ARRAY_TASK_ID", "3"),
                ("SLURM_ARRAY_TASK_COUNT", "3"),
                ("SLURM_ARRAY_TASK_MIN", "1"),
                ("SLURM_ARRAY_TASK_MAX", "5"),
            ][..],
            "sparse",
        ),
        (
            &[
                ("SLURM_ARRAY_TASK_ID", "3"),
                ("SLURM_ARRAY_TASK_COUNT", "8"),
                ("SLURM_ARRAY_TASK_STEP", "2"),
            ][..],
            "stepped",
        ),
    ] {
        let e = Shard::from_env(env(bad)).unwrap_err();
        assert!(e.contains(says), "{e}");
    }
}

#[test]
fn case_ids_are_stable() {
    let a = CaseSpec::new("paper/scene.toml", solvers::Method::Gap)
        .with("b", 2)
        .with("a", 1);
    let b = CaseSpec::new("paper/scene.toml", solvers::Method::Gap)
        .with("a", 1)
        .with("b", 2);
    assert_eq!(a.id, b.id);
    assert_eq!(a.id.len(), 16);
    assert_ne!(a.id, a.clone().with("a", 3).id);
}

fn csv_header(path: &std::path::Path) -> Vec<String> {
    let text = std::fs::read_to_string(path).unwrap();
    text.lines()
        .next()
        .unwrap()
        .split(',')
        .map(String::from)
        .collect()
}

/// The data tables are tidy: one name per column, the same columns whether the cases
/// finish or all fail, and the per-story peaks in a long table with the buildings' names
/// and the amplification over the case's run without contact.
#[test]
fn data_tables_are_tidy() {
    let (ok_dir, bad_dir) = (tmp("tidy_ok"), tmp("tidy_bad"));
    // 8 s: the roofs first meet at 6.67 s, so the amplifications are not all 1.
    let base = CaseSpec::new("paper/scene.toml", solvers::Method::Momentum)
        .with("analysis.duration", "8.0")
        .param("variant", "momentum")
        .param("record", "CAP000")
        .param("gap_m", 0.1);
    let bad = base.clone().with("contacts.0.restitution", "1.5");
    let run = |dir: &std::path::PathBuf, specs: Vec<CaseSpec>| {
        let opts = engine(dir.clone(), true);
        run_cases(&specs, &opts).unwrap();
        let res = studies::sweep::collect("t", &specs, dir).unwrap();
        studies::sweep::write_cases_table(dir, &res).unwrap();
    };
    run(&ok_dir, vec![base.clone(), base.baseline()]);
    run(&bad_dir, vec![bad]);
    let (h_ok, h_bad) = (
        csv_header(&ok_dir.join("cases.csv")),
        csv_header(&bad_dir.join("cases.csv")),
    );
    assert_eq!(h_ok, h_bad, "the schema does not depend on success");
    let mut unique = h_ok.clone();
    unique.sort();
    unique.dedup();
    assert_eq!(unique.len(), h_ok.len(), "one name per column: {h_ok:?}");
    for dimensional in [
        "peak_closure_m",
        "energy_input_J",
        "wall_s",
        "pga_g",
        "gap_m",
    ] {
        assert!(
            h_ok.iter().any(|h| h == dimensional),
            "{dimensional} in {h_ok:?}"
        );
    }
    assert_eq!(
        csv_header(&ok_dir.join("peaks.csv")),
        [
            "case_id",
            "building",
            "story",
            "story_shear_max_N",
            "floor_displacement_max_m",
            "amplification",
            "story_drift_max_m",
            "residual_drift_m"
        ]
    );
    let peaks = std::fs::read_to_string(ok_dir.join("peaks.csv")).unwrap();
    let rows: Vec<Vec<&str>> = peaks
        .lines()
        .skip(1)
        .map(|l| l.split(',').collect())
        .collect();
    // 2 cases × 2 buildings × 15 stories; the baseline has no amplification of its own.
    assert_eq!(rows.len(), 60);
    let with: Vec<&Vec<&str>> = rows.iter().filter(|r| r[0] == base.id).collect();
    assert_eq!(with.len(), 30);
    assert!(with.iter().any(|r| r[1] == "building2" && r[2] == "15"));
    // The amplification is the case's peak story shear over its baseline's, story by story
    // (both printed in full precision); the impacts make some of them differ from 1.
    let baseline: Vec<&Vec<&str>> = rows.iter().filter(|r| r[0] != base.id).collect();
    assert_eq!(baseline.len(), 30);
    let mut not_one = 0;
    for (r, b) in with.iter().zip(&baseline) {
        assert_eq!((r[1], r[2]), (b[1], b[2]));
        let a: f64 = r[5].parse().unwrap();
        let (v, v0): (f64, f64) = (r[3].parse().unwrap(), b[3].parse().unwrap());
        assert!(
            (a - v / v0).abs() <= 4.0 * f64::EPSILON * a,
            "{a} vs {v} / {v0}"
        );
        not_one += usize::from((a - 1.0).abs() > 1e-6);
    }
    assert!(not_one > 0, "no story amplified: the case does not pound");
    // A story's peak drift is at most the peak displacement of the floor above it plus that
    // of the floor below (|u_j − u_{j−1}| ≤ |u_j| + |u_{j−1}|, u_0 = 0), and above 0.
    for pair in with.windows(2) {
        let (below, r) = (pair[0], pair[1]);
        let d: f64 = r[6].parse().unwrap();
        let up: f64 = r[4].parse().unwrap();
        let down: f64 = if r[2] == "1" {
            0.0
        } else {
            below[4].parse().unwrap()
        };
        assert!(
            d > 0.0 && d <= (up + down) * (1.0 + 1e-12),
            "drift {d} of {r:?}"
        );
    }
    let failed = std::fs::read_to_string(bad_dir.join("peaks.csv")).unwrap();
    assert_eq!(failed.lines().count(), 1, "failed cases have no peak rows");
}

/// A baseline is the model without any contact, even when the scene file has several
/// contact entries (the case's override only names entry 0).
#[test]
fn baseline_has_no_active_contact_with_several_contact_entries() {
    let dir = tmp("baseline-two-contacts");
    std::fs::create_dir_all(&dir).unwrap();
    let scene = dir.join("two.toml");
    std::fs::write(
        &scene,
        r#"
[[buildings]]
name = "a"
masses = [1.0e5, 1.0e5]
story_stiffness = [4.0e7, 4.0e7]
initial_velocity = [0.5, 1.0]
[[buildings]]
name = "b"
masses = [1.0e5, 1.0e5]
story_stiffness = [5.0e7, 5.0e7]
[[contacts]]
left = "a"
left_floor = 2
right = "b"
right_floor = 2
gap = 0.01
[[contacts]]
left = "a"
left_floor = 1
right = "b"
right_floor = 1
gap = 0.01
[analysis]
duration = 3.0
"#,
    )
    .unwrap();
    let case = CaseSpec::new(scene.to_str().unwrap(), solvers::Method::Momentum);
    let with_contact = studies::sweep::run_case(&case, &dir);
    assert!(with_contact.ok().unwrap().impacts > 0, "the scene pounds");
    let base = studies::sweep::run_case(&case.baseline(), &dir);
    let o = base.ok().expect("baseline runs");
    assert_eq!(o.impacts, 0, "baseline of a two-contact scene still pounds");
}
