//! The commanded carriage heights of `delta-gcode trace` with a `firmware: marlin` profile
//! against a slow, separately written reference of Marlin 2.1.2.x (tests/marlin_ref; what
//! it is and leaves out: tests/fixtures/marlin-ref/README.md). Targets (issue 14): carriage
//! heights p99 within 0.05 mm, the print time (`summary.print_time_s` of `check`) within
//! 0.5 %, with and without S-curve, on hand-written files and on the first 3000 lines of
//! real Marlin-flavour slicer files.
//!
//! The streaming planner times each block as Marlin's stepper ISR does, in closed form
//! (src/firmware/marlin/isr.rs); docs/planner.md gives the figures each file measures.

mod common;
mod marlin_ref;

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};

use delta_gcode::machine::Machine;

use marlin_ref::{Options, Run, Timing};

/// Ceiling of the p99 of |Δq| over the towers and samples, mm.
const P99_MM: f64 = 0.05;
/// Ceiling of the relative print time error.
const TIME_ERROR: f64 = 0.005;
/// The reference's stepper timing: Marlin's ISR with the 2 MHz step timer of the Q5's
/// `mks_robin_nano` build (integer tick intervals, the first step 1/120 s into a start from
/// rest). The step-rate profile integrated exactly (`Timing::Continuous`) is 0.04–0.11 mm
/// (p99) and 0.2–0.4 % of print time away from it on these fixtures (README.md); the
/// streaming planner, which models the ISR, 0.005–0.008 mm and under 0.01 %.
const REFERENCE_TIMING: Timing = Timing::Discrete {
    timer_hz: 2_000_000,
};

fn fixture(name: &str) -> PathBuf {
    common::repo(&format!("tests/fixtures/marlin-ref/{name}"))
}

/// The FLSUN Q5 under Marlin, with or without S_CURVE_ACCELERATION.
fn profile(s_curve: bool) -> PathBuf {
    common::repo(if s_curve {
        "tests/fixtures/profiles/marlin-q5.yaml"
    } else {
        "tests/fixtures/profiles/marlin-q5-trapezoid.yaml"
    })
}

/// Commanded carriage heights against time.
struct Heights {
    t: Vec<f64>,
    q: Vec<[f64; 3]>,
}

/// `delta-gcode trace`'s commanded heights and `check`'s print time.
fn delta_gcode(gcode: &Path, profile: &Path) -> (Heights, f64) {
    static RUN: AtomicUsize = AtomicUsize::new(0);
    let csv = Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!(
        "marlin-reference-{}-{}.csv",
        std::process::id(),
        RUN.fetch_add(1, Ordering::Relaxed)
    ));
    let args = |cmd: &'static str| {
        [
            cmd,
            gcode.to_str().expect("utf-8"),
            "-m",
            profile.to_str().expect("utf-8"),
        ]
    };
    let out = common::bin()
        .args(args("trace"))
        .arg("-o")
        .arg(&csv)
        .output()
        .expect("delta-gcode runs");
    assert!(out.status.success(), "trace: {}", common::stderr(&out));
    let text = std::fs::read_to_string(&csv).expect("trace");
    std::fs::remove_file(&csv).expect("trace removed");
    let (header, rows) = common::read_trace(&text);
    let col = |name: &str| {
        header
            .iter()
            .position(|h| h == name)
            .unwrap_or_else(|| panic!("column {name}"))
    };
    let (t, q1, q2, q3) = (
        col("t_s"),
        col("q1_cmd_mm"),
        col("q2_cmd_mm"),
        col("q3_cmd_mm"),
    );
    let heights = Heights {
        t: rows.iter().map(|r| r[t]).collect(),
        q: rows.iter().map(|r| [r[q1], r[q2], r[q3]]).collect(),
    };
    let out = common::bin()
        .args(args("check"))
        .args(["--format", "json"])
        .output()
        .expect("delta-gcode runs");
    assert!(
        out.status.code() != Some(2),
        "check: {}{}",
        common::stderr(&out),
        common::stdout(&out)
    );
    let report: serde_json::Value = serde_json::from_slice(&out.stdout).expect("json");
    let print_time = report["summary"]["print_time_s"]
        .as_f64()
        .expect("print_time_s");
    (heights, print_time)
}

/// The reference's run of a file.
fn reference(gcode: &Path, profile: &Path, timing: Timing) -> Run {
    let machine = Machine::load(profile).expect("profile");
    let bytes = std::fs::read(gcode).expect("gcode");
    marlin_ref::simulate(
        &bytes,
        &machine,
        &Options {
            timing,
            ..Options::default()
        },
    )
}

/// The instant the heights first leave the first sample's by `d` mm (linear between
/// samples).
fn departure(h: &Heights, d: f64) -> f64 {
    let from = h.q[0];
    let dist = |q: &[f64; 3]| (0..3).map(|i| (q[i] - from[i]).abs()).fold(0.0, f64::max);
    let k =
        h.q.iter()
            .position(|q| dist(q) >= d)
            .expect("the carriages move");
    let (d0, d1) = (dist(&h.q[k - 1]), dist(&h.q[k]));
    h.t[k - 1] + (h.t[k] - h.t[k - 1]) * (d - d0) / (d1 - d0)
}

struct Fidelity {
    p99_mm: f64,
    max_mm: f64,
    time_error: f64,
    /// The largest local shift of the time lines from the first one, ms.
    drift_ms: f64,
}

/// The time lines are aligned window by window (this long, s): Marlin's own execution
/// drifts in time with the MCU's step timer (one Q5 build has a 2 MHz timer, another
/// 4 MHz; each interval is truncated to whole ticks, and the two are millimetres apart
/// after a minute, 0.002–0.05 mm p99 with these windows), so the heights are compared on
/// the motion's shape, each window shifted to fit best; the print time bounds the drift
/// over the whole file.
const WINDOW_S: f64 = 0.25;

/// Compares `ours` (and our print time) with the reference's run. The first origin: where
/// each first leaves its start by 0.05 mm; the first window's shift is searched within
/// ±20 ms of it (starts from rest are where timing models differ most: the first step
/// comes 1/120 s after a block starts), each later one within ±5 ms of the last.
fn compare(ours: &Heights, print_time_s: f64, reference: &Run) -> Fidelity {
    // |Δq| of each tower at our rows `rows`, the reference's time line shifted by `shift`.
    let diffs = |rows: &[usize], shift: f64| -> Vec<f64> {
        let times: Vec<f64> = rows.iter().map(|&k| ours.t[k] - shift).collect();
        let q = reference.heights_at(&times);
        rows.iter()
            .zip(q)
            .flat_map(|(&k, qr)| (0..3).map(move |i| (ours.q[k][i] - qr[i]).abs()))
            .collect()
    };
    let mean = |d: Vec<f64>| d.iter().sum::<f64>() / d.len().max(1) as f64;
    // The best shift within ±half of `around`: 1 ms steps, then 0.05 ms steps around the
    // best; ties (a window without motion) keep the shift nearest `around`.
    let best = |rows: &[usize], around: f64, half: f64| -> f64 {
        let search = |centre: f64, step: f64, n: i32| {
            (-n..=n)
                .map(|k| centre + k as f64 * step)
                .map(|s| (mean(diffs(rows, s)), (s - around).abs(), s))
                .min_by(|a, b| a.0.total_cmp(&b.0).then(a.1.total_cmp(&b.1)))
                .expect("shifts")
                .2
        };
        let coarse = search(around, 1e-3, (half / 1e-3).round() as i32);
        search(coarse, 5e-5, 20)
    };
    let own_t: Vec<f64> = (0..=(reference.print_time_s() / 1e-3) as usize)
        .map(|k| k as f64 * 1e-3)
        .collect();
    let own = Heights {
        q: reference.heights_at(&own_t),
        t: own_t,
    };
    let first = departure(ours, 0.05) - departure(&own, 0.05);
    let mut all = Vec::new();
    let (mut shift, mut half, mut drift) = (first, 0.02, 0.0f64);
    let mut k = 0;
    while k < ours.t.len() {
        let end = ours.t[k] + WINDOW_S;
        let rows: Vec<usize> = (k..ours.t.len()).take_while(|&j| ours.t[j] < end).collect();
        shift = best(&rows, shift, half);
        half = 0.005;
        drift = drift.max((shift - first).abs());
        all.extend(diffs(&rows, shift));
        k += rows.len();
    }
    all.sort_by(f64::total_cmp);
    let want = reference.print_time_s();
    Fidelity {
        p99_mm: all[all.len() * 99 / 100],
        max_mm: all[all.len() - 1],
        time_error: (print_time_s - want).abs() / want,
        drift_ms: drift * 1e3,
    }
}

/// Runs `name` through delta-gcode and the reference, with and without S-curve.
fn check(name: &str) {
    let gcode = fixture(name);
    for s_curve in [false, true] {
        let profile = profile(s_curve);
        let (ours, print_time) = delta_gcode(&gcode, &profile);
        let run = reference(&gcode, &profile, REFERENCE_TIMING);
        let f = compare(&ours, print_time, &run);
        eprintln!(
            "{name} s-curve {s_curve}: p99 {:.4} mm, max {:.4} mm, print time {print_time:.3} s \
             vs {:.3} s ({:.3} %), drift up to {:.1} ms",
            f.p99_mm,
            f.max_mm,
            run.print_time_s(),
            f.time_error * 100.0,
            f.drift_ms
        );
        assert!(
            f.p99_mm <= P99_MM,
            "{name} s-curve {s_curve}: p99 {} mm",
            f.p99_mm
        );
        assert!(
            f.time_error <= TIME_ERROR,
            "{name} s-curve {s_curve}: print time off by {} %",
            f.time_error * 100.0
        );
    }
}

#[test]
fn corners_arcs_retracts_and_limit_changes_are_marlins() {
    check("hand.gcode");
}

#[test]
fn the_edge_and_slow_moves_are_marlins() {
    check("edge.gcode");
}

#[test]
fn a_prusaslicer_marlin2_file_with_its_own_limits_is_marlins() {
    check("ps25_bunny3000.gcode");
}

#[test]
fn a_prusaslicer_q5_vendor_file_with_a_helix_is_marlins() {
    check("ps25_q5cube3000.gcode");
}

#[test]
fn a_cura_marlin_file_is_marlins() {
    check("cura413_cube3000.gcode");
}

/// The comparison can fail: the reference against itself passes with nothing to spare;
/// against itself 20 ms late, or with another acceleration, it fails. Also measures how
/// far Marlin's ISR timing is from the step-rate profile integrated exactly.
#[test]
fn the_comparison_tells_a_different_motion_apart() {
    let gcode = fixture("hand.gcode");
    let profile = profile(true);
    let run = reference(&gcode, &profile, Timing::default());
    let sampled = |r: &Run, delay: f64| {
        let s = r.sample(1e-3);
        Heights {
            t: s.iter().map(|(t, _)| t + delay).collect(),
            q: s.iter().map(|(_, q)| *q).collect(),
        }
    };
    let same = compare(&sampled(&run, 0.0), run.print_time_s(), &run);
    assert!(
        same.p99_mm < 1e-9 && same.time_error < 1e-12,
        "{}",
        same.p99_mm
    );
    // A late start is found and taken out by the alignment …
    let late = compare(&sampled(&run, 0.02), run.print_time_s(), &run);
    assert!(late.p99_mm < 1e-9, "{}", late.p99_mm);
    // … but a motion that drifts in time is not.
    let machine = Machine::load(&profile).expect("profile");
    let slower = {
        let text = std::fs::read_to_string(&gcode).expect("gcode");
        marlin_ref::simulate(
            format!("M220 S95\n{text}").as_bytes(),
            &machine,
            &Options::default(),
        )
    };
    let f = compare(&sampled(&slower, 0.0), slower.print_time_s(), &run);
    assert!(
        f.p99_mm > P99_MM && f.time_error > TIME_ERROR,
        "{} {}",
        f.p99_mm,
        f.time_error
    );
    let continuous = reference(&gcode, &profile, Timing::Continuous);
    let f = compare(&sampled(&continuous, 0.0), continuous.print_time_s(), &run);
    eprintln!(
        "hand.gcode, continuous step-rate profile against Marlin's ISR timing: p99 {:.4} mm, \
         max {:.4} mm, print time {:+.3} %",
        f.p99_mm,
        f.max_mm,
        f.time_error * 100.0
    );
}
