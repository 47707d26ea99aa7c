//! Rain sheltered by boxes: a drop is where it is only if nothing stood in its way on the way
//! down. The path it came along is the ray from the drop back along its velocity (up, and
//! upwind); a drop whose ray meets a box is removed. Under an awning only what the wind
//! blows in remains; inside a building none.

use super::drops::Drop;
use crate::scene::boxes::SceneBox;
use crate::scene::raycast::occluded;
use glam::Vec3;
use rayon::prelude::*;

/// The boxes that can shelter drops within `near_m` of `center_m`: those reaching above the
/// region's floor whose footprint comes within the wind's drift of it.
fn candidates(boxes: &[SceneBox], drops: &[Drop], center_m: Vec3, near_m: f32) -> Vec<SceneBox> {
    // Largest horizontal drift per metre of rise among the drops.
    let slope = drops.iter().fold(0.0f32, |m, d| {
        let v = d.velocity_m_s;
        m.max(Vec3::new(v.x, 0.0, v.z).length() / v.y.abs().max(1e-3))
    });
    let floor = center_m.y - near_m;
    boxes
        .iter()
        .filter(|b| {
            if b.max_m.y <= floor {
                return false;
            }
            let reach = near_m + (b.max_m.y - floor) * slope;
            b.min_m.x <= center_m.x + reach
                && b.max_m.x >= center_m.x - reach
                && b.min_m.z <= center_m.z + reach
                && b.max_m.z >= center_m.z - reach
        })
        .copied()
        .collect()
}

/// Whether a box stands on the path back along its velocity of the drop `d`, positioned
/// relative to `origin_m`.
#[inline]
pub fn sheltered(boxes: &[SceneBox], origin_m: Vec3, d: &Drop) -> bool {
    let back = -d.velocity_m_s;
    back.length() > 0.0 && occluded(boxes, origin_m + d.position_m, back.normalize())
}

/// Removes the drops `boxes` shelter (drops within `near_m` of `center_m`, positioned
/// relative to it), keeping the others in order.
pub fn remove_sheltered(drops: &mut Vec<Drop>, boxes: &[SceneBox], center_m: Vec3, near_m: f32) {
    if boxes.is_empty() || drops.is_empty() {
        return;
    }
    let near = candidates(boxes, drops, center_m, near_m);
    if near.is_empty() {
        return;
    }
    let keep: Vec<bool> = drops
        .par_iter()
        .map(|d| !sheltered(&near, center_m, d))
        .collect();
    let mut k = keep.iter();
    drops.retain(|_| k.next().copied().unwrap_or(true));
}

#[cfg(test)]
mod tests {
    use super::*;

    fn drop_at(p: Vec3, v: Vec3) -> Drop {
        Drop {
            position_m: p,
            velocity_m_s: v,
            diameter_m: 1e-3,
            id: [0; 5],
        }
    }

    #[test]
    fn an_awning_shelters_what_the_wind_does_not_blow_in() {
        // Awning over x in [0, 4] at 3 m.
        let awning = SceneBox {
            min_m: Vec3::new(0.0, 3.0, -10.0),
            max_m: Vec3::new(4.0, 3.2, 10.0),
            albedo: Vec3::ONE,
        };
        let still = Vec3::new(0.0, -6.0, 0.0);
        let windy = Vec3::new(3.0, -6.0, 0.0); // blows towards +x: slant 0.5 m per m of fall
        let mut drops = vec![
            drop_at(Vec3::new(2.0, 1.0, 0.0), still), // under it: sheltered
            drop_at(Vec3::new(-1.0, 1.0, 0.0), still), // beside it: open
            drop_at(Vec3::new(0.5, 1.0, 0.0), windy), // came from x = -0.5 at 3 m: blown in
            drop_at(Vec3::new(2.0, 1.0, 0.0), windy), // came from x = 1 at 3 m: sheltered
            drop_at(Vec3::new(2.0, 4.0, 0.0), still), // above it: open
        ];
        // Drops are positioned relative to the region's centre.
        let c = Vec3::new(0.0, 1.6, 0.0);
        for d in &mut drops {
            d.position_m -= c;
        }
        remove_sheltered(&mut drops, &[awning], c, 5.0);
        let xs: Vec<(f32, f32)> = drops
            .iter()
            .map(|d| (d.position_m.x + c.x, d.position_m.y + c.y))
            .collect();
        assert_eq!(xs, vec![(-1.0, 1.0), (0.5, 1.0), (2.0, 4.0)]);
        // Far boxes are not considered; none at all changes nothing.
        let far = SceneBox {
            min_m: Vec3::new(100.0, 0.0, 100.0),
            max_m: Vec3::new(101.0, 1.0, 101.0),
            albedo: Vec3::ONE,
        };
        assert!(candidates(&[far], &drops, Vec3::ZERO, 5.0).is_empty());
        let before = drops.clone();
        remove_sheltered(&mut drops, &[], Vec3::ZERO, 5.0);
        assert_eq!(drops, before);
    }
}
