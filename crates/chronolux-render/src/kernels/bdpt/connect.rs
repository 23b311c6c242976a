//! Connection strategies (s, t) and their multiple-importance weights (Veach 1997 §10.2,
//! pbrt-v4 `ConnectBDPT` / `MISWeight`).

use super::vertex::{Vertex, VertexKind, g, light_emission_bary};
use super::{BdptSettings, MisHeuristic};
use chronolux_core::bsdf::TransportMode;
use chronolux_core::color::Rgb;
use chronolux_core::geometry::spawn_ray_to;
use chronolux_core::math::Vec2;
use chronolux_core::sampling::sampler::PixelSampler;
use chronolux_core::scene::frame::FrameScene;
use chronolux_core::stats::Stats;

/// The MIS-weighted contribution of one strategy.
#[derive(Clone, Copy, Debug)]
pub struct Contribution {
    /// Weighted contribution to the pixel measurement.
    pub l: Rgb,
    /// For t = 1 (light tracing): the raster position to splat `l` to, with the image
    /// normalisation of [`chronolux_core::camera::Camera::we`] (divide the sum of splats by
    /// the light subpaths per pixel). `None`: `l` belongs to the camera sample's own pixel.
    pub raster: Option<Vec2>,
}

/// Connects the first `s` vertices of `light` with the first `t` of `camera` (t ≥ 1) and
/// returns the MIS-weighted contribution, `None` when it is zero.
///
/// ## Estimator contract
/// - `camera` comes from [`super::generate_camera_subpath`] and `light` from
///   [`super::generate_light_subpath`] on the same `scene`, with the same `settings`.
/// - s = 0: the camera subpath's vertex t−1 is an emitter (or the escaped ray's point at
///   infinity); s = 1: a fresh light sample at camera vertex t−1 (draws 3 numbers from
///   `sampler`, always, so the stream stays aligned); t = 1: light vertex s−1 is connected
///   to the pinhole and splatted (see [`Contribution::raster`]); otherwise a deterministic
///   connection with visibility. (s, t) = (1, 1) and t = 0 are not strategies here.
/// - The sum over all (s, t) with s + t − 1 ≤ max_depth (segments) is an unbiased
///   estimate of the pixel measurement (MIS weights sum to 1 over the strategies able to
///   produce a path; Russian roulette only rescales subpath throughputs) — without the
///   paths E S⁺ X S⁺ L when [`BdptSettings::caustics`] is on (s = 0 drops them, the
///   caustic photon estimate [`super::caustic`] adds them).
#[allow(clippy::too_many_arguments)] // reason: the two subpaths, the strategy and the streams
pub fn connect(
    scene: &FrameScene,
    settings: &BdptSettings,
    light: &[Vertex],
    camera: &[Vertex],
    s: usize,
    t: usize,
    sampler: &mut PixelSampler,
    stats: &mut Stats,
) -> Option<Contribution> {
    connect_with(
        scene,
        settings,
        light,
        camera,
        s,
        t,
        sampler,
        stats,
        &mut |r| !scene.occluded(r),
    )
    .map(|c| c.contribution)
}

/// Advances `sampler` exactly as [`connect`] / [`connect_with`] would for strategy
/// (s, t) on subpaths of these lengths, without evaluating it: only s = 1 with t ≥ 2
/// draws (its 3 numbers, whenever it gets past the checks that precede them). A
/// technique that takes a strategy's value from elsewhere (a sample reused from another
/// frame) calls this in its place, so the strategies it does evaluate after it draw the
/// numbers they would have drawn in a full evaluation.
pub fn skip_connect(
    settings: &BdptSettings,
    light_len: usize,
    camera: &[Vertex],
    s: usize,
    t: usize,
    sampler: &mut PixelSampler,
) {
    if s == 1 && t > 1 && has_strategy(settings, light_len, camera, s, t) {
        sampler.next_1d();
        sampler.next_2d();
    }
}

/// Whether subpaths of these lengths have strategy (s, t) at all: the checks
/// [`connect_with`] makes before it draws any number (shared with [`skip_connect`], so
/// the two draw alike).
fn has_strategy(
    settings: &BdptSettings,
    light_len: usize,
    camera: &[Vertex],
    s: usize,
    t: usize,
) -> bool {
    if t == 0 || t > camera.len() || s > light_len.max(usize::from(settings.path_strategies)) {
        return false;
    }
    // A camera subpath ending at infinity only serves s = 0.
    !(t > 1 && s != 0 && camera[t - 1].kind == VertexKind::Light)
}

/// A strategy's contribution as [`connect_with`] reports it.
#[derive(Clone, Debug)]
pub struct Connection {
    pub contribution: Contribution,
    /// The contribution before its MIS weight, and the weight (`contribution.l` is their
    /// product).
    pub unweighted: Rgb,
    pub weight: f32,
    /// The vertex sampled for the connection (s = 1: the light point; t = 1: the camera
    /// point), for evaluating another weight of the same path ([`mis_weight`]).
    pub sampled: Option<Vertex>,
    /// The light-side endpoint of the connection (light vertex s − 1, or the light point
    /// sampled for s = 1); `None` for s = 0.
    pub light_point: Option<chronolux_core::math::Vec3>,
}

/// [`connect`] with the visibility test of the connection's shadow ray left to `visible`
/// (called at most once, only when the unoccluded contribution is non-zero; the
/// contribution is returned iff it answers true). A technique answering the shadow ray for
/// several frames at once (sample reuse) passes a closure that records the answer.
#[allow(clippy::too_many_arguments)] // reason: connect's arguments and the visibility oracle
pub fn connect_with(
    scene: &FrameScene,
    settings: &BdptSettings,
    light: &[Vertex],
    camera: &[Vertex],
    s: usize,
    t: usize,
    sampler: &mut PixelSampler,
    stats: &mut Stats,
    visible: &mut dyn FnMut(&chronolux_core::geometry::Ray) -> bool,
) -> Option<Connection> {
    if !has_strategy(settings, light.len(), camera, s, t) {
        return None;
    }
    let mut sampled: Option<Vertex> = None;
    let mut raster = None;
    let l = if s == 0 {
        let pt = &camera[t - 1];
        if t < 2 || !pt.is_light(scene) {
            return None;
        }
        // E S⁺ X S⁺ L: left to the caustic photon estimate (its only strategy is this one).
        if settings.caustics() && super::caustic::is_caustic_path(camera, t) {
            return None;
        }
        pt.le(scene, &camera[t - 2]) * pt.beta
    } else if t == 1 {
        let qs = &light[s - 1];
        if !qs.is_connectible(scene) {
            return None;
        }
        let cs = scene.camera.sample_wi(qs.p)?;
        let v = Vertex::camera(cs.p, Rgb::splat(cs.we / cs.pdf), false);
        let mut l = qs.beta * qs.f(&v, TransportMode::Importance) * v.beta;
        if qs.is_on_surface() {
            l *= cs.wi.dot(qs.ns).abs();
        }
        if l == Rgb::ZERO {
            return None;
        }
        stats.shadow_rays += 1;
        if !visible(&spawn_ray_to(qs.p, qs.ng, cs.p, v.ng)) {
            return None;
        }
        raster = Some(cs.raster);
        sampled = Some(v);
        l
    } else if s == 1 {
        let u_light = sampler.next_1d();
        let u_lp = sampler.next_2d();
        let pt = &camera[t - 1];
        if !pt.is_connectible(scene) {
            return None;
        }
        let (li, pmf, _) = scene.light_sampler.sample(u_light)?;
        let light_ref = &scene.lights[li];
        let ls = light_ref.sample_li(pt.p, u_lp, scene.scene_radius)?;
        if ls.pdf <= 0.0 || pmf <= 0.0 {
            return None;
        }
        let le = light_emission_bary(scene, light_ref, ls.li, ls.bary);
        let mut v = Vertex::light(scene, Some(li), ls.p, ls.n, le / (ls.pdf * pmf), 0.0);
        v.pdf_fwd = v.pdf_light_origin(scene, pt);
        let mut l = pt.beta * pt.f(&v, TransportMode::Radiance) * v.beta;
        if pt.is_on_surface() {
            l *= ls.wi.dot(pt.ns).abs();
        }
        if l == Rgb::ZERO {
            return None;
        }
        stats.shadow_rays += 1;
        if !visible(&spawn_ray_to(pt.p, pt.ng, ls.p, ls.n)) {
            return None;
        }
        sampled = Some(v);
        l
    } else {
        let (qs, pt) = (&light[s - 1], &camera[t - 1]);
        if !qs.is_connectible(scene) || !pt.is_connectible(scene) {
            return None;
        }
        let l = qs.beta
            * qs.f(pt, TransportMode::Importance)
            * pt.f(qs, TransportMode::Radiance)
            * pt.beta;
        if l == Rgb::ZERO {
            return None;
        }
        let gt = g(qs, pt, stats, visible);
        if gt == 0.0 {
            return None;
        }
        l * gt
    };
    if l == Rgb::ZERO {
        return None;
    }
    let w = mis_weight(scene, settings, light, camera, sampled.as_ref(), s, t);
    let light_point = match s {
        0 => None,
        1 if t > 1 => sampled.as_ref().map(|v| v.p),
        _ => Some(light[s - 1].p),
    };
    Some(Connection {
        contribution: Contribution { l: l * w, raster },
        unweighted: l,
        weight: w,
        sampled,
        light_point,
    })
}

/// MIS weight of strategy (s, t) for the path it built, by the ratio trick over reversed
/// densities (pbrt-v4 `MISWeight`): `1 / Σ_i (p_i/p_s)^β`, β = 1 (balance) or 2 (power),
/// skipping strategies that would connect through a delta vertex or start at a delta light.
/// `sampled` replaces light vertex 0 (s = 1) or camera vertex 0 (t = 1).
pub fn mis_weight(
    scene: &FrameScene,
    settings: &BdptSettings,
    light: &[Vertex],
    camera: &[Vertex],
    sampled: Option<&Vertex>,
    s: usize,
    t: usize,
) -> f32 {
    if s + t == 2 {
        return 1.0;
    }
    let mut sum = 0.0f32;
    other_strategies(scene, settings, light, camera, sampled, s, t, |_, r| {
        sum += heuristic(settings, r)
    });
    1.0 / (1.0 + sum)
}

/// The MIS heuristic applied to a density ratio.
fn heuristic(settings: &BdptSettings, r: f32) -> f32 {
    match settings.mis {
        MisHeuristic::Balance => r,
        MisHeuristic::Power => r * r,
    }
}

/// Strategy (s, t ≥ 2)'s MIS weight, 1 / Σ h(p_{s′} / p_s) over the path's strategies,
/// split by how each ratio depends on x0 (the camera) and on the view direction at x1, so
/// that the weight of the same path seen by another camera (same x1 and subpaths) follows
/// from three densities ([`ViewSplit::reweight`]). Of the densities in the ratios only
/// three involve x0: x1's density from the camera p_cam(x1) (a factor 1 / p_cam in light
/// tracing's ratio, t′ = 1: every other strategy samples x1 from the camera too), and the
/// densities at x1 that depend on the direction to x0: for t ≥ 3 the continuation's
/// p(x1 → x2) (a factor 1 / p in the ratios of t′ = 1 and t′ = 2), for t = 2 the reverse
/// density at the light vertex connected to, p(x0, x1 → y) (a factor p in every ratio of
/// the light side). `None`: t < 2.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ViewSplit {
    /// h of the ratios that do not depend on x0, plus 1 (the strategy itself).
    pub rest: f32,
    /// h(ratio) of light tracing (t′ = 1), 0 when the path has none (light tracing off).
    pub lt: f32,
    /// t ≥ 3: h(ratio) of t′ = 2.
    pub cam2: f32,
    /// t = 2: Σ h(ratio) over the light side's strategies.
    pub light: f32,
    /// The heuristic's exponent β (h(k r) = k^β h(r)).
    pub beta: i32,
}

impl ViewSplit {
    /// The factor turning the weight computed with x0 into the weight with another camera
    /// x0′: `rho` = p_cam(x1) / p′_cam(x1), `cont` = p(x1 → x2 | x0) / p(x1 → x2 | x0′)
    /// (t ≥ 3), `light` = p(x0′, x1 → y) / p(x0, x1 → y) (t = 2). A factor that is not
    /// finite and positive (a zero density) leaves that term as it was.
    pub fn reweight(&self, rho: f32, cont: f32, light: f32) -> f32 {
        let k = |x: f32| {
            let x = if x.is_finite() && x > 0.0 { x } else { 1.0 };
            if self.beta == 2 { x * x } else { x }
        };
        let before = self.rest + self.lt + self.cam2 + self.light;
        let after =
            self.rest + k(rho) * k(cont) * self.lt + k(cont) * self.cam2 + k(light) * self.light;
        let w = before / after;
        if w.is_finite() { w } else { 1.0 }
    }
}

/// [`ViewSplit`] of strategy (s, t) of these subpaths (`mis_weight`'s arguments).
#[allow(clippy::too_many_arguments)] // reason: mis_weight's arguments
pub fn view_split(
    scene: &FrameScene,
    settings: &BdptSettings,
    light: &[Vertex],
    camera: &[Vertex],
    sampled: Option<&Vertex>,
    s: usize,
    t: usize,
) -> Option<ViewSplit> {
    if t < 2 {
        return None;
    }
    let beta = match settings.mis {
        MisHeuristic::Balance => 1,
        MisHeuristic::Power => 2,
    };
    let mut v = ViewSplit {
        rest: 1.0,
        lt: 0.0,
        cam2: 0.0,
        light: 0.0,
        beta,
    };
    if s + t > 2 {
        other_strategies(scene, settings, light, camera, sampled, s, t, |s2, r| {
            let h = heuristic(settings, r);
            if s2 + 1 == s + t {
                v.lt += h;
            } else if t >= 3 && s2 + 2 == s + t {
                v.cam2 += h;
            } else if t == 2 && s2 < s {
                v.light += h;
            } else {
                v.rest += h;
            }
        });
    }
    Some(v)
}

/// The strategies able to produce the path built by strategy (s, t), as (s′, p_{s′} / p_s):
/// each strategy's density for this path relative to (s, t)'s own (pbrt-v4's ratio trick,
/// as in [`mis_weight`], with the same rules for delta vertices, delta lights and light
/// tracing), (s, t) itself included with ratio 1. Written into `out` (cleared). Used to
/// estimate, from BDPT's samples, the variance another set of strategies would have
/// (stbpt's choice between all strategies and the path strategies).
#[allow(clippy::too_many_arguments)] // reason: mis_weight's arguments and the output
pub fn strategy_ratios(
    scene: &FrameScene,
    settings: &BdptSettings,
    light: &[Vertex],
    camera: &[Vertex],
    sampled: Option<&Vertex>,
    s: usize,
    t: usize,
    out: &mut Vec<(usize, f32)>,
) {
    out.clear();
    out.push((s, 1.0));
    if s + t == 2 {
        return;
    }
    other_strategies(scene, settings, light, camera, sampled, s, t, |s2, r| {
        out.push((s2, r))
    });
}

/// The ratio walk shared by [`mis_weight`] and [`strategy_ratios`]: calls `visit(s′,
/// p_{s′} / p_s)` for every strategy other than (s, t) that can make the path (s, t)
/// built, camera side first (s′ = s + t − i for camera vertex i), then the light side
/// (s′ = i), skipping connections through delta vertices, delta lights, light tracing
/// when it is off and, with `path_strategies`, every strategy beyond s′ ≤ 1. Needs
/// s + t > 2.
#[allow(clippy::too_many_arguments)] // reason: mis_weight's arguments and the visitor
fn other_strategies(
    scene: &FrameScene,
    settings: &BdptSettings,
    light: &[Vertex],
    camera: &[Vertex],
    sampled: Option<&Vertex>,
    s: usize,
    t: usize,
    mut visit: impl FnMut(usize, f32),
) {
    let lv = |i: usize| -> &Vertex {
        match sampled {
            Some(v) if s == 1 && i == 0 => v,
            _ => &light[i],
        }
    };
    let cv = |i: usize| -> &Vertex {
        match sampled {
            Some(v) if t == 1 && i == 0 => v,
            _ => &camera[i],
        }
    };
    let remap = |f: f32| if f != 0.0 { f } else { 1.0 };
    let pt = cv(t - 1);
    let qs = (s > 0).then(|| lv(s - 1));
    let pt_minus = (t > 1).then(|| cv(t - 2));
    let qs_minus = (s > 1).then(|| lv(s - 2));
    // Reverse densities of the four vertices next to the connection.
    let pt_rev = match qs {
        Some(q) => q.pdf(scene, qs_minus, pt),
        None => pt.pdf_light_origin(scene, pt_minus.expect("s = 0 needs t ≥ 2")),
    };
    let pt_minus_rev = pt_minus.map(|pm| match qs {
        Some(q) => pt.pdf(scene, Some(q), pm),
        None => pt.pdf_light(scene, pm),
    });
    let qs_rev = qs.map(|q| pt.pdf(scene, pt_minus, q));
    let qs_minus_rev = qs_minus.map(|qm| qs.unwrap().pdf(scene, Some(pt), qm));

    let mut ri = 1.0f32;
    for i in (1..t).rev() {
        let v = cv(i);
        let rev = if i == t - 1 {
            pt_rev
        } else if i + 2 == t {
            pt_minus_rev.unwrap()
        } else {
            v.pdf_rev
        };
        ri *= remap(rev) / remap(v.pdf_fwd);
        let delta_i = i != t - 1 && v.delta;
        // i = 1 is the light-tracing strategy (one camera vertex); this term is strategy
        // (s + t − i, i), absent from the path strategies when it has a light subpath.
        let exists = (i > 1 || settings.light_tracing)
            && (!settings.path_strategies || (i > 1 && s + t - i <= 1));
        if !delta_i && !cv(i - 1).delta && exists {
            visit(s + t - i, ri);
        }
    }
    ri = 1.0;
    for i in (0..s).rev() {
        let v = lv(i);
        let rev = if i == s - 1 {
            qs_rev.unwrap()
        } else if i + 2 == s {
            qs_minus_rev.unwrap()
        } else {
            v.pdf_rev
        };
        ri *= remap(rev) / remap(v.pdf_fwd);
        let delta_i = i != s - 1 && v.delta;
        let delta_light = if i > 0 {
            lv(i - 1).delta
        } else {
            lv(0).is_delta_light(scene)
        };
        if !delta_i && !delta_light {
            visit(i, ri);
        }
    }
}
