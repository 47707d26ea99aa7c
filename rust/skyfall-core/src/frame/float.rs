//! The float output stage: the linear float32 frame and its layers, its stages drawn band by
//! band by [`crate::stage::draw_bands`] (see the module docs of [`super`]).

use super::passes::Particles;
use super::stages::Frame;
use super::{FrameBuffers, FrameOut, RainReport, SceneRef, check_frame_size, check_photo};
use crate::error::Result;
use crate::particles::composite::BAND_ROWS;
use crate::snow::streaks::SnowStats;
use crate::stage::{Output, Whole, draw_bands, draw_whole};

/// Renders `frame` on the CPU into new buffers (see [`draw`]).
pub fn render_frame(frame: &Frame<'_>) -> Result<FrameBuffers> {
    FrameBuffers::filled(frame.cam, frame.layers(), |out| {
        draw(frame, out).map(|(rain, _)| rain)
    })
}

/// Draws `frame` into `out` (every value overwritten): its stages made once, then drawn band
/// by band (16 rows) while the band is in cache, each row through the row stages (the scene,
/// the clouds, the haze, the glows), then the band through the particles; then the whole frame
/// through the whole-frame stages (the windshield). Returns the rain's and the snow's reports.
pub fn draw(
    frame: &Frame<'_>,
    out: FrameOut<'_>,
) -> Result<(Option<RainReport>, Option<SnowStats>)> {
    let cam = frame.cam;
    check_frame_size(cam)?;
    if let SceneRef::Photo { rgb, depth_m } = frame.scene {
        check_photo(cam, rgb, depth_m)?;
    }
    let plan = frame.plan();
    out.check(cam, plan.layers())?;
    let prepared = frame.prepare_planned(&plan, Output::Float)?;
    let FrameOut {
        rgb,
        depth_m,
        mut layers,
    } = out;
    let stages = prepared.stages();
    let width = cam.width as usize;
    draw_bands(
        &stages,
        width,
        BAND_ROWS,
        &mut *rgb,
        &mut *depth_m,
        layers.reborrow(),
    );
    draw_whole(
        &stages,
        &mut Whole {
            width,
            rgb,
            depth_m,
            layers,
        },
    )?;
    let particles = prepared.particles();
    Ok((
        particles.and_then(Particles::rain_report),
        particles.and_then(|p| p.snow),
    ))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::error::{Error, Param};
    use crate::frame::fixture::one_box;
    use crate::frame::scene::SceneLight;
    use crate::haze::Haze;
    use crate::rain::streaks::RainFrame;
    use crate::scene::camera::Camera;
    use crate::sky::ambient::AmbientMap;
    use crate::sky::{Sky, cie::SkyKind};
    use crate::stage::layers::Layer;
    use glam::{Mat3, Vec3};

    #[test]
    fn fused_frame_is_the_ray_cast_then_eq_2_per_pixel() {
        let (cam, scene, h, sky, amb) = one_box(40, 30);
        let light = SceneLight::new(&sky, &amb);
        let fused = render_frame(
            &Frame::new(SceneRef::Boxes(&scene), &cam, &light).with_effects(Some(&h), None, None),
        )
        .unwrap();
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
        let plain = render_frame(
            &Frame::new(
                SceneRef::Photo {
                    rgb: &fused.rgb,
                    depth_m: &fused.depth_m,
                },
                &cam,
                &light,
            )
            .with_effects(None, None, None),
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
        let want =
            render_frame(&Frame::new(scene, &cam, &light).with_effects(Some(&h), Some(&rf), None))
                .unwrap();
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
        let (stats, drops) = draw(
            &Frame::new(scene, &cam, &light).with_effects(Some(&h), Some(&rf), None),
            out,
        )
        .map(|(r, _)| r)
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
            draw(
                &Frame::new(scene, &cam, &light).with_effects(None, None, None),
                short
            )
            .map(|(r, _)| r),
            Err(Error::Length {
                param: Param { name: "rgb", .. },
                ..
            })
        ));
        let missing = FrameOut::from_layers(&mut rgb, &mut d, []);
        assert!(matches!(
            draw(
                &Frame::new(scene, &cam, &light).with_effects(Some(&h), None, None),
                missing
            )
            .map(|(r, _)| r),
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
            draw(
                &Frame::new(scene, &cam, &light).with_effects(None, None, None),
                extra
            )
            .map(|(r, _)| r),
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
            render_frame(
                &Frame::new(
                    SceneRef::Photo {
                        rgb: &[],
                        depth_m: &[]
                    },
                    &cam,
                    &light
                )
                .with_effects(None, None, None)
            ),
            // the photo's arrays are checked before any frame-sized allocation
            Err(Error::Length { .. })
        ));
        // every size the width and height ranges accept is within the budget
        assert!(crate::frame::check_frame_size(&cam).is_ok());
    }
}
