//! clothlab's native Python module, `clothlab._clothlab`: the facade crate's [`clothlab::Sim`],
//! `backends`, `validate` and `bench` for Python. The package's Python layer
//! (`python/clothlab/__init__.py`) is the public API: it checks and converts arguments
//! (numpy arrays, parameter values) and documents every call; this module does the work.
//!
//! Each `Sim` runs on a thread of its own, which opens the solver and keeps it: a GPU
//! context (OpenGL's above all) stays on the thread that made it, and Python threads may
//! call from anywhere. A call hands the thread a job and waits for its answer with the GIL
//! released, so other Python threads run while the cloth steps. Every error is a
//! `clothlab.ClothlabError` with the command line's one-line message — a
//! `ClothlabValueError` (a `ValueError`), or a `ClothlabRuntimeError` (a `RuntimeError`)
//! where a device or driver failed; a panic on the thread (never expected) is one too, and
//! the `Sim` is closed after it.

use std::sync::Mutex;
use std::sync::mpsc::{Receiver, Sender, channel, sync_channel};
use std::thread::JoinHandle;

use clothlab::{Backend, Physics, SceneSource, SimOptions};
use numpy::{PyArray1, PyArrayMethods, PyReadonlyArray1, PyReadonlyArray2};
use pyo3::exceptions::{PyException, PyRuntimeError, PyTypeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList, PyTuple};

pyo3::create_exception!(
    _clothlab,
    ClothlabError,
    PyException,
    "What clothlab refused or could not do, in one line: raised as ClothlabTypeError (a TypeError: a wrong type), ClothlabValueError (a ValueError: a bad value, a scene file's error) or ClothlabRuntimeError (a RuntimeError: a missing GPU, a driver's failure)."
);

/// The three kinds of [`ClothlabError`] (each also the builtin error it names), made when
/// the module loads: `(name, builtin, doc)`.
const KINDS: [(&str, &str, &str); 3] = [
    ("ClothlabTypeError", "TypeError", "An argument of the wrong type."),
    ("ClothlabValueError", "ValueError", "An argument, parameter or file clothlab refuses."),
    (
        "ClothlabRuntimeError",
        "RuntimeError",
        "A device, driver or thread that failed (no GPU adapter, a driver error).",
    ),
];

/// An error as Python sees it: the message and its causes on one line, as a
/// `ClothlabRuntimeError` where a device or driver failed, else a `ClothlabValueError`.
fn py_err(e: anyhow::Error) -> PyErr {
    let runtime = e.chain().any(|c| {
        matches!(
            c.downcast_ref::<clothlab::core::error::SolverError>(),
            Some(clothlab::core::error::SolverError::NoAdapter(_) | clothlab::core::error::SolverError::Driver(_))
        )
    });
    let msg: Vec<String> = e.chain().map(|c| c.to_string()).collect();
    kind_err(if runtime { "ClothlabRuntimeError" } else { "ClothlabValueError" }, msg.join(": "))
}

/// A `name` error (one of [`KINDS`]) with `msg`; the base class if the module's own is
/// not found (never expected: made when it loads).
fn kind_err(name: &str, msg: impl Into<String>) -> PyErr {
    let msg: String = msg.into();
    Python::attach(|py| {
        let class = py.import("clothlab._clothlab").and_then(|m| m.getattr(name));
        match class.and_then(|c| c.call1((msg.clone(),))) {
            Ok(err) => PyErr::from_value(err),
            Err(_) => ClothlabError::new_err(msg),
        }
    })
}

/// A job for a simulation's thread.
type Job = Box<dyn FnOnce(&mut clothlab::Sim) + Send>;

/// A simulation on its own thread.
#[pyclass(module = "clothlab._clothlab")]
struct Sim {
    jobs: Mutex<Option<Sender<Job>>>,
    thread: Mutex<Option<JoinHandle<()>>>,
}

impl Sim {
    /// Runs `f` on the simulation's thread with the GIL released and returns its answer.
    fn call<T: Send + 'static>(
        &self,
        py: Python<'_>,
        f: impl FnOnce(&mut clothlab::Sim) -> anyhow::Result<T> + Send + 'static,
    ) -> PyResult<T> {
        let (tx, rx) = sync_channel(1);
        let sent = {
            let jobs = self.jobs.lock().map_err(|_| kind_err("ClothlabValueError", "the simulation is closed"))?;
            let Some(jobs) = jobs.as_ref() else {
                return Err(kind_err("ClothlabValueError", "the simulation is closed"));
            };
            jobs.send(Box::new(move |sim: &mut clothlab::Sim| {
                let _ = tx.send(f(sim));
            }))
        };
        if sent.is_err() {
            return Err(kind_err("ClothlabRuntimeError", "the simulation's thread has stopped"));
        }
        match py.detach(move || rx.recv()) {
            Ok(r) => r.map_err(py_err),
            Err(_) => {
                // The job dropped its answer: it panicked, and the thread is gone.
                self.shut();
                Err(kind_err(
                    "ClothlabRuntimeError",
                    "internal error: the simulation's thread stopped (a bug: please report it)",
                ))
            }
        }
    }

    /// Ends the thread (after the jobs already sent).
    fn shut(&self) {
        if let Ok(mut jobs) = self.jobs.lock() {
            jobs.take();
        }
        let handle = self.thread.lock().ok().and_then(|mut t| t.take());
        if let Some(h) = handle
            && h.thread().id() != std::thread::current().id()
        {
            let _ = h.join();
        }
    }
}

/// A timing row: label, samples, median, min and max (ns).
type TimingRow = (String, usize, f64, f64, f64);

/// A backend as `backends()` lists it: name, API, adapter, why not.
type BackendRow = (String, Option<String>, Option<String>, Option<String>);

/// Rows of `(N, 3)` float32 as a flat vector of triples.
fn rows3(a: &PyReadonlyArray2<'_, f32>) -> PyResult<Vec<[f32; 3]>> {
    let v = a.as_array();
    if v.ncols() != 3 {
        return Err(kind_err(
            "ClothlabValueError",
            format!("expected an (N, 3) array, got ({}, {})", v.nrows(), v.ncols()),
        ));
    }
    Ok(v.rows().into_iter().map(|r| [r[0], r[1], r[2]]).collect())
}

/// `(N, 3)` float32 of triples.
fn array3<'py>(py: Python<'py>, v: Vec<[f32; 3]>) -> PyResult<Bound<'py, PyAny>> {
    let n = v.len();
    Ok(PyArray1::from_vec(py, v.into_flattened()).reshape([n, 3])?.into_any())
}

#[pymethods]
impl Sim {
    /// Opens a scene on a backend (see `clothlab.Sim`).
    #[new]
    #[pyo3(signature = (backend, scene=None, toml=None, n=None, integrator=None, sets=Vec::new(), preset=None, set_variant=Vec::new(), envs=None, grad=false))]
    #[allow(clippy::too_many_arguments)]
    fn new(
        py: Python<'_>,
        backend: &str,
        scene: Option<std::path::PathBuf>,
        toml: Option<String>,
        n: Option<u32>,
        integrator: Option<&str>,
        sets: Vec<String>,
        preset: Option<String>,
        set_variant: Vec<String>,
        envs: Option<u32>,
        grad: bool,
    ) -> PyResult<Self> {
        let options = (|| -> anyhow::Result<SimOptions> {
            let backend = Backend::parse(backend)?;
            let scene = match (scene, toml) {
                (Some(_), Some(_)) => anyhow::bail!("give a scene file or a scene's TOML text, not both"),
                (Some(path), None) => SceneSource::File(path),
                (None, Some(text)) => SceneSource::Toml(text),
                (None, None) => SceneSource::Default,
            };
            let integrator = match integrator {
                None => None,
                Some(name) => Some(clothlab::Integrator::parse(name).ok_or_else(|| {
                    let names: Vec<&str> = clothlab::Integrator::ALL.iter().map(|i| i.name()).collect();
                    anyhow::anyhow!("unknown integrator `{name}` (known: {})", names.join(", "))
                })?),
            };
            let variant = clothlab::variant_spec(backend, preset.as_deref(), &set_variant)?;
            Ok(SimOptions {
                backend,
                physics: Physics { scene, integrator, set: sets },
                n,
                gpu: clothlab::GpuSetup { variant, ..Default::default() },
                envs,
                grad,
            })
        })()
        .map_err(py_err)?;
        let (jobs, inbox): (Sender<Job>, Receiver<Job>) = channel();
        let (ready_tx, ready_rx) = sync_channel::<anyhow::Result<()>>(1);
        let thread = std::thread::Builder::new()
            .name("clothlab-sim".into())
            .spawn(move || {
                let mut sim = match clothlab::Sim::open(options) {
                    Ok(s) => {
                        let _ = ready_tx.send(Ok(()));
                        s
                    }
                    Err(e) => {
                        let _ = ready_tx.send(Err(e));
                        return;
                    }
                };
                while let Ok(job) = inbox.recv() {
                    job(&mut sim);
                }
            })
            .map_err(|e| kind_err("ClothlabRuntimeError", format!("cannot start the simulation's thread: {e}")))?;
        match py.detach(move || ready_rx.recv()) {
            Ok(Ok(())) => Ok(Sim { jobs: Mutex::new(Some(jobs)), thread: Mutex::new(Some(thread)) }),
            Ok(Err(e)) => {
                let _ = thread.join();
                Err(py_err(e))
            }
            Err(_) => {
                let _ = thread.join();
                Err(kind_err("ClothlabRuntimeError", "internal error: opening the simulation stopped its thread"))
            }
        }
    }

    /// Facts about the simulation: backend, solver name, adapter, particles, triangles,
    /// scene title.
    fn info<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let (backend, name, adapter, np, nt, title, envs) = self.call(py, |s| {
            Ok((
                s.backend().name(),
                s.name().to_owned(),
                s.adapter(),
                s.num_particles(),
                s.triangles().len(),
                s.title().map(str::to_owned),
                s.envs(),
            ))
        })?;
        let d = PyDict::new(py);
        d.set_item("backend", backend)?;
        d.set_item("name", name)?;
        d.set_item("adapter", adapter)?;
        d.set_item("particles", np)?;
        d.set_item("triangles", nt)?;
        d.set_item("title", title)?;
        d.set_item("envs", envs)?;
        Ok(d)
    }

    /// Advances `frames` frames.
    fn step(&self, py: Python<'_>, frames: u64) -> PyResult<()> {
        self.call(py, move |s| s.step(frames))
    }

    /// The gradients of a loss of the final state (see `clothlab.Sim.backward`): a dict of
    /// `positions` and `velocities` ((N, 3) float64), `params` ({name: float}), `pinned`
    /// (the pinned particles' indices) and `pins` ((frames, pinned, 3) float64).
    #[pyo3(signature = (positions=None, velocities=None))]
    fn backward<'py>(
        &self,
        py: Python<'py>,
        positions: Option<PyReadonlyArray2<'py, f32>>,
        velocities: Option<PyReadonlyArray2<'py, f32>>,
    ) -> PyResult<Bound<'py, PyDict>> {
        let x = positions.as_ref().map(rows3).transpose()?;
        let v = velocities.as_ref().map(rows3).transpose()?;
        let g = self.call(py, move |s| s.backward(x.as_deref(), v.as_deref()))?;
        let d = PyDict::new(py);
        let array = |rows: Vec<[f64; 3]>| -> PyResult<Bound<'py, PyAny>> {
            let n = rows.len();
            Ok(PyArray1::from_vec(py, rows.into_flattened()).reshape([n, 3])?.into_any())
        };
        d.set_item("positions", array(g.positions)?)?;
        d.set_item("velocities", array(g.velocities)?)?;
        let params = PyDict::new(py);
        for (name, value) in g.params {
            params.set_item(name, value)?;
        }
        d.set_item("params", params)?;
        let (frames, pinned) = (g.pins.len(), g.pinned.len());
        d.set_item("pinned", PyArray1::from_vec(py, g.pinned))?;
        let pins: Vec<f64> = g.pins.into_iter().flatten().flatten().collect();
        d.set_item("pins", PyArray1::from_vec(py, pins).reshape([frames, pinned, 3])?)?;
        Ok(d)
    }

    /// Starts a new recording for gradients from the current state and parameters.
    fn reset_grad(&self, py: Python<'_>) -> PyResult<()> {
        self.call(py, |s| s.reset_grad())
    }

    /// Frames recorded for gradients and the bytes their checkpoints hold, or None.
    fn recorded(&self, py: Python<'_>) -> PyResult<Option<(usize, usize)>> {
        self.call(py, |s| Ok(s.recorded()))
    }

    /// Advances `k` substeps.
    fn substep(&self, py: Python<'_>, k: u64) -> PyResult<()> {
        self.call(py, move |s| s.substep(k))
    }

    /// Moves a scripted pin group to a pose over the next frame (world `world`, or all).
    #[pyo3(signature = (group, offset, rotate_deg, world=None))]
    fn set_pin_pose(
        &self,
        py: Python<'_>,
        group: usize,
        offset: [f32; 3],
        rotate_deg: [f32; 3],
        world: Option<usize>,
    ) -> PyResult<()> {
        self.call(py, move |s| s.set_pin_pose(group, offset, rotate_deg, world))
    }

    /// Restores worlds (all, or those listed) to their state and time at opening.
    #[pyo3(signature = (worlds=None))]
    fn reset(&self, py: Python<'_>, worlds: Option<Vec<usize>>) -> PyResult<()> {
        self.call(py, move |s| s.reset(worlds.as_deref()))
    }

    /// Simulated time, s.
    fn time(&self, py: Python<'_>) -> PyResult<f64> {
        self.call(py, |s| Ok(s.time()))
    }

    /// Sets the simulated time, s.
    fn set_time(&self, py: Python<'_>, t: f64) -> PyResult<()> {
        self.call(py, move |s| s.set_time(t))
    }

    /// Positions, (N, 3) float32.
    fn positions<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        array3(py, self.call(py, |s| s.positions())?)
    }

    /// Velocities, (N, 3) float32.
    fn velocities<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        array3(py, self.call(py, |s| s.velocities())?)
    }

    /// Normals, (N, 3) float32.
    fn normals<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        array3(py, self.call(py, |s| s.normals())?)
    }

    /// Inverse masses, (N,) float32.
    fn inverse_masses<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray1<f32>>> {
        Ok(PyArray1::from_vec(py, self.call(py, |s| s.inverse_masses())?))
    }

    /// Sets the positions from (N, 3) float32.
    fn set_positions(&self, py: Python<'_>, x: PyReadonlyArray2<'_, f32>) -> PyResult<()> {
        let x = rows3(&x)?;
        self.call(py, move |s| s.set_positions(&x))
    }

    /// Sets the velocities from (N, 3) float32.
    fn set_velocities(&self, py: Python<'_>, v: PyReadonlyArray2<'_, f32>) -> PyResult<()> {
        let v = rows3(&v)?;
        self.call(py, move |s| s.set_velocities(&v))
    }

    /// Sets the inverse masses from (N,) float32.
    fn set_inverse_masses(&self, py: Python<'_>, w: PyReadonlyArray1<'_, f32>) -> PyResult<()> {
        let w = w.as_array().to_vec();
        self.call(py, move |s| s.set_inverse_masses(&w))
    }

    /// Triangles, (T, 3) int32.
    fn triangles<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let t = self.call(py, |s| Ok(s.triangles().to_vec()))?;
        let n = t.len();
        let flat: Vec<i32> = t.into_iter().flatten().map(|i| i as i32).collect();
        Ok(PyArray1::from_vec(py, flat).reshape([n, 3])?.into_any())
    }

    /// Each cloth's ranges: a list of dicts.
    fn cloths<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyList>> {
        let parts = self.call(py, |s| Ok(s.cloths()))?;
        let list = PyList::empty(py);
        for p in parts {
            let d = PyDict::new(py);
            d.set_item("label", p.label)?;
            d.set_item("first", p.first)?;
            d.set_item("count", p.count)?;
            d.set_item("first_triangle", p.first_triangle)?;
            d.set_item("triangles", p.triangles)?;
            list.append(d)?;
        }
        Ok(list)
    }

    /// Applies `NAME=VALUE` overrides (all or none).
    fn set(&self, py: Python<'_>, sets: Vec<String>) -> PyResult<()> {
        self.call(py, move |s| s.set(&sets))
    }

    /// The parameters as JSON text.
    fn params_json(&self, py: Python<'_>) -> PyResult<String> {
        self.call(py, |s| Ok(serde_json::to_string(&s.params_json()?)?))
    }

    /// Grabs a particle and holds it at a target.
    fn grab(&self, py: Python<'_>, particle: u32, target: [f32; 3]) -> PyResult<()> {
        self.call(py, move |s| s.grab(particle, target))
    }

    /// Lets go of the grabbed particle.
    fn release(&self, py: Python<'_>) -> PyResult<()> {
        self.call(py, |s| {
            s.release();
            Ok(())
        })
    }

    /// Per-kernel timings: a list of (label, samples, median_ns, min_ns, max_ns).
    fn timings(&self, py: Python<'_>) -> PyResult<Vec<TimingRow>> {
        let t = self.call(py, |s| Ok(s.timings()))?;
        Ok(t.rows.into_iter().map(|r| (r.label, r.samples, r.median_ns, r.min_ns, r.max_ns)).collect())
    }

    /// Forgets the timings.
    fn reset_timings(&self, py: Python<'_>) -> PyResult<()> {
        self.call(py, |s| {
            s.reset_timings();
            Ok(())
        })
    }

    /// Crossings in the current state.
    fn crossings(&self, py: Python<'_>) -> PyResult<usize> {
        self.call(py, |s| s.crossings())
    }

    /// The scene drawn now: (H, W, 4) uint8 and the adapter.
    #[pyo3(signature = (width, height, mode, api=None))]
    fn render<'py>(
        &self,
        py: Python<'py>,
        width: u32,
        height: u32,
        mode: &str,
        api: Option<&str>,
    ) -> PyResult<(Bound<'py, PyAny>, String)> {
        let mode = match mode {
            "triangles" => clothlab::RenderMode::Triangles,
            "lines" => clothlab::RenderMode::Lines,
            "points" => clothlab::RenderMode::Points,
            other => {
                return Err(kind_err(
                    "ClothlabValueError",
                    format!("unknown render mode `{other}` (known: triangles, lines, points)"),
                ));
            }
        };
        let api = api.map(clothlab::Api::parse).transpose().map_err(py_err)?;
        let (pixels, adapter) = self.call(py, move |s| {
            let view = s.view(mode);
            s.render(width, height, &view, api)
        })?;
        let image = PyArray1::from_vec(py, pixels).reshape([height as usize, width as usize, 4])?;
        Ok((image.into_any(), adapter))
    }

    /// Records `frames` frames to a .glb (world `world` of a batch, or every world);
    /// returns the frames kept.
    #[pyo3(signature = (path, frames, every, world=None))]
    fn record(
        &self,
        py: Python<'_>,
        path: std::path::PathBuf,
        frames: u64,
        every: u32,
        world: Option<usize>,
    ) -> PyResult<usize> {
        self.call(py, move |s| s.record(&path, frames, every, world))
    }

    /// Ends the simulation's thread; later calls raise.
    fn close(&self) {
        self.shut();
    }
}

impl Drop for Sim {
    fn drop(&mut self) {
        self.shut();
    }
}

/// Every backend: (name, api or None, adapter or None, why not or None).
#[pyfunction]
fn backends(py: Python<'_>) -> Vec<BackendRow> {
    let found = py.detach(clothlab::available);
    found
        .into_iter()
        .map(|(b, r)| {
            let api = b.api().map(|a| a.name().to_owned());
            match r {
                Ok(adapter) => (b.name().to_owned(), api, Some(adapter), None),
                Err(e) => (b.name().to_owned(), api, None, Some(e)),
            }
        })
        .collect()
}

/// Parses backend names.
fn parse_backends(names: &[String]) -> anyhow::Result<Vec<Backend>> {
    names.iter().map(|n| Backend::parse(n)).collect()
}

/// The scene of a file or a TOML text.
fn source(scene: Option<std::path::PathBuf>, toml: Option<String>) -> anyhow::Result<SceneSource> {
    Ok(match (scene, toml) {
        (Some(_), Some(_)) => anyhow::bail!("give a scene file or a scene's TOML text, not both"),
        (Some(p), None) => SceneSource::File(p),
        (None, Some(t)) => SceneSource::Toml(t),
        (None, None) => SceneSource::Default,
    })
}

/// One validation check as a dict.
type CheckRow = (String, String, String, f64, f64, f64, f64, bool, String);

/// Runs validate; a list of (backend, check, buffer, max_abs, rms, error, bound, passed, adapter).
#[pyfunction]
#[pyo3(signature = (backends, scene=None, toml=None, n=None, steps=200, every_switch=false, bisect=false, sets=Vec::new(), envs=None))]
#[allow(clippy::too_many_arguments)]
fn validate(
    py: Python<'_>,
    backends: Vec<String>,
    scene: Option<std::path::PathBuf>,
    toml: Option<String>,
    n: Option<u32>,
    steps: u32,
    every_switch: bool,
    bisect: bool,
    sets: Vec<String>,
    envs: Option<u32>,
) -> PyResult<Vec<CheckRow>> {
    let run = move || -> anyhow::Result<Vec<CheckRow>> {
        let opts = clothlab::ValidateOptions {
            backends: parse_backends(&backends)?,
            physics: Physics { scene: source(scene, toml)?, integrator: None, set: sets },
            n,
            steps,
            bisect,
            every_switch,
            preset: None,
            set_variant: Vec::new(),
            envs,
        };
        let v = clothlab::validate(&opts, |_| Ok(()))?;
        Ok(v.checks()
            .map(|(b, c)| {
                (
                    b.to_owned(),
                    c.what.clone(),
                    c.buffer.to_string(),
                    f64::from(c.max_abs),
                    f64::from(c.rms),
                    f64::from(c.error),
                    f64::from(c.bound),
                    c.passed(),
                    v.adapter(b).unwrap_or_default().to_owned(),
                )
            })
            .collect())
    };
    // The GPU devices are opened and closed on this thread, with the GIL released.
    py.detach(run).map_err(py_err)
}

/// One bench row: (backend, n, adapter, table, label, samples, median_ns, min_ns, max_ns).
type BenchRow = (String, u32, String, String, String, usize, f64, f64, f64);

/// Runs bench cells; rows, and the backends skipped with why.
#[pyfunction]
#[pyo3(signature = (backends, sizes, frames=30, scene=None, toml=None, sets=Vec::new(), resolution=(640, 360)))]
#[allow(clippy::too_many_arguments)]
#[pyo3(name = "bench")]
fn bench_cells(
    py: Python<'_>,
    backends: Vec<String>,
    sizes: Vec<u32>,
    frames: u32,
    scene: Option<std::path::PathBuf>,
    toml: Option<String>,
    sets: Vec<String>,
    resolution: (u32, u32),
) -> PyResult<(Vec<BenchRow>, Vec<String>)> {
    let run = move || -> anyhow::Result<(Vec<BenchRow>, Vec<String>)> {
        let opts = clothlab::bench::BenchOptions {
            backends: parse_backends(&backends)?,
            sizes,
            frames,
            resolution,
            physics: Physics { scene: source(scene, toml)?, integrator: None, set: sets },
        };
        let run = clothlab::bench::cells(&opts)?;
        let mut rows = Vec::new();
        for c in &run.cells {
            for (table, list) in [("kernel", &c.kernels), ("frame", &c.frames)] {
                for r in list {
                    rows.push((
                        c.backend.clone(),
                        c.n,
                        c.adapter.clone(),
                        table.to_owned(),
                        r.label.clone(),
                        r.samples,
                        r.median_ns,
                        r.min_ns,
                        r.max_ns,
                    ));
                }
            }
        }
        Ok((rows, run.skipped))
    };
    py.detach(run).map_err(py_err)
}

/// The integrators' names.
#[pyfunction]
fn integrators() -> Vec<(&'static str, &'static str)> {
    clothlab::Integrator::ALL.iter().map(|i| (i.name(), i.summary())).collect()
}

/// The native module.
#[pymodule]
fn _clothlab(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    let base = py.get_type::<ClothlabError>();
    m.add("ClothlabError", &base)?;
    let builtins = [
        ("TypeError", py.get_type::<PyTypeError>()),
        ("ValueError", py.get_type::<PyValueError>()),
        ("RuntimeError", py.get_type::<PyRuntimeError>()),
    ];
    for (name, builtin, doc) in KINDS {
        let other = builtins.iter().find(|(n, _)| *n == builtin).map(|(_, t)| t.clone()).expect("a builtin of KINDS");
        let attrs = PyDict::new(py);
        attrs.set_item("__doc__", doc)?;
        attrs.set_item("__module__", "clothlab")?;
        let bases = PyTuple::new(py, [base.clone().into_any(), other.into_any()])?;
        let class = py.import("builtins")?.getattr("type")?.call1((name, bases, attrs))?;
        m.add(name, class)?;
    }
    m.add_class::<Sim>()?;
    m.add_function(wrap_pyfunction!(backends, m)?)?;
    m.add_function(wrap_pyfunction!(validate, m)?)?;
    m.add_function(wrap_pyfunction!(bench_cells, m)?)?;
    m.add_function(wrap_pyfunction!(integrators, m)?)?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}
