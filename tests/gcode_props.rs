//! Property tests: arbitrary bytes never panic the parser or the interpreter, events hold
//! only finite numbers, and the emitter gives its input back.

use std::collections::BTreeMap;

use delta_gcode::emit::{emit, strip};
use delta_gcode::gcode::{ArcRules, Event, interpret, parse_line};
use delta_gcode::path::Vec3;
use proptest::prelude::*;

/// Bytes that look like G-code often enough to reach deep into the interpreter.
fn gcode_like() -> impl Strategy<Value = Vec<u8>> {
    let token = prop_oneof![
        Just(b"G1 ".to_vec()),
        Just(b"G0 ".to_vec()),
        Just(b"G2 ".to_vec()),
        Just(b"G3 ".to_vec()),
        Just(b"G91\n".to_vec()),
        Just(b"G90\n".to_vec()),
        Just(b"G92 ".to_vec()),
        Just(b"G20\n".to_vec()),
        Just(b"G28\n".to_vec()),
        Just(b"M83\n".to_vec()),
        Just(b"G10\nG11\n".to_vec()),
        Just(b"M204 ".to_vec()),
        Just(b"M220 ".to_vec()),
        Just(b"SET_VELOCITY_LIMIT ACCEL=".to_vec()),
        Just(b"\r\n".to_vec()),
        Just(b"\n".to_vec()),
        Just(b";".to_vec()),
        "[XYZEIJRFPST]-?[0-9]{0,4}(\\.[0-9]{0,3})? ".prop_map(String::into_bytes),
        "[XYZEIJR]99999999[0-9] ".prop_map(String::into_bytes),
        proptest::collection::vec(any::<u8>(), 0..6),
    ];
    proptest::collection::vec(token, 0..60).prop_map(|v| v.concat())
}

fn finite_event(e: &Event) -> bool {
    match e {
        Event::Move(m) => {
            let path_ok = (m.path.start.iter().chain(m.path.end.iter())).all(|v| v.is_finite());
            path_ok
                && m.e_mm.is_finite()
                && m.feed_mm_s.is_finite()
                && m.feed_mm_s > 0.0
                && m.path.length_mm().is_finite()
        }
        Event::Stop { dwell_s, .. } => dwell_s.is_finite() && *dwell_s >= 0.0,
        Event::Limits { change, .. } => [
            change.velocity_mm_s,
            change.accel_mm_s2,
            change.square_corner_velocity_mm_s,
            change.minimum_cruise_ratio,
        ]
        .iter()
        .flatten()
        .all(|v| v.is_finite() && *v >= 0.0),
        Event::Shaper { change, .. } => change
            .freq_hz
            .iter()
            .chain(&change.damping_ratio)
            .flatten()
            .all(|v| v.is_finite() && *v >= 0.0),
        // Every number of a Marlin setting is finite (the Debug form shows NaN and inf).
        Event::Marlin { change, .. } => {
            let text = format!("{change:?}");
            !text.contains("NaN") && !text.contains("inf")
        }
    }
}

fn check_reading(data: &[u8]) {
    for l in data.split(|&b| b == b'\n') {
        let p = parse_line(l);
        for w in p.words() {
            assert!(w.value.is_none_or(f64::is_finite));
        }
    }
    let mut bad = Vec::new();
    let mut last_line = 0;
    let stats = interpret(
        data,
        Vec3::new(0.0, 0.0, 250.0),
        ArcRules::default(),
        |e| {
            if !finite_event(&e) {
                bad.push(e);
            }
        },
        |d| {
            assert!(d.line >= last_line && d.line >= 1 && d.column >= 1);
            last_line = d.line;
        },
    )
    .unwrap();
    assert!(bad.is_empty(), "{bad:?}");
    assert_eq!(stats.bytes, data.len() as u64);
}

fn round_trip(data: &[u8]) {
    let mut out = Vec::new();
    emit(data, &mut out, &BTreeMap::new(), &[]).unwrap();
    assert_eq!(out, data);
    let mut ann = BTreeMap::new();
    for n in [1u64, 2, 5, 9] {
        ann.insert(n, vec![format!("; delta-gcode: at {n}")]);
    }
    let summary = vec![
        "; delta-gcode: end".to_string(),
        "; delta-gcode".to_string(),
    ];
    let mut annotated = Vec::new();
    emit(data, &mut annotated, &ann, &summary).unwrap();
    let mut back = Vec::new();
    strip(&annotated[..], &mut back).unwrap();
    assert_eq!(back, data);
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(512))]

    #[test]
    fn arbitrary_bytes_read_safely(data in proptest::collection::vec(any::<u8>(), 0..400)) {
        check_reading(&data);
    }

    #[test]
    fn gcode_like_bytes_read_safely(data in gcode_like()) {
        check_reading(&data);
    }

    #[test]
    fn emit_reproduces_and_strip_inverts(data in proptest::collection::vec(any::<u8>(), 0..400)) {
        round_trip(&data);
    }

    #[test]
    fn emit_round_trips_gcode_like(data in gcode_like()) {
        round_trip(&data);
    }
}
