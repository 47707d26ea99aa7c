//! Seed 000's billboards, drawn sparsely: per voxel and diameter bin, the bin's rain texture
//! ([`super::texture::draw_streaks`], one per bin, shared by all voxels) on a 1 m × 1 m
//! billboard through the voxel centre. Billboards are cylindrical: they face the horizontal
//! direction to the camera. Each billboard's texture scrolls down at the fall speed of its
//! bin's middle diameter and wraps (the seed moves billboards down by v·dt and wraps them), and
//! gets a random offset per voxel and bin so neighbouring voxels do not repeat one pattern
//! (the seed repeats it). The texture's streaks become drops on the billboard plane: every
//! streak of a billboard is drawn at the billboard's depth, which is the approximation that the
//! per-drop reference ([`super::drops`]) measures.

use super::drops::{voxel_in_view, voxels_where, Drop, RainRegion};
use super::texture::{draw_streaks, Streak};
use crate::physics::air::Air;
use crate::physics::fall_speed::{FallSpeed, FallSpeedModel};
use crate::scene::camera::Camera;
use crate::seed::derive;
use glam::Vec3;
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64Mcg;

fn wrap(x: f64) -> f64 {
    x - x.floor()
}

/// The billboards' streaks as drops, for the voxels that can draw into `cam`'s frame.
pub fn billboards_in_view(region: &RainRegion, cam: &Camera, exposure_s: f64, camera_speed_m_s: f64, ground: bool) -> Vec<Drop> {
    let law = FallSpeed::new(FallSpeedModel::Beard, &Air::STANDARD.props());
    let textures: Vec<Vec<Streak>> =
        region.bins.iter().map(|&(lo, hi)| draw_streaks(region.rain_rate_mm_h, lo, hi, exposure_s, region.seed)).collect();
    let scroll: Vec<f64> = region.bins.iter().map(|&(lo, hi)| law.m_s(0.5 * (lo + hi)) * region.time_s).collect();
    let eye = cam.position_m;
    // A billboard's streak can end up to its own length below the voxel (the texture wraps).
    let longest = region.bins.last().map_or(0.0, |b| law.m_s(b.1)) * exposure_s;
    voxels_where(region, cam.position_m, ground, voxel_in_view(region, cam, exposure_s, camera_speed_m_s, longest), |voxel, out| {
        let centre = Vec3::new(voxel[0] as f32 + 0.5, voxel[1] as f32 + 0.5, voxel[2] as f32 + 0.5);
        let to_eye = Vec3::new(eye.x - centre.x, 0.0, eye.z - centre.z);
        let n = if to_eye.length_squared() > 1e-12 { to_eye.normalize() } else { Vec3::Z };
        let right = Vec3::new(n.z, 0.0, -n.x);
        for (bin, streaks) in textures.iter().enumerate() {
            let key = derive(region.seed, &[voxel[0] as u64, voxel[1] as u64, voxel[2] as u64, bin as u64, 0xB111_B0A4D]);
            let mut rng = Pcg64Mcg::seed_from_u64(key);
            let (ox, oy): (f64, f64) = (rng.random(), rng.random());
            for (k, s) in streaks.iter().enumerate() {
                let u = wrap(s.x_m + ox);
                let top = wrap(s.y_m + oy + scroll[bin]);
                let bottom = top + s.length_m;
                let end = centre + right * (u - 0.5) as f32 + Vec3::Y * (0.5 - bottom) as f32;
                let fall = (s.length_m / exposure_s) as f32;
                out.push(Drop {
                    position_m: end,
                    velocity_m_s: Vec3::new(region.wind_m_s.x as f32, -fall, region.wind_m_s.z as f32),
                    diameter_m: s.diameter_m as f32,
                    id: [voxel[0], voxel[1], voxel[2], bin as i64, k as i64],
                });
            }
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rain::drops::drops_in_view;
    use glam::Mat3;

    #[test]
    fn billboards_hold_as_many_drops_as_the_reference_and_face_the_camera() {
        let r = RainRegion::new(20.0, &[1.0, 1.5, 2.0], 4.0, [0.0; 3], 0.3, 2).unwrap();
        let cam = Camera::new(120, 80, [90.0, 90.0, 60.0, 40.0], Vec3::new(0.3, 1.6, 0.2), Mat3::IDENTITY).unwrap();
        let b = billboards_in_view(&r, &cam, 1.0 / 30.0, 0.0, true);
        let d = drops_in_view(&r, &cam, 1.0 / 30.0, 0.0, true);
        // Over the voxels both draw (billboards keep a few more at the frustum's edge: their
        // streaks reach below the voxel).
        let voxel = |x: &Drop| [x.id[0], x.id[1], x.id[2]];
        let drawn: std::collections::HashSet<[i64; 3]> = d.iter().map(voxel).collect();
        let shared = b.iter().filter(|x| drawn.contains(&voxel(x))).count();
        assert!(shared <= b.len() && b.len() < 2 * shared);
        let ratio = shared as f64 / d.len() as f64;
        assert!((ratio - 1.0).abs() < 0.1, "{shared} billboard drops vs {} drops", d.len());
        // every billboard drop lies on its voxel's plane through the centre, facing the camera
        for drop in b.iter().take(500) {
            let c = Vec3::new(drop.id[0] as f32 + 0.5, drop.id[1] as f32 + 0.5, drop.id[2] as f32 + 0.5);
            let n = Vec3::new(cam.position_m.x - c.x, 0.0, cam.position_m.z - c.z).normalize();
            assert!((drop.position_m - c).dot(n).abs() < 1e-4);
        }
    }
}
