//! `chronolux compare`: image error and flicker between two frame sequences.
//!
//! Frames are matched by number: the frame number of `NAME.exr` is the run of digits that
//! ends its stem (`frame_0012.exr`, `mitsuba_f12.exr` → 12; `frame_0012_A.exr` is
//! ignored). Every test frame needs a reference frame of the same size; reference frames
//! without a test frame are ignored. The metrics and their definitions are those of
//! [`chronolux_core::metrics`].

use anyhow::{Context, Result, bail};
use chronolux_core::metrics::{self, flip};
use chronolux_io::image::{Image, Rgb8Image, read_exr, tonemap_srgb8, write_png_rgb8};
use clap::Args;
use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

#[derive(Args, Debug)]
pub struct CompareArgs {
    /// Folder of the frames under test (linear EXRs, e.g. frame_NNNN.exr).
    pub test_dir: PathBuf,
    /// Folder of the reference frames (linear EXRs, matched to the test frames by number).
    pub ref_dir: PathBuf,
    /// Write one CSV row per frame: frame,relmse,rmse,psnr,flip_hdr,flip_ldr,flicker,
    /// flicker_noref (the flickers empty when frame − 1 is not compared; flicker_noref is
    /// mean |I_t − I_{t−1}| of the test alone).
    #[arg(long, value_name = "FILE")]
    pub csv: Option<PathBuf>,
    /// Write an SVG plot of FLIP, relMSE and flicker per frame.
    #[arg(long, value_name = "FILE")]
    pub plot: Option<PathBuf>,
    /// A second sequence under test (e.g. the same frames rendered frame by frame at equal
    /// time), measured against the same reference: its summary is printed and `--plot`
    /// draws it dashed in the same panels, on the same axes.
    #[arg(long, value_name = "DIR")]
    pub versus: Option<PathBuf>,
    /// Write the HDR-FLIP error map of every frame as DIR/flip_NNNN.png (magma colour map,
    /// as the FLIP tool draws it).
    #[arg(long, value_name = "DIR")]
    pub heatmaps: Option<PathBuf>,
    /// Write an animated GIF of test | reference | HDR-FLIP heat map (images tone-mapped
    /// as the PNGs: exposure 0, clipped, sRGB).
    #[arg(long, value_name = "FILE")]
    pub preview: Option<PathBuf>,
    /// Frames per second of the preview GIF.
    #[arg(long, default_value_t = 24.0, value_name = "FPS")]
    pub fps: f32,
    /// Pixels per degree for FLIP (default 67.02: 0.7 m from a 0.7 m wide 3840-pixel
    /// monitor, FLIP's default).
    #[arg(long, value_name = "PPD")]
    pub ppd: Option<f32>,
}

/// Metrics of one frame.
#[derive(Clone, Debug, serde::Serialize)]
pub struct FrameMetrics {
    pub frame: u32,
    pub relmse: f64,
    pub rmse: f64,
    pub psnr: f64,
    pub flip_hdr: f64,
    pub flip_ldr: f64,
    /// Against the reference; `None` when frame − 1 is not compared.
    pub flicker: Option<f64>,
    /// Without reference: mean |I_t − I_{t−1}| of the test frames (absolute; the truth is 0
    /// on a static scene); `None` when frame − 1 is not compared.
    pub flicker_noref: Option<f64>,
}

/// Frame number → path of every `*.exr` in `dir` whose stem ends with digits.
pub fn list_frames(dir: &Path) -> Result<BTreeMap<u32, PathBuf>> {
    let entries =
        std::fs::read_dir(dir).with_context(|| format!("cannot read folder {}", dir.display()))?;
    let mut frames = BTreeMap::new();
    for e in entries {
        let path = e
            .with_context(|| format!("cannot read folder {}", dir.display()))?
            .path();
        if !path
            .extension()
            .is_some_and(|x| x.eq_ignore_ascii_case("exr"))
        {
            continue;
        }
        let Some(stem) = path.file_stem().and_then(|s| s.to_str()) else {
            continue;
        };
        let digits: String = stem
            .chars()
            .rev()
            .take_while(|c| c.is_ascii_digit())
            .collect::<Vec<_>>()
            .into_iter()
            .rev()
            .collect();
        let Ok(n) = digits.parse::<u32>() else {
            continue;
        };
        if let Some(other) = frames.insert(n, path.clone()) {
            bail!(
                "two files for frame {n} in {}: {} and {}",
                dir.display(),
                other.display(),
                path.display()
            );
        }
    }
    if frames.is_empty() {
        bail!(
            "no frames (NAME_NNNN.exr) in {} — is it the right folder?",
            dir.display()
        );
    }
    Ok(frames)
}

fn read(path: &Path) -> Result<Image> {
    read_exr(path).with_context(|| format!("reading {}", path.display()))
}

/// Compares the frames of `test` with `reference` (number → path); calls `each` with each
/// frame's metrics, test image, reference image and HDR-FLIP map as they are computed.
pub fn compare_frames(
    test: &BTreeMap<u32, PathBuf>,
    reference: &BTreeMap<u32, PathBuf>,
    ppd: f32,
    mut each: impl FnMut(&FrameMetrics, &Image, &Image, &flip::FlipMap) -> Result<()>,
) -> Result<Vec<FrameMetrics>> {
    for (&f, p) in test {
        if !reference.contains_key(&f) {
            bail!(
                "frame {f}: no reference frame for {} (reference folder has frames {})",
                p.display(),
                ranges(reference.keys().copied())
            );
        }
    }
    let mut out = Vec::new();
    let mut prev: Option<(u32, Image, Image)> = None;
    for (&f, tp) in test {
        let rp = &reference[&f];
        let t = read(tp)?;
        let r = read(rp)?;
        if (t.width, t.height) != (r.width, r.height) {
            bail!(
                "frame {f}: test {} is {}x{} but reference {} is {}x{}",
                tp.display(),
                t.width,
                t.height,
                rp.display(),
                r.width,
                r.height
            );
        }
        let (w, h) = (t.width as usize, t.height as usize);
        let hdr = flip::flip_hdr(
            &r.pixels,
            &t.pixels,
            w,
            h,
            &flip::HdrSettings {
                ppd,
                ..Default::default()
            },
        );
        let ldr = flip::flip_ldr(&r.pixels, &t.pixels, w, h, ppd);
        let flicker = match &prev {
            Some((pf, pt, pr)) if *pf + 1 == f => Some(metrics::flicker(
                &pt.pixels, &t.pixels, &pr.pixels, &r.pixels,
            )),
            _ => None,
        };
        let flicker_noref = match &prev {
            Some((pf, pt, _)) if *pf + 1 == f => {
                Some(metrics::flicker_no_reference(&pt.pixels, &t.pixels))
            }
            _ => None,
        };
        let m = FrameMetrics {
            frame: f,
            relmse: metrics::rel_mse(&t.pixels, &r.pixels),
            rmse: metrics::rmse(&t.pixels, &r.pixels),
            psnr: metrics::psnr(&t.pixels, &r.pixels),
            flip_hdr: hdr.mean(),
            flip_ldr: ldr.mean(),
            flicker,
            flicker_noref,
        };
        each(&m, &t, &r, &hdr)?;
        out.push(m);
        prev = Some((f, t, r));
    }
    Ok(out)
}

/// `0..=7, 12, 24` style list of frame numbers.
fn ranges(frames: impl Iterator<Item = u32>) -> String {
    let mut parts: Vec<(u32, u32)> = Vec::new();
    for f in frames {
        match parts.last_mut() {
            Some((_, b)) if *b + 1 == f => *b = f,
            _ => parts.push((f, f)),
        }
    }
    if parts.is_empty() {
        return "none".into();
    }
    parts
        .iter()
        .map(|&(a, b)| {
            if a == b {
                a.to_string()
            } else {
                format!("{a}..={b}")
            }
        })
        .collect::<Vec<_>>()
        .join(", ")
}

fn mean(v: impl Iterator<Item = f64>) -> Option<f64> {
    let (s, n) = v.fold((0.0, 0usize), |(s, n), x| (s + x, n + 1));
    (n > 0).then(|| s / n as f64)
}

/// Means over frames: (relMSE, RMSE, PSNR, FLIP-HDR, FLIP-LDR, flicker).
pub struct Summary {
    pub relmse: f64,
    pub rmse: f64,
    pub psnr: f64,
    pub flip_hdr: f64,
    pub flip_ldr: f64,
    pub flicker: Option<f64>,
}

pub fn summarize(m: &[FrameMetrics]) -> Summary {
    Summary {
        relmse: mean(m.iter().map(|x| x.relmse)).unwrap_or(0.0),
        rmse: mean(m.iter().map(|x| x.rmse)).unwrap_or(0.0),
        psnr: mean(m.iter().map(|x| x.psnr)).unwrap_or(0.0),
        flip_hdr: mean(m.iter().map(|x| x.flip_hdr)).unwrap_or(0.0),
        flip_ldr: mean(m.iter().map(|x| x.flip_ldr)).unwrap_or(0.0),
        flicker: mean(m.iter().filter_map(|x| x.flicker)),
    }
}

pub fn csv(m: &[FrameMetrics]) -> String {
    let mut s = String::from("frame,relmse,rmse,psnr,flip_hdr,flip_ldr,flicker,flicker_noref\n");
    for x in m {
        let _ = writeln!(
            s,
            "{},{:e},{:e},{},{},{},{},{}",
            x.frame,
            x.relmse,
            x.rmse,
            x.psnr,
            x.flip_hdr,
            x.flip_ldr,
            x.flicker.map(|v| v.to_string()).unwrap_or_default(),
            x.flicker_noref.map(|v| v.to_string()).unwrap_or_default()
        );
    }
    s
}

/// A hand-written SVG: three panels (FLIP HDR/LDR, relMSE, flicker) against frame number.
pub fn svg_plot(m: &[FrameMetrics], title: &str) -> String {
    svg_plot_many(&[("", m)], title)
}

/// [`svg_plot`] of several sequences on shared axes: the first solid, the others dashed,
/// each series' legend suffixed with its sequence's label.
pub fn svg_plot_many(seqs: &[(&str, &[FrameMetrics])], title: &str) -> String {
    let (pw, ph, left, top, gap) = (720.0f64, 170.0f64, 70.0f64, 40.0f64, 50.0f64);
    let n_panels = 3.0;
    let height = top + n_panels * (ph + gap);
    let mut s = String::new();
    let _ = writeln!(
        s,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{}" height="{height}" font-family="sans-serif" font-size="12">"#,
        left + pw + 230.0
    );
    let _ = writeln!(s, r#"<rect width="100%" height="100%" fill="white"/>"#);
    let _ = writeln!(
        s,
        r#"<text x="{left}" y="22" font-size="15">{}</text>"#,
        xml_escape(title)
    );
    let frames = || seqs.iter().flat_map(|(_, m)| m.iter().map(|x| x.frame));
    let f0 = frames().min().unwrap_or(0) as f64;
    let f1 = frames().max().unwrap_or(1).max(f0 as u32 + 1) as f64;
    // (label, colour, dashed, points)
    type Series = (String, &'static str, bool, Vec<(f64, f64)>);
    let mut panels: Vec<(&str, Vec<Series>)> = vec![
        ("FLIP (mean)", vec![]),
        ("relMSE", vec![]),
        ("flicker", vec![]),
    ];
    for (q, (label, m)) in seqs.iter().enumerate() {
        let name = |n: &str| {
            if label.is_empty() {
                n.to_string()
            } else {
                format!("{n} {label}")
            }
        };
        let dashed = q > 0;
        panels[0].1.push((
            name("HDR-FLIP"),
            "#b5367a",
            dashed,
            m.iter().map(|x| (x.frame as f64, x.flip_hdr)).collect(),
        ));
        panels[0].1.push((
            name("LDR-FLIP"),
            "#f89540",
            dashed,
            m.iter().map(|x| (x.frame as f64, x.flip_ldr)).collect(),
        ));
        panels[1].1.push((
            name("relMSE"),
            "#2c7bb6",
            dashed,
            m.iter().map(|x| (x.frame as f64, x.relmse)).collect(),
        ));
        panels[2].1.push((
            name("flicker"),
            "#1a9641",
            dashed,
            m.iter()
                .filter_map(|x| x.flicker.map(|v| (x.frame as f64, v)))
                .collect(),
        ));
    }
    for (k, (name, series)) in panels.iter().enumerate() {
        let y0 = top + k as f64 * (ph + gap);
        let vmax = series
            .iter()
            .flat_map(|(_, _, _, p)| p.iter().map(|q| q.1))
            .filter(|v| v.is_finite())
            .fold(0.0f64, f64::max);
        let vmax = if vmax > 0.0 { vmax * 1.1 } else { 1.0 };
        let px = |f: f64| left + (f - f0) / (f1 - f0) * pw;
        let py = |v: f64| y0 + ph - (v / vmax).clamp(0.0, 1.0) * ph;
        let _ = writeln!(
            s,
            r##"<rect x="{left}" y="{y0}" width="{pw}" height="{ph}" fill="none" stroke="#888"/>"##
        );
        let _ = writeln!(
            s,
            r#"<text x="{left}" y="{}" font-weight="bold">{name}</text>"#,
            y0 - 6.0
        );
        for i in 0..=4 {
            let v = vmax * i as f64 / 4.0;
            let y = py(v);
            let _ = writeln!(
                s,
                r##"<line x1="{}" y1="{y}" x2="{left}" y2="{y}" stroke="#888"/><text x="{}" y="{}" text-anchor="end">{}</text>"##,
                left - 4.0,
                left - 6.0,
                y + 4.0,
                fmt_tick(v)
            );
        }
        let ticks = 8.min((f1 - f0) as usize);
        for i in 0..=ticks {
            let f = (f0 + (f1 - f0) * i as f64 / ticks.max(1) as f64).round();
            let x = px(f);
            let _ = writeln!(
                s,
                r##"<line x1="{x}" y1="{}" x2="{x}" y2="{}" stroke="#888"/><text x="{x}" y="{}" text-anchor="middle">{f}</text>"##,
                y0 + ph,
                y0 + ph + 4.0,
                y0 + ph + 17.0
            );
        }
        for (j, (label, color, dashed, pts)) in series.iter().enumerate() {
            let dash = if *dashed {
                r#" stroke-dasharray="7 4""#
            } else {
                ""
            };
            let pts: Vec<String> = pts
                .iter()
                .filter(|p| p.1.is_finite())
                .map(|&(f, v)| format!("{:.1},{:.1}", px(f), py(v)))
                .collect();
            if pts.len() == 1 {
                let (x, y) = pts[0].split_once(',').unwrap();
                let _ = writeln!(s, r#"<circle cx="{x}" cy="{y}" r="3" fill="{color}"/>"#);
            } else if !pts.is_empty() {
                let _ = writeln!(
                    s,
                    r#"<polyline points="{}" fill="none" stroke="{color}" stroke-width="1.8"{dash}/>"#,
                    pts.join(" ")
                );
            }
            let ly = y0 + 14.0 + 18.0 * j as f64;
            let _ = writeln!(
                s,
                r#"<line x1="{}" y1="{ly}" x2="{}" y2="{ly}" stroke="{color}" stroke-width="3"{dash}/><text x="{}" y="{}">{}</text>"#,
                left + pw + 10.0,
                left + pw + 30.0,
                left + pw + 35.0,
                ly + 4.0,
                xml_escape(label)
            );
        }
    }
    let _ = writeln!(
        s,
        r#"<text x="{}" y="{}" text-anchor="middle">frame</text>"#,
        left + pw / 2.0,
        height - 8.0
    );
    s.push_str("</svg>\n");
    s
}

fn fmt_tick(v: f64) -> String {
    if v == 0.0 {
        "0".into()
    } else if v.abs() < 0.01 || v.abs() >= 1000.0 {
        format!("{v:.1e}")
    } else {
        format!("{v:.3}")
    }
}

fn xml_escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
}

/// test | reference | heat map side by side, 8-bit sRGB.
fn side_by_side(t: &Image, r: &Image, map: &flip::FlipMap) -> Rgb8Image {
    let (w, h) = (t.width as usize, t.height as usize);
    let (ts, rs, hs) = (
        tonemap_srgb8(t, 0.0),
        tonemap_srgb8(r, 0.0),
        map.magma_rgb8(),
    );
    let mut pixels = Vec::with_capacity(3 * w * h);
    for y in 0..h {
        for src in [&ts, &rs, &hs] {
            pixels.extend_from_slice(&src[y * w..(y + 1) * w]);
        }
    }
    Rgb8Image {
        width: 3 * w as u32,
        height: h as u32,
        pixels,
    }
}

/// Box-downscales by an integer factor so the long side is at most `max_side`.
fn downscale(img: &Rgb8Image, max_side: u32) -> Rgb8Image {
    let k = img.width.max(img.height).div_ceil(max_side).max(1);
    if k == 1 {
        return img.clone();
    }
    let (w, h) = ((img.width / k).max(1), (img.height / k).max(1));
    let mut pixels = Vec::with_capacity((w * h) as usize);
    for y in 0..h {
        for x in 0..w {
            let mut acc = [0u32; 3];
            for dy in 0..k {
                for dx in 0..k {
                    let p = img.get(
                        (x * k + dx).min(img.width - 1),
                        (y * k + dy).min(img.height - 1),
                    );
                    for c in 0..3 {
                        acc[c] += u32::from(p[c]);
                    }
                }
            }
            pixels.push(acc.map(|a| (a / (k * k)) as u8));
        }
    }
    Rgb8Image {
        width: w,
        height: h,
        pixels,
    }
}

/// Longest side of the preview GIF.
const PREVIEW_MAX_SIDE: u32 = 1536;

fn write_gif(path: &Path, frames: &[Rgb8Image], fps: f32) -> Result<()> {
    let first = frames.first().context("no frames for the preview")?;
    if first.width > u16::MAX as u32 || first.height > u16::MAX as u32 {
        bail!("preview too large for a GIF");
    }
    let file =
        std::fs::File::create(path).with_context(|| format!("cannot create {}", path.display()))?;
    let mut enc = gif::Encoder::new(
        std::io::BufWriter::new(file),
        first.width as u16,
        first.height as u16,
        &[],
    )
    .with_context(|| format!("writing {}", path.display()))?;
    enc.set_repeat(gif::Repeat::Infinite)?;
    let delay = ((100.0 / fps).round() as u16).max(2);
    for f in frames {
        let rgb: Vec<u8> = f.pixels.iter().flatten().copied().collect();
        let mut frame = gif::Frame::from_rgb_speed(f.width as u16, f.height as u16, &rgb, 10);
        frame.delay = delay;
        enc.write_frame(&frame)
            .with_context(|| format!("writing {}", path.display()))?;
    }
    Ok(())
}

fn create_parent(path: &Path) -> Result<()> {
    if let Some(p) = path.parent().filter(|p| !p.as_os_str().is_empty()) {
        std::fs::create_dir_all(p).with_context(|| format!("cannot create {}", p.display()))?;
    }
    Ok(())
}

/// A folder's last component (its whole path if it has none), for legends.
fn dir_label(dir: &Path) -> String {
    dir.file_name()
        .map_or_else(|| dir.display().to_string(), |n| n.to_string_lossy().into())
}

fn fmt_flicker(v: Option<f64>) -> String {
    v.map_or_else(|| "-".into(), |v| format!("{v:.4}"))
}

pub fn run(args: CompareArgs) -> Result<()> {
    let ppd = args.ppd.unwrap_or_else(flip::default_ppd);
    if !(ppd > 0.0 && ppd.is_finite()) {
        bail!("--ppd must be a positive number of pixels per degree");
    }
    if !(args.fps > 0.0 && args.fps <= 100.0) {
        bail!("--fps {} out of range (0 < fps ≤ 100)", args.fps);
    }
    let test = list_frames(&args.test_dir)?;
    let reference = list_frames(&args.ref_dir)?;
    if let Some(d) = &args.heatmaps {
        std::fs::create_dir_all(d).with_context(|| format!("cannot create {}", d.display()))?;
    }
    println!(
        "{:>6} {:>11} {:>10} {:>8} {:>9} {:>9} {:>8}",
        "frame", "relMSE", "RMSE", "PSNR dB", "FLIP-HDR", "FLIP-LDR", "flicker"
    );
    let mut previews = Vec::new();
    let results = compare_frames(&test, &reference, ppd, |m, t, r, map| {
        println!(
            "{:>6} {:>11.4e} {:>10.4e} {:>8.2} {:>9.4} {:>9.4} {:>8}",
            m.frame,
            m.relmse,
            m.rmse,
            m.psnr,
            m.flip_hdr,
            m.flip_ldr,
            fmt_flicker(m.flicker)
        );
        if let Some(d) = &args.heatmaps {
            let p = d.join(format!("flip_{:04}.png", m.frame));
            let img = Rgb8Image {
                width: t.width,
                height: t.height,
                pixels: map.magma_rgb8(),
            };
            write_png_rgb8(&p, &img).with_context(|| format!("writing {}", p.display()))?;
        }
        if args.preview.is_some() {
            previews.push(downscale(&side_by_side(t, r, map), PREVIEW_MAX_SIDE));
        }
        Ok(())
    })?;
    let s = summarize(&results);
    println!(
        "{:>6} {:>11.4e} {:>10.4e} {:>8.2} {:>9.4} {:>9.4} {:>8}",
        "mean",
        s.relmse,
        s.rmse,
        s.psnr,
        s.flip_hdr,
        s.flip_ldr,
        fmt_flicker(s.flicker)
    );
    println!(
        "summary: {} frame(s) [{}], relMSE {:.4e}, HDR-FLIP {:.4}, LDR-FLIP {:.4}, flicker {}",
        results.len(),
        ranges(results.iter().map(|m| m.frame)),
        s.relmse,
        s.flip_hdr,
        s.flip_ldr,
        fmt_flicker(s.flicker)
    );
    let versus = match &args.versus {
        Some(dir) => {
            let frames = list_frames(dir)?;
            let v = compare_frames(&frames, &reference, ppd, |_, _, _, _| Ok(()))?;
            let s = summarize(&v);
            println!(
                "versus {}: {} frame(s) [{}], relMSE {:.4e}, HDR-FLIP {:.4}, LDR-FLIP {:.4}, flicker {}",
                dir.display(),
                v.len(),
                ranges(v.iter().map(|m| m.frame)),
                s.relmse,
                s.flip_hdr,
                s.flip_ldr,
                fmt_flicker(s.flicker)
            );
            Some((dir, v))
        }
        None => None,
    };
    if let Some(p) = &args.csv {
        create_parent(p)?;
        std::fs::write(p, csv(&results)).with_context(|| format!("writing {}", p.display()))?;
    }
    if let Some(p) = &args.plot {
        create_parent(p)?;
        let svg = match &versus {
            None => svg_plot(
                &results,
                &format!("{} vs {}", args.test_dir.display(), args.ref_dir.display()),
            ),
            Some((dir, v)) => {
                let (a, b) = (dir_label(&args.test_dir), dir_label(dir));
                svg_plot_many(
                    &[(a.as_str(), &results), (b.as_str(), v)],
                    &format!("{a} (solid) and {b} (dashed) vs {}", args.ref_dir.display()),
                )
            }
        };
        std::fs::write(p, svg).with_context(|| format!("writing {}", p.display()))?;
    }
    if let Some(p) = &args.preview {
        create_parent(p)?;
        write_gif(p, &previews, args.fps)?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use chronolux_core::color::Rgb;
    use chronolux_io::image::write_exr;

    fn constant(w: u32, h: u32, v: f32) -> Image {
        Image::from_pixels(w, h, vec![Rgb::splat(v); (w * h) as usize])
    }

    fn tmp(name: &str) -> PathBuf {
        let d =
            std::env::temp_dir().join(format!("chronolux-compare-{}-{name}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(&d).unwrap();
        d
    }

    fn args(t: &Path, r: &Path) -> CompareArgs {
        CompareArgs {
            test_dir: t.into(),
            ref_dir: r.into(),
            csv: None,
            plot: None,
            versus: None,
            heatmaps: None,
            preview: None,
            fps: 24.0,
            ppd: None,
        }
    }

    fn err(a: CompareArgs) -> String {
        let e = run(a).unwrap_err();
        e.chain()
            .map(|c| c.to_string())
            .collect::<Vec<_>>()
            .join(": ")
    }

    /// Our FLIP means agree with flip-evaluator's to 1e-3 on the Mitsuba reference of the
    /// shared Cornell scene against deterministic noisy versions of it (EXRs both ways).
    #[test]
    fn flip_matches_flip_evaluator_on_mitsuba_reference() {
        use chronolux_core::testing::{flip_python, shared_file};
        let (Some(rp), Some(other), Some(py)) = (
            shared_file("peers/mitsuba-refs/mitsuba_f00.exr"),
            shared_file("peers/mitsuba-refs/mitsuba_f24.exr"),
            flip_python(),
        ) else {
            return;
        };
        let r = read_exr(&rp).unwrap();
        let other = read_exr(other).unwrap();
        let dir = tmp("flip-py");
        let mut state = 0x9e37_79b9_7f4a_7c15u64;
        let mut next = move || {
            state = chronolux_core::sampling::mix64(state.wrapping_add(0x9e37_79b9));
            (state >> 40) as f32 / (1u64 << 24) as f32
        };
        let mut cases = Vec::new();
        for amp in [0.05f32, 0.2, 0.6] {
            let px = r
                .pixels
                .iter()
                .map(|c| {
                    // Heavy-tailed multiplicative noise, like few-sample path tracing.
                    let u = Rgb::new(next(), next(), next());
                    (*c * (Rgb::ONE + (u * 2.0 - Rgb::ONE) * amp)
                        + Rgb::splat(amp * 0.05 * next().powi(8) * 4.0))
                    .max(Rgb::ZERO)
                })
                .collect();
            cases.push((
                format!("noise {amp}"),
                Image::from_pixels(r.width, r.height, px),
            ));
        }
        cases.push(("frame 24".into(), other));
        let ppd = flip::default_ppd();
        for (name, t) in &cases {
            let tp = dir.join("t.exr");
            write_exr(&tp, t).unwrap();
            let t = read_exr(&tp).unwrap();
            let (w, h) = (r.width as usize, r.height as usize);
            let ours_hdr = flip::flip_hdr(&r.pixels, &t.pixels, w, h, &Default::default()).mean();
            let ours_ldr = flip::flip_ldr(&r.pixels, &t.pixels, w, h, ppd).mean();
            let script = format!(
                "import numpy as np, flip_evaluator as fl\n\
                 r=np.ascontiguousarray(np.maximum(fl.load(r'{}'),0),dtype=np.float32)\n\
                 t=np.ascontiguousarray(np.maximum(fl.load(r'{}'),0),dtype=np.float32)\n\
                 h=fl.evaluate(r,t,'HDR',inputsRGB=False,applyMagma=False)[1]\n\
                 l=fl.evaluate(np.minimum(r,1),np.minimum(t,1),'LDR',inputsRGB=False,applyMagma=False)[1]\n\
                 print(repr(float(h)), repr(float(l)))\n",
                rp.display(),
                tp.display()
            );
            let out = std::process::Command::new(&py)
                .args(["-c", &script])
                .output()
                .unwrap();
            assert!(
                out.status.success(),
                "{}",
                String::from_utf8_lossy(&out.stderr)
            );
            let text = String::from_utf8_lossy(&out.stdout);
            let v: Vec<f64> = text
                .split_whitespace()
                .map(|s| s.parse().unwrap())
                .collect();
            eprintln!(
                "{name}: HDR-FLIP {ours_hdr:.6} vs {:.6}, LDR-FLIP {ours_ldr:.6} vs {:.6}",
                v[0], v[1]
            );
            assert!(
                (ours_hdr - v[0]).abs() < 1e-3,
                "{name}: HDR {ours_hdr} vs {}",
                v[0]
            );
            assert!(
                (ours_ldr - v[1]).abs() < 1e-3,
                "{name}: LDR {ours_ldr} vs {}",
                v[1]
            );
        }
    }

    #[test]
    fn mismatched_sizes_error_clearly() {
        let (t, r) = (tmp("size-t"), tmp("size-r"));
        write_exr(t.join("frame_0000.exr"), &constant(8, 8, 0.5)).unwrap();
        write_exr(r.join("frame_0000.exr"), &constant(8, 6, 0.5)).unwrap();
        let e = err(args(&t, &r));
        assert!(
            e.contains("frame 0") && e.contains("8x8") && e.contains("8x6"),
            "{e}"
        );
        assert!(!e.contains('\n'));
    }

    #[test]
    fn missing_frames_and_empty_folders_error_clearly() {
        let (t, r) = (tmp("miss-t"), tmp("miss-r"));
        write_exr(t.join("frame_0000.exr"), &constant(4, 4, 0.5)).unwrap();
        write_exr(t.join("frame_0001.exr"), &constant(4, 4, 0.5)).unwrap();
        write_exr(r.join("frame_0000.exr"), &constant(4, 4, 0.5)).unwrap();
        let e = err(args(&t, &r));
        assert!(e.contains("frame 1: no reference"), "{e}");
        let empty = tmp("empty");
        let e = err(args(&empty, &r));
        assert!(e.contains("no frames"), "{e}");
        let e = err(args(&t.join("nonexistent"), &r));
        assert!(e.contains("cannot read folder"), "{e}");
    }

    #[test]
    fn compare_writes_outputs_with_known_values() {
        let (t, r, o) = (tmp("ok-t"), tmp("ok-r"), tmp("ok-o"));
        // Reference static 0.5; test 0.6, 0.4, 0.6: relMSE 0.01/0.26 every frame,
        // flicker |∓0.2| / 0.5 = 0.4 for frames 1 and 2.
        for (f, v) in [(0u32, 0.6f32), (1, 0.4), (2, 0.6)] {
            write_exr(t.join(format!("frame_{f:04}.exr")), &constant(16, 16, v)).unwrap();
            write_exr(
                r.join(format!("mitsuba_f{f:02}.exr")),
                &constant(16, 16, 0.5),
            )
            .unwrap();
        }
        let mut a = args(&t, &r);
        a.csv = Some(o.join("m.csv"));
        a.plot = Some(o.join("m.svg"));
        a.heatmaps = Some(o.join("heat"));
        a.preview = Some(o.join("p.gif"));
        run(a).unwrap();
        let text = std::fs::read_to_string(o.join("m.csv")).unwrap();
        let rows: Vec<Vec<&str>> = text.lines().map(|l| l.split(',').collect()).collect();
        assert_eq!(rows[0][0], "frame");
        assert_eq!(rows.len(), 4);
        assert_eq!(rows[1][6], "", "no flicker for the first frame");
        let noref: f64 = rows[2][7].parse().unwrap();
        assert!((noref - 0.2).abs() < 1e-6, "{noref}");
        let rel: f64 = rows[2][1].parse().unwrap();
        assert!((rel - 0.01 / 0.26).abs() < 1e-6, "{rel}");
        let fl: f64 = rows[2][6].parse().unwrap();
        assert!((fl - 0.4).abs() < 1e-5, "{fl}");
        assert!(o.join("heat/flip_0002.png").exists());
        assert!(
            std::fs::read_to_string(o.join("m.svg"))
                .unwrap()
                .contains("<polyline")
        );
        assert!(std::fs::metadata(o.join("p.gif")).unwrap().len() > 100);
    }

    #[test]
    fn versus_is_measured_and_drawn_dashed_on_shared_axes() {
        let (t, v, r, o) = (tmp("vs-t"), tmp("vs-v"), tmp("vs-r"), tmp("vs-o"));
        // Test 0.55 everywhere (relMSE 0.0025/0.2601), versus 0.6 (0.01/0.26, four times
        // higher): the relMSE axis must reach the versus values, both polylines drawn.
        for f in 0..3u32 {
            write_exr(t.join(format!("frame_{f:04}.exr")), &constant(8, 8, 0.55)).unwrap();
            write_exr(v.join(format!("frame_{f:04}.exr")), &constant(8, 8, 0.6)).unwrap();
            write_exr(r.join(format!("frame_{f:04}.exr")), &constant(8, 8, 0.5)).unwrap();
        }
        let mut a = args(&t, &r);
        a.plot = Some(o.join("m.svg"));
        a.versus = Some(v.clone());
        run(a).unwrap();
        let svg = std::fs::read_to_string(o.join("m.svg")).unwrap();
        // 3 panels: solid and dashed series (2 FLIP + relMSE + flicker per sequence).
        assert_eq!(svg.matches("<polyline").count(), 8, "{svg}");
        assert_eq!(svg.matches("<polyline points").count(), 8);
        assert_eq!(
            svg.matches(r#"stroke-dasharray="7 4"/>"#).count(),
            8,
            "4 dashed polylines + 4 dashed legend lines"
        );
        assert!(svg.contains("relMSE chronolux-compare") && svg.contains("vs-v"));
        // The relMSE axis's top tick is 1.1 × the largest value, the versus 0.01 / 0.26.
        let top = 1.1 * 0.01 / 0.26;
        assert!(svg.contains(&format!(">{}<", fmt_tick(top))), "{top}");
    }
}
