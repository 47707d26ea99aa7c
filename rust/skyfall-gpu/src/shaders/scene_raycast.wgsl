// Procedural box scene, ray cast per pixel. CPU reference: skyfall_core::scene::boxes
// (kept line-for-line comparable). Prepended with common.wgsl.

struct SceneInfo {
    ground_albedo: vec4<f32>,
    counts: vec4<u32>,   // number of boxes, ground (0/1)
}

struct SceneBox {
    min_m: vec4<f32>,
    max_m: vec4<f32>,
    albedo: vec4<f32>,
}

@group(0) @binding(0) var<uniform> cam: Camera;
@group(0) @binding(1) var<uniform> scene: SceneInfo;
@group(0) @binding(2) var<storage, read> boxes: array<SceneBox>;
@group(0) @binding(3) var<storage, read_write> rgb: array<f32>;
@group(0) @binding(4) var<storage, read_write> depth: array<f32>;

const WINDOW_ALBEDO_FACTOR: f32 = 0.2;
const T_MIN: f32 = 1e-4;

fn sky_radiance(dir_unit: vec3<f32>) -> f32 {
    let s = max(dir_unit.y, 0.0);
    return (9.0 / 7.0) * (1.0 + 2.0 * s) / 3.0;
}

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
        c = a * (0.5 * (1.0 + best_n.y));
        d = best_t;
    } else {
        c = vec3<f32>(sky_radiance(normalize(dir)));
        d = infinity();
    }
    let i = gid.y * w + gid.x;
    rgb[3u * i] = c.x;
    rgb[3u * i + 1u] = c.y;
    rgb[3u * i + 2u] = c.z;
    depth[i] = d;
}
