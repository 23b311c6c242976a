//! The one integration-test binary of chronolux-core (statistical tests).

mod bsdf;
<<<<<<< HEAD
mod chi2;
mod light;
=======
mod metrics;
>>>>>>> yard
