//! Water drops on a windshield (Gotou, Tanaka & Sagawa, *Real-Time Rendering of Flow of Water
//! Drops on a Windshield*, Meijo University): the drops' simulation on the glass ([`sim`]: the
//! mesh model away from the wipers, the particle model near them, the rain's arrival), when a
//! drop slides ([`furmidge`]), and their drawing as refracting 2D metaballs ([`render`]).

pub mod clock;
pub mod furmidge;
mod merge;
pub mod render;
pub mod sim;
pub mod stage;
pub mod steady;

pub use sim::{DropKind, Metaball, Windshield, WindshieldConfig, WindshieldState, Wiper};
