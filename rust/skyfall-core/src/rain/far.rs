//! The rain's far level of detail: the drops beyond `far_m` (horizontally) of the camera drawn
//! as a few pre-rasterised, world-anchored layers instead of one streak each, in the spirit of
//! Yoshida, Dobashi & Yamamoto's rain textures (*A fast method of drawing rain streaks for rainy
//! scenery*).
//!
//! The far part of the rain region, horizontal distances ρ in [far_m, near_m + …) within
//! `near_m` of the eye, is cut into K cylindrical shells about the camera's vertical, ρ in
//! [R_k − Δ/2, R_k + Δ/2] (Δ ≈ [`LAYER_SPACING_M`], 1.5 m). A shell's drops are drawn, once, into a
//! tileable opacity texture in the shell's own coordinates: a = azimuth / δ and b = height on
//! the shell / (R_k·δ), δ the angle of one texel (close to one pixel's, and an integer fraction
//! of the full turn, so the texture wraps seamlessly around the camera). Each drop is the
//! per-drop path's streak ([`crate::particles::streak`]) of a drop at distance R_k straight
//! ahead: width D/(R_k δ), length v·T/(R_k δ) texels, α = (π/4)·w/L. A shell holds n·Δ drops
//! per m² (n the Marshall–Palmer number density of the bins), as the shell's volume,
//! R_k·Δ per m² of it, holds exactly.
//!
//! A pixel looks up each shell's texture where its ray meets the shell: a = azimuth/δ and
//! b = tan(elevation)/δ for every shell (the same texel for all of them, up to each shell's
//! offset); that is exact on a cylinder, whatever the camera's pitch and roll, and vertical
//! streaks stay vertical in the world, converging as the per-drop path's do. Per pixel the
//! texture's α is scaled by sec(elevation) = |r|/h (an oblique ray crosses a shell Δ/cos
//! wide; r the ray with camera z = −1 and h its horizontal length: the per-drop path's drops
//! carry their off-axis (π/4)·w²·sec θ, so their opacity per pixel is n·πD²/4 per metre of ray
//! everywhere in the frame, and the texture's drops are each drawn straight ahead) and by the share of the shell's depth span in front of both the scene and the region's
//! sphere (drops' opacity per pixel is uniform in their distance for streaks under a pixel wide), and
//! composited far to near like a streak fragment, before the near streaks. Wind and the camera's
//! motion slant the streaks: the lookup is sheared by the relative horizontal velocity's
//! component across the ray over the fall speed, which makes a vertical texture streak the
//! slanted path a drop draws; the component along the ray (streaks shortening towards the
//! camera) is left out. Time scrolls each shell down at the middle diameter's fall speed, and
//! the camera's height shifts the shells too: they stay anchored to the world as the camera
//! turns or rises, but are centred on it, so a camera moving horizontally carries its far
//! rain along (no parallax beyond `far_m`).
//!
//! Textures depend only on the rain, the exposure, δ and the shells, not on the seed (a seed
//! draws each shell's offset), and are cached ([`CACHE_ENTRIES`] sets). So that nearby weather
//! shares them (a dataset's or a sweep's every item at a new rain rate), they are drawn at the
//! rain rate and the exposure rounded to a grid ([`quantised_rate`], [`RATE_STEPS_PER_DECADE`];
//! [`quantised_exposure`], [`EXPOSURE_STEPS_PER_OCTAVE`]), and a frame scales their opacity by
//! its own rate's drop cross-section per m³ over the grid rate's ([`opacity_scale`]): a
//! texture's mean opacity is that cross-section times the shell's depth, so the frame's mean
//! opacity is its own rate's (measured within 1 % in `tests`), while its streaks are
//! up to 15 % more or fewer and up to 4.4 % longer or shorter than its own rate and exposure
//! would draw. Light is sampled per
//! [`BLOCK_PX`]-pixel block and shell (the sky's share from the ambient map, the lamps, the
//! cull threshold and the shelter of boxes at the shell's point on the block's centre ray).
//! The measured error against the per-drop reference, and the speed, are in
//! `benches/results/rain.md`.

use super::drops::{BinSpeeds, RainRegion};
use super::streaks::RainShading;
use crate::error::{Error, Param, Result};
use crate::particles::composite::{Accumulator, Blend};
use crate::particles::streak::{LAYER_RAIN, screen_streak_through};
use crate::particles::voxels::voxel_seed;
use crate::physics::dsd::BinSampler;
use crate::physics::fall_speed::FallSpeed;
use crate::scene::boxes::SceneBox;
use crate::scene::camera::Camera;
use glam::{DVec3, IVec4, Mat3, Vec2, Vec3, Vec4};
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64Mcg;
use std::sync::{Arc, Mutex};

/// Side of a shell's texture, texels (a power of two: lookups wrap by a mask).
pub const TEXTURE_SIZE: usize = 1024;
/// The shells' target spacing, m: K = ⌈(near_m − far_m) / this⌉ shells, at most [`MAX_LAYERS`]
/// (1.5 m against 1 m: a third fewer lookups, the same mean opacity and blurred SSIM against
/// the per-drop reference, measured on the 1080p bench frame, 2026-12-02).
pub const LAYER_SPACING_M: f64 = 1.5;
/// The most shells a frame draws.
pub const MAX_LAYERS: usize = 8;
/// Side of the blocks the shells' light is sampled on, px.
pub const BLOCK_PX: usize = 16;
/// Texture sets kept for reuse, at most (each K·[`TEXTURE_SIZE`]² f32: 12 MiB for three
/// shells; the oldest go first): a dataset's rates of 1–50 mm/h at one exposure fall on 14
/// grid rates ([`RATE_STEPS_PER_DECADE`]).
pub const CACHE_ENTRIES: usize = 16;
/// The most memory the cached texture sets may hold together, bytes (the newest is kept
/// whatever its size): 16 sets of three shells.
pub const CACHE_BYTES: usize = 192 << 20;
/// The most drops a frame's shells' textures may hold: more is refused before any is drawn
/// (a small frame's texel is a large angle, so its textures span much of the region; at
/// 1080p, 10 mm/h and 5 m they hold about 10 000).
pub const TEXTURE_DROP_BUDGET: f64 = 4.0e6;
/// The rain rates textures are drawn at: this many per decade, 10^(i / this) mm/h (neighbours
/// 1.33× apart: a frame's rate is within 15 % of its texture's).
pub const RATE_STEPS_PER_DECADE: f64 = 8.0;
/// The exposures textures are drawn at: this many per doubling, 2^(i / this) s (a frame's
/// streaks within 4.4 % of their length).
pub const EXPOSURE_STEPS_PER_OCTAVE: f64 = 8.0;
/// The textures' own seed (a frame's seed draws the shells' offsets).
const TEXTURE_SEED: u64 = 0x00FA_2F1E_1D5E_ED00;
/// tan(elevation) is clamped to this (a ray straight up or down meets no shell).
/// (87°, where the shells' cylinders are all but edge-on)
const MAX_TAN: f32 = 20.0;

/// Which textures: everything they depend on, as bits.
#[derive(Debug, Clone, PartialEq, Eq)]
struct TextureKey(Vec<u64>);

/// The textures of a frame's shells, K·S² opacities (far shell first).
#[derive(Clone, PartialEq)]
struct Textures(Arc<Vec<f32>>);

impl std::fmt::Debug for Textures {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "Textures({} texels)", self.0.len())
    }
}

static CACHE: Mutex<Vec<(TextureKey, Textures)>> = Mutex::new(Vec::new());

/// A frame's far rain, ready to composite.
#[derive(Debug, Clone, PartialEq)]
pub struct FarRain {
    /// The shells' radii R_k, m, far to near.
    radii: Vec<f32>,
    /// Δ, m.
    spacing_m: f32,
    /// The region's radius, m.
    near_m: f32,
    /// Per shell: the texture offsets (a, b), texels, in [0, S) (b plus whole textures enough
    /// to keep every lookup positive).
    offsets: Vec<[f32; 2]>,
    textures: Textures,
    /// The frame's rate's cross-section over its textures' ([`opacity_scale`]).
    opacity_scale: f32,
    /// 1/δ, texels per radian.
    inv_delta: f32,
    /// Camera to world.
    rotation: Mat3,
    /// fx, fy, cx, cy.
    intrinsics: [f32; 4],
    /// The relative horizontal velocity (wind − camera) over the fall speed, (x, z).
    shear: Vec2,
    /// r.
    reflectance: f32,
    /// Blocks per row.
    blocks_x: usize,
    /// Per block and shell (block-major): the shell's light there, None where culled or
    /// sheltered.
    lights: Vec<Option<Vec3>>,
}

/// A frame's far rain as plain arrays (see [`FarRain::arrays`] and [`FarRain::composite`], whose
/// per-pixel lookup they serve).
#[derive(Debug, Clone)]
pub struct FarArrays<'a> {
    /// The shells' radii R_k, m, far to near.
    pub radii: &'a [f32],
    /// Per shell: the texture offsets (a, b), texels.
    pub offsets: &'a [[f32; 2]],
    /// The shells' textures, K·[`TEXTURE_SIZE`]² opacities (far shell first).
    pub textures: &'a [f32],
    /// The textures' identity while they are cached (equal ids: the same texels).
    pub texture_id: usize,
    /// What the textures' opacity is scaled by ([`opacity_scale`]).
    pub opacity_scale: f32,
    /// Per [`BLOCK_PX`] block and shell (block-major): the shell's light (r, g, b, 1), or
    /// zeros where culled or sheltered.
    pub lights: Vec<[f32; 4]>,
    /// 1/δ, texels per radian.
    pub inv_delta: f32,
    /// Δ, m.
    pub spacing_m: f32,
    /// The region's radius, m.
    pub near_m: f32,
    /// The drops' share r of their light.
    pub reflectance: f32,
    /// The relative horizontal velocity over the fall speed, (x, z).
    pub shear: [f32; 2],
    /// Blocks per row.
    pub blocks_x: usize,
}

/// tan(elevation) is clamped to ± this in a far lookup.
pub const FAR_MAX_TAN: f32 = MAX_TAN;

fn invalid(name: &'static str, message: impl Into<String>) -> Error {
    Error::Invalid {
        param: Param { name, index: None },
        message: message.into(),
    }
}

/// The shells for the region `[far_m, near_m]`: (radii far to near, spacing), m.
pub fn shells(far_m: f64, near_m: f64) -> (Vec<f64>, f64) {
    let k = ((near_m - far_m) / LAYER_SPACING_M)
        .ceil()
        .clamp(1.0, MAX_LAYERS as f64) as usize;
    let dr = (near_m - far_m) / k as f64;
    let radii = (0..k)
        .rev()
        .map(|i| far_m + (i as f64 + 0.5) * dr)
        .collect();
    (radii, dr)
}

/// δ for a camera of vertical focal length `fy`: the full turn over an integer number of
/// texture widths, the nearest to one pixel's angle.
pub fn texel_angle(fy: f32) -> f64 {
    let turn = std::f64::consts::TAU;
    let m = (turn * f64::from(fy) / TEXTURE_SIZE as f64)
        .round()
        .max(1.0);
    turn / (m * TEXTURE_SIZE as f64)
}

/// The rain rate a frame's textures are drawn at: `rain_rate_mm_h` rounded to the nearest of
/// [`RATE_STEPS_PER_DECADE`] per decade (in log), mm/h.
pub fn quantised_rate(rain_rate_mm_h: f64) -> f64 {
    on_log_grid(rain_rate_mm_h, 10.0, f64::log10, RATE_STEPS_PER_DECADE)
}

/// The exposure a frame's textures are drawn at: `exposure_s` rounded to the nearest of
/// [`EXPOSURE_STEPS_PER_OCTAVE`] per doubling (in log), s.
pub fn quantised_exposure(exposure_s: f64) -> f64 {
    on_log_grid(exposure_s, 2.0, f64::log2, EXPOSURE_STEPS_PER_OCTAVE)
}

/// `x` > 0 rounded to the nearest of `steps` per factor `base` in log (`log` the logarithm to
/// that base); other values as they are.
fn on_log_grid(x: f64, base: f64, log: fn(f64) -> f64, steps: f64) -> f64 {
    if x > 0.0 {
        base.powf((log(x) * steps).round() / steps)
    } else {
        x
    }
}

/// The drops' cross-section per m³ of air, Σ over `bins` of ∫ N(D)·πD²/4 dD (Marshall–Palmer
/// at `rain_rate_mm_h`), m²/m³: what a shell's mean opacity is proportional to. Half the rain's
/// extinction (Q = 2) times the bins' share of it ([`crate::physics::extinction::bins_share`]).
pub fn cross_section_per_m3(rain_rate_mm_h: f64, bins: &[(f64, f64)]) -> f64 {
    0.5 * crate::physics::extinction::rain_extinction_per_m(rain_rate_mm_h)
        * crate::physics::extinction::bins_share(rain_rate_mm_h, bins)
}

/// What a frame at `rain_rate_mm_h` scales its textures' opacity by: its rate's cross-section
/// per m³ over that of the rate they were drawn at ([`quantised_rate`]); 1 on the grid.
pub fn opacity_scale(rain_rate_mm_h: f64, bins: &[(f64, f64)]) -> f64 {
    let drawn = cross_section_per_m3(quantised_rate(rain_rate_mm_h), bins);
    if drawn > 0.0 {
        cross_section_per_m3(rain_rate_mm_h, bins) / drawn
    } else {
        1.0
    }
}

/// Draws one shell's texture: its drops' streaks at `rain_rate_mm_h` (the region's bins),
/// wrapped, as opacities 1 − ∏(1 − a).
fn shell_texture(
    region: &RainRegion,
    rain_rate_mm_h: f64,
    exposure_s: f64,
    radius_m: f64,
    spacing_m: f64,
    delta: f64,
    stream: u64,
) -> Result<Vec<f32>> {
    let s = TEXTURE_SIZE;
    let f = (1.0 / delta) as f32;
    let half = 0.5 * s as f32;
    let cam = Camera::new(
        s as u32,
        s as u32,
        [f, f, half, half],
        DVec3::ZERO,
        Mat3::IDENTITY,
    )?;
    let mut keep = crate::error::try_filled("a far-rain shell's texture", s * s, 1.0f32)?;
    let speeds = BinSpeeds::new(&region.bins);
    let side_m = s as f64 * delta * radius_m;
    let volume_m3 = side_m * side_m * spacing_m;
    let mut rng = Pcg64Mcg::seed_from_u64(voxel_seed(TEXTURE_SEED, [stream as i64, 0, 0], &[]));
    let r = radius_m as f32;
    for (bin, &(lo, hi)) in region.bins.iter().enumerate() {
        let sampler = BinSampler::new(rain_rate_mm_h, lo, hi);
        for _ in 0..sampler.count_in(volume_m3, &mut rng) {
            let d_mm = sampler.diameter_mm(rng.random());
            let (a, b): (f32, f32) = (
                rng.random::<f32>() * s as f32,
                rng.random::<f32>() * s as f32,
            );
            // Drawn straight ahead (its path's middle on the axis) and moved to (a, b): every
            // texel stands for the same angle at the shell, so the texture carries no
            // obliquity of its own (the lookup scales it per pixel).
            let fall = speeds.m_s(bin, d_mm) as f32;
            let drop = crate::particles::Particle {
                position_m: Vec3::new(0.0, -0.5 * fall * exposure_s as f32, -r),
                velocity_m_s: Vec3::new(0.0, -fall, 0.0),
                diameter_m: (d_mm * 1e-3) as f32,
                id: [0; 5],
            };
            let Some(st) = screen_streak_through(&cam, None, &drop, exposure_s as f32, Vec3::ZERO)
            else {
                continue;
            };
            let st = st.translated(Vec2::new(a - half, b - half));
            let (x0, x1) = (st.min.x.floor() as i64, st.max.x.ceil() as i64);
            let (y0, y1) = (st.min.y.floor() as i64, st.max.y.ceil() as i64);
            for y in y0..y1 {
                let row = y.rem_euclid(s as i64) as usize * s;
                for x in x0..x1 {
                    if let Some((alpha, _)) = st.fragment(Vec2::new(x as f32 + 0.5, y as f32 + 0.5))
                    {
                        keep[row + x.rem_euclid(s as i64) as usize] *= 1.0 - alpha;
                    }
                }
            }
        }
    }
    for k in &mut keep {
        *k = 1.0 - *k;
    }
    Ok(keep)
}

/// The textures of the shells `radii` for a frame at the region's rain rate and `exposure_s`,
/// drawn at [`quantised_rate`] and [`quantised_exposure`] of them (cached; see the module docs).
fn textures(
    region: &RainRegion,
    exposure_s: f64,
    radii: &[f64],
    spacing_m: f64,
    delta: f64,
) -> Result<Textures> {
    let rate = quantised_rate(region.rain_rate_mm_h);
    let exposure_s = quantised_exposure(exposure_s);
    let mut key = vec![
        rate.to_bits(),
        exposure_s.to_bits(),
        spacing_m.to_bits(),
        delta.to_bits(),
    ];
    key.extend(
        region
            .bins
            .iter()
            .flat_map(|b| [b.0.to_bits(), b.1.to_bits()]),
    );
    key.extend(radii.iter().map(|r| r.to_bits()));
    let key = TextureKey(key);
    let drops: f64 = radii
        .iter()
        .map(|&r| {
            let side_m = TEXTURE_SIZE as f64 * delta * r;
            side_m * side_m * spacing_m
        })
        .sum::<f64>()
        * region
            .bins
            .iter()
            .map(|&(lo, hi)| BinSampler::new(rate, lo, hi).expected_per_m3())
            .sum::<f64>();
    if drops > TEXTURE_DROP_BUDGET {
        return Err(invalid(
            "rain_far_m",
            format!(
                "the far layers' textures would hold {drops:.3e} drops (at most \
                 {TEXTURE_DROP_BUDGET:.0e}: a frame this small at {} mm/h out to \
                 rain_near_m = {} m): raise rain_far_m, lower rain_near_m or use rain_far_m = None",
                region.rain_rate_mm_h, region.near_m
            ),
        ));
    }
    if let Ok(cache) = CACHE.lock()
        && let Some((_, t)) = cache.iter().find(|(k, _)| *k == key)
    {
        return Ok(t.clone());
    }
    use rayon::prelude::*;
    let layers: Vec<Vec<f32>> = radii
        .par_iter()
        .enumerate()
        .map(|(k, &r)| shell_texture(region, rate, exposure_s, r, spacing_m, delta, k as u64))
        .collect::<Result<_>>()?;
    let texels = TEXTURE_SIZE * TEXTURE_SIZE * radii.len();
    let mut all: Vec<f32> = Vec::new();
    all.try_reserve_exact(texels)
        .map_err(|_| Error::out_of_memory::<f32>("the far rain's textures", texels))?;
    all.extend(layers.iter().flatten());
    let t = Textures(Arc::new(all));
    if let Ok(mut cache) = CACHE.lock() {
        cache.push((key, t.clone()));
        let bytes =
            |c: &[(TextureKey, Textures)]| -> usize { c.iter().map(|(_, t)| 4 * t.0.len()).sum() };
        while cache.len() > 1 && (cache.len() > CACHE_ENTRIES || bytes(&cache) > CACHE_BYTES) {
            cache.remove(0);
        }
    }
    Ok(t)
}

/// What prepares a frame's far rain.
pub struct FarRequest<'a> {
    /// The rain (its `far_m` set).
    pub region: &'a RainRegion,
    /// The exposure, s.
    pub exposure_s: f32,
    /// The camera's velocity, m/s.
    pub camera_velocity_m_s: Vec3,
    /// Whether the camera has a thin lens (refused: the shells are drawn in focus).
    pub lens: bool,
    /// The boxes that shelter the rain.
    pub shelter: &'a [SceneBox],
    /// How drops are lit.
    pub shading: &'a RainShading,
}

impl FarRain {
    /// The far rain of `req` for `cam`; None when the region has no `far_m`.
    pub fn prepare(cam: &Camera, req: &FarRequest<'_>) -> Result<Option<Self>> {
        let region = req.region;
        let Some(far_m) = region.far_m else {
            return Ok(None);
        };
        if req.lens {
            return Err(invalid(
                "rain_far_m",
                "the far level of detail draws its layers in focus: use a pinhole camera \
                 (f_number = None) or rain_far_m = None",
            ));
        }
        let (radii, dr) = shells(far_m, region.near_m);
        let delta = texel_angle(cam.fy);
        let exposure = f64::from(req.exposure_s);
        let textures = textures(region, exposure, &radii, dr, delta)?;
        let law = *FallSpeed::beard_standard();
        let d_mid = region.middle_diameter_mm();
        let fall = law.m_s(d_mid).max(1e-3);
        let rel = DVec3::new(
            region.wind_m_s.x - f64::from(req.camera_velocity_m_s.x),
            0.0,
            region.wind_m_s.z - f64::from(req.camera_velocity_m_s.z),
        );
        let shear = Vec2::new((rel.x / fall) as f32, (rel.z / fall) as f32);
        let eye = cam.position_m;
        let s = TEXTURE_SIZE as f64;
        let offsets = radii
            .iter()
            .enumerate()
            .map(|(k, &r)| {
                let mut rng =
                    Pcg64Mcg::seed_from_u64(voxel_seed(region.seed, [k as i64, 0, 0], &[0xFA2]));
                let (ou, ov): (f64, f64) = (rng.random(), rng.random());
                let texel_m = r * delta;
                // b grows downwards in the texture (a pixel looks up b = offset − tan/δ): a
                // drop falling, or the eye rising, lowers the offset.
                let b = ov * s - (fall * region.time_s + eye.y) / texel_m;
                // (plus the least whole number of textures that keeps every lookup's b ≥ 0)
                let bias = (f64::from(MAX_TAN) / delta / s).ceil() * s;
                [(ou * s) as f32, (b.rem_euclid(s) + bias) as f32]
            })
            .collect();
        // The light per block and shell.
        let (bw, bh) = (
            (cam.width as usize).div_ceil(BLOCK_PX),
            (cam.height as usize).div_ceil(BLOCK_PX),
        );
        let sh = req.shading;
        let velocity = Vec3::new(
            region.wind_m_s.x as f32,
            -fall as f32,
            region.wind_m_s.z as f32,
        );
        use rayon::prelude::*;
        // Per block, then per shell (block-major), into a list reserved fallibly.
        let k = radii.len();
        let mut lights: Vec<Option<Vec3>> =
            crate::error::try_with_capacity("the far rain's light per block", bw * bh * k)?;
        (0..bw * bh * k)
            .into_par_iter()
            .with_min_len(64 * k)
            .map(|i| {
                let (blk, r) = (i / k, radii[i % k]);
                let (bx, by) = (blk % bw, blk / bw);
                // (the block's middle pixel, or the frame's last)
                let ray = cam.ray_direction(
                    (bx * BLOCK_PX + BLOCK_PX / 2).min(cam.width as usize - 1) as u32,
                    (by * BLOCK_PX + BLOCK_PX / 2).min(cam.height as usize - 1) as u32,
                );
                let h = Vec2::new(ray.x, ray.z).length().max(1e-6);
                {
                    let p = ray * (r as f32 / h);
                    let probe = crate::particles::Particle {
                        position_m: p,
                        velocity_m_s: velocity,
                        diameter_m: 0.0,
                        id: [0; 5],
                    };
                    if super::shelter::sheltered(req.shelter, cam.eye(), &probe) {
                        return None;
                    }
                    let light = sh.drop_light(cam.eye() + p);
                    if sh.cull_threshold.is_some_and(|t| light.max_element() < t) {
                        return None;
                    }
                    Some(light * sh.radiance_scale)
                }
            })
            .collect_into_vec(&mut lights);
        Ok(Some(FarRain {
            radii: radii.iter().map(|&r| r as f32).collect(),
            spacing_m: dr as f32,
            near_m: region.near_m as f32,
            offsets,
            textures,
            opacity_scale: opacity_scale(region.rain_rate_mm_h, &region.bins) as f32,
            inv_delta: (1.0 / delta) as f32,
            rotation: cam.rotation,
            intrinsics: [cam.fx, cam.fy, cam.cx, cam.cy],
            shear,
            reflectance: sh.reflectance,
            blocks_x: bw,
            lights,
        }))
    }

    /// The shells drawn.
    pub fn layers(&self) -> usize {
        self.radii.len()
    }

    /// What an output with its own per-pixel lookup needs (the GPU's far pass), as plain arrays.
    pub fn arrays(&self) -> FarArrays<'_> {
        FarArrays {
            radii: &self.radii,
            offsets: &self.offsets,
            textures: &self.textures.0,
            texture_id: Arc::as_ptr(&self.textures.0) as usize,
            opacity_scale: self.opacity_scale,
            lights: self
                .lights
                .iter()
                .map(|l| l.map_or([0.0; 4], |l| [l.x, l.y, l.z, 1.0]))
                .collect(),
            inv_delta: self.inv_delta,
            spacing_m: self.spacing_m,
            near_m: self.near_m,
            reflectance: self.reflectance,
            shear: [self.shear.x, self.shear.y],
            blocks_x: self.blocks_x,
        }
    }

    /// Whether every light the shells carry is grey (the 8-bit output then keeps one Q plane).
    pub fn grey(&self) -> bool {
        self.lights
            .iter()
            .flatten()
            .all(|l| l.x == l.y && l.y == l.z)
    }

    /// Composites the shells over a band: rows `y0..y0 + rows` of a `w`-wide frame, columns
    /// `cols`, `depth` the band's scene depth (z, m), into `acc` (indexed as the band), far to
    /// near. Call before the band's streaks.
    pub fn composite<B: Blend>(
        &self,
        y0: usize,
        rows: usize,
        w: usize,
        cols: std::ops::Range<usize>,
        depth: &[f32],
        acc: &mut Accumulator<'_, B>,
    ) {
        let k_n = self.radii.len();
        let size = TEXTURE_SIZE;
        let mask = IVec4::splat(size as i32 - 1);
        let tex = &self.textures.0[..];
        let [fx, fy, cx, cy] = self.intrinsics;
        let m = self.rotation;
        let px = rows * w;
        let mut sts: Vec<Option<(B::Light, usize)>> = Vec::with_capacity(k_n);
        let turn = std::f32::consts::TAU * self.inv_delta;
        for row in 0..rows {
            let y = y0 + row;
            let v = -((y as f32 + 0.5 - cy) / fy);
            // The ray's world components, linear in u: c0 + u·c1.
            let base = m * Vec3::new(0.0, v, -1.0);
            let (du, dy_row) = (m.x_axis, v * v + 1.0);
            let by = y / BLOCK_PX;
            // [A, V, h, near/sec] at four pixel centres xs of the row (lanes).
            let terms = |xs: Vec4| -> [Vec4; 4] {
                let u = (xs - Vec4::splat(cx)) / Vec4::splat(fx);
                let rx = Vec4::splat(base.x) + u * du.x;
                let ry = Vec4::splat(base.y) + u * du.y;
                let rz = Vec4::splat(base.z) + u * du.z;
                let h = (rx * rx + rz * rz).max(Vec4::splat(1e-12)).sqrt();
                let inv_h = Vec4::ONE / h;
                let norm = (u * u + Vec4::splat(dy_row)).sqrt();
                let tan = (ry * inv_h).clamp(Vec4::splat(-MAX_TAN), Vec4::splat(MAX_TAN));
                let vv = tan * self.inv_delta;
                // across the ray: (−z, 0, x)/h; the shear per texel of V.
                let s = (Vec4::splat(self.shear.x) * -rz + Vec4::splat(self.shear.y) * rx) * inv_h;
                // (a whole turn added: a whole number of textures, and A stays positive)
                let a = atan2_x4(rx, -rz) * self.inv_delta + s * vv + Vec4::splat(turn);
                [a, vv, h, Vec4::splat(self.near_m) * h / norm]
            };
            let mut xb = cols.start;
            while xb < cols.end {
                let bx = xb / BLOCK_PX;
                let xe = ((bx + 1) * BLOCK_PX).min(cols.end);
                let blk = (by * self.blocks_x + bx) * k_n;
                sts.clear();
                sts.extend(
                    self.lights[blk..blk + k_n]
                        .iter()
                        .map(|l| l.map(|l| acc.streak(l, self.reflectance, LAYER_RAIN))),
                );
                if sts.iter().all(Option::is_none) {
                    xb = xe;
                    continue;
                }
                // The lookups' terms, exact at the segment's first and last pixel centres and
                // linear between (their curvature over a block moves a lookup by well under a
                // texel): A = azimuth/δ + shear·V, V = tan(elevation)/δ, h (the ray's
                // horizontal length, camera z = −1), the sphere's radius as a horizontal
                // distance.
                let ends = Vec4::new(xb as f32 + 0.5, (xe - 1) as f32 + 0.5, 0.0, 0.0);
                let tm = terms(ends);
                let a0: [f32; 4] = std::array::from_fn(|j| tm[j].x);
                let mut a1: [f32; 4] = std::array::from_fn(|j| tm[j].y);
                // (across the azimuth's seam, behind +Z, A jumps by a whole turn: a whole
                // number of textures, the same texels)
                if a1[0] - a0[0] > 0.5 * turn {
                    a1[0] -= turn;
                } else if a0[0] - a1[0] > 0.5 * turn {
                    a1[0] += turn;
                }
                let span = ((xe - xb - 1) as f32).max(1.0);
                let slope: [f32; 4] = std::array::from_fn(|j| (a1[j] - a0[j]) / span);
                let mut x = xb;
                while x < xe {
                    let lanes = (xe - x).min(4);
                    let t = Vec4::new(0.0, 1.0, 2.0, 3.0) + Vec4::splat((x - xb) as f32);
                    let at = |j: usize| Vec4::splat(a0[j]) + t * slope[j];
                    let (az, vv, h, near_h) = (at(0), at(1), at(2), at(3));
                    // sec(elevation) = |ray|/h for the oblique crossing (the per-drop path's
                    // drops carry (π/4)·w²·sec θ, so their opacity per pixel is n·πD²/4 per
                    // metre of ray everywhere in the frame).
                    let u = (t + Vec4::splat(xb as f32 + 0.5 - cx)) / Vec4::splat(fx);
                    let scale =
                        (u * u + Vec4::splat(dy_row)).sqrt() / h * Vec4::splat(self.opacity_scale);
                    let i = row * w + x;
                    let mut d = [f32::INFINITY; 4];
                    d[..lanes].copy_from_slice(&depth[i..i + lanes]);
                    let d = Vec4::from_array(d);
                    // The visible end, as a horizontal distance: the scene or the sphere.
                    let end_h = (d * h).min(near_h);
                    // Shell k's α·coverage at the four pixels (None: hidden there).
                    let lookup = |k: usize| -> Option<Vec4> {
                        let lo = self.radii[k] - 0.5 * self.spacing_m;
                        let wgt = ((end_h - Vec4::splat(lo)) / self.spacing_m)
                            .clamp(Vec4::ZERO, Vec4::ONE);
                        if wgt.cmple(Vec4::ZERO).all() {
                            return None;
                        }
                        let [oa, ob] = self.offsets[k];
                        // (both positive: truncation is the floor)
                        let ia = (az + Vec4::splat(oa)).as_ivec4() & mask;
                        let ib = (Vec4::splat(ob) - vv).as_ivec4() & mask;
                        let idx = ib * size as i32 + ia + IVec4::splat((k * size * size) as i32);
                        let t = Vec4::new(
                            tex[idx.x as usize],
                            tex[idx.y as usize],
                            tex[idx.z as usize],
                            tex[idx.w as usize],
                        );
                        Some((t * scale).min(Vec4::ONE) * wgt)
                    };
                    let mut add = |st: &(B::Light, usize), a: Vec4, inv_z: Vec4| {
                        if lanes == 4 && i + 4 <= px {
                            acc.add_x4(st, i, a, inv_z);
                        } else {
                            for l in 0..lanes {
                                acc.add(st, i + l, a[l], inv_z[l]);
                            }
                        }
                    };
                    for (k, st) in sts.iter().enumerate() {
                        // (a culled or sheltered shell is not looked up)
                        if let Some(st) = st
                            && let Some(a) = lookup(k)
                        {
                            add(st, a, h / self.radii[k]);
                        }
                    }
                    x += lanes;
                }
                xb = xe;
            }
        }
    }
}

/// atan2(y, x) for four values (|error| < 2e-5 rad, tested), in pure f32 arithmetic: the same bits on
/// every CPU.
#[inline(always)]
fn atan2_x4(y: Vec4, x: Vec4) -> Vec4 {
    let (ax, ay) = (x.abs(), y.abs());
    let (mx, mn) = (ax.max(ay), ax.min(ay));
    let a = mn / mx.max(Vec4::splat(f32::MIN_POSITIVE));
    let s = a * a;
    // Minimax odd polynomial of degree 11 on [0, 1].
    let p = ((((Vec4::splat(-0.011_721_2) * s + Vec4::splat(0.052_653_32)) * s
        - Vec4::splat(0.116_432_87))
        * s
        + Vec4::splat(0.193_543_46))
        * s
        - Vec4::splat(0.332_623_47))
        * s
        + Vec4::splat(0.999_977_26);
    let p = p * a;
    let p = Vec4::select(
        ay.cmpgt(ax),
        Vec4::splat(std::f32::consts::FRAC_PI_2) - p,
        p,
    );
    let p = Vec4::select(
        x.cmplt(Vec4::ZERO),
        Vec4::splat(std::f32::consts::PI) - p,
        p,
    );
    Vec4::select(y.cmplt(Vec4::ZERO), -p, p)
}

impl crate::particles::composite::Backdrop for FarRain {
    fn composite_colour(
        &self,
        y0: usize,
        rows: usize,
        w: usize,
        depth: &[f32],
        acc: &mut crate::particles::composite::ColourAccumulator<'_>,
    ) {
        self.composite(y0, rows, w, 0..w, depth, acc);
    }
}

#[cfg(test)]
mod tests;
