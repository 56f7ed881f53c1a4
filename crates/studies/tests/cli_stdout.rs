//! Failed writes to stdout: a reader that closes the pipe (`pound … | head -1`) ends `pound`
//! quietly with status 141, any other failure (`> /dev/full`) is `error: cannot write to
//! stdout: …` with status 1; never a panic. Also the scene file named in the `modes` and
//! `export opensees` refusals.

mod common;

use std::io::Read;
use std::process::{Command, Stdio};

use common::{pound, TempDir, POUND};

/// The status of a broken pipe (128 + SIGPIPE), as `main.rs` documents.
const BROKEN_PIPE: i32 = 141;

/// A linux pipe holds 64 KiB unless resized (Rust's `Stdio::piped` does not resize it): an
/// output several times that cannot fit in it, so the child is still writing when the reader
/// goes.
const PIPE_BUFFER: usize = 64 * 1024;

const PAPER: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/../../studies/paper/scene.toml"
);
const RECORD: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/../../data/ground-motions/RSN752_LOMAP_CAP000.AT2"
);

/// Two 1000-storey buildings, one contact, three modes kept, one second of the record: large
/// outputs (modes, JSON result, script: 150-550 kB) in half a second each.
fn big_scene(d: &TempDir) -> String {
    let record = std::fs::canonicalize(RECORD).unwrap();
    let text = format!(
        r#"[[buildings]]
name = "a"
stories = 1000
mass = 2.0e6
story_stiffness = 4.0e11

[[buildings]]
name = "b"
stories = 1000
mass = 2.0e6
story_stiffness = 5.0e11

[[contacts]]
left = "a"
left_floor = 1000
right = "b"
right_floor = 1000
gap = 0.01

[ground_motion]
file = {:?}
pga = 0.4

[analysis]
duration = 1.0

[momentum]
modes = 3
"#,
        record.display().to_string()
    );
    d.write("big.toml", &text).display().to_string()
}

fn no_panic(stderr: &[u8], what: &str) {
    let e = String::from_utf8_lossy(stderr);
    assert!(
        !e.contains("panicked") && !e.contains("Broken pipe"),
        "{what}: {e}"
    );
}

/// Runs `pound args` with stdout piped, reads 1 kB of it, closes the read end and waits:
/// `pound` must exit quietly with [`BROKEN_PIPE`]. The output is checked first (a normal run)
/// to exceed the pipe's buffer by far, so the child is blocked writing when the reader goes:
/// no timing race.
fn broken_pipe_after_reading(args: &[&str]) {
    let full = pound(args);
    assert!(
        full.status.success(),
        "{args:?}: {}",
        String::from_utf8_lossy(&full.stderr)
    );
    assert!(
        full.stdout.len() > 2 * PIPE_BUFFER + 1024,
        "{args:?}: only {} bytes of output, too few to fill the pipe",
        full.stdout.len()
    );
    let mut child = Command::new(POUND)
        .args(args)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut stdout = child.stdout.take().unwrap();
    let mut first = [0u8; 1024];
    stdout.read_exact(&mut first).unwrap();
    drop(stdout);
    let o = child.wait_with_output().unwrap();
    quiet_broken_pipe(args, &o);
}

/// Runs `pound args` with stdout a pipe whose read end is closed before the child starts: its
/// first write fails, whatever the output's size.
fn broken_pipe_closed_before(args: &[&str]) {
    let (reader, writer) = std::io::pipe().unwrap();
    drop(reader);
    let o = Command::new(POUND)
        .args(args)
        .stdout(writer)
        .stderr(Stdio::piped())
        .output()
        .unwrap();
    quiet_broken_pipe(args, &o);
}

/// A broken pipe's outcome: no panic, the broken-pipe status and nothing said on stderr.
fn quiet_broken_pipe(args: &[&str], o: &std::process::Output) {
    no_panic(&o.stderr, &format!("{args:?}"));
    assert_eq!(
        o.status.code(),
        Some(BROKEN_PIPE),
        "{args:?}: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    assert!(
        !String::from_utf8_lossy(&o.stderr).contains("error:"),
        "{args:?}: a broken pipe is quiet: {}",
        String::from_utf8_lossy(&o.stderr)
    );
}

/// Runs `pound args` with stdout `/dev/full` (every write: no space left on device).
#[cfg(target_os = "linux")]
fn dev_full(args: &[&str]) {
    let full = std::fs::OpenOptions::new()
        .write(true)
        .open("/dev/full")
        .unwrap();
    let o = Command::new(POUND)
        .args(args)
        .stdout(full)
        .stderr(Stdio::piped())
        .output()
        .unwrap();
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(!e.contains("panicked"), "{args:?}: {e}");
    assert!(
        e.contains("error: cannot write to stdout: No space left on device"),
        "{args:?}: {e}"
    );
    assert_eq!(o.status.code(), Some(1), "{args:?}: {e}");
}

#[test]
fn export_opensees_broken_pipe() {
    let d = TempDir::new("stdout-export");
    let big = big_scene(&d);
    broken_pipe_after_reading(&["export", "opensees", &big]);
    broken_pipe_closed_before(&["export", "opensees", PAPER]);
}

#[test]
fn run_out_stdout_broken_pipe() {
    let d = TempDir::new("stdout-run");
    let big = big_scene(&d);
    let json = [
        "run",
        &big,
        "--method",
        "momentum",
        "--no-baseline",
        "--out",
        "-",
    ];
    broken_pipe_after_reading(&json);
    broken_pipe_closed_before(&json);
    // The summary.
    broken_pipe_closed_before(&["run", &big, "--method", "momentum", "--no-baseline"]);
}

#[test]
fn modes_broken_pipe() {
    let d = TempDir::new("stdout-modes");
    let big = big_scene(&d);
    broken_pipe_after_reading(&["modes", &big, "--json"]);
    broken_pipe_closed_before(&["modes", &big]);
    broken_pipe_closed_before(&["modes", PAPER, "--json"]);
}

#[test]
fn record_and_spectrum_broken_pipe() {
    broken_pipe_closed_before(&["record", RECORD]);
    broken_pipe_closed_before(&["record", RECORD, "--json"]);
    broken_pipe_closed_before(&["spectrum", RECORD]);
    // 3000 periods: about 180 kB of CSV.
    let periods: Vec<String> = (1..=3000)
        .map(|i| format!("{}", i as f64 * 0.003))
        .collect();
    let periods = periods.join(",");
    broken_pipe_after_reading(&["spectrum", RECORD, "--periods", &periods]);
}

#[test]
fn help_broken_pipe() {
    broken_pipe_closed_before(&["--help"]);
}

#[cfg(target_os = "linux")]
#[test]
fn full_stdout_is_an_error() {
    dev_full(&["run", PAPER, "--method", "momentum", "--no-baseline"]);
    dev_full(&[
        "run",
        PAPER,
        "--method",
        "momentum",
        "--no-baseline",
        "--out",
        "-",
    ]);
    dev_full(&["export", "opensees", PAPER]);
    dev_full(&["modes", PAPER]);
    dev_full(&["modes", PAPER, "--json"]);
    dev_full(&["record", RECORD]);
    dev_full(&["spectrum", RECORD]);
    dev_full(&["--help"]);
}

/// A building the eigen-solver would refuse (a stiffness matrix singular in f64): `pound modes`
/// refuses it naming the scene file and the key, in both output modes. (Since the scene's
/// ranges came in, validation refuses it before the eigen-solver runs; an eigen-solver
/// failure itself would name the file the same way.)
#[test]
fn modes_refusal_names_the_scene() {
    let d = TempDir::new("stdout-eigen");
    let scene = d.write(
        "singular.toml",
        "[[buildings]]\nname = \"a\"\nmasses = [1.0, 1.0]\nstory_stiffness = [1e-20, 1e20]\n",
    );
    for json in [false, true] {
        let mut args = vec!["modes".to_string(), scene.display().to_string()];
        if json {
            args.push("--json".into());
        }
        let o = pound(&args);
        let e = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{e}");
        assert!(
            e.contains(&format!("error: {}: ", scene.display()))
                && e.contains("buildings[0].story_stiffness"),
            "{e}"
        );
        assert!(!e.contains("panicked"), "{e}");
        assert!(o.stdout.is_empty());
    }
}

/// The export's refusal of a law it cannot write names the scene file and the key.
#[test]
fn export_refusal_names_the_scene() {
    let d = TempDir::new("stdout-hertz");
    let out = d.path("model.py");
    let o = pound(&[
        "export",
        "opensees",
        PAPER,
        "--set",
        "gap_element.law=\"hertz-damp\"",
        "--out",
        out.to_str().unwrap(),
    ]);
    let e = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{e}");
    assert!(
        e.contains(&format!("error: {PAPER}: gap_element.law = \"hertz-damp\"")),
        "{e}"
    );
    assert!(!out.exists());
}

/// Stderr that cannot be written: the message is lost, the exit code stays (2 for a missing
/// scene), not a panic's 101.
#[cfg(target_os = "linux")]
#[test]
fn full_stderr_keeps_the_exit_code() {
    let full = std::fs::OpenOptions::new()
        .write(true)
        .open("/dev/full")
        .unwrap();
    let o = Command::new(POUND)
        .args(["modes", "/nonexistent/scene.toml"])
        .stderr(full)
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
}
