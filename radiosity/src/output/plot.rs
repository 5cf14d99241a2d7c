//! `convergence.csv` and `convergence.png`: unshot-power fraction (and RMS error against a
//! reference, when given) against shots and against run time, on log scales.

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

/// Returns `convergence.csv`: `shots,seconds,unshot_fraction,rms_error,vertices`.
pub fn convergence_csv(history: &[ConvergencePoint], rms: &[Option<f64>]) -> String {
    let mut s = String::from("shots,seconds,unshot_fraction,rms_error,vertices\n");
    for (i, p) in history.iter().enumerate() {
        let r = rms
            .get(i)
            .copied()
            .flatten()
            .map_or(String::new(), |r| r.to_string());
        s += &format!(
            "{},{:.6},{:.9e},{r},{}\n",
            p.shots, p.seconds, p.unshot_fraction, p.vertices
        );
    }
    s
}

/// Draws `convergence.png` (two panels: against shots, against seconds).
pub fn convergence_png(
    history: &[ConvergencePoint],
    rms: &[Option<f64>],
    labels: bool,
) -> Result<Vec<u8>, OutputError> {
    let (w, h) = (1200u32, 500u32);
    let mut buf = vec![255u8; (w * h * 3) as usize];
    {
        let root = BitMapBackend::with_buffer(&mut buf, (w, h)).into_drawing_area();
        let panels = root.split_evenly((1, 2));
        let shots: Vec<f64> = history.iter().map(|p| p.shots as f64).collect();
        let secs: Vec<f64> = history.iter().map(|p| p.seconds).collect();
        panel(&panels[0], &shots, history, rms, "shots", labels)?;
        panel(&panels[1], &secs, history, rms, "seconds", labels)?;
        root.present()
            .map_err(|e| OutputError::Plot(e.to_string()))?;
    }
    encode_png(&buf, w, h)
}

fn panel<DB: DrawingBackend>(
    area: &DrawingArea<DB, plotters::coord::Shift>,
    xs: &[f64],
    history: &[ConvergencePoint],
    rms: &[Option<f64>],
    x_name: &str,
    labels: bool,
) -> Result<(), OutputError> {
    let err = |e: &dyn std::fmt::Display| OutputError::Plot(e.to_string());
    let x_max = xs.last().copied().unwrap_or(1.0).max(1e-9);
    let ys = history
        .iter()
        .map(|p| p.unshot_fraction)
        .chain(rms.iter().flatten().copied());
    let y_min = ys.filter(|y| *y > 0.0).fold(1.0f64, f64::min).max(1e-12) * 0.5;
    let mut builder = ChartBuilder::on(area);
    builder.margin(15);
    if labels {
        builder
            .caption(format!("convergence against {x_name}"), ("sans-serif", 20))
            .x_label_area_size(40)
            .y_label_area_size(70);
    }
    let mut chart = builder
        .build_cartesian_2d(0.0..x_max, (y_min..2.0).log_scale())
        .map_err(|e| err(&e))?;
    let mut mesh = chart.configure_mesh();
    if labels {
        mesh.x_desc(x_name).y_desc("fraction (log)");
    } else {
        mesh.x_labels(0).y_labels(0);
    }
    mesh.draw().map_err(|e| err(&e))?;
    let unshot = xs
        .iter()
        .zip(history)
        .map(|(&x, p)| (x, p.unshot_fraction.max(y_min)));
    let series = chart
        .draw_series(LineSeries::new(unshot, BLUE.stroke_width(2)))
        .map_err(|e| err(&e))?;
    if labels {
        series
            .label("unshot power / emitted")
            .legend(|(x, y)| PathElement::new([(x, y), (x + 20, y)], BLUE));
    }
    let rms_points: Vec<(f64, f64)> = xs
        .iter()
        .zip(rms)
        .filter_map(|(&x, r)| r.map(|r| (x, r.max(y_min))))
        .collect();
    if !rms_points.is_empty() {
        let s = chart
            .draw_series(LineSeries::new(rms_points, RED.stroke_width(2)))
            .map_err(|e| err(&e))?;
        if labels {
            s.label("relative RMS error vs reference")
                .legend(|(x, y)| PathElement::new([(x, y), (x + 20, y)], RED));
        }
    }
    if labels {
        chart
            .configure_series_labels()
            .background_style(WHITE)
            .border_style(BLACK)
            .draw()
            .map_err(|e| err(&e))?;
    }
    Ok(())
}
