//! The live viewer of `chronolux view`: a page on a local web server showing the
//! progressive image of the current camera while the user moves the animation time,
//! nodes and lights, and changes materials; selective photon tracing (`spt`) brings the
//! indirect light up to date after each change, queued groups first by priority.
//!
//! - [`scene`]: the scene plus the user's edits, built into frames;
//! - [`engine`]: the render loop's state (the SPT pool, the image being refined);
//! - [`server`]: the routes (embedded page, server-sent events, edits) and the threads.
//!
//! The renderer crates never depend on this one, so they never compile the web stack.

pub mod engine;
pub mod scene;
pub mod server;

pub use engine::{Frame, Status, ViewOptions, Viewer};
pub use scene::{Edit, EditableScene};
pub use server::{DEFAULT_BIND, Running, bind, router, start};
