//! Rays per second of the multi-frame visibility query against separate per-frame queries,
//! on the demo, for windows of 2K + 1 frames around frame 24 (24 fps).
//!
//! `cargo run --release -p chronolux-core --example multi_frame_bench [rays] [rounds]`
//!
//! Single-threaded; rounds interleaved and medians reported (shared machines). Ray sets as
//! in `chronolux bench rays`: *box* (origin uniform in the scene bounds, direction uniform
//! on the sphere), *hemi* (from a surface point of the middle frame, direction uniform on
//! the sphere, origin offset to the side it leaves), and *shadow* (segments between two
//! surface points, any-hit).

use chronolux_core::accel::multi_frame::{MultiFrameAccel, WindowHit};
use chronolux_core::geometry::{Ray, spawn_ray, spawn_ray_to};
use chronolux_core::math::{Vec2, Vec3};
use chronolux_core::sampling::rng::Pcg32;
use chronolux_core::sampling::warps::sample_uniform_sphere;
use chronolux_core::scene::desc::AnimationId;
use chronolux_core::scene::frame::{CameraChoice, FrameBuilder, FrameScene};
use chronolux_core::scene::source::frame_time;
use chronolux_core::scene::stage;
use std::hint::black_box;
use std::sync::Arc;
use std::time::Instant;

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let n: usize = args.get(1).map_or(200_000, |s| s.parse().unwrap());
    let rounds: usize = args.get(2).map_or(5, |s| s.parse().unwrap());
    let (fps, centre) = (24.0f32, 24u32);
    let mut b = FrameBuilder::new(
        Arc::new(stage::demo()),
        Some(AnimationId(0)),
        CameraChoice::First,
        64,
        64,
    )
    .unwrap();
    let kmax = 8u32;
    let frames: Vec<FrameScene> = (centre - kmax..=centre + kmax)
        .map(|g| b.build(frame_time(g, fps)))
        .collect();
    let mid = &frames[kmax as usize];
    let accept = |t, b1, b2| mid.accept(t, b1, b2);

    let mut r = Pcg32::new(2024, 7);
    let bb = mid.bounds;
    let uniform_point = |r: &mut Pcg32| {
        bb.min + (bb.max - bb.min) * Vec3::new(r.next_f32(), r.next_f32(), r.next_f32())
    };
    let dir = |r: &mut Pcg32| sample_uniform_sphere(Vec2::new(r.next_f32(), r.next_f32()));
    let surface = |r: &mut Pcg32| loop {
        let ray = Ray::new(uniform_point(r), dir(r));
        if let Some(h) = mid.intersect(&ray) {
            let si = mid.interaction(&h, &ray);
            return (si.p, si.ng);
        }
    };
    let boxed: Vec<Ray> = (0..n)
        .map(|_| {
            let o =
                bb.min + (bb.max - bb.min) * Vec3::new(r.next_f32(), r.next_f32(), r.next_f32());
            Ray::new(o, dir(&mut r))
        })
        .collect();
    let hemi: Vec<Ray> = (0..n)
        .map(|_| {
            let (p, ng) = surface(&mut r);
            spawn_ray(p, ng, dir(&mut r))
        })
        .collect();
    let shadow: Vec<Ray> = (0..n)
        .map(|_| {
            let (p0, n0) = surface(&mut r);
            let (p1, n1) = surface(&mut r);
            spawn_ray_to(p0, n0, p1, n1)
        })
        .collect();

    println!(
        "demo, {n} rays per set, {rounds} rounds, single thread; Mrays/s = rays answered for \
         ALL 2K+1 frames per second"
    );
    println!(
        "{:>2} {:>7} | {:>9} {:>9} {:>7} | {:>9} {:>9} {:>7} | {:>9} {:>9} {:>7} | {:>8} {:>9}",
        "K",
        "frames",
        "box win",
        "box sep",
        "x",
        "hemi win",
        "hemi sep",
        "x",
        "shad win",
        "shad sep",
        "x",
        "build ms",
        "1-frame"
    );
    for k in [2u32, 4, 8] {
        let win = &frames[(kmax - k) as usize..=(kmax + k) as usize];
        let refs: Vec<_> = win.iter().map(|f| &f.accel).collect();
        let t0 = Instant::now();
        let w = MultiFrameAccel::new(centre - k, &refs);
        let build_ms = t0.elapsed().as_secs_f64() * 1e3;
        let all = w.all_frames();
        let mut times = vec![Vec::new(); 7];
        let mut out = WindowHit::default();
        for _ in 0..rounds {
            for (set, rays) in [&boxed, &hemi].into_iter().enumerate() {
                let t = Instant::now();
                for ray in rays {
                    w.intersect_window_into(ray, all, accept, &mut out);
                    black_box(&out);
                }
                times[2 * set].push(t.elapsed().as_secs_f64());
                let t = Instant::now();
                for ray in rays {
                    for f in win {
                        black_box(f.intersect(ray));
                    }
                }
                times[2 * set + 1].push(t.elapsed().as_secs_f64());
            }
            let t = Instant::now();
            for ray in &shadow {
                black_box(w.occluded_window(ray, all, accept));
            }
            times[4].push(t.elapsed().as_secs_f64());
            let t = Instant::now();
            for ray in &shadow {
                for f in win {
                    black_box(f.occluded(ray));
                }
            }
            times[5].push(t.elapsed().as_secs_f64());
            // One per-frame query of one frame: what a ray costs in a single frame.
            let t = Instant::now();
            for ray in &hemi {
                black_box(mid.intersect(ray));
            }
            times[6].push(t.elapsed().as_secs_f64());
        }
        let m: Vec<f64> = times
            .into_iter()
            .map(|v| n as f64 / median(v) / 1e6)
            .collect();
        println!(
            "{:>2} {:>7} | {:>9.2} {:>9.2} {:>7.2} | {:>9.2} {:>9.2} {:>7.2} | {:>9.2} {:>9.2} {:>7.2} | {:>8.3} {:>9.2}",
            k,
            2 * k + 1,
            m[0],
            m[1],
            m[0] / m[1],
            m[2],
            m[3],
            m[2] / m[3],
            m[4],
            m[5],
            m[4] / m[5],
            build_ms,
            m[6]
        );
        println!(
            "   window: {} static instance(s), {} dynamic window instances ({} instance-frames)",
            w.stats.static_instances, w.stats.dynamic_instances, w.stats.dynamic_instance_frames
        );
    }
}
