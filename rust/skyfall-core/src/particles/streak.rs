//! Particles in screen space: a particle (a raindrop now, a snowflake next) moving during the
//! exposure is drawn as a perspective-correct, anti-aliased streak, with its inverse depth
//! interpolated along it for the depth test.
//!
//! A particle of diameter D moving at velocity u during the exposure T sweeps the segment from
//! p − u·T to p. Both ends are projected (clipped at [`NEAR_CLIP_M`]); the streak is a band
//! whose width is the projected diameter w = D·f/z, interpolated along it. A pixel on the path
//! is covered for the fraction α = w / max(L, w) of the exposure (L: the streak's length in
//! pixels; the screen-space form of Yoshida, Dobashi & Yamamoto's D / (v T), fast rendering of
//! rain streaks),
//! times the pixel's coverage of the band, box-filtered: across, clamp(w/2 + ½ − dist, 0, 1)
//! for w ≥ 1 px and w·clamp(1 − dist, 0, 1) below (a particle narrower than a pixel covers it
//! partially); along, a one-pixel ramp at each end. α carries the particle's silhouette: a
//! sphere's time-averaged shadow on its w-wide band is π/4 of the band ([`SILHOUETTE`]), so
//! each streak adds α·w·L = (π/4)·w² of opacity-area, the drop's πD²/4 cross-section on
//! screen (the same cross-section the haze's extinction counts). Off the optical axis by θ a
//! sphere's image is an ellipse stretched by sec θ along the radial direction (the image plane
//! meets its ray obliquely), so the band's width is the ellipse's across the path and the
//! opacity-area (π/4)·w²·sec θ: a pixel's expected coverage is then the same n·πD²/4 per metre
//! of its ray everywhere in the frame. Through a thin lens
//! ([`screen_streak_through`]) the streak is widened and lengthened by the drop's circle of
//! confusion and α divided so that this opacity-area is unchanged. [`ScreenStreak::fragment`] is the per-pixel definition; the walks of
//! [`super::walk`] and the GPU's `rain.wgsl` compute the same values, and
//! [`ScreenStreak::packed`] is the GPU's packing contract.

use super::Particle;
use super::num::{ceil_nonneg, clamp01, floor_nonneg, idx_f32, least, pos};
use crate::scene::camera::{Camera, Defocus};
use crate::stage::layers::Layer;
use glam::{Vec2, Vec3, Vec4};

/// The share of a particle's band a sphere's silhouette covers, averaged along its path: a
/// disc of diameter w passing over a w-wide band shades π/4 of it (πw²/4 of a w × w square).
pub const SILHOUETTE: f32 = std::f32::consts::FRAC_PI_4;

/// Streak ends nearer than this (m along the axis) are clipped.
pub const NEAR_CLIP_M: f32 = 0.05;

/// A streak in screen space.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ScreenStreak {
    pub(crate) a: Vec2,
    pub(crate) b: Vec2,
    pub(crate) inv_za: f32,
    pub(crate) inv_zb: f32,
    pub(crate) wa: f32,
    pub(crate) wb: f32,
    pub(crate) alpha: f32,
    pub(crate) min: Vec2,
    pub(crate) max: Vec2,
    pub(crate) light: Vec3,
    /// r, the share of its own light the particle shows (I = r·L + (1 − r)·background):
    /// set by its effect, so particles of several effects composite in one list.
    pub(crate) reflectance: f32,
    /// Unit direction a → b (+y for a dot) and length, px: per streak, not per pixel.
    pub(crate) dir: Vec2,
    pub(crate) len: f32,
    /// 1/len (0 for a dot), dx/dy and the half-width of a row's window, px, for steep streaks
    /// (see [`for_each_fragment`]): per streak, not per band of rows.
    pub(crate) inv_len: f32,
    pub(crate) slope: f32,
    pub(crate) half: f32,
    /// Which effect's layers the particle draws into ([`LAYER_RAIN`], [`LAYER_SNOW`]).
    pub(crate) layer: u8,
    /// Its sprite across the path ([`Sprite`]; the rain's: flat).
    pub(crate) sprite: Sprite,
}

/// Layer index of the rain's particles: `rain_alpha` and `rain_depth_m`.
pub const LAYER_RAIN: u8 = 0;
/// Layer index of the snow's particles: `snow_alpha`.
pub const LAYER_SNOW: u8 = 1;

/// A particle effect's layers: its coverage, and the depth of its nearest visible particle
/// when it has one (the rain's).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ParticleLayer {
    /// The coverage 1 − ∏(1 − aᵢ) of the effect's particles.
    pub coverage: Layer,
    /// The depth of its nearest visible particle, m (inf: none).
    pub depth: Option<Layer>,
}

/// Every particle effect's layers, indexed by a particle's layer index ([`LAYER_RAIN`],
/// [`LAYER_SNOW`]): the GPU binds the coverages as one array of planes in this order (and keeps
/// a pixel's coverage products in the lanes of one vector: at most four layers, asserted).
pub const PARTICLE_LAYERS: [ParticleLayer; 2] = [
    ParticleLayer {
        coverage: Layer::RainAlpha,
        depth: Some(Layer::RainDepth),
    },
    ParticleLayer {
        coverage: Layer::SnowAlpha,
        depth: None,
    },
];

const _: () = assert!(PARTICLE_LAYERS.len() <= 4);

/// The kinds of sprite a particle's path can carry across it.
pub const SPRITE_FLAT: u8 = 0;
/// A lump (an aggregate seen as a disc): the disc's projection, (4/π)·√(1 − x²).
pub const SPRITE_LUMP: u8 = 1;
/// A six-armed stellar dendrite at an angle θ to the path: a quarter a disc-like core, three
/// quarters its three diameters (arms), each projected onto the axis across the path as a
/// uniform density over |x| ≤ c_k = max(|cos(θ + kπ/3)|, [`ARM_MIN`]).
pub const SPRITE_STAR: u8 = 2;
/// A broad, flat aggregate: 1.5·(1 − x²).
pub const SPRITE_AGGREGATE: u8 = 3;
/// The narrowest projected arm of a star, as a share of its half-width (an arm along the path
/// projects to a line: it is given this width instead).
pub const ARM_MIN: f32 = 0.2;
/// A lump's round end, 6/π: its density (6/π)·√(1 − r²) has mean 1 over a quarter square.
const ROUND_LUMP: f32 = 6.0 / std::f32::consts::PI;
/// An aggregate's round end, 8/π: (8/π)·(1 − r²) has mean 1 over a quarter square.
const ROUND_AGGREGATE: f32 = 8.0 / std::f32::consts::PI;

/// A procedural sprite: the particle's shape seen across its motion, a density p(x) over
/// x = across / half-width in [0, 1] with mean 1 (so the streak's opacity-area α·w·L is kept).
/// A streak long against its width is its sprite averaged along the path, which is the
/// sprite's projection onto the axis across it: that projection is what is drawn, times the
/// flake's own round density within half a width of either end ([`Sprite::density`]).
/// `ScreenStreak::packed` carries it as one float (layer·8 + kind + θ/(π/3)); `rain.wgsl`'s
/// `sprite_profile` mirrors [`Sprite::profile`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sprite {
    kind: u8,
    /// θ / (π/3) in [0, 1) (stars only).
    turn: f32,
    /// 1/c_k per arm (stars), and the c_k.
    arm: [f32; 3],
    inv_arm: [f32; 3],
}

impl Sprite {
    /// The rain's: flat across (its silhouette is in α).
    pub const FLAT: Sprite = Sprite {
        kind: SPRITE_FLAT,
        turn: 0.0,
        arm: [1.0; 3],
        inv_arm: [1.0; 3],
    };

    /// A sprite of `kind` (one of the `SPRITE_*`), a star turned by `turn`·π/3 (in [0, 1)).
    pub fn new(kind: u8, turn: f32) -> Self {
        let kind = kind.min(SPRITE_AGGREGATE);
        let turn = if kind == SPRITE_STAR {
            turn.clamp(0.0, 0.999)
        } else {
            0.0
        };
        let third = std::f32::consts::FRAC_PI_3;
        let arm: [f32; 3] =
            std::array::from_fn(|k| (turn * third + k as f32 * third).cos().abs().max(ARM_MIN));
        Sprite {
            kind,
            turn,
            arm,
            inv_arm: arm.map(|c| 1.0 / c),
        }
    }

    /// Its kind (`SPRITE_*`).
    pub fn kind(&self) -> u8 {
        self.kind
    }

    /// The density across at x = across / half-width (≥ 0), mean 1 over [0, 1].
    #[inline(always)]
    pub fn profile(&self, x: f32) -> f32 {
        let one_minus = pos(1.0 - x * x);
        match self.kind {
            SPRITE_LUMP => std::f32::consts::FRAC_2_PI * 2.0 * one_minus.sqrt(),
            SPRITE_STAR => {
                let disc = std::f32::consts::FRAC_2_PI * 2.0 * one_minus.sqrt();
                let arm = |k: usize| {
                    if x <= self.arm[k] {
                        self.inv_arm[k]
                    } else {
                        0.0
                    }
                };
                0.25 * disc + 0.25 * (arm(0) + arm(1) + arm(2))
            }
            SPRITE_AGGREGATE => 1.5 * one_minus,
            _ => 1.0,
        }
    }

    /// The sprite's density at x = across / half-width (≥ 0), `e` px in from the nearer end of
    /// a band `half_w` px in half-width. Further in than half a width: the profile across.
    /// Within it, u = 1 − e/half_w along: a lump or an aggregate is round there, the disc's own
    /// density at r = √(x² + u²) (a sphere's projection (6/π)·√(1 − r²), a flat aggregate's
    /// (8/π)·(1 − r²)), so a path's ends are the flake's half-discs (a moving disc's smear is a
    /// capsule) and a dot, a path as long as the flake is wide, a disc rather than a square;
    /// a star keeps the profile across times the profile along (its arms). Every end's mean
    /// over the quarter square x, u ∈ [0, 1] is 1, as the profile's: the opacity-area is kept.
    #[inline(always)]
    pub fn density(&self, x: f32, e: f32, half_w: f32) -> f32 {
        if e >= half_w {
            return self.profile(x);
        }
        let u = 1.0 - e / half_w;
        let one_minus = pos(1.0 - x * x - u * u);
        match self.kind {
            SPRITE_LUMP => ROUND_LUMP * one_minus.sqrt(),
            SPRITE_AGGREGATE => ROUND_AGGREGATE * one_minus,
            _ => self.profile(x) * self.profile(u),
        }
    }

    /// [`Self::density`] for four values, lane for lane the same bits.
    #[inline(always)]
    pub fn density_x4(&self, x: Vec4, e: Vec4, half_w: Vec4) -> Vec4 {
        let across = self.profile_x4(x);
        let u = Vec4::ONE - e / half_w;
        let one_minus = (Vec4::ONE - x * x - u * u).max(Vec4::ZERO);
        let end = match self.kind {
            SPRITE_LUMP => Vec4::splat(ROUND_LUMP) * one_minus.sqrt(),
            SPRITE_AGGREGATE => Vec4::splat(ROUND_AGGREGATE) * one_minus,
            _ => across * self.profile_x4(u),
        };
        Vec4::select(e.cmplt(half_w), end, across)
    }

    /// [`Self::profile`] for four values, lane for lane the same bits.
    #[inline(always)]
    pub fn profile_x4(&self, x: Vec4) -> Vec4 {
        let one_minus = (Vec4::ONE - x * x).max(Vec4::ZERO);
        let k = std::f32::consts::FRAC_2_PI * 2.0;
        match self.kind {
            SPRITE_LUMP => Vec4::splat(k) * one_minus.sqrt(),
            SPRITE_STAR => {
                let disc = Vec4::splat(k) * one_minus.sqrt();
                let arm = |j: usize| {
                    Vec4::select(
                        x.cmple(Vec4::splat(self.arm[j])),
                        Vec4::splat(self.inv_arm[j]),
                        Vec4::ZERO,
                    )
                };
                Vec4::splat(0.25) * disc + Vec4::splat(0.25) * (arm(0) + arm(1) + arm(2))
            }
            SPRITE_AGGREGATE => Vec4::splat(1.5) * one_minus,
            _ => Vec4::ONE,
        }
    }
}

/// How much of a sprite shows on a band `width` px wide: none below 2 px (the pixels average
/// it away), all from 4 px.
#[inline(always)]
fn sprite_ramp(width: f32) -> f32 {
    clamp01(0.5 * width - 1.0)
}

/// A point relative to the camera's position (as particles are kept) in camera space.
fn to_camera(cam: &Camera, p: glam::Vec3) -> glam::Vec3 {
    cam.rotation.transpose() * p
}

fn project(cam: &Camera, pc: glam::Vec3) -> Vec2 {
    let z = -pc.z;
    Vec2::new(cam.cx + cam.fx * pc.x / z, cam.cy - cam.fy * pc.y / z)
}

/// How a sphere's image stretches off the optical axis, at one point of its path (camera
/// space): its width across the streak and its extent along it relative to the on-axis
/// D·f/z, and sec θ, its area's ratio to the on-axis disc's.
struct Obliquity {
    across: f32,
    along: f32,
    sec: f32,
}

impl Obliquity {
    fn at(pc: glam::Vec3, across: Vec2, along: Vec2) -> Self {
        let z = -pc.z;
        // The point's offset from the image's centre on the image plane at unit distance
        // (image rows grow downwards): radial, of length tan θ.
        let t = Vec2::new(pc.x, -pc.y) / z;
        Obliquity {
            across: (1.0 + across.dot(t).powi(2)).sqrt(),
            along: (1.0 + along.dot(t).powi(2)).sqrt(),
            sec: (1.0 + t.length_squared()).sqrt(),
        }
    }
}

/// The distance from a streak's axis beyond which a pixel gets no coverage, px: its widest
/// half-width plus half a pixel, at least one pixel (see [`ScreenStreak::fragment`]).
#[inline]
pub(crate) fn reach(wa: f32, wb: f32) -> f32 {
    (0.5 * wa.max(wb) + 0.5).max(1.0)
}

/// Projects a drop's exposure-long path relative to a camera moving at `camera_velocity_m_s`
/// (the camera's pose is the one at the end of the exposure); None when it is behind.
pub fn screen_streak(
    cam: &Camera,
    d: &Particle,
    exposure_s: f32,
    camera_velocity_m_s: Vec3,
) -> Option<ScreenStreak> {
    screen_streak_through(cam, None, d, exposure_s, camera_velocity_m_s)
}

/// [`screen_streak`] through a thin lens (`None`: the pinhole, the same bits as
/// [`screen_streak`]): the streak is the drop's pinhole streak convolved with its blur circle,
/// approximated by a box: each end's width grows by that end's blur diameter c (at its depth,
/// [`Defocus::blur_px`]) and each end moves out along the axis by c/2, and α is divided so
/// that the opacity-area α·w·L stays the drop's (π/4)·w²·sec θ (a blur spreads the drop's
/// shadow, it does not add to it).
pub fn screen_streak_through(
    cam: &Camera,
    lens: Option<&Defocus>,
    d: &Particle,
    exposure_s: f32,
    camera_velocity_m_s: Vec3,
) -> Option<ScreenStreak> {
    let mut pa = to_camera(
        cam,
        d.position_m - (d.velocity_m_s - camera_velocity_m_s) * exposure_s,
    );
    let mut pb = to_camera(cam, d.position_m);
    let (za, zb) = (-pa.z, -pb.z);
    if za < NEAR_CLIP_M && zb < NEAR_CLIP_M {
        return None;
    }
    if za < NEAR_CLIP_M {
        pa = pa + (pb - pa) * ((NEAR_CLIP_M - za) / (zb - za));
    } else if zb < NEAR_CLIP_M {
        pb = pb + (pa - pb) * ((NEAR_CLIP_M - zb) / (za - zb));
    }
    let (za, zb) = (-pa.z, -pb.z);
    let f = 0.5 * (cam.fx + cam.fy);
    let (mut a, mut b) = (project(cam, pa), project(cam, pb));
    // The drop's width on the tangent side (across the line to the image's centre): D·f/z, z
    // its depth along the axis.
    let (wa, wb) = (d.diameter_m * f / za, d.diameter_m * f / zb);
    let mut len = a.distance(b);
    let w_mid = 0.5 * (wa + wb);
    let path = if len > 1e-6 { (b - a) / len } else { Vec2::Y };
    let across = path.perp();
    // Off the axis by θ a sphere images to an ellipse, D·f/z across the radial direction and
    // D·f/(z cos θ) along it (the image plane meets the ray obliquely): its area is the
    // on-axis disc's over cos θ, sec θ = |p|/z. With t = (x, −y)/z the point's offset on the
    // image plane (radial, of length tan θ), the ellipse's width across a unit direction n is
    // w·√(1 + (n·t)²). [`Obliquity`] holds one end's.
    let (oa, ob) = (
        Obliquity::at(pa, across, path),
        Obliquity::at(pb, across, path),
    );
    let (wa_band, wb_band) = (wa * oa.across, wb * ob.across);
    let band_mid = 0.5 * (wa_band + wb_band);
    let along_mid = w_mid * 0.5 * (oa.along + ob.along);
    // Every streak carries the drop's (π/4)·w²·sec θ of opacity-area, whatever the exposure:
    // its pixels' coverage sums to α·w_band·L for L ≥ 1 px, wherever it falls on the pixel
    // grid (the anti-aliased ends are one pixel long), so α = area / (w_band·L). A path shorter
    // than a pixel or than the drop is long along it (a near drop in a short exposure, a drop
    // moving with the camera) is lengthened about its middle to max(that, 1 px): opaque over
    // its π/4 when w ≥ 1 px, as the drop's ellipse is.
    let area = SILHOUETTE * w_mid * w_mid * 0.5 * (oa.sec + ob.sec);
    let l = len.max(along_mid).max(1.0);
    if l > len {
        let grow = 0.5 * (l - len);
        (a, b) = (a - path * grow, b + path * grow);
        len = l;
    }
    let mut alpha = area / (band_mid * l);
    let (mut wa, mut wb) = (wa_band, wb_band);
    if let Some(lens) = lens {
        let (ca, cb) = (lens.blur_px(1.0 / za), lens.blur_px(1.0 / zb));
        if ca > 0.0 || cb > 0.0 {
            // (len ≥ 1 px here)
            let dir = (b - a) / len;
            (a, b) = (a - dir * (0.5 * ca), b + dir * (0.5 * cb));
            len += 0.5 * (ca + cb);
            (wa, wb) = (wa + ca, wb + cb);
            alpha *= band_mid * l / (0.5 * (wa + wb) * len);
        }
    }
    let r = 0.5 * wa.max(wb) + 1.0;
    let min = a.min(b) - Vec2::splat(r);
    let max = a.max(b) + Vec2::splat(r);
    let on_screen =
        min.x < cam.width as f32 && min.y < cam.height as f32 && max.x > 0.0 && max.y > 0.0;
    if !on_screen || !alpha.is_finite() {
        return None;
    }
    let dir = if len > 1e-6 { (b - a) / len } else { Vec2::Y };
    let inv_len = if len > 1e-6 { 1.0 / len } else { 0.0 };
    // Pixels farther than `reach` from the axis get no coverage; on a steep streak a row's
    // window is the pixels whose centre lies within `half` of the axis' crossing.
    let reach = reach(wa, wb);
    let (slope, half) = if dir.y.abs() > 0.5 {
        (dir.x / dir.y, reach / dir.y.abs())
    } else {
        (0.0, 0.0)
    };
    Some(ScreenStreak {
        a,
        b,
        inv_za: 1.0 / za,
        inv_zb: 1.0 / zb,
        wa,
        wb,
        alpha,
        min,
        max,
        light: Vec3::ONE,
        reflectance: 1.0,
        dir,
        len,
        inv_len,
        slope,
        half,
        layer: LAYER_RAIN,
        sprite: Sprite::FLAT,
    })
}

impl ScreenStreak {
    /// One value of the streak (to pull its cache line in ahead of use).
    #[inline(always)]
    pub fn touch(&self) -> f32 {
        self.half
    }

    /// The drop's received light I_R, per channel (relative units).
    pub fn light(&self) -> Vec3 {
        self.light
    }

    /// r, the share of its own light it shows.
    pub fn reflectance(&self) -> f32 {
        self.reflectance
    }

    /// Which effect's layers it draws into ([`LAYER_RAIN`], [`LAYER_SNOW`]).
    pub fn layer(&self) -> u8 {
        self.layer
    }

    /// Its sprite.
    pub fn sprite(&self) -> Sprite {
        self.sprite
    }

    /// The streak drawn into `layer`'s layers with `sprite` across it, its light `light`, r
    /// `reflectance` and α scaled by `opacity` (a particle's share of its band's silhouette
    /// and its fading with distance).
    pub fn with_particle(
        mut self,
        layer: u8,
        sprite: Sprite,
        light: Vec3,
        reflectance: f32,
        opacity: f32,
    ) -> Self {
        self.layer = layer;
        self.sprite = sprite;
        self.light = light;
        self.reflectance = reflectance;
        self.alpha *= opacity;
        self
    }

    /// The streak moved by `by`, px.
    pub(crate) fn translated(mut self, by: Vec2) -> Self {
        self.a += by;
        self.b += by;
        self.min += by;
        self.max += by;
        self
    }

    /// α, the share of the exposure a pixel on its path is covered (times its opacity).
    pub fn alpha(&self) -> f32 {
        self.alpha
    }

    /// The sprite and layer as the packed float: layer·8 + kind + turn.
    fn sprite_code(&self) -> f32 {
        f32::from(self.layer) * 8.0 + f32::from(self.sprite.kind) + self.sprite.turn
    }

    /// The streak as 16 floats for the GPU pass: a.xy, the unit direction | length, reach
    /// (the distance from the axis beyond which a pixel gets no coverage), w_a, w_b | 1/z_a,
    /// 1/z_b, α, r | light rgb, sprite (layer·8 + kind + turn: 0 for rain). Direction, length and reach are the values
    /// [`Self::fragment`] uses, so the shader does not compute its own.
    pub fn packed(&self) -> [f32; 16] {
        [
            self.a.x,
            self.a.y,
            self.dir.x,
            self.dir.y,
            self.len,
            reach(self.wa, self.wb),
            self.wa,
            self.wb,
            self.inv_za,
            self.inv_zb,
            self.alpha,
            self.reflectance,
            self.light.x,
            self.light.y,
            self.light.z,
            self.sprite_code(),
        ]
    }

    /// The streak's opacity-area inside a `width` × `height` frame, px²: α times the length of
    /// its axis inside the frame times its mean width there, the sum of its pixels' α·coverage
    /// up to the anti-aliased ends. Over the whole axis it is (π/4)·w²·sec θ (streaks are at least a
    /// pixel long, see [`screen_streak`]), which goes as 1/z² with the drop's depth z.
    pub fn opacity_area_in(&self, width: f32, height: f32) -> f32 {
        let inside = |p: Vec2| p.x >= 0.0 && p.y >= 0.0 && p.x <= width && p.y <= height;
        if self.len <= 1e-6 {
            let w = 0.5 * (self.wa + self.wb);
            return if inside(self.a) {
                self.alpha * w * w
            } else {
                0.0
            };
        }
        // Liang–Barsky: the part t ∈ [t0, t1] of a + t·(b − a) inside the frame.
        let d = self.b - self.a;
        let (mut t0, mut t1) = (0.0f32, 1.0f32);
        for (p, q) in [
            (-d.x, self.a.x),
            (d.x, width - self.a.x),
            (-d.y, self.a.y),
            (d.y, height - self.a.y),
        ] {
            if p == 0.0 {
                if q < 0.0 {
                    return 0.0;
                }
            } else if p < 0.0 {
                t0 = t0.max(q / p);
            } else {
                t1 = t1.min(q / p);
            }
        }
        if t1 <= t0 {
            return 0.0;
        }
        // The width is linear along the axis: its mean over [t0, t1] is its value midway.
        let w = self.wa + (self.wb - self.wa) * (0.5 * (t0 + t1));
        self.alpha * w * self.len * (t1 - t0)
    }

    /// Pixel rows and columns the streak may touch: (x0, x1, y0, y1), end-exclusive, clipped
    /// to a `width` × `height` frame.
    pub fn pixel_bounds(&self, width: u32, height: u32) -> (u32, u32, u32, u32) {
        // Clamped first, so truncation is the floor (no libm floor/ceil on SSE2 targets).
        let lo = |v: f32, hi: u32| floor_nonneg(v.clamp(0.0, hi as f32)) as u32;
        let up = |v: f32, hi: u32| ceil_nonneg(v.clamp(0.0, hi as f32)) as u32;
        (
            lo(self.min.x, width),
            up(self.max.x, width),
            lo(self.min.y, height),
            up(self.max.y, height),
        )
    }

    /// Pixel columns (x0, x1), end-exclusive, that the streak may touch within pixel rows
    /// `rows`, inside its box's columns `bx0..bx1` ([`Self::pixel_bounds`]): a covered pixel's centre lies less
    /// than ½ px beyond either end and less than the reach (½·w + ½, at least 1) across, so
    /// within r = ½·max(w) + 1.5 of the axis segment; the segment's part within r of the rows'
    /// centres, widened by r and a pixel for rounding, holds every column it covers there. A
    /// slanted streak then meets far fewer tiles than its bounding box does.
    pub(crate) fn columns_in_rows(
        &self,
        rows: std::ops::Range<u32>,
        (bx0, bx1): (u32, u32),
        width: u32,
    ) -> (u32, u32) {
        let r = 0.5 * self.wa.max(self.wb) + 1.5;
        let (ylo, yhi) = (
            idx_f32(rows.start as usize) + 0.5 - r,
            idx_f32(rows.end as usize) - 0.5 + r,
        );
        let dy = self.b.y - self.a.y;
        let (t0, t1) = if dy.abs() > 1e-6 {
            let (ta, tb) = ((ylo - self.a.y) / dy, (yhi - self.a.y) / dy);
            (ta.min(tb).max(0.0), ta.max(tb).min(1.0))
        } else {
            (0.0, 1.0)
        };
        // (false for NaN too)
        if t0
            .partial_cmp(&t1)
            .is_none_or(|o| o == std::cmp::Ordering::Greater)
        {
            return (bx0, bx0);
        }
        let (xa, xb) = (
            self.a.x + (self.b.x - self.a.x) * t0,
            self.a.x + (self.b.x - self.a.x) * t1,
        );
        let pad = r + 1.0;
        let lo = |v: f32| floor_nonneg(v.clamp(0.0, width as f32)) as u32;
        let up = |v: f32| ceil_nonneg(v.clamp(0.0, width as f32)) as u32;
        let (x0, x1) = (lo(xa.min(xb) - pad).max(bx0), up(xa.max(xb) + pad).min(bx1));
        (x0, x1.max(x0))
    }

    /// Coverage of the pixel centred at `p` and the depth there: (α·coverage, depth m), or
    /// None when the pixel is off the streak. Mirrored line for line in `rain.wgsl`.
    #[inline]
    pub fn fragment(&self, p: Vec2) -> Option<(f32, f32)> {
        let (dir, len) = (self.dir, self.len);
        let q = p - self.a;
        let along = q.dot(dir);
        let across = q.perp_dot(dir).abs();
        let k = if len > 1e-6 {
            (along / len).clamp(0.0, 1.0)
        } else {
            0.0
        };
        let width = self.wa + (self.wb - self.wa) * k;
        let mut cov_across = if width >= 1.0 {
            (0.5 * width + 0.5 - across).clamp(0.0, 1.0)
        } else {
            width * (1.0 - across).clamp(0.0, 1.0)
        };
        if self.sprite.kind != SPRITE_FLAT && width >= 1.0 {
            let p =
                self.sprite
                    .density(across / (0.5 * width), along.min(len - along), 0.5 * width);
            cov_across *= 1.0 + sprite_ramp(width) * (p - 1.0);
        }
        let cov_along = (along + 0.5)
            .clamp(0.0, 1.0)
            .min((len - along + 0.5).clamp(0.0, 1.0));
        let cov = cov_across * cov_along;
        if cov <= 0.0 {
            return None;
        }
        // A sprite's peak (up to 1.6 at a flake's middle) times α can pass 1 on a short
        // path: a coverage is at most 1.
        Some((
            (self.alpha * cov).min(1.0),
            1.0 / (self.inv_za + (self.inv_zb - self.inv_za) * k),
        ))
    }

    /// [`Self::fragment`]'s coverage and inverse depth (0 off the streak) at the point
    /// `along` px along the axis from `a` and `across` px off it, for the walk of
    /// [`for_each_fragment`]: a product by 1/L for the division by L, compare-selects for the
    /// clamps. `THIN`: the streak is under a pixel wide all along (the coverage across is
    /// w·(1 − d)).
    #[inline(always)]
    pub(crate) fn coverage<const THIN: bool>(&self, along: f32, across: f32) -> (f32, f32) {
        let k = clamp01(along * self.inv_len);
        let width = self.wa + (self.wb - self.wa) * k;
        let mut cov_across = if THIN {
            width * pos(1.0 - across)
        } else if width >= 1.0 {
            clamp01(0.5 * width + 0.5 - across)
        } else {
            width * clamp01(1.0 - across)
        };
        if !THIN && self.sprite.kind != SPRITE_FLAT && width >= 1.0 {
            let p = self.sprite.density(
                across / (0.5 * width),
                least(along, self.len - along),
                0.5 * width,
            );
            cov_across *= 1.0 + sprite_ramp(width) * (p - 1.0);
        }
        let cov_along = clamp01(least(along, self.len - along) + 0.5);
        (
            (self.alpha * cov_across * cov_along).min(1.0),
            self.inv_za + (self.inv_zb - self.inv_za) * k,
        )
    }
}

impl ScreenStreak {
    /// [`Self::coverage`] for four pixels, lane for lane the same bits.
    #[inline(always)]
    pub(crate) fn coverage_x4<const THIN: bool>(&self, along: Vec4, across: Vec4) -> (Vec4, Vec4) {
        let (zero, one, half) = (Vec4::ZERO, Vec4::ONE, Vec4::splat(0.5));
        let clamp01 = |x: Vec4| x.max(zero).min(one);
        let k = clamp01(along * self.inv_len);
        let width = Vec4::splat(self.wa) + Vec4::splat(self.wb - self.wa) * k;
        let mut cov_across = if THIN {
            width * (one - across).max(zero)
        } else {
            let wide = clamp01(half * width + half - across);
            let thin = width * clamp01(one - across);
            Vec4::select(width.cmpge(one), wide, thin)
        };
        if !THIN && self.sprite.kind != SPRITE_FLAT {
            // As `coverage`, lane by lane: only where the band is a pixel wide or more.
            let p = self.sprite.density_x4(
                across / (half * width),
                along.min(Vec4::splat(self.len) - along),
                half * width,
            );
            let ramp = clamp01(half * width - one);
            let shaped = cov_across * (one + ramp * (p - one));
            cov_across = Vec4::select(width.cmpge(one), shaped, cov_across);
        }
        let cov_along = clamp01(along.min(Vec4::splat(self.len) - along) + half);
        (
            (Vec4::splat(self.alpha) * cov_across * cov_along).min(one),
            Vec4::splat(self.inv_za) + Vec4::splat(self.inv_zb - self.inv_za) * k,
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::{Mat3, Vec3};

    #[test]
    fn opacity_area_is_the_sum_of_the_pixels_coverage() {
        // Against ScreenStreak::fragment summed over every pixel of the frame, for random drops
        // near and far, thin and wide, many leaving the frame: the analytic α·w·(length inside)
        // that the billboards' opacity balance integrates.
        use rand::{Rng, SeedableRng};
        let (w, h) = (96usize, 64usize);
        let cam = Camera::new(
            w as u32,
            h as u32,
            [60.0, 60.0, 48.0, 32.0],
            Vec3::ZERO,
            Mat3::IDENTITY,
        )
        .unwrap();
        let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(17);
        let (mut checked, mut clipped) = (0, 0);
        for _ in 0..600 {
            let z: f32 = rng.random_range(0.2..6.0);
            let p = Vec3::new(
                rng.random_range(-1.2..1.2) * z,
                rng.random_range(-1.0..1.0) * z,
                -z,
            );
            let v = Vec3::new(
                rng.random_range(-4.0..4.0),
                rng.random_range(-9.0..-2.0),
                rng.random_range(-2.0..2.0),
            );
            let d = Particle {
                position_m: p,
                velocity_m_s: v,
                diameter_m: rng.random_range(0.5e-3..4e-3),
                id: [0; 5],
            };
            let Some(s) = screen_streak(&cam, &d, 1.0 / 30.0, Vec3::ZERO) else {
                continue;
            };
            let sum: f32 = (0..w * h)
                .filter_map(|i| s.fragment(Vec2::new((i % w) as f32 + 0.5, (i / w) as f32 + 0.5)))
                .map(|f| f.0)
                .sum();
            let area = s.opacity_area_in(w as f32, h as f32);
            // The pixel grid samples the streak: its anti-aliased ends and the frame's edges
            // are off by at most about a pixel of length.
            let slack = 2.0 * s.alpha * (s.wa.max(s.wb) + 1.0);
            assert!(
                (sum - area).abs() <= 0.03 * area + slack,
                "{sum} vs {area} ({s:?})"
            );
            checked += 1;
            clipped += usize::from(
                s.min.x < 0.0 || s.min.y < 0.0 || s.max.x > w as f32 || s.max.y > h as f32,
            );
        }
        assert!(
            checked > 200 && clipped > 50,
            "{checked} streaks, {clipped} clipped"
        );
        // off the frame entirely: nothing
        let off = Particle {
            position_m: Vec3::new(5.0, 0.0, -1.0),
            velocity_m_s: Vec3::new(0.0, -6.0, 0.0),
            diameter_m: 2e-3,
            id: [0; 5],
        };
        assert!(
            screen_streak(&cam, &off, 1.0 / 30.0, Vec3::ZERO)
                .is_none_or(|s| s.opacity_area_in(w as f32, h as f32) == 0.0)
        );
    }

    #[test]
    fn defocus_keeps_each_drops_opacity_area_and_widens_by_the_blur_circle() {
        // Drops near and far through a wide aperture focused at 3 m, in a frame large enough to
        // hold every streak whole: the sum of α·coverage over the pixels, ScreenStreak::fragment
        // at every pixel centre, is the pinhole streak's, drop by drop; each end's width grows by
        // the thin lens's blur circle at that end's depth.
        use crate::scene::camera::ThinLens;
        use rand::{Rng, SeedableRng};
        let (w, h) = (400usize, 400usize);
        let cam = Camera::new(
            w as u32,
            h as u32,
            [600.0, 600.0, 200.0, 200.0],
            Vec3::ZERO,
            Mat3::IDENTITY,
        )
        .unwrap();
        // f = 600 px · 36 mm / 400 px = 54 mm at f/1.4
        let lens = ThinLens::new(1.4, 3.0, 36.0).unwrap();
        let defocus = lens.defocus(&cam).unwrap();
        let mut rng = rand_pcg::Pcg64Mcg::seed_from_u64(5);
        let sum = |s: &ScreenStreak| -> f64 {
            (0..w * h)
                .filter_map(|i| s.fragment(Vec2::new((i % w) as f32 + 0.5, (i / w) as f32 + 0.5)))
                .map(|f| f64::from(f.0))
                .sum()
        };
        let (mut worst, mut blurred) = (0.0f64, 0);
        let (mut total_pin, mut total_lensed) = (0.0f64, 0.0f64);
        for _ in 0..150 {
            let z: f32 = rng.random_range(0.3..8.0);
            let p = Vec3::new(
                rng.random_range(-0.3..0.3) * z,
                rng.random_range(-0.2..0.3) * z,
                -z,
            );
            let v = Vec3::new(
                rng.random_range(-1.0..1.0),
                rng.random_range(-7.0..-2.0),
                0.0,
            );
            let d = Particle {
                position_m: p,
                velocity_m_s: v,
                diameter_m: rng.random_range(0.5e-3..4e-3),
                id: [0; 5],
            };
            let exposure = rng.random_range(1e-3..1.0 / 60.0);
            let (Some(pin), Some(lensed)) = (
                screen_streak(&cam, &d, exposure, Vec3::ZERO),
                screen_streak_through(&cam, Some(&defocus), &d, exposure, Vec3::ZERO),
            ) else {
                continue;
            };
            let inside = |s: &ScreenStreak| {
                s.min.x > 1.0
                    && s.min.y > 1.0
                    && s.max.x < w as f32 - 1.0
                    && s.max.y < h as f32 - 1.0
            };
            if !inside(&pin) || !inside(&lensed) {
                continue;
            }
            // the widths: the thin-lens circle at each end's depth (f64, as ThinLens writes it)
            for (w0, w1, inv_z) in [
                (pin.wa, lensed.wa, pin.inv_za),
                (pin.wb, lensed.wb, pin.inv_zb),
            ] {
                let c_m = lens.blur_diameter_m(&cam, 1.0 / f64::from(inv_z));
                let c_px = (c_m / lens.pixel_pitch_m(&cam)).min(f64::from(defocus.max_px));
                assert!(
                    (f64::from(w1 - w0) - c_px).abs() < 1e-3 * c_px.max(1.0),
                    "{w0} {w1} {c_px}"
                );
            }
            let (a, b) = (sum(&pin), sum(&lensed));
            // The drop's image: π/4 · (D·f/z)² · sec θ, z and sec θ = |p|/z at each end.
            let (start, end) = (p - v * exposure, p);
            let wz = |q: Vec3| f64::from(d.diameter_m * 600.0 / -q.z);
            let sec = |q: Vec3| f64::from(q.length() / -q.z);
            let analytic = f64::from(SILHOUETTE)
                * (0.5 * (wz(start) + wz(end))).powi(2)
                * 0.5
                * (sec(start) + sec(end));
            // The analytic opacity-area is kept exactly; the pixel grid samples a streak's
            // anti-aliased ends, so a streak about a pixel long sums to within a few per cent
            // of it: drop by drop for streaks 4 px long or more, and over all drops.
            let rel = (b - a).abs() / a;
            if pin.len >= 4.0 {
                worst = worst.max(rel);
                assert!(
                    rel < 0.02 && (b - analytic).abs() < 0.02 * analytic,
                    "{a} vs {b} (analytic {analytic}): {pin:?} {lensed:?}"
                );
            }
            let kept = f64::from(lensed.opacity_area_in(w as f32, h as f32));
            assert!(
                (kept - analytic).abs() < 1e-4 * analytic,
                "{kept} vs {analytic}"
            );
            (total_pin, total_lensed) = (total_pin + a, total_lensed + b);
            blurred += usize::from(lensed.wa > pin.wa + 2.0);
        }
        let total = (total_lensed - total_pin).abs() / total_pin;
        assert!(
            blurred > 30 && total < 0.005,
            "{blurred} drops visibly blurred; worst {worst}, all drops {total}"
        );
        eprintln!(
            "defocus conservation: worst {worst:.2e} per drop (≥ 4 px), {total:.2e} over all"
        );
    }
}
