//! Reading a sweep's `sweep.csv` back for `drape inspect`: a table cut
//! short (a copy that stopped, a disk that filled under another writer) is
//! told apart from a sweep of fewer runs. `drape sweep` writes the table
//! whole (a temporary renamed over it), so a cut one did not come from it
//! as it is.
//!
//! Not here: writing the table (`sweep_table` in the `drape` binary).

/// The columns of the table's header after the swept keys, as `drape
/// sweep` writes them (one list, so writer and reader cannot drift).
pub const MEASURE_COLUMNS: [&str; 12] = [
    "status",
    "max_shear_deg",
    "draw_in_dx_mm",
    "draw_in_dy_mm",
    "draw_in_dd_mm",
    "max_fibre_tension_n",
    "balance_error",
    "steps",
    "wall_s",
    "peak_max_shear_deg",
    "peak_time_s",
    "max_fibre_tension_n_per_mm",
];

/// The last column of the table's header.
pub const LAST_COLUMN: &str = MEASURE_COLUMNS[MEASURE_COLUMNS.len() - 1];

/// Checks the text of a `sweep.csv` and returns its rows (the header
/// first), or why it is not a whole table: no header, a header without
/// the columns `drape sweep` writes, a last line without its end, a row
/// with another number of fields than the header, rows not numbered
/// run_000, run_001, … in order, or no run row at all (a sweep runs at
/// least one). A table cut exactly at the end of a row cannot be told
/// from a smaller sweep by its text: [`note`] compares it with the run
/// folders beside it.
pub fn check(text: &str) -> Result<Vec<Vec<&str>>, String> {
    let Some(header) = text.lines().next() else {
        return Err("empty: no header, no runs".to_owned());
    };
    let columns: Vec<&str> = header.split(',').collect();
    if columns.first() != Some(&"run")
        || !columns.contains(&"status")
        || columns.last() != Some(&LAST_COLUMN)
    {
        return Err(format!(
            "the header `{header}` is not a sweep table's (run, the swept keys, status, … \
             {LAST_COLUMN}): cut short or not written by drape sweep"
        ));
    }
    let rows: Vec<Vec<&str>> = text.lines().map(|l| l.split(',').collect()).collect();
    let whole = rows.len() - 1;
    if !text.ends_with('\n') {
        return Err(format!(
            "cut short: its last line `{}` has no end; {} whole run rows before it",
            text.lines().last().unwrap_or_default(),
            whole.saturating_sub(1)
        ));
    }
    for (i, row) in rows.iter().enumerate().skip(1) {
        let name = format!("run_{:03}", i - 1);
        if row.len() != columns.len() || row[0] != name {
            return Err(format!(
                "line {} (`{}`) is not {name}'s row of {} fields: cut or damaged",
                i + 1,
                row.join(","),
                columns.len()
            ));
        }
    }
    if whole == 0 {
        return Err("cut short: a header and no run row (a sweep runs at least one)".to_owned());
    }
    Ok(rows)
}

/// A note when the folder holds more run folders (`run_folders`) than the
/// table has rows (`rows`, without the header): the table may be cut at a
/// row's end, or an earlier, larger sweep left them.
pub fn note(rows: usize, run_folders: usize) -> Option<String> {
    (run_folders > rows).then(|| {
        format!(
            "the folder holds {run_folders} run folders (run_NNN) and the table {rows} rows: \
             run_{rows:03} on are not in it (an earlier, larger sweep's, or the table is cut \
             short)"
        )
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    const HEADER: &str = "run,tools.0.friction,status,max_shear_deg,draw_in_dx_mm,\
draw_in_dy_mm,draw_in_dd_mm,max_fibre_tension_n,balance_error,steps,wall_s,peak_max_shear_deg,\
peak_time_s,max_fibre_tension_n_per_mm";

    fn row(i: usize) -> String {
        format!("run_{i:03},0.1,completed,1,2,3,4,5,1e-3,100,0.5,1,0.1,0.2")
    }

    #[test]
    fn a_whole_table_reads_and_every_cut_is_named() {
        let whole = format!("{HEADER}\n{}\n{}\n", row(0), row(1));
        assert_eq!(check(&whole).unwrap().len(), 3);
        // Cut inside the second row.
        let cut = &whole[..whole.len() - 10];
        let why = check(cut).unwrap_err();
        assert!(
            why.contains("cut short") && why.contains("1 whole run rows"),
            "{why}"
        );
        // Cut inside the header: no runs is not "0 runs".
        let why = check(&HEADER[..40]).unwrap_err();
        assert!(why.contains("not a sweep table"), "{why}");
        // Cut after the header.
        let why = check(&format!("{HEADER}\n")).unwrap_err();
        assert!(why.contains("no run row"), "{why}");
        // Cut at a row's end: the text is a smaller sweep's; the folders
        // tell.
        let at_line = format!("{HEADER}\n{}\n", row(0));
        assert_eq!(check(&at_line).unwrap().len(), 2);
        let said = note(1, 2).unwrap();
        assert!(
            said.contains("2 run folders") && said.contains("run_001 on"),
            "{said}"
        );
        assert_eq!(note(2, 2), None);
        assert!(check("").unwrap_err().contains("empty"));
        // A row short of fields.
        let short = format!("{HEADER}\nrun_000,0.1,completed\n");
        assert!(check(&short).unwrap_err().contains("line 2"));
    }
}
