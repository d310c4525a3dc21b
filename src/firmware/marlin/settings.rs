//! Marlin's motion settings as the planner reads them: the profile's `marlin:` section,
//! changed by the file's M201, M203, M204, M205 and M665 S as Marlin's handlers change them
//! (gcode/config/M200-M205.cpp, gcode/calibrate/M665.cpp).

use crate::gcode::MarlinChange;
use crate::machine::Marlin as Profile;

/// The settings in force. Index 0..3 are towers A, B, C (Marlin's X, Y, Z), 3 is E.
#[derive(Clone, Debug, PartialEq)]
pub struct Settings {
    /// `planner.settings.axis_steps_per_mm`, steps/mm.
    pub steps_per_mm: [f64; 4],
    /// `segments_per_second` (M665 S).
    pub segments_per_second: f64,
    /// `max_feedrate_mm_s` (M203), mm/s.
    pub max_feedrate_mm_s: [f64; 4],
    /// `max_acceleration_steps_per_s2` (M201 × steps/mm, truncated to an integer as Marlin's
    /// `uint32_t`), steps/s².
    pub max_accel_steps_s2: [f64; 4],
    max_accel_mm_s2: [f64; 4],
    /// `acceleration` (M204 P), `retract_acceleration` (M204 R), `travel_acceleration`
    /// (M204 T), mm/s².
    pub print_accel_mm_s2: f64,
    pub retract_accel_mm_s2: f64,
    pub travel_accel_mm_s2: f64,
    /// `max_jerk` (M205 X Y Z E), mm/s.
    pub jerk_mm_s: [f64; 4],
    /// `min_feedrate_mm_s` (M205 S) and `min_travel_feedrate_mm_s` (M205 T), mm/s.
    pub min_feedrate_mm_s: f64,
    pub min_travel_feedrate_mm_s: f64,
    /// `MIN_STEPS_PER_SEGMENT`.
    pub min_steps_per_segment: u32,
    /// `MINIMUM_PLANNER_SPEED`, mm/s.
    pub minimum_planner_speed_mm_s: f64,
    /// `BLOCK_BUFFER_SIZE`.
    pub block_buffer_size: usize,
    /// `AUTO_BED_LEVELING_UBL`: UBL's segmenter.
    pub ubl: bool,
    /// `S_CURVE_ACCELERATION`.
    pub s_curve: bool,
}

impl Settings {
    pub fn new(p: &Profile) -> Settings {
        let spm = [
            p.steps_per_mm,
            p.steps_per_mm,
            p.steps_per_mm,
            p.e_steps_per_mm,
        ];
        let mut s = Settings {
            steps_per_mm: spm,
            segments_per_second: p.segments_per_second,
            max_feedrate_mm_s: p.max_feedrate_mm_s,
            max_accel_steps_s2: [0.0; 4],
            max_accel_mm_s2: p.max_accel_mm_s2,
            print_accel_mm_s2: p.print_accel_mm_s2,
            retract_accel_mm_s2: p.retract_accel_mm_s2,
            travel_accel_mm_s2: p.travel_accel_mm_s2,
            jerk_mm_s: p.jerk_mm_s,
            min_feedrate_mm_s: crate::machine::defaults::MARLIN_MIN_FEEDRATE_MM_S,
            min_travel_feedrate_mm_s: crate::machine::defaults::MARLIN_MIN_TRAVEL_FEEDRATE_MM_S,
            min_steps_per_segment: p.min_steps_per_segment,
            minimum_planner_speed_mm_s: p.minimum_planner_speed_mm_s,
            block_buffer_size: p.block_buffer_size as usize,
            ubl: p.ubl,
            s_curve: p.s_curve,
        };
        s.refresh_accel_steps();
        s
    }

    /// `Planner::refresh_acceleration_rates`: the max accelerations in steps/s².
    fn refresh_accel_steps(&mut self) {
        for i in 0..4 {
            self.max_accel_steps_s2[i] = (self.max_accel_mm_s2[i] * self.steps_per_mm[i]).floor();
        }
    }

    /// A settings command of the file, from the next move on.
    pub fn apply(&mut self, change: &MarlinChange) {
        let set = |dst: &mut [f64; 4], src: &[Option<f64>; 4]| {
            for (d, s) in dst.iter_mut().zip(src) {
                if let Some(v) = s {
                    *d = *v;
                }
            }
        };
        match change {
            MarlinChange::MaxAccel(v) => {
                set(&mut self.max_accel_mm_s2, v);
                self.refresh_accel_steps();
            }
            MarlinChange::MaxFeedrate(v) => set(&mut self.max_feedrate_mm_s, v),
            MarlinChange::Accel {
                print,
                retract,
                travel,
            } => {
                let keep = |dst: &mut f64, v: &Option<f64>| *dst = v.unwrap_or(*dst);
                keep(&mut self.print_accel_mm_s2, print);
                keep(&mut self.retract_accel_mm_s2, retract);
                keep(&mut self.travel_accel_mm_s2, travel);
            }
            MarlinChange::Jerk {
                jerk,
                min_feedrate,
                min_travel_feedrate,
            } => {
                set(&mut self.jerk_mm_s, jerk);
                self.min_feedrate_mm_s = min_feedrate.unwrap_or(self.min_feedrate_mm_s);
                self.min_travel_feedrate_mm_s =
                    min_travel_feedrate.unwrap_or(self.min_travel_feedrate_mm_s);
            }
            // The geometry (L, R, H, trims) stays the profile's: the dynamic model is built
            // from it (docs/planner.md).
            MarlinChange::Delta(d) => {
                if let Some(s) = d.segments_per_second {
                    self.segments_per_second = s;
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn commands_change_only_what_they_give() {
        let mut s = Settings::new(&Profile::default());
        let before = s.clone();
        s.apply(&MarlinChange::MaxAccel([Some(1000.5), None, None, None]));
        assert_eq!(
            s.max_accel_steps_s2[0],
            (1000.5 * s.steps_per_mm[0]).floor()
        );
        assert_eq!(s.max_accel_steps_s2[1], before.max_accel_steps_s2[1]);
        s.apply(&MarlinChange::Accel {
            print: Some(700.0),
            retract: None,
            travel: Some(900.0),
        });
        assert_eq!(
            (
                s.print_accel_mm_s2,
                s.retract_accel_mm_s2,
                s.travel_accel_mm_s2
            ),
            (700.0, before.retract_accel_mm_s2, 900.0)
        );
        s.apply(&MarlinChange::Jerk {
            jerk: [None, None, None, Some(2.5)],
            min_feedrate: None,
            min_travel_feedrate: Some(1.0),
        });
        assert_eq!(s.jerk_mm_s[3], 2.5);
        assert_eq!(s.jerk_mm_s[0], before.jerk_mm_s[0]);
        assert_eq!(s.min_travel_feedrate_mm_s, 1.0);
        s.apply(&MarlinChange::Delta(crate::gcode::DeltaChange {
            segments_per_second: Some(80.0),
            ..Default::default()
        }));
        assert_eq!(s.segments_per_second, 80.0);
    }
}
