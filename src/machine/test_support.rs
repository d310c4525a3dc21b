//! A machine for the unit tests of the stages after the profile.

use super::Machine;

/// A Kossel-like machine with slightly unequal arms and a nozzle offset, so no test
/// passes by symmetry, and the paper's masses.
pub(crate) const KOSSEL_YAML: &str = "
name: test kossel
geometry:
  delta_radius_mm: 105
  arm_length_mm: [215.0, 215.5, 214.5]
  nozzle_offset_mm: 3
  home_z_mm: 290
  print_radius_mm: 85
masses: {cart_kg: 0.25, link_kg: 0.02, platform_kg: 0.5}
limits: {max_velocity_mm_s: 300, max_accel_mm_s2: 3000}
motors: {max_force_n: 30}
";

pub(crate) fn kossel_machine() -> Machine {
    Machine::from_yaml_str(KOSSEL_YAML, "test").unwrap()
}

/// The same machine driven by Marlin: accelerations 1000, jerk 10 (E 5), towers' feedrate
/// 200.
pub(crate) fn marlin_machine() -> Machine {
    let yaml = format!(
        "{KOSSEL_YAML}firmware: marlin
marlin:
  print_accel_mm_s2: 1000
  travel_accel_mm_s2: 1000
  jerk_mm_s: [10, 10, 10, 5]
  max_feedrate_mm_s: [200, 200, 200, 200]
"
    );
    Machine::from_yaml_str(&yaml, "test").unwrap()
}
