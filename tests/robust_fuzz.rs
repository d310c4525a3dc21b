//! Robustness property tests: arbitrary bytes, G-code-like tokens and mutated real slicer
//! output through the parser, the interpreter, the planner and the whole pipeline
//! (`analysis::run` with machines/kossel.yaml). No panic, and no NaN or infinity in any
//! event, planned move, per-move statistic, trace row or JSON report number.
//!
//! Each case is bounded so that it runs in milliseconds: inputs of at most a few KiB, and a
//! case whose planned print time exceeds [`MAX_PRINT_TIME_S`] is planned (checked) but not
//! sampled: a slow feed, a tiny M220 factor, G2/G3 with many extra turns or a move of 1e9 mm
//! makes the model sample for hours. Those are the known hangs of docs/robustness.md,
//! pinned by the ignored tests of tests/robust_gcode.rs.

use std::collections::BTreeMap;

use delta_gcode::analysis::{self, MoveResult, TraceRows, Window};
use delta_gcode::emit::{emit, strip};
use delta_gcode::firmware::klipper::planner::{PlannedMove, Planner};
use delta_gcode::gcode::{ArcRules, Event, LimitChange, Move, interpret};
use delta_gcode::machine::Machine;
use delta_gcode::path::{Path, Vec3};
use delta_gcode::report::{MoveStats, Problem, Report, write_json};
use proptest::prelude::*;

fn kossel() -> Machine {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("machines/kossel.yaml");
    Machine::load(&path).expect("machines/kossel.yaml loads")
}

/// Real slicer output, each file as its lines (terminators kept).
fn fixture_lines() -> Vec<Vec<u8>> {
    const FILES: [&[u8]; 4] = [
        include_bytes!("fixtures/cura413_header.gcode"),
        include_bytes!("fixtures/flsun_q5_start.gcode"),
        include_bytes!("fixtures/ps25_bunny_head.gcode"),
        include_bytes!("fixtures/ps29_arcs_exclude.gcode"),
    ];
    FILES
        .iter()
        .flat_map(|f| f.split_inclusive(|&b| b == b'\n'))
        .map(<[u8]>::to_vec)
        .collect()
}

/// Longest planned print time of a case, s: at 1 ms per sample, at most 600 000 samples.
const MAX_PRINT_TIME_S: f64 = 600.0;

// ---- Finiteness checks ----------------------------------------------------------------

fn finite(v: &[f64]) -> bool {
    v.iter().all(|x| x.is_finite())
}

fn finite_path(p: &Path) -> bool {
    finite(p.start.as_slice()) && finite(p.end.as_slice())
}

fn check_event(e: &Event) {
    match e {
        Event::Move(m) => {
            assert!(finite_path(&m.path), "{e:?}");
            assert!(finite(&[m.e_mm, m.feed_mm_s, m.path.length_mm()]), "{e:?}");
            assert!(m.feed_mm_s > 0.0, "{e:?}");
        }
        Event::Stop { dwell_s, .. } => assert!(dwell_s.is_finite() && *dwell_s >= 0.0),
        Event::Limits { change, .. } => {
            let c = change;
            for v in [
                c.velocity_mm_s,
                c.accel_mm_s2,
                c.square_corner_velocity_mm_s,
                c.minimum_cruise_ratio,
            ]
            .into_iter()
            .flatten()
            {
                assert!(v.is_finite() && v >= 0.0, "{e:?}");
            }
        }
        Event::Shaper { change, .. } => {
            let c = change;
            for v in c.freq_hz.into_iter().chain(c.damping_ratio).flatten() {
                assert!(v.is_finite() && v >= 0.0, "{e:?}");
            }
        }
        // Every number of a Marlin setting is finite (the Debug form shows NaN and inf).
        Event::Marlin { change, .. } => {
            let text = format!("{change:?}");
            assert!(!text.contains("NaN") && !text.contains("inf"), "{e:?}");
        }
    }
}

fn check_planned(m: &PlannedMove) {
    assert!(finite_path(&m.path), "{m:?}");
    let numbers = [
        m.e_mm,
        m.distance_mm,
        m.start_v_mm_s,
        m.cruise_v_mm_s,
        m.end_v_mm_s,
        m.accel_mm_s2,
        m.accel_t_s,
        m.cruise_t_s,
        m.decel_t_s,
        m.t0_s,
    ];
    assert!(finite(&numbers), "{m:?}");
    for v in &numbers[1..] {
        assert!(*v >= 0.0, "{m:?}");
    }
    assert!(m.distance_mm > 0.0, "{m:?}");
    assert!(
        m.start_v_mm_s <= m.cruise_v_mm_s * (1.0 + 1e-9) + 1e-9,
        "{m:?}"
    );
    assert!(
        m.end_v_mm_s <= m.cruise_v_mm_s * (1.0 + 1e-9) + 1e-9,
        "{m:?}"
    );
}

fn check_stats(s: &MoveStats) {
    assert!(finite(&s.peak_force_n), "{s:?}");
    assert!(finite(&s.peak_t_s), "{s:?}");
    assert!(
        s.worst
            .iter()
            .all(|w| w.force_n.is_finite() && w.available_n.is_finite()),
        "{s:?}"
    );
    match s.checks.problem.as_deref() {
        None => {}
        Some(Problem::Unreachable { t_s, pos_mm, .. }) => {
            assert!(t_s.is_finite() && finite(pos_mm), "{s:?}")
        }
        Some(Problem::AboveHome { t_s, over_mm, .. }) => {
            assert!(t_s.is_finite() && over_mm.is_finite(), "{s:?}")
        }
        Some(Problem::OutsideRadius {
            radius_mm,
            limit_mm,
        }) => assert!(radius_mm.is_finite() && limit_mm.is_finite(), "{s:?}"),
        Some(Problem::BelowBed { z_mm }) => assert!(z_mm.is_finite(), "{s:?}"),
        Some(Problem::NotSampled { duration_s }) => assert!(duration_s.is_finite(), "{s:?}"),
    }
    if let Some((_, ratio)) = s.checks.near_singular {
        assert!(ratio > 0.0 && !ratio.is_nan(), "{s:?}");
    }
}

/// Every number of a JSON value is finite and nothing is null (serde_json writes a NaN as
/// null).
fn check_json(v: &serde_json::Value, at: &str) {
    match v {
        serde_json::Value::Null => panic!("null at {at}"),
        serde_json::Value::Number(n) => {
            assert!(n.as_f64().is_some_and(f64::is_finite), "{n} at {at}")
        }
        serde_json::Value::Array(a) => a
            .iter()
            .enumerate()
            .for_each(|(i, x)| check_json(x, &format!("{at}[{i}]"))),
        serde_json::Value::Object(o) => o
            .iter()
            .for_each(|(k, x)| check_json(x, &format!("{at}.{k}"))),
        _ => {}
    }
}

/// The planner alone over the events of `data`: every planned move finite. Returns the
/// number of lines with moves (a line's arc chords are one) and the print time.
fn check_planner(data: &[u8], machine: &Machine) -> (usize, f64) {
    let mut planner = Planner::new(machine);
    let mut out = Vec::new();
    let home = Vec3::new(0.0, 0.0, machine.geometry.home_z_mm);
    let mut move_lines = Vec::new();
    interpret(
        data,
        home,
        ArcRules::default(),
        |e| {
            check_event(&e);
            if let Event::Move(m) = &e {
                move_lines.push(m.line);
            }
            planner.push(&e, &mut |m| out.push(m));
        },
        |_| {},
    )
    .expect("reading from memory cannot fail");
    planner.finish(&mut |m| out.push(m));
    out.iter().for_each(check_planned);
    let time_s = planner.print_time_s();
    assert!(time_s.is_finite() && time_s >= 0.0);
    move_lines.dedup();
    (move_lines.len(), time_s)
}

/// The whole pipeline over `data`, with the trace when `trace`: per-move statistics, the
/// trace rows and the JSON report all finite. A case planned longer than
/// [`MAX_PRINT_TIME_S`] is only planned.
fn check_pipeline(data: &[u8], machine: &Machine, trace: bool) {
    let (planned, time_s) = check_planner(data, machine);
    if time_s > MAX_PRINT_TIME_S {
        return;
    }
    let mut report = Report::new(
        "fuzz.gcode",
        &machine.name,
        machine.motors.max_force_n,
        true,
    );
    let mut diags = Vec::new();
    let mut moves = 0;
    // The verdict alone, or with the trace rows and a plot window as well.
    let observer = trace.then_some((
        TraceRows::new(&machine.motors),
        Window {
            from_s: 0.0,
            to_s: 1.0,
        },
    ));
    let columns = analysis::trace_header().split(',').count();
    let totals = analysis::run(
        data,
        machine,
        observer,
        |r: &mut MoveResult<Option<(Vec<u8>, _)>>| {
            moves += 1;
            check_stats(&r.stats);
            report.add_move(&r.stats);
            let rows = r.observed.as_ref().map_or(&[][..], |(rows, _)| rows);
            for row in String::from_utf8_lossy(rows).lines() {
                let fields: Vec<&str> = row.split(',').collect();
                assert_eq!(fields.len(), columns, "{row}");
                for f in fields {
                    let v: f64 = f.parse().unwrap_or(f64::NAN);
                    assert!(v.is_finite(), "{row}");
                }
            }
        },
        |d| diags.push(d),
    )
    .expect("reading from memory cannot fail");
    assert_eq!(moves, planned, "every line with moves is evaluated once");
    assert!(totals.print_time_s.is_finite() && totals.print_time_s >= 0.0);
    assert_eq!(totals.read.bytes, data.len() as u64);
    for d in &diags {
        assert!(d.line >= 1 && d.column >= 1, "{d:?}");
        report.add_diagnostic(d);
    }
    report.summary.lines = totals.read.lines;
    report.summary.print_time_s = totals.print_time_s;
    let mut json = Vec::new();
    write_json(&mut json, std::slice::from_ref(&report)).expect("JSON to memory");
    let v: serde_json::Value = serde_json::from_slice(&json).expect("valid JSON");
    check_json(&v, "report");
}

// ---- Generators -------------------------------------------------------------------------

/// Bytes that look like G-code often enough to reach deep into the interpreter and planner.
fn gcode_like() -> impl Strategy<Value = Vec<u8>> {
    let token = prop_oneof![
        4 => Just(b"\nG1 ".to_vec()),
        1 => Just(b"\nG0 ".to_vec()),
        1 => Just(b"\nG2 ".to_vec()),
        1 => Just(b"\nG3 ".to_vec()),
        1 => Just(b"\nG91\n".to_vec()),
        1 => Just(b"\nG90\n".to_vec()),
        1 => Just(b"\nG92 ".to_vec()),
        1 => Just(b"\nG20\n".to_vec()),
        1 => Just(b"\nG21\n".to_vec()),
        1 => Just(b"\nG28\n".to_vec()),
        1 => Just(b"\nG4 ".to_vec()),
        1 => Just(b"\nM83\n".to_vec()),
        1 => Just(b"\nG10\nG11\n".to_vec()),
        1 => Just(b"\nM204 ".to_vec()),
        1 => Just(b"\nM220 ".to_vec()),
        1 => Just(b"\nM400\n".to_vec()),
        1 => Just(b"\nSET_VELOCITY_LIMIT ACCEL=".to_vec()),
        1 => Just(b"\nSET_VELOCITY_LIMIT SQUARE_CORNER_VELOCITY=".to_vec()),
        1 => Just(b"\nSET_VELOCITY_LIMIT MINIMUM_CRUISE_RATIO=".to_vec()),
        1 => Just(b"\r\n".to_vec()),
        1 => Just(b";".to_vec()),
        8 => "[XYZEIJRFPST]-?[0-9]{0,3}(\\.[0-9]{0,3})? ".prop_map(String::into_bytes),
        1 => "[0-9]{1,4}(\\.[0-9]{1,3})?".prop_map(String::into_bytes),
        1 => proptest::collection::vec(any::<u8>(), 0..6),
    ];
    proptest::collection::vec(token, 0..80).prop_map(|v| v.concat())
}

/// One edit of a real G-code window.
#[derive(Clone, Debug)]
enum Mutation {
    /// Overwrite the byte at (position modulo length).
    Byte(usize, u8),
    /// Insert a piece of text at a position.
    Insert(usize, &'static [u8]),
    /// Delete up to `n` bytes from a position.
    Delete(usize, usize),
    /// Repeat the line containing a position.
    DuplicateLine(usize),
    /// Replace the number after the n-th letter with another value.
    Number(usize, &'static [u8]),
}

const PIECES: [&[u8]; 26] = [
    b"-",
    b".",
    b"9",
    b"e",
    b"E",
    b" ",
    b"\n",
    b"\r",
    b"\0",
    b"*",
    b";",
    b"(",
    b")",
    b"G2 ",
    b"G3 ",
    b"G91\n",
    b"G20\n",
    b"M83\n",
    b"G92 X0\n",
    b"G28\n",
    b"F0 ",
    b"F-1 ",
    b"M204 S0\n",
    b"R-7 ",
    b"\xff\xfe",
    b"X",
];

const VALUES: [&[u8]; 16] = [
    b"0",
    b"-0",
    b"-1",
    b"0.0001",
    b"-.5",
    b".",
    b"-",
    b"1e5",
    b"-1999",
    b"123.4.5",
    b"9999999999",
    b"1e-9",
    b"60",
    b"30000",
    b"3.14159",
    b"",
];

fn mutation() -> impl Strategy<Value = Mutation> {
    prop_oneof![
        1 => (any::<usize>(), any::<u8>()).prop_map(|(p, b)| Mutation::Byte(p, b)),
        1 => (any::<usize>(), 0..PIECES.len()).prop_map(|(p, i)| Mutation::Insert(p, PIECES[i])),
        1 => (any::<usize>(), 1..12usize).prop_map(|(p, n)| Mutation::Delete(p, n)),
        1 => any::<usize>().prop_map(Mutation::DuplicateLine),
        3 => (any::<usize>(), 0..VALUES.len()).prop_map(|(p, i)| Mutation::Number(p, VALUES[i])),
    ]
}

fn apply(data: &mut Vec<u8>, m: &Mutation) {
    if data.is_empty() {
        return;
    }
    let at = |p: usize| p % data.len();
    match *m {
        Mutation::Byte(p, b) => {
            let i = at(p);
            data[i] = b;
        }
        Mutation::Insert(p, piece) => {
            let i = at(p);
            data.splice(i..i, piece.iter().copied());
        }
        Mutation::Delete(p, n) => {
            let i = at(p);
            let end = (i + n).min(data.len());
            data.drain(i..end);
        }
        Mutation::DuplicateLine(p) => {
            let i = at(p);
            let start = data[..i]
                .iter()
                .rposition(|&b| b == b'\n')
                .map_or(0, |s| s + 1);
            let end = data[i..]
                .iter()
                .position(|&b| b == b'\n')
                .map_or(data.len(), |e| i + e + 1);
            let line = data[start..end].to_vec();
            data.splice(end..end, line);
        }
        Mutation::Number(n, value) => {
            // The n-th (modulo their count) letter followed by a number.
            let starts: Vec<usize> = (1..data.len())
                .filter(|&i| {
                    data[i - 1].is_ascii_uppercase()
                        && (data[i].is_ascii_digit() || data[i] == b'-' || data[i] == b'.')
                })
                .collect();
            if starts.is_empty() {
                return;
            }
            let s = starts[n % starts.len()];
            let len = data[s..]
                .iter()
                .position(|&b| !(b.is_ascii_digit() || b == b'-' || b == b'.'))
                .unwrap_or(data.len() - s);
            data.splice(s..s + len, value.iter().copied());
        }
    }
}

/// A window of 10 to 60 lines of real slicer output, after a homing and a drop to the bed,
/// with up to 6 mutations.
fn mutated_real() -> impl Strategy<Value = Vec<u8>> {
    let lines = fixture_lines();
    let n = lines.len();
    (
        0..n,
        10..60usize,
        proptest::collection::vec(mutation(), 0..6),
    )
        .prop_map(move |(start, len, muts)| {
            let mut data = b"G28\nG1 Z5 F6000\n".to_vec();
            for l in &lines[start..(start + len).min(n)] {
                data.extend_from_slice(l);
            }
            for m in &muts {
                apply(&mut data, m);
            }
            data
        })
}

/// A planner event with any numbers: finite, huge, tiny, negative, NaN, infinite.
fn any_number() -> impl Strategy<Value = f64> {
    prop_oneof![
        4 => -200.0..200.0f64,
        1 => Just(0.0),
        1 => Just(-0.0),
        1 => Just(1e-300),
        1 => Just(1e300),
        1 => Just(-1e300),
        1 => Just(f64::NAN),
        1 => Just(f64::INFINITY),
        1 => Just(f64::NEG_INFINITY),
        1 => Just(f64::MIN_POSITIVE),
        1 => any::<f64>(),
    ]
}

fn any_event() -> impl Strategy<Value = Event> {
    let v3 = || (any_number(), any_number(), any_number()).prop_map(|(x, y, z)| Vec3::new(x, y, z));
    let line = (v3(), v3()).prop_map(|(a, b)| Path::line(a, b));
    let opt = || proptest::option::of(any_number());
    prop_oneof![
        6 => (line, any_number(), any_number(), 1..1000u64).prop_map(
            |(path, e_mm, feed_mm_s, line)| Event::Move(Move { line, path, e_mm, feed_mm_s, offset_mm: Vec3::zeros(), arc: None })
        ),
        1 => (any_number(), 1..1000u64).prop_map(|(dwell_s, line)| Event::Stop { line, dwell_s }),
        1 => (opt(), opt(), opt(), opt(), opt(), 1..1000u64).prop_map(|(v, a, s, m, a2d, line)| Event::Limits {
            line,
            change: LimitChange {
                velocity_mm_s: v,
                accel_mm_s2: a,
                square_corner_velocity_mm_s: s,
                minimum_cruise_ratio: m,
                accel_to_decel_mm_s2: a2d,
            },
        }),
    ]
}

// ---- The properties ------------------------------------------------------------------

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    #[test]
    fn pipeline_survives_arbitrary_bytes(data in proptest::collection::vec(any::<u8>(), 0..2000)) {
        check_pipeline(&data, &kossel(), false);
    }

    #[test]
    fn pipeline_survives_gcode_like_tokens(data in gcode_like()) {
        check_pipeline(&data, &kossel(), false);
    }

    #[test]
    fn pipeline_survives_mutated_slicer_output(data in mutated_real()) {
        check_pipeline(&data, &kossel(), true);
        // The emitter still gives every byte back, annotated or not.
        let mut out = Vec::new();
        emit(&data[..], &mut out, &BTreeMap::new(), &[]).unwrap();
        prop_assert_eq!(&out, &data);
        let notes = BTreeMap::from([(3u64, vec!["; delta-gcode: x".to_string()])]);
        let mut annotated = Vec::new();
        emit(&data[..], &mut annotated, &notes, &["; delta-gcode: end".to_string()]).unwrap();
        let mut back = Vec::new();
        strip(&annotated[..], &mut back).unwrap();
        prop_assert_eq!(back, data);
    }

    /// The planner fed events directly, with numbers the interpreter never sends (NaN,
    /// infinities, 1e300): it drops what it cannot plan and plans the rest finitely.
    #[test]
    fn planner_survives_any_numbers(events in proptest::collection::vec(any_event(), 0..40)) {
        let machine = kossel();
        let mut planner = Planner::new(&machine);
        let mut out = Vec::new();
        for e in events {
            planner.push(&e, &mut |m| out.push(m));
        }
        planner.finish(&mut |m| out.push(m));
        out.iter().for_each(check_planned);
        prop_assert!(planner.print_time_s().is_finite());
    }
}
