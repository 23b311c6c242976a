//! The one place where technique names map to types.

use crate::bdpt::{Bdpt, BdptSettings};
use crate::dept::{Dept, DeptSequence, DeptSettings};
use crate::pt::{PathSettings, PathTracer};
use crate::sequence::{FrameByFrame, SequenceRenderer};
use crate::temporal::spacetime_dept::{SpacetimeDept, SpacetimeSettings};
use crate::temporal::stbpt::{Stbpt, StbptSettings};

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
    (
        "dept",
        "photon density estimation on mesh elements, frame by frame, no filtering",
    ),
    (
        "dept-spatial",
        "photon density estimation on mesh elements, spatial Gaussian filter",
    ),
    (
        "dept-bilateral",
        "photon density estimation on mesh elements, spatial bilateral filter",
    ),
    (
        "stbpt",
        "spatio-temporal BDPT: each sample reused in the frames of a window [f-K, f+K]",
    ),
    (
        "spacetime-dept",
        "photon density estimation on mesh elements, space-time window + bilateral filter",
    ),
];

/// A technique and its settings.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
#[serde(tag = "method", rename_all = "kebab-case", deny_unknown_fields)]
pub enum TechniqueConfig {
    Path(PathSettings),
    Bdpt(BdptSettings),
    Dept(DeptSettings),
    DeptSpatial(DeptSettings),
    DeptBilateral(DeptSettings),
    SpacetimeDept(SpacetimeSettings),
    Stbpt(StbptSettings),
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
            TechniqueConfig::Dept(s) => Box::new(DeptSequence::new(Dept::new(s.clone()), "dept")),
            TechniqueConfig::DeptSpatial(s) => {
                Box::new(DeptSequence::new(Dept::new(s.clone()), "dept-spatial"))
            }
            TechniqueConfig::DeptBilateral(s) => {
                Box::new(DeptSequence::new(Dept::new(s.clone()), "dept-bilateral"))
            }
            TechniqueConfig::SpacetimeDept(s) => Box::new(SpacetimeDept::new(s.clone())),
            TechniqueConfig::Stbpt(s) => Box::new(Stbpt::new(s.clone())),
        }
    }
}
