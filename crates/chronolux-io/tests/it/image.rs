//! Image I/O: EXR and PNG round trips, tone mapping, the Mitsuba reference.

use std::path::{Path, PathBuf};

use chronolux_core::color::Rgb;
use chronolux_io::image::{
    Image, ImageError, read_exr, read_png_rgb8, tonemap_srgb8, write_exr, write_png,
};

/// A fresh, unique folder under the system temp dir.
pub fn temp_dir(name: &str) -> PathBuf {
    use std::sync::atomic::{AtomicU32, Ordering};
    static N: AtomicU32 = AtomicU32::new(0);
    let nanos = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .unwrap()
        .subsec_nanos();
    let dir = std::env::temp_dir().join(format!(
        "chronolux-io-{name}-{}-{nanos}-{}",
        std::process::id(),
        N.fetch_add(1, Ordering::Relaxed)
    ));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// Names of the files in `dir` ending in `.tmp`.
pub fn tmp_files(dir: &Path) -> Vec<String> {
    std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.ends_with(".tmp"))
        .collect()
}

/// A non-square image with awkward values (tiny, huge, negative, odd bit patterns).
pub fn test_image(w: u32, h: u32) -> Image {
    let mut img = Image::new(w, h);
    for y in 0..h {
        for x in 0..w {
            let i = (y * w + x) as f32;
            img.set(
                x,
                y,
                Rgb::new(
                    (i * 0.1234567).sin() * 3.0,
                    1e-7 * i + 1e-30,
                    f32::from_bits(0x3e00_0001 + (x * 7919 + y * 104_729)),
                ),
            );
        }
    }
    img
}

#[test]
fn image_accessors_and_mean() {
    let mut img = Image::new(3, 2);
    assert_eq!(img.pixels.len(), 6);
    img.set(2, 1, Rgb::new(6.0, 0.0, 3.0));
    assert_eq!(img.get(2, 1), Rgb::new(6.0, 0.0, 3.0));
    assert_eq!(
        img.pixels[5],
        Rgb::new(6.0, 0.0, 3.0),
        "row-major, top row first"
    );
    assert_eq!(img.mean(), Rgb::new(1.0, 0.0, 0.5));
    assert!((img.mean_value() - 0.5).abs() < 1e-7);
}

#[test]
fn exr_round_trip_is_bit_exact() {
    let dir = temp_dir("exr-rt");
    let path = dir.join("a.exr");
    let img = test_image(37, 19);
    write_exr(&path, &img).unwrap();
    let back = read_exr(&path).unwrap();
    assert_eq!((back.width, back.height), (37, 19));
    for (a, b) in img.pixels.iter().zip(&back.pixels) {
        for k in 0..3 {
            assert_eq!(a[k].to_bits(), b[k].to_bits());
        }
    }
    assert!(tmp_files(&dir).is_empty());
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn exr_write_replaces_existing_file() {
    let dir = temp_dir("exr-replace");
    let path = dir.join("a.exr");
    write_exr(&path, &test_image(8, 8)).unwrap();
    let img = Image::from_pixels(2, 1, vec![Rgb::splat(0.25), Rgb::splat(4.0)]);
    write_exr(&path, &img).unwrap();
    assert_eq!(read_exr(&path).unwrap(), img);
    assert!(tmp_files(&dir).is_empty());
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn exr_write_of_empty_image_is_an_error_and_leaves_nothing() {
    let dir = temp_dir("exr-empty");
    let path = dir.join("a.exr");
    let err = write_exr(&path, &Image::new(0, 4)).unwrap_err();
    assert!(matches!(err, ImageError::Invalid { .. }), "{err}");
    assert!(!path.exists());
    assert!(tmp_files(&dir).is_empty());
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn exr_read_errors_name_the_file() {
    let dir = temp_dir("exr-bad");
    let missing = dir.join("missing.exr");
    let err = read_exr(&missing).unwrap_err();
    assert!(err.to_string().contains("missing.exr"), "{err}");

    let garbage = dir.join("garbage.exr");
    std::fs::write(&garbage, b"this is not an exr file").unwrap();
    let err = read_exr(&garbage).unwrap_err();
    assert!(err.to_string().contains("garbage.exr"), "{err}");

    let good = dir.join("good.exr");
    write_exr(&good, &test_image(64, 64)).unwrap();
    let bytes = std::fs::read(&good).unwrap();
    let truncated = dir.join("truncated.exr");
    std::fs::write(&truncated, &bytes[..bytes.len() / 2]).unwrap();
    let err = read_exr(&truncated).unwrap_err();
    assert!(err.to_string().contains("truncated.exr"), "{err}");
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn reads_mitsuba_reference() {
    let Some(path) = chronolux_core::testing::shared_file("peers/mitsuba-refs/mitsuba_f00.exr")
    else {
        return;
    };
    let img = read_exr(&path).unwrap();
    assert_eq!((img.width, img.height), (256, 256));
    let mean = img.mean_value();
    eprintln!(
        "{}: mean pixel value {mean}, per channel {}",
        path.display(),
        img.mean()
    );
    assert!(
        (mean - 0.152).abs() <= 0.01,
        "mean pixel value {mean}, README says ≈ 0.152"
    );
    assert!(
        img.pixels
            .iter()
            .all(|p| p.is_finite() && p.min_element() >= 0.0)
    );
}

#[test]
fn tonemap_known_values() {
    let img = Image::from_pixels(
        6,
        1,
        vec![
            Rgb::new(0.0, 0.5, 1.0),
            Rgb::new(1.5, 100.0, -1.0),
            Rgb::new(f32::NAN, f32::INFINITY, 0.0031308),
            Rgb::new(0.25, 0.25, 0.25),
            Rgb::splat(0.04),
            Rgb::splat(1e-4),
        ],
    );
    let t = tonemap_srgb8(&img, 0.0);
    assert_eq!(t[0], [0, 188, 255]);
    assert_eq!(t[1], [255, 255, 0]);
    assert_eq!(t[2], [0, 255, 10]);
    assert_eq!(t[3], [137, 137, 137]);
    assert_eq!(t[4], [56, 56, 56]);
    assert_eq!(t[5], [0, 0, 0]);
    // Exposure +1 doubles: 0.25 → 0.5 → 188; −1 halves: 1.0 → 0.5 → 188.
    let up = tonemap_srgb8(&img, 1.0);
    assert_eq!(up[3], [188, 188, 188]);
    let down = tonemap_srgb8(&img, -1.0);
    assert_eq!(down[0][2], 188);
}

#[test]
fn tonemap_is_one_to_one_with_srgb_decode_below_one() {
    // Every 8-bit code decoded to linear and re-encoded gives the same code.
    let codes: Vec<Rgb> = (0..=255u8)
        .map(|v| Rgb::splat(chronolux_core::color::srgb_to_linear(f32::from(v) / 255.0)))
        .collect();
    let img = Image::from_pixels(256, 1, codes);
    let t = tonemap_srgb8(&img, 0.0);
    for (v, p) in t.iter().enumerate() {
        assert_eq!(*p, [v as u8; 3]);
    }
}

#[test]
fn png_round_trip_of_known_values() {
    let dir = temp_dir("png-rt");
    let path = dir.join("a.png");
    let img = Image::from_pixels(
        2,
        3,
        vec![
            Rgb::new(0.0, 0.0, 0.0),
            Rgb::new(0.5, 0.5, 0.5),
            Rgb::new(1.0, 1.0, 1.0),
            Rgb::new(2.0, 7.5, 1e9),
            Rgb::new(0.5, 0.0, 1.0),
            Rgb::new(-3.0, 0.0, 0.0),
        ],
    );
    write_png(&path, &img, 0.0).unwrap();
    let back = read_png_rgb8(&path).unwrap();
    assert_eq!((back.width, back.height), (2, 3));
    assert_eq!(
        back.pixels,
        vec![
            [0, 0, 0],
            [188, 188, 188],
            [255, 255, 255],
            [255, 255, 255],
            [188, 0, 255],
            [0, 0, 0]
        ]
    );
    assert_eq!(back.get(0, 2), [188, 0, 255]);
    assert_eq!(back.pixels, tonemap_srgb8(&img, 0.0));
    // Decoding back to linear gives 0.5 within the 8-bit step.
    let lin = back.to_linear();
    assert!((lin.get(1, 0).x - 0.5).abs() < 0.003);
    assert!(tmp_files(&dir).is_empty());
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn png_has_srgb_chunk() {
    let dir = temp_dir("png-srgb");
    let path = dir.join("a.png");
    write_png(&path, &test_image(4, 4), 0.0).unwrap();
    let bytes = std::fs::read(&path).unwrap();
    assert!(bytes.windows(4).any(|w| w == b"sRGB"), "no sRGB chunk");
    let decoder = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(&path).unwrap()));
    let reader = decoder.read_info().unwrap();
    assert!(reader.info().srgb.is_some());
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn png_write_into_missing_folder_is_an_error_naming_the_file() {
    let dir = temp_dir("png-missing");
    let path = dir.join("no-such-folder").join("a.png");
    let err = write_png(&path, &test_image(2, 2), 0.0).unwrap_err();
    assert!(err.to_string().contains("a.png"), "{err}");
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn reads_f16_rgba_exr() {
    use exr::prelude::f16;
    let dir = temp_dir("exr-f16");
    let path = dir.join("half.exr");
    exr::prelude::write_rgba_file(&path, 5, 3, |x, y| {
        let v = f16::from_f32(x as f32 * 0.5 + y as f32 * 2.0);
        (
            v,
            f16::from_f32(0.25),
            f16::from_f32(-1.5),
            f16::from_f32(0.5),
        )
    })
    .unwrap();
    let img = read_exr(&path).unwrap();
    assert_eq!((img.width, img.height), (5, 3));
    assert_eq!(img.get(3, 2), Rgb::new(5.5, 0.25, -1.5));
    assert_eq!(img.get(0, 0), Rgb::new(0.0, 0.25, -1.5));
    std::fs::remove_dir_all(dir).unwrap();
}

// ---------------------------------------------------------------------------------------
// View transforms and automatic exposure

use chronolux_io::image::{AUTO_EXPOSURE_KEY, View, auto_exposure, tonemap_view_srgb8};

#[test]
fn agx_is_monotone_neutral_and_rolls_off_softly() {
    let agx = |v: f32| View::Agx.apply(Rgb::splat(v));
    // Black stays black (the curve's foot −0.00232 clamps to 0).
    assert!(agx(0.0).max_element() < 1e-3, "{}", agx(0.0));
    let mut prev = -1.0f32;
    let mut v = 1e-3f32; // above the log encoding's floor, 2^−12.47 ≈ 1.8e-4
    while v < 100.0 {
        let d = agx(v);
        // Neutral: grey stays grey. The published matrices' rows sum to 1 within 2e-4, so
        // channels differ by at most a few 1e-4.
        assert!(d.max_element() - d.min_element() < 1e-3, "{v}: {d}");
        // Monotone; strictly until the 4.03-stop ceiling (16) clamps the log encoding.
        assert!(
            d.x >= prev && (d.x > prev || v > 16.0),
            "{v}: {} after {prev}",
            d.x
        );
        prev = d.x;
        v *= 1.1;
    }
    // Middle grey well inside, diffuse white unclipped, 4 stops over it (≈ 16) reaches 1:
    // the roll-off that keeps a sun-lit scene from clipping.
    assert!((0.35..0.55).contains(&agx(0.18).x), "{}", agx(0.18));
    assert!((0.6..0.9).contains(&agx(1.0).x), "{}", agx(1.0));
    assert!(agx(16.0).x > 0.99 && agx(1000.0).x <= 1.0);
    // Standard: the old clamp and sRGB curve, byte for byte.
    let img = Image {
        width: 3,
        height: 1,
        pixels: vec![Rgb::splat(0.1), Rgb::new(0.5, 2.0, f32::NAN), Rgb::ZERO],
    };
    assert_eq!(
        tonemap_view_srgb8(&img, 0.5, View::Standard),
        tonemap_srgb8(&img, 0.5)
    );
    // A NaN channel counts as 0 (before AgX's matrices mix the channels): an all-NaN
    // pixel is black.
    let nan = Image {
        width: 1,
        height: 1,
        pixels: vec![Rgb::splat(f32::NAN)],
    };
    assert_eq!(tonemap_view_srgb8(&nan, 0.0, View::Agx), vec![[0, 0, 0]]);
}

#[test]
fn auto_exposure_puts_the_90th_percentile_at_the_key() {
    // A sun-lit surface of radiance 1600 on 80% of the pixels, a dark rest: the 90th
    // percentile is the surface, brought to the key.
    let mut px = vec![Rgb::splat(1600.0); 80];
    px.extend(vec![Rgb::splat(0.01); 20]);
    let ev = auto_exposure(&px);
    assert!(
        (ev - (AUTO_EXPOSURE_KEY / 1600.0).log2()).abs() < 1e-5,
        "{ev}"
    );
    // A small bright object on black: the 90th percentile is black, the 99th is used.
    let mut px = vec![Rgb::ZERO; 95];
    px.extend(vec![Rgb::splat(4.0); 5]);
    assert!((auto_exposure(&px) - (AUTO_EXPOSURE_KEY / 4.0).log2()).abs() < 1e-5);
    // All black, empty or non-finite: no change.
    assert_eq!(auto_exposure(&[Rgb::ZERO; 10]), 0.0);
    assert_eq!(auto_exposure(&[]), 0.0);
    assert_eq!(auto_exposure(&[Rgb::splat(f32::NAN)]), 0.0);
}
