//! The CPU backend's frame: passes fused row by row, so a row is produced, hazed and left
//! while it is in cache.

use crate::error::{Error, Param, Result};
use crate::haze::{Haze, apply_row, check_depth};
use crate::particles::composite::{BAND_ROWS, bin_by_bands, composite_band_colour};
use crate::rain::streaks::{RainFrame, RainStats};
use crate::scene::boxes::{BoxScene, SceneLight, shade_pixel};
use crate::scene::camera::Camera;
use rayon::prelude::*;

/// Largest frame (rgb + depth + layers, float32) the renderers allocate: 4 GiB.
pub const FRAME_BUDGET_BYTES: u64 = 4 << 30;
/// float32 values per pixel a frame may hold: rgb, depth and up to four layers.
const VALUES_PER_PIXEL: u64 = 8;

/// What the frame shows.
#[derive(Debug, Clone, Copy)]
pub enum SceneRef<'a> {
    /// The procedural box scene, ray cast.
    Boxes(&'a BoxScene),
    /// A photo (linear RGB, H·W·3) with its depth map (H·W, metres along the axis, inf = sky).
    Photo {
        /// Linear RGB.
        rgb: &'a [f32],
        /// Depth, m.
        depth_m: &'a [f32],
    },
}

/// What the rain pass wrote.
#[derive(Debug, Clone, PartialEq)]
pub struct RainBuffers {
    /// Streak coverage 1 − ∏(1 − aᵢ), H·W.
    pub alpha: Vec<f32>,
    /// Nearest visible streak depth, m (inf: none), H·W.
    pub depth_m: Vec<f32>,
    /// Streaks drawn and culled.
    pub stats: RainStats,
    /// Drops generated (in the voxels that can reach the view).
    pub drops: usize,
}

/// A rendered frame's buffers.
#[derive(Debug, Clone, PartialEq)]
pub struct FrameBuffers {
    /// Linear RGB, H·W·3.
    pub rgb: Vec<f32>,
    /// Depth along the optical axis, m (inf for sky), H·W.
    pub depth_m: Vec<f32>,
    /// Haze transmittance e^(−σ d), H·W, when the haze pass ran.
    pub transmittance: Option<Vec<f32>>,
    /// Rain layers, when the rain pass ran.
    pub rain: Option<RainBuffers>,
}

/// Refuses frames over [`FRAME_BUDGET_BYTES`] before allocating.
pub fn check_frame_size(cam: &Camera) -> Result<()> {
    let bytes = cam.pixels() as u128 * u128::from(VALUES_PER_PIXEL) * 4;
    if bytes > u128::from(FRAME_BUDGET_BYTES) {
        let what = format!("a {}x{} frame", cam.width, cam.height);
        return Err(Error::too_large(what, bytes, FRAME_BUDGET_BYTES));
    }
    Ok(())
}

/// Checks a photo scene's arrays against the camera.
pub fn check_photo(cam: &Camera, rgb: &[f32], depth_m: &[f32]) -> Result<()> {
    let n = cam.pixels();
    if rgb.len() != 3 * n {
        return Err(Error::Length {
            param: Param {
                name: "image",
                index: None,
            },
            len: rgb.len(),
            expected: 3 * n,
        });
    }
    if depth_m.len() != n {
        return Err(Error::Length {
            param: Param {
                name: "depth_m",
                index: None,
            },
            len: depth_m.len(),
            expected: n,
        });
    }
    check_depth(depth_m)
}

/// Where [`render_into`] writes a frame: buffers the caller owns, every value overwritten
/// (the Python binding passes numpy's arrays, so a frame's megabytes come from numpy's
/// allocator, which asks for huge pages: a fresh frame then costs a few dozen page faults
/// instead of one per 4 KiB).
pub struct FrameOut<'a> {
    /// Linear RGB, H·W·3.
    pub rgb: &'a mut [f32],
    /// Depth along the optical axis, m, H·W.
    pub depth_m: &'a mut [f32],
    /// Haze transmittance, H·W: given exactly when there is haze.
    pub transmittance: Option<&'a mut [f32]>,
    /// Rain coverage and nearest streak depth, H·W each: given exactly when it rains.
    pub rain: Option<(&'a mut [f32], &'a mut [f32])>,
}

/// What [`render_into`] reports of the rain: streaks drawn and culled, drops generated.
pub type RainReport = (RainStats, usize);

impl FrameOut<'_> {
    /// Checks the buffers against a `cam` frame with or without haze and rain: every length,
    /// and the layers given exactly when they are drawn.
    pub fn check(&self, cam: &Camera, haze: bool, rain: bool) -> Result<()> {
        let n = cam.pixels();
        let length = |name: &'static str, len: usize, expected: usize| Error::Length {
            param: Param { name, index: None },
            len,
            expected,
        };
        if self.rgb.len() != 3 * n {
            return Err(length("rgb", self.rgb.len(), 3 * n));
        }
        if self.depth_m.len() != n {
            return Err(length("depth_m", self.depth_m.len(), n));
        }
        let t = self.transmittance.as_ref().map_or(0, |t| t.len());
        if t != if haze { n } else { 0 } || haze != self.transmittance.is_some() {
            return Err(length("transmittance", t, if haze { n } else { 0 }));
        }
        let (a, d) = self
            .rain
            .as_ref()
            .map_or((0, 0), |(a, d)| (a.len(), d.len()));
        if a != if rain { n } else { 0 } || rain != self.rain.is_some() {
            return Err(length("rain_alpha", a, if rain { n } else { 0 }));
        }
        if d != a {
            return Err(length("rain_depth_m", d, a));
        }
        Ok(())
    }
}

impl FrameBuffers {
    /// A `cam` frame's buffers (with the transmittance layer when `haze`, the rain layers when
    /// `rain`), sized after the frame is checked to fit, filled by a backend's `render_into`.
    pub fn filled<E: From<Error>>(
        cam: &Camera,
        haze: bool,
        rain: bool,
        render_into: impl FnOnce(FrameOut<'_>) -> std::result::Result<Option<RainReport>, E>,
    ) -> std::result::Result<Self, E> {
        check_frame_size(cam)?;
        let n = cam.pixels();
        let (mut rgb, mut depth) = (vec![0.0f32; 3 * n], vec![0.0f32; n]);
        let mut trans = haze.then(|| vec![0.0f32; n]);
        let mut layers = rain.then(|| (vec![0.0f32; n], vec![0.0f32; n]));
        let out = FrameOut {
            rgb: &mut rgb,
            depth_m: &mut depth,
            transmittance: trans.as_deref_mut(),
            rain: layers
                .as_mut()
                .map(|(a, d)| (a.as_mut_slice(), d.as_mut_slice())),
        };
        let report = render_into(out)?;
        let rain = layers
            .zip(report)
            .map(|((alpha, depth_m), (stats, drops))| RainBuffers {
                alpha,
                depth_m,
                stats,
                drops,
            });
        Ok(FrameBuffers {
            rgb,
            depth_m: depth,
            transmittance: trans,
            rain,
        })
    }
}

/// Renders a frame on the CPU: scene (ray cast under `light`, or photo copy) and haze fused
/// row by row, then the rain streaks over the result.
pub fn render(
    scene: SceneRef<'_>,
    cam: &Camera,
    light: &SceneLight<'_>,
    haze: Option<&Haze>,
    rain: Option<&RainFrame<'_>>,
) -> Result<FrameBuffers> {
    FrameBuffers::filled(cam, haze.is_some(), rain.is_some(), |out| {
        render_into(scene, cam, light, haze, rain, out)
    })
}

/// [`render`] into the caller's buffers (see [`FrameOut`]); the rain's report when it rains.
pub fn render_into(
    scene: SceneRef<'_>,
    cam: &Camera,
    light: &SceneLight<'_>,
    haze: Option<&Haze>,
    rain: Option<&RainFrame<'_>>,
    out: FrameOut<'_>,
) -> Result<Option<RainReport>> {
    check_frame_size(cam)?;
    if let SceneRef::Photo { rgb, depth_m } = scene {
        check_photo(cam, rgb, depth_m)?;
    }
    out.check(cam, haze.is_some(), rain.is_some())?;
    let w = cam.width as usize;
    let FrameOut {
        rgb,
        depth_m: depth,
        transmittance: trans,
        rain: layers,
    } = out;
    // The particles first (they do not depend on the scene), binned to the bands.
    let prepared = match rain.zip(layers) {
        Some((rf, layers)) => {
            let (streaks, stats, drops) = rf.streaks(cam)?;
            let bins = bin_by_bands(cam, &streaks);
            Some(((streaks, bins, stats, drops), layers))
        }
        None => None,
    };
    let (rain, layers) = prepared.unzip();
    let band = BAND_ROWS * w;
    let bands = cam.pixels().div_ceil(band);
    let mut t_bands: Vec<Option<&mut [f32]>> = match trans {
        Some(t) => t.chunks_mut(band).map(Some).collect(),
        None => (0..bands).map(|_| None).collect(),
    };
    let mut rain_bands: Vec<Option<(&mut [f32], &mut [f32])>> = match layers {
        Some((alpha, rain_depth)) => alpha
            .chunks_mut(band)
            .zip(rain_depth.chunks_mut(band))
            .map(Some)
            .collect(),
        None => (0..bands).map(|_| None).collect(),
    };
    let u2 = cam.column_slopes_sq();
    let particles = rain
        .as_ref()
        .map(|(streaks, bins, ..)| (streaks.as_slice(), bins));
    // The pipeline, band by band while the band is in cache: the scene stage, then the effect
    // passes in physical order (haze, rain).
    rgb.par_chunks_mut(3 * band)
        .zip(depth.par_chunks_mut(band))
        .zip(t_bands.par_iter_mut())
        .zip(rain_bands.par_iter_mut())
        .enumerate()
        .for_each(|(bi, (((rgb_band, depth_band), t_band), rain_band))| {
            let y0 = bi * BAND_ROWS;
            for (k, (rgb_row, depth_row)) in rgb_band
                .chunks_mut(3 * w)
                .zip(depth_band.chunks_mut(w))
                .enumerate()
            {
                let y = y0 + k;
                scene_row(scene, cam, light, y, rgb_row, depth_row);
                if let (Some(h), Some(t_band)) = (haze, t_band.as_deref_mut()) {
                    let t_row = &mut t_band[k * w..(k + 1) * w];
                    apply_row(
                        h,
                        &u2,
                        cam.row_slope_sq(y as u32),
                        rgb_row,
                        depth_row,
                        t_row,
                    );
                }
            }
            if let (Some((streaks, (offsets, indices))), Some((alpha, rain_depth))) =
                (particles, rain_band.as_mut())
            {
                let list = &indices[offsets[bi] as usize..offsets[bi + 1] as usize];
                composite_band_colour(
                    streaks, list, y0, w, depth_band, rgb_band, alpha, rain_depth,
                );
            }
        });
    Ok(rain.map(|(_, _, stats, drops)| (stats, drops)))
}

/// The scene stage of one row: the box scene ray cast, or the photo's row copied.
fn scene_row(
    scene: SceneRef<'_>,
    cam: &Camera,
    light: &SceneLight<'_>,
    y: usize,
    rgb_row: &mut [f32],
    depth_row: &mut [f32],
) {
    let w = depth_row.len();
    match scene {
        SceneRef::Boxes(b) => {
            for x in 0..w {
                let (c, d) = shade_pixel(b, cam, light, x as u32, y as u32);
                rgb_row[3 * x..3 * x + 3].copy_from_slice(&c.to_array());
                depth_row[x] = d;
            }
        }
        SceneRef::Photo { rgb, depth_m } => {
            rgb_row.copy_from_slice(&rgb[3 * w * y..3 * w * (y + 1)]);
            depth_row.copy_from_slice(&depth_m[w * y..w * (y + 1)]);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::boxes;
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
        let h = Haze {
            extinction_per_m: 0.02,
            airlight: [0.43; 3],
        };
        let sky = Sky::new(SkyKind::Overcast, 0.0, 1000.0).unwrap();
        let amb = AmbientMap::uniform([1.0, 0.4, 0.4, 0.4, 0.4]);
        let light = SceneLight {
            sky: &sky,
            ambient: &amb,
        };
        let fused = render(SceneRef::Boxes(&scene), &cam, &light, Some(&h), None).unwrap();
        let t_layer = fused.transmittance.clone().unwrap();
        for y in 0..30u32 {
            for x in 0..40u32 {
                let i = (y * 40 + x) as usize;
                let (c, d) = boxes::shade_pixel(&scene, &cam, &light, x, y);
                let t = if d.is_infinite() {
                    0.0
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
        )
        .unwrap();
        assert_eq!(plain.rgb, fused.rgb);
        assert!(plain.transmittance.is_none());
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
        let light = SceneLight {
            sky: &sky,
            ambient: &amb,
        };
        let n = cam.pixels();
        let (photo, depth) = (vec![0.2f32; 3 * n], vec![3.0f32; n]);
        let scene = SceneRef::Photo {
            rgb: &photo,
            depth_m: &depth,
        };
        let h = Haze {
            extinction_per_m: 0.02,
            airlight: [0.43; 3],
        };
        let region = RainRegion::new(40.0, &[1.0, 1.5, 2.0], 3.0, [0.0; 3], 0.0, 4).unwrap();
        let shading = RainShading::open_sky();
        let rf = RainFrame {
            region: &region,
            exposure_s: 1.0 / 30.0,
            camera_velocity_m_s: Vec3::ZERO,
            ground: true,
            shelter: &[],
            shading: &shading,
        };
        let want = render(scene, &cam, &light, Some(&h), Some(&rf)).unwrap();
        let (mut rgb, mut d, mut t, mut a, mut rd) = (
            vec![f32::NAN; 3 * n],
            vec![f32::NAN; n],
            vec![f32::NAN; n],
            vec![f32::NAN; n],
            vec![f32::NAN; n],
        );
        let out = FrameOut {
            rgb: &mut rgb,
            depth_m: &mut d,
            transmittance: Some(&mut t),
            rain: Some((&mut a, &mut rd)),
        };
        let (stats, drops) = render_into(scene, &cam, &light, Some(&h), Some(&rf), out)
            .unwrap()
            .unwrap();
        let bits = |v: &[f32]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        let rain = want.rain.unwrap();
        assert!(stats.streaks > 0 && drops == rain.drops && stats == rain.stats);
        assert_eq!(bits(&rgb), bits(&want.rgb));
        assert_eq!(bits(&d), bits(&want.depth_m));
        assert_eq!(bits(&t), bits(&want.transmittance.unwrap()));
        assert_eq!(bits(&a), bits(&rain.alpha));
        assert_eq!(bits(&rd), bits(&rain.depth_m));
        // Buffers that do not match the request are named.
        let short = FrameOut {
            rgb: &mut rgb[1..],
            depth_m: &mut d,
            transmittance: None,
            rain: None,
        };
        assert!(matches!(
            render_into(scene, &cam, &light, None, None, short),
            Err(Error::Length {
                param: Param { name: "rgb", .. },
                ..
            })
        ));
        let missing = FrameOut {
            rgb: &mut rgb,
            depth_m: &mut d,
            transmittance: None,
            rain: None,
        };
        assert!(matches!(
            render_into(scene, &cam, &light, Some(&h), None, missing),
            Err(Error::Length {
                param: Param {
                    name: "transmittance",
                    ..
                },
                ..
            })
        ));
        let extra = FrameOut {
            rgb: &mut rgb,
            depth_m: &mut d,
            transmittance: None,
            rain: Some((&mut a, &mut rd)),
        };
        assert!(matches!(
            render_into(scene, &cam, &light, None, None, extra),
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
    fn huge_frames_are_refused() {
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
        let light = SceneLight {
            sky: &sky,
            ambient: &amb,
        };
        assert!(matches!(
            render(
                SceneRef::Photo {
                    rgb: &[],
                    depth_m: &[]
                },
                &cam,
                &light,
                None,
                None
            ),
            Err(Error::TooLarge { .. })
        ));
    }
}
