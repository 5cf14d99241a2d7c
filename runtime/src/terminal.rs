//! The keyboard of a terminal in raw mode, as KRoC's keyboard process sets it: each key reaches
//! the program as it is pressed, and the terminal does not echo it (the course library's input
//! routines echo what they accept themselves). Ctrl-C still interrupts.
//!
//! [`RawMode::enter`] switches standard input when it is a terminal; dropping the guard
//! switches it back. So that an interrupted program does not leave the user's shell without
//! echo, SIGINT, SIGTERM, SIGQUIT and SIGHUP restore the terminal before they take their
//! default action.

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Mutex, OnceLock};

/// The terminal settings before raw mode, for the guard and the signal handler.
static SAVED: OnceLock<libc::termios> = OnceLock::new();
/// Whether raw mode is on (the handler restores only then).
static RAW: AtomicBool = AtomicBool::new(false);
/// Serialises entering and leaving.
static SWITCH: Mutex<()> = Mutex::new(());

const SIGNALS: [libc::c_int; 4] = [libc::SIGINT, libc::SIGTERM, libc::SIGQUIT, libc::SIGHUP];

/// Raw mode on standard input while it lives.
#[derive(Debug)]
pub(crate) struct RawMode(());

impl RawMode {
    /// Switches standard input to raw mode (no line editing, no echo; signals kept), or `None`
    /// when it is not a terminal or cannot be switched.
    pub(crate) fn enter() -> Option<RawMode> {
        let _switch = SWITCH.lock().unwrap_or_else(|p| p.into_inner());
        // SAFETY: isatty, tcgetattr and tcsetattr on fd 0 with a termios this function owns.
        unsafe {
            if libc::isatty(libc::STDIN_FILENO) != 1 {
                return None;
            }
            let mut t: libc::termios = std::mem::zeroed();
            if libc::tcgetattr(libc::STDIN_FILENO, &mut t) != 0 {
                return None;
            }
            let saved = *SAVED.get_or_init(|| t);
            let mut raw = saved;
            raw.c_lflag &= !(libc::ICANON | libc::ECHO);
            raw.c_cc[libc::VMIN] = 1;
            raw.c_cc[libc::VTIME] = 0;
            install_handlers();
            if libc::tcsetattr(libc::STDIN_FILENO, libc::TCSANOW, &raw) != 0 {
                return None;
            }
        }
        RAW.store(true, Ordering::SeqCst);
        Some(RawMode(()))
    }
}

impl Drop for RawMode {
    fn drop(&mut self) {
        let _switch = SWITCH.lock().unwrap_or_else(|p| p.into_inner());
        restore();
    }
}

/// Puts the saved settings back if raw mode is on. Async-signal-safe (tcsetattr is).
fn restore() {
    if RAW.swap(false, Ordering::SeqCst)
        && let Some(saved) = SAVED.get()
    {
        // SAFETY: fd 0 and settings read from it before.
        unsafe {
            libc::tcsetattr(libc::STDIN_FILENO, libc::TCSANOW, saved);
        }
    }
}

extern "C" fn on_signal(signal: libc::c_int) {
    restore();
    // SA_RESETHAND made the action the default again: raise it for the default outcome.
    // SAFETY: raise is async-signal-safe.
    unsafe {
        libc::raise(signal);
    }
}

/// Installs [`on_signal`] for [`SIGNALS`] that are not ignored (once per raw mode; a handler
/// resets itself when it runs).
fn install_handlers() {
    for signal in SIGNALS {
        // SAFETY: sigaction with a zeroed action and a handler that only restores and re-raises.
        unsafe {
            let mut old: libc::sigaction = std::mem::zeroed();
            if libc::sigaction(signal, std::ptr::null(), &mut old) != 0
                || old.sa_sigaction == libc::SIG_IGN
            {
                continue;
            }
            let mut action: libc::sigaction = std::mem::zeroed();
            action.sa_sigaction = on_signal as extern "C" fn(libc::c_int) as libc::sighandler_t;
            action.sa_flags = libc::SA_RESETHAND;
            libc::sigemptyset(&mut action.sa_mask);
            libc::sigaction(signal, &action, std::ptr::null_mut());
        }
    }
}
