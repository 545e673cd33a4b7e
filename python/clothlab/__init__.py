"""clothlab: cloth simulation on any Vulkan or OpenGL GPU, or the CPU.

One cloth model (grids and triangle meshes, several cloths, eight integrators, moving
colliders, Coulomb friction, self-collision, wind) on several backends: ``cpu`` and
``cpu-par`` (rayon threads, SIMD), and on the GPU ``wgpu``, raw ``vulkan`` and raw ``gl``,
each also as its ``-naive`` variant. Every GPU kernel has a CPU twin it is checked against
(:func:`validate`); every kernel is timed (:meth:`Sim.timings`, :func:`bench`).

Quick start::

    import clothlab
    clothlab.backends()                      # what this machine can run
    sim = clothlab.Sim(scene="scenes/heap.toml", backend="vulkan", integrator="xpbd")
    sim.step(frames=10)
    x = sim.positions()                      # numpy float32 (N, 3)

Errors are :class:`ClothlabError` with the command line's one-line message, raised as
:class:`ClothlabTypeError` (also a ``TypeError``: an argument of the wrong type),
:class:`ClothlabValueError` (also a ``ValueError``: a bad value, a scene file's error) or
:class:`ClothlabRuntimeError` (also a ``RuntimeError``: no GPU adapter, a driver's
failure). Stepping releases the GIL.
"""

from __future__ import annotations

import json
import os
from typing import Any, Dict, Iterable, List, Mapping, Optional, Sequence, Tuple, Union

import numpy as np

# Mesa's device-select layer (an implicit Vulkan layer) connects to the Wayland display
# for every Vulkan instance that enables the Wayland surface extension (wgpu's always
# does), and libwayland prints "error: XDG_RUNTIME_DIR is invalid or not set" on stderr
# wherever that variable is unset: X11, Xvfb, a terminal or a notebook server without a
# login session. There the layer is switched off by its documented variable, as the
# command line does (app/src/main.rs runs itself again with it); it only orders the GPUs,
# and clothlab picks its own. The Vulkan loader reads it when an instance is created, so
# setting it before the first one is enough. A variable the user set is left as it is.
if "XDG_RUNTIME_DIR" not in os.environ:
    os.environ.setdefault("NODEVICE_SELECT", "1")

from . import _clothlab  # noqa: E402
from ._clothlab import ClothlabError, ClothlabRuntimeError, ClothlabTypeError, ClothlabValueError  # noqa: E402

__all__ = [
    "Sim",
    "ClothlabError",
    "ClothlabTypeError",
    "ClothlabValueError",
    "ClothlabRuntimeError",
    "backends",
    "integrators",
    "validate",
    "bench",
    "__version__",
]
__version__: str = _clothlab.__version__

PathLike = Union[str, "os.PathLike[str]"]

BACKENDS = ("cpu", "cpu-par", "wgpu-naive", "wgpu", "vulkan-naive", "vulkan", "gl-naive", "gl")


def _value(value: Any) -> str:
    """A parameter value as ``--set`` reads it: a string as it is, anything else as JSON."""
    if isinstance(value, str):
        return value
    if isinstance(value, np.ndarray):
        value = value.tolist()
    elif isinstance(value, np.generic):
        value = value.item()
    try:
        return json.dumps(value, allow_nan=True)
    except TypeError as e:
        raise ClothlabTypeError(f"a parameter value must be a number, a bool, a string or a list: {e}") from None


def _sets(params: Optional[Mapping[str, Any]]) -> List[str]:
    if params is None:
        return []
    if not isinstance(params, Mapping):
        raise ClothlabTypeError(f"params must be a dict of parameter names to values, not {type(params).__name__}")
    return [f"{name}={_value(v)}" for name, v in params.items()]


def _path(p: Optional[PathLike]) -> Optional[str]:
    return None if p is None else os.fspath(p)


def _floats(x: Any, what: str) -> np.ndarray:
    """``x`` as a contiguous float32 array, or a :class:`ClothlabTypeError` saying why not."""
    try:
        return np.ascontiguousarray(x, dtype=np.float32)
    except (TypeError, ValueError) as e:
        raise ClothlabTypeError(f"{what}: expected an array of numbers, got {type(x).__name__} ({e})") from None


def _rows3(x: Any, n: int, what: str) -> np.ndarray:
    a = _floats(x, what)
    if a.shape != (n, 3):
        raise ClothlabValueError(f"{what}: expected an array of shape ({n}, 3), got {a.shape}")
    return a


def _whole(k: Any, what: str) -> int:
    """``k`` as an int: a :class:`ClothlabTypeError` for what is not a whole number."""
    if isinstance(k, bool) or not isinstance(k, (int, np.integer)):
        raise ClothlabTypeError(f"{what} must be a whole number, not {k!r}")
    return int(k)


def backends() -> List[Dict[str, Any]]:
    """Every backend and whether this machine can run it.

    Returns a list of dicts: ``name`` (what :class:`Sim` takes), ``api`` (``"wgpu"``,
    ``"vulkan"``, ``"gl"``, or ``None`` for the CPU), ``available`` (bool), ``adapter``
    (the device it runs on, e.g. ``"llvmpipe (LLVM 15.0.6, 256 bits) (Vulkan)"``) and
    ``error`` (why not, when unavailable).
    """
    return [
        {"name": name, "api": api, "available": adapter is not None, "adapter": adapter, "error": error}
        for name, api, adapter, error in _clothlab.backends()
    ]


def integrators() -> Dict[str, str]:
    """The integrators by name, with a one-line summary of each."""
    return dict(_clothlab.integrators())


class Sim:
    """A scene simulated on one backend.

    ``Sim(scene=None, backend="cpu", integrator=None, params=None, n=None, toml=None,
    variant=None, set_variant=None, envs=None, grad=False)``

    * ``scene`` -- a scene file (TOML, see ``scenes/``); ``toml`` -- a scene file's text
      instead; neither: the default scene (a grid over three spheres and a floor).
    * ``backend`` -- ``cpu``, ``cpu-par``, ``wgpu``, ``vulkan``, ``gl`` or a ``-naive``
      one (see :func:`backends`).
    * ``integrator`` -- e.g. ``"verlet"``, ``"implicit"``, ``"xpbd"``, ``"vbd"`` (see
      :func:`integrators`); default: the scene's.
    * ``params`` -- parameter overrides, ``{"substeps": 16, "damping": 0.001}``: any name
      ``clothlab sim --set`` takes (docs/parameters.md), checked.
    * ``n`` -- a grid's particles per side (default 100, or the scene file's).
    * ``variant``, ``set_variant`` -- a GPU backend's preset (``"naive"``,
      ``"optimized"``, ``"thesis"``) and single switches (``["fusion=tile"]``).
    * ``envs`` -- worlds: copies of the scene stepped together, each with its own state
      and parameters (default: the scene file's ``envs``, else 1; on a GPU backend every
      kernel runs once for all worlds, and what its worlds share — the spring table, the
      integrator — must be the same in each). A parameter takes one value per world as an array
      (``params={"damping": np.linspace(0, 0.01, 64)}``); the state's arrays gain a
      leading axis of worlds, ``(envs, N, 3)``. World k computes, bit for bit, what a
      single run with its parameters computes.
    * ``grad`` -- record the run for gradients (:meth:`backward`, docs/gradients.md):
      each frame's starting state is kept; one world, Verlet or symplectic Euler without
      wind, self-contact or Coulomb friction (on a GPU backend its adjoint kernels walk
      the recording back, on cloths of up to 128 × 128). What has no adjoint yet is
      refused when opened.

    Everything is checked before the solver opens; a refusal raises
    :class:`ClothlabError` with the reason. The solver lives on a thread of its own:
    a call waits for it with the GIL released.
    """

    def __init__(
        self,
        scene: Optional[PathLike] = None,
        backend: str = "cpu",
        integrator: Optional[str] = None,
        params: Optional[Mapping[str, Any]] = None,
        n: Optional[int] = None,
        toml: Optional[str] = None,
        variant: Optional[str] = None,
        set_variant: Optional[Sequence[str]] = None,
        envs: Optional[int] = None,
        grad: bool = False,
    ) -> None:
        if not isinstance(backend, str):
            raise ClothlabTypeError(f"backend must be a name such as 'cpu' or 'vulkan', not {backend!r}")
        if n is not None and not 0 < _whole(n, "n") < 2**32:
            raise ClothlabValueError(f"n must be a positive whole number of particles per side, not {n!r}")
        if envs is not None and not 0 < _whole(envs, "envs") < 2**32:
            raise ClothlabValueError(f"envs must be a positive whole number of worlds, not {envs!r}")
        if not isinstance(grad, (bool, np.bool_)):
            raise ClothlabTypeError(f"grad must be True or False, not {grad!r}")
        self._sim = _clothlab.Sim(
            backend,
            scene=_path(scene),
            toml=toml,
            n=None if n is None else int(n),
            integrator=integrator,
            sets=_sets(params),
            preset=variant,
            set_variant=list(set_variant or []),
            envs=None if envs is None else int(envs),
            grad=bool(grad),
        )
        self._info = self._sim.info()

    def __repr__(self) -> str:
        i = self._info
        what = f"scene {i['title']!r}" if i["title"] else "the default scene"
        return f"<clothlab.Sim {i['name']} on {i['adapter']}: {what}, {i['particles']} particles, t = {self.time:.4f} s>"

    # -- what it is ---------------------------------------------------------------------

    @property
    def backend(self) -> str:
        """The backend's name."""
        return self._info["backend"]

    @property
    def name(self) -> str:
        """The solver's name: backend and variant (e.g. ``vulkan``, ``wgpu+fusion=tile``)."""
        return self._info["name"]

    @property
    def adapter(self) -> str:
        """Where it runs: the GPU adapter and API, or ``CPU``."""
        return self._info["adapter"]

    @property
    def num_particles(self) -> int:
        """Particles in the state (of one world: the rows of :meth:`positions`)."""
        return self._info["particles"]

    @property
    def envs(self) -> int:
        """Worlds (1 for a single run)."""
        return self._info["envs"]

    def _shaped(self, a: np.ndarray) -> np.ndarray:
        """Every world's rows as ``(envs, N, ...)`` in a batch, as they are in a single run."""
        return a if self.envs == 1 else a.reshape((self.envs, self.num_particles) + a.shape[1:])

    def _rows(self, x: Any, what: str) -> np.ndarray:
        """``x`` as the rows of every world: ``(N, 3)``, or ``(envs, N, 3)`` in a batch."""
        if self.envs == 1:
            return _rows3(x, self.num_particles, what)
        a = _floats(x, what)
        want = (self.envs, self.num_particles, 3)
        if a.shape != want:
            raise ClothlabValueError(f"{what}: expected an array of shape {want}, got {a.shape}")
        return a.reshape(-1, 3)

    @property
    def title(self) -> Optional[str]:
        """The scene file's title, if it has one."""
        return self._info["title"]

    # -- stepping -----------------------------------------------------------------------

    def step(self, frames: int = 1) -> None:
        """Advance ``frames`` frames (each ``params["substeps"]`` substeps of
        ``frame_dt / substeps`` seconds)."""
        self._sim.step(_count(frames, "frames"))

    def substep(self, k: int = 1) -> None:
        """Advance ``k`` substeps (each run as a frame of one substep of the same dt)."""
        self._sim.substep(_count(k, "k"))

    # -- gradients ----------------------------------------------------------------------

    def backward(self, positions: Any = None, velocities: Any = None) -> Dict[str, Any]:
        """The gradients of a loss of the final state, back through every frame recorded
        since the recording began (``grad=True``; :meth:`reset_grad`).

        ``positions``, ``velocities`` -- the loss's gradient with respect to the final
        positions and velocities, array-likes of shape (N, 3) (either may be omitted:
        zeros). Returns a dict: ``"positions"`` and ``"velocities"`` -- the gradient with
        respect to the recording's initial state, float64 (N, 3); ``"params"`` --
        ``{name: value}`` for each differentiable parameter under its ``params`` name
        (the stiffnesses and dampings, the moduli, ``damping``, ``air_drag``,
        ``cloth_mass``, ``friction``, ``gravity[0]`` … ``gravity[2]``); ``"pinned"`` --
        the pinned particles' indices; ``"pins"`` -- float64 (frames, pinned, 3), the
        gradient with respect to each pinned particle's position during each frame
        (what a controller that sets them between frames moves). At a contact the
        derivative is the side the run took (docs/gradients.md).
        """
        n = self.num_particles
        x = None if positions is None else _rows3(positions, n, "positions")
        v = None if velocities is None else _rows3(velocities, n, "velocities")
        return self._sim.backward(x, v)

    def reset_grad(self) -> None:
        """Start a new recording for gradients from the current state and parameters
        (changing the parameters, the masses or the free particles' state between
        frames starts one too)."""
        self._sim.reset_grad()

    @property
    def recorded(self) -> Optional[Tuple[int, int]]:
        """Frames recorded for gradients and the bytes their checkpoints hold (``None``
        without ``grad``)."""
        return self._sim.recorded()

    @property
    def time(self) -> float:
        """Simulated time, s (settable: moving colliders and pins go where their motion
        puts them then)."""
        return self._sim.time()

    @time.setter
    def time(self, t: float) -> None:
        self._sim.set_time(float(t))

    # -- state --------------------------------------------------------------------------

    def positions(self) -> np.ndarray:
        """Positions, m: float32 array of shape (N, 3), or (envs, N, 3) in a batch."""
        return self._shaped(self._sim.positions())

    def velocities(self) -> np.ndarray:
        """Velocities, m/s: float32 array of shape (N, 3), or (envs, N, 3)."""
        return self._shaped(self._sim.velocities())

    def normals(self) -> np.ndarray:
        """Unit vertex normals: float32 array of shape (N, 3), or (envs, N, 3)."""
        return self._shaped(self._sim.normals())

    def inverse_masses(self) -> np.ndarray:
        """Inverse masses, 1/kg: float32 array of shape (N,), or (envs, N); 0 is pinned."""
        return self._shaped(self._sim.inverse_masses())

    def set_positions(self, x: Any) -> None:
        """Set the positions (any array-like of shape (N, 3), or (envs, N, 3) in a batch;
        finite, else refused with nothing changed)."""
        self._sim.set_positions(self._rows(x, "positions"))

    def set_velocities(self, v: Any) -> None:
        """Set the velocities (any array-like of shape (N, 3), or (envs, N, 3); finite)."""
        self._sim.set_velocities(self._rows(v, "velocities"))

    def set_inverse_masses(self, w: Any) -> None:
        """Set the inverse masses, 1/kg (shape (N,), or (envs, N); finite, ≥ 0; 0 pins a
        particle)."""
        a = _floats(w, "inverse masses")
        want = (self.num_particles,) if self.envs == 1 else (self.envs, self.num_particles)
        if a.shape != want:
            raise ClothlabValueError(f"inverse masses: expected shape {want}, got {a.shape}")
        self._sim.set_inverse_masses(a.reshape(-1))

    def reset(self, envs: Optional[Iterable[int]] = None) -> None:
        """Restore worlds to their state and time at opening, as a new run starts (all of
        them, or the worlds listed in ``envs``); their parameters stay."""
        worlds = None if envs is None else [_count(k, "a world") for k in envs]
        self._sim.reset(worlds)

    def triangles(self) -> np.ndarray:
        """The triangles as particle indices: int32 array of shape (T, 3)."""
        return self._sim.triangles()

    def cloths(self) -> List[Dict[str, Any]]:
        """Each cloth's particles and triangles: dicts with ``label``, ``first``, ``count``,
        ``first_triangle``, ``triangles`` (particles ``first : first + count`` of
        :meth:`positions`)."""
        return self._sim.cloths()

    # -- parameters ---------------------------------------------------------------------

    def set(self, name: str, value: Any) -> None:
        """Set one parameter (any ``--set`` name, e.g. ``sim.set("damping", 0.001)`` or
        ``sim.set("wind", [2, 0, 1])``), checked against the cloth; refused with nothing
        changed. In a batch one value per world: ``sim.set("damping", array_of_envs)``
        (``wind``: an (envs, 4) array)."""
        if not isinstance(name, str):
            raise ClothlabTypeError(f"a parameter name is a string, not {name!r}")
        self._sim.set([f"{name}={_value(value)}"])

    def update(self, params: Mapping[str, Any]) -> None:
        """Set several parameters at once: all of them or, when one is refused, none."""
        self._sim.set(_sets(params))

    @property
    def params(self) -> Dict[str, Any]:
        """Every parameter by name (a copy: change them with :meth:`set`)."""
        return json.loads(self._sim.params_json())

    # -- interaction --------------------------------------------------------------------

    def grab(self, particle: int, target: Sequence[float]) -> None:
        """Grab ``particle`` and hold it at ``target`` (x, y, z in m) until :meth:`release`."""
        t = [float(v) for v in _floats(target, "a grab target").reshape(-1)]
        if len(t) != 3:
            raise ClothlabValueError(f"a grab target is (x, y, z), got {len(t)} values")
        self._sim.grab(_count(particle, "particle"), t)

    def release(self) -> None:
        """Let go of the grabbed particle."""
        self._sim.release()

    def set_pin_pose(self, group: int, offset: Any, rotate_deg: Any = (0.0, 0.0, 0.0)) -> None:
        """Move ``[[pins]]`` group ``group`` (one the scene marks ``scripted = true``) to
        ``offset`` (m, from where the scene placed it) turned by ``rotate_deg`` about its
        pivot (degrees about x, then y, then z), over the next frame at constant speed, and
        hold it there. In a batch ``offset`` and ``rotate_deg`` may be ``(envs, 3)``: one
        pose per world."""
        g = _count(group, "group")
        o = _floats(offset, "set_pin_pose: offset")
        r = _floats(rotate_deg, "set_pin_pose: rotate_deg")
        per_world = o.ndim == 2 or r.ndim == 2
        if per_world:
            want = (self.envs, 3)
            o = np.broadcast_to(o, want) if o.shape in ((3,), want) else o
            r = np.broadcast_to(r, want) if r.shape in ((3,), want) else r
            if o.shape != want or r.shape != want:
                raise ClothlabValueError(f"set_pin_pose: one pose per world is ({self.envs}, 3), got {o.shape} and {r.shape}")
            for k in range(self.envs):
                self._sim.set_pin_pose(g, [float(v) for v in o[k]], [float(v) for v in r[k]], k)
            return
        if o.shape != (3,) or r.shape != (3,):
            raise ClothlabValueError(f"set_pin_pose: offset and rotate_deg are (x, y, z), got {o.shape} and {r.shape}")
        self._sim.set_pin_pose(g, [float(v) for v in o], [float(v) for v in r], None)

    # -- measuring ----------------------------------------------------------------------

    def timings(self) -> Dict[str, Dict[str, float]]:
        """Per-kernel timings since the last reset: ``{kernel: {"median_us", "min_us",
        "max_us", "samples"}}``, per substep (``frame`` per frame)."""
        return {
            label: {"median_us": med / 1e3, "min_us": lo / 1e3, "max_us": hi / 1e3, "samples": samples}
            for label, samples, med, lo, hi in self._sim.timings()
        }

    def reset_timings(self) -> None:
        """Forget the recorded timings."""
        self._sim.reset_timings()

    def crossings(self) -> int:
        """Edges that pass through triangles they share no vertex with, now (0 for cloth
        that has not passed through itself)."""
        return self._sim.crossings()

    # -- output -------------------------------------------------------------------------

    def render(self, width: int = 640, height: int = 480, mode: str = "triangles", api: Optional[str] = None) -> np.ndarray:
        """The scene drawn now: uint8 array of shape (height, width, 4), RGBA, top row
        first. ``mode``: ``"triangles"``, ``"lines"`` or ``"points"``. A GPU backend draws
        through its own API; a CPU one through ``api`` (default wgpu)."""
        image, _adapter = self._sim.render(_count(width, "width"), _count(height, "height"), mode, api)
        return image

    def record(self, path: PathLike, frames: int = 120, every: int = 1, world: Optional[int] = None) -> int:
        """Run ``frames`` frames recording every ``every``-th (and the first) to a binary
        glTF file (as ``clothlab sim --record``); returns the frames kept. In a batch every
        world is recorded, each a node ``world k`` laid out on a grid, or ``world`` alone."""
        w = None if world is None else _count(world, "world")
        return self._sim.record(os.fspath(path), _count(frames, "frames"), _count(every, "every"), w)

    def close(self) -> None:
        """Release the solver and its device now (later calls raise)."""
        self._sim.close()

    def __enter__(self) -> "Sim":
        return self

    def __exit__(self, *exc: Any) -> None:
        self.close()


def _count(k: Any, what: str) -> int:
    if _whole(k, what) < 0:
        raise ClothlabValueError(f"{what} must be a whole number ≥ 0, not {k!r}")
    return int(k)


def _names(backend: Optional[str], backends: Optional[Iterable[str]], default: Sequence[str]) -> List[str]:
    if backend is not None and backends is not None:
        raise ClothlabValueError("give backend or backends, not both")
    if backend is not None:
        return [backend]
    if backends is not None:
        if isinstance(backends, str):
            return [backends]
        return list(backends)
    return list(default)


def validate(
    backend: Optional[str] = None,
    backends: Optional[Iterable[str]] = None,
    scene: Optional[PathLike] = None,
    toml: Optional[str] = None,
    params: Optional[Mapping[str, Any]] = None,
    n: Optional[int] = None,
    steps: int = 200,
    every_switch: bool = False,
    bisect: bool = False,
    envs: Optional[int] = None,
) -> List[Dict[str, Any]]:
    """Check GPU backends against the CPU (as ``clothlab validate``): every kernel of the
    backend's recipe against its CPU twin on random inputs, and a rollout of ``steps``
    substeps against the CPU solver. With ``envs``: a batch of that many worlds (their
    values the lists in ``params``) on each backend, each world against a single run
    with its parameters (on ``cpu`` for the CPU backends, on the backend itself for a GPU
    one; ``validate --envs``).

    ``backend`` or ``backends``: GPU backends (default: every one; with ``envs``,
    ``cpu`` and ``cpu-par``). Returns one dict per check: ``backend``, ``check`` (kernel,
    rollout or world), ``buffer``, ``max_abs``, ``rms``, ``error`` (relative for
    kernels, metres for rollouts and worlds), ``bound``, ``passed``, ``adapter``.
    """
    default = ["cpu", "cpu-par"] if envs is not None else [b for b in BACKENDS if not b.startswith("cpu")]
    names = _names(backend, backends, default)
    rows = _clothlab.validate(
        names,
        scene=_path(scene),
        toml=toml,
        n=None if n is None else _count(n, "n"),
        steps=_count(steps, "steps"),
        every_switch=bool(every_switch),
        bisect=bool(bisect),
        sets=_sets(params),
        envs=None if envs is None else _count(envs, "envs"),
    )
    keys = ("backend", "check", "buffer", "max_abs", "rms", "error", "bound", "passed", "adapter")
    return [dict(zip(keys, r)) for r in rows]


def bench(
    sizes: Sequence[int] = (64,),
    backends: Optional[Iterable[str]] = None,
    frames: int = 30,
    scene: Optional[PathLike] = None,
    toml: Optional[str] = None,
    params: Optional[Mapping[str, Any]] = None,
    resolution: Sequence[int] = (640, 360),
) -> List[Dict[str, Any]]:
    """Measure backends at grid sizes (as one cell of ``clothlab bench`` each): a few
    warm-up frames, ``frames`` frames timed kernel by kernel, then ``frames`` frames
    timed whole with an offscreen render each.

    Returns one dict per row: ``backend``, ``n``, ``adapter``, ``table`` (``"kernel"``:
    per-kernel times per substep, with ``substep`` the whole substep; ``"frame"``:
    ``sim``, ``render``, ``frame`` per frame), ``label``, ``median_us``, ``min_us``,
    ``max_us``, ``samples``. A GPU backend this machine lacks is skipped with a warning.
    """
    import warnings

    names = _names(None, backends, ["cpu", "cpu-par"])
    if isinstance(sizes, (int, np.integer)):
        sizes = [sizes]
    if isinstance(resolution, (str, bytes)) or not isinstance(resolution, Iterable):
        raise ClothlabTypeError(f"resolution is (width, height), not {resolution!r}")
    res = [_whole(v, "a resolution") for v in resolution]
    if len(res) != 2:
        raise ClothlabValueError(f"resolution is (width, height), got {len(res)} values")
    rows, skipped = _clothlab.bench(
        names,
        [_count(s, "size") for s in sizes],
        frames=_count(frames, "frames"),
        scene=_path(scene),
        toml=toml,
        sets=_sets(params),
        resolution=(res[0], res[1]),
    )
    for s in skipped:
        warnings.warn(f"clothlab.bench skipped {s}", stacklevel=2)
    keys = ("backend", "n", "adapter", "table", "label", "samples", "median_ns", "min_ns", "max_ns")
    out = []
    for r in rows:
        d = dict(zip(keys, r))
        for k in ("median", "min", "max"):
            d[f"{k}_us"] = d.pop(f"{k}_ns") / 1e3
        out.append(d)
    return out
