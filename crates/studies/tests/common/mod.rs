//! Helpers shared by the integration tests of the `pound` binary.
#![allow(dead_code)] // each test crate uses a part

use std::path::PathBuf;
use std::sync::atomic::{AtomicUsize, Ordering};

/// The `pound` binary under test.
pub const POUND: &str = env!("CARGO_BIN_EXE_pound");

/// Runs `pound` with `args` and waits for it.
pub fn pound<S: AsRef<std::ffi::OsStr>>(args: &[S]) -> std::process::Output {
    std::process::Command::new(POUND)
        .args(args)
        .output()
        .unwrap()
}

/// A fresh folder under the system temporary directory, removed on drop.
pub struct TempDir(pub PathBuf);

impl TempDir {
    /// `pound-<tag>-<pid>-<n>` under the temporary directory, empty.
    pub fn new(tag: &str) -> Self {
        static N: AtomicUsize = AtomicUsize::new(0);
        let p = std::env::temp_dir().join(format!(
            "pound-{tag}-{}-{}",
            std::process::id(),
            N.fetch_add(1, Ordering::Relaxed)
        ));
        let _ = std::fs::remove_dir_all(&p);
        std::fs::create_dir_all(&p).unwrap();
        TempDir(p)
    }

    /// Writes `content` to `name` inside the folder and returns its path.
    pub fn write(&self, name: &str, content: &str) -> PathBuf {
        let p = self.0.join(name);
        std::fs::write(&p, content).unwrap();
        p
    }

    /// The path of `name` inside the folder (not created).
    pub fn path(&self, name: &str) -> PathBuf {
        self.0.join(name)
    }
}

impl Drop for TempDir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

/// The repository's `studies/` folder.
pub const STUDIES: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../studies");

/// `pound studies run <study> --quick --studies-dir <studies_dir> --out <out>`.
pub fn quick_run(study: &str, studies_dir: &str, out: &str) -> std::process::Output {
    quick_run_with(study, studies_dir, out, &[])
}

/// [`quick_run`] with `extra` arguments after it (`--records FILE…`, say).
pub fn quick_run_with(
    study: &str,
    studies_dir: &str,
    out: &str,
    extra: &[&str],
) -> std::process::Output {
    let mut a = vec![
        "studies",
        "run",
        study,
        "--quick",
        "--studies-dir",
        studies_dir,
        "--out",
        out,
    ];
    a.extend_from_slice(extra);
    pound(&a)
}

/// Runs `pound studies run <study> --quick` into `<d>/results`, asserts success and returns
/// the study's output folder.
pub fn quick_study(d: &TempDir, study: &str) -> PathBuf {
    let out = d.path("results");
    let o = quick_run(study, STUDIES, out.to_str().unwrap());
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    out.join(study)
}

/// A CSV file as rows of strings, header first.
pub fn read_csv(path: &std::path::Path) -> Vec<Vec<String>> {
    let mut r = csv::Reader::from_path(path).unwrap();
    let mut rows = vec![r.headers().unwrap().iter().map(String::from).collect()];
    for rec in r.records() {
        rows.push(rec.unwrap().iter().map(String::from).collect());
    }
    rows
}

/// `python3` with the library folder of the `openseespylinux` wheel on LD_LIBRARY_PATH (its
/// bundled liblapack needs the bundled libblas), or None when openseespy does not import
/// (also when python3 itself is missing).
pub fn opensees_python() -> Option<std::process::Command> {
    let find = std::process::Command::new("python3")
        .args([
            "-c",
            "import importlib.util as u, os\n\
             s = u.find_spec('openseespylinux')\n\
             print(os.path.join(list(s.submodule_search_locations)[0], 'lib') if s else '')",
        ])
        .output()
        .ok()?;
    let lib = String::from_utf8_lossy(&find.stdout).trim().to_string();
    let mk = || {
        let mut c = std::process::Command::new("python3");
        if !lib.is_empty() {
            let old = std::env::var("LD_LIBRARY_PATH").unwrap_or_default();
            c.env("LD_LIBRARY_PATH", format!("{lib}:{old}"));
        }
        c
    };
    let ok = mk()
        .args(["-c", "import openseespy.opensees"])
        .output()
        .ok()?
        .status
        .success();
    ok.then(mk)
}
