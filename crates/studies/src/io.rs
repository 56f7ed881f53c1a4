//! Output files that are never partial: everything is written to a temporary file in the
//! destination folder and renamed into place (a device or pipe such as `/dev/null` is
//! written through instead; a symbolic link has its target replaced, the link kept).

use std::io::Write;
use std::path::{Path, PathBuf};

use solvers::History;
use structure::Scene;

/// Errors from writing outputs.
#[derive(Debug, thiserror::Error)]
pub enum OutputError {
    /// The OS error is part of the message, not a chained source (printed once).
    #[error("cannot write {path}: {error}")]
    Io { path: String, error: std::io::Error },
    /// The destination is a folder.
    #[error("cannot write {path}: it is a folder (expected a file name)")]
    IsAFolder { path: String },
    /// A component of the destination's folder is a file.
    #[error("cannot write {path}: {file} is a file, not a folder")]
    NotAFolder { path: String, file: String },
    #[error("cannot serialise {what}: {source}")]
    Json {
        what: String,
        source: serde_json::Error,
    },
}

/// The nearest existing ancestor of `dir` (itself included) if it is not a folder: the
/// reason a file cannot be created below it.
fn file_in_the_way(dir: &Path) -> Option<&Path> {
    let existing = dir.ancestors().find(|a| a.exists())?;
    (!existing.is_dir()).then_some(existing)
}

/// Writes `bytes` to `path` atomically (temporary file in the same folder, then rename).
/// An existing read-only file at `path` is an error, not replaced.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), OutputError> {
    write_all_atomic(&[(path, bytes)])
}

/// Where and how a destination is written ([`write_all_atomic`]).
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Destination {
    /// A regular file, or none yet: a temporary file beside it, renamed into place. The path
    /// is the file to replace: symbolic links followed, its folder resolved when it exists.
    Replace(PathBuf),
    /// A device, pipe or socket (`/dev/null`, a FIFO, `/dev/stdout`): written through, as a
    /// shell's `>` would; renaming a file over it would replace the device. The path as given.
    Through(PathBuf),
}

/// The destination of `path`. What the path finally names is asked of the kernel, which
/// follows every link (`/dev/stdout` → `/proc/self/fd/1` → a pipe, whose link text is not a
/// path): a folder is refused, a device or pipe written through. A regular file or a new one
/// is replaced where its links lead, link by link (a dangling link's target is created, the
/// link kept), at most 40 deep as the kernel does.
pub fn destination(path: &Path) -> Result<Destination, OutputError> {
    let io_err = |error| OutputError::Io {
        path: path.display().to_string(),
        error,
    };
    match std::fs::metadata(path) {
        Ok(m) if m.is_dir() => {
            return Err(OutputError::IsAFolder {
                path: path.display().to_string(),
            })
        }
        Ok(m) if !m.is_file() => return Ok(Destination::Through(path.to_path_buf())),
        _ => {}
    }
    let mut real = path.to_path_buf();
    for _ in 0..40 {
        match std::fs::symlink_metadata(&real) {
            Ok(m) if m.file_type().is_symlink() => {
                let target = std::fs::read_link(&real).map_err(io_err)?;
                real = match real.parent() {
                    Some(dir) => dir.join(target),
                    None => target,
                };
            }
            _ => {
                // The folder resolved (links, `..`) when it exists, so that two paths to one
                // file compare equal; the file name as it is (the file need not exist).
                let dir = match real.parent() {
                    Some(d) if !d.as_os_str().is_empty() => d,
                    _ => Path::new("."),
                };
                if let (Ok(d), Some(n)) = (std::fs::canonicalize(dir), real.file_name()) {
                    real = d.join(n);
                }
                return Ok(Destination::Replace(real));
            }
        }
    }
    Err(io_err(std::io::Error::other(
        "too many levels of symbolic links",
    )))
}

/// Checks, before any work is done, that `path` can be written, so that a run is not
/// thrown away at its end: [`destination`]'s checks (a folder is refused), then, for a file
/// to replace, that it is not read-only, that no file stands where its folder should be, and
/// that a file can be created in its folder (or, when the folder does not exist yet, in the
/// nearest folder that does, where it will be made): an empty probe file is created there
/// and removed at once. A device or pipe is not opened here (opening a FIFO would wake its
/// reader); it is opened when written.
pub fn check_writable(path: &Path) -> Result<Destination, OutputError> {
    let dest = destination(path)?;
    let Destination::Replace(real) = &dest else {
        return Ok(dest);
    };
    let err = |error| OutputError::Io {
        path: path.display().to_string(),
        error,
    };
    if std::fs::metadata(real).is_ok_and(|m| m.permissions().readonly()) {
        return Err(err(std::io::Error::new(
            std::io::ErrorKind::PermissionDenied,
            "the file exists and is read-only; it is not replaced",
        )));
    }
    let dir = match real.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    if let Some(file) = file_in_the_way(dir) {
        return Err(OutputError::NotAFolder {
            path: path.display().to_string(),
            file: file.display().to_string(),
        });
    }
    let Some(existing) = dir.ancestors().find(|a| a.exists()) else {
        return Ok(dest);
    };
    let name = real
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let probe = existing.join(format!(".{name}.probe-{}", std::process::id()));
    std::fs::OpenOptions::new()
        .write(true)
        .create_new(true)
        .open(&probe)
        .map_err(err)?;
    let _ = std::fs::remove_file(&probe);
    Ok(dest)
}

/// Whether `a` and `b` name one existing regular file (the same device and inode, so links,
/// `..` and hard links are seen through): an output that would overwrite an input.
#[cfg(unix)]
pub fn same_file(a: &Path, b: &Path) -> bool {
    use std::os::unix::fs::MetadataExt;
    match (std::fs::metadata(a), std::fs::metadata(b)) {
        (Ok(x), Ok(y)) => x.is_file() && (x.dev(), x.ino()) == (y.dev(), y.ino()),
        _ => false,
    }
}

/// Elsewhere: the same canonical path.
#[cfg(not(unix))]
pub fn same_file(a: &Path, b: &Path) -> bool {
    match (std::fs::canonicalize(a), std::fs::canonicalize(b)) {
        (Ok(x), Ok(y)) => x == y && std::fs::metadata(&x).is_ok_and(|m| m.is_file()),
        _ => false,
    }
}

/// Whether `path` names the file standard output writes to: the same device and inode as
/// stdout's (`/dev/stdout`, `/proc/self/fd/1`, or the file or pipe stdout is redirected to).
/// False when either cannot be asked (a path that does not exist yet is not stdout).
#[cfg(unix)]
pub fn is_stdout(path: &Path) -> bool {
    use std::os::fd::AsFd;
    use std::os::unix::fs::MetadataExt;
    let Ok(fd) = std::io::stdout().as_fd().try_clone_to_owned() else {
        return false;
    };
    let (Ok(out), Ok(p)) = (std::fs::File::from(fd).metadata(), std::fs::metadata(path)) else {
        return false;
    };
    (out.dev(), out.ino()) == (p.dev(), p.ino())
}

/// Elsewhere stdout's file cannot be asked: no path is taken for it (`--out -` still is).
#[cfg(not(unix))]
pub fn is_stdout(_path: &Path) -> bool {
    false
}

/// Whether two output paths would write the same file: the same file to replace once links
/// and folders are resolved (`--out link.json --history target.json`), or the same path. Two
/// outputs to one device (`/dev/null`) are not: each is written through in turn.
pub fn same_destination(a: &Path, b: &Path) -> bool {
    match (destination(a), destination(b)) {
        (Ok(Destination::Replace(x)), Ok(Destination::Replace(y))) => x == y,
        (Ok(Destination::Through(_)), Ok(Destination::Through(_))) => false,
        _ => a == b,
    }
}

/// Writes several files all or nothing: every file goes to a temporary file in its folder
/// first; only when all are written are they renamed into place. If any cannot be written,
/// the temporary files are removed and every destination is left as it was (an existing
/// file is neither replaced nor deleted). A destination that is a symbolic link has its
/// target written (the link stays); one that is a folder is refused before anything is
/// written. A device or pipe ([`Destination::Through`]) is opened first (a pipe without a
/// reader blocks there, as a shell's `>` does, before any temporary file exists) and
/// written after the temporary files and before any rename, so that a failing device
/// (`/dev/full`) leaves the files as they were; what was written to a device cannot be taken
/// back if a rename fails after it (a folder made read-only meanwhile).
pub fn write_all_atomic(files: &[(&Path, &[u8])]) -> Result<(), OutputError> {
    let dests = files
        .iter()
        .map(|(p, _)| destination(p))
        .collect::<Result<Vec<_>, _>>()?;
    let mut devices = Vec::new();
    for ((path, bytes), dest) in files.iter().zip(&dests) {
        if let Destination::Through(real) = dest {
            let f = std::fs::OpenOptions::new()
                .write(true)
                .open(real)
                .map_err(|error| OutputError::Io {
                    path: path.display().to_string(),
                    error,
                })?;
            devices.push((f, path, bytes));
        }
    }
    let mut staged: Vec<(PathBuf, &Path, &Path)> = Vec::new();
    let cleanup = |staged: &[(PathBuf, &Path, &Path)]| {
        for (tmp, _, _) in staged {
            let _ = std::fs::remove_file(tmp);
        }
    };
    for (k, ((path, bytes), dest)) in files.iter().zip(&dests).enumerate() {
        let Destination::Replace(real) = dest else {
            continue;
        };
        let err = |error| OutputError::Io {
            path: path.display().to_string(),
            error,
        };
        let dir = match real.parent() {
            Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
            _ => PathBuf::from("."),
        };
        let ro = std::fs::metadata(real).is_ok_and(|m| m.permissions().readonly());
        let name = real
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default();
        let tmp = dir.join(format!(".{name}.tmp-{}-{k}", std::process::id()));
        let result = if ro {
            Err(std::io::Error::new(
                std::io::ErrorKind::PermissionDenied,
                "the file exists and is read-only; it is not replaced",
            ))
        } else {
            (|| {
                std::fs::create_dir_all(&dir)?;
                let mut f = std::fs::File::create(&tmp)?;
                f.write_all(bytes)?;
                f.sync_all()
            })()
        };
        if let Err(e) = result {
            let _ = std::fs::remove_file(&tmp);
            cleanup(&staged);
            return Err(match file_in_the_way(&dir) {
                Some(file) => OutputError::NotAFolder {
                    path: path.display().to_string(),
                    file: file.display().to_string(),
                },
                None => err(e),
            });
        }
        staged.push((tmp, real.as_path(), path));
    }
    for (mut f, path, bytes) in devices {
        if let Err(error) = f.write_all(bytes).and_then(|()| f.flush()) {
            cleanup(&staged);
            return Err(OutputError::Io {
                path: path.display().to_string(),
                error,
            });
        }
    }
    for (i, (tmp, real, path)) in staged.iter().enumerate() {
        if let Err(e) = std::fs::rename(tmp, real) {
            cleanup(&staged[i..]);
            return Err(OutputError::Io {
                path: path.display().to_string(),
                error: e,
            });
        }
    }
    Ok(())
}

/// Serialises `value` as pretty JSON and writes it atomically.
pub fn write_json<T: serde::Serialize>(path: &Path, value: &T) -> Result<(), OutputError> {
    write_atomic(
        path,
        json_text(value, &path.display().to_string())?.as_bytes(),
    )
}

/// `value` as pretty JSON with a final newline, the text [`write_json`] writes (`what` names
/// it in an error).
pub fn json_text<T: serde::Serialize>(value: &T, what: &str) -> Result<String, OutputError> {
    let mut s = serde_json::to_string_pretty(value).map_err(|source| OutputError::Json {
        what: what.to_string(),
        source,
    })?;
    s.push('\n');
    Ok(s)
}

/// The history rows written with `--history-dt every` (all without it): the first sample,
/// the first sample at or after each later multiple of `every` (a sample within 1e-9·every
/// below a multiple counts as on it: record points are sums of steps), and the last sample.
/// The samples are the record points and event instants, so a row falls on a multiple only
/// where a sample does.
pub fn history_rows(time: &[f64], every: Option<f64>) -> Vec<usize> {
    let Some(dt) = every else {
        return (0..time.len()).collect();
    };
    let tol = 1e-9 * dt;
    let mut rows = Vec::new();
    let mut next = f64::NEG_INFINITY;
    for (s, &t) in time.iter().enumerate() {
        if t >= next - tol || s + 1 == time.len() {
            rows.push(s);
            next = (((t + tol) / dt).floor() + 1.0) * dt;
            // An interval so short that t/dt overflows: keep every sample, as a short one does.
            if !next.is_finite() {
                next = f64::NEG_INFINITY;
            }
        }
    }
    rows
}

/// CSV text of a history, one row per sample (record points and event instants, so the
/// grid is not uniform). Columns, every header quoted, buildings as named in the scene,
/// floors and stories counted from 1, contacts from 0 as in the JSON:
/// `time_s`; the ground acceleration `ground_a_m_per_s2`; floor displacements relative to the ground `<building>_u<floor>_m`; floor
/// velocities `<building>_v<floor>_m_per_s`; absolute floor accelerations
/// `<building>_a<floor>_abs_m_per_s2` from each floor's equilibrium,
/// a = M⁻¹ (f_contact − C u̇ − f_s) with the story forces f_s (K u for linear stories) (exact for the gap element and for the momentum method
/// with all modes; with fewer modes the equilibrium acceleration of the reconstructed
/// motion, and at an impact instant the regular part only, the impulse being in the JSON);
/// inter-story drifts `<building>_drift<story>_m` = u_j − u_{j−1}; drift ratios
/// `<building>_drift_ratio<story>` = (u_j − u_{j−1}) / h_j (dimensionless; only for buildings
/// whose scene entry gives `story_height`); story shears
/// `<building>_V<story>_N` = k_j (u_j − u_{j−1}) (a yielding building: the story law's force,
/// as recorded by the solver, which the accelerations use too); contact forces
/// `contact<i>_force_N` (compressive > 0).
pub fn history_csv(
    scene: &Scene,
    history: &History,
    every: Option<f64>,
) -> Result<String, OutputError> {
    let csv_err = |e: csv::Error| OutputError::Io {
        path: "history".into(),
        error: std::io::Error::other(e.to_string()),
    };
    let mut w = csv::WriterBuilder::new()
        .quote_style(csv::QuoteStyle::NonNumeric)
        .from_writer(Vec::new());
    let mut header = vec!["time_s".to_string(), "ground_a_m_per_s2".to_string()];
    let cols: [(&str, &str); 5] = [
        ("u", "_m"),
        ("v", "_m_per_s"),
        ("a", "_abs_m_per_s2"),
        ("drift", "_m"),
        ("V", "_N"),
    ];
    // Story heights per building, where the scene gives them (drift ratios).
    let heights = |bi: usize| scene.story_heights.get(bi).and_then(|h| h.as_ref());
    for (q, unit) in cols {
        if q == "V" {
            for (bi, b) in scene.buildings.iter().enumerate() {
                if heights(bi).is_some() {
                    for f in 1..=b.n_floors() {
                        header.push(format!("{}_drift_ratio{f}", b.name));
                    }
                }
            }
        }
        for b in &scene.buildings {
            for f in 1..=b.n_floors() {
                header.push(format!("{}_{q}{f}{unit}", b.name));
            }
        }
    }
    for i in 0..scene.contacts.len() {
        header.push(format!("contact{i}_force_N"));
    }
    w.write_record(&header).map_err(csv_err)?;
    // Damping matrices once (classical damping from each building's modes).
    let damping: Vec<Option<Vec<f64>>> = scene
        .buildings
        .iter()
        .map(|b| {
            b.modes()
                .ok()
                .map(|m| b.damping_matrix(&m).as_slice().to_vec())
        })
        .collect();
    let fmt = |x: f64| format!("{x:.9e}");
    let nc = scene.contacts.len();
    for s in history_rows(&history.time, every) {
        let t = history.time[s];
        let u = &history.displacement[s];
        let v = history.velocity.get(s).map(|r| r.as_slice()).unwrap_or(&[]);
        let fc = history
            .contact_force
            .get(s)
            .map(|r| r.as_slice())
            .unwrap_or(&[]);
        let ag = scene.ground.as_ref().map_or(0.0, |g| g.accel_at(t));
        let mut row = vec![format!("{t:e}"), fmt(ag)];
        let mut off = 0;
        let mut offsets = Vec::new();
        for b in &scene.buildings {
            offsets.push(off);
            off += b.n_floors();
        }
        let floors = |b: usize| offsets[b]..offsets[b] + scene.buildings[b].n_floors();
        // Story shears recorded by the solver (the law's for yielding stories), else k·drift.
        let recorded = history.story_shear.get(s).filter(|r| r.len() == u.len());
        let shears = |bi: usize| -> Vec<f64> {
            match recorded {
                Some(r) => r[floors(bi)].to_vec(),
                None => scene.buildings[bi].story_shears(&u[floors(bi)]),
            }
        };
        row.extend(u.iter().map(|&x| fmt(x)));
        if v.len() == u.len() {
            row.extend(v.iter().map(|&x| fmt(x)));
        } else {
            row.extend(std::iter::repeat_n(String::new(), u.len()));
        }
        // Absolute accelerations from floor equilibrium.
        for (bi, b) in scene.buildings.iter().enumerate() {
            let n = b.n_floors();
            let r = floors(bi);
            let (ub, vb) = (&u[r.clone()], v.get(r.clone()));
            let mut f = vec![0.0; n];
            if b.story_law.is_yielding() {
                let v = shears(bi);
                for (j, fj) in f.iter_mut().enumerate() {
                    *fj -= v[j];
                    if j + 1 < n {
                        *fj += v[j + 1];
                    }
                }
            } else {
                for (j, fj) in f.iter_mut().enumerate() {
                    let below = if j > 0 { ub[j - 1] } else { 0.0 };
                    *fj -= b.story_stiffness[j] * (ub[j] - below);
                    if j + 1 < n {
                        *fj += b.story_stiffness[j + 1] * (ub[j + 1] - ub[j]);
                    }
                }
            }
            match (vb, &damping[bi]) {
                (Some(vb), Some(c)) => {
                    for (j, vj) in vb.iter().enumerate() {
                        for (i, fi) in f.iter_mut().enumerate() {
                            *fi -= c[j * n + i] * vj;
                        }
                    }
                }
                _ => {
                    row.extend(std::iter::repeat_n(String::new(), n));
                    continue;
                }
            }
            if fc.len() == nc {
                for (c, &force) in scene.contacts.iter().zip(fc) {
                    if c.left == bi {
                        f[c.left_dof] -= force;
                    }
                    // A wall takes the reaction: no force on a second floor.
                    if c.right == bi && !c.wall {
                        f[c.right_dof] += force;
                    }
                }
            }
            row.extend(f.iter().zip(&b.masses).map(|(fi, m)| fmt(fi / m)));
        }
        for (bi, b) in scene.buildings.iter().enumerate() {
            let ub = &u[floors(bi)];
            let mut below = 0.0;
            for &x in ub.iter().take(b.n_floors()) {
                row.push(fmt(x - below));
                below = x;
            }
        }
        for (bi, b) in scene.buildings.iter().enumerate() {
            if let Some(h) = heights(bi) {
                let ub = &u[floors(bi)];
                let mut below = 0.0;
                for (&x, hj) in ub.iter().take(b.n_floors()).zip(h) {
                    row.push(fmt((x - below) / hj));
                    below = x;
                }
            }
        }
        for (bi, b) in scene.buildings.iter().enumerate() {
            if b.story_law.is_yielding() {
                row.extend(shears(bi).into_iter().map(fmt));
            } else {
                row.extend(b.story_shears(&u[floors(bi)]).into_iter().map(fmt));
            }
        }
        if fc.len() == nc {
            row.extend(fc.iter().map(|&x| fmt(x)));
        } else {
            row.extend(std::iter::repeat_n(String::new(), nc));
        }
        w.write_record(&row).map_err(csv_err)?;
    }
    let bytes = w.into_inner().map_err(|e| OutputError::Io {
        path: "history".into(),
        error: std::io::Error::other(e.to_string()),
    })?;
    Ok(String::from_utf8_lossy(&bytes).into_owned())
}

#[cfg(test)]
mod tests {
    use super::history_rows;

    #[test]
    fn history_rows_keep_the_first_sample_after_each_multiple_and_the_last() {
        // Record points of 0.1 s, an event at 0.25 s, the last sample off the grid.
        let t = [0.0, 0.1, 0.2, 0.25, 0.30000000000000004, 0.4, 0.45];
        assert_eq!(history_rows(&t, None), (0..7).collect::<Vec<_>>());
        // Every 0.2 s: 0, 0.2, 0.4 (0.25 and 0.3 fall between multiples), and the last.
        assert_eq!(history_rows(&t, Some(0.2)), vec![0, 2, 5, 6]);
        // A sample within 1e-9·S below a multiple counts as on it: 0.3 − 1e-12.
        let u = [0.0, 0.1, 0.3 - 1e-12, 0.35];
        assert_eq!(history_rows(&u, Some(0.3)), vec![0, 2, 3]);
        // An interval longer than the record: the first and the last sample.
        assert_eq!(history_rows(&t, Some(100.0)), vec![0, 6]);
        // One shorter than the sample spacing, down to one that overflows t/S: every sample.
        for s in [1e-3, 1e-300, 1e-310, 5e-324] {
            assert_eq!(
                history_rows(&t, Some(s)),
                (0..7).collect::<Vec<_>>(),
                "S = {s}"
            );
        }
        assert!(history_rows(&[], Some(0.1)).is_empty());
    }
}
