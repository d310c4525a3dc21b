//! The firmware: what a printer's firmware makes of the G-code's events, the commanded
//! motion its steps encode. One module per firmware; each turns the interpreter's events
//! into the commanded motion as pieces ([`Segment`]s), in time order.
//!
//! To add a firmware: a module here with a type implementing [`Firmware`], and a case in
//! [`for_machine`].

pub mod klipper;
pub mod marlin;

use crate::gcode::Event;
use crate::machine::{Firmware as MachineFirmware, Machine};
use crate::motion::Segment;

/// A firmware's motion planning and step generation, as a stream.
pub trait Firmware {
    /// Takes the next event; appends to `commanded` the pieces of the commanded motion
    /// that no later event can change.
    fn push(&mut self, event: &Event, commanded: &mut Vec<Segment>);

    /// The end of the input: appends the rest of the commanded motion (the machine comes
    /// to rest).
    fn finish(&mut self, commanded: &mut Vec<Segment>);
}

/// The firmware the profile names.
pub fn for_machine(machine: &Machine) -> Box<dyn Firmware + Send + '_> {
    match &machine.firmware {
        MachineFirmware::Klipper => Box::new(klipper::Klipper::new(machine)),
        MachineFirmware::Marlin(m) => Box::new(marlin::Marlin::new(
            machine,
            marlin::settings::Settings::new(m),
        )),
    }
}
