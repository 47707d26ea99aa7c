//! Pinhole camera with intrinsics (fx, fy, cx, cy) in pixels.

use crate::error::{Error, Param, Range, Result};
use glam::{DVec3, Mat3, Vec3};

/// Valid frame sides, pixels.
pub const SIDE_PX: Range = crate::ranges::SIDE_PX;

/// A pinhole camera: pose and intrinsics.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Camera {
    /// Frame width, px.
    pub width: u32,
    /// Frame height, px.
    pub height: u32,
    /// Focal lengths, px.
    pub fx: f32,
    /// Focal length along y, px.
    pub fy: f32,
    /// Principal point x, px from the left edge.
    pub cx: f32,
    /// Principal point y, px from the top edge.
    pub cy: f32,
    /// Camera position in the world, m, in f64: far from the world's origin (UTM-sized
    /// scenes) an f32 position snaps to a coarse grid (0.5 m at 5e6 m), so particles are made
    /// and drawn relative to it (see [`crate::particles::voxels`]).
    pub position_m: DVec3,
    /// Rotation `world_from_camera`: columns are the camera's right, up and back axes.
    pub rotation: Mat3,
}

impl Camera {
    /// Validated camera. `rotation` must be orthonormal (checked to 1e-3).
    pub fn new(
        width: u32,
        height: u32,
        intrinsics: [f32; 4],
        position_m: impl Into<DVec3>,
        rotation: Mat3,
    ) -> Result<Self> {
        let position_m: DVec3 = position_m.into();
        SIDE_PX.check("width", None, f64::from(width))?;
        SIDE_PX.check("height", None, f64::from(height))?;
        let [fx, fy, cx, cy] = intrinsics;
        let positive = crate::ranges::FOCAL_PX;
        positive.check("fx", None, f64::from(fx))?;
        positive.check("fy", None, f64::from(fy))?;
        let finite = crate::ranges::PRINCIPAL_PX;
        finite.check("cx", None, f64::from(cx))?;
        finite.check("cy", None, f64::from(cy))?;
        let world = crate::ranges::POSITION_M.range;
        for (i, v) in position_m.to_array().into_iter().enumerate() {
            world.check("position_m", Some(i), v)?;
        }
        let gram = rotation.transpose() * rotation;
        let off = (gram - Mat3::IDENTITY)
            .to_cols_array()
            .iter()
            .fold(0.0f32, |m, v| m.max(v.abs()));
        if off.is_nan() || off > 1e-3 || rotation.determinant() < 0.0 {
            return Err(Error::Invalid {
                param: Param {
                    name: "rotation",
                    index: None,
                },
                message: "world_from_camera rotation must be orthonormal and right-handed".into(),
            });
        }
        Ok(Camera {
            width,
            height,
            fx,
            fy,
            cx,
            cy,
            position_m,
            rotation,
        })
    }

    /// The position in f32, for world-space work that needs no more (ray casting the box
    /// scene, lights, the ambient-light map).
    #[inline]
    pub fn eye(&self) -> Vec3 {
        self.position_m.as_vec3()
    }

    /// World-space ray direction through the centre of pixel (x, y), scaled so that its
    /// camera-space z is −1: the point at parameter t lies t metres along the optical axis.
    #[inline]
    pub fn ray_direction(&self, x: u32, y: u32) -> Vec3 {
        let dc = Vec3::new(
            (x as f32 + 0.5 - self.cx) / self.fx,
            -((y as f32 + 0.5 - self.cy) / self.fy),
            -1.0,
        );
        self.rotation * dc
    }

    /// Distance along the view ray per metre of depth, for pixel (x, y): |ray_direction|.
    #[inline]
    pub fn distance_per_depth(&self, x: u32, y: u32) -> f32 {
        let u = (x as f32 + 0.5 - self.cx) / self.fx;
        let v = (y as f32 + 0.5 - self.cy) / self.fy;
        (u * u + v * v + 1.0).sqrt()
    }

    /// Squared horizontal ray slopes ((x + 0.5 − cx) / fx)² of every column, so a frame can
    /// compute [`Camera::distance_per_depth`] as `√(u²[x] + v² + 1)` without divisions.
    pub fn column_slopes_sq(&self) -> Vec<f32> {
        (0..self.width)
            .map(|x| {
                let u = (x as f32 + 0.5 - self.cx) / self.fx;
                u * u
            })
            .collect()
    }

    /// Squared vertical ray slope of row `y`.
    #[inline]
    pub fn row_slope_sq(&self, y: u32) -> f32 {
        let v = (y as f32 + 0.5 - self.cy) / self.fy;
        v * v
    }

    /// Solid angle of a view pyramid that holds the frame, sr: 4·asin(sin α·sin β) with α, β
    /// the half-angles to the frame's farther side and edge (≥ the frame's own, when the
    /// principal point is off centre).
    pub fn view_solid_angle_sr(&self) -> f64 {
        let half = |c: f32, side: u32, f: f32| {
            (f64::from(c.abs().max((side as f32 - c).abs())) / f64::from(f)).atan()
        };
        let (a, b) = (
            half(self.cx, self.width, self.fx),
            half(self.cy, self.height, self.fy),
        );
        4.0 * (a.sin() * b.sin()).min(1.0).asin()
    }

    /// Pixel count.
    pub fn pixels(&self) -> usize {
        self.width as usize * self.height as usize
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn principal_ray_is_the_optical_axis() {
        let cam = Camera::new(4, 2, [2.0, 2.0, 2.0, 1.0], Vec3::ZERO, Mat3::IDENTITY);
        let cam = cam.unwrap_or_else(|_| unreachable_cam());
        // pixel (1, 0) centre is at (1.5, 0.5): half a pixel left and up of (2, 1).
        let d = cam.ray_direction(1, 0);
        assert!((d - Vec3::new(-0.25, 0.25, -1.0)).length() < 1e-6);
        assert!((cam.distance_per_depth(1, 0) - d.length()).abs() < 1e-6);
    }

    #[test]
    fn view_solid_angle_is_the_pyramids() {
        // 90° × 90°: 4·asin(sin 45°·sin 45°) = 2π/3; an off-centre principal point widens the
        // pyramid to its farther side
        let c = Camera::new(
            100,
            100,
            [50.0, 50.0, 50.0, 50.0],
            Vec3::ZERO,
            Mat3::IDENTITY,
        )
        .unwrap_or_else(|_| unreachable_cam());
        assert!((c.view_solid_angle_sr() - 2.0 * std::f64::consts::PI / 3.0).abs() < 1e-9);
        let off = Camera::new(
            100,
            100,
            [50.0, 50.0, 0.0, 50.0],
            Vec3::ZERO,
            Mat3::IDENTITY,
        )
        .unwrap_or_else(|_| unreachable_cam());
        assert!(off.view_solid_angle_sr() > c.view_solid_angle_sr());
    }

    fn unreachable_cam() -> Camera {
        Camera {
            width: 1,
            height: 1,
            fx: 1.0,
            fy: 1.0,
            cx: 0.0,
            cy: 0.0,
            position_m: glam::DVec3::ZERO,
            rotation: Mat3::IDENTITY,
        }
    }

    #[test]
    fn rejects_bad_rotation_and_sizes() {
        assert!(
            Camera::new(
                4,
                4,
                [1.0; 4],
                Vec3::ZERO,
                Mat3::from_diagonal(Vec3::new(1.0, 1.0, -1.0))
            )
            .is_err()
        );
        assert!(Camera::new(0, 4, [1.0; 4], Vec3::ZERO, Mat3::IDENTITY).is_err());
        assert!(Camera::new(4, 4, [f32::NAN, 1.0, 1.0, 1.0], Vec3::ZERO, Mat3::IDENTITY).is_err());
    }
}
