//! Wet surfaces: the water the rain leaves on a scene's surfaces ([`film`]), how it changes
//! their look ([`optics`]: darker, after Lekner & Dorf, and mirroring, after Fresnel), and the
//! stage that draws it after the scene ([`stage`]).

pub mod film;
pub mod optics;
pub mod stage;
