//! The one integration-test binary of chronolux-io.

mod gltf;
mod image;
mod output;
