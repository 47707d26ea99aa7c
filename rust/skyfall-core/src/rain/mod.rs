//! Rain streaks from precomputed rain textures (seed 000, Yoshida, Dobashi & Yamamoto).

pub mod billboards;
pub mod bins;
pub mod drops;
pub mod shelter;
pub mod splat;
pub mod texture;
