#!/bin/sh
# Install twoball with the app extra into a new virtual environment ($1) and build the numba
# cache of the exact solver, so that no server start or session waits for the compiler.
# Run from the repository root; the Dockerfile and tests/app/test_app_docker.py both call it.
set -eu
venv="$1"
python3 -m venv "$venv"
"$venv/bin/pip" install --quiet --editable ".[app]"
# editable: the package finds the shipped cubes in precomputed/ beside its source
"$venv/bin/python" -c "import twoball; twoball.simulate(0.9, 0.01, 0.01, dense=True); print(twoball.load_cube('map').sizes)"
