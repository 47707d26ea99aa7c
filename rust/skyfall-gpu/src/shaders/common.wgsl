// Shared by every pass: the camera block and its rays (see skyfall_core::scene::camera).
struct Camera {
    right: vec4<f32>,
    up: vec4<f32>,
    back: vec4<f32>,
    pos: vec4<f32>,
    intr: vec4<f32>,   // fx, fy, cx, cy (px)
    size: vec4<u32>,   // width, height
}

fn pixel_uv(cam: Camera, x: u32, y: u32) -> vec2<f32> {
    return vec2<f32>((f32(x) + 0.5 - cam.intr.z) / cam.intr.x, (f32(y) + 0.5 - cam.intr.w) / cam.intr.y);
}

// World ray through the pixel centre, camera-space z = -1: the point at t is t metres deep.
fn ray_direction(cam: Camera, x: u32, y: u32) -> vec3<f32> {
    let uv = pixel_uv(cam, x, y);
    return cam.right.xyz * uv.x + cam.up.xyz * (-uv.y) - cam.back.xyz;
}

fn distance_per_depth(cam: Camera, x: u32, y: u32) -> f32 {
    let uv = pixel_uv(cam, x, y);
    return sqrt(uv.x * uv.x + uv.y * uv.y + 1.0);
}

fn infinity() -> f32 {
    return bitcast<f32>(0x7f800000u);
}

// A light-aligned volume's box relative to the camera (skyfall_core::cloud::frame::VolumeView),
// and one axis's cell and fraction as its trilinear sampler takes them (clamped to the faces).
struct VolumeBox {
    origin: vec4<f32>,   // corner relative to the camera (m), resolution R (w)
    axes: array<vec4<f32>, 3>,   // each edge over its squared length; axes[0].w: the volume's offset in its buffer, as u32 bits
}

struct VolumeCell {
    i: u32,
    f: f32,
}

fn volume_cell(t: f32, n: u32) -> VolumeCell {
    let x = clamp(t * f32(n) - 0.5, 0.0, f32(n - 1u));
    let i = min(u32(x), n - 2u);
    return VolumeCell(i, x - f32(i));
}
