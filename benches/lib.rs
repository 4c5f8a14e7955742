//! drape's criterion benches live in `benches/` (`kernels.rs`: the
//! per-integration-point kernels; `elements.rs`: the element batch passes;
//! `explicit.rs`: the explicit driver's step throughput; `contact.rs`: the
//! contact pass against the element pass; `implicit_iteration.rs`: the
//! pieces of one implicit Newton iteration on the hemisphere's tangent). This library holds what they
//! may share: a stopwatch that reads either the wall clock or the calling
//! thread's CPU time.
//!
//! On a machine shared with other work, `DRAPE_BENCH_CLOCK=thread-cpu`
//! makes the single-thread benches time by the CPU time of the thread that
//! runs the work (Linux `CLOCK_THREAD_CPUTIME_ID`): the time it spends
//! descheduled no longer counts, so a per-core figure stays meaningful while
//! other processes compete for the cores. Multi-threaded benches always use
//! the wall clock.

use std::time::{Duration, Instant};

/// Which clock a [`Stopwatch`] reads.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Clock {
    /// Wall time (criterion's default).
    Wall,
    /// CPU time of the thread that starts and reads the stopwatch.
    ThreadCpu,
}

impl Clock {
    /// [`Clock::ThreadCpu`] if `DRAPE_BENCH_CLOCK=thread-cpu`, else wall.
    ///
    /// # Panics
    /// If thread CPU time is asked for on a platform without it here
    /// (anything but 64-bit Linux).
    pub fn from_env() -> Self {
        let wanted = std::env::var("DRAPE_BENCH_CLOCK").is_ok_and(|v| v == "thread-cpu");
        if !wanted {
            return Self::Wall;
        }
        if cfg!(all(target_os = "linux", target_pointer_width = "64")) {
            Self::ThreadCpu
        } else {
            panic!("DRAPE_BENCH_CLOCK=thread-cpu needs 64-bit Linux")
        }
    }
}

/// A started measurement.
#[derive(Debug, Clone, Copy)]
pub enum Stopwatch {
    /// Started at this instant.
    Wall(Instant),
    /// Started at this thread CPU time.
    ThreadCpu(Duration),
}

impl Stopwatch {
    /// Starts measuring with `clock`.
    pub fn start(clock: Clock) -> Self {
        match clock {
            Clock::Wall => Self::Wall(Instant::now()),
            Clock::ThreadCpu => Self::ThreadCpu(thread_cpu_time()),
        }
    }

    /// Time since the start (on the same thread for [`Clock::ThreadCpu`]).
    pub fn elapsed(&self) -> Duration {
        match self {
            Self::Wall(start) => start.elapsed(),
            Self::ThreadCpu(start) => thread_cpu_time().saturating_sub(*start),
        }
    }
}

/// Runs `f` `iters` times and returns the time taken by `clock`, for
/// criterion's `iter_custom`.
pub fn time_iters(clock: Clock, iters: u64, mut f: impl FnMut()) -> Duration {
    let watch = Stopwatch::start(clock);
    for _ in 0..iters {
        f();
    }
    watch.elapsed()
}

/// The calling thread's CPU time (Linux `CLOCK_THREAD_CPUTIME_ID`).
///
/// # Panics
/// On a platform without it here (anything but 64-bit Linux).
#[cfg(all(target_os = "linux", target_pointer_width = "64"))]
pub fn thread_cpu_time() -> Duration {
    #[repr(C)]
    struct Timespec {
        tv_sec: i64,
        tv_nsec: i64,
    }
    unsafe extern "C" {
        fn clock_gettime(clock: i32, ts: *mut Timespec) -> i32;
    }
    const CLOCK_THREAD_CPUTIME_ID: i32 = 3;
    let mut ts = Timespec {
        tv_sec: 0,
        tv_nsec: 0,
    };
    // SAFETY: `ts` is a valid, writable `struct timespec` (64-bit `time_t`
    // and `long` on 64-bit Linux).
    let rc = unsafe { clock_gettime(CLOCK_THREAD_CPUTIME_ID, &mut ts) };
    assert_eq!(rc, 0, "clock_gettime(CLOCK_THREAD_CPUTIME_ID) failed");
    Duration::new(ts.tv_sec as u64, ts.tv_nsec as u32)
}

/// The calling thread's CPU time: not available on this platform.
///
/// # Panics
/// Always (see [`Clock::from_env`]).
#[cfg(not(all(target_os = "linux", target_pointer_width = "64")))]
pub fn thread_cpu_time() -> Duration {
    panic!("thread CPU time needs 64-bit Linux")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn both_clocks_advance_with_work() {
        let clocks: &[Clock] = if cfg!(all(target_os = "linux", target_pointer_width = "64")) {
            &[Clock::Wall, Clock::ThreadCpu]
        } else {
            &[Clock::Wall]
        };
        for &clock in clocks {
            let mut x = 1.0f64;
            let t = time_iters(clock, 2_000_000, || {
                x = std::hint::black_box(x.sqrt() + 1.0)
            });
            assert!(t > Duration::ZERO, "{clock:?}");
        }
    }
}
