//! Networks through `occ run`: the same output on one thread and on two, runs that repeat
//! exactly on one thread, memory budgets, and settings that are refused with a reason.

use std::path::PathBuf;
use std::process::{Command, Output};

fn corpus(name: &str) -> PathBuf {
    PathBuf::from(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../tests/lang/network"
    ))
    .join(name)
}

fn occ_run(file: &std::path::Path, args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_occ"))
        .arg("run")
        .arg(file)
        .args(args)
        .output()
        .expect("the occ binary runs")
}

fn text(b: &[u8]) -> String {
    String::from_utf8_lossy(b).into_owned()
}

/// The `-- args:` words of a test file (its topology, if any).
fn file_args(file: &std::path::Path) -> Vec<String> {
    let source = std::fs::read_to_string(file).expect("test file readable");
    source
        .lines()
        .filter_map(|l| l.trim().strip_prefix("-- args:"))
        .flat_map(|a| a.split_whitespace().map(str::to_string))
        .collect()
}

/// Every network program that runs to completion prints the same on one thread as on two.
#[test]
fn one_thread_and_two_print_the_same() {
    for name in [
        "token_ring.occ",
        "tree_broadcast_sum.occ",
        "link_multiplexer.occ",
        "pipeline_sort.occ",
        "alt_links_timeout.occ",
        "deadlock_two_nodes.occ",
    ] {
        let file = corpus(name);
        let args = file_args(&file);
        let mut outs = Vec::new();
        for threads in ["1", "2"] {
            let mut a: Vec<&str> = args.iter().map(String::as_str).collect();
            a.extend(["--threads", threads]);
            let o = occ_run(&file, &a);
            outs.push((o.status.code(), text(&o.stdout), text(&o.stderr)));
        }
        assert_eq!(outs[0].0, outs[1].0, "{name}: exit status");
        assert_eq!(outs[0].1, outs[1].1, "{name}: stdout");
        assert!(
            !outs[0].1.is_empty() || name.starts_with("deadlock"),
            "{name} printed nothing"
        );
        // Deadlock reports list the same nodes and processes whatever the threads.
        assert_eq!(outs[0].2, outs[1].2, "{name}: stderr");
    }
}

/// On one thread a run repeats exactly: the same output and the same per-node counters.
#[test]
fn one_thread_repeats_exactly() {
    let file = corpus("tree_broadcast_sum.occ");
    let counters = |o: &Output| -> Vec<String> {
        // Node rows of --stats, less the busy column (time, which no run repeats).
        text(&o.stderr)
            .lines()
            .filter(|l| {
                !l.contains(" link ")
                    && l.strip_prefix("node ")
                        .is_some_and(|r| r.starts_with(|c: char| c.is_ascii_digit()))
            })
            .map(|l| {
                let f: Vec<&str> = l.split_whitespace().collect();
                format!("{} {} {} {} {} {}", f[0], f[1], f[2], f[3], f[4], f[6])
            })
            .collect()
    };
    let args = ["--topology", "tree3:13", "--threads", "1", "--stats"];
    let a = occ_run(&file, &args);
    let b = occ_run(&file, &args);
    assert!(a.status.success(), "{}", text(&a.stderr));
    assert_eq!(text(&a.stdout), text(&b.stdout));
    let (ca, cb) = (counters(&a), counters(&b));
    assert_eq!(ca.len(), 13, "one row per node:\n{}", text(&a.stderr));
    assert_eq!(ca, cb);
}

/// A busy low-priority loop on one node does not keep the other nodes of its thread from
/// running: the pool hands the thread on after a few timeslices.
#[test]
fn a_busy_node_gives_way_on_one_thread() {
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("net");
    std::fs::create_dir_all(&dir).expect("temp dir");
    let file = dir.join("busy.occ");
    std::fs::write(
        &file,
        "#INCLUDE \"course.module\"\n\
         PROC main (CHAN BYTE keyboard?, screen!, error!)\n  CHAN INT c:\n  PLACED PAR\n    \
         PROCESSOR 0\n      INT x:\n      SEQ\n        c ? x\n        out.int (x, 0, screen!)\n        \
         screen ! '*n'\n    PROCESSOR 1\n      INT n:\n      SEQ\n        n := 0\n        \
         WHILE n < 3000000\n          n := n + 1\n        c ! n\n:\n",
    )
    .expect("write test program");
    let o = occ_run(&file, &["--threads", "1"]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    assert_eq!(text(&o.stdout), "3000000\n");
}

/// Writes the program of the memory tests: PROCESSOR 7 declares and fills a 400,000-byte
/// table, PROCESSOR 0 does nothing; returns its path.
fn table_on_processor_7(name: &str) -> PathBuf {
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("net-{name}"));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let file = dir.join("table.occ");
    std::fs::write(
        &file,
        "PROC main (CHAN BYTE keyboard?, screen!, error!)\n  PLACED PAR\n    PROCESSOR 0\n      \
         SKIP\n    PROCESSOR 7\n      [100000]INT table:\n      SEQ i = 0 FOR 100000\n        \
         table[i] := i\n:\n",
    )
    .expect("write test program");
    file
}

/// A node whose program needs more memory than `--node-memory` gives it is a runtime error
/// naming the node.
#[test]
fn a_node_over_its_memory_budget_is_named() {
    let file = table_on_processor_7("mem");
    let ok = occ_run(&file, &[]);
    assert!(
        ok.status.success(),
        "fits the default: {}",
        text(&ok.stderr)
    );
    let o = occ_run(&file, &["--node-memory", "64K"]);
    let err = text(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(
        err.contains("PROCESSOR") && err.contains("out of memory"),
        "{err}"
    );
    assert!(err.contains("65536"), "names the budget: {err}");
}

/// A large array is taken from a node's memory when its declaration runs: the node that never
/// declares it takes none of it, though every node runs the same program with the same frame.
#[test]
fn a_node_takes_only_the_large_arrays_it_declares() {
    let o = occ_run(&table_on_processor_7("vec"), &["--stats"]);
    let out = text(&o.stdout) + &text(&o.stderr);
    assert!(o.status.success(), "{out}");
    let peak = |node: &str| -> u64 {
        out.lines()
            .find(|l| l.starts_with(node))
            .and_then(|l| l.split_whitespace().last())
            .and_then(|w| w.parse().ok())
            .unwrap_or_else(|| panic!("no peak for {node}: {out}"))
    };
    assert!(peak("PROCESSOR 0") < 4096, "{out}");
    assert!(peak("PROCESSOR 7") >= 400_000, "{out}");
}

/// Settings that cannot work are refused with a reason naming the setting.
#[test]
fn bad_settings_are_refused() {
    let node_program = corpus("tree_broadcast_sum.occ");
    let configured = corpus("token_ring.occ");
    for (file, args, why) in [
        (
            &node_program,
            vec!["--topology", "hypercube:5"],
            "a transputer has 4",
        ),
        (&node_program, vec!["--nodes", "0"], "at least one node"),
        (&node_program, vec![], "--topology"),
        (
            &node_program,
            vec!["--topology", "tree3:13", "--threads", "0"],
            "--threads",
        ),
        (
            &configured,
            vec!["--nodes", "4"],
            "configures its own network",
        ),
        (
            &node_program,
            vec!["--topology", "tree3:4", "--node-memory", "lots"],
            "byte count",
        ),
    ] {
        let o = occ_run(file, &args);
        let err = text(&o.stderr);
        assert_ne!(o.status.code(), Some(0), "{args:?} ran");
        assert!(err.contains(why), "{args:?}: {err}");
    }
}

/// Only what a `PLACED PAR`'s branches call is compiled: `--stats` counts the course library's
/// PROCs left out, and the output is the one of `--all-routines`, which compiles them all.
#[test]
fn stats_count_the_routines_nothing_calls() {
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("net-lean");
    std::fs::create_dir_all(&dir).expect("temp dir");
    let file = dir.join("lean.occ");
    std::fs::write(
        &file,
        "#INCLUDE \"course.module\"\n\
         PROC unused (CHAN INT c!)\n  c ! 1\n:\n\
         PROC produce (CHAN INT c!)\n  c ! 42\n:\n\
         PROC main (CHAN BYTE keyboard?, screen!, error!)\n  CHAN INT c:\n  PLACED PAR\n    \
         PROCESSOR 0\n      INT x:\n      SEQ\n        c ? x\n        out.int (x, 0, screen!)\n        \
         screen ! '*n'\n    PROCESSOR 1\n      produce (c!)\n:\n",
    )
    .expect("write test program");
    let lean = occ_run(&file, &["--stats", "--threads", "1"]);
    let all = occ_run(&file, &["--stats", "--threads", "1", "--all-routines"]);
    assert!(lean.status.success(), "{}", text(&lean.stderr));
    assert!(all.status.success(), "{}", text(&all.stderr));
    assert_eq!(text(&lean.stdout), "42\n");
    assert_eq!(text(&all.stdout), text(&lean.stdout));
    let line = text(&lean.stderr)
        .lines()
        .find(|l| l.starts_with("left out: "))
        .map(str::to_string)
        .unwrap_or_else(|| panic!("no left-out line:\n{}", text(&lean.stderr)));
    assert!(
        line.contains(" PROCs and FUNCTIONs")
            && line.ends_with(" not compiled: nothing calls them"),
        "{line}"
    );
    assert!(!text(&all.stderr).contains("left out: "));
    let _ = std::fs::remove_dir_all(&dir);
}
