//! `chronolux reference`: converged references, rendered progressively to a target error.

use anyhow::{Result, bail};
use clap::Args;

#[derive(Args, Debug)]
pub struct ReferenceArgs {}

pub fn run(_args: ReferenceArgs) -> Result<()> {
    bail!("`chronolux reference` is not available in this build yet")
}
