//! Pieces of real slicer output (tests/fixtures): read without errors, with the expected
//! events; the emitter round-trips them.

use std::collections::BTreeMap;

use delta_gcode::emit::{emit, strip};
use delta_gcode::gcode::Move;
use delta_gcode::gcode::{
    ArcRules, Command, Diagnostic, Event, ReadStats, Severity, interpret, parse_line,
};
use delta_gcode::path::Vec3;

fn fixture(name: &str) -> Vec<u8> {
    let p = format!("{}/tests/fixtures/{name}", env!("CARGO_MANIFEST_DIR"));
    std::fs::read(&p).unwrap_or_else(|e| panic!("{p}: {e}"))
}

fn read(src: &[u8]) -> (Vec<Event>, Vec<Diagnostic>, ReadStats) {
    let mut ev = Vec::new();
    let mut d = Vec::new();
    let stats = interpret(
        src,
        Vec3::new(0.0, 0.0, 290.0),
        ArcRules::default(),
        |e| ev.push(e),
        |x| d.push(x),
    )
    .unwrap();
    (ev, d, stats)
}

fn errors(d: &[Diagnostic]) -> Vec<&Diagnostic> {
    d.iter().filter(|d| d.severity == Severity::Error).collect()
}

#[test]
fn flsun_start_code_has_the_helix() {
    let src = fixture("flsun_q5_start.gcode");
    let (ev, d, stats) = read(&src);
    assert!(d.is_empty(), "{d:?}");
    assert_eq!(stats.lines, 300);
    // The G3 of line 28 as Klipper's chords: a quarter circle of r = 98 (153.9 mm),
    // 153 chords on the circle, E shared evenly.
    let chords: Vec<&Move> = ev
        .iter()
        .filter_map(|e| match e {
            Event::Move(m) if m.line == 28 => Some(m),
            _ => None,
        })
        .collect();
    assert_eq!(stats.arcs, 1);
    assert_eq!(chords.len(), 153);
    assert!((chords[0].path.start() - Vec3::new(-98.0, 0.0, 0.2)).norm() < 1e-12);
    assert!((chords[152].path.end() - Vec3::new(0.0, -98.0, 0.2)).norm() < 1e-9);
    for c in &chords {
        assert!((c.path.end().xy().norm() - 98.0).abs() < 1e-9);
    }
    let e: f64 = chords.iter().map(|c| c.e_mm).sum();
    assert!((e - 40.0).abs() < 1e-9);
    // G28 on line 20 is a stop.
    assert!(ev.contains(&Event::Stop {
        line: 20,
        dwell_s: 0.0
    }));
}

#[test]
fn ps29_arcs_and_exclude_object() {
    let src = fixture("ps29_arcs_exclude.gcode");
    let (ev, d, stats) = read(&src);
    assert!(d.is_empty(), "{d:?}");
    // Count G2/G3 lines by text, independently of the parser.
    let text = String::from_utf8_lossy(&src);
    let arc_lines = text
        .lines()
        .filter(|l| l.starts_with("G2 ") || l.starts_with("G3 "))
        .count() as u64;
    assert!(arc_lines > 100);
    assert_eq!(stats.arcs, arc_lines);
    // Line 57: G3 X2.643 Y-23.072 I1.297 J25.032 E.17852, from (-1.2, -23.168).
    // Centre (0.097, 1.864), radius 25.066, a counter-clockwise sweep of 0.155 rad
    // (3.88 mm): 3 chords.
    let chords: Vec<&Move> = ev
        .iter()
        .filter_map(|e| match e {
            Event::Move(m) if m.line == 57 => Some(m),
            _ => None,
        })
        .collect();
    assert_eq!(chords.len(), 3);
    let centre = Vec3::new(0.097, 1.864, 0.0);
    let r = 1.297_f64.hypot(25.032);
    for c in &chords[..2] {
        let d = c.path.end() - centre;
        assert!((d.xy().norm() - r).abs() < 1e-9);
    }
    // The last chord ends on the written end point, 3 µm off the circle (slicer rounding).
    assert_eq!(
        chords[2].path.end().xy(),
        Vec3::new(2.643, -23.072, 0.0).xy()
    );
    assert!(
        chords
            .iter()
            .all(|c| (c.e_mm - 0.17852 / 3.0).abs() < 1e-12)
    );
    // The EXCLUDE_OBJECT_DEFINE lines keep their parameters.
    let l27 = text.lines().nth(26).unwrap();
    let p = parse_line(l27.as_bytes());
    assert!(
        matches!(p.command, Command::Extended { name, .. } if name == b"EXCLUDE_OBJECT_DEFINE")
    );
    assert_eq!(p.param("NAME").unwrap().value, b"plate_3objects_stl_1");
    assert_eq!(p.param("CENTER").unwrap().value, b"26.531,30.254");
    assert!(
        p.param("POLYGON")
            .unwrap()
            .value
            .starts_with(b"[[28.394,16.106],")
    );
    // M204 S800 on line 53.
    assert!(ev.iter().any(
        |e| matches!(e, Event::Limits { line: 53, change } if change.accel_mm_s2 == Some(800.0))
    ));
}

#[test]
fn cura_header() {
    let src = fixture("cura413_header.gcode");
    let (ev, d, _) = read(&src);
    assert!(errors(&d).is_empty(), "{d:?}");
    assert!(d.is_empty());
    // `G1 F200 E3` on line 27 is an E-only move at 200/60 mm/s.
    let m = ev
        .iter()
        .find_map(|e| match e {
            Event::Move(m) if m.line == 27 => Some(*m),
            _ => None,
        })
        .unwrap();
    assert_eq!(m.path.length_mm(), 0.0);
    assert_eq!(m.e_mm, 3.0);
    assert!((m.feed_mm_s - 200.0 / 60.0).abs() < 1e-12);
}

#[test]
fn bunny_head_warns_only_about_m204_p() {
    let src = fixture("ps25_bunny_head.gcode");
    let (_, d, stats) = read(&src);
    assert!(stats.moves > 300);
    assert!(!d.is_empty());
    assert!(
        d.iter()
            .all(|d| d.severity == Severity::Warning && d.message.contains("only P")),
        "{d:?}"
    );
}

/// The real slicer files' pieces (copied from /work/shared/corpus into tests/fixtures):
/// read without an error, every move finite with a positive feed. (This replaced an
/// ignored test over the whole decompressed corpus.)
#[test]
fn every_fixture_reads_without_errors_into_finite_moves() {
    for name in [
        "flsun_q5_start.gcode",
        "ps29_arcs_exclude.gcode",
        "cura413_header.gcode",
        "ps25_bunny_head.gcode",
    ] {
        let (ev, d, stats) = read(&fixture(name));
        assert!(errors(&d).is_empty(), "{name}: {d:#?}");
        assert!(stats.moves > 50, "{name}: {stats:?}");
        for e in ev {
            if let Event::Move(m) = e {
                let p = m.path;
                let finite = p
                    .start()
                    .iter()
                    .chain(p.end().iter())
                    .all(|v| v.is_finite());
                assert!(finite && m.e_mm.is_finite(), "{name}: {m:?}");
                assert!(
                    m.feed_mm_s.is_finite() && m.feed_mm_s > 0.0,
                    "{name}: {m:?}"
                );
            }
        }
    }
}

#[test]
fn object_labels_and_display_text_raise_nothing() {
    // PrusaSlicer's object labels (M486 A…), Klipper's EXCLUDE_OBJECT_*, M117 text.
    let src = b"M486 T3\nM486 S0\nM486 Acylinder_d40.stl\nM486 S-1\n\
        EXCLUDE_OBJECT_DEFINE NAME=cylinder_d40.stl_id_0_copy_0 CENTER=0,0 POLYGON=[[-20,-20],[20,-20],[20,20]]\n\
        EXCLUDE_OBJECT_START NAME=cylinder_d40.stl_id_0_copy_0\nM117 Layer 1 of 20 X1 D5 L2 _\n\
        EXCLUDE_OBJECT_END NAME='plate 1'\nG1 X1 F600\n";
    let (ev, d, _) = read(src);
    assert!(d.is_empty(), "{d:#?}");
    assert_eq!(ev.len(), 1);
}

#[test]
fn thumbnail_block_is_comments() {
    let src =
        b"; thumbnail begin 16x16 200\r\n; iVBORw0KGgoAAAANSUhEUgAAABAAAAAQCAYAAAAf8/9hAAAA\r\n\
                ; +0lEQVR4nGNgGAWjYBSMglEw==\r\n; thumbnail end\r\nG1 X1\r\n";
    let (ev, d, stats) = read(src);
    assert!(d.is_empty());
    assert_eq!((ev.len(), stats.unknown_commands), (1, 0));
}

#[test]
fn fixtures_round_trip_through_the_emitter() {
    for name in [
        "flsun_q5_start.gcode",
        "ps29_arcs_exclude.gcode",
        "cura413_header.gcode",
        "ps25_bunny_head.gcode",
    ] {
        let src = fixture(name);
        let mut plain = Vec::new();
        emit(&src[..], &mut plain, &BTreeMap::new(), &[]).unwrap();
        assert_eq!(plain, src, "{name}");
        // Annotate every 7th line, then strip.
        let mut ann = BTreeMap::new();
        for n in (1..300).step_by(7) {
            ann.insert(n, vec![format!("; delta-gcode: line {n}")]);
        }
        let summary = vec!["; delta-gcode summary".to_string()];
        let mut out = Vec::new();
        emit(&src[..], &mut out, &ann, &summary).unwrap();
        let added: usize = ann
            .values()
            .flatten()
            .chain(&summary)
            .map(|s| s.len() + 1)
            .sum();
        assert_eq!(out.len(), src.len() + added);
        let mut back = Vec::new();
        strip(&out[..], &mut back).unwrap();
        assert_eq!(back, src, "{name}");
        // The annotated file reads the same (comments only added).
        let (ev0, _, _) = read(&src);
        let (ev1, _, _) = read(&out);
        assert_eq!(ev0.len(), ev1.len());
    }
}
