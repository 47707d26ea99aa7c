//! Pinhole camera with intrinsics (fx, fy, cx, cy) in pixels, and the thin lens that can stand
//! in its pinhole ([`ThinLens`]): a point off the plane in focus is imaged as a blur circle.

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

/// The largest blur circle a streak is widened by, as a share of the frame's larger side
/// (see [`Defocus`]): 1/16, 40 px at 640 × 360.
pub const MAX_BLUR_FRACTION: f32 = 1.0 / 16.0;

/// A thin lens in place of the camera's pinhole: its f-number, the distance in focus and the
/// sensor's width, which with the camera's focal length in pixels gives the focal length in
/// metres (f = f_px · sensor width / frame width) and so the aperture A = f / N.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ThinLens {
    /// N = f / A.
    pub f_number: f64,
    /// s, m along the optical axis (inf: focused at infinity).
    pub focus_distance_m: f64,
    /// The sensor's width, mm (36: full frame).
    pub sensor_width_mm: f64,
}

/// A thin lens at one camera's resolution: the blur circle's diameter on screen, px, of a point
/// at depth z is c(z) = k · |1/z − 1/s|, the thin-lens circle of confusion
/// A·f·|z − s| / (z·(s − f)) over the pixel pitch, so k = A·f·s / ((s − f)·pitch) (A·f / pitch
/// focused at infinity); capped at [`MAX_BLUR_FRACTION`] of the frame's larger side.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Defocus {
    /// k, px·m.
    pub scale_px_m: f32,
    /// 1/s, 1/m.
    pub inv_focus_per_m: f32,
    /// The cap on c, px.
    pub max_px: f32,
}

impl ThinLens {
    /// A validated lens (each value within its range, see [`crate::ranges`]).
    pub fn new(f_number: f64, focus_distance_m: f64, sensor_width_mm: f64) -> Result<Self> {
        crate::ranges::F_NUMBER.check(f_number)?;
        crate::ranges::FOCUS_DISTANCE_M.check(focus_distance_m)?;
        crate::ranges::SENSOR_WIDTH_MM.check(sensor_width_mm)?;
        Ok(ThinLens {
            f_number,
            focus_distance_m,
            sensor_width_mm,
        })
    }

    /// The pixel pitch of `cam`'s sensor, m.
    pub fn pixel_pitch_m(&self, cam: &Camera) -> f64 {
        self.sensor_width_mm * 1e-3 / f64::from(cam.width)
    }

    /// The focal length, m, of `cam` (its mean focal length in pixels, as the streaks use,
    /// times the pixel pitch).
    pub fn focal_length_m(&self, cam: &Camera) -> f64 {
        0.5 * (f64::from(cam.fx) + f64::from(cam.fy)) * self.pixel_pitch_m(cam)
    }

    /// The blur circle's diameter on the sensor, m, of a point at depth `z_m`:
    /// A·f·|z − s| / (z·(s − f)), A = f / N (A·f / z focused at infinity).
    pub fn blur_diameter_m(&self, cam: &Camera, z_m: f64) -> f64 {
        let f = self.focal_length_m(cam);
        let a = f / self.f_number;
        let s = self.focus_distance_m;
        if s.is_infinite() {
            a * f / z_m
        } else {
            a * f * (z_m - s).abs() / (z_m * (s - f))
        }
    }

    /// The lens at `cam`'s resolution; refused when the distance in focus is not beyond the
    /// focal length (nothing would be in focus on the sensor).
    pub fn defocus(&self, cam: &Camera) -> Result<Defocus> {
        let f = self.focal_length_m(cam);
        let s = self.focus_distance_m;
        if s <= f {
            return Err(Error::Unusable {
                param: Param {
                    name: "focus_distance_m",
                    index: None,
                },
                value: s,
                message: format!(
                    "is not beyond the lens's focal length {f:.4} m (its f_px · sensor_width_mm / width)"
                ),
            });
        }
        let a = f / self.f_number;
        let pitch = self.pixel_pitch_m(cam);
        let scale = if s.is_infinite() {
            a * f / pitch
        } else {
            a * f * s / ((s - f) * pitch)
        };
        let side = cam.width.max(cam.height) as f32;
        Ok(Defocus {
            scale_px_m: scale as f32,
            inv_focus_per_m: (1.0 / s) as f32,
            max_px: (MAX_BLUR_FRACTION * side).max(1.0),
        })
    }
}

impl Defocus {
    /// The blur circle's diameter, px, at inverse depth `inv_z` (1/m), capped.
    #[inline]
    pub fn blur_px(&self, inv_z: f32) -> f32 {
        (self.scale_px_m * (inv_z - self.inv_focus_per_m).abs()).min(self.max_px)
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
    fn blur_circles_are_the_thin_lens_formula() {
        // 50 mm f/2 on a full-frame sensor 1000 px wide (pitch 36 µm, f_px = 50/0.036), focused
        // at 4 m: c = A·f·|z − s| / (z·(s − f)) written out here in millimetres.
        let f_px = 50.0 / 0.036;
        let cam = Camera::new(
            1000,
            600,
            [f_px, f_px, 500.0, 300.0],
            Vec3::ZERO,
            Mat3::IDENTITY,
        )
        .unwrap_or_else(|_| unreachable_cam());
        let lens = ThinLens::new(2.0, 4.0, 36.0).unwrap_or_else(|_| unreachable!());
        assert!((lens.focal_length_m(&cam) - 0.05).abs() < 1e-9);
        let d = lens.defocus(&cam).unwrap_or_else(|_| unreachable!());
        for z_m in [0.3f64, 1.0, 2.5, 4.0, 10.0, 100.0] {
            let (a_mm, f_mm, s_mm, z_mm) = (25.0, 50.0, 4000.0, z_m * 1e3);
            let c_mm = a_mm * f_mm * (z_mm - s_mm).abs() / (z_mm * (s_mm - f_mm));
            // (f_px is an f32: the focal length is 0.05 m to 1e-7)
            assert!((lens.blur_diameter_m(&cam, z_m) * 1e3 - c_mm).abs() < 1e-6 * c_mm.max(1e-3));
            let want_px = (c_mm / 0.036).min(1000.0 / 16.0);
            let got = f64::from(d.blur_px((1.0 / z_m) as f32));
            assert!(
                (got - want_px).abs() < 1e-4 * want_px.max(1.0),
                "{z_m}: {got} vs {want_px}"
            );
        }
        // in focus: none; near the lens: the cap
        assert!(d.blur_px(0.25) < 1e-6 && d.blur_px(20.0) == d.max_px);
        // at infinity: A·f / z
        let inf = ThinLens::new(2.0, f64::INFINITY, 36.0).unwrap_or_else(|_| unreachable!());
        assert!((inf.blur_diameter_m(&cam, 2.0) / (0.025 * 0.05 / 2.0) - 1.0).abs() < 1e-6);
        let di = inf.defocus(&cam).unwrap_or_else(|_| unreachable!());
        assert!((di.blur_px(0.5) - (0.025 * 0.05 / 2.0 / 36e-6) as f32).abs() < 1e-3);
        // focus within the focal length, or out of range: refused naming the parameter
        let near = ThinLens::new(2.0, 0.04, 36.0).unwrap_or_else(|_| unreachable!());
        assert!(
            near.defocus(&cam)
                .unwrap_err()
                .to_string()
                .starts_with("focus_distance_m")
        );
        assert!(ThinLens::new(0.1, 4.0, 36.0).is_err() && ThinLens::new(2.0, 0.0, 36.0).is_err());
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
