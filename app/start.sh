#!/bin/sh
# The image's entry (Dockerfile CMD): `twoball serve`, the command a teacher runs, on
# 0.0.0.0:$PORT (default 5006) for browsers that open it as $ALLOWED_ORIGIN (host[:port], default
# localhost:5006), on $NUM_PROCS processes (default: every core the container may run on, as
# twoball serve decides; set it when a CPU quota, --cpus, gives fewer cores than the host has).
# /liveness answers the health check.
set -eu
exec twoball serve \
    --address 0.0.0.0 \
    --port "${PORT:-5006}" \
    --allow-websocket-origin "${ALLOWED_ORIGIN:-localhost:5006}" \
    ${NUM_PROCS:+--num-procs "$NUM_PROCS"}
