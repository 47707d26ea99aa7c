//! Every valid range of a user-facing parameter, declared once.
//!
//! One [`Limit`] per parameter, named as the user writes it (`exposure_s`, not "the
//! exposure"), with its interval, unit and meaning. The core's checks use these, the Python
//! bindings check their arguments against them, and `skyfall._core.RANGES` exports [`ALL`] to
//! Python, whose own checks (`skyfall._validate.in_range`) read it and leave the message to
//! [`check_named`]: a value outside a range is refused with the same words on every path
//! (`exposure_s = 0.2 is outside the valid range [1e-6, 0.1] s`).
//!
//! Choices where the checks had drifted apart:
//! - `exposure_s` is [1e-6, 0.1] s (the camera's) for the rain textures and the bindings too
//!   (they took (0, 0.1]): 1 µs is shorter than any shutter, and below it the f32 the passes
//!   use rounds a tiny exposure to 0 (1e-300 s was accepted, then drawn as T = 0).
//! - `sun_elevation_deg` is [0, 90] deg (the Weather's): the CIE general skies model a sun
//!   above the horizon, and the bindings' former [-90, 90] let through suns the sky refused
//!   later for the types that depend on it and ignored silently for the others.
//! - `cloud_base_m(rain_rate_mm_h)` takes the rain rate's own [0, 500] mm/h (the bindings
//!   allowed [0, 10000], beyond every other use of the rate).
//! - `sky_illuminance_lux` is [1e-4, 150000] lx (the Weather's) for frames made through the
//!   bindings too (they accepted any positive number).

use crate::error::{Error, Param, Range, Result};

/// A user-facing parameter's valid range.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Limit {
    /// The parameter's name as the user writes it.
    pub name: &'static str,
    /// Its valid interval, with unit.
    pub range: Range,
    /// What it is, in one line.
    pub meaning: &'static str,
}

impl Limit {
    const fn new(name: &'static str, range: Range, meaning: &'static str) -> Self {
        Limit {
            name,
            range,
            meaning,
        }
    }

    /// Checks a value of this parameter.
    pub fn check(&self, value: f64) -> Result<f64> {
        self.range.check(self.name, None, value)
    }

    /// Checks element `index` of an array parameter.
    pub fn check_at(&self, index: Option<usize>, value: f64) -> Result<f64> {
        self.range.check(self.name, index, value)
    }

    /// Checks every element (indices named only for arrays longer than one).
    pub fn check_all(&self, values: &[f64]) -> Result<()> {
        self.range.check_all(self.name, values)
    }
}

const INF: f64 = f64::INFINITY;

// Weather.
/// Rain rate R.
pub const RAIN_RATE_MM_H: Limit = Limit::new(
    "rain_rate_mm_h",
    Range::closed(0.0, 500.0, "mm/h"),
    "rain rate R (0: no drops, zero extinction)",
);
/// Rain rates of a texture set (each as [`RAIN_RATE_MM_H`]).
pub const RAIN_RATES_MM_H: Limit = Limit::new(
    "rain_rates_mm_h",
    RAIN_RATE_MM_H.range,
    "rain rates of a set of rain textures",
);
/// Snowfall rate as liquid-water equivalent.
pub const SNOW_RATE_MM_H: Limit = Limit::new(
    "snow_rate_mm_h",
    Range::closed(0.0, 100.0, "mm/h"),
    "snowfall rate as liquid-water equivalent (0: no flakes, no cover)",
);
/// Bulk density of the snow lying on the ground.
pub const SNOW_DENSITY_KG_M3: Limit = Limit::new(
    "snow_density_kg_m3",
    Range::closed(20.0, 917.0, "kg/m^3"),
    "bulk density of the snow cover (fresh snow 70-150; 917: solid ice)",
);
/// How long the snow of a cover falls (`skyfall.snow.accumulate`).
pub const DURATION_S: Limit = Limit::new(
    "duration_s",
    Range::closed(0.0, 1e7, "s"),
    "how long the snow of a cover falls (0: no cover)",
);
/// A simulation's time step: the snow cover's and the windshield's (one name, one range).
pub const DT_S: Limit = Limit::new(
    "dt_s",
    Range::open_closed(0.0, 1e7, "s"),
    "time step: of the snow cover's accumulation (longer than duration_s: one step), or of a \
     windshield (run in internal steps of at most 1/120 s, so its cost grows with dt_s)",
);
/// Cell side of the cover's height field.
pub const RESOLUTION_M: Limit = Limit::new(
    "resolution_m",
    Range::closed(0.01, 100.0, "m"),
    "cell side of the snow cover's height field",
);
/// Amplitude of the cover's random factor.
pub const ROUGHNESS: Limit = Limit::new(
    "roughness",
    Range::closed(0.0, 1.0, ""),
    "amplitude of the snow cover's random factor r = 1 + roughness u, u in [-1, 1]",
);
/// The gusts of the snow cover's wind, as a share of the mean wind.
pub const TURBULENCE: Limit = Limit::new(
    "turbulence",
    Range::closed(0.0, 2.0, ""),
    "standard deviation of each horizontal component of the snow cover's gusts, as a share of \
     the mean wind (over cities 0.3-0.4; 0: no gusts)",
);
/// How long the rain has fallen on the surfaces (`Weather.rain_duration_s`).
pub const RAIN_DURATION_S: Limit = Limit::new(
    "rain_duration_s",
    Range::closed(0.0, 1e7, "s"),
    "how long the rain has fallen on the surfaces (0: dry surfaces; None: long enough to fill them)",
);
/// How long ago the rain stopped (`Weather.dry_s`).
pub const DRY_S: Limit = Limit::new(
    "dry_s",
    Range::closed(0.0, 1e7, "s"),
    "how long ago the rain stopped: the surfaces dry and no rain falls (0: it is raining)",
);
/// Meteorological visibility of the air without rain.
pub const VISIBILITY_M: Limit = Limit::new(
    "visibility_m",
    Range::closed(0.01, INF, "m"),
    "meteorological visibility of the air without rain (inf: perfectly clear)",
);
/// Horizontal illuminance of the open sky at the ground.
pub const SKY_ILLUMINANCE_LUX: Limit = Limit::new(
    "sky_illuminance_lux",
    Range::closed(1e-4, 150_000.0, "lx"),
    "horizontal illuminance E of the open sky at the ground, rain included",
);
/// Wind velocity, per component.
pub const WIND_M_S: Limit = Limit::new(
    "wind_m_s",
    Range::closed(-60.0, 60.0, "m/s"),
    "wind velocity, each of x, y, z",
);
/// Radius of the rain region drawn as streaks.
pub const RAIN_NEAR_M: Limit = Limit::new(
    "rain_near_m",
    Range::open_closed(0.0, 50.0, "m"),
    "radius of the rain region around the camera drawn as streaks",
);
/// Where the rain's far level of detail begins (below `rain_near_m`, checked with it).
pub const RAIN_FAR_M: Limit = Limit::new(
    "rain_far_m",
    Range::open_closed(0.0, 50.0, "m"),
    "horizontal distance beyond which the rain's drops are drawn as pre-rasterised layers",
);
/// Radius of the snow region drawn as flakes.
pub const SNOW_NEAR_M: Limit = Limit::new(
    "snow_near_m",
    Range::open_closed(0.0, 50.0, "m"),
    "radius of the snow region around the camera drawn as flakes",
);
/// Drop diameters whose bins are drawn.
pub const RAIN_DIAMETERS_MM: Limit = Limit::new(
    "rain_diameters_mm",
    Range::open_closed(0.0, 8.0, "mm"),
    "drop diameters (strictly increasing) whose bins are drawn",
);
/// Texture diameters (each as [`RAIN_DIAMETERS_MM`]).
pub const DIAMETERS_MM: Limit = Limit::new(
    "diameters_mm",
    RAIN_DIAMETERS_MM.range,
    "drop diameters (strictly increasing) of rain textures and their bins",
);
/// CIE general sky type.
pub const SKY: Limit = Limit::new(
    "sky",
    Range::closed(1.0, 15.0, "").integers(),
    "CIE S 011 general sky type (or \"overcast\")",
);
/// The sun's elevation.
pub const SUN_ELEVATION_DEG: Limit = Limit::new(
    "sun_elevation_deg",
    Range::closed(0.0, 90.0, "deg"),
    "the sun's elevation above the horizon",
);
/// The sun's direct normal illuminance.
pub const SUN_ILLUMINANCE_LUX: Limit = Limit::new(
    "sun_illuminance_lux",
    Range::closed(0.0, 150_000.0, "lx"),
    "the sun's direct illuminance on a surface facing it, at the ground",
);
/// The sun's azimuth.
pub const SUN_AZIMUTH_DEG: Limit = Limit::new(
    "sun_azimuth_deg",
    Range::open(-INF, INF, "deg"),
    "the sun's azimuth from -Z (north) towards +X (east), any finite angle",
);
/// Elevation of a direction the sky is looked up in.
pub const ELEVATION_DEG: Limit = Limit::new(
    "elevation_deg",
    Range::closed(-90.0, 90.0, "deg"),
    "elevation of a viewing direction above the horizon (below it the sky is 0)",
);
/// Azimuth of a direction the sky is looked up in.
pub const AZIMUTH_DEG: Limit = Limit::new(
    "azimuth_deg",
    Range::open(-INF, INF, "deg"),
    "azimuth of a viewing direction from -Z towards +X, any finite angle",
);
/// Cloud base height.
pub const CLOUD_BASE_M: Limit = Limit::new(
    "cloud_base_m",
    Range::closed(1.0, 20_000.0, "m"),
    "cloud base height H above the ground",
);

// Camera.
/// Frame and camera width or height.
pub const SIDE_PX: Range = Range::closed(1.0, 16_384.0, "px").integers();
/// Frame width.
pub const WIDTH: Limit = Limit::new("width", SIDE_PX, "frame width");
/// Frame height.
pub const HEIGHT: Limit = Limit::new("height", SIDE_PX, "frame height");
/// World coordinate of a camera or light.
pub const POSITION_M: Limit = Limit::new(
    "position_m",
    Range::closed(-1e7, 1e7, "m"),
    "world position of a camera or light, each coordinate",
);
/// Camera heading.
pub const YAW_DEG: Limit = Limit::new(
    "yaw_deg",
    Range::open(-INF, INF, "deg"),
    "camera heading about +Y, any finite angle",
);
/// Camera pitch.
pub const PITCH_DEG: Limit = Limit::new(
    "pitch_deg",
    Range::closed(-89.0, 89.0, "deg"),
    "elevation of the camera's view direction",
);
/// Vertical field of view.
pub const VERTICAL_FOV_DEG: Limit = Limit::new(
    "vertical_fov_deg",
    Range::closed_open(0.001, 179.0, "deg"),
    "vertical field of view",
);
/// Focal lengths in pixels.
pub const FOCAL_PX: Range = Range::open_closed(0.0, 1e9, "px");
/// Horizontal focal length.
pub const FX: Limit = Limit::new("fx", FOCAL_PX, "horizontal focal length");
/// Vertical focal length.
pub const FY: Limit = Limit::new("fy", FOCAL_PX, "vertical focal length");
/// Principal point coordinates in pixels.
pub const PRINCIPAL_PX: Range = Range::closed(-1e9, 1e9, "px");
/// Principal point, x.
pub const CX: Limit = Limit::new("cx", PRINCIPAL_PX, "principal point, x");
/// Principal point, y.
pub const CY: Limit = Limit::new("cy", PRINCIPAL_PX, "principal point, y");
/// Shutter time.
pub const EXPOSURE_S: Limit = Limit::new(
    "exposure_s",
    Range::closed(1e-6, 0.1, "s"),
    "shutter time T: a drop's streak is its path v T (a streak must fit in the 1 m texture)",
);
/// A lens's focal length.
pub const FOCAL_LENGTH_MM: Limit = Limit::new(
    "focal_length_mm",
    Range::closed(1.0, 5000.0, "mm"),
    "lens focal length f: with sensor_width_mm it sets the field of view (fx = f / sensor width · frame width)",
);
/// The sensor's width.
pub const SENSOR_WIDTH_MM: Limit = Limit::new(
    "sensor_width_mm",
    Range::closed(1.0, 500.0, "mm"),
    "sensor width (36: full frame), which maps focal lengths and blur circles to pixels",
);
/// A lens's f-number.
pub const F_NUMBER: Limit = Limit::new(
    "f_number",
    Range::closed(0.5, 256.0, ""),
    "f-number N = f / aperture diameter (thin lens; left out: a pinhole)",
);
/// A lens's focus distance.
pub const FOCUS_DISTANCE_M: Limit = Limit::new(
    "focus_distance_m",
    Range::open_closed(0.0, INF, "m"),
    "distance in focus along the optical axis (inf: focused at infinity); more than the focal length",
);
/// The camera's speed.
pub const VELOCITY_M_S: Limit = Limit::new(
    "velocity_m_s",
    Range::closed(0.0, 1000.0, "m/s"),
    "the camera's own speed |v|",
);

// Lights.
/// Luminous intensity of a light.
pub const INTENSITY_CD: Limit = Limit::new(
    "intensity_cd",
    Range::closed(0.0, 1e9, "cd"),
    "luminous intensity of a light (on the axis of a spot)",
);
/// Colour multiplier of a light.
pub const COLOR: Limit = Limit::new(
    "color",
    Range::closed(0.0, 1000.0, ""),
    "linear RGB multiplier of a light's intensity, each channel",
);
/// Outer half-angle of a spot light.
pub const CONE_DEG: Limit = Limit::new(
    "cone_deg",
    Range::open_closed(0.0, 90.0, "deg"),
    "outer half-angle of a spot light's cone",
);

// Frames and sky light.
/// Time of a frame.
pub const TIME_S: Limit = Limit::new(
    "time_s",
    Range::closed(-1e7, 1e7, "s"),
    "time of a frame: drops have fallen v time_s",
);
// Clouds (`cloud/`).
/// Particles of a generated cloud.
pub const N_PARTICLES: Limit = Limit::new(
    "n_particles",
    Range::closed(1.0, 1_000_000.0, "").integers(),
    "particles of a generated cloud",
);
/// Horizontal extent of a generated cloud.
pub const EXTENT_M: Limit = Limit::new(
    "extent_m",
    Range::closed(10.0, 100_000.0, "m"),
    "horizontal extent of a generated cloud (a cell's diameter, a field's side)",
);
/// Altitude of a generated cloud's base.
pub const ALTITUDE_M: Limit = Limit::new(
    "altitude_m",
    Range::closed(0.0, 20_000.0, "m"),
    "altitude of a generated cloud's base above y = 0",
);
/// A cloud particle's position coordinate.
pub const POSITIONS_M: Limit = Limit::new(
    "positions_m",
    Range::closed(-1e7, 1e7, "m"),
    "a cloud particle's world coordinate",
);
/// A cloud particle's Gaussian radius.
pub const RADII_M: Limit = Limit::new(
    "radii_m",
    Range::open_closed(0.0, 1e5, "m"),
    "a cloud particle's Gaussian 1/e radius",
);
/// A cloud particle's optical depth through its centre.
pub const OPTICAL_DEPTHS: Limit = Limit::new(
    "optical_depths",
    Range::closed(0.0, 1e4, ""),
    "a cloud particle's extinction optical depth through its centre",
);
/// A cloud particle's single-scattering albedo.
pub const ALBEDOS: Limit = Limit::new(
    "albedos",
    Range::closed(0.0, 1.0, ""),
    "a cloud particle's single-scattering albedo",
);
/// Henyey–Greenstein asymmetry of a cloud's droplets.
pub const ASYMMETRY_G: Limit = Limit::new(
    "asymmetry_g",
    Range::closed(0.0, 0.99, ""),
    "Henyey-Greenstein asymmetry parameter g of a cloud's droplets",
);
/// Sun radiance entering a cloud.
pub const SUN_RADIANCE: Limit = Limit::new(
    "sun_radiance",
    Range::closed(0.0, 1e12, ""),
    "radiance of the sun entering a cloud (any unit; the illumination has the same)",
);
/// Voxels per side of a cloud's attenuation volume.
pub const RESOLUTION: Limit = Limit::new(
    "resolution",
    Range::closed(2.0, 512.0, "").integers(),
    "voxels per side of a cloud's attenuation volume",
);
/// Rain seed.
pub const SEED: Limit = Limit::new(
    "seed",
    Range::closed_open(0.0, 18_446_744_073_709_551_616.0, "").integers(),
    "seed of the rain, an integer below 2^64",
);
/// Received-light threshold below which drops are skipped.
pub const CULL_THRESHOLD: Limit = Limit::new(
    "cull_threshold",
    Range::closed_open(0.0, INF, ""),
    "skip drops whose received light I_R (1.0: the open sky's) is below this",
);
/// A photo's airlight, in its own linear units.
pub const AIRLIGHT: Limit = Limit::new(
    "airlight",
    Range::closed(0.0, 1e6, ""),
    "a photo's airlight, linear RGB in the photo's own units, each channel",
);
/// Height of a photo's camera above its ground plane (the depth fallback).
pub const CAMERA_HEIGHT_M: Limit = Limit::new(
    "camera_height_m",
    Range::open_closed(0.0, 1e4, "m"),
    "height of a photo's camera above the ground plane its depth fallback assumes",
);
/// Distance of a photo's content without a depth map (everything not sky; the farthest its
/// ground plane reaches).
pub const DISTANCE_M: Limit = Limit::new(
    "distance_m",
    Range::open_closed(0.0, 1e5, "m"),
    "distance a photo without a depth map is taken to show wherever it shows no sky",
);
/// Image row of a photo's horizon (the depth fallback).
pub const HORIZON_ROW: Limit = Limit::new(
    "horizon_row",
    Range::closed(-1e9, 1e9, "px"),
    "image row (from the top, pixel centres at k + 0.5) where a photo's level horizon lies",
);
/// Node spacing of an ambient-light map.
pub const SPACING_M: Limit = Limit::new(
    "spacing_m",
    Range::closed(0.05, 100.0, "m"),
    "node spacing of an ambient-light map",
);
/// The renderer's ambient-map spacing (as [`SPACING_M`]).
pub const AMBIENT_SPACING_M: Limit = Limit::new(
    "ambient_spacing_m",
    SPACING_M.range,
    "node spacing of a frame's ambient-light map",
);
/// Azimuths sampled per point.
pub const SAMPLES: Limit = Limit::new(
    "samples",
    Range::closed(4.0, 65_536.0, "").integers(),
    "azimuths sampled per point of a sky-illuminance integral",
);
/// The renderer's azimuths per map node (as [`SAMPLES`]).
pub const AMBIENT_SAMPLES: Limit = Limit::new(
    "ambient_samples",
    SAMPLES.range,
    "azimuths per node of a frame's ambient-light map",
);

// Physics.
/// Drop diameter.
pub const DIAMETER_MM: Limit = Limit::new(
    "diameter_mm",
    Range::closed(0.0, 8.0, "mm"),
    "equivolume drop diameter (drops above ~8 mm break up)",
);
/// Air temperature.
pub const TEMPERATURE_C: Limit = Limit::new(
    "temperature_c",
    Range::closed(-40.0, 50.0, "°C"),
    "air temperature",
);
/// Air pressure.
pub const PRESSURE_HPA: Limit = Limit::new(
    "pressure_hpa",
    Range::closed(50.0, 1100.0, "hPa"),
    "air pressure",
);
/// Relative humidity.
pub const RELATIVE_HUMIDITY: Limit = Limit::new(
    "relative_humidity",
    Range::closed(0.0, 1.0, "(fraction)"),
    "relative humidity as a fraction",
);
/// Lower diameter of a drop-count interval.
pub const D_MIN_MM: Limit = Limit::new(
    "d_min_mm",
    Range::closed(0.0, INF, "mm"),
    "lower diameter of an interval of the drop-size distribution",
);
/// Texture size.
pub const SIZE_PX: Limit = Limit::new(
    "size_px",
    Range::closed(16.0, 16_384.0, "px").integers(),
    "rain texture size, pixels per side (per metre of the cube)",
);

// The windshield (skyfall.windshield).
/// Glass width.
pub const GLASS_WIDTH_MM: Limit = Limit::new(
    "glass_width_mm",
    Range::closed(10.0, 4000.0, "mm"),
    "windshield glass width",
);
/// Glass height along its slope.
pub const GLASS_HEIGHT_MM: Limit = Limit::new(
    "glass_height_mm",
    Range::closed(10.0, 4000.0, "mm"),
    "windshield glass height along its slope",
);
/// Glass inclination from the horizontal.
pub const GLASS_TILT_DEG: Limit = Limit::new(
    "glass_tilt_deg",
    Range::closed(0.0, 90.0, "deg"),
    "windshield inclination from the horizontal (90: upright)",
);
/// The car's speed.
pub const CAR_SPEED_M_S: Limit = Limit::new(
    "car_speed_m_s",
    Range::closed(0.0, 80.0, "m/s"),
    "the car's speed: airflow up the glass, rain swept into it",
);
/// The windshield's grid cell.
pub const CELL_MM: Limit = Limit::new(
    "cell_mm",
    Range::closed(0.5, 10.0, "mm"),
    "side of the windshield's grid cells (the mesh model); the glass is at most 4e6 cells \
     (glass_width_mm / cell_mm × glass_height_mm / cell_mm)",
);
/// Advancing contact angle of water on the glass.
pub const ADVANCING_DEG: Limit = Limit::new(
    "advancing_deg",
    Range::open(0.0, 180.0, "deg"),
    "advancing contact angle of water on the glass",
);
/// Receding contact angle of water on the glass.
pub const RECEDING_DEG: Limit = Limit::new(
    "receding_deg",
    Range::open(0.0, 180.0, "deg"),
    "receding contact angle of water on the glass (below the advancing one)",
);
/// Number of wipers.
pub const WIPERS: Limit = Limit::new(
    "wipers",
    Range::closed(0.0, 2.0, "").integers(),
    "number of wipers (0, 1 or 2)",
);
/// Wiper period.
pub const WIPER_PERIOD_S: Limit = Limit::new(
    "wiper_period_s",
    Range::closed(0.2, 60.0, "s"),
    "the wipers' period, there and back",
);
/// Wiper angles.
pub const WIPER_ANGLES_DEG: Limit = Limit::new(
    "wiper_angles_deg",
    Range::closed(-30.0, 210.0, "deg"),
    "the wipers' sweep, (from, to) from the glass's horizontal towards its top",
);
/// The particle model's particle radius.
pub const PARTICLE_RADIUS_MM: Limit = Limit::new(
    "particle_radius_mm",
    Range::closed(0.2, 5.0, "mm"),
    "base radius of the particle model's equal particles (near the wipers)",
);
/// Every limit, for export and lookup by name.
pub const ALL: &[Limit] = &[
    RAIN_RATE_MM_H,
    RAIN_RATES_MM_H,
    SNOW_RATE_MM_H,
    SNOW_DENSITY_KG_M3,
    DURATION_S,
    DT_S,
    RESOLUTION_M,
    ROUGHNESS,
    TURBULENCE,
    RAIN_DURATION_S,
    DRY_S,
    VISIBILITY_M,
    SKY_ILLUMINANCE_LUX,
    WIND_M_S,
    RAIN_NEAR_M,
    RAIN_FAR_M,
    SNOW_NEAR_M,
    RAIN_DIAMETERS_MM,
    DIAMETERS_MM,
    SKY,
    SUN_ELEVATION_DEG,
    SUN_AZIMUTH_DEG,
    SUN_ILLUMINANCE_LUX,
    ELEVATION_DEG,
    AZIMUTH_DEG,
    CLOUD_BASE_M,
    WIDTH,
    HEIGHT,
    POSITION_M,
    YAW_DEG,
    PITCH_DEG,
    VERTICAL_FOV_DEG,
    FX,
    FY,
    CX,
    CY,
    EXPOSURE_S,
    FOCAL_LENGTH_MM,
    SENSOR_WIDTH_MM,
    F_NUMBER,
    FOCUS_DISTANCE_M,
    VELOCITY_M_S,
    INTENSITY_CD,
    COLOR,
    CONE_DEG,
    TIME_S,
    SEED,
    CULL_THRESHOLD,
    AIRLIGHT,
    CAMERA_HEIGHT_M,
    DISTANCE_M,
    HORIZON_ROW,
    SPACING_M,
    AMBIENT_SPACING_M,
    SAMPLES,
    AMBIENT_SAMPLES,
    DIAMETER_MM,
    TEMPERATURE_C,
    PRESSURE_HPA,
    RELATIVE_HUMIDITY,
    D_MIN_MM,
    SIZE_PX,
    N_PARTICLES,
    EXTENT_M,
    ALTITUDE_M,
    POSITIONS_M,
    RADII_M,
    OPTICAL_DEPTHS,
    ALBEDOS,
    ASYMMETRY_G,
    SUN_RADIANCE,
    RESOLUTION,
    GLASS_WIDTH_MM,
    GLASS_HEIGHT_MM,
    GLASS_TILT_DEG,
    CAR_SPEED_M_S,
    CELL_MM,
    ADVANCING_DEG,
    RECEDING_DEG,
    WIPERS,
    WIPER_PERIOD_S,
    WIPER_ANGLES_DEG,
    PARTICLE_RADIUS_MM,
];

/// The limit of the parameter `name`.
pub fn find(name: &str) -> Option<&'static Limit> {
    ALL.iter().find(|l| l.name == name)
}

/// Checks `value` (element `index` of an array) of the parameter `name`; an unknown name is
/// [`Error::Invalid`].
pub fn check_named(name: &str, index: Option<usize>, value: f64) -> Result<f64> {
    match find(name) {
        Some(l) => l.check_at(index, value),
        None => Err(Error::Invalid {
            param: Param {
                name: "name",
                index: None,
            },
            message: format!("no parameter {name:?} has a declared range"),
        }),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_are_unique_and_ends_are_refused_just_outside() {
        for (i, l) in ALL.iter().enumerate() {
            assert!(ALL[i + 1..].iter().all(|m| m.name != l.name), "{}", l.name);
            let r = l.range;
            assert!(r.lo < r.hi, "{}", l.name);
            let step = |x: f64| 1e-9 * x.abs().max(1.0);
            if r.lo.is_finite() {
                let out = if r.lo_open { r.lo } else { r.lo - step(r.lo) };
                let msg = l.check(out).unwrap_err().to_string();
                assert!(msg.starts_with(&format!("{} = ", l.name)), "{msg}");
                assert!(msg.contains(&r.to_string()), "{msg}");
            }
            if r.hi.is_finite() && r.hi < 1e18 {
                let out = if r.hi_open { r.hi } else { r.hi + step(r.hi) };
                assert!(l.check(out).is_err(), "{} {out}", l.name);
            }
            assert!(l.check(f64::NAN).is_err(), "{}", l.name);
        }
        assert_eq!(
            EXPOSURE_S.check(0.2).unwrap_err().to_string(),
            "exposure_s = 0.2 is outside the valid range [1e-6, 0.1] s"
        );
        assert_eq!(
            check_named("wind_m_s", Some(2), 61.0)
                .unwrap_err()
                .to_string(),
            "wind_m_s[2] = 61.0 is outside the valid range [-60, 60] m/s"
        );
        assert!(check_named("no_such", None, 0.0).is_err());
        assert!(SUN_AZIMUTH_DEG.check(1e300).is_ok() && SUN_AZIMUTH_DEG.check(INF).is_err());
    }
}
