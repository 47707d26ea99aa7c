// The defocused drops' blur (skyfall-core windshield::render::box_blur): one axis of a separable
// box blur of half-width r px over the drop layer's four channels, the window clamped to the
// frame and normalised by the pixels inside it. The CPU sums in f64 with a running window; this
// sums each window afresh in f32 (no drift; the difference is f32 rounding).

struct WsBlurParams {
    // width, height, radius, axis (0: along rows, 1: along columns)
    dims: vec4<u32>,
}

@group(0) @binding(0) var<uniform> wb_p: WsBlurParams;
@group(0) @binding(1) var<storage, read> wb_src: array<vec4<f32>>;
@group(0) @binding(2) var<storage, read_write> wb_dst: array<vec4<f32>>;

@compute @workgroup_size(8, 8)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let w = wb_p.dims.x;
    let h = wb_p.dims.y;
    if (gid.x >= w || gid.y >= h) {
        return;
    }
    let r = wb_p.dims.z;
    var n = w;
    var k = gid.x;
    var step = 1u;
    var base = gid.y * w;
    if (wb_p.dims.w == 1u) {
        n = h;
        k = gid.y;
        step = w;
        base = gid.x;
    }
    let lo = select(k - r, 0u, k < r);
    let hi = min(k + r, n - 1u);
    var acc = vec4<f32>(0.0, 0.0, 0.0, 0.0);
    for (var q = lo; q <= hi; q = q + 1u) {
        acc = acc + wb_src[base + q * step];
    }
    wb_dst[base + k * step] = acc / f32(hi - lo + 1u);
}
