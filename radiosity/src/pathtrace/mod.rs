//! The ground truth: a Monte Carlo path tracer for diffuse scenes, independent of the solver (its
//! own `f64` geometry and [`bvh::Bvh`], no form factors, no octree, no mesh). It estimates
//!
//! - each object's mean radiosity `B̄ = (1/A) ∫ B dA` (RGB), by sampling points uniformly over the
//!   object's area, and
//! - the radiosity `B(x)` at probe points,
//!
//! each with its standard error (the sample standard deviation over `√N`; samples are
//! independent).
//!
//! At a point `x` of an object with emitted radiance `Lₑ` and reflectance `ρ`,
//! `B(x) = π Lₑ + ρ H(x)`, and the irradiance `H(x) = ∫ L cos θ dω` is estimated along one path:
//! at each vertex, next-event estimation samples a point on an emitter (chosen in proportion to
//! area × emitted radiance) with a shadow ray; the path continues in a cosine-distributed
//! direction, whose estimator of the reflected part is `ρ(y) H(y)` at the point `y` it hits.
//! Emission is counted both ways, combined by the balance heuristic (Veach 1997), which keeps
//! every contribution below `π Lₑ` and the variance finite. Russian roulette ends paths after
//! the third vertex without bias.
//!
//! The conventions are the solver's: surfaces are one-sided (a ray meeting the back of a
//! triangle ends there: backs neither reflect nor emit), emitters emit from their front only, and
//! an open scene loses what leaves it.

pub mod bvh;

use glam::{DVec3, Vec3};
use rayon::prelude::*;

use crate::output::probe::Probe;
use crate::rng::Pcg32;
use crate::scene::Scene;
use bvh::{Bvh, Triangle};

/// Settings of a path-traced estimate.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct PathTraceConfig {
    /// Paths (surface points) per object, and per probe.
    pub samples: u64,
    /// Seed; the estimate is a pure function of the scene, the settings and the seed.
    pub seed: u64,
    /// Hard limit on path length (Russian roulette ends nearly all paths long before; the bias
    /// is below `ρ_max^max_bounces`).
    pub max_bounces: u32,
}

impl Default for PathTraceConfig {
    fn default() -> Self {
        PathTraceConfig {
            samples: 1 << 16,
            seed: 1,
            max_bounces: 1000,
        }
    }
}

/// A Monte Carlo estimate of an RGB quantity.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Estimate {
    /// The sample mean.
    pub mean: [f64; 3],
    /// Its standard error (sample standard deviation / √samples).
    pub std_err: [f64; 3],
    /// Samples.
    pub samples: u64,
}

/// Running mean and sum of squared deviations of samples (Welford's update; Chan et al.'s
/// merge of two parts), exact for constant samples.
#[derive(Clone, Copy, Debug, Default)]
struct Sums {
    n: u64,
    mean: DVec3,
    m2: DVec3,
}

impl Sums {
    fn add(&mut self, x: DVec3) {
        self.n += 1;
        let delta = x - self.mean;
        self.mean += delta / self.n as f64;
        self.m2 += delta * (x - self.mean);
    }

    fn merge(self, o: Sums) -> Sums {
        if self.n == 0 || o.n == 0 {
            return if self.n == 0 { o } else { self };
        }
        let n = self.n + o.n;
        let delta = o.mean - self.mean;
        Sums {
            n,
            mean: self.mean + delta * (o.n as f64 / n as f64),
            m2: self.m2 + o.m2 + delta * delta * (self.n as f64 * o.n as f64 / n as f64),
        }
    }

    fn estimate(&self) -> Estimate {
        let n = self.n.max(1) as f64;
        let var = self.m2 / (n - 1.0).max(1.0);
        Estimate {
            mean: self.mean.to_array(),
            std_err: (var / n).max(DVec3::ZERO).powf(0.5).to_array(),
            samples: self.n,
        }
    }
}

/// Paths per parallel work unit (each has its own random stream, so results do not depend on
/// the number of threads).
const CHUNK: u64 = 1024;

/// The path tracer over one scene.
pub struct PathTracer<'a> {
    scene: &'a Scene,
    bvh: Bvh,
    /// Per triangle: reflectance and emitted radiance of its object.
    rho: Vec<DVec3>,
    emission: Vec<DVec3>,
    /// Emitting triangles and the cumulative distribution choosing them.
    lights: Vec<u32>,
    light_cdf: Vec<f64>,
    /// Per object: its triangles and the cumulative area over them.
    object_tris: Vec<(Vec<u32>, Vec<f64>)>,
    /// Ray parameters below this (scene units) do not count as hits.
    eps: f64,
}

impl<'a> PathTracer<'a> {
    /// Prepares the scene: triangles in `f64`, the hierarchy, emitter and area distributions.
    pub fn new(scene: &'a Scene) -> PathTracer<'a> {
        let d = |v: Vec3| v.as_dvec3();
        let tris: Vec<Triangle> = scene
            .triangles
            .iter()
            .map(|t| Triangle::new(d(t.tri.v[0]), d(t.tri.v[1]), d(t.tri.v[2])))
            .collect();
        let object = |i: usize| &scene.objects[scene.triangles[i].object as usize];
        let rho = (0..tris.len()).map(|i| d(object(i).reflectance)).collect();
        let emission: Vec<DVec3> = (0..tris.len()).map(|i| d(object(i).emission)).collect();
        let mut lights = Vec::new();
        let mut light_cdf = Vec::new();
        let mut total = 0.0;
        for (i, t) in tris.iter().enumerate() {
            let weight = t.area * emission[i].element_sum();
            if weight > 0.0 {
                total += weight;
                lights.push(i as u32);
                light_cdf.push(total);
            }
        }
        let mut object_tris = vec![(Vec::new(), Vec::new()); scene.objects.len()];
        for (i, t) in scene.triangles.iter().enumerate() {
            let (ids, cdf) = &mut object_tris[t.object as usize];
            let before = cdf.last().copied().unwrap_or(0.0);
            ids.push(i as u32);
            cdf.push(before + tris[i].area);
        }
        PathTracer {
            scene,
            eps: 1e-9 * scene.diagonal() as f64,
            bvh: Bvh::build(tris),
            rho,
            emission,
            lights,
            light_cdf,
            object_tris,
        }
    }

    /// Estimates each object's mean radiosity (index = object index; objects with no area get
    /// an estimate of zero from zero samples).
    pub fn object_means(&self, config: &PathTraceConfig) -> Vec<Estimate> {
        let chunks = config.samples.div_ceil(CHUNK);
        let work: Vec<(usize, u64)> = (0..self.scene.objects.len())
            .filter(|&o| self.object_tris[o].1.last().is_some_and(|&a| a > 0.0))
            .flat_map(|o| (0..chunks).map(move |c| (o, c)))
            .collect();
        let sums: Vec<(usize, Sums)> = work
            .par_iter()
            .map(|&(o, c)| {
                let mut rng = Pcg32::new(config.seed ^ (c << 24), 2 * o as u64 + 1);
                let mut s = Sums::default();
                for _ in 0..CHUNK.min(config.samples - c * CHUNK) {
                    let (tri, x) = self.sample_object(o, &mut rng);
                    s.add(self.radiosity(x, tri, config, &mut rng));
                }
                (o, s)
            })
            .collect();
        let mut per_object = vec![Sums::default(); self.scene.objects.len()];
        for (o, s) in sums {
            per_object[o] = per_object[o].merge(s);
        }
        per_object.iter().map(Sums::estimate).collect()
    }

    /// Estimates the radiosity at each probe: `None` when no surface lies within 1e-3 of the
    /// scene diagonal of the point facing the probe's way (the rule `probe.csv` uses).
    pub fn probes(&self, probes: &[Probe], config: &PathTraceConfig) -> Vec<Option<Estimate>> {
        probes
            .par_iter()
            .enumerate()
            .map(|(i, p)| {
                let tri = self.surface_at(p)?;
                let x = p.pos.as_dvec3();
                let mut s = Sums::default();
                let mut rng = Pcg32::new(config.seed, 0x9e37_79b9 + 2 * i as u64);
                for _ in 0..config.samples {
                    s.add(self.radiosity(x, tri, config, &mut rng));
                }
                Some(s.estimate())
            })
            .collect()
    }

    /// The triangle a probe lies on: the nearest one facing its way, within 1e-3 of the diagonal.
    fn surface_at(&self, p: &Probe) -> Option<u32> {
        let n = p.normal.as_dvec3();
        let x = p.pos.as_dvec3();
        let (mut best, mut dist) = (None, 1e-3 * self.scene.diagonal() as f64);
        for (i, t) in self.scene.triangles.iter().enumerate() {
            if self.bvh.tris[i].normal.dot(n) < 0.9 {
                continue;
            }
            let d = (t.tri.closest_point(p.pos).as_dvec3() - x).length();
            if d <= dist {
                (best, dist) = (Some(i as u32), d);
            }
        }
        best
    }

    /// A point uniformly distributed over object `o`'s area, and its triangle.
    fn sample_object(&self, o: usize, rng: &mut Pcg32) -> (u32, DVec3) {
        let (ids, cdf) = &self.object_tris[o];
        let i = pick(cdf, rng);
        let tri = ids[i];
        (
            tri,
            self.bvh.tris[tri as usize].sample(f64_of(rng), f64_of(rng)),
        )
    }

    /// One path's estimate of `B(x) = π Lₑ + ρ H(x)` at `x` on triangle `tri` (front side).
    fn radiosity(&self, x: DVec3, tri: u32, config: &PathTraceConfig, rng: &mut Pcg32) -> DVec3 {
        let t = tri as usize;
        let mut b = self.emission[t] * std::f64::consts::PI;
        if self.rho[t] != DVec3::ZERO {
            b += self.rho[t] * self.irradiance(x, tri, config, rng);
        }
        b
    }

    /// One path's estimate of the irradiance at `x` on the front of triangle `tri`.
    pub fn irradiance(
        &self,
        mut x: DVec3,
        mut tri: u32,
        config: &PathTraceConfig,
        rng: &mut Pcg32,
    ) -> DVec3 {
        let mut h = DVec3::ZERO;
        let mut weight = DVec3::ONE;
        for bounce in 0..config.max_bounces {
            let n = self.bvh.tris[tri as usize].normal;
            h += weight * self.direct(x, n, tri, rng);
            let d = cosine_direction(n, rng);
            let Some((s, hit)) = self.bvh.closest(x, d, self.eps, f64::INFINITY, Some(tri)) else {
                break;
            };
            let cos_y = -self.bvh.tris[hit as usize].normal.dot(d);
            if cos_y <= 0.0 {
                break; // the back of a surface: black
            }
            // Emission met by the cosine-sampled direction, weighted against next-event
            // estimation by the balance heuristic (both densities per solid angle).
            let emitted = self.emission[hit as usize];
            if emitted != DVec3::ZERO {
                let p_light = self.light_density(hit) * s * s / cos_y;
                let cos_x = n.dot(d);
                h += weight * emitted * (cos_x / (cos_x / std::f64::consts::PI + p_light));
            }
            weight *= self.rho[hit as usize];
            if bounce >= 2 {
                let q = weight.max_element().min(0.95);
                if q <= 0.0 || f64_of(rng) >= q {
                    break;
                }
                weight /= q;
            }
            x += d * s;
            tri = hit;
        }
        h
    }

    /// The density per unit area with which next-event estimation picks a point of emitting
    /// triangle `j` (emitters are chosen in proportion to area × emitted radiance).
    fn light_density(&self, j: u32) -> f64 {
        let total = self.light_cdf.last().copied().unwrap_or(0.0);
        self.emission[j as usize].element_sum() / total
    }

    /// Next-event estimate of the irradiance at `(x, n)` straight from the emitters, weighted
    /// against cosine sampling by the balance heuristic (so that it stays below `π Lₑ` however
    /// close the emitter: plain area sampling has infinite variance at an emitter's edge).
    fn direct(&self, x: DVec3, n: DVec3, tri: u32, rng: &mut Pcg32) -> DVec3 {
        if self.lights.is_empty() {
            return DVec3::ZERO;
        }
        let j = self.lights[pick(&self.light_cdf, rng)];
        let light = &self.bvh.tris[j as usize];
        let y = light.sample(f64_of(rng), f64_of(rng));
        let r = y - x;
        let len2 = r.length_squared();
        let len = len2.sqrt();
        let (cos_x, cos_y) = (n.dot(r) / len, -light.normal.dot(r) / len);
        if cos_x <= 0.0 || cos_y <= 0.0 || j == tri {
            return DVec3::ZERO;
        }
        let margin = self.eps / len;
        if self
            .bvh
            .occluded(x, r, margin, 1.0 - margin, [Some(tri), Some(j)])
        {
            return DVec3::ZERO;
        }
        let p_light = self.light_density(j) * len2 / cos_y;
        self.emission[j as usize] * (cos_x / (cos_x / std::f64::consts::PI + p_light))
    }
}

/// Picks an index with probability proportional to the steps of the cumulative `cdf`.
fn pick(cdf: &[f64], rng: &mut Pcg32) -> usize {
    let total = cdf[cdf.len() - 1];
    let u = f64_of(rng) * total;
    cdf.partition_point(|&c| c <= u).min(cdf.len() - 1)
}

/// A uniform `f64` in [0, 1) with 53 random bits.
fn f64_of(rng: &mut Pcg32) -> f64 {
    let hi = (rng.next_u32() >> 5) as u64;
    let lo = (rng.next_u32() >> 6) as u64;
    ((hi << 26) | lo) as f64 * (1.0 / (1u64 << 53) as f64)
}

/// A direction about the unit normal `n` with density `cos θ / π` (Malley's method, on an
/// orthonormal basis built as Duff et al. 2017 do).
fn cosine_direction(n: DVec3, rng: &mut Pcg32) -> DVec3 {
    let sign = 1f64.copysign(n.z);
    let a = -1.0 / (sign + n.z);
    let b = n.x * n.y * a;
    let t = DVec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x);
    let s = DVec3::new(b, sign + n.y * n.y * a, -n.y);
    let r = f64_of(rng).sqrt();
    let phi = 2.0 * std::f64::consts::PI * f64_of(rng);
    let (x, y) = (r * phi.cos(), r * phi.sin());
    let z = (1.0 - x * x - y * y).max(0.0).sqrt();
    t * x + s * y + n * z
}
