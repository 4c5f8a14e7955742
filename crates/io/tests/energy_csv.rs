//! `energy.csv` never holds NaN or inf: a value that is not a number is
//! left empty (issue 29: a 0-step run wrote `NaN` kinetic energy).

use drape_io::results::{EnergyRow, ResultsDir};
use drape_time::Energies;

#[test]
fn a_value_that_is_not_a_number_is_left_empty() {
    let dir = std::env::temp_dir().join(format!("drape-energy-csv-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let out = ResultsDir::create(&dir).unwrap();
    let rows = [EnergyRow {
        time: 0.0,
        step: 0,
        energy: Energies {
            kinetic: f64::NAN,
            strain: f64::INFINITY,
            internal_work: 1.5,
            ..Energies::default()
        },
    }];
    out.write_energy(&rows).unwrap();
    let csv = std::fs::read_to_string(dir.join("energy.csv")).unwrap();
    let row = csv.lines().nth(1).unwrap();
    assert_eq!(row, "0,0,,,1.5,0,0,0,0,0,0,0,0,0");
    assert!(!csv.to_lowercase().contains("nan") && !csv.contains("inf"));
    drop(out);
    std::fs::remove_dir_all(&dir).unwrap();
}
