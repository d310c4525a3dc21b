//! Klipper: its toolhead's lookahead planner ([`planner`], klippy/toolhead.py), the planned
//! trapezoids as pieces, and its input shaper (klippy/chelper/kin_shaper.c). (Klipper's
//! arcs are cut by the interpreter, as its gcode_arcs.py does: `gcode::arc`.)

pub mod planner;

use super::Firmware;
use crate::gcode::Event;
use crate::machine::Machine;
use crate::motion::Segment;
use crate::motion::planned::PlannedPieces;
use crate::motion::shaper::{InputShaper, Shaper};
use planner::{PlannedMove, Planner};

/// Klipper's motion: planned by its toolhead, shaped by its input shaper.
pub struct Klipper {
    planner: Planner,
    pieces: PlannedPieces,
    /// The input shaper in force (SET_INPUT_SHAPER changes it), and its stream.
    input_shaper: InputShaper,
    shaper: Shaper,
}

impl Klipper {
    pub fn new(machine: &Machine) -> Self {
        Klipper {
            planner: Planner::new(machine),
            pieces: PlannedPieces::new(),
            input_shaper: machine.input_shaper,
            shaper: Shaper::new(&machine.input_shaper),
        }
    }

    /// Plans `event` (`None`: the end of the input) and hands the moves now final on as
    /// pieces, through the shaper; without one, as they are (through the shaper's closure,
    /// a call and a copy of each piece: 4.9 % of the firmware thread's instructions). Each
    /// move goes from the planner straight to its pieces (gathered in a vector first, every
    /// move was stored and copied out again: 0.65 % of an unshaped run's instructions).
    fn plan(&mut self, event: Option<&Event>, commanded: &mut Vec<Segment>) {
        let pieces = &mut self.pieces;
        if self.shaper.passes_through() {
            let mut on_move = |mv: PlannedMove| pieces.push(&mv, &mut |seg| commanded.push(seg));
            step(&mut self.planner, event, &mut on_move);
            return;
        }
        let shaper = &mut self.shaper;
        let mut on_move = |mv: PlannedMove| {
            pieces.push(&mv, &mut |seg| shaper.push(seg, &mut |c| commanded.push(c)));
        };
        step(&mut self.planner, event, &mut on_move);
    }
}

/// The planner takes `event`, or finishes at the end of the input (`None`).
fn step(planner: &mut Planner, event: Option<&Event>, out: &mut impl FnMut(PlannedMove)) {
    match event {
        Some(event) => planner.push(event, out),
        None => planner.finish(out),
    }
}

impl Firmware for Klipper {
    fn push(&mut self, event: &Event, commanded: &mut Vec<Segment>) {
        self.plan(Some(event), commanded);
        if let Event::Shaper { change, .. } = event {
            // The Stop before it has flushed the lookahead: the moves after it are shaped
            // with the changed shaper.
            self.input_shaper.apply(change);
            self.shaper.reconfigure(&self.input_shaper);
        }
    }

    fn finish(&mut self, commanded: &mut Vec<Segment>) {
        self.plan(None, commanded);
        self.shaper.finish(&mut |c| commanded.push(c));
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::gcode::interpret;
    use crate::machine::test_support::kossel_machine;
    use crate::motion::shaper::{AxisShaper, ShaperType};
    use crate::path::Vec3;

    /// The commanded pieces of `gcode` on `machine`.
    fn commanded(machine: &Machine, gcode: &str) -> Vec<Segment> {
        let mut klipper = Klipper::new(machine);
        let mut out = Vec::new();
        let home = Vec3::new(0.0, 0.0, machine.geometry.home_z_mm);
        interpret(
            gcode.as_bytes(),
            home,
            machine.dialect(),
            |e| klipper.push(&e, &mut out),
            |_| {},
        )
        .expect("reads");
        klipper.finish(&mut out);
        out
    }

    /// Without a shaper the planned pieces go on as they are; a SET_INPUT_SHAPER then shapes
    /// the moves after it as a profile with that shaper does from the start.
    #[test]
    fn a_shaper_set_in_the_file_shapes_what_follows() {
        let moves = "G1 X10 Y5 F6000\nG1 X-20 Y15\nG1 X5 Y-25\nG1 X0 Y0\n";
        let plain = kossel_machine();
        let mut shaped = kossel_machine();
        let mzv = Some(AxisShaper {
            kind: ShaperType::Mzv,
            freq_hz: 40.0,
            damping_ratio: 0.1,
        });
        (shaped.input_shaper.x, shaped.input_shaper.y) = (mzv, mzv);
        let unshaped = commanded(&plain, moves);
        let set = "SET_INPUT_SHAPER SHAPER_TYPE=MZV SHAPER_FREQ_X=40 SHAPER_FREQ_Y=40 \
                   DAMPING_RATIO_X=0.1 DAMPING_RATIO_Y=0.1\n";
        let later = commanded(&plain, &format!("{set}{moves}"));
        let from_start = commanded(&shaped, &format!("\n{moves}"));
        assert!(unshaped.len() > 4 && later.len() > 2 * unshaped.len());
        assert_eq!(later, from_start);
    }
}
