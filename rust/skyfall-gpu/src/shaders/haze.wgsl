// Rain haze along view rays. CPU reference: skyfall_core::haze. Prepended with common.wgsl.

struct Haze {
    params: vec4<f32>,   // extinction (1/m), unused x3
    airlight: vec4<f32>, // linear RGB
}

@group(0) @binding(0) var<uniform> cam: Camera;
@group(0) @binding(1) var<uniform> haze: Haze;
@group(0) @binding(2) var<storage, read_write> rgb: array<f32>;
@group(0) @binding(3) var<storage, read> depth: array<f32>;
@group(0) @binding(4) var<storage, read_write> transmittance: array<f32>;

// Transmittance along the ray of a pixel at depth `depth_m` (inf: sky).
fn haze_transmittance(depth_m: f32, per_depth: f32) -> f32 {
    let sigma = haze.params.x;
    if sigma <= 0.0 {
        return 1.0;
    }
    if depth_m > 3.0e38 {
        return 0.0;
    }
    return exp(-sigma * (depth_m * per_depth));
}

@compute @workgroup_size(8, 8)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let w = cam.size.x;
    if gid.x >= w || gid.y >= cam.size.y {
        return;
    }
    let i = gid.y * w + gid.x;
    let t = haze_transmittance(depth[i], distance_per_depth(cam, gid.x, gid.y));
    transmittance[i] = t;
    for (var k = 0u; k < 3u; k++) {
        rgb[3u * i + k] = rgb[3u * i + k] * t + haze.airlight[k] * (1.0 - t);
    }
}
