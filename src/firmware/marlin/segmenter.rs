//! How Marlin cuts a G0/G1 on a delta into planner segments: `line_to_destination_kinematic`
//! (module/motion.cpp) or, with `AUTO_BED_LEVELING_UBL`, UBL's
//! `line_to_destination_segmented` (feature/bedlevel/ubl/ubl_motion.cpp, leveling off).
//! Each segment goes to `Planner::buffer_line` with the same feed and a hint of its
//! Cartesian length.

use crate::path::Vec3;

/// UBL's `SEGMENT_MIN_LENGTH` on a kinematic machine, mm.
const UBL_SEGMENT_MIN_MM: f64 = 0.1;

/// The segments of one straight move from `from` to `to` (machine positions, mm) with
/// `e_mm` of filament at `feed_mm_s` (after M220): the number of segments and the hint
/// `millimeters` each carries (0: none, the planner measures the segment itself).
/// None when Marlin queues nothing (no length and no E).
pub fn count(
    from: Vec3,
    to: Vec3,
    e_mm: f64,
    feed_mm_s: f64,
    segments_per_second: f64,
    ubl: bool,
) -> Option<(u32, f64)> {
    let d = to - from;
    if ubl {
        // ubl_motion.cpp: the XY length sets the count (rounded), at least 0.1 mm each.
        let xy = d.x.hypot(d.y);
        let by_time = (segments_per_second * xy / feed_mm_s).round();
        let by_length = (xy / UBL_SEGMENT_MIN_MM).round();
        let n = clamp_count(by_time.min(by_length));
        return Some((n, xy.hypot(d.z) / n as f64));
    }
    // motion.cpp: a move without XY is one block with no hint.
    if d.x == 0.0 && d.y == 0.0 {
        return Some((1, 0.0));
    }
    let mut cart_mm = d.norm();
    if cart_mm < 1e-6 {
        cart_mm = e_mm.abs();
    }
    if cart_mm < 1e-6 {
        return None;
    }
    // `uint16_t segments = segments_per_second * seconds`: truncated.
    let n = clamp_count((segments_per_second * cart_mm / feed_mm_s).floor());
    Some((n, cart_mm / n as f64))
}

/// At least one segment; Marlin's count is a `uint16_t` (a wrap there is not modelled: such
/// a move, hundreds of mm at 1 mm/s, is capped instead).
fn clamp_count(n: f64) -> u32 {
    if n.is_finite() {
        n.clamp(1.0, u16::MAX as f64) as u32
    } else {
        1
    }
}

/// The end of segment `k` of `n` (1-based; the last ends exactly on `to`), as Marlin's
/// loop `raw += step` reaches it.
pub fn point(from: Vec3, to: Vec3, k: u32, n: u32) -> Vec3 {
    if k >= n {
        to
    } else {
        from + (to - from) * (k as f64 / n as f64)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn v(x: f64, y: f64, z: f64) -> Vec3 {
        Vec3::new(x, y, z)
    }

    /// The counts of marlin-delta-spec.md T8, both segmenters.
    #[test]
    fn segment_counts_follow_marlins_two_segmenters() {
        let o = v(0.0, 0.0, 0.0);
        let cases = [
            (v(50.0, 0.0, 0.0), 50.0, 200.0, 200, 200),
            (v(10.3, 0.0, 0.0), 100.0, 200.0, 20, 21),
            (v(50.0, 0.0, 0.0), 50.0, 80.0, 80, 80),
            (v(30.0, 40.0, 120.0), 100.0, 200.0, 260, 100),
            (v(1.0, 0.0, 0.0), 1.0, 200.0, 200, 10),
            (v(0.0, 0.0, 5.0), 10.0, 200.0, 1, 1),
        ];
        for (to, f, s, plain, ubl) in cases {
            assert_eq!(count(o, to, 0.0, f, s, false).unwrap().0, plain, "{to}");
            assert_eq!(count(o, to, 0.0, f, s, true).unwrap().0, ubl, "{to}");
        }
        let (n, hint) = count(o, v(30.0, 40.0, 120.0), 0.0, 100.0, 200.0, false).unwrap();
        assert!((hint - 130.0 / n as f64).abs() < 1e-12);
        let (n, hint) = count(o, v(30.0, 40.0, 120.0), 0.0, 100.0, 200.0, true).unwrap();
        assert!((hint - 1.3).abs() < 1e-12 && n == 100);
        assert_eq!(count(o, o, 0.0, 10.0, 200.0, false), Some((1, 0.0)));
        assert_eq!(point(o, v(1.0, 2.0, 3.0), 4, 4), v(1.0, 2.0, 3.0));
    }
}
