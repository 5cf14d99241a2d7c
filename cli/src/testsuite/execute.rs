//! The one place where running a compiled test program hooks in: `run`, `runtime-error` and
//! `deadlock` tests start `occ run FILE -I DIR...` as a child process (so that a crash or hang of
//! the program under test cannot take the harness down), feed it `stdin`, enforce a time limit,
//! and hand the [`Execution`] to [`crate::testsuite::judge`]. A run that cannot be started is
//! an error of the test, never a skip.

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

/// How long one test program may run before it is killed.
const TIME_LIMIT: std::time::Duration = std::time::Duration::from_secs(20);

/// Runs the program in `path` with `stdin` as its keyboard input, in a child `runner run`
/// process killed after [`TIME_LIMIT`].
///
/// Fails, saying why, when the child cannot be started.
pub fn run_program(
    runner: &Path,
    path: &Path,
    include_dirs: &[std::path::PathBuf],
    args: &[String],
    stdin: &str,
) -> Result<Execution, String> {
    use std::io::{Read, Write};
    use std::process::{Command, Stdio};
    let mut cmd = Command::new(runner);
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
        .map_err(|e| format!("cannot start `{} run`: {e}", runner.display()))?;
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
