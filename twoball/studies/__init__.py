"""Studies of the solvers, apart from the library they study.

- :mod:`~twoball.studies.precision`: error against run time, every method (``twoball precision``);
- :mod:`~twoball.studies.stability`: stiff and extreme cases (``twoball stability``);
- :mod:`~twoball.studies.bench`: the exact solver against LSODA as the paper ran it
  (``twoball bench``);
- :mod:`~twoball.studies.report`: the paper's headline numbers beside ours (``twoball report``);
- :mod:`~twoball.studies.truth`: a 40-digit mpmath reference, independent of the exact solver.
"""
