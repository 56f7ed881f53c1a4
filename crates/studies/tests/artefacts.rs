//! The artefacts of the studies, checked on a quick run of every study written to an
//! arbitrary `--out` folder (and, for the links, on the committed `results/` tree):
//! - every SVG is self-contained (no `<text>` that a viewer would set in a system font, or
//!   else an embedded `@font-face`; every glyph reference resolves) and legible: its smallest
//!   text has an em of at least 0.0332 × the figure width, i.e. 8 pt when printed 85 mm wide;
//! - every image link of every `summary.md` resolves relative to the summary's own folder;
//! - every `cases.csv` is tidy: one name per column, rectangular, units on dimensional
//!   columns;
//! - no written text hedges a plural as "record(s)": a count says "1 record" or "2 records".

mod common;

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

use common::{pound, TempDir};

/// 8 pt at 85 mm print width: 8 × 25.4 / 72 mm ÷ 85 mm.
const MIN_EM_PER_WIDTH: f64 = 8.0 * 25.4 / 72.0 / 85.0;

fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// Units per em of the committed font, read from its `head` table (offset 18).
fn font_units_per_em() -> f64 {
    let f = std::fs::read(repo().join("data/fonts/DejaVuSans.ttf")).unwrap();
    let u16_at = |o: usize| u16::from_be_bytes([f[o], f[o + 1]]) as usize;
    let u32_at = |o: usize| u32::from_be_bytes([f[o], f[o + 1], f[o + 2], f[o + 3]]) as usize;
    let tables = u16_at(4);
    let head = (0..tables)
        .map(|i| 12 + 16 * i)
        .find(|&r| &f[r..r + 4] == b"head")
        .map(|r| u32_at(r + 8))
        .expect("font has a head table");
    u16_at(head + 18) as f64
}

fn files(dir: &Path, name: &dyn Fn(&str) -> bool, out: &mut Vec<PathBuf>) {
    for e in std::fs::read_dir(dir).unwrap() {
        let p = e.unwrap().path();
        let n = p.file_name().unwrap().to_string_lossy().into_owned();
        if p.is_dir() {
            if n != "cases" {
                files(&p, name, out);
            }
        } else if name(&n) {
            out.push(p);
        }
    }
}

fn find(dir: &Path, name: &dyn Fn(&str) -> bool) -> Vec<PathBuf> {
    let mut v = Vec::new();
    files(dir, name, &mut v);
    v.sort();
    v
}

/// Value of attribute `name` in the tag text `tag`.
fn attr<'a>(tag: &'a str, name: &str) -> Option<&'a str> {
    let key = format!(" {name}=\"");
    let a = tag.find(&key)? + key.len();
    let b = tag[a..].find('"')? + a;
    Some(&tag[a..b])
}

/// Every start tag `<name …>` of `svg`.
fn tags<'a>(svg: &'a str, name: &str) -> Vec<&'a str> {
    let open = format!("<{name} ");
    let mut v = Vec::new();
    let mut rest = svg;
    while let Some(a) = rest.find(&open) {
        let b = rest[a..].find('>').unwrap() + a;
        v.push(&rest[a..=b]);
        rest = &rest[b..];
    }
    v
}

/// Checks one SVG; returns its smallest em / width.
fn check_svg(path: &Path, upem: f64) -> f64 {
    let svg = std::fs::read_to_string(path).unwrap();
    let name = path.display();
    let root = tags(&svg, "svg");
    let width: f64 = attr(root[0], "width").unwrap().parse().unwrap();
    assert!(width > 0.0, "{name}: width");
    let embedded = svg.contains("@font-face");
    let mut ems: Vec<f64> = Vec::new();
    for t in tags(&svg, "text") {
        assert!(
            embedded,
            "{name}: <text> set in a system font (no embedded @font-face): {t}"
        );
        let size = attr(t, "font-size").expect("font-size on text");
        ems.push(size.trim_end_matches("px").parse().unwrap());
    }
    // Text drawn as glyph outlines: <g aria-label=… transform="… scale(s -s)"> of <use>s,
    // em = s × units per em.
    let defined: BTreeSet<&str> = tags(&svg, "path")
        .into_iter()
        .filter_map(|t| attr(t, "id"))
        .collect();
    let groups: Vec<&str> = tags(&svg, "g")
        .into_iter()
        .filter(|t| attr(t, "aria-label").is_some())
        .collect();
    for g in &groups {
        let tr = attr(g, "transform").unwrap_or_else(|| panic!("{name}: {g}"));
        let s = tr
            .split("scale(")
            .nth(1)
            .unwrap_or_else(|| panic!("{name}: {g}"));
        let sx: f64 = s.split([' ', ',', ')']).next().unwrap().parse().unwrap();
        ems.push(sx * upem);
    }
    for u in tags(&svg, "use") {
        let href = attr(u, "href").or_else(|| attr(u, "xlink:href")).unwrap();
        let id = href.trim_start_matches('#');
        assert!(defined.contains(id), "{name}: glyph {href} is not defined");
    }
    assert!(
        !ems.is_empty(),
        "{name}: no text found (titles, ticks and captions expected)"
    );
    let min = ems.iter().copied().fold(f64::INFINITY, f64::min);
    min / width
}

/// Image links `![alt](target)` of a markdown text.
fn image_links(md: &str) -> Vec<String> {
    let mut v = Vec::new();
    let mut rest = md;
    while let Some(a) = rest.find("![") {
        rest = &rest[a + 2..];
        let Some(close) = rest.find("](") else { break };
        let after = &rest[close + 2..];
        let Some(end) = after.find(')') else { break };
        let target = after[..end]
            .split_whitespace()
            .next()
            .unwrap_or("")
            .trim_matches(['<', '>']);
        v.push(target.to_string());
        rest = &after[end..];
    }
    v
}

/// Every image link of every `summary.md` under `root` names an existing file relative to
/// the summary's folder; returns the number of links checked.
/// Panics at the first "word(s)" of the text (a letter right before "(s)"; a unit such as
/// "t (s)" has a space); returns the number of files read.
fn check_plurals(files: &[PathBuf]) -> usize {
    for f in files {
        let text = std::fs::read_to_string(f).unwrap();
        if let Some(at) = text
            .match_indices("(s)")
            .map(|(i, _)| i)
            .find(|&i| text[..i].ends_with(|c: char| c.is_ascii_alphabetic()))
        {
            let from = text[..at].rfind(char::is_whitespace).map_or(0, |w| w + 1);
            panic!(
                "{}: \"{}(s)\" hedges a plural",
                f.display(),
                &text[from..at]
            );
        }
    }
    files.len()
}

fn check_links(root: &Path) -> usize {
    let summaries = find(root, &|n| n == "summary.md");
    assert!(
        !summaries.is_empty(),
        "no summary.md under {}",
        root.display()
    );
    let mut n = 0;
    for s in summaries {
        let md = std::fs::read_to_string(&s).unwrap();
        let dir = s.parent().unwrap();
        for l in image_links(&md) {
            assert!(
                !l.contains("://") && !Path::new(&l).is_absolute(),
                "{}: link {l} is not relative",
                s.display()
            );
            assert!(
                dir.join(&l).is_file(),
                "{}: image {l} does not exist relative to {}",
                s.display(),
                dir.display()
            );
            n += 1;
        }
    }
    n
}

/// Dimensional quantities a column name may mention, with the unit suffixes allowed.
const UNITS: &[(&str, &[&str])] = &[
    ("energy", &["_J"]),
    ("penetration", &["_m"]),
    ("closure", &["_m"]),
    ("displacement", &["_m"]),
    ("drift", &["_m"]),
    ("stiffness", &["_N_per_m"]),
    ("shear", &["_N"]),
    ("force", &["_N"]),
    ("wall", &["_s"]),
    ("duration", &["_s"]),
    ("time_step", &["_s"]),
    ("velocity", &["_m_per_s"]),
    ("acceleration", &["_m_per_s2", "_g"]),
    ("pga", &["_g", "_m_per_s2"]),
];

fn check_cases_csv(path: &Path) {
    let name = path.display();
    let mut r = csv::Reader::from_path(path).unwrap();
    let header: Vec<String> = r.headers().unwrap().iter().map(String::from).collect();
    let mut seen = BTreeSet::new();
    for h in &header {
        assert!(seen.insert(h.as_str()), "{name}: column {h} twice");
        let lower = h.to_lowercase();
        for (what, suffixes) in UNITS {
            if lower.contains(what) {
                assert!(
                    suffixes.iter().any(|s| h.ends_with(s)),
                    "{name}: column {h} ({what}) has no unit suffix {suffixes:?}"
                );
            }
        }
        // gap_m, gap_stiffness_N_per_m: a gap column is a length unless it says otherwise.
        if lower.starts_with("gap") && !lower.contains("stiffness") {
            assert!(
                h.ends_with("_m"),
                "{name}: column {h} has no unit suffix _m"
            );
        }
    }
    for f in ["case_id", "status", "error_kind", "wall_s"] {
        assert!(header.iter().any(|h| h == f), "{name}: no column {f}");
    }
    let mut rows = 0;
    for rec in r.records() {
        // The reader is strict: a row with another number of fields is an error.
        let rec = rec.unwrap_or_else(|e| panic!("{name}: {e}"));
        assert_eq!(rec.len(), header.len(), "{name}: ragged row");
        rows += 1;
    }
    assert!(rows > 0, "{name}: no rows");
}

#[test]
fn quick_run_artefacts_are_legible_linked_and_tidy() {
    let out = TempDir::new("artefacts");
    let dest = out.path("some/where else");
    let o = pound(&[
        "studies".as_ref(),
        "run".as_ref(),
        "--all".as_ref(),
        "--quick".as_ref(),
        "--fresh".as_ref(),
        "--out".as_ref(),
        dest.as_os_str(),
        "--studies-dir".as_ref(),
        repo().join("studies").as_os_str(),
    ]);
    assert!(
        o.status.success(),
        "quick run failed: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    let upem = font_units_per_em();
    let svgs = find(&dest, &|n| n.ends_with(".svg"));
    let n_studies = studies::studies::NAMES.len();
    assert!(
        svgs.len() >= n_studies,
        "one figure per study at least: {svgs:?}"
    );
    for s in &svgs {
        let ratio = check_svg(s, upem);
        assert!(
            ratio >= MIN_EM_PER_WIDTH,
            "{}: smallest text {:.4} × width < {MIN_EM_PER_WIDTH:.4} (under 8 pt at 85 mm)",
            s.display(),
            ratio
        );
        // Every SVG has its PNG.
        assert!(s.with_extension("png").is_file(), "{}", s.display());
    }
    assert!(check_links(&dest) >= n_studies);
    let cases = find(&dest, &|n| n == "cases.csv");
    assert_eq!(cases.len(), n_studies, "{cases:?}");
    for c in &cases {
        check_cases_csv(c);
    }
    let texts = find(&dest, &|n| {
        n.ends_with(".md") || n.ends_with(".csv") || n.ends_with(".json")
    });
    assert!(check_plurals(&texts) > n_studies);
}

/// In the committed data tables a record has one name: as many distinct `record` values as
/// distinct `record_file` values (the component alone, e.g. "032", repeats across records).
#[test]
fn committed_cases_name_each_record_once() {
    let results = repo().join("results");
    let mut checked = 0;
    for c in find(&results, &|n| n == "cases.csv") {
        let mut r = csv::Reader::from_path(&c).unwrap();
        let h = r.headers().unwrap().clone();
        let (Some(ir), Some(ifile)) = (
            h.iter().position(|x| x == "record"),
            h.iter().position(|x| x == "record_file"),
        ) else {
            panic!("{}: no record / record_file columns", c.display())
        };
        let mut pairs = BTreeSet::new();
        for row in r.records() {
            let row = row.unwrap();
            pairs.insert((row[ir].to_string(), row[ifile].to_string()));
        }
        let names: BTreeSet<_> = pairs.iter().map(|p| &p.0).collect();
        let files: BTreeSet<_> = pairs.iter().map(|p| &p.1).collect();
        assert_eq!(
            names.len(),
            files.len(),
            "{}: record names are ambiguous",
            c.display()
        );
        checked += 1;
    }
    assert!(checked >= 8, "{checked} cases.csv checked");
}

#[test]
fn committed_texts_count_their_nouns() {
    let results = repo().join("results");
    let texts = find(&results, &|n| n.ends_with(".md") || n.ends_with(".csv"));
    assert!(check_plurals(&texts) >= 30);
}

#[test]
fn committed_summaries_link_existing_images() {
    let results = repo().join("results");
    if results.is_dir() {
        assert!(check_links(&results) >= 7);
    }
}

#[test]
fn checks_catch_bad_artefacts() {
    // The checks themselves: a system-font <text>, a small text, a broken link, a ragged or
    // doubled or unit-less column are all refused.
    let t = TempDir::new("artefact-checks");
    let upem = font_units_per_em();
    let text = t.write(
        "a.svg",
        r#"<svg width="1000" height="500"><text x="1" y="2" font-size="40">x</text></svg>"#,
    );
    assert!(std::panic::catch_unwind(|| check_svg(&text, upem)).is_err());
    let small = t.write(
        "b.svg",
        &format!(
            r##"<svg width="1000" height="500"><defs><path id="g1" d="M0 0Z"/></defs><g aria-label="x" transform="translate(1 2) scale({} {})"><use href="#g1" x="0"/></g></svg>"##,
            20.0 / upem,
            -20.0 / upem
        ),
    );
    assert!((check_svg(&small, upem) - 0.02).abs() < 1e-9);
    let md = t.write("summary.md", "![a](missing.png)\n");
    assert!(std::panic::catch_unwind(|| check_links(&t.0)).is_err());
    std::fs::remove_file(md).unwrap();
    for bad in [
        "case_id,status,error_kind,wall_s,record,record\n1,ok,,1,a,b\n",
        "case_id,status,error_kind,wall_s,energy_input\n1,ok,,1,2\n",
        "case_id,status,error_kind,wall_s,gap\n1,ok,,1,2\n",
        "case_id,status,error_kind,wall_s\n1,ok,,1,2\n",
    ] {
        let p = t.write("cases.csv", bad);
        assert!(
            std::panic::catch_unwind(|| check_cases_csv(&p)).is_err(),
            "{bad}"
        );
    }
    let hedged = t.write("hedge.md", "Of 2 record(s) at t (s) = 1.\n");
    assert!(std::panic::catch_unwind(|| check_plurals(&[hedged])).is_err());
    let plain = t.write("plain.md", "Of 2 records at t (s) = 1 (see (s)).\n");
    assert_eq!(check_plurals(&[plain]), 1);
    let good = t.write(
        "cases.csv",
        "case_id,status,error_kind,wall_s,gap_m,energy_input_J\n1,ok,,1,0.1,2\n",
    );
    check_cases_csv(&good);
}
