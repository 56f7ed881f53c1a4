//! `pound export opensees`: the same scene as an OpenSeesPy script, for cross-checking in a
//! framework users already trust.
//!
//! The script is self-contained (the record values are embedded) and is run as
//! `python model.py out.json`; it writes the `pound run --out` JSON layout
//! (`buildings[].name/story_shear_max/floor_displacement_max`, `impacts[]`,
//! `method: "opensees"`) to its first argument.
//!
//! # The model
//!
//! - `model('basic', '-ndm', 1, '-ndf', 1)`: one horizontal DOF per node. Per building a
//!   fixed ground node and one node per floor carrying the lumped floor mass; story `j` is a
//!   `zeroLength` element (`-dir 1`) from the node below to floor `j` with a uniaxial
//!   `Elastic` material of stiffness `k_j`. All nodes sit at x = 0 (zero-length elements).
//!   A building with `story_law = "bilinear"` gets `Steel01(F_y, k_j, b)` instead (yield
//!   shear F_y in N, elastic stiffness E0 = k_j in N/m, hardening ratio b): the bilinear law
//!   with kinematic hardening of pound's story law (Steel01's isotropic-hardening
//!   parameters a1…a4 are left at their defaults, a1 = a3 = 0: none). Its trial answer is
//!   the elastic predictor from the committed state clamped to the hardening lines
//!   V = ±(1 − b) F_y + b k₀ d, the same return mapping as pound's, and pound's damping
//!   matrix stays the elastic building's, as the modal damping here. An initial drift
//!   beyond the yield drift is a caveat ([`opensees_caveats`]): pound commits the story on
//!   its yield surface at t = 0, Steel01 answers the first step from its virgin state.
//! - Damping: classical modal damping C = M Φ diag(2ζω) Φᵀ M, the matrix both pound solvers
//!   use, through OpenSees' `modalDamping` after `eigen('-fullGenLapack', N)` with *all* N
//!   modes of the model. The buildings are uncoupled when the eigen analysis runs (contacts
//!   are added afterwards), so the model's modes are the union of the buildings' modes; the
//!   script lists one ratio per mode in ascending order of frequency (computed here from
//!   each building's own modes) and checks that OpenSees finds the same frequencies.
//!   `system('FullGeneral')` keeps the full damping tangent consistent with the residual.
//! - Contacts: a `zeroLength` element from the left floor (iNode) to the right floor
//!   (jNode). Its deformation is u_right − u_left, and pound's contact closes when
//!   u_left − u_right ≥ gap, i.e. deformation ≤ −gap: a compression gap, which OpenSees
//!   materials take with a *negative* gap.
//!   - `linear` law: `ElasticPPGap(E = k, Fy = −1e30, gap = −gap)` (negative Fy selects the
//!     compression branch; the yield force is out of reach, so the spring stays elastic).
//!   - `kelvin-voigt` law: `ViscoelasticGap(K = k, C = c, gap = −gap)` with pound's dashpot
//!     c = 2ξ√(k m_eff), ξ from the restitution (Anagnostopoulos), m_eff of the two contact
//!     floors. ViscoelasticGap lets the dashpot pull until the gap reopens, which is
//!     pound's `gap_element.tension = true`; with the default `false` pound clamps the force
//!     at zero (see [`opensees_caveats`]).
//!   - `hertz-damp` has no OpenSees equivalent here: [`ExportError::Unsupported`].
//!   - a wall contact (`right = "wall"`) joins its floor to a fixed node (at relative
//!     displacement 0, i.e. moving with the ground under `UniformExcitation`), with the
//!     floor mass as the Kelvin–Voigt effective mass (the limit of an infinitely heavy
//!     neighbour), as pound's gap element does.
//! - Ground motion: `timeSeries('Path', 1, '-dt', dt, '-values', *record_g, '-factor',
//!   G·scale)` with the record as read (converted to g) and the scene's scale factor (the
//!   one that gives the requested PGA), then `pattern('UniformExcitation', 1, 1, '-accel',
//!   1)`: the same effective force −M 1 a_g as pound.
//! - Analysis: `Newmark` average acceleration (γ = ½, β = ¼) with `Newton` at the step
//!   pound's fixed-step Newmark uses (`gap_element.time_step`, shortened so that a whole
//!   number of steps spans the duration), `NormDispIncr` test. Initial conditions through
//!   `setNodeDisp`/`setNodeVel`, with the consistent initial acceleration set explicitly.
//! - Outputs: tracked in Python as pound's Newmark does: floor displacements (`nodeDisp`),
//!   story shears k_j (u_j − u_{j−1}) (a bilinear story: the element's basic force, i.e. the
//!   Steel01 stress), story drifts and their peaks at every step, as pound's Newmark, the
//!   drifts at the end (`residual_drift`) and, for a bilinear building, the ductility
//!   demand (peak drift / (F_y/k_j)); a contact
//!   episode starts at the first step whose contact element carries a force and ends at the
//!   first step where it carries none (times, relative velocities, impulse, peak force and
//!   penetration as in `pound run`).
//!
//! Compare with `pound run SCENE --method gap --set gap_element.integrator=newmark`.

use std::fmt::Write as _;

use structure::scene::ContactLaw;
use structure::{GroundMotion, Scene, G};

/// Why a scene cannot be exported.
#[derive(Debug, thiserror::Error)]
pub enum ExportError {
    #[error("{what} cannot be expressed in the OpenSees export: {why}")]
    Unsupported { what: String, why: String },
    #[error("cannot re-read the ground motion for the export: {0}")]
    Record(#[from] structure::RecordError),
    #[error(transparent)]
    Model(#[from] structure::ModelError),
}

/// Compressive yield force of the linear law's `ElasticPPGap`, N: out of reach.
const FY_NEVER: f64 = 1.0e30;

/// Python literal of a finite float: Rust's shortest round-trip form (`2000000.0`, `1e-8`),
/// which Python reads back to the same double.
fn num(x: f64) -> String {
    debug_assert!(x.is_finite());
    format!("{x:?}")
}

/// A Python list of floats, `per_line` values a line, indented by `indent` spaces.
fn list(values: &[f64], per_line: usize, indent: usize) -> String {
    if values.len() <= per_line {
        let v: Vec<String> = values.iter().map(|x| num(*x)).collect();
        return format!("[{}]", v.join(", "));
    }
    let pad = " ".repeat(indent + 4);
    let mut s = String::from("[\n");
    for chunk in values.chunks(per_line) {
        let v: Vec<String> = chunk.iter().map(|x| num(*x)).collect();
        let _ = writeln!(s, "{pad}{},", v.join(", "));
    }
    s.push_str(&" ".repeat(indent));
    s.push(']');
    s
}

/// A Python string literal (JSON string syntax is valid Python for printable text).
fn pystr(s: &str) -> String {
    serde_json::to_string(s).unwrap_or_else(|_| "\"\"".into())
}

/// Things the export reproduces only approximately; the CLI prints them as warnings.
pub fn opensees_caveats(scene: &Scene) -> Vec<String> {
    let mut w = Vec::new();
    if scene.gap_element.integrator != structure::scene::Integrator::Newmark {
        w.push(format!(
            "the script integrates with Newmark (average acceleration) at gap_element.time_step = \
             {} s; this scene's gap element is adaptive (tolerance {:e}), so compare with \
             `pound run --method gap --set gap_element.integrator=newmark`",
            scene.gap_element.time_step, scene.gap_element.tolerance
        ));
    }
    if !scene.contacts.is_empty()
        && scene.gap_element.law == ContactLaw::KelvinVoigt
        && !scene.gap_element.tension
    {
        w.push(
            "OpenSees' ViscoelasticGap lets the dashpot pull until the gap reopens (pound's \
             gap_element.tension = true); this scene clamps the contact force at zero \
             (tension = false), so rebound velocities will differ slightly: compare with \
             `--set gap_element.tension=true`"
                .into(),
        );
    }
    for b in &scene.buildings {
        let Some(params) = b.story_law.bilinear_params(&b.story_stiffness) else {
            continue;
        };
        let mut below = 0.0;
        for (j, (p, &u)) in params.iter().zip(&b.initial_displacement).enumerate() {
            if (u - below).abs() > p.yield_drift() {
                w.push(format!(
                    "building `{}` story {}: the initial drift {:.4e} m exceeds the yield drift \
                     {:.4e} m; pound starts the story on its yield surface, while OpenSees' \
                     Steel01 answers the first step from its virgin state, so the first steps \
                     will differ",
                    b.name,
                    j + 1,
                    u - below,
                    p.yield_drift()
                ));
                break;
            }
            below = u;
        }
    }
    w
}

/// One mode of the combined (uncoupled) model.
struct Mode {
    omega: f64,
    zeta: f64,
    building: usize,
}

/// The OpenSeesPy script of `scene` (see the module docs).
pub fn opensees_script(scene: &Scene) -> Result<String, ExportError> {
    if !scene.contacts.is_empty() && scene.gap_element.law == ContactLaw::HertzDamp {
        return Err(ExportError::Unsupported {
            what: "gap_element.law = \"hertz-damp\"".into(),
            why: "the export writes the linear law as ElasticPPGap and kelvin-voigt as \
                  ViscoelasticGap; set gap_element.law to \"linear\" or \"kelvin-voigt\""
                .into(),
        });
    }

    // Modes of the combined model, ascending; a tie between buildings with different
    // damping ratios would make the order of the ratios ambiguous.
    let mut modes = Vec::new();
    for (bi, b) in scene.buildings.iter().enumerate() {
        let m = b.modes()?;
        for (w, z) in m.omega.iter().zip(&m.zeta) {
            modes.push(Mode {
                omega: *w,
                zeta: *z,
                building: bi,
            });
        }
    }
    modes.sort_by(|a, b| a.omega.total_cmp(&b.omega));
    for p in modes.windows(2) {
        let (a, b) = (&p[0], &p[1]);
        if a.building != b.building && a.zeta != b.zeta && (b.omega - a.omega) <= 1e-6 * b.omega {
            return Err(ExportError::Unsupported {
                what: format!(
                    "modal damping of buildings `{}` and `{}`",
                    scene.buildings[a.building].name, scene.buildings[b.building].name
                ),
                why: format!(
                    "they share a frequency ({:.6} Hz) with different damping ratios ({} and \
                     {}), which OpenSees' modalDamping (one ratio per mode of the whole \
                     model) cannot tell apart",
                    a.omega / (2.0 * std::f64::consts::PI),
                    a.zeta,
                    b.zeta
                ),
            });
        }
    }

    // Ground motion: the record as read, in g, and the factor to m/s² (G × scale).
    let (record_g, record_dt, record_factor, record_note) =
        match (&scene.ground, &scene.ground_source) {
            (None, _) => (
                Vec::new(),
                0.0,
                0.0,
                "free vibration (no ground motion)".to_string(),
            ),
            (Some(_), Some(src)) => {
                let raw = GroundMotion::load(&src.file, &src.format)?;
                let note = match src.pga_g {
                    Some(p) => format!(
                        "{} scaled to PGA {} g (factor {})",
                        src.file.display(),
                        p,
                        src.factor
                    ),
                    None => format!("{} scaled by {}", src.file.display(), src.factor),
                };
                (
                    raw.accel.iter().map(|a| a / G).collect(),
                    raw.dt,
                    G * src.factor,
                    note,
                )
            }
            (Some(g), None) => (
                g.accel.iter().map(|a| a / G).collect(),
                g.dt,
                G,
                format!("record `{}` (already scaled)", g.name),
            ),
        };

    let dt_req = scene.gap_element.time_step;
    let nsteps = solvers::gap::newmark::steps_and_step(scene).0;

    let mut s = String::new();
    let name = &scene.name;
    let origin = scene.file.as_ref().map_or_else(
        || "(built in code)".to_string(),
        |p| p.display().to_string(),
    );
    let _ = write!(
        s,
        r#"#!/usr/bin/env python3
"""OpenSeesPy model of the pound scene {name_lit}, written by `pound export opensees`.

Scene file: {origin_lit}
Ground motion: {record_note_lit}

Run:  python model.py out.json
Needs openseespy (pip install openseespy). Writes the `pound run --out` JSON layout
(buildings[].story_shear_max, floor_displacement_max, impacts[], method "opensees") to the
path given as the first argument. Compare with
    pound run SCENE --method gap --set gap_element.integrator=newmark --out pound.json

Model: zeroLength story springs (uniaxial Elastic; Steel01 for bilinear stories), lumped
floor masses, classical modal
damping C = M Phi diag(2 zeta omega) Phi^T M through modalDamping over all modes, the
contacts as zeroLength gap elements (ElasticPPGap for the linear law, ViscoelasticGap for
Kelvin-Voigt), UniformExcitation from the embedded record, Newmark average acceleration
with Newton at a fixed step. Units: kg, N/m, m, s.
"""

import json
import math
import os
import sys
import time

try:
    import openseespy.opensees as ops
except ImportError as e:
    sys.exit(f"this script needs OpenSeesPy: pip install openseespy (or make opensees in pound's repository): {{e}}")

SCENE = {name_lit}
G = {g}  # m/s^2
DURATION = {duration}  # s
N_STEPS = {nsteps}  # fixed Newmark steps: DURATION in equal steps of at most gap_element.time_step
DT = DURATION / N_STEPS  # s (gap_element.time_step = {dt_req})
# Peaks are taken where pound's Newmark takes them: at every step.
PEAK_STRIDE = 1
SETTINGS = {settings_lit}

"#,
        name_lit = pystr(name),
        origin_lit = pystr(&origin).trim_matches('"'),
        record_note_lit = pystr(&record_note).trim_matches('"'),
        g = num(G),
        duration = num(scene.duration),
        nsteps = nsteps,
        dt_req = num(dt_req),
        settings_lit = pystr(&format!(
            "{} k={} N/m, Newmark average acceleration dt={} s, Newton, modalDamping",
            match scene.gap_element.law {
                ContactLaw::Linear => "ElasticPPGap (linear law)",
                ContactLaw::KelvinVoigt => "ViscoelasticGap (kelvin-voigt law)",
                ContactLaw::HertzDamp => "hertz-damp",
            },
            num(scene.gap_element.stiffness),
            num(scene.duration / nsteps as f64),
        )),
    );

    s.push_str(
        "# Buildings: floor 1 (lowest) first; story j joins floor j-1 (the ground for j = 1)\n",
    );
    s.push_str("# to floor j.\nBUILDINGS = [\n");
    for b in &scene.buildings {
        let _ = writeln!(s, "    {{");
        let _ = writeln!(s, "        \"name\": {},", pystr(&b.name));
        let _ = writeln!(s, "        \"masses\": {},  # kg", list(&b.masses, 6, 8));
        let _ = writeln!(
            s,
            "        \"story_stiffness\": {},  # N/m",
            list(&b.story_stiffness, 4, 8)
        );
        match b.story_law.bilinear_params(&b.story_stiffness) {
            Some(p) => {
                let fy: Vec<f64> = p.iter().map(|p| p.yield_shear).collect();
                let _ = writeln!(
                    s,
                    "        \"yield_shear\": {},  # N (Steel01 Fy)",
                    list(&fy, 4, 8)
                );
                let _ = writeln!(
                    s,
                    "        \"hardening_ratio\": {},  # Steel01 b",
                    num(p.first().map_or(0.0, |p| p.hardening_ratio))
                );
            }
            None => {
                let _ = writeln!(s, "        \"yield_shear\": None,  # linear stories");
            }
        }
        let _ = writeln!(
            s,
            "        \"initial_displacement\": {},  # m",
            list(&b.initial_displacement, 6, 8)
        );
        let _ = writeln!(
            s,
            "        \"initial_velocity\": {},  # m/s",
            list(&b.initial_velocity, 6, 8)
        );
        let _ = writeln!(s, "    }},");
    }
    s.push_str("]\n\n");

    let omegas: Vec<f64> = modes.iter().map(|m| m.omega).collect();
    let zetas: Vec<f64> = modes.iter().map(|m| m.zeta).collect();
    let owners: Vec<String> = modes.iter().map(|m| m.building.to_string()).collect();
    let _ = writeln!(
        s,
        "# Every mode of the uncoupled model, ascending: circular frequency (rad/s) as pound\n\
         # computes it, the damping ratio given to modalDamping, and the building it belongs to.\n\
         MODAL_OMEGA = {}\nMODAL_DAMPING = {}\nMODAL_BUILDING = [{}]\n",
        list(&omegas, 4, 0),
        list(&zetas, 8, 0),
        owners.join(", ")
    );

    s.push_str("# Contacts: floors counted from 1. In contact while u_left - u_right >= gap.\n");
    s.push_str("CONTACTS = [\n");
    for c in &scene.contacts {
        let ml = scene.buildings[c.left].masses[c.left_dof];
        // Against a wall the effective mass is the floor's own (m_r → ∞).
        let m_eff = if c.wall {
            ml
        } else {
            let mr = scene.buildings[c.right].masses[c.right_dof];
            ml * mr / (ml + mr)
        };
        let k = scene.gap_element.stiffness;
        let (law, dashpot) = match scene.gap_element.law {
            ContactLaw::Linear => ("linear", 0.0),
            _ => {
                let xi = solvers::gap::law::kelvin_voigt_xi(c.restitution);
                ("kelvin-voigt", 2.0 * xi * (k * m_eff).sqrt())
            }
        };
        let _ =
            writeln!(
            s,
            "    {{\"left\": {}, \"left_floor\": {}, \"right\": {}, \"right_floor\": {},\n     \
             \"gap\": {}, \"restitution\": {}, \"law\": {}, \"stiffness\": {}, \"dashpot\": {}}},  \
             # {} floor {} <-> {} floor {}; gap m, k N/m, c N*s/m",
            c.left,
            c.left_dof + 1,
            if c.wall { "None".to_string() } else { c.right.to_string() },
            if c.wall { "None".to_string() } else { (c.right_dof + 1).to_string() },
            num(c.gap),
            num(c.restitution),
            pystr(law),
            num(k),
            num(dashpot),
            // Names quoted and escaped (a name is user text: a raw newline in a comment
            // would end it and start code).
            pystr(&scene.buildings[c.left].name),
            c.left_dof + 1,
            if c.wall { "the wall".to_string() } else { pystr(&scene.buildings[c.right].name) },
            if c.wall { 0 } else { c.right_dof + 1 },
        );
    }
    s.push_str("]\n");
    let _ = writeln!(
        s,
        "# Compressive yield force of the linear law's ElasticPPGap (N): out of reach.\nFY_NEVER = {}\n# The fixed node of wall contacts (\"right\": None), created by build().\nWALL_NODE = None\n",
        num(FY_NEVER)
    );

    let _ = writeln!(
        s,
        "# Ground acceleration: RECORD_G[i] (g) at t = i * RECORD_DT, times RECORD_FACTOR (m/s^2\n\
         # per g, i.e. G times the scene's scale factor); zero after the record ends.\n\
         RECORD_DT = {}  # s\nRECORD_FACTOR = {}\nRECORD_NPTS = {}\nRECORD_G = {}\n",
        num(record_dt),
        num(record_factor),
        record_g.len(),
        list(&record_g, 6, 0)
    );

    s.push_str(LOGIC);
    Ok(s)
}

/// The part of the script that does not depend on the scene.
const LOGIC: &str = r#"

def fail(message):
    sys.stderr.write("error: " + message + "\n")
    sys.exit(1)


def build():
    """Nodes, masses, story springs; returns the floor node tags per building and the last tag."""
    ops.wipe()
    ops.model('basic', '-ndm', 1, '-ndf', 1)
    floors = []
    tag = 0
    for b in BUILDINGS:
        tag += 1
        ground = tag
        ops.node(ground, 0.0)
        ops.fix(ground, 1)
        below = ground
        nodes = []
        for j, (m, k) in enumerate(zip(b["masses"], b["story_stiffness"])):
            tag += 1
            ops.node(tag, 0.0)
            ops.mass(tag, m)
            # The story below this floor: node, material and element share the tag.
            if b["yield_shear"] is None:
                ops.uniaxialMaterial('Elastic', tag, k)
            else:
                # Bilinear story: Steel01(Fy, E0, b), kinematic hardening only (a1..a4
                # left at their defaults: no isotropic hardening).
                ops.uniaxialMaterial('Steel01', tag, b["yield_shear"][j], k, b["hardening_ratio"])
            ops.element('zeroLength', tag, below, tag, '-mat', tag, '-dir', 1)
            nodes.append(tag)
            below = tag
        floors.append(nodes)
    if any(c["right"] is None for c in CONTACTS):
        # The wall: a fixed node, created with the model so that the eigen analysis (and the
        # modal damping built from it) covers it.
        global WALL_NODE
        tag += 1
        WALL_NODE = tag
        ops.node(WALL_NODE, 0.0)
        ops.fix(WALL_NODE, 1)
    return floors, tag


def modal_damping(floors):
    """eigen over every mode, check the frequencies, modalDamping; returns (omega, phi)."""
    n = sum(len(nodes) for nodes in floors)
    lam = ops.eigen('-fullGenLapack', n)
    omega = [math.sqrt(x) for x in lam]
    for i, (w, w_ref) in enumerate(zip(omega, MODAL_OMEGA)):
        if abs(w - w_ref) > 1e-6 * w_ref:
            fail("mode %d: OpenSees finds %.9g rad/s, pound %.9g rad/s" % (i + 1, w, w_ref))
    ops.modalDamping(*MODAL_DAMPING)
    # Mass-normalised mode shapes, for the initial acceleration.
    masses = [m for b in BUILDINGS for m in b["masses"]]
    nodes = [t for fl in floors for t in fl]
    phi = []
    for mode in range(1, n + 1):
        v = [ops.nodeEigenvector(t, mode, 1) for t in nodes]
        norm = math.sqrt(sum(m * x * x for m, x in zip(masses, v)))
        phi.append([x / norm for x in v])
    return omega, phi


def add_contacts(floors, tag):
    """The contact elements (after the eigen analysis: their gaps are open at rest). A wall
    contact ("right": None) joins its floor to a fixed node: at relative displacement 0 under
    UniformExcitation, i.e. a wall that moves with the ground."""
    tags = []
    for c in CONTACTS:
        left = floors[c["left"]][c["left_floor"] - 1]
        right = WALL_NODE if c["right"] is None else floors[c["right"]][c["right_floor"] - 1]
        tag += 1
        # zeroLength deformation = u_j - u_i = u_right - u_left (iNode left, jNode right).
        # Contact when u_left - u_right >= gap, i.e. deformation <= -gap: a compression
        # gap, given to both materials as a negative gap (and a negative Fy for
        # ElasticPPGap, which selects its compression branch). The stress is negative
        # (compressive) while in contact.
        if c["law"] == "linear":
            ops.uniaxialMaterial('ElasticPPGap', tag, c["stiffness"], -FY_NEVER, -c["gap"])
        else:
            ops.uniaxialMaterial('ViscoelasticGap', tag, c["stiffness"], c["dashpot"], -c["gap"])
        ops.element('zeroLength', tag, left, right, '-mat', tag, '-dir', 1)
        tags.append(tag)
    return tags


def initial_conditions(floors, omega, phi):
    """Initial displacements and velocities, and the consistent initial acceleration
    a0 = -M^-1 (K u0 + C v0 + contact forces) - a_g(0)."""
    masses = [m for b in BUILDINGS for m in b["masses"]]
    u0 = [x for b in BUILDINGS for x in b["initial_displacement"]]
    v0 = [x for b in BUILDINGS for x in b["initial_velocity"]]
    nodes = [t for fl in floors for t in fl]
    # Story forces at u0 in story form (a bilinear story answers from its virgin state:
    # beyond the yield drift on the hardening line).
    ku = []
    for b in BUILDINGS:
        u = b["initial_displacement"]
        k = b["story_stiffness"]
        n = len(u)

        def story(j):
            f = k[j] * (u[j] - (u[j - 1] if j > 0 else 0.0))
            if b["yield_shear"] is not None:
                fy, hb = b["yield_shear"][j], b["hardening_ratio"]
                if abs(f) > fy:
                    f = math.copysign(fy + hb * (abs(f) - fy), f)
            return f

        for j in range(n):
            f = story(j)
            if j + 1 < n:
                f -= story(j + 1)
            ku.append(f)
    # C v0 = M Phi diag(2 zeta omega) Phi^T M v0.
    mv = [m * v for m, v in zip(masses, v0)]
    cv = [0.0] * len(nodes)
    for w, z, p in zip(omega, MODAL_DAMPING, phi):
        q = 2.0 * z * w * sum(pi * x for pi, x in zip(p, mv))
        for i in range(len(nodes)):
            cv[i] += masses[i] * p[i] * q
    # Contacts already closed at t = 0: +F on the right floor, -F on the left floor.
    index = {}
    off = 0
    for bi, b in enumerate(BUILDINGS):
        for j in range(len(b["masses"])):
            index[(bi, j + 1)] = off + j
        off += len(b["masses"])
    for c in CONTACTS:
        il = index[(c["left"], c["left_floor"])]
        ir = None if c["right"] is None else index[(c["right"], c["right_floor"])]
        ur, vr = (0.0, 0.0) if ir is None else (u0[ir], v0[ir])
        delta = u0[il] - ur - c["gap"]
        if delta > 0.0:
            force = c["stiffness"] * delta + c["dashpot"] * (v0[il] - vr)
            ku[il] += force
            if ir is not None:
                ku[ir] -= force
    ag0 = RECORD_G[0] * RECORD_FACTOR if RECORD_NPTS > 0 else 0.0
    for i, t in enumerate(nodes):
        if u0[i] != 0.0:
            ops.setNodeDisp(t, 1, u0[i], '-commit')
        if v0[i] != 0.0:
            ops.setNodeVel(t, 1, v0[i], '-commit')
        ops.setNodeAccel(t, 1, -(ku[i] + cv[i]) / masses[i] - ag0, '-commit')


class Tracker:
    """Peak floor displacements and story shears, and contact episodes, observed after
    every step (as pound's Newmark does)."""

    def __init__(self, floors, contact_tags):
        self.floors = floors
        self.contact_tags = contact_tags
        self.disp_max = [[0.0] * len(nodes) for nodes in floors]
        self.shear_max = [[0.0] * len(nodes) for nodes in floors]
        self.drift_max = [[0.0] * len(nodes) for nodes in floors]
        self.drift = [[0.0] * len(nodes) for nodes in floors]
        n = len(CONTACTS)
        self.active = [False] * n
        self.force = [0.0] * n
        self.ddot = [0.0] * n
        self.impulse = [0.0] * n
        self.episode = [None] * n
        self.impacts = []

    def contact_state(self, i):
        c = CONTACTS[i]
        left = self.floors[c["left"]][c["left_floor"] - 1]
        if c["right"] is None:
            u_r, v_r = 0.0, 0.0
        else:
            right = self.floors[c["right"]][c["right_floor"] - 1]
            u_r, v_r = ops.nodeDisp(right, 1), ops.nodeVel(right, 1)
        delta = ops.nodeDisp(left, 1) - u_r - c["gap"]
        ddot = ops.nodeVel(left, 1) - v_r
        # Basic force of the zeroLength element = material stress (negative in compression).
        force = -ops.basicForce(self.contact_tags[i])[0]
        return delta, ddot, force

    def observe_peaks(self):
        for bi, (b, nodes) in enumerate(zip(BUILDINGS, self.floors)):
            below = 0.0
            for j, t in enumerate(nodes):
                u = ops.nodeDisp(t, 1)
                self.disp_max[bi][j] = max(self.disp_max[bi][j], abs(u))
                if b["yield_shear"] is None:
                    v = b["story_stiffness"][j] * (u - below)
                else:
                    # The story element (same tag as its floor node): Steel01's force.
                    v = ops.basicForce(t)[0]
                self.shear_max[bi][j] = max(self.shear_max[bi][j], abs(v))
                self.drift[bi][j] = u - below
                self.drift_max[bi][j] = max(self.drift_max[bi][j], abs(u - below))
                below = u

    def start(self):
        self.observe_peaks()
        for i in range(len(CONTACTS)):
            delta, ddot, force = self.contact_state(i)
            self.ddot[i] = ddot
            self.force[i] = force
            self.active[i] = delta > 0.0 and force != 0.0
            if self.active[i]:
                self.episode[i] = dict(t_close=0.0, v_before=ddot, impulse0=0.0,
                                       peak_force=force, max_pen=delta)

    def step(self, t1, dt, sample):
        changed = False
        for i in range(len(CONTACTS)):
            delta, ddot, force = self.contact_state(i)
            fbar = 0.5 * (self.force[i] + force)
            self.impulse[i] += dt * fbar
            now = delta > 0.0 and force != 0.0
            if now and not self.active[i]:
                self.episode[i] = dict(t_close=t1, v_before=self.ddot[i],
                                       impulse0=self.impulse[i] - dt * fbar,
                                       peak_force=0.0, max_pen=0.0)
            if now:
                ep = self.episode[i]
                ep["peak_force"] = max(ep["peak_force"], force)
                ep["max_pen"] = max(ep["max_pen"], delta)
            if not now and self.active[i]:
                self.close(i, t1, ddot)
            if now != self.active[i]:
                changed = True
            self.active[i] = now
            self.force[i] = force
            self.ddot[i] = ddot
        if sample or changed:
            self.observe_peaks()

    def close(self, i, t_open, v_after):
        ep = self.episode[i]
        before = ep["v_before"]
        self.impacts.append({
            "contact": i,
            "time": ep["t_close"],
            "relative_velocity_before": before,
            "relative_velocity_after": v_after,
            "achieved_restitution": (-v_after / before) if before != 0.0 else None,
            "impulse": self.impulse[i] - ep["impulse0"],
            "duration": t_open - ep["t_close"],
            "peak_force": ep["peak_force"],
            "max_penetration": ep["max_pen"],
        })

    def finish(self, t_end):
        for i in range(len(CONTACTS)):
            if self.active[i]:
                self.close(i, t_end, self.ddot[i])
        self.impacts.sort(key=lambda x: x["time"])


def main():
    if len(sys.argv) != 2:
        sys.stderr.write("usage: python %s OUT.json\n" % os.path.basename(sys.argv[0]))
        sys.exit(2)
    out_path = sys.argv[1]
    started = time.time()

    floors, tag = build()
    omega, phi = modal_damping(floors)
    contact_tags = add_contacts(floors, tag)
    if RECORD_NPTS > 0:
        ops.timeSeries('Path', 1, '-dt', RECORD_DT, '-values', *RECORD_G, '-factor', RECORD_FACTOR)
        ops.pattern('UniformExcitation', 1, 1, '-accel', 1)
    initial_conditions(floors, omega, phi)

    ops.constraints('Plain')
    ops.numberer('Plain')
    ops.system('FullGeneral')  # the modal damping matrix is full
    ops.test('NormDispIncr', 1.0e-12, 50)
    ops.algorithm('Newton')
    ops.integrator('Newmark', 0.5, 0.25)
    ops.analysis('Transient')

    tracker = Tracker(floors, contact_tags)
    tracker.start()
    substeps = 0
    for step in range(1, N_STEPS + 1):
        t1 = step * DT
        if ops.analyze(1, DT) != 0:
            # Retry the step in ten parts before giving up.
            substeps += 1
            for _ in range(10):
                if ops.analyze(1, DT / 10.0) != 0:
                    fail("the analysis did not converge at t = %.6f s" % t1)
        tracker.step(t1, DT, step % PEAK_STRIDE == 0 or step == N_STEPS)
    tracker.finish(DURATION)

    def building_result(bi):
        b = BUILDINGS[bi]
        r = {
            "name": b["name"],
            "story_shear_max": tracker.shear_max[bi],
            "floor_displacement_max": tracker.disp_max[bi],
            "story_drift_max": tracker.drift_max[bi],
            "residual_drift": tracker.drift[bi],
        }
        if b["yield_shear"] is not None:
            r["ductility"] = [d / (fy / k) for d, fy, k in
                              zip(tracker.drift_max[bi], b["yield_shear"], b["story_stiffness"])]
        return r

    result = {
        "method": "opensees",
        "settings": SETTINGS,
        "scene": SCENE,
        "duration": DURATION,
        "buildings": [building_result(bi) for bi in range(len(BUILDINGS))],
        "impacts": tracker.impacts,
        "persistent_contacts": [],
        "stats": {
            "steps": N_STEPS,
            "retried_steps": substeps,
            "impacts": len(tracker.impacts),
            "wall_seconds": time.time() - started,
        },
    }
    tmp = out_path + ".tmp"
    with open(tmp, "w") as f:
        json.dump(result, f, indent=2, allow_nan=False)
        f.write("\n")
    os.replace(tmp, out_path)


if __name__ == "__main__":
    main()
"#;
