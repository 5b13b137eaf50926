//! The open hand against the object at t = 0: the check every simulated scene makes before
//! it integrates (an open finger that already penetrates the object ends the run at t = 0,
//! "open finger penetrates the object at t = 0"), made on an exported scene so that no model
//! starts with the object inside a finger (docs/export.md).

use super::ExportedDesign;
use crate::math::V2;
use crate::sim::FingerModel;
use nalgebra::Vector2;

/// The penetration above which a scene's start is refused: the threshold of the scenes'
/// start check in `crate::sim` (`begin`: a contact with δ > 1e-12 m at t = 0).
pub const START_PENETRATION_TOL: f64 = 1e-12;

/// The deepest phalanx of the open hand inside the object at t = 0.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OpenPenetration {
    /// 1 or 2 (finger 1 at +x, finger 2 its mirror at −x).
    pub finger: usize,
    /// `proximal` or `distal`.
    pub phalanx: &'static str,
    /// Penetration depth δ = R + w − d (m, > [`START_PENETRATION_TOL`]).
    pub depth: f64,
}

impl ExportedDesign {
    /// The deepest penetration of the open hand into the object at the exported offset
    /// (None: both fingers clear it, as a simulation of the scene requires at t = 0).
    pub fn open_penetration(&self) -> Option<OpenPenetration> {
        self.penetration_at(self.placement.x_off)
    }

    /// The largest offset of the same sign as the exported one, up to it, at which the open
    /// hand still clears the object (bisection to the last bit); None when even the centred
    /// object touches an open finger. For an error message ("clears the object up to …").
    pub fn clear_offset(&self) -> Option<f64> {
        let x = self.placement.x_off;
        if self.penetration_at(0.0).is_some() {
            return None;
        }
        if self.penetration_at(x).is_none() {
            return Some(x);
        }
        let (mut lo, mut hi) = (0.0, x);
        for _ in 0..64 {
            let mid = 0.5 * (lo + hi);
            if mid == lo || mid == hi {
                break;
            }
            if self.penetration_at(mid).is_some() {
                hi = mid;
            } else {
                lo = mid;
            }
        }
        Some(lo)
    }

    /// The deepest penetration with the object's axis at (x_off, R): each finger's
    /// phalanges (the capsules of the simulated contacts) at the open pose against the object
    /// centre in that finger's frame, (x_off, R) for finger 1 and (−x_off, R) for finger 2,
    /// as the offset and free scenes see it (the centred scene: x_off = 0).
    fn penetration_at(&self, x_off: f64) -> Option<OpenPenetration> {
        let model = FingerModel::new(&self.finger, &self.scene, self.tau_s0);
        let open = &self.finger.open;
        // the pose the simulations start from (their DGM at the open joint angles)
        let linkage = model.linkage(Vector2::new(open.q11, open.q21), Vector2::zeros(), false);
        let pose = linkage.as_ref().map_or(open, |l| &l.pose);
        let xd = self.finger.distal_dir(pose);
        let r = self.scene.object.radius;
        let mut deepest: Option<OpenPenetration> = None;
        for (finger, centre) in [(1, V2::new(x_off, r)), (2, V2::new(-x_off, r))] {
            for (i, phalanx) in [(0, "proximal"), (1, "distal")] {
                let depth = model.phalanx(pose, xd, centre, i).delta;
                if depth > START_PENETRATION_TOL && deepest.is_none_or(|d| depth > d.depth) {
                    deepest = Some(OpenPenetration { finger, phalanx, depth });
                }
            }
        }
        deepest
    }
}
