//! Scenes: the plain description ([`desc`]), animation evaluation ([`anim`]), the
//! render-ready frame ([`frame`]), what changed between frames ([`delta`]) and scenes built
//! in code for tests ([`testing`]).

pub mod anim;
pub mod delta;
pub mod desc;
pub mod frame;
pub mod generated;
pub mod source;
pub mod stage;
pub mod testing;
