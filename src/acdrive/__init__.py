"""acdrive: AC-machine drives -- models, controller design and analysis, compiled simulation."""

__version__ = "0.1.0"
