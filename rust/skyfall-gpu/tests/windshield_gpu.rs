//! The windshield pass on the GPU (lavapipe where there is no GPU) against the CPU's
//! `skyfall_core::windshield::render`: the height map, the normals' effect (the refraction of a
//! textured frame, offset and Snell) and the coverage, by SSIM ≥ 0.99 and small differences.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use skyfall_core::windshield::render::{self, RefractMode, Refraction, WATER_INDEX};
use skyfall_gpu::AdapterChoice;
use skyfall_gpu::context::GpuContext;
use skyfall_gpu::windshield::WindshieldPass;

/// Mean SSIM over 8 × 8 windows (step 4) of one channel, constants of Wang et al. 2004 for the
/// data range `range`.
fn ssim(a: &[f32], b: &[f32], w: usize, h: usize, range: f64) -> f64 {
    let (c1, c2) = ((0.01 * range).powi(2), (0.03 * range).powi(2));
    let mut total = 0.0;
    let mut count = 0.0;
    for y in (0..h.saturating_sub(7)).step_by(4) {
        for x in (0..w.saturating_sub(7)).step_by(4) {
            let (mut ma, mut mb, mut va, mut vb, mut cab) = (0.0, 0.0, 0.0, 0.0, 0.0);
            for j in y..y + 8 {
                for i in x..x + 8 {
                    ma += a[j * w + i] as f64;
                    mb += b[j * w + i] as f64;
                }
            }
            ma /= 64.0;
            mb /= 64.0;
            for j in y..y + 8 {
                for i in x..x + 8 {
                    let (da, db) = (a[j * w + i] as f64 - ma, b[j * w + i] as f64 - mb);
                    va += da * da;
                    vb += db * db;
                    cab += da * db;
                }
            }
            let (va, vb, cab) = (va / 63.0, vb / 63.0, cab / 63.0);
            total += ((2.0 * ma * mb + c1) * (2.0 * cab + c2))
                / ((ma * ma + mb * mb + c1) * (va + vb + c2));
            count += 1.0;
        }
    }
    total / count
}

fn channel(rgb: &[f32], c: usize) -> Vec<f32> {
    rgb.chunks_exact(3).map(|p| p[c]).collect()
}

#[test]
fn the_gpu_draws_the_cpus_drops() {
    let ctx = GpuContext::new(AdapterChoice::Any).expect("a Vulkan adapter (lavapipe in CI)");
    let pass = WindshieldPass::new(&ctx).unwrap();
    let (w, h) = (256usize, 192usize);
    // a fixed pseudo-random scatter (a 64-bit LCG, Knuth's MMIX constants)
    let mut state = 3u64;
    let mut uniform = move || {
        state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (state >> 40) as f32 / (1u64 << 24) as f32
    };
    let mut centres = Vec::new();
    let mut radii = Vec::new();
    for _ in 0..400 {
        centres.push([uniform() * w as f32, uniform() * h as f32]);
        radii.push(1.0 + 9.0 * uniform().powi(2));
    }
    // a textured frame: stripes and a gradient, so that refraction shows
    let mut frame = vec![0.0f32; w * h * 3];
    for j in 0..h {
        for i in 0..w {
            let p = (j * w + i) * 3;
            frame[p] = 0.5 + 0.4 * ((i as f32) * 0.3).sin();
            frame[p + 1] = j as f32 / h as f32;
            frame[p + 2] = if (i / 8 + j / 8) % 2 == 0 { 0.8 } else { 0.1 };
        }
    }
    let field = render::height_map(&centres, &radii, w, h, true).unwrap();
    for mode in [RefractMode::Offset, RefractMode::Snell] {
        for lookup_px in [0usize, 64] {
            let r = Refraction {
                mode,
                focal_px: 300.0,
                principal_px: [w as f64 / 2.0, h as f64 / 2.0],
                index: WATER_INDEX,
                slope_px: 6.0,
                lookup_px,
                blur_px: 0.0,
            };
            let mut rgb = vec![0.0f32; w * h * 3];
            let mut mask = vec![0.0f32; w * h];
            render::refract_frame(&frame, w, h, &field, &r, &mut rgb, &mut mask).unwrap();
            let g = pass
                .draw(&ctx, &centres, &radii, w, h, true, &frame, &r)
                .unwrap();
            let fmax = field.iter().cloned().fold(0.0f32, f32::max) as f64;
            let df = field
                .iter()
                .zip(&g.field)
                .map(|(a, b)| (a - b).abs())
                .fold(0.0f32, f32::max);
            assert!(df < 1e-4, "field differs by {df}");
            assert!(ssim(&field, &g.field, w, h, fmax) > 0.999);
            let s_mask = ssim(&mask, &g.mask, w, h, 1.0);
            assert!(s_mask > 0.99, "{mode:?} mask SSIM {s_mask}");
            for c in 0..3 {
                let s = ssim(&channel(&rgb, c), &channel(&g.rgb, c), w, h, 1.0);
                eprintln!(
                    "{mode:?} lookup {lookup_px} channel {c}: SSIM {s:.6}, field max diff {df:e}, mask SSIM {s_mask:.6}"
                );
                assert!(
                    s >= 0.99,
                    "{mode:?} lookup {lookup_px} channel {c}: SSIM {s}"
                );
            }
            let off = rgb
                .iter()
                .zip(&g.rgb)
                .filter(|(a, b)| (*a - *b).abs() > 0.02)
                .count();
            assert!(
                (off as f64) < 0.005 * rgb.len() as f64,
                "{mode:?}: {off} values off by > 0.02"
            );
            assert!(mask.contains(&1.0) && mask.contains(&0.0));
            // the drops show: the GPU's frame is not the frame behind the glass
            let moved = g
                .rgb
                .iter()
                .zip(&frame)
                .filter(|(a, b)| (*a - *b).abs() > 0.05)
                .count();
            assert!(moved > rgb.len() / 50, "{mode:?}: {moved} values moved");
            let dmax = rgb
                .iter()
                .zip(&g.rgb)
                .map(|(a, b)| (a - b).abs())
                .fold(0.0f32, f32::max);
            eprintln!(
                "{mode:?} lookup {lookup_px}: rgb max diff {dmax:e}, {moved} values moved by the drops"
            );
        }
    }
    // blur is the CPU's
    let r = Refraction {
        mode: RefractMode::Offset,
        focal_px: 300.0,
        principal_px: [0.0, 0.0],
        index: WATER_INDEX,
        slope_px: 6.0,
        lookup_px: 0,
        blur_px: 3.0,
    };
    assert!(
        pass.draw(&ctx, &centres, &radii, w, h, true, &frame, &r)
            .is_err()
    );
}
