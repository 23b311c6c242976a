//! Motion blur: the trajectory-splatting kernel (exact lengths, weights, clipping) and, for
//! a quad moving at constant speed, time-sampled path tracing (`--shutter`) and trajectory
//! splatting against the analytic blurred profile (issue 4, item 8).

use chronolux_core::color::Rgb;
use chronolux_core::math::{Vec2, Vec3};
use chronolux_core::sampling::rng::Pcg32;
use chronolux_core::sampling::sampler::PixelSampler;
use chronolux_core::scene::desc::{
    Animation, Channel, ChannelTarget, Interpolation, Material, Primitive, Projection, Trs,
};
use chronolux_core::scene::testing::single_mesh_scene;
use chronolux_render::framework::integrator::Integrator;
use chronolux_render::framework::integrator::instant_of;
use chronolux_render::framework::sequence::SequenceRenderer;
use chronolux_render::framework::shutter::{MotionBlur, shutter_instants};
use chronolux_render::framework::technique::check_shutter;
use chronolux_render::kernels::bdpt::{Bdpt, BdptSettings};
use chronolux_render::kernels::blur::{
    PixelShare, TrajectoryVertex, segment_cells, splat_trajectory,
};
use chronolux_render::kernels::path::{PathSettings, PathTracer};
use std::collections::BTreeMap;

/// Pixels crossed by a segment and the length inside each, in order.
fn cells(a: Vec2, b: Vec2, w: u32, h: u32) -> Vec<((u32, u32), f32)> {
    let len = (b - a).length();
    let mut out = Vec::new();
    segment_cells(a, b, w, h, |x, y, u0, u1| {
        out.push(((x, y), (u1 - u0) * len))
    });
    out
}

/// f32 rounding of parameters of order 1, times lengths of order 10: a few ulps.
const EXACT: f32 = 1e-5;

fn assert_cells(got: &[((u32, u32), f32)], want: &[((u32, u32), f32)]) {
    assert_eq!(got.len(), want.len(), "{got:?} vs {want:?}");
    for (g, w) in got.iter().zip(want) {
        assert_eq!(g.0, w.0, "{got:?} vs {want:?}");
        assert!((g.1 - w.1).abs() <= EXACT, "{got:?} vs {want:?}");
    }
}

#[test]
fn dda_lengths_are_exact_for_axis_aligned_and_diagonal_segments() {
    let v = Vec2::new;
    // Horizontal, both directions: half pixels at the ends.
    let want = [((0, 2), 0.5), ((1, 2), 1.0), ((2, 2), 1.0), ((3, 2), 0.5)];
    assert_cells(&cells(v(0.5, 2.5), v(3.5, 2.5), 8, 8), &want);
    let rev: Vec<_> = want.iter().rev().copied().collect();
    assert_cells(&cells(v(3.5, 2.5), v(0.5, 2.5), 8, 8), &rev);
    // Vertical, starting on a pixel edge.
    assert_cells(
        &cells(v(1.25, 1.0), v(1.25, 3.5), 8, 8),
        &[((1, 1), 1.0), ((1, 2), 1.0), ((1, 3), 0.5)],
    );
    // Going up from a pixel edge: the pixel below the start is not touched.
    assert_cells(
        &cells(v(1.25, 3.0), v(1.25, 1.5), 8, 8),
        &[((1, 2), 1.0), ((1, 1), 0.5)],
    );
    // The diagonal through pixel corners: √2 per pixel, no side pixels.
    let s2 = 2f32.sqrt();
    assert_cells(
        &cells(v(0.0, 0.0), v(3.0, 3.0), 8, 8),
        &[((0, 0), s2), ((1, 1), s2), ((2, 2), s2)],
    );
    assert_cells(
        &cells(v(3.0, 0.0), v(0.0, 3.0), 8, 8),
        &[((2, 0), s2), ((1, 1), s2), ((0, 2), s2)],
    );
    // Slope 1/2 through one corner (2, 1): total √5, shares 1/4, 1/2, 1/4.
    let s5 = 5f32.sqrt();
    assert_cells(
        &cells(v(0.5, 0.25), v(2.5, 1.25), 8, 8),
        &[((0, 0), 0.25 * s5), ((1, 0), 0.5 * s5), ((2, 1), 0.25 * s5)],
    );
    // Zero length: its pixel, length 0.
    assert_cells(&cells(v(2.5, 3.5), v(2.5, 3.5), 8, 8), &[((2, 3), 0.0)]);
}

#[test]
fn dda_matches_dense_sampling_and_clips_at_the_border() {
    // Random segments, many partly outside the 12×9 image, against the pixel of each of
    // N equally spaced points: a pixel's run of points misses at most one spacing at each
    // end, so the lengths agree to 2·|b − a| / N (plus f32 rounding).
    let (w, h) = (12u32, 9u32);
    let mut rng = Pcg32::new(5, 1);
    let n = 20_000;
    for _ in 0..200 {
        let mut p = || Vec2::new(rng.next_f32() * 18.0 - 3.0, rng.next_f32() * 15.0 - 3.0);
        let (a, b) = (p(), p());
        let len = (b - a).length();
        let mut count: BTreeMap<(u32, u32), u32> = BTreeMap::new();
        for i in 0..n {
            let q = a + (b - a) * ((i as f32 + 0.5) / n as f32);
            if q.x >= 0.0 && q.y >= 0.0 && q.x < w as f32 && q.y < h as f32 {
                *count.entry((q.x as u32, q.y as u32)).or_default() += 1;
            }
        }
        let dense: BTreeMap<(u32, u32), f32> = count
            .into_iter()
            .map(|(c, k)| (c, (k as f64 * len as f64 / n as f64) as f32))
            .collect();
        let got = cells(a, b, w, h);
        let mut seen = BTreeMap::new();
        for (c, l) in &got {
            assert!(
                seen.insert(*c, *l).is_none(),
                "pixel {c:?} twice: {a} → {b}"
            );
        }
        let tol = 2.0 * len / n as f32 + EXACT;
        for c in seen.keys().chain(dense.keys()) {
            let (g, d) = (
                seen.get(c).copied().unwrap_or(0.0),
                dense.get(c).copied().unwrap_or(0.0),
            );
            assert!((g - d).abs() <= tol, "{a} → {b} pixel {c:?}: {g} vs {d}");
        }
    }
    // Half outside on the left: the visible half only.
    let got = cells(Vec2::new(-2.0, 0.5), Vec2::new(2.0, 0.5), 4, 4);
    assert_cells(&got, &[((0, 0), 1.0), ((1, 0), 1.0)]);
    // Entirely outside, and along the far edge (pixels are half-open).
    assert!(cells(Vec2::new(-2.0, -1.0), Vec2::new(5.0, -0.1), 4, 4).is_empty());
    assert!(cells(Vec2::new(0.5, 4.0), Vec2::new(3.5, 4.0), 4, 4).is_empty());
    assert!(cells(Vec2::new(f32::NAN, 1.0), Vec2::new(2.0, 1.0), 4, 4).is_empty());
}

fn vert(x: f32, y: f32, t: f32, l: f32) -> TrajectoryVertex {
    TrajectoryVertex {
        raster: Vec2::new(x, y),
        time: t,
        radiance: Rgb::splat(l),
    }
}

fn by_pixel(shares: &[PixelShare]) -> BTreeMap<u32, (f32, f32)> {
    let mut m = BTreeMap::new();
    for s in shares {
        let e = m.entry(s.pixel).or_insert((0.0, 0.0));
        e.0 += s.weight;
        e.1 += s.value.x;
    }
    m
}

#[test]
fn splat_weights_sum_to_one_and_follow_time_and_length() {
    let (w, h) = (16u32, 12u32);
    let mut rng = Pcg32::new(9, 2);
    let mut out = Vec::new();
    for _ in 0..100 {
        // Random on-screen trajectories of 2..6 vertices at increasing times.
        let k = 2 + rng.next_u32() % 5;
        let mut t = 0.0;
        let verts: Vec<_> = (0..k)
            .map(|_| {
                t += rng.next_f32();
                vert(rng.next_f32() * 16.0, rng.next_f32() * 12.0, t, 1.0)
            })
            .collect();
        out.clear();
        let on = splat_trajectory(&verts, w, h, &mut out);
        let sum: f32 = out.iter().map(|s| s.weight).sum();
        // f32 sums of at most ~100 pieces of weights ≤ 1: 1e-5.
        assert!(
            (on - 1.0).abs() < 1e-5 && (sum - 1.0).abs() < 1e-5,
            "{on} {sum}"
        );
        // Constant radiance: value = weight · L.
        assert!(out.iter().all(|s| (s.value.x - s.weight).abs() < 1e-6));
    }
    // Zero length: everything in its pixel, at its radiance.
    out.clear();
    let on = splat_trajectory(
        &[vert(3.5, 2.2, 0.0, 2.0), vert(3.5, 2.2, 1.0, 2.0)],
        w,
        h,
        &mut out,
    );
    assert_eq!(on, 1.0);
    assert_eq!(
        out,
        vec![PixelShare {
            pixel: 2 * w + 3,
            weight: 1.0,
            value: Rgb::splat(2.0)
        }]
    );
    // Constant speed (equal times, equal lengths): weights ∝ length in each pixel.
    out.clear();
    splat_trajectory(
        &[
            vert(0.5, 0.5, 0.0, 1.0),
            vert(2.0, 0.5, 1.0, 1.0),
            vert(3.5, 0.5, 2.0, 1.0),
        ],
        w,
        h,
        &mut out,
    );
    let m = by_pixel(&out);
    for (px, want) in [
        (0u32, 0.5 / 3.0),
        (1, 1.0 / 3.0),
        (2, 1.0 / 3.0),
        (3, 0.5 / 3.0),
    ] {
        assert!((m[&px].0 - want).abs() < EXACT, "{m:?}");
    }
    // A point that stops: the second segment has no length but half the time.
    out.clear();
    splat_trajectory(
        &[
            vert(0.5, 0.5, 0.0, 1.0),
            vert(1.5, 0.5, 1.0, 1.0),
            vert(1.5, 0.5, 2.0, 1.0),
        ],
        w,
        h,
        &mut out,
    );
    let m = by_pixel(&out);
    assert!(
        (m[&0].0 - 0.25).abs() < EXACT && (m[&1].0 - 0.75).abs() < EXACT,
        "{m:?}"
    );
    // Radiance linear in time from 0 to 2 across two pixels: pixel 0 gets ∫₀^½ 2t dt = ¼,
    // pixel 1 gets ∫_½^1 2t dt = ¾.
    out.clear();
    splat_trajectory(
        &[vert(0.0, 0.5, 0.0, 0.0), vert(2.0, 0.5, 1.0, 2.0)],
        w,
        h,
        &mut out,
    );
    let m = by_pixel(&out);
    assert!(
        (m[&0].1 - 0.25).abs() < EXACT && (m[&1].1 - 0.75).abs() < EXACT,
        "{m:?}"
    );
    // Leaving the image: the off-screen time is dropped, not renormalised.
    out.clear();
    let on = splat_trajectory(
        &[vert(14.0, 0.5, 0.0, 1.0), vert(18.0, 0.5, 1.0, 1.0)],
        w,
        h,
        &mut out,
    );
    assert!((on - 0.5).abs() < EXACT, "{on}");
    let m = by_pixel(&out);
    assert!((m[&14].0 - 0.25).abs() < EXACT && (m[&15].0 - 0.25).abs() < EXACT);
}

// ---------------------------------------------------------------------------------------
// A quad moving at constant speed in front of a black background (item 8).

/// Image: 64×4 pixels, orthographic camera at the origin looking down −Z with half-height
/// 0.5, so x ∈ [−8, 8] maps to raster [0, 64] (4 pixels per unit) and the quad, 2 wide and
/// 4 tall, fills every row. Its centre moves from x = −4 at t = 0 to 4 at t = 2: 16 pixels
/// per second; at 1 fps, frame 1 is centred.
const IW: u32 = 64;
const IH: u32 = 4;
const FPS: f32 = 1.0;
const SHUTTER: f32 = 0.75;

fn centre(t: f32) -> f32 {
    -4.0 + 4.0 * t
}

fn raster_x(x: f32) -> f32 {
    4.0 * x + 32.0
}

fn moving_quad() -> chronolux_core::scene::desc::SceneDesc {
    moving_quad_seen(true)
}

/// The moving quad seen through the orthographic camera, or through a perspective one
/// with tan(yfov/2) = 0.5: on the quad's plane z = −1 both map x ∈ [−8, 8] to raster
/// [0, 64] linearly, so the analytic profile is the same.
pub(crate) fn moving_quad_seen(orthographic: bool) -> chronolux_core::scene::desc::SceneDesc {
    let quad = Primitive {
        positions: vec![
            Vec3::new(-1.0, -2.0, -1.0),
            Vec3::new(1.0, -2.0, -1.0),
            Vec3::new(1.0, 2.0, -1.0),
            Vec3::new(-1.0, 2.0, -1.0),
        ],
        indices: vec![[0, 1, 2], [0, 2, 3]],
        ..Default::default()
    };
    let mut m = Material::diffuse("emitter", Rgb::ZERO);
    m.emissive = Rgb::ONE;
    let mut d = single_mesh_scene("moving quad", quad, m, Trs::default(), 1.0);
    d.cameras[0].projection = if orthographic {
        Projection::Orthographic {
            xmag: 8.0,
            ymag: 0.5,
        }
    } else {
        Projection::Perspective {
            yfov: 2.0 * 0.5f32.atan(),
            aspect: None,
            znear: 0.01,
        }
    };
    d.animations.push(Animation {
        name: "slide".into(),
        channels: vec![Channel {
            node: chronolux_core::scene::desc::NodeId(0),
            target: ChannelTarget::Translation,
            interpolation: Interpolation::Linear,
            times: vec![0.0, 2.0],
            values: vec![centre(0.0), 0.0, 0.0, centre(2.0), 0.0, 0.0],
            components: 3,
        }],
    });
    d
}

/// Length of pixel column [x, x+1] to the left of u, and its antiderivative in u.
fn g(x: f64, u: f64) -> f64 {
    (u - x).clamp(0.0, 1.0)
}
fn big_g(x: f64, u: f64) -> f64 {
    let s = u - x;
    if s <= 0.0 {
        0.0
    } else if s < 1.0 {
        0.5 * s * s
    } else {
        s - 0.5
    }
}

/// Edges of the quad in raster x at time t.
fn edges(t: f64) -> (f64, f64) {
    let c = centre(t as f32) as f64;
    (
        raster_x((c - 1.0) as f32) as f64,
        raster_x((c + 1.0) as f32) as f64,
    )
}

/// Analytic blurred value of column x for frame 1: the pixel's covered fraction averaged
/// over the shutter, ∫ (g(b(t)) − g(a(t))) dt / Δ with the edges moving by m pixels.
fn blurred(x: f64) -> f64 {
    let t0 = 1.0 - 0.5 * SHUTTER as f64 / FPS as f64;
    let (a0, b0) = edges(t0);
    let m = 16.0 * SHUTTER as f64 / FPS as f64;
    ((big_g(x, b0 + m) - big_g(x, b0)) - (big_g(x, a0 + m) - big_g(x, a0))) / m
}

/// The same average by the midpoint rule at the renderer's instants.
fn discretised(x: f64, n: u32) -> f64 {
    let ts = shutter_instants(1, FPS, SHUTTER, n);
    ts.iter()
        .map(|&t| {
            let (a, b) = edges(t as f64);
            g(x, b) - g(x, a)
        })
        .sum::<f64>()
        / n as f64
}

#[test]
fn time_samples_are_stratified_over_the_instants() {
    // spp = 64, T = 16: every instant gets exactly 4 samples of every pixel.
    for (px, py) in [(0, 0), (17, 3), (63, 1)] {
        let mut s = PixelSampler::new(0, 1, px, py);
        let mut count = [0u32; 16];
        for i in 0..64 {
            s.start_sample(i);
            s.next_2d();
            count[instant_of(s.next_1d(), 16)] += 1;
        }
        assert_eq!(count, [4; 16], "pixel ({px}, {py})");
    }
    assert!(check_shutter(0.0).is_ok() && check_shutter(1.0).is_ok());
    assert!(check_shutter(-0.1).is_err() && check_shutter(1.5).is_err());
    assert!(check_shutter(f32::NAN).is_err());
}

#[test]
fn shutter_path_tracing_matches_the_analytic_blur_of_a_moving_quad() {
    let spp = 256;
    let tracer = PathTracer::new(PathSettings {
        common: chronolux_render::registry::CommonSettings {
            spp,
            max_depth: Some(1),
            ..PathSettings::default().common
        },
        ..Default::default()
    });
    let mut source = crate::source(moving_quad(), IW, IH, FPS, vec![1]);
    let mut mb = MotionBlur::<PathTracer>::new(tracer.clone(), SHUTTER);
    let t = mb.instants() as usize;
    assert_eq!(t, 16);
    let img = mb.render_frame(&mut source, 1, &|_| {});
    assert_eq!(img.invalid_samples, 0);
    // Discretisation error of the midpoint rule at the test's parameters (each pixel's
    // coverage rises and falls once: TV ≤ 2, bound TV / (2T) from the module doc).
    let disc_err = (0..IW)
        .map(|x| (discretised(x as f64, t as u32) - blurred(x as f64)).abs())
        .fold(0.0, f64::max);
    assert!(disc_err <= 2.0 / (2.0 * t as f64), "{disc_err}");
    let mut worst = 0.0f64;
    for y in 0..IH {
        for x in 0..IW {
            let i = (y * IW + x) as usize;
            let v = img.pixels[i].x as f64;
            let sigma = (img.variance[i].x as f64).sqrt();
            // Against the quadrature the renderer converges to: 5 estimated standard
            // errors (an over-estimate: Sobol samples are stratified), plus f32 rounding.
            let want = discretised(x as f64, t as u32);
            assert!(
                (v - want).abs() <= 5.0 * sigma + 1e-5,
                "pixel ({x}, {y}): {v} vs {want} ± {sigma}"
            );
            // Against the continuous blur: the same, plus the discretisation error.
            let exact = blurred(x as f64);
            assert!((v - exact).abs() <= 5.0 * sigma + disc_err + 1e-5);
            worst = worst.max((v - exact).abs());
        }
    }
    eprintln!("moving quad: max |path − analytic| = {worst:.4}, discretisation {disc_err:.5}");
    // The profile is really blurred: 12 px ramps, peak 8/12 (the quad is narrower than
    // its motion), while the unblurred frame is a sharp 8-pixel box.
    assert!((blurred(32.0) - 8.0 / 12.0).abs() < 1e-9);
    let sharp = tracer.render(&source.frame(1), 1, &|_| {});
    assert_eq!(sharp.pixels[32].x, 1.0);
    // Closed shutter: exactly the frame without motion blur.
    let mut closed = MotionBlur::<PathTracer>::new(tracer, 0.0);
    let c = closed.render_frame(&mut source, 1, &|_| {});
    assert_eq!(c.pixels, sharp.pixels);
}

#[test]
fn trajectory_splats_of_a_moving_quad_match_the_analytic_blur() {
    // Points across the quad's width (N per row, midpoints), each carrying its share
    // 8/N pixels of the quad's 8-pixel width at radiance 1, splatted along the raster
    // trajectory through the camera at shutter open, middle and close.
    let mut source = crate::source(moving_quad(), IW, IH, FPS, vec![1]);
    let cam = source.frame(1).camera.clone();
    let times = shutter_instants(1, FPS, SHUTTER, 1);
    let (open, close) = (
        times[0] - 0.5 * SHUTTER / FPS,
        times[0] + 0.5 * SHUTTER / FPS,
    );
    let instants = [open, 0.5 * (open + close), close];
    let n = 512;
    let mut img = vec![0.0f64; (IW * IH) as usize];
    let mut out = Vec::new();
    for row in 0..IH {
        let y_world = 0.5 - (row as f32 + 0.5) / IH as f32;
        for i in 0..n {
            let u = -1.0 + 2.0 * (i as f32 + 0.5) / n as f32;
            let verts: Vec<_> = instants
                .iter()
                .map(|&t| TrajectoryVertex {
                    raster: cam
                        .project(Vec3::new(centre(t) + u, y_world, -1.0))
                        .expect("the quad stays in view"),
                    time: t,
                    radiance: Rgb::ONE,
                })
                .collect();
            out.clear();
            let on = splat_trajectory(&verts, IW, IH, &mut out);
            assert!((on - 1.0).abs() < 1e-5);
            for s in &out {
                assert_eq!(s.pixel / IW, row);
                img[s.pixel as usize] += s.value.x as f64 * 8.0 / n as f64;
            }
        }
    }
    // Midpoint rule over the quad's width with spacing δ = 8/N px of a per-point weight
    // whose total variation in its start position is 2/m (m = 12 px of motion): error
    // ≤ δ·(2/m)/2 = δ/m; plus f32 weights (1e-5 relative over N terms).
    let m = 16.0 * SHUTTER as f64 / FPS as f64;
    let tol = (8.0 / n as f64) / m + 1e-4;
    for y in 0..IH {
        for x in 0..IW {
            let v = img[(y * IW + x) as usize];
            let want = blurred(x as f64);
            assert!((v - want).abs() <= tol, "pixel ({x}, {y}): {v} vs {want}");
        }
    }
}

#[test]
fn time_sampled_frames_do_not_depend_on_the_thread_count() {
    let tracer = PathTracer::new(PathSettings {
        common: chronolux_render::registry::CommonSettings {
            spp: 16,
            max_depth: Some(1),
            ..PathSettings::default().common
        },
        ..Default::default()
    });
    let render = |threads: usize| {
        let mut source = crate::source(moving_quad(), IW, IH, FPS, vec![1]);
        let mut mb = MotionBlur::<PathTracer>::new(tracer.clone(), SHUTTER);
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| mb.render_frame(&mut source, 1, &|_| {}))
    };
    let (a, b) = (render(1), render(3));
    assert_eq!(a.pixels, b.pixels);
    assert_eq!(a.variance, b.variance);
}

#[test]
fn shutter_bdpt_matches_the_analytic_blur_of_a_moving_quad() {
    // Perspective camera (light tracing connects to a pinhole), each pixel sample at its
    // own instant. In this scene BDPT's directly seen emitter comes from the camera
    // strategy alone (its unblurred render is exact, zero variance), so this checks the
    // time sampling of the splatting driver, not its splats of other instants.
    let spp = 256;
    let bdpt = Bdpt::new(BdptSettings {
        common: chronolux_render::registry::CommonSettings {
            spp,
            max_depth: Some(1),
            ..BdptSettings::default().common
        },
        ..Default::default()
    });
    let mut source = crate::source(moving_quad_seen(false), IW, IH, FPS, vec![1]);
    let mut mb = MotionBlur::new(bdpt, SHUTTER);
    let t = mb.instants();
    let img = mb.render_frame(&mut source, 1, &|_| {});
    assert_eq!(img.invalid_samples, 0);
    let (mut worst, mut max_sigma) = (0.0f64, 0.0f64);
    for y in 0..IH {
        for x in 0..IW {
            let i = (y * IW + x) as usize;
            let v = img.pixels[i].x as f64;
            let sigma = (img.variance[i].x as f64).sqrt();
            // 5 estimated standard errors of the per-pass values (splats included), plus
            // f32 rounding; the perspective projection of the plane z = −1 is the same
            // linear map as the orthographic one up to f32 rounding (1e-4 px → 1e-4).
            let want = discretised(x as f64, t);
            assert!(
                (v - want).abs() <= 5.0 * sigma + 2e-4,
                "pixel ({x}, {y}): {v} vs {want} ± {sigma}"
            );
            worst = worst.max((v - want).abs());
            max_sigma = max_sigma.max(sigma);
        }
    }
    eprintln!("bdpt moving quad: max |bdpt − quadrature| = {worst:.4}, max σ = {max_sigma:.4}");
    // Blurred: partly covered pixels vary between samples (instants).
    assert!(max_sigma > 0.0);
}

/// Blurred BDPT and blurred path tracing of the demo (the block slides and turns; caustics
/// from the glass sphere, so light-tracing splats carry part of the image) converge to
/// the same time-averaged image: both estimate the mean over the same instants. Image
/// means per channel within 5 standard errors of their difference (variances from the
/// renderers' per-pixel estimates).
#[test]
fn shutter_bdpt_and_path_agree_on_the_moving_demo() {
    let (w, h) = (24, 24);
    let fps = 24.0;
    let frame = 12;
    let render = |r: &mut dyn SequenceRenderer| {
        let mut source =
            crate::source(chronolux_core::scene::stage::demo(), w, h, fps, vec![frame]);
        r.render_frame(&mut source, frame, &|_| {})
    };
    let p = render(&mut MotionBlur::new(
        PathTracer::new(PathSettings {
            common: chronolux_render::registry::CommonSettings {
                spp: 256,
                ..PathSettings::default().common
            },
            ..Default::default()
        }),
        1.0,
    ));
    let b = render(&mut MotionBlur::new(
        Bdpt::new(BdptSettings {
            common: chronolux_render::registry::CommonSettings {
                spp: 64,
                ..BdptSettings::default().common
            },
            ..Default::default()
        }),
        1.0,
    ));
    assert_eq!(p.invalid_samples + b.invalid_samples, 0);
    let n = (w * h) as f64;
    for c in 0..3 {
        let mean = |f: &chronolux_render::framework::integrator::RenderedFrame| {
            f.pixels.iter().map(|v| v[c] as f64).sum::<f64>() / n
        };
        let var = |f: &chronolux_render::framework::integrator::RenderedFrame| {
            f.variance.iter().map(|v| v[c] as f64).sum::<f64>() / (n * n)
        };
        let se = (var(&p) + var(&b)).sqrt();
        let z = (mean(&p) - mean(&b)).abs() / se;
        eprintln!(
            "blurred demo, channel {c}: path {:.5} bdpt {:.5}, z = {z:.2}",
            mean(&p),
            mean(&b)
        );
        assert!(z < 5.0, "channel {c}: z = {z:.2}");
    }
}

/// stbpt's motion blur (issue 4, item 5): each pixel of the reconstructed frame is spread
/// along the trajectory of the point it shows, known from the neighbouring frames of the
/// window (the quad moves 16 px per frame, so the trajectory over the shutter is ±6 px).
/// The quad's edges are on pixel boundaries at frame 1, every pixel shows the quad or the
/// black background whole, and a trajectory's ends fall on pixel centres: spreading each
/// pixel's value from its centre then integrates exactly like the analytic box-convolved-
/// with-box blur (the half pixel at each end of a unit box's spread is the same integral
/// as the spread's half pixel ramp). What is left is f32 rounding of the projections
/// (1e-4 px, as in the BDPT test above) times the profile's slope (1/12 per px).
#[test]
fn shutter_stbpt_matches_the_analytic_blur_of_a_moving_quad() {
    use chronolux_render::techniques::stbpt::{Stbpt, StbptSettings};
    let mut source = crate::source(moving_quad_seen(false), IW, IH, FPS, vec![0, 1, 2]);
    let mut st = Stbpt::new(StbptSettings {
        bdpt: BdptSettings {
            common: chronolux_render::registry::CommonSettings {
                spp: 4,
                max_depth: Some(1),
                ..BdptSettings::default().common
            },
            ..Default::default()
        },
        window: 1,
        shutter: SHUTTER,
        ..Default::default()
    });
    let img = st.render_frame(&mut source, 1, &|_| {});
    assert_eq!(img.invalid_samples, 0);
    let mut worst = 0.0f64;
    for y in 0..IH {
        for x in 0..IW {
            let v = img.pixels[(y * IW + x) as usize].x as f64;
            let want = blurred(x as f64);
            worst = worst.max((v - want).abs());
            assert!((v - want).abs() <= 1e-4, "pixel ({x}, {y}): {v} vs {want}");
        }
    }
    eprintln!("stbpt moving quad: max |stbpt − analytic| = {worst:.2e}");
    // Really blurred, and a closed shutter gives the sharp 8-pixel box.
    assert!((img.pixels[32].x - 8.0 / 12.0).abs() < 1e-3);
    let mut sharp = Stbpt::new(StbptSettings {
        bdpt: BdptSettings {
            common: chronolux_render::registry::CommonSettings {
                spp: 4,
                max_depth: Some(1),
                ..BdptSettings::default().common
            },
            ..Default::default()
        },
        window: 1,
        ..Default::default()
    });
    let s = sharp.render_frame(&mut source, 1, &|_| {});
    assert_eq!(s.pixels[32].x, 1.0);
}
