//! `chronolux bench`: speed measurements (rays/s, BVH builds, samples/s) and equal-quality comparisons.

use anyhow::{Result, bail};
use clap::Args;

#[derive(Args, Debug)]
pub struct BenchArgs {}

pub fn run(_args: BenchArgs) -> Result<()> {
    bail!("`chronolux bench` is not available in this build yet")
}
