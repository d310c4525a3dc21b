//! The three limits the tuning lowers, and the edit of the event stream that applies caps
//! to them: what the firmware would do with limit commands added before the
//! moves (`fix`) or with lower limits everywhere (the recommendation).

use std::collections::VecDeque;
use std::sync::{Arc, Mutex};

use super::held::{FileLimits, Held};
use crate::gcode::{Event, LimitChange};
use crate::machine::Machine;

/// The three limits the tuning lowers, one per cause, mm/s², mm/s, mm/s: Klipper's
/// acceleration, square-corner velocity and velocity (toolhead.py `set_max_velocities`);
/// for Marlin, caps on M204 P/T, on the towers' classic jerk M205 X/Y/Z and on their
/// feedrate M203 X/Y/Z (`held`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Toolhead {
    pub accel_mm_s2: f64,
    pub scv_mm_s: f64,
    pub velocity_mm_s: f64,
}

impl Toolhead {
    /// No cap.
    pub const UNLIMITED: Toolhead = Toolhead {
        accel_mm_s2: f64::INFINITY,
        scv_mm_s: f64::INFINITY,
        velocity_mm_s: f64::INFINITY,
    };

    /// The profile's limits, those the firmware starts with.
    pub fn of(machine: &Machine) -> Toolhead {
        let l = &machine.limits;
        Toolhead {
            accel_mm_s2: l.max_accel_mm_s2,
            scv_mm_s: l.square_corner_velocity_mm_s,
            velocity_mm_s: l.max_velocity_mm_s,
        }
    }

    /// After an M204 / SET_VELOCITY_LIMIT, with the values Klipper accepts
    /// ([`LimitChange::accepted`], as the planner applies them).
    pub fn apply(&mut self, change: &LimitChange) {
        let c = change.accepted();
        self.velocity_mm_s = c.velocity_mm_s.unwrap_or(self.velocity_mm_s);
        self.accel_mm_s2 = c.accel_mm_s2.unwrap_or(self.accel_mm_s2);
        self.scv_mm_s = c.square_corner_velocity_mm_s.unwrap_or(self.scv_mm_s);
    }

    /// Each limit the smaller of the two.
    pub fn min(&self, o: &Toolhead) -> Toolhead {
        Toolhead {
            accel_mm_s2: self.accel_mm_s2.min(o.accel_mm_s2),
            scv_mm_s: self.scv_mm_s.min(o.scv_mm_s),
            velocity_mm_s: self.velocity_mm_s.min(o.velocity_mm_s),
        }
    }

    /// Each limit the larger of the two.
    pub fn max(&self, o: &Toolhead) -> Toolhead {
        Toolhead {
            accel_mm_s2: self.accel_mm_s2.max(o.accel_mm_s2),
            scv_mm_s: self.scv_mm_s.max(o.scv_mm_s),
            velocity_mm_s: self.velocity_mm_s.max(o.velocity_mm_s),
        }
    }

    /// The change that takes a firmware at `from` to these limits: only the limits that
    /// differ.
    pub fn change_from(&self, from: &Toolhead) -> LimitChange {
        let differs = |a: f64, b: f64| (a != b).then_some(a);
        LimitChange {
            velocity_mm_s: differs(self.velocity_mm_s, from.velocity_mm_s),
            accel_mm_s2: differs(self.accel_mm_s2, from.accel_mm_s2),
            square_corner_velocity_mm_s: differs(self.scv_mm_s, from.scv_mm_s),
            ..LimitChange::default()
        }
    }
}

/// Caps over ranges of lines: disjoint, sorted `(first line, last line, caps)`.
pub type Segments = [(u64, u64, Toolhead)];

/// Disjoint segments from ranges that may overlap, each line capped by every range that
/// holds it.
pub fn segments(
    ranges: impl IntoIterator<Item = (u64, u64, Toolhead)>,
) -> Vec<(u64, u64, Toolhead)> {
    let ranges: Vec<_> = ranges.into_iter().filter(|r| r.0 <= r.1).collect();
    let mut cuts: Vec<u64> = ranges.iter().flat_map(|r| [r.0, r.1 + 1]).collect();
    cuts.sort_unstable();
    cuts.dedup();
    let mut out: Vec<(u64, u64, Toolhead)> = Vec::new();
    for w in cuts.windows(2) {
        let (a, b) = (w[0], w[1] - 1);
        let caps = ranges
            .iter()
            .filter(|r| r.0 <= a && b <= r.1)
            .fold(None, |acc: Option<Toolhead>, r| {
                Some(acc.map_or(r.2, |c| c.min(&r.2)))
            });
        let Some(caps) = caps else { continue };
        match out.last_mut() {
            Some(last) if last.1 + 1 == a && last.2 == caps => last.1 = b,
            _ => out.push((a, b, caps)),
        }
    }
    out
}

/// The limits one move ran with: its line and the limits in force (velocity also capped by
/// the move's own feed).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MoveLimits {
    pub line: u64,
    pub limits: Toolhead,
}

/// The limits of the moves on their way through the pipeline: the edit adds them, the
/// stage that sees the moves' results takes them. Bounded by the moves in flight.
pub type InFlight = Arc<Mutex<VecDeque<MoveLimits>>>;

/// A limit command added before a move: its line and the event (Klipper's
/// `Event::Limits`, or one `Event::Marlin` per command).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Added {
    pub before_line: u64,
    pub event: Event,
}

/// The edit of the events: the file's own limit changes go through (they are what the
/// file set, restored after a capped range); before each move whose limits differ from
/// what the firmware has, the changes to `min(the file's, the caps)`, in the firmware's
/// own events (Klipper's `SET_VELOCITY_LIMIT`, Marlin's M204/M205/M203: [`Held`]).
pub struct CapEdit<'s> {
    segments: &'s Segments,
    next: usize,
    global: Toolhead,
    /// What the file set (the profile's limits until it sets one).
    file: FileLimits,
    /// What the firmware has now.
    firmware: FileLimits,
    /// The largest limits the file set.
    pub file_peak: Held,
    pub in_flight: InFlight,
    /// The limit commands added, when kept (for `fix`'s output).
    pub added: Option<Vec<Added>>,
}

impl<'s> CapEdit<'s> {
    pub fn new(machine: &Machine, segments: &'s Segments, global: Toolhead, keep: bool) -> Self {
        let start = FileLimits::of(machine);
        CapEdit {
            segments,
            next: 0,
            global,
            file_peak: start.held(),
            firmware: start.clone(),
            file: start,
            in_flight: InFlight::default(),
            added: keep.then(Vec::new),
        }
    }

    /// The caps on `line` (lines come in increasing order).
    fn caps(&mut self, line: u64) -> Toolhead {
        while self.segments.get(self.next).is_some_and(|s| s.1 < line) {
            self.next += 1;
        }
        match self.segments.get(self.next) {
            Some(&(a, _, caps)) if a <= line => caps.min(&self.global),
            _ => self.global,
        }
    }

    /// Takes one event of the interpreter; hands on what the firmware is to see.
    pub fn edit(&mut self, event: &Event, out: &mut dyn FnMut(&Event)) {
        match event {
            Event::Move(m) => {
                let caps = self.caps(m.line);
                let want = self.file.held().capped(&caps);
                let have = self.firmware.held();
                if want != have {
                    for e in want.events_from(&have, m.line) {
                        if let Some(added) = &mut self.added {
                            added.push(Added {
                                before_line: m.line,
                                event: e,
                            });
                        }
                        out(&e);
                    }
                    self.firmware.set(&want);
                }
                if let Ok(mut q) = self.in_flight.lock() {
                    q.push_back(MoveLimits {
                        line: m.line,
                        limits: want.ran(m),
                    });
                }
            }
            e => {
                if self.file.apply(e) {
                    self.file_peak = self.file_peak.max(&self.file.held());
                    self.firmware.apply(e);
                }
            }
        }
        out(event);
    }
}

/// The limits of the move of `line` (results come in line order): the entries of earlier
/// lines are dropped.
pub fn limits_of(in_flight: &InFlight, line: u64) -> Option<Toolhead> {
    let mut q = in_flight.lock().ok()?;
    while q.front().is_some_and(|m| m.line < line) {
        q.pop_front();
    }
    q.front().filter(|m| m.line == line).map(|m| m.limits)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn caps(a: f64) -> Toolhead {
        Toolhead {
            accel_mm_s2: a,
            ..Toolhead::UNLIMITED
        }
    }

    #[test]
    fn caps_go_before_their_moves_and_the_file_s_own_limits_come_back() {
        use crate::gcode::Move;
        use crate::path::{Path, Vec3};
        let machine = crate::machine::test_support::kossel_machine();
        let mv = |line| {
            Event::Move(Move {
                line,
                path: Path::line(Vec3::new(0.0, 0.0, 10.0), Vec3::new(1.0, 0.0, 10.0)),
                e_mm: 0.0,
                feed_mm_s: 50.0,
                offset_mm: Vec3::zeros(),
                arc: None,
            })
        };
        let limits = |line, accel| Event::Limits {
            line,
            change: LimitChange {
                accel_mm_s2: Some(accel),
                ..LimitChange::default()
            },
        };
        let segs = [(3, 5, caps(1000.0))];
        let mut edit = CapEdit::new(&machine, &segs, Toolhead::UNLIMITED, true);
        let mut seen = Vec::new();
        for e in [
            limits(1, 5000.0),
            mv(2),
            mv(3),
            limits(4, 6000.0),
            mv(5),
            mv(6),
        ] {
            edit.edit(&e, &mut |e| seen.push(*e));
        }
        let accel_change = |line, a| Event::Limits {
            line,
            change: LimitChange {
                accel_mm_s2: Some(a),
                ..LimitChange::default()
            },
        };
        assert_eq!(
            seen,
            [
                limits(1, 5000.0),
                mv(2),
                accel_change(3, 1000.0),
                mv(3),
                // The file's own change inside the range: the cap again before the move.
                limits(4, 6000.0),
                accel_change(5, 1000.0),
                mv(5),
                // After the range: what the file set last.
                accel_change(6, 6000.0),
                mv(6),
            ]
        );
        assert_eq!(edit.added.as_ref().map(Vec::len), Some(3));
        assert_eq!(edit.file_peak.knobs().accel_mm_s2, 6000.0);
        // The moves' limits, velocity capped by their feed.
        assert_eq!(limits_of(&edit.in_flight, 3).unwrap().accel_mm_s2, 1000.0);
        let six = limits_of(&edit.in_flight, 6).unwrap();
        assert_eq!((six.accel_mm_s2, six.velocity_mm_s), (6000.0, 50.0));
    }

    #[test]
    fn overlapping_ranges_become_disjoint_segments() {
        let s = segments([
            (10, 20, caps(1000.0)),
            (15, 30, caps(500.0)),
            (40, 41, caps(9.0)),
        ]);
        assert_eq!(
            s,
            vec![
                (10, 14, caps(1000.0)),
                (15, 30, caps(500.0)),
                (40, 41, caps(9.0))
            ]
        );
        assert_eq!(
            segments([(5, 5, caps(1.0)), (6, 8, caps(1.0))]),
            vec![(5, 8, caps(1.0))]
        );
    }
}
