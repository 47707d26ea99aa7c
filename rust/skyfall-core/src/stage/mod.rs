//! The seam every effect of a frame goes through: a [`Stage`] declares the layers it draws and
//! draws itself row by row or band by band; a frame is the list of its stages, in physical
//! order, drawn by one generic loop ([`draw_bands`]) on the float output, and the same list
//! decides once which outputs can draw the frame ([`Plan`]).
//!
//! This module is a leaf (it names only the layers), so each effect's folder can implement
//! [`Stage`] beside its method (`haze::stage`, `cloud::stage`, `glow::stage`) without a
//! module importing one that imports it back; the frame pipeline (`frame::stages`) builds
//! the list.

use crate::error::{Error, Param, Result};
use layers::{Layer, LayerSet, Layers};
use rayon::prelude::*;

pub mod layers;

/// One row of a band, as a stage draws it.
pub struct Row<'r> {
    /// The row's index in the frame.
    pub y: u32,
    /// Linear RGB, W·3.
    pub rgb: &'r mut [f32],
    /// Depth along the optical axis, m (inf for sky), W.
    pub depth_m: &'r mut [f32],
    /// The frame's layers' values on this row, W each (those the frame draws).
    pub layers: Layers<&'r mut [f32]>,
}

/// A band of whole rows, as a stage draws it.
pub struct Band<'b> {
    /// The band's first row in the frame.
    pub y0: usize,
    /// The frame's width, px.
    pub width: usize,
    /// Linear RGB, rows·W·3.
    pub rgb: &'b mut [f32],
    /// Depth along the optical axis, m, rows·W.
    pub depth_m: &'b mut [f32],
    /// The frame's layers' values on this band, rows·W each (those the frame draws).
    pub layers: Layers<&'b mut [f32]>,
}

impl Band<'_> {
    /// The band's rows.
    pub fn rows(&self) -> usize {
        self.depth_m.len() / self.width.max(1)
    }

    /// Row `k` of the band.
    pub fn row(&mut self, k: usize) -> Row<'_> {
        let w = self.width;
        let mut layers = Layers::default();
        for (slot, l) in self.layers.0.iter_mut().zip(Layer::ALL) {
            if let Some(b) = slot {
                layers.set(l, &mut b[k * w..(k + 1) * w]);
            }
        }
        Row {
            y: (self.y0 + k) as u32,
            rgb: &mut self.rgb[3 * k * w..3 * (k + 1) * w],
            depth_m: &mut self.depth_m[k * w..(k + 1) * w],
            layers,
        }
    }
}

/// One stage of a frame, prepared for it: the scene, the clouds, the haze, the glows, the
/// particles, and the effects to come. A stage draws row by row ([`Stage::row`], every row of
/// a band in turn, each row through every row stage while it is in cache) or on the whole band
/// after its rows ([`Stage::band`]: the particles, whose streaks are binned by bands).
pub trait Stage: Sync {
    /// The layers the stage writes (every value of each, on every row or band it draws).
    fn layers(&self) -> LayerSet;

    /// Draws one row.
    fn row(&self, _row: &mut Row<'_>) {}

    /// Draws a band, after every row stage drew its rows.
    fn band(&self, _band: &mut Band<'_>) {}

    /// Whether the stage draws on the whole frame ([`Stage::whole`]) after every band: a stage
    /// that reads other rows' pixels (the windshield's drops refract what lies around them).
    fn is_whole(&self) -> bool {
        false
    }

    /// Draws on the whole frame, after every band of every stage (see [`draw_whole`]).
    fn whole(&self, _frame: &mut Whole<'_>) -> Result<()> {
        Ok(())
    }
}

/// The whole frame, as a whole-frame stage ([`Stage::whole`]) draws it.
pub struct Whole<'f> {
    /// The frame's width, px.
    pub width: usize,
    /// Linear RGB, H·W·3.
    pub rgb: &'f mut [f32],
    /// Depth along the optical axis, m, H·W.
    pub depth_m: &'f mut [f32],
    /// The frame's layers (those the frame draws), H·W each.
    pub layers: Layers<&'f mut [f32]>,
}

impl Whole<'_> {
    /// The frame's height, px.
    pub fn height(&self) -> usize {
        self.depth_m.len() / self.width.max(1)
    }
}

/// Whether any of `stages` draws on the whole frame.
pub fn any_whole(stages: &[&dyn Stage]) -> bool {
    stages.iter().any(|s| s.is_whole())
}

/// The whole-frame stages of `stages`, in their order, over a frame drawn by [`draw_bands`].
pub fn draw_whole(stages: &[&dyn Stage], frame: &mut Whole<'_>) -> Result<()> {
    for s in stages.iter().filter(|s| s.is_whole()) {
        s.whole(frame)?;
    }
    Ok(())
}

/// Draws `stages`, in their order, over a frame `width` wide: bands of `band_rows` rows in
/// parallel, each row through every stage's [`Stage::row`], then the band through every
/// stage's [`Stage::band`]. `layers` are the frame's layer buffers, each as long as `depth_m`.
pub fn draw_bands(
    stages: &[&dyn Stage],
    width: usize,
    band_rows: usize,
    rgb: &mut [f32],
    depth_m: &mut [f32],
    layers: Layers<&mut [f32]>,
) {
    let band = band_rows * width;
    if band == 0 {
        return;
    }
    let bands = depth_m.len().div_ceil(band);
    let mut layer_bands: Vec<Layers<&mut [f32]>> = (0..bands).map(|_| Layers::default()).collect();
    for (slot, l) in layers.0.into_iter().zip(Layer::ALL) {
        if let Some(buf) = slot {
            for (b, chunk) in layer_bands.iter_mut().zip(buf.chunks_mut(band)) {
                b.set(l, chunk);
            }
        }
    }
    rgb.par_chunks_mut(3 * band)
        .zip(depth_m.par_chunks_mut(band))
        .zip(layer_bands.into_par_iter())
        .enumerate()
        .for_each(|(bi, ((rgb, depth_m), layers))| {
            draw_band(
                stages,
                &mut Band {
                    y0: bi * band_rows,
                    width,
                    rgb,
                    depth_m,
                    layers,
                },
            );
        });
}

/// One band through `stages`: each row through every [`Stage::row`], then the band through
/// every [`Stage::band`].
fn draw_band(stages: &[&dyn Stage], band: &mut Band<'_>) {
    for k in 0..band.rows() {
        let mut row = band.row(k);
        for s in stages {
            s.row(&mut row);
        }
    }
    for s in stages {
        s.band(band);
    }
}

/// [`draw_bands`] for an output that keeps only a band's encoding: each band is drawn into
/// scratch buffers (its linear RGB, its depth, and each layer of `drawn` that `layers` lacks;
/// one set per worker thread), then handed to `finish` with its part of `out`
/// (`out_per_px` values a pixel). The frame has `out.len() / out_per_px` pixels; `layers` are
/// the caller's full-frame buffers of the layers it keeps. Every stage writes every value of
/// what it draws, so the scratch is reused across bands without clearing.
#[allow(clippy::too_many_arguments)]
pub fn draw_bands_then<T: Send>(
    stages: &[&dyn Stage],
    width: usize,
    band_rows: usize,
    drawn: LayerSet,
    out: &mut [T],
    out_per_px: usize,
    layers: Layers<&mut [f32]>,
    finish: impl Fn(&Band<'_>, &mut [T]) + Sync,
) {
    let band = band_rows * width;
    if band == 0 || out_per_px == 0 {
        return;
    }
    let pixels = out.len() / out_per_px;
    let bands = pixels.div_ceil(band);
    let mut kept: Vec<Layers<&mut [f32]>> = (0..bands).map(|_| Layers::default()).collect();
    for (slot, l) in layers.0.into_iter().zip(Layer::ALL) {
        if let Some(buf) = slot {
            for (b, chunk) in kept.iter_mut().zip(buf.chunks_mut(band)) {
                b.set(l, chunk);
            }
        }
    }
    out.par_chunks_mut(out_per_px * band)
        .zip(kept.into_par_iter())
        .enumerate()
        .for_each_init(
            || {
                (
                    vec![0.0f32; 3 * band],
                    vec![0.0f32; band],
                    Layers::<Vec<f32>>::default(),
                )
            },
            |(rgb, depth_m, scratch), (bi, (out, kept))| {
                let n = out.len() / out_per_px;
                let mut layers: Layers<&mut [f32]> = Layers::default();
                for (slot, l) in kept.0.into_iter().zip(Layer::ALL) {
                    if let Some(b) = slot {
                        layers.set(l, b);
                    }
                }
                for l in drawn.iter() {
                    if layers.get(l).is_none() && scratch.get(l).is_none() {
                        scratch.set(l, vec![0.0f32; band]);
                    }
                }
                for (slot, l) in scratch.0.iter_mut().zip(Layer::ALL) {
                    if let Some(buf) = slot
                        && drawn.contains(l)
                        && layers.get(l).is_none()
                    {
                        layers.set(l, &mut buf[..n]);
                    }
                }
                let mut b = Band {
                    y0: bi * band_rows,
                    width,
                    rgb: &mut rgb[..3 * n],
                    depth_m: &mut depth_m[..n],
                    layers,
                };
                draw_band(stages, &mut b);
                finish(&b, out);
            },
        );
}

/// The outputs a frame can be drawn by.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Output {
    /// The linear float32 frame (`frame::float`): draws every stage, the reference.
    Float,
    /// The fused 8-bit sRGB output for 8-bit photos (`frame::srgb8`).
    Srgb8,
    /// The GPU backend (`skyfall-gpu`).
    Gpu,
}

impl Output {
    /// The output's name in messages.
    pub const fn name(self) -> &'static str {
        match self {
            Output::Float => "the float output",
            Output::Srgb8 => "the fused 8-bit output",
            Output::Gpu => "the GPU backend",
        }
    }
}

/// Which stage a declaration is. Every output draws a frame by walking its plan's list and
/// drawing each stage by its kind in one exhaustive `match`, so a new kind does not compile until
/// every output draws it (or its declaration says that output does not).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Kind {
    /// The box scene's ray cast, or the photo.
    Scene,
    /// The wet surfaces.
    Wet,
    /// The clouds.
    Clouds,
    /// The haze.
    Haze,
    /// The lights' glows.
    Glow,
    /// The particles (rain and snow).
    Particles,
    /// The windshield.
    Windshield,
}

impl Kind {
    /// The stage's name.
    pub const fn name(self) -> &'static str {
        match self {
            Kind::Scene => "scene",
            Kind::Wet => "wet",
            Kind::Clouds => "clouds",
            Kind::Haze => "haze",
            Kind::Glow => "glow",
            Kind::Particles => "particles",
            Kind::Windshield => "windshield",
        }
    }
}

/// A stage as a frame declares it before drawing: its kind, its layers and the outputs that
/// draw it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Declared {
    /// Which stage it is.
    pub kind: Kind,
    /// What it draws.
    pub layers: LayerSet,
    /// Whether the fused 8-bit output draws it.
    pub srgb8: bool,
    /// Whether the GPU backend draws it.
    pub gpu: bool,
    /// The user's parameter that asks for what an output cannot draw (`"clouds"`,
    /// `"rain_far_m"`, ...), which its error names.
    pub param: &'static str,
    /// Why an output that does not draw it does not, for the message.
    pub why_not: &'static str,
}

impl Declared {
    /// The stage's name (`"scene"`, `"clouds"`, `"haze"`, `"glow"`, `"particles"`, ...).
    pub const fn name(&self) -> &'static str {
        self.kind.name()
    }

    /// Whether `output` draws the stage.
    pub const fn drawn_by(&self, output: Output) -> bool {
        match output {
            Output::Float => true,
            Output::Srgb8 => self.srgb8,
            Output::Gpu => self.gpu,
        }
    }
}

/// A frame's stages as declared, in drawing order: what the frame draws and which outputs can
/// draw it, decided once from the stages' own declarations.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct Plan(pub Vec<Declared>);

impl Plan {
    /// Every layer the frame's stages draw.
    pub fn layers(&self) -> LayerSet {
        self.0
            .iter()
            .fold(LayerSet::EMPTY, |s, d| s.union(d.layers))
    }

    /// Whether `output` draws every stage.
    pub fn drawn_by(&self, output: Output) -> bool {
        self.0.iter().all(|d| d.drawn_by(output))
    }

    /// `Ok` when `output` draws every stage; else an error naming the first stage it cannot.
    pub fn check(&self, output: Output) -> Result<()> {
        match self.0.iter().find(|d| !d.drawn_by(output)) {
            None => Ok(()),
            Some(d) => Err(Error::Invalid {
                param: Param {
                    name: d.param,
                    index: None,
                },
                message: format!(
                    "{} does not draw the {} stage: {}",
                    output.name(),
                    d.name(),
                    d.why_not
                ),
            }),
        }
    }

    /// The stages' names, in order.
    pub fn names(&self) -> impl Iterator<Item = &'static str> + '_ {
        self.0.iter().map(Declared::name)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Writes its row index into its layer and adds 1 to red, row by row.
    struct Rows(Layer);
    impl Stage for Rows {
        fn layers(&self) -> LayerSet {
            LayerSet::of(&[self.0])
        }
        fn row(&self, row: &mut Row<'_>) {
            row.layers.get_mut(self.0).unwrap().fill(row.y as f32);
            for px in row.rgb.chunks_exact_mut(3) {
                px[0] += 1.0;
            }
        }
    }

    /// Doubles red over the band, after the rows.
    struct Bands;
    impl Stage for Bands {
        fn layers(&self) -> LayerSet {
            LayerSet::EMPTY
        }
        fn band(&self, band: &mut Band<'_>) {
            for px in band.rgb.chunks_exact_mut(3) {
                px[0] *= 2.0;
            }
            let w = band.width;
            for (k, d) in band.depth_m.chunks_mut(w).enumerate() {
                d.fill((band.y0 + k) as f32);
            }
        }
    }

    #[test]
    fn every_row_goes_through_the_row_stages_then_its_band_through_the_band_stages() {
        // 7 × 37: the last band is short (37 = 2·16 + 5).
        let (w, h) = (7, 37);
        let (mut rgb, mut depth, mut t) =
            (vec![0.5f32; 3 * w * h], vec![0.0; w * h], vec![-1.0; w * h]);
        let mut layers = Layers::default();
        layers.set(Layer::Transmittance, &mut t[..]);
        let stages: [&dyn Stage; 2] = [&Bands, &Rows(Layer::Transmittance)];
        draw_bands(&stages, w, 16, &mut rgb, &mut depth, layers);
        for y in 0..h {
            for x in 0..w {
                let i = y * w + x;
                // the row stage ran before the band stage, whatever the list's order
                assert_eq!(rgb[3 * i], (0.5 + 1.0) * 2.0);
                assert_eq!(rgb[3 * i + 1], 0.5);
                assert_eq!(t[i], y as f32);
                assert_eq!(depth[i], y as f32);
            }
        }
    }

    #[test]
    fn a_plan_names_the_first_stage_an_output_cannot_draw() {
        let stage = |kind, srgb8, gpu| Declared {
            kind,
            layers: LayerSet::EMPTY,
            srgb8,
            gpu,
            param: "p",
            why_not: "reason",
        };
        let plan = Plan(vec![
            stage(Kind::Scene, true, true),
            Declared {
                layers: LayerSet::of(&[Layer::CloudAlpha]),
                ..stage(Kind::Clouds, false, true)
            },
            Declared {
                layers: LayerSet::of(&[Layer::Transmittance]),
                ..stage(Kind::Haze, true, true)
            },
        ]);
        assert_eq!(
            plan.layers(),
            LayerSet::of(&[Layer::Transmittance, Layer::CloudAlpha])
        );
        assert!(plan.check(Output::Float).is_ok() && plan.check(Output::Gpu).is_ok());
        let refused = plan.check(Output::Srgb8);
        let Err(Error::Invalid { param, message }) = refused else {
            unreachable!("the 8-bit output draws no clouds: {refused:?}")
        };
        assert_eq!(param.name, "p");
        assert!(message.contains("8-bit") && message.contains("clouds"));
        assert!(message.contains("reason"));
        assert_eq!(
            plan.names().collect::<Vec<_>>(),
            ["scene", "clouds", "haze"]
        );
    }
}
