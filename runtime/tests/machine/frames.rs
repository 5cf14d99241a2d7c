//! Blocking PROC calls through the frame chain: the innermost frame is resumed directly, and a
//! finished callee returns to its caller's after-call index, so resuming costs O(1).

use occ_runtime::abi::{ProcFn, Status, Word, Wptr, slot};
use occ_runtime::chan::rt_in;
use occ_runtime::{CodeInfo, Node, ProgramInfo, RunError, WaitsOn};

use crate::common::*;

// Caller locals: 0 chan, 1 n, 2 entry counter address, 3 result, 4 spare; callee frame above.
const CALLEE: usize = 5 + slot::HEADER_WORDS;
const FRAME_WORDS: usize = CALLEE + 8 + slot::HEADER_WORDS + 8;

/// Prepares callee frame `c` of caller `ws` (protocol step 1) and copies locals 0..3.
unsafe fn prepare(ws: Wptr, c: Wptr, code: ProcFn) {
    unsafe {
        *c.offset(slot::CODE) = code as usize as Word;
        *c.offset(slot::IPTR) = 0;
        *c.offset(slot::CALLER) = ws as Word;
        *c.offset(slot::ROOT) = *ws.offset(slot::ROOT);
        for i in 0..3 {
            *l(c, i) = *l(ws, i);
        }
    }
}

/// Calls `code` in a callee frame, then stores the callee's local 3 into its own local 3.
unsafe fn caller(ws: Wptr, node: *mut Node, code: ProcFn) -> Status {
    unsafe {
        *(*l(ws, 2) as *mut Word) += 1; // count entries into this function
        let c = ws.add(CALLEE);
        if iptr(ws) == 0 {
            prepare(ws, c, code);
            set_iptr(ws, 1); // after-call index
            check!(code(c, node));
        }
        *l(ws, 3) = *l(c, 3);
        Status::DONE
    }
}

/// Sums n inputs from chan into local 3.
unsafe extern "C" fn inner(ws: Wptr, node: *mut Node) -> Status {
    unsafe {
        loop {
            match iptr(ws) {
                0 => {
                    *l(ws, 3) = 0;
                    *l(ws, 4) = 0;
                    set_iptr(ws, 1);
                }
                1 => {
                    if *l(ws, 4) == *l(ws, 1) {
                        return Status::DONE;
                    }
                    set_iptr(ws, 2);
                    check!(rt_in(node, ws, *l(ws, 0) as *mut Word, l(ws, 5).cast(), 8));
                }
                _ => {
                    *l(ws, 3) += *l(ws, 5);
                    *l(ws, 4) += 1;
                    set_iptr(ws, 1);
                }
            }
        }
    }
}

unsafe extern "C" fn middle(ws: Wptr, node: *mut Node) -> Status {
    unsafe { caller(ws, node, inner) }
}

unsafe extern "C" fn outer(ws: Wptr, node: *mut Node) -> Status {
    unsafe { caller(ws, node, middle) }
}

#[test]
fn blocking_call_resumes_innermost_frame_in_constant_time() {
    let (mut node, _) = node();
    let mut c = channel();
    let chan = &mut *c as *mut Word as Word;
    let n = 100;
    let mut entries: Word = 0;
    let ws = spawn(
        &mut node,
        outer,
        FRAME_WORDS + CALLEE,
        &[chan, n, &mut entries as *mut Word as Word],
    );
    spawn(&mut node, crate::chan::sender, 4, &[chan, n]);
    node.run().unwrap();
    let expected: Word = (0..n).map(|i| i * 10).sum();
    unsafe { assert_eq!(*l(ws, 3), expected) };
    // outer and middle are each entered twice (entry, after-call), although inner blocked 100
    // times: wake-ups went straight to the innermost frame.
    assert_eq!(entries, 4);
}

unsafe extern "C" fn faulty(ws: Wptr, node: *mut Node) -> Status {
    unsafe {
        occ_runtime::error::rt_error(
            node,
            ws,
            occ_runtime::ErrorKind::Overflow as Word,
            *l(ws, 1),
        )
    }
}

unsafe extern "C" fn calls_faulty(ws: Wptr, node: *mut Node) -> Status {
    unsafe { caller(ws, node, faulty) }
}

#[test]
fn runtime_error_in_a_callee_halts_with_its_proc_and_line() {
    let mut program = ProgramInfo::default();
    let loc = program.add_location("calls.occ", 17);
    program.procs.push(CodeInfo::new("faulty", faulty));
    program.procs.push(CodeInfo::new("main", calls_faulty));
    let (mut node, _) = node_with(program, b"", true);
    let mut entries: Word = 0;
    spawn(
        &mut node,
        calls_faulty,
        FRAME_WORDS + CALLEE,
        &[0, loc as Word, &mut entries as *mut Word as Word],
    );
    let err = node.run().expect_err("halts");
    let RunError::Halted(h) = &err else {
        panic!("{err}")
    };
    assert_eq!(h.kind, Some(occ_runtime::ErrorKind::Overflow));
    assert_eq!(h.proc_name.as_deref(), Some("faulty"));
    assert_eq!(
        err.to_string(),
        "calls.occ:17: runtime error: arithmetic overflow (in PROC faulty)"
    );
    assert_eq!(entries, 1, "the caller did not continue after the error");
}

#[test]
fn deadlock_inside_a_callee_names_the_callee() {
    let mut program = ProgramInfo::default();
    let l_main = program.add_location("deep.occ", 3);
    let l_in = program.add_location("deep.occ", 9);
    let mut p = CodeInfo::new("inner", inner);
    p.resume_locations = vec![u32::MAX, u32::MAX, l_in];
    program.procs.push(p);
    let mut p = CodeInfo::new("outer", middle);
    p.resume_locations = vec![u32::MAX, l_main];
    p.channels.push(occ_runtime::ChannelName {
        offset: 4,
        count: 1,
        name: "never".into(),
    });
    program.procs.push(p);
    let (mut node, _) = node_with(program, b"", true);
    let mut entries: Word = 0;
    let ws = node.alloc_workspace(FRAME_WORDS + CALLEE).unwrap();
    unsafe {
        *l(ws, 0) = l(ws, 4) as Word; // the channel lives in outer's frame, local 4
        *l(ws, 1) = 1;
        *l(ws, 2) = &mut entries as *mut Word as Word;
        *l(ws, 4) = 0;
        node.spawn(ws, middle);
    }
    let err = node.run().expect_err("nobody outputs");
    let RunError::Deadlock(d) = &err else {
        panic!("{err}")
    };
    assert_eq!(d.blocked.len(), 1);
    let b = &d.blocked[0];
    assert_eq!(b.proc_name.as_deref(), Some("inner"));
    assert_eq!(b.location.as_ref().map(|l| l.line), Some(9));
    assert_eq!(b.waits_on, WaitsOn::Input(Some("never".into())));
    assert_eq!(
        err.to_string(),
        "deadlock: 1 process(es) blocked\n  deep.occ:9: PROC inner blocked on input from channel never"
    );
}
