//! Boxes from numpy: the (N, 9) rows (min xyz, max xyz, albedo rgb) that `skyfall.scenes`
//! stores a scene's boxes and a photo's occluders in.

use crate::errors::{CoreError, invalid};
use glam::Vec3;
use numpy::PyReadonlyArray2;
use pyo3::prelude::*;
use skyfall_core::scene::boxes::{BoxScene, SceneBox};

/// Box scene from an (N, 9) array: min xyz, max xyz, albedo rgb per row (the layout of
/// `skyfall.scenes`' box arrays).
pub fn box_rows(boxes: &PyReadonlyArray2<'_, f32>) -> PyResult<Vec<SceneBox>> {
    let a = boxes.as_array();
    if a.ncols() != 9 {
        return Err(invalid(
            "boxes",
            None,
            format!("must have shape (N, 9), got {:?}", a.shape()),
        ));
    }
    Ok(a.rows()
        .into_iter()
        .map(|r| SceneBox {
            min_m: Vec3::new(r[0], r[1], r[2]),
            max_m: Vec3::new(r[3], r[4], r[5]),
            albedo: Vec3::new(r[6], r[7], r[8]),
        })
        .collect())
}

/// A box scene from its rows, ground flag and ground albedo, validated by the core.
pub fn box_scene(
    boxes: &PyReadonlyArray2<'_, f32>,
    ground: bool,
    ground_albedo: [f32; 3],
) -> PyResult<BoxScene> {
    Ok(BoxScene::new(box_rows(boxes)?, ground, Vec3::from(ground_albedo)).map_err(CoreError)?)
}
