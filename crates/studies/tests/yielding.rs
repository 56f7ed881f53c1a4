//! The yielding study (`pound studies run yielding`, and its stronger pair
//! `yielding-strong`) in its quick form (one record, 12 s, the `quick_pga` levels of the
//! definition): it runs, and its tables obey the physics they rest on:
//! - with one record the strength of every story is that record's own elastic demand at the
//!   reference PGA, and the elastic response without contact is linear in the PGA, so the
//!   elastic ductility demand without contact is R = PGA / reference PGA exactly (to the 6
//!   significant digits the yield shears are written with);
//! - at the lowest level (R < 1 by the definition, and no impact) nothing yields, so every
//!   inelastic method gives the elastic answer to its integration tolerance, and the domain
//!   of validity table finds no departure there;
//! - the summary tables are the case rows they summarise.

mod common;
use common::{quick_study, read_csv, TempDir, STUDIES};

fn num(s: &str) -> f64 {
    s.parse::<f64>()
        .unwrap_or_else(|_| panic!("`{s}` is not a number"))
}

#[test]
fn quick_yielding_study_obeys_its_closed_forms() {
    check_quick("yielding");
}

/// The stronger pair (strength at the median elastic demand at 0.40 g), run by name.
#[test]
fn quick_yielding_strong_study_obeys_its_closed_forms() {
    check_quick("yielding-strong");
}

fn check_quick(study: &str) {
    let d = TempDir::new(study);
    let dir = quick_study(&d, study);
    for f in [
        "yielding.csv",
        "yielding.md",
        "yielding_all.csv",
        "yielding_strength.csv",
        "yielding_validity.csv",
        "yielding_cpu.csv",
        "yielding_validity.png",
        "yielding_validity.svg",
        "summary.md",
        "cases.csv",
        "peaks.csv",
    ] {
        assert!(dir.join(f).is_file(), "{f} missing");
    }
    let def: toml::Table = toml::from_str(
        &std::fs::read_to_string(std::path::Path::new(STUDIES).join(format!("{study}.toml")))
            .unwrap(),
    )
    .unwrap();
    let reference = def["reference_pga"].as_float().unwrap();
    let tolerance = def["tolerance"].as_float().unwrap();
    let levels: Vec<f64> = def["quick_pga"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_float().unwrap())
        .collect();
    let inelastic: Vec<String> = def["inelastic"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_str().unwrap().to_string())
        .collect();
    let (lo, hi) = (levels[0], levels[levels.len() - 1]);
    assert!(
        lo / reference < 1.0,
        "the definition's first quick level must be below the strength"
    );

    let all = read_csv(&dir.join("yielding_all.csv"));
    let h = &all[0];
    let col = |name: &str| {
        h.iter()
            .position(|x| x == name)
            .unwrap_or_else(|| panic!("no column {name}"))
    };
    let rows = |method: &str, pga: f64, pounding: bool| -> Vec<&Vec<String>> {
        all[1..]
            .iter()
            .filter(|r| {
                r[col("method")] == method
                    && num(&r[col("pga_g")]) == pga
                    && r[col("pounding")] == pounding.to_string()
            })
            .collect()
    };
    // Every method at every level with and without pounding, one record, all finished.
    assert_eq!(all.len() - 1, levels.len() * (1 + inelastic.len()) * 2);
    assert!(all[1..].iter().all(|r| r[col("status")] == "ok"));

    // (1) Elastic ductility demand without contact = R at every level.
    for &pga in &levels {
        let r = rows("momentum", pga, false);
        assert_eq!(r.len(), 1);
        for c in ["ductility_b1", "ductility_b2"] {
            let mu = num(&r[0][col(c)]);
            let want = pga / reference;
            assert!(
                (mu / want - 1.0).abs() < 1e-5,
                "{pga} g {c}: elastic ductility {mu}, R = {want}"
            );
        }
    }
    // And R = 8 > 1: the elastic demand exceeds the strength at the top level.
    assert!(hi / reference > 1.0);

    // (2) Lowest level: no impact, nothing yields, the inelastic answers are the elastic ones.
    let el = rows("momentum", lo, true);
    assert_eq!(
        el[0][col("impacts")],
        "0",
        "the first quick level should not pound"
    );
    for m in &inelastic {
        for pounding in [true, false] {
            let (e, i) = (rows("momentum", lo, pounding), rows(m, lo, pounding));
            assert_eq!(i.len(), 1);
            for b in ["b1", "b2"] {
                let mu = num(&i[0][col(&format!("ductility_{b}"))]);
                assert!(mu < 1.0, "{m} at {lo} g yields: ductility {mu}");
                let (de, di) = (
                    num(&e[0][col(&format!("drift_max_{b}_m"))]),
                    num(&i[0][col(&format!("drift_max_{b}_m"))]),
                );
                // The global error of the adaptive runs, within 10 × their tolerance
                // (measured 0.12 × tolerance).
                assert!(
                    (di / de - 1.0).abs() < 10.0 * tolerance,
                    "{m} at {lo} g, pounding {pounding}, {b}: drift {di} vs elastic {de}"
                );
            }
            // No plastic flow, no hysteretic energy (when the method reports it).
            let hy = &i[0][col("hysteretic_energy_J")];
            if !hy.is_empty() {
                assert_eq!(num(hy), 0.0, "{m} at {lo} g: hysteretic energy");
            }
        }
    }
    let val = read_csv(&dir.join("yielding_validity.csv"));
    let vh = &val[0];
    let vcol = |name: &str| vh.iter().position(|x| x == name).unwrap();
    let at_lo: Vec<&Vec<String>> = val[1..]
        .iter()
        .filter(|r| num(&r[vcol("PGA (g)")]) == lo)
        .collect();
    assert_eq!(at_lo.len(), 3 * inelastic.len());
    for r in at_lo {
        assert_eq!(num(&r[vcol("share e > band")]), 0.0, "{r:?}");
        assert!(num(&r[vcol("e median")]) < 10.0 * tolerance, "{r:?}");
    }

    // (3) The response table is the case rows (one record: median = the value).
    let t = read_csv(&dir.join("yielding.csv"));
    let th = &t[0];
    let tcol = |name: &str| th.iter().position(|x| x == name).unwrap();
    assert_eq!(t.len() - 1, levels.len() * (1 + inelastic.len()) * 2);
    for r in &t[1..] {
        let pga = num(&r[tcol("PGA (g)")]);
        let pounding = r[tcol("pounding")] == "yes";
        let method = if r[tcol("method")].starts_with("momentum") {
            "momentum".to_string()
        } else {
            inelastic
                .iter()
                .find(|m| r[tcol("method")].starts_with(m.as_str()))
                .cloned()
                .unwrap_or_else(|| panic!("method of {r:?}"))
        };
        let c = rows(&method, pga, pounding);
        assert_eq!(r[tcol("n")], "1");
        let drift = num(&r[tcol("drift b1 median (m)")]);
        assert!((drift - num(&c[0][col("drift_max_b1_m")])).abs() <= 0.5e-4);
        let mu = num(&r[tcol("ductility b2 median")]);
        assert!((mu - num(&c[0][col("ductility_b2")])).abs() <= 0.5e-2);
        if pounding {
            let a = num(&r[tcol("amp. b1 median")]);
            assert!((a - num(&c[0][col("amplification_b1")])).abs() <= 0.5e-3);
        }
    }
    let summary = std::fs::read_to_string(dir.join("summary.md")).unwrap();
    assert!(summary.contains("**Quick run**"), "{summary}");
    assert!(summary.contains("yielding_validity.png"));
}

/// A definition the study cannot use is refused before anything runs (exit 2), naming the
/// file and the key; so is the momentum method as an "inelastic" method.
#[test]
fn bad_yielding_definitions_are_refused_naming_the_key() {
    let root = STUDIES;
    let good = std::fs::read_to_string(format!("{root}/yielding.toml"))
        .unwrap()
        .replace(
            "\"paper/scene-aligned.toml\"",
            &format!("\"{root}/paper/scene-aligned.toml\""),
        )
        .replace("\"../data/", &format!("\"{root}/../data/"));
    let inelastic_line = good
        .lines()
        .find(|l| l.starts_with("inelastic"))
        .unwrap()
        .to_string();
    let pga_line = good
        .lines()
        .find(|l| l.starts_with("quick_pga"))
        .unwrap()
        .to_string();
    for (bad, words) in [
        (
            good.replace(&pga_line, "quick_pga = [0.6, 0.05]"),
            &["yielding.toml", "quick_pga", "increasing"][..],
        ),
        (
            good.replace(&inelastic_line, "inelastic = [\"momentum\"]"),
            &["yielding.toml", "inelastic", "momentum"][..],
        ),
        (
            good.replace(&inelastic_line, "inelastic = [\"newmark\"]"),
            &["yielding.toml", "newmark"][..],
        ),
        (
            format!("{good}\nstrength = 3\n"),
            &["yielding.toml", "strength"][..],
        ),
        (
            good.replace(&inelastic_line, "inelastic = [\"gap\", \"gap\"]"),
            &["yielding.toml", "inelastic", "twice"][..],
        ),
        (
            good.replace("hardening_ratio = 0.02", "hardening_ratio = 1.0"),
            &["yielding.toml", "hardening_ratio", "[0, 1)"][..],
        ),
    ] {
        let d = TempDir::new("yielding-bad");
        d.write("yielding.toml", &bad);
        let out = d.path("results");
        let o = common::quick_run(
            "yielding",
            d.path("").to_str().unwrap(),
            out.to_str().unwrap(),
        );
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{err}");
        for w in words {
            assert!(err.contains(w), "{err:?} should name {w:?}");
        }
        assert!(!out.exists(), "nothing written");
        assert!(o.stdout.is_empty());
    }
}
