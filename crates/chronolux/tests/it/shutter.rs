//! `--shutter`: motion blur of the path tracer and BDPT, recorded in run.json, with clear
//! errors.

use crate::common::*;

fn render(dir: &std::path::Path, extra: &[&str]) -> std::process::Output {
    let mut args = vec![
        "render",
        "--output",
        dir.to_str().unwrap(),
        "--frames",
        "12",
        "--no-preview",
    ];
    args.extend(FAST);
    args.extend(extra);
    // The path tracer unless the test names another method (the default is spacetime-dept).
    if !extra.contains(&"--method") {
        args.extend(["--method", "path"]);
    }
    run(&args)
}

#[test]
fn shutter_out_of_range_or_with_another_method_is_an_error() {
    let dir = temp_dir("shutter-bad");
    for s in ["-0.1", "1.5", "NaN"] {
        fails(&render(&dir, &["--shutter", s]), &["--shutter", "[0, 1]"]);
    }
    fails(
        &render(&dir, &["--shutter", "0.5", "--method", "dept"]),
        &["--shutter", "path", "bdpt"],
    );
}

#[test]
fn shutter_blurs_the_demo_and_is_recorded() {
    let frame = |d: &std::path::Path| std::fs::read(d.join("frame_0012.exr")).unwrap();
    let sharp = temp_dir("shutter-none");
    ok(&render(&sharp, &[]));
    let closed = temp_dir("shutter-zero");
    ok(&render(&closed, &["--shutter", "0"]));
    // A closed shutter is the render without motion blur, bit for bit.
    assert_eq!(frame(&sharp), frame(&closed));
    let open = temp_dir("shutter-open");
    ok(&render(&open, &["--shutter", "0.5"]));
    assert_eq!(manifest(&open)["settings"]["shutter"], 0.5);
    assert_eq!(manifest(&sharp)["settings"]["shutter"], 0.0);
    // The demo's block moves at frame 12: the blurred frame differs.
    assert_ne!(frame(&sharp), frame(&open));
    let bdpt = temp_dir("shutter-bdpt");
    ok(&render(&bdpt, &["--shutter", "0.5", "--method", "bdpt"]));
    assert_eq!(manifest(&bdpt)["settings"]["shutter"], 0.5);
}
