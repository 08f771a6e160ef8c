"""pneumaquad: simulator for pneumatically actuated legged robots."""

__version__ = "0.1.0"
