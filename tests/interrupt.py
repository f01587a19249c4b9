"""A run stopped as by a kill: shared by the resume and store-error tests."""
from __future__ import annotations

import importlib

import pytest

import cracklab

SIM = importlib.import_module("cracklab.output.simulate")


def interrupted_run(scene, store, monkeypatch, *, stop, checkpoint_every):
    """Simulate ``scene`` into ``store`` and stop it (KeyboardInterrupt) right after step
    ``stop`` has been recorded, with checkpoints every ``checkpoint_every`` steps; the
    recorder is restored afterwards. Returns ``store``."""
    real = SIM.Recorder.__call__

    def interrupted(self, state):
        real(self, state)
        if state.n == stop:
            raise KeyboardInterrupt

    monkeypatch.setattr(SIM.Recorder, "__call__", interrupted)
    with pytest.raises(KeyboardInterrupt):
        cracklab.simulate(scene, store=store, checkpoint_every=checkpoint_every)
    monkeypatch.setattr(SIM.Recorder, "__call__", real)
    return store
