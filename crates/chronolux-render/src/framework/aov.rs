//! Render passes (AOVs) of a frame, the same for every technique: first-hit albedo,
//! shading normal, depth, and screen-space motion towards the previous and next frame.
//!
//! They depend only on the frame's geometry, materials and camera (and its neighbours' for
//! motion), not on light transport, so they are made once here, by the run loop, whatever
//! the technique ([`crate::framework::run::RunOptions::passes`]); a denoiser takes albedo and normal
//! from them.
//!
//! ## Conventions (written into the EXR layers by the output path)
//! - Each pass is the box-filtered mean of [`AOV_SPP`] jittered camera samples per pixel
//!   (Owen-scrambled Sobol keyed by pixel, like the beauty), so edges are antialiased as
//!   the beauty is (what Open Image Denoise asks of its auxiliary images).
//! - **albedo**: the directional albedo of the first surface hit, approximated from the
//!   material's lobes as diffuse + metal·F0 + dielectric specular F0 + transmission tint
//!   (each lobe's normal-incidence reflectance times its weight), clamped to [0, 1]; for a
//!   near-specular surface (GGX α < 0.1: mirrors, glass) the lobe tints alone, as OIDN
//!   recommends for delta-like materials; 0 where the ray escapes (background).
//! - **normal**: world-space shading normal (unit, facing the camera side) at the first
//!   hit; 0 where the ray escapes.
//! - **depth**: distance from the camera's ray origin to the first hit along the ray (world
//!   units); [`DEPTH_MISS`] where the ray escapes (Blender writes 1e10 there too).
//! - **motion**: where the first-hit point of the pixel centre is seen in the previous and
//!   in the next frame, minus where it is seen now, in pixels of this image, raster
//!   convention (+x right, +y down). The point is followed with its object (the same
//!   triangle and barycentrics in the other frame's scene: exact for rigid, skinned and
//!   morphed geometry) and projected with that frame's camera, so camera motion is
//!   included. 0 at a sequence end (no frame on that side), where the ray escapes, or
//!   where the point is behind the other frame's camera.
//! - **direct**, **indirect**: not made here but by the light transport of a technique
//!   that separates them ([`crate::framework::integrator::LightSplit`] has the convention; they add
//!   up to the beauty exactly); [`PassSet::resolve`] refuses them for any other one.

use crate::framework::integrator::tile_rect;
use chronolux_core::color::Rgb;
use chronolux_core::math::{Vec2, Vec3};
use chronolux_core::parallel;
use chronolux_core::sampling::sampler::PixelSampler;
use chronolux_core::scene::frame::FrameScene;

/// Camera samples per pixel of the passes. Four: for the denoiser (stbpt + OIDN on
/// cornell-moving, 256², 1–4 spp) 8 samples cost 2–12 % more CPU than 4 for 0.2–0.4 %
/// lower HDR-FLIP, and 2 lose 1.5–2 % of FLIP (BENCHMARKS.md, "Issue 17: the denoiser's
/// passes").
pub const AOV_SPP: u32 = 4;
/// Depth written where a ray escapes.
pub const DEPTH_MISS: f32 = 1e10;
/// Seed salt separating the passes' sample streams from the beauty's.
const AOV_STREAM: u64 = 0x4a4f_5653_5041_5353;

/// Which passes to make. `direct` and `indirect` are the technique's light split
/// ([`crate::framework::integrator::LightSplit`]), not made here: only a technique that separates
/// them can write them ([`PassSet::resolve`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(default)]
pub struct PassSet {
    pub albedo: bool,
    pub normal: bool,
    pub depth: bool,
    pub motion: bool,
    pub direct: bool,
    pub indirect: bool,
    /// The preset `all` was given: direct and indirect too, where the technique
    /// separates them (and silently not where it does not).
    pub all: bool,
}

impl PassSet {
    /// Every pass name `--passes` accepts.
    pub const NAMES: [&'static str; 6] =
        ["albedo", "normal", "depth", "motion", "direct", "indirect"];

    /// Parses `albedo,normal,…`, or the presets `all` (every pass the technique can
    /// write), `denoise` (albedo, normal) and `light` (direct, indirect).
    pub fn parse(list: &str) -> Result<PassSet, String> {
        let mut p = PassSet::default();
        for name in list.split(',').map(str::trim).filter(|s| !s.is_empty()) {
            match name {
                "albedo" => p.albedo = true,
                "normal" => p.normal = true,
                "depth" => p.depth = true,
                "motion" => p.motion = true,
                "direct" => p.direct = true,
                "indirect" => p.indirect = true,
                "light" => {
                    p.direct = true;
                    p.indirect = true;
                }
                "denoise" => {
                    p.albedo = true;
                    p.normal = true;
                }
                "all" => {
                    p.albedo = true;
                    p.normal = true;
                    p.depth = true;
                    p.motion = true;
                    p.all = true;
                }
                other => {
                    return Err(format!(
                        "unknown pass '{other}' (passes: {}; presets: all, denoise, light)",
                        Self::NAMES.join(", ")
                    ));
                }
            }
        }
        Ok(p)
    }

    /// The set for a technique that does (`separates`) or does not separate direct and
    /// indirect light: `all` takes them where it does; naming `direct` or `indirect`
    /// for a technique that does not is an error.
    pub fn resolve(self, method: &str, separates: bool) -> Result<PassSet, String> {
        if (self.direct || self.indirect) && !separates {
            return Err(format!(
                "method '{method}' does not separate direct and indirect light, so it cannot write the passes direct and indirect (README, \"Render passes and denoising\", lists the methods that do)"
            ));
        }
        let mut p = self;
        if p.all && separates {
            p.direct = true;
            p.indirect = true;
        }
        Ok(p)
    }

    /// Whether any pass is asked for.
    pub fn any(&self) -> bool {
        self.geometric() || self.direct || self.indirect
    }

    /// Whether any of the passes made here (from geometry, not light transport) is.
    pub fn geometric(&self) -> bool {
        self.albedo || self.normal || self.depth || self.motion
    }

    /// The union of two sets.
    pub fn with(self, o: PassSet) -> PassSet {
        PassSet {
            albedo: self.albedo || o.albedo,
            normal: self.normal || o.normal,
            depth: self.depth || o.depth,
            motion: self.motion || o.motion,
            direct: self.direct || o.direct,
            indirect: self.indirect || o.indirect,
            all: self.all || o.all,
        }
    }
}

/// The passes of one frame, row-major, top row first; a pass not asked for is empty.
#[derive(Clone, Debug, Default)]
pub struct Aovs {
    pub width: u32,
    pub height: u32,
    pub albedo: Vec<Rgb>,
    pub normal: Vec<Vec3>,
    pub depth: Vec<f32>,
    /// Offset to where the point is seen in the previous frame (pixels).
    pub motion_prev: Vec<Vec2>,
    /// Offset to where the point is seen in the next frame (pixels).
    pub motion_next: Vec<Vec2>,
}

/// Directional albedo of the lobes at normal incidence (see the module doc).
fn albedo_of(b: &chronolux_core::bsdf::Bsdf) -> Rgb {
    let l = &b.lobes;
    let a = l.diffuse
        + l.specular_f0 * l.specular_weight
        + l.metal * l.metal_weight
        + l.transmission * l.transmission_weight;
    a.clamp(Rgb::ZERO, Rgb::ONE)
}

/// The passes `set` of the frame `scene`, with its neighbours for motion. Tiles in
/// parallel, merged in tile order: bit-identical for any thread count.
pub fn render_aovs(
    scene: &FrameScene,
    prev: Option<&FrameScene>,
    next: Option<&FrameScene>,
    frame: u32,
    seed: u64,
    set: PassSet,
) -> Aovs {
    let cam = &scene.camera;
    let (w, h) = (cam.width, cam.height);
    let tile = crate::framework::integrator::TILE;
    let tiles_x = w.div_ceil(tile);
    let n_tiles = (tiles_x * h.div_ceil(tile)) as usize;
    type TileOut = (u32, u32, u32, u32, Vec<(Rgb, Vec3, f32, Vec2, Vec2)>);
    let tiles: Vec<TileOut> = parallel::map_chunks(n_tiles, 1, |range| {
        let (x0, y0, tw, th) = tile_rect(range.start as u32, tiles_x, tile, w, h);
        let mut out = Vec::with_capacity((tw * th) as usize);
        for y in y0..y0 + th {
            for x in x0..x0 + tw {
                out.push(pixel(scene, prev, next, frame, seed, set, x, y));
            }
        }
        (x0, y0, tw, th, out)
    });
    let n = (w * h) as usize;
    let mut a = Aovs {
        width: w,
        height: h,
        albedo: if set.albedo {
            vec![Rgb::ZERO; n]
        } else {
            vec![]
        },
        normal: if set.normal {
            vec![Vec3::ZERO; n]
        } else {
            vec![]
        },
        depth: if set.depth { vec![0.0; n] } else { vec![] },
        motion_prev: if set.motion {
            vec![Vec2::ZERO; n]
        } else {
            vec![]
        },
        motion_next: if set.motion {
            vec![Vec2::ZERO; n]
        } else {
            vec![]
        },
    };
    for (x0, y0, tw, th, px) in tiles {
        for dy in 0..th {
            for dx in 0..tw {
                let k = ((y0 + dy) * w + x0 + dx) as usize;
                let (al, no, de, mp, mn) = px[(dy * tw + dx) as usize];
                if set.albedo {
                    a.albedo[k] = al;
                }
                if set.normal {
                    a.normal[k] = no;
                }
                if set.depth {
                    a.depth[k] = de;
                }
                if set.motion {
                    a.motion_prev[k] = mp;
                    a.motion_next[k] = mn;
                }
            }
        }
    }
    a
}

/// One pixel's passes: albedo, normal and depth averaged over [`AOV_SPP`] jittered
/// samples (depth over the samples that hit, else [`DEPTH_MISS`]); motion of the pixel
/// centre's point.
fn pixel(
    scene: &FrameScene,
    prev: Option<&FrameScene>,
    next: Option<&FrameScene>,
    frame: u32,
    seed: u64,
    set: PassSet,
    x: u32,
    y: u32,
) -> (Rgb, Vec3, f32, Vec2, Vec2) {
    let mut sampler = PixelSampler::new(seed ^ AOV_STREAM, frame, x, y);
    let (mut albedo, mut normal, mut depth, mut hits) = (Rgb::ZERO, Vec3::ZERO, 0.0f32, 0u32);
    if set.albedo || set.normal || set.depth {
        for s in 0..AOV_SPP {
            sampler.start_sample(s);
            let raster = Vec2::new(x as f32, y as f32) + sampler.next_2d();
            let ray = scene.camera.generate_ray(raster);
            let Some(hit) = scene.intersect(&ray) else {
                continue;
            };
            let si = scene.interaction(&hit, &ray);
            let bsdf = scene.bsdf(&si);
            albedo += albedo_of(&bsdf);
            let n = bsdf.frame.n;
            normal += if n.dot(ray.d) > 0.0 { -n } else { n };
            depth += hit.t * ray.d.length();
            hits += 1;
        }
    }
    let inv = 1.0 / AOV_SPP as f32;
    let normal = if normal.length_squared() > 0.0 {
        normal.normalize() * (hits as f32 * inv)
    } else {
        Vec3::ZERO
    };
    let depth = if hits > 0 {
        depth / hits as f32
    } else {
        DEPTH_MISS
    };
    let (mut mp, mut mn) = (Vec2::ZERO, Vec2::ZERO);
    if set.motion {
        let here = Vec2::new(x as f32 + 0.5, y as f32 + 0.5);
        let ray = scene.camera.generate_ray(here);
        if let Some(hit) = scene.intersect(&ray) {
            let at = |other: Option<&FrameScene>| -> Vec2 {
                let Some(o) = other else {
                    return Vec2::ZERO;
                };
                let inst = o.geometry_instance[hit.tri.geometry as usize];
                let p = o.surface_at(hit.tri, inst, hit.b1, hit.b2, None).p;
                // Where the point is now, projected with this frame's camera (equal to
                // `here` up to rounding), so a static point gets exactly zero.
                let now = scene.camera.project(
                    scene
                        .surface_at(hit.tri, hit.instance, hit.b1, hit.b2, None)
                        .p,
                );
                match (o.camera.project(p), now) {
                    (Some(a), Some(b)) => a - b,
                    _ => Vec2::ZERO,
                }
            };
            mp = at(prev);
            mn = at(next);
        }
    }
    (albedo * inv, normal, depth, mp, mn)
}
