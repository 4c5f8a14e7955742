//! `--set key=value`: one override applied to a scene's TOML table before
//! it is read.

use super::locate;

/// Sets `key` (dotted, numeric parts index lists; `tools[0].friction` is
/// read as `tools.0.friction`) to the TOML `value` (a bare word that is not
/// TOML is taken as text). A missing table on the way is created, a
/// missing list entry is an error.
pub fn set_path(table: &mut toml::Table, key: &str, value: &str) -> Result<(), String> {
    let parsed: toml::Value = match toml::from_str::<toml::Table>(&format!("v = {value}"))
        .ok()
        .and_then(|mut t| t.remove("v"))
    {
        Some(v) => v,
        None => {
            let v = value.trim();
            let digits = v.trim_start_matches(['+', '-']);
            if !digits.is_empty() && digits.bytes().all(|b| b.is_ascii_digit()) {
                return Err(format!(
                    "{v} is too large: whole numbers go up to {}",
                    i64::MAX
                ));
            }
            toml::Value::String(value.to_owned())
        }
    };
    let parts = locate::key_parts(key);
    if parts.iter().any(String::is_empty) {
        return Err("expected a key such as simulation.end_time or tools.0.friction".into());
    }
    let index_of = |here: &str, part: &str, len: usize| -> Result<usize, String> {
        let index: usize = part
            .parse()
            .map_err(|_| format!("`{here}` is a list: index it with a number, not `{part}`"))?;
        if index < len {
            Ok(index)
        } else if len == 0 {
            Err(format!(
                "`{here}` is an empty list: there is no entry {index}"
            ))
        } else {
            Err(format!(
                "`{here}` has {len} entries (0 to {}): there is no entry {index}",
                len - 1
            ))
        }
    };
    let mut current: Option<&mut toml::Value> = None;
    for (i, part) in parts.iter().enumerate() {
        let here = parts[..i].join(".");
        let next_is_index = parts
            .get(i + 1)
            .is_some_and(|p| p.bytes().all(|b| b.is_ascii_digit()));
        let missing = |t: &toml::Table| !t.contains_key(part.as_str());
        let slot = match current {
            None => {
                if next_is_index && missing(table) {
                    return Err(format!(
                        "the scene has no `{part}` list, so there is no entry {}",
                        parts[i + 1]
                    ));
                }
                table
                    .entry(part.as_str())
                    .or_insert_with(|| toml::Value::Table(toml::Table::new()))
            }
            Some(toml::Value::Table(t)) => {
                if next_is_index && missing(t) {
                    return Err(format!(
                        "`{here}` has no `{part}` list, so there is no entry {}",
                        parts[i + 1]
                    ));
                }
                t.entry(part.as_str())
                    .or_insert_with(|| toml::Value::Table(toml::Table::new()))
            }
            Some(toml::Value::Array(a)) => {
                let index = index_of(&here, part, a.len())?;
                &mut a[index]
            }
            Some(_) => return Err(format!("`{here}` is a value, not a table")),
        };
        current = Some(slot);
    }
    if let Some(slot) = current {
        *slot = parsed;
    }
    Ok(())
}
