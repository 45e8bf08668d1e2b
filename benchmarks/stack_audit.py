"""Where the linear stack kernel loses accuracy, phase by phase (docs/accuracy.md, "The linear
stack").

Runs one drop through the kernel with its
phases recorded and through the 40-digit reference with its events traced, and prints at each
phase start the kernel's clock and relative state (each contact's overlap e_c and rate e_c')
against the reference's at the same event, in units of the coordinate's own ulp: where the
error first jumps beyond rounding. ``--continue K ...`` also continues the 40-digit reference
from the kernel's state at phase start K and prints the h2 that gives against the reference's:
the error in h2 that the kernel has made before phase K.

    .venv/bin/python benchmarks/stack_audit.py CASE [--continue K ...] [--cache FILE]
    .venv/bin/python benchmarks/stack_audit.py CASE --local | --orders

CASE is an index into stack_truth.cases() or RATIOS,EPS,GAP,H (e.g. 0.2,0.2,0.9,0.2,1e4).
``--local``: each phase's own error (the reference from the kernel's start of the phase to its
first event). ``--orders``: the contact order at H moved by 1 to 2^16 ulps.
"""

from __future__ import annotations

import argparse
import contextlib
import math
import pickle
from pathlib import Path

import mpmath
import numpy as np

from twoball.kernels import stack as kernel
from twoball.stacks import check_stack
from twoball.stacks.stack import _store_for
from twoball.studies import stack_truth


def kernel_phases(case: dict) -> tuple[np.ndarray, object]:
    stack = check_stack(case["mass_ratios"], case["eps"], case["tau_ratios"], height=case["height"])
    out = kernel.run(stack.masses, stack.zeta, stack.x_start, 2, np.inf, True, _store_for(stack))
    return out.phases, out


def relative(y: list, n: int) -> tuple[list, list]:
    """(e, e') of a reference state y = (x, v, 1)."""
    e = [y[0]] + [y[c] - y[c - 1] for c in range(1, n)]
    de = [y[n]] + [y[n + c] - y[n + c - 1] for c in range(1, n)]
    return e, de


def absolute(e: np.ndarray, de: np.ndarray) -> list:
    """The reference's state (x, v, 1) of a kernel phase start, summed exactly."""
    x = [mpmath.mpf(0)] * e.size
    v = [mpmath.mpf(0)] * e.size
    for c in range(e.size):
        x[c] = (x[c - 1] if c else 0) + mpmath.mpf(float(e[c]))
        v[c] = (v[c - 1] if c else 0) + mpmath.mpf(float(de[c]))
    return x + v + [mpmath.mpf(1)]


def on(bits: int, n: int) -> str:
    """The active contacts of a phase, floor first: x active, . not."""
    return "".join("x" if (bits >> c) & 1 else "." for c in range(n))


class _OneEvent(list):
    """A trace that stops the reference at its first event."""

    def append(self, item) -> None:
        super().append(item)
        raise StopIteration


def local_errors(phases: np.ndarray, masses, zeta, x_start) -> None:
    """Each phase from the kernel's start state to its first event by the reference, against
    the kernel's next start: the phase's own error (switch placement included), in ulps of each
    coordinate's size over the phase."""
    n = masses.size
    for k in range(len(phases) - 1):
        trace = _OneEvent()
        active = [(int(phases[k, 1]) >> c) & 1 == 1 for c in range(n)]
        start = (0, absolute(phases[k, 2 : 2 + n], phases[k, 2 + n :]), active)
        with contextlib.suppress(StopIteration):
            stack_truth.solve_stack_truth(masses, zeta, x_start, start=start, trace=trace)
        tau, event, y = trace[0]
        e_ref, de_ref = relative(y, n)
        cells = []
        for name, column, ref in (("e", 2, e_ref), ("e'", 2 + n, de_ref)):
            for c in range(n):
                size = max(abs(phases[k, column + c]), abs(phases[k + 1, column + c]))
                error = mpmath.mpf(float(phases[k + 1, column + c])) - ref[c]
                cells.append(f"{name}{c} {float(error / math.ulp(size)):7.1f}")
        kernel_tau = phases[k + 1, 0] - phases[k, 0]
        print(
            f"{k:3d} {on(int(phases[k, 1]), n)} event {event:2d} tau {float(tau):.6f} "
            f"(kernel - reference {kernel_tau - float(tau):8.1e}) | " + " ".join(cells),
            flush=True,
        )


def orders(case: dict) -> None:
    """H moved by 1 to 2^16 ulps up and down, by the kernel: the contacts before h2, the first
    that differs in order from the drop's own, and h2's relative move. Where the order changes
    at every size, a difference quotient over them measures a secant across jumps."""
    from twoball.stacks import simulate_stack

    def run(height: float) -> tuple:
        result = simulate_stack(case["mass_ratios"], case["eps"], case["tau_ratios"], height=height)
        ordered = sorted(result.contacts, key=lambda c: c.start)
        return [c.contact for c in ordered if c.start < result.t2], result.h2

    base, h2 = run(case["height"])
    print(f"{len(base)} contacts before h2")
    for power in (0, 4, 8, 12, 16):
        for sign in (1, -1):
            moved, h = run(case["height"] + sign * 2.0**power * math.ulp(case["height"]))
            first = next(
                (i for i, (a, b) in enumerate(zip(moved, base, strict=False)) if a != b), None
            )
            print(
                f"H {'+-'[sign < 0]}2^{power} ulps: {len(moved)} contacts, order differs "
                f"from contact {first}, h2 moves by {abs(h / h2 - 1):.1e}"
            )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("case", help="an index into stack_truth.cases(), or RATIOS,EPS,GAP,H")
    parser.add_argument("--continue", dest="starts", type=int, nargs="*", default=[])
    parser.add_argument("--local", action="store_true", help="each phase's own error")
    parser.add_argument("--orders", action="store_true", help="contact orders at moved H")
    parser.add_argument("--cache", help="a file keeping the reference's trace between runs")
    args = parser.parse_args()
    if args.case.isdigit():
        case = stack_truth.cases()[int(args.case)]
    else:
        *ratios, eps, gap, height = (float(v) for v in args.case.split(","))
        case = {"mass_ratios": ratios, "eps": eps, "tau_ratios": gap, "height": height}
    masses, zeta, x_start = stack_truth.inputs(
        case["mass_ratios"], case["eps"], case["tau_ratios"], case["height"]
    )
    n = masses.size
    phases, out = kernel_phases(case)
    if args.orders:
        orders(case)
        return
    if args.local:
        with mpmath.workdps(40):
            local_errors(phases, masses, zeta, x_start)
        return
    cache = Path(args.cache) if args.cache else None
    if cache is not None and cache.exists():
        truth, trace = pickle.loads(cache.read_bytes())
    else:
        trace = []
        truth = stack_truth.solve_stack_truth(masses, zeta, x_start, trace=trace)
        if cache is not None:
            cache.write_bytes(pickle.dumps((truth, trace)))
    print(f"kernel h2 {out.apexes[-1, 2]!r}, reference {mpmath.nstr(truth.h2, 20)}")
    print(f"{len(phases)} kernel phases, {len(trace)} reference events")
    with mpmath.workdps(40):
        for k in range(1, min(len(phases), len(trace) + 1)):
            t_ref, event, y = trace[k - 1]
            e_ref, de_ref = relative(y, n)
            e, de = phases[k, 2 : 2 + n], phases[k, 2 + n :]
            bits = int(phases[k, 1])
            cells = []
            around = phases[max(k - 1, 0) : k + 2]
            for name, mine, ref, column in (("e", e, e_ref, 2), ("e'", de, de_ref, 2 + n)):
                for c in range(n):
                    ulp = math.ulp(np.abs(around[:, column + c]).max())
                    cells.append(
                        f"{name}{c} {float((mpmath.mpf(float(mine[c])) - ref[c]) / ulp):7.1f}"
                    )
            dt = float(mpmath.mpf(float(phases[k, 0])) - t_ref)
            print(
                f"{k:3d} event {event:2d} on {on(bits, n)} t {float(t_ref):10.5f} "
                f"dt {dt:9.1e} | " + " ".join(cells),
                flush=True,
            )
        for k in args.starts:
            apexes_before = sum(1 for _, ev, _ in trace[:k] if ev == stack_truth.APEX)
            active = [(int(phases[k, 1]) >> c) & 1 == 1 for c in range(n)]
            fresh = stack_truth.solve_stack_truth(
                masses,
                zeta,
                x_start,
                apexes=2 - apexes_before,
                start=(trace[k - 1][0], absolute(phases[k, 2 : 2 + n], phases[k, 2 + n :]), active),
            )
            h2 = fresh.apex_h[-1]
            print(f"from the kernel's phase {k}: h2 off by {float(h2 / truth.h2 - 1):.2e}")


if __name__ == "__main__":
    main()
