//! Shared fixtures for the model's unit tests.

use super::{DeltaModel, Geometry, Masses};
use crate::path::Vec3;

/// A Kossel-like robot with slightly unequal arms and a nozzle offset, so no test passes by
/// symmetry.
pub(crate) const KOSSEL: Geometry = Geometry {
    delta_radius_mm: 105.0,
    arm_length_mm: [215.0, 215.5, 214.5],
    nozzle_offset_mm: 3.0,
    tower_angles_deg: [210.0, 330.0, 90.0],
    home_z_mm: 290.0,
};

/// The paper's masses (section 5), no rotor.
pub(crate) const PAPER_MASSES: Masses = Masses {
    cart_kg: 0.25,
    link_kg: 0.02,
    platform_kg: 0.5,
    rotor_reflected_kg: 0.0,
};

pub(crate) const GRAVITY_M_S2: f64 = 9.81;

pub(crate) fn kossel() -> DeltaModel {
    DeltaModel::new(&KOSSEL, &PAPER_MASSES, GRAVITY_M_S2)
}

/// Points over the print disc (radius 85) from the bed up to 200 mm.
pub(crate) fn workspace_points() -> impl Iterator<Item = Vec3> {
    (0..=8).flat_map(|ring| {
        let r = 85.0 * ring as f64 / 8.0;
        (0..24).flat_map(move |k| {
            let th = (k as f64 * 15.0 + 7.0).to_radians();
            [0.0, 0.3, 50.0, 120.0, 200.0].map(|z| Vec3::new(r * th.cos(), r * th.sin(), z))
        })
    })
}

/// A small deterministic generator (xorshift) for random trajectories.
pub(crate) struct Rng(pub u64);

impl Rng {
    /// Uniform in [lo, hi).
    pub(crate) fn range(&mut self, lo: f64, hi: f64) -> f64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        lo + (hi - lo) * (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
}
