//! `report.json`: scene summary, what was left out, per-object area and mean B, energy totals,
//! settings, timings and per-node / per-link statistics (one node for the reference solver).

use glam::DVec3;
use serde::Serialize;

use super::OutputError;
use crate::mesh::MeshStats;
use crate::octree::OctreeStats;
use crate::solver::{SolveStats, Solver};

/// Scene summary.
#[derive(Clone, Debug, Serialize)]
pub struct SceneSummary {
    /// Scene file name.
    pub file: String,
    /// Objects.
    pub objects: usize,
    /// Input triangles kept.
    pub triangles: usize,
    /// Degenerate triangles dropped.
    pub dropped_degenerate_triangles: usize,
    /// Meshing counts.
    pub mesh: MeshStats,
    /// Sample points at the end (after adaptive subdivision).
    pub final_vertices: usize,
    /// Elements at the end.
    pub final_elements: usize,
    /// Octree shape.
    pub octree: OctreeStats,
}

/// One object's result.
#[derive(Clone, Debug, Serialize)]
pub struct ObjectReport {
    /// OBJ `o`/`g` name.
    pub name: String,
    /// Area in scene units squared.
    pub area: f64,
    /// Mean radiosity B = π × outgoing radiance, RGB (no ambient term).
    pub mean_b: [f64; 3],
}

/// Energy totals (power in B × area units, RGB).
#[derive(Clone, Debug, Serialize)]
pub struct Totals {
    /// Emitted.
    pub emitted: [f64; 3],
    /// Absorbed by surfaces.
    pub absorbed: [f64; 3],
    /// Shot but received by no surface: leaves through openings, plus form-factor error.
    pub escaped: [f64; 3],
    /// Still unshot.
    pub unshot: [f64; 3],
    /// Unshot / emitted (channels summed).
    pub unshot_fraction: f64,
    /// |emitted - absorbed - escaped - unshot| / emitted, worst channel.
    pub energy_balance_error: f64,
}

/// Timings in seconds.
#[derive(Clone, Debug, Default, Serialize)]
pub struct Timings {
    /// Loading the scene.
    pub load: f64,
    /// Meshing.
    pub mesh: f64,
    /// Octree build.
    pub octree: f64,
    /// Solving.
    pub solve: f64,
}

/// Statistics of one node (the reference solver is one node with no links).
#[derive(Clone, Debug, Serialize)]
pub struct NodeReport {
    /// Node number.
    pub node: usize,
    /// Solver counters.
    pub stats: SolveStats,
}

/// The whole report.
#[derive(Clone, Debug, Serialize)]
pub struct Report {
    /// Which solver produced it.
    pub solver: String,
    /// Scene summary.
    pub scene: SceneSummary,
    /// What was left out and why: statements of the scene file the loader skipped, and stages
    /// of the solver the scene does not need ([`crate::analysis::Stages::left_out`]).
    pub left_out: Vec<String>,
    /// What the scene analysis found ([`crate::analysis`]).
    pub analysis: crate::analysis::SceneAnalysis,
    /// The stages the solve ran.
    pub stages: crate::analysis::Stages,
    /// Per object.
    pub objects: Vec<ObjectReport>,
    /// Energy totals.
    pub totals: Totals,
    /// Settings used.
    pub settings: serde_json::Value,
    /// Timings.
    pub timings: Timings,
    /// Per-node statistics.
    pub nodes: Vec<NodeReport>,
    /// Per-link statistics (none for the sequential solver).
    pub links: Vec<serde_json::Value>,
    /// Final area-weighted RMS relative error against the reference (`--reference`,
    /// `--reference-mc`), if given ([`crate::convergence::Errors`]).
    pub rms_error: Option<f64>,
    /// Final largest relative error of any object in any channel against the reference.
    pub max_error: Option<f64>,
    /// Each object's error against the path-traced truth (`--reference-mc`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub truth: Option<Vec<super::truth::ObjectError>>,
    /// Each probe's error against the path tracer's (`--probe` with a reference that has the
    /// same probes: `--reference` a `pathtrace.json`, or `--reference-mc`).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub probes: Vec<super::truth::ProbeError>,
}

/// Builds the report of a finished solve.
pub fn build(solver: &Solver, file: &str, timings: Timings) -> Report {
    let scene = solver.scene;
    let objects = scene
        .objects
        .iter()
        .zip(solver.object_means())
        .map(|(o, (area, b))| ObjectReport {
            name: o.name.clone(),
            area,
            mean_b: b.to_array(),
        })
        .collect();
    let a = solver.accounts;
    let errors = solver.errors();
    let mut left_out = scene.left_out.clone();
    left_out.extend(solver.stages.left_out());
    Report {
        solver: "reference".into(),
        scene: SceneSummary {
            file: file.into(),
            objects: scene.objects.len(),
            triangles: scene.triangles.len(),
            dropped_degenerate_triangles: scene.dropped_degenerate,
            mesh: solver.mesh.stats,
            final_vertices: solver.mesh.vertices.len(),
            final_elements: solver.mesh.elements.len(),
            octree: solver.octree.stats(),
        },
        left_out,
        analysis: solver.analysis,
        stages: solver.stages,
        objects,
        totals: Totals {
            emitted: a.emitted,
            absorbed: a.absorbed,
            escaped: a.escaped,
            unshot: a.unshot,
            unshot_fraction: solver.unshot_fraction(),
            energy_balance_error: a.balance_error(),
        },
        settings: serde_json::to_value(solver.config()).unwrap_or_default(),
        timings,
        nodes: vec![NodeReport {
            node: 0,
            stats: solver.stats,
        }],
        links: Vec::new(),
        rms_error: errors.as_ref().map(|e| e.rms),
        max_error: errors.map(|e| e.max),
        truth: None,
        probes: Vec::new(),
    }
}

/// Reads the per-object mean B of a reference `report.json`, matched to `names` by object name.
pub fn reference_means(
    file: &str,
    text: &str,
    names: &[String],
) -> Result<Vec<Option<DVec3>>, OutputError> {
    let err = |message: String| OutputError::Reference {
        file: file.into(),
        message,
    };
    let value: serde_json::Value =
        serde_json::from_str(text).map_err(|e| err(format!("not JSON: {e}")))?;
    let objects = value
        .get("objects")
        .and_then(|o| o.as_array())
        .ok_or_else(|| err("no `objects` array".into()))?;
    let mut by_name = std::collections::HashMap::new();
    for o in objects {
        let name = o
            .get("name")
            .and_then(|n| n.as_str())
            .ok_or_else(|| err("an object has no `name`".into()))?;
        let b = o
            .get("mean_b")
            .and_then(|b| b.as_array())
            .filter(|b| b.len() == 3);
        let b = b.and_then(|b| b.iter().map(|x| x.as_f64()).collect::<Option<Vec<f64>>>());
        let b = b.ok_or_else(|| err(format!("object `{name}` has no numeric `mean_b` triple")))?;
        by_name.insert(name.to_string(), DVec3::new(b[0], b[1], b[2]));
    }
    if !names.iter().any(|n| by_name.contains_key(n)) {
        return Err(err("no object name matches the scene".into()));
    }
    Ok(names.iter().map(|n| by_name.get(n).copied()).collect())
}

/// Warnings when a reference report does not describe this scene: objects of the scene it
/// lacks, objects it has that the scene lacks, and objects whose areas differ by more than 1%
/// (`objects` gives this scene's names and areas). Unreadable references give no warning here
/// ([`reference_means`] reports them).
pub fn reference_mismatch(file: &str, text: &str, objects: &[(String, f64)]) -> Vec<String> {
    let Ok(value) = serde_json::from_str::<serde_json::Value>(text) else {
        return Vec::new();
    };
    let Some(theirs) = value.get("objects").and_then(|o| o.as_array()) else {
        return Vec::new();
    };
    let theirs: std::collections::HashMap<&str, Option<f64>> = theirs
        .iter()
        .filter_map(|o| {
            let name = o.get("name")?.as_str()?;
            Some((name, o.get("area").and_then(|a| a.as_f64())))
        })
        .collect();
    let mut out = Vec::new();
    let missing: Vec<&str> = objects
        .iter()
        .filter(|(n, _)| !theirs.contains_key(n.as_str()))
        .map(|(n, _)| n.as_str())
        .collect();
    if !missing.is_empty() {
        out.push(format!(
            "{file}: no reference for object(s) {}",
            missing.join(", ")
        ));
    }
    let ours: std::collections::HashSet<&str> = objects.iter().map(|(n, _)| n.as_str()).collect();
    let mut extra: Vec<&str> = theirs
        .keys()
        .copied()
        .filter(|n| !ours.contains(n))
        .collect();
    extra.sort_unstable();
    if !extra.is_empty() {
        out.push(format!(
            "{file}: the reference has object(s) this scene lacks: {}",
            extra.join(", ")
        ));
    }
    for (name, area) in objects {
        if let Some(Some(r)) = theirs.get(name.as_str())
            && (area - r).abs() > 0.01 * r.abs().max(*area)
        {
            out.push(format!(
                "{file}: object {name} has area {area:.4e} here and {r:.4e} in the \
                 reference: a different scene?"
            ));
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_reference_of_another_scene_is_warned_about() {
        let text = r#"{"objects": [{"name": "floor", "area": 100.0, "mean_b": [1, 1, 1]},
                                   {"name": "lamp", "area": 1.0, "mean_b": [1, 1, 1]}]}"#;
        let same = [("floor".to_string(), 100.0), ("lamp".to_string(), 1.0)];
        assert!(reference_mismatch("r.json", text, &same).is_empty());
        let other = [("floor".to_string(), 150.0), ("wall".to_string(), 1.0)];
        let w = reference_mismatch("r.json", text, &other).join("\n");
        assert!(w.contains("no reference for object(s) wall"), "{w}");
        assert!(w.contains("lacks: lamp"), "{w}");
        assert!(w.contains("object floor has area"), "{w}");
    }
}
