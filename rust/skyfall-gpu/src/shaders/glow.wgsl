// The lights seen through the rain and mist: each one's emitter disc and its glow (a
// Henyey-Greenstein lobe per scattering order), added to the hazed frame. CPU reference:
// skyfall_core::glow (GlowSource::radiance, Glow::apply_row). Prepended with common.wgsl.

struct GlowInfo {
    params: vec4<f32>,   // angular size of a pixel (rad), unused x3
    counts: vec4<u32>,   // number of sources
}

struct GlowSource {
    dir_cut: vec4<f32>,       // unit direction from the eye, cut chord
    flux_radius: vec4<f32>,   // light at the camera (relative x sr), disc radius (rad)
    disc: vec4<f32>,          // disc radiance (relative)
    weights_a: vec4<f32>,     // orders 1-4: weight
    weights_b: vec4<f32>,     // orders 5-6: weight
    asym_a: vec4<f32>,        // orders 1-4: asymmetry
    asym_b: vec4<f32>,        // orders 5-6: asymmetry
}

@group(0) @binding(0) var<uniform> cam: Camera;
@group(0) @binding(1) var<uniform> glow: GlowInfo;
@group(0) @binding(2) var<storage, read> sources: array<GlowSource>;
@group(0) @binding(3) var<storage, read_write> rgb: array<f32>;

// PI comes from the core (pass::shared_constants).

// skyfall_core::glow::henyey_greenstein.
fn henyey_greenstein(g: f32, one_minus_cos: f32) -> f32 {
    let den = (1.0 - g) * (1.0 - g) + 2.0 * g * one_minus_cos;
    return (1.0 - g * g) / (4.0 * PI * den * sqrt(den));
}

// skyfall_core::glow::GlowSource::radiance.
fn source_radiance(s: GlowSource, ray: vec3<f32>) -> vec3<f32> {
    let dv = ray - s.dir_cut.xyz;
    let chord = sqrt(dot(dv, dv));
    if chord > s.dir_cut.w {
        return vec3<f32>(0.0);
    }
    let omc = 0.5 * chord * chord;
    var k = 0.0;
    k += s.weights_a.x * henyey_greenstein(s.asym_a.x, omc);
    k += s.weights_a.y * henyey_greenstein(s.asym_a.y, omc);
    k += s.weights_a.z * henyey_greenstein(s.asym_a.z, omc);
    k += s.weights_a.w * henyey_greenstein(s.asym_a.w, omc);
    k += s.weights_b.x * henyey_greenstein(s.asym_b.x, omc);
    k += s.weights_b.y * henyey_greenstein(s.asym_b.y, omc);
    let cover = clamp((s.flux_radius.w - chord) / glow.params.x + 0.5, 0.0, 1.0);
    return s.flux_radius.xyz * k + s.disc.xyz * cover;
}

@compute @workgroup_size(8, 8)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let w = cam.size.x;
    if gid.x >= w || gid.y >= cam.size.y {
        return;
    }
    let r = ray_direction(cam, gid.x, gid.y);
    let ray = r / sqrt(dot(r, r));
    var add = vec3<f32>(0.0);
    for (var i = 0u; i < glow.counts.x; i++) {
        add += source_radiance(sources[i], ray);
    }
    let i = gid.y * w + gid.x;
    rgb[3u * i] = rgb[3u * i] + add.x;
    rgb[3u * i + 1u] = rgb[3u * i + 1u] + add.y;
    rgb[3u * i + 2u] = rgb[3u * i + 2u] + add.z;
}
