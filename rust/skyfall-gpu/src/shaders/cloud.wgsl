// The cloud pass: camera-facing Gaussian splats composited back to front over the frame,
// E_k = S_k + T_k E_{k-1}, each fragment lit from the attenuation volumes (trilinear).
// CPU reference: skyfall_core::cloud::frame (CloudSplats::apply_row, VolumeView::sample),
// kept line-for-line comparable. Prepended with common.wgsl.

struct CloudInfo {
    counts: vec4<u32>,   // tiles across, tile side (px), sun present, cloud_alpha written
    sun_g: vec4<f32>,    // towards the sun, g
    sun_light: vec4<f32>,   // the sun's light (xyz), diffuse light on (w != 0)
    sky_light: vec4<f32>,   // the sky's light (xyz), the splats' farthest reach (w, m)
    sun_volume: VolumeBox,
    zenith_volume: VolumeBox,
}

@group(0) @binding(0) var<uniform> cam: Camera;
@group(0) @binding(1) var<uniform> info: CloudInfo;
@group(0) @binding(2) var<storage, read> splats: array<vec4<f32>>;   // 2 per splat: centre, r; tau, albedo, distance, 0
@group(0) @binding(3) var<storage, read> offsets: array<u32>;
@group(0) @binding(4) var<storage, read> indices: array<u32>;
@group(0) @binding(5) var<storage, read> gammas: array<f32>;   // the zenith's volume, then the sun's
@group(0) @binding(6) var<storage, read_write> rgb: array<f32>;
@group(0) @binding(7) var<storage, read> depth: array<f32>;
@group(0) @binding(8) var<storage, read_write> alpha_out: array<f32>;

// CUTOFF_RADII, MIN_TRANSMITTANCE and PI come from the core (pass::shared_constants).

// VolumeView::sample_with_exit: (Γ at p, Γ where the light leaves) of volume `v`.
fn sample_volume(v: VolumeBox, p: vec3<f32>) -> vec2<f32> {
    let n = u32(v.origin.w);
    let base = bitcast<u32>(v.axes[0].w);
    if n == 1u {
        return vec2<f32>(gammas[base], gammas[base]);
    }
    let d = p - v.origin.xyz;
    let a = volume_cell(dot(d, v.axes[0].xyz), n);
    let b = volume_cell(dot(d, v.axes[1].xyz), n);
    let c = volume_cell(dot(d, v.axes[2].xyz), n);
    var pl: array<f32, 2>;
    var ex: array<f32, 2>;
    for (var u = 0u; u < 2u; u++) {
        let r0 = base + ((a.i + u) * n + b.i) * n + c.i;
        let r1 = base + ((a.i + u) * n + b.i + 1u) * n + c.i;
        let lo = mix(gammas[r0], gammas[r0 + 1u], c.f);
        let hi = mix(gammas[r1], gammas[r1 + 1u], c.f);
        pl[u] = lo + (hi - lo) * b.f;
        let e0 = gammas[base + ((a.i + u) * n + b.i) * n + n - 1u];
        let e1 = gammas[base + ((a.i + u) * n + b.i + 1u) * n + n - 1u];
        ex[u] = e0 + (e1 - e0) * b.f;
    }
    return vec2<f32>(pl[0] + (pl[1] - pl[0]) * a.f, ex[0] + (ex[1] - ex[0]) * a.f);
}

fn henyey_greenstein(cos_theta: f32, g: f32) -> f32 {
    let d = 1.0 + g * g - 2.0 * g * cos_theta;
    return (1.0 - g * g) / (4.0 * PI * d * sqrt(d));
}

// skyfall_core::cloud::frame::diffuse_light: with k = STREAM_DEPTH 3/4/(1 + g), a = -k ln(gamma) and
// b = k ln(gamma/exit), D = 1/(1 + a) and D R = b/((1 + a)(1 + b)).
fn diffuse_light(gamma: f32, exit: f32, g: f32, with_direct: bool, weights: vec2<f32>) -> f32 {
    let k = STREAM_DEPTH * 0.75 / (1.0 + g);
    let ln_gamma = log(max(gamma, 1e-30));
    let above = -k * ln_gamma;
    let below = max(k * (ln_gamma - log(max(exit, 1e-30))), 0.0);
    let q = 1.0 / ((1.0 + above) * (1.0 + below));
    let d = (1.0 + below) * q;
    var reaching = max(d - gamma, 0.0);
    if with_direct {
        reaching = d;
    }
    return weights.x * reaching + weights.y * (below * q);
}

// skyfall_core::cloud::frame::stream_share: the share of a stream a particle scatters towards
// a viewer the light leaves towards at mu = v . t.
fn stream_share(mu: f32, g: f32) -> f32 {
    var forward = 0.5;
    if abs(g) >= 1e-4 {
        forward = (1.0 + g) / (2.0 * g) - (1.0 - g * g) / (2.0 * g * sqrt(1.0 + g * g));
    }
    let rise = (1.0 - exp(-min(abs(mu), 1.0) / STREAM_WIDTH)) / (1.0 - exp(-1.0 / STREAM_WIDTH));
    var signed = rise;
    if mu < 0.0 {
        signed = -rise;
    }
    return 0.5 + (forward - 0.5) * signed;
}

// skyfall_core::cloud::frame::stream_weights.
fn stream_weights(mu: f32, g: f32) -> vec2<f32> {
    let w = 0.5 + PHASE_SHARE * (stream_share(mu, g) - 0.5);
    return vec2<f32>(K_THROUGH * w, K_BACK * (1.0 - w));
}

// CloudSplats::source.
// The sun's unscattered beam at a point of a particle of albedo `albedo`: the sun volume keeps
// the δ-M share exp(−Σ(1 − a g²)τ) (the diffuse term's direct beam); single scattering with the
// full phase needs the full extinction exp(−Στ), that share to the power 1/(1 − a g²) (exact
// for a cloud of one albedo). Mirrors skyfall_core::cloud::frame::unscattered.
fn unscattered(gamma: f32, albedo: f32, g: f32) -> f32 {
    return exp(log(max(gamma, 1e-30)) * (1.0 / (1.0 - albedo * g * g)));
}

fn source(x: vec3<f32>, d: vec3<f32>, albedo: f32, w_sky: vec2<f32>, w_sun: vec2<f32>) -> vec3<f32> {
    let g = info.sun_g.w;
    let diffuse_on = info.sun_light.w != 0.0;
    let z = sample_volume(info.zenith_volume, x);
    var sky = info.sky_light.xyz * z.x;
    if diffuse_on {
        sky = info.sky_light.xyz * diffuse_light(z.x, z.y, g, true, w_sky);
    }
    if info.counts.z == 0u {
        return sky;
    }
    let s = sample_volume(info.sun_volume, x);
    let phase = henyey_greenstein(dot(d, info.sun_g.xyz), g);
    var diffuse = 0.0;
    if diffuse_on {
        diffuse = diffuse_light(s.x, s.y, g, false, w_sun);
    }
    return info.sun_light.xyz * (PI * phase * unscattered(s.x, albedo, g) + diffuse) + sky;
}

@compute @workgroup_size(8, 8)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let w = cam.size.x;
    if gid.x >= w || gid.y >= cam.size.y {
        return;
    }
    let i = gid.y * w + gid.x;
    let tile = (gid.y / info.counts.y) * info.counts.x + gid.x / info.counts.y;
    let start = offsets[tile];
    let end = offsets[tile + 1u];
    var alpha = 0.0;
    if end > start {
        let d = normalize(ray_direction(cam, gid.x, gid.y));
        let axial = -dot(d, cam.back.xyz);
        let dep = depth[i];
        var acc = vec3<f32>(0.0);
        var trans = 1.0;
        // The diffuse light's stream weights of this pixel's view (CloudSplats::composite):
        // the sky's stream travels along -Y, the sun's along -sun.
        let w_sky = stream_weights(d.y, info.sun_g.w);
        let w_sun = stream_weights(dot(d, info.sun_g.xyz), info.sun_g.w);
        // The splats end at the first whose centre is farther than the scene by more than
        // any support (CloudSplats::apply_row).
        let beyond = (dep / axial + info.sky_light.w) * 1.001 + 0.01;
        // Near to far (the lists are far to near), stopped once the light from behind is
        // below MIN_TRANSMITTANCE (CloudSplats::apply_row).
        for (var j = end; j > start; j--) {
            let k = indices[j - 1u];
            let s0 = splats[2u * k];
            let s1 = splats[2u * k + 1u];
            if s1.z >= beyond {
                break;
            }
            let centre = s0.xyz;
            let along = dot(centre, d);
            if along <= 0.0 || along * axial >= dep {
                continue;
            }
            let x_near = d * along;
            let off = centre - x_near;
            let rho2 = dot(off, off);
            let r2 = s0.w * s0.w;
            if rho2 >= CUTOFF_RADII * CUTOFF_RADII * r2 {
                continue;
            }
            let t_k = exp(-s1.x * exp(-rho2 / r2));
            let a = 1.0 - t_k;
            acc = acc + source(x_near, d, s1.y, w_sky, w_sun) * (trans * a * s1.y);
            trans = trans * t_k;
            if trans < MIN_TRANSMITTANCE {
                break;
            }
        }
        let e = acc + vec3<f32>(rgb[3u * i], rgb[3u * i + 1u], rgb[3u * i + 2u]) * trans;
        rgb[3u * i] = e.x;
        rgb[3u * i + 1u] = e.y;
        rgb[3u * i + 2u] = e.z;
        alpha = 1.0 - trans;
    }
    if info.counts.w != 0u {
        alpha_out[i] = alpha;
    }
}
