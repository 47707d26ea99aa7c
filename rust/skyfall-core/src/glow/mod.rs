//! Lamps and headlights seen by the camera: each light drawn as a small emitter disc, and the
//! glow of its light scattered by the rain and mist on the way (an atmospheric point-spread
//! function, after Narasimhan & Nayar, *Shedding light on the weather*, CVPR 2003).
//!
//! A light whose illuminance at the camera is E_c (lux, [`Light::illuminance_lux`] at the eye:
//! a spot's cone towards the camera included) reaches it through the optical depth T = σ·d
//! (σ the weather's extinction, d the distance; less the particles drawn near the eye, whose
//! streaks hide the lamp themselves: [`crate::haze::Haze::optical_depth`]). Of that light, the part that was scattered n
//! times arrives with the Poisson weight p_n = e^(−T) Tⁿ/n! (the direct part is n = 0):
//!
//! - the **direct** part, e^(−T)·E_c, is the emitter: a disc of angular radius
//!   α = max([`SOURCE_RADIUS_M`]/d, one pixel δ) (at most [`MAX_DISC_RAD`]) of radiance
//!   e^(−T)·E_c/(π(α² + δ²/12)), its edge a ramp one pixel wide (the area of the ramped disc is that denominator; a disc
//!   smaller than a pixel keeps its flux: it is widened and dimmed);
//! - the **scattered** part is spread around the source's direction by the phase function of
//!   the drops. With a Henyey–Greenstein lobe of asymmetry q for one scattering, n scatterings
//!   give exactly a Henyey–Greenstein lobe of asymmetry qⁿ (the lobe's Legendre coefficients are
//!   q^l, and the convolutions multiply them), so the glow is Σₙ p_n·HG(qⁿ, θ)·E_c, whose
//!   Legendre coefficients exp(−T(1 − q^l)) − e^(−T) have the form of Narasimhan & Nayar's APSF:
//!   it widens as T grows and narrows as q → 1. The sum is cut at [`ORDERS`] orders, the last
//!   carrying all the higher ones' weight, so direct + glow = E_c exactly for every T (the glow
//!   keeps widening up to T ≈ [`ORDERS`] and then stays at the last order's width). The model
//!   follows the angle only (scattered light is not displaced sideways) and, like the APSF,
//!   keeps the scattered light in the image: energy is redistributed, not lost.
//!
//! Radiance is relative, as the frame's: E_c becomes E_c·π/E (E the sky's horizontal
//! illuminance), so a radiance in 1/sr times it is relative radiance. A glow fainter than
//! [`GLOW_FLOOR`] is cut where it falls below it (per source, at a precomputed angle).
//!
//! Depth test: a light hidden from the camera by a box (or the ground) has neither disc nor
//! glow (the ray from the eye to the light is cast through the scene). The glow is added after
//! the haze (it is light that reached the camera) and before the particles (drops in front of
//! a lamp hide it). [`Glow::apply_row`] is the CPU reference of `skyfall-gpu`'s `glow.wgsl`.

pub mod stage;

use crate::scene::boxes::{BoxScene, trace};
use crate::scene::camera::Camera;
use crate::scene::lights::Light;
use glam::Vec3;

/// Scattering orders the glow sums (the last carries the weight of all higher ones).
pub const ORDERS: usize = 6;
/// The Henyey–Greenstein asymmetry q of one scattering by the rain and mist: strongly forward
/// (water drops far larger than the wavelength).
pub const FORWARD_SCATTERING_Q: f32 = 0.95;
/// The radius of a lamp's or headlight's emitting disc, m.
pub const SOURCE_RADIUS_M: f32 = 0.15;
/// The largest angular radius of an emitter disc, rad.
pub const MAX_DISC_RAD: f32 = 0.5;
/// Relative radiance (1.0 = white under the open sky) below which a glow is not drawn.
pub const GLOW_FLOOR: f32 = 1e-3;

/// The Henyey–Greenstein phase function of asymmetry `g` at the angle θ given by
/// `one_minus_cos` = 1 − cos θ, 1/sr (it integrates to 1 over the sphere).
#[inline]
pub fn henyey_greenstein(g: f32, one_minus_cos: f32) -> f32 {
    let den = (1.0 - g) * (1.0 - g) + 2.0 * g * one_minus_cos;
    (1.0 - g * g) / (4.0 * std::f32::consts::PI * den * den.sqrt())
}

/// The scattered orders at optical depth `t`: (weight, asymmetry) of orders 1..=[`ORDERS`], the
/// weights p_n = e^(−T) Tⁿ/n!, the last order taking 1 − e^(−T) − the others (so they sum to
/// 1 − e^(−T)), the asymmetries qⁿ.
pub fn orders(t: f32) -> [(f32, f32); ORDERS] {
    let direct = (-t).exp();
    let mut out = [(0.0, 0.0); ORDERS];
    let (mut p, mut g, mut sum) = (direct, 1.0, 0.0);
    for (n, o) in out.iter_mut().enumerate() {
        p *= t / (n + 1) as f32;
        g *= FORWARD_SCATTERING_Q;
        *o = (p, g);
        sum += p;
    }
    // The tail of the higher orders into the last (f32 round-off kept non-negative).
    let scattered = 1.0 - direct;
    out[ORDERS - 1].0 = (scattered - (sum - out[ORDERS - 1].0)).max(0.0);
    out
}

/// One light as the camera sees it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GlowSource {
    /// Unit vector from the eye to the light (world).
    pub dir: Vec3,
    /// E_c·π/E per channel: the light at the camera, relative radiance × sr.
    pub flux: Vec3,
    /// Radiance of the direct disc, relative, per channel.
    pub disc: Vec3,
    /// The disc's angular radius, rad.
    pub disc_radius: f32,
    /// The scattered orders (weight, asymmetry).
    pub orders: [(f32, f32); ORDERS],
    /// Chord |ray − dir| beyond which neither disc nor glow is drawn.
    pub cut_chord: f32,
}

impl GlowSource {
    /// Relative radiance this source adds along the unit ray `ray`, `pixel` the angular size of
    /// a pixel, rad (the disc's antialiasing width).
    #[inline]
    pub fn radiance(&self, ray: Vec3, pixel: f32) -> Vec3 {
        let chord = (ray - self.dir).length();
        if chord > self.cut_chord {
            return Vec3::ZERO;
        }
        let one_minus_cos = 0.5 * chord * chord;
        let mut k = 0.0;
        for &(w, g) in &self.orders {
            k += w * henyey_greenstein(g, one_minus_cos);
        }
        let cover = ((self.disc_radius - chord) / pixel + 0.5).clamp(0.0, 1.0);
        self.flux * k + self.disc * cover
    }
}

/// The glows of a frame: its visible lights.
#[derive(Debug, Clone, PartialEq)]
pub struct Glow {
    /// The lights in front of the camera and not hidden by the scene.
    pub sources: Vec<GlowSource>,
    /// Angular size of a pixel at the frame's centre, rad.
    pub pixel_rad: f32,
}

impl Glow {
    /// The glows of `lights` in `scene` seen by `cam` through the optical depth
    /// `optical_depth(d)` to a light d m away (the haze's, [`crate::haze::Haze::optical_depth`];
    /// 0 in clear air: discs only), under a sky of horizontal illuminance
    /// `sky_illuminance_lux`; None when no light is in front of the camera and visible.
    pub fn prepare(
        cam: &Camera,
        scene: &BoxScene,
        lights: &[Light],
        optical_depth: impl Fn(f32) -> f32,
        sky_illuminance_lux: f32,
    ) -> Option<Self> {
        let eye = cam.eye();
        let forward = -cam.rotation.z_axis;
        let pixel_rad = 1.0 / cam.fx.max(cam.fy);
        let to_relative = std::f32::consts::PI / sky_illuminance_lux;
        let sources: Vec<GlowSource> = lights
            .iter()
            .filter_map(|l| {
                let to = l.position_m - eye;
                let d = to.length();
                if d <= 1e-3 || to.dot(forward) <= 0.0 {
                    return None;
                }
                // The depth test: anything hit before the light (t < 1 along `to`) hides it.
                if matches!(trace(scene, eye, to), Some((t, _, _)) if t < 1.0) {
                    return None;
                }
                let flux = l.illuminance_lux(eye) * to_relative;
                if flux.max_element() <= 0.0 {
                    return None;
                }
                let t = optical_depth(d);
                // (at most MAX_DISC_RAD: a camera all but inside a lamp sees a wide disc, not
                // a sphere's worth of one)
                let disc_radius =
                    (SOURCE_RADIUS_M / d).clamp(pixel_rad, MAX_DISC_RAD.max(pixel_rad));
                // The antialiased disc's integral is π(α² + δ²/12) (a ramp of width δ): its
                // radiance carries the direct part exactly.
                let area = std::f32::consts::PI
                    * (disc_radius * disc_radius + pixel_rad * pixel_rad / 12.0);
                let disc = flux * ((-t).exp() / area);
                let orders = orders(t);
                Some(GlowSource {
                    dir: to / d,
                    flux,
                    disc,
                    disc_radius,
                    orders,
                    cut_chord: cut_chord(flux.max_element(), &orders, disc_radius + pixel_rad),
                })
            })
            .collect();
        (!sources.is_empty()).then_some(Glow { sources, pixel_rad })
    }

    /// Relative radiance the glows add along the unit ray `ray`.
    #[inline]
    pub fn radiance(&self, ray: Vec3) -> Vec3 {
        self.sources
            .iter()
            .fold(Vec3::ZERO, |acc, s| acc + s.radiance(ray, self.pixel_rad))
    }

    /// Adds the glows to row `y` of a frame (linear RGB, relative).
    pub fn apply_row(&self, cam: &Camera, y: u32, rgb_row: &mut [f32]) {
        for (x, px) in rgb_row.chunks_exact_mut(3).enumerate() {
            let ray = cam.ray_direction(x as u32, y).normalize();
            let add = self.radiance(ray);
            px[0] += add.x;
            px[1] += add.y;
            px[2] += add.z;
        }
    }
}

/// The chord beyond which the glow of peak flux `flux` is below [`GLOW_FLOOR`] (bisection on
/// the lobes, which fall monotonically with the angle), and never inside `disc_chord`.
fn cut_chord(flux: f32, orders: &[(f32, f32); ORDERS], disc_chord: f32) -> f32 {
    let glow = |chord: f32| {
        let omc = 0.5 * chord * chord;
        flux * orders
            .iter()
            .map(|&(w, g)| w * henyey_greenstein(g, omc))
            .sum::<f32>()
    };
    let (mut lo, mut hi) = (0.0f32, 2.0f32);
    if glow(hi) >= GLOW_FLOOR {
        return 2.0;
    }
    for _ in 0..40 {
        let mid = 0.5 * (lo + hi);
        if glow(mid) >= GLOW_FLOOR {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    hi.max(disc_chord)
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Mat3;

    /// ∫ f(θ) dω over the sphere, f given 1 − cos θ (midpoint rule in cos θ, finer near θ = 0).
    fn sphere_integral(f: impl Fn(f64) -> f64) -> f64 {
        // substitution 1 − cos θ = 2 s², s in [0, 1]: dω = 2π d(1 − cos θ) = 8π s ds
        let n = 200_000;
        (0..n)
            .map(|i| {
                let s = (i as f64 + 0.5) / n as f64;
                f(2.0 * s * s) * 8.0 * std::f64::consts::PI * s / n as f64
            })
            .sum()
    }

    #[test]
    fn henyey_greenstein_lobes_integrate_to_one() {
        for g in [0.0f32, 0.3, 0.6, 0.9, 0.95] {
            let total = sphere_integral(|omc| f64::from(henyey_greenstein(g, omc as f32)));
            assert!((total - 1.0).abs() < 1e-4, "g {g}: {total}");
        }
    }

    #[test]
    fn direct_plus_glow_is_the_unattenuated_light_at_every_optical_depth() {
        // e^(−T) + ∫ Σ p_n HG(qⁿ) dω = 1: the energy of the PSF, numerically.
        for t in [0.0f32, 0.01, 0.1, 0.5, 1.0, 2.0, 5.0, 20.0] {
            let o = orders(t);
            let glow = sphere_integral(|omc| {
                o.iter()
                    .map(|&(w, g)| f64::from(w * henyey_greenstein(g, omc as f32)))
                    .sum()
            });
            let total = f64::from((-t).exp()) + glow;
            assert!((total - 1.0).abs() < 2e-4, "T {t}: {total}");
            // and the weights are Poisson's below the last order
            if t > 0.0 {
                let p1 = f64::from(t) * f64::from(-t).exp();
                assert!((f64::from(o[0].0) - p1).abs() < 1e-6 * (1.0 + p1));
            }
        }
    }

    #[test]
    fn the_glow_widens_with_optical_depth() {
        // The half-energy angle of the scattered light grows with T.
        let half_angle = |t: f32| {
            let o = orders(t);
            let lobe = |omc: f64| -> f64 {
                o.iter()
                    .map(|&(w, g)| f64::from(w * henyey_greenstein(g, omc as f32)))
                    .sum()
            };
            let total = sphere_integral(lobe);
            // cumulative energy out to angle θ, by the same substitution
            let n = 100_000;
            let mut acc = 0.0;
            for i in 0..n {
                let s = (i as f64 + 0.5) / n as f64;
                acc += lobe(2.0 * s * s) * 8.0 * std::f64::consts::PI * s / n as f64;
                if acc >= 0.5 * total {
                    return (1.0 - 2.0 * s * s).acos();
                }
            }
            std::f64::consts::PI
        };
        let widths: Vec<f64> = [0.05f32, 0.3, 1.0, 3.0]
            .iter()
            .map(|&t| half_angle(t))
            .collect();
        for w in widths.windows(2) {
            assert!(w[1] > 1.05 * w[0], "{widths:?}");
        }
        // One scattering alone: HG(q)'s half-energy angle, analytic from its CDF.
        let q = f64::from(FORWARD_SCATTERING_Q);
        let single = {
            // HG's energy inside θ: (1 − q²)/(2q) · (1/(1 − q) − 1/sqrt(1 + q² − 2q cos θ));
            // set to 1/2 and solved for cos θ.
            let a = (1.0 - q * q) / (2.0 * q);
            let inv = 1.0 / (1.0 - q) - 0.5 / a;
            let mu = (1.0 + q * q - 1.0 / (inv * inv)) / (2.0 * q);
            mu.acos()
        };
        assert!(
            (widths[0] - single).abs() < 0.1 * single,
            "{} vs {single}",
            widths[0]
        );
    }

    #[test]
    fn a_frame_of_the_glow_carries_the_light_and_a_box_hides_it() {
        // A lamp 20 m ahead through T = 0.4: the frame's added radiance × each pixel's solid
        // angle sums to E_c·π/E (within the cut and the frame's edges), and a wall between
        // hides it.
        let cam = Camera::new(
            801,
            801,
            [400.0, 400.0, 400.5, 400.5],
            Vec3::new(0.0, 1.5, 0.0),
            Mat3::IDENTITY,
        )
        .unwrap();
        let lamp = Light::from_row(
            &[
                0.0, 1.5, -20.0, 1.0, 1.0, 1.0, 2000.0, 0.0, 0.0, 0.0, 0.0, 0.0,
            ],
            0,
        )
        .unwrap();
        let open = BoxScene::new(vec![], true, Vec3::splat(0.2)).unwrap();
        let e_sky = 30.0;
        let glow = Glow::prepare(&cam, &open, &[lamp], |d| 0.02 * d, e_sky).unwrap();
        let want = 2000.0 / 400.0 * std::f64::consts::PI / 30.0;
        let mut sum = 0.0f64;
        let mut direct = 0.0f64;
        for y in 0..cam.height {
            let mut row = vec![0.0f32; 3 * cam.width as usize];
            glow.apply_row(&cam, y, &mut row);
            for x in 0..cam.width {
                let r = cam.ray_direction(x, y);
                // solid angle of a pixel: (1/f²) cos³ of its angle off the axis
                let c = 1.0 / f64::from(r.length());
                let omega = c * c * c / (400.0 * 400.0);
                sum += f64::from(row[3 * x as usize]) * omega;
                let s = &glow.sources[0];
                let cover = ((s.disc_radius - (r.normalize() - s.dir).length()) / glow.pixel_rad
                    + 0.5)
                    .clamp(0.0, 1.0);
                direct += f64::from(s.disc.x * cover) * omega;
            }
        }
        let t = 0.4f64;
        assert!(
            (direct / want / (-t).exp() - 1.0).abs() < 0.01,
            "{}",
            direct / want
        );
        // a 90° field of view holds most of the glow: the orders' energy outside ±45° is small
        assert!(
            sum / want > 0.9 && sum / want < 1.0 + 1e-3,
            "{}",
            sum / want
        );
        let wall = crate::scene::boxes::SceneBox {
            min_m: Vec3::new(-3.0, 0.0, -11.0),
            max_m: Vec3::new(3.0, 4.0, -10.0),
            albedo: Vec3::splat(0.5),
        };
        let walled = BoxScene::new(vec![wall], true, Vec3::splat(0.2)).unwrap();
        assert!(Glow::prepare(&cam, &walled, &[lamp], |d| 0.02 * d, e_sky).is_none());
        // behind the camera: none either
        let behind = Light {
            position_m: Vec3::new(0.0, 1.5, 5.0),
            ..lamp
        };
        assert!(Glow::prepare(&cam, &open, &[behind], |d| 0.02 * d, e_sky).is_none());
    }
}
