//! What identifies a render, for the two checks that compare renders before mixing their samples:
//!
//! * [`job_keys`]: what a checkpoint records and `--resume` compares (beside the scene hash, seed,
//!   method and resolution, which `Checkpoint` holds itself);
//! * [`job_fields`]: what the MPI ranks compare before any work (`distributed::job::agree_job`).
//!
//! Both take the method options generically, from their serialized form, so a method's new
//! option is compared without a line here.

use super::{Plan, RenderJob};
use crate::distributed::job::JobField;
use crate::scene::Scene;

/// The inputs besides the scene hash, seed, method and resolution that change the image, as the
/// checkpoint records and `--resume` compares them (`Checkpoint::job`): each `-D NAME` value, and
/// every method option, generically: the serialized options of the plan's method (`MethodArgs::options_for`) flattened to
/// `option KEY` = JSON value (so `--max-depth` is `option max_depth`). Left out: the time budget
/// (`time_budget_s`: a resume may extend `--time`, and every pass stays an unbiased sample), and
/// `pt-cf`'s light paths when its pilot chose them (not given on the command line): the pilot
/// reads the CF product, whose photon count under `--time` follows the measured speed, so a
/// resume may choose another count, and a pass is an unbiased sample at any count.
pub fn job_keys(job: &RenderJob, plan: &Plan) -> Vec<(String, String)> {
    let mut keys: Vec<(String, String)> = job.defines.iter().map(|(k, v)| (format!("-D {k}"), v.clone())).collect();
    let mut options = Vec::new();
    flatten("", &serde_json::to_value(plan.args.options_for(plan.method)).unwrap_or_default(), &mut options);
    let piloted = job.args.ptcf.light_paths.is_none();
    let kept = |k: &str| k != "time_budget_s" && !(piloted && k == "light_paths");
    keys.extend(options.into_iter().filter(|(k, _)| kept(k)).map(|(k, v)| (format!("option {k}"), v)));
    keys
}

/// `value`'s leaves as (dotted key, JSON text) pairs.
fn flatten(prefix: &str, value: &serde_json::Value, out: &mut Vec<(String, String)>) {
    match value {
        serde_json::Value::Object(m) => {
            for (k, v) in m {
                let key = if prefix.is_empty() { k.clone() } else { format!("{prefix}.{k}") };
                flatten(&key, v, out);
            }
        }
        leaf => out.push((prefix.to_string(), leaf.to_string())),
    }
}

/// The fields every MPI rank must share (`distributed::job::agree_job`): the scene's content (its
/// hash covers the file and its meshes), the `-D` values, the method and its options, the
/// resolution, the seed, spp or time, and the options that decide the collectives
/// (`--checkpoint-every`, `--snapshots`). Long values are hashed.
pub fn job_fields(job: &RenderJob, scene: &Scene, plan: &Plan) -> Vec<JobField> {
    let hash = |s: &str| format!("{:016x}", crate::checkpoint::checksum(s.as_bytes()));
    let defines: Vec<String> = job.defines.iter().map(|(k, v)| format!("{k}={v}")).collect();
    let options = serde_json::to_string(&plan.args.options_for(plan.method)).unwrap_or_default();
    let (w, h) = plan.resolution;
    vec![
        ("the scene's content (file and meshes)", format!("{:016x}", scene.hash)),
        ("-D", hash(&defines.join("\u{0}"))),
        ("--method", plan.checkpoint_label()),
        ("the method's options", hash(&options)),
        ("--resolution", format!("{w}x{h}")),
        ("--seed", plan.seed.to_string()),
        ("--spp", format!("{:?}", plan.spp)),
        ("--time", format!("{:?}", plan.time)),
        ("--checkpoint-every", job.checkpoint_every.is_some().to_string()),
        ("--snapshots", format!("{:?}", job.snapshots)),
    ]
}
