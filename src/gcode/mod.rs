//! Reading G-code: a streaming line reader, a per-line nom parser, and the modal
//! interpreter that turns lines into [`Event`]s for the planner.

mod event;

pub use event::{Diagnostic, Event, LimitChange, Move, Severity};
