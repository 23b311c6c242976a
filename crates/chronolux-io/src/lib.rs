//! # chronolux-io
//!
//! Bytes ↔ values, no light transport: glTF 2.0 scenes with animation into
//! [`chronolux_core::scene::desc::SceneDesc`] ([`gltf`]), images out and reference images in
//! ([`image`]), environment maps in ([`envmap`]), and frame sequences on disk with their manifest ([`output`]); every file is
//! written through [`atomic`].

pub mod atomic;
pub mod envmap;
pub mod gltf;
pub mod image;
pub mod output;
