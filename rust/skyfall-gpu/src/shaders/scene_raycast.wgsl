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
@group(0) @binding(11) var<uniform> snow: SnowInfo;
@group(0) @binding(12) var<storage, read> snow_cells: array<vec4<f32>>; // base, depth, slope x, slope z
@group(0) @binding(13) var<storage, read_write> snow_out: array<f32>;
@group(0) @binding(14) var<uniform> sun: SunInfo;
@group(0) @binding(15) var<storage, read> sun_gamma: array<f32>;
@group(0) @binding(16) var<storage, read_write> sun_out: array<f32>;
@group(0) @binding(17) var<storage, read_write> grain_out: array<vec4<f32>>; // w·F·mirrored, depth (-1: none)
// wet_face writes each pixel's face: (point, -), (albedo, 1 hit / -1 none), (normal, -); wet_lights
// and MIRROR read the mirror rays wet_film.wgsl made of them: (point, w·F), (mirror direction,
// 1 puddle / 0 film / -1 none), (normal, w).
@group(0) @binding(18) var<storage, read_write> mirror_rays: array<vec4<f32>>;

// The wet stage (skyfall_core::wet::stage, WetStage), in four pipelines over the frame main
// drew: wet_face here (each pixel's face, ray cast again), wet_film.wgsl (the film, the
// puddles, the darkening and each wet pixel's mirror ray), wet_lights here (the highlights of
// the lights and the sun, in lit frames) and main again with MIRROR (each mirror ray cast and
// lit as a view ray is). Fewer, larger pipelines (all of it in main, as first written; the
// face, the film and the highlights in one entry point; the film in an entry point of this
// module) made lavapipe's compiler (Mesa 22.3) write into freed memory (valgrind's memcheck,
// in vkCreateComputePipelines); these four compile cleanly.
override MIRROR: bool = false;

// The sun on the surfaces (skyfall_core::frame::scene::SunLight); its code runs in the LIT
// pipelines only (a frame with a sun takes them).
struct SunInfo {
    dir: vec4<f32>,      // towards the sun, normal illuminance over E (w)
    flags: vec4<u32>,    // sun on, clouds' volume present, sun_transmittance written
    volume: VolumeBox,
    colour: vec4<f32>,   // the colour of its light (xyz, luminance 1)
}

// True in the pipelines for frames with a snow cover (skyfall_core::snow::cover::render).
override SNOW: bool = false;

struct SnowInfo {
    grid: vec4<f32>,    // origin x, origin z (m), cell side (m), depth on open ground (m)
    range: vec4<f32>,   // lowest base, highest top of the cells with snow (m), albedo, depth of whole coverage (m)
    dims: vec4<u32>,    // cells along x, along z
    relief: array<vec4<f32>, 9>, // the relief noise's quantiles (the snow's patches: snow::cover::look)
}

struct LampInfo {
    params: vec4<f32>,   // 1/E (1/lux), SHADOW_SKIP_RELATIVE, unused x2
    counts: vec4<u32>,   // number of lights
}

struct SkyInfo {
    abcd: vec4<f32>,      // CIE a, b, c, d
    e_scale: vec4<f32>,   // CIE e, scale (pi / normalisation), kind (0 overcast, 1 general)
    sun: vec4<f32>,       // unit vector towards the sun
    colour: vec4<f32>,    // the sky light's colour (xyz), the sky has a colour (w = 1)
    colour_sun: vec4<f32>, // towards the sun as the colour model takes it
    model: array<vec4<f32>, 8>, // Hosek-Wilkie: 27 parameters, 3 radiances, saturation, 0
}

struct AmbientInfo {
    origin_spacing: vec4<f32>,   // node (0,0,0) in m, spacing in m
    dims: vec4<u32>,             // nodes along x, y, z
}

// CHANNELS and HALF_PI come from the core (pass::shared_constants).

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

// Element i of the sky's colour model.
fn sky_model(i: u32) -> f32 {
    return sky.model[i / 4u][i % 4u];
}

// The sky's chroma along unit `dir`, linear RGB of luminance 1
// (skyfall_core::sky::colour::SkyColour::chroma; neutral without a colour). Only the LIT
// pipelines have it: a frame whose sky has a colour takes them (an overcast frame without lights
// compiles none of it: on lavapipe the unlit street was 1.09x slower with it).
fn sky_chroma(dir: vec3<f32>) -> vec3<f32> {
    if !LIT || sky.colour.w == 0.0 {
        return vec3<f32>(1.0);
    }
    let cos_theta = max(dir.y, 0.0);
    let cos_gamma = clamp(dot(dir, sky.colour_sun.xyz), -1.0, 1.0);
    let gamma = acos(cos_gamma);
    let zenith = sqrt(cos_theta);
    var rgb = vec3<f32>(0.0);
    for (var k = 0u; k < 3u; k = k + 1u) {
        let b = 9u * k;
        let p8 = sky_model(b + 8u);
        let mie = (1.0 + cos_gamma * cos_gamma) / pow(1.0 + p8 * p8 - 2.0 * p8 * cos_gamma, 1.5);
        let lhs = 1.0 + sky_model(b) * exp(sky_model(b + 1u) / (cos_theta + 0.01));
        let rhs = sky_model(b + 2u) + sky_model(b + 3u) * exp(sky_model(b + 4u) * gamma)
            + sky_model(b + 5u) * cos_gamma * cos_gamma + sky_model(b + 6u) * mie
            + sky_model(b + 7u) * zenith;
        rgb[k] = max(sky_model(27u + k) * lhs * rhs, 0.0);
    }
    let y = dot(vec3<f32>(LUMA_R, LUMA_G, LUMA_B), rgb);
    if !(y > 0.0) {
        return vec3<f32>(1.0);
    }
    return vec3<f32>(1.0) + (rgb / y - vec3<f32>(1.0)) * sky_model(30u);
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

// WINDOW_ALBEDO_FACTOR and T_MIN come from the core (pass::shared_constants).

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
        if box_blocks(boxes[i], p, inv, t_max, lo_seg, hi_seg) {
            return true;
        }
    }
    return false;
}

// SKIP_LEVELS and SHADOW_OFFSET_M come from the core (pass::shared_constants).

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

// --- the snow cover (skyfall_core::snow::cover::render::SnowRender) ---------------------

fn snow_signum(v: f32) -> f32 {
    return select(1.0, -1.0, v < 0.0);
}

// SnowRender::normal: (-dtop/dx, 1, -dtop/dz) of the cell's slope, made once per cell
// (SnowRender::slope_of).
fn snow_normal(i: u32, k: u32) -> vec3<f32> {
    let c = snow_cells[k * snow.dims.x + i];
    return normalize(vec3<f32>(-c.z, 1.0, -c.w));
}

struct SnowHit {
    t: f32,
    n: vec3<f32>,
    d: f32,
    hit: bool,
    // A column's top (its depth and normal then interpolated by the caller), its cell and base.
    top: bool,
    cell: vec2<u32>,
    base: f32,
}

struct SnowAt {
    d: f32,
    n: vec3<f32>,
    has_n: bool,
}

// SnowRender::surface_at: the depth at p over cell (i, k) and the normal, bilinear between the
// centres of the cells around p on the surface of y_ref (bases within a cell's width).
fn snow_surface_at(p: vec3<f32>, i: u32, k: u32, y_ref: f32) -> SnowAt {
    let s = snow.grid.z;
    let nx = i32(snow.dims.x);
    let nz = i32(snow.dims.y);
    let u = (p.x - snow.grid.x) / s - 0.5;
    let v = (p.z - snow.grid.y) / s - 0.5;
    let i0 = clamp(i32(floor(u)), i32(i) - 1, i32(i));
    let k0 = clamp(i32(floor(v)), i32(k) - 1, i32(k));
    let fx = clamp(u - f32(i0), 0.0, 1.0);
    let fz = clamp(v - f32(k0), 0.0, 1.0);
    var w_sum = 0.0;
    var d_sum = 0.0;
    var n_sum = vec3<f32>(0.0);
    for (var dk = 0; dk < 2; dk++) {
        let wz = select(1.0 - fz, fz, dk == 1);
        for (var di = 0; di < 2; di++) {
            let wx = select(1.0 - fx, fx, di == 1);
            let ii = i0 + di;
            let kk = k0 + dk;
            if ii < 0 || kk < 0 || ii >= nx || kk >= nz {
                continue;
            }
            let j = u32(kk * nx + ii);
            let cell = snow_cells[j];
            // (A NaN base fails the comparison.)
            if !(abs(cell.x - y_ref) <= s) {
                continue;
            }
            let w = wx * wz;
            w_sum += w;
            d_sum += w * cell.y;
            if cell.y > 0.0 {
                n_sum += w * snow_normal(u32(ii), u32(kk));
            }
        }
    }
    var out = SnowAt(0.0, vec3<f32>(0.0), false);
    if w_sum > 0.0 {
        out.d = d_sum / w_sum;
    }
    if any(n_sum != vec3<f32>(0.0)) {
        out.n = normalize(n_sum);
        out.has_n = true;
    }
    return out;
}

// SnowRender::cell_of: the cell over p, clamped to the grid.
fn snow_cell_of(p: vec3<f32>) -> vec2<u32> {
    let s = snow.grid.z;
    let i = min(u32(max(floor((p.x - snow.grid.x) / s), 0.0)), snow.dims.x - 1u);
    let k = min(u32(max(floor((p.z - snow.grid.y) / s), 0.0)), snow.dims.y - 1u);
    return vec2<u32>(i, k);
}

// SnowRender::trace: the nearest snow along o + t d, 0 <= t <= t_max (a 2D DDA over the grid).
fn snow_trace(o: vec3<f32>, d: vec3<f32>, t_max: f32) -> SnowHit {
    var none = SnowHit(0.0, vec3<f32>(0.0), 0.0, false, false, vec2<u32>(0u), 0.0);
    if snow.range.x > snow.range.y {
        return none;
    }
    let s = snow.grid.z;
    let nx = snow.dims.x;
    let nz = snow.dims.y;
    let lo = vec3<f32>(snow.grid.x, snow.range.x, snow.grid.y);
    let hi = vec3<f32>(snow.grid.x + s * f32(nx), snow.range.y, snow.grid.y + s * f32(nz));
    let inv = vec3<f32>(1.0 / safe(d.x), 1.0 / safe(d.y), 1.0 / safe(d.z));
    let t1v = (lo - o) * inv;
    let t2v = (hi - o) * inv;
    let tn = min(t1v, t2v);
    let tf = max(t1v, t2v);
    let t_enter = max(max(max(tn.x, tn.y), tn.z), 0.0);
    let t_exit = min(min(min(tf.x, tf.y), tf.z), t_max);
    if t_enter > t_exit {
        return none;
    }
    var side: vec3<f32>;
    if tn.x >= tn.y && tn.x >= tn.z {
        side = vec3<f32>(-snow_signum(d.x), 0.0, 0.0);
    } else if tn.z >= tn.y {
        side = vec3<f32>(0.0, 0.0, -snow_signum(d.z));
    } else {
        side = vec3<f32>(0.0, -snow_signum(d.y), 0.0);
    }
    let p = o + d * t_enter;
    var i = min(u32(max(floor((p.x - snow.grid.x) / s), 0.0)), nx - 1u);
    var k = min(u32(max(floor((p.z - snow.grid.y) / s), 0.0)), nz - 1u);
    let sx = d.x >= 0.0;
    let sz = d.z >= 0.0;
    var tx = 3.4e38;
    if d.x != 0.0 {
        tx = (snow.grid.x + s * (f32(i) + select(0.0, 1.0, sx)) - o.x) * inv.x;
    }
    var tz = 3.4e38;
    if d.z != 0.0 {
        tz = (snow.grid.y + s * (f32(k) + select(0.0, 1.0, sz)) - o.z) * inv.z;
    }
    let dtx = abs(s * inv.x);
    let dtz = abs(s * inv.z);
    var t_in = t_enter;
    for (var step = 0u; step < nx + nz + 2u; step++) {
        let t_out = min(min(tx, tz), t_exit);
        let idx = k * nx + i;
        let cell = snow_cells[idx];
        let dep = cell.y;
        if dep > 0.0 {
            let b = cell.x;
            let top = b + dep;
            var a0 = 3.4e38;
            var a1 = -3.4e38;
            if d.y != 0.0 {
                let ta = (b - o.y) / d.y;
                let tb = (top - o.y) / d.y;
                a0 = min(ta, tb);
                a1 = max(ta, tb);
            } else if o.y >= b && o.y <= top {
                a0 = -3.4e38;
                a1 = 3.4e38;
            }
            let h0 = max(t_in, a0);
            let h1 = min(t_out, a1);
            if h0 <= h1 {
                if h0 > t_in || o.y + d.y * h0 - b < 0.5 * s {
                    // The top (the caller interpolates its depth and normal over the surface:
                    // once, outside this loop, which lavapipe's compiler then keeps small; its
                    // normal is the caller's).
                    return SnowHit(h0, side, dep, true, true, vec2<u32>(i, k), b);
                }
                return SnowHit(h0, side, dep, true, false, vec2<u32>(i, k), b);
            }
        }
        if t_out >= t_exit {
            return none;
        }
        if tx <= tz {
            if (sx && i + 1u >= nx) || (!sx && i == 0u) {
                return none;
            }
            i = select(i - 1u, i + 1u, sx);
            t_in = tx;
            tx += dtx;
            side = vec3<f32>(select(1.0, -1.0, sx), 0.0, 0.0);
        } else {
            if (sz && k + 1u >= nz) || (!sz && k == 0u) {
                return none;
            }
            k = select(k - 1u, k + 1u, sz);
            t_in = tz;
            tz += dtz;
            side = vec3<f32>(0.0, 0.0, select(1.0, -1.0, sz));
        }
    }
    return none;
}

fn snow_covers(p: vec3<f32>) -> bool {
    let u = (p.x - snow.grid.x) / snow.grid.z;
    let v = (p.z - snow.grid.y) / snow.grid.z;
    return u >= 0.0 && v >= 0.0 && u < f32(snow.dims.x) && v < f32(snow.dims.y);
}

// look::coverage: 1 - (1 - d/full)^2 below full, 1 from there.
fn snow_coverage(dep: f32) -> f32 {
    if dep <= 0.0 {
        return 0.0;
    }
    if dep >= snow.range.w {
        return 1.0;
    }
    let x = 1.0 - dep / snow.range.w;
    return 1.0 - x * x;
}

// look::footprint_m
fn snow_footprint(t: f32, d: vec3<f32>, n: vec3<f32>, f_px: f32) -> f32 {
    let len = length(d);
    let across = t * len / f_px;
    let c = max(abs(dot(n, d) / len), 0.0025);
    return across / sqrt(c);
}

// look::drawn_share: the share of a pixel at (x, z) under snow of coverage c, for a footprint.
fn snow_drawn_share(x: f32, z: f32, c: f32, footprint: f32) -> f32 {
    if c <= 0.0 || c >= 1.0 {
        return clamp(c, 0.0, 1.0);
    }
    let f = clamp((footprint / SNOW_PATCH_M - SNOW_SHARP_BELOW) / (SNOW_BLEND_FROM - SNOW_SHARP_BELOW), 0.0, 1.0);
    if f >= 1.0 {
        return c;
    }
    let k = RELIEF_SCALE_M / SNOW_PATCH_M;
    let u = relief_u(x * k + SNOW_PATCH_OFFSET, z * k - SNOW_PATCH_OFFSET, snow.relief);
    let sharp = select(0.0, 1.0, u < c);
    return sharp + (c - sharp) * f;
}

// sparkle::sparkle: the glints a pixel adds at p on a face n seen along to_camera (any length)
// under the sun along l, footprint of side fp (radiance over E/pi per unit of the sun's normal
// illuminance over E); most pixels draw none and cost a hash (1 - e^-N <= N).
fn snow_sparkle(p: vec3<f32>, n: vec3<f32>, to_camera: vec3<f32>, l: vec3<f32>, fp: f32) -> f32 {
    let area = fp * fp;
    let count = area / (FACET_M * FACET_M) * (SUN_RADIUS_RAD * SUN_RADIUS_RAD / 8.0);
    if count <= 0.0 {
        return 0.0;
    }
    let u = unit24(cell_hash(p, GLINT_CELL_M, 0x51a7u));
    if u >= count {
        return 0.0;
    }
    let hit = 1.0 - exp(-count);
    if u >= hit {
        return 0.0;
    }
    let v = normalize(to_camera);
    let nv = dot(n, v);
    let nl = dot(n, l);
    if nv <= 0.0 || nl <= 0.0 {
        return 0.0;
    }
    let hv = clamp(dot(normalize(v + l), v), 0.0, 1.0);
    let one = fresnel(hv, ICE_INDEX) * FACET_M * FACET_M * hv / (SUN_RADIUS_RAD * SUN_RADIUS_RAD * area * nv);
    return one * count / hit;
}

// skyfall_core::cloud::frame::VolumeView::sample over the clouds' Γ for the sun.
fn sun_volume(p: vec3<f32>) -> f32 {
    let v = sun.volume;
    let n = u32(v.origin.w);
    if n == 1u {
        return sun_gamma[0];
    }
    let d = p - v.origin.xyz;
    let a = volume_cell(dot(d, v.axes[0].xyz), n);
    let b = volume_cell(dot(d, v.axes[1].xyz), n);
    let c = volume_cell(dot(d, v.axes[2].xyz), n);
    var pl: array<f32, 2>;
    for (var u = 0u; u < 2u; u++) {
        let r0 = ((a.i + u) * n + b.i) * n + c.i;
        let r1 = ((a.i + u) * n + b.i + 1u) * n + c.i;
        let lo = mix(sun_gamma[r0], sun_gamma[r0 + 1u], c.f);
        let hi = mix(sun_gamma[r1], sun_gamma[r1 + 1u], c.f);
        pl[u] = lo + (hi - lo) * b.f;
    }
    return pl[0] + (pl[1] - pl[0]) * a.f;
}

// SUN_RAY_M comes from the core (pass::shared_constants).

// SunLight::share: 0 facing away or behind a box, else the clouds' Γ at p.
fn sun_share(p: vec3<f32>, n: vec3<f32>) -> f32 {
    if dot(n, sun.dir.xyz) <= 0.0 {
        return 0.0;
    }
    if occluded_within(p + n * SHADOW_OFFSET_M, sun.dir.xyz, SUN_RAY_M) {
        return 0.0;
    }
    if sun.flags.y == 0u {
        return 1.0;
    }
    return sun_volume(p - cam.pos.xyz);
}

struct Shaded {
    c: vec3<f32>,
    share: f32,   // of the sun's direct light (1 without a sun)
}

// SceneLight::surface_radiance_sun.
fn surface_radiance(p: vec3<f32>, n: vec3<f32>, a: vec3<f32>) -> Shaded {
    let ch = ambient_channel(n);
    var e = 0.0;
    if ch < CHANNELS {
        e = ambient_sample(p, ch);
    }
    var c = a * e;
    if LIT {
        c = a * (sky.colour.xyz * e);
    }
    var share = 1.0;
    if LIT && sun.flags.x != 0u {
        share = sun_share(p, n);
        c = c + a * (sun.colour.xyz * (sun.dir.w * max(dot(n, sun.dir.xyz), 0.0) * share));
    }
    if LIT && lamps.counts.x != 0u {
        c = c + a * lamp_light(p, n, a, c);
    }
    return Shaded(c, share);
}

// skyfall_core::scene::boxes::trace: the nearest hit along origin + t dir, t > T_MIN.
struct Hit {
    hit: bool,
    t: f32,
    n: vec3<f32>,
    a: vec3<f32>,
}

fn trace(origin: vec3<f32>, dir: vec3<f32>) -> Hit {
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
    return Hit(hit, best_t, best_n, best_a);
}

// --- wet surfaces (skyfall_core::wet) ---------------------------------------------------

// WetStage::highlights: the lights' and the sun's on water of roughness alpha and normal n at
// p (albedo a, seen along unit d, receiving `share` of the sun).
fn wet_highlights(a: vec3<f32>, p: vec3<f32>, n: vec3<f32>, d: vec3<f32>, share: f32, alpha: f32) -> vec3<f32> {
    let v = -d;
    let lifted = p + n * WET_OFFSET_M;
    var highlights = vec3<f32>(0.0);
    {
        for (var i = 0u; i < lamps.counts.x; i++) {
            let s = surface_lit(lights[i], p, n, a);
            if max(max(s.e.x, s.e.y), s.e.z) <= 0.0 {
                continue;
            }
            let f = wet_brdf(n, v, s.dir, alpha);
            if f > 0.0 && !occluded_within(lifted, s.dir, s.r - WET_OFFSET_M) {
                highlights += s.e * (f * lamps.params.x);
            }
        }
        if sun.flags.x != 0u && share > 0.0 {
            let cs = max(dot(n, sun.dir.xyz), 0.0);
            highlights += sun.colour.xyz * (wet_brdf(n, v, sun.dir.xyz, alpha) * sun.dir.w * cs * share);
        }
    }
    return highlights;
}

// The wet stage's third pipeline, in lit frames only (a frame without lights or a sun has no
// highlights): each wet pixel's highlights (WetStage::highlights) times its wetness added to
// rgb, at the face wet_film.wgsl wetted.
@compute @workgroup_size(8, 8)
fn wet_lights(@builtin(global_invocation_id) gid: vec3<u32>) {
    let w = cam.size.x;
    if gid.x >= w || gid.y >= cam.size.y {
        return;
    }
    let i = gid.y * w + gid.x;
    let ray = mirror_rays[3u * i + 1u];
    if ray.w < 0.0 {
        return;
    }
    let face = mirror_rays[3u * i + 2u];
    let n = face.xyz;
    let p = mirror_rays[3u * i].xyz;
    let d = normalize(ray_direction(cam, gid.x, gid.y));
    var share = 1.0;
    if sun.flags.z != 0u {
        share = sun_out[i];
    }
    let h = face.w * wet_highlights(vec3<f32>(1.0), p, n, d, share, select(FILM_ROUGHNESS, PUDDLE_ROUGHNESS, ray.w > 0.5));
    rgb[3u * i] += h.x;
    rgb[3u * i + 1u] += h.y;
    rgb[3u * i + 2u] += h.z;
}

// The wet stage's first pipeline: each pixel's ray cast again for its face (its point, its
// albedo and whether there is one, its normal) into mirror_rays, for wet_film.wgsl.
@compute @workgroup_size(8, 8)
fn wet_face(@builtin(global_invocation_id) gid: vec3<u32>) {
    let w = cam.size.x;
    if gid.x >= w || gid.y >= cam.size.y {
        return;
    }
    let i = gid.y * w + gid.x;
    let origin = cam.pos.xyz;
    let dir = ray_direction(cam, gid.x, gid.y);
    let first = trace(origin, dir);
    let p = origin + dir * first.t;
    mirror_rays[3u * i] = vec4<f32>(p, 0.0);
    mirror_rays[3u * i + 1u] = vec4<f32>(surface_albedo(first.a, first.n, p), select(-1.0, 1.0, first.hit));
    mirror_rays[3u * i + 2u] = vec4<f32>(first.n, 0.0);
}

@compute @workgroup_size(8, 8)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let w = cam.size.x;
    let h = cam.size.y;
    if gid.x >= w || gid.y >= h {
        return;
    }
    let i = gid.y * w + gid.x;
    var origin = cam.pos.xyz;
    var dir = ray_direction(cam, gid.x, gid.y);
    if MIRROR {
        // A wet pixel's mirror ray (wet_main), or none.
        if mirror_rays[3u * i + 1u].w < 0.0 {
            grain_out[i] = vec4<f32>(0.0, 0.0, 0.0, -1.0);
            return;
        }
        origin = mirror_rays[3u * i].xyz + mirror_rays[3u * i + 2u].xyz * WET_OFFSET_M;
        dir = mirror_rays[3u * i + 1u].xyz;
    }
    let first = trace(origin, dir);
    let hit = first.hit;
    let best_t = first.t;
    let best_n = first.n;
    let best_a = first.a;
    if SNOW {
        // SnowRender::shade_pixel.
        let sh = snow_trace(origin, dir, select(3.4e38, best_t, hit));
        // What the pixel shows of the cover: a column's top (depth and normal interpolated
        // over its surface), a column's side, or an upward face beside the cover (the depth
        // thinning out over a cell) or beyond the grid (the open ground's, not lifted).
        var t = sh.t;
        var n = sh.n;
        var dep = sh.d;
        var under = vec3<f32>(snow.range.z);
        var interp = sh.hit && sh.top;
        var ip = origin + dir * sh.t;
        var ic = sh.cell;
        var iy = sh.base;
        if sh.hit {
            if hit && best_n.y > 0.5 {
                under = best_a;
            }
        } else if hit && best_n.y > 0.5 {
            t = best_t;
            n = best_n;
            under = best_a;
            ip = origin + dir * best_t;
            dep = snow.grid.w;
            if snow_covers(ip) {
                interp = true;
                ic = snow_cell_of(ip);
                iy = ip.y;
            }
        } else {
            dep = 0.0;
        }
        if interp {
            let at = snow_surface_at(ip, ic.x, ic.y, iy);
            dep = at.d;
            if sh.hit {
                n = at.n;
                if !at.has_n {
                    n = snow_normal(ic.x, ic.y);
                }
            }
        }
        let found = sh.hit || dep > 0.0;
        var sc = Shaded(vec3<f32>(0.0), 1.0);
        var sd = 0.0;
        if found {
            // White where its patches lie, sparkling where the sun reaches it.
            let p = origin + dir * t;
            let fp = snow_footprint(t, dir, n, cam.intr.y);
            let cov = snow_coverage(dep);
            let share = snow_drawn_share(p.x, p.z, cov, fp);
            // render::drawn_depth: patches dep / cov deep, the share of them the pixel shows.
            if share > 0.0 && cov > 0.0 {
                sd = dep / cov * share;
            }
            sc = surface_radiance(p, n, under + (vec3<f32>(snow.range.z) - under) * share);
            if LIT && sun.flags.x != 0u && sc.share * share > 0.0 {
                let g = snow_sparkle(p, n, -dir, sun.dir.xyz, fp);
                sc.c += sun.colour.xyz * (sun.dir.w * sc.share * share * g);
            }
        }
        let st = t;
        snow_out[i] = sd;
        if found {
            rgb[3u * i] = sc.c.x;
            rgb[3u * i + 1u] = sc.c.y;
            rgb[3u * i + 2u] = sc.c.z;
            depth[i] = st;
            if LIT && sun.flags.z != 0u {
                sun_out[i] = sc.share;
            }
            return;
        }
    }
    var c: vec3<f32>;
    var d: f32;
    var share = 1.0;
    if hit {
        let p = origin + dir * best_t;
        let a = surface_albedo(best_a, best_n, p);
        let s = surface_radiance(p, best_n, a);
        c = s.c;
        share = s.share;
        d = best_t;
    } else {
        let u = normalize(dir);
        c = vec3<f32>(sky.e_scale.y * relative_to_zenith(u));
        if LIT {
            c = c * sky_chroma(u);
        }
        d = infinity();
    }
    if MIRROR {
        // Fresnel's share of what the mirror ray sees, times the wetness: a puddle's added
        // here, the film's left for its row averaging (wet_grain.wgsl).
        let m = c * mirror_rays[3u * i].w;
        if mirror_rays[3u * i + 1u].w > 0.5 {
            rgb[3u * i] += m.x;
            rgb[3u * i + 1u] += m.y;
            rgb[3u * i + 2u] += m.z;
            grain_out[i] = vec4<f32>(0.0, 0.0, 0.0, -1.0);
        } else {
            grain_out[i] = vec4<f32>(m, depth[i]);
        }
        return;
    }
    if LIT && sun.flags.z != 0u {
        sun_out[i] = share;
    }
    rgb[3u * i] = c.x;
    rgb[3u * i + 1u] = c.y;
    rgb[3u * i + 2u] = c.z;
    depth[i] = d;
}
