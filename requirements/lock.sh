#!/bin/sh
# Regenerate the pins of every dependency: a fresh virtual environment per extra, frozen.
# Run from the repository root. app.txt pins the Docker image; test.txt pins CI and the
# README's commands (pip install -c requirements/test.txt ...).
set -eu
for extra in app test; do
    venv="$(mktemp -d)"
    python3 -m venv "$venv"
    "$venv/bin/pip" install --quiet ".[$extra]"
    {
        echo "# Pins for twoball[$extra], made by requirements/lock.sh; regenerate with it."
        "$venv/bin/pip" freeze --all | grep -v -i -E '^(twoball|pip|setuptools|wheel)[= @]'
    } >"requirements/$extra.txt"
    rm -rf "$venv"
done
