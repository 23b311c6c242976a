//! Intel Embree 4 as the ray-query backend, loaded at run time.
//!
//! Why Embree and not a faster traversal of our own: Mitsuba 3 and Cycles, the peers every
//! figure is measured against, trace their CPU rays with Embree, whose 4-, 8- and 16-wide
//! BVHs with spatial splits and hand-vectorised AVX2/AVX-512 kernels took Intel a decade;
//! on the same rays our CWBVH traversal (obvhs) did 0.5–0.7× its closest-hit and
//! 0.35–0.45× its shadow rays (the first run, 2026-11-22: bench-results/HISTORY.md §2;
//! BENCHMARKS.md, "The ray core on Embree", has the current figures). Calling the same
//! kernel gives the same speed by construction, so the work here is the binding, not a
//! race.
//!
//! Nothing is linked: like the denoiser, the library is opened with `dlopen` when the first
//! structure is built, so a build or machine without it still renders (on [`super`]'s own
//! BVH, saying why once). Where it is looked for, in order:
//! 1. `CHRONOLUX_EMBREE_LIB` (a path to `libembree4.so.4` or any file of that API);
//! 2. the path the build found or fetched (`CHRONOLUX_EMBREE_BUILD_LIB`, baked in by
//!    `build.rs`: pkg-config `embree4`, else the `embreex` wheel from PyPI, Embree 4.4's
//!    release build with its TBB);
//! 3. `libembree4.so.4` on the system's library path.
//!
//! `CHRONOLUX_ACCEL=bvh` keeps the own BVH even where Embree loads (for comparisons);
//! `CHRONOLUX_ACCEL=embree` makes a failure to load an error message on every build
//! instead of a silent fallback.
//!
//! What is mapped: a [`Blas`](super::Blas) becomes an Embree scene with one triangle
//! geometry (primitive *i* is the BLAS's triangle *i*), an [`Accel`](super::Accel) with
//! more than one instance (or a transformed one) a top-level Embree scene: for a small
//! frame (≤ [`super::FLAT_MAX`] triangles) one flat scene of world-space triangles, one
//! geometry per instance (Embree's instance level cost 15–20 % of its ray rate on a
//! Cornell box), else instance geometries; either way the ids are the instance indices. Alpha-tested BLASes (the `accept` filter)
//! keep the own BVH: Embree's filter callbacks cannot call a Rust closure without a
//! context trampoline, and such content is rare; an `Accel` with one of them uses the own
//! top level over mixed BLASes. Queries are single rays (`rtcIntersect1`,
//! `rtcOccluded1`), as our kernels issue them; Embree's queries are thread-safe and
//! deterministic per ray, so images stay independent of the thread count.

use std::ffi::{CStr, CString, c_char, c_void};
use std::sync::OnceLock;

type RtcDevice = *mut c_void;
type RtcScene = *mut c_void;
type RtcGeometry = *mut c_void;

const GEOMETRY_TYPE_TRIANGLE: i32 = 0;
const GEOMETRY_TYPE_INSTANCE: i32 = 121;
const BUFFER_TYPE_INDEX: i32 = 0;
const BUFFER_TYPE_VERTEX: i32 = 1;
const FORMAT_UINT3: i32 = 0x5003;
const FORMAT_FLOAT3: i32 = 0x9003;
const FORMAT_FLOAT3X4_COLUMN_MAJOR: i32 = 0x9234;
const BUILD_QUALITY_MEDIUM: i32 = 1;
const BUILD_QUALITY_HIGH: i32 = 2;
const INVALID_ID: u32 = u32::MAX;

/// `RTCRay`: a ray of the open interval `0 < t < tmax` (the own BVH's). Embree's triangle
/// test accepts `tnear·|den| < T ≤ tfar·|den|` (`T` = t·|den| before the division), so
/// `tnear = 0` already excludes t = 0 and only the far end is moved one float inwards.
///
/// `tnear` is 0, not the smallest positive float (as until 2026-12-08): that product
/// `tnear·|den|` is then a subnormal in every triangle test, and subnormal arithmetic
/// without flush-to-zero (which our threads do not set: it would change the shading's
/// floats) took 12 % of the single-ray and 25–35 % of the packet rate on the AMD EPYC
/// (BENCHMARKS.md, "The ray core on Embree"). Mitsuba passes 0 as well.
#[repr(C, align(16))]
struct RtcRay {
    org: [f32; 3],
    tnear: f32,
    dir: [f32; 3],
    time: f32,
    tfar: f32,
    mask: u32,
    id: u32,
    flags: u32,
}

impl RtcRay {
    fn new(org: [f32; 3], dir: [f32; 3], tmax: f32) -> RtcRay {
        RtcRay {
            org,
            tnear: 0.0,
            dir,
            time: 0.0,
            tfar: tmax.next_down(),
            mask: u32::MAX,
            id: 0,
            flags: 0,
        }
    }
}

/// `RTCHit` (Embree 4, one instance level), with one spare word for builds with instance
/// arrays (`instPrimID`), which Embree writes after `instID`.
#[repr(C, align(16))]
struct RtcHit {
    ng: [f32; 3],
    u: f32,
    v: f32,
    prim_id: u32,
    geom_id: u32,
    inst_id: [u32; 1],
    inst_prim_id: [u32; 1],
}

impl RtcHit {
    const NONE: RtcHit = RtcHit {
        ng: [0.0; 3],
        u: 0.0,
        v: 0.0,
        prim_id: INVALID_ID,
        geom_id: INVALID_ID,
        inst_id: [INVALID_ID],
        inst_prim_id: [INVALID_ID],
    };
}

/// `RTCRayHit`.
#[repr(C)]
struct RayHit {
    ray: RtcRay,
    hit: RtcHit,
}

/// Rays per packet query (`rtcIntersect16`: one AVX-512 register per field; on AVX2
/// machines Embree runs it as two 8-wide halves).
pub const PACKET: usize = 16;

/// `RTCRay16`: structure of arrays, one lane per ray, as [`RtcRay`].
#[repr(C, align(64))]
struct Ray16 {
    org: [[f32; PACKET]; 3],
    tnear: [f32; PACKET],
    dir: [[f32; PACKET]; 3],
    time: [f32; PACKET],
    tfar: [f32; PACKET],
    mask: [u32; PACKET],
    id: [u32; PACKET],
    flags: [u32; PACKET],
}

impl Ray16 {
    /// The first `rays.len()` (≤ [`PACKET`]) lanes from `rays`, the rest unused.
    fn new(rays: &[PacketRay]) -> Ray16 {
        let mut p = Ray16 {
            org: [[0.0; PACKET]; 3],
            tnear: [0.0; PACKET],
            dir: [[0.0; PACKET]; 3],
            time: [0.0; PACKET],
            tfar: [0.0; PACKET],
            mask: [u32::MAX; PACKET],
            id: [0; PACKET],
            flags: [0; PACKET],
        };
        for (k, (o, d, tmax)) in rays.iter().take(PACKET).enumerate() {
            for a in 0..3 {
                p.org[a][k] = o[a];
                p.dir[a][k] = d[a];
            }
            p.tfar[k] = tmax.next_down();
        }
        p
    }
}

/// `RTCHit16`, with the spare `instPrimID` lanes as [`RtcHit`].
#[repr(C, align(64))]
struct Hit16 {
    ng: [[f32; PACKET]; 3],
    u: [f32; PACKET],
    v: [f32; PACKET],
    prim_id: [u32; PACKET],
    geom_id: [u32; PACKET],
    inst_id: [u32; PACKET],
    inst_prim_id: [u32; PACKET],
}

/// `RTCRayHit16`.
#[repr(C)]
struct RayHit16 {
    ray: Ray16,
    hit: Hit16,
}

// The C layouts the structs mirror (Embree 4's rtcore_ray.h): the hit starts right after
// the ray, 48 bytes for one ray and 12 lanes × 64 bytes for a packet.
const _: () = {
    assert!(std::mem::size_of::<RtcRay>() == 48);
    assert!(std::mem::offset_of!(RayHit, hit) == 48);
    assert!(std::mem::offset_of!(RayHit16, hit) == 12 * 4 * PACKET);
};

/// `valid` mask of a packet: −1 for the first `n` lanes.
#[repr(C, align(64))]
struct Valid16([i32; PACKET]);

impl Valid16 {
    fn first(n: usize) -> Valid16 {
        let mut v = [0; PACKET];
        v[..n].fill(-1);
        Valid16(v)
    }
}

/// A ray of a packet query: origin, direction, `tmax` (the open interval `0 < t < tmax`).
pub type PacketRay = ([f32; 3], [f32; 3], f32);

type ErrorFn = unsafe extern "C" fn(*mut c_void, i32, *const c_char);

/// The entry points used, resolved once.
struct Api {
    _lib: libloading::Library,
    device: RtcDevice,
    new_scene: unsafe extern "C" fn(RtcDevice) -> RtcScene,
    set_scene_build_quality: unsafe extern "C" fn(RtcScene, i32),
    commit_scene: unsafe extern "C" fn(RtcScene),
    release_scene: unsafe extern "C" fn(RtcScene),
    new_geometry: unsafe extern "C" fn(RtcDevice, i32) -> RtcGeometry,
    set_new_geometry_buffer:
        unsafe extern "C" fn(RtcGeometry, i32, u32, i32, usize, usize) -> *mut c_void,
    set_geometry_build_quality: unsafe extern "C" fn(RtcGeometry, i32),
    set_geometry_instanced_scene: unsafe extern "C" fn(RtcGeometry, RtcScene),
    set_geometry_transform: unsafe extern "C" fn(RtcGeometry, u32, i32, *const c_void),
    commit_geometry: unsafe extern "C" fn(RtcGeometry),
    attach_geometry_by_id: unsafe extern "C" fn(RtcScene, RtcGeometry, u32),
    release_geometry: unsafe extern "C" fn(RtcGeometry),
    get_device_error: unsafe extern "C" fn(RtcDevice) -> i32,
    intersect1: unsafe extern "C" fn(RtcScene, *mut RayHit, *mut c_void),
    occluded1: unsafe extern "C" fn(RtcScene, *mut RtcRay, *mut c_void),
    intersect16: unsafe extern "C" fn(*const i32, RtcScene, *mut RayHit16, *mut c_void),
    occluded16: unsafe extern "C" fn(*const i32, RtcScene, *mut Ray16, *mut c_void),
}

// SAFETY: the device handle is only used through Embree's API, which is thread-safe for
// creating scenes and for queries on committed scenes.
unsafe impl Send for Api {}
unsafe impl Sync for Api {}

unsafe extern "C" fn on_error(_: *mut c_void, code: i32, msg: *const c_char) {
    let text = if msg.is_null() {
        String::new()
    } else {
        // SAFETY: Embree passes a NUL-terminated message valid for the call.
        unsafe { CStr::from_ptr(msg) }
            .to_string_lossy()
            .into_owned()
    };
    log::error!("Embree error {code}: {text}");
}

/// Candidate library paths, in the order of the module docs.
fn candidates() -> Vec<String> {
    let mut out = Vec::new();
    if let Some(p) = std::env::var_os("CHRONOLUX_EMBREE_LIB") {
        out.push(p.to_string_lossy().into_owned());
    }
    if let Some(p) = option_env!("CHRONOLUX_EMBREE_BUILD_LIB").filter(|p| !p.is_empty()) {
        out.push(p.to_string());
    }
    out.push("libembree4.so.4".to_string());
    out
}

fn open() -> Result<Api, String> {
    let mut tried = Vec::new();
    let mut found = None;
    for path in candidates() {
        // SAFETY: loading Embree runs its (and TBB's) initialisers, which have no
        // preconditions.
        match unsafe { libloading::Library::new(&path) } {
            Ok(lib) => {
                found = Some((lib, path));
                break;
            }
            Err(e) => {
                let why = if path.contains('/') && !std::path::Path::new(&path).exists() {
                    "no such file".to_string()
                } else {
                    std::error::Error::source(&e).map_or(e.to_string(), |s| s.to_string())
                };
                tried.push(format!("{path}: {why}"))
            }
        }
    }
    let Some((lib, path)) = found else {
        let note = option_env!("CHRONOLUX_EMBREE_BUILD_NOTE").unwrap_or("");
        return Err(format!(
            "Embree 4 not found ({}{})",
            tried.join("; "),
            if note.is_empty() {
                String::new()
            } else {
                format!("; at build time: {note}")
            }
        ));
    };
    macro_rules! sym {
        ($name:literal) => {
            // SAFETY: the symbol's type is Embree 4's C declaration of that name.
            *unsafe { lib.get(concat!($name, "\0").as_bytes()) }
                .map_err(|e| format!("{path} has no {}: {e}", $name))?
        };
    }
    let new_device: unsafe extern "C" fn(*const c_char) -> RtcDevice = sym!("rtcNewDevice");
    let set_error: unsafe extern "C" fn(RtcDevice, Option<ErrorFn>, *mut c_void) =
        sym!("rtcSetDeviceErrorFunction");
    let config = CString::new("verbose=0").expect("no NUL");
    // SAFETY: a valid C string; a null device is handled below.
    let device = unsafe { new_device(config.as_ptr()) };
    if device.is_null() {
        return Err(format!(
            "{path} loaded but rtcNewDevice failed (CPU not supported?)"
        ));
    }
    // SAFETY: `on_error` matches RTCErrorFunction and needs no user pointer.
    unsafe { set_error(device, Some(on_error), std::ptr::null_mut()) };
    let api = Api {
        device,
        new_scene: sym!("rtcNewScene"),
        set_scene_build_quality: sym!("rtcSetSceneBuildQuality"),
        commit_scene: sym!("rtcCommitScene"),
        release_scene: sym!("rtcReleaseScene"),
        new_geometry: sym!("rtcNewGeometry"),
        set_new_geometry_buffer: sym!("rtcSetNewGeometryBuffer"),
        set_geometry_build_quality: sym!("rtcSetGeometryBuildQuality"),
        set_geometry_instanced_scene: sym!("rtcSetGeometryInstancedScene"),
        set_geometry_transform: sym!("rtcSetGeometryTransform"),
        commit_geometry: sym!("rtcCommitGeometry"),
        attach_geometry_by_id: sym!("rtcAttachGeometryByID"),
        release_geometry: sym!("rtcReleaseGeometry"),
        get_device_error: sym!("rtcGetDeviceError"),
        intersect1: sym!("rtcIntersect1"),
        occluded1: sym!("rtcOccluded1"),
        intersect16: sym!("rtcIntersect16"),
        occluded16: sym!("rtcOccluded16"),
        _lib: lib,
    };
    log::info!("ray queries on Embree ({path})");
    Ok(api)
}

/// Which ray-query backend builds the structures of this process.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Backend {
    /// Embree, loaded from the path given.
    Embree,
    /// Our own CWBVH; the string says why not Embree.
    Own(String),
}

struct State {
    api: Option<Api>,
    backend: Backend,
}

fn state() -> &'static State {
    static STATE: OnceLock<State> = OnceLock::new();
    STATE.get_or_init(|| {
        let choice = std::env::var("CHRONOLUX_ACCEL").unwrap_or_default();
        if choice == "bvh" {
            return State {
                api: None,
                backend: Backend::Own("CHRONOLUX_ACCEL=bvh".into()),
            };
        }
        match open() {
            Ok(api) => State {
                api: Some(api),
                backend: Backend::Embree,
            },
            Err(why) => {
                if choice == "embree" {
                    log::error!("CHRONOLUX_ACCEL=embree but {why}");
                } else {
                    log::warn!(
                        "{why}: ray queries on the built-in BVH (up to 1.8x slower on large scenes)"
                    );
                }
                State {
                    api: None,
                    backend: Backend::Own(why),
                }
            }
        }
    })
}

fn api() -> Option<&'static Api> {
    state().api.as_ref()
}

/// The backend of this process (loads Embree on first call).
pub fn backend() -> &'static Backend {
    &state().backend
}

/// A short name for records (`run.json`, `info`): "embree" or "bvh".
pub fn backend_name() -> &'static str {
    match backend() {
        Backend::Embree => "embree",
        Backend::Own(_) => "bvh",
    }
}

/// A committed Embree scene (released on drop).
pub struct Scene {
    raw: RtcScene,
}

// SAFETY: a committed scene is immutable and Embree's queries on it are thread-safe.
unsafe impl Send for Scene {}
unsafe impl Sync for Scene {}

impl Drop for Scene {
    fn drop(&mut self) {
        if let Some(api) = api() {
            // SAFETY: `raw` came from rtcNewScene and is released once.
            unsafe { (api.release_scene)(self.raw) };
        }
    }
}

/// The hit of a query: t, primitive, barycentrics of vertices 1 and 2, instance (or
/// `u32::MAX` when the scene has no instance level) and geometry id in its scene.
pub struct RawHit {
    pub t: f32,
    pub prim: u32,
    pub u: f32,
    pub v: f32,
    pub instance: u32,
    pub geom: u32,
}

impl Scene {
    /// A scene over a triangle soup (`tris[i]` is primitive *i*), or `None` if Embree is not
    /// the backend or the build failed (the caller keeps its own BVH).
    pub fn triangles(tris: &[[[f32; 3]; 3]]) -> Option<Scene> {
        Self::soups(&[(0, tris)], BUILD_QUALITY_HIGH)
    }

    /// A flat scene of several soups, `(geometry id, triangles)`: hits report the id as
    /// [`RawHit::geom`]. Built at Embree's default (medium) quality: it is made per frame.
    pub fn flat(soups: &[(u32, &[[[f32; 3]; 3]])]) -> Option<Scene> {
        Self::soups(soups, BUILD_QUALITY_MEDIUM)
    }

    fn soups(soups: &[(u32, &[[[f32; 3]; 3]])], quality: i32) -> Option<Scene> {
        let api = api()?;
        if soups.iter().any(|(_, t)| t.len() > (u32::MAX / 3) as usize) {
            return None;
        }
        // SAFETY: every handle below comes from the call before it; the buffers are
        // Embree-allocated with exactly the sizes written.
        unsafe {
            let scene = (api.new_scene)(api.device);
            if scene.is_null() {
                return None;
            }
            (api.set_scene_build_quality)(scene, quality);
            for (id, tris) in soups.iter().filter(|(_, t)| !t.is_empty()) {
                let n = tris.len();
                let geom = (api.new_geometry)(api.device, GEOMETRY_TYPE_TRIANGLE);
                if geom.is_null() {
                    (api.release_scene)(scene);
                    return None;
                }
                let verts = (api.set_new_geometry_buffer)(
                    geom,
                    BUFFER_TYPE_VERTEX,
                    0,
                    FORMAT_FLOAT3,
                    12,
                    3 * n,
                ) as *mut [f32; 3];
                let index =
                    (api.set_new_geometry_buffer)(geom, BUFFER_TYPE_INDEX, 0, FORMAT_UINT3, 12, n)
                        as *mut [u32; 3];
                if verts.is_null() || index.is_null() {
                    (api.release_geometry)(geom);
                    (api.release_scene)(scene);
                    return None;
                }
                let verts = std::slice::from_raw_parts_mut(verts, 3 * n);
                let index = std::slice::from_raw_parts_mut(index, n);
                for (i, t) in tris.iter().enumerate() {
                    verts[3 * i..3 * i + 3].copy_from_slice(t);
                    let b = 3 * i as u32;
                    index[i] = [b, b + 1, b + 2];
                }
                (api.set_geometry_build_quality)(geom, quality);
                (api.commit_geometry)(geom);
                (api.attach_geometry_by_id)(scene, geom, *id);
                (api.release_geometry)(geom);
            }
            (api.commit_scene)(scene);
            let out = Scene { raw: scene };
            ((api.get_device_error)(api.device) == 0).then_some(out)
        }
    }

    /// A top-level scene: `instances[k] = (id, scene, world_from_object as 3×4
    /// column-major)`; hits report `id` as their instance.
    pub fn instances(instances: &[(u32, &Scene, [f32; 12])]) -> Option<Scene> {
        let api = api()?;
        // SAFETY: as in `triangles`; the instanced scenes are committed and outlive this
        // one (the caller holds them in the same `Accel`).
        unsafe {
            let scene = (api.new_scene)(api.device);
            if scene.is_null() {
                return None;
            }
            for (id, inner, xfm) in instances {
                let geom = (api.new_geometry)(api.device, GEOMETRY_TYPE_INSTANCE);
                if geom.is_null() {
                    (api.release_scene)(scene);
                    return None;
                }
                (api.set_geometry_instanced_scene)(geom, inner.raw);
                (api.set_geometry_transform)(
                    geom,
                    0,
                    FORMAT_FLOAT3X4_COLUMN_MAJOR,
                    xfm.as_ptr() as *const c_void,
                );
                (api.commit_geometry)(geom);
                (api.attach_geometry_by_id)(scene, geom, *id);
                (api.release_geometry)(geom);
            }
            (api.commit_scene)(scene);
            let out = Scene { raw: scene };
            ((api.get_device_error)(api.device) == 0).then_some(out)
        }
    }

    /// Closest hit with `0 < t < tmax`.
    #[inline]
    pub fn intersect(&self, o: [f32; 3], d: [f32; 3], tmax: f32) -> Option<RawHit> {
        // A `Scene` exists only where the API loaded.
        let api = api()?;
        let mut rh = RayHit {
            ray: RtcRay::new(o, d, tmax),
            hit: RtcHit::NONE,
        };
        // SAFETY: a committed scene and a properly aligned, initialised RTCRayHit.
        unsafe { (api.intersect1)(self.raw, &mut rh, std::ptr::null_mut()) };
        let h = &rh.hit;
        (h.geom_id != INVALID_ID).then_some(RawHit {
            t: rh.ray.tfar,
            prim: h.prim_id,
            u: h.u,
            v: h.v,
            instance: h.inst_id[0],
            geom: h.geom_id,
        })
    }

    /// Whether anything lies along the ray with `0 < t < tmax`.
    #[inline]
    pub fn occluded(&self, o: [f32; 3], d: [f32; 3], tmax: f32) -> bool {
        let Some(api) = api() else {
            return false;
        };
        let mut r = RtcRay::new(o, d, tmax);
        // SAFETY: a committed scene and a properly aligned, initialised RTCRay.
        unsafe { (api.occluded1)(self.raw, &mut r, std::ptr::null_mut()) };
        r.tfar == f32::NEG_INFINITY
    }

    /// Closest hits of up to [`PACKET`] rays at once (`out[k]` for `rays[k]`).
    pub fn intersect_packet(&self, rays: &[PacketRay], out: &mut [Option<RawHit>]) {
        let n = rays.len().min(PACKET);
        let Some(api) = api() else {
            out[..n].iter_mut().for_each(|o| *o = None);
            return;
        };
        let mut p = RayHit16 {
            ray: Ray16::new(&rays[..n]),
            hit: Hit16 {
                ng: [[0.0; PACKET]; 3],
                u: [0.0; PACKET],
                v: [0.0; PACKET],
                prim_id: [INVALID_ID; PACKET],
                geom_id: [INVALID_ID; PACKET],
                inst_id: [INVALID_ID; PACKET],
                inst_prim_id: [INVALID_ID; PACKET],
            },
        };
        let valid = Valid16::first(n);
        // SAFETY: a committed scene, a 64-byte-aligned RTCRayHit16 and valid mask.
        unsafe { (api.intersect16)(valid.0.as_ptr(), self.raw, &mut p, std::ptr::null_mut()) };
        let h = &p.hit;
        for (k, o) in out[..n].iter_mut().enumerate() {
            *o = (h.geom_id[k] != INVALID_ID).then_some(RawHit {
                t: p.ray.tfar[k],
                prim: h.prim_id[k],
                u: h.u[k],
                v: h.v[k],
                instance: h.inst_id[k],
                geom: h.geom_id[k],
            });
        }
    }

    /// Occlusion of up to [`PACKET`] rays at once.
    pub fn occluded_packet(&self, rays: &[PacketRay], out: &mut [bool]) {
        let n = rays.len().min(PACKET);
        let Some(api) = api() else {
            out[..n].fill(false);
            return;
        };
        let mut p = Ray16::new(&rays[..n]);
        let valid = Valid16::first(n);
        // SAFETY: a committed scene, a 64-byte-aligned RTCRay16 and valid mask.
        unsafe { (api.occluded16)(valid.0.as_ptr(), self.raw, &mut p, std::ptr::null_mut()) };
        for (k, o) in out[..n].iter_mut().enumerate() {
            *o = p.tfar[k] == f32::NEG_INFINITY;
        }
    }
}
