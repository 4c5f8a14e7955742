//! `shear_3d.png`: the formed part seen obliquely, coloured by its shear,
//! with the outline of the tools, beside the top view of `shear_map.png`.
//!
//! An orthographic view from azimuth −60° (measured from +x about z) and
//! elevation 35°, z up on the screen: the usual isometric-like look of a
//! part on a press table. Elements are painted far to near (painter's
//! algorithm on their centroids' depth), each with the viridis colour of
//! its |γ| on the scale of the colour bar; no shading, so that a colour
//! reads as a shear angle anywhere. The tools are drawn under the part as
//! their outline in grey: the silhouette (edges between a triangle facing
//! the viewer and one facing away) and their open edges, clipped to the
//! part's surroundings. A small triad shows the axes.
//!
//! A laminate's plies are drawn one per picture (`shear_3d_<ply>.png`):
//! a fraction of a millimetre apart, painted together by their centroids'
//! depth, the plies' elements would show through each other in specks.
//!
//! What it is not: no hidden-line removal for the tools' outline (the part
//! is painted over it, which is what hides what the part hides) and no
//! perspective.

use std::collections::HashMap;

use drape_model::stack::Ply;
use drape_model::{ElementFields, Model, State};
use nalgebra::Vector3;
use plotters::prelude::*;

use super::super::tools::ToolMeshes;
use super::{FAMILY, MAP_SIZE, Result, colour_bar, drawing, human, on_scale, render, shear_scale};

/// The view's azimuth and elevation (degrees).
pub(in crate::results) const VIEW_DEG: (f64, f64) = (-60.0, 35.0);

/// The screen axes of the view: right, up, and towards the viewer.
fn view_axes() -> [Vector3<f64>; 3] {
    let (az, el) = (VIEW_DEG.0.to_radians(), VIEW_DEG.1.to_radians());
    let towards = Vector3::new(el.cos() * az.cos(), el.cos() * az.sin(), el.sin());
    let right = Vector3::new(-az.sin(), az.cos(), 0.0);
    let up = towards.cross(&right);
    [right, up, towards]
}

/// The segment p–q clipped to the box [x0, x1] × [y0, y1] (Liang–Barsky).
fn clip(p: (f64, f64), q: (f64, f64), x: [f64; 2], y: [f64; 2]) -> Option<[(f64, f64); 2]> {
    let (dx, dy) = (q.0 - p.0, q.1 - p.1);
    let (mut t0, mut t1) = (0.0f64, 1.0f64);
    for (den, num) in [
        (-dx, p.0 - x[0]),
        (dx, x[1] - p.0),
        (-dy, p.1 - y[0]),
        (dy, y[1] - p.1),
    ] {
        if den == 0.0 {
            if num < 0.0 {
                return None;
            }
        } else {
            let t = num / den;
            if den < 0.0 {
                t0 = t0.max(t);
            } else {
                t1 = t1.min(t);
            }
        }
    }
    (t0 <= t1).then_some([
        (p.0 + t0 * dx, p.1 + t0 * dy),
        (p.0 + t1 * dx, p.1 + t1 * dy),
    ])
}

/// The outline of one tool seen along `towards`: its silhouette edges and
/// open edges, as pairs of points.
fn outline(
    vertices: &[Vector3<f64>],
    triangles: &[[u32; 3]],
    towards: &Vector3<f64>,
) -> Vec<[Vector3<f64>; 2]> {
    // Per edge: how many triangles use it and how many of them face the
    // viewer.
    let mut edges: HashMap<(u32, u32), (u32, u32)> = HashMap::new();
    for t in triangles {
        let [a, b, c] = t.map(|i| vertices[i as usize]);
        let facing = u32::from((b - a).cross(&(c - a)).dot(towards) > 0.0);
        for k in 0..3 {
            let (i, j) = (t[k], t[(k + 1) % 3]);
            let e = edges.entry((i.min(j), i.max(j))).or_default();
            e.0 += 1;
            e.1 += facing;
        }
    }
    let mut lines: Vec<_> = edges
        .into_iter()
        .filter(|&(_, (uses, facing))| uses == 1 || (uses == 2 && facing == 1))
        .map(|((i, j), _)| (i, j))
        .collect();
    // Hash order is arbitrary: sort, so the picture is the same every run.
    lines.sort_unstable();
    lines
        .into_iter()
        .map(|(i, j)| [vertices[i as usize], vertices[j as usize]])
        .collect()
}

/// One element as the view sees it.
struct Patch {
    /// Its index in [`ElementFields`] order (which the tests check).
    #[cfg_attr(not(test), allow(dead_code))]
    element: usize,
    /// Its corners on the screen (mm).
    corners: Vec<(f64, f64)>,
    /// |γ| in degrees.
    value: f64,
    /// Its centroid's distance towards the viewer, for painting far to near.
    depth: f64,
}

/// What a view draws: the elements of the picture, far to near, and the
/// frame and colour scale it shares with the other plies' pictures.
struct Patches {
    /// The elements drawn, far to near.
    drawn: Vec<Patch>,
    /// The screen's extent of every element of the model (empty ranges,
    /// ∞ to −∞, when none is finite).
    u: [f64; 2],
    v: [f64; 2],
    /// The largest finite |γ| of every element of the model (degrees).
    vmax_all: f64,
}

/// The elements of `model` at `state` seen along the view (with `ply`,
/// that ply's only); the frame and the largest shear are the whole
/// model's either way, so that the plies' pictures share them.
fn view_patches(
    model: &Model,
    state: &State,
    fields: &ElementFields,
    ply: Option<&Ply>,
) -> Result<Patches> {
    let [right, up, towards] = view_axes();
    let screen = |p: &Vector3<f64>| (p.dot(&right), p.dot(&up));
    let mut drawn = Vec::with_capacity(fields.shear.len());
    let (mut u, mut v) = (
        [f64::INFINITY, f64::NEG_INFINITY],
        [f64::INFINITY, f64::NEG_INFINITY],
    );
    let mut vmax_all = 0.0f64;
    let mut element = 0;
    for batch in &model.membranes {
        for e in 0..batch.len() {
            let k = element;
            element += 1;
            let nodes = batch.element_nodes(e);
            let mut corners = Vec::with_capacity(nodes.len());
            let mut centroid = Vector3::zeros();
            for &n in nodes {
                let p = state.x.get(n as usize).ok_or_else(|| {
                    format!(
                        "element {k} names a node beyond the state's {}",
                        state.x.len()
                    )
                })?;
                corners.push(screen(p));
                centroid += p;
            }
            for &(a, b) in &corners {
                if a.is_finite() && b.is_finite() {
                    u = [u[0].min(a), u[1].max(a)];
                    v = [v[0].min(b), v[1].max(b)];
                }
            }
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
            drawn.push(Patch {
                element: k,
                corners,
                value,
                depth: (centroid / nodes.len() as f64).dot(&towards),
            });
        }
    }
    // Far to near: the nearer element hides the farther.
    drawn.sort_by(|a, b| a.depth.total_cmp(&b.depth));
    Ok(Patches {
        drawn,
        u,
        v,
        vmax_all,
    })
}

/// `shear_3d.png` of `model` at `state`, the tools of `tools` displaced by
/// `displacements` along their axes, the colours over the |γ| `range`
/// (None: 0 to the largest).
///
/// With `ply` (`shear_3d_<ply>.png` of a laminate), that ply's elements
/// only, on the frame and colour scale of the whole laminate, so that the
/// plies' pictures compare pixel for pixel and colour for colour.
pub(in crate::results) fn oblique_view(
    model: &Model,
    state: &State,
    fields: &ElementFields,
    tools: &ToolMeshes,
    displacements: &[f64],
    range: Option<[f64; 2]>,
    ply: Option<&Ply>,
) -> Result<Vec<u8>> {
    let [right, up, towards] = view_axes();
    let screen = |p: &Vector3<f64>| (p.dot(&right), p.dot(&up));
    let Patches {
        drawn: patches,
        u,
        v,
        vmax_all,
    } = view_patches(model, state, fields, ply)?;
    let vmax = patches
        .iter()
        .map(|p| p.value)
        .filter(|v| v.is_finite())
        .fold(0.0, f64::max);
    let scale = shear_scale(range, if ply.is_some() { vmax_all } else { vmax });
    // The tools' surroundings: 25 % of the part's size around it.
    let pad = 0.25 * (u[1] - u[0]).max(v[1] - v[0]).max(1.0);
    let (ub, vb) = ([u[0] - pad, u[1] + pad], [v[0] - pad, v[1] + pad]);
    let mut tool_lines = Vec::new();
    for (k, tool) in tools.tools.iter().enumerate() {
        let moved: Vec<Vector3<f64>> = tool
            .vertices_at(displacements.get(k).copied().unwrap_or(0.0))
            .collect();
        for [p, q] in outline(&moved, &tool.triangles, &towards) {
            if let Some(segment) = clip(screen(&p), screen(&q), ub, vb) {
                tool_lines.push(segment);
            }
        }
    }

    let title = match ply {
        None => format!(
            "Shear angle |γ|, oblique view   (time {} s, largest {}°)",
            human(state.time),
            human(vmax)
        ),
        Some(p) => format!(
            "Ply {}: shear angle |γ|, oblique view   (time {} s, largest {}°)",
            p.name,
            human(state.time),
            human(vmax)
        ),
    };
    render(MAP_SIZE, |root| {
        let (w, _) = MAP_SIZE;
        let body = root.titled(&title, (FAMILY, 24)).map_err(drawing)?;
        let (map_area, _) = body.split_horizontally(w - 190);
        if u[0] > u[1] {
            map_area
                .draw(&Text::new("no element to draw", (40, 40), (FAMILY, 20)))
                .map_err(drawing)?;
            return Ok(());
        }
        let (pw, ph) = map_area.dim_in_pixel();
        let margin = 30.0;
        // Equal scales; the part (not the tools) fills the area.
        let (du, dv) = ((u[1] - u[0]).max(1e-9), (v[1] - v[0]).max(1e-9));
        let s = ((f64::from(pw) - 2.0 * margin) / du).min((f64::from(ph) - 2.0 * margin) / dv);
        let (cu, cv) = (0.5 * (u[0] + u[1]), 0.5 * (v[0] + v[1]));
        let to_px = |(a, b): (f64, f64)| {
            (
                (0.5 * f64::from(pw) + (a - cu) * s).round() as i32,
                (0.5 * f64::from(ph) - (b - cv) * s).round() as i32,
            )
        };
        let tool_style = RGBColor(150, 150, 150).stroke_width(1);
        for [p, q] in &tool_lines {
            map_area
                .draw(&PathElement::new(vec![to_px(*p), to_px(*q)], tool_style))
                .map_err(drawing)?;
        }
        let mean_area = fields.area.iter().sum::<f64>() / fields.area.len().max(1) as f64;
        let show_mesh = mean_area.sqrt() * s > 14.0;
        for p in &patches {
            let colour = on_scale(p.value, scale);
            let corners: Vec<(i32, i32)> = p.corners.iter().map(|&c| to_px(c)).collect();
            let mut ring = corners.clone();
            ring.push(corners[0]);
            let edge = if show_mesh {
                BLACK.mix(0.25)
            } else {
                colour.to_rgba()
            };
            map_area
                .draw(&Polygon::new(corners, colour.filled()))
                .map_err(drawing)?;
            map_area
                .draw(&PathElement::new(ring, edge.stroke_width(1)))
                .map_err(drawing)?;
        }

        // The axes' triad in the lower left corner.
        let origin = (50, ph as i32 - 50);
        for (axis, name) in [
            (Vector3::x(), "x"),
            (Vector3::y(), "y"),
            (Vector3::z(), "z"),
        ] {
            let (a, b) = screen(&axis);
            let tip = (
                origin.0 + (34.0 * a).round() as i32,
                origin.1 - (34.0 * b).round() as i32,
            );
            map_area
                .draw(&PathElement::new(vec![origin, tip], BLACK.stroke_width(2)))
                .map_err(drawing)?;
            let label = (
                origin.0 + (46.0 * a).round() as i32 - 4,
                origin.1 - (46.0 * b).round() as i32 - 8,
            );
            map_area
                .draw(&Text::new(name, label, (FAMILY, 16)))
                .map_err(drawing)?;
        }

        let (_, base_y) = map_area.get_base_pixel();
        let rows = base_y + margin as i32..base_y + ph as i32 - margin as i32;
        let key_height = 80;
        let (bar_left, root_y) = colour_bar(root, w, rows.clone(), key_height, scale, "|γ| (deg)")?;
        if !tool_lines.is_empty() {
            let key = root.clone().shrink(
                (bar_left, rows.end - root_y - key_height as i32 + 40),
                (170, 40),
            );
            key.draw(&PathElement::new(vec![(0, 8), (26, 8)], tool_style))
                .map_err(drawing)?;
            key.draw(&Text::new(
                "tool outline",
                (34, 0),
                (FAMILY, 15).into_font().color(&BLACK),
            ))
            .map_err(drawing)?;
        }
        Ok(())
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_ply_s_view_draws_that_ply_s_elements_on_the_laminate_s_frame() {
        let (model, state, fields) = super::super::tests::two_plies();
        let elements = |p: &Patches| {
            let mut e: Vec<usize> = p.drawn.iter().map(|d| d.element).collect();
            e.sort_unstable();
            e
        };
        let all = view_patches(&model, &state, &fields, None).unwrap();
        assert_eq!(elements(&all), (0..13).collect::<Vec<_>>());
        // The top ply's last element: 0.12 rad.
        assert!((all.vmax_all - 0.12f64.to_degrees()).abs() < 1e-12);
        for ply in &model.plies {
            let one = view_patches(&model, &state, &fields, Some(ply)).unwrap();
            assert_eq!(
                elements(&one),
                ply.elements.clone().collect::<Vec<_>>(),
                "{}",
                ply.name
            );
            // Far to near, each patch its own element's shear.
            assert!(one.drawn.windows(2).all(|w| w[0].depth <= w[1].depth));
            for d in &one.drawn {
                assert_eq!(d.value, fields.shear[d.element].abs().to_degrees());
            }
            // The whole laminate's frame and largest shear.
            assert_eq!((one.u, one.v, one.vmax_all), (all.u, all.v, all.vmax_all));
        }
    }

    #[test]
    fn the_view_axes_are_orthonormal_and_z_is_up() {
        let [r, u, t] = view_axes();
        for (a, b) in [(r, u), (u, t), (t, r)] {
            assert!(a.dot(&b).abs() < 1e-15);
        }
        for a in [r, u, t] {
            assert!((a.norm() - 1.0).abs() < 1e-15);
        }
        assert!(r.cross(&u).dot(&t) > 0.999_999, "right-handed");
        assert!(u.z > 0.0 && r.z == 0.0, "z up on the screen");
    }

    #[test]
    fn clipping_keeps_the_part_inside_the_box() {
        let b = [0.0, 1.0];
        assert_eq!(
            clip((-1.0, 0.5), (2.0, 0.5), b, b),
            Some([(0.0, 0.5), (1.0, 0.5)])
        );
        assert_eq!(
            clip((0.2, 0.2), (0.4, 0.6), b, b),
            Some([(0.2, 0.2), (0.4, 0.6)])
        );
        assert_eq!(clip((-1.0, 2.0), (-0.5, 3.0), b, b), None);
    }

    #[test]
    fn a_closed_surface_outlines_its_silhouette_only() {
        // An octahedron seen from +z: its four equator edges are the
        // silhouette; the eight edges to the poles face one way on both
        // sides.
        let v = vec![
            Vector3::new(1.0, 0.0, 0.0),
            Vector3::new(0.0, 1.0, 0.0),
            Vector3::new(-1.0, 0.0, 0.0),
            Vector3::new(0.0, -1.0, 0.0),
            Vector3::new(0.0, 0.0, 1.0),
            Vector3::new(0.0, 0.0, -1.0),
        ];
        let mut t = Vec::new();
        for k in 0..4u32 {
            let (a, b) = (k, (k + 1) % 4);
            t.push([a, b, 4]);
            t.push([b, a, 5]);
        }
        let lines = outline(&v, &t, &Vector3::new(0.0, 0.0, 1.0));
        assert_eq!(lines.len(), 4);
        assert!(lines.iter().all(|[p, q]| p.z == 0.0 && q.z == 0.0));
    }
}
