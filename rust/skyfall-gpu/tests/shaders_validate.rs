//! Every WGSL file in `src/shaders/` parses and validates with naga (no device needed), as the
//! passes compile it: `common.wgsl` and the constants shared with the core prepended. The folder is walked, so a new stage's shader
//! is checked without being listed here.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use std::path::Path;

fn validate(name: &str, source: &str) {
    let code = skyfall_gpu::pass::assemble(source);
    let module = naga::front::wgsl::parse_str(&code)
        .unwrap_or_else(|e| panic!("{name}: {}", e.emit_to_string(&code)));
    naga::valid::Validator::new(
        naga::valid::ValidationFlags::all(),
        naga::valid::Capabilities::all(),
    )
    .validate(&module)
    .unwrap_or_else(|e| panic!("{name}: {e:?}"));
}

#[test]
fn every_shader_in_the_folder_is_valid() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("src/shaders");
    let mut names = Vec::new();
    for entry in std::fs::read_dir(&dir).unwrap() {
        let p = entry.unwrap().path();
        let name = p.file_name().unwrap().to_string_lossy().to_string();
        if p.extension().is_some_and(|e| e == "wgsl") && name != "common.wgsl" {
            validate(&name, &std::fs::read_to_string(&p).unwrap());
            names.push(name);
        }
    }
    names.sort();
    // Every pass's shader was among them (the folder was read).
    for want in [
        "cloud.wgsl",
        "glow.wgsl",
        "haze.wgsl",
        "rain.wgsl",
        "scene_raycast.wgsl",
    ] {
        assert!(names.iter().any(|n| n == want), "{want} not in {names:?}");
    }
}

#[test]
fn a_broken_shader_is_refused() {
    let caught = std::panic::catch_unwind(|| validate("broken", "fn main() { let x: f32 = ; }"));
    assert!(caught.is_err());
}

#[test]
fn the_shared_constants_are_the_cores_values_to_the_bit() {
    let code = skyfall_gpu::pass::shared_constants();
    let module = naga::front::wgsl::parse_str(&code).unwrap();
    let mut seen = std::collections::BTreeMap::new();
    for (_, c) in module.constants.iter() {
        let value = match module.global_expressions[c.init] {
            naga::Expression::Literal(naga::Literal::F32(v)) => f64::from(v.to_bits()),
            naga::Expression::Literal(naga::Literal::U32(v)) => f64::from(v),
            ref other => panic!("{other:?}"),
        };
        seen.insert(c.name.clone().unwrap(), value);
    }
    let bits = |v: f32| f64::from(v.to_bits());
    use skyfall_core::frame::scene::{SHADOW_OFFSET_M, SKIP_LEVELS, SUN_RAY_M};
    let want = [
        ("PI", bits(std::f32::consts::PI)),
        ("HALF_PI", bits(std::f32::consts::FRAC_PI_2)),
        (
            "STREAM_WIDTH",
            bits(skyfall_core::cloud::frame::STREAM_WIDTH),
        ),
        ("PHASE_SHARE", bits(skyfall_core::cloud::frame::PHASE_SHARE)),
        ("K_THROUGH", bits(skyfall_core::cloud::frame::K_THROUGH)),
        ("K_BACK", bits(skyfall_core::cloud::frame::K_BACK)),
        (
            "STREAM_DEPTH",
            bits(skyfall_core::cloud::frame::STREAM_DEPTH),
        ),
        ("LUMA_R", bits(skyfall_core::sky::colour::LUMA.x)),
        ("LUMA_G", bits(skyfall_core::sky::colour::LUMA.y)),
        ("LUMA_B", bits(skyfall_core::sky::colour::LUMA.z)),
        (
            "CUTOFF_RADII",
            bits(skyfall_core::cloud::CUTOFF_RADII as f32),
        ),
        (
            "MIN_TRANSMITTANCE",
            bits(skyfall_core::cloud::frame::MIN_TRANSMITTANCE),
        ),
        ("CHANNELS", skyfall_core::sky::illuminance::CHANNELS as f64),
        (
            "WINDOW_ALBEDO_FACTOR",
            bits(skyfall_core::scene::boxes::WINDOW_ALBEDO_FACTOR),
        ),
        ("T_MIN", bits(skyfall_core::scene::raycast::T_MIN)),
        ("SKIP_LEVELS", SKIP_LEVELS as f64),
        ("SHADOW_OFFSET_M", bits(SHADOW_OFFSET_M)),
        ("SUN_RAY_M", bits(SUN_RAY_M)),
        (
            "PARTICLE_LAYERS",
            skyfall_core::particles::streak::PARTICLE_LAYERS.len() as f64,
        ),
        (
            "LAYER_RAIN",
            f64::from(skyfall_core::particles::streak::LAYER_RAIN),
        ),
        ("WET_OFFSET_M", bits(skyfall_core::wet::stage::OFFSET_M)),
        (
            "SHELTER_RAY_M",
            bits(skyfall_core::wet::stage::SHELTER_RAY_M),
        ),
        (
            "MIN_EXPOSURE",
            bits(skyfall_core::wet::film::MIN_EXPOSURE as f32),
        ),
        (
            "STORAGE_MM",
            bits(skyfall_core::wet::film::STORAGE_MM as f32),
        ),
        (
            "WET_FILM_MM",
            bits(skyfall_core::wet::film::WET_FILM_MM as f32),
        ),
        (
            "WATER_INDEX",
            bits(skyfall_core::wet::optics::WATER_INDEX as f32),
        ),
        (
            "FILM_ROUGHNESS",
            bits(skyfall_core::wet::optics::FILM_ROUGHNESS),
        ),
        ("MARCH_STEPS", skyfall_core::wet::stage::MARCH_STEPS as f64),
        (
            "PUDDLE_ROUGHNESS",
            bits(skyfall_core::wet::optics::PUDDLE_ROUGHNESS),
        ),
        (
            "RELIEF_MM",
            bits(skyfall_core::wet::puddles::RELIEF_MM as f32),
        ),
        (
            "RELIEF_SCALE_M",
            bits(skyfall_core::wet::puddles::RELIEF_SCALE_M),
        ),
        (
            "LEVEL_MIN_UP",
            bits(skyfall_core::wet::puddles::LEVEL_MIN_UP),
        ),
        (
            "GRAIN_CELL_M",
            bits(skyfall_core::wet::puddles::GRAIN_CELL_M),
        ),
        (
            "RELIEF_QUANTILES",
            skyfall_core::wet::puddles::RELIEF_QUANTILES as f64,
        ),
        (
            "SNOW_PATCH_M",
            bits(skyfall_core::snow::cover::look::SNOW_PATCH_M),
        ),
        (
            "SNOW_SHARP_BELOW",
            bits(skyfall_core::snow::cover::look::SHARP_BELOW),
        ),
        (
            "SNOW_BLEND_FROM",
            bits(skyfall_core::snow::cover::look::BLEND_FROM),
        ),
        (
            "SNOW_PATCH_OFFSET",
            bits(skyfall_core::snow::cover::look::PATCH_OFFSET),
        ),
        ("FACET_M", bits(skyfall_core::snow::cover::sparkle::FACET_M)),
        (
            "ICE_INDEX",
            bits(skyfall_core::snow::cover::sparkle::ICE_INDEX),
        ),
        (
            "SUN_RADIUS_RAD",
            bits(skyfall_core::snow::cover::sparkle::SUN_RADIUS_RAD),
        ),
        (
            "GLINT_CELL_M",
            bits(skyfall_core::snow::cover::sparkle::GLINT_CELL_M),
        ),
    ];
    assert_eq!(seen.len(), want.len(), "{seen:?}");
    for (name, v) in want {
        assert_eq!(seen.get(name), Some(&v), "{name}");
    }
}
