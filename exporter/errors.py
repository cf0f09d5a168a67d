"""The exporter's error: a ValueError, so ``wetcloth run`` prints it cleanly and exits 2."""


class ExportError(ValueError):
    """Frames cannot be written: the directory is unusable, taken by another run, or the data is wrong."""
