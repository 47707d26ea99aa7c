// Rain haze along view rays. CPU reference: skyfall_core::haze. Prepended with common.wgsl.

struct Haze {
    params: vec4<f32>,   // extinction (1/m), cloud base above the eye (m, may be inf), the red's
                         // and the blue's extinction beyond it (1/m; 0: a grey haze)
    airlight: vec4<f32>, // linear RGB
    drawn: vec4<f32>,    // the rain's radius (m) and drawn share (1/m), the snow's
}

@group(0) @binding(0) var<uniform> cam: Camera;
@group(0) @binding(1) var<uniform> haze: Haze;
@group(0) @binding(2) var<storage, read_write> rgb: array<f32>;
@group(0) @binding(3) var<storage, read> depth: array<f32>;
@group(0) @binding(4) var<storage, read_write> transmittance: array<f32>;

// The path from the eye to a cloud base `ceiling` m above it, on the Earth's sphere, along a ray
// of elevation sin `s` (skyfall_core::haze::path_to_ceiling_m).
fn path_to_ceiling(s_in: f32, ceiling: f32) -> f32 {
    let r = 6.371e6;
    let s = clamp(s_in, -1.0, 1.0);
    let k = ceiling * (2.0 * r + ceiling);
    let root = sqrt(k + (r * s) * (r * s));
    if s >= 0.0 {
        return k / (root + r * s);
    }
    return root - r * s;
}

// Transmittances (red, green, blue) along the ray of a pixel at depth `depth_m`, whose ray has
// length `per_depth` and world-y component `rise` per metre of depth. A sky pixel (depth inf) is
// hazed up to the cloud base, `params.y` above the eye (skyfall_core::haze::Haze::
// transmittance_row), one transmittance for its three channels; a surface's red and blue
// channels see `params.z` and `params.w` more extinction (skyfall_core::haze::apply_row).
fn haze_transmittance(depth_m: f32, per_depth: f32, rise: f32) -> vec3<f32> {
    let sigma = haze.params.x;
    if sigma <= 0.0 {
        return vec3<f32>(1.0);
    }
    var path = depth_m * per_depth;
    let sky = depth_m > 3.0e38;
    if sky {
        if haze.params.y > 3.0e38 {
            return vec3<f32>(0.0);
        }
        path = path_to_ceiling(rise / per_depth, haze.params.y);
    }
    // The particles drawn near the eye carry their share of σ there
    // (skyfall_core::haze::Haze::optical_depth).
    let drawn = haze.drawn.y * min(path, haze.drawn.x) + haze.drawn.w * min(path, haze.drawn.z);
    let tau = max(sigma * path - drawn, 0.0);
    if sky {
        // (the sky model's colour holds what the air along its path scatters)
        return vec3<f32>(exp(-tau));
    }
    return exp(-max(vec3<f32>(tau + haze.params.z * path, tau, tau + haze.params.w * path), vec3<f32>(0.0)));
}

@compute @workgroup_size(8, 8)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let w = cam.size.x;
    if gid.x >= w || gid.y >= cam.size.y {
        return;
    }
    let i = gid.y * w + gid.x;
    let rise = ray_direction(cam, gid.x, gid.y).y;
    let t = haze_transmittance(depth[i], distance_per_depth(cam, gid.x, gid.y), rise);
    transmittance[i] = t.y;
    for (var k = 0u; k < 3u; k++) {
        rgb[3u * i + k] = rgb[3u * i + k] * t[k] + haze.airlight[k] * (1.0 - t[k]);
    }
}
