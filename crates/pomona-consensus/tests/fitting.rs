//! End-to-end fits on synthetic partial, noisy shapes with outliers.

#![allow(clippy::unwrap_used, clippy::expect_used)]

mod common;

use common::*;
use pomona_consensus::nalgebra::{Point3, Unit, Vector3};
use pomona_consensus::{
    Acceptance, Consensus, CylinderEstimatorParams, KnnNormalParams, MsacParams, OrientedPoint,
    Ransac, RansacParams, RepeatLimits, Shape, ShapeChoice, ShapeExtractionParams,
    SphereEstimatorParams, UniformSampler,
};

/// 40 % camera-facing cap of a 40 mm sphere, σ = 3 mm, plus as many outliers (50 %) uniform in
/// the cube `centre ± half_box_m`.
fn noisy_cap_with_outliers(seed: u64, half_box_m: f64) -> (Vec<OrientedPoint>, Point3<f64>, f64) {
    let mut r = rng(seed);
    let c = Point3::new(0.03, -0.02, 0.75);
    let radius = 0.04;
    let mut pts = sphere_cap(c, radius, 0.4, 1000, 0.003, &mut r);
    pts.extend(box_outliers(c, half_box_m, 1000, &mut r));
    (pts, c, radius)
}

/// Outliers spread over a 30 cm cube around the fruit.
const SPREAD: f64 = 0.15;
/// Outliers packed into a 20 cm cube around the fruit (dense clutter).
const DENSE: f64 = 0.10;

fn cluttered_msac() -> MsacParams {
    MsacParams {
        acceptance: Acceptance::InlierResidual {
            max_residual_m: 0.010,
            min_inlier_fraction: 0.3,
        },
        ..Default::default()
    }
}

#[test]
fn msac_recovers_noisy_partial_sphere_with_half_outliers() {
    let est = SphereEstimatorParams::default().check().unwrap();
    // The paper's T = 25 mm with outliers spread over a 30 cm cube; in dense clutter (20 cm cube)
    // a 25 mm truncation lets larger spheres buy cost by grazing outliers, so T = 10 mm there.
    for (half_box, t) in [(SPREAD, 0.025), (DENSE, 0.010)] {
        let msac = MsacParams {
            cost_threshold_m: t,
            inlier_threshold_m: t,
            ..cluttered_msac()
        }
        .check()
        .unwrap();
        for seed in 0..5 {
            let (pts, c, radius) = noisy_cap_with_outliers(seed, half_box);
            let fit = msac
                .fit(&est, &pts, &mut UniformSampler::new(42 + seed))
                .unwrap()
                .unwrap();
            let centre_err = (fit.model.center - c).norm();
            let radius_err = (fit.model.radius_m - radius).abs();
            assert!(
                centre_err < 0.005,
                "box {half_box} seed {seed}: centre error {centre_err}"
            );
            assert!(
                radius_err < 0.003,
                "box {half_box} seed {seed}: radius error {radius_err}"
            );
            assert!(fit.accepted);
        }
    }
    let (pts, _, _) = noisy_cap_with_outliers(1, SPREAD);

    // The paper's literal acceptance (mean cost over all points ≤ 2 mm) must refuse this cloud:
    // half the points cost T = 25 mm each.
    let literal = MsacParams::default()
        .check()
        .unwrap()
        .fit(&est, &pts, &mut UniformSampler::new(42))
        .unwrap()
        .unwrap();
    assert!(!literal.accepted);
    assert!(literal.cost > 0.0125, "{}", literal.cost);
}

/// Scoring hypotheses on a stride of 200 of the 2000 points finds the same sphere; the reported
/// cost and inliers are those of the winner over every point.
#[test]
fn msac_scoring_a_stride_finds_the_sphere_and_reports_the_full_cost() {
    let est = SphereEstimatorParams::default().check().unwrap();
    let full = MsacParams {
        cost_threshold_m: 0.010,
        inlier_threshold_m: 0.010,
        ..cluttered_msac()
    };
    let strided = MsacParams {
        max_scored_points: Some(200),
        ..full
    };
    for seed in 0..5 {
        let (pts, c, radius) = noisy_cap_with_outliers(seed, DENSE);
        let fit = |p: MsacParams| {
            p.check()
                .unwrap()
                .fit(&est, &pts, &mut UniformSampler::new(7 + seed))
                .unwrap()
                .unwrap()
        };
        let (a, b) = (fit(full), fit(strided));
        for f in [&a, &b] {
            assert!(
                (f.model.center - c).norm() < 0.005,
                "seed {seed}: {:?}",
                f.model
            );
            assert!((f.model.radius_m - radius).abs() < 0.003);
            assert!(f.accepted);
        }
        // The strided fit's cost is the mean truncated residual over all 2000 points.
        let mean_cost = pts
            .iter()
            .map(|p| (p.position - b.model.center).norm() - b.model.radius_m)
            .map(|e| e.abs().min(0.010))
            .sum::<f64>()
            / pts.len() as f64;
        assert!(
            (b.cost - mean_cost).abs() < 1e-9,
            "{} vs {mean_cost}",
            b.cost
        );
        assert_eq!(b.valid_points, pts.len());
        assert!(b.inliers.len() > 800, "{}", b.inliers.len());
    }
    assert!(MsacParams {
        max_scored_points: Some(0),
        ..Default::default()
    }
    .check()
    .is_err());
}

#[test]
fn msac_quadratic_and_ransac_also_recover_the_sphere() {
    let (pts, c, radius) = noisy_cap_with_outliers(2, SPREAD);
    let est = SphereEstimatorParams::default().check().unwrap();
    let quadratic = MsacParams {
        cost: pomona_consensus::CostFunction::TruncatedQuadratic,
        cost_threshold_m: 0.010,
        ..cluttered_msac()
    }
    .check()
    .unwrap()
    .fit(&est, &pts, &mut UniformSampler::new(3))
    .unwrap()
    .unwrap();
    let ransac: Ransac = RansacParams::default().check().unwrap();
    let plain = ransac
        .fit(&est, &pts, &mut UniformSampler::new(3))
        .unwrap()
        .unwrap();
    for fit in [quadratic, plain] {
        assert!((fit.model.center - c).norm() < 0.005, "{:?}", fit.model);
        assert!((fit.model.radius_m - radius).abs() < 0.003);
    }
}

#[test]
fn msac_is_deterministic_per_seed() {
    let (pts, c, _) = noisy_cap_with_outliers(4, SPREAD);
    let est = SphereEstimatorParams::default().check().unwrap();
    let msac = cluttered_msac().check().unwrap();
    let a = msac
        .fit(&est, &pts, &mut UniformSampler::new(9))
        .unwrap()
        .unwrap();
    let b = msac
        .fit(&est, &pts, &mut UniformSampler::new(9))
        .unwrap()
        .unwrap();
    assert_eq!(a, b);
    let d = msac
        .fit(&est, &pts, &mut UniformSampler::new(10))
        .unwrap()
        .unwrap();
    assert_ne!(a.model, d.model);
    for fit in [a, d] {
        assert!(fit.accepted && (fit.model.center - c).norm() < 0.005);
    }
}

#[test]
fn invalid_points_are_skipped_and_too_few_is_an_error() {
    let (mut pts, c, _) = noisy_cap_with_outliers(5, SPREAD);
    for p in pts.iter_mut().step_by(7) {
        p.position = Point3::new(f64::NAN, 0.0, 1.0);
    }
    let est = SphereEstimatorParams::default().check().unwrap();
    let msac = cluttered_msac().check().unwrap();
    let fit = msac
        .fit(&est, &pts, &mut UniformSampler::new(1))
        .unwrap()
        .unwrap();
    assert!((fit.model.center - c).norm() < 0.005);
    assert!(fit.inliers.iter().all(|&i| pts[i].position.x.is_finite()));
    assert_eq!(fit.valid_points, pts.len() - pts.len().div_ceil(7));

    let three = &pts[1..4];
    assert!(msac.fit(&est, three, &mut UniformSampler::new(1)).is_err());
    assert!(MsacParams {
        iterations: 0,
        ..Default::default()
    }
    .check()
    .is_err());
    assert!(MsacParams {
        cost_threshold_m: f64::NAN,
        ..Default::default()
    }
    .check()
    .is_err());
}

#[test]
fn msac_recovers_noisy_partial_cylinder_with_estimated_normals() {
    let axis = Unit::new_normalize(Vector3::new(0.2, 1.0, 0.3));
    let c = Point3::new(-0.02, 0.04, 0.7);
    let radius = 0.03;
    // Distances only (the paper), and with Schnabel's normal-angle test α = 30°.
    for alpha in [None, Some(30f64.to_radians())] {
        let est = CylinderEstimatorParams {
            max_normal_deviation_rad: alpha,
            ..Default::default()
        }
        .check()
        .unwrap();
        for seed in 0..3 {
            // Camera-facing half of an 18 cm × 30 mm fruit, σ = 3 mm, plus 300 outliers.
            let mut r = rng(11 + seed);
            let mut pts = cylinder_half(c, axis, radius, 0.18, 1500, 0.003, &mut r);
            pts.extend(box_outliers(c, 0.12, 300, &mut r));
            // Normals from the noisy points, as the detector would have them.
            let positions: Vec<Point3<f64>> = pts.iter().map(|p| p.position).collect();
            let normals = KnnNormalParams {
                k: 30,
                ..Default::default()
            }
            .check()
            .unwrap()
            .estimate(&positions);
            let data = OrientedPoint::zip(&positions, &normals);
            let fit = cluttered_msac()
                .check()
                .unwrap()
                .fit(&est, &data, &mut UniformSampler::new(5 + seed))
                .unwrap()
                .unwrap();
            let axis_err = angle_deg(&fit.model.axis, &axis);
            let radius_err = (fit.model.radius_m - radius).abs();
            assert!(
                axis_err < 5.0,
                "{alpha:?} {seed}: axis error {axis_err} deg"
            );
            assert!(
                radius_err < 0.003,
                "{alpha:?} {seed}: radius error {radius_err}"
            );
            assert!(fit.model.distance_to_axis(&c) < 0.005);
            let len = fit.model.length_m().unwrap();
            assert!((len - 0.18).abs() < 0.03, "length {len}");
            assert!(
                (fit.model.midpoint() - c).norm() < 0.015,
                "{:?}",
                fit.model.midpoint()
            );
        }
    }
}

#[test]
fn repeated_extraction_finds_two_separated_spheres() {
    let mut r = rng(21);
    let c1 = Point3::new(-0.06, 0.0, 0.8);
    let c2 = Point3::new(0.07, 0.02, 0.85);
    let mut pts = sphere_cap(c1, 0.035, 0.4, 800, 0.001, &mut r);
    pts.extend(sphere_cap(c2, 0.045, 0.4, 1000, 0.001, &mut r));
    let params = ShapeExtractionParams {
        msac: MsacParams {
            acceptance: Acceptance::InlierResidual {
                max_residual_m: 0.003,
                min_inlier_fraction: 0.2,
            },
            ..Default::default()
        },
        limits: RepeatLimits {
            min_points: 50,
            min_inliers: 50,
            max_shapes: 8,
        },
        seed: 1,
        ..Default::default()
    };
    let shapes = params.check().unwrap().extract(&pts).unwrap();
    assert_eq!(shapes.len(), 2, "{shapes:?}");
    let mut found: Vec<(Point3<f64>, f64, usize)> = shapes
        .iter()
        .map(|s| (s.model.center(), s.model.radius_m(), s.inliers.len()))
        .collect();
    found.sort_by(|a, b| a.0.x.total_cmp(&b.0.x));
    assert!((found[0].0 - c1).norm() < 0.003 && (found[0].1 - 0.035).abs() < 0.002);
    assert!((found[1].0 - c2).norm() < 0.003 && (found[1].1 - 0.045).abs() < 0.002);
    // Inliers are disjoint and index the input.
    let mut all: Vec<usize> = shapes.iter().flat_map(|s| s.inliers.clone()).collect();
    let n = all.len();
    all.sort_unstable();
    all.dedup();
    assert_eq!(all.len(), n);
    assert!(n >= 1700);

    // Same seed, same shapes; another seed finds them too.
    assert_eq!(params.check().unwrap().extract(&pts).unwrap(), shapes);
    // Spheres without a normal-angle test do not read normals (`uses_normals`): the same shapes
    // with every normal removed. With the test, the normals decide.
    assert!(!params.uses_normals());
    let bare: Vec<OrientedPoint> = pts
        .iter()
        .map(|p| OrientedPoint::without_normal(p.position))
        .collect();
    assert_eq!(params.check().unwrap().extract(&bare).unwrap(), shapes);
    let mut tested = params;
    tested.sphere.max_normal_deviation_rad = Some(0.3);
    assert!(tested.uses_normals());
    let mut flipped = pts.clone();
    for p in flipped.iter_mut().take(800) {
        p.normal = p
            .normal
            .map(|n| Unit::new_normalize(n.cross(&Vector3::x())));
    }
    let found = tested.check().unwrap().extract(&flipped).unwrap();
    assert!(found.len() < shapes.len(), "{found:?}");
    let other = ShapeExtractionParams { seed: 99, ..params }
        .check()
        .unwrap()
        .extract(&pts)
        .unwrap();
    assert_eq!(other.len(), 2);

    // The paper's literal acceptance (mean cost over the whole cluster) rejects the first round:
    // each sphere alone leaves ≥ 44 % of the cluster costing T.
    let literal = ShapeExtractionParams {
        seed: 1,
        ..Default::default()
    }
    .check()
    .unwrap()
    .extract(&pts)
    .unwrap();
    assert!(literal.is_empty());
}

#[test]
fn paper_defaults_extract_a_clean_sphere_and_both_mode_picks_the_right_model() {
    let mut r = rng(31);
    let c = Point3::new(0.0, 0.0, 0.9);
    let sphere_pts = sphere_cap(c, 0.04, 0.4, 1200, 0.001, &mut r);
    let shapes = ShapeExtractionParams {
        shapes: ShapeChoice::Both,
        seed: 3,
        ..Default::default()
    }
    .check()
    .unwrap()
    .extract(&sphere_pts)
    .unwrap();
    assert_eq!(shapes.len(), 1);
    assert!(
        matches!(shapes[0].model, Shape::Sphere(_)),
        "{:?}",
        shapes[0]
    );
    assert!((shapes[0].model.center() - c).norm() < 0.003);

    let axis = Unit::new_normalize(Vector3::new(1.0, 0.1, 0.2));
    let cyl_pts = cylinder_half(c, axis, 0.03, 0.2, 1500, 0.001, &mut r);
    let shapes = ShapeExtractionParams {
        shapes: ShapeChoice::Both,
        seed: 3,
        ..Default::default()
    }
    .check()
    .unwrap()
    .extract(&cyl_pts)
    .unwrap();
    assert!(!shapes.is_empty());
    let Shape::Cylinder(cyl) = shapes[0].model else {
        panic!("expected a cylinder, got {:?}", shapes[0]);
    };
    assert!(angle_deg(&cyl.axis, &axis) < 2.0);
    assert!((cyl.radius_m - 0.03).abs() < 0.002);
    assert!((cyl.midpoint() - c).norm() < 0.01);
}

#[test]
fn early_stop_needs_far_fewer_samples_on_clean_data() {
    let mut r = rng(41);
    let axis = Unit::new_normalize(Vector3::new(0.2, 1.0, 0.3));
    let c = Point3::new(0.0, 0.0, 0.8);
    let pts = cylinder_half(c, axis, 0.03, 0.18, 2000, 0.002, &mut r);
    let est = CylinderEstimatorParams::default().check().unwrap();
    let full = MsacParams::default().check().unwrap();
    let early = MsacParams {
        early_stop_confidence: Some(0.99),
        ..Default::default()
    }
    .check()
    .unwrap();
    let a = full
        .fit(&est, &pts, &mut UniformSampler::new(1))
        .unwrap()
        .unwrap();
    let b = early
        .fit(&est, &pts, &mut UniformSampler::new(1))
        .unwrap()
        .unwrap();
    assert_eq!(a.iterations_run, 500);
    assert!(b.iterations_run < 20, "{}", b.iterations_run);
    for fit in [a, b] {
        assert!(fit.accepted);
        assert!(angle_deg(&fit.model.axis, &axis) < 1.0);
        assert!((fit.model.radius_m - 0.03).abs() < 0.001);
    }
    assert!(MsacParams {
        early_stop_confidence: Some(1.0),
        ..Default::default()
    }
    .check()
    .is_err());
}

#[test]
fn generic_repeated_extraction_with_ransac() {
    let mut r = rng(51);
    let c1 = Point3::new(-0.06, 0.0, 0.8);
    let c2 = Point3::new(0.07, 0.02, 0.85);
    // Bare positions: the sphere estimator runs on `Point3<f64>` too.
    let mut pts: Vec<Point3<f64>> = sphere_cap(c1, 0.035, 0.4, 600, 0.001, &mut r)
        .into_iter()
        .map(|p| p.position)
        .collect();
    pts.extend(
        sphere_cap(c2, 0.045, 0.4, 600, 0.001, &mut r)
            .into_iter()
            .map(|p| p.position),
    );
    pts.push(Point3::new(f64::NAN, 1.0, 1.0));
    let ransac = RansacParams {
        inlier_threshold_m: 0.005,
        min_inlier_fraction: Some(0.3),
        ..Default::default()
    }
    .check()
    .unwrap();
    let est = SphereEstimatorParams::default().check().unwrap();
    let found = pomona_consensus::extract_repeated(
        &ransac,
        &est,
        &pts,
        &RepeatLimits::default(),
        |round| UniformSampler::new(round as u64),
    )
    .unwrap();
    assert_eq!(found.len(), 2);
    for e in &found {
        let c = if e.model.center.x < 0.0 { c1 } else { c2 };
        assert!((e.model.center - c).norm() < 0.003);
        assert!(e.inliers.len() >= 550);
    }
    let seeded = ransac.fit_seeded(&est, &pts, 3).unwrap().unwrap();
    assert_eq!(
        seeded,
        ransac
            .fit(&est, &pts, &mut UniformSampler::new(3))
            .unwrap()
            .unwrap()
    );
}

#[test]
fn a_cylinder_across_two_touching_balls_gives_way_to_them_and_a_real_cylinder_stays() {
    // The repeated extraction of shape-fit's defaults: truncated cost 25 mm, inliers 12 mm.
    let msac = MsacParams {
        inlier_threshold_m: 0.012,
        acceptance: Acceptance::InlierResidual {
            max_residual_m: 0.008,
            min_inlier_fraction: 0.1,
        },
        ..Default::default()
    };
    let params = |ratio: Option<f64>| ShapeExtractionParams {
        msac,
        shapes: ShapeChoice::Both,
        round_pair_cost_ratio: ratio,
        limits: RepeatLimits {
            min_points: 30,
            min_inliers: 30,
            max_shapes: 6,
        },
        seed: 5,
        ..Default::default()
    };
    let mut r = rng(105);
    let (a, b) = (Point3::new(-0.034, 0.0, 1.2), Point3::new(0.034, 0.0, 1.2));
    let mut pair = sphere_cap(a, 0.035, 0.35, 700, 0.002, &mut r);
    pair.extend(sphere_cap(b, 0.035, 0.35, 700, 0.002, &mut r));
    let without = params(None).check().unwrap().extract(&pair).unwrap();
    assert!(
        matches!(without[0].model, Shape::Cylinder(_)),
        "{without:?}"
    );
    let with = params(Some(0.85)).check().unwrap().extract(&pair).unwrap();
    let balls: Vec<Point3<f64>> = with
        .iter()
        .filter(|e| e.inliers.len() > 500)
        .map(|e| match e.model {
            Shape::Sphere(s) => s.center,
            Shape::Cylinder(_) => panic!("a cylinder is left: {with:?}"),
        })
        .collect();
    assert_eq!(balls.len(), 2, "{with:?}");
    for truth in [a, b] {
        assert!(
            balls.iter().any(|c| (c - truth).norm() < 0.004),
            "{balls:?}"
        );
    }

    let axis = Unit::new_normalize(Vector3::new(1.0, 0.1, 0.2));
    let c = Point3::new(0.0, 0.0, 0.9);
    let long = cylinder_half(c, axis, 0.03, 0.2, 1500, 0.001, &mut r);
    let shapes = params(Some(0.85)).check().unwrap().extract(&long).unwrap();
    assert!(matches!(shapes[0].model, Shape::Cylinder(_)), "{shapes:?}");
    assert!(params(Some(1.5)).check().is_err());
    assert!(params(Some(0.0)).check().is_err());
}
