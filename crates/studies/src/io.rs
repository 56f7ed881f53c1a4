//! Output files that are never partial: everything is written to a temporary file in the
//! destination folder and renamed into place.

use std::io::Write;
use std::path::{Path, PathBuf};

use solvers::History;
use structure::Scene;

/// Errors from writing outputs.
#[derive(Debug, thiserror::Error)]
pub enum OutputError {
    #[error("cannot write {path}: {source}")]
    Io {
        path: String,
        source: std::io::Error,
    },
    #[error("cannot serialise {what}: {source}")]
    Json {
        what: String,
        source: serde_json::Error,
    },
}

/// Writes `bytes` to `path` atomically (temporary file in the same folder, then rename).
/// An existing read-only file at `path` is an error, not replaced.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), OutputError> {
    let err = |source| OutputError::Io {
        path: path.display().to_string(),
        source,
    };
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => PathBuf::from("."),
    };
    std::fs::create_dir_all(&dir).map_err(err)?;
    // A rename replaces even a read-only file: refuse one explicitly.
    if let Ok(m) = std::fs::metadata(path) {
        if m.permissions().readonly() {
            return Err(err(std::io::Error::new(
                std::io::ErrorKind::PermissionDenied,
                "the file exists and is read-only; it is not replaced",
            )));
        }
    }
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let tmp = dir.join(format!(".{name}.tmp-{}", std::process::id()));
    let result = (|| {
        let mut f = std::fs::File::create(&tmp)?;
        f.write_all(bytes)?;
        f.sync_all()?;
        std::fs::rename(&tmp, path)
    })();
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result.map_err(err)
}

/// Serialises `value` as pretty JSON and writes it atomically.
pub fn write_json<T: serde::Serialize>(path: &Path, value: &T) -> Result<(), OutputError> {
    let mut s = serde_json::to_string_pretty(value).map_err(|source| OutputError::Json {
        what: path.display().to_string(),
        source,
    })?;
    s.push('\n');
    write_atomic(path, s.as_bytes())
}

/// CSV text of a history: `time_s`, floor displacements `<building>_u<floor>_m`, then story
/// shears `<building>_V<story>_N` (V_j = k_j (u_j − u_{j−1})).
pub fn history_csv(scene: &Scene, history: &History) -> String {
    let mut out = String::from("time_s");
    for b in &scene.buildings {
        for f in 1..=b.n_floors() {
            out.push_str(&format!(",{}_u{f}_m", b.name));
        }
    }
    for b in &scene.buildings {
        for f in 1..=b.n_floors() {
            out.push_str(&format!(",{}_V{f}_N", b.name));
        }
    }
    out.push('\n');
    for (t, row) in history.time.iter().zip(&history.displacement) {
        out.push_str(&format!("{t:.6}"));
        for u in row {
            out.push_str(&format!(",{u:.9e}"));
        }
        let mut off = 0;
        for b in &scene.buildings {
            let n = b.n_floors();
            for v in b.story_shears(&row[off..off + n]) {
                out.push_str(&format!(",{v:.9e}"));
            }
            off += n;
        }
        out.push('\n');
    }
    out
}
