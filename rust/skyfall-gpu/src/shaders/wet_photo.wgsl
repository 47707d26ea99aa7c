// The wet stage of a photo: its surfaces and normals from the depth map, each film darkening the
// photo and mirroring what a march through the depth map finds (the photo's sky where the ray
// leaves the frame), and the lights' highlights. CPU reference: skyfall_core::wet::stage
// (WetStage::photo_pixel, photo_surface, march) and skyfall_core::wet::puddles (the relief, the
// puddles, the film's grain), kept line-for-line comparable. Prepended with common.wgsl.

struct WetPhotoInfo {
    dirs: array<vec4<f32>, 3>,   // the quartile drops' directions of fall
    film: vec4<f32>,             // water per unit exposure, mm (< 0: the storage, filled), dried, mm
    optics: vec4<f32>,           // Lekner & Dorf's (1 - R)(1 - p), p, 1/E (1/lux)
    sky: vec4<f32>,              // the photo's mean sky (linear rgb)
    counts: vec4<u32>,           // occluders that shelter, lights, snow depth bound, wetness written
    flags: vec4<u32>,            // puddle_mask written
    relief: array<vec4<f32>, 9>, // the relief noise's RELIEF_QUANTILES quantiles (puddles::relief_quantiles)
}

@group(0) @binding(0) var<uniform> cam: Camera;
@group(0) @binding(1) var<uniform> wet: WetPhotoInfo;
@group(0) @binding(2) var<storage, read> photo: array<f32>;
@group(0) @binding(3) var<storage, read> depth: array<f32>;
@group(0) @binding(4) var<storage, read_write> rgb: array<f32>;
@group(0) @binding(5) var<storage, read_write> wet_out: array<f32>;
@group(0) @binding(6) var<storage, read> occluders: array<SceneBox>;
@group(0) @binding(7) var<storage, read> lights: array<LightElement>;
@group(0) @binding(8) var<storage, read> snow_depth: array<f32>;
@group(0) @binding(9) var<storage, read_write> puddle_out: array<f32>;
@group(0) @binding(10) var<storage, read_write> grain_out: array<vec4<f32>>; // w·F·mirrored, depth (-1: none)

// MARCH_STEPS and the puddles' constants come from the core (pass::shared_constants).

fn finite(d: f32) -> bool {
    return d < 3.0e38;
}

fn photo_rgb(i: u32) -> vec3<f32> {
    return vec3<f32>(photo[3u * i], photo[3u * i + 1u], photo[3u * i + 2u]);
}

// A pixel's point on its surface and its 1/depth (ok false on the sky).
struct Pt {
    ok: bool,
    p: vec3<f32>,
    inv: f32,
}

fn point(x: u32, y: u32) -> Pt {
    let d = depth[y * cam.size.x + x];
    if !finite(d) {
        return Pt(false, vec3<f32>(0.0), 0.0);
    }
    return Pt(true, cam.pos.xyz + ray_direction(cam, x, y) * d, 1.0 / d);
}

// One axis's tangent (w: 1 when there is one), as photo_surface's.
fn tangent(b: Pt, a: Pt, p: vec3<f32>, inv: f32) -> vec4<f32> {
    if b.ok && a.ok {
        let fb = inv - b.inv;
        let fa = a.inv - inv;
        if abs(fa - fb) <= 0.1 * max(abs(fa), abs(fb)) + 1e-9 {
            return vec4<f32>(a.p - b.p, 1.0);
        } else if abs(fa) < abs(fb) {
            return vec4<f32>(a.p - p, 1.0);
        }
        return vec4<f32>(p - b.p, 1.0);
    }
    if b.ok {
        return vec4<f32>(p - b.p, 1.0);
    }
    if a.ok {
        return vec4<f32>(a.p - p, 1.0);
    }
    return vec4<f32>(0.0);
}

fn none() -> Pt {
    return Pt(false, vec3<f32>(0.0), 0.0);
}

// The pixel a world point projects to and its depth (x, y, z; z <= 0: none).
fn project(q: vec3<f32>) -> vec3<f32> {
    let c = q - cam.pos.xyz;
    let z = -dot(cam.back.xyz, c);
    if z <= 1e-6 {
        return vec3<f32>(0.0, 0.0, -1.0);
    }
    let x = cam.intr.z + cam.intr.x * dot(cam.right.xyz, c) / z;
    let y = cam.intr.w - cam.intr.y * dot(cam.up.xyz, c) / z;
    if x < 0.0 || y < 0.0 || x >= f32(cam.size.x) || y >= f32(cam.size.y) {
        return vec3<f32>(0.0, 0.0, -1.0);
    }
    return vec3<f32>(floor(x), floor(y), z);
}

fn sheltered(p: vec3<f32>, dir: vec3<f32>) -> bool {
    let inv = vec3<f32>(1.0 / safe(dir.x), 1.0 / safe(dir.y), 1.0 / safe(dir.z));
    let q = p + dir * SHELTER_RAY_M;
    let lo_seg = min(p, q);
    let hi_seg = max(p, q);
    for (var i = 0u; i < wet.counts.x; i++) {
        if box_blocks(occluders[i], p, inv, SHELTER_RAY_M, lo_seg, hi_seg) {
            return true;
        }
    }
    return false;
}

// WetStage::march: what the surface at p (normal n) mirrors along unit r.
fn march(p: vec3<f32>, n: vec3<f32>, r: vec3<f32>) -> vec3<f32> {
    let w = cam.size.x;
    let eye = cam.pos.xyz;
    var s = 0.01 * max(length(p - eye), 0.1);
    var travelled = 0.0;
    for (var k = 0u; k < MARCH_STEPS; k++) {
        travelled += s;
        s *= 1.12;
        let at = project(p + r * travelled);
        if at.z <= 0.0 {
            break;
        }
        let px = u32(at.x);
        let py = u32(at.y);
        let d = depth[py * w + px];
        if finite(d) && at.z > d && at.z - d < max(0.1 * d, 0.3) {
            let off = eye + ray_direction(cam, px, py) * d - p;
            if dot(off, n) > 0.02 * length(off) + 0.01 {
                return photo_rgb(py * w + px);
            }
        }
    }
    let sky_at = project(eye + r * 1e4);
    if sky_at.z > 0.0 {
        let i = u32(sky_at.y) * w + u32(sky_at.x);
        if !finite(depth[i]) {
            return photo_rgb(i);
        }
    }
    return wet.sky.xyz;
}

@compute @workgroup_size(8, 8)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let w = cam.size.x;
    let h = cam.size.y;
    if gid.x >= w || gid.y >= h {
        return;
    }
    let x = gid.x;
    let y = gid.y;
    let i = y * w + x;
    var wetness = 0.0;
    var still = false;
    var grain = vec4<f32>(0.0, 0.0, 0.0, -1.0);
    let snowed = wet.counts.z != 0u && snow_depth[i] > 0.0;
    let here = point(x, y);
    if here.ok && !snowed {
        var before = none();
        var after = none();
        if x > 0u {
            before = point(x - 1u, y);
        }
        if x + 1u < w {
            after = point(x + 1u, y);
        }
        let tx = tangent(before, after, here.p, here.inv);
        before = none();
        after = none();
        if y > 0u {
            before = point(x, y - 1u);
        }
        if y + 1u < h {
            after = point(x, y + 1u);
        }
        let ty = tangent(before, after, here.p, here.inv);
        var n = cross(tx.xyz, ty.xyz);
        let len = length(n);
        if tx.w != 0.0 && ty.w != 0.0 && len > 0.0 {
            n = n / len;
            let p = here.p;
            if dot(n, cam.pos.xyz - p) < 0.0 {
                n = -n;
            }
            let lifted = p + n * WET_OFFSET_M;
            var sum = 0.0;
            for (var k = 0u; k < 3u; k++) {
                let v = wet.dirs[k].xyz;
                let hit = -dot(n, v);
                if hit > 0.0 && !(wet.counts.x != 0u && sheltered(lifted, -v)) {
                    sum += hit / -v.y;
                }
            }
            let water = wet_water(sum / 3.0, wet.film);
            wetness = min(water / WET_FILM_MM, 1.0);
            if wetness > 0.0 {
                still = n.y >= LEVEL_MIN_UP && water > WET_FILM_MM && relief_u(p.x, p.z, wet.relief) < puddle_share(water);
                let dry = vec3<f32>(rgb[3u * i], rgb[3u * i + 1u], rgb[3u * i + 2u]);
                let a = min(dry, vec3<f32>(1.0));
                let d = normalize(p - cam.pos.xyz);
                let v = -d;
                let r = reflected(d, n, p, still);
                let mirrored = march(p, n, r) * fresnel(dot(n, v), WATER_INDEX);
                var highlights = vec3<f32>(0.0);
                for (var l = 0u; l < wet.counts.y; l++) {
                    let to = lights[l].pos_cd.xyz - p;
                    let dist = max(length(to), 1e-2);
                    let dir = to / dist;
                    let cs = dot(n, dir);
                    if cs <= 0.0 {
                        continue;
                    }
                    let e = light_illuminance(lights[l], p) * cs;
                    if max(max(e.x, e.y), e.z) <= 0.0 {
                        continue;
                    }
                    highlights += e * (wet_brdf(n, v, dir, select(FILM_ROUGHNESS, PUDDLE_ROUGHNESS, still)) * wet.optics.z);
                }
                let k = vec3<f32>(1.0 - wetness) + wetness * wet.optics.x / (vec3<f32>(1.0) - wet.optics.y * a);
                var c = dry * k + wetness * highlights;
                if still {
                    c += wetness * mirrored;
                } else {
                    grain = vec4<f32>(wetness * mirrored, depth[i]);
                }
                rgb[3u * i] = c.x;
                rgb[3u * i + 1u] = c.y;
                rgb[3u * i + 2u] = c.z;
            }
        }
    }
    if wet.counts.w != 0u {
        wet_out[i] = wetness;
    }
    if wet.flags.x != 0u {
        puddle_out[i] = select(0.0, 1.0, still);
    }
    grain_out[i] = grain;
}
