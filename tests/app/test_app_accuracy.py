"""The Accuracy scene's measurements made ahead, once the kernels are compiled."""

from __future__ import annotations

from app import accuracy
from app.state import ExplorerState
from app.steps import STEPS


def test_the_default_drop_and_the_lesson_s_accuracy_step_are_measured_ahead(monkeypatch):
    """``measure_ahead`` (app_hooks runs it once the kernels are compiled) measures the drop a
    page opens on and the lesson's accuracy step, each once; a page then finds it measured."""
    asked = []
    monkeypatch.setattr(
        accuracy, "work_precision", lambda *drop, **options: asked.append((drop, options)) or []
    )
    accuracy.measured.cache_clear()
    accuracy.measure_ahead()
    default = ExplorerState()
    (step,) = [step for step in STEPS if step.scene == "accuracy"]
    expected = [
        ((default.eps, default.mu, default.tau_ratio),
         {"eps12": default.eps12, "height": default.height}),
        ((step.drop["eps"], step.drop["mu"], step.drop["tau_ratio"]),
         {"eps12": step.drop["eps12"], "height": step.drop["height"]}),
    ]  # fmt: skip
    # (each once: the lesson's step shows the default drop today)
    assert sorted(asked, key=repr) == sorted({repr(e): e for e in expected}.values(), key=repr)
    drop = step.drop
    accuracy.measured(
        drop["eps"], drop["mu"], drop["tau_ratio"], drop["eps12"], drop["height"], True
    )
    assert len(asked) == len({repr(e) for e in expected})  # (from the cache)
    accuracy.measured.cache_clear()
