//! The windshield as a stage of the frame: the glass at the frame's time ([`Glass`], taken from
//! a [`Windshield`]), placed in front of the camera where it just covers the frame
//! ([`GlassView`]), its drops drawn as refracting metaballs ([`super::render`]) over everything
//! behind it and the wipers' blades over them ([`WindshieldStage`], a whole-frame stage: a drop
//! refracts what lies around it, so it draws after every band of every other stage).

use super::render::{self, RefractMode, Refraction, THRESHOLD, WATER_INDEX};
use super::sim::{Metaball, Windshield};
use crate::error::Result;
use crate::scene::camera::{Camera, Defocus};
use crate::stage::layers::{Layer, LayerSet};
use crate::stage::{Stage, Whole};

/// What the windshield stage draws.
pub const LAYERS: LayerSet = LayerSet::of(&[Layer::DropMask, Layer::DropHeight]);

/// The blades' rubber and arm, relative to a white surface under the same sky.
pub const BLADE_ALBEDO: f32 = 0.04;

/// The least distance from the camera to the glass, m.
pub const MIN_GLASS_DISTANCE_M: f64 = 0.2;

/// The drops' refraction looks into a copy box-averaged to this many px on its short side (the
/// paper's 64²).
pub const LOOKUP_PX: usize = 64;

/// Metaballs smaller than this on screen (radius, px) are not drawn.
const MIN_RADIUS_PX: f32 = 0.05;

/// The typical drop's base radius, mm, whose edge sets the water surface's slope.
const TYPICAL_DROP_MM: f64 = 1.5;

/// One wiper's blade at the glass's time.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Blade {
    /// The pivot, glass mm (x across, y down the slope).
    pub pivot_mm: [f64; 2],
    /// The blade's angle from the glass's horizontal towards its top, rad.
    pub angle_rad: f64,
    /// Its length from the pivot, mm.
    pub length_mm: f64,
    /// Its width, mm.
    pub width_mm: f64,
}

/// A windshield as one frame draws it: its size, its drops' metaballs and its blades at one
/// time.
#[derive(Debug, Clone, PartialEq)]
pub struct Glass {
    /// Glass width, mm.
    pub width_mm: f64,
    /// Glass height along its slope, mm.
    pub height_mm: f64,
    /// Inclination from the horizontal, deg.
    pub tilt_deg: f64,
    /// The mean of the advancing and receding contact angles, deg.
    pub contact_deg: f64,
    /// Every metaball (the drops' and their sub-metaballs), glass mm.
    pub metaballs: Vec<Metaball>,
    /// The wipers' blades.
    pub blades: Vec<Blade>,
}

impl Glass {
    /// The glass of `w` as it is now.
    pub fn of(w: &Windshield) -> Self {
        let c = w.config();
        let angle = w.wiper_angle_rad();
        Glass {
            width_mm: c.width_mm,
            height_mm: c.height_mm,
            tilt_deg: c.tilt_deg,
            contact_deg: 0.5 * (c.advancing_deg + c.receding_deg),
            metaballs: w.metaballs(),
            blades: c
                .wipers
                .iter()
                .map(|b| Blade {
                    pivot_mm: b.pivot_mm,
                    angle_rad: angle,
                    length_mm: b.length_mm,
                    width_mm: b.width_mm,
                })
                .collect(),
        }
    }

    /// The foreshortening of the glass's slope as the camera sees it, sin(tilt) (at least
    /// sin 1°: the camera looks horizontally).
    fn fore(&self) -> f64 {
        self.tilt_deg.max(1.0).to_radians().sin()
    }
}

/// How the camera sees the glass: a plane `distance_m` in front of it, the glass's centre at the
/// frame's centre, its slope foreshortened by sin(tilt).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GlassView {
    /// The camera's focal length, px.
    pub focal_px: f64,
    /// The principal point, px.
    pub principal_px: [f64; 2],
    /// The frame's size, px.
    pub width: usize,
    /// The frame's height, px.
    pub height: usize,
    /// From the camera to the glass, m.
    pub distance_m: f64,
    /// The drops' blur circle, px (0: in focus).
    pub blur_px: f64,
}

impl GlassView {
    /// The view of `glass` from `cam` where the glass just covers the frame (a driver's view:
    /// the windshield fills it), at least [`MIN_GLASS_DISTANCE_M`]; the drops blurred by the
    /// camera's thin lens (`defocus`) at that distance.
    pub fn covering(glass: &Glass, cam: &Camera, defocus: Option<&Defocus>) -> Self {
        let (fx, cx, cy) = (f64::from(cam.fx), cam.cx, cam.cy);
        let (w, h) = (cam.width as usize, cam.height as usize);
        let d_mm =
            (glass.width_mm * fx / w as f64).min(glass.height_mm * glass.fore() * fx / h as f64);
        let distance_m = (d_mm * 1e-3).max(MIN_GLASS_DISTANCE_M);
        let blur_px = defocus.map_or(0.0, |d| f64::from(d.blur_px((1.0 / distance_m) as f32)));
        GlassView {
            focal_px: fx,
            principal_px: [f64::from(cx), f64::from(cy)],
            width: w,
            height: h,
            distance_m,
            blur_px: blur_px.min(1024.0),
        }
    }

    /// Image px per glass mm across the glass.
    pub fn px_per_mm(&self) -> f64 {
        self.focal_px / (self.distance_m * 1e3)
    }

    /// Glass mm to image px (x, y).
    pub fn to_px(&self, glass: &Glass, x_mm: f64, y_mm: f64) -> [f64; 2] {
        let s = self.px_per_mm();
        [
            self.width as f64 / 2.0 + (x_mm - glass.width_mm / 2.0) * s,
            self.height as f64 / 2.0 + (y_mm - glass.height_mm / 2.0) * s * glass.fore(),
        ]
    }
}

/// The windshield stage of one frame: its metaballs on screen, the refraction and the blades.
pub struct WindshieldStage {
    centres_px: Vec<[f32; 2]>,
    radii_px: Vec<f32>,
    refraction: Refraction,
    view: GlassView,
    glass: Glass,
}

impl WindshieldStage {
    /// `glass` seen by `cam` through its thin lens (`defocus`; None: a pinhole).
    pub fn new(glass: &Glass, cam: &Camera, defocus: Option<&Defocus>) -> Result<Self> {
        let view = GlassView::covering(glass, cam, defocus);
        let s = view.px_per_mm();
        let (mut centres_px, mut radii_px) = (Vec::new(), Vec::new());
        for m in &glass.metaballs {
            let r = (m.radius_mm * s) as f32;
            if r > MIN_RADIUS_PX {
                let [x, y] = view.to_px(glass, m.x_mm, m.y_mm);
                centres_px.push([x as f32, y as f32]);
                radii_px.push(r);
            }
        }
        // a cap at the mean contact angle: the edge's slope tan θ for a drop of the typical size
        let theta = glass.contact_deg.to_radians().min(80f64.to_radians());
        let refraction = Refraction {
            mode: RefractMode::Offset,
            focal_px: view.focal_px,
            principal_px: view.principal_px,
            index: WATER_INDEX,
            slope_px: TYPICAL_DROP_MM * s * theta.tan(),
            lookup_px: LOOKUP_PX,
            blur_px: view.blur_px,
        };
        refraction.validate()?;
        Ok(WindshieldStage {
            centres_px,
            radii_px,
            refraction,
            view,
            glass: glass.clone(),
        })
    }

    /// The metaballs on screen: centres (x, y) and radii, px.
    pub fn metaballs_px(&self) -> (&[[f32; 2]], &[f32]) {
        (&self.centres_px, &self.radii_px)
    }

    /// The refraction the drops draw with.
    pub fn refraction(&self) -> &Refraction {
        &self.refraction
    }

    /// The (compressed) metaball field over the frame.
    pub fn field(&self) -> Result<Vec<f32>> {
        let v = &self.view;
        render::height_map(&self.centres_px, &self.radii_px, v.width, v.height, true)
    }

    /// What follows the refraction: the field above its threshold into `drop_height` (when
    /// kept), then the blades over `rgb`.
    pub fn finish(&self, rgb: &mut [f32], field: &[f32], drop_height: Option<&mut [f32]>) {
        if let Some(h) = drop_height {
            for (h, &v) in h.iter_mut().zip(field) {
                *h = (v - THRESHOLD).max(0.0);
            }
        }
        self.draw_blades(rgb);
    }

    /// The wipers' blades on screen, as [`Self::draw_blades`] draws them (and the GPU's pass).
    pub fn blades_px(&self) -> Vec<BladePx> {
        let (v, g) = (&self.view, &self.glass);
        let s = v.px_per_mm();
        let fore = g.fore();
        let (w, h) = (v.width as i64, v.height as i64);
        g.blades
            .iter()
            .map(|b| {
                let (c, sn) = (b.angle_rad.cos(), b.angle_rad.sin());
                let [p0, p1] = [
                    v.to_px(g, b.pivot_mm[0], b.pivot_mm[1]),
                    v.to_px(
                        g,
                        b.pivot_mm[0] + b.length_mm * c,
                        b.pivot_mm[1] - b.length_mm * sn,
                    ),
                ]
                .map(|p| p.map(|x| f64::from(x as f32)));
                let pad = b.width_mm * s;
                let lo = [
                    (p0[0].min(p1[0]) - pad).floor() as i64,
                    (p0[1].min(p1[1]) - pad).floor() as i64,
                ];
                let hi = [
                    (p0[0].max(p1[0]) + pad).ceil() as i64,
                    (p0[1].max(p1[1]) + pad).ceil() as i64,
                ];
                BladePx {
                    pivot_px: v.to_px(g, b.pivot_mm[0], b.pivot_mm[1]),
                    mm_per_px: [1.0 / s, 1.0 / (s * fore)],
                    cos_sin: [c, sn],
                    half_width_mm: 0.5 * b.width_mm,
                    length_mm: b.length_mm,
                    // one pixel of edge, measured in the blade's across direction on screen
                    px_across: s * sn.hypot(c * fore),
                    px_per_mm: s,
                    bounds: [lo[0].max(0), lo[1].max(0), hi[0].min(w), hi[1].min(h)],
                }
            })
            .collect()
    }

    /// Draws the wipers' blades into `rgb` (H·W·3): dark ([`BLADE_ALBEDO`], in the frame's
    /// units: 1 is a white surface under the open sky), anti-aliased over one pixel across
    /// their edges, sharp (not defocused).
    pub fn draw_blades(&self, rgb: &mut [f32]) {
        let w = self.view.width;
        for b in self.blades_px() {
            let [x0, y0, x1, y1] = b.bounds;
            for y in y0..y1 {
                for x in x0..x1 {
                    let Some(cover) = b.cover(x as f64 + 0.5, y as f64 + 0.5) else {
                        continue;
                    };
                    let i = 3 * (y as usize * w + x as usize);
                    for px in &mut rgb[i..i + 3] {
                        *px *= 1.0 - cover;
                        *px += cover * BLADE_ALBEDO;
                    }
                }
            }
        }
    }
}

/// A wiper's blade on screen: a bar from its pivot, anti-aliased over one pixel across its
/// edges and at its tip, drawn in its bounding box.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BladePx {
    /// The pivot, px (x, y).
    pub pivot_px: [f64; 2],
    /// Glass mm per px across the glass and down its slope (foreshortened).
    pub mm_per_px: [f64; 2],
    /// The blade's angle's cosine and sine.
    pub cos_sin: [f64; 2],
    /// Half its width, mm.
    pub half_width_mm: f64,
    /// Its length from the pivot, mm.
    pub length_mm: f64,
    /// Screen px per glass mm across its edges.
    pub px_across: f64,
    /// Screen px per glass mm along it.
    pub px_per_mm: f64,
    /// Its bounding box, px: x0, y0, x1, y1 (ends excluded), inside the frame.
    pub bounds: [i64; 4],
}

impl BladePx {
    /// The blade's coverage of the pixel whose centre is (`x`, `y`) px, None behind the pivot.
    pub fn cover(&self, x: f64, y: f64) -> Option<f32> {
        let dx = (x - self.pivot_px[0]) * self.mm_per_px[0];
        let dy = (self.pivot_px[1] - y) * self.mm_per_px[1];
        let [c, sn] = self.cos_sin;
        let along = dx * c + dy * sn;
        let across = -dx * sn + dy * c;
        if along < 0.0 {
            return None;
        }
        let cover = ((self.half_width_mm - across.abs()) * self.px_across + 0.5).clamp(0.0, 1.0)
            * ((self.length_mm - along) * self.px_per_mm + 0.5).clamp(0.0, 1.0);
        Some(cover as f32)
    }
}

impl Stage for WindshieldStage {
    fn layers(&self) -> LayerSet {
        LAYERS
    }

    fn is_whole(&self) -> bool {
        true
    }

    /// The frame behind the glass refracted through the drops, their coverage and field, then
    /// the blades.
    fn whole(&self, frame: &mut Whole<'_>) -> Result<()> {
        let (w, h) = (self.view.width, self.view.height);
        let field = self.field()?;
        let mut behind =
            crate::error::try_filled_par("the frame behind the glass", 3 * w * h, 0.0f32)?;
        behind.copy_from_slice(frame.rgb);
        let mut scratch;
        let mask: &mut [f32] = match frame.layers.get_mut(Layer::DropMask) {
            Some(m) => m,
            None => {
                scratch = crate::error::try_filled_par("the drops' coverage", w * h, 0.0f32)?;
                &mut scratch
            }
        };
        render::refract_frame(&behind, w, h, &field, &self.refraction, frame.rgb, mask)?;
        let height = frame.layers.get_mut(Layer::DropHeight).map(|b| &mut **b);
        self.finish(frame.rgb, &field, height);
        Ok(())
    }
}
