//! `pm-ic`: photon mapping with final gathering cached in an irradiance cache, frame by
//! frame (Jensen 1996/2001 with Ward's cache), the baseline of `ic-static-dynamic` and
//! `ic-selective`. The method (photon maps, eye paths, gathers, cache) is the gather
//! kernel, [`crate::kernels::gather`]; this module renders it frame by frame.

use crate::framework::integrator::{RenderedFrame, render_camera_rays};
use crate::kernels::gather::irradiance_cache::IrradianceCache;
use crate::kernels::gather::view::EyeView;
use crate::kernels::gather::*;
use chronolux_core::sampling::hash_words;
use chronolux_core::scene::frame::FrameScene;

/// Frame-by-frame photon mapping with an irradiance cache.
pub struct PmIc {
    pub settings: PmIcSettings,
    pub name: &'static str,
}

impl PmIc {
    /// Renders one frame from scratch.
    pub fn render(
        &self,
        scene: &FrameScene,
        frame: u32,
        progress: &(dyn Fn(u64) + Sync),
    ) -> RenderedFrame {
        let s = &self.settings;
        let t0 = std::time::Instant::now();
        let maps = frame_maps(scene, s, photon_base(s, frame));
        let t_photons = t0.elapsed().as_secs_f64();
        let mut cache = IrradianceCache::new(s.cache.accuracy, base_cell(scene));
        let key = hash_words(&[s.common.seed, photon_base(s, frame), 0x6963]);
        let probe_src = view::NoIndirect;
        let probe_view = EyeView::new(s, scene, &maps.caustic, &probe_src);
        let points = probe_points(&probe_view, scene, key);
        let records = extend_cache(
            &mut cache,
            &points,
            &s.cache,
            |_| true,
            |q, k| gather_at(scene, s, &[&maps.global], q.p, q.n, k),
        );
        let t_cache = t0.elapsed().as_secs_f64() - t_photons;
        let src = CacheSource {
            settings: s,
            cache: &cache,
            global: &maps.global,
            unstored: Default::default(),
        };
        let eye = EyeView::new(s, scene, &maps.caustic, &src);
        let mut out = render_camera_rays(&eye, scene, frame, s.common.spp, s.common.seed, progress);
        out.stats.rays += maps.rays;
        let r = &mut out.report;
        r.insert("photons".into(), s.photons.into());
        r.insert("global_photons_stored".into(), maps.global.len().into());
        r.insert("caustic_photons_stored".into(), maps.caustic.len().into());
        r.insert("cache_records".into(), records.into());
        r.insert("unstored_gathers".into(), src.unstored.into_inner().into());
        r.insert("seconds_photons".into(), t_photons.into());
        r.insert("seconds_cache".into(), t_cache.into());
        out
    }
}

impl crate::framework::sequence::SequenceRenderer for PmIc {
    fn name(&self) -> &'static str {
        self.name
    }

    fn render_frame(
        &mut self,
        source: &mut chronolux_core::scene::source::FrameSource,
        frame: u32,
        progress: &(dyn Fn(u64) + Sync),
    ) -> RenderedFrame {
        let scene = source.frame(frame);
        self.render(&scene, frame, progress)
    }
}

/// Registry entry of `pm-ic`.
pub static TECHNIQUE: crate::framework::technique::Preset<PmIcSettings> =
    crate::framework::technique::Preset {
        name: "pm-ic",
        summary: "photon mapping (global + caustic maps) with final gathering in an irradiance cache with gradients, frame by frame",
        capabilities: crate::framework::technique::Capabilities {
            motion_blur: false,
            // `--photons` means dept's count-or-stopping-rule; here `--set photons=N`.
            photons: false,
            window: false,
            max_depth: false,
            stateless: true,
            effort: crate::framework::technique::Effort {
                key: "photons",
                per_unit: 1000,
                unit: "thousand photons per map and frame",
            },
        },
        quality: &[],
        defaults: PmIcSettings::default,
        common: |s| &mut s.common,
        build: |s, _, name| Ok(Box::new(PmIc { settings: s, name })),
    };
