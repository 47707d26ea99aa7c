//! Ray casts against the box scene's boxes (the slab test), shared by the frame's ray cast
//! ([`super::boxes::trace`]), the sky's occlusion ([`crate::sky::illuminance`]) and the
//! rain's shelter ([`crate::rain::shelter`]).

use super::boxes::SceneBox;
use glam::Vec3;

/// Hits nearer than this along a ray, m, are ignored (the surface a ray starts from).
pub const T_MIN: f32 = 1e-4;

/// 1/dir per axis; a component tinier than 1e-20 is taken as ±1e-20 (its sign kept), so the
/// division stays finite.
#[inline]
pub fn inverse_direction(dir: Vec3) -> Vec3 {
    let safe = |d: f32| {
        if d.abs() < 1e-20 {
            if d < 0.0 { -1e-20 } else { 1e-20 }
        } else {
            d
        }
    };
    Vec3::new(1.0 / safe(dir.x), 1.0 / safe(dir.y), 1.0 / safe(dir.z))
}

/// The slab test of the ray `origin + t·dir` (`inv` = [`inverse_direction`] of `dir`) against
/// `b`: per axis, the parameters where the ray enters and leaves the box's slab.
#[inline]
pub fn slabs(b: &SceneBox, origin: Vec3, inv: Vec3) -> (Vec3, Vec3) {
    let t1 = (b.min_m - origin) * inv;
    let t2 = (b.max_m - origin) * inv;
    (t1.min(t2), t1.max(t2))
}

/// Whether the ray from `p` along `dir` meets a box (a box containing `p` counts; one `p` sits
/// on while the ray leaves it does not).
#[inline]
pub fn occluded(boxes: &[SceneBox], p: Vec3, dir: Vec3) -> bool {
    let inv = inverse_direction(dir);
    boxes.iter().any(|b| {
        let (lo, hi) = slabs(b, p, inv);
        let t_near = lo.max_element();
        let t_far = hi.min_element();
        t_far > T_MIN && t_near <= t_far
    })
}

/// Whether a box meets the segment from `p` along unit-free `dir` up to `t_max` (in units of
/// `dir`): the shadow ray of a surface point towards a light at `p + t_max·dir`. Boxes apart
/// from the segment's bounding box are passed over before the slab test (the same answer).
#[inline]
pub fn occluded_within(boxes: &[SceneBox], p: Vec3, dir: Vec3, t_max: f32) -> bool {
    let inv = inverse_direction(dir);
    let q = p + dir * t_max;
    let (lo_seg, hi_seg) = (p.min(q), p.max(q));
    boxes.iter().any(|b| {
        if b.min_m.cmpgt(hi_seg).any() || b.max_m.cmplt(lo_seg).any() {
            return false;
        }
        let (lo, hi) = slabs(b, p, inv);
        let t_near = lo.max_element().max(T_MIN);
        let t_far = hi.min_element().min(t_max);
        t_near <= t_far
    })
}
