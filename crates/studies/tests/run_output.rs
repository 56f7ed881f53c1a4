//! `pound run --out` says what was run (version, overrides, record) and reports the
//! amplification factors from a run of the same model without contact.

mod common;
use common::{pound, TempDir};

/// `pound run SCENE --method momentum --no-baseline --set analysis.duration=SECS EXTRA...`.
fn run_momentum(scene: &str, secs: &str, extra: &[&str]) -> std::process::Output {
    let dur = format!("analysis.duration={secs}");
    let mut a = vec![
        "run",
        scene,
        "--method",
        "momentum",
        "--no-baseline",
        "--set",
        &dur,
    ];
    a.extend_from_slice(extra);
    pound(&a)
}

/// `pound run ARGS... --out OUT`, which must succeed: its stderr and the JSON written.
fn run_json(args: &[&str], out: &std::path::Path) -> (String, serde_json::Value) {
    let mut a = vec!["run"];
    a.extend_from_slice(args);
    a.extend(["--out", out.to_str().unwrap()]);
    let o = pound(&a);
    let err = String::from_utf8_lossy(&o.stderr).into_owned();
    assert!(o.status.success(), "{err}");
    let v = serde_json::from_str(&std::fs::read_to_string(out).unwrap()).unwrap();
    (err, v)
}

fn scene() -> String {
    concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../studies/paper/scene.toml"
    )
    .to_string()
}

#[test]
fn run_json_has_provenance_and_amplification() {
    let d = TempDir::new("runjson");
    let out = d.path("run.json");
    let (_, v) = run_json(
        &[
            &scene(),
            "--method",
            "momentum",
            "--set",
            "contacts.0.gap=0.05",
            "--set",
            "analysis.duration=12",
        ],
        &out,
    );
    assert_eq!(v["version"], env!("CARGO_PKG_VERSION"));
    assert_eq!(
        v["overrides"],
        serde_json::json!(["contacts.0.gap=0.05", "analysis.duration=12"])
    );
    let file = v["record"]["file"].as_str().unwrap();
    assert!(std::path::Path::new(file).is_absolute() && file.ends_with("RSN752_LOMAP_CAP000.AT2"));
    assert_eq!(v["record"]["pga_g"], 0.4);
    // Amplification = peak story shear with contact / without; recompute the denominator.
    let free = d.path("free.json");
    let o = pound(&[
        "run",
        &scene(),
        "--method",
        "momentum",
        "--set",
        "contacts.0.gap=1000",
        "--set",
        "analysis.duration=12",
        "--no-baseline",
        "--out",
        free.to_str().unwrap(),
    ]);
    assert!(o.status.success());
    let f: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&free).unwrap()).unwrap();
    assert!(f.get("amplification").is_none(), "--no-baseline skips it");
    for b in 0..2 {
        let amp = v["amplification"][b]["story_shear"].as_array().unwrap();
        let with = v["buildings"][b]["story_shear_max"].as_array().unwrap();
        let without = f["buildings"][b]["story_shear_max"].as_array().unwrap();
        assert_eq!(amp.len(), 15);
        for ((a, w), wo) in amp.iter().zip(with).zip(without) {
            let expect = w.as_f64().unwrap() / wo.as_f64().unwrap();
            assert!(
                (a.as_f64().unwrap() - expect).abs() <= 1e-12 * expect,
                "{a} vs {expect}"
            );
        }
    }
    // The printed summary has the column too.
    let o = pound(&[
        "run",
        &scene(),
        "--method",
        "gap",
        "--set",
        "analysis.duration=12",
    ]);
    assert!(String::from_utf8_lossy(&o.stdout).contains("amplification"));
}

/// `--out` onto a read-only file fails (exit 1) and leaves it as it was; the history written
/// before is removed: all or nothing.
#[test]
fn read_only_out_is_not_replaced_and_nothing_is_left_behind() {
    let d = TempDir::new("readonly");
    let out = d.write("run.json", "keep me\n");
    let mut perm = std::fs::metadata(&out).unwrap().permissions();
    perm.set_readonly(true);
    std::fs::set_permissions(&out, perm).unwrap();
    let hist = d.path("history.csv");
    let o = pound(&[
        "run",
        &scene(),
        "--method",
        "momentum",
        "--set",
        "analysis.duration=2",
        "--history",
        hist.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(
        err.contains("read-only") && err.contains("run.json"),
        "{err}"
    );
    assert_eq!(std::fs::read_to_string(&out).unwrap(), "keep me\n");
    assert!(!hist.exists(), "history left behind");
}

/// A history file that was there before survives a failed `--out` unchanged (the two files
/// are written together or not at all), and no temporary file is left in its folder.
#[test]
fn failed_out_leaves_an_existing_history_as_it_was() {
    let d = TempDir::new("keephist");
    let hist = d.write("history.csv", "earlier run\n");
    let blocker = d.write("afile", "");
    let out = blocker.join("run.json"); // its folder is a file: cannot be written
    let err = failed_output(&d, &hist, &out);
    assert!(err.contains("run.json"), "{err}");
    assert_eq!(std::fs::read_to_string(&hist).unwrap(), "earlier run\n");
}

/// A 2 s momentum run of the paper scene with `--history hist --out out` that must fail to
/// write (exit 1) and leave no temporary file in `d`: its stderr.
fn failed_output(d: &TempDir, hist: &std::path::Path, out: &std::path::Path) -> String {
    let o = run_momentum(
        &scene(),
        "2",
        &[
            "--history",
            hist.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ],
    );
    let err = String::from_utf8_lossy(&o.stderr).into_owned();
    assert_eq!(o.status.code(), Some(1), "{err}");
    let left: Vec<_> = std::fs::read_dir(&d.0)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.contains(".tmp-"))
        .collect();
    assert!(left.is_empty(), "temporary files left: {left:?}");
    err
}

/// `--out` naming a folder is refused before anything is written: the history that was
/// there before stays as it was (the rename of the history used to come first and replace
/// it, then the JSON's rename failed).
#[test]
fn out_naming_a_folder_writes_nothing() {
    let d = TempDir::new("outfolder");
    let hist = d.write("history.csv", "earlier run\n");
    let folder = d.path("results");
    std::fs::create_dir(&folder).unwrap();
    let err = failed_output(&d, &hist, &folder);
    assert!(
        err.contains("is a folder") && err.contains("results"),
        "{err}"
    );
    assert_eq!(std::fs::read_to_string(&hist).unwrap(), "earlier run\n");
    assert_eq!(std::fs::read_dir(&folder).unwrap().count(), 0);
}

/// An output that is a symbolic link has its target written and stays a link (a dangling
/// link's target is created); a named pipe is written through and stays a pipe (renaming a
/// file over it replaced it, as it replaced /dev/null for a root user).
#[cfg(unix)]
#[test]
fn outputs_follow_links_and_write_through_pipes() {
    use std::os::unix::fs::FileTypeExt;
    let d = TempDir::new("outlinks");
    let target = d.write("target.json", "old\n");
    let link = d.path("link.json");
    std::os::unix::fs::symlink("target.json", &link).unwrap();
    let dangling = d.path("dangling.json");
    std::os::unix::fs::symlink("created.json", &dangling).unwrap();
    for l in [&link, &dangling] {
        let o = run_momentum(&scene(), "1", &["--out", l.to_str().unwrap()]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        assert!(std::fs::symlink_metadata(l)
            .unwrap()
            .file_type()
            .is_symlink());
    }
    for f in [&target, &d.path("created.json")] {
        let v: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(f).unwrap()).unwrap();
        assert!(v["buildings"].is_array(), "{}", f.display());
    }
    let fifo = d.path("pipe.json");
    let made = std::process::Command::new("mkfifo").arg(&fifo).status();
    if !made.is_ok_and(|s| s.success()) {
        eprintln!("mkfifo unavailable: the pipe part is skipped");
        return;
    }
    let (tx, rx) = std::sync::mpsc::channel();
    {
        let fifo = fifo.clone();
        std::thread::spawn(move || tx.send(std::fs::read_to_string(fifo)));
    }
    let o = run_momentum(&scene(), "1", &["--out", fifo.to_str().unwrap()]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    // (Checked before waiting for the reader: a pipe replaced by a file leaves it blocked.)
    assert!(std::fs::symlink_metadata(&fifo)
        .unwrap()
        .file_type()
        .is_fifo());
    let text = rx
        .recv_timeout(std::time::Duration::from_secs(60))
        .expect("the pipe's reader got the JSON")
        .unwrap();
    let v: serde_json::Value = serde_json::from_str(&text).unwrap();
    assert!(v["buildings"].is_array());
}

/// `/dev/stdout` as `--out` writes through whatever stdout is (its link's text is not a
/// path when stdout is a pipe: `pipe:[N]`), and two outputs to one device are not "the same
/// file".
#[cfg(unix)]
#[test]
fn dev_stdout_and_one_device_twice_are_written_through() {
    if !std::path::Path::new("/dev/stdout").exists() {
        eprintln!("no /dev/stdout: skipped");
        return;
    }
    let o = run_momentum(&scene(), "1", &["--out", "/dev/stdout"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).expect("the JSON on stdout");
    assert!(v["buildings"].is_array());
    let o = run_momentum(
        &scene(),
        "1",
        &["--out", "/dev/null", "--history", "/dev/null"],
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
}

/// `--out` and `--history` that lead to one file through a link are refused as the same
/// file (following the link, both were renamed onto the target and the history was lost).
#[cfg(unix)]
#[test]
fn out_and_history_through_a_link_to_one_file_are_refused() {
    let d = TempDir::new("samefile");
    let target = d.write("target.json", "old\n");
    let link = d.path("link.json");
    std::os::unix::fs::symlink("target.json", &link).unwrap();
    let o = run_momentum(
        &scene(),
        "1",
        &[
            "--out",
            link.to_str().unwrap(),
            "--history",
            target.to_str().unwrap(),
        ],
    );
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains("the same file"), "{err}");
    assert_eq!(std::fs::read_to_string(&target).unwrap(), "old\n");
}

/// A device that fails the write (/dev/full: no space) fails the run's output with exit 1
/// and the reason, and stays the device; the other output is not written.
#[cfg(unix)]
#[test]
fn a_failing_device_fails_the_output_and_stays_a_device() {
    use std::os::unix::fs::FileTypeExt;
    let full = std::path::Path::new("/dev/full");
    if !std::fs::metadata(full).is_ok_and(|m| m.file_type().is_char_device()) {
        eprintln!("no /dev/full: skipped");
        return;
    }
    let d = TempDir::new("devfull");
    let hist = d.path("history.csv");
    let err = failed_output(&d, &hist, full);
    assert!(err.contains("/dev/full") && err.contains("space"), "{err}");
    assert!(std::fs::metadata(full)
        .unwrap()
        .file_type()
        .is_char_device());
    assert!(!hist.exists(), "history written beside a failed output");
}

/// The linear gap element is an elastic spring: a restitution below 1 (or `tension`) that it
/// cannot use is said on stderr, and the run goes on; the Kelvin–Voigt law says nothing.
#[test]
fn gap_settings_the_linear_law_ignores_are_noted() {
    let run = |law: &str| {
        let o = pound(&[
            "run",
            &scene(),
            "--method",
            "gap",
            "--no-baseline",
            "--set",
            "analysis.duration=1",
            "--set",
            &format!("gap_element.law={law}"),
            "--set",
            "contacts.0.restitution=0.5",
            "--set",
            "gap_element.tension=true",
        ]);
        assert_eq!(o.status.code(), Some(0));
        String::from_utf8_lossy(&o.stderr).into_owned()
    };
    let lin = run("linear");
    assert!(
        lin.contains("contacts.0.restitution = 0.5 is not used by the linear gap element"),
        "{lin}"
    );
    assert!(
        lin.contains("gap_element.tension = true applies to the kelvin-voigt law only"),
        "{lin}"
    );
    let kv = run("kelvin-voigt");
    assert!(!kv.contains("note:"), "{kv}");
    // A `floors = "aligned"` entry expands to 15 contacts: one note, naming the entry's key
    // (`contacts.0`; the expanded contacts' indices are no keys of the file).
    let aligned = scene().replace("scene.toml", "scene-aligned.toml");
    let o = pound(&[
        "run",
        &aligned,
        "--method",
        "gap",
        "--no-baseline",
        "--set",
        "analysis.duration=1",
        "--set",
        "gap_element.law=linear",
        "--set",
        "contacts.0.restitution=0.5",
    ]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(0), "{err}");
    assert_eq!(err.matches("note:").count(), 1, "{err}");
    assert!(
        err.contains(
            "note: contacts.0.restitution = 0.5 (for the 15 contacts this entry expands to)"
        ),
        "{err}"
    );
    assert!(!err.contains("contacts.1."), "{err}");
}

/// `--out -` prints the JSON on stdout (and nothing else there), for a pipe.
#[test]
fn out_dash_prints_the_json_on_stdout() {
    let o = run_momentum(&scene(), "2", &["--out", "-"]);
    assert_eq!(o.status.code(), Some(0));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).expect("stdout is the JSON");
    assert!(v["buildings"].is_array());
    assert!(!std::path::Path::new("-").exists(), "no file named -");
}

/// A ground motion far above any recorded PGA (here a record scaled by 981, as a record in
/// cm/s² read as g would be) is run, with a warning that names what to check: for an AT2
/// record its header's units (a scene's `units` is refused for AT2) and `scale`.
#[test]
fn implausible_pga_is_warned_about() {
    let d = TempDir::new("bigpga");
    let rec = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../data/ground-motions/RSN752_LOMAP_CAP000.AT2"
    );
    let text = std::fs::read_to_string(scene())
        .unwrap()
        .replace("pga = 0.40", "scale = 981.0")
        .replace("../../data/ground-motions/RSN752_LOMAP_CAP000.AT2", rec);
    let sc = d.write("scene.toml", &text);
    let o = run_momentum(sc.to_str().unwrap(), "1", &[]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(0), "{err}");
    assert!(
        err.contains("PGA is")
            && err
                .contains("check the record's units (its header, line 3) and ground_motion.scale"),
        "{err}"
    );
    assert!(!err.contains("ground_motion.units"), "{err}");
    // A two-column record: its units are the scene's `units` key.
    let two = d.write("two.txt", "0 0.1\n0.5 0.2\n1.0 -0.1\n1.5 0.0\n");
    let sc = d.write("scene-two.toml", &text.replace(rec, two.to_str().unwrap()));
    let o = run_momentum(sc.to_str().unwrap(), "1", &[]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(0), "{err}");
    assert!(
        err.contains("check the record's units (ground_motion.units and ground_motion.scale)"),
        "{err}"
    );
    let normal = run_momentum(&scene(), "1", &[]);
    assert!(!String::from_utf8_lossy(&normal.stderr).contains("PGA is"));
    // A `pga` the scene gives (here 300, meant as 0.3 g or as 300 cm/s²) is the PGA as run:
    // the warning names it, not the record's units, which it overrides.
    let o = run_momentum(&scene(), "1", &["--set", "ground_motion.pga=300"]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(0), "{err}");
    assert!(
        err.contains("PGA is 300.000 g")
            && err.contains("check ground_motion.pga = 300: it is the PGA as run, in g"),
        "{err}"
    );
    assert!(!err.contains("ground_motion.units"), "{err}");
}

/// `pound spectrum --pga` takes a number in g: `0.3g` is refused saying so (exit 2).
#[test]
fn spectrum_pga_with_a_unit_is_refused_saying_what_is_expected() {
    let rec = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../data/ground-motions/RSN752_LOMAP_CAP000.AT2"
    );
    let o = pound(&["spectrum", rec, "--pga", "0.3g"]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        err.contains("--pga")
            && err.contains("0.3g")
            && err.contains("expected a number in g, e.g. 0.3"),
        "{err}"
    );
    assert!(!err.contains("invalid float literal"), "{err}");
    assert!(o.stdout.is_empty());
    let o = pound(&["spectrum", rec, "--pga", "0.3", "--periods", "1"]);
    assert_eq!(o.status.code(), Some(0));
}

/// The `pound run` summary starts with the record as run (file name, PGA, duration) and the
/// contacts as resolved; an aligned entry is one line with its count of floor pairs. With
/// `--out FILE` (a file, or a device such as `/dev/null`) the summary is printed too; with
/// `--out -` or `--out /dev/stdout` (stdout's own file) stdout holds the JSON alone.
#[test]
fn run_summary_heads_with_record_and_contacts_and_comes_with_out_file() {
    let d = TempDir::new("summary-head");
    let out = d.path("run.json");
    let o = run_momentum(&scene(), "2", &["--out", out.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(0));
    let text = String::from_utf8_lossy(&o.stdout);
    let mut lines = text.lines();
    assert_eq!(
        lines.next(),
        Some(
            "record: RSN752_LOMAP_CAP000.AT2, PGA 0.400 g as run, duration 2.00 s (the record: \
        39.95 s)"
        ),
        "{text}"
    );
    assert_eq!(
        lines.next(),
        Some("contacts: building1 floor 15 – building2 floor 15, gap 0.1 m, c_r 1"),
        "{text}"
    );
    assert!(text.contains("paper-pair — method momentum"), "{text}");
    assert!(text.contains("energy (J):"), "{text}");
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&out).unwrap()).unwrap();
    assert!(v["buildings"].is_array());
    // Aligned: one line for the entry.
    let aligned = scene().replace("scene.toml", "scene-aligned.toml");
    let o = run_momentum(&aligned, "2", &[]);
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(
        text.contains(
            "\ncontacts: building1 – building2 at 15 floor pairs (15–15 … 1–1), gap 0.1 m, c_r 1\n"
        ),
        "{text}"
    );
    // `--out -` and `--out /dev/stdout` (here the test's pipe): the JSON alone.
    for to in ["-", "/dev/stdout"] {
        let o = run_momentum(&scene(), "2", &["--out", to]);
        assert_eq!(o.status.code(), Some(0), "{to}");
        let _: serde_json::Value = serde_json::from_slice(&o.stdout).expect("stdout is the JSON");
    }
    // Another device takes the JSON, and the summary is printed.
    let o = run_momentum(&scene(), "2", &["--out", "/dev/null"]);
    assert_eq!(o.status.code(), Some(0));
    assert!(String::from_utf8_lossy(&o.stdout).starts_with("record: "));
    // A folder is refused before the analysis runs (exit 1, nothing on stdout).
    let o = run_momentum(&scene(), "2", &["--out", d.path("").to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(1));
    assert!(o.stdout.is_empty());
    assert!(String::from_utf8_lossy(&o.stderr).contains("folder"));
    // So is a folder given to --history.
    let o = run_momentum(&scene(), "2", &["--history", d.path("").to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(1));
    assert!(o.stdout.is_empty());
    assert!(String::from_utf8_lossy(&o.stderr).contains("folder"));
}

/// The summary's header gives an aligned contact entry of a pair of the user's own as one
/// line with its floor pairs.
#[test]
fn aligned_contacts_are_one_line_of_the_summary() {
    let d = TempDir::new("one-window");
    let rec = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../data/ground-motions/RSN767_LOMAP_G03000.AT2"
    );
    let sc = d.write(
        "soft.toml",
        &format!(
            "[[buildings]]\nname = \"a\"\nstories = 6\nmass = 5.0e5\nstory_stiffness = 9.4e8\n\
             damping_ratio = 0.05\n[[buildings]]\nname = \"b\"\nstories = 10\nmass = 5.0e5\n\
             story_stiffness = 8.8e8\ndamping_ratio = 0.05\n[[contacts]]\nleft = \"a\"\n\
             right = \"b\"\nfloors = \"aligned\"\ngap = 0.04\n[ground_motion]\nfile = {rec:?}\n\
             pga = 0.3\n"
        ),
    );
    let o = run_momentum(sc.to_str().unwrap(), "1", &[]);
    let text = String::from_utf8_lossy(&o.stdout);
    assert_eq!(
        o.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    assert!(text.contains("contacts: a – b at 6 floor pairs"), "{text}");
}

const FREE_SCENE: &str = r#"
[[buildings]]
name = "left"
masses = [1.0e5, 1.0e5, 1.0e5]
story_stiffness = [2.0e8, 1.5e8, 1.0e8]
initial_velocity = [0.2, 0.4, 0.5]

[[buildings]]
name = "right, east"
masses = [1.5e5, 1.5e5]
story_stiffness = [3.0e8, 2.0e8]

[[contacts]]
left = "left"
left_floor = 2
right = "right, east"
right_floor = 2
gap = 0.01

[analysis]
duration = 2.0

[gap_element]
stiffness = 2e8
law = "linear"
tolerance = 1e-11
"#;

struct Csv {
    header: Vec<String>,
    rows: Vec<Vec<f64>>,
}

impl Csv {
    fn read(path: &std::path::Path) -> Csv {
        let text = std::fs::read_to_string(path).unwrap();
        let mut lines = text.lines();
        // Headers are quoted (a building name may hold a comma): split on `","`.
        let h = lines.next().unwrap();
        assert!(
            h.starts_with('"') && h.ends_with('"'),
            "unquoted header {h}"
        );
        let header: Vec<String> = h[1..h.len() - 1].split("\",\"").map(String::from).collect();
        let rows: Vec<Vec<f64>> = lines
            .map(|l| l.split(',').map(|x| x.parse::<f64>().unwrap()).collect())
            .collect();
        assert!(rows.iter().all(|r| r.len() == header.len()));
        Csv { header, rows }
    }
    fn col(&self, name: &str) -> usize {
        self.header
            .iter()
            .position(|h| h == name)
            .unwrap_or_else(|| panic!("no column {name} in {:?}", self.header))
    }
}

/// `--history-dt 0.05`: the first sample, the first sample at or after each multiple of
/// 0.05 s and the last one, each the very row of the full history (the momentum method
/// splits this stiffer pair's 5 ms record steps in parts and samples each part).
#[test]
fn history_dt_keeps_one_row_per_interval() {
    let d = TempDir::new("historydt");
    let (full, every) = (d.path("full.csv"), d.path("every.csv"));
    let stiff = "buildings.0.target_frequencies_hz=[4.0, 12.0]";
    for (path, extra) in [(&full, vec![]), (&every, vec!["--history-dt", "0.05"])] {
        let mut a = vec!["--set", stiff, "--history", path.to_str().unwrap()];
        a.extend(extra);
        let o = run_momentum(&scene(), "3", &a);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    }
    let lines = |p: &std::path::Path| -> Vec<String> {
        std::fs::read_to_string(p)
            .unwrap()
            .lines()
            .map(String::from)
            .collect()
    };
    let (all, kept) = (lines(&full), lines(&every));
    assert_eq!(all[0], kept[0], "header");
    let time = |l: &String| l.split(',').next().unwrap().parse::<f64>().unwrap();
    let times: Vec<f64> = all[1..].iter().map(time).collect();
    // The split: more than one sample per record step.
    assert!(times.len() > 2 * 600, "{} samples", times.len());
    let mut want = vec![1];
    for k in 1..=60 {
        let mark = k as f64 * 0.05;
        if let Some(i) = times.iter().position(|&t| t >= mark - 1e-9 * 0.05) {
            if !want.contains(&(i + 1)) {
                want.push(i + 1);
            }
        }
    }
    if !want.contains(&(all.len() - 1)) {
        want.push(all.len() - 1);
    }
    let expect: Vec<&String> = want.iter().map(|&i| &all[i]).collect();
    let got: Vec<&String> = kept[1..].iter().collect();
    assert_eq!(got.len(), 61, "rows at 0, 0.05, …, 3 s");
    assert_eq!(got, expect);
}

/// The history CSV: quoted headers, every quantity the README lists, and a state that is
/// consistent with itself: drift and shear from the displacements, the contact force of
/// the linear law, and the equilibrium accelerations equal to the time derivative of the
/// velocities (central differences on equally spaced samples of a tight adaptive run).
#[test]
fn history_csv_is_consistent() {
    let d = TempDir::new("histcsv");
    let scene = d.write("free.toml", FREE_SCENE);
    let (out, hist) = (d.path("run.json"), d.path("hist.csv"));
    let o = pound(&[
        "run",
        scene.to_str().unwrap(),
        "--method",
        "gap",
        "--no-baseline",
        "--history",
        hist.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let c = Csv::read(&hist);
    assert_eq!(c.header.len(), 2 + 5 * 5 + 1, "{:?}", c.header);
    let (t, fc) = (c.col("time_s"), c.col("contact0_force_N"));
    let (ul, ur) = (c.col("left_u2_m"), c.col("right, east_u2_m"));
    let mut contact_samples = 0;
    for r in &c.rows {
        let delta = r[ul] - r[ur] - 0.01;
        let law = if delta > 0.0 { 2e8 * delta } else { 0.0 };
        // The CSV's 10 significant digits of u (about 1e-11 m here) limit the recomputed
        // k δ to about 1e-9 k·gap (measured 5.1e-10).
        assert!(
            (r[fc] - law).abs() <= 5e-9 * 2e8 * 0.01,
            "force {} vs k δ {law}",
            r[fc]
        );
        contact_samples += (r[fc] > 0.0) as usize;
    }
    assert!(
        contact_samples > 20,
        "the contact carries force: {contact_samples} samples"
    );
    let (mut worst, mut scale): (f64, f64) = (0.0, 0.0);
    for (b, n) in [("left", 3), ("right, east", 2)] {
        let shears = (1..=n).map(|j| c.col(&format!("{b}_V{j}_N")));
        for (j, iv_shear) in (1..=n).zip(shears) {
            let (iu, idr) = (
                c.col(&format!("{b}_u{j}_m")),
                c.col(&format!("{b}_drift{j}_m")),
            );
            let (iv, ia) = (
                c.col(&format!("{b}_v{j}_m_per_s")),
                c.col(&format!("{b}_a{j}_abs_m_per_s2")),
            );
            let ground = c.col("ground_a_m_per_s2");
            for w in c.rows.windows(3) {
                let below = if j > 1 { w[1][iu - 1] } else { 0.0 };
                let tol = 1e-9 * (w[1][iu].abs() + below.abs()) + 1e-300;
                assert!((w[1][idr] - (w[1][iu] - below)).abs() <= tol);
                let k = w[1][iv_shear] / w[1][idr];
                if w[1][idr].abs() > 1e-4 {
                    let k_expect = match (b, j) {
                        ("left", 1) => 2.0e8,
                        ("left", 2) => 1.5e8,
                        ("left", _) => 1.0e8,
                        (_, 1) => 3.0e8,
                        _ => 2.0e8,
                    };
                    assert!(
                        (k / k_expect - 1.0).abs() < 1e-8,
                        "{b} story {j}: V/drift = {k}"
                    );
                }
                let (h0, h1) = (w[1][t] - w[0][t], w[2][t] - w[1][t]);
                if (h0 - h1).abs() > 1e-12 {
                    continue;
                }
                let fd = (w[2][iv] - w[0][iv]) / (h0 + h1);
                worst = worst.max((fd - (w[1][ia] - w[1][ground])).abs());
                scale = scale.max(w[1][ia].abs());
            }
        }
    }
    assert!(scale > 1.0, "accelerations of order m/s²: {scale}");
    // Second-order differences at h = 1 ms: observed 7e-4 of the largest acceleration; a
    // wrong damping term, sign or missing contact force is of order 1.
    assert!(
        worst < 2e-3 * scale,
        "equilibrium vs d/dt of velocity: {worst} of {scale}"
    );
}

/// The momentum method's history: the holding force of a persistent contact (c_r = 0)
/// is positive while the floors are held (δ = 0), zero in free flight.
#[test]
fn momentum_history_has_holding_forces() {
    let d = TempDir::new("histmom");
    let scene = d.write("free.toml", FREE_SCENE);
    let (out, hist) = (d.path("run.json"), d.path("hist.csv"));
    let o = pound(&[
        "run",
        scene.to_str().unwrap(),
        "--method",
        "momentum",
        "--set",
        "contacts.0.restitution=0",
        "--no-baseline",
        "--history",
        hist.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let c = Csv::read(&hist);
    let (fc, ul, ur) = (
        c.col("contact0_force_N"),
        c.col("left_u2_m"),
        c.col("right, east_u2_m"),
    );
    let held: Vec<&Vec<f64>> = c.rows.iter().filter(|r| r[fc] != 0.0).collect();
    assert!(!held.is_empty(), "a persistent phase carries force");
    for r in &c.rows {
        let delta = r[ul] - r[ur] - 0.01;
        assert!(delta <= 1e-9, "no penetration: {delta}");
        if r[fc] != 0.0 {
            assert!(
                r[fc] > 0.0 && delta.abs() <= 1e-9,
                "held: F = {}, δ = {delta}",
                r[fc]
            );
        }
    }
}

fn strip_nulls(v: &mut serde_json::Value) {
    match v {
        serde_json::Value::Object(m) => {
            m.retain(|_, x| !x.is_null());
            m.values_mut().for_each(strip_nulls);
        }
        serde_json::Value::Array(a) => a.iter_mut().for_each(strip_nulls),
        _ => {}
    }
}

/// `resolved_scene` is the scene that was run: written back as a scene file (TOML, without
/// its nulls) and run with no overrides, it gives bit-identical peaks.
#[test]
fn resolved_scene_reruns_the_same_analysis() {
    let d = TempDir::new("resolved");
    let (a, b) = (d.path("a.json"), d.path("b.json"));
    let (_, va) = run_json(
        &[
            &scene(),
            "--method",
            "momentum",
            "--set",
            "contacts.0.gap=0.05",
            "--set",
            "momentum.modes=10",
            "--set",
            "ground_motion.pga=0.3",
            "--set",
            "analysis.duration=8",
            "--no-baseline",
        ],
        &a,
    );
    let mut rs = va["resolved_scene"].clone();
    assert_eq!(rs["contacts"][0]["gap"], 0.05);
    assert_eq!(rs["momentum"]["modes"], 10);
    assert_eq!(rs["ground_motion"]["pga"], 0.3);
    assert_eq!(rs["analysis"]["duration"], 8.0);
    assert_eq!(
        rs["gap_element"]["stiffness"], 1e10,
        "defaults are spelled out"
    );
    assert!(std::path::Path::new(rs["ground_motion"]["file"].as_str().unwrap()).is_absolute());
    assert!(va["scene_file"].as_str().unwrap().ends_with("scene.toml"));
    strip_nulls(&mut rs);
    let toml = toml::to_string(&rs).unwrap();
    let again = d.write("again.toml", &toml);
    let o = pound(&[
        "run",
        again.to_str().unwrap(),
        "--method",
        "momentum",
        "--no-baseline",
        "--out",
        b.to_str().unwrap(),
    ]);
    assert!(
        o.status.success(),
        "{}\n{toml}",
        String::from_utf8_lossy(&o.stderr)
    );
    let vb: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&b).unwrap()).unwrap();
    assert_eq!(va["buildings"], vb["buildings"]);
    assert_eq!(va["impacts"], vb["impacts"]);
}

/// With story heights the history also has drift ratios, drift / h per story, after the
/// drifts; without them it has none (the test above counts the columns).
#[test]
fn history_has_drift_ratios_where_story_heights_are_given() {
    let d = TempDir::new("histratio");
    let scene = d.write("free.toml", FREE_SCENE);
    let hist = d.path("hist.csv");
    let o = pound(&[
        "run",
        scene.to_str().unwrap(),
        "--method",
        "momentum",
        "--no-baseline",
        "--set",
        "buildings.0.story_height=3.5",
        "--set",
        "buildings.1.story_height=[4.0, 3.0]",
        "--history",
        hist.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let c = Csv::read(&hist);
    assert_eq!(c.header.len(), 2 + 6 * 5 + 1, "{:?}", c.header);
    let mut checked = 0;
    for (b, h) in [
        ("left", vec![3.5, 3.5, 3.5]),
        ("right, east", vec![4.0, 3.0]),
    ] {
        for (j, hj) in h.iter().enumerate() {
            let (idr, irat) = (
                c.col(&format!("{b}_drift{}_m", j + 1)),
                c.col(&format!("{b}_drift_ratio{}", j + 1)),
            );
            assert!(
                idr < irat && irat < c.col(&format!("{b}_V1_N")),
                "column order"
            );
            // Both columns are printed with 10 significant digits.
            for r in &c.rows {
                assert!((r[irat] - r[idr] / hj).abs() <= 2e-9 * (r[idr] / hj).abs() + 1e-300);
                checked += (r[idr] != 0.0) as usize;
            }
        }
    }
    assert!(checked > 100, "{checked} non-zero drifts compared");
}

/// The overlap audit (issue 11): the roof-only paper scene warns on stderr naming the worst
/// pair, lists the overlaps in the summary and in the JSON (`overlaps`, `unmodelled`); the
/// aligned scene has nothing to audit and no warning.
#[test]
fn overlaps_warn_and_are_reported() {
    let d = TempDir::new("overlaps");
    let out = d.path("run.json");
    let (err, v) = run_json(&[&scene(), "--method", "momentum", "--no-baseline"], &out);
    let ov = v["overlaps"].as_array().unwrap();
    assert_eq!(ov.len(), 14);
    assert_eq!(v["unmodelled"], serde_json::json!([]));
    let worst = ov
        .iter()
        .max_by(|a, b| {
            a["max_overlap"]
                .as_f64()
                .unwrap()
                .total_cmp(&b["max_overlap"].as_f64().unwrap())
        })
        .unwrap();
    assert!(worst["max_overlap"].as_f64().unwrap() > 0.0);
    let named = format!(
        "worst: building1 floor {} / building2 floor {}",
        worst["left_floor"], worst["right_floor"]
    );
    assert!(err.contains("warning:") && err.contains(&named), "{err}");
    // How many, in the plural (the roof-only scene: several lower pairs).
    let beyond = ov
        .iter()
        .filter(|o| o["max_overlap"].as_f64().unwrap() > 0.0)
        .count();
    assert!(beyond > 1, "{beyond}");
    assert!(
        err.contains(&format!(
            "warning: {beyond} facing floor pairs without a contact overlapped beyond the gap; "
        )),
        "{err}"
    );
    // The summary lists them.
    let o = pound(&["run", &scene(), "--method", "gap", "--no-baseline"]);
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(
        text.contains("overlaps (facing floors without a contact"),
        "{text}"
    );
    assert!(
        text.contains("building1 floor 1 / building2 floor 1: -"),
        "{text}"
    );
    // Contact at every floor: nothing to audit, no warning.
    let aligned = scene().replace("scene.toml", "scene-aligned.toml");
    let (err, v) = run_json(
        &[
            &aligned,
            "--method",
            "momentum",
            "--no-baseline",
            "--set",
            "analysis.duration=12",
        ],
        &out,
    );
    // (stderr names the file written, whose folder's name holds "overlap": look for the
    // warning itself.)
    assert!(!err.contains("warning"));
    assert_eq!(v["overlaps"], serde_json::json!([]));
    assert_eq!(
        v["resolved_scene"]["contacts"].as_array().unwrap().len(),
        15
    );
}

/// The overlap warning in the singular: a two-story pair with a roof contact, whose first
/// floors (the one pair without a contact) overlap beyond the gap under a 2 Hz sine.
#[test]
fn one_overlapping_pair_is_named_in_the_singular() {
    let d = TempDir::new("overlap-one");
    let record: String = (0..300)
        .map(|i| {
            format!(
                "{:.6}\n",
                0.8 * (2.0 * std::f64::consts::PI * 2.0 * i as f64 * 0.01).sin()
            )
        })
        .collect();
    std::fs::write(d.path("sine.txt"), record).unwrap();
    let scene = d.path("pair.toml");
    std::fs::write(
        &scene,
        "name = \"two-story pair\"\n\
         [[buildings]]\nname = \"a\"\nmasses = [1.0e5, 1.0e5]\nstory_stiffness = [2.0e8, 2.0e8]\ndamping_ratio = 0.05\n\
         [[buildings]]\nname = \"b\"\nmasses = [1.0e5, 1.0e5]\nstory_stiffness = [6.0e8, 6.0e8]\ndamping_ratio = 0.05\n\
         [[contacts]]\nleft = \"a\"\nleft_floor = 2\nright = \"b\"\nright_floor = 2\ngap = 0.002\n\
         [ground_motion]\nfile = \"sine.txt\"\ndt = 0.01\n",
    )
    .unwrap();
    let (err, v) = run_json(
        &[
            scene.to_str().unwrap(),
            "--method",
            "momentum",
            "--no-baseline",
        ],
        &d.path("run.json"),
    );
    let ov = v["overlaps"].as_array().unwrap();
    assert_eq!(ov.len(), 1);
    assert!(ov[0]["max_overlap"].as_f64().unwrap() > 0.0, "{ov:?}");
    assert!(
        err.contains(
            "warning: 1 facing floor pair without a contact overlapped beyond the gap; worst: a \
             floor 1 / b floor 1 by "
        ),
        "{err}"
    );
}
