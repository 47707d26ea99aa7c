// The rain's far level of detail over the frame, per pixel: each shell's texture looked up
// where the pixel's ray meets the shell, composited far to near before the near streaks
// (rain.wgsl continues from the rain's coverage plane and the depth written here). CPU reference:
// skyfall_core::rain::far (FarRain::composite), whose lookups are exact at each 16-pixel
// segment's ends and linear between, and whose atan2 is a polynomial within 2e-5 rad.
// Prepended with common.wgsl.

struct FarParams {
    dims: vec4<u32>,   // shells K, texture side S, blocks per row, block side (px)
    misc: vec4<f32>,   // 1/delta (texels per rad), shell spacing (m), region radius (m), r
    shear: vec4<f32>,  // shear (x, z), max |tan(elevation)|, a whole turn in texels
    extra: vec4<f32>,  // the frame's rate's cross-section over the textures' (far::opacity_scale), 0, 0, 0
}

@group(0) @binding(0) var<uniform> cam: Camera;
@group(0) @binding(1) var<uniform> params: FarParams;
@group(0) @binding(2) var<storage, read> radii: array<f32>;
@group(0) @binding(3) var<storage, read> offsets: array<vec2<f32>>;
@group(0) @binding(4) var<storage, read> textures: array<f32>;
@group(0) @binding(5) var<storage, read> lights: array<vec4<f32>>;  // per block and shell; w = 0: none
@group(0) @binding(6) var<storage, read_write> rgb: array<f32>;
@group(0) @binding(7) var<storage, read> depth: array<f32>;
@group(0) @binding(8) var<storage, read_write> coverage: array<f32>;  // the particle layers' planes (rain_alpha's: LAYER_RAIN)
@group(0) @binding(9) var<storage, read_write> rain_depth: array<f32>;

@compute @workgroup_size(8, 8)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let w = cam.size.x;
    if gid.x >= w || gid.y >= cam.size.y {
        return;
    }
    let i = gid.y * w + gid.x;
    let k_n = params.dims.x;
    let size = params.dims.y;
    let mask = i32(size) - 1;
    let inv_delta = params.misc.x;
    let spacing = params.misc.y;
    let r = params.misc.w;
    // The ray, camera z = -1: its horizontal length h, tan(elevation), the shear across it.
    let ray = ray_direction(cam, gid.x, gid.y);
    let h = sqrt(max(ray.x * ray.x + ray.z * ray.z, 1e-12));
    let norm = distance_per_depth(cam, gid.x, gid.y);
    let vv = clamp(ray.y / h, -params.shear.z, params.shear.z) * inv_delta;
    let s = (params.shear.x * -ray.z + params.shear.y * ray.x) / h;
    let a = atan2(ray.x, -ray.z) * inv_delta + s * vv + params.shear.w;
    // sec(elevation) for the oblique crossing; the visible end as a horizontal distance.
    let scale = norm / h * params.extra.x;
    let end_h = min(depth[i] * h, params.misc.z * h / norm);
    let blk = ((gid.y / params.dims.w) * params.dims.z + gid.x / params.dims.w) * k_n;
    var c = vec3<f32>(rgb[3u * i], rgb[3u * i + 1u], rgb[3u * i + 2u]);
    var keep = 1.0;
    var z_min = infinity();
    for (var k = 0u; k < k_n; k++) {
        let light = lights[blk + k];
        if light.w == 0.0 {
            continue;
        }
        let wgt = clamp((end_h - (radii[k] - 0.5 * spacing)) / spacing, 0.0, 1.0);
        if wgt <= 0.0 {
            continue;
        }
        let o = offsets[k];
        // (both positive: truncation is the floor)
        let ia = i32(a + o.x) & mask;
        let ib = i32(o.y - vv) & mask;
        let t = textures[k * size * size + u32(ib) * size + u32(ia)];
        let fa = min(t * scale, 1.0) * wgt;
        c += fa * r * (light.xyz - c);
        keep *= 1.0 - fa;
        if fa > 0.0 {
            z_min = min(z_min, radii[k] / h);
        }
    }
    rgb[3u * i] = c.x;
    rgb[3u * i + 1u] = c.y;
    rgb[3u * i + 2u] = c.z;
    coverage[LAYER_RAIN * w * cam.size.y + i] = 1.0 - keep;
    rain_depth[i] = z_min;
}
