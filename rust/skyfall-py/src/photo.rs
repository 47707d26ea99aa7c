//! A photo's airlight estimate (He, Sun & Tang's dark channel prior), on uint8 sRGB codes or
//! float32 linear light, GIL released.

use crate::errors::{CoreError, invalid};
use numpy::ndarray::Ix2;
use numpy::{PyArray2, PyReadonlyArray3, PyUntypedArrayMethods};
use pyo3::prelude::*;
use skyfall_core::haze::airlight;

/// An H·W·3 image's pixels as the core reads them.
enum Pixels<'py> {
    Codes(PyReadonlyArray3<'py, u8>),
    Linear(PyReadonlyArray3<'py, f32>),
}

fn pixels<'py>(image: &Bound<'py, PyAny>) -> PyResult<(Pixels<'py>, usize, usize)> {
    let p = if let Ok(a) = image.extract::<PyReadonlyArray3<'py, u8>>() {
        Pixels::Codes(a)
    } else if let Ok(a) = image.extract::<PyReadonlyArray3<'py, f32>>() {
        Pixels::Linear(a)
    } else {
        return Err(invalid(
            "image",
            None,
            "must be a C-contiguous (H, W, 3) uint8 or float32 array",
        ));
    };
    let shape = match &p {
        Pixels::Codes(a) => a.shape().to_vec(),
        Pixels::Linear(a) => a.shape().to_vec(),
    };
    if shape[2] != 3 {
        return Err(invalid(
            "image",
            None,
            format!("must have shape (H, W, 3), got {shape:?}"),
        ));
    }
    Ok((p, shape[0], shape[1]))
}

/// The dark channel of `image` (H, W, 3): each pixel's channel minimum over the
/// `patch_px`-square window around it, float32 (H, W), in the image's own values.
#[pyfunction]
pub fn dark_channel<'py>(
    py: Python<'py>,
    image: &Bound<'py, PyAny>,
    patch_px: usize,
) -> PyResult<Bound<'py, PyArray2<f32>>> {
    let (p, h, w) = pixels(image)?;
    let dark = match &p {
        Pixels::Codes(a) => {
            let s = a.as_slice()?;
            py.detach(|| airlight::dark_channel(s, w, h, patch_px))
        }
        Pixels::Linear(a) => {
            let s = a.as_slice()?;
            py.detach(|| airlight::dark_channel(s, w, h, patch_px))
        }
    }
    .map_err(CoreError)?;
    crate::alloc::filled::<f32, Ix2>(py, &[h, w], |out| {
        out.copy_from_slice(&dark);
        Ok(())
    })
}

/// (row, column) of `image`'s atmospheric light: among the brightest `top_fraction` of its
/// dark channel, the pixel whose channels sum highest.
#[pyfunction]
pub fn atmospheric_light_pixel(
    py: Python<'_>,
    image: &Bound<'_, PyAny>,
    patch_px: usize,
    top_fraction: f64,
) -> PyResult<(usize, usize)> {
    let (p, h, w) = pixels(image)?;
    let i = match &p {
        Pixels::Codes(a) => {
            let s = a.as_slice()?;
            py.detach(|| airlight::atmospheric_light_pixel(s, w, h, patch_px, top_fraction))
        }
        Pixels::Linear(a) => {
            let s = a.as_slice()?;
            py.detach(|| airlight::atmospheric_light_pixel(s, w, h, patch_px, top_fraction))
        }
    }
    .map_err(CoreError)?;
    Ok((i / w, i % w))
}
