//! The recommendation that costs the least print time. Several combinations of limits can
//! make a file pass: a Marlin corner passes with a lower jerk, or with a lower acceleration
//! that leaves the towers less to brake; a Klipper corner with a lower square-corner
//! velocity, or a lower acceleration where the drive's ringing adds to the braking. The
//! physics search ([`search`]) lowers the limit each flagged move points at; here, for each
//! limit it lowered, one more search holds that limit halfway (geometrically) between what
//! it found and the file's own, and lowers only the others, as the physics says (the
//! physics search also overshoots: lowering a limit by the ratio of a move that then
//! rings less often goes further than needed, which the held limit finds back). The
//! quickest combination that passed wins, and the next round starts from it.

use std::path::Path;

use super::search::{Cause, Passed, Rules, search, search_from};
use crate::machine::Machine;

/// Rounds of alternatives, each from the quickest combination so far.
const ROUNDS: usize = 4;
/// Passes an alternative may take (it starts near limits that passed: most pass in one
/// or two; one that does not settle by then is dropped, which bounds the cost).
const PASSES: usize = 4;

/// The quickest passing limits over the whole file, of the physics search's and the
/// alternatives' (see the module documentation), in up to [`ROUNDS`] rounds while one is
/// quicker.
pub fn cheapest(path: &Path, machine: &Machine) -> anyhow::Result<Passed> {
    let first = search(path, machine, false)?;
    let own = first.file_peak.knobs();
    let rules = Rules::of(machine);
    let mut best = first.clone();
    for _ in 0..ROUNDS {
        let from = best.clone();
        for c in Cause::ALL {
            let (found, own) = (c.value(&from.global), c.value(&own));
            // Not lowered (infinite), or not below the file's own: nothing to trade.
            if found >= own {
                continue;
            }
            let held = c.round_down((found * own).sqrt());
            if held <= found {
                continue;
            }
            let mut start = from.global;
            c.set(&mut start, held);
            // A limit at infinity in the floor is not lowered.
            let mut floor = rules.floor;
            c.set(&mut floor, f64::INFINITY);
            // No combination with this limit held: the others stand.
            if let Ok(p) = search_from(
                path,
                machine,
                false,
                start,
                &Rules {
                    floor,
                    max_passes: PASSES,
                    ..rules
                },
            ) && p.print_time_s < best.print_time_s
            {
                best = Passed {
                    first_print_time_s: first.first_print_time_s,
                    passes: best.passes + p.passes,
                    ..p
                };
            }
        }
        if best.print_time_s >= from.print_time_s {
            break;
        }
    }
    Ok(best)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn repo(p: &str) -> std::path::PathBuf {
        Path::new(env!("CARGO_MANIFEST_DIR")).join(p)
    }

    #[test]
    fn a_quicker_combination_than_the_physics_first_one_is_kept() {
        // The Kossel's 12 V motors at 400 mm/s: the physics lowers the velocity alone;
        // a lower acceleration with a higher velocity passes sooner.
        let yaml = std::fs::read_to_string(repo("machines/kossel.yaml")).unwrap();
        let machine = Machine::from_yaml_str(&yaml, "kossel").unwrap();
        let file = repo("samples/over-limit.gcode");
        let physics = search(&file, &machine, false).unwrap();
        let quick = cheapest(&file, &machine).unwrap();
        assert!(
            quick.print_time_s < physics.print_time_s,
            "{} vs {}",
            quick.print_time_s,
            physics.print_time_s
        );
        assert!(quick.global.velocity_mm_s > physics.global.velocity_mm_s);
        assert!(quick.global.accel_mm_s2 < physics.global.accel_mm_s2);
        assert_eq!(quick.first_print_time_s, physics.first_print_time_s);
    }
}
