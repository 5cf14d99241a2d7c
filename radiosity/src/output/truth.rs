//! The path-traced ground truth as a file (`pathtrace.json`, and the references stored beside the
//! scenes), and the solver's error against it (the `truth` section of `report.json`).
//!
//! A reference file is read by `--reference` like any `report.json`: its `objects` carry `name`
//! and `mean_b`; they also carry `std_err`, and the file says how it was made (`command`).

use glam::{DVec3, Vec3};
use serde::{Deserialize, Serialize};

use super::OutputError;
use super::probe::{Probe, ProbeValue};
use crate::pathtrace::{Estimate, PathTraceConfig};
use crate::scene::Scene;

/// One object's path-traced mean radiosity.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ObjectTruth {
    /// OBJ `o`/`g` name.
    pub name: String,
    /// Area in scene units squared.
    pub area: f64,
    /// Mean radiosity B (RGB).
    pub mean_b: [f64; 3],
    /// Standard error of `mean_b`.
    pub std_err: [f64; 3],
}

/// One probe's path-traced radiosity.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ProbeTruth {
    /// Position.
    pub pos: [f32; 3],
    /// Unit normal.
    pub normal: [f32; 3],
    /// B (RGB) and its standard error; `None` when no surface faces that way at the point.
    pub b: Option<Estimate>,
}

/// A path-traced reference.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Reference {
    /// What made it.
    pub tool: String,
    /// The command line that made it.
    pub command: String,
    /// Scene file.
    pub scene: String,
    /// Settings.
    pub samples_per_object: u64,
    /// Seed.
    pub seed: u64,
    /// Seconds taken (wall clock).
    pub seconds: f64,
    /// Per object, in scene order.
    pub objects: Vec<ObjectTruth>,
    /// Per probe, in file order.
    pub probes: Vec<ProbeTruth>,
}

impl Reference {
    /// Assembles a reference from the path tracer's estimates.
    pub fn new(
        scene: (&str, &Scene),
        command: &str,
        config: &PathTraceConfig,
        seconds: f64,
        objects: &[Estimate],
        probes: &[(Probe, Option<Estimate>)],
    ) -> Reference {
        let areas = object_areas(scene.1);
        Reference {
            tool: "occ radiosity --pathtrace".into(),
            command: command.into(),
            scene: scene.0.into(),
            samples_per_object: config.samples,
            seed: config.seed,
            seconds,
            objects: scene
                .1
                .objects
                .iter()
                .zip(objects)
                .zip(areas)
                .map(|((o, e), area)| ObjectTruth {
                    name: o.name.clone(),
                    area,
                    mean_b: e.mean,
                    std_err: e.std_err,
                })
                .collect(),
            probes: probes
                .iter()
                .map(|(p, b)| ProbeTruth {
                    pos: p.pos.to_array(),
                    normal: p.normal.to_array(),
                    b: *b,
                })
                .collect(),
        }
    }

    /// Parses a reference file.
    pub fn parse(file: &str, text: &str) -> Result<Reference, OutputError> {
        serde_json::from_str(text).map_err(|e| OutputError::Reference {
            file: file.into(),
            message: format!("not a path-traced reference: {e}"),
        })
    }

    /// The probes of a reference file read by `--reference`: a path-traced reference's (it
    /// names its `tool`); none from a `report.json`, whose `probes` are its errors.
    pub fn probes_of(file: &str, text: &str) -> Result<Vec<ProbeTruth>, OutputError> {
        let err = |message: String| OutputError::Reference {
            file: file.into(),
            message,
        };
        let value: serde_json::Value =
            serde_json::from_str(text).map_err(|e| err(format!("not JSON: {e}")))?;
        match value.get("probes") {
            _ if value.get("tool").is_none() => Ok(Vec::new()),
            None => Ok(Vec::new()),
            Some(probes) => serde_json::from_value(probes.clone())
                .map_err(|e| err(format!("its `probes` are not a path tracer's: {e}"))),
        }
    }

    /// The reference's object of this name.
    pub fn object(&self, name: &str) -> Option<&ObjectTruth> {
        self.objects.iter().find(|o| o.name == name)
    }

    /// How far a solver's mean of `object`'s channel `c` may be from this reference: 1% of the
    /// reference's mean, 2% where the channel is below a tenth of the scene's area-weighted mean
    /// (the light included: a dim face), plus three of the reference's standard errors.
    pub fn tolerance(&self, object: &ObjectTruth, c: usize) -> f64 {
        let area: f64 = self.objects.iter().map(|o| o.area).sum();
        let mean = (self.objects.iter())
            .map(|o| o.area * o.mean_b[c])
            .sum::<f64>()
            / area;
        let share = if object.mean_b[c] < 0.1 * mean {
            0.02
        } else {
            0.01
        };
        share * object.mean_b[c] + 3.0 * object.std_err[c]
    }
}

/// Each object's area, from the scene's triangles (the path tracer samples them).
fn object_areas(scene: &Scene) -> Vec<f64> {
    let mut areas = vec![0.0; scene.objects.len()];
    for t in &scene.triangles {
        areas[t.object as usize] += t.tri.area() as f64;
    }
    areas
}

/// One object's solver result against the truth.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ObjectError {
    /// Object name.
    pub name: String,
    /// The solver's mean B.
    pub mean_b: [f64; 3],
    /// The path-traced mean B.
    pub reference_b: [f64; 3],
    /// Its standard error.
    pub reference_std_err: [f64; 3],
    /// `mean_b / reference_b - 1` per channel (0 where the reference is 0).
    pub relative_error: [f64; 3],
}

/// The solver's means (per object, scene order) against the truth, matched by name.
pub fn object_errors(names: &[String], means: &[DVec3], truth: &Reference) -> Vec<ObjectError> {
    names
        .iter()
        .zip(means)
        .filter_map(|(name, b)| {
            let t = truth.object(name)?;
            let rel = |c: usize| {
                if t.mean_b[c] > 0.0 {
                    b[c] / t.mean_b[c] - 1.0
                } else {
                    0.0
                }
            };
            Some(ObjectError {
                name: name.clone(),
                mean_b: b.to_array(),
                reference_b: t.mean_b,
                reference_std_err: t.std_err,
                relative_error: [rel(0), rel(1), rel(2)],
            })
        })
        .collect()
}

/// One probe's B against the truth.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ProbeError {
    /// Position.
    pub pos: [f32; 3],
    /// Unit normal.
    pub normal: [f32; 3],
    /// B gathered at the probe ([`super::probe::gathered`]).
    pub b: [f64; 3],
    /// B as the mesh interpolates it ([`super::probe::evaluate`]).
    pub mesh_b: [f64; 3],
    /// The path-traced B.
    pub reference_b: [f64; 3],
    /// Its standard error.
    pub reference_std_err: [f64; 3],
    /// `b / reference_b - 1` per channel (0 where the reference is 0).
    pub relative_error: [f64; 3],
    /// `mesh_b / reference_b - 1` per channel.
    pub mesh_relative_error: [f64; 3],
}

/// The probes' B ([`super::probe::values`]) against the truth's `probes`: each probe that
/// both read, matched by position (within a millionth of its size) and normal.
pub fn probe_errors(values: &[ProbeValue], probes: &[ProbeTruth]) -> Vec<ProbeError> {
    let same = |v: &ProbeValue, t: &ProbeTruth| {
        let (pos, normal) = (Vec3::from(t.pos), Vec3::from(t.normal));
        v.probe.pos.distance(pos) <= 1e-6 * (1.0 + pos.abs().max_element())
            && v.probe.normal.dot(normal) > 0.999
    };
    values
        .iter()
        .filter_map(|v| {
            let t = probes.iter().find(|t| same(v, t))?;
            let (est, b, mesh) = (t.b.as_ref()?, v.b?.as_dvec3(), v.mesh?.as_dvec3());
            let rel = |x: DVec3| {
                std::array::from_fn(|c| {
                    if est.mean[c] > 0.0 {
                        x[c] / est.mean[c] - 1.0
                    } else {
                        0.0
                    }
                })
            };
            Some(ProbeError {
                pos: t.pos,
                normal: t.normal,
                b: b.to_array(),
                mesh_b: mesh.to_array(),
                reference_b: est.mean,
                reference_std_err: est.std_err,
                relative_error: rel(b),
                mesh_relative_error: rel(mesh),
            })
        })
        .collect()
}

/// A line on the probes' errors ([`probe_errors`]) for the terminal: how many, the worst
/// channel gathered and by the mesh.
pub fn probe_summary(errors: &[ProbeError]) -> String {
    let worst = |f: fn(&ProbeError) -> [f64; 3]| {
        errors
            .iter()
            .flat_map(f)
            .fold(0.0f64, |w, x| if x.abs() > w.abs() { x } else { w })
    };
    format!(
        "probes: {} against the path tracer, worst channel {:+.2}% gathered ({:+.2}% by the mesh)\n",
        errors.len(),
        100.0 * worst(|e| e.relative_error),
        100.0 * worst(|e| e.mesh_relative_error)
    )
}

/// A plain-text table of [`object_errors`] (percentages), for the terminal.
pub fn error_table(errors: &[ObjectError]) -> String {
    let mut s = format!(
        "{:<24} {:>27} {:>27} {:>23}\n",
        "object", "solver B (R G B)", "path-traced B (R G B)", "error % (R G B)"
    );
    for e in errors {
        let f = |v: [f64; 3]| format!("{:8.4} {:8.4} {:8.4}", v[0], v[1], v[2]);
        let p = e.relative_error.map(|x| x * 100.0);
        s += &format!(
            "{:<24} {:>27} {:>27} {:>7.2} {:>7.2} {:>7.2}\n",
            e.name,
            f(e.mean_b),
            f(e.reference_b),
            p[0],
            p[1],
            p[2]
        );
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    fn truth(pos: [f32; 3], mean: [f64; 3]) -> ProbeTruth {
        ProbeTruth {
            pos,
            normal: [0.0, 1.0, 0.0],
            b: Some(Estimate {
                mean,
                std_err: [0.001; 3],
                samples: 1,
            }),
        }
    }

    #[test]
    fn a_probe_is_held_to_the_path_tracer_s_at_its_point_and_normal() {
        let value = |x: f32, normal: Vec3| ProbeValue {
            probe: Probe {
                pos: Vec3::new(x, 0.0, 0.0),
                normal,
            },
            b: Some(Vec3::new(0.5, 0.25, 0.0)),
            mesh: Some(Vec3::new(0.25, 0.25, 0.125)),
        };
        let values = [
            value(1.0, Vec3::Y),
            value(2.0, Vec3::Y),
            value(3.0, -Vec3::Y),
        ];
        // in another order, one probe the values lack, and one facing the other way
        let probes = [
            truth([2.0, 0.0, 0.0], [1.0, 0.25, 0.0]),
            truth([1.0, 0.0, 0.0], [0.25, 0.5, 0.25]),
            truth([3.0, 0.0, 0.0], [0.5, 0.5, 0.5]),
            truth([4.0, 0.0, 0.0], [0.5, 0.5, 0.5]),
        ];
        let errors = probe_errors(&values, &probes);
        assert_eq!(errors.len(), 2);
        assert_eq!(errors[0].pos, [1.0, 0.0, 0.0]);
        assert_eq!(errors[0].relative_error, [1.0, -0.5, -1.0]);
        assert_eq!(errors[0].mesh_relative_error, [0.0, -0.5, -0.5]);
        // (a channel the path tracer found dark counts 0)
        assert_eq!(errors[1].relative_error, [-0.5, 0.0, 0.0]);
        assert!(probe_summary(&errors).contains("+100.00% gathered (-75.00% by the mesh)"));
    }
}
