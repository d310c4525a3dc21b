//! The limits the tuning changes as each firmware holds them, and the events that change
//! them: Klipper's three toolhead limits (`SET_VELOCITY_LIMIT`), or Marlin's settings
//! behind the same three causes (docs/report.md, "Recommendation"):
//! - acceleration: M204 P (printing moves) and T (travel); R is left alone (an E-only
//!   move does not move the towers);
//! - corner: classic jerk M205 X Y Z, on a delta the largest jump of towers A, B, C's
//!   speeds at a block junction (`_populate_block`, firmware/marlin/block.rs);
//! - speed: M203 X Y Z, on a delta the cap on towers A, B, C's carriage speeds: what the
//!   motor's torque-speed curve limits.
//!
//! Marlin's settings are followed with the planner's own [`Settings::apply`], and the
//! changes go to the planner as [`Event::Marlin`], which it applies the same way.

use super::limits::Toolhead;
use crate::firmware::marlin::settings::Settings;
use crate::gcode::{Event, MarlinChange, Move};
use crate::machine::{Firmware, Machine};

/// Marlin's settings the tuning lowers; towers A, B, C (Marlin's X, Y, Z).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MarlinLimits {
    /// M204 P and T, mm/s².
    pub print_accel_mm_s2: f64,
    pub travel_accel_mm_s2: f64,
    /// M205 X Y Z, mm/s.
    pub jerk_mm_s: [f64; 3],
    /// M203 X Y Z, mm/s.
    pub max_feedrate_mm_s: [f64; 3],
}

impl MarlinLimits {
    fn of(s: &Settings) -> MarlinLimits {
        MarlinLimits {
            print_accel_mm_s2: s.print_accel_mm_s2,
            travel_accel_mm_s2: s.travel_accel_mm_s2,
            jerk_mm_s: [s.jerk_mm_s[0], s.jerk_mm_s[1], s.jerk_mm_s[2]],
            max_feedrate_mm_s: [
                s.max_feedrate_mm_s[0],
                s.max_feedrate_mm_s[1],
                s.max_feedrate_mm_s[2],
            ],
        }
    }

    fn set_in(&self, s: &mut Settings) {
        s.print_accel_mm_s2 = self.print_accel_mm_s2;
        s.travel_accel_mm_s2 = self.travel_accel_mm_s2;
        s.jerk_mm_s[..3].copy_from_slice(&self.jerk_mm_s);
        s.max_feedrate_mm_s[..3].copy_from_slice(&self.max_feedrate_mm_s);
    }

    /// Each the smaller of itself and its cause's cap.
    pub fn capped(&self, caps: &Toolhead) -> MarlinLimits {
        MarlinLimits {
            print_accel_mm_s2: self.print_accel_mm_s2.min(caps.accel_mm_s2),
            travel_accel_mm_s2: self.travel_accel_mm_s2.min(caps.accel_mm_s2),
            jerk_mm_s: self.jerk_mm_s.map(|j| j.min(caps.scv_mm_s)),
            max_feedrate_mm_s: self.max_feedrate_mm_s.map(|v| v.min(caps.velocity_mm_s)),
        }
    }

    /// The largest of each cause: the acceleration, jerk and tower feedrate.
    pub fn knobs(&self) -> Toolhead {
        let most = |v: [f64; 3]| v[0].max(v[1]).max(v[2]);
        Toolhead {
            accel_mm_s2: self.print_accel_mm_s2.max(self.travel_accel_mm_s2),
            scv_mm_s: most(self.jerk_mm_s),
            velocity_mm_s: most(self.max_feedrate_mm_s),
        }
    }

    /// The changes that take Marlin from `from` to these settings: only what differs.
    fn changes_from(&self, from: &MarlinLimits) -> Vec<MarlinChange> {
        let differs = |a: f64, b: f64| (a != b).then_some(a);
        let towers = |a: [f64; 3], b: [f64; 3]| {
            let d: [Option<f64>; 3] = std::array::from_fn(|i| differs(a[i], b[i]));
            d.iter()
                .any(Option::is_some)
                .then_some([d[0], d[1], d[2], None])
        };
        let mut out = Vec::new();
        let print = differs(self.print_accel_mm_s2, from.print_accel_mm_s2);
        let travel = differs(self.travel_accel_mm_s2, from.travel_accel_mm_s2);
        if print.is_some() || travel.is_some() {
            out.push(MarlinChange::Accel {
                print,
                retract: None,
                travel,
            });
        }
        if let Some(jerk) = towers(self.jerk_mm_s, from.jerk_mm_s) {
            out.push(MarlinChange::Jerk {
                jerk,
                min_feedrate: None,
                min_travel_feedrate: None,
            });
        }
        if let Some(v) = towers(self.max_feedrate_mm_s, from.max_feedrate_mm_s) {
            out.push(MarlinChange::MaxFeedrate(v));
        }
        out
    }

    /// The commands that set all of them (the recommendation's).
    pub fn all_changes(&self) -> Vec<MarlinChange> {
        let none = MarlinLimits {
            print_accel_mm_s2: f64::NAN,
            travel_accel_mm_s2: f64::NAN,
            jerk_mm_s: [f64::NAN; 3],
            max_feedrate_mm_s: [f64::NAN; 3],
        };
        self.changes_from(&none)
    }
}

/// The limits the tuning changes, as the firmware holds them.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Held {
    Klipper(Toolhead),
    Marlin(MarlinLimits),
}

impl Held {
    /// Each the smaller of itself and its cause's cap.
    pub fn capped(&self, caps: &Toolhead) -> Held {
        match self {
            Held::Klipper(t) => Held::Klipper(t.min(caps)),
            Held::Marlin(m) => Held::Marlin(m.capped(caps)),
        }
    }

    /// Each the larger of the two (of the same firmware; else `self`).
    pub fn max(&self, o: &Held) -> Held {
        match (self, o) {
            (Held::Klipper(a), Held::Klipper(b)) => Held::Klipper(a.max(b)),
            (Held::Marlin(a), Held::Marlin(b)) => {
                let most = |x: [f64; 3], y: [f64; 3]| std::array::from_fn(|i| x[i].max(y[i]));
                Held::Marlin(MarlinLimits {
                    print_accel_mm_s2: a.print_accel_mm_s2.max(b.print_accel_mm_s2),
                    travel_accel_mm_s2: a.travel_accel_mm_s2.max(b.travel_accel_mm_s2),
                    jerk_mm_s: most(a.jerk_mm_s, b.jerk_mm_s),
                    max_feedrate_mm_s: most(a.max_feedrate_mm_s, b.max_feedrate_mm_s),
                })
            }
            _ => *self,
        }
    }

    /// The largest limit of each cause.
    pub fn knobs(&self) -> Toolhead {
        match self {
            Held::Klipper(t) => *t,
            Held::Marlin(m) => m.knobs(),
        }
    }

    /// The limits of each cause that move `m` runs with (before the planner's own caps):
    /// Klipper's velocity also capped by the move's feed; Marlin's M204 P when it extrudes
    /// (`_populate_block`'s choice), T when not.
    pub fn ran(&self, m: &Move) -> Toolhead {
        match self {
            Held::Klipper(t) => {
                let mut limits = *t;
                if m.feed_mm_s > 0.0 {
                    limits.velocity_mm_s = limits.velocity_mm_s.min(m.feed_mm_s);
                }
                limits
            }
            Held::Marlin(l) => Toolhead {
                accel_mm_s2: if m.e_mm != 0.0 {
                    l.print_accel_mm_s2
                } else {
                    l.travel_accel_mm_s2
                },
                ..l.knobs()
            },
        }
    }

    /// The events that take the firmware from `from` to these limits, at `line`.
    pub fn events_from(&self, from: &Held, line: u64) -> Vec<Event> {
        match (self, from) {
            (Held::Klipper(t), Held::Klipper(f)) => vec![Event::Limits {
                line,
                change: t.change_from(f),
            }],
            (Held::Marlin(m), Held::Marlin(f)) => m
                .changes_from(f)
                .into_iter()
                .map(|change| Event::Marlin { line, change })
                .collect(),
            _ => Vec::new(),
        }
    }
}

/// What the file has set, as the firmware reads it: Klipper's limits, or all of Marlin's
/// settings (a change names only some).
#[derive(Clone, Debug, PartialEq)]
pub enum FileLimits {
    Klipper(Toolhead),
    Marlin(Box<Settings>),
}

impl FileLimits {
    /// The profile's, those the firmware starts with.
    pub fn of(machine: &Machine) -> FileLimits {
        match &machine.firmware {
            Firmware::Klipper => FileLimits::Klipper(Toolhead::of(machine)),
            Firmware::Marlin(p) => FileLimits::Marlin(Box::new(Settings::new(p))),
        }
    }

    /// After one of the file's events; whether it changed a setting of this firmware.
    pub fn apply(&mut self, e: &Event) -> bool {
        match (self, e) {
            (FileLimits::Klipper(t), Event::Limits { change, .. }) => {
                t.apply(change);
                true
            }
            (FileLimits::Marlin(s), Event::Marlin { change, .. }) => {
                s.apply(change);
                true
            }
            _ => false,
        }
    }

    /// The limits the tuning changes.
    pub fn held(&self) -> Held {
        match self {
            FileLimits::Klipper(t) => Held::Klipper(*t),
            FileLimits::Marlin(s) => Held::Marlin(MarlinLimits::of(s)),
        }
    }

    /// Sets the limits the tuning changes, the others kept.
    pub fn set(&mut self, h: &Held) {
        match (self, h) {
            (FileLimits::Klipper(t), Held::Klipper(h)) => *t = *h,
            (FileLimits::Marlin(s), Held::Marlin(h)) => h.set_in(s),
            _ => {}
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn marlin_caps_go_to_m204_m205_m203_and_back() {
        let machine = crate::machine::test_support::marlin_machine();
        let mut file = FileLimits::of(&machine);
        // The file's M204 S1500: print and travel.
        assert!(file.apply(&Event::Marlin {
            line: 1,
            change: MarlinChange::Accel {
                print: Some(1500.0),
                retract: None,
                travel: Some(1500.0),
            },
        }));
        let Held::Marlin(m) = file.held() else {
            panic!()
        };
        assert_eq!((m.print_accel_mm_s2, m.jerk_mm_s), (1500.0, [10.0; 3]));
        let caps = Toolhead {
            accel_mm_s2: 1200.0,
            scv_mm_s: 4.0,
            velocity_mm_s: f64::INFINITY,
        };
        let want = file.held().capped(&caps);
        let ev = want.events_from(&file.held(), 7);
        assert_eq!(
            ev,
            [
                Event::Marlin {
                    line: 7,
                    change: MarlinChange::Accel {
                        print: Some(1200.0),
                        retract: None,
                        travel: Some(1200.0)
                    }
                },
                Event::Marlin {
                    line: 7,
                    change: MarlinChange::Jerk {
                        jerk: [Some(4.0), Some(4.0), Some(4.0), None],
                        min_feedrate: None,
                        min_travel_feedrate: None
                    }
                }
            ]
        );
        // The planner's settings after those events are the capped ones; back to the
        // file's by the events the other way.
        let mut fw = file.clone();
        for e in &ev {
            fw.apply(e);
        }
        assert_eq!(fw.held(), want);
        for e in file.held().events_from(&want, 9) {
            fw.apply(&e);
        }
        assert_eq!(fw, file);
        // A travel runs with T, a print move with P; the knobs are the largest.
        assert_eq!(want.knobs().velocity_mm_s, 200.0);
    }
}
