//! Scene loading: Wavefront OBJ + MTL through `tobj`, checked line by line first so that every
//! malformed input is reported with its file and line (tobj's own errors carry no line).
//!
//! Conventions: `Kd` is the diffuse reflectance, `Ke` the emitted radiance (RGB), object names come
//! from `o` or `g`, and a comment line `# camera: pos (x y z) dir (x y z) up (x y z) fov DEG` (or
//! `look (x y z)`, a point looked at, instead of `dir`) gives the view used for `image.png`.
//!
//! Files as real exporters write them: CRLF line ends; bytes that are not UTF-8 (read as
//! Latin-1, see [`decode`]); statements we do not use, counted and listed in
//! [`Scene::left_out`]; non-diffuse materials (specular, mirror, glass, textured) replaced by
//! their diffuse approximation (`Kd`, times the mean colour of a `map_Kd` PNG texture when one
//! can be read; `Ks` when there is no `Kd`), with a note listing them. The loader takes text,
//! never paths: the caller supplies the OBJ text and a [`Files`] that returns material
//! libraries and textures by the name the file gives (see [`SearchFiles`] for the usual
//! search).

use std::collections::HashMap;
use std::io::BufReader;

use glam::{DVec3, Vec3};

use crate::geom::Tri;

/// Returns the text of a scene file's bytes: UTF-8 when they are, otherwise each byte as its
/// Latin-1 character (exporters write names and comments in the local code page), with `true`.
pub fn decode(bytes: &[u8]) -> (String, bool) {
    match std::str::from_utf8(bytes) {
        Ok(s) => (s.to_string(), false),
        Err(_) => (bytes.iter().map(|&b| b as char).collect(), true),
    }
}

/// Where the loader gets the files a scene names.
pub trait Files {
    /// The text of material library `name` (as written after `mtllib`), or why not.
    fn library(&self, name: &str) -> Result<String, String>;
    /// The bytes of texture `name` (as written in a material library), or why not.
    fn texture(&self, name: &str) -> Result<Vec<u8>, String> {
        Err(format!("no texture `{name}`"))
    }
}

impl<F: Fn(&str) -> Result<String, String>> Files for F {
    fn library(&self, name: &str) -> Result<String, String> {
        self(name)
    }
}

/// Files looked up relative to the scene's folder, then the working folder. A failure names
/// every path tried.
pub struct SearchFiles {
    /// Folders to try, in order.
    pub folders: Vec<std::path::PathBuf>,
}

impl SearchFiles {
    /// The folder of `scene`, then the working folder.
    pub fn beside(scene: &std::path::Path) -> SearchFiles {
        let dir = scene
            .parent()
            .map(std::path::Path::to_path_buf)
            .unwrap_or_default();
        SearchFiles {
            folders: vec![dir, std::path::PathBuf::from(".")],
        }
    }

    fn read(&self, name: &str) -> Result<Vec<u8>, String> {
        // Exporters on Windows write backslashes.
        let name = name.trim().replace('\\', "/");
        let mut tried = Vec::new();
        for folder in &self.folders {
            let path = folder.join(&name);
            match std::fs::read(&path) {
                Ok(bytes) => return Ok(bytes),
                Err(e) => tried.push(format!("{} ({e})", path.display())),
            }
        }
        Err(format!("tried {}", tried.join(", ")))
    }
}

impl Files for SearchFiles {
    fn library(&self, name: &str) -> Result<String, String> {
        self.read(name).map(|b| decode(&b).0)
    }

    fn texture(&self, name: &str) -> Result<Vec<u8>, String> {
        self.read(name)
    }
}

/// A scene error, always naming the file (and the line where there is one).
#[derive(Debug, thiserror::Error, PartialEq)]
#[non_exhaustive]
pub enum SceneError {
    /// Occurs when a number is malformed, infinite or NaN (`v 1 nan 2`, `Kd 0.5 x 0.5`).
    #[error("{file}:{line}: {message}")]
    BadNumber {
        /// File name.
        file: String,
        /// 1-based line number.
        line: usize,
        /// What was wrong.
        message: String,
    },
    /// Occurs when a face refers to a vertex that does not exist (`f 1 2 99` with 3 vertices).
    #[error(
        "{file}:{line}: face vertex index {index} is out of range (the file has {count} vertices so far)"
    )]
    FaceIndexOutOfRange {
        /// File name.
        file: String,
        /// 1-based line number.
        line: usize,
        /// The index as written.
        index: i64,
        /// Number of vertices defined before this line.
        count: usize,
    },
    /// Occurs when a face has fewer than three vertices (`f 1 2`).
    #[error("{file}:{line}: a face needs at least 3 vertices")]
    ShortFace {
        /// File name.
        file: String,
        /// 1-based line number.
        line: usize,
    },
    /// Occurs when `mtllib` names a material library that cannot be read.
    #[error("{file}:{line}: cannot read material library `{name}`: {reason}")]
    MissingMaterialLibrary {
        /// File name.
        file: String,
        /// 1-based line number.
        line: usize,
        /// The library as named.
        name: String,
        /// Why it could not be read.
        reason: String,
    },
    /// Occurs when `usemtl` names a material that no library defines.
    #[error("{file}:{line}: unknown material `{name}`")]
    UnknownMaterial {
        /// File name.
        file: String,
        /// 1-based line number.
        line: usize,
        /// The material as named.
        name: String,
    },
    /// Occurs when a reflectance is outside [0, 1] or an emission is negative (`Kd 1.2 0 0`).
    #[error("{file}:{line}: {message}")]
    OutOfRange {
        /// File name.
        file: String,
        /// 1-based line number.
        line: usize,
        /// What was wrong.
        message: String,
    },
    /// Occurs when the scene lies so far from the origin for its size that single precision
    /// cannot place its vertices finely enough (`v 1e6 1e6 1e6` in a scene 1e-3 across).
    #[error("{file}:{line}: {message}")]
    BeyondPrecision {
        /// File name.
        file: String,
        /// 1-based line number of the vertex farthest from the origin.
        line: usize,
        /// What was wrong.
        message: String,
    },
    /// Occurs when the camera comment is malformed.
    #[error(
        "{file}:{line}: malformed camera comment (expected `# camera: pos (x y z) dir (x y z) up (x y z) fov DEG`)"
    )]
    BadCamera {
        /// File name.
        file: String,
        /// 1-based line number.
        line: usize,
    },
    /// Occurs when tobj rejects the file after our own checks passed.
    #[error("{file}: {message}")]
    Obj {
        /// File name.
        file: String,
        /// tobj's message.
        message: String,
    },
    /// Occurs when no triangle is left (empty file, or only degenerate faces).
    #[error("{file}: the scene has no (non-degenerate) triangles")]
    NoGeometry {
        /// File name.
        file: String,
    },
    /// Occurs when no material has a positive `Ke`: there is no light, so nothing to solve.
    #[error("{file}: the scene has no emitters (no material with a positive Ke)")]
    NoEmitters {
        /// File name.
        file: String,
    },
}

/// A named object (OBJ `o`/`g` with one material).
#[derive(Clone, Debug, PartialEq)]
pub struct Object {
    /// Object name from `o` or `g` (or `unnamed`).
    pub name: String,
    /// Diffuse reflectance `Kd`, RGB in [0, 1].
    pub reflectance: Vec3,
    /// Emitted radiance `Ke`, RGB.
    pub emission: Vec3,
}

impl Object {
    /// The radiosity `B = E + ρ H` of the object's surface under the irradiance `h` (`E = π
    /// Ke`, the exitance of its emitted radiance).
    pub fn radiosity(&self, h: DVec3) -> DVec3 {
        self.emission.as_dvec3() * std::f64::consts::PI + self.reflectance.as_dvec3() * h
    }
}

/// One triangle of the scene and the object it belongs to.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SceneTri {
    /// Geometry.
    pub tri: Tri,
    /// Index into [`Scene::objects`].
    pub object: u32,
}

/// A pinhole camera.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    /// Eye position.
    pub pos: Vec3,
    /// Viewing direction.
    pub dir: Vec3,
    /// Up vector.
    pub up: Vec3,
    /// Horizontal field of view in degrees.
    pub fov_deg: f32,
}

/// A loaded scene: objects, triangles, the camera and what was left out.
#[derive(Clone, Debug, Default)]
pub struct Scene {
    /// Objects in file order.
    pub objects: Vec<Object>,
    /// Non-degenerate triangles.
    pub triangles: Vec<SceneTri>,
    /// The file's vertex normals (`vn`) averaged over each triangle, by triangle index (zero
    /// for a triangle without them; empty when the file has none). The mesher turns over
    /// triangles whose winding disagrees with them.
    pub normal_hints: Vec<Vec3>,
    /// The camera from the `# camera:` comment, if any.
    pub camera: Option<Camera>,
    /// Degenerate (zero-area) triangles dropped.
    pub dropped_degenerate: usize,
    /// What the loader ignored and why (textures, normals, ...), one sentence each.
    pub left_out: Vec<String>,
}

impl Scene {
    /// Returns the axis-aligned bounds `(min, max)` of all triangles.
    pub fn bounds(&self) -> (Vec3, Vec3) {
        let mut lo = Vec3::splat(f32::INFINITY);
        let mut hi = Vec3::splat(f32::NEG_INFINITY);
        for t in &self.triangles {
            for v in t.tri.v {
                lo = lo.min(v);
                hi = hi.max(v);
            }
        }
        (lo, hi)
    }

    /// Returns the length of the bounding box diagonal.
    pub fn diagonal(&self) -> f32 {
        let (lo, hi) = self.bounds();
        (hi - lo).length()
    }
}

/// Parses an OBJ scene. `file` names it in errors; `library` returns the text of a material
/// library named by `mtllib` (or a reason why it cannot). Textures are not read.
pub fn load_obj(
    file: &str,
    obj_text: &str,
    library: &dyn Fn(&str) -> Result<String, String>,
) -> Result<Scene, SceneError> {
    load_obj_with(file, obj_text, &library)
}

/// [`load_obj`] with material libraries and textures from `files`.
pub fn load_obj_with(file: &str, obj_text: &str, files: &dyn Files) -> Result<Scene, SceneError> {
    let text = obj_text.replace("\r\n", "\n");
    let mut checked = check_obj(file, &text, files)?;
    checked.extent.check_precision(file)?;
    let (models, materials) = run_tobj(file, &text, &checked.libraries)?;
    let mut scene = Scene {
        camera: checked.camera,
        left_out: std::mem::take(&mut checked.left_out),
        ..Scene::default()
    };
    collect_triangles(&mut scene, &models, &materials, &checked.diffuse);
    if scene.triangles.is_empty() {
        return Err(SceneError::NoGeometry { file: file.into() });
    }
    if !scene.objects.iter().any(|o| o.emission.max_element() > 0.0) {
        return Err(SceneError::NoEmitters { file: file.into() });
    }
    Ok(scene)
}

/// What the line-by-line check found.
struct Checked {
    camera: Option<Camera>,
    libraries: HashMap<String, String>,
    left_out: Vec<String>,
    /// The diffuse reflectance to use for each material made diffuse (by name).
    diffuse: HashMap<String, [f32; 3]>,
    /// Where the vertices lie.
    extent: Extent,
}

/// The bounding box of the vertices and the line of the one farthest from the origin.
#[derive(Default)]
struct Extent {
    lo: Vec3,
    hi: Vec3,
    /// The largest |coordinate| and the line of its vertex.
    farthest: (f32, usize),
}

impl Extent {
    fn add(&mut self, v: Vec3, line: usize) {
        if self.farthest.1 == 0 {
            (self.lo, self.hi) = (v, v);
        }
        self.lo = self.lo.min(v);
        self.hi = self.hi.max(v);
        let m = v.abs().max_element();
        if m > self.farthest.0 || self.farthest.1 == 0 {
            self.farthest = (m, line);
        }
    }

    /// Refuses a scene whose coordinates single precision rounds by more than 1e-6 of its
    /// size (the distance by which the solver lifts rays off surfaces).
    fn check_precision(&self, file: &str) -> Result<(), SceneError> {
        let (far, line) = self.farthest;
        let size = (self.hi - self.lo).length();
        let step = far * f32::EPSILON;
        if line == 0 || step <= 1e-6 * size {
            return Ok(());
        }
        Err(SceneError::BeyondPrecision {
            file: file.into(),
            line,
            message: format!(
                "this vertex lies {far:.3e} from the origin in a scene {size:.3e} across: \
                 single precision places coordinates there only to {step:.1e}, more than 1e-6 \
                 of the scene's size; move the scene nearer the origin"
            ),
        })
    }
}

/// OBJ statements the loader reads or knowingly skips without a note.
const OBJ_KNOWN: &[&str] = &["v", "vn", "vt", "f", "mtllib", "usemtl", "o", "g", "s"];

/// Statements met that the loader does not use: keyword -> (count, first line).
type Unknown = std::collections::BTreeMap<String, (usize, usize)>;

fn note_unknown(unknown: &mut Unknown, key: &str, line: usize) {
    unknown.entry(key.to_string()).or_insert((0, line)).0 += 1;
}

fn report_unknown(file: &str, unknown: Unknown, left_out: &mut Vec<String>) {
    for (key, (count, line)) in unknown {
        left_out.push(format!(
            "{file}:{line}: `{key}` statements ignored ({count}): not used by radiosity"
        ));
    }
}

/// Checks every OBJ line that we rely on and every library it names.
fn check_obj(file: &str, text: &str, files: &dyn Files) -> Result<Checked, SceneError> {
    let mut out = Checked {
        camera: None,
        libraries: HashMap::new(),
        left_out: Vec::new(),
        diffuse: HashMap::new(),
        extent: Extent::default(),
    };
    let mut materials: Vec<String> = Vec::new();
    let mut vertices = 0usize;
    let (mut normals, mut texcoords) = (false, false);
    let mut unknown = Unknown::new();
    for (i, raw) in text.lines().enumerate() {
        let line = i + 1;
        let trimmed = raw.trim();
        if let Some(rest) = trimmed.strip_prefix("# camera:") {
            out.camera = Some(parse_camera(rest).ok_or(SceneError::BadCamera {
                file: file.into(),
                line,
            })?);
            continue;
        }
        let mut words = trimmed.split_whitespace();
        match words.next() {
            Some("v") => {
                let v = parse_numbers(file, line, words, 3)?;
                out.extent.add(Vec3::new(v[0], v[1], v[2]), line);
                vertices += 1;
            }
            Some("vn") => normals = true,
            Some("vt") => texcoords = true,
            Some("f") => check_face(file, line, words, vertices)?,
            Some("mtllib") => {
                let name = words.collect::<Vec<_>>().join(" ");
                let body = files
                    .library(&name)
                    .map_err(|reason| SceneError::MissingMaterialLibrary {
                        file: file.into(),
                        line,
                        name: name.clone(),
                        reason,
                    })?
                    .replace("\r\n", "\n");
                materials.extend(check_mtl(&name, &body, files, &mut out)?);
                out.libraries.insert(name, body);
            }
            Some("usemtl") => {
                let name = words.collect::<Vec<_>>().join(" ");
                if !materials.contains(&name) {
                    return Err(SceneError::UnknownMaterial {
                        file: file.into(),
                        line,
                        name,
                    });
                }
            }
            Some(key) if !key.starts_with('#') && !OBJ_KNOWN.contains(&key) => {
                note_unknown(&mut unknown, key, line);
            }
            _ => {}
        }
    }
    if normals {
        out.left_out.push(
            "vertex normals (vn) used only to turn over triangles wound against them: radiosity \
             uses the geometric normal of each face"
                .into(),
        );
    }
    if texcoords {
        out.left_out
            .push("texture coordinates (vt) ignored: a texture counts by its mean colour".into());
    }
    report_unknown(file, unknown, &mut out.left_out);
    Ok(out)
}

/// Parses at least `n` finite numbers from `words`.
fn parse_numbers<'a>(
    file: &str,
    line: usize,
    words: impl Iterator<Item = &'a str>,
    n: usize,
) -> Result<Vec<f32>, SceneError> {
    let mut out = Vec::with_capacity(n);
    for w in words {
        match w.parse::<f32>() {
            Ok(x) if x.is_finite() => out.push(x),
            _ => {
                return Err(SceneError::BadNumber {
                    file: file.into(),
                    line,
                    message: format!("`{w}` is not a finite number"),
                });
            }
        }
    }
    if out.len() < n {
        return Err(SceneError::BadNumber {
            file: file.into(),
            line,
            message: format!("expected {n} numbers, found {}", out.len()),
        });
    }
    Ok(out)
}

/// Checks the vertex indices of an `f` line against the vertices defined so far.
fn check_face<'a>(
    file: &str,
    line: usize,
    words: impl Iterator<Item = &'a str>,
    count: usize,
) -> Result<(), SceneError> {
    let mut corners = 0;
    for w in words {
        let first = w.split('/').next().unwrap_or("");
        let index: i64 = first.parse().map_err(|_| SceneError::BadNumber {
            file: file.into(),
            line,
            message: format!("`{w}` is not a vertex index"),
        })?;
        let resolved = if index < 0 {
            count as i64 + index + 1
        } else {
            index
        };
        if resolved < 1 || resolved > count as i64 {
            return Err(SceneError::FaceIndexOutOfRange {
                file: file.into(),
                line,
                index,
                count,
            });
        }
        corners += 1;
    }
    if corners < 3 {
        return Err(SceneError::ShortFace {
            file: file.into(),
            line,
        });
    }
    Ok(())
}

/// A material as far as being diffuse goes.
#[derive(Default)]
struct MaterialNotes {
    name: String,
    kd: Option<[f32; 3]>,
    ks: Option<[f32; 3]>,
    texture: Option<String>,
    /// Why it is not diffuse (empty: it is).
    why: Vec<&'static str>,
}

/// MTL statements read or knowingly skipped without a note.
const MTL_KNOWN: &[&str] = &[
    "newmtl", "Kd", "Ke", "Ka", "Ks", "Ns", "Ni", "d", "Tr", "Tf", "illum",
];

/// Checks a material library's `Kd`/`Ke` lines; returns the material names it defines and
/// records the diffuse approximation of each non-diffuse material in `out`.
fn check_mtl(
    file: &str,
    text: &str,
    files: &dyn Files,
    out: &mut Checked,
) -> Result<Vec<String>, SceneError> {
    let mut names = Vec::new();
    let mut all: Vec<MaterialNotes> = Vec::new();
    let mut unknown = Unknown::new();
    for (i, raw) in text.lines().enumerate() {
        let line = i + 1;
        let mut words = raw.split_whitespace();
        let key = words.next();
        let current = all.last_mut();
        match (key, current) {
            (Some("newmtl"), _) => {
                let name = words.collect::<Vec<_>>().join(" ");
                names.push(name.clone());
                all.push(MaterialNotes {
                    name,
                    ..MaterialNotes::default()
                });
            }
            (Some("Kd"), m) => {
                let kd = parse_numbers(file, line, words, 3)?;
                if kd.iter().any(|&x| !(0.0..=1.0).contains(&x)) {
                    return Err(out_of_range(
                        file,
                        line,
                        "a reflectance Kd must lie in [0, 1]",
                    ));
                }
                if let Some(m) = m {
                    m.kd = Some([kd[0], kd[1], kd[2]]);
                }
            }
            (Some("Ke"), _) => {
                let ke = parse_numbers(file, line, words, 3)?;
                if ke.iter().any(|&x| x < 0.0) {
                    return Err(out_of_range(
                        file,
                        line,
                        "an emission Ke must not be negative",
                    ));
                }
            }
            (Some("Ks"), Some(m)) => {
                if let Ok(ks) = parse_numbers(file, line, words, 3)
                    && ks.iter().any(|&x| x > 0.0)
                {
                    m.ks = Some([ks[0], ks[1], ks[2]].map(|x| x.clamp(0.0, 1.0)));
                    m.why.push("specular");
                }
            }
            (Some("Tf"), Some(m)) => {
                if parse_numbers(file, line, words, 3).is_ok_and(|t| t.iter().any(|&x| x < 1.0)) {
                    m.why.push("transmissive");
                }
            }
            (Some("d"), Some(m)) => {
                if parse_numbers(file, line, words, 1).is_ok_and(|t| t[0] < 1.0) {
                    m.why.push("transparent");
                }
            }
            (Some("Tr"), Some(m)) => {
                if parse_numbers(file, line, words, 1).is_ok_and(|t| t[0] > 0.0) {
                    m.why.push("transparent");
                }
            }
            (Some("map_Kd"), Some(m)) => {
                // Options (-s, -o, ...) come first; the file name is last.
                m.texture = words.last().map(str::to_string);
                m.why.push("textured");
            }
            (Some(key), _) if key.starts_with('#') || MTL_KNOWN.contains(&key) => {}
            (Some(key), _) => note_unknown(&mut unknown, key, line),
            (None, _) => {}
        }
    }
    report_unknown(file, unknown, &mut out.left_out);
    let mut made_diffuse = Vec::new();
    for mut m in all {
        if m.why.is_empty() {
            continue;
        }
        m.why.dedup();
        let (rho, how) = diffuse_of(&m, files);
        made_diffuse.push(format!("{} ({}; {how})", m.name, m.why.join(", ")));
        out.diffuse.insert(m.name, rho);
    }
    if !made_diffuse.is_empty() {
        out.left_out.push(format!(
            "{file}: non-diffuse materials made diffuse: {}",
            made_diffuse.join(", ")
        ));
    }
    Ok(names)
}

/// The diffuse approximation of a material: `Kd` (or `Ks` without `Kd`, or grey 0.5 without
/// either), times the mean of its texture when that can be read; and how it was made.
fn diffuse_of(m: &MaterialNotes, files: &dyn Files) -> ([f32; 3], String) {
    let (base, from) = match (m.kd, m.ks) {
        (Some(kd), _) => (kd, "Kd"),
        (None, Some(ks)) => (ks, "Ks, no Kd"),
        (None, None) => ([0.5; 3], "grey 0.5, no Kd"),
    };
    let Some(name) = &m.texture else {
        return (base, from.to_string());
    };
    match files.texture(name).and_then(|bytes| texture_mean(&bytes)) {
        Ok(mean) => {
            let rho = std::array::from_fn(|i| (base[i] * mean[i]).clamp(0.0, 1.0));
            (rho, format!("{from} x mean of {name}"))
        }
        Err(why) => (base, format!("{from}; texture {name} not read: {why}")),
    }
}

/// The mean linear RGB of a PNG image (sRGB-decoded, alpha ignored).
fn texture_mean(bytes: &[u8]) -> Result<[f32; 3], String> {
    if !bytes.starts_with(b"\x89PNG") {
        return Err("only PNG textures are read".into());
    }
    let mut decoder = png::Decoder::new(std::io::Cursor::new(bytes));
    decoder.set_transformations(png::Transformations::EXPAND | png::Transformations::STRIP_16);
    let mut reader = decoder.read_info().map_err(|e| e.to_string())?;
    let mut buf = vec![0; reader.output_buffer_size().ok_or("image too large")?];
    let info = reader.next_frame(&mut buf).map_err(|e| e.to_string())?;
    let channels = info.color_type.samples();
    let pixels = &buf[..info.buffer_size()];
    let linear = |b: u8| {
        let x = f64::from(b) / 255.0;
        if x <= 0.04045 {
            x / 12.92
        } else {
            ((x + 0.055) / 1.055).powf(2.4)
        }
    };
    let mut sum = [0.0f64; 3];
    let mut n = 0usize;
    for px in pixels.chunks_exact(channels) {
        for (c, s) in sum.iter_mut().enumerate() {
            // Grey images have one (or two, with alpha) channels.
            *s += linear(px[if channels >= 3 { c } else { 0 }]);
        }
        n += 1;
    }
    if n == 0 {
        return Err("empty image".into());
    }
    Ok(sum.map(|s| (s / n as f64) as f32))
}

fn out_of_range(file: &str, line: usize, message: &str) -> SceneError {
    SceneError::OutOfRange {
        file: file.into(),
        line,
        message: message.into(),
    }
}

/// Parses `pos (x y z) dir (x y z) up (x y z) fov DEG` (`look (x y z)`, a point looked at, may
/// replace `dir`; the parentheses are optional).
pub fn parse_camera(text: &str) -> Option<Camera> {
    let cleaned: String = text
        .chars()
        .map(|c| if c == '(' || c == ')' { ' ' } else { c })
        .collect();
    let words: Vec<&str> = cleaned.split_whitespace().collect();
    let mut fields: HashMap<&str, Vec<f32>> = HashMap::new();
    let mut key = "";
    for w in words {
        match w.parse::<f32>() {
            Ok(x) if x.is_finite() => fields.entry(key).or_default().push(x),
            Ok(_) => return None,
            Err(_) => key = w,
        }
    }
    let v = |k: &str| {
        fields
            .get(k)
            .filter(|f| f.len() == 3)
            .map(|f| Vec3::new(f[0], f[1], f[2]))
    };
    let fov = fields.get("fov").filter(|f| f.len() == 1)?[0];
    let dir = v("dir").or_else(|| Some(v("look")? - v("pos")?))?;
    let up = v("up")?;
    (dir.length() > 0.0 && up.cross(dir).length() > 0.0 && fov > 0.0 && fov < 180.0).then_some(
        Camera {
            pos: v("pos")?,
            dir: dir.normalize(),
            up: up.normalize(),
            fov_deg: fov,
        },
    )
}

type Models = (Vec<tobj::Model>, Vec<tobj::Material>);

/// Runs tobj on text that already passed [`check_obj`].
fn run_tobj(
    file: &str,
    text: &str,
    libraries: &HashMap<String, String>,
) -> Result<Models, SceneError> {
    let options = tobj::LoadOptions {
        triangulate: true,
        single_index: false,
        ..Default::default()
    };
    let loader = |p: &std::path::Path| {
        let name = p.to_string_lossy();
        match libraries.get(name.as_ref()) {
            Some(body) => tobj::load_mtl_buf(&mut BufReader::new(body.as_bytes())),
            None => Err(tobj::LoadError::OpenFileFailed),
        }
    };
    let (models, materials) =
        tobj::load_obj_buf(&mut BufReader::new(text.as_bytes()), &options, loader).map_err(
            |e| SceneError::Obj {
                file: file.into(),
                message: e.to_string(),
            },
        )?;
    let materials = materials.map_err(|e| SceneError::Obj {
        file: file.into(),
        message: e.to_string(),
    })?;
    Ok((models, materials))
}

/// Converts tobj models into objects and triangles, dropping degenerate triangles.
fn collect_triangles(
    scene: &mut Scene,
    models: &[tobj::Model],
    materials: &[tobj::Material],
    diffuse: &HashMap<String, [f32; 3]>,
) {
    let mut object_of: HashMap<(String, Option<usize>), u32> = HashMap::new();
    let positions: Vec<Vec<Vec3>> = models
        .iter()
        .map(|m| {
            m.mesh
                .positions
                .chunks_exact(3)
                .map(|p| Vec3::new(p[0], p[1], p[2]))
                .collect()
        })
        .collect();
    let scale = positions
        .iter()
        .flatten()
        .fold(0.0f32, |s, p| s.max(p.abs().max_element()))
        .max(1e-30);
    for (model, pos) in models.iter().zip(&positions) {
        let key = (model.name.clone(), model.mesh.material_id);
        let object = *object_of.entry(key).or_insert_with(|| {
            scene.objects.push(object_for(model, materials, diffuse));
            scene.objects.len() as u32 - 1
        });
        let mesh = &model.mesh;
        // Only when every corner has one (tobj lists normals for the corners that give them).
        let with_normals = mesh.normal_indices.len() == mesh.indices.len();
        let normal = |k: usize| {
            if !with_normals {
                return None;
            }
            let i = *mesh.normal_indices.get(k)? as usize;
            let n = mesh.normals.get(3 * i..3 * i + 3)?;
            Some(Vec3::new(n[0], n[1], n[2]))
        };
        for (t, f) in mesh.indices.chunks_exact(3).enumerate() {
            let tri = Tri::new(pos[f[0] as usize], pos[f[1] as usize], pos[f[2] as usize]);
            if tri.cross().length() <= 1e-12 * scale * scale || !tri.cross().is_finite() {
                scene.dropped_degenerate += 1;
                continue;
            }
            scene.triangles.push(SceneTri { tri, object });
            let hint = (0..3)
                .map(|k| normal(3 * t + k))
                .sum::<Option<Vec3>>()
                .filter(|n| n.is_finite())
                .map_or(Vec3::ZERO, Vec3::normalize_or_zero);
            if hint != Vec3::ZERO {
                scene
                    .normal_hints
                    .resize(scene.triangles.len() - 1, Vec3::ZERO);
                scene.normal_hints.push(hint);
            }
        }
    }
}

/// Builds an [`Object`] for a tobj model (grey 0.5 when it has no material).
fn object_for(
    model: &tobj::Model,
    materials: &[tobj::Material],
    diffuse: &HashMap<String, [f32; 3]>,
) -> Object {
    let material = model.mesh.material_id.and_then(|i| materials.get(i));
    let v = |a: Option<[f32; 3]>, d: f32| a.map(Vec3::from).unwrap_or(Vec3::splat(d));
    let name = if model.name.is_empty() {
        "unnamed".to_string()
    } else {
        model.name.clone()
    };
    Object {
        name,
        reflectance: v(
            material.and_then(|m| diffuse.get(&m.name).copied().or(m.diffuse)),
            0.5,
        ),
        emission: v(material.and_then(|m| m.emissive), 0.0),
    }
}

/// The default scene: the measured Cornell box, embedded in the binary.
pub mod cornell {
    /// OBJ text of `scenes/cornell-box.obj`.
    pub const OBJ: &str = include_str!("../../scenes/cornell-box.obj");
    /// MTL text of `scenes/cornell-box.mtl`.
    pub const MTL: &str = include_str!("../../scenes/cornell-box.mtl");
    /// OBJ text of `scenes/cornell-empty.obj` (the box without its blocks).
    pub const EMPTY_OBJ: &str = include_str!("../../scenes/cornell-empty.obj");

    /// Returns the Cornell box with each quad (an object of two triangles) split into an
    /// `n × n` grid of cells, two triangles each (`n = 18` gives the 10,368 triangles of the
    /// throughput benchmark in `BENCHMARKS.md`).
    pub fn grid_triangles(n: u32) -> Result<Vec<crate::geom::Tri>, super::SceneError> {
        let scene = load(true)?;
        let mut out = Vec::new();
        for o in 0..scene.objects.len() as u32 {
            let tris: Vec<_> = scene
                .triangles
                .iter()
                .filter(|t| t.object == o)
                .map(|t| t.tri)
                .collect();
            if let [t0, t1] = tris.as_slice() {
                let q = [t0.v[0], t0.v[1], t0.v[2], t1.v[2]];
                let at = |i: u32, j: u32| {
                    let (u, v) = (i as f32 / n as f32, j as f32 / n as f32);
                    q[0] * (1.0 - u) * (1.0 - v)
                        + q[1] * u * (1.0 - v)
                        + q[2] * u * v
                        + q[3] * (1.0 - u) * v
                };
                for i in 0..n {
                    for j in 0..n {
                        let (a, b, c, d) = (at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1));
                        out.push(crate::geom::Tri::new(a, b, c));
                        out.push(crate::geom::Tri::new(a, c, d));
                    }
                }
            } else {
                out.extend(tris);
            }
        }
        Ok(out)
    }

    /// Loads the embedded Cornell box (with the blocks when `blocks` is true).
    pub fn load(blocks: bool) -> Result<super::Scene, super::SceneError> {
        let (name, text) = if blocks {
            ("cornell-box.obj", OBJ)
        } else {
            ("cornell-empty.obj", EMPTY_OBJ)
        };
        super::load_obj(name, text, &|lib| {
            if lib == "cornell-box.mtl" {
                Ok(MTL.to_string())
            } else {
                Err("not embedded".into())
            }
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn lib(_: &str) -> Result<String, String> {
        Ok("newmtl l\nKe 1 1 1\nKd 0.5 0.5 0.5\n".into())
    }

    #[test]
    fn cornell_box_loads_with_camera_and_light() {
        let scene = cornell::load(true).expect("cornell");
        assert_eq!(scene.objects.len(), 16);
        assert_eq!(scene.triangles.len(), 32);
        let cam = scene.camera.expect("camera");
        assert_eq!(cam.pos, Vec3::new(278.0, 273.0, -800.0));
        let light = scene
            .objects
            .iter()
            .find(|o| o.name == "light")
            .expect("light");
        assert_eq!(light.emission, Vec3::new(17.0, 12.0, 4.0));
    }

    #[test]
    fn errors_name_the_line() {
        let bad = "mtllib x.mtl\nv 0 0 0\nv 1 nan 0\n";
        assert!(matches!(
            load_obj("s.obj", bad, &lib),
            Err(SceneError::BadNumber { line: 3, .. })
        ));
        let out = "mtllib x.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n";
        assert!(matches!(
            load_obj("s.obj", out, &lib),
            Err(SceneError::FaceIndexOutOfRange {
                line: 5,
                index: 4,
                count: 3,
                ..
            })
        ));
        let missing = "v 0 0 0\nmtllib nope.mtl\n";
        let err = load_obj("s.obj", missing, &|_| Err("no such file".into()));
        assert!(matches!(
            err,
            Err(SceneError::MissingMaterialLibrary { line: 2, .. })
        ));
    }

    #[test]
    fn degenerate_triangles_are_dropped_and_counted() {
        let text = "mtllib x.mtl\nusemtl l\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 2 0 0\nf 1 2 3\nf 1 2 4\n";
        let scene = load_obj("s.obj", text, &lib).expect("scene");
        assert_eq!(scene.triangles.len(), 1);
        assert_eq!(scene.dropped_degenerate, 1);
    }

    #[test]
    fn no_emitters_is_an_error() {
        let text = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
        assert!(matches!(
            load_obj("s.obj", text, &lib),
            Err(SceneError::NoEmitters { .. })
        ));
    }

    /// A one-triangle scene whose light uses material `mat` from library `lib.mtl`.
    fn one_triangle(mat: &str) -> String {
        format!("mtllib lib.mtl\nusemtl {mat}\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")
    }

    struct Mem(Vec<(&'static str, Vec<u8>)>);

    impl Files for Mem {
        fn library(&self, name: &str) -> Result<String, String> {
            self.texture(name).map(|b| decode(&b).0)
        }
        fn texture(&self, name: &str) -> Result<Vec<u8>, String> {
            self.0
                .iter()
                .find(|f| f.0 == name)
                .map(|f| f.1.clone())
                .ok_or_else(|| format!("no {name}"))
        }
    }

    fn reflectance(mtl: &str, extra: Vec<(&'static str, Vec<u8>)>) -> (Vec3, Vec<String>) {
        let mut files = vec![("lib.mtl", mtl.as_bytes().to_vec())];
        files.extend(extra);
        let scene = load_obj_with("s.obj", &one_triangle("m"), &Mem(files)).expect("scene");
        (scene.objects[0].reflectance, scene.left_out)
    }

    #[test]
    fn non_diffuse_materials_become_diffuse_with_a_note() {
        let (rho, notes) = reflectance(
            "newmtl m\nKe 1 1 1\nKd 0.2 0.3 0.4\nKs 0.5 0.5 0.5\n",
            vec![],
        );
        assert_eq!(rho, Vec3::new(0.2, 0.3, 0.4));
        assert!(
            notes.iter().any(|n| n.contains("m (specular; Kd)")),
            "{notes:?}"
        );
        // A mirror without Kd takes its Ks.
        let (rho, notes) = reflectance("newmtl m\nKe 1 1 1\nKs 0.9 0.9 0.9\n", vec![]);
        assert_eq!(rho, Vec3::splat(0.9));
        assert!(notes.iter().any(|n| n.contains("Ks, no Kd")), "{notes:?}");
        // Glass: transmissive and transparent, Kd kept.
        let (rho, notes) = reflectance(
            "newmtl m\nKe 1 1 1\nKd 0.1 0.1 0.1\nTf 0.5 0.5 0.5\nd 0.5\n",
            vec![],
        );
        assert_eq!(rho, Vec3::splat(0.1));
        assert!(
            notes
                .iter()
                .any(|n| n.contains("transmissive, transparent")),
            "{notes:?}"
        );
        // A diffuse material gets no note.
        let (_, notes) = reflectance("newmtl m\nKe 1 1 1\nKd 0.1 0.1 0.1\nKs 0 0 0\n", vec![]);
        assert!(notes.is_empty(), "{notes:?}");
    }

    #[test]
    fn a_readable_texture_counts_by_its_mean_and_an_unreadable_one_by_kd() {
        // 2 x 1 pixels: sRGB 255 (linear 1) and 0: mean 0.5 in every channel.
        let png = crate::output::encode_png(&[255, 255, 255, 0, 0, 0], 2, 1).expect("png");
        let mtl = "newmtl m\nKe 1 1 1\nKd 0.8 0.8 0.8\nmap_Kd -s 1 1 1 tex.png\n";
        let (rho, notes) = reflectance(mtl, vec![("tex.png", png)]);
        assert!((rho - Vec3::splat(0.4)).abs().max_element() < 1e-6, "{rho}");
        assert!(
            notes.iter().any(|n| n.contains("mean of tex.png")),
            "{notes:?}"
        );
        let mtl = "newmtl m\nKe 1 1 1\nKd 0.8 0.8 0.8\nmap_Kd tex.jpg\n";
        let (rho, notes) = reflectance(mtl, vec![("tex.jpg", vec![0xff, 0xd8, 0xff])]);
        assert_eq!(rho, Vec3::splat(0.8));
        assert!(notes.iter().any(|n| n.contains("only PNG")), "{notes:?}");
        let (rho, notes) = reflectance(mtl, vec![]);
        assert_eq!(rho, Vec3::splat(0.8));
        assert!(
            notes.iter().any(|n| n.contains("not read: no tex.jpg")),
            "{notes:?}"
        );
    }

    #[test]
    fn crlf_and_latin1_files_load() {
        let lf = "# caf\u{e9}\nmtllib lib.mtl\no caf\u{e9}\nusemtl m\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
        let latin1: Vec<u8> = lf.chars().map(|c| c as u8).collect();
        let (text, was_latin1) = decode(&latin1);
        assert!(was_latin1);
        let crlf = text.replace('\n', "\r\n");
        let mtl = Mem(vec![(
            "lib.mtl",
            b"newmtl m\r\nKe 1 1 1\r\nKd 0.5 0.5 0.5\r\n".to_vec(),
        )]);
        let scene = load_obj_with("s.obj", &crlf, &mtl).expect("scene");
        assert_eq!(scene.triangles.len(), 1);
        assert_eq!(scene.objects[0].name, "caf\u{e9}");
        assert_eq!(scene.objects[0].emission, Vec3::ONE);
    }

    #[test]
    fn vertex_normals_are_kept_per_triangle_as_hints() {
        // Two triangles facing +z; the first has vertex normals against its winding.
        let text = "mtllib lib.mtl\nusemtl m\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nvn 0 0 -1\n\
                    vn 0 0 1\nf 1//1 2//1 3//1\nf 2//2 4//2 3//2\n";
        let mtl = Mem(vec![("lib.mtl", b"newmtl m\nKe 1 1 1\n".to_vec())]);
        let scene = load_obj_with("s.obj", text, &mtl).expect("scene");
        assert_eq!(scene.triangles.len(), 2);
        assert!(scene.triangles[0].tri.normal().z > 0.0);
        assert_eq!(scene.normal_hints[0], Vec3::NEG_Z);
        assert_eq!(scene.normal_hints[1], Vec3::Z);
    }

    #[test]
    fn unknown_statements_are_counted_and_listed() {
        let text = format!("{}l 1 2\nl 2 3\ncurv 0 1 1 2\n", one_triangle("m"));
        let files = Mem(vec![("lib.mtl", b"newmtl m\nKe 1 1 1\nPwr 100\n".to_vec())]);
        let scene = load_obj_with("s.obj", &text, &files).expect("scene");
        let notes = scene.left_out.join("\n");
        assert!(
            notes.contains("s.obj:7: `l` statements ignored (2)"),
            "{notes}"
        );
        assert!(notes.contains("`curv` statements ignored (1)"), "{notes}");
        assert!(
            notes.contains("lib.mtl:3: `Pwr` statements ignored (1)"),
            "{notes}"
        );
    }

    #[test]
    fn material_libraries_are_searched_beside_the_scene_then_in_order_naming_every_path() {
        let root = std::env::temp_dir().join(format!("occ-mtl-search-{}", std::process::id()));
        let (a, b) = (root.join("a"), root.join("b"));
        std::fs::create_dir_all(&a).expect("dir");
        std::fs::create_dir_all(&b).expect("dir");
        std::fs::write(b.join("lib.mtl"), "newmtl m\nKe 1 1 1\n").expect("write");
        let files = SearchFiles {
            folders: vec![a.clone(), b.clone()],
        };
        assert!(load_obj_with("s.obj", &one_triangle("m"), &files).is_ok());
        let err = load_obj_with(
            "s.obj",
            &one_triangle("m").replace("lib.mtl", "nope.mtl"),
            &files,
        )
        .expect_err("missing");
        let text = err.to_string();
        assert!(
            text.contains(&a.join("nope.mtl").display().to_string()),
            "{text}"
        );
        assert!(
            text.contains(&b.join("nope.mtl").display().to_string()),
            "{text}"
        );
        assert_eq!(
            SearchFiles::beside(&a.join("scene.obj")).folders,
            vec![a.clone(), std::path::PathBuf::from(".")]
        );
        let _ = std::fs::remove_dir_all(&root);
    }

    #[test]
    fn the_camera_comment_takes_a_point_to_look_at() {
        let cam = parse_camera(" pos 0 0 -5 look 0 0 0 up 0 1 0 fov 40").expect("camera");
        assert_eq!(cam.dir, Vec3::Z);
        assert!(parse_camera("pos 0 0 0 look 0 0 0 up 0 1 0 fov 40").is_none());
    }
}
