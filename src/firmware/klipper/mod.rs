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
    /// The planned moves now final (reused).
    planned: Vec<PlannedMove>,
    pieces: PlannedPieces,
    /// The input shaper in force (SET_INPUT_SHAPER changes it), and its stream.
    input_shaper: InputShaper,
    shaper: Shaper,
}

impl Klipper {
    pub fn new(machine: &Machine) -> Self {
        Klipper {
            planner: Planner::new(machine),
            planned: Vec::new(),
            pieces: PlannedPieces::new(),
            input_shaper: machine.input_shaper,
            shaper: Shaper::new(&machine.input_shaper),
        }
    }

    /// The planned moves now final, as pieces through the shaper.
    fn hand_on(&mut self, commanded: &mut Vec<Segment>) {
        for mv in self.planned.drain(..) {
            let shaper = &mut self.shaper;
            self.pieces
                .push(&mv, &mut |seg| shaper.push(seg, &mut |c| commanded.push(c)));
        }
    }
}

impl Firmware for Klipper {
    fn push(&mut self, event: &Event, commanded: &mut Vec<Segment>) {
        self.planner.push(event, &mut self.planned);
        self.hand_on(commanded);
        if let Event::Shaper { change, .. } = event {
            // The Stop before it has flushed the lookahead: the moves after it are shaped
            // with the changed shaper.
            self.input_shaper.apply(change);
            self.shaper.reconfigure(&self.input_shaper);
        }
    }

    fn finish(&mut self, commanded: &mut Vec<Segment>) {
        self.planner.finish(&mut self.planned);
        self.hand_on(commanded);
        self.shaper.finish(&mut |c| commanded.push(c));
    }
}
