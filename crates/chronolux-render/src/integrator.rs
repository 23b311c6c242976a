//! The single-frame integrator contract and the deterministic tiled camera-ray driver.

use chronolux_core::color::Rgb;
use chronolux_core::film::Film;
use chronolux_core::math::Vec2;
use chronolux_core::parallel;
use chronolux_core::sampling::sampler::PixelSampler;
use chronolux_core::scene::frame::FrameScene;
use chronolux_core::stats::Stats;

/// A rendered frame: linear RGB, row-major, top row first.
#[derive(Clone, Debug)]
pub struct RenderedFrame {
    pub width: u32,
    pub height: u32,
    pub pixels: Vec<Rgb>,
    /// Estimated variance of each pixel value (of the mean over its samples), per channel.
    pub variance: Vec<Rgb>,
    pub stats: Stats,
    /// Samples dropped because their value was NaN or infinite (should be 0).
    pub invalid_samples: u64,
}

/// Renders one frame of a [`FrameScene`].
pub trait Integrator: Sync {
    /// `frame` keys the sample streams (a frame-by-frame baseline decorrelates frames on
    /// purpose). `progress` is called with the number of pixels finished since the last call.
    fn render(
        &self,
        scene: &FrameScene,
        frame: u32,
        progress: &(dyn Fn(u64) + Sync),
    ) -> RenderedFrame;
}

/// An estimator of radiance along one camera ray.
pub trait RadianceEstimator: Sync {
    /// Radiance arriving at the camera along `ray`; draws its numbers from `sampler`.
    fn li(
        &self,
        scene: &FrameScene,
        ray: &chronolux_core::geometry::Ray,
        sampler: &mut PixelSampler,
        stats: &mut Stats,
    ) -> Rgb;
}

/// Tile edge in pixels. Results do not depend on it (each pixel has its own sample
/// stream); it only sets the grain of parallel work.
pub const TILE: u32 = 16;

/// The one camera-ray driver: `spp` samples per pixel through `est`, box-filtered, tiles
/// rendered in parallel and merged in tile order (bit-identical for any thread count).
pub fn render_camera_rays<E: RadianceEstimator>(
    est: &E,
    scene: &FrameScene,
    frame: u32,
    spp: u32,
    seed: u64,
    progress: &(dyn Fn(u64) + Sync),
) -> RenderedFrame {
    let cam = &scene.camera;
    let (w, h) = (cam.width, cam.height);
    let tiles_x = w.div_ceil(TILE);
    let tiles_y = h.div_ceil(TILE);
    let n_tiles = (tiles_x * tiles_y) as usize;
    let results = parallel::map_chunks(n_tiles, 1, |range| {
        let t = range.start as u32;
        let (x0, y0) = ((t % tiles_x) * TILE, (t / tiles_x) * TILE);
        let (tw, th) = (TILE.min(w - x0), TILE.min(h - y0));
        let mut film = Film::new(tw, th);
        let mut stats = Stats::default();
        let mut invalid = 0u64;
        for y in 0..th {
            for x in 0..tw {
                let (px, py) = (x0 + x, y0 + y);
                let mut sampler = PixelSampler::new(seed, frame, px, py);
                for s in 0..spp {
                    sampler.start_sample(s);
                    let raster = Vec2::new(px as f32, py as f32) + sampler.next_2d();
                    let ray = cam.generate_ray(raster);
                    let l = est.li(scene, &ray, &mut sampler, &mut stats);
                    stats.samples += 1;
                    if l.is_finite() {
                        film.add(x, y, l, 1.0);
                    } else {
                        invalid += 1;
                        film.add(x, y, Rgb::ZERO, 1.0);
                    }
                }
            }
        }
        progress((tw * th) as u64);
        (x0, y0, film, stats, invalid)
    });
    let mut film = Film::new(w, h);
    let mut stats = Stats::default();
    let mut invalid = 0;
    for (x0, y0, tile, s, inv) in &results {
        film.merge_tile(tile, *x0, *y0);
        stats += *s;
        invalid += inv;
    }
    RenderedFrame {
        width: w,
        height: h,
        pixels: film.pixels(),
        variance: film.variance_of_mean(),
        stats,
        invalid_samples: invalid,
    }
}
