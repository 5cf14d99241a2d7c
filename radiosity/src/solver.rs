//! The sequential reference solver: progressive refinement radiosity (Cohen et al. 1988) with
//! ray-cast vertex-to-source form factors (Wallace et al. 1989).
//!
//! Each shot takes the patch with the most unshot power, computes the form factor from every
//! sample point to it ([`crate::kernels::shoot_batch`]), refines edges where the shot's
//! contribution changes fast and is not linear, and books the power:
//! - each element receives `A_e · ΔB_src · mean(F)`, its mean taken from the form factors at the
//!   vertices exactly for quadratic fields ([`crate::quadrature`]);
//! - it absorbs `(1 - ρ)` of that and adds `ρ` of it to its own unshot power (a patch's is the
//!   sum over its elements, and a patch shoots from where its elements hold it:
//!   [`SourceDensity`]; each channel from where its own power is when the light a patch
//!   received is not of one colour all over it: [`channels_differ`]);
//! - what no element received is booked as *escaped* (through openings, plus form-factor error).
//!
//! Accounts are kept in `f64` so that `emitted = absorbed + escaped + unshot` holds to rounding.

use std::time::Instant;

use glam::{DVec3, Vec3};
use rayon::prelude::*;

use crate::analysis::{self, SceneAnalysis, Stages};
use crate::convergence::{Cadence, Errors};
use crate::estimate::{self, Tally};
use crate::formfactor::{DensitySet, FormFactorConfig, SourceDensity, channels_differ};
use crate::geom::Tri;
use crate::kernels::{SamplePoint, shoot_batch_sets, shoot_batch_visibility};
use crate::mesh::Mesh;
use crate::octree::{Octree, OctreeConfig};
use crate::overshoot::{self, Acceleration};
use crate::quadrature::{ElementMeans, MeanRule};
use crate::refine;
use crate::scene::Scene;

/// Cells per side of the grid that tabulates a shooting patch's unshot radiosity
/// ([`SourceDensity`]): finer than the elements of a patch at the default sizes (a patch is
/// about five elements across), so each element's share is seen.
pub const DENSITY_GRID: u32 = 24;

/// The default [`SolverConfig::full_rays_power`]. The noise a shot leaves at a sample point
/// is in proportion to its power over the square root of its rays, so the rays that buy the
/// least noise overall are in proportion to each shot's power. The first shots (the lights and
/// the brightest patches) carry several percent each and keep all their rays; the hundreds of
/// shots that finish a solve carry hundredths of a percent each and cast one ray to each far
/// receiver. On the Cornell box at the defaults this takes about half the time, with the large
/// surfaces' answers as close to the path-traced reference (`radiosity/REFERENCES.md`).
pub const FULL_RAYS_POWER: f64 = 0.01;

/// Receivers per batch of a shot: each batch draws its receivers' samples from one generator.
pub const RECEIVER_BATCH: usize = 256;

/// The seed of the generator that receiver `i` of a shot from `seed` draws its samples from,
/// and its place in that generator's batch (the set of samples it takes): the solver's batches
/// and a node program's receivers, wherever they are, draw the same samples.
pub fn receiver_seed(seed: u64, i: usize) -> (u64, usize) {
    let batch = (i / RECEIVER_BATCH) as u64;
    (seed.wrapping_add(batch * 7919), i % RECEIVER_BATCH)
}

/// Shadow rays per far form factor ([`FormFactorConfig::far_rays`]) for a shot carrying
/// `share` of the emitted power ([`shot_share`]): `rays` when `share` is at least
/// `full_rays_power`, fewer in proportion below, at least one. The solver and `RAD.SHOT.RAYS`
/// both ask this.
pub fn far_rays(rays: u32, share: f64, full_rays_power: f64) -> u32 {
    let rays = rays.max(1);
    if share >= full_rays_power {
        return rays;
    }
    ((f64::from(rays) * share / full_rays_power).round() as u32).clamp(1, rays)
}

/// A shot's share of the emitted power, in the channel where it is largest: `max |shot_c| /
/// emitted_c` over channels that emit (0 when none does). Per channel, so that a dim light of
/// a colour no brighter light has keeps its rays: its shots carry all of that colour.
pub fn shot_share(shot: DVec3, emitted: DVec3) -> f64 {
    (0..3)
        .filter(|&c| emitted[c] > 0.0)
        .map(|c| shot[c].abs() / emitted[c])
        .fold(0.0, f64::max)
}

/// When to stop shooting.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub enum Until {
    /// Stop when the unshot power is at most this fraction of the emitted power.
    Unshot(f64),
    /// Stop after this many shots.
    Shots(u64),
    /// Stop after this many seconds.
    Seconds(f64),
    /// Stop when the relative error of every object's mean radiosity is at most this: when
    /// [`Solver::estimated_error`] is at most [`estimate::ERROR_MARGIN`] times it.
    Error(f64),
}

impl std::str::FromStr for Until {
    type Err = String;
    /// Parses `unshot=0.001`, `shots=N`, `time=S` or `error=0.005`.
    fn from_str(s: &str) -> Result<Self, String> {
        let (key, value) = s
            .split_once('=')
            .ok_or_else(|| format!("`{s}`: expected error=F, unshot=F, shots=N or time=S"))?;
        let bad = |_| format!("`{value}` is not a valid number for `{key}`");
        match key {
            "unshot" => value
                .parse::<f64>()
                .map_err(bad)
                .and_then(|v| finite_non_negative(v).map(Until::Unshot)),
            "shots" => value
                .parse::<u64>()
                .map(Until::Shots)
                .map_err(|_| format!("`{value}` is not a shot count")),
            "time" => value
                .parse::<f64>()
                .map_err(bad)
                .and_then(|v| finite_non_negative(v).map(Until::Seconds)),
            "error" => value
                .parse::<f64>()
                .map_err(bad)
                .and_then(|v| finite_non_negative(v).map(Until::Error)),
            _ => Err(format!(
                "unknown stopping rule `{key}` (expected error, unshot, shots or time)"
            )),
        }
    }
}

fn finite_non_negative(v: f64) -> Result<f64, String> {
    if v.is_finite() && v >= 0.0 {
        Ok(v)
    } else {
        Err(format!("{v} must be a finite number >= 0"))
    }
}

/// Adaptive subdivision settings.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct AdaptConfig {
    /// Test an edge when this shot's contributions at its ends differ by more than this fraction
    /// of the local irradiance (gathered so far plus this shot): a steep gradient.
    pub difference: f32,
    /// ... and split it when the contribution at the midpoint departs from the linear
    /// interpolation by more than this fraction of the local irradiance (linearity check).
    pub nonlinearity: f32,
    /// Never split edges shorter than this (scene units).
    pub min_edge: f32,
    /// Only shots carrying at least this fraction of the emitted power refine.
    pub min_shot_power: f64,
    /// Refinement passes per shot (each can halve an edge once more).
    pub passes: u32,
    /// No refinement once the mesh has this many sample points.
    pub max_vertices: usize,
}

/// Solver settings.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct SolverConfig {
    /// Form-factor kernel settings.
    pub form_factor: FormFactorConfig,
    /// Adaptive subdivision; `None` turns it off.
    pub adapt: Option<AdaptConfig>,
    /// Overshooting (over-relaxation) factor: a shot sends `overshoot ×` the unshot power and
    /// leaves the rest (negative beyond 1) as unshot. 1 = plain progressive refinement.
    pub overshoot: f64,
    /// Overshooting by the ambient estimate ([`crate::overshoot`]).
    pub acceleration: Acceleration,
    /// Shots carrying at least this fraction of the emitted power cast `form_factor.rays`
    /// shadow rays per form factor; weaker ones cast fewer to receivers outside the source's
    /// near field, in proportion to their power, and at least one ([`Solver::shot_rays`],
    /// [`FormFactorConfig::far_rays`]). 0: every shot casts them all.
    pub full_rays_power: f64,
    /// Stopping rule.
    pub until: Until,
    /// Hard limit on shots whatever the rule.
    pub max_shots: u64,
    /// Seed of the source sampling.
    pub seed: u64,
    /// Run every stage even where the scene does not need it ([`crate::analysis`]).
    pub all_stages: bool,
    /// Seconds between rows of the convergence record ([`Cadence`]; 0: a row every shot).
    pub record_every: f64,
    /// The octree's shape: how many triangles a leaf (voxel) holds at most. Visibility does
    /// not depend on it (every ray is tested against every triangle it could meet), only the
    /// time a ray takes and, for carm.occ, how finely the geometry can be spread over nodes.
    pub octree: OctreeConfig,
    /// Each channel of a shot from where its own unshot power lies over the source when the
    /// channels lie differently ([`channels_differ`]); false: every channel from the
    /// channels' summed density, as carm.occ shoots (programs/README.md, "Not there yet").
    pub channel_densities: bool,
    /// How an element's received power is taken from its corners' form factors, and an
    /// object's mean from its vertices' irradiance ([`MeanRule`]).
    pub element_means: MeanRule,
    /// Leave the triangles that can hide nothing out of the octree the shadow rays are tested
    /// against ([`crate::analysis::occluders`]: those in faces of the scene's box that face
    /// into it); false: every triangle. carm.occ's voxels are this octree's, so they leave the
    /// same triangles out. `all_stages` keeps them too.
    pub inert_faces: bool,
}

impl Default for SolverConfig {
    fn default() -> Self {
        SolverConfig {
            form_factor: FormFactorConfig::default(),
            adapt: None,
            overshoot: 1.0,
            acceleration: Acceleration::Auto,
            full_rays_power: FULL_RAYS_POWER,
            until: Until::Unshot(0.01),
            max_shots: 1_000_000,
            seed: 1,
            all_stages: false,
            record_every: 0.05,
            octree: OctreeConfig::default(),
            channel_densities: true,
            element_means: MeanRule::Quadratic,
            inert_faces: true,
        }
    }
}

/// Energy accounts (power, in radiosity × area units), per RGB channel.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct Accounts {
    /// Total emitted power Σ E A.
    pub emitted: [f64; 3],
    /// Power absorbed by surfaces.
    pub absorbed: [f64; 3],
    /// Power shot that no surface received.
    pub escaped: [f64; 3],
    /// Power still to be shot.
    pub unshot: [f64; 3],
}

impl Accounts {
    /// Returns `|emitted - absorbed - escaped - unshot| / emitted`, worst channel.
    pub fn balance_error(&self) -> f64 {
        (0..3)
            .map(|c| {
                let e = self.emitted[c];
                if e == 0.0 {
                    0.0
                } else {
                    (e - self.absorbed[c] - self.escaped[c] - self.unshot[c]).abs() / e
                }
            })
            .fold(0.0, f64::max)
    }
}

/// One row of the convergence record.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct ConvergencePoint {
    /// Shots so far.
    pub shots: u64,
    /// Seconds since the solve started.
    pub seconds: f64,
    /// Unshot power / emitted power (sum over channels).
    pub unshot_fraction: f64,
    /// Sample points at this time.
    pub vertices: usize,
    /// The error against the reference, when there is one ([`Solver::errors`]).
    pub errors: Option<Errors>,
}

/// Counters of a solve.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct SolveStats {
    /// Shots.
    pub shots: u64,
    /// Form factors computed.
    pub form_factors: u64,
    /// Shadow rays cast.
    pub rays: u64,
    /// Form factors that used the analytic form.
    pub analytic_form_factors: u64,
    /// Edges split by adaptive subdivision.
    pub adaptive_splits: u64,
    /// Shots that overshot by the ambient estimate ([`crate::overshoot`]).
    pub overshoots: u64,
    /// Seconds spent shooting.
    pub seconds: f64,
}

/// The state of a progressive refinement solution.
pub struct Solver<'a> {
    /// The scene.
    pub scene: &'a Scene,
    /// The mesh (grows with adaptive subdivision).
    pub mesh: Mesh,
    /// The octree over the scene's triangles (visibility).
    pub octree: Octree,
    /// Irradiance gathered at each sample point (RGB).
    pub irradiance: Vec<Vec3>,
    /// Unshot power of each patch.
    pub unshot: Vec<DVec3>,
    /// Energy accounts.
    pub accounts: Accounts,
    /// Convergence record (rows at the cadence of [`SolverConfig::record_every`], and the last).
    pub history: Vec<ConvergencePoint>,
    /// Counters.
    pub stats: SolveStats,
    /// What the scene's shape showed ([`crate::analysis`]).
    pub analysis: SceneAnalysis,
    /// The stages this solve runs.
    pub stages: Stages,
    /// Reference mean B per object (from `--reference`), `None` for objects it lacks.
    pub reference: Option<Vec<Option<DVec3>>>,
    config: SolverConfig,
    patch_area: Vec<f64>,
    /// Per patch, whether it has shot.
    has_shot: Vec<bool>,
    /// The share of each patch's form-factor row that lands on the backs of sheets, per cell of
    /// its source-density grid (empty: none; [`analysis::back_shares`]): what a closed row
    /// leaves out.
    back_share: Vec<Vec<f32>>,
    element_area: Vec<f64>,
    /// The elements' means of a field at the vertices, fitted to the mesh after each shot's
    /// refinement.
    means: ElementMeans,
    /// Per object: its area and the power its elements have received (before reflection), as
    /// [`Solver::book`] books it: the running tally the stopping rule reads
    /// ([`Solver::estimated_errors`]).
    object_received: Vec<(f64, DVec3)>,
    /// Unshot power of each element (a patch's is the sum over its elements): where on the
    /// patch the power it shoots comes from.
    element_unshot: Vec<DVec3>,
    /// Power shot so far, and the part of it that surfaces received (the rest escaped).
    shot_total: DVec3,
    received_total: DVec3,
}

/// The densities a shot is made with ([`Solver::source_densities`]): the channels summed, and
/// each channel's when they shoot apart.
struct ShotDensities<'d> {
    sum: Option<&'d SourceDensity>,
    channels: Option<[Option<&'d SourceDensity>; 3]>,
}

/// A shot's form factors at the sample points: weighted by the channels' summed density (what
/// refinement tests), and per channel when the channels shoot apart (what is then booked).
struct Factors {
    sum: Vec<f32>,
    channels: Option<Vec<[f32; 3]>>,
}

impl<'a> Solver<'a> {
    /// Prepares a solve: builds the octree and books the emitted power as unshot.
    pub fn new(scene: &'a Scene, mesh: Mesh, config: SolverConfig) -> Solver<'a> {
        let tris: Vec<_> = scene.triangles.iter().map(|t| t.tri).collect();
        let occluders = match config.inert_faces && !config.all_stages {
            true => analysis::occluders(&tris, scene.diagonal()),
            false => tris.clone(),
        };
        let octree = Octree::build(&occluders, config.octree);
        let patch_area: Vec<f64> = mesh.patches.iter().map(|t| t.area() as f64).collect();
        let element_area = mesh
            .elements
            .iter()
            .map(|e| mesh.tri(e).area() as f64)
            .collect();
        let element_area: Vec<f64> = element_area;
        let element_unshot: Vec<DVec3> = mesh
            .elements
            .iter()
            .zip(&element_area)
            .map(|(e, &a)| {
                scene.objects[e.object as usize].emission.as_dvec3() * std::f64::consts::PI * a
            })
            .collect();
        let mut unshot = vec![DVec3::ZERO; mesh.patches.len()];
        for (e, u) in mesh.elements.iter().zip(&element_unshot) {
            unshot[e.patch as usize] += *u;
        }
        let emitted = unshot.iter().fold(DVec3::ZERO, |s, u| s + *u).to_array();
        let hidden = mesh.hidden_patches();
        let (analysis, sheet) =
            SceneAnalysis::with_sheets(&mesh.patches, &hidden, scene.diagonal());
        let back_share = analysis::back_shares(
            &mesh.patches,
            &hidden,
            &sheet,
            scene.diagonal(),
            DENSITY_GRID,
        );
        let means = ElementMeans::new(&mesh, config.element_means);
        let object_received = mesh
            .object_areas(scene.objects.len())
            .into_iter()
            .map(|a| (a, DVec3::ZERO))
            .collect();
        Solver {
            analysis,
            stages: Stages::for_scene(&analysis, config.all_stages, tris.len() - occluders.len()),
            scene,
            irradiance: vec![Vec3::ZERO; mesh.vertices.len()],
            mesh,
            octree,
            unshot,
            accounts: Accounts {
                emitted,
                unshot: emitted,
                ..Accounts::default()
            },
            history: Vec::new(),
            stats: SolveStats::default(),
            reference: None,
            config,
            has_shot: vec![false; patch_area.len()],
            patch_area,
            back_share,
            element_area,
            element_unshot,
            means,
            object_received,
            shot_total: DVec3::ZERO,
            received_total: DVec3::ZERO,
        }
    }

    /// Returns the unshot power as a fraction of the emitted power (channels summed).
    pub fn unshot_fraction(&self) -> f64 {
        let total: f64 = self.accounts.emitted.iter().sum();
        let unshot: f64 = self.unshot.iter().map(|u| u.abs().element_sum()).sum();
        if total > 0.0 { unshot / total } else { 0.0 }
    }

    /// Shoots until the stopping rule holds; `progress(shots, unshot_fraction)` is called after
    /// every shot. Records a row of [`Solver::history`] at the cadence of
    /// [`SolverConfig::record_every`] and after the last shot.
    pub fn run(&mut self, mut progress: impl FnMut(u64, f64)) {
        let start = Instant::now();
        let mut cadence = Cadence::new(self.config.record_every);
        loop {
            let done = match self.config.until {
                Until::Unshot(f) => self.unshot_fraction() <= f,
                Until::Shots(n) => self.stats.shots >= n,
                Until::Seconds(s) => start.elapsed().as_secs_f64() >= s,
                Until::Error(f) => estimate::reached(self.estimated_errors(), f),
            };
            // Under the error rule, a patch never shot shoots before the solve stops
            // ([`Solver::never_shot`]).
            let next = match (done, self.config.until) {
                (false, _) => Some(None),
                (true, Until::Error(_)) => self.never_shot().map(Some),
                (true, _) => None,
            };
            let Some(next) = next else {
                break;
            };
            if self.stats.shots >= self.config.max_shots || !self.shoot_once_from(next) {
                break;
            }
            let seconds = start.elapsed().as_secs_f64();
            if cadence.due(self.stats.shots, seconds) {
                self.record(seconds);
            }
            progress(self.stats.shots, self.unshot_fraction());
        }
        let seconds = start.elapsed().as_secs_f64();
        if self.history.last().map(|p| p.shots) != Some(self.stats.shots) {
            self.record(seconds);
        }
        self.stats.seconds += seconds;
    }

    /// Appends a row to [`Solver::history`] for the state after `seconds` of solving.
    pub fn record(&mut self, seconds: f64) {
        self.history.push(ConvergencePoint {
            shots: self.stats.shots,
            seconds,
            unshot_fraction: self.unshot_fraction(),
            vertices: self.mesh.vertices.len(),
            errors: self.errors(),
        });
    }

    /// Shoots the patch with the most unshot power; returns false when nothing is left.
    pub fn shoot_once(&mut self) -> bool {
        self.shoot_once_from(None)
    }

    /// The patch never shot that holds the most unshot power, if any holds some. The error
    /// estimate ([`crate::estimate`]) spreads the unshot power evenly over the surfaces, but a
    /// patch too small ever to be chosen gives what it holds to its neighbours: the pieces the
    /// table's legs cut from the underside of the table top see the legs' tops with form
    /// factors near 1/2, and the legs, beside twenty such pieces, read 0.9% low at the stop
    /// (radiosity/REFERENCES.md, "A patch never shot"). So before the solve stops on the
    /// error rule, every patch that holds unshot power shoots once (carm.occ's controller
    /// does the same).
    fn never_shot(&self) -> Option<usize> {
        let (best, power) = (self.unshot.iter().enumerate())
            .filter(|(i, _)| !self.has_shot[*i])
            .map(|(i, u)| (i, u.abs().element_sum()))
            .fold((0, 0.0), |b, x| if x.1 > b.1 { x } else { b });
        (power > 0.0).then_some(best)
    }

    /// Shoots `src`, or the patch with the most unshot power.
    fn shoot_once_from(&mut self, src: Option<usize>) -> bool {
        // The ambient irradiance to overshoot by, when overshooting ([`crate::overshoot`]).
        let ambient = (self.config.acceleration)
            .active(self.reflected_share())
            .then(|| self.ambient().as_dvec3());
        let Some(src) = src.or_else(|| self.pick_shooter(ambient)) else {
            return false;
        };
        self.has_shot[src] = true;
        let borrowed = ambient.map_or_else(Vec::new, |a| self.borrow_overshoot(src, a));
        let shot = self.unshot[src] * self.config.overshoot;
        let (density, channels) = self.source_densities(src);
        self.unshot[src] -= shot;
        let keep = 1.0 - self.config.overshoot;
        for (e, u) in self.mesh.elements.iter().zip(&mut self.element_unshot) {
            if e.patch as usize == src {
                *u *= keep;
            }
        }
        let delta_b = (shot / self.patch_area[src]).as_vec3();
        let form_factor = FormFactorConfig {
            far_rays: self.shot_rays(shot),
            ..self.config.form_factor
        };
        let densities = ShotDensities {
            sum: density.as_ref(),
            channels: channels.as_ref().map(|c| c.each_ref().map(Option::as_ref)),
        };
        let factors = self.shoot_all(src, &densities, &form_factor);
        let mut factors = self.refine(src, factors, shot, &densities, &form_factor);
        self.means.fit(&self.mesh);
        if self.stages.close_rows {
            self.close_rows(src, &densities, &mut factors);
        }
        self.book(src, shot, delta_b, &factors);
        self.repay_overshoot(src, &borrowed);
        self.stats.shots += 1;
        true
    }

    /// Scales this shot's form factors so that the receivers get all the power patch `src`
    /// sends but the share that lands on the backs of sheets ([`analysis::row_scale`]; only for
    /// closed scenes).
    fn close_row(&self, src: usize, density: Option<&SourceDensity>, factors: &mut [f32]) {
        let received = self.means.integral(&self.mesh, factors);
        let target = self.patch_area[src] * (1.0 - self.back_share_of(src, density));
        let scale = analysis::row_scale(target, received) as f32;
        factors.iter_mut().for_each(|f| *f *= scale);
    }

    /// [`Solver::close_row`] of the shot's factors, and of each channel's with its own
    /// density when the channels shoot apart.
    fn close_rows(&self, src: usize, densities: &ShotDensities, factors: &mut Factors) {
        self.close_row(src, densities.sum, &mut factors.sum);
        if let (Some(channels), Some(per)) = (densities.channels, factors.channels.as_mut()) {
            for (c, density) in channels.into_iter().enumerate() {
                let mut f: Vec<f32> = per.iter().map(|f| f[c]).collect();
                self.close_row(src, density, &mut f);
                per.iter_mut().zip(f).for_each(|(p, f)| p[c] = f);
            }
        }
    }

    /// The share of each patch's form-factor row that lands on the backs of sheets, per cell
    /// of its source-density grid (empty: none; [`analysis::back_shares`]).
    pub fn back_shares(&self) -> &[Vec<f32>] {
        &self.back_share
    }

    /// The share of a shot from patch `src` that lands on the backs of sheets: its cells'
    /// shares weighted by the shot's source density (uniform without one).
    fn back_share_of(&self, src: usize, density: Option<&SourceDensity>) -> f64 {
        let cells = &self.back_share[src];
        if cells.is_empty() {
            return 0.0;
        }
        let weight = |i: usize| density.map_or(1.0, |d| f64::from(d.cells()[i]));
        let (sum, total) = (0..cells.len()).fold((0.0, 0.0), |(s, w), i| {
            (s + weight(i) * f64::from(cells[i]), w + weight(i))
        });
        if total > 0.0 { sum / total } else { 0.0 }
    }

    /// Adds the overshoot of patch `src` by the ambient irradiance `ambient`
    /// ([`crate::overshoot`]) to its unshot power before it shoots; returns the amount per
    /// element of the patch, for [`Solver::repay_overshoot`] to take away after the shot.
    fn borrow_overshoot(&mut self, src: usize, ambient: DVec3) -> Vec<(usize, DVec3)> {
        let parts: Vec<usize> = (0..self.mesh.elements.len())
            .filter(|&i| self.mesh.elements[i].patch as usize == src)
            .collect();
        let rho_area: Vec<(DVec3, f64)> = parts
            .iter()
            .map(|&i| {
                let object = self.mesh.elements[i].object as usize;
                let rho = self.scene.objects[object].reflectance.as_dvec3();
                (rho, self.element_area[i])
            })
            .collect();
        let amounts = overshoot::element_amounts(ambient, &rho_area);
        for (&i, a) in parts.iter().zip(&amounts) {
            self.element_unshot[i] += *a;
            self.unshot[src] += *a;
        }
        self.stats.overshoots += 1;
        parts.into_iter().zip(amounts).collect()
    }

    /// Takes the overshoot lent by [`Solver::borrow_overshoot`] away again: the patch's unshot
    /// power goes negative by it, and the accounts see it.
    fn repay_overshoot(&mut self, src: usize, borrowed: &[(usize, DVec3)]) {
        if borrowed.is_empty() {
            return;
        }
        for &(i, a) in borrowed {
            self.element_unshot[i] -= a;
            self.unshot[src] -= a;
        }
        let unshot = self.unshot.iter().fold(DVec3::ZERO, |s, u| s + *u);
        self.accounts.unshot = unshot.to_array();
    }

    /// How the unshot radiosity of patch `src` varies over it (its elements' unshot power over
    /// their areas), channels summed (`None` when it is uniform), and per channel when some
    /// channel's departs from the sum's ([`channels_differ`]; `None` when none does).
    fn source_densities(
        &self,
        src: usize,
    ) -> (Option<SourceDensity>, Option<[Option<SourceDensity>; 3]>) {
        let parts: Vec<(Tri, [f32; 4])> = self
            .mesh
            .elements
            .iter()
            .zip(&self.element_unshot)
            .zip(&self.element_area)
            .filter(|((e, _), _)| e.patch as usize == src)
            .map(|((e, u), &a)| {
                let a = a.max(1e-300);
                let d = [u.element_sum(), u.x, u.y, u.z].map(|x| (x / a) as f32);
                (self.mesh.tri(e), d)
            })
            .collect();
        let [sum, r, g, b] =
            SourceDensity::of_parts_sets(&self.mesh.patches[src], DENSITY_GRID, &parts);
        let channels = [r, g, b];
        let apart = self.config.channel_densities && channels_differ(sum.as_ref(), &channels);
        (sum, apart.then_some(channels))
    }

    /// Shadow rays per far form factor ([`FormFactorConfig::far_rays`]) for a shot of `shot`
    /// power ([`far_rays`]).
    pub fn shot_rays(&self, shot: DVec3) -> u32 {
        far_rays(
            self.config.form_factor.rays,
            shot_share(shot, DVec3::from(self.accounts.emitted)),
            self.config.full_rays_power,
        )
    }

    /// The patch with the most power to shoot: its unshot power, plus its overshoot when
    /// overshooting by `ambient` (so that a patch whose unshot power is its own overshoot,
    /// negated, waits for the light that pays it back).
    fn pick_shooter(&self, ambient: Option<DVec3>) -> Option<usize> {
        let over = |i: usize| {
            ambient.map_or(DVec3::ZERO, |a| {
                let object = self.mesh.patch_object[i] as usize;
                overshoot::patch_amount(
                    self.scene.objects[object].reflectance.as_dvec3(),
                    self.patch_area[i],
                    a,
                )
            })
        };
        let (best, power) = self
            .unshot
            .iter()
            .enumerate()
            .map(|(i, u)| (i, (*u + over(i)).abs().element_sum()))
            .fold((0, 0.0), |b, x| if x.1 > b.1 { x } else { b });
        (power > 0.0).then_some(best)
    }

    /// Form factors (weighted by `density`) from every sample point to patch `src`.
    fn shoot_all(
        &mut self,
        src: usize,
        densities: &ShotDensities,
        config: &FormFactorConfig,
    ) -> Factors {
        let points: Vec<SamplePoint> = self.mesh.vertices.iter().map(SamplePoint::from).collect();
        self.shoot_points(src, densities, &points, config)
    }

    fn shoot_points(
        &mut self,
        src: usize,
        densities: &ShotDensities,
        points: &[SamplePoint],
        config: &FormFactorConfig,
    ) -> Factors {
        match densities.channels {
            None => {
                let sum = densities.sum;
                let mut stats = crate::kernels::BatchStats::default();
                let sum =
                    self.shoot_batches(src, points, &mut stats, |source, chunk, seed, out| {
                        shoot_batch_visibility(source.0, source.1, sum, chunk, config, seed, out)
                    });
                self.count(stats);
                Factors {
                    sum,
                    channels: None,
                }
            }
            Some([r, g, b]) => {
                let set = DensitySet::new([densities.sum, r, g, b]);
                let mut stats = crate::kernels::BatchStats::default();
                let sets =
                    self.shoot_batches(src, points, &mut stats, |source, chunk, seed, out| {
                        shoot_batch_sets(source.0, source.1, &set, chunk, config, seed, out)
                    });
                self.count(stats);
                Factors {
                    sum: sets.iter().map(|f| f[0]).collect(),
                    channels: Some(sets.into_iter().map(|[_, r, g, b]| [r, g, b]).collect()),
                }
            }
        }
    }

    /// Runs `batch` over `points` in batches of [`RECEIVER_BATCH`] (in parallel), each with
    /// the octree (none where the scene needs no shadow rays), the source patch `src` and its
    /// batch's seed ([`receiver_seed`]); returns its outputs in order and adds up its
    /// counts into `stats`.
    fn shoot_batches<T: Clone + Default + Send>(
        &self,
        src: usize,
        points: &[SamplePoint],
        stats: &mut crate::kernels::BatchStats,
        batch: impl Fn(
            (Option<&Octree>, &Tri),
            &[SamplePoint],
            u64,
            &mut [T],
        ) -> crate::kernels::BatchStats
        + Sync,
    ) -> Vec<T> {
        let source = self.mesh.patches[src];
        let seed = self.config.seed ^ (self.stats.shots << 20) ^ src as u64;
        let octree = self.stages.shadow_rays.then_some(&self.octree);
        let chunks: Vec<(Vec<T>, crate::kernels::BatchStats)> = points
            .par_chunks(RECEIVER_BATCH)
            .enumerate()
            .map(|(i, chunk)| {
                let mut out = vec![T::default(); chunk.len()];
                let seed = receiver_seed(seed, i * RECEIVER_BATCH).0;
                let stats = batch((octree, &source), chunk, seed, &mut out);
                (out, stats)
            })
            .collect();
        let mut factors = Vec::with_capacity(points.len());
        for (f, s) in chunks {
            factors.extend(f);
            stats.form_factors += s.form_factors;
            stats.rays += s.rays;
            stats.analytic += s.analytic;
        }
        factors
    }

    /// Adds a shot's batch counts to the solve's.
    fn count(&mut self, s: crate::kernels::BatchStats) {
        self.stats.form_factors += s.form_factors;
        self.stats.rays += s.rays;
        self.stats.analytic_form_factors += s.analytic;
    }

    /// Adaptive subdivision for this shot: split edges whose form factors differ strongly and
    /// are not linear along the edge. Returns the factors extended to the new sample points.
    fn refine(
        &mut self,
        src: usize,
        mut factors: Factors,
        shot: DVec3,
        densities: &ShotDensities,
        config: &FormFactorConfig,
    ) -> Factors {
        let Some(adapt) = self.config.adapt else {
            return factors;
        };
        let emitted: f64 = self.accounts.emitted.iter().sum();
        if shot.abs().element_sum() < adapt.min_shot_power * emitted {
            return factors;
        }
        let budget = adapt.max_vertices.max(self.mesh.vertices.len());
        let db = (shot / self.patch_area[src]).as_vec3().element_sum();
        for _ in 0..adapt.passes {
            let mut candidates = self.refinement_candidates(&factors.sum, db, &adapt);
            let room = budget.saturating_sub(self.mesh.vertices.len());
            if candidates.is_empty() || room == 0 {
                break;
            }
            candidates.truncate(room);
            let mids: Vec<SamplePoint> = candidates
                .iter()
                .map(|&(a, b)| self.midpoint(a, b))
                .collect();
            let mid_f = self.shoot_points(src, densities, &mids, config);
            let mut split = 0;
            for (k, (&(a, b), m)) in candidates.iter().zip(&mids).enumerate() {
                let fm = mid_f.sum[k];
                let (fa, fb) = (factors.sum[a as usize], factors.sum[b as usize]);
                let (ia, ib) = (
                    self.irradiance[a as usize].element_sum(),
                    self.irradiance[b as usize].element_sum(),
                );
                let local = refine::local_irradiance(ia, ib, db, fa, fb);
                if !refine::nonlinear(fa, fb, fm, local, db, adapt.nonlinearity) {
                    continue;
                }
                let v = self.split_edge_at_midpoint(a, b);
                debug_assert_eq!(self.mesh.vertices[v as usize].pos, Vec3::from(m.pos));
                factors.sum.push(fm);
                if let (Some(all), Some(mid)) = (factors.channels.as_mut(), &mid_f.channels) {
                    all.push(mid[k]);
                }
                split += 1;
            }
            if split == 0 {
                break;
            }
        }
        factors
    }

    /// The edges to test by a midpoint this shot ([`refine::candidates`]), steepest first.
    fn refinement_candidates(
        &self,
        factors: &[f32],
        db: f32,
        adapt: &AdaptConfig,
    ) -> Vec<(u32, u32)> {
        let irradiance = |v: u32| self.irradiance[v as usize].element_sum();
        let edges = self.mesh.edges().map(|(a, b)| refine::EdgeEnds {
            ends: (a, b),
            length: (self.mesh.vertices[a as usize].pos - self.mesh.vertices[b as usize].pos)
                .length(),
            factors: (factors[a as usize], factors[b as usize]),
            irradiance: (irradiance(a), irradiance(b)),
        });
        let test = refine::EdgeTest {
            difference: adapt.difference,
            min_edge: adapt.min_edge,
        };
        refine::candidates(edges, db, test)
    }

    /// Adds the sample point in the middle of edge `(a, b)` ([`refine::midpoint`]) and splits
    /// the edge there in every element that has it, as adaptive subdivision does; returns the
    /// new point's index. Its irradiance starts as the mean of the ends' (earlier shots are
    /// interpolated along the edge), and the split elements' halves share their unshot power
    /// by area. A host replaying the splits a node program made calls this in their order.
    pub fn split_edge_at_midpoint(&mut self, a: u32, b: u32) -> u32 {
        let m = self.midpoint(a, b);
        let v = self.mesh.add_edge_vertex(a, b, Vec3::from(m.pos));
        self.mesh.vertices[v as usize].eval = Vec3::from(m.eval);
        let h = 0.5 * (self.irradiance[a as usize] + self.irradiance[b as usize]);
        self.irradiance.push(h);
        let before = self.mesh.elements.len();
        let shrunk = self.mesh.split_edge(a, b, v);
        self.fix_split_areas(before, &shrunk);
        self.stats.adaptive_splits += 1;
        v
    }

    fn midpoint(&self, a: u32, b: u32) -> SamplePoint {
        refine::midpoint(
            &SamplePoint::from(&self.mesh.vertices[a as usize]),
            &SamplePoint::from(&self.mesh.vertices[b as usize]),
        )
    }

    /// Recomputes element areas after a split appended elements from index `before` and shrank
    /// the elements `shrunk`.
    /// The appended halves follow the order of `shrunk` ([`Mesh::split_edge`]'s contract); each
    /// half takes its share of the element's unshot power by area.
    fn fix_split_areas(&mut self, before: usize, shrunk: &[u32]) {
        let n = self.mesh.elements.len();
        self.element_area.resize(n, 0.0);
        self.element_unshot.resize(n, DVec3::ZERO);
        for (k, &t) in shrunk.iter().enumerate() {
            let (t, half) = (t as usize, before + k);
            let area = |i: usize| self.mesh.tri(&self.mesh.elements[i]).area() as f64;
            let (a, b) = (area(t), area(half));
            let unshot = self.element_unshot[t];
            let share = if a + b > 0.0 { b / (a + b) } else { 0.5 };
            self.element_unshot[half] = unshot * share;
            self.element_unshot[t] = unshot * (1.0 - share);
            self.element_area[t] = a;
            self.element_area[half] = b;
        }
    }

    /// Books one shot: irradiance at sample points, power into elements, unshot and absorbed.
    /// Each channel takes its own factors when the channels shoot apart ([`Factors`]).
    fn book(&mut self, _src: usize, shot: DVec3, delta_b: Vec3, factors: &Factors) {
        match &factors.channels {
            None => {
                for (h, &f) in self.irradiance.iter_mut().zip(&factors.sum) {
                    *h += delta_b * f;
                }
            }
            Some(per) => {
                for (h, f) in self.irradiance.iter_mut().zip(per) {
                    *h += delta_b * Vec3::from(*f);
                }
            }
        }
        let db = delta_b.as_dvec3();
        let means = match &factors.channels {
            None => self.means.means(&self.mesh, &factors.sum),
            Some(per) => {
                let per: Vec<Vec3> = per.iter().map(|&f| Vec3::from(f)).collect();
                self.means.means(&self.mesh, &per)
            }
        };
        let mut received = DVec3::ZERO;
        let mut absorbed = DVec3::ZERO;
        let elements = self.mesh.elements.iter().zip(&self.element_area);
        for (((e, &area), u), f) in elements.zip(&mut self.element_unshot).zip(means) {
            let power = db * (f * area);
            self.object_received[e.object as usize].1 += power;
            let rho = self.scene.objects[e.object as usize].reflectance.as_dvec3();
            received += power;
            absorbed += power * (DVec3::ONE - rho);
            self.unshot[e.patch as usize] += power * rho;
            *u += power * rho;
        }
        self.book_totals(shot, received, absorbed);
    }

    /// Books a shot's totals into the accounts and the closure of the ambient term: the power
    /// `shot`, the part of it the surfaces `received`, the part of that they `absorbed`. The
    /// patches' unshot power must already hold the shot (a solver driven from outside, as by
    /// carm.occ's host, books each patch's share itself and then calls this).
    pub fn book_totals(&mut self, shot: DVec3, received: DVec3, absorbed: DVec3) {
        self.shot_total += shot;
        self.received_total += received;
        let acc = &mut self.accounts;
        for c in 0..3 {
            acc.absorbed[c] += absorbed[c];
            acc.escaped[c] += shot[c] - received[c];
        }
        let unshot = self.unshot.iter().fold(DVec3::ZERO, |s, u| s + *u);
        acc.unshot = unshot.to_array();
    }

    /// Returns the ambient irradiance: where the unshot power would still go, spread evenly over
    /// the surfaces ([`Tally::ambient`]).
    pub fn ambient(&self) -> Vec3 {
        self.tally().ambient()
    }

    /// [`Solver::ambient`] of the unshot power's magnitude: the same where no power is negative;
    /// a bound on what is still to come where overshooting made some negative.
    fn ambient_bound(&self) -> Vec3 {
        Tally {
            unshot: self.unshot.iter().fold(DVec3::ZERO, |s, u| s + u.abs()),
            ..self.tally()
        }
        .ambient()
    }

    /// The share of shot power that comes back as unshot power, per channel: `c r` of
    /// [`Tally::ambient`] (before the first shot, the area-weighted mean reflectance).
    pub fn reflected_share(&self) -> DVec3 {
        let (c, r) = self.tally().closure();
        c * r
    }

    /// The running totals the error estimate is made of.
    pub fn tally(&self) -> Tally {
        let mut rho = DVec3::ZERO;
        let mut total_area = 0.0;
        for (e, &a) in self.mesh.elements.iter().zip(&self.element_area) {
            rho += self.scene.objects[e.object as usize].reflectance.as_dvec3() * a;
            total_area += a;
        }
        Tally {
            total_area,
            rho_avg: rho / total_area.max(1e-300),
            unshot: self.unshot.iter().fold(DVec3::ZERO, |s, u| s + *u),
            shot: self.shot_total,
            received: self.received_total,
            absorbed: DVec3::from(self.accounts.absorbed),
        }
    }

    /// Estimates each object's relative error: the ambient term's share of its mean radiosity,
    /// `ρ H_amb / (B + ρ H_amb)`, worst channel (objects with no area or reflectance: 0). It
    /// assumes the power still unshot lands evenly; objects far from where it is (a room lit
    /// only through a door, not yet reached) have `B` near 0 and so an estimate near 1, which
    /// keeps the solve going until light reaches them. The means are those of the power each
    /// object's elements have been booked (a running tally, not a pass over the mesh).
    pub fn estimated_errors(&self) -> Vec<f64> {
        let ambient = self.ambient_bound();
        self.means_of(self.object_received.clone())
            .into_iter()
            .zip(&self.scene.objects)
            .map(|((area, b), o)| {
                estimate::object_error(area, b, o.reflectance.as_dvec3(), ambient)
            })
            .collect()
    }

    /// The worst of [`Solver::estimated_errors`].
    pub fn estimated_error(&self) -> f64 {
        self.estimated_errors().into_iter().fold(0.0, f64::max)
    }

    /// Returns the radiosity B = E + ρ (H + ambient) at each corner of element `e`.
    pub fn element_corner_radiosity(&self, e: usize, ambient: Vec3) -> [Vec3; 3] {
        let el = &self.mesh.elements[e];
        let obj = &self.scene.objects[el.object as usize];
        let emitted = obj.emission * std::f32::consts::PI;
        el.v.map(|v| emitted + obj.reflectance * (self.irradiance[v as usize] + ambient))
    }

    /// Returns per-object `(area, mean B)` (area-weighted over elements, each element's mean
    /// of the irradiance at the vertices taken by [`SolverConfig::element_means`]; no ambient
    /// term). (B is linear in the irradiance H, so each object's mean is `E + ρ` times its
    /// mean H.)
    pub fn object_means(&self) -> Vec<(f64, DVec3)> {
        let mut out = vec![(0.0, DVec3::ZERO); self.scene.objects.len()];
        let h = self.element_irradiance();
        for ((e, &a), mean) in self.mesh.elements.iter().zip(&self.element_area).zip(h) {
            let o = &mut out[e.object as usize];
            o.0 += a;
            o.1 += mean * a;
        }
        self.means_of(out)
    }

    /// Each element's mean irradiance (of the irradiance at its vertices, taken by
    /// [`SolverConfig::element_means`]; no ambient term).
    fn element_irradiance(&self) -> Vec<DVec3> {
        let rebuilt;
        let means = if self.means.fits(&self.mesh) {
            &self.means
        } else {
            rebuilt = ElementMeans::new(&self.mesh, self.config.element_means);
            &rebuilt
        };
        means.means(&self.mesh, &self.irradiance)
    }

    /// Each element's mean radiosity `E + ρ H` (its mean irradiance `H` as
    /// [`Solver::object_means`] takes it; no ambient term) and its area.
    pub fn element_radiosity(&self) -> Vec<(DVec3, f64)> {
        let h = self.element_irradiance();
        (self.mesh.elements.iter().zip(h).zip(&self.element_area))
            .map(|((e, h), &a)| (self.scene.objects[e.object as usize].radiosity(h), a))
            .collect()
    }

    /// Each object's area (the sum of its elements').
    pub fn object_areas(&self) -> Vec<f64> {
        let mut out = vec![0.0; self.scene.objects.len()];
        for (e, &a) in self.mesh.elements.iter().zip(&self.element_area) {
            out[e.object as usize] += a;
        }
        out
    }

    /// [`Solver::errors`] of a solution known by the power each object has received so far
    /// (`received[o]`: the sum over its patches of every shot's received power, which is its
    /// irradiance integrated over its area, element by element as [`Solver::object_means`]
    /// integrates it), with its `areas` ([`Solver::object_areas`]). A node program reports the
    /// power its patches receive at every shot but the irradiance at its points only at the
    /// end, so its error rows come from this.
    pub fn errors_of_received(&self, areas: &[f64], received: &[DVec3]) -> Option<Errors> {
        let sums = areas.iter().zip(received).map(|(&a, &r)| (a, r)).collect();
        Errors::of(&self.means_of(sums), self.reference.as_ref()?)
    }

    /// Each object's area and mean B from its area and its irradiance integrated over it.
    fn means_of(&self, sums: Vec<(f64, DVec3)>) -> Vec<(f64, DVec3)> {
        sums.into_iter()
            .zip(&self.scene.objects)
            .map(|((a, s), obj)| {
                (
                    a,
                    if a > 0.0 {
                        obj.radiosity(s / a)
                    } else {
                        DVec3::ZERO
                    },
                )
            })
            .collect()
    }

    /// Returns the error of the objects' means against the reference ([`Errors::of`]); `None`
    /// without a reference, and then the objects' means (which [`Solver::record`] would
    /// otherwise work out at every shot, for nothing) are not worked out.
    pub fn errors(&self) -> Option<Errors> {
        let reference = self.reference.as_ref()?;
        Errors::of(&self.object_means(), reference)
    }

    /// Returns the area-weighted RMS relative error against the reference ([`Errors::rms`]).
    pub fn rms_error(&self) -> Option<f64> {
        self.errors().map(|e| e.rms)
    }

    /// Returns the configuration.
    pub fn config(&self) -> &SolverConfig {
        &self.config
    }
}
