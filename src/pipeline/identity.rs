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
    let mut keys: Vec<(String, String)> =
        defines_in_effect(&job.defines).into_iter().map(|(k, v)| (format!("-D {k}"), v)).collect();
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

/// The `-D NAME=VALUE` definitions as the scene reader applies them: each name once, with the
/// last value given for it (a later `-D` overrides an earlier one), sorted by name, so that the
/// order they were written in does not matter.
pub fn defines_in_effect(defines: &[(String, String)]) -> Vec<(String, String)> {
    let set: std::collections::BTreeMap<&str, &str> = defines.iter().map(|(k, v)| (k.as_str(), v.as_str())).collect();
    set.into_iter().map(|(k, v)| (k.to_string(), v.to_string())).collect()
}

/// The `-D` field of [`job_fields`]: a hash of [`defines_in_effect`] (names and values
/// length-prefixed, so no two sets share a text).
fn defines_field(defines: &[(String, String)]) -> String {
    let mut text = String::new();
    for (k, v) in defines_in_effect(defines) {
        text += &format!("{}:{k}{}:{v}", k.len(), v.len());
    }
    format!("{:016x}", crate::checkpoint::checksum(text.as_bytes()))
}

/// The fields every MPI rank must share (`distributed::job::agree_job`): the scene's content (its
/// hash covers the file and its meshes), the `-D` values, the method and its options, the
/// resolution, the seed, spp or time, and the options that decide the collectives
/// (`--checkpoint-every`, `--snapshots`). Long values are hashed.
pub fn job_fields(job: &RenderJob, scene: &Scene, plan: &Plan) -> Vec<JobField> {
    let hash = |s: &str| format!("{:016x}", crate::checkpoint::checksum(s.as_bytes()));
    let options = serde_json::to_string(&plan.args.options_for(plan.method)).unwrap_or_default();
    let (w, h) = plan.resolution;
    vec![
        ("the scene's content (file, meshes and images)", format!("{:016x}", scene.hash)),
        ("-D", defines_field(&job.defines)),
        ("--method", plan.checkpoint_label()),
        ("the method's options", hash(&options)),
        ("--resolution", format!("{w}x{h}")),
        ("--seed", plan.seed.to_string()),
        ("--spp", format!("{:?}", plan.spp)),
        ("--time", format!("{:?}", plan.time)),
        ("--checkpoint-every", job.checkpoint_every.is_some().to_string()),
        ("--snapshots", format!("{:?}", job.snapshots)),
        // only rank 0 writes: another rank's own --out would be ignored without a word
        ("--out", job.out.display().to_string()),
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    fn d(pairs: &[(&str, &str)]) -> Vec<(String, String)> {
        pairs.iter().map(|(k, v)| (k.to_string(), v.to_string())).collect()
    }

    /// The ranks compare `-D` as the set the scene reader applies: order-independent, the last
    /// value of a repeated name winning (issue #63: a reordered list was another job).
    #[test]
    fn defines_are_compared_as_the_set_in_effect() {
        let ab = defines_field(&d(&[("a", "1"), ("b", "2")]));
        assert_eq!(ab, defines_field(&d(&[("b", "2"), ("a", "1")])));
        assert_eq!(ab, defines_field(&d(&[("a", "0"), ("b", "2"), ("a", "1")])));
        assert_ne!(ab, defines_field(&d(&[("a", "1"), ("b", "2"), ("a", "0")])));
        assert_ne!(ab, defines_field(&d(&[("a", "2"), ("b", "1")])));
        assert_ne!(ab, defines_field(&d(&[("a", "1")])));
        // no two sets share a text: `a=1,b=2` is not `a=1b:2`
        assert_ne!(defines_field(&d(&[("a", "1"), ("b", "2")])), defines_field(&d(&[("a", "1b:2")])));
        assert_eq!(defines_field(&[]), defines_field(&[]));
        assert_eq!(defines_in_effect(&d(&[("z", "1"), ("a", "2"), ("z", "3")])), d(&[("a", "2"), ("z", "3")]));
    }
}
