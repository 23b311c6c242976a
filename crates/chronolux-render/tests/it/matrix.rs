//! The registry's test matrix: every technique in [`TECHNIQUES`] (so a new one is covered
//! without editing this file), built from its registry defaults at low effort through
//! [`registry::resolve`] and run through the one run loop ([`run::run`]) into a
//! [`MemorySink`]:
//!
//! - images are bit-identical with 1 and 2 worker threads (every frame of a short
//!   sequence of the animated demo (two frames, so temporal techniques carry state from
//!   one frame to the next);
//! - on the static Cornell box every technique converges to the path tracer's image: each
//!   channel's image mean within the bias bound stated at [`BIAS_BOUND`].

use crate::bits;
use crate::source;
use chronolux_core::scene::desc::SceneDesc;
use chronolux_core::scene::stage;
use chronolux_render::framework::integrator::RenderedFrame;
use chronolux_render::framework::run::{self, MemorySink};
use chronolux_render::registry::{self, BuildContext, TECHNIQUES, Technique};
use serde_json::Value;

pub(crate) const W: u32 = 24;
pub(crate) const H: u32 = 24;

/// Settings of `t`: its defaults with its effort knob at `units` effort units (samples per
/// pixel, thousands of photons).
pub(crate) fn settings(t: &dyn Technique, units: u64) -> Value {
    let e = t.capabilities().effort;
    registry::resolve(
        t,
        None,
        &[(e.key.to_string(), Value::from(units * e.per_unit))],
    )
    .unwrap_or_else(|err| panic!("{}: {err}", t.name()))
}

/// Frames `frames` of `desc` at 24 fps rendered by `t` with `settings` through the run
/// loop; the images in frame order.
pub(crate) fn render(
    t: &dyn Technique,
    settings: &Value,
    desc: SceneDesc,
    frames: &[u32],
) -> Vec<RenderedFrame> {
    let mut renderer = t
        .build(settings, &BuildContext::default())
        .unwrap_or_else(|e| panic!("{}: {e}", t.name()));
    let mut src = source(desc, W, H, 24.0, frames.to_vec());
    let mut sink = MemorySink::new();
    run::run(&mut *renderer, &mut src, frames, &mut [&mut sink], None)
        .unwrap_or_else(|e| panic!("{}: {e}", t.name()));
    assert_eq!(sink.frames.len(), frames.len(), "{}", t.name());
    sink.frames.into_iter().map(|(_, img, _)| img).collect()
}

#[test]
fn every_technique_is_bit_identical_across_thread_counts() {
    let frames = [0u32, 1];
    for t in TECHNIQUES {
        let s = settings(*t, 1);
        let with = |threads: usize| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap()
                .install(|| render(*t, &s, stage::demo(), &frames))
        };
        let t0 = std::time::Instant::now();
        let (a, b) = (with(1), with(2));
        eprintln!("{}: {:.1} s", t.name(), t0.elapsed().as_secs_f64());
        for (k, (x, y)) in a.iter().zip(&b).enumerate() {
            assert_eq!(x.invalid_samples, 0, "{} frame {k}", t.name());
            assert!(
                x.pixels.iter().any(|p| p.max_element() > 0.0),
                "{} frame {k}: black image",
                t.name()
            );
            assert!(
                bits(&x.pixels) == bits(&y.pixels),
                "{} frame {}: 1 and 2 threads differ",
                t.name(),
                frames[k]
            );
            assert_eq!(x.stats, y.stats, "{} frame {}", t.name(), frames[k]);
        }
    }
}

/// Bound on |technique − path tracer| / path tracer for each channel's image mean of the
/// static Cornell box at 24×24 (the middle frame of 3, at 32 effort units; reference: the
/// path tracer at 256 spp), on top of 5 standard errors of the reference. Where it comes
/// from: measured (2026-12-02, printed by the test) worst case 0.8 % with this setup
/// (photon-density estimators 0.3–0.8 %: their element discretisation bias on this diffuse
/// box, plus photon noise at 32 000 photons per frame; path, bdpt and stbpt 0.3–0.8 %, their
/// noise), and 2.2 % when the compared frame was frame 2 of 5, against a reference whose
/// own standard error is 0.7–0.9 % per channel. 5 % is over twice the worst seen; a
/// technique with a systematic error of 5 % or more in any channel's mean fails.
const BIAS_BOUND: f64 = 0.05;

#[test]
fn every_technique_converges_to_the_path_tracer_on_a_static_scene() {
    let frames = [0u32, 1, 2];
    let out = 1;
    let pt = registry::find("path").unwrap();
    let reference = &render(pt, &settings(pt, 256), stage::cornell_box(), &[out])[0];
    let n = (W * H) as f64;
    for t in TECHNIQUES {
        let t0 = std::time::Instant::now();
        let img = &render(*t, &settings(*t, 32), stage::cornell_box(), &frames)[out as usize];
        eprintln!("{}: {:.1} s", t.name(), t0.elapsed().as_secs_f64());
        assert_eq!(img.invalid_samples, 0, "{}", t.name());
        for c in 0..3 {
            let m: f64 = img.pixels.iter().map(|p| p[c] as f64).sum::<f64>() / n;
            let r: f64 = reference.pixels.iter().map(|p| p[c] as f64).sum::<f64>() / n;
            let se_ref =
                (reference.variance.iter().map(|v| v[c] as f64).sum::<f64>() / (n * n)).sqrt();
            let rel = (m - r).abs() / r;
            eprintln!(
                "{}: channel {c}: {m:.5} vs path {r:.5} (rel {rel:.4}, reference se {se_ref:.1e})",
                t.name()
            );
            assert!(
                (m - r).abs() <= BIAS_BOUND * r + 5.0 * se_ref,
                "{}: channel {c}: image mean {m:.5} vs path tracer {r:.5}: relative error \
                 {rel:.4} beyond the bias bound {BIAS_BOUND} + 5 se ({se_ref:.1e})",
                t.name()
            );
        }
    }
}
