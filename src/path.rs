//! The geometry of one commanded segment: a straight line or a circular (optionally
//! helical) arc, in nozzle coordinates of the bed frame, mm.
//!
//! A path is parameterised by u ∈ [0, 1]. The resampler steps u with the paper's Taylor
//! step (eq. 19), which needs p(u), dp/du and d²p/du²; the planner needs the length, the end
//! tangents (for junctions) and the smallest radius of curvature (for the v²/r ≤ a cap).

use nalgebra::Vector3;

/// A position, velocity or acceleration in the bed frame (mm, mm/s, mm/s²).
pub type Vec3 = Vector3<f64>;

/// A circular arc in the XY plane with a linear Z rise (a helix when `z_delta_mm` ≠ 0).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Arc {
    /// Centre of the circle in XY, mm.
    pub center_mm: [f64; 2],
    /// Radius of the circle, mm (> 0).
    pub radius_mm: f64,
    /// Polar angle of the start point around the centre, rad.
    pub start_angle_rad: f64,
    /// Signed swept angle: positive counter-clockwise (G3), negative clockwise (G2).
    pub sweep_rad: f64,
    /// Z at the start, mm.
    pub z_start_mm: f64,
    /// Z rise over the whole arc, mm.
    pub z_delta_mm: f64,
}

/// A curve's position p(u) and its derivatives dp/du, d²p/du² at one parameter (mm).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Jet {
    pub p: Vec3,
    pub d1: Vec3,
    pub d2: Vec3,
}

/// The geometry of one segment.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Path {
    Line { start: Vec3, end: Vec3 },
    Arc(Arc),
}

impl Path {
    /// A straight segment from `start` to `end`.
    pub fn line(start: Vec3, end: Vec3) -> Self {
        Path::Line { start, end }
    }

    /// Position and first two derivatives at parameter u ∈ [0, 1], together: an arc's
    /// angle, sine and cosine are computed once for all three.
    #[inline(always)]
    pub fn jet(&self, u: f64) -> Jet {
        match self {
            Path::Line { start, end } => {
                let d1 = end - start;
                Jet {
                    p: start + d1 * u,
                    d1,
                    d2: Vec3::zeros(),
                }
            }
            Path::Arc(a) => {
                let th = a.start_angle_rad + a.sweep_rad * u;
                let (sin, cos) = th.sin_cos();
                let (r, w) = (a.radius_mm, a.sweep_rad);
                Jet {
                    p: Vec3::new(
                        a.center_mm[0] + r * cos,
                        a.center_mm[1] + r * sin,
                        a.z_start_mm + a.z_delta_mm * u,
                    ),
                    d1: Vec3::new(-w * r * sin, w * r * cos, a.z_delta_mm),
                    d2: Vec3::new(-w * w * r * cos, -w * w * r * sin, 0.0),
                }
            }
        }
    }

    /// Position at parameter u ∈ [0, 1].
    #[inline(always)]
    pub fn point(&self, u: f64) -> Vec3 {
        self.jet(u).p
    }

    /// First derivative dp/du (its norm is the path length for both kinds).
    #[inline(always)]
    pub fn d1(&self, u: f64) -> Vec3 {
        self.jet(u).d1
    }

    /// Second derivative d²p/du².
    #[inline(always)]
    pub fn d2(&self, u: f64) -> Vec3 {
        self.jet(u).d2
    }

    pub fn start(&self) -> Vec3 {
        self.point(0.0)
    }

    pub fn end(&self) -> Vec3 {
        match self {
            Path::Line { end, .. } => *end,
            Path::Arc(_) => self.point(1.0),
        }
    }

    /// Arc length, mm. For both kinds |dp/du| is constant, so length = |dp/du|.
    pub fn length_mm(&self) -> f64 {
        self.d1(0.0).norm()
    }

    /// Unit tangent at the start (zero for a zero-length path).
    pub fn start_dir(&self) -> Vec3 {
        unit(self.d1(0.0))
    }

    /// Unit tangent at the end (zero for a zero-length path).
    pub fn end_dir(&self) -> Vec3 {
        unit(self.d1(1.0))
    }

    /// Smallest radius of curvature along the path, mm (infinite for a line).
    /// For a helix of radius r, swept angle θ and rise h: r + h²/(r·θ²).
    pub fn min_radius_mm(&self) -> f64 {
        match self {
            Path::Line { .. } => f64::INFINITY,
            Path::Arc(a) => {
                let th2 = a.sweep_rad * a.sweep_rad;
                if th2 == 0.0 {
                    f64::INFINITY
                } else {
                    a.radius_mm + a.z_delta_mm * a.z_delta_mm / (a.radius_mm * th2)
                }
            }
        }
    }

    /// Largest distance of the path from the Z axis, squared (mm²): the planner's and the
    /// report's "outside the print radius" test.
    pub fn max_xy2_mm2(&self) -> f64 {
        self.max_dist2_from_mm2([0.0, 0.0])
    }

    /// Largest horizontal distance of the path from the vertical line through `xy`, squared
    /// (mm²): the farthest point from the Z axis, or from a tower.
    pub fn max_dist2_from_mm2(&self, xy: [f64; 2]) -> f64 {
        let d2 = |p: Vec3| (p.x - xy[0]).powi(2) + (p.y - xy[1]).powi(2);
        let ends = d2(self.start()).max(d2(self.end()));
        match self {
            Path::Line { .. } => ends,
            Path::Arc(a) => {
                let (cx, cy) = (a.center_mm[0] - xy[0], a.center_mm[1] - xy[1]);
                let c = cx.hypot(cy);
                // The farthest point of the full circle lies at the centre's polar angle
                // (seen from `xy`); it counts only when the arc sweeps over it.
                if c == 0.0 {
                    a.radius_mm * a.radius_mm
                } else if sweeps_over(a, cy.atan2(cx)) {
                    ends.max((c + a.radius_mm).powi(2))
                } else {
                    ends
                }
            }
        }
    }

    /// Lowest z of the path, mm (z is linear along lines and helices).
    pub fn min_z_mm(&self) -> f64 {
        self.start().z.min(self.end().z)
    }
}

fn unit(v: Vec3) -> Vec3 {
    let n = v.norm();
    if n > 0.0 { v / n } else { Vec3::zeros() }
}

/// Whether the arc passes through polar angle `angle` (about its own centre).
fn sweeps_over(a: &Arc, angle: f64) -> bool {
    use std::f64::consts::TAU;
    if a.sweep_rad.abs() >= TAU {
        return true;
    }
    let rel = (angle - a.start_angle_rad).rem_euclid(TAU);
    if a.sweep_rad >= 0.0 {
        rel <= a.sweep_rad
    } else {
        TAU - rel <= -a.sweep_rad || rel == 0.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::{FRAC_PI_2, PI};

    fn helix() -> Path {
        Path::Arc(Arc {
            center_mm: [10.0, -5.0],
            radius_mm: 20.0,
            start_angle_rad: 0.3,
            sweep_rad: -1.7 * PI,
            z_start_mm: 0.2,
            z_delta_mm: 3.0,
        })
    }

    #[test]
    fn derivatives_match_finite_differences() {
        let p = helix();
        let h = 1e-5;
        for &u in &[0.0, 0.25, 0.6, 1.0] {
            let fd1 = (p.point(u + h) - p.point(u - h)) / (2.0 * h);
            let fd2 = (p.point(u + h) - 2.0 * p.point(u) + p.point(u - h)) / (h * h);
            assert!((fd1 - p.d1(u)).norm() < 1e-6 * p.d1(u).norm(), "d1 at {u}");
            assert!(
                (fd2 - p.d2(u)).norm() < 1e-3,
                "d2 at {u}: {fd2} vs {}",
                p.d2(u)
            );
        }
    }

    #[test]
    fn arc_length_matches_polyline() {
        let p = helix();
        let n = 20_000;
        let poly: f64 = (0..n)
            .map(|i| (p.point((i + 1) as f64 / n as f64) - p.point(i as f64 / n as f64)).norm())
            .sum();
        assert!((poly - p.length_mm()).abs() < 1e-6 * poly);
    }

    #[test]
    fn helix_curvature_radius_matches_formula() {
        // κ = |p' × p''| / |p'|³; radius = 1/κ.
        let p = helix();
        let (d1, d2) = (p.d1(0.4), p.d2(0.4));
        let r = d1.norm().powi(3) / d1.cross(&d2).norm();
        assert!((r - p.min_radius_mm()).abs() < 1e-9 * r);
    }

    #[test]
    fn max_radius_of_arc_through_far_side() {
        // Quarter circle around (10, 0), radius 5, from angle -45° to +45°: passes angle 0,
        // the point (15, 0).
        let a = Path::Arc(Arc {
            center_mm: [10.0, 0.0],
            radius_mm: 5.0,
            start_angle_rad: -FRAC_PI_2 / 2.0,
            sweep_rad: FRAC_PI_2,
            z_start_mm: 0.0,
            z_delta_mm: 0.0,
        });
        assert!((a.max_xy2_mm2() - 225.0).abs() < 1e-9);
        // The same arc clockwise from +45° to -45° passes it too.
        let b = Path::Arc(Arc {
            start_angle_rad: FRAC_PI_2 / 2.0,
            sweep_rad: -FRAC_PI_2,
            ..match a {
                Path::Arc(a) => a,
                Path::Line { .. } => unreachable!(),
            }
        });
        assert!((b.max_xy2_mm2() - 225.0).abs() < 1e-9);
        // The far side (angle π) is not swept: the largest radius is at an end.
        let l = Path::line(Vec3::new(3.0, 4.0, 0.0), Vec3::new(0.0, 1.0, 0.0));
        assert_eq!(l.max_xy2_mm2(), 25.0);
        // Seen from (20, 0), the arc's farthest point is at angle π: (5, 0), 15 mm away,
        // which the arc does not sweep; its ends are √((20−13.536)² + 3.536²) away.
        let end = 10.0 + 5.0 * (FRAC_PI_2 / 2.0).cos();
        let expect = (20.0 - end).powi(2) + (5.0 * (FRAC_PI_2 / 2.0).sin()).powi(2);
        assert!((a.max_dist2_from_mm2([20.0, 0.0]) - expect).abs() < 1e-9);
        // Seen from (0, 0) it is the far side again; from (10, 0), the centre, the radius.
        assert!((a.max_dist2_from_mm2([0.0, 0.0]) - 225.0).abs() < 1e-9);
        assert!((a.max_dist2_from_mm2([10.0, 0.0]) - 25.0).abs() < 1e-9);
    }

    #[test]
    fn tangents() {
        let l = Path::line(Vec3::zeros(), Vec3::new(3.0, 4.0, 0.0));
        assert!((l.start_dir() - Vec3::new(0.6, 0.8, 0.0)).norm() < 1e-15);
        let z = Path::line(Vec3::zeros(), Vec3::zeros());
        assert_eq!(z.start_dir(), Vec3::zeros());
        assert_eq!(z.length_mm(), 0.0);
    }
}
