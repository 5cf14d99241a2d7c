//! Host channels: screen output and keyboard input through external endpoints.

use occ_runtime::Node;
use occ_runtime::abi::{Status, Word, Wptr};
use occ_runtime::chan::{rt_in, rt_out};

use crate::common::*;

/// Echoes keyboard bytes to the screen, upper-cased, until end of input (255).
/// Locals: 0 keyboard, 1 screen, 2 byte buffer.
unsafe extern "C" fn echo(ws: Wptr, node: *mut Node) -> Status {
    unsafe {
        loop {
            match iptr(ws) {
                0 => {
                    *l(ws, 2) = 0;
                    set_iptr(ws, 1);
                    check!(rt_in(node, ws, *l(ws, 0) as *mut Word, l(ws, 2).cast(), 1));
                }
                1 => {
                    let b = *l(ws, 2) as u8;
                    if b == occ_runtime::host::END_OF_INPUT {
                        return Status::DONE;
                    }
                    *l(ws, 2) = b.to_ascii_uppercase() as Word;
                    set_iptr(ws, 0);
                    check!(rt_out(node, ws, *l(ws, 1) as *mut Word, l(ws, 2).cast(), 1));
                }
                _ => unreachable!(),
            }
        }
    }
}

#[test]
fn keyboard_to_screen() {
    let (mut node, screen) = node_with(Default::default(), b"hello, occam\n", true);
    let [kb, scr, _err] = node.host_channels();
    spawn(&mut node, echo, 3, &[kb as Word, scr as Word]);
    node.run().unwrap();
    assert_eq!(screen.text(), "HELLO, OCCAM\n");
    assert_eq!(node.stats().communications, 2 * 13 + 1);
}
