//! The viewer's render loop state: the edited scene, its SPT photon pool and the image
//! being refined.
//!
//! - **After an edit** ([`Viewer::edit`]) the frame is rebuilt, [`FrameDelta`] between the
//!   old and new frame is taken, the pool's pilots and path scan queue the groups the
//!   change invalidated ([`SptState::invalidate`]), and one camera pass is rendered at
//!   once: its direct light (next-event estimation per pixel) is already the new scene's,
//!   its indirect light the partly updated pool's.
//! - **While groups are queued** ([`Viewer::step`]) one slice of the queue is re-shot
//!   (at most [`ViewOptions::slice`] of wall-clock time, whole groups, in priority order)
//!   and a fresh pass is rendered: the image restarts because its indirect light changed.
//! - **Once the queue is empty** each step adds one more sample per pixel to the image
//!   (progressive refinement) until [`ViewOptions::max_spp`]; then the loop is idle.
//!
//! A topology change (an edit that changes the light count, e.g. an emissive mesh
//! switched off) cannot be carried over by the pool; a new pool is shot, as `spt` does in
//! a sequence.

use crate::scene::{Edit, EditableScene};
use anyhow::Result;
use chronolux_core::color::Rgb;
use chronolux_core::scene::delta::FrameDelta;
use chronolux_core::scene::desc::{AnimationId, SceneDesc};
use chronolux_core::scene::frame::{CameraChoice, FrameScene};
use chronolux_io::image::{Image, View, auto_exposure, tonemap_view_srgb8};
use chronolux_render::framework::integrator::render_camera_rays;
use chronolux_render::kernels::elements::reconstruct::ElementSolution;
use chronolux_render::techniques::spt::pool::{Budget, SptState};
use chronolux_render::techniques::spt::{SptSettings, reconstruct, view::SptView};
use serde::Serialize;
use std::sync::Arc;
use std::time::{Duration, Instant};

/// Settings of the viewer's loop.
#[derive(Clone, Debug)]
pub struct ViewOptions {
    /// Photons in the SPT pool.
    pub photons: u64,
    /// Samples per pixel at which refinement stops.
    pub max_spp: u32,
    /// Wall-clock time of one slice of queue re-shooting (checked between batches of
    /// groups, so a slice may overrun by one batch).
    pub slice: Duration,
}

impl Default for ViewOptions {
    fn default() -> Self {
        ViewOptions {
            photons: 100_000,
            max_spp: 256,
            slice: Duration::from_millis(150),
        }
    }
}

/// What the page shows beside the image.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct Status {
    /// Id of the last edit applied (0: none yet).
    pub edit: u64,
    /// SPT groups still queued for re-shooting.
    pub queued: usize,
    /// Seconds since the last edit (or since the pool was shot, before any edit).
    pub seconds_since_change: f64,
    /// Seconds from the last edit until the queue was empty (`None` while it is not).
    pub settled_after: Option<f64>,
    /// Groups the last edit invalidated.
    pub invalidated: u64,
    /// Photons traced since the last edit (pilots included).
    pub photons_since_change: u64,
    /// Samples per pixel in the image.
    pub spp: u32,
    /// Animation time of the frame.
    pub t: f32,
    /// Photons in the pool and its group count.
    pub pool: u64,
    pub groups: u64,
    /// Times a new pool had to be shot (topology changes).
    pub rebuilds: u32,
}

/// One displayed image.
#[derive(Clone, Debug)]
pub struct Frame {
    pub width: u32,
    pub height: u32,
    /// Display-encoded sRGB pixels, row-major from the top.
    pub rgb8: Vec<[u8; 3]>,
    pub status: Status,
}

impl Frame {
    /// The image as PNG, with fast compression (it is sent many times a second).
    pub fn png(&self) -> Vec<u8> {
        let mut out = Vec::new();
        {
            let mut enc = png::Encoder::new(&mut out, self.width, self.height);
            enc.set_color(png::ColorType::Rgb);
            enc.set_depth(png::BitDepth::Eight);
            enc.set_compression(png::Compression::Fast);
            let mut w = enc
                .write_header()
                .expect("PNG header into memory cannot fail");
            w.write_image_data(self.rgb8.as_flattened())
                .expect("PNG data of the right size into memory cannot fail");
        }
        out
    }
}

/// The render loop state; see the module documentation.
pub struct Viewer {
    scene: EditableScene,
    state: SptState,
    options: ViewOptions,
    /// The reconstructed indirect and caustic fields of the current solution.
    fields: Option<(ElementSolution, ElementSolution)>,
    sum: Vec<Rgb>,
    spp: u32,
    exposure: Option<f32>,
    changed_at: Instant,
    status: Status,
}

impl Viewer {
    /// Loads the scene, shoots the pool (the slow part: every photon of the pool).
    pub fn new(
        desc: SceneDesc,
        anim: Option<AnimationId>,
        camera: CameraChoice,
        width: u32,
        height: u32,
        options: ViewOptions,
    ) -> Result<Viewer> {
        let (scene, frame) = EditableScene::new(desc, anim, camera, width, height)?;
        Ok(Self::from_scene(scene, frame, options))
    }

    /// [`Viewer::new`] from a scene already loaded (and its first frame).
    pub fn from_scene(scene: EditableScene, frame: FrameScene, options: ViewOptions) -> Viewer {
        let state = SptState::new(Arc::new(frame), settings(&options));
        let n = pixel_count(&state);
        let status = Status {
            t: scene.time(),
            pool: state.layout.photons(),
            groups: state.layout.groups,
            photons_since_change: state.layout.photons(),
            settled_after: Some(0.0),
            ..Default::default()
        };
        Viewer {
            scene,
            state,
            options,
            fields: None,
            sum: vec![Rgb::ZERO; n],
            spp: 0,
            exposure: None,
            changed_at: Instant::now(),
            status,
        }
    }

    /// The edited scene.
    pub fn scene(&self) -> &EditableScene {
        &self.scene
    }

    /// SPT groups queued for re-shooting.
    pub fn queued(&self) -> usize {
        self.state.queue_len()
    }

    /// Applies the edits `edits` (with ids; the last id is reported), updates the pool's
    /// queue and renders the first pass at once. An edit that fails its check is
    /// skipped and its message returned (the others still apply).
    pub fn edit(&mut self, edits: &[(u64, Edit)]) -> (Frame, Vec<String>) {
        let mut errors = Vec::new();
        for (id, e) in edits {
            if let Err(msg) = self.scene.apply(e) {
                errors.push(msg);
            }
            self.status.edit = self.status.edit.max(*id);
        }
        self.changed_at = Instant::now();
        self.status.settled_after = None;
        match self.scene.build() {
            Ok(frame) => {
                let frame = Arc::new(frame);
                if self.state.accepts(&frame) {
                    let changes = FrameDelta::between(self.state.scene(), &frame);
                    let u = self.state.invalidate(frame, &changes);
                    self.status.invalidated = u.groups_invalidated;
                    self.status.photons_since_change = u.photons_traced + u.pilots_traced;
                } else {
                    self.state = SptState::new(frame, settings(&self.options));
                    self.status.rebuilds += 1;
                    self.status.invalidated = self.state.layout.groups;
                    self.status.photons_since_change = self.state.layout.photons();
                }
            }
            Err(e) => errors.push(format!("{e:#}")),
        }
        self.status.t = self.scene.time();
        self.restart_image();
        self.pass();
        (self.frame(), errors)
    }

    /// One unit of work: a slice of the queue and a fresh pass while groups are queued,
    /// else one more sample per pixel; `None` when the image has `max_spp` samples and
    /// nothing is queued (idle).
    pub fn step(&mut self) -> Option<Frame> {
        if self.state.queue_len() > 0 {
            let d = self.state.drain(Budget {
                photons: 0,
                time: Some(self.options.slice),
            });
            self.status.photons_since_change += d.photons_traced;
            if self.state.queue_len() == 0 {
                self.status.settled_after = Some(self.changed_at.elapsed().as_secs_f64());
            }
            self.restart_image();
        } else if self.spp >= self.options.max_spp {
            return None;
        }
        self.pass();
        Some(self.frame())
    }

    /// The image, after rendering its first pass if it has none yet.
    pub fn frame_after_pass(&mut self) -> Frame {
        if self.spp == 0 {
            self.pass();
        }
        self.frame()
    }

    /// Nothing queued and the image refined to `max_spp`.
    pub fn idle(&self) -> bool {
        self.state.queue_len() == 0 && self.spp >= self.options.max_spp
    }

    fn restart_image(&mut self) {
        self.fields = None;
        self.sum.iter_mut().for_each(|p| *p = Rgb::ZERO);
        self.spp = 0;
    }

    /// One sample per pixel of the eye pass over the current solution, added to the image.
    fn pass(&mut self) {
        let s = &self.state.settings;
        let (indirect, caustic) = self
            .fields
            .get_or_insert_with(|| reconstruct(&self.state, s.filter));
        let v = SptView {
            mesh: &self.state.mesh,
            indirect,
            caustic,
            max_specular_depth: s.max_specular_depth,
            max_glossy_depth: s.max_glossy_depth,
            glossy_roughness: s.glossy_roughness,
        };
        // The sample index picks the sample stream (as the frame number does for a
        // sequence): successive passes add new samples, and an image restarted over the
        // same solution repeats itself exactly.
        let f = render_camera_rays(&v, self.state.scene(), self.spp, 1, s.common.seed, &|_| {});
        for (acc, p) in self.sum.iter_mut().zip(&f.pixels) {
            *acc += *p;
        }
        self.spp += 1;
    }

    /// The image as it stands in linear RGB (the mean of its samples per pixel).
    pub fn linear(&self) -> Vec<Rgb> {
        let inv = 1.0 / self.spp.max(1) as f32;
        self.sum.iter().map(|p| *p * inv).collect()
    }

    /// The image as it stands, with the status.
    pub fn frame(&mut self) -> Frame {
        let cam = &self.state.scene().camera;
        let (w, h) = (cam.width, cam.height);
        let img = Image::from_pixels(w, h, self.linear());
        // Exposure is fixed from the first image, so edits that brighten or darken the
        // scene show as such.
        let exposure = *self
            .exposure
            .get_or_insert_with(|| auto_exposure(&img.pixels));
        self.status.queued = self.state.queue_len();
        self.status.spp = self.spp;
        self.status.seconds_since_change = self.changed_at.elapsed().as_secs_f64();
        Frame {
            width: w,
            height: h,
            rgb8: tonemap_view_srgb8(&img, exposure, View::Agx),
            status: self.status.clone(),
        }
    }
}

fn settings(o: &ViewOptions) -> SptSettings {
    SptSettings {
        photons: o.photons,
        ..SptSettings::default()
    }
}

fn pixel_count(st: &SptState) -> usize {
    let c = &st.scene().camera;
    c.width as usize * c.height as usize
}
