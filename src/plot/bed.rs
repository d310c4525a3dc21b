//! A map of the bed coloured by how much of the motor limit each point uses.

use std::path::Path;

use plotters::prelude::*;

/// Viridis at 0, ¼, ½, ¾, 1 of the limit: dark blue (idle) to yellow (at the limit).
const RAMP: [(u8, u8, u8); 5] = [
    (68, 1, 84),
    (59, 82, 139),
    (33, 145, 140),
    (94, 201, 98),
    (253, 231, 37),
];
/// Over the limit: red, darkening to maroon at twice the limit.
const OVER: [(u8, u8, u8); 2] = [(230, 30, 30), (110, 0, 20)];
const MAP_PX: u32 = 640;
const BAR_PX: u32 = 150;

/// Above this many points the map keeps the worst point of each of CELLS × CELLS cells.
const MAX_DOTS: usize = 20_000;
/// Cells per side: a dot is 6 px wide on a map of about 560 px.
const CELLS: usize = 100;

/// The worst point (highest use) of each cell of a `cells` × `cells` grid over
/// [−reach, reach]², so a whole print's moves make a map of bounded size that still shows
/// every over-limit spot.
fn worst_per_cell(points: &[(f64, f64, f64)], reach: f64, cells: usize) -> Vec<(f64, f64, f64)> {
    let cell_of = |v: f64| (((v + reach) / (2.0 * reach) * cells as f64) as usize).min(cells - 1);
    let mut grid: Vec<Option<(f64, f64, f64)>> = vec![None; cells * cells];
    for &p in points {
        let slot = &mut grid[cell_of(p.1) * cells + cell_of(p.0)];
        if slot.is_none_or(|q| p.2 > q.2) {
            *slot = Some(p);
        }
    }
    grid.into_iter().flatten().collect()
}

/// The colour of a use (1 = the limit). Non-finite counts as over.
fn colour_of(use_: f64) -> RGBColor {
    let lerp = |a: (u8, u8, u8), b: (u8, u8, u8), f: f64| {
        let c = |a: u8, b: u8| (f64::from(a) + (f64::from(b) - f64::from(a)) * f).round() as u8;
        RGBColor(c(a.0, b.0), c(a.1, b.1), c(a.2, b.2))
    };
    if use_.is_nan() || use_ > 1.0 {
        let f = if use_.is_finite() {
            (use_ - 1.0).min(1.0)
        } else {
            1.0
        };
        return lerp(OVER[0], OVER[1], f);
    }
    let s = use_.max(0.0) * (RAMP.len() - 1) as f64;
    let k = (s.floor() as usize).min(RAMP.len() - 2);
    lerp(RAMP[k], RAMP[k + 1], s - k as f64)
}

/// Writes the bed map to `path` as SVG: every point (x_mm, y_mm, use) a dot coloured by its
/// use of the force limit (0 = idle, 1 = at the limit, above 1 = over, in reds), the worst
/// drawn on top, the print circle of `print_radius_mm`, and a colour scale with the limit
/// marked. Beyond 20 000 points only the worst point of each cell of a 100 × 100 grid is
/// drawn. Points with a non-finite coordinate or a NaN use are left out.
pub fn bed_map_svg(
    path: &Path,
    title: &str,
    points: &[(f64, f64, f64)],
    print_radius_mm: f64,
) -> anyhow::Result<()> {
    super::write_svg(path, &bed_map_string(title, points, print_radius_mm)?)
}

/// [`bed_map_svg`] into a string.
pub fn bed_map_string(
    title: &str,
    points: &[(f64, f64, f64)],
    print_radius_mm: f64,
) -> anyhow::Result<String> {
    anyhow::ensure!(
        print_radius_mm.is_finite() && print_radius_mm > 0.0,
        "print radius must be > 0, found {print_radius_mm}"
    );
    let mut shown: Vec<(f64, f64, f64)> = points
        .iter()
        .copied()
        .filter(|p| p.0.is_finite() && p.1.is_finite() && !p.2.is_nan())
        .map(|(x, y, u)| (x, y, u.max(0.0)))
        .collect();
    let reach = shown
        .iter()
        .map(|p| p.0.abs().max(p.1.abs()))
        .fold(print_radius_mm, f64::max)
        * 1.08;
    if shown.len() > MAX_DOTS {
        shown = worst_per_cell(&shown, reach, CELLS);
    }
    // The worst points on top.
    shown.sort_by(|a, b| a.2.total_cmp(&b.2));
    let worst = shown.last().map_or(0.0, |p| p.2);
    // The scale runs to the limit at least, to the worst point when it is finite.
    let top = if worst.is_finite() {
        (worst * 10.0).ceil().max(10.0) / 10.0
    } else {
        2.0
    };
    let mut svg = String::new();
    {
        let root =
            SVGBackend::with_string(&mut svg, (MAP_PX + BAR_PX, MAP_PX + 40)).into_drawing_area();
        root.fill(&WHITE)?;
        let root = root.titled(title, ("sans-serif", 22))?;
        let (map, bar) = root.split_horizontally(MAP_PX);
        let mut ctx = ChartBuilder::on(&map)
            .margin(12)
            .x_label_area_size(40)
            .y_label_area_size(50)
            .build_cartesian_2d(-reach..reach, -reach..reach)?;
        ctx.configure_mesh()
            .x_desc("x (mm)")
            .y_desc("y (mm)")
            .light_line_style(RGBColor(240, 240, 240))
            .label_style(("sans-serif", 14))
            .draw()?;
        let circle = (0..=360).map(|k| {
            let (s, c) = f64::from(k).to_radians().sin_cos();
            (print_radius_mm * c, print_radius_mm * s)
        });
        ctx.draw_series(LineSeries::new(circle, BLACK.stroke_width(1)))?;
        ctx.draw_series(
            shown
                .iter()
                .map(|&(x, y, u)| Circle::new((x, y), 3, colour_of(u).filled())),
        )?;
        let mut scale = ChartBuilder::on(&bar)
            .margin_top(12)
            .margin_bottom(52)
            .margin_right(12)
            .y_label_area_size(55)
            .caption("peak force / limit", ("sans-serif", 14))
            .build_cartesian_2d(0.0..1.0, 0.0..top)?;
        scale
            .configure_mesh()
            .disable_x_mesh()
            .disable_x_axis()
            .disable_y_mesh()
            .label_style(("sans-serif", 14))
            .draw()?;
        let steps = 100;
        scale.draw_series((0..steps).map(|k| {
            let (a, b) = (
                top * k as f64 / steps as f64,
                top * (k + 1) as f64 / steps as f64,
            );
            Rectangle::new([(0.0, a), (1.0, b)], colour_of(0.5 * (a + b)).filled())
        }))?;
        scale.draw_series(LineSeries::new(
            [(0.0, 1.0), (1.0, 1.0)],
            BLACK.stroke_width(2),
        ))?;
    }
    Ok(svg)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::plot::tests::assert_valid_svg;

    #[test]
    fn colours_run_from_the_ramp_to_red_over_the_limit() {
        assert_eq!(colour_of(0.0), RGBColor(68, 1, 84));
        assert_eq!(colour_of(1.0), RGBColor(253, 231, 37));
        assert_eq!(colour_of(0.5), RGBColor(33, 145, 140));
        assert_eq!(colour_of(1.0 + 1e-9), RGBColor(230, 30, 30));
        assert_eq!(colour_of(5.0), RGBColor(110, 0, 20));
        assert_eq!(colour_of(f64::INFINITY), RGBColor(110, 0, 20));
        assert_eq!(colour_of(-1.0), colour_of(0.0));
        // Halfway between two stops is the mean of their channels.
        assert_eq!(colour_of(0.125), RGBColor(64, 42, 112));
    }

    #[test]
    fn a_large_map_keeps_the_worst_point_of_each_cell() {
        let points: Vec<(f64, f64, f64)> = (0..100_000)
            .map(|k| {
                let th = f64::from(k) * 0.001;
                let r = 80.0 * f64::from(k % 997) / 997.0;
                (r * th.cos(), r * th.sin(), 0.5)
            })
            .chain([(10.0, 10.0, 1.7)])
            .collect();
        let kept = worst_per_cell(&points, 90.0, 50);
        assert!(kept.len() <= 2500 && kept.len() > 1000, "{}", kept.len());
        assert!(
            kept.contains(&(10.0, 10.0, 1.7)),
            "the over-limit point survives"
        );
        let svg = bed_map_string("big", &points, 85.0).unwrap();
        assert_valid_svg(&svg);
        let dots = svg.matches("<circle").count();
        assert!(dots <= CELLS * CELLS, "{dots}");
        let RGBColor(r, g, b) = colour_of(1.7);
        assert!(svg.contains(&format!("fill=\"#{r:02X}{g:02X}{b:02X}\"")));
    }

    #[test]
    fn bed_map_draws_every_point_the_circle_and_the_scale() {
        let points: Vec<(f64, f64, f64)> = (0..200)
            .map(|k| {
                let th = f64::from(k) * 0.1;
                let r = 80.0 * f64::from(k) / 200.0;
                (r * th.cos(), r * th.sin(), f64::from(k) / 150.0)
            })
            .chain([(f64::NAN, 0.0, 1.0), (0.0, 0.0, f64::NAN)])
            .collect();
        let svg = bed_map_string("bed", &points, 85.0).unwrap();
        assert_valid_svg(&svg);
        assert_eq!(
            svg.matches("<circle").count(),
            200,
            "non-finite points left out"
        );
        assert!(svg.contains("peak force / limit") && svg.contains(">\nbed\n</text>"));
        // The worst point (use 199/150, over the limit) is drawn last, in its red.
        let RGBColor(r, g, b) = colour_of(199.0 / 150.0);
        // 1.3267 is 0.3267 of the way from (230, 30, 30) to (110, 0, 20).
        assert!((r, g, b) == (191, 20, 27), "{r} {g} {b}");
        let last = svg.rfind("<circle").unwrap();
        assert!(svg[last..].contains("fill=\"#BF141B\""), "{}", &svg[last..]);
        assert!(bed_map_string("x", &points, 0.0).is_err());
        assert_valid_svg(&bed_map_string("empty", &[], 85.0).unwrap());
    }
}
