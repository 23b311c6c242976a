//! Output folder: atomic writes, frame sink, resume check, manifest, preview.

use std::io::Write;

use chronolux_core::color::Rgb;
use chronolux_io::image::{Image, read_exr, read_png_rgb8, write_png};
use chronolux_io::output::{
    FrameRecord, FrameSink, Manifest, OutputError, frame_exr_name, frame_png_name, frame_stem,
    timestamp_utc, tmp_path, write_atomic, write_preview,
};

use crate::image::{temp_dir, test_image, tmp_files};

#[test]
fn frame_names() {
    assert_eq!(frame_stem(0), "frame_0000");
    assert_eq!(frame_stem(47), "frame_0047");
    assert_eq!(frame_stem(12345), "frame_12345");
    assert_eq!(frame_exr_name(3), "frame_0003.exr");
    assert_eq!(frame_png_name(3), "frame_0003.png");
}

#[test]
fn timestamps_are_rfc3339_utc() {
    use std::time::{Duration, UNIX_EPOCH};
    assert_eq!(timestamp_utc(UNIX_EPOCH), "1970-01-01T00:00:00Z");
    // 2000-02-29T12:34:56Z (leap day) and 2026-11-22T01:27:00Z.
    assert_eq!(
        timestamp_utc(UNIX_EPOCH + Duration::from_secs(951_827_696)),
        "2000-02-29T12:34:56Z"
    );
    assert_eq!(
        timestamp_utc(UNIX_EPOCH + Duration::from_secs(1_795_310_820)),
        "2026-11-22T01:27:00Z"
    );
}

#[test]
fn atomic_write_leaves_no_tmp_and_cleans_up_on_error() {
    let dir = temp_dir("atomic");
    let path = dir.join("x.txt");
    assert_eq!(tmp_path(&path), dir.join("x.txt.tmp"));
    write_atomic(&path, |w| w.write_all(b"first")).unwrap();
    assert_eq!(std::fs::read(&path).unwrap(), b"first");
    assert!(tmp_files(&dir).is_empty());

    // A failing writer leaves the old file intact and no temporary.
    let err = write_atomic(&path, |w| {
        w.write_all(b"half")?;
        Err::<(), _>(std::io::Error::other("encoder failed"))
    })
    .unwrap_err();
    assert_eq!(err.to_string(), "encoder failed");
    assert_eq!(std::fs::read(&path).unwrap(), b"first");
    assert!(tmp_files(&dir).is_empty());
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn sink_writes_frames_and_checks_completeness() {
    let dir = temp_dir("sink").join("nested").join("out");
    let sink = FrameSink::create(&dir).unwrap();
    assert!(dir.is_dir());
    assert_eq!(
        std::fs::read_dir(&dir).unwrap().count(),
        0,
        "probe file left behind"
    );
    assert!(!sink.is_complete(0));

    let img = test_image(40, 30);
    sink.write_frame(0, &img, 0.0).unwrap();
    assert!(sink.is_complete(0));
    assert!(!sink.is_complete(1));
    assert_eq!(sink.exr_path(0), dir.join("frame_0000.exr"));
    assert_eq!(read_exr(sink.exr_path(0)).unwrap(), img);
    let png = read_png_rgb8(sink.png_path(0)).unwrap();
    assert_eq!((png.width, png.height), (40, 30));
    assert!(tmp_files(&dir).is_empty());

    // Truncated EXR (as after a crash mid-write without atomic rename): not complete.
    sink.write_frame(1, &img, 0.0).unwrap();
    let bytes = std::fs::read(sink.exr_path(1)).unwrap();
    std::fs::write(sink.exr_path(1), &bytes[..bytes.len() - 100]).unwrap();
    assert!(!sink.is_complete(1));
    // Header only.
    std::fs::write(sink.exr_path(1), &bytes[..bytes.len() / 4]).unwrap();
    assert!(!sink.is_complete(1));
    std::fs::write(sink.exr_path(1), b"").unwrap();
    assert!(!sink.is_complete(1));
    // EXR fine but PNG missing.
    sink.write_frame(2, &img, 0.0).unwrap();
    std::fs::remove_file(sink.png_path(2)).unwrap();
    assert!(!sink.is_complete(2));
    // EXR fine but PNG truncated.
    sink.write_frame(3, &img, 0.0).unwrap();
    let png = std::fs::read(sink.png_path(3)).unwrap();
    std::fs::write(sink.png_path(3), &png[..png.len() - 1]).unwrap();
    assert!(!sink.is_complete(3));
    std::fs::write(sink.png_path(3), &png).unwrap();
    assert!(sink.is_complete(3));

    std::fs::remove_dir_all(dir.parent().unwrap().parent().unwrap()).unwrap();
}

#[test]
fn sink_in_unwritable_folder_is_an_error_naming_the_path() {
    let base = temp_dir("unwritable");
    let file = base.join("regular-file");
    std::fs::write(&file, b"x").unwrap();
    let bad = file.join("out");
    let err = FrameSink::create(&bad).unwrap_err();
    assert!(matches!(err, OutputError::Unwritable { .. }), "{err:?}");
    let msg = err.to_string();
    assert!(msg.contains(&bad.display().to_string()), "{msg}");
    assert!(!msg.contains('\n'), "{msg}");
    // The path itself being a regular file.
    let err = FrameSink::create(&file).unwrap_err();
    assert!(err.to_string().contains("regular-file"), "{err}");
    std::fs::remove_dir_all(base).unwrap();
}

fn record(frame: u32, wall_s: f64) -> FrameRecord {
    FrameRecord::new(
        frame,
        frame as f32 / 24.0,
        wall_s,
        serde_json::json!({ "spp": 16 }),
    )
}

#[test]
fn manifest_round_trip_and_merge() {
    let dir = temp_dir("manifest");
    let sink = FrameSink::create(&dir).unwrap();
    assert!(sink.read_manifest().unwrap().is_none());

    let mut m = Manifest::new(
        vec!["chronolux".into(), "render".into(), "scene.glb".into()],
        serde_json::json!({ "spp": 16, "exposure": 0.0 }),
        serde_json::json!({ "triangles": 36, "frames": [0, 47] }),
    );
    m.upsert_frame(record(2, 1.5));
    m.upsert_frame(record(0, 1.25));
    assert_eq!(m.frames.iter().map(|r| r.frame).collect::<Vec<_>>(), [0, 2]);
    assert_eq!(m.frames[0].file_exr, "frame_0000.exr");
    assert_eq!(m.frames[0].file_png, "frame_0000.png");
    assert!(
        m.started.ends_with('Z') && m.started.len() == 20,
        "{}",
        m.started
    );
    assert!(m.finished.is_none());
    sink.write_manifest(&m).unwrap();
    assert!(tmp_files(&dir).is_empty());
    let text = std::fs::read_to_string(sink.manifest_path()).unwrap();
    assert!(
        text.contains("\n  \"chronolux_version\""),
        "pretty JSON expected:\n{text}"
    );
    let back = sink.read_manifest().unwrap().unwrap();
    assert_eq!(back, m);

    // Resume: a new run re-renders frame 2 and renders frame 1; frame 0 comes from before.
    let mut m2 = Manifest::new(
        vec!["chronolux".into()],
        serde_json::json!({}),
        serde_json::json!({}),
    );
    m2.upsert_frame(record(2, 9.0));
    m2.upsert_frame(record(1, 3.0));
    m2.merge_earlier(&back);
    assert_eq!(
        m2.frames
            .iter()
            .map(|r| (r.frame, r.wall_s))
            .collect::<Vec<_>>(),
        [(0, 1.25), (1, 3.0), (2, 9.0)]
    );
    m2.finish(13.25);
    assert!(m2.finished.is_some());
    sink.write_manifest(&m2).unwrap();
    assert_eq!(sink.read_manifest().unwrap().unwrap(), m2);

    // A corrupt manifest is an error naming the file.
    std::fs::write(sink.manifest_path(), b"{ not json").unwrap();
    let err = sink.read_manifest().unwrap_err();
    assert!(err.to_string().contains("run.json"), "{err}");
    std::fs::remove_dir_all(dir).unwrap();
}

/// Frame count and size of a GIF.
fn gif_info(path: &std::path::Path) -> (usize, u16, u16, Vec<u16>) {
    let mut opts = gif::DecodeOptions::new();
    opts.set_color_output(gif::ColorOutput::RGBA);
    let mut dec = opts.read_info(std::fs::File::open(path).unwrap()).unwrap();
    let (w, h) = (dec.width(), dec.height());
    let mut n = 0;
    let mut delays = Vec::new();
    while let Some(f) = dec.read_next_frame().unwrap() {
        n += 1;
        delays.push(f.delay);
    }
    (n, w, h, delays)
}

#[test]
fn preview_gif_has_all_frames() {
    let dir = temp_dir("preview");
    let sink = FrameSink::create(&dir).unwrap();
    let frames = [0u32, 1, 2, 3, 4];
    for &f in &frames {
        let mut img = Image::new(64, 48);
        for y in 0..48 {
            for x in 0..64 {
                img.set(
                    x,
                    y,
                    Rgb::new(x as f32 / 64.0, y as f32 / 48.0, f as f32 / 5.0),
                );
            }
        }
        sink.write_frame(f, &img, 0.0).unwrap();
    }
    let gif_path = write_preview(&dir, &frames, 24.0).unwrap();
    assert_eq!(gif_path, dir.join("preview.gif"));
    let (n, w, h, delays) = gif_info(&gif_path);
    assert_eq!((n, w, h), (5, 64, 48));
    assert!(delays.iter().all(|&d| d == 4), "{delays:?}");
    assert!(tmp_files(&dir).is_empty());

    // Non-contiguous frames are fine (the MP4, if any, is skipped).
    let gif_path = write_preview(&dir, &[4, 0, 2], 10.0).unwrap();
    let (n, _, _, delays) = gif_info(&gif_path);
    assert_eq!(n, 3);
    assert!(delays.iter().all(|&d| d == 10), "{delays:?}");
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn preview_downscales_long_side_to_512() {
    let dir = temp_dir("preview-big");
    let mut img = Image::new(1100, 300);
    // White up to column 550, black after: output column 256 straddles the edge.
    for y in 0..300 {
        for x in 0..551 {
            img.set(x, y, Rgb::ONE);
        }
    }
    write_png(dir.join("frame_0007.png"), &img, 0.0).unwrap();
    let gif_path = write_preview(&dir, &[7], 12.0).unwrap();
    let (n, w, h, _) = gif_info(&gif_path);
    assert_eq!((n, w, h), (1, 512, 140));
    // Content survives: white on the left, black on the right, a mix in the middle column.
    let mut opts = gif::DecodeOptions::new();
    opts.set_color_output(gif::ColorOutput::RGBA);
    let mut dec = opts
        .read_info(std::fs::File::open(&gif_path).unwrap())
        .unwrap();
    let frame = dec.read_next_frame().unwrap().unwrap();
    let px = |x: usize, y: usize| frame.buffer[(y * 512 + x) * 4];
    assert!(
        px(10, 70) >= 250 && px(250, 10) >= 250,
        "{} {}",
        px(10, 70),
        px(250, 10)
    );
    assert!(
        px(300, 70) <= 5 && px(511, 139) <= 5,
        "{} {}",
        px(300, 70),
        px(511, 139)
    );
    let mid = px(256, 70);
    assert!((100..=250).contains(&mid), "middle column {mid}");
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn preview_errors() {
    let dir = temp_dir("preview-err");
    assert!(write_preview(&dir, &[], 24.0).is_err());
    let err = write_preview(&dir, &[0], 24.0).unwrap_err();
    assert!(err.to_string().contains("frame_0000.png"), "{err}");
    write_png(dir.join("frame_0000.png"), &test_image(8, 8), 0.0).unwrap();
    write_png(dir.join("frame_0001.png"), &test_image(9, 8), 0.0).unwrap();
    let err = write_preview(&dir, &[0, 1], 24.0).unwrap_err();
    assert!(err.to_string().contains("frame_0001.png"), "{err}");
    assert!(!dir.join("preview.gif").exists());
    assert!(tmp_files(&dir).is_empty());
    std::fs::remove_dir_all(dir).unwrap();
}
