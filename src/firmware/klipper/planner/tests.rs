//! Planner tests. Every expected number is worked out by hand in the comments, from the
//! kinematics of a trapezoid: accel_t = (v − v0)/a, accel_d = (v² − v0²)/(2a),
//! cruise_t = cruise_d / v.

use super::*;
use crate::gcode::{LimitChange, Move};
use crate::machine::{Extruder, Geometry, Limits, Masses, Motors, Sampling};
use crate::path::Vec3;
use std::f64::consts::PI;

/// A Kossel-like machine: R = 105, l = 215, 300 mm/s, 3000 mm/s², scv 5, mcr 0.5,
/// extrude-only 50 mm/s and 500 mm/s², instantaneous_corner_velocity 1.
pub(super) fn machine() -> Machine {
    Machine {
        name: "test".into(),
        geometry: Geometry {
            delta_radius_mm: 105.0,
            arm_length_mm: [215.0; 3],
            nozzle_offset_mm: 0.0,
            tower_angles_deg: [210.0, 330.0, 90.0],
            home_z_mm: 280.0,
            print_radius_mm: 85.0,
            arm_magnet_hold_n: None,
        },
        masses: Masses {
            cart_kg: 0.25,
            link_kg: 0.02,
            platform_kg: 0.5,
        },
        limits: Limits {
            max_velocity_mm_s: 300.0,
            max_accel_mm_s2: 3000.0,
            square_corner_velocity_mm_s: 5.0,
            minimum_cruise_ratio: 0.5,
            max_accel_to_decel_mm_s2: None,
            max_z_velocity_mm_s: 300.0,
            max_z_accel_mm_s2: 3000.0,
            edge_slowdown: true,
        },
        extruder: Extruder {
            nozzle_diameter_mm: 0.4,
            filament_diameter_mm: 1.75,
            max_extrude_only_velocity_mm_s: 50.0,
            max_extrude_only_accel_mm_s2: 500.0,
            instantaneous_corner_velocity_mm_s: 1.0,
        },
        motors: Motors {
            max_force_n: 40.0,
            reflected_mass_kg: 0.0,
            curve: None,
            stiffness_n_m: None,
            model: None,
        },
        sampling: Sampling { period_s: 0.001 },
        gravity_m_s2: 9.81,
        arc_rules: crate::gcode::ArcRules::default(),
        input_shaper: crate::motion::shaper::InputShaper::default(),
        drive: crate::motion::drive::Drive::Rigid,
        drive_default: None,
        firmware: crate::machine::Firmware::Klipper,
    }
}

fn line(a: [f64; 3], b: [f64; 3]) -> Path {
    Path::line(Vec3::new(a[0], a[1], a[2]), Vec3::new(b[0], b[1], b[2]))
}

fn mv(line: u64, path: Path, e_mm: f64, feed_mm_s: f64) -> Event {
    Event::Move(Move {
        line,
        path,
        e_mm,
        feed_mm_s,
        offset_mm: Vec3::zeros(),
        arc: None,
    })
}

fn e_only(line: u64, at: [f64; 3], e_mm: f64, feed_mm_s: f64) -> Event {
    mv(line, self::line(at, at), e_mm, feed_mm_s)
}

fn accel_to(line: u64, accel: f64) -> Event {
    Event::Limits {
        line,
        change: LimitChange {
            accel_mm_s2: Some(accel),
            ..LimitChange::default()
        },
    }
}

fn plan_with(machine: &Machine, events: &[Event]) -> (Vec<PlannedMove>, f64) {
    let mut p = Planner::new(machine);
    let mut out = Vec::new();
    for e in events {
        p.push(e, &mut |m| out.push(m));
    }
    p.finish(&mut |m| out.push(m));
    check_consistent(&out);
    (out, p.print_time_s())
}

fn plan(events: &[Event]) -> (Vec<PlannedMove>, f64) {
    plan_with(&machine(), events)
}

fn close(got: f64, want: f64, what: &str) {
    assert!(
        (got - want).abs() <= 1e-6 * want.abs().max(1.0),
        "{what}: got {got}, want {want}"
    );
}

/// Every plan: finite, non-negative phases covering the distance exactly, times chained.
fn check_consistent(moves: &[PlannedMove]) {
    let mut t = None;
    for m in moves {
        let f = [
            m.start_v_mm_s,
            m.cruise_v_mm_s,
            m.end_v_mm_s,
            m.accel_mm_s2,
            m.accel_t_s,
            m.cruise_t_s,
            m.decel_t_s,
            m.t0_s,
        ];
        assert!(f.iter().all(|x| x.is_finite() && *x >= 0.0), "{m:?}");
        assert!(m.start_v_mm_s <= m.cruise_v_mm_s && m.end_v_mm_s <= m.cruise_v_mm_s);
        let d = (m.start_v_mm_s + m.cruise_v_mm_s) * 0.5 * m.accel_t_s
            + m.cruise_v_mm_s * m.cruise_t_s
            + (m.end_v_mm_s + m.cruise_v_mm_s) * 0.5 * m.decel_t_s;
        assert!(
            (d - m.distance_mm).abs() < 1e-9 * m.distance_mm.max(1.0),
            "{m:?}"
        );
        if let Some(t) = t {
            assert!(m.t0_s >= t - 1e-9, "t0 goes back: {m:?}");
        }
        t = Some(m.t0_s + m.duration_s());
    }
}

#[test]
fn rest_to_rest_trapezoid() {
    // 100 mm at 100 mm/s, a = 3000: accel 100/3000 = 0.033333 s over 100²/6000 = 1.666667
    // mm, the same to decelerate, cruise (100 − 3.333333)/100 = 0.966667 s; 1.033333 s.
    let (m, t) = plan(&[mv(1, line([-50.0, 0.0, 0.0], [50.0, 0.0, 0.0]), 0.0, 100.0)]);
    assert_eq!(m.len(), 1);
    let m = m[0];
    close(m.start_v_mm_s, 0.0, "start");
    close(m.cruise_v_mm_s, 100.0, "cruise");
    close(m.accel_t_s, 1.0 / 30.0, "accel_t");
    close(m.decel_t_s, 1.0 / 30.0, "decel_t");
    close(m.cruise_t_s, 0.966_666_667, "cruise_t");
    close(
        m.cruise_v_mm_s * 0.5 * m.accel_t_s,
        1.666_666_667,
        "accel_d",
    );
    close(t, 1.033_333_333, "print time");
}

#[test]
fn triangle_without_minimum_cruise_ratio() {
    // mcr = 0: 2 mm at F 300 cannot reach 300 mm/s; the peak is v² = a·d = 6000,
    // v = 77.459667, accel_t = v/a = 0.025819889 s, no cruise; 0.051639778 s.
    let mut mach = machine();
    mach.limits.minimum_cruise_ratio = 0.0;
    let (m, t) = plan_with(&mach, &[mv(1, line([0.0; 3], [2.0, 0.0, 0.0]), 0.0, 300.0)]);
    close(m[0].cruise_v_mm_s, 77.459_666_92, "peak");
    close(m[0].accel_t_s, 0.025_819_889, "accel_t");
    close(m[0].cruise_t_s, 0.0, "cruise_t");
    close(t, 0.051_639_778, "print time");
}

#[test]
fn minimum_cruise_ratio_keeps_half_the_move_cruising() {
    // mcr = 0.5: the peak is set with the pseudo-accel 3000·0.5 = 1500:
    // v² = (0 + 2·2·1500)/2 = 3000, v = 54.772256. Accel and decel take 3000/6000 = 0.5 mm
    // each (0.018257419 s), the middle 1 mm cruises (1/54.772256 = 0.018257419 s).
    // Total 0.054772256 s, against 0.051639778 s for the triangle.
    let (m, t) = plan(&[mv(1, line([0.0; 3], [2.0, 0.0, 0.0]), 0.0, 300.0)]);
    close(m[0].cruise_v_mm_s, 54.772_255_75, "cruise");
    close(m[0].accel_t_s, 0.018_257_419, "accel_t");
    close(m[0].cruise_t_s, 0.018_257_419, "cruise_t");
    close(t, 0.054_772_256, "print time");
}

#[test]
fn square_corner_runs_at_square_corner_velocity() {
    // 90°: θ = 90°, sin(θ/2) = √½, R_jd = √½/(1 − √½) = 1/(√2 − 1); the junction
    // deviation is scv²(√2 − 1)/a, so v² = R_jd·jd·a = scv² whatever the accel.
    // Centripetal caps ¼·tan45°·2·50·3000 = 75000 do not bind.
    // Each 50 mm move: 0→100 in 100/3000 s (1.666667 mm), 100→5 in 95/3000 s
    // ((10000 − 25)/6000 = 1.6625 mm), cruise (50 − 3.329167)/100 = 0.466708 s:
    // 0.531708 s; both 1.063417 s.
    let (m, t) = plan(&[
        mv(1, line([0.0; 3], [50.0, 0.0, 0.0]), 0.0, 100.0),
        mv(2, line([50.0, 0.0, 0.0], [50.0, 50.0, 0.0]), 0.0, 100.0),
    ]);
    close(m[0].end_v_mm_s, 5.0, "junction");
    close(m[1].start_v_mm_s, 5.0, "junction");
    close(m[0].duration_s(), 0.531_708_333, "first");
    close(m[1].t0_s, 0.531_708_333, "t0");
    close(t, 1.063_416_667, "print time");
    for (accel, scv) in [(1000.0, 7.0), (5000.0, 2.0), (800.0, 12.0)] {
        let mut mach = machine();
        mach.limits.max_accel_mm_s2 = accel;
        mach.limits.square_corner_velocity_mm_s = scv;
        let (m, _) = plan_with(
            &mach,
            &[
                mv(1, line([0.0; 3], [0.0, 50.0, 0.0]), 0.0, 100.0),
                mv(2, line([0.0, 50.0, 0.0], [-50.0, 50.0, 0.0]), 0.0, 100.0),
            ],
        );
        close(m[0].end_v_mm_s, scv, "junction at other accel");
    }
}

#[test]
fn corner_uses_each_moves_own_accel() {
    // max_z_accel 1500: the move (0,0,0)→(30,0,40) (d = 50, |dz| = 40) gets 1500·1.25 =
    // 1875 mm/s²; its junction deviation is still 25(√2 − 1)/3000. At the 90° corner with
    // an XY move, its own cap R_jd·jd·a = 25·1875/3000 = 15.625 binds (the XY move's is
    // 25): v = √15.625 = 3.952847 mm/s, whichever side the Z move is on.
    let mut mach = machine();
    mach.limits.max_z_accel_mm_s2 = 1500.0;
    let (m, _) = plan_with(
        &mach,
        &[
            mv(1, line([0.0; 3], [30.0, 0.0, 40.0]), 0.0, 100.0),
            mv(2, line([30.0, 0.0, 40.0], [30.0, 50.0, 40.0]), 0.0, 100.0),
        ],
    );
    close(m[0].accel_mm_s2, 1875.0, "z accel");
    close(m[0].end_v_mm_s, 3.952_847_075, "z move first");
    let (m, _) = plan_with(
        &mach,
        &[
            mv(1, line([0.0, -50.0, 0.0], [0.0, 0.0, 0.0]), 0.0, 100.0),
            mv(2, line([0.0; 3], [30.0, 0.0, 40.0]), 0.0, 100.0),
        ],
    );
    close(m[0].end_v_mm_s, 3.952_847_075, "z move second");
}

#[test]
fn straight_continuation_keeps_full_speed() {
    // Two collinear 50 mm moves plan as one 100 mm move: 1.033333 s, 100 mm/s across.
    let (m, t) = plan(&[
        mv(1, line([-50.0, 0.0, 0.0], [0.0, 0.0, 0.0]), 0.0, 100.0),
        mv(2, line([0.0, 0.0, 0.0], [50.0, 0.0, 0.0]), 0.0, 100.0),
    ]);
    close(m[0].end_v_mm_s, 100.0, "junction");
    close(m[1].start_v_mm_s, 100.0, "junction");
    close(t, 1.033_333_333, "print time");
}

#[test]
fn extrude_only_move_stops_the_toolhead_and_uses_extruder_limits() {
    // 20 mm at 100 mm/s with E 1 (ratio 0.05, not limited): rest to rest,
    // 2·100/3000 + (20 − 3.333333)/100 = 0.233333 s.
    // E-only −10 mm at F 100: capped at 50 mm/s, 500 mm/s²: 0.1 s and 2.5 mm to reach 50,
    // the same to stop, 5 mm cruise in 0.1 s: 0.3 s (the mcr peak (0 + 2·10·500)/2 = 5000
    // does not bind). Then 20 mm again: 0.233333 s. Total 0.766667 s.
    let (m, t) = plan(&[
        mv(1, line([0.0; 3], [20.0, 0.0, 0.0]), 1.0, 100.0),
        e_only(2, [20.0, 0.0, 0.0], -10.0, 100.0),
        mv(3, line([20.0, 0.0, 0.0], [40.0, 0.0, 0.0]), 1.0, 100.0),
    ]);
    assert_eq!(m.len(), 3);
    close(m[0].end_v_mm_s, 0.0, "stop before");
    assert!(!m[1].kinematic);
    close(m[1].distance_mm, 10.0, "E distance");
    close(m[1].cruise_v_mm_s, 50.0, "E cruise");
    close(m[1].accel_mm_s2, 500.0, "E accel");
    close(m[1].duration_s(), 0.3, "E time");
    close(m[2].start_v_mm_s, 0.0, "stop after");
    close(m[2].t0_s, 0.533_333_333, "t0");
    close(t, 0.766_666_667, "print time");
}

#[test]
fn retract_while_moving_uses_extrude_only_limits() {
    // 10 mm with E −5: ratio 0.5, so 50/0.5 = 100 mm/s and 500/0.5 = 1000 mm/s².
    // F 200 is capped to 100: 0.1 s over 5 mm up, 0.1 s down, no cruise: 0.2 s.
    let (m, t) = plan(&[mv(1, line([0.0; 3], [10.0, 0.0, 0.0]), -5.0, 200.0)]);
    close(m[0].cruise_v_mm_s, 100.0, "cruise");
    close(m[0].accel_mm_s2, 1000.0, "accel");
    close(t, 0.2, "print time");
}

#[test]
fn extrusion_ratio_change_caps_the_junction() {
    // Two collinear 50 mm moves at 100 mm/s, E ratios 0.05 and 0.03: the extruder's speed
    // jumps by v·0.02, capped at 1 mm/s: v = 1/0.02 = 50 mm/s.
    let (m, _) = plan(&[
        mv(1, line([-50.0, 0.0, 0.0], [0.0, 0.0, 0.0]), 2.5, 100.0),
        mv(2, line([0.0, 0.0, 0.0], [50.0, 0.0, 0.0]), 1.5, 100.0),
    ]);
    close(m[0].end_v_mm_s, 50.0, "junction");
}

#[test]
fn z_move_is_capped_by_max_z_limits() {
    // 10 mm straight up at F 100 with max_z 20 mm/s, 100 mm/s² (ratio d/|dz| = 1):
    // 0.2 s over 2 mm to reach 20, 0.2 s to stop, 6 mm cruise in 0.3 s: 0.7 s.
    // A diagonal (30, 0, 40), d = 50: ratio 1.25, so 25 mm/s and 125 mm/s²:
    // 0.2 s, 2.5 mm each end, 45 mm cruise in 1.8 s: 2.2 s.
    let mut mach = machine();
    mach.limits.max_z_velocity_mm_s = 20.0;
    mach.limits.max_z_accel_mm_s2 = 100.0;
    let (m, t) = plan_with(
        &mach,
        &[mv(1, line([0.0; 3], [0.0, 0.0, 10.0]), 0.0, 100.0)],
    );
    close(m[0].cruise_v_mm_s, 20.0, "cruise");
    close(m[0].accel_mm_s2, 100.0, "accel");
    close(t, 0.7, "print time");
    let (m, t) = plan_with(
        &mach,
        &[mv(1, line([0.0; 3], [30.0, 0.0, 40.0]), 0.0, 100.0)],
    );
    close(m[0].cruise_v_mm_s, 25.0, "diagonal cruise");
    close(m[0].accel_mm_s2, 125.0, "diagonal accel");
    close(t, 2.2, "diagonal time");
}

#[test]
fn edge_slowdown_halves_then_quarters() {
    // Slow radius 98.9669 mm, very slow 107.0747 mm (limits.rs).
    // (0,0)→(100,0) at F 300: half of 300 and 3000: 150 mm/s, 1500 mm/s²: 0.1 s and
    // 7.5 mm each end, 85 mm in 0.566667 s: 0.766667 s.
    let out = |mach: &Machine, to: [f64; 3], feed: f64| {
        plan_with(mach, &[mv(1, line([0.0; 3], to), 0.0, feed)])
    };
    let (m, t) = out(&machine(), [100.0, 0.0, 0.0], 300.0);
    close(m[0].cruise_v_mm_s, 150.0, "half");
    close(m[0].accel_mm_s2, 1500.0, "half accel");
    close(t, 0.766_666_667, "half time");
    // (0,0)→(0,108): a quarter: 75 mm/s, 750 mm/s²: 0.1 s and 3.75 mm each end,
    // 100.5 mm in 1.34 s: 1.54 s.
    let (m, t) = out(&machine(), [0.0, 108.0, 0.0], 300.0);
    close(m[0].cruise_v_mm_s, 75.0, "quarter");
    close(t, 1.54, "quarter time");
    // Off: full 300 mm/s, 3000: 0.1 s and 15 mm each end, 70 mm in 0.233333 s: 0.433333.
    let mut off = machine();
    off.limits.edge_slowdown = false;
    let (_, t) = out(&off, [100.0, 0.0, 0.0], 300.0);
    close(t, 0.433_333_333, "off");
    // Just inside the slow radius: full speed.
    let (m, _) = out(&machine(), [98.9, 0.0, 0.0], 300.0);
    close(m[0].cruise_v_mm_s, 300.0, "inside");
    // The slowdown is a fraction of the CONFIG limits: after SET_VELOCITY_LIMIT
    // VELOCITY=1000 ACCEL=10000 the edge move still gets 150 mm/s and 1500 mm/s².
    let (m, t) = plan(&[
        Event::Limits {
            line: 1,
            change: LimitChange {
                velocity_mm_s: Some(1000.0),
                accel_mm_s2: Some(10000.0),
                ..LimitChange::default()
            },
        },
        mv(2, line([0.0; 3], [100.0, 0.0, 0.0]), 0.0, 1000.0),
    ]);
    close(m[0].cruise_v_mm_s, 150.0, "config-based");
    close(t, 0.766_666_667, "config-based time");
}

#[test]
fn m204_changes_accel_from_the_next_move() {
    // 100 mm at 100 mm/s with a = 3000, then M204 S1000, then 100 mm straight on.
    // Junction at full 100 mm/s. First: 0.033333 s up (1.666667 mm), 98.333333 mm cruise:
    // 1.016667 s. Second: 95 mm cruise (0.95 s), decel at 1000: 0.1 s over 5 mm: 1.05 s.
    // (Edge slowdown off: the second move passes the slow radius.)
    let mut mach = machine();
    mach.limits.edge_slowdown = false;
    let (m, t) = plan_with(
        &mach,
        &[
            mv(1, line([-50.0, 0.0, 0.0], [50.0, 0.0, 0.0]), 0.0, 100.0),
            accel_to(2, 1000.0),
            mv(3, line([50.0, 0.0, 0.0], [150.0, 0.0, 0.0]), 0.0, 100.0),
        ],
    );
    close(m[0].accel_mm_s2, 3000.0, "before");
    close(m[1].accel_mm_s2, 1000.0, "after");
    close(m[0].end_v_mm_s, 100.0, "junction");
    close(m[0].duration_s(), 1.016_666_667, "first");
    close(m[1].duration_s(), 1.05, "second");
    close(t, 2.066_666_667, "print time");
}

#[test]
fn dwell_adds_time_and_stops() {
    // Two collinear 20 mm moves at 100 mm/s with G4 P500 between: each rest to rest
    // 0.233333 s, plus 0.5 s: the second starts at 0.733333, all ends at 0.966667 s.
    let (m, t) = plan(&[
        mv(1, line([0.0; 3], [20.0, 0.0, 0.0]), 0.0, 100.0),
        Event::Stop {
            line: 2,
            dwell_s: 0.5,
        },
        mv(3, line([20.0, 0.0, 0.0], [40.0, 0.0, 0.0]), 0.0, 100.0),
    ]);
    close(m[0].end_v_mm_s, 0.0, "stopped");
    close(m[1].start_v_mm_s, 0.0, "restarted");
    close(m[1].t0_s, 0.733_333_333, "t0");
    close(t, 0.966_666_667, "print time");
}

#[test]
fn an_arc_runs_as_chords_with_junctions_at_square_corner_velocity_limits() {
    // A full circle r = 5 at F 6000 cut into 31 chords of 2·5·sin(π/31) = 1.01246 mm
    // (Klipper's gcode_arcs): each junction turns by 2π/31, so the angle θ between the
    // reversed incoming and the outgoing direction is π − 2π/31 and sin(θ/2) = cos(π/31)
    // = 0.994869. Junction deviation scv²(√2 − 1)/a = 0.0034518 mm:
    // v² = sin(θ/2)/(1 − sin(θ/2))·jd·a = 193.89·0.0034518·3000 = 2007.9, v = 44.81 mm/s.
    // The chords' own cap ¼·tan(θ/2)·2·d·a = 0.25·9.834·6074.8 = 14935 (122 mm/s) does
    // not bind. Each chord accelerates from 44.81 mm/s over 1.0125 mm at most to
    // √(44.81² + 3000·1.0125) = 72.6 mm/s (mcr: half of that distance, 59.7 mm/s): the
    // sawtooth Klipper runs, never 100 mm/s.
    let start = Vec3::new(5.0, 0.0, 0.0);
    let chords = crate::gcode::arc::Chords::klipper(
        start,
        start,
        [-5.0, 0.0],
        false,
        crate::gcode::Plane::Xy,
        1.0,
    );
    let mut from = start;
    let moves: Vec<Event> = chords
        .map(|to| {
            let e = mv(1, Path::line(from, to), 0.0, 100.0);
            from = to;
            e
        })
        .collect();
    let (m, _) = plan(&moves);
    assert_eq!(m.len(), 31);
    close(m[0].distance_mm, 10.0 * (PI / 31.0).sin(), "chord");
    let jd = 25.0 * (std::f64::consts::SQRT_2 - 1.0) / 3000.0;
    let sin_half = (PI / 31.0).cos();
    let v_junction = (sin_half / (1.0 - sin_half) * jd * 3000.0).sqrt();
    assert!(
        (v_junction - 44.81).abs() < 0.005,
        "hand value {v_junction}"
    );
    for w in m[1..].windows(2) {
        close(w[0].end_v_mm_s, v_junction, "junction");
        let peak = (v_junction * v_junction + 3000.0 * w[0].distance_mm).sqrt();
        assert!(w[0].cruise_v_mm_s <= peak + 1e-9, "{}", w[0].cruise_v_mm_s);
        assert!(w[0].cruise_v_mm_s < 60.0, "{}", w[0].cruise_v_mm_s);
    }
}

/// A deterministic, varied sequence (xorshift from `seed`, which must not be 0): lines of
/// 0.05–30 mm turning by random angles, arcs, Z hops, retracts (E-only and while moving),
/// feed and accel changes.
fn random_events(n: usize, mut seed: u64) -> Vec<Event> {
    let mut rnd = move || {
        seed ^= seed << 13;
        seed ^= seed >> 7;
        seed ^= seed << 17;
        (seed >> 11) as f64 / (1u64 << 53) as f64
    };
    let mut events = Vec::with_capacity(n);
    let mut pos = Vec3::new(0.0, 0.0, 0.2);
    let mut heading = 0.0f64;
    for i in 0..n {
        let line_no = i as u64 + 1;
        let r = rnd();
        let feed = [30.0, 80.0, 150.0, 300.0][(rnd() * 4.0) as usize];
        if r < 0.03 {
            events.push(e_only(line_no, pos.into(), -1.0 + 2.0 * rnd(), 40.0));
            continue;
        }
        if r < 0.05 {
            events.push(accel_to(line_no, 500.0 + 4000.0 * rnd()));
            continue;
        }
        // Stay within 60 mm of the centre; turn by up to ±120°, often by very little.
        let turn = if rnd() < 0.5 { 0.05 } else { 2.1 } * (2.0 * rnd() - 1.0);
        heading += turn;
        if pos.x.hypot(pos.y) > 60.0 {
            heading = pos.y.atan2(pos.x) + PI;
        }
        let dir = Vec3::new(heading.cos(), heading.sin(), 0.0);
        if r < 0.15 {
            // An arc, as the chords Klipper cuts it into.
            let radius = 1.0 + 10.0 * rnd();
            let sweep = (if rnd() < 0.5 { 1.0 } else { -1.0 }) * (0.2 + 3.0 * rnd());
            let side = if sweep > 0.0 { 1.0 } else { -1.0 };
            let normal = Vec3::new(-dir.y, dir.x, 0.0) * side;
            let c = pos + normal * radius;
            let start = (pos.y - c.y).atan2(pos.x - c.x) + sweep;
            let target = Vec3::new(
                c.x + radius * start.cos(),
                c.y + radius * start.sin(),
                pos.z,
            );
            let offset = [c.x - pos.x, c.y - pos.y];
            let chords = crate::gcode::arc::Chords::klipper(
                pos,
                target,
                offset,
                sweep < 0.0,
                crate::gcode::Plane::Xy,
                1.0,
            );
            for to in chords {
                let path = Path::line(pos, to);
                events.push(mv(line_no, path, path.length_mm() * 0.04, feed));
                heading = path.dir().y.atan2(path.dir().x);
                pos = to;
            }
            continue;
        }
        let len = if rnd() < 0.5 {
            0.05 + rnd()
        } else {
            30.0 * rnd() + 0.05
        };
        let mut end = pos + dir * len;
        if r < 0.18 {
            end.z += 0.4 * (rnd() - 0.5);
        }
        let e = if r < 0.22 {
            -0.3
        } else {
            len * (0.02 + 0.04 * rnd())
        };
        events.push(mv(line_no, Path::line(pos, end), e, feed));
        pos = end;
    }
    events
}

fn assert_same_plan(a: &[PlannedMove], b: &[PlannedMove]) {
    assert_eq!(a.len(), b.len());
    for (x, y) in a.iter().zip(b) {
        assert_eq!(x.line, y.line);
        for (p, q, what) in [
            (x.start_v_mm_s, y.start_v_mm_s, "start"),
            (x.cruise_v_mm_s, y.cruise_v_mm_s, "cruise"),
            (x.end_v_mm_s, y.end_v_mm_s, "end"),
            (x.accel_t_s, y.accel_t_s, "accel_t"),
            (x.cruise_t_s, y.cruise_t_s, "cruise_t"),
            (x.decel_t_s, y.decel_t_s, "decel_t"),
            (x.t0_s, y.t0_s, "t0"),
        ] {
            assert!(
                (p - q).abs() <= 1e-9 * p.abs().max(1.0),
                "line {}: {what} {p} vs {q}",
                x.line
            );
        }
    }
}

/// Plans `events` with the lazy flush and with the whole input in memory; returns the two
/// plans, their print times and the longest lazy queue.
fn lazy_and_whole(mach: &Machine, events: &[Event]) -> [(Vec<PlannedMove>, f64, usize); 2] {
    [true, false].map(|lazy| {
        let mut p = Planner::new(mach);
        p.lookahead.lazy = lazy;
        let mut out = Vec::new();
        let mut max_queued = 0;
        for e in events {
            p.push(e, &mut |m| out.push(m));
            max_queued = max_queued.max(p.queued());
        }
        if !lazy {
            assert!(out.is_empty(), "the reference must hold the whole input");
        }
        p.finish(&mut |m| out.push(m));
        check_consistent(&out);
        (out, p.print_time_s(), max_queued)
    })
}

#[test]
fn lazy_flush_gives_the_whole_file_plan() {
    let mach = machine();
    let events = random_events(20_000, 0x2545_f491_4f6c_dd1d);
    let [(got, got_t, max_queued), (want, want_t, _)] = lazy_and_whole(&mach, &events);
    // The lazy run did hand moves on early: its queue stayed short.
    assert!(max_queued < 200, "the lazy flush kept {max_queued} moves");
    assert_same_plan(&got, &want);
    close(got_t, want_t, "print time");
    // More, shorter sequences from other seeds.
    for k in 1..50u64 {
        let events = random_events(2_000, k.wrapping_mul(0x9e37_79b9_7f4a_7c15) | 1);
        let [(got, _, _), (want, _, _)] = lazy_and_whole(&mach, &events);
        assert_same_plan(&got, &want);
    }
}

#[test]
fn queue_stays_short_on_a_million_segment_line() {
    // 10^6 segments of 0.01 mm at 100 mm/s (edge off: the line is 10 m long). The first
    // lazy flush is tried after 1 s (BUFFER_TIME_HIGH) = 10000 segments, then every
    // 0.15 s = 1500 segments; the tail that may still have to brake is at most
    // 100²/(2·1500) = 3.33 mm = 334 segments (mcr pseudo-accel). So the queue never
    // exceeds 10000, and after the first flush stays under 1500 + 334 + 1.
    // Print time: 10000/100 + 100/3000 = 100.033333 s.
    let mut mach = machine();
    mach.limits.edge_slowdown = false;
    let mut p = Planner::new(&mach);
    let mut out = Vec::new();
    let (mut max_queued, mut max_later, mut count) = (0, 0, 0);
    for i in 0..1_000_000u32 {
        let x0 = -5000.0 + 0.01 * f64::from(i);
        let path = line([x0, 0.0, 0.0], [x0 + 0.01, 0.0, 0.0]);
        p.push(&mv(u64::from(i) + 1, path, 0.0, 100.0), &mut |m| {
            out.push(m)
        });
        max_queued = max_queued.max(p.queued());
        if i >= 10_000 {
            max_later = max_later.max(p.queued());
        }
        count += out.len();
        out.clear();
    }
    p.finish(&mut |m| out.push(m));
    count += out.len();
    assert_eq!(count, 1_000_000);
    assert!(max_queued <= 10_000, "queue reached {max_queued}");
    assert!(
        max_later <= 1835,
        "queue reached {max_later} after the first flush"
    );
    assert!((p.print_time_s() - 100.033_333_333).abs() < 1e-6);
}

#[test]
fn queue_cap_bounds_a_ramp_that_never_peaks() {
    // a = 1 mm/s²: 20000 segments of 0.1 mm accelerate the whole way (reaching 100 mm/s
    // would take 5 m), so no lazy boundary ever appears. The cap (1000 here) hands on
    // the older half each time; the plan stays continuous and feasible, and no faster
    // than the whole-file plan.
    let mut mach = machine();
    mach.limits.max_accel_mm_s2 = 1.0;
    mach.limits.edge_slowdown = false;
    let events: Vec<Event> = (0..20_000u32)
        .map(|i| {
            let x0 = -1000.0 + 0.1 * f64::from(i);
            mv(
                u64::from(i) + 1,
                line([x0, 0.0, 0.0], [x0 + 0.1, 0.0, 0.0]),
                0.0,
                100.0,
            )
        })
        .collect();
    let mut capped = Planner::new(&mach);
    capped.lookahead.max_queue = 1000;
    let mut got = Vec::new();
    let mut max_queued = 0;
    for e in &events {
        capped.push(e, &mut |m| got.push(m));
        max_queued = max_queued.max(capped.queued());
    }
    capped.finish(&mut |m| got.push(m));
    assert!(max_queued <= 1000);
    assert_eq!(got.len(), 20_000);
    check_consistent(&got);
    for w in got.windows(2) {
        assert!((w[0].end_v_mm_s - w[1].start_v_mm_s).abs() < 1e-9, "{w:?}");
    }
    let (want, whole_t) = plan_with(&mach, &events);
    for (g, w) in got.iter().zip(&want) {
        assert!(g.cruise_v_mm_s <= w.cruise_v_mm_s + 1e-9);
    }
    assert!(capped.print_time_s() >= whole_t - 1e-9);
}

#[test]
fn bad_numbers_never_give_nan() {
    // A NaN coordinate or E is dropped; F 0 and a negative F mean "no F limit" (300 mm/s):
    // 100 mm rest to rest at 300, a = 3000 (edge off): 0.1 s and 15 mm each end, 70 mm in
    // 0.233333 s: 0.433333 s.
    let mut mach = machine();
    mach.limits.edge_slowdown = false;
    let (m, t) = plan_with(
        &mach,
        &[
            mv(1, line([0.0; 3], [f64::NAN, 0.0, 0.0]), 1.0, 100.0),
            mv(2, line([0.0; 3], [10.0, 0.0, 0.0]), f64::NAN, 100.0),
            mv(3, line([0.0; 3], [100.0, 0.0, 0.0]), 0.0, 0.0),
            Event::Stop {
                line: 4,
                dwell_s: f64::NAN,
            },
            mv(5, line([100.0, 0.0, 0.0], [0.0; 3]), 0.0, -5.0),
        ],
    );
    assert_eq!(m.iter().map(|m| m.line).collect::<Vec<_>>(), [3, 5]);
    close(t, 2.0 * 0.433_333_333, "print time");
}

#[test]
fn klipper_before_2024_keeps_its_accel_to_decel_when_accel_changes() {
    // A 10 mm move from rest to rest at 300 mm/s after ACCEL=1000: since 2024 the
    // minimum_cruise_ratio 0.5 gives a pseudo-accel of 500, so the move's peak is the
    // smaller of √(a·d) = 100 and √(a_mcr·d) = 70.71 (the cruise plateau caps the triangle
    // at the mcr pseudo-accel's); before, max_accel_to_decel 1500 (capped at ACCEL = 1000)
    // gives √(1000·10) = 100.
    let line_move = |m: &mut Machine| {
        let change = LimitChange {
            accel_mm_s2: Some(1000.0),
            ..LimitChange::default()
        };
        let mut planner = Planner::new(m);
        let mut out = Vec::new();
        planner.push(&Event::Limits { line: 1, change }, &mut |m| out.push(m));
        planner.push(
            &mv(2, line([0.0, 0.0, 0.0], [10.0, 0.0, 0.0]), 0.0, 300.0),
            &mut |m| out.push(m),
        );
        planner.finish(&mut |m| out.push(m));
        out[0].cruise_v_mm_s
    };
    let mut now = machine();
    close(line_move(&mut now), 70.710_678_1, "since 2024");
    let mut legacy = machine();
    legacy.limits.max_accel_to_decel_mm_s2 = Some(1500.0);
    close(line_move(&mut legacy), 100.0, "before 2024");
}
