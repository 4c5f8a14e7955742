//! The contract every `drape` subcommand keeps with whoever started it (a
//! shell, a script, a batch scheduler), in one place so that no command
//! keeps a version of its own:
//!
//! - exit codes: [`DONE`] 0, [`FAILED`] 1 (the work was attempted and did
//!   not give what it claims: a summary says why), [`BAD_INPUT`] 2 (bad
//!   input, or an output folder that cannot be used: refused before
//!   anything is written), [`STOPPED`] 130 (a signal stopped it);
//! - the output folder: every writing command claims it ([`claim_output`];
//!   released at once, [`OutputClaim::release`], where the library's
//!   [`drape_io::results::ResultsDir`] takes the claim itself) through the
//!   same lock a run holds (`.drape.lock`), so nothing writes into a
//!   folder a running run writes into, an unwritable, held or
//!   file-occupied folder is exit 2 for every command, and bad input found
//!   after the claim leaves no folder behind ([`settle`]);
//! - signals: the handler is installed before anything is read; while the
//!   input is being read ([`reading`]: a scene from a FIFO can block there
//!   for ever) nothing has been written, so the first signal quits at once
//!   with 130 instead of waiting for a run that has not started.
//!
//! Not here: what a run writes when it stops (the facade's `run_in`), or
//! the messages for one command's own bad input.

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};

use anyhow::Result;
use drape_io::results::OutputLock;

/// The work was done (and is what the summary says).
#[allow(dead_code)]
pub const DONE: u8 = 0;
/// The work was attempted and did not give what it claims; a summary on
/// the console (and in the output, where there is one) says why.
pub const FAILED: u8 = 1;
/// Bad input or an unusable output folder: refused before anything is
/// written.
pub const BAD_INPUT: u8 = 2;
/// Stopped by a signal (128 + SIGINT, as shells report Ctrl-C; SIGTERM and
/// SIGHUP too).
pub const STOPPED: u8 = 130;

/// Set while the command only reads its input (nothing written yet).
static READING: AtomicBool = AtomicBool::new(false);

/// Set by a command that has no clean stopping point of its own (a
/// kinematic drape, a comparison of two folders, an export: seconds, each
/// file written whole): a signal quits it at once.
static AT_ONCE: AtomicBool = AtomicBool::new(false);

/// From now on a signal quits at once with [`STOPPED`] (see [`AT_ONCE`]).
pub fn quit_at_once_on_signal() {
    AT_ONCE.store(true, Ordering::SeqCst);
    if crate::interrupted() {
        quit_now();
    }
}

/// What the signal handler does with a signal: quit at once (`true`:
/// reading the input, or a command without a stopping point), or ask the
/// run to stop after its step (`false`).
pub fn signal_quits_at_once() -> bool {
    READING.load(Ordering::SeqCst) || AT_ONCE.load(Ordering::SeqCst)
}

/// Exits with [`STOPPED`], saying what is left.
pub fn quit_now() -> ! {
    if READING.load(Ordering::SeqCst) {
        quit_before_writing();
    }
    eprintln!(
        "\nstopped: every file written so far is whole; the rest were not written (and no \
         summary says the work is done)"
    );
    std::process::exit(i32::from(STOPPED));
}

/// Runs `read` (reading input, writing nothing) so that a signal during it
/// quits at once with [`STOPPED`]: a read can block (a FIFO, a stalled
/// network file system), and there is nothing to stop cleanly yet. A
/// signal that came before is honoured here too.
pub fn reading<T>(read: impl FnOnce() -> T) -> T {
    READING.store(true, Ordering::SeqCst);
    if crate::interrupted() {
        quit_before_writing();
    }
    let value = read();
    READING.store(false, Ordering::SeqCst);
    value
}

/// Exits with [`STOPPED`] while nothing has been written.
pub fn quit_before_writing() -> ! {
    eprintln!("\nstopped while reading the input: nothing was written");
    std::process::exit(i32::from(STOPPED));
}

/// An output folder claimed for this process: the same lock a run takes
/// (held until dropped), so that no run writes into it meanwhile and this
/// command writes into no folder a run is writing into.
#[derive(Debug)]
pub struct OutputClaim {
    lock: Option<OutputLock>,
    /// The folder, and the outermost folder this claim created (None when
    /// it existed).
    dir: PathBuf,
    created: Option<PathBuf>,
}

impl OutputClaim {
    /// Lets go of the lock (for a library call that claims the folder
    /// itself), keeping the note of what was created for [`settle`].
    pub fn release(mut self) -> Self {
        self.lock = None;
        self
    }

    /// Undoes the claim after bad input: the lock file goes, and the
    /// folders the claim created go too if nothing else was put in them,
    /// so bad input leaves nothing behind.
    fn abandon(mut self) {
        self.lock = None;
        let Some(top) = &self.created else { return };
        let _ = std::fs::remove_file(self.dir.join(drape_io::results::LOCK_FILE));
        for dir in self.dir.ancestors() {
            // Fails, and stops here, on a folder that holds anything.
            if std::fs::remove_dir(dir).is_err() || dir == top {
                break;
            }
        }
    }
}

/// `result`, after undoing `claims` (innermost first) when it is bad input
/// (exit 2: nothing may be left written).
pub fn settle<T>(claims: Vec<OutputClaim>, result: Result<T>) -> Result<T> {
    if let Err(e) = &result
        && e.downcast_ref::<crate::BadInput>().is_some()
    {
        for claim in claims.into_iter().rev() {
            claim.abandon();
        }
    }
    result
}

/// Claims `out` (creating it if needed). A folder that is a file, lies
/// inside one, cannot be written, or that a running run holds is bad input
/// (exit 2) with the message a run gives for it.
pub fn claim_output(out: &Path) -> Result<OutputClaim> {
    let created = out
        .ancestors()
        .take_while(|a| !a.as_os_str().is_empty() && !a.exists())
        .last()
        .map(Path::to_owned);
    let lock = match OutputLock::acquire(out) {
        Ok(lock) => lock,
        Err(e) => {
            let unusable = crate::unusable_output(out, &e);
            if let Some(top) = &created {
                // What create_dir_all made before the failure, if empty.
                for dir in out.ancestors() {
                    if std::fs::remove_dir(dir).is_err() || dir == top {
                        break;
                    }
                }
            }
            return Err(unusable);
        }
    };
    // Held: no writer is left in the folder, so a temporary there is one a
    // killed command left.
    let _ = drape_io::atomic::remove_temporaries(out);
    Ok(OutputClaim {
        lock: Some(lock),
        dir: out.to_owned(),
        created,
    })
}
