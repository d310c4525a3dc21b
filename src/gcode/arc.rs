//! G2/G3 as the firmware runs them: cut into straight chords, each an ordinary move.
//! Klipper's rules are those of klippy/extras/gcode_arcs.py (`planArc`); Marlin's those of
//! `plan_arc` (Marlin/src/gcode/motion/G2_G3.cpp, 2.1.2.x): [`MarlinChords`].

use std::f64::consts::TAU;

use crate::path::Vec3;

/// The plane of G2/G3: G17 (XY, centre from I and J), G18 (XZ, from I and K) or G19 (YZ,
/// from J and K); the third axis moves linearly (a helix).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Plane {
    Xy,
    Xz,
    Yz,
}

impl Plane {
    /// The axes (0 = X) of the plane's two coordinates and of the helical axis.
    pub fn axes(self) -> [usize; 3] {
        match self {
            Plane::Xy => [0, 1, 2],
            Plane::Xz => [0, 2, 1],
            Plane::Yz => [1, 2, 0],
        }
    }

    /// The letters of the centre offset in this plane.
    pub fn offset_letters(self) -> [u8; 2] {
        match self {
            Plane::Xy => [b'I', b'J'],
            Plane::Xz => [b'I', b'K'],
            Plane::Yz => [b'J', b'K'],
        }
    }
}

/// How the firmware cuts arcs into chords.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ArcRules {
    /// Klipper's `[gcode_arcs]`: chords of `resolution` mm (default 1).
    Klipper { resolution_mm: f64 },
    /// Marlin's `plan_arc` with its `ARC_SUPPORT` settings (the profile's `marlin:`
    /// section; defaults in `machine::defaults`, `MARLIN_*ARC*`).
    Marlin {
        /// `MAX_ARC_SEGMENT_MM`.
        max_segment_mm: f64,
        /// `MIN_ARC_SEGMENT_MM`.
        min_segment_mm: f64,
        /// `MIN_CIRCLE_SEGMENTS`.
        min_circle_segments: u32,
        /// `ARC_SEGMENTS_PER_SEC` (0: not defined).
        segments_per_sec: f64,
        /// `N_ARC_CORRECTION`.
        n_arc_correction: u32,
    },
}

/// An arc cut into more chords than this is refused: no printable arc comes near it (a
/// full turn of radius 15 m at 0.1 mm), a wrong number in the file can (R1e9).
pub const MAX_CHORDS: u64 = 1_000_000;

/// Klipper's `[gcode_arcs] resolution` default, mm.
pub const KLIPPER_ARC_RESOLUTION_MM: f64 = 1.0;

impl Default for ArcRules {
    fn default() -> Self {
        ArcRules::Klipper {
            resolution_mm: KLIPPER_ARC_RESOLUTION_MM,
        }
    }
}

/// The chords of one arc: their end points, in the coordinates `start` and `target` are
/// given in (the G-code's). The last chord ends exactly at `target`.
#[derive(Clone, Copy, Debug)]
pub struct Chords {
    /// Centre of the circle in the plane's two coordinates.
    centre: [f64; 2],
    /// −offset: the start point seen from the centre.
    radius_vec: [f64; 2],
    theta_per_chord: f64,
    helix_start: f64,
    helix_per_chord: f64,
    axes: [usize; 3],
    target: Vec3,
    count: u64,
    next: u64,
}

impl Chords {
    /// gcode_arcs.py `planArc`: the angular travel from the atan2 of the start and end
    /// vectors (a full turn when start and end coincide and the angle is 0), counter-
    /// clockwise positive; max(1, ⌊length / resolution⌋) chords, the length counting the
    /// helical rise.
    pub fn klipper(
        start: Vec3,
        target: Vec3,
        offset: [f64; 2],
        clockwise: bool,
        plane: Plane,
        resolution_mm: f64,
    ) -> Chords {
        let axes = plane.axes();
        let [a, b, h] = axes;
        let (r_p, r_q) = (-offset[0], -offset[1]);
        let centre = [start[a] - r_p, start[b] - r_q];
        let (rt_a, rt_b) = (target[a] - centre[0], target[b] - centre[1]);
        let mut angular = (r_p * rt_b - r_q * rt_a).atan2(r_p * rt_a + r_q * rt_b);
        if angular < 0.0 {
            angular += TAU;
        }
        if clockwise {
            angular -= TAU;
        }
        if angular == 0.0 && start[a] == target[a] && start[b] == target[b] {
            angular = TAU;
        }
        let linear = target[h] - start[h];
        let flat = r_p.hypot(r_q) * angular;
        let travel = if linear != 0.0 {
            flat.hypot(linear)
        } else {
            flat.abs()
        };
        let count = (travel / resolution_mm).floor().max(1.0);
        // Not a finite number of chords, or too many: `chord_count` says so (0 chords).
        let count = if count.is_finite() && count <= MAX_CHORDS as f64 {
            count
        } else {
            0.0
        };
        Chords {
            centre,
            radius_vec: [r_p, r_q],
            theta_per_chord: angular / count,
            helix_start: start[h],
            helix_per_chord: linear / count,
            axes,
            target,
            count: count as u64,
            next: 1,
        }
    }

    /// How many chords the arc has: 0 when the numbers of the arc are not finite or it
    /// would have more than [`MAX_CHORDS`].
    pub fn chord_count(&self) -> u64 {
        self.count
    }
}

impl Iterator for Chords {
    type Item = Vec3;

    fn next(&mut self) -> Option<Vec3> {
        let i = self.next;
        if i > self.count {
            return None;
        }
        self.next += 1;
        if i == self.count {
            return Some(self.target);
        }
        let (sin, cos) = (i as f64 * self.theta_per_chord).sin_cos();
        let [r_p, r_q] = self.radius_vec;
        let [a, b, h] = self.axes;
        let mut c = Vec3::zeros();
        c[a] = self.centre[0] + r_p * cos - r_q * sin;
        c[b] = self.centre[1] + r_p * sin + r_q * cos;
        c[h] = self.helix_start + i as f64 * self.helix_per_chord;
        Some(c)
    }
}

/// One chord of a Marlin arc: its end (before the firmware's clamp), and what the planner's
/// hint needs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MarlinChord {
    /// The chord's end, in the coordinates of the arc's start and target.
    pub end: Vec3,
    /// 1-based index; the last chord (`index == segments`) ends exactly on the target.
    pub index: u64,
}

/// The chords of one arc as Marlin's `plan_arc` cuts them (XY plane, Z helical): the
/// angular travel from the atan2 of the start and end vectors (a full circle when start and
/// end coincide), `max(⌊flat / ideal⌋, min_segments)` chords, moved into
/// [`MIN_ARC_SEGMENT_MM`, `MAX_ARC_SEGMENT_MM`]; the chord ends by a small-angle rotation
/// (sin θ ≈ θ − θ³/6, cos θ ≈ 1 − θ²/2) corrected exactly every `N_ARC_CORRECTION`-th.
#[derive(Clone, Copy, Debug)]
pub struct MarlinChords {
    centre: [f64; 2],
    /// The initial radius vector −offset, and the current one.
    r0: [f64; 2],
    r: [f64; 2],
    theta: f64,
    sin_t: f64,
    cos_t: f64,
    z: f64,
    dz: f64,
    target: Vec3,
    radius: f64,
    flat_mm: f64,
    segments: u64,
    n_correction: u32,
    recalc: u32,
    next: u64,
}

/// What Marlin does with one G2/G3.
#[derive(Clone, Copy, Debug)]
pub enum MarlinArc {
    /// Chords to queue.
    Chords(MarlinChords),
    /// The arc is too short (under 0.1 µm of arc and no Z): Marlin moves E alone, as a G1.
    ExtrudeOnly,
    /// No angle between start and end: nothing is queued, the position is kept.
    Nothing,
}

impl MarlinChords {
    /// `plan_arc(cart, offset, clockwise)` from `start` to `target` with the centre at
    /// `start.xy + offset`, at `feed_mm_s` (the feed after M220).
    #[allow(clippy::too_many_arguments)]
    pub fn plan(
        start: Vec3,
        target: Vec3,
        offset: [f64; 2],
        clockwise: bool,
        rules: &ArcRules,
        feed_mm_s: f64,
        extrudes: bool,
    ) -> MarlinArc {
        let ArcRules::Marlin {
            max_segment_mm,
            min_segment_mm,
            min_circle_segments,
            segments_per_sec,
            n_arc_correction,
        } = *rules
        else {
            return MarlinArc::Nothing;
        };
        let r0 = [-offset[0], -offset[1]];
        let radius = r0[0].hypot(r0[1]);
        let centre = [start.x - r0[0], start.y - r0[1]];
        let (rt_x, rt_y) = (target.x - centre[0], target.y - centre[1]);
        let near = |a: f64, b: f64| (a - b).abs() < 1e-6;
        let (angle, min_segments) = if near(start.x, target.x) && near(start.y, target.y) {
            (
                if clockwise { -TAU } else { TAU },
                min_circle_segments as f64,
            )
        } else {
            let mut a = (r0[0] * rt_y - r0[1] * rt_x).atan2(r0[0] * rt_x + r0[1] * rt_y);
            if a == 0.0 {
                return MarlinArc::Nothing;
            }
            if a > 0.0 && clockwise {
                a -= TAU;
            } else if a < 0.0 && !clockwise {
                a += TAU;
            }
            (a, (min_circle_segments as f64 * a.abs() / TAU).ceil())
        };
        let dz = target.z - start.z;
        let flat_mm = radius * angle.abs();
        if flat_mm < 1e-4 && dz.abs() < 1e-6 {
            return if extrudes {
                MarlinArc::ExtrudeOnly
            } else {
                MarlinArc::Nothing
            };
        }
        let ideal = if segments_per_sec > 0.0 {
            (feed_mm_s / segments_per_sec).clamp(min_segment_mm, max_segment_mm)
        } else {
            max_segment_mm
        };
        let nominal = (flat_mm / ideal).floor().max(min_segments);
        let nominal_mm = flat_mm / nominal;
        let segments = if nominal_mm > max_segment_mm {
            (flat_mm / max_segment_mm).ceil()
        } else if nominal_mm < min_segment_mm {
            (flat_mm / min_segment_mm).floor().max(1.0)
        } else {
            nominal
        };
        // uint16_t in Marlin; a number beyond it is not a printable arc.
        let segments = if segments.is_finite() && segments >= 1.0 {
            segments.min(MAX_CHORDS as f64) as u64
        } else {
            1
        };
        let theta = angle / segments as f64;
        let th2 = theta * theta;
        MarlinArc::Chords(MarlinChords {
            centre,
            r0,
            r: r0,
            theta,
            sin_t: theta - th2 * theta / 6.0,
            cos_t: 1.0 - 0.5 * th2,
            z: start.z,
            dz: dz / segments as f64,
            target,
            radius,
            flat_mm,
            segments,
            n_correction: n_arc_correction,
            recalc: n_arc_correction,
            next: 1,
        })
    }

    /// Chords of the arc.
    pub fn segments(&self) -> u64 {
        self.segments
    }

    /// The circle's radius, mm.
    pub fn radius_mm(&self) -> f64 {
        self.radius
    }

    /// The arc's length in the plane (without the helical rise), mm.
    pub fn flat_mm(&self) -> f64 {
        self.flat_mm
    }
}

impl Iterator for MarlinChords {
    type Item = MarlinChord;

    fn next(&mut self) -> Option<MarlinChord> {
        let i = self.next;
        if i > self.segments {
            return None;
        }
        self.next += 1;
        if i == self.segments {
            return Some(MarlinChord {
                end: self.target,
                index: i,
            });
        }
        self.recalc -= 1;
        if self.recalc > 0 {
            let [a, b] = self.r;
            self.r = [
                a * self.cos_t - b * self.sin_t,
                a * self.sin_t + b * self.cos_t,
            ];
        } else {
            self.recalc = self.n_correction;
            let (sin, cos) = (i as f64 * self.theta).sin_cos();
            let [a, b] = self.r0;
            self.r = [a * cos - b * sin, a * sin + b * cos];
        }
        self.z += self.dz;
        Some(MarlinChord {
            end: Vec3::new(
                self.centre[0] + self.r[0],
                self.centre[1] + self.r[1],
                self.z,
            ),
            index: i,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn v(x: f64, y: f64, z: f64) -> Vec3 {
        Vec3::new(x, y, z)
    }

    #[test]
    fn a_quarter_circle_is_cut_like_klipper() {
        // r = 10 quarter circle counter-clockwise from (10, 0) around the origin: length
        // 15.708 mm, 15 chords of 6°; the points lie on the circle, the last is the target.
        let c = Chords::klipper(
            v(10.0, 0.0, 1.0),
            v(0.0, 10.0, 1.0),
            [-10.0, 0.0],
            false,
            Plane::Xy,
            1.0,
        );
        assert_eq!(c.chord_count(), 15);
        let pts: Vec<Vec3> = c.collect();
        assert_eq!(pts.len(), 15);
        for (i, p) in pts.iter().enumerate() {
            let th = (6.0 * (i + 1) as f64).to_radians();
            assert!(
                (p - v(10.0 * th.cos(), 10.0 * th.sin(), 1.0)).norm() < 1e-12,
                "{i}"
            );
        }
        assert_eq!(pts[14], v(0.0, 10.0, 1.0));
    }

    #[test]
    fn clockwise_helix_full_turn_and_planes() {
        // The FLSUN Q5 start G-code, G3 X0 Y-98 I98 Z0.2 from (−98, 0, 5): centre (0, 0),
        // counter-clockwise from 180° to 270°, a quarter turn descending 4.8 mm.
        let start = v(-98.0, 0.0, 5.0);
        let c = Chords::klipper(
            start,
            v(0.0, -98.0, 0.2),
            [98.0, 0.0],
            false,
            Plane::Xy,
            1.0,
        );
        let quarter = 98.0 * std::f64::consts::FRAC_PI_2;
        assert_eq!(c.chord_count(), quarter.hypot(4.8).floor() as u64);
        let pts: Vec<Vec3> = c.collect();
        assert!(pts[10].x < -90.0 && pts[10].y < 0.0 && pts[10].z < 5.0);
        // G2 to the same point: three quarters, clockwise over the top (y > 0).
        let cw: Vec<Vec3> =
            Chords::klipper(start, v(0.0, -98.0, 5.0), [98.0, 0.0], true, Plane::Xy, 1.0).collect();
        assert_eq!(cw.len(), (3.0 * quarter).floor() as usize);
        assert!(cw[10].x < -90.0 && cw[10].y > 0.0);
        // Start = target: a full circle of 2π·5 = 31.4 mm, 31 chords.
        let full = Chords::klipper(
            v(5.0, 0.0, 0.0),
            v(5.0, 0.0, 0.0),
            [-5.0, 0.0],
            true,
            Plane::Xy,
            1.0,
        );
        assert_eq!(full.chord_count(), 31);
        // G18 (XZ): centre from I and K, Y the helical axis.
        let xz: Vec<Vec3> = Chords::klipper(
            v(0.0, 0.0, 10.0),
            v(10.0, 2.0, 0.0),
            [0.0, -10.0],
            true,
            Plane::Xz,
            1.0,
        )
        .collect();
        let last = xz.len() - 1;
        for p in &xz[..last] {
            assert!(((p.x).hypot(p.z) - 10.0).abs() < 1e-9);
        }
        assert_eq!(xz[last], v(10.0, 2.0, 0.0));
        // An arc shorter than the resolution is one chord, straight to the target.
        let tiny: Vec<Vec3> = Chords::klipper(
            v(0.0, 0.0, 0.0),
            v(0.1, 0.1, 0.0),
            [0.1, 0.0],
            false,
            Plane::Xy,
            1.0,
        )
        .collect();
        assert_eq!(tiny, [v(0.1, 0.1, 0.0)]);
    }
}
