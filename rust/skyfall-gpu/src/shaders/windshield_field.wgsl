// The windshield's metaball field (skyfall-core windshield::render::height_map): per pixel, the
// metaballs binned in its 16 x 16 tile, summed in their index order, N = 1/(1 + (h/R)^4) out
// to h = 4R, then compressed five times (V0 = 0.5 ... 0.9, k = 0.3).

struct WsFieldParams {
    // width, height, tiles across, compress (0/1)
    dims: vec4<u32>,
}

@group(0) @binding(0) var<uniform> ws_p: WsFieldParams;
@group(0) @binding(1) var<storage, read> ws_balls: array<vec4<f32>>;
@group(0) @binding(2) var<storage, read> ws_offsets: array<u32>;
@group(0) @binding(3) var<storage, read> ws_items: array<u32>;
@group(0) @binding(4) var<storage, read_write> ws_field: array<f32>;

@compute @workgroup_size(8, 8)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let w = ws_p.dims.x;
    let h = ws_p.dims.y;
    if (gid.x >= w || gid.y >= h) {
        return;
    }
    let tile = (gid.y / 16u) * ws_p.dims.z + gid.x / 16u;
    let px = f32(gid.x) + 0.5;
    let py = f32(gid.y) + 0.5;
    var v = 0.0;
    for (var k = ws_offsets[tile]; k < ws_offsets[tile + 1u]; k = k + 1u) {
        let b = ws_balls[ws_items[k]];
        let dx = px - b.x;
        let dy = py - b.y;
        let h2 = dx * dx + dy * dy;
        let reach = 4.0 * b.z;
        if (h2 <= reach * reach) {
            let q = h2 / (b.z * b.z);
            v = v + 1.0 / (1.0 + q * q);
        }
    }
    if (ws_p.dims.w != 0u) {
        for (var i = 0u; i < 5u; i = i + 1u) {
            let v0 = 0.5 + 0.1 * f32(i);
            if (v > v0) {
                v = 0.3 * (v - v0) + v0;
            }
        }
    }
    ws_field[gid.y * w + gid.x] = v;
}
