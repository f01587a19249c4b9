"""The command line: run a TOML scene, rerun from its output store, bench."""
import json

import numpy as np
import pytest
import xarray as xr
from click.testing import CliRunner

from cracklab.cli import main

SCENE = """
t_end = 0.05
beta = 0.5
name = "cli-test"

[material]
mu = 1.0
cs = 1.0
nu = 0.25

[grid]
n1 = 16
n3 = 16
L1 = 1.0
L3 = 1.0

[law]
kind = "linear_cohesive"
tau_c = 1.0
delta_c = 0.01
initial_crack = [%s]

[loading]
tau0_2 = 1.2

[record]
fields = ["delta_2", "v_2"]
every = 2
"""


def scene_toml(tmp_path):
    rows = ["[" + ", ".join("true" if 6 <= i <= 9 else "false" for _ in range(16)) + "]" for i in range(16)]
    path = tmp_path / "scene.toml"
    path.write_text(SCENE % ", ".join(rows))
    return path


def test_run_toml_then_rerun_from_store(tmp_path):
    runner = CliRunner()
    first = tmp_path / "a.zarr"
    res = runner.invoke(main, ["run", str(scene_toml(tmp_path)), "-o", str(first)])
    assert res.exit_code == 0, res.output
    a = xr.open_zarr(first, consolidated=False)
    assert float(a.delta_2.isel(t=-1).max()) > 0
    second = tmp_path / "b.zarr"
    res = runner.invoke(main, ["run", str(first), "-o", str(second)])
    assert res.exit_code == 0, res.output
    b = xr.open_zarr(second, consolidated=False)
    for name in ("delta_2", "v_2", "rupture_time"):
        np.testing.assert_allclose(b[name].values, a[name].values, rtol=1e-12, atol=1e-15, equal_nan=True)


def test_run_rejects_unknown_key(tmp_path):
    path = scene_toml(tmp_path)
    path.write_text(path.read_text().replace("[grid]\n", "[grid]\nspacing = 3\n"))
    res = CliRunner().invoke(main, ["run", str(path), "-o", str(tmp_path / "x.zarr")])
    assert res.exit_code != 0
    assert "grid.spacing: unknown key" in res.output
    assert not (tmp_path / "x.zarr").exists()


def test_bench_json():
    res = CliRunner().invoke(main, ["bench", "--n1", "32", "--n3", "32", "--steps", "20", "--json"])
    assert res.exit_code == 0, res.output
    out = json.loads(res.output)
    for key in ("ms_per_step", "fft_pair_ms", "peak_rss_mb", "engine", "transforms_per_step", "fft_floor_ms"):
        assert key in out
    assert out["ms_per_step"] > 0 and out["fft_pair_ms"] > 0
    # the baseline was timed within the run (one pair after every 10th of the 10 timed
    # steps, the step after it left out); the timed half alternates 8 plain steps and 8 by stage
    assert out["fft_pairs_timed"] == 1 and out["timed_steps"] == 8 and out["stage_steps"] == 2
    # mode I, displacement scheme: one transform forward and one back per step
    assert out["transforms_per_step"] == 2
    assert out["fft_floor_ms"] == out["fft_pair_ms"]


def test_bench_counts_the_shear_transforms():
    """The product scheme (default for shear) transforms both components forward and back
    in the predictor and again in the corrector: eight transforms per step."""
    from cracklab.cli.bench import run

    out = run(16, 16, "shear", 30, engine="exponential", engine_threads=2)
    assert out["overlap"] and out["fft_pairs_timed"] == 1
    assert out["transforms_per_step"] == 8
    assert out["fft_floor_ms"] == 4 * out["fft_pair_ms"]


SLEEP = 0.003


def _sleepy_solve(monkeypatch):
    """TractionFree.solve made SLEEP seconds longer: a step's law stage then has a known
    least length, long beside the rest of a small step (the host's noise with it)."""
    import time

    from cracklab.laws import TractionFree

    solve = TractionFree.solve

    def slow(self, *args, **kwargs):
        time.sleep(SLEEP)
        return solve(self, *args, **kwargs)

    monkeypatch.setattr(TractionFree, "solve", slow)


@pytest.mark.parametrize("mode, solves", [("I", 1), ("shear", 2)])
def test_bench_reports_the_step_by_stage(monkeypatch, mode, solves):
    """stages_ms: every stage of bench.STAGES is reported, the time is where it was spent
    (a law solve made longer shows in the law's stage, not in the glue), and the stages sum
    to the step timed by stage, set against the plain step (how close they come is the
    host's: reported, not asserted; the clock's own cost is a few microseconds per wrapped
    call). The displacement scheme solves the law once per step, the product scheme twice
    (predictor and step); only the product scheme has start-up weights."""
    from cracklab.cli.bench import STAGES, run

    _sleepy_solve(monkeypatch)
    out = run(32, 32, mode, 60, engine="exponential")
    stages = out["stages_ms"]
    assert tuple(stages) == STAGES and out["stage_steps"] >= 8 and out["worker_ms"] is None
    assert stages["law"] >= solves * 1e3 * SLEEP
    assert stages["glue"] < 0.5 * 1e3 * SLEEP
    assert stages["transforms"] > 0 and stages["advance"] > 0 and stages["taps"] > 0
    assert stages["wait"] < stages["advance"]           # no worker: nothing to wait for
    assert (stages["start"] > 0) == (mode == "shear")     # E_0: the product scheme's
    total = sum(stages.values())
    assert abs(total / out["stages_total_ms"] - 1) < 1e-9, (total, out["stages_total_ms"])
    assert out["stages_vs_step"] == out["stages_total_ms"] / out["ms_per_step"]
    assert out["stages_fft_pairs"] == {k: v / out["fft_pair_ms"] for k, v in stages.items()}


#: the four cases of docs/studies/performance.md's breakdown: (mode, law, bimaterial)
STAGE_CASES = [("I", "traction_free", False), ("shear", "slip_weakening", False), ("shear", "rate_state", False),
               ("shear", "slip_weakening", True)]


@pytest.mark.parametrize("mode, law, bimaterial", STAGE_CASES)
def test_bench_stages_of_the_four_cases(monkeypatch, mode, law, bimaterial):
    """Mode I, shear with slip weakening, with rate and state, and bimaterial shear: every
    stage is reported, none negative, the time of a law made longer shows in the law's
    stage, and the stages sum to the step timed by stage; the text report has the same rows
    and sets their sum against the plain step (how close they come is the host's: reported,
    not asserted)."""
    import time

    from cracklab.cli.bench import STAGE_SLACK, STAGES, bench_scene, run, stage_table

    cls = type(bench_scene(8, 8, mode, 4, law=law).law)
    solve = cls.solve

    def slow(self, *args, **kwargs):
        time.sleep(SLEEP)
        return solve(self, *args, **kwargs)

    monkeypatch.setattr(cls, "solve", slow)
    out = run(32, 32, mode, 60, engine="exponential", law=law, bimaterial=bimaterial)
    stages = out["stages_ms"]
    assert tuple(stages) == STAGES and out["stage_steps"] >= 8
    assert all(v >= 0 for v in stages.values()), stages
    solves = 1 if mode == "I" else 2           # displacement scheme: one solve; product: predictor and step
    assert stages["law"] >= solves * 1e3 * SLEEP
    assert stages["transforms"] > 0 and stages["advance"] > 0 and stages["taps"] > 0
    assert (stages["start"] > 0) == (mode != "I")        # E_0: the product scheme's (shear, bimaterial)
    assert abs(sum(stages.values()) / out["stages_total_ms"] - 1) < 1e-9
    assert out["stages_vs_step"] == out["stages_total_ms"] / out["ms_per_step"]
    table = stage_table(out).splitlines()
    for stage in STAGES + ("sum",):
        row = next(line.split() for line in table if line.split()[:1] == [stage])
        ms = out["stages_total_ms"] if stage == "sum" else stages[stage]
        assert float(row[1]) == pytest.approx(ms, abs=6e-4)
        assert float(row[2]) == pytest.approx(ms / out["fft_pair_ms"], abs=6e-3)
    within = abs(out["stages_vs_step"] - 1) < STAGE_SLACK
    assert (f"{'within' if within else 'outside'} the {100 * STAGE_SLACK:.0f} % slack") in table[-1]


def test_bench_text_report_has_the_stage_table():
    """Without --json the stages are a table (ms, FFT pairs, share) after the other figures,
    their sum set against the plain step; the stage keys are not repeated as lines."""
    res = CliRunner().invoke(main, ["bench", "--n1", "32", "--n3", "32", "--steps", "40"])
    assert res.exit_code == 0, res.output
    lines = res.output.splitlines()
    assert any(line.strip().startswith("ms_per_step:") for line in lines)
    assert not any(line.strip().startswith(("stages_ms:", "stages_total_ms:")) for line in lines)
    start = next(i for i, line in enumerate(lines) if line.startswith("where the time goes"))
    assert lines[start + 2].split() == ["stage", "ms", "x", "FFT", "pair", "share"]
    rows = [line.split()[0] for line in lines[start + 3:start + 11]]
    assert rows == ["transforms", "advance", "start", "wait", "taps", "law", "glue", "sum"]
    assert "the stages sum to" in lines[-1] and "slack" in lines[-1]


def test_bench_stages_with_the_overlap(monkeypatch):
    """With two engine threads the advance runs on the worker: the step's stages count the
    caller's wait for it, worker_ms the worker's time per step, and the stages still sum to
    the step."""
    from cracklab.cli.bench import run

    _sleepy_solve(monkeypatch)
    out = run(32, 32, "shear", 60, engine="exponential", engine_threads=2)
    stages = out["stages_ms"]
    assert out["overlap"] and out["worker_ms"] > 0
    # the advance is the worker's: the caller's share of it is small against the known sleep
    # of the law (a bound with a wide margin, not a comparison of two timings of the same size)
    assert stages["advance"] < 0.5 * 1e3 * SLEEP and stages["start"] < 0.5 * 1e3 * SLEEP
    assert stages["law"] >= 2e3 * SLEEP and stages["glue"] < 0.5 * 1e3 * SLEEP
    total = sum(stages.values())
    assert abs(total / out["stages_total_ms"] - 1) < 1e-9, (total, out["stages_total_ms"])


def test_bench_stage_clock_leaves_nothing_behind():
    """The clock's wrappers exist only while a step is timed by stage: after the run the
    transforms, engines and law answer with their classes' own methods again."""
    from cracklab.cli.bench import StageClock, bench_scene
    from cracklab.solver.interfaces import for_scene
    from cracklab.solver.spectral import Transforms
    from cracklab.solver.stepper import Stepper

    scene = bench_scene(16, 16, "shear", 10, engine="exponential", law="slip_weakening")
    stepper = Stepper(scene, for_scene(scene, Transforms(scene.grid)))
    clock = StageClock(stepper)
    assert len({id(obj) for obj, _, _ in clock._targets}) == 1 + 1 + 2   # transforms, law, two engines
    clock.install()
    assert all(name in vars(obj) for obj, name, _ in clock._targets)
    for _ in zip(range(3), stepper):
        pass
    clock.remove()
    assert sum(clock.read().values()) > 0
    assert not any(name in vars(obj) for obj, name, _ in clock._targets)
    assert stepper.scene.law.solve.__func__ is type(stepper.scene.law).solve


def test_bench_fit_steps_fixes_the_terms():
    """--fit-steps: runs of different lengths carry the same exponential terms (the fit
    covers the longer length), so their costs differ by the history's length alone."""
    from cracklab.cli.bench import run

    short = run(16, 16, "I", 20, engine="exponential", fit_steps=4000)
    longer = run(16, 16, "I", 200, engine="exponential", fit_steps=4000)
    own = run(16, 16, "I", 20, engine="exponential")
    assert short["fit_steps"] == longer["fit_steps"] == 4000 and own["fit_steps"] == 20
    assert short["terms"] == longer["terms"]
    # the run's own length asks for fewer terms than a fit over 4000 steps
    assert own["terms"]["I"] < short["terms"]["I"]
    res = CliRunner().invoke(main, ["bench", "--n1", "16", "--n3", "16", "--steps", "10", "--fit-steps", "0"])
    assert res.exit_code != 0 and "--fit-steps" in res.output


@pytest.mark.parametrize("law", ["slip_weakening", "rate_state"])
def test_bench_friction_laws(law):
    """--law: a shear rupture on 100 m cells; the rate-and-state bench counts its Newton
    evaluations (two solves per step: the product scheme's predictor and corrector)."""
    res = CliRunner().invoke(main, ["bench", "--n1", "32", "--n3", "32", "--steps", "20", "--law", law, "--json"])
    assert res.exit_code == 0, res.output
    out = json.loads(res.output)
    assert out["law"] == law and out["mode"] == "shear" and out["ms_per_step"] > 0
    if law == "rate_state":
        assert out["newton_solves_per_point_step"] == 2.0
        assert 2.0 <= out["newton_evaluations_per_point_step"] < 6 and out["newton_most_evaluations"] >= 1
    else:
        assert out["newton_evaluations_per_point_step"] is None
    res = CliRunner().invoke(main, ["bench", "--n1", "16", "--n3", "16", "--steps", "10", "--law", law, "--mode", "I"])
    assert res.exit_code != 0 and "mode: the" in res.output


def test_bench_free_surface():
    """--free-surface: the half plane n1 x (n3 + 1) below a free surface (the mirror), with
    the same eight transforms per step in shear; the baseline pair is then the cost per
    component of the shear pair's transform of the doubled cell."""
    res = CliRunner().invoke(main, ["bench", "--n1", "32", "--n3", "16", "--mode", "shear", "--steps", "30",
                                    "--free-surface", "--json"])
    assert res.exit_code == 0, res.output
    out = json.loads(res.output)
    assert out["free_surface"] is True and out["transforms_per_step"] == 8 and out["fft_pair_ms"] > 0
    res = CliRunner().invoke(main, ["bench", "--n1", "32", "--n3", "1", "--steps", "10", "--free-surface"])
    assert res.exit_code != 0 and "grid.free_surface" in res.output
    assert "--free-surface" in CliRunner().invoke(main, ["bench", "--help"]).output


def test_bench_mixed_mode_runs_all_three_components():
    """--mode mixed: the opening and both slips, the one-material step to set a bimaterial
    one against (the faces always carry the normal channel); 4 + 4 transforms per step."""
    from cracklab.cli.bench import bench_scene, run

    assert bench_scene(16, 16, "mixed", 10).components == (1, 2, 3)
    one = run(16, 16, "mixed", 10, engine="exponential")
    assert set(one["terms"]) == {"I", "II", "III"} and one["formulation"] == "product"
    assert one["transforms_per_step"] == 12.0
    two = run(16, 16, "mixed", 10, engine="exponential", bimaterial=True)
    assert {k.split(".")[1] for k in two["terms"]} == {"L", "N", "LN", "NL", "T"}
    res = CliRunner().invoke(main, ["bench", "--n1", "16", "--n3", "16", "--steps", "10", "--law", "slip_weakening",
                                    "--mode", "mixed"])
    assert res.exit_code != 0 and "mode" in res.output and "mixed" in res.output
