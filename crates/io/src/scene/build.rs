//! From a read [`SceneFile`] to a [`Model`] and the drivers' settings:
//! every value checked, every error located. Reading the file is
//! [`super::Scene::parse`]'s work.

use std::path::Path;

use drape_constitutive::Material;
use drape_contact::{Amplitude, Surface, Tool, ToolMotion};
use drape_elements::{ForceTable, SpringBatch};
use drape_model::blank::{ElementKind, FibreRepresentation, Meshing, RectangleBlank};
use drape_model::{BoundaryCondition, Model, ModelError, Motion, NodalLoad};
use drape_time::{ExplicitSettings, GuardSettings, ImplicitSettings};
use nalgebra::Vector3;

use super::bending::yarn_bending;
use super::limits;
use super::locate::Locator;
use super::placement::{self, Placement};
use super::{
    BcMotionSpec, FabricSpec, GeometrySpec, MAX_FRAMES, MaterialSpec, MotionSpec, NodeSelection,
    Pointing, PressureSpec, SceneError, SceneFile, open_mesh,
};

fn vector(v: [f64; 3]) -> Vector3<f64> {
    Vector3::from(v)
}

pub(super) fn positive(at: &Locator<'_>, field: &str, v: f64) -> Result<f64, SceneError> {
    if v.is_finite() && v > 0.0 {
        Ok(v)
    } else {
        Err(at.error(
            field,
            format!("{v} is not allowed: expected a positive number"),
        ))
    }
}

pub(super) fn finite3(
    at: &Locator<'_>,
    field: &str,
    v: [f64; 3],
) -> Result<Vector3<f64>, SceneError> {
    if v.iter().all(|x| x.is_finite()) {
        Ok(vector(v))
    } else {
        Err(at.error(field, "every component must be a finite number"))
    }
}

pub(super) fn unit(at: &Locator<'_>, field: &str, v: [f64; 3]) -> Result<Vector3<f64>, SceneError> {
    limits::direction(at, field, v)
}

fn amplitude(at: &Locator<'_>, field: &str, a: &Amplitude) -> Result<Amplitude, SceneError> {
    a.validate().map_err(|m| {
        // The key the message is about, when it is one of the table's.
        let key = match a {
            Amplitude::Ramp { .. } | Amplitude::SmoothStep { .. } => ".duration",
            Amplitude::Table { .. } => ".points",
            Amplitude::Constant => "",
        };
        at.error(&format!("{field}{key}"), m)
    })?;
    Ok(a.clone())
}

/// A `[[pressure]]` on `model` (its tools already in): the elements
/// selected, oriented to the side asked for.
fn pressure(
    at: &Locator<'_>,
    here: &str,
    model: &Model,
    p: &PressureSpec,
) -> Result<drape_model::PressureLoad, SceneError> {
    if !(p.value.is_finite() && p.value >= 0.0) {
        return Err(at.error(
            &format!("{here}.value"),
            format!(
                "{} is not allowed: expected a pressure ≥ 0 in MPa (0.1 is one bar); \
                 `towards` or `side` says which way it pushes",
                p.value
            ),
        ));
    }
    let amplitude = amplitude(at, &format!("{here}.amplitude"), &p.amplitude)?;
    let selected = match &p.nodes {
        Some(sel) => Some(nodes(at, &format!("{here}.nodes"), model, sel)?),
        None => None,
    };
    let load = |flip| {
        drape_model::PressureLoad::on_membranes(
            model,
            selected.as_deref(),
            flip,
            p.value,
            amplitude.clone(),
        )
    };
    let plus = load(false);
    if plus.is_empty() {
        return Err(at.error(
            &format!("{here}.nodes"),
            "no element of the blank has all its nodes in this selection: the pressure would act on nothing",
        ));
    }
    let flip = match (&p.towards, p.side.as_deref()) {
        (Some(_), Some(_)) | (None, None) => {
            return Err(at.error(
                here,
                "give exactly one of `towards = \"<tool name>\"` and `side = \"+\"` or `\"-\"`",
            ));
        }
        (None, Some("+")) => false,
        (None, Some("-")) => true,
        (None, Some(other)) => {
            return Err(at.error(
                &format!("{here}.side"),
                format!("`{other}` is not allowed: expected \"+\" (along the blank's normal, +z for a rectangle) or \"-\""),
            ));
        }
        (Some(name), None) => {
            let field = format!("{here}.towards");
            let Some(tool) = model.tools.iter().find(|t| &t.name == name) else {
                let known: Vec<&str> = model.tools.iter().map(|t| t.name.as_str()).collect();
                return Err(at.error(
                    &field,
                    if known.is_empty() {
                        format!("unknown tool `{name}`: the scene has no tools; use `side` instead")
                    } else {
                        format!("unknown tool `{name}`; the tools are: {}", known.join(", "))
                    },
                ));
            };
            // Which way the elements' normals (node order) face the tool,
            // weighted by area: the tool's side of the blank at the start.
            let (mut facing, mut total) = (0.0, 0.0);
            for e in 0..plus.len() {
                let nodes = plus.element(e);
                let area = drape_model::pressure::vector_area(nodes, &model.x0);
                let centroid = nodes
                    .iter()
                    .map(|&n| model.x0[n as usize])
                    .sum::<Vector3<f64>>()
                    / nodes.len() as f64;
                let to = tool.surface.project(&centroid).point - centroid;
                let d = to.norm();
                if d > 0.0 {
                    facing += area.dot(&to) / d;
                }
                total += area.norm();
            }
            if facing.is_nan() || facing.abs() <= 0.05 * total {
                return Err(at.error(
                    &field,
                    format!(
                        "cannot tell which side of the blank tool `{name}` is on (it lies \
                         edgewise to the blank or on both sides of it): give `side = \"+\"` \
                         (along +z for a rectangle) or `side = \"-\"` instead"
                    ),
                ));
            }
            facing < 0.0
        }
    };
    if model.plies.len() > 1 {
        return outer_ply_pressure(
            at,
            here,
            model,
            &plus,
            selected.as_deref(),
            flip,
            p,
            amplitude,
        );
    }
    Ok(if flip { load(true) } else { plus })
}

/// A `[[pressure]]` on a stack: on its outer ply on the side the pressure
/// comes from, the top ply for one pushing down the stack and the bottom
/// ply for one pushing up (`plus`: the load on every ply unflipped, for
/// its direction). A bag presses the laminate, not each ply: loaded ply by
/// ply, a stack of n plies pressed the tool under it n times as hard, and
/// each interface by the plies above it. `selected` narrows the loaded
/// elements within that ply.
#[allow(clippy::too_many_arguments)]
fn outer_ply_pressure(
    at: &Locator<'_>,
    here: &str,
    model: &Model,
    plus: &drape_model::PressureLoad,
    selected: Option<&[u32]>,
    flip: bool,
    p: &PressureSpec,
    amplitude: drape_model::Amplitude,
) -> Result<drape_model::PressureLoad, SceneError> {
    let up = model.stack_up();
    let along_up: f64 = (0..plus.len())
        .map(|e| drape_model::pressure::vector_area(plus.element(e), &model.x0).dot(&up))
        .sum();
    let pushes_up = (along_up > 0.0) != flip;
    let (ply, which) = if pushes_up {
        (model.plies.first(), "bottom")
    } else {
        (model.plies.last(), "top")
    };
    let ply = ply.expect("a stack has plies");
    let mut chosen = vec![selected.is_none(); model.node_count()];
    for &n in selected.unwrap_or(&[]) {
        if let Some(c) = chosen.get_mut(n as usize) {
            *c = true;
        }
    }
    let nodes: Vec<u32> = ply.nodes.clone().filter(|&n| chosen[n as usize]).collect();
    let load =
        drape_model::PressureLoad::on_membranes(model, Some(&nodes), flip, p.value, amplitude);
    if load.is_empty() {
        return Err(at.error(
            &format!("{here}.nodes"),
            format!(
                "on a stack a pressure acts on its outer ply on the side it comes from: this one \
                 pushes {} the stack, onto its {which} ply `{}`, and the selection has no element \
                 of that ply (name a set of `{}`, e.g. `{}.left`, or leave `nodes` out)",
                if pushes_up { "up" } else { "down" },
                ply.name,
                ply.name,
                ply.name
            ),
        ));
    }
    Ok(load)
}

/// The nodes `held`, grouped by their share of the blank's outline (mm):
/// half the reference length of each outline edge (an edge of one element
/// only) they end. Groups in order of first appearance, nodes in the given
/// order, so the model does not depend on anything but the scene. A node
/// off the outline has no share: that is an error naming it, since a
/// force "per mm of edge" means nothing there.
fn edge_shares(
    at: &Locator<'_>,
    field: &str,
    model: &Model,
    held: &[u32],
) -> Result<Vec<(f64, Vec<u32>)>, SceneError> {
    let mut share = vec![0.0; model.x0.len()];
    for [a, b] in crate::results::boundary_edges(model) {
        let half = 0.5 * (model.x0[a as usize] - model.x0[b as usize]).norm();
        share[a as usize] += half;
        share[b as usize] += half;
    }
    let mut groups: Vec<(f64, Vec<u32>)> = Vec::new();
    for &n in held {
        let s = share[n as usize];
        if s == 0.0 {
            return Err(at.error(
                field,
                format!(
                    "node {n} is not on the blank's edge, so `per_length` gives it no share of a \
                     force per mm of edge: hold only edge nodes (the set `boundary`, an edge set)"
                ),
            ));
        }
        // Equal shares to the last bit (a uniform grid) share a batch.
        match groups.iter_mut().find(|(g, _)| g.to_bits() == s.to_bits()) {
            Some((_, nodes)) => nodes.push(n),
            None => groups.push((s, vec![n])),
        }
    }
    Ok(groups)
}

fn nodes(
    at: &Locator<'_>,
    field: &str,
    model: &Model,
    sel: &NodeSelection,
) -> Result<Vec<u32>, SceneError> {
    match sel {
        NodeSelection::Set(name) => {
            if let Ok(set) = model.node_set(name) {
                return Ok(set.to_vec());
            }
            // Set names are matched regardless of case when that is not
            // ambiguous: Abaqus's are case-insensitive (`*NSET, NSET=Clamp`
            // is `clamp`), and a rectangle's `LEFT` can only mean `left`.
            let same: Vec<&String> = model
                .node_sets
                .keys()
                .filter(|k| k.eq_ignore_ascii_case(name))
                .collect();
            if let [only] = same[..] {
                return Ok(model.node_sets[only].clone());
            }
            let known: Vec<&str> = model.node_sets.keys().map(String::as_str).collect();
            Err(at.error(
                field,
                if same.is_empty() {
                    format!(
                        "unknown node set `{name}`; known sets: {}",
                        known.join(", ")
                    )
                } else {
                    let names: Vec<&str> = same.iter().map(|s| s.as_str()).collect();
                    format!(
                        "`{name}` matches the sets {} when case is ignored: write the name \
                         exactly as one of them",
                        names.join(", ")
                    )
                },
            ))
        }
        NodeSelection::Sets(names) => {
            let mut all = Vec::new();
            for name in names {
                all.extend(nodes(at, field, model, &NodeSelection::Set(name.clone()))?);
            }
            all.sort_unstable();
            all.dedup();
            Ok(all)
        }
        NodeSelection::List(list) => {
            let count = model.node_count();
            match list.iter().find(|&&n| n as usize >= count) {
                Some(n) => Err(at.error(
                    field,
                    format!("node {n} does not exist (the blank has {count} nodes)"),
                )),
                None => Ok(list.clone()),
            }
        }
    }
}

/// The model of a rectangular blank, and its bottom-left corner (the
/// default pin of a picture frame).
/// The model of a blank, a rectangle or a mesh file, for `table`.
pub(super) fn fabric_blank(
    at: &Locator<'_>,
    table: &str,
    fabric: &FabricSpec,
    material: &Material,
) -> Result<(Model, Vector3<f64>), SceneError> {
    match &fabric.blank.mesh {
        Some(file) => mesh_blank(at, table, fabric, file, material),
        None => rectangle_blank(at, table, fabric, material),
    }
}

fn rectangle_blank(
    at: &Locator<'_>,
    table: &str,
    fabric: &FabricSpec,
    material: &Material,
) -> Result<(Model, Vector3<f64>), SceneError> {
    let b = &fabric.blank;
    let mesh_keys = [
        ("units", b.units.is_some()),
        ("scale", b.scale.is_some()),
        ("rotate", b.rotate.is_some()),
        ("offset", b.offset.is_some()),
        ("reorient", b.reorient.is_some()),
    ];
    if let Some((key, _)) = mesh_keys.iter().find(|(_, given)| *given) {
        return Err(at.error(
            &format!("{table}.blank.{key}"),
            format!(
                "`{key}` places a blank read from a mesh file (`mesh = \"file.msh\"`); a \
                 rectangle is placed by `center`"
            ),
        ));
    }
    let (Some(width), Some(height)) = (b.width, b.height) else {
        let missing = if b.width.is_none() { "width" } else { "height" };
        return Err(at.error(
            &format!("{table}.blank"),
            format!(
                "`{missing}` is missing: give `width`, `height` and `cells` (or `element_size`) \
                 for a rectangle, or `mesh = \"file.msh\"` (or .inp) for a meshed blank"
            ),
        ));
    };
    limits::length(at, &format!("{table}.blank.width"), width)?;
    limits::length(at, &format!("{table}.blank.height"), height)?;
    let meshing = match (b.cells, b.element_size) {
        (Some(c), None) => Meshing::Cells(c),
        (None, Some(h)) => Meshing::Size(limits::length(
            at,
            &format!("{table}.blank.element_size"),
            h,
        )?),
        _ => {
            return Err(at.error(
                &format!("{table}.blank"),
                "give exactly one of `cells = [nx, ny]` and `element_size`",
            ));
        }
    };
    let blank = RectangleBlank {
        width,
        height,
        center: limits::position(
            at,
            &format!("{table}.blank.center"),
            b.center.unwrap_or_default(),
        )?,
        orientation_deg: fabric.orientation_deg,
        element: b.element.unwrap_or(ElementKind::Quad),
        meshing,
        fibres: fabric.fibres,
    };
    let model = Model::from_blank(&blank, material).map_err(|e| match e {
        ModelError::Mesh(drape_model::blank::MeshError::Invalid {
            field,
            value,
            expected,
        }) => {
            let path = match field {
                "orientation_deg" => format!("{table}.orientation_deg"),
                "meshing" => format!("{table}.blank.cells"),
                f => format!("{table}.blank.{f}"),
            };
            at.error(&path, format!("{value} is not allowed: {expected}"))
        }
        other => at.error(table, other.to_string()),
    })?;
    let corner = blank.center - Vector3::new(0.5 * blank.width, 0.5 * blank.height, 0.0);
    Ok((model, corner))
}

/// The model of a blank meshed in a file (`fabric.blank.mesh`, relative to
/// the scene file), with embedded fibres along the warp (cos θ, sin θ, 0)
/// projected on each element; and its bounding box's low corner (the
/// default pin of a picture frame).
fn mesh_blank(
    at: &Locator<'_>,
    table: &str,
    fabric: &FabricSpec,
    file: &str,
    material: &Material,
) -> Result<(Model, Vector3<f64>), SceneError> {
    let b = &fabric.blank;
    let rectangle_keys = [
        ("width", b.width.is_some()),
        ("height", b.height.is_some()),
        ("center", b.center.is_some()),
        ("element", b.element.is_some()),
        ("cells", b.cells.is_some()),
        ("element_size", b.element_size.is_some()),
    ];
    if let Some((key, _)) = rectangle_keys.iter().find(|(_, given)| *given) {
        return Err(at.error(
            &format!("{table}.blank.{key}"),
            format!(
                "`{key}` describes a rectangle and cannot be combined with `mesh`: a blank is \
                 either a rectangle (`width`, `height`, `cells` or `element_size`) or a mesh file"
            ),
        ));
    }
    if fabric.fibres != FibreRepresentation::Embedded {
        return Err(at.error(
            &format!("{table}.fibres"),
            "a blank from a mesh file needs `fibres = \"embedded\"`: trusses need the \
             fibre-aligned lattice that drape meshes itself",
        ));
    }
    if !fabric.orientation_deg.is_finite() {
        return Err(at.error(
            &format!("{table}.orientation_deg"),
            "must be a finite angle",
        ));
    }
    let placement = Placement::new(
        at,
        &format!("{table}.blank"),
        b.units,
        b.scale,
        b.rotate,
        b.offset,
    )?;
    let path = at.file.parent().unwrap_or(Path::new(".")).join(file);
    let (mut mesh, turned) = if b.reorient == Some(true) {
        crate::mesh_import::read_mesh_reoriented(&path)
    } else {
        crate::mesh_import::read_mesh(&path).map(|m| (m, 0))
    }
    .map_err(|e| at.error(&format!("{table}.blank.mesh"), e.to_string()))?;
    if turned > 0 {
        at.warn(
            &format!("{table}.blank.reorient"),
            format!(
                "{}: turned {turned} element{} over to the node order of their neighbours",
                path.display(),
                if turned == 1 { "" } else { "s" }
            ),
        );
    }
    placement.check(at, &format!("{table}.blank"), "mesh", &mesh.x0)?;
    limits::mesh_size(
        at,
        &format!("{table}.blank.mesh"),
        mesh.quad_labels.len() + mesh.triangle_labels.len(),
        "element",
        limits::BLANK_BYTES_PER_ELEMENT,
        Some(limits::MAX_BLANK_ELEMENTS),
    )?;
    for x in &mut mesh.x0 {
        *x = placement.apply(x);
    }
    // drape works in mm: a blank of less than a millimetre or more than ten
    // metres across is most likely a file in another unit.
    let (low, high) = mesh.x0.iter().fold(
        (
            Vector3::repeat(f64::INFINITY),
            Vector3::repeat(f64::NEG_INFINITY),
        ),
        |(l, h), x| (l.inf(x), h.sup(x)),
    );
    let size = (high - low).norm();
    if !(1.0..=10_000.0).contains(&size) {
        at.warn(
            &format!("{table}.blank.mesh"),
            format!(
                "{}: the blank is {size:.3e} mm across, after `units`/`scale`: drape's lengths \
                 are in mm; if the file is in another unit, give `units = \"m\"` (or \"cm\", \
                 \"in\") or `scale` in [{table}.blank]",
                path.display()
            ),
        );
    }
    let model = Model::from_mesh(
        &mesh.blank_mesh(fabric.orientation_deg),
        material,
        FibreRepresentation::Embedded,
    )
    .map_err(|e| {
        let message = match &e {
            // The batch's index back to the file's label.
            ModelError::Element { kind, error } => {
                let labels = if *kind == "quad" {
                    &mesh.quad_labels
                } else {
                    &mesh.triangle_labels
                };
                match labels.get(error.element) {
                    Some(label) => format!(
                        "{}: element {label} ({kind}): {} (at integration point {})",
                        path.display(),
                        error.cause,
                        error.point
                    ),
                    None => format!("{}: {e}", path.display()),
                }
            }
            _ => format!("{}: {e}", path.display()),
        };
        at.error(&format!("{table}.blank.mesh"), message)
    })?;
    let low = mesh
        .x0
        .iter()
        .fold(Vector3::repeat(f64::INFINITY), |m, x| m.inf(x));
    Ok((model, low))
}

/// The material of `table` (`fabric` or a ply): a preset, a card file
/// beside the scene, or a table of values; validated.
pub(super) fn material(
    at: &Locator<'_>,
    table: &str,
    spec: &MaterialSpec,
    yarn_buckling: Option<bool>,
) -> Result<Material, SceneError> {
    let material = match spec {
        // A card file (`drape fit … --out card.toml`), beside the scene.
        MaterialSpec::Preset(name) if super::spec::is_card(name) => {
            let path = at.file.parent().unwrap_or(Path::new(".")).join(name);
            let text = std::fs::read_to_string(&path).map_err(|e| {
                at.error(
                    &format!("{table}.material"),
                    format!("material card {}: {e}", path.display()),
                )
            })?;
            toml::from_str::<Material>(&text).map_err(|e| {
                at.error(
                    &format!("{table}.material"),
                    format!("material card {}: {}", path.display(), e.message()),
                )
            })?
        }
        MaterialSpec::Preset(name) => Material::preset(name).ok_or_else(|| {
            at.error(
                &format!("{table}.material"),
                format!(
                    "unknown preset `{name}`: expected one of {}, a material card \
                     (`card.toml`, beside the scene) or a table of values",
                    drape_constitutive::PRESET_NAMES.join(", ")
                ),
            )
        })?,
        MaterialSpec::Inline(m) => m.clone(),
    };
    let material = super::yarn_buckling::apply(yarn_buckling, material, at)?;
    material.validate().map_err(|e| {
        at.error(
            &format!("{table}.material.{}", e.field),
            format!("{} is not allowed: expected {}", e.value, e.expected),
        )
    })?;
    Ok(material)
}

pub(super) fn build(
    spec: &SceneFile,
    at: &Locator<'_>,
) -> Result<(Model, ExplicitSettings, ImplicitSettings), SceneError> {
    let sim = &spec.simulation;
    positive(at, "simulation.end_time", sim.end_time)?;
    if sim.frames == 0 || sim.frames > MAX_FRAMES {
        return Err(at.error(
            "simulation.frames",
            format!(
                "{} is not allowed: expected from 1 to {MAX_FRAMES} frames (each frame is a \
                 VTU file of the whole blank)",
                sim.frames
            ),
        ));
    }
    if !(sim.safety_factor > 0.0 && sim.safety_factor <= 1.0) {
        return Err(at.error(
            "simulation.safety_factor",
            format!(
                "{} is not allowed: expected a number in (0, 1]",
                sim.safety_factor
            ),
        ));
    }
    if let Some(dt) = sim.time_step {
        positive(at, "simulation.time_step", dt)?;
    }
    if let Some(dt) = sim.mass_scaling_dt {
        positive(at, "simulation.mass_scaling_dt", dt)?;
    }
    if !(sim.damping.is_finite() && sim.damping >= 0.0) {
        return Err(at.error(
            "simulation.damping",
            format!("{} is not allowed: expected ≥ 0", sim.damping),
        ));
    }
    if let Some(e) = sim.max_energy_error {
        positive(at, "simulation.max_energy_error", e)?;
    }
    positive(at, "simulation.contact_margin", sim.contact_margin)?;
    for (field, value) in [
        ("simulation.initial_increment", sim.initial_increment),
        ("simulation.max_increment", sim.max_increment),
        ("simulation.min_increment", sim.min_increment),
    ] {
        if let Some(v) = value {
            positive(at, field, v)?;
        }
    }
    if !(0.0..=1.0).contains(&sim.spectral_radius) {
        return Err(at.error(
            "simulation.spectral_radius",
            format!(
                "{} is not allowed: expected a number in [0, 1]",
                sim.spectral_radius
            ),
        ));
    }
    positive(at, "simulation.force_tolerance", sim.force_tolerance)?;
    positive(
        at,
        "simulation.displacement_tolerance",
        sim.displacement_tolerance,
    )?;
    positive(at, "simulation.gap_tolerance", sim.gap_tolerance)?;
    if sim.max_iterations == 0 {
        return Err(at.error(
            "simulation.max_iterations",
            "0 is not allowed: expected at least 1 Newton iteration",
        ));
    }

    let fabric = &spec.fabric;
    let material = material(at, "fabric", &fabric.material, fabric.yarn_buckling)?;
    let (mut model, default_pin, ply_bending) = match &spec.stack {
        Some(stack) => super::stack::build(at, spec, stack, &material)?,
        None => {
            let (model, pin) = fabric_blank(at, "fabric", fabric, &material)?;
            (model, pin, Vec::new())
        }
    };

    for (i, t) in spec.tools.iter().enumerate() {
        let here = format!("tools[{i}]");
        if !(t.friction.is_finite() && t.friction >= 0.0) {
            return Err(at.error(
                &format!("{here}.friction"),
                format!(
                    "{} is not allowed: expected a friction coefficient ≥ 0",
                    t.friction
                ),
            ));
        }
        let g = format!("{here}.geometry");
        let surface_err = |e: drape_contact::SurfaceError| at.error(&g, e.to_string());
        let surface = match &t.geometry {
            GeometrySpec::Plane { point, normal } => Surface::plane(
                limits::position(at, &format!("{g}.point"), *point)?,
                unit(at, &format!("{g}.normal"), *normal)?,
            )
            .map_err(surface_err)?,
            GeometrySpec::Sphere { center, radius } => {
                limits::length(at, &format!("{g}.radius"), *radius)?;
                Surface::sphere(
                    limits::position(at, &format!("{g}.center"), *center)?,
                    *radius,
                )
                .map_err(surface_err)?
            }
            GeometrySpec::HemisphericalPunch {
                pole,
                radius,
                shank,
                pointing,
            } => {
                limits::length(at, &format!("{g}.radius"), *radius)?;
                limits::length(at, &format!("{g}.shank"), *shank)?;
                let pole = limits::position(at, &format!("{g}.pole"), *pole)?;
                match pointing {
                    Pointing::Up => Surface::hemispherical_punch(pole, *radius, *shank),
                    Pointing::Down => Surface::hemispherical_punch_down(pole, *radius, *shank),
                }
                .map_err(surface_err)?
            }
            GeometrySpec::Die {
                center,
                opening_radius,
                fillet_radius,
                depth,
                outer_radius,
            } => {
                let (a, f) = (
                    limits::length(at, &format!("{g}.opening_radius"), *opening_radius)?,
                    limits::length(at, &format!("{g}.fillet_radius"), *fillet_radius)?,
                );
                limits::length(at, &format!("{g}.depth"), *depth)?;
                if outer_radius.is_nan() || *outer_radius <= a + f {
                    return Err(at.error(
                        &format!("{g}.outer_radius"),
                        format!("{outer_radius} is not allowed: expected more than opening + fillet radius ({})", a + f),
                    ));
                }
                limits::length(at, &format!("{g}.outer_radius"), *outer_radius)?;
                Surface::die(
                    limits::position(at, &format!("{g}.center"), *center)?,
                    a,
                    f,
                    *depth,
                    *outer_radius,
                )
                .map_err(surface_err)?
            }
            GeometrySpec::Ring {
                center,
                inner_radius,
                outer_radius,
                edge_radius,
                thickness,
            } => {
                limits::length(at, &format!("{g}.inner_radius"), *inner_radius)?;
                if !(edge_radius.is_finite()
                    && *edge_radius >= 0.0
                    && *edge_radius <= limits::MAX_COORDINATE_MM)
                {
                    return Err(at.error(
                        &format!("{g}.edge_radius"),
                        format!(
                            "{edge_radius} is not allowed: expected a radius ≥ 0 (0: a sharp \
                             edge), at most {:e} mm",
                            limits::MAX_COORDINATE_MM
                        ),
                    ));
                }
                if outer_radius.is_nan() || *outer_radius <= inner_radius + edge_radius {
                    return Err(at.error(
                        &format!("{g}.outer_radius"),
                        format!(
                            "{outer_radius} is not allowed: expected more than the inner radius plus the edge radius ({})",
                            inner_radius + edge_radius
                        ),
                    ));
                }
                limits::length(at, &format!("{g}.outer_radius"), *outer_radius)?;
                let thickness = match thickness {
                    Some(t) => {
                        if !(t.is_finite() && *t > 0.0 && t >= edge_radius) {
                            return Err(at.error(
                                &format!("{g}.thickness"),
                                format!("{t} is not allowed: expected a height > 0 and at least the edge radius ({edge_radius})"),
                            ));
                        }
                        *t
                    }
                    None => f64::max(10.0, 2.0 * edge_radius),
                };
                Surface::ring(
                    limits::position(at, &format!("{g}.center"), *center)?,
                    *inner_radius,
                    *outer_radius,
                    *edge_radius,
                    thickness,
                )
                .map_err(surface_err)?
            }
            GeometrySpec::Revolution { origin, profile } => Surface::revolution(
                limits::position(at, &format!("{g}.origin"), *origin)?,
                profile.clone(),
            )
            .map_err(surface_err)?,
            GeometrySpec::Mesh {
                file,
                offset,
                units,
                scale,
                rotate,
                reorient,
                drop_degenerate,
                instance,
                flip_normals,
                rim_extension,
            } => {
                let placement = Placement::new(at, &g, *units, *scale, *rotate, Some(*offset))?;
                let options = drape_contact::RepairOptions {
                    drop_degenerate: *drop_degenerate,
                    reorient: *reorient,
                };
                let surface =
                    placement::tool_mesh(at, &g, file, &placement, options, instance.as_deref())?;
                let open = open_mesh::OpenMesh {
                    flip_normals: *flip_normals,
                    rim_extension: *rim_extension,
                };
                open_mesh::place(at, &g, &t.name, surface, &open, &model, &material)?
            }
        };
        let m = format!("{here}.motion");
        let motion = match &t.motion {
            MotionSpec::Fixed => ToolMotion::Fixed,
            MotionSpec::Displacement {
                direction,
                distance,
                amplitude: a,
            } => ToolMotion::Displacement {
                direction: unit(at, &format!("{m}.direction"), *direction)?,
                distance: if distance.is_finite() {
                    *distance
                } else {
                    return Err(at.error(&format!("{m}.distance"), "must be a finite number"));
                },
                amplitude: amplitude(at, &format!("{m}.amplitude"), a)?,
            },
            MotionSpec::Force {
                direction,
                force,
                amplitude: a,
                mass,
            } => ToolMotion::Force {
                direction: unit(at, &format!("{m}.direction"), *direction)?,
                force: if force.is_finite() {
                    *force
                } else {
                    return Err(at.error(&format!("{m}.force"), "must be a finite number"));
                },
                amplitude: amplitude(at, &format!("{m}.amplitude"), a)?,
                mass: positive(at, &format!("{m}.mass"), *mass)?,
            },
        };
        model.tools.push(Tool {
            name: t.name.clone(),
            surface,
            motion,
            friction: t.friction,
        });
    }

    for (i, s) in spec.springs.iter().enumerate() {
        let here = format!("springs[{i}]");
        let held = nodes(at, &format!("{here}.nodes"), &model, &s.nodes)?;
        let table = match (&s.table, s.stiffness) {
            (Some(t), None) => {
                ForceTable::new(t).map_err(|e| at.error(&format!("{here}.table"), e.to_string()))?
            }
            (None, Some(k)) => {
                limits::stiffness(at, &format!("{here}.stiffness"), k)?;
                limits::force(at, &format!("{here}.preload"), s.preload)?;
                ForceTable::linear(k, s.preload)
            }
            _ => {
                return Err(at.error(
                    &here,
                    "give exactly one of `stiffness` (with an optional `preload`) and `table`",
                ));
            }
        };
        if !(s.rest_length.is_finite()
            && s.rest_length >= 0.0
            && s.rest_length <= limits::MAX_COORDINATE_MM)
        {
            return Err(at.error(
                &format!("{here}.rest_length"),
                format!(
                    "{} is not allowed: expected a length ≥ 0, at most {:e} mm",
                    s.rest_length,
                    limits::MAX_COORDINATE_MM
                ),
            ));
        }
        let offset = limits::position(at, &format!("{here}.anchor_offset"), s.anchor_offset)?;
        // Anchored at its node, a spring starts at zero length: a force
        // there pulls in no direction, and near the anchor its transverse
        // stiffness F/l has no bound (no time step is stable).
        let (start, _) = table.force_and_stiffness(offset.norm() - s.rest_length);
        // As short as a subnormal, it is zero to the mechanics (its
        // direction, F/l) but not to the test below.
        if offset != Vector3::zeros() && offset.norm() < limits::MIN_MESH_SIZE_MM {
            return Err(at.error(
                &format!("{here}.anchor_offset"),
                format!(
                    "a spring {:e} mm long has no usable direction: give an anchor_offset of at \
                     least {:e} mm, or [0, 0, 0] with no force at the start",
                    offset.norm(),
                    limits::MIN_MESH_SIZE_MM
                ),
            ));
        }
        if offset == Vector3::zeros() && start != 0.0 {
            return Err(at.error(
                &here,
                format!(
                    "a spring anchored at its own node starts at zero length, where its force of {start} N \
                     has no direction: give an anchor_offset, or no force at the start (preload, rest_length)"
                ),
            ));
        }
        // Per length: one batch per distinct edge share, its forces scaled
        // by the share (a table's extensions stay as given).
        let groups = if s.per_length {
            edge_shares(at, &format!("{here}.nodes"), &model, &held)?
        } else {
            vec![(1.0, held)]
        };
        for (share, held) in groups {
            let table = match (&s.table, s.stiffness) {
                (Some(t), _) if share != 1.0 => {
                    ForceTable::new(&t.iter().map(|&[d, f]| [d, share * f]).collect::<Vec<_>>())
                        .map_err(|e| at.error(&format!("{here}.table"), e.to_string()))?
                }
                (None, Some(k)) if share != 1.0 => ForceTable::linear(share * k, share * s.preload),
                _ => table.clone(),
            };
            model.springs.push(SpringBatch {
                table,
                anchors: held
                    .iter()
                    .map(|&n| model.x0[n as usize] + offset)
                    .collect(),
                rest_length: vec![s.rest_length; held.len()],
                nodes: held,
            });
        }
    }

    for (i, bc) in spec.boundary.iter().enumerate() {
        let here = format!("boundary[{i}]");
        let held = nodes(at, &format!("{here}.nodes"), &model, &bc.nodes)?;
        let mut components = [false; 3];
        for ch in bc.components.chars() {
            match ch {
                'x' => components[0] = true,
                'y' => components[1] = true,
                'z' => components[2] = true,
                other => {
                    return Err(at.error(
                        &format!("{here}.components"),
                        format!("`{other}` is not allowed: expected some of the letters x, y, z"),
                    ));
                }
            }
        }
        let motion = match &bc.motion {
            BcMotionSpec::Fixed => Motion::Fixed,
            BcMotionSpec::Displacement {
                value,
                amplitude: a,
            } => Motion::Displacement {
                value: finite3(at, &format!("{here}.motion.value"), *value)?,
                amplitude: amplitude(at, &format!("{here}.motion.amplitude"), a)?,
            },
            BcMotionSpec::Velocity {
                value,
                amplitude: a,
            } => Motion::Velocity {
                value: finite3(at, &format!("{here}.motion.value"), *value)?,
                amplitude: amplitude(at, &format!("{here}.motion.amplitude"), a)?,
            },
            BcMotionSpec::PictureFrame {
                shear_deg,
                amplitude: a,
                pin,
            } => {
                if !(shear_deg.is_finite() && shear_deg.abs() < 90.0) {
                    return Err(at.error(
                        &format!("{here}.motion.shear_deg"),
                        format!("{shear_deg} is not allowed: expected a shear angle between −90° and 90°"),
                    ));
                }
                let pin = match pin {
                    Some(p) => limits::position(at, &format!("{here}.motion.pin"), *p)?,
                    None => default_pin,
                };
                let a = amplitude(at, &format!("{here}.motion.amplitude"), a)?;
                let gamma = shear_deg.to_radians();
                Motion::Trajectory(std::sync::Arc::new(move |x0: &Vector3<f64>, t: f64| {
                    let (s, c) = (0.5 * gamma * a.value(t)).sin_cos();
                    let d = x0 - pin;
                    Vector3::new(c * d.x + s * d.y, s * d.x + c * d.y, d.z) - d
                }))
            }
        };
        model.boundary.push(BoundaryCondition {
            nodes: held,
            components,
            motion,
        });
    }

    for (i, l) in spec.loads.iter().enumerate() {
        let here = format!("loads[{i}]");
        let loaded = nodes(at, &format!("{here}.nodes"), &model, &l.nodes)?;
        let force = finite3(at, &format!("{here}.force"), l.force)?;
        let amplitude = amplitude(at, &format!("{here}.amplitude"), &l.amplitude)?;
        let groups = if l.per_length {
            edge_shares(at, &format!("{here}.nodes"), &model, &loaded)?
        } else {
            vec![(1.0, loaded)]
        };
        for (share, nodes) in groups {
            model.loads.push(NodalLoad {
                nodes,
                force: share * force,
                amplitude: amplitude.clone(),
            });
        }
    }
    if let Some(g) = spec.gravity {
        model.gravity = finite3(at, "gravity", g)?;
    }
    for (i, p) in spec.pressure.iter().enumerate() {
        let load = pressure(at, &format!("pressure[{i}]"), &model, p)?;
        model.pressure.push(load);
    }
    // After the boundary conditions: lines are clamped at the fixed nodes.
    let bending = match &spec.stack {
        Some(_) => {
            super::stack::add_bending(at, &mut model, &ply_bending)?;
            None
        }
        None => yarn_bending(fabric, &material, &model, at)?,
    };
    if let Some(rigidity) = bending {
        let theta = fabric.orientation_deg.to_radians();
        let warp = Vector3::new(theta.cos(), theta.sin(), 0.0);
        model
            .add_yarn_bending(warp, Vector3::z(), rigidity)
            .map_err(|e| at.error("fabric.bending", e.to_string()))?;
    }
    if !(spec.output.locking_angle_deg.is_finite() && spec.output.locking_angle_deg > 0.0) {
        return Err(at.error("output.locking_angle_deg", "expected a positive angle"));
    }
    if let Some([lo, hi]) = spec.output.shear_range_deg
        && !(lo.is_finite() && hi.is_finite() && 0.0 <= lo && lo < hi)
    {
        return Err(at.error(
            "output.shear_range_deg",
            format!(
                "[{lo}, {hi}]: expected [min, max] in degrees of |γ|, finite, with 0 ≤ min < max"
            ),
        ));
    }
    let guard = GuardSettings {
        enabled: sim.instability_guard,
        max_energy_error: sim.max_energy_error.or(GuardSettings::default()
            .max_energy_error
            .filter(|_| sim.instability_guard)),
        max_kinetic_ratio: sim
            .quasi_static
            .then_some(drape_time::guard::QUASI_STATIC_KINETIC_RATIO),
        ..GuardSettings::default()
    };
    let settings = ExplicitSettings {
        end_time: sim.end_time,
        safety_factor: sim.safety_factor,
        time_step: sim.time_step,
        mass_scaling: sim.mass_scaling_dt,
        damping: sim.damping,
        frames: sim.frames,
        guard: guard.clone(),
        contact_margin: sim.contact_margin,
        ..ExplicitSettings::default()
    };
    let implicit = ImplicitSettings {
        end_time: sim.end_time,
        frames: sim.frames,
        initial_increment: sim.initial_increment,
        max_increment: sim.max_increment,
        min_increment: sim.min_increment,
        spectral_radius: sim.spectral_radius,
        force_tolerance: sim.force_tolerance,
        displacement_tolerance: sim.displacement_tolerance,
        gap_tolerance: sim.gap_tolerance,
        max_iterations: sim.max_iterations,
        damping: sim.damping,
        contact_margin: sim.contact_margin,
        mass_scaling: sim.mass_scaling_dt,
        safety_factor: sim.safety_factor,
        membrane_tangent: sim.membrane_tangent.into(),
        contact_solver: sim.contact_solver.into(),
        guard,
        ..ImplicitSettings::default()
    };
    super::implicit_checks::check(at, &implicit, &model)?;
    Ok((model, settings, implicit))
}
