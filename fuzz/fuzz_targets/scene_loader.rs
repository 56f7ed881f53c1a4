//! Fuzz target: the scene loader on arbitrary UTF-8 text. Any input must give a scene or an
//! error, never a panic.
//!
//! Text after the first NUL byte is a list of `--set PATH=VALUE` expressions separated by
//! NUL bytes, so the override parser is fuzzed too. Record paths resolve against the
//! current directory (run from the repository root so the seeds' records are found).

#![no_main]

use std::path::Path;

use libfuzzer_sys::fuzz_target;
use structure::Scene;

fuzz_target!(|data: &[u8]| {
    let Ok(all) = std::str::from_utf8(data) else {
        return;
    };
    let mut parts = all.split('\0');
    let text = parts.next().unwrap_or("");
    let overrides: Vec<String> = parts.map(str::to_string).collect();
    match Scene::from_str_with_overrides(text, "fuzz.toml", Path::new("."), &overrides) {
        // A scene that loads is valid (the property tests of tests/scene.rs assert the same).
        Ok(scene) => {
            if let Some(v) = structure::testing::loaded_scene_violation(&scene) {
                panic!("a loaded scene is invalid: {v}");
            }
        }
        Err(e) => {
            // Every message names the file or the --set expression.
            let m = e.to_string();
            assert!(m.contains("fuzz.toml") || m.starts_with("--set "), "{m}");
        }
    }
});
