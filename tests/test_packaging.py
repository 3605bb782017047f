"""A pip install is a working product: the core needs only gymnasium, pybullet, numpy and
numba; the wheel carries the license, ``py.typed`` and the best baseline of each id; and (slow, run by CI
on its own line) the wheel installed in a fresh venv without any extra, used from outside the
checkout, makes, resets and steps the newest id, runs the scripted policy and says that it compiles."""

from __future__ import annotations

import json
import os
import re
import shutil
import subprocess
import sys
import time
import venv
import zipfile
from pathlib import Path

import pytest

tomllib = pytest.importorskip("tomllib")  # Python 3.11+
ROOT = Path(__file__).resolve().parents[1]
PYPROJECT = tomllib.loads((ROOT / "pyproject.toml").read_text())
CORE = {"gymnasium", "pybullet", "numpy", "numba"}


def _names(requirements: list[str]) -> set[str]:
    return {re.split(r"[<>=!~;\[ ]", r, maxsplit=1)[0].strip().lower() for r in requirements}


def test_the_core_install_is_lean_and_the_rest_are_extras():
    project = PYPROJECT["project"]
    assert _names(project["dependencies"]) == CORE
    extras = project["optional-dependencies"]
    assert _names(extras["train"]) == {"stable-baselines3", "torch", "tensorboard", "tqdm"}
    assert _names(extras["plots"]) == {"matplotlib"} and _names(extras["video"]) == {"moviepy"}
    assert _names(extras["offline"]) == {"minari"} and _names(extras["rllib"]) == {"ray"}
    assert _names(extras["reference"]) == {"scikit-fem", "scipy"} and _names(extras["peers"]) == {"mujoco"}
    assert _names(extras["multigrid"]) == {"scipy"}
    assert _names(extras["docs"]) >= {"sphinx", "myst-parser"}
    # the CPU build on disk (2.13.0) satisfies the torch range, so pip keeps it (no CUDA download)
    (torch,) = [r for r in extras["train"] if r.startswith("torch")]
    lo, hi = re.fullmatch(r"torch>=([\d.]+),<=([\d.]+)", torch).groups()
    as_tuple = lambda v: tuple(int(x) for x in v.split("."))  # noqa: E731
    assert as_tuple(lo) <= (2, 13, 0) <= as_tuple(hi)
    # the setup script installs every extra but Ray (which gets a venv of its own) and the docs
    # toolchain (.ci/run adds it for the site's build)
    setup = (ROOT / "scripts" / "setup.sh").read_text()
    assert 'make_venv .venv "train,plots,video,offline,reference,multigrid,peers,test"' in setup
    assert setup.index('"torch==2.13.0"') < setup.index('-e ".[$2]"')


def test_the_package_imports_none_of_the_extras():
    """``import softgrasp_env`` and the policies package (what a core install runs) import neither
    torch, stable-baselines3, tensorboard nor matplotlib."""
    code = ("import sys, softgrasp_env, softgrasp_env.policies, softgrasp_env.env, softgrasp_env.render, "
            "softgrasp_env.wrappers; "
            "bad = sorted(m for m in ('torch', 'stable_baselines3', 'tensorboard', 'matplotlib', 'moviepy', 'tqdm') "
            "if m in sys.modules); print(bad)")  # fmt: skip
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT, check=True)
    assert out.stdout.strip() == "[]"


def test_files_users_expect_are_there():
    assert "MIT License" in (ROOT / "LICENSE").read_text()
    assert PYPROJECT["project"]["license"] == "MIT" and PYPROJECT["project"]["license-files"] == ["LICENSE"]
    assert (ROOT / "softgrasp_env" / "py.typed").exists()
    cff = (ROOT / "CITATION.cff").read_text()
    assert "cff-version: 1.2.0" in cff
    assert 'title: "Combining rigid body simulations with oriented particles"' in cff
    assert 'title: "Solid Simulation with Oriented Particles"' in cff and "Chentanez" in cff
    assert (ROOT / "CHANGELOG.md").read_text().startswith("# Changelog")
    assert "CHANGELOG.md" in (ROOT / "README.md").read_text()
    classifiers = PYPROJECT["project"]["classifiers"]
    assert "Typing :: Typed" in classifiers and any(c.startswith("Programming Language :: Python :: 3") for c in classifiers)
    assert PYPROJECT["project"]["urls"]
    data = PYPROJECT["tool"]["setuptools"]["package-data"]
    assert data["softgrasp_env"] == ["py.typed"]
    assert PYPROJECT["tool"]["setuptools"]["include-package-data"] is False  # the list is all there is


def _best() -> dict[str, str]:
    from softgrasp_env.policies.baselines import TRAINED, best_per_env

    return best_per_env([json.loads(p.read_text()) for p in TRAINED.glob("*/card.json")])


def test_the_wheel_lists_the_best_baseline_of_each_id():
    """pyproject's package data names exactly the best baseline of each id (the highest success on
    its card; ties to the last name), every other one stays in the repository; and every id with
    a baseline is a registered one."""
    import softgrasp_env

    listed = PYPROJECT["tool"]["setuptools"]["package-data"]["softgrasp_env.policies"]
    names = [re.fullmatch(r"trained/([\w.-]+)/\*", entry).group(1) for entry in listed]
    best = _best()
    assert sorted(names) == sorted(best.values()), (names, best)
    assert set(best) <= set(softgrasp_env.ENV_IDS)
    for name in names:
        assert (ROOT / "softgrasp_env" / "policies" / "trained" / name / "model.zip").is_file()


# --- the wheel, installed where a user would --------------------------------------------------------

_USER_SCRIPT = r'''
import json, re, sys, time
import gymnasium as gym
import softgrasp_env
from softgrasp_env.policies import ScriptedGraspPolicy, list_baselines, load_baseline

out = {"file": softgrasp_env.__file__}
newest = {}
for env_id in softgrasp_env.ENV_IDS:  # the newest version of each name
    name, version = env_id.rsplit("-v", 1)
    newest[name] = max(newest.get(name, 0), int(version))
env_id = "SoftGrasp-v%d" % newest["SoftGrasp"]
tic = time.perf_counter()
env = gym.make(env_id)
out["make_s"] = time.perf_counter() - tic
tic = time.perf_counter()
obs, info = env.reset(seed=1000)
out["reset_s"] = time.perf_counter() - tic
tic = time.perf_counter()
obs, *_ = env.step(env.action_space.sample())
out["first_step_s"] = time.perf_counter() - tic
policy = ScriptedGraspPolicy.for_env(env)  # the arm's speed and acceleration limits of this id
obs, info = env.reset(seed=1000)
steps, done = 0, False
while not done:
    obs, reward, terminated, truncated, info = env.step(policy(obs))
    steps, done = steps + 1, terminated or truncated
out.update(env=env_id, steps=steps, success=bool(info["is_success"]), in_space=bool(env.observation_space.contains(obs)))
env.close()
out["baselines"] = len(list_baselines())
from softgrasp_env.scene.objects import PRESETS, object_geometry  # the shipped meshes load from the install
out["pebble_cm3"] = round(object_geometry(PRESETS["pebble-0"]).volume * 1e6, 1)
try:
    load_baseline("SoftGrasp-v4_sac_0")  # the id's best: in the wheel
    out["load_error"] = None
except ImportError as exc:
    out["load_error"] = str(exc)
try:
    load_baseline("SoftGraspRigid-v3_ppo_0")  # not the id's best: kept in the repository, not the wheel
    out["other_error"] = None
except ValueError as exc:
    out["other_error"] = str(exc)
for mod in ("agents", "torch", "stable_baselines3", "matplotlib"):
    try:
        __import__(mod)
        out[mod] = True
    except ImportError:
        out[mod] = False
print("RESULT " + json.dumps(out))
'''


@pytest.mark.slow
def test_the_wheel_works_in_a_fresh_venv_without_extras(tmp_path):
    """Build the wheel, install it (no extras) in a new venv, and use it from a folder outside the
    checkout: the numba cache is cold there, as after any pip install. Measured: the wheel 6.5 MB
    with the best baseline of each of 7 ids (7.4 MB with 8), the install 10 s from pip's cache, the first gym.make
    35 s (the compile), then reset 0.03 s and the first step 0.004 s."""
    dist = tmp_path / "dist"
    tic = time.perf_counter()
    # from a copy of the sources without build products: setuptools packs a checkout's stale
    # build/lib as it finds it (retired models came back into a wheel that way)
    source = tmp_path / "source"
    skip = shutil.ignore_patterns(".git", ".venv*", "build", "_build", "*.egg-info", "runs", "__pycache__", ".*_cache")
    shutil.copytree(ROOT, source, symlinks=True, ignore=skip)
    subprocess.run([sys.executable, "-m", "pip", "wheel", "--no-deps", "-q", "-w", str(dist), str(source)], check=True)
    (wheel,) = dist.glob("softgrasp_env-*.whl")
    build_s = time.perf_counter() - tic
    with zipfile.ZipFile(wheel) as z:
        names = z.namelist()
    assert "softgrasp_env/py.typed" in names and any(n.endswith(".dist-info/licenses/LICENSE") for n in names)
    from softgrasp_env.scene.objects import MESHES

    assert {f"softgrasp_env/scene/meshes/{m}.obj" for m in MESHES} <= set(names)  # the pebbles' meshes
    # the wheel carries the best baseline of each id; the others stay in the repository
    current = set(_best().values())
    assert len(current) >= 3
    in_wheel = {n.split("/")[3] for n in names if n.startswith("softgrasp_env/policies/trained/")}
    assert in_wheel == current, in_wheel
    assert not any(n.startswith("agents/") or "__pycache__" in n or n.endswith((".nbi", ".nbc")) for n in names)
    # A shipped model (weights, card, log) compresses to 0.6-0.9 MB (the grip ids' 171 inputs are
    # the largest); a replay buffer, a numba cache or every seed swept in would cost tens of MB.
    # Measured: 6.5 MB for the 7 best models (7.4 MB for 8); the bound is 10 MB.
    size_mb = wheel.stat().st_size / 1e6
    assert size_mb <= 10.0 and size_mb < 1.0 * len(current) + 1, (size_mb, len(current))

    env_dir = tmp_path / "venv"
    venv.EnvBuilder(with_pip=True, clear=True).create(env_dir)  # a truly fresh venv: no system site-packages
    python = env_dir / "bin" / "python"
    tic = time.perf_counter()
    subprocess.run([str(python), "-m", "pip", "install", "-q", "--disable-pip-version-check", str(wheel)], check=True)
    install_s = time.perf_counter() - tic

    user_dir = tmp_path / "elsewhere"  # not the checkout: nothing of it on the path
    user_dir.mkdir()
    clean = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "NUMBA_CACHE_DIR", "VIRTUAL_ENV")}
    run = subprocess.run([str(python), "-c", _USER_SCRIPT], capture_output=True, text=True, cwd=user_dir, env=clean,
                         timeout=900)  # fmt: skip
    assert run.returncode == 0, run.stderr
    result = json.loads(next(line for line in run.stdout.splitlines() if line.startswith("RESULT "))[7:])
    assert result["file"].startswith(str(env_dir)), result  # the installed copy, not the checkout's
    import softgrasp_env

    newest = max((i for i in softgrasp_env.ENV_IDS if i.rsplit("-v", 1)[0] == "SoftGrasp"),
                 key=lambda i: int(i.rsplit("-v", 1)[1]))
    assert newest == "SoftGrasp-v5"
    assert result["env"] == newest and result["steps"] == 100 and result["success"] and result["in_space"]
    assert result["baselines"] == len(current)
    assert result["pebble_cm3"] == 112.7, result  # pebble-0's volume, from the installed mesh
    assert "softgrasp-env[train]" in result["load_error"]
    assert "best baseline of each id" in result["other_error"] and "source repository" in result["other_error"], result
    assert not any(result[m] for m in ("agents", "torch", "stable_baselines3", "matplotlib")), result
    # the first run talks: a line when numba starts compiling, one with the time when it is done
    assert "softgrasp_env: numba is compiling the solver's kernels" in run.stderr, run.stderr
    done = re.search(r"softgrasp_env: compiled the solver's kernels \((\d+) kernels\) in ([\d.]+) s", run.stderr)
    assert done and int(done.group(1)) >= 3, run.stderr
    assert result["reset_s"] < 2.0 and result["first_step_s"] < 2.0, result  # compiled at make, not here

    # the command that warms the cache: the env's kernels are there now (only the accuracy checks'
    # penetration kernel may still compile), and a second run finds everything cached
    for _ in range(2):
        again = subprocess.run([str(python), "-m", "softgrasp_env.compile"], capture_output=True, text=True,
                               cwd=user_dir, env=clean, timeout=600)  # fmt: skip
        assert again.returncode == 0, again
    assert "loaded from numba's cache" in again.stdout and "compiling" not in again.stderr, again
    print(f"wheel {size_mb:.1f} MB built in {build_s:.0f} s; installed in {install_s:.0f} s; first make "
          f"{result['make_s']:.1f} s ({done.group(0)}), reset {result['reset_s']:.2f} s, first step "
          f"{result['first_step_s']:.3f} s")  # fmt: skip
