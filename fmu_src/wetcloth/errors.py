"""Errors wetcloth raises for users: each names what went wrong and how to fix it."""


class ParameterError(ValueError):
    """A scene parameter is unknown, of the wrong type or out of its allowed range."""

    def __init__(self, name: str, message: str):
        super().__init__(f"parameter '{name}': {message}")
        self.name = name


class BlowUpError(RuntimeError):
    """The state went non-finite or exploded; carries the last good time (s).

    ``partial_result`` is set by ``wetcloth.runner.run``: the run's outputs up to the last frame
    before the blow-up (a ``RunResult``), so that a front end can still write them.
    """

    def __init__(self, message: str, last_good_time: float):
        super().__init__(message)
        self.last_good_time = last_good_time
        self.partial_result = None
