//! Techniques: one module per `--method`, each a registry entry ([`crate::registry`]
//! lists them) over the framework and the kernels. A technique imports
//! [`crate::framework`] and [`crate::kernels`], never another technique: what two
//! techniques share is a kernel.
//!
//! Frame by frame (the baselines): [`path`], [`bdpt`], [`dept`] (with its `-spatial` and
//! `-bilateral` presets), [`pm_ic`]. Temporal (the MPI temporal-coherence work):
//! [`spacetime_dept`], [`spt`], [`ic_static_dynamic`], [`ic_selective`], [`stbpt`].

pub mod bdpt;
pub mod dept;
pub mod ic_selective;
pub mod ic_static_dynamic;
pub mod path;
pub mod pm_ic;
pub mod spacetime_dept;
pub mod spt;
pub mod stbpt;
