//! `pomona plan`: which arm of seed 004's two-arm robot picks which fruit, in which order
//! (`pomona-arm`): reads `{"targets": [{"id", "center_m"}]}` in arm A's hub frame, writes the
//! plan JSON (docs/formats.md) and prints a summary.

use std::path::PathBuf;
use std::time::Instant;

use anyhow::{bail, Context, Result};
use pomona_arm::{
    plan_exact, plan_heuristic, MotionModel, PlanProblem, TargetList, TwoArmCell, MAX_EXACT_TARGETS,
};
use pomona_io::read_budget::{read_json_text, MAX_JSON_FILE_BYTES};

/// Arguments of `pomona plan`.
#[derive(Debug, clap::Args)]
pub struct PlanArgs {
    /// Targets: `{"targets": [{"id": "...", "center_m": [x, y, z]}, ...]}`, metres, in arm A's
    /// hub frame (x right, y down, z forward).
    #[arg(long, value_name = "T.json")]
    pub targets: PathBuf,
    /// Where to write the plan (JSON).
    #[arg(long, value_name = "PLAN.json")]
    pub out: PathBuf,
    /// Solve exactly (every split of the shared targets, Held–Karp per arm) instead of the
    /// heuristic; at most 14 reachable targets.
    #[arg(long)]
    pub exact: bool,
}

/// Runs `pomona plan`.
///
/// # Errors
/// An unreadable or malformed targets file (naming it), invalid targets (non-finite, repeated
/// ids), too many targets for `--exact`, or an unwritable output.
pub fn run(args: &PlanArgs) -> Result<()> {
    let path = &args.targets;
    let text = read_json_text(path, MAX_JSON_FILE_BYTES)
        .with_context(|| format!("cannot read targets file {}", path.display()))?;
    let list: TargetList = serde_json::from_str(&text)
        .with_context(|| format!("{}: not a targets file", path.display()))?;
    let problem = PlanProblem::new(
        &list.targets,
        &TwoArmCell::default(),
        &MotionModel::default(),
    )
    .with_context(|| format!("{}: invalid targets", path.display()))?;
    let started = Instant::now();
    let plan = if args.exact {
        plan_exact(&problem).with_context(|| {
            format!("--exact handles at most {MAX_EXACT_TARGETS} reachable targets")
        })?
    } else {
        plan_heuristic(&problem)
    };
    let ms = started.elapsed().as_secs_f64() * 1e3;
    if !plan.is_valid_for(&problem) {
        bail!("internal error: the plan does not pick every reachable target once");
    }
    pomona_io::write_json(&args.out, &plan.to_file(&problem))
        .with_context(|| format!("cannot write {}", args.out.display()))?;
    println!(
        "{} targets: arm A picks {} ({:.1} s), arm B {} ({:.1} s), {} unreachable; makespan \
         {:.1} s; planned in {ms:.2} ms; plan in {}",
        problem.len(),
        plan.routes[0].len(),
        plan.time_s[0],
        plan.routes[1].len(),
        plan.time_s[1],
        plan.unreachable.len(),
        plan.makespan_s(),
        args.out.display()
    );
    Ok(())
}
