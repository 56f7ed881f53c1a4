//! Human-readable tables for the command line.

use solvers::RunOutput;
use structure::scene::UnmodelledFacing;
use structure::{GroundMotion, Modes, Scene};

use crate::table::count;

/// The modes of every building, in scene order: solved once each, for the building's rows
/// and for every contact that touches it (an aligned pair of 1000-story buildings has 1000
/// contacts).
fn building_modes(scene: &Scene) -> Result<Vec<Modes>, structure::ModelError> {
    scene.buildings.iter().map(|b| b.modes()).collect()
}

/// `pound modes` table.
pub fn modes_table(scene: &Scene) -> Result<String, structure::ModelError> {
    let modes = building_modes(scene)?;
    let mut s = String::new();
    for (b, m) in scene.buildings.iter().zip(&modes) {
        let f = m.frequencies_hz();
        let t = m.periods();
        let e = m.effective_mass_ratios();
        s.push_str(&format!(
            "{} ({}, total mass {:.4e} kg)\n",
            b.name,
            count(b.n_floors(), "floor", "floors"),
            b.total_mass()
        ));
        // The reference frequencies are the scene's `reference_frequencies_hz` (for the
        // paper scene, the paper's).
        s.push_str("  mode   f (Hz) reference (Hz)  diff (%)    T (s)  eff. mass   cumul.\n");
        let mut cum = 0.0;
        for i in 0..m.n_modes() {
            cum += e[i];
            let (p, d) = match b.reference_frequencies_hz.get(i) {
                Some(r) => (
                    format!("{r:14.3}"),
                    // Rounded to the digits shown first, so round-off prints +0.0000, not -0.0000.
                    format!("{:+9.4}", (1e6 * (f[i] - r) / r).round() / 1e4 + 0.0),
                ),
                None => (format!("{:>14}", "-"), format!("{:>9}", "")),
            };
            s.push_str(&format!(
                "  {:4} {:8.4} {} {} {:8.4} {:10.4} {:8.4}\n",
                i + 1,
                f[i],
                p,
                d,
                t[i],
                e[i],
                cum
            ));
        }
    }
    for (ci, c) in scene.contacts.iter().enumerate() {
        let (bl, br) = (&scene.buildings[c.left], &scene.buildings[c.right]);
        let rl = modes[c.left].contact_flexibility(c.left_dof);
        // A wall has no modes: its column stays empty.
        let rr = if c.wall {
            vec![]
        } else {
            modes[c.right].contact_flexibility(c.right_dof)
        };
        let right = if c.wall {
            "the wall".to_string()
        } else {
            format!("{} floor {}", br.name, c.right_dof + 1)
        };
        s.push_str(&format!(
            "contact {ci}: {} floor {} <-> {right}, gap {} m, c_r {}\n  r_N (contact flexibility fraction kept by N modes)\n  N     left     right\n",
            bl.name,
            c.left_dof + 1,
            c.gap,
            c.restitution
        ));
        for n in 0..rl.len().max(rr.len()) {
            let g = |r: &Vec<f64>| {
                r.get(n)
                    .map_or("      -".to_string(), |v| format!("{v:8.4}"))
            };
            s.push_str(&format!("  {:<3} {} {}\n", n + 1, g(&rl), g(&rr)));
        }
    }
    Ok(s)
}

/// `pound modes --json` document.
pub fn modes_json(scene: &Scene) -> Result<serde_json::Value, structure::ModelError> {
    let modes = building_modes(scene)?;
    let mut buildings = Vec::new();
    for (b, m) in scene.buildings.iter().zip(&modes) {
        buildings.push(serde_json::json!({
            "name": b.name,
            "floors": b.n_floors(),
            "total_mass_kg": b.total_mass(),
            "masses_kg": b.masses,
            "story_stiffness_n_per_m": b.story_stiffness,
            "frequencies_hz": m.frequencies_hz(),
            "reference_frequencies_hz": b.reference_frequencies_hz,
            "periods_s": m.periods(),
            "effective_mass_ratios": m.effective_mass_ratios(),
            "participation_factors": m.participation,
        }));
    }
    let mut contacts = Vec::new();
    for c in &scene.contacts {
        let rl = modes[c.left].contact_flexibility(c.left_dof);
        if c.wall {
            // A wall: no right floor and no right flexibility.
            contacts.push(serde_json::json!({
                "left": scene.buildings[c.left].name, "left_floor": c.left_dof + 1,
                "right": structure::scene::WALL,
                "gap_m": c.gap, "restitution": c.restitution,
                "r_n_left": rl,
            }));
            continue;
        }
        let rr = modes[c.right].contact_flexibility(c.right_dof);
        contacts.push(serde_json::json!({
            "left": scene.buildings[c.left].name, "left_floor": c.left_dof + 1,
            "right": scene.buildings[c.right].name, "right_floor": c.right_dof + 1,
            "gap_m": c.gap, "restitution": c.restitution,
            "r_n_left": rl, "r_n_right": rr,
        }));
    }
    Ok(serde_json::json!({
        "scene": scene.name,
        "buildings": buildings,
        "contacts": contacts,
        "unmodelled": scene.unmodelled_facings(),
    }))
}

/// Peak ground velocity and displacement alongside the basic record facts.
pub fn record_json(gm: &GroundMotion) -> serde_json::Value {
    serde_json::json!({
        "name": gm.name,
        "npts": gm.npts(),
        "dt_s": gm.dt,
        "duration_s": gm.duration(),
        "pga_g": gm.pga() / structure::G,
        "pga_m_per_s2": gm.pga(),
        "pgv_m_per_s": gm.pgv(),
        "pgd_m": gm.pgd(),
    })
}

/// `pound record` table.
pub fn record_table(gm: &GroundMotion) -> String {
    format!(
        "record    {}\nnpts      {}\ndt        {} s\nduration  {:.3} s\nPGA       {:.4} g ({:.4} m/s^2)\nPGV       {:.4} m/s\nPGD       {:.4} m\n",
        gm.name,
        gm.npts(),
        gm.dt,
        gm.duration(),
        gm.pga() / structure::G,
        gm.pga(),
        gm.pgv(),
        gm.pgd()
    )
}

/// Summary of a run for stdout.
/// Amplification factors per building and story: peak story shear with contact over the
/// peak story shear of the same model without contact (same method and options). Where the
/// latter is 0 (a building at rest without ground motion) the factor is not finite: the
/// summary prints –, the JSON null.
pub fn amplification(run: &RunOutput, without: &RunOutput) -> Vec<Vec<f64>> {
    run.buildings
        .iter()
        .zip(&without.buildings)
        .map(|(a, b)| {
            a.story_shear_max
                .iter()
                .zip(&b.story_shear_max)
                .map(|(x, y)| x / y)
                .collect()
        })
        .collect()
}

/// The `pound run --out` document: the run's result plus what was run (program version,
/// the `--set` overrides as given, the record as resolved) and the amplification factors.
pub fn run_json(
    scene: &Scene,
    overrides: &[String],
    run: &RunOutput,
    amplification: Option<&[Vec<f64>]>,
) -> serde_json::Value {
    let mut v = serde_json::to_value(run).expect("a run serialises");
    let obj = v.as_object_mut().expect("an object");
    obj.insert("version".into(), env!("CARGO_PKG_VERSION").into());
    obj.insert("overrides".into(), overrides.into());
    obj.insert("resolved_scene".into(), resolved_scene(scene));
    if let Some(f) = &scene.file {
        let f = std::fs::canonicalize(f).unwrap_or_else(|_| f.clone());
        obj.insert("scene_file".into(), f.display().to_string().into());
    }
    if let (Some(g), Some(src)) = (&scene.ground, &scene.ground_source) {
        let file = std::fs::canonicalize(&src.file).unwrap_or_else(|_| src.file.clone());
        obj.insert(
            "record".into(),
            serde_json::json!({
                "file": file.display().to_string(),
                "pga_g": src.pga_g,
                "scale": src.factor,
                "dt_s": g.dt,
                "npts": g.npts(),
            }),
        );
    }
    if let Some(a) = amplification {
        let per: Vec<serde_json::Value> = run
            .buildings
            .iter()
            .zip(a)
            .map(|(b, f)| serde_json::json!({"name": b.name, "story_shear": f}))
            .collect();
        obj.insert("amplification".into(), per.into());
    }
    v
}

/// Most entries of the scene file's `contacts` that [`run_header`] lists one a line.
const CONTACT_ENTRIES_LISTED: usize = 5;

/// The head of the `pound run` summary: the record as run (file name, PGA, the duration
/// analysed) and the contacts as resolved, one line per entry of the scene file's `contacts`
/// (an entry with `floors = "aligned"` is one line with its count of floor pairs).
pub fn run_header(scene: &Scene) -> String {
    let mut s = String::new();
    match (&scene.ground, &scene.ground_source) {
        (Some(g), Some(src)) => {
            let name = src.file.file_name().map_or_else(
                || src.file.display().to_string(),
                |n| n.to_string_lossy().into_owned(),
            );
            let of = if (scene.duration - g.duration()).abs() > 1e-9 * g.duration().max(1.0) {
                format!(" (the record: {:.2} s)", g.duration())
            } else {
                String::new()
            };
            s.push_str(&format!(
                "record: {name}, PGA {:.3} g as run, duration {:.2} s{of}\n",
                g.pga() / structure::G,
                scene.duration
            ));
        }
        (Some(g), None) => s.push_str(&format!(
            "record: (given in code), PGA {:.3} g as run, duration {:.2} s\n",
            g.pga() / structure::G,
            scene.duration
        )),
        (None, _) => s.push_str(&format!(
            "record: none (free vibration), duration {:.2} s\n",
            scene.duration
        )),
    }
    // The contacts of each entry, in order of first appearance.
    let lines: Vec<String> = scene
        .contact_entries()
        .iter()
        .map(|(_, group)| contact_entry_line(scene, group))
        .collect();
    match lines.len() {
        0 => s.push_str("contacts: none\n"),
        1 => s.push_str(&format!("contacts: {}\n", lines[0])),
        n => {
            s.push_str(&format!(
                "contacts: {} in {n} scene entries\n",
                scene.contacts.len()
            ));
            for l in lines.iter().take(CONTACT_ENTRIES_LISTED) {
                s.push_str(&format!("  {l}\n"));
            }
            if n > CONTACT_ENTRIES_LISTED {
                s.push_str(&format!(
                    "  … {} more (every contact in `resolved_scene` of --out)\n",
                    count(n - CONTACT_ENTRIES_LISTED, "entry", "entries")
                ));
            }
        }
    }
    s
}

/// One entry of the scene file's `contacts` as resolved: its floor pair, or its count of
/// floor pairs, the gap and c_r (`contacts`: the indices of its contacts, at least one).
fn contact_entry_line(scene: &Scene, contacts: &[usize]) -> String {
    let cs: Vec<&structure::Contact> = contacts.iter().map(|&i| &scene.contacts[i]).collect();
    let c = cs[0];
    let left = &scene.buildings[c.left].name;
    let right = |c: &structure::Contact| {
        if c.wall {
            "the wall".to_string()
        } else {
            format!(
                "{} floor {}",
                scene.buildings[c.right].name,
                c.right_dof + 1
            )
        }
    };
    let range = |v: Vec<f64>, unit: &str| {
        let (lo, hi) = v
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &x| {
                (a.min(x), b.max(x))
            });
        if lo == hi {
            format!("{lo}{unit}")
        } else {
            format!("{lo} … {hi}{unit}")
        }
    };
    let gap = range(cs.iter().map(|c| c.gap).collect(), " m");
    let cr = range(cs.iter().map(|c| c.restitution).collect(), "");
    let pairs = if let [only] = cs[..] {
        format!("{left} floor {} – {}", only.left_dof + 1, right(only))
    } else {
        let last = cs[cs.len() - 1];
        if c.wall {
            format!(
                "{left} floors {} … {} – the wall ({} contacts)",
                c.left_dof + 1,
                last.left_dof + 1,
                cs.len()
            )
        } else {
            format!(
                "{left} – {} at {} floor pairs ({}–{} … {}–{})",
                scene.buildings[c.right].name,
                cs.len(),
                c.left_dof + 1,
                c.right_dof + 1,
                last.left_dof + 1,
                last.right_dof + 1
            )
        }
    };
    format!("{pairs}, gap {gap}, c_r {cr}")
}

pub fn run_summary(scene: &Scene, run: &RunOutput, amplification: Option<&[Vec<f64>]>) -> String {
    let mut s = run_header(scene);
    s.push_str(&format!(
        "{} — method {} ({})\n",
        scene.name, run.method, run.settings
    ));
    for (bi, b) in run.buildings.iter().enumerate() {
        let amp = amplification.and_then(|a| a.get(bi));
        let mu = b.ductility.as_deref();
        s.push_str(&format!(
            "{}\n  story  shear max (MN)  floor disp max (m)  drift max (m){}{}\n",
            b.name,
            if mu.is_some() {
                "  ductility  residual drift (m)"
            } else {
                ""
            },
            if amp.is_some() { "  amplification" } else { "" }
        ));
        for j in (0..b.story_shear_max.len()).rev() {
            s.push_str(&format!(
                "  {:5} {:16.4} {:19.5} {:14.5}",
                j + 1,
                b.story_shear_max[j] / 1e6,
                b.floor_displacement_max[j],
                b.story_drift_max.get(j).copied().unwrap_or(f64::NAN)
            ));
            if let Some(mu) = mu {
                s.push_str(&format!(
                    " {:10.3} {:18.5}",
                    mu[j],
                    b.residual_drift.get(j).copied().unwrap_or(f64::NAN)
                ));
            }
            if let Some(a) = amp {
                if a[j].is_finite() {
                    s.push_str(&format!(" {:14.3}", a[j]));
                } else {
                    s.push_str(&format!(" {:>14}", "–"));
                }
            }
            s.push('\n');
        }
        if amp.is_some_and(|a| a.iter().any(|x| !x.is_finite())) {
            s.push_str(
                "  –: no amplification where the story carries no shear without contact (e.g. a building at rest without ground motion)\n",
            );
        }
        if let Some(eh) = b.hysteretic_energy {
            s.push_str(&format!("  hysteretic energy (J): {eh:.4e}\n"));
        }
    }
    s.push_str(&format!("impacts: {}", run.impacts.len()));
    if let (Some(first), Some(last)) = (run.impacts.first(), run.impacts.last()) {
        s.push_str(&format!(
            " (first at {:.4} s, last at {:.4} s)",
            first.time, last.time
        ));
    }
    s.push('\n');
    for p in &run.persistent_contacts {
        s.push_str(&format!(
            "persistent contact {}: {:.4} … {:.4} s ({})\n",
            p.contact, p.start, p.end, p.released_by
        ));
    }
    s.push_str(&overlap_lines(run));
    let e = &run.energy;
    s.push_str(&format!(
        "energy (J): initial {:.4e}, input {:.4e}, damping {:.4e}, contact {:.4e}, hysteretic {:.4e}, final {:.4e}, balance error {:.3e}{}\n",
        e.initial,
        e.input,
        e.damping,
        e.contact,
        e.hysteretic,
        e.final_,
        e.balance_error,
        // Newmark: how much of the balance error its Newton residuals' work explains.
        e.residual_work
            .map_or(String::new(), |w| format!(" (Newton residuals' work {w:.3e})"))
    ));
    let st = &run.stats;
    s.push_str(&format!(
        "stats: {} ({} rejected), {}, {}, {}{}, {:.3} ms\n",
        count(st.steps, "step", "steps"),
        st.rejected_steps,
        count(st.events, "event", "events"),
        count(st.impacts, "impact", "impacts"),
        if st.story_kinks > 0 {
            format!("{}, ", count(st.story_kinks, "story kink", "story kinks"))
        } else {
            String::new()
        },
        count(st.root_iterations, "root iteration", "root iterations"),
        st.wall_seconds * 1e3
    ));
    s
}

/// The overlap audit in the `pound run` summary: every facing floor pair without a contact
/// of its own, with its largest overlap beyond the gap (m, negative when the gap never
/// closes), and the floor-to-column facings the model leaves out.
pub fn overlap_lines(run: &RunOutput) -> String {
    let mut s = String::new();
    if !run.overlaps.is_empty() {
        s.push_str(&format!(
            "overlaps (facing floors without a contact; max of u_left − u_right − gap, m): {}, {} \
            beyond the gap
",
            count(run.overlaps.len(), "pair", "pairs"),
            run.overlaps.iter().filter(|o| o.max_overlap > 0.0).count()
        ));
        for o in &run.overlaps {
            s.push_str(&format!(
                "  {} floor {} / {} floor {}: {:+.5} m at {:.4} s (gap {} m)\n",
                o.left, o.left_floor, o.right, o.right_floor, o.max_overlap, o.time, o.gap
            ));
        }
    }
    for f in &run.unmodelled {
        s.push_str(&format!(
            "not modelled: floor {} of {} ({:.3} m) faces the column of {} between levels {} and {} (floor-to-column impact)\n",
            f.floor, f.building, f.elevation, f.other, f.between[0], f.between[1]
        ));
    }
    s
}

/// The stderr warnings of `pound run` about the overlap audit: when floors without a
/// contact pass through each other beyond the gap (naming the worst pair), and when
/// floor-to-column facings are not modelled.
pub fn overlap_warnings(run: &RunOutput) -> Vec<String> {
    let mut w = Vec::new();
    let beyond = run.overlaps.iter().filter(|o| o.max_overlap > 0.0).count();
    if let Some(o) = solvers::overlap::worst(&run.overlaps).filter(|o| o.max_overlap > 0.0) {
        w.push(format!(
            "{} without a contact overlapped beyond the gap; worst: {} floor {} / {} floor {} by {:.4} m at {:.3} s (add contacts, e.g. floors = \"aligned\")",
            crate::table::count(beyond, "facing floor pair", "facing floor pairs"),
            o.left, o.left_floor, o.right, o.right_floor, o.max_overlap, o.time
        ));
    }
    w.extend(unmodelled_warning(
        &run.unmodelled,
        "in `unmodelled` of the --out JSON",
    ));
    w
}

/// Most floor-to-column facings [`unmodelled_warning`] names.
const FACINGS_NAMED: usize = 3;

/// The warning (stderr) of `pound modes` and `pound run` about floors that face an adjacent
/// building mid-story (the scene gives `story_height` on both and their floors are at other
/// elevations): the first three named, and `rest` saying where the whole list is (e.g. "in
/// `unmodelled` of the --out JSON"). `None` without such floors.
pub fn unmodelled_warning(facings: &[UnmodelledFacing], rest: &str) -> Option<String> {
    if facings.is_empty() {
        return None;
    }
    let named: Vec<String> = facings
        .iter()
        .take(FACINGS_NAMED)
        .map(|f| {
            format!(
                "floor {} of {} ({:.3} m) between levels {} and {} of {}",
                f.floor, f.building, f.elevation, f.between[0], f.between[1], f.other
            )
        })
        .collect();
    let more = match facings.len().saturating_sub(FACINGS_NAMED) {
        0 => format!(" (listed {rest})"),
        n => format!("; {n} more (all {rest})"),
    };
    Some(format!(
        "{} face an adjacent building mid-story (floor-to-column impact, not modelled): {}{more}",
        count(facings.len(), "floor", "floors"),
        named.join("; ")
    ))
}

/// The scene as it was run, after `--set` overrides and defaults, in the scene-file format
/// (keys as in the README's scene section, floors counted from 1, SI units): every building
/// with its per-floor masses, story stiffnesses and damping, every contact, the record with
/// its absolute path and its `pga` (g) or `scale`, and every solver option (`momentum.modes`
/// is `null` for all modes). Written as TOML without its `null`s it is a scene file that runs
/// the same analysis.
pub fn resolved_scene(scene: &Scene) -> serde_json::Value {
    use structure::model::Damping;
    let buildings: Vec<serde_json::Value> = scene
        .buildings
        .iter()
        .enumerate()
        .map(|(bi, b)| {
            let damping = match &b.damping {
                Damping::Uniform(z) => serde_json::json!(z),
                Damping::PerMode(v) => serde_json::json!(v),
            };
            let mut v = serde_json::json!({
                "name": b.name,
                "masses": b.masses,
                "story_stiffness": b.story_stiffness,
                "damping_ratio": damping,
                "initial_displacement": b.initial_displacement,
                "initial_velocity": b.initial_velocity,
            });
            if let Some(Some(h)) = scene.story_heights.get(bi) {
                v["story_height"] = serde_json::json!(h);
            }
            if let structure::model::StoryLaw::Bilinear {
                yield_shear,
                hardening_ratio,
            } = &b.story_law
            {
                v["story_law"] = serde_json::json!("bilinear");
                v["yield_shear"] = serde_json::json!(yield_shear);
                v["hardening_ratio"] = serde_json::json!(hardening_ratio);
            }
            v
        })
        .collect();
    let contacts: Vec<serde_json::Value> = scene
        .contacts
        .iter()
        .map(|c| {
            if c.wall {
                // Round-trips as `right = "wall"` (no right_floor).
                return serde_json::json!({
                    "left": scene.buildings[c.left].name,
                    "left_floor": c.left_dof + 1,
                    "right": structure::scene::WALL,
                    "gap": c.gap,
                    "restitution": c.restitution,
                });
            }
            serde_json::json!({
                "left": scene.buildings[c.left].name,
                "left_floor": c.left_dof + 1,
                "right": scene.buildings[c.right].name,
                "right_floor": c.right_dof + 1,
                "gap": c.gap,
                "restitution": c.restitution,
            })
        })
        .collect();
    let ground = scene.ground_source.as_ref().map(|src| {
        let file = std::fs::canonicalize(&src.file).unwrap_or_else(|_| src.file.clone());
        let mut g = serde_json::json!({ "file": file.display().to_string() });
        if let serde_json::Value::Object(f) = serde_json::to_value(src.format).unwrap_or_default() {
            g.as_object_mut().expect("an object").extend(f);
        }
        match src.pga_g {
            Some(p) => g["pga"] = p.into(),
            None => g["scale"] = src.factor.into(),
        }
        g
    });
    let m = &scene.momentum;
    let g = &scene.gap_element;
    serde_json::json!({
        "name": scene.name,
        "buildings": buildings,
        "contacts": contacts,
        "ground_motion": ground,
        "analysis": {
            "duration": scene.duration,
            "max_impact_rate": scene.limits.max_impact_rate,
            "max_steps": scene.limits.max_steps,
        },
        "momentum": {
            "modes": m.modes,
            "impulse": to_json(m.impulse),
            "persistent_contact": m.persistent_contact,
            "capture_velocity": m.capture_velocity,
            "held_tolerance": m.held_tolerance,
        },
        "gap_element": {
            "stiffness": g.stiffness,
            "law": to_json(g.law),
            "integrator": to_json(g.integrator),
            "tolerance": g.tolerance,
            "time_step": g.time_step,
            "tension": g.tension,
        },
    })
}

fn to_json<T: serde::Serialize>(v: T) -> serde_json::Value {
    serde_json::to_value(v).unwrap_or(serde_json::Value::Null)
}
