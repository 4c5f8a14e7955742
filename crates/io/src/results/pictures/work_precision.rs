//! `work-precision.png`: run time against error, one panel per measure.
//!
//! For `cargo xtask bench work-precision`: each setting of a scene is a
//! marker at (wall time, error against a reference solution), numbered as
//! in the bench's table; the shipped setting is a red square. Both axes are
//! logarithmic (run times span decades, and so do errors); an error of
//! exactly zero is drawn on the bottom edge. The Pareto front (the settings
//! that no other setting beats in both time and error, [`pareto_front`]) is
//! drawn as a staircase, and an optional target error as a dashed line.
//!
//! Not for general plotting: the layout (panels side by side, numbered
//! markers) is this picture's.

use plotters::prelude::*;

use super::{FAMILY, Result, drawing, render};

/// One setting of a work–precision study.
#[derive(Debug, Clone, PartialEq)]
pub struct WorkPrecisionPoint {
    /// Its number in the bench's table (drawn beside the marker).
    pub number: usize,
    /// Run time (s, the picture's time axis); a non-finite or non-positive
    /// time is not drawn.
    pub wall_s: f64,
    /// One error per panel; a non-finite error is not drawn.
    pub errors: Vec<f64>,
    /// The shipped setting.
    pub default: bool,
}

/// One panel: which error it shows.
#[derive(Debug, Clone, PartialEq)]
pub struct WorkPrecisionPanel {
    /// The y axis's description.
    pub label: String,
    /// A target error drawn as a dashed line.
    pub target: Option<f64>,
}

/// Size of one panel, pixels.
const PANEL: (u32, u32) = (620, 520);

const POINT_COLOUR: RGBColor = RGBColor(31, 119, 180);
const FRONT_COLOUR: RGBColor = RGBColor(44, 160, 44);
const DEFAULT_COLOUR: RGBColor = RGBColor(214, 39, 40);
const TARGET_COLOUR: RGBColor = RGBColor(120, 120, 120);

/// The indices of `points` (time, error) on the Pareto front, by
/// increasing time: a point is on it when no other point is at most as
/// slow and at most as wrong and better in one of the two. Points with a
/// non-finite coordinate are never on it; of exact duplicates the first
/// is kept.
pub fn pareto_front(points: &[(f64, f64)]) -> Vec<usize> {
    let mut order: Vec<usize> = (0..points.len())
        .filter(|&i| points[i].0.is_finite() && points[i].1.is_finite())
        .collect();
    // By time, then error: a sweep keeps each point that is better than
    // every faster one.
    order.sort_by(|&a, &b| {
        points[a]
            .0
            .total_cmp(&points[b].0)
            .then(points[a].1.total_cmp(&points[b].1))
    });
    let mut front = Vec::new();
    let mut best = f64::INFINITY;
    for i in order {
        if points[i].1 < best {
            best = points[i].1;
            front.push(i);
        }
    }
    front
}

/// Decades covering the positive finite `values`, padded a little.
fn log_range(values: impl Iterator<Item = f64>) -> Option<(f64, f64)> {
    let (lo, hi) = values
        .filter(|v| v.is_finite() && *v > 0.0)
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
            (a.min(v), b.max(v))
        });
    (lo <= hi).then(|| (lo / 1.6, hi * 1.6))
}

/// The PNG of `points`, one panel per entry of `panels` side by side.
pub(in crate::results) fn work_precision_png(
    title: &str,
    time_label: &str,
    panels: &[WorkPrecisionPanel],
    points: &[WorkPrecisionPoint],
) -> Result<Vec<u8>> {
    if panels.is_empty() {
        return Err("a work-precision picture needs at least one error measure".into());
    }
    if let Some(p) = points.iter().find(|p| p.errors.len() != panels.len()) {
        return Err(format!(
            "setting {} has {} errors for {} panels",
            p.number,
            p.errors.len(),
            panels.len()
        ));
    }
    let size = (PANEL.0 * panels.len() as u32, PANEL.1 + 40);
    render(size, |root| {
        let body = root.titled(title, (FAMILY, 22)).map_err(drawing)?;
        let areas = body.split_evenly((1, panels.len()));
        for (k, area) in areas.iter().enumerate() {
            panel(area, time_label, &panels[k], points, k)?;
        }
        Ok(())
    })
}

fn panel(
    area: &super::Canvas<'_>,
    time_label: &str,
    panel: &WorkPrecisionPanel,
    points: &[WorkPrecisionPoint],
    k: usize,
) -> Result<()> {
    let drawn: Vec<(usize, f64, f64)> = points
        .iter()
        .filter(|p| p.wall_s.is_finite() && p.wall_s > 0.0 && p.errors[k].is_finite())
        .map(|p| (p.number, p.wall_s, p.errors[k].max(0.0)))
        .collect();
    let (x0, x1) = log_range(drawn.iter().map(|d| d.1)).unwrap_or((0.1, 10.0));
    let (y0, y1) = log_range(drawn.iter().map(|d| d.2).chain(panel.target)).unwrap_or((0.01, 1.0));
    // A zero error sits on the bottom edge.
    let y_of = |e: f64| e.max(y0);
    let mut chart = ChartBuilder::on(area)
        .margin(14)
        .x_label_area_size(50)
        .y_label_area_size(70)
        .build_cartesian_2d((x0..x1).log_scale(), (y0..y1).log_scale())
        .map_err(drawing)?;
    chart
        .configure_mesh()
        .max_light_lines(1)
        .light_line_style(RGBColor(242, 242, 242))
        .bold_line_style(RGBColor(222, 222, 222))
        .x_desc(time_label)
        .y_desc(panel.label.as_str())
        .x_label_formatter(&|v| short(*v))
        .y_label_formatter(&|v| short(*v))
        .label_style((FAMILY, 14))
        .axis_desc_style((FAMILY, 15))
        .draw()
        .map_err(drawing)?;
    if let Some(t) = panel.target {
        chart
            .draw_series(DashedLineSeries::new(
                [(x0, t), (x1, t)],
                6,
                4,
                TARGET_COLOUR.stroke_width(1),
            ))
            .map_err(drawing)?
            .label(format!("target {}", short(t)))
            .legend(|(x, y)| {
                PathElement::new(
                    vec![(x - 10, y), (x + 10, y)],
                    TARGET_COLOUR.stroke_width(1),
                )
            });
    }
    let xy: Vec<(f64, f64)> = drawn.iter().map(|d| (d.1, d.2)).collect();
    let front = pareto_front(&xy);
    // The front as a staircase: each front point holds its error until the
    // next (faster to slower) improves on it.
    let mut stairs = Vec::new();
    for (n, &i) in front.iter().enumerate() {
        if n > 0 {
            stairs.push((xy[i].0, y_of(xy[front[n - 1]].1)));
        }
        stairs.push((xy[i].0, y_of(xy[i].1)));
    }
    if let Some(&last) = front.last() {
        stairs.push((x1, y_of(xy[last].1)));
    }
    chart
        .draw_series(LineSeries::new(stairs, FRONT_COLOUR.stroke_width(2)))
        .map_err(drawing)?
        .label("Pareto front")
        .legend(|(x, y)| {
            PathElement::new(vec![(x - 10, y), (x + 10, y)], FRONT_COLOUR.stroke_width(2))
        });
    chart
        .draw_series(drawn.iter().map(|&(number, x, e)| {
            let colour = if points.iter().any(|p| p.number == number && p.default) {
                DEFAULT_COLOUR
            } else {
                POINT_COLOUR
            };
            EmptyElement::at((x, y_of(e)))
                + Circle::new((0, 0), 4, colour.filled())
                + Text::new(number.to_string(), (5, -15), (FAMILY, 13).into_font())
        }))
        .map_err(drawing)?;
    // The shipped setting: a red square over its dot, named in the legend.
    if let Some(p) = points
        .iter()
        .find(|p| p.default && p.wall_s.is_finite() && p.wall_s > 0.0 && p.errors[k].is_finite())
    {
        chart
            .draw_series([EmptyElement::at((p.wall_s, y_of(p.errors[k])))
                + Rectangle::new([(-6, -6), (6, 6)], DEFAULT_COLOUR.filled())])
            .map_err(drawing)?
            .label(format!("{}: shipped setting", p.number))
            .legend(|(x, y)| {
                Rectangle::new([(x - 5, y - 5), (x + 5, y + 5)], DEFAULT_COLOUR.filled())
            });
    }
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperRight)
        .label_font((FAMILY, 13))
        .background_style(WHITE.mix(0.85))
        .border_style(RGBColor(160, 160, 160))
        .draw()
        .map_err(drawing)?;
    Ok(())
}

/// A log-axis tick: 0.001, 0.5, 20, 1e+04.
fn short(v: f64) -> String {
    let a = v.abs();
    if !(1e-3..1e4).contains(&a) {
        format!("{v:.0e}")
    } else {
        let text = format!("{v:.3}");
        text.trim_end_matches('0').trim_end_matches('.').to_owned()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn front_keeps_what_nothing_beats() {
        // (time, error): 0 fast but wrong, 1 dominated by 2, 2 and 3 on the
        // front, 4 slower than 3 and no better, 5 not finite.
        let points = [
            (1.0, 5.0),
            (3.0, 2.0),
            (2.0, 1.0),
            (10.0, 0.1),
            (20.0, 0.1),
            (f64::NAN, 0.0),
        ];
        assert_eq!(pareto_front(&points), [0, 2, 3]);
        assert!(pareto_front(&[]).is_empty());
        // Equal times: the smaller error only.
        assert_eq!(pareto_front(&[(1.0, 2.0), (1.0, 1.0)]), [1]);
    }

    #[test]
    fn picture_is_a_png_and_checks_its_input() {
        let points: Vec<WorkPrecisionPoint> = (1..=4)
            .map(|n| WorkPrecisionPoint {
                number: n,
                wall_s: 0.5 * n as f64,
                errors: vec![1.0 / n as f64, if n == 2 { 0.0 } else { 0.3 }],
                default: n == 3,
            })
            .collect();
        let panels = [
            WorkPrecisionPanel {
                label: "max shear error (deg)".into(),
                target: Some(0.5),
            },
            WorkPrecisionPanel {
                label: "profile RMS error (deg)".into(),
                target: None,
            },
        ];
        let png = work_precision_png("test", "wall time (s)", &panels, &points).unwrap();
        assert_eq!(&png[1..4], b"PNG");
        let mut wrong = points.clone();
        wrong[0].errors.pop();
        assert!(work_precision_png("test", "wall time (s)", &panels, &wrong).is_err());
        assert!(work_precision_png("test", "wall time (s)", &[], &points).is_err());
    }
}
