//! The passes' uniform blocks as `#[repr(C)]` Pod structs, each mirroring its WGSL struct
//! field for field (vec4-sized fields: no implicit padding on either side).

use bytemuck::{Pod, Zeroable};
use skyfall_core::scene::camera::Camera;

/// `Camera` in `shaders/common.wgsl`: the world_from_camera axes, the position (f32: the box
/// scene's ray origin; particles arrive already projected), intrinsics and frame size.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Default, Pod, Zeroable)]
pub struct CameraUniform {
    /// Right axis (xyz).
    pub right: [f32; 4],
    /// Up axis (xyz).
    pub up: [f32; 4],
    /// Back axis (xyz): the camera looks along −back.
    pub back: [f32; 4],
    /// Position, m (xyz).
    pub pos: [f32; 4],
    /// fx, fy, cx, cy, px.
    pub intr: [f32; 4],
    /// Width, height, px.
    pub size: [u32; 4],
}

impl CameraUniform {
    /// The block of `cam`.
    pub fn new(cam: &Camera) -> Self {
        let v = |a: glam::Vec3| [a.x, a.y, a.z, 0.0];
        CameraUniform {
            right: v(cam.rotation.x_axis),
            up: v(cam.rotation.y_axis),
            back: v(cam.rotation.z_axis),
            pos: v(cam.eye()),
            intr: [cam.fx, cam.fy, cam.cx, cam.cy],
            size: [cam.width, cam.height, 0, 0],
        }
    }
}

/// `Haze` in `shaders/haze.wgsl`.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Default, Pod, Zeroable)]
pub struct HazeUniform {
    /// Extinction σ, 1/m (x); the cloud base's height above the eye, m (y, may be ∞).
    pub params: [f32; 4],
    /// Airlight, linear RGB.
    pub airlight: [f32; 4],
    /// The drawn shares ([`skyfall_core::haze::Drawn`]): the rain's radius, m, and share,
    /// 1/m, then the snow's.
    pub drawn: [f32; 4],
}

/// `RainParams` in `shaders/rain.wgsl`.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Default, Pod, Zeroable)]
pub struct RainUniform {
    /// Streaks in the list (each carries its own r).
    pub streak_count: u32,
    /// Tiles per row.
    pub tiles_x: u32,
    /// Tile width, px.
    pub tile_w: u32,
    /// Tile height, px.
    pub tile_h: u32,
    /// Bit 0: the depth layer (`rain_depth_m`) is drawn; bit 2: the far pass drew the rain's
    /// far shells into the rain's coverage plane and the depth, which the streaks continue.
    pub layers: u32,
    /// Bit k: particle layer k's nearest visible particle is the depth layer's.
    pub depth_layers: u32,
    /// Bit k: particle layer k's coverage plane is drawn (the frame keeps its layer).
    pub planes: u32,
    /// Padding to 16 bytes.
    pub pad: u32,
}

/// `SceneInfo` in `shaders/scene_raycast.wgsl`.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Default, Pod, Zeroable)]
pub struct SceneUniform {
    /// Ground albedo (rgb).
    pub ground_albedo: [f32; 4],
    /// Number of boxes, ground (0/1).
    pub counts: [u32; 4],
}

/// `SnowInfo` in `shaders/scene_raycast.wgsl`: the snow cover's grid.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Default, Pod, Zeroable)]
pub struct SnowUniform {
    /// Origin x, origin z (m), cell side (m), depth on open ground (m).
    pub grid: [f32; 4],
    /// Lowest base and highest top of the cells with snow (m), albedo, depth of whole coverage (m).
    pub range: [f32; 4],
    /// Cells along x and z.
    pub dims: [u32; 4],
    /// The relief noise's quantiles (the snow's patches, `skyfall_core::snow::cover::look`).
    pub relief: [[f32; 4]; 9],
}

/// `SceneBox` in `shaders/common.wgsl` (a storage array's element).
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Default, Pod, Zeroable)]
pub struct BoxElement {
    /// Lower corner, m.
    pub min_m: [f32; 4],
    /// Upper corner, m.
    pub max_m: [f32; 4],
    /// Albedo.
    pub albedo: [f32; 4],
}

impl BoxElement {
    /// The elements of `boxes`, or one zeroed element when there are none (a binding may not
    /// be empty; the shader's count of 0 keeps it unread).
    pub fn list(boxes: &[skyfall_core::scene::boxes::SceneBox]) -> Vec<Self> {
        let v = |a: glam::Vec3| [a.x, a.y, a.z, 0.0];
        let mut out: Vec<Self> = boxes
            .iter()
            .map(|b| BoxElement {
                min_m: v(b.min_m),
                max_m: v(b.max_m),
                albedo: v(b.albedo),
            })
            .collect();
        if out.is_empty() {
            out.push(BoxElement::default());
        }
        out
    }
}

/// `SkyInfo` in `shaders/scene_raycast.wgsl`.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Default, Pod, Zeroable)]
pub struct SkyUniform {
    /// CIE a, b, c, d.
    pub abcd: [f32; 4],
    /// CIE e, scale (π / normalisation), kind (0 overcast, 1 general).
    pub e_scale: [f32; 4],
    /// Unit vector towards the sun.
    pub sun: [f32; 4],
    /// The sky light's colour (xyz: `Sky::light_colour`) and whether the sky has a colour (w).
    pub colour: [f32; 4],
    /// Towards the sun as the colour model takes it (its elevation clamped to [0°, 90°]).
    pub colour_sun: [f32; 4],
    /// The colour model (`skyfall_core::sky::colour::SkyColour`): its 27 parameters, its 3
    /// radiance scales, its saturation, 0.
    pub model: [[f32; 4]; 8],
}

/// `AmbientInfo` in `shaders/scene_raycast.wgsl`.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Default, Pod, Zeroable)]
pub struct AmbientUniform {
    /// Node (0, 0, 0), m, and the spacing, m.
    pub origin_spacing: [f32; 4],
    /// Nodes along x, y, z.
    pub dims: [u32; 4],
}

/// `LampInfo` in `shaders/scene_raycast.wgsl`.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Default, Pod, Zeroable)]
pub struct LampUniform {
    /// 1/E (1/lux), the shadow-skip bound.
    pub params: [f32; 4],
    /// Number of lights.
    pub counts: [u32; 4],
}

/// `LightElement` in `shaders/scene_raycast.wgsl` (a storage array's element).
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Default, Pod, Zeroable)]
pub struct LightElement {
    /// Position, m; intensity, cd.
    pub pos_cd: [f32; 4],
    /// Linear RGB; 1 for a spot.
    pub color_spot: [f32; 4],
    /// The spot's unit axis; cos of its outer half-angle.
    pub axis_outer: [f32; 4],
    /// cos of its inner half-angle.
    pub inner: [f32; 4],
}

impl LightElement {
    /// The elements of `lights`, or one zeroed element when there are none (see
    /// [`BoxElement::list`]).
    pub fn list(lights: &[skyfall_core::scene::lights::Light]) -> Vec<Self> {
        let mut out: Vec<Self> = lights.iter().map(LightElement::new).collect();
        if out.is_empty() {
            out.push(LightElement::default());
        }
        out
    }

    /// The element of `l`.
    pub fn new(l: &skyfall_core::scene::lights::Light) -> Self {
        let p = l.position_m;
        let c = l.color;
        let (axis, outer, inner, spot) = match l.spot {
            Some((a, o, i)) => (a, o, i, 1.0),
            None => (glam::Vec3::ZERO, 0.0, 0.0, 0.0),
        };
        LightElement {
            pos_cd: [p.x, p.y, p.z, l.intensity_cd],
            color_spot: [c.x, c.y, c.z, spot],
            axis_outer: [axis.x, axis.y, axis.z, outer],
            inner: [inner, 0.0, 0.0, 0.0],
        }
    }
}

/// `GlowInfo` in `shaders/glow.wgsl`.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Default, Pod, Zeroable)]
pub struct GlowUniform {
    /// The angular size of a pixel, rad.
    pub params: [f32; 4],
    /// Number of sources.
    pub counts: [u32; 4],
}

/// `GlowSource` in `shaders/glow.wgsl` (a storage array's element).
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Default, Pod, Zeroable)]
pub struct GlowElement {
    /// Unit direction from the eye; the cut chord.
    pub dir_cut: [f32; 4],
    /// The light at the camera, relative × sr; the disc's angular radius, rad.
    pub flux_radius: [f32; 4],
    /// The disc's radiance, relative.
    pub disc: [f32; 4],
    /// The orders' weights (first four).
    pub weights_a: [f32; 4],
    /// The orders' weights (last two).
    pub weights_b: [f32; 4],
    /// The orders' asymmetries (first four).
    pub asym_a: [f32; 4],
    /// The orders' asymmetries (last two).
    pub asym_b: [f32; 4],
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_block_is_whole_vec4s() {
        // WGSL uniform structs of vec4 fields have 16-byte strides: the Rust side must match.
        for size in [
            size_of::<CameraUniform>(),
            size_of::<HazeUniform>(),
            size_of::<RainUniform>(),
            size_of::<SceneUniform>(),
            size_of::<BoxElement>(),
            size_of::<SkyUniform>(),
            size_of::<AmbientUniform>(),
            size_of::<LampUniform>(),
            size_of::<LightElement>(),
            size_of::<GlowUniform>(),
            size_of::<GlowElement>(),
        ] {
            assert_eq!(size % 16, 0, "{size}");
        }
        assert_eq!(size_of::<CameraUniform>(), 96);
    }
}

/// A volume's box relative to the camera (`VolumeBox` in `shaders/scene_raycast.wgsl` and
/// `shaders/cloud.wgsl`): skyfall_core::cloud::frame::VolumeView.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Default, Pod, Zeroable)]
pub struct VolumeUniform {
    /// The corner relative to the camera, m (xyz); resolution R (w, as f32).
    pub origin: [f32; 4],
    /// Each edge over its squared length, 1/m (xyz); the first's w holds, as u32 bits, where
    /// the volume starts in its storage buffer.
    pub axes: [[f32; 4]; 3],
}

impl VolumeUniform {
    /// The block of a volume view starting at `offset` values into its buffer (zeros without
    /// one).
    pub fn new(v: Option<&skyfall_core::cloud::frame::VolumeView<'_>>, offset: u32) -> Self {
        match v {
            Some(v) => {
                let a = |x: glam::Vec3, w: f32| [x.x, x.y, x.z, w];
                let o = v.origin_rel;
                VolumeUniform {
                    origin: [o.x, o.y, o.z, v.resolution as f32],
                    axes: [
                        a(v.axes[0], f32::from_bits(offset)),
                        a(v.axes[1], 0.0),
                        a(v.axes[2], 0.0),
                    ],
                }
            }
            None => VolumeUniform::default(),
        }
    }
}

/// `SunInfo` in `shaders/scene_raycast.wgsl`: the sun's direct light on the surfaces.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Default, Pod, Zeroable)]
pub struct SunUniform {
    /// Towards the sun (xyz), its normal illuminance over E (w).
    pub dir: [f32; 4],
    /// Sun on (x), clouds' volume present (y), sun_transmittance written (z).
    pub flags: [u32; 4],
    /// The clouds' Γ for the sun.
    pub volume: VolumeUniform,
    /// The colour of its light (xyz, luminance 1).
    pub colour: [f32; 4],
}

/// `WetInfo` in `shaders/wet_film.wgsl`: the film of a box scene's wet stage
/// (`skyfall_core::wet::stage::WetGpu`).
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Default, Pod, Zeroable)]
pub struct WetUniform {
    /// The quartile drops' directions of fall (xyz).
    pub dirs: [[f32; 4]; 3],
    /// Water per unit exposure, mm (x; < 0: the storage, filled), dried, mm (y).
    pub film: [f32; 4],
    /// Lekner & Dorf's (1 − R̄)(1 − p) (x) and p (y).
    pub optics: [f32; 4],
    /// Boxes that shelter (x), wetness written (y), puddle_mask written (z), a snow cover (w).
    pub flags: [u32; 4],
    /// The relief noise's quantiles (`skyfall_core::wet::puddles::relief_quantiles`), 33 of 36.
    pub relief: [[f32; 4]; 9],
}

impl WetUniform {
    /// The uniform of `wet` with `shelter` boxes that keep the rain off, which of its layers
    /// are written and whether the frame has a snow cover (whose covered pixels are not wet).
    pub fn new(
        wet: &skyfall_core::wet::stage::WetGpu,
        shelter: usize,
        wetness: bool,
        puddles: bool,
        snow: bool,
    ) -> Self {
        let d = |v: glam::Vec3| [v.x, v.y, v.z, 0.0];
        WetUniform {
            dirs: wet.directions.map(d),
            film: [wet.mm_per_exposure.unwrap_or(-1.0), wet.dried_mm, 0.0, 0.0],
            optics: [wet.darkening_numerator, wet.internal_reflectance, 0.0, 0.0],
            flags: [
                if wet.sheltered { shelter as u32 } else { 0 },
                u32::from(wetness),
                u32::from(puddles),
                u32::from(snow),
            ],
            relief: relief_quantiles(),
        }
    }
}

/// The relief noise's quantiles, four to an element (`WetInfo.relief`, `WetPhotoInfo.relief`).
pub fn relief_quantiles() -> [[f32; 4]; 9] {
    let mut relief = [[0.0f32; 4]; 9];
    for (k, q) in skyfall_core::wet::puddles::relief_quantiles()
        .iter()
        .enumerate()
    {
        relief[k / 4][k % 4] = *q;
    }
    relief
}

/// `WetPhotoInfo` in `shaders/wet_photo.wgsl`: a photo's wet stage.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Default, Pod, Zeroable)]
pub struct WetPhotoUniform {
    /// The quartile drops' directions of fall (xyz).
    pub dirs: [[f32; 4]; 3],
    /// Water per unit exposure, mm (x; < 0: the storage, filled), dried, mm (y).
    pub film: [f32; 4],
    /// Lekner & Dorf's (1 − R̄)(1 − p) (x), p (y), 1/E (z).
    pub optics: [f32; 4],
    /// The photo's mean sky (xyz).
    pub sky: [f32; 4],
    /// Sheltering occluders (x), lights (y), snow depth bound (z), wetness written (w).
    pub counts: [u32; 4],
    /// puddle_mask written (x).
    pub flags: [u32; 4],
    /// The relief noise's quantiles (`skyfall_core::wet::puddles::relief_quantiles`), 33 of 36.
    pub relief: [[f32; 4]; 9],
}

/// `CloudInfo` in `shaders/cloud.wgsl`.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Default, Pod, Zeroable)]
pub struct CloudUniform {
    /// Tiles across (x), tile side px (y), sun present (z), cloud_alpha written (w).
    pub counts: [u32; 4],
    /// Towards the sun (xyz), Henyey–Greenstein g (w).
    pub sun_g: [f32; 4],
    /// The sun's normal illuminance over E per channel (xyz); the diffuse light on (w = 1).
    pub sun_light: [f32; 4],
    /// The open sky's light per channel (xyz); the splats' farthest reach from their centres,
    /// m (w: `CloudSplats::reach_m`).
    pub sky_light: [f32; 4],
    /// The sun's Γ.
    pub sun_volume: VolumeUniform,
    /// The zenith's Γ.
    pub zenith_volume: VolumeUniform,
}
