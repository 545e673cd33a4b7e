"""The Python package against the library underneath: state in and out, refusals with
their messages, free fall against the analytic recurrence, substeps against frames,
validate's rows, a rendered image, a recording, bench's rows, a GL solver called from
another thread.

GPU tests run on whatever Vulkan and GL this machine has (lavapipe and llvmpipe in CI);
with CLOTHLAB_REQUIRE_GPU=1 (as .ci/run sets) a missing one fails instead of skipping.
"""

import os
import threading
from pathlib import Path

import numpy as np
import pytest

import clothlab

ROOT = Path(__file__).resolve().parents[2]
SCENES = ROOT / "scenes"


def _need(backend):
    """Skips (or, with CLOTHLAB_REQUIRE_GPU=1, fails) where `backend` has no adapter."""
    found = {b["name"]: b for b in clothlab.backends()}
    if not found[backend]["available"]:
        msg = f"{backend}: {found[backend]['error']}"
        if os.environ.get("CLOTHLAB_REQUIRE_GPU") == "1":
            pytest.fail(msg)
        pytest.skip(msg)


def test_backends_lists_every_backend_and_the_cpu_runs_everywhere():
    found = clothlab.backends()
    assert [b["name"] for b in found] == list(clothlab.BACKENDS)
    cpu = found[0]
    assert cpu["available"] and cpu["api"] is None and cpu["error"] is None
    for b in found:
        # Either an adapter or why not: never both, never neither.
        assert (b["adapter"] is None) != (b["error"] is None), b


def test_state_goes_in_and_comes_out_exactly_and_bad_state_is_refused_with_nothing_changed():
    sim = clothlab.Sim(n=16, backend="cpu-par")
    assert sim.num_particles == 256
    x = sim.positions()
    assert x.shape == (256, 3) and x.dtype == np.float32
    moved = x + np.float32(0.25)
    sim.set_positions(moved)
    # Written and read as float32: exact.
    assert np.array_equal(sim.positions(), moved)
    v = np.tile(np.array([0.5, -1.0, 0.25], dtype=np.float64), (256, 1))  # float64 in: converted
    sim.set_velocities(v)
    assert np.array_equal(sim.velocities(), v.astype(np.float32))

    bad = moved.copy()
    bad[7, 1] = np.nan
    with pytest.raises(clothlab.ClothlabError, match="particle 7"):
        sim.set_positions(bad)
    with pytest.raises(ValueError, match=r"shape \(256, 3\)"):
        sim.set_positions(moved[:10])
    assert np.array_equal(sim.positions(), moved), "a refused state changes nothing"

    tri = sim.triangles()
    assert tri.shape == (2 * 15 * 15, 3) and tri.dtype == np.int32
    assert tri.min() == 0 and tri.max() == 255
    assert sim.cloths() == [{"label": "cloth", "first": 0, "count": 256, "first_triangle": 0, "triangles": 450}]


def test_inverse_masses_are_the_particles_mass_and_zero_where_pinned():
    sim = clothlab.Sim(n=10, backend="cpu")
    w = sim.inverse_masses()
    mass = sim.params["cloth_mass"]
    free = w[w > 0]
    # A grid's particles share the cloth's mass equally: 1/w = mass/N to float rounding.
    assert np.allclose(1.0 / free, mass / 100, rtol=1e-6)
    assert (w == 0).sum() >= 1, "the default scene pins its top corners"
    w2 = np.full(100, 2.0, dtype=np.float32)
    sim.set_inverse_masses(w2)
    assert np.allclose(sim.inverse_masses(), w2, rtol=1e-6)
    with pytest.raises(ValueError, match="≥ 0"):
        sim.set_inverse_masses(-w2)


def test_parameters_are_checked_and_refused_with_the_command_lines_message():
    sim = clothlab.Sim(n=8)
    sim.set("damping", 0.001)
    assert sim.params["damping"] == pytest.approx(0.001)
    sim.set("wind", [2, 0, 1])
    assert sim.params["wind"] == [2.0, 0.0, 1.0]
    with pytest.raises(ValueError, match="finite"):
        sim.set("damping", float("nan"))
    with pytest.raises(ValueError, match=r"unknown parameter `dampig` \(known: .*damping"):
        sim.set("dampig", 0.1)
    with pytest.raises(ValueError, match="substeps"):
        sim.set("substeps", 0)
    before = sim.params
    with pytest.raises(ValueError):
        sim.update({"damping": 0.002, "substeps": -1})
    assert sim.params == before, "a refused update changes nothing"
    with pytest.raises(ValueError, match=r"unknown backend `cuda` \(known: cpu, cpu-par"):
        clothlab.Sim(backend="cuda")
    with pytest.raises(ValueError, match="unknown integrator"):
        clothlab.Sim(integrator="euler-forward")
    with pytest.raises(ValueError, match="n"):
        clothlab.Sim(n=1)
    with pytest.raises(ValueError, match="missing.toml"):
        clothlab.Sim(scene="missing.toml")
    with pytest.raises(ValueError, match="GPU backends only"):
        clothlab.Sim(backend="cpu", variant="naive")
    with pytest.raises(ValueError, match=r"<scene text>:1:7: unclosed table"):
        clothlab.Sim(toml="[cloth\nn = 4")


@pytest.mark.parametrize("backend", ["cpu", "vulkan"])
def test_free_fall_follows_the_analytic_recurrence(backend):
    if backend != "cpu":
        _need(backend)
    sim = clothlab.Sim(scene=SCENES / "free-fall.toml", backend=backend)
    p = sim.params
    dt = p["frame_dt"] / p["substeps"]
    g = p["gravity"][1]
    x0 = sim.positions().astype(np.float64)
    # The velocity at -dt/2 of a cloth at rest at 0: Verlet in velocity form is then
    # exact on the parabola but for f32 rounding.
    v = np.zeros_like(x0)
    v[:, 1] = -0.5 * g * dt
    sim.set_velocities(v)
    frames = 20
    sim.step(frames=frames)
    k = frames * p["substeps"]
    # The recurrence v += g dt; y += v dt, in float64.
    y, vy = x0[:, 1].copy(), np.full(len(x0), -0.5 * g * dt)
    for _ in range(k):
        vy += g * dt
        y += vy * dt
    t = frames * p["frame_dt"]
    assert np.allclose(y, x0[:, 1] + 0.5 * g * t * t, atol=1e-9), "the recurrence is the parabola"
    got = sim.positions()
    # f32 rounding of y and v over k substeps (the Rust suite's bound for this scene).
    ulp = 2.0**-22
    bound = k / 2 * ulp + k * k / 2 * ulp * dt
    err = np.abs(got[:, 1] - y).max()
    assert err <= bound, f"{backend}: {err:.2e} m from the recurrence (bound {bound:.1e})"
    assert sim.time == pytest.approx(t, rel=1e-6)


def test_substeps_add_up_to_a_frame():
    a = clothlab.Sim(n=12, backend="cpu")
    b = clothlab.Sim(n=12, backend="cpu")
    a.step(frames=1)
    b.substep(a.params["substeps"])
    assert b.time == pytest.approx(a.time, rel=1e-9)
    # The same substeps at the same dt. What runs once a frame (the normals, which reach
    # the dynamics only through the wind) runs after each; the default scene has no wind,
    # so the CPU's bits are the same.
    assert a.params["wind"] == [0.0, 0.0, 0.0]
    assert np.array_equal(a.positions(), b.positions())
    assert np.array_equal(a.velocities(), b.velocities())
    assert b.params["substeps"] == a.params["substeps"], "the frame's substeps are restored"


def test_a_grabbed_particle_is_held_at_its_target():
    sim = clothlab.Sim(n=10)
    sim.grab(55, [0.1, 2.5, -0.2])
    sim.step(frames=3)
    assert np.allclose(sim.positions()[55], [0.1, 2.5, -0.2], atol=1e-6)
    sim.release()
    with pytest.raises(ValueError, match="particle 100"):
        sim.grab(100, [0, 0, 0])


def test_validate_gives_one_passed_row_per_check():
    _need("vulkan")
    rows = clothlab.validate(backend="vulkan", n=8, steps=32)
    assert rows, "no checks"
    assert {"backend", "check", "buffer", "max_abs", "error", "bound", "passed", "adapter"} <= set(rows[0])
    assert any(r["check"].startswith("rollout") for r in rows)
    for r in rows:
        assert r["passed"] and r["error"] <= r["bound"], r
        assert "llvmpipe" in r["adapter"] or r["adapter"]
    with pytest.raises(ValueError, match="reference itself"):
        clothlab.validate(backend="cpu")


def test_render_draws_the_scene():
    _need("vulkan")
    sim = clothlab.Sim(scene=SCENES / "heap.toml", backend="vulkan")
    sim.step(frames=2)
    img = sim.render(96, 64)
    assert img.shape == (64, 96, 4) and img.dtype == np.uint8
    assert (img[..., 3] == 255).all(), "opaque"
    # A picture, not a cleared target: the sky, the floor and the cloth differ.
    assert img[..., :3].std() > 10
    with pytest.raises(ValueError, match="own API"):
        sim.render(96, 64, api="gl")
    with pytest.raises(ValueError, match="render mode"):
        sim.render(96, 64, mode="wireframe")


def test_a_gl_solver_steps_when_called_from_another_thread():
    _need("gl")
    sim = clothlab.Sim(n=12, backend="gl")
    out = {}

    def work():
        sim.step(frames=2)
        out["x"] = sim.positions()

    t = threading.Thread(target=work)
    t.start()
    t.join()
    cpu = clothlab.Sim(n=12, backend="cpu")
    cpu.step(frames=2)
    # GL on llvmpipe computes the CPU's bits on this scene; a real GPU rounds otherwise.
    assert np.abs(out["x"] - cpu.positions()).max() < 1e-4


def test_record_writes_a_glb(tmp_path):
    sim = clothlab.Sim(n=8)
    kept = sim.record(tmp_path / "run.glb", frames=4, every=2)
    assert kept == 3  # the first frame and frames 2 and 4
    data = (tmp_path / "run.glb").read_bytes()
    assert data[:4] == b"glTF"
    with pytest.raises(ValueError, match=".glb"):
        sim.record(tmp_path / "run.gltf", frames=1)


def test_record_of_a_batch_writes_every_world_or_the_one_asked_for(tmp_path):
    # World 1 of a damping sweep recorded alone is the recording of a single run with its
    # damping, byte for byte (a world computes a single run's bits); every world's
    # recording holds a node per world; a world past the batch is refused.
    batch = clothlab.Sim(n=6, envs=2, params={"damping": [0.01, 0.2]})
    assert batch.record(tmp_path / "all.glb", frames=2) == 3
    assert b'"world 1"' in (tmp_path / "all.glb").read_bytes()
    batch = clothlab.Sim(n=6, envs=2, params={"damping": [0.01, 0.2]})
    batch.record(tmp_path / "one.glb", frames=2, world=1)
    clothlab.Sim(n=6, params={"damping": 0.2}).record(tmp_path / "single.glb", frames=2)
    assert (tmp_path / "one.glb").read_bytes() == (tmp_path / "single.glb").read_bytes()
    with pytest.raises(ValueError, match="world 2: the batch has 2 worlds"):
        batch.record(tmp_path / "x.glb", frames=1, world=2)


def test_validate_envs_checks_each_world_against_its_single_run():
    # Two worlds of different damping on cpu and cpu-par: each world's positions and
    # velocities are its single run's (bound 0).
    rows = clothlab.validate(envs=2, params={"damping": [0.0, 0.05]}, n=6, steps=16)
    assert len(rows) == 2 * 2 * 2
    assert {r["backend"] for r in rows} == {"cpu", "cpu-par"}
    assert all(r["passed"] and r["max_abs"] == 0.0 for r in rows)
    # On a GPU backend: each world against its single run there.
    rows = clothlab.validate(backend="vulkan", envs=2, params={"damping": [0.0, 0.05]}, n=6, steps=16)
    assert len(rows) == 2 * 2 and all(r["passed"] and r["max_abs"] == 0.0 for r in rows)
    # What a GPU batch's worlds share (the spring table) differing: refused naming the world.
    with pytest.raises(ValueError, match="world 1: its spring constants"):
        clothlab.validate(backend="vulkan", envs=2, n=6, steps=16, params={"structural_stiffness": [0.5, 0.4]})


def test_bench_gives_kernel_and_frame_rows():
    rows = clothlab.bench(sizes=[16], backends=["cpu"], frames=2, resolution=(32, 32))
    kernel = {r["label"]: r for r in rows if r["table"] == "kernel"}
    frame = {r["label"]: r for r in rows if r["table"] == "frame"}
    assert "substep" in kernel and kernel["substep"]["median_us"] > 0
    assert "sim" in frame and frame["sim"]["samples"] == 2
    assert all(r["backend"] == "cpu" and r["n"] == 16 for r in rows)
    with pytest.raises(ValueError, match="2 ..= 4096"):
        clothlab.bench(sizes=[1], backends=["cpu"])


def test_a_pinned_particle_moved_by_its_position_stays_there():
    # The default scene pins the top corners (inverse mass 0): a pin's target is its
    # position, moved by set_positions and held there by every integrator.
    for integrator in ["verlet", "xpbd"]:
        sim = clothlab.Sim(n=10, integrator=integrator)
        pinned = np.flatnonzero(sim.inverse_masses() == 0)
        assert len(pinned) >= 1
        x = sim.positions()
        x[pinned] += np.float32(0.3)
        sim.set_positions(x)
        sim.step(frames=5)
        assert np.array_equal(sim.positions()[pinned], x[pinned]), integrator


def test_stepping_releases_the_gil():
    # With a switch interval of 1 s no Python thread takes the GIL from another: a counting
    # thread only counts while the main thread is inside a call that released it. Held
    # through a 20-frame step, the count would not move; released, it moves by at least
    # thousands (Python counts about ten million a second).
    import sys

    sim = clothlab.Sim(n=24, backend="cpu")
    count = [0]
    stop = threading.Event()
    started = threading.Event()

    def counter():
        started.set()
        while not stop.is_set():
            count[0] += 1

    old = sys.getswitchinterval()
    t = threading.Thread(target=counter)
    t.start()
    started.wait()
    sys.setswitchinterval(1.0)
    try:
        before = count[0]
        sim.step(frames=20)
        during = count[0] - before
    finally:
        sys.setswitchinterval(old)
        stop.set()
        t.join()
    assert during > 1000, f"the counting thread counted {during} while the cloth stepped"


def test_a_batch_of_worlds_sweeps_a_parameter_in_one_call_each_world_a_single_run():
    damping = np.array([0.0, 0.002, 0.004, 0.008], dtype=np.float32)
    sim = clothlab.Sim(n=8, backend="cpu-par", envs=4, params={"damping": damping})
    assert sim.envs == 4
    x = sim.positions()
    assert x.shape == (4, 64, 3) and x.dtype == np.float32
    assert sim.inverse_masses().shape == (4, 64)
    sim.step(10)
    after = sim.positions()
    for k in (0, 3):
        single = clothlab.Sim(n=8, backend="cpu", params={"damping": float(damping[k])})
        single.step(10)
        # World k is the single run with its damping, bit for bit.
        assert np.array_equal(after[k], single.positions()), k
    # More damping, less motion: the worlds differ as their damping does.
    assert not np.array_equal(after[0], after[3])
    # State in per world; reset brings chosen worlds back to their start.
    sim.set_velocities(np.zeros((4, 64, 3)))
    sim.reset(envs=[1])
    assert np.array_equal(sim.positions()[1], x[1])
    assert not np.array_equal(sim.positions()[2], x[2])
    sim.set("damping", np.full(4, 0.01))
    assert sim.params["damping"] == pytest.approx(0.01)
    with pytest.raises(clothlab.ClothlabError, match="`damping` has 3 values for 4 worlds"):
        sim.set("damping", [0.1, 0.2, 0.3])
    with pytest.raises(clothlab.ClothlabError, match="world 2"):
        sim.set("damping", [0.1, 0.2, 0.9, 0.1])
    with pytest.raises(clothlab.ClothlabError, match=r"shape \(4, 64, 3\)"):
        sim.set_positions(np.zeros((64, 3)))
    with pytest.raises(clothlab.ClothlabError, match="world 4"):
        sim.reset(envs=[4])
    with pytest.raises(clothlab.ClothlabError, match="envs must be a positive whole number"):
        clothlab.Sim(n=8, envs=0)


SCRIPTED = """
[cloth]
n = 8
size = 1.0
top_center = [0.0, 2.0, 0.0]
across = [1.0, 0.0, 0.0]
down = [0.0, -1.0, 0.0]
pinning = "none"
[floor]
enabled = false
[[pins]]
min = [-0.6, 1.99, -0.01]
max = [0.6, 2.01, 0.01]
scripted = true
"""


def test_a_script_moves_each_world_s_pinned_edge_where_it_says():
    sim = clothlab.Sim(toml=SCRIPTED, backend="cpu-par", envs=3)
    rest = sim.positions()[0, :8].copy()
    # World k's edge 0.1·k m along x, over one frame; then held.
    sim.set_pin_pose(0, [[0.0, 0.0, 0.0], [0.1, 0.0, 0.0], [0.2, 0.0, 0.0]])
    sim.step(2)
    for k in range(3):
        moved = sim.positions()[k, :8] - rest
        # The keys' f32 times: within 1e-6 m of the pose asked for.
        assert np.allclose(moved, [0.1 * k, 0.0, 0.0], atol=1e-6), (k, moved)
    with pytest.raises(clothlab.ClothlabError, match=r"one pose per world is \(3, 3\)"):
        sim.set_pin_pose(0, np.zeros((2, 3)))
    with pytest.raises(clothlab.ClothlabError, match="pin group 4"):
        sim.set_pin_pose(4, [0, 0, 0])


def test_errors_are_type_value_or_runtime_errors_and_all_clothlab_errors():
    sim = clothlab.Sim(n=8)
    # A wrong type: a TypeError (and a ClothlabError), never a ValueError.
    for call in (
        lambda: clothlab.Sim(n="eight"),
        lambda: clothlab.Sim(backend=3),
        lambda: sim.set(4, 0.1),
        lambda: sim.set_positions("not numbers"),
        lambda: sim.step("ten"),
        lambda: sim.update([("damping", 0.1)]),
    ):
        with pytest.raises(clothlab.ClothlabTypeError) as e:
            call()
        assert isinstance(e.value, TypeError) and isinstance(e.value, clothlab.ClothlabError)
        assert not isinstance(e.value, ValueError), e.value
    # A bad value, from the Python layer or the library underneath: a ValueError.
    for call in (
        lambda: clothlab.Sim(n=-3),
        lambda: sim.set("damping", -1.0),
        lambda: sim.set_positions(np.zeros((3, 3))),
        lambda: clothlab.Sim(scene="missing.toml"),
    ):
        with pytest.raises(clothlab.ClothlabValueError) as e:
            call()
        assert isinstance(e.value, ValueError) and not isinstance(e.value, TypeError), e.value
    # A device that is not there: a RuntimeError. Vulkan with its loader pointed at no
    # driver, in a process of its own (the loader reads the variable when it starts).
    import subprocess
    import sys

    code = (
        "import clothlab\n"
        "try:\n    clothlab.Sim(n=8, backend='vulkan')\n"
        "except clothlab.ClothlabRuntimeError as e:\n    print('runtime', isinstance(e, RuntimeError), e)\n"
    )
    env = dict(os.environ, VK_ICD_FILENAMES="/nonexistent-clothlab-icd.json")
    out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, timeout=120)
    assert out.stdout.startswith("runtime True no GPU adapter found (Vulkan)"), (out.stdout, out.stderr)


def test_listing_and_drawing_print_nothing_on_stderr_without_a_login_session():
    # Where XDG_RUNTIME_DIR is unset (Xvfb, CI, a terminal without a login session),
    # Mesa's device-select Vulkan layer made libwayland print "XDG_RUNTIME_DIR is invalid"
    # twice for every listing of the backends and every picture; the package switches the
    # layer off there (NODEVICE_SELECT), so stderr stays empty. In a process of its own:
    # the loader reads the variable when the first instance is created. Run with the
    # variable the user may have set removed too, so the package's own default is tested.
    import subprocess
    import sys

    code = (
        "import os, clothlab\n"
        "names = [b['name'] for b in clothlab.backends() if b['available']]\n"
        "sim = clothlab.Sim(n=8, backend='cpu')\n"
        "img = sim.render(64, 48)\n"
        "print(len(names), img.shape, os.environ.get('NODEVICE_SELECT'))\n"
    )
    env = {k: v for k, v in os.environ.items() if k not in ("XDG_RUNTIME_DIR", "NODEVICE_SELECT")}
    out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, out.stderr
    # Every backend of this machine listed (cpu and cpu-par at least), a picture drawn.
    count, shape = out.stdout.split(" ", 1)
    assert int(count) >= 2 and "(48, 64, 4)" in shape and shape.strip().endswith("1"), out.stdout
    assert out.stderr == "", out.stderr
    # And with the variable set by the user, the package leaves it alone.
    env["NODEVICE_SELECT"] = "0"
    out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, timeout=120)
    assert out.stdout.strip().endswith(" 0"), out.stdout


def test_the_native_modules_stubs_name_every_function_and_parameter_it_has():
    # python/clothlab/_clothlab.pyi is what type checkers and editors read for the native
    # module: every public function, class and method the module has is in it with the
    # same parameters in the same order (from pyo3's text signatures), and it names
    # nothing the module lacks. The package itself (__init__.py) is typed inline and
    # ships py.typed.
    import ast
    import inspect

    from clothlab import _clothlab

    stub = ast.parse((Path(clothlab.__file__).parent / "_clothlab.pyi").read_text())
    assert (Path(clothlab.__file__).parent / "py.typed").exists()

    def params(f: ast.FunctionDef) -> list:
        return [a.arg for a in f.args.args if a.arg != "self"]

    def native(obj) -> list:
        sig = getattr(obj, "__text_signature__", None)
        assert sig, f"{obj} has no text signature"
        return [p for p in inspect.signature(obj).parameters if p not in ("self", "$self")]

    stubbed = {}
    for node in stub.body:
        if isinstance(node, ast.FunctionDef):
            stubbed[node.name] = params(node)
        elif isinstance(node, ast.ClassDef):
            stubbed[node.name] = None
            for m in node.body:
                if isinstance(m, ast.FunctionDef):
                    stubbed[f"{node.name}.{m.name}"] = params(m)
    have = {}
    for name, obj in vars(_clothlab).items():
        if name.startswith("_"):
            continue
        if inspect.isclass(obj):
            have[name] = None
            for m, f in vars(obj).items():
                if not m.startswith("_") and callable(f):
                    have[f"{name}.{m}"] = native(f)
            if obj is _clothlab.Sim:
                have["Sim.__init__"] = native(obj)
        elif callable(obj):
            have[name] = native(obj)
    missing = sorted(set(have) - set(stubbed))
    extra = sorted(set(stubbed) - set(have) - {"__version__"})
    assert not missing and not extra, (missing, extra)
    differ = {k: (stubbed[k], have[k]) for k in have if have[k] is not None and stubbed[k] != have[k]}
    assert not differ, differ
    # Sim's methods and the four functions at least: a reader that found none proves nothing.
    assert len([k for k in have if k.startswith("Sim.")]) >= 25 and "validate" in have, sorted(have)
