//! The one integration-test binary of chronolux-io.

mod fuzz;
mod gltf;
mod image;
mod output;
