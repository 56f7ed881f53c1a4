//! Inputs that used to give a wrong number with exit 0 (issue 12): a two-column file read
//! as one column, AT2 units ignored, conflicting record options, damping lists of the wrong
//! length, a clamped mode count, a Newmark step that skips the record, and error messages
//! that leaked internals, dropped array indices, doubled OS errors or called a directory
//! missing.

mod common;
use common::{pound, TempDir};

const AT2: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/../../data/ground-motions/RSN752_LOMAP_CAP000.AT2"
);

fn scene() -> String {
    concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../studies/paper/scene.toml"
    )
    .to_string()
}

/// `pound run` of the paper scene with the momentum method over its first second, without
/// the baseline run, and `extra` arguments.
fn paper_momentum(extra: &[&str]) -> std::process::Output {
    let s = scene();
    let mut a = vec![
        "run",
        s.as_str(),
        "--method",
        "momentum",
        "--no-baseline",
        "--set",
        "analysis.duration=1",
    ];
    a.extend_from_slice(extra);
    pound(&a)
}

/// Runs pound, expects exit 2 with every fragment on stderr, nothing on stdout.
#[track_caller]
fn refused(args: &[&str], expect: &[&str]) -> String {
    let o = pound(args);
    let err = String::from_utf8_lossy(&o.stderr).into_owned();
    assert_eq!(o.status.code(), Some(2), "pound {args:?}: {err}");
    assert!(!err.contains("panicked"), "{err}");
    for e in expect {
        assert!(err.contains(e), "stderr should contain {e:?}: {err}");
    }
    assert!(o.stdout.is_empty());
    err
}

fn two_column(d: &TempDir) -> std::path::PathBuf {
    let mut text = String::new();
    for i in 0..200 {
        text.push_str(&format!(
            "{:.2} {:.4}\n",
            i as f64 * 0.01,
            0.1 * ((i % 7) as f64 - 3.0)
        ));
    }
    d.write("two.txt", &text)
}

#[test]
fn two_column_file_is_not_read_as_one_column() {
    let d = TempDir::new("twocol");
    let f = two_column(&d);
    let f = f.to_str().unwrap();
    for cmd in ["record", "spectrum"] {
        refused(&[cmd, f, "--dt", "0.01"], &["two.txt line 1", "two-column"]);
        refused(
            &[cmd, f, "--format", "one-column", "--dt", "0.01"],
            &["two.txt line 1", "two-column"],
        );
    }
    refused(
        &["record", f, "--format", "two-column", "--dt", "0.01"],
        &["--dt", "time column"],
    );
    // Read as what it is, its PGA is that of the second column: 0.3 g.
    let o = pound(&["record", f, "--json"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert!((v["pga_g"].as_f64().unwrap() - 0.3).abs() < 1e-12, "{v}");
}

#[test]
fn at2_units_come_from_the_header() {
    let d = TempDir::new("at2units");
    let text = std::fs::read_to_string(AT2).unwrap();
    let g: serde_json::Value =
        serde_json::from_slice(&pound(&["record", AT2, "--json"]).stdout).unwrap();
    let pga_g = g["pga_g"].as_f64().unwrap();
    for (units, factor) in [
        ("CM/S/S", 0.01 / structure::G),
        ("CM/SEC/SEC", 0.01 / structure::G),
        ("GAL", 0.01 / structure::G),
        ("M/S/S", 1.0 / structure::G),
        ("G", 1.0),
    ] {
        let mut lines: Vec<&str> = text.lines().collect();
        let l3 = format!("ACCELERATION TIME SERIES IN UNITS OF {units}");
        lines[2] = &l3;
        let f = d.write("u.AT2", &(lines.join("\n") + "\n"));
        let o = pound(&["record", f.to_str().unwrap(), "--json"]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
        let got = v["pga_g"].as_f64().unwrap();
        assert!(
            (got / (pga_g * factor) - 1.0).abs() < 1e-12,
            "{units}: {got}"
        );
    }
    let mut lines: Vec<&str> = text.lines().collect();
    lines[2] = "ACCELERATION TIME SERIES IN UNITS OF FURLONGS/FORTNIGHT";
    let f = d.write("bad.AT2", &(lines.join("\n") + "\n"));
    refused(
        &["record", f.to_str().unwrap()],
        &["bad.AT2 line 3", "UNITS OF G"],
    );
    // --units agreeing with the header is harmless; contradicting it or --dt is refused.
    assert!(pound(&["record", AT2, "--units", "g"]).status.success());
    refused(
        &["record", AT2, "--units", "cm/s^2"],
        &["--units", "line 3", "g"],
    );
    refused(&["record", AT2, "--dt", "0.01"], &["--dt", "line 4"]);
}

#[test]
fn scene_values_that_used_to_be_repeated_clamped_or_skipped() {
    let s = scene();
    refused(
        &[
            "run",
            &s,
            "--method",
            "momentum",
            "--set",
            "buildings.1.damping_ratio=[0.05, 0.02]",
        ],
        &[
            "buildings[1].damping_ratio",
            "2 ratios",
            "15 floors",
            "one ratio per mode",
        ],
    );
    refused(
        &[
            "run",
            &s,
            "--method",
            "gap",
            "--set",
            "gap_element.integrator=newmark",
            "--set",
            "gap_element.time_step=10",
        ],
        &["gap_element.time_step", "0.005"],
    );
    // A mode count above the floors is clamped, as users expect, and said on stderr.
    let o = paper_momentum(&["--set", "momentum.modes=99"]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    assert!(
        err.contains("momentum.modes = 99 exceeds the 15 modes of building1: all 15 kept"),
        "{err}"
    );
}

#[test]
fn messages_name_keys_with_indices_and_no_internals() {
    let s = scene();
    let e = refused(
        &[
            "run",
            &s,
            "--method",
            "momentum",
            "--set",
            "buildings.0.mass=abc",
        ],
        &["buildings[0].mass"],
    );
    assert!(!e.contains("`buildings.mass`"), "{e}");
    let e = refused(
        &[
            "run",
            &s,
            "--method",
            "momentum",
            "--set",
            "buildings.1.damping_ratio=abc",
        ],
        &[
            "buildings[1].damping_ratio",
            "a number or a list of numbers",
        ],
    );
    assert!(
        !e.contains("untagged") && !e.contains("ScalarOrList"),
        "{e}"
    );
    let e = refused(
        &["run", &s, "--method", "momentum", "--set", "contacts.0=5"],
        &["contacts[0]", "a contact table with keys left, left_floor"],
    );
    assert!(!e.contains("RawContact"), "{e}");
    let e = refused(
        &[
            "run",
            &s,
            "--method",
            "momentum",
            "--set",
            "ground_motion.pga=1e400",
        ],
        &["1e400", "out of the range"],
    );
    assert!(!e.contains("invalid type: string"), "{e}");
    let d = TempDir::new("msgs");
    let f = d.write(
        "list.toml",
        "[[buildings]]\nname = \"a\"\nmasses = [1e5, 1e5]\nstory_stiffness = \"lots\"\n[analysis]\nduration = 1\n",
    );
    let e = refused(
        &["run", f.to_str().unwrap(), "--method", "momentum"],
        &["line 4", "a number or a list of numbers"],
    );
    assert!(!e.contains("untagged"), "{e}");
}

#[test]
fn directories_and_os_errors() {
    let d = TempDir::new("dirs");
    let dir = d.0.to_str().unwrap();
    refused(&["run", dir, "--method", "momentum"], &["is a directory"]);
    refused(&["record", dir], &["is a directory"]);
    let f = d.write(
        "s.toml",
        &format!("[[buildings]]\nname = \"a\"\nmasses = [1e5, 1e5]\nstory_stiffness = 1e8\n[ground_motion]\nfile = \"{dir}\"\n"),
    );
    let e = refused(
        &["run", f.to_str().unwrap(), "--method", "momentum"],
        &["is a directory"],
    );
    assert!(!e.contains("does not exist"), "{e}");
    let e = refused(&["record", "/no/such/file.AT2"], &["no such file"]);
    assert_eq!(e.matches("os error").count(), 0, "{e}");
    // An output that cannot be written: the OS error once.
    let o = paper_momentum(&["--out", "/proc/pound-cannot-write.json"]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert_eq!(err.matches("os error").count(), 1, "{err}");
}

#[test]
fn modes_of_a_structure_alone() {
    // `pound modes` needs neither a record nor a duration (it used to refuse
    // `analysis.duration: missing`); `pound run` of the same scene still needs one.
    // Uniform shear building, n = 3, m = 1e5 kg, k = 1e8 N/m:
    // ω_j = 2 √(k/m) sin((2j − 1)π / (2(2n + 1))).
    let d = TempDir::new("modes-alone");
    let f = d.write(
        "s.toml",
        "[[buildings]]\nname = \"A\"\nstories = 3\nmass = 1e5\nstory_stiffness = 1e8\n",
    );
    let f = f.to_str().unwrap();
    let o = pound(&["modes", f, "--json"]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let text = v.to_string();
    for j in 1..=3 {
        let w =
            2.0 * (1e8_f64 / 1e5).sqrt() * ((2 * j - 1) as f64 * std::f64::consts::PI / 14.0).sin();
        let hz = w / (2.0 * std::f64::consts::PI);
        let found = v["buildings"][0]["frequencies_hz"][j - 1]
            .as_f64()
            .unwrap_or_else(|| panic!("no frequency_hz of mode {j} in {text}"));
        assert!(
            (found / hz - 1.0).abs() < 1e-12,
            "mode {j}: {found} vs {hz}"
        );
    }
    refused(
        &["run", f, "--method", "momentum"],
        &["s.toml", "analysis.duration", "missing"],
    );
}

/// `pound spectrum` periods between 0 and 1e-6 s are refused (at 1e-160 s the spectrum
/// came out NaN: ω² overflows), 0 and 1e-6 s give the PGA, and a spectrum that would not be
/// finite (a record scaled beyond what f64 holds) is refused: no NaN or inf is ever written.
#[test]
fn spectrum_periods_and_results_are_finite() {
    let d = TempDir::new("spectrum-periods");
    let csv = d.path("s.csv");
    let c = csv.to_str().unwrap();
    for periods in ["1e-160", "1e-7,1", "0.5,1e-300"] {
        refused(
            &["spectrum", AT2, "--periods", periods, "--out", c],
            &["--periods", "is not a period", ">= 1e-6 s"],
        );
        assert!(!csv.exists(), "{periods}: nothing written");
    }
    refused(
        &[
            "spectrum",
            AT2,
            "--periods",
            "1e-6,1,1e300",
            "--pga",
            "1e308",
            "--out",
            c,
        ],
        &["RSN752_LOMAP_CAP000.AT2", "not finite", "--pga 1e308"],
    );
    assert!(!csv.exists(), "nothing written");
    let o = pound(&["spectrum", AT2, "--periods", "0,1e-6,0.5,1e300"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let text = String::from_utf8_lossy(&o.stdout);
    let rows: Vec<Vec<f64>> = text
        .lines()
        .skip(1)
        .map(|l| l.split(',').map(|x| x.parse().unwrap()).collect())
        .collect();
    assert_eq!(rows.len(), 4, "{text}");
    for r in &rows {
        assert!(r.iter().all(|x| x.is_finite()), "{text}");
    }
    // Both the rigid limit and the smallest period give the PGA (0.5285 g).
    assert!(
        (rows[0][3] - rows[1][3]).abs() < 1e-6 * rows[0][3],
        "{text}"
    );
    // Periods as written, extreme ones in exponent form (1e300 is not 301 digits).
    let periods: Vec<&str> = text
        .lines()
        .skip(1)
        .map(|l| l.split(',').next().unwrap())
        .collect();
    assert_eq!(periods, ["0", "1e-6", "0.5", "1e300"], "{text}");
}

/// `pound modes` on a pair with a contact at every floor: every contact has its floor's r_N
/// (rising to 1 with all modes), the same in the table and the JSON; the modes of each
/// building are shared by all its contacts.
#[test]
fn modes_of_an_aligned_pair_give_every_contact_its_floors_flexibility() {
    let d = TempDir::new("modes-aligned");
    let f = d.write(
        "s.toml",
        "[[buildings]]\nname = \"A\"\nstories = 12\nmass = 1e5\nstory_stiffness = 1e8\nstory_height = 3.0\n\
         [[buildings]]\nname = \"B\"\nstories = 8\nmass = 2e5\nstory_stiffness = 3e8\nstory_height = 3.0\n\
         [[contacts]]\nleft = \"A\"\nright = \"B\"\nfloors = \"aligned\"\ngap = 0.05\nrestitution = 1.0\n",
    );
    let f = f.to_str().unwrap();
    let o = pound(&["modes", f, "--json"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let contacts = v["contacts"].as_array().unwrap();
    assert_eq!(contacts.len(), 8, "one contact per facing floor");
    let o = pound(&["modes", f]);
    assert!(o.status.success());
    let table = String::from_utf8_lossy(&o.stdout).into_owned();
    let mut floors = Vec::new();
    for (ci, c) in contacts.iter().enumerate() {
        let floor = c["left_floor"].as_u64().unwrap();
        assert_eq!(c["right_floor"].as_u64(), Some(floor));
        floors.push(floor);
        for (side, n) in [("r_n_left", 12), ("r_n_right", 8)] {
            let r: Vec<f64> = c[side]
                .as_array()
                .unwrap()
                .iter()
                .map(|x| x.as_f64().unwrap())
                .collect();
            assert_eq!(r.len(), n, "contact {ci} {side}");
            assert!(r.windows(2).all(|w| w[1] >= w[0] - 1e-12), "{side}: {r:?}");
            assert!((r[n - 1] - 1.0).abs() < 1e-9, "{side}: {r:?}");
        }
        // The table's first row of the contact: N = 1, left and right as printed.
        let head = format!("contact {ci}: A floor {floor} <-> B floor {floor}");
        let at = table
            .find(&head)
            .unwrap_or_else(|| panic!("{head} in {table}"));
        let row = table[at..]
            .lines()
            .find(|l| l.trim_start().starts_with("1 "))
            .unwrap();
        let want = format!(
            "  1   {:8.4} {:8.4}",
            c["r_n_left"][0].as_f64().unwrap(),
            c["r_n_right"][0].as_f64().unwrap()
        );
        assert_eq!(row, want, "contact {ci}");
    }
    floors.sort();
    assert_eq!(floors, (1..=8).collect::<Vec<u64>>());
}

/// Messages that say what to do: a one-column file read as two columns, a record whose PGA
/// is implausible (units), a negative period, a relative record path that does not resolve,
/// an output below a file; and `pound modes` prints no negative zero.
#[test]
fn messages_that_say_what_to_do() {
    let d = TempDir::new("messages");
    let one = d.write("one.txt", "0.1\n0.2\n-0.1\n");
    let one = one.to_str().unwrap();
    refused(
        &["record", one],
        &["one.txt line 1", "one-column record", "dt"],
    );
    // A record in cm/s² read as g: a warning, not an error.
    let mut text = String::new();
    for i in 0..100 {
        text.push_str(&format!(
            "{:.2} {}\n",
            i as f64 * 0.01,
            if i % 2 == 0 { 500 } else { -500 }
        ));
    }
    let cm = d.write("cm.txt", &text);
    let o = pound(&["record", cm.to_str().unwrap()]);
    assert!(o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("500.000 g") && err.contains("--units"),
        "{err}"
    );
    refused(
        &["spectrum", AT2, "--periods", "-1,1"],
        &["--periods: -1", ">= 1e-6 s"],
    );
    refused(&["spectrum", AT2, "--damping", "-0.1"], &["--damping -0.1"]);
    // The paper scene copied elsewhere: its record path is relative to the scene's folder.
    let copy = d.write("scene.toml", &std::fs::read_to_string(scene()).unwrap());
    refused(
        &["run", copy.to_str().unwrap(), "--method", "momentum"],
        &["does not exist", "relative to the scene's folder"],
    );
    // An output path below a file.
    let file = d.write("afile", "");
    let target = file.join("r.json");
    let o = paper_momentum(&["--out", target.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(1));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("afile is a file, not a folder"), "{err}");
    let o = pound(&["modes", &scene()]);
    let table = String::from_utf8_lossy(&o.stdout);
    assert!(
        table.contains("+0.0000") && !table.contains("-0.0000"),
        "{table}"
    );
}

/// A building at rest without ground motion has no story shear without contact: its
/// amplification is undefined, printed as – with a note and written as null, not inf.
#[test]
fn undefined_amplification_is_not_inf() {
    let d = TempDir::new("free-vibration");
    let f = d.write(
        "fv.toml",
        "[[buildings]]\nname = \"a\"\nmasses = [1e5, 1e5]\nstory_stiffness = [1e8, 1e8]\ninitial_velocity = [0.5, 1.0]\n\
         [[buildings]]\nname = \"b\"\nmasses = [1e5, 1e5]\nstory_stiffness = [1e8, 1e8]\n\
         [[contacts]]\nleft = \"a\"\nright = \"b\"\nfloors = \"aligned\"\ngap = 0.01\n[analysis]\nduration = 2.0\n",
    );
    let f = f.to_str().unwrap();
    let o = pound(&["run", f, "--method", "momentum"]);
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(!text.contains("inf") && !text.contains("NaN"), "{text}");
    assert!(
        text.contains("no amplification where the story carries no shear"),
        "{text}"
    );
    let o = pound(&["run", f, "--method", "momentum", "--out", "-"]);
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(
        v["amplification"][1]["story_shear"],
        serde_json::json!([null, null])
    );
    assert!(v["amplification"][0]["story_shear"][0]
        .as_f64()
        .unwrap()
        .is_finite());
}

/// The momentum method's continuous peaks see one sign change of a rate per step: a record
/// step longer than a quarter of the shortest kept period is split, and the result says so
/// (not on the paper scene).
#[test]
fn a_record_step_long_against_the_shortest_period_is_split() {
    let run = |extra: &[&str]| {
        let o = paper_momentum(&[&["--out", "-"], extra].concat());
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
        v["settings"].as_str().unwrap().to_string()
    };
    let plain = run(&[]);
    assert!(
        plain.contains("h = 5.0000e-3 s (2 event-check") && !plain.contains("parts"),
        "{plain}"
    );
    // Stories of 1e12 N/m: shortest period 0.0045 s, record step 0.005 s → 5 parts.
    let split = run(&[
        "--set",
        "buildings.0.target_frequencies_hz=",
        "--set",
        "buildings.0.story_stiffness=1e12",
    ]);
    assert!(
        split.contains("h = 1.0000e-3 s (record step in 5 parts, 2 event-check"),
        "{split}"
    );
}

/// Two buildings whose floors stand at other elevations (`story_height` 3.5 m and 3.0 m):
/// the floors that face the other building mid-story. Free vibration, for `pound run` too.
const MID_STORY: &str = r#"
[[buildings]]
name = "low"
stories = 4
mass = 1.0e5
story_stiffness = 2.0e8
story_height = 3.5
initial_velocity = [0.1, 0.2, 0.3, 0.4]

[[buildings]]
name = "tall"
stories = 6
mass = 1.0e5
story_stiffness = 2.0e8
story_height = 3.0

[[contacts]]
left = "low"
left_floor = 4
right = "tall"
right_floor = 4
gap = 0.01

[analysis]
duration = 1.0
"#;

/// `pound modes` warns (stderr) about floors that face the other building mid-story, as
/// `pound run` does, naming the first ones; `--json` lists them all under `unmodelled`, as
/// `pound run --out` does. Without story heights: no warning and an empty list.
#[test]
fn modes_warns_about_floors_facing_mid_story() {
    let d = TempDir::new("modes-facing");
    let f = d.write("mid.toml", MID_STORY);
    let f = f.to_str().unwrap();
    let o = pound(&["modes", f]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(0), "{err}");
    let run_json = d.path("run.json");
    let r = pound(&[
        "run",
        f,
        "--method",
        "gap",
        "--no-baseline",
        "--out",
        run_json.to_str().unwrap(),
    ]);
    assert_eq!(
        r.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&r.stderr)
    );
    let run: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&run_json).unwrap()).unwrap();
    let n = run["unmodelled"].as_array().unwrap().len();
    assert!(n > 3, "{n} facings");
    let head = format!(
        "warning: {n} floors face an adjacent building mid-story (floor-to-column impact, not \
        modelled): floor 1 of low (3.500 m) between levels 1 and 2 of tall"
    );
    assert!(err.contains(&head), "{err}");
    assert!(
        String::from_utf8_lossy(&r.stderr).contains(&head),
        "the same warning from `pound run`"
    );
    assert!(
        err.contains("floor 1 of low (3.500 m) between levels 1 and 2 of tall"),
        "{err}"
    );
    assert!(
        err.contains(&format!(
            "{} more (all in `unmodelled` of `pound modes --json`)",
            n - 3
        )),
        "{err}"
    );
    let o = pound(&["modes", f, "--json"]);
    assert_eq!(o.status.code(), Some(0));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v["unmodelled"], run["unmodelled"]);
    let more = format!("{} more (all in `unmodelled`)", n - 3);
    assert!(
        String::from_utf8_lossy(&r.stderr).contains(&format!(
            "{} more (all in `unmodelled` of the --out JSON)",
            n - 3
        )),
        "pound run says where the list is"
    );
    assert!(String::from_utf8_lossy(&o.stderr).contains(&more));
    // Without story heights every floor faces a floor.
    let plain = d.write(
        "plain.toml",
        &MID_STORY.replace("story_height", "# story_height"),
    );
    let o = pound(&["modes", plain.to_str().unwrap(), "--json"]);
    assert!(!String::from_utf8_lossy(&o.stderr).contains("warning"));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v["unmodelled"], serde_json::json!([]));
}

/// The `pound modes` column of the scene's `reference_frequencies_hz` is headed "reference
/// (Hz)" (any scene may give them, not only the paper's), and a one-floor building is "1
/// floor".
#[test]
fn modes_reference_column_and_singular_floor() {
    let o = pound(&["modes", &scene()]);
    let table = String::from_utf8_lossy(&o.stdout);
    assert!(
        table.contains("  mode   f (Hz) reference (Hz)  diff (%)    T (s)  eff. mass   cumul.\n"),
        "{table}"
    );
    assert!(!table.contains("paper"), "{table}");
    let d = TempDir::new("modes-one-floor");
    let f = d.write(
        "one.toml",
        "[[buildings]]\nname = \"a\"\nmasses = [1e5]\nstory_stiffness = [1e8]\n",
    );
    let o = pound(&["modes", f.to_str().unwrap()]);
    assert!(String::from_utf8_lossy(&o.stdout).starts_with("a (1 floor, total mass"));
}
