//! `dept`, `dept-spatial`, `dept-bilateral`: photon tracing with density estimation on
//! mesh elements, frame by frame, without / with spatial Gaussian / with spatial
//! bilateral filtering (Myszkowski et al. 2001; Weber et al. 2004), the baselines of the
//! space-time technique. The per-frame solve and eye pass are the element kernels
//! ([`crate::kernels::elements`]); this module runs them frame by frame and names the
//! three presets.

use crate::framework::integrator::RenderedFrame;
use crate::kernels::elements::{Dept, DeptSettings};

/// Frame-by-frame DEPT as a sequence renderer; each frame's report has its `photons`.
pub struct DeptSequence {
    pub dept: Dept,
    pub name: &'static str,
}

impl DeptSequence {
    pub fn new(dept: Dept, name: &'static str) -> Self {
        DeptSequence { dept, name }
    }
}

impl crate::framework::sequence::SequenceRenderer for DeptSequence {
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
        let scene = &*scene;
        let solved = self.dept.solve(scene, frame);
        let mut out = self.dept.render_solved(scene, frame, &solved, progress);
        out.report
            .insert("photons".into(), solved.photons.photons().into());
        out.report.insert(
            "elements_per_diagonal".into(),
            self.dept.elements_per_diagonal().into(),
        );
        out
    }

    /// Direct light per pixel, indirect from the elements ([`crate::kernels::elements::view`]).
    fn separates_light(&self) -> bool {
        true
    }
}

/// What the three `dept` presets share: photons (effort in thousands per frame), frame by
/// frame.
const DEPT_CAPABILITIES: crate::framework::technique::Capabilities =
    crate::framework::technique::Capabilities {
        motion_blur: false,
        photons: true,
        window: false,
        max_depth: true,
        stateless: true,
        effort: crate::framework::technique::Effort {
            key: "photons",
            per_unit: 1000,
            unit: "thousand photons per frame",
        },
    };

fn build_dept(
    s: DeptSettings,
    _: &crate::framework::technique::BuildContext,
    name: &'static str,
) -> Result<crate::framework::technique::Renderer, String> {
    Ok(Box::new(DeptSequence::new(Dept::new(s), name)))
}

/// Registry entry of `dept` (no filtering).
pub static TECHNIQUE: crate::framework::technique::Preset<DeptSettings> =
    crate::framework::technique::Preset {
        name: "dept",
        summary: "photon density estimation on mesh elements, frame by frame, no filtering",
        capabilities: DEPT_CAPABILITIES,
        quality: &[],
        defaults: DeptSettings::default,
        common: |s| &mut s.common,
        build: build_dept,
    };

/// `dept-spatial`: `dept` with its spatial Gaussian filter ([`DeptSettings::spatial`]).
pub static SPATIAL: crate::framework::technique::Preset<DeptSettings> =
    crate::framework::technique::Preset {
        name: "dept-spatial",
        summary: "photon density estimation on mesh elements, spatial Gaussian filter (a preset of dept)",
        capabilities: DEPT_CAPABILITIES,
        quality: &[],
        defaults: DeptSettings::spatial,
        common: |s| &mut s.common,
        build: build_dept,
    };

/// `dept-bilateral`: `dept` with its spatial bilateral filter ([`DeptSettings::bilateral`]).
pub static BILATERAL: crate::framework::technique::Preset<DeptSettings> =
    crate::framework::technique::Preset {
        name: "dept-bilateral",
        summary: "photon density estimation on mesh elements, spatial bilateral filter (a preset of dept)",
        capabilities: DEPT_CAPABILITIES,
        quality: &[],
        defaults: DeptSettings::bilateral,
        common: |s| &mut s.common,
        build: build_dept,
    };
