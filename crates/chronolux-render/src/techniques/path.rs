//! `path`: unidirectional path tracing frame by frame, the reference every other
//! technique is measured against. The per-path kernel is [`crate::kernels::path`]; this
//! module is its registry entry and quality table.

use crate::kernels::path::{PathSettings, PathTracer};

/// Registry entry of `path`; with a shutter, time-sampled motion blur
/// ([`crate::framework::shutter::MotionBlur`]).
pub static TECHNIQUE: crate::framework::technique::Preset<PathSettings> =
    crate::framework::technique::Preset {
        name: "path",
        summary: "unidirectional path tracing with NEE and MIS, frame by frame (the reference)",
        capabilities: crate::framework::shutter::FRAME_BY_FRAME_SPP,
        // Measured: BENCHMARKS.md, "The quality table".
        quality: &[
            crate::framework::technique::QualityLevel::denoised("draft", 0.1131, &[("spp", "2")]),
            crate::framework::technique::QualityLevel::denoised("preview", 0.0778, &[("spp", "8")]),
            crate::framework::technique::QualityLevel::denoised("final", 0.0562, &[("spp", "32")]),
            // 512²: the denoiser does more of the work (BENCHMARKS.md, 512² sweep).
            crate::framework::technique::QualityLevel::denoised("draft", 0.0917, &[("spp", "2")])
                .at(512, 512),
            crate::framework::technique::QualityLevel::denoised("preview", 0.0753, &[("spp", "4")])
                .at(512, 512),
            crate::framework::technique::QualityLevel::denoised("final", 0.0561, &[("spp", "16")])
                .at(512, 512),
        ],
        defaults: PathSettings::default,
        common: |s| &mut s.common,
        build: |s, ctx, name| {
            Ok(crate::framework::shutter::frame_by_frame(
                PathTracer::new(s),
                ctx.shutter,
                name,
            ))
        },
    };
