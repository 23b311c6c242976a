//! Flag groups shared by several subcommands (clap): the scene ([`SceneArgs`], every
//! command that loads one) and a render's configuration ([`RenderArgs`]: `render`,
//! `plan`, `farm`), with the long help drawn from the registry. Every flag documents its
//! unit and default. The command tree itself is [`crate::cli`], above every command.

use chronolux_render::registry;
use clap::Args;
use std::path::PathBuf;

/// Which scene and how to present it; shared by every subcommand that loads a scene.
#[derive(Args, Debug, Clone)]
pub struct SceneArgs {
    /// glTF 2.0 scene (.gltf or .glb). Omit to use the built-in demo (an animated Cornell
    /// box: a sliding, turning block, a metal sphere and a glass sphere; 2 s).
    /// `builtin:demo`, `builtin:caustic` (a glass sphere's caustic, and an occluder that
    /// enters abruptly between frames 3 and 4), `builtin:dolly` (the demo filmed by a
    /// camera that trucks, dollies in and turns), `builtin:flythrough` (the dolly's camera
    /// path through the demo's room with nothing else moving) and `builtin:banner` (a skinned banner
    /// whose lower half swings while its upper half stays still) name the built-in scenes.
    pub scene: Option<PathBuf>,
    /// Animation clip to play, by name or index (default: the first clip).
    #[arg(long, value_name = "NAME|INDEX")]
    pub animation: Option<String>,
    /// Camera to render through, by camera name, camera node name or camera index
    /// (unnamed cameras are called cameraN; `chronolux info` lists them). Default: the
    /// scene's first camera; a scene without cameras is framed automatically.
    #[arg(long, value_name = "NAME|INDEX")]
    pub camera: Option<String>,
    /// Put the scene's content, scaled to fit, into a built-in stage. `cornell`: a Cornell
    /// room lit by its ceiling light, so any animated model becomes a GI test.
    #[arg(long, value_name = "STAGE", value_parser = ["cornell"])]
    pub stage: Option<String>,
}

#[derive(Args, Debug)]
pub struct RenderArgs {
    #[command(flatten)]
    pub scene: SceneArgs,
    /// Frames to render: `A..B` (half-open, as in Rust), `A..=B` (inclusive) or `N`.
    /// Frame f is shown at time f/fps. Default: every frame of the clip, 0 through the
    /// frame of its last key (a scene without animation: frame 0).
    #[arg(long, value_name = "RANGE", allow_hyphen_values = true)]
    pub frames: Option<String>,
    /// Frames per second of the animation timeline (above 0, at most 1000).
    /// Default 24 (or the `--config` file's).
    #[arg(long, value_name = "FPS", allow_negative_numbers = true)]
    pub fps: Option<f32>,
    /// Samples per pixel (1 to 1048576): the technique's `spp` setting. Default: the
    /// technique's, at the chosen --quality (`--help` lists them).
    #[arg(long, value_name = "N", long_help = spp_help())]
    pub spp: Option<u32>,
    /// Image size in pixels, WIDTHxHEIGHT (each 1 to 16384). Default: 512 wide, height
    /// from the camera's aspect ratio (square when the camera gives none); 256x256 for the
    /// built-in demo.
    #[arg(long, value_name = "WxH", allow_hyphen_values = true)]
    pub resolution: Option<String>,
    /// Longest light path in segments from the camera, as Mitsuba's max_depth: 1 shows
    /// emitters only, 2 adds direct lighting. Default: unlimited (Russian roulette ends paths).
    #[arg(long, value_name = "N", long_help = max_depth_help())]
    pub max_depth: Option<u32>,
    /// Light-transport method (default `spacetime-dept`). Every technique's settings can be
    /// set with --set; an unknown key (e.g. `--set list=1`) lists the valid ones.
    #[arg(long, value_name = "METHOD", long_help = method_help(),
          value_parser = clap::builder::PossibleValuesParser::new(chronolux_render::registry::names()))]
    pub method: Option<String>,
    /// Set any setting of the chosen technique, `KEY=VALUE` (repeatable), e.g.
    /// `--set window=6 --set film_budget_mb=256`. Nested keys as `bdpt.mis=balance`, or by
    /// their last part when unique (`spp` is stbpt's `bdpt.spp`). VALUE is JSON when it
    /// parses as JSON, else text. An unknown key lists the valid ones. Applied after every
    /// other flag, in order.
    #[arg(long = "set", value_name = "KEY=VALUE")]
    pub set: Vec<String>,
    /// Read the configuration from a JSON file: a `run.json` of an earlier render (its
    /// settings are replayed: the same frames, bit for bit), or an object of the
    /// technique's settings. Flags given on the command line override the file.
    #[arg(long, value_name = "FILE.json")]
    pub config: Option<PathBuf>,
    /// Motion blur: fraction of the frame interval the shutter is open, in [0, 1], centred
    /// on the frame time (Blender's default); 0 = no motion blur. `path` and `bdpt`: each
    /// pixel sample gets a time in the shutter, the scene is built at min(spp, 16) instants.
    /// `stbpt`: each sample's trajectory across the shutter (its point in the neighbouring
    /// frames) is splatted over the pixels it crosses.
    /// Default 0.
    #[arg(long, value_name = "S", allow_negative_numbers = true, long_help = shutter_help())]
    pub shutter: Option<f32>,
    /// The technique's `window` setting (0 to 31): how many frames on each side of a frame
    /// share its work (`--help` lists the methods and their defaults).
    #[arg(long, value_name = "K", value_parser = clap::value_parser!(u32).range(0..=31),
          long_help = window_help())]
    pub window: Option<u32>,
    /// Photons of the photon methods: a count (e.g. 250000), or `auto` for the stopping
    /// rule where the method has one (`--help` lists the methods and their defaults).
    #[arg(long, value_name = "N|auto", long_help = photons_help())]
    pub photons: Option<String>,
    /// Seed of every random sequence; the same seed gives bit-identical images. Default 0.
    #[arg(long, value_name = "S")]
    pub seed: Option<u64>,
    /// Worker threads (default: all cores). Images do not depend on it.
    #[arg(long, value_name = "N")]
    pub threads: Option<usize>,
    /// Output folder; frames are written as frame_NNNN.exr (linear) and frame_NNNN.png
    /// (sRGB), with run.json and preview.gif (and preview.mp4 when ffmpeg is installed).
    #[arg(long, short, default_value = "out", value_name = "DIR")]
    pub output: PathBuf,
    /// Exposure of the PNG and preview in stops (the EXR is never altered). Default:
    /// automatic, measured once on the first frame (its 90th luminance percentile) and
    /// kept for the whole sequence; run.json records it as `auto_exposure`.
    #[arg(long, value_name = "EV", allow_negative_numbers = true)]
    pub exposure: Option<f32>,
    /// View transform of the PNG and preview: `agx` (default; soft highlight roll-off, as
    /// Blender's default) or `standard` (clamp and sRGB curve). The EXR is never altered.
    #[arg(long, value_name = "agx|standard", value_parser = parse_view)]
    pub view: Option<chronolux_io::image::View>,
    /// Skip frames whose EXR and PNG are already complete (and recorded in run.json) in the
    /// output folder; settings must match the earlier run's. A technique that carries light
    /// from frame to frame without a window (ic-static-dynamic, ic-selective, spt) renders
    /// the complete frames before the last missing one again, the same bits, for its history.
    #[arg(long)]
    pub resume: bool,
    /// Do not write the animated preview.
    #[arg(long)]
    pub no_preview: bool,
    /// Light the scene with an environment map: an equirectangular (latitude-longitude)
    /// image of linear radiance, OpenEXR (.exr) or Radiance HDR (.hdr). Its top row is
    /// straight up (+Y), its centre column looks along +X and the column a quarter across
    /// along -Z (as Blender's Environment Texture in a scene exported to glTF). It replaces
    /// the default sky of a scene without lights and adds to a scene's own lights; camera
    /// rays see it (unless --environment-hidden). Importance-sampled by its luminance.
    #[arg(long, value_name = "FILE.exr|FILE.hdr")]
    pub environment: Option<PathBuf>,
    /// Multiplier of the environment map's radiance (Blender's Background strength),
    /// finite and ≥ 0. Default 1.
    #[arg(
        long,
        value_name = "S",
        allow_negative_numbers = true,
        requires = "environment"
    )]
    pub environment_strength: Option<f32>,
    /// Rotation of the environment map about the up axis (+Y) in degrees: the map is looked
    /// up at each direction turned by this angle, as Blender's Mapping node (type Point)
    /// rotating about Z. Default 0.
    #[arg(
        long,
        value_name = "DEG",
        allow_negative_numbers = true,
        requires = "environment"
    )]
    pub environment_rotation: Option<f32>,
    /// Camera rays that leave the scene see black instead of the environment map (it still
    /// lights the scene and shows in reflections and refractions).
    #[arg(long, requires = "environment")]
    pub environment_hidden: bool,
    /// Render passes written as layers of each frame's EXR (Blender's multilayer names):
    /// `albedo` (ViewLayer.Denoising Albedo), `normal` (ViewLayer.Denoising Normal, world
    /// space), `depth` (ViewLayer.Depth, distance along the camera ray), `motion`
    /// (ViewLayer.Vector: X,Y towards the previous frame, Z,W towards the next, in pixels,
    /// +y down), and where the method separates them `direct` and `indirect` light
    /// (ViewLayer.Direct, ViewLayer.Indirect: they add up to the beauty; an error for a
    /// method that does not); presets `denoise` (albedo, normal), `light` (direct,
    /// indirect) and `all` (every pass the method can write).
    #[arg(long, value_name = "LIST")]
    pub passes: Option<String>,
    /// Denoise each frame with Intel Open Image Denoise (albedo and normal passes as
    /// guides): the default wherever the library can be had (the build fetches it; README,
    /// "Render passes and denoising"), otherwise the run says why and renders without.
    /// The EXR's main image is the denoised one; the noisy one is kept as the layer
    /// ViewLayer.Noisy Image. Given explicitly, a missing library is an error.
    #[arg(long, conflicts_with = "no_denoise")]
    pub denoise: bool,
    /// Do not denoise: the EXR's main image is the renderer's own estimate.
    #[arg(long)]
    pub no_denoise: bool,
    /// One setting for the effort: `draft`, `preview` (the default: about HDR-FLIP 0.08 on
    /// the shared Cornell scenes) or `final`. Sets every effort parameter of the method
    /// (camera samples, photons, windows, the denoiser's network) from its measured table
    /// in the registry (BENCHMARKS.md, "The quality table"); --spp, --photons, --window,
    /// --denoise-quality and --set still override. A method without a table keeps its
    /// defaults (an explicit --quality is then an error naming the methods with one).
    #[arg(long, value_name = "LEVEL", value_parser = clap::builder::PossibleValuesParser::new(chronolux_render::registry::QUALITIES))]
    pub quality: Option<String>,
    /// Open Image Denoise's quality: `high` (OIDN's own default), `balanced` (the
    /// same network as `high` on a CPU) or `fast` (a smaller network: about half the
    /// filter's CPU time, a higher error at equal samples). Unset, the quality level's
    /// table entry chooses (`fast` for `spacetime-dept`'s draft and preview, where it
    /// reached the same HDR-FLIP with less CPU: BENCHMARKS.md, "The quality table"), else
    /// `high`.
    #[arg(
        long,
        value_enum,
        value_name = "QUALITY",
        conflicts_with = "no_denoise"
    )]
    pub denoise_quality: Option<crate::denoise::DenoiseQuality>,
    /// Render one segment of a farm plan (`chronolux plan`, `chronolux farm`): the plan
    /// fixes every setting, so only --segment, --output, --threads, --resume and
    /// --no-preview may be given with it.
    #[arg(long, value_name = "PLAN.json", requires = "segment")]
    pub plan: Option<PathBuf>,
    /// Index of the segment of --plan to render (0-based): it computes the frames its
    /// technique needs around its own and writes only its own frames, with its manifest
    /// `run.segment-NNNN.json`.
    #[arg(long, value_name = "I", requires = "plan")]
    pub segment: Option<u32>,
}

/// `--method`'s long help: every technique of the registry with its summary.
pub fn method_help() -> String {
    let mut s = format!(
        "Light-transport method (default `{}`). Every setting of a technique can be set \
with --set KEY=VALUE; an unknown key lists the valid ones.\n",
        chronolux_render::registry::DEFAULT_METHOD
    );
    for t in chronolux_render::registry::TECHNIQUES {
        s += &format!("\n  {:<18} {}", t.name(), t.summary());
    }
    s
}

/// What `--spp` sets for each technique and its default there (at the default quality
/// with denoising, which is how `render` runs by default), from the registry.
pub fn spp_help() -> String {
    let mut s = String::from(
        "Samples per pixel (1 to 1048576): the `spp` of the technique's common settings. \
Overrides --quality. Defaults, at the default --quality (denoised) where the method has a \
quality table, else the method's own:\n",
    );
    for t in registry::TECHNIQUES {
        let e = t.capabilities().effort;
        let what = if e.key == "spp" {
            e.unit
        } else {
            "camera samples per pixel"
        };
        let spp = default_settings(*t)
            .and_then(|v| t.common(&v).ok())
            .map_or_else(|| "?".into(), |c| c.spp.to_string());
        s += &format!("\n  {:<18} {spp} {what}", t.name());
    }
    s
}

/// The settings `render` starts from for `t` when no flag is given.
fn default_settings(t: &dyn registry::Technique) -> Option<serde_json::Value> {
    match registry::quality_settings(t, None, true, None) {
        Ok(Some((s, _))) => Some(s),
        Ok(None) => Some(t.defaults()),
        Err(_) => None,
    }
}

/// `--max-depth`: which techniques implement a depth limit, from the registry.
pub fn max_depth_help() -> String {
    format!(
        "Longest light path in segments from the camera, as Mitsuba's max_depth: 1 shows \
emitters only, 2 adds direct lighting (at least 1). Default: unlimited (Russian roulette ends \
paths). Methods with a depth limit: {}; the others refuse it (their eye walk ends at their \
`max_specular_depth` setting).",
        registry::names_where(|c| c.max_depth).join(", ")
    )
}

/// `--shutter`: the techniques with motion blur, from the registry.
pub fn shutter_help() -> String {
    format!(
        "Motion blur: fraction of the frame interval the shutter is open, in [0, 1], centred \
on the frame time (Blender's default); 0 = no motion blur. `path` and `bdpt`: each pixel \
sample gets a time in the shutter, the scene is built at min(spp, 16) instants. `stbpt`: each \
sample's trajectory across the shutter (its point in the neighbouring frames) is splatted over \
the pixels it crosses. Default 0. Methods with motion blur: {}.",
        registry::names_where(|c| c.motion_blur).join(", ")
    )
}

/// `--window`: the windowed techniques with their default windows, from the registry.
pub fn window_help() -> String {
    let mut s = String::from(
        "The technique's `window` setting (0 to 31): frames f-K..f+K share the work made for \
frame f. `stbpt`: each sample serves at most those frames (each frame's K chosen from the \
reuse statistics unless `--set adaptive=false`); `spacetime-dept`: photons pooled over them \
where the animation leaves the light unchanged. Methods with a window, and their defaults:\n",
    );
    for t in registry::TECHNIQUES
        .iter()
        .filter(|t| t.capabilities().window)
    {
        let k = default_settings(*t)
            .and_then(|v| registry::get_key(&v, "window").cloned())
            .map_or_else(|| "?".into(), |v| v.to_string());
        s += &format!("\n  {:<18} {k}", t.name());
    }
    s
}

/// `--photons`: the photon techniques with their default counts, from the registry.
pub fn photons_help() -> String {
    let mut s = String::from(
        "Photons of the photon methods: a count (e.g. 250000), or `auto` for the stopping rule \
(where the method has one), which shoots batches until the reconstruction's noise is below a \
2 % luminance contrast on all but 5 % of the (power-weighted) surface, at most 4 million. \
run.json records the photons of every frame. Methods, their defaults (at the default \
--quality where they have a table) and what the count is:\n",
    );
    for t in registry::TECHNIQUES
        .iter()
        .filter(|t| t.capabilities().photons)
    {
        let d = default_settings(*t);
        let n = d
            .as_ref()
            .and_then(|v| registry::get_key(v, "photons").cloned())
            .map_or_else(|| "?".into(), |v| v.to_string());
        let e = t.capabilities().effort;
        let unit = e
            .unit
            .strip_prefix("thousand ")
            .unwrap_or("photons per frame");
        let auto = if d.is_some_and(|v| registry::find_key(&v, "auto").is_some()) {
            ", or auto"
        } else {
            ""
        };
        s += &format!("\n  {:<18} {n} {unit}{auto}", t.name());
    }
    s
}

fn parse_view(s: &str) -> Result<chronolux_io::image::View, String> {
    use chronolux_io::image::View;
    match s {
        "agx" => Ok(View::Agx),
        "standard" => Ok(View::Standard),
        _ => Err(format!("unknown view `{s}` (agx or standard)")),
    }
}
