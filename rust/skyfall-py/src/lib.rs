//! `skyfall._core`: thin pyo3 wrappers over `skyfall-core`. The public API is the Python
//! package `skyfall`; this module's contract is `python/skyfall/_core.pyi`.

mod alloc;
mod boxes;
mod clouds;
mod color;
mod errors;
mod interrupt;
mod photo;
mod physics;
mod rain;
mod rain_frame;
mod ranges;
mod render;
mod request;
mod sky;
mod snow;
mod snow_frame;
mod weather;
mod windshield;

use pyo3::prelude::*;

#[pymodule]
mod _core {
    #[pymodule_export]
    use super::clouds::{
        CloudDome, CloudField, attenuation_volume, check_sun_direction, cloud_particles,
        cloud_path_traced, harris_illumination, sample_attenuation,
    };
    #[pymodule_export]
    use super::color::{apply_lut8, encode_srgb8};
    #[pymodule_export]
    use super::errors::{GpuUnavailableError, SkyfallError};
    #[pymodule_export]
    use super::photo::{atmospheric_light_pixel, dark_channel};
    #[pymodule_export]
    use super::physics::{
        air_density_kg_m3, air_viscosity, drops_per_m3, marshall_palmer, rain_extinction_per_m,
        rain_rate_from_dsd, terminal_velocity_m_s,
    };
    #[pymodule_export]
    use super::rain::{rain_diameter_bins, rain_textures};
    #[pymodule_export]
    use super::rain_frame::rain_drops;
    #[pymodule_export]
    use super::ranges::check_range;
    #[pymodule_export]
    use super::render::{GpuDevice, frame_plan, render_frame, render_frame8, render_photo8};
    #[pymodule_export]
    use super::sky::{AmbientHorizon, AmbientLightMap, SkyModel, ambient_horizon, cloud_base_m};
    #[pymodule_export]
    use super::snow::{SnowCoverGrid, snow_cover_boxes, snow_cover_photo};
    #[pymodule_export]
    use super::snow_frame::snowflakes;
    #[pymodule_export]
    use super::weather::{weather_optics, weather_sun};
    #[pymodule_export]
    use super::windshield::{
        GlassClock, Windshield, furmidge_critical, metaball_height_map, metaball_normals,
        refract_through_drops, windshield_gpu,
    };

    use pyo3::prelude::*;

    #[pymodule_init]
    fn init(m: &Bound<'_, PyModule>) -> PyResult<()> {
        m.add("__version__", env!("CARGO_PKG_VERSION"))?;
        m.add("SNOW_ALBEDO", skyfall_core::snow::SNOW_ALBEDO)?;
        {
            use skyfall_core::snow::cover::look;
            m.add("SNOW_COVER_FULL_M", look::COVER_FULL_M)?;
            m.add("SNOW_PATCH_M", look::SNOW_PATCH_M)?;
            m.add("SNOW_PATCH_BLEND", (look::SHARP_BELOW, look::BLEND_FROM))?;
        }
        m.add("RANGES", super::ranges::table(m.py())?)?;
        // The frame layers, name -> meaning, in the order frames list them.
        let layers = pyo3::types::PyDict::new(m.py());
        for l in skyfall_core::frame::layers::Layer::ALL {
            layers.set_item(l.name(), l.meaning())?;
        }
        m.add("LAYERS", layers)?;
        // Each layer's value where its pass drew nothing (a frame without rain: rain_alpha 0).
        let neutral = pyo3::types::PyDict::new(m.py());
        for l in skyfall_core::frame::layers::Layer::ALL {
            neutral.set_item(l.name(), l.neutral())?;
        }
        m.add("LAYER_NEUTRAL", neutral)?;
        m.add("RANGE_MEANINGS", super::ranges::meanings(m.py())?)?;
        m.add(
            "TEXTURE_BUDGET_BYTES",
            skyfall_core::rain::texture::TEXTURE_BUDGET_BYTES,
        )?;
        m.add(
            "MAX_DIAMETER_MM",
            skyfall_core::physics::fall_speed::DIAMETER_MM.hi,
        )?;
        m.add(
            "MAX_RAIN_RATE_MM_H",
            skyfall_core::physics::dsd::RAIN_RATE_MM_H.hi,
        )?;
        m.add("KOSCHMIEDER", skyfall_core::weather::KOSCHMIEDER)?;
        m.add("AIRLIGHT_PATCH_PX", skyfall_core::haze::airlight::PATCH_PX)?;
        m.add(
            "AIRLIGHT_TOP_FRACTION",
            skyfall_core::haze::airlight::TOP_FRACTION,
        )?;
        m.add("AMBIENT_EXTENT_M", skyfall_core::sky::ambient::MAP_EXTENT_M)?;
        m.add("CLOUD_DOME_FACE_PX", skyfall_core::cloud::dome::FACE_PX)?;
        m.add("HORIZON_MAX_PAIRS", skyfall_core::sky::horizon::MAX_PAIRS)?;
        m.add(
            "FRAME_BUDGET_BYTES",
            skyfall_core::frame::FRAME_BUDGET_BYTES,
        )?;
        Ok(())
    }
}
