//! `sweep.png`: a sweep's measures against each swept parameter.
//!
//! One column per swept key, one row per measure: the largest shear at the
//! end (always), and the draw-in DX and DD when the runs report them (a
//! rectangular blank). In a panel every run is a dot at its value of that
//! key; runs that share the values of the other keys are joined by a line,
//! one colour per such group (named in the legend), so a trend reads along
//! a line and the effect of the other keys across lines. A key whose values
//! are not all numbers is drawn as categories, in the order given.

use plotters::prelude::*;

use super::{FAMILY, Result, drawing, render, tick};

/// One swept key and its values, as given on the command line.
#[derive(Debug, Clone, PartialEq)]
pub struct SweepAxis {
    /// The key (`tools.0.friction`).
    pub key: String,
    /// Its values, in the order given.
    pub values: Vec<String>,
}

/// One run of a sweep: its value of each key and its measures (NaN when it
/// has none, a failed run's included).
#[derive(Debug, Clone, PartialEq)]
pub struct SweepRun {
    /// One value per axis.
    pub values: Vec<String>,
    /// Largest |shear angle| at the end (degrees).
    pub max_shear_deg: f64,
    /// Draw-in DX (mm).
    pub draw_in_dx_mm: f64,
    /// Draw-in DD (mm).
    pub draw_in_dd_mm: f64,
}

/// Size of one panel, pixels.
const PANEL: (u32, u32) = (560, 400);

/// matplotlib's `tab10` colours.
pub(super) const PALETTE: [RGBColor; 10] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(127, 127, 127),
    RGBColor(188, 189, 34),
    RGBColor(23, 190, 207),
];

/// The PNG of `runs` over `axes`.
pub(in crate::results) fn sweep_png(axes: &[SweepAxis], runs: &[SweepRun]) -> Result<Vec<u8>> {
    if axes.is_empty() {
        return Err("a sweep needs at least one swept key".into());
    }
    if let Some(r) = runs.iter().find(|r| r.values.len() != axes.len()) {
        return Err(format!(
            "a run has {} values for {} swept keys",
            r.values.len(),
            axes.len()
        ));
    }
    type Measure = (&'static str, fn(&SweepRun) -> f64);
    let mut measures: Vec<Measure> = vec![("largest |γ| at the end (deg)", |r| r.max_shear_deg)];
    if runs.iter().any(|r| r.draw_in_dx_mm.is_finite()) {
        measures.push(("draw-in DX (mm)", |r| r.draw_in_dx_mm));
    }
    if runs.iter().any(|r| r.draw_in_dd_mm.is_finite()) {
        measures.push(("draw-in DD (mm)", |r| r.draw_in_dd_mm));
    }
    let size = (PANEL.0 * axes.len() as u32, PANEL.1 * measures.len() as u32);
    render(size, |root| {
        let panels = root.split_evenly((measures.len(), axes.len()));
        for (p, area) in panels.iter().enumerate() {
            let (m, a) = (p / axes.len(), p % axes.len());
            panel(area, axes, a, runs, measures[m])?;
        }
        Ok(())
    })
}

/// The panel of measure `measure` against axis `a`.
fn panel(
    area: &super::Canvas<'_>,
    axes: &[SweepAxis],
    a: usize,
    runs: &[SweepRun],
    (label, value): (&str, fn(&SweepRun) -> f64),
) -> Result<()> {
    let axis = &axes[a];
    let numbers: Option<Vec<f64>> = axis
        .values
        .iter()
        .map(|v| v.parse::<f64>().ok().filter(|x| x.is_finite()))
        .collect();
    // The x of a run's value: the number, or the category's position.
    let x_of = |v: &str| -> f64 {
        match &numbers {
            Some(n) => n[axis.values.iter().position(|w| w == v).unwrap_or(0)],
            None => axis.values.iter().position(|w| w == v).unwrap_or(0) as f64,
        }
    };
    let (x0, x1) = match &numbers {
        Some(n) => {
            let (lo, hi) = n
                .iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &x| {
                    (a.min(x), b.max(x))
                });
            let pad = (0.08 * (hi - lo)).max(1e-3 * hi.abs().max(1.0));
            (lo - pad, hi + pad)
        }
        None => (-0.5, axis.values.len() as f64 - 0.5),
    };
    let ys: Vec<f64> = runs.iter().map(value).filter(|y| y.is_finite()).collect();
    let (y0, y1) = ys
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &y| {
            (a.min(y), b.max(y))
        });
    let (y0, y1) = if y0 <= y1 {
        let pad = (0.1 * (y1 - y0)).max(0.05 * y1.abs().max(1.0));
        (y0 - pad, y1 + pad)
    } else {
        (0.0, 1.0)
    };
    // Runs grouped by the values of the other keys, in first-seen order.
    // (the other keys' values, the group's points)
    type Group<'a> = (Vec<&'a str>, Vec<(f64, f64)>);
    let mut groups: Vec<Group<'_>> = Vec::new();
    for r in runs {
        let others: Vec<&str> = r
            .values
            .iter()
            .enumerate()
            .filter(|&(k, _)| k != a)
            .map(|(_, v)| v.as_str())
            .collect();
        let point = (x_of(&r.values[a]), value(r));
        match groups.iter_mut().find(|(o, _)| *o == others) {
            Some((_, points)) => points.push(point),
            None => groups.push((others, vec![point])),
        }
    }
    let categories = axis.values.clone();
    let categorical = numbers.is_none();
    let x_label = move |x: &f64| {
        if categorical {
            let i = x.round();
            if (x - i).abs() < 1e-9 && i >= 0.0 {
                categories.get(i as usize).cloned().unwrap_or_default()
            } else {
                String::new()
            }
        } else {
            tick(x)
        }
    };
    let mut chart = ChartBuilder::on(area)
        .margin(14)
        .x_label_area_size(50)
        .y_label_area_size(70)
        .build_cartesian_2d(x0..x1, y0..y1)
        .map_err(drawing)?;
    let mut mesh = chart.configure_mesh();
    mesh.max_light_lines(1)
        .light_line_style(RGBColor(242, 242, 242))
        .bold_line_style(RGBColor(222, 222, 222))
        .x_desc(axis.key.as_str())
        .y_desc(label)
        .x_label_formatter(&x_label)
        .y_label_formatter(&tick)
        .label_style((FAMILY, 14))
        .axis_desc_style((FAMILY, 15));
    if categorical {
        mesh.x_labels(axis.values.len() * 2 + 1);
    }
    mesh.draw().map_err(drawing)?;
    let other_keys: Vec<&str> = axes
        .iter()
        .enumerate()
        .filter(|&(k, _)| k != a)
        .map(|(_, x)| x.key.as_str())
        .collect();
    for (g, (others, points)) in groups.iter_mut().enumerate() {
        points.sort_by(|p, q| p.0.total_cmp(&q.0));
        let colour = PALETTE[g % PALETTE.len()];
        let finite: Vec<(f64, f64)> = points.iter().copied().filter(|p| p.1.is_finite()).collect();
        let series = chart
            .draw_series(LineSeries::new(finite.clone(), colour.stroke_width(2)))
            .map_err(drawing)?;
        if !others.is_empty() {
            let name: Vec<String> = other_keys
                .iter()
                .zip(others.iter())
                .map(|(k, v)| format!("{k} {v}"))
                .collect();
            series.label(name.join(", ")).legend(move |(x, y)| {
                PathElement::new(vec![(x - 10, y), (x + 10, y)], colour.stroke_width(2))
            });
        }
        chart
            .draw_series(finite.iter().map(|&p| Circle::new(p, 4, colour.filled())))
            .map_err(drawing)?;
    }
    if groups.len() > 1 {
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::UpperRight)
            .label_font((FAMILY, 13))
            .background_style(WHITE.mix(0.85))
            .border_style(RGBColor(160, 160, 160))
            .draw()
            .map_err(drawing)?;
    }
    Ok(())
}
