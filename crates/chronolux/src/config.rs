//! The resolved configuration of a run: which technique with which settings, on which
//! scene, frames and image. `run.json` records it whole (its `settings`), and
//! `chronolux render --config run.json` replays it: the same configuration gives
//! bit-identical frames.
//!
//! Precedence, lowest first: the technique's defaults (its registry entry), the `--config`
//! file, the command line's flags (`--spp`, `--seed` and `--max-depth` set the technique's
//! [`registry::CommonSettings`] through [`Technique::with_common`]; `--window` and the
//! other technique-specific flags the settings key of the same name, found as
//! [`registry::find_key`] finds keys), then each `--set key=value` in order. A flag the
//! chosen technique has no setting for is an error, never silently ignored.

use anyhow::{Context, Result, bail};
use chronolux_render::kernels::elements::budget::PhotonCount;
use chronolux_render::registry::{self, Technique};
use serde::{Deserialize, Serialize};
use serde_json::Value;
use std::path::Path;

/// Everything that decides the pixels of a run (not the thread count, not the output).
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct RunConfig {
    /// Registry name of the technique (`--method`).
    pub method: String,
    /// Its complete settings.
    pub technique: Value,
    /// The scene argument: a .gltf/.glb path or `builtin:NAME`; `null` for the demo.
    pub scene: Option<String>,
    pub stage: Option<String>,
    /// Animation clip (name, or index when unnamed); `null` for none.
    pub animation: Option<String>,
    /// Camera by name; `null` for the first (or the automatic framing).
    pub camera: Option<String>,
    pub resolution: [u32; 2],
    pub fps: f32,
    pub frames: Vec<u32>,
    /// Fraction of the frame interval the shutter is open (0: no motion blur).
    pub shutter: f32,
    /// PNG/preview exposure in stops (the EXR is never altered); `null`: automatic, from the
    /// first frame (see `exposure.rs`; run.json records the value as `auto_exposure`).
    pub exposure: Option<f32>,
    /// PNG/preview view transform.
    #[serde(default)]
    pub view: chronolux_io::image::View,
    /// Render passes written as EXR layers.
    #[serde(default)]
    pub passes: chronolux_render::framework::aov::PassSet,
    /// Denoise with Open Image Denoise (on by default where the library can be had).
    #[serde(default)]
    pub denoise: bool,
    /// The denoiser's quality (when `denoise`).
    #[serde(default)]
    pub denoise_quality: crate::denoise::DenoiseQuality,
    /// The `--quality` level whose effort settings `technique` started from (`null`: the
    /// technique's own defaults; see `registry::quality_settings`).
    #[serde(default)]
    pub quality: Option<String>,
    /// The environment map that lights the scene (`--environment`); `null`: the scene's
    /// own lights (or its default sky).
    #[serde(default)]
    pub environment: Option<EnvironmentConfig>,
}

/// An environment map as run.json records it.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct EnvironmentConfig {
    /// The image (.exr or .hdr), as an absolute path where it could be resolved.
    pub file: String,
    /// Radiance multiplier.
    pub strength: f32,
    /// Rotation about +Y, degrees.
    pub rotation_deg: f32,
    /// Whether camera rays see black instead of the map.
    pub hidden: bool,
}

impl EnvironmentConfig {
    /// Reads the map: a clear error for a missing or malformed file, a bad strength or
    /// rotation.
    pub fn load(&self) -> Result<chronolux_core::light::Environment> {
        let image = chronolux_io::envmap::read_environment(&self.file)
            .with_context(|| "cannot use --environment".to_string())?;
        let map = chronolux_core::light::EnvMap::new(
            image.width as usize,
            image.height as usize,
            image.pixels,
            self.strength,
            self.rotation_deg,
        )
        .map_err(|e| anyhow::anyhow!("--environment {}: {e}", self.file))?;
        Ok(chronolux_core::light::Environment::from_map(
            map,
            !self.hidden,
        ))
    }
}

/// A `--config` file: a `run.json` (its `settings` are a [`RunConfig`]), a `RunConfig`
/// alone, or a settings object of the chosen technique (partial: missing keys default).
pub enum ConfigFile {
    Run(Box<PartialRun>),
    Settings(Value),
}

/// A [`RunConfig`] read from a file, every field optional (a hand-written file may give
/// only some).
#[derive(Clone, Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PartialRun {
    pub method: Option<String>,
    pub technique: Option<Value>,
    pub scene: Option<String>,
    pub stage: Option<String>,
    pub animation: Option<String>,
    pub camera: Option<String>,
    pub resolution: Option<[u32; 2]>,
    pub fps: Option<f32>,
    pub frames: Option<Vec<u32>>,
    pub shutter: Option<f32>,
    pub exposure: Option<f32>,
    pub passes: Option<chronolux_render::framework::aov::PassSet>,
    pub denoise: Option<bool>,
    pub denoise_quality: Option<crate::denoise::DenoiseQuality>,
    pub quality: Option<String>,
    pub view: Option<chronolux_io::image::View>,
    pub environment: Option<EnvironmentConfig>,
    /// Recorded in run.json (the automatic exposure found), not a setting: a replay
    /// measures it again, identically.
    #[serde(default, rename = "auto_exposure")]
    pub _auto_exposure: Option<Value>,
    /// Recorded in run.json but not part of the configuration (images do not depend on it).
    #[serde(default, rename = "threads")]
    pub _threads: Option<Value>,
    /// Recorded in run.json: the denoiser's library, or why a default run was not
    /// denoised. Not settings (the file's `denoise` says whether to denoise).
    #[serde(default, rename = "denoise_library")]
    pub _denoise_library: Option<Value>,
    #[serde(default, rename = "denoise_unavailable")]
    pub _denoise_unavailable: Option<Value>,
    /// Recorded in run.json: the ray-query backend (`embree` or `bvh`) and why not Embree.
    #[serde(default, rename = "ray_backend")]
    pub _ray_backend: Option<Value>,
    #[serde(default, rename = "ray_backend_note")]
    pub _ray_backend_note: Option<Value>,
    /// Recorded by `chronolux reference`; not a render setting.
    #[serde(default)]
    pub kind: Option<Value>,
}

impl ConfigFile {
    pub fn read(path: &Path) -> Result<ConfigFile> {
        let text = std::fs::read_to_string(path)
            .with_context(|| format!("cannot read --config {}", path.display()))?;
        let v: Value = serde_json::from_str(&text)
            .with_context(|| format!("--config {} is not valid JSON", path.display()))?;
        let run = match v.get("settings") {
            Some(s) if v.get("frames").is_some() => s.clone(), // a run.json
            _ => v,
        };
        if run.get("method").is_some() {
            let p: PartialRun = serde_json::from_value(run)
                .with_context(|| format!("--config {}: not a run configuration", path.display()))?;
            if p.kind.as_ref().and_then(Value::as_str) == Some("reference") {
                bail!(
                    "--config {}: the run.json of `chronolux reference`, not of a render",
                    path.display()
                );
            }
            Ok(ConfigFile::Run(Box::new(p)))
        } else if run.is_object() {
            Ok(ConfigFile::Settings(run))
        } else {
            bail!("--config {}: expected a JSON object", path.display())
        }
    }

    /// The method the file names, if any.
    pub fn method(&self) -> Option<&str> {
        match self {
            ConfigFile::Run(p) => p.method.as_deref(),
            ConfigFile::Settings(_) => None,
        }
    }

    /// The run part of the file (empty for a settings-only file).
    pub fn run(&self) -> PartialRun {
        match self {
            ConfigFile::Run(p) => (**p).clone(),
            ConfigFile::Settings(_) => PartialRun::default(),
        }
    }
}

/// `--spp`, `--seed` and `--max-depth`: the technique's common settings block
/// ([`registry::CommonSettings`]), which every technique has; `None`: not given.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct CommonFlags {
    pub spp: Option<u32>,
    pub seed: Option<u64>,
    pub max_depth: Option<u32>,
}

/// A command-line flag that names a technique setting.
pub struct FlagSetting {
    /// The flag as the user typed it (`--window`).
    pub flag: &'static str,
    /// The settings key it sets.
    pub key: &'static str,
    pub value: Value,
}

/// Parses `--set key=value` arguments.
pub fn parse_sets(sets: &[String]) -> Result<Vec<(String, Value)>> {
    sets.iter()
        .map(|s| {
            let (k, v) = s.split_once('=').with_context(|| {
                format!("--set '{s}': expected key=value (e.g. --set window=6)")
            })?;
            let k = k.trim();
            if k.is_empty() {
                bail!("--set '{s}': empty key");
            }
            Ok((k.to_string(), registry::parse_value(v.trim())))
        })
        .collect()
}

/// The settings of `tech` from `base` (a config file's settings of the same technique),
/// then the flags, then `--photons`, then the `--set`s. A flag the technique has no
/// setting for is an error.
pub fn technique_settings(
    tech: &dyn Technique,
    base: Option<&Value>,
    common: CommonFlags,
    flags: &[FlagSetting],
    photons: Option<&str>,
    sets: &[(String, Value)],
) -> Result<Value> {
    let mut s = registry::resolve(tech, base, &[]).map_err(anyhow::Error::msg)?;
    if common != CommonFlags::default() {
        let mut c = tech.common(&s).map_err(anyhow::Error::msg)?;
        c.spp = common.spp.unwrap_or(c.spp);
        c.seed = common.seed.unwrap_or(c.seed);
        c.max_depth = common.max_depth.or(c.max_depth);
        // The technique refuses what it cannot do (a depth limit where it has none:
        // `Capabilities::max_depth`); the error names the flags that asked for it.
        let given = [
            ("--spp", common.spp.map(u64::from)),
            ("--seed", common.seed),
            ("--max-depth", common.max_depth.map(u64::from)),
        ]
        .into_iter()
        .filter_map(|(f, v)| v.map(|v| format!("{f} {v}")))
        .collect::<Vec<_>>()
        .join(" ");
        s = tech
            .with_common(&s, c)
            .map_err(|e| anyhow::anyhow!("{given}: {e}"))?;
    }
    for f in flags {
        if registry::find_key(&s, f.key).is_none() {
            bail!(
                "{} does not apply to --method {} (its settings: {})",
                f.flag,
                tech.name(),
                registry::keys(&s).join(", ")
            );
        }
        registry::set_key(&mut s, f.key, f.value.clone()).map_err(anyhow::Error::msg)?;
    }
    if let Some(p) = photons {
        if !tech.capabilities().photons {
            bail!(
                "--photons applies to the photon methods ({}) only, not {}",
                registry::names_where(|c| c.photons).join(", "),
                tech.name()
            );
        }
        let count: PhotonCount = p.parse().map_err(anyhow::Error::msg)?;
        registry::set_photons(&mut s, &count).map_err(anyhow::Error::msg)?;
    }
    registry::resolve(tech, Some(&s), sets).map_err(anyhow::Error::msg)
}
