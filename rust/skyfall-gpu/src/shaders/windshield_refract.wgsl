// The frame seen through the windshield's drops (skyfall-core windshield::render::refract_frame,
// in focus): coverage from the field's crossing of 0.5 over one pixel, the normal from central
// differences, the lookup by the paper's offset (mode 0) or Snell's law (mode 1), bilinear and
// mirrored in the box-averaged lookup copy, into the drop layer (premultiplied: M x the refracted
// light, and M), which windshield_blur.wgsl blurs when the drops are defocused and
// windshield_over.wgsl lays over the frame.

struct WsRefractParams {
    // width, height, lookup width, lookup height
    dims: vec4<u32>,
    // lookup scale, mode, 0, 0
    opts: vec4<u32>,
    // focal px, principal x, principal y, index
    lens: vec4<f32>,
    // slope px, 0, 0, 0
    more: vec4<f32>,
}

@group(0) @binding(0) var<uniform> ws_r: WsRefractParams;
@group(0) @binding(1) var<storage, read> ws_field: array<f32>;
@group(0) @binding(2) var<storage, read> ws_look: array<f32>;
@group(0) @binding(3) var<storage, read_write> ws_layer: array<vec4<f32>>;  // M x light, M
@group(0) @binding(4) var<storage, read_write> ws_mask: array<f32>;
@group(0) @binding(5) var<storage, read_write> ws_height: array<f32>;  // the field above its 0.5 threshold

fn ws_at(x: u32, y: u32) -> f32 {
    return ws_field[y * ws_r.dims.x + x];
}

fn ws_gradient(i: u32, j: u32) -> vec2<f32> {
    let w = ws_r.dims.x;
    let h = ws_r.dims.y;
    let il = select(i - 1u, 0u, i == 0u);
    let ir = min(i + 1u, w - 1u);
    let ju = select(j - 1u, 0u, j == 0u);
    let jd = min(j + 1u, h - 1u);
    var g = vec2<f32>(0.0, 0.0);
    if (ir > il) {
        g.x = (ws_at(ir, j) - ws_at(il, j)) / f32(ir - il);
    }
    if (jd > ju) {
        g.y = (ws_at(i, jd) - ws_at(i, ju)) / f32(jd - ju);
    }
    return g;
}

fn ws_refract(d: vec3<f32>, n: vec3<f32>, eta: f32) -> vec3<f32> {
    let cosi = -dot(d, n);
    let k = max(1.0 - eta * eta * (1.0 - cosi * cosi), 0.0);
    return eta * d + (eta * cosi - sqrt(k)) * n;
}

fn ws_mirror(x: f32, n: u32) -> f32 {
    let nf = f32(n);
    let period = 2.0 * nf;
    var m = x - period * floor(x / period);
    if (m >= nf) {
        m = period - m;
    }
    return clamp(m, 0.0, nf - 1e-3);
}

fn ws_sample(x: f32, y: f32) -> vec3<f32> {
    let lw = ws_r.dims.z;
    let lh = ws_r.dims.w;
    let sx = ws_mirror(x, lw) - 0.5;
    let sy = ws_mirror(y, lh) - 0.5;
    let x0 = floor(sx);
    let y0 = floor(sy);
    let fx = sx - x0;
    let fy = sy - y0;
    let i0 = u32(clamp(x0, 0.0, f32(lw - 1u)));
    let i1 = u32(clamp(x0 + 1.0, 0.0, f32(lw - 1u)));
    let j0 = u32(clamp(y0, 0.0, f32(lh - 1u)));
    let j1 = u32(clamp(y0 + 1.0, 0.0, f32(lh - 1u)));
    var out = vec3<f32>(0.0, 0.0, 0.0);
    for (var c = 0u; c < 3u; c = c + 1u) {
        let a = ws_look[(j0 * lw + i0) * 3u + c];
        let b = ws_look[(j0 * lw + i1) * 3u + c];
        let e = ws_look[(j1 * lw + i0) * 3u + c];
        let f = ws_look[(j1 * lw + i1) * 3u + c];
        let top = a * (1.0 - fx) + b * fx;
        let bot = e * (1.0 - fx) + f * fx;
        out[c] = top * (1.0 - fy) + bot * fy;
    }
    return out;
}

@compute @workgroup_size(8, 8)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let w = ws_r.dims.x;
    let h = ws_r.dims.y;
    if (gid.x >= w || gid.y >= h) {
        return;
    }
    let i = gid.x;
    let j = gid.y;
    let p = j * w + i;
    let v = ws_at(i, j);
    let g = ws_gradient(i, j);
    let glen = max(length(g), 1e-6);
    let m = clamp((v - 0.5) / glen + 0.5, 0.0, 1.0);
    ws_mask[p] = m;
    ws_height[p] = max(v - 0.5, 0.0);
    var c = vec3<f32>(0.0, 0.0, 0.0);
    if (m > 0.0) {
        let s = ws_r.more.x;
        let nn = vec3<f32>(-s * g.x, -s * g.y, 1.0);
        let n = nn / sqrt(dot(nn, nn));
        let px = f32(i) + 0.5;
        let py = f32(j) + 0.5;
        let f = ws_r.lens.x;
        var q = vec2<f32>(0.0, 0.0);
        if (ws_r.opts.y == 0u) {
            let k = (ws_r.lens.w - 1.0) * f;
            q = vec2<f32>(px - k * n.x, py - k * n.y);
        } else {
            let d = normalize(vec3<f32>((px - ws_r.lens.y) / f, (py - ws_r.lens.z) / f, 1.0));
            let dw = ws_refract(d, vec3<f32>(0.0, 0.0, -1.0), 1.0 / ws_r.lens.w);
            let o = ws_refract(dw, -n, ws_r.lens.w);
            let z = max(o.z, 1e-6);
            q = vec2<f32>(ws_r.lens.y + f * o.x / z, ws_r.lens.z + f * o.y / z);
        }
        let sc = f32(ws_r.opts.x);
        c = ws_sample(q.x / sc, q.y / sc);
    }
    ws_layer[p] = vec4<f32>(m * c.x, m * c.y, m * c.z, m);
}
