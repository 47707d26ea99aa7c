use super::*;
use crate::particles::composite::{Accumulator, ColourBlend, Cover};

fn region(rate: f64, near: f64, far: f64, seed: u64) -> RainRegion {
    let mut r = RainRegion::new(rate, &[1.0, 1.5, 2.0], near, [0.0; 3], 0.0, seed).unwrap();
    r.far_m = Some(far);
    r
}

#[test]
fn shells_tile_the_far_region() {
    // 3 m at 1.5 m a shell: two, far first
    let (radii, dr) = shells(2.0, 5.0);
    assert_eq!(radii.len(), 2);
    assert!((dr - 1.5).abs() < 1e-12);
    assert_eq!(radii, vec![4.25, 2.75]);
    let (radii, dr) = shells(2.0, 6.0);
    assert_eq!((radii.len(), dr), (3, 4.0 / 3.0));
    let (radii, dr) = shells(1.0, 40.0);
    assert_eq!(radii.len(), MAX_LAYERS);
    assert!((radii[MAX_LAYERS - 1] - 0.5 * dr - 1.0).abs() < 1e-12);
    assert!((radii[0] + 0.5 * dr - 40.0).abs() < 1e-9);
}

#[test]
fn a_texel_is_about_a_pixel_and_the_turn_holds_whole_textures() {
    for fy in [50.0f32, 400.0, 935.3, 1800.0, 5000.0] {
        let d = texel_angle(fy);
        let turns = std::f64::consts::TAU / (d * TEXTURE_SIZE as f64);
        assert!((turns - turns.round()).abs() < 1e-9, "{turns}");
        if fy > 500.0 {
            assert!(
                (d * f64::from(fy) - 1.0).abs() < 0.1,
                "{fy}: {}",
                d * f64::from(fy)
            );
        }
    }
}

#[test]
fn the_vector_arctangent_is_within_its_bound_in_every_quadrant() {
    let mut worst = 0.0f64;
    for i in 0..720 {
        let t = (f64::from(i) + 0.37) * std::f64::consts::TAU / 720.0;
        for r in [1e-3, 0.7, 2.0, 1e3] {
            let (y, x) = ((t.sin() * r) as f32, (t.cos() * r) as f32);
            let got = atan2_x4(Vec4::splat(y), Vec4::splat(x)).x;
            let want = f64::from(y).atan2(f64::from(x));
            let mut e = (f64::from(got) - want).abs();
            e = e.min((e - std::f64::consts::TAU).abs());
            worst = worst.max(e);
        }
    }
    assert!(worst < 2e-5, "{worst}");
}

#[test]
fn a_shells_texture_holds_the_opacity_of_its_drops() {
    // Thin streaks carry (π/4)·w² texels² each, w = D/(R δ): a shell's mean opacity is
    // n·Δ·(π/4)·E[D²] (n drops per m³, Δ m thick), whatever its radius; the texture's
    // 1 − ∏(1 − a) is under that sum by the overlaps, about half its square.
    let r = region(10.0, 5.0, 2.0, 1);
    let delta = texel_angle(935.0);
    for radius in [2.5, 4.5] {
        let tex = shell_texture(&r, r.rain_rate_mm_h, 1.0 / 60.0, radius, 1.0, delta, 0).unwrap();
        let mean = tex.iter().map(|&a| f64::from(a)).sum::<f64>() / tex.len() as f64;
        let mut want = 0.0;
        for &(lo, hi) in &r.bins {
            let s = BinSampler::new(r.rain_rate_mm_h, lo, hi);
            let m = 4000;
            let d2: f64 = (0..m)
                .map(|i| (s.diameter_mm((i as f64 + 0.5) / m as f64) * 1e-3).powi(2))
                .sum::<f64>()
                / m as f64;
            want += s.expected_per_m3() * 1.0 * std::f64::consts::FRAC_PI_4 * d2;
        }
        let want = want - 0.5 * want * want;
        assert!(
            (mean / want - 1.0).abs() < 0.05,
            "R = {radius}: {mean} vs {want}"
        );
    }
}

#[test]
fn textures_are_cached_with_the_same_bits() {
    let r = region(7.0, 4.0, 2.0, 3);
    let (radii, dr) = shells(2.0, 4.0);
    let delta = texel_angle(300.0);
    let a = textures(&r, 0.02, &radii, dr, delta).unwrap();
    let b = textures(&r, 0.02, &radii, dr, delta).unwrap();
    assert_eq!(a, b);
    // (drawn at the grid's rate and exposure)
    let (rate, exposure) = (quantised_rate(7.0), quantised_exposure(0.02));
    assert!((rate / 7.0 - 1.0).abs() < 0.155 && (exposure / 0.02 - 1.0).abs() < 0.045);
    let fresh = shell_texture(&r, rate, exposure, radii[1], dr, delta, 1).unwrap();
    let s2 = TEXTURE_SIZE * TEXTURE_SIZE;
    for (t, f) in a.0[s2..2 * s2].iter().zip(&fresh) {
        assert_eq!(t.to_bits(), f.to_bits());
    }
}

fn camera(w: u32, h: u32, pitch_deg: f32) -> Camera {
    let f = 0.9 * w as f32;
    Camera::new(
        w,
        h,
        [f, f, 0.5 * w as f32, 0.5 * h as f32],
        DVec3::new(0.3, 1.6, 0.2),
        Mat3::from_rotation_x(pitch_deg.to_radians()),
    )
    .unwrap()
}

/// The far rain's coverage over a frame whose scene lies at `depth` everywhere.
fn coverage(far: &FarRain, cam: &Camera, depth: f32) -> Vec<f32> {
    let (w, h) = (cam.width as usize, cam.height as usize);
    let mut rgb = vec![0.0f32; 3 * w * h];
    let mut alpha = vec![0.0f32; w * h];
    let mut rd = vec![0.0f32; w * h];
    let depth = vec![depth; w * h];
    let mut acc = Accumulator {
        colour: ColourBlend { rgb: &mut rgb },
        cover: Cover::started([&mut alpha, &mut []], [&mut rd, &mut []]),
    };
    far.composite(0, h, w, 0..w, &depth, &mut acc);
    acc.cover.finish();
    alpha
}

fn far_of(r: &RainRegion, cam: &Camera, lens: bool) -> Result<Option<FarRain>> {
    FarRain::prepare(
        cam,
        &FarRequest {
            region: r,
            exposure_s: 1.0 / 60.0,
            camera_velocity_m_s: Vec3::ZERO,
            lens,
            shelter: &[],
            shading: &RainShading::open_sky(),
        },
    )
}

#[test]
fn the_scene_hides_the_shells_behind_it_in_proportion() {
    let r = region(20.0, 5.0, 2.0, 5);
    let cam = camera(160, 90, 0.0);
    let far = far_of(&r, &cam, false).unwrap().unwrap();
    assert_eq!(far.layers(), 2);
    let (w, h) = (cam.width as usize, cam.height as usize);
    let mean = |d: f32| {
        let a = coverage(&far, &cam, d);
        a.iter().map(|&x| f64::from(x)).sum::<f64>() / a.len() as f64
    };
    // Each shell's texture holds about the same mean opacity, so a frame's mean coverage goes
    // as the sum over pixels and shells of 1/h (h the ray's horizontal length, camera z = −1:
    // sec(elevation) over |ray|) times the share of the shell's span
    // in front of the scene and inside the sphere, worked out here in f64 from the geometry.
    let expected = |d: f64| {
        let mut sum = 0.0;
        for y in 0..h {
            for x in 0..w {
                let u = (x as f64 + 0.5 - f64::from(cam.cx)) / f64::from(cam.fx);
                let v = -(y as f64 + 0.5 - f64::from(cam.cy)) / f64::from(cam.fy);
                let ray = cam.rotation.as_dmat3() * DVec3::new(u, v, -1.0);
                let horiz = ray.x.hypot(ray.z);
                let sec = ray.length() / horiz;
                let end = (d * horiz).min(5.0 / sec);
                for lo in [2.0, 3.5] {
                    sum += ((end - lo) / 1.5).clamp(0.0, 1.0) / horiz;
                }
            }
        }
        sum
    };
    let (none, all, part) = (mean(1.5), mean(f32::INFINITY), mean(3.5));
    assert_eq!(none, 0.0);
    assert!(all > 0.0);
    let want = expected(3.5) / expected(f64::INFINITY);
    assert!(
        (part / all / want - 1.0).abs() < 0.05,
        "{} vs {want}",
        part / all
    );
    // with a lens the layers are refused, naming the parameter
    let e = far_of(&r, &cam, true).unwrap_err();
    assert!(e.to_string().contains("rain_far_m"), "{e}");
}

#[test]
fn the_shells_stay_anchored_when_the_camera_turns() {
    // looking north (−Z), and south, where the azimuth's seam runs through the view's centre
    for base in [0.0, std::f32::consts::PI] {
        anchored_across_a_turn(base);
    }
}

fn anchored_across_a_turn(base_yaw: f32) {
    // Two cameras a few degrees apart in yaw: the same world direction shows the same texels.
    let r = region(20.0, 5.0, 2.0, 5);
    let mut a = camera(200, 100, 0.0);
    a.rotation = Mat3::from_rotation_y(base_yaw);
    let mut b = a;
    let f = a.fx;
    // turn left by exactly 20 px' worth of angle at the centre
    let yaw = (20.0 / f).atan();
    b.rotation = Mat3::from_rotation_y(base_yaw + yaw);
    let (fa, fb) = (
        far_of(&r, &a, false).unwrap().unwrap(),
        far_of(&r, &b, false).unwrap().unwrap(),
    );
    let (ca, cb) = (
        coverage(&fa, &a, f32::INFINITY),
        coverage(&fb, &b, f32::INFINITY),
    );
    // Near the centre, b's pixel 20 px right of a's looks the same way: the coverages agree
    // there (nearest texels differ only where a texel's edge falls between the two), and do
    // not where the camera's turn is ignored.
    let w = 200usize;
    let corr = |shift: usize| {
        let (mut xs, mut ys) = (Vec::new(), Vec::new());
        for y in 40..60 {
            for x in 85..115 {
                xs.push(f64::from(ca[y * w + x]));
                ys.push(f64::from(cb[y * w + x + shift]));
            }
        }
        let n = xs.len() as f64;
        let (mx, my) = (xs.iter().sum::<f64>() / n, ys.iter().sum::<f64>() / n);
        let cov: f64 = xs.iter().zip(&ys).map(|(a, b)| (a - mx) * (b - my)).sum();
        let vx: f64 = xs.iter().map(|a| (a - mx).powi(2)).sum();
        let vy: f64 = ys.iter().map(|b| (b - my).powi(2)).sum();
        cov / (vx * vy).sqrt()
    };
    let (anchored, ignored) = (corr(20), corr(0));
    assert!(
        anchored > 0.8 && ignored < 0.3,
        "{base_yaw}: {anchored} {ignored}"
    );
}

#[test]
fn textures_beyond_the_drop_budget_are_refused_by_name() {
    // A 64-px-tall frame's texel is 2π/1024 rad: its shells' textures span the region's
    // whole circumference; at 500 mm/h out to 50 m that is far too many drops.
    let r = region(500.0, 50.0, 1.0, 1);
    let cam = camera(64, 48, 0.0);
    let e = far_of(&r, &cam, false).unwrap_err();
    let text = e.to_string();
    assert!(
        text.contains("rain_far_m") && text.contains("drops"),
        "{text}"
    );
}

#[test]
fn the_voxels_skipped_beyond_far_m_hold_none_of_the_near_drops() {
    // RainFrame::streaks makes the near drops only in voxels that reach within far_m
    // horizontally: after the cut at far_m they are exactly the reference's drops within it.
    use crate::rain::drops::{drops_in_view, drops_in_view_where};
    let r = region(30.0, 6.0, 2.2, 7);
    let cam = camera(200, 120, -10.0);
    let reach = 2.2 + std::f64::consts::FRAC_1_SQRT_2;
    let within = |d: &crate::particles::Particle| {
        d.position_m.x * d.position_m.x + d.position_m.z * d.position_m.z < (2.2f32 * 2.2)
    };
    let all: Vec<_> = drops_in_view(&r, &cam, 1.0 / 60.0, 0.0, true)
        .unwrap()
        .into_iter()
        .filter(within)
        .map(|d| d.id)
        .collect();
    let fewer: Vec<_> = drops_in_view_where(&r, &cam, 1.0 / 60.0, 0.0, true, |c| {
        f64::from(c.x).hypot(f64::from(c.z)) < reach
    })
    .unwrap()
    .into_iter()
    .filter(within)
    .map(|d| d.id)
    .collect();
    assert!(!all.is_empty());
    assert_eq!(all, fewer);
}

#[test]
fn nearby_rates_share_textures_and_keep_their_own_mean_opacity() {
    // A frame at a rate off the textures' grid draws the grid rate's textures with their
    // opacity scaled by the cross-section ratio. Its textures' mean opacity, so scaled, against
    // textures drawn at the frame's own rate and exposure (each mean over 6 independent
    // textures, 1024² texels, so that the drops' own Poisson noise, about 0.3 %, stays well
    // under the bound): within 1 %, the bound, for rates across a decade and
    // exposures off the grid.
    let delta = texel_angle(288.0);
    let (radius, dr) = (3.5, 1.5);
    let mean = |r: &RainRegion, rate: f64, exposure: f64| {
        (0..6u64)
            .map(|k| {
                let t = shell_texture(r, rate, exposure, radius, dr, delta, k).unwrap();
                t.iter().map(|&a| f64::from(a)).sum::<f64>() / t.len() as f64
            })
            .sum::<f64>()
            / 6.0
    };
    let mut worst = 0.0f64;
    for (rate, exposure) in [(2.2, 1.0 / 60.0), (7.3, 1.0 / 30.0), (17.0, 1.0 / 100.0)] {
        let r = region(rate, 5.0, 2.0, 11);
        let scale = opacity_scale(rate, &r.bins);
        let got = scale * mean(&r, quantised_rate(rate), quantised_exposure(exposure));
        let want = mean(&r, rate, exposure);
        let err = got / want - 1.0;
        worst = worst.max(err.abs());
        assert!(
            err.abs() < 0.01,
            "{rate} mm/h, {exposure} s: {got} vs {want}"
        );
        assert!((0.8..1.25).contains(&scale), "{scale}");
    }
    eprintln!("worst mean-opacity error {worst:.2e}");
    // A frame carries the scale; rates on one grid step share one set of textures.
    let cam = camera(320, 180, 5.0);
    let r = region(7.3, 5.0, 2.0, 1);
    let far = far_of(&r, &cam, false).unwrap().unwrap();
    assert_eq!(far.opacity_scale, opacity_scale(7.3, &r.bins) as f32);
    let delta = texel_angle(cam.fy);
    let (radii, dr) = shells(2.0, 5.0);
    let (a, b) = (region(5.0, 5.0, 2.0, 1), region(5.4, 5.0, 2.0, 2));
    assert_eq!(quantised_rate(5.0), quantised_rate(5.4));
    let (ta, tb) = (
        textures(&a, 1.0 / 60.0, &radii, dr, delta).unwrap(),
        textures(&b, 1.0 / 61.0, &radii, dr, delta).unwrap(),
    );
    assert!(Arc::ptr_eq(&ta.0, &tb.0));
    // on the grid the scale is 1 exactly
    assert_eq!(opacity_scale(10.0, &a.bins), 1.0);
}
