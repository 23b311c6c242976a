//! Photon tracing with density estimation on mesh elements (DEPT), frame by frame: the
//! baselines `dept` (no filtering), `dept-spatial` (spatial Gaussian over elements) and
//! `dept-bilateral` (spatial bilateral), and the per-frame building blocks the space-time
//! technique reuses.
//!
//! Per frame `f` with `N` photons: photons `f·N .. (f+1)·N` of the Halton stream (so the
//! union of consecutive frames' photons is one contiguous Halton range) are traced by
//! [`crate::kernels::photon`] and their flux summed on the elements of
//! [`element_map::ElementMesh`]; [`reconstruct`] turns the sums into a smooth irradiance
//! field; [`view`] renders eye rays with per-pixel direct light and element indirect light.

pub mod element_map;
pub mod reconstruct;
pub mod view;

use crate::integrator::{Integrator, RenderedFrame, render_camera_rays};
use chronolux_core::scene::frame::FrameScene;
use element_map::{ElementMesh, FrameElements, FramePhotons, deposit_photons};
use reconstruct::{ElementSolution, Filter, filtered_irradiance};

/// Settings of the frame-by-frame DEPT baselines.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct DeptSettings {
    /// Photons emitted per frame. Default 500 000.
    pub photons: u64,
    /// Camera samples per pixel (direct light and anti-aliasing). Default 16.
    pub spp: u32,
    /// Target element count along the scene's bounding-box diagonal (element edge =
    /// diagonal / this). Default 100.
    pub elements: f32,
    /// Longest chain of specular bounces followed by eye rays. Default 8.
    pub max_specular_depth: u32,
    /// Filtering of the element estimates.
    pub filter: Filter,
    /// Seed of the photon and camera streams. Default 0.
    pub seed: u64,
}

impl Default for DeptSettings {
    fn default() -> Self {
        DeptSettings {
            photons: 500_000,
            spp: 16,
            elements: 100.0,
            max_specular_depth: 8,
            filter: Filter::None,
            seed: 0,
        }
    }
}

impl DeptSettings {
    /// Defaults with a spatial Gaussian filter of radius 2.5 elements (`dept-spatial`).
    pub fn spatial() -> Self {
        DeptSettings {
            filter: Filter::Gaussian { radius: 2.5 },
            ..Default::default()
        }
    }

    /// Defaults with a spatial bilateral filter (`dept-bilateral`).
    pub fn bilateral() -> Self {
        DeptSettings {
            filter: Filter::Bilateral {
                radius: 2.5,
                kappa: 2.0,
                min_photons: 8,
            },
            ..Default::default()
        }
    }
}

/// Everything computed for one frame before the eye pass.
pub struct DeptFrame {
    pub mesh: ElementMesh,
    pub elements: FrameElements,
    pub photons: FramePhotons,
    pub indirect: ElementSolution,
    pub caustic: ElementSolution,
}

/// Frame-by-frame DEPT.
#[derive(Clone, Debug, Default)]
pub struct Dept {
    pub settings: DeptSettings,
}

impl Dept {
    pub fn new(settings: DeptSettings) -> Self {
        Dept { settings }
    }

    /// Photon pass and reconstruction of frame `frame` (photons `frame·N .. (frame+1)·N`).
    pub fn solve(&self, scene: &FrameScene, frame: u32) -> DeptFrame {
        let s = &self.settings;
        let mesh = ElementMesh::build(scene, s.elements);
        let elements = FrameElements::new(scene, &mesh);
        let first = frame as u64 * s.photons;
        let photons = deposit_photons(scene, &mesh, first..first + s.photons, s.seed);
        let ind = filtered_irradiance(&mesh, &photons.indirect, &elements, s.filter);
        let cau = filtered_irradiance(&mesh, &photons.caustic, &elements, s.filter);
        DeptFrame {
            indirect: ElementSolution::from_elements(&mesh, &elements, &ind),
            caustic: ElementSolution::from_elements(&mesh, &elements, &cau),
            mesh,
            elements,
            photons,
        }
    }

    /// Eye pass over a solved frame.
    pub fn render_solved(
        &self,
        scene: &FrameScene,
        frame: u32,
        solved: &DeptFrame,
        progress: &(dyn Fn(u64) + Sync),
    ) -> RenderedFrame {
        let mut img = render_view(
            &self.settings,
            scene,
            frame,
            &solved.mesh,
            &solved.indirect,
            &solved.caustic,
            progress,
        );
        img.stats.rays += solved.photons.stats.rays;
        img
    }
}

/// Eye pass over an element solution (camera samples, seed and specular depth from
/// `settings`).
pub fn render_view(
    settings: &DeptSettings,
    scene: &FrameScene,
    frame: u32,
    mesh: &ElementMesh,
    indirect: &ElementSolution,
    caustic: &ElementSolution,
    progress: &(dyn Fn(u64) + Sync),
) -> RenderedFrame {
    let view = view::DeptView {
        mesh,
        indirect,
        caustic,
        max_specular_depth: settings.max_specular_depth,
    };
    render_camera_rays(&view, scene, frame, settings.spp, settings.seed, progress)
}

impl Integrator for Dept {
    fn render(
        &self,
        scene: &FrameScene,
        frame: u32,
        progress: &(dyn Fn(u64) + Sync),
    ) -> RenderedFrame {
        let solved = self.solve(scene, frame);
        self.render_solved(scene, frame, &solved, progress)
    }
}
