//! *When* a move is sampled: the instants of the span a move owns (see `sampler`), in time
//! order, without knowing what the state is at them.

/// Smallest k with k·Ts ≥ t (the grid time is always computed as `k as f64 * period_s`).
pub(super) fn first_grid_index(t: f64, period_s: f64) -> i64 {
    // ⌈t/Ts⌉ without `f64::ceil`, a library call on baseline x86-64.
    let q = t / period_s;
    let mut k = q as i64;
    if (k as f64) < q {
        k += 1;
    }
    while (k as f64) * period_s < t {
        k += 1;
    }
    while ((k - 1) as f64) * period_s >= t {
        k -= 1;
    }
    k
}

/// One instant (or run of instants) of a schedule.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) enum Tick {
    /// A sample at `t_s` in the phase in force: the junction at the start, a grid point, a
    /// boundary's left limit, or the end of the span.
    At { t_s: f64 },
    /// Phase boundary `index` (into the boundaries given to [`Schedule::new`]) is crossed:
    /// the next `At`, at the same time, is its right limit.
    Cross { index: usize },
    /// The grid points k0·Ts … (k0 + len − 1)·Ts, all in the phase in force and inside the
    /// plain window: they may be computed as a run.
    Run { k0: i64, len: usize },
}

/// The instants of a span [t0, t_end] on the global grid k·Ts:
/// 1. the start t0 (a grid point exactly at t0 is this sample, not a second one);
/// 2. every grid point with t0 < k·Ts < t_end;
/// 3. at each phase boundary tb with t0 < tb < t_end, the left limit then (after a
///    [`Tick::Cross`]) the right limit, both at tb; a grid point exactly at tb is that pair;
/// 4. the end t_end.
///
/// Grid points inside the plain window (if any) come as [`Tick::Run`]s when more than none
/// lie before the next boundary; the others one [`Tick::At`] each. An empty span (t_end ≤
/// t0) has only its start.
pub(super) struct Schedule {
    period_s: f64,
    t_end: f64,
    bounds: [f64; 2],
    n_bounds: usize,
    /// Grid points in [from, to) may come as runs.
    plain: Option<(f64, f64)>,
    /// Index of the next grid point to visit.
    k: i64,
    /// Index of the next boundary to cross.
    b: usize,
    /// The instant of the last (or pending) `At`.
    t_s: f64,
    /// An `At { t_s }` is due.
    at_due: bool,
    /// The last `At` was a boundary's left limit: its `Cross` is due.
    cross_due: bool,
    /// The last `At` was the end of the span.
    done: bool,
}

impl Schedule {
    /// The schedule of [t0, t_end] with the given phase boundaries (strictly inside, in
    /// order, at most two). `period_s` must be positive and finite.
    pub(super) fn new(
        t0: f64,
        t_end: f64,
        bounds: &[f64],
        period_s: f64,
        plain: Option<(f64, f64)>,
    ) -> Self {
        let mut k = first_grid_index(t0, period_s);
        if k as f64 * period_s <= t0 {
            k += 1; // the grid point at t0 is the start sample
        }
        let mut b = [0.0; 2];
        let n_bounds = bounds.len().min(2);
        b[..n_bounds].copy_from_slice(&bounds[..n_bounds]);
        Schedule {
            period_s,
            t_end,
            bounds: b,
            n_bounds,
            plain,
            k,
            b: 0,
            t_s: t0,
            at_due: true,
            cross_due: false,
            done: t_end <= t0,
        }
    }
}

impl Iterator for Schedule {
    type Item = Tick;

    fn next(&mut self) -> Option<Tick> {
        if self.at_due {
            self.at_due = false;
            return Some(Tick::At { t_s: self.t_s });
        }
        if self.done {
            return None;
        }
        if self.cross_due {
            self.cross_due = false;
            self.at_due = true;
            return Some(Tick::Cross { index: self.b - 1 });
        }
        let next_bound = (self.b < self.n_bounds).then(|| self.bounds[self.b]);
        let ts = self.period_s;
        if let Some((from, to)) = self.plain
            && self.k as f64 * ts >= from
        {
            let limit = next_bound.unwrap_or(self.t_end).min(to);
            let k_end = first_grid_index(limit, ts);
            if k_end > self.k {
                let run = Tick::Run {
                    k0: self.k,
                    len: (k_end - self.k) as usize,
                };
                self.k = k_end;
                return Some(run);
            }
        }
        let tg = self.k as f64 * ts;
        match next_bound {
            Some(tb) if tb <= tg => {
                self.t_s = tb;
                self.b += 1;
                if tb == tg {
                    self.k += 1;
                }
                self.cross_due = true;
            }
            _ if tg >= self.t_end => {
                self.t_s = self.t_end;
                self.done = true;
            }
            _ => {
                self.t_s = tg;
                self.k += 1;
            }
        }
        Some(Tick::At { t_s: self.t_s })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const TS: f64 = 0.001;

    fn ticks(t0: f64, t_end: f64, bounds: &[f64], plain: Option<(f64, f64)>) -> Vec<Tick> {
        Schedule::new(t0, t_end, bounds, TS, plain).collect()
    }

    #[test]
    fn start_grid_boundary_pair_and_end() {
        use Tick::*;
        // Span [0.0005, 0.0032] with a boundary on the grid point 0.002: that grid point
        // is the pair, not a third sample.
        let t = ticks(0.0005, 0.0032, &[0.002], None);
        assert_eq!(
            t,
            [
                At { t_s: 0.0005 },
                At { t_s: 0.001 },
                At { t_s: 0.002 },
                Cross { index: 0 },
                At { t_s: 0.002 },
                At { t_s: 0.003 },
                At { t_s: 0.0032 },
            ]
        );
        // A start on a grid point is the start sample only; an empty span has only it.
        assert_eq!(
            ticks(0.002, 0.0025, &[], None)[..2],
            [At { t_s: 0.002 }, At { t_s: 0.0025 }]
        );
        assert_eq!(ticks(0.002, 0.002, &[], None), [At { t_s: 0.002 }]);
    }

    #[test]
    fn plain_grid_points_come_as_runs_up_to_the_next_boundary() {
        use Tick::*;
        let t = ticks(0.0, 0.0101, &[0.0055], Some((0.0005, 0.0096)));
        assert_eq!(
            t,
            [
                At { t_s: 0.0 },
                Run { k0: 1, len: 5 },
                At { t_s: 0.0055 },
                Cross { index: 0 },
                At { t_s: 0.0055 },
                Run { k0: 6, len: 4 },
                At { t_s: 0.01 },
                At { t_s: 0.0101 },
            ]
        );
    }

    #[test]
    fn first_grid_index_is_the_ceiling_in_grid_arithmetic() {
        assert_eq!(first_grid_index(0.0, TS), 0);
        assert_eq!(first_grid_index(0.0030000001, TS), 4);
        // 3·0.001 is 0.003 in floating point; 0.003 itself is the grid point.
        assert_eq!(first_grid_index(3.0 * TS, TS), 3);
        for k in [1_i64, 7, 1234, 98_765_432] {
            let t = k as f64 * TS;
            assert_eq!(first_grid_index(t, TS), k);
            assert_eq!(first_grid_index(t + 1e-12 * t.max(1.0), TS), k + 1);
        }
    }
}
