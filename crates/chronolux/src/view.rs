//! `chronolux view`: the live viewer (the `chronolux-view` crate) behind the command line.

use crate::args::SceneArgs;
use crate::{render, scene_input};
use anyhow::{Context, Result, bail};
use chronolux_view::{DEFAULT_BIND, EditableScene, ViewOptions};
use clap::Args;
use std::net::{IpAddr, SocketAddr};
use std::time::Duration;

#[derive(Args, Debug)]
pub struct ViewArgs {
    #[command(flatten)]
    pub scene: SceneArgs,
    /// TCP port of the page (0: any free port; the address is printed).
    #[arg(long, default_value_t = 7878, value_name = "P")]
    pub port: u16,
    /// Interface to listen on. Default 127.0.0.1 (this machine only); anything else
    /// exposes the viewer to the network and prints a warning.
    #[arg(long, default_value_t = DEFAULT_BIND, value_name = "ADDR")]
    pub bind: IpAddr,
    /// Image size, WIDTHxHEIGHT (each 1 to 16384). Default: 256 wide, height from the
    /// camera's aspect ratio.
    #[arg(long, value_name = "WxH", allow_hyphen_values = true)]
    pub resolution: Option<String>,
    /// Photons in the selective-photon-tracing pool.
    #[arg(long, default_value_t = 100_000, value_name = "Z")]
    pub photons: u64,
    /// Samples per pixel at which the image stops refining.
    #[arg(long, default_value_t = 256, value_name = "N")]
    pub max_spp: u32,
    /// Worker threads for rendering and photon tracing (default: all cores).
    #[arg(long, value_name = "N")]
    pub threads: Option<usize>,
}

pub fn run(a: ViewArgs) -> Result<()> {
    if a.photons == 0 || a.max_spp == 0 {
        bail!("--photons and --max-spp must be at least 1");
    }
    if let Some(n) = a.threads {
        rayon::ThreadPoolBuilder::new()
            .num_threads(n.max(1))
            .build_global()
            .context("cannot set up the thread pool")?;
    }
    let input = scene_input::load(&a.scene)?;
    let (w, h) = match a.resolution.as_deref() {
        Some(r) => render::parse_resolution(r)?,
        None => {
            let (w, h) = render::default_resolution(&input.desc, &input.camera);
            (256, ((h as f32 * 256.0 / w as f32).round() as u32).max(1))
        }
    };
    let (scene, frame) = EditableScene::new(input.desc, input.animation, input.camera, w, h)
        .with_context(|| format!("cannot show {}", input.source))?;
    let listener = chronolux_view::bind(SocketAddr::new(a.bind, a.port))?;
    if !a.bind.is_loopback() {
        log::warn!(
            "listening on {} — the viewer is reachable from other machines",
            a.bind
        );
    }
    let opts = ViewOptions {
        photons: a.photons,
        max_spp: a.max_spp,
        slice: Duration::from_millis(150),
    };
    let running = chronolux_view::start(listener, scene, frame, opts)?;
    println!(
        "chronolux view: {} on http://{}/",
        input.source, running.addr
    );
    running.wait()
}
