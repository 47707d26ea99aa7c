//! The wet stage: after the scene stage, each visible surface's film ([`super::film`]) darkens
//! it (Lekner & Dorf, [`super::optics::Wetting`]) and adds the film's reflection: Fresnel's
//! share of what the mirrored ray sees (on a box scene the ray cast through the boxes, lit as
//! the scene stage lights surfaces, or the sky; on a photo a screen-space march through its
//! depth map, the photo's own sky where the ray leaves the frame) and the highlights of the
//! lamps and the sun on the rippled film (a GGX lobe, [`super::optics::brdf`]). The film's
//! mirror ray leaves about a microfacet normal of its GGX grain, a puddle's about the face's
//! own normal ([`super::puddles`]). It draws the `wetness` layer (0 on the sky, dry and
//! snow-covered surfaces) and the `puddle_mask` layer (1 on a puddle, else 0).
//!
//! A wet surface's light is its dry light times (1 − w) + w·darkening(a) per channel, plus
//! w·(reflection): w the wetness as the share of the surface under the film. The dry light
//! of a Lambertian face is its albedo a times the light it receives, so the factor applies to
//! all of it; a photo's albedo is read from its pixel (linear, at most 1).

use super::film::{Film, RainDirections, WET_FILM_MM};
use super::optics::{FILM_ROUGHNESS, PUDDLE_ROUGHNESS, WATER_INDEX, Wetting, brdf, fresnel};
use super::puddles::{in_puddle, reflected};
use crate::scene::SurfaceLight;
use crate::scene::boxes::{BoxScene, SceneBox, surface_albedo, trace};
use crate::scene::camera::Camera;
use crate::scene::lights::Light;
use crate::scene::raycast::occluded_within;
use crate::stage::layers::{Layer, LayerSet};
use crate::stage::{Row, Stage};
use glam::Vec3;

/// The layers the wet stage draws.
pub const LAYERS: LayerSet = LayerSet::of(&[Layer::Wetness, Layer::PuddleMask]);

/// Surfaces are lifted off their face by this before a reflected or shelter ray, m.
pub const OFFSET_M: f32 = 1e-3;

/// How far up its path a box keeps the rain off a surface, m (any box above it).
pub const SHELTER_RAY_M: f32 = 1e5;

/// A photo's wet stage on the GPU (`shaders/wet_photo.wgsl`): the photo the march reads, its
/// mean sky, the boxes that shelter it and the lights whose highlights it shows.
#[derive(Debug, Clone, Copy)]
pub struct WetPhotoGpu<'a> {
    /// The photo, linear RGB H·W·3 (what the march mirrors).
    pub rgb: &'a [f32],
    /// Its sky pixels' mean (for rays that leave the frame elsewhere).
    pub sky: Vec3,
    /// The boxes that keep the rain off (empty: none).
    pub shelter: &'a [SceneBox],
    /// The lights.
    pub lamps: &'a [Light],
    /// 1/E, 1/lux.
    pub inv_sky_lux: f32,
}

/// What the GPU's scene pass needs to draw a box scene's wet stage (`scene_raycast.wgsl`,
/// `WET`): the film as numbers.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WetGpu {
    /// The quartile drops' directions of fall (unit, downwards).
    pub directions: [Vec3; 3],
    /// Water per unit exposure while it rained, mm (R·t/3600); None: the storage, filled.
    pub mm_per_exposure: Option<f32>,
    /// Water evaporated since the rain stopped, mm.
    pub dried_mm: f32,
    /// Lekner & Dorf's (1 − R̄)(1 − p): the darkening is this over (1 − p·a).
    pub darkening_numerator: f32,
    /// p, the film's internal reflection of diffuse light.
    pub internal_reflectance: f32,
    /// Whether the boxes keep the rain off what they cover.
    pub sheltered: bool,
    /// The row's denoising window of the film's grain, px each side ([`grain_radius_px`]).
    pub grain_radius_px: usize,
}

/// Steps of a photo's screen-space march.
pub const MARCH_STEPS: usize = 64;

/// What the wet stage's surfaces are.
#[derive(Clone, Copy)]
pub enum Surfaces<'a> {
    /// A box scene, ray cast again per pixel.
    Boxes(&'a BoxScene),
    /// A photo: linear RGB H·W·3 and depth along the optical axis H·W (inf: sky).
    Photo {
        /// Linear RGB, H·W·3.
        rgb: &'a [f32],
        /// Depth along the optical axis, m (inf: sky), H·W.
        depth_m: &'a [f32],
    },
}

/// The wet stage of a frame.
pub struct WetStage<'a> {
    surfaces: Surfaces<'a>,
    cam: &'a Camera,
    film: Film,
    rain: RainDirections,
    shelter: &'a [SceneBox],
    light: &'a (dyn SurfaceLight + Sync),
    lamps: &'a [Light],
    inv_sky_lux: f32,
    sun: Option<(Vec3, Vec3)>,
    wetting: Wetting,
    /// A photo's sky colour for reflected rays that leave the frame (its sky pixels' mean).
    photo_sky: Vec3,
    /// The row's denoising window of the film's grain, px each side ([`grain_radius_px`]).
    grain_radius: usize,
}

/// The window over which a row's film grain is averaged, px each side, for a camera of focal
/// length `fx_px`: an eighth of the film's GGX lobe's width α on the screen (α·fx/8), 1–16 px.
pub fn grain_radius_px(fx_px: f32) -> usize {
    (FILM_ROUGHNESS * fx_px / 8.0).round().clamp(1.0, 16.0) as usize
}

/// What the wet stage reads from its frame.
pub struct WetFrame<'a> {
    /// The surfaces.
    pub surfaces: Surfaces<'a>,
    /// The camera.
    pub cam: &'a Camera,
    /// The rain the surfaces received.
    pub film: Film,
    /// The wind, m/s (it slants the rain).
    pub wind_m_s: [f64; 3],
    /// Boxes that keep the rain off what they cover (empty: none).
    pub shelter: &'a [SceneBox],
    /// How the frame lights a surface (for what a reflected ray hits).
    pub light: &'a (dyn SurfaceLight + Sync),
    /// The point and spot lights, whose highlights the film shows.
    pub lamps: &'a [Light],
    /// The sky's horizontal illuminance E, lux (the lamps' unit).
    pub sky_illuminance_lux: f32,
    /// Towards the sun, and its normal illuminance over E in colour (linear RGB), when the sky
    /// has a sun.
    pub sun: Option<(Vec3, Vec3)>,
}

impl<'a> WetStage<'a> {
    /// The stage for `frame`, or None when no surface is wet.
    pub fn new(frame: WetFrame<'a>) -> Option<Self> {
        if !frame.film.any() {
            return None;
        }
        let photo_sky = match frame.surfaces {
            Surfaces::Photo { rgb, depth_m } => photo_sky(rgb, depth_m, frame.cam.width as usize),
            Surfaces::Boxes(_) => Vec3::ZERO,
        };
        Some(WetStage {
            surfaces: frame.surfaces,
            cam: frame.cam,
            film: frame.film,
            rain: RainDirections::new(frame.film.rate_mm_h, frame.wind_m_s),
            shelter: frame.shelter,
            light: frame.light,
            lamps: frame.lamps,
            inv_sky_lux: 1.0 / frame.sky_illuminance_lux.max(1e-12),
            sun: frame.sun,
            wetting: Wetting::new(WATER_INDEX),
            photo_sky,
            grain_radius: grain_radius_px(frame.cam.fx),
        })
    }

    /// The stage's film as the GPU draws it (a box scene's in its scene pass, a photo's in
    /// its wet pass, with [`Self::photo_gpu`]).
    pub fn gpu(&self) -> WetGpu {
        let f = self.film;
        let w = self.wetting;
        WetGpu {
            directions: self.rain.0,
            mm_per_exposure: f.duration_s.map(|t| (f.rate_mm_h * t / 3600.0) as f32),
            dried_mm: (super::film::DRYING_MM_H * f.dry_s / 3600.0) as f32,
            darkening_numerator: ((1.0 - w.diffuse_reflectance) * (1.0 - w.internal_reflectance))
                as f32,
            internal_reflectance: w.internal_reflectance as f32,
            sheltered: !self.shelter.is_empty(),
            grain_radius_px: self.grain_radius,
        }
    }

    /// The boxes that keep the rain off the surfaces (empty: none).
    pub fn shelter(&self) -> &'a [SceneBox] {
        self.shelter
    }

    /// What the GPU's wet pass of a photo needs besides [`Self::gpu`] (None for a box scene).
    pub fn photo_gpu(&self) -> Option<WetPhotoGpu<'_>> {
        match self.surfaces {
            Surfaces::Photo { rgb, .. } => Some(WetPhotoGpu {
                rgb,
                sky: self.photo_sky,
                shelter: self.shelter,
                lamps: self.lamps,
                inv_sky_lux: self.inv_sky_lux,
            }),
            Surfaces::Boxes(_) => None,
        }
    }

    /// The water on a face of normal `n` at `p`, mm.
    pub fn water_mm(&self, p: Vec3, n: Vec3) -> f64 {
        let lifted = p + n * OFFSET_M;
        let exposure = self.rain.exposure(n, |up| {
            occluded_within(self.shelter, lifted, up, SHELTER_RAY_M)
        });
        self.film.water_mm(exposure)
    }

    /// The film at `p` on a face of normal `n`, seen along unit `d`: its wetness (0: dry),
    /// whether it is a puddle, and the direction it mirrors.
    fn film_at(&self, p: Vec3, n: Vec3, d: Vec3) -> (f32, bool, Vec3) {
        let water = self.water_mm(p, n);
        let w = (water / WET_FILM_MM).min(1.0) as f32;
        let still = in_puddle(p, n, water);
        (w, still, reflected(d, n, p, still, FILM_ROUGHNESS))
    }

    /// The wet pixel of a surface: `dry` (its dry radiance, albedo `a`) darkened by the film
    /// of wetness `w`, plus w times the film's reflection: the `highlights`, and `mirrored`
    /// (Fresnel's share of what the reflected ray sees), which a puddle (`still`) adds here
    /// and the film's grain leaves to the row's denoising ([`WetPixel::grain`]).
    fn wet(
        &self,
        dry: Vec3,
        a: Vec3,
        w: f32,
        still: bool,
        mirrored: Vec3,
        highlights: Vec3,
    ) -> WetPixel {
        let k = a.to_array().map(|c| {
            let d = self.wetting.darkening(f64::from(c)) as f32;
            1.0 - w + w * d
        });
        let darkened = dry * Vec3::from(k) + w * highlights;
        if still {
            WetPixel {
                rgb: darkened + w * mirrored,
                wetness: w,
                puddle: true,
                grain: None,
            }
        } else {
            WetPixel {
                rgb: darkened,
                wetness: w,
                puddle: false,
                grain: Some(w * mirrored),
            }
        }
    }

    /// The highlights of the lamps (shadowed by `boxes`) and the sun (`sun_share` of it
    /// reaching the face) on water of roughness `alpha` and normal `n` at `p` seen along unit
    /// `v` (towards the camera), relative to E.
    fn highlights(
        &self,
        boxes: &[SceneBox],
        p: Vec3,
        n: Vec3,
        v: Vec3,
        sun_share: f32,
        alpha: f32,
    ) -> Vec3 {
        let index = WATER_INDEX as f32;
        let lifted = p + n * OFFSET_M;
        let mut sum = Vec3::ZERO;
        for l in self.lamps {
            let (e, dir, r) = l.surface_illuminance_lux(p, n);
            if e.max_element() <= 0.0 {
                continue;
            }
            let f = brdf(n, v, dir, alpha, index);
            if f > 0.0 && !occluded_within(boxes, lifted, dir, r - OFFSET_M) {
                sum += e * (f * self.inv_sky_lux);
            }
        }
        if let Some((s, rel)) = self.sun
            && sun_share > 0.0
        {
            let cos = n.dot(s).max(0.0);
            sum += rel * (brdf(n, v, s, alpha, index) * cos * sun_share);
        }
        sum
    }

    /// One pixel of a box scene (None: not a surface).
    fn box_pixel(&self, scene: &BoxScene, x: u32, y: u32, dry: Vec3, sun: f32) -> Option<WetPixel> {
        let eye = self.cam.eye();
        let dir = self.cam.ray_direction(x, y);
        let (t, n, albedo) = trace(scene, eye, dir)?;
        let p = eye + dir * t;
        let d = dir.normalize();
        let (w, still, r) = self.film_at(p, n, d);
        if w <= 0.0 {
            return Some(WetPixel::dry(dry));
        }
        let a = surface_albedo(albedo, n, p);
        let v = -d;
        let lifted = p + n * OFFSET_M;
        let seen = match trace(scene, lifted, r) {
            Some((t2, n2, a2)) => {
                let q = lifted + r * t2;
                let a2 = surface_albedo(a2, n2, q);
                self.light.surface_radiance_sun(&scene.boxes, q, n2, a2).0
            }
            None => self.light.sky_pixel(r),
        };
        let f = fresnel(f64::from(n.dot(v)), WATER_INDEX) as f32;
        let highlights = self.highlights(&scene.boxes, p, n, v, sun, roughness(still));
        Some(self.wet(dry, a, w, still, seen * f, highlights))
    }

    /// One pixel of a photo.
    fn photo_pixel(&self, rgb: &[f32], depth_m: &[f32], x: usize, y: usize, dry: Vec3) -> WetPixel {
        let w_px = self.cam.width as usize;
        let Some((p, n)) = photo_surface(self.cam, depth_m, x, y) else {
            return WetPixel::dry(dry);
        };
        let d = (p - self.cam.eye()).normalize();
        let (w, still, r) = self.film_at(p, n, d);
        if w <= 0.0 {
            return WetPixel::dry(dry);
        }
        let a = dry.min(Vec3::ONE);
        let v = -d;
        let seen = self.march(rgb, depth_m, w_px, p, n, r);
        let f = fresnel(f64::from(n.dot(v)), WATER_INDEX) as f32;
        let highlights = self.highlights(&[], p, n, v, 1.0, roughness(still));
        self.wet(dry, a, w, still, seen * f, highlights)
    }

    /// What a photo's surface at `p` (normal `n`) mirrors along unit `r`: the photo's pixel
    /// where the march meets its depth (a surface above the plane of `p`: at grazing angles
    /// the march runs just above its own plane, which a pixel's single depth would otherwise
    /// take for a hit), else the sky the direction shows (a sky pixel in view, or the photo's
    /// mean sky).
    fn march(&self, rgb: &[f32], depth_m: &[f32], w: usize, p: Vec3, n: Vec3, r: Vec3) -> Vec3 {
        let cam = self.cam;
        let dist = (p - cam.eye()).length();
        let mut s = 0.01 * dist.max(0.1);
        let mut travelled = 0.0;
        for _ in 0..MARCH_STEPS {
            travelled += s;
            s *= 1.12;
            let Some((px, py, z)) = project(cam, p + r * travelled) else {
                break;
            };
            let d = depth_m[py * w + px];
            if d.is_finite() && z > d && z - d < (0.1 * d).max(0.3) {
                let hit = cam.eye() + cam.ray_direction(px as u32, py as u32) * d;
                let off = hit - p;
                if off.dot(n) > 0.02 * off.length() + 0.01 {
                    return Vec3::from_slice(&rgb[3 * (py * w + px)..]);
                }
            }
        }
        // The sky along r: where its direction falls in the frame on the sky, that pixel.
        if let Some((px, py, _)) = project(cam, cam.eye() + r * 1e4)
            && depth_m[py * w + px].is_infinite()
        {
            return Vec3::from_slice(&rgb[3 * (py * w + px)..]);
        }
        self.photo_sky
    }
}

/// The roughness of the water's highlights: a puddle's ([`PUDDLE_ROUGHNESS`]) or the film's.
fn roughness(still: bool) -> f32 {
    if still {
        PUDDLE_ROUGHNESS
    } else {
        FILM_ROUGHNESS
    }
}

/// One pixel as the wet stage draws it.
#[derive(Debug, Clone, Copy)]
struct WetPixel {
    /// Its light, but for the film's grain.
    rgb: Vec3,
    /// Its wetness.
    wetness: f32,
    /// Whether it is a puddle.
    puddle: bool,
    /// The film's grained mirror image, w·F·(what the grained ray sees), added after the
    /// row's denoising ([`denoise_grain`]); None: none (dry, a puddle).
    grain: Option<Vec3>,
}

impl WetPixel {
    /// A dry surface's pixel.
    fn dry(rgb: Vec3) -> Self {
        WetPixel {
            rgb,
            wetness: 0.0,
            puddle: false,
            grain: None,
        }
    }
}

/// Adds the film's grained mirror images of a row to its `rgb`: each pixel's the mean over the
/// pixels within `radius` of it along the row that have one and whose depth is within 5 % of
/// its own (the same surface). Each pixel's own is one draw from the film's GGX lobe
/// ([`super::puddles::reflected`]); the mean of a window of them estimates the lobe's
/// blurred image, as a rough wet road shows, where one draw alone would be noise.
pub fn denoise_grain(grain: &[Option<Vec3>], depth_m: &[f32], radius: usize, rgb: &mut [f32]) {
    for (x, own) in grain.iter().enumerate() {
        if own.is_none() {
            continue;
        }
        let d = depth_m[x];
        let (mut sum, mut n) = (Vec3::ZERO, 0u32);
        for j in x.saturating_sub(radius)..(x + radius + 1).min(grain.len()) {
            if let Some(g) = grain[j]
                && (depth_m[j] - d).abs() <= 0.05 * d
            {
                sum += g;
                n += 1;
            }
        }
        let c = Vec3::from_slice(&rgb[3 * x..]) + sum / n.max(1) as f32;
        rgb[3 * x..3 * x + 3].copy_from_slice(&c.to_array());
    }
}

/// The pixel (x, y) a world point projects to and its depth along the optical axis, or None
/// behind the camera or outside the frame.
fn project(cam: &Camera, q: Vec3) -> Option<(usize, usize, f32)> {
    let c = cam.rotation.transpose() * (q - cam.eye());
    let z = -c.z;
    if z <= 1e-6 {
        return None;
    }
    let x = cam.cx + cam.fx * c.x / z;
    let y = cam.cy - cam.fy * c.y / z;
    if x < 0.0 || y < 0.0 || x >= cam.width as f32 || y >= cam.height as f32 {
        return None;
    }
    Some((x as usize, y as usize, z))
}

/// A photo's point at pixel (x, y) and its normal (towards the camera) from the depth map, or
/// None on the sky or without a neighbour along an axis.
///
/// Along each axis the tangent is a difference to a neighbour: the central one where both
/// neighbours lie on one plane with the pixel (1/depth is linear across a plane in a
/// perspective image: its two one-sided differences agree within 10 %), else the one-sided
/// difference to the neighbour nearer in 1/depth (at a depth edge, the pixel's own surface).
pub fn photo_surface(cam: &Camera, depth_m: &[f32], x: usize, y: usize) -> Option<(Vec3, Vec3)> {
    let (w, h) = (cam.width as usize, cam.height as usize);
    let d = depth_m[y * w + x];
    if !d.is_finite() {
        return None;
    }
    let point = |x: usize, y: usize| {
        let d = depth_m[y * w + x];
        d.is_finite().then(|| {
            (
                cam.eye() + cam.ray_direction(x as u32, y as u32) * d,
                1.0 / d,
            )
        })
    };
    let p = cam.eye() + cam.ray_direction(x as u32, y as u32) * d;
    let inv = 1.0 / d;
    // One axis: its neighbours before and after (None off the frame or on the sky).
    let tangent = |before: Option<(Vec3, f32)>, after: Option<(Vec3, f32)>| match (before, after) {
        (Some((pb, ib)), Some((pa, ia))) => {
            let (fb, fa) = (inv - ib, ia - inv);
            if (fa - fb).abs() <= 0.1 * fa.abs().max(fb.abs()) + 1e-9 {
                Some(pa - pb)
            } else if fa.abs() < fb.abs() {
                Some(pa - p)
            } else {
                Some(p - pb)
            }
        }
        (Some((pb, _)), None) => Some(p - pb),
        (None, Some((pa, _))) => Some(pa - p),
        (None, None) => None,
    };
    let tx = tangent(
        (x > 0).then(|| point(x - 1, y)).flatten(),
        (x + 1 < w).then(|| point(x + 1, y)).flatten(),
    )?;
    // Rows run down the image: "before" is the row above.
    let ty = tangent(
        (y > 0).then(|| point(x, y - 1)).flatten(),
        (y + 1 < h).then(|| point(x, y + 1)).flatten(),
    )?;
    let n = tx.cross(ty).normalize_or_zero();
    if n == Vec3::ZERO {
        return None;
    }
    let towards = cam.eye() - p;
    Some((p, if n.dot(towards) < 0.0 { -n } else { n }))
}

/// The mean of a photo's sky pixels (its top row's mean when it has none).
fn photo_sky(rgb: &[f32], depth_m: &[f32], w: usize) -> Vec3 {
    let (mut sum, mut n) = (Vec3::ZERO, 0u32);
    for (i, d) in depth_m.iter().enumerate() {
        if d.is_infinite() {
            sum += Vec3::from_slice(&rgb[3 * i..]);
            n += 1;
        }
    }
    if n == 0 {
        for i in 0..w.min(depth_m.len()) {
            sum += Vec3::from_slice(&rgb[3 * i..]);
            n += 1;
        }
    }
    sum / n.max(1) as f32
}

impl Stage for WetStage<'_> {
    fn layers(&self) -> LayerSet {
        LAYERS
    }

    fn row(&self, row: &mut Row<'_>) {
        let y = row.y;
        let [wet, puddle, snow, sun] = row
            .layers
            .0
            .get_disjoint_mut([
                Layer::Wetness.index(),
                Layer::PuddleMask.index(),
                Layer::SnowDepth.index(),
                Layer::SunTransmittance.index(),
            ])
            .unwrap_or_else(|_| unreachable!("four distinct layers"));
        let width = row.depth_m.len();
        let mut grain: Vec<Option<Vec3>> = vec![None; width];
        for x in 0..width {
            let (mut w, mut still) = (0.0, false);
            let snowed = snow.as_deref().is_some_and(|s| s[x] > 0.0);
            if row.depth_m[x].is_finite() && !snowed {
                let dry = Vec3::from_slice(&row.rgb[3 * x..]);
                let lit = match self.surfaces {
                    Surfaces::Boxes(scene) => {
                        let share = sun.as_deref().map_or(1.0, |s| s[x]);
                        self.box_pixel(scene, x as u32, y, dry, share)
                    }
                    Surfaces::Photo { rgb, depth_m } => {
                        Some(self.photo_pixel(rgb, depth_m, x, y as usize, dry))
                    }
                };
                if let Some(px) = lit {
                    row.rgb[3 * x..3 * x + 3].copy_from_slice(&px.rgb.to_array());
                    (w, still, grain[x]) = (px.wetness, px.puddle, px.grain);
                }
            }
            if let Some(l) = wet.as_deref_mut() {
                l[x] = w;
            }
            if let Some(l) = puddle.as_deref_mut() {
                l[x] = f32::from(u8::from(still));
            }
        }
        denoise_grain(&grain, row.depth_m, self.grain_radius, row.rgb);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Mat3;

    #[test]
    fn a_depth_maps_ground_has_an_upward_normal_up_to_a_depth_edge() {
        // A level camera 1.5 m up over a ground plane, with a wall 4 m away in the middle
        // columns: ground pixels beside the wall (a depth edge on one side) still get +Y from
        // their one-sided difference, the wall's pixels +Z, the sky none.
        let (w, h) = (40u32, 30u32);
        let cam = Camera::new(
            w,
            h,
            [30.0, 30.0, 20.0, 15.0],
            Vec3::new(0.0, 1.5, 0.0),
            Mat3::IDENTITY,
        )
        .unwrap();
        let mut depth = vec![f32::INFINITY; (w * h) as usize];
        for y in 0..h {
            for x in 0..w {
                let d = cam.ray_direction(x, y);
                let ground = if d.y < 0.0 { -1.5 / d.y } else { f32::INFINITY };
                let wall = (14..26).contains(&x) && y >= 10;
                depth[(y * w + x) as usize] = if wall { ground.min(4.0) } else { ground };
            }
        }
        for (x, y, want) in [
            (5, 29, Vec3::Y),
            (13, 27, Vec3::Y),
            (26, 25, Vec3::Y),
            (20, 12, Vec3::Z),
            (14, 11, Vec3::Z),
        ] {
            let (_, n) = photo_surface(&cam, &depth, x, y).unwrap();
            assert!((n - want).length() < 1e-3, "({x}, {y}): {n}");
        }
        assert!(photo_surface(&cam, &depth, 5, 3).is_none());
    }
}
