// The refraction's lookup copy (skyfall-core windshield::render::lookup_copy): the frame
// box-averaged over s x s blocks (clipped at the edges), each block summed row by row in the
// CPU's order; s = 1 is the frame itself.

struct WsLookupParams {
    // width, height, lookup width, block side s
    dims: vec4<u32>,
}

@group(0) @binding(0) var<uniform> ws_l: WsLookupParams;
@group(0) @binding(1) var<storage, read> ws_src: array<f32>;
@group(0) @binding(2) var<storage, read_write> ws_dst: array<f32>;

@compute @workgroup_size(8, 8)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let w = ws_l.dims.x;
    let h = ws_l.dims.y;
    let lw = ws_l.dims.z;
    let s = ws_l.dims.w;
    let lh = (h + s - 1u) / s;
    if (gid.x >= lw || gid.y >= lh) {
        return;
    }
    var acc = vec3<f32>(0.0, 0.0, 0.0);
    var n = 0.0;
    for (var j = gid.y * s; j < min((gid.y + 1u) * s, h); j = j + 1u) {
        for (var i = gid.x * s; i < min((gid.x + 1u) * s, w); i = i + 1u) {
            let p = (j * w + i) * 3u;
            acc = acc + vec3<f32>(ws_src[p], ws_src[p + 1u], ws_src[p + 2u]);
            n = n + 1.0;
        }
    }
    let o = (gid.y * lw + gid.x) * 3u;
    ws_dst[o] = acc.x / n;
    ws_dst[o + 1u] = acc.y / n;
    ws_dst[o + 2u] = acc.z / n;
}
