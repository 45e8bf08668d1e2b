#!/bin/sh
# Serve the explorer from the virtual environment $1 on 0.0.0.0:$PORT (default 5006); browsers
# may open it from $ALLOWED_ORIGIN (host[:port], default localhost:5006). /liveness answers
# the health check. Run from the repository root; the Dockerfile's CMD and the tests call it.
set -eu
venv="$1"
exec "$venv/bin/panel" serve app \
    --address 0.0.0.0 \
    --port "${PORT:-5006}" \
    --allow-websocket-origin "${ALLOWED_ORIGIN:-localhost:5006}" \
    --liveness
