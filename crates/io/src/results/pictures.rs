//! PNG pictures of a result: the shear map seen from above and the shear
//! profiles.
//!
//! Drawn with plotters into an RGB buffer and encoded with `png`, so the
//! file is written whole by the caller. Text uses a subset of DejaVu Sans
//! shipped in `assets/` (licence beside it), registered with plotters'
//! `ab_glyph` font support for measuring text and drawn by [`text`]'s
//! backend wrapper for correct glyph placement: plotters' default `ttf`
//! feature would look fonts up through the system's fontconfig, which a
//! fresh machine lacks.
//! The colour map is viridis (perceptually uniform, readable in grey and
//! by colour-blind readers), sampled from matplotlib's table (CC0).

pub(super) mod fit;
pub(super) mod maps;
pub(super) mod oblique;
pub(super) mod sweep;
mod text;
pub(super) mod work_precision;

use std::collections::BTreeMap;
use std::sync::OnceLock;

use ab_glyph::FontRef;

use drape_model::measures::ProfilePoint;
use drape_model::{ElementFields, Measures, Model, State};
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::FontStyle;
use plotters::style::text_anchor::{HPos, Pos, VPos};

/// DejaVu Sans, subset to Latin-1, Greek and common symbols (see
/// `assets/README.md` for how it was made).
static FONT: &[u8] = include_bytes!("../../assets/DejaVuSans-subset.ttf");

/// The family every text style below asks for.
const FAMILY: &str = "sans-serif";

/// Size of `shear_map.png`, pixels.
const MAP_SIZE: (u32, u32) = (1000, 820);
/// Size of `profiles.png`, pixels.
const PROFILE_SIZE: (u32, u32) = (1000, 600);

/// Viridis at 17 evenly spaced points, interpolated linearly between them
/// (indistinguishable from the 256-entry table at 8 bits per channel).
const VIRIDIS: [[u8; 3]; 17] = [
    [68, 1, 84],
    [72, 24, 106],
    [71, 45, 123],
    [66, 64, 134],
    [59, 82, 139],
    [51, 99, 141],
    [44, 114, 142],
    [38, 130, 142],
    [33, 145, 140],
    [31, 159, 136],
    [39, 173, 129],
    [61, 188, 116],
    [92, 200, 99],
    [129, 211, 77],
    [170, 220, 50],
    [213, 226, 26],
    [253, 231, 37],
];

/// Colour of an element whose shear is not a number.
const NAN_COLOUR: RGBColor = RGBColor(190, 190, 190);
/// The two profile lines (matplotlib's first two default colours).
const DIAGONAL_COLOUR: RGBColor = RGBColor(31, 119, 180);
const MEDIAN_COLOUR: RGBColor = RGBColor(255, 127, 14);

type Result<T> = std::result::Result<T, String>;

/// Plotters' errors carry the backend's error type; the caller only needs
/// the message.
fn drawing<E: std::fmt::Display>(e: E) -> String {
    format!("drawing failed: {e}")
}

/// The shipped font, parsed and registered with plotters once per process.
fn font() -> Result<&'static FontRef<'static>> {
    static FONT_REF: OnceLock<Option<FontRef<'static>>> = OnceLock::new();
    FONT_REF
        .get_or_init(|| {
            let registered =
                plotters::style::register_font(FAMILY, FontStyle::Normal, FONT).is_ok();
            FontRef::try_from_slice(FONT).ok().filter(|_| registered)
        })
        .as_ref()
        .ok_or_else(|| "the shipped font assets/DejaVuSans-subset.ttf cannot be parsed".to_owned())
}

/// The drawing area every picture is drawn on.
type Canvas<'a> = DrawingArea<text::GlyphText<'a, BitMapBackend<'a>>, Shift>;

/// Viridis colour of `t` in [0, 1] (clamped).
fn viridis(t: f64) -> RGBColor {
    if t.is_nan() {
        return NAN_COLOUR;
    }
    let s = t.clamp(0.0, 1.0) * (VIRIDIS.len() - 1) as f64;
    let i = (s.floor() as usize).min(VIRIDIS.len() - 2);
    let f = s - i as f64;
    let [a, b] = [VIRIDIS[i], VIRIDIS[i + 1]];
    let mix = |k: usize| (f64::from(a[k]) + f * (f64::from(b[k]) - f64::from(a[k]))).round() as u8;
    RGBColor(mix(0), mix(1), mix(2))
}

/// `v` with about four significant digits, for titles.
fn human(v: f64) -> String {
    let a = v.abs();
    if v == 0.0 || !v.is_finite() {
        format!("{v}")
    } else if !(1e-4..1e6).contains(&a) {
        format!("{v:.3e}")
    } else {
        let decimals = (3 - a.log10().floor() as i32).clamp(0, 6) as usize;
        let text = format!("{v:.decimals$}");
        // 0.1200 → 0.12: trailing zeros carry no information here.
        if text.contains('.') {
            text.trim_end_matches('0').trim_end_matches('.').to_owned()
        } else {
            text
        }
    }
}

/// Tick labels without float noise ("12.5", not "12.500000000000002").
fn tick(v: &f64) -> String {
    let r = (v * 1e6).round() / 1e6;
    if r == 0.0 {
        "0".to_owned()
    } else {
        format!("{r}")
    }
}

/// An RGB canvas, drawn by `draw` and encoded as PNG.
fn render(size: (u32, u32), draw: impl FnOnce(&Canvas<'_>) -> Result<()>) -> Result<Vec<u8>> {
    let font = font()?;
    let (w, h) = size;
    let mut rgb = vec![255u8; w as usize * h as usize * 3];
    {
        let backend = text::GlyphText {
            inner: BitMapBackend::with_buffer(&mut rgb, size),
            font,
        };
        let root = backend.into_drawing_area();
        root.fill(&WHITE).map_err(drawing)?;
        // Breathing room above the title, which plotters puts at the very top.
        draw(&root.margin(8, 0, 0, 0))?;
        root.present().map_err(drawing)?;
    }
    let mut png_bytes = Vec::new();
    let mut encoder = png::Encoder::new(&mut png_bytes, w, h);
    encoder.set_color(png::ColorType::Rgb);
    encoder.set_depth(png::BitDepth::Eight);
    let encode = |e: png::EncodingError| format!("PNG encoding failed: {e}");
    let mut writer = encoder.write_header().map_err(encode)?;
    writer.write_image_data(&rgb).map_err(encode)?;
    writer.finish().map_err(encode)?;
    Ok(png_bytes)
}

/// One element seen from above.
struct Patch {
    corners: Vec<(f64, f64)>,
    /// |γ| in degrees.
    value: f64,
    /// Height of the centroid, for painting higher elements last.
    z: f64,
}

/// Edges used by one element only (node pairs), in node order: the outline
/// of a mesh, holes included.
pub(crate) fn boundary_edges(model: &Model) -> Vec<[u32; 2]> {
    let mut count: BTreeMap<[u32; 2], u32> = BTreeMap::new();
    for batch in &model.membranes {
        for e in 0..batch.len() {
            let nodes = batch.element_nodes(e);
            for (k, &a) in nodes.iter().enumerate() {
                let b = nodes[(k + 1) % nodes.len()];
                *count.entry([a.min(b), a.max(b)]).or_default() += 1;
            }
        }
    }
    count
        .into_iter()
        .filter(|&(_, c)| c == 1)
        .map(|(edge, _)| edge)
        .collect()
}

/// x and y ranges holding every finite point, padded by 4 % (at least
/// 1 mm, so a degenerate part still has an extent).
fn bounds(points: impl Iterator<Item = (f64, f64)>) -> Option<([f64; 2], [f64; 2])> {
    let mut x = [f64::INFINITY, f64::NEG_INFINITY];
    let mut y = x;
    for (px, py) in points.filter(|(a, b)| a.is_finite() && b.is_finite()) {
        x = [x[0].min(px), x[1].max(px)];
        y = [y[0].min(py), y[1].max(py)];
    }
    if x[0] > x[1] {
        return None;
    }
    let pad = (0.04 * (x[1] - x[0]).max(y[1] - y[0])).max(1.0);
    Some(([x[0] - pad, x[1] + pad], [y[0] - pad, y[1] + pad]))
}

/// The |γ| range (degrees) a shear picture's colours span: `fixed` (the
/// scene's `output.shear_range_deg`), or 0 to the largest `vmax` (to 1
/// when nothing is sheared, so that the bar has a length).
fn shear_scale(fixed: Option<[f64; 2]>, vmax: f64) -> [f64; 2] {
    match fixed {
        Some([lo, hi]) if lo.is_finite() && hi.is_finite() && lo < hi => [lo, hi],
        _ if vmax > 0.0 => [0.0, vmax],
        _ => [0.0, 1.0],
    }
}

/// The viridis colour of `v` on `range` (clamped to its ends).
fn on_scale(v: f64, [lo, hi]: [f64; 2]) -> RGBColor {
    viridis((v - lo) / (hi - lo))
}

/// `shear_map.png`: the part seen from above (x to the right, y up, equal
/// scales), each element filled with the viridis colour of |γ| over
/// `range` (None: 0 to the largest), a colour bar, the blank's outline
/// before forming and the largest shear marked.
///
/// With `ply` (`shear_map_<ply>.png` of a laminate), that ply's elements
/// only, its outline and its largest shear, on the frame and colour scale
/// of the whole laminate's picture, so that the plies' pictures compare
/// pixel for pixel and colour for colour.
pub(super) fn shear_map(
    model: &Model,
    state: &State,
    fields: &ElementFields,
    measures: &Measures,
    range: Option<[f64; 2]>,
    ply: Option<&drape_model::stack::Ply>,
) -> Result<Vec<u8>> {
    let mut patches = Vec::with_capacity(fields.shear.len());
    // The laminate's largest |γ|: the colour scale of every ply's picture.
    let mut vmax_all = 0.0f64;
    let mut element = 0;
    for batch in &model.membranes {
        for e in 0..batch.len() {
            let k = element;
            element += 1;
            let value = fields
                .shear
                .get(k)
                .map_or(f64::NAN, |g| g.abs().to_degrees());
            if value.is_finite() {
                vmax_all = vmax_all.max(value);
            }
            if ply.is_some_and(|p| !p.elements.contains(&k)) {
                continue;
            }
            let nodes = batch.element_nodes(e);
            let corners = nodes
                .iter()
                .map(|&n| state.x.get(n as usize).map(|p| (p.x, p.y)));
            let corners: Option<Vec<_>> = corners.collect();
            let Some(corners) = corners else {
                return Err(format!(
                    "element {} names a node beyond the state's {}",
                    patches.len(),
                    state.x.len()
                ));
            };
            let z = nodes.iter().map(|&n| state.x[n as usize].z).sum::<f64>() / nodes.len() as f64;
            patches.push(Patch { corners, value, z });
        }
    }
    // Painter's order: seen from above, the higher element hides the lower.
    patches.sort_by(|a, b| a.z.total_cmp(&b.z));
    let vmax = patches
        .iter()
        .map(|p| p.value)
        .filter(|v| v.is_finite())
        .fold(0.0, f64::max);
    let scale = shear_scale(range, if ply.is_some() { vmax_all } else { vmax });
    let mut outline = boundary_edges(model);
    let mut max_shear_at = measures.max_shear_at;
    if let Some(p) = ply {
        let nodes = p.nodes.clone();
        outline.retain(|edge| edge.iter().all(|n| nodes.contains(n)));
        // The ply's own largest shear (its first element of the largest,
        // as the laminate's is found).
        let mut largest: Option<(usize, f64)> = None;
        for k in p.elements.clone() {
            let v = fields.shear.get(k).map_or(f64::NAN, |g| g.abs());
            if v.is_finite() && largest.is_none_or(|(_, b)| v > b) {
                largest = Some((k, v));
            }
        }
        max_shear_at = largest
            .and_then(|(k, _)| fields.centroid.get(k))
            .map_or([f64::NAN; 3], |c| [c.x, c.y, c.z]);
    }

    // No "=" in titles: plotters 0.3.7's ab_glyph text drops each glyph's
    // left side bearing, which glues "=" to the character before it.
    let title = match ply {
        None => format!(
            "Shear angle |γ| seen from above   (time {} s, largest {}°)",
            human(state.time),
            human(vmax)
        ),
        Some(p) => format!(
            "Ply {}: shear angle |γ| seen from above   (time {} s, largest {}°)",
            p.name,
            human(state.time),
            human(vmax)
        ),
    };
    render(MAP_SIZE, |root| {
        let (w, _) = MAP_SIZE;
        let body = root.titled(&title, (FAMILY, 24)).map_err(drawing)?;
        let (map_area, _) = body.split_horizontally(w - 190);
        let all = state.x.iter().chain(&model.x0).map(|p| (p.x, p.y));
        let Some((mut xr, mut yr)) = bounds(all) else {
            map_area
                .draw(&Text::new("no element to draw", (40, 40), (FAMILY, 20)))
                .map_err(drawing)?;
            return Ok(());
        };
        let builder = |area| {
            let mut b = ChartBuilder::on(area);
            b.margin(12).x_label_area_size(56).y_label_area_size(76);
            b
        };
        // Equal scales on x and y: measure the plotting area, then widen
        // the shorter range about its centre to the area's aspect ratio.
        let (pw, ph) = builder(&map_area)
            .build_cartesian_2d(0.0..1.0, 0.0..1.0)
            .map_err(drawing)?
            .plotting_area()
            .dim_in_pixel();
        let mm_per_px = ((xr[1] - xr[0]) / f64::from(pw)).max((yr[1] - yr[0]) / f64::from(ph));
        let widen = |r: &mut [f64; 2], px: u32| {
            let (c, half) = (0.5 * (r[0] + r[1]), 0.5 * mm_per_px * f64::from(px));
            *r = [c - half, c + half];
        };
        widen(&mut xr, pw);
        widen(&mut yr, ph);
        let mut chart = builder(&map_area)
            .build_cartesian_2d(xr[0]..xr[1], yr[0]..yr[1])
            .map_err(drawing)?;
        chart
            .configure_mesh()
            .disable_mesh()
            .x_desc("x (mm)")
            .y_desc("y (mm)")
            .x_label_formatter(&tick)
            .y_label_formatter(&tick)
            .label_style((FAMILY, 16))
            .axis_desc_style((FAMILY, 18))
            .draw()
            .map_err(drawing)?;

        // Element edges are drawn only when elements are big enough on
        // screen for a mesh line not to drown the colours; otherwise each
        // polygon is outlined in its own colour, which closes the hairline
        // gaps the rasteriser leaves between neighbours.
        let mean_area = fields.area.iter().sum::<f64>() / fields.area.len().max(1) as f64;
        let show_mesh = mean_area.sqrt() / mm_per_px > 14.0;
        chart
            .draw_series(patches.iter().flat_map(|p| {
                let colour = on_scale(p.value, scale);
                let mut ring = p.corners.clone();
                ring.push(p.corners[0]);
                let edge = if show_mesh {
                    BLACK.mix(0.25)
                } else {
                    colour.to_rgba()
                };
                [
                    Polygon::new(p.corners.clone(), colour.filled()).into_dyn(),
                    PathElement::new(ring, edge.stroke_width(1)).into_dyn(),
                ]
            }))
            .map_err(drawing)?;

        let outline_style = RGBColor(120, 120, 120).stroke_width(2);
        chart
            .draw_series(outline.iter().map(|&[a, b]| {
                let (p, q) = (model.x0[a as usize], model.x0[b as usize]);
                PathElement::new(vec![(p.x, p.y), (q.x, q.y)], outline_style)
            }))
            .map_err(drawing)?;

        let [mx, my, _] = max_shear_at;
        if vmax > 0.0 && mx.is_finite() && my.is_finite() {
            chart
                .draw_series([
                    Circle::new((mx, my), 9, WHITE.stroke_width(4)),
                    Circle::new((mx, my), 9, BLACK.stroke_width(2)),
                ])
                .map_err(drawing)?;
        }

        // The colour bar, as tall as the map's plotting area, in the column
        // to its right; under it, the key to the outline and the marker.
        let (_, rows) = chart.plotting_area().get_pixel_range();
        let key_height = 110;
        let (bar_left, base_y) = colour_bar(root, w, rows.clone(), key_height, scale, "|γ| (deg)")?;
        let key_top = rows.end - base_y - key_height as i32 + 40;
        let key = root.clone().shrink((bar_left, key_top), (170, 70));
        let text = (FAMILY, 15).into_font().color(&BLACK);
        key.draw(&PathElement::new(vec![(0, 8), (26, 8)], outline_style))
            .map_err(drawing)?;
        key.draw(&Text::new("blank outline", (34, 0), text.clone()))
            .map_err(drawing)?;
        key.draw(&Text::new("before forming", (34, 17), text.clone()))
            .map_err(drawing)?;
        key.draw(&Circle::new((13, 50), 7, BLACK.stroke_width(2)))
            .map_err(drawing)?;
        key.draw(&Text::new("largest |γ|", (34, 42), text))
            .map_err(drawing)?;
        Ok(())
    })
}

/// `waviness_map.png`: the element waviness (the wrinkle indicator,
/// [`drape_model::measures::waviness`]) on the flat blank, each element at
/// its reference position: a fold or wrinkle hidden under the formed part
/// seen from above still shows, at the place of the blank it happened to.
/// The colours run from 0 to the largest waviness, but at least to twice
/// the wrinkle threshold, so that the few tenths of a degree a smooth part
/// has stay dark instead of filling the scale.
///
/// With `ply` (`waviness_map_<ply>.png` of a laminate), that ply's
/// elements only, on the frame and colour scale of the whole laminate:
/// on the flat blank the plies lie on one another, and the top one would
/// hide a fold of the one below.
pub(super) fn waviness_map(
    model: &Model,
    fields: &ElementFields,
    measures: &Measures,
    ply: Option<&drape_model::stack::Ply>,
) -> Result<Vec<u8>> {
    let threshold = drape_model::measures::WRINKLE_THRESHOLD_DEG;
    let largest = fields
        .waviness
        .iter()
        .filter(|v| v.is_finite())
        .fold(0.0f64, |a, &b| a.max(b));
    let Some(p) = ply else {
        return maps::flat_maps(
            model,
            &[maps::MapPanel {
                title: format!(
                    "Waviness, flat blank: largest {}°, {} mm² above {}°",
                    human(largest),
                    human(measures.wrinkle_area),
                    human(threshold)
                ),
                values: &fields.waviness,
                label: "waviness (deg)".into(),
                signed: false,
                scale: Some(largest.max(2.0 * threshold)),
                range: None,
            }],
        );
    };
    let PlyCells {
        cells,
        waviness: values,
        area,
    } = ply_cells(model, fields, p)?;
    let (ply_largest, wavy) = drape_model::measures::wrinkle_indicator(values, area);
    maps::flat_maps_of(
        &model.x0,
        &cells,
        &[maps::MapPanel {
            title: format!(
                "Ply {}: waviness, flat blank: largest {}°, {} mm² above {}°",
                p.name,
                human(ply_largest),
                human(wavy),
                human(threshold)
            ),
            values,
            label: "waviness (deg)".into(),
            signed: false,
            scale: Some(largest.max(2.0 * threshold)),
            range: None,
        }],
    )
}

/// What a ply's waviness map draws.
struct PlyCells<'a> {
    /// Its elements' nodes, in [`ElementFields`] order.
    cells: Vec<Vec<u32>>,
    /// Their waviness (degrees)...
    waviness: &'a [f64],
    /// ...and reference area (mm²).
    area: &'a [f64],
}

/// The elements of `ply` with their waviness and reference area.
fn ply_cells<'a>(
    model: &Model,
    fields: &'a ElementFields,
    ply: &drape_model::stack::Ply,
) -> Result<PlyCells<'a>> {
    let e = ply.elements.clone();
    let (Some(values), Some(area)) = (fields.waviness.get(e.clone()), fields.area.get(e.clone()))
    else {
        return Err(format!(
            "ply `{}` has elements {}..{} of {} with fields",
            ply.name,
            e.start,
            e.end,
            fields.waviness.len().min(fields.area.len())
        ));
    };
    let mut cells = Vec::with_capacity(e.len());
    for b in ply.membranes.clone() {
        let batch = model.membranes.get(b).ok_or_else(|| {
            format!(
                "ply `{}` names membrane batch {b} of {}",
                ply.name,
                model.membranes.len()
            )
        })?;
        for k in 0..batch.len() {
            cells.push(batch.element_nodes(k).to_vec());
        }
    }
    if cells.len() != e.len() {
        return Err(format!(
            "ply `{}`: its batches hold {} elements, not its {}",
            ply.name,
            cells.len(),
            e.len()
        ));
    }
    Ok(PlyCells {
        cells,
        waviness: values,
        area,
    })
}

/// The viridis colour bar of `label` over `[lo, hi]` in the right-hand
/// column (170 px) of a picture `w` pixels wide, over the absolute pixel
/// rows `rows` less `key_height` at their foot (for a key). Returns the
/// bar's left edge relative to `root` and `root`'s vertical offset.
fn colour_bar(
    root: &Canvas<'_>,
    w: u32,
    rows: std::ops::Range<i32>,
    key_height: u32,
    [lo, hi]: [f64; 2],
    label: &str,
) -> Result<(i32, i32)> {
    // Pixel ranges are absolute, `shrink` offsets relative to `root`.
    let (base_x, base_y) = root.get_base_pixel();
    let bar_left = (w - 170) as i32 - base_x;
    let bar_height = (rows.end - rows.start).max(1) as u32;
    let bar_area = root.clone().shrink(
        (bar_left, rows.start - base_y),
        (150, bar_height.saturating_sub(key_height)),
    );
    let mut bar = ChartBuilder::on(&bar_area)
        .margin_right(4)
        .right_y_label_area_size(66)
        .build_cartesian_2d(0.0..1.0, lo..hi)
        .map_err(drawing)?;
    bar.configure_mesh()
        .disable_mesh()
        .disable_x_axis()
        .y_desc(label)
        .y_label_formatter(&tick)
        .label_style((FAMILY, 16))
        .axis_desc_style((FAMILY, 18))
        .draw()
        .map_err(drawing)?;
    let steps = 256;
    bar.draw_series((0..steps).map(|k| {
        let (a, b) = (k as f64 / steps as f64, (k + 1) as f64 / steps as f64);
        Rectangle::new(
            [(0.0, lo + a * (hi - lo)), (1.0, lo + b * (hi - lo))],
            viridis(0.5 * (a + b)).filled(),
        )
    }))
    .map_err(drawing)?;
    bar.draw_series([Rectangle::new(
        [(0.0, lo), (1.0, hi)],
        BLACK.stroke_width(1),
    )])
    .map_err(drawing)?;
    Ok((bar_left, base_y))
}

/// The finite points of a profile as (distance, |γ|).
fn magnitudes(points: &[ProfilePoint]) -> Vec<(f64, f64)> {
    points
        .iter()
        .filter(|p| p.distance.is_finite() && p.shear_deg.is_finite())
        .map(|p| (p.distance, p.shear_deg.abs()))
        .collect()
}

/// Points (sorted by distance) averaged at equal distances: an even grid
/// puts two rows of elements at the same distance from a median, and a
/// line through both would zigzag.
fn mean_curve(points: &[(f64, f64)]) -> Vec<(f64, f64)> {
    let mut curve: Vec<(f64, f64, usize)> = Vec::new();
    for &(distance, value) in points {
        match curve.last_mut() {
            Some((d, sum, n)) if (distance - *d).abs() <= 1e-9 * d.abs().max(1.0) => {
                *sum += value;
                *n += 1;
            }
            _ => curve.push((distance, value, 1)),
        }
    }
    curve
        .into_iter()
        .map(|(d, sum, n)| (d, sum / n as f64))
        .collect()
}

/// `profiles.png`: |shear angle| against signed initial distance from the
/// blank's centre, along the diagonal and the median, each element a dot
/// and a line through their means.
///
/// Magnitudes, as on the shear map: the two rows of elements beside a
/// median shear in opposite senses by symmetry, and the mean of signed
/// values would draw a flat line through a sheared region. `profiles.csv`
/// keeps the signs.
pub(super) fn profiles(measures: &Measures, time: f64) -> Result<Vec<u8>> {
    profiles_of(
        &measures.profile_diagonal,
        &measures.profile_median,
        time,
        None,
    )
}

/// [`profiles`] of the `diagonal` and `median` of the ply named `ply`
/// (`profiles_<ply>.png`), or of the model's blank for None.
pub(super) fn profiles_of(
    diagonal: &[ProfilePoint],
    median: &[ProfilePoint],
    time: f64,
    ply: Option<&str>,
) -> Result<Vec<u8>> {
    let lines = [
        ("diagonal".to_owned(), magnitudes(diagonal), DIAGONAL_COLOUR),
        (
            "median (parallel to x)".to_owned(),
            magnitudes(median),
            MEDIAN_COLOUR,
        ),
    ];
    let title = match ply {
        None => format!(
            "Shear along the blank's diagonal and median   (time {} s)",
            human(time)
        ),
        Some(ply) => format!(
            "Ply {ply}: shear along its blank's diagonal and median   (time {} s)",
            human(time)
        ),
    };
    profile_lines(&title, &lines)
}

/// Several shear profiles on one plot (runs side by side, like the paper's
/// Figs. 7 and 12): |γ| against the signed initial distance from the
/// blank's centre, each curve in the next of matplotlib's `tab10` colours.
pub(super) fn profile_comparison(
    title: &str,
    curves: &[(String, &[ProfilePoint])],
) -> Result<Vec<u8>> {
    let lines: Vec<ProfileLine> = curves
        .iter()
        .enumerate()
        .map(|(k, (name, points))| {
            let palette = &sweep::PALETTE;
            (name.clone(), magnitudes(points), palette[k % palette.len()])
        })
        .collect();
    profile_lines(title, &lines)
}

/// One curve of a profile plot: its name, its (distance, |γ|) points and
/// its colour.
type ProfileLine = (String, Vec<(f64, f64)>, RGBColor);

/// Draws `lines` (name, (distance, |γ|) points, colour): a dot per element
/// and a line through the means at equal distances.
fn profile_lines(title: &str, lines: &[ProfileLine]) -> Result<Vec<u8>> {
    let all: Vec<(f64, f64)> = lines.iter().flat_map(|l| l.1.iter().copied()).collect();
    let (mut x0, mut x1, mut y1) = (f64::INFINITY, f64::NEG_INFINITY, 0.0f64);
    for &(d, g) in &all {
        (x0, x1, y1) = (x0.min(d), x1.max(d), y1.max(g));
    }
    let xpad = (0.03 * (x1 - x0)).max(0.5);
    let ytop = if y1 > 0.0 { 1.1 * y1 } else { 1.0 };
    render(PROFILE_SIZE, |root| {
        if all.is_empty() {
            // No axes: empty axes would suggest a profile of zeros.
            let (w, h) = PROFILE_SIZE;
            let body = root.titled(title, (FAMILY, 24)).map_err(drawing)?;
            let note = "No profile: the model was not meshed from a rectangular blank.";
            let style = (FAMILY, 20)
                .into_font()
                .color(&BLACK)
                .pos(Pos::new(HPos::Center, VPos::Center));
            body.draw(&Text::new(note, (w as i32 / 2, h as i32 / 2 - 40), style))
                .map_err(drawing)?;
            return Ok(());
        }
        let mut chart = ChartBuilder::on(root)
            .caption(title, (FAMILY, 24))
            .margin(16)
            .x_label_area_size(56)
            .y_label_area_size(76)
            .build_cartesian_2d((x0 - xpad)..(x1 + xpad), 0.0..ytop)
            .map_err(drawing)?;
        chart
            .configure_mesh()
            .max_light_lines(1)
            .light_line_style(RGBColor(242, 242, 242))
            .bold_line_style(RGBColor(222, 222, 222))
            .x_desc("initial distance from the blank's centre (mm)")
            .y_desc("|shear angle γ| (deg)")
            .x_label_formatter(&tick)
            .y_label_formatter(&tick)
            .label_style((FAMILY, 16))
            .axis_desc_style((FAMILY, 18))
            .draw()
            .map_err(drawing)?;
        for (name, points, colour) in lines {
            let colour = *colour;
            chart
                .draw_series(LineSeries::new(mean_curve(points), colour.stroke_width(2)))
                .map_err(drawing)?
                .label(format!("{name}, {} elements", points.len()))
                .legend(move |(x, y)| {
                    EmptyElement::at((x, y))
                        + PathElement::new(vec![(-10, 0), (10, 0)], colour.stroke_width(2))
                        + Circle::new((0, 0), 3, colour.filled())
                });
            chart
                .draw_series(points.iter().map(|&p| Circle::new(p, 3, colour.filled())))
                .map_err(drawing)?;
        }
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::UpperMiddle)
            .label_font((FAMILY, 16))
            .background_style(WHITE.mix(0.9))
            .border_style(RGBColor(160, 160, 160))
            .draw()
            .map_err(drawing)?;
        Ok(())
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A laminate of two 40 mm plies, 2 × 2 quads under 3 × 3 (their
    /// element sets differ in size), flat, each element's shear its index
    /// in hundredths of a radian (the top ply has the largest).
    pub(super) fn two_plies() -> (Model, State, ElementFields) {
        use drape_model::blank::{ElementKind, FibreRepresentation, Meshing, RectangleBlank};
        use drape_model::stack::PlyModel;
        let material = drape_constitutive::Material::preset("glass-serge-4x3").unwrap();
        let h = material.thickness;
        let ply = |name: &str, cells: usize| {
            let blank = RectangleBlank {
                width: 40.0,
                height: 40.0,
                center: nalgebra::Vector3::zeros(),
                orientation_deg: 0.0,
                element: ElementKind::Quad,
                meshing: Meshing::Cells([cells, cells]),
                fibres: FibreRepresentation::Embedded,
            };
            let mesh = blank.mesh().unwrap();
            PlyModel {
                model: Model::from_mesh(&mesh, &material, FibreRepresentation::Embedded).unwrap(),
                name: name.into(),
                thickness: h,
                orientation_deg: 0.0,
                friction_below: 0.0,
            }
        };
        let model = Model::stack(vec![ply("low", 2), ply("high", 3)]).unwrap();
        let state = model.initial_state();
        let mut fields = model.element_fields(&state).unwrap();
        for (k, g) in fields.shear.iter_mut().enumerate() {
            *g = 0.01 * k as f64;
        }
        (model, state, fields)
    }

    #[test]
    fn each_ply_s_waviness_map_draws_that_ply_s_elements() {
        let (model, _, fields) = two_plies();
        let mut all = Vec::new();
        for b in &model.membranes {
            for e in 0..b.len() {
                all.push(b.element_nodes(e).to_vec());
            }
        }
        assert_eq!(all.len(), 4 + 9);
        for ply in &model.plies {
            let drawn = ply_cells(&model, &fields, ply).unwrap();
            assert_eq!(drawn.cells, all[ply.elements.clone()], "{}", ply.name);
            assert!(drawn.cells.iter().flatten().all(|n| ply.nodes.contains(n)));
            assert_eq!(drawn.waviness, &fields.waviness[ply.elements.clone()]);
            assert_eq!(drawn.area, &fields.area[ply.elements.clone()]);
        }
        assert_eq!(model.plies[0].elements, 0..4);
        assert_eq!(model.plies[1].elements, 4..13);
        // Fields of another model are an error, not a panic.
        let mut short = fields.clone();
        short.waviness.truncate(5);
        let Err(e) = ply_cells(&model, &short, &model.plies[1]) else {
            panic!("short fields accepted");
        };
        assert!(e.contains("ply `high`"), "{e}");
    }

    #[test]
    fn viridis_ends_and_clamps() {
        assert_eq!(viridis(0.0), RGBColor(68, 1, 84));
        assert_eq!(viridis(1.0), RGBColor(253, 231, 37));
        assert_eq!(viridis(-3.0), viridis(0.0));
        assert_eq!(viridis(7.0), viridis(1.0));
        assert_eq!(viridis(f64::NAN), NAN_COLOUR);
    }

    #[test]
    fn titles_use_about_four_digits() {
        assert_eq!(human(0.0), "0");
        assert_eq!(human(0.12), "0.12");
        assert_eq!(human(42.345_678), "42.35");
        assert_eq!(human(1.5e-7), "1.500e-7");
    }

    #[test]
    fn mean_curve_merges_equal_distances() {
        let p = |distance, shear_deg| ProfilePoint {
            distance,
            shear_deg,
        };
        let points = magnitudes(&[p(-1.0, 2.0), p(-1.0, -4.0), p(0.0, 1.0), p(1.0, f64::NAN)]);
        assert_eq!(mean_curve(&points), vec![(-1.0, 3.0), (0.0, 1.0)]);
    }

    #[test]
    fn a_fixed_shear_range_replaces_the_largest() {
        assert_eq!(shear_scale(None, 23.0), [0.0, 23.0]);
        assert_eq!(shear_scale(None, 0.0), [0.0, 1.0]);
        assert_eq!(shear_scale(Some([10.0, 60.0]), 23.0), [10.0, 60.0]);
        // A colour is its place on the range, the ends clamped.
        assert_eq!(on_scale(35.0, [10.0, 60.0]), viridis(0.5));
        assert_eq!(on_scale(5.0, [10.0, 60.0]), viridis(0.0));
        assert_eq!(on_scale(75.0, [10.0, 60.0]), viridis(1.0));
        assert_eq!(on_scale(f64::NAN, [10.0, 60.0]), NAN_COLOUR);
    }

    #[test]
    fn shipped_font_registers() {
        font().unwrap();
    }
}
