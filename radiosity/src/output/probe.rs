//! Probes: `x y z nx ny nz` per line in, B (RGB) out: gathered at the point from every patch's
//! radiosity ([`crate::gather`]), and as the solution mesh interpolates it there. The surface
//! at the point is the element in the plane of the point, facing the same way, that contains it
//! or comes closest.

use glam::Vec3;

use super::OutputError;
use crate::gather::Gather;
use crate::solver::Solver;

/// A probe point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Probe {
    /// Position.
    pub pos: Vec3,
    /// Surface normal (need not be unit).
    pub normal: Vec3,
}

/// Parses a probe file (blank lines and `#` comments skipped).
pub fn parse_probes(file: &str, text: &str) -> Result<Vec<Probe>, OutputError> {
    let mut out = Vec::new();
    for (i, raw) in text.lines().enumerate() {
        let line = raw.split('#').next().unwrap_or("").trim();
        if line.is_empty() {
            continue;
        }
        let err = |message: String| OutputError::Probe {
            file: file.into(),
            line: i + 1,
            message,
        };
        let nums: Vec<f32> = line
            .split(|c: char| c.is_whitespace() || c == ',')
            .filter(|w| !w.is_empty())
            .map(|w| {
                w.parse::<f32>()
                    .ok()
                    .filter(|x| x.is_finite())
                    .ok_or_else(|| err(format!("`{w}` is not a finite number")))
            })
            .collect::<Result<_, _>>()?;
        if nums.len() != 6 {
            return Err(err(format!(
                "expected 6 numbers `x y z nx ny nz`, found {}",
                nums.len()
            )));
        }
        let normal = Vec3::new(nums[3], nums[4], nums[5]);
        if normal.length() == 0.0 {
            return Err(err("the normal is zero".into()));
        }
        out.push(Probe {
            pos: Vec3::new(nums[0], nums[1], nums[2]),
            normal: normal.normalize(),
        });
    }
    Ok(out)
}

/// Returns B (RGB) at the probe as the mesh interpolates it (linearly, from the radiosity at the
/// corners of the element holding it), or `None` when no surface faces that way near the point.
pub fn evaluate(solver: &Solver, probe: &Probe) -> Option<Vec3> {
    let (i, bary) = surface_at(solver, probe)?;
    let b = solver.element_corner_radiosity(i, Vec3::ZERO);
    Some(b[0] * bary[0] + b[1] * bary[1] + b[2] * bary[2])
}

/// Returns B (RGB) at the probe gathered from the patches of `gather` (`solver`'s:
/// [`Gather::irradiance`]), `seed` choosing the samples; `None` as for [`evaluate`].
pub fn gathered(solver: &Solver, gather: &Gather, probe: &Probe, seed: u64) -> Option<Vec3> {
    let (i, _) = surface_at(solver, probe)?;
    let object = &solver.scene.objects[solver.mesh.elements[i].object as usize];
    let h = gather.irradiance(probe.pos, probe.normal, seed);
    Some(object.radiosity(h).as_vec3())
}

/// The element of the surface at the probe and the probe's barycentric coordinates in it (of
/// the element's point closest to it), or `None` when no element facing the probe's way lies
/// within a thousandth of the scene's diagonal.
fn surface_at(solver: &Solver, probe: &Probe) -> Option<(usize, [f32; 3])> {
    let mesh = &solver.mesh;
    let mut best: Option<(f32, usize, [f32; 3])> = None;
    for (i, e) in mesh.elements.iter().enumerate() {
        let t = mesh.tri(e);
        if t.normal().dot(probe.normal) < 0.9 {
            continue;
        }
        let d = (t.closest_point(probe.pos) - probe.pos).length();
        if best.is_none_or(|b| d < b.0) {
            let bary = t.barycentric(t.closest_point(probe.pos));
            best = Some((d, i, bary));
        }
    }
    let (d, i, bary) = best?;
    (d <= 1e-3 * solver.scene.diagonal()).then_some((i, bary))
}

/// A probe's B: gathered ([`gathered`]) and as the mesh interpolates it ([`evaluate`]); both
/// `None` when no surface matched.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ProbeValue {
    /// The probe.
    pub probe: Probe,
    /// B gathered at the point.
    pub b: Option<Vec3>,
    /// B as the mesh interpolates it.
    pub mesh: Option<Vec3>,
}

/// Each probe's [`ProbeValue`], the solver's seed choosing the gather's samples (each probe
/// its own).
pub fn values(solver: &Solver, probes: &[Probe]) -> Vec<ProbeValue> {
    let gather = Gather::new(solver);
    (probes.iter().enumerate())
        .map(|(i, &probe)| {
            let seed = solver.config().seed ^ (i as u64) << 32;
            ProbeValue {
                probe,
                b: gathered(solver, &gather, &probe, seed),
                mesh: evaluate(solver, &probe),
            }
        })
        .collect()
}

/// Returns `probe.csv`: `x,y,z,nx,ny,nz,b_r,b_g,b_b,mesh_r,mesh_g,mesh_b`, B gathered at each
/// probe and as the mesh interpolates it ([`values`]); empty where no surface matched.
pub fn probe_csv(values: &[ProbeValue]) -> String {
    let mut s = String::from("x,y,z,nx,ny,nz,b_r,b_g,b_b,mesh_r,mesh_g,mesh_b\n");
    let rgb = |b: Option<Vec3>| b.map_or(",,".to_string(), |b| format!("{},{},{}", b.x, b.y, b.z));
    for v in values {
        let (p, n) = (v.probe.pos, v.probe.normal);
        s += &format!(
            "{},{},{},{},{},{},{},{}\n",
            p.x,
            p.y,
            p.z,
            n.x,
            n.y,
            n.z,
            rgb(v.b),
            rgb(v.mesh)
        );
    }
    s
}
