//! Optional denoising with Intel Open Image Denoise (`--denoise`), behind the cargo
//! feature `oidn` (the default build stays free of it; README: "Denoising").
//!
//! The beauty is filtered by OIDN's `RT` filter in HDR mode with the first-hit albedo and
//! shading normal of the run's render passes ([`chronolux_render::aov`]) as auxiliary
//! images; the noisy beauty is kept as a layer of the EXR (`ViewLayer.Noisy Image`).

use chronolux_core::color::Rgb;
use chronolux_render::aov::Aovs;

/// Whether this build can denoise.
pub const AVAILABLE: bool = cfg!(feature = "oidn");

/// Why `--denoise` cannot be used in this build (`None`: it can).
pub fn unavailable() -> Option<&'static str> {
    (!AVAILABLE).then_some(
        "--denoise needs a build with Open Image Denoise: `cargo build --release --features oidn` with OIDN_DIR set to an OIDN install (README, \"Denoising\")",
    )
}

/// Open Image Denoise's filter quality (`--denoise-quality`): its networks by name.
#[derive(
    Clone,
    Copy,
    Debug,
    Default,
    PartialEq,
    Eq,
    clap::ValueEnum,
    serde::Serialize,
    serde::Deserialize,
)]
#[serde(rename_all = "kebab-case")]
pub enum DenoiseQuality {
    /// OIDN's default and best network.
    #[default]
    High,
    /// Meant for real-time use; the same network as `high` on a CPU device.
    Balanced,
    /// A smaller network: about half the filter's CPU, a higher error at equal samples.
    /// On the peers' scene, stbpt + OIDN reached HDR-FLIP 0.08 with 10 % less CPU with it
    /// on an AMD EPYC, where the filter takes 7.7 µs of CPU per pixel (BENCHMARKS.md,
    /// "Issue 17: the denoiser's cost").
    Fast,
}

fn flat3(v: impl Iterator<Item = [f32; 3]>) -> Vec<f32> {
    v.flatten().collect()
}

/// The beauty `pixels` denoised with the albedo and normal passes of `aovs`.
#[cfg(feature = "oidn")]
pub fn denoise(pixels: &[Rgb], aovs: &Aovs, quality: DenoiseQuality) -> Result<Vec<Rgb>, String> {
    let (w, h) = (aovs.width as usize, aovs.height as usize);
    if pixels.len() != w * h || aovs.albedo.len() != w * h || aovs.normal.len() != w * h {
        return Err("denoise: the beauty, albedo and normal differ in size".into());
    }
    let color = flat3(pixels.iter().map(|p| [p.x, p.y, p.z]));
    let albedo = flat3(aovs.albedo.iter().map(|p| [p.x, p.y, p.z]));
    let normal = flat3(aovs.normal.iter().map(|n| [n.x, n.y, n.z]));
    let mut out = vec![0.0f32; color.len()];
    // One device for the process: creating one per frame re-initialises OIDN every frame.
    // `Device` is `Send` but not `Sync`, so it lives behind a mutex (frames are denoised
    // one at a time anyway; OIDN threads inside the filter).
    static DEVICE: std::sync::Mutex<Option<oidn::Device>> = std::sync::Mutex::new(None);
    let mut slot = DEVICE.lock().unwrap_or_else(|e| e.into_inner());
    if slot.is_none() {
        *slot = Some(oidn::Device::new().map_err(|e| format!("Open Image Denoise: {e:?}"))?);
    }
    let device = slot.as_ref().expect("just set");
    let mut filter =
        oidn::RayTracing::try_new(device).map_err(|e| format!("Open Image Denoise: {e:?}"))?;
    filter
        .hdr(true)
        .filter_quality(match quality {
            DenoiseQuality::High => oidn::Quality::High,
            DenoiseQuality::Balanced => oidn::Quality::Balanced,
            DenoiseQuality::Fast => oidn::Quality::Fast,
        })
        .image_dimensions(w, h)
        .albedo_normal(&albedo, &normal);
    filter
        .filter(&color, &mut out)
        .map_err(|e| format!("Open Image Denoise: {e:?}"))?;
    Ok(out
        .chunks_exact(3)
        .map(|c| Rgb::new(c[0], c[1], c[2]))
        .collect())
}

/// Without the `oidn` feature there is no denoiser; [`unavailable`] stops `--denoise`
/// before any rendering, so this is never reached.
#[cfg(not(feature = "oidn"))]
pub fn denoise(pixels: &[Rgb], aovs: &Aovs, quality: DenoiseQuality) -> Result<Vec<Rgb>, String> {
    let _ = (pixels, aovs, quality, flat3(std::iter::empty()));
    Err(unavailable().unwrap_or_default().to_string())
}

/// The EXR channels of the passes (see `chronolux_render::aov` for the conventions):
/// Blender's multilayer names `ViewLayer.<pass>.<channel>`.
pub fn pass_channels(aovs: &Aovs) -> Vec<(String, Vec<f32>)> {
    let mut out = Vec::new();
    let mut push = |pass: &str, chans: &[&str], get: &dyn Fn(usize, usize) -> f32, n: usize| {
        for (c, name) in chans.iter().enumerate() {
            out.push((
                format!("ViewLayer.{pass}.{name}"),
                (0..n).map(|k| get(k, c)).collect(),
            ));
        }
    };
    let n = (aovs.width * aovs.height) as usize;
    if !aovs.albedo.is_empty() {
        push(
            "Denoising Albedo",
            &["R", "G", "B"],
            &|k, c| aovs.albedo[k][c],
            n,
        );
    }
    if !aovs.normal.is_empty() {
        push(
            "Denoising Normal",
            &["X", "Y", "Z"],
            &|k, c| aovs.normal[k][c],
            n,
        );
    }
    if !aovs.depth.is_empty() {
        push("Depth", &["Z"], &|k, _| aovs.depth[k], n);
    }
    if !aovs.motion_prev.is_empty() {
        push(
            "Vector",
            &["X", "Y", "Z", "W"],
            &|k, c| match c {
                0 => aovs.motion_prev[k].x,
                1 => aovs.motion_prev[k].y,
                2 => aovs.motion_next[k].x,
                _ => aovs.motion_next[k].y,
            },
            n,
        );
    }
    out
}

/// The EXR channels of a technique's light split (`ViewLayer.Direct.{R,G,B}`,
/// `ViewLayer.Indirect.{R,G,B}`; they add up to the beauty, see
/// [`chronolux_render::integrator::LightSplit`]).
pub fn light_channels(
    light: &chronolux_render::integrator::LightSplit,
    direct: bool,
    indirect: bool,
) -> Vec<(String, Vec<f32>)> {
    let mut out = Vec::new();
    for (keep, pass, img) in [
        (direct, "Direct", &light.direct),
        (indirect, "Indirect", &light.indirect),
    ] {
        if keep {
            for (c, name) in ["R", "G", "B"].iter().enumerate() {
                out.push((
                    format!("ViewLayer.{pass}.{name}"),
                    img.iter().map(|p| p[c]).collect(),
                ));
            }
        }
    }
    out
}
