//! The one integration-test binary of chronolux-core (statistical tests).

mod bsdf;
mod chi2;
mod delta;
mod light;
mod metrics;
