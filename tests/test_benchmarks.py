"""The benchmarks' fast versions: they run, their outputs have the structure the docs describe,
and what they show makes sense (the full runs are in docs/RESULTS.md)."""

from __future__ import annotations

import csv
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


def run(script: str, *args: str, out: Path) -> str:
    proc = subprocess.run([sys.executable, str(ROOT / "benchmarks" / script), *args, "--out", str(out)], cwd=ROOT,
                          capture_output=True, text=True, timeout=900, env={"PYTHONPATH": str(ROOT), "PATH": ""})  # fmt: skip
    assert proc.returncode == 0, proc.stderr[-2000:]
    return proc.stdout


def test_methods_chart_has_every_method_and_ours_converges_with_the_time_step(tmp_path):
    out = run("methods.py", "--tiny", "--no-bound", out=tmp_path)
    rows = list(csv.DictReader(open(tmp_path / "methods.csv")))
    assert (tmp_path / "methods.png").stat().st_size > 10_000
    from softgrasp_env.config import FINGER_KINDS
    from softgrasp_env.presets import PRESETS

    families = {r["method"] for r in rows}
    assert {k for k in FINGER_KINDS if k != "tissue"} <= families and "tissue, thesis" in families
    assert {r["setting"] for r in rows if r["method"] == "preset"} == set(PRESETS)
    by = {(r["method"], r["setting"]): r for r in rows}
    assert all(r["held"] == "True" for r in rows), [(r["method"], r["setting"]) for r in rows if r["held"] != "True"]
    # the pose error against the converged run falls as the time step does
    assert float(by["tissue, thesis", "dt/2"]["pose_rms_mm"]) < 0.5 * float(by["tissue, thesis", "default"]["pose_rms_mm"])
    # rigid blocks are the fastest; every method's speed was measured
    assert float(by["rigid", "rigid"]["steps_per_s"]) > max(float(r["steps_per_s"]) for r in rows if r["method"] != "rigid")
    assert "convergence order" in out
