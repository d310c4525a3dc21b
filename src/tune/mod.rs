//! Limits under which a file passes: the recommendation of `check` (one set of limits for
//! the whole file) and `fix` (the firmware's limit commands around the moves that need
//! them). Both search by the physics of each flagged move, re-plan and re-check the whole
//! file with what they found, and report only limits that passed (`search`).
//!
//! Each pass streams the file again: memory does not grow with its size, except for the
//! caps and the commands `fix` adds (a few per flagged move).

pub mod capacity;
mod cheapest;
mod commands;
mod held;
mod limits;
mod search;

use std::collections::BTreeMap;
use std::path::Path;

pub use held::{Held, MarlinLimits};
pub use limits::{Added, CapEdit, Toolhead};
pub use search::{Cause, FLOOR, MIN_STEP, Over, Passed, TARGET, Unfixable, search, wanted};

use crate::emit::Additions;
use crate::gcode::Event;
use crate::machine::Machine;
use crate::report::{MarlinRecommendation, Recommendation};

/// The limits under which the whole file passes, each the largest of its kind the search
/// found (the file's own where it needs no lower one), with the print time then: Klipper's,
/// or Marlin's M204 P/T, M205 X/Y/Z and M203 X/Y/Z (`held`).
pub fn recommend(path: &Path, machine: &Machine) -> anyhow::Result<Recommendation> {
    Ok(recommendation(&cheapest::cheapest(path, machine)?))
}

fn recommendation(p: &Passed) -> Recommendation {
    let capped = p.file_peak.capped(&p.global);
    let caps = capped.knobs();
    let marlin = match capped {
        Held::Marlin(m) => Some(MarlinRecommendation {
            print_accel_mm_s2: m.print_accel_mm_s2,
            travel_accel_mm_s2: m.travel_accel_mm_s2,
            jerk_mm_s: caps.scv_mm_s,
            max_feedrate_mm_s: caps.velocity_mm_s,
            commands: MarlinLimits {
                jerk_mm_s: [caps.scv_mm_s; 3],
                max_feedrate_mm_s: [caps.velocity_mm_s; 3],
                ..m
            }
            .all_changes()
            .into_iter()
            .filter_map(|change| commands::command(&Event::Marlin { line: 0, change }))
            .collect(),
        }),
        Held::Klipper(_) => None,
    };
    Recommendation {
        max_accel_mm_s2: caps.accel_mm_s2,
        square_corner_velocity_mm_s: caps.scv_mm_s,
        max_velocity_mm_s: caps.velocity_mm_s,
        print_time_s: p.print_time_s,
        marlin,
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
        let global = cheapest::cheapest(path, machine)?;
        let rec = recommendation(&global);
        if local.print_time_s <= global.print_time_s {
            (local, Some(rec), true)
        } else {
            (global, Some(rec), false)
        }
    };
    let mut before: BTreeMap<u64, Vec<String>> = BTreeMap::new();
    let mut commands = 0;
    for a in &chosen.added {
        if let Some(line) = commands::line(&a.event) {
            commands += 1;
            before.entry(a.before_line).or_default().push(line);
        }
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
