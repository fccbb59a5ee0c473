//! A scene's `[render]` options over the command line's: the render settings and method options
//! a scene file records by their long flag names (`clusters = 32`, `scene::RenderOption`), each
//! parsed by clap as `--KEY=VALUE`, so that a value in a scene is checked exactly as its flag is
//! (parser, range, conflicts, the group's `validate`). The command line wins
//! (`MethodArgs::given`).
//!
//! A key must name a render setting or an option of the scene's own method (its `[render]
//! method`, or `auto`'s choice): another method's is refused as on the command line (`--clusters
//! belongs to iws-cf/pt-cf, not pt`), at the key's line. When `--method` renders another method
//! than the scene's, the scene's options that this method does not take are left out (`reference`
//! renders `pt` from a scene that records its `pt-cf` options). Every error names the file, the
//! line and the key, as the scene reader's do.

use super::RenderError;
use crate::integrators::{Method, MethodArgs, MethodError, OptionName};
use crate::scene::{RenderOption, Scene, SceneError};

/// `args` (the command line's) with `scene`'s `[render]` options for `method`, the method that
/// renders; `own` is the scene's own method, which every option must fit.
pub(super) fn apply(args: &MethodArgs, scene: &Scene, method: Method, own: Method) -> Result<MethodArgs, RenderError> {
    let mut flags = Vec::new();
    let mut out = args.clone();
    for o in &scene.render.options {
        let name = option_name(scene, o, own)?;
        if args.given.contains(&name.id) || !name.group.is_none_or(|g| method.groups().contains(&g)) {
            continue;
        }
        flags.push(format!("{}={}", name.long, o.value));
        // all the flags so far, so that a conflict is reported at the later key
        let parsed = args.with_flags(&flags).map_err(|e| error_at(scene, o, clap_message(&e), None))?;
        parsed.validate().map_err(|e| error_at(scene, o, e.to_string(), Some(e)))?;
        out = parsed;
    }
    Ok(out)
}

/// The option `o` names, if it is a render setting or an option of `own`.
fn option_name(scene: &Scene, o: &RenderOption, own: Method) -> Result<OptionName, RenderError> {
    // `max_depth` is the table's own key (the spelling `max-depth` would set it twice)
    let Some(name) = MethodArgs::option_named(&o.key).filter(|n| n.id != "max_depth") else {
        let m = format!(
            "unknown key `{}`: [render] takes method, spp, time, seed, max_depth and the render settings and \
             method options of `forecast render --help` by their long names (e.g. `clusters = 32`)",
            o.key
        );
        return Err(error_at(scene, o, m, None));
    };
    match MethodArgs::foreign_flag(own, std::slice::from_ref(&name.id)) {
        Some(e) => Err(error_at(scene, o, e.to_string(), Some(e))),
        None => Ok(name),
    }
}

/// `message` at `o`'s line and key, as the scene reader words its errors; `cause`: the method's
/// refusal that `message` words.
fn error_at(scene: &Scene, o: &RenderOption, message: String, cause: Option<MethodError>) -> RenderError {
    let at = SceneError { file: scene.path.clone(), line: o.line, key: format!("render.{}", o.key), message };
    RenderError::SceneOption { at, cause: cause.map(Box::new) }
}

/// clap's message without its `error: ` and its hints (`For more information, try '--help'`).
fn clap_message(e: &clap::Error) -> String {
    let text = e.to_string();
    let first = text.lines().next().unwrap_or_default();
    first.strip_prefix("error: ").unwrap_or(first).to_string()
}
