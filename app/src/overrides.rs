//! The simulation parameters of a command line: `--set NAME=VALUE` through the serde form
//! of `SimParams`, and `--integrator`.

use anyhow::{Context, Result, bail};
use clothlab_core::SimParams;

use crate::cli::PhysicsArgs;

impl PhysicsArgs {
    /// The defaults with `--set` and `--integrator` applied, validated.
    pub fn params(&self) -> Result<SimParams> {
        let mut p = apply_overrides(&SimParams::default(), &self.set)?;
        if let Some(i) = self.integrator {
            p.integrator = i;
        }
        p.validate()?;
        Ok(p)
    }
}

/// Applies `NAME=VALUE` overrides to `params` through its serde form, so every field is
/// reachable and an unknown name or a value of the wrong type is refused.
pub fn apply_overrides(params: &SimParams, sets: &[String]) -> Result<SimParams> {
    let mut value = serde_json::to_value(params)?;
    for s in sets {
        let Some((name, raw)) = s.split_once('=') else {
            bail!("--set expects NAME=VALUE, got `{s}`");
        };
        let name = name.trim();
        let obj = value.as_object_mut().context("parameters are not an object")?;
        let Some(slot) = obj.get_mut(name) else {
            let mut known: Vec<&String> = obj.keys().collect();
            known.sort();
            let known: Vec<&str> = known.iter().map(|s| s.as_str()).collect();
            bail!("unknown parameter `{name}` (known: {})", known.join(", "));
        };
        let parsed: serde_json::Value = match raw.trim() {
            // JSON has no NaN or infinities; name them so that validate() refuses them
            // with its own message instead of a parse error.
            "nan" | "NaN" | "inf" | "-inf" | "infinity" | "-infinity" => {
                bail!("invalid parameter `{name}` = {raw}: must be a finite number")
            }
            // A word that is not JSON is a string (`stiffness_units=physical`).
            r => serde_json::from_str(r).unwrap_or_else(|_| serde_json::Value::String(r.to_owned())),
        };
        *slot = parsed;
    }
    let out: SimParams =
        serde_json::from_value(value).map_err(|e| anyhow::anyhow!("a parameter of the wrong type: {e}"))?;
    out.validate()?;
    Ok(out)
}
