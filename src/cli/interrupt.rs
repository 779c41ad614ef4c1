//! Ctrl-C (SIGINT) and SIGTERM during a run. The handler only notes the signal in atomics
//! (`signal-hook`); the run checks the flag once per step (`sim::Control::cancel`) and ends
//! after the step it is in, and the command then exits with status 128 + the signal's number
//! ([`Interrupted`]). A second signal ends the process at once, with the same status, for a
//! run that does not stop soon enough (its temporary files are removed by the next run in the
//! folder: `io::remove_stale_temps`).

use signal_hook::consts::{SIGINT, SIGTERM};
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::{Arc, OnceLock};

/// What the signal handlers set.
#[derive(Debug, Default)]
pub struct Signals {
    flag: Arc<AtomicBool>,
    which: Arc<AtomicUsize>,
}

static SIGNALS: OnceLock<Signals> = OnceLock::new();

/// Installs the handlers of SIGINT and SIGTERM (once per process) and returns what they set.
pub fn install() -> anyhow::Result<&'static Signals> {
    if let Some(s) = SIGNALS.get() {
        return Ok(s);
    }
    let s = Signals::default();
    for sig in [SIGINT, SIGTERM] {
        // The shutdown first: it sees the flag of an earlier signal, not of this one.
        signal_hook::flag::register_conditional_shutdown(sig, 128 + sig, s.flag.clone())?;
        signal_hook::flag::register_usize(sig, s.which.clone(), sig as usize)?;
        signal_hook::flag::register(sig, s.flag.clone())?;
    }
    Ok(SIGNALS.get_or_init(|| s))
}

impl Signals {
    /// The flag a run checks (`sim::Control::cancel`).
    pub fn cancel(&self) -> &AtomicBool {
        &self.flag
    }

    /// The error of a command stopped by the signal that came, with `message` after its name.
    pub fn interrupted(&self, message: impl std::fmt::Display) -> Interrupted {
        let signal = match self.which.load(Ordering::SeqCst) as i32 {
            0 => SIGINT,
            s => s,
        };
        let name = match signal {
            SIGINT => "SIGINT (Ctrl-C)",
            SIGTERM => "SIGTERM",
            _ => "a signal",
        };
        Interrupted {
            signal,
            message: format!("interrupted by {name} {message}"),
        }
    }
}

/// A command stopped by a signal: one line on stderr, exit status 128 + the signal's number.
#[derive(Debug, thiserror::Error)]
#[error("{message}")]
pub struct Interrupted {
    /// The signal's number.
    pub signal: i32,
    /// What happened and what to do next.
    pub message: String,
}

impl Interrupted {
    /// The exit status: 130 for SIGINT, 143 for SIGTERM.
    pub fn status(&self) -> u8 {
        u8::try_from(128 + self.signal).unwrap_or(1)
    }
}

/// The command line that continues this run: the one given, with `--resume` (quoted for a
/// POSIX shell).
pub fn resume_command() -> String {
    let mut args: Vec<String> = std::env::args().collect();
    if !args.iter().any(|a| a == "--resume") {
        args.push("--resume".into());
    }
    shlex::try_join(args.iter().map(String::as_str)).unwrap_or_else(|_| args.join(" "))
}
