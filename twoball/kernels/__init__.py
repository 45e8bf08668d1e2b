"""The kernels: closed forms, certified steps and the compiled phase loops of the two-ball, the
N-ball and the Hertz solvers (numba; docs/model.md). Nothing here validates input or builds a
result: :mod:`twoball.exact`, :mod:`twoball.stacks` and :func:`twoball.simulate` do."""
