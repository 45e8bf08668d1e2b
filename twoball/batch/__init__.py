"""Many drops at once: the sweep over a grid of (eps, mu, tau_ratio) (:mod:`twoball.batch.sweep`),
the labelled cubes it writes and ships (:mod:`twoball.batch.cubes`), and the worker pools the
studies run on (:mod:`twoball.batch.workers`)."""
