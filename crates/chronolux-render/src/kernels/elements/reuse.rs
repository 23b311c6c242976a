//! The eye pass with its per-pixel light kept, and that light reused over past frames
//! where the animation leaves a pixel's paths unchanged.
//!
//! The eye pass of [`super::view`] splits every camera sample into the per-pixel light
//! (emission seen through delta bounces and the light samples of the path: independent of
//! the element solution) and the elements' term. [`eye_pass`] keeps, per pixel, the sums
//! of both and the **reach** of its paths: the bounds of their ray origins and of their
//! vertices ([`Reach`]). In a later frame `f`, the light of a past frame `g` is pooled with
//! `f`'s own where nothing that differs between `g` and `f` can touch those paths, decided
//! from the animation alone ([`FrameDelta`], never from pixel values) by
//! [`Validity::between`]:
//! - the camera, the lights, the materials and the scene bounds are the same in `g` and
//!   `f` (otherwise no pixel of `g` is used);
//! - the world bounds of every instance that moved or deformed between `g` and `f`, in both
//!   frames, stay clear of the region the pixel's light depends on: the segments from its
//!   ray origins to its vertices (delta chains included) and the shadow rays from its
//!   vertices to any point of any light. That region is inside two capsules — origins box
//!   to vertex box, vertex box to the lights' box, each with the larger of its two boxes'
//!   bounding radii — and a changed instance is inside a ball; a pixel is refused when a
//!   ball touches a capsule (conservative: it refuses more than the exact test would).
//!   A directional light (a sun) has no box, but its shadow rays are parallel: from the
//!   vertex ball they sweep a half-cylinder of the ball's radius towards the light, and a
//!   ball clear of it leaves them unchanged (as conservative as the capsules).
//!
//! The region is that of the pixel's samples in **both** frames (the union of their
//! reaches): `g`'s own paths, traced in `g`, avoid everything that differs in `f`, so each
//! of them has the same value in `f`; `f`'s paths avoiding it too makes it unlikely that
//! the pixel has paths through a changed object that neither frame's samples found (a
//! bias only then: at most the chance `(1 − q)^(2·spp)` that both frames' samples miss
//! a part `q` of the pixel's paths, times that part's difference).
//!
//! Glossy continuations grow the box like delta chains: how a pixel's glossy paths
//! spread is sampled by both frames' samples, and a box touched by an object that moves
//! refuses the whole pixel, so which samples are pooled does not depend on where each
//! one went (a test per sample would pool exactly the samples that missed the object,
//! a biased selection). Unbounded paths (a ray leaving the scene) and environment lights
//! (a sky: its shadow rays leave in every direction above a vertex) are reused only when
//! no instance changed.

use super::view::DeptView;
pub use super::view::Reach;
use chronolux_core::color::Rgb;
use chronolux_core::geometry::Bounds3;
use chronolux_core::light::Light;
use chronolux_core::math::{Vec2, Vec3};
use chronolux_core::parallel;
use chronolux_core::sampling::sampler::PixelSampler;
use chronolux_core::scene::delta::FrameDelta;
use chronolux_core::scene::frame::FrameScene;
use chronolux_core::stats::Stats;

/// One frame's eye pass, per pixel (row-major): sums over its `spp` samples.
#[derive(Clone, Debug)]
pub struct EyeRecord {
    pub width: u32,
    pub height: u32,
    pub spp: u32,
    /// Σ direct light ([`crate::framework::integrator::LightSplit`]'s convention).
    pub direct: Vec<Rgb>,
    /// Σ light-sampled indirect light (light samples of diffuse surfaces seen through
    /// glossy ones).
    pub path: Vec<Rgb>,
    /// Σ the elements' term.
    pub elements: Vec<Rgb>,
    /// Σ (sample value)², per channel, of the whole sample.
    pub sq: Vec<Rgb>,
    pub reach: Vec<Reach>,
    pub stats: Stats,
    pub invalid_samples: u64,
}

/// The eye pass of `view` over `scene` with `spp` samples per pixel from the streams of
/// (`seed`, `frame`, pixel), as [`crate::framework::integrator::render_camera_rays`] draws them.
pub fn eye_pass(
    view: &DeptView,
    scene: &FrameScene,
    frame: u32,
    spp: u32,
    seed: u64,
    progress: &(dyn Fn(u64) + Sync),
) -> EyeRecord {
    let (w, h) = (scene.camera.width, scene.camera.height);
    let rows = parallel::map_chunks(h as usize, 1, |range| {
        let mut out = Vec::with_capacity(range.len() * w as usize);
        let mut stats = Stats::default();
        let mut invalid = 0u64;
        for py in range {
            for px in 0..w {
                let mut sampler = PixelSampler::new(seed, frame, px, py as u32);
                let mut reach = Reach::default();
                let mut sums = [Rgb::ZERO; 4];
                for s in 0..spp {
                    sampler.start_sample(s);
                    let raster = Vec2::new(px as f32, py as f32) + sampler.next_2d();
                    let ray = scene.camera.generate_ray(raster);
                    let parts =
                        view.trace_parts(scene, &ray, &mut sampler, &mut stats, Some(&mut reach));
                    stats.samples += 1;
                    let l = parts[0] + parts[1] + parts[2];
                    if !l.is_finite() {
                        invalid += 1;
                        continue;
                    }
                    for (acc, v) in sums.iter_mut().zip(parts) {
                        *acc += v;
                    }
                    sums[3] += l * l;
                }
                out.push((sums, reach));
            }
            progress(w as u64);
        }
        (out, stats, invalid)
    });
    let n = (w * h) as usize;
    let mut rec = EyeRecord {
        width: w,
        height: h,
        spp,
        direct: Vec::with_capacity(n),
        path: Vec::with_capacity(n),
        elements: Vec::with_capacity(n),
        sq: Vec::with_capacity(n),
        reach: Vec::with_capacity(n),
        stats: Stats::default(),
        invalid_samples: 0,
    };
    for (px, stats, invalid) in rows {
        for ([d, p, e, q], r) in px {
            rec.direct.push(d);
            rec.path.push(p);
            rec.elements.push(e);
            rec.sq.push(q);
            rec.reach.push(r);
        }
        rec.stats += stats;
        rec.invalid_samples += invalid;
    }
    rec
}

/// A ball (centre, radius) around a box; `None` for an empty box.
fn ball(b: &Bounds3) -> Option<(Vec3, f32)> {
    (!b.is_empty()).then(|| (b.center(), 0.5 * b.diagonal().length()))
}

/// Distance from `p` to the segment `a`–`b`.
fn segment_distance(p: Vec3, a: Vec3, b: Vec3) -> f32 {
    let ab = b - a;
    let t = if ab.length_squared() > 0.0 {
        ((p - a).dot(ab) / ab.length_squared()).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (a + ab * t - p).length()
}

/// Whether a past frame's per-pixel light may be pooled with the current frame's.
#[derive(Clone, Debug)]
pub enum Validity {
    /// Nothing that paths can see changed: every pixel.
    All,
    /// The camera, a light, a material or the scene bounds changed: no pixel.
    None,
    /// Balls around the instances that changed (bounds in both frames): pixels whose
    /// bounded reach stays clear of them. `lights`: where the shadow rays go, `None` under
    /// an environment light (then only unchanged scenes are reused).
    Clear {
        changed: Vec<(Vec3, f32)>,
        lights: Option<LightReach>,
    },
}

/// Where the shadow rays of a scene's lights go: to a ball around every light with a
/// position (`None` when there is none), and towards each directional light (unit
/// directions to the light).
#[derive(Clone, Debug, PartialEq)]
pub struct LightReach {
    pub local: Option<(Vec3, f32)>,
    pub toward: Vec<Vec3>,
}

impl Validity {
    /// From the animation: frames `past` and `current` of one builder.
    pub fn between(past: &FrameScene, current: &FrameScene) -> Validity {
        let d = FrameDelta::between(past, current);
        if d.camera_changed() || d.lights_changed() || d.materials_changed() || d.bounds_changed() {
            return Validity::None;
        }
        if d.is_static() {
            return Validity::All;
        }
        // Past frame's bounds, then current's: the delta's regions.
        let changed = d.changed_bounds().iter().filter_map(ball).collect();
        Validity::Clear {
            changed,
            lights: light_reach(current),
        }
    }

    /// Whether any pixel at all may pool the past frame's light (false for
    /// [`Validity::None`], and for [`Validity::Clear`] under an environment light).
    pub fn may_allow(&self) -> bool {
        match self {
            Validity::All => true,
            Validity::None => false,
            Validity::Clear { lights, .. } => lights.is_some(),
        }
    }

    /// Whether pixels may pool the past frame's light wherever their paths stay clear of
    /// the changes, as far as the animation tells: [`Validity::may_allow`] without a
    /// directional light. Under a sun a pixel pools only where its paths stay inside the
    /// scene (a ray that leaves it makes the reach unbounded): in a room, not on an open
    /// ground whose glossy layer sends rays to the sky; the animation does not say which,
    /// so `spacetime-dept` lets its path probe decide then.
    pub fn may_allow_unprobed(&self) -> bool {
        match self {
            Validity::Clear {
                lights: Some(l), ..
            } => l.toward.is_empty(),
            v => v.may_allow(),
        }
    }

    /// Pixel with `reach` may pool the past frame's light.
    pub fn allows(&self, reach: &Reach) -> bool {
        match self {
            Validity::All => true,
            Validity::None => false,
            Validity::Clear { changed, lights } => {
                let (Reach::Bounded { origins, vertices }, Some(lights)) = (reach, lights) else {
                    return false;
                };
                let (Some((co, ro)), Some((cv, rv))) = (ball(origins), ball(vertices)) else {
                    return false;
                };
                changed.iter().all(|&(c, r)| {
                    segment_distance(c, co, cv) > r + ro.max(rv)
                        && lights
                            .local
                            .is_none_or(|(cl, rl)| segment_distance(c, cv, cl) > r + rv.max(rl))
                        && lights
                            .toward
                            .iter()
                            .all(|&d| half_line_distance(c, cv, d) > r + rv)
                })
            }
        }
    }
}

/// Where the shadow rays of `scene`'s lights go; `None` under an environment light.
fn light_reach(scene: &FrameScene) -> Option<LightReach> {
    let mut b = Bounds3::EMPTY;
    let mut toward = Vec::new();
    for l in scene.lights.iter() {
        match l {
            Light::Point { p, .. } | Light::Spot { p, .. } => b.grow(*p),
            Light::Triangle { p0, e1, e2, .. } => {
                b.grow(*p0);
                b.grow(*p0 + *e1);
                b.grow(*p0 + *e2);
            }
            // Its light samples leave towards −dir ([`Light::sample_li`]).
            Light::Directional { dir, .. } => toward.push(-dir.normalize_or_zero()),
            Light::Environment { .. } => return None,
        }
    }
    Some(LightReach {
        local: ball(&b),
        toward,
    })
}

/// Distance from `p` to the half-line from `a` along the unit direction `d`.
fn half_line_distance(p: Vec3, a: Vec3, d: Vec3) -> f32 {
    let t = (p - a).dot(d).max(0.0);
    (a + d * t - p).length()
}

/// The combined frame: per pixel, the current frame's elements' term plus its per-pixel
/// light pooled (by sample count) with that of every past record whose [`Validity`]
/// allows the pixel. Returns `[direct, indirect]` per pixel, the variance of the current
/// frame's own mean (an upper bound for the pooled one) and, per pixel, the samples of
/// light pooled.
pub fn combine(
    current: &EyeRecord,
    past: &[(&EyeRecord, Validity)],
) -> (Vec<[Rgb; 2]>, Vec<Rgb>, Vec<u32>) {
    let n = current.direct.len();
    let mut out = Vec::with_capacity(n);
    let mut var = Vec::with_capacity(n);
    let mut pooled = Vec::with_capacity(n);
    let inv = 1.0 / current.spp.max(1) as f32;
    for i in 0..n {
        let (mut d, mut p, mut m) = (current.direct[i], current.path[i], current.spp);
        for (rec, v) in past {
            if rec.direct.len() == n && v.allows(&current.reach[i].union(&rec.reach[i])) {
                d += rec.direct[i];
                p += rec.path[i];
                m += rec.spp;
            }
        }
        let k = 1.0 / m.max(1) as f32;
        out.push([d * k, p * k + current.elements[i] * inv]);
        let mean = (current.direct[i] + current.path[i] + current.elements[i]) * inv;
        let v = (current.sq[i] * inv - mean * mean).max(Rgb::ZERO);
        var.push(v * (1.0 / (current.spp.max(2) - 1) as f32));
        pooled.push(m);
    }
    (out, var, pooled)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn bounded(o: Vec3, v: &[Vec3]) -> Reach {
        let mut r = Reach::default();
        r.origin(o);
        for p in v {
            r.vertex(*p);
        }
        r
    }

    #[test]
    fn a_change_away_from_the_paths_keeps_the_pixel_and_one_on_them_refuses_it() {
        // Camera at the origin, a floor point at (0, −1, −5), a lamp at (0, 3, −5).
        let reach = bounded(Vec3::ZERO, &[Vec3::new(0.0, -1.0, -5.0)]);
        let lights = Some(LightReach {
            local: Some((Vec3::new(0.0, 3.0, -5.0), 0.1)),
            toward: vec![],
        });
        let far = Validity::Clear {
            changed: vec![(Vec3::new(5.0, -1.0, -5.0), 0.5)],
            lights: lights.clone(),
        };
        assert!(far.allows(&reach));
        // On the shadow ray (floor → lamp) and on the camera ray.
        for c in [Vec3::new(0.2, 1.0, -5.0), Vec3::new(0.0, -0.5, -2.5)] {
            let v = Validity::Clear {
                changed: vec![(c, 0.3)],
                lights: lights.clone(),
            };
            assert!(!v.allows(&reach), "{c}");
        }
        assert!(!far.allows(&Reach::Unbounded));
        assert!(Validity::All.allows(&Reach::Unbounded));
        assert!(!Validity::None.allows(&reach));
        // Under a sky, no pixel of a changed scene.
        let sky = Validity::Clear {
            changed: vec![(Vec3::new(5.0, -1.0, -5.0), 0.5)],
            lights: None,
        };
        assert!(!sky.may_allow() && !sky.allows(&reach));
    }

    #[test]
    fn a_sun_refuses_a_pixel_only_for_a_change_on_its_shadow_rays() {
        // The floor point (0, −1, −5) seen from the origin, a sun straight above and
        // tilted towards +x: its shadow rays leave along (1, 2, 0) / √5.
        let reach = bounded(Vec3::ZERO, &[Vec3::new(0.0, -1.0, -5.0)]);
        let d = Vec3::new(1.0, 2.0, 0.0).normalize();
        let sun = |c: Vec3| Validity::Clear {
            changed: vec![(c, 0.3)],
            lights: Some(LightReach {
                local: None,
                toward: vec![d],
            }),
        };
        // High up on the shadow ray (far beyond any light box): refused.
        assert!(!sun(Vec3::new(0.0, -1.0, -5.0) + d * 50.0).allows(&reach));
        // The same height straight above, off the tilted ray; below the floor point, on
        // the ray's backward extension; beside it: kept.
        for c in [
            Vec3::new(0.0, 99.0, -5.0),
            Vec3::new(-1.0, -3.0, -5.0),
            Vec3::new(3.0, -1.0, -5.0),
        ] {
            assert!(sun(c).allows(&reach), "{c}");
            // Some pixels may pool; whether many do, the path probe decides.
            assert!(sun(c).may_allow() && !sun(c).may_allow_unprobed());
        }
    }

    #[test]
    fn half_line_distance_is_euclidean() {
        let (a, d) = (Vec3::ZERO, Vec3::X);
        assert_eq!(half_line_distance(Vec3::new(5.0, 2.0, 0.0), a, d), 2.0);
        assert_eq!(half_line_distance(Vec3::new(-3.0, 4.0, 0.0), a, d), 5.0);
    }

    #[test]
    fn segment_distance_is_euclidean() {
        let (a, b) = (Vec3::ZERO, Vec3::new(2.0, 0.0, 0.0));
        assert_eq!(segment_distance(Vec3::new(1.0, 1.0, 0.0), a, b), 1.0);
        assert_eq!(segment_distance(Vec3::new(-3.0, 4.0, 0.0), a, b), 5.0);
        assert_eq!(segment_distance(Vec3::new(2.0, 0.0, 0.0), a, a), 2.0);
    }
}
