//! Rain: precomputed rain-streak textures (Yoshida, Dobashi & Yamamoto, fast rendering of rain
//! streaks), drops and billboards anchored in the world, shelter under boxes, and the rain's
//! streaks drawn through the particle toolkit ([`crate::particles`]).

pub mod billboards;
pub mod bins;
pub mod drops;
pub mod shelter;
pub mod streaks;
pub mod texture;
