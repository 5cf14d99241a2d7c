//! The keyboard read on a thread of its own (as for a terminal): a process waiting for a key
//! blocks only itself. The input here is slow on purpose: its first byte comes 300 ms late.

mod common;

use std::io::Read;
use std::time::Duration;

use common::{Buf, compile};
use occ_runtime::{HostIo, NodeConfig};

/// Input that waits `delay` before its first read returns, then yields `text`.
struct Slow {
    delay: Option<Duration>,
    text: std::io::Cursor<Vec<u8>>,
}

impl Read for Slow {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        if let Some(d) = self.delay.take() {
            std::thread::sleep(d);
        }
        self.text.read(buf)
    }
}

/// Runs `src` with `text` arriving 300 ms late on the keyboard, read on its own thread when
/// `threaded`; returns what the screen got.
fn run_slow(src: &str, text: &str, threaded: bool) -> String {
    let c = compile(src);
    let out = Buf::default();
    let input = Slow {
        delay: Some(Duration::from_millis(300)),
        text: std::io::Cursor::new(text.as_bytes().to_vec()),
    };
    let host = HostIo::new(
        Box::new(input),
        Box::new(out.clone()),
        Box::new(std::io::sink()),
    )
    .keyboard_thread(threaded);
    let (result, _) = c.run(NodeConfig::default(), host);
    let stdout = String::from_utf8_lossy(&out.0.lock().expect("buffer")).into_owned();
    if let Err(e) = result {
        panic!("run failed: {e}\nstdout so far: {stdout}");
    }
    stdout
}

/// One branch waits for a key while the other waits 1 ms on a timer and says whether it woke
/// on time (within 100 ms).
const WAIT_BESIDE_A_TIMER: &str = r#"#INCLUDE "course.module"
PROC main (CHAN BYTE keyboard?, screen!, error!)
  CHAN BYTE c:
  PAR
    BYTE ch:
    SEQ
      keyboard ? ch
      c ! ch
    TIMER tim:
    INT t, now:
    BYTE ch:
    SEQ
      tim ? t
      tim ? AFTER t PLUS 1000
      tim ? now
      IF
        (now MINUS t) < 100000
          out.string ("on time ", 0, screen!)
        TRUE
          out.string ("late ", 0, screen!)
      c ? ch
      screen ! ch
      screen ! '*n'
:
"#;

#[test]
fn a_process_waiting_for_a_key_blocks_only_itself() {
    assert_eq!(run_slow(WAIT_BESIDE_A_TIMER, "x", true), "on time x\n");
}

/// An ALT between the keyboard and a 50 ms timeout, twice: the first times out (the key is
/// 300 ms late), the second, waiting 1 s, gets the key.
const ALT_WITH_TIMEOUT: &str = r#"#INCLUDE "course.module"
PROC main (CHAN BYTE keyboard?, screen!, error!)
  TIMER tim:
  INT t:
  SEQ
    SEQ i = 0 FOR 2
      SEQ
        tim ? t
        ALT
          BYTE ch:
          keyboard ? ch
            SEQ
              out.string ("key ", 0, screen!)
              screen ! ch
          tim ? AFTER t PLUS (50000 + (i * 1000000))
            out.string ("timeout", 0, screen!)
        screen ! '*n'
:
"#;

#[test]
fn an_alt_on_the_keyboard_can_time_out() {
    assert_eq!(run_slow(ALT_WITH_TIMEOUT, "k", true), "timeout\nkey k\n");
}

#[test]
fn read_on_the_node_thread_the_keyboard_guard_is_always_ready() {
    // The contrast that shows the test above can fail: without the thread an ALT takes the
    // keyboard at once and waits for the key (then for end of input, byte 255).
    let out = run_slow(ALT_WITH_TIMEOUT, "k", false);
    assert!(out.starts_with("key k\nkey "), "{out:?}");
}

#[test]
fn the_keyboard_delivers_end_of_input_to_a_waiting_process() {
    let src = r#"#INCLUDE "course.module"
PROC main (CHAN BYTE keyboard?, screen!, error!)
  BYTE a, b:
  SEQ
    keyboard ? a
    keyboard ? b
    out.int (INT a, 0, screen!)
    screen ! ' '
    out.int (INT b, 0, screen!)
    screen ! '*n'
:
"#;
    assert_eq!(run_slow(src, "A", true), "65 255\n");
}
