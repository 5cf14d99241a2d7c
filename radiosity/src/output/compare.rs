//! `occ radiosity compare RUN...`: the convergence records of several runs (each run's
//! `convergence.csv`) overlaid in one plot and one table, so that settings can be chosen by the
//! error they buy per second.
//!
//! A run's error is its RMS relative error against the reference it was run with
//! (`--reference`, `--reference-mc`); when some run has none, every run is compared by its
//! unshot-power fraction instead (the plot's title and the table say which).

use super::OutputError;
use super::plot::{Curve, draw_panels};

/// One row of a run's record: the columns `compare` reads.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Row {
    /// Seconds since the solve started.
    pub seconds: f64,
    /// Shots so far.
    pub shots: u64,
    /// Unshot power / emitted.
    pub unshot_fraction: f64,
    /// RMS relative error against the run's reference, if it had one.
    pub rms_error: Option<f64>,
    /// Largest relative error against the run's reference, if it had one.
    pub max_error: Option<f64>,
}

/// One run: its name (its folder) and its rows.
#[derive(Clone, Debug, PartialEq)]
pub struct Run {
    /// Name shown in the legend and the table.
    pub name: String,
    /// Rows in time order.
    pub rows: Vec<Row>,
}

/// What the runs are compared by.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Measure {
    /// RMS relative error against each run's reference.
    RmsError,
    /// Unshot power / emitted (some run had no reference).
    Unshot,
}

impl Measure {
    /// The measure every run has.
    pub fn of(runs: &[Run]) -> Measure {
        let all = runs
            .iter()
            .all(|r| !r.rows.is_empty() && r.rows.iter().all(|x| x.rms_error.is_some()));
        if all {
            Measure::RmsError
        } else {
            Measure::Unshot
        }
    }

    fn name(self) -> &'static str {
        match self {
            Measure::RmsError => "RMS relative error",
            Measure::Unshot => "unshot power fraction",
        }
    }

    fn value(self, row: &Row) -> f64 {
        match self {
            Measure::RmsError => row.rms_error.unwrap_or(f64::NAN),
            Measure::Unshot => row.unshot_fraction,
        }
    }
}

/// Reads a `convergence.csv` (`file` names it in errors) by its header: `seconds`, `shots`,
/// `unshot_fraction`, and `rms_error` and `max_error` when present (empty cells: no reference).
pub fn parse_csv(file: &str, text: &str) -> Result<Vec<Row>, OutputError> {
    let err = |line: usize, message: String| OutputError::Convergence {
        file: file.into(),
        line,
        message,
    };
    let mut lines = text.lines().enumerate();
    let header: Vec<&str> = lines
        .next()
        .ok_or_else(|| err(1, "empty file".into()))?
        .1
        .split(',')
        .collect();
    let column = |name: &str| header.iter().position(|h| *h == name);
    let need = |name: &str| {
        column(name).ok_or_else(|| err(1, format!("no `{name}` column in the header")))
    };
    let (seconds, shots, unshot) = (need("seconds")?, need("shots")?, need("unshot_fraction")?);
    let (rms, max) = (column("rms_error"), column("max_error"));
    let mut rows = Vec::new();
    for (i, line) in lines.filter(|(_, l)| !l.trim().is_empty()) {
        let cells: Vec<&str> = line.split(',').collect();
        let number = |c: usize| -> Result<f64, OutputError> {
            let cell = cells.get(c).copied().unwrap_or("");
            cell.trim().parse::<f64>().map_err(|_| {
                err(
                    i + 1,
                    format!("`{cell}` in column {} is not a number", header[c]),
                )
            })
        };
        let optional = |c: Option<usize>| -> Result<Option<f64>, OutputError> {
            match c {
                Some(c) if !cells.get(c).is_none_or(|x| x.trim().is_empty()) => number(c).map(Some),
                _ => Ok(None),
            }
        };
        let shots_value = number(shots)?;
        if shots_value < 0.0 || shots_value.fract() != 0.0 {
            return Err(err(i + 1, format!("`{shots_value}` is not a shot count")));
        }
        rows.push(Row {
            seconds: number(seconds)?,
            shots: shots_value as u64,
            unshot_fraction: number(unshot)?,
            rms_error: optional(rms)?,
            max_error: optional(max)?,
        });
    }
    Ok(rows)
}

/// The first time a run's measure is at most `target`, if it gets there.
fn time_to(run: &Run, measure: Measure, target: f64) -> Option<f64> {
    run.rows
        .iter()
        .find(|r| measure.value(r) <= target)
        .map(|r| r.seconds)
}

/// The comparison table (Markdown): per run, the error reached, the largest error, the time and
/// shots it took, and the first times the measure reached 10% and 1%.
pub fn table(runs: &[Run]) -> String {
    let measure = Measure::of(runs);
    let mut s = format!(
        "| run | {} reached | largest error | seconds | shots | seconds to 10% | seconds to 1% |\n\
         | --- | ---: | ---: | ---: | ---: | ---: | ---: |\n",
        measure.name()
    );
    let opt = |x: Option<f64>, f: &dyn Fn(f64) -> String| x.map_or("-".to_string(), f);
    for run in runs {
        let last = run.rows.last();
        let pct = |x: f64| format!("{:.3}%", 100.0 * x);
        let secs = |x: f64| format!("{x:.3}");
        s += &format!(
            "| {} | {} | {} | {} | {} | {} | {} |\n",
            run.name,
            opt(last.map(|r| measure.value(r)), &pct),
            opt(last.and_then(|r| r.max_error), &pct),
            opt(last.map(|r| r.seconds), &secs),
            last.map_or("-".to_string(), |r| r.shots.to_string()),
            opt(time_to(run, measure, 0.1), &secs),
            opt(time_to(run, measure, 0.01), &secs),
        );
    }
    s
}

/// The comparison plot: each run's measure against seconds (left) and shots (right), log-log.
pub fn compare_png(runs: &[Run], labels: bool) -> Result<Vec<u8>, OutputError> {
    let measure = Measure::of(runs);
    let curves = |x: fn(&Row) -> f64| -> Vec<Curve> {
        runs.iter()
            .map(|run| Curve {
                label: run.name.clone(),
                points: run.rows.iter().map(|r| (x(r), measure.value(r))).collect(),
            })
            .collect()
    };
    let panels = [
        ("seconds", curves(|r| r.seconds)),
        ("shots", curves(|r| r.shots as f64)),
    ];
    draw_panels(&panels, &format!("{} against", measure.name()), labels)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::convergence::Errors;
    use crate::output::plot::convergence_csv;
    use crate::solver::ConvergencePoint;
    use glam::DVec3;

    fn record(errors: bool) -> Vec<ConvergencePoint> {
        (1..=4u64)
            .map(|i| ConvergencePoint {
                shots: i * 10,
                seconds: i as f64 * 0.5,
                unshot_fraction: 0.5f64.powi(i as i32),
                vertices: 100,
                errors: errors.then(|| {
                    let b = DVec3::splat(1.0 + 0.2f64.powi(i as i32));
                    Errors::of(&[(1.0, b)], &[Some(DVec3::ONE)]).expect("errors")
                }),
            })
            .collect()
    }

    #[test]
    fn a_written_record_reads_back() {
        let names = ["floor, left".to_string()];
        let csv = convergence_csv(&record(true), &names);
        assert!(
            csv.lines().next().unwrap().ends_with("\"floor, left.b\""),
            "{csv}"
        );
        let rows = parse_csv("convergence.csv", &csv).expect("parses");
        assert_eq!(rows.len(), 4);
        assert_eq!((rows[3].shots, rows[3].seconds), (40, 2.0));
        let rms = rows[1].rms_error.expect("rms");
        assert!((rms - 0.04).abs() < 1e-6, "{rms}");
        let plain = parse_csv("c.csv", &convergence_csv(&record(false), &names)).unwrap();
        assert!(
            plain
                .iter()
                .all(|r| r.rms_error.is_none() && r.max_error.is_none())
        );
    }

    #[test]
    fn the_table_compares_by_error_when_every_run_has_one() {
        let csv = convergence_csv(&record(true), &[]);
        let fast = Run {
            name: "fast".into(),
            rows: parse_csv("a", &csv).unwrap(),
        };
        let t = table(std::slice::from_ref(&fast));
        assert!(t.contains("RMS relative error reached"), "{t}");
        // 0.2, 0.04, 0.008: 10% first at 1 s, 1% at 1.5 s.
        assert!(
            t.contains("| fast | 0.160% | 0.160% | 2.000 | 40 | 1.000 | 1.500 |"),
            "{t}"
        );
        let plain = Run {
            name: "plain".into(),
            rows: parse_csv("b", &convergence_csv(&record(false), &[])).unwrap(),
        };
        let t = table(&[fast, plain.clone()]);
        assert!(t.contains("unshot power fraction reached"), "{t}");
        assert!(
            t.contains("| plain | 6.250% | - | 2.000 | 40 | 2.000 | - |"),
            "{t}"
        );
        assert!(compare_png(&[plain], false).is_ok());
    }

    #[test]
    fn a_broken_record_is_refused_with_its_line() {
        let e = parse_csv(
            "x.csv",
            "seconds,shots,unshot_fraction\n0.1,1,0.5\n0.2,two,0.4\n",
        )
        .unwrap_err()
        .to_string();
        assert!(e.contains("x.csv:3") && e.contains("`two`"), "{e}");
        let e = parse_csv("y.csv", "shots,unshot_fraction\n")
            .unwrap_err()
            .to_string();
        assert!(e.contains("y.csv:1") && e.contains("seconds"), "{e}");
    }
}
