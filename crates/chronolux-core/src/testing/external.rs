//! Tests that need something the repository does not contain: the development data in
//! `shared/` beside the repository (glTF scenes, Mitsuba references) or a tool
//! (`flip-evaluator` in a Python environment).
//!
//! **One policy** (implemented once, in [`require_external`]): when such a thing is missing,
//!
//! - under CI (environment variable `CI` set to anything but empty, `0` or `false`; `.ci/run`
//!   sets `CI=true`) the test **fails**, saying what is missing and how `.ci/run` provides
//!   it: a test that CI cannot run must not pass silently;
//! - elsewhere it prints one `SKIPPED: …` line on stderr (shown with `--nocapture`, and
//!   in the output of a failing run) and returns without asserting anything.
//!
//! Paths to `shared/` are relative to this crate's manifest folder
//! (`crates/chronolux-core/../../../shared`, i.e. `shared/` next to the repository's root
//! folder), never absolute, so a clone anywhere with a copy of `shared/` beside it works.

use std::path::{Path, PathBuf};

/// Environment variable naming the Python interpreter that can `import flip_evaluator,
/// numpy` (default `python3`). `.ci/run` sets it to the interpreter of the virtual
/// environment `.venv-flip` it installs `flip-evaluator` into.
pub const FLIP_PYTHON_VAR: &str = "CHRONOLUX_FLIP_PYTHON";

/// How `.ci/run` provides `shared/`, for the failure message.
const SHARED_REMEDY: &str = "CI runs from a clone with a copy of the development data \
    folder `shared/` beside the repository's root folder (`.ci/run` checks it is there \
    before testing); outside CI, put or link `shared/` there";

/// How `.ci/run` provides flip-evaluator, for the failure message.
const FLIP_REMEDY: &str = "`.ci/run` installs it with `python3 -m venv .venv-flip && \
    .venv-flip/bin/pip install flip-evaluator numpy` and sets \
    CHRONOLUX_FLIP_PYTHON=.venv-flip/bin/python; do the same by hand, or set \
    CHRONOLUX_FLIP_PYTHON to a Python that has both packages";

/// Whether the tests run under CI (`CI` set, and not empty, `0` or `false`).
pub fn in_ci() -> bool {
    std::env::var("CI").is_ok_and(|v| {
        let v = v.trim().to_ascii_lowercase();
        !(v.is_empty() || v == "0" || v == "false")
    })
}

/// The policy of the [module documentation](self): `found` if it is `Some`; otherwise,
/// under CI a panic naming `what` is missing and `remedy` (how `.ci/run` provides it),
/// outside CI a `SKIPPED: …` line on stderr and `None` (the test then returns).
///
/// ```ignore
/// let Some(path) = shared_file("scenes/BoxAnimated.glb") else { return };
/// ```
pub fn require_external<T>(found: Option<T>, what: &str, remedy: &str) -> Option<T> {
    if found.is_some() {
        return found;
    }
    if in_ci() {
        panic!("missing under CI (CI is set, so this test may not skip): {what}. {remedy}.");
    }
    eprintln!("SKIPPED: missing {what} ({remedy}).");
    None
}

/// Path of `rel` inside `shared/` beside the repository, whether or not it exists.
pub fn shared_path(rel: &str) -> PathBuf {
    Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/../../../shared")).join(rel)
}

/// Path of `rel` inside `shared/` beside the repository, under the policy of
/// [`require_external`] when it does not exist.
pub fn shared_file(rel: &str) -> Option<PathBuf> {
    let p = shared_path(rel);
    let found = p.exists().then(|| p.clone());
    require_external(
        found,
        &format!("shared data file {} (shared/{rel})", p.display()),
        SHARED_REMEDY,
    )
}

/// The Python interpreter named by [`FLIP_PYTHON_VAR`] (default `python3`) if it can
/// `import flip_evaluator, numpy` (what the agreement tests' scripts use), under the
/// policy of [`require_external`] otherwise.
pub fn flip_python() -> Option<String> {
    let py = std::env::var(FLIP_PYTHON_VAR).unwrap_or_else(|_| "python3".into());
    let run = std::process::Command::new(&py)
        .args(["-c", "import flip_evaluator, numpy"])
        .output();
    let found = match &run {
        Ok(o) if o.status.success() => Some(py.clone()),
        _ => None,
    };
    let why = match &run {
        Ok(o) => String::from_utf8_lossy(&o.stderr)
            .lines()
            .last()
            .unwrap_or("")
            .to_string(),
        Err(e) => e.to_string(),
    };
    require_external(
        found,
        &format!(
            "the Python package flip-evaluator (`{py} -c \"import flip_evaluator, numpy\"` \
             fails: {why}; {FLIP_PYTHON_VAR}={})",
            std::env::var(FLIP_PYTHON_VAR).unwrap_or_else(|_| "unset".into())
        ),
        FLIP_REMEDY,
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The policy for a missing file, in whichever mode this run is in.
    #[test]
    fn missing_file_skips_outside_ci_and_fails_under_ci() {
        let rel = "no-such-folder/no-such-file.exr";
        assert!(!shared_path(rel).exists());
        let got = std::panic::catch_unwind(|| shared_file(rel));
        if in_ci() {
            let msg = got.unwrap_err().downcast::<String>().unwrap();
            assert!(
                msg.contains("no-such-file.exr") && msg.contains("shared/"),
                "{msg}"
            );
        } else {
            assert_eq!(got.unwrap(), None);
        }
        // A present path is returned in both modes (`shared/` itself, when it is there).
        let root = shared_path("");
        if root.exists() {
            assert_eq!(shared_file(""), Some(root));
        }
    }
}
