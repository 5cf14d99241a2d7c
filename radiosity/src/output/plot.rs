//! `convergence.csv` and `convergence.png`: the unshot-power fraction and, against a reference,
//! the RMS and largest relative error ([`crate::convergence::Errors`]) against shots and against
//! run time, on log axes; and the log-log chart that `compare` ([`super::compare`]) draws too.

use plotters::prelude::*;

use super::{OutputError, encode_png};
use crate::solver::ConvergencePoint;

/// Font files tried, in order, for plot labels.
const FONT_PATHS: &[&str] = &[
    "/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf",
    "/usr/share/fonts/TTF/DejaVuSans.ttf",
    "/usr/share/fonts/truetype/liberation/LiberationSans-Regular.ttf",
    "/System/Library/Fonts/Supplemental/Arial.ttf",
    "C:\\Windows\\Fonts\\arial.ttf",
];

/// Registers a system font for plot labels; returns false when none was found (plots are then
/// drawn without text). Reads a file: call it from the binary, once.
pub fn register_system_font() -> bool {
    for path in FONT_PATHS {
        if let Ok(bytes) = std::fs::read(path) {
            let bytes: &'static [u8] = Box::leak(bytes.into_boxed_slice());
            if plotters::style::register_font("sans-serif", FontStyle::Normal, bytes).is_ok() {
                return true;
            }
        }
    }
    false
}

/// The columns of `convergence.csv` before the per-object ones.
pub const CSV_COLUMNS: [&str; 12] = [
    "seconds",
    "shots",
    "unshot_fraction",
    "vertices",
    "rms_error",
    "max_error",
    "rms_r",
    "rms_g",
    "rms_b",
    "max_r",
    "max_g",
    "max_b",
];

/// Returns `convergence.csv`: a row per record ([`CSV_COLUMNS`]), then each object's relative
/// error per channel (`NAME.r`, `NAME.g`, `NAME.b`, named by `names`); error cells are empty
/// without a reference, and for objects or channels it does not cover.
pub fn convergence_csv(history: &[ConvergencePoint], names: &[String]) -> String {
    let mut header: Vec<String> = CSV_COLUMNS.iter().map(|c| c.to_string()).collect();
    for n in names {
        header.extend(["r", "g", "b"].map(|c| csv_field(&format!("{n}.{c}"))));
    }
    let mut s = header.join(",") + "\n";
    let cell = |x: f64| {
        if x.is_finite() {
            format!("{x:.6e}")
        } else {
            String::new()
        }
    };
    for p in history {
        let mut row = vec![
            format!("{:.6}", p.seconds),
            p.shots.to_string(),
            format!("{:.9e}", p.unshot_fraction),
            p.vertices.to_string(),
        ];
        match &p.errors {
            Some(e) => {
                row.extend([cell(e.rms), cell(e.max)]);
                row.extend(e.rms_channel.iter().chain(&e.max_channel).map(|&x| cell(x)));
                for o in names
                    .iter()
                    .enumerate()
                    .map(|(i, _)| e.objects.get(i).copied().flatten())
                {
                    row.extend(o.map_or([f64::NAN; 3], |o| o).map(cell));
                }
            }
            None => row.extend(std::iter::repeat_n(String::new(), 8 + 3 * names.len())),
        }
        s += &(row.join(",") + "\n");
    }
    s
}

/// Quotes a CSV field that needs it (RFC 4180).
fn csv_field(text: &str) -> String {
    if text.contains([',', '"', '\n']) {
        format!("\"{}\"", text.replace('"', "\"\""))
    } else {
        text.to_string()
    }
}

/// One curve of a log-log chart: its legend and its points (non-positive values are dropped).
pub struct Curve {
    /// Legend text.
    pub label: String,
    /// `(x, y)` points.
    pub points: Vec<(f64, f64)>,
}

/// Draws `convergence.png`: unshot fraction, RMS and largest error against shots (left) and
/// against seconds (right), log-log.
pub fn convergence_png(history: &[ConvergencePoint], labels: bool) -> Result<Vec<u8>, OutputError> {
    let curves = |x: &dyn Fn(&ConvergencePoint) -> f64| {
        let mut out = vec![Curve {
            label: "unshot power / emitted".into(),
            points: history.iter().map(|p| (x(p), p.unshot_fraction)).collect(),
        }];
        if history.iter().any(|p| p.errors.is_some()) {
            let pick = |f: fn(&crate::convergence::Errors) -> f64| {
                history
                    .iter()
                    .filter_map(|p| p.errors.as_ref().map(|e| (x(p), f(e))))
                    .collect()
            };
            out.push(Curve {
                label: "RMS relative error vs reference".into(),
                points: pick(|e| e.rms),
            });
            out.push(Curve {
                label: "largest relative error vs reference".into(),
                points: pick(|e| e.max),
            });
        }
        out
    };
    let panels = [
        ("shots", curves(&|p| p.shots as f64)),
        ("seconds", curves(&|p| p.seconds)),
    ];
    draw_panels(&panels, "convergence against", labels)
}

/// Draws one log-log panel per `(x axis name, curves)`, side by side, titled
/// `"{title} {x axis name}"`.
pub fn draw_panels(
    panels: &[(&str, Vec<Curve>)],
    title: &str,
    labels: bool,
) -> Result<Vec<u8>, OutputError> {
    let (w, h) = (600 * panels.len().max(1) as u32, 500u32);
    let mut buf = vec![255u8; (w * h * 3) as usize];
    {
        let root = BitMapBackend::with_buffer(&mut buf, (w, h)).into_drawing_area();
        let areas = root.split_evenly((1, panels.len().max(1)));
        for (area, (x_name, curves)) in areas.iter().zip(panels) {
            log_log_panel(area, &format!("{title} {x_name}"), x_name, curves, labels)?;
        }
        root.present()
            .map_err(|e| OutputError::Plot(e.to_string()))?;
    }
    encode_png(&buf, w, h)
}

/// Line colours, in order of the curves.
const COLOURS: [RGBColor; 8] = [
    BLUE,
    RED,
    RGBColor(230, 140, 0),
    RGBColor(0, 150, 0),
    MAGENTA,
    CYAN,
    BLACK,
    RGBColor(120, 80, 40),
];

fn log_log_panel<DB: DrawingBackend>(
    area: &DrawingArea<DB, plotters::coord::Shift>,
    title: &str,
    x_name: &str,
    curves: &[Curve],
    labels: bool,
) -> Result<(), OutputError> {
    let err = |e: &dyn std::fmt::Display| OutputError::Plot(e.to_string());
    let positive: Vec<Vec<(f64, f64)>> = curves
        .iter()
        .map(|c| {
            c.points
                .iter()
                .copied()
                .filter(|(x, y)| *x > 0.0 && *y > 0.0 && x.is_finite() && y.is_finite())
                .collect()
        })
        .collect();
    let all = || positive.iter().flatten();
    let range = |f: fn(&(f64, f64)) -> f64, lo: f64, hi: f64| {
        let (min, max) = all()
            .map(f)
            .fold((f64::INFINITY, 0.0f64), |(a, b), v| (a.min(v), b.max(v)));
        if min.is_finite() {
            (min * 0.8, max * 1.25)
        } else {
            (lo, hi)
        }
    };
    let (x_min, x_max) = range(|p| p.0, 1e-3, 1.0);
    let (y_min, y_max) = range(|p| p.1, 1e-6, 1.0);
    let mut builder = ChartBuilder::on(area);
    builder.margin(15);
    if labels {
        builder
            .caption(title, ("sans-serif", 20))
            .x_label_area_size(40)
            .y_label_area_size(70);
    }
    let mut chart = builder
        .build_cartesian_2d((x_min..x_max).log_scale(), (y_min..y_max).log_scale())
        .map_err(|e| err(&e))?;
    let mut mesh = chart.configure_mesh();
    if labels {
        mesh.x_desc(format!("{x_name} (log)"))
            .y_desc("fraction (log)");
    } else {
        mesh.x_labels(0).y_labels(0);
    }
    mesh.draw().map_err(|e| err(&e))?;
    for (i, (curve, points)) in curves.iter().zip(positive).enumerate() {
        let colour = COLOURS[i % COLOURS.len()];
        let series = chart
            .draw_series(LineSeries::new(points, colour.stroke_width(2)))
            .map_err(|e| err(&e))?;
        if labels {
            series
                .label(curve.label.clone())
                .legend(move |(x, y)| PathElement::new([(x, y), (x + 20, y)], colour));
        }
    }
    if labels && !curves.is_empty() {
        chart
            .configure_series_labels()
            .background_style(WHITE)
            .border_style(BLACK)
            .draw()
            .map_err(|e| err(&e))?;
    }
    Ok(())
}
