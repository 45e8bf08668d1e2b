# The classroom explorer:  docker build -t twoball . && docker run -p 5006:5006 twoball
# then open http://localhost:5006/app . For a class, see the README ("Serving a class").
# BASE is a build argument so that a test can pass a local stand-in for the official image.
ARG BASE=python:3.11.14-slim-bookworm
FROM ${BASE}

ENV PYTHONDONTWRITEBYTECODE=1 \
    PYTHONUNBUFFERED=1 \
    PIP_NO_CACHE_DIR=1 \
    PIP_DISABLE_PIP_VERSION_CHECK=1 \
    PATH=/opt/venv/bin:$PATH \
    NUMBA_CACHE_DIR=/opt/numba-cache \
    PORT=5006 \
    ALLOWED_ORIGIN=localhost:5006 \
    MPLCONFIGDIR=/tmp/matplotlib

# The pinned dependencies in a layer of their own: a change to the sources reinstalls nothing.
COPY requirements/app.txt /opt/twoball/requirements/app.txt
RUN python3 -m venv /opt/venv && pip install --quiet -r /opt/twoball/requirements/app.txt

# The package with its app (a plain install: the cubes and the explorer travel inside it), then
# its compiled solver, cached for the user the image runs as (uid 1000); another uid, or a
# read-only root, gets a copy of the cache in /tmp (twoball/jit.py), and a new CPU compiles
# while the page is served. The image serves as a teacher does: `twoball serve` (app/start.sh).
WORKDIR /opt/twoball
COPY pyproject.toml README.md ./
COPY twoball ./twoball
COPY app ./app
RUN pip install --quiet --no-deps . && cp app/start.sh /opt/start.sh && rm -rf build twoball app \
    && python -c "from twoball import warmup; warmup.warm_up()" && chown -R 1000:1000 "$NUMBA_CACHE_DIR"

USER 1000:1000
EXPOSE 5006
HEALTHCHECK --interval=5s --timeout=3s --start-period=60s --retries=3 \
    CMD python -c "import os, urllib.request; urllib.request.urlopen('http://127.0.0.1:%s/liveness' % os.environ['PORT'], timeout=2)"
CMD ["sh", "/opt/start.sh"]
