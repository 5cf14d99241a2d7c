//! Scene loading: Wavefront OBJ + MTL through `tobj`, checked line by line first so that every
//! malformed input is reported with its file and line (tobj's own errors carry no line).
//!
//! Conventions: `Kd` is the diffuse reflectance, `Ke` the emitted radiance (RGB), object names come
//! from `o` or `g`, and a comment line `# camera: pos (x y z) dir (x y z) up (x y z) fov DEG` gives
//! the view used for `image.png`. The loader takes text, never paths: the caller supplies the OBJ
//! text and a function that returns the text of a named material library.

use std::collections::HashMap;
use std::io::BufReader;

use glam::Vec3;

use crate::geom::Tri;

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
/// library named by `mtllib` (or a reason why it cannot).
pub fn load_obj(
    file: &str,
    obj_text: &str,
    library: &dyn Fn(&str) -> Result<String, String>,
) -> Result<Scene, SceneError> {
    let mut checked = check_obj(file, obj_text, library)?;
    let (models, materials) = run_tobj(file, obj_text, &checked.libraries)?;
    let mut scene = Scene {
        camera: checked.camera,
        left_out: std::mem::take(&mut checked.left_out),
        ..Scene::default()
    };
    collect_triangles(&mut scene, &models, &materials);
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
}

/// Checks every OBJ line that we rely on and every library it names.
fn check_obj(
    file: &str,
    text: &str,
    library: &dyn Fn(&str) -> Result<String, String>,
) -> Result<Checked, SceneError> {
    let mut out = Checked {
        camera: None,
        libraries: HashMap::new(),
        left_out: Vec::new(),
    };
    let mut materials: Vec<String> = Vec::new();
    let mut vertices = 0usize;
    let (mut normals, mut texcoords) = (false, false);
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
                parse_numbers(file, line, words, 3)?;
                vertices += 1;
            }
            Some("vn") => normals = true,
            Some("vt") => texcoords = true,
            Some("f") => check_face(file, line, words, vertices)?,
            Some("mtllib") => {
                let name = words.collect::<Vec<_>>().join(" ");
                let body = library(&name).map_err(|reason| SceneError::MissingMaterialLibrary {
                    file: file.into(),
                    line,
                    name: name.clone(),
                    reason,
                })?;
                materials.extend(check_mtl(&name, &body, &mut out.left_out)?);
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
            _ => {}
        }
    }
    if normals {
        out.left_out.push(
            "vertex normals (vn) ignored: radiosity uses the geometric normal of each face".into(),
        );
    }
    if texcoords {
        out.left_out
            .push("texture coordinates (vt) ignored: textures are not supported".into());
    }
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

/// Checks a material library's `Kd`/`Ke` lines; returns the material names it defines.
fn check_mtl(
    file: &str,
    text: &str,
    left_out: &mut Vec<String>,
) -> Result<Vec<String>, SceneError> {
    let mut names = Vec::new();
    for (i, raw) in text.lines().enumerate() {
        let line = i + 1;
        let mut words = raw.split_whitespace();
        match words.next() {
            Some("newmtl") => names.push(words.collect::<Vec<_>>().join(" ")),
            Some("Kd") => {
                let kd = parse_numbers(file, line, words, 3)?;
                if kd.iter().any(|&x| !(0.0..=1.0).contains(&x)) {
                    return Err(out_of_range(
                        file,
                        line,
                        "a reflectance Kd must lie in [0, 1]",
                    ));
                }
            }
            Some("Ke") => {
                let ke = parse_numbers(file, line, words, 3)?;
                if ke.iter().any(|&x| x < 0.0) {
                    return Err(out_of_range(
                        file,
                        line,
                        "an emission Ke must not be negative",
                    ));
                }
            }
            Some(key) if key.starts_with("map_") || key == "bump" || key == "disp" => {
                left_out.push(format!(
                    "{file}:{line}: `{key}` ignored: textures are not supported"
                ));
            }
            Some("Ks" | "Ns" | "Ni" | "Tf" | "Tr" | "d" | "illum") => {
                let msg = format!(
                    "{file}:{line}: non-diffuse parameters ignored: radiosity is diffuse only"
                );
                if !left_out.contains(&msg)
                    && !left_out
                        .iter()
                        .any(|m| m.starts_with(file) && m.contains("non-diffuse"))
                {
                    left_out.push(msg);
                }
            }
            _ => {}
        }
    }
    Ok(names)
}

fn out_of_range(file: &str, line: usize, message: &str) -> SceneError {
    SceneError::OutOfRange {
        file: file.into(),
        line,
        message: message.into(),
    }
}

/// Parses `pos (x y z) dir (x y z) up (x y z) fov DEG`.
fn parse_camera(text: &str) -> Option<Camera> {
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
    let dir = v("dir")?;
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
fn collect_triangles(scene: &mut Scene, models: &[tobj::Model], materials: &[tobj::Material]) {
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
            scene.objects.push(object_for(model, materials));
            scene.objects.len() as u32 - 1
        });
        for f in model.mesh.indices.chunks_exact(3) {
            let tri = Tri::new(pos[f[0] as usize], pos[f[1] as usize], pos[f[2] as usize]);
            if tri.cross().length() <= 1e-12 * scale * scale || !tri.cross().is_finite() {
                scene.dropped_degenerate += 1;
            } else {
                scene.triangles.push(SceneTri { tri, object });
            }
        }
    }
}

/// Builds an [`Object`] for a tobj model (grey 0.5 when it has no material).
fn object_for(model: &tobj::Model, materials: &[tobj::Material]) -> Object {
    let material = model.mesh.material_id.and_then(|i| materials.get(i));
    let v = |a: Option<[f32; 3]>, d: f32| a.map(Vec3::from).unwrap_or(Vec3::splat(d));
    let name = if model.name.is_empty() {
        "unnamed".to_string()
    } else {
        model.name.clone()
    };
    Object {
        name,
        reflectance: v(material.and_then(|m| m.diffuse), 0.5),
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
    /// throughput benchmark in the notes §5).
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
}
