//! `S_CURVE_ACCELERATION`: the stepper's rate follows a quintic Bézier in time over each
//! acceleration and deceleration phase (`Stepper::_calc_bezier_curve_setup`,
//! `_eval_bezier_curve`): v(τ) = v0 + Δv·(10τ³ − 15τ⁴ + 6τ⁵), τ = t/T, over the trapezoid
//! phase's time T and distance, so the acceleration a·30τ²(1 − τ)² is 0 at both ends and
//! 1.875 a at the middle. A [`Ramp`] has a constant acceleration, so a phase is drawn as
//! [`SIDE_PIECES`] pieces on each side of a narrow middle piece: each side piece has the
//! Bézier's mean acceleration over its time (the rate is exact at its ends), the middle
//! piece the peak itself (so the peak is never under-reported), and the last piece ends on
//! the phase's exact step count.

use super::trapezoid::Ramp;

/// Pieces on each side of the middle piece.
pub const SIDE_PIECES: u32 = 8;
/// The middle piece spans τ ∈ [½ − h, ½ + h].
const MIDDLE_HALF_WIDTH: f64 = 0.005;
/// The Bézier's peak acceleration over the trapezoid's: 30/16.
pub const PEAK_RATIO: f64 = 1.875;

/// B(τ) = 10τ³ − 15τ⁴ + 6τ⁵: the share of the rate change made by τ.
fn share(tau: f64) -> f64 {
    tau * tau * tau * (10.0 + tau * (-15.0 + 6.0 * tau))
}

/// ∫₀^τ B: 2.5τ⁴ − 3τ⁵ + τ⁶ (½ at τ = 1).
fn share_integral(tau: f64) -> f64 {
    tau.powi(4) * (2.5 + tau * (-3.0 + tau))
}

/// The pieces of one trapezoid phase `r` (constant acceleration) as the Bézier runs it.
pub fn bezier(r: &Ramp, out: &mut Vec<Ramp>) {
    let t_total = r.dt_s;
    let dv = r.accel * t_total;
    let h = MIDDLE_HALF_WIDTH;
    let side = f64::from(SIDE_PIECES);
    let mut bounds: Vec<f64> = (0..=SIDE_PIECES)
        .map(|k| (0.5 - h) * f64::from(k) / side)
        .collect();
    bounds.extend((0..=SIDE_PIECES).map(|k| 0.5 + h + (0.5 - h) * f64::from(k) / side));
    let (mut s, mut v) = (r.s0, r.rate);
    let last = bounds.len() - 2;
    for (i, w) in bounds.windows(2).enumerate() {
        let (ta, tb) = (w[0], w[1]);
        let dt = (tb - ta) * t_total;
        let accel = if i == SIDE_PIECES as usize {
            // The middle piece, [½ − h, ½ + h]: the peak.
            PEAK_RATIO * r.accel
        } else if i == last {
            // The last ends on the phase's distance.
            let end = r.s0 + r.rate * t_total + dv * t_total * share_integral(1.0);
            2.0 * (end - s - v * dt) / (dt * dt)
        } else {
            // The rate exact at the piece's end: the mean acceleration (after the middle
            // piece, less its small excess).
            (r.rate + dv * share(tb) - v) / dt
        };
        let piece = Ramp {
            dt_s: dt,
            s0: s,
            rate: v,
            accel,
            phase: r.phase,
        };
        s = piece.s1();
        v += accel * dt;
        out.push(piece);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::motion::Phase;

    /// T3: Δv = 100 mm/s at 1000 mm/s² (T = 0.1 s): v(T/4) = 10.35 mm/s, v(T/2) = 50 mm/s,
    /// the peak 1875 mm/s² at T/2, the distance 5 mm as the trapezoid's.
    #[test]
    fn the_bezier_peaks_at_1_875_times_the_acceleration_over_the_same_time_and_distance() {
        let r = Ramp {
            dt_s: 0.1,
            s0: 2.0,
            rate: 0.0,
            accel: 1000.0,
            phase: Phase::Accel,
        };
        let mut out = Vec::new();
        bezier(&r, &mut out);
        assert_eq!(out.len(), 2 * SIDE_PIECES as usize + 1);
        let time: f64 = out.iter().map(|p| p.dt_s).sum();
        assert!((time - 0.1).abs() < 1e-15);
        let end = out.last().unwrap();
        assert!((end.s1() - 7.0).abs() < 1e-12, "{}", end.s1());
        let v_end = end.rate + end.accel * end.dt_s;
        // (The last piece lands on the exact distance; its rate ends within 10⁻⁵ of Δv.)
        assert!((v_end - 100.0).abs() < 1e-3, "{v_end}");
        let peak = out.iter().map(|p| p.accel).fold(f64::MIN, f64::max);
        assert_eq!(peak, 1875.0);
        // The piece with τ = ½ in it is the peak.
        let mut t = 0.0;
        for p in &out {
            if t <= 0.05 && 0.05 < t + p.dt_s {
                assert_eq!(p.accel, 1875.0);
            }
            t += p.dt_s;
        }
        // v(T/4) = 100·B(¼) = 10.35 mm/s: at the start of the 5th piece (τ = 0.2475) less
        // than that, and the rate at each side boundary exact.
        assert!((100.0 * share(0.25) - 10.3516).abs() < 1e-4);
        let fifth = out[4];
        assert!((fifth.rate - 100.0 * share(4.0 * 0.495 / 8.0)).abs() < 1e-9);
        // Position within 10 µm of the Bézier's anywhere (here in mm).
        let mut t = 0.0;
        for p in &out {
            let tau = (t + 0.5 * p.dt_s) / 0.1;
            let want = 2.0 + 100.0 * 0.1 * share_integral(tau);
            let (half, _) = (
                p.s0 + p.rate * 0.5 * p.dt_s + 0.125 * p.accel * p.dt_s * p.dt_s,
                0,
            );
            assert!((half - want).abs() < 1e-2, "{half} {want}");
            t += p.dt_s;
        }
    }
}
