// The windshield over the frame (skyfall-core windshield::render::refract_frame's last step, and
// WindshieldStage::draw_blades): the drop layer laid over the frame behind the glass,
// C (1 - M) + M L, then each wiper blade, dark (its albedo), anti-aliased over one pixel across
// its edges and at its tip, drawn only in its bounding box, as the CPU draws it.

struct WsOverParams {
    // width, height, blades, 0
    dims: vec4<u32>,
    // blade albedo, 0, 0, 0
    albedo: vec4<f32>,
}

// One blade: [pivot x px, pivot y px, 1 / (px per mm across), 1 / (px per mm down the slope)],
// [cos, sin, half width mm, length mm], [px per mm across its edge, px per mm, 0, 0],
// its bounding box [x0, y0, x1, y1) in px.
struct WsBlade {
    pivot: vec4<f32>,
    axis: vec4<f32>,
    edge: vec4<f32>,
    bounds: vec4<i32>,
}

@group(0) @binding(0) var<uniform> wo_p: WsOverParams;
@group(0) @binding(1) var<storage, read> wo_layer: array<vec4<f32>>;
@group(0) @binding(2) var<storage, read> wo_blades: array<WsBlade>;
@group(0) @binding(3) var<storage, read_write> wo_rgb: array<f32>;

@compute @workgroup_size(8, 8)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let w = wo_p.dims.x;
    let h = wo_p.dims.y;
    if (gid.x >= w || gid.y >= h) {
        return;
    }
    let p = gid.y * w + gid.x;
    let l = wo_layer[p];
    var c = vec3<f32>(wo_rgb[p * 3u], wo_rgb[p * 3u + 1u], wo_rgb[p * 3u + 2u]);
    c = c * (1.0 - l.w) + l.xyz;
    let x = i32(gid.x);
    let y = i32(gid.y);
    for (var b = 0u; b < wo_p.dims.z; b = b + 1u) {
        let bl = wo_blades[b];
        if (x < bl.bounds.x || y < bl.bounds.y || x >= bl.bounds.z || y >= bl.bounds.w) {
            continue;
        }
        let dx = (f32(gid.x) + 0.5 - bl.pivot.x) * bl.pivot.z;
        let dy = (bl.pivot.y - (f32(gid.y) + 0.5)) * bl.pivot.w;
        let along = dx * bl.axis.x + dy * bl.axis.y;
        let across = -dx * bl.axis.y + dy * bl.axis.x;
        if (along < 0.0) {
            continue;
        }
        let cover = clamp((bl.axis.z - abs(across)) * bl.edge.x + 0.5, 0.0, 1.0)
            * clamp((bl.axis.w - along) * bl.edge.y + 0.5, 0.0, 1.0);
        c = c * (1.0 - cover) + cover * wo_p.albedo.x;
    }
    wo_rgb[p * 3u] = c.x;
    wo_rgb[p * 3u + 1u] = c.y;
    wo_rgb[p * 3u + 2u] = c.z;
}
