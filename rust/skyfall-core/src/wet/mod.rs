//! Wet surfaces: the water the rain leaves on a scene's surfaces ([`film`]), how it changes
//! their look ([`optics`]: darker, after Lekner & Dorf, and mirroring, after Fresnel), and the
//! stage that draws it after the scene ([`stage`]); where it stands in puddles, and the grain of
//! the film's reflection elsewhere ([`puddles`]).

pub mod film;
pub mod optics;
pub mod puddles;
pub mod stage;
