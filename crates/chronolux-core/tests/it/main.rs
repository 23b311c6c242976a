//! The one integration-test binary of chronolux-core (statistical tests).

mod auto_camera;
mod bsdf;
mod chi2;
mod delta;
mod envmap;
mod hostile;
mod light;
mod metrics;
