//! Photon tracing with density estimation on mesh elements (DEPT), frame by frame: the
//! baselines `dept` (no filtering), `dept-spatial` (spatial Gaussian over elements) and
//! `dept-bilateral` (spatial bilateral), and the per-frame building blocks the space-time
//! technique reuses.
//!
//! Per frame `f` with `N` photons: photons `f·N .. (f+1)·N` of the Halton stream (so the
//! union of consecutive frames' photons is one contiguous Halton range) are traced by
//! [`crate::kernels::photon`] and their flux summed on the elements of
//! [`element_map::ElementMesh`]; [`reconstruct`] turns the sums into a smooth irradiance
//! field; [`view`] renders eye rays with per-pixel direct light and element indirect light
//! (as a reader of the shared eye walk, [`crate::kernels::eye`]).

pub mod budget;
pub mod element_map;
pub mod reconstruct;
pub mod reuse;
pub mod view;

use crate::framework::integrator::{Integrator, RenderedFrame, render_camera_rays};
use budget::{AutoPhotons, PhotonCount, assess, luminances, next_total};
use chronolux_core::color::{Rgb, luminance};
use chronolux_core::scene::frame::FrameScene;
use element_map::{ElementMesh, FrameElements, FramePhotons, deposit_more_photons};
use reconstruct::{ElementSolution, Filter, filtered_irradiance_sigma};

/// Settings of the frame-by-frame DEPT baselines.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct DeptSettings {
    /// Camera samples, path depth and seed ([`crate::framework::technique::CommonSettings`]). `spp`:
    /// Camera samples per pixel (direct light and anti-aliasing). Default 16. `max_depth`:
    /// Longest path in segments from the camera (`--max-depth`, Mitsuba's `max_depth`):
    /// photons of at most `max_depth − 2` scattering events are deposited and the eye pass
    /// stops at the same depth ([`view`], "Path depth"). `None` (default): unlimited.
    /// `seed`: Seed of the photon and camera streams. Default 0.
    #[serde(flatten)]
    pub common: crate::framework::technique::CommonSettings,
    /// Photons emitted per frame when `auto` is not set. Default 500 000.
    pub photons: u64,
    /// Stopping rule choosing the photons of each frame ([`budget`]); `None`: `photons`.
    pub auto: Option<AutoPhotons>,
    /// Target element count along the scene's bounding-box diagonal (element edge =
    /// diagonal / this). 0 (default): chosen from the photons per frame
    /// ([`element_map::auto_elements`]; with `auto`, from its `max_photons`), e.g. 19.7
    /// at 32k, 31 at the default 500k photons.
    pub elements: f32,
    /// Longest chain of specular (delta and glossy) bounces followed by eye rays.
    /// Default 8.
    pub max_specular_depth: u32,
    /// Glossy surfaces an eye path continues through before it reads the elements as
    /// uniform incident light ([`view`]). Default 2; 0 reads them at the first surface.
    pub max_glossy: u32,
    /// Filtering of the element estimates.
    pub filter: Filter,
}

impl Default for DeptSettings {
    fn default() -> Self {
        DeptSettings {
            common: crate::framework::technique::CommonSettings {
                spp: 16,
                max_depth: None,
                seed: 0,
            },
            photons: 500_000,
            auto: None,
            elements: 0.0,
            max_specular_depth: 8,
            max_glossy: 2,
            filter: Filter::None,
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

    /// These settings with `--photons` applied (`None`: unchanged).
    pub fn with_photons(mut self, p: Option<PhotonCount>) -> Self {
        match p {
            None => {}
            Some(PhotonCount::Fixed(n)) => {
                self.photons = n;
                self.auto = None;
            }
            Some(PhotonCount::Auto(a)) => self.auto = Some(a),
        }
        self
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

    /// Elements per scene diagonal: `elements`, or when 0 the automatic count for one
    /// frame's photons (with the stopping rule: its most photons).
    pub fn elements_per_diagonal(&self) -> f32 {
        let s = &self.settings;
        let photons = s.auto.map_or(s.photons, |a| a.max_photons);
        element_map::elements_per_diagonal(s.elements, photons as f64)
    }

    /// Photon pass and reconstruction of frame `frame`: photons `frame·N .. (frame+1)·N`
    /// for a fixed count `N`; with the stopping rule, the first photons of
    /// `frame·max_photons ..`, in batches until [`budget::next_total`] says stop.
    pub fn solve(&self, scene: &FrameScene, frame: u32) -> DeptFrame {
        let s = &self.settings;
        let mesh = ElementMesh::build(scene, self.elements_per_diagonal());
        let elements = FrameElements::new(scene, &mesh);
        let mut photons = FramePhotons::new(mesh.element_count());
        let (base, mut total) = match s.auto {
            None => (frame as u64 * s.photons, s.photons),
            Some(a) => (
                frame as u64 * a.max_photons,
                a.batch.clamp(1, a.max_photons.max(1)),
            ),
        };
        let (ind, cau) = loop {
            let done = photons.photons();
            deposit_more_photons(
                scene,
                &mesh,
                base + done..base + total,
                s.common.seed,
                element_map::max_photon_bounces(s.common.max_depth),
                &mut photons,
            );
            let (ind, si) =
                filtered_irradiance_sigma(&mesh, &photons.indirect, &elements, s.filter);
            let (cau, sc) = filtered_irradiance_sigma(&mesh, &photons.caustic, &elements, s.filter);
            let Some(rule) = s.auto else {
                break (ind, cau);
            };
            let a = assess_frame(&rule, &mesh, &elements, &photons, &ind, &cau, &si, &sc);
            log::debug!(
                "dept frame {frame}: {total} photons, {:.1} % of the power-weighted surface above the {} contrast threshold, {} photons predicted",
                100.0 * a.fraction_above,
                rule.weber,
                a.predicted_photons
            );
            match next_total(&rule, total, &a) {
                Some(t) => total = t,
                None => break (ind, cau),
            }
        };
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

/// The stopping rule's verdict on a frame's reconstruction: indirect + caustic estimates
/// and their standard errors per element side, against the direct irradiance of the same
/// photons' first hits (Gaussian-smoothed over 2.5 elements, it only sets the contrast).
#[allow(clippy::too_many_arguments)]
pub fn assess_frame(
    rule: &AutoPhotons,
    mesh: &ElementMesh,
    elements: &FrameElements,
    photons: &FramePhotons,
    ind: &[Rgb],
    cau: &[Rgb],
    sigma_ind: &[f32],
    sigma_cau: &[f32],
) -> budget::NoiseAssessment {
    let (direct, _) = filtered_irradiance_sigma(
        mesh,
        &photons.direct,
        elements,
        Filter::Gaussian { radius: 2.5 },
    );
    let lum: Vec<f32> = ind
        .iter()
        .zip(cau)
        .map(|(a, b)| luminance(*a + *b))
        .collect();
    let sigma: Vec<f32> = sigma_ind
        .iter()
        .zip(sigma_cau)
        .map(|(a, b)| (a * a + b * b).sqrt())
        .collect();
    assess(
        rule,
        photons.photons(),
        &lum,
        &sigma,
        &luminances(&direct),
        |slot| elements.area[slot / 2],
    )
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
        max_glossy: settings.max_glossy,
        max_depth: settings.common.max_depth,
    };
    render_camera_rays(
        &view,
        scene,
        frame,
        settings.common.spp,
        settings.common.seed,
        progress,
    )
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

    fn separates_light(&self) -> bool {
        true
    }
}
