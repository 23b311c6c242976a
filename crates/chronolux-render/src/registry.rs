//! The one place where technique names map to types.

use crate::bdpt::{Bdpt, BdptSettings};
use crate::pt::{PathSettings, PathTracer};
use crate::sequence::{FrameByFrame, SequenceRenderer};

/// Techniques selectable with `--method`.
pub const METHODS: &[(&str, &str)] = &[
    (
        "path",
        "unidirectional path tracing with NEE and MIS (the reference)",
    ),
    (
        "bdpt",
        "bidirectional path tracing, all strategies with MIS, frame by frame",
    ),
];

/// A technique and its settings.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
#[serde(tag = "method", rename_all = "kebab-case", deny_unknown_fields)]
pub enum TechniqueConfig {
    Path(PathSettings),
    Bdpt(BdptSettings),
}

impl TechniqueConfig {
    pub fn build(&self) -> Box<dyn SequenceRenderer + Send> {
        match self {
            TechniqueConfig::Path(s) => Box::new(FrameByFrame {
                integrator: PathTracer::new(s.clone()),
                name: "path",
            }),
            TechniqueConfig::Bdpt(s) => Box::new(FrameByFrame {
                integrator: Bdpt::new(s.clone()),
                name: "bdpt",
            }),
        }
    }
}
