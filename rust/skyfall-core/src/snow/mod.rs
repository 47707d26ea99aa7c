//! Snow after Koitabashi, Matsubara, Moriya & Takahashi, *Snowfall and snow-cover scenes with
//! wind*: the flakes falling with the wind (drawn through the particle toolkit) and the cover
//! they lay where the wind lets them. The flakes' sizes, masses and speeds are
//! [`crate::physics::snow`].

pub mod cover;
