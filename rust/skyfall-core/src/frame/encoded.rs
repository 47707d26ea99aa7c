//! The 8-bit output of any frame: the frame's stages drawn band by band as the float output
//! draws them ([`crate::stage::draw_bands_then`]), each band encoded to 8-bit sRGB as soon as
//! it is finished, with no frame-sized float buffer. The same bytes as the float frame encoded
//! by [`crate::color::encode_srgb8`]; what the fused path ([`super::srgb8`]) does not draw
//! (clouds, a snow cover, box scenes and their glows, a windshield) is drawn here. A frame with a
//! whole-frame stage (the windshield, whose drops refract other rows) is drawn into a float
//! frame first, then through that stage, then encoded.

use super::stages::Frame;
use super::{RainReport, SceneRef, check_frame_size, check_photo};
use crate::color::encode_srgb8_serial;
use crate::error::{Error, Param, Result};
use crate::particles::composite::BAND_ROWS;
use crate::snow::streaks::SnowStats;
use crate::stage::layers::{Layer, Layers};
use crate::stage::{Output, Whole, any_whole, draw_bands, draw_bands_then, draw_whole};
use rayon::prelude::*;

/// Draws `frame` as 8-bit sRGB into `out_srgb8` (H·W·3), and into `layers` each layer the
/// caller keeps (H·W each): the frame's value where a stage draws it, the layer's neutral
/// value ([`Layer::neutral`]) where none does. Returns the rain's and the snow's reports.
pub fn draw_srgb8(
    frame: &Frame<'_>,
    out_srgb8: &mut [u8],
    layers: Layers<&mut [f32]>,
) -> Result<(Option<RainReport>, Option<SnowStats>)> {
    let cam = frame.cam;
    check_frame_size(cam)?;
    if let SceneRef::Photo { rgb, depth_m } = frame.scene {
        check_photo(cam, rgb, depth_m)?;
    }
    let n = cam.pixels();
    let length = |name: &'static str, len: usize, expected: usize| Error::Length {
        param: Param { name, index: None },
        len,
        expected,
    };
    if out_srgb8.len() != 3 * n {
        return Err(length("out", out_srgb8.len(), 3 * n));
    }
    for (slot, l) in layers.0.iter().zip(Layer::ALL) {
        if let Some(b) = slot
            && b.len() != n
        {
            return Err(length(l.name(), b.len(), n));
        }
    }
    let plan = frame.plan();
    let drawn = plan.layers();
    let prepared = frame.prepare_planned(&plan, Output::Float)?;
    // The kept layers no stage draws hold their neutral value; the others go to the stages.
    let mut kept: Layers<&mut [f32]> = Layers::default();
    for (slot, l) in layers.0.into_iter().zip(Layer::ALL) {
        match slot {
            Some(b) if drawn.contains(l) => kept.set(l, b),
            Some(b) => b.fill(l.neutral()),
            None => {}
        }
    }
    let level = crate::simd::Dispatch::detect().encode();
    let stages = prepared.stages();
    if any_whole(&stages) {
        // A whole-frame stage (the windshield) reads other rows: the float frame first, then
        // the stage, then the encoding.
        let w = cam.width as usize;
        let mut rgb = crate::error::try_filled_par("the float frame", 3 * n, 0.0f32)?;
        let mut depth = crate::error::try_filled_par("the frame's depth", n, 0.0f32)?;
        let mut scratch: Layers<Vec<f32>> = Layers::default();
        for l in drawn.iter() {
            if kept.get(l).is_none() {
                scratch.set(l, crate::error::try_filled_par(l.name(), n, 0.0f32)?);
            }
        }
        let mut all: Layers<&mut [f32]> = Layers::default();
        for (l, (k, s)) in Layer::ALL
            .into_iter()
            .zip(kept.0.into_iter().zip(scratch.0.iter_mut()))
        {
            match (k, s) {
                (Some(b), _) => all.set(l, b),
                (None, Some(b)) => all.set(l, &mut b[..]),
                (None, None) => {}
            }
        }
        draw_bands(&stages, w, BAND_ROWS, &mut rgb, &mut depth, all.reborrow());
        draw_whole(
            &stages,
            &mut Whole {
                width: w,
                rgb: &mut rgb,
                depth_m: &mut depth,
                layers: all,
            },
        )?;
        out_srgb8
            .par_chunks_mut(3 * BAND_ROWS * w)
            .zip(rgb.par_chunks(3 * BAND_ROWS * w))
            .for_each(|(out, rgb)| encode_srgb8_serial(level, rgb, out));
        return Ok((prepared.rain_report(), prepared.snow_report()));
    }
    draw_bands_then(
        &stages,
        cam.width as usize,
        BAND_ROWS,
        drawn,
        out_srgb8,
        3,
        kept,
        |band, out| encode_srgb8_serial(level, band.rgb, out),
    );
    Ok((prepared.rain_report(), prepared.snow_report()))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::color::encode_srgb8;
    use crate::frame::fixture::one_box;
    use crate::frame::float::render_frame;
    use crate::frame::scene::SceneLight;

    #[test]
    fn the_bands_encoded_are_the_float_frame_encoded() {
        // 37 rows: two whole bands of 16 and a short one
        let (cam, scene, h, sky, amb) = one_box(41, 37);
        let light = SceneLight::new(&sky, &amb);
        let frame =
            Frame::new(SceneRef::Boxes(&scene), &cam, &light).with_effects(Some(&h), None, None);
        let float = render_frame(&frame).unwrap();
        let mut want = vec![0u8; float.rgb.len()];
        encode_srgb8(&float.rgb, &mut want);
        let n = cam.pixels();
        let (mut t, mut rain) = (vec![-1.0f32; n], vec![-1.0f32; n]);
        let mut layers = Layers::default();
        layers.set(Layer::Transmittance, t.as_mut_slice());
        layers.set(Layer::RainAlpha, rain.as_mut_slice());
        let mut got = vec![0u8; 3 * n];
        draw_srgb8(&frame, &mut got, layers).unwrap();
        assert_eq!(got, want);
        assert_eq!(t.as_slice(), float.layer(Layer::Transmittance).unwrap());
        // a kept layer no stage draws is its neutral value everywhere
        assert!(rain.iter().all(|&a| a == Layer::RainAlpha.neutral()));
        // a buffer of the wrong length is named
        let mut short = vec![0u8; 3 * n - 1];
        let err = draw_srgb8(&frame, &mut short, Layers::default()).unwrap_err();
        assert!(err.to_string().contains("out"), "{err}");
    }
}
