//! The light-aligned frame: axis w along the sunlight's travel (away from the sun), u and v
//! across it. Both illumination methods sort or sum along w.

use glam::DVec3;

use super::{CUTOFF_RADII, Cloud};

/// An orthonormal right-handed frame (u, v, w) with w = −sun.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LightFrame {
    /// Across the light.
    pub u: DVec3,
    /// Across the light, w × u.
    pub v: DVec3,
    /// Along the light's travel.
    pub w: DVec3,
}

impl LightFrame {
    /// The frame of a unit direction towards the sun.
    pub fn new(sun: DVec3) -> Self {
        let w = -sun;
        let helper = if w.y.abs() < 0.9 { DVec3::Y } else { DVec3::X };
        let u = helper.cross(w).normalize();
        let v = w.cross(u);
        LightFrame { u, v, w }
    }

    /// A world point's (u, v, w) coordinates.
    #[inline]
    pub fn to_light(&self, p: DVec3) -> DVec3 {
        DVec3::new(p.dot(self.u), p.dot(self.v), p.dot(self.w))
    }

    /// The world point at light coordinates `l`.
    #[inline]
    pub fn to_world(&self, l: DVec3) -> DVec3 {
        self.u * l.x + self.v * l.y + self.w * l.z
    }
}

/// A cloud's particles in light coordinates, with the box their supports fill.
#[derive(Debug, Clone)]
pub struct LightParticles {
    /// (u, v, w) of each centre, m.
    pub centres: Vec<DVec3>,
    /// Lower corner of the supports' box, m.
    pub lo: DVec3,
    /// Upper corner, m.
    pub hi: DVec3,
}

impl LightParticles {
    /// Projects `cloud` into `frame`.
    pub fn new(cloud: &Cloud, frame: &LightFrame) -> Self {
        let centres: Vec<DVec3> = cloud
            .positions_m
            .iter()
            .map(|p| frame.to_light(DVec3::from_array(*p)))
            .collect();
        let mut lo = DVec3::splat(f64::INFINITY);
        let mut hi = DVec3::splat(f64::NEG_INFINITY);
        for (c, r) in centres.iter().zip(&cloud.radii_m) {
            let e = DVec3::splat(CUTOFF_RADII * r);
            lo = lo.min(*c - e);
            hi = hi.max(*c + e);
        }
        LightParticles { centres, lo, hi }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frame_is_orthonormal_and_right_handed() {
        for s in [
            DVec3::Y,
            -DVec3::Y,
            DVec3::new(0.3, 0.5, -0.8).normalize(),
            DVec3::X,
        ] {
            let f = LightFrame::new(s);
            assert!((f.u.cross(f.v) - f.w).length() < 1e-12);
            assert!(f.u.dot(f.w).abs() < 1e-12 && f.v.dot(f.w).abs() < 1e-12);
            assert!((f.w + s).length() < 1e-12);
            let p = DVec3::new(1.0, -2.0, 3.0);
            assert!((f.to_world(f.to_light(p)) - p).length() < 1e-12);
        }
    }
}
