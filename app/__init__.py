"""The classroom explorer: a Panel directory app (``panel serve app``), one module per scene."""
