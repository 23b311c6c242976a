//! Cost of the WindowFilm disk cache, and its memory, on a synthetic sample-reuse workload.
//!
//! `cargo run --release -p chronolux-render --example film_cache -- [options]`
//!
//! Options (defaults in brackets): `--width` [1920] `--height` [1080] `--frames` [24]
//! `--window K` [4: windows of 2K + 1 = 9 frames] `--budget-mb` [64] `--spp` [1]
//! `--mode both|disk-first|mem|disk` [both] `--dir PATH` [system temp dir] `--render-ref` (also
//! path-trace the demo at 480×270, 1 spp, and scale to the film's size: the render time
//! the cache cost is compared with).
//!
//! Workload, as a sample-reusing technique (stbpt) produces it: for each source frame f in
//! order, `spp` camera samples per pixel, rendered in 16×16 tiles; each sample contributes
//! to every frame g of its window [f − K, f + K] at its reprojected pixel (the source
//! pixel moved by (3, 1)·(g − f) pixels plus up to ±1 pixel of jitter; off-screen ones
//! dropped). Batches are one row of render tiles (16 image rows), merged in order; frame g
//! is finished once source frame g + K is done. Generation of the contributions is not
//! timed; `add_batch` and `finish` are. `mem` keeps every tile in memory, `disk` holds at
//! most the budget (LRU tiles spill to the cache directory); the cache's cost is
//! t(disk) − t(mem). Single-threaded (the film is fed by one thread).

use chronolux_core::color::Rgb;
use chronolux_core::sampling::rng::Pcg32;
use chronolux_render::framework::window_film::{Contribution, FilmStats, WindowFilm};
use std::time::Instant;

struct Opts {
    width: u32,
    height: u32,
    frames: u32,
    window: u32,
    budget_mb: u64,
    spp: u32,
    mode: String,
    dir: Option<std::path::PathBuf>,
    render_ref: bool,
}

fn parse() -> Opts {
    let mut o = Opts {
        width: 1920,
        height: 1080,
        frames: 24,
        window: 4,
        budget_mb: 64,
        spp: 1,
        mode: "both".into(),
        dir: None,
        render_ref: false,
    };
    let args: Vec<String> = std::env::args().skip(1).collect();
    let mut i = 0;
    while i < args.len() {
        let v = || args.get(i + 1).expect("option needs a value").clone();
        match args[i].as_str() {
            "--width" => o.width = v().parse().unwrap(),
            "--height" => o.height = v().parse().unwrap(),
            "--frames" => o.frames = v().parse().unwrap(),
            "--window" => o.window = v().parse().unwrap(),
            "--budget-mb" => o.budget_mb = v().parse().unwrap(),
            "--spp" => o.spp = v().parse().unwrap(),
            "--mode" => o.mode = v(),
            "--dir" => o.dir = Some(v().into()),
            "--render-ref" => {
                o.render_ref = true;
                i += 1;
                continue;
            }
            a => panic!("unknown option {a}"),
        }
        i += 2;
    }
    o
}

/// Contributions of the 16-row band `band` of source frame `f`.
fn band(o: &Opts, f: u32, band: u32, out: &mut Vec<Contribution>) {
    out.clear();
    let mut rng = Pcg32::new(((f as u64) << 32) | band as u64, 3);
    let (lo, hi) = (f.saturating_sub(o.window), (f + o.window).min(o.frames - 1));
    for y in band * 16..((band + 1) * 16).min(o.height) {
        for x in 0..o.width {
            for _ in 0..o.spp {
                let v = Rgb::new(rng.next_f32(), rng.next_f32(), rng.next_f32());
                for g in lo..=hi {
                    let d = g as f32 - f as f32;
                    let gx = x as f32 + 3.0 * d + 2.0 * rng.next_f32() - 1.0;
                    let gy = y as f32 + d + 2.0 * rng.next_f32() - 1.0;
                    if gx < 0.0 || gy < 0.0 || gx >= o.width as f32 || gy >= o.height as f32 {
                        continue;
                    }
                    out.push(Contribution {
                        frame: g,
                        pixel: gy as u32 * o.width + gx as u32,
                        value: v,
                        weight: 1.0,
                        splat: false,
                    });
                }
            }
        }
    }
}

/// CPU seconds (user + system) of the calling thread so far, from /proc (Linux; 10 ms
/// ticks): on a loaded shared machine wall time measures the neighbours as much as us.
/// Page-cache I/O is kernel CPU work, so it shows here too.
fn thread_cpu() -> f64 {
    cpu_of("/proc/thread-self/stat")
}

/// CPU seconds of `/proc/.../stat` (a thread or the process).
fn cpu_of(path: &str) -> f64 {
    let s = std::fs::read_to_string(path).unwrap_or_default();
    let rest = s.rsplit_once(')').map(|r| r.1).unwrap_or("");
    let f: Vec<&str> = rest.split_whitespace().collect();
    // Fields 14 and 15 of stat(5) are the 12th and 13th after the command name.
    let tick = |i: usize| f.get(i).and_then(|v| v.parse::<f64>().ok()).unwrap_or(0.0);
    (tick(11) + tick(12)) / 100.0
}

/// CPU seconds of generating the workload alone (subtracted from each run's CPU time).
fn generation_cpu(o: &Opts) -> f64 {
    let c = thread_cpu();
    let mut batch = Vec::new();
    let mut n = 0usize;
    for f in 0..o.frames {
        for b in 0..o.height.div_ceil(16) {
            band(o, f, b, &mut batch);
            n += batch.len();
        }
    }
    std::hint::black_box(n);
    thread_cpu() - c
}

struct Run {
    /// CPU seconds of the whole run (generation included).
    cpu: f64,
    seconds: f64,
    contributions: u64,
    stats: FilmStats,
    checksum: f64,
}

fn run(o: &Opts, mut film: WindowFilm) -> Run {
    let cpu0 = thread_cpu();
    let mut batch = Vec::new();
    let mut seconds = 0.0;
    let mut contributions = 0u64;
    let mut checksum = 0.0f64;
    let bands = o.height.div_ceil(16);
    let mut finish = |film: &mut WindowFilm, g: u32, seconds: &mut f64| {
        let t = Instant::now();
        let (px, _) = film.finish(g, 1.0);
        *seconds += t.elapsed().as_secs_f64();
        checksum += px.iter().map(|p| p.x as f64).sum::<f64>();
    };
    for f in 0..o.frames {
        for b in 0..bands {
            band(o, f, b, &mut batch);
            contributions += batch.len() as u64;
            let t = Instant::now();
            film.add_batch(&batch);
            seconds += t.elapsed().as_secs_f64();
        }
        if f >= o.window {
            finish(&mut film, f - o.window, &mut seconds);
        }
    }
    for g in o.frames.saturating_sub(o.window)..o.frames {
        finish(&mut film, g, &mut seconds);
    }
    let stats = film.stats();
    drop(film);
    Run {
        cpu: thread_cpu() - cpu0,
        seconds,
        contributions,
        stats,
        checksum,
    }
}

fn report(name: &str, r: &Run, gen_cpu: f64) {
    let s = &r.stats;
    println!(
        "{name}: film CPU {:.2} s (run {:.2} s − generation {:.2} s)",
        r.cpu - gen_cpu,
        r.cpu,
        gen_cpu
    );
    let hits = s.tile_hits as f64 / (s.tile_hits + s.tile_misses).max(1) as f64;
    println!(
        "{name}: {:.2} s for {} contributions ({:.1} M/s); peak {:.1} MB of tiles; \
         tile hit rate {:.4} ({} hits, {} misses, {} written); {:.2} GB written, {:.2} GB read, \
         I/O {:.2} s; checksum {:.6e}",
        r.seconds,
        r.contributions,
        r.contributions as f64 / r.seconds / 1e6,
        s.peak_bytes as f64 / 1e6,
        hits,
        s.tile_hits,
        s.tile_misses,
        s.tiles_written,
        s.bytes_written as f64 / 1e9,
        s.bytes_read as f64 / 1e9,
        s.io_seconds,
        r.checksum
    );
}

fn main() {
    let o = parse();
    println!(
        "film cache: {}x{}, {} frames, window {} (2K+1 = {}), {} spp, budget {} MB (+ one tile of {} B)",
        o.width,
        o.height,
        o.frames,
        o.window,
        2 * o.window + 1,
        o.spp,
        o.budget_mb,
        WindowFilm::tile_bytes()
    );
    let budget = o.budget_mb * 1_000_000;
    let gen_cpu = generation_cpu(&o);
    let run_mem = || {
        let r = run(&o, WindowFilm::new(o.width, o.height));
        report("mem ", &r, gen_cpu);
        r
    };
    let run_disk = || {
        let film = WindowFilm::with_budget(o.width, o.height, budget, o.dir.as_deref());
        let r = run(&o, film);
        report("disk", &r, gen_cpu);
        r
    };
    // `disk-first`: both, the cached film first (to see the order's effect on a loaded
    // machine).
    let (mem, disk) = match o.mode.as_str() {
        "mem" => (Some(run_mem()), None),
        "disk" => (None, Some(run_disk())),
        "disk-first" => {
            let d = run_disk();
            (Some(run_mem()), Some(d))
        }
        _ => {
            let m = run_mem();
            (Some(m), Some(run_disk()))
        }
    };
    if let (Some(m), Some(d)) = (&mem, &disk) {
        assert_eq!(m.checksum.to_bits(), d.checksum.to_bits(), "frames differ");
        println!(
            "cache cost: {:.2} s over {} frames = {:.3} s per frame, {:.1} % of the accumulation work",
            d.seconds - m.seconds,
            o.frames,
            (d.seconds - m.seconds) / o.frames as f64,
            100.0 * (d.seconds - m.seconds) / m.seconds
        );
        println!(
            "cache cost in CPU: {:.2} s = {:.3} s per frame, {:.1} % of the film's CPU work",
            d.cpu - m.cpu,
            (d.cpu - m.cpu) / o.frames as f64,
            100.0 * (d.cpu - m.cpu) / (m.cpu - gen_cpu)
        );
    }
    if o.render_ref {
        use chronolux_core::scene::frame::{CameraChoice, FrameBuilder};
        use chronolux_render::framework::integrator::Integrator;
        use chronolux_render::kernels::path::{PathSettings, PathTracer};
        let desc = std::sync::Arc::new(chronolux_core::scene::stage::demo());
        let anim = Some(chronolux_core::scene::desc::AnimationId(0));
        let (rw, rh) = (480u32, 270u32);
        let mut b = FrameBuilder::new(desc, anim, CameraChoice::First, rw, rh).unwrap();
        let scene = b.build(0.5);
        let mut settings = PathSettings::default();
        settings.common.spp = 1;
        let pt = PathTracer::new(settings);
        // On one thread, like the film's figures (CPU seconds of this thread).
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .unwrap();
        // The render runs on the pool's thread: CPU of the whole process.
        let (t, c) = (Instant::now(), cpu_of("/proc/self/stat"));
        pool.install(|| pt.render(&scene, 12, &|_| {}));
        let scale = (o.width * o.height) as f64 / (rw * rh) as f64;
        let per_spp = t.elapsed().as_secs_f64() * scale;
        let per_spp_cpu = (cpu_of("/proc/self/stat") - c) * scale;
        println!(
            "reference: path tracing the demo costs {per_spp:.2} s wall per sample per pixel at {}x{} on one thread",
            o.width, o.height
        );
        if let (Some(m), Some(d)) = (&mem, &disk) {
            let cost = (d.seconds - m.seconds) / o.frames as f64;
            println!(
                "cache cost per frame / path-tracing time per frame at {} spp: {:.1} % (wall)",
                o.spp,
                100.0 * cost / (per_spp * o.spp as f64)
            );
            let cost = (d.cpu - m.cpu) / o.frames as f64;
            println!(
                "reference CPU: {per_spp_cpu:.2} s per sample per pixel; cache CPU per frame / path-tracing CPU per frame at {} spp: {:.1} %",
                o.spp,
                100.0 * cost / (per_spp_cpu * o.spp as f64)
            );
        }
    }
}
