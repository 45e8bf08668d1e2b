#!/bin/sh
# Serve the explorer on 0.0.0.0:$PORT (default 5006) to browsers that open it as
# $ALLOWED_ORIGIN (host[:port], default localhost:5006); /liveness answers the health check.
# Run from the directory that holds app/ (the Dockerfile's CMD, the README and the tests).
set -eu
exec panel serve app \
    --address 0.0.0.0 \
    --port "${PORT:-5006}" \
    --allow-websocket-origin "${ALLOWED_ORIGIN:-localhost:5006}" \
    --liveness
