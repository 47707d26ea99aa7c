// Particle streaks (rain and snow) over the frame, per pixel over its tile's streaks (sorted
// far to near on the CPU). CPU reference: skyfall_core::particles (ScreenStreak::fragment,
// Sprite::profile, composite_band), kept line for line comparable. Prepended with common.wgsl.

struct RainParams {
    streak_count: u32,
    tiles_x: u32,
    tile_w: u32,
    tile_h: u32,
    layers: u32,  // bit 0: the depth layer (rain_depth_m) drawn; bit 2: continue the far pass's rain plane and depth
    depth_layers: u32,  // bit k: particle layer k's nearest particle is the depth layer's
    planes: u32,  // bit k: particle layer k's coverage plane is drawn (the frame keeps it)
    pad2: u32,
}

// Sprite::profile: a particle's density across its path at x = across / half-width, mean 1
// over [0, 1]; kind 0 flat (rain), 1 lump, 2 six-armed star turned by turn·π/3, 3 aggregate.
fn sprite_profile(kind: u32, turn: f32, x: f32) -> f32 {
    let one_minus = max(1.0 - x * x, 0.0);
    let disc = 1.2732395 * sqrt(one_minus);
    if kind == 1u {
        return disc;
    }
    if kind == 2u {
        let third = 1.0471976;
        var arms = 0.0;
        for (var k = 0u; k < 3u; k++) {
            let c = max(abs(cos(turn * third + f32(k) * third)), 0.2);
            if x <= c {
                arms += 1.0 / c;
            }
        }
        return 0.25 * disc + 0.25 * arms;
    }
    if kind == 3u {
        return 1.5 * one_minus;
    }
    return 1.0;
}

@group(0) @binding(0) var<uniform> cam: Camera;
@group(0) @binding(1) var<uniform> params: RainParams;
@group(0) @binding(2) var<storage, read> streaks: array<vec4<f32>>;  // 4 per streak (ScreenStreak::packed)
@group(0) @binding(3) var<storage, read> offsets: array<u32>;
@group(0) @binding(4) var<storage, read> indices: array<u32>;
@group(0) @binding(5) var<storage, read_write> rgb: array<f32>;
@group(0) @binding(6) var<storage, read> depth: array<f32>;
// One coverage plane per particle layer (skyfall_core::particles::streak::PARTICLE_LAYERS), W·H each.
@group(0) @binding(7) var<storage, read_write> coverage: array<f32>;
@group(0) @binding(8) var<storage, read_write> rain_depth: array<f32>;

@compute @workgroup_size(8, 8)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let w = cam.size.x;
    if gid.x >= w || gid.y >= cam.size.y {
        return;
    }
    let i = gid.y * w + gid.x;
    let p = vec2<f32>(f32(gid.x) + 0.5, f32(gid.y) + 0.5);
    let t = (gid.y / params.tile_h) * params.tiles_x + gid.x / params.tile_w;
    var c = vec3<f32>(rgb[3u * i], rgb[3u * i + 1u], rgb[3u * i + 2u]);
    let n = w * cam.size.y;
    // ∏(1 − a) per particle layer, lane k for layer k (in registers: at most four layers)
    let lanes = vec4<u32>(0u, 1u, 2u, 3u);
    var keep = vec4<f32>(1.0);
    var z_min = infinity();
    if (params.layers & 4u) != 0u {
        keep = select(keep, vec4<f32>(1.0 - coverage[LAYER_RAIN * n + i]), lanes == vec4<u32>(LAYER_RAIN));
        z_min = rain_depth[i];
    }
    let scene_depth = depth[i];
    for (var j = offsets[t]; j < offsets[t + 1u]; j++) {
        let k = indices[j];
        let s0 = streaks[4u * k];
        let s1 = streaks[4u * k + 1u];
        let dir = s0.zw;
        let len = s1.x;
        let q = p - s0.xy;
        let along = dot(q, dir);
        let across = abs(q.x * dir.y - q.y * dir.x);
        // Beyond the streak's reach across (its widest half-width plus half a pixel, at least
        // one pixel) or half a pixel beyond either end along, the coverage below is 0: such
        // pixels skip the rest (1e-3 px to spare for rounding; the same result).
        if across >= s1.y + 1e-3 || along <= -0.5 - 1e-3 || along >= len + 0.5 + 1e-3 {
            continue;
        }
        var kk = 0.0;
        if len > 1e-6 {
            kk = clamp(along / len, 0.0, 1.0);
        }
        let width = s1.z + (s1.w - s1.z) * kk;
        var cov_across: f32;
        if width >= 1.0 {
            cov_across = clamp(0.5 * width + 0.5 - across, 0.0, 1.0);
        } else {
            cov_across = width * clamp(1.0 - across, 0.0, 1.0);
        }
        // The sprite: packed as layer·8 + kind + turn (0 for rain).
        let code = streaks[4u * k + 3u].w;
        let layer = u32(floor(code / 8.0));
        let rest = code - 8.0 * f32(layer);
        let kind = u32(floor(rest));
        if kind != 0u && width >= 1.0 {
            let turn = rest - f32(kind);
            let half_w = 0.5 * width;
            let x = across / half_w;
            var p = sprite_profile(kind, turn, x);
            // Sprite::density: within half a width of either end a lump or an aggregate is
            // round (the disc's density at r = |(x, u)|), a star the profile along times across.
            let e = min(along, len - along);
            if e < half_w {
                let u = 1.0 - e / half_w;
                let one_minus = max(1.0 - x * x - u * u, 0.0);
                if kind == 1u {
                    p = 1.9098593 * sqrt(one_minus);
                } else if kind == 3u {
                    p = 2.5464791 * one_minus;
                } else {
                    p *= sprite_profile(kind, turn, u);
                }
            }
            cov_across *= 1.0 + clamp(0.5 * width - 1.0, 0.0, 1.0) * (p - 1.0);
        }
        let cov_along = min(clamp(along + 0.5, 0.0, 1.0), clamp(len - along + 0.5, 0.0, 1.0));
        let cov = cov_across * cov_along;
        if cov <= 0.0 {
            continue;
        }
        let s2 = streaks[4u * k + 2u];
        let z = 1.0 / (s2.x + (s2.y - s2.x) * kk);
        if z >= scene_depth {
            continue;
        }
        let light = streaks[4u * k + 3u].xyz;
        // At most 1: a sprite's peak times α can pass it on a short path (as the CPU's).
        let fa = min(s2.z * cov, 1.0);
        let ar = fa * s2.w;  // r, per streak
        c += ar * (light - c);
        let l = min(layer, PARTICLE_LAYERS - 1u);
        keep *= select(vec4<f32>(1.0), vec4<f32>(1.0 - fa), lanes == vec4<u32>(l));
        if ((params.depth_layers >> l) & 1u) != 0u {
            z_min = min(z_min, z);
        }
    }
    rgb[3u * i] = c.x;
    rgb[3u * i + 1u] = c.y;
    rgb[3u * i + 2u] = c.z;
    for (var k = 0u; k < PARTICLE_LAYERS; k++) {
        if ((params.planes >> k) & 1u) != 0u {
            coverage[k * n + i] = 1.0 - keep[k];
        }
    }
    if (params.layers & 1u) != 0u {
        rain_depth[i] = z_min;
    }
}
