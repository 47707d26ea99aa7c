// The film of a box scene's wet stage (WetStage::box_pixel but for the highlights and the
// mirror ray's radiance), at the face the scene pass's wet_face found for each pixel: its
// wetness (the rain's exposure and the boxes' shelter), its puddle, its darkening into rgb, and
// its mirror ray for the scene pass's wet_lights and MIRROR. A module of its own: with the
// scene pass's code beside it, lavapipe's compiler (Mesa 22.3) wrote into freed memory making
// it (valgrind's memcheck). CPU reference: skyfall_core::wet::stage and wet::puddles.
// Prepended with common.wgsl.

struct WetInfo {
    dirs: array<vec4<f32>, 3>,   // the quartile drops' directions of fall
    film: vec4<f32>,             // water per unit exposure, mm (< 0: the storage, filled), dried, mm
    optics: vec4<f32>,           // Lekner & Dorf's (1 - R)(1 - p), p
    flags: vec4<u32>,            // boxes that shelter, wetness written, puddle_mask written, snow cover
    relief: array<vec4<f32>, 9>, // the relief noise's quantiles (puddles::relief_quantiles)
}

@group(0) @binding(0) var<uniform> cam: Camera;
@group(0) @binding(1) var<uniform> wet: WetInfo;
@group(0) @binding(2) var<storage, read> boxes: array<SceneBox>;
@group(0) @binding(3) var<storage, read> faces: array<vec4<f32>>;       // per pixel: (point, -), (albedo, 1 hit / -1 none), (normal, -)
@group(0) @binding(4) var<storage, read> depth: array<f32>;
@group(0) @binding(5) var<storage, read> snow_depth: array<f32>;
@group(0) @binding(6) var<storage, read_write> rgb: array<f32>;
@group(0) @binding(7) var<storage, read_write> rays: array<vec4<f32>>;  // per pixel: (point, w·F), (mirror direction, 1 puddle / 0 film / -1 none), (normal, w)
@group(0) @binding(8) var<storage, read_write> wet_out: array<f32>;
@group(0) @binding(9) var<storage, read_write> puddle_out: array<f32>;

// skyfall_core::scene::raycast::occluded_within over the boxes, for a shelter ray.
fn sheltered(p: vec3<f32>, dir: vec3<f32>) -> bool {
    let inv = vec3<f32>(1.0 / safe(dir.x), 1.0 / safe(dir.y), 1.0 / safe(dir.z));
    let q = p + dir * SHELTER_RAY_M;
    let lo_seg = min(p, q);
    let hi_seg = max(p, q);
    for (var i = 0u; i < wet.flags.x; i++) {
        if box_blocks(boxes[i], p, inv, SHELTER_RAY_M, lo_seg, hi_seg) {
            return true;
        }
    }
    return false;
}

@compute @workgroup_size(8, 8)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let w = cam.size.x;
    if gid.x >= w || gid.y >= cam.size.y {
        return;
    }
    let i = gid.y * w + gid.x;
    let p = faces[3u * i].xyz;
    let albedo = faces[3u * i + 1u];
    let n = faces[3u * i + 2u].xyz;
    var wetness = 0.0;
    var still = false;
    var f = 0.0;
    var ray_d = vec4<f32>(0.0, 0.0, 0.0, -1.0);
    let snowed = wet.flags.w != 0u && snow_depth[i] > 0.0;
    if depth[i] < 3.0e38 && !snowed && albedo.w > 0.0 {
        // WetStage::water_mm
        let lifted = p + n * WET_OFFSET_M;
        var sum = 0.0;
        for (var k = 0u; k < 3u; k++) {
            let v = wet.dirs[k].xyz;
            let h = -dot(n, v);
            if h > 0.0 && !sheltered(lifted, -v) {
                sum += h / -v.y;
            }
        }
        let water = wet_water(sum / 3.0, wet.film);
        wetness = min(water / WET_FILM_MM, 1.0);
        if wetness > 0.0 {
            let d = normalize(ray_direction(cam, gid.x, gid.y));
            still = n.y >= LEVEL_MIN_UP && water > WET_FILM_MM && relief_u(p.x, p.z, wet.relief) < puddle_share(water);
            let a = albedo.xyz;
            let dry = vec3<f32>(rgb[3u * i], rgb[3u * i + 1u], rgb[3u * i + 2u]);
            let c = dry * (vec3<f32>(1.0 - wetness) + wetness * wet.optics.x / (vec3<f32>(1.0) - wet.optics.y * a));
            rgb[3u * i] = c.x;
            rgb[3u * i + 1u] = c.y;
            rgb[3u * i + 2u] = c.z;
            f = wetness * fresnel(dot(n, -d), WATER_INDEX);
            ray_d = vec4<f32>(reflected(d, n, p, still), select(0.0, 1.0, still));
        }
    }
    rays[3u * i] = vec4<f32>(p, f);
    rays[3u * i + 1u] = ray_d;
    rays[3u * i + 2u] = vec4<f32>(n, wetness);
    if wet.flags.y != 0u {
        wet_out[i] = wetness;
    }
    if wet.flags.z != 0u {
        puddle_out[i] = select(0.0, 1.0, still);
    }
}
