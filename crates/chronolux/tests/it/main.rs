//! End-to-end tests of the `chronolux` binary: each runs the built executable in its own
//! temporary folder, at tiny resolutions and sample counts so that each takes well under a
//! second or two.

mod bad_input;
mod common;
mod config;
mod farm;
mod info;
mod kill_resume;
mod passes;
mod render;
mod shutter;
mod stbpt;
