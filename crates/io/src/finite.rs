//! The check every writer of numbers makes before a value reaches a file:
//! no `NaN` or infinity is ever written. A value that cannot be computed
//! is the writer's to report as missing (an empty CSV field, a listed
//! element set) with the reason; one that should always be finite and is
//! not is an error naming what it is.

/// The first value of `values` that is not finite, with its position.
pub fn first_non_finite(values: impl IntoIterator<Item = f64>) -> Option<(usize, f64)> {
    values.into_iter().enumerate().find(|(_, v)| !v.is_finite())
}

/// `Err` naming `what` and the position of its first value that is not
/// finite.
pub fn check(what: &str, values: impl IntoIterator<Item = f64>) -> Result<(), String> {
    match first_non_finite(values) {
        None => Ok(()),
        Some((k, v)) => Err(format!(
            "{what}: value {} is {v}, not a finite number: not written",
            k + 1
        )),
    }
}

/// `v` written by `format`, or an empty field when it is not finite.
pub fn or_empty(v: f64, format: impl Fn(f64) -> String) -> String {
    if v.is_finite() {
        format(v)
    } else {
        String::new()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn finds_the_first_value_that_is_not_finite() {
        assert_eq!(first_non_finite([1.0, 2.0]), None);
        assert_eq!(
            first_non_finite([1.0, f64::INFINITY, f64::NAN]).unwrap().0,
            1
        );
        let e = check("thickness", [1.0, 2.0, f64::NAN]).unwrap_err();
        assert!(e.contains("thickness: value 3 is NaN"), "{e}");
        assert!(check("x", [0.0, -1e308]).is_ok());
        assert_eq!(or_empty(f64::NEG_INFINITY, |v| v.to_string()), "");
        assert_eq!(or_empty(0.5, |v| v.to_string()), "0.5");
    }
}
