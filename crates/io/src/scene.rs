//! Scene files: a forming simulation in TOML, read into a [`Model`] and the
//! run's settings.
//!
//! Every table rejects unknown keys, and every invalid value is a
//! [`SceneError`] that names the file, the line and the field and says what
//! is allowed. The format is documented with examples in
//! `docs/scene-reference.md`.
//!
//! ```
//! let text = r#"
//! [simulation]
//! end_time = 0.01
//!
//! [fabric]
//! material = "glass-serge-4x3"
//! orientation_deg = 0
//! fibres = "trusses"
//! blank = { width = 100, height = 100, cells = [10, 10] }
//!
//! [[boundary]]
//! nodes = "left"
//! motion = { kind = "fixed" }
//! "#;
//! let scene = drape_io::scene::Scene::parse(text, "example.toml".as_ref(), &[]).unwrap();
//! assert_eq!(scene.model.node_count(), 121);
//! ```

use std::path::{Path, PathBuf};

mod implicit_checks;
mod kinematic;
mod limits;
pub use kinematic::{KinematicSetup, KinematicSpec};
pub use limits::{
    BLANK_BYTES_PER_ELEMENT, MAX_BLANK_ELEMENTS, MAX_COORDINATE_MM, MIN_MESH_SIZE_MM,
    TOOL_BYTES_PER_TRIANGLE,
};

use drape_model::Model;
use drape_time::{ExplicitSettings, ImplicitSettings};

mod bending;
mod build;
mod locate;
mod open_mesh;
mod placement;
mod set_path;
mod shape;
mod spec;
mod stack;
mod yarn_buckling;
pub use stack::{MAX_PLIES, PlySpec, StackSpec};

use build::{build, finite3, positive, unit};
use locate::{Locator, Override, field_at, line_at, plain};
pub use placement::LengthUnit;
pub use set_path::set_path;
pub use spec::*;

/// A scene that cannot be used: where and why.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{}{}: {field}: {message}", file.display(), line.map(|l| format!(":{l}")).unwrap_or_default())]
pub struct SceneError {
    /// The scene file.
    pub file: PathBuf,
    /// The line of the offending field, when known.
    pub line: Option<usize>,
    /// Dotted path of the field (`tools[0].friction`), or what failed.
    pub field: String,
    /// What is wrong and what is allowed.
    pub message: String,
}

/// A scene ready to run.
#[derive(Debug, Clone)]
pub struct Scene {
    /// The file it came from.
    pub file: PathBuf,
    /// What the file said (after `--set` overrides).
    pub spec: SceneFile,
    /// The model.
    pub model: Model,
    /// The explicit driver's settings.
    pub settings: ExplicitSettings,
    /// The implicit driver's settings (`[simulation] solver = "implicit"`).
    pub implicit: ImplicitSettings,
    /// The kinematic drape (`drape kinematic`), or why the scene has none:
    /// without a `[kinematic]` table a default that cannot be found is not
    /// an error for the other commands.
    pub kinematic: Result<KinematicSetup, SceneError>,
    /// What may not be what was meant, located like errors (a blank mesh
    /// whose size suggests metres, degenerate triangles dropped from a tool
    /// mesh, elements turned over): the command prints them.
    pub warnings: Vec<String>,
}

impl Scene {
    /// Reads the scene at `path`, with `--set key.path=value` overrides.
    pub fn from_file(path: &Path, overrides: &[(String, String)]) -> Result<Self, SceneError> {
        let text = std::fs::read_to_string(path).map_err(|e| SceneError {
            file: path.to_owned(),
            line: None,
            field: "file".into(),
            message: format!("cannot read the scene: {e}"),
        })?;
        Self::parse(&text, path, overrides)
    }

    /// Reads a scene from its text; `path` names it in errors and anchors
    /// relative file names.
    ///
    /// An error names the field and its line, or, when the value came from
    /// an override, the `--set key=value` that gave it.
    pub fn parse(
        text: &str,
        path: &Path,
        overrides: &[(String, String)],
    ) -> Result<Self, SceneError> {
        let given: Vec<Override> = overrides.iter().map(|(k, v)| Override::new(k, v)).collect();
        let at = Locator {
            file: path,
            text: Some(text),
            overrides: &given,
            warnings: Default::default(),
        };
        let syntax = |e: toml::de::Error| SceneError {
            file: path.to_owned(),
            line: e.span().map(|s| line_at(text, s.start)),
            field: e
                .span()
                .and_then(|s| field_at(text, s.start))
                .unwrap_or_else(|| "scene".into()),
            message: plain(e.message()),
        };
        // The document that is read: the file's text, or with overrides the
        // file's table with them applied, written out again so that the
        // reader's error spans still lead to a field.
        let document = if overrides.is_empty() {
            text.to_owned()
        } else {
            let mut table: toml::Table = toml::from_str(text).map_err(syntax)?;
            for ((key, value), o) in overrides.iter().zip(&given) {
                set_path(&mut table, key, value).map_err(|message| SceneError {
                    file: path.to_owned(),
                    line: None,
                    field: o.field.clone(),
                    message: format!("--set {}: {message}", o.given),
                })?;
            }
            toml::to_string(&table).map_err(|e| SceneError {
                file: path.to_owned(),
                line: None,
                field: "--set".into(),
                message: format!("the overrides do not make a valid scene: {e}"),
            })?
        };
        let spec: SceneFile = toml::from_str(&document).map_err(|e| {
            let start = e.span().map(|s| s.start);
            let message = plain(e.message());
            let found = start.and_then(|s| field_at(&document, s)).map(|field| {
                toml::from_str(&document)
                    .ok()
                    .and_then(|d| shape::refine_length_error(&d, &field, e.message()))
                    .unwrap_or(field)
            });
            match found {
                Some(field) if overrides.is_empty() => {
                    at.error_with_line(&field, start.map(|s| line_at(text, s)), message)
                }
                Some(field) => at.error(&field, message),
                None if overrides.is_empty() => syntax(e),
                None => at.error("scene", message),
            }
        })?;
        shape::check(&document, &spec, &at)?;
        Self::assemble(spec, path, &at)
    }

    /// Builds a scene from its values alone (a checkpoint's copy of
    /// [`Self::resolved_spec`]); `file` names it in errors and anchors any
    /// relative file name. Errors have no line: there is no text.
    pub fn from_spec(spec: SceneFile, file: &Path) -> Result<Self, SceneError> {
        let at = Locator {
            file,
            text: None,
            overrides: &[],
            warnings: Default::default(),
        };
        Self::assemble(spec, file, &at)
    }

    /// The model, the run settings and the kinematic set-up of `spec`; a
    /// `[kinematic]` table the scene gives must be valid, an absent one is
    /// only needed by `drape kinematic`.
    fn assemble(spec: SceneFile, file: &Path, at: &Locator<'_>) -> Result<Self, SceneError> {
        let (model, settings, implicit) = build(&spec, at)?;
        let kinematic = kinematic::setup(&spec, &model, at);
        if spec.kinematic.is_some() {
            kinematic.clone()?;
        }
        Ok(Self {
            file: file.to_owned(),
            spec,
            model,
            settings,
            implicit,
            kinematic,
            warnings: at.warnings.take(),
        })
    }

    /// The scene as it runs, self-contained: every value after the
    /// overrides, and the files it reads (the blanks' meshes, tools'
    /// meshes, material cards) as absolute paths, so that [`Self::from_spec`] builds the same scene
    /// from any directory.
    pub fn resolved_spec(&self) -> SceneFile {
        let base = self.file.parent().unwrap_or(Path::new("."));
        let absolute = |file: &str| -> String {
            let joined = base.join(file);
            std::path::absolute(&joined)
                .unwrap_or(joined)
                .to_string_lossy()
                .into_owned()
        };
        let mut spec = self.spec.clone();
        if let Some(mesh) = &mut spec.fabric.blank.mesh {
            *mesh = absolute(mesh);
        }
        if let Some(stack) = &mut spec.stack {
            stack::absolute_meshes(stack, absolute);
        }
        for tool in &mut spec.tools {
            if let GeometrySpec::Mesh { file, .. } = &mut tool.geometry {
                *file = absolute(file);
            }
        }
        let plies = spec.stack.iter_mut().flat_map(|s| s.ply.iter_mut());
        for m in std::iter::once(&mut spec.fabric.material)
            .chain(plies.filter_map(|p| p.material.as_mut()))
        {
            if let MaterialSpec::Preset(name) = m
                && is_card(name)
            {
                *name = absolute(name);
            }
        }
        spec
    }

    /// The files the scene reads beside itself (the blanks' meshes, tools'
    /// meshes, material cards), as absolute paths.
    pub fn input_files(&self) -> Vec<PathBuf> {
        let spec = self.resolved_spec();
        spec.fabric
            .blank
            .mesh
            .iter()
            .chain(spec.stack.iter().flat_map(|s| {
                s.ply
                    .iter()
                    .filter_map(|p| p.blank.as_ref().and_then(|b| b.mesh.as_ref()))
            }))
            .chain(spec.tools.iter().filter_map(|t| match &t.geometry {
                GeometrySpec::Mesh { file, .. } => Some(file),
                _ => None,
            }))
            .chain(
                std::iter::once(&spec.fabric.material)
                    .chain(
                        spec.stack
                            .iter()
                            .flat_map(|s| s.ply.iter().filter_map(|p| p.material.as_ref())),
                    )
                    .filter_map(|m| match m {
                        MaterialSpec::Preset(name) if is_card(name) => Some(name),
                        _ => None,
                    }),
            )
            .map(PathBuf::from)
            .collect()
    }
}
