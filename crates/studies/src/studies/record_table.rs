//! The record metadata table, `data/ground-motions/records.csv`: one row per ground-motion
//! file, so the record-based studies can separate records with a velocity pulse from those
//! without.
//!
//! Columns (a header row names them; order free, every column required):
//!
//! | column | meaning |
//! |---|---|
//! | `file` | path relative to `data/ground-motions/` (records are matched by file name) |
//! | `rsn` | PEER record sequence number |
//! | `earthquake`, `year`, `station`, `component` | as in the PROVENANCE tables |
//! | `set` | `far-field` or `near-field` (the FEMA P695 set the file comes from) |
//! | `pulse` | `yes`, `no` (FEMA P695 near-field classification) or `unclassified` (the far-field set is not classified) |
//! | `source` | the provenance file the row was copied from |
//!
//! A record that is not in the table (e.g. a file passed with `--records`) is
//! `unclassified`.

use std::collections::BTreeMap;
use std::path::Path;

use serde::Deserialize;

use crate::sweep::StudyError;

/// Whether a record carries a velocity pulse (FEMA P695 near-field classification).
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum PulseClass {
    Pulse,
    NoPulse,
    Unclassified,
}

impl PulseClass {
    /// The three classes in report order.
    pub const ALL: [PulseClass; 3] = [
        PulseClass::Pulse,
        PulseClass::NoPulse,
        PulseClass::Unclassified,
    ];

    pub fn label(self) -> &'static str {
        match self {
            PulseClass::Pulse => "pulse",
            PulseClass::NoPulse => "no pulse",
            PulseClass::Unclassified => "unclassified",
        }
    }
}

/// Errors reading the table: file, line and what was expected.
#[derive(Debug, thiserror::Error)]
pub enum RecordTableError {
    #[error("cannot read {path}: {message}")]
    Read { path: String, message: String },
    #[error("{path}: line {line}: {message}")]
    Row {
        path: String,
        line: u64,
        message: String,
    },
    #[error("{path}: line {line}: `{file}` is listed twice (first on line {first})")]
    Duplicate {
        path: String,
        line: u64,
        first: u64,
        file: String,
    },
}

impl From<RecordTableError> for StudyError {
    fn from(e: RecordTableError) -> Self {
        match e {
            RecordTableError::Read { path, message } => StudyError::Read { path, message },
            RecordTableError::Row {
                path,
                line,
                message,
            } => StudyError::Definition {
                file: path,
                message: format!("line {line}: {message}"),
            },
            RecordTableError::Duplicate {
                path,
                line,
                first,
                file,
            } => StudyError::Definition {
                file: path,
                message: format!("line {line}: `{file}` is listed twice (first on line {first})"),
            },
        }
    }
}

/// One row of the table.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RecordInfo {
    pub file: String,
    pub rsn: u32,
    pub earthquake: String,
    pub year: u16,
    pub station: String,
    pub component: String,
    pub set: String,
    pub pulse: String,
    pub source: String,
}

impl RecordInfo {
    /// The `pulse` column as a class (validated on load).
    pub fn class(&self) -> PulseClass {
        match self.pulse.as_str() {
            "yes" => PulseClass::Pulse,
            "no" => PulseClass::NoPulse,
            _ => PulseClass::Unclassified,
        }
    }
}

/// The table, keyed by file name.
#[derive(Debug, Clone, Default)]
pub struct RecordTable {
    by_name: BTreeMap<String, RecordInfo>,
}

fn file_name(p: &str) -> String {
    Path::new(p)
        .file_name()
        .map_or_else(|| p.to_string(), |n| n.to_string_lossy().into_owned())
}

impl RecordTable {
    /// Reads and validates the table at `path`.
    pub fn load(path: &Path) -> Result<Self, RecordTableError> {
        let shown = path.display().to_string();
        let text = std::fs::read_to_string(path).map_err(|e| RecordTableError::Read {
            path: shown.clone(),
            message: e.to_string(),
        })?;
        Self::parse(&text, &shown)
    }

    /// Parses the CSV text; `path` names the file in errors.
    pub fn parse(text: &str, path: &str) -> Result<Self, RecordTableError> {
        let mut rd = csv::Reader::from_reader(text.as_bytes());
        let mut by_name = BTreeMap::new();
        let mut lines: BTreeMap<String, u64> = BTreeMap::new();
        for row in rd.deserialize::<RecordInfo>() {
            let row = row.map_err(|e| RecordTableError::Row {
                path: path.to_string(),
                line: e.position().map_or(0, |p| p.line()),
                message: match e.kind() {
                    csv::ErrorKind::Deserialize { err, .. } => match err.field() {
                        Some(i) => format!("column {}: {}", i + 1, err.kind()),
                        None => err.kind().to_string(),
                    },
                    _ => e.to_string(),
                },
            })?;
            // Header is line 1; rows follow one a line (no quoted newlines in this table).
            let line = lines.len() as u64 + 2;
            if !matches!(row.pulse.as_str(), "yes" | "no" | "unclassified") {
                return Err(RecordTableError::Row {
                    path: path.into(),
                    line,
                    message: format!(
                        "pulse `{}`: expected `yes`, `no` or `unclassified`",
                        row.pulse
                    ),
                });
            }
            let name = file_name(&row.file);
            if let Some(&first) = lines.get(&name) {
                return Err(RecordTableError::Duplicate {
                    path: path.into(),
                    line,
                    first,
                    file: name,
                });
            }
            lines.insert(name.clone(), line);
            by_name.insert(name, row);
        }
        Ok(RecordTable { by_name })
    }

    /// The row of a record file (matched by file name), if listed.
    pub fn get(&self, record: &str) -> Option<&RecordInfo> {
        self.by_name.get(&file_name(record))
    }

    /// The pulse class of a record file; `Unclassified` when not listed.
    pub fn class(&self, record: &str) -> PulseClass {
        self.get(record)
            .map_or(PulseClass::Unclassified, RecordInfo::class)
    }

    pub fn len(&self) -> usize {
        self.by_name.len()
    }

    pub fn is_empty(&self) -> bool {
        self.by_name.is_empty()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const HEAD: &str = "file,rsn,earthquake,year,station,component,set,pulse,source\n";

    #[test]
    fn parses_rows_and_classes() {
        let t = RecordTable::parse(
            &format!(
                "{HEAD}near-field/A_1.AT2,1,Eq,1990,St,X,near-field,yes,p\nB_2.AT2,2,Eq,1990,St,Y,far-field,unclassified,p\nnear-field/C_3.AT2,3,Eq,1990,St,Z,near-field,no,p\n"
            ),
            "t.csv",
        )
        .unwrap();
        assert_eq!(t.len(), 3);
        assert_eq!(t.class("/abs/dir/A_1.AT2"), PulseClass::Pulse);
        assert_eq!(t.class("../x/C_3.AT2"), PulseClass::NoPulse);
        assert_eq!(t.class("B_2.AT2"), PulseClass::Unclassified);
        assert_eq!(t.class("missing.AT2"), PulseClass::Unclassified);
        assert_eq!(t.get("A_1.AT2").unwrap().rsn, 1);
    }

    #[test]
    fn refuses_bad_rows_naming_the_line() {
        let bad = RecordTable::parse(
            &format!("{HEAD}A.AT2,1,Eq,1990,St,X,near-field,maybe,p\n"),
            "t.csv",
        )
        .unwrap_err()
        .to_string();
        assert!(
            bad.contains("t.csv: line 2") && bad.contains("maybe"),
            "{bad}"
        );
        let dup = RecordTable::parse(
            &format!("{HEAD}a/A.AT2,1,E,1990,S,X,s,no,p\nb/A.AT2,2,E,1990,S,X,s,no,p\n"),
            "t.csv",
        )
        .unwrap_err()
        .to_string();
        assert!(
            dup.contains("line 3") && dup.contains("first on line 2"),
            "{dup}"
        );
        let num = RecordTable::parse(&format!("{HEAD}A.AT2,one,E,1990,S,X,s,no,p\n"), "t.csv")
            .unwrap_err()
            .to_string();
        assert!(num.contains("line 2") && num.contains("column 2"), "{num}");
    }

    #[test]
    fn record_names_drop_only_the_peer_sequence_prefix() {
        use crate::studies::record_name;
        assert_eq!(record_name("../x/RSN752_LOMAP_CAP000.AT2"), "LOMAP_CAP000");
        assert_eq!(
            record_name("/a/near-field/RSN1063_NORTHR-RRS_032.AT2"),
            "NORTHR-RRS_032"
        );
        assert_eq!(record_name("RSNX_a.AT2"), "RSNX_a");
        assert_eq!(record_name("my_record.txt"), "my_record");
        assert_eq!(record_name("RSN12_.AT2"), "RSN12_");
    }

    #[test]
    fn the_committed_table_lists_every_record_file() {
        let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../data/ground-motions");
        let t = RecordTable::load(&root.join("records.csv")).unwrap();
        let mut files = 0;
        for dir in [root.clone(), root.join("near-field")] {
            for e in std::fs::read_dir(&dir).unwrap() {
                let n = e.unwrap().file_name().to_string_lossy().into_owned();
                if n.ends_with(".AT2") {
                    files += 1;
                    assert!(t.get(&n).is_some(), "{n} missing from records.csv");
                }
            }
        }
        assert_eq!(t.len(), files);
        let count = |c| t.by_name.values().filter(|r| r.class() == c).count();
        // FEMA P695 near-field set: 28 components with pulses, 28 without.
        assert_eq!(count(PulseClass::Pulse), 28);
        assert_eq!(count(PulseClass::NoPulse), 28);
    }
}
