//! Host channels: screen output and keyboard input through endpoints.

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

/// Writes "partial" to the screen, then halts with a STOP.
unsafe extern "C" fn write_then_stop(ws: Wptr, node: *mut Node) -> Status {
    unsafe {
        if iptr(ws) == 0 {
            let text = b"partial";
            std::ptr::copy_nonoverlapping(text.as_ptr(), l(ws, 1).cast::<u8>(), text.len());
            set_iptr(ws, 1);
            check!(rt_out(node, ws, *l(ws, 0) as *mut Word, l(ws, 1).cast(), 7));
        }
        occ_runtime::error::rt_error(node, ws, occ_runtime::ErrorKind::Stop as Word, -1)
    }
}

#[test]
fn screen_output_is_flushed_when_the_node_halts() {
    let (mut node, screen) = node();
    let [_, scr, _] = node.host_channels();
    spawn(&mut node, write_then_stop, 3, &[scr as Word]);
    assert!(node.run().is_err());
    assert_eq!(screen.text(), "partial");
}

/// PRI ALT { keyboard ? b; SKIP }: the keyboard is always ready (input may block the node).
unsafe extern "C" fn alt_on_keyboard(ws: Wptr, node: *mut Node) -> Status {
    use occ_runtime::alt::*;
    unsafe {
        if iptr(ws) == 0 {
            let kb = *l(ws, 0) as *mut Word;
            rt_alt(node, ws);
            rt_enbc(node, ws, 1, kb);
            rt_enbs(node, ws, 1);
            set_iptr(ws, 1);
            check!(rt_altwt(node, ws));
        }
        if iptr(ws) == 1 {
            let kb = *l(ws, 0) as *mut Word;
            rt_disc(node, ws, 1, kb, 0);
            rt_diss(node, ws, 1, 1);
            *l(ws, 2) = rt_altend(node, ws);
            set_iptr(ws, 2);
            if *l(ws, 2) == 0 {
                check!(rt_in(node, ws, kb, l(ws, 1).cast(), 1));
            }
        }
        Status::DONE
    }
}

#[test]
fn alt_on_the_keyboard() {
    let (mut node, _) = node_with(Default::default(), b"x", true);
    let [kb, _, _] = node.host_channels();
    let ws = spawn(&mut node, alt_on_keyboard, 3, &[kb as Word, 0]);
    node.run().unwrap();
    unsafe {
        assert_eq!(*l(ws, 2), 0, "keyboard guard selected");
        assert_eq!(*l(ws, 1), b'x' as Word);
    }
}

/// Outputs the bytes of local 1.. (count in local 2) one at a time on the screen (local 0).
unsafe extern "C" fn put_bytes(ws: Wptr, node: *mut Node) -> Status {
    unsafe {
        loop {
            match iptr(ws) {
                0 => {
                    *l(ws, 3) = 0;
                    set_iptr(ws, 1);
                }
                _ => {
                    if *l(ws, 3) == *l(ws, 2) {
                        return Status::DONE;
                    }
                    let p = (*l(ws, 1) as *const u8).add(*l(ws, 3) as usize);
                    *l(ws, 4) = *p as Word;
                    *l(ws, 3) += 1;
                    set_iptr(ws, 1);
                    check!(rt_out(node, ws, *l(ws, 0) as *mut Word, l(ws, 4).cast(), 1));
                }
            }
        }
    }
}

#[test]
fn flush_byte_flushes_instead_of_printing() {
    let (mut node, screen) = node();
    let [_, scr, _] = node.host_channels();
    let text = [b'a', b'b', occ_runtime::host::FLUSH, b'c'];
    spawn(
        &mut node,
        put_bytes,
        5,
        &[scr as Word, text.as_ptr() as Word, 4],
    );
    node.run().unwrap();
    assert_eq!(screen.text(), "abc");
}
