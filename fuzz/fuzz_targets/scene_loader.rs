//! Fuzz target: the scene loader on arbitrary UTF-8 text. Any input must give a scene or an
//! error, never a panic.
//!
//! Text after the first NUL byte is a list of `--set PATH=VALUE` expressions separated by
//! NUL bytes, so the override parser is fuzzed too. Record paths resolve against the
//! current directory (run from the repository root so the seeds' records are found).

#![no_main]

use std::path::Path;

use libfuzzer_sys::fuzz_target;
use structure::scene::MAX_STORIES;
use structure::Scene;

fuzz_target!(|data: &[u8]| {
    let Ok(all) = std::str::from_utf8(data) else {
        return;
    };
    let mut parts = all.split('\0');
    let text = parts.next().unwrap_or("");
    let overrides: Vec<String> = parts.map(str::to_string).collect();
    match Scene::from_str_with_overrides(text, "fuzz.toml", Path::new("."), &overrides) {
        Ok(scene) => {
            assert!(!scene.buildings.is_empty());
            assert!(scene.duration.is_finite() && scene.duration > 0.0);
            for b in &scene.buildings {
                assert!(b.validate().is_ok(), "a loaded building is valid");
                assert!((1..=MAX_STORIES).contains(&b.n_floors()));
            }
            for c in &scene.contacts {
                // A wall contact repeats its left side on the right (`Contact::wall`).
                assert!(c.left != c.right || (c.wall && c.left_dof == c.right_dof));
                assert!(c.left_dof < scene.buildings[c.left].n_floors());
                assert!(c.right_dof < scene.buildings[c.right].n_floors());
                assert!(c.gap >= 0.0 && (0.0..=1.0).contains(&c.restitution));
            }
        }
        Err(e) => {
            // Every message names the file or the --set expression.
            let m = e.to_string();
            assert!(m.contains("fuzz.toml") || m.starts_with("--set "), "{m}");
        }
    }
});
