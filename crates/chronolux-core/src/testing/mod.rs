//! The test harness shared by every crate's tests: statistical tests of Monte Carlo images
//! ([`stats`]), evidence images written when such a test fails ([`evidence`]), and the one
//! policy for tests that need something outside the repository ([`external`]).
//!
//! Pure functions with no test-framework dependency, so integration tests, unit tests in
//! `src` and the command-line crate's tests all call the same code.

pub mod evidence;
pub mod external;
pub mod stats;

pub use external::{flip_python, require_external, shared_file};
pub use stats::{BlockTest, Estimate, block_t_test, block_z_test, channel_means};
