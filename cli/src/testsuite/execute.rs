//! The one place where running a compiled test program hooks in.
//!
//! `run`, `runtime-error` and `deadlock` tests need the code generator and the runtime. Until they
//! exist, [`run_program`] answers [`Unavailable`] and the harness counts those tests as skipped after
//! checking them with the front end. When `occ run` works, make `run_program` start the `occ` binary
//! itself (`std::env::current_exe()`, so that a crash or hang of the program under test cannot take
//! the harness down) with `run FILE -I DIR...`, feed `stdin`, enforce a time limit, and fill in an
//! [`Execution`]; [`crate::testsuite::judge`] already knows how to compare it.

use std::path::Path;

/// How a program run ended, as the harness needs to see it.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Execution {
    /// Everything the program wrote to its screen channel (stdout).
    pub stdout: String,
    /// Everything written to stderr, where the runtime reports errors and deadlocks.
    pub stderr: String,
    /// The exit status; `None` when the process was killed (signal or time limit).
    pub status: Option<i32>,
}

/// Running programs is not possible yet.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Unavailable;

/// The reason shown for tests that could not be run.
pub const SKIP_REASON: &str = "no code generator yet";

/// How long one test program may run before it is killed.
const TIME_LIMIT: std::time::Duration = std::time::Duration::from_secs(20);

/// Runs the program in `path` with `stdin` as its keyboard input, in a child `occ run` process
/// (so that a crash or hang of the program under test cannot take the harness down), killed after
/// [`TIME_LIMIT`].
pub fn run_program(
    path: &Path,
    include_dirs: &[std::path::PathBuf],
    args: &[String],
    stdin: &str,
) -> Result<Execution, Unavailable> {
    use std::io::{Read, Write};
    use std::process::{Command, Stdio};
    let exe = std::env::current_exe().map_err(|_| Unavailable)?;
    let mut cmd = Command::new(exe);
    cmd.arg("run").arg(path);
    for d in include_dirs {
        cmd.arg("-I").arg(d);
    }
    cmd.args(args);
    let mut child = cmd
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .map_err(|_| Unavailable)?;
    let input = stdin.as_bytes().to_vec();
    let mut child_in = child.stdin.take();
    let feeder = std::thread::spawn(move || {
        if let Some(w) = child_in.as_mut() {
            let _ = w.write_all(&input);
        }
    });
    let mut out_pipe = child.stdout.take();
    let mut err_pipe = child.stderr.take();
    let out_reader = std::thread::spawn(move || {
        let mut s = Vec::new();
        if let Some(r) = out_pipe.as_mut() {
            let _ = r.read_to_end(&mut s);
        }
        s
    });
    let err_reader = std::thread::spawn(move || {
        let mut s = Vec::new();
        if let Some(r) = err_pipe.as_mut() {
            let _ = r.read_to_end(&mut s);
        }
        s
    });
    let start = std::time::Instant::now();
    let status = loop {
        match child.try_wait() {
            Ok(Some(st)) => break st.code(),
            Ok(None) if start.elapsed() > TIME_LIMIT => {
                let _ = child.kill();
                let _ = child.wait();
                break None;
            }
            Ok(None) => std::thread::sleep(std::time::Duration::from_millis(5)),
            Err(_) => break None,
        }
    };
    let _ = feeder.join();
    let stdout = out_reader.join().unwrap_or_default();
    let stderr = err_reader.join().unwrap_or_default();
    Ok(Execution {
        stdout: String::from_utf8_lossy(&stdout).into_owned(),
        stderr: String::from_utf8_lossy(&stderr).into_owned(),
        status,
    })
}
