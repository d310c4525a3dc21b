//! Rest-to-rest moves (a `G4 P0` after each) have no junction impulses, so the peak forces
//! `check` reports must equal a dense evaluation of the same trapezoids, worked out here
//! from the move, the feed and the acceleration alone.

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
fn rest_to_rest_peaks_equal_a_dense_evaluation() {
    let machine_path = repo("machines/kossel.yaml");
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
