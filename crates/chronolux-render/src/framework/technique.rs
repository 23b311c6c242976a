//! The technique contract: what every technique is to the driver.
//!
//! A technique is a [`Preset`] (name, one-line summary, its settings type with their
//! defaults, its [`Capabilities`], its measured [`QualityLevel`] table and how it is
//! built) seen through the object-safe [`Technique`] trait. As in pbrt-v4, where each
//! integrator parses its own parameters, the driver knows no names: settings travel as
//! JSON and are checked by the technique's own serde type ([`resolve`]), so an unknown
//! key or a bad value is an error that names the valid keys. Settings shared by every
//! technique ([`CommonSettings`]: samples, depth, seed) are one block flattened into each.
//! The list of techniques is not here but at the top of the crate, in
//! [`crate::registry`], so that this contract imports no technique.

use crate::framework::sequence::SequenceRenderer;
use serde::Serialize;
use serde::de::DeserializeOwned;
use serde_json::{Map, Value};

/// A built technique, ready to render a sequence.
pub type Renderer = Box<dyn SequenceRenderer + Send>;

/// What the effort of a technique is, for `bench quality`, which doubles it.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub struct Effort {
    /// The settings key set to `effort × per_unit` (found as [`set_key`] finds keys).
    pub key: &'static str,
    /// Units of `key` per effort level (1 sample per pixel; 1000 photons).
    pub per_unit: u64,
    /// What one effort unit is, for reports.
    pub unit: &'static str,
}

/// What a technique can do, for the command line's checks.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub struct Capabilities {
    /// `--shutter` (motion blur) is supported.
    pub motion_blur: bool,
    /// It shoots photons (`--photons N|auto` applies).
    pub photons: bool,
    /// It reuses work over a window of neighbouring frames (`--window K`).
    pub window: bool,
    /// It honours [`CommonSettings::max_depth`] (`--max-depth`); the others refuse a
    /// depth rather than ignore it.
    pub max_depth: bool,
    /// Its frames depend only on (seed, frame, pixel, sample index), not on other frames
    /// rendered before them (frame-by-frame baselines).
    pub stateless: bool,
    /// The knob `bench quality` doubles.
    pub effort: Effort,
}

/// The settings every technique has, flattened into its own settings type
/// (`#[serde(flatten)] pub common: CommonSettings`, so the keys stay `spp`, `max_depth`
/// and `seed` at the top of its settings object; a technique that embeds another's
/// settings, as `stbpt` embeds `bdpt`'s, has them there). The command line's `--spp`,
/// `--max-depth` and `--seed` reach them through [`Technique::common`] and
/// [`Technique::with_common`], by type, not by searching key names. Each technique's
/// defaults (its own `Default`) choose the values; the meaning of `spp` per technique is
/// in the docs of its settings field.
///
/// Worker threads are not here: a technique's images do not depend on them (the
/// determinism tests across thread counts prove it), so they belong to the run (`render
/// --threads`), and settings that differ only in threads name the same images (as `render
/// --resume` and a farm plan compare them).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, serde::Deserialize)]
pub struct CommonSettings {
    /// Camera samples per pixel (at least 1).
    pub spp: u32,
    /// Longest light path in segments from the camera, Mitsuba's `max_depth` convention:
    /// 1 = emitters seen directly, 2 = direct lighting; `None`: unlimited (Russian
    /// roulette ends paths). Only for the techniques whose [`Capabilities::max_depth`]
    /// says so; the others refuse a value.
    pub max_depth: Option<u32>,
    /// Seed of every sample stream: the same seed gives bit-identical images.
    pub seed: u64,
}

/// Everything a technique is built from besides its own settings: what belongs to the
/// run (the camera's shutter), not to the light transport.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct BuildContext {
    /// Fraction of the frame interval the shutter is open (0 = no motion blur).
    pub shutter: f32,
}

/// One level of `render --quality`: every effort setting of one technique, measured to
/// reach an error on the shared Cornell scene as fast as the measurements found
/// (BENCHMARKS.md, "The quality table": the time to FLIP of each candidate, and which
/// won). The levels are measured for denoised renders (the default route); `undenoised`
/// gives the settings for a render with `--no-denoise` where those were measured too.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct QualityLevel {
    /// One of [`QUALITIES`].
    pub name: &'static str,
    /// The mean HDR-FLIP it reached (cornell-moving at [`Self::pixels`], whole animation,
    /// 12 scored frames against Mitsuba's converged references of that size, denoised).
    pub flip: f32,
    /// `(key, JSON value)` set on the technique's defaults when denoising (keys as
    /// [`set_key`] finds them: `spp` reaches `bdpt.spp` in stbpt's settings).
    pub denoised: &'static [(&'static str, &'static str)],
    /// The same for an undenoised render; `None`: not measured, and then an explicit
    /// `--quality` with `--no-denoise` is an error and the default quality leaves the
    /// technique's own defaults (which its own benchmarks tuned, undenoised).
    pub undenoised: Option<&'static [(&'static str, &'static str)]>,
    /// Open Image Denoise's network at this level (`high` or `fast`).
    pub denoiser: &'static str,
    /// The image's pixel count it was measured at. A table may hold a level more than
    /// once, measured at different resolutions: the cost of a camera sample grows with
    /// the pixels while a photon pass does not, and the denoiser does more of the work
    /// at a higher resolution, so the fastest settings to an error move with it
    /// (BENCHMARKS.md, "The quality table": `spacetime-dept`'s preview takes 128k photons
    /// at 256², 64k at 512²; `path`'s 8 and 4 spp). A render takes the entry measured
    /// nearest its own pixel count (by ratio).
    pub pixels: u32,
}

impl QualityLevel {
    /// A level measured denoised only (OIDN's `high` network; undenoised not measured).
    pub const fn denoised(
        name: &'static str,
        flip: f32,
        denoised: &'static [(&'static str, &'static str)],
    ) -> Self {
        Self {
            name,
            flip,
            denoised,
            undenoised: None,
            denoiser: "high",
            pixels: MEASURED_PIXELS,
        }
    }

    /// The same level with Open Image Denoise's `fast` network (measured so: on 2 AVX2
    /// cores `high` is a large share of a 512² frame's cost, BENCHMARKS.md).
    pub const fn fast(self) -> Self {
        Self {
            denoiser: "fast",
            ..self
        }
    }

    /// The same level measured at `width × height` instead of the shared 256².
    pub const fn at(self, width: u32, height: u32) -> Self {
        Self {
            pixels: width * height,
            ..self
        }
    }

    /// How far `pixels` is from the resolution this entry was measured at (the log of
    /// the ratio, 0 when equal).
    pub fn distance(&self, pixels: u64) -> f64 {
        (pixels.max(1) as f64 / f64::from(self.pixels.max(1)))
            .ln()
            .abs()
    }

    /// The entry of level `name` in `table` measured nearest `pixels` (the first of equals).
    pub fn nearest<'a>(table: &'a [Self], name: &str, pixels: u64) -> Option<&'a Self> {
        table
            .iter()
            .filter(|l| l.name == name)
            .min_by(|a, b| a.distance(pixels).total_cmp(&b.distance(pixels)))
    }
}

/// The resolution quality levels are measured at unless they say otherwise (256²: the
/// peers' references of cornell-moving).
pub const MEASURED_PIXELS: u32 = 256 * 256;

/// The quality levels, lowest first, as `--quality` names them.
pub const QUALITIES: [&str; 3] = ["draft", "preview", "final"];

/// The quality `render` uses when none is given: the one that reaches about HDR-FLIP
/// 0.08 on the shared Cornell scenes (what the peers are compared at).
pub const DEFAULT_QUALITY: &str = "preview";

/// A technique as the registry sees it (object-safe; implemented by [`Preset`]).
pub trait Technique: Sync {
    fn name(&self) -> &'static str;
    fn summary(&self) -> &'static str;
    fn capabilities(&self) -> Capabilities;
    /// Its measured quality levels (none: `--quality` does not apply; its defaults are
    /// its only effort).
    fn quality(&self) -> &'static [QualityLevel];
    /// The default settings, every field present.
    fn defaults(&self) -> Value;
    /// Checks `settings` against the settings type and returns them completed and
    /// normalised (every field present, in the type's own form).
    fn check(&self, settings: &Value) -> Result<Value, String>;
    /// The common block of `settings` (as [`Technique::check`] accepts).
    fn common(&self, settings: &Value) -> Result<CommonSettings, String>;
    /// `settings` with their common block replaced by `common`, checked.
    fn with_common(&self, settings: &Value, common: CommonSettings) -> Result<Value, String>;
    /// Builds the technique from settings (as [`Technique::check`] accepts).
    fn build(&self, settings: &Value, ctx: &BuildContext) -> Result<Renderer, String>;
}

/// A registry entry: a settings type `S` with named defaults and a constructor.
pub struct Preset<S> {
    pub name: &'static str,
    pub summary: &'static str,
    pub capabilities: Capabilities,
    /// Its `--quality` table (empty where none was measured).
    pub quality: &'static [QualityLevel],
    pub defaults: fn() -> S,
    /// Where its [`CommonSettings`] are (`|s| &mut s.common`; `|s| &mut s.bdpt.common`
    /// for a technique that embeds another's settings).
    pub common: fn(&mut S) -> &mut CommonSettings,
    /// Builds the technique; the name is the preset's (for reports). An error: settings
    /// that pass the settings type but cannot be built (e.g. an unwritable store folder),
    /// said before any frame renders.
    pub build: fn(S, &BuildContext, &'static str) -> Result<Renderer, String>,
}

impl<S> Preset<S>
where
    S: Serialize + DeserializeOwned,
{
    fn parse(&self, settings: &Value) -> Result<S, String> {
        // Completed from the defaults first, so a partial object (a `--config` file that
        // sets two keys) means "these two, the rest as default".
        let mut full = full_defaults(self);
        merge(&mut full, settings);
        refuse_empty_renders(&full, "")
            .map_err(|e| format!("settings of --method {}: {e}", self.name))?;
        let mut s: S = serde_json::from_value(full).map_err(|e| {
            format!(
                "settings of --method {}: {e} (valid keys: {})",
                self.name,
                keys(&full_defaults(self)).join(", ")
            )
        })?;
        if let Some(d) = (self.common)(&mut s).max_depth
            && !self.capabilities.max_depth
        {
            return Err(format!(
                "settings of --method {}: max_depth = {d}: {LACKS_MAX_DEPTH}",
                self.name
            ));
        }
        Ok(s)
    }
}

impl<S> Technique for Preset<S>
where
    S: Serialize + DeserializeOwned + Sync,
{
    fn name(&self) -> &'static str {
        self.name
    }
    fn summary(&self) -> &'static str {
        self.summary
    }
    fn capabilities(&self) -> Capabilities {
        self.capabilities
    }
    fn quality(&self) -> &'static [QualityLevel] {
        self.quality
    }
    fn defaults(&self) -> Value {
        serde_json::to_value((self.defaults)()).expect("settings serialise")
    }
    fn check(&self, settings: &Value) -> Result<Value, String> {
        let s = self.parse(settings)?;
        Ok(serde_json::to_value(s).expect("settings serialise"))
    }
    fn common(&self, settings: &Value) -> Result<CommonSettings, String> {
        let mut s = self.parse(settings)?;
        Ok(*(self.common)(&mut s))
    }
    fn with_common(&self, settings: &Value, common: CommonSettings) -> Result<Value, String> {
        let mut s = self.parse(settings)?;
        *(self.common)(&mut s) = common;
        self.check(&serde_json::to_value(s).expect("settings serialise"))
    }
    fn build(&self, settings: &Value, ctx: &BuildContext) -> Result<Renderer, String> {
        if ctx.shutter != 0.0 && !self.capabilities.motion_blur {
            return Err(format!("--shutter {LACKS_SHUTTER} {}", self.name));
        }
        check_shutter(ctx.shutter)?;
        (self.build)(self.parse(settings)?, ctx, self.name)
            .map_err(|e| format!("--method {}: {e}", self.name))
    }
}

/// Refuses the values that would render nothing at all, at any depth of a settings
/// object (`--set` and `--config` reach them past the CLI's own range checks): camera
/// samples `spp` = 0 (a black image) and `max_depth` = 0 (no path segment). `at`: the
/// dotted path of `v`.
fn refuse_empty_renders(v: &Value, at: &str) -> Result<(), String> {
    let Value::Object(m) = v else {
        return Ok(());
    };
    for (k, x) in m {
        let key = if at.is_empty() {
            k.clone()
        } else {
            format!("{at}.{k}")
        };
        match (k.as_str(), x.as_u64()) {
            ("spp", Some(0)) => {
                return Err(format!(
                    "{key} = 0 renders a black image (at least 1 sample per pixel)"
                ));
            }
            ("max_depth", Some(0)) => {
                return Err(format!(
                    "{key} = 0 renders nothing (1 shows emitters only, 2 adds direct lighting)"
                ));
            }
            _ => refuse_empty_renders(x, &key)?,
        }
    }
    Ok(())
}

fn full_defaults<S: Serialize>(p: &Preset<S>) -> Value {
    serde_json::to_value((p.defaults)()).expect("settings serialise")
}

/// Which neighbouring frames a technique needs around the frames it outputs (what a
/// farm segment must compute besides its own frames).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, serde::Deserialize)]
pub struct FrameContext {
    /// Frames before / after an output frame whose scenes (and, for windowed
    /// techniques, samples) it uses.
    pub before: u32,
    pub after: u32,
    /// The frames before must be *rendered*, in order (a stateful technique's history),
    /// not only be present in the frame list.
    pub render_before: bool,
    /// With this context an output frame is bit-identical to the same frame of a single
    /// run over the whole range (its samples depend only on seed, frame, pixel and index);
    /// otherwise a segment's first frames start from a shorter history and the seam is
    /// measured instead.
    pub exact: bool,
}

/// Warm-up frames a stateful technique without a window gets at a segment's start.
pub const STATEFUL_WARM_UP: u32 = 8;

/// The [`FrameContext`] of `technique` with `settings`, from its capabilities: frame by
/// frame needs nothing; a windowed technique needs its `window` (K) frames on each side
/// (the frames enter the frame list and are traced as its window requires, exactly as in
/// a single run); any other stateful technique gets [`STATEFUL_WARM_UP`] rendered frames
/// of history, and is not exact.
pub fn frame_context(technique: &dyn Technique, settings: &Value) -> FrameContext {
    let c = technique.capabilities();
    if c.stateless {
        return FrameContext {
            before: 0,
            after: 0,
            render_before: false,
            exact: true,
        };
    }
    let window = get_key(settings, "window").and_then(Value::as_u64);
    match (c.window, window) {
        (true, Some(k)) => FrameContext {
            before: k as u32,
            after: k as u32,
            render_before: false,
            exact: true,
        },
        _ => FrameContext {
            before: STATEFUL_WARM_UP,
            after: 0,
            render_before: true,
            exact: false,
        },
    }
}

/// Merges `over` into `base` (objects key by key, recursively; anything else replaces).
pub fn merge(base: &mut Value, over: &Value) {
    match (base, over) {
        (Value::Object(b), Value::Object(o)) => {
            for (k, v) in o {
                match b.get_mut(k) {
                    Some(slot) if slot.is_object() && v.is_object() => merge(slot, v),
                    _ => {
                        b.insert(k.clone(), v.clone());
                    }
                }
            }
        }
        (b, o) => *b = o.clone(),
    }
}

/// Every settable leaf of a settings object, nested ones as `outer.inner` (what error
/// messages list as the valid keys).
pub fn keys(settings: &Value) -> Vec<String> {
    paths(settings, false)
}

/// Every path of a settings object: leaves and, with `objects`, the objects too (an
/// embedded baseline's settings, a tagged enum such as `filter`, can be set whole).
fn paths(settings: &Value, objects: bool) -> Vec<String> {
    fn walk(v: &Value, prefix: &str, objects: bool, out: &mut Vec<String>) {
        if let Value::Object(m) = v {
            for (k, v) in m {
                let key = if prefix.is_empty() {
                    k.clone()
                } else {
                    format!("{prefix}.{k}")
                };
                if v.is_object() {
                    if objects {
                        out.push(key.clone());
                    }
                    walk(v, &key, objects, out);
                } else {
                    out.push(key);
                }
            }
        }
    }
    let mut out = Vec::new();
    walk(settings, "", objects, &mut out);
    out
}

/// The full path of `key` in `settings`: itself when it is a path there, else the one
/// nested path whose last component is `key` (so `spp` finds `bdpt.spp` in stbpt's
/// settings, which embed bdpt's). `None` when absent or ambiguous.
pub fn find_key(settings: &Value, key: &str) -> Option<String> {
    let all = paths(settings, true);
    if all.iter().any(|k| k == key) {
        return Some(key.to_string());
    }
    let suffix = format!(".{key}");
    let mut hits = all.into_iter().filter(|k| k.ends_with(&suffix));
    let first = hits.next()?;
    hits.next().is_none().then_some(first)
}

/// The value of `key` in `settings`, found as [`find_key`] finds it.
pub fn get_key<'a>(settings: &'a Value, key: &str) -> Option<&'a Value> {
    find_key(settings, key)?
        .split('.')
        .try_fold(settings, |v, p| v.get(p))
}

/// Parses the value of `--set key=value`: JSON when it is JSON (numbers, `true`, `null`,
/// `{"Gaussian": {"radius": 3}}`), else the text as a string (`--set mis=balance`).
pub fn parse_value(text: &str) -> Value {
    serde_json::from_str(text).unwrap_or_else(|_| Value::String(text.to_string()))
}

/// Sets `key` (a path of [`keys`], or a unique last component, see [`find_key`]) in
/// `settings` to `value`. Errors name the valid keys.
pub fn set_key(settings: &mut Value, key: &str, value: Value) -> Result<(), String> {
    let path = find_key(settings, key).ok_or_else(|| {
        format!(
            "unknown setting '{key}' (valid keys: {})",
            keys(settings).join(", ")
        )
    })?;
    let mut v = settings;
    let parts: Vec<&str> = path.split('.').collect();
    for p in &parts[..parts.len() - 1] {
        v = v.get_mut(*p).expect("path from keys()");
    }
    let m: &mut Map<String, Value> = v.as_object_mut().expect("object");
    m.insert(parts[parts.len() - 1].to_string(), value);
    Ok(())
}

/// The refusal of a depth limit by a technique without one ([`Capabilities::max_depth`]).
/// The framework cannot name the techniques that have one (it sits below their list); the
/// registry's list hands out each technique wrapped so that it adds them to any error
/// carrying this text.
pub const LACKS_MAX_DEPTH: &str = "a path depth is not implemented for it";
/// The refusal of a shutter by a technique without motion blur
/// ([`Capabilities::motion_blur`]); as [`LACKS_MAX_DEPTH`], completed by the registry.
pub const LACKS_SHUTTER: &str = "(motion blur) is not implemented for --method";

/// The settings of `technique` from its defaults, then `config` (a partial settings
/// object, e.g. from `--config`), then each `(key, value)` of `sets` in order; checked and
/// completed by the technique. An unknown key or a bad value is an error naming the key.
pub fn resolve(
    technique: &dyn Technique,
    config: Option<&Value>,
    sets: &[(String, Value)],
) -> Result<Value, String> {
    let mut s = technique.defaults();
    if let Some(c) = config {
        if !c.is_object() {
            return Err(format!(
                "the settings of --method {} must be a JSON object",
                technique.name()
            ));
        }
        // Unknown keys are refused by the settings type (serde, deny_unknown_fields).
        merge(&mut s, c);
    }
    for (k, v) in sets {
        set_key(&mut s, k, v.clone())
            .map_err(|e| format!("--set {k}: {e} (method {})", technique.name()))?;
        technique
            .check(&s)
            .map_err(|e| format!("--set {k}={v}: {e}"))?;
    }
    technique.check(&s)
}

/// Checks a shutter fraction: in [0, 1].
pub fn check_shutter(shutter: f32) -> Result<(), String> {
    if (0.0..=1.0).contains(&shutter) {
        Ok(())
    } else {
        Err(format!(
            "--shutter {shutter} out of range: the shutter is open for a fraction of the frame interval in [0, 1] (0 = no motion blur)"
        ))
    }
}
