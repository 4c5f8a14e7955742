//! `[kinematic]`: how `drape kinematic` drapes the scene's blank as a
//! pin-jointed net (drape-fishnet): which tool is the mould, where the net
//! starts, the yarn spacing, the draping direction and the generators.
//!
//! Every key has the default a forming engineer expects, so a forming
//! scene drapes kinematically without the table: the mould is the shape
//! the blank is formed to (see [`default_mould`]: the only tool, a fixed
//! female mould a punch presses the blank into, or the punch of a deep
//! drawing), the seed is the blank's centre put
//! on the mould along the draping direction (the top of a punch under the
//! blank), the warp leaves it along the blank's orientation, the spacing is
//! the blank's element size, the draping direction is against the mould's
//! motion (a fixed mould's: the motion of the punch pressing into it, or
//! −z). When the table is absent and a default
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
    /// The ply of a `[stack]` the net is of (default: the bottom ply).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ply: Option<String>,
}

/// A kinematic drape ready to run.
#[derive(Debug, Clone, PartialEq)]
pub struct KinematicSetup {
    /// Index of the mould in the model's tools.
    pub mould: usize,
    /// Why this tool is the mould, for the output ("given by
    /// kinematic.mould", "the scene's only tool", …).
    pub mould_reason: String,
    /// The mould's displacement along its motion at the scene's end time
    /// (mm; 0 for a fixed or force-driven tool): the net is moved with it,
    /// so that it lies where a forming run's part does.
    pub mould_displacement: f64,
    /// The net.
    pub net: NetSpec,
    /// The ply of a laminate the net is of (index into the model's
    /// `plies`; None for one ply): its orientation, blank and element
    /// size are the net's, and `drape compare` compares its elements only.
    pub ply: Option<usize>,
}

/// The default mould and why it is the one.
struct MouldChoice {
    mould: usize,
    /// The moving tool that presses the blank into a fixed mould: the
    /// blank moves onto the mould along its motion.
    pressed_by: Option<usize>,
    reason: String,
}

/// The mould when `[kinematic]` names none: the shape the blank is formed
/// to. A die (`kind = "die"`) and a blank holder (`kind = "ring"`) have an
/// opening where the part forms, so they are never the default; of the
/// other tools, the only one; else, of one fixed and one moving tool, the
/// fixed one when it lies beyond the blank in the moving one's direction
/// (a punch pressing the blank into a female mould), the moving one when
/// it does not (a punch drawing the blank away from a fixed tool behind
/// it); else the only moving one. Anything else is ambiguous: the message
/// names the tools.
fn default_mould(spec: &SceneFile, model: &Model) -> Result<MouldChoice, String> {
    let tools = &model.tools;
    let names: Vec<&str> = tools.iter().map(|t| t.name.as_str()).collect();
    let chosen = |mould: usize, reason: String| MouldChoice {
        mould,
        pressed_by: None,
        reason,
    };
    match tools.len() {
        0 => return Err("a kinematic drape needs a mould: the scene has no tools".to_owned()),
        1 => return Ok(chosen(0, "the scene's only tool".to_owned())),
        _ => {}
    }
    let opening = |i: usize| {
        spec.tools.get(i).is_some_and(|t| {
            matches!(
                t.geometry,
                super::GeometrySpec::Die { .. } | super::GeometrySpec::Ring { .. }
            )
        })
    };
    let mut candidates: Vec<usize> = (0..tools.len()).filter(|&i| !opening(i)).collect();
    if candidates.is_empty() {
        candidates = (0..tools.len()).collect();
    }
    if let [only] = candidates[..] {
        return Ok(chosen(
            only,
            "the only tool that is not a die or a blank holder (ring)".to_owned(),
        ));
    }
    let moves = |i: usize| tools[i].motion.direction() != Vector3::zeros();
    let moving: Vec<usize> = candidates.iter().copied().filter(|&i| moves(i)).collect();
    let fixed: Vec<usize> = candidates.iter().copied().filter(|&i| !moves(i)).collect();
    if let ([punch], [mould]) = (&moving[..], &fixed[..]) {
        // How far along the punch's motion each tool's point closest to
        // the blank's centre lies: the blank is pressed into the fixed
        // tool when that one lies further on.
        let centre = model.x0.iter().sum::<Vector3<f64>>() / model.x0.len().max(1) as f64;
        let d = tools[*punch].motion.direction();
        let ahead = |i: usize| (tools[i].project(&centre, 0.0).point - centre).dot(&d);
        if ahead(*mould) > ahead(*punch) {
            return Ok(MouldChoice {
                mould: *mould,
                pressed_by: Some(*punch),
                reason: format!(
                    "the fixed tool that the moving tool `{}` presses the blank into",
                    names[*punch]
                ),
            });
        }
    }
    if let [only] = moving[..] {
        return Ok(chosen(only, "the only moving tool".to_owned()));
    }
    Err(format!(
        "the scene has {} tools ({}): name the mould with `mould = \"…\"` in [kinematic]",
        names.len(),
        names.join(", ")
    ))
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
    let choice = match &k.mould {
        Some(name) => MouldChoice {
            mould: names.iter().position(|n| n == name).ok_or_else(|| {
                at.error(
                    "kinematic.mould",
                    if names.is_empty() {
                        format!("no tool `{name}`: the scene has no tools")
                    } else {
                        format!("no tool `{name}`: expected one of {}", names.join(", "))
                    },
                )
            })?,
            pressed_by: None,
            reason: "given by kinematic.mould".to_owned(),
        },
        None => {
            default_mould(spec, model).map_err(|message| at.error("kinematic.mould", message))?
        }
    };
    let mould = choice.mould;
    let tool = &model.tools[mould];
    // A laminate's plies each drape as a net of their own (a net knows no
    // thickness or neighbour): one ply at a time, by name.
    let ply = match (&k.ply, model.plies.len()) {
        (name, n) if n > 1 => {
            let name = name.clone().unwrap_or_else(|| model.plies[0].name.clone());
            let found = model.plies.iter().position(|p| p.name == name);
            Some(found.ok_or_else(|| {
                let names: Vec<&str> = model.plies.iter().map(|p| p.name.as_str()).collect();
                at.error(
                    "kinematic.ply",
                    format!("no ply `{name}`: expected one of {}", names.join(", ")),
                )
            })?)
        }
        (Some(name), _) => {
            return Err(at.error(
                "kinematic.ply",
                format!("`{name}`: the scene is one ply, so there is no ply to choose"),
            ));
        }
        (None, _) => None,
    };
    let (blank, orientation_deg, membranes) = match ply {
        Some(p) => {
            let ply = &model.plies[p];
            (
                &ply.blank,
                ply.orientation_deg,
                &model.membranes[ply.membranes.clone()],
            )
        }
        None => (
            &model.blank,
            spec.fabric.orientation_deg,
            &model.membranes[..],
        ),
    };
    let Some(blank) = blank else {
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
            let cells: f64 = membranes
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
            match choice.pressed_by {
                // The blank travels with the tool that presses it into
                // the fixed mould.
                Some(punch) => model.tools[punch].motion.direction(),
                None if moving == Vector3::zeros() => -Vector3::z(),
                None => -moving,
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
        mould_reason: choice.reason,
        mould_displacement: tool
            .prescribed_displacement(spec.simulation.end_time)
            .unwrap_or(0.0),
        net: NetSpec {
            outline: frame,
            seed,
            orientation_deg,
            spacing: [spacing, spacing],
            direction,
            warp_curve,
            weft_curve,
        },
        ply,
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

    /// A laminate drapes one ply at a time: the bottom one by default,
    /// with that ply's orientation, blank and element size (not the
    /// stack's, whose elements are every ply's).
    #[test]
    fn a_stack_drapes_the_ply_named_with_its_own_orientation_and_cells() {
        let stack = SCENE.replacen(
            "\n[[tools]]",
            "\n[stack]\n[[stack.ply]]\nname = \"bottom\"\n[[stack.ply]]\nname = \"top\"\n\
             orientation_deg = -45\nblank = { width = 60, height = 40, cells = [3, 2] }\n\n[[tools]]",
            1,
        );
        let parse = |extra: &str| {
            Scene::parse(&format!("{stack}{extra}"), "s.toml".as_ref(), &[])
                .unwrap()
                .kinematic
        };
        let k = parse("").unwrap();
        assert_eq!(k.ply, Some(0));
        assert_eq!(k.net.orientation_deg, 30.0);
        assert_eq!(k.net.spacing, [10.0, 10.0]);
        assert_eq!(k.net.outline.width, 120.0);
        let k = parse("\n[kinematic]\nply = \"top\"\n").unwrap();
        assert_eq!(k.ply, Some(1));
        assert_eq!(k.net.orientation_deg, -45.0);
        assert_eq!(k.net.outline.width, 60.0);
        // A −45° ply of 3 × 2 cells on 60 × 40 mm: its own elements set
        // the spacing.
        let scene = Scene::parse(&stack, "s.toml".as_ref(), &[]).unwrap();
        let top = &scene.model.plies[1];
        let elements = (top.elements.end - top.elements.start) as f64;
        assert!(
            (k.net.spacing[0] - (60.0 * 40.0 / elements).sqrt()).abs() < 1e-12,
            "{:?} for {elements} elements",
            k.net.spacing
        );
        // A table given is the scene's: its errors refuse the scene.
        let refused = |text: String| Scene::parse(&text, "s.toml".as_ref(), &[]).unwrap_err();
        let e = refused(format!("{stack}\n[kinematic]\nply = \"middle\"\n"));
        assert_eq!(e.field, "kinematic.ply");
        assert!(e.message.contains("expected one of bottom, top"), "{e}");
        // One ply: nothing to choose.
        let e = refused(format!("{SCENE}\n[kinematic]\nply = \"top\"\n"));
        assert_eq!(e.field, "kinematic.ply");
        assert!(e.message.contains("the scene is one ply"), "{e}");
        assert_eq!(
            Scene::parse(SCENE, "s.toml".as_ref(), &[])
                .unwrap()
                .kinematic
                .unwrap()
                .ply,
            None
        );
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

    /// A fixed female mould under the blank and a punch above it coming
    /// down: the blank is formed into the mould, so the net goes there,
    /// along the punch's motion, whichever order the tools come in.
    #[test]
    fn a_punch_pressing_into_a_fixed_mould_drapes_on_the_mould() {
        let punch = r#"
[[tools]]
name = "punch"
geometry = { kind = "sphere", center = [0, 0, 60], radius = 50 }
motion = { kind = "displacement", direction = [0, 0, -1], distance = 40, amplitude = { kind = "ramp", duration = 1.0 } }
"#;
        let mould = r#"
[[tools]]
name = "cavity"
geometry = { kind = "revolution", origin = [0, 0, 0], profile = [{ kind = "line", from = [0, -40], to = [80, -40] }, { kind = "line", from = [80, -40], to = [80, 0] }] }
"#;
        let head = r#"
[simulation]
end_time = 1.0

[fabric]
material = "glass-serge-4x3"
fibres = "embedded"
blank = { width = 120, height = 120, cells = [12, 12], center = [0, 0, 2] }
"#;
        for tools in [format!("{punch}{mould}"), format!("{mould}{punch}")] {
            let scene = Scene::parse(&format!("{head}{tools}"), "s.toml".as_ref(), &[]).unwrap();
            let k = scene.kinematic.unwrap();
            assert_eq!(scene.model.tools[k.mould].name, "cavity");
            assert_eq!(
                k.mould_reason,
                "the fixed tool that the moving tool `punch` presses the blank into"
            );
            assert_eq!(k.mould_displacement, 0.0);
            assert_eq!(k.net.direction, -nalgebra::Vector3::z());
        }
    }

    /// The shipped forming scenes: a deep drawing's die and blank holder
    /// have an opening where the part forms, so the punch is the mould.
    #[test]
    fn the_shipped_scenes_drape_on_their_punch() {
        let scenes = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes");
        for (file, mould) in [
            ("deep-drawing-0-90.toml", "punch"),
            ("deep-drawing-45.toml", "punch"),
            ("hemisphere-ring.toml", "punch"),
            ("hemisphere-0-90.toml", "punch"),
            ("hemisphere-conform.toml", "mould"),
        ] {
            let scene = Scene::from_file(&scenes.join(file), &[]).unwrap();
            let k = scene.kinematic.unwrap_or_else(|e| panic!("{file}: {e}"));
            assert_eq!(scene.model.tools[k.mould].name, mould, "{file}");
        }
    }
}
