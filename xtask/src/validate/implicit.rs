//! Validation of the implicit driver (SPEC §7 "Implicit", §6 "Normal,
//! implicit"): every contact case of [`super::contact`] run again with
//! Newton increments and the condensed contact solve, with the same
//! references and tolerances.

use super::contact::{self, Driver};
use super::{Case, Check};

/// The cases of this module.
pub const CASES: &[Case] = &[
    Case {
        name: "implicit/incline",
        quick: true,
        run: incline,
    },
    Case {
        name: "implicit/capstan",
        quick: true,
        run: capstan,
    },
    Case {
        name: "implicit/no-penetration",
        quick: true,
        run: no_penetration,
    },
    Case {
        name: "implicit/pinching",
        quick: true,
        run: pinching,
    },
];

fn incline() -> Vec<Check> {
    contact::incline_with(Driver::Implicit)
}

fn capstan() -> Vec<Check> {
    contact::capstan_with(Driver::Implicit)
}

fn no_penetration() -> Vec<Check> {
    contact::no_penetration_with(Driver::Implicit)
}

fn pinching() -> Vec<Check> {
    contact::pinching_with(Driver::Implicit)
}
