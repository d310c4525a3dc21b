//! Every default of the machine profile and every constant taken from Klipper, each written
//! once: the profile loader, the Klipper importer, the planner and the `machine` command read
//! them from here. Each names its source: a Klipper file and function (`klippy/…`), or
//! delta-gcode's own choice where Klipper has none.

/// Tower angles A, B, C from +X, degrees: delta.py `DeltaKinematics.__init__`,
/// `sconfig.getfloat('angle', angle)` over `[210., 330., 90.]`.
pub const TOWER_ANGLES_DEG: [f64; 3] = [210.0, 330.0, 90.0];

/// Klipper's `[printer] square_corner_velocity`, mm/s: toolhead.py `ToolHead.__init__`,
/// `config.getfloat('square_corner_velocity', 5., minval=0.)`.
pub const SQUARE_CORNER_VELOCITY_MM_S: f64 = 5.0;

/// Klipper's `[printer] minimum_cruise_ratio`: toolhead.py `ToolHead.__init__`, default 0.5
/// when neither it nor the deprecated `max_accel_to_decel` is set.
pub const MINIMUM_CRUISE_RATIO: f64 = 0.5;

/// Klipper's `[extruder] instantaneous_corner_velocity`, mm/s: extruder.py
/// `PrinterExtruder.__init__`, `config.getfloat('instantaneous_corner_velocity', 1., minval=0.)`.
pub const INSTANTANEOUS_CORNER_VELOCITY_MM_S: f64 = 1.0;

/// Nozzle diameter, mm. Klipper has no default (extruder.py requires `nozzle_diameter`);
/// delta-gcode's is the commonest nozzle.
pub const NOZZLE_DIAMETER_MM: f64 = 0.4;

/// Filament diameter, mm. Klipper has no default (extruder.py requires
/// `filament_diameter`); delta-gcode's is the commonest filament.
pub const FILAMENT_DIAMETER_MM: f64 = 1.75;

/// Tooth pitch of a GT2 belt, mm (delta-gcode's default for `motors.belt_pitch_mm`; Klipper
/// describes the pulley by its `rotation_distance` instead).
pub const BELT_PITCH_MM: f64 = 2.0;

/// Standard gravity, rounded, m/s² (delta-gcode's default for `gravity_m_s2`).
pub const GRAVITY_M_S2: f64 = 9.81;

/// The resampler's period Ts, s (delta-gcode's default for `sampling.period_s`: 1 ms).
pub const SAMPLING_PERIOD_S: f64 = 0.001;

/// delta.py `SLOW_RATIO`: Klipper halves a move's speed and acceleration beyond the radius
/// where a carriage moves this many times faster than the nozzle, and quarters them beyond
/// twice this ratio (`DeltaKinematics.check_move`).
pub const SLOW_RATIO: f64 = 3.0;

/// delta.py `DeltaKinematics.__init__`, `ratio_to_xy(4. * SLOW_RATIO)`: Klipper refuses moves
/// beyond the radius where a carriage moves this many times faster than the nozzle (12).
pub const REACH_RATIO: f64 = 4.0 * SLOW_RATIO;

/// The extrude-only limits' default ratio: extruder.py `PrinterExtruder.__init__`,
/// `def_max_extrude_ratio = 4·nozzle² / filament_area`; Klipper's default
/// `max_extrude_only_velocity` (`_accel`) is `max_velocity` (`max_accel`) times it.
pub fn extrude_only_ratio(nozzle_diameter_mm: f64, filament_diameter_mm: f64) -> f64 {
    let filament_area = std::f64::consts::PI * (filament_diameter_mm * 0.5).powi(2);
    4.0 * nozzle_diameter_mm.powi(2) / filament_area
}

/// delta.py `DeltaKinematics.__init__`, `ratio_to_xy` with `half_min_step_dist` = 0: the
/// nozzle radius beyond which some carriage can move `ratio` times faster than the nozzle,
/// ratio·√(l²/(ratio² + 1)) − delta_radius, l the shortest arm.
pub fn edge_radius_mm(ratio: f64, min_arm_mm: f64, delta_radius_mm: f64) -> f64 {
    ratio * (min_arm_mm * min_arm_mm / (ratio * ratio + 1.0)).sqrt() - delta_radius_mm
}

/// Klipper's reach, the largest print radius it accepts: delta.py `DeltaKinematics.__init__`,
/// `max_xy2 = min(print_radius, min_arm_length - radius, ratio_to_xy(4. * SLOW_RATIO))²`
/// (its `print_radius` defaults to `delta_radius`): the edge radius of [`REACH_RATIO`],
/// always below `arm − radius`, so the profile's rule
/// arm > delta_radius + print_radius holds within it. The half step distance Klipper
/// subtracts changes it by far less than 0.1 mm and is left out.
pub fn klipper_reach_mm(min_arm_mm: f64, delta_radius_mm: f64) -> f64 {
    edge_radius_mm(REACH_RATIO, min_arm_mm, delta_radius_mm)
}
