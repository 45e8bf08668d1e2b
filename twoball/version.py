"""The installed version of twoball, for the package, the command line and the cubes' metadata."""

from importlib.metadata import PackageNotFoundError, version

try:
    __version__ = version("twoball")
except PackageNotFoundError:  # running from a source tree that was not installed
    __version__ = "0+unknown"
