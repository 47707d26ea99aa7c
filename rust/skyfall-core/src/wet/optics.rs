//! How a water film changes the look of a surface: the darkening of a rough surface under it
//! (Lekner & Dorf, "Why some things are darker when wet", Applied Optics 27, 1988) and the
//! film's own reflection (Fresnel's equations for unpolarised light, and a GGX lobe for the
//! highlights of the lamps and the sun on a rippled film).

/// The refractive index of water in visible light.
pub const WATER_INDEX: f64 = 1.33;

/// The roughness α of a rain-rippled water film (GGX, Trowbridge–Reitz), for the highlights
/// of point lights: a chosen value, which stretches a lamp's reflection on a wet road into
/// the streak seen in night-time photos (α = 0 would be a point).
pub const FILM_ROUGHNESS: f32 = 0.12;

/// The roughness α of a puddle's surface, dimpled by the arriving drops but otherwise still: a
/// chosen value, which keeps a lamp's reflection in a puddle a bright spot a few times the
/// lamp's own size.
pub const PUDDLE_ROUGHNESS: f32 = 0.04;

/// Fresnel's reflectance of unpolarised light arriving from air at a flat surface of index
/// `n`, at incidence cos θ = `cos_i` (0.020 at normal incidence for water, 1 at grazing).
pub fn fresnel(cos_i: f64, n: f64) -> f64 {
    let c = cos_i.clamp(0.0, 1.0);
    let sin_t = (1.0 - c * c).max(0.0).sqrt() / n;
    let cos_t = (1.0 - sin_t * sin_t).max(0.0).sqrt();
    let rs = ((c - n * cos_t) / (c + n * cos_t)).powi(2);
    let rp = ((cos_t - n * c) / (cos_t + n * c)).powi(2);
    if c == 0.0 { 1.0 } else { 0.5 * (rs + rp) }
}

/// The reflectance of a flat surface of index `n` for diffuse (Lambertian) light from the air:
/// ∫ R(θ) 2 sin θ cos θ dθ over the hemisphere (0.0659 for water).
pub fn diffuse_reflectance(n: f64) -> f64 {
    const STEPS: usize = 4096;
    let h = std::f64::consts::FRAC_PI_2 / STEPS as f64;
    (0..STEPS)
        .map(|i| {
            let th = (i as f64 + 0.5) * h;
            fresnel(th.cos(), n) * (2.0 * th).sin() * h
        })
        .sum()
}

/// The wetting of rough surfaces by a film of index `n` (Lekner & Dorf): light reaches the
/// surface with probability 1 − R̄ (R̄ the film's [`diffuse_reflectance`]: the light of the
/// sky arrives diffuse); what the surface reflects diffusely escapes the film with probability
/// 1 − p, p = 1 − (1 − R̄)/n² (its total internal reflection), else returns to the surface.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Wetting {
    /// R̄: the film's reflectance for diffuse light from the air.
    pub diffuse_reflectance: f64,
    /// p: the share of the surface's diffuse light the film sends back to it.
    pub internal_reflectance: f64,
}

impl Wetting {
    /// The wetting by a film of index `n`.
    pub fn new(n: f64) -> Self {
        let r = diffuse_reflectance(n);
        Wetting {
            diffuse_reflectance: r,
            internal_reflectance: 1.0 - (1.0 - r) / (n * n),
        }
    }

    /// The albedo of a surface of dry albedo `a` under the film:
    /// (1 − R̄)·a·(1 − p)/(1 − p·a) (Lekner & Dorf's, without their second correction for the
    /// material's index relative to water): 0.2 → 0.109, 0.5 → 0.323, 0.8 → 0.634.
    pub fn wet_albedo(&self, a: f64) -> f64 {
        let a = a.clamp(0.0, 1.0);
        let p = self.internal_reflectance;
        (1.0 - self.diffuse_reflectance) * a * (1.0 - p) / (1.0 - p * a)
    }

    /// The factor a wet surface's diffuse light is multiplied by: wet_albedo(a)/a (its limit
    /// (1 − R̄)(1 − p) at a = 0).
    pub fn darkening(&self, a: f64) -> f64 {
        if a <= 0.0 {
            let p = self.internal_reflectance;
            return (1.0 - self.diffuse_reflectance) * (1.0 - p);
        }
        self.wet_albedo(a) / a
    }
}

/// The GGX (Trowbridge–Reitz) reflection of a film of roughness `alpha` and index `index`,
/// its BRDF F(v·h)·D(h)·G / (4 cos θᵥ cos θₗ) with Smith's masking, sr⁻¹, for unit normal
/// `n`, unit directions `v` (towards the camera) and `l` (towards the light): a point light's
/// highlight has the radiance BRDF · E, E its illuminance on the face.
pub fn brdf(n: glam::Vec3, v: glam::Vec3, l: glam::Vec3, alpha: f32, index: f32) -> f32 {
    let nv = n.dot(v);
    let nl = n.dot(l);
    if nv <= 0.0 || nl <= 0.0 {
        return 0.0;
    }
    let h = (v + l).normalize_or_zero();
    let nh = n.dot(h).max(0.0);
    let a2 = alpha * alpha;
    let d = a2 / (std::f32::consts::PI * (nh * nh * (a2 - 1.0) + 1.0).powi(2));
    let g1 = |c: f32| 2.0 * c / (c + (a2 + (1.0 - a2) * c * c).sqrt());
    let f = fresnel(f64::from(v.dot(h)), f64::from(index)) as f32;
    f * d * g1(nv) * g1(nl) / (4.0 * nv * nl)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fresnel_is_two_percent_at_normal_incidence_and_one_at_grazing() {
        let r0 = ((WATER_INDEX - 1.0) / (WATER_INDEX + 1.0)).powi(2);
        assert!((fresnel(1.0, WATER_INDEX) - r0).abs() < 1e-12);
        assert!((fresnel(1.0, WATER_INDEX) - 0.0201).abs() < 1e-4);
        assert_eq!(fresnel(0.0, WATER_INDEX), 1.0);
        // Brewster's angle: rp = 0, so R = rs/2 there.
        let tb = WATER_INDEX.atan();
        let (c, s) = (tb.cos(), tb.sin());
        let ct = (1.0 - (s / WATER_INDEX).powi(2)).sqrt();
        let rs = ((c - WATER_INDEX * ct) / (c + WATER_INDEX * ct)).powi(2);
        assert!((fresnel(c, WATER_INDEX) - rs / 2.0).abs() < 1e-12);
        // monotone in the angle
        let mut last = 0.0;
        for i in (0..=100).rev() {
            let r = fresnel(f64::from(i) / 100.0, WATER_INDEX);
            assert!(r >= last);
            last = r;
        }
    }

    #[test]
    fn the_wet_albedo_is_lekner_and_dorfs_and_darker_for_dark_surfaces() {
        let w = Wetting::new(WATER_INDEX);
        assert!((w.diffuse_reflectance - 0.0659).abs() < 2e-4, "{w:?}");
        for (a, want) in [(0.2, 0.1089), (0.5, 0.3228), (0.8, 0.6339)] {
            assert!(
                (w.wet_albedo(a) - want).abs() < 2e-4,
                "{a}: {}",
                w.wet_albedo(a)
            );
        }
        assert!(w.darkening(0.1) < w.darkening(0.5) && w.darkening(0.5) < w.darkening(0.9));
        assert!((w.darkening(1e-9) - w.darkening(0.0)).abs() < 1e-6);
        // a white surface loses only what the film reflects back out: (1 - R̄)
        assert!((w.wet_albedo(1.0) - (1.0 - w.diffuse_reflectance)).abs() < 1e-12);
    }

    #[test]
    fn the_highlight_peaks_at_the_mirror_direction_and_integrates_below_one() {
        use glam::Vec3;
        let n = Vec3::Y;
        let v = Vec3::new(0.0, 0.3, 1.0).normalize();
        let mirror = Vec3::new(0.0, 0.3, -1.0).normalize();
        let at = |l: Vec3| brdf(n, v, l.normalize(), FILM_ROUGHNESS, WATER_INDEX as f32);
        let peak = at(mirror);
        for off in [0.05f32, 0.1, 0.2] {
            assert!(at(mirror + Vec3::new(off, 0.0, 0.0)) < peak);
            assert!(at(mirror + Vec3::new(0.0, off, 0.0)) < peak);
        }
        // ∫ f cos θₗ dω ≤ 1 (energy): the lobe reflects at most all the light; at least
        // Fresnel's share at normal incidence, less the masking.
        let steps = 400;
        let mut total = 0.0f64;
        for i in 0..steps {
            for j in 0..2 * steps {
                let th = (i as f64 + 0.5) / steps as f64 * std::f64::consts::FRAC_PI_2;
                let ph = (j as f64 + 0.5) / (2 * steps) as f64 * std::f64::consts::TAU;
                let l = Vec3::new(
                    (th.sin() * ph.cos()) as f32,
                    th.cos() as f32,
                    (th.sin() * ph.sin()) as f32,
                );
                let dw = th.sin()
                    * (std::f64::consts::FRAC_PI_2 / steps as f64)
                    * (std::f64::consts::TAU / (2 * steps) as f64);
                total += f64::from(at(l)) * th.cos() * dw;
            }
        }
        assert!(total < 1.0 && total > 0.02, "{total}");
    }
}
