"""``twoball serve``: the explorer served from wherever it is installed, at ``/app``.

Panel's own ``panel serve`` command, with this directory as the app and four defaults changed
for a class:

- ``--num-procs``: every core this process may use (``os.sched_getaffinity``; a container's CPU
  set, not the host's count). One Python process runs one session's callback at a time, so on
  two cores one process left the second idle while a class queued.
- ``--reuse-sessions``: the page's HTTP request is answered from a session kept per page kind
  (``app_hooks.page_kind``) instead of building one, and the session is built once, when the page's
  websocket connects. With several processes the two requests may reach different processes
  (the kernel hands each connection to any of them); without this the app was built twice for
  one page, and the first copy lived on until it expired.
- ``--liveness``: ``/liveness`` answers a health check (the Docker image's).
- ``--websocket-compression-level 1``: messages are deflated (browsers offer permessage-deflate);
  a page's first document crosses the network in about a fifth of its size, for a fraction of a
  millisecond of zlib's fastest level (benchmarks/app_load.py).

Any other ``panel serve`` option is passed on (``twoball serve --help`` lists them). ``panel serve
app`` from a clone serves the same directory at the same address.
"""

from __future__ import annotations

import argparse
import os
import signal
import socket
import sys
from pathlib import Path

from panel.command.serve import Serve

from twoball.errors import ParameterError

APP_DIR = Path(__file__).resolve().parent
ROUTE = "/app"  # shared links (/app?scene=map&eps=0.9) work however the explorer is served


class AppServe(Serve):
    """Panel's ``serve`` command serving :data:`APP_DIR` at :data:`ROUTE`."""

    def customize_applications(self, args, applications):
        applications = super().customize_applications(args, applications)
        own = f"/{APP_DIR.name}"  # "/app" from a clone, "/twoball_app" when installed
        return {ROUTE if route == own else route: app for route, app in applications.items()}


def default_processes() -> int:
    """The cores this process may run on."""
    return len(os.sched_getaffinity(0))


class _Parser(argparse.ArgumentParser):
    def error(self, message: str) -> None:  # one line and status 2 (twoball.cli.main)
        raise ParameterError(f"serve: {message}")


def build_parser() -> argparse.ArgumentParser:
    parser = _Parser(
        prog="twoball serve",
        description="Serve the classroom explorer at /app (Panel's serve command; see "
        "'Serving a class' in the README).",
    )
    AppServe(parser=parser)
    parser.set_defaults(
        num_procs=default_processes(),
        reuse_sessions=True,
        liveness=True,
        port=5006,
        websocket_compression_level=1,
    )
    return parser


def stop_together_on_sigterm() -> None:
    """With several processes, a SIGTERM to the first one stops them all.

    That process only waits for the ones it forked (Tornado's ``fork_processes``) and handles no
    SIGTERM; as a container's PID 1 it ignored ``docker stop`` (the kernel delivers no signal
    to PID 1 that it does not handle), which killed it after its grace period (exit 137), and
    elsewhere it died alone, leaving its children serving. Forwarded once to the process
    group, the SIGTERM stops each server (Bokeh's own handler, exit 0), and the first process
    then exits 0."""
    forwarded = False

    def forward(signum: int, frame: object) -> None:
        nonlocal forwarded
        if not forwarded:
            forwarded = True
            os.killpg(os.getpgrp(), signal.SIGTERM)

    signal.signal(signal.SIGTERM, forward)


def where_not_to_listen(address: str | None, port: int) -> str | None:
    """Why the server could not listen at ``address`` and ``port`` (Tornado's own failure is a
    traceback, or a log line and status 1), or None. The port is tried as Tornado binds it."""
    if not 0 <= port <= 65535:
        return f"--port must be between 0 and 65535; got {port}"
    try:
        found = socket.getaddrinfo(
            address or None, port, type=socket.SOCK_STREAM, flags=socket.AI_PASSIVE
        )
    except (socket.gaierror, UnicodeError) as error:
        return f"--address {address!r} is not an address ({error})"
    family, kind, protocol, _, where = found[0]
    with socket.socket(family, kind, protocol) as trial:
        trial.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        try:
            trial.bind(where)
        except OSError as error:
            return f"cannot listen at {address or 'every address'}, port {port}: {error.strerror}"
    return None


def main(argv: list[str]) -> int:
    """Run the server until it is stopped; returns the exit status."""
    parser = build_parser()
    args = parser.parse_args([str(APP_DIR), *argv])
    if args.num_procs < 1:
        parser.error(f"--num-procs must be at least 1; got {args.num_procs}")
    if args.files != [str(APP_DIR)]:
        parser.error(f"takes no app to serve (it serves the explorer); got {args.files[1:]}")
    problem = where_not_to_listen(args.address, args.port)
    if problem:
        parser.error(problem)
    if args.num_procs > 1:
        stop_together_on_sigterm()
    AppServe(parser=argparse.ArgumentParser()).invoke(args)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
