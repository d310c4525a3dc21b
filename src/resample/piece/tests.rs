use super::*;
use crate::motion::drive::{Drive, DriveStage, Lag, Spring};
use crate::motion::{PhaseChanges, Segment};
use crate::resample::StateBox;

const TS: f64 = 0.001;

fn seg(t0: f64, dt: f64, p: Vec3, v: Vec3, a: Vec3) -> Segment {
    Segment {
        t0_s: t0,
        dt_s: dt,
        p,
        v,
        a,
        line: 3,
        phase: Phase::Cruise,
        later_phases: PhaseChanges::NO_PHASES,
        changes: PhaseChanges::NONE,
    }
}

fn work(s: Segment, kicks: Kicks, end_sample: bool) -> PieceWork {
    PieceWork {
        commanded: s,
        lag: Lag::default(),
        edge: Edge::Kicks(kicks),
        end_sample,
        corner_until_s: f64::NEG_INFINITY,
    }
}

fn samples(w: &PieceWork, r: Option<&Response>) -> Vec<Sample> {
    let mut out = Vec::new();
    sample_piece(w, r, TS, &mut |s| out.push(s));
    out
}

#[test]
fn the_start_every_grid_point_inside_and_the_end_when_asked() {
    let v = Vec3::new(10.0, 0.0, 0.0);
    let a = seg(0.0005, 0.0027, Vec3::zeros(), v, Vec3::zeros());
    let (p, _) = a.end();
    let b = seg(0.0032, 0.0028, p, v, Vec3::zeros());
    let t: Vec<f64> = samples(&work(a, Kicks::default(), true), None)
        .iter()
        .chain(&samples(&work(b, Kicks::default(), false), None))
        .map(|s| s.t_s)
        .collect();
    let (end_a, start_b) = (a.t1_s(), b.t0_s);
    assert_eq!(
        t,
        [0.0005, 0.001, 0.002, 0.003, end_a, start_b, 0.004, 0.005]
    );
    // A piece starting on a grid point: that point is its start, once.
    let c = seg(0.002, 0.0015, p, v, Vec3::zeros());
    let t: Vec<f64> = samples(&work(c, Kicks::default(), false), None)
        .iter()
        .map(|s| s.t_s)
        .collect();
    assert_eq!(t, [0.002, 0.003]);
}

#[test]
fn a_rigid_corner_between_long_pieces_is_dv_over_ts() {
    // 60 mm/s along X, then along Y: |Δv| = 60√2 at t = 0.1, spread over one period.
    let (vx, vy) = (Vec3::new(60.0, 0.0, 0.0), Vec3::new(0.0, 60.0, 0.0));
    let a = seg(0.05, 0.05, Vec3::zeros(), vx, Vec3::zeros());
    let (p, _) = a.end();
    let b = seg(0.1, 0.05, p, vy, Vec3::zeros());
    let jump = vy - vx;
    let ka = Kicks::around(&a, Vec3::zeros(), 0.0, jump, b.dt_s, TS);
    let kb = Kicks::around(&b, jump, a.dt_s, Vec3::zeros(), 0.0, TS);
    let sa = samples(&work(a, ka, true), None);
    let sb = samples(&work(b, kb, false), None);
    let left = sa.last().unwrap();
    let right = &sb[0];
    for s in [left, right] {
        assert_eq!(s.t_s, 0.1);
        assert!((s.acc_mm_s2 - jump / TS).norm() < 1e-9, "{}", s.acc_mm_s2);
        assert_eq!(s.phase, Phase::Corner);
    }
    // Half a period on either side the box ends.
    assert!(
        sa.iter()
            .chain(&sb)
            .filter(|s| s.phase == Phase::Corner)
            .count()
            <= 4
    );
    assert_eq!(sb[1].acc_mm_s2, Vec3::zeros());
}

#[test]
fn a_circle_of_short_rigid_chords_shows_v2_over_r_at_every_sample() {
    // Chords lasting 0.7·Ts at 80 mm/s on r = 10: each junction's box reaches half a
    // chord either way, the boxes tile the time line, every sample sees one junction:
    // |Δv|/τ = v·2sin(θ/2)/(2r·sin(θ/2)/v) = v²/r.
    let (r, v) = (10.0, 80.0);
    let n = (std::f64::consts::TAU * r / (0.7 * TS * v)).round() as usize;
    let th = std::f64::consts::TAU / n as f64;
    let chord = 2.0 * r * (th / 2.0).sin();
    let tau = chord / v;
    assert!(tau < TS && tau > 0.6 * TS, "{tau}");
    let pt = |k: usize| {
        let a = th * k as f64;
        Vec3::new(r * a.cos(), r * a.sin(), 1.0)
    };
    let dir = |k: usize| (pt(k + 1) - pt(k)) / chord;
    let mut acc = Vec::new();
    for k in 1..n - 1 {
        let s = seg(k as f64 * tau, tau, pt(k), dir(k) * v, Vec3::zeros());
        let jin = (dir(k) - dir(k - 1)) * v;
        let jout = (dir(k + 1) - dir(k)) * v;
        let kicks = Kicks::around(&s, jin, tau, jout, tau, TS);
        for x in samples(&work(s, kicks, true), None) {
            acc.push(x.acc_mm_s2.norm());
        }
    }
    assert!(acc.len() > 100);
    for a in acc {
        assert!((a - v * v / r).abs() < 1e-6 * v * v / r, "{a}");
    }
}

#[test]
fn with_a_drive_a_sample_is_the_command_plus_the_lag() {
    let spring = Spring {
        frequency_hz: 45.0,
        damping_ratio: 0.1,
    };
    let r = Response::new(&spring);
    let mut drive = DriveStage::new(&Drive::Spring(spring));
    let a = seg(
        0.0,
        0.02,
        Vec3::zeros(),
        Vec3::new(50.0, 0.0, 0.0),
        Vec3::zeros(),
    );
    let piece = drive.push::<Vec3>(&a);
    let w = PieceWork::new(a, &piece, 0.5 / 45.0);
    for s in samples(&w, Some(&r)) {
        let lag = r.lag_at(&piece.lag, a.a, s.t_s);
        let (p, v, _) = a.at(s.t_s);
        assert_eq!(s.cmd_pos_mm, p);
        // The grid points come from the lag's fixed step: the closed form within
        // rounding.
        assert!((s.pos_mm - (p + lag.e)).norm() < 1e-14);
        assert!((s.vel_mm_s - (v + lag.de)).norm() < 1e-11);
        assert!((s.acc_mm_s2 - r.acceleration(&lag)).norm() < 1e-9);
        let corner = s.t_s < 0.5 / 45.0;
        assert_eq!(s.phase == Phase::Corner, corner, "{}", s.t_s);
    }
}

/// A ringing piece: long enough for a sparse evaluation, starting with a lag that rings.
fn ringing_piece() -> (PieceWork, Response) {
    let spring = Spring {
        frequency_hz: 51.0,
        damping_ratio: 0.1,
    };
    let r = Response::new(&spring).with_step(TS);
    let s = seg(
        12.3456,
        0.2834,
        Vec3::new(10.0, -20.0, 5.0),
        Vec3::new(80.0, -30.0, 2.0),
        Vec3::new(-600.0, 200.0, 0.0),
    );
    let w = PieceWork {
        commanded: s,
        lag: Lag {
            e: Vec3::new(0.02, -0.01, 0.0),
            de: Vec3::new(-4.0, 2.5, 0.3),
        },
        edge: Edge::End(Lag::default()),
        end_sample: false,
        corner_until_s: 12.35,
    };
    (with_end(w, &r), r)
}

/// `w` (the ringing piece) passing into two more phases: one between grid points, one on
/// a grid point.
fn phased(mut w: PieceWork) -> PieceWork {
    w.commanded.changes = PhaseChanges {
        at_s: [12.40005, 12500.0 * TS],
    };
    w.commanded.later_phases = [Phase::Decel, Phase::Accel];
    w
}

/// A piece with phase changes is sampled as its parts were when the shaper made a piece of
/// each: at the same instants (a change on a grid point once), each sample named by its
/// part's phase, the states those pieces had (each part's lag the drive's closed form from
/// the piece's start), with the whole piece's box holding them all.
#[test]
fn a_piece_through_phases_samples_as_its_parts_did() {
    let (w, r) = ringing_piece();
    let w = phased(w);
    let seg = w.commanded;
    let bounds = [seg.t0_s, 12.40005, 12500.0 * TS, seg.t1_s()];
    let phases = [seg.phase, Phase::Decel, Phase::Accel];
    let mut want = Vec::new();
    for i in 0..3 {
        let (t0, t1) = (bounds[i], bounds[i + 1]);
        let (p, v, _) = seg.at(t0 - seg.t0_s);
        let part = PieceWork {
            commanded: Segment {
                phase: phases[i],
                ..self::seg(t0, t1 - t0, p, v, seg.a)
            },
            lag: r.lag_at(&w.lag, seg.a, t0 - seg.t0_s),
            end_sample: false,
            ..w
        };
        want.extend(samples(&with_end(part, &r), Some(&r)));
    }
    let got = samples(&w, Some(&r));
    assert_eq!(got.len(), want.len());
    assert_eq!(piece_samples(&w, TS), got.len() as u64);
    let on_change = |t: f64| got.iter().filter(|s| s.t_s == t).count();
    assert_eq!((on_change(bounds[1]), on_change(bounds[2])), (1, 1));
    for (g, x) in got.iter().zip(&want) {
        assert_eq!((g.t_s, g.phase, g.line), (x.t_s, x.phase, x.line));
        assert!((g.pos_mm - x.pos_mm).norm() < 1e-9, "{g:?} {x:?}");
        assert!((g.vel_mm_s - x.vel_mm_s).norm() < 1e-7, "{g:?} {x:?}");
        assert!((g.acc_mm_s2 - x.acc_mm_s2).norm() < 1e-5, "{g:?} {x:?}");
    }
    let phase_of = |t: f64| match t {
        t if t < 12.35 => Phase::Corner,
        t if t < bounds[1] => Phase::Cruise,
        t if t < bounds[2] => Phase::Decel,
        _ => Phase::Accel,
    };
    assert!(got.iter().all(|s| s.phase == phase_of(s.t_s)));
}

/// `w` with the lag at its end that the drive stage gives it.
fn with_end(mut w: PieceWork, r: &Response) -> PieceWork {
    w.edge = Edge::End(r.lag_at(&w.lag, w.commanded.a, w.commanded.dt_s));
    w
}

/// A sink that skips the runs `skip` says to, recording what it was asked; offered
/// whole pieces too when `whole`.
struct Sparse<F> {
    samples: Vec<Sample>,
    asked: Vec<(StateBox, u64)>,
    skip: F,
    whole: bool,
}

impl<F: FnMut(&StateBox) -> bool> SampleSink for Sparse<F> {
    fn sample(&mut self, s: Sample) {
        self.samples.push(s);
    }
    fn sparse(&self) -> bool {
        true
    }
    fn whole_pieces(&self) -> bool {
        self.whole
    }
    fn skip(&mut self, b: &StateBox, count: u64) -> bool {
        self.asked.push((*b, count));
        (self.skip)(b)
    }
}

#[test]
fn every_sample_of_a_run_lies_in_its_box_and_skipped_runs_leave_the_rest_bit_for_bit() {
    let (w, r) = ringing_piece();
    let dense = samples(&w, Some(&r));
    assert!(dense.len() > 250);
    // Skip every other run asked about, from the second.
    let mut flip = true;
    let mut sink = Sparse {
        samples: Vec::new(),
        asked: Vec::new(),
        skip: |_: &StateBox| {
            flip = !flip;
            flip
        },
        whole: false,
    };
    sample_piece(&w, Some(&r), TS, &mut sink);
    let Sparse { samples, asked, .. } = sink;
    assert!(asked.len() >= 3, "{}", asked.len());
    let skipped: u64 = asked.iter().skip(1).step_by(2).map(|a| a.1).sum();
    assert!(skipped > 0);
    assert_eq!(samples.len() as u64 + skipped, dense.len() as u64);
    // The samples kept are dense ones, bit for bit (the walk steps over skipped runs).
    let mut d = dense.iter();
    for s in &samples {
        assert!(d.any(|x| x == s), "{s:?}");
    }
    // Every run's box holds the dense samples of the run: runs from each grid point,
    // of every length.
    let grid = Grid {
        work: &w,
        response: &r,
        period_s: TS,
    };
    let k0 = first_grid_index(w.commanded.t0_s, TS);
    let contains = |i: Interval, x: f64| i.lo <= x && x <= i.hi;
    for from in (1..dense.len()).step_by(7) {
        for len in [1, 2, 5, 17, 64, 200] {
            let to = (from + len).min(dense.len());
            let b = grid.states(k0 + from as i64 - 1, k0 + to as i64 - 2);
            for s in &dense[from..to] {
                for k in 0..3 {
                    assert!(contains(b.pos_mm[k], s.pos_mm[k]), "{k} {s:?} {b:?}");
                    assert!(contains(b.vel_mm_s[k], s.vel_mm_s[k]), "{k} {s:?} {b:?}");
                    assert!(contains(b.acc_mm_s2[k], s.acc_mm_s2[k]), "{k} {s:?} {b:?}");
                }
            }
        }
    }
}

#[test]
fn a_whole_piece_box_holds_every_sample_and_counts_them() {
    let (w, r) = ringing_piece();
    // With its end sample, starting on a grid point, a piece with no grid point, and
    // pieces shorter than half a swing, with and without their end sample.
    let on_grid = PieceWork {
        end_sample: true,
        ..w
    };
    let cut = |t0_s: f64, dt_s: f64, end_sample: bool| {
        let mut c = w;
        c.commanded.t0_s = t0_s;
        c.commanded.dt_s = dt_s;
        c.end_sample = end_sample;
        with_end(c, &r)
    };
    let short = cut(12.3452, 0.0003, false);
    let mut at_grid = w;
    at_grid.commanded.t0_s = 12.345;
    let swings = [cut(12.3452, 0.0074, false), cut(12.3452, 0.0091, true)];
    let contains = |i: Interval, x: f64| i.lo <= x && x <= i.hi;
    for w in &swings {
        // Tighter than the ringing's envelope over the piece.
        let (whole, envelope) = (
            piece_states(w, &r, TS, Fit::Swing),
            Grid {
                work: w,
                response: &r,
                period_s: TS,
            }
            .span(0.0, w.commanded.dt_s, Fit::Envelope),
        );
        for k in 0..2 {
            let width = |i: Interval| i.hi - i.lo;
            assert!(width(whole.acc_mm_s2[k]) < 0.8 * width(envelope.acc_mm_s2[k]));
        }
    }
    let mut shorts = 0;
    for w in [w, on_grid, short, at_grid, swings[0], swings[1], phased(w)] {
        let dense = samples(&w, Some(&r));
        let (b, count) = (piece_states(&w, &r, TS, Fit::Swing), piece_samples(&w, TS));
        assert_eq!(count, dense.len() as u64);
        for s in &dense {
            for k in 0..3 {
                assert!(contains(b.pos_mm[k], s.pos_mm[k]), "{k} {s:?} {b:?}");
                assert!(contains(b.vel_mm_s[k], s.vel_mm_s[k]), "{k} {s:?} {b:?}");
                assert!(contains(b.acc_mm_s2[k], s.acc_mm_s2[k]), "{k} {s:?} {b:?}");
            }
        }
        // Offered whole first, unless it has too few samples: a yes leaves every sample
        // out, a no takes them all.
        let offered = count >= SPARSE_MIN_SAMPLES;
        for skip in [true, false] {
            let mut sink = Sparse {
                samples: Vec::new(),
                asked: Vec::new(),
                skip: |_: &StateBox| skip,
                whole: true,
            };
            sample_piece(&w, Some(&r), TS, &mut sink);
            assert_eq!(sink.asked.first() == Some(&(b, count)), offered);
            let left_out = skip && offered;
            assert_eq!(
                sink.samples,
                if left_out { Vec::new() } else { dense.clone() }
            );
        }
        shorts += usize::from(!offered);
    }
    assert_eq!(shorts, 1, "the short piece is sampled without a bound");
}

#[test]
fn the_peak_candidates_are_samples() {
    let (w, r) = ringing_piece();
    let dense = samples(&w, Some(&r));
    let mut n = 0;
    peak_candidates(&w, &r, TS, |p, v, a| {
        n += 1;
        let close = |x: Vec3, y: Vec3| (x - y).norm() <= 1e-9 * (1.0 + y.norm());
        assert!(
            dense
                .iter()
                .any(|s| close(s.pos_mm, p) && close(s.vel_mm_s, v) && close(s.acc_mm_s2, a)),
            "{p} {v} {a}"
        );
    });
    assert_eq!(n, 4);
}

proptest::proptest! {
    /// A chain's count is its pieces' counts summed, whether each piece starts where the
    /// one before it ends (then the end's grid index is reused), on a grid point, or
    /// elsewhere (a re-homing); and it is the samples `sample_piece` takes. Contiguous
    /// pieces ending on a grid point (or a unit in the last place beside it), early in a
    /// print and hours into it, try the count of a whole chain; weeks into it, beyond
    /// `GRID_NEAR_MAX` periods, piece by piece.
    #[test]
    fn a_chains_count_is_its_pieces_counts(
        pieces in proptest::collection::vec(
            (0.0..0.004f64, 0u8..6, proptest::bool::ANY, 0u8..3),
            1..12,
        ),
        start in proptest::prop_oneof![0.0..0.01f64, 1e3..3e4f64, 2e6..3e6f64],
    ) {
        let mut t = start;
        let mut works = Vec::new();
        for (dt, kind, end_sample, changes) in pieces {
            // 0: contiguous; 1: starts on the next grid point; 2: a gap; 3: zero length;
            // 4 and 5: contiguous, ending on the next grid point or the one after.
            match kind {
                1 => t = (t / TS).ceil() * TS,
                2 => t += 0.0027,
                _ => {}
            }
            let dt = match kind {
                3 => 0.0,
                4 | 5 => ((t / TS).floor() + f64::from(kind - 3)) * TS - t,
                _ => dt,
            };
            let mut s = seg(t, dt, Vec3::zeros(), Vec3::zeros(), Vec3::zeros());
            // Phase changes: none, one inside, or one on the piece's first grid point
            // inside (if it has one) and one after it.
            let on_grid = first_inside(t, TS) as f64 * TS;
            let at: &[f64] = match changes {
                1 if dt > 0.0 => &[t + 0.4 * dt],
                2 if on_grid < t + 0.5 * dt => &[on_grid, t + 0.75 * dt],
                _ => &[],
            };
            for (i, &c) in at.iter().enumerate() {
                (s.changes.at_s[i], s.later_phases[i]) = (c, Phase::Decel);
            }
            works.push(work(s, Kicks::default(), end_sample));
            t = s.t1_s();
        }
        let summed: u64 = works.iter().map(|w| piece_samples(w, TS)).sum();
        let taken: usize = works.iter().map(|w| samples(w, None).len()).sum();
        proptest::prop_assert_eq!(move_samples(&works, TS, f64::INFINITY), Some(summed));
        // A piece longer than allowed: no count.
        let longest = works.iter().map(|w| w.commanded.dt_s).fold(0.0, f64::max);
        if longest > 0.0 {
            proptest::prop_assert_eq!(move_samples(&works, TS, 0.5 * longest), None);
        }
        proptest::prop_assert_eq!(summed, taken as u64);
    }

    /// The first grid index is the smallest k with k·Ts ≥ t, as the grid's times are
    /// computed (`k as f64 * Ts`), for times anywhere, on grid points and a few units in
    /// the last place beside them, with periods that are not powers of two.
    #[test]
    fn the_first_grid_index_is_the_smallest_at_or_after(
        k in -1_000_000i64..100_000_000,
        frac in 0.0..1.0f64,
        ulps in -3i64..=3,
        period in proptest::sample::select(vec![0.001, 0.0005, 0.00025, 0.003, 1.0 / 3000.0]),
    ) {
        for t in [(k as f64 + frac) * period, k as f64 * period] {
            let t = t + ulps as f64 * f64::EPSILON * t.abs();
            let i = first_grid_index(t, period);
            proptest::prop_assert!(i as f64 * period >= t, "{t} {i}");
            proptest::prop_assert!(((i - 1) as f64) * period < t, "{t} {i}");
        }
    }
}
