//! Host I/O: the top-level PROC's `keyboard`, `screen` and `error` byte channels.
//!
//! The three channels are endpoints ([`crate::Node::host_channels`]): output on `screen`
//! or `error` appends to a buffered writer and completes at once (the byte [`FLUSH`] flushes
//! instead); input on `keyboard` flushes the
//! screen, then reads from the host's input (blocking the node's thread, like KRoC's blocking
//! keyboard process). At end of input the keyboard delivers byte 255 ([`END_OF_INPUT`]), and
//! again on every later read. Output is flushed when the node stops, in every case.
//!
//! When the input is a terminal, it is read on a thread of its own instead (the `keyboard` module),
//! so that a process waiting for a key blocks only itself.
//!
//! When the screen is a terminal ([`HostIo::stdio`] asks), it is also flushed at each newline, as
//! KRoC's screen is, so a program that prints a line now and then is seen as it runs; output to a
//! file or pipe stays fully buffered, which keeps bulk output fast.
//!
//! When the input is a terminal ([`HostIo::stdio`] asks), the first keyboard input puts it in
//! raw mode, as KRoC does: each key reaches the program as it is pressed, without the terminal's
//! echo. The terminal is put back when the host streams are dropped (the program has ended) or a
//! signal stops the process.

use std::io::{BufWriter, IsTerminal, Read, Write};

use crate::keyboard::Keyboard;

/// Which host stream an output endpoint writes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum HostStream {
    /// `screen`: standard output.
    Screen,
    /// `error`: standard error.
    Error,
}

/// The byte delivered by `keyboard` at end of input.
pub const END_OF_INPUT: u8 = 255;

/// The byte that, sent to `screen` or `error`, flushes it instead of being written (the course
/// library's `FLUSH`).
pub const FLUSH: u8 = 255;

/// The host streams a node's host channels are bound to.
pub struct HostIo {
    input: Box<dyn Read + Send>,
    screen: BufWriter<Box<dyn Write + Send>>,
    error: BufWriter<Box<dyn Write + Send>>,
    /// Flush the screen at each newline (a terminal).
    line_flush: bool,
    /// Whether [`FLUSH`] bytes are written as they are (a host protocol of binary data).
    binary: bool,
    /// Read the input on a thread of its own (see [`crate::keyboard`]).
    keyboard_thread: bool,
    /// That thread, once the first input has started it.
    keyboard: Option<Keyboard>,
    /// Put a terminal input in raw mode at the first input.
    raw_terminal: bool,
    /// Raw mode, while it is on.
    raw: Option<crate::terminal::RawMode>,
}

impl std::fmt::Debug for HostIo {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("HostIo")
    }
}

impl HostIo {
    /// Binds to the given streams (tests pass in-memory buffers).
    pub fn new(
        input: Box<dyn Read + Send>,
        screen: Box<dyn Write + Send>,
        error: Box<dyn Write + Send>,
    ) -> HostIo {
        HostIo {
            input,
            screen: BufWriter::with_capacity(1 << 16, screen),
            error: BufWriter::new(error),
            line_flush: false,
            binary: false,
            keyboard_thread: false,
            keyboard: None,
            raw_terminal: false,
            raw: None,
        }
    }

    /// Puts the process's standard input, a terminal, in raw mode at the first keyboard input
    /// (`true`), as KRoC's keyboard does; the input must be standard input.
    pub fn raw_terminal(mut self, on: bool) -> HostIo {
        self.raw_terminal = on;
        self
    }

    /// Raw mode on, if asked for and not yet on.
    fn enter_raw(&mut self) {
        if self.raw_terminal && self.raw.is_none() {
            self.raw = crate::terminal::RawMode::enter();
            // Tried once: a terminal that refuses stays as it is.
            self.raw_terminal = false;
        }
    }

    /// Reads the input on a thread of its own (`true`), so that a process waiting for a key
    /// blocks only itself, or on the node's thread when a process inputs (`false`, which keeps
    /// runs with piped input exactly repeatable). Used only by a node outside a network.
    pub fn keyboard_thread(mut self, on: bool) -> HostIo {
        self.keyboard_thread = on;
        self
    }

    /// The keyboard thread, started now if this is the first input; `None` when the input is
    /// read on the node's thread.
    pub(crate) fn keyboard(&mut self) -> Option<Keyboard> {
        if !self.keyboard_thread {
            return None;
        }
        self.enter_raw();
        let input = &mut self.input;
        let kb = self.keyboard.get_or_insert_with(|| {
            Keyboard::spawn(std::mem::replace(input, Box::new(std::io::empty())))
        });
        Some(kb.clone())
    }

    /// The keyboard thread if it has been started.
    pub(crate) fn started_keyboard(&self) -> Option<&Keyboard> {
        self.keyboard.as_ref()
    }

    /// Flushes the screen (before a keyboard input, so that a prompt shows).
    pub(crate) fn flush_screen(&mut self) -> std::io::Result<()> {
        self.screen.flush()
    }

    /// The same streams for a program that speaks a binary protocol with its host: every byte
    /// sent to `screen` or `error` is written, [`FLUSH`] too.
    pub fn binary(self) -> HostIo {
        HostIo {
            binary: true,
            ..self
        }
    }

    /// Flushes the screen at each newline (`true`) or only at [`FLUSH`], input and the end.
    pub fn flush_lines(mut self, on: bool) -> HostIo {
        self.line_flush = on;
        self
    }

    /// Binds to the process's stdin, stdout and stderr.
    pub fn stdio() -> HostIo {
        HostIo::new(
            Box::new(std::io::stdin()),
            Box::new(std::io::stdout()),
            Box::new(std::io::stderr()),
        )
        .flush_lines(std::io::stdout().is_terminal())
        .keyboard_thread(std::io::stdin().is_terminal())
        .raw_terminal(std::io::stdin().is_terminal())
    }

    /// Writes `bytes` to `stream`; a [`FLUSH`] byte is not written but flushes the stream (as
    /// KRoC's screen process does for the course library's `flush`), unless the host is
    /// [`HostIo::binary`]. Error output is flushed at once.
    pub(crate) fn write(&mut self, stream: HostStream, bytes: &[u8]) -> std::io::Result<()> {
        let w = match stream {
            HostStream::Screen => &mut self.screen,
            HostStream::Error => &mut self.error,
        };
        if self.binary {
            w.write_all(bytes)?;
            if stream == HostStream::Error {
                w.flush()?;
            }
            return Ok(());
        }
        let mut parts = bytes.split(|&b| b == FLUSH).peekable();
        let by_line = self.line_flush && stream == HostStream::Screen;
        while let Some(part) = parts.next() {
            match part.iter().rposition(|&b| b == b'\n') {
                Some(end) if by_line => {
                    w.write_all(&part[..=end])?;
                    w.flush()?;
                    w.write_all(&part[end + 1..])?;
                }
                _ => w.write_all(part)?,
            }
            if parts.peek().is_some() {
                w.flush()?;
            }
        }
        if stream == HostStream::Error {
            w.flush()?;
        }
        Ok(())
    }

    /// Fills `buf` from the input (flushing the screen first); [`END_OF_INPUT`] past the end.
    pub(crate) fn read(&mut self, buf: &mut [u8]) -> std::io::Result<()> {
        self.enter_raw();
        self.screen.flush()?;
        let mut filled = 0;
        while filled < buf.len() {
            match self.input.read(&mut buf[filled..]) {
                Ok(0) => {
                    buf[filled..].fill(END_OF_INPUT);
                    return Ok(());
                }
                Ok(n) => filled += n,
                Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
                Err(e) => return Err(e),
            }
        }
        Ok(())
    }

    /// Flushes both output streams.
    pub(crate) fn flush(&mut self) -> Result<(), crate::RunError> {
        self.screen.flush()?;
        self.error.flush()?;
        Ok(())
    }
}

#[cfg(test)]
mod test {
    use super::*;
    use std::sync::{Arc, Mutex};

    /// A writer whose bytes the test can see while `HostIo` still holds it.
    #[derive(Clone, Default)]
    struct Shared(Arc<Mutex<Vec<u8>>>);

    impl Write for Shared {
        fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
            self.0.lock().unwrap().extend_from_slice(buf);
            Ok(buf.len())
        }
        fn flush(&mut self) -> std::io::Result<()> {
            Ok(())
        }
    }

    fn host(screen: &Shared, by_line: bool) -> HostIo {
        HostIo::new(
            Box::new(std::io::empty()),
            Box::new(screen.clone()),
            Box::new(std::io::sink()),
        )
        .flush_lines(by_line)
    }

    #[test]
    fn a_terminal_screen_shows_each_finished_line() {
        let screen = Shared::default();
        let mut io = host(&screen, true);
        io.write(HostStream::Screen, b"one\ntw").unwrap();
        assert_eq!(*screen.0.lock().unwrap(), b"one\n");
        io.write(HostStream::Screen, b"o\n").unwrap();
        assert_eq!(*screen.0.lock().unwrap(), b"one\ntwo\n");
    }

    #[test]
    fn other_screens_wait_for_flush() {
        let screen = Shared::default();
        let mut io = host(&screen, false);
        io.write(HostStream::Screen, b"one\n").unwrap();
        assert!(screen.0.lock().unwrap().is_empty());
        io.write(HostStream::Screen, &[b'x', FLUSH]).unwrap();
        assert_eq!(*screen.0.lock().unwrap(), b"one\nx");
    }

    #[test]
    fn a_binary_host_gets_flush_bytes_as_they_are() {
        let screen = Shared::default();
        let mut io = host(&screen, false).binary();
        io.write(HostStream::Screen, &[1, FLUSH, 2]).unwrap();
        io.flush().unwrap();
        assert_eq!(*screen.0.lock().unwrap(), [1, FLUSH, 2]);
    }
}
