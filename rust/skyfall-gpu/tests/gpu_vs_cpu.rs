//! GPU passes against their CPU references, on whatever Vulkan adapter exists (lavapipe in CI).
//! `make test` installs lavapipe when it is missing, so these run everywhere it runs.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use glam::{Mat3, Vec3};
use skyfall_core::frame::layers::Layer;
use skyfall_core::frame::scene::SceneLight;
use skyfall_core::frame::stages::Frame;
use skyfall_core::frame::{FrameOut, SceneRef, draw, render_frame};
use skyfall_core::haze::Haze;
use skyfall_core::rain::drops::RainRegion;
use skyfall_core::rain::streaks::{RainFrame, RainShading};
use skyfall_core::scene::boxes::{BoxScene, SceneBox};
use skyfall_core::scene::camera::{Camera, ThinLens};
use skyfall_core::scene::lights::Light;
use skyfall_core::sky::ambient::{AmbientMap, scene_bounds};
use skyfall_core::sky::cie::SkyKind;
use skyfall_core::sky::illuminance::SkyTable;
use skyfall_core::sky::{Sky, sun_direction};
use skyfall_gpu::AdapterChoice;
use skyfall_gpu::context::GpuError;
use skyfall_gpu::frame::GpuRenderer;

fn street() -> (BoxScene, Camera) {
    let b = |min: [f32; 3], max: [f32; 3], a: [f32; 3]| SceneBox {
        min_m: Vec3::from(min),
        max_m: Vec3::from(max),
        albedo: Vec3::from(a),
    };
    let boxes = vec![
        b([-12.0, 0.0, -60.0], [-5.0, 14.0, -8.0], [0.55, 0.5, 0.45]),
        b([5.0, 0.0, -50.0], [11.0, 9.0, -6.0], [0.4, 0.42, 0.5]),
        b([-3.0, 0.0, -90.0], [3.0, 25.0, -80.0], [0.6, 0.6, 0.6]),
    ];
    let scene = BoxScene::new(boxes, true, Vec3::splat(0.12)).unwrap();
    let yaw = 0.1f32;
    let rot = Mat3::from_rotation_y(yaw) * Mat3::from_rotation_x(0.05);
    let cam = Camera::new(
        96,
        64,
        [70.0, 70.0, 48.0, 32.0],
        Vec3::new(0.5, 1.6, 0.0),
        rot,
    )
    .unwrap();
    (scene, cam)
}

/// The scene's ambient-light map under `sky`, 2 m spacing.
fn lit(scene: &BoxScene, cam: &Camera, sky: &Sky) -> AmbientMap {
    let s = SkyTable::new(sky, 64).unwrap();
    let (lo, hi) = scene_bounds(scene, &[cam.eye()], 2.0);
    AmbientMap::build(scene, &s, lo, hi, 2.0).unwrap()
}

fn max_abs(a: &[f32], b: &[f32]) -> (f32, usize) {
    let mut worst = 0.0f32;
    let mut big = 0;
    for (x, y) in a.iter().zip(b) {
        let d = if x.is_infinite() && y.is_infinite() && x == y {
            0.0
        } else {
            (x - y).abs()
        };
        if d > 1e-3 {
            big += 1;
        }
        worst = worst.max(d);
    }
    (worst, big)
}

/// How many of `gpu`'s values differ from the CPU's `cpu` by more than `tol` relative (to the
/// CPU's value, or absolute below 1).
fn differing(cpu: &[f32], gpu: &[f32], tol: f32) -> usize {
    cpu.iter()
        .zip(gpu)
        .filter(|(x, y)| (*x - *y).abs() > tol * x.abs().max(1.0))
        .count()
}

/// A box scene's rgb on both backends: at most 0.5 % of the values more than 0.1 % apart (a
/// silhouette moved by f32 rounding) and 1 % more than 0.02 % apart.
fn assert_rgb_agrees(cpu: &[f32], gpu: &[f32]) {
    let (coarse, fine) = (differing(cpu, gpu, 1e-3), differing(cpu, gpu, 2e-4));
    assert!(
        coarse * 200 <= cpu.len(),
        "{coarse} rgb values differ by > 0.1 %"
    );
    assert!(
        fine * 100 <= cpu.len(),
        "{fine} rgb values differ by > 0.02 %"
    );
}

#[test]
fn gpu_matches_cpu_on_the_box_scene_and_on_a_photo() {
    let gpu = GpuRenderer::new(AdapterChoice::Any)
        .expect("a Vulkan adapter (lavapipe) is required: make test installs it");
    let (scene, cam) = street();
    let haze = Haze::new(0.004, [3.0 / 7.0; 3], 1200.0).unwrap();
    let sky = Sky::new(SkyKind::Overcast, 0.0, 1000.0).unwrap();
    let amb = lit(&scene, &cam, &sky);
    let light = SceneLight::new(&sky, &amb);
    let c = render_frame(
        &Frame::new(SceneRef::Boxes(&scene), &cam, &light).with_effects(Some(&haze), None, None),
    )
    .unwrap();
    let g = gpu
        .render_frame(
            &Frame::new(SceneRef::Boxes(&scene), &cam, &light).with_effects(
                Some(&haze),
                None,
                None,
            ),
        )
        .unwrap();
    // Silhouette pixels may pick another surface when f32 rounding differs (FMA): allow 0.5 %.
    let (_, rgb_big) = max_abs(&c.rgb, &g.rgb);
    let (_, depth_big) = max_abs(&c.depth_m, &g.depth_m);
    assert!(rgb_big * 200 <= c.rgb.len(), "{rgb_big} rgb values differ");
    assert!(
        depth_big * 200 <= c.depth_m.len(),
        "{depth_big} depths differ"
    );
    // Haze alone on identical inputs: exp differs by a few ulps.
    let photo = SceneRef::Photo {
        rgb: &c.rgb,
        depth_m: &c.depth_m,
    };
    let c2 = render_frame(&Frame::new(photo, &cam, &light).with_effects(Some(&haze), None, None))
        .unwrap();
    let g2 = gpu
        .render_frame(&Frame::new(photo, &cam, &light).with_effects(Some(&haze), None, None))
        .unwrap();
    let (worst, _) = max_abs(&c2.rgb, &g2.rgb);
    assert!(worst < 1e-5, "haze max abs diff {worst}");
    let (worst_t, _) = max_abs(
        c2.layer(Layer::Transmittance).unwrap(),
        g2.layer(Layer::Transmittance).unwrap(),
    );
    assert!(worst_t < 1e-5, "transmittance max abs diff {worst_t}");
    assert_eq!(c2.depth_m, g2.depth_m);
}

#[test]
fn gpu_rain_matches_cpu_rain() {
    let gpu = GpuRenderer::new(AdapterChoice::Any).unwrap();
    let (scene, cam) = street();
    let region = RainRegion::new(40.0, &[1.0, 1.4, 2.0], 4.0, [2.0, 0.0, 0.0], 0.7, 11).unwrap();
    let lamp = Light::from_row(
        &[
            -1.0, 2.5, -3.0, 1.0, 0.8, 0.6, 800.0, 0.0, 0.0, 0.0, 0.0, 0.0,
        ],
        0,
    )
    .unwrap();
    let shading = RainShading {
        lights: vec![lamp],
        sky_illuminance_lux: 50.0,
        ..RainShading::open_sky()
    };
    let rf = RainFrame {
        region: &region,
        exposure_s: 1.0 / 30.0,
        camera_velocity_m_s: Vec3::new(0.0, 0.0, -8.0),
        lens: None,
        ground: true,
        shelter: &scene.boxes,
        shading: &shading,
    };
    // Rain over identical backgrounds: a photo of the CPU's box frame.
    let sky = Sky::new(SkyKind::Overcast, 0.0, 1000.0).unwrap();
    let amb = lit(&scene, &cam, &sky);
    let light = SceneLight::new(&sky, &amb);
    let bg = render_frame(
        &Frame::new(SceneRef::Boxes(&scene), &cam, &light).with_effects(None, None, None),
    )
    .unwrap();
    let photo = SceneRef::Photo {
        rgb: &bg.rgb,
        depth_m: &bg.depth_m,
    };
    let c =
        render_frame(&Frame::new(photo, &cam, &light).with_effects(None, Some(&rf), None)).unwrap();
    let g = gpu
        .render_frame(&Frame::new(photo, &cam, &light).with_effects(None, Some(&rf), None))
        .unwrap();
    let ((cs, _), (gs, gd)) = (c.rain.unwrap(), g.rain.unwrap());
    assert_eq!(c.rain, g.rain);
    assert!(cs.streaks > 100);
    let (ga, gz) = (
        g.layer(Layer::RainAlpha).unwrap(),
        g.layer(Layer::RainDepth).unwrap(),
    );
    let (worst_a, _) = max_abs(c.layer(Layer::RainAlpha).unwrap(), ga);
    let (worst_rgb, _) = max_abs(&c.rgb, &g.rgb);
    assert!(worst_a < 1e-4, "rain alpha max abs diff {worst_a}");
    assert!(worst_rgb < 1e-4, "rgb max abs diff {worst_rgb}");
    let (worst_z, _) = max_abs(c.layer(Layer::RainDepth).unwrap(), gz);
    assert!(worst_z < 1e-3, "rain depth max abs diff {worst_z}");
    // Read back into the caller's buffers (numpy's, from Python): every value overwritten.
    let n = cam.pixels();
    let (mut rgb, mut d, mut a, mut rd) = (
        vec![f32::NAN; 3 * n],
        vec![f32::NAN; n],
        vec![f32::NAN; n],
        vec![f32::NAN; n],
    );
    let out = FrameOut::from_layers(
        &mut rgb,
        &mut d,
        [
            (Layer::RainAlpha, &mut a[..]),
            (Layer::RainDepth, &mut rd[..]),
        ],
    );
    let (stats, drops) = gpu
        .draw(
            &Frame::new(photo, &cam, &light).with_effects(None, Some(&rf), None),
            out,
        )
        .map(|(r, _)| r)
        .unwrap()
        .unwrap();
    assert_eq!((stats, drops), (gs, gd));
    let bits = |v: &[f32]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
    assert_eq!(bits(&rgb), bits(&g.rgb));
    assert_eq!(bits(&d), bits(&g.depth_m));
    assert_eq!(bits(&a), bits(ga));
    assert_eq!(bits(&rd), bits(gz));
    let short = FrameOut::from_layers(
        &mut rgb[3..],
        &mut d,
        [
            (Layer::RainAlpha, &mut a[..]),
            (Layer::RainDepth, &mut rd[..]),
        ],
    );
    assert!(
        gpu.draw(
            &Frame::new(photo, &cam, &light).with_effects(None, Some(&rf), None),
            short
        )
        .map(|(r, _)| r)
        .is_err()
    );
    // Rain that does not fit the device's storage buffers is an error that names the streaks,
    // not a wgpu failure: the frame's buffers fit this limit, the streak list does not.
    let mut small = GpuRenderer::new(AdapterChoice::Any).unwrap();
    let frame_bytes = (3 * n * 4) as u64;
    small.ctx.limits.max_storage_buffer_binding_size = frame_bytes;
    assert!(
        small
            .render_frame(&Frame::new(photo, &cam, &light).with_effects(None, None, None))
            .is_ok()
    );
    assert!((gs.streaks * 64) as u64 > frame_bytes);
    let err = small
        .render_frame(&Frame::new(photo, &cam, &light).with_effects(None, Some(&rf), None))
        .unwrap_err();
    assert!(
        matches!(err, GpuError::TooLarge { .. }) && err.to_string().contains("streaks"),
        "{err}"
    );
}

#[test]
fn gpu_rain_matches_cpu_rain_through_a_lens() {
    // Defocus is made on the CPU (the streaks' widths, ends and α), so the GPU's compositor
    // draws the blurred streaks as it draws any: the same frame as the CPU's, and not the
    // pinhole's. f/0.7 on a 200 mm wide sensor (f = 70 px · 200 mm / 96 px = 146 mm) focused
    // at 10 m: blur circles up to the cap, 6 px here.
    let gpu = GpuRenderer::new(AdapterChoice::Any).unwrap();
    let (scene, cam) = street();
    let region = RainRegion::new(40.0, &[1.0, 1.4, 2.0], 4.0, [2.0, 0.0, 0.0], 0.7, 11).unwrap();
    let shading = RainShading::open_sky();
    let lens = ThinLens::new(0.7, 10.0, 200.0).unwrap();
    let pinhole = RainFrame {
        region: &region,
        exposure_s: 1.0 / 60.0,
        camera_velocity_m_s: Vec3::ZERO,
        lens: None,
        ground: true,
        shelter: &[],
        shading: &shading,
    };
    let rf = RainFrame {
        lens: Some(lens.defocus(&cam).unwrap()),
        ..pinhole
    };
    let sky = Sky::new(SkyKind::Overcast, 0.0, 1000.0).unwrap();
    let amb = lit(&scene, &cam, &sky);
    let light = SceneLight::new(&sky, &amb);
    let bg = render_frame(
        &Frame::new(SceneRef::Boxes(&scene), &cam, &light).with_effects(None, None, None),
    )
    .unwrap();
    let photo = SceneRef::Photo {
        rgb: &bg.rgb,
        depth_m: &bg.depth_m,
    };
    let c =
        render_frame(&Frame::new(photo, &cam, &light).with_effects(None, Some(&rf), None)).unwrap();
    let g = gpu
        .render_frame(&Frame::new(photo, &cam, &light).with_effects(None, Some(&rf), None))
        .unwrap();
    let p = render_frame(&Frame::new(photo, &cam, &light).with_effects(None, Some(&pinhole), None))
        .unwrap();
    assert_eq!(c.rain, g.rain);
    assert!(c.rain.unwrap().0.streaks > 100);
    let (ca, ga, pa) = (
        c.layer(Layer::RainAlpha).unwrap(),
        g.layer(Layer::RainAlpha).unwrap(),
        p.layer(Layer::RainAlpha).unwrap(),
    );
    let (worst_a, _) = max_abs(ca, ga);
    let (worst_rgb, _) = max_abs(&c.rgb, &g.rgb);
    let (worst_z, _) = max_abs(
        c.layer(Layer::RainDepth).unwrap(),
        g.layer(Layer::RainDepth).unwrap(),
    );
    eprintln!(
        "through a lens, GPU vs CPU: alpha {worst_a:.2e}, rgb {worst_rgb:.2e}, depth {worst_z:.2e}"
    );
    assert!(worst_a < 1e-4, "rain alpha max abs diff {worst_a}");
    assert!(worst_rgb < 1e-4, "rgb max abs diff {worst_rgb}");
    assert!(worst_z < 1e-3, "rain depth max abs diff {worst_z}");
    let (_, changed) = max_abs(ca, pa);
    assert!(
        changed * 10 > ca.len(),
        "{changed} pixels differ from the pinhole's"
    );
}

#[test]
fn gpu_matches_cpu_under_a_cie_sky_with_sky_visibility() {
    let gpu = GpuRenderer::new(AdapterChoice::Any).unwrap();
    let (scene, cam) = street();
    // CIE type 12 (clear sky) with the sun low in the south-west, and rain reshaping it.
    let kind = SkyKind::general(12, Some(sun_direction(25.0, 220.0))).unwrap();
    let sky = Sky::new(kind, 2e-3, 900.0).unwrap();
    let amb = lit(&scene, &cam, &sky);
    let light = SceneLight::new(&sky, &amb);
    let c = render_frame(
        &Frame::new(SceneRef::Boxes(&scene), &cam, &light).with_effects(None, None, None),
    )
    .unwrap();
    let g = gpu
        .render_frame(
            &Frame::new(SceneRef::Boxes(&scene), &cam, &light).with_effects(None, None, None),
        )
        .unwrap();
    // Relative: the clear sky reaches 12 E/π and the WGSL evaluates it in f32 (the CPU in f64).
    // Away from silhouettes the sky and the map's trilinear sample agree to f32 rounding.
    assert_rgb_agrees(&c.rgb, &g.rgb);
    // The map really shades: a wall's pixel differs from the open-sky vertical value somewhere.
    assert!(amb.values.chunks(5).any(|v| v[0] < 0.9));
}

#[test]
fn pooled_buffers_give_the_same_frames_and_do_not_grow() {
    // Frames of one size reuse the pool's buffers: the same bits as the first frame (every
    // pass overwrites what it writes, so old contents never show), and no more pooled memory
    // after the second frame than after the first. A frame of another size in between, or
    // rain with fewer streaks, does not leak into the next.
    let gpu = GpuRenderer::new(AdapterChoice::Any).unwrap();
    let (scene, cam) = street();
    let sky = Sky::new(SkyKind::Overcast, 0.0, 1000.0).unwrap();
    let amb = lit(&scene, &cam, &sky);
    let light = SceneLight::new(&sky, &amb);
    let h = Haze::new(0.01, [0.4; 3], 500.0).unwrap();
    let region = RainRegion::new(30.0, &[1.0, 1.5, 2.0], 4.0, [1.0, 0.0, 0.0], 0.2, 3).unwrap();
    let shading = RainShading::open_sky();
    let rf = RainFrame {
        region: &region,
        exposure_s: 1.0 / 30.0,
        camera_velocity_m_s: Vec3::ZERO,
        lens: None,
        ground: true,
        shelter: &[],
        shading: &shading,
    };
    let boxes = SceneRef::Boxes(&scene);
    assert_eq!(gpu.pooled_bytes(), 0);
    let first = gpu
        .render_frame(&Frame::new(boxes, &cam, &light).with_effects(Some(&h), Some(&rf), None))
        .unwrap();
    let after_one = gpu.pooled_bytes();
    assert!(after_one >= (cam.pixels() * 4 * 7) as u64, "{after_one}");
    let small = Camera::new(
        40,
        30,
        [30.0, 30.0, 20.0, 15.0],
        Vec3::new(0.0, 1.6, 0.0),
        Mat3::IDENTITY,
    )
    .unwrap();
    gpu.render_frame(&Frame::new(boxes, &small, &light).with_effects(None, None, None))
        .unwrap();
    let dry = RainRegion::new(1.0, &[1.0], 2.0, [0.0; 3], 0.0, 9).unwrap();
    let drizzle = RainFrame { region: &dry, ..rf };
    gpu.render_frame(&Frame::new(boxes, &cam, &light).with_effects(Some(&h), Some(&drizzle), None))
        .unwrap();
    let again = gpu
        .render_frame(&Frame::new(boxes, &cam, &light).with_effects(Some(&h), Some(&rf), None))
        .unwrap();
    assert_eq!(again, first);
    let settled = gpu.pooled_bytes();
    gpu.render_frame(&Frame::new(boxes, &cam, &light).with_effects(Some(&h), Some(&rf), None))
        .unwrap();
    assert_eq!(gpu.pooled_bytes(), settled);
}

#[test]
fn gpu_matches_cpu_with_lamps_shadows_and_glows() {
    // The street at dusk (30 lx) in haze: lamps over the street (one behind a building: no
    // glow), a spot aimed at the camera (its disc and glow) and one aimed down the road (its
    // pool), the surfaces lit and shadowed, the discs and glows over the hazed frame.
    let gpu = GpuRenderer::new(AdapterChoice::Any).unwrap();
    let (scene, cam) = street();
    let haze = Haze::new(0.01, [0.05; 3], 900.0).unwrap();
    let sky = Sky::new(SkyKind::Overcast, 0.0, 1000.0).unwrap();
    let amb = lit(&scene, &cam, &sky);
    let lamp = |x: f32, z: f32| Light {
        position_m: Vec3::new(x, 5.0, z),
        intensity_cd: 2000.0,
        color: Vec3::new(1.0, 0.8, 0.55),
        spot: None,
    };
    let spot = |z: f32, axis: Vec3| Light {
        position_m: Vec3::new(-1.5, 0.7, z),
        intensity_cd: 15000.0,
        color: Vec3::ONE,
        spot: Some((axis.normalize(), 0.8, 0.9)),
    };
    let lights = [
        lamp(-4.0, -10.0),
        lamp(4.0, -20.0),
        lamp(-4.0, -35.0),
        lamp(-14.0, -30.0), // behind the left block
        spot(-25.0, Vec3::new(0.05, -0.05, 1.0)),
        spot(-5.0, Vec3::new(0.0, -0.3, -1.0)),
    ];
    let light = SceneLight::new(&sky, &amb).with_lights(&lights, 30.0);
    let c = render_frame(
        &Frame::new(SceneRef::Boxes(&scene), &cam, &light).with_effects(Some(&haze), None, None),
    )
    .unwrap();
    let g = gpu
        .render_frame(
            &Frame::new(SceneRef::Boxes(&scene), &cam, &light).with_effects(
                Some(&haze),
                None,
                None,
            ),
        )
        .unwrap();
    // As the box scene without lights: silhouettes (and a light at a skip level's edge) may
    // differ where f32 rounding differs; everywhere else f32 rounding.
    assert_rgb_agrees(&c.rgb, &g.rgb);
    // The lights really show: against the frame without them, the lamps lit much of it, and
    // the hidden lamp has no glow source.
    let dark = render_frame(
        &Frame::new(
            SceneRef::Boxes(&scene),
            &cam,
            &SceneLight::new(&sky, &amb).with_lights(&[], 30.0),
        )
        .with_effects(Some(&haze), None, None),
    )
    .unwrap();
    let brighter = c
        .rgb
        .iter()
        .zip(&dark.rgb)
        .filter(|(x, y)| **x > 1.2 * **y + 1e-3)
        .count();
    assert!(brighter * 4 > c.rgb.len(), "{brighter}");
    let glow =
        skyfall_core::glow::Glow::prepare(&cam, &scene, &lights, |d| 0.01 * d, 30.0).unwrap();
    assert_eq!(
        glow.sources.len(),
        4,
        "the hidden lamp and the spot turned away have none"
    );
}

#[test]
fn gpu_snow_and_rain_match_the_cpu_in_one_list() {
    // Flakes (every sprite, near ones several pixels wide) and drops in one far-to-near list
    // over a photo of the CPU's box frame: the same counts, rgb and each effect's layers.
    use skyfall_core::snow::SNOW_ALBEDO;
    use skyfall_core::snow::flakes::SnowRegion;
    use skyfall_core::snow::streaks::{SnowFrame, SnowOpacity};
    let gpu = GpuRenderer::new(AdapterChoice::Any).unwrap();
    let (scene, cam) = street();
    let sky = Sky::new(SkyKind::Overcast, 0.0, 1000.0).unwrap();
    let amb = lit(&scene, &cam, &sky);
    let light = SceneLight::new(&sky, &amb);
    let bg = render_frame(
        &Frame::new(SceneRef::Boxes(&scene), &cam, &light).with_effects(None, None, None),
    )
    .unwrap();
    let photo = SceneRef::Photo {
        rgb: &bg.rgb,
        depth_m: &bg.depth_m,
    };
    let rain = RainRegion::new(40.0, &[1.0, 1.4, 2.0], 4.0, [2.0, 0.0, 0.0], 0.7, 11).unwrap();
    let shading = RainShading::open_sky();
    let rf = RainFrame {
        region: &rain,
        exposure_s: 1.0 / 30.0,
        camera_velocity_m_s: Vec3::ZERO,
        lens: None,
        ground: true,
        shelter: &scene.boxes,
        shading: &shading,
    };
    let snow_shading = RainShading {
        reflectance: 1.0,
        drop_radiance: SNOW_ALBEDO,
        ..RainShading::open_sky()
    };
    for opacity in [SnowOpacity::Extinction, SnowOpacity::Levels] {
        let region = SnowRegion::new(3.0, 5.0, [2.0, 0.0, 1.0], 0.7, 11).unwrap();
        let sf = SnowFrame {
            region: &region,
            exposure_s: 1.0 / 30.0,
            camera_velocity_m_s: Vec3::ZERO,
            lens: None,
            ground: true,
            shelter: &scene.boxes,
            shading: &snow_shading,
            opacity,
            haze: Some(skyfall_core::haze::Haze::new(0.01, [1.0; 3], f32::INFINITY).unwrap()),
        };
        for rain in [None, Some(&rf)] {
            let c =
                render_frame(&Frame::new(photo, &cam, &light).with_effects(None, rain, Some(&sf)))
                    .unwrap();
            let g = gpu
                .render_frame(&Frame::new(photo, &cam, &light).with_effects(None, rain, Some(&sf)))
                .unwrap();
            assert_eq!(c.rain, g.rain);
            assert_eq!(
                c.layers.0.iter().filter(|l| l.is_some()).count(),
                if rain.is_some() { 3 } else { 1 }
            );
            let n = cam.pixels();
            let (mut rgb, mut d) = (vec![0.0; 3 * n], vec![0.0; n]);
            let (mut a, mut z, mut s) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
            let layers: Vec<(Layer, &mut [f32])> = match rain {
                Some(_) => vec![
                    (Layer::RainAlpha, &mut a[..]),
                    (Layer::RainDepth, &mut z[..]),
                    (Layer::SnowAlpha, &mut s[..]),
                ],
                None => vec![(Layer::SnowAlpha, &mut s[..])],
            };
            let (_, stats) = draw(
                &Frame::new(photo, &cam, &light).with_effects(None, rain, Some(&sf)),
                FrameOut::from_layers(&mut rgb, &mut d, layers),
            )
            .unwrap();
            let stats = stats.unwrap();
            assert!(stats.streaks > 300, "{stats:?}");
            let cs = c.layer(Layer::SnowAlpha).unwrap();
            assert_eq!(cs, &s[..]);
            let (worst_s, _) = max_abs(cs, g.layer(Layer::SnowAlpha).unwrap());
            // The shader's cos may put a star's arm edge on the other side of a pixel centre:
            // a few pixels differ by an arm's step, the rest by rounding.
            let off = differing(cs, g.layer(Layer::SnowAlpha).unwrap(), 1e-4);
            assert!(
                off * 200 <= n && worst_s < 0.05,
                "{off} snow alpha values differ, worst {worst_s}"
            );
            assert_rgb_agrees(&c.rgb, &g.rgb);
            if rain.is_some() {
                let (worst_a, _) = max_abs(
                    c.layer(Layer::RainAlpha).unwrap(),
                    g.layer(Layer::RainAlpha).unwrap(),
                );
                assert!(worst_a < 1e-4, "rain alpha max abs diff {worst_a}");
                assert!(c.layer(Layer::RainAlpha).unwrap().iter().any(|&x| x > 1e-3));
            }
        }
    }
}

#[test]
fn gpu_matches_cpu_with_a_snow_cover_on_boxes_and_on_a_photo() {
    use skyfall_core::snow::cover::{CoverParams, Grid, HeightField, SnowRender, accumulate};
    let gpu = GpuRenderer::new(AdapterChoice::Any).unwrap();
    let (scene, cam) = street();
    let sky = Sky::new(SkyKind::Overcast, 0.0, 1000.0).unwrap();
    let amb = lit(&scene, &cam, &sky);
    let grid = Grid::covering([-20.0, -100.0], [20.0, 10.0], 0.5).unwrap();
    let field = HeightField::from_boxes(&scene, grid).unwrap();
    let weather = skyfall_core::weather::Weather {
        rain_rate_mm_h: 0.0,
        snow_rate_mm_h: 5.0,
        snow_density_kg_m3: 100.0,
        snow_near_m: 8.0,
        snow_opacity: skyfall_core::snow::streaks::SnowOpacity::Extinction,
        visibility_m: f64::INFINITY,
        sky_illuminance_lux: 10_000.0,
        wind_m_s: [0.3, 0.0, 0.2],
        rain_near_m: 5.0,
        rain_far_m: None,
        rain_diameters_mm: vec![1.0],
        rain_streaks: true,
        rain_method: skyfall_core::rain::drops::RainMethod::Billboards,
        rain_sheltered: true,
        rain_duration_s: Some(0.0),
        dry_s: 0.0,
        sky: skyfall_core::weather::SkySpec::Overcast,
        sun_deg: None,
        cloud_base_m: None,
        sun_illuminance_lux: None,
    };
    let params = CoverParams {
        duration_s: 3600.0,
        dt_s: 300.0,
        roughness: 0.2,
        seed: 1,
        turbulence: 0.4,
        redistribute: true,
    };
    let cover = accumulate(field, &weather, &params, None).unwrap();
    let snow = SnowRender::boxes(&cover).unwrap();
    let light = SceneLight::new(&sky, &amb).with_snow(Some(&snow));
    let c = render_frame(
        &Frame::new(SceneRef::Boxes(&scene), &cam, &light).with_effects(None, None, None),
    )
    .unwrap();
    let g = gpu
        .render_frame(
            &Frame::new(SceneRef::Boxes(&scene), &cam, &light).with_effects(None, None, None),
        )
        .unwrap();
    assert_rgb_agrees(&c.rgb, &g.rgb);
    let (c_snow, g_snow) = (
        c.layer(Layer::SnowDepth).unwrap(),
        g.layer(Layer::SnowDepth).unwrap(),
    );
    let covered = c_snow.iter().filter(|&&d| d > 0.0).count();
    assert!(covered * 8 > c_snow.len(), "{covered} pixels under snow");
    assert!(differing(c_snow, g_snow, 1e-3) * 200 <= c_snow.len());
    let (_, depth_big) = max_abs(&c.depth_m, &g.depth_m);
    assert!(
        depth_big * 200 <= c.depth_m.len(),
        "{depth_big} depths differ"
    );
    // Without the cover the GPU frame is the one it always was.
    let bare = SceneLight::new(&sky, &amb);
    let g0 = gpu
        .render_frame(
            &Frame::new(SceneRef::Boxes(&scene), &cam, &bare).with_effects(None, None, None),
        )
        .unwrap();
    assert!(g0.layer(Layer::SnowDepth).is_none());
    assert!(max_abs(&g0.rgb, &g.rgb).1 > 1000);
    // A photo of the bare frame under the same cover: the CPU's whitening, uploaded.
    let photo = SceneRef::Photo {
        rgb: &g0.rgb,
        depth_m: &g0.depth_m,
    };
    let pcover = accumulate(
        HeightField::from_depth_map(&cam, &g0.depth_m, 0.5).unwrap(),
        &weather,
        &params,
        None,
    )
    .unwrap();
    let psnow = SnowRender::photo(&pcover, &cam, &g0.depth_m, Vec3::ONE).unwrap();
    let plight = SceneLight::new(&sky, &amb).with_snow(Some(&psnow));
    let cp =
        render_frame(&Frame::new(photo, &cam, &plight).with_effects(None, None, None)).unwrap();
    let gp = gpu
        .render_frame(&Frame::new(photo, &cam, &plight).with_effects(None, None, None))
        .unwrap();
    assert_eq!(cp.rgb, gp.rgb);
    assert_eq!(
        cp.layer(Layer::SnowDepth).unwrap(),
        gp.layer(Layer::SnowDepth).unwrap()
    );
    assert!(cp.layer(Layer::SnowDepth).unwrap().iter().any(|&d| d > 0.0));
}

#[test]
fn gpu_draws_the_whole_windshield_in_focus_and_defocused() {
    // The windshield stage wholly on the device: drops, their defocus blur (the CPU's running
    // f64 box sums against the GPU's f32 window sums) and the blades, against the CPU's stage.
    use skyfall_core::windshield::sim::Metaball;
    use skyfall_core::windshield::stage::{Blade, Glass};
    let gpu = GpuRenderer::new(AdapterChoice::Any).unwrap();
    let (scene, cam) = street();
    let sky = Sky::new(SkyKind::Overcast, 0.0, 1000.0).unwrap();
    let amb = lit(&scene, &cam, &sky);
    let light = SceneLight::new(&sky, &amb);
    let mut metaballs = Vec::new();
    for k in 0..60 {
        let f = f64::from(k);
        metaballs.push(Metaball {
            x_mm: (f * 97.3) % 600.0,
            y_mm: (f * 53.9) % 400.0,
            radius_mm: 2.0 + (f * 1.7) % 9.0,
        });
    }
    let glass = Glass {
        width_mm: 600.0,
        height_mm: 400.0,
        tilt_deg: 60.0,
        contact_deg: 30.0,
        metaballs,
        blades: vec![
            Blade {
                pivot_mm: [150.0, 390.0],
                angle_rad: 0.9,
                length_mm: 300.0,
                width_mm: 30.0,
            },
            Blade {
                pivot_mm: [420.0, 390.0],
                angle_rad: 1.7,
                length_mm: 280.0,
                width_mm: 3.0,
            },
        ],
    };
    // f/0.7 on a 200 mm sensor focused at 10 m: the glass (0.2 m or more away) blurs by the cap.
    let lens = ThinLens::new(0.7, 10.0, 200.0).unwrap();
    let plain = render_frame(&Frame::new(SceneRef::Boxes(&scene), &cam, &light)).unwrap();
    let mut seen = Vec::new();
    for defocus in [None, Some(lens.defocus(&cam).unwrap())] {
        let frame = Frame::new(SceneRef::Boxes(&scene), &cam, &light)
            .with_windshield(Some(&glass), defocus);
        let c = render_frame(&frame).unwrap();
        let g = gpu.render_frame(&frame).unwrap();
        for l in [Layer::DropMask, Layer::DropHeight] {
            let (worst, _) = max_abs(c.layer(l).unwrap(), g.layer(l).unwrap());
            assert!(worst < 1e-4, "{l:?} max abs diff {worst}");
        }
        let (worst, big) = max_abs(&c.rgb, &g.rgb);
        eprintln!("windshield defocus {defocus:?}: rgb max diff {worst:.2e}, {big} > 1e-3");
        assert_rgb_agrees(&c.rgb, &g.rgb);
        // the blades show (dark) on both, the drops change the frame
        let dark = |rgb: &[f32]| {
            rgb.chunks(3)
                .zip(plain.rgb.chunks(3))
                .filter(|(a, p)| a[1] < 0.5 * p[1] && p[1] > 0.1)
                .count()
        };
        assert!(dark(&g.rgb) > 40, "{} blade pixels", dark(&g.rgb));
        assert!(dark(&g.rgb).abs_diff(dark(&c.rgb)) <= dark(&c.rgb) / 50);
        seen.push(g.rgb);
    }
    // the blur changed the frame (not the in-focus drops again)
    let (_, changed) = max_abs(&seen[0], &seen[1]);
    assert!(changed * 20 > seen[0].len(), "{changed} values blurred");
}
