"""The exact solver on many-contact drops against the 40-digit reference.

docs/accuracy.md, "Many-contact drops", quotes its result.

A seeded sample of drops at H = 1e4 with mu in [1e-4, 1e-3], tau_d/tau_f in [1e-3, 0.1] (both
log-uniform) and eps in [0.6, 1], keeping those with at least MIN_CONTACTS ball contacts before
the first apex. For each: the exact solver's relative error in h1 and h2 against
:func:`twoball.studies.truth.solve_truth`, the contact counts of both, and the drop's
conditioning (:mod:`twoball.studies.conditioning`, which states the rule the rows are held
to). The reference's h1 and h2 are written too (25 digits), so that a change to the solver can
be checked against them in a second (tests/test_many_contacts.py) instead of the reference's
minutes.

Run ``twoball many-contacts --out docs`` (writes many_contacts.csv; about 4 minutes on 2
cores).
"""

from __future__ import annotations

import time
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np

from twoball.batch.workers import Workers
from twoball.errors import ParameterError
from twoball.observables import BALLS
from twoball.solve import simulate
from twoball.studies.conditioning import (
    Comparison,
    against_reference,
    reference_text,
    within_rule,
)
from twoball.studies.precision import write_csv

HEIGHT = 1e4
SEED = 10
SAMPLE = 20
MIN_CONTACTS = 6
COLUMNS = (
    "eps",
    "mu",
    "tau_ratio",
    "contacts_first",
    "contacts_first_truth",
    "rel_err_h1",
    "rel_err_h2",
    "cond_h1",
    "cond_h2",
    "truth_seconds",
    "h1_truth",
    "h2_truth",
)


def sample_drops(count: int = SAMPLE, seed: int = SEED) -> list[tuple[float, float, float]]:
    """The first ``count`` seeded drops with at least MIN_CONTACTS ball contacts."""
    rng = np.random.default_rng(seed)
    drops = []
    while len(drops) < count:
        eps = float(rng.uniform(0.6, 1.0))
        mu = float(10.0 ** rng.uniform(-4.0, -3.0))
        tau_ratio = float(10.0 ** rng.uniform(-3.0, -1.0))
        result = simulate(eps, mu, tau_ratio, height=HEIGHT)
        if result.reason is None and result.contacts_first[BALLS] >= MIN_CONTACTS:
            drops.append((eps, mu, tau_ratio))
    return drops


@dataclass(frozen=True)
class ManyContactsRow(Comparison):
    """One drop of the sample (:func:`measure`): the comparison with the 40-digit reference, the
    drop, the reference heights as text and the reference's run time; :data:`COLUMNS` are its
    fields."""

    eps: float
    mu: float
    tau_ratio: float
    truth_seconds: float
    h1_truth: str
    h2_truth: str


def measure(drop: tuple[float, float, float]) -> ManyContactsRow:
    """One drop: exact vs truth, contact counts, conditioning."""
    from twoball.studies.truth import solve_truth

    eps, mu, tau_ratio = drop
    start = time.perf_counter()
    truth = solve_truth(eps, mu, tau_ratio, height=HEIGHT)
    seconds = time.perf_counter() - start
    compared = against_reference(
        eps, mu, tau_ratio, truth.h1, truth.h2, truth.contacts_first[BALLS], height=HEIGHT
    )
    return ManyContactsRow(
        **asdict(compared),
        eps=eps,
        mu=mu,
        tau_ratio=tau_ratio,
        truth_seconds=round(seconds, 1),
        h1_truth=reference_text(truth.h1),
        h2_truth=reference_text(truth.h2),
    )


def progress_line(row: ManyContactsRow) -> str:
    """One drop's result in words, as the study prints it."""
    rule = "within the rule" if within_rule(row) else "OUTSIDE the rule"
    return (
        f"eps {row.eps:.4g}, mu {row.mu:.4g}, tau_ratio {row.tau_ratio:.4g}: "
        f"{row.contacts_first} ball contacts (reference {row.contacts_first_truth}), "
        f"relative error h1 {row.rel_err_h1:.2g}, h2 {row.rel_err_h2:.2g} "
        f"(conditioning {row.cond_h1:.2g}, {row.cond_h2:.2g}): {rule}"
    )


def run_study(
    out: Path, *, count: int = SAMPLE, seed: int = SEED, workers: int = 2
) -> list[ManyContactsRow]:
    """Measure the seeded sample on ``workers`` processes and write many_contacts.csv into
    ``out``; returns the rows."""
    if count < 1:
        raise ParameterError(f"count must be at least 1; got {count!r}")
    if workers < 1:
        raise ParameterError(f"workers must be at least 1; got {workers!r}")
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    drops = sample_drops(count, seed)
    rows: list[ManyContactsRow | None] = [None] * len(drops)
    with Workers(min(workers, len(drops)), measure) as pool:
        for index, row, _ in pool.results([(drop,) for drop in drops]):
            rows[index] = row
            print(f"  drop {index + 1}/{len(drops)}: {progress_line(row)}", flush=True)
    write_csv(rows, out / "many_contacts.csv", COLUMNS)
    worst = max(max(r.rel_err_h1, r.rel_err_h2) for r in rows)
    outside = sum(not within_rule(r) for r in rows)
    print(
        f"{len(rows)} drops: worst relative error {worst:.2g}; outside the rule on {outside}; "
        f"wrote {out / 'many_contacts.csv'}"
    )
    return rows
