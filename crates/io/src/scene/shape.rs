//! Lists of a fixed length (`gravity = [x, y, z]`, `cells = [nx, ny]`,
//! a table's `[t, a]` points) given with more values than they hold.
//!
//! serde reads an array `[T; N]` from the first N values of a list and
//! drops the rest without a word, so a stray comma in `[0, 0, -9,810]`
//! made gravity −9. Rather than a wrapper on every such field (in this
//! crate, in `drape-contact`'s profiles and amplitudes, in
//! `drape-constitutive`'s material), the scene that was read is written
//! back to a TOML tree and compared with the tree it was read from: a list
//! that comes back shorter lost values, whatever type dropped them. The
//! same goes for lists inside internally tagged tables (a tool's
//! `geometry`, `motion`), which serde does check but reports at the table:
//! [`refine_length_error`] names the list there.
//!
//! Not for checking values: that is `build`'s.

use toml::{Table, Value};

use super::locate::Locator;
use super::{SceneError, SceneFile};

/// Refuses a list of `document` (the text that was read, overrides
/// applied) that has more values than `spec` (what was read from it)
/// kept, naming the list.
pub(super) fn check(document: &str, spec: &SceneFile, at: &Locator<'_>) -> Result<(), SceneError> {
    // Both trees exist whenever `spec` was read from `document`; if one
    // cannot be made there is nothing to compare.
    let (Ok(given), Ok(read)) = (toml::from_str::<Table>(document), Table::try_from(spec)) else {
        return Ok(());
    };
    match dropped_values(&given, &read) {
        None => Ok(()),
        Some((field, n, kept)) => Err(at.error(
            &field,
            format!(
                "a list of {n} values is not allowed: expected {kept} (a comma inside a \
                 number, as in 9,810, makes two values)"
            ),
        )),
    }
}

/// The first list of `given` (the tree the scene was read from) that has
/// more values than the same list of `read` (the scene written back): its
/// path in error form (`tools[0].geometry.point`), how many values it has
/// and how many were kept.
pub(super) fn dropped_values(given: &Table, read: &Table) -> Option<(String, usize, usize)> {
    table(given, read, "")
}

fn table(given: &Table, read: &Table, prefix: &str) -> Option<(String, usize, usize)> {
    given.iter().find_map(|(key, value)| {
        let here = if prefix.is_empty() {
            key.clone()
        } else {
            format!("{prefix}.{key}")
        };
        read.get(key)
            .and_then(|kept| self::value(value, kept, &here))
    })
}

fn value(given: &Value, read: &Value, here: &str) -> Option<(String, usize, usize)> {
    match (given, read) {
        (Value::Table(g), Value::Table(r)) => table(g, r, here),
        (Value::Array(g), Value::Array(r)) => {
            if g.len() > r.len() {
                return Some((here.to_owned(), g.len(), r.len()));
            }
            g.iter()
                .zip(r)
                .enumerate()
                .find_map(|(i, (g, r))| value(g, r, &format!("{here}[{i}]")))
        }
        _ => None,
    }
}

/// serde's "invalid length N, expected M …" error (too many or too few
/// values) inside an internally
/// tagged table (`tools[0].motion`, found at `field`) points at the table:
/// the list to name is the list of N values in it that, cut or padded to
/// M values, leaves no error about a list's length.
pub(super) fn refine_length_error(document: &Table, field: &str, message: &str) -> Option<String> {
    let (n, expected) = message
        .strip_prefix("invalid length ")?
        .split_once(", expected ")?;
    let n: usize = n.trim().parse().ok()?;
    // "3 elements in sequence" (too many) or "an array of length 3".
    let m: usize = expected.split(' ').find_map(|w| w.parse().ok())?;
    let whole = Value::Table(document.clone());
    let mut found = Vec::new();
    lists_of_length(get(&whole, field)?, n, field, &mut found);
    found.into_iter().find(|list| {
        let mut cut = whole.clone();
        if let Some(Value::Array(a)) = get_mut(&mut cut, list) {
            // Padded with its own last value, a list of lists stays one.
            let last = a.last().cloned().unwrap_or(Value::Float(0.0));
            a.resize(m, last);
        }
        // A list that was right, cut, makes a length error of its own.
        match cut.try_into::<SceneFile>() {
            Ok(_) => true,
            Err(e) => !e.message().starts_with("invalid length "),
        }
    })
}

/// `a.b[1][2].c` as keys and indices.
fn steps(path: &str) -> impl Iterator<Item = Result<&str, usize>> {
    path.split('.').flat_map(|part| {
        let mut pieces = part.split('[');
        let key = pieces.next().map(Ok);
        key.into_iter()
            .chain(pieces.map(|i| i.trim_end_matches(']').parse().map_err(|_| 0).and_then(Err)))
    })
}

fn get<'a>(value: &'a Value, path: &str) -> Option<&'a Value> {
    steps(path).try_fold(value, |v, step| match step {
        Ok(key) => v.as_table()?.get(key),
        Err(i) => v.as_array()?.get(i),
    })
}

fn get_mut<'a>(value: &'a mut Value, path: &str) -> Option<&'a mut Value> {
    steps(path).try_fold(value, |v, step| match step {
        Ok(key) => v.as_table_mut()?.get_mut(key),
        Err(i) => v.as_array_mut()?.get_mut(i),
    })
}

/// The paths of the lists of `n` values under `value` (at `here`).
fn lists_of_length(value: &Value, n: usize, here: &str, found: &mut Vec<String>) {
    match value {
        Value::Table(t) => {
            for (key, v) in t {
                lists_of_length(v, n, &format!("{here}.{key}"), found);
            }
        }
        Value::Array(a) => {
            if a.len() == n {
                found.push(here.to_owned());
            }
            for (i, v) in a.iter().enumerate() {
                lists_of_length(v, n, &format!("{here}[{i}]"), found);
            }
        }
        _ => {}
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tree(text: &str) -> Table {
        toml::from_str(text).unwrap()
    }

    #[test]
    fn a_longer_list_is_found_at_its_path() {
        let given = tree("a = [1, 2, 3, 4]\n[[t]]\nb = [[1, 2], [3, 4, 5]]");
        let read = tree("a = [1, 2, 3, 4]\n[[t]]\nb = [[1, 2], [3, 4]]");
        assert_eq!(
            dropped_values(&given, &read),
            Some(("t[0].b[1]".to_owned(), 3, 2))
        );
        assert_eq!(dropped_values(&read, &read), None);
        // Keys the reader added (defaults) or left out are not losses.
        let read = tree("a = [1, 2, 3, 4]\nc = [1]");
        assert_eq!(
            dropped_values(&tree("a = [1, 2, 3, 4]\nd = [1]"), &read),
            None
        );
    }

    #[test]
    fn paths_lead_to_their_values() {
        let mut doc = Value::Table(tree("[[t]]\nb = [[1, 2], [3, 4, 5]]"));
        assert_eq!(get(&doc, "t[0].b[1][2]"), Some(&Value::Integer(5)));
        assert_eq!(get(&doc, "t[0].b[2]"), None);
        assert_eq!(get(&doc, "t.b"), None);
        if let Some(Value::Array(a)) = get_mut(&mut doc, "t[0].b[1]") {
            a.truncate(2);
        }
        assert_eq!(get(&doc, "t[0].b[1][2]"), None);
    }
}
