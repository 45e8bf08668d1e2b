"""``twoball bench``: run time of the exact solver against LSODA as the paper used it.

Random points of the paper's cube (eps in (0.5, 1), mu in (0.01, 1/3), tau_d/tau_f in (0.01, 1),
H = 1e4), each run to the second apex in one process: the exact solver, and LSODA through
``odeint`` with rtol = atol = 1e-8 on a time grid (the paper's way). Each time is the median of
repeats; the ratio is per case, then summarised by its median. Accuracy is checked against an
independent method, DOP853 at rtol = atol = 1e-12 with restarts at every apex; the case where
the two differ most is then solved by the 40-digit reference of ``twoball.studies.truth`` to say
which
of the two is off.
"""

from __future__ import annotations

import statistics

import numpy as np

from twoball.observables import relative_error
from twoball.solve import simulate
from twoball.studies.precision import CVODE_INSTALLED
from twoball.studies.timing import median_seconds

CVODE_TOLERANCE = 1e-12  # rtol = atol: CVODE's closest approach to the exact solver's error

PAPER_CUBE = {"eps": (0.5, 1.0), "mu": (0.01, 1.0 / 3.0), "tau_ratio": (0.01, 1.0)}


def random_cases(count: int, seed: int) -> list[tuple[float, float, float]]:
    """``count`` points drawn uniformly from the paper's cube (eps, mu, tau_ratio)."""
    rng = np.random.default_rng(seed)
    columns = [rng.uniform(low, high, count) for low, high in PAPER_CUBE.values()]
    return [tuple(float(c[i]) for c in columns) for i in range(count)]


def benchmark(count: int = 50, seed: int = 0, repeats: int = 5, height: float = 1e4) -> dict:
    """Time and check both methods on ``count`` random cases; returns the figures."""
    simulate(0.8, 0.1, 0.5)  # compile (or load) the kernel outside the timings
    rows = []
    for eps, mu, tau_ratio in random_cases(count, seed):

        def exact_run(eps=eps, mu=mu, tau_ratio=tau_ratio):
            return simulate(eps, mu, tau_ratio, height=height)

        def lsoda_run(eps=eps, mu=mu, tau_ratio=tau_ratio):
            return simulate(eps, mu, tau_ratio, height=height, method="odeint")

        exact = exact_run()
        lsoda = lsoda_run()
        check = simulate(eps, mu, tau_ratio, height=height, method="DOP853", rtol=1e-12, atol=1e-12)
        peer = {}
        if CVODE_INSTALLED:  # the strongest general peer, at its tightest useful tolerance

            def cvode_run(eps=eps, mu=mu, tau_ratio=tau_ratio):
                return simulate(
                    eps, mu, tau_ratio, height=height, method="CVODE",
                    rtol=CVODE_TOLERANCE, atol=CVODE_TOLERANCE, throw=False,
                )  # fmt: skip

            cvode = cvode_run()
            peer = {
                "cvode_failed": not cvode.success,
                "cvode_s": median_seconds(cvode_run, max(1, repeats // 2)),
                "cvode_vs_exact": max(
                    relative_error(cvode.h1, exact.h1), relative_error(cvode.h2, exact.h2)
                ),
            }
        rows.append(
            {
                **peer,
                "eps": eps,
                "mu": mu,
                "tau_ratio": tau_ratio,
                "exact_s": median_seconds(exact_run, repeats),
                "lsoda_s": median_seconds(lsoda_run, max(1, repeats // 2)),
                "exact_vs_dop853": max(
                    relative_error(exact.h1, check.h1), relative_error(exact.h2, check.h2)
                ),
                "lsoda_vs_exact": max(
                    relative_error(lsoda.h1, exact.h1), relative_error(lsoda.h2, exact.h2)
                ),
            }
        )
    ratios = [row["lsoda_s"] / row["exact_s"] for row in rows]
    worst = max(rows, key=lambda row: row["exact_vs_dop853"])
    from twoball.studies.truth import solve_truth  # the studies extra (mpmath)

    truth = solve_truth(worst["eps"], worst["mu"], worst["tau_ratio"], height=height)
    exact = simulate(worst["eps"], worst["mu"], worst["tau_ratio"], height=height)
    check = simulate(
        worst["eps"],
        worst["mu"],
        worst["tau_ratio"],
        height=height,
        method="DOP853",
        rtol=1e-12,
        atol=1e-12,
    )
    truth_h1, truth_h2 = float(truth.h1), float(truth.h2)
    return {
        "worst_case": (worst["eps"], worst["mu"], worst["tau_ratio"]),
        "worst_exact_vs_truth": max(
            relative_error(exact.h1, truth_h1), relative_error(exact.h2, truth_h2)
        ),
        "worst_dop853_vs_truth": max(
            relative_error(check.h1, truth_h1), relative_error(check.h2, truth_h2)
        ),
        "cases": rows,
        "exact_median_s": statistics.median(row["exact_s"] for row in rows),
        "lsoda_median_s": statistics.median(row["lsoda_s"] for row in rows),
        "speedup_median": statistics.median(ratios),
        "speedup_min": min(ratios),
        "exact_vs_dop853_max": max(row["exact_vs_dop853"] for row in rows),
        "lsoda_vs_exact_median": statistics.median(row["lsoda_vs_exact"] for row in rows),
        **_cvode_figures(rows),
    }


def _cvode_figures(rows: list[dict]) -> dict:
    """CVODE's median time, its time over the exact solver's, and its error, over the runs it
    finished, and how many it did not (empty without the cvode extra). A failed run had been
    counted in the times and gave an error of inf ("largest inf") with no word of why."""
    if not CVODE_INSTALLED:
        return {}
    finished = [row for row in rows if not row["cvode_failed"]] or rows
    return {
        "cvode_failed": sum(row["cvode_failed"] for row in rows),
        "cvode_median_s": statistics.median(row["cvode_s"] for row in finished),
        "cvode_speedup_median": statistics.median(r["cvode_s"] / r["exact_s"] for r in finished),
        "cvode_vs_exact_median": statistics.median(row["cvode_vs_exact"] for row in finished),
        "cvode_vs_exact_max": max(row["cvode_vs_exact"] for row in finished),
    }
