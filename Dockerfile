# The classroom explorer: docker build -t twoball . && docker run -p 5006:5006 twoball
# Open http://localhost:5006/app ; from another host set ALLOWED_ORIGIN to the host:port the
# browser uses (docker run -e ALLOWED_ORIGIN=class.example.org:5006 ...).
FROM python:3.11-slim

ENV PYTHONDONTWRITEBYTECODE=1 \
    PIP_NO_CACHE_DIR=1 \
    PIP_DISABLE_PIP_VERSION_CHECK=1 \
    PORT=5006 \
    ALLOWED_ORIGIN=localhost:5006

RUN useradd --create-home --uid 1000 twoball
WORKDIR /home/twoball/twoball
COPY --chown=twoball:twoball . .
USER twoball

# the package, its app extra and the shipped cubes (precomputed/); the numba cache is built here
RUN sh app/install.sh /home/twoball/venv

EXPOSE 5006
HEALTHCHECK --interval=30s --timeout=5s --start-period=60s --retries=3 \
    CMD python3 -c "import os, urllib.request; urllib.request.urlopen('http://127.0.0.1:%s/liveness' % os.environ['PORT'], timeout=4)"
CMD ["sh", "app/start.sh", "/home/twoball/venv"]
