//! What `drape run` prints on the terminal: the progress (a bar, or a
//! line every 10 % where the output is not a terminal) and the summary of
//! the setup and of the finished run.

use super::*;

/// A progress bar on a terminal, plain lines every 10 % otherwise; both
/// with the time left at the run's recent pace ([`drape::eta`]).
pub(super) struct Reporter {
    bar: Option<ProgressBar>,
    next_line: f64,
    started: Instant,
    eta: drape::eta::Eta,
}

impl Reporter {
    pub(super) fn new() -> Self {
        let bar = std::io::stderr().is_terminal().then(|| {
            let bar = ProgressBar::new(1000);
            bar.set_style(
                ProgressStyle::with_template("{spinner} [{bar:32}] {percent:>3}% {msg}")
                    .expect("valid template")
                    .progress_chars("=> "),
            );
            bar
        });
        Self {
            bar,
            next_line: 0.1,
            started: Instant::now(),
            eta: drape::eta::Eta::new(),
        }
    }

    pub(super) fn update(&mut self, p: &RunProgress) -> RunControl {
        let fraction = if p.progress.end_time > 0.0 {
            p.progress.time / p.progress.end_time
        } else {
            1.0
        };
        let message = match &p.progress.increment {
            None => format!(
                "step {} t = {:.4e} s, max shear {:.1}°",
                p.progress.step, p.progress.time, p.max_shear_deg
            ),
            Some(i) => format!(
                "increment {} t = {:.4e} s (h {:.2e}): Newton {}, solves {}, factorisations {}, active-set changes {}, contacts {} ({} stick, {} slip){}, max shear {:.1}°",
                p.progress.step,
                p.progress.time,
                p.progress.dt,
                i.newton,
                i.contact_iterations,
                i.factorisations,
                i.active_changes,
                i.active,
                i.stick,
                i.slip,
                if i.cutbacks > 0 {
                    format!(", {} cutbacks", i.cutbacks)
                } else {
                    String::new()
                },
                p.max_shear_deg
            ),
        };
        if interrupted() {
            return RunControl::Stop;
        }
        let left = self.eta.update(
            self.started.elapsed().as_secs_f64(),
            p.progress.time,
            p.progress.end_time,
        );
        let message = match left {
            Some(s) => format!("{message}, eta {}", drape::eta::duration(s)),
            None => message,
        };
        match &self.bar {
            Some(bar) => {
                bar.set_position((fraction * 1000.0) as u64);
                bar.set_message(message);
            }
            None => {
                if fraction >= self.next_line {
                    eprintln!(
                        "{:>3.0}% {message} ({:.1} s)",
                        fraction * 100.0,
                        self.started.elapsed().as_secs_f64()
                    );
                    while self.next_line <= fraction {
                        self.next_line += 0.1;
                    }
                }
            }
        }
        RunControl::Continue
    }

    pub(super) fn finish(&self) {
        if let Some(bar) = &self.bar {
            bar.finish_and_clear();
        }
    }
}

pub(super) fn print_summary(s: &Summary, out: &Path) {
    println!("status            {}", s.status);
    if let Some(r) = &s.reason {
        println!("reason            {r}");
    }
    println!("scene             {}", s.scene);
    print_mould(s);
    println!(
        "time reached      {:.6} s in {} {}",
        s.time,
        s.run.steps,
        if s.run.solver == "implicit" {
            "increments"
        } else {
            "steps"
        }
    );
    println!(
        "max shear         {:.2}° at ({:.1}, {:.1}, {:.1}) mm",
        s.max_shear_deg, s.max_shear_at[0], s.max_shear_at[1], s.max_shear_at[2]
    );
    println!("draw-in           {}", draw_in_line(s));
    print_plies(s);
    let p = &s.peak;
    if p.max_shear_time_s < s.time && p.max_shear_deg > s.max_shear_deg {
        println!(
            "peak shear        {:.2}° at t = {:.6} s, at ({:.1}, {:.1}, {:.1}) mm",
            p.max_shear_deg,
            p.max_shear_time_s,
            p.max_shear_at[0],
            p.max_shear_at[1],
            p.max_shear_at[2]
        );
    }
    println!(
        "yarn tension      {} at the end, {} largest (t = {:.6} s){}",
        drape::limits::or_na(s.max_fibre_tension_n_per_mm, 4, "N/mm"),
        drape::limits::or_na(p.max_fibre_tension_n_per_mm, 4, "N/mm"),
        p.max_fibre_tension_time_s,
        if s.max_fibre_tension_n.is_finite() {
            format!("; largest truss force {:.4} N", s.max_fibre_tension_n)
        } else {
            String::new()
        }
    );
    for t in s.tools.iter().filter(|t| t.max_force_n != 0.0) {
        let travel = if t.displacement_mm == 0.0 {
            String::new()
        } else {
            format!("travel {:.2} mm; ", t.displacement_mm)
        };
        println!(
            "tool {:<12} {travel}force on the fabric {:.1} N at the end, {:.1} N largest (t = {:.6} s)",
            t.name, t.force_n, t.max_force_n, t.max_force_time_s
        );
    }
    println!("above locking     {:.0} mm²", s.area_above_locking_mm2);
    println!(
        "wrinkle indicator max waviness {:.1}°, area above 5° {:.0} mm²",
        s.max_waviness_deg, s.wrinkle_area_mm2
    );
    // An implicit run's balance error is the work of the residual its
    // Newton iterations accept; said beside it, a gap between the two is a
    // work term the balance misses.
    let residual = s.energy.newton_residual_work.map_or(String::new(), |w| {
        format!(" (Newton residual's work {:.2e})", w.abs())
    });
    println!(
        "energy            balance error {:.2e}{residual}, {}",
        s.energy.balance_error,
        kinetic_share_text(&s.energy)
    );
    println!(
        "run               {:.1} s wall, {}",
        s.run.wall_s,
        match &s.run.device {
            Some(gpu) => format!("{} on the GPU ({gpu})", s.run.solver),
            None => format!("{} threads, {}", s.run.threads, s.run.solver),
        }
    );
    if let Some(i) = &s.run.implicit {
        println!(
            "implicit          {} contact solver: {} Newton iterations ({} more in {} cutbacks), \
             {} solves with the factors, {} active-set changes, \
             {} factorisations ({} indefinite, {} with the resin's compression scaled down), \
             factorisation {:.1} s ({:.0} % of the run)",
            i.contact_solver,
            i.newton_iterations,
            i.wasted_iterations,
            i.cutbacks,
            i.contact_iterations,
            i.active_set_changes,
            i.factorisations,
            i.indefinite,
            i.compression_scaled,
            i.factor_s,
            100.0 * i.factor_share
        );
        if i.cutbacks > 0 {
            println!(
                "cutbacks          {} (each one in cutbacks.csv)",
                i.cutback_reasons.describe()
            );
        }
    }
    for w in &s.warnings {
        println!("warning           {w}");
    }
    println!("results           {}", out.display());
}

/// What `compare SCENE` says of its forming run beside the status: why it
/// stopped, else what its fold check or warnings say, so that a run that
/// gathered is not reported as sound.
pub(super) fn forming_run_note(summary: &drape_io::results::Summary) -> String {
    if let Some(reason) = &summary.reason {
        return reason.clone();
    }
    let folded = summary.fold.as_ref().is_some_and(|f| f.folded);
    match (folded, summary.warnings.len()) {
        (true, _) => "but the fold check warns that the ply folds or gathers (see its \
                      summary.json's warnings): its shear there is not a formed ply's"
            .to_string(),
        (false, 0) => "no warning".to_string(),
        (false, 1) => "1 warning (see its summary.json)".to_string(),
        (false, n) => format!("{n} warnings (see its summary.json)"),
    }
}

/// The tool a kinematic drape was draped on, why, and how to choose
/// another; the laminate's ply it is of, likewise (nothing for a forming
/// run).
pub(super) fn print_mould(s: &Summary) {
    if let Some(ply) = &s.run.ply {
        println!(
            "ply               `{ply}`: each ply of a stack drapes as a net of its own \
             (another: --set kinematic.ply=NAME)"
        );
    }
    if let Some(mould) = &s.run.mould {
        println!(
            "mould             `{mould}`: {} (another: --set kinematic.mould=NAME)",
            s.run
                .mould_reason
                .as_deref()
                .unwrap_or("no reason recorded")
        );
    }
}

/// Output piped into a reader that stops early (`drape inspect DIR | head`)
/// ends drape quietly, as it ends `cat` or `grep`: Rust ignores SIGPIPE, so
/// the next `println!` would panic on the broken pipe instead. A run killed
/// so keeps what it wrote: every output file is written whole or not at
/// all.
pub(super) fn quit_on_a_closed_pipe() {
    #[cfg(unix)]
    // SAFETY: called first thing in `main`, before any thread is started,
    // and SIG_DFL is a valid disposition for SIGPIPE.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
}

/// A laminate's plies, one line each, bottom first: what `summary.json`'s
/// `plies` holds, so that the terminal says which ply shears most, slips
/// and is pressed (nothing for a single ply).
pub(super) fn print_plies(s: &Summary) {
    if s.plies.len() < 2 {
        return;
    }
    for p in &s.plies {
        println!(
            "ply {:<13} max shear {:.2}°, max waviness {:.1}°, draw-in {}; slip on the ply below {:.3} mm, \
             pressure {:.4} MPa, overlap {:.2e} mm",
            p.name,
            p.max_shear_deg,
            p.max_waviness_deg,
            draw_in_values(&p.draw_in_mm),
            p.max_slip_mm,
            p.max_pressure_mpa,
            p.max_overlap_mm
        );
    }
}

/// The draw-in values a summary has, `n/a` for those it lacks, and its
/// note saying why.
pub(super) fn draw_in_line(s: &Summary) -> String {
    let d = &s.draw_in_mm;
    let mut line = draw_in_values(d);
    if ![d.dx, d.dy, d.dd].iter().all(|v| v.is_finite()) {
        line.push_str(&format!(
            " ({})",
            s.draw_in_note.as_deref().unwrap_or("not measured")
        ));
    }
    line
}

/// DX, DY and DD, `n/a` for those not measured.
pub(super) fn draw_in_values(d: &drape_io::results::DrawInMm) -> String {
    let value = |name: &str, v: f64| {
        if v.is_finite() {
            format!("{name} {v:.2} mm")
        } else {
            format!("{name} n/a")
        }
    };
    [value("DX", d.dx), value("DY", d.dy), value("DD", d.dd)].join(", ")
}

/// E_kin/E_int, or both energies where the internal one is too small for
/// a ratio (the summary's ratio is null then).
pub(super) fn kinetic_share_text(e: &drape_io::results::EnergySummary) -> String {
    if e.kinetic_to_internal.is_finite() {
        return format!("E_kin/E_int {:.2e}", e.kinetic_to_internal);
    }
    match (e.kinetic_mj, e.internal_mj) {
        (Some(k), Some(i)) => {
            format!("E_kin {k:.3e} mJ, E_int {i:.3e} mJ (the blank is barely strained: no ratio)")
        }
        _ => "E_kin/E_int n/a".to_owned(),
    }
}

/// The model and the time step of a run, before it starts (on stderr, with
/// the progress).
pub(super) fn print_setup(s: &drape_io::results::RunSetup, solver: drape_io::scene::Solver) {
    let fibres = if s.trusses > 0 {
        format!("{} trusses", s.trusses)
    } else {
        format!("fibres {}", s.fibres)
    };
    eprintln!(
        "model             {} nodes, {} membrane elements, {fibres}",
        s.nodes, s.membrane_elements
    );
    let scaled = match s.mass_scaling_dt_s {
        Some(target) => format!(
            "; mass-scaled to {target:.3e} s, adding {:.3e} t ({:.1} % of the mass)",
            s.added_mass_t,
            100.0 * s.added_mass_fraction
        ),
        None => String::new(),
    };
    if solver == drape_io::scene::Solver::Implicit {
        eprintln!(
            "increments        implicit, {}; first {:.3e} s, then as Newton converges \
             (explicit stable step {:.3e} s)",
            if scaled.is_empty() {
                "physical mass".to_owned()
            } else {
                scaled.trim_start_matches("; ").to_owned()
            },
            s.time_step_s,
            s.stable_time_step_s
        );
        return;
    }
    eprintln!(
        "time step         stable {:.3e} s{scaled}; starts at {:.3e} s, about {} steps",
        s.stable_time_step_s, s.time_step_s, s.expected_steps
    );
}
