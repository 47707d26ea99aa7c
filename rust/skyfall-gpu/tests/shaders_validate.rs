//! Every WGSL file in `src/shaders/` parses and validates with naga (no device needed), as the
//! passes compile it: `common.wgsl` prepended. The folder is walked, so a new stage's shader
//! is checked without being listed here.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use std::path::Path;

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
