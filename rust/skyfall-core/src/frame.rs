//! The CPU backend's frame: passes fused row by row, so a row is produced, hazed and left
//! while it is in cache.

use crate::error::{Error, Param, Result};
use crate::haze::{apply_row, check_depth, Haze};
use crate::rain::splat::{composite_streaks, RainFrame, RainStats, RainTargets};
use crate::scene::boxes::{shade_pixel, BoxScene, SceneLight};
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
        return Err(Error::Length { param: Param { name: "image", index: None }, len: rgb.len(), expected: 3 * n });
    }
    if depth_m.len() != n {
        return Err(Error::Length { param: Param { name: "depth_m", index: None }, len: depth_m.len(), expected: n });
    }
    check_depth(depth_m)
}

/// Renders a frame on the CPU: scene (ray cast under `light`, or photo copy) and haze fused
/// row by row, then the rain streaks over the result.
pub fn render(scene: SceneRef<'_>, cam: &Camera, light: &SceneLight<'_>, haze: Option<&Haze>, rain: Option<&RainFrame<'_>>) -> Result<FrameBuffers> {
    check_frame_size(cam)?;
    if let SceneRef::Photo { rgb, depth_m } = scene {
        check_photo(cam, rgb, depth_m)?;
    }
    let w = cam.width as usize;
    let n = cam.pixels();
    let mut rgb = vec![0.0f32; 3 * n];
    let mut depth = vec![0.0f32; n];
    let mut trans = haze.map(|_| vec![0.0f32; n]);
    let mut t_rows: Vec<Option<&mut [f32]>> = match trans.as_mut() {
        Some(t) => t.chunks_mut(w).map(Some).collect(),
        None => (0..cam.height).map(|_| None).collect(),
    };
    let u2 = cam.column_slopes_sq();
    rgb.par_chunks_mut(3 * w)
        .zip(depth.par_chunks_mut(w))
        .zip(t_rows.par_iter_mut())
        .enumerate()
        .for_each(|(y, ((rgb_row, depth_row), t_row))| {
            // The scene: ray cast, or the photo's row copied.
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
            // Haze over the row while it is in cache: each pixel leaves memory once.
            if let (Some(h), Some(t_row)) = (haze, t_row.as_deref_mut()) {
                apply_row(h, &u2, cam.row_slope_sq(y as u32), rgb_row, depth_row, t_row);
            }
        });
    let rain = rain.map(|rf| {
        let (streaks, stats, drops) = rf.streaks(cam);
        let mut alpha = vec![0.0f32; n];
        let mut rain_depth = vec![0.0f32; n];
        composite_streaks(
            cam,
            &streaks,
            rf.shading.reflectance,
            RainTargets { rgb: &mut rgb, depth_m: &depth, alpha: &mut alpha, rain_depth_m: &mut rain_depth },
        );
        RainBuffers { alpha, depth_m: rain_depth, stats, drops }
    });
    Ok(FrameBuffers { rgb, depth_m: depth, transmittance: trans, rain })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::boxes;
    use crate::sky::ambient::AmbientMap;
    use crate::sky::{cie::SkyKind, Sky};
    use glam::{Mat3, Vec3};

    #[test]
    fn fused_frame_is_the_ray_cast_then_eq_2_per_pixel() {
        let cam = Camera::new(40, 30, [30.0, 30.0, 20.0, 15.0], Vec3::new(0.0, 1.6, 0.0), Mat3::IDENTITY).unwrap();
        let b = boxes::SceneBox { min_m: Vec3::new(-3.0, 0.0, -12.0), max_m: Vec3::new(3.0, 6.0, -8.0), albedo: Vec3::new(0.6, 0.5, 0.4) };
        let scene = BoxScene::new(vec![b], true, Vec3::splat(0.1)).unwrap();
        let h = Haze { extinction_per_m: 0.02, airlight: [0.43; 3] };
        let sky = Sky::new(SkyKind::Overcast, 0.0, 1000.0).unwrap();
        let amb = AmbientMap::uniform([1.0, 0.4, 0.4, 0.4, 0.4]);
        let light = SceneLight { sky: &sky, ambient: &amb };
        let fused = render(SceneRef::Boxes(&scene), &cam, &light, Some(&h), None).unwrap();
        let t_layer = fused.transmittance.clone().unwrap();
        for y in 0..30u32 {
            for x in 0..40u32 {
                let i = (y * 40 + x) as usize;
                let (c, d) = boxes::shade_pixel(&scene, &cam, &light, x, y);
                let t = if d.is_infinite() { 0.0 } else { (-0.02 * d * cam.distance_per_depth(x, y)).exp() };
                assert_eq!(fused.depth_m[i], d);
                assert!((t_layer[i] - t).abs() <= 1e-6, "{x},{y}");
                for k in 0..3 {
                    assert!((fused.rgb[3 * i + k] - (c[k] * t + 0.43 * (1.0 - t))).abs() <= 1e-6);
                }
            }
        }
        // A photo of that frame rendered without haze comes back unchanged.
        let plain = render(SceneRef::Photo { rgb: &fused.rgb, depth_m: &fused.depth_m }, &cam, &light, None, None).unwrap();
        assert_eq!(plain.rgb, fused.rgb);
        assert!(plain.transmittance.is_none());
    }

    #[test]
    fn huge_frames_are_refused() {
        let cam = Camera::new(16384, 16384, [1e4, 1e4, 8192.0, 8192.0], Vec3::ZERO, Mat3::IDENTITY).unwrap();
        let sky = Sky::new(SkyKind::Overcast, 0.0, 1000.0).unwrap();
        let amb = AmbientMap::uniform([1.0; 5]);
        let light = SceneLight { sky: &sky, ambient: &amb };
        assert!(matches!(render(SceneRef::Photo { rgb: &[], depth_m: &[] }, &cam, &light, None, None), Err(Error::TooLarge { .. })));
    }
}
