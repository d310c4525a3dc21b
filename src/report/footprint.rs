//! Where a file's moves go on the bed, to tell a file sliced for another printer: when most
//! moves end outside the print disc, the report says so and names the extent it found,
//! instead of only listing a violation per move.

use super::Report;
use crate::interval::{greater, lesser};

/// Where the moves end: their XY extent and how many end outside the print disc.
#[derive(Clone, Debug, Default)]
pub(super) struct Footprint {
    min_mm: [f64; 2],
    max_mm: [f64; 2],
    moves: u64,
    outside: u64,
}

/// Slicers round to the µm: a move this far past the print radius is still on it.
const ROUNDING_MM: f64 = 1e-3;

impl Report {
    /// Takes where a move ends (bed frame, mm), in file order.
    pub fn add_end_xy(&mut self, xy: [f64; 2], print_radius_mm: f64) {
        let f = &mut self.footprint;
        if f.moves == 0 {
            (f.min_mm, f.max_mm) = (xy, xy);
        }
        f.min_mm = [lesser(xy[0], f.min_mm[0]), lesser(xy[1], f.min_mm[1])];
        f.max_mm = [greater(xy[0], f.max_mm[0]), greater(xy[1], f.max_mm[1])];
        f.moves += 1;
        // Squared: `hypot`, a library call guarding against overflow no bed coordinate
        // reaches, was 1.7 % of a run's time.
        let limit = print_radius_mm + ROUNDING_MM;
        if xy[0] * xy[0] + xy[1] * xy[1] > limit * limit {
            f.outside += 1;
        }
    }

    /// Adds the note that the file seems sliced for another printer, when most moves end
    /// outside the print disc of radius `print_radius_mm`.
    pub fn note_footprint(&mut self, print_radius_mm: f64) {
        let f = &self.footprint;
        if f.outside * 2 <= f.moves {
            return;
        }
        self.notes.push(format!(
            "the file seems sliced for another printer: {} of its {} moves end outside the print radius of {print_radius_mm:.0} mm around X0 Y0; they span X {:.1} to {:.1} mm, Y {:.1} to {:.1} mm",
            f.outside, f.moves, f.min_mm[0], f.max_mm[0], f.min_mm[1], f.max_mm[1]
        ));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn report_of(ends: &[[f64; 2]]) -> Report {
        let mut r = Report::new("part.gcode", "Kossel", 30.0, false);
        for &xy in ends {
            r.add_end_xy(xy, 85.0);
        }
        r.note_footprint(85.0);
        r
    }

    #[test]
    fn a_cartesian_file_is_told_with_its_extent() {
        // A 220 mm Cartesian bed's part near its centre (110, 110), and the origin.
        let r = report_of(&[[0.0, 0.0], [100.0, 95.5], [120.25, 130.0], [110.0, 20.0]]);
        assert_eq!(
            r.notes,
            [
                "the file seems sliced for another printer: 3 of its 4 moves end outside the print radius of 85 mm around X0 Y0; they span X 0.0 to 120.2 mm, Y 0.0 to 130.0 mm"
            ]
        );
    }

    #[test]
    fn a_delta_file_with_a_few_moves_outside_has_no_note() {
        let r = report_of(&[[0.0, 0.0], [84.0, 0.0], [85.0009, 0.0], [90.0, 0.0]]);
        assert!(r.notes.is_empty());
        // Half outside is not most.
        let r = report_of(&[[0.0, 0.0], [90.0, 0.0]]);
        assert!(r.notes.is_empty());
        assert!(report_of(&[]).notes.is_empty());
    }

    /// A move is outside beyond the print radius and its rounding, in any direction.
    #[test]
    fn outside_is_past_the_radius_and_its_rounding() {
        let d = std::f64::consts::FRAC_1_SQRT_2;
        let inside = [85.0009, 85.0009 * d, -85.0009 * d];
        let outside = [85.0011, 85.0011 * d, -85.0011 * d];
        let ends = |r: [f64; 3]| [[r[0], 0.0], [r[1], r[1]], [0.0, -r[0]], [r[2], r[1]]];
        assert_eq!(report_of(&ends(inside)).footprint.outside, 0);
        assert_eq!(report_of(&ends(outside)).footprint.outside, 4);
    }
}
