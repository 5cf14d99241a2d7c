//! Runtime errors and deadlock reports.

use occ_runtime::abi::{Status, Word, Wptr, join};
use occ_runtime::chan::rt_in;
use occ_runtime::error::rt_error;
use occ_runtime::par::{rt_endp, rt_par_wait, rt_startp};
use occ_runtime::{ChannelName, CodeInfo, ErrorKind, Node, ProgramInfo, RunError, WaitsOn};

use crate::common::*;

/// Halts with the kind and location in locals 0 and 1.
unsafe extern "C" fn failing(ws: Wptr, node: *mut Node) -> Status {
    unsafe { rt_error(node, ws, *l(ws, 0), *l(ws, 1)) }
}

/// Sets the word at local 0's address.
unsafe extern "C" fn marker(ws: Wptr, _node: *mut Node) -> Status {
    unsafe { *(*l(ws, 0) as *mut Word) = 1 };
    Status::DONE
}

#[test]
fn runtime_error_names_file_line_kind_and_proc() {
    let mut program = ProgramInfo::default();
    let loc = program.add_location("arrays.occ", 42);
    program.procs.push(CodeInfo::new("index.it", failing));
    let (mut node, _) = node_with(program, b"", true);
    let mut ran: Word = 0;
    spawn(
        &mut node,
        failing,
        2,
        &[ErrorKind::Subscript as Word, loc as Word],
    );
    spawn(&mut node, marker, 1, &[&mut ran as *mut Word as Word]);
    let err = node.run().expect_err("halts");
    assert_eq!(
        err.to_string(),
        "arrays.occ:42: runtime error: array subscript out of bounds (in PROC index.it)"
    );
    assert_eq!(ran, 0, "the node stops at once: no other process runs");
}

#[test]
fn every_error_kind_has_a_code_and_message() {
    for code in 0..17 {
        let k = ErrorKind::from_code(code).expect("kind");
        assert_eq!(k as Word, code);
        assert!(!k.describe().is_empty());
    }
    // The words the test corpus (tests/lang/run) names kinds by.
    for (k, word) in [
        (ErrorKind::Stop, "stop"),
        (ErrorKind::IfNoBranch, "stop"),
        (ErrorKind::CaseNoMatch, "stop"),
        (ErrorKind::Subscript, "bounds"),
        (ErrorKind::Segment, "bounds"),
        (ErrorKind::Conversion, "conversion"),
        (ErrorKind::Overflow, "overflow"),
        (ErrorKind::DivideByZero, "division"),
        (ErrorKind::Assert, "assert"),
        (ErrorKind::Floating, "floating-point"),
        (ErrorKind::ReplicatorCount, "replicator count"),
        (ErrorKind::AddressRange, "address out of range"),
        (ErrorKind::Memory, "out of memory"),
    ] {
        assert!(k.describe().to_lowercase().contains(word), "{k:?}");
    }
    assert_eq!(ErrorKind::from_code(12), Some(ErrorKind::Stopped));
    assert_eq!(ErrorKind::from_code(13), Some(ErrorKind::Floating));
    assert_eq!(ErrorKind::from_code(14), Some(ErrorKind::ReplicatorCount));
    assert_eq!(ErrorKind::from_code(15), Some(ErrorKind::AddressRange));
    assert_eq!(ErrorKind::from_code(16), Some(ErrorKind::Memory));
    assert_eq!(ErrorKind::from_code(17), None);
    assert_eq!(ErrorKind::from_code(-1), None);
}

#[test]
fn unknown_kind_and_location_still_halt_cleanly() {
    let (mut node, _) = node();
    spawn(&mut node, failing, 2, &[999, 12345]);
    let err = node.run().expect_err("halts");
    assert_eq!(err.to_string(), "runtime error: unknown kind 999");
}

#[test]
fn stop_is_a_runtime_error() {
    let mut program = ProgramInfo::default();
    let loc = program.add_location("stop.occ", 5);
    let (mut node, _) = node_with(program, b"", true);
    spawn(
        &mut node,
        failing,
        2,
        &[ErrorKind::Stop as Word, loc as Word],
    );
    let err = node.run().expect_err("halts");
    assert_eq!(err.to_string(), "stop.occ:5: runtime error: STOP executed");
}

// Deadlock: main declares channels c and d and runs PAR { c ? x ; d ? y }: both readers block
// for ever, main waits on the join.

const M_C: usize = 2; // channel c
const M_D: usize = 3; // channel d
const M_B0: usize = 4 + occ_runtime::abi::slot::HEADER_WORDS;
const M_STRIDE: usize = occ_runtime::abi::slot::HEADER_WORDS + 3;

/// Reader branch: locals 0 join, 1 chan, 2 buffer.
unsafe extern "C" fn reader(ws: Wptr, node: *mut Node) -> Status {
    unsafe {
        if iptr(ws) == 0 {
            set_iptr(ws, 1);
            check!(rt_in(node, ws, *l(ws, 1) as *mut Word, l(ws, 2).cast(), 8));
        }
        rt_endp(node, ws, *l(ws, 0) as *mut Word)
    }
}

unsafe extern "C" fn deadlocking_main(ws: Wptr, node: *mut Node) -> Status {
    unsafe {
        if iptr(ws) == 0 {
            *ws.offset(join::PARENT) = 0;
            *ws.offset(join::COUNT) = 2;
            *l(ws, M_C) = 0;
            *l(ws, M_D) = 0;
            for (i, ch) in [M_C, M_D].into_iter().enumerate() {
                let b = ws.add(M_B0 + i * M_STRIDE);
                *l(b, 0) = ws as Word;
                *l(b, 1) = l(ws, ch) as Word;
                rt_startp(node, ws, b, reader, 0);
            }
            set_iptr(ws, 1);
            check!(rt_par_wait(node, ws, ws));
        }
        Status::DONE
    }
}

#[test]
fn deadlock_reports_every_blocked_process() {
    let mut program = ProgramInfo::default();
    let l_par = program.add_location("dead.occ", 4);
    let l_in = program.add_location("dead.occ", 7);
    let mut m = CodeInfo::new("main", deadlocking_main);
    m.resume_locations = vec![u32::MAX, l_par];
    m.channels = vec![
        ChannelName {
            offset: M_C as i64,
            count: 1,
            name: "c".into(),
        },
        ChannelName {
            offset: M_D as i64,
            count: 1,
            name: "d".into(),
        },
    ];
    program.procs.push(m);
    let mut r = CodeInfo::new("main", reader);
    r.resume_locations = vec![u32::MAX, l_in];
    program.procs.push(r);
    let (mut node, _) = node_with(program, b"", true);
    spawn(&mut node, deadlocking_main, M_B0 + 2 * M_STRIDE, &[]);
    let err = node.run().expect_err("deadlock");
    let RunError::Deadlock(report) = &err else {
        panic!("{err}")
    };
    let mut waits: Vec<String> = report
        .blocked
        .iter()
        .map(|b| b.waits_on.to_string())
        .collect();
    waits.sort();
    assert_eq!(
        waits,
        vec!["PAR join", "input from channel c", "input from channel d"]
    );
    assert!(
        report
            .blocked
            .iter()
            .all(|b| b.proc_name.as_deref() == Some("main"))
    );
    let lines: Vec<u32> = report
        .blocked
        .iter()
        .filter_map(|b| b.location.as_ref().map(|l| l.line))
        .collect();
    assert_eq!(lines.iter().filter(|&&l| l == 7).count(), 2);
    assert_eq!(lines.iter().filter(|&&l| l == 4).count(), 1);
    let text = err.to_string();
    assert!(
        text.starts_with("deadlock: 3 process(es) blocked"),
        "{text}"
    );
    assert!(
        text.contains("dead.occ:7: PROC main blocked on input from channel d"),
        "{text}"
    );
    assert!(
        report
            .blocked
            .iter()
            .any(|b| b.waits_on == WaitsOn::ParJoin)
    );
}

#[test]
fn stopped_process_shows_in_the_deadlock_report() {
    unsafe extern "C" fn stopper(ws: Wptr, node: *mut Node) -> Status {
        unsafe {
            set_iptr(ws, 1);
            occ_runtime::par::rt_stopp(node, ws)
        }
    }
    let (mut node, _) = node();
    spawn(&mut node, stopper, 1, &[]);
    let err = node.run().expect_err("never ends");
    assert_eq!(
        err.to_string(),
        "deadlock: 1 process(es) blocked\n  ?: PROC ? blocked on stopped"
    );
}
