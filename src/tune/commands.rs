//! The firmware's own commands for a change of the limits; `fix`'s lines end in
//! `; delta-gcode` (so that `fix` and `strip` know them again).

use crate::gcode::{Event, LimitChange, MarlinChange};

/// Every command line ends with this (the emitter's mark of `fix`'s lines).
const MARK: &str = " ; delta-gcode";

/// The firmware's command that makes a limit change `e`, without the mark: Klipper's
/// `SET_VELOCITY_LIMIT ACCEL= SQUARE_CORNER_VELOCITY= VELOCITY=` (klippy/toolhead.py
/// `cmd_SET_VELOCITY_LIMIT`), Marlin's `M204 P T` (print and travel acceleration),
/// `M205 X Y Z` (the towers' classic jerk), `M203 X Y Z` (the towers' max feedrate), each
/// naming only what it changes (gcode/config/M200-M205.cpp). None for an empty change or
/// another event. Numbers in Rust's shortest form that reads back as the same value.
pub fn command(e: &Event) -> Option<String> {
    let words = |w: &[(&str, Option<f64>)]| -> Vec<String> {
        w.iter()
            .filter_map(|(k, x)| x.map(|x| format!("{k}{x}")))
            .collect()
    };
    let (head, words) = match e {
        Event::Limits { change, .. } => {
            let LimitChange {
                accel_mm_s2: a,
                square_corner_velocity_mm_s: s,
                velocity_mm_s: v,
                ..
            } = *change;
            (
                "SET_VELOCITY_LIMIT",
                words(&[
                    ("ACCEL=", a),
                    ("SQUARE_CORNER_VELOCITY=", s),
                    ("VELOCITY=", v),
                ]),
            )
        }
        Event::Marlin { change, .. } => match *change {
            MarlinChange::Accel {
                print,
                retract,
                travel,
            } => (
                "M204",
                words(&[("P", print), ("R", retract), ("T", travel)]),
            ),
            MarlinChange::Jerk { jerk: j, .. } => (
                "M205",
                words(&[("X", j[0]), ("Y", j[1]), ("Z", j[2]), ("E", j[3])]),
            ),
            MarlinChange::MaxFeedrate(v) => (
                "M203",
                words(&[("X", v[0]), ("Y", v[1]), ("Z", v[2]), ("E", v[3])]),
            ),
            MarlinChange::MaxAccel(_) | MarlinChange::Delta(_) => return None,
        },
        _ => return None,
    };
    (!words.is_empty()).then(|| format!("{head} {}", words.join(" ")))
}

/// The line `fix` adds for `e`: its [`command`] ending in `; delta-gcode`.
pub fn line(e: &Event) -> Option<String> {
    command(e).map(|c| c + MARK)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::emit::{Drop, is_ours};
    use crate::gcode::Dialect;

    fn limits(c: LimitChange) -> Event {
        Event::Limits { line: 1, change: c }
    }

    fn marlin(change: MarlinChange) -> Event {
        Event::Marlin { line: 1, change }
    }

    #[test]
    fn commands_name_only_what_changes_and_are_ours() {
        let c = LimitChange {
            accel_mm_s2: Some(2200.0),
            velocity_mm_s: Some(150.5),
            ..LimitChange::default()
        };
        assert_eq!(
            line(&limits(c)).unwrap(),
            "SET_VELOCITY_LIMIT ACCEL=2200 VELOCITY=150.5 ; delta-gcode"
        );
        let m = [
            marlin(MarlinChange::Accel {
                print: Some(2200.0),
                retract: None,
                travel: Some(1800.0),
            }),
            marlin(MarlinChange::Jerk {
                jerk: [Some(4.0), None, Some(4.5), None],
                min_feedrate: None,
                min_travel_feedrate: None,
            }),
            marlin(MarlinChange::MaxFeedrate([
                Some(150.5),
                Some(150.5),
                Some(150.5),
                None,
            ])),
        ]
        .map(|e| line(&e).unwrap());
        assert_eq!(
            m,
            [
                "M204 P2200 T1800 ; delta-gcode",
                "M205 X4 Z4.5 ; delta-gcode",
                "M203 X150.5 Y150.5 Z150.5 ; delta-gcode"
            ]
        );
        for l in m.iter().chain([&line(&limits(c)).unwrap()]) {
            assert!(is_ours(l.as_bytes(), true, Drop::All), "{l}");
            assert!(!is_ours(l.as_bytes(), true, Drop::Notes), "{l}");
        }
        assert!(line(&limits(LimitChange::default())).is_none());
        assert!(line(&marlin(MarlinChange::MaxFeedrate([None; 4]))).is_none());
    }

    /// The commands read by the interpreter in `dialect`: the events they make.
    fn read_back(events: &[Event], dialect: Dialect) -> Vec<Event> {
        let text: Vec<String> = events.iter().filter_map(line).collect();
        let mut got = Vec::new();
        crate::gcode::interpret(
            text.join("\n").as_bytes(),
            crate::path::Vec3::new(0.0, 0.0, 100.0),
            dialect,
            |e| got.push(e),
            |d| panic!("{d:?}"),
        )
        .unwrap();
        got
    }

    #[test]
    fn each_firmware_reads_the_command_back_as_the_same_change() {
        let c = LimitChange {
            accel_mm_s2: Some(2180.0),
            square_corner_velocity_mm_s: Some(3.7),
            velocity_mm_s: Some(0.1 + 0.2),
            ..LimitChange::default()
        };
        let k = [limits(c)];
        let dialect = Dialect::klipper(crate::gcode::ArcRules::default());
        assert_eq!(read_back(&k, dialect), k);
        let m = [
            marlin(MarlinChange::Accel {
                print: Some(0.1 + 0.2),
                retract: None,
                travel: Some(1234.5),
            }),
            marlin(MarlinChange::Jerk {
                jerk: [Some(3.7), Some(8.0), None, None],
                min_feedrate: None,
                min_travel_feedrate: None,
            }),
            marlin(MarlinChange::MaxFeedrate([
                None,
                Some(99.9),
                Some(200.0),
                None,
            ])),
        ];
        let got = read_back(&m, crate::machine::test_support::marlin_machine().dialect());
        let lines: Vec<u64> = got.iter().map(Event::line).collect();
        assert_eq!(lines, [1, 2, 3]);
        for (g, w) in got.iter().zip(&m) {
            let (Event::Marlin { change: g, .. }, Event::Marlin { change: w, .. }) = (g, w) else {
                panic!("{g:?}")
            };
            assert_eq!(g, w);
        }
    }
}
