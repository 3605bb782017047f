"""The benchmarks' fast versions: they run, their outputs have the structure the docs describe,
and what they show makes sense (the full runs are in docs/RESULTS.md)."""

from __future__ import annotations

import csv
import subprocess
import sys
from pathlib import Path

import pytest

from softgrasp_env.config import DEFAULT_MAX_DEVIATION
from softgrasp_env.registration import TISSUE_V3

ROOT = Path(__file__).resolve().parents[2]


def run(script: str, *args: str, out: Path) -> str:
    proc = subprocess.run([sys.executable, str(ROOT / "benchmarks" / script), *args, "--out", str(out)], cwd=ROOT,
                          capture_output=True, text=True, timeout=900, env={"PYTHONPATH": str(ROOT), "PATH": ""})  # fmt: skip
    assert proc.returncode == 0, proc.stderr[-2000:]
    return proc.stdout


def test_methods_chart_has_every_method_and_ours_converges_with_the_time_step(tmp_path):
    out = run("methods.py", "--tiny", "--no-bound", out=tmp_path)
    rows = list(csv.DictReader(open(tmp_path / "methods.csv")))
    assert (tmp_path / "methods.png").stat().st_size > 10_000
    from benchmarks.methods import TINY_PRESETS_SKIP, TINY_SKIP
    from softgrasp_env.fingers import FINGERS
    from softgrasp_env.presets import PRESETS

    families = {r["method"] for r in rows}
    assert {k for k in FINGERS if k not in ("tissue", *TINY_SKIP)} <= families and "tissue, thesis" in families
    assert {r["setting"] for r in rows if r["method"] == "preset"} == set(PRESETS) - set(TINY_PRESETS_SKIP)
    by = {(r["method"], r["setting"]): r for r in rows}
    assert all(r["held"] == "True" for r in rows), [(r["method"], r["setting"]) for r in rows if r["held"] != "True"]
    # the pose error against the converged run falls as the time step does
    assert float(by["tissue, thesis", "dt/2"]["pose_rms_mm"]) < 0.5 * float(by["tissue, thesis", "default"]["pose_rms_mm"])
    # rigid blocks (with or without torsional friction) are the fastest; every method's speed was measured
    rigid = max(float(by[k, k]["steps_per_s"]) for k in ("rigid", "rigid_torsion"))
    assert rigid > max(float(r["steps_per_s"]) for r in rows if not r["method"].startswith("rigid"))
    assert "convergence order" in out


def test_stability_map_sees_rigid_fingers_fail_where_the_tissue_holds(tmp_path):
    """The full map (docs/RESULTS.md) marks a 0.1 rad jaw wedge as rigid-slips / tissue-holds; the
    tiny map sees the same, and every method appears in its CSV."""
    run("stability_map.py", "--tiny", out=tmp_path)
    rows = list(csv.DictReader(open(tmp_path / "stability_map.csv")))
    outcome = {(r["method"], float(r["row_value"])): r["label"] for r in rows}
    from benchmarks.stability_map import TINY_SKIP
    from softgrasp_env.fingers import FINGERS

    kinds = {k for k in FINGERS if k not in ("tissue", *TINY_SKIP)}
    assert {r["method"] for r in rows} >= kinds | {"tissue, thesis", "tissue, consistent", "tissue, v4"}
    assert outcome["rigid", 0.0] == "held" and outcome["rigid", 0.1] != "held"
    assert outcome["tissue, thesis", 0.1] == "held" and outcome["tissue, consistent", 0.1] == "held"
    assert outcome["tissue, v4", 0.1] == "held"
    assert (tmp_path / "stability_map.png").stat().st_size > 5_000


def _run_plain(script: str, *args: str) -> str:
    proc = subprocess.run([sys.executable, str(ROOT / "benchmarks" / script), *args], cwd=ROOT, capture_output=True,
                          text=True, timeout=900, env={"PYTHONPATH": str(ROOT), "PATH": ""})  # fmt: skip
    assert proc.returncode == 0, proc.stderr[-2000:]
    return proc.stdout


def test_vec_throughput_measures_in_process_and_subprocess_envs():
    import re

    out = _run_plain("vec_throughput.py", "--env", "SoftGraspRigid-v3", "--seconds", "0.5", "--max-envs", "2")
    rates = [float(x) for x in re.findall(r":\s+(\d+) env steps/s", out)]
    assert len(rates) == 5 and min(rates) > 0, out  # in-process; SB3's 1 and 2 subprocesses; gymnasium's 1 and 2
    assert "gym.make_vec   2 envs (async)" in out
    assert "x1.00 over 1 subprocess" in out


def test_wedge_sign_splits_success_by_the_wedge():
    out = _run_plain("wedge_sign.py", "--policy", "scripted", "--episodes", "4")
    assert "scripted: success" in out and "|wedge|" in out and "held when the carry began:" in out


def test_build_scaling_prints_linear_memory():
    out = _run_plain("build_scaling.py", "--factors", "1", "4")
    rows = [line.split() for line in out.splitlines()[1:] if len(line.split()) == 6]  # pybullet prints argv[0]= lines
    assert len(rows) == 2
    per_particle = [float(r[5].replace(",", "")) for r in rows]
    assert max(per_particle) < 1.5 * min(per_particle)  # linear in the particle count, not quadratic


def test_random_soak_counts_divergences_and_reports_the_tissue_deviation():
    """The soak's bookkeeping on a short run (the 10^5-step run is the slow test below)."""
    from benchmarks.random_soak import soak

    r = soak("SoftGrasp-v5", 150, "noisy-scripted")
    assert r["steps"] == 150 and r["episodes"] >= 1 and r["divergences"] == []  # episodes end at 100 steps or a drop
    assert 0.0 < r["max_deviation"] < 0.03


def test_random_soak_runs_a_seeded_chunk_on_a_preset(capsys):
    """The command line of a chunk of a long soak: the preset and the seed reach the env and the
    episodes (seed * 10^6 on), and the line says so."""
    from benchmarks.random_soak import main

    assert main(["--env", "SoftGraspEasy-v4", "--preset", "fine", "--seed", "2", "--steps", "15",
                 "--streams", "uniform"]) == 0  # fmt: skip
    out = capsys.readouterr().out
    assert "SoftGraspEasy-v4 uniform (seed 2, fine): 15 steps" in out and "0 divergences" in out, out


@pytest.mark.slow
@pytest.mark.parametrize(("env_id", "keywords"), [("SoftGrasp-v4", TISSUE_V3),
                                                  ("SoftGrasp-v4", {**TISSUE_V3, "friction_law": "contact"}),
                                                  ("SoftGrasp-v4", {}), ("SoftGrasp-v5", {})],
                         ids=["thesis", "thesis-contact", "v4", "v5"])  # fmt: skip
@pytest.mark.parametrize("stream", ["uniform", "noisy-scripted"])
def test_no_tearing_in_a_hundred_thousand_random_steps(stream, env_id, keywords):
    """No tearing: 10^5 env steps on the thesis tissue (SoftGrasp-v4 with TISSUE_V3), about 1,000
    episodes, without one divergence: uniform random actions, and the harsher noisy scripted grasp
    (benchmarks/random_soak.py: the scripted policy plus Gaussian noise, pressing on rim and ground
    thousands of times). Measured: none in either (8-9 min each); the largest tissue deviation
    20.00 mm, the strain limit (TissueConfig.max_deviation). Without the limit the compliant pad
    tore 2 and 3 times, caught on the cylinder's top rim; 0.4.0's per-step pad 0 and 1. The same
    with Coulomb at every contact (friction_law="contact"): none in either (1,008 and 1,067
    episodes, 13-14 min each), the largest deviation 20.00 mm. On SoftGrasp-v4's own v4 tissue (the
    continuum material, Coulomb per contact): none in either (1,015 and 1,091 episodes, 31-33 min
    each at 50-54 env steps/s), the largest deviation 20.00 mm. On SoftGrasp-v5 (the same tissue
    solved globally): none in either (1,015 and 1,079 episodes at 329 and 183 env steps/s, 5 and
    9 min, other jobs beside), the largest deviation 20.00 mm."""
    from benchmarks.random_soak import soak

    r = soak(env_id, 100_000, stream, **keywords)
    assert r["divergences"] == [], r["divergences"]
    assert r["max_deviation"] <= DEFAULT_MAX_DEVIATION + 1e-9


@pytest.mark.slow
@pytest.mark.parametrize("stream", ["uniform", "noisy-scripted"])
def test_no_tearing_at_the_fine_preset(stream):
    """The soak at four times the particle density (SoftGrasp-v5, ``preset="fine"``), 2 x 10^4 env
    steps a stream (about 200 episodes). Measured: no divergence in either (201 and 216 episodes at
    73 and 65 env steps/s, two trainings beside), the largest deviation 20.00 mm, the strain limit."""
    from benchmarks.random_soak import soak

    r = soak("SoftGrasp-v5", 20_000, stream, preset="fine")
    assert r["divergences"] == [], r["divergences"]
    assert r["max_deviation"] <= DEFAULT_MAX_DEVIATION + 1e-9


def test_physics_floor_prints_the_floor_the_ratios_and_a_breakdown_that_adds_up():
    import re

    out = _run_plain("physics_floor.py", "--seconds", "0.3", "--repeats", "1", "--no-converged", "--ids",
                     "SoftGrasp-v4,SoftGraspRigid-v3")  # fmt: skip
    targets = out.split("targets (this run)")[1]
    assert re.search(r"SoftGrasp-v4 +[\d.]+ of the floor \(target >= 0.25\): (met|missed); hand-over \+ env \d+%", targets)
    assert re.search(r"SoftGraspRigid-v3 +[\d.]+ of the floor \(target >= 0.8\): (met|missed)", targets), out
    out = out.split("targets (this run)")[0]
    floors = [float(f.replace(",", "")) for f in re.findall(r"world step 1/(?:240|1440) s: ([\d,]+) pybullet", out)]
    assert len(floors) == 2 and min(floors) > 0, out
    table, breakdown = out.split("where an env step goes")
    rows = {line.split()[0]: line.split()[1:] for line in table.splitlines() if line.startswith("SoftGrasp")}
    soft_rate, soft_ratio, soft_pb = (float(x) for x in rows["SoftGrasp-v4"][:3])
    assert soft_rate > 0 and soft_ratio > 0, out
    assert soft_pb == 72 and float(rows["SoftGraspRigid-v3"][2]) == 12, out  # 6 world steps per physics step
    # the breakdown's second rows: pybullet, kernel, solver call, hand-over, env, total [us]
    soft = [float(x) for x in breakdown.split("SoftGrasp-v4")[1].split()[:6]]
    assert soft[1] > 0 and soft[0] > 0 and abs(sum(soft[:5]) - soft[5]) <= 3, out  # rounding of 5 figures
    rigid = [float(x) for x in breakdown.split("SoftGraspRigid-v3")[1].split()[:6]]
    assert rigid[1] == 0 and rigid[2] == 0, out  # no tissue
    # two particle rows across every face: the tip's groups round, 3 world steps per physics step
    out = _run_plain("physics_floor.py", "--seconds", "0.3", "--repeats", "1", "--no-converged", "--ids",
                     "SoftGrasp-v4", "--min-rows", "2")  # fmt: skip
    row = next(line.split() for line in out.split("where an env step goes")[0].splitlines()
               if line.startswith("SoftGrasp-v4"))  # fmt: skip
    assert int(row[3]) == 36, out
    # the material solved across its groups: the coupling's 2 world steps per physics step
    out = _run_plain("physics_floor.py", "--seconds", "0.3", "--repeats", "1", "--no-converged", "--ids",
                     "SoftGrasp-v4", "--material-solve", "global")  # fmt: skip
    row = next(line.split() for line in out.split("where an env step goes")[0].splitlines()
               if line.startswith("SoftGrasp-v4"))  # fmt: skip
    assert int(row[3]) == 24, out


def test_torch_threads_trains_at_each_count_alone_and_side_by_side():
    out = _run_plain("torch_threads.py", "--env", "SoftGraspRigid-v3", "--steps", "20", "--threads", "1")
    row = next(line.split() for line in out.splitlines() if line.strip().startswith("1 "))
    assert float(row[1]) > 0 and float(row[2]) > 0 and float(row[4]) > 0, out


def test_learners_times_a_learner_on_the_env_and_on_pendulum():
    out = _run_plain("learners.py", "--env", "SoftGraspRigid-v3", "--steps", "20", "--learners", "sac")
    row = next(line.split() for line in out.splitlines() if line.startswith("sac "))
    ours, pendulum, ratio = (float(x) for x in row[1:4])
    # the rates are printed as whole numbers, the ratio to 0.01: at a few dozen steps/s (a loaded
    # machine) the rounding of the rates alone moves their quotient by more than 0.01
    slack = 0.005 + (ours / pendulum) * (0.5 / ours + 0.5 / pendulum)
    assert ours > 0 and pendulum > 0 and abs(ratio - ours / pendulum) <= slack, out


def test_env_throughput_prints_every_id_asked_for():
    ids = "SoftGraspRigid-v3,SoftGraspRigidTorsion-v3@cylinder_mass=0.2"
    out = _run_plain("env_throughput.py", "--steps", "5", "--ids", ids)
    rows = [line.split() for line in out.splitlines() if line.startswith("SoftGrasp")]
    assert [r[0] for r in rows] == ids.split(","), out
    assert all(float(x) > 0 for r in rows for x in r[1:]), out


def test_env_throughput_reads_a_comma_inside_a_value():
    from benchmarks.env_throughput import parse_spec, split_specs

    specs = split_specs("SoftGrasp-v5,SoftGrasp-v5@tactile=(4,3),SoftGraspRigid-v3@carry_frequency=[1.5, 2.0]")
    assert [parse_spec(s) for s in specs] == [("SoftGrasp-v5", {}), ("SoftGrasp-v5", {"tactile": (4, 3)}),
                                              ("SoftGraspRigid-v3", {"carry_frequency": [1.5, 2.0]})]  # fmt: skip


def test_learner_race_writes_each_runs_curve_and_the_table(tmp_path):
    """Two learners for a few seconds of one core each, side by side: every run's evaluations on
    the training clock, the steps it reached, and the table over them."""
    out = run("learner_race.py", "--env", "SoftGraspRigid-v3", "--learners", "sac", "--seeds", "0,1", "--minutes",
              "0.1", "--every", "3", "--episodes", "1", out=tmp_path)  # fmt: skip
    import json

    for seed in (0, 1):
        result = json.loads((tmp_path / f"sac_{seed}.json").read_text())
        curve = result["curve"]
        assert result["threads"]["torch"] == 1 and len(curve) >= 2, result
        assert [r["train_seconds"] for r in curve] == sorted(r["train_seconds"] for r in curve)
        assert curve[-1]["train_seconds"] >= 6.0 and curve[-1]["timesteps"] > curve[0]["timesteps"] > 0
    assert "sac 0" in out and "sac 1" in out and "mean over seeds" in out, out


def test_incipient_slip_compares_the_pads_with_coulomb(tmp_path):
    out = _run_plain("incipient_slip.py", "--fingers", "tissue,rigid", "--plot", str(tmp_path / "slip.png"))
    rows = {line.split()[0]: line.split() for line in out.splitlines() if line.startswith(("tissue ", "rigid "))}
    assert set(rows) == {"tissue", "rigid"}, out
    for kind, row in rows.items():
        assert abs(float(row[2].rstrip("%"))) < (4.0 if kind == "tissue" else 7.0), out  # slip load vs Coulomb
    assert 0.9 < float(rows["tissue"][-1]) < 1.1, out  # the shear stays linear up to slip
    assert (tmp_path / "slip.png").stat().st_size > 10_000


def test_slip_warning_tables_the_lead_per_kind_and_writes_every_run(tmp_path):
    out = _run_plain("slip_warning.py", "--kinds", "tissue,rigid", "--rates", "2", "--squeezes", "2,4",
                     "--frictions", "0.9", "--csv", str(tmp_path / "slip.csv"))  # fmt: skip
    rows = {tuple(line.split(" | ")[:2]): line.split(" | ")[1:] for line in out.splitlines()
            if line.startswith(("| mu |", "| shear lag |"))}  # fmt: skip
    rows = {(d.lstrip("| "), k): r for (d, k), r in rows.items()}
    assert set(rows) == {(d, k) for d in ("mu", "shear lag") for k in ("tissue", "rigid")}, out
    assert rows["mu", "tissue"][2] == "2" and rows["mu", "tissue"][6].rstrip(" |") == "0", out  # warned twice, never far
    assert rows["mu", "rigid"][6].rstrip(" |") == "2", out  # on from the hold in both
    assert rows["shear lag", "tissue"][2] == "2" and rows["shear lag", "tissue"][6].rstrip(" |") == "0", out
    assert rows["shear lag", "rigid"][5] == "2", out  # no shear to read: missed both
    with open(tmp_path / "slip.csv", newline="") as f:
        runs = list(csv.DictReader(f))
    assert len(runs) == 4 and {r["kind"] for r in runs} == {"tissue", "rigid"}
    tissue = [r for r in runs if r["kind"] == "tissue"]
    assert all(0.18 <= float(r["lead_share"]) <= 0.37 for r in tissue), tissue  # measured 0.36 and 0.20
    assert all(0.24 <= float(r["lag_lead_share"]) <= 0.45 for r in tissue), tissue  # measured 0.38 and 0.27


def test_slip_warning_grip_reads_the_margin_of_a_held_tissue_grip():
    out = _run_plain("slip_warning_grip.py", "--ids", "SoftGraspGrip-v6", "--seeds", "2", "--factors", "1.2,2")
    rows = [line.split(" | ") for line in out.splitlines() if line.startswith("| SoftGraspGrip-v6")]
    assert [r[1] for r in rows] == ["1.2", "2"], out
    near, far = rows
    # measured over 12 seeds: 9 of 9 holds at 1.2 x the least read "on", 1 of 12 at 2 x
    assert near[6] == near[7].rstrip(" |") and int(near[6]) >= 1, out
    assert far[7].rstrip(" |") == "0" and far[3] == "0", out


def test_taxel_field_pictures_the_hold_and_the_slip(tmp_path):
    out = _run_plain("taxel_field.py", "--rows", "4", "--cols", "3", "--plot", str(tmp_path / "field.png"))
    import re

    rows = re.findall(r"load ([\d.]+) N: pressure x area \[([\d.]+) +([\d.]+) *\] N", out)
    assert len(rows) == 3, out
    loads = [float(r[0]) for r in rows]
    assert loads[0] < loads[1] < loads[2], out
    assert all(abs(float(x) - 3.0) < 0.1 for r in rows for x in r[1:]), out  # the squeeze, at every moment
    assert (tmp_path / "field.png").stat().st_size > 10_000


def test_env_throughput_names_a_malformed_keyword_argument():
    from benchmarks.env_throughput import parse_spec

    assert parse_spec("SoftGrasp-v5@tissue_contact_cone=True@shear_modulus=2e3") == (
        "SoftGrasp-v5", {"tissue_contact_cone": True, "shear_modulus": 2000.0})
    with pytest.raises(ValueError, match="'shear_modulus' is not key=value"):
        parse_spec("SoftGrasp-v5@shear_modulus")


def test_grasp_checks_arm_row_is_smooth():
    import re

    out = _run_plain("grasp_checks.py", "--rows", "arm")
    pattern = r"(v\d): palm peak acceleration, full-up from rest, dt 1/(\d+): ([\d.]+)"
    peak = {(v, hz): float(a) for v, hz, a in re.findall(pattern, out)}
    assert len(peak) == 3, out
    assert all(peak["v3", hz] <= 2.0 for hz in ("1000", "240", "120")), peak  # measured 1.40-1.50


def test_carry_bands_counts_the_tissue_and_the_torsional_peer_holding_in_every_band():
    """Over the whole v3 band (1.2-3 Hz x 0.5, 1 m/s^2 x across / diagonal / along, seed 1000),
    at the defaults: the scripted soft grasp and the torsional peer hold through every cell (the
    full benchmark, 10 seeds: 300 / 300 each; the plain rigid twin 54 of the 120 it lifted)."""
    out = _run_plain("carry_bands.py", "--seeds", "1", "--kinds", "tissue,rigid_torsion")
    assert "tissue          all cells: held when the carry began 30/30, held through it 30/30" in out, out
    assert "rigid_torsion   all cells: held when the carry began 30/30, held through it 30/30" in out, out


def test_carry_bands_takes_any_policy_per_kind():
    """The learned gap per band goes through --policy KIND=SPEC: random actions never lift the
    cylinder, so no cell has a grip when the carry begins; a bad spec is named."""
    out = _run_plain("carry_bands.py", "--seeds", "1", "--kinds", "rigid", "--policy", "rigid=random")
    assert "(rigid: random)" in out, out
    assert "rigid           all cells: held when the carry began 0/30, held through it 0/0" in out, out
    from benchmarks import carry_bands

    with pytest.raises(SystemExit):
        carry_bands.main(["--policy", "soft=scripted"])


def test_task_regions_split_the_same_starts_for_every_kind():
    """The per-region table: the kinds draw the same starts from a seed (so a region
    holds the same episodes in every column), each third of a drawn quantity holds a third of the
    episodes, and the scripted soft grasp and torsional peer hold every one (cards: 100 / 100)."""
    from benchmarks import task_regions

    results = {k: task_regions.episodes(k, None, range(1000, 1003)) for k in ("tissue", "rigid_torsion")}
    assert [r["success"] for r in results["tissue"]] == [1.0, 1.0, 1.0]
    assert [r["held_at_carry"] for r in results["rigid_torsion"]] == [1.0, 1.0, 1.0]
    rows = task_regions.regions(results)
    labels = {label for label, _, _ in rows}
    # v3's reach task draws the wedge, yaw, start, and the sway; not the cylinder or the friction
    assert labels == {task_regions.QUANTITIES[q] for q in ("jaw_wedge", "abs_yaw", "approach", "carry_frequency",
                                                           "carry_acceleration", "carry_direction")}, labels
    assert all(cell == {"tissue": (1, 1, 1), "rigid_torsion": (1, 1, 1)} for _, _, cell in rows), rows
    for r in results["tissue"]:
        assert -0.15 <= r["jaw_wedge"] <= 0.15 and 0.0 <= r["carry_direction"] <= 90.0
    results["rigid_torsion"][0] = {**results["rigid_torsion"][0], "jaw_wedge": 0.3}
    with pytest.raises(RuntimeError, match="other starts"):
        task_regions.regions(results)
    with pytest.raises(SystemExit):
        task_regions.main(["--kinds", "tissue", "--policy", "rigid=random"])
    with pytest.raises(SystemExit):
        task_regions.main(["--option", "cylinder_mass=heavy"])
    # a fixed option reaches every reset: the heavier cylinder is the one the scene holds
    (row,) = task_regions.episodes("rigid_torsion", "random", range(1000, 1001), {"cylinder_mass": 0.3})
    assert row["cylinder_mass"] == pytest.approx(300.0) and row["success"] == 0.0


def test_stability_diff_reads_the_shipped_v3_map():
    out = _run_plain("stability_diff.py", str(ROOT / "docs" / "results" / "stability_map_v3.csv"),
                     "--a", "tissue, thesis", "--b", "rigid_torsion")  # fmt: skip
    assert "tissue, thesis holds, rigid_torsion does not: 0 of 719 cells" in out, out
    assert "rigid_torsion holds, tissue, thesis does not: 16 of 719 cells" in out, out


def test_convergence_reads_monotone_series_and_the_pad_rows_against_coulomb():
    from benchmarks.convergence import monotone, tissue_rows
    from softgrasp_env.config import SimConfig

    assert monotone([0.3, -0.2, 0.1, 0.0]) and not monotone([0.1, 0.2])
    rows = tissue_rows(SimConfig())
    for metric, (figure, coulomb) in rows.items():  # measured +0.08 %, +0.00 %, -0.10 % at the defaults
        assert abs(figure / coulomb - 1.0) < 0.005, (metric, figure, coulomb)


def test_grip_force_runs_every_policy_and_writes_each_episode(tmp_path):
    out = tmp_path / "grip.json"
    proc = subprocess.run([sys.executable, str(ROOT / "benchmarks" / "grip_force.py"), "--seeds", "3", "--ids",
                           "SoftGraspGripRigid-v5", "--json", str(out)], cwd=ROOT, capture_output=True, text=True,
                          timeout=900, env={"PYTHONPATH": str(ROOT), "PATH": ""}, check=False)  # fmt: skip
    assert proc.returncode == 0, proc.stderr[-2000:]
    lines = [line for line in proc.stdout.splitlines() if line.startswith("SoftGraspGripRigid-v5")]
    assert [line.split()[1] for line in lines] == ["tactile", "open", "shear-lag", "constant", "constant", "constant",
                                                   "constant"]  # fmt: skip
    import json

    runs = json.loads(out.read_text())["runs"]
    assert len(runs) == 7 and all(len(r) == 3 for r in runs.values())
    # the tactile policy holds all three seeds within the factor; 3 N holds them all, and succeeds
    # exactly where that is within twice the least
    assert all(r["success"] for r in runs["SoftGraspGripRigid-v5 tactile"])
    for r in runs["SoftGraspGripRigid-v5 constant 3 N"]:
        assert r["held"] and r["success"] == (r["carry_squeeze"] <= 2 * r["least_squeeze"])


def test_the_contact_cones_hold_no_grip_below_coulombs_least_force():
    """The patch law with contact cones (``tissue_contact_cone=True``): the cores must push with
    m g / (2 mu_s) to hold the cylinder up, however the pads were dragged onto it. The scene
    squeezes 4 N on the way down, lifts, then lowers the squeeze without stopping while the arm
    holds still. Measured (seed 1013, least 1.337 N): held (sinking slower than 1 cm/s) while the
    cores pushed 1.663 N (1.24 x the least), sliding out at the next lowering (1.51 N, 70 mm/s;
    counted as held by the env's flag until it landed, which read 1.01 x); at the end the contacts'
    friction at most 1.01 x mu_s their normal force at position level (what a clamped contact sheds
    goes to the others of its patch, which may take them a little past their cones; the default
    law: friction up to 6.8 times the normal force, 9.8 x mu_s). The velocity half of a sliding
    patch's friction is not bounded per contact (friction_glue's cone_excess: 43 x); Coulomb per
    contact (friction_law="contact", tests/tissue/test_contact_friction.py) bounds both."""
    from benchmarks.friction_glue import glue

    result = glue(1013, report=lambda line: None, cones=True)
    assert not result["held"] and result["top_ratio"] <= 1.05 * result["mu"], result
    assert 0.97 <= result["weakest_hold"] / result["least"] <= 1.3, result


@pytest.mark.xfail(strict=True, reason="the default tissue friction (the patch law) has no per-contact bound "
                   "(benchmarks/friction_glue.py): a pad stays glued to the cylinder once the squeeze is "
                   "gone; the cones that fix it are not the default yet (they change the pad's compression)")
def test_no_tissue_grip_holds_below_coulombs_least_force_by_default():
    """The same at the defaults. Fails today: held while the cores pushed 0.058 N, 0.04 x the
    least, 13 of 14 contacts above their cones at the end; strict, so that the day the cones
    become the default it says so."""
    from benchmarks.friction_glue import glue

    result = glue(1013, report=lambda line: None)
    assert not result["held"] and result["over"] == 0, result
    assert 0.97 <= result["weakest_hold"] / result["least"], result


def test_rim_creep_centre_grips_hold_under_palm_noise_and_the_peer_holds_high():
    """'Where ours loses', the part that holds: a 0.2 kg cylinder at half friction
    (Coulomb's margin 1.19 with the arm's 1.5 m/s^2), lifted to 11 cm with the palm shaken. The
    tissue gripping at the centre keeps it (creep measured 2.3-2.6 mm, the pads' shear included);
    the torsional peer keeps it gripped 4 cm up too (0.0-2.5 mm)."""
    from benchmarks.rim_creep import run

    options = {"cylinder_mass": 0.2, "friction_scale": 0.5}
    soft = run("tissue", 0.0, 0.11, 0.8, range(1000, 1003), options)
    assert soft["success"] == 3 and soft["max_creep"] < 0.005 and soft["margin"] == pytest.approx(1.19, abs=0.01), soft
    assert soft["max_push"] < 0.01, soft  # gripped at the centre, no contact presses on the top face or rim (0.00 N)
    peer = run("rigid_torsion", 0.04, 0.11, 0.8, range(1000, 1003), options)
    assert peer["success"] == 3 and peer["max_creep"] < 0.005, peer


def test_rim_creep_is_a_discretisation_error_that_refines_away():
    """Why the high grip creeps: surface particles, spheres of their support radius along the
    contact normal (Mueller & Chentanez 2011 sec. 5), reach about half the particle spacing over the
    cylinder's rim and press its top face and edge down. Halving the spacing (4000 -> 16000
    particles per m^2) must shrink that push and the creep it causes about in proportion (first
    order: to ~0.5; measured 0.32-0.39 for the push, 0.38-0.43 for the creep, 10 and 3 seeds),
    toward the centre grip's 2-3 mm of elastic shear."""
    from benchmarks.rim_creep import run

    options, seeds = {"cylinder_mass": 0.2, "friction_scale": 0.5}, range(1000, 1003)
    coarse = run("tissue", 0.04, 0.11, 0.0, seeds, options)
    fine = run("tissue", 0.04, 0.11, 0.0, seeds, options, particle_density=16_000.0)
    assert coarse["success"] == fine["success"] == 3, (coarse, fine)
    assert coarse["median_push"] > 2.0, coarse  # the push exceeds the cylinder's weight (1.96 N): 3.5-4.2 N measured
    assert fine["median_push"] < 0.6 * coarse["median_push"], (coarse, fine)
    assert fine["median_creep"] < 0.6 * coarse["median_creep"], (coarse, fine)


@pytest.mark.xfail(strict=True, reason="a tissue grip with the pads' upper 2 cm above the cylinder's rim creeps down "
                   "(13 mm median on a still lift) and is lost when the palm moves about, at 1.19 x Coulomb's margin "
                   "where the torsional peer holds: the particles' reach over the rim presses the cylinder down, a "
                   "discretisation error that refinement shrinks (benchmarks/rim_creep.py) but the default keeps")
def test_a_tissue_grip_high_on_the_cylinder_holds_what_coulomb_allows():
    """Measured at the defaults: 0 of 10 (per-contact cones: 1 of 10), the cylinder sliding 52 mm
    (median) down the pads; at 4x the particles 2 of 10. Strict, so that the fix says so."""
    from benchmarks.rim_creep import run

    soft = run("tissue", 0.04, 0.11, 0.8, range(1000, 1003), {"cylinder_mass": 0.2, "friction_scale": 0.5})
    assert soft["success"] == 3 and soft["max_creep"] < 0.005, soft


@pytest.mark.parametrize("solve", ["groups", "global"])
def test_convergence_table_prints_the_slip_rows_with_their_orders(tmp_path, solve):
    """The one-table benchmark's slip rows on the continuum pad under Coulomb per contact at two
    densities, under each material solve (measured: the first contact slides at Q / mu P 0.57 and
    0.03, the whole strip at 1.04 and 1.01; global: 0.55 / 0.029 and 1.029 / 1.020; Coulomb's 1 and
    Cattaneo-Mindlin's 0), and its CSV."""
    import csv
    import re

    out = _run_plain("convergence_table.py", "--material", "continuum", "--law", "contact", "--rows", "slip",
                     "--densities", "4000,16000", "--material-solve", solve, "--out", str(tmp_path))  # fmt: skip
    assert f"material solve {solve}" in out, out
    gross = re.search(r"whole strip slides at Q / mu P\s+([\d.]+)\s+([\d.]+)\s+ref 1;", out)
    first = re.search(r"first contact slides at Q / mu P\s+([\d.]+)\s+([\d.]+)\s+ref 0;", out)
    assert gross and first, out
    assert all(0.98 < float(g) < 1.06 for g in gross.groups()), out
    assert float(first.group(2)) < 0.2 < float(first.group(1)), out  # the edges let go first once resolved
    name = "convergence_table_continuum_contact" + ("" if solve == "groups" else "_global")
    rows = list(csv.DictReader(open(tmp_path / f"{name}.csv")))
    assert {r["quantity"] for r in rows} == {"first_slide", "gross_slide"} and len(rows) == 4


def test_convergence_table_rejects_bad_layers():
    proc = subprocess.run([sys.executable, str(ROOT / "benchmarks" / "convergence_table.py"), "--layers", "1,2",
                           "--densities", "4000,16000,64000"], cwd=ROOT, capture_output=True, text=True, timeout=300,
                          env={"PYTHONPATH": str(ROOT), "PATH": ""})  # fmt: skip
    assert proc.returncode == 2 and "2 counts for 3 densities" in proc.stderr


def test_the_bounds_bisection_widens_a_bracket_that_misses_and_never_leaves_its_limits():
    """A tight bracket saves a fine level's hour-long episodes; one that misses the boundary is
    widened (1.25 x per try) inside the limits, and gives the boundary the full range gives."""
    import math

    from benchmarks.grasp_checks import bisect

    calls = []

    def held(m):
        calls.append(m)
        return m < 0.3

    full = bisect(held, 0.05, 1.5)
    assert abs(full / 0.3 - 1.0) < 0.02
    for lo, hi in ((0.29, 0.31), (0.5, 0.6), (0.1, 0.2), (0.05, 0.06)):
        calls.clear()
        m = bisect(held, lo, hi, limits=(0.05, 1.5))
        assert abs(m / 0.3 - 1.0) < 0.02, (lo, hi, m)
        assert all(0.05 <= c <= 1.5 for c in calls)
    calls.clear()
    bisect(held, 0.29, 0.31, limits=(0.05, 1.5))
    assert len(calls) < 6  # a bracket that straddles: its ends and a few halvings
    assert math.isnan(bisect(lambda m: True, 0.5, 0.6, limits=(0.05, 1.5)))  # holds everything
    assert math.isnan(bisect(lambda m: False, 0.5, 0.6, limits=(0.05, 1.5)))  # holds nothing
    with pytest.raises(ValueError, match="bracket"):
        bisect(held, 0.6, 0.5, limits=(0.05, 1.5))


def test_convergence_table_rejects_a_bracket_outside_its_range():
    proc = subprocess.run([sys.executable, str(ROOT / "benchmarks" / "convergence_table.py"), "--rows", "hold",
                           "--hold-bracket", "0.5,2"], cwd=ROOT, capture_output=True, text=True, timeout=300,
                          env={"PYTHONPATH": str(ROOT), "PATH": ""})  # fmt: skip
    assert proc.returncode == 2 and "--hold-bracket must be increasing inside 0.05-1.5" in proc.stderr


def test_gpu_inputs_colour_the_groups_so_no_two_in_a_colour_share_a_particle():
    """The GPU page's inputs at the default resolution: one group per particle, the group solves per
    env step from the iterations and world steps, and a colouring under which a colour's groups
    could run at once (no shared member)."""
    import gymnasium as gym
    import numpy as np

    from benchmarks.gpu_inputs import PHYSICS_STEPS_PER_ENV_STEP, greedy_colours, preset_inputs

    r = preset_inputs("default")
    env = gym.make("SoftGraspEasy-v4")
    try:
        env.reset(seed=0)
        world = env.unwrapped.scene.world
        m = world.model
        assert r["groups"] == r["particles"] == m.particle_count
        assert r["solves/env step"] == r["groups"] * world.sim.iterations * world.substeps * PHYSICS_STEPS_PER_ENV_STEP
        assert world.sim.dt * PHYSICS_STEPS_PER_ENV_STEP == pytest.approx(1.0 / env.unwrapped.control_frequency)
        colour = greedy_colours(m.group_offsets, m.group_members)
        for c in range(colour.max() + 1):
            groups = np.flatnonzero(colour == c)
            members = np.concatenate([m.group_members[m.group_offsets[g] : m.group_offsets[g + 1]] for g in groups])
            assert len(np.unique(members)) == len(members), f"colour {c} has groups sharing a particle"
        assert r["colours"] == colour.max() + 1 and sum(r["per colour"]) > 0
    finally:
        env.close()


def test_solver_kernel_breakdown_prints_a_steps_fixed_cost_its_iterations_and_the_sweep(capsys):
    """The kernel's breakdown on SoftGrasp-v4's pads pressed on the cylinder prints each figure (no
    timing is asserted: the machines are shared). The group sweep runs on the solver's own buffers,
    so this breaks if the sweep's arguments change and the benchmark is not updated."""
    import re

    from benchmarks.solver_kernel import bench_breakdown

    bench_breakdown(converged=False, repeats=1)
    out = capsys.readouterr().out
    # one repeat on a shared machine: the 3 -> 6 iteration slope can come out negative, and the
    # figures derived from it with it (the test is of what is printed, not of the timing)
    assert re.search(r"default: 60 particles, 60 groups of 8\.0 members", out), out
    assert re.search(r"iterations [\d.]+ / [\d.]+ / [\d.]+ / [\d.]+ us", out), out
    assert re.search(r"per iteration -?[\d.]+ us .* fixed -?[\d.]+ us", out), out
    assert re.search(r"the group sweep alone [\d.]+ us \([\d.]+ us per group\), -?\d+% of an iteration", out), out


def test_the_rest_hessian_solves_the_pads_implicit_step_in_passes_the_sweep_and_projective_dynamics_cannot():
    # benchmarks/implicit_step.py at the default density and step: after 2 passes the sweep is at 0.13
    # of its first residual and projective dynamics at 0.075 (measured), the rest Hessian at 1.3e-4
    from benchmarks.implicit_step import pad, run

    res = run(pad(4_000.0), 1.0 / 240.0, 3)
    assert res["k0"][1] < 5e-4 and res["k0"][2] < res["k0"][1] / 20.0
    assert res["sweep"][1] > 0.03 and res["pd"][1] > 0.03
    assert all(b < a for a, b in zip(res["pd"], res["pd"][1:], strict=False))  # projective dynamics: monotone
