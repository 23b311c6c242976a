//! `chronolux compare`: image error and flicker between two frame sequences.

use anyhow::{Result, bail};
use clap::Args;

#[derive(Args, Debug)]
pub struct CompareArgs {}

pub fn run(_args: CompareArgs) -> Result<()> {
    bail!("`chronolux compare` is not available in this build yet")
}
