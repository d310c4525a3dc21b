//! Limits under which a file passes: the recommendation of `check` (one set of limits for
//! the whole file) and `fix` (the firmware's limit commands around the moves that need
//! them). Both search by the physics of each flagged move, re-plan and re-check the whole
//! file with what they found, and report only limits that passed (`search`).
//!
//! Each pass streams the file again: memory does not grow with its size, except for the
//! caps and the commands `fix` adds (a few per flagged move).

pub mod capacity;
mod commands;
mod limits;
mod search;

use std::collections::BTreeMap;
use std::path::Path;

pub use commands::LimitCommands;
pub use limits::{Added, CapEdit, Toolhead};
pub use search::{Cause, FLOOR, MIN_STEP, Over, Passed, TARGET, Unfixable, search, wanted};

use crate::emit::Additions;
use crate::machine::Machine;
use crate::report::Recommendation;

/// The limits under which the whole file passes, each the largest of its kind the search
/// found (the file's own where it needs no lower one), with the print time then.
/// Not for a Marlin profile yet: the search changes Klipper's limits, which Marlin's
/// planner does not read (its own are M201/M203/M204/M205).
pub fn recommend(path: &Path, machine: &Machine) -> anyhow::Result<Recommendation> {
    if let crate::machine::Firmware::Marlin(_) = machine.firmware {
        anyhow::bail!(
            "no recommendation for a Marlin profile yet (its limits are M201/M203/M204/M205, \
             which the search does not change)"
        );
    }
    let p = search(path, machine, false)?;
    Ok(recommendation(&p))
}

fn recommendation(p: &Passed) -> Recommendation {
    let caps = p.global.min(&p.file_peak);
    Recommendation {
        max_accel_mm_s2: caps.accel_mm_s2,
        square_corner_velocity_mm_s: caps.scv_mm_s,
        max_velocity_mm_s: caps.velocity_mm_s,
        print_time_s: p.print_time_s,
    }
}

/// What `fix` adds to a file, and what it costs.
#[derive(Clone, Debug)]
pub struct FixPlan {
    /// The limit commands, before their moves.
    pub additions: Additions,
    /// Limit commands added.
    pub commands: usize,
    /// Print time of the file as it is, and with the commands, s.
    pub original_print_time_s: f64,
    pub print_time_s: f64,
    /// The limits for the whole file (`check`'s recommendation), None when the file passes.
    pub recommendation: Option<Recommendation>,
    /// Whether the commands cap only ranges of moves (else they cap the whole file as the
    /// recommendation does: it was quicker).
    pub local: bool,
}

/// The commands that make every move of `path` pass: caps on the moves that need them, or
/// the recommendation's limits over the whole file when those print sooner (a file of
/// `fix`'s output is planned without its old commands).
pub fn plan_fix(path: &Path, machine: &Machine) -> anyhow::Result<FixPlan> {
    let local = search(path, machine, true)?;
    let (chosen, recommendation, is_local) = if local.passes == 1 {
        (local, None, true)
    } else {
        let global = search(path, machine, false)?;
        let rec = recommendation(&global);
        if local.print_time_s <= global.print_time_s {
            (local, Some(rec), true)
        } else {
            (global, Some(rec), false)
        }
    };
    let emitter = LimitCommands::of(machine);
    let mut before: BTreeMap<u64, Vec<String>> = BTreeMap::new();
    let mut commands = 0;
    for a in &chosen.added {
        let lines = emitter.lines(&a.change);
        commands += lines.len();
        before.entry(a.before_line).or_default().extend(lines);
    }
    Ok(FixPlan {
        additions: Additions {
            before,
            ..Additions::default()
        },
        commands,
        original_print_time_s: chosen.first_print_time_s,
        print_time_s: chosen.print_time_s,
        recommendation,
        local: is_local,
    })
}
