"""`cracklab demo` finds the study it runs in the source checkout."""
from pathlib import Path

from cracklab.cli.demo import STUDY

ROOT = Path(__file__).resolve().parents[2]


def test_demo_study_is_the_checkouts_study_file():
    assert STUDY == ROOT / "studies" / "asperity_ensemble" / "study.toml"
    assert STUDY.is_file()


def test_the_demo_runs_the_ensemble_then_lamb_and_writes_what_getting_started_names(tmp_path, monkeypatch,
                                                                                     capsys):
    """`cracklab demo` (on a one-member study of small grids, and Lamb on 32 x 32): the
    ensemble first, then Lamb's problem, as docs/guide/getting_started.md's "First run" says,
    writing every output that paragraph names; the summary figure's title counts
    "1 member" in the singular."""
    import re

    from cracklab import plots
    from cracklab.cli import demo

    text = (ROOT / "docs" / "guide" / "getting_started.md").read_text()
    first_run = text.split("## First run", 1)[1].split("\n## ", 1)[0]
    named = sorted(set(re.findall(r"`out/([\w.]+)`", first_run)))
    assert {"ensemble.zarr", "lamb.zarr", "lamb.png", "ensemble_random.gif"} <= set(named), named
    assert first_run.index("asperity ensemble") < first_run.index("Then Lamb's problem")

    study = tmp_path / "study.toml"
    study.write_text('[study]\nname = "tiny"\nbuilder = "asperity_row"\nentropy = 3\n[base]\nn1 = 32\nn3 = 16\n'
                     't_end = 0.5\nrecord.every = 4\n[[members]]\nbuilder = "random_toughness"\ncov = 0.2\n'
                     'correlation_length = 0.25\n')
    real = demo.ensemble_demo
    monkeypatch.setattr(demo, "ensemble_demo", lambda out, **kw: real(out, **{**kw, "study": study}))
    titles = []
    summary = plots.ensemble_summary

    def ensemble_summary(ens, **kw):
        titles.append(kw.get("title"))
        return summary(ens, **kw)
    monkeypatch.setattr(plots, "ensemble_summary", ensemble_summary)
    out = tmp_path / "out"
    assert demo.main(out=str(out), n=32, scheduler="synchronous", progress=False)
    printed = capsys.readouterr().out
    for name in named:
        assert (out / name).exists(), name
    assert printed.index("study 'tiny'") < printed.index("figures (") < printed.index("lamb.zarr")
    assert titles == ["tiny: 1 member"]
