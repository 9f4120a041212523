//! `arps-train partition-oracle`: how well GMR registers the validation pairs when the
//! memberships are exactly the `seg` loss's targets (the canonical partition, computed with the
//! ground truth). It is the ceiling a network that learned the partition perfectly would reach,
//! for choosing the partition's concentration `kappa`.

use arps::data::metrics::{pair_error, summarize};
use arps::train::partition::{targets, Role};
use arps::train::run::data::{to_train_pair, TrainData};
use std::path::Path;

/// Prints one table row per `kappa`: recall (15 deg, 0.2), MRE, MTE of oracle memberships on the
/// run's first `pairs` validation pairs, with `points` (default: the run's N) points per cloud.
pub fn run(run: &Path, pairs: u64, kappas: &[f64], points: Option<usize>) -> Result<(), String> {
    let st = arps::train::run::checkpoint::load(&run.join("checkpoint.safetensors"))?.state;
    let data = TrainData::new(&st.config)?;
    let (n, j) = (points.unwrap_or(st.config.model.n_points), st.config.model.gaussians);
    if n < j {
        return Err(format!("--points {n}: need at least J = {j} points"));
    }
    let mut val = Vec::new();
    for i in 0..pairs {
        let p = data.val_pair(i).map_err(|e| format!("validation pair {i}: {e}"))?;
        val.push(to_train_pair(&p, n, i));
    }
    out!("oracle memberships (canonical partition, J = {j}, N = {n}) on {pairs} validation pairs");
    out!("{:>8} {:>8} {:>9} {:>8}", "kappa", "recall", "MRE(deg)", "MTE");
    for &kappa in kappas {
        let errors: Vec<_> = val
            .iter()
            .map(|tp| {
                let gs = targets(&tp.source, tp.source_centroid(), &tp.t_gt, Role::Source, j, kappa);
                let gt = targets(&tp.target, tp.target_centroid(), &tp.t_gt, Role::Target, j, kappa);
                let t = arps::gmr::solve(
                    &arps::gmr::gmm_params(&tp.source, &gs, j),
                    &arps::gmr::gmm_params(&tp.target, &gt, j),
                );
                pair_error(&t, &tp.t_gt, 1.0)
            })
            .collect();
        let s = summarize(&errors, &vec![0.0; errors.len()], 15.0, 0.2);
        out!("{kappa:>8.1} {:>8.3} {:>9.2} {:>8.4}", s.recall, s.mre, s.mte);
    }
    Ok(())
}
