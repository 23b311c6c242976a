//! # chronolux-core
//!
//! Everything one frame of an animation needs, and nothing about how frames are rendered
//! over time or stored on disk.
//!
//! ## Conventions
//! - **Units and colour**: scene-referred linear RGB ([`color::Rgb`]). A material with
//!   emission 1.0 has radiance 1.0. Punctual lights follow the convention of the Khronos
//!   sample viewer and three.js: a point light of `I` candela has radiant intensity `I` in
//!   these units (W/sr-equivalent), a directional light of `E` lux gives irradiance `E`.
//! - **Handedness**: glTF's right-handed frame, +Y up, cameras look down their local −Z.
//! - **Directions**: `wo` points away from the surface towards the viewer (or previous
//!   vertex), `wi` away from the surface towards the light (or next vertex). Both unit
//!   length. In a local shading frame the normal is +Z.
//! - **Measures**: every `pdf` says in its doc whether it is with respect to solid angle or
//!   area. BSDF pdfs are solid angle; light `sample_li` pdfs are solid angle; delta
//!   distributions return pdf 1 with an `is_delta` flag.
//! - **Transforms** are named by direction: `world_from_object` maps object space to world.
//! - **Determinism**: every random number comes from a stream keyed by what it serves
//!   ([`sampling::sampler`]); results do not depend on thread count or scheduling.
//!
//! ## Layers (a module may use those listed before it, never after)
//! `math` → `color` → `stats` → `parallel` → `sampling` → `geometry` → `accel` → `texture`
//! → `bsdf` → `material` → `scene::desc` → `scene::anim` → `light` → `camera` → `film`
//! → `scene::frame` → `scene::testing` → `testing` (the test harness: statistics, evidence
//! images, external data; used by tests only).

pub mod accel;
pub mod bsdf;
pub mod camera;
pub mod color;
pub mod film;
pub mod geometry;
pub mod light;
pub mod material;
pub mod math;
pub mod metrics;
pub mod parallel;
pub mod sampling;
pub mod scene;
pub mod stats;
pub mod testing;
pub mod texture;
