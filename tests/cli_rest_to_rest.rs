//! The peak forces `check` reports against independent computations of the same motion:
//! rest-to-rest trapezoids (a `G4 P0` after each) on the rigid model, evaluated densely;
//! and, with the drive's spring, a rest-to-rest move and a corner whose actual motion is
//! integrated numerically (RK4 at 2 µs) from the hand-computed trapezoids.

mod common;

use common::*;
use delta_gcode::machine::Machine;
use delta_gcode::path::Vec3;

/// Nozzle state at time t of a rest-to-rest trapezoid from `a` to `b` at speed `v` and
/// acceleration `acc` (long enough to reach `v`).
fn trapezoid(a: Vec3, b: Vec3, v: f64, acc: f64, t: f64) -> (Vec3, Vec3, Vec3) {
    let d = (b - a).norm();
    let dir = (b - a) / d;
    let (ta, da) = (v / acc, v * v / (2.0 * acc));
    let tc = (d - 2.0 * da) / v;
    let (s, sv, sa) = if t < ta {
        (0.5 * acc * t * t, acc * t, acc)
    } else if t < ta + tc {
        (da + v * (t - ta), v, 0.0)
    } else {
        let u = t - ta - tc;
        (da + v * tc + v * u - 0.5 * acc * u * u, v - acc * u, -acc)
    };
    (a + dir * s, dir * sv, dir * sa)
}

#[test]
fn rigid_rest_to_rest_peaks_equal_a_dense_evaluation() {
    let machine_path = repo("tests/fixtures/profiles/kossel-rigid.yaml");
    let machine = Machine::load(&machine_path).unwrap();
    let model = machine.model();
    let acc = machine.limits.max_accel_mm_s2;
    // Long moves at 100 mm/s: each reaches its cruise speed (1.67 mm to accelerate).
    let points = [
        Vec3::new(0.0, 0.0, 10.0),
        Vec3::new(60.0, -20.0, 10.0),
        Vec3::new(-40.0, 50.0, 12.0),
        Vec3::new(-50.0, -50.0, 10.0),
    ];
    let v = 100.0;
    let mut gcode = String::from("G28\nG1 X0 Y0 Z10 F6000\nG4 P0\n");
    for p in &points[1..] {
        gcode += &format!("G1 X{} Y{} Z{} F{}\nG4 P0\n", p.x, p.y, p.z, v * 60.0);
    }
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("r2r.gcode");
    std::fs::write(&file, gcode).unwrap();
    let o = run(&[
        "check",
        file.to_str().unwrap(),
        "-m",
        machine_path.to_str().unwrap(),
        "--format",
        "json",
        "--all-moves",
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let report: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let moves = report["moves"].as_array().unwrap();
    for (k, w) in points.windows(2).enumerate() {
        let line = 4 + 2 * k as u64; // the G1 lines 4, 6, 8, each followed by its G4 P0
        let reported = moves
            .iter()
            .find(|m| m["line"] == line)
            .map(|m| m["peak_force_n"].clone())
            .unwrap_or_else(|| panic!("line {line}"));
        let d = (w[1] - w[0]).norm();
        let duration = d / v + v / acc;
        let mut dense = [0.0_f64; 3];
        let n = 200_000;
        for i in 0..=n {
            let t = duration * i as f64 / n as f64;
            let (p, vel, a) = trapezoid(w[0], w[1], v, acc, t);
            let f = model.evaluate(p, vel, a).unwrap().force_n;
            for j in 0..3 {
                dense[j] = dense[j].max(f[j].abs());
            }
        }
        for j in 0..3 {
            let r = reported[j].as_f64().unwrap();
            assert!(
                (r - dense[j]).abs() < 1e-3 * dense[j],
                "move {k} tower {j}: reported {r} N, dense {} N",
                dense[j]
            );
        }
    }
}

/// Position and velocity of a trapezoid from `a` to `b`: speed `v0` up to `v` at `acc`,
/// cruise, down to `v1`, at time t after its start (rest at `b` after its end).
fn trapezoid_from(a: Vec3, b: Vec3, [v0, v, v1]: [f64; 3], acc: f64, t: f64) -> (Vec3, Vec3) {
    let d = (b - a).norm();
    let dir = (b - a) / d;
    let (ta, da) = ((v - v0) / acc, (v * v - v0 * v0) / (2.0 * acc));
    let (td, dd) = ((v - v1) / acc, (v * v - v1 * v1) / (2.0 * acc));
    let tc = (d - da - dd) / v;
    let (s, sv) = if t < 0.0 {
        (0.0, 0.0)
    } else if t < ta {
        (v0 * t + 0.5 * acc * t * t, v0 + acc * t)
    } else if t < ta + tc {
        (da + v * (t - ta), v)
    } else if t < ta + tc + td {
        let u = t - ta - tc;
        (da + v * tc + v * u - 0.5 * acc * u * u, v - acc * u)
    } else {
        (d, 0.0)
    };
    (a + dir * s, dir * sv)
}

/// The peak |Q_i| of the actual motion behind the commanded `cmd(t)` (position, velocity)
/// through the spring of `f` Hz and damping `z`: RK4 at `dt` on ẍ = ω²(x_c − x) +
/// 2ζω(ẋ_c − ẋ) for each axis from rest on the command, the model at every step.
fn rk4_peaks(
    model: &delta_gcode::delta::DeltaModel,
    (f, z): (f64, f64),
    cmd: impl Fn(f64) -> (Vec3, Vec3),
    t_end: f64,
    dt: f64,
) -> [f64; 3] {
    let w = std::f64::consts::TAU * f;
    let acc = |t: f64, x: Vec3, v: Vec3| {
        let (xc, vc) = cmd(t);
        (xc - x) * (w * w) + (vc - v) * (2.0 * z * w)
    };
    let (mut t, mut x, mut v) = (0.0, cmd(0.0).0, Vec3::zeros());
    let mut peak = [0.0_f64; 3];
    while t < t_end {
        let (k1x, k1v) = (v, acc(t, x, v));
        let (k2x, k2v) = (
            v + k1v * (0.5 * dt),
            acc(t + 0.5 * dt, x + k1x * (0.5 * dt), v + k1v * (0.5 * dt)),
        );
        let (k3x, k3v) = (
            v + k2v * (0.5 * dt),
            acc(t + 0.5 * dt, x + k2x * (0.5 * dt), v + k2v * (0.5 * dt)),
        );
        let (k4x, k4v) = (v + k3v * dt, acc(t + dt, x + k3x * dt, v + k3v * dt));
        x += (k1x + k2x * 2.0 + k3x * 2.0 + k4x) * (dt / 6.0);
        v += (k1v + k2v * 2.0 + k3v * 2.0 + k4v) * (dt / 6.0);
        t += dt;
        let f = model.evaluate(x, v, acc(t, x, v)).unwrap().force_n;
        for i in 0..3 {
            peak[i] = peak[i].max(f[i].abs());
        }
    }
    peak
}

/// The test Kossel with a 40 Hz, ζ = 0.08 drive, and the peaks `check` reports for line
/// `line` of `gcode`.
fn sprung_check(gcode: &str, line: u64) -> (Machine, [f64; 3]) {
    let dir = tempfile::tempdir().unwrap();
    let profile = std::fs::read_to_string(repo("tests/fixtures/profiles/kossel-rigid.yaml"))
        .unwrap()
        .replace(
            "drive: rigid",
            "drive: {frequency_hz: 40, damping_ratio: 0.08}",
        );
    let machine_path = dir.path().join("sprung.yaml");
    std::fs::write(&machine_path, &profile).unwrap();
    let file = dir.path().join("t.gcode");
    std::fs::write(&file, gcode).unwrap();
    let o = run(&[
        "check",
        file.to_str().unwrap(),
        "-m",
        machine_path.to_str().unwrap(),
        "--format",
        "json",
        "--all-moves",
    ]);
    let report: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let entry = report["moves"]
        .as_array()
        .unwrap()
        .iter()
        .find(|m| m["line"] == line)
        .unwrap_or_else(|| panic!("line {line}"));
    let peak = [0, 1, 2].map(|i| entry["peak_force_n"][i].as_f64().unwrap());
    (Machine::load(&machine_path).unwrap(), peak)
}

#[test]
fn sprung_peaks_equal_an_integration_of_the_drive_on_a_rest_to_rest_move() {
    // From rest at (−40, 10, 10) to (50, −30, 10) at 150 mm/s, 3000 mm/s²: 98.5 mm, accel
    // and decel 50 ms each. The command starts at t = 0 (the planner's first instant).
    let (a, b) = (Vec3::new(-40.0, 10.0, 10.0), Vec3::new(50.0, -30.0, 10.0));
    // A second of rest first: the ringing of the descent from home dies down (e^-20).
    let gcode = "G28\nG1 X-40 Y10 Z10 F6000\nG4 P1000\nG1 X50 Y-30 F9000\nG4 P0\n";
    let (machine, reported) = sprung_check(gcode, 4);
    let model = machine.model();
    let peak = rk4_peaks(
        &model,
        (40.0, 0.08),
        |t| trapezoid_from(a, b, [0.0, 150.0, 0.0], 3000.0, t - 0.05),
        1.0,
        2e-6,
    );
    for i in 0..3 {
        assert!(
            (reported[i] - peak[i]).abs() < 0.02 * peak[i],
            "tower {i}: reported {} N, integrated {} N",
            reported[i],
            peak[i]
        );
    }
}

#[test]
fn sprung_peaks_equal_an_integration_of_the_drive_through_a_corner() {
    // (−40, −30) → (40, −30) → (40, 50) at 150 mm/s, 3000 mm/s², square-corner velocity 5:
    // the 90° corner's junction speed is 5 mm/s (jd·a·sin(45°)/(1 − sin 45°) = 25), so the
    // command's velocity jumps by 5√2 mm/s there. Trapezoids 0 → 150 → 5 and 5 → 150 → 0.
    let (a, b, c) = (
        Vec3::new(-40.0, -30.0, 10.0),
        Vec3::new(40.0, -30.0, 10.0),
        Vec3::new(40.0, 50.0, 10.0),
    );
    let gcode = "G28\nG1 X-40 Y-30 Z10 F6000\nG4 P1000\nG1 X40 Y-30 F9000\nG1 X40 Y50\nG4 P0\n";
    let (machine, first) = sprung_check(gcode, 4);
    let (_, second) = sprung_check(gcode, 5);
    let reported = [0, 1, 2].map(|i| first[i].max(second[i]));
    let (acc, v) = (3000.0, 150.0);
    let t0 = 0.05;
    // The first trapezoid's duration: accel 50 ms (3.75 mm), decel to 5 mm/s 48.3 ms.
    let d1 = 80.0 - (v * v) / (2.0 * acc) - (v * v - 25.0) / (2.0 * acc);
    let t1 = t0 + v / acc + d1 / v + (v - 5.0) / acc;
    let model = machine.model();
    let peak = rk4_peaks(
        &model,
        (40.0, 0.08),
        |t| {
            if t < t1 {
                trapezoid_from(a, b, [0.0, v, 5.0], acc, t - t0)
            } else {
                trapezoid_from(b, c, [5.0, v, 0.0], acc, t - t1)
            }
        },
        2.0,
        2e-6,
    );
    for i in 0..3 {
        assert!(
            (reported[i] - peak[i]).abs() < 0.02 * peak[i],
            "tower {i}: reported {} N, integrated {} N",
            reported[i],
            peak[i]
        );
    }
}
