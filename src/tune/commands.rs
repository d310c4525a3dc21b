//! The firmware's own commands for a change of the limits, each ending in `; delta-gcode`
//! (so that `fix` and `strip` know them again).

use crate::gcode::LimitChange;
use crate::machine::{Firmware, Machine};

/// Whose commands.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LimitCommands {
    /// `SET_VELOCITY_LIMIT ACCEL= SQUARE_CORNER_VELOCITY= VELOCITY=` (klippy/toolhead.py
    /// `cmd_SET_VELOCITY_LIMIT`).
    Klipper,
    /// `M204 P T` (print and travel acceleration), `M205 X Y Z` (the corner: classic
    /// jerk), `M203 X Y Z` (the towers' feed rates).
    Marlin,
}

/// Every command line ends with this (the emitter's mark of `fix`'s lines).
const MARK: &str = " ; delta-gcode";

impl LimitCommands {
    pub fn of(machine: &Machine) -> LimitCommands {
        match machine.firmware {
            Firmware::Klipper => LimitCommands::Klipper,
            Firmware::Marlin(_) => LimitCommands::Marlin,
        }
    }

    /// The lines that make `change` (nothing for an empty change). Numbers in Rust's
    /// shortest form that reads back as the same value.
    pub fn lines(self, c: &LimitChange) -> Vec<String> {
        let (a, s, v) = (
            c.accel_mm_s2,
            c.square_corner_velocity_mm_s,
            c.velocity_mm_s,
        );
        match self {
            LimitCommands::Klipper => {
                let words: Vec<String> =
                    [("ACCEL", a), ("SQUARE_CORNER_VELOCITY", s), ("VELOCITY", v)]
                        .into_iter()
                        .filter_map(|(k, x)| x.map(|x| format!("{k}={x}")))
                        .collect();
                if words.is_empty() {
                    return Vec::new();
                }
                vec![format!("SET_VELOCITY_LIMIT {}{MARK}", words.join(" "))]
            }
            LimitCommands::Marlin => [
                a.map(|a| format!("M204 P{a} T{a}{MARK}")),
                s.map(|j| format!("M205 X{j} Y{j} Z{j}{MARK}")),
                v.map(|v| format!("M203 X{v} Y{v} Z{v}{MARK}")),
            ]
            .into_iter()
            .flatten()
            .collect(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::emit::{Drop, is_ours};

    #[test]
    fn commands_name_only_what_changes_and_are_ours() {
        let c = LimitChange {
            accel_mm_s2: Some(2200.0),
            velocity_mm_s: Some(150.5),
            ..LimitChange::default()
        };
        let k = LimitCommands::Klipper.lines(&c);
        assert_eq!(
            k,
            ["SET_VELOCITY_LIMIT ACCEL=2200 VELOCITY=150.5 ; delta-gcode"]
        );
        let m = LimitCommands::Marlin.lines(&LimitChange {
            square_corner_velocity_mm_s: Some(4.0),
            ..c
        });
        assert_eq!(
            m,
            [
                "M204 P2200 T2200 ; delta-gcode",
                "M205 X4 Y4 Z4 ; delta-gcode",
                "M203 X150.5 Y150.5 Z150.5 ; delta-gcode"
            ]
        );
        for l in k.iter().chain(&m) {
            assert!(is_ours(l.as_bytes(), true, Drop::All), "{l}");
            assert!(!is_ours(l.as_bytes(), true, Drop::Notes), "{l}");
        }
        assert!(
            LimitCommands::Klipper
                .lines(&LimitChange::default())
                .is_empty()
        );
    }

    #[test]
    fn klipper_reads_the_command_back_as_the_same_change() {
        let c = LimitChange {
            accel_mm_s2: Some(2180.0),
            square_corner_velocity_mm_s: Some(3.7),
            velocity_mm_s: Some(0.1 + 0.2),
            ..LimitChange::default()
        };
        let text = LimitCommands::Klipper.lines(&c).join("\n");
        let mut got = Vec::new();
        crate::gcode::interpret(
            text.as_bytes(),
            crate::path::Vec3::new(0.0, 0.0, 100.0),
            crate::gcode::ArcRules::default(),
            |e| {
                if let crate::gcode::Event::Limits { change, .. } = e {
                    got.push(change);
                }
            },
            |d| panic!("{d:?}"),
        )
        .unwrap();
        assert_eq!(got, [c]);
    }
}
