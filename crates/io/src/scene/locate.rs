//! Where a scene error is and how it reads: the field's path and line in
//! the file, or the `--set` override it came from, and serde's messages
//! put in the user's terms (what a field accepts, never a Rust type name).
//!
//! Not for checking values: that is `build`'s (in the parent module).

use std::path::Path;

use toml::de::{DeTable, DeValue};

use super::SceneError;

/// A `--set` override as the user wrote it, with its key in the form
/// errors use (`tools[0].friction` for `tools.0.friction`).
#[derive(Debug, Clone)]
pub(super) struct Override {
    /// The key in error form.
    pub(super) field: String,
    /// `key=value` as given.
    pub(super) given: String,
}

impl Override {
    pub(super) fn new(key: &str, value: &str) -> Self {
        Self {
            field: field_form(key),
            given: format!("{key}={value}"),
        }
    }
}

/// Where the errors of one scene are: its file, its text (none for a
/// scene rebuilt from a checkpoint's copy), and the overrides applied.
pub(super) struct Locator<'a> {
    pub(super) file: &'a Path,
    pub(super) text: Option<&'a str>,
    pub(super) overrides: &'a [Override],
    /// Warnings found while building: a scene that runs but may not be
    /// what was meant (a mesh in metres, triangles dropped).
    pub(super) warnings: std::cell::RefCell<Vec<String>>,
}

/// Whether `field` is `key` or inside it (`tools[0].geometry.radius` is in
/// `tools[0]`, `tools[10]` is not).
fn within(field: &str, key: &str) -> bool {
    field == key
        || field
            .strip_prefix(key)
            .is_some_and(|rest| rest.starts_with('.') || rest.starts_with('['))
}

impl Locator<'_> {
    /// A warning at `field`, located as an error would be.
    pub(super) fn warn(&self, field: &str, message: impl Into<String>) {
        let located = self.error(field, message).to_string();
        self.warnings.borrow_mut().push(located);
    }

    /// An error at `field`: located on its line in the file, or named as
    /// coming from the `--set` override that gave its value.
    pub(super) fn error(&self, field: &str, message: impl Into<String>) -> SceneError {
        self.error_with_line(field, None, message)
    }

    /// [`Self::error`] with the line already known (from a parser's span).
    pub(super) fn error_with_line(
        &self,
        field: &str,
        line: Option<usize>,
        message: impl Into<String>,
    ) -> SceneError {
        let mut message = message.into();
        // The value itself (or a table holding it) was set on the command
        // line: the file's line would point at a value that is not used.
        if let Some(o) = self
            .overrides
            .iter()
            .rev()
            .find(|o| within(field, &o.field))
        {
            return SceneError {
                file: self.file.to_owned(),
                line: None,
                field: field.to_owned(),
                message: format!("{message} (the value comes from --set {})", o.given),
            };
        }
        // Part of the table was set on the command line: the file's line,
        // and which override took part.
        let parts: Vec<&str> = self
            .overrides
            .iter()
            .filter(|o| within(&o.field, field))
            .map(|o| o.given.as_str())
            .collect();
        if !parts.is_empty() {
            message = format!("{message} (with --set {})", parts.join(", --set "));
        }
        SceneError {
            file: self.file.to_owned(),
            line: line.or_else(|| self.text.and_then(|t| line_of(t, field))),
            field: field.to_owned(),
            message,
        }
    }
}

/// `tools.0.friction` or `tools[0].friction` as the dotted parts
/// `["tools", "0", "friction"]`.
pub(super) fn key_parts(key: &str) -> Vec<String> {
    key.replace('[', ".")
        .replace(']', "")
        .split('.')
        .map(|p| p.trim().to_owned())
        .collect()
}

/// A key in the form errors use: numeric parts as indices
/// (`tools.0.friction` → `tools[0].friction`).
pub(super) fn field_form(key: &str) -> String {
    let mut out = String::new();
    for part in key_parts(key) {
        if !out.is_empty() && part.bytes().all(|b| b.is_ascii_digit()) && !part.is_empty() {
            out.push_str(&format!("[{part}]"));
        } else {
            if !out.is_empty() {
                out.push('.');
            }
            out.push_str(&part);
        }
    }
    out
}

/// The 1-based line of byte `offset` in `text`.
pub(super) fn line_at(text: &str, offset: usize) -> usize {
    text.as_bytes()[..offset.min(text.len())]
        .iter()
        .filter(|&&b| b == b'\n')
        .count()
        + 1
}

/// The 1-based line of the dotted `field` (with `[i]` indices) in `text`,
/// or of its deepest existing parent.
pub(super) fn line_of(text: &str, field: &str) -> Option<usize> {
    let doc = DeTable::parse(text).ok()?;
    let mut span = doc.span();
    let mut table: Option<&DeTable<'_>> = Some(doc.get_ref());
    for part in field.split('.') {
        let (key, index) = match part.find('[') {
            Some(i) => (
                &part[..i],
                part[i + 1..part.len() - 1].parse::<usize>().ok(),
            ),
            None => (part, None),
        };
        let Some((_, v)) = table.and_then(|t| t.iter().find(|(k, _)| k.get_ref().as_ref() == key))
        else {
            break;
        };
        span = v.span();
        let mut value = v.get_ref();
        if let (Some(i), DeValue::Array(a)) = (index, value) {
            match a.get(i) {
                Some(item) => {
                    span = item.span();
                    value = item.get_ref();
                }
                None => break,
            }
        }
        table = match value {
            DeValue::Table(t) => Some(t),
            _ => None,
        };
    }
    Some(line_at(text, span.start))
}

/// The path (`tools[0].geometry.point`) of the deepest key or value of
/// `text` that holds byte `offset`: the field a parser's error span points
/// into.
pub(super) fn field_at(text: &str, offset: usize) -> Option<String> {
    let doc = DeTable::parse(text).ok()?;
    find_in_table(doc.get_ref(), offset, "")
}

fn holds(span: &std::ops::Range<usize>, offset: usize) -> bool {
    span.start <= offset && offset < span.end.max(span.start + 1)
}

fn find_in_table(table: &DeTable<'_>, offset: usize, prefix: &str) -> Option<String> {
    for (key, value) in table.iter() {
        let here = if prefix.is_empty() {
            key.get_ref().to_string()
        } else {
            format!("{prefix}.{}", key.get_ref())
        };
        if let Some(deeper) = find_in_value(value.get_ref(), offset, &here) {
            return Some(deeper);
        }
        if holds(&key.span(), offset) || holds(&value.span(), offset) {
            return Some(here);
        }
    }
    None
}

fn find_in_value(value: &DeValue<'_>, offset: usize, here: &str) -> Option<String> {
    match value {
        DeValue::Table(t) => find_in_table(t, offset, here),
        DeValue::Array(a) => a.iter().enumerate().find_map(|(i, item)| {
            let path = format!("{here}[{i}]");
            find_in_value(item.get_ref(), offset, &path)
                .or_else(|| holds(&item.span(), offset).then_some(path))
        }),
        _ => None,
    }
}

/// serde's and toml's message put in the user's terms: what was given and
/// what the field accepts, without Rust type names (`f64`, `usize`,
/// `struct FabricSpec`, `untagged enum MaterialSpec`).
pub(super) fn plain(message: &str) -> String {
    let m = message.trim();
    for prefix in ["invalid type: ", "invalid value: "] {
        if let Some((given, expected)) = m
            .strip_prefix(prefix)
            .and_then(|rest| rest.split_once(", expected "))
        {
            return format!(
                "{} is not allowed: expected {}",
                given_text(given),
                expected_text(expected)
            );
        }
    }
    if let Some((n, expected)) = m
        .strip_prefix("invalid length ")
        .and_then(|rest| rest.split_once(", expected "))
    {
        return format!(
            "a list of {n} values is not allowed: expected {}",
            expected_text(expected)
        );
    }
    if let Some(name) = m.strip_prefix("data did not match any variant of untagged enum ") {
        return format!("expected {}", type_text(name));
    }
    if let Some(field) = m.strip_prefix("missing field ") {
        return format!("{field} is missing");
    }
    if let Some(rest) = m.strip_prefix("unknown field ") {
        return match rest.split_once(", expected ") {
            Some((key, allowed)) => format!("unknown key {key}: expected {allowed}"),
            None => format!(
                "unknown key {}",
                rest.trim_end_matches(", there are no fields")
            ),
        };
    }
    if let Some((variant, allowed)) = m
        .strip_prefix("unknown variant ")
        .and_then(|rest| rest.split_once(", expected "))
    {
        return format!("{variant} is not allowed: expected {allowed}");
    }
    m.to_owned()
}

/// serde's "unexpected" part: `string "abc"`, ``integer `5` ``, `map`, …
fn given_text(given: &str) -> String {
    if let Some(s) = given.strip_prefix("string ") {
        return format!("the text {s}");
    }
    for kind in ["integer ", "floating point ", "boolean "] {
        if let Some(v) = given.strip_prefix(kind) {
            return v.trim_matches('`').to_owned();
        }
    }
    match given {
        "map" => "a table".into(),
        "sequence" => "a list".into(),
        other => other.into(),
    }
}

/// serde's "expected" part in the user's terms.
fn expected_text(expected: &str) -> String {
    let e = expected.trim();
    match e {
        "f64" | "f32" => return "a number".into(),
        "usize" | "u64" | "u32" | "u16" | "u8" => return "a whole number ≥ 0".into(),
        "isize" | "i64" | "i32" | "i16" | "i8" => return "a whole number".into(),
        "a boolean" | "bool" => return "true or false".into(),
        "a string" | "a borrowed string" | "char" => return "text in quotes".into(),
        "a sequence" => return "a list [ … ]".into(),
        "a map" => return "a table { … }".into(),
        _ => {}
    }
    if let Some(n) = e.strip_prefix("an array of length ") {
        return format!("a list of {n} values");
    }
    // serde's arrays read inside tagged tables say "3 elements in sequence".
    if let Some(n) = e.strip_suffix(" elements in sequence") {
        return format!("{n} values");
    }
    for kind in [
        "internally tagged enum ",
        "adjacently tagged enum ",
        "untagged enum ",
        "tuple struct ",
        "unit struct ",
        "struct ",
        "enum ",
    ] {
        if let Some(name) = e.strip_prefix(kind) {
            return type_text(name).into();
        }
    }
    e.into()
}

/// What a value of one of the scene's types is, in a scene file's words.
fn type_text(name: &str) -> &'static str {
    match name.trim() {
        "SceneFile" => "a scene: tables [simulation], [fabric], [[tools]], …",
        "SimulationSpec" => "a table of run settings (end_time, frames, …)",
        "FabricSpec" => "a table with `material`, `fibres` and `blank`",
        "BlankSpec" => {
            "a table such as { width = 100, height = 100, cells = [10, 10] } or \
             { mesh = \"blank.msh\" }"
        }
        "MaterialSpec" => {
            "a preset name (carbon-prepreg-2x2, glass-serge-4x3, twintex-plain) or a table of material values"
        }
        "Material" => {
            "a table of material values (name, thickness, fibre_volume_fraction, density, \
             fibre, resin)"
        }
        "FibreLaw" => "a table of fibre values (modulus, crimp_strain, compression_factor)",
        "ResinLaw" => "a table of resin values (young, poisson, prony)",
        "PronyTerm" => "a table { g = …, tau = … }",
        "GeometrySpec" => {
            "a geometry table with a `kind`: plane, sphere, hemispherical_punch, die, ring, \
             revolution or mesh"
        }
        "MotionSpec" => "a motion table with a `kind`: fixed, displacement or force",
        "BcMotionSpec" => {
            "a motion table with a `kind`: fixed, displacement, velocity or picture_frame"
        }
        "Amplitude" => {
            "an amplitude table with a `kind`: constant, ramp, smooth_step or table, e.g. \
             { kind = \"smooth_step\", duration = 1 }"
        }
        "ProfileSegment" => "a profile segment table with a `kind`: line or arc",
        "ToolSpec" => "a tool table (name, geometry, motion, friction)",
        "NodeSelection" => {
            "a node set name (\"left\"), a list of node numbers ([0, 5]) or a list of set names"
        }
        "ElementKind" => "\"quad\" or \"triangle\"",
        "FibreRepresentation" => "\"trusses\" or \"embedded\"",
        "Solver" => "\"explicit\"",
        "Pointing" => "\"up\" or \"down\"",
        _ => "a table { … }",
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn keys_take_the_error_form() {
        assert_eq!(field_form("tools.0.friction"), "tools[0].friction");
        assert_eq!(field_form("tools[0].friction"), "tools[0].friction");
        assert_eq!(field_form("springs.12"), "springs[12]");
        assert_eq!(field_form("simulation.end_time"), "simulation.end_time");
        assert!(within("tools[0].friction", "tools[0]"));
        assert!(!within("tools[10].friction", "tools[1]"));
        assert!(!within("simulation.frames_x", "simulation.frames"));
    }

    #[test]
    fn fields_are_found_from_a_position() {
        let text = "[simulation]\nend_time = 1\n\n[[tools]]\nname = \"a\"\n\n[[tools]]\nname = \"b\"\n\
                    geometry = { kind = \"plane\", point = [0, 0], normal = [0, 0, 1] }\n";
        let at = |s: &str| field_at(text, text.find(s).unwrap());
        assert_eq!(at("1\n").as_deref(), Some("simulation.end_time"));
        assert_eq!(at("\"b\"").as_deref(), Some("tools[1].name"));
        assert_eq!(at("[0, 0]").as_deref(), Some("tools[1].geometry.point"));
        assert_eq!(at("normal").as_deref(), Some("tools[1].geometry.normal"));
    }

    #[test]
    fn messages_name_no_rust_types() {
        for (raw, want) in [
            (
                "invalid type: string \"abc\", expected f64",
                "the text \"abc\" is not allowed: expected a number",
            ),
            (
                "invalid type: floating point `1.5`, expected usize",
                "1.5 is not allowed: expected a whole number ≥ 0",
            ),
            (
                "invalid type: integer `5`, expected struct FabricSpec",
                "5 is not allowed: expected a table with `material`, `fibres` and `blank`",
            ),
            (
                "invalid length 2, expected an array of length 3",
                "a list of 2 values is not allowed: expected a list of 3 values",
            ),
            ("missing field `end_time`", "`end_time` is missing"),
        ] {
            assert_eq!(plain(raw), want);
        }
        for raw in [
            "data did not match any variant of untagged enum MaterialSpec",
            "invalid type: integer `3`, expected internally tagged enum Amplitude",
            "invalid type: map, expected a sequence",
            "invalid value: integer `-1`, expected u32",
        ] {
            let m = plain(raw);
            for rust in [
                "enum",
                "struct",
                "Spec",
                "Amplitude",
                "u32",
                "sequence",
                "map",
            ] {
                assert!(!m.contains(rust), "{raw} → {m}");
            }
        }
    }
}
