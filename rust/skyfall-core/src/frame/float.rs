//! The float output stage: the linear float32 frame and its layers, band by band (see the
//! module docs of [`super`]).

use super::layers::Layer;
use super::passes::Passes;
use super::scene::{SceneLight, shade_pixel_sun};
use super::{FrameBuffers, FrameOut, RainReport, SceneRef, check_frame_size, check_photo};
use crate::cloud::frame::CloudSplats;
use crate::error::Result;
use crate::haze::{Haze, ViewRays, apply_row};
use crate::particles::composite::{BAND_ROWS, bin_by_bands, composite_band_colour};
use crate::rain::streaks::RainFrame;
use crate::scene::camera::Camera;
use crate::snow::streaks::{SnowFrame, SnowStats};
use rayon::prelude::*;

/// Renders a frame on the CPU: scene (ray cast under `light`, or photo copy) and haze fused
/// row by row, then the rain's and the snow's streaks over the result.
pub fn render(
    scene: SceneRef<'_>,
    cam: &Camera,
    light: &SceneLight<'_>,
    haze: Option<&Haze>,
    rain: Option<&RainFrame<'_>>,
    snow: Option<&SnowFrame<'_>>,
) -> Result<FrameBuffers> {
    FrameBuffers::filled(
        cam,
        light.drawn(haze.is_some(), rain.is_some(), snow.is_some()),
        |out| render_into(scene, cam, light, haze, rain, snow, out),
    )
}

/// [`render`] into the caller's buffers (see [`FrameOut`]); the rain's report when it rains.
pub fn render_into(
    scene: SceneRef<'_>,
    cam: &Camera,
    light: &SceneLight<'_>,
    haze: Option<&Haze>,
    rain: Option<&RainFrame<'_>>,
    snow: Option<&SnowFrame<'_>>,
    out: FrameOut<'_>,
) -> Result<Option<RainReport>> {
    render_into_reporting(scene, cam, light, haze, rain, snow, out).map(|(rain, _)| rain)
}

/// [`render_into`], with the snow's report too.
pub fn render_into_reporting(
    scene: SceneRef<'_>,
    cam: &Camera,
    light: &SceneLight<'_>,
    haze: Option<&Haze>,
    rain: Option<&RainFrame<'_>>,
    snow: Option<&SnowFrame<'_>>,
    out: FrameOut<'_>,
) -> Result<(Option<RainReport>, Option<SnowStats>)> {
    check_frame_size(cam)?;
    if let SceneRef::Photo { rgb, depth_m } = scene {
        check_photo(cam, rgb, depth_m)?;
    }
    out.check(
        cam,
        light.drawn(haze.is_some(), rain.is_some(), snow.is_some()),
    )?;
    let w = cam.width as usize;
    let FrameOut {
        rgb,
        depth_m: depth,
        mut layers,
    } = out;
    let trans = layers.take(Layer::Transmittance);
    let snow_depth = layers.take(Layer::SnowDepth);
    let rain_layers = layers
        .take(Layer::RainAlpha)
        .zip(layers.take(Layer::RainDepth));
    let snow_layer = layers.take(Layer::SnowAlpha);
    let cloud_alpha = layers.take(Layer::CloudAlpha);
    let sun_t = layers.take(Layer::SunTransmittance);
    // The clouds' splats, sorted and binned once.
    let clouds = light
        .clouds
        .as_ref()
        .map(|c| CloudSplats::prepare(c, cam))
        .transpose()?;
    // The passes first (the particles do not depend on the scene), the particles binned to
    // the bands.
    let lit = match scene {
        SceneRef::Boxes(b) => Some((b, light)),
        SceneRef::Photo { .. } => None,
    };
    let passes = Passes::prepare(cam, lit, haze, rain, snow)?;
    let glow = passes.glow.as_ref();
    let binned = passes
        .particles
        .as_ref()
        .map(|p| bin_by_bands(cam, &p.streaks).map(|bins| (p.streaks.as_slice(), bins)))
        .transpose()?;
    let band = BAND_ROWS * w;
    let bands = cam.pixels().div_ceil(band);
    let mut t_bands = split_bands(trans, band, bands);
    // Each band's particle layers: [rain_alpha, rain_depth_m, snow_alpha], empty where the
    // frame does not draw one (no particle of that effect is in the list then).
    let mut rain_bands: Vec<[&mut [f32]; 3]> = (0..bands).map(|_| Default::default()).collect();
    if let Some((alpha, rain_depth)) = rain_layers {
        for (b, (a, d)) in rain_bands
            .iter_mut()
            .zip(alpha.chunks_mut(band).zip(rain_depth.chunks_mut(band)))
        {
            (b[0], b[1]) = (a, d);
        }
    }
    if let Some(snow_alpha) = snow_layer {
        for (b, s) in rain_bands.iter_mut().zip(snow_alpha.chunks_mut(band)) {
            b[2] = s;
        }
    }
    // The snow cover's depth per band (a frame with a cover only).
    let mut cover_bands = split_bands(snow_depth, band, bands);
    let mut cloud_bands = split_bands(cloud_alpha, band, bands);
    let mut sun_bands = split_bands(sun_t, band, bands);
    let rays = ViewRays::new(cam);
    let particles = binned.as_ref().map(|(streaks, bins)| (*streaks, bins));
    let far = passes.far();
    // The pipeline, band by band while the band is in cache: the scene stage, then the effect
    // passes in physical order (haze, the lights' glows, the particles).
    rgb.par_chunks_mut(3 * band)
        .zip(depth.par_chunks_mut(band))
        .zip(t_bands.par_iter_mut())
        .zip(rain_bands.par_iter_mut())
        .zip(cover_bands.par_iter_mut())
        .zip(cloud_bands.par_iter_mut().zip(sun_bands.par_iter_mut()))
        .enumerate()
        .for_each(
            |(
                bi,
                (
                    ((((rgb_band, depth_band), t_band), rain_band), cover_band),
                    (cloud_band, sun_band),
                ),
            )| {
                let y0 = bi * BAND_ROWS;
                for (k, (rgb_row, depth_row)) in rgb_band
                    .chunks_mut(3 * w)
                    .zip(depth_band.chunks_mut(w))
                    .enumerate()
                {
                    let y = y0 + k;
                    let row = k * w..(k + 1) * w;
                    let sun_row = sun_band.as_deref_mut().map(|b| &mut b[row.clone()]);
                    match (light.snow, cover_band.as_deref_mut()) {
                        (Some(snow), Some(s_band)) => {
                            let s_row = &mut s_band[row.clone()];
                            let rows = (&mut *rgb_row, &mut *depth_row, s_row, sun_row);
                            snow_scene_row(scene, cam, light, snow, y, rows);
                        }
                        _ => scene_row(scene, cam, light, y, rgb_row, depth_row, sun_row),
                    }
                    if let Some(c) = &clouds {
                        let a_row = cloud_band.as_deref_mut().map(|b| &mut b[row.clone()]);
                        c.apply_row(cam, y as u32, rgb_row, depth_row, a_row);
                    }
                    if let (Some(h), Some(t_band)) = (haze, t_band.as_deref_mut()) {
                        let t_row = &mut t_band[k * w..(k + 1) * w];
                        apply_row(h, &rays.row(y as u32, 0..w), rgb_row, depth_row, t_row);
                    }
                    if let Some(g) = glow {
                        g.apply_row(cam, y as u32, rgb_row);
                    }
                }
                if let Some((streaks, (offsets, indices))) = particles {
                    let list = &indices[offsets[bi] as usize..offsets[bi + 1] as usize];
                    let [alpha, rain_depth, snow_alpha] = rain_band;
                    composite_band_colour(
                        streaks,
                        list,
                        far,
                        y0,
                        w,
                        depth_band,
                        rgb_band,
                        [&mut **alpha, &mut **rain_depth, &mut **snow_alpha],
                    );
                }
            },
        );
    Ok((passes.rain_report(), passes.snow_report()))
}

/// A layer's bands of `band` values (`bands` of them), or `bands` Nones without the layer.
fn split_bands(layer: Option<&mut [f32]>, band: usize, bands: usize) -> Vec<Option<&mut [f32]>> {
    match layer {
        Some(t) => t.chunks_mut(band).map(Some).collect(),
        None => (0..bands).map(|_| None).collect(),
    }
}

/// The scene stage of one row: the box scene ray cast (with each pixel's share of the sun into
/// `sun_row` when given), or the photo's row copied.
fn scene_row(
    scene: SceneRef<'_>,
    cam: &Camera,
    light: &SceneLight<'_>,
    y: usize,
    rgb_row: &mut [f32],
    depth_row: &mut [f32],
    mut sun_row: Option<&mut [f32]>,
) {
    let w = depth_row.len();
    match scene {
        SceneRef::Boxes(b) => {
            for x in 0..w {
                let (c, d, s) = shade_pixel_sun(b, cam, light, x as u32, y as u32);
                rgb_row[3 * x..3 * x + 3].copy_from_slice(&c.to_array());
                depth_row[x] = d;
                if let Some(r) = sun_row.as_deref_mut() {
                    r[x] = s;
                }
            }
        }
        SceneRef::Photo { rgb, depth_m } => {
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
    scene: SceneRef<'_>,
    cam: &Camera,
    light: &SceneLight<'_>,
    snow: &crate::snow::cover::SnowRender,
    y: usize,
    (rgb_row, depth_row, snow_row, mut sun_row): SnowRows<'_>,
) {
    match scene {
        SceneRef::Boxes(b) => {
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
        SceneRef::Photo { .. } => {
            scene_row(scene, cam, light, y, rgb_row, depth_row, None);
            snow.photo_row(cam, light.ambient, y, rgb_row, depth_row, Some(snow_row));
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::error::{Error, Param};
    use crate::scene::boxes;
    use crate::scene::boxes::BoxScene;
    use crate::sky::ambient::AmbientMap;
    use crate::sky::{Sky, cie::SkyKind};
    use glam::{Mat3, Vec3};

    #[test]
    fn fused_frame_is_the_ray_cast_then_eq_2_per_pixel() {
        let cam = Camera::new(
            40,
            30,
            [30.0, 30.0, 20.0, 15.0],
            Vec3::new(0.0, 1.6, 0.0),
            Mat3::IDENTITY,
        )
        .unwrap();
        let b = boxes::SceneBox {
            min_m: Vec3::new(-3.0, 0.0, -12.0),
            max_m: Vec3::new(3.0, 6.0, -8.0),
            albedo: Vec3::new(0.6, 0.5, 0.4),
        };
        let scene = BoxScene::new(vec![b], true, Vec3::splat(0.1)).unwrap();
        let h = Haze::new(0.02, [0.43; 3], 700.0).unwrap();
        let sky = Sky::new(SkyKind::Overcast, 0.0, 1000.0).unwrap();
        let amb = AmbientMap::uniform([1.0, 0.4, 0.4, 0.4, 0.4]);
        let light = SceneLight::new(&sky, &amb);
        let fused = render(SceneRef::Boxes(&scene), &cam, &light, Some(&h), None, None).unwrap();
        let t_layer = fused.layer(Layer::Transmittance).unwrap().to_vec();
        for y in 0..30u32 {
            for x in 0..40u32 {
                let i = (y * 40 + x) as usize;
                let (c, d) = super::super::scene::shade_pixel(&scene, &cam, &light, x, y);
                let t = if d.is_infinite() {
                    // the sky is hazed up to the cloud base, 700 m above the eye
                    let up = cam.ray_direction(x, y).normalize().y;
                    if up > 0.0 {
                        (-0.02 * 700.0 / up).exp()
                    } else {
                        0.0
                    }
                } else {
                    (-0.02 * d * cam.distance_per_depth(x, y)).exp()
                };
                assert_eq!(fused.depth_m[i], d);
                assert!((t_layer[i] - t).abs() <= 1e-6, "{x},{y}");
                for k in 0..3 {
                    assert!((fused.rgb[3 * i + k] - (c[k] * t + 0.43 * (1.0 - t))).abs() <= 1e-6);
                }
            }
        }
        // A photo of that frame rendered without haze comes back unchanged.
        let plain = render(
            SceneRef::Photo {
                rgb: &fused.rgb,
                depth_m: &fused.depth_m,
            },
            &cam,
            &light,
            None,
            None,
            None,
        )
        .unwrap();
        assert_eq!(plain.rgb, fused.rgb);
        assert!(plain.layer(Layer::Transmittance).is_none());
    }

    #[test]
    fn render_into_overwrites_every_value_and_checks_its_buffers() {
        // Buffers full of NaN (numpy's np.empty could hold anything) come out as render's
        // frame, bit for bit, rain and haze included.
        use crate::rain::drops::RainRegion;
        use crate::rain::streaks::RainShading;
        let cam = Camera::new(
            48,
            32,
            [40.0, 40.0, 24.0, 16.0],
            Vec3::new(0.0, 1.6, 0.0),
            Mat3::IDENTITY,
        )
        .unwrap();
        let sky = Sky::new(SkyKind::Overcast, 0.0, 1000.0).unwrap();
        let amb = AmbientMap::uniform([1.0, 0.4, 0.4, 0.4, 0.4]);
        let light = SceneLight::new(&sky, &amb);
        let n = cam.pixels();
        let (photo, depth) = (vec![0.2f32; 3 * n], vec![3.0f32; n]);
        let scene = SceneRef::Photo {
            rgb: &photo,
            depth_m: &depth,
        };
        let h = Haze::new(0.02, [0.43; 3], f32::INFINITY).unwrap();
        let region = RainRegion::new(40.0, &[1.0, 1.5, 2.0], 3.0, [0.0; 3], 0.0, 4).unwrap();
        let shading = RainShading::open_sky();
        let rf = RainFrame {
            region: &region,
            exposure_s: 1.0 / 30.0,
            camera_velocity_m_s: Vec3::ZERO,
            lens: None,
            ground: true,
            shelter: &[],
            shading: &shading,
        };
        let want = render(scene, &cam, &light, Some(&h), Some(&rf), None).unwrap();
        let (mut rgb, mut d, mut t, mut a, mut rd) = (
            vec![f32::NAN; 3 * n],
            vec![f32::NAN; n],
            vec![f32::NAN; n],
            vec![f32::NAN; n],
            vec![f32::NAN; n],
        );
        let out = FrameOut::from_layers(
            &mut rgb,
            &mut d,
            [
                (Layer::Transmittance, &mut t[..]),
                (Layer::RainAlpha, &mut a[..]),
                (Layer::RainDepth, &mut rd[..]),
            ],
        );
        let (stats, drops) = render_into(scene, &cam, &light, Some(&h), Some(&rf), None, out)
            .unwrap()
            .unwrap();
        let bits = |v: &[f32]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        assert!(stats.streaks > 0 && want.rain == Some((stats, drops)));
        assert_eq!(bits(&rgb), bits(&want.rgb));
        assert_eq!(bits(&d), bits(&want.depth_m));
        assert_eq!(bits(&t), bits(want.layer(Layer::Transmittance).unwrap()));
        assert_eq!(bits(&a), bits(want.layer(Layer::RainAlpha).unwrap()));
        assert_eq!(bits(&rd), bits(want.layer(Layer::RainDepth).unwrap()));
        // Buffers that do not match the request are named.
        let short = FrameOut::from_layers(&mut rgb[1..], &mut d, []);
        assert!(matches!(
            render_into(scene, &cam, &light, None, None, None, short),
            Err(Error::Length {
                param: Param { name: "rgb", .. },
                ..
            })
        ));
        let missing = FrameOut::from_layers(&mut rgb, &mut d, []);
        assert!(matches!(
            render_into(scene, &cam, &light, Some(&h), None, None, missing),
            Err(Error::Length {
                param: Param {
                    name: "transmittance",
                    ..
                },
                ..
            })
        ));
        let extra = FrameOut::from_layers(
            &mut rgb,
            &mut d,
            [
                (Layer::RainAlpha, &mut a[..]),
                (Layer::RainDepth, &mut rd[..]),
            ],
        );
        assert!(matches!(
            render_into(scene, &cam, &light, None, None, None, extra),
            Err(Error::Length {
                param: Param {
                    name: "rain_alpha",
                    ..
                },
                ..
            })
        ));
    }

    #[test]
    fn the_largest_documented_frame_is_within_the_budget_and_checked_before_allocating() {
        let cam = Camera::new(
            16384,
            16384,
            [1e4, 1e4, 8192.0, 8192.0],
            Vec3::ZERO,
            Mat3::IDENTITY,
        )
        .unwrap();
        let sky = Sky::new(SkyKind::Overcast, 0.0, 1000.0).unwrap();
        let amb = AmbientMap::uniform([1.0; 5]);
        let light = SceneLight::new(&sky, &amb);
        assert!(matches!(
            render(
                SceneRef::Photo {
                    rgb: &[],
                    depth_m: &[]
                },
                &cam,
                &light,
                None,
                None,
                None
            ),
            // the photo's arrays are checked before any frame-sized allocation
            Err(Error::Length { .. })
        ));
        // every size the width and height ranges accept is within the budget
        assert!(crate::frame::check_frame_size(&cam).is_ok());
    }
}
