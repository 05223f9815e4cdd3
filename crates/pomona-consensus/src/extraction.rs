//! Repeated shape extraction — seed 002 Algorithm 1.
//!
//! One MSAC run finds one shape, but a region-growing cluster may hold several touching fruits.
//! Algorithm 1 therefore repeats: fit, and if the best model passes the acceptance test, record it
//! with its inliers, remove those inliers from the cluster and fit again; stop when the cluster is
//! exhausted or no model passes. [`extract_repeated`] is that loop for any
//! [`Consensus`]/[`Estimator`] pair; [`ShapeExtractor`] runs it with spheres and/or cylinders.
//!
//! ## Sphere or cylinder
//! The paper names both models but picks one per crop (spheres for peppers and guavas, cylinders
//! for eggplants) and does not describe a competition between them. [`ShapeChoice`] offers that
//! per-crop choice, plus [`ShapeChoice::Both`] (our addition): each round fits both and keeps the
//! accepted model with the lower MSAC cost; ties go to the sphere, the simpler model. Two knobs
//! bend that choice: `sphere_preference` keeps the sphere unless the cylinder is cheaper by a
//! margin, and `round_pair_cost_ratio` replaces a cylinder by two spheres when they explain its
//! two halves much better (two touching round fruit under one cylinder).
//!
//! ## Details the paper leaves open
//! * Points with non-finite positions are skipped up front (cylinders also skip points without a
//!   normal); indices in the results always refer to the caller's slice.
//! * The loop also stops once fewer points remain than `min_points`, after `max_shapes` shapes, or
//!   when an accepted model has fewer than `min_inliers` inliers (so it always makes progress).
//! * Each round and shape kind draws from its own ChaCha stream derived from the seed (SplitMix64
//!   of seed and stream number), so results are reproducible and independent of thread count.

use nalgebra::Point3;
use serde::{Deserialize, Serialize};

use crate::{
    Consensus, ConsensusError, Cylinder, CylinderEstimator, CylinderEstimatorParams, Estimator,
    Fit, Msac, MsacParams, OrientedPoint, Positioned, Sampler, Sphere, SphereEstimator,
    SphereEstimatorParams, UniformSampler,
};

/// A model found by repeated extraction, with its inliers (indices into the caller's data).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Extracted<M> {
    /// The accepted model.
    pub model: M,
    /// Indices of its inliers in the input slice, ascending.
    pub inliers: Vec<usize>,
    /// Its consensus cost over the points remaining when it was found (see [`Fit::cost`]).
    pub cost: f64,
}

/// Limits of the repetition in [`extract_repeated`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct RepeatLimits {
    /// Stop when fewer points than this remain (never less than the minimal sample).
    pub min_points: usize,
    /// Discard (and stop at) an accepted model with fewer inliers than this (at least 1).
    pub min_inliers: usize,
    /// Stop after this many shapes.
    pub max_shapes: usize,
}

impl Default for RepeatLimits {
    fn default() -> Self {
        Self {
            min_points: 1,
            min_inliers: 1,
            max_shapes: 64,
        }
    }
}

/// Mixes a base seed with a stream number (SplitMix64 finaliser) for independent sub-streams.
pub(crate) fn derive_seed(seed: u64, stream: u64) -> u64 {
    let mut z = seed ^ stream.wrapping_add(1).wrapping_mul(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// Algorithm 1 for one estimator: fit, accept, remove inliers, repeat. `make_sampler(round)`
/// gives the sampler of each round.
///
/// Data the estimator rejects are skipped. Stops silently when too few points remain.
///
/// # Errors
/// None in practice today (fits on too few points end the loop instead); the `Result` leaves room
/// for consensus loops that can fail.
pub fn extract_repeated<D, C, E, S>(
    consensus: &C,
    estimator: &E,
    data: &[D],
    limits: &RepeatLimits,
    mut make_sampler: impl FnMut(usize) -> S,
) -> Result<Vec<Extracted<E::Model>>, ConsensusError>
where
    D: Clone,
    C: Consensus,
    E: Estimator<D>,
    S: Sampler,
{
    let mut remaining: Vec<usize> = (0..data.len())
        .filter(|&i| estimator.is_datum_valid(&data[i]))
        .collect();
    let mut out = Vec::new();
    let min_points = limits.min_points.max(estimator.min_samples()).max(1);
    let mut round = 0;
    while remaining.len() >= min_points && out.len() < limits.max_shapes {
        let subset: Vec<D> = remaining.iter().map(|&i| data[i].clone()).collect();
        let mut sampler = make_sampler(round);
        round += 1;
        let fit = match consensus.fit(estimator, &subset, &mut sampler) {
            Ok(Some(fit)) => fit,
            Ok(None) | Err(ConsensusError::TooFewPoints { .. }) => break,
            Err(e) => return Err(e),
        };
        if !fit.accepted || fit.inliers.len() < limits.min_inliers.max(1) {
            break;
        }
        out.push(take(fit, &mut remaining));
    }
    Ok(out)
}

/// Turns a fit on `remaining`'s subset into original indices and removes its inliers.
fn take<M>(fit: Fit<M>, remaining: &mut Vec<usize>) -> Extracted<M> {
    let inliers: Vec<usize> = fit.inliers.iter().map(|&k| remaining[k]).collect();
    let mut is_inlier = vec![false; remaining.len()];
    for &k in &fit.inliers {
        is_inlier[k] = true;
    }
    let mut k = 0;
    remaining.retain(|_| {
        let keep = !is_inlier[k];
        k += 1;
        keep
    });
    Extracted {
        model: fit.model,
        inliers,
        cost: fit.cost,
    }
}

/// Which shape models to look for. Written in kebab-case like every other parameter value
/// (`"sphere"`); the capitalised names of older model files are still read.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum ShapeChoice {
    /// Spheres only (peppers, guavas, apples, oranges).
    #[default]
    #[serde(alias = "Sphere")]
    Sphere,
    /// Cylinders only (eggplants); needs normals.
    #[serde(alias = "Cylinder")]
    Cylinder,
    /// Both each round; the accepted one with the lower cost wins.
    #[serde(alias = "Both")]
    Both,
}

/// A fitted fruit shape.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub enum Shape {
    /// A sphere.
    Sphere(Sphere),
    /// A cylinder (with its inliers' extent along the axis).
    Cylinder(Cylinder),
}

impl Shape {
    /// The fruit centre: the sphere centre, or the cylinder's axis midpoint.
    pub fn center(&self) -> nalgebra::Point3<f64> {
        match self {
            Shape::Sphere(s) => s.center,
            Shape::Cylinder(c) => c.midpoint(),
        }
    }

    /// Radius, metres.
    pub fn radius_m(&self) -> f64 {
        match self {
            Shape::Sphere(s) => s.radius_m,
            Shape::Cylinder(c) => c.radius_m,
        }
    }

    /// Signed distance of `p` from the surface (positive outside), metres.
    pub fn signed_distance(&self, p: &nalgebra::Point3<f64>) -> f64 {
        match self {
            Shape::Sphere(s) => s.signed_distance(p),
            Shape::Cylinder(c) => c.signed_distance(p),
        }
    }
}

/// Parameters of [`ShapeExtractor`] (paper defaults inside); validate with
/// [`ShapeExtractionParams::check`].
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct ShapeExtractionParams {
    /// The MSAC loop (T = 25 mm, d = 2 mm, L = 500).
    pub msac: MsacParams,
    /// A different MSAC loop for cylinders, when set (for example without early stopping:
    /// nearly every two-point cylinder sample looks good, so an early stop settles on poor ones).
    #[serde(default)]
    pub cylinder_msac: Option<MsacParams>,
    /// Sphere estimator (radius prior).
    pub sphere: SphereEstimatorParams,
    /// Cylinder estimator (radius prior, optional normal-angle test).
    pub cylinder: CylinderEstimatorParams,
    /// Which models to fit.
    pub shapes: ShapeChoice,
    /// With [`ShapeChoice::Both`], how much a round prefers its sphere: the cylinder is taken
    /// only when its cost is below `(1 − sphere_preference)` times the sphere's (default 0: the
    /// lower cost wins; at most 0.99). A cylinder has more freedom than a sphere and fits a round
    /// fruit with a leaf edge or a stem beside it at a slightly lower cost; a real elongated
    /// fruit is cheaper by far (not in seed 002, which fits one shape per crop).
    #[serde(default)]
    pub sphere_preference: f64,
    /// With [`ShapeChoice::Both`]: a round's cylinder is tested against two spheres, one fitted to
    /// each half of its inliers along the axis, and replaced by them when their summed truncated
    /// cost is below this fraction of the cylinder's — two touching round fruit that one cylinder
    /// spans (default `None`: off; not in seed 002). A straight elongated fruit is fitted better
    /// by its cylinder than by two balls. At most 1.
    #[serde(default)]
    pub round_pair_cost_ratio: Option<f64>,
    /// Repetition limits.
    pub limits: RepeatLimits,
    /// Seed of every random draw (default 0).
    pub seed: u64,
}

impl ShapeExtractionParams {
    /// Whether extraction reads the points' normals: cylinders do (their minimal sample is two
    /// oriented points), and spheres only with a normal-angle test. Without it the shapes found
    /// are the same whether or not normals are given, so a caller may skip estimating them.
    ///
    /// ```
    /// use pomona_consensus::{ShapeChoice, ShapeExtractionParams};
    /// let spheres = ShapeExtractionParams::default();
    /// assert!(!spheres.uses_normals());
    /// let both = ShapeExtractionParams { shapes: ShapeChoice::Both, ..spheres };
    /// assert!(both.uses_normals());
    /// ```
    pub fn uses_normals(&self) -> bool {
        self.shapes != ShapeChoice::Sphere || self.sphere.max_normal_deviation_rad.is_some()
    }

    /// Validates every part into a [`ShapeExtractor`].
    ///
    /// # Errors
    /// [`ConsensusError::InvalidParameter`] from any part, `max_shapes == 0`, a
    /// `sphere_preference` outside `[0, 0.99]` or a `round_pair_cost_ratio` outside `(0, 1]`.
    pub fn check(self) -> Result<ShapeExtractor, ConsensusError> {
        if !(0.0..=0.99).contains(&self.sphere_preference) {
            return Err(ConsensusError::InvalidParameter {
                name: "sphere_preference",
                value: self.sphere_preference,
                reason: "must lie in [0, 0.99]",
            });
        }
        if let Some(ratio) = self.round_pair_cost_ratio {
            crate::consensus::check_fraction("round_pair_cost_ratio", ratio)?;
        }
        if self.limits.max_shapes == 0 {
            return Err(ConsensusError::InvalidParameter {
                name: "limits.max_shapes",
                value: 0.0,
                reason: "must be at least 1",
            });
        }
        Ok(ShapeExtractor {
            msac: self.msac.check()?,
            cylinder_msac: self.cylinder_msac.unwrap_or(self.msac).check()?,
            sphere: self.sphere.check()?,
            cylinder: self.cylinder.check()?,
            params: self,
        })
    }
}

/// Seed 002's MSAC shape detection on one cluster; build with [`ShapeExtractionParams::check`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ShapeExtractor {
    params: ShapeExtractionParams,
    msac: Msac,
    cylinder_msac: Msac,
    sphere: SphereEstimator,
    cylinder: CylinderEstimator,
}

impl ShapeExtractor {
    /// The validated parameters.
    pub fn params(&self) -> &ShapeExtractionParams {
        &self.params
    }

    /// Extracts shapes from one cluster (Algorithm 1), in the order they were found.
    ///
    /// Points with non-finite positions are skipped; cylinders use only points with normals.
    ///
    /// # Errors
    /// [`ConsensusError::TooFewPoints`] when the cluster has fewer valid points than the smallest
    /// minimal sample of the chosen shapes (a cluster that merely yields no shape is `Ok(vec![])`).
    pub fn extract(&self, data: &[OrientedPoint]) -> Result<Vec<Extracted<Shape>>, ConsensusError> {
        let p = &self.params;
        let seed = p.seed;
        let valid = data.iter().filter(|d| d.has_finite_position()).count();
        let needed = match p.shapes {
            ShapeChoice::Sphere => 4,
            ShapeChoice::Cylinder | ShapeChoice::Both => 2,
        };
        if valid < needed {
            return Err(ConsensusError::TooFewPoints {
                what: "shape extraction",
                needed,
                valid,
            });
        }
        let sampler = |round: usize, kind: u64| {
            UniformSampler::new(derive_seed(seed, 2 * round as u64 + kind))
        };
        match p.shapes {
            ShapeChoice::Sphere => {
                Ok(
                    extract_repeated(&self.msac, &self.sphere, data, &p.limits, |r| sampler(r, 0))?
                        .into_iter()
                        .map(|e| Extracted {
                            model: Shape::Sphere(e.model),
                            inliers: e.inliers,
                            cost: e.cost,
                        })
                        .collect(),
                )
            }
            ShapeChoice::Cylinder => {
                Ok(
                    extract_repeated(&self.cylinder_msac, &self.cylinder, data, &p.limits, |r| {
                        sampler(r, 1)
                    })?
                    .into_iter()
                    .map(|e| Extracted {
                        model: Shape::Cylinder(e.model),
                        inliers: e.inliers,
                        cost: e.cost,
                    })
                    .collect(),
                )
            }
            ShapeChoice::Both => self.extract_both(data, &sampler),
        }
    }

    fn extract_both(
        &self,
        data: &[OrientedPoint],
        sampler: &impl Fn(usize, u64) -> UniformSampler,
    ) -> Result<Vec<Extracted<Shape>>, ConsensusError> {
        let (p, limits) = (&self.params, &self.params.limits);
        let cylinder_cost_m = self.cylinder_msac.params().cost_threshold_m;
        let mut remaining: Vec<usize> = (0..data.len())
            .filter(|&i| data[i].has_finite_position())
            .collect();
        let mut out = Vec::new();
        let mut round = 0;
        while remaining.len() >= limits.min_points.max(2) && out.len() < limits.max_shapes {
            let subset: Vec<OrientedPoint> = remaining.iter().map(|&i| data[i]).collect();
            let sphere = accepted(
                self.msac.fit(&self.sphere, &subset, &mut sampler(round, 0)),
                limits,
            )?;
            let cylinder = accepted(
                self.cylinder_msac
                    .fit(&self.cylinder, &subset, &mut sampler(round, 1)),
                limits,
            )?;
            round += 1;
            let chosen = match (sphere, cylinder) {
                (Some(s), Some(c)) if cylinder_wins(c.cost, s.cost, p.sphere_preference) => {
                    take_shape(c, Shape::Cylinder, &mut remaining)
                }
                (Some(s), _) => take_shape(s, Shape::Sphere, &mut remaining),
                (None, Some(c)) => take_shape(c, Shape::Cylinder, &mut remaining),
                (None, None) => break,
            };
            if let (Some(ratio), Shape::Cylinder(c)) = (p.round_pair_cost_ratio, &chosen.model) {
                let range = self.sphere.params().radius_range_m;
                let pair = round_pair(c, &chosen.inliers, data, range, cylinder_cost_m, ratio);
                if let Some(pair) = pair {
                    out.extend(pair);
                    continue;
                }
            }
            out.push(chosen);
        }
        Ok(out)
    }
}

/// Two spheres in place of `cylinder` when they explain its `inliers` (indices into `data`) at a
/// summed truncated cost (each point's distance from its shape, capped at `cost_m`) below
/// `max_cost_ratio` times the cylinder's: the inliers split at the middle of the cylinder's
/// extent along its axis, a least-squares sphere fitted to each half, both radii within
/// `radius_range_m`. `None` when a half has fewer than four points, a fit fails or the cylinder
/// is not that much costlier. Each sphere takes its half of the cylinder's inliers; its `cost` is
/// its mean truncated cost on them.
fn round_pair(
    cylinder: &Cylinder,
    inliers: &[usize],
    data: &[OrientedPoint],
    radius_range_m: (f64, f64),
    cost_m: f64,
    max_cost_ratio: f64,
) -> Option<[Extracted<Shape>; 2]> {
    let along = |p: &Point3<f64>| (p - cylinder.axis_point).dot(&cylinder.axis);
    let (lo, hi) = cylinder.extent_m?;
    let middle = 0.5 * (lo + hi);
    let (first, second): (Vec<usize>, Vec<usize>) = inliers
        .iter()
        .partition(|&&i| along(&data[i].position) < middle);
    let truncated = |d: f64| d.abs().min(cost_m);
    // A half's sphere, with its summed truncated cost; `None` when it cannot stand for a fruit.
    let ball = |half: Vec<usize>| -> Option<(Extracted<Shape>, f64)> {
        let points: Vec<Point3<f64>> = half.iter().map(|&i| data[i].position).collect();
        let sphere = Sphere::fit_least_squares(&points)?;
        if sphere.radius_m < radius_range_m.0 || sphere.radius_m > radius_range_m.1 {
            return None;
        }
        let cost: f64 = points
            .iter()
            .map(|p| truncated(sphere.signed_distance(p)))
            .sum();
        let mean_cost = cost / points.len() as f64;
        let model = Shape::Sphere(sphere);
        Some((
            Extracted {
                model,
                inliers: half,
                cost: mean_cost,
            },
            cost,
        ))
    };
    let (first, first_cost) = ball(first)?;
    let (second, second_cost) = ball(second)?;
    let cost_cylinder: f64 = inliers
        .iter()
        .map(|&i| truncated(cylinder.signed_distance(&data[i].position)))
        .sum();
    (first_cost + second_cost < max_cost_ratio * cost_cylinder).then_some([first, second])
}

/// Whether a round's accepted cylinder (cost `cylinder_cost`) is taken over its accepted sphere
/// under [`ShapeExtractionParams::sphere_preference`].
fn cylinder_wins(cylinder_cost: f64, sphere_cost: f64, sphere_preference: f64) -> bool {
    cylinder_cost < (1.0 - sphere_preference) * sphere_cost
}

/// The fit if it passed acceptance and has enough inliers; "too few points" means no candidate.
fn accepted<M>(
    fit: Result<Option<Fit<M>>, ConsensusError>,
    limits: &RepeatLimits,
) -> Result<Option<Fit<M>>, ConsensusError> {
    match fit {
        Ok(Some(f)) if f.accepted && f.inliers.len() >= limits.min_inliers.max(1) => Ok(Some(f)),
        Ok(_) | Err(ConsensusError::TooFewPoints { .. }) => Ok(None),
        Err(e) => Err(e),
    }
}

fn take_shape<M>(
    fit: Fit<M>,
    wrap: impl Fn(M) -> Shape,
    remaining: &mut Vec<usize>,
) -> Extracted<Shape> {
    let e = take(fit, remaining);
    Extracted {
        model: wrap(e.model),
        inliers: e.inliers,
        cost: e.cost,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_sphere_preference_lets_only_a_much_cheaper_cylinder_win() {
        // Without preference the lower cost wins, ties go to the sphere.
        assert!(cylinder_wins(0.9, 1.0, 0.0));
        assert!(!cylinder_wins(1.0, 1.0, 0.0));
        // With 0.3 a cylinder must cost less than 70 % of the sphere.
        assert!(!cylinder_wins(0.8, 1.0, 0.3));
        assert!(cylinder_wins(0.6, 1.0, 0.3));
        let out_of_range = ShapeExtractionParams {
            sphere_preference: 1.0,
            ..Default::default()
        };
        assert!(out_of_range.check().is_err());
        let negative = ShapeExtractionParams {
            sphere_preference: -0.1,
            ..Default::default()
        };
        assert!(negative.check().is_err());
    }
}
