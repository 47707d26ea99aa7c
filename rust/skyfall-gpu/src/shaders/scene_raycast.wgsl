// Procedural box scene, ray cast per pixel, lit by the sky through the ambient-light map and
// by the scene's point and spot lights with their shadows.
// CPU references: skyfall_core::frame::scene (shade_pixel, SceneLight::lamp_light),
// skyfall_core::scene::lights (Light), skyfall_core::scene::raycast, skyfall_core::sky::cie
// (relative_to_zenith) and skyfall_core::sky::ambient (AmbientMap::sample), kept
// line-for-line comparable. Prepended with common.wgsl.

struct SceneInfo {
    ground_albedo: vec4<f32>,
    counts: vec4<u32>,   // number of boxes, ground (0/1)
}

struct SceneBox {
    min_m: vec4<f32>,
    max_m: vec4<f32>,
    albedo: vec4<f32>,
}

// False in the pipeline for scenes without lights: the lights' code is compiled out.
override LIT: bool = true;

@group(0) @binding(0) var<uniform> cam: Camera;
@group(0) @binding(1) var<uniform> scene: SceneInfo;
@group(0) @binding(2) var<storage, read> boxes: array<SceneBox>;
@group(0) @binding(3) var<storage, read_write> rgb: array<f32>;
@group(0) @binding(4) var<storage, read_write> depth: array<f32>;
@group(0) @binding(5) var<uniform> sky: SkyInfo;
@group(0) @binding(6) var<uniform> amb: AmbientInfo;
@group(0) @binding(7) var<storage, read> amb_values: array<f32>;
@group(0) @binding(8) var<storage, read> amb_solid: array<u32>;
@group(0) @binding(9) var<uniform> lamps: LampInfo;
@group(0) @binding(10) var<storage, read> lights: array<LightElement>;

struct LampInfo {
    params: vec4<f32>,   // 1/E (1/lux), SHADOW_SKIP_RELATIVE, unused x2
    counts: vec4<u32>,   // number of lights
}

struct LightElement {
    pos_cd: vec4<f32>,      // position (m), intensity (cd)
    color_spot: vec4<f32>,  // linear RGB, 1 for a spot
    axis_outer: vec4<f32>,  // the spot's unit axis, cos of its outer half-angle
    inner: vec4<f32>,       // cos of its inner half-angle
}

struct SkyInfo {
    abcd: vec4<f32>,      // CIE a, b, c, d
    e_scale: vec4<f32>,   // CIE e, scale (pi / normalisation), kind (0 overcast, 1 general)
    sun: vec4<f32>,       // unit vector towards the sun
}

struct AmbientInfo {
    origin_spacing: vec4<f32>,   // node (0,0,0) in m, spacing in m
    dims: vec4<u32>,             // nodes along x, y, z
}

const CHANNELS: u32 = 5u;
const HALF_PI: f32 = 1.5707963267948966;

// L/Lz of the sky along unit `dir` (skyfall_core::sky::cie::SkyKind::relative_to_zenith).
fn relative_to_zenith(dir: vec3<f32>) -> f32 {
    let cz = dir.y;
    if cz < 0.0 {
        return 0.0;
    }
    if sky.e_scale.z == 0.0 {
        return (1.0 + 2.0 * cz) / 3.0;
    }
    let a = sky.abcd.x;
    let b = sky.abcd.y;
    let c = sky.abcd.z;
    let d = sky.abcd.w;
    let e = sky.e_scale.x;
    var phi = 1.0;
    if cz > 0.0 {
        phi = 1.0 + a * exp(b / cz);
    }
    let phi0 = 1.0 + a * exp(b);
    let chi = acos(clamp(dot(dir, sky.sun.xyz), -1.0, 1.0));
    let zs = acos(clamp(sky.sun.y, -1.0, 1.0));
    let f_chi = 1.0 + c * (exp(d * chi) - exp(d * HALF_PI)) + e * cos(chi) * cos(chi);
    let f_zs = 1.0 + c * (exp(d * zs) - exp(d * HALF_PI)) + e * cos(zs) * cos(zs);
    return phi * f_chi / (phi0 * f_zs);
}

// Lower node and fraction along one axis of `n` nodes, clamped to the grid.
fn amb_axis(coord: f32, origin: f32, n: u32) -> vec2<f32> {
    let g = clamp((coord - origin) / amb.origin_spacing.w, 0.0, f32(n - 1u));
    let i0 = min(floor(g), f32(max(n, 2u) - 2u));
    return vec2<f32>(i0, select(0.0, g - i0, n > 1u));
}

// One corner's contribution: (w v, w) over all corners and over the open ones.
fn amb_corner(acc: vec4<f32>, i: u32, j: u32, k: u32, ch: u32, w: f32) -> vec4<f32> {
    let n = (i * amb.dims.y + j) * amb.dims.z + k;
    let v = amb_values[n * CHANNELS + ch];
    let open = select(0.0, 1.0, amb_solid[n] == 0u);
    return acc + vec4<f32>(w * v, w, open * w * v, open * w);
}

// Trilinear sample of one channel, clamped to the grid, over the cell's open corners
// (all of them when every weighted corner is solid): skyfall_core::sky::ambient::AmbientMap::sample.
fn ambient_sample(p: vec3<f32>, ch: u32) -> f32 {
    let ax = amb_axis(p.x, amb.origin_spacing.x, amb.dims.x);
    let ay = amb_axis(p.y, amb.origin_spacing.y, amb.dims.y);
    let az = amb_axis(p.z, amb.origin_spacing.z, amb.dims.z);
    let i0 = u32(ax.x);
    let j0 = u32(ay.x);
    let k0 = u32(az.x);
    let i1 = min(i0 + 1u, amb.dims.x - 1u);
    let j1 = min(j0 + 1u, amb.dims.y - 1u);
    let k1 = min(k0 + 1u, amb.dims.z - 1u);
    let fx = ax.y;
    let fy = ay.y;
    let fz = az.y;
    var acc = vec4<f32>(0.0);
    acc = amb_corner(acc, i0, j0, k0, ch, (1.0 - fx) * (1.0 - fy) * (1.0 - fz));
    acc = amb_corner(acc, i1, j0, k0, ch, fx * (1.0 - fy) * (1.0 - fz));
    acc = amb_corner(acc, i0, j1, k0, ch, (1.0 - fx) * fy * (1.0 - fz));
    acc = amb_corner(acc, i1, j1, k0, ch, fx * fy * (1.0 - fz));
    acc = amb_corner(acc, i0, j0, k1, ch, (1.0 - fx) * (1.0 - fy) * fz);
    acc = amb_corner(acc, i1, j0, k1, ch, fx * (1.0 - fy) * fz);
    acc = amb_corner(acc, i0, j1, k1, ch, (1.0 - fx) * fy * fz);
    acc = amb_corner(acc, i1, j1, k1, ch, fx * fy * fz);
    if acc.w > 0.0 {
        return acc.z / acc.w;
    }
    return acc.x;
}

// Channel of an axis-aligned normal: 0 up, 1 +X, 2 -X, 3 +Z, 4 -Z; 5 for faces looking down.
fn ambient_channel(n: vec3<f32>) -> u32 {
    if n.y > 0.5 { return 0u; }
    if n.y < -0.5 { return 5u; }
    if n.x > 0.5 { return 1u; }
    if n.x < -0.5 { return 2u; }
    if n.z > 0.5 { return 3u; }
    return 4u;
}

const WINDOW_ALBEDO_FACTOR: f32 = 0.2;
const T_MIN: f32 = 1e-4;

fn surface_albedo(albedo: vec3<f32>, n: vec3<f32>, p: vec3<f32>) -> vec3<f32> {
    if abs(n.y) < 0.5 {
        let u = select(p.x, p.z, abs(n.x) > 0.5);
        let fu = fract(u / 3.0);
        let fv = fract((p.y - 1.0) / 3.0);
        if p.y > 1.0 && fu > 0.25 && fu < 0.75 && fv < 0.5 {
            return albedo * WINDOW_ALBEDO_FACTOR;
        }
    }
    return albedo;
}

fn safe(d: f32) -> f32 {
    if abs(d) < 1e-20 {
        return select(1e-20, -1e-20, d < 0.0);
    }
    return d;
}

// skyfall_core::scene::lights::Light::illuminance_lux.
fn light_illuminance(l: LightElement, p: vec3<f32>) -> vec3<f32> {
    let d = p - l.pos_cd.xyz;
    let r2 = max(dot(d, d), 1e-4);
    var cone = 1.0;
    if l.color_spot.w != 0.0 {
        let c = dot(l.axis_outer.xyz, d) / sqrt(r2);
        let co = l.axis_outer.w;
        let ci = l.inner.x;
        if c <= co {
            cone = 0.0;
        } else if c >= ci {
            cone = 1.0;
        } else {
            let t = (c - co) / max(ci - co, 1e-6);
            cone = t * t * (3.0 - 2.0 * t);
        }
    }
    return l.color_spot.xyz * (l.pos_cd.w * cone / r2);
}

// Light::surface_illuminance_lux: (E·cos θ, its channel max share with albedo a) and the unit
// vector to the light with its distance.
struct Lit {
    e: vec3<f32>,
    dir: vec3<f32>,
    r: f32,
    share: f32,
}

fn surface_lit(l: LightElement, p: vec3<f32>, n: vec3<f32>, a: vec3<f32>) -> Lit {
    let to = l.pos_cd.xyz - p;
    let r = max(sqrt(dot(to, to)), 1e-2);
    let dir = to / r;
    let cos = dot(n, dir);
    var e = vec3<f32>(0.0);
    if cos > 0.0 {
        e = light_illuminance(l, p) * cos;
    }
    let ae = a * e;
    return Lit(e, dir, r, max(max(ae.x, ae.y), ae.z) * lamps.params.x);
}

// skyfall_core::scene::raycast::occluded_within.
fn occluded_within(p: vec3<f32>, dir: vec3<f32>, t_max: f32) -> bool {
    let inv = vec3<f32>(1.0 / safe(dir.x), 1.0 / safe(dir.y), 1.0 / safe(dir.z));
    let q = p + dir * t_max;
    let lo_seg = min(p, q);
    let hi_seg = max(p, q);
    for (var i = 0u; i < scene.counts.x; i++) {
        let b = boxes[i];
        if any(b.min_m.xyz > hi_seg) || any(b.max_m.xyz < lo_seg) {
            continue;
        }
        let t1 = (b.min_m.xyz - p) * inv;
        let t2 = (b.max_m.xyz - p) * inv;
        let lo = min(t1, t2);
        let hi = max(t1, t2);
        let t_near = max(max(max(lo.x, lo.y), lo.z), T_MIN);
        let t_far = min(min(min(hi.x, hi.y), hi.z), t_max);
        if t_near <= t_far {
            return true;
        }
    }
    return false;
}

const SKIP_LEVELS: u32 = 8u;
const SHADOW_OFFSET_M: f32 = 1e-3;

// SceneLight::lamp_light: the lights' illuminance relative to E on the face, shadowed, the
// faintest (together at most SHADOW_SKIP_RELATIVE of the pixel) without a shadow ray.
fn lamp_light(p: vec3<f32>, n: vec3<f32>, a: vec3<f32>, ambient: vec3<f32>) -> vec3<f32> {
    let count = lamps.counts.x;
    var total = max(max(ambient.x, ambient.y), ambient.z);
    for (var i = 0u; i < count; i++) {
        total += surface_lit(lights[i], p, n, a).share;
    }
    let budget = lamps.params.y * total;
    var below = array<u32, 8>(0u, 0u, 0u, 0u, 0u, 0u, 0u, 0u);
    for (var i = 0u; i < count; i++) {
        let c = surface_lit(lights[i], p, n, a).share;
        if c > 0.0 {
            for (var j = 0u; j < SKIP_LEVELS; j++) {
                if c <= budget / f32(1u << j) {
                    below[j] += 1u;
                }
            }
        }
    }
    var skip = 0.0;
    for (var j = 0u; j < SKIP_LEVELS; j++) {
        let tau = budget / f32(1u << j);
        if f32(below[j]) * tau <= budget {
            skip = tau;
            break;
        }
    }
    let lifted = p + n * SHADOW_OFFSET_M;
    var sum = vec3<f32>(0.0);
    for (var i = 0u; i < count; i++) {
        let s = surface_lit(lights[i], p, n, a);
        if s.share <= 0.0 {
            continue;
        }
        if s.share <= skip || !occluded_within(lifted, s.dir, s.r - SHADOW_OFFSET_M) {
            sum += s.e;
        }
    }
    return sum * lamps.params.x;
}

@compute @workgroup_size(8, 8)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let w = cam.size.x;
    let h = cam.size.y;
    if gid.x >= w || gid.y >= h {
        return;
    }
    let origin = cam.pos.xyz;
    let dir = ray_direction(cam, gid.x, gid.y);
    var hit = false;
    var best_t = 3.4e38;
    var best_n = vec3<f32>(0.0);
    var best_a = vec3<f32>(0.0);
    if scene.counts.y != 0u && dir.y < 0.0 && origin.y > 0.0 {
        hit = true;
        best_t = -origin.y / dir.y;
        best_n = vec3<f32>(0.0, 1.0, 0.0);
        best_a = scene.ground_albedo.xyz;
    }
    let inv = vec3<f32>(1.0 / safe(dir.x), 1.0 / safe(dir.y), 1.0 / safe(dir.z));
    for (var i = 0u; i < scene.counts.x; i++) {
        let b = boxes[i];
        let t1 = (b.min_m.xyz - origin) * inv;
        let t2 = (b.max_m.xyz - origin) * inv;
        let lo = min(t1, t2);
        let hi = max(t1, t2);
        let t_near = max(max(lo.x, lo.y), lo.z);
        let t_far = min(min(hi.x, hi.y), hi.z);
        if t_near > T_MIN && t_near <= t_far && t_near < best_t {
            hit = true;
            best_t = t_near;
            if t_near == lo.x {
                best_n = vec3<f32>(-sign(dir.x), 0.0, 0.0);
            } else if t_near == lo.y {
                best_n = vec3<f32>(0.0, -sign(dir.y), 0.0);
            } else {
                best_n = vec3<f32>(0.0, 0.0, -sign(dir.z));
            }
            best_a = b.albedo.xyz;
        }
    }
    var c: vec3<f32>;
    var d: f32;
    if hit {
        let p = origin + dir * best_t;
        let a = surface_albedo(best_a, best_n, p);
        let ch = ambient_channel(best_n);
        var e = 0.0;
        if ch < CHANNELS {
            e = ambient_sample(p, ch);
        }
        c = a * e;
        if LIT && lamps.counts.x != 0u {
            c = c + a * lamp_light(p, best_n, a, c);
        }
        d = best_t;
    } else {
        c = vec3<f32>(sky.e_scale.y * relative_to_zenith(normalize(dir)));
        d = infinity();
    }
    let i = gid.y * w + gid.x;
    rgb[3u * i] = c.x;
    rgb[3u * i + 1u] = c.y;
    rgb[3u * i + 2u] = c.z;
    depth[i] = d;
}
