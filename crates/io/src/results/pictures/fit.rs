//! `*.fit.png`: a characterisation test's measured curves against the
//! fitted law (`drape fit`).
//!
//! One dot series per measured curve (lab, repeat), one colour each, and
//! the fitted curve as a black line, all in the units the fit compares
//! them in. Not for general plotting: the layout is this picture's.

use plotters::prelude::*;

use super::sweep::PALETTE;
use super::{FAMILY, Result, drawing, render, tick};

/// Size of the picture, pixels.
const SIZE: (u32, u32) = (1000, 640);

/// The PNG: `measured` (name, (x, y) points) as dots, `fitted` as a line.
pub(in crate::results) fn fit_png(
    title: &str,
    (x_label, y_label): (&str, &str),
    measured: &[(String, Vec<(f64, f64)>)],
    fitted: &[(f64, f64)],
) -> Result<Vec<u8>> {
    let all = measured.iter().flat_map(|m| m.1.iter()).chain(fitted);
    let (mut x1, mut y0, mut y1) = (0.0f64, 0.0f64, 0.0f64);
    for &(x, y) in all.filter(|p| p.0.is_finite() && p.1.is_finite()) {
        (x1, y0, y1) = (x1.max(x), y0.min(y), y1.max(y));
    }
    let x1 = if x1 > 0.0 { 1.05 * x1 } else { 1.0 };
    let y1 = if y1 > y0 {
        y1 + 0.08 * (y1 - y0)
    } else {
        y0 + 1.0
    };
    render(SIZE, |root| {
        let mut chart = ChartBuilder::on(root)
            .caption(title, (FAMILY, 24))
            .margin(16)
            .x_label_area_size(56)
            .y_label_area_size(86)
            .build_cartesian_2d(0.0..x1, y0..y1)
            .map_err(drawing)?;
        chart
            .configure_mesh()
            .max_light_lines(1)
            .light_line_style(RGBColor(242, 242, 242))
            .bold_line_style(RGBColor(222, 222, 222))
            .x_desc(x_label)
            .y_desc(y_label)
            .x_label_formatter(&tick)
            .y_label_formatter(&tick)
            .label_style((FAMILY, 16))
            .axis_desc_style((FAMILY, 18))
            .draw()
            .map_err(drawing)?;
        for (k, (name, points)) in measured.iter().enumerate() {
            let colour = PALETTE[k % PALETTE.len()];
            chart
                .draw_series(points.iter().map(|&p| Circle::new(p, 3, colour.filled())))
                .map_err(drawing)?
                .label(format!("{name} (measured)"))
                .legend(move |(x, y)| Circle::new((x, y), 3, colour.filled()));
        }
        chart
            .draw_series(LineSeries::new(
                fitted.iter().copied(),
                BLACK.stroke_width(2),
            ))
            .map_err(drawing)?
            .label("fitted law")
            .legend(|(x, y)| {
                PathElement::new(vec![(x - 10, y), (x + 10, y)], BLACK.stroke_width(2))
            });
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::UpperLeft)
            .label_font((FAMILY, 16))
            .background_style(WHITE.mix(0.9))
            .border_style(RGBColor(160, 160, 160))
            .draw()
            .map_err(drawing)?;
        Ok(())
    })
}
