// The wet film's grain denoised along each row (skyfall_core::wet::stage::denoise_grain): each
// pixel with a grained mirror image (w >= 0: its depth) gets the mean of those within the radius
// along its row whose depth is within 5 % of its own, added to its rgb. Prepended with
// common.wgsl.

struct WetGrainParams {
    dims: vec4<u32>, // width, height, radius px
}

@group(0) @binding(0) var<uniform> wg: WetGrainParams;
@group(0) @binding(1) var<storage, read> grain: array<vec4<f32>>;
@group(0) @binding(2) var<storage, read_write> rgb: array<f32>;

@compute @workgroup_size(8, 8)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let w = wg.dims.x;
    if gid.x >= w || gid.y >= wg.dims.y {
        return;
    }
    let row = gid.y * w;
    let own = grain[row + gid.x];
    if own.w < 0.0 {
        return;
    }
    let d = own.w;
    let r = wg.dims.z;
    let lo = select(0u, gid.x - r, gid.x >= r);
    let hi = min(gid.x + r + 1u, w);
    var sum = vec3<f32>(0.0);
    var n = 0u;
    for (var j = lo; j < hi; j++) {
        let g = grain[row + j];
        if g.w >= 0.0 && abs(g.w - d) <= 0.05 * d {
            sum += g.xyz;
            n += 1u;
        }
    }
    let i = row + gid.x;
    let c = vec3<f32>(rgb[3u * i], rgb[3u * i + 1u], rgb[3u * i + 2u]) + sum / f32(max(n, 1u));
    rgb[3u * i] = c.x;
    rgb[3u * i + 1u] = c.y;
    rgb[3u * i + 2u] = c.z;
}
