//! Stage 2 of the pipeline (`pipeline` module docs): the caustic preprocess on rank 0, and
//! unless `--light-paths` is given `pt-cf`'s light-path pilot (`light_pilot`), broadcast to
//! every rank, which builds its integrator from the same bytes and count (rank 0 after a pilot
//! takes the pilot's, set to that count: the same integrator, already built).
//!
//! Invariant: every rank leaves together when rank 0 fails (`distributed::agree` before each
//! collective), so none waits in a broadcast.

use super::budget::{Budget, BUILD_SHARE, PILOT_SHARE, PREPROCESS_SHARE};
use super::light_pilot::{self, LightPathRule};
use super::{secs, Plan, RankStats, RenderError};
use crate::accel::World;
use crate::distributed::{self, Cluster};
use crate::integrators::Integrator;
use crate::progress::PhaseBar;
use std::time::Instant;

/// The integrator built from the broadcast preprocess product, with the figures of both.
pub(super) struct Prepared {
    pub(super) integrator: Box<dyn Integrator>,
    pub(super) stats: RankStats,
    /// `pt-cf`'s light-path pilot (rank 0 without `--light-paths`; `None` otherwise).
    pub(super) light_path_rule: Option<LightPathRule>,
}

/// Stage 2: the caustic preprocess on rank 0 (with `pt-cf`'s light-path pilot,
/// `light_pilot`), broadcast to the others; every rank builds its integrator from the same
/// bytes and the same light-path count, which `plan` then records. Its phases are shown under
/// the render bar's rules.
/// Each part runs inside its share of the budget (`budget::PREPROCESS_SHARE`, `PILOT_SHARE`) and
/// ends early there or at a signal (fewer photons; the pilot cut short leaves the default count).
pub(super) fn preprocess(
    world: &World,
    plan: &mut Plan,
    cluster: &dyn Cluster,
    visible: bool,
    budget: &mut Budget,
) -> Result<Prepared, RenderError> {
    let t_pre = Instant::now();
    let pilot = light_pilot::wanted(plan);
    let pre = if cluster.rank() == 0 {
        let (stop, allowed) = budget.stop_for(PREPROCESS_SHARE);
        let phases = PhaseBar::new(visible).with_stop(stop.clone());
        let product = plan.method.preprocess_reporting(world, &plan.args, plan.seed, &phases);
        budget.record("preprocess", secs(t_pre), allowed, stop.is_due());
        let t_pilot = Instant::now();
        let (stop, allowed) = budget.stop_for(PILOT_SHARE);
        let skip = allowed.is_some_and(|a| a < light_pilot::PILOT_MIN_S);
        let rule = match product {
            Ok(product) if pilot && skip => Ok((product, (None, None))),
            Ok(product) if pilot => {
                light_pilot::choose(world, &plan.args, (plan.seed, plan.resolution), &product, &stop)
                    .map(|(rule, integrator)| (product, (rule, Some(integrator))))
                    .map_err(RenderError::from)
            }
            Ok(product) => Ok((product, (None, None))),
            Err(e) => Err(e.into()),
        };
        if pilot {
            budget.record("light pilot", secs(t_pilot), allowed, skip || stop.is_due());
        }
        rule
    } else {
        Ok((Vec::new(), (None, None)))
    };
    let preprocess_s = secs(t_pre);
    // every rank must leave together when rank 0 fails, or the others wait in the broadcast
    let (mut product, (light_path_rule, pilot_integrator)) = distributed::agree(cluster, pre)?;
    let t_bc = Instant::now();
    cluster.broadcast_bytes(&mut product);
    if pilot {
        plan.args.ptcf.light_paths = Some(light_pilot::broadcast_count(cluster, plan, light_path_rule.as_ref())?);
    }
    let stats = RankStats {
        rank: cluster.rank(),
        preprocess_s,
        broadcast_s: secs(t_bc),
        bytes_broadcast: product.len(),
        product_hash: crate::checkpoint::checksum(&product),
        ..RankStats::default()
    };
    let t_build = Instant::now();
    // the integrator's build: its lookup grid stops at its share (then asks the cluster map
    // everywhere: the same image), the rest is a minimal phase
    let (stop, allowed) = budget.stop_for(BUILD_SHARE);
    plan.args.cf.build_deadline = stop.deadline();
    let integrator = match (pilot_integrator, plan.args.ptcf.light_paths) {
        // rank 0 after a pilot: its integrator at the broadcast count (`light_pilot::choose`)
        (Some(mut integrator), Some(n)) => {
            if let Some(light) = integrator.light_tracer_mut() {
                light.set_light_paths(n);
            }
            integrator
        }
        _ => plan.method.build(world, &plan.args, &product)?,
    };
    budget.record("build", secs(t_build), allowed, stop.is_due());
    Ok(Prepared { integrator, stats, light_path_rule })
}
