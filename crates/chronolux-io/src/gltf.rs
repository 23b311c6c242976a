//! glTF 2.0 (`.gltf` with external or `data:` buffers, and `.glb`) into a [`SceneDesc`].
//!
//! Entry points: [`load`] (a file on disk) and [`load_slice`] (bytes in memory, with an
//! optional directory for external references). Every failure is a [`LoadError`] whose
//! `Display` is one line naming the file and, where it applies, the JSON path of the
//! offending element (e.g. `meshes[2].primitives[0].attributes.POSITION`). Untrusted data is
//! never indexed unchecked: accessor, buffer-view and buffer ranges are bounds-checked, and
//! the GLB container is parsed here with checked arithmetic.
//!
//! What is read:
//! - the node hierarchy of the default scene (or the first scene; with no scene at all,
//!   every parentless node), renumbered in depth-first order; nodes outside the displayed
//!   scene are dropped, together with animation channels that target them;
//! - node matrices decomposed to TRS (a warning when the matrix has shear);
//! - meshes (every mesh of the file), with `POSITION`, `NORMAL` (normalised), `TEXCOORD_0/1`,
//!   `TANGENT`, `JOINTS_0`, `WEIGHTS_0`, indices (sequential when absent), morph targets and
//!   default weights. Strips and fans become triangle lists; points and lines are skipped
//!   with a warning; degenerate triangles (repeated index or zero area) are removed and
//!   counted in one warning. Non-finite positions are an error;
//! - materials (metallic-roughness, emissive × `KHR_materials_emissive_strength`,
//!   `KHR_materials_specular`, `KHR_materials_transmission`, `KHR_materials_ior`,
//!   `KHR_texture_transform`, `KHR_materials_volume` (absorption only: attenuation colour
//!   and distance; thickness decides volume versus thin-walled), alpha mode, double
//!   sided), textures decoded to RGBA8 (PNG via
//!   `png`, JPEG via `zune-jpeg`) with their sampler's wrap modes and magnification filter;
//! - `KHR_lights_punctual` lights, cameras, skins, and every animation clip, flattened as
//!   [`Channel`] documents (normalised integer outputs are converted to floats).
//!
//! Extensions: a required extension outside [`SUPPORTED_EXTENSIONS`] is an error; an
//! unsupported optional one adds one warning.
//!
//! **Default light:** when the scene has no punctual light and no emissive material, a
//! neutral sky-to-ground gradient with a dark backdrop
//! ([`chronolux_core::scene::desc::default_environment`]) is added so the scene is visible,
//! and a warning says so.

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use base64::Engine as _;
use chronolux_core::color::Rgb;
use chronolux_core::math::{Mat4, Quat, Vec2, Vec3, Vec4};
use chronolux_core::scene::desc::{
    AlphaMode, Animation, CameraDesc, CameraId, Channel, ChannelTarget, Interpolation, LightDesc,
    LightId, LightKind, Material, MaterialId, Mesh, MeshId, MorphTarget, Node, NodeId, Primitive,
    Projection, SceneDesc, Skin, SkinId, Texture, TextureId, TextureRef, Trs, WrapMode,
};
use gltf::json;
use gltf::json::validation::{Checked, Validate as _};

/// Extensions Chronolux reads; any other required extension makes loading fail.
pub const SUPPORTED_EXTENSIONS: &[&str] = &[
    "KHR_lights_punctual",
    "KHR_materials_emissive_strength",
    "KHR_materials_specular",
    "KHR_materials_transmission",
    "KHR_materials_ior",
    "KHR_texture_transform",
    "KHR_materials_volume",
];

/// Why a glTF file could not be loaded. `Display` is a single line.
#[derive(Debug, thiserror::Error)]
pub enum LoadError {
    /// The file itself could not be read.
    #[error("{file}: cannot read file: {reason}")]
    Io { file: String, reason: String },
    /// Not a glTF 2.0 document (bad JSON, wrong GLB container, missing `asset`, ...).
    #[error("{file}: not a valid glTF 2.0 file: {reason}")]
    NotGltf { file: String, reason: String },
    /// The document is glTF but some element is invalid.
    #[error("{file}: {json_path}: {reason}")]
    Invalid {
        file: String,
        json_path: String,
        reason: String,
    },
    /// An external or embedded resource (buffer, image) is missing or unreadable.
    #[error("{file}: {json_path}: cannot load `{uri}`: {reason}")]
    Resource {
        file: String,
        json_path: String,
        uri: String,
        reason: String,
    },
    /// `extensionsRequired` names an extension Chronolux does not implement.
    #[error("{file}: extensionsRequired: extension `{extension}` is required but not supported")]
    UnsupportedExtension { file: String, extension: String },
}

/// Loads a `.gltf` or `.glb` file; external resources are resolved next to it.
pub fn load(path: &Path) -> Result<SceneDesc, LoadError> {
    let file = path.display().to_string();
    let bytes = std::fs::read(path).map_err(|e| LoadError::Io {
        file: file.clone(),
        reason: one_line(&e.to_string()),
    })?;
    let name = path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let base_dir = path
        .parent()
        .map(Path::to_path_buf)
        .unwrap_or_else(|| PathBuf::from("."));
    load_impl(&bytes, Some(&base_dir), &name, file)
}

/// Loads glTF or GLB bytes. `base_dir` resolves relative URIs (`None`: only `data:` URIs and
/// the GLB blob are allowed); `name` becomes `desc.name` and names the source in errors.
pub fn load_slice(
    bytes: &[u8],
    base_dir: Option<&Path>,
    name: &str,
) -> Result<SceneDesc, LoadError> {
    load_impl(bytes, base_dir, name, name.to_string())
}

fn one_line(s: &str) -> String {
    s.split_whitespace().collect::<Vec<_>>().join(" ")
}

// ---------------------------------------------------------------------------------------
// Container and document

/// Splits a GLB container into its JSON chunk and optional BIN chunk.
fn parse_glb(bytes: &[u8]) -> Result<(&[u8], Option<&[u8]>), String> {
    let u32_at = |o: usize| -> Option<u32> {
        bytes
            .get(o..o.checked_add(4)?)
            .map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
    };
    let version = u32_at(4).ok_or("GLB header is truncated")?;
    if version != 2 {
        return Err(format!("GLB version {version} (only 2 is supported)"));
    }
    let length = u32_at(8).ok_or("GLB header is truncated")? as usize;
    if length > bytes.len() {
        return Err(format!(
            "GLB is truncated: header says {length} bytes, file has {}",
            bytes.len()
        ));
    }
    let data = &bytes[..length];
    let mut chunks = Vec::new();
    let mut off = 12usize;
    while off < data.len() {
        let len = u32_at(off)
            .filter(|_| off + 8 <= data.len())
            .ok_or("GLB chunk header is truncated")? as usize;
        let ty = u32_at(off + 4).ok_or("GLB chunk header is truncated")?;
        let start = off + 8;
        let end = start.checked_add(len).filter(|&e| e <= data.len()).ok_or_else(|| {
            format!("GLB chunk at byte {off} claims {len} bytes but only {} remain (truncated file?)", data.len() - start)
        })?;
        chunks.push((ty, &data[start..end]));
        off = end.div_ceil(4) * 4;
    }
    const JSON: u32 = 0x4E4F_534A;
    const BIN: u32 = 0x004E_4942;
    match chunks.first() {
        Some(&(JSON, json)) => {
            let bin = chunks.get(1).filter(|c| c.0 == BIN).map(|c| c.1);
            Ok((json, bin))
        }
        Some(_) => Err("first GLB chunk is not JSON".into()),
        None => Err("GLB has no chunks (truncated file?)".into()),
    }
}

/// The load in phases: container, JSON with the channel repair, version and extensions,
/// the index checks gltf-json would panic on, gltf-json's validation and ours, then the
/// [`Loader`].
fn load_impl(
    bytes: &[u8],
    base_dir: Option<&Path>,
    name: &str,
    file: String,
) -> Result<SceneDesc, LoadError> {
    let not_gltf = |reason: String| LoadError::NotGltf {
        file: file.clone(),
        reason: one_line(&reason),
    };
    let (json_bytes, blob) = if bytes.starts_with(b"glTF") {
        parse_glb(bytes).map_err(not_gltf)?
    } else {
        (bytes, None)
    };
    let (root, channel_index, mut warnings) = parse_root(json_bytes).map_err(not_gltf)?;
    if !root.asset.version.starts_with("2.") {
        return Err(not_gltf(format!(
            "asset.version is \"{}\", expected 2.x",
            root.asset.version
        )));
    }
    if let Some(ext) = root
        .extensions_required
        .iter()
        .find(|e| !SUPPORTED_EXTENSIONS.contains(&e.as_str()))
    {
        return Err(LoadError::UnsupportedExtension {
            file,
            extension: ext.clone(),
        });
    }
    for ext in &root.extensions_used {
        if !SUPPORTED_EXTENSIONS.contains(&ext.as_str()) {
            warnings.push(format!(
                "optional extension `{ext}` is not supported and was ignored"
            ));
        }
    }
    if let Some((json_path, reason)) = unchecked_indices(&root) {
        return Err(LoadError::Invalid {
            file,
            json_path,
            reason,
        });
    }
    let errors = validation_errors(&root, &channel_index);
    if let Some((p, e)) = errors.first() {
        let more = if errors.len() > 1 {
            format!(" (and {} more problems)", errors.len() - 1)
        } else {
            String::new()
        };
        return Err(LoadError::Invalid {
            file,
            json_path: p.clone(),
            reason: format!("invalid glTF: {e}{more}"),
        });
    }
    let doc = gltf::Document::from_json_without_validation(root);
    let mut loader = Loader {
        file,
        doc: &doc,
        base_dir,
        buffers: Vec::new(),
        warnings,
        channel_index,
    };
    loader.load_buffers(blob)?;
    let mut desc = loader.build()?;
    desc.name = name.to_string();
    Ok(desc)
}

/// The typed document, per animation the original index of each channel kept, and the
/// warnings so far.
type ParsedRoot = (json::Root, Vec<Vec<usize>>, Vec<String>);

/// [`ParsedRoot`] from the JSON bytes. Animation channels without `target.node` are valid glTF (the node may
/// be set by an extension) but gltf-json requires the field: such channels are dropped
/// here, from the raw JSON, with one warning each; the channel indices keep the original
/// numbers for the messages about the remaining channels.
fn parse_root(json_bytes: &[u8]) -> Result<ParsedRoot, String> {
    let mut value: serde_json::Value =
        serde_json::from_slice(json_bytes).map_err(|e| e.to_string())?;
    let (dropped, channel_index) = drop_channels_without_node(&mut value);
    let root = if dropped.is_empty() {
        // Unchanged document: parse the bytes so errors keep their line and column.
        serde_json::from_slice(json_bytes)
    } else {
        serde_json::from_value(value)
    }
    .map_err(|e| e.to_string())?;
    let warnings = dropped
        .into_iter()
        .map(|p| format!("{p}: channel has no target.node (allowed only for extensions); ignored"))
        .collect();
    Ok((root, channel_index, warnings))
}

/// The first of the indices gltf and gltf-json use before (or without) validating them,
/// as (JSON path, reason).
fn unchecked_indices(root: &json::Root) -> Option<(String, String)> {
    // gltf-json's own validation indexes `accessors` with a primitive's POSITION index
    // before checking it (gltf-json-1.4.1/src/mesh.rs:151): check it first.
    for (mi, m) in root.meshes.iter().enumerate() {
        for (pi, p) in m.primitives.iter().enumerate() {
            if let Some(a) = p
                .attributes
                .get(&Checked::Valid(json::mesh::Semantic::Positions))
                && a.value() >= root.accessors.len()
            {
                return Some((
                    format!("meshes[{mi}].primitives[{pi}].attributes.POSITION"),
                    format!(
                        "accessor index {} out of bounds ({} accessors)",
                        a.value(),
                        root.accessors.len()
                    ),
                ));
            }
        }
    }
    // `gltf::Image::source` unwraps the URI when there is no buffer view, and the MIME type
    // when there is one (gltf-1.4.1/src/image.rs:124-128); neither is validated.
    root.images.iter().enumerate().find_map(|(ii, im)| {
        let reason = match (&im.buffer_view, &im.uri, &im.mime_type) {
            (None, None, _) => Some("image has neither uri nor bufferView"),
            (Some(_), _, None) => Some("image in a bufferView needs a mimeType"),
            _ => None,
        };
        reason.map(|r| (format!("images[{ii}]"), r.to_string()))
    })
}

/// gltf-json's validation (less what we are lenient about) and the animation-target
/// checks it lacks, as (JSON path, problem).
fn validation_errors(root: &json::Root, channel_index: &[Vec<usize>]) -> Vec<(String, String)> {
    let mut errors: Vec<(String, String)> = Vec::new();
    root.validate(root, json::Path::new, &mut |path, err| {
        use json::validation::Error as E;
        let p = path().to_string();
        // Required extensions were checked above (with our own list); POSITION min/max are
        // required by the spec but often missing in the wild and we compute bounds anyway.
        let lenient = p.starts_with("extensionsRequired")
            || (matches!(err, E::Missing) && (p.ends_with(".min") || p.ends_with(".max")));
        if !lenient {
            let what = match err {
                E::IndexOutOfBounds => "index out of bounds",
                E::Invalid => "invalid value",
                E::Missing => "required value missing",
                E::Oversize => "size exceeds system limits",
                E::Unsupported => "unsupported",
            };
            errors.push((p, what.to_string()));
        }
    });
    // gltf-json's `Animation::validate` checks only sampler indices, not the channel targets,
    // and `gltf::animation::Target::node` unwraps the node index: check targets here.
    for (ai, a) in root.animations.iter().enumerate() {
        for (ci, ch) in a.channels.iter().enumerate() {
            let ci = channel_index
                .get(ai)
                .and_then(|m| m.get(ci))
                .copied()
                .unwrap_or(ci);
            let base = format!("animations[{ai}].channels[{ci}].target");
            if ch.target.node.value() >= root.nodes.len() {
                errors.push((
                    format!("{base}.node"),
                    format!(
                        "node index {} out of bounds ({} nodes)",
                        ch.target.node.value(),
                        root.nodes.len()
                    ),
                ));
            }
            if !matches!(ch.target.path, Checked::Valid(_)) {
                errors.push((
                    format!("{base}.path"),
                    "invalid value (expected translation, rotation, scale or weights)".into(),
                ));
            }
        }
    }
    errors
}

/// How the elements of an accessor lie in its bytes, and how a component reads.
struct AccessorLayout {
    ct: json::accessor::ComponentType,
    normalized: bool,
    /// Components per element, as rows × columns (a matrix is stored column by column).
    n: usize,
    rows: usize,
    cols: usize,
    /// Bytes of a component; of a column (a matrix's padded to 4 bytes); of an element.
    cs: usize,
    col_stride: usize,
    elem_size: usize,
}

impl AccessorLayout {
    fn new(ct: json::accessor::ComponentType, ty: json::accessor::Type, normalized: bool) -> Self {
        use json::accessor::Type;
        let cs = ct.size();
        let n = ty.multiplicity();
        let (rows, cols) = match ty {
            Type::Mat2 => (2, 2),
            Type::Mat3 => (3, 3),
            Type::Mat4 => (4, 4),
            _ => (n, 1),
        };
        let col_stride = if cols > 1 {
            (rows * cs).div_ceil(4) * 4
        } else {
            rows * cs
        };
        AccessorLayout {
            ct,
            normalized,
            n,
            rows,
            cols,
            cs,
            col_stride,
            elem_size: col_stride * cols,
        }
    }

    /// The component in `b` (its `cs` bytes), normalised integers converted to [0, 1] /
    /// [-1, 1].
    fn component(&self, b: &[u8]) -> f64 {
        use json::accessor::ComponentType as Ct;
        let normalized = self.normalized;
        match self.ct {
            Ct::I8 => {
                let v = b[0] as i8 as f64;
                if normalized { (v / 127.0).max(-1.0) } else { v }
            }
            Ct::U8 => {
                let v = b[0] as f64;
                if normalized { v / 255.0 } else { v }
            }
            Ct::I16 => {
                let v = i16::from_le_bytes([b[0], b[1]]) as f64;
                if normalized {
                    (v / 32767.0).max(-1.0)
                } else {
                    v
                }
            }
            Ct::U16 => {
                let v = u16::from_le_bytes([b[0], b[1]]) as f64;
                if normalized { v / 65535.0 } else { v }
            }
            Ct::U32 => u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64,
            Ct::F32 => f32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64,
        }
    }
}

struct Loader<'a> {
    file: String,
    doc: &'a gltf::Document,
    base_dir: Option<&'a Path>,
    buffers: Vec<Vec<u8>>,
    warnings: Vec<String>,
    /// Per animation, the original index of each channel kept (see
    /// [`drop_channels_without_node`]).
    channel_index: Vec<Vec<usize>>,
}

/// Removes from `animations[*].channels` every channel whose `target` has no `node`; returns
/// the JSON paths of the removed channels and, per animation, the original index of each
/// channel kept. Anything that is not shaped as expected is left for the typed parse to
/// report.
fn drop_channels_without_node(v: &mut serde_json::Value) -> (Vec<String>, Vec<Vec<usize>>) {
    let mut dropped = Vec::new();
    let mut index = Vec::new();
    let Some(anims) = v.get_mut("animations").and_then(|a| a.as_array_mut()) else {
        return (dropped, index);
    };
    for (ai, a) in anims.iter_mut().enumerate() {
        let mut kept = Vec::new();
        if let Some(chs) = a.get_mut("channels").and_then(|c| c.as_array_mut()) {
            let mut ci = 0;
            chs.retain(|ch| {
                let i = ci;
                ci += 1;
                let no_node = ch
                    .get("target")
                    .and_then(|t| t.as_object())
                    .is_some_and(|t| !t.contains_key("node"));
                if no_node {
                    dropped.push(format!("animations[{ai}].channels[{i}]"));
                } else {
                    kept.push(i);
                }
                !no_node
            });
        }
        index.push(kept);
    }
    (dropped, index)
}

fn percent_decode(s: &str) -> String {
    let b = s.as_bytes();
    let mut out = Vec::with_capacity(b.len());
    let mut i = 0;
    while i < b.len() {
        if b[i] == b'%' && i + 2 < b.len() {
            let hex = |c: u8| (c as char).to_digit(16);
            if let (Some(h), Some(l)) = (hex(b[i + 1]), hex(b[i + 2])) {
                out.push((h * 16 + l) as u8);
                i += 3;
                continue;
            }
        }
        out.push(b[i]);
        i += 1;
    }
    String::from_utf8_lossy(&out).into_owned()
}

impl Loader<'_> {
    fn json(&self) -> &json::Root {
        self.doc.as_json()
    }

    fn invalid(&self, json_path: impl Into<String>, reason: impl Into<String>) -> LoadError {
        LoadError::Invalid {
            file: self.file.clone(),
            json_path: json_path.into(),
            reason: one_line(&reason.into()),
        }
    }

    fn resource(&self, json_path: &str, uri: &str, reason: impl Into<String>) -> LoadError {
        let uri = if uri.starts_with("data:") {
            "data: URI".to_string()
        } else {
            uri.to_string()
        };
        LoadError::Resource {
            file: self.file.clone(),
            json_path: json_path.into(),
            uri,
            reason: one_line(&reason.into()),
        }
    }

    /// Bytes of a `data:` URI or of a file relative to the base directory.
    fn load_uri(&self, uri: &str, json_path: &str) -> Result<Vec<u8>, LoadError> {
        if let Some(rest) = uri.strip_prefix("data:") {
            let (meta, data) = rest
                .split_once(',')
                .ok_or_else(|| self.resource(json_path, uri, "malformed data: URI"))?;
            if !meta.ends_with(";base64") {
                return Err(self.resource(json_path, uri, "only base64 data: URIs are supported"));
            }
            return base64::engine::general_purpose::STANDARD
                .decode(data.trim())
                .map_err(|e| self.resource(json_path, uri, format!("bad base64: {e}")));
        }
        if uri.contains("://") {
            return Err(self.resource(
                json_path,
                uri,
                "only relative file paths and data: URIs are supported",
            ));
        }
        let base = self.base_dir.ok_or_else(|| {
            self.resource(
                json_path,
                uri,
                "external file referenced but no base directory was given",
            )
        })?;
        let p = base.join(percent_decode(uri));
        // Only regular files: a device (`/dev/zero`), a FIFO or a directory named by a
        // hostile or broken file would hang the read or exhaust memory.
        match std::fs::metadata(&p) {
            Ok(m) if !m.is_file() => {
                return Err(self.resource(
                    json_path,
                    uri,
                    format!("not a regular file ({})", p.display()),
                ));
            }
            _ => {}
        }
        std::fs::read(&p)
            .map_err(|e| self.resource(json_path, uri, format!("{} ({})", e, p.display())))
    }

    fn load_buffers(&mut self, blob: Option<&[u8]>) -> Result<(), LoadError> {
        let mut blob = blob;
        let mut buffers = Vec::new();
        for (i, b) in self.json().buffers.iter().enumerate() {
            let path = format!("buffers[{i}]");
            let data = match &b.uri {
                Some(uri) => self.load_uri(uri, &path)?,
                None => match blob.take() {
                    Some(bin) => bin.to_vec(),
                    None => {
                        return Err(self.invalid(
                            &path,
                            "buffer has no uri and the file has no (unused) GLB BIN chunk",
                        ));
                    }
                },
            };
            let need = b.byte_length.0;
            if (data.len() as u64) < need {
                return Err(self.invalid(
                    format!("{path}.byteLength"),
                    format!(
                        "buffer declares {need} bytes but its data has only {}",
                        data.len()
                    ),
                ));
            }
            buffers.push(data);
        }
        self.buffers = buffers;
        Ok(())
    }

    /// The bytes of buffer view `v` and its stride.
    fn view(&self, v: usize, path: &str) -> Result<(&[u8], Option<usize>), LoadError> {
        let view = self
            .json()
            .buffer_views
            .get(v)
            .ok_or_else(|| self.invalid(path, format!("bufferView {v} does not exist")))?;
        let vpath = format!("bufferViews[{v}]");
        let buf = self.buffers.get(view.buffer.value()).ok_or_else(|| {
            self.invalid(
                &vpath,
                format!("buffer {} does not exist", view.buffer.value()),
            )
        })?;
        let off = view.byte_offset.map_or(0, |o| o.0);
        let len = view.byte_length.0;
        let end = off
            .checked_add(len)
            .filter(|&e| e <= buf.len() as u64)
            .ok_or_else(|| {
                self.invalid(
                    &vpath,
                    format!(
                        "bytes {off}..{} lie outside buffer {} ({} bytes)",
                        off.saturating_add(len),
                        view.buffer.value(),
                        buf.len()
                    ),
                )
            })?;
        Ok((
            &buf[off as usize..end as usize],
            view.byte_stride.map(|s| s.0),
        ))
    }

    /// Reads accessor `idx` as flat `f64` components (normalised integers converted to
    /// [0, 1] / [-1, 1]). Returns (values, components per element).
    fn read_accessor(&self, idx: usize, path: &str) -> Result<(Vec<f64>, usize), LoadError> {
        use json::accessor::GenericComponentType;
        let apath = format!("{path} (accessors[{idx}])");
        let acc = self
            .json()
            .accessors
            .get(idx)
            .ok_or_else(|| self.invalid(path, format!("accessor {idx} does not exist")))?;
        let ct = match acc.component_type {
            Checked::Valid(GenericComponentType(c)) => c,
            Checked::Invalid => return Err(self.invalid(&apath, "invalid componentType")),
        };
        let ty = match acc.type_ {
            Checked::Valid(t) => t,
            Checked::Invalid => return Err(self.invalid(&apath, "invalid type")),
        };
        let layout = AccessorLayout::new(ct, ty, acc.normalized);
        let (n, elem_size) = (layout.n, layout.elem_size);
        let count = usize::try_from(acc.count.0).unwrap_or(usize::MAX);
        if count.saturating_mul(n) > (1 << 27) {
            return Err(self.invalid(&apath, format!("count {count} is unreasonably large")));
        }
        let mut values = match acc.buffer_view {
            Some(v) => {
                let (data, stride) = self.view(v.value(), &apath)?;
                let stride = stride.unwrap_or(elem_size);
                if stride < elem_size {
                    return Err(self.invalid(
                        &apath,
                        format!("byteStride {stride} is smaller than the element size {elem_size}"),
                    ));
                }
                let off = usize::try_from(acc.byte_offset.map_or(0, |o| o.0)).unwrap_or(usize::MAX);
                self.read_elements(&layout, &apath, data, off, stride, count, "buffer view")?
            }
            None => vec![0.0; count * n],
        };
        if let Some(sparse) = &acc.sparse {
            self.apply_sparse(sparse, &layout, &apath, count, &mut values)?;
        }
        Ok((values, n))
    }

    /// Reads `count` elements of `layout` starting at `off` with `stride` from `data` (the
    /// `what` of accessor `apath`), bounds-checked.
    fn read_elements(
        &self,
        layout: &AccessorLayout,
        apath: &str,
        data: &[u8],
        off: usize,
        stride: usize,
        count: usize,
        what: &str,
    ) -> Result<Vec<f64>, LoadError> {
        let &AccessorLayout {
            n,
            rows,
            cols,
            cs,
            col_stride,
            elem_size,
            ..
        } = layout;
        if count == 0 {
            return Ok(Vec::new());
        }
        let last = stride
            .checked_mul(count - 1)
            .and_then(|x| x.checked_add(off))
            .and_then(|x| x.checked_add(elem_size))
            .unwrap_or(usize::MAX);
        if last > data.len() {
            return Err(self.invalid(
                apath,
                format!("{count} elements of {elem_size} bytes (stride {stride}, offset {off}) need {last} bytes but the {what} has {}", data.len()),
            ));
        }
        let mut out = Vec::with_capacity(count * n);
        for e in 0..count {
            let base = off + e * stride;
            for c in 0..cols {
                for r in 0..rows {
                    let o = base + c * col_stride + r * cs;
                    out.push(layout.component(&data[o..o + cs]));
                }
            }
        }
        Ok(out)
    }

    /// Writes the sparse substitutes of accessor `apath` (of `count` elements) into its
    /// `values`.
    fn apply_sparse(
        &self,
        sparse: &json::accessor::sparse::Sparse,
        layout: &AccessorLayout,
        apath: &str,
        count: usize,
        values: &mut [f64],
    ) -> Result<(), LoadError> {
        let n = layout.n;
        let scount = usize::try_from(sparse.count.0).unwrap_or(usize::MAX);
        if scount > count {
            return Err(self.invalid(
                format!("{apath}.sparse"),
                "more sparse values than elements",
            ));
        }
        let ict = match sparse.indices.component_type {
            Checked::Valid(json::accessor::IndexComponentType(c)) => c,
            Checked::Invalid => {
                return Err(
                    self.invalid(format!("{apath}.sparse.indices"), "invalid componentType")
                );
            }
        };
        let isz = ict.size();
        let (idata, _) = self.view(sparse.indices.buffer_view.value(), apath)?;
        let ioff = usize::try_from(sparse.indices.byte_offset.0).unwrap_or(usize::MAX);
        let iend = isz
            .checked_mul(scount)
            .and_then(|x| x.checked_add(ioff))
            .unwrap_or(usize::MAX);
        if iend > idata.len() {
            return Err(self.invalid(
                format!("{apath}.sparse.indices"),
                "indices lie outside their buffer view",
            ));
        }
        let (vdata, _) = self.view(sparse.values.buffer_view.value(), apath)?;
        let voff = usize::try_from(sparse.values.byte_offset.0).unwrap_or(usize::MAX);
        let svals = self.read_elements(
            layout,
            apath,
            vdata,
            voff,
            layout.elem_size,
            scount,
            "sparse values buffer view",
        )?;
        for k in 0..scount {
            let b = &idata[ioff + k * isz..ioff + (k + 1) * isz];
            let i = match isz {
                1 => b[0] as usize,
                2 => u16::from_le_bytes([b[0], b[1]]) as usize,
                _ => u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as usize,
            };
            if i >= count {
                return Err(self.invalid(
                    format!("{apath}.sparse.indices"),
                    format!("index {i} out of range (count {count})"),
                ));
            }
            values[i * n..(i + 1) * n].copy_from_slice(&svals[k * n..(k + 1) * n]);
        }
        Ok(())
    }

    fn read_vecs<const N: usize>(
        &self,
        idx: usize,
        path: &str,
    ) -> Result<Vec<[f32; N]>, LoadError> {
        let (v, n) = self.read_accessor(idx, path)?;
        if n != N {
            return Err(self.invalid(
                path,
                format!("expected {N} components per element, accessor {idx} has {n}"),
            ));
        }
        Ok(v.chunks_exact(N)
            .map(|c| std::array::from_fn(|i| c[i] as f32))
            .collect())
    }

    /// A per-vertex attribute: `N`-component elements mapped by `f`, which must number `nv`
    /// (the primitive's POSITION count).
    fn read_vertex_attr<const N: usize, T>(
        &self,
        idx: usize,
        path: &str,
        nv: usize,
        f: impl Fn([f32; N]) -> T,
    ) -> Result<Vec<T>, LoadError> {
        let v: Vec<T> = self.read_vecs::<N>(idx, path)?.into_iter().map(f).collect();
        if v.len() != nv {
            return Err(self.invalid(
                path,
                format!("has {} elements but POSITION has {nv}", v.len()),
            ));
        }
        Ok(v)
    }

    fn read_scalars_u32(&self, idx: usize, path: &str) -> Result<Vec<u32>, LoadError> {
        let (v, n) = self.read_accessor(idx, path)?;
        if n != 1 {
            return Err(self.invalid(
                path,
                format!("expected scalar accessor, accessor {idx} has {n} components"),
            ));
        }
        Ok(v.into_iter().map(|x| x as u32).collect())
    }

    // -----------------------------------------------------------------------------------
    // Whole scene

    fn build(mut self) -> Result<SceneDesc, LoadError> {
        let doc = self.doc;
        let mut materials = Vec::new();
        for m in doc.materials() {
            materials.push(self.load_material(&m));
        }
        let mut desc = SceneDesc {
            textures: self.load_textures()?,
            materials,
            meshes: self.load_meshes()?,
            cameras: doc.cameras().map(|c| load_camera(&c)).collect(),
            ..Default::default()
        };
        if let Some(lights) = doc.lights() {
            desc.lights = lights.map(|l| load_light(&l)).collect();
        }
        // Node hierarchy of the displayed scene.
        let node_count = doc.nodes().len();
        let roots_old: Vec<usize> = match doc.default_scene().or_else(|| doc.scenes().next()) {
            Some(s) => s.nodes().map(|n| n.index()).collect(),
            None => {
                let mut has_parent = vec![false; node_count];
                for n in doc.nodes() {
                    for c in n.children() {
                        has_parent[c.index()] = true;
                    }
                }
                if node_count > 0 {
                    self.warnings
                        .push("file has no scene: showing every parentless node".into());
                }
                (0..node_count).filter(|&i| !has_parent[i]).collect()
            }
        };
        let nodes_vec: Vec<gltf::Node> = doc.nodes().collect();
        let mut map: Vec<Option<u32>> = vec![None; node_count];
        let mut order: Vec<(usize, Option<u32>)> = Vec::new();
        let mut stack: Vec<(usize, Option<u32>)> =
            roots_old.iter().rev().map(|&i| (i, None)).collect();
        while let Some((old, parent)) = stack.pop() {
            if map[old].is_some() {
                return Err(self.invalid(
                    format!("nodes[{old}]"),
                    "node is reached twice: the node hierarchy is not a tree",
                ));
            }
            map[old] = Some(order.len() as u32);
            let new = order.len() as u32;
            order.push((old, parent));
            let node = nodes_vec
                .get(old)
                .ok_or_else(|| self.invalid(format!("nodes[{old}]"), "missing node"))?;
            let children: Vec<usize> = node.children().map(|c| c.index()).collect();
            for &c in children.iter().rev() {
                stack.push((c, Some(new)));
            }
        }
        for &(old, parent) in &order {
            let n = &nodes_vec[old];
            let path = format!("nodes[{old}]");
            let transform = self.node_transform(n, &path)?;
            desc.nodes.push(Node {
                name: n.name().unwrap_or_default().to_string(),
                parent: parent.map(NodeId),
                children: n
                    .children()
                    .filter_map(|c| map[c.index()])
                    .map(NodeId)
                    .collect(),
                transform,
                mesh: n.mesh().map(|m| MeshId(m.index() as u32)),
                camera: n.camera().map(|c| CameraId(c.index() as u32)),
                light: n.light().map(|l| LightId(l.index() as u32)),
                skin: n.skin().map(|s| SkinId(s.index() as u32)),
                weights: n.weights().map(<[f32]>::to_vec).unwrap_or_default(),
            });
        }
        desc.roots = roots_old
            .iter()
            .filter_map(|&i| map[i])
            .map(NodeId)
            .collect();
        // Skins.
        let used_skins: Vec<usize> = order
            .iter()
            .filter_map(|&(old, _)| nodes_vec[old].skin().map(|s| s.index()))
            .collect();
        for s in doc.skins() {
            let path = format!("skins[{}]", s.index());
            let mut joints = Vec::new();
            let mut ok = true;
            for (j, jn) in s.joints().enumerate() {
                match map[jn.index()] {
                    Some(id) => joints.push(NodeId(id)),
                    None if used_skins.contains(&s.index()) => {
                        return Err(self.invalid(
                            format!("{path}.joints[{j}]"),
                            format!(
                                "joint node {} is not part of the displayed scene",
                                jn.index()
                            ),
                        ));
                    }
                    None => ok = false,
                }
            }
            if !ok {
                joints.clear();
            }
            let ibms = match s.inverse_bind_matrices() {
                Some(a) if ok => {
                    let m =
                        self.read_vecs::<16>(a.index(), &format!("{path}.inverseBindMatrices"))?;
                    if m.len() < joints.len() {
                        return Err(self.invalid(
                            format!("{path}.inverseBindMatrices"),
                            format!("{} matrices for {} joints", m.len(), joints.len()),
                        ));
                    }
                    m.iter()
                        .take(joints.len())
                        .map(Mat4::from_cols_array)
                        .collect()
                }
                _ => vec![Mat4::IDENTITY; joints.len()],
            };
            desc.skins.push(Skin {
                name: s.name().unwrap_or_default().to_string(),
                joints,
                inverse_bind_matrices: ibms,
            });
        }
        // Animations.
        for a in doc.animations() {
            desc.animations
                .push(self.load_animation(&a, &map, &desc.meshes)?);
        }
        // Summary warnings and the default light.
        let has_emission = desc
            .materials
            .iter()
            .any(|m| m.emissive.max_element() > 0.0);
        if desc.lights.is_empty() && !has_emission {
            desc.environment = Some(chronolux_core::scene::desc::default_environment());
            self.warnings
                .push(chronolux_core::scene::desc::DEFAULT_ENVIRONMENT_WARNING.into());
        }
        desc.warnings = self.warnings;
        Ok(desc)
    }

    fn node_transform(&mut self, n: &gltf::Node, path: &str) -> Result<Trs, LoadError> {
        match n.transform() {
            gltf::scene::Transform::Matrix { matrix } => {
                let m = Mat4::from_cols_array_2d(&matrix);
                if !m.is_finite() {
                    return Err(self.invalid(
                        format!("{path}.matrix"),
                        "matrix has NaN or infinite entries",
                    ));
                }
                let (scale, rotation, translation) = m.to_scale_rotation_translation();
                // A singular matrix (zero scale) has no defined rotation.
                let rotation = if rotation.is_finite() {
                    rotation
                } else {
                    Quat::IDENTITY
                };
                let trs = Trs {
                    translation,
                    rotation,
                    scale,
                };
                let back = trs.matrix();
                let err = (back - m)
                    .to_cols_array()
                    .iter()
                    .fold(0.0f32, |a, x| a.max(x.abs()));
                let mag = m.to_cols_array().iter().fold(1.0f32, |a, x| a.max(x.abs()));
                if !back.is_finite() || err > 1e-4 * mag {
                    self.warnings.push(format!("{path}.matrix is not a TRS transform (shear or projection); it was approximated"));
                }
                Ok(trs)
            }
            gltf::scene::Transform::Decomposed {
                translation,
                rotation,
                scale,
            } => {
                let t = Vec3::from(translation);
                let r = Quat::from_array(rotation);
                let s = Vec3::from(scale);
                if !(t.is_finite() && r.is_finite() && s.is_finite()) {
                    return Err(self.invalid(
                        path,
                        "translation/rotation/scale has NaN or infinite values",
                    ));
                }
                let r = if r.length_squared() > 0.0 {
                    r.normalize()
                } else {
                    Quat::IDENTITY
                };
                Ok(Trs {
                    translation: t,
                    rotation: r,
                    scale: s,
                })
            }
        }
    }

    // -----------------------------------------------------------------------------------
    // Textures and materials

    fn load_textures(&self) -> Result<Vec<Texture>, LoadError> {
        let mut cache: HashMap<usize, (u32, u32, Vec<[u8; 4]>)> = HashMap::new();
        let mut out = Vec::new();
        for t in self.doc.textures() {
            let img = t.source();
            let ii = img.index();
            if let std::collections::hash_map::Entry::Vacant(slot) = cache.entry(ii) {
                let path = format!("images[{ii}]");
                let (bytes, what) = match img.source() {
                    gltf::image::Source::View { view, .. } => (
                        self.view(view.index(), &path)?.0.to_vec(),
                        format!("bufferView {}", view.index()),
                    ),
                    gltf::image::Source::Uri { uri, .. } => {
                        (self.load_uri(uri, &format!("{path}.uri"))?, uri.to_string())
                    }
                };
                let decoded = decode_image(&bytes).map_err(|e| self.resource(&path, &what, e))?;
                slot.insert(decoded);
            }
            let (w, h, px) = cache.get(&ii).cloned().unwrap_or_default();
            let s = t.sampler();
            let wrap = |m: gltf::texture::WrappingMode| match m {
                gltf::texture::WrappingMode::ClampToEdge => WrapMode::ClampToEdge,
                gltf::texture::WrappingMode::MirroredRepeat => WrapMode::MirroredRepeat,
                gltf::texture::WrappingMode::Repeat => WrapMode::Repeat,
            };
            out.push(Texture {
                name: t.name().or(img.name()).unwrap_or_default().to_string(),
                width: w,
                height: h,
                rgba8: px,
                wrap_s: wrap(s.wrap_s()),
                wrap_t: wrap(s.wrap_t()),
                bilinear: s.mag_filter() != Some(gltf::texture::MagFilter::Nearest),
            });
        }
        Ok(out)
    }

    fn load_material(&mut self, m: &gltf::Material) -> Material {
        let pbr = m.pbr_metallic_roughness();
        let bc = pbr.base_color_factor();
        let strength = m.emissive_strength().unwrap_or(1.0);
        let mut mat = Material {
            name: m.name().unwrap_or_default().to_string(),
            base_color: Rgb::new(bc[0], bc[1], bc[2]),
            alpha: bc[3],
            base_color_texture: pbr.base_color_texture().map(|i| tex_ref(&i)),
            metallic: pbr.metallic_factor(),
            roughness: pbr.roughness_factor(),
            metallic_roughness_texture: pbr.metallic_roughness_texture().map(|i| tex_ref(&i)),
            emissive: Rgb::from(m.emissive_factor()) * strength,
            emissive_texture: m.emissive_texture().map(|i| tex_ref(&i)),
            normal_texture: m
                .normal_texture()
                .map(|n| TextureRef::new(TextureId(n.texture().index() as u32), n.tex_coord())),
            normal_scale: m.normal_texture().map_or(1.0, |n| n.scale()),
            alpha_mode: match m.alpha_mode() {
                gltf::material::AlphaMode::Opaque => AlphaMode::Opaque,
                gltf::material::AlphaMode::Mask => AlphaMode::Mask(m.alpha_cutoff().unwrap_or(0.5)),
                gltf::material::AlphaMode::Blend => AlphaMode::Blend,
            },
            double_sided: m.double_sided(),
            ior: m.ior().unwrap_or(1.5),
            ..Default::default()
        };
        if let Some(s) = m.specular() {
            mat.specular = s.specular_factor();
            mat.specular_color = Rgb::from(s.specular_color_factor());
        }
        if let Some(t) = m.transmission() {
            mat.transmission = t.transmission_factor();
            mat.transmission_texture = t.transmission_texture().map(|i| tex_ref(&i));
        }
        if let Some(v) = m.volume() {
            let path = format!(
                "materials[{}].extensions.KHR_materials_volume",
                m.index().unwrap_or(0)
            );
            let c = Rgb::from(v.attenuation_color()).clamp(Rgb::ZERO, Rgb::ONE);
            let d = v.attenuation_distance();
            let absorbs = c != Rgb::ONE && d.is_finite();
            if !(d > 0.0) {
                self.warnings.push(format!(
                    "{path}: attenuationDistance {d} is not positive; volume ignored"
                ));
            } else if !(v.thickness_factor() > 0.0) {
                // The spec: thicknessFactor 0 (its default) is a thin-walled surface.
                if absorbs {
                    self.warnings.push(format!(
                        "{path}: thicknessFactor 0 makes the material thin-walled; attenuation ignored"
                    ));
                }
            } else if absorbs {
                // Rays measure the real path inside the closed mesh, so thicknessFactor
                // and thicknessTexture (a rasteriser's stand-in for that path) only decide
                // volume versus thin-walled.
                mat.volume = Some(chronolux_core::scene::desc::Volume::from_attenuation(c, d));
            }
        }
        mat
    }

    // -----------------------------------------------------------------------------------
    // Meshes

    fn load_meshes(&mut self) -> Result<Vec<Mesh>, LoadError> {
        let mut meshes = Vec::new();
        let mut degenerate = 0usize;
        let mut degenerate_prims = 0usize;
        for mesh in self.doc.meshes() {
            let mi = mesh.index();
            let mut prims = Vec::new();
            let mut max_targets = 0;
            for p in mesh.primitives() {
                let path = format!("meshes[{mi}].primitives[{}]", p.index());
                if let Some((prim, skipped)) = self.load_primitive(&p, &path)? {
                    if skipped > 0 {
                        degenerate += skipped;
                        degenerate_prims += 1;
                    }
                    max_targets = max_targets.max(prim.morph_targets.len());
                    prims.push(prim);
                }
            }
            let mut weights = mesh.weights().map(<[f32]>::to_vec).unwrap_or_default();
            weights.resize(max_targets.max(weights.len()), 0.0);
            meshes.push(Mesh {
                name: mesh.name().unwrap_or_default().to_string(),
                primitives: prims,
                weights,
            });
        }
        if degenerate > 0 {
            self.warnings.push(format!(
                "skipped {degenerate} degenerate triangle(s) (repeated index or zero area) in {degenerate_prims} primitive(s)"
            ));
        }
        Ok(meshes)
    }

    /// One primitive; `None` when skipped (points/lines); also returns the count of
    /// degenerate triangles removed.
    fn load_primitive(
        &mut self,
        p: &gltf::Primitive,
        path: &str,
    ) -> Result<Option<(Primitive, usize)>, LoadError> {
        use gltf::mesh::{Mode, Semantic};
        let mode = p.mode();
        if matches!(
            mode,
            Mode::Points | Mode::Lines | Mode::LineLoop | Mode::LineStrip
        ) {
            self.warnings.push(format!(
                "{path}: {mode:?} primitive skipped (only triangles are rendered)"
            ));
            return Ok(None);
        }
        let Some(pos_acc) = p.get(&Semantic::Positions) else {
            self.warnings
                .push(format!("{path}: primitive without POSITION skipped"));
            return Ok(None);
        };
        let positions = self.read_positions(&pos_acc, path)?;
        let nv = positions.len();
        let mut prim = Primitive {
            positions,
            material: p.material().index().map(|i| MaterialId(i as u32)),
            ..Default::default()
        };
        self.read_vertex_attributes(p, path, &mut prim)?;
        if prim.joints.is_some() != prim.joint_weights.is_some() {
            self.warnings.push(format!(
                "{path}: JOINTS_0 without WEIGHTS_0 (or the reverse): skinning ignored"
            ));
            prim.joints = None;
            prim.joint_weights = None;
        }
        prim.morph_targets = self.read_morph_targets(p, path, nv)?;
        let tris = self.read_triangles(p, path, nv)?;
        let before = tris.len();
        let pos = &prim.positions;
        prim.indices = tris
            .into_iter()
            .filter(|&[a, b, c]| {
                if a == b || b == c || a == c {
                    return false;
                }
                let (pa, pb, pc) = (pos[a as usize], pos[b as usize], pos[c as usize]);
                (pb - pa).cross(pc - pa).length_squared() > 0.0
            })
            .collect();
        let skipped = before - prim.indices.len();
        Ok(Some((prim, skipped)))
    }

    /// A primitive's POSITION, checked to be finite and within what f32 geometry holds.
    fn read_positions(&self, pos_acc: &gltf::Accessor, path: &str) -> Result<Vec<Vec3>, LoadError> {
        let ppath = format!("{path}.attributes.POSITION");
        let positions: Vec<Vec3> = self
            .read_vecs::<3>(pos_acc.index(), &ppath)?
            .into_iter()
            .map(Vec3::from)
            .collect();
        if let Some(i) = positions.iter().position(|v| !v.is_finite()) {
            return Err(self.invalid(
                &ppath,
                format!("vertex {i} has a NaN or infinite coordinate"),
            ));
        }
        let max = chronolux_core::accel::MAX_COORD;
        if let Some(i) = positions.iter().position(|v| v.abs().max_element() > max) {
            return Err(self.invalid(
                &ppath,
                format!("vertex {i} lies beyond ±{max:e}, outside what f32 geometry can hold"),
            ));
        }
        Ok(positions)
    }

    /// The primitive's other vertex attributes (normals, tangents, two UV sets, joints and
    /// weights), each checked for length against `prim.positions`.
    fn read_vertex_attributes(
        &self,
        p: &gltf::Primitive,
        path: &str,
        prim: &mut Primitive,
    ) -> Result<(), LoadError> {
        use gltf::mesh::Semantic;
        let nv = prim.positions.len();
        for (sem, acc) in p.attributes() {
            let apath = format!("{path}.attributes.{}", sem.to_string());
            match sem {
                Semantic::Normals => {
                    let v: Vec<Vec3> =
                        self.read_vertex_attr::<3, _>(acc.index(), &apath, nv, |a| {
                            Vec3::from(a).normalize_or_zero()
                        })?;
                    prim.normals = Some(v);
                }
                Semantic::Tangents => {
                    let v: Vec<Vec4> =
                        self.read_vertex_attr::<4, _>(acc.index(), &apath, nv, Vec4::from)?;
                    prim.tangents = Some(v);
                }
                Semantic::TexCoords(set @ (0 | 1)) => {
                    let v: Vec<Vec2> =
                        self.read_vertex_attr::<2, _>(acc.index(), &apath, nv, Vec2::from)?;
                    if set == 0 {
                        prim.uvs = Some(v);
                    } else {
                        prim.uvs1 = Some(v);
                    }
                }
                Semantic::Joints(0) => {
                    let v: Vec<[u16; 4]> =
                        self.read_vertex_attr::<4, _>(acc.index(), &apath, nv, |a| {
                            a.map(|x| x.clamp(0.0, u16::MAX as f32) as u16)
                        })?;
                    prim.joints = Some(v);
                }
                Semantic::Weights(0) => {
                    let v: Vec<Vec4> =
                        self.read_vertex_attr::<4, _>(acc.index(), &apath, nv, Vec4::from)?;
                    prim.joint_weights = Some(v);
                }
                _ => {}
            }
        }
        Ok(())
    }

    /// The primitive's morph targets over its `nv` vertices.
    fn read_morph_targets(
        &self,
        p: &gltf::Primitive,
        path: &str,
        nv: usize,
    ) -> Result<Vec<MorphTarget>, LoadError> {
        let mut targets = Vec::new();
        for (ti, t) in p.morph_targets().enumerate() {
            let tpath = format!("{path}.targets[{ti}]");
            // One reader for the three displacement attributes, each checked for length
            // against the base vertices and for finite values.
            let read_target =
                |acc: Option<gltf::Accessor>, name: &str| -> Result<Option<Vec<Vec3>>, LoadError> {
                    let Some(a) = acc else { return Ok(None) };
                    let ap = format!("{tpath}.{name}");
                    let v = self.read_vertex_attr::<3, _>(a.index(), &ap, nv, Vec3::from)?;
                    if v.iter().any(|d| !d.is_finite()) {
                        return Err(self.invalid(&ap, "NaN or infinite displacement"));
                    }
                    Ok(Some(v))
                };
            let mt = MorphTarget {
                positions: read_target(t.positions(), "POSITION")?,
                normals: read_target(t.normals(), "NORMAL")?,
                tangents: read_target(t.tangents(), "TANGENT")?,
            };
            targets.push(mt);
        }
        Ok(targets)
    }

    /// The primitive's triangles (of a list, strip or fan; indices checked against its
    /// `nv` vertices; without indices, the vertices in order).
    fn read_triangles(
        &mut self,
        p: &gltf::Primitive,
        path: &str,
        nv: usize,
    ) -> Result<Vec<[u32; 3]>, LoadError> {
        use gltf::mesh::Mode;
        let idx: Vec<u32> = match p.indices() {
            Some(a) => {
                let ipath = format!("{path}.indices");
                let v = self.read_scalars_u32(a.index(), &ipath)?;
                if let Some((k, &i)) = v.iter().enumerate().find(|&(_, &i)| i as usize >= nv) {
                    return Err(self.invalid(
                        &ipath,
                        format!("index {i} at position {k} is out of range ({nv} vertices)"),
                    ));
                }
                v
            }
            None => (0..nv as u32).collect(),
        };
        Ok(match p.mode() {
            Mode::TriangleStrip => (0..idx.len().saturating_sub(2))
                .map(|i| {
                    if i % 2 == 0 {
                        [idx[i], idx[i + 1], idx[i + 2]]
                    } else {
                        [idx[i + 1], idx[i], idx[i + 2]]
                    }
                })
                .collect(),
            Mode::TriangleFan => (0..idx.len().saturating_sub(2))
                .map(|i| [idx[i + 1], idx[i + 2], idx[0]])
                .collect(),
            _ => {
                if !idx.len().is_multiple_of(3) {
                    self.warnings.push(format!(
                        "{path}: index count {} is not a multiple of 3; extra indices ignored",
                        idx.len()
                    ));
                }
                idx.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect()
            }
        })
    }

    // -----------------------------------------------------------------------------------
    // Animations

    fn load_animation(
        &mut self,
        a: &gltf::Animation,
        map: &[Option<u32>],
        meshes: &[Mesh],
    ) -> Result<Animation, LoadError> {
        use gltf::animation::{Interpolation as I, Property};
        let ai = a.index();
        let mut anim = Animation {
            name: a
                .name()
                .map(str::to_string)
                .unwrap_or_else(|| format!("animation{ai}")),
            channels: Vec::new(),
        };
        for (ci, ch) in a.channels().enumerate() {
            let ci = self
                .channel_index
                .get(ai)
                .and_then(|m| m.get(ci))
                .copied()
                .unwrap_or(ci);
            let cpath = format!("animations[{ai}].channels[{ci}]");
            let target = ch.target();
            let node = target.node();
            let Some(new_node) = map.get(node.index()).copied().flatten() else {
                self.warnings.push(format!(
                    "{cpath}: targets node {} outside the displayed scene; ignored",
                    node.index()
                ));
                continue;
            };
            let sampler = ch.sampler();
            let spath = format!("animations[{ai}].samplers[{}]", sampler.index());
            let interpolation = match sampler.interpolation() {
                I::Step => Interpolation::Step,
                I::Linear => Interpolation::Linear,
                I::CubicSpline => Interpolation::CubicSpline,
            };
            let (ct, components) = match target.property() {
                Property::Translation => (ChannelTarget::Translation, 3),
                Property::Rotation => (ChannelTarget::Rotation, 4),
                Property::Scale => (ChannelTarget::Scale, 3),
                Property::MorphTargetWeights => {
                    let n = node
                        .mesh()
                        .and_then(|m| meshes.get(m.index()))
                        .map_or(0, |m| m.weights.len());
                    if n == 0 {
                        self.warnings.push(format!(
                            "{cpath}: weights channel on a node without morph targets; ignored"
                        ));
                        continue;
                    }
                    (ChannelTarget::Weights, n)
                }
            };
            let ipath = format!("{spath}.input");
            let (times, tn) = self.read_accessor(sampler.input().index(), &ipath)?;
            if tn != 1 {
                return Err(self.invalid(&ipath, "key times must be a scalar accessor"));
            }
            let times: Vec<f32> = times.into_iter().map(|t| t as f32).collect();
            if times.is_empty() {
                self.warnings
                    .push(format!("{cpath}: sampler has no keys; ignored"));
                continue;
            }
            if times.iter().any(|t| !t.is_finite()) || times.windows(2).any(|w| w[1] < w[0]) {
                return Err(self.invalid(&ipath, "key times must be finite and increasing"));
            }
            let opath = format!("{spath}.output");
            let (values, _) = self.read_accessor(sampler.output().index(), &opath)?;
            let per_key = components
                * if interpolation == Interpolation::CubicSpline {
                    3
                } else {
                    1
                };
            if values.len() != times.len() * per_key {
                return Err(self.invalid(
                    &opath,
                    format!(
                        "{} keys need {} values ({per_key} per key), found {}",
                        times.len(),
                        times.len() * per_key,
                        values.len()
                    ),
                ));
            }
            let values: Vec<f32> = values.into_iter().map(|v| v as f32).collect();
            if values.iter().any(|v| !v.is_finite()) {
                return Err(self.invalid(&opath, "NaN or infinite key value"));
            }
            anim.channels.push(Channel {
                node: NodeId(new_node),
                target: ct,
                interpolation,
                times,
                values,
                components,
            });
        }
        Ok(anim)
    }
}

fn tex_ref(info: &gltf::texture::Info) -> TextureRef {
    let mut r = TextureRef::new(TextureId(info.texture().index() as u32), info.tex_coord());
    if let Some(t) = info.texture_transform() {
        if let Some(tc) = t.tex_coord() {
            r.uv_set = tc;
        }
        let [ox, oy] = t.offset();
        let [sx, sy] = t.scale();
        let (s, c) = t.rotation().sin_cos();
        // KHR_texture_transform: uv' = T · R · S · uv with R = [[c, s], [-s, c]].
        r.transform = [
            Vec2::new(c * sx, -s * sx),
            Vec2::new(s * sy, c * sy),
            Vec2::new(ox, oy),
        ];
    }
    r
}

fn load_camera(c: &gltf::Camera) -> CameraDesc {
    let projection = match c.projection() {
        gltf::camera::Projection::Perspective(p) => Projection::Perspective {
            yfov: p.yfov(),
            aspect: p.aspect_ratio(),
            znear: p.znear(),
        },
        gltf::camera::Projection::Orthographic(o) => Projection::Orthographic {
            xmag: o.xmag(),
            ymag: o.ymag(),
        },
    };
    CameraDesc {
        name: c.name().unwrap_or_default().to_string(),
        projection,
    }
}

fn load_light(l: &gltf::khr_lights_punctual::Light) -> LightDesc {
    let kind = match l.kind() {
        gltf::khr_lights_punctual::Kind::Point => LightKind::Point,
        gltf::khr_lights_punctual::Kind::Directional => LightKind::Directional,
        gltf::khr_lights_punctual::Kind::Spot {
            inner_cone_angle,
            outer_cone_angle,
        } => LightKind::Spot {
            inner_cone: inner_cone_angle,
            outer_cone: outer_cone_angle,
        },
    };
    LightDesc {
        name: l.name().unwrap_or_default().to_string(),
        color: Rgb::from(l.color()),
        intensity: l.intensity(),
        kind,
    }
}

// ---------------------------------------------------------------------------------------
// Image decoding

type Decoded = (u32, u32, Vec<[u8; 4]>);

fn decode_image(bytes: &[u8]) -> Result<Decoded, String> {
    if bytes.starts_with(b"\x89PNG") {
        decode_png(bytes)
    } else if bytes.starts_with(&[0xFF, 0xD8]) {
        decode_jpeg(bytes)
    } else {
        Err("unsupported image format (only PNG and JPEG are supported)".into())
    }
}

/// Most pixels a texture may have (16384 × 8192; 512 MiB as RGBA8). A header claiming more
/// is refused before anything is allocated: fuzzing found a 12 kB GLB whose PNG header
/// claimed 841 TB of pixels, and the allocation aborted the process.
pub const MAX_TEXTURE_PIXELS: u64 = 1 << 27;

fn check_texture_size(kind: &str, w: u64, h: u64) -> Result<(), String> {
    if w * h > MAX_TEXTURE_PIXELS {
        return Err(format!(
            "{kind}: {w} × {h} pixels is larger than the {MAX_TEXTURE_PIXELS}-pixel texture limit"
        ));
    }
    Ok(())
}

fn decode_png(bytes: &[u8]) -> Result<Decoded, String> {
    let mut dec = png::Decoder::new(std::io::Cursor::new(bytes));
    dec.set_transformations(png::Transformations::normalize_to_color8());
    let mut reader = dec.read_info().map_err(|e| format!("PNG: {e}"))?;
    let header = reader.info();
    check_texture_size("PNG", header.width as u64, header.height as u64)?;
    let size = reader.output_buffer_size().ok_or("PNG: image too large")?;
    let mut buf = vec![0u8; size];
    let info = reader
        .next_frame(&mut buf)
        .map_err(|e| format!("PNG: {e}"))?;
    let (w, h) = (info.width, info.height);
    let px = (w as usize) * (h as usize);
    let ch = match info.color_type {
        png::ColorType::Grayscale => 1,
        png::ColorType::GrayscaleAlpha => 2,
        png::ColorType::Rgb => 3,
        png::ColorType::Rgba => 4,
        png::ColorType::Indexed => return Err("PNG: palette was not expanded".into()),
    };
    let mut out = Vec::with_capacity(px);
    for y in 0..h as usize {
        let row = buf
            .get(y * info.line_size..(y + 1) * info.line_size)
            .ok_or("PNG: short image data")?;
        for c in row.chunks_exact(ch).take(w as usize) {
            out.push(match ch {
                1 => [c[0], c[0], c[0], 255],
                2 => [c[0], c[0], c[0], c[1]],
                3 => [c[0], c[1], c[2], 255],
                _ => [c[0], c[1], c[2], c[3]],
            });
        }
    }
    if out.len() != px {
        return Err("PNG: short image data".into());
    }
    Ok((w, h, out))
}

fn decode_jpeg(bytes: &[u8]) -> Result<Decoded, String> {
    use zune_jpeg::zune_core::colorspace::ColorSpace;
    use zune_jpeg::zune_core::options::DecoderOptions;
    let opts = DecoderOptions::default().jpeg_set_out_colorspace(ColorSpace::RGBA);
    let mut dec = zune_jpeg::JpegDecoder::new_with_options(
        zune_jpeg::zune_core::bytestream::ZCursor::new(bytes),
        opts,
    );
    dec.decode_headers().map_err(|e| format!("JPEG: {e:?}"))?;
    let (w, h) = dec.dimensions().ok_or("JPEG: no dimensions")?;
    check_texture_size("JPEG", w as u64, h as u64)?;
    let data = dec.decode().map_err(|e| format!("JPEG: {e:?}"))?;
    let (w, h) = dec.dimensions().ok_or("JPEG: no dimensions")?;
    let out: Vec<[u8; 4]> = data
        .chunks_exact(4)
        .map(|c| [c[0], c[1], c[2], c[3]])
        .collect();
    if out.len() != w * h {
        return Err("JPEG: short image data".into());
    }
    Ok((w as u32, h as u32, out))
}
