//! The outputs of a solve, as bytes or text (the caller writes the files): `report.json`,
//! `convergence.csv`/`.png`, `image.png`, `solution.ply` and `probe.csv`, and the path-traced
//! truth (`pathtrace.json`); and the comparison of several runs' records (`compare`).

pub mod compare;
pub mod image;
pub mod plot;
pub mod ply;
pub mod probe;
pub mod report;
pub mod truth;

/// An output error.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum OutputError {
    /// Occurs when PNG encoding fails.
    #[error("PNG encoding failed: {0}")]
    Png(String),
    /// Occurs when the plotting library fails to draw.
    #[error("plotting failed: {0}")]
    Plot(String),
    /// Occurs when a reference report is malformed (`--reference`).
    #[error("{file}: {message}")]
    Reference {
        /// File name.
        file: String,
        /// What was wrong.
        message: String,
    },
    /// Occurs when a convergence record is malformed (`occ radiosity compare`).
    #[error("{file}:{line}: {message}")]
    Convergence {
        /// File name.
        file: String,
        /// 1-based line number.
        line: usize,
        /// What was wrong.
        message: String,
    },
    /// Occurs when a probe file line is malformed (`--probe`).
    #[error("{file}:{line}: {message}")]
    Probe {
        /// File name.
        file: String,
        /// 1-based line number.
        line: usize,
        /// What was wrong.
        message: String,
    },
}

/// Encodes an RGB8 buffer as PNG.
pub fn encode_png(rgb: &[u8], width: u32, height: u32) -> Result<Vec<u8>, OutputError> {
    let mut bytes = Vec::new();
    let mut encoder = png::Encoder::new(&mut bytes, width, height);
    encoder.set_color(png::ColorType::Rgb);
    encoder.set_depth(png::BitDepth::Eight);
    let mut writer = encoder
        .write_header()
        .map_err(|e| OutputError::Png(e.to_string()))?;
    writer
        .write_image_data(rgb)
        .map_err(|e| OutputError::Png(e.to_string()))?;
    writer
        .finish()
        .map_err(|e| OutputError::Png(e.to_string()))?;
    Ok(bytes)
}

/// Maps a linear value to an sRGB byte (IEC 61966-2-1 transfer function, clamped).
pub fn srgb_byte(linear: f32) -> u8 {
    let x = linear.clamp(0.0, 1.0);
    let s = if x <= 0.0031308 {
        12.92 * x
    } else {
        1.055 * x.powf(1.0 / 2.4) - 0.055
    };
    (s * 255.0 + 0.5) as u8
}
