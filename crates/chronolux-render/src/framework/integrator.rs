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
    /// The technique's own report of this frame (photons shot, reuse statistics, …),
    /// merged into the frame's record in `run.json`. Empty for plain integrators.
    pub report: Report,
    /// The image split into direct and indirect light, from a technique that separates
    /// them ([`RadianceEstimator::separates_light`]); `None` from every other one.
    pub light: Option<LightSplit>,
}

/// A frame's light split into two images that add up to the beauty: for every pixel,
/// `direct + indirect == pixels` exactly (the driver forms the beauty as that sum).
///
/// Convention (a first-non-delta-vertex split): **direct** is emission (surface or
/// environment) that reaches the camera with no scattering or through delta (mirror,
/// smooth glass) bounces only, plus light arriving at the first non-delta vertex straight
/// from an emitter (that vertex's light sample and the emission its BSDF-sampled ray hits,
/// each with its MIS weight); **indirect** is everything else (two or more scattering
/// vertices, one of them non-delta, including caustics `light → specular → first
/// non-delta vertex`). Blender's DiffDir + GlossDir + TransDir + Emit + Env correspond to
/// the direct image, its DiffInd + GlossInd + TransInd to the indirect one, without the
/// split by lobe.
#[derive(Clone, Debug, Default)]
pub struct LightSplit {
    pub direct: Vec<Rgb>,
    pub indirect: Vec<Rgb>,
}

/// A technique's per-frame report: named JSON values (`"photons"`, `"reuse"`, …).
pub type Report = serde_json::Map<String, serde_json::Value>;

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

    /// The same integrator for one pass of a progressive rendering
    /// ([`crate::framework::sequence::FrameByFrame`]'s passes): `spp` samples per pixel drawn from the
    /// streams of [`crate::framework::sequence::batch_seed`]`(its seed, round, half)`, an independent
    /// randomisation. `None`: it cannot be re-batched.
    fn batch(&self, spp: u32, round: u32, half: u32) -> Option<Box<dyn Integrator + Send>> {
        let _ = (spp, round, half);
        None
    }
    /// Whether its frames carry [`RenderedFrame::light`] (see [`LightSplit`]).
    fn separates_light(&self) -> bool {
        false
    }
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

    /// Whether [`Self::li_split`] separates direct from indirect light ([`LightSplit`]'s
    /// convention). False by default: such an estimator writes no light split.
    fn separates_light(&self) -> bool {
        false
    }

    /// The sample [`Self::li`] would return, as `[direct, indirect]` (their sum is the
    /// sample's radiance). Called instead of `li` when [`Self::separates_light`]; the
    /// default (never used then) counts everything as direct.
    fn li_split(
        &self,
        scene: &FrameScene,
        ray: &chronolux_core::geometry::Ray,
        sampler: &mut PixelSampler,
        stats: &mut Stats,
    ) -> [Rgb; 2] {
        [self.li(scene, ray, sampler, stats), Rgb::ZERO]
    }
}

/// The scene(s) a driver traces a frame's pixel samples in: the frame's one scene, or
/// the scenes of a shutter's instants (motion blur, [`crate::framework::shutter`]), in which case
/// each sample draws its instant from its own stream, the dimension right after its
/// raster position.
#[derive(Clone, Copy)]
pub(crate) enum Scenes<'a> {
    One(&'a FrameScene),
    Shutter(&'a [FrameScene]),
}

impl<'a> Scenes<'a> {
    /// The scene that sets the image size.
    fn first(&self) -> &'a FrameScene {
        match *self {
            Scenes::One(s) => s,
            Scenes::Shutter(v) => v.first().expect("no scene in the shutter interval"),
        }
    }

    /// The scene of one pixel sample (draws one number for a shutter, none otherwise).
    #[inline]
    fn pick(&self, sampler: &mut PixelSampler) -> &'a FrameScene {
        match *self {
            Scenes::One(s) => s,
            Scenes::Shutter(v) => &v[instant_of(sampler.next_1d(), v.len())],
        }
    }
}

/// Tile edge in pixels. Results do not depend on it (each pixel has its own sample
/// stream); it only sets the grain of parallel work.
pub const TILE: u32 = 16;

/// Pixel rectangle (x0, y0, width, height) of tile `t` in a `w`×`h` image cut into
/// `tile`×`tile` tiles, `tiles_x` per row; edge tiles are clipped.
#[inline]
pub(crate) fn tile_rect(t: u32, tiles_x: u32, tile: u32, w: u32, h: u32) -> (u32, u32, u32, u32) {
    let (x0, y0) = ((t % tiles_x) * tile, (t / tiles_x) * tile);
    (x0, y0, tile.min(w - x0), tile.min(h - y0))
}

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
    render_camera_rays_tiled(est, scene, frame, spp, seed, TILE, progress)
}

/// [`render_camera_rays`] with tiles of `tile`×`tile` pixels; the image is bit-identical
/// for every tile size (a test checks it), which only changes the grain of parallel work.
pub fn render_camera_rays_tiled<E: RadianceEstimator>(
    est: &E,
    scene: &FrameScene,
    frame: u32,
    spp: u32,
    seed: u64,
    tile: u32,
    progress: &(dyn Fn(u64) + Sync),
) -> RenderedFrame {
    camera_rays(est, Scenes::One(scene), frame, spp, seed, tile, progress)
}

/// The camera-ray driver over [`Scenes`] (one frame, or a shutter's instants).
pub(crate) fn camera_rays<E: RadianceEstimator>(
    est: &E,
    scenes: Scenes,
    frame: u32,
    spp: u32,
    seed: u64,
    tile: u32,
    progress: &(dyn Fn(u64) + Sync),
) -> RenderedFrame {
    let cam = &scenes.first().camera;
    let (w, h) = (cam.width, cam.height);
    let split = est.separates_light();
    let tile = tile.max(1);
    let tiles_x = w.div_ceil(tile);
    let tiles_y = h.div_ceil(tile);
    let n_tiles = (tiles_x * tiles_y) as usize;
    let results = parallel::map_chunks(n_tiles, 1, |range| {
        let (x0, y0, tw, th) = tile_rect(range.start as u32, tiles_x, tile, w, h);
        let mut film = Film::new(tw, th);
        // Direct and indirect films, for an estimator that separates them.
        let mut parts = split.then(|| [Film::new(tw, th), Film::new(tw, th)]);
        let mut stats = Stats::default();
        let mut invalid = 0u64;
        for y in 0..th {
            for x in 0..tw {
                let (px, py) = (x0 + x, y0 + y);
                let mut sampler = PixelSampler::new(seed, frame, px, py);
                for s in 0..spp {
                    sampler.start_sample(s);
                    let raster = Vec2::new(px as f32, py as f32) + sampler.next_2d();
                    let scene = scenes.pick(&mut sampler);
                    let ray = scene.camera.generate_ray(raster);
                    let (l, dl) = match parts {
                        None => (est.li(scene, &ray, &mut sampler, &mut stats), None),
                        Some(_) => {
                            let [d, i] = est.li_split(scene, &ray, &mut sampler, &mut stats);
                            (d + i, Some([d, i]))
                        }
                    };
                    stats.samples += 1;
                    let ok = l.is_finite();
                    if !ok {
                        invalid += 1;
                    }
                    film.add(x, y, if ok { l } else { Rgb::ZERO }, 1.0);
                    if let (Some(films), Some(dl)) = (parts.as_mut(), dl) {
                        for (f, v) in films.iter_mut().zip(dl) {
                            f.add(x, y, if ok { v } else { Rgb::ZERO }, 1.0);
                        }
                    }
                }
            }
        }
        progress((tw * th) as u64);
        (x0, y0, film, parts, stats, invalid)
    });
    let mut film = Film::new(w, h);
    let mut parts = split.then(|| [Film::new(w, h), Film::new(w, h)]);
    let mut stats = Stats::default();
    let mut invalid = 0;
    for (x0, y0, tile, tile_parts, s, inv) in &results {
        film.merge_tile(tile, *x0, *y0);
        if let (Some(p), Some(t)) = (parts.as_mut(), tile_parts) {
            p[0].merge_tile(&t[0], *x0, *y0);
            p[1].merge_tile(&t[1], *x0, *y0);
        }
        stats += *s;
        invalid += inv;
    }
    let light = parts.map(|[d, i]| LightSplit {
        direct: d.pixels(),
        indirect: i.pixels(),
    });
    // With a split, the beauty is defined as direct + indirect (equal to the film's mean
    // up to rounding), so that the two add up to it exactly.
    let pixels = match &light {
        Some(l) => l
            .direct
            .iter()
            .zip(&l.indirect)
            .map(|(d, i)| *d + *i)
            .collect(),
        None => film.pixels(),
    };
    RenderedFrame {
        width: w,
        height: h,
        pixels,
        variance: film.variance_of_mean(),
        stats,
        invalid_samples: invalid,
        report: Report::new(),
        light,
    }
}

/// An estimator whose samples, besides the radiance of their own camera sample, contribute
/// to arbitrary pixels (light tracing, the t = 1 strategies of bidirectional methods).
pub trait SplattingEstimator: Sync {
    /// Estimate for the camera sample at `raster` (already jittered inside its pixel),
    /// drawing every number from `sampler`. Contributions to the pixel a raster position
    /// falls in are pushed to `splats` as (raster, value), with values normalised so that a
    /// pixel's estimate is the sum of the splats it receives from **all** pixels' samples
    /// of one sample index (see [`render_with_splats`]).
    fn sample(
        &self,
        scene: &FrameScene,
        raster: Vec2,
        sampler: &mut PixelSampler,
        stats: &mut Stats,
        splats: &mut Vec<(Vec2, Rgb)>,
    ) -> Rgb;
}

/// The splatting driver: like [`render_camera_rays`], plus contributions splatted to other
/// pixels. Samples are taken in passes, one sample index per pass over the whole image;
/// within a pass tiles run in parallel and their splats are merged in tile order, so the
/// image is bit-identical for any thread count. Pixel `k`'s value for pass `s` is its own
/// camera estimate plus every splat of pass `s` that lands in it; the film averages these
/// per-pass values, so [`RenderedFrame::variance`] is the variance of the mean of `spp`
/// independent per-pass estimates (splats included).
pub fn render_with_splats<E: SplattingEstimator>(
    est: &E,
    scene: &FrameScene,
    frame: u32,
    spp: u32,
    seed: u64,
    progress: &(dyn Fn(u64) + Sync),
) -> RenderedFrame {
    splatting(est, Scenes::One(scene), frame, spp, seed, progress)
}

/// The splatting driver over [`Scenes`] (one frame, or a shutter's instants: each pixel's
/// sample runs, and splats, in its own instant's scene).
pub(crate) fn splatting<E: SplattingEstimator>(
    est: &E,
    scenes: Scenes,
    frame: u32,
    spp: u32,
    seed: u64,
    progress: &(dyn Fn(u64) + Sync),
) -> RenderedFrame {
    let cam = &scenes.first().camera;
    let (w, h) = (cam.width, cam.height);
    let tiles_x = w.div_ceil(TILE);
    let tiles_y = h.div_ceil(TILE);
    let n_tiles = (tiles_x * tiles_y) as usize;
    let mut film = Film::new(w, h);
    let mut stats = Stats::default();
    let mut invalid = 0u64;
    let mut pass = vec![Rgb::ZERO; (w * h) as usize];
    for s in 0..spp {
        let results = parallel::map_chunks(n_tiles, 1, |range| {
            let (x0, y0, tw, th) = tile_rect(range.start as u32, tiles_x, TILE, w, h);
            let mut own = Vec::with_capacity((tw * th) as usize);
            let mut splats = Vec::new();
            let mut stats = Stats::default();
            let mut invalid = 0u64;
            for y in 0..th {
                for x in 0..tw {
                    let (px, py) = (x0 + x, y0 + y);
                    let mut sampler = PixelSampler::new(seed, frame, px, py);
                    sampler.start_sample(s);
                    let raster = Vec2::new(px as f32, py as f32) + sampler.next_2d();
                    let scene = scenes.pick(&mut sampler);
                    let l = est.sample(scene, raster, &mut sampler, &mut stats, &mut splats);
                    stats.samples += 1;
                    own.push(if l.is_finite() {
                        l
                    } else {
                        invalid += 1;
                        Rgb::ZERO
                    });
                }
            }
            // Spread this tile's progress over the passes (sums to tw·th per tile).
            let n = (tw * th) as u64;
            progress(n * (s as u64 + 1) / spp as u64 - n * s as u64 / spp as u64);
            (x0, y0, tw, th, own, splats, stats, invalid)
        });
        for (x0, y0, tw, th, own, _, st, inv) in &results {
            for y in 0..*th {
                for x in 0..*tw {
                    pass[((y0 + y) * w + x0 + x) as usize] = own[(y * tw + x) as usize];
                }
            }
            stats += *st;
            invalid += inv;
        }
        for (.., splats, _, _) in &results {
            for (r, v) in splats {
                if !v.is_finite() {
                    invalid += 1;
                    continue;
                }
                let (x, y) = (r.x as u32, r.y as u32);
                if r.x >= 0.0 && r.y >= 0.0 && x < w && y < h {
                    pass[(y * w + x) as usize] += *v;
                }
            }
        }
        for y in 0..h {
            for x in 0..w {
                film.add(x, y, pass[(y * w + x) as usize], 1.0);
            }
        }
    }
    RenderedFrame {
        width: w,
        height: h,
        pixels: film.pixels(),
        variance: film.variance_of_mean(),
        stats,
        invalid_samples: invalid,
        report: Report::new(),
        light: None,
    }
}

/// Index of the instant a time sample `u ∈ [0, 1)` falls in, of `n`.
#[inline]
pub fn instant_of(u: f32, n: usize) -> usize {
    ((u * n as f32) as usize).min(n - 1)
}
