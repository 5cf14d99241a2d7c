//! The KRoC compiler tests (cgtests) run through `occ run`, each count compared with KRoC's.
//!
//! The tests are GPL and live outside the repository (see `tests/cgtests.md`): in the folder named
//! by `OCC_CGTESTS`, else in `shared/cgtests` beside the repository. That folder's `EXPECTED` gives
//! KRoC's count for each test. `tests/cgtests/known` lists the tests where occ still falls short,
//! with the count occ reaches (or `fail`) and why; every other test must print
//! `All N tests passed` with KRoC's N and exit 0. A test that does better than `known`
//! says also fails, so that the list is kept true.
//!
//! When the folder lacks `EXPECTED`, the test fails and says where it looked: it never passes
//! quietly.

use std::collections::BTreeMap;
use std::io::Read;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::sync::Mutex;
use std::time::{Duration, Instant};

/// A test still running after this long is killed and reported.
const TIME_LIMIT: Duration = Duration::from_secs(240);

/// What one test must do.
#[derive(Debug, Clone, PartialEq, Eq)]
enum Want {
    /// Pass with this count.
    Pass(u32),
    /// Fail (not compile, or not report all checks passed): a known shortfall.
    Fail,
}

/// What one run did.
#[derive(Debug, Clone, PartialEq, Eq)]
enum Got {
    Pass(u32),
    Fail(String),
}

/// The folder `OCC_CGTESTS` names (made absolute: cargo runs the test in `cli/`, so a relative
/// path is taken from there), else `shared/cgtests` beside the repository, where the project's
/// machines keep the suite.
fn cgtests_dir() -> PathBuf {
    match std::env::var_os("OCC_CGTESTS") {
        Some(dir) => std::path::absolute(&dir)
            .unwrap_or_else(|e| panic!("OCC_CGTESTS={}: {e}", Path::new(&dir).display())),
        None => Path::new(env!("CARGO_MANIFEST_DIR")).join("../../shared/cgtests"),
    }
}

/// The repository's `tests/cgtests/`: `known` and the `config.inc` the tests include.
fn support_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../tests/cgtests")
}

/// Reads `name count` lines (`#` comments, blank lines ignored).
fn read_table(path: &Path) -> Vec<(String, String, String)> {
    let text = std::fs::read_to_string(path)
        .unwrap_or_else(|e| panic!("cannot read {}: {e}", path.display()));
    text.lines()
        .map(str::trim)
        .filter(|l| !l.is_empty() && !l.starts_with('#'))
        .map(|l| {
            let mut words = l.splitn(3, char::is_whitespace);
            let name = words.next().unwrap_or_default().to_string();
            let count = words.next().unwrap_or_default().trim().to_string();
            let rest = words.next().unwrap_or_default().trim().to_string();
            (name, count, rest)
        })
        .collect()
}

/// Runs one test and classifies what it printed.
fn run(dir: &Path, name: &str) -> Got {
    let mut child = Command::new(env!("CARGO_BIN_EXE_occ"))
        .arg("run")
        .arg("-I")
        .arg(support_dir())
        .arg(format!("{name}.occ"))
        .current_dir(dir)
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("the occ binary runs");
    let mut stdout = child.stdout.take().expect("piped stdout");
    let mut stderr = child.stderr.take().expect("piped stderr");
    let out_reader = std::thread::spawn(move || {
        let mut s = String::new();
        let _ = stdout.read_to_string(&mut s);
        s
    });
    let err_reader = std::thread::spawn(move || {
        let mut s = String::new();
        let _ = stderr.read_to_string(&mut s);
        s
    });
    let start = Instant::now();
    let status = loop {
        if let Some(status) = child.try_wait().expect("wait for occ") {
            break Some(status);
        }
        if start.elapsed() > TIME_LIMIT {
            let _ = child.kill();
            let _ = child.wait();
            break None;
        }
        std::thread::sleep(Duration::from_millis(50));
    };
    let out = out_reader.join().unwrap_or_default();
    let err = err_reader.join().unwrap_or_default();
    let Some(status) = status else {
        return Got::Fail(format!("killed after {} s", TIME_LIMIT.as_secs()));
    };
    let count = out.lines().find_map(|line| {
        let rest = line.split("^^^ Passed").nth(1)?;
        let rest = rest.split("All ").nth(1)?;
        rest.split_whitespace().next()?.parse::<u32>().ok()
    });
    match (status.success(), count) {
        (true, Some(n)) => Got::Pass(n),
        _ => {
            let first = err
                .lines()
                .chain(out.lines().filter(|l| l.contains("Failed")))
                .find(|l| !l.trim().is_empty())
                .unwrap_or("no output")
                .trim()
                .to_string();
            Got::Fail(format!("{status}: {first}"))
        }
    }
}

#[test]
fn every_cgtest_reaches_its_count() {
    let dir = cgtests_dir();
    let expected_file = dir.join("EXPECTED");
    assert!(
        expected_file.is_file(),
        "the KRoC cgtests are not where this test looks: {} (no EXPECTED file). Set OCC_CGTESTS to \
         the folder that holds them; tests/cgtests.md says how to get them.",
        dir.display()
    );
    let known_file = support_dir().join("known");
    let known: BTreeMap<String, Want> = read_table(&known_file)
        .into_iter()
        .map(|(name, count, _why)| {
            let want = if count == "fail" {
                Want::Fail
            } else {
                Want::Pass(count.parse().unwrap_or_else(|_| {
                    panic!("tests/cgtests/known: `{name}` needs a count or `fail`, not `{count}`")
                }))
            };
            (name, want)
        })
        .collect();
    let kroc: Vec<(String, u32)> = read_table(&expected_file)
        .into_iter()
        .map(|(name, count, _)| {
            let n = count
                .parse()
                .unwrap_or_else(|_| panic!("EXPECTED: bad count for {name}"));
            (name, n)
        })
        .collect();
    for name in known.keys() {
        assert!(
            kroc.iter().any(|(n, _)| n == name),
            "tests/cgtests/known names {name}, which EXPECTED does not list"
        );
    }

    // One worker per core, taking tests from a shared queue.
    let queue = Mutex::new(kroc.clone());
    let results = Mutex::new(BTreeMap::new());
    let threads = std::thread::available_parallelism().map_or(2, |n| n.get());
    std::thread::scope(|s| {
        for _ in 0..threads {
            s.spawn(|| {
                loop {
                    let Some((name, _)) = queue.lock().unwrap().pop() else {
                        break;
                    };
                    let got = run(&dir, &name);
                    results.lock().unwrap().insert(name, got);
                }
            });
        }
    });
    let results = results.into_inner().unwrap();

    let mut table = String::from("test      KRoC   occ    status\n");
    let mut wrong = Vec::new();
    for (name, kroc_count) in &kroc {
        let got = &results[name];
        let want = known.get(name).cloned().unwrap_or(Want::Pass(*kroc_count));
        let ours = match got {
            Got::Pass(n) => n.to_string(),
            Got::Fail(_) => "-".to_string(),
        };
        let status = match got {
            Got::Pass(n) if n == kroc_count => "pass".to_string(),
            Got::Pass(_) => "short".to_string(),
            Got::Fail(why) => format!("fail ({why})"),
        };
        table.push_str(&format!("{name:<9} {kroc_count:>5} {ours:>5}  {status}\n"));
        let as_wanted = match (&want, got) {
            (Want::Pass(w), Got::Pass(n)) => w == n,
            (Want::Fail, Got::Fail(_)) => true,
            _ => false,
        };
        if !as_wanted {
            wrong.push(format!("{name}: wanted {want:?}, got {got:?}"));
        }
    }
    println!("{table}");
    assert!(
        wrong.is_empty(),
        "cgtests differ from tests/cgtests/known (update it when a test improves):\n{}\n\n{table}",
        wrong.join("\n")
    );
}
