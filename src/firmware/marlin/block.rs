//! A planner block as `Planner::_populate_block` (module/planner.cpp, 2.1.2.x) fills it on a
//! delta: step counts, the drop of a segment under `MIN_STEPS_PER_SEGMENT`, the nominal
//! speed and step rate, the per-tower feed (M203) and acceleration (M201) limits, M204's
//! acceleration, and the classic-jerk junction on tower speeds. Cartesian mm for the
//! block's length and speeds; tower (carriage) mm for the per-axis quantities.

use super::settings::Settings;

/// One planner block.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Block {
    /// The G-code line of its move.
    pub line: u64,
    /// Tower and E positions at the start and the end, steps.
    pub from_steps: [i64; 4],
    pub to_steps: [i64; 4],
    /// `step_event_count`: the most steps any axis makes (E included).
    pub step_events: u32,
    /// `millimeters`: the Cartesian length the timing uses.
    pub millimeters: f64,
    /// `nominal_speed` (mm/s) and `nominal_rate` (steps/s of the dominant axis).
    pub nominal_speed: f64,
    pub nominal_rate: f64,
    /// `acceleration_steps_per_s2` and `acceleration` (mm/s²).
    pub accel_steps_s2: f64,
    pub accel_mm_s2: f64,
    /// `max_entry_speed_sqr` and `entry_speed_sqr`, (mm/s)².
    pub max_entry_sqr: f64,
    pub entry_sqr: f64,
    /// The entry the last reverse pass gave it, before the forward pass (NaN before the
    /// first), (mm/s)²: where a pass gives the same, it can stop (`Lookahead`).
    pub reverse_sqr: f64,
}

impl Block {
    /// The towers move (a block can be timed as E-only and still move a tower a few steps).
    pub fn moves_towers(&self) -> bool {
        (0..3).any(|i| self.to_steps[i] != self.from_steps[i])
    }
}

/// What `_populate_block` keeps from one block for the next: `previous_speed`,
/// `previous_nominal_speed`, `previous_safe_speed`.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Previous {
    speed_mm_s: [f64; 4],
    nominal_speed: f64,
    safe_speed: f64,
}

/// A segment for the planner: its target in steps, the feed and the length hint.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Target {
    pub line: u64,
    pub to_steps: [i64; 4],
    pub feed_mm_s: f64,
    /// `hints.millimeters` (0: none).
    pub hint_mm: f64,
    /// The Cartesian length of the segment (used when there is no hint).
    pub cart_mm: f64,
}

/// `_populate_block`: the block from `from_steps` to the segment's target, or None when
/// Marlin drops it (fewer than `MIN_STEPS_PER_SEGMENT` steps on every axis: its steps go
/// into the next block and its time is lost). `moves_queued` counts the blocks waiting
/// (not executing) before this one; `prev` is updated for an accepted block only.
pub fn populate(
    s: &Settings,
    from_steps: [i64; 4],
    seg: &Target,
    moves_queued: usize,
    prev: &mut Previous,
) -> Option<Block> {
    let d: [i64; 4] = std::array::from_fn(|i| seg.to_steps[i] - from_steps[i]);
    let steps: [u64; 4] = d.map(|v| v.unsigned_abs());
    let min_steps = u64::from(s.min_steps_per_segment);
    let n = *steps.iter().max().unwrap_or(&0);
    if n < min_steps || n == 0 {
        return None;
    }
    let dist_mm: [f64; 4] = std::array::from_fn(|i| d[i] as f64 / s.steps_per_mm[i]);
    let millimeters = if steps[..3].iter().all(|&k| k < min_steps) {
        dist_mm[3].abs()
    } else if seg.hint_mm > 0.0 {
        seg.hint_mm
    } else {
        seg.cart_mm
    };
    if millimeters <= 0.0 || !millimeters.is_finite() {
        return None;
    }
    let extrudes = steps[3] > 0;
    let feed = seg.feed_mm_s.max(if extrudes {
        s.min_feedrate_mm_s
    } else {
        s.min_travel_feedrate_mm_s
    });
    // SLOWDOWN is compiled out on kinematic machines (Conditionals_post.h): no
    // minimum segment time on a delta.
    let inverse_secs = feed / millimeters;
    let mut nominal_speed = millimeters * inverse_secs;
    let mut nominal_rate = (n as f64 * inverse_secs).ceil();
    // M203 per axis: tower speeds.
    let mut speed: [f64; 4] = dist_mm.map(|v| v * inverse_secs);
    let mut factor: f64 = 1.0;
    for (v, max) in speed.iter().zip(&s.max_feedrate_mm_s) {
        if v.abs() > *max {
            factor = factor.min(max / v.abs());
        }
    }
    if factor < 1.0 {
        speed = speed.map(|v| v * factor);
        nominal_speed *= factor;
        nominal_rate = (nominal_rate * factor).floor();
    }
    // M204 and M201: the dominant axis's acceleration, capped per axis.
    let steps_per_mm = n as f64 / millimeters;
    let accel_steps = if steps[..3].iter().all(|&k| k == 0) {
        (s.retract_accel_mm_s2 * steps_per_mm).ceil()
    } else {
        let base = if extrudes {
            s.print_accel_mm_s2
        } else {
            s.travel_accel_mm_s2
        };
        let mut a = (base * steps_per_mm).ceil();
        for i in [3, 0, 1, 2] {
            let max = s.max_accel_steps_s2[i];
            if steps[i] > 0 && max < a {
                // uint32 arithmetic: (max · n) / steps, truncated.
                a = a.min((max * n as f64 / steps[i] as f64).floor());
            }
        }
        a
    };
    let max_entry = junction_speed(s, &speed, nominal_speed, moves_queued, prev);
    *prev = Previous {
        speed_mm_s: speed,
        nominal_speed,
        safe_speed: prev.safe_speed,
    };
    let mps = s.minimum_planner_speed_mm_s;
    Some(Block {
        line: seg.line,
        from_steps,
        to_steps: seg.to_steps,
        step_events: n as u32,
        millimeters,
        nominal_speed,
        nominal_rate,
        accel_steps_s2: accel_steps,
        accel_mm_s2: accel_steps / steps_per_mm,
        max_entry_sqr: max_entry * max_entry,
        entry_sqr: mps * mps,
        reverse_sqr: f64::NAN,
    })
}

/// The jerk between two speeds of one axis as `_populate_block` measures it: their
/// difference when they have the same sign, the larger magnitude on a reversal.
fn axis_jerk(exit: f64, entry: f64) -> f64 {
    if exit > entry {
        if entry > 0.0 || exit < 0.0 {
            exit - entry
        } else {
            exit.max(-entry)
        }
    } else if entry < 0.0 || exit > 0.0 {
        entry - exit
    } else {
        (-exit).max(entry)
    }
}

/// Classic jerk (`CLASSIC_JERK`, the only junction rule Marlin allows on a delta): the
/// block's safe speed (from and to rest), then the junction speed from the previous
/// block's axis speeds, towers A, B, C and E in order, each later axis tested with the
/// speeds already scaled; the safe-speed override. Sets `prev.safe_speed`.
fn junction_speed(
    s: &Settings,
    speed: &[f64; 4],
    nominal_speed: f64,
    moves_queued: usize,
    prev: &mut Previous,
) -> f64 {
    let mut safe = nominal_speed;
    let mut limited = false;
    for (v, &mj) in speed.iter().zip(&s.jerk_mm_s) {
        let j = v.abs();
        if j > mj {
            if limited {
                if j * safe > nominal_speed * mj {
                    safe = nominal_speed * mj / j;
                }
            } else {
                safe *= mj / j;
                limited = true;
            }
        }
    }
    let vmax = if moves_queued > 0 && prev.nominal_speed > 1e-6 {
        let (mut vmax, k) = if nominal_speed < prev.nominal_speed {
            (nominal_speed, nominal_speed / prev.nominal_speed)
        } else {
            (prev.nominal_speed, 1.0)
        };
        let mut vf: f64 = 1.0;
        let mut limited = false;
        for ((&exit, &entry), &mj) in prev.speed_mm_s.iter().zip(speed).zip(&s.jerk_mm_s) {
            let (mut ve, mut vn) = (exit * k, entry);
            if limited {
                ve *= vf;
                vn *= vf;
            }
            let jerk = axis_jerk(ve, vn);
            if jerk > mj {
                vf *= mj / jerk;
                limited = true;
            }
        }
        if limited {
            vmax *= vf;
        }
        if prev.safe_speed > 0.99 * vmax && safe > 0.99 * vmax {
            vmax = safe;
        }
        vmax
    } else {
        safe
    };
    prev.safe_speed = safe;
    vmax
}
