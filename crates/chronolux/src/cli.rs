//! The command tree (clap): one variant per subcommand, each holding that command's
//! arguments from its own module. Nothing below imports it; `main` dispatches on it.

use clap::{Parser, Subcommand};

#[derive(Parser, Debug)]
#[command(
    name = "chronolux",
    version,
    about = "Global-illumination renderer for glTF 2.0 animations",
    long_about = "Chronolux renders animated glTF 2.0 scenes (.gltf/.glb) to frame sequences \
(linear OpenEXR + sRGB PNG + an animated preview) with physically based light transport. \
Without a scene it renders a built-in animated Cornell box."
)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Command,
}

#[derive(Subcommand, Debug)]
pub enum Command {
    /// Render frames of an animation (or the built-in demo when no SCENE is given).
    Render(crate::args::RenderArgs),
    /// Print what a scene contains: geometry, materials, lights, cameras, animations.
    Info(crate::info::InfoArgs),
    /// Compare a rendered frame sequence with a reference sequence: relMSE, FLIP, flicker.
    Compare(crate::compare::CompareArgs),
    /// Render converged reference frames, progressively, until their estimated error is
    /// below a target.
    Reference(crate::reference::ReferenceArgs),
    /// Measure speed: ray casting, BVH builds, path samples, equal-quality comparisons.
    Bench(crate::bench::BenchArgs),
    /// Cut a render into segments for a farm: the frames each owns and the neighbouring
    /// frames its technique needs (printed as JSON; `render --plan` runs a segment).
    Plan(crate::farm::PlanArgs),
    /// Write (and optionally submit) a farm job: `slurm` (sbatch job array) or `openjd`
    /// (Open Job Description template for Deadline Cloud).
    Farm(crate::farm::FarmArgs),
    /// Check a farm render's folder: every frame present and readable, manifests merged
    /// into run.json, preview written, seams between segments measured.
    Assemble(crate::farm::AssembleArgs),
    /// Live viewer: a page on 127.0.0.1 showing the progressive image while you move the
    /// animation time, nodes and lights and change materials (selective photon tracing
    /// updates the indirect light).
    View(crate::view::ViewArgs),
}
