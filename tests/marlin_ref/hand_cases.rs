//! The reference against figures worked out by hand from Marlin's rules (the research spec
//! `marlin-delta-spec.md` §13, T1–T15; each test recomputes its figures in its comments).
//! The machine is the FLSUN Q5 of tests/fixtures/profiles/marlin-q5.yaml (L 215, R 107.5,
//! 80 steps/mm, E 428 steps/mm, S 200, jerk 10/5, accel 1000); a test that needs other
//! limits sets them with M201/M203/M204, as a file would.

use std::path::Path;

use delta_gcode::machine::{Firmware, Machine};

use super::planner::Executed;
use super::stepper::{Bezier, Timing, bezier_fraction, block_duration, step_ticks};
use super::{Options, Run, Segmenter, simulate};

const TR: u32 = 2_000_000;

fn q5() -> Machine {
    Machine::load(
        &Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/profiles/marlin-q5.yaml"),
    )
    .expect("the Q5 test profile loads")
}

fn with_marlin(f: impl FnOnce(&mut delta_gcode::machine::Marlin)) -> Machine {
    let mut m = q5();
    let Firmware::Marlin(mm) = &mut m.firmware else {
        panic!("a Marlin profile")
    };
    f(mm);
    m
}

fn options(segmenter: Segmenter, timing: Timing) -> Options {
    Options {
        segmenter,
        timing,
        ..Options::default()
    }
}

/// The blocks `moves` makes after `preamble` has run to its end (the preamble ends with a
/// synchronising command, so the moves start from rest).
fn blocks_after(preamble: &str, moves: &str, m: &Machine, opts: &Options) -> (Run, Vec<Executed>) {
    let before = simulate(preamble.as_bytes(), m, opts).executed.len();
    let run = simulate(format!("{preamble}{moves}").as_bytes(), m, opts);
    let blocks = run.executed[before..].to_vec();
    (run, blocks)
}

fn total_s(blocks: &[Executed]) -> f64 {
    blocks.iter().map(|e| e.duration_s).sum()
}

fn close(got: f64, want: f64, tol: f64, what: &str) {
    assert!(
        (got - want).abs() <= tol,
        "{what}: {got} vs {want} (±{tol})"
    );
}

/// T1 and T2 machine: M204 3000, M201 9000 (towers and E), M203 500.
const GENERIC: &str = "M201 X9000 Y9000 Z9000 E9000\nM203 X500 Y500 Z500\nM204 P3000 R3000 T3000\n";

/// T1: a 100 mm Z move at F6000 from rest to rest is one block of n = 8000 steps;
/// nominal rate 8000/s; accel ceil(3000 · 80) = 240000 steps/s²; initial = final =
/// max(ceil(8000 · 0.05/100), 120) = 120; ramps (8000² − 120²)/480000 = 133.303 steps, so
/// accelerate_until = ceil = 134, decelerate_after = 8000 − floor = 7867. Continuous time
/// 2 · 7880/240000 + (8000 − 2 · 133.303)/8000 = 1.032341 s.
#[test]
fn t1_a_straight_move_takes_its_trapezoid_time() {
    let pre = format!("{GENERIC}G1 Z50 F6000\nM400\n");
    for (timing, s_curve, want) in [
        (Timing::Continuous, false, 1.032341),
        (Timing::Continuous, true, 1.032341),
        (Timing::default(), false, 1.029548),
        (Timing::default(), true, 1.024958),
    ] {
        let m = with_marlin(|mm| mm.s_curve = s_curve);
        let (_, b) = blocks_after(&pre, "G1 Z150\n", &m, &options(Segmenter::Plain, timing));
        assert_eq!(b.len(), 1, "a Z move is one block");
        let bl = &b[0].block;
        assert_eq!(
            (bl.n, bl.nominal_rate, bl.accel_steps),
            (8000, 8000, 240000)
        );
        let t = &bl.trap;
        assert_eq!((t.initial_rate, t.final_rate), (120, 120));
        assert_eq!((t.accelerate_until, t.decelerate_after), (134, 7867));
        close(
            b[0].duration_s,
            want,
            2e-6,
            &format!("T1 {timing:?} s-curve {s_curve}"),
        );
    }
}

/// T2: G1 Z51 from Z50 at F6000: n = 80, no plateau: accelerate_steps =
/// ceil((80 + 0)/2) = 40; cruise = uint(√(120² + 2 · 240000 · 40)) = 4383 steps/s;
/// continuous time 2 · (4383 − 120)/240000 = 0.035525 s.. with the exact ramps meeting at
/// 40 steps: 2 · (√(120² + 480000 · 40) − 120)/240000 = 0.035529 s.
#[test]
fn t2_a_short_move_has_no_plateau() {
    let pre = format!("{GENERIC}G1 Z50 F6000\nM400\n");
    for (timing, s_curve, want) in [
        (Timing::Continuous, false, 0.035529),
        (Timing::default(), false, 0.030813),
        (Timing::default(), true, 0.031480),
    ] {
        let m = with_marlin(|mm| mm.s_curve = s_curve);
        let (_, b) = blocks_after(&pre, "G1 Z51\n", &m, &options(Segmenter::Plain, timing));
        let t = &b[0].block.trap;
        assert_eq!(
            (b[0].block.n, t.accelerate_until, t.decelerate_after),
            (80, 40, 40)
        );
        assert_eq!(t.cruise_rate, 4383);
        close(
            b[0].duration_s,
            want,
            2e-6,
            &format!("T2 {timing:?} s-curve {s_curve}"),
        );
    }
}

/// T3: the S-curve's velocity fraction 10τ³ − 15τ⁴ + 6τ⁵ has slope 30τ²(1 − τ)², 1.875 at
/// τ = ½: the peak acceleration is 1.875 times the trapezoid's, over the same time. Checked
/// three ways: the polynomial, Marlin's integer Bézier (rates 120 → 8000 steps/s over the
/// T1 ramp, a = 240000 steps/s²), and the carriage heights the reference samples.
#[test]
fn t3_s_curve_peaks_at_1_875_times_the_acceleration() {
    let h = 1e-4;
    let peak = (0..=10000)
        .map(|k| k as f64 / 10000.0)
        .map(|tau| (bezier_fraction(tau + h) - bezier_fraction(tau - h)) / (2.0 * h))
        .fold(0.0, f64::max);
    close(peak, 1.875, 1e-6, "polynomial");
    close(
        bezier_fraction(0.25) * 100.0,
        10.35,
        0.01,
        "v(T/4) of a 100 mm/s ramp",
    );

    // Marlin's 32-bit Bézier: acceleration_time = uint32(TR/a · (8000 − 120)) ticks.
    let a = 240000.0;
    let time = (TR as f64 / a * 7880.0) as u32;
    let bz = Bezier::new(120, 8000, u32::MAX / time);
    let dt = 2000; // 1 ms in ticks
    let slope = (dt..time - dt)
        .step_by(100)
        .map(|t| (bz.eval(t + dt) as f64 - bz.eval(t - dt) as f64) / (2.0 * dt as f64 / TR as f64))
        .fold(0.0, f64::max);
    close(slope / a, 1.875, 0.01, "integer Bézier");
    assert_eq!(bz.eval(0), 120);
    close(
        bz.eval(time / 2) as f64,
        4060.0,
        2.0,
        "half way: (120 + 8000)/2",
    );

    // The sampled heights of T1 with the continuous S-curve: 3000 mm/s² · 1.875 = 5625.
    let m = with_marlin(|mm| mm.s_curve = true);
    let opts = options(Segmenter::Plain, Timing::Continuous);
    let run = simulate(
        format!("{GENERIC}G1 Z50 F6000\nM400\nG1 Z150\n").as_bytes(),
        &m,
        &opts,
    );
    let dt = 0.0005;
    let s = run.sample(dt);
    let accel = s
        .windows(3)
        .map(|w| (w[2].1[0] - 2.0 * w[1].1[0] + w[0].1[0]) / (dt * dt))
        .fold(0.0, |m: f64, a| m.max(a.abs()));
    close(
        accel,
        5625.0,
        5625.0 * 0.01,
        "sampled peak acceleration, mm/s²",
    );
}

/// T4: Marlin's IK on the Q5 (towers A (−93.0977, −53.75), B (93.0977, −53.75),
/// C (0, 107.5)): carriage = z + √(215² − d²).
#[test]
fn t4_inverse_kinematics() {
    let d = super::kinematics::Delta::from_geometry(&q5().geometry);
    for (p, want) in [
        ([0.0, 0.0, 0.0], [186.1955; 3]),
        ([50.0, 0.0, 0.0], [151.1919, 203.6628, 179.3565]),
        ([0.0, 50.0, 0.0], [163.6880, 163.6880, 207.1684]),
        ([-10.0, 0.0, 5.0], [195.8683, 185.8502, 190.9267]),
        ([0.0, 10.0, 5.0], [188.0130, 188.0130, 196.6214]),
    ] {
        let q = d.carriages(p[0], p[1], p[2]).expect("reachable");
        for i in 0..3 {
            close(q[i], want[i], 1e-4, &format!("{p:?} tower {i}"));
        }
    }
}

/// T5: a 90° corner at the centre (jerk 10, accel 1000, S 200). Each 10 mm leg at 50 mm/s
/// is 40 segments of 0.25 mm. The last segment of leg 1 moves (10, 10, 0) steps: tower
/// speeds (∓25, ±25, 0) mm/s; the first of leg 2 moves (6, 6, 11): (−15, −15, +27.5).
/// Jerk loop: A |25 − 15| = 10, not over; B reverses: max(25, 15) = 25 → v_factor 0.4;
/// C 27.5 · 0.4 = 11 > 10 → 0.4 · 10/11 = 0.363636; vmax = 50 · 0.363636 = 18.1818 mm/s.
/// Safe speeds 500/25 = 20 and 500/27.5 = 18.18 are both over 0.99 · vmax: vmax = 18.1818.
/// Rest to rest, the 80 blocks' trapezoids integrated exactly take 0.4649 s (the spec's
/// 0.4698 s ramps the end blocks from a cruise rate rounded up to a whole step, covering
/// more steps than they have; see T6).
#[test]
fn t5_a_corner_is_jerk_limited_on_tower_speeds() {
    let m = q5();
    let pre = "G1 X-10 Y0 Z5 F3000\nM400\n";
    let (_, b) = blocks_after(
        pre,
        "G1 X0 Y0\nG1 X0 Y10\n",
        &m,
        &options(Segmenter::Plain, Timing::Continuous),
    );
    assert_eq!(b.len(), 80);
    let (last, first) = (&b[39].block, &b[40].block);
    assert_eq!(last.steps[..3], [10, 10, 0]);
    assert_eq!(first.steps[..3], [6, 6, 11]);
    close(first.speeds[2], 27.5, 1e-9, "tower C speed entering leg 2");
    close(first.max_entry_sqr.sqrt(), 18.1818, 1e-4, "junction speed");
    close(first.entry_speed, 18.1818, 1e-4, "planned entry");
    close(last.exit_speed, 18.1818, 1e-4, "planned exit of leg 1");
    close(total_s(&b), 0.4649, 2e-4, "rest to rest");
}

/// T6: G1 X10 from (0, 0, 5) at F1200: 100 segments of 0.1 mm, (4, 4, 0) steps each.
/// MIN_STEPS_PER_SEGMENT 1: 100 blocks at 800 steps/s (a = 40 steps/mm · 1000): 96 of
/// them cruise 5 ms; the first ramps 120 → 572.2 → 566 steps/s (the ramps meet at
/// s = (566² − 120² + 80000 · 4)/160000 = 3.912 steps): 11.459 ms; the second 566 → 800:
/// 5.856 ms; the last two mirror them (5.856 ms, and 708 → 712.6 → 120 over 5 steps at
/// 50000 steps/s²: 11.945 ms): 0.5151 s in all (the spec's 0.5179 s ramps the last block
/// from a cruise rate of 775, rounded up to a whole step, over 5.9 steps). With 6: every other
/// segment is dropped, its steps go into the next one ((8, 8, 0), some (9, 7, 1)) at the
/// same 0.1 mm length: 50 blocks at 1600–1800 steps/s, 0.2700 s in the spec — twice as
/// fast (within 2 ms: the spec's end-block ramps overcount as above).
#[test]
fn t6_segments_under_min_steps_are_merged_and_run_fast() {
    let pre = "G1 X0 Y0 Z5 F3000\nM400\n";
    for (min_steps, count, dropped, want, tol) in
        [(1, 100, 0, 0.5151, 2e-4), (6, 50, 50, 0.2700, 2e-3)]
    {
        let m = with_marlin(|mm| mm.min_steps_per_segment = min_steps);
        let opts = options(Segmenter::Plain, Timing::Continuous);
        let before = simulate(pre.as_bytes(), &m, &opts).dropped;
        let (run, b) = blocks_after(pre, "G1 X10 F1200\n", &m, &opts);
        assert_eq!(b.len(), count, "MIN {min_steps}");
        assert_eq!(run.dropped - before, dropped, "MIN {min_steps}");
        close(total_s(&b), want, tol, &format!("MIN {min_steps}"));
        if min_steps == 6 {
            assert!(
                b.iter()
                    .all(|e| (1600..=1800).contains(&e.block.nominal_rate))
            );
        } else {
            // 0.1 mm at 20 mm/s: 200 · n steps/s (800, or 1000 for the (5, 3) blocks).
            assert!(b.iter().all(|e| e.block.nominal_rate == 200 * e.block.n));
        }
    }
}

/// T7: sub-step segments. G1 X1 at F60 from (0, 0, 5): plain segmenter 200 segments of
/// 5 µm, 120 without a whole step dropped, 80 one-step blocks at 200 steps/s, ≈ 0.400 s
/// instead of 1 s (0.403 s with the ISR's integer ticks). UBL: min(lround(200), lround(10)) = 10 segments of 0.1 mm (3–4 steps)
/// at 40–50 steps/s < 120: each takes 1/120 s for its first step, then (n − 1)/rate:
/// ≈ 0.838 s.
#[test]
fn t7_sub_step_segments() {
    let m = q5();
    let pre = "G1 X0 Y0 Z5 F3000\nM400\n";
    let opts = options(Segmenter::Plain, Timing::Continuous);
    let before = simulate(pre.as_bytes(), &m, &opts).dropped;
    let (run, b) = blocks_after(pre, "G1 X1 F60\n", &m, &opts);
    assert_eq!((b.len(), run.dropped - before), (80, 120));
    close(total_s(&b), 0.400, 0.005, "plain");
    let (_, b) = blocks_after(
        pre,
        "G1 X1 F60\n",
        &m,
        &options(Segmenter::Plain, Timing::default()),
    );
    close(total_s(&b), 0.403, 0.0015, "plain, Marlin's ISR");
    let (_, b) = blocks_after(
        pre,
        "G1 X1 F60\n",
        &m,
        &options(Segmenter::Ubl, Timing::default()),
    );
    assert_eq!(b.len(), 10);
    close(total_s(&b), 0.838, 0.005, "UBL");
}

/// T8: segment counts of both segmenters; T10: arc chord counts.
#[test]
fn t8_t10_segment_and_chord_counts() {
    use super::motion::{arc_segment_count, plain_segment_count, ubl_segment_count};
    assert_eq!(plain_segment_count(50.0, 50.0, 200.0), 200);
    assert_eq!(plain_segment_count(10.3, 100.0, 200.0), 20);
    assert_eq!(plain_segment_count(130.0, 100.0, 200.0), 260);
    assert_eq!(plain_segment_count(1.0, 1.0, 200.0), 200);
    assert_eq!(plain_segment_count(50.0, 50.0, 80.0), 80);
    assert_eq!(ubl_segment_count([10.3, 0.0, 0.0, 0.0], 100.0, 200.0).0, 21);
    let (n, hint) = ubl_segment_count([30.0, 40.0, 120.0, 0.0], 100.0, 200.0);
    assert_eq!(n, 100);
    close(hint, 1.3, 1e-12, "UBL hint: XYZ length / count");
    assert_eq!(ubl_segment_count([1.0, 0.0, 0.0, 0.0], 1.0, 200.0).0, 10);
    let quarter = std::f64::consts::FRAC_PI_2;
    let full = std::f64::consts::TAU;
    let chords = |r: f64, angle: f64| {
        let min = (72.0 * angle / full).ceil() as u32;
        arc_segment_count(r * angle, min)
    };
    assert_eq!(chords(10.0, quarter), 18);
    assert_eq!(chords(10.0, full), 72);
    assert_eq!(chords(1.0, quarter), 15);
    assert_eq!(chords(50.0, quarter), 79);
    assert_eq!(chords(100.0, full), 629);
    assert_eq!(chords(0.5, full), 31);
}

/// T11: a retract G1 E−5 F2400 (E 428 steps/mm): n = 2140, 5 mm, nominal 17120 steps/s,
/// accel ceil(1000 · 428) = 428000 (M204 R, not M201 E); ramps (17120² − 120²)/856000 =
/// 342.38: accelerate_until 343, decelerate_after 2140 − 342 = 1798; continuous time
/// 2 · 17000/428000 + (2140 − 684.77)/17120 = 0.16444 s.
#[test]
fn t11_a_retract_uses_the_retract_acceleration() {
    let m = q5();
    let opts = options(Segmenter::Plain, Timing::Continuous);
    let (_, b) = blocks_after("M201 E100\nM83\nM400\n", "G1 E-5 F2400\n", &m, &opts);
    let bl = &b[0].block;
    assert_eq!(
        (bl.n, bl.nominal_rate, bl.accel_steps),
        (2140, 17120, 428000)
    );
    assert_eq!(
        (bl.trap.accelerate_until, bl.trap.decelerate_after),
        (343, 1798)
    );
    close(bl.millimeters, 5.0, 1e-12, "E-only length");
    close(b[0].duration_s, 0.16444, 1e-5, "time");
}

/// T12: outside the printable radius (100) a homed machine scales x, y and z alike:
/// G1 X150 Y0 Z10 goes to (100, 0, 6.667). With soft endstops off it is dropped.
#[test]
fn t12_the_radius_clamp_scales_z() {
    let m = q5();
    let run = simulate(b"G1 X150 Y0 Z10 F3000\n", &m, &Options::default());
    close(run.final_position[0], 100.0, 1e-9, "x");
    close(run.final_position[2], 10.0 * 100.0 / 150.0, 1e-9, "z");
    let run = simulate(b"M211 S0\nG1 X150 Y0 Z10 F3000\n", &m, &Options::default());
    assert_eq!(run.final_position[..3], [0.0, 0.0, 217.42]);
    assert_eq!(run.refused, 1);
}

/// T13: SLOWDOWN is compiled out on a delta: M205 B (minimum segment time) changes no block.
/// (On a Cartesian Marlin, with these 5 ms segments and 3 queued, 2000 µs would become
/// 5000 + 2 · 15000/3 = 15000 µs.)
#[test]
fn t13_min_segment_time_has_no_effect() {
    let m = q5();
    let moves = "G1 X0 Y0 Z5 F3000\nG1 X20 Y5\nG1 X-10 Y30\nG2 X10 Y30 I10 J0\n";
    let plain = simulate(moves.as_bytes(), &m, &Options::default());
    let slowed = simulate(
        format!("M205 B100000\n{moves}").as_bytes(),
        &m,
        &Options::default(),
    );
    assert!(plain.executed.len() > 100);
    assert_eq!(plain.executed.len(), slowed.executed.len());
    for (a, b) in plain.executed.iter().zip(&slowed.executed) {
        assert_eq!((a.start_s, a.duration_s), (b.start_s, b.duration_s));
    }
}

/// T14: modal state: G90 resets E to absolute (M83 then G90: 1 mm in all); G90 then M83:
/// 2 mm; G92 X10 at X0 then G1 X10: no move.
#[test]
fn t14_modal_state() {
    let m = q5();
    let e = |g: &str| simulate(g.as_bytes(), &m, &Options::default()).final_position[3];
    close(
        e("M83\nG90\nG1 X1 E1 F600\nG1 X2 E1\n"),
        1.0,
        1e-12,
        "M83, G90",
    );
    close(
        e("G90\nM83\nG1 X1 E1 F600\nG1 X2 E1\n"),
        2.0,
        1e-12,
        "G90, M83",
    );
    let run = simulate(b"G92 X10\nG1 X10 F600\n", &m, &Options::default());
    assert!(run.executed.is_empty());
}

/// T15: after M400 (or G4) the next block starts from rest: entry 0.05 mm/s, initial rate
/// 120 steps/s, its first step 1/120 s after it starts.
#[test]
fn t15_a_sync_restarts_from_rest() {
    let m = q5();
    for sync in ["M400", "G4 P0"] {
        let (run, b) = blocks_after(
            &format!("G1 X10 F3000\n{sync}\n"),
            "G1 X20\n",
            &m,
            &Options::default(),
        );
        let bl = &b[0].block;
        close(bl.entry_speed, 0.05, 1e-12, sync);
        assert_eq!(bl.trap.initial_rate, 120);
        let first = step_ticks(bl, run.s_curve, TR)[0];
        assert_eq!(first, u64::from(TR / 120), "{sync}");
        close(
            block_duration(bl, run.s_curve, Timing::default()),
            b[0].duration_s,
            1e-12,
            "duration as run",
        );
    }
}
