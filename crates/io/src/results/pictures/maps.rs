//! Maps of per-element values side by side on the flat blank: the
//! picture of a comparison (a forming run's shear, the kinematic net's
//! shear at the same material points, their difference).
//!
//! Each panel draws every membrane element at its reference (flat)
//! position, filled with the colour of its value: viridis from 0 to the
//! panel's scale for magnitudes, a blue–white–red scale centred on zero
//! for signed values (a difference); a colour bar under each map. Drawing
//! on the flat blank puts both results on the same material points, where
//! their formed shapes would not overlap.

use drape_model::Model;
use nalgebra::Vector3;
use plotters::prelude::*;

use super::{FAMILY, Result, bounds, drawing, render, tick, viridis};

/// One panel of a side-by-side map.
#[derive(Debug, Clone)]
pub struct MapPanel<'a> {
    /// The panel's title.
    pub title: String,
    /// One value per membrane element, in the model's order (NaN: no value,
    /// drawn grey).
    pub values: &'a [f64],
    /// The colour bar's label.
    pub label: String,
    /// Signed values: a scale centred on zero.
    pub signed: bool,
    /// The colour range: [0, scale], or [−scale, scale] when signed; None
    /// takes the largest |value|.
    pub scale: Option<f64>,
    /// A fixed colour range [low, high] of magnitudes, in place of
    /// `scale` (the scene's `output.shear_range_deg`); ignored when
    /// signed.
    pub range: Option<[f64; 2]>,
}

/// Size of one panel, pixels.
const PANEL: (u32, u32) = (620, 720);

/// The diverging scale at t ∈ [−1, 1]: blue, light grey, red (the ends
/// and middle of ColorBrewer's RdBu).
fn diverging(t: f64) -> RGBColor {
    if t.is_nan() {
        return super::NAN_COLOUR;
    }
    let t = t.clamp(-1.0, 1.0);
    let (end, mid) = if t < 0.0 {
        ([33.0, 102.0, 172.0], [247.0, 247.0, 247.0])
    } else {
        ([178.0, 24.0, 43.0], [247.0, 247.0, 247.0])
    };
    let a = t.abs();
    let mix = |k: usize| (mid[k] + a * (end[k] - mid[k])).round() as u8;
    RGBColor(mix(0), mix(1), mix(2))
}

/// A PNG of `panels` side by side, each drawing every element of `model`
/// at its reference position.
pub(in crate::results) fn flat_maps(model: &Model, panels: &[MapPanel<'_>]) -> Result<Vec<u8>> {
    let mut cells = Vec::with_capacity(model.membrane_count());
    for batch in &model.membranes {
        for e in 0..batch.len() {
            cells.push(batch.element_nodes(e).to_vec());
        }
    }
    flat_maps_of(&model.x0, &cells, panels)
}

/// A PNG of `panels` side by side, each drawing the elements `cells`
/// (node indices into `x0`) at the (x, y) of `x0`.
pub(in crate::results) fn flat_maps_of(
    x0: &[Vector3<f64>],
    cells: &[Vec<u32>],
    panels: &[MapPanel<'_>],
) -> Result<Vec<u8>> {
    let elements = cells.len();
    if let Some(p) = panels.iter().find(|p| p.values.len() != elements) {
        return Err(format!(
            "panel `{}` has {} values for {elements} elements",
            p.title,
            p.values.len()
        ));
    }
    let mut polygons = Vec::with_capacity(elements);
    for nodes in cells {
        let corners: Option<Vec<(f64, f64)>> = nodes
            .iter()
            .map(|&n| x0.get(n as usize).map(|p| (p.x, p.y)))
            .collect();
        polygons.push(corners.ok_or("an element names a node that does not exist")?);
    }
    let Some((xr, yr)) = bounds(x0.iter().map(|p| (p.x, p.y))) else {
        return Err("the model has no nodes to draw".into());
    };
    let size = (PANEL.0 * panels.len().max(1) as u32, PANEL.1);
    render(size, |root| {
        let areas = root.split_evenly((1, panels.len().max(1)));
        for (area, panel) in areas.iter().zip(panels) {
            let largest = panel
                .values
                .iter()
                .filter(|v| v.is_finite())
                .fold(0.0f64, |m, v| m.max(v.abs()));
            let scale = panel.scale.unwrap_or(largest);
            let scale = if scale > 0.0 { scale } else { 1.0 };
            let [lo, scale] = match panel.range {
                Some([a, b]) if !panel.signed && a.is_finite() && b.is_finite() && a < b => [a, b],
                _ if panel.signed => [-scale, scale],
                _ => [0.0, scale],
            };
            let colour = |v: f64| {
                if panel.signed {
                    diverging(v / scale)
                } else {
                    viridis((v.abs() - lo) / (scale - lo))
                }
            };
            let body = area.titled(&panel.title, (FAMILY, 20)).map_err(drawing)?;
            let (map_area, bar_area) = body.split_vertically(PANEL.1 - 130);
            // Equal scales: widen the shorter range to the area's aspect.
            let (w, h) = map_area.dim_in_pixel();
            let (pw, ph) = (
                f64::from(w.saturating_sub(90).max(1)),
                f64::from(h.saturating_sub(60).max(1)),
            );
            let mm_per_px = ((xr[1] - xr[0]) / pw).max((yr[1] - yr[0]) / ph);
            let widen = |r: [f64; 2], px: f64| {
                let (c, half) = (0.5 * (r[0] + r[1]), 0.5 * mm_per_px * px);
                c - half..c + half
            };
            let mut chart = ChartBuilder::on(&map_area)
                .margin(10)
                .x_label_area_size(40)
                .y_label_area_size(60)
                .build_cartesian_2d(widen(xr, pw), widen(yr, ph))
                .map_err(drawing)?;
            chart
                .configure_mesh()
                .disable_mesh()
                .x_desc("x₀ (mm)")
                .y_desc("y₀ (mm)")
                .x_label_formatter(&tick)
                .y_label_formatter(&tick)
                .label_style((FAMILY, 14))
                .axis_desc_style((FAMILY, 15))
                .draw()
                .map_err(drawing)?;
            chart
                .draw_series(polygons.iter().zip(panel.values).flat_map(|(corners, &v)| {
                    let c = colour(v);
                    let mut ring = corners.clone();
                    ring.push(corners[0]);
                    [
                        Polygon::new(corners.clone(), c.filled()).into_dyn(),
                        PathElement::new(ring, c.stroke_width(1)).into_dyn(),
                    ]
                }))
                .map_err(drawing)?;

            let mut bar = ChartBuilder::on(&bar_area)
                .margin_left(70)
                .margin_right(30)
                .margin_top(10)
                .margin_bottom(10)
                .x_label_area_size(60)
                .build_cartesian_2d(lo..scale, 0.0..1.0)
                .map_err(drawing)?;
            bar.configure_mesh()
                .disable_mesh()
                .disable_y_axis()
                .x_desc(panel.label.as_str())
                .x_label_formatter(&tick)
                .label_style((FAMILY, 14))
                .axis_desc_style((FAMILY, 15))
                .draw()
                .map_err(drawing)?;
            let steps = 200;
            bar.draw_series((0..steps).map(|k| {
                let (a, b) = (k as f64 / steps as f64, (k + 1) as f64 / steps as f64);
                let (x0, x1) = (lo + a * (scale - lo), lo + b * (scale - lo));
                Rectangle::new([(x0, 0.0), (x1, 1.0)], colour(0.5 * (x0 + x1)).filled())
            }))
            .map_err(drawing)?;
            bar.draw_series([Rectangle::new(
                [(lo, 0.0), (scale, 1.0)],
                BLACK.stroke_width(1),
            )])
            .map_err(drawing)?;
        }
        Ok(())
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_diverging_scale_is_light_at_zero_and_saturates() {
        assert_eq!(diverging(0.0), RGBColor(247, 247, 247));
        assert_eq!(diverging(-1.0), RGBColor(33, 102, 172));
        assert_eq!(diverging(5.0), RGBColor(178, 24, 43));
        assert_eq!(diverging(f64::NAN), super::super::NAN_COLOUR);
    }
}
