//! The clouds in the sky's light: what a cloud field hides of the sky above a point, and the
//! light it sends down instead, for the ambient-light map (and, through the map's light at the
//! eye, the haze's airlight).
//!
//! [`CloudDome::build`] draws the clouds with the frames' own cloud pass ([`CloudSplats`]) on
//! the upward faces of a cube around a point: the zenith's face and the upper halves of the
//! four sides', 90° each. Per pixel it keeps the clouds' transmittance T and the light S they
//! send towards the point, in the frames' relative units (a white surface under the open sky
//! is 1). [`CloudDome::sample`] reads them bilinearly along any direction above the horizon.
//!
//! A sky with these clouds in it sends, along ω ([`clouded`]),
//!
//!   L'(ω) = τ(ω) (L_c(ω) T(ω) + S(ω)) + A (1 − τ(ω)),
//!
//! the cloud base's light where the clouds let it through plus the clouds' own, both through
//! the haze below (τ and A as in [`Sky`]); with no cloud along ω (T = 1, S = 0) it is
//! [`Sky::received`]. [`clouded_light`] tabulates it for the ambient-light map (the same tables
//! a clear sky's map reads, along every azimuth) and integrates its colour on a horizontal
//! surface, which tints the map's light.
//!
//! One point stands for the whole map: clouds lie hundreds of metres up and more, so a street's
//! width moves them across its sky by a few degrees; that parallax is left out.

use glam::{DVec3, Mat3, Vec3};
use rayon::prelude::*;
use std::sync::atomic::AtomicBool;

use super::frame::{CloudField, CloudLight, CloudPass, CloudSplats};
use crate::error::{Range, Result, try_filled};
use crate::scene::camera::Camera;
use crate::sky::Sky;
use crate::sky::colour::LUMA;
use crate::sky::illuminance::SkyTable;
use crate::sky::light_colour_of;

/// Pixels along a face's side (the zenith's face; the sides' are half as tall): about 2.8° a
/// pixel. The light the `broken` and `stratocumulus` presets' skies give the open ground's
/// five normals is within 0.5 % of 128 px faces' (measured; the map integrates the dome, so
/// its resolution matters little).
pub const FACE_PX: u32 = 32;

/// Valid face sides, px.
pub const FACE_PX_RANGE: Range = Range::closed(4.0, 1024.0, "px");

/// The faces' view directions: the zenith, then the four horizontal ones.
const VIEWS: [Vec3; 5] = [Vec3::Y, Vec3::X, Vec3::NEG_X, Vec3::Z, Vec3::NEG_Z];

/// One face: its camera and, per pixel, the clouds' transmittance and light.
#[derive(Debug, Clone)]
struct Face {
    cam: Camera,
    transmittance: Vec<f32>,
    light: Vec<Vec3>,
}

/// The clouds over a point, seen along every direction above its horizon.
#[derive(Debug, Clone)]
pub struct CloudDome {
    /// The point, m.
    pub eye_m: DVec3,
    faces: Vec<Face>,
}

/// The camera of a face looking along `view` from `eye_m`: 90° across, `n` px wide; a side
/// face keeps only its upper half (`n` × `n`/2, the principal point on its bottom edge).
fn face_camera(view: Vec3, eye_m: DVec3, n: u32) -> Result<Camera> {
    let back = -view;
    let up = if view == Vec3::Y { Vec3::Z } else { Vec3::Y };
    let right = up.cross(back);
    let half = n as f32 / 2.0;
    let height = if view == Vec3::Y { n } else { n / 2 };
    Camera::new(
        n,
        height,
        [half, half, half, half],
        eye_m,
        Mat3::from_cols(right, up, back),
    )
}

impl CloudDome {
    /// The clouds of `field` lit by `light`, seen from `eye_m` on faces `face_px` wide
    /// ([`FACE_PX`] by default; in [`FACE_PX_RANGE`]).
    pub fn build(
        field: &CloudField,
        light: CloudLight,
        eye_m: DVec3,
        face_px: u32,
    ) -> Result<Self> {
        FACE_PX_RANGE.check("face_px", None, f64::from(face_px))?;
        let pass = CloudPass { field, light };
        let mut faces = Vec::with_capacity(VIEWS.len());
        for view in VIEWS {
            let cam = face_camera(view, eye_m, face_px)?;
            let splats = CloudSplats::prepare(&pass, &cam)?;
            let (w, h) = (cam.width as usize, cam.height as usize);
            let mut transmittance = try_filled("the clouds' dome", w * h, 1.0f32)?;
            let mut light = try_filled("the clouds' dome", w * h, Vec3::ZERO)?;
            transmittance
                .par_chunks_mut(w)
                .zip(light.par_chunks_mut(w))
                .enumerate()
                .for_each(|(y, (t_row, s_row))| {
                    let mut rgb = vec![0.0f32; 3 * w];
                    let depth = vec![f32::INFINITY; w];
                    splats.apply_row(&cam, y as u32, &mut rgb, &depth, Some(t_row));
                    for (t, (s, px)) in t_row.iter_mut().zip(s_row.iter_mut().zip(rgb.chunks(3))) {
                        *t = 1.0 - *t;
                        *s = Vec3::from_slice(px);
                    }
                });
            faces.push(Face {
                cam,
                transmittance,
                light,
            });
        }
        Ok(CloudDome { eye_m, faces })
    }

    /// Whether no cloud shows anywhere above the horizon (T = 1 and S = 0 on every face): the
    /// sky is then its own, and a map need not be made any differently.
    pub fn is_clear(&self) -> bool {
        self.faces.iter().all(|f| {
            f.transmittance.iter().all(|&t| t == 1.0) && f.light.iter().all(|&s| s == Vec3::ZERO)
        })
    }

    /// The clouds' transmittance T and light S (relative units, linear RGB) along unit `dir`,
    /// bilinear between the face's pixel centres; (1, 0) at and below the horizon.
    pub fn sample(&self, dir: Vec3) -> (f32, Vec3) {
        if dir.y <= 0.0 {
            return (1.0, Vec3::ZERO);
        }
        let (ax, az) = (dir.x.abs(), dir.z.abs());
        let k = if dir.y >= ax.max(az) {
            0
        } else if ax >= az {
            if dir.x > 0.0 { 1 } else { 2 }
        } else if dir.z > 0.0 {
            3
        } else {
            4
        };
        let face = &self.faces[k];
        let cam = &face.cam;
        let c = cam.rotation.transpose() * dir;
        let x = cam.cx + cam.fx * c.x / -c.z - 0.5;
        let y = cam.cy - cam.fy * c.y / -c.z - 0.5;
        let (w, h) = (cam.width as usize, cam.height as usize);
        let at = |v: f32, n: usize| {
            let v = v.clamp(0.0, (n - 1) as f32);
            let i = (v as usize).min(n.saturating_sub(2));
            (i, (v - i as f32).min(1.0), (i + 1).min(n - 1))
        };
        let (i0, fx, i1) = at(x, w);
        let (j0, fy, j1) = at(y, h);
        let mix = |get: &dyn Fn(usize) -> Vec3| {
            let top = get(j0 * w + i0).lerp(get(j0 * w + i1), fx);
            let bottom = get(j1 * w + i0).lerp(get(j1 * w + i1), fx);
            top.lerp(bottom, fy)
        };
        let t = mix(&|i| Vec3::splat(face.transmittance[i])).x;
        (t, mix(&|i| face.light[i]))
    }
}

/// The luminance a sky with clouds in it sends along unit `dir` (above the horizon), relative
/// to E/π: [`Sky::received`] with the cloud base's light L_c·τ taken through the clouds'
/// transmittance `t` and their light `s` added through the haze (see the module).
#[inline]
pub fn clouded(sky: &Sky, dir: Vec3, t: f32, s: Vec3) -> f64 {
    let tau = sky.transmittance(f64::from(dir.y));
    sky.received(dir) + tau * (f64::from(LUMA.dot(s)) - sky.emitted(dir) * f64::from(1.0 - t))
}

/// [`clouded`] in colour: linear RGB whose luminance it is.
#[inline]
pub fn clouded_rgb(sky: &Sky, dir: Vec3, t: f32, s: Vec3) -> Vec3 {
    let tau = sky.transmittance(f64::from(dir.y)) as f32;
    sky.received_rgb(dir) + (s - sky.sky_pixel_rgb(dir) * (1.0 - t)) * tau
}

/// The ambient-light map's sky table of `sky` with `dome`'s clouds in it (on `azimuths`
/// sectors, along every one), and the colour of its light on a horizontal surface
/// ([`light_colour_of`], as [`Sky::light_colour`] is made). A caller whose dome [`CloudDome::is_clear`] keeps the sky's
/// own table instead, so that clouds nowhere in the sky change no bit of a frame.
pub fn clouded_light(
    sky: &Sky,
    dome: &CloudDome,
    azimuths: usize,
    cancel: &AtomicBool,
) -> Result<(SkyTable, Vec3)> {
    let radiance = |dir: Vec3| {
        let (t, s) = dome.sample(dir);
        clouded(sky, dir, t, s)
    };
    let table = SkyTable::from_radiance(radiance, azimuths, cancel)?;
    let colour = light_colour_of(|dir| {
        let (t, s) = dome.sample(dir);
        clouded_rgb(sky, dir, t, s)
    });
    Ok((table, colour))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cloud::Cloud;
    use crate::sky::cie::SkyKind;
    use crate::sky::illuminance::irradiance;
    use std::f32::consts::FRAC_1_SQRT_2;
    use std::f64::consts::{FRAC_PI_4, PI};

    /// A clear sky with nothing in it (T = 1, S = 0) is the sky's own table, bit for bit.
    #[test]
    fn a_sky_without_clouds_is_its_own_table() {
        let sun = Some(crate::sky::sun_direction(35.0, 120.0));
        let cancel = AtomicBool::new(false);
        for sigma in [0.0, 1.5e-3] {
            let sky = Sky::new(SkyKind::general(12, sun).unwrap(), sigma, 900.0).unwrap();
            let own = SkyTable::per_azimuth(&sky, 32, &cancel).unwrap();
            let clear = SkyTable::from_radiance(|d| clouded(&sky, d, 1.0, Vec3::ZERO), 32, &cancel)
                .unwrap();
            assert_eq!(own, clear);
            let d = Vec3::new(0.3, 0.5, -0.8).normalize();
            assert_eq!(clouded_rgb(&sky, d, 1.0, Vec3::ZERO), sky.received_rgb(d));
        }
    }

    /// A uniform sky (CIE type 5, L = E/π) whose part above 45° is an opaque cloud of
    /// luminance s: the ground receives the view factors' shares, sin²45° = ½ of the sky and ½
    /// of the cloud; a wall (π/4 ± ½)/π of each: E·(0.409 + 0.091 s/L) (the integral of
    /// cos²γ over each band). The cap's edge lies on a step of the tables, so they are exact in
    /// elevation; a wall's cos φ has kinks the azimuths' midpoint rule meets at O(1/n²): 1e-5
    /// at 256 azimuths.
    #[test]
    fn a_cap_of_cloud_lights_the_ground_and_walls_by_their_view_factors() {
        let sky = Sky::new(SkyKind::general(5, None).unwrap(), 0.0, 1500.0).unwrap();
        let l = sky.received(Vec3::Y);
        let cancel = AtomicBool::new(false);
        for s in [0.0f32, 0.4, 2.5] {
            let cap = |d: Vec3| {
                if d.y > FRAC_1_SQRT_2 {
                    (0.0, Vec3::splat(s))
                } else {
                    (1.0, Vec3::ZERO)
                }
            };
            let table = SkyTable::from_radiance(
                |d| {
                    let (t, c) = cap(d);
                    clouded(&sky, d, t, c)
                },
                256,
                &cancel,
            )
            .unwrap();
            let e = irradiance(&[], &table, Vec3::ZERO);
            let s = f64::from(s);
            let up = 0.5 * l + 0.5 * s;
            let below = (FRAC_PI_4 + 0.5) / PI;
            let above = (FRAC_PI_4 - 0.5) / PI;
            let wall = below * l + above * s;
            assert!(
                (f64::from(e[0]) - up).abs() < 1e-6,
                "s {s}: up {} vs {up}",
                e[0]
            );
            for (c, v) in e.iter().enumerate().skip(1) {
                assert!(
                    (f64::from(*v) - wall).abs() < 3e-5,
                    "s {s}: side {c} {v} vs {wall}"
                );
            }
        }
    }

    /// The dome read along a frame camera's pixels (looking up and sideways, across faces)
    /// gives what the cloud pass draws in that camera's frame, within the resampling's error.
    #[test]
    fn the_dome_sees_what_a_cameras_frame_of_the_clouds_shows() {
        // A few broad particles 1.2-2 km away, lit by a sun 40° up.
        let mut positions = Vec::new();
        let mut radii = Vec::new();
        for (k, &(x, y, z)) in [
            (300.0, 1400.0, -600.0),
            (-200.0, 1200.0, -900.0),
            (600.0, 900.0, -700.0),
            (100.0, 1600.0, -200.0),
            (900.0, 1000.0, -1100.0),
        ]
        .iter()
        .enumerate()
        {
            positions.push([x, y, z]);
            radii.push(160.0 + 30.0 * k as f64);
        }
        let n = positions.len();
        let cloud = Cloud::new(positions, radii, vec![3.0; n], vec![1.0; n], 0.86).unwrap();
        let sun = crate::sky::sun_direction(40.0, 200.0).as_dvec3().to_array();
        let field = CloudField::new(cloud, Some(sun), 32).unwrap();
        let light = CloudLight {
            sun: Vec3::new(2.9, 2.8, 2.6),
            sky: Vec3::new(0.9, 1.0, 1.2),
        };
        let eye = DVec3::new(5.0, 2.0, -3.0);
        let dome = CloudDome::build(&field, light, eye, 128).unwrap();
        // A 64 x 48 camera looking 55° up towards azimuth 20°, 70° across.
        let view = Vec3::new(0.35f32.sin() * 0.574, 0.819, -(0.35f32.cos()) * 0.574).normalize();
        let back = -view;
        let right = Vec3::Y.cross(back).normalize();
        let up = back.cross(right);
        let (w, h) = (64u32, 48u32);
        let f = w as f32 / 2.0 / (35f32.to_radians()).tan();
        let cam = Camera::new(
            w,
            h,
            [f, f, w as f32 / 2.0, h as f32 / 2.0],
            eye,
            Mat3::from_cols(right, up, back),
        )
        .unwrap();
        let splats = CloudSplats::prepare(
            &CloudPass {
                field: &field,
                light,
            },
            &cam,
        )
        .unwrap();
        let (mut worst_t, mut worst_s, mut sum_t, mut covered) = (0.0f32, 0.0f32, 0.0f32, 0);
        for y in 0..h {
            let mut rgb = vec![0.0f32; 3 * w as usize];
            let mut alpha = vec![0.0f32; w as usize];
            let depth = vec![f32::INFINITY; w as usize];
            splats.apply_row(&cam, y, &mut rgb, &depth, Some(&mut alpha));
            for x in 0..w {
                let d = cam.ray_direction(x, y).normalize();
                let (t, s) = dome.sample(d);
                let want_s = Vec3::from_slice(&rgb[3 * x as usize..3 * x as usize + 3]);
                let dt = (t - (1.0 - alpha[x as usize])).abs();
                worst_t = worst_t.max(dt);
                sum_t += dt;
                worst_s = worst_s.max((s - want_s).abs().max_element());
                covered += usize::from(alpha[x as usize] > 0.1);
            }
        }
        let mean_t = sum_t / (w * h) as f32;
        assert!(covered > 200, "the camera sees the clouds: {covered} px");
        assert!(
            worst_t < 0.03 && mean_t < 0.002,
            "T: worst {worst_t}, mean {mean_t}"
        );
        assert!(worst_s < 0.06, "S: worst {worst_s}");
        // Nothing below the horizon.
        assert_eq!(
            dome.sample(Vec3::new(0.0, -0.2, -1.0).normalize()),
            (1.0, Vec3::ZERO)
        );
    }
}
