"""The Dask client a study runs on: a given client, a running scheduler, or a local cluster.

The local cluster (one single-threaded worker process per core, each under a Nanny) starts and
stops with :func:`dask_client`.  Its worker processes ignore Ctrl-C (a terminal's SIGINT reaches
every process of the group; this process stops them).  SIGINT is held back while it starts, so a
Ctrl-C then is taken once it is up, and it is stopped whole: no process is left behind.  And it
refuses to start from the top level of a script without a ``__main__`` guard, which its worker
processes would re-import and so start the study again, each.
"""

from __future__ import annotations

import ast
import logging
import signal
import sys
import threading
import traceback
from contextlib import ExitStack, contextmanager
from multiprocessing import resource_tracker
from pathlib import Path
from typing import Callable

LOCAL_HTTP = "127.0.0.1:0"  # the local cluster's dashboard / HTTP address: any free port, loopback only
SCHEDULER_TIMEOUT = 60.0  # s to connect to a scheduler, and then for the workers asked for to connect
SCHEDULER_FORM = "tcp://host:8786"  # the form of a scheduler's address, as messages say


class MainGuardMissing(SystemExit):
    """A script starts a local cluster at its top level, outside ``if __name__ == "__main__":``.

    A SystemExit with the one line to read, rather than the hundreds of lines of the worker
    processes failing to start (they re-import the script)."""


def check_workers(workers) -> int | None:
    if workers is None:
        return None
    if isinstance(workers, bool) or not isinstance(workers, int) or workers < 1:
        raise ValueError(f"workers must be a whole number >= 1, got {workers!r}")
    return workers


def check_scheduler_address(address: str) -> str:
    """``address`` if it has the form of a Dask scheduler's (``[scheme://]host:port``, a scheme Dask knows, a
    port 1..65535), read by Dask's own parser without connecting; else a ValueError naming the form."""
    from distributed.comm import get_address_host_port

    try:
        host, port = get_address_host_port(address)
        if not host or not 0 < port < 65536:
            raise ValueError("it needs a host and a port 1..65535")
    except ValueError as exc:
        raise ValueError(f"{address!r} is not a Dask scheduler's address ({exc}); expected the form "
                         f"{SCHEDULER_FORM}") from None
    return address


def dashboard_line(client) -> str:
    """'Dask dashboard: http://127.0.0.1:40123/status' for the cluster of ``client``, or a line saying
    its scheduler reports none (a scheduler started without its HTTP server)."""
    try:
        link = client.dashboard_link
    except KeyError:  # the scheduler lists no 'dashboard' service
        link = None
    if not link:
        return f"Dask dashboard: none (the scheduler at {client.scheduler.address} reports no dashboard address)"
    return f"Dask dashboard: {link}"


@contextmanager
def dask_client(client=None, scheduler: str | None = None, workers: int | None = None, timeout: float | None = None,
                announce: Callable[[str], None] | None = None):
    """A Dask client: ``client`` as given; one connected to ``scheduler`` (waiting for ``workers``;
    ``timeout`` s each, default ``SCHEDULER_TIMEOUT``); or a local cluster of ``workers``
    single-threaded processes (default one per core) that starts here and stops on exit.
    ``announce(line)`` is given the dashboard's address (``dashboard_line``) once the client is
    connected to a scheduler or a local cluster started here.  A malformed ``scheduler`` is refused
    before any connection (``check_scheduler_address``)."""
    workers = check_workers(workers)
    timeout = SCHEDULER_TIMEOUT if timeout is None else timeout
    if client is not None:
        yield client
        return
    from dask.system import CPU_COUNT  # the cores this process may use (affinity and cgroup limits)
    from distributed import Client, LocalCluster

    _drop_sync_cancel_errors()

    if scheduler:
        with Client(check_scheduler_address(scheduler), set_as_default=False, timeout=timeout) as c:
            if announce is not None:
                announce(dashboard_line(c))
            if workers:
                c.wait_for_workers(workers, timeout=timeout)
            yield c
        return
    check_main_guard()
    with ExitStack() as stack:
        with sigint_held():  # each part is registered for closing before a held Ctrl-C is let through
            # the scheduler always serves HTTP: on a free port of this machine only, not on 8787 of every interface
            cluster = stack.enter_context(LocalCluster(
                n_workers=workers or CPU_COUNT, threads_per_worker=1, processes=True, dashboard_address=LOCAL_HTTP,
                silence_logs=logging.ERROR, preload=[__name__]))
            c = stack.enter_context(Client(cluster, set_as_default=False))
            stack.push(_quiet_when_interrupted)  # closes first: before the client and the cluster
        if announce is not None:
            announce(dashboard_line(c))
        yield c


def _quiet_when_interrupted(exc_type, exc, tb) -> bool:
    """On Ctrl-C, silence Dask's logs before the cluster closes: the scheduler's comms to the client close
    under it as it stops, and it may log that as an error with a traceback, noise to a user who
    stopped the study (the command says what it kept).  Lets the exception through."""
    if exc_type is not None and issubclass(exc_type, KeyboardInterrupt):
        for name in ["distributed", *logging.root.manager.loggerDict]:
            if name.startswith("distributed"):
                logging.getLogger(name).setLevel(logging.CRITICAL + 1)
    return False


class _ClosedCommFilter(logging.Filter):
    """Drops the log records of a connection closed under a local worker: its scheduler, in the process
    that started it, stopping (a heartbeat then fails with a traceback, noise after Ctrl-C)."""

    def filter(self, record: logging.LogRecord) -> bool:
        from distributed.comm.core import CommClosedError

        return not (record.exc_info and isinstance(record.exc_info[1], CommClosedError))


class _SyncCancelFilter(logging.Filter):
    """Drops the NameError that distributed's ``sync`` logs (through tornado) when Ctrl-C comes before the
    call it waits for has started: its ``cancel`` callback reads a future not yet assigned (distributed
    2026.8).  Its traceback, noise to a user who stopped the study, failed
    test_ctrl_c_saves_finished_runs_and_stops_quietly once in CI."""

    def filter(self, record: logging.LogRecord) -> bool:
        if not (record.exc_info and isinstance(record.exc_info[1], NameError)):
            return True
        last = traceback.extract_tb(record.exc_info[2])[-1]
        return not (last.name == "cancel" and Path(last.filename).parts[-2:] == ("distributed", "utils.py"))


def _drop_sync_cancel_errors() -> None:
    """Put _SyncCancelFilter on tornado's callback log (once)."""
    logger = logging.getLogger("tornado.application")
    if not any(isinstance(f, _SyncCancelFilter) for f in logger.filters):
        logger.addFilter(_SyncCancelFilter())


def dask_setup(worker) -> None:
    """Preload of the local cluster's workers (Dask calls it in each worker process as it starts):
    ignore SIGINT, and leave out the logs of the connection to the scheduler closing.  Ctrl-C in a
    terminal reaches every process of the group; this process then cancels the runs and stops the
    workers, which would otherwise each print a traceback."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    closed = _ClosedCommFilter()
    for name in ("distributed", "distributed.worker", "distributed.core", "distributed.comm"):
        logger = logging.getLogger(name)
        logger.addFilter(closed)
        for handler in logger.handlers:
            handler.addFilter(closed)


@contextmanager
def sigint_held():
    """Hold SIGINT back in this block (main thread only); one that came is raised on leaving it.

    Threads and processes started inside inherit the held signal: the cluster's event-loop thread
    and its worker processes (these ignore it for good, see ``dask_setup``)."""
    if threading.current_thread() is not threading.main_thread() or not hasattr(signal, "pthread_sigmask"):
        yield
        return
    # multiprocessing's resource tracker, when it first starts, unblocks SIGINT in the thread that
    # starts it (the cluster's event loop, whose threads start the workers): start it before.
    resource_tracker.ensure_running()
    before = signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT})
    try:
        yield
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, before)


def check_main_guard() -> None:
    """Refuse (``MainGuardMissing``) to start a local cluster from the top level of the ``__main__``
    script outside an ``if __name__ == "__main__":`` block: the worker processes re-import the
    script, which would start the cluster again in each of them."""
    main = sys.modules.get("__main__")
    path = getattr(main, "__file__", None)
    if not path or not str(path).endswith(".py"):
        return  # an interactive session, python -c, a notebook: nothing is re-imported
    frame = next((f for f, _ in traceback.walk_stack(None)
                  if f.f_globals is main.__dict__ and f.f_code.co_name == "<module>"), None)
    if frame is None:
        return  # not called while the script's top level runs
    try:
        tree = ast.parse(Path(path).read_text(encoding="utf-8"), path)
    except (OSError, SyntaxError, ValueError):
        return
    if not _guarded(tree, frame.f_lineno):
        raise MainGuardMissing(
            f"wetcloth: {path}, line {frame.f_lineno}, starts a local Dask cluster at the script's top level; its "
            f"worker processes re-import the script and would start it again: put that code under "
            f"'if __name__ == \"__main__\":'")


def _guarded(tree: ast.Module, line: int) -> bool:
    """Whether ``line`` of the module runs only when it is the main script: inside the block of a
    top-level ``if __name__ == "__main__":`` (or the ``else`` of ``!=``)."""
    for node in tree.body:
        if not isinstance(node, ast.If):
            continue
        for c in (n for n in ast.walk(node.test) if isinstance(n, ast.Compare) and len(n.ops) == 1):
            operands = (c.left, *c.comparators)
            if not (any(isinstance(n, ast.Name) and n.id == "__name__" for n in operands)
                    and any(isinstance(n, ast.Constant) and n.value == "__main__" for n in operands)):
                continue
            block = node.body if isinstance(c.ops[0], ast.Eq) else node.orelse if isinstance(c.ops[0], ast.NotEq) else []
            if block and block[0].lineno <= line <= block[-1].end_lineno:
                return True
    return False
