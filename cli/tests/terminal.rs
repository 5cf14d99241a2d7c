//! The keyboard of a terminal, as KRoC's: raw mode at the program's first input (each key
//! reaches the program as it is pressed, and the terminal does not echo it), the terminal put
//! back when the program ends or a signal stops it. Run on a pseudo-terminal.

use std::io::Read;
use std::os::fd::{AsRawFd, FromRawFd, OwnedFd};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

mod common;

/// Reads two keys and prints them between brackets.
const TWO_KEYS: &str = "\
PROC main (CHAN BYTE keyboard?, screen!, error!)
  BYTE a, b:
  SEQ
    keyboard ? a
    keyboard ? b
    screen ! '['
    screen ! a
    screen ! b
    screen ! ']'
    screen ! '*n'
:
";

/// A pseudo-terminal: (master, slave).
fn pty() -> (OwnedFd, OwnedFd) {
    let (mut master, mut slave) = (0, 0);
    // SAFETY: openpty writes the two descriptors it opens; no name, default settings.
    let rc = unsafe {
        libc::openpty(
            &mut master,
            &mut slave,
            std::ptr::null_mut(),
            std::ptr::null(),
            std::ptr::null(),
        )
    };
    assert_eq!(rc, 0, "openpty failed");
    // SAFETY: both are open descriptors this test now owns.
    unsafe { (OwnedFd::from_raw_fd(master), OwnedFd::from_raw_fd(slave)) }
}

/// The terminal's local flags.
fn lflags(fd: &OwnedFd) -> libc::tcflag_t {
    // SAFETY: tcgetattr fills the zeroed termios for an open terminal descriptor.
    unsafe {
        let mut t: libc::termios = std::mem::zeroed();
        assert_eq!(libc::tcgetattr(fd.as_raw_fd(), &mut t), 0);
        t.c_lflag
    }
}

fn raw(fd: &OwnedFd) -> bool {
    lflags(fd) & (libc::ICANON | libc::ECHO) == 0
}

/// Waits up to ten seconds for `done`.
fn wait_for(what: &str, mut done: impl FnMut() -> bool) {
    let start = Instant::now();
    while !done() {
        assert!(
            start.elapsed() < Duration::from_secs(10),
            "{what}: not within 10 s"
        );
        std::thread::sleep(Duration::from_millis(20));
    }
}

/// `occ run` of `program` with the terminal `slave` as its standard input.
fn run_on(slave: &OwnedFd, program: &str, name: &str) -> Child {
    let dir = common::scratch(name);
    std::fs::create_dir_all(&dir).expect("scratch folder");
    let file = dir.join("keys.occ");
    std::fs::write(&file, program).expect("program written");
    Command::new(env!("CARGO_BIN_EXE_occ"))
        .arg("run")
        .arg(&file)
        .stdin(Stdio::from(slave.try_clone().expect("slave cloned")))
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("occ runs")
}

/// The child's exit, killing it after ten seconds.
fn finish(mut child: Child) -> (Option<i32>, String) {
    let start = Instant::now();
    let status = loop {
        if let Some(s) = child.try_wait().expect("wait") {
            break s;
        }
        if start.elapsed() > Duration::from_secs(10) {
            let _ = child.kill();
            panic!("occ did not end within 10 s");
        }
        std::thread::sleep(Duration::from_millis(20));
    };
    let mut out = String::new();
    if let Some(mut o) = child.stdout.take() {
        o.read_to_string(&mut out).expect("stdout");
    }
    (status.code(), out)
}

/// What the terminal shows (its echo), waiting a little for it.
fn shown(master: &OwnedFd) -> Vec<u8> {
    let mut got = Vec::new();
    let mut poll = libc::pollfd {
        fd: master.as_raw_fd(),
        events: libc::POLLIN,
        revents: 0,
    };
    // SAFETY: poll and read on the open master with a buffer of the given length.
    unsafe {
        while libc::poll(&mut poll, 1, 200) == 1 {
            let mut buf = [0u8; 256];
            let n = libc::read(master.as_raw_fd(), buf.as_mut_ptr().cast(), buf.len());
            if n <= 0 {
                break;
            }
            got.extend_from_slice(&buf[..n as usize]);
        }
    }
    got
}

#[test]
fn a_terminal_keyboard_delivers_each_key_unechoed_and_is_put_back() {
    let (master, slave) = pty();
    assert!(!raw(&slave), "a new terminal starts in line mode");
    let child = run_on(&slave, TWO_KEYS, "terminal-keys");
    wait_for("raw mode at the first input", || raw(&slave));
    // Two keys and no newline: in line mode the program would wait for the end of the line.
    // SAFETY: write of two bytes from a live buffer to the open master.
    let wrote = unsafe { libc::write(master.as_raw_fd(), b"xy".as_ptr().cast(), 2) };
    assert_eq!(wrote, 2);
    let (code, out) = finish(child);
    assert_eq!(code, Some(0));
    assert_eq!(out, "[xy]\n");
    let echo = shown(&master);
    assert!(
        !echo.windows(2).any(|w| w == b"xy"),
        "the terminal echoed the keys: {echo:?}"
    );
    assert!(!raw(&slave), "the terminal is back in line mode with echo");
}

#[test]
fn an_interrupted_program_puts_the_terminal_back() {
    let (_master, slave) = pty();
    let child = run_on(&slave, TWO_KEYS, "terminal-interrupt");
    wait_for("raw mode at the first input", || raw(&slave));
    // SAFETY: a signal to the child this test started.
    assert_eq!(
        unsafe { libc::kill(child.id() as libc::pid_t, libc::SIGINT) },
        0
    );
    let (code, _) = finish(child);
    assert_eq!(code, None, "SIGINT ends the program");
    assert!(!raw(&slave), "the terminal is back in line mode with echo");
}
