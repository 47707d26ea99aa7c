//! The scene stage of the box scene: each pixel's ray cast against the boxes and the ground,
//! its surface lit by the ambient-light map (the sky light it sees) and by the scene's point
//! and spot lights (I·cone·cos θ / r², shadowed by the boxes), sky pixels the sky itself.
//!
//! Lights in relative units: a light adds albedo · E_l / E to the radiance (E_l its
//! illuminance on the face, lux, [`Light::surface_illuminance_lux`]; E the sky's horizontal
//! illuminance), the unit in which 1.0 is a white surface under the open sky. Each light that
//! reaches the face gets a shadow ray through the boxes
//! ([`crate::scene::raycast::occluded_within`]), except the faintest: the lights whose
//! unshadowed shares of the pixel sum to at most [`SHADOW_SKIP_RELATIVE`] of the pixel's
//! unshadowed radiance (sky + every light; found among eight levels, see
//! [`SceneLight::lamp_light`]) are added unshadowed, so the skipped rays change a pixel by at
//! most [`SHADOW_SKIP_RELATIVE`] of its radiance (and only where a skipped light is hidden).

use crate::cloud::frame::{CloudPass, VolumeView};
use crate::scene::SurfaceLight;
use crate::scene::boxes::{BoxScene, surface_albedo, trace};
use crate::scene::camera::Camera;
use crate::scene::lights::Light;
use crate::scene::raycast::occluded_within;
use crate::sky::Sky;
use crate::sky::ambient::AmbientMap;
use crate::stage::layers::{Layer, LayerSet};
use crate::stage::{Row, Stage};
use glam::Vec3;

/// Bound on the relative change of a pixel's radiance by the shadow rays skipped (see the
/// module docs): 1 %.
pub const SHADOW_SKIP_RELATIVE: f32 = 0.01;

/// Surfaces are lifted off their face by this before a shadow ray, m.
pub const SHADOW_OFFSET_M: f32 = 1e-3;

/// How a frame's scene is lit: the sky seen by sky pixels and the map surfaces read, and the
/// scene's lights.
#[derive(Debug, Clone, Copy)]
pub struct SceneLight<'a> {
    /// The sky.
    pub sky: &'a Sky,
    /// Illuminance relative to E on the five normals.
    pub ambient: &'a AmbientMap,
    /// Point and spot lights that light the surfaces (none: the sky alone).
    pub lights: &'a [Light],
    /// The sky's horizontal illuminance E, lux: the unit a light's illuminance is divided by.
    pub sky_illuminance_lux: f32,
    /// The snow cover on the surfaces, when the frame has one.
    pub snow: Option<&'a crate::snow::cover::SnowRender>,
    /// The sun's direct light on a box scene's surfaces, when the sky has a sun.
    pub sun: Option<SunLight<'a>>,
    /// The clouds in the sky, when the weather has them.
    pub clouds: Option<CloudPass<'a>>,
}

/// The sun's direct light on the surfaces: a face of normal n at p receives
/// (E_sun/E)·max(n·s, 0)·V·Γ relative to E, V = 0 where a box hides the sun, Γ the clouds'
/// share of sunlight at p.
#[derive(Debug, Clone, Copy)]
pub struct SunLight<'a> {
    /// Towards the sun, unit.
    pub direction: Vec3,
    /// The sun's normal illuminance over E.
    pub relative: f32,
    /// The colour of its light (linear RGB of luminance 1: [`crate::sky::Sky::sun_colour`]).
    pub colour: Vec3,
    /// The clouds' Γ for the sun, seen from the camera, when there are clouds.
    pub clouds: Option<VolumeView<'a>>,
    /// The camera, for the clouds' camera-relative volume.
    pub eye: Vec3,
}

impl SunLight<'_> {
    /// The share of the sun's direct light reaching a face of normal `n` at `p`: 0 facing away
    /// or behind a box, else the clouds' Γ there.
    #[inline]
    pub fn share(&self, boxes: &[crate::scene::boxes::SceneBox], p: Vec3, n: Vec3) -> f32 {
        if n.dot(self.direction) <= 0.0 {
            return 0.0;
        }
        let lifted = p + n * SHADOW_OFFSET_M;
        if occluded_within(boxes, lifted, self.direction, SUN_RAY_M) {
            return 0.0;
        }
        // The clouds' Γ there (1 without clouds).
        self.clouds.as_ref().map_or(1.0, |v| v.sample(p - self.eye))
    }

    /// The sun's illuminance relative to E on a face of normal `n` receiving `share` of it.
    #[inline]
    pub fn illuminance(&self, n: Vec3, share: f32) -> f32 {
        self.relative * n.dot(self.direction).max(0.0) * share
    }
}

/// How far a sun shadow ray looks for boxes, m (beyond every scene's boxes).
pub const SUN_RAY_M: f32 = 1e5;

impl<'a> SceneLight<'a> {
    /// The sky and its map, no lights.
    pub fn new(sky: &'a Sky, ambient: &'a AmbientMap) -> Self {
        SceneLight {
            sky,
            ambient,
            lights: &[],
            sky_illuminance_lux: 1.0,
            snow: None,
            sun: None,
            clouds: None,
        }
    }

    /// The same with `lights`, under a sky of horizontal illuminance `sky_illuminance_lux`.
    pub fn with_lights(self, lights: &'a [Light], sky_illuminance_lux: f32) -> Self {
        SceneLight {
            lights,
            sky_illuminance_lux,
            ..self
        }
    }

    /// Radiance (relative) of a Lambertian face of albedo `a` and normal `n` at `p`: the sky
    /// light of the map on its normal, the sun and the lights, with the shadows of `boxes`
    /// (how [`shade_pixel`] lights the boxes and the snow cover lights its surfaces).
    #[inline]
    pub fn surface_radiance(
        &self,
        boxes: &[crate::scene::boxes::SceneBox],
        p: Vec3,
        n: Vec3,
        a: Vec3,
    ) -> Vec3 {
        self.surface_radiance_sun(boxes, p, n, a).0
    }

    /// The same with the sun `sun` and the clouds `clouds`.
    pub fn with_sky_light(self, sun: Option<SunLight<'a>>, clouds: Option<CloudPass<'a>>) -> Self {
        SceneLight {
            sun,
            clouds,
            ..self
        }
    }

    /// The same with the snow cover `snow` on its surfaces.
    pub fn with_snow(self, snow: Option<&'a crate::snow::cover::SnowRender>) -> Self {
        SceneLight { snow, ..self }
    }

    /// Illuminance relative to E on the face of normal `n` at `p` from the lights, with the
    /// shadows of `boxes` (see the module docs); `a` the face's albedo and `ambient` its
    /// radiance from the sky, which the skip rule weighs the lights against.
    #[inline]
    pub fn lamp_light(
        &self,
        boxes: &[crate::scene::boxes::SceneBox],
        p: Vec3,
        n: Vec3,
        a: Vec3,
        ambient: Vec3,
    ) -> Vec3 {
        let inv_e = 1.0 / self.sky_illuminance_lux;
        let share = |l: &Light| {
            let (e, dir, r) = l.surface_illuminance_lux(p, n);
            (e, dir, r, (a * e).max_element() * inv_e)
        };
        // Each light's illuminance, direction, distance and share once, kept for up to KEPT
        // lights (the rest computed again: the same values).
        let mut kept = [(Vec3::ZERO, Vec3::ZERO, 0.0f32, 0.0f32); KEPT];
        let lit = |i: usize, l: &Light, kept: &[(Vec3, Vec3, f32, f32); KEPT]| {
            if i < KEPT { kept[i] } else { share(l) }
        };
        // The unshadowed total S first, then the skip level τ: the largest of
        // ε·S, ε·S/2, …, ε·S/2⁷ with (lights at or below it) · τ ≤ ε·S, so the lights skipped
        // add at most ε·S together.
        let mut total = ambient.max_element();
        for (i, l) in self.lights.iter().enumerate() {
            let s = share(l);
            if i < KEPT {
                kept[i] = s;
            }
            total += s.3;
        }
        let budget = SHADOW_SKIP_RELATIVE * total;
        let mut below = [0u32; SKIP_LEVELS];
        for (i, l) in self.lights.iter().enumerate() {
            let c = lit(i, l, &kept).3;
            if c > 0.0 {
                for (j, k) in below.iter_mut().enumerate() {
                    if c <= skip_level(budget, j) {
                        *k += 1;
                    }
                }
            }
        }
        let mut skip = 0.0;
        for (j, &k) in below.iter().enumerate() {
            let tau = skip_level(budget, j);
            if k as f32 * tau <= budget {
                skip = tau;
                break;
            }
        }
        let lifted = p + n * SHADOW_OFFSET_M;
        let mut sum = Vec3::ZERO;
        for (i, l) in self.lights.iter().enumerate() {
            let (e, dir, r, c) = lit(i, l, &kept);
            if c <= 0.0 {
                continue;
            }
            if c <= skip || !occluded_within(boxes, lifted, dir, r - SHADOW_OFFSET_M) {
                sum += e;
            }
        }
        sum * inv_e
    }
}

/// Lights whose illuminance and share [`SceneLight::lamp_light`] keeps between its passes
/// (the rest it computes again).
const KEPT: usize = 32;

/// Levels of the skip rule: ε·S/2ʲ for j < this.
pub const SKIP_LEVELS: usize = 8;

/// ε·S/2ʲ.
#[inline]
fn skip_level(budget: f32, j: usize) -> f32 {
    budget / (1u32 << j) as f32
}

/// Radiance (relative) and depth (m along the optical axis, inf for sky) of one pixel.
#[inline]
pub fn shade_pixel(
    scene: &BoxScene,
    cam: &Camera,
    light: &SceneLight<'_>,
    x: u32,
    y: u32,
) -> (Vec3, f32) {
    let (c, d, _) = shade_pixel_sun(scene, cam, light, x, y);
    (c, d)
}

/// [`shade_pixel`] with the share of the sun's direct light the pixel's surface receives
/// (1 for sky pixels and without a sun).
#[inline]
pub fn shade_pixel_sun(
    scene: &BoxScene,
    cam: &Camera,
    light: &SceneLight<'_>,
    x: u32,
    y: u32,
) -> (Vec3, f32, f32) {
    let dir = cam.ray_direction(x, y);
    match trace(scene, cam.eye(), dir) {
        Some((t, n, albedo)) => {
            let p = cam.eye() + dir * t;
            let a = surface_albedo(albedo, n, p);
            let (c, share) = light.surface_radiance_sun(&scene.boxes, p, n, a);
            (c, t, share)
        }
        None => (light.sky.sky_pixel_rgb(dir.normalize()), f32::INFINITY, 1.0),
    }
}

/// The one definition of a surface's light (the boxes', through [`SceneLight::surface_radiance`],
/// and the snow cover's): the sky light of the map on the face's normal, the sun with the share
/// of it the face receives (1 without a sun: `sun_transmittance`), and the lights.
impl crate::scene::SurfaceLight for SceneLight<'_> {
    #[inline]
    fn surface_radiance_sun(
        &self,
        boxes: &[crate::scene::boxes::SceneBox],
        p: Vec3,
        n: Vec3,
        a: Vec3,
    ) -> (Vec3, f32) {
        let e = AmbientMap::channel(n).map_or(0.0, |c| self.ambient.sample(p)[c]);
        let mut sky_lit = a * (self.sky.light_colour * e);
        let mut share = 1.0;
        if let Some(sun) = &self.sun {
            share = sun.share(boxes, p, n);
            sky_lit += a * (sun.colour * sun.illuminance(n, share));
        }
        if self.lights.is_empty() {
            return (sky_lit, share);
        }
        (
            sky_lit + a * self.lamp_light(boxes, p, n, a, sky_lit),
            share,
        )
    }

    #[inline]
    fn sky_pixel(&self, dir: Vec3) -> Vec3 {
        self.sky.sky_pixel_rgb(dir)
    }

    #[inline]
    fn sun_glint(&self) -> Option<(Vec3, Vec3)> {
        self.sun
            .as_ref()
            .map(|s| (s.direction, s.colour * s.relative))
    }
}

/// The scene as the first stage of a frame: each row's box scene ray cast (with its snow cover,
/// into `snow_depth_m`, and the sun's share, into `sun_transmittance`) or the photo's row
/// copied (whitened by its snow cover).
pub struct SceneStage<'a> {
    /// The photo or the box scene.
    pub scene: super::SceneRef<'a>,
    /// The frame's camera.
    pub cam: &'a Camera,
    /// How the scene is lit.
    pub light: &'a SceneLight<'a>,
}

impl Stage for SceneStage<'_> {
    fn layers(&self) -> LayerSet {
        LayerSet::EMPTY
            .with_if(Layer::SnowDepth, self.light.snow.is_some())
            .with_if(Layer::SunTransmittance, self.light.sun.is_some())
    }

    fn row(&self, row: &mut Row<'_>) {
        let (scene, cam, light, y) = (self.scene, self.cam, self.light, row.y as usize);
        let [cover, sun] = row
            .layers
            .0
            .get_disjoint_mut([Layer::SnowDepth.index(), Layer::SunTransmittance.index()])
            .unwrap_or_else(|_| unreachable!("two distinct layers"));
        let sun_row = sun.as_deref_mut();
        match (light.snow, cover.as_deref_mut()) {
            (Some(snow), Some(s_row)) => {
                let rows = (&mut *row.rgb, &mut *row.depth_m, s_row, sun_row);
                snow_scene_row(scene, cam, light, snow, y, rows);
            }
            _ => scene_row(scene, cam, light, y, row.rgb, row.depth_m, sun_row),
        }
    }
}

/// The scene stage of one row: the box scene ray cast (with each pixel's share of the sun into
/// `sun_row` when given), or the photo's row copied.
fn scene_row(
    scene: super::SceneRef<'_>,
    cam: &Camera,
    light: &SceneLight<'_>,
    y: usize,
    rgb_row: &mut [f32],
    depth_row: &mut [f32],
    mut sun_row: Option<&mut [f32]>,
) {
    let w = depth_row.len();
    match scene {
        super::SceneRef::Boxes(b) => {
            for x in 0..w {
                let (c, d, s) = shade_pixel_sun(b, cam, light, x as u32, y as u32);
                rgb_row[3 * x..3 * x + 3].copy_from_slice(&c.to_array());
                depth_row[x] = d;
                if let Some(r) = sun_row.as_deref_mut() {
                    r[x] = s;
                }
            }
        }
        super::SceneRef::Photo { rgb, depth_m } => {
            rgb_row.copy_from_slice(&rgb[3 * w * y..3 * w * (y + 1)]);
            depth_row.copy_from_slice(&depth_m[w * y..w * (y + 1)]);
        }
    }
}

/// A row's buffers: rgb, depth, the snow's depth, and the sun's share when the frame has it.
type SnowRows<'r> = (
    &'r mut [f32],
    &'r mut [f32],
    &'r mut [f32],
    Option<&'r mut [f32]>,
);

/// [`scene_row`] with a snow cover on the surfaces, its depth into `snow_row` (and the share of
/// the sun on the visible surface, the cover's or the one beneath, into `sun_row`).
fn snow_scene_row(
    scene: super::SceneRef<'_>,
    cam: &Camera,
    light: &SceneLight<'_>,
    snow: &crate::snow::cover::SnowRender,
    y: usize,
    (rgb_row, depth_row, snow_row, mut sun_row): SnowRows<'_>,
) {
    match scene {
        super::SceneRef::Boxes(b) => {
            for x in 0..depth_row.len() {
                let (c, d, s, sun) = snow.shade_pixel(b, cam, light, x as u32, y as u32);
                rgb_row[3 * x..3 * x + 3].copy_from_slice(&c.to_array());
                depth_row[x] = d;
                snow_row[x] = s;
                if let Some(r) = sun_row.as_deref_mut() {
                    r[x] = sun;
                }
            }
        }
        super::SceneRef::Photo { .. } => {
            scene_row(scene, cam, light, y, rgb_row, depth_row, None);
            snow.photo_row(cam, light.ambient, y, rgb_row, depth_row, Some(snow_row));
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::boxes::{SceneBox, WINDOW_ALBEDO_FACTOR};
    use crate::scene::lights::Light;
    use crate::sky::cie::SkyKind;
    use crate::sky::illuminance::{SkyTable, irradiance};
    use glam::Mat3;

    /// The overcast sky and its open-sky light (no occluders).
    fn open() -> (Sky, AmbientMap) {
        let sky = Sky::new(SkyKind::Overcast, 0.0, 1000.0).unwrap();
        let e = irradiance(&[], &SkyTable::new(&sky, 256).unwrap(), Vec3::ZERO);
        (sky, AmbientMap::uniform(e))
    }

    fn cam() -> Camera {
        Camera::new(
            64,
            48,
            [40.0, 40.0, 32.0, 24.0],
            Vec3::new(0.0, 1.5, 0.0),
            Mat3::IDENTITY,
        )
        .unwrap_or(Camera {
            width: 1,
            height: 1,
            fx: 1.0,
            fy: 1.0,
            cx: 0.0,
            cy: 0.0,
            position_m: glam::DVec3::ZERO,
            rotation: Mat3::IDENTITY,
        })
    }

    #[test]
    fn overcast_sky_integrates_to_its_illuminance() {
        // ∫ L cos θ dω over the hemisphere = E, i.e. ∫ (L/(E/π)) cos θ dω = π.
        let (sky, _) = open();
        let n = 2000;
        let mut sum = 0.0f64;
        for i in 0..n {
            let el = (i as f64 + 0.5) / n as f64 * std::f64::consts::FRAC_PI_2;
            let l = sky.emitted(Vec3::new(0.0, el.sin() as f32, el.cos() as f32));
            sum += l
                * el.sin()
                * el.cos()
                * (std::f64::consts::FRAC_PI_2 / n as f64)
                * 2.0
                * std::f64::consts::PI;
        }
        assert!((sum / std::f64::consts::PI - 1.0).abs() < 1e-4, "{sum}");
    }

    #[test]
    fn ground_depth_is_analytic() {
        let scene = BoxScene::new(vec![], true, Vec3::splat(0.2)).unwrap_or(BoxScene {
            boxes: vec![],
            ground: true,
            ground_albedo: Vec3::ONE,
        });
        let c = cam();
        let (sky, amb) = open();
        let light = SceneLight::new(&sky, &amb);
        // bottom row centre: ray dir y = -(47.5 - 24)/40, so t = 1.5 / ((47.5 - 24) / 40)
        let (rad, t) = shade_pixel(&scene, &c, &light, 32, 47);
        assert!((t - 1.5 * 40.0 / 23.5).abs() < 1e-4, "{t}");
        assert!((rad - Vec3::splat(0.2)).length() < 1e-5);
        let (_, t_sky) = shade_pixel(&scene, &c, &light, 32, 0);
        assert!(t_sky.is_infinite());
    }

    #[test]
    fn a_wall_ahead_is_hit_at_its_distance_with_windows() {
        let wall = SceneBox {
            min_m: Vec3::new(-5.0, 0.0, -10.0),
            max_m: Vec3::new(5.0, 3.0, -9.0),
            albedo: Vec3::splat(0.5),
        };
        let scene = BoxScene::new(vec![wall], false, Vec3::ZERO).unwrap_or(BoxScene {
            boxes: vec![],
            ground: false,
            ground_albedo: Vec3::ZERO,
        });
        let c = cam();
        let (sky, amb) = open();
        let light = SceneLight::new(&sky, &amb);
        let wall_e = amb.sample(Vec3::ZERO)[3];
        assert!(
            (f64::from(wall_e) - (3.0 / 14.0 + 4.0 / (7.0 * std::f64::consts::PI))).abs() < 2e-3
        );
        // Row 23 looks 0.5/40 up: the front face z = -9 at depth 9, p.y = 1.61, p.x = 0.1125 (a wall facing +Z, lit by the open sky's vertical illuminance).
        let (rad, t) = shade_pixel(&scene, &c, &light, 32, 23);
        assert!((t - 9.0).abs() < 1e-4, "{t}");
        assert!((rad - Vec3::splat(0.5 * wall_e)).length() < 1e-6, "{rad}");
        // Column 38: p.x = 1.4625, inside a pane.
        let (pane, _) = shade_pixel(&scene, &c, &light, 38, 23);
        assert!(
            (pane - Vec3::splat(0.5 * WINDOW_ALBEDO_FACTOR * wall_e)).length() < 1e-6,
            "{pane}"
        );
        assert!(
            BoxScene::new(
                vec![SceneBox {
                    min_m: Vec3::ONE,
                    max_m: Vec3::ZERO,
                    albedo: Vec3::ZERO
                }],
                true,
                Vec3::ZERO
            )
            .is_err()
        );
    }

    fn lamp(pos: Vec3, cd: f32) -> Light {
        Light {
            position_m: pos,
            intensity_cd: cd,
            color: Vec3::new(1.0, 0.8, 0.5),
            spot: None,
        }
    }

    #[test]
    fn a_lamp_over_open_ground_gives_the_analytic_illuminance() {
        // Ground of albedo 0.2 under a 2000 cd lamp 5 m up, 30 lx of sky: at each ground pixel
        // the radiance is 0.2 · (1 + I·h/r³ / E) per channel (cos θ = h/r).
        let scene = BoxScene::new(vec![], true, Vec3::splat(0.2)).unwrap();
        let c = cam();
        let (sky, amb) = open();
        let l = lamp(Vec3::new(1.0, 5.0, -12.0), 2000.0);
        let lights = [l];
        let light = SceneLight::new(&sky, &amb).with_lights(&lights, 30.0);
        let mut worst = 0.0f32;
        for (x, y) in [(32, 47), (32, 30), (10, 40), (60, 28), (50, 26), (0, 47)] {
            let (rad, t) = shade_pixel(&scene, &c, &light, x, y);
            let p = c.eye() + c.ray_direction(x, y) * t;
            let r = (l.position_m - p).length();
            let e = l.intensity_cd * l.position_m.y / (r * r * r);
            let want = Vec3::splat(0.2) * (Vec3::ONE + l.color * (e / 30.0));
            worst = worst.max(((rad - want) / want).abs().max_element());
        }
        assert!(worst < 1e-5, "{worst}");
        // A spot aimed down the street: full intensity inside its inner cone, none outside.
        let spot = Light {
            position_m: Vec3::new(0.0, 0.7, -30.0),
            intensity_cd: 15000.0,
            color: Vec3::ONE,
            spot: Some((Vec3::new(0.0, -0.05, 1.0).normalize(), 0.9, 0.95)),
        };
        let spots = [spot];
        let light = SceneLight::new(&sky, &amb).with_lights(&spots, 30.0);
        let (rad, t) = shade_pixel(&scene, &c, &light, 32, 30); // ahead, inside the beam
        let p = c.eye() + c.ray_direction(32, 30) * t;
        let d = spot.position_m - p;
        let (axis, _, cos_inner) = spot.spot.unwrap();
        assert!(axis.dot(-d.normalize()) > cos_inner);
        let e = 15000.0 * d.y / d.length().powi(3);
        assert!(
            (rad.x / (0.2 * (1.0 + e / 30.0)) - 1.0).abs() < 1e-5,
            "{rad}"
        );
        // Turned to +X, the same spot leaves that point (90° off its axis) unlit.
        let away = [Light {
            spot: Some((Vec3::X, 0.9, 0.95)),
            ..spot
        }];
        let light = SceneLight::new(&sky, &amb).with_lights(&away, 30.0);
        let (rad, _) = shade_pixel(&scene, &c, &light, 32, 30);
        assert!((rad - Vec3::splat(0.2)).length() < 1e-6, "{rad}");
    }

    #[test]
    fn a_box_shadows_what_is_behind_it_from_the_lamp() {
        // A slab hung 2 m up under a lamp shadows the ground beneath it: there only the sky's
        // light; further on the lamp's, analytic.
        let slab = SceneBox {
            min_m: Vec3::new(-1.5, 2.0, -11.5),
            max_m: Vec3::new(1.5, 2.5, -8.5),
            albedo: Vec3::splat(0.5),
        };
        let scene = BoxScene::new(vec![slab], true, Vec3::splat(0.2)).unwrap();
        let c = cam();
        let (sky, amb) = open();
        let l = lamp(Vec3::new(0.0, 5.0, -10.0), 2000.0);
        let lights = [l];
        let light = SceneLight::new(&sky, &amb).with_lights(&lights, 30.0);
        let (shadowed, t) = shade_pixel(&scene, &c, &light, 32, 29);
        assert!((t - 1.5 / 0.1375).abs() < 1e-3, "{t}");
        assert!((shadowed - Vec3::splat(0.2)).length() < 1e-6, "{shadowed}");
        let (lit, t) = shade_pixel(&scene, &c, &light, 32, 26);
        let p = c.eye() + c.ray_direction(32, 26) * t;
        let r = (l.position_m - p).length();
        let want = Vec3::splat(0.2) * (Vec3::ONE + l.color * (2000.0 * 5.0 / (r * r * r) / 30.0));
        assert!(
            ((lit - want) / want).abs().max_element() < 1e-5,
            "{lit} {want}"
        );
        // Without the slab the shadowed point is lit: the shadow is the box's.
        let open_scene = BoxScene::new(vec![], true, Vec3::splat(0.2)).unwrap();
        let (bare, _) = shade_pixel(&open_scene, &c, &light, 32, 29);
        assert!(bare.x > 1.5 * 0.2, "{bare}");
        // The slab's own top faces the lamp (lit), its underside does not (sky only: none).
        assert!(
            light
                .lamp_light(
                    &scene.boxes,
                    Vec3::new(0.0, 2.5, -10.0),
                    Vec3::Y,
                    Vec3::ONE,
                    Vec3::ZERO
                )
                .x
                > 0.0
        );
        assert_eq!(
            light.lamp_light(
                &scene.boxes,
                Vec3::new(0.0, 2.0, -10.0),
                -Vec3::Y,
                Vec3::ONE,
                Vec3::ZERO
            ),
            Vec3::ZERO
        );
    }

    #[test]
    fn shadow_rays_skipped_change_a_pixel_by_at_most_the_bound() {
        // Many faint far lamps behind a wall and one near lamp: the skipped rays' error is
        // within SHADOW_SKIP_RELATIVE of the pixel's radiance, against every ray cast.
        let wall = SceneBox {
            min_m: Vec3::new(-50.0, 0.0, -31.0),
            max_m: Vec3::new(50.0, 20.0, -30.0),
            albedo: Vec3::splat(0.5),
        };
        let boxes = [wall];
        let (sky, amb) = open();
        let mut lights = vec![lamp(Vec3::new(0.0, 5.0, -5.0), 2000.0)];
        for k in 0..10 {
            lights.push(lamp(
                Vec3::new(k as f32 * 3.0 - 15.0, 5.0, -60.0 - k as f32),
                300.0,
            ));
        }
        let light = SceneLight::new(&sky, &amb).with_lights(&lights, 30.0);
        let p = Vec3::new(0.0, 0.0, -4.0);
        let a = Vec3::splat(0.2);
        let fast = light.lamp_light(&boxes, p, Vec3::Y, a, a);
        // every shadow ray: the far lamps are all behind the wall
        let exact = lights[0].surface_illuminance_lux(p, Vec3::Y).0 / 30.0;
        let total = a + a * fast;
        assert!(((fast - exact) * a).max_element() <= SHADOW_SKIP_RELATIVE * total.max_element());
        assert!(
            fast.x > exact.x,
            "the far lamps were skipped, so added unshadowed"
        );
    }
}
