//! Helpers shared by the scene tests.

use structure::scene::{Scene, SceneError};

/// Asserts that `r` is an error whose message contains every one of `parts`.
#[track_caller]
pub fn err_has(r: Result<Scene, SceneError>, parts: &[&str]) -> String {
    let msg = match r {
        Ok(_) => panic!("expected an error containing {parts:?}, the scene loaded"),
        Err(e) => e.to_string(),
    };
    for p in parts {
        assert!(msg.contains(p), "error {msg:?} should contain {p:?}");
    }
    msg
}
