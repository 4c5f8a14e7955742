//! `[stack]`: a laminate of plies, bottom to top, each a `[fabric]` of
//! its own whose every key defaults to `[fabric]`'s, with the friction
//! between neighbouring plies; built into one model by
//! [`drape_model::Model::stack`].
//!
//! Each ply bends its own yarns (`bending`, as `[fabric]`'s, per ply).
//!
//! Not here: the ply–ply contact (`drape_contact::PlyContact`) and the
//! per-ply results.

use drape_constitutive::Material;
use drape_model::Model;
use drape_model::blank::FibreRepresentation;
use drape_model::stack::PlyModel;
use nalgebra::Vector3;
use serde::{Deserialize, Serialize};

use super::bending::{Whose, decide};
use super::build::{fabric_blank, material};
use super::{BlankSpec, FabricSpec, Locator, MaterialSpec, SceneError, SceneFile, Solver};

/// The most plies a stack may have (real laminates have up to ~100).
pub const MAX_PLIES: usize = 200;

/// `[stack]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StackSpec {
    /// Coulomb coefficient between neighbouring plies, unless a ply gives
    /// its own `friction`.
    #[serde(default)]
    pub friction: f64,
    /// `[[stack.ply]]`, bottom to top.
    pub ply: Vec<PlySpec>,
}

/// `[[stack.ply]]`: every key but `name` and `friction` defaults to
/// `[fabric]`'s.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PlySpec {
    /// Its name (default `ply1`, `ply2`... from the bottom).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub name: Option<String>,
    /// Its material.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub material: Option<MaterialSpec>,
    /// θ, warp angle from x (degrees).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub orientation_deg: Option<f64>,
    /// `trusses` or `embedded`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub fibres: Option<FibreRepresentation>,
    /// Its thickness (mm), replacing the material's.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub thickness: Option<f64>,
    /// Its blank.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub blank: Option<BlankSpec>,
    /// Coulomb coefficient against the ply below (not on the bottom ply).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub friction: Option<f64>,
    /// Yarn bending of this ply (as `fabric.bending`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub bending: Option<bool>,
}

/// One ply's yarn bending, decided with its blank and added once the
/// boundary conditions are known (lines are clamped at fixed nodes).
#[derive(Debug, Clone)]
pub(super) struct PlyBending {
    /// The ply (index into `Model::plies`).
    ply: usize,
    /// Its warp in the blank plane.
    warp: Vector3<f64>,
    /// [warp, weft] (N·mm).
    rigidity: [f64; 2],
    /// The field its errors name.
    field: String,
}

fn coefficient(at: &Locator<'_>, field: &str, mu: f64) -> Result<f64, SceneError> {
    if mu.is_finite() && mu >= 0.0 {
        Ok(mu)
    } else {
        Err(at.error(
            field,
            format!("{mu} is not allowed: expected a friction coefficient ≥ 0"),
        ))
    }
}

/// The stacked model, the bottom ply's default pin (as one blank's) and
/// the plies' yarn bending to add after the boundary conditions
/// ([`add_bending`]).
pub(super) fn build(
    at: &Locator<'_>,
    spec: &SceneFile,
    stack: &StackSpec,
    fabric_material: &Material,
) -> Result<(Model, Vector3<f64>, Vec<PlyBending>), SceneError> {
    if stack.ply.is_empty() || stack.ply.len() > MAX_PLIES {
        return Err(at.error(
            "stack",
            format!(
                "{} plies: expected from 1 to {MAX_PLIES} `[[stack.ply]]` tables",
                stack.ply.len()
            ),
        ));
    }
    if spec.simulation.solver == Solver::Implicit && stack.ply.len() > 1 {
        return Err(at.error(
            "simulation.solver",
            "a stack of plies (ply–ply contact) runs with the explicit solver only: the \
             implicit solver's condensed contact solve has no ply–ply constraints; set \
             `solver = \"explicit\"`",
        ));
    }
    let default_friction = coefficient(at, "stack.friction", stack.friction)?;
    let fabric = &spec.fabric;
    let mut plies = Vec::with_capacity(stack.ply.len());
    let mut settings = Vec::with_capacity(stack.ply.len());
    let mut pin = Vector3::zeros();
    for (i, p) in stack.ply.iter().enumerate() {
        let here = format!("stack.ply[{i}]");
        let name = p.name.clone().unwrap_or_else(|| format!("ply{}", i + 1));
        if name.is_empty()
            || name.contains(['.', '"', ',', '/', '\\', ':', '*', '?', '<', '>', '|'])
            || name.chars().any(|c| c.is_whitespace() || c.is_control())
        {
            return Err(at.error(
                &format!("{here}.name"),
                format!(
                    "`{name}` is not allowed: a ply's name names node sets (`NAME.left`), \
                     results columns and files (`shear_map_NAME.png`), so it is not empty and \
                     has no dot, space, comma, quote or any of / \\ : * ? < > |"
                ),
            ));
        }
        if let Some(j) = plies.iter().position(|q: &PlyModel| q.name == name) {
            return Err(at.error(
                &format!("{here}.name"),
                format!("`{name}` is the name of stack.ply[{j}] already: each ply needs its own"),
            ));
        }
        // The orientation export names each ply's element set and
        // orientations in Abaqus, whose names are case-blind.
        if let Some(q) = plies
            .iter()
            .find(|q: &&PlyModel| q.name.eq_ignore_ascii_case(&name))
        {
            return Err(at.error(
                &format!("{here}.name"),
                format!(
                    "`{name}` differs from the ply `{}` below only in case: the orientations \
                     export names each ply in Abaqus, where case does not count",
                    q.name
                ),
            ));
        }
        let mut material = match &p.material {
            // `fabric.yarn_buckling` holds for every ply.
            Some(m) => material(at, &here, m, fabric.yarn_buckling)?,
            None => fabric_material.clone(),
        };
        if let Some(t) = p.thickness {
            material.thickness = super::limits::length(at, &format!("{here}.thickness"), t)?;
            material.validate().map_err(|e| {
                at.error(
                    &format!("{here}.thickness"),
                    format!("{} is not allowed: expected {}", e.value, e.expected),
                )
            })?;
        }
        let friction_below = match (i, p.friction) {
            (0, Some(_)) => {
                return Err(at.error(
                    &format!("{here}.friction"),
                    "the bottom ply has no ply below it: its friction on a tool is the tool's \
                     `friction`",
                ));
            }
            (_, Some(mu)) => coefficient(at, &format!("{here}.friction"), mu)?,
            (_, None) => default_friction,
        };
        let ply_fabric = FabricSpec {
            material: MaterialSpec::Inline(material.clone()),
            orientation_deg: p.orientation_deg.unwrap_or(fabric.orientation_deg),
            fibres: p.fibres.unwrap_or(fabric.fibres),
            blank: p.blank.clone().unwrap_or_else(|| fabric.blank.clone()),
            bending: None,
            // Already applied to `material` above.
            yarn_buckling: fabric.yarn_buckling,
        };
        // Errors of a ply's own keys point at the ply, of inherited ones
        // at [fabric].
        let table = if p.blank.is_some() || p.fibres.is_some() || p.orientation_deg.is_some() {
            here.as_str()
        } else {
            "fabric"
        };
        let (model, ply_pin) = fabric_blank(at, table, &ply_fabric, &material)?;
        if i == 0 {
            pin = ply_pin;
        }
        let field = match p.bending {
            Some(_) => format!("{here}.bending"),
            None => "fabric.bending".to_owned(),
        };
        settings.push((p.bending.or(fabric.bending), field, material.clone()));
        plies.push(PlyModel {
            model,
            name,
            thickness: material.thickness,
            orientation_deg: ply_fabric.orientation_deg,
            friction_below,
        });
    }
    let model = Model::stack(plies).map_err(|e| at.error("stack", e.to_string()))?;
    // Each ply bends its own yarns: its lines through its own nodes along
    // its own warp, with its own material's rigidity; decided as a
    // `[fabric]` blank's would be.
    let mut bending = Vec::new();
    for (i, (setting, field, material)) in settings.into_iter().enumerate() {
        let ply = &model.plies[i];
        let theta = ply.orientation_deg.to_radians();
        let warp = Vector3::new(theta.cos(), theta.sin(), 0.0);
        let whose = Whose {
            field: &field,
            ply: Some(&ply.name),
        };
        let coverage = || model.yarn_coverage_of(ply.membranes.clone(), warp, Vector3::z());
        if let Some(rigidity) = decide(at, &whose, setting, &material, coverage)? {
            bending.push(PlyBending {
                ply: i,
                warp,
                rigidity,
                field,
            });
        }
    }
    Ok((model, pin, bending))
}

/// Adds the plies' yarn bending to `model` (after its boundary conditions:
/// lines are clamped at the nodes they fix).
pub(super) fn add_bending(
    at: &Locator<'_>,
    model: &mut Model,
    bending: &[PlyBending],
) -> Result<(), SceneError> {
    for b in bending {
        let membranes = model.plies[b.ply].membranes.clone();
        model
            .add_yarn_bending_of(membranes, b.warp, Vector3::z(), b.rigidity)
            .map_err(|e| at.error(&b.field, format!("ply `{}`: {e}", model.plies[b.ply].name)))?;
    }
    Ok(())
}

/// The plies' blank meshes as absolute paths (for a resolved scene).
pub(super) fn absolute_meshes(stack: &mut StackSpec, absolute: impl Fn(&str) -> String) {
    for p in &mut stack.ply {
        if let Some(BlankSpec {
            mesh: Some(mesh), ..
        }) = &mut p.blank
        {
            *mesh = absolute(mesh);
        }
    }
}
