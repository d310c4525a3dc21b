//! Marlin's planner against hand-computed cases (marlin-delta-spec.md §13: T1, T4, T5, T6,
//! T13): each expected figure is worked out in the comment beside it.

use super::block::{self, Previous, Target};
use super::settings::Settings;
use super::*;
use crate::firmware::Firmware;
use crate::gcode::Move;
use crate::machine::{Firmware as MachineFirmware, Marlin as Profile};
use crate::motion::Phase;
use crate::path::Path;

/// The test Kossel with Marlin, on a delta of `radius` and `arm` mm.
fn machine(radius: f64, arm: f64) -> Machine {
    let text = include_str!("../../../tests/fixtures/profiles/kossel-marlin.yaml");
    let mut m = Machine::from_yaml_str(text, "kossel-marlin.yaml").unwrap();
    m.geometry.delta_radius_mm = radius;
    m.geometry.arm_length_mm = [arm; 3];
    m
}

fn profile(m: &Machine) -> Profile {
    match &m.firmware {
        MachineFirmware::Marlin(p) => p.clone(),
        MachineFirmware::Klipper => unreachable!("the fixture runs Marlin"),
    }
}

/// The FLSUN Q5's delta (L 215, R 107.5) with jerk 10/10/10/5, accelerations 1000 and 200
/// segments/s (the spec's Q5 cases).
fn q5(min_steps: u32) -> (Machine, Profile) {
    let m = machine(107.5, 215.0);
    let p = Profile {
        steps_per_mm: 80.0,
        e_steps_per_mm: 428.0,
        max_feedrate_mm_s: [200.0; 4],
        max_accel_mm_s2: [1000.0; 4],
        print_accel_mm_s2: 1000.0,
        retract_accel_mm_s2: 1000.0,
        travel_accel_mm_s2: 1000.0,
        jerk_mm_s: [10.0, 10.0, 10.0, 5.0],
        min_steps_per_segment: min_steps,
        ..profile(&m)
    };
    (m, p)
}

/// The spec's generic delta (L 250, R 124) at 3000 mm/s², towers capped at 9000 mm/s².
fn generic() -> (Machine, Profile) {
    let m = machine(124.0, 250.0);
    let p = Profile {
        print_accel_mm_s2: 3000.0,
        travel_accel_mm_s2: 3000.0,
        max_accel_mm_s2: [9000.0; 4],
        max_feedrate_mm_s: [500.0; 4],
        ..profile(&m)
    };
    (m, p)
}

fn v(x: f64, y: f64, z: f64) -> Vec3 {
    Vec3::new(x, y, z)
}

/// Runs straight moves (from, to, feed) without extrusion; the pieces, checked contiguous.
fn run(m: &Machine, p: &Profile, moves: &[(Vec3, Vec3, f64)]) -> Vec<Segment> {
    let mut fw = Marlin::new(m, Settings::new(p));
    let mut out = Vec::new();
    for (i, &(a, b, f)) in moves.iter().enumerate() {
        let mv = Move {
            line: i as u64 + 1,
            path: Path::line(a, b),
            e_mm: 0.0,
            feed_mm_s: f,
            offset_mm: Vec3::zeros(),
            arc: None,
        };
        fw.push(&Event::Move(mv), &mut out);
    }
    fw.finish(&mut out);
    for w in out.windows(2) {
        let (p_end, _) = w[0].end();
        assert!((w[0].t1_s() - w[1].t0_s).abs() < 1e-12, "{w:?}");
        assert!((p_end - w[1].p).norm() < 1e-9, "{w:?}");
    }
    let total: f64 = out.iter().map(|s| s.dt_s).sum();
    assert!((total - fw.print_time_s()).abs() < 1e-9);
    out
}

fn duration(pieces: &[Segment]) -> f64 {
    pieces.last().unwrap().t1_s() - pieces[0].t0_s
}

/// T4: Marlin's towers (210°, 330°, 90°) and IK, `z + sqrt(L² − d²)`.
#[test]
fn the_towers_and_the_inverse_kinematics_are_marlins() {
    let model = machine(107.5, 215.0).model();
    let q = model.inverse(v(50.0, 0.0, 0.0)).unwrap();
    for (q, want) in q.iter().zip([151.1919, 203.6628, 179.3565]) {
        assert!((q - want).abs() < 5e-5, "{q} {want}");
    }
}

/// T1: G1 Z150 from Z50 at 100 mm/s, accel 3000, 80 steps/mm: one block of n = 8000 steps,
/// nominal rate 8000, a = ⌈3000·80⌉ = 240000 steps/s², initial = final = 120 steps/s
/// (MINIMAL_STEP_RATE). acc_f = dec_f = (8000² − 120²)/480000 = 133.303, so
/// accelerate_until = 134, decelerate_after = 8000 − 133 = 7867. Integrated, the ramp
/// would take (8000 − 120)/240000 + (7867 − 133.303)/8000 + (8000 − 400)/240000 =
/// 1.031208 s (the spec's continuous model: 1.032341 s); the ISR runs the first step
/// 1/120 s at 120 steps/s, lags on the ramp and ends the deceleration early: the spec's
/// discrete stepper takes 1.029548 s.
#[test]
fn a_straight_move_takes_the_isrs_time() {
    let (m, p) = generic();
    let pieces = run(&m, &p, &[(v(0.0, 0.0, 50.0), v(0.0, 0.0, 150.0), 100.0)]);
    let d = duration(&pieces);
    assert!((d - 1.029548).abs() < 5e-5, "{d}");
    let s1 = (8000.0f64.powi(2) - 120.0f64.powi(2)) / 480000.0;
    let integrated =
        (8000.0 - 120.0) / 240000.0 + (7867.0 - s1) / 8000.0 + (8000.0 - 400.0) / 240000.0;
    assert!(integrated - d > 1.5e-3, "{integrated} {d}");
    let cruise = pieces.iter().find(|s| s.phase == Phase::Cruise).unwrap();
    assert!((cruise.v.norm() - 100.0).abs() < 1e-6);
    // The first step at the initial rate, then the ramp at Marlin's acceleration.
    assert_eq!(pieces[0].a.norm(), 0.0);
    assert!((pieces[0].dt_s - 16666.0 / 2e6).abs() < 1e-12);
    let accel = pieces
        .iter()
        .find(|s| s.phase == Phase::Accel && s.a.norm() > 0.0);
    assert!((accel.unwrap().a.norm() - 3000.0).abs() < 1e-6);
    let (end, _) = pieces.last().unwrap().end();
    assert!((end - v(0.0, 0.0, 150.0)).norm() < 1e-9);
}

/// T5: the junction of (−10, 10, 0) steps in 0.25 mm at 50 mm/s (tower speeds −25, 25, 0)
/// and (−6, −6, 11) steps (−15, −15, 27.5 mm/s). A: |−15 − (−25)| = 10, not over 10.
/// B: a reversal, max(25, 15) = 25 > 10, vf = 0.4. C: 27.5·0.4 = 11 > 10, vf = 0.4·10/11.
/// vmax = 50·vf = 18.18; the safe speeds, 500/25 = 20 and 500/27.5 = 18.18, are both above
/// 0.99·vmax, so vmax = 18.1818 (the new block's safe speed).
#[test]
fn a_corners_junction_speed_comes_from_the_tower_speeds() {
    let (_, p) = q5(1);
    let s = Settings::new(&p);
    let mut prev = Previous::default();
    let target = |to_steps| Target {
        line: 1,
        to_steps,
        feed_mm_s: 50.0,
        hint_mm: 0.25,
        cart_mm: 0.25,
    };
    let a = [-10, 10, 0, 0];
    let b1 = block::populate(&s, [0; 4], &target(a), 0, &mut prev).unwrap();
    // From rest: the safe speed, 20 mm/s.
    assert!((b1.max_entry_sqr.sqrt() - 20.0).abs() < 1e-12);
    let b2 = block::populate(&s, a, &target([-16, 4, 11, 0]), 1, &mut prev).unwrap();
    assert!((b2.max_entry_sqr.sqrt() - 500.0 / 27.5).abs() < 1e-9);
    // The full corner G1 X0 Y0 then Y10 from (−10, 0, 5) at 50 mm/s: the speed where the
    // second leg starts is that junction's, within the blocks' step rounding.
    let (m, p) = q5(1);
    let z = 5.0;
    let pieces = run(
        &m,
        &p,
        &[
            (v(-10.0, 0.0, z), v(0.0, 0.0, z), 50.0),
            (v(0.0, 0.0, z), v(0.0, 10.0, z), 50.0),
        ],
    );
    let first = pieces.iter().find(|s| s.line == 2).unwrap();
    assert!(
        (first.v.norm() - 18.1818).abs() < 0.05 * 18.18,
        "{}",
        first.v.norm()
    );
    // The spec's continuous-model time of the 80 blocks, 0.4698 s, is 2.4 % longer: its
    // decelerating blocks take more steps than they have (see
    // `trapezoid_ramps_keep_the_step_count`).
    assert!(
        (duration(&pieces) - 0.4698).abs() < 0.03 * 0.4698,
        "{}",
        duration(&pieces)
    );
}

/// T6: G1 X10 from (0, 0, 5) at 20 mm/s: 100 segments of 0.1 mm, each about (4, 4, 0)
/// steps. With MIN_STEPS_PER_SEGMENT 1 every segment is a block (0.5179 s, the ideal
/// 0.52 s); with 6 every other one is dropped, its steps go into the next block and its
/// time is lost: 0.2700 s, about twice the commanded speed.
#[test]
fn segments_under_min_steps_merge_into_the_next_and_run_faster() {
    let leg = [(v(0.0, 0.0, 5.0), v(10.0, 0.0, 5.0), 20.0)];
    let (m, p) = q5(1);
    let one = duration(&run(&m, &p, &leg));
    let (m, p) = q5(6);
    let six = duration(&run(&m, &p, &leg));
    // Within 2 % and 3 % of the spec's continuous model, which lets a block decelerate over more
    // steps than it has (see `trapezoid_ramps_keep_the_step_count`).
    assert!((one - 0.5179).abs() < 0.02 * 0.5179, "{one}");
    assert!((six - 0.2700).abs() < 0.03 * 0.2700, "{six}");
    assert!(six < 0.55 * one);
}

/// The block buffer bounds the lookahead: with 8 slots (7 blocks, the executing one and the
/// entry after it frozen) a move of 0.5 mm segments at 100 mm/s and 1000 mm/s² must be
/// able to stop within about 4 to 6 blocks (2 to 3 mm), so it never reaches
/// √(2·1000·3) = 77.5 mm/s; with 64 slots it cruises at 100.
#[test]
fn the_block_buffer_bounds_the_speed() {
    let leg = [(v(-40.0, 0.0, 5.0), v(40.0, 0.0, 5.0), 100.0)];
    let peak = |buffer: u32| {
        let (m, p) = q5(1);
        let p = Profile {
            block_buffer_size: buffer,
            max_feedrate_mm_s: [500.0; 4],
            jerk_mm_s: [1000.0; 4],
            ..p
        };
        let pieces = run(&m, &p, &leg);
        pieces.iter().map(|s| s.v.norm()).fold(0.0, f64::max)
    };
    let small = peak(8);
    assert!(
        small > (2.0 * 1000.0 * 2.0f64).sqrt() && small < 77.5,
        "{small}"
    );
    // (A piece's speed is its chord's length over the block's hint times the feed: the
    // whole steps move it by a few percent.)
    assert!((peak(64) - 100.0).abs() < 5.0, "{}", peak(64));
}

/// T13: SLOWDOWN is compiled out on kinematic machines (Conditionals_post.h), so the
/// minimum segment time (M205 B, `min_segment_time_us`) changes no block, even when the
/// buffer drains on short segments that SLOWDOWN would stretch (5 ms < 20 ms).
#[test]
fn slowdown_does_not_act_on_a_delta() {
    let short: Vec<_> = (0..10)
        .map(|i| {
            let x = i as f64;
            (v(x, 0.0, 5.0), v(x + 1.0, 0.0, 5.0), 200.0)
        })
        .collect();
    let (m, p) = q5(1);
    let with = duration(&run(
        &m,
        &Profile {
            min_segment_time_us: 20_000,
            ..p.clone()
        },
        &short,
    ));
    let without = duration(&run(
        &m,
        &Profile {
            min_segment_time_us: 0,
            ..p
        },
        &short,
    ));
    assert_eq!(with, without);
}

/// Inside a block the carriages move on the straight tower-space line between its ends,
/// whose heights are whole steps above or below the home height.
#[test]
fn blocks_end_on_whole_steps_and_move_linearly_in_tower_space() {
    let (m, p) = q5(1);
    let model = m.model();
    let home = model.home_carriages_mm();
    let pieces = run(&m, &p, &[(v(-60.0, -20.0, 1.0), v(60.0, 30.0, 1.0), 150.0)]);
    let mut block_ends = 0;
    for w in pieces.windows(2) {
        let (a, _) = w[0].end();
        let q = model.inverse(a).unwrap();
        let on_steps = (0..3).all(|i| {
            let k = (q[i] - home[i]) * 80.0;
            (k - k.round()).abs() < 1e-6
        });
        block_ends += usize::from(on_steps);
        // Mid-piece, the carriages are on the line between the piece's ends' carriages.
        let (mid, _, _) = w[0].at(0.5 * w[0].dt_s);
        let (qa, qm) = (model.inverse(w[0].p).unwrap(), model.inverse(mid).unwrap());
        let dq: Vec<f64> = (0..3).map(|i| q[i] - qa[i]).collect();
        let big = (0..3)
            .max_by(|&i, &j| dq[i].abs().total_cmp(&dq[j].abs()))
            .unwrap();
        if dq[big].abs() > 1e-9 {
            let f = (qm[big] - qa[big]) / dq[big];
            for i in 0..3 {
                let off = qm[i] - (qa[i] + f * dq[i]);
                // Within the tolerance of the block's line, so within twice it of the
                // line between a piece's ends.
                assert!(off.abs() < 2.0 * pieces::CHORD_TOLERANCE_MM, "{off}");
            }
        }
    }
    // 120 mm at 150 mm/s, 200 segments/s: ⌊160⌋ blocks.
    assert!(block_ends >= 150, "{block_ends}");
}

/// The last block of T5's second leg: 10 steps, a = 40000 steps/s², entry 895 and exit 120
/// steps/s; accelerate_until = decelerate_after = 1 (the intersection). By hand, as the ISR
/// runs it: step 1 at ⌊2·10⁶/895⌋ = 2234 ticks; the rate then 895 + round(40000 · 2234/2·10⁶)
/// = 940, step 2 at 2234 + ⌊2·10⁶/940⌋ = 4361 ticks; then the deceleration from 940 by the
/// time since it began: 940, 897, 853, 806, 756, 703, 647, 585 steps/s for the 8 steps
/// left, the last at 25540 ticks = 12.77 ms, still at 585 steps/s (Marlin's stop is abrupt,
/// marlin-delta-spec.md §7.5). The spec's continuous model decelerates all the way to 120,
/// 10.8 steps: more than the block has.
#[test]
fn trapezoid_ramps_keep_the_step_count() {
    let t = trapezoid::Trapezoid {
        initial_rate: 895.0,
        final_rate: 120.0,
        nominal_rate: 2000.0,
        accelerate_until: 1.0,
        decelerate_after: 1.0,
    };
    let mut r = Vec::new();
    isr::ramps(&t, 40000.0, 10.0, false, &mut r);
    assert!((r[0].dt_s - 2234.0 / 2e6).abs() < 1e-15);
    let end: f64 = r.iter().map(|p| p.dt_s).sum();
    assert!((end - 0.01277).abs() < 3e-5, "{end}");
    let last = r.last().unwrap();
    assert!((last.s1() - 10.0).abs() < 1e-9);
    assert!(last.rate + last.accel * last.dt_s > 500.0);
}

/// T1 with S_CURVE_ACCELERATION: the same end, the time of the spec's discrete stepper with
/// the Bézier (1.024958 s: its deceleration, slow near the final rate, is cut shorter than
/// the trapezoid's), the acceleration peaking at 1.875 × 3000 mm/s² and starting from 0.
#[test]
fn the_s_curve_takes_the_isrs_time_and_peaks_at_1_875_times_the_acceleration() {
    let (m, p) = generic();
    let leg = [(v(0.0, 0.0, 50.0), v(0.0, 0.0, 150.0), 100.0)];
    let trapezoid = run(&m, &p, &leg);
    let s_curve = run(&m, &Profile { s_curve: true, ..p }, &leg);
    assert!(
        (duration(&s_curve) - 1.024958).abs() < 1e-4,
        "{}",
        duration(&s_curve)
    );
    assert!(duration(&trapezoid) - duration(&s_curve) > 4e-3);
    // The middle pieces at the peak, 1.875·Δv/T over the phase's time in whole timer ticks
    // (a hair shorter than Δv/a, as Marlin's).
    let peak = s_curve.iter().map(|s| s.a.norm()).fold(0.0, f64::max);
    assert!((1.875 * 3000.0..1.876 * 3000.0).contains(&peak), "{peak}");
    assert!(s_curve[0].a.norm() < 0.05 * 3000.0);
    let (end, _) = s_curve.last().unwrap().end();
    assert!((end - v(0.0, 0.0, 150.0)).norm() < 1e-9);
}

/// A constant rate runs at a whole number of 2 MHz timer ticks per step: 4000 steps/s is
/// 500 ticks exactly; 4100 steps/s is ⌊487.8⌋ = 487 ticks, so 2 000 000/487 = 4106.78.
#[test]
fn a_constant_rate_runs_at_whole_timer_ticks() {
    assert_eq!(trapezoid::ticked_rate(4000.0), 4000.0);
    assert!((trapezoid::ticked_rate(4100.0) - 2_000_000.0 / 487.0).abs() < 1e-9);
}
