"""pneumaquad: simulator for pneumatically actuated legged robots."""

from importlib.metadata import PackageNotFoundError, version

try:
    __version__ = version("pneumaquad")  # one source: pyproject.toml
except PackageNotFoundError:  # pragma: no cover - run from a source tree, not installed
    __version__ = "0+unknown"
