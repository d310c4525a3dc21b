//! Tests of the resampler: the grid, the one-sided limits, the junction boxes, the walk.
use super::*;
use crate::path::{Arc, Path};
use std::f64::consts::{PI, TAU};

const TS: f64 = 0.001;

/// A planned move with trapezoid times computed from its speeds (cruise_v is the peak).
fn planned(path: Path, t0: f64, vs: f64, vc: f64, ve: f64, a: f64) -> PlannedMove {
    let len = path.length_mm();
    let (ta, td) = ((vc - vs) / a, (vc - ve) / a);
    let (da, dd) = (
        (vc * vc - vs * vs) / (2.0 * a),
        (vc * vc - ve * ve) / (2.0 * a),
    );
    let dc = len - da - dd;
    assert!(dc >= -1e-9, "trapezoid does not fit: {dc}");
    PlannedMove {
        line: 7,
        path,
        e_mm: 0.0,
        kinematic: true,
        distance_mm: len,
        start_v_mm_s: vs,
        cruise_v_mm_s: vc,
        end_v_mm_s: ve,
        accel_mm_s2: a,
        accel_t_s: ta,
        cruise_t_s: dc.max(0.0) / vc,
        decel_t_s: td,
        t0_s: t0,
    }
}

fn collect(
    prev: Option<&PlannedMove>,
    mv: &PlannedMove,
    next: Option<&PlannedMove>,
) -> Vec<Sample> {
    let mut v = Vec::new();
    sample_move(prev, mv, next, TS, &mut |s| v.push(s));
    v
}

fn collect_seq(moves: &[PlannedMove]) -> Vec<Sample> {
    let mut v = Vec::new();
    for i in 0..moves.len() {
        let prev = i.checked_sub(1).map(|p| &moves[p]);
        sample_move(prev, &moves[i], moves.get(i + 1), TS, &mut |s| v.push(s));
    }
    v
}

fn is_grid(t: f64) -> bool {
    (t / TS).round() * TS == t
}

fn arc(r: f64, th0: f64, sweep: f64) -> Path {
    Path::Arc(Arc {
        center_mm: [3.0, -4.0],
        radius_mm: r,
        start_angle_rad: th0,
        sweep_rad: sweep,
        z_start_mm: 0.2,
        z_delta_mm: 0.0,
    })
}

#[test]
fn runs_of_a_line_are_the_samples_of_its_walk() {
    // The bulk loop over a line's plain grid points against the walk one sample at a
    // time (the path every arc takes): the same samples, bit for bit. Junctions with
    // and without a bend, all three phases, a move after a pause.
    let p = |x: f64, y: f64| Vec3::new(x, y, 0.3);
    // (end point, pause before, start, cruise and end speeds, acceleration)
    let legs = [
        (p(40.0, 0.0), 0.012_3, [0.0, 120.0, 30.0], 3000.0),
        (p(40.0, 25.0), 0.0, [30.0, 90.0, 0.0], 3000.0),
        (p(10.0, 25.0), 0.2, [0.0, 100.0, 0.0], 1e4),
    ];
    let (mut from, mut t) = (p(0.0, 0.0), 0.0);
    let moves = legs.map(|(to, pause, [vs, vc, ve], acc)| {
        let mv = planned(Path::line(from, to), t + pause, vs, vc, ve, acc);
        (from, t) = (to, mv.t0_s + mv.duration_s());
        mv
    });
    let mut runs = 0;
    for i in 0..moves.len() {
        let (prev, mv, next) = (
            i.checked_sub(1).map(|j| &moves[j]),
            &moves[i],
            moves.get(i + 1),
        );
        let (t_end, kicks) = span(prev, mv, next, TS);
        let Path::Line { start, end } = mv.path else {
            unreachable!()
        };
        let line = Line {
            start,
            delta: end - start,
        };
        let (mut bulk, mut walk) = (Vec::new(), Vec::new());
        sample_curve(mv, &line, Some(line), t_end, TS, kicks, &mut |s| {
            bulk.push(s)
        });
        sample_curve(mv, &line, None, t_end, TS, kicks, &mut |s| walk.push(s));
        assert!(bulk.len() > 20, "move {i}: {} samples", bulk.len());
        assert_eq!(bulk.len(), walk.len());
        for (x, y) in bulk.iter().zip(&walk) {
            assert_eq!(x, y);
            for k in 0..3 {
                assert_eq!(x.pos_mm[k].to_bits(), y.pos_mm[k].to_bits());
                assert_eq!(x.vel_mm_s[k].to_bits(), y.vel_mm_s[k].to_bits());
                assert_eq!(x.acc_mm_s2[k].to_bits(), y.acc_mm_s2[k].to_bits());
            }
        }
        runs += 1;
    }
    assert_eq!(runs, 3);
}

#[test]
fn constant_speed_line_samples_are_v_ts_apart() {
    let p = Path::line(Vec3::new(1.0, 2.0, 0.5), Vec3::new(31.0, 42.0, 120.5));
    let v = 50.0;
    let mv = planned(p, 0.00041, v, v, v, 1000.0);
    let s = collect(None, &mv, None);
    let grid: Vec<&Sample> = s.iter().filter(|x| is_grid(x.t_s)).collect();
    assert!(grid.len() > 2000);
    for w in grid.windows(2) {
        let d = (w[1].pos_mm - w[0].pos_mm).norm();
        assert!((d - v * TS).abs() < 1e-9, "spacing {d}");
        assert!((w[1].vel_mm_s.norm() - v).abs() < 1e-9);
    }
    let last = s.last().map_or(Vec3::zeros(), |x| x.pos_mm);
    assert!((last - p.end()).norm() < 1e-9);
}

#[test]
fn constant_speed_arc_samples_are_v_ts_apart_and_centripetal() {
    let (r, v) = (20.0, 80.0);
    let p = arc(r, 0.3, -1.5 * PI);
    let mv = planned(p, 0.0123, v, v, v, 1000.0);
    let s = collect(None, &mv, None);
    let angle = |x: &Sample| (x.pos_mm.y + 4.0).atan2(x.pos_mm.x - 3.0);
    let interior: Vec<&Sample> = s
        .iter()
        .filter(|x| is_grid(x.t_s) && x.phase == Phase::Cruise)
        .collect();
    assert!(interior.len() > 300);
    for w in interior.windows(2) {
        let dth = (angle(w[0]) - angle(w[1])).rem_euclid(TAU);
        assert!((dth * r - v * TS).abs() < 1e-9, "arc step {}", dth * r);
        let to_centre = Vec3::new(3.0, -4.0, 0.2) - w[1].pos_mm;
        assert!((w[1].acc_mm_s2 - to_centre * (v * v / (r * r))).norm() < 1e-8);
    }
}

#[test]
fn grid_is_global_and_consecutive_moves_partition_it() {
    let a = planned(
        Path::line(Vec3::zeros(), Vec3::new(20.0, 0.0, 0.0)),
        0.012_345_6,
        0.0,
        100.0,
        30.0,
        3000.0,
    );
    let b = planned(
        Path::line(Vec3::new(20.0, 0.0, 0.0), Vec3::new(20.0, 15.0, 0.0)),
        a.t0_s + a.duration_s(),
        30.0,
        80.0,
        0.0,
        3000.0,
    );
    let sa = collect(None, &a, Some(&b));
    let sb = collect(Some(&a), &b, None);
    let all: Vec<&Sample> = sa.iter().chain(sb.iter()).collect();
    for w in all.windows(2) {
        assert!(w[1].t_s >= w[0].t_s, "not in time order");
    }
    let t_start = a.t0_s;
    let t_stop = b.t0_s + b.duration_s();
    let ks: Vec<i64> = all
        .iter()
        .filter(|x| is_grid(x.t_s))
        .map(|x| (x.t_s / TS).round() as i64)
        .collect();
    let k_first = (t_start / TS).ceil() as i64;
    let k_last = (t_stop / TS).ceil() as i64 - 1;
    let expect: Vec<i64> = (k_first..=k_last).collect();
    assert_eq!(ks, expect, "grid samples missing or duplicated");
    for x in &all {
        if is_grid(x.t_s) {
            assert_eq!(x.t_s, (x.t_s / TS).round() * TS);
        }
    }
    // Off-grid samples: a's start, two per boundary (a: 2 boundaries, b: 2), a's end
    // and b's start at the junction, b's end.
    let off: Vec<f64> = all
        .iter()
        .filter(|x| !is_grid(x.t_s))
        .map(|x| x.t_s)
        .collect();
    assert_eq!(off.len(), 1 + 4 + 2 + 4 + 1, "{off:?}");
    let at_junction = all.iter().filter(|x| x.t_s == b.t0_s).count();
    assert_eq!(at_junction, 2, "junction: a's left limit and b's start");
    assert_eq!(sa.last().map(|x| x.t_s), Some(b.t0_s));
    assert_eq!(sb.first().map(|x| x.t_s), Some(b.t0_s));
}

#[test]
fn phase_boundaries_give_both_one_sided_limits() {
    let p = Path::line(Vec3::zeros(), Vec3::new(0.0, 30.0, 0.0));
    let acc = 2000.0;
    let trapezoid = planned(p, 0.000_25, 0.0, 120.0, 0.0, acc);
    let triangle = planned(p, 0.000_25, 0.0, (acc * 30.0_f64).sqrt(), 0.0, acc);
    for (mv, expect) in [
        (
            trapezoid,
            vec![(Phase::Accel, Phase::Cruise), (Phase::Cruise, Phase::Decel)],
        ),
        (triangle, vec![(Phase::Accel, Phase::Decel)]),
    ] {
        let s = collect(None, &mv, None);
        let pairs: Vec<(&Sample, &Sample)> = s
            .windows(2)
            .filter(|w| w[0].t_s == w[1].t_s)
            .map(|w| (&w[0], &w[1]))
            .collect();
        assert_eq!(pairs.len(), expect.len());
        for ((l, r), (pl, pr)) in pairs.iter().zip(expect) {
            assert_eq!((l.phase, r.phase), (pl, pr));
            assert_eq!(l.pos_mm, r.pos_mm);
            assert_eq!(l.vel_mm_s, r.vel_mm_s);
            let a_of = |ph: Phase| match ph {
                Phase::Accel => acc,
                Phase::Decel => -acc,
                _ => 0.0,
            };
            assert!((l.acc_mm_s2.y - a_of(pl)).abs() < 1e-9);
            assert!((r.acc_mm_s2.y - a_of(pr)).abs() < 1e-9);
        }
    }
}

#[test]
fn boundary_on_a_grid_point_replaces_it() {
    // t0 = 0, accel 0 → 100 at 10000 mm/s²: accel ends at exactly 0.01 s = 10·Ts.
    let p = Path::line(Vec3::zeros(), Vec3::new(10.0, 0.0, 0.0));
    let mv = planned(p, 0.0, 0.0, 100.0, 0.0, 10_000.0);
    let tb = mv.t0_s + mv.accel_t_s;
    assert_eq!(tb, 10.0 * TS);
    let s = collect(None, &mv, None);
    let at: Vec<Phase> = s.iter().filter(|x| x.t_s == tb).map(|x| x.phase).collect();
    assert_eq!(at, vec![Phase::Accel, Phase::Cruise]);
    assert_eq!(s.iter().filter(|x| x.t_s == 0.0).count(), 1);
}

/// Independent closed form of a rest-to-rest trapezoid: (distance, speed, accel) at
/// time t, `second` selecting the right limit at a boundary.
fn trapezoid(mv: &PlannedMove, t: f64, second: bool) -> (f64, f64, f64) {
    let (a, vc) = (mv.accel_mm_s2, mv.cruise_v_mm_s);
    let (ta, tc) = (mv.accel_t_s, mv.cruise_t_s);
    let da = 0.5 * a * ta * ta;
    let (t1, t2) = (mv.t0_s + ta, mv.t0_s + ta + tc);
    let tau = t - mv.t0_s;
    let in_accel = t < t1 || (t == t1 && !second);
    let in_cruise = !in_accel && (t < t2 || (t == t2 && !second));
    if in_accel {
        (0.5 * a * tau * tau, a * tau, a)
    } else if in_cruise {
        (da + vc * (tau - ta), vc, 0.0)
    } else {
        let td = tau - ta - tc;
        (da + vc * tc + vc * td - 0.5 * a * td * td, vc - a * td, -a)
    }
}

#[test]
fn rest_to_rest_matches_closed_form_trapezoid() {
    let line = Path::line(Vec3::new(-10.0, 5.0, 1.0), Vec3::new(25.0, -20.0, 31.0));
    let (r, th0, sweep) = (15.0, 0.7, 1.2 * PI);
    let arc_path = arc(r, th0, sweep);
    // 20 turns, 12,000 samples or more: each sample is one step from its phase's start,
    // so nothing drifts over a long move.
    let long_arc = arc(r, th0, 40.0 * PI);
    for path in [line, arc_path, long_arc] {
        for (vc, acc) in [(150.0_f64, 3000.0), (400.0, 1500.0)] {
            let len = path.length_mm();
            let vc = vc.min((acc * len).sqrt());
            let mv = planned(path, 1.234_567_8, 0.0, vc, 0.0, acc);
            let s = collect(None, &mv, None);
            assert!(s.len() > 100);
            let mut prev_t = f64::NAN;
            for x in &s {
                let second = x.t_s == prev_t;
                prev_t = x.t_s;
                assert_ne!(x.phase, Phase::Corner);
                let (d, v, at) = trapezoid(&mv, x.t_s, second);
                let (pos, vel, accel) = match path {
                    Path::Line { start, end } => {
                        let dir = (end - start) / len;
                        (start + dir * d, dir * v, dir * at)
                    }
                    Path::Arc(_) => {
                        let th = th0 + d / r;
                        let (c, sn) = (th.cos(), th.sin());
                        let radial = Vec3::new(c, sn, 0.0);
                        let tangent = Vec3::new(-sn, c, 0.0);
                        let centre = Vec3::new(3.0, -4.0, 0.2);
                        (
                            centre + radial * r,
                            tangent * v,
                            tangent * at - radial * (v * v / r),
                        )
                    }
                };
                let tol = 1e-9 * (1.0 + len);
                assert!(
                    (x.pos_mm - pos).norm() < tol,
                    "pos at {}: {} vs {}",
                    x.t_s,
                    x.pos_mm,
                    pos
                );
                assert!((x.vel_mm_s - vel).norm() < 1e-6, "vel at {}", x.t_s);
                assert!((x.acc_mm_s2 - accel).norm() < 1e-6, "acc at {}", x.t_s);
            }
            let end = s.last().map_or(Vec3::zeros(), |x| x.pos_mm);
            assert!((end - path.end()).norm() < 1e-9);
            // Neighbours that stop before and start after it change nothing.
            let before = planned(
                Path::line(path.start() - Vec3::new(0.0, 9.0, 0.0), path.start()),
                0.0,
                0.0,
                30.0,
                0.0,
                acc,
            );
            let before = PlannedMove {
                t0_s: mv.t0_s - before.duration_s(),
                ..before
            };
            let after = planned(
                Path::line(path.end(), path.end() + Vec3::new(7.0, 0.0, 1.0)),
                mv.t0_s + mv.duration_s(),
                0.0,
                40.0,
                0.0,
                acc,
            );
            assert_eq!(collect(Some(&before), &mv, Some(&after)), s);
        }
    }
}

#[test]
fn collinear_junction_is_not_a_corner_but_a_bend_is() {
    let (v, t0) = (60.0, 0.100_4);
    let dir = Vec3::new(1.0, 2.0, 0.5);
    let p0 = Vec3::new(0.1, 0.2, 0.3);
    let p1 = p0 + dir * 3.7;
    let p2 = p1 + dir * 0.7;
    let a = planned(Path::line(p0, p1), t0, v, v, v, 1000.0);
    let b = planned(Path::line(p1, p2), t0 + a.duration_s(), v, v, v, 1000.0);
    let s = collect(None, &b, None);
    let straight = collect(Some(&a), &b, None);
    // The tangents differ by rounding only.
    let dv = (a.path.end_dir() - b.path.start_dir()).norm();
    assert!(dv > 0.0 && dv < 1e-15);
    assert!(straight.iter().take(3).all(|x| x.phase == Phase::Cruise));
    // A bend: (1, 2, 0.5) then (2, −1, 0), at right angles: |Δv| = v·√2 at the junction.
    let c = planned(
        Path::line(p1, p1 + Vec3::new(2.0, -1.0, 0.0)),
        b.t0_s,
        v,
        v,
        v,
        1000.0,
    );
    let bent = collect(Some(&a), &c, None);
    assert_eq!(bent[0].phase, Phase::Corner);
    assert!((bent[0].acc_mm_s2.norm() - v * 2f64.sqrt() / TS).abs() < 1e-6);
    assert_eq!(s.len(), straight.len());
}

#[test]
fn extrude_only_move_stands_still() {
    let here = Vec3::new(4.0, 5.0, 0.3);
    let mut mv = planned(Path::line(here, here), 2.0, 0.0, 0.0, 0.0, 500.0);
    mv.kinematic = false;
    mv.distance_mm = 3.0;
    mv.e_mm = -3.0;
    mv.cruise_v_mm_s = 30.0;
    mv.accel_t_s = 0.06;
    mv.decel_t_s = 0.06;
    mv.cruise_t_s = 0.04;
    let before = planned(Path::line(Vec3::zeros(), here), 1.0, 0.0, 20.0, 0.0, 500.0);
    let before = PlannedMove {
        t0_s: mv.t0_s - before.duration_s(),
        ..before
    };
    let s = collect(Some(&before), &mv, None);
    assert!(s.len() > 150);
    for x in &s {
        assert_eq!(x.pos_mm, here);
        assert_eq!(x.vel_mm_s, Vec3::zeros());
        assert_eq!(x.acc_mm_s2, Vec3::zeros());
        assert_ne!(x.phase, Phase::Corner);
    }
}

#[test]
fn empty_span_gives_only_the_junction_sample_and_bad_period_nothing() {
    let p = Path::line(Vec3::zeros(), Vec3::new(1.0, 0.0, 0.0));
    let mut mv = planned(p, 0.5, 0.0, 10.0, 0.0, 100.0);
    let next = PlannedMove { t0_s: 0.5, ..mv };
    assert_eq!(collect(None, &mv, Some(&next)).len(), 1);
    mv.t0_s = 0.7;
    for bad in [0.0, -1.0, f64::NAN, f64::INFINITY] {
        let mut n = 0;
        sample_move(None, &mv, None, bad, &mut |_| n += 1);
        assert_eq!(n, 0);
    }
}

/// A circle of `n` chords of length c = v·τ run at constant speed v, starting at t = t0.
fn tessellated_circle(n: usize, v: f64, tau: f64, t0: f64) -> (Vec<PlannedMove>, f64) {
    let c = v * tau;
    let r = c / (2.0 * (PI / n as f64).sin());
    let at = |i: usize| {
        let th = TAU * i as f64 / n as f64;
        Vec3::new(r * th.cos(), r * th.sin(), 0.0)
    };
    let moves = (0..n)
        .map(|i| {
            planned(
                Path::line(at(i), at(i + 1)),
                t0 + i as f64 * tau,
                v,
                v,
                v,
                1000.0,
            )
        })
        .collect();
    (moves, r)
}

/// Relative error of |a| against v²/r, and the cosine between a and the inward radius.
fn centripetal_error(s: &Sample, v: f64, r: f64) -> (f64, f64) {
    let a = s.acc_mm_s2;
    let inward = -s.pos_mm / s.pos_mm.norm();
    (
        (a.norm() - v * v / r).abs() / (v * v / r),
        a.dot(&inward) / a.norm(),
    )
}

#[test]
fn tessellated_circle_shows_v2_over_r_at_every_sample() {
    let v = 100.0;
    // Chords lasting Ts, Ts/3 and 0.7·Ts, junctions off the grid: every sample, on or
    // off the grid, shows the centripetal acceleration of the circle through the
    // vertices (the chord polygon's own v²/r: Δv/d = 2v·sin(π/n)/d = v²/r).
    for (n, tau) in [(600, TS), (1800, TS / 3.0), (1000, 0.7 * TS)] {
        let (moves, r) = tessellated_circle(n, v, tau, 0.000_37);
        let all = collect_seq(&moves);
        let mut worst = 0.0_f64;
        for s in &all[all.len() / 10..all.len() * 9 / 10] {
            let (e, cos) = centripetal_error(s, v, r);
            assert!(cos > 0.999, "n={n}: direction {cos}");
            worst = worst.max(e);
        }
        assert!(worst < 0.02, "n={n}: worst {worst}");
    }
}

#[test]
fn short_moves_spread_each_impulse_over_their_own_halves() {
    // Three moves of 0.2·Ts each around a single bend: the bend's Δv is spread over
    // half of each of its two moves, 0.2·Ts in all, and the other samples have none.
    let v = 50.0;
    let d = 0.2 * TS;
    let p0 = Vec3::zeros();
    let p1 = p0 + Vec3::new(v * d, 0.0, 0.0);
    let p2 = p1 + Vec3::new(0.0, v * d, 0.0);
    let p3 = p2 + Vec3::new(0.0, v * d, 0.0);
    let t0 = 0.010_05;
    let a = planned(Path::line(p0, p1), t0, v, v, v, 1000.0);
    let b = planned(Path::line(p1, p2), t0 + d, v, v, v, 1000.0);
    let c = planned(Path::line(p2, p3), t0 + 2.0 * d, v, v, v, 1000.0);
    let dv = (Vec3::new(0.0, v, 0.0) - Vec3::new(v, 0.0, 0.0)) / d;
    let in_b = collect(Some(&a), &b, Some(&c));
    for s in &in_b {
        let expect = if s.t_s < b.t0_s + 0.5 * d {
            dv
        } else {
            Vec3::zeros()
        };
        assert!(
            (s.acc_mm_s2 - expect).norm() < 1e-6 * dv.norm(),
            "t={}",
            s.t_s
        );
    }
    let in_a = collect(None, &a, Some(&b));
    let last = in_a.last().map(|s| s.acc_mm_s2).unwrap_or_default();
    assert!((last - dv).norm() < 1e-6 * dv.norm());
}
