//! One Levenberg–Marquardt step, shared by the sphere and cylinder refinements: solve the damped
//! normal equations, raising the damping until the step lowers the squared error.

use nalgebra::{SMatrix, SVector};

/// Damping tries per step before giving up.
const MAX_TRIES: usize = 8;

/// Tries `(JᵀJ + λ·diag(JᵀJ)) δ = −Jᵀr` with λ growing tenfold per try; the first `δ` whose
/// model (`apply(δ)`) is `valid` and has no larger `sse` than `current_sse` is taken, and λ
/// shrinks for the next step. Returns the new model, its error and whether it moved by more than
/// a negligible amount (a sub-0.1 µm step or a relative decrease below 1e-10 means converged);
/// `None` when no try improved.
pub(crate) fn damped_step<const N: usize, M>(
    jtj: &SMatrix<f64, N, N>,
    jtr: &SVector<f64, N>,
    current_sse: f64,
    lambda: &mut f64,
    apply: impl Fn(&SVector<f64, N>) -> M,
    valid: impl Fn(&M) -> bool,
    sse: impl Fn(&M) -> f64,
) -> Option<(M, f64, bool)> {
    for _ in 0..MAX_TRIES {
        let mut damped = *jtj;
        for k in 0..N {
            damped[(k, k)] *= 1.0 + *lambda;
        }
        let Some(chol) = damped.cholesky() else {
            *lambda *= 10.0;
            continue;
        };
        let delta = chol.solve(&(-jtr));
        let candidate = apply(&delta);
        let cand_sse = sse(&candidate);
        if valid(&candidate) && cand_sse <= current_sse {
            let moved = !(delta.norm() < 1e-10 || current_sse - cand_sse <= 1e-10 * current_sse);
            *lambda = (*lambda * 0.1).max(1e-12);
            return Some((candidate, cand_sse, moved));
        }
        *lambda *= 10.0;
    }
    None
}
