//! G2/G3 geometry: centre from I/J or R, signed sweep, helical Z.

use std::f64::consts::TAU;

use crate::path::{Arc, Vec3};

/// End points closer than this (mm, in XY) make an I/J arc a full circle.
pub const FULL_CIRCLE_MM: f64 = 1e-6;

/// Allowed difference between the start and end radius: this absolute part (mm) plus
/// [`RADIUS_REL_TOL`] times the radius. Beyond it the arc is reported (the firmware still
/// runs it with the start radius, as here).
pub const RADIUS_ABS_TOL_MM: f64 = 0.01;
pub const RADIUS_REL_TOL: f64 = 1e-3;

/// How the centre of an arc is given.
#[derive(Clone, Copy, Debug)]
pub enum Centre {
    /// I/J: offset of the centre from the start point, mm.
    Offset([f64; 2]),
    /// R: radius, mm; negative selects the arc longer than a half turn (Marlin).
    Radius(f64),
}

/// Why an arc cannot be built.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ArcError {
    /// The centre coincides with the start point.
    ZeroRadius,
    /// R form: the end point is farther than 2|R| from the start, by this much (mm).
    RadiusTooSmall(f64),
    /// R form with the end point equal to the start: the centre is undefined.
    RadiusFullCircle,
}

/// The arc from `start` to `end` (XY circle, linear Z) and the start/end radius mismatch,
/// mm. `clockwise` is G2; `turns` adds whole extra circles (Marlin's P).
pub fn arc(
    start: Vec3,
    end: Vec3,
    centre: Centre,
    clockwise: bool,
    turns: u32,
) -> Result<(Arc, f64), ArcError> {
    let (dx, dy) = (end.x - start.x, end.y - start.y);
    let chord = dx.hypot(dy);
    let offset = match centre {
        Centre::Offset(o) => o,
        Centre::Radius(r) => {
            if chord < FULL_CIRCLE_MM {
                return Err(ArcError::RadiusFullCircle);
            }
            let h2 = r * r - chord * chord / 4.0;
            let h = if h2 >= 0.0 {
                h2.sqrt()
            } else if chord / 2.0 - r.abs() <= RADIUS_ABS_TOL_MM + RADIUS_REL_TOL * r.abs() {
                // Rounding in the file: the half-circle.
                0.0
            } else {
                return Err(ArcError::RadiusTooSmall(chord / 2.0 - r.abs()));
            };
            // Centre to the left of the chord for a short counter-clockwise arc; right for
            // clockwise; a negative R takes the other side (the long arc).
            let side = if clockwise == (r < 0.0) { 1.0 } else { -1.0 };
            let (lx, ly) = (-dy / chord, dx / chord);
            [dx / 2.0 + side * h * lx, dy / 2.0 + side * h * ly]
        }
    };
    let radius = offset[0].hypot(offset[1]);
    if radius == 0.0 {
        return Err(ArcError::ZeroRadius);
    }
    let center = [start.x + offset[0], start.y + offset[1]];
    // Vectors from the centre to the start and to the end.
    let (sx, sy) = (-offset[0], -offset[1]);
    let (ex, ey) = (end.x - center[0], end.y - center[1]);
    let end_radius = ex.hypot(ey);
    let raw = (sx * ey - sy * ex).atan2(sx * ex + sy * ey);
    let mut sweep = match (chord < FULL_CIRCLE_MM, clockwise) {
        (true, false) => TAU,
        (true, true) => -TAU,
        (false, false) if raw <= 0.0 => raw + TAU,
        (false, true) if raw >= 0.0 => raw - TAU,
        _ => raw,
    };
    let extra = f64::from(turns) * TAU;
    sweep += if clockwise { -extra } else { extra };
    Ok((
        Arc {
            center_mm: center,
            radius_mm: radius,
            start_angle_rad: sy.atan2(sx),
            sweep_rad: sweep,
            z_start_mm: start.z,
            z_delta_mm: end.z - start.z,
        },
        (end_radius - radius).abs(),
    ))
}

/// Whether a start/end radius difference is beyond the tolerance.
pub fn radius_mismatch(radius_mm: f64, mismatch_mm: f64) -> bool {
    mismatch_mm > RADIUS_ABS_TOL_MM + RADIUS_REL_TOL * radius_mm
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::path::Path;
    use std::f64::consts::{FRAC_PI_2, PI};

    fn v(x: f64, y: f64, z: f64) -> Vec3 {
        Vec3::new(x, y, z)
    }

    #[test]
    fn flsun_helix_quarter_turn() {
        // G1 X-98 Y0 Z0.2, then G3 X0 Y-98 I98 Z0.2: centre (0,0), counter-clockwise
        // from 180° to 270°: a quarter turn.
        let (a, mis) = arc(
            v(-98.0, 0.0, 0.2),
            v(0.0, -98.0, 0.2),
            Centre::Offset([98.0, 0.0]),
            false,
            0,
        )
        .unwrap();
        assert_eq!(a.center_mm, [0.0, 0.0]);
        assert_eq!(a.radius_mm, 98.0);
        assert!((a.sweep_rad - FRAC_PI_2).abs() < 1e-12);
        assert!(mis < 1e-12);
        let p = Path::Arc(a);
        assert!((p.end() - v(0.0, -98.0, 0.2)).norm() < 1e-9);
        // The midpoint lies at 225°.
        let m = p.point(0.5);
        let h = 98.0 / 2f64.sqrt();
        assert!((m - v(-h, -h, 0.2)).norm() < 1e-9);
    }

    #[test]
    fn clockwise_is_negative_and_helical_z() {
        let (a, _) = arc(
            v(10.0, 0.0, 1.0),
            v(0.0, 10.0, 3.0),
            Centre::Offset([-10.0, 0.0]),
            true,
            0,
        )
        .unwrap();
        // Clockwise from 0° to 90° is three quarters of a turn.
        assert!((a.sweep_rad + 1.5 * PI).abs() < 1e-12);
        assert_eq!((a.z_start_mm, a.z_delta_mm), (1.0, 2.0));
        let p = Path::Arc(a);
        // Passing 270° = (0, -10) at u = 1/3, z one third up.
        assert!((p.point(1.0 / 3.0) - v(0.0, -10.0, 1.0 + 2.0 / 3.0)).norm() < 1e-9);
    }

    #[test]
    fn full_circles_and_turns() {
        let s = v(5.0, 0.0, 0.0);
        let (a, _) = arc(s, s, Centre::Offset([-5.0, 0.0]), false, 0).unwrap();
        assert_eq!(a.sweep_rad, TAU);
        let (a, _) = arc(s, s, Centre::Offset([-5.0, 0.0]), true, 0).unwrap();
        assert_eq!(a.sweep_rad, -TAU);
        let (a, _) = arc(s, v(0.0, 5.0, 0.0), Centre::Offset([-5.0, 0.0]), false, 2).unwrap();
        assert!((a.sweep_rad - (FRAC_PI_2 + 2.0 * TAU)).abs() < 1e-12);
    }

    #[test]
    fn radius_form_both_sides() {
        // From (0,0) to (10,0) with R5: a half circle, centre (5,0).
        let (a, _) = arc(
            v(0.0, 0.0, 0.0),
            v(10.0, 0.0, 0.0),
            Centre::Radius(5.0),
            true,
            0,
        )
        .unwrap();
        assert!((a.center_mm[0] - 5.0).abs() < 1e-12 && a.center_mm[1].abs() < 1e-12);
        // R = 5√2 from (0,0) to (10,0): the centre is at (5, ±5). Counter-clockwise short
        // arc: centre on the left of the chord, (5, 5); a quarter turn.
        let r = 50f64.sqrt();
        let (a, _) = arc(
            v(0.0, 0.0, 0.0),
            v(10.0, 0.0, 0.0),
            Centre::Radius(r),
            false,
            0,
        )
        .unwrap();
        assert!((a.center_mm[0] - 5.0).abs() < 1e-12 && (a.center_mm[1] - 5.0).abs() < 1e-12);
        assert!((a.sweep_rad - FRAC_PI_2).abs() < 1e-12);
        // Clockwise short arc: centre (5, -5), sweep -90°.
        let (a, _) = arc(
            v(0.0, 0.0, 0.0),
            v(10.0, 0.0, 0.0),
            Centre::Radius(r),
            true,
            0,
        )
        .unwrap();
        assert!((a.center_mm[1] + 5.0).abs() < 1e-12);
        assert!((a.sweep_rad + FRAC_PI_2).abs() < 1e-12);
        // Negative R: the long way round, three quarters.
        let (a, _) = arc(
            v(0.0, 0.0, 0.0),
            v(10.0, 0.0, 0.0),
            Centre::Radius(-r),
            false,
            0,
        )
        .unwrap();
        assert!((a.sweep_rad - 1.5 * PI).abs() < 1e-12);
        assert!(matches!(
            arc(
                v(0.0, 0.0, 0.0),
                v(10.0, 0.0, 0.0),
                Centre::Radius(4.0),
                false,
                0
            ),
            Err(ArcError::RadiusTooSmall(_))
        ));
    }

    #[test]
    fn mismatch_is_measured() {
        let (a, mis) = arc(
            v(10.0, 0.0, 0.0),
            v(0.0, 10.5, 0.0),
            Centre::Offset([-10.0, 0.0]),
            false,
            0,
        )
        .unwrap();
        assert!((mis - 0.5).abs() < 1e-12);
        assert!(radius_mismatch(a.radius_mm, mis));
        assert!(!radius_mismatch(10.0, 0.015));
        assert_eq!(
            arc(
                v(1.0, 1.0, 0.0),
                v(2.0, 2.0, 0.0),
                Centre::Offset([0.0, 0.0]),
                false,
                0
            )
            .unwrap_err(),
            ArcError::ZeroRadius
        );
    }
}
