//! What is simulated: the scene and parameters of a scene file, a scene file's text, or
//! the default scene, with a grid size, an integrator and `NAME=VALUE` overrides (through
//! the serde form of `SimParams`) applied over them — the command line's `--scene`,
//! `--n`, `--integrator` and `--set`.

use std::path::PathBuf;

use anyhow::{Context, Result, bail};
use clothlab_core::{Integrator, OrbitCamera, Scene, SceneFile, SimParams};

/// Where a scene comes from.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub enum SceneSource {
    /// The default scene (three spheres and a floor under a grid).
    #[default]
    Default,
    /// A scene file (TOML; see `scenes/` and docs/scenes.md).
    File(PathBuf),
    /// A scene file's text (mesh paths in it are relative to the working folder).
    Toml(String),
}

/// A scene and what applies over it: what every command that simulates takes.
#[derive(Debug, Clone, Default)]
pub struct Physics {
    /// The scene.
    pub scene: SceneSource,
    /// The integrator, over the scene's.
    pub integrator: Option<Integrator>,
    /// `NAME=VALUE` parameter overrides (names as in `SimParams`; docs/parameters.md).
    pub set: Vec<String>,
}

/// A scene and its parameters, checked, with what a scene file says about the view.
#[derive(Debug, Clone)]
pub struct Setup {
    /// The scene.
    pub scene: Scene,
    /// The parameters.
    pub params: SimParams,
    /// The file's camera, if it sets one.
    pub camera: Option<OrbitCamera>,
    /// The file's light position, if it sets one.
    pub light: Option<[f32; 3]>,
    /// The file's title, if it has one.
    pub title: Option<String>,
    /// The file's `envs` (worlds), if it says.
    pub envs: Option<u32>,
    /// The file's `[params]` values given one per world (`SceneFile::world_params`).
    pub world_params: Vec<WorldSet>,
}

impl Setup {
    /// The default scene with an `n × n` cloth and the default parameters.
    pub fn default_with_n(n: u32) -> Self {
        Self {
            scene: Scene::with_n(n),
            params: SimParams::default(),
            camera: None,
            light: None,
            title: None,
            envs: None,
            world_params: Vec::new(),
        }
    }

    /// World `k`'s parameters: the file's values given one per world, its k-th (what
    /// world k of a batch of the file runs with; one world: the parameters).
    pub fn params_of_world(&self, k: usize) -> Result<SimParams> {
        let envs = self.envs.unwrap_or(1) as usize;
        if k >= envs {
            bail!("world {k}: the scene has {envs} worlds (0 ..= {})", envs - 1);
        }
        Ok(world_params(std::slice::from_ref(&self.params), &self.world_params, envs)?.swap_remove(k))
    }

    /// A scene file's contents.
    pub fn from_file(f: SceneFile) -> Self {
        Self {
            scene: f.scene,
            params: f.params,
            camera: f.camera,
            light: f.light,
            title: f.title,
            envs: f.envs,
            world_params: f.world_params,
        }
    }
}

impl Physics {
    /// The scene file's scene and parameters (for [`SceneSource::Default`]: the default
    /// scene with an `default_n × default_n` cloth), with `n` (a grid's side), the
    /// integrator and the overrides applied, all checked; nothing of a refused file is
    /// used. A mesh's vertices in no triangle are dropped, said once on stderr.
    pub fn setup(&self, n: Option<u32>, default_n: u32) -> Result<Setup> {
        // A file's parameters get `--integrator` and `--set` before they are checked against
        // its cloth (a scene stable under XPBD is not refused for Verlet's sake), and an
        // override's error is the command line's own.
        let mut refused = None;
        let adjust = |p: &mut SimParams| match self.apply(p) {
            Ok(q) => {
                *p = q;
                Ok(())
            }
            Err(e) => {
                let message = e.to_string();
                refused = Some(e);
                Err(message)
            }
        };
        let mut setup = match &self.scene {
            SceneSource::File(path) => match SceneFile::load_with(path, adjust) {
                Ok(f) => Setup::from_file(f),
                Err(e) => return Err(refused.unwrap_or_else(|| e.into())),
            },
            SceneSource::Toml(text) => match SceneFile::parse_with(text, "<scene text>", adjust) {
                Ok(f) => Setup::from_file(f),
                Err(e) => return Err(refused.unwrap_or_else(|| e.into())),
            },
            SceneSource::Default => {
                let mut setup = Setup::default_with_n(default_n);
                setup.params = self.apply(&setup.params)?;
                setup
            }
        };
        // A mesh's vertices in no triangle are dropped: said once, on stderr.
        if let (Some(m), Some(file)) = (&setup.scene.cloth.mesh_data, &setup.scene.cloth.mesh)
            && m.dropped() > 0
        {
            eprintln!(
                "note: {}: {} of its {} vertices are in no triangle and were dropped (pins keep the file's numbering)",
                file.display(),
                m.dropped(),
                m.file_vertices
            );
        }
        if let Some(n) = n {
            if setup.scene.cloth.is_mesh() {
                bail!("--n {n} sets a grid's side, and this scene's cloth is a mesh");
            }
            setup.scene.cloth.n = n;
        }
        if let Err(e) = setup.scene.validate() {
            match n {
                Some(n) if e.field == "cloth.n" => bail!("invalid --n {n}: {}", e.reason),
                _ => return Err(e.into()),
            }
        }
        Ok(setup)
    }

    /// `params` with the overrides and the integrator applied, validated.
    pub fn apply(&self, params: &SimParams) -> Result<SimParams> {
        let mut p = apply_overrides(params, &self.set)?;
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

/// An override with one value per world: the parameter's name and the worlds' values.
pub type WorldSet = (String, Vec<serde_json::Value>);

/// `NAME=VALUE` overrides split into those every world takes and those with one value per
/// world: a list where the parameter takes one value (`damping=[0.01,0.02]`), or a list of
/// lists where it takes a list (`wind=[[1,0,0,0],[2,0,0,0]]`). What is not one of these
/// (an unknown name, a word) is left to [`apply_overrides`] to take or refuse.
pub fn split_world_sets(sets: &[String]) -> (Vec<String>, Vec<WorldSet>) {
    let (mut common, mut per_world) = (Vec::new(), Vec::new());
    for s in sets {
        let parsed = s.split_once('=').and_then(|(name, raw)| {
            let value: serde_json::Value = serde_json::from_str(raw.trim()).ok()?;
            Some((name.trim().to_owned(), clothlab_core::params::per_world(name.trim(), &value)?))
        });
        match parsed {
            Some(w) => per_world.push(w),
            None => common.push(s.clone()),
        }
    }
    (common, per_world)
}

/// The lists that give each world its value: the scene file's (`setup.world_params`) less
/// those whose names `sets` (every `--set`) gives again, then the command line's own
/// (`per_world`, from [`split_world_sets`]). [`crate::Sim::open`] and
/// [`crate::SimOptions::world`] both take them so.
pub fn world_lists(setup: &Setup, sets: &[String], per_world: Vec<WorldSet>) -> Vec<WorldSet> {
    let named = |s: &String| s.split_once('=').map(|(n, _)| n.trim().to_owned());
    let given: Vec<String> = sets.iter().filter_map(named).collect();
    setup.world_params.iter().filter(|(name, _)| !given.contains(name)).cloned().chain(per_world).collect()
}

/// Every list of `per_world` holds one value a world of `envs`, or the first that does
/// not is named.
pub fn check_lists(per_world: &[WorldSet], envs: usize) -> Result<()> {
    for (name, values) in per_world {
        if values.len() != envs {
            let worlds = if envs == 1 { "1 world".to_string() } else { format!("{envs} worlds") };
            let n = values.len();
            bail!("`{name}` has {n} value{} for {worlds}: give one per world", if n == 1 { "" } else { "s" });
        }
    }
    Ok(())
}

/// Each of `envs` worlds' parameters: `base` with world k's value of every override in
/// `per_world` applied (each list one value per world), each world's checked on its own;
/// a refusal names the world.
pub fn world_params(base: &[SimParams], per_world: &[WorldSet], envs: usize) -> Result<Vec<SimParams>> {
    check_lists(per_world, envs)?;
    (0..envs)
        .map(|k| {
            let sets: Vec<String> = per_world.iter().map(|(name, v)| format!("{name}={}", v[k])).collect();
            apply_overrides(&base[k.min(base.len() - 1)], &sets).map_err(|e| anyhow::anyhow!("world {k}: {e}"))
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_files_world_takes_its_value_of_each_list_and_a_world_past_the_batch_is_refused() {
        // What the app shows of a file of several worlds (world 0 of a dropped file,
        // `run --world K`): the k-th of each `[params]` list, the rest as the file says.
        let text = "envs = 3\n[cloth]\nn = 6\n[params]\ndamping = [0.0, 0.01, 0.1]\nair_drag = 0.3\n";
        let setup = Setup::from_file(clothlab_core::scene_file::SceneFile::parse(text, "w.toml").unwrap());
        let p = setup.params_of_world(2).unwrap();
        assert_eq!((p.damping, p.air_drag), (0.1, 0.3));
        assert_eq!(setup.params_of_world(0).unwrap().damping, 0.0);
        let err = setup.params_of_world(3).unwrap_err().to_string();
        assert!(err.contains("world 3: the scene has 3 worlds (0 ..= 2)"), "{err}");
    }
}
