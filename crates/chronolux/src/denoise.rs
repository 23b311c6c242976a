//! Denoising with Intel Open Image Denoise: on by default for `render` (`--no-denoise`
//! turns it off), in the default build.
//!
//! The beauty is filtered by OIDN's `RT` filter in HDR mode with the first-hit albedo and
//! shading normal of the run's render passes ([`chronolux_render::framework::aov`]) as auxiliary
//! images; the noisy beauty is kept as a layer of the EXR (`ViewLayer.Noisy Image`).
//!
//! The library is loaded at run time, not linked, so that one build both denoises where
//! OIDN can be had and renders (undenoised, saying why) where it cannot, and so that
//! finding it needs no variable set by hand. Where it is looked for, first found wins:
//!
//! 1. `CHRONOLUX_OIDN_LIB`, the library file itself (when set, nothing else is tried: a
//!    path that does not exist is how the tests simulate a machine without OIDN);
//! 2. `$OIDN_DIR/lib` at run time;
//! 3. the folder the build found or fetched it into (`build.rs`: `OIDN_DIR`, pkg-config,
//!    or the pyoidn wheel unpacked into a user cache);
//! 4. the system's library search path (`libOpenImageDenoise.so.2`).
//!
//! One CPU device and one filter serve the whole run (loading the library and creating
//! the device cost about 0.1 s; each frame re-commits the filter with its images, and
//! OIDN rebuilds its network only when the size or the quality changes). OIDN is called through eight C functions of its stable 2.x API,
//! declared in [`ffi`]; `unsafe` is confined there.

use chronolux_core::color::Rgb;
use chronolux_render::framework::aov::Aovs;
use std::path::PathBuf;

/// Why denoising cannot be used on this machine (`None`: it can). Loads the library and
/// creates the device on the first call; the answer holds for the process.
pub fn unavailable() -> Option<String> {
    ffi::denoiser()
        .err()
        .map(|why| format!("Open Image Denoise is not available: {why}"))
}

/// The library file that denoises, once [`unavailable`] said it can.
pub fn library() -> Option<PathBuf> {
    ffi::denoiser().ok().map(|d| d.path.clone())
}

/// Open Image Denoise's filter quality (`--denoise-quality`): its networks by name.
#[derive(
    Clone,
    Copy,
    Debug,
    Default,
    PartialEq,
    Eq,
    clap::ValueEnum,
    serde::Serialize,
    serde::Deserialize,
)]
#[serde(rename_all = "kebab-case")]
pub enum DenoiseQuality {
    /// OIDN's default and best network.
    #[default]
    High,
    /// Meant for real-time use; the same network as `high` on a CPU device.
    Balanced,
    /// A smaller network: about half the filter's CPU, a higher error at equal samples.
    /// On the peers' scene, stbpt + OIDN reached HDR-FLIP 0.08 with 10 % less CPU with it
    /// on an AMD EPYC, where the filter takes 7.7 µs of CPU per pixel (BENCHMARKS.md,
    /// "Issue 17: the denoiser's cost").
    Fast,
}

fn flat3(v: impl Iterator<Item = [f32; 3]>) -> Vec<f32> {
    v.flatten().collect()
}

/// The beauty `pixels` denoised with the albedo and normal passes of `aovs`.
pub fn denoise(pixels: &[Rgb], aovs: &Aovs, quality: DenoiseQuality) -> Result<Vec<Rgb>, String> {
    let (w, h) = (aovs.width as usize, aovs.height as usize);
    if pixels.len() != w * h || aovs.albedo.len() != w * h || aovs.normal.len() != w * h {
        return Err("denoise: the beauty, albedo and normal differ in size".into());
    }
    let color = flat3(pixels.iter().map(|p| [p.x, p.y, p.z]));
    let albedo = flat3(aovs.albedo.iter().map(|p| [p.x, p.y, p.z]));
    let normal = flat3(aovs.normal.iter().map(|n| [n.x, n.y, n.z]));
    let mut out = vec![0.0f32; color.len()];
    let denoiser = ffi::denoiser().map_err(|why| format!("Open Image Denoise: {why}"))?;
    // OIDN's quality enum: DEFAULT 0, FAST 4, BALANCED 5, HIGH 6 (oidn.h).
    let q = match quality {
        DenoiseQuality::High => 6,
        DenoiseQuality::Balanced => 5,
        DenoiseQuality::Fast => 4,
    };
    denoiser
        .filter(w, h, q, &color, &albedo, &normal, &mut out)
        .map_err(|e| format!("Open Image Denoise: {e}"))?;
    Ok(out
        .chunks_exact(3)
        .map(|c| Rgb::new(c[0], c[1], c[2]))
        .collect())
}

/// The EXR channels of the passes (see `chronolux_render::framework::aov` for the conventions):
/// Blender's multilayer names `ViewLayer.<pass>.<channel>`.
pub fn pass_channels(aovs: &Aovs) -> Vec<(String, Vec<f32>)> {
    let mut out = Vec::new();
    let mut push = |pass: &str, chans: &[&str], get: &dyn Fn(usize, usize) -> f32, n: usize| {
        for (c, name) in chans.iter().enumerate() {
            out.push((
                format!("ViewLayer.{pass}.{name}"),
                (0..n).map(|k| get(k, c)).collect(),
            ));
        }
    };
    let n = (aovs.width * aovs.height) as usize;
    if !aovs.albedo.is_empty() {
        push(
            "Denoising Albedo",
            &["R", "G", "B"],
            &|k, c| aovs.albedo[k][c],
            n,
        );
    }
    if !aovs.normal.is_empty() {
        push(
            "Denoising Normal",
            &["X", "Y", "Z"],
            &|k, c| aovs.normal[k][c],
            n,
        );
    }
    if !aovs.depth.is_empty() {
        push("Depth", &["Z"], &|k, _| aovs.depth[k], n);
    }
    if !aovs.motion_prev.is_empty() {
        push(
            "Vector",
            &["X", "Y", "Z", "W"],
            &|k, c| match c {
                0 => aovs.motion_prev[k].x,
                1 => aovs.motion_prev[k].y,
                2 => aovs.motion_next[k].x,
                _ => aovs.motion_next[k].y,
            },
            n,
        );
    }
    out
}

/// The EXR channels of a technique's light split (`ViewLayer.Direct.{R,G,B}`,
/// `ViewLayer.Indirect.{R,G,B}`; they add up to the beauty, see
/// [`chronolux_render::framework::integrator::LightSplit`]).
pub fn light_channels(
    light: &chronolux_render::framework::integrator::LightSplit,
    direct: bool,
    indirect: bool,
) -> Vec<(String, Vec<f32>)> {
    let mut out = Vec::new();
    for (keep, pass, img) in [
        (direct, "Direct", &light.direct),
        (indirect, "Indirect", &light.indirect),
    ] {
        if keep {
            for (c, name) in ["R", "G", "B"].iter().enumerate() {
                out.push((
                    format!("ViewLayer.{pass}.{name}"),
                    img.iter().map(|p| p[c]).collect(),
                ));
            }
        }
    }
    out
}

/// The run-time binding to Open Image Denoise: the library, one CPU device and one
/// filter, found and created once per process.
// Unsafe code (besides `bench_update`'s CPU clock, the crate's only one): calls into
// OIDN's C API through a library loaded at run time. Each call's contract is OIDN 2's (oidn.h): handles come from the same
// device, shared images stay alive and unaliased until `oidnExecuteFilter` returns (they
// are borrowed for the whole call here), and every use of the device and filter is under
// one mutex, as OIDN asks of a device shared between threads.
#[allow(unsafe_code)]
mod ffi {
    use std::ffi::{CStr, c_char, c_int, c_void};
    use std::path::{Path, PathBuf};
    use std::sync::{Mutex, OnceLock};

    type Handle = *mut c_void;

    /// OIDN's functions used here, looked up by name in the loaded library.
    struct Api {
        new_device: unsafe extern "C" fn(c_int) -> Handle,
        commit_device: unsafe extern "C" fn(Handle),
        get_device_error: unsafe extern "C" fn(Handle, *mut *const c_char) -> c_int,
        new_filter: unsafe extern "C" fn(Handle, *const c_char) -> Handle,
        set_shared_filter_image: unsafe extern "C" fn(
            Handle,
            *const c_char,
            *mut c_void,
            c_int,
            usize,
            usize,
            usize,
            usize,
            usize,
        ),
        set_filter_bool: unsafe extern "C" fn(Handle, *const c_char, bool),
        set_filter_int: unsafe extern "C" fn(Handle, *const c_char, c_int),
        commit_filter: unsafe extern "C" fn(Handle),
        execute_filter: unsafe extern "C" fn(Handle),
    }

    /// The filter kept between frames.
    struct Filter {
        handle: Handle,
    }

    pub struct Denoiser {
        /// The library file that was loaded.
        pub path: PathBuf,
        api: Api,
        device: Handle,
        filter: Mutex<Filter>,
        /// Keeps the functions of `api` loaded for the life of the process.
        _lib: libloading::Library,
    }

    // SAFETY: the device and filter handles are used only under `filter`'s mutex; OIDN
    // objects may be used from any thread as long as calls do not overlap.
    unsafe impl Send for Denoiser {}
    unsafe impl Sync for Denoiser {}

    /// OIDN_DEVICE_TYPE_CPU: the images are in host memory, shared without copies.
    const DEVICE_CPU: c_int = 1;
    /// OIDN_FORMAT_FLOAT3.
    const FORMAT_FLOAT3: c_int = 3;

    /// The process's denoiser, or why there is none (the first call decides).
    pub fn denoiser() -> Result<&'static Denoiser, &'static str> {
        static ONE: OnceLock<Result<Denoiser, String>> = OnceLock::new();
        ONE.get_or_init(open).as_ref().map_err(String::as_str)
    }

    const LIB_NAME: &str = if cfg!(target_os = "macos") {
        "libOpenImageDenoise.2.dylib"
    } else if cfg!(windows) {
        "OpenImageDenoise.dll"
    } else {
        "libOpenImageDenoise.so.2"
    };

    /// The places to try, in order (module docs), each with how it was chosen.
    fn candidates() -> Vec<(PathBuf, &'static str)> {
        if let Some(p) = std::env::var_os("CHRONOLUX_OIDN_LIB") {
            return vec![(PathBuf::from(p), "CHRONOLUX_OIDN_LIB")];
        }
        let mut out = Vec::new();
        if let Some(d) = std::env::var_os("OIDN_DIR") {
            out.push((Path::new(&d).join("lib").join(LIB_NAME), "OIDN_DIR"));
        }
        let built = env!("CHRONOLUX_OIDN_BUILD_LIB");
        if !built.is_empty() {
            out.push((Path::new(built).join(LIB_NAME), "the build"));
        }
        // A bare name: the dynamic loader's own search (LD_LIBRARY_PATH, ld.so.cache).
        out.push((PathBuf::from(LIB_NAME), "the system's library path"));
        out
    }

    fn open() -> Result<Denoiser, String> {
        let mut tried = Vec::new();
        for (path, from) in candidates() {
            if path.components().count() > 1 && !path.exists() {
                tried.push(format!("{} ({from}) does not exist", path.display()));
                continue;
            }
            // SAFETY: loading runs the library's initialisers; OIDN's (and TBB's) are
            // those of an ordinary shared library.
            match unsafe { libloading::Library::new(&path) } {
                Ok(lib) => return start(lib, path),
                Err(e) => tried.push(format!("{} ({from}): {e}", path.display())),
            }
        }
        let build_note = env!("CHRONOLUX_OIDN_BUILD_NOTE");
        Err(format!(
            "{}{}",
            tried.join("; "),
            if build_note.is_empty() {
                String::new()
            } else {
                format!("; at build time: {build_note}")
            }
        ))
    }

    fn start(lib: libloading::Library, path: PathBuf) -> Result<Denoiser, String> {
        // SAFETY: each symbol is declared with its signature in oidn.h (OIDN 2.x).
        let api = unsafe {
            macro_rules! sym {
                ($name:literal) => {
                    *lib.get($name)
                        .map_err(|e| format!("{}: {e}", path.display()))?
                };
            }
            Api {
                new_device: sym!("oidnNewDevice"),
                commit_device: sym!("oidnCommitDevice"),
                get_device_error: sym!("oidnGetDeviceError"),
                new_filter: sym!("oidnNewFilter"),
                set_shared_filter_image: sym!("oidnSetSharedFilterImage"),
                set_filter_bool: sym!("oidnSetFilterBool"),
                set_filter_int: sym!("oidnSetFilterInt"),
                commit_filter: sym!("oidnCommitFilter"),
                execute_filter: sym!("oidnExecuteFilter"),
            }
        };
        // SAFETY: OIDN's device creation; a null handle is checked.
        let device = unsafe { (api.new_device)(DEVICE_CPU) };
        if device.is_null() {
            return Err(format!("{}: cannot create a CPU device", path.display()));
        }
        // SAFETY: `device` is a fresh device handle.
        unsafe { (api.commit_device)(device) };
        let d = Denoiser {
            path,
            filter: Mutex::new(Filter {
                handle: std::ptr::null_mut(),
            }),
            api,
            device,
            _lib: lib,
        };
        d.error()
            .map_err(|e| format!("{}: {e}", d.path.display()))?;
        // SAFETY: a filter of the committed device; a null handle is checked.
        let filter = unsafe { (d.api.new_filter)(d.device, c"RT".as_ptr()) };
        if filter.is_null() {
            let e = d.error().err().unwrap_or_default();
            return Err(format!("{}: no RT filter: {e}", d.path.display()));
        }
        d.filter.lock().unwrap_or_else(|e| e.into_inner()).handle = filter;
        Ok(d)
    }

    impl Denoiser {
        /// The device's pending error, cleared.
        fn error(&self) -> Result<(), String> {
            let mut msg: *const c_char = std::ptr::null();
            // SAFETY: `msg` receives a pointer owned by OIDN, valid until the next call.
            let code = unsafe { (self.api.get_device_error)(self.device, &mut msg) };
            if code == 0 {
                return Ok(());
            }
            let text = if msg.is_null() {
                String::new()
            } else {
                // SAFETY: OIDN's message is a NUL-terminated string.
                unsafe { CStr::from_ptr(msg) }
                    .to_string_lossy()
                    .into_owned()
            };
            Err(format!("error {code}: {text}"))
        }

        /// `out` = the RT filter of `color` guided by `albedo` and `normal` (each `3·w·h`
        /// floats, RGB per pixel), in HDR mode, at OIDN quality `quality`.
        #[allow(clippy::too_many_arguments)]
        pub fn filter(
            &self,
            w: usize,
            h: usize,
            quality: c_int,
            color: &[f32],
            albedo: &[f32],
            normal: &[f32],
            out: &mut [f32],
        ) -> Result<(), String> {
            let n = 3 * w * h;
            if [color.len(), albedo.len(), normal.len(), out.len()] != [n; 4] {
                return Err("the images differ in size".into());
            }
            let f = self.filter.lock().unwrap_or_else(|e| e.into_inner());
            let set = |name: &CStr, data: *mut c_void| {
                // SAFETY: `data` points to `3·w·h` floats borrowed for this call; a zero
                // stride means packed FLOAT3 pixels and rows.
                unsafe {
                    (self.api.set_shared_filter_image)(
                        f.handle,
                        name.as_ptr(),
                        data,
                        FORMAT_FLOAT3,
                        w,
                        h,
                        0,
                        0,
                        0,
                    )
                }
            };
            set(c"color", color.as_ptr() as *mut c_void);
            set(c"albedo", albedo.as_ptr() as *mut c_void);
            set(c"normal", normal.as_ptr() as *mut c_void);
            set(c"output", out.as_mut_ptr() as *mut c_void);
            // SAFETY: parameters of the RT filter by their documented names; the commit
            // and execution read the images set above, which outlive the call.
            unsafe {
                (self.api.set_filter_bool)(f.handle, c"hdr".as_ptr(), true);
                (self.api.set_filter_int)(f.handle, c"quality".as_ptr(), quality);
                (self.api.commit_filter)(f.handle);
            }
            self.error()?;
            // SAFETY: as above.
            unsafe { (self.api.execute_filter)(f.handle) };
            self.error()
        }
    }
}
