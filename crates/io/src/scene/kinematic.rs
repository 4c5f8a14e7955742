//! `[kinematic]`: how `drape kinematic` drapes the scene's blank as a
//! pin-jointed net (drape-fishnet): which tool is the mould, where the net
//! starts, the yarn spacing, the draping direction and the generators.
//!
//! Every key has the default a forming engineer expects, so a forming
//! scene drapes kinematically without the table: the mould is the scene's
//! only tool (or its only moving one), the seed is the blank's centre put
//! on the mould along the draping direction (the top of a punch under the
//! blank), the warp leaves it along the blank's orientation, the spacing is
//! the blank's element size, the draping direction is against the mould's
//! motion (−z for a fixed mould). When the table is absent and a default
//! cannot be found (several tools, a blank from a mesh file), the scene
//! still loads for `drape run` and the reason is kept for `drape kinematic`.

use drape_fishnet::NetSpec;
use drape_model::Model;
use drape_model::blank::BlankFrame;
use nalgebra::Vector3;
use serde::{Deserialize, Serialize};

use super::{Locator, SceneError, SceneFile, finite3, positive, unit};

/// `[kinematic]`.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct KinematicSpec {
    /// The name of the tool the net is draped on.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mould: Option<String>,
    /// The flat blank's point (x, y) where the net starts (mm).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub seed: Option<[f64; 2]>,
    /// The side of a net cell, the yarn spacing (mm).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub spacing: Option<f64>,
    /// The direction in which the blank moves onto the mould.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub direction: Option<[f64; 3]>,
    /// The warp generator: points of a curve on the mould through the
    /// seed, in the mould's own coordinates.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub warp_generator: Option<Vec<[f64; 3]>>,
    /// The weft generator, likewise.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub weft_generator: Option<Vec<[f64; 3]>>,
}

/// A kinematic drape ready to run.
#[derive(Debug, Clone, PartialEq)]
pub struct KinematicSetup {
    /// Index of the mould in the model's tools.
    pub mould: usize,
    /// The mould's displacement along its motion at the scene's end time
    /// (mm; 0 for a fixed or force-driven tool): the net is moved with it,
    /// so that it lies where a forming run's part does.
    pub mould_displacement: f64,
    /// The net.
    pub net: NetSpec,
}

/// The setup of `spec`'s `[kinematic]` table (or of its defaults) on the
/// built `model`. Errors name the table's fields and lines.
pub(super) fn setup(
    spec: &SceneFile,
    model: &Model,
    at: &Locator<'_>,
) -> Result<KinematicSetup, SceneError> {
    let k = spec.kinematic.clone().unwrap_or_default();
    let names: Vec<&str> = model.tools.iter().map(|t| t.name.as_str()).collect();
    let mould = match &k.mould {
        Some(name) => names.iter().position(|n| n == name).ok_or_else(|| {
            at.error(
                "kinematic.mould",
                if names.is_empty() {
                    format!("no tool `{name}`: the scene has no tools")
                } else {
                    format!("no tool `{name}`: expected one of {}", names.join(", "))
                },
            )
        })?,
        None => {
            let moving: Vec<usize> = (0..model.tools.len())
                .filter(|&i| model.tools[i].motion.direction() != Vector3::zeros())
                .collect();
            match (model.tools.len(), moving.as_slice()) {
                (0, _) => {
                    return Err(at.error(
                        "kinematic.mould",
                        "a kinematic drape needs a mould: the scene has no tools",
                    ));
                }
                (1, _) => 0,
                (_, &[only]) => only,
                _ => {
                    return Err(at.error(
                        "kinematic.mould",
                        format!(
                            "the scene has {} tools ({}): name the mould with `mould = \"…\"` in [kinematic]",
                            names.len(),
                            names.join(", ")
                        ),
                    ));
                }
            }
        }
    };
    let tool = &model.tools[mould];
    let Some(blank) = &model.blank else {
        return Err(at.error(
            "fabric.blank",
            "a kinematic drape needs a rectangular blank (width and height), not a mesh file",
        ));
    };
    let frame: BlankFrame = blank.frame;
    let seed = match k.seed {
        Some(s) => {
            if !(s.iter().all(|v| v.is_finite())
                && (s[0] - frame.center.x).abs() <= 0.5 * frame.width
                && (s[1] - frame.center.y).abs() <= 0.5 * frame.height)
            {
                return Err(at.error(
                    "kinematic.seed",
                    format!(
                        "[{}, {}] is not on the blank: expected x within {} ± {} and y within {} ± {} mm",
                        s[0],
                        s[1],
                        frame.center.x,
                        0.5 * frame.width,
                        frame.center.y,
                        0.5 * frame.height
                    ),
                ));
            }
            s
        }
        None => [frame.center.x, frame.center.y],
    };
    let spacing = match k.spacing {
        Some(s) => positive(at, "kinematic.spacing", s)?,
        None => {
            // One cell of the blank's mesh: a quad, or two triangles.
            let cells: f64 = model
                .membranes
                .iter()
                .map(|b| match b.shape() {
                    drape_elements::MembraneShape::Quad => b.len() as f64,
                    drape_elements::MembraneShape::Triangle => 0.5 * b.len() as f64,
                })
                .sum();
            (frame.width * frame.height / cells.max(1.0)).sqrt()
        }
    };
    let direction = match k.direction {
        Some(d) => unit(at, "kinematic.direction", d)?,
        None => {
            let moving = tool.motion.direction();
            if moving == Vector3::zeros() {
                -Vector3::z()
            } else {
                -moving
            }
        }
    };
    let curve = |field: &str,
                 points: &Option<Vec<[f64; 3]>>|
     -> Result<Option<Vec<Vector3<f64>>>, SceneError> {
        let Some(points) = points else {
            return Ok(None);
        };
        if points.len() < 2 {
            return Err(at.error(field, "a generator curve needs at least two points"));
        }
        points
            .iter()
            .enumerate()
            .map(|(i, p)| finite3(at, &format!("{field}[{i}]"), *p))
            .collect::<Result<Vec<_>, _>>()
            .map(Some)
    };
    let warp_curve = curve("kinematic.warp_generator", &k.warp_generator)?;
    let weft_curve = curve("kinematic.weft_generator", &k.weft_generator)?;
    Ok(KinematicSetup {
        mould,
        mould_displacement: tool
            .prescribed_displacement(spec.simulation.end_time)
            .unwrap_or(0.0),
        net: NetSpec {
            outline: frame,
            seed,
            orientation_deg: spec.fabric.orientation_deg,
            spacing: [spacing, spacing],
            direction,
            warp_curve,
            weft_curve,
        },
    })
}

#[cfg(test)]
mod tests {
    use super::super::Scene;

    const SCENE: &str = r#"
[simulation]
end_time = 2.0

[fabric]
material = "glass-serge-4x3"
orientation_deg = 30
fibres = "embedded"
blank = { width = 120, height = 80, cells = [12, 8], center = [5, 0, 3] }

[[tools]]
name = "punch"
geometry = { kind = "hemispherical_punch", pole = [0, 0, 0], radius = 50, shank = 20 }
motion = { kind = "displacement", direction = [0, 0, 1], distance = 40, amplitude = { kind = "ramp", duration = 4.0 } }

[[tools]]
name = "die"
geometry = { kind = "plane", point = [0, 0, -100], normal = [0, 0, 1] }
"#;

    #[test]
    fn defaults_are_the_moving_tool_the_blank_centre_and_its_cells() {
        let scene = Scene::parse(SCENE, "s.toml".as_ref(), &[]).unwrap();
        let k = scene.kinematic.unwrap();
        assert_eq!(k.mould, 0);
        // The ramp is half way at the end time.
        assert_eq!(k.mould_displacement, 20.0);
        assert_eq!(k.net.seed, [5.0, 0.0]);
        assert_eq!(k.net.spacing, [10.0, 10.0]);
        assert_eq!(k.net.direction, -nalgebra::Vector3::z());
        assert_eq!(k.net.orientation_deg, 30.0);
        assert_eq!(k.net.outline.center.z, 3.0);
        assert!(k.net.warp_curve.is_none());
    }

    #[test]
    fn given_values_are_checked_and_used() {
        let with = |table: &str| {
            Scene::parse(
                &format!("{SCENE}\n[kinematic]\n{table}"),
                "s.toml".as_ref(),
                &[],
            )
        };
        let k = with("mould = \"die\"\nseed = [10, -5]\nspacing = 4\ndirection = [0, 0, -2]\nwarp_generator = [[0, 0, 0], [1, 0, 0]]\n")
            .unwrap()
            .kinematic
            .unwrap();
        assert_eq!((k.mould, k.mould_displacement), (1, 0.0));
        assert_eq!(k.net.seed, [10.0, -5.0]);
        assert_eq!(k.net.spacing, [4.0, 4.0]);
        assert_eq!(k.net.direction, -nalgebra::Vector3::z());
        assert_eq!(k.net.warp_curve.as_ref().map(Vec::len), Some(2));
        for (table, field, line) in [
            ("mould = \"anvil\"\n", "kinematic.mould", 21),
            ("seed = [70, 0]\n", "kinematic.seed", 21),
            ("spacing = 0\n", "kinematic.spacing", 21),
            ("direction = [0, 0, 0]\n", "kinematic.direction", 21),
            (
                "weft_generator = [[0, 0, 0]]\n",
                "kinematic.weft_generator",
                21,
            ),
        ] {
            let e = with(table).unwrap_err();
            assert_eq!((e.field.as_str(), e.line), (field, Some(line)), "{e}");
        }
        // Without the table an ambiguous mould is kept for `drape
        // kinematic`, not an error for the scene.
        let two_fixed = SCENE.replace(
            "motion = { kind = \"displacement\", direction = [0, 0, 1], distance = 40, amplitude = { kind = \"ramp\", duration = 4.0 } }",
            "",
        );
        let scene = Scene::parse(&two_fixed, "s.toml".as_ref(), &[]).unwrap();
        let e = scene.kinematic.unwrap_err();
        assert!(e.message.contains("2 tools (punch, die)"), "{e}");
    }
}
