//! The real slicer files of `/work/shared/corpus`, decompressed to `/tmp` (too big for the
//! repository): no error diagnostics, counts and throughput printed. Ignored by default;
//! run with `cargo test --release --test gcode_corpus -- --ignored --nocapture`.

use std::collections::BTreeMap;
use std::fs::File;
use std::time::Instant;

use delta_gcode::gcode::{ArcRules, Event, Severity, interpret};
use delta_gcode::path::Vec3;

const FILES: [&str; 4] = [
    "/tmp/ps25_delta170_marlin2_bunny-big.gcode",
    "/tmp/ps25_flsun-q5-vendor_marlin_calib-cube.gcode",
    "/tmp/ps29_delta170_klipper_arcs_3objects-exclude.gcode",
    "/tmp/cura413_kossel-mini_marlin_calib-cube.gcode",
];

#[test]
#[ignore = "needs the decompressed corpus in /tmp"]
fn corpus_reads_without_errors() {
    for f in FILES {
        let Ok(file) = File::open(f) else {
            eprintln!("{f}: missing, skipped");
            continue;
        };
        let mut warnings: BTreeMap<String, (u64, u64)> = BTreeMap::new();
        let mut errors = Vec::new();
        let mut bad_numbers = 0u64;
        let t0 = Instant::now();
        let stats = interpret(
            std::io::BufReader::new(file),
            Vec3::new(0.0, 0.0, 290.0),
            ArcRules::default(),
            |e| {
                if let Event::Move(m) = e {
                    let p = m.path;
                    if !(p
                        .start()
                        .iter()
                        .chain(p.end().iter())
                        .all(|v| v.is_finite())
                        && m.e_mm.is_finite()
                        && m.feed_mm_s.is_finite()
                        && m.feed_mm_s > 0.0)
                    {
                        bad_numbers += 1;
                    }
                }
            },
            |d| match d.severity {
                Severity::Error => errors.push(d),
                Severity::Warning => {
                    let key: String = d.message.chars().take(40).collect();
                    let w = warnings.entry(key).or_insert((0, d.line));
                    w.0 += 1;
                }
            },
        )
        .unwrap();
        let dt = t0.elapsed().as_secs_f64();
        eprintln!(
            "{f}: {stats:?}\n  {:.1} MB/s; warnings by kind (count, first line): {warnings:?}",
            stats.bytes as f64 / dt / 1e6
        );
        // Throughput of `interpret` alone: the file in memory, events only counted.
        let data = std::fs::read(f).unwrap();
        let t0 = Instant::now();
        let mut n = 0u64;
        interpret(
            &data[..],
            Vec3::new(0.0, 0.0, 290.0),
            ArcRules::default(),
            |_| n += 1,
            |_| {},
        )
        .unwrap();
        let dt = t0.elapsed().as_secs_f64();
        eprintln!(
            "  interpret from memory: {n} events, {:.3} s, {:.1} MB/s",
            dt,
            data.len() as f64 / dt / 1e6
        );
        assert!(errors.is_empty(), "{f}: {errors:#?}");
        assert_eq!(bad_numbers, 0);
        assert!(stats.moves > 1000);
    }
}
