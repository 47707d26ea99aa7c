//! Rain: precomputed rain-streak textures (Yoshida, Dobashi & Yamamoto, fast rendering of rain
//! streaks), drops and billboards anchored in the world, shelter under boxes, the rain's
//! streaks drawn through the particle toolkit ([`crate::particles`]), and the far level of
//! detail that draws the far drops as pre-rasterised layers ([`far`]).

pub mod billboards;
pub mod bins;
pub mod drops;
pub mod far;
pub mod shelter;
pub mod streaks;
pub mod texture;
