//! Marlin 2.1.2.x on a linear delta (docs/planner.md, "Marlin"): each G0/G1 cut into
//! segments ([`segmenter`], `line_to_destination_kinematic`), each segment a planner block
//! on whole tower steps ([`block`], `_populate_block`: per-tower limits, classic jerk), the
//! block buffer's bounded lookahead ([`lookahead`], `recalculate`), each block's step-rate
//! trapezoid ([`trapezoid`]) or S-curve ([`scurve`]) as the stepper ISR times it ([`isr`]),
//! and its pieces, linear in tower space ([`pieces`]). Arcs come
//! cut by `plan_arc` from the interpreter; each chord is one block.

pub mod block;
pub mod isr;
pub mod lookahead;
pub mod pieces;
pub mod scurve;
pub mod segmenter;
pub mod settings;
#[cfg(test)]
mod tests;
pub mod trapezoid;

use super::Firmware;
use crate::delta::DeltaModel;
use crate::gcode::{Event, Move};
use crate::machine::Machine;
use crate::motion::{CONTINUITY_MM, Segment};
use crate::path::Vec3;
use block::{Previous, Target};
use lookahead::{Lookahead, Planned};
use pieces::Pose;
use settings::Settings;
use trapezoid::Ramp;

/// Marlin's planner and stepper as a stream.
pub struct Marlin {
    model: DeltaModel,
    settings: Settings,
    lookahead: Lookahead,
    prev: Previous,
    /// `DELTA_IK`'s towers (x, y) and squared rods: Marlin's carriage height is above the
    /// nozzle's Z; ours adds the nozzle offset.
    towers_xy_mm: [[f64; 2]; 3],
    arm2_mm2: [f64; 3],
    /// The carriages at home: their heights (ours) and step counts (Marlin's).
    home_q_mm: [f64; 3],
    home_steps: [i64; 3],
    /// `planner.position`: the last accepted block's target, steps (towers, E).
    steps: [i64; 4],
    /// The last segment's Cartesian target, and the E position, mm.
    cart: Vec3,
    e_mm: f64,
    /// Where the last handed-on block ended, and when.
    pose: Pose,
    t_s: f64,
    ramps: Vec<Ramp>,
    planned: Vec<Planned>,
}

impl Marlin {
    /// Marlin with `settings` on `machine`'s geometry, at home.
    pub fn new(machine: &Machine, settings: Settings) -> Marlin {
        let model = machine.model();
        let home = Vec3::new(0.0, 0.0, machine.geometry.home_z_mm);
        let home_q_mm = model.home_carriages_mm();
        let nozzle_offset_mm = machine.geometry.nozzle_offset_mm;
        let home_steps: [i64; 3] = std::array::from_fn(|i| {
            lround((home_q_mm[i] - nozzle_offset_mm) * settings.steps_per_mm[i])
        });
        Marlin {
            lookahead: Lookahead::new(
                settings.block_buffer_size,
                settings.minimum_planner_speed_mm_s,
            ),
            prev: Previous::default(),
            towers_xy_mm: model.towers_xy_mm(),
            arm2_mm2: machine.geometry.arm_length_mm.map(|l| l * l),
            home_q_mm,
            home_steps,
            steps: [home_steps[0], home_steps[1], home_steps[2], 0],
            cart: home,
            e_mm: 0.0,
            pose: Pose {
                q_mm: home_q_mm,
                p: home,
            },
            t_s: 0.0,
            ramps: Vec::new(),
            planned: Vec::new(),
            model,
            settings,
        }
    }

    /// Print time of the blocks handed on so far, dwells included, s.
    pub fn print_time_s(&self) -> f64 {
        self.t_s
    }

    /// `buffer_segment`'s targets: the towers' (`DELTA_IK`, `lroundf(mm · steps/mm)`), E's.
    /// Marlin's IK has no check: a target above the carriages' travel gets its steps (the
    /// analysis reports it); one beyond the arms' reach (a NaN in Marlin) none.
    fn target_steps(&self, p: Vec3, e_mm: f64) -> Option<[i64; 4]> {
        let spm = &self.settings.steps_per_mm;
        let mut out = [0; 4];
        for i in 0..3 {
            let [tx, ty] = self.towers_xy_mm[i];
            let radicand = self.arm2_mm2[i] - (tx - p.x).powi(2) - (ty - p.y).powi(2);
            if radicand.is_nan() || radicand <= 0.0 || !p.z.is_finite() {
                return None;
            }
            out[i] = lround((p.z + radicand.sqrt()) * spm[i]);
        }
        out[3] = lround(e_mm * spm[3]);
        Some(out)
    }

    /// The carriages' heights for tower step counts: the endstops fix the steps at home,
    /// so a step count is its height above or below the home height.
    fn pose(&self, steps: &[i64; 4], fallback: Vec3) -> Pose {
        let q_mm = std::array::from_fn(|i| {
            self.home_q_mm[i]
                + (steps[i] - self.home_steps[i]) as f64 / self.settings.steps_per_mm[i]
        });
        Pose {
            q_mm,
            p: self.model.forward(q_mm).unwrap_or(fallback),
        }
    }

    /// A move: its segments, each a block (or dropped, or a block's room made).
    fn add_move(&mut self, m: &Move, commanded: &mut Vec<Segment>) {
        let start = m.path.start();
        if (start - self.cart).norm() > CONTINUITY_MM {
            // Re-homed (G28), or placed before the first move: the planner starts there.
            self.flush(commanded);
            self.cart = start;
            if let Some(s) = self.target_steps(start, self.e_mm) {
                self.steps = s;
                self.pose = self.pose(&s, start);
            }
        }
        let end = m.path.end();
        let (count, hint_mm) = if m.arc.is_some() {
            (1, 0.0)
        } else {
            match segmenter::count(
                start,
                end,
                m.e_mm,
                m.feed_mm_s,
                self.settings.segments_per_second,
                self.settings.ubl,
            ) {
                Some(c) => c,
                None => return,
            }
        };
        let e0 = self.e_mm;
        for k in 1..=count {
            let p = segmenter::point(start, end, k, count);
            let e = if k == count {
                e0 + m.e_mm
            } else {
                e0 + m.e_mm * (k as f64 / count as f64)
            };
            self.add_segment(m.line, p, e, m.feed_mm_s, hint_mm, commanded);
        }
        self.e_mm = e0 + m.e_mm;
        self.cart = end;
    }

    /// `buffer_line` of one segment.
    fn add_segment(
        &mut self,
        line: u64,
        p: Vec3,
        e_mm: f64,
        feed_mm_s: f64,
        hint_mm: f64,
        commanded: &mut Vec<Segment>,
    ) {
        let cart_mm = (p - self.cart).norm();
        self.cart = p;
        // An unreachable target is reported by the move's check; Marlin's IK would give
        // NaN steps: nothing is queued.
        let Some(to_steps) = self.target_steps(p, e_mm) else {
            return;
        };
        let planned = &mut self.planned;
        let moves_queued = self.lookahead.make_room(&mut |b| planned.push(b));
        let target = Target {
            line,
            to_steps,
            feed_mm_s,
            hint_mm,
            cart_mm,
        };
        if let Some(b) = block::populate(
            &self.settings,
            self.steps,
            &target,
            moves_queued,
            &mut self.prev,
        ) {
            self.steps = to_steps;
            self.lookahead.push(b);
        }
        self.hand_on(commanded);
    }

    fn flush(&mut self, commanded: &mut Vec<Segment>) {
        let planned = &mut self.planned;
        self.lookahead.flush(&mut |b| planned.push(b));
        self.hand_on(commanded);
    }

    /// The planned blocks as pieces, in time order.
    fn hand_on(&mut self, commanded: &mut Vec<Segment>) {
        let planned = std::mem::take(&mut self.planned);
        for pb in &planned {
            let b = &pb.block;
            let t = trapezoid::trapezoid(b, pb.entry_mm_s, pb.exit_mm_s);
            let n = f64::from(b.step_events);
            isr::ramps(
                &t,
                b.accel_steps_s2,
                n,
                self.settings.s_curve,
                &mut self.ramps,
            );
            let duration: f64 = self.ramps.iter().map(|r| r.dt_s).sum();
            let to = self.pose(&b.to_steps, self.pose.p);
            if b.moves_towers() {
                pieces::emit(
                    &self.model,
                    self.pose,
                    to,
                    n,
                    &self.ramps,
                    self.t_s,
                    b.line,
                    &mut |s| commanded.push(s),
                );
            } else if duration > 0.0 {
                commanded.push(Segment::rest(self.t_s, duration, self.pose.p, b.line));
            }
            self.pose = to;
            self.t_s += duration;
        }
        self.planned = planned;
        self.planned.clear();
    }
}

/// `lroundf`: to the nearest integer, halves away from zero.
fn lround(v: f64) -> i64 {
    v.round() as i64
}

impl Firmware for Marlin {
    fn push(&mut self, event: &Event, commanded: &mut Vec<Segment>) {
        match event {
            Event::Move(m) => self.add_move(m, commanded),
            Event::Stop { line, dwell_s } => {
                self.flush(commanded);
                if dwell_s.is_finite() && *dwell_s > 0.0 {
                    commanded.push(Segment::rest(self.t_s, *dwell_s, self.pose.p, *line));
                    self.t_s += dwell_s;
                }
            }
            Event::Marlin { change, .. } => self.settings.apply(change),
            // Klipper's commands: the interpreter does not send them in Marlin's dialect.
            Event::Limits { .. } | Event::Shaper { .. } => {}
        }
    }

    fn finish(&mut self, commanded: &mut Vec<Segment>) {
        self.flush(commanded);
    }
}
