//! The geometry of one move: a straight segment in nozzle coordinates of the bed frame, mm.
//! (The firmware cuts arcs into such chords before planning them: `gcode::arc`.)
//!
//! A path is parameterised by u ∈ [0, 1]; the planner needs its length and direction, the
//! checks its extent on the bed.

use nalgebra::Vector3;

use crate::interval::{greater, lesser};

/// A position, velocity or acceleration in the bed frame (mm, mm/s, mm/s²).
pub type Vec3 = Vector3<f64>;

/// A curve's position p(u) and its derivatives dp/du, d²p/du² at one parameter (mm).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Jet {
    pub p: Vec3,
    pub d1: Vec3,
    pub d2: Vec3,
}

/// A straight segment from `start` to `end`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Path {
    pub start: Vec3,
    pub end: Vec3,
}

impl Path {
    /// A straight segment from `start` to `end`.
    pub fn line(start: Vec3, end: Vec3) -> Self {
        Path { start, end }
    }

    /// Position and first two derivatives at parameter u ∈ [0, 1].
    #[inline(always)]
    pub fn jet(&self, u: f64) -> Jet {
        let d1 = self.end - self.start;
        Jet {
            p: self.start + d1 * u,
            d1,
            d2: Vec3::zeros(),
        }
    }

    /// Position at parameter u ∈ [0, 1].
    #[inline(always)]
    pub fn point(&self, u: f64) -> Vec3 {
        self.start + (self.end - self.start) * u
    }

    pub fn start(&self) -> Vec3 {
        self.start
    }

    pub fn end(&self) -> Vec3 {
        self.end
    }

    /// Length, mm.
    pub fn length_mm(&self) -> f64 {
        (self.end - self.start).norm()
    }

    /// Unit direction (zero for a zero-length path).
    pub fn dir(&self) -> Vec3 {
        let n = self.length_mm();
        if n > 0.0 { self.unit(n) } else { Vec3::zeros() }
    }

    /// The unit direction of a path whose [`Self::length_mm`] is `length_mm` (not 0): the
    /// bits of [`Self::dir`], without computing the length again.
    pub fn unit(&self, length_mm: f64) -> Vec3 {
        (self.end - self.start) / length_mm
    }

    /// Whether the path moves in XY.
    pub fn moves_xy(&self) -> bool {
        self.start.x != self.end.x || self.start.y != self.end.y
    }

    /// Largest distance of the path from the Z axis, squared (mm²): the planner's and the
    /// report's "outside the print radius" test.
    pub fn max_xy2_mm2(&self) -> f64 {
        self.max_dist2_from_mm2([0.0, 0.0])
    }

    /// Largest horizontal distance of the path from the vertical line through `xy`, squared
    /// (mm²): the farthest point of a segment is one of its ends.
    pub fn max_dist2_from_mm2(&self, xy: [f64; 2]) -> f64 {
        let d2 = |p: Vec3| (p.x - xy[0]).powi(2) + (p.y - xy[1]).powi(2);
        // Plain comparisons: a path is finite (the parser bounds every number).
        greater(d2(self.start), d2(self.end))
    }

    /// Lowest z of the path, mm.
    pub fn min_z_mm(&self) -> f64 {
        lesser(self.start.z, self.end.z)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn length_direction_and_extent() {
        let l = Path::line(Vec3::new(3.0, 4.0, 1.0), Vec3::new(0.0, 1.0, 2.0));
        assert!((l.length_mm() - 19.0_f64.sqrt()).abs() < 1e-15);
        assert!((l.dir() * l.length_mm() - (l.end - l.start)).norm() < 1e-15);
        assert_eq!(l.max_xy2_mm2(), 25.0);
        assert_eq!(l.max_dist2_from_mm2([3.0, 1.0]), 9.0);
        assert_eq!(l.min_z_mm(), 1.0);
        assert_eq!(l.point(0.5), Vec3::new(1.5, 2.5, 1.5));
        let z = Path::line(Vec3::zeros(), Vec3::zeros());
        assert_eq!(z.dir(), Vec3::zeros());
        assert!(!z.moves_xy());
    }
}
