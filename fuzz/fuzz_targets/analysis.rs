//! Bytes into `analysis::run` with machines/kossel.yaml: no panic, no NaN or infinity in a
//! move's statistics, the print time finite.
#![no_main]

use std::sync::OnceLock;

use delta_gcode::analysis;
use delta_gcode::machine::Machine;
use libfuzzer_sys::fuzz_target;

fn machine() -> &'static Machine {
    static MACHINE: OnceLock<Machine> = OnceLock::new();
    MACHINE.get_or_init(|| {
        let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../machines/kossel.yaml");
        Machine::load(std::path::Path::new(path)).expect("machines/kossel.yaml loads")
    })
}

fuzz_target!(|data: &[u8]| {
    let totals = analysis::run(
        data,
        machine(),
        (),
        |r| {
            let s = &r.stats;
            assert!(s.peak_force_n.iter().all(|f| f.is_finite()), "{s:?}");
            assert!(s.peak_t_s.iter().all(|t| t.is_finite()), "{s:?}");
            assert!(s.worst.iter().all(|w| w.force_n.is_finite() && w.available_n.is_finite()), "{s:?}");
        },
        |d| assert!(d.line >= 1 && d.column >= 1, "{d:?}"),
    )
    .expect("reading from memory cannot fail");
    assert!(totals.print_time_s.is_finite());
});
