//! The camera as a uniform block shared by the passes (see `Camera` in the WGSL files).

use skyfall_core::scene::camera::Camera;

/// 6 × vec4: right, up, back, position (xyz), intrinsics (fx, fy, cx, cy), size (w, h as u32).
pub const CAMERA_WORDS: usize = 24;

/// Packs a camera into 32-bit words in the shaders' layout.
pub fn camera_words(cam: &Camera) -> [u32; CAMERA_WORDS] {
    let mut w = [0u32; CAMERA_WORDS];
    let cols = [
        cam.rotation.x_axis,
        cam.rotation.y_axis,
        cam.rotation.z_axis,
        cam.eye(),
    ];
    for (i, c) in cols.iter().enumerate() {
        for k in 0..3 {
            w[4 * i + k] = c[k].to_bits();
        }
    }
    for (k, v) in [cam.fx, cam.fy, cam.cx, cam.cy].iter().enumerate() {
        w[16 + k] = v.to_bits();
    }
    w[20] = cam.width;
    w[21] = cam.height;
    w
}
