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

// An axis-aligned box of a scene (or a photo's occluder), m.
struct SceneBox {
    min_m: vec4<f32>,
    max_m: vec4<f32>,
    albedo: vec4<f32>,
}

// Whether box b meets the segment p + t dir, T_MIN <= t <= t_max (inv = 1/dir, safely; the
// segment's bounds lo_seg, hi_seg): one box of skyfall_core::scene::raycast::occluded_within.
fn box_blocks(b: SceneBox, p: vec3<f32>, inv: vec3<f32>, t_max: f32, lo_seg: vec3<f32>, hi_seg: vec3<f32>) -> bool {
    if any(b.min_m.xyz > hi_seg) || any(b.max_m.xyz < lo_seg) {
        return false;
    }
    let t1 = (b.min_m.xyz - p) * inv;
    let t2 = (b.max_m.xyz - p) * inv;
    let lo = min(t1, t2);
    let hi = max(t1, t2);
    let t_near = max(max(max(lo.x, lo.y), lo.z), T_MIN);
    let t_far = min(min(min(hi.x, hi.y), hi.z), t_max);
    return t_near <= t_far;
}

fn safe(d: f32) -> f32 {
    if abs(d) < 1e-20 {
        return select(1e-20, -1e-20, d < 0.0);
    }
    return d;
}

// A point or spot light (skyfall_core::scene::lights::Light).
struct LightElement {
    pos_cd: vec4<f32>,      // position (m), intensity (cd)
    color_spot: vec4<f32>,  // linear RGB, 1 for a spot
    axis_outer: vec4<f32>,  // the spot's unit axis, cos of its outer half-angle
    inner: vec4<f32>,       // cos of its inner half-angle
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

// --- wet surfaces (skyfall_core::wet), shared by the box scene's pass and the photos' -----

// wet::optics::fresnel: unpolarised, from the air into index n.
fn fresnel(cos_i: f32, n: f32) -> f32 {
    let c = clamp(cos_i, 0.0, 1.0);
    if c == 0.0 {
        return 1.0;
    }
    let sin_t = sqrt(max(1.0 - c * c, 0.0)) / n;
    let cos_t = sqrt(max(1.0 - sin_t * sin_t, 0.0));
    let rs = (c - n * cos_t) / (c + n * cos_t);
    let rp = (cos_t - n * c) / (cos_t + n * c);
    return 0.5 * (rs * rs + rp * rp);
}

// wet::optics::brdf: the water's GGX lobe of roughness alpha (Smith's masking, Fresnel at v.h),
// 1/sr.
fn wet_brdf(n: vec3<f32>, v: vec3<f32>, l: vec3<f32>, alpha: f32) -> f32 {
    let nv = dot(n, v);
    let nl = dot(n, l);
    if nv <= 0.0 || nl <= 0.0 {
        return 0.0;
    }
    let hv = v + l;
    let hl = length(hv);
    var h = vec3<f32>(0.0);
    if hl > 0.0 {
        h = hv / hl;
    }
    let nh = max(dot(n, h), 0.0);
    let a2 = alpha * alpha;
    let q = nh * nh * (a2 - 1.0) + 1.0;
    let d = a2 / (PI * q * q);
    let g_v = 2.0 * nv / (nv + sqrt(a2 + (1.0 - a2) * nv * nv));
    let g_l = 2.0 * nl / (nl + sqrt(a2 + (1.0 - a2) * nl * nl));
    return fresnel(dot(v, h), WATER_INDEX) * d * g_v * g_l / (4.0 * nv * nl);
}

// wet::film::Film::water_mm of a face of `exposure`: `film` holds the water per unit exposure, mm
// (x; < 0: the storage, filled) and the water dried since the rain stopped, mm (y).
fn wet_water(exposure: f32, film: vec4<f32>) -> f32 {
    if exposure < MIN_EXPOSURE {
        return 0.0;
    }
    var filled = STORAGE_MM;
    if film.x >= 0.0 {
        filled = min(film.x * exposure, STORAGE_MM);
    }
    return max(filled - film.y, 0.0);
}

// wet::film::Film::wetness of a face of `exposure`.
fn wet_film(exposure: f32, film: vec4<f32>) -> f32 {
    return min(wet_water(exposure, film) / WET_FILM_MM, 1.0);
}

// --- puddles and the film's grain (skyfall_core::wet::puddles) ---------------------------------

// puddles::hash (Chris Wellons' lowbias32).
fn lowbias(x0: u32) -> u32 {
    var x = x0;
    x ^= x >> 16u;
    x *= 0x7feb352du;
    x ^= x >> 15u;
    x *= 0x846ca68bu;
    x ^= x >> 16u;
    return x;
}

// puddles::cell_hash: the hash of the cell of side cell_m holding p, salted.
fn cell_hash(p: vec3<f32>, cell_m: f32, salt: u32) -> u32 {
    let c = floor(p / cell_m);
    return lowbias(bitcast<u32>(i32(c.x)) ^ lowbias(bitcast<u32>(i32(c.y)) ^ lowbias(bitcast<u32>(i32(c.z)) ^ salt)));
}

fn unit24(h: u32) -> f32 {
    return f32(h >> 8u) * (1.0 / 16777216.0);
}

fn lattice(i: i32, j: i32, salt: u32) -> f32 {
    return unit24(lowbias(bitcast<u32>(i) ^ lowbias(bitcast<u32>(j) ^ lowbias(salt))));
}

// puddles::value_noise
fn value_noise(x: f32, z: f32, salt: u32) -> f32 {
    let fx = floor(x);
    let fz = floor(z);
    let i = i32(fx);
    let j = i32(fz);
    let tx = x - fx;
    let tz = z - fz;
    let sx = tx * tx * (3.0 - 2.0 * tx);
    let sz = tz * tz * (3.0 - 2.0 * tz);
    let v00 = lattice(i, j, salt);
    let v10 = lattice(i + 1, j, salt);
    let v01 = lattice(i, j + 1, salt);
    let v11 = lattice(i + 1, j + 1, salt);
    let a = v00 + (v10 - v00) * sx;
    let b = v01 + (v11 - v01) * sx;
    return a + (b - a) * sz;
}

// puddles::relief_u: three octaves through the tabulated distribution `q` (RELIEF_QUANTILES of
// its quantiles, four to an element: puddles::relief_quantiles), uniform on [0, 1].
fn relief_u(x: f32, z: f32, q: array<vec4<f32>, 9>) -> f32 {
    var scale = 1.0 / RELIEF_SCALE_M;
    let n = (value_noise(x * scale, z * scale, 0u) + 0.5 * value_noise(x * scale * 2.0, z * scale * 2.0, 1u)
        + 0.25 * value_noise(x * scale * 4.0, z * scale * 4.0, 2u)) / 1.75;
    var k = 0u;
    for (var i = 0u; i < RELIEF_QUANTILES; i++) {
        if q[i / 4u][i % 4u] <= n {
            k = i + 1u;
        }
    }
    k = clamp(k, 1u, RELIEF_QUANTILES - 1u);
    let lo = q[(k - 1u) / 4u][(k - 1u) % 4u];
    let hi = q[k / 4u][k % 4u];
    var t = 0.0;
    if hi > lo {
        t = clamp((n - lo) / (hi - lo), 0.0, 1.0);
    }
    return (f32(k - 1u) + t) / f32(RELIEF_QUANTILES - 1u);
}

// puddles::puddle_share
fn puddle_share(water: f32) -> f32 {
    return min(sqrt(2.0 * max(water - WET_FILM_MM, 0.0) / RELIEF_MM), 1.0);
}

// puddles::reflected: about n in a puddle, else about the film's GGX grain at p.
fn reflected(d: vec3<f32>, n: vec3<f32>, p: vec3<f32>, still: bool) -> vec3<f32> {
    let mirror = d - 2.0 * dot(d, n) * n;
    if still {
        return mirror;
    }
    let h = cell_hash(p, GRAIN_CELL_M, 0x9e37u);
    let u1 = unit24(h);
    let u2 = unit24(lowbias(h));
    let tn = FILM_ROUGHNESS * sqrt(u1 / (1.0 - u1));
    let cos_t = 1.0 / sqrt(1.0 + tn * tn);
    let sin_t = tn * cos_t;
    let phi = 2.0 * PI * u2;
    var a = vec3<f32>(0.0, 0.0, 1.0);
    if abs(n.x) < 0.9 {
        a = vec3<f32>(1.0, 0.0, 0.0);
    }
    let t = normalize(cross(n, a));
    let b = cross(n, t);
    let m = normalize(n * cos_t + (t * cos(phi) + b * sin(phi)) * sin_t);
    let r = d - 2.0 * dot(d, m) * m;
    if dot(r, n) > 0.0 {
        return r;
    }
    return mirror;
}
