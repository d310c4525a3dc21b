//! The modal interpreter against hand-computed positions, speeds and limits.

use std::f64::consts::{FRAC_PI_2, PI, TAU};

use delta_gcode::gcode::{ArcRules, Diagnostic, Event, LimitChange, Move, Severity, interpret};
use delta_gcode::path::Vec3;

const HOME: [f64; 3] = [0.0, 0.0, 290.0];

fn run(src: &str) -> (Vec<Event>, Vec<Diagnostic>) {
    let mut events = Vec::new();
    let mut diags = Vec::new();
    let stats = interpret(
        src.as_bytes(),
        Vec3::from(HOME),
        ArcRules::default(),
        |e| events.push(e),
        |d| diags.push(d),
    )
    .unwrap();
    assert_eq!(stats.bytes, src.len() as u64);
    (events, diags)
}

fn moves(events: &[Event]) -> Vec<Move> {
    events
        .iter()
        .filter_map(|e| match e {
            Event::Move(m) => Some(*m),
            _ => None,
        })
        .collect()
}

fn v(x: f64, y: f64, z: f64) -> Vec3 {
    Vec3::new(x, y, z)
}

fn line(m: &Move) -> (Vec3, Vec3) {
    (m.path.start, m.path.end)
}

#[test]
fn starts_at_home_and_g28_returns_there() {
    let (ev, d) = run("G1 X10 F600\nG28\nG1 Y5\n");
    assert!(d.is_empty());
    let m = moves(&ev);
    assert_eq!(line(&m[0]), (v(0.0, 0.0, 290.0), v(10.0, 0.0, 290.0)));
    assert_eq!(m[0].feed_mm_s, 10.0);
    assert_eq!(
        ev[1],
        Event::Stop {
            line: 2,
            dwell_s: 0.0
        }
    );
    assert_eq!(line(&m[1]), (v(0.0, 0.0, 290.0), v(0.0, 5.0, 290.0)));
    assert_eq!(m[1].line, 3);
}

#[test]
fn default_feed_is_klippers_25_mm_s_and_m220_scales_it() {
    let (ev, _) = run("G1 X1\nM220 S50\nG1 X2\nG1 X3 F1200\nM220\nG1 X4\n");
    let f: Vec<f64> = moves(&ev).iter().map(|m| m.feed_mm_s).collect();
    assert_eq!(f, vec![25.0, 12.5, 10.0, 20.0]);
}

#[test]
fn relative_modes_and_g92() {
    // M83 relative E under G90; G91 makes E relative too; G92 shifts coordinates.
    let src = "G28\nG1 X10 Y0 Z1 E1\nG1 E3\nM83\nG1 E0.5\nM82\nG91\nG1 X1 E0.25\nG90\n\
               G92 X0 E0\nG1 X5 E2\nG92\nG1 Z0\n";
    let (ev, d) = run(src);
    assert!(d.is_empty(), "{d:?}");
    let m = moves(&ev);
    let e: Vec<f64> = m.iter().map(|m| m.e_mm).collect();
    assert_eq!(e, vec![1.0, 2.0, 0.5, 0.25, 2.0]);
    assert_eq!(line(&m[3]), (v(10.0, 0.0, 1.0), v(11.0, 0.0, 1.0)));
    // After G92 X0 at machine X 11, X5 is machine 16.
    assert_eq!(line(&m[4]).1, v(16.0, 0.0, 1.0));
    // G92 alone zeroes every axis at the current place: Z0 is no move, no event.
    assert_eq!(m.len(), 5);
    // E-only moves are zero-length lines where the nozzle is.
    assert_eq!(line(&m[1]), (v(10.0, 0.0, 1.0), v(10.0, 0.0, 1.0)));
}

#[test]
fn inches() {
    let (ev, _) = run("G28\nG20\nG1 X1 E0.1 F10\nG21\nG1 X1\n");
    let m = moves(&ev);
    assert!((line(&m[0]).1.x - 25.4).abs() < 1e-12);
    assert!((m[0].e_mm - 2.54).abs() < 1e-12);
    assert!((m[0].feed_mm_s - 254.0 / 60.0).abs() < 1e-12);
    assert_eq!(line(&m[1]).1.x, 1.0);
}

#[test]
fn zero_length_moves_without_e_give_nothing() {
    let (ev, d) = run("G28\nG1 X0 Y0\nG1 F3000\nG0\n");
    assert!(d.is_empty());
    assert_eq!(ev.len(), 1);
}

#[test]
fn flsun_helix_start() {
    // The FLSUN Q5 vendor start code: a quarter turn round the bed centre, E 40, cut as
    // Klipper does into ⌊98·π/2⌋ = 153 chords of 1.006 mm.
    let (ev, d) = run("G28\nM83\nG1 X-98 Y0 Z0.2 F4000\nG3 X0 Y-98 I98 Z0.2 E40 F400\n");
    assert!(d.is_empty());
    let m = moves(&ev);
    let chords = &m[1..];
    assert_eq!(chords.len(), 153);
    let step = FRAC_PI_2 / 153.0;
    for (i, c) in chords.iter().enumerate() {
        let th = PI + step * (i + 1) as f64;
        let want = v(98.0 * th.cos(), 98.0 * th.sin(), 0.2);
        assert!((c.path.end - want).norm() < 1e-9, "chord {i}");
        assert_eq!(c.line, 4);
        assert!((c.feed_mm_s - 400.0 / 60.0).abs() < 1e-12);
        assert!((c.e_mm - 40.0 / 153.0).abs() < 1e-12);
    }
    assert_eq!(chords[152].path.end, v(0.0, -98.0, 0.2));
}

#[test]
fn helix_with_z_rise_and_full_circles() {
    let (ev, d) = run("G28\nG1 X10 Y0 Z0\nG2 I-10 Z2\nG3 X10 Y0 I-10 J0 Z3\n");
    assert!(d.is_empty(), "{d:?}");
    let m = moves(&ev);
    // Clockwise full circle rising 2 mm: √((2π·10)² + 2²) = 62.86 mm, 62 chords; then the
    // counter-clockwise one rising 1 mm: 62.84 mm, 62 chords.
    assert_eq!(m.len(), 1 + 62 + 62);
    let first = &m[1..63];
    for (i, c) in first.iter().enumerate() {
        let th = -TAU * (i + 1) as f64 / 62.0;
        let want = v(
            10.0 * th.cos(),
            10.0 * th.sin(),
            2.0 * (i + 1) as f64 / 62.0,
        );
        assert!(
            (c.path.end - want).norm() < 1e-9,
            "chord {i}: {}",
            c.path.end
        );
    }
    // The second turns the other way: its first chord ends above the X axis.
    assert!(m[63].path.end.y > 0.0 && m[63].path.end.z > 2.0);
    assert_eq!(m[124].path.end, v(10.0, 0.0, 3.0));
}

#[test]
fn arc_planes_follow_g17_g18_g19() {
    // G18: the XZ plane, centre from I and K, Y linear. From (0, 0, 10) round (0, _, 5).
    let (ev, d) = run("G28\nG1 X0 Y0 Z10\nG18\nG2 X5 Y2 Z5 I0 K-5\nG17\n");
    assert!(d.is_empty(), "{d:?}");
    let m = moves(&ev);
    let arc = &m[1..];
    // A clockwise quarter turn of r = 5 (7.854 mm) rising 2 mm in Y: 8.105 mm, 8 chords.
    assert_eq!(arc.len(), 8);
    for c in &arc[..arc.len() - 1] {
        let p = c.path.end;
        assert!((p.x.hypot(p.z - 5.0) - 5.0).abs() < 1e-9, "{p}");
    }
    assert_eq!(arc[arc.len() - 1].path.end, v(5.0, 2.0, 5.0));
}

#[test]
fn arcs_klipper_refuses_are_errors() {
    let src = "G28\nG1 X10 Y0 Z5\nG3 X0 Y11 I-10\nG2 X1 Y1\nG3 X20 Y0 R1\nG91\nG2 X1 I1\nG90\nG2 X5 I1 P2\n";
    let (ev, d) = run(src);
    let sev: Vec<(u64, Severity)> = d.iter().map(|d| (d.line, d.severity)).collect();
    assert_eq!(
        sev,
        vec![
            (4, Severity::Error),
            (5, Severity::Error),
            (7, Severity::Error),
            (9, Severity::Warning)
        ]
    );
    assert!(d[1].message.contains("R"), "{}", d[1].message);
    assert!(d[2].message.contains("relative"), "{}", d[2].message);
    // The arc whose end is off its circle still runs, as in Klipper: its last chord goes to
    // the end point.
    let m = moves(&ev);
    assert!(
        m.iter()
            .any(|c| c.line == 3 && c.path.end == v(0.0, 11.0, 5.0))
    );
    assert!(m.iter().any(|c| c.line == 9));
}

#[test]
fn m204_as_klipper_reads_it() {
    let (ev, d) = run("M204 S1000 P5\nM204 P1500 T3000\nM204 P800\nM204 T900\nM204 S0\n");
    let acc: Vec<(u64, Option<f64>)> = ev
        .iter()
        .map(|e| match e {
            Event::Limits { line, change } => (*line, change.accel_mm_s2),
            _ => panic!(),
        })
        .collect();
    assert_eq!(acc, vec![(1, Some(1000.0)), (2, Some(1500.0))]);
    let sev: Vec<(u64, Severity)> = d.iter().map(|d| (d.line, d.severity)).collect();
    assert_eq!(
        sev,
        vec![
            (3, Severity::Warning),
            (4, Severity::Warning),
            (5, Severity::Error)
        ]
    );
}

#[test]
fn set_velocity_limit() {
    let (ev, d) = run(
        "SET_VELOCITY_LIMIT VELOCITY=250 ACCEL=3000 SQUARE_CORNER_VELOCITY=0 \
         MINIMUM_CRUISE_RATIO=0.25\nset_velocity_limit accel=500 ACCEL_TO_DECEL=250\n\
         SET_VELOCITY_LIMIT MINIMUM_CRUISE_RATIO=1 VELOCITY=-1\nSET_VELOCITY_LIMIT\n",
    );
    assert_eq!(
        ev,
        vec![
            Event::Limits {
                line: 1,
                change: LimitChange {
                    velocity_mm_s: Some(250.0),
                    accel_mm_s2: Some(3000.0),
                    square_corner_velocity_mm_s: Some(0.0),
                    minimum_cruise_ratio: Some(0.25),
                    accel_to_decel_mm_s2: None,
                }
            },
            Event::Limits {
                line: 2,
                change: LimitChange {
                    accel_mm_s2: Some(500.0),
                    accel_to_decel_mm_s2: Some(250.0),
                    ..LimitChange::default()
                }
            }
        ]
    );
    let got: Vec<(u64, u32, Severity)> = d.iter().map(|d| (d.line, d.column, d.severity)).collect();
    assert_eq!(
        got,
        vec![(3, 43, Severity::Error), (3, 20, Severity::Error)]
    );
}

#[test]
fn dwell_and_stops() {
    let (ev, _) = run("G4 P250\nG4 S2\nG4\nM400\n");
    let stops: Vec<(u64, f64)> = ev
        .iter()
        .map(|e| match e {
            Event::Stop { line, dwell_s } => (*line, *dwell_s),
            _ => panic!(),
        })
        .collect();
    assert_eq!(stops, vec![(1, 0.25), (2, 2.0), (3, 0.0), (4, 0.0)]);
}

#[test]
fn firmware_retraction() {
    let (ev, _) = run(
        "G28\nG10\nG10\nG11\nG11\nSET_RETRACTION RETRACT_LENGTH=0.5 RETRACT_SPEED=30\nG10\nG10 L2 P1 X0\n",
    );
    let m = moves(&ev);
    let e: Vec<(f64, f64)> = m.iter().map(|m| (m.e_mm, m.feed_mm_s)).collect();
    // Marlin's defaults: 3 mm at 45 mm/s, back at 8 mm/s; a repeated G10/G11 does nothing;
    // G10 with L/P (coordinate systems) is not a retract.
    assert_eq!(e, vec![(-3.0, 45.0), (3.0, 8.0), (-0.5, 30.0)]);
    assert_eq!(line(&m[0]), (v(0.0, 0.0, 290.0), v(0.0, 0.0, 290.0)));
}

#[test]
fn bad_feed_keeps_the_previous_one() {
    let (ev, d) = run("G1 X1 F600\nG1 X2 F0\nG1 X3 F-5\n");
    let f: Vec<f64> = moves(&ev).iter().map(|m| m.feed_mm_s).collect();
    assert_eq!(f, vec![10.0, 10.0, 10.0]);
    let at: Vec<(u64, u32, Severity)> = d.iter().map(|d| (d.line, d.column, d.severity)).collect();
    assert_eq!(at, vec![(2, 7, Severity::Error), (3, 7, Severity::Error)]);
}

#[test]
fn malformed_motion_line_is_an_error_and_skipped() {
    let (ev, d) = run("G1 X1\nG1 X2.3.4 Y5\nG1 Y1\n");
    let m = moves(&ev);
    assert_eq!(m.len(), 2);
    assert_eq!(line(&m[1]), (v(1.0, 0.0, 290.0), v(1.0, 1.0, 290.0)));
    assert_eq!(
        (d[0].line, d[0].column, d[0].severity),
        (2, 5, Severity::Error)
    );
}

#[test]
fn unknown_commands_are_counted_and_t_is_not_a_move() {
    let mut n = 0;
    let stats = interpret(
        &b"M104 S215 T1\nT0\nPRINT_START BED=60\nM117 G1 X5\nG29.1\n; G1 X9\n"[..],
        Vec3::from(HOME),
        ArcRules::default(),
        |_| n += 1,
        |_| {},
    )
    .unwrap();
    assert_eq!(n, 0);
    assert_eq!(stats.unknown_commands, 5);
    assert_eq!(stats.lines, 6);
}

#[test]
fn overlong_line_is_a_warning_and_reading_goes_on() {
    let mut src = vec![b';'; 300_000];
    src.extend_from_slice(b"\nG1 X1\n");
    let mut diags = Vec::new();
    let mut moves = 0;
    let stats = interpret(
        &src[..],
        Vec3::from(HOME),
        ArcRules::default(),
        |_| moves += 1,
        |d| diags.push(d),
    )
    .unwrap();
    assert_eq!((stats.lines, stats.truncated_lines, moves), (2, 1, 1));
    assert_eq!(diags[0].line, 1);
    assert_eq!(diags[0].severity, Severity::Warning);
}

#[test]
fn crlf_comments_and_missing_final_newline_give_the_same_events() {
    let lf = "G28\nG1 X1 Y2 E0.5 F1200 ; caf\u{e9}\nG2 X3 Y2 I1\nG1 Z5\n";
    let (want, d) = run(lf);
    assert!(d.is_empty());
    let crlf = lf.replace('\n', "\r\n");
    assert_eq!(run(&crlf).0, want);
    assert_eq!(run(lf.trim_end()).0, want);
    // Non-UTF-8 bytes in a comment.
    let mut raw = lf.as_bytes().to_vec();
    let at = raw.windows(3).position(|w| w == b"caf").unwrap() + 3;
    raw.splice(at..at, [0xff, 0xfe]);
    let mut ev = Vec::new();
    let mut diags = Vec::new();
    interpret(
        &raw[..],
        Vec3::from(HOME),
        ArcRules::default(),
        |e| ev.push(e),
        |x| diags.push(x),
    )
    .unwrap();
    assert!(std::str::from_utf8(&raw).is_err());
    assert_eq!((ev, diags.len()), (want, 0));
}

#[test]
fn g92_before_homing_says_where_the_nozzle_is() {
    // No G28: G92 X0 Y0 Z20 puts the nozzle at (0, 0, 20); the move goes to z = 25.
    let (ev, d) = run("G92 X0 Y0 Z20 E0\nG1 Z25 X10 E1 F600\nG92 X0\nG1 X5\nG28\nG92 Z5\nG1 Z10\n");
    assert!(d.is_empty(), "{d:?}");
    let m = moves(&ev);
    assert_eq!(line(&m[0]), (v(0.0, 0.0, 20.0), v(10.0, 0.0, 25.0)));
    assert_eq!(m[0].offset_mm, Vec3::zeros());
    // After the first move G92 shifts coordinates: X0 here is machine 10, X5 machine 15.
    assert_eq!(line(&m[1]).1, v(15.0, 0.0, 25.0));
    assert_eq!(m[1].offset_mm, v(10.0, 0.0, 0.0));
    // After G28 too: Z5 at machine 290 makes Z10 machine 295.
    assert_eq!(line(&m[2]), (v(0.0, 0.0, 290.0), v(0.0, 0.0, 295.0)));
    assert_eq!(m[2].offset_mm, v(10.0, 0.0, 285.0));
}

#[test]
fn m221_scales_extrusion_and_heater_waits_stop() {
    let (ev, d) = run(
        "G28\nM83\nG1 X1 E1\nM221 S50\nG1 X2 E1\nM109 S200\nM190 S60\nTEMPERATURE_WAIT SENSOR=extruder MINIMUM=190\nM221\nG1 X3 E1\n",
    );
    assert!(d.is_empty(), "{d:?}");
    let e: Vec<f64> = moves(&ev).iter().map(|m| m.e_mm).collect();
    assert_eq!(e, vec![1.0, 0.5, 1.0]);
    let stops: Vec<u64> = ev
        .iter()
        .filter_map(|e| match e {
            Event::Stop { line, .. } => Some(*line),
            _ => None,
        })
        .collect();
    assert_eq!(stops, vec![1, 6, 7, 8]);
}

#[test]
fn set_input_shaper_stops_and_changes_the_shaper() {
    use delta_gcode::motion::shaper::ShaperType;
    let (ev, d) = run(
        "SET_INPUT_SHAPER SHAPER_FREQ_X=40 SHAPER_TYPE=EI DAMPING_RATIO_Y=0.05\n\
         SET_INPUT_SHAPER SHAPER_TYPE_Y=bogus SHAPER_FREQ_Y=-3\n",
    );
    assert_eq!(d.len(), 2, "{d:?}");
    assert!(
        d.iter()
            .all(|d| d.severity == Severity::Error && d.line == 2)
    );
    assert!(matches!(ev[0], Event::Stop { line: 1, .. }));
    let Event::Shaper { line: 1, change } = ev[1] else {
        panic!("{:?}", ev[1])
    };
    assert_eq!(change.kind, [Some(ShaperType::Ei), Some(ShaperType::Ei)]);
    assert_eq!(change.freq_hz, [Some(40.0), None]);
    assert_eq!(change.damping_ratio, [None, Some(0.05)]);
}
