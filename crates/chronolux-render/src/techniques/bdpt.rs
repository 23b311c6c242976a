//! `bdpt`: bidirectional path tracing frame by frame, the baseline of `stbpt`. The
//! estimator (subpaths, connections, MIS, caustic photons) is [`crate::kernels::bdpt`];
//! this module is its registry entry.

use crate::kernels::bdpt::{Bdpt, BdptSettings};

/// Registry entry of `bdpt`; with a shutter, time-sampled motion blur
/// ([`crate::framework::shutter::MotionBlur`]).
pub static TECHNIQUE: crate::framework::technique::Preset<BdptSettings> =
    crate::framework::technique::Preset {
        name: "bdpt",
        summary: "bidirectional path tracing, all strategies with MIS, frame by frame",
        capabilities: crate::framework::shutter::FRAME_BY_FRAME_SPP,
        quality: &[],
        defaults: BdptSettings::default,
        common: |s| &mut s.common,
        build: |s, ctx, name| {
            Ok(crate::framework::shutter::frame_by_frame(
                Bdpt::new(s),
                ctx.shutter,
                name,
            ))
        },
    };
