//! Marlin's planner on a delta: `_populate_block` (spec §4), the block queue with its
//! look-ahead (`recalculate`: reverse pass, forward pass, trapezoids; spec §5) and
//! `calculate_trapezoid_for_block` (spec §6).
//!
//! The queue is a `Vec` whose index 0 is Marlin's `block_buffer_tail`; `busy` says whether
//! the stepper is running that block; `planned` is `block_buffer_planned` as an index into
//! the `Vec`. The passes are Marlin's, with its `planned` pointer, its `recalculate` flags
//! and its `nominal_length` shortcut, written over the `Vec`.
//!
//! Time runs only when the stepper is fed (infinite CPU, spec §5.4): a new block waits for a
//! free slot (at most `BLOCK_BUFFER_SIZE − 1` blocks queued, the busy one included); when
//! the queue is full the oldest block is started (if the stepper is idle) and run to its end,
//! and the next one starts at once, with the exit speed and trapezoid it has at that
//! moment. A synchronising command runs the whole queue. Each block started is logged with
//! its start time and its frozen profile ([`Executed`]).

use super::stepper::{self, Timing};

/// Marlin's `MINIMAL_STEP_RATE` (planner.cpp), steps/s.
pub const MINIMAL_STEP_RATE: u32 = 120;

/// Axis indices: towers A, B, C (Marlin's X, Y, Z steppers), then E.
pub const E: usize = 3;

/// The planner's settings (M92 figures and what M201/M203/M204/M205/M221 change).
#[derive(Clone, Debug)]
pub struct Settings {
    /// Steps/mm of A, B, C, E.
    pub spm: [f64; 4],
    /// M203, mm/s (towers A, B, C, and E).
    pub max_feedrate: [f64; 4],
    /// M201, mm/s².
    pub max_accel: [f64; 4],
    /// M204 P.
    pub print_accel: f64,
    /// M204 R.
    pub retract_accel: f64,
    /// M204 T.
    pub travel_accel: f64,
    /// M205 X Y Z E (classic jerk), mm/s.
    pub jerk: [f64; 4],
    /// M205 S, mm/s.
    pub min_feedrate: f64,
    /// M205 T, mm/s.
    pub min_travel_feedrate: f64,
    /// M221 S, percent (`flow_percentage`, an int16 in Marlin).
    pub flow_percent: i32,
    /// `MIN_STEPS_PER_SEGMENT`.
    pub min_steps_per_segment: u32,
    /// `MINIMUM_PLANNER_SPEED`, mm/s.
    pub minimum_planner_speed: f64,
    /// `BLOCK_BUFFER_SIZE`.
    pub block_buffer_size: usize,
    /// `S_CURVE_ACCELERATION`.
    pub s_curve: bool,
}

impl Settings {
    /// `max_acceleration_steps_per_s2[i]` = uint32(M201 · steps/mm).
    pub fn max_accel_steps(&self, i: usize) -> u64 {
        to_u32(self.max_accel[i] * self.spm[i]) as u64
    }

    /// `e_factor`: flow % · 0.01 (no volumetric extrusion).
    pub fn e_factor(&self) -> f64 {
        self.flow_percent as f64 * 0.01
    }
}

/// A float stored into a `uint32_t` on ARM: truncation, negative → 0, saturating.
pub fn to_u32(v: f64) -> u32 {
    if v.is_nan() || v <= 0.0 {
        0
    } else if v >= u32::MAX as f64 {
        u32::MAX
    } else {
        v as u32
    }
}

/// A block's trapezoid (spec §6), in step rates of its dominant axis.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Trapezoid {
    pub initial_rate: u32,
    pub final_rate: u32,
    /// `cruise_rate`: the nominal rate, or the peak rate when the plateau is missing.
    pub cruise_rate: u32,
    pub accelerate_until: u32,
    pub decelerate_after: u32,
}

/// One planner block.
#[derive(Clone, Debug)]
pub struct Block {
    /// Tower step positions when the block starts.
    pub start: [i64; 3],
    /// Signed tower steps of the block.
    pub delta: [i64; 3],
    /// |steps| of A, B, C and the (flow-scaled, rounded) E steps.
    pub steps: [u32; 4],
    /// `step_event_count`.
    pub n: u32,
    /// Cartesian mm (the segment's hint, or |E| when no tower reaches MIN_STEPS).
    pub millimeters: f64,
    /// mm/s.
    pub nominal_speed: f64,
    /// steps/s.
    pub nominal_rate: u32,
    /// `acceleration_steps_per_s2`.
    pub accel_steps: u32,
    /// `acceleration`, Cartesian mm/s².
    pub acceleration: f64,
    /// `current_speed`: carriage mm/s of A, B, C and E mm/s, after the speed factor.
    pub speeds: [f64; 4],
    pub max_entry_sqr: f64,
    pub entry_sqr: f64,
    pub nominal_length: bool,
    pub recalculate: bool,
    pub trap: Trapezoid,
    /// Entry and exit speed (mm/s) of the last trapezoid computed.
    pub entry_speed: f64,
    pub exit_speed: f64,
}

/// A block as the stepper ran it: frozen when it started.
#[derive(Clone, Debug)]
pub struct Executed {
    pub block: Block,
    /// Global time of its start, s.
    pub start_s: f64,
    /// Its duration in the timing model, s.
    pub duration_s: f64,
}

/// A queue slot: a move, or a sync block (G92 E while moves are queued).
#[derive(Clone, Debug)]
pub enum Slot {
    Move(Box<Block>),
    Sync,
}

impl Slot {
    fn block(&self) -> Option<&Block> {
        match self {
            Slot::Move(b) => Some(b),
            Slot::Sync => None,
        }
    }
    fn block_mut(&mut self) -> Option<&mut Block> {
        match self {
            Slot::Move(b) => Some(b),
            Slot::Sync => None,
        }
    }
}

/// The planner and the stepper's feed.
#[derive(Debug)]
pub struct Planner {
    pub settings: Settings,
    pub timing: Timing,
    /// `position`: A, B, C, E in steps (last accepted target).
    pub position: [i64; 4],
    pub previous_speed: [f64; 4],
    pub previous_nominal_speed: f64,
    pub previous_safe_speed: f64,
    pub queue: Vec<Slot>,
    /// The stepper runs `queue[0]`.
    pub busy: bool,
    /// `block_buffer_planned`, an index into `queue`.
    pub planned: usize,
    /// The time the stepper becomes free (end of the running or last block), s.
    pub clock_s: f64,
    pub executed: Vec<Executed>,
    /// Segments dropped for fewer than MIN_STEPS_PER_SEGMENT steps.
    pub dropped: usize,
}

impl Planner {
    pub fn new(settings: Settings, timing: Timing) -> Planner {
        Planner {
            settings,
            timing,
            position: [0; 4],
            previous_speed: [0.0; 4],
            previous_nominal_speed: 0.0,
            previous_safe_speed: 0.0,
            queue: Vec::new(),
            busy: false,
            planned: 0,
            clock_s: 0.0,
            executed: Vec::new(),
            dropped: 0,
        }
    }

    /// At most this many slots are used (one is always empty).
    fn capacity(&self) -> usize {
        self.settings.block_buffer_size.max(2) - 1
    }

    fn is_busy(&self, index: usize) -> bool {
        self.busy && index == 0
    }

    // ----- the stepper's side -------------------------------------------------------

    /// The stepper takes the tail (`get_current_block`): sync blocks are consumed at once;
    /// a move becomes busy, its profile frozen, and runs from `clock_s`.
    fn start_tail(&mut self) {
        debug_assert!(!self.busy);
        while !self.queue.is_empty() {
            // `block_buffer_nonbusy` = tail + 1; push `planned` if it pointed at the tail.
            if self.planned == 0 {
                self.planned = 1;
            }
            match &self.queue[0] {
                Slot::Sync => {
                    self.queue.remove(0);
                    self.planned -= 1;
                }
                Slot::Move(b) => {
                    let block = (**b).clone();
                    let duration_s =
                        stepper::block_duration(&block, self.settings.s_curve, self.timing);
                    self.executed.push(Executed {
                        block,
                        start_s: self.clock_s,
                        duration_s,
                    });
                    self.clock_s += duration_s;
                    self.busy = true;
                    return;
                }
            }
        }
    }

    /// The running block ends; the next one starts at once.
    fn finish_busy(&mut self) {
        debug_assert!(self.busy);
        self.queue.remove(0);
        self.planned = self.planned.saturating_sub(1);
        self.busy = false;
        self.start_tail();
    }

    /// `get_next_free_block`: wait (running blocks) until a slot is free.
    fn wait_for_free_slot(&mut self) {
        while self.queue.len() >= self.capacity() {
            if self.busy {
                self.finish_busy();
            } else {
                self.start_tail();
            }
        }
    }

    /// `planner.synchronize()`: run every queued block to its end.
    pub fn synchronize(&mut self) {
        if !self.busy {
            self.start_tail();
        }
        while self.busy {
            self.finish_busy();
        }
        debug_assert!(self.queue.is_empty());
        self.planned = 0;
    }

    /// Idle time (a dwell) after a synchronize.
    pub fn dwell(&mut self, seconds: f64) {
        self.clock_s += seconds.max(0.0);
    }

    // ----- the planner's side -------------------------------------------------------

    /// `set_e_position_mm` (G92 E): the planner's E; a sync block if blocks are queued.
    pub fn set_e_position(&mut self, e_mm: f64) {
        self.position[E] = (e_mm * self.settings.spm[E]).round() as i64;
        if !self.queue.is_empty() {
            self.wait_for_free_slot();
            self.queue.push(Slot::Sync);
        }
    }

    /// `set_position` of the towers (after G28): the planner and stepper positions.
    pub fn set_tower_position(&mut self, steps: [i64; 3]) {
        self.position[..3].copy_from_slice(&steps);
    }

    /// `buffer_segment` → `_buffer_steps`: wait for a slot, populate (the block may be
    /// dropped), queue it and recalculate. `cart_dist` is the Cartesian XYZ distance, used
    /// when `hint_mm` is 0.
    pub fn buffer_segment(
        &mut self,
        target: [i64; 4],
        cart_dist: [f64; 3],
        fr_mm_s: f64,
        hint_mm: f64,
        safe_exit_sqr: f64,
    ) {
        self.wait_for_free_slot();
        match self.populate(target, cart_dist, fr_mm_s, hint_mm) {
            None => self.dropped += 1,
            Some(block) => {
                self.queue.push(Slot::Move(Box::new(block)));
                self.recalculate(safe_exit_sqr);
            }
        }
    }

    /// `_populate_block` (spec §4; planner.cpp 1880–2950). None: the block is dropped
    /// (fewer than MIN_STEPS_PER_SEGMENT steps) and nothing is updated.
    fn populate(
        &mut self,
        target: [i64; 4],
        cart_dist: [f64; 3],
        fr_mm_s: f64,
        hint_mm: f64,
    ) -> Option<Block> {
        let s = &self.settings;
        let d: [i64; 4] = [0, 1, 2, 3].map(|i| target[i] - self.position[i]);
        // 4.1 steps, E with flow.
        let esteps_float = d[E] as f64 * s.e_factor();
        let esteps = (esteps_float.abs() + 0.5) as u32;
        let steps = [
            d[0].unsigned_abs() as u32,
            d[1].unsigned_abs() as u32,
            d[2].unsigned_abs() as u32,
            esteps,
        ];
        let steps_dist_mm = [
            d[0] as f64 / s.spm[0],
            d[1] as f64 / s.spm[1],
            d[2] as f64 / s.spm[2],
            esteps_float / s.spm[E],
        ];
        // 4.2 millimeters.
        let min_steps = s.min_steps_per_segment;
        let millimeters = if steps[..3].iter().all(|&st| st < min_steps) {
            steps_dist_mm[E].abs()
        } else if hint_mm != 0.0 {
            hint_mm
        } else {
            (cart_dist[0].powi(2) + cart_dist[1].powi(2) + cart_dist[2].powi(2)).sqrt()
        };
        // 4.3 drop test.
        let n = steps.iter().copied().max().unwrap_or(0);
        if n < min_steps {
            return None;
        }
        // A block whose towers move but whose Cartesian length is 0 (only after an M665
        // change of the geometry): Marlin would divide by zero; we take the longest
        // carriage travel as its length.
        let millimeters = if millimeters > 0.0 {
            millimeters
        } else {
            steps_dist_mm.iter().fold(0.0f64, |m, v| m.max(v.abs()))
        };
        // 4.4 minimum feedrate.
        let fr = if esteps > 0 {
            fr_mm_s.max(s.min_feedrate)
        } else {
            fr_mm_s.max(s.min_travel_feedrate)
        };
        // 4.5 inverse time (SLOWDOWN is compiled out on a delta).
        let inverse_secs = fr / millimeters;
        let moves_queued = self.queue.len() - usize::from(self.busy);
        // 4.6 nominal speed and rate.
        let mut nominal_speed = millimeters * inverse_secs;
        let mut nominal_rate = to_u32((n as f64 * inverse_secs).ceil());
        // 4.7 per-axis (tower) speed limits.
        let mut speeds = steps_dist_mm.map(|v| v * inverse_secs);
        let mut speed_factor = 1.0f64;
        for (v, max) in speeds.iter().zip(s.max_feedrate) {
            if v.abs() > max {
                speed_factor = speed_factor.min(max / v.abs());
            }
        }
        if speed_factor < 1.0 {
            for v in &mut speeds {
                *v *= speed_factor;
            }
            nominal_rate = to_u32(nominal_rate as f64 * speed_factor);
            nominal_speed *= speed_factor;
        }
        // 4.8 acceleration.
        let steps_per_mm = n as f64 / millimeters;
        let mut accel: u32;
        if steps[..3].iter().all(|&st| st == 0) {
            accel = to_u32((s.retract_accel * steps_per_mm).ceil());
        } else {
            let a = if esteps > 0 {
                s.print_accel
            } else {
                s.travel_accel
            };
            accel = to_u32((a * steps_per_mm).ceil());
            // Order E, A, B, C; `max_acc · n / steps` in integers.
            for i in [E, 0, 1, 2] {
                let max_acc = s.max_accel_steps(i);
                if steps[i] > 0 && max_acc < accel as u64 {
                    let cap = max_acc * n as u64 / steps[i] as u64;
                    accel = accel.min(cap.min(u32::MAX as u64) as u32);
                }
            }
        }
        let acceleration = accel as f64 / steps_per_mm;
        // 4.10 classic jerk, axes A, B, C, E in this order.
        let mut safe_speed = nominal_speed;
        let mut limited = false;
        for (i, v) in speeds.iter().enumerate() {
            let jerk = v.abs();
            let maxj = s.jerk[i];
            if jerk > maxj {
                if limited {
                    let mjerk = nominal_speed * maxj;
                    if jerk * safe_speed > mjerk {
                        safe_speed = mjerk / jerk;
                    }
                } else {
                    safe_speed *= maxj / jerk;
                    limited = true;
                }
            }
        }
        let vmax_junction;
        if moves_queued > 0 && self.previous_nominal_speed >= 0.000001 {
            let mut v_factor = 1.0f64;
            let mut limited = false;
            let mut smaller_speed_factor = 1.0f64;
            let mut vmax = if nominal_speed < self.previous_nominal_speed {
                smaller_speed_factor = nominal_speed / self.previous_nominal_speed;
                nominal_speed
            } else {
                self.previous_nominal_speed
            };
            for (axis, (&previous, &v_new)) in self.previous_speed.iter().zip(&speeds).enumerate() {
                let mut v_exit = previous * smaller_speed_factor;
                let mut v_entry = v_new;
                if limited {
                    v_exit *= v_factor;
                    v_entry *= v_factor;
                }
                let jerk = if v_exit > v_entry {
                    if v_entry > 0.0 || v_exit < 0.0 {
                        v_exit - v_entry
                    } else {
                        v_exit.max(-v_entry)
                    }
                } else if v_entry < 0.0 || v_exit > 0.0 {
                    v_entry - v_exit
                } else {
                    (-v_exit).max(v_entry)
                };
                let maxj = s.jerk[axis];
                if jerk > maxj {
                    v_factor *= maxj / jerk;
                    limited = true;
                }
            }
            if limited {
                vmax *= v_factor;
            }
            let threshold = vmax * 0.99;
            if self.previous_safe_speed > threshold && safe_speed > threshold {
                vmax = safe_speed;
            }
            vmax_junction = vmax;
        } else {
            vmax_junction = safe_speed;
        }
        self.previous_safe_speed = safe_speed;
        // 4.11 entry and flags.
        let mps2 = s.minimum_planner_speed * s.minimum_planner_speed;
        let block = Block {
            start: [self.position[0], self.position[1], self.position[2]],
            delta: [d[0], d[1], d[2]],
            steps,
            n,
            millimeters,
            nominal_speed,
            nominal_rate,
            accel_steps: accel,
            acceleration,
            speeds,
            max_entry_sqr: vmax_junction * vmax_junction,
            entry_sqr: mps2,
            nominal_length: nominal_speed * nominal_speed
                <= mps2 + 2.0 * acceleration * millimeters,
            recalculate: true,
            trap: Trapezoid::default(),
            entry_speed: 0.0,
            exit_speed: 0.0,
        };
        self.previous_speed = speeds;
        self.previous_nominal_speed = nominal_speed;
        self.position = target;
        Some(block)
    }

    /// `recalculate(safe_exit_speed_sqr)`: the passes unless the new block is the only
    /// plannable one, then the trapezoids.
    fn recalculate(&mut self, safe_exit_sqr: f64) {
        let newest = self.queue.len() - 1;
        if newest != self.planned {
            self.reverse_pass(safe_exit_sqr);
            self.forward_pass();
        }
        self.recalculate_trapezoids(safe_exit_sqr);
    }

    /// From the newest block down to, not including, `planned`; moves only.
    fn reverse_pass(&mut self, safe_exit_sqr: f64) {
        if self.planned >= self.queue.len() {
            return;
        }
        let mps2 = self.settings.minimum_planner_speed.powi(2);
        let mut next: Option<usize> = None;
        let mut index = self.queue.len() - 1;
        while index != self.planned {
            if self.queue[index].block().is_some() {
                let (next_entry_sqr, next_recalculate) = match next {
                    Some(j) => {
                        let nb = self.queue[j].block().expect("a move");
                        (nb.entry_sqr, nb.recalculate)
                    }
                    None => (safe_exit_sqr.max(mps2), false),
                };
                let busy = self.is_busy(index);
                let cur = self.queue[index].block_mut().expect("a move");
                let max_entry = cur.max_entry_sqr;
                if cur.entry_sqr != max_entry || next_recalculate {
                    let new_entry = if cur.nominal_length {
                        max_entry
                    } else {
                        max_entry.min(next_entry_sqr + 2.0 * cur.acceleration * cur.millimeters)
                    };
                    if cur.entry_sqr != new_entry && !busy {
                        cur.recalculate = true;
                        cur.entry_sqr = new_entry;
                    }
                }
                next = Some(index);
            }
            index -= 1;
        }
    }

    /// From `planned` to the newest block; moves only.
    fn forward_pass(&mut self) {
        let mut previous: Option<usize> = None;
        let mut index = self.planned;
        while index < self.queue.len() {
            if self.queue[index].block().is_some() {
                if previous.is_none_or(|p| !self.is_busy(p)) {
                    self.forward_kernel(previous, index);
                }
                previous = Some(index);
            }
            index += 1;
        }
    }

    fn forward_kernel(&mut self, previous: Option<usize>, index: usize) {
        let Some(p) = previous else { return };
        let prev = self.queue[p].block().expect("a move").clone();
        let busy = self.is_busy(index);
        let cur = self.queue[index].block_mut().expect("a move");
        let mut planned = None;
        if !prev.nominal_length && prev.entry_sqr < cur.entry_sqr {
            let new_entry = prev.entry_sqr + 2.0 * prev.acceleration * prev.millimeters;
            if new_entry < cur.entry_sqr && !busy {
                cur.recalculate = true;
                cur.entry_sqr = new_entry;
                planned = Some(index);
            }
        }
        if cur.entry_sqr == cur.max_entry_sqr {
            planned = Some(index);
        }
        if let Some(i) = planned {
            self.planned = i;
        }
    }

    /// `recalculate_trapezoids`: every flagged non-busy block, then the newest move always,
    /// with exit max(√safe_exit, MINIMUM_PLANNER_SPEED).
    fn recalculate_trapezoids(&mut self, safe_exit_sqr: f64) {
        let mut head = self.queue.len();
        while head > 0 && self.queue[head - 1].block().is_none() {
            head -= 1;
        }
        let mut block: Option<usize> = None;
        let mut current_entry_speed = 0.0;
        for index in 0..head {
            let Some(next) = self.queue[index].block() else {
                continue;
            };
            let next_entry_speed = next.entry_sqr.sqrt();
            let next_recalculate = next.recalculate;
            if let Some(b) = block {
                let busy = self.is_busy(b);
                let prev = self.queue[b].block_mut().expect("a move");
                if next_recalculate {
                    prev.recalculate = true;
                }
                if prev.recalculate {
                    if !busy {
                        calculate_trapezoid(prev, current_entry_speed, next_entry_speed);
                    }
                    prev.recalculate = false;
                }
            }
            block = Some(index);
            current_entry_speed = next_entry_speed;
        }
        if let Some(b) = block {
            let exit = safe_exit_sqr
                .sqrt()
                .max(self.settings.minimum_planner_speed);
            let busy = self.is_busy(b);
            let last = self.queue[b].block_mut().expect("a move");
            if !busy {
                calculate_trapezoid(last, current_entry_speed, exit);
            }
            last.recalculate = false;
        }
    }
}

/// `calculate_trapezoid_for_block(block, entry/nominal, exit/nominal)` (spec §6).
pub fn calculate_trapezoid(b: &mut Block, entry_speed: f64, exit_speed: f64) {
    let nomr = 1.0 / b.nominal_speed;
    let entry_factor = entry_speed * nomr;
    let exit_factor = exit_speed * nomr;
    let initial_rate = to_u32((b.nominal_rate as f64 * entry_factor).ceil()).max(MINIMAL_STEP_RATE);
    let final_rate = to_u32((b.nominal_rate as f64 * exit_factor).ceil()).max(MINIMAL_STEP_RATE);
    let mut cruise_rate = b.nominal_rate;
    let n = b.n;
    let mut accelerate_steps: u32 = 0;
    let mut decelerate_steps: u32 = 0;
    let accel = b.accel_steps;
    if accel != 0 {
        let half_inverse_accel = 0.5 / accel as f64;
        let nominal_rate_sq = (b.nominal_rate as f64).powi(2);
        let decelerate_steps_float =
            half_inverse_accel * (nominal_rate_sq - (final_rate as f64).powi(2));
        let accelerate_steps_float =
            half_inverse_accel * (nominal_rate_sq - (initial_rate as f64).powi(2));
        accelerate_steps = to_u32(accelerate_steps_float.ceil());
        decelerate_steps = to_u32(decelerate_steps_float.floor());
        let plateau_steps = n as i64 - accelerate_steps as i64 - decelerate_steps as i64;
        if plateau_steps < 0 {
            let a = ((n as f64 + accelerate_steps_float - decelerate_steps_float) * 0.5).ceil();
            accelerate_steps = to_u32(a.max(0.0)).min(n);
            decelerate_steps = n - accelerate_steps;
            cruise_rate = to_u32(
                ((initial_rate as f64).powi(2) + 2.0 * accel as f64 * accelerate_steps as f64)
                    .sqrt(),
            );
        }
    }
    b.trap = Trapezoid {
        initial_rate,
        final_rate,
        cruise_rate,
        accelerate_until: accelerate_steps,
        decelerate_after: n - decelerate_steps,
    };
    b.entry_speed = entry_speed;
    b.exit_speed = exit_speed;
}
