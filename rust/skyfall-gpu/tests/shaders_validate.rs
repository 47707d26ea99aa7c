//! Every pass's WGSL parses and validates with naga (no device needed).
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

fn validate(name: &str, source: &str) {
    let code = format!("{}\n{}", skyfall_gpu::pass::COMMON_WGSL, source);
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
fn scene_raycast_wgsl_is_valid() {
    validate(
        "scene_raycast",
        include_str!("../src/shaders/scene_raycast.wgsl"),
    );
}

#[test]
fn haze_wgsl_is_valid() {
    validate("haze", include_str!("../src/shaders/haze.wgsl"));
}

#[test]
fn rain_wgsl_is_valid() {
    validate("rain", include_str!("../src/shaders/rain.wgsl"));
}

#[test]
fn glow_wgsl_is_valid() {
    validate("glow", include_str!("../src/shaders/glow.wgsl"));
}

#[test]
fn windshield_wgsl_is_valid() {
    validate(
        "windshield_field",
        include_str!("../src/shaders/windshield_field.wgsl"),
    );
    validate(
        "windshield_refract",
        include_str!("../src/shaders/windshield_refract.wgsl"),
    );
}
