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

/// A stepper's full-step angle, degrees (delta-gcode's default for `motors.step_angle_deg`:
/// the common 1.8°, 200 steps a turn; Klipper's `full_steps_per_rotation` defaults to 200).
pub const STEP_ANGLE_DEG: f64 = 1.8;

/// Klipper's `[input_shaper] shaper_type`: input_shaper.py `InputShaperParams.__init__`,
/// `config.get('shaper_type', 'mzv')`.
pub const SHAPER_TYPE: &str = "mzv";

/// Klipper's `[input_shaper] damping_ratio_x` / `_y`: shaper_defs.py `DEFAULT_DAMPING_RATIO`.
pub const SHAPER_DAMPING_RATIO: f64 = crate::motion::shaper::DEFAULT_SHAPER_DAMPING_RATIO;

// The physical default of `drive` (docs/machine-profile.md, "The default drive").

/// The drive's damping ratio when the profile gives none: a typical figure, not a
/// measurement; it is the damping Klipper assumes of a printer's resonance when it builds
/// its shapers (shaper_defs.py `DEFAULT_DAMPING_RATIO`).
pub const DRIVE_DAMPING_RATIO: f64 = SHAPER_DAMPING_RATIO;

/// Force per unit strain (E·A) of a 6 mm GT2 belt, N. Gates' own figure was not found in
/// the sources searched; this is a measurement scaled by width: a 9 mm Gates GT2 belt (the
/// Shapeoko 3's stock belt) stretched 2.9 mm over 500 mm (0.58 %) under 38 lbf (169.0 N)
/// (community.carbide3d.com, "Belt stretch and stepper holding measured", post 22):
/// 169.0 / 0.0058 = 29.1 kN for 9 mm, 19.4 kN for 6 mm.
pub const GT2_6MM_BELT_EA_N: f64 = 19_400.0;

/// The motor assumed when a profile gives only `max_force_n`: a NEMA 17 of 0.40 N·m
/// holding torque (the class of the 17HS4401; the shipped profiles' assumption), 1.8°.
pub const TYPICAL_HOLDING_TORQUE_NM: f64 = 0.40;

/// The pulley assumed with [`TYPICAL_HOLDING_TORQUE_NM`]: GT2 (2 mm) 20 teeth, Klipper's
/// `rotation_distance: 40`, the deltas' usual pulley.
pub const TYPICAL_PULLEY_TEETH: u32 = 20;

// Marlin's defaults (Marlin 2.1.2.x, config/default Configuration.h and
// Configuration_adv.h, Configurations tag 2.1.2.4). Marlin's default configuration is a
// Cartesian printer's: its Z figures (400 steps/mm, 5 mm/s, 100 mm/s², jerk 0.3 mm/s) are a
// lead screw's. A delta's three towers are Marlin's X, Y and Z steppers and every Marlin
// delta example sets them alike, so the towers take Marlin's X defaults.

/// `DEFAULT_AXIS_STEPS_PER_UNIT` X (towers): 80 (200 steps × 16 / (2 mm × 20 teeth)).
pub const MARLIN_STEPS_PER_MM: f64 = 80.0;
/// `DEFAULT_AXIS_STEPS_PER_UNIT` E: 500.
pub const MARLIN_E_STEPS_PER_MM: f64 = 500.0;
/// `DEFAULT_SEGMENTS_PER_SECOND` (delta; M665 S): 200.
pub const MARLIN_SEGMENTS_PER_SECOND: f64 = 200.0;
/// `DEFAULT_MAX_FEEDRATE` (M203), mm/s: X 300 for each tower, E 25.
pub const MARLIN_MAX_FEEDRATE_MM_S: [f64; 4] = [300.0, 300.0, 300.0, 25.0];
/// `DEFAULT_MAX_ACCELERATION` (M201), mm/s²: X 3000 for each tower, E 10000.
pub const MARLIN_MAX_ACCEL_MM_S2: [f64; 4] = [3000.0, 3000.0, 3000.0, 10000.0];
/// `DEFAULT_ACCELERATION` (M204 P), mm/s².
pub const MARLIN_PRINT_ACCEL_MM_S2: f64 = 3000.0;
/// `DEFAULT_RETRACT_ACCELERATION` (M204 R), mm/s².
pub const MARLIN_RETRACT_ACCEL_MM_S2: f64 = 3000.0;
/// `DEFAULT_TRAVEL_ACCELERATION` (M204 T), mm/s².
pub const MARLIN_TRAVEL_ACCEL_MM_S2: f64 = 3000.0;
/// `DEFAULT_XJERK` for each tower and `DEFAULT_EJERK` (M205 X/Z/E, classic jerk), mm/s.
pub const MARLIN_JERK_MM_S: [f64; 4] = [10.0, 10.0, 10.0, 5.0];
/// `S_CURVE_ACCELERATION`: off.
pub const MARLIN_S_CURVE: bool = false;
/// `BLOCK_BUFFER_SIZE` (Configuration_adv.h): 16.
pub const MARLIN_BLOCK_BUFFER_SIZE: u32 = 16;
/// `MIN_STEPS_PER_SEGMENT` (Configuration_adv.h): 6.
pub const MARLIN_MIN_STEPS_PER_SEGMENT: u32 = 6;
/// `DEFAULT_MINSEGMENTTIME` (M205 B), µs: 20000.
pub const MARLIN_MIN_SEGMENT_TIME_US: u32 = 20_000;
/// `MINIMUM_PLANNER_SPEED` (Configuration_adv.h), mm/s: 0.05.
pub const MARLIN_MINIMUM_PLANNER_SPEED_MM_S: f64 = 0.05;
/// `DEFAULT_MINIMUMFEEDRATE` (M205 S), mm/s: 0.
pub const MARLIN_MIN_FEEDRATE_MM_S: f64 = 0.0;
/// `DEFAULT_MINTRAVELFEEDRATE` (M205 T), mm/s: 0.
pub const MARLIN_MIN_TRAVEL_FEEDRATE_MM_S: f64 = 0.0;
/// `AUTO_BED_LEVELING_UBL` (Configuration.h): off. With it, a delta's moves are cut by UBL's
/// segmenter (`line_to_destination_segmented`) instead of the plain one.
pub const MARLIN_UBL: bool = false;
/// `MAX_ARC_SEGMENT_MM` (Configuration_adv.h, `ARC_SUPPORT`), mm: 1.0.
pub const MARLIN_MAX_ARC_SEGMENT_MM: f64 = 1.0;
/// `MIN_ARC_SEGMENT_MM`, mm: 0.1.
pub const MARLIN_MIN_ARC_SEGMENT_MM: f64 = 0.1;
/// `MIN_CIRCLE_SEGMENTS`: 72 chords in a full circle at least.
pub const MARLIN_MIN_CIRCLE_SEGMENTS: u32 = 72;
/// `ARC_SEGMENTS_PER_SEC`: off (commented out, 50), written 0.
pub const MARLIN_ARC_SEGMENTS_PER_SEC: f64 = 0.0;
/// `N_ARC_CORRECTION`: every 25th chord end is computed exactly, the others by a small-angle
/// rotation.
pub const MARLIN_N_ARC_CORRECTION: u32 = 25;
/// `DEFAULT_FEEDRATE_MM_M` (motion.cpp, when the configuration does not define it): the feed
/// before the first F, mm/min.
pub const MARLIN_DEFAULT_FEEDRATE_MM_MIN: f64 = 4000.0;
/// `MINIMAL_STEP_RATE` (planner.cpp, a hard `#define` in 2.1.2.x): the lowest initial and
/// final step rate of a block, steps/s.
pub const MARLIN_MINIMAL_STEP_RATE: u32 = 120;
/// `STEPPER_TIMER_RATE`, ticks/s: 2 MHz on AVR (16 MHz / 8) and on the STM32 HAL (the FLSUN Q5's
/// `mks_robin_nano_v1v2` build, the Kossel's ATmega2560). The stepper's intervals are whole ticks.
pub const MARLIN_STEPPER_TIMER_RATE_HZ: u32 = 2_000_000;
