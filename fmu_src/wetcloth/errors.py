"""Errors wetcloth raises for users: each names what went wrong and how to fix it.

A config source (a scene file, ``--set``, Python overrides, a study) is checked whole: every
mistake found is collected (:class:`Mistakes`) and reported at once, one line each.
"""

from __future__ import annotations

import difflib
from typing import Iterable


class ConfigError(ValueError):
    """One or more mistakes of one config source, all reported at once.

    ``problems`` holds ``(label, name, message)`` for each mistake (label: 'parameter', 'study',
    '[run]' ...); ``source`` says where they were found (e.g. 'scene file models/towel.toml').
    """

    label = "setting"

    def __init__(self, name: str, message: str, label: str | None = None):
        super().__init__(name, message)
        self.problems = [(label or self.label, name, message)]
        self.source: str | None = None

    @property
    def name(self) -> str:
        """The (first) parameter or key in question."""
        return self.problems[0][1]

    def __str__(self) -> str:
        lines = [line(label, name, message) for label, name, message in self.problems]
        head = f"{self.source}: " if self.source else ""
        if len(lines) == 1:
            return head + lines[0]
        return f"{head}{len(lines)} mistakes\n" + "\n".join("  " + line for line in lines)

    @classmethod
    def merged(cls, errors: Iterable["ConfigError"], source: str | None = None) -> "ConfigError":
        """One error of class ``cls`` carrying every problem of ``errors``, found in ``source``."""
        return _made(cls, [p for e in errors for p in e.problems], source)

    def __reduce__(self):  # picklable (Dask sends exceptions between processes)
        return _made, (type(self), self.problems, self.source)


def line(label: str, name: str, message: str) -> str:
    """"parameter 'width': expected a number ..." or, for a message that says what the name is,
    "parameter 'width' is fixed once ..." (no colon between subject and verb)."""
    return f"{label} '{name}'{' ' if message.startswith('is ') else ': '}{message}"


def not_a_number(value) -> str:
    """"expected a number, got '0.5' (text: write the number without quotes)": what a number setting says of
    ``value`` (the hint for text only)."""
    hint = " (text: write the number without quotes)" if isinstance(value, str) else ""
    return f"expected a number, got {value!r}{hint}"


def _made(cls, problems: list[tuple[str, str, str]], source: str | None) -> ConfigError:
    error = cls.__new__(cls)
    ValueError.__init__(error)
    error.problems, error.source = problems, source
    return error


class ParameterError(ConfigError):
    """A scene parameter is unknown, of the wrong type or out of its allowed range (or several are)."""

    label = "parameter"


class StudyError(ConfigError):
    """A batch study file or study dict is malformed; the message names the key and what is allowed."""

    label = "study"

    @property
    def key(self) -> str:
        return self.name


class Mistakes:
    """Collects the mistakes of one config source, so that all of them are reported at once.

        mistakes = Mistakes("scene file x.toml")
        with mistakes.collect():
            check(...)               # a ConfigError here is kept, and checking goes on
        mistakes.raise_if_any()
    """

    def __init__(self, source: str | None = None):
        self.source = source
        self.errors: list[ConfigError] = []

    def add(self, error: ConfigError) -> None:
        self.errors.append(error)

    def collect(self):
        return _Collector(self)

    def raise_if_any(self) -> None:
        """Raise every mistake found: one error as it is (with the source), several as one error of
        their common class (ConfigError if they differ)."""
        if not self.errors:
            return
        if len(self.errors) == 1 and self.source is None:
            raise self.errors[0]
        kinds = {type(e) for e in self.errors}
        cls = kinds.pop() if len(kinds) == 1 else ConfigError
        raise cls.merged(self.errors, self.source)


class _Collector:
    def __init__(self, mistakes: Mistakes):
        self.mistakes = mistakes

    def __enter__(self):
        return self

    def __exit__(self, exc_type, exc, tb):
        if exc_type is not None and issubclass(exc_type, ConfigError):
            self.mistakes.add(exc)
            return True
        return False


def did_you_mean(name: str, known: Iterable[str], what: str = "parameter", listing: str | None = None) -> str:
    """'unknown parameter; did you mean 'width'?': the nearest known names (difflib ratio >= 0.6 and
    within 0.1 of the best), else ``listing`` (where to find the names) or the names themselves."""
    known = list(known)
    scores = {k: difflib.SequenceMatcher(None, name, k).ratio() for k in known}
    best = max(scores.values(), default=0.0)
    close = sorted((k for k, r in scores.items() if r >= max(0.6, best - 0.1)), key=scores.get, reverse=True)[:3]
    if close:
        return f"unknown {what}; did you mean " + " or ".join(repr(c) for c in close) + "?"
    return f"unknown {what} ({listing})" if listing else f"unknown {what}; known: {', '.join(known)}"


def check_choice(error: type[ConfigError], key: str, value, allowed: Iterable[str]) -> str:
    """``value`` if it is one of ``allowed``, else ``error(key, ...)`` listing the allowed values."""
    allowed = tuple(allowed)
    if value not in allowed:
        raise error(key, f"{value!r} is not allowed; allowed: {', '.join(allowed)}")
    return value


class BlowUpError(RuntimeError):
    """The state went non-finite or exploded; carries the last good time (s).

    ``partial_result`` is set by ``wetcloth.runner.run``: the run's outputs up to the last frame
    before the blow-up (a ``RunResult``), so that a front end can still write them.
    """

    def __init__(self, message: str, last_good_time: float):
        super().__init__(message)
        self.last_good_time = last_good_time
        self.partial_result = None
